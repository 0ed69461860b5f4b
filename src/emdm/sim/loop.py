"""The control loop (brief Algorithm 1), compiled, and its complete record.

At each state ``k`` (time ``t_k = k dt``): ``p_k = f(q_k)``, ``e_k = p_goal - p_k``, ``v_k = Kp e_k``;
the run stops when ``||e_k|| < tolerance`` (reached) or when ``t_k`` reaches ``max_time``; otherwise
the controller's program is built, made admissible by the infeasibility policy, solved, its answer
certified by its KKT residuals, and ``q_{k+1} = q_k + qd_k dt``.

One compiled kernel, :func:`run_kernel`, does all of that and records every quantity of a step. It
hands a step back to Python (and resumes after it) only when the step leaves what it settles
exactly: a policy other than ``scale`` on an infeasible task, no feasible task scale, dependent
task rows, a solver other than ``active-set``, or an answer its certificate does not accept. Python
then solves that step through the solver chain (:func:`emdm.solvers.solve_chain`), certified by
the same compiled KKT check, and records which solver answered. The record grows in chunks, so a
run allocates for the steps it takes, not for ``max_time / dt``.

The :class:`Run` holds ``K + 1`` states and ``K`` commands (row ``k`` of a command array is the
command computed at state ``k``).
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from enum import IntEnum
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..core.arm import Matrix, Vector
from ..core.checks import _Checker
from ..core.controllers import (
    Admissible,
    Controller,
    Name,
    _admissible,
    _step_program,
    controller_of,
    get_controller,
    slack_weight,
    state_at,
)
from ..core.distance import chain_points, link_gaps
from ..core.jit import compile_for, ensure_compiled, kernel, plain, seconds_per_tick, ticks
from ..core.kernels import (
    ArmData,
    Geometry,
    kinematics,
    task_kinematics,
)
from ..core.problem import QP
from ..core.scenario import Scenario
from ..core.simplex import feasible_point_rows, task_scale_rows
from ..core.terms import ProgramData, ProgramOut, StepInput, build_program
from ..core.terms.base import TermKind
from ..core.terms.obstacle import SLOWEST
from ..core.terms.program import SHAPED
from ..core.tolerances import STALL_BAND, STALL_TIME
from ..core.validation import Policy
from ..core.zonotope import feasible_point, task_scale
from ..errors import NoSolution
from ..solvers import BOUND_TOL, DEFAULT_FALLBACK, DEFAULT_SOLVER, KKT_TOL, get_solver
from ..solvers.base import MAX_BUDGET, _solve_chain
from ..solvers.kernels import (
    INFEASIBLE,
    OK,
    _cold_start,
    _warm_start,
    active_set,
    certify,
)
from .buffers import (
    Motion,
    Record,
    StepWork,
    mark_active,
    new_record,
    require_memory,
    step_work,
)
from .rows import count_active_rows, hold_rows, partition_rows, recall_rows, settle_rows

F64 = NDArray[np.float64]

FIRST_CHUNK = 256
"""Steps the record holds at first; it grows fourfold whenever a run needs more."""

SLICED_FROM = 64
"""From this many joints a step may take long (0.55 s at 400): the loop runs in slices of
``SLICE_WORK / n**3`` steps (at least one), written into the record through views, so that the
interpreter, and a signal, gets a turn between two slices (a slice's end is not a step's: the
record is the same)."""

SLICE_WORK = 2e7
"""Steps times ``n**3`` per slice (76 steps at 64 joints, one at 400)."""


class Exit(IntEnum):
    """Why :func:`run_kernel` returned (kernels return the plain integers below)."""

    REACHED = 0  # ||e_k|| < tolerance at state k
    TIMEOUT = 1  # t_k reached max_time
    HANDOFF = 2  # step k is for the solver chain (its nominal program is in the StepWork)
    FULL = 3  # the record has no room for step k


REACHED, TIMEOUT, HANDOFF, FULL = (int(e) for e in Exit)  # IntEnum does not cross numba's parfors


@kernel(refcount=False)
def run_kernel(
    arm: ArmData,
    geo: Geometry,
    motion: Motion,
    prog: ProgramData,
    scale_policy: bool,
    solve: bool,
    rec: Record,
    k0: int,
    w: StepWork,
    full: Any,
) -> tuple[int, int]:
    """Run from state ``k0`` (``rec.q[k0]`` set) until an :class:`Exit`; returns ``(exit, k)``.

    ``full`` is ``None`` for a plain planar run (a planar task, no obstacles, a program without
    inequality rows: :func:`plain_planar`) and ``True`` otherwise. numba removes every branch
    that tests ``full is None`` or ``full is not None`` before it compiles (its dead-branch
    pruning of ``None`` arguments), so a plain planar run compiles no spatial kinematics,
    obstacle distances or row handling: about a third of the first use's compile time. The
    record is the same either way (the removed code does nothing without rows and obstacles)."""
    n = arm.lengths.size
    nt = rec.p.shape[1]
    if k0 == 0:  # a new run: no working set to try first, so a run never depends on the last
        w.qp.warm[0] = False
        w.rows[1] = 0
    scaled = False
    cap = rec.qd.shape[0]
    out = ProgramOut(w.P, w.c, w.A, w.b, w.G, w.h, w.lb, w.ub, w.ids)
    for k in range(k0, cap + 1):
        if full is None or nt == 2:  # the planar kinematics directly: no spatial code on this path
            m = kinematics(arm.lengths, rec.q[k], rec.p[k], w.J, w.Jm, w.kin)
            rec.e[k, 0] = motion.goal[0] - rec.p[k, 0]
            rec.e[k, 1] = motion.goal[1] - rec.p[k, 1]
        else:
            m = task_kinematics(
                arm.lengths,
                geo,
                motion.task,
                motion.goal,
                rec.q[k],
                rec.p[k],
                rec.e[k],
                w.J,
                w.Jm,
                w.kin,
                w.sp,
            )
        rec.m[k] = m
        t = k * motion.dt
        if full is not None and motion.obstacles.size:
            chain_points(geo, rec.p[k], w.kin, w.sp, w.pts, w.axes)
            rec.clearance[k] = link_gaps(motion.obstacles, t, w.pts, w.gaps)
        err2 = 0.0
        for i in range(nt):
            rec.v[k, i] = motion.kp[i] * rec.e[k, i]
            err2 += rec.e[k, i] * rec.e[k, i]
        err = math.sqrt(err2)
        if err < motion.tolerance:
            return REACHED, k
        if k >= motion.n_steps:
            return TIMEOUT, k
        if k == cap:
            return FULL, k
        ng = build_program(
            prog,
            StepInput(
                rec.q[k], w.J, w.Jm, rec.v[k], err, rec.p[k], t, w.pts, w.axes, w.gaps, SLOWEST
            ),
            out,
            full,
        )
        G, h = w.G[:ng], w.h[:ng]
        near = 0
        if full is not None and ng > 0:
            near = partition_rows(w.G, w.h, w.ids, w.lb, w.ub, ng)
        if full is not None and w.qp.warm[0] and (ng > 0 or w.rows[1] > 0):
            recall_rows(w, ng)
        Gn, hn = (G, h) if near == ng else (w.G[:near], w.h[:near])  # the rows solved first
        w.rows[0] = ng
        for j in range(n):
            rec.lo[k, j], rec.hi[k, j] = w.lb[j], w.ub[j]
        if not solve:
            return HANDOFF, k
        if full is None or nt == 2:  # the exact 2-D task scale first (cheap), then the solve
            alpha = task_scale(w.A, w.b, w.lb, w.ub, w.qp.feas)
            if alpha < 0.0 or (alpha < 1.0 and not scale_policy):
                return HANDOFF, k
            for i in range(nt):
                w.b[i] *= alpha
            start = ticks()
            code, iterations = active_set(
                w.P, w.c, w.A, w.b, Gn, hn, w.lb, w.ub, w.x, w.qp, w.res, full
            )
            if full is not None and ng > 0 and code != INFEASIBLE:
                code, iterations = settle_rows(w, near, ng, code, iterations)
            if full is not None and code == INFEASIBLE and ng > 0:  # the rows cut the task: the
                for i in range(nt):  # exact scale under the rows too (a linear program)
                    w.b[i] = rec.v[k, i]
                alpha = task_scale_rows(w.A, w.b, G, h, w.lb, w.ub, w.qp.feas)
                if alpha < 0.0 or (alpha < 1.0 and not scale_policy):
                    return HANDOFF, k
                for i in range(nt):
                    w.b[i] *= alpha
                code, iterations = active_set(
                    w.P, w.c, w.A, w.b, G, h, w.lb, w.ub, w.x, w.qp, w.res, full
                )
                code, iterations = settle_rows(w, ng, ng, code, iterations)
        else:  # the solve first (its warm start proves the task feasible); the scale's LP if not
            alpha = 1.0
            start = ticks()
            code, iterations = INFEASIBLE, 0
            if not scaled:  # after a scaled step the task is most likely scaled again
                code, iterations = active_set(
                    w.P, w.c, w.A, w.b, Gn, hn, w.lb, w.ub, w.x, w.qp, w.res, full
                )
                if ng > 0 and code != INFEASIBLE:
                    code, iterations = settle_rows(w, near, ng, code, iterations)
            if code == INFEASIBLE:
                alpha = task_scale_rows(w.A, w.b, G, h, w.lb, w.ub, w.qp.feas)
                if alpha < 0.0 or (alpha < 1.0 and not scale_policy):
                    return HANDOFF, k
                if alpha < 1.0:
                    for i in range(nt):
                        w.b[i] *= alpha
                    # the scaled task leaves the LP's optimal face, most often its vertex alone:
                    # that vertex is the optimum when its certificate says so (else the method)
                    for j in range(w.x.size):
                        w.x[j] = w.qp.feas.centre[j]
                    certify(w.P, w.c, w.A, w.b, G, h, w.lb, w.ub, w.x, w.qp, w.res)
                    if max(w.res[0], w.res[1], w.res[2]) <= KKT_TOL and w.res[3] <= BOUND_TOL:
                        code, iterations = OK, 0
                if code != OK:
                    code, iterations = active_set(
                        w.P, w.c, w.A, w.b, G, h, w.lb, w.ub, w.x, w.qp, w.res, full
                    )
                    if ng > 0:
                        code, iterations = settle_rows(w, ng, ng, code, iterations)
            scaled = alpha < 1.0
        stop = ticks()
        if code != OK or max(w.res[0], w.res[1], w.res[2]) > KKT_TOL or w.res[3] > BOUND_TOL:
            for i in range(nt):
                w.b[i] = rec.v[k, i]  # the nominal program, for the chain
            return HANDOFF, k
        effort = 0.0
        manip = 0.0
        for j in range(n):
            qd = w.x[j]
            rec.qd[k, j] = qd
            rec.q[k + 1, j] = rec.q[k, j] + qd * motion.dt
            effort += qd * qd
            manip += w.Jm[j] * qd
        rec.effort[k] = 0.5 * effort
        rec.manip[k] = manip
        mark_active(rec.qd[k], w.lb, w.ub, rec.active[k])
        if full is not None and (ng > 0 or w.rows[1] > 0):
            hold_rows(w, ng)
        if full is not None and ng > 0:
            rec.rows[k] = ng
            rec.rows_active[k] = count_active_rows(G, h, w.x)
        if prog.slack:
            for i in range(nt):
                rec.delta[k, i] = w.x[n + i]
        rec.alpha[k] = alpha
        rec.iterations[k] = iterations
        rec.ticks[k] = stop - start
        rec.kkt[k] = max(w.res[0], w.res[1], w.res[2])
        rec.excess[k] = w.res[3]
    return FULL, cap


@dataclass(eq=False)
class Run:
    """The record of one closed-loop run.

    States (``K + 1`` rows): ``t`` (s), ``q`` (rad), ``p``, ``e`` (m), ``v`` (m/s), ``m``.
    Commands (``K`` rows): ``qd`` (rad/s), ``effort`` ``E = 1/2 ||qd||^2``, ``manip_rate``
    ``M = Jm . qd``, ``alpha`` (task scale), ``delta`` (task slack, m/s), joint bounds ``lo, hi``
    (rad/s, +-inf for UC), ``active`` (-1 at lo, +1 at hi, 0 free), and per solve ``solver``,
    ``status``, ``iterations``, ``solve_time`` (s), ``kkt`` (relative KKT residual), ``fallback``,
    ``attempts`` (every solver tried and its outcome) and ``policy`` (the policy that acted, or "").
    """

    scenario: Scenario
    controller: Controller
    t: Vector
    q: Matrix
    p: Matrix
    e: Matrix
    v: Matrix
    m: Vector
    qd: Matrix
    effort: Vector
    manip_rate: Vector
    alpha: Vector
    delta: Matrix
    lo: Matrix
    hi: Matrix
    active: np.ndarray
    iterations: np.ndarray
    solve_time: Vector
    kkt: Vector
    bound_excess: Vector
    fallback: np.ndarray
    rows: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    """Per command: how many inequality rows the program had (plane dampers within reach)."""
    rows_active: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    """Per command: how many of them the command holds with equality (the record's "at a bound")."""
    clearance: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """Per state: the smallest distance (m) of any link to any obstacle (``inf`` without
    obstacles; recorded whether or not the controller sees them)."""
    solver: list[str] = field(default_factory=list)
    status: list[str] = field(default_factory=list)
    attempts: list[str] = field(default_factory=list)
    policy: list[str] = field(default_factory=list)
    reached: bool = False

    @property
    def steps(self) -> int:
        """Number of commands ``K`` (the final state has index ``K``)."""
        return int(self.qd.shape[0])

    @property
    def scaled(self) -> np.ndarray:
        """Per command: whether its task was scaled (``alpha < 1``), the one definition of a
        scaled step (metrics, explanations and figures read it)."""
        return np.asarray(self.alpha < 1.0)

    @property
    def stalled_from(self) -> int | None:
        """The state from which a run that missed its goal has stalled (its error stays within
        :data:`~emdm.core.tolerances.STALL_BAND` of the final one for at least
        :data:`~emdm.core.tolerances.STALL_TIME`), or ``None``: the one definition of a stall."""
        if self.reached or self.steps == 0:
            return None
        err = self.error_norm
        outside = np.flatnonzero(np.abs(err - err[-1]) > STALL_BAND)
        k = int(outside[-1] + 1) if outside.size else 0
        return k if self.t[-1] - self.t[k] >= STALL_TIME else None

    @property
    def error_norm(self) -> Vector:
        """``||e_k||`` (m) at every state."""
        return np.asarray(np.linalg.norm(self.e, axis=1))

    @property
    def time_to_goal(self) -> float | None:
        """``t_K`` when the goal was reached, else ``None``."""
        return float(self.t[-1]) if self.reached else None


def plain_planar(scenario: Scenario, prog: ProgramData) -> bool:
    """Whether a run needs none of :func:`run_kernel`'s spatial, obstacle and row code: a
    planar task (two rows), no obstacles and a program with no inequality rows and no term that
    reads obstacles (:data:`~emdm.core.terms.program.SHAPED`)."""
    return (
        scenario.nt == 2
        and not scenario.obstacles
        and prog.rows == 0
        and SHAPED.isdisjoint(prog.codes.tolist())  # 0.2 us (np.isin: 10 us, per run)
    )


def full_flag(scenario: Scenario, prog: ProgramData) -> bool | None:
    """:func:`run_kernel`'s ``full`` argument: ``None`` for a :func:`plain_planar` run."""
    return None if plain_planar(scenario, prog) else True


def motion_data(scenario: Scenario, goal: Vector | None = None) -> Motion:
    """The scenario's task as kernel input (``goal`` replaces the scenario's when given; without
    one, built once per scenario and kept in its memo)."""
    if goal is None:
        if "motion" not in scenario.memo:
            scenario.memo["motion"] = motion_data(scenario, scenario.motion.goal)
        return scenario.memo["motion"]  # type: ignore[no-any-return]
    mo = scenario.motion
    return Motion(
        np.array(goal, dtype=float),
        np.array(mo.kp, dtype=float),
        float(mo.dt),
        float(mo.tolerance),
        scenario.max_steps,
        scenario.task_code,
        np.array(scenario.obstacle_data, dtype=float),
    )


_local = threading.local()


def _work(n: int, nx: int, nt: int, ng: int = 0, no: int = 0) -> StepWork:
    """This thread's step buffers for the shape ``(n, nx, nt, ng, no)``, built once (they hold no
    result)."""
    cache: dict[tuple[int, ...], StepWork] = _local.__dict__.setdefault("work", {})
    if (n, nx, nt, ng, no) not in cache:
        cache[n, nx, nt, ng, no] = plain(step_work)(n, nx, nt, ng, no)
    return cache[n, nx, nt, ng, no]


def _grow(rec: Record, cap: int, n: int) -> Record:
    bigger = plain(new_record)(cap, n, rec.p.shape[1])
    for old, new in zip(rec, bigger, strict=True):
        old_arr, new_arr = np.asarray(old), np.asarray(new)
        new_arr[: old_arr.shape[0]] = old_arr
    return bigger


class _Steps:
    """Per-step text fields of a run: kernel steps share one value, chain steps get their own."""

    def __init__(self) -> None:
        self.solver: dict[int, str] = {}
        self.status: dict[int, str] = {}
        self.attempts: dict[int, str] = {}
        self.policy: dict[int, str] = {}
        self.time: dict[int, float] = {}
        self.fallback: set[int] = set()

    def column(self, values: dict[int, str], default: str, K: int) -> list[str]:
        out = [default] * K
        for k, value in values.items():
            if k < K:
                out[k] = value
        return out


def simulate(
    scenario: Scenario,
    controller: str | Controller,
    *,
    solver: str = DEFAULT_SOLVER,
    fallback: Sequence[str] = DEFAULT_FALLBACK,
    certify: bool = True,
    budget: int | None = None,
) -> Run:
    """Run ``controller`` on ``scenario`` from ``q0`` until the goal or ``max_time``.

    With the default ``solver="active-set"`` every step runs in the compiled loop; a step it cannot
    settle goes through ``[solver, *fallback]``, the first answer whose KKT report is optimal being
    used. Another ``solver`` is tried first at every step, then each of ``fallback`` in order; with
    ``certify=False`` the first finite answer is used as it is (to study inexact solvers in
    closed loop; its KKT residual is recorded). ``budget`` is the evaluation budget of the chain's
    gradient-free solvers (None: each one's default). Raises :class:`~emdm.errors.NoSolution` when a step
    has no admissible command (``on_infeasible = "error"``, or no solver succeeds); the exception
    carries the partial run (``.run``), the controller and the step. Before the first step, raises
    :class:`~emdm.errors.ScenarioError` naming the argument that is not valid (``scenario`` a
    Scenario, ``controller`` a name or a Controller, ``solver`` a name, ``fallback`` a list of
    names, ``certify`` True or False, ``budget`` None or an integer >= 1),
    :class:`~emdm.errors.EmdmError` for an unknown controller
    and :class:`~emdm.errors.SolverNotFound` for an unknown solver.
    """
    ctrl, fallback = _arguments("simulate", scenario, controller, solver, fallback)
    _Checker("simulate").flag("certify", certify)
    if budget is not None:
        budget = _Checker("simulate").count("budget", budget, 1, MAX_BUDGET)
    chain = [solver, *[f for f in fallback if f != solver]]
    for name in chain:
        get_solver(name)  # fail before the loop on an unknown solver
    n, nt = scenario.n, scenario.nt
    prog = ctrl.program_data(scenario)
    full = full_flag(scenario, prog)
    if full is None:
        ensure_compiled(_warm_up_plain, helper=_warm_up_plain_share)
    else:
        ensure_compiled(_warm_up, helper=_warm_up_share)
    nx = n + nt if prog.slack else n
    arm, geo, motion = scenario.arm_data, scenario.geometry, motion_data(scenario)
    policy = scenario.controller.on_infeasible
    in_kernel = solver == DEFAULT_SOLVER
    cap = min(motion.n_steps, FIRST_CHUNK)
    require_memory(scenario.name, n, nx, nt, prog.rows, scenario.spatial, copies=1, steps=cap)
    rec = plain(new_record)(cap, n, nt)
    rec.q[0] = scenario.motion.q0
    work = _work(n, nx, nt, prog.rows, len(scenario.obstacles))
    steps = _Steps()
    k = 0
    kernel = _entry((arm, geo, motion, prog, True, True, rec, k, work, full))
    per_call = max(1, int(SLICE_WORK / n**3)) if n >= SLICED_FROM else None
    while True:
        limit = cap if per_call is None else min(cap, k + per_call)
        view = rec if limit == cap else Record._make(a[: a.shape[0] - (cap - limit)] for a in rec)
        code, k = kernel(
            arm, geo, motion, prog, policy is Policy.SCALE, in_kernel, view, k, work, full
        )
        if code == Exit.FULL and k < cap:  # the end of a slice: a signal is honoured here
            continue
        if code == Exit.FULL:  # a longer run than the record holds: grow it, if it fits
            cap = min(motion.n_steps, 4 * cap)
            require_memory(
                scenario.name, n, nx, nt, prog.rows, scenario.spatial, copies=1, steps=cap
            )
            rec = _grow(rec, cap, n)
            continue
        if code != Exit.HANDOFF:
            break
        try:
            _chain_step(scenario, ctrl, chain, certify, rec, k, work, steps, budget)
        except NoSolution as exc:
            exc.run = _run(scenario, ctrl, rec, k, steps, reached=False)
            exc.controller, exc.step = ctrl.name, k
            raise
        k += 1
    return _run(scenario, ctrl, rec, k, steps, reached=code == Exit.REACHED)


_entries: dict[bool, Callable[..., tuple[int, int]]] = {}


def _entry(args: tuple[Any, ...]) -> Callable[..., tuple[int, int]]:
    """:func:`run_kernel`'s machine code for :func:`simulate`'s arguments, looked up once.

    numba's dispatcher finds a kernel's machine code by fingerprinting every argument at every
    call: about 100 arrays here, 10 us, a fifth of a short run's cost. :func:`simulate`'s
    arguments always have one type: every array in them is made by emdm's own builders
    (:func:`~emdm.sim.buffers.new_record`, :func:`~emdm.sim.buffers.step_work`,
    :func:`motion_data`, ``Scenario.arm_data`` and ``geometry``, ``Controller.program_data``),
    each with a fixed dtype, number of dimensions and C layout, so the lookup is done on the
    first call and its entry point reused; one for plain planar runs (``full`` is ``None``), one
    for all others (``tests/test_simulate.py`` checks that every kind of arm, task, program and
    obstacle gives one of these two signatures)."""
    plain = args[-1] is None
    if plain not in _entries:
        dispatcher: Any = run_kernel
        signature = tuple(dispatcher.typeof_pyval(a) for a in args)
        if signature not in dispatcher.overloads:  # not warmed up for it: compiled (or loaded)
            dispatcher.compile(signature)
        _entries[plain] = dispatcher.overloads[signature].entry_point
    return _entries[plain]


def _arguments(
    source: str,
    scenario: Scenario,
    controller: str | Controller,
    solver: str = DEFAULT_SOLVER,
    fallback: Sequence[str] = DEFAULT_FALLBACK,
) -> tuple[Controller, list[str]]:
    """The controller and the fallback chain of a run of ``source`` (:func:`simulate`,
    :func:`~emdm.sim.batch.simulate_batch`), its arguments checked."""
    if (  # the usual call, recognised in a few hundred nanoseconds (the per-run cost counts)
        type(scenario) is Scenario
        and type(controller) is str
        and type(solver) is str
        and solver
        and type(fallback) is tuple
        and all(type(f) is str for f in fallback)
    ):
        return get_controller(controller), list(fallback)
    check = _Checker(source)
    check.instance("scenario", scenario, Scenario, "a Scenario (from emdm.load_scenario)")
    ctrl = controller_of(source, controller)
    check.text("solver", solver, "a solver's name")
    return ctrl, check.names("fallback", fallback, "solver names")


def _standstill(nominal: QP, policy: str) -> Admissible:
    """The task scaled to zero, when standing still is admissible and the policy scales: a stall
    in front of an obstacle can leave a largest scale of order 1e-11 whose feasible set is
    narrower than the certificate's tolerance, so that no solver's answer is certified
    (docs/mathematics.md, "Obstacles"); the scale 0 is admissible and its program certifiable.
    Raises :class:`NoSolution` otherwise."""
    zero = np.zeros(nominal.lb.size)
    if policy != "scale" or nominal.bound_excess(zero) > 0.0:
        raise NoSolution("standing still is not admissible either", problem=nominal)
    return Admissible(nominal._rhs(np.zeros_like(nominal.b)), 0.0, "scale")


def _chain_step(
    scenario: Scenario,
    ctrl: Controller,
    chain: list[str],
    certify: bool,
    rec: Record,
    k: int,
    w: StepWork,
    steps: _Steps,
    budget: int | None = None,
) -> None:
    """Step ``k`` through the policy and the solver chain; its nominal program is in ``w``."""
    n = scenario.n
    nominal = QP._trusted(
        w.P.copy(),
        w.c.copy(),
        w.A.copy(),
        w.b.copy(),
        w.lb.copy(),
        w.ub.copy(),
        n,
        w.G[: w.rows[0]].copy(),
        w.h[: w.rows[0]].copy(),
    )
    error_norm = float(np.linalg.norm(rec.e[k]))
    t = k * scenario.motion.dt
    weight = slack_weight(scenario, error_norm)
    policy = scenario.controller.on_infeasible
    context = f"step {k} (t = {t:g} s): "
    try:
        program = _admissible(nominal, policy, slack_weight=weight, step=k)
        result = _solve_chain(program.qp, chain, context=context, certify=certify, budget=budget)
    except NoSolution:
        if not (scenario.obstacles and ctrl.has(TermKind.OBSTACLE)):
            raise
        # the obstacle rows' speed floor left no admissible command: the step again without
        # it, where standing still is admissible (docs/mathematics.md, "Obstacles")
        state = state_at(scenario, rec.q[k])
        nominal = _step_program(
            ctrl, scenario, rec.q[k], state.kin, rec.v[k], error_norm, t=t, floor=0.0
        )
        try:
            program = _admissible(nominal, policy, slack_weight=weight, step=k)
            result = _solve_chain(
                program.qp, chain, context=context, certify=certify, budget=budget
            )
        except NoSolution:
            program = _standstill(nominal, policy)
            result = _solve_chain(
                program.qp, chain, context=context, certify=certify, budget=budget
            )
        rec.lo[k], rec.hi[k] = nominal.lb[:n], nominal.ub[:n]
    x = result.x
    rec.qd[k] = x[:n]
    rec.delta[k] = x[n : n + scenario.nt] if program.qp.n_slack else 0.0
    mark_active(rec.qd[k], rec.lo[k], rec.hi[k], rec.active[k])
    rec.effort[k] = 0.5 * float(rec.qd[k] @ rec.qd[k])
    rec.manip[k] = float(w.Jm @ rec.qd[k])
    rec.alpha[k] = program.alpha
    qp = program.qp
    rec.rows[k] = qp.n_rows
    rec.rows_active[k] = count_active_rows(
        np.ascontiguousarray(qp.G), np.ascontiguousarray(qp.h), np.ascontiguousarray(x)
    )
    rec.iterations[k] = result.iterations
    rec.kkt[k], rec.excess[k] = result.kkt.residual, result.kkt.bound_excess
    rec.q[k + 1] = rec.q[k] + rec.qd[k] * scenario.motion.dt
    steps.solver[k], steps.status[k] = result.solver, result.status
    steps.attempts[k] = "; ".join(f"{s}: {o}" for s, o in result.attempts)
    steps.policy[k] = program.policy or ""
    steps.time[k] = result.time
    if result.fallback:
        steps.fallback.add(k)


def _run(
    scenario: Scenario, ctrl: Controller, rec: Record, K: int, steps: _Steps, *, reached: bool
) -> Run:
    """The :class:`Run` of states ``0..K`` and commands ``0..K-1`` of ``rec``."""
    solve_time: Vector = rec.ticks[:K].astype(np.float64) * seconds_per_tick()
    for k, seconds in steps.time.items():
        if k < K:
            solve_time[k] = seconds
    fallback = np.zeros(K, dtype=bool)
    if steps.fallback:
        fallback[[k for k in steps.fallback if k < K]] = True
    policy = [""] * K
    for k in (rec.alpha[:K] < 1.0).nonzero()[0].tolist():
        policy[k] = "scale"
    for k, value in steps.policy.items():
        if k < K:
            policy[k] = value
    return Run(
        scenario=scenario,
        controller=ctrl,
        t=np.arange(K + 1, dtype=float) * scenario.motion.dt,
        q=rec.q[: K + 1],
        p=rec.p[: K + 1],
        e=rec.e[: K + 1],
        v=rec.v[: K + 1],
        m=rec.m[: K + 1],
        qd=rec.qd[:K],
        effort=rec.effort[:K],
        manip_rate=rec.manip[:K],
        alpha=rec.alpha[:K],
        delta=rec.delta[:K],
        lo=rec.lo[:K],
        hi=rec.hi[:K],
        active=rec.active[:K],
        iterations=rec.iterations[:K],
        solve_time=solve_time,
        kkt=rec.kkt[:K],
        bound_excess=rec.excess[:K],
        fallback=fallback,
        rows=rec.rows[:K],
        rows_active=rec.rows_active[:K],
        clearance=rec.clearance[: K + 1],
        solver=steps.column(steps.solver, DEFAULT_SOLVER, K),
        status=steps.column(steps.status, "optimal", K),
        attempts=steps.column(steps.attempts, f"{DEFAULT_SOLVER}: optimal", K),
        policy=policy,
        reached=reached,
    )


WARM_UP_PLANAR = ("task1", "task2")
"""The presets whose runs are plain planar (:func:`plain_planar`): the plain warm-up's."""
WARM_UP_PRESETS = (*WARM_UP_PLANAR, "panda", "ur5")
"""One preset of each kind of task and program: planar (redundant, slack), pose (redundant, slack)."""


def _warm_up(planar: bool = False) -> None:
    """Compile (or load) every kernel of the loop: one short run of each kind of program, for
    runs that are not plain planar (``planar``: for those that are, the planar presets only)."""
    from ..core.loading import load_scenario

    seconds_per_tick()
    for task in WARM_UP_PLANAR if planar else WARM_UP_PRESETS:
        sc = load_scenario(task, {"motion.max_time": 0.1})
        for name in (Name.UC_IVKC, Name.C_EMDM):
            ctrl = get_controller(name)
            prog = ctrl.program_data(sc)
            nx = sc.n + sc.nt if prog.slack else sc.n
            rec = plain(new_record)(2, sc.n, sc.nt)
            rec.q[0] = sc.motion.q0
            work = plain(step_work)(sc.n, nx, sc.nt, 0, 0)
            full = full_flag(sc, prog) if planar else True
            args = (sc.arm_data, sc.geometry, motion_data(sc), prog, True, True, rec, 0, work)
            run_kernel(*args, full)


def _warm_up_plain() -> None:
    """:func:`_warm_up` for plain planar runs: the first use of a planar task compiles no more."""
    _warm_up(planar=True)


def _warm_up_share(planar: bool = False) -> None:
    """The share of :func:`_warm_up` a helper process compiles while the first process compiles
    the rest (:func:`~emdm.core.jit.ensure_compiled`): the kernels the loop calls, in the reverse
    of the order the first process meets them (the active set's cold start and its two subtrees,
    the feasible point and the certificate, then its warm start, the task scale, the program and
    the kinematics), each one skipped when the first process is compiling it already: the two
    meet in the middle (``planar``: for :func:`_warm_up_plain`)."""
    from ..core.loading import load_scenario

    sc = load_scenario("task1", {"motion.max_time": 0.1})
    prog = get_controller(Name.C_EMDM).program_data(sc)
    w = plain(step_work)(sc.n, sc.n, sc.nt, 0, 0)
    rec = plain(new_record)(2, sc.n, sc.nt)
    full = None if planar else True
    qp = (w.P, w.c, w.A, w.b, w.G, w.h, w.lb, w.ub, w.x, w.qp, w.res)
    step = StepInput(
        rec.q[0], w.J, w.Jm, rec.v[0], 0.0, rec.p[0], 0.0, w.pts, w.axes, w.gaps, SLOWEST
    )
    out = ProgramOut(w.P, w.c, w.A, w.b, w.G, w.h, w.lb, w.ub, w.ids)
    share: list[tuple[Any, tuple[Any, ...]]]
    if planar:
        share = [
            (feasible_point, (w.A, w.b, w.lb, w.ub, w.x, w.qp.feas)),
            (certify, qp),
            (_cold_start, (*qp, full)),
            (_warm_start, qp),
            (task_scale, (w.A, w.b, w.lb, w.ub, w.qp.feas)),
            (build_program, (prog, step, out, full)),
            (kinematics, (sc.arm_data.lengths, rec.q[0], rec.p[0], w.J, w.Jm, w.kin)),
        ]
    else:  # the first process compiles the spatial kinematics and the program meanwhile, then
        # the rows' settling (which calls the active set), then their task scale
        share = [
            (feasible_point_rows, (w.A, w.b, w.G, w.h, w.lb, w.ub, w.x, w.qp.feas)),
            (certify, qp),
            (_cold_start, (*qp, full)),
            (_warm_start, qp),
            (task_scale_rows, (w.A, w.b, w.G, w.h, w.lb, w.ub, w.qp.feas)),
        ]
    for compiled, args in share:
        compile_for(compiled, *args, unless_busy=True)


def _warm_up_plain_share() -> None:
    """:func:`_warm_up_share` for :func:`_warm_up_plain`."""
    _warm_up_share(planar=True)


__all__ = ["NoSolution", "Run", "simulate"]
