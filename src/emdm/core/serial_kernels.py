"""Kinematics of a serial chain of revolute and prismatic joints in 3-D, compiled: pose, geometric
Jacobian, kinematic Hessian, manipulability and its Jacobian.

The one implementation behind :class:`~emdm.core.serial.SerialArm`; the formulas are stated in
``docs/mathematics.md`` ("Spatial arms") and in the docstring of :mod:`emdm.core.serial`.
Kernels write into caller-owned buffers, so a control loop allocates nothing per step.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from .jit import kernel
from .tolerances import FACTOR_PIVOT

F64 = NDArray[np.float64]
B8 = NDArray[np.bool_]

ROWS_ALL, ROWS_TRANS, ROWS_ROT = 0, 1, 2
"""Which rows of the 6 x n Jacobian a manipulability uses: all, the linear (first three) rows,
or the angular (last three) rows."""


@kernel(refcount=False, internal=True)
def _compose(A: F64, B: F64, out: F64) -> None:
    """``out = A B`` for homogeneous 4 x 4 transforms (``out`` must not alias ``A`` or ``B``)."""
    for i in range(3):
        for j in range(4):
            acc = A[i, 0] * B[0, j] + A[i, 1] * B[1, j] + A[i, 2] * B[2, j]
            if j == 3:
                acc += A[i, 3]
            out[i, j] = acc
    out[3, 0], out[3, 1], out[3, 2], out[3, 3] = 0.0, 0.0, 0.0, 1.0


@kernel(refcount=False)
def chain_kinematics(
    origins: F64, axes: F64, prismatic: B8, tool: F64, q: F64, frames: F64, W: F64, T: F64, J: F64
) -> None:
    """Pose ``T`` (4 x 4, base frame) of the end effector and geometric Jacobian ``J`` (6 x n,
    base frame, linear rows first) of a chain of ``n`` joints.

    Joint ``i`` sits at ``origins[i]`` (4 x 4, relative to the frame after joint ``i - 1``; the
    base for ``i = 0``) and moves about (revolute) or along (``prismatic[i]``) the unit
    ``axes[i]`` of that frame by ``q[i]``; ``tool`` (4 x 4) follows the last joint. So
    ``T = prod_i (origins[i] M_i(q_i)) tool`` with ``M_i`` the rotation ``Rot(a_i, q_i)`` or the
    translation ``q_i a_i``, URDF's joint semantics. ``frames[0]`` receives the base (identity),
    ``frames[i + 1]`` the frame after joint ``i``; ``W`` is scratch (4 x 4).

    With ``z_i`` the axis in the base frame and ``o_i`` the origin of ``frames[i + 1]``, column
    ``i`` of ``J`` is ``(z_i x (p_e - o_i), z_i)`` (revolute) or ``(z_i, 0)`` (prismatic). A
    rotation about the frame's own ``z`` (every DH joint, most URDF joints) takes the short path.
    """
    n = q.size
    for i in range(4):
        for j in range(4):
            frames[0, i, j] = 1.0 if i == j else 0.0
    for i in range(n):
        _compose(frames[i], origins[i], W)
        F = frames[i + 1]
        ax, ay, az = axes[i, 0], axes[i, 1], axes[i, 2]
        zx = W[0, 0] * ax + W[0, 1] * ay + W[0, 2] * az
        zy = W[1, 0] * ax + W[1, 1] * ay + W[1, 2] * az
        zz = W[2, 0] * ax + W[2, 1] * ay + W[2, 2] * az
        for r in range(4):
            F[r, 3] = W[r, 3]
            F[3, r] = W[3, r]
        if prismatic[i]:
            for r in range(3):
                for c in range(3):
                    F[r, c] = W[r, c]
            F[0, 3] += q[i] * zx
            F[1, 3] += q[i] * zy
            F[2, 3] += q[i] * zz
        elif ax == 0.0 and ay == 0.0 and az == 1.0:
            cq, sq = math.cos(q[i]), math.sin(q[i])
            for r in range(3):
                F[r, 0] = cq * W[r, 0] + sq * W[r, 1]
                F[r, 1] = cq * W[r, 1] - sq * W[r, 0]
                F[r, 2] = W[r, 2]
        else:  # R_W Rot(a, q) = c R_W + s [z]x R_W + (1 - c) z a^T, with z = R_W a
            cq, sq = math.cos(q[i]), math.sin(q[i])
            vq = 1.0 - cq
            for c in range(3):
                wx, wy, wz = W[0, c], W[1, c], W[2, c]
                a_c = axes[i, c]
                F[0, c] = cq * wx + sq * (zy * wz - zz * wy) + vq * zx * a_c
                F[1, c] = cq * wy + sq * (zz * wx - zx * wz) + vq * zy * a_c
                F[2, c] = cq * wz + sq * (zx * wy - zy * wx) + vq * zz * a_c
        J[3, i], J[4, i], J[5, i] = zx, zy, zz
    _compose(frames[n], tool, T)
    for i in range(n):
        zx, zy, zz = J[3, i], J[4, i], J[5, i]
        if prismatic[i]:
            J[0, i], J[1, i], J[2, i] = zx, zy, zz
            J[3, i], J[4, i], J[5, i] = 0.0, 0.0, 0.0
        else:
            f = frames[i + 1]
            rx, ry, rz = T[0, 3] - f[0, 3], T[1, 3] - f[1, 3], T[2, 3] - f[2, 3]
            J[0, i] = zy * rz - zz * ry
            J[1, i] = zz * rx - zx * rz
            J[2, i] = zx * ry - zy * rx


@kernel(refcount=False)
def serial_hessian(J: F64, prismatic: B8, H: F64) -> None:
    """Kinematic Hessian ``H[i] = dJ/dq_i`` (n x 6 x n) of a chain, from ``J`` alone.

    With ``z_k`` a joint's axis (the angular rows of a revolute column, the linear rows of a
    prismatic one) and ``v_k`` the linear rows of column ``k``: a revolute column has
    ``dv_k/dq_i = z_i x v_k`` for a revolute ``i <= k`` (0 for a prismatic one),
    ``z_k x v_i`` for ``i > k``, and ``dz_k/dq_i = z_i x z_k`` for a revolute ``i < k`` (else 0);
    a prismatic column has ``dv_k/dq_i = z_i x z_k`` for a revolute ``i < k`` (else 0) and no
    angular rows.
    """
    n = J.shape[1]
    for i in range(n):
        for k in range(n):
            lx = ly = lz = 0.0
            gx = gy = gz = 0.0
            turns = not prismatic[i]
            ix, iy, iz = J[3, i], J[4, i], J[5, i]
            if not prismatic[k]:
                if i <= k:
                    if turns:
                        vx, vy, vz = J[0, k], J[1, k], J[2, k]
                        lx, ly, lz = iy * vz - iz * vy, iz * vx - ix * vz, ix * vy - iy * vx
                else:
                    kx, ky, kz = J[3, k], J[4, k], J[5, k]
                    vx, vy, vz = J[0, i], J[1, i], J[2, i]
                    lx, ly, lz = ky * vz - kz * vy, kz * vx - kx * vz, kx * vy - ky * vx
                if i < k and turns:
                    kx, ky, kz = J[3, k], J[4, k], J[5, k]
                    gx, gy, gz = iy * kz - iz * ky, iz * kx - ix * kz, ix * ky - iy * kx
            elif i < k and turns:
                kx, ky, kz = J[0, k], J[1, k], J[2, k]
                lx, ly, lz = iy * kz - iz * ky, iz * kx - ix * kz, ix * ky - iy * kx
            H[i, 0, k], H[i, 1, k], H[i, 2, k] = lx, ly, lz
            H[i, 3, k], H[i, 4, k], H[i, 5, k] = gx, gy, gz


@kernel(refcount=False, internal=True)
def _gradient_by_qr(J: F64, prismatic: B8, first: int, count: int, Jm: F64, qr: F64) -> float:
    """``m`` and ``Jm_i = m trace((Ja Ja^T)^-1 Ja Ha_i^T)`` from a Householder factor
    ``Ja^T = Q R`` (``Q``: n x count, orthonormal columns): ``Ja Ja^T = R^T R``, so
    ``m = prod |R_aa|`` and ``(Ja Ja^T)^-1 Ja = R^-1 Q^T``, without forming ``Ja Ja^T`` (which
    would square the condition number). -1 when some ``|R_aa|`` is at most
    :data:`FACTOR_PIVOT` times the largest row norm of ``Ja`` (near a singularity, where the SVD
    form is used). ``qr`` (at least ``2 n + 2`` rows of ``count``) holds the factors."""
    n = J.shape[1]
    A = qr[:n]  # Ja^T, overwritten by R above its diagonal and the reflectors below
    big = 0.0
    for a in range(count):
        norm2 = 0.0
        for j in range(n):
            A[j, a] = J[first + a, j]
            norm2 += A[j, a] * A[j, a]
        big = max(big, norm2)
    diag, beta = qr[2 * n], qr[2 * n + 1]  # R's diagonal, the reflectors' 2 / (v^T v)
    m = 1.0
    for c in range(count):
        norm2 = 0.0
        for j in range(c, n):
            norm2 += A[j, c] * A[j, c]
        norm = math.sqrt(norm2)
        alpha = -norm if A[c, c] >= 0.0 else norm
        if norm <= FACTOR_PIVOT * math.sqrt(big):
            return -1.0
        A[c, c] -= alpha  # the reflector v = x - alpha e_1 is A[c:, c]
        vv = norm2 - 2.0 * alpha * (A[c, c] + alpha) + alpha * alpha
        beta[c] = 2.0 / vv
        for b in range(c + 1, count):
            dot = 0.0
            for j in range(c, n):
                dot += A[j, c] * A[j, b]
            dot *= beta[c]
            for j in range(c, n):
                A[j, b] -= dot * A[j, c]
        diag[c] = alpha
        m *= norm
    Q = qr[n : 2 * n]  # the thin Q: the reflectors applied to the first columns of I
    for j in range(n):
        for a in range(count):
            Q[j, a] = 1.0 if j == a else 0.0
    for c in range(count - 1, -1, -1):
        for b in range(c, count):  # columns b < c of Q are still e_b, untouched by reflector c
            dot = 0.0
            for j in range(c, n):
                dot += A[j, c] * Q[j, b]
            dot *= beta[c]
            for j in range(c, n):
                Q[j, b] -= dot * A[j, c]
    for j in range(n):  # Q[j] <- row j of (R^-1 Q^T)^T, i.e. B[:, j], by back substitution
        for a in range(count - 1, -1, -1):
            acc = Q[j, a]
            for c in range(a + 1, count):
                acc -= A[a, c] * Q[j, c]
            Q[j, a] = acc / diag[a]
    _contract(J, prismatic, first, count, Q, m, Jm)
    return m


@kernel(refcount=False, inline=True)
def _part(B: F64, k: int, first: int, count: int, row: int) -> float:
    """Entry ``row`` of the 6 rows of column ``k`` of ``B^T`` whose rows ``first`` to
    ``first + count - 1`` are stored (0 for the others)."""
    a = row - first
    return B[k, a] if 0 <= a < count else 0.0


@kernel(refcount=False, internal=True)
def _contract(J: F64, prismatic: B8, first: int, count: int, B: F64, m: float, Jm: F64) -> None:
    """``Jm_i = m sum_{a,k} B[k, a] H[i, first + a, k]`` without forming ``H``
    (:func:`serial_hessian`'s entries are cross products): with ``b_k``, ``c_k`` the linear and
    angular parts of row ``k`` of ``B`` (``Ja^+``), ``v_k``, ``z_k`` those of column ``k`` of ``J``,

    ``S_i = z_i . (sum_{k >= i} v_k x b_k + sum_{k > i} z_k x c_k) + v_i . sum_{k < i} b_k x z_k``

    (by ``a . (x x y) = x . (y x a)``; the term ``k = i`` and every ``z_i`` term only for a revolute
    ``i``, the ``z_k`` sums only over revolute ``k``), in O(n) instead of O(6 n^2)."""
    n = J.shape[1]
    ax = ay = az = 0.0  # suffix sum of v_k x b_k + z_k x c_k over k > i
    for i in range(n - 1, -1, -1):
        bx, by, bz = (
            _part(B, i, first, count, 0),
            _part(B, i, first, count, 1),
            _part(B, i, first, count, 2),
        )
        cx, cy, cz = (
            _part(B, i, first, count, 3),
            _part(B, i, first, count, 4),
            _part(B, i, first, count, 5),
        )
        vx, vy, vz = J[0, i], J[1, i], J[2, i]
        zx, zy, zz = J[3, i], J[4, i], J[5, i]
        # v_i x b_i, which the sum for i itself includes (a revolute i only)
        wx, wy, wz = vy * bz - vz * by, vz * bx - vx * bz, vx * by - vy * bx
        Jm[i] = 0.0
        if not prismatic[i]:
            Jm[i] = zx * (ax + wx) + zy * (ay + wy) + zz * (az + wz)
            ax += zy * cz - zz * cy
            ay += zz * cx - zx * cz
            az += zx * cy - zy * cx
        ax, ay, az = ax + wx, ay + wy, az + wz
    px = py = pz = 0.0  # prefix sum of b_k x z_k over revolute k < i
    for i in range(n):
        vx, vy, vz = J[0, i], J[1, i], J[2, i]
        Jm[i] = m * (Jm[i] + vx * px + vy * py + vz * pz)
        if not prismatic[i]:
            bx, by, bz = (
                _part(B, i, first, count, 0),
                _part(B, i, first, count, 1),
                _part(B, i, first, count, 2),
            )
            zx, zy, zz = J[3, i], J[4, i], J[5, i]
            px += by * zz - bz * zy
            py += bz * zx - bx * zz
            pz += bx * zy - by * zx


@kernel(refcount=False)
def manipulability_gradient(J: F64, prismatic: B8, H: F64, rows: int, Jm: F64, qr: F64) -> float:
    """Manipulability ``m = sqrt(det(Ja Ja^T))`` of the rows ``rows`` (:data:`ROWS_ALL`,
    :data:`ROWS_TRANS`, :data:`ROWS_ROT`) and its gradient ``Jm`` (n,); returns ``m``.

    Away from singularities, by a Householder factor of ``Ja^T`` (:func:`_gradient_by_qr`);
    near one, from the singular values ``s`` and vectors ``u_r, v_r`` of ``Ja``: ``m = prod s`` and
    ``Jm_i = sum_r (prod_{l != r} s_l) u_r^T Ha_i v_r``, the textbook
    ``m trace((Ja Ja^T)^-1 Ja Ha_i^T)`` without its inverse. Where ``Ja`` loses rank (``m = 0``,
    not differentiable) this is the gradient of the signed product of singular values: finite,
    never NaN, and along it ``m`` grows on one side of the singularity. ``qr``: a buffer of at
    least ``2 n + 2`` rows of 6 for the factor; ``H`` (n x 6 x n): a buffer for the kinematic
    Hessian, filled only on the SVD path (the factor's path contracts without it,
    :func:`_contract`); the SVD (:func:`_gradient_by_svd`) allocates.
    """
    n = J.shape[1]
    first, count = (0, 6) if rows == ROWS_ALL else ((0, 3) if rows == ROWS_TRANS else (3, 3))
    if count <= n:
        m = _gradient_by_qr(J, prismatic, first, count, Jm, qr)
        if m >= 0.0:
            return m
    serial_hessian(J, prismatic, H)
    return _gradient_by_svd(J, H, first, count, Jm)


@kernel(internal=True)
def _gradient_by_svd(J: F64, H: F64, first: int, count: int, Jm: F64) -> float:
    """The SVD form of :func:`manipulability_gradient` (near a singularity; allocates)."""
    n = J.shape[1]
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
