"""The per-step kinematics, compiled: the planar arm and the task of a spatial arm.

This is the one implementation of each formula; :class:`~emdm.core.arm.PlanarArm`,
:class:`~emdm.core.serial.SerialArm` (through :mod:`emdm.core.serial_kernels`) and the compiled
control loop call these kernels. They write into caller-owned buffers (grouped in small
NamedTuples) so a control loop allocates nothing per step. The task's feasibility is in
:mod:`emdm.core.zonotope` (two rows) and :mod:`emdm.core.simplex` (any rows, inequality rows), the
terms of the program in :mod:`emdm.core.terms`; the mathematics is stated in
``docs/mathematics.md``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from .jit import kernel
from .serial_kernels import chain_kinematics, manipulability_gradient
from .tolerances import SINGULAR_RELATIVE

F64 = NDArray[np.float64]

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
    """A spatial arm's chain as kernel input (:class:`emdm.core.serial.Chain`): per joint its
    ``origins`` (n x 4 x 4; 0 x 4 x 4 for a planar arm), unit ``axes`` (n x 3) and ``prismatic``
    flags, the ``tool`` transform after the last joint (the chain's tail, then the tool; 4 x 4),
    and the Jacobian ``rows`` of the manipulability (``serial_kernels.ROWS_*``)."""

    origins: F64
    axes: F64
    prismatic: NDArray[np.bool_]
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
    pose, the 6 x n Jacobian, the Hessian, a rotation, and the manipulability's factor
    (:func:`~emdm.core.serial_kernels.manipulability_gradient`). Apart from :class:`KinWork`, as a kernel
    call counts every array of the tuples it is passed and the planar path needs none of these."""

    frames: F64
    link: F64
    T: F64
    J6: F64
    H: F64
    R: F64
    qr: F64


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
        np.empty((2 * n + 2, 6)),
    )


@kernel(refcount=False, internal=True)
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


@kernel(refcount=False, internal=True)
def matrix_rank(M: F64, rows: int, cols: int, tol: float) -> int:
    """Rank of ``M[:rows, :cols]`` by Gaussian elimination with complete pivoting (in place), a
    pivot counting when above ``tol``: the one rank test of the feasibility kernels and of the
    active set's working set."""
    rank = 0
    for step in range(min(rows, cols)):
        pr, pc, best = step, step, 0.0
        for i in range(step, rows):
            for j in range(step, cols):
                if abs(M[i, j]) > best:
                    best, pr, pc = abs(M[i, j]), i, j
        if best <= tol:
            break
        for j in range(cols):
            M[step, j], M[pr, j] = M[pr, j], M[step, j]
        for i in range(rows):
            M[i, step], M[i, pc] = M[i, pc], M[i, step]
        for i in range(step + 1, rows):
            f = M[i, step] / M[step, step]
            for j in range(step, cols):
                M[i, j] -= f * M[step, j]
        rank += 1
    return rank


@kernel(refcount=False)
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
    else:  # exact singularity: steepest one-sided ascent (rare; allocates)
        _singular_ascent(G, Jm)
    return m


@kernel(internal=True)
def _singular_ascent(G: F64, Jm: F64) -> None:
    """``Jm = s1 v1`` (the leading singular pair of ``G``, signed so that its largest component is
    positive): the planar gradient at an exact singularity. Apart from :func:`kinematics`, which
    borrows, since the SVD allocates."""
    n = Jm.size
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


@kernel
def kinematics_of(lengths: F64, q: F64, p: F64, J: F64, Jm: F64) -> float:
    """:func:`kinematics` with its own buffers: the entry point for callers in Python (arrays
    only, so numba types the call quickly)."""
    return kinematics(lengths, q, p, J, Jm, kin_work(q.size))


@kernel(refcount=False)
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


@kernel(refcount=False)
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


@kernel(refcount=False, internal=True)
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
    if geo.origins.shape[0] == 0:
        m = kinematics(lengths, q, p, J, Jm, w)
        e[0], e[1] = goal[0] - p[0], goal[1] - p[1]
        return m
    n = q.size
    frames, link, T, J6, H, Rg = sw.frames, sw.link, sw.T, sw.J6, sw.H, sw.R
    chain_kinematics(geo.origins, geo.axes, geo.prismatic, geo.tool, q, frames, link, T, J6)
    m = manipulability_gradient(J6, geo.prismatic, H, geo.rows, Jm, sw.qr)
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
