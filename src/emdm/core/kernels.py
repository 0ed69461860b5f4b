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
from .serial_kernels import manipulability_gradient, serial_hessian, serial_kinematics

F64 = NDArray[np.float64]

SINGULAR_RELATIVE = 1e-14
"""``m <= SINGULAR_RELATIVE (sum l)^2`` counts as an exact singularity (the minors are rounding)."""
RANK_TOL = 1e-12
FEASIBILITY_TOL = 1e-10

# what a feasibility kernel returns
OK, NEEDS_REFERENCE, INFEASIBLE = 0, 1, 2

# the task of a run: the planar tip position, the 3-D position or the 6-D pose of a spatial arm
TASK_PLANAR, TASK_POSITION, TASK_POSE = 0, 1, 2


class ArmData(NamedTuple):
    """An arm's links and joint limits as kernel input (per joint: m, rad, rad/s, rad, rad, -).

    ``lengths`` are a planar arm's links (a spatial arm's: ``hypot(a, d)`` per DH row, for scales
    only); a spatial arm's chain is in :class:`Geometry`, kept apart so that the kernels of the
    joint bounds do not carry it.
    """

    lengths: F64
    q_min: F64
    q_max: F64
    qd_min: F64
    qd_max: F64
    influence: F64
    stop: F64
    gain: F64


class Geometry(NamedTuple):
    """A spatial arm's chain as kernel input: DH rows ``[a, alpha, d, offset]`` (0 x 4 for a planar
    arm), ``modified`` for Craig's convention, the ``tool`` transform (4 x 4), and the Jacobian
    ``rows`` of the manipulability (``serial_kernels.ROWS_*``)."""

    dh: F64
    modified: bool
    tool: F64
    rows: int


class KinWork(NamedTuple):
    """Scratch buffers of the planar kinematics: tip vectors, Cauchy-Binet minors and
    ``G = dc/dq``."""

    rx: F64
    ry: F64
    minors: F64
    G: F64


class SpatialWork(NamedTuple):
    """Scratch buffers of a spatial arm's kinematics: link frames, one link, the end-effector
    pose, the 6 x n Jacobian, the Hessian and a rotation. Apart from :class:`KinWork`, as a kernel
    call counts every array of the tuples it is passed and the planar path needs none of these."""

    frames: F64
    link: F64
    T: F64
    J6: F64
    H: F64
    R: F64


class FeasWork(NamedTuple):
    """Scratch buffers of the feasibility kernels (for programs of ``nx`` variables, ``nt`` task
    rows and ``ng`` inequality rows): the 2-D zonotope geometry, the simplex method of programs
    with other row counts, and at the end of ``lpf`` the program with its inequality rows made
    equalities (:func:`_augment`, :class:`AugViews`). No array is added for the rows: a kernel
    call pays for every array of the tuples it is passed."""

    cand: F64
    base: F64
    free: NDArray[np.bool_]
    parallel: NDArray[np.bool_]
    centre: F64
    lpf: F64
    lpi: NDArray[np.int64]


class AugViews(NamedTuple):
    """The augmented program of :func:`_augment` (views of the end of ``FeasWork.lpf``): ``A``
    and ``b`` of ``A x = alpha b``, bounds ``lb``, ``ub`` and the answer ``x``."""

    A: F64
    b: F64
    lb: F64
    ub: F64
    x: F64


@kernel
def _lp_size(nx: int, nt: int) -> int:
    """Length of the simplex method's part of ``lpf`` for ``nx`` variables and ``nt`` rows."""
    nv = nx + 1 + nt
    return 4 * nv + 3 * nt + nt * nt + nt * nx


@kernel
def _aug_views(w: FeasWork, nx: int, nt: int, ng: int) -> AugViews:
    """Views of the augmented program (``nx + ng + 1`` variables, ``nt + ng`` rows)."""
    nxa, nta = nx + ng + 1, nt + ng
    f = w.lpf
    a = _lp_size(nxa, nta)
    b = a + nta * nxa
    return AugViews(
        f[a:b].reshape((nta, nxa)),
        f[b : b + nta],
        f[b + nta : b + nta + nxa],
        f[b + nta + nxa : b + nta + 2 * nxa],
        f[b + nta + 2 * nxa : b + nta + 3 * nxa],
    )


class LPViews(NamedTuple):
    """Views of :class:`FeasWork`'s flat buffers for the simplex method (:func:`_lp_views`):
    per variable its status (0 basic, -1 / +1 at a bound), value, bounds and cost; per row the
    artificial's sign, the basis, and scratch; the basis matrix; the free columns."""

    status: NDArray[np.int64]
    val: F64
    vlo: F64
    vhi: F64
    cost: F64
    sigma: F64
    basis: NDArray[np.int64]
    Bm: F64
    y: F64
    d: F64
    Af: F64


@kernel
def kin_work(n: int) -> KinWork:
    """Buffers for the planar kinematics of an ``n``-joint arm."""
    npairs = n * (n - 1) // 2
    return KinWork(np.empty(n), np.empty(n), np.empty(npairs), np.empty((npairs, n)))


@kernel
def spatial_work(n: int) -> SpatialWork:
    """Buffers for the kinematics of an ``n``-joint spatial arm."""
    return SpatialWork(
        np.empty((n + 1, 4, 4)),
        np.empty((4, 4)),
        np.empty((4, 4)),
        np.empty((6, n)),
        np.empty((n, 6, n)),
        np.empty((3, 3)),
    )


@kernel
def feas_work(nx: int, nt: int, ng: int) -> FeasWork:
    """Buffers for the feasibility kernels of a program with ``nx`` variables, ``nt`` task rows
    and ``ng`` inequality rows (the simplex method's buffers fit the augmented program of
    :func:`_augment`: ``nx + ng + 1`` variables, ``nt + ng`` rows)."""
    nxa = nx + ng + 1 if ng > 0 else nx
    nta = nt + ng
    nv = nxa + 1 + nta
    aug = nta * nxa + nta + 3 * nxa if ng > 0 else 0
    return FeasWork(
        np.empty((4 * (nx + 3), 2)),
        np.empty((nx + 3, 2)),
        np.empty(nxa, dtype=np.bool_),
        np.empty(nx, dtype=np.bool_),
        np.empty(nxa),
        np.empty(_lp_size(nxa, nta) + aug),
        np.empty(nv + nta, dtype=np.int64),
    )


@kernel
def _lp_views(w: FeasWork, nx: int, nt: int) -> LPViews:
    """The simplex method's arrays as views of ``w.lpf`` and ``w.lpi`` (see :class:`LPViews`)."""
    nv = nx + 1 + nt
    f = w.lpf
    a = 4 * nv
    b = a + 3 * nt
    c = b + nt * nt
    return LPViews(
        w.lpi[:nv],
        f[:nv],
        f[nv : 2 * nv],
        f[2 * nv : 3 * nv],
        f[3 * nv : a],
        f[a : a + nt],
        w.lpi[nv : nv + nt],
        f[b:c].reshape((nt, nt)),
        f[a + nt : a + 2 * nt],
        f[a + 2 * nt : b],
        f[c : c + nt * nx].reshape((nt, nx)),
    )


@kernel
def solve_in_place(K: F64, rhs: F64, size: int) -> bool:
    """Gaussian elimination with partial pivoting on ``K[:size, :size]``; ``rhs`` becomes the
    solution. False for a singular matrix."""
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


# ------------------------------------------------------------------- spatial task kinematics
@kernel
def rotation_vector(R: F64, out: F64, at: int) -> None:
    """``out[at:at+3]`` = the rotation vector ``theta u`` of the rotation matrix ``R`` (theta in
    [0, pi]): from its skew part ``sin(theta) [u]x`` away from ``theta = pi``, else from its
    symmetric part ``cos(theta) I + (1 - cos(theta)) u u^T``, the sign taken from the skew part."""
    sx, sy, sz = R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]
    sn = 0.5 * math.sqrt(sx * sx + sy * sy + sz * sz)
    cs = 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)
    theta = math.atan2(sn, cs)
    if cs > -0.9:
        f = 0.5 * theta / sn if sn > 0.0 else 0.5
        out[at], out[at + 1], out[at + 2] = f * sx, f * sy, f * sz
        return
    k = 0
    for i in range(1, 3):
        if R[i, i] > R[k, k]:
            k = i
    scale = 1.0 - cs
    mkk = (R[k, k] - cs) / scale
    norm = math.sqrt(max(mkk, 1e-300))
    u0 = (0.5 * (R[0, k] + R[k, 0]) - (cs if k == 0 else 0.0)) / scale / norm
    u1 = (0.5 * (R[1, k] + R[k, 1]) - (cs if k == 1 else 0.0)) / scale / norm
    u2 = (0.5 * (R[2, k] + R[k, 2]) - (cs if k == 2 else 0.0)) / scale / norm
    if u0 * sx + u1 * sy + u2 * sz < 0:
        u0, u1, u2 = -u0, -u1, -u2
    out[at], out[at + 1], out[at + 2] = theta * u0, theta * u1, theta * u2


@kernel
def rotation_matrix(rx: float, ry: float, rz: float, R: F64) -> None:
    """``R`` = the rotation of rotation vector ``(rx, ry, rz)`` (Rodrigues' formula)."""
    theta = math.sqrt(rx * rx + ry * ry + rz * rz)
    if theta > 0.0:
        a = math.sin(theta) / theta
        h = math.sin(0.5 * theta) / theta
        b = 2.0 * h * h  # (1 - cos theta) / theta^2 without cancellation
    else:
        a, b = 1.0, 0.5
    R[0, 0] = 1.0 - b * (ry * ry + rz * rz)
    R[1, 1] = 1.0 - b * (rx * rx + rz * rz)
    R[2, 2] = 1.0 - b * (rx * rx + ry * ry)
    R[0, 1] = b * rx * ry - a * rz
    R[1, 0] = b * rx * ry + a * rz
    R[0, 2] = b * rx * rz + a * ry
    R[2, 0] = b * rx * rz - a * ry
    R[1, 2] = b * ry * rz - a * rx
    R[2, 1] = b * ry * rz + a * rx


@kernel
def task_kinematics(
    lengths: F64,
    geo: Geometry,
    task: int,
    goal: F64,
    q: F64,
    p: F64,
    e: F64,
    J: F64,
    Jm: F64,
    w: KinWork,
    sw: SpatialWork,
) -> float:
    """The task at ``q``: ``p`` (its value), ``e = goal - p`` (its error), ``J`` (its rows of the
    Jacobian) and ``Jm``; returns the manipulability ``m``.

    Planar arm: ``p`` = tip position (2). Spatial arm, ``TASK_POSITION``: ``p`` = end-effector
    position (3), ``J`` = the linear rows; ``TASK_POSE``: ``p`` = position and rotation vector of
    the end effector's orientation ``R`` (6), ``J`` = the geometric Jacobian, and the orientation
    error is the rotation vector of ``R_goal R^T`` (base frame), where ``R_goal`` is the rotation
    of the goal's rotation vector. ``m`` and ``Jm`` are over the rows ``geo.rows``.
    """
    if geo.dh.shape[0] == 0:
        m = kinematics(lengths, q, p, J, Jm, w)
        e[0], e[1] = goal[0] - p[0], goal[1] - p[1]
        return m
    n = q.size
    frames, link, T, J6, H, Rg = sw.frames, sw.link, sw.T, sw.J6, sw.H, sw.R
    serial_kinematics(geo.dh, geo.modified, geo.tool, q, frames, link, T, J6)
    serial_hessian(J6, H)
    m = manipulability_gradient(J6, H, geo.rows, Jm)
    rows = 6 if task == TASK_POSE else 3
    for i in range(rows):
        for j in range(n):
            J[i, j] = J6[i, j]
    for i in range(3):
        p[i] = T[i, 3]
        e[i] = goal[i] - p[i]
    if task == TASK_POSE:
        rotation_vector(T, p, 3)
        E = link
        rotation_matrix(goal[3], goal[4], goal[5], Rg)
        for i in range(3):
            for k in range(3):
                E[i, k] = Rg[i, 0] * T[k, 0] + Rg[i, 1] * T[k, 1] + Rg[i, 2] * T[k, 2]
        rotation_vector(E, e, 3)
    return m


@kernel
def task_kinematics_of(
    lengths: F64, geo: Geometry, task: int, goal: F64, q: F64, p: F64, e: F64, J: F64, Jm: F64
) -> float:
    """:func:`task_kinematics` with its own buffers (the entry point for callers in Python)."""
    n = q.size
    return task_kinematics(lengths, geo, task, goal, q, p, e, J, Jm, kin_work(n), spatial_work(n))


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
def free_rank(A: F64, free: NDArray[np.bool_], w: FeasWork) -> int:
    """Rank of the columns of ``A`` marked free (at most the row count ``nt``).

    Two rows: rank 2 when some pair of columns has a 2x2 minor above ``RANK_TOL`` times the squared
    size of the columns (minors are exact zero for parallel columns and accurate to rounding
    otherwise). Other row counts: Gaussian elimination with complete pivoting on a copy, a pivot
    counting when above ``RANK_TOL`` times the largest entry times the row count.
    """
    nt, n = A.shape
    if nt == 2:
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
    M = _lp_views(w, n, nt).Af
    cols = 0
    big = 0.0
    for j in range(n):
        if free[j]:
            for i in range(nt):
                M[i, cols] = A[i, j]
                big = max(big, abs(A[i, j]))
            cols += 1
    if big <= 0:
        return 0
    tol = RANK_TOL * big * nt
    rank = 0
    for step in range(min(nt, cols)):
        pr, pc, best = step, step, 0.0
        for i in range(step, nt):
            for j in range(step, cols):
                if abs(M[i, j]) > best:
                    best, pr, pc = abs(M[i, j]), i, j
        if best <= tol:
            break
        for j in range(cols):
            M[step, j], M[pr, j] = M[pr, j], M[step, j]
        for i in range(nt):
            M[i, step], M[i, pc] = M[i, pc], M[i, step]
        for i in range(step + 1, nt):
            f = M[i, step] / M[step, step]
            for j in range(step, cols):
                M[i, j] -= f * M[step, j]
        rank += 1
    return rank


# ------------------------------------------------------------- feasibility (any row count)
@kernel
def _column(A: F64, b: F64, sigma: F64, j: int, i: int) -> float:
    """Row ``i`` of column ``j`` of ``[A, -b, diag(sigma)]`` (variables, task scale, artificials)."""
    nx = A.shape[1]
    if j < nx:
        return float(A[i, j])
    if j == nx:
        return float(-b[i])
    return float(sigma[i]) if j - nx - 1 == i else 0.0


@kernel
def _basis_matrix(A: F64, b: F64, w: LPViews, transpose: bool) -> None:
    nt = A.shape[0]
    for i in range(nt):
        for r in range(nt):
            v = _column(A, b, w.sigma, w.basis[r], i)
            if transpose:
                w.Bm[r, i] = v
            else:
                w.Bm[i, r] = v


@kernel
def _simplex(A: F64, b: F64, w: LPViews) -> bool:
    """Minimise ``cost . v`` over ``vlo <= v <= vhi`` with ``A x - alpha b + diag(sigma) a = 0``,
    ``v = (x, alpha, a)``, from the basis ``w.basis`` (``status`` 0: basic, -1 / +1: at the
    lower / upper bound). The bounded-variable primal simplex method with Bland's rule (the first
    improving variable enters, ties leave by smallest index), so it cannot cycle. True at an
    optimum, False when a basis turns singular or the iteration limit runs out."""
    nt, nx = A.shape
    nv = nx + 1 + nt
    status, val, lo, hi, cost, basis, y, d = (
        w.status,
        w.val,
        w.vlo,
        w.vhi,
        w.cost,
        w.basis,
        w.y,
        w.d,
    )
    for _ in range(20 * nv):
        # basic values: B v_B = -(N v_N)
        for i in range(nt):
            acc = 0.0
            for j in range(nv):
                if status[j] != 0 and val[j] != 0.0:
                    acc -= _column(A, b, w.sigma, j, i) * val[j]
            y[i] = acc
        _basis_matrix(A, b, w, False)
        if not solve_in_place(w.Bm, y, nt):
            return False
        for r in range(nt):
            val[basis[r]] = y[r]
        # duals: B^T u = c_B
        for r in range(nt):
            y[r] = cost[basis[r]]
        _basis_matrix(A, b, w, True)
        if not solve_in_place(w.Bm, y, nt):
            return False
        enter = -1
        for j in range(nv):
            if status[j] == 0 or lo[j] == hi[j]:
                continue
            dj = cost[j]
            for i in range(nt):
                dj -= y[i] * _column(A, b, w.sigma, j, i)
            if (status[j] == -1 and dj < -1e-11) or (status[j] == 1 and dj > 1e-11):
                enter = j
                break
        if enter < 0:
            return True
        direction = 1.0 if status[enter] == -1 else -1.0
        for i in range(nt):
            d[i] = _column(A, b, w.sigma, enter, i)
        _basis_matrix(A, b, w, False)
        if not solve_in_place(w.Bm, d, nt):
            return False
        dmax = 0.0
        for r in range(nt):
            dmax = max(dmax, abs(d[r]))
        step = hi[enter] - lo[enter]
        leave, leave_to = -1, 0
        for r in range(nt):
            rate = -direction * d[r]
            if abs(rate) <= 1e-12 * (1.0 + dmax):
                continue
            j = basis[r]
            if rate < 0:
                room, to = (val[j] - lo[j]) / -rate, -1
            elif math.isinf(hi[j]):
                continue
            else:
                room, to = (hi[j] - val[j]) / rate, 1
            room = max(room, 0.0)
            if room < step or (room == step and leave >= 0 and j < basis[leave]):
                step, leave, leave_to = room, r, to
        if math.isinf(step):
            return False
        if leave < 0:  # the entering variable reaches its other bound first
            status[enter] = -status[enter]
            val[enter] = hi[enter] if status[enter] == 1 else lo[enter]
        else:
            j = basis[leave]
            status[j] = leave_to
            val[j] = lo[j] if leave_to < 0 else hi[j]
            basis[leave] = enter
            status[enter] = 0
    return False


@kernel
def _lp(A: F64, b: F64, lb: F64, ub: F64, scale: bool, x: F64, w: FeasWork) -> tuple[int, float]:
    """``A x = alpha b``, ``lb <= x <= ub`` (every bound finite) by the simplex method: with
    ``scale``, the largest ``alpha`` in [0, 1]; without, ``alpha = 1``. Returns ``(code, alpha)``
    and a vertex ``x`` of the feasible set (``OK``), or ``INFEASIBLE`` / ``NEEDS_REFERENCE``.

    Phase 1 starts every variable at its bound nearest zero (``alpha`` at 0, or fixed at 1) and
    minimises the artificial variables that absorb the residual; phase 2 maximises ``alpha``.
    """
    nt, nx = A.shape
    v = _lp_views(w, nx, nt)
    status, val, lo, hi, cost, sigma = v.status, v.val, v.vlo, v.vhi, v.cost, v.sigma
    for j in range(nx):
        lo[j], hi[j] = lb[j], ub[j]
        if abs(lb[j]) <= abs(ub[j]):
            status[j], val[j] = -1, lb[j]
        else:
            status[j], val[j] = 1, ub[j]
        cost[j] = 0.0
    lo[nx], hi[nx] = (0.0, 1.0) if scale else (1.0, 1.0)
    status[nx], val[nx], cost[nx] = -1, lo[nx], 0.0
    size = 1.0
    for i in range(nt):
        r = val[nx] * b[i]
        size += abs(b[i])
        for j in range(nx):
            r -= A[i, j] * val[j]
            size += abs(A[i, j]) * max(abs(lb[j]), abs(ub[j]))
        sigma[i] = 1.0 if r >= 0 else -1.0
        a = nx + 1 + i
        lo[a], hi[a], cost[a] = 0.0, math.inf, 1.0
        status[a], val[a] = 0, abs(r)
        v.basis[i] = a
    if not _simplex(A, b, v):
        return NEEDS_REFERENCE, 0.0
    left = 0.0
    for i in range(nt):
        left += val[nx + 1 + i]
    if left > FEASIBILITY_TOL * size:
        return INFEASIBLE, 0.0
    for i in range(nt):
        a = nx + 1 + i
        hi[a], cost[a] = 0.0, 0.0
        if status[a] != 0:
            val[a] = 0.0
    if scale:
        cost[nx] = -1.0
        if not _simplex(A, b, v):
            return NEEDS_REFERENCE, 0.0
    for j in range(nx):
        x[j] = min(max(val[j], lb[j]), ub[j])
    alpha = min(max(float(val[nx]), 0.0), 1.0)
    for i in range(nt):
        r = -alpha * b[i]
        for j in range(nx):
            r += A[i, j] * x[j]
        if abs(r) > FEASIBILITY_TOL * size:
            return NEEDS_REFERENCE, 0.0
    return OK, alpha


@kernel
def _mark_free(lb: F64, ub: F64, free: NDArray[np.bool_]) -> int:
    count = 0
    for j in range(lb.size):
        free[j] = math.isinf(lb[j]) and math.isinf(ub[j])
        count += free[j]
    return count


@kernel
def task_scale(A: F64, b: F64, lb: F64, ub: F64, w: FeasWork) -> float:
    """Largest ``alpha`` in [0, 1] with ``A x = alpha b``, ``lb <= x <= ub`` feasible (two rows;
    :func:`task_scale_rows` takes any).

    Returns -1 when no ``alpha`` in [0, 1] is, and -2 for the case left to the numpy reference
    (unbounded variables whose columns have rank < 2).
    """
    if _mark_free(lb, ub, w.free) > 0:
        return 1.0 if free_rank(A, w.free, w) == A.shape[0] else -2.0
    t_lo, t_hi, _, _, _ = _ray_interval(A, lb, ub, 0.0, 0.0, b[0], b[1], w)
    lo = max(0.0, t_lo)
    hi = min(1.0, t_hi)
    if hi < lo - 1e-12:
        return -1.0
    return hi if hi >= lo else lo


@kernel
def _augment(A: F64, b: F64, G: F64, h: F64, lb: F64, ub: F64, w: FeasWork) -> bool:
    """The program with its inequality rows made equalities, in :func:`_aug_views`: variables
    ``(x, s, t)``, rows ``A x = alpha b`` and ``G x + s - h t = 0``, with
    ``0 <= s <= s_max``, ``t = 1``. ``s_max_i = max(0, h_i - min over the box of G_i x)`` bounds
    the slack without cutting off any feasible ``x``. False when a variable of ``x`` is unbounded
    (``s_max`` would be infinite; the caller hands the case to the reference)."""
    nt, nx = A.shape
    ng = G.shape[0]
    aug = _aug_views(w, nx, nt, ng)
    Ag, bg, lg, ug = aug.A, aug.b, aug.lb, aug.ub
    for j in range(nx):
        if math.isinf(lb[j]) or math.isinf(ub[j]):
            return False
        lg[j], ug[j] = lb[j], ub[j]
    for i in range(nt + ng):
        for j in range(nx + ng + 1):
            Ag[i, j] = 0.0
    for i in range(nt):
        bg[i] = b[i]
        for j in range(nx):
            Ag[i, j] = A[i, j]
    for i in range(ng):
        r = nt + i
        bg[r] = 0.0
        least = 0.0
        for j in range(nx):
            Ag[r, j] = G[i, j]
            least += min(G[i, j] * lb[j], G[i, j] * ub[j])
        Ag[r, nx + i] = 1.0
        Ag[r, nx + ng] = -h[i]
        lg[nx + i], ug[nx + i] = 0.0, max(0.0, h[i] - least)
    lg[nx + ng], ug[nx + ng] = 1.0, 1.0
    return True


@kernel
def rows_hold(G: F64, h: F64, x: F64) -> bool:
    """True when ``G x <= h`` up to rounding (``FEASIBILITY_TOL`` relative to the row's size)."""
    for i in range(G.shape[0]):
        gx = 0.0
        size = 1.0 + abs(h[i])
        for j in range(x.size):
            gx += G[i, j] * x[j]
            size += abs(G[i, j] * x[j])
        if gx - h[i] > FEASIBILITY_TOL * size:
            return False
    return True


@kernel
def task_scale_rows(A: F64, b: F64, G: F64, h: F64, lb: F64, ub: F64, w: FeasWork) -> float:
    """:func:`task_scale` for programs of any row count and with inequality rows ``G x <= h``,
    by the simplex method (:func:`_lp`); the answer's vertex is left in ``w.centre``. Kept apart
    from the 2-D kernel, whose hot path would otherwise carry the simplex method's code."""
    nx = A.shape[1]
    if G.shape[0] > 0:
        if not _augment(A, b, G, h, lb, ub, w):
            return -2.0
        aug = _aug_views(w, nx, A.shape[0], G.shape[0])
        code, alpha = _lp(aug.A, aug.b, aug.lb, aug.ub, True, aug.x, w)
        for j in range(nx):
            w.centre[j] = aug.x[j]
        return alpha if code == OK else (-1.0 if code == INFEASIBLE else -2.0)
    if A.shape[0] == 2:
        return task_scale(A, b, lb, ub, w)
    if _mark_free(lb, ub, w.free) > 0:
        return 1.0 if free_rank(A, w.free, w) == A.shape[0] else -2.0
    code, alpha = _lp(A, b, lb, ub, True, w.centre, w)
    return alpha if code == OK else (-1.0 if code == INFEASIBLE else -2.0)


@kernel
def task_scale_of(A: F64, b: F64, G: F64, h: F64, lb: F64, ub: F64) -> float:
    """:func:`task_scale_rows` with its own buffers (the entry point for callers in Python)."""
    return task_scale_rows(A, b, G, h, lb, ub, feas_work(A.shape[1], A.shape[0], G.shape[0]))


@kernel
def feasible_point(A: F64, b: F64, lb: F64, ub: F64, x: F64, w: FeasWork) -> tuple[int, bool]:
    """Fill ``x`` with a feasible point; returns ``(OK | INFEASIBLE | NEEDS_REFERENCE, unique)``.

    Walks from the box centre towards ``b``, leaves the zonotope through an edge, reads the box
    vertex (or edge) that maps there and takes the convex combination that lands on ``b``.
    ``unique`` is True when ``b`` lies on an edge whose preimage is one point (at most one
    generator parallel to the edge): then ``x`` is the only feasible point, hence the optimum.
    Two task rows; :func:`feasible_point_rows` takes any.
    """
    free, centre = w.free, w.centre
    n = A.shape[1]
    if _mark_free(lb, ub, free) > 0:
        if free_rank(A, free, w) != 2:
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


@kernel
def feasible_point_rows(
    A: F64, b: F64, G: F64, h: F64, lb: F64, ub: F64, x: F64, w: FeasWork
) -> tuple[int, bool]:
    """:func:`feasible_point` for programs of any row count and with inequality rows
    ``G x <= h``. Without inequality rows: the 2-D geometry, or a vertex found by the simplex
    method (:func:`_lp`; ``unique`` always False with other than two rows); unbounded variables
    whose columns span the task space take the least-norm solution for the rest of the task, the
    bounded ones the point of their box nearest zero. With them: that point when it keeps every
    row (an inactive row changes nothing), else a vertex of the augmented program
    (:func:`_augment`). Kept apart from the 2-D kernel, whose hot path would otherwise carry the
    simplex method's code."""
    code, unique = _task_point(A, b, lb, ub, x, w)
    if G.shape[0] == 0 or code == INFEASIBLE or (code == OK and rows_hold(G, h, x)):
        return code, unique
    if not _augment(A, b, G, h, lb, ub, w):
        return NEEDS_REFERENCE, False
    aug = _aug_views(w, x.size, A.shape[0], G.shape[0])
    code, _ = _lp(aug.A, aug.b, aug.lb, aug.ub, False, aug.x, w)
    for j in range(x.size):
        x[j] = aug.x[j]
    return code, False


@kernel
def _task_point(A: F64, b: F64, lb: F64, ub: F64, x: F64, w: FeasWork) -> tuple[int, bool]:
    """A feasible point of ``A x = b``, ``lb <= x <= ub`` (see :func:`feasible_point_rows`)."""
    nt, n = A.shape
    if nt == 2:
        return feasible_point(A, b, lb, ub, x, w)
    free = w.free
    if _mark_free(lb, ub, free) > 0:
        if free_rank(A, free, w) != nt:
            return NEEDS_REFERENCE, False
        lp = _lp_views(w, n, nt)
        for i in range(nt):
            lp.y[i] = b[i]
        for j in range(n):
            if not free[j]:
                x[j] = min(max(0.0, lb[j]), ub[j])
                for i in range(nt):
                    lp.y[i] -= A[i, j] * x[j]
        for i in range(nt):
            for k in range(nt):
                acc = 0.0
                for j in range(n):
                    if free[j]:
                        acc += A[i, j] * A[k, j]
                lp.Bm[i, k] = acc
        if not solve_in_place(lp.Bm, lp.y, nt):
            return NEEDS_REFERENCE, False
        for j in range(n):
            if free[j]:
                acc = 0.0
                for i in range(nt):
                    acc += A[i, j] * lp.y[i]
                x[j] = acc
        return OK, False
    code, _ = _lp(A, b, lb, ub, False, x, w)
    return code, False


@kernel
def feasible_point_of(A: F64, b: F64, G: F64, h: F64, lb: F64, ub: F64, x: F64) -> tuple[int, bool]:
    """:func:`feasible_point_rows` with its own buffers (the entry point for callers in Python)."""
    return feasible_point_rows(A, b, G, h, lb, ub, x, feas_work(x.size, A.shape[0], G.shape[0]))
