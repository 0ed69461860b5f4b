"""The compiled KKT certificate: residuals and the best sign-feasible multipliers of any point.

Programs have the form ``min 1/2 x^T P x + c^T x  s.t.  A x = b (nt rows), G x <= h (ng rows),
lb <= x <= ub``. :func:`kkt_residuals` measures how far ``(x, lam, mu, nu)`` is from the KKT
conditions

    P x + c = A^T lam + mu - G^T nu,   A x = b,   G x <= h,   lb <= x <= ub,
    mu_j >= 0 only where x_j = lb_j,   mu_j <= 0 only where x_j = ub_j,
    nu_i >= 0, and nu_i > 0 only where G_i x = h_i,

with residuals relative to the size of the gradient ``P x + c`` (stationarity, complementarity)
and of ``|A| |x|`` (equality). The multipliers do not enter the scale: huge multipliers, the mark
of a rank-deficient task, must not make a wrong point look stationary. :func:`best_multipliers`
finds, for any ``x``, the sign-feasible multipliers over the bounds and rows active at ``x`` that
fit stationarity best (non-negative least squares, Lawson-Hanson), so a solver's answer can be
certified without trusting anything the solver says. For a strictly convex QP, small residuals
prove ``x`` the unique optimum, whoever found it. The buffers :class:`QPWork` serve the
certificate and the active set (:mod:`emdm.solvers.kernels`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..core.jit import kernel
from ..core.tolerances import ACTIVE_TOL
from ..core.zonotope import FeasWork, feas_work

F64 = NDArray[np.float64]


class QPWork(NamedTuple):
    """Scratch buffers of the solver kernels for programs of ``nx`` variables, ``nt`` equality and
    ``ng`` inequality rows. ``lam`` holds the task rows' multipliers, then the inequality rows'
    (``nu = lam[nt:]``); ``work`` the working set's bounds (-1 / +1 per variable), then its rows
    (1 when held). The rows add no array: a kernel call pays for every array it is passed.
    ``trace`` (one row per iteration: objective, largest step component, working-set size) and
    ``limit`` (an iteration limit when positive) serve the solver lab; the control loop leaves
    them empty and 0."""

    feas: FeasWork
    work: NDArray[np.int8]
    snap: F64
    g: F64
    p: F64
    idx: NDArray[np.int64]
    K: F64
    rhs: F64
    lam: F64
    mu: F64
    M: F64
    z: F64
    s: F64
    w: F64
    r: F64
    passive: NDArray[np.bool_]
    skip: NDArray[np.bool_]
    B: F64
    warm: NDArray[np.bool_]
    trace: F64
    limit: NDArray[np.int64]


@kernel
def qp_work(nx: int, nt: int, ng: int, trace_rows: int = 0) -> QPWork:
    """Buffers for programs with ``nx`` variables, ``nt`` equality and ``ng`` inequality rows
    (and ``trace_rows`` iterations of trace, filled with NaN)."""
    cols = 2 * nt + 2 * nx + ng
    size = nx + nt + ng
    return QPWork(
        feas_work(nx, nt, ng),  # compiled here; a Python caller of qp_work.py_func gets it boxed
        np.zeros(nx + ng, dtype=np.int8),
        np.empty(nx),
        np.empty(nx),
        np.empty(nx),
        np.empty(nx, dtype=np.int64),
        np.empty((size, size)),
        np.empty(size),
        np.zeros(nt + ng),
        np.empty(nx),
        np.empty((nx, cols)),
        np.empty(cols),
        np.empty(cols),
        np.empty(cols),
        np.empty(nx),
        np.empty(cols, dtype=np.bool_),
        np.empty(cols, dtype=np.bool_),
        np.empty((nx, cols + 1)),
        np.zeros(1, dtype=np.bool_),  # work holds the last optimum's working set
        np.full((trace_rows, 3), np.nan),
        np.zeros(1, dtype=np.int64),
    )


@kernel(refcount=False, internal=True)
def kkt_residuals(
    P: F64,
    c: F64,
    A: F64,
    b: F64,
    G: F64,
    h: F64,
    lb: F64,
    ub: F64,
    x: F64,
    lam: F64,
    mu: F64,
    nu: F64,
    out: F64,
) -> None:
    """``out = (stationarity, equality, complementarity, bound excess)`` of ``(x, lam, mu, nu)``.

    ``mu`` is signed (``> 0``: multiplier of the lower bound, ``< 0``: of the upper bound); ``nu``
    are the multipliers of the rows ``G x <= h`` (``>= 0``). A multiplier of a bound that does not
    exist, or a negative ``nu``, counts in full as complementarity (dual infeasible). The bound
    excess covers the rows: ``max(lb - x, x - ub, G x - h)``.
    """
    n = x.size
    nt = A.shape[0]
    ng = G.shape[0]
    scale_g = 1.0
    stat = 0.0
    comp = 0.0
    for j in range(n):
        px = 0.0
        for i in range(n):
            px += P[j, i] * x[i]
        residual = px + c[j]
        for i in range(nt):
            residual -= A[i, j] * lam[i]
        for i in range(ng):
            residual += G[i, j] * nu[i]
        scale_g = max(scale_g, abs(px), abs(c[j]))
        stat = max(stat, abs(residual - mu[j]))
        if mu[j] > 0:
            gap = x[j] - lb[j] if math.isfinite(lb[j]) else math.inf
        elif mu[j] < 0:
            gap = ub[j] - x[j] if math.isfinite(ub[j]) else math.inf
        else:
            gap = 0.0
        if gap == math.inf:
            comp = max(comp, abs(mu[j]))
        else:
            comp = max(comp, abs(mu[j] * gap))
    scale_eq = 1.0
    eq = 0.0
    excess = 0.0
    for i in range(nt):
        ax = 0.0
        aax = 0.0
        for j in range(n):
            ax += A[i, j] * x[j]
            aax += abs(A[i, j]) * abs(x[j])
        scale_eq = max(scale_eq, abs(b[i]), aax)
        eq = max(eq, abs(ax - b[i]))
    for j in range(n):
        excess = max(excess, lb[j] - x[j], x[j] - ub[j])
    for i in range(ng):
        gx = 0.0
        for j in range(n):
            gx += G[i, j] * x[j]
        excess = max(excess, gx - h[i])
        if nu[i] < 0:
            comp = max(comp, abs(nu[i]))
        else:
            comp = max(comp, nu[i] * max(h[i] - gx, 0.0))
    out[0] = stat / scale_g
    out[1] = eq / scale_eq
    out[2] = comp / scale_g
    out[3] = excess


@kernel(refcount=False, internal=True)
def _least_squares(M: F64, passive: NDArray[np.bool_], d: F64, s: F64, B: F64) -> bool:
    """``s`` = least-squares coefficients of the passive columns of ``M`` for ``d`` (0 elsewhere),
    by Householder QR. False when the passive columns are numerically dependent."""
    n, cols = M.shape
    p = 0
    for j in range(cols):
        s[j] = 0.0
        if passive[j]:
            for i in range(n):
                B[i, p] = M[i, j]
            p += 1
    for i in range(n):
        B[i, p] = d[i]
    big = 0.0
    for k in range(p):
        norm = 0.0
        for i in range(k, n):
            norm += B[i, k] * B[i, k]
        norm = math.sqrt(norm)
        big = max(big, norm)
        if norm <= 1e-13 * max(big, 1e-300) or k >= n:
            return False
        alpha = -norm if B[k, k] >= 0 else norm
        v0 = B[k, k] - alpha
        vnorm2 = v0 * v0
        for i in range(k + 1, n):
            vnorm2 += B[i, k] * B[i, k]
        B[k, k] = alpha
        if vnorm2 == 0.0:
            continue
        for col in range(k + 1, p + 1):
            dot = v0 * B[k, col]
            for i in range(k + 1, n):
                dot += B[i, k] * B[i, col]
            f = 2.0 * dot / vnorm2
            B[k, col] -= f * v0
            for i in range(k + 1, n):
                B[i, col] -= f * B[i, k]
        for i in range(k + 1, n):
            B[i, k] = 0.0
    # back substitution R coef = (Q^T d)[:p]
    for k in range(p - 1, -1, -1):
        acc = B[k, p]
        for col in range(k + 1, p):
            acc -= B[k, col] * B[col, p]
        B[k, p] = acc / B[k, k]
    q = 0
    for j in range(cols):
        if passive[j]:
            s[j] = B[q, p]
            q += 1
    return True


@kernel(refcount=False, internal=True)
def best_multipliers(
    P: F64,
    c: F64,
    A: F64,
    G: F64,
    h: F64,
    lb: F64,
    ub: F64,
    x: F64,
    lam: F64,
    mu: F64,
    nu: F64,
    w: QPWork,
) -> None:
    """Sign-feasible ``(lam, mu, nu)`` over the bounds and rows active at ``x`` that fit
    ``P x + c`` best.

    Non-negative least squares (Lawson and Hanson) on the columns ``[A^T, -A^T, e_lo, -e_hi,
    -G_a^T]`` (``lam = lam+ - lam-``, one pair of columns per task row; one column per active
    inequality row), the same problem as the reference certificate of the tests.
    """
    n = x.size
    nt = A.shape[0]
    M, z, s, wv, r, passive, B, g = w.M, w.z, w.s, w.w, w.r, w.passive, w.B, w.g
    skip = w.skip
    for j in range(n):
        acc = c[j]
        for i in range(n):
            acc += P[j, i] * x[i]
        g[j] = acc
    cols = 2 * nt
    for j in range(n):
        for k in range(M.shape[1]):
            M[j, k] = 0.0
        for i in range(nt):
            M[j, i], M[j, nt + i] = A[i, j], -A[i, j]
    for j in range(n):
        if math.isfinite(lb[j]) and x[j] - lb[j] <= ACTIVE_TOL * (1.0 + abs(lb[j])):
            M[j, cols] = 1.0
            cols += 1
    for j in range(n):
        if math.isfinite(ub[j]) and ub[j] - x[j] <= ACTIVE_TOL * (1.0 + abs(ub[j])):
            M[j, cols] = -1.0
            cols += 1
    nbounds = cols
    for i in range(G.shape[0]):
        nu[i] = 0.0
        gx = 0.0
        for j in range(n):
            gx += G[i, j] * x[j]
        if h[i] - gx <= ACTIVE_TOL * (1.0 + abs(h[i])):
            for j in range(n):
                M[j, cols] = -G[i, j]
            cols += 1
    Mv = M[:, :cols]
    zv, sv, wvv, pv = z[:cols], s[:cols], wv[:cols], passive[:cols]
    gnorm = 0.0
    colmax = 0.0
    for j in range(n):
        gnorm = max(gnorm, abs(g[j]))
        for k in range(cols):
            colmax = max(colmax, abs(Mv[j, k]))
    tol = 1e-14 * (1.0 + colmax * gnorm) * n
    for k in range(cols):
        zv[k] = 0.0
        pv[k] = False
        skip[k] = False
    for j in range(n):
        r[j] = g[j]
    for _ in range(3 * cols):
        best, t = tol, -1
        for k in range(cols):
            if not pv[k] and not skip[k]:
                acc = 0.0
                for j in range(n):
                    acc += Mv[j, k] * r[j]
                wvv[k] = acc
                if acc > best:
                    best, t = acc, k
        if t < 0:
            break
        pv[t] = True
        for _inner in range(3 * cols):
            if not _least_squares(Mv, pv, g, sv, B):
                pv[t] = False
                break
            smallest = math.inf
            for k in range(cols):
                if pv[k]:
                    smallest = min(smallest, sv[k])
            if smallest > 0:
                for k in range(cols):
                    zv[k] = sv[k]
                break
            alpha, leaving = 1.0, -1
            for k in range(cols):
                if pv[k] and sv[k] <= 0:
                    step = zv[k] / (zv[k] - sv[k])
                    if step < alpha or leaving < 0:
                        alpha, leaving = min(alpha, step), k
            largest = 0.0
            for k in range(cols):
                zv[k] += alpha * (sv[k] - zv[k])
                largest = max(largest, abs(zv[k]))
            for k in range(cols):  # the blocking coefficient leaves, and any that became dust
                if pv[k] and (k == leaving or zv[k] <= 1e-15 * largest):
                    pv[k] = False
                    zv[k] = 0.0
        else:
            break
        if not pv[t] and zv[t] == 0.0:
            # the entering column depends on the passive ones: try the next best column (a
            # cone's point is always a non-negative sum of independent generators, Caratheodory)
            skip[t] = True
            continue
        for k in range(cols):
            skip[k] = False
        for j in range(n):
            acc = g[j]
            for k in range(cols):
                acc -= Mv[j, k] * zv[k]
            r[j] = acc
    for i in range(nt):
        lam[i] = zv[i] - zv[nt + i]
    for j in range(n):
        mu[j] = 0.0
    for k in range(2 * nt, nbounds):
        for j in range(n):
            if Mv[j, k] != 0.0:
                mu[j] += Mv[j, k] * zv[k]
    k = nbounds
    for i in range(G.shape[0]):
        if k < cols:
            gx = 0.0
            for j in range(n):
                gx += G[i, j] * x[j]
            if h[i] - gx <= ACTIVE_TOL * (1.0 + abs(h[i])):
                nu[i] = zv[k]
                k += 1


@kernel(refcount=False)
def certify(
    P: F64, c: F64, A: F64, b: F64, G: F64, h: F64, lb: F64, ub: F64, x: F64, w: QPWork, out: F64
) -> None:
    """The KKT residuals of ``x`` with the best sign-feasible multipliers (solver-independent)."""
    nu = w.lam[A.shape[0] :]
    best_multipliers(P, c, A, G, h, lb, ub, x, w.lam, w.mu, nu, w)
    kkt_residuals(P, c, A, b, G, h, lb, ub, x, w.lam, w.mu, nu, out)


@kernel
def multipliers_of(
    P: F64, c: F64, A: F64, b: F64, G: F64, h: F64, lb: F64, ub: F64, x: F64, out: F64
) -> tuple[F64, F64, F64]:
    """:func:`certify` with its own buffers, returning the multipliers ``(lam, mu, nu)`` it
    found (signed ``mu``: > 0 at the lower bound; ``nu >= 0`` of the rows ``G x <= h``)."""
    w = qp_work(x.size, A.shape[0], G.shape[0])
    certify(P, c, A, b, G, h, lb, ub, x, w, out)
    nt = A.shape[0]
    return w.lam[:nt].copy(), w.mu.copy(), w.lam[nt:].copy()


@kernel
def certify_of(
    P: F64, c: F64, A: F64, b: F64, G: F64, h: F64, lb: F64, ub: F64, x: F64, out: F64
) -> None:
    """:func:`certify` with its own buffers (the entry point for callers in Python)."""
    certify(P, c, A, b, G, h, lb, ub, x, qp_work(x.size, A.shape[0], G.shape[0]), out)
