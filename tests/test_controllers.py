"""The four controllers' programs against the exact facts of docs/mathematics.md, and the policies."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog

import emdm
from emdm import NoSolution, admissible, get_controller, solve_chain, step_program
from emdm.core.controllers import slack_weight


def _program(sc, name, q):
    kin = sc.planar_arm.kinematics(q)
    e = sc.motion.goal - kin.p
    v = sc.motion.kp * e
    return kin, v, e, step_program(get_controller(name), sc, q, kin, v, float(np.linalg.norm(e)))


def _solve(qp):
    return solve_chain(qp, ["active-set"]).x


def test_uc_emdm_redundant_closed_form(rng):
    sc = emdm.load_scenario("task1")
    for q in rng.uniform(-1.5, 1.5, (30, 3)):
        kin, v, _, qp = _program(sc, "UC-EMDM", q)
        Jp = np.linalg.pinv(kin.J)
        N = np.eye(3) - Jp @ kin.J
        r = sc.weights.manipulability / sc.weights.effort
        np.testing.assert_allclose(_solve(qp), Jp @ v + r * N @ kin.Jm, atol=1e-12)


def test_uc_ivkc_is_the_pseudoinverse_on_both_arms(rng):
    for task, n in (("task1", 3), ("task2", 2)):
        sc = emdm.load_scenario(task)
        for q in rng.uniform(-1.5, 1.5, (20, n)):
            kin, v, _, qp = _program(sc, "UC-IVKC", q)
            np.testing.assert_allclose(_solve(qp), np.linalg.pinv(kin.J) @ v, atol=1e-12)


def test_non_redundant_slack_program_reduces_to_a_linear_system(rng):
    sc = emdm.load_scenario("task2").with_overrides(
        {"slack.min": [-50.0, -50.0], "slack.max": [50.0, 50.0]}
    )
    w = sc.weights
    for q in rng.uniform(-1.5, 1.5, (30, 2)):
        kin, v, e, qp = _program(sc, "UC-EMDM", q)
        ws = w.slack / np.linalg.norm(e)
        J, Jm = kin.J, kin.Jm
        expected = np.linalg.solve(
            w.effort * np.eye(2) + ws * J.T @ J, w.manipulability * Jm + ws * J.T @ v
        )
        x = _solve(qp)
        np.testing.assert_allclose(x[:2], expected, atol=1e-10)
        np.testing.assert_allclose(x[2:], v - J @ x[:2], atol=1e-12)  # delta = v - J qd


def test_constrained_programs_carry_the_damper_and_box(rng):
    sc = emdm.load_scenario("task1")
    q = np.array([1.6, -1.95 + 0.2, 0.0])
    _, _, _, qp = _program(sc, "C-EMDM", q)
    i, s = 0.785398, 0.0872665
    assert qp.ub[0] == pytest.approx((2.0 - 1.6 - s) / (i - s))
    assert qp.lb[0] == -1.0
    assert qp.lb[1] == pytest.approx(-(0.2 + 0.05 - s) / (i - s))
    assert qp.ub[1] == 1.0 and qp.lb[2] == -1.0 and qp.ub[2] == 1.0
    _, _, _, uc = _program(sc, "UC-EMDM", q)
    assert not uc.bounded


def test_weights_override_the_scenario():
    sc = emdm.load_scenario("task1")
    q = np.asarray(sc.motion.q0)
    kin = sc.planar_arm.kinematics(q)
    e = sc.motion.goal - kin.p
    weights = emdm.core.scenario.Weights(effort=1.0, manipulability=0.0, slack=1.0)
    a = step_program(get_controller("UC-EMDM"), sc, q, kin, e, 1.0, weights=weights)
    b = step_program(get_controller("UC-IVKC"), sc, q, kin, e, 1.0)
    np.testing.assert_allclose(_solve(a), _solve(b), atol=1e-13)


# ----------------------------------------------------------------------------------- policies
def _task1_start(policy):
    sc = emdm.load_scenario("task1", {"controller.on_infeasible": policy})
    q = np.asarray(sc.motion.q0)
    kin, v, e, qp = _program(sc, "C-EMDM", q)
    return sc, kin, v, e, qp


def test_scale_policy_finds_the_largest_feasible_scale():
    sc, kin, v, e, qp = _task1_start("scale")
    adm = admissible(qp, "scale", slack_weight=slack_weight(sc, np.linalg.norm(e)))
    n = 3
    res = linprog(
        np.r_[np.zeros(n), -1.0],
        A_eq=np.c_[kin.J, -v],
        b_eq=np.zeros(2),
        bounds=[*zip(qp.lb, qp.ub, strict=True), (0, 1)],
        method="highs",
    )
    assert adm.alpha == pytest.approx(-res.fun, abs=1e-9)
    assert adm.policy == "scale"
    x = _solve(adm.qp)
    np.testing.assert_allclose(kin.J @ x, adm.alpha * v, atol=1e-12)
    # direction preserved: the commanded task velocity is parallel to v
    u = kin.J @ x
    assert u[0] * v[1] - u[1] * v[0] == pytest.approx(0.0, abs=1e-12)


def test_slack_policy_relaxes_the_task():
    sc, kin, v, e, qp = _task1_start("slack")
    adm = admissible(qp, "slack", slack_weight=slack_weight(sc, np.linalg.norm(e)))
    assert adm.alpha == 1.0 and adm.policy == "slack" and adm.qp.n_slack == 2
    x = _solve(adm.qp)
    assert np.all(x[:3] <= qp.ub + 1e-12) and np.all(x[:3] >= qp.lb - 1e-12)
    np.testing.assert_allclose(kin.J @ x[:3] + x[3:], v, atol=1e-12)
    assert np.linalg.norm(x[3:]) > 1.0  # the bounds cannot deliver most of |v| = 1.57 m/s


def test_error_policy_names_the_step():
    sc, _, _, _, qp = _task1_start("error")
    with pytest.raises(NoSolution, match=r"step 0: the task is infeasible.*alpha = 0\.18"):
        admissible(qp, "error", slack_weight=1.0, step=0)
    with pytest.raises(NoSolution, match="step 0"):
        emdm.simulate(sc, "C-EMDM")


def test_feasible_programs_are_left_alone():
    sc = emdm.load_scenario("task1")
    q = np.asarray(sc.motion.q0)
    _, _, _, qp = _program(sc, "UC-EMDM", q)
    adm = admissible(qp, "scale", slack_weight=1.0)
    assert adm.alpha == 1.0 and adm.policy is None and adm.qp is qp


def test_unknown_controller():
    with pytest.raises(emdm.EmdmError, match="unknown controller 'X-EMDM'"):
        get_controller("X-EMDM")
    assert get_controller("c-emdm").name == "C-EMDM"


def test_the_brief_slack_applies_on_every_arm_when_asked():
    """Readings 269, 277: the brief's Table 1 lists slack limits for the redundant arm too.
    ``controller.slack = "always"`` puts EMDM's slack (its bounds and weight c_S/||e||) into the
    three-link program; the default, ``auto``, keeps the brief's slack program to the
    non-redundant arm. IVKC has no slack either way."""
    nominal = emdm.load_scenario("task1")
    always = emdm.load_scenario("task1", {"controller.slack": "always"})
    q = np.asarray(nominal.motion.q0)
    for name in ("UC-EMDM", "C-EMDM"):
        assert _program(nominal, name, q)[3].n_slack == 0
        qp = _program(always, name, q)[3]
        assert qp.n_slack == 2
        np.testing.assert_array_equal(qp.lb[-2:], always.slack.min)
        np.testing.assert_array_equal(qp.ub[-2:], always.slack.max)
        e = always.motion.goal - always.planar_arm.kinematics(q).p
        w_s = always.weights.slack / np.linalg.norm(e)
        assert qp.P[-1, -1] == pytest.approx(w_s, rel=1e-12)
    assert _program(always, "C-IVKC", q)[3].n_slack == 0
    # the brief's slack lets the start's task through: C-EMDM's first step is not scaled
    assert emdm.simulate(always, "C-EMDM").alpha[0] == 1.0
    assert emdm.simulate(nominal, "C-EMDM").alpha[0] < 1.0
