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


# ------------------------------------------------------------------------------ kinematics
@njit(cache=True)
def _kinematics(lengths, q, p, J, Jm):
    """p, J, Jm in place; returns m (see emdm.arm)."""
    n = q.size
    rx = np.empty(n)
    ry = np.empty(n)
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
    minors = np.empty(npairs)
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
    G = np.empty((npairs, n))
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
    else:  # steepest one-sided ascent (emdm.arm._steepest_ascent)
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
def _ray_interval(G, lb, ub, y0, d):
    """(t_lo, t_hi, wx, wy, ok): y0 + t d in the zonotope G box (emdm.feasibility)."""
    nb = G.shape[1]
    # candidate normals: +-perp(g), +-g, +-e1, +-e2, +-d, +-perp(d), normalised
    cand = np.empty((4 * (nb + 3), 2))
    count = 0
    base = np.empty((nb + 3, 2))
    nbase = 0
    for j in range(nb + 3):
        if j < nb:
            vx, vy = G[0, j], G[1, j]
        elif j == nb:
            vx, vy = 1.0, 0.0
        elif j == nb + 1:
            vx, vy = 0.0, 1.0
        else:
            vx, vy = d[0], d[1]
        norm = math.hypot(vx, vy)
        if norm > 0:
            base[nbase, 0] = vx / norm
            base[nbase, 1] = vy / norm
            nbase += 1
    for j in range(nbase):
        vx, vy = base[j, 0], base[j, 1]
        for wx, wy in ((vx, vy), (-vy, vx), (-vx, -vy), (vy, -vx)):
            cand[count, 0] = wx
            cand[count, 1] = wy
            count += 1
    size = 1.0 + abs(y0[0]) + abs(y0[1])
    for j in range(nb):
        size += (abs(G[0, j]) + abs(G[1, j])) * max(abs(lb[j]), abs(ub[j]))
    dsum = abs(d[0]) + abs(d[1])
    t_lo, t_hi = -math.inf, math.inf
    bwx, bwy = 0.0, 0.0
    found = False
    for c in range(count):
        wx, wy = cand[c, 0], cand[c, 1]
        h = -(wx * y0[0] + wy * y0[1])
        for j in range(nb):
            s = wx * G[0, j] + wy * G[1, j]
            h += max(s * lb[j], s * ub[j])
        a = wx * d[0] + wy * d[1]
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
def _boundary_preimage(G, lb, ub, centre, tx, ty, wx, wy, x):
    """Fill x; returns how many generators are parallel to the edge (they share its length)."""
    nb = G.shape[1]
    ux, uy = -wy, wx
    denom = 0.0
    rx, ry = tx, ty
    parallel = np.zeros(nb, dtype=np.bool_)
    for j in range(nb):
        s = wx * G[0, j] + wy * G[1, j]
        gn = math.hypot(G[0, j], G[1, j])
        if abs(s) <= 1e-12 * max(gn, 1e-300):
            parallel[j] = True
            x[j] = centre[j]
        else:
            x[j] = ub[j] if s > 0 else lb[j]
        rx -= G[0, j] * x[j]
        ry -= G[1, j] * x[j]
    for j in range(nb):
        if parallel[j]:
            denom += abs(ux * G[0, j] + uy * G[1, j]) * 0.5 * (ub[j] - lb[j])
    if denom > 0:
        tau = (ux * rx + uy * ry) / denom
        tau = min(1.0, max(-1.0, tau))
        for j in range(nb):
            if parallel[j]:
                gu = ux * G[0, j] + uy * G[1, j]
                sgn = 1.0 if gu > 0 else (-1.0 if gu < 0 else 0.0)
                x[j] += tau * 0.5 * (ub[j] - lb[j]) * sgn
    count = 0
    for j in range(nb):
        count += parallel[j]
    return count


@njit(cache=True)
def _free_rank(A, free):
    """Rank (0, 1, 2) of the columns of A marked free.

    Rank 2 when some pair of columns has a 2x2 minor above ``RANK_TOL`` times the squared size
    of the columns: minors are exact zero for parallel columns and accurate to rounding
    otherwise (a Gram determinant would drown in rounding at this tolerance).
    """
    idx = np.flatnonzero(free)
    scale = 0.0
    for a in range(idx.size):
        j = idx[a]
        scale += A[0, j] * A[0, j] + A[1, j] * A[1, j]
    if scale <= 0:
        return 0
    for a in range(idx.size):
        i = idx[a]
        for b in range(a + 1, idx.size):
            k = idx[b]
            if abs(A[0, i] * A[1, k] - A[1, i] * A[0, k]) > RANK_TOL * scale:
                return 2
    return 1


@njit(cache=True)
def _task_scale(A, b, lb, ub):
    """Largest feasible task scale in [0, 1]; -1 when none; -2 when the reference is needed."""
    n = A.shape[1]
    free = np.empty(n, dtype=np.bool_)
    nfree = 0
    for j in range(n):
        free[j] = math.isinf(lb[j]) and math.isinf(ub[j])
        nfree += free[j]
    if nfree > 0:
        if _free_rank(A, free) == 2:
            return 1.0
        return -2.0
    d = np.empty(2)
    d[0], d[1] = b[0], b[1]
    t_lo, t_hi, _, _, _ = _ray_interval(A, lb, ub, np.zeros(2), d)
    lo = max(0.0, t_lo)
    hi = min(1.0, t_hi)
    if hi < lo - 1e-12:
        return -1.0
    return hi if hi >= lo else lo


@njit(cache=True)
def _feasible_point(A, b, lb, ub, x):
    """Fill x with a feasible point; returns (OK | INFEASIBLE | NEEDS_REFERENCE, unique).

    ``unique`` is True when b lies on an edge of the zonotope whose preimage is one point (at most
    one generator parallel to the edge): then x is the only feasible point, hence the optimum.
    """
    n = A.shape[1]
    free = np.empty(n, dtype=np.bool_)
    nfree = 0
    for j in range(n):
        free[j] = math.isinf(lb[j]) and math.isinf(ub[j])
        nfree += free[j]
    if nfree > 0:
        if _free_rank(A, free) != 2:
            return NEEDS_REFERENCE, False
        # bounded variables at clip(0); the free ones solve the rest (least norm)
        rx, ry = b[0], b[1]
        for j in range(n):
            if not free[j]:
                x[j] = min(max(0.0, lb[j]), ub[j])
                rx -= A[0, j] * x[j]
                ry -= A[1, j] * x[j]
        g00 = g01 = g11 = 0.0
        for j in range(n):
            if free[j]:
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
    centre = 0.5 * (lb + ub)
    y0 = A @ centre
    d = np.empty(2)
    d[0], d[1] = b[0] - y0[0], b[1] - y0[1]
    noise = RANK_TOL * (1.0 + max(abs(b[0]), abs(b[1])) + max(abs(y0[0]), abs(y0[1])))
    for j in range(n):
        x[j] = centre[j]
    unique = False
    if max(abs(d[0]), abs(d[1])) > noise:
        t_lo, t_hi, wx, wy, found = _ray_interval(A, lb, ub, y0, d)
        if not found or t_hi < 1.0 - 1e-9 or t_lo > t_hi:
            return INFEASIBLE, False
        parallel = _boundary_preimage(
            A, lb, ub, centre, y0[0] + t_hi * d[0], y0[1] + t_hi * d[1], wx, wy, x
        )
        unique = t_hi <= 1.0 + 1e-12 and parallel <= 1
        if t_hi > 1.0:
            for j in range(n):
                x[j] = centre[j] + (x[j] - centre[j]) / t_hi
    size = 1.0 + max(abs(b[0]), abs(b[1]))
    amax = 0.0
    xsum = 0.0
    for j in range(n):
        amax = max(amax, abs(A[0, j]), abs(A[1, j]))
        xsum += abs(x[j])
    size += amax * xsum
    r = A @ x - b
    if max(abs(r[0]), abs(r[1])) > FEASIBILITY_TOL * size:
        return INFEASIBLE, False
    return OK, unique


# ---------------------------------------------------------------------------- active set
@njit(cache=True)
def _active_set(Pd, c, A, b, lb, ub, x):
    """Primal active set (emdm.solvers.active_set) for diagonal P; returns (code, iterations)."""
    n = x.size
    code, unique = _feasible_point(A, b, lb, ub, x)
    if code != OK:
        return code, 0
    if unique:  # the scaled task leaves a single feasible point: it is the optimum
        return OK, 0
    work = np.zeros(n, dtype=np.int8)
    snap = np.empty(n)
    for j in range(n):
        a = abs(lb[j]) if math.isfinite(lb[j]) else 0.0
        bb = abs(ub[j]) if math.isfinite(ub[j]) else 0.0
        snap[j] = 1e-13 * (1.0 + max(a, bb))
    free = np.ones(n, dtype=np.bool_)
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
    g = np.empty(n)
    p = np.zeros(n)
    for iteration in range(1, limit + 1):
        idx = np.flatnonzero(work == 0)
        f = idx.size
        for j in range(n):
            g[j] = Pd[j] * x[j] + c[j]
            p[j] = 0.0
        lam0 = lam1 = 0.0
        if f == 2:  # no null space: p = 0, A_F^T lam = g_F
            i0, i1 = idx[0], idx[1]
            det = A[0, i0] * A[1, i1] - A[1, i0] * A[0, i1]
            lam0 = (g[i0] * A[1, i1] - g[i1] * A[1, i0]) / det
            lam1 = (A[0, i0] * g[i1] - A[0, i1] * g[i0]) / det
        else:
            K = np.zeros((f + 2, f + 2))
            rhs = np.zeros(f + 2)
            for a in range(f):
                j = idx[a]
                K[a, a] = Pd[j]
                K[a, f] = -A[0, j]
                K[a, f + 1] = -A[1, j]
                K[f, a] = A[0, j]
                K[f + 1, a] = A[1, j]
                rhs[a] = -g[j]
            sol = np.linalg.solve(K, rhs)
            for a in range(f):
                p[idx[a]] = sol[a]
            lam0, lam1 = sol[f], sol[f + 1]
        pmax = 0.0
        xmax = 0.0
        for j in range(n):
            pmax = max(pmax, abs(p[j]))
            xmax = max(xmax, abs(x[j]))
        if not math.isfinite(pmax):
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
            rest = work == 0
            rest[block] = False
            if _free_rank(A, rest) == 2:
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
    NEEDS_REFERENCE / INFEASIBLE with k the step to hand over.
    """
    n = lengths.size
    slack = method_emdm and n == 2
    nx = n + 2 if slack else n
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
        m_rec[k] = _kinematics(lengths, q[k], p, J, Jm)
        ex, ey = goal[0] - p[0], goal[1] - p[1]
        err = math.sqrt(ex * ex + ey * ey)
        if err < tol:
            return OK, k
        if k >= n_steps:
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
            ws = c_s / max(err, 1e-9)
            for i in range(2):
                Pd[n + i], c[n + i] = ws, 0.0
                A[0, n + i] = 1.0 if i == 0 else 0.0
                A[1, n + i] = 1.0 if i == 1 else 0.0
                lb[n + i], ub[n + i] = smin[i], smax[i]
        a = _task_scale(A, b, lb, ub)
        if a < 0:  # no feasible scale, or a case for the reference path
            return NEEDS_REFERENCE, k
        b[0] *= a
        b[1] *= a
        code, _ = _active_set(Pd, c, A, b, lb, ub, x)
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
    from .controllers import get_controller, program_at, state_at
    from .solvers import DEFAULT_FALLBACK, DEFAULT_SOLVER, solve_chain

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
    from .scenario import load_scenario

    start = time.perf_counter()
    for task in ("task1", "task2"):
        sc = load_scenario(task, {"motion.max_time": 0.1})
        for name in ("UC-IVKC", "C-EMDM"):
            run_fast(sc, name)
    return time.perf_counter() - start


__all__: list[str] = ["HAVE_NUMBA", "run_fast", "warm_up"]
