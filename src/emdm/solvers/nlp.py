"""General-purpose optimisers on the per-step programs: gradient-based and gradient-free.

Gradient-based (scipy): ``slsqp`` and ``trust-constr`` on the full program, with the exact gradient
``P x + c``, the exact Hessian ``P`` (trust-constr) and the exact constraint Jacobian ``A``.

Gradient-free methods search the *reduced* program, where the task equality is eliminated:

- with task slack (the non-redundant programs): ``t = qd`` and ``delta = b - A_qd qd``, so the slack
  bounds become linear inequalities on ``qd`` (docs/mathematics.md);
- without slack: ``x = x_p + Z t`` with ``x_p = A^+ b`` and ``Z`` an orthonormal basis of ``null(A)``.

Either way only the linear inequalities ``G t <= h`` (from the bounds) remain. ``cobyqa``, ``cobyla``
and ``differential-evolution`` take them natively; ``nelder-mead``, ``powell`` and ``cma-es`` see an
exact l1 penalty ``rho * sum(max(0, G t - h))`` with ``rho = PENALTY (1 + max|P|)``. Nothing is
projected or clipped afterwards: the returned point's constraint violation is measured by the lab.
Random methods are seeded (``seed``, 0 by default) so every run is reproducible.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..core.arm import Matrix, Vector
from ..core.problem import QP
from .base import SolverResult, infeasible

PENALTY = 1e4
"""The l1 penalty weight of the penalised gradient-free methods, per unit of ``1 + max|P|``."""

SEEDED = ("differential-evolution", "cma-es")
"""The stochastic methods: each takes a ``seed`` (0 by default), so a run is reproducible and
their spread is sampled by running seeds 0, 1, ... (:data:`emdm.studies.lab.SEEDS`)."""

WHOLE_GENERATIONS = ("differential-evolution", "cma-es")
"""The methods whose budget ends them at the last whole generation that fits in it: they stop
a few evaluations short of the budget."""
PENALISED = ("nelder-mead", "powell", "cma-es")
"""The gradient-free methods that see the bounds as the exact l1 penalty (the others take them
as constraints)."""


def penalty_weight(qp: QP, per_unit: float = PENALTY) -> float:
    """``rho = PENALTY (1 + max|P|)``: the l1 penalty weight the :data:`PENALISED` methods use
    (``per_unit``: another weight per unit of ``1 + max|P|``, the lab's sensitivity check)."""
    return per_unit * (1.0 + float(np.abs(qp.P).max()))


DEFAULT_BUDGET = 2000
"""Default number of objective evaluations for the gradient-free methods."""


@dataclass(frozen=True, eq=False)
class Reduced:
    """The program in the reduced variables ``t``: ``x = x0 + Z t`` and ``G t <= h``."""

    x0: Vector
    Z: Matrix
    G: Matrix
    h: Vector
    qp: QP

    @property
    def dim(self) -> int:
        return int(self.Z.shape[1])

    def x(self, t: Vector) -> Vector:
        return self.x0 + self.Z @ t

    def objective(self, t: Vector) -> float:
        return self.qp.objective(self.x(t))

    def excess(self, t: Vector) -> float:
        return float(np.maximum(self.G @ t - self.h, 0.0).sum()) if self.h.size else 0.0

    def box(self, default: float = 10.0) -> tuple[Vector, Vector]:
        """The tightest box around the feasible set of ``t`` (one small LP per side), or +-default."""
        from scipy.optimize import linprog  # loaded on first use: the control loop never needs it

        lo, hi = np.full(self.dim, -default), np.full(self.dim, default)
        if not self.h.size:
            return lo, hi
        for i in range(self.dim):
            for sign in (1.0, -1.0):
                cost = np.zeros(self.dim)
                cost[i] = sign
                res = linprog(
                    cost, A_ub=self.G, b_ub=self.h, bounds=[(None, None)] * self.dim, method="highs"
                )
                if res.status == 0:
                    if sign > 0:
                        lo[i] = res.fun
                    else:
                        hi[i] = -res.fun
        return lo, hi


def reduce(qp: QP) -> Reduced:
    """Eliminate the task equality (and the slack, when the program has one)."""
    n, k = qp.n_joints, qp.n_slack
    if k == qp.A.shape[0] and np.array_equal(qp.A[:, n:], np.eye(k)):
        x0 = np.concatenate((np.zeros(n), qp.b))
        Z = np.vstack((np.eye(n), -qp.A[:, :n]))
    else:
        U, s, Vt = np.linalg.svd(qp.A)
        rank = int(np.sum(s > 1e-12 * max(s[0], 1.0)))
        x0 = Vt[:rank].T @ ((U[:, :rank].T @ qp.b) / s[:rank])
        Z = Vt[rank:].T
    rows, rhs = [], []
    for bound, sign in ((qp.ub, 1.0), (qp.lb, -1.0)):
        finite = np.isfinite(bound)
        rows.append(sign * Z[finite])
        rhs.append(sign * (bound[finite] - x0[finite]))
    if qp.n_rows:  # the program's own rows G x <= h, in the reduced variables
        rows.append(qp.G @ Z)
        rhs.append(qp.h - qp.G @ x0)
    G = np.vstack(rows) if rows else np.zeros((0, Z.shape[1]))
    return Reduced(x0, Z, G, np.concatenate(rhs), qp)


@dataclass
class _Recorder:
    """Counts evaluations and keeps the history of evaluated points (objective and violation)."""

    red: Reduced
    penalty: float = 0.0
    keep: bool = False
    evaluations: int = 0
    gradients: int = 0
    """Gradient evaluations (the reduced slsqp's: the gradient-free methods take none)."""
    trace: list[dict[str, float]] = field(default_factory=list)

    def __call__(self, t: Vector) -> float:
        self.evaluations += 1
        f = self.red.objective(t)
        if self.keep:
            self.trace.append(
                {
                    "evaluations": float(self.evaluations),
                    "objective": f,
                    "violation": self.red.qp.violation(self.red.x(t)),
                }
            )
        return f + self.penalty * self.red.excess(t) if self.penalty else f


def _finish(
    red: Reduced, t: Vector, status: str, iterations: int, rec: _Recorder, start: float
) -> SolverResult:
    return SolverResult(
        red.x(np.asarray(t, dtype=float)),
        status,
        iterations,
        time.perf_counter() - start,
        tuple(rec.trace),
        rec.evaluations,
        rec.gradients,
    )


def gradient_free(method: str) -> Callable[..., SolverResult]:
    """A solver function running the gradient-free ``method`` on the reduced program."""

    def solve(
        qp: QP,
        *,
        budget: int = DEFAULT_BUDGET,
        history: bool = False,
        seed: int = 0,
        penalty: float = PENALTY,
    ) -> SolverResult:
        """``seed`` is used by the :data:`SEEDED` methods only (an integer >= 0); ``penalty``,
        the l1 weight per unit of ``1 + max|P|``, by the :data:`PENALISED` methods only."""
        from scipy.optimize import Bounds, LinearConstraint, differential_evolution, minimize

        start = time.perf_counter()
        if infeasible(qp):
            return SolverResult(None, "infeasible", 0, time.perf_counter() - start)
        red = reduce(qp)
        if red.dim == 0:  # the equality leaves a single point
            rec = _Recorder(red, keep=history)
            rec(np.zeros(0))
            return _finish(red, np.zeros(0), "optimal", 0, rec, start)
        # the exact l1 penalty for the methods that cannot take the bounds themselves
        rho = penalty_weight(qp, penalty) if method in PENALISED else 0.0
        t0 = np.zeros(red.dim)
        cons = LinearConstraint(red.G, -np.inf, red.h) if red.h.size else None
        status, iterations, limited = "optimal", 0, False
        if method in ("nelder-mead", "powell"):
            rec = _Recorder(red, penalty=rho, keep=history)
            options: dict[str, Any] = {"maxfev": budget, "xatol": 1e-12, "fatol": 1e-14}
            if method == "powell":
                options = {"maxfev": budget, "xtol": 1e-12, "ftol": 1e-14}
            res = minimize(
                rec,
                t0,
                method="Nelder-Mead" if method == "nelder-mead" else "Powell",
                options=options,
            )
            t, iterations, ok = res.x, int(res.get("nit", 0)), bool(res.success)
        elif method in ("cobyqa", "cobyla"):
            rec = _Recorder(red, penalty=rho, keep=history)
            opts = (
                {"maxfev": budget, "final_tr_radius": 1e-10}
                if method == "cobyqa"
                else {"maxiter": budget, "tol": 1e-10}
            )
            res = minimize(
                rec, t0, method=method.upper(), constraints=[cons] if cons else (), options=opts
            )
            t, iterations, ok = res.x, int(res.get("nit", res.nfev)), bool(res.success)
        elif method == "differential-evolution":
            rec = _Recorder(red, penalty=rho, keep=history)
            lo, hi = red.box()
            popsize = 15
            generation = popsize * red.dim  # trial points; only feasible ones are evaluated

            def last_whole_generation(intermediate_result: Any) -> bool:
                """Stop where another generation could overrun the evaluation budget."""
                return rec.evaluations + generation > budget

            res = differential_evolution(
                rec,
                Bounds(lo, hi),
                constraints=cons if cons else (),
                seed=seed,
                tol=1e-12,
                atol=1e-14,
                popsize=popsize,
                polish=False,
                maxiter=budget,  # the callback stops it first
                callback=last_whole_generation,
            )
            t, iterations, ok = res.x, int(res.nit), bool(res.success)
            limited = rec.evaluations + generation > budget
        elif method == "cma-es":
            import cma

            rec = _Recorder(red, penalty=rho, keep=history)
            lo, hi = red.box()
            sigma = 0.3 * float(np.max(hi - lo))
            es = cma.CMAEvolutionStrategy(
                np.clip(t0, lo, hi),
                sigma,
                {
                    "bounds": [list(lo), list(hi)],
                    "maxfevals": budget,
                    "seed": seed + 1,  # (cma's seed 0 would draw one from the clock)
                    "verbose": -9,
                    "tolfun": 1e-14,
                    "tolx": 1e-13,
                },
            )
            # cma stops once its count passes maxfevals, after the generation that passed it
            # (606 of a 600 budget): the last whole generation that fits ends it instead (a
            # budget below one generation still runs one)
            es.opts["maxfevals"] = max(budget - es.popsize, 0)
            es.optimize(rec)
            t, iterations = es.result.xbest, int(es.result.iterations)
            limited = "maxfevals" in es.result.stop  # (not one of its convergence tests)
            ok = not limited
        else:  # pragma: no cover - guarded by the registry
            raise ValueError(method)
        if not ok:
            limited = limited or rec.evaluations >= budget
            status = "max_iter" if limited else "not converged"
        return _finish(red, t, status, iterations, rec, start)

    solve.__name__ = f"solve_{method.replace('-', '_')}"
    return solve


def solve_slsqp(qp: QP, *, max_iter: int = 500, history: bool = False) -> SolverResult:
    """SLSQP (sequential least squares) with exact gradients, on the full program."""
    return _scipy_gradient(qp, "SLSQP", max_iter, history)


def solve_slsqp_reduced(qp: QP, *, max_iter: int = 500, history: bool = False) -> SolverResult:
    """SLSQP on the reduced program the gradient-free methods search: the same variables ``t``,
    the same inequalities ``G t <= h`` (taken natively), the exact reduced gradient
    ``Z^T (P x + c)``, its objective evaluations counted the same way; beside them in the lab,
    a gradient-based method on their formulation rather than on the full program."""
    from scipy.optimize import LinearConstraint, minimize

    start = time.perf_counter()
    if infeasible(qp):
        return SolverResult(None, "infeasible", 0, time.perf_counter() - start)
    red = reduce(qp)
    rec = _Recorder(red, keep=history)
    if red.dim == 0:  # the equality leaves a single point
        rec(np.zeros(0))
        return _finish(red, np.zeros(0), "optimal", 0, rec, start)

    def grad(t: Vector) -> Vector:
        rec.gradients += 1
        return np.asarray(red.Z.T @ (qp.P @ red.x(t) + qp.c))

    rows = [LinearConstraint(red.G, -np.inf, red.h)] if red.h.size else []
    res = minimize(
        rec,
        np.zeros(red.dim),
        jac=grad,
        method="SLSQP",
        constraints=rows,
        options={"maxiter": max_iter, "ftol": 1e-14},
    )
    status = "optimal" if res.success else f"not converged: {res.message}"
    return _finish(red, res.x, status, int(res.get("nit", 0)), rec, start)


def solve_trust_constr(qp: QP, *, max_iter: int = 500, history: bool = False) -> SolverResult:
    """trust-constr (interior-point trust region) with the exact gradient and Hessian."""
    return _scipy_gradient(qp, "trust-constr", max_iter, history)


def _scipy_gradient(qp: QP, method: str, max_iter: int, history: bool) -> SolverResult:
    from scipy.optimize import Bounds, LinearConstraint, minimize

    start = time.perf_counter()
    if infeasible(qp):
        return SolverResult(None, "infeasible", 0, time.perf_counter() - start)
    evaluations = gradients = 0
    trace: list[dict[str, float]] = []

    def f(x: Vector) -> float:
        nonlocal evaluations
        evaluations += 1
        return qp.objective(x)

    def grad(x: Vector) -> Vector:
        nonlocal gradients
        gradients += 1
        return np.asarray(qp.P @ x + qp.c)

    def callback(*args: Any) -> None:
        x = np.asarray(args[0], dtype=float)
        trace.append(
            {
                "iteration": float(len(trace) + 1),
                "evaluations": float(evaluations),
                "objective": qp.objective(x),
                "violation": qp.violation(x),
            }
        )

    x0 = np.clip(np.linalg.lstsq(qp.A, qp.b, rcond=None)[0], qp.lb, qp.ub)
    bounds = Bounds(qp.lb, qp.ub) if qp.bounded else None
    rows: list[Any] = []
    if method == "SLSQP":
        if qp.n_rows:
            rows = [{"type": "ineq", "fun": lambda x: qp.h - qp.G @ x, "jac": lambda x: -qp.G}]
    elif qp.n_rows:
        rows = [LinearConstraint(qp.G, -np.inf, qp.h)]
    if method == "SLSQP":
        res = minimize(
            f,
            x0,
            jac=grad,
            method="SLSQP",
            bounds=bounds,
            constraints=[
                {"type": "eq", "fun": lambda x: qp.A @ x - qp.b, "jac": lambda x: qp.A},
                *rows,
            ],
            options={"maxiter": max_iter, "ftol": 1e-14},
            callback=callback if history else None,
        )
    else:
        res = minimize(
            f,
            x0,
            jac=grad,
            hess=lambda x: qp.P,
            method="trust-constr",
            bounds=bounds,
            constraints=[LinearConstraint(qp.A, qp.b, qp.b), *rows],
            options={"maxiter": max_iter, "gtol": 1e-12, "xtol": 1e-14},
            callback=(lambda x, state: callback(x)) if history else None,
        )
    status = "optimal" if res.success else f"not converged: {res.message}"
    return SolverResult(
        np.asarray(res.x, dtype=float),
        status,
        int(res.get("nit", 0)),
        time.perf_counter() - start,
        tuple(trace),
        evaluations,
        gradients,
    )
