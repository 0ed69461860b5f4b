"""Many closed-loop runs at once: the compiled loop on every core, reduced to outcomes.

Each thread of :func:`run_all` owns one record and one set of step buffers and runs its share
of the runs through :func:`emdm.sim.loop.run_kernel`, then reduces each record with
:func:`emdm.sim.metrics.outcomes`. A run with a step the kernel hands back (see
:mod:`emdm.sim.loop`) is finished by :func:`emdm.simulate` itself, so every outcome is exact.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, fields
from typing import Any

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core.checks import _Checker
from ..core.controllers import Controller, Name, get_controller
from ..core.jit import ensure_compiled, kernel
from ..core.kernels import ArmData, Geometry
from ..core.scenario import Scenario
from ..core.terms import ProgramData
from ..core.validation import RANGES, Policy, check_start_angles
from ..errors import NoSolution
from .buffers import Motion, new_record, require_memory, step_work
from .loop import (
    REACHED,
    TIMEOUT,
    WARM_UP_PLANAR,
    WARM_UP_PRESETS,
    Exit,
    _arguments,
    _warm_up,
    _warm_up_plain,
    _warm_up_plain_share,
    _warm_up_share,
    full_flag,
    motion_data,
    run_kernel,
    simulate,
)
from .metrics import OUTCOMES, outcomes, run_outcomes

F64 = NDArray[np.float64]


@kernel
def run_share(
    arm: ArmData,
    geo: Geometry,
    motion: Motion,
    prog: ProgramData,
    goals: F64,
    q0s: F64,
    first: int,
    stride: int,
    out: F64,
    codes: NDArray[np.int64],
    full: Any,
) -> None:
    """Runs ``first, first + stride, ...`` with one record and one set of buffers (``full``:
    :func:`~emdm.sim.loop.run_kernel`'s)."""
    runs, n = q0s.shape
    nt = goals.shape[1]
    nx = nt + n if prog.slack else n
    rec = new_record(motion.n_steps, n, nt)
    work = step_work(n, nx, nt, prog.rows, int(motion.obstacles[5]) if motion.obstacles.size else 0)
    for r in range(first, runs, stride):
        task = Motion(
            goals[r],
            motion.kp,
            motion.dt,
            motion.tolerance,
            motion.n_steps,
            motion.task,
            motion.obstacles,
        )
        for j in range(n):
            rec.q[0, j] = q0s[r, j]
        code, k = run_kernel(arm, geo, task, prog, True, True, rec, 0, work, full)
        codes[r] = code
        if code == REACHED or code == TIMEOUT:
            reached = code == REACHED
            outcomes(
                rec.m,
                rec.effort,
                rec.qd,
                rec.e,
                rec.q,
                rec.clearance,
                arm.q_min,
                arm.q_max,
                k,
                reached,
                motion.dt,
                out[r],
            )


def run_all(
    arm: ArmData,
    geo: Geometry,
    motion: Motion,
    prog: ProgramData,
    goals: F64,
    q0s: F64,
    threads: int,
    out: F64,
    codes: NDArray[np.int64],
    full: bool | None,
) -> None:
    """Run ``goals[r]`` from ``q0s[r]`` for every ``r`` on ``threads`` threads; ``out[r]`` =
    outcomes, ``codes[r]`` = how the run ended. :func:`run_share` releases the GIL, so plain
    threads run in parallel (no parallel compile of the whole loop is needed)."""
    if threads <= 1:
        run_share(arm, geo, motion, prog, goals, q0s, 0, 1, out, codes, full)
        return
    with ThreadPoolExecutor(max_workers=threads) as pool:
        jobs = [
            pool.submit(run_share, arm, geo, motion, prog, goals, q0s, t, threads, out, codes, full)
            for t in range(threads)
        ]
        for job in jobs:
            job.result()


def precompile() -> None:
    """Compile every kernel of :func:`emdm.simulate` and :func:`simulate_batch` now (or load
    them from the cache): once, before many processes start (``make test`` before its workers,
    an image build, a Dask cluster's set-up), so that each of them loads the kernels in under a
    second instead of compiling them again."""
    ensure_compiled(_warm_up_plain, helper=_warm_up_plain_share)
    ensure_compiled(_warm_up, helper=_warm_up_share)
    ensure_compiled(_warm_up_batch_plain, what="the batch loop")
    ensure_compiled(_warm_up_batch, what="the batch loop")
    ensure_compiled(_warm_up_steps, what="the per-step API")


def _warm_up_steps() -> None:
    """Compile (or load) the kernels of the per-step API that the loop does not share (the
    path of the solver lab, the Pareto study and the benchmark):
    :func:`~emdm.core.controllers.state_at`, :func:`~emdm.core.controllers.program_at` and the
    default solver with its certificate, at the start of each kind of preset, for both kinds
    of program."""
    from ..core.controllers import program_at
    from ..core.loading import load_scenario
    from ..solvers import DEFAULT_SOLVER
    from ..solvers.base import solve_chain

    for task in WARM_UP_PRESETS:
        sc = load_scenario(task)
        for name in (Name.UC_IVKC, Name.C_EMDM):
            program = program_at(get_controller(name), sc, np.asarray(sc.motion.q0))
            solve_chain(program.qp, [DEFAULT_SOLVER])


def _warm_up_batch(plain: bool = False) -> None:
    """Compile (or load) the batch kernel on a two-step run of each kind of program (``plain``:
    of the plain planar presets only, as :func:`~emdm.sim.loop._warm_up`)."""
    from ..core.loading import load_scenario

    for task in WARM_UP_PLANAR if plain else WARM_UP_PRESETS:
        sc = load_scenario(task, {"motion.max_time": 0.1})
        for name in (Name.UC_IVKC, Name.C_EMDM):
            q0s = np.array([sc.motion.q0], dtype=float)
            goals = np.array([sc.motion.goal], dtype=float)
            out, codes = np.empty((1, len(OUTCOMES))), np.empty(1, dtype=np.int64)
            prog = get_controller(name).program_data(sc)
            full = full_flag(sc, prog) if plain else True
            args = (sc.arm_data, sc.geometry, motion_data(sc), prog, goals, q0s, 0, 1, out, codes)
            run_share(*args, full)


def _warm_up_batch_plain() -> None:
    """:func:`_warm_up_batch` for plain planar runs."""
    _warm_up_batch(plain=True)


@dataclass(frozen=True)
class BatchResult:
    """One array of ``R`` values per outcome (see :data:`emdm.sim.metrics.OUTCOMES`).

    ``reached`` is boolean and ``time_to_goal`` NaN where a run did not reach its goal;
    ``reference_runs`` lists the runs a step of which the solver chain settled, ``stopped_runs``
    those that ended at a step with no admissible command (:class:`~emdm.errors.NoSolution`; they
    count as not reached).
    """

    steps: NDArray[np.int64]
    reached: NDArray[np.bool_]
    time_to_goal: F64
    min_manipulability: F64
    mean_manipulability: F64
    total_effort: F64
    final_error: F64
    max_abs_qd: F64
    final_manipulability: F64
    min_joint_margin: F64
    min_clearance: F64
    """The smallest distance of any link to any obstacle over each run (m; ``inf`` without
    obstacles, and then left out of :meth:`outcomes`)."""
    reference_runs: NDArray[np.int64]
    stopped_runs: NDArray[np.int64]

    def outcomes(self) -> dict[str, np.ndarray]:
        """The outcome arrays by name (everything but the run lists, and ``min_clearance`` in a
        scene without obstacles)."""
        skip = ["reference_runs", "stopped_runs"]
        if np.all(np.isinf(self.min_clearance)):
            skip.append("min_clearance")  # no obstacles
        return {f.name: getattr(self, f.name) for f in fields(self) if f.name not in skip}

    def __len__(self) -> int:
        return int(self.steps.size)


def _starts(scenario: Scenario, goals: ArrayLike | None, q0s: ArrayLike | None) -> tuple[F64, F64]:
    """The goals and start angles of :func:`simulate_batch` as 2-D arrays (R x task rows,
    R x n), checked as the scenario checks ``motion.goal`` and ``motion.q0``."""
    check = _Checker("simulate_batch")
    nt, n = scenario.nt, scenario.n
    if goals is None:
        g = np.atleast_2d(np.asarray(scenario.motion.goal, dtype=float))
    else:
        g = check.array("goals", goals, None, what=f"rows of {nt} numbers (one per task row)")
        g = check.array("goals", np.atleast_2d(g), (None, nt), what=f"rows of {nt} numbers")
        low, high, unit = RANGES["motion.goal"]
        if np.any((g < low) | (g > high)):
            r, i = (int(x) for x in np.argwhere((g < low) | (g > high))[0])
            raise check.fail(
                f"goals[{r}]", f"must be between {low:g} and {high:g}{unit}, got {g[r, i]:g}"
            )
    if q0s is None:
        q = np.atleast_2d(np.asarray(scenario.motion.q0, dtype=float))
    else:
        q = check.array("q0s", q0s, None, what=f"rows of {n} joint angles (rad)")
        q = check.array("q0s", np.atleast_2d(q), (None, n), what=f"rows of {n} joint angles")
        arm, stop = scenario.arm, scenario.damper.stop
        margin = np.minimum(arm.q_max - q, q - arm.q_min)
        bad = np.flatnonzero(np.any(margin < stop, axis=1))  # outside the limits: margin < 0
        if bad.size:
            r = int(bad[0])
            check_start_angles(check, f"q0s[{r}]", q[r], arm.q_min, arm.q_max, stop)
    if g.shape[0] != q.shape[0] and 1 not in (g.shape[0], q.shape[0]):
        raise check.fail(
            "q0s",
            f"has {q.shape[0]} rows and goals {g.shape[0]}: give as many rows as goals, or one",
        )
    return g, q


def simulate_batch(
    scenario: Scenario,
    controller: str | Controller,
    *,
    goals: ArrayLike | None = None,
    q0s: ArrayLike | None = None,
) -> BatchResult:
    """Many closed-loop runs of ``controller``, in parallel on every core.

    ``goals`` (R x task rows: m, and rad for a pose's orientation) and ``q0s`` (R x n, rad)
    default to the scenario's; either may be given alone (one row is broadcast, and a single
    row may be given as a vector). The outcomes equal those of :func:`emdm.simulate` run by run.

    Raises :class:`~emdm.errors.ScenarioError` naming the argument that is not valid:
    ``scenario`` a Scenario, ``controller`` a name or a Controller (an unknown name:
    :class:`~emdm.errors.EmdmError`), ``goals`` finite rows of one value per task row within
    the range of ``motion.goal``, ``q0s`` finite rows of ``n`` joint angles within the joint
    limits and outside the dampers' stop zones, the same number of rows or one.
    """
    ctrl, _ = _arguments("simulate_batch", scenario, controller)
    g, q = _starts(scenario, goals, q0s)
    prog = ctrl.program_data(scenario)
    full = full_flag(scenario, prog)
    if full is None:
        ensure_compiled(_warm_up_plain, helper=_warm_up_plain_share)
    else:
        ensure_compiled(_warm_up, helper=_warm_up_share)
    ensure_compiled(_warm_up_batch_plain if full is None else _warm_up_batch, what="the batch loop")
    n = scenario.n
    runs = 0 if 0 in (g.shape[0], q.shape[0]) else max(g.shape[0], q.shape[0])
    # writable copies: a broadcast view is read-only, and numba would compile the kernel again
    # for read-only arrays (a specialization precompile() does not warm)
    g = np.array(np.broadcast_to(g, (runs, scenario.nt)), order="C")
    q = np.array(np.broadcast_to(q, (runs, n)), order="C")
    out = np.empty((runs, len(OUTCOMES)))
    codes = np.full(runs, Exit.HANDOFF, dtype=np.int64)
    if scenario.controller.on_infeasible is Policy.SCALE and runs:
        threads = min(numba.get_num_threads(), runs)
        nx = n + scenario.nt if prog.slack else n
        steps = motion_data(scenario).n_steps
        require_memory(
            scenario.name,
            n,
            nx,
            scenario.nt,
            prog.rows,
            scenario.spatial,
            copies=threads,
            steps=steps,
        )
        run_all(
            scenario.arm_data,
            scenario.geometry,
            motion_data(scenario),
            prog,
            g,
            q,
            threads,
            out,
            codes,
            full,
        )
    redo = np.flatnonzero((codes != Exit.REACHED) & (codes != Exit.TIMEOUT))
    stopped: list[int] = []
    for r in redo:  # finish these runs exactly, through the solver chain where needed
        sc = scenario.with_overrides({"motion.goal": g[r].tolist(), "motion.q0": q[r].tolist()})
        try:
            run = simulate(sc, ctrl)
        except NoSolution as exc:  # the run ends at a step without an admissible command
            if exc.run is None:
                raise
            run = exc.run
            stopped.append(int(r))
        run_outcomes(run, out[r])
    columns: dict[str, Any] = {name: out[:, i].copy() for i, name in enumerate(OUTCOMES)}
    columns["steps"] = columns["steps"].astype(np.int64)
    columns["reached"] = columns["reached"].astype(bool)
    return BatchResult(
        **columns, reference_runs=redo, stopped_runs=np.array(stopped, dtype=np.int64)
    )
