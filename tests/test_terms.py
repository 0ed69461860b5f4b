"""The terms of the per-step program: each writer against its formula, controllers as lists of
terms, and the worked example of docs/architecture.md (the joint-centring objective)."""

from __future__ import annotations

import numpy as np
import pytest

import emdm
from emdm.core.controllers import BASELINES, CONTROLLERS, get_controller, step_program
from emdm.core.terms import TermKind
from emdm.core.terms.centring import gradient


def _range_index(sc, q):
    """Liegeois' joint-range index H(q) = 1/2 sum ((q - m) / r)^2, written out (the oracle)."""
    mid = 0.5 * (sc.arm.q_min + sc.arm.q_max)
    r = sc.arm.q_max - sc.arm.q_min
    return 0.5 * float(np.sum(((q - mid) / r) ** 2))


def test_centring_gradient_matches_central_differences(rng):
    sc = emdm.load_scenario("task1")
    for q in rng.uniform(-1.8, 1.8, (10, 3)):
        out = np.empty(3)
        gradient(q, sc.arm.q_min, sc.arm.q_max, out)
        h = 1e-6
        fd = [
            (_range_index(sc, q + h * e) - _range_index(sc, q - h * e)) / (2 * h) for e in np.eye(3)
        ]
        np.testing.assert_allclose(out, fd, atol=1e-9)


def test_centring_enters_the_closed_form_of_uc_emdm(rng):
    """With w_C > 0 the redundant UC-EMDM optimum is ``J^+ v + N (w_M Jm - w_C grad H) / w_E``."""
    sc = emdm.load_scenario("task1", {"weights.centring": 0.7})
    for q in rng.uniform(-1.5, 1.5, (20, 3)):
        kin = sc.planar_arm.kinematics(q)
        e = sc.motion.goal - kin.p
        v = sc.motion.kp * e
        qp = step_program(get_controller("UC-EMDM"), sc, q, kin, v, float(np.linalg.norm(e)))
        x = emdm.solve_chain(qp, ["active-set"]).x
        grad = np.empty(3)
        gradient(q, sc.arm.q_min, sc.arm.q_max, grad)
        Jp = np.linalg.pinv(kin.J)
        N = np.eye(3) - Jp @ kin.J
        w = sc.weights
        expected = Jp @ v + N @ (w.manipulability * kin.Jm - 0.7 * grad) / w.effort
        np.testing.assert_allclose(x, expected, atol=1e-12)


def test_centring_moves_the_joints_toward_the_middle_of_their_range():
    """In closed loop the centring term ends the run at the configuration of the goal's
    self-motion that is nearest the middle of the joint ranges (the minimum of H over the
    configurations that reach the goal, found by SLSQP), while w_C = 0 ends elsewhere."""
    from scipy.optimize import minimize

    base = emdm.load_scenario("task1", {"weights.manipulability": 0.0})
    centred = base.with_overrides({"weights.centring": 2.0})
    arm, goal = base.planar_arm, base.motion.goal
    best = minimize(
        lambda q: _range_index(base, q),
        np.array([1.0, 1.5, 0.6]),
        constraints=[{"type": "eq", "fun": lambda q: arm.forward(q) - goal}],
        method="SLSQP",
        options={"ftol": 1e-14},
    )
    assert best.success
    r0, r1 = emdm.simulate(base, "C-EMDM"), emdm.simulate(centred, "C-EMDM")
    assert r0.reached and r1.reached
    assert _range_index(centred, r1.q[-1]) == pytest.approx(best.fun, abs=2e-4)  # stops 1 mm short
    assert _range_index(base, r0.q[-1]) > best.fun + 1e-3


def test_a_zero_centring_weight_leaves_the_program_unchanged():
    sc = emdm.load_scenario("task2")
    with_zero = sc.with_overrides({"weights.centring": 0.0})
    for name in CONTROLLERS:
        a = get_controller(name).program_data(sc)
        b = get_controller(name).program_data(with_zero)
        np.testing.assert_array_equal(a.codes, b.codes)


@pytest.mark.parametrize("name", [*CONTROLLERS, *BASELINES])
def test_controllers_are_lists_of_terms(name):
    """The brief's four and the baselines are data: what sets them apart is which terms they
    hold, and the C- controllers are exactly those holding the joint bounds."""
    ctrl = get_controller(name)
    kinds = [t.kind for t in ctrl.terms]
    assert kinds[0] is TermKind.TASK and TermKind.EFFORT in kinds
    assert ctrl.constrained == (name.startswith("C-") or name == "MMC")
    assert ctrl.constrained == ctrl.has(TermKind.DAMPER)
    assert ctrl.has(TermKind.MANIPULABILITY) == (name.endswith("EMDM") or name in ("PARK", "MMC"))


def test_slack_follows_the_arm():
    """The brief's rule: EMDM carries the task slack on a non-redundant arm only; MMC always."""
    redundant, two_link = emdm.load_scenario("task1"), emdm.load_scenario("task2")
    assert not get_controller("C-EMDM").program_data(redundant).slack
    assert get_controller("C-EMDM").program_data(two_link).slack
    assert get_controller("MMC").program_data(redundant).slack
    assert not get_controller("PARK").program_data(two_link).slack


def test_bad_centring_weight_is_one_clear_error():
    with pytest.raises(emdm.ScenarioError, match=r"weights\.centring"):
        emdm.load_scenario("task1", {"weights.centring": -1.0})
