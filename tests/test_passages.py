"""The one definition of chattering, the slack in use, near-singular passages and coinciding runs
(emdm.sim.passages), and the playground's sentences built on it."""

from __future__ import annotations

import dataclasses
import re
import warnings

import numpy as np
import pytest

import emdm
from emdm.core.controllers import state_at
from emdm.core.tolerances import CHATTER_SPEED, CHATTER_STEPS, NEAR_SINGULAR
from emdm.play import logic
from emdm.sim import passages


def scenario(name: str, **overrides: object) -> emdm.Scenario:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return emdm.load_scenario(name, overrides)


@pytest.fixture(scope="module")
def runs():
    seven = scenario(
        "task1", **{"arm.lengths": [1.5 / 7] * 7, "motion.q0": [0.3] * 7, "weights.effort": 1e-3}
    )
    return {
        "task1": emdm.simulate(scenario("task1"), "C-EMDM"),
        "task1 C-IVKC": emdm.simulate(scenario("task1"), "C-IVKC"),
        "task2": emdm.simulate(scenario("task2"), "C-EMDM"),
        "task2 UC-IVKC": emdm.simulate(scenario("task2"), "UC-IVKC"),
        "seven": emdm.simulate(seven, "C-EMDM"),
    }


def test_chattering_is_every_step_a_reversal_above_the_speed(runs):
    found = passages.chattering(runs["seven"])  # 7 links, w_E = 0.001: the case
    assert found and {c.joint for c in found} == set(range(7))
    for c in found:
        qd = runs["seven"].qd[c.start : c.stop + 1, c.joint]
        assert c.stop - c.start >= CHATTER_STEPS
        assert np.all(qd[1:] * qd[:-1] < 0) and np.all(np.abs(qd) >= CHATTER_SPEED)
        assert c.peak == pytest.approx(np.abs(qd).max())
    assert passages.chattering(runs["task1"]) == []  # a smooth run


def test_chattering_needs_enough_reversals_in_a_row(runs):
    run = runs["task1"]
    qd = np.full_like(run.qd, 0.01)  # below the speed: never
    signs = np.array([1.0 if k % 2 else -1.0 for k in range(run.steps)])
    for reversals, expected in ((CHATTER_STEPS - 1, 0), (CHATTER_STEPS, 1)):
        qd[:] = 0.01
        qd[10 : 10 + reversals + 1, 2] = 0.5 * signs[10 : 10 + reversals + 1]
        found = passages.chattering(dataclasses.replace(run, qd=qd.copy()))
        assert len(found) == expected
        if expected:
            assert (found[0].joint, found[0].start, found[0].stop) == (2, 10, 10 + reversals)


def test_the_slack_in_use(runs):
    assert passages.slack_in_use(runs["task2"]).all()  # the 2-link arm relaxes every step
    assert not passages.slack_in_use(runs["task2 UC-IVKC"]).any()  # no slack in that program


def test_dexterity_is_the_smallest_singular_value_over_the_reach(runs):
    run = runs["task2"]
    dex = passages.dexterity(run)
    arm = run.scenario.planar_arm
    for k in (0, 100, run.steps):
        J = arm.jacobian(run.q[k])
        assert dex[k] == pytest.approx(np.linalg.svd(J, compute_uv=False)[-1] / arm.reach)
    near = passages.spans(dex < NEAR_SINGULAR)
    assert len(near) == 1 and 10.0 < run.t[near[0][0]] < run.t[near[0][1]] < 12.0
    outstretched = dataclasses.replace(run, q=np.zeros((2, 2)))
    assert passages.dexterity(outstretched).max() < 1e-12


def test_spatial_dexterity_divides_only_the_position_rows():
    sc = scenario("panda", **{"motion.max_time": 0.1})
    run = emdm.simulate(sc, "C-EMDM")
    J = state_at(sc, run.q[0]).kin.J.copy()
    J[:3] /= sc.reach
    assert passages.dexterity(run)[0] == pytest.approx(np.linalg.svd(J, compute_uv=False)[-1])


def test_spans():
    assert passages.spans(np.array([0, 1, 1, 0, 1], bool)) == [(1, 2), (4, 4)]
    assert passages.spans(np.zeros(3, bool)) == []


def test_coinciding_runs(runs):
    a, b = runs["task1"], runs["task1 C-IVKC"]
    shared = passages.coinciding(a, b)
    assert 0 < shared < a.q.shape[0]  # alike while the scaled start fixes the command
    assert np.abs(a.q[:shared] - b.q[:shared]).max() <= 1e-9
    assert np.abs(a.q[shared] - b.q[shared]).max() > 1e-9
    assert passages.coinciding(a, a) == a.q.shape[0]


def test_the_playground_names_each_passage_with_its_time(runs):
    sc = scenario("task2")
    emdm_, ivkc = (logic.run_controller(sc, n) for n in ("C-EMDM", "UC-IVKC"))
    text = logic.explain(sc, emdm_)
    assert "task slack was in use on 329 of 329 steps" in text
    assert re.search(r"near-singular from t = 10\.\d\d s to 11\.\d\d s", text)
    rows = dict(logic.status_rows(emdm_, 10.8))
    assert rows["alpha"].startswith("1 (not scaled; the slack relaxes")
    assert rows["task slack"].startswith("||delta|| = ")
    assert rows["m"].endswith("(near-singular)")
    assert "task slack" not in dict(logic.status_rows(ivkc, 1.0))
    seven = scenario(
        "task1", **{"arm.lengths": [1.5 / 7] * 7, "motion.q0": [0.3] * 7, "weights.effort": 1e-3}
    )
    assert "joints 1, 2, 3, 4, 5, 6 and 7 chatter from t = " in logic.explain(
        seven, logic.run_controller(seven, "C-EMDM")
    )
    same = scenario("task1", **{"weights.manipulability": 0.0})
    pair = [logic.run_controller(same, n) for n in ("C-EMDM", "C-IVKC")]
    assert "coincide throughout" in logic.explain_pair(*pair)
    nominal = scenario("task1")
    pair = [logic.run_controller(nominal, n) for n in ("C-EMDM", "C-IVKC")]
    assert "coincide until t = 2.00 s" in logic.explain_pair(*pair)
    pair = [logic.run_controller(nominal, n) for n in ("UC-EMDM", "UC-IVKC")]
    assert logic.explain_pair(*pair) == ""
