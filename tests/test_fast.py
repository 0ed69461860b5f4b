"""The compiled fast path and the batch API against the reference path (to 1e-12)."""

from __future__ import annotations

import numpy as np
import pytest

import emdm
from emdm import NoSolution
from emdm.sim.fast import run_fast, simulate_batch

CONTROLLERS = ["UC-IVKC", "C-IVKC", "UC-EMDM", "C-EMDM"]


def assert_same(sc, controller, expect_reference_steps=None):
    ref = emdm.simulate(sc, controller)
    fast = run_fast(sc, controller)
    assert fast["steps"] == ref.steps and fast["reached"] == ref.reached
    for key, value in (
        ("q", ref.q),
        ("qd", ref.qd),
        ("delta", ref.delta),
        ("alpha", ref.alpha),
        ("m", ref.m),
    ):
        # to 1e-12 of the quantity's magnitude (UC commands reach 20 rad/s on random arms)
        scale = max(1.0, float(np.abs(value).max(initial=0.0)))
        np.testing.assert_allclose(fast[key], value, rtol=0, atol=1e-12 * scale, err_msg=key)
    if expect_reference_steps is not None:
        assert (len(fast["reference_steps"]) > 0) == expect_reference_steps
    return fast


@pytest.mark.parametrize("task", ["task1", "task2"])
@pytest.mark.parametrize("controller", CONTROLLERS)
def test_presets_match_the_reference_without_help(task, controller):
    assert_same(emdm.load_scenario(task), controller, expect_reference_steps=False)


def assert_every_step_exact(sc, controller):
    """At every state the fast path visits, its command is the reference optimum of that state."""
    from emdm.core.controllers import program_at
    from emdm.solvers import solve_chain

    fast = run_fast(sc, controller)
    ctrl = emdm.get_controller(controller)
    n = sc.n
    for k in range(fast["steps"]):
        program = program_at(ctrl, sc, fast["q"][k])
        ref = solve_chain(program.qp, ["active-set", "daqp"]).x
        x = np.concatenate((fast["qd"][k], fast["delta"][k][: program.qp.n_slack]))
        assert np.abs(x - ref).max() <= 1e-12 * max(1.0, np.abs(ref).max()), (controller, k)
        assert abs(fast["alpha"][k] - program.alpha) <= 1e-12
        np.testing.assert_allclose(
            fast["q"][k + 1],
            fast["q"][k] + x[:n] * sc.motion.dt,
            rtol=0,
            atol=1e-15 * max(1.0, np.abs(fast["q"][k]).max()),
        )


def test_random_arms_match_the_reference(rng):
    # Step by step, not whole trajectories: random UC-EMDM weights drive joints at up to
    # ~1000 rad/s, a chaotic closed loop in which any two exact solvers' 1e-16 differences
    # grow to O(1) within 100 steps (daqp and the active set alike).
    checked = 0
    for trial in range(16):
        n = 2 + trial % 7
        lengths = rng.uniform(0.1, 0.8, n)
        lim = rng.uniform(1.5, 3.0)
        q0 = rng.uniform(-lim + 0.3, lim - 0.3, n)
        goal = emdm.PlanarArm(lengths).forward(rng.uniform(-lim, lim, n))
        data = emdm.load_scenario("task1").to_dict()
        data["arm"] = {
            "lengths": lengths.tolist(),
            "q_min": -lim,
            "q_max": lim,
            "qd_min": -rng.uniform(0.3, 2),
            "qd_max": rng.uniform(0.3, 2),
        }
        data["motion"].update(
            q0=q0.tolist(), goal=goal.tolist(), max_time=2.0, kp=float(rng.uniform(0.5, 3))
        )
        data["weights"] = {
            "effort": float(10 ** rng.uniform(-2, 0)),
            "manipulability": float(rng.uniform(0, 20)),
            "slack": 10.0,
        }
        data["damper"] = {"influence": 0.6, "stop": 0.08, "gain": float(rng.uniform(0.5, 2))}
        sc = emdm.scenario_from_dict(data, source=f"random{trial}")
        for controller in CONTROLLERS:
            assert_every_step_exact(sc, controller)
            checked += 1
    assert checked == 64


@pytest.mark.parametrize("controller", CONTROLLERS)
def test_singular_start_hands_steps_to_the_reference(controller):
    sc = emdm.load_scenario("task1", {"motion.q0": [0.0, 0.0, 0.0], "motion.max_time": 3.0})
    fast = assert_same(sc, controller)
    if not controller.startswith("C-"):
        assert fast["reference_steps"][:1] == [0]  # rank-deficient J with free variables


def test_other_policies_run_through_the_reference():
    sc = emdm.load_scenario("task1", {"controller.on_infeasible": "slack", "motion.max_time": 2.0})
    fast = assert_same(sc, "C-EMDM")
    assert len(fast["reference_steps"]) == fast["steps"]
    err = emdm.load_scenario("task1", {"controller.on_infeasible": "error"})
    with pytest.raises(NoSolution, match="step 0"):
        run_fast(err, "C-EMDM")


def test_batch_outcomes_equal_the_reference_metrics(rng):
    sc = emdm.load_scenario("task1", {"motion.max_time": 12.0})
    arm = sc.planar_arm
    goals = np.array([arm.forward(t) for t in rng.uniform(-1.2, 1.2, (12, 3))])
    q0s = rng.uniform(-1.5, 1.5, (12, 3))
    for controller in ("C-EMDM", "UC-IVKC"):
        out = simulate_batch(sc, controller, goals=goals, q0s=q0s)
        for r in range(12):
            one = sc.with_overrides({"motion.goal": list(goals[r]), "motion.q0": list(q0s[r])})
            mt = emdm.metrics(emdm.simulate(one, controller))
            assert out["steps"][r] == mt["steps"] and out["reached"][r] == mt["reached"]
            for key in (
                "min_manipulability",
                "mean_manipulability",
                "total_effort",
                "final_error",
                "max_abs_qd",
            ):
                assert out[key][r] == pytest.approx(mt[key], rel=1e-12, abs=1e-12), key
            if mt["reached"]:
                assert out["time_to_goal"][r] == pytest.approx(mt["time_to_goal"], abs=1e-12)
            else:
                assert np.isnan(out["time_to_goal"][r])


def test_batch_broadcasts_and_finishes_hard_runs_exactly():
    sc = emdm.load_scenario("task1", {"motion.max_time": 2.0})
    q0s = np.array([[0.0, 0.0, 0.0], list(sc.motion.q0)])  # a singular start needs the reference
    out = emdm.simulate_batch(sc, "UC-EMDM", q0s=q0s)
    assert out["steps"].shape == (2,) and list(out["reference_runs"]) == [0]
    ref = emdm.metrics(emdm.simulate(sc.with_overrides({"motion.q0": [0.0, 0.0, 0.0]}), "UC-EMDM"))
    assert out["mean_manipulability"][0] == pytest.approx(ref["mean_manipulability"], rel=1e-12)
