"""The numpy statement of the primal active-set method: the oracle of the compiled kernel.

Nocedal & Wright, Algorithm 16.3, for equality rows and simple bounds, written with dense
linear algebra (null-space steps by SVD) and nothing of emdm's but the exact feasible point and
the KKT report. ``tests/test_solvers.py`` checks the kernel against it iteration by iteration
(the objective, the step and the working set) and at the optimum.
"""

from __future__ import annotations

import numpy as np

from emdm.core.feasibility import feasible_point
from emdm.core.tolerances import RANK_TOL
from emdm.solvers.active_set import independent_rows
from emdm.solvers.base import kkt_report


def _full_row_rank(A):
    if A.shape[1] < A.shape[0]:
        return False
    s = np.linalg.svd(A, compute_uv=False)
    return bool(s.size == A.shape[0] and s[-1] > RANK_TOL * max(s[0], 1.0)) if A.shape[0] else True


def _eqp(P, A, g):
    """Step ``p`` and multipliers ``lam`` of ``min 1/2 p^T P p + g^T p s.t. A p = 0``:
    ``p = -Z (Z^T P Z)^-1 Z^T g`` with ``Z`` an orthonormal basis of ``null(A)``, then
    ``A^T lam = P p + g``."""
    U, s, Vt = np.linalg.svd(A)
    m = A.shape[0]
    Z = Vt[m:].T
    p = -Z @ np.linalg.solve(Z.T @ P @ Z, Z.T @ g) if Z.shape[1] else np.zeros(g.size)
    lam = U @ ((Vt[:m] @ (P @ p + g)) / s)
    return p, lam


def numpy_active_set(qp, max_iter=None):
    """``(x, status, trace)`` for a program with bounds only; ``trace`` holds per iteration
    ``(objective, max |p|, working-set size)``."""
    assert qp.n_rows == 0, "the numpy method knows bounds only"
    A, b = independent_rows(qp.A, qp.b)  # as the kernel's wrapper does, before its start
    x0 = feasible_point(A, b, qp.lb, qp.ub)
    if x0 is None:
        return None, "infeasible", []
    x = x0.copy()
    P, c, lb, ub = qp.P, qp.c, qp.lb, qp.ub
    n = qp.n
    limit = max_iter if max_iter is not None else 10 * (n + A.shape[0]) + 20
    bound = np.maximum(
        np.abs(np.where(np.isfinite(lb), lb, 0.0)), np.abs(np.where(np.isfinite(ub), ub, 0.0))
    )
    snap = 1e-13 * (1.0 + bound)
    at_lo, at_hi = x - lb <= snap, ub - x <= snap
    x[at_lo], x[at_hi] = lb[at_lo], ub[at_hi]
    work = np.zeros(n, dtype=np.int8)  # -1: fixed at lb, +1: fixed at ub, 0: free
    for j in map(int, np.flatnonzero(at_lo | at_hi)):
        trial = work == 0
        trial[j] = False
        if _full_row_rank(A[:, trial]):
            work[j] = -1 if at_lo[j] else 1
    trace = []
    zero_step = False
    for _ in range(limit):
        free = work == 0
        g = P @ x + c
        p_free, lam = _eqp(P[np.ix_(free, free)], A[:, free], g[free])
        p = np.zeros(n)
        p[free] = p_free
        trace.append((qp.objective(x), float(np.abs(p).max()), int(np.count_nonzero(work))))
        if np.abs(p).max() <= 1e-12 * (1.0 + np.abs(x).max()):
            mu = g - A.T @ lam
            wrong = np.where(work == -1, -mu, np.where(work == 1, mu, 0.0))
            tol = 1e-12 * (1.0 + np.abs(g).max())
            if wrong.max() <= tol or kkt_report(qp, x).is_optimal():
                return x, "optimal", trace
            j = int(np.flatnonzero(wrong > tol)[0]) if zero_step else int(np.argmax(wrong))
            work[j] = 0
            continue
        moving = free & (np.abs(p) > 1e-13 * np.abs(p).max())
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(p < 0, (lb - x) / p, np.where(p > 0, (ub - x) / p, np.inf))
        ratio[~moving] = np.inf
        blocking = int(np.argmin(ratio))
        step = min(1.0, max(0.0, float(ratio[blocking])))
        x = x + step * p
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
    return x, "max_iter", trace
