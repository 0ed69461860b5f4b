"""Custom exact solvers for the per-step programs.

``kkt``: the equality-constrained program solved in one linear system,

    [ P   A^T ] [  x   ]   [ -c ]
    [ A    0  ] [ -lam ] = [  b ]

which for ``min 1/2 ||qd||^2 s.t. J qd = v`` gives ``qd = J^+ v`` (mathematics.md eq. 4, 5). It ignores bounds
and returns no point (status ``"unsupported"``) when its answer leaves them.

``active-set``: a primal active-set method (Nocedal & Wright, Algorithm 16.3) specialised to
equalities plus simple bounds. It starts from an exact feasible point (:mod:`emdm.feasibility`), keeps
a *working set* of variables fixed at a bound, and solves at each iteration the equality-constrained
step over the free variables. The working set is kept linearly independent together with the rows of
``A`` (the free columns of ``A`` keep full row rank), so the multipliers are unique; a blocking bound
is added after a partial step, and a bound with a multiplier of the wrong sign is dropped (the most
negative one, or the lowest index after a zero-length step: Bland's rule against cycling). For a
strictly convex QP this terminates after finitely many iterations at the exact optimum.
"""

from __future__ import annotations

import time

import numpy as np

from ..core.arm import Matrix, Vector
from ..core.feasibility import RANK_TOL, feasible_point
from ..core.problem import QP
from . import kernels
from .base import UNSUPPORTED_ROWS, SolverResult, kkt_report


def independent_rows(A: Matrix, b: Vector) -> tuple[Matrix, Vector]:
    """Drop linearly dependent equality rows (a singular Jacobian); ``A x = b`` must be consistent."""
    U, s, _ = np.linalg.svd(A, full_matrices=False)
    rank = int(np.sum(s > RANK_TOL * max(s[0], 1.0))) if s.size else 0
    if rank == A.shape[0]:
        return A, b
    return U[:, :rank].T @ A, U[:, :rank].T @ b


def _full_row_rank(A: Matrix) -> bool:
    if A.shape[1] < A.shape[0]:
        return False
    s = np.linalg.svd(A, compute_uv=False)
    return bool(s.size == A.shape[0] and s[-1] > RANK_TOL * max(s[0], 1.0)) if A.shape[0] else True


def _eqp(P: Matrix, A: Matrix, g: Vector) -> tuple[Vector, Vector]:
    """Step ``p`` and multipliers ``lam`` of ``min 1/2 p^T P p + g^T p s.t. A p = 0`` (A full row rank).

    Null-space method: ``p = -Z (Z^T P Z)^-1 Z^T g`` with ``Z`` an orthonormal basis of ``null(A)``,
    so ``p`` is exactly 0 when the null space is empty, then ``A^T lam = P p + g``.
    """
    U, s, Vt = np.linalg.svd(A)
    m = A.shape[0]
    Z = Vt[m:].T
    if Z.shape[1]:
        p = -Z @ np.linalg.solve(Z.T @ P @ Z, Z.T @ g)
    else:
        p = np.zeros(g.size)
    lam = U @ ((Vt[:m] @ (P @ p + g)) / s)
    return p, lam


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

    Two-row programs run the compiled kernel (:func:`emdm.solvers.kernels.active_set`, the one the
    control loop uses); the numpy method below serves what the kernel leaves (dependent task rows),
    other shapes, an iteration limit, and per-iteration histories.
    """
    start = time.perf_counter()
    if (qp.A.shape[0] == 2 or qp.n_rows) and max_iter is None and not history:
        x = np.empty(qp.n)
        P, c, A, b, G, h, lb, ub = (
            np.ascontiguousarray(a, dtype=float)
            for a in (qp.P, qp.c, qp.A, qp.b, qp.G, qp.h, qp.lb, qp.ub)
        )
        code, iterations = kernels.active_set_of(P, c, A, b, G, h, lb, ub, x, np.empty(4))
        if code == kernels.OK:
            return SolverResult(x, "optimal", iterations, time.perf_counter() - start)
        if code == kernels.INFEASIBLE:
            return SolverResult(None, "infeasible", 0, time.perf_counter() - start)
        start = time.perf_counter()  # the kernel left this program to the numpy method
    if qp.n_rows:  # the numpy method knows bounds only: the chain's next solver takes the rows
        return SolverResult(None, UNSUPPORTED_ROWS, 0, time.perf_counter() - start)
    x0 = feasible_point(qp.A, qp.b, qp.lb, qp.ub)
    if x0 is None:
        return SolverResult(None, "infeasible", 0, time.perf_counter() - start)
    x = x0.copy()
    P, c, lb, ub = qp.P, qp.c, qp.lb, qp.ub
    A, _ = independent_rows(qp.A, qp.b)
    n = qp.n
    limit = max_iter if max_iter is not None else 10 * (n + A.shape[0]) + 20

    snap = 1e-13 * (
        1.0
        + np.maximum(
            np.abs(np.where(np.isfinite(lb), lb, 0.0)), np.abs(np.where(np.isfinite(ub), ub, 0.0))
        )
    )
    at_lo, at_hi = x - lb <= snap, ub - x <= snap
    x[at_lo], x[at_hi] = lb[at_lo], ub[at_hi]
    work = np.zeros(n, dtype=np.int8)  # -1: fixed at lb, +1: fixed at ub, 0: free
    for j in map(int, np.flatnonzero(at_lo | at_hi)):
        trial = work == 0
        trial[j] = False
        if _full_row_rank(A[:, trial]):
            work[j] = -1 if at_lo[j] else 1

    trace: list[dict[str, float]] = []
    zero_step = False
    for iteration in range(1, limit + 1):
        free = work == 0
        g = P @ x + c
        try:
            p_free, lam = _eqp(P[np.ix_(free, free)], A[:, free], g[free])
        except np.linalg.LinAlgError as exc:
            return SolverResult(x, f"error: {exc}", iteration, time.perf_counter() - start)
        if not np.all(np.isfinite(p_free)):
            return SolverResult(x, "error: singular step", iteration, time.perf_counter() - start)
        p = np.zeros(n)
        p[free] = p_free
        if history:
            trace.append(
                {
                    "iteration": float(iteration),
                    "objective": qp.objective(x),
                    "step": float(np.abs(p).max()),
                    "working_set": float(np.count_nonzero(work)),
                }
            )
        if np.abs(p).max() <= 1e-12 * (1.0 + np.abs(x).max()):
            mu = g - A.T @ lam  # multiplier of each fixed variable's bound
            wrong = np.where(work == -1, -mu, np.where(work == 1, mu, 0.0))
            tol = 1e-12 * (1.0 + np.abs(g).max())
            if wrong.max() <= tol or kkt_report(qp, x).is_optimal():
                # the second test settles degenerate vertices: more bounds are active than the
                # working set can hold, and sign-feasible multipliers exist over all of them
                return SolverResult(
                    x, "optimal", iteration, time.perf_counter() - start, tuple(trace)
                )
            j = int(np.flatnonzero(wrong > tol)[0]) if zero_step else int(np.argmax(wrong))
            work[j] = 0
            continue
        # rounding-level components cannot block: they would add a dependent bound
        moving = free & (np.abs(p) > 1e-13 * np.abs(p).max())
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(p < 0, (lb - x) / p, np.where(p > 0, (ub - x) / p, np.inf))
        ratio[~moving] = np.inf
        blocking = int(np.argmin(ratio))
        step = min(1.0, max(0.0, float(ratio[blocking])))
        x = x + step * p
        # ties in the ratio test land on their bound up to rounding: put them exactly there
        x = np.where(moving & (x < lb) & (lb - x <= snap), lb, x)
        x = np.where(moving & (x > ub) & (x - ub <= snap), ub, x)
        zero_step = step == 0.0
        if step < 1.0:
            side = -1 if p[blocking] < 0 else 1
            x[blocking] = lb[blocking] if side < 0 else ub[blocking]
            rest = work == 0
            rest[blocking] = False
            if _full_row_rank(A[:, rest]):
                work[blocking] = side
    return SolverResult(x, "max_iter", limit, time.perf_counter() - start, tuple(trace))
