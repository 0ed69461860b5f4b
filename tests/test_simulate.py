"""Closed-loop runs: every recorded command is the optimum of its step's program; limits hold."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import assert_step_optimal, reference_bounds

import emdm

CONTROLLERS = ["UC-IVKC", "C-IVKC", "UC-EMDM", "C-EMDM"]


@pytest.fixture(scope="module")
def preset_runs():
    return {
        (task, c): emdm.simulate(emdm.load_scenario(task), c)
        for task in ("task1", "task2")
        for c in CONTROLLERS
    }


@pytest.mark.parametrize("task", ["task1", "task2"])
@pytest.mark.parametrize("controller", CONTROLLERS)
def test_every_step_is_the_exact_optimum(preset_runs, task, controller):
    run = preset_runs[(task, controller)]
    sc = run.scenario
    assert run.steps > 0
    for k in range(run.steps):
        assert_step_optimal(sc, controller, run.q[k], run.qd[k], run.delta[k], run.alpha[k])
    assert run.kkt.max() <= 1e-9
    assert run.bound_excess.max() <= 1e-12


@pytest.mark.parametrize("task", ["task1", "task2"])
@pytest.mark.parametrize("controller", ["C-IVKC", "C-EMDM"])
def test_constrained_runs_respect_velocity_limits_and_stop_zones(preset_runs, task, controller):
    run = preset_runs[(task, controller)]
    sc = run.scenario
    for k in range(run.steps):
        lo, hi = reference_bounds(sc, run.q[k])
        assert np.all(run.qd[k] >= lo - 1e-12) and np.all(run.qd[k] <= hi + 1e-12)
    assert np.all(np.abs(run.qd) <= sc.arm.qd_max + 1e-12)
    margin = np.minimum(run.q - sc.arm.q_min, sc.arm.q_max - run.q)
    assert margin.min() >= sc.damper.stop.min()
    # the damper invariant: inside the influence zone, d - s shrinks by at most the factor
    # 1 - dt / (K (i - s)) per step, so a joint never reaches its stop zone
    factor = 1 - sc.motion.dt / (sc.damper.gain * (sc.damper.influence - sc.damper.stop))
    for side in (sc.arm.q_max - run.q, run.q - sc.arm.q_min):
        gap = side - sc.damper.stop
        assert np.all(gap > 0)
        in_zone = side[:-1] < sc.damper.influence
        assert np.all((gap[1:] >= factor * gap[:-1] - 1e-12)[in_zone])


def test_task1_start_is_scaled_and_recorded(preset_runs):
    run = preset_runs[("task1", "C-EMDM")]
    assert 0.17 < run.alpha[0] < 0.19
    assert run.policy[0] == "scale"
    scaled = run.alpha < 1
    # the commanded end-effector velocity is alpha v, along v
    for k in np.flatnonzero(scaled)[:10]:
        J = run.scenario.planar_arm.jacobian(run.q[k])
        np.testing.assert_allclose(J @ run.qd[k], run.alpha[k] * run.v[k], atol=1e-12)


def test_outcomes_of_the_presets(preset_runs):
    for (task, controller), run in preset_runs.items():
        if (task, controller) == ("task2", "C-IVKC"):
            # the straight path to the goal needs q1 beyond its damper: IVKC stalls there
            assert not run.reached and run.steps == run.scenario.max_steps
            assert run.alpha[-1] < 1e-6
        else:
            assert run.reached, (task, controller)
            assert run.error_norm[-1] < run.scenario.motion.tolerance
            assert np.all(run.error_norm[:-1] >= run.scenario.motion.tolerance)


def test_emdm_raises_mean_manipulability_over_ivkc_on_task1(preset_runs):
    for prefix in ("UC-", "C-"):
        emdm_run, ivkc = (
            preset_runs[("task1", prefix + "EMDM")],
            preset_runs[("task1", prefix + "IVKC")],
        )
        assert emdm_run.m.mean() > ivkc.m.mean()


def test_runs_are_deterministic(preset_runs):
    again = emdm.simulate(emdm.load_scenario("task1"), "C-EMDM")
    ref = preset_runs[("task1", "C-EMDM")]
    assert np.array_equal(again.q, ref.q) and np.array_equal(again.qd, ref.qd)


def test_record_is_consistent(preset_runs):
    run = preset_runs[("task1", "C-EMDM")]
    sc = run.scenario
    dt = sc.motion.dt
    np.testing.assert_array_equal(run.t, np.arange(run.steps + 1) * dt)
    np.testing.assert_allclose(run.q[1:], run.q[:-1] + run.qd * dt, atol=1e-15)
    for k in range(run.steps + 1):
        np.testing.assert_allclose(run.p[k], sc.planar_arm.forward(run.q[k]), atol=1e-15)
    np.testing.assert_allclose(run.effort, 0.5 * np.sum(run.qd**2, axis=1))
    assert len(run.solver) == len(run.status) == run.steps


def test_run_that_times_out_is_a_result():
    sc = emdm.load_scenario("task1", {"motion.max_time": 1.0})
    run = emdm.simulate(sc, "C-EMDM")
    assert not run.reached and run.steps == 20 and run.time_to_goal is None


def test_a_budget_reaches_the_gradient_free_solvers_of_the_chain_and_no_other(monkeypatch):
    """``simulate(..., budget=N)`` gives every gradient-free solver of its chain N evaluations
    per step (the solver lab runs each solver's closed loop at the budget it measured it at)."""
    import dataclasses

    from emdm.solvers import base

    calls: list[tuple[str, dict]] = []

    def spy(name):
        spec = base.get_solver(name)

        def solve(qp, **kwargs):
            calls.append((name, kwargs))
            return spec.solve(qp, **kwargs)

        return dataclasses.replace(spec, solve=solve)

    for name in ("nelder-mead", "active-set"):
        monkeypatch.setitem(base._REGISTRY, name, spy(name))
    sc = emdm.load_scenario("task2", {"motion.max_time": 0.15})
    run = emdm.simulate(sc, "C-EMDM", solver="nelder-mead", certify=False, budget=37)
    assert run.steps == 3 and [n for n, _ in calls] == ["nelder-mead"] * 3
    assert all(kwargs == {"budget": 37} for _, kwargs in calls)
    assert run.iterations.max() <= 37  # nelder-mead iterates at most once per evaluation
    calls.clear()
    emdm.simulate(sc, "C-EMDM", solver="nelder-mead", certify=False)
    assert [kwargs for _, kwargs in calls] == [{}] * 3  # no budget: each solver's own default
    calls.clear()
    emdm.simulate(sc, "C-EMDM", solver="nelder-mead", fallback=("active-set",), budget=37)
    assert {n: kw for n, kw in calls} == {"nelder-mead": {"budget": 37}, "active-set": {}}


def test_goal_at_the_start_needs_no_step():
    sc = emdm.load_scenario("task2")
    start = sc.planar_arm.forward(sc.motion.q0)
    run = emdm.simulate(sc.with_overrides({"motion.goal": list(start)}), "C-EMDM")
    assert run.reached and run.steps == 0 and run.time_to_goal == 0.0


@pytest.mark.parametrize("q0", [[0.0, 0.0, 0.0], [0.5, 0.0]])
@pytest.mark.parametrize("controller", CONTROLLERS)
def test_singular_starts_run_cleanly(q0, controller):
    base = "task1" if len(q0) == 3 else "task2"
    sc = emdm.load_scenario(base, {"motion.q0": q0})
    run = emdm.simulate(sc, controller)
    assert np.all(np.isfinite(run.q)) and np.all(np.isfinite(run.qd))
    if controller.endswith("EMDM"):
        assert run.m[1] > 0 or run.reached  # EMDM leaves the singularity at once


def test_one_definition_of_scaled_and_stalled():
    """``Run.scaled`` and ``Run.stalled_from`` are what metrics, the report and the playground read:
    task2 C-IVKC stalls from the state after which its error stays within STALL_BAND of the end."""
    from emdm.core.tolerances import STALL_BAND, STALL_TIME

    sc = emdm.load_scenario("task2")
    run = emdm.simulate(sc, "C-IVKC")
    k = run.stalled_from
    assert k is not None and run.t[-1] - run.t[k] >= STALL_TIME
    err = run.error_norm
    assert (
        np.all(np.abs(err[k:] - err[-1]) <= STALL_BAND) and abs(err[k - 1] - err[-1]) > STALL_BAND
    )
    assert emdm.metrics(run)["scaled_steps"] == int(run.scaled.sum()) == int((run.alpha < 1).sum())
    assert emdm.simulate(sc, "C-EMDM").stalled_from is None  # it reaches the goal


def test_precompile_loads_every_loop_kernel_once(monkeypatch):
    import emdm
    from emdm.core import jit
    from emdm.sim.batch import _warm_up_batch
    from emdm.sim.loop import _warm_up

    emdm.precompile()
    assert _warm_up in jit._compiled and _warm_up_batch in jit._compiled

    def again(*_args: object) -> None:
        raise AssertionError("warmed up twice")

    monkeypatch.setattr(jit, "_first_use", again)
    emdm.precompile()  # a second call does nothing


def _signatures() -> dict[str, int]:
    """How many specializations every kernel of emdm has compiled (or loaded) in this process."""
    import sys

    from numba.core.dispatcher import Dispatcher

    found = {}
    for name, module in list(sys.modules.items()):
        if name.startswith("emdm"):
            for attr, value in vars(module).items():
                if isinstance(value, Dispatcher):
                    found[f"{value.py_func.__module__}.{attr}"] = len(value.signatures)
    return found


def test_after_precompile_batches_and_the_per_step_api_compile_nothing_more():
    """precompile() warms what users meet first: a batch given one goal or start row for many
    (broadcast views are read-only, and read-only arrays were a specialization of their own:
    20 s of compiling in the first batch of a process), and the per-step API of the lab."""
    from emdm.core.controllers import get_controller, program_at
    from emdm.solvers import DEFAULT_SOLVER, solve_chain

    emdm.precompile()
    before = _signatures()
    for task in ("task1", "panda"):
        sc = emdm.load_scenario(task)
        emdm.simulate_batch(sc, "C-EMDM", goals=[sc.motion.goal] * 2)  # q0s: one row for two
        emdm.simulate_batch(sc, "UC-IVKC", q0s=[sc.motion.q0] * 2)  # goals: one row for two
        for name in ("UC-IVKC", "C-EMDM"):
            program = program_at(get_controller(name), sc, np.asarray(sc.motion.q0))
            solve_chain(program.qp, [DEFAULT_SOLVER])
    after = _signatures()
    assert {k: (before.get(k, 0), v) for k, v in after.items() if v != before.get(k, 0)} == {}


def test_buffer_estimates_and_a_run_too_large_for_the_machine_is_refused_up_front(monkeypatch):
    """An arm whose buffers would not fit is one ScenarioError naming the key, before anything
    is allocated (a 2,000-link planar arm needs about 32 GB: its gradient's minors grow with the
    cube of the joints); the estimates are within 25 % of what is allocated."""
    import pytest

    from emdm.sim import buffers

    def allocated(x: object) -> int:
        if isinstance(x, np.ndarray):
            return x.nbytes
        if isinstance(x, tuple):
            return sum(allocated(y) for y in x)
        return 0

    for n, nt, ng, spatial in (
        (50, 2, 0, False),
        (200, 2, 0, False),
        (40, 6, 0, True),
        (20, 2, 100, False),
    ):
        nx = n + nt
        real = allocated(buffers.step_work(n, nx, nt, ng, 0))
        assert 0.8 <= buffers.work_bytes(n, nx, nt, ng, spatial) / real <= 1.25
    monkeypatch.setattr(buffers, "memory_available", lambda: 2_000_000)
    sc = emdm.load_scenario(
        "task1",
        {"arm.lengths": [0.02] * 60, "motion.q0": [0.02] * 60, "damper.influence": 0.5},
    )
    with pytest.raises(emdm.ScenarioError, match=r"arm: 60 joints need about .* use fewer joints"):
        emdm.simulate(sc, "C-EMDM")
    # a run that never arrives, with room for a billion steps: its record grows until it would
    # not fit, then one ScenarioError naming max_time (a pareto grid was killed at 24 GB)
    far = emdm.load_scenario("task1", {"motion.goal": [3.0, 0.0], "motion.max_time": 5e7})
    with pytest.raises(
        emdm.ScenarioError, match=r"motion.max_time: a record of 4096 steps .* use a shorter one"
    ):
        emdm.simulate(far, "C-EMDM")
    with pytest.raises(emdm.ScenarioError, match=r"task1: (arm|motion\.max_time): .* GB"):
        emdm.simulate_batch(sc, "C-EMDM")  # a full-length record per thread: the larger part
    assert emdm.simulate(emdm.load_scenario("task1"), "C-EMDM").reached  # small runs go on


def test_simulate_passes_one_signature_per_kind_of_run_to_the_loop(monkeypatch):
    """simulate calls the loop's machine code without numba's per-call type lookup
    (loop._entry, one entry for plain planar runs and one for all others): sound only while
    every kind of arm, task, program and obstacle gives the loop arguments of one of these two
    types, told apart by the last (``full``), which this checks."""
    from emdm.sim import loop

    seen: set[tuple[object, ...]] = set()
    real = loop._entry

    def spy(args):
        seen.add(tuple(loop.run_kernel.typeof_pyval(a) for a in args))
        return real(args)

    monkeypatch.setattr(loop, "_entry", spy)
    planes = {"planes.normals": [[0.0, 1.0]], "planes.offsets": [-0.5]}
    cases = [(p, {}) for p in ("task1", "task2", "obstacle", "panda", "ur5", "panda-obstacles")]
    cases += [("task1", {"arm.lengths": [0.3] * 7, "motion.q0": [0.3] * 7}), ("task1", planes)]
    cases += [("ur5", {"motion.axes": "trans"}), ("task1", {"controller.on_infeasible": "slack"})]
    for preset, overrides in cases:
        sc = emdm.load_scenario(preset, {"motion.max_time": 0.2, **overrides})
        for name in ("UC-IVKC", "C-EMDM", "MMC", "NEO"):
            emdm.simulate(sc, name)
    assert len(seen) == 2, seen
    assert sorted(str(signature[-1]) for signature in seen) == ["bool", "none"]


@pytest.mark.parametrize(
    ("preset", "overrides"),
    [
        ("task1", {}),
        ("task2", {}),
        ("task1", {"arm.lengths": [0.3] * 7, "motion.q0": [0.3] * 7, "weights.effort": 0.001}),
        ("task1", {"controller.on_infeasible": "slack"}),
        ("task2", {"motion.goal": [-0.5, -0.6], "motion.max_time": 3.0}),
    ],
)
def test_a_plain_planar_run_records_what_the_full_loop_records(monkeypatch, preset, overrides):
    """The loop compiled for plain planar runs (``full`` None: no spatial, obstacle or row code)
    records, bit for bit, what the loop compiled for every kind of run records on the same
    scenario (the solve times aside, which are measured)."""
    from emdm.sim import loop

    sc = emdm.load_scenario(preset, overrides)
    names = ("UC-IVKC", "C-IVKC", "UC-EMDM", "C-EMDM")
    plain = {name: emdm.simulate(sc, name) for name in names}
    assert loop.full_flag(sc, emdm.get_controller("C-EMDM").program_data(sc)) is None
    monkeypatch.setattr(loop, "full_flag", lambda scenario, prog: True)
    for name in names:
        full = emdm.simulate(sc, name)
        for key in ("q", "qd", "p", "e", "v", "m", "alpha", "delta", "lo", "hi", "active"):
            np.testing.assert_array_equal(getattr(full, key), getattr(plain[name], key))
        for key in ("iterations", "kkt", "rows", "clearance"):
            np.testing.assert_array_equal(getattr(full, key), getattr(plain[name], key))
        assert full.solver == plain[name].solver and full.reached == plain[name].reached


def test_a_large_arm_runs_in_slices_with_the_same_record(monkeypatch):
    """From SLICED_FROM joints the loop returns to Python every few steps (a signal is honoured
    between two slices, not only when a 256-step chunk ends: a 400-link step takes about 0.5 s);
    the slices write through views of the record, which ends the same as in one piece."""
    from emdm.sim import loop

    n = 70
    sc = emdm.load_scenario(
        "task1",
        {"arm.lengths": [1.5 / n] * n, "motion.q0": [0.02] * n, "motion.max_time": 1.0},
    )
    calls: list[int] = []
    real = loop._entry

    def counted(args):
        kernel = real(args)

        def call(*a):
            calls.append(a[7])  # the step each call starts from
            return kernel(*a)

        return call

    monkeypatch.setattr(loop, "_entry", counted)
    monkeypatch.setattr(loop, "SLICE_WORK", 5 * n**3)  # five steps per slice
    sliced = emdm.simulate(sc, "C-EMDM")
    assert calls[:3] == [0, 5, 10] and len(calls) >= sliced.steps // 5
    calls.clear()
    monkeypatch.setattr(loop, "SLICED_FROM", 10**6)  # in one piece
    whole = emdm.simulate(sc, "C-EMDM")
    assert len(calls) == 1
    for name in ("q", "qd", "alpha", "m", "kkt", "active", "iterations"):
        assert np.array_equal(getattr(sliced, name), getattr(whole, name)), name
