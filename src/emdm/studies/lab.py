"""The solver lab: every solver on the real per-step programs, measured against the exact optimum.

Two experiments per solver (brief Task 1 and 2; ``emdm solvers``):

1. *Closed loop*: the controller runs with that solver alone (its answers used as they are,
   certified or not, with the exact ``active-set`` only where it returns nothing). Does it still
   reach the goal, and when?
2. *Re-solve*: at the states of the exact trajectory, each step's program is solved again and the
   answer compared with the exact optimum ``x*`` (the certified command of the reference run):
   ``gap = f(x) - f(x*)`` and ``violation`` = the largest equality residual or bound excess. Times
   are medians over repeats after one warm-up solve, per step.

Convergence histories (objective, residuals per iteration or per evaluation) are recorded at three
representative steps: the first, the first scaled one (``alpha < 1``) when there is one, the last
and the least dexterous.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import time
from collections import Counter
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

import numpy as np

from ..core.arm import Vector
from ..core.controllers import Controller, get_controller, program_at
from ..core.problem import QP
from ..core.scenario import Scenario
from ..errors import NoSolution, ScenarioError, check_stop, die_with_parent
from ..sim.loop import Run, simulate
from ..solvers import SolverResult, SolverSpec, available_solvers, get_solver
from ..solvers.base import multipliers
from ..solvers.nlp import DEFAULT_BUDGET, PENALISED, PENALTY, SEEDED, penalty_weight

DEFAULT_LAB_SOLVERS = (
    "active-set",
    "interior-point",
    "admm",
    "daqp",
    "quadprog",
    "slsqp",
    "slsqp-reduced",
    "trust-constr",
    "nelder-mead",
    "powell",
    "cobyqa",
    "cobyla",
    "differential-evolution",
    "cma-es",
)
"""The default comparison: custom, exact off-the-shelf, gradient-based and gradient-free."""

LIKE_FOR_LIKE = "slsqp-reduced"
"""slsqp on the gradient-free methods' own reduced program: the control that separates the
method from the formulation, reported beside them, never a family's fastest."""

PENALTY_CHECK = 1e-3
"""The penalised methods are measured again with their l1 weight scaled by this (reading 275:
does the large weight handicap them?); at the lab's margins the smaller weight stays exact."""

SLOW_CALL = 0.02
"""A call slower than this (s) is timed once: its time is already far above timer noise."""

SEEDS = 5
"""Seeds 0, 1, ... run by each stochastic method (:data:`~emdm.solvers.nlp.SEEDED`): the timed
solves, histories and closed loop are seed 0's; every seed solves every program once more for the
spread of its evaluations, gaps, violations and overruns (``seeds`` in ``solvers.json``)."""

EXACT = 1e-9
"""A solver is exact on the lab's programs when its largest gap to the optimum and its largest
bound violation are both at most this (the paper's and the pitch's one criterion)."""


def exact_answer(gap: float, violation: float) -> bool:
    """Whether a solver's largest gap to the optimum and bound violation make it exact."""
    return abs(gap) <= EXACT and violation <= EXACT


FEATURES = ("cond_reduced", "w_slack", "cond_J", "m", "alpha", "active")
"""Per-step features recorded with every re-solve (see :func:`step_features`)."""


class Representative(StrEnum):
    """The steps whose convergence histories are recorded (see :func:`representative_steps`)."""

    FIRST = "first"
    SCALED = "scaled"
    LAST = "last"
    LEAST_DEXTEROUS = "least dexterous"


@dataclass(frozen=True, eq=False)
class StepSolve:
    """One solver's answer to one step's program."""

    step: int
    x: Vector | None
    objective: float
    gap: float
    violation: float
    iterations: int
    evaluations: int
    time: float
    status: str
    gradients: int = 0


@dataclass(eq=False)
class SolverStudy:
    """Everything measured for one solver."""

    spec: SolverSpec
    solves: list[StepSolve] = field(default_factory=list)
    histories: dict[Representative, tuple[dict[str, float], ...]] = field(default_factory=dict)
    closed_loop: Run | None = None
    closed_loop_error: str | None = None
    seeds: list[dict[str, Any]] = field(default_factory=list)
    """A stochastic method's summary per seed (:func:`seed_summary`); empty for the others."""
    penalty_check: dict[str, Any] | None = None
    """A :data:`PENALISED` method's summary (:func:`run_summary`) with its l1 weight scaled by
    :data:`PENALTY_CHECK`, beside ``penalty_weight``; None for the others."""

    def __getstate__(self) -> dict[str, Any]:
        # solver functions may be closures: pickle the solver by name (the registry restores it)
        return {**self.__dict__, "spec": self.spec.name}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update({**state, "spec": get_solver(state["spec"])})

    def summary(self, period: float) -> dict[str, Any]:
        """The solver's row of ``solvers.json`` (``period``: the control period its times are
        held against, counted in ``over_period``)."""
        times = np.array([s.time for s in self.solves])
        found = [s for s in self.solves if s.x is not None]
        gaps = np.array([s.gap for s in found]) if found else np.array([math.nan])
        out: dict[str, Any] = {
            "family": self.spec.family,
            "description": self.spec.description,
            "loop": self.spec.loop,
            "resolved_steps": len(self.solves),
            "failures": len(self.solves) - len(found),
            "median_time": float(np.median(times)),
            "p95_time": float(np.percentile(times, 95)),
            "max_time": float(np.max(times)),
            "over_period": int(np.sum(times > period)),
            "median_iterations": float(np.median([s.iterations for s in self.solves])),
            "median_evaluations": float(np.median([s.evaluations for s in self.solves])),
            # a gradient-based method's gradients beside its objective evaluations (reading
            # 160: counting only the latter flattered it against the gradient-free methods)
            "median_gradients": float(np.median([s.gradients for s in self.solves])),
            # the searches an iteration or evaluation limit ended (a gradient-free method's
            # budget: :attr:`LabResult.budget`), not a convergence test
            "limit_stops": sum(s.status == "max_iter" for s in self.solves),
            "max_gap": float(gaps.max()),
            "max_abs_gap": float(np.abs(gaps).max()),
            "max_violation": float(max((s.violation for s in found), default=math.nan)),
            "optimal_claims": sum(s.status == "optimal" for s in self.solves),
        }
        if self.seeds:
            out["seeds"] = self.seeds
        if self.penalty_check is not None:
            out["penalty_check"] = self.penalty_check
        run = self.closed_loop
        if run is not None:
            out.update(
                reached=run.reached,
                time_to_goal=run.time_to_goal,
                closed_loop_steps=run.steps,
                closed_loop_final_error=float(run.error_norm[-1]),
                closed_loop_fallback_steps=int(run.fallback.sum()),
                closed_loop_fallback_reasons=dict(
                    Counter(run.attempts[k].split("; ")[0] for k in np.flatnonzero(run.fallback))
                ),
                closed_loop_max_kkt=float(run.kkt.max()) if run.steps else 0.0,
                closed_loop_max_bound_excess=float(run.bound_excess.max()) if run.steps else 0.0,
                closed_loop_mean_manipulability=float(run.m.mean()),
            )
        else:
            out.update(reached=False, time_to_goal=None, closed_loop_error=self.closed_loop_error)
        return out


def step_features(run: Run, k: int, qp: QP) -> dict[str, float]:
    """What makes step ``k``'s program hard: the numerical challenges the lab characterises.

    ``cond_reduced``: condition number of the reduced Hessian ``Z^T P Z`` (``Z`` spans
    ``null(A)``), which sets the rate of first-order methods; ``w_slack``: the slack weight
    ``c_S / ||e||``, growing near the goal; ``cond_J``: ``sigma_max / sigma_min`` of ``J`` (near
    singular arms); ``m``: manipulability (the gradient ``Jm`` is non-smooth at ``m = 0``);
    ``alpha``: task scale (``< 1``: the feasible set is a face, degenerate active sets);
    ``active``: number of joint bounds active at the optimum; ``penalty_margin``: the l1
    penalty weight of the gradient-free methods over the largest optimal multiplier of the
    bounds and rows (the penalty is exact, its minimiser the program's, when this exceeds 1);
    ``width``: on a task-scaled step, the feasible set's extent (:func:`admissible_width`; NaN on
    the others); ``unknowns`` and ``rows``: the program's variables and task rows.
    """
    _, s, Vt = np.linalg.svd(qp.A)
    Z = Vt[int(np.sum(s > 1e-12 * s[0])) :].T
    reduced = Z.T @ qp.P @ Z
    cond = float(np.linalg.cond(reduced)) if reduced.size else 1.0
    J = qp.A[:, : qp.n_joints]
    sj = np.linalg.svd(J, compute_uv=False)
    x_star = np.concatenate((run.qd[k], run.delta[k][: qp.n_slack]))
    mult = multipliers(qp, x_star)  # the reduced program's inequalities keep these multipliers
    largest = max(float(np.abs(mult.mu).max(initial=0.0)), float(mult.nu.max(initial=0.0)))
    rho = penalty_weight(qp)
    return {
        "width": admissible_width(qp) if run.alpha[k] < 1.0 else math.nan,
        "unknowns": float(qp.P.shape[0]),
        "rows": float(qp.A.shape[0]),
        "cond_reduced": cond,
        "w_slack": float(qp.P[-1, -1]) if qp.n_slack else 0.0,
        "cond_J": float(sj[0] / sj[-1]) if sj[-1] > 0 else math.inf,
        "m": float(run.m[k]),
        "alpha": float(run.alpha[k]),
        "active": float(np.count_nonzero(run.active[k])),
        "penalty_margin": rho / largest if largest > 0 else math.inf,
    }


def admissible_width(qp: QP) -> float:
    """The widest extent of the program's feasible set along any variable: ``max_j (max x_j -
    min x_j)`` over ``A x = b, G x <= h, lb <= x <= ub``, by two linear programs per variable
    (HiGHS). Zero when the set is one point (a task-scaled step's: the largest scale leaves one
    command), positive when the objective has a face or more to choose from."""
    from scipy.optimize import linprog  # loaded on first use: the control loop never needs it

    n = qp.P.shape[0]
    widest = 0.0
    for j in range(n):
        ends = []
        for sign in (1.0, -1.0):
            c = np.zeros(n)
            c[j] = sign
            res = linprog(
                c,
                A_ub=qp.G if qp.G.shape[0] else None,
                b_ub=qp.h if qp.G.shape[0] else None,
                A_eq=qp.A,
                b_eq=qp.b,
                bounds=list(zip(qp.lb, qp.ub, strict=True)),
                method="highs",
            )
            if res.status != 0:  # unbounded along j (a free slack) or numerically infeasible
                return math.inf if res.status == 3 else math.nan
            ends.append(float(res.x[j]))
        widest = max(widest, ends[1] - ends[0])
    return widest


@dataclass(eq=False)
class LabResult:
    """The reference run, the re-solved steps and every solver's study."""

    scenario: Scenario
    controller: Controller
    reference: Run
    steps: list[int]
    representative: dict[Representative, int]
    studies: dict[str, SolverStudy]
    optimum: dict[int, tuple[Vector, float]]
    features: dict[int, dict[str, float]] = field(default_factory=dict)
    repeats: int = 1
    """Each call is timed as the median of up to this many (one above :data:`SLOW_CALL`)."""
    budget: int = DEFAULT_BUDGET
    """The gradient-free methods' evaluation budget per program."""


def sample_steps(run: Run, sample: int | None) -> list[int]:
    """All steps, or ``sample`` evenly spaced ones that always include the representative steps
    and the least dexterous one (the smallest ``m``: the worst-conditioned program, which an
    even spacing could miss)."""
    steps = list(range(run.steps))
    if sample is None or sample >= len(steps):
        return steps
    chosen = even_steps(run.steps, sample)
    chosen |= set(representative_steps(run).values())  # the least dexterous one among them
    return sorted(chosen)


def even_steps(steps: int, sample: int) -> set[int]:
    """``sample`` evenly spaced steps of a run of ``steps``, its first and last among them."""
    return {round(i) for i in np.linspace(0, steps - 1, sample)}


def sample_made_of(
    resolved: list[int], representative: list[int], steps: int
) -> tuple[int, list[int]]:
    """How a lab's ``resolved`` steps were chosen from a run of ``steps``: the number of evenly
    spaced ones and the ``representative`` steps added to them (:func:`sample_steps`, read back
    from a record); ``(len(resolved), [])`` when every step was re-solved."""
    have = set(resolved)
    for count in range(len(have), 0, -1):
        grid = even_steps(steps, count)
        if grid <= have and grid | set(representative) == have:
            return count, sorted(have - grid)
    raise ValueError("the resolved steps are not an even sample plus representative steps")


def worker_pool(workers: int) -> ProcessPoolExecutor:
    """A pool of ``workers`` forked processes (they inherit the compiled kernels) that end with
    the process that made them, even when it is killed (:func:`~emdm.errors.die_with_parent`)."""
    return ProcessPoolExecutor(
        max_workers=workers,
        mp_context=multiprocessing.get_context("fork"),
        initializer=die_with_parent,
        initargs=(os.getpid(),),
    )


def representative_steps(run: Run) -> dict[Representative, int]:
    """The first step, the first scaled step (if any), the last step of a run and its least
    dexterous one (the smallest ``m``: the worst-conditioned program)."""
    reps = {Representative.FIRST: 0}
    scaled = np.flatnonzero(run.alpha < 1.0)
    if scaled.size:
        first = int(scaled[0]) if scaled[0] != 0 else int(scaled[min(1, scaled.size - 1)])
        reps[Representative.SCALED] = first
    reps[Representative.LAST] = run.steps - 1
    reps[Representative.LEAST_DEXTEROUS] = int(np.argmin(run.m[: run.steps]))
    return reps


def _call(
    spec: SolverSpec,
    qp: QP,
    budget: int | None,
    history: bool = False,
    seed: int | None = None,
    penalty: float | None = None,
) -> SolverResult:
    kwargs: dict[str, Any] = {"history": history}
    if budget is not None and spec.family == "gradient-free":
        kwargs["budget"] = budget
    if seed is not None:
        kwargs["seed"] = seed
    if penalty is not None:  # (the penalised methods only)
        kwargs["penalty"] = penalty
    return spec.solve(qp, **kwargs)


def _timed(
    spec: SolverSpec,
    qp: QP,
    budget: int | None,
    repeats: int,
    seed: int | None = None,
    penalty: float | None = None,
) -> tuple[SolverResult, float]:
    """The solver's result and the median wall time of up to ``repeats`` solves (>= 1)."""
    times = []
    result = None
    for _ in range(max(1, repeats)):
        start = time.perf_counter()
        try:
            result = _call(spec, qp, budget, seed=seed, penalty=penalty)
        except Exception as exc:  # a raising solver is a measured failure
            result = SolverResult(None, f"error: {type(exc).__name__}: {exc}", 0, 0.0)
        times.append(time.perf_counter() - start)
        if times[-1] > SLOW_CALL:  # one measurement is already far above timer noise
            break
    assert result is not None
    return result, float(np.median(times))


def run_lab(
    scenario: Scenario,
    controller: str | Controller,
    solvers: Sequence[str] = DEFAULT_LAB_SOLVERS,
    *,
    sample: int | None = 100,
    repeats: int = 5,
    budget: int | None = None,
    closed_loop: bool = True,
    workers: int = 1,
    progress: Any = None,
) -> LabResult:
    """Measure ``solvers`` on ``controller``'s programs along the exact trajectory of ``scenario``.

    ``sample`` limits the number of re-solved steps (``None``: every step); ``budget`` sets the
    evaluation budget of the gradient-free methods (default: their own); ``workers > 1`` spreads
    the solvers over that many processes (each solver's timings stay within one process).
    """
    ctrl = controller if isinstance(controller, Controller) else get_controller(controller)
    specs = [get_solver(name) for name in solvers]
    reference = simulate(scenario, ctrl)
    if reference.steps == 0:
        raise ScenarioError(
            scenario.source,
            "motion.goal",
            f"{ctrl.name} is at the goal at the start: there is no program to solve",
        )
    steps = sample_steps(reference, sample)
    reps = representative_steps(reference) if reference.steps else {}
    programs = {k: program_at(ctrl, scenario, reference.q[k]).qp for k in steps}
    optimum = {}
    for k, qp in programs.items():
        x_star = np.concatenate((reference.qd[k], reference.delta[k][: qp.n_slack]))
        optimum[k] = (x_star, qp.objective(x_star))

    jobs = [
        (scenario, ctrl, spec.name, programs, optimum, reps, budget, repeats, closed_loop)
        for spec in specs
    ]
    studies: dict[str, SolverStudy] = {}
    if workers > 1 and len(jobs) > 1:
        with worker_pool(workers) as pool:
            futures = {pool.submit(_study, *job): job[2] for job in jobs}
            done = {}
            for future in as_completed(futures):
                check_stop()  # a safe point (a signal's exception may have been dropped)
                done[futures[future]] = future.result()
                if progress is not None:
                    progress(futures[future])
        parts = [done[spec.name] for spec in specs]
    else:
        parts = []
        for job in jobs:
            check_stop()
            parts.append(_study(*job))
            if progress is not None:
                progress(job[2])
    for spec, (solves, histories, run, error, seeds, check) in zip(specs, parts, strict=True):
        studies[spec.name] = SolverStudy(spec, solves, histories, run, error, seeds, check)
    features = {k: step_features(reference, k, qp) for k, qp in programs.items()}
    for study in studies.values():  # the smaller weight's margin over the multipliers
        if study.penalty_check is not None and features:
            scale = study.penalty_check["penalty_weight"] / PENALTY  # (rho is linear in it)
            margin = min(f["penalty_margin"] for f in features.values())
            study.penalty_check["penalty_margin"] = margin * scale
    return LabResult(
        scenario,
        ctrl,
        reference,
        steps,
        reps,
        studies,
        optimum,
        features,
        repeats=repeats,
        budget=DEFAULT_BUDGET if budget is None else budget,
    )


def _study(
    scenario: Scenario,
    ctrl: Controller,
    name: str,
    programs: dict[int, QP],
    optimum: dict[int, tuple[Vector, float]],
    reps: dict[Representative, int],
    budget: int | None,
    repeats: int,
    closed_loop: bool,
) -> tuple[
    list[StepSolve],
    dict[Representative, tuple[dict[str, float], ...]],
    Run | None,
    str | None,
    list[dict[str, Any]],
    dict[str, Any] | None,
]:
    """One solver's measurements (runs in a worker process when the lab is parallel)."""
    spec = get_solver(name)
    steps = sorted(programs)
    if steps:
        _timed(spec, programs[steps[0]], budget, 1)  # warm-up, not measured
    solves = _solves(spec, programs, optimum, budget, repeats)
    seeds: list[dict[str, Any]] = []
    if name in SEEDED:  # the spread of a stochastic method: every program again per seed
        period = scenario.motion.dt
        seeds.append(seed_summary(0, solves, period))
        for seed in range(1, SEEDS):
            again = _solves(spec, programs, optimum, budget, 1, seed)
            seeds.append(seed_summary(seed, again, period))
    check = None
    if name in PENALISED:  # the same programs with a smaller l1 weight (reading 275)
        weight = PENALTY * PENALTY_CHECK
        again = _solves(spec, programs, optimum, budget, 1, penalty=weight)
        check = {"penalty_weight": weight, **run_summary(again, scenario.motion.dt)}
    histories: dict[Representative, tuple[dict[str, float], ...]] = {}
    for label, k in reps.items():
        try:
            histories[label] = _call(spec, programs[k], budget, history=True).history
        except Exception:  # a raising solver simply has no history to show
            histories[label] = ()
    run, error = None, None
    if closed_loop:
        try:
            run = simulate(  # each solver as the lab measured it: the same evaluation budget
                scenario, ctrl, solver=name, fallback=("active-set",), certify=False, budget=budget
            )
        except NoSolution as exc:
            error = str(exc)
    return solves, histories, run, error, seeds, check


def _solves(
    spec: SolverSpec,
    programs: dict[int, QP],
    optimum: dict[int, tuple[Vector, float]],
    budget: int | None,
    repeats: int,
    seed: int | None = None,
    penalty: float | None = None,
) -> list[StepSolve]:
    """``spec``'s answer to every program, each timed (median of up to ``repeats`` solves)."""
    solves = []
    for k in sorted(programs):
        qp = programs[k]
        result, elapsed = _timed(spec, qp, budget, repeats, seed, penalty)
        x = result.x if result.x is not None and np.all(np.isfinite(result.x)) else None
        objective = qp.objective(x) if x is not None else math.nan
        solves.append(
            StepSolve(
                step=k,
                x=x,
                objective=objective,
                gap=objective - optimum[k][1],
                violation=qp.violation(x) if x is not None else math.nan,
                iterations=result.iterations,
                evaluations=result.evaluations,
                gradients=result.gradients,
                time=elapsed,
                status=result.status,
            )
        )
    return solves


def seed_summary(seed: int, solves: Sequence[StepSolve], period: float) -> dict[str, Any]:
    """One seed's run of a stochastic method over the lab's programs (:func:`run_summary`)."""
    return {"seed": seed, **run_summary(solves, period)}


def run_summary(solves: Sequence[StepSolve], period: float) -> dict[str, Any]:
    """A method's run over the lab's programs: its median evaluations, largest |gap| and bound
    violation over the answers found, failures, and the programs it took longer than the
    control ``period`` (s) to solve."""
    found = [s for s in solves if s.x is not None]
    return {
        "median_evaluations": float(np.median([s.evaluations for s in solves])),
        "max_abs_gap": float(max((abs(s.gap) for s in found), default=math.nan)),
        "max_violation": float(max((s.violation for s in found), default=math.nan)),
        "failures": len(solves) - len(found),
        "over_period": sum(s.time > period for s in solves),
    }


def lab_json(lab: LabResult) -> dict[str, Any]:
    """``solvers.json`` (its format is in the README)."""
    return {
        "scenario": lab.scenario.name,
        "controller": lab.controller.name,
        "reference_solver": "active-set",
        "resolved_steps": lab.steps,
        "representative_steps": lab.representative,
        "installed": available_solvers(),
        # the gradient-free methods' exact l1 penalty: rho = penalty_weight (1 + max|P|)
        "penalty_weight": PENALTY,
        "repeats": lab.repeats,
        "budget": lab.budget,
        "solvers": {
            name: study.summary(lab.scenario.motion.dt) for name, study in lab.studies.items()
        },
        "challenges": challenges(lab),
    }


def lab_histories(lab: LabResult) -> dict[str, Any]:
    """``histories.json``: every solver's iterates on the representative programs (its format
    is in the README), the record the convergence figures are drawn from.

    Per representative step: its exact optimum ``f*``; per solver: its family, its history at
    each representative (the solver's own fields per iterate: ``iteration``, ``objective`` and,
    as it reports them, ``evaluations``, ``violation`` or ``primal_residual``) and
    ``returned``: ``|f - f*|`` + bound violation of the answer it returned there (null: none).
    """
    returned: dict[str, dict[str, float | None]] = {}
    for name, study in lab.studies.items():
        answers = {st.step: st for st in study.solves if st.x is not None}
        returned[name] = {
            str(rep): (float(abs(answers[k].gap) + answers[k].violation) if k in answers else None)
            for rep, k in lab.representative.items()
        }
    return {
        "scenario": lab.scenario.name,
        "controller": lab.controller.name,
        "representative_steps": {str(rep): k for rep, k in lab.representative.items()},
        "optimum": {str(rep): float(lab.optimum[k][1]) for rep, k in lab.representative.items()},
        "solvers": {
            name: {
                "family": study.spec.family,
                "histories": {str(rep): list(h) for rep, h in study.histories.items()},
                "returned": returned[name],
            }
            for name, study in lab.studies.items()
        },
    }


def challenges(lab: LabResult) -> dict[str, Any]:
    """How the numerical challenges show in the measurements (from the lab's own records).

    For each iterative solver: the Spearman rank correlation of its iteration count with the
    reduced-Hessian condition number, and its median iterations on scaled (``alpha < 1``) against
    unscaled steps. Plus the ranges of the features over the re-solved steps.
    """
    if not lab.features:
        return {}
    steps = lab.steps
    cond = np.array([lab.features[k]["cond_reduced"] for k in steps])
    scaled = np.array([lab.features[k]["alpha"] < 1.0 for k in steps])
    ranges = {}
    for key in ("cond_reduced", "w_slack", "cond_J", "m", "alpha", "penalty_margin"):
        # (a program with no active bound has no multiplier: its penalty margin is infinite)
        values = [f[key] for f in lab.features.values() if math.isfinite(f[key])]
        ranges[key] = [float(min(values)), float(max(values))] if values else []
    per_solver = {}
    for name, study in lab.studies.items():
        its = np.array([s.iterations for s in study.solves], dtype=float)
        if np.ptp(its) == 0:
            continue
        entry: dict[str, Any] = {"iterations_vs_cond_spearman": _spearman(its, cond)}
        if scaled.any() and (~scaled).any():
            entry["median_iterations_scaled"] = float(np.median(its[scaled]))
            entry["median_iterations_unscaled"] = float(np.median(its[~scaled]))
        per_solver[name] = entry
    # a scaled step's admissible set: its extent (one point: zero) and the bounds active there
    # (with the task rows, more active constraints than unknowns: a degenerate vertex)
    on_scaled = [lab.features[k] for k, s in zip(steps, scaled, strict=True) if s]
    vertex = (
        {
            "max_width": float(max(f["width"] for f in on_scaled)),
            "active": [
                int(min(f["active"] for f in on_scaled)),
                int(max(f["active"] for f in on_scaled)),
            ],
            "unknowns": int(on_scaled[0]["unknowns"]),
            "task_rows": int(on_scaled[0]["rows"]),
            "steps": len(on_scaled),  # how many scaled steps these rest on (the lab's sample)
        }
        if on_scaled
        else None
    )
    return {
        "feature_ranges": ranges,
        "scaled_steps": int(scaled.sum()),
        "scaled_vertex": vertex,
        "solvers": per_solver,
        "min_manipulability_step": int(
            steps[int(np.argmin([lab.features[k]["m"] for k in steps]))]
        ),
    }


def _spearman(a: Vector, b: Vector) -> float:
    """Spearman's rank correlation (ties broken by order; enough for a descriptive number)."""
    if np.ptp(a) == 0 or np.ptp(b) == 0:
        return math.nan
    ra, rb = np.argsort(np.argsort(a)), np.argsort(np.argsort(b))
    return float(np.corrcoef(ra, rb)[0, 1])


def _x_width(lab: LabResult) -> int:
    return max((x.size for x, _ in lab.optimum.values()), default=lab.scenario.n)


def lab_header(lab: LabResult) -> list[str]:
    """Columns of ``solvers/<NAME>.csv``: the documented ones, then the step features."""
    n = lab.scenario.n
    return [
        "step",
        *[f"q{i}" for i in range(1, n + 1)],
        *[f"x{i}" for i in range(1, _x_width(lab) + 1)],
        "objective",
        "gap",
        "violation",
        "iterations",
        "evaluations",
        "time",
        "status",
        *FEATURES,
    ]


def lab_rows(lab: LabResult, name: str) -> list[list[Any]]:
    """One row per re-solved step of solver ``name``."""
    width = _x_width(lab)
    rows = []
    for s in lab.studies[name].solves:
        x = list(s.x) if s.x is not None else []
        x += [""] * (width - len(x))
        feats = lab.features.get(s.step, {})
        rows.append(
            [
                s.step,
                *lab.reference.q[s.step],
                *x,
                s.objective,
                s.gap,
                s.violation,
                s.iterations,
                s.evaluations,
                s.time,
                s.status,
                *[feats.get(key, math.nan) for key in FEATURES],
            ]
        )
    return rows


def merge_labs(parts: Sequence[LabResult]) -> LabResult:
    """One lab from labs of the same scenario, controller and steps run for different solvers."""
    first = parts[0]
    for part in parts[1:]:
        if (part.steps, part.controller, part.budget) != (
            first.steps,
            first.controller,
            first.budget,
        ):
            raise ValueError("only labs of the same controller, steps and budget can be merged")
    studies: dict[str, SolverStudy] = {}
    for part in parts:
        studies.update(part.studies)
    return LabResult(
        first.scenario,
        first.controller,
        first.reference,
        first.steps,
        first.representative,
        studies,
        first.optimum,
        first.features,
        repeats=first.repeats,
        budget=first.budget,
    )
