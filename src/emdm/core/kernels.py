"""The per-step formulas of the core, compiled: kinematics, joint bounds and the task's feasibility.

This is the one implementation of each formula; :class:`~emdm.core.arm.PlanarArm`,
:func:`~emdm.core.limits.position_damper`, :func:`~emdm.core.feasibility.task_scale` and the
compiled control loop all call these kernels. The kernels write into caller-owned buffers (grouped
in small NamedTuples) so a control loop allocates nothing per step. The mathematics is stated in
``docs/mathematics.md``; the module docstrings of :mod:`emdm.core.arm`, :mod:`emdm.core.limits` and
:mod:`emdm.core.feasibility` repeat what each formula means.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from .jit import kernel

F64 = NDArray[np.float64]

SINGULAR_RELATIVE = 1e-14
"""``m <= SINGULAR_RELATIVE (sum l)^2`` counts as an exact singularity (the minors are rounding)."""
RANK_TOL = 1e-12
FEASIBILITY_TOL = 1e-10

# what a feasibility kernel returns
OK, NEEDS_REFERENCE, INFEASIBLE = 0, 1, 2


class ArmData(NamedTuple):
    """A planar arm and its joint limits as kernel input (per joint: m, rad, rad/s, rad, rad, -)."""

    lengths: F64
    q_min: F64
    q_max: F64
    qd_min: F64
    qd_max: F64
    influence: F64
    stop: F64
    gain: F64


class KinWork(NamedTuple):
    """Scratch buffers of :func:`kinematics`: tip vectors, Cauchy-Binet minors and ``G = dc/dq``."""

    rx: F64
    ry: F64
    minors: F64
    G: F64


class FeasWork(NamedTuple):
    """Scratch buffers of the feasibility kernels (for programs of ``nx`` variables)."""

    cand: F64
    base: F64
    free: NDArray[np.bool_]
    parallel: NDArray[np.bool_]
    centre: F64


@kernel
def kin_work(n: int) -> KinWork:
    """Buffers for :func:`kinematics` of an ``n``-joint arm."""
    npairs = n * (n - 1) // 2
    return KinWork(np.empty(n), np.empty(n), np.empty(npairs), np.empty((npairs, n)))


@kernel
def feas_work(nx: int) -> FeasWork:
    """Buffers for the feasibility kernels of a program with ``nx`` variables."""
    return FeasWork(
        np.empty((4 * (nx + 3), 2)),
        np.empty((nx + 3, 2)),
        np.empty(nx, dtype=np.bool_),
        np.empty(nx, dtype=np.bool_),
        np.empty(nx),
    )


# ------------------------------------------------------------------------------ kinematics
@kernel
def kinematics(lengths: F64, q: F64, p: F64, J: F64, Jm: F64, w: KinWork) -> float:
    """``p = f(q)``, ``J`` and ``Jm`` in place; returns ``m`` (see :mod:`emdm.core.arm`).

    Tip vectors ``r_j``; ``J_j = perp(r_j)``; minors ``c_ik = cross(r_i, r_k)``, ``m = ||c||``;
    ``Jm = G^T c / m`` with ``dc_ik/dq_j = r_i . r_max(k,j) - r_max(i,j) . r_k``; at an exact
    singularity ``Jm = s1 v1``, the steepest one-sided ascent (leading singular pair of ``G``).
    """
    rx, ry, minors, G = w.rx, w.ry, w.minors, w.G
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
    else:  # exact singularity: steepest one-sided ascent (rare; may allocate)
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
                Jm[j] = sign * sv[0] * vt[0, j] + 0.0  # + 0.0 turns -0.0 into 0.0
    return m


@kernel
def kinematics_of(lengths: F64, q: F64, p: F64, J: F64, Jm: F64) -> float:
    """:func:`kinematics` with its own buffers: the entry point for callers in Python (arrays
    only, so numba types the call quickly)."""
    return kinematics(lengths, q, p, J, Jm, kin_work(q.size))


# ------------------------------------------------------------------------------ joint bounds
@kernel
def joint_bounds(arm: ArmData, q: F64, lo: F64, hi: F64) -> None:
    """The velocity box intersected with the position dampers at ``q`` (brief eq. 10, 11)."""
    for j in range(q.size):
        d_up = arm.q_max[j] - q[j]
        d_dn = q[j] - arm.q_min[j]
        span = arm.gain[j] * (arm.influence[j] - arm.stop[j])
        h = (d_up - arm.stop[j]) / span if d_up < arm.influence[j] else math.inf
        low = -(d_dn - arm.stop[j]) / span if d_dn < arm.influence[j] else -math.inf
        lo[j] = max(arm.qd_min[j], low)
        hi[j] = min(arm.qd_max[j], h)


@kernel
def damper_bounds(
    q: F64, q_min: F64, q_max: F64, influence: F64, stop: F64, gain: F64, lo: F64, hi: F64
) -> None:
    """The position-damper bounds alone (+-inf outside the influence zones)."""
    for j in range(q.size):
        d_up = q_max[j] - q[j]
        d_dn = q[j] - q_min[j]
        span = gain[j] * (influence[j] - stop[j])
        hi[j] = (d_up - stop[j]) / span if d_up < influence[j] else math.inf
        lo[j] = -(d_dn - stop[j]) / span if d_dn < influence[j] else -math.inf


# ------------------------------------------------------------------------ feasibility (2-D)
@kernel
def _ray_interval(
    G: F64, lb: F64, ub: F64, y0x: float, y0y: float, dx: float, dy: float, w: FeasWork
) -> tuple[float, float, float, float, bool]:
    """``(t_lo, t_hi, wx, wy, found)``: ``y0 + t d`` lies in the zonotope ``{G x : lb <= x <= ub}``
    for ``t`` in [t_lo, t_hi]; ``(wx, wy)`` is the normal of the half-plane that sets ``t_hi``."""
    cand, base = w.cand, w.base
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


@kernel
def _boundary_preimage(
    G: F64,
    lb: F64,
    ub: F64,
    tx: float,
    ty: float,
    wx: float,
    wy: float,
    x: F64,
    w: FeasWork,
) -> int:
    """A box point ``x`` with ``G x = t`` for ``t`` on the supporting line of normal ``w``.

    Returns how many generators are parallel to that edge (they share its length).
    """
    centre, parallel = w.centre, w.parallel
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


@kernel
def free_rank(A: F64, free: NDArray[np.bool_]) -> int:
    """Rank (0, 1, 2) of the columns of the 2-row ``A`` marked free.

    Rank 2 when some pair of columns has a 2x2 minor above ``RANK_TOL`` times the squared size of
    the columns: minors are exact zero for parallel columns and accurate to rounding otherwise.
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


@kernel
def _mark_free(lb: F64, ub: F64, free: NDArray[np.bool_]) -> int:
    count = 0
    for j in range(lb.size):
        free[j] = math.isinf(lb[j]) and math.isinf(ub[j])
        count += free[j]
    return count


@kernel
def task_scale(A: F64, b: F64, lb: F64, ub: F64, w: FeasWork) -> float:
    """Largest ``alpha`` in [0, 1] with ``A x = alpha b``, ``lb <= x <= ub`` feasible.

    Returns -1 when no ``alpha`` in [0, 1] is, and -2 for the case left to the numpy reference
    (unbounded variables whose columns have rank < 2).
    """
    if _mark_free(lb, ub, w.free) > 0:
        return 1.0 if free_rank(A, w.free) == 2 else -2.0
    t_lo, t_hi, _, _, _ = _ray_interval(A, lb, ub, 0.0, 0.0, b[0], b[1], w)
    lo = max(0.0, t_lo)
    hi = min(1.0, t_hi)
    if hi < lo - 1e-12:
        return -1.0
    return hi if hi >= lo else lo


@kernel
def task_scale_of(A: F64, b: F64, lb: F64, ub: F64) -> float:
    """:func:`task_scale` with its own buffers (the entry point for callers in Python)."""
    return task_scale(A, b, lb, ub, feas_work(A.shape[1]))


@kernel
def feasible_point(A: F64, b: F64, lb: F64, ub: F64, x: F64, w: FeasWork) -> tuple[int, bool]:
    """Fill ``x`` with a feasible point; returns ``(OK | INFEASIBLE | NEEDS_REFERENCE, unique)``.

    Walks from the box centre towards ``b``, leaves the zonotope through an edge, reads the box
    vertex (or edge) that maps there and takes the convex combination that lands on ``b``.
    ``unique`` is True when ``b`` lies on an edge whose preimage is one point (at most one
    generator parallel to the edge): then ``x`` is the only feasible point, hence the optimum.
    """
    free, centre = w.free, w.centre
    n = A.shape[1]
    if _mark_free(lb, ub, free) > 0:
        if free_rank(A, free) != 2:
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
        t_lo, t_hi, wx, wy, found = _ray_interval(A, lb, ub, y0x, y0y, dx, dy, w)
        if not found or t_hi < 1.0 - 1e-9 or t_lo > t_hi:
            return INFEASIBLE, False
        count = _boundary_preimage(A, lb, ub, y0x + t_hi * dx, y0y + t_hi * dy, wx, wy, x, w)
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


# ------------------------------------------------------------------------------ the program
class ProgramData(NamedTuple):
    """What a controller's program needs besides the state (see :mod:`emdm.core.controllers`).

    ``w_e`` and ``w_m`` weigh effort and manipulability rate (IVKC: 1 and 0); ``slack`` adds the
    task slack ``delta`` with weight ``c_s / max(||e||, 1e-9 m)`` and bounds ``[s_min, s_max]``
    (m/s); ``constrained`` applies the joint bounds (velocity box and dampers).
    """

    w_e: float
    w_m: float
    c_s: float
    slack: bool
    constrained: bool
    s_min: F64
    s_max: F64


ERROR_FLOOR = 1e-9
"""Smallest ``||e||`` (m) used in ``w_S = c_S / ||e||``."""


@kernel
def build_program(
    arm: ArmData,
    prog: ProgramData,
    q: F64,
    J: F64,
    Jm: F64,
    v: F64,
    error_norm: float,
    P: F64,
    c: F64,
    A: F64,
    b: F64,
    lb: F64,
    ub: F64,
) -> None:
    """The program ``min 1/2 x^T P x + c^T x  s.t.  A x = b, lb <= x <= ub`` of a controller.

    ``x = (qd, delta)``: ``P = diag(w_e, ..., w_S, w_S)``, ``c = (-w_m Jm, 0, 0)``,
    ``A = [J, I]``, ``b = v``; without slack ``x = qd``, ``P = w_e I``, ``c = -w_m Jm``, ``A = J``.
    """
    n = q.size
    nx = c.size
    for i in range(nx):
        for j in range(nx):
            P[i, j] = 0.0
    if prog.constrained:
        joint_bounds(arm, q, lb, ub)
    else:
        for j in range(n):
            lb[j], ub[j] = -math.inf, math.inf
    for j in range(n):
        A[0, j], A[1, j] = J[0, j], J[1, j]
        P[j, j] = prog.w_e
        c[j] = -prog.w_m * Jm[j]
    if prog.slack:
        w_s = prog.c_s / max(error_norm, ERROR_FLOOR)
        for i in range(2):
            P[n + i, n + i] = w_s
            c[n + i] = 0.0
            A[0, n + i] = 1.0 if i == 0 else 0.0
            A[1, n + i] = 1.0 if i == 1 else 0.0
            lb[n + i], ub[n + i] = prog.s_min[i], prog.s_max[i]
    b[0], b[1] = v[0], v[1]


@kernel
def feasible_point_of(A: F64, b: F64, lb: F64, ub: F64, x: F64) -> tuple[int, bool]:
    """:func:`feasible_point` with its own buffers (the entry point for callers in Python)."""
    return feasible_point(A, b, lb, ub, x, feas_work(x.size))
