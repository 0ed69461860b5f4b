"""The compiled loop: equal to the numpy solver path to 1e-12, exact at every step, a full record,
batches equal to single runs, steps handed to the solver chain, and a record that grows."""

from __future__ import annotations

import numpy as np
import pytest
import reference

import emdm
from emdm.sim import loop

CONTROLLERS = ["UC-IVKC", "C-IVKC", "UC-EMDM", "C-EMDM"]
FIELDS = ("q", "p", "e", "v", "m", "qd", "effort", "manip_rate", "alpha", "delta", "lo", "hi")


def assert_same_run(a, b, tol=1e-12):
    assert a.steps == b.steps and a.reached == b.reached
    for key in FIELDS:
        x, y = getattr(a, key), getattr(b, key)
        finite = np.isfinite(x)
        np.testing.assert_array_equal(finite, np.isfinite(y), err_msg=key)
        scale = max(1.0, float(np.abs(x[finite]).max(initial=0.0)))
        np.testing.assert_allclose(x[finite], y[finite], rtol=0, atol=tol * scale, err_msg=key)
    np.testing.assert_array_equal(a.active, b.active)
    assert a.policy == b.policy


@pytest.mark.parametrize("task", ["task1", "task2"])
@pytest.mark.parametrize("controller", CONTROLLERS)
def test_compiled_loop_equals_the_numpy_solver_path(task, controller, numpy_solver):
    sc = emdm.load_scenario(task)
    fast = emdm.simulate(sc, controller)
    slow = emdm.simulate(sc, controller, solver=numpy_solver, fallback=())
    assert set(fast.solver) == {"active-set"} and set(slow.solver) == {numpy_solver}
    assert_same_run(fast, slow)


def random_scenario(rng, policy="scale"):
    n = int(rng.integers(2, 9))
    lengths = rng.uniform(0.1, 0.6, n)
    r = rng.uniform(0.3, 0.8) * lengths.sum()
    angle = rng.uniform(-np.pi, np.pi)
    return emdm.load_scenario(
        "task1",
        {
            "arm.lengths": lengths.tolist(),
            "arm.q_min": -2.0,
            "arm.q_max": 2.0,
            "arm.qd_min": -1.0,
            "arm.qd_max": 1.0,
            "damper.influence": 0.785398,
            "damper.stop": 0.0872665,
            "damper.gain": 1.0,
            "motion.q0": rng.uniform(-1.2, 1.2, n).tolist(),
            "motion.goal": [r * np.cos(angle), r * np.sin(angle)],
            "motion.max_time": 8.0,
            "controller.on_infeasible": policy,
        },
    )


@pytest.mark.slow
def test_random_arms_equal_the_numpy_path_and_every_step_is_exact(rng, numpy_solver):
    """2-8 links: runs that reach agree to 1e-12 with the numpy path (a run that does not reach
    may be chaotic: UC-EMDM at 100 rad/s amplifies rounding), and every step is certified."""
    compared = 0
    for trial in range(10):
        sc = random_scenario(rng, ("scale", "slack")[trial % 2])
        for controller in CONTROLLERS:
            fast = emdm.simulate(sc, controller)
            assert fast.kkt.max() <= 1e-9 and fast.bound_excess.max() <= 1e-12
            for k in range(0, fast.steps, 7):  # an independent optimum at every 7th step
                P, c, A, b, lb, ub = reference_program(sc, controller, fast, k)
                x = np.concatenate((fast.qd[k], fast.delta[k][: P.shape[0] - sc.n]))
                assert reference.kkt_residual(P, c, A, b, lb, ub, x) <= 1e-9
            if fast.reached:
                slow = emdm.simulate(sc, controller, solver=numpy_solver, fallback=())
                assert_same_run(fast, slow)
                compared += 1
    assert compared >= 15


def reference_program(sc, controller, run, k):
    from conftest import reference_program as program

    free = run.policy[k] == "slack"
    return program(sc, controller, run.q[k], run.alpha[k], slack_free=free)


def test_slack_policy_hands_infeasible_steps_to_the_chain_and_records_them():
    sc = emdm.load_scenario("task1", {"controller.on_infeasible": "slack"})
    run = emdm.simulate(sc, "C-EMDM")
    slack_steps = [k for k, p in enumerate(run.policy) if p == "slack"]
    assert slack_steps and run.alpha.max() == 1.0
    for k in slack_steps:
        assert run.attempts[k].startswith("active-set: ")
        assert np.any(run.delta[k] != 0)
    assert run.kkt.max() <= 1e-9


def test_another_solver_runs_every_step_through_the_chain():
    sc = emdm.load_scenario("task2")
    run = emdm.simulate(sc, "C-EMDM", solver="daqp")
    fast = emdm.simulate(sc, "C-EMDM")
    assert set(run.solver) == {"daqp"} and not run.fallback.any()
    assert_same_run(run, fast, tol=1e-9)


def test_the_record_grows_past_its_first_chunk():
    sc = emdm.load_scenario("task2")
    run = emdm.simulate(sc, "C-IVKC")  # stalls at its damper: 600 steps, past 256
    assert run.steps == sc.max_steps > loop.FIRST_CHUNK and not run.reached
    assert run.q.shape == (run.steps + 1, sc.n) and len(run.solver) == run.steps
    assert np.all(np.isfinite(run.q)) and np.all(np.isfinite(run.solve_time))


def test_the_record_is_sized_by_the_run_not_by_max_time():
    sc = emdm.load_scenario("task1", {"motion.max_time": 1e7})
    run = emdm.simulate(sc, "C-EMDM")
    assert run.reached and run.steps == 163
    assert run.q.base is not None and run.q.base.shape[0] <= 4 * loop.FIRST_CHUNK + 1


def test_record_fields_are_consistent_with_each_other():
    sc = emdm.load_scenario("task1")
    run = emdm.simulate(sc, "C-EMDM")
    arm = sc.planar_arm
    for k in (0, 50, run.steps - 1):
        p, _, m, Jm = reference.kinematics(sc.arm.lengths, run.q[k])
        np.testing.assert_allclose(run.p[k], p, atol=1e-15)
        assert run.m[k] == pytest.approx(m, abs=1e-15)
        assert run.manip_rate[k] == pytest.approx(Jm @ run.qd[k], abs=1e-14)
        assert run.effort[k] == pytest.approx(0.5 * run.qd[k] @ run.qd[k], rel=1e-15)
        np.testing.assert_allclose(run.e[k], sc.motion.goal - arm.forward(run.q[k]), atol=1e-15)
    assert np.all(run.solve_time > 0) and np.all(run.iterations >= 0)
    tol = 1e-12 * (1 + np.abs(run.hi))
    expected = np.where(run.qd <= run.lo + tol, -1, np.where(run.qd >= run.hi - tol, 1, 0))
    np.testing.assert_array_equal(run.active, expected)


def test_failed_step_carries_the_partial_run():
    sc = emdm.load_scenario("task1", {"controller.on_infeasible": "error"})
    with pytest.raises(emdm.NoSolution) as info:
        emdm.simulate(sc, "C-EMDM")
    exc = info.value
    assert exc.controller == "C-EMDM" and exc.step == 0
    assert exc.run is not None and exc.run.steps == 0 and exc.run.q.shape == (1, 3)


@pytest.mark.parametrize("controller", CONTROLLERS)
def test_batch_equals_single_runs(controller, rng):
    sc = emdm.load_scenario("task1")
    targets = rng.uniform(-1.2, 1.2, (6, sc.n))
    goals = np.array([sc.planar_arm.forward(t) for t in targets])
    batch = emdm.simulate_batch(sc, controller, goals=goals)
    assert isinstance(batch, emdm.BatchResult) and len(batch) == 6
    for r, goal in enumerate(goals):
        run = emdm.simulate(sc.with_overrides({"motion.goal": goal.tolist()}), controller)
        m = emdm.metrics(run)
        assert batch.steps[r] == run.steps and batch.reached[r] == run.reached
        for key in ("min_manipulability", "mean_manipulability", "total_effort", "final_error"):
            assert getattr(batch, key)[r] == pytest.approx(m[key], rel=1e-12, abs=1e-15), key


def test_batch_finishes_runs_the_kernel_hands_back():
    sc = emdm.load_scenario("task1", {"controller.on_infeasible": "slack"})
    batch = emdm.simulate_batch(sc, "C-EMDM", q0s=[sc.motion.q0, [0.0, 0.5, 0.5]])
    assert list(batch.reference_runs) == [0, 1]
    run = emdm.simulate(sc, "C-EMDM")
    assert batch.steps[0] == run.steps and batch.time_to_goal[0] == run.time_to_goal


def test_compile_notice_is_one_line_and_only_when_slow(capsys, monkeypatch):
    import time

    from emdm.core import jit

    def slow() -> None:
        time.sleep(0.3)

    jit.ensure_compiled(slow, what="a test", notice_after=0.05)
    err = capsys.readouterr().err
    assert err.startswith("emdm: compiling a test") and err.count("\n") == 1 and " done in " in err
    jit.ensure_compiled(slow, notice_after=0.05)  # once per process
    assert capsys.readouterr().err == ""
    jit.ensure_compiled(lambda: None, notice_after=0.05)  # fast: a cache load says nothing
    assert capsys.readouterr().err == ""


def test_internal_kernels_refuse_python_and_plain_builders_match_the_compiled_ones():
    """A kernel compiled without an entry point for Python (``@kernel(internal=True)``) raises
    TypeError when Python calls it (a call would otherwise jump to a null address); the Python
    builders of :func:`~emdm.core.jit.plain` give arrays of the types the compiled ones give, so
    a run warmed up on either loads the same machine code."""
    from numba import typeof

    from emdm.core import jit
    from emdm.sim.buffers import step_work
    from emdm.solvers.kernels import _row_value

    with pytest.raises(TypeError, match="called only from kernels"):
        _row_value(np.zeros((1, 1)), 0, np.zeros(1))
    assert typeof(jit.plain(step_work)(3, 5, 2, 1, 1)) == typeof(step_work(3, 5, 2, 1, 1))


def test_a_helper_process_shares_the_first_compile_and_ends_with_it(tmp_path, monkeypatch):
    """:func:`~emdm.core.jit.ensure_compiled` with a helper: a second process runs the helper's
    share while the warm-up runs, and no process outlives the warm-up, whether the helper
    finished or not."""
    import signal
    import subprocess
    import time

    from emdm.core import jit

    started: list[subprocess.Popen[bytes]] = []
    real = jit._start_helper

    def start(helper):  # type: ignore[no-untyped-def]
        started.append(real(helper))
        return started[-1]

    monkeypatch.setattr(jit, "_start_helper", start)
    monkeypatch.setattr(jit, "_empty_cache", lambda: True)
    jit.ensure_compiled(lambda: time.sleep(0.5), helper=signal.pause)  # a helper that never ends
    assert len(started) == 1 and started[0].poll() is not None  # stopped with the warm-up


def _plus_one(x: float) -> float:
    return x + 1.0


def test_a_helper_skips_the_kernel_another_process_is_compiling():
    """The helper's share goes on to its next kernel when the first process holds a kernel's
    lock (it is compiling it), and compiles a kernel nobody holds."""
    import subprocess
    import sys

    from emdm.core import jit

    compiled = jit.kernel(_plus_one)
    path = jit._lock_path(compiled)
    assert path is not None
    hold = (
        "import fcntl, os, sys, time; fd = os.open(sys.argv[1], os.O_RDWR | os.O_CREAT); "
        "fcntl.flock(fd, fcntl.LOCK_EX); print('held', flush=True); time.sleep(60)"
    )
    other = subprocess.Popen([sys.executable, "-c", hold, path], stdout=subprocess.PIPE, text=True)
    try:
        assert other.stdout is not None and other.stdout.readline().strip() == "held"
        assert jit._busy(compiled)
        jit.compile_for(compiled, 1.0, unless_busy=True)
        assert not compiled.overloads  # skipped
    finally:
        other.kill()
        other.wait()
    assert not jit._busy(compiled)
    jit.compile_for(compiled, 1.0, unless_busy=True)
    assert len(compiled.overloads) == 1 and compiled(2.0) == 3.0


def test_kernel_failure_reaches_the_caller():
    from emdm.core import jit

    def broken() -> None:
        raise RuntimeError("no compiler")

    with pytest.raises(RuntimeError, match="no compiler"):
        jit.ensure_compiled(broken)


def _holds_array(t) -> bool:
    from numba.core import types

    if isinstance(t, types.Array):
        return True
    return isinstance(t, types.BaseTuple) and any(_holds_array(x) for x in t.types)


def test_kernels_that_borrow_return_no_array_and_leak_nothing():
    """``@kernel(refcount=False)`` compiles reference counting out of a kernel: sound only if it
    allocates no array (numba refuses to compile that) and returns none (the caller would release
    a reference it never got). Runs on every preset kind, then checks every compiled signature of
    every such kernel, and that the runtime's allocations and frees balance over repeated runs."""
    import gc
    import re

    from numba.core.runtime import _nrt_python, rtsys

    from emdm.core import jit

    cases = [("task1", "C-EMDM"), ("task2", "C-IVKC"), ("panda", "C-EMDM"), ("obstacle", "C-EMDM")]
    scenarios = [(emdm.load_scenario(p), c) for p, c in cases]
    for sc, c in scenarios:
        emdm.simulate(sc, c)
    _nrt_python.memsys_enable_stats()
    gc.collect()
    before = rtsys.get_allocation_stats()
    for _ in range(3):
        for sc, c in scenarios:
            emdm.simulate(sc, c)
    gc.collect()
    after = rtsys.get_allocation_stats()
    assert after.alloc - after.free == before.alloc - before.free
    assert after.mi_alloc - after.mi_free == before.mi_alloc - before.mi_free
    scalar = re.compile(r"(None|int|float|bool|tuple\[(int|float|bool)(, (int|float|bool))*\])")
    assert len(jit.BORROWING) >= 60
    for dispatcher in jit.BORROWING:  # declared (mypy holds the body to it), and where compiled
        name = dispatcher.py_func.__qualname__
        assert scalar.fullmatch(dispatcher.py_func.__annotations__["return"]), name
        for cres in dispatcher.overloads.values():
            assert not _holds_array(cres.signature.return_type), name

    def allocating(n: int):
        return np.empty(n).size

    with pytest.raises(Exception, match="empty"):  # numba will not allocate without counting
        jit.kernel(refcount=False)(allocating)(3)
