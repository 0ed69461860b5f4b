"""Kinematics of a serial chain of revolute joints in 3-D, compiled: pose, geometric Jacobian,
kinematic Hessian, manipulability and its Jacobian.

The one implementation behind :class:`~emdm.core.serial.SerialArm`; the formulas are stated in
``docs/mathematics.md`` ("Spatial arms") and in the docstring of :mod:`emdm.core.serial`.
Kernels write into caller-owned buffers, so a control loop allocates nothing per step.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from .jit import kernel
from .tolerances import CHOLESKY_PIVOT

F64 = NDArray[np.float64]

ROWS_ALL, ROWS_TRANS, ROWS_ROT = 0, 1, 2
"""Which rows of the 6 x n Jacobian a manipulability uses: all, the linear (first three) rows,
or the angular (last three) rows."""


@kernel
def link_transform(a: float, alpha: float, d: float, theta: float, modified: bool, T: F64) -> None:
    """``T`` = the transform of one link: standard DH ``Rz(theta) Tz(d) Tx(a) Rx(alpha)``,
    modified (Craig) DH ``Rx(alpha) Tx(a) Rz(theta) Tz(d)``."""
    ct, st = math.cos(theta), math.sin(theta)
    ca, sa = math.cos(alpha), math.sin(alpha)
    if modified:
        T[0, 0], T[0, 1], T[0, 2], T[0, 3] = ct, -st, 0.0, a
        T[1, 0], T[1, 1], T[1, 2], T[1, 3] = st * ca, ct * ca, -sa, -sa * d
        T[2, 0], T[2, 1], T[2, 2], T[2, 3] = st * sa, ct * sa, ca, ca * d
    else:
        T[0, 0], T[0, 1], T[0, 2], T[0, 3] = ct, -st * ca, st * sa, a * ct
        T[1, 0], T[1, 1], T[1, 2], T[1, 3] = st, ct * ca, -ct * sa, a * st
        T[2, 0], T[2, 1], T[2, 2], T[2, 3] = 0.0, sa, ca, d
    T[3, 0], T[3, 1], T[3, 2], T[3, 3] = 0.0, 0.0, 0.0, 1.0


@kernel
def _compose(A: F64, B: F64, out: F64) -> None:
    """``out = A B`` for homogeneous 4 x 4 transforms (``out`` must not alias ``A`` or ``B``)."""
    for i in range(3):
        for j in range(4):
            acc = A[i, 0] * B[0, j] + A[i, 1] * B[1, j] + A[i, 2] * B[2, j]
            if j == 3:
                acc += A[i, 3]
            out[i, j] = acc
    out[3, 0], out[3, 1], out[3, 2], out[3, 3] = 0.0, 0.0, 0.0, 1.0


@kernel
def serial_kinematics(
    dh: F64, modified: bool, tool: F64, q: F64, frames: F64, link: F64, T: F64, J: F64
) -> None:
    """Pose ``T`` (4 x 4, base frame) of the end effector and geometric Jacobian ``J`` (6 x n,
    base frame, linear rows first) of the chain ``dh`` (rows ``a, alpha, d, offset``; m, rad).

    ``frames[i]`` receives the pose of link frame ``i`` (``frames[0]`` the base). Joint ``i``
    (1-based) turns about the z axis of frame ``i - 1`` (standard DH) or ``i`` (modified DH),
    through that frame's origin; its column is ``(z x (p_e - o), z)``.
    """
    n = q.size
    for i in range(4):
        for j in range(4):
            frames[0, i, j] = 1.0 if i == j else 0.0
    for i in range(n):
        link_transform(dh[i, 0], dh[i, 1], dh[i, 2], q[i] + dh[i, 3], modified, link)
        _compose(frames[i], link, frames[i + 1])
    _compose(frames[n], tool, T)
    for i in range(n):
        f = frames[i + 1] if modified else frames[i]
        zx, zy, zz = f[0, 2], f[1, 2], f[2, 2]
        rx, ry, rz = T[0, 3] - f[0, 3], T[1, 3] - f[1, 3], T[2, 3] - f[2, 3]
        J[0, i] = zy * rz - zz * ry
        J[1, i] = zz * rx - zx * rz
        J[2, i] = zx * ry - zy * rx
        J[3, i], J[4, i], J[5, i] = zx, zy, zz


@kernel
def serial_hessian(J: F64, H: F64) -> None:
    """Kinematic Hessian ``H[i] = dJ/dq_i`` (n x 6 x n) of a revolute chain, from ``J`` alone.

    With ``z_k`` the axis (angular rows) and ``v_k`` the linear rows of column ``k``:
    ``dv_k/dq_i = z_min(i,k) x v_max(i,k)`` and ``dz_k/dq_i = z_i x z_k`` for ``i < k``, else 0.
    """
    n = J.shape[1]
    for i in range(n):
        for k in range(n):
            lo, hi = min(i, k), max(i, k)
            zx, zy, zz = J[3, lo], J[4, lo], J[5, lo]
            vx, vy, vz = J[0, hi], J[1, hi], J[2, hi]
            H[i, 0, k] = zy * vz - zz * vy
            H[i, 1, k] = zz * vx - zx * vz
            H[i, 2, k] = zx * vy - zy * vx
            if i < k:
                ax, ay, az = J[3, i], J[4, i], J[5, i]
                bx, by, bz = J[3, k], J[4, k], J[5, k]
                H[i, 3, k] = ay * bz - az * by
                H[i, 4, k] = az * bx - ax * bz
                H[i, 5, k] = ax * by - ay * bx
            else:
                H[i, 3, k] = 0.0
                H[i, 4, k] = 0.0
                H[i, 5, k] = 0.0


@kernel
def _gradient_by_cholesky(J: F64, H: F64, first: int, count: int, Jm: F64) -> float:
    """``m`` and ``Jm_i = m trace((Ja Ja^T)^-1 Ja Ha_i^T)`` by a Cholesky factor ``L L^T`` of
    ``Ja Ja^T`` (``m`` = the product of its pivots); -1 when a pivot is below
    :data:`CHOLESKY_PIVOT` (near a singularity, where the SVD form is the accurate one)."""
    n = J.shape[1]
    L = np.empty((count, count))
    for a in range(count):
        for b in range(a + 1):
            acc = 0.0
            for j in range(n):
                acc += J[first + a, j] * J[first + b, j]
            L[a, b] = acc
    big = 0.0
    for a in range(count):
        big = max(big, L[a, a])
    m = 1.0
    for a in range(count):
        for b in range(a):
            acc = L[a, b]
            for c in range(b):
                acc -= L[a, c] * L[b, c]
            L[a, b] = acc / L[b, b]
        acc = L[a, a]
        for c in range(a):
            acc -= L[a, c] * L[a, c]
        if acc <= CHOLESKY_PIVOT * CHOLESKY_PIVOT * big:
            return -1.0
        L[a, a] = math.sqrt(acc)
        m *= L[a, a]
    B = np.empty((count, n))  # B = (L L^T)^-1 Ja, column by column
    for j in range(n):
        for a in range(count):
            acc = J[first + a, j]
            for c in range(a):
                acc -= L[a, c] * B[c, j]
            B[a, j] = acc / L[a, a]
        for a in range(count - 1, -1, -1):
            acc = B[a, j]
            for c in range(a + 1, count):
                acc -= L[c, a] * B[c, j]
            B[a, j] = acc / L[a, a]
    for i in range(n):
        acc = 0.0
        for a in range(count):
            for b in range(n):
                acc += B[a, b] * H[i, first + a, b]
        Jm[i] = m * acc
    return m


@kernel
def manipulability_gradient(J: F64, H: F64, rows: int, Jm: F64) -> float:
    """Manipulability ``m = sqrt(det(Ja Ja^T))`` of the rows ``rows`` (:data:`ROWS_ALL`,
    :data:`ROWS_TRANS`, :data:`ROWS_ROT`) and its gradient ``Jm`` (n,); returns ``m``.

    Away from singularities, by a Cholesky factor of ``Ja Ja^T`` (:func:`_gradient_by_cholesky`);
    near one, from the singular values ``s`` and vectors ``u_r, v_r`` of ``Ja``: ``m = prod s`` and
    ``Jm_i = sum_r (prod_{l != r} s_l) u_r^T Ha_i v_r``, the textbook
    ``m trace((Ja Ja^T)^-1 Ja Ha_i^T)`` without its inverse. Where ``Ja`` loses rank (``m = 0``,
    not differentiable) this is the gradient of the signed product of singular values: finite,
    never NaN, and along it ``m`` grows on one side of the singularity.
    """
    n = J.shape[1]
    first, count = (0, 6) if rows == ROWS_ALL else ((0, 3) if rows == ROWS_TRANS else (3, 3))
    if count <= n:
        m = _gradient_by_cholesky(J, H, first, count, Jm)
        if m >= 0.0:
            return m
    k = min(count, n)
    Ja = np.ascontiguousarray(J[first : first + count, :])
    U, s, Vt = np.linalg.svd(Ja, full_matrices=False)
    m = 1.0
    for r in range(k):
        m *= s[r]
    if count > n:  # more task rows than joints: J Ja^T is singular, m = 0 everywhere
        m = 0.0
    for i in range(n):
        total = 0.0
        if count <= n:
            for r in range(k):
                others = 1.0
                for l_ in range(k):
                    if l_ != r:
                        others *= s[l_]
                acc = 0.0
                for a in range(count):
                    row = 0.0
                    for b in range(n):
                        row += H[i, first + a, b] * Vt[r, b]
                    acc += U[a, r] * row
                total += others * acc
        Jm[i] = total
    return m
