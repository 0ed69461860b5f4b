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
    PI,
    PS,
    Y,
    command,
    paper_table,
    run_paper_protocol,
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
