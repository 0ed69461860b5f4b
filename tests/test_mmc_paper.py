"""``emdm mmc --protocol paper``: the authors' servo and controllers, each step checked against an
independent statement (robotics-toolbox-python's ``p_servo``, a QP solver for the exact optima)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from qpsolvers import solve_qp

from emdm.cli.main import main
from emdm.core.loading import load_scenario
from emdm.studies.mmc_paper import (
    CONTROLLERS,
    DT,
    PI,
    PROTOCOLS,
    PS,
    Paper,
    Singular,
    Y,
    command,
    paper_table,
    run_paper_protocol,
    run_trials,
    servo,
)


def _state(rng, name="panda"):
    sc = load_scenario(name)
    arm = sc.serial_arm
    lo, hi = np.asarray(sc.arm.q_min), np.asarray(sc.arm.q_max)
    q = rng.uniform(lo, hi)
    T, J0 = arm.forward(q), arm.jacobian(q)
    R = T[:3, :3]
    J = np.vstack((R.T @ J0[:3], R.T @ J0[3:]))
    goal = arm.forward(rng.uniform(lo, hi))
    return arm, q, lo, hi, T, J, goal


def test_servo_is_robotics_toolbox_p_servo():
    rtb = pytest.importorskip("roboticstoolbox")
    rng = np.random.default_rng(0)
    for _ in range(20):
        _, _, _, _, T, _, goal = _state(rng)
        v, arrived, _ = servo(T, goal)
        v_ref, arrived_ref = rtb.p_servo(T, goal, gain=1.0, threshold=0.17)
        assert np.abs(v - v_ref).max() < 1e-12 and arrived == arrived_ref


def test_each_step_is_the_exact_optimum_of_its_program():
    rng = np.random.default_rng(1)
    for _ in range(10):
        arm, q, lo, hi, T, J, goal = _state(rng)
        Jm = arm.manipulability_jacobian(q)
        v, _, e_s = servo(T, goal)
        n = q.size
        park = command("PARK", J, Jm, v, e_s, q, lo, hi)  # closed form against a QP solver
        ref = solve_qp(Y * np.eye(n), -Jm, A=J, b=v, solver="quadprog")
        assert np.abs(park - ref).max() < 1e-8
        assert np.abs(J @ command("RRMC", J, Jm, v, e_s, q, lo, hi) - v).max() < 1e-9
        mmc = command("MMC", J, Jm, v, e_s, q, lo, hi)
        lb, ub = np.full(n + 6, -np.inf), np.full(n + 6, np.inf)
        low, high = q - lo <= PI, hi - q <= PI
        lb[:n][low] = -((q - lo - PS) / (PI - PS))[low]
        ub[:n][high] = ((hi - q - PS) / (PI - PS))[high]
        P = np.diag(np.r_[np.full(n, Y), np.full(6, 1.0 / e_s)])
        x = solve_qp(
            P,
            np.r_[-Jm, np.zeros(6)],
            A=np.hstack((J, np.eye(6))),
            b=v,
            lb=lb,
            ub=ub,
            solver="quadprog",
        )
        assert np.abs(mmc - x[:n]).max() < 1e-6 * max(1.0, np.abs(x).max())


def one_trial(arm, lo, hi, q0, goal, cap):
    """The oracle: the authors' loop as their script runs it, one trial at a time, each
    controller's step from :func:`servo` and :func:`command` (each checked above against an
    independent statement)."""
    n = q0.size
    state = {
        c: {"q": q0.copy(), "arrived": False, "failed": False, "singular": False, "m": 0.0, "it": 0}
        for c in CONTROLLERS
    }
    it = 0
    while True:
        for c in CONTROLLERS:
            s = state[c]
            if s["arrived"] or s["failed"]:
                continue
            q = s["q"]
            T, J0, m, Jm = arm.state(q)
            R = T[:3, :3]
            J = np.vstack((R.T @ J0[:3], R.T @ J0[3:]))
            v, s["arrived"], e_s = servo(T, goal)
            try:
                qd = command(c, J, Jm, v, e_s, q, lo, hi)
            except Singular:
                s["failed"] = s["singular"] = True
                qd = np.zeros(n)
            s["m"] += m
            s["it"] += 1
            if np.any(q[: n - 2] <= lo[: n - 2]) or np.any(q[: n - 2] >= hi[: n - 2]):
                s["failed"] = True
            s["qd"] = qd
        for c in CONTROLLERS:
            if "qd" in state[c]:
                state[c]["q"] = state[c]["q"] + DT * state[c].pop("qd")
        it += 1
        if all(state[c]["arrived"] or state[c]["failed"] for c in (Paper.RRMC, Paper.MMC)):
            break
        if it > cap:
            break
    return {
        c: {
            "arrived": s["arrived"],
            "failed": s["failed"] and not s["arrived"],
            "singular": s["singular"],
            "missed": not s["arrived"] and not s["failed"],
            "joint_limit": s["failed"] and not s["arrived"] and not s["singular"],
            "mean_m": s["m"] / s["it"] if s["it"] else np.nan,
            "final_m": arm.manipulability(s["q"]),
        }
        for c, s in state.items()
    }


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_the_stacked_trials_are_the_authors_loop_one_trial_at_a_time(name):
    """run_trials steps every trial together; each trial's outcome is the one the authors'
    loop gives it alone (the oracle above), on random tasks that arrive, fail and miss."""
    sc = load_scenario(name)
    arm, protocol = sc.serial_arm, PROTOCOLS[name]
    lo, hi = np.asarray(sc.arm.q_min, float), np.asarray(sc.arm.q_max, float)
    if protocol.limit is not None:
        lo, hi = np.full(sc.n, -protocol.limit), np.full(sc.n, protocol.limit)
    rng = np.random.default_rng(7)
    off = protocol.shrink * (np.abs(lo) + np.abs(hi))
    q0s = rng.uniform(lo + off, hi - off, (24, sc.n))
    goals = np.stack([arm.forward(rng.uniform(lo + off, hi - off)) for _ in range(24)])
    q0s[0] = lo + 1e-3  # a start at a limit: failed at once
    stacked = run_trials(arm, lo, hi, q0s, goals, protocol.cap)
    seen = set()
    for got, q0, goal in zip(stacked, q0s, goals, strict=True):
        want = one_trial(arm, lo, hi, q0, goal, protocol.cap)
        for c in CONTROLLERS:
            flags = ("arrived", "failed", "singular", "missed", "joint_limit")
            assert {k: got[c][k] for k in flags} == {k: want[c][k] for k in flags}, c
            assert got[c]["mean_m"] == pytest.approx(want[c]["mean_m"], rel=1e-9, abs=1e-15)
            assert got[c]["final_m"] == pytest.approx(want[c]["final_m"], rel=1e-9, abs=1e-15)
            seen |= {k for k in flags if got[c][k]}
    assert {"arrived", "failed"} <= seen  # the cases the comparison covers


def test_the_protocol_counts_every_trial_once_and_is_seeded(tmp_path, capsys):
    data = run_paper_protocol(arms=("panda",), trials=12, seed=3)
    again = run_paper_protocol(arms=("panda",), trials=12, seed=3)
    assert data == again
    for c in CONTROLLERS:
        r = data["results"]["panda"][c]
        assert r["arrived"] + r["failed"] + r["missed"] == 12
        assert r["failed"] == r["joint_limit"] + r["singular"]
        assert r["failure_rate"] == pytest.approx(100 * (12 - r["arrived"]) / 12)
    assert data["results"]["panda"]["MMC"]["joint_limit"] == 0  # the damper holds
    assert "(0.0942)" in paper_table(data)
    out = tmp_path / "m"
    assert main(["mmc", "--arm", "panda", "--trials", "3", "--json", "--out", str(out)]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed["protocol"] == "paper" and set(printed["results"]["panda"]) == set(CONTROLLERS)
    assert main(["mmc", "--protocol", "paper", "--arm", "task1"]) == 2


def test_the_ur5_runs_under_its_scripts_limits_and_subset_and_alone_as_with_the_panda():
    """expUR.py loads the joint-limited UR5 (+-pi), shrinks by 0.27 and caps at 100 steps, and
    averages over the trials where RRMC and MMC arrived; seeded by name, the UR5's rows do not
    depend on whether the Panda ran first."""
    assert PROTOCOLS["ur5"].limit == pytest.approx(np.pi) and PROTOCOLS["ur5"].cap == 100
    alone = run_paper_protocol(arms=("ur5",), trials=6, seed=2)["results"]["ur5"]
    both = run_paper_protocol(arms=("panda", "ur5"), trials=6, seed=2)["results"]["ur5"]
    assert repr(alone) == repr(both)
    assert alone["MMC"]["subset"] == ["RRMC", "MMC"]
    for c in CONTROLLERS:
        lo, hi = alone[c]["failure_rate_ci"]
        assert lo <= alone[c]["failure_rate"] <= hi


def test_confidence_intervals_against_scipy():
    from scipy import stats

    from emdm.studies.stats import mean_interval, wilson

    x = np.random.default_rng(0).normal(0.05, 0.01, 40)
    lo, hi = stats.t.interval(0.95, len(x) - 1, loc=x.mean(), scale=stats.sem(x))
    assert mean_interval(x) == pytest.approx((lo, hi), rel=1e-12)
    # Wilson's interval is the set of p whose score test accepts the observed count
    k, n = 23, 90
    a, b = wilson(k, n)
    for p, inside in ((a + 1e-9, True), (b - 1e-9, True), (a - 1e-6, False), (b + 1e-6, False)):
        z = (k / n - p) / np.sqrt(p * (1 - p) / n)
        assert (abs(z) <= 1.96) == inside
    assert np.isnan(mean_interval([1.0])[0]) and np.isnan(wilson(0, 0)[0])
