"""Distances between an arm's links and the obstacles of a scenario, compiled.

Every arm is seen the same way here, planar or spatial: a polyline of points ``pts`` (base, every
joint frame's origin, end effector; planar arms have ``z = 0``) whose consecutive points bound its
links, and per joint ``j`` its axis ``axes[j] = [point (3), unit direction (3), a]``, where ``a``
is the index in ``pts`` of the axis point (``j`` for a planar arm, ``j + 1`` for a spatial one,
whose points are the origins of the frames after each joint, :mod:`emdm.core.serial`).
Joint ``j`` moves ``pts[k]`` exactly when ``j < k``, with velocity column
``axis_j x (pts[k] - point_j)`` (a revolute joint).

Every obstacle is a capsule: a segment ``[A, B]`` and a radius ``r`` (a circle or a sphere has
``A = B``), moving at a constant velocity ``v`` (``A + v t``). A link is a capsule too, of radius
``link_radius``. The distance of a link to an obstacle is ``||x* - w*|| - r - link_radius`` for the
closest points ``x*`` (on the link) and ``w*`` (on the obstacle's segment), and its Jacobian is
``J_d = n^T J_{x*}`` with ``n = (x* - w*) / ||x* - w*||`` and ``J_{x*}`` the link point's
Jacobian at its fixed fraction along the link (docs/mathematics.md, "Obstacles").

Packed obstacle data (one array, read by the obstacle term and by the loop's clearance record):
``[influence, stop, gain, link_radius, dt, count]``, then per obstacle ``[A (3), B (3), r,
v (3)]`` (:data:`HEADER`, :data:`STRIDE`).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from .jit import kernel
from .kernels import Geometry, KinWork, SpatialWork, kin_work, spatial_work, task_kinematics

F64 = NDArray[np.float64]

HEADER = 6
"""Numbers before the first obstacle in the packed data."""
STRIDE = 10
"""Numbers per obstacle in the packed data: ``A (3), B (3), radius, velocity (3)``."""
AXIS = 9
"""Numbers per joint in ``axes``: the axis point (3), its unit direction (3), the point's index,
then two numbers of the obstacle term's own (the joint's bounds before its rows)."""
GAP = 7
"""Numbers per link and obstacle in the gaps of :func:`link_gaps`: the distance, the unit
normal (3), the obstacle's closest point (3)."""
POINT = 5
"""Numbers per point in ``pts``: the position (3), then two numbers of the obstacle term's own
(its tightening and reach of the point, written by :mod:`emdm.core.terms.obstacle`)."""


@kernel(refcount=False, internal=True)
def chain_points(geo: Geometry, p: F64, w: KinWork, sw: SpatialWork, pts: F64, axes: F64) -> None:
    """``pts`` and ``axes`` (see the module notes) from the kinematics just computed: the planar
    tip vectors ``w.rx, w.ry`` and tip ``p``, or a spatial arm's frames ``sw.frames`` and end
    effector ``sw.T``."""
    n = axes.shape[0]
    if geo.origins.shape[0] == 0:
        for i in range(n):
            pts[i, 0] = p[0] - w.rx[i]
            pts[i, 1] = p[1] - w.ry[i]
            pts[i, 2] = 0.0
        for i in (n, n + 1):
            pts[i, 0], pts[i, 1], pts[i, 2] = p[0], p[1], 0.0
        for j in range(n):
            for a in range(3):
                axes[j, a] = pts[j, a]
            axes[j, 3], axes[j, 4], axes[j, 5], axes[j, 6] = 0.0, 0.0, 1.0, float(j)
        return
    for i in range(n + 1):
        for a in range(3):
            pts[i, a] = sw.frames[i, a, 3]
    for a in range(3):
        pts[n + 1, a] = sw.T[a, 3]
    for j in range(n):  # the joint's frame: its origin is on the axis, which is revolute here
        for a in range(3):
            axes[j, a] = sw.frames[j + 1, a, 3]
            axes[j, 3 + a] = sw.J6[3 + a, j]
        axes[j, 6] = float(j + 1)


@kernel
def chain_points_of(lengths: F64, geo: Geometry, q: F64, pts: F64, axes: F64) -> None:
    """:func:`chain_points` at ``q`` with its own buffers (the entry point for Python)."""
    n = q.size
    nt = 2 if geo.origins.shape[0] == 0 else 3
    w, sw = kin_work(n), spatial_work(n)
    p, e = np.empty(nt), np.empty(nt)
    J, Jm = np.empty((nt, n)), np.empty(n)
    task_kinematics(lengths, geo, 1, np.zeros(nt), q, p, e, J, Jm, w, sw)
    chain_points(geo, p, w, sw, pts, axes)


@kernel(refcount=False, internal=True)
def segment_params(
    px: float,
    py: float,
    pz: float,
    ux: float,
    uy: float,
    uz: float,
    ax: float,
    ay: float,
    az: float,
    wx: float,
    wy: float,
    wz: float,
) -> tuple[float, float]:
    """``(s, t)`` in [0, 1]^2 such that ``P + s u`` and ``A + t w`` are closest points of the
    segments ``[P, P + u]`` and ``[A, A + w]`` (3-D; either may be a point): the textbook clamped
    solution of the 2 x 2 normal equations (Ericson, Real-Time Collision Detection, sec. 5.1.9),
    exact for degenerate segments. Scalars only: the hot loops create no array views."""
    rx, ry, rz = px - ax, py - ay, pz - az
    a = ux * ux + uy * uy + uz * uz
    e = wx * wx + wy * wy + wz * wz
    f = wx * rx + wy * ry + wz * rz
    s, t = 0.0, 0.0
    if a == 0.0 and e == 0.0:
        return s, t
    if a == 0.0:
        return s, min(max(f / e, 0.0), 1.0)
    c = ux * rx + uy * ry + uz * rz
    if e == 0.0:
        return min(max(-c / a, 0.0), 1.0), t
    b = ux * wx + uy * wy + uz * wz
    denom = a * e - b * b
    if denom > 0.0:
        s = min(max((b * f - c * e) / denom, 0.0), 1.0)
    t = (b * s + f) / e
    if t < 0.0:
        t = 0.0
        s = min(max(-c / a, 0.0), 1.0)
    elif t > 1.0:
        t = 1.0
        s = min(max((b - c) / a, 0.0), 1.0)
    return s, t


@kernel(refcount=False)
def closest_points(P: F64, Q: F64, A: F64, B: F64, x: F64, y: F64) -> float:
    """Closest points ``x`` on segment ``[P, Q]`` and ``y`` on ``[A, B]`` (3-D; either may be a
    point); returns ``||x - y||`` (:func:`segment_params`)."""
    u0, u1, u2 = Q[0] - P[0], Q[1] - P[1], Q[2] - P[2]
    w0, w1, w2 = B[0] - A[0], B[1] - A[1], B[2] - A[2]
    s, t = segment_params(P[0], P[1], P[2], u0, u1, u2, A[0], A[1], A[2], w0, w1, w2)
    x[0], x[1], x[2] = P[0] + u0 * s, P[1] + u1 * s, P[2] + u2 * s
    y[0], y[1], y[2] = A[0] + w0 * t, A[1] + w1 * t, A[2] + w2 * t
    return math.sqrt((x[0] - y[0]) ** 2 + (x[1] - y[1]) ** 2 + (x[2] - y[2]) ** 2)


@kernel(refcount=False, internal=True)
def link_gap(
    pts: F64, i: int, data: F64, o: int, t: float
) -> tuple[float, float, float, float, float, float, float]:
    """Link ``i`` (``pts[i]`` to ``pts[i + 1]``) against obstacle ``o`` at time ``t``:
    ``(span, dx, dy, dz, cx, cy, cz)`` with ``d = x* - w*`` the vector between the closest points
    (link minus obstacle), ``span = ||d||`` and ``c = w*`` the obstacle's closest point (m)."""
    at = HEADER + o * STRIDE
    vx, vy, vz = data[at + 7], data[at + 8], data[at + 9]
    ax, ay, az = data[at] + vx * t, data[at + 1] + vy * t, data[at + 2] + vz * t
    wx, wy, wz = data[at + 3] - data[at], data[at + 4] - data[at + 1], data[at + 5] - data[at + 2]
    px, py, pz = pts[i, 0], pts[i, 1], pts[i, 2]
    ux, uy, uz = pts[i + 1, 0] - px, pts[i + 1, 1] - py, pts[i + 1, 2] - pz
    s, tt = segment_params(px, py, pz, ux, uy, uz, ax, ay, az, wx, wy, wz)
    cx, cy, cz = ax + tt * wx, ay + tt * wy, az + tt * wz
    dx, dy, dz = px + s * ux - cx, py + s * uy - cy, pz + s * uz - cz
    return math.sqrt(dx * dx + dy * dy + dz * dz), dx, dy, dz, cx, cy, cz


@kernel(refcount=False, internal=True)
def obstacle_at(data: F64, o: int, t: float, A: F64, B: F64) -> float:
    """Obstacle ``o``'s segment at time ``t`` (s) into ``A, B``; returns its radius (m)."""
    at = HEADER + o * STRIDE
    for a in range(3):
        v = data[at + 7 + a]
        A[a] = data[at + a] + v * t
        B[a] = data[at + 3 + a] + v * t
    return float(data[at + 6])


@kernel(refcount=False)
def link_gaps(data: F64, t: float, pts: F64, gaps: F64) -> float:
    """``gaps[o, i] = [d, n (3), w* (3)]`` (:data:`GAP`) for link ``i`` (``pts[i]`` to
    ``pts[i + 1]``) and obstacle ``o`` at time ``t``: the distance ``d`` (m, radii subtracted),
    the unit vector ``n`` from the obstacle's closest point ``w*`` to the link's (0 where they
    meet) and ``w*``; returns the smallest ``d`` (``inf`` without obstacles), the record's
    clearance. Computed once per step, read by the obstacle rows."""
    least = math.inf
    for o in range(int(data[5])):
        r = data[HEADER + o * STRIDE + 6] + data[3]
        for i in range(pts.shape[0] - 1):
            span, dx, dy, dz, cx, cy, cz = link_gap(pts, i, data, o, t)
            d = span - r
            g = gaps[o, i]
            g[0] = d
            if span > 0.0:
                g[1], g[2], g[3] = dx / span, dy / span, dz / span
            else:
                g[1], g[2], g[3] = 0.0, 0.0, 0.0
            g[4], g[5], g[6] = cx, cy, cz
            if d < least:
                least = d
    return least


@kernel
def distance_jacobian(
    data: F64, t: float, pts: F64, axes: F64, i: int, o: int, Jd: F64, x: F64, y: F64
) -> float:
    """The distance ``d`` (m) of link ``i`` to obstacle ``o`` at time ``t`` (returned), its
    closest points ``x`` (link) and ``y`` (obstacle's segment), and ``Jd = d d / d q`` (m/rad)
    for a static obstacle (a moving one adds ``-n . v``): ``n^T J_x`` with ``J_x = (1 - s) J_i +
    s J_(i+1)``, the Jacobian of the link point at its fraction ``s`` along the link."""
    A, B = np.empty(3), np.empty(3)
    r = obstacle_at(data, o, t, A, B)
    span = closest_points(pts[i], pts[i + 1], A, B, x, y)
    length2 = 0.0
    along = 0.0
    for a in range(3):
        seg = pts[i + 1, a] - pts[i, a]
        length2 += seg * seg
        along += (x[a] - pts[i, a]) * seg
    s = along / length2 if length2 > 0.0 else 0.0
    n = axes.shape[0]
    for j in range(n):
        acc = 0.0
        if span > 0.0:
            for k, weight in ((i, 1.0 - s), (i + 1, s)):
                if j >= k or weight == 0.0:
                    continue
                rx, ry, rz = pts[k, 0] - axes[j, 0], pts[k, 1] - axes[j, 1], pts[k, 2] - axes[j, 2]
                ax, ay, az = axes[j, 3], axes[j, 4], axes[j, 5]
                cx, cy, cz = ay * rz - az * ry, az * rx - ax * rz, ax * ry - ay * rx
                acc += weight * ((x[0] - y[0]) * cx + (x[1] - y[1]) * cy + (x[2] - y[2]) * cz)
            acc /= span
        Jd[j] = acc
    return float(span - r - data[3])


def pack(
    centers_a: np.ndarray,
    centers_b: np.ndarray,
    radii: np.ndarray,
    velocities: np.ndarray,
    *,
    influence: float,
    stop: float,
    gain: float,
    link_radius: float,
    dt: float,
) -> list[float]:
    """The packed obstacle data (module notes) from per-obstacle rows (2-D rows get ``z = 0``)."""
    out = [influence, stop, gain, link_radius, dt, float(len(radii))]
    for a, b, r, v in zip(centers_a, centers_b, radii, velocities, strict=True):
        for row in (a, b):
            out += [float(c) for c in row] + [0.0] * (3 - len(row))
        out.append(float(r))
        out += [float(c) for c in v] + [0.0] * (3 - len(v))
    return out
