"""The compiled solver: the primal active-set method for the per-step programs.

Programs have the form ``min 1/2 x^T P x + c^T x  s.t.  A x = b (nt rows), G x <= h (ng rows),
lb <= x <= ub``, with ``nt`` = 2 for a planar task, 3 for a position and 6 for a pose, and ``ng``
general inequality rows (0 for the brief's programs; box bounds stay boxes, the fast path).

:func:`active_set` is Nocedal & Wright's Algorithm 16.3 specialised to equality rows, inequality
rows and simple bounds (see :mod:`emdm.solvers.active_set` and docs/mathematics.md); it starts
from the exact feasible point of :func:`emdm.core.simplex.feasible_point_rows` and returns the
multipliers of its final working set, checked by the certificate of :mod:`emdm.solvers.certificate`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..core.jit import kernel
from ..core.kernels import matrix_rank, solve_in_place
from ..core.simplex import feasible_point_rows
from ..core.tolerances import ACTIVE_TOL, BOUND_TOL, KKT_TOL, RANK_TOL
from ..core.zonotope import INFEASIBLE, NEEDS_REFERENCE, OK, feasible_point, free_rank
from .certificate import (
    QPWork,
    best_multipliers,
    certify,
    certify_of,
    kkt_residuals,
    multipliers_of,
    qp_work,
)

F64 = NDArray[np.float64]

__all__ = [
    "BOUND_TOL",
    "INFEASIBLE",
    "KKT_TOL",
    "NEEDS_REFERENCE",
    "OK",
    "QPWork",
    "best_multipliers",
    "certify",
    "certify_of",
    "kkt_residuals",
    "multipliers_of",
    "qp_work",
]


MAX_ITER_EXCEEDED = 3
"""Code of :func:`active_set` when its iteration limit ran out."""


@kernel(refcount=False, inline=True)
def active_set(
    P: F64,
    c: F64,
    A: F64,
    b: F64,
    G: F64,
    h: F64,
    lb: F64,
    ub: F64,
    x: F64,
    w: QPWork,
    out: F64,
    full: Any,
) -> tuple[int, int]:
    """Exact optimum of the program by the primal active-set method: ``(code, iterations)``.

    ``full`` is ``None`` for the programs of a plain planar run (two task rows, no inequality
    rows, no trace; :func:`emdm.sim.loop.run_kernel`'s argument of that name) and ``True`` for
    any other: numba prunes the branches that test it, so the plain planar loop compiles no
    simplex method and no row handling (the same answers: those branches do nothing there).

    On ``OK``, ``x`` is the optimum, ``w.lam`` (task rows, then inequality rows), ``w.mu`` its
    multipliers and ``out``
    the KKT residuals of :func:`kkt_residuals` for them. ``NEEDS_REFERENCE`` leaves a case this
    kernel does not settle (dependent equality rows) to the numpy method; ``INFEASIBLE`` means no
    point satisfies the constraints.

    The working set holds bounds (``w.work[:n]``: -1 at lb, +1 at ub) and inequality rows
    (``w.work[n:]``: 1 when ``G_i x = h_i`` is held). In a control loop the optimum's working set
    rarely changes from one step to the next, so the previous one is tried first
    (:func:`_warm_start`, one iteration); the method starts from an exact feasible point only when
    that guess fails its exact optimality conditions.
    """
    if w.warm[0] and _warm_start(P, c, A, b, G, h, lb, ub, x, w, out):
        return OK, 1
    code, iterations = _cold_start(P, c, A, b, G, h, lb, ub, x, w, out, full)
    w.warm[0] = code == OK and iterations > 0
    return code, iterations


@kernel(refcount=False)
def _kkt_matrix(
    P: F64, A: F64, G: F64, gwork: NDArray[np.int8], idx: NDArray[np.int64], f: int, K: F64
) -> int:
    """``K = [[P_FF, -A_F^T, G_WF^T], [A_F, 0, 0], [G_WF, 0, 0]]`` for the free variables
    ``idx[:f]`` and the rows ``W`` held in ``gwork``; returns its size ``f + nt + |W|``."""
    nt = A.shape[0]
    nw = 0
    for i in range(G.shape[0]):
        nw += gwork[i]
    size = f + nt + nw
    for r in range(size):
        for cc in range(size):
            K[r, cc] = 0.0
    for a in range(f):
        j = idx[a]
        for a2 in range(f):
            K[a, a2] = P[j, idx[a2]]
        for i in range(nt):
            K[a, f + i] = -A[i, j]
            K[f + i, a] = A[i, j]
        r = f + nt
        for i in range(G.shape[0]):
            if gwork[i]:
                K[a, r] = G[i, j]
                K[r, a] = G[i, j]
                r += 1
    return int(size)


@kernel(refcount=False)
def _kkt_solve(
    P: F64,
    A: F64,
    G: F64,
    gwork: NDArray[np.int8],
    idx: NDArray[np.int64],
    f: int,
    K: F64,
    rhs: F64,
) -> int:
    """Solve the KKT system of :func:`_kkt_matrix` for ``rhs = [-g_F, r]`` in place: ``rhs``
    becomes ``[x_F, lam, nu]``; returns the system's size, or -1 for a singular one.

    Where ``P_FF`` is diagonal and positive (every objective term of the controllers), by the
    range-space method: with ``D = P_FF``, ``E = [A_F; G_WF]`` and ``y = [lam; -nu]``,
    ``x = D^-1 (E^T y - g)`` and ``E D^-1 E^T y = r + E D^-1 g``, solved through the Householder
    factor ``D^-1/2 E^T = Q [R; 0]`` (never forming ``E D^-1 E^T``, so the accuracy is that of the
    whole system, not its square). About a third of the work of Gaussian elimination on the
    whole matrix (docs/mathematics.md, "The active-set method"). Otherwise the whole matrix by
    Gaussian elimination with partial pivoting."""
    nt = A.shape[0]
    nw = 0
    for i in range(G.shape[0]):
        nw += gwork[i]
    m = nt + nw
    size = f + m
    diagonal = m <= f and max(m, f) + 2 <= K.shape[0]  # and its scratch fits in K (below)
    for a in range(f):
        if not diagonal:
            break
        ja = idx[a]
        if not P[ja, ja] > 0.0:
            diagonal = False
        for a2 in range(f):
            if a2 != a and P[ja, idx[a2]] != 0.0:
                diagonal = False
    if not diagonal:
        size = _kkt_matrix(P, A, G, gwork, idx, f, K)
        return size if solve_in_place(K, rhs, size) else -1
    # K[:m, :f] = E D^-1/2 (row k: the k-th column of D^-1/2 E^T, then its reflector);
    # K[k, f] = R_kk, K[k, f + 1] = v^T v of reflector k; row m: sqrt(D); row m + 1: D^-1/2 g,
    # then Q^T D^-1/2 g, then -Q^T z
    sd, gt = K[m], K[m + 1]
    for a in range(f):
        sd[a] = math.sqrt(P[idx[a], idx[a]])
        gt[a] = -rhs[a] / sd[a]
    for k in range(nt):
        for a in range(f):
            K[k, a] = A[k, idx[a]] / sd[a]
    r = nt
    for i in range(G.shape[0]):
        if gwork[i]:
            for a in range(f):
                K[r, a] = G[i, idx[a]] / sd[a]
            r += 1
    for k in range(m):
        norm2 = 0.0
        for a in range(k, f):
            norm2 += K[k, a] * K[k, a]
        if norm2 == 0.0 or not math.isfinite(norm2):
            return -1
        x0 = K[k, k]
        alpha = -math.sqrt(norm2) if x0 >= 0.0 else math.sqrt(norm2)
        v0 = x0 - alpha
        K[k, k] = v0
        vv = norm2 - x0 * x0 + v0 * v0
        K[k, f], K[k, f + 1] = alpha, vv
        for row in range(k + 1, m + 2):
            if row == m:
                continue  # sqrt(D)
            acc = 0.0
            for a in range(k, f):
                acc += K[k, a] * K[row, a]
            acc = 2.0 * acc / vv
            for a in range(k, f):
                K[row, a] -= acc * K[k, a]
    # R^T u = r (R[i, k] = K[k, i] above the diagonal), u into rhs[f:]
    for k in range(m):
        acc = rhs[f + k]
        for i in range(k):
            acc -= K[k, i] * rhs[f + i]
        rhs[f + k] = acc / K[k, f]
    # R y = u + (Q^T g~)[:m] in place of gt[:m]
    for k in range(m - 1, -1, -1):
        acc = rhs[f + k] + gt[k]
        for j in range(k + 1, m):
            acc -= K[j, k] * gt[j]
        gt[k] = acc / K[k, f]
    for k in range(m):  # y out, -z~ = [-u, (Q^T g~)[m:]] in
        rhs[f + k], gt[k] = gt[k], -rhs[f + k]
    for k in range(m - 1, -1, -1):  # -z = Q (-z~)
        acc = 0.0
        for a in range(k, f):
            acc += K[k, a] * gt[a]
        acc = 2.0 * acc / K[k, f + 1]
        for a in range(k, f):
            gt[a] -= acc * K[k, a]
    for a in range(f):
        rhs[a] = -gt[a] / sd[a]
    for k in range(nt, m):
        rhs[f + k] = -rhs[f + k]
    return int(size)


@kernel(refcount=False, internal=True)
def _row_value(G: F64, i: int, x: F64) -> float:
    acc = 0.0
    for j in range(x.size):
        acc += G[i, j] * x[j]
    return acc


@kernel(refcount=False, internal=True)
def _independent(
    A: F64, G: F64, gwork: NDArray[np.int8], extra: int, free: NDArray[np.bool_], w: QPWork
) -> bool:
    """True when the working rows restricted to the free variables, ``[A_F; G_WF]`` plus row
    ``extra`` of ``G`` (if ``>= 0``), are linearly independent: Gaussian elimination with complete
    pivoting on a copy, a pivot counting when above ``RANK_TOL`` times the largest entry times the
    row count. Without inequality rows this is :func:`emdm.core.kernels.free_rank`'s test."""
    if G.shape[0] == 0:
        return bool(free_rank(A, free, w.feas) == A.shape[0])
    nt, n = A.shape
    M = w.K  # free between two KKT solves: (n + nt + ng)^2 >= (nt + ng) x n
    rows = 0
    for i in range(nt + G.shape[0]):
        if i < nt:
            src, gi = A, i
        else:
            gi = i - nt
            if not (gwork[gi] or gi == extra):
                continue
            src = G
        cols = 0
        for j in range(n):
            if free[j]:
                M[rows, cols] = src[gi, j]
                cols += 1
        rows += 1
    cols = 0
    big = 0.0
    for j in range(n):
        if free[j]:
            cols += 1
    if rows > cols:
        return False
    for r in range(rows):
        for cc in range(cols):
            big = max(big, abs(M[r, cc]))
    if big <= 0:
        return rows == 0
    return matrix_rank(M, rows, cols, RANK_TOL * big * rows) == rows


@kernel(refcount=False, internal=True)
def _warm_start(
    P: F64, c: F64, A: F64, b: F64, G: F64, h: F64, lb: F64, ub: F64, x: F64, w: QPWork, out: F64
) -> bool:
    """Solve the equality-constrained program with the bounds of ``w.work`` and the rows of
    ``w.work[n:]`` held, and accept its answer only where it is the optimum: every other variable
    within its bounds and every other row kept, every held bound's and row's multiplier of the
    right sign (the tolerances of the cold method), KKT residuals within :data:`KKT_TOL`. ``x``
    is overwritten either way."""
    n = x.size
    nt = A.shape[0]
    ng = G.shape[0]
    work, gwork, snap, idx, K, rhs, lam, mu, nu = (
        w.work,
        w.work[n:],
        w.snap,
        w.idx,
        w.K,
        w.rhs,
        w.lam,
        w.mu,
        w.lam[nt:],
    )
    f = 0
    for j in range(n):
        a = abs(lb[j]) if math.isfinite(lb[j]) else 0.0
        bb = abs(ub[j]) if math.isfinite(ub[j]) else 0.0
        snap[j] = 1e-13 * (1.0 + max(a, bb))
        if work[j] == -1:
            if not math.isfinite(lb[j]):
                return False
            x[j] = lb[j]
        elif work[j] == 1:
            if not math.isfinite(ub[j]):
                return False
            x[j] = ub[j]
        else:
            idx[f] = j
            f += 1
    nw = 0
    for i in range(ng):
        nw += gwork[i]
    size = f + nt + nw
    if f < size - f:
        return False
    for i in range(nt):
        acc = b[i]
        for j in range(n):
            if work[j] != 0:
                acc -= A[i, j] * x[j]
        rhs[f + i] = acc
    r = f + nt
    for i in range(ng):
        if gwork[i]:
            acc = h[i]
            for j in range(n):
                if work[j] != 0:
                    acc -= G[i, j] * x[j]
            rhs[r] = acc
            r += 1
    for a in range(f):
        j = idx[a]
        acc = c[j]
        for i in range(n):
            if work[i] != 0:
                acc += P[j, i] * x[i]
        rhs[a] = -acc
    if _kkt_solve(P, A, G, gwork, idx, f, K, rhs) < 0:
        return False
    for a in range(f):
        j = idx[a]
        v = rhs[a]
        if not math.isfinite(v):
            return False
        if v < lb[j]:
            if lb[j] - v > snap[j]:
                return False
            v = lb[j]
        elif v > ub[j]:
            if v - ub[j] > snap[j]:
                return False
            v = ub[j]
        x[j] = v
    for i in range(nt):
        lam[i] = rhs[f + i]
    r = f + nt
    for i in range(ng):
        if gwork[i]:
            nu[i] = rhs[r]
            r += 1
        else:
            nu[i] = 0.0
            if _row_value(G, i, x) - h[i] > 1e-13 * (1.0 + abs(h[i])):
                return False
    gmax = 0.0
    for j in range(n):
        acc = c[j]
        for i in range(n):
            acc += P[j, i] * x[i]
        gmax = max(gmax, abs(acc))
        if work[j] != 0:
            for i in range(nt):
                acc -= A[i, j] * lam[i]
            for i in range(ng):
                acc += G[i, j] * nu[i]
            mu[j] = acc
        else:
            mu[j] = 0.0
    tol = 1e-12 * (1.0 + gmax)
    for j in range(n):
        if (work[j] == -1 and mu[j] < -tol) or (work[j] == 1 and mu[j] > tol):
            return False
    for i in range(ng):
        if nu[i] < -tol:
            return False
    kkt_residuals(P, c, A, b, G, h, lb, ub, x, lam, mu, nu, out)
    return bool(max(out[0], out[1], out[2]) <= KKT_TOL and out[3] <= BOUND_TOL)


@kernel(refcount=False, internal=True)
def _row_active(G: F64, h: F64, i: int, x: F64) -> bool:
    return bool(h[i] - _row_value(G, i, x) <= ACTIVE_TOL * (1.0 + abs(h[i])))


@kernel(refcount=False, internal=True)
def _cold_start(
    P: F64,
    c: F64,
    A: F64,
    b: F64,
    G: F64,
    h: F64,
    lb: F64,
    ub: F64,
    x: F64,
    w: QPWork,
    out: F64,
    full: Any,
) -> tuple[int, int]:
    """The primal active-set method from an exact feasible point (see :func:`active_set`)."""
    free = w.feas.free
    n = x.size
    nt = A.shape[0]
    ng = G.shape[0]
    work, gwork, snap, g, p, idx, K, rhs, lam, mu, nu = (
        w.work,
        w.work[n:],
        w.snap,
        w.g,
        w.p,
        w.idx,
        w.K,
        w.rhs,
        w.lam,
        w.mu,
        w.lam[nt:],
    )
    if full is None:  # two task rows, no inequality row: feasible_point_rows' first case
        code, unique = feasible_point(A, b, lb, ub, x, w.feas)
    else:
        code, unique = feasible_point_rows(A, b, G, h, lb, ub, x, w.feas)
    if code != OK:
        return code, 0
    if unique:  # the (scaled) task leaves one feasible point: it is the optimum
        # the trace's working set: the bounds the point sits on
        if full is not None and w.trace.shape[0]:
            for j in range(n):
                work[j] = -1 if x[j] == lb[j] else (1 if x[j] == ub[j] else 0)
            for i in range(ng):
                work[n + i] = 0
            _trace(P, c, x, 0.0, w, 0)
        certify(P, c, A, b, G, h, lb, ub, x, w, out)
        if max(out[0], out[1], out[2]) <= KKT_TOL and out[3] <= BOUND_TOL:
            return OK, 0
        return NEEDS_REFERENCE, 0  # a degenerate zonotope (parallel columns) fooled the test
    for j in range(n):
        a = abs(lb[j]) if math.isfinite(lb[j]) else 0.0
        bb = abs(ub[j]) if math.isfinite(ub[j]) else 0.0
        snap[j] = 1e-13 * (1.0 + max(a, bb))
        work[j] = 0
        free[j] = True
    for i in range(ng):
        gwork[i] = 0
        nu[i] = 0.0
    for j in range(n):
        at_lo = x[j] - lb[j] <= snap[j]
        at_hi = ub[j] - x[j] <= snap[j]
        if at_lo:
            x[j] = lb[j]
        elif at_hi:
            x[j] = ub[j]
        if at_lo or at_hi:
            free[j] = False
            if full is None or ng == 0:
                holds = free_rank(A, free, w.feas) == nt
            else:
                holds = _independent(A, G, gwork, -1, free, w)
            if holds:
                work[j] = -1 if at_lo else 1
            else:
                free[j] = True
    if full is not None:
        for i in range(ng):
            if _row_active(G, h, i, x) and _independent(A, G, gwork, i, free, w):
                gwork[i] = 1
    limit = w.limit[0] if w.limit[0] > 0 else 10 * (n + ng + 2) + 20
    zero_step = False
    for iteration in range(1, limit + 1):
        f = 0
        for j in range(n):
            acc = c[j]
            for i in range(n):
                acc += P[j, i] * x[i]
            g[j] = acc
            p[j] = 0.0
            if work[j] == 0:
                idx[f] = j
                f += 1
        nw = 0
        for i in range(ng):
            nw += gwork[i]
        if f == 2 and nt == 2 and nw == 0:  # no null space: p = 0, A_F^T lam = g_F
            i0, i1 = idx[0], idx[1]
            det = A[0, i0] * A[1, i1] - A[1, i0] * A[0, i1]
            size = math.hypot(A[0, i0], A[1, i0]) * math.hypot(A[0, i1], A[1, i1])
            if abs(det) <= RANK_TOL * size:  # dependent task rows: the numpy method's case
                return NEEDS_REFERENCE, iteration
            lam[0] = (g[i0] * A[1, i1] - g[i1] * A[1, i0]) / det
            lam[1] = (A[0, i0] * g[i1] - A[0, i1] * g[i0]) / det
        else:
            size = f + nt + nw
            for a in range(f):
                rhs[a] = -g[idx[a]]
            for i in range(f, size):
                rhs[i] = 0.0
            if _kkt_solve(P, A, G, gwork, idx, f, K, rhs) < 0:
                return NEEDS_REFERENCE, iteration
            for a in range(f):
                p[idx[a]] = rhs[a]
            for i in range(nt):
                lam[i] = rhs[f + i]
            r = f + nt
            for i in range(ng):
                if gwork[i]:
                    nu[i] = rhs[r]
                    r += 1
                else:
                    nu[i] = 0.0
        pmax = xmax = 0.0
        for j in range(n):
            pmax = max(pmax, abs(p[j]))
            xmax = max(xmax, abs(x[j]))
        finite = math.isfinite(pmax)
        for i in range(nt):
            finite = finite and math.isfinite(lam[i])
        for i in range(ng):
            finite = finite and math.isfinite(nu[i])
        if not finite:
            return NEEDS_REFERENCE, iteration
        if full is not None and w.trace.shape[0]:
            _trace(P, c, x, pmax, w, iteration - 1)
        if pmax <= 1e-12 * (1.0 + xmax):
            gmax = 0.0
            for j in range(n):
                gmax = max(gmax, abs(g[j]))
            tol = 1e-12 * (1.0 + gmax)
            worst, drop, first = tol, -1, -1
            for j in range(n):
                mu[j] = 0.0
                if work[j] != 0:
                    acc = g[j]
                    for i in range(nt):
                        acc -= A[i, j] * lam[i]
                    for i in range(ng):
                        acc += G[i, j] * nu[i]
                    mu[j] = acc
                    wrong = -mu[j] if work[j] == -1 else mu[j]
                    if wrong > tol and first < 0:
                        first = j
                    if wrong > worst:
                        worst, drop = wrong, j
            for i in range(ng):
                if gwork[i]:
                    wrong = -nu[i]
                    if wrong > tol and first < 0:
                        first = n + i
                    if wrong > worst:
                        worst, drop = wrong, n + i
            if drop < 0:
                kkt_residuals(P, c, A, b, G, h, lb, ub, x, lam, mu, nu, out)
                return OK, iteration
            # a bound or row active at x outside the working set makes the vertex degenerate:
            # the multipliers are not unique, and the certificate settles optimality over all
            degenerate = False
            for j in range(n):
                if work[j] == 0 and (
                    (math.isfinite(lb[j]) and x[j] - lb[j] <= ACTIVE_TOL * (1.0 + abs(lb[j])))
                    or (math.isfinite(ub[j]) and ub[j] - x[j] <= ACTIVE_TOL * (1.0 + abs(ub[j])))
                ):
                    degenerate = True
            if full is not None:
                for i in range(ng):
                    if gwork[i] == 0 and _row_active(G, h, i, x):
                        degenerate = True
            if degenerate:
                certify(P, c, A, b, G, h, lb, ub, x, w, out)
                if max(out[0], out[1], out[2]) <= KKT_TOL and out[3] <= BOUND_TOL:
                    return OK, iteration
            leave = first if zero_step else drop
            if leave < n:
                work[leave] = 0
            else:
                gwork[leave - n] = 0
            continue
        while True:
            step = 1.0
            block = -1
            for j in range(n):
                if work[j] != 0 or abs(p[j]) <= 1e-13 * pmax:
                    continue
                r = (lb[j] - x[j]) / p[j] if p[j] < 0 else (ub[j] - x[j]) / p[j]
                if r < step:
                    step, block = r, j
            for i in range(ng):
                if gwork[i]:
                    continue
                rate = 0.0
                row_size = 0.0
                for j in range(n):
                    rate += G[i, j] * p[j]
                    row_size += abs(G[i, j])
                if rate <= 1e-13 * pmax * row_size:
                    continue
                r = (h[i] - _row_value(G, i, x)) / rate
                if r < step:
                    step, block = r, n + i
            if (
                0 <= block < n
                and step <= 0.0
                and abs(p[block]) <= 1e-9 * pmax
                and not _holdable(A, G, gwork, work, block, free, w, full)
            ):
                # rounding noise of the step on a bound that cannot join the working set (its
                # column depends on the free ones): it would block every step from here on
                p[block] = 0.0
                continue
            break
        step = max(0.0, step)
        for j in range(n):
            x[j] += step * p[j]
            if work[j] == 0 and abs(p[j]) > 1e-13 * pmax:
                if x[j] < lb[j] and lb[j] - x[j] <= snap[j]:
                    x[j] = lb[j]
                elif x[j] > ub[j] and x[j] - ub[j] <= snap[j]:
                    x[j] = ub[j]
        zero_step = step == 0.0
        if 0 <= block < n:
            side = -1 if p[block] < 0 else 1
            x[block] = lb[block] if side < 0 else ub[block]
            if _holdable(A, G, gwork, work, block, free, w, full):
                work[block] = side
        elif full is not None and block >= n:
            for j in range(n):
                free[j] = work[j] == 0
            if _independent(A, G, gwork, block - n, free, w):
                gwork[block - n] = 1
    return MAX_ITER_EXCEEDED, limit


@kernel(refcount=False, internal=True)
def _holdable(
    A: F64,
    G: F64,
    gwork: NDArray[np.int8],
    work: NDArray[np.int8],
    j: int,
    free: NDArray[np.bool_],
    w: QPWork,
    full: Any,
) -> bool:
    """Whether bound ``j`` can join the working set: the free columns left keep the task rows
    (and the rows held) independent. Overwrites ``free``."""
    for i in range(work.size - gwork.size):
        free[i] = work[i] == 0 and i != j
    if full is None or G.shape[0] == 0:
        return bool(free_rank(A, free, w.feas) == A.shape[0])
    return bool(_independent(A, G, gwork, -1, free, w))


@kernel(refcount=False, internal=True)
def _trace(P: F64, c: F64, x: F64, step: float, w: QPWork, row: int) -> None:
    """Row ``row`` of the lab's trace: objective at ``x``, the step's largest component, the
    working set's size (bounds and rows held)."""
    if row >= w.trace.shape[0]:
        return
    n = x.size
    f = 0.0
    for j in range(n):
        acc = 0.5 * P[j, j] * x[j] + c[j]
        for i in range(j):
            acc += P[j, i] * x[i]
        f += acc * x[j]
    held = 0
    for j in range(w.work.size):
        held += w.work[j] != 0
    w.trace[row, 0] = f
    w.trace[row, 1] = step
    w.trace[row, 2] = held


@kernel
def active_set_of(
    P: F64, c: F64, A: F64, b: F64, G: F64, h: F64, lb: F64, ub: F64, x: F64, out: F64
) -> tuple[int, int]:
    """:func:`active_set` with its own buffers (the entry point for callers in Python)."""
    w = qp_work(x.size, A.shape[0], G.shape[0])
    return active_set(P, c, A, b, G, h, lb, ub, x, w, out, True)


@kernel
def active_set_traced(
    P: F64,
    c: F64,
    A: F64,
    b: F64,
    G: F64,
    h: F64,
    lb: F64,
    ub: F64,
    x: F64,
    out: F64,
    trace_rows: int,
    max_iter: int,
) -> tuple[int, int, F64]:
    """:func:`active_set` from a cold start with an iteration limit (``max_iter`` > 0) and a trace
    of ``trace_rows`` iterations (NaN past the last): the solver lab's entry point."""
    w = qp_work(x.size, A.shape[0], G.shape[0], trace_rows)
    w.limit[0] = max_iter
    code, iterations = active_set(P, c, A, b, G, h, lb, ub, x, w, out, True)
    return code, iterations, w.trace
