"""The fast path: the control loop compiled with numba, for single runs and batches.

Every kernel here restates, for speed, mathematics whose reference lives elsewhere; the tests
cross-check the two paths to 1e-12 on both presets and on random scenarios:

- ``_kinematics``: :meth:`emdm.arm.PlanarArm.kinematics` (tip vectors, Cauchy-Binet minors);
- ``_bounds``: :func:`emdm.limits.position_damper` intersected with the velocity box;
- ``_program``: :func:`emdm.controllers.step_program` (P is always diagonal here);
- ``_ray_interval``, ``_task_scale``, ``_feasible_point``: :mod:`emdm.feasibility`;
- ``_active_set``: :func:`emdm.solvers.active_set.solve_active_set`.

The loop never trades exactness for speed: whenever a step leaves the cases the kernels handle
(a rank-deficient Jacobian with free variables, a degenerate vertex that needs the full KKT
certificate, the iteration limit, or a policy other than ``scale``), the kernel returns, the
reference path solves that step with its certificate, and the kernel resumes.

Without numba (``pip install 'emdm[fast]'``) the same kernels run as plain Python: correct, slow.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

njit: Any
prange: Any
try:  # pragma: no cover - depends on the installation
    import numba

    njit, prange = numba.njit, numba.prange
    HAVE_NUMBA = True
except ImportError:  # pragma: no cover
    HAVE_NUMBA = False
    prange = range

    def _plain(*args: Any, **kwargs: Any) -> Any:
        """Stand-in for numba.njit: the kernels run as plain Python."""
        if args and callable(args[0]):
            return args[0]
        return lambda f: f

    njit = _plain


SINGULAR_RELATIVE = 1e-14
RANK_TOL = 1e-12
FEASIBILITY_TOL = 1e-10

# codes a kernel returns
OK, NEEDS_REFERENCE, INFEASIBLE = 0, 1, 2


# ------------------------------------------------------------------------------ workspace
@njit(cache=True)
def _workspace(n, nx):
    """Every buffer a run needs, allocated once: the step loop allocates nothing (threads scale)."""
    npairs = n * (n - 1) // 2
    return (
        np.empty(n),
        np.empty(n),
        np.empty(npairs),
        np.empty((npairs, n)),
        np.empty((4 * (nx + 3), 2)),
        np.empty((nx + 3, 2)),
        np.empty(nx, dtype=np.bool_),
        np.empty(nx, dtype=np.bool_),
        np.empty(nx),
        np.empty(nx, dtype=np.int8),
        np.empty(nx),
        np.empty(nx),
        np.empty(nx),
        np.empty(nx, dtype=np.int64),
        np.empty((nx + 2, nx + 2)),
        np.empty(nx + 2),
    )


# ------------------------------------------------------------------------------ kinematics
@njit(cache=True)
def _kinematics(lengths, q, p, J, Jm, rx, ry, minors, G):
    """p, J, Jm in place; returns m (see emdm.arm)."""
    n = q.size
    th = 0.0
    for i in range(n):
        th += q[i]
        rx[i] = lengths[i] * math.cos(th)
        ry[i] = lengths[i] * math.sin(th)
    for i in range(n - 2, -1, -1):
        rx[i] += rx[i + 1]
        ry[i] += ry[i + 1]
    p[0] = rx[0]
    p[1] = ry[0]
    for j in range(n):
        J[0, j] = -ry[j]
        J[1, j] = rx[j]
    npairs = n * (n - 1) // 2
    k = 0
    m2 = 0.0
    for i in range(n):
        for kk in range(i + 1, n):
            c = rx[i] * ry[kk] - ry[i] * rx[kk]
            minors[k] = c
            m2 += c * c
            k += 1
    m = math.sqrt(m2)
    total = 0.0
    for i in range(n):
        total += lengths[i]
    k = 0
    for i in range(n):
        for kk in range(i + 1, n):
            for j in range(n):
                a = kk if kk > j else j
                b = i if i > j else j
                G[k, j] = (rx[i] * rx[a] + ry[i] * ry[a]) - (rx[b] * rx[kk] + ry[b] * ry[kk])
            k += 1
    if m > SINGULAR_RELATIVE * total * total:
        for j in range(n):
            s = 0.0
            for k in range(npairs):
                s += G[k, j] * minors[k]
            Jm[j] = s / m
    else:  # steepest one-sided ascent (emdm.arm._steepest_ascent); rare, may allocate
        _, sv, vt = np.linalg.svd(G)
        if sv[0] == 0.0:
            for j in range(n):
                Jm[j] = 0.0
        else:
            big = 0
            for j in range(n):
                if abs(vt[0, j]) > abs(vt[0, big]):
                    big = j
            sign = 1.0 if vt[0, big] >= 0 else -1.0
            for j in range(n):
                Jm[j] = sign * sv[0] * vt[0, j] + 0.0
    return m


# ------------------------------------------------------------------------------ the program
@njit(cache=True)
def _bounds(q, qmin, qmax, qdmin, qdmax, infl, stop, gain, lo, hi):
    for j in range(q.size):
        d_up = qmax[j] - q[j]
        d_dn = q[j] - qmin[j]
        span = gain[j] * (infl[j] - stop[j])
        h = (d_up - stop[j]) / span if d_up < infl[j] else math.inf
        low = -(d_dn - stop[j]) / span if d_dn < infl[j] else -math.inf
        lo[j] = max(qdmin[j], low)
        hi[j] = min(qdmax[j], h)


# ------------------------------------------------------------------------ feasibility (2-D)
@njit(cache=True)
def _ray_interval(G, lb, ub, y0x, y0y, dx, dy, cand, base):
    """(t_lo, t_hi, wx, wy, found): y0 + t d in the zonotope of G over the box (emdm.feasibility)."""
    nb = G.shape[1]
    nbase = 0
    for j in range(nb + 3):
        if j < nb:
            vx, vy = G[0, j], G[1, j]
        elif j == nb:
            vx, vy = 1.0, 0.0
        elif j == nb + 1:
            vx, vy = 0.0, 1.0
        else:
            vx, vy = dx, dy
        norm = math.hypot(vx, vy)
        if norm > 0:
            base[nbase, 0] = vx / norm
            base[nbase, 1] = vy / norm
            nbase += 1
    count = 0
    for j in range(nbase):
        vx, vy = base[j, 0], base[j, 1]
        cand[count, 0], cand[count, 1] = vx, vy
        cand[count + 1, 0], cand[count + 1, 1] = -vy, vx
        cand[count + 2, 0], cand[count + 2, 1] = -vx, -vy
        cand[count + 3, 0], cand[count + 3, 1] = vy, -vx
        count += 4
    size = 1.0 + abs(y0x) + abs(y0y)
    for j in range(nb):
        size += (abs(G[0, j]) + abs(G[1, j])) * max(abs(lb[j]), abs(ub[j]))
    dsum = abs(dx) + abs(dy)
    t_lo, t_hi = -math.inf, math.inf
    bwx, bwy = 0.0, 0.0
    found = False
    for c in range(count):
        wx, wy = cand[c, 0], cand[c, 1]
        h = -(wx * y0x + wy * y0y)
        for j in range(nb):
            s = wx * G[0, j] + wy * G[1, j]
            h += max(s * lb[j], s * ub[j])
        a = wx * dx + wy * dy
        if abs(a) <= 1e-13 * max(dsum, 1e-300):
            if h < -FEASIBILITY_TOL * size:
                return math.inf, -math.inf, 0.0, 0.0, False
        elif a > 0:
            r = h / a
            if r < t_hi:
                t_hi, bwx, bwy, found = r, wx, wy, True
        else:
            r = h / a
            if r > t_lo:
                t_lo = r
    return t_lo, t_hi, bwx, bwy, found


@njit(cache=True)
def _boundary_preimage(G, lb, ub, centre, tx, ty, wx, wy, x, parallel):
    """Fill x; returns how many generators are parallel to the edge (they share its length)."""
    nb = G.shape[1]
    ux, uy = -wy, wx
    rx, ry = tx, ty
    count = 0
    for j in range(nb):
        s = wx * G[0, j] + wy * G[1, j]
        gn = math.hypot(G[0, j], G[1, j])
        parallel[j] = abs(s) <= 1e-12 * max(gn, 1e-300)
        if parallel[j]:
            x[j] = centre[j]
            count += 1
        else:
            x[j] = ub[j] if s > 0 else lb[j]
        rx -= G[0, j] * x[j]
        ry -= G[1, j] * x[j]
    denom = 0.0
    for j in range(nb):
        if parallel[j]:
            denom += abs(ux * G[0, j] + uy * G[1, j]) * 0.5 * (ub[j] - lb[j])
    if denom > 0:
        tau = min(1.0, max(-1.0, (ux * rx + uy * ry) / denom))
        for j in range(nb):
            if parallel[j]:
                gu = ux * G[0, j] + uy * G[1, j]
                sgn = 1.0 if gu > 0 else (-1.0 if gu < 0 else 0.0)
                x[j] += tau * 0.5 * (ub[j] - lb[j]) * sgn
    return count


@njit(cache=True)
def _free_rank(A, free):
    """Rank (0, 1, 2) of the columns of A marked free.

    Rank 2 when some pair of columns has a 2x2 minor above ``RANK_TOL`` times the squared size
    of the columns: minors are exact zero for parallel columns and accurate to rounding
    otherwise (a Gram determinant would drown in rounding at this tolerance).
    """
    n = A.shape[1]
    scale = 0.0
    for j in range(n):
        if free[j]:
            scale += A[0, j] * A[0, j] + A[1, j] * A[1, j]
    if scale <= 0:
        return 0
    for i in range(n):
        if not free[i]:
            continue
        for k in range(i + 1, n):
            if free[k] and abs(A[0, i] * A[1, k] - A[1, i] * A[0, k]) > RANK_TOL * scale:
                return 2
    return 1


@njit(cache=True)
def _mark_free(lb, ub, free):
    count = 0
    for j in range(lb.size):
        free[j] = math.isinf(lb[j]) and math.isinf(ub[j])
        count += free[j]
    return count


@njit(cache=True)
def _task_scale(A, b, lb, ub, free, cand, base):
    """Largest feasible task scale in [0, 1]; -1 when none; -2 when the reference is needed."""
    if _mark_free(lb, ub, free) > 0:
        return 1.0 if _free_rank(A, free) == 2 else -2.0
    t_lo, t_hi, _, _, _ = _ray_interval(A, lb, ub, 0.0, 0.0, b[0], b[1], cand, base)
    lo = max(0.0, t_lo)
    hi = min(1.0, t_hi)
    if hi < lo - 1e-12:
        return -1.0
    return hi if hi >= lo else lo


@njit(cache=True)
def _feasible_point(A, b, lb, ub, x, free, parallel, centre, cand, base):
    """Fill x with a feasible point; returns (OK | INFEASIBLE | NEEDS_REFERENCE, unique).

    ``unique`` is True when b lies on an edge of the zonotope whose preimage is one point (at most
    one generator parallel to the edge): then x is the only feasible point, hence the optimum.
    """
    n = A.shape[1]
    if _mark_free(lb, ub, free) > 0:
        if _free_rank(A, free) != 2:
            return NEEDS_REFERENCE, False
        rx, ry = b[0], b[1]
        g00 = g01 = g11 = 0.0
        for j in range(n):
            if not free[j]:
                x[j] = min(max(0.0, lb[j]), ub[j])
                rx -= A[0, j] * x[j]
                ry -= A[1, j] * x[j]
            else:
                g00 += A[0, j] * A[0, j]
                g01 += A[0, j] * A[1, j]
                g11 += A[1, j] * A[1, j]
        det = g00 * g11 - g01 * g01
        l0 = (g11 * rx - g01 * ry) / det
        l1 = (g00 * ry - g01 * rx) / det
        for j in range(n):
            if free[j]:
                x[j] = A[0, j] * l0 + A[1, j] * l1
        return OK, False
    y0x = y0y = 0.0
    for j in range(n):
        centre[j] = 0.5 * (lb[j] + ub[j])
        x[j] = centre[j]
        y0x += A[0, j] * centre[j]
        y0y += A[1, j] * centre[j]
    dx, dy = b[0] - y0x, b[1] - y0y
    noise = RANK_TOL * (1.0 + max(abs(b[0]), abs(b[1])) + max(abs(y0x), abs(y0y)))
    unique = False
    if max(abs(dx), abs(dy)) > noise:
        t_lo, t_hi, wx, wy, found = _ray_interval(A, lb, ub, y0x, y0y, dx, dy, cand, base)
        if not found or t_hi < 1.0 - 1e-9 or t_lo > t_hi:
            return INFEASIBLE, False
        count = _boundary_preimage(
            A, lb, ub, centre, y0x + t_hi * dx, y0y + t_hi * dy, wx, wy, x, parallel
        )
        unique = t_hi <= 1.0 + 1e-12 and count <= 1
        if t_hi > 1.0:
            for j in range(n):
                x[j] = centre[j] + (x[j] - centre[j]) / t_hi
    amax = xsum = 0.0
    r0, r1 = -b[0], -b[1]
    for j in range(n):
        amax = max(amax, abs(A[0, j]), abs(A[1, j]))
        xsum += abs(x[j])
        r0 += A[0, j] * x[j]
        r1 += A[1, j] * x[j]
    if max(abs(r0), abs(r1)) > FEASIBILITY_TOL * (1.0 + max(abs(b[0]), abs(b[1])) + amax * xsum):
        return INFEASIBLE, False
    return OK, unique


@njit(cache=True)
def _solve_in_place(K, rhs, size):
    """Gaussian elimination with partial pivoting on K[:size, :size]; rhs becomes the solution.
    Returns False for a (numerically) singular matrix."""
    for col in range(size):
        piv = col
        for r in range(col + 1, size):
            if abs(K[r, col]) > abs(K[piv, col]):
                piv = r
        if K[piv, col] == 0.0:
            return False
        if piv != col:
            for c in range(size):
                K[col, c], K[piv, c] = K[piv, c], K[col, c]
            rhs[col], rhs[piv] = rhs[piv], rhs[col]
        for r in range(col + 1, size):
            f = K[r, col] / K[col, col]
            if f != 0.0:
                for c in range(col, size):
                    K[r, c] -= f * K[col, c]
                rhs[r] -= f * rhs[col]
    for r in range(size - 1, -1, -1):
        s = rhs[r]
        for c in range(r + 1, size):
            s -= K[r, c] * rhs[c]
        rhs[r] = s / K[r, r]
    return True


# ---------------------------------------------------------------------------- active set
@njit(cache=True)
def _active_set(Pd, c, A, b, lb, ub, x, ws):
    """Primal active set (emdm.solvers.active_set) for diagonal P; returns (code, iterations)."""
    (_, _, _, _, cand, base, free, parallel, centre, work, snap, g, p, idx, K, rhs) = ws
    n = x.size
    code, unique = _feasible_point(A, b, lb, ub, x, free, parallel, centre, cand, base)
    if code != OK:
        return code, 0
    if unique:  # the scaled task leaves a single feasible point: it is the optimum
        return OK, 0
    for j in range(n):
        a = abs(lb[j]) if math.isfinite(lb[j]) else 0.0
        bb = abs(ub[j]) if math.isfinite(ub[j]) else 0.0
        snap[j] = 1e-13 * (1.0 + max(a, bb))
        work[j] = 0
        free[j] = True
    for j in range(n):
        at_lo = x[j] - lb[j] <= snap[j]
        at_hi = ub[j] - x[j] <= snap[j]
        if at_lo:
            x[j] = lb[j]
        elif at_hi:
            x[j] = ub[j]
        if at_lo or at_hi:
            free[j] = False
            if _free_rank(A, free) == 2:
                work[j] = -1 if at_lo else 1
            else:
                free[j] = True
    limit = 10 * (n + 2) + 20
    zero_step = False
    for iteration in range(1, limit + 1):
        f = 0
        for j in range(n):
            g[j] = Pd[j] * x[j] + c[j]
            p[j] = 0.0
            if work[j] == 0:
                idx[f] = j
                f += 1
        lam0 = lam1 = 0.0
        if f == 2:  # no null space: p = 0, A_F^T lam = g_F
            i0, i1 = idx[0], idx[1]
            det = A[0, i0] * A[1, i1] - A[1, i0] * A[0, i1]
            lam0 = (g[i0] * A[1, i1] - g[i1] * A[1, i0]) / det
            lam1 = (A[0, i0] * g[i1] - A[0, i1] * g[i0]) / det
        else:
            size = f + 2
            for r in range(size):
                rhs[r] = 0.0
                for cc in range(size):
                    K[r, cc] = 0.0
            for a in range(f):
                j = idx[a]
                K[a, a] = Pd[j]
                K[a, f] = -A[0, j]
                K[a, f + 1] = -A[1, j]
                K[f, a] = A[0, j]
                K[f + 1, a] = A[1, j]
                rhs[a] = -g[j]
            if not _solve_in_place(K, rhs, size):
                return NEEDS_REFERENCE, iteration
            for a in range(f):
                p[idx[a]] = rhs[a]
            lam0, lam1 = rhs[f], rhs[f + 1]
        pmax = xmax = 0.0
        for j in range(n):
            pmax = max(pmax, abs(p[j]))
            xmax = max(xmax, abs(x[j]))
        if not (math.isfinite(pmax) and math.isfinite(lam0) and math.isfinite(lam1)):
            return NEEDS_REFERENCE, iteration
        if pmax <= 1e-12 * (1.0 + xmax):
            gmax = 0.0
            for j in range(n):
                gmax = max(gmax, abs(g[j]))
            tol = 1e-12 * (1.0 + gmax)
            worst, drop, first = tol, -1, -1
            for j in range(n):
                if work[j] != 0:
                    mu = g[j] - A[0, j] * lam0 - A[1, j] * lam1
                    wrong = -mu if work[j] == -1 else mu
                    if wrong > tol and first < 0:
                        first = j
                    if wrong > worst:
                        worst, drop = wrong, j
            if drop < 0:
                return OK, iteration
            # a bound active at x but outside the working set: a degenerate vertex, whose
            # optimality needs the full certificate of the reference path
            for j in range(n):
                if work[j] == 0 and (x[j] - lb[j] <= snap[j] or ub[j] - x[j] <= snap[j]):
                    return NEEDS_REFERENCE, iteration
            work[first if zero_step else drop] = 0
            continue
        step = 1.0
        block = -1
        for j in range(n):
            if work[j] != 0 or abs(p[j]) <= 1e-13 * pmax:
                continue
            r = (lb[j] - x[j]) / p[j] if p[j] < 0 else (ub[j] - x[j]) / p[j]
            if r < step:
                step, block = r, j
        step = max(0.0, step)
        for j in range(n):
            x[j] += step * p[j]
            if work[j] == 0 and abs(p[j]) > 1e-13 * pmax:
                if x[j] < lb[j] and lb[j] - x[j] <= snap[j]:
                    x[j] = lb[j]
                elif x[j] > ub[j] and x[j] - ub[j] <= snap[j]:
                    x[j] = ub[j]
        zero_step = step == 0.0
        if block >= 0:
            side = -1 if p[block] < 0 else 1
            x[block] = lb[block] if side < 0 else ub[block]
            for j in range(n):
                free[j] = work[j] == 0 and j != block
            if _free_rank(A, free) == 2:
                work[block] = side
    return NEEDS_REFERENCE, limit


# ---------------------------------------------------------------------------------- the loop
@njit(cache=True)
def _run(
    lengths,
    qmin,
    qmax,
    qdmin,
    qdmax,
    infl,
    stop,
    gain,
    goal,
    kp,
    dt,
    tol,
    n_steps,
    w_e,
    w_m,
    c_s,
    smin,
    smax,
    method_emdm,
    constrained,
    q,
    qd,
    delta,
    alpha,
    m_rec,
    k0,
):
    """Run from state k0 until the goal, the time limit or a step that needs the reference.

    Returns (code, k): code OK with k the final state index (reached when its error < tol), or
    NEEDS_REFERENCE with k the step to hand over.
    """
    n = lengths.size
    slack = method_emdm and n == 2
    nx = n + 2 if slack else n
    ws = _workspace(n, nx)
    rx, ry, minors, G, cand, base, free = ws[0], ws[1], ws[2], ws[3], ws[4], ws[5], ws[6]
    p = np.empty(2)
    J = np.empty((2, n))
    Jm = np.empty(n)
    lo = np.empty(n)
    hi = np.empty(n)
    Pd = np.empty(nx)
    c = np.empty(nx)
    A = np.zeros((2, nx))
    b = np.empty(2)
    lb = np.empty(nx)
    ub = np.empty(nx)
    x = np.empty(nx)
    for k in range(k0, n_steps + 1):
        m_rec[k] = _kinematics(lengths, q[k], p, J, Jm, rx, ry, minors, G)
        ex, ey = goal[0] - p[0], goal[1] - p[1]
        err = math.sqrt(ex * ex + ey * ey)
        if err < tol or k >= n_steps:
            return OK, k
        b[0], b[1] = kp[0] * ex, kp[1] * ey
        if constrained:
            _bounds(q[k], qmin, qmax, qdmin, qdmax, infl, stop, gain, lo, hi)
        else:
            for j in range(n):
                lo[j], hi[j] = -math.inf, math.inf
        for j in range(n):
            A[0, j], A[1, j] = J[0, j], J[1, j]
            lb[j], ub[j] = lo[j], hi[j]
            if method_emdm:
                Pd[j], c[j] = w_e, -w_m * Jm[j]
            else:
                Pd[j], c[j] = 1.0, 0.0
        if slack:
            ws_ = c_s / max(err, 1e-9)
            for i in range(2):
                Pd[n + i], c[n + i] = ws_, 0.0
                A[0, n + i] = 1.0 if i == 0 else 0.0
                A[1, n + i] = 1.0 if i == 1 else 0.0
                lb[n + i], ub[n + i] = smin[i], smax[i]
        a = _task_scale(A, b, lb, ub, free, cand, base)
        if a < 0:  # no feasible scale, or a case for the reference path
            return NEEDS_REFERENCE, k
        b[0] *= a
        b[1] *= a
        code, _ = _active_set(Pd, c, A, b, lb, ub, x, ws)
        if code != OK:
            return NEEDS_REFERENCE, k
        alpha[k] = a
        for j in range(n):
            qd[k, j] = x[j]
            q[k + 1, j] = q[k, j] + x[j] * dt
        if slack:
            delta[k, 0], delta[k, 1] = x[n], x[n + 1]
        else:
            delta[k, 0], delta[k, 1] = 0.0, 0.0
    return OK, n_steps


@njit(cache=True, parallel=True)
def _batch(
    lengths,
    qmin,
    qmax,
    qdmin,
    qdmax,
    infl,
    stop,
    gain,
    goals,
    kp,
    dt,
    tol,
    n_steps,
    w_e,
    w_m,
    c_s,
    smin,
    smax,
    method_emdm,
    constrained,
    q0s,
    out,
):
    """Runs in parallel; ``out[r]`` = steps, reached, time to goal, min m, mean m, total effort,
    final error, max |qd|, code (OK, or NEEDS_REFERENCE: to be finished by run_fast)."""
    runs, n = q0s.shape
    for r in prange(runs):
        q = np.empty((n_steps + 1, n))
        qd = np.empty((n_steps, n))
        delta = np.empty((n_steps, 2))
        alpha = np.empty(n_steps)
        m = np.empty(n_steps + 1)
        for j in range(n):
            q[0, j] = q0s[r, j]
        code, k = _run(
            lengths,
            qmin,
            qmax,
            qdmin,
            qdmax,
            infl,
            stop,
            gain,
            goals[r],
            kp,
            dt,
            tol,
            n_steps,
            w_e,
            w_m,
            c_s,
            smin,
            smax,
            method_emdm,
            constrained,
            q,
            qd,
            delta,
            alpha,
            m,
            0,
        )
        effort = 0.0
        qmax_abs = 0.0
        for i in range(k):
            e = 0.0
            for j in range(n):
                e += qd[i, j] * qd[i, j]
                qmax_abs = max(qmax_abs, abs(qd[i, j]))
            effort += 0.5 * e * dt
        mmin, msum = math.inf, 0.0
        for i in range(k + 1):
            mmin = min(mmin, m[i])
            msum += m[i]
        # final error from the last state's kinematics (recomputed: m[k] came with it)
        th = 0.0
        px = 0.0
        py = 0.0
        for j in range(n):
            th += q[k, j]
            px += lengths[j] * math.cos(th)
            py += lengths[j] * math.sin(th)
        err = math.hypot(goals[r, 0] - px, goals[r, 1] - py)
        out[r, 0] = k
        out[r, 1] = 1.0 if err < tol else 0.0
        out[r, 2] = k * dt if err < tol else math.nan
        out[r, 3] = mmin
        out[r, 4] = msum / (k + 1)
        out[r, 5] = effort
        out[r, 6] = err
        out[r, 7] = qmax_abs
        out[r, 8] = code


# ---------------------------------------------------------------------------- Python side
def _arrays(scenario: Any) -> tuple[Any, ...]:
    arm, mo, w, d = scenario.arm, scenario.motion, scenario.weights, scenario.damper
    return (
        np.asarray(arm.lengths, float),
        np.asarray(arm.q_min, float),
        np.asarray(arm.q_max, float),
        np.asarray(arm.qd_min, float),
        np.asarray(arm.qd_max, float),
        np.asarray(d.influence, float),
        np.asarray(d.stop, float),
        np.asarray(d.gain, float),
        np.asarray(mo.goal, float),
        np.asarray(mo.kp, float),
        float(mo.dt),
        float(mo.tolerance),
        scenario.max_steps,
        float(w.effort),
        float(w.manipulability),
        float(w.slack),
        np.asarray(scenario.slack.min, float),
        np.asarray(scenario.slack.max, float),
    )


def run_fast(scenario: Any, controller: Any) -> dict[str, Any]:
    """One closed-loop run on the fast path: ``q, qd, delta, alpha, m, steps, reached,
    reference_steps`` (the steps the reference path solved)."""
    from ..core.controllers import get_controller, program_at, state_at
    from ..solvers import DEFAULT_FALLBACK, DEFAULT_SOLVER, solve_chain

    ctrl = controller if not isinstance(controller, str) else get_controller(controller)
    n, N = scenario.n, scenario.max_steps
    q = np.empty((N + 1, n))
    q[0] = scenario.motion.q0
    qd, delta = np.zeros((N, n)), np.zeros((N, 2))
    alpha, m = np.ones(N), np.empty(N + 1)
    args = _arrays(scenario)
    emdm_method, constrained = ctrl.method == "EMDM", ctrl.constrained
    policy_scale = scenario.controller.on_infeasible == "scale"
    reference_steps = []
    k = 0
    while True:
        if policy_scale:
            code, k = _run(*args, emdm_method, constrained, q, qd, delta, alpha, m, k)
        else:
            code = NEEDS_REFERENCE
        if code == OK:
            break
        # this step by the reference path, certified; then back to the kernel
        state = state_at(scenario, q[k])
        m[k] = state.kin.m
        if state.error_norm < scenario.motion.tolerance or k >= N:
            break
        program = program_at(ctrl, scenario, q[k], state, step=k)
        result = solve_chain(program.qp, [DEFAULT_SOLVER, *DEFAULT_FALLBACK])
        qd[k] = result.x[:n]
        delta[k] = result.x[n : n + 2] if program.qp.n_slack else 0.0
        alpha[k] = program.alpha
        q[k + 1] = q[k] + qd[k] * scenario.motion.dt
        reference_steps.append(k)
        k += 1
    err = np.hypot(*(scenario.motion.goal - scenario.planar_arm.forward(q[k])))
    return {
        "q": q[: k + 1],
        "qd": qd[:k],
        "delta": delta[:k],
        "alpha": alpha[:k],
        "m": m[: k + 1],
        "steps": k,
        "reached": bool(err < scenario.motion.tolerance),
        "reference_steps": reference_steps,
    }


def warm_up() -> float:
    """Compile (or load from the cache) every kernel; returns the seconds it took."""
    from ..core.scenario import load_scenario

    start = time.perf_counter()
    for task in ("task1", "task2"):
        sc = load_scenario(task, {"motion.max_time": 0.1})
        for name in ("UC-IVKC", "C-EMDM"):
            run_fast(sc, name)
            simulate_batch(sc, name)
    return time.perf_counter() - start


OUTCOMES = (
    "steps",
    "reached",
    "time_to_goal",
    "min_manipulability",
    "mean_manipulability",
    "total_effort",
    "final_error",
    "max_abs_qd",
)


def simulate_batch(
    scenario: Any,
    controller: Any,
    *,
    goals: np.ndarray | None = None,
    q0s: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Many closed-loop runs of ``controller`` on the fast path, in parallel on every core.

    ``goals`` (R x 2, m) and ``q0s`` (R x n, rad) default to the scenario's; either may be given
    alone. Returns one array of R values per outcome in :data:`OUTCOMES` (``reached`` as bool,
    ``time_to_goal`` NaN where not reached) and ``reference_runs``, the runs a step of which the
    reference path solved. The outcomes equal those of :func:`emdm.simulate` to 1e-12 (tested).
    """
    from ..core.controllers import get_controller

    ctrl = controller if not isinstance(controller, str) else get_controller(controller)
    n = scenario.n
    goals = np.atleast_2d(np.asarray(goals if goals is not None else scenario.motion.goal, float))
    q0s = np.atleast_2d(np.asarray(q0s if q0s is not None else scenario.motion.q0, float))
    runs = max(goals.shape[0], q0s.shape[0])
    goals = np.ascontiguousarray(np.broadcast_to(goals, (runs, 2)))
    q0s = np.ascontiguousarray(np.broadcast_to(q0s, (runs, n)))
    args = list(_arrays(scenario))
    args[8] = goals
    out = np.empty((runs, 9))
    if scenario.controller.on_infeasible == "scale":
        _batch(*args, ctrl.method == "EMDM", ctrl.constrained, q0s, out)
    else:
        out[:, 8] = NEEDS_REFERENCE
    redo = np.flatnonzero(out[:, 8] != OK)
    for r in redo:  # finish these runs exactly, step by step where needed
        sc = scenario.with_overrides({"motion.goal": list(goals[r]), "motion.q0": list(q0s[r])})
        res = run_fast(sc, ctrl)
        dt = scenario.motion.dt
        err = float(np.hypot(*(goals[r] - sc.planar_arm.forward(res["q"][-1]))))
        k = res["steps"]
        out[r, :8] = (
            k,
            float(res["reached"]),
            k * dt if res["reached"] else np.nan,
            res["m"].min(),
            res["m"].mean(),
            0.5 * float((res["qd"] ** 2).sum()) * dt,
            err,
            float(np.abs(res["qd"]).max()) if k else 0.0,
        )
    result = {name: out[:, i].copy() for i, name in enumerate(OUTCOMES)}
    result["steps"] = result["steps"].astype(np.int64)
    result["reached"] = result["reached"].astype(bool)
    result["reference_runs"] = redo
    return result


__all__: list[str] = ["HAVE_NUMBA", "OUTCOMES", "run_fast", "simulate_batch", "warm_up"]
