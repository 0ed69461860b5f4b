"""Custom exact solvers for the per-step programs.

``kkt``: the equality-constrained program solved in one linear system,

    [ P   A^T ] [  x   ]   [ -c ]
    [ A    0  ] [ -lam ] = [  b ]

which for ``min 1/2 ||qd||^2 s.t. J qd = v`` gives ``qd = J^+ v`` (mathematics.md eq. 4, 5). It ignores bounds
and returns no point (status ``"unsupported"``) when its answer leaves them.

``active-set``: the compiled primal active-set method of :mod:`emdm.solvers.kernels` (Nocedal &
Wright, Algorithm 16.3, specialised to equality rows, inequality rows and simple bounds), the one
the control loop runs, called here from a cold start with an optional iteration limit and trace.
It starts from an exact feasible point (:mod:`emdm.core.simplex`), keeps a *working set* of bounds
and rows held as equalities, linearly independent together with the task rows so the multipliers
are unique, and solves at each iteration the equality-constrained step over the free variables;
a blocking bound or row is added after a partial step, and one with a multiplier of the wrong sign
is dropped (the most negative one, or the lowest index after a zero-length step: Bland's rule
against cycling). For a strictly convex QP this terminates after finitely many iterations at the
exact optimum. The numpy statement of the same method is the tests' oracle
(``tests/reference_active_set.py``).
"""

from __future__ import annotations

import time

import numpy as np

from ..core.arm import Matrix, Vector
from ..core.problem import QP
from ..core.tolerances import RANK_TOL
from . import kernels
from .base import UNSUPPORTED_ROWS, SolverResult


def independent_rows(A: Matrix, b: Vector) -> tuple[Matrix, Vector]:
    """Drop linearly dependent equality rows (a singular Jacobian); ``A x = b`` must be consistent."""
    U, s, _ = np.linalg.svd(A, full_matrices=False)
    rank = int(np.sum(s > RANK_TOL * max(s[0], 1.0))) if s.size else 0
    if rank == A.shape[0]:
        return A, b
    return U[:, :rank].T @ A, U[:, :rank].T @ b


def solve_kkt(qp: QP, *, history: bool = False) -> SolverResult:
    """The equality-constrained optimum in one KKT solve (bounds are not enforced, only checked)."""
    start = time.perf_counter()
    if qp.n_rows:
        return SolverResult(None, UNSUPPORTED_ROWS, 0, time.perf_counter() - start)
    try:
        A, b = independent_rows(qp.A, qp.b)
        n, m = qp.n, A.shape[0]
        K = np.zeros((n + m, n + m))
        K[:n, :n], K[:n, n:], K[n:, :n] = qp.P, -A.T, A
        x = np.linalg.solve(K, np.concatenate((-qp.c, b)))[:n]
    except np.linalg.LinAlgError as exc:
        return SolverResult(None, f"error: {exc}", 1, time.perf_counter() - start)
    elapsed = time.perf_counter() - start
    if np.abs(qp.A @ x - qp.b).max() > 1e-9 * max(1.0, float(np.abs(qp.b).max())):
        return SolverResult(None, "infeasible", 1, elapsed)
    excess = qp.bound_excess(x)
    if excess > 0.0:  # not an answer to the bounded program: say so, return no point
        return SolverResult(
            None, f"unsupported: the equality optimum leaves the bounds by {excess:.2g}", 1, elapsed
        )
    return SolverResult(x, "optimal", 1, elapsed)


def solve_active_set(qp: QP, *, max_iter: int | None = None, history: bool = False) -> SolverResult:
    """Exact optimum of ``qp`` by the primal active-set method (see the module notes).

    This is the compiled kernel the control loop uses (:func:`emdm.solvers.kernels.active_set`),
    from a cold start; ``max_iter`` limits its iterations (status ``"max_iter"``, the last iterate
    returned) and ``history`` returns its trace. Dependent task rows (a singular Jacobian) are
    reduced to independent ones first when the kernel meets them.
    """
    start = time.perf_counter()
    P, c, A, b, G, h, lb, ub = (
        np.ascontiguousarray(a, dtype=float)
        for a in (qp.P, qp.c, qp.A, qp.b, qp.G, qp.h, qp.lb, qp.ub)
    )
    if max_iter is not None and max_iter < 1:
        raise ValueError(f"max_iter must be at least 1, got {max_iter}")
    limit = max_iter if max_iter is not None else 10 * (qp.n + qp.n_rows + 2) + 20
    x = np.empty(qp.n)
    code, iterations, trace = kernels.active_set_traced(
        P, c, A, b, G, h, lb, ub, x, np.empty(4), limit if history else 0, max_iter or 0
    )
    if code == kernels.NEEDS_REFERENCE and A.shape[0]:
        A, b = (np.ascontiguousarray(a) for a in independent_rows(A, b))
        if A.shape[0] < qp.A.shape[0]:
            code, iterations, trace = kernels.active_set_traced(
                P, c, A, b, G, h, lb, ub, x, np.empty(4), limit if history else 0, max_iter or 0
            )
    elapsed = time.perf_counter() - start
    steps = tuple(
        {"iteration": float(k + 1), "objective": f, "step": s, "working_set": held}
        for k, (f, s, held) in enumerate(trace.tolist())
        if np.isfinite(f)
    )
    if code == kernels.OK:
        return SolverResult(x, "optimal", iterations, elapsed, steps)
    if code == kernels.INFEASIBLE:
        return SolverResult(None, "infeasible", 0, elapsed, steps)
    if code == kernels.MAX_ITER_EXCEEDED:
        return SolverResult(x, "max_iter", iterations, elapsed, steps)
    return SolverResult(
        None,
        "error: a singular step (the objective is not strictly convex on the task's null space)",
        iterations,
        elapsed,
        steps,
    )
