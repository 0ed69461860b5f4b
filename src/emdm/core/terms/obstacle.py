"""Obstacle dampers (constraint): no link enters the stop distance of an obstacle, in discrete time.

For a link ``[E_0, E_1]`` within reach of an obstacle, with closest points ``x*`` (link) and ``w*``
(obstacle) and ``n = (x* - w*) / ||x* - w*||``, the obstacle lies in the half-space
``n . (y - w*) <= 0`` and every point of the link in ``n . (y - w*) >= ||x* - w*||``. The term
writes one row per endpoint ``E`` of the link, with its half-space distance
``d_E = n . (E - w*) - r - link_radius`` (>= the link's distance ``d``):

    -n^T J_E qd <= gain (d_E - stop) / (influence - stop) - n . v_obs - c_E,

NEO's velocity damper (Haviland and Corke, 2021) written at the endpoints, tightened by ``c_E``,
a bound on the second-order motion of ``E`` over one step at the speeds the joint bounds allow.
Where ``c_E`` would take more than half the damper's own allowance (close to the stop
distance), the joints that move ``E`` are slowed by ``sqrt(allowance / (2 c_E))`` instead
(``c_E`` scales with their speed squared), down to :data:`SLOWEST`: the row keeps half its
allowance, and only within ``c_E (influence - stop) / (8 gain)`` of the stop distance asks the
link to move away.
After the Euler step both endpoints stay at least ``stop`` into the half-space, hence the whole
link, whatever the curvature of the distance (docs/mathematics.md, "Obstacles"); a controller
without joint bounds (unbounded speeds) gets the rows untightened. Data: the packed obstacles of
:mod:`emdm.core.distance`. Reads the program's ``lb, ub``, so it comes after the velocity box and
the joint dampers in a controller.
"""

from __future__ import annotations

import math

from ..distance import HEADER, STRIDE
from ..jit import kernel
from ..scenario import Scenario
from .base import F64, OBSTACLE, ROW_ID

SLOWEST = 0.25
"""The obstacle rows slow a joint to no less than this fraction of its bound: below it, a row
asks the link to move away instead (the arm hovers just outside the stop distance rather than
freezing there). Where that leaves no admissible command, the step is built again with no floor
(standing still is then admissible, and exact)."""


@kernel(refcount=False, internal=True)
def _reach(pts: F64, axes: F64, lb: F64, ub: F64, dt: float) -> None:
    """Per point ``k``: ``pts[k, 3] = c_k`` (m/s), the tightening, and ``pts[k, 4]`` (m), how far
    the point can move in one step.

    With ``u_j = max(|lb_j|, |ub_j|)`` and ``D_m`` the length of the polyline from joint ``m``'s
    axis point to ``pts[k]`` (a bound on their distance whatever ``q``), the second derivatives
    of the point obey ``|d2 E / dq_j dq_l| <= D_max(j,l)``, so over a step ``Delta = dt qd`` the
    remainder of the linear prediction is at most ``1/2 dt^2 sum_jl u_j u_l D_max(j,l) = dt c_k``.
    """
    n = axes.shape[0]
    for k in range(pts.shape[0]):
        joints = min(k, n)
        total = 0.0
        finite = True
        for j in range(joints):
            u = max(abs(lb[j]), abs(ub[j]))
            finite = finite and u < math.inf
            total += u
        if not finite:
            pts[k, 3], pts[k, 4] = 0.0, math.inf
            continue
        # backwards over the joints: D_m from the polyline's lengths, S_m = sum_{j <= m} u_j
        c, first = 0.0, 0.0
        length, at = 0.0, k
        above = total
        for m in range(joints - 1, -1, -1):
            stop_at = int(axes[m, 6])
            while at > stop_at:
                length += math.sqrt(
                    (pts[at, 0] - pts[at - 1, 0]) ** 2
                    + (pts[at, 1] - pts[at - 1, 1]) ** 2
                    + (pts[at, 2] - pts[at - 1, 2]) ** 2
                )
                at -= 1
            u = max(abs(lb[m]), abs(ub[m]))
            below = above - u
            c += length * (above * above - below * below)
            first += length * u
            above = below
        pts[k, 3] = 0.5 * dt * c
        pts[k, 4] = dt * (first + 0.5 * dt * c)


@kernel(refcount=False, internal=True)
def write(
    data: F64,
    pts: F64,
    axes: F64,
    gaps: F64,
    lb: F64,
    ub: F64,
    G: F64,
    h: F64,
    ids: F64,
    rows: int,
    floor: float,
) -> int:
    """Rows of ``G x <= h`` at ``G[rows:]`` for every link and obstacle within reach (module
    notes); returns the new row count (the task slack's columns of a row are 0).

    ``gaps`` are this step's distances and closest points
    (:func:`emdm.core.distance.link_gaps`, computed once for the rows and the record). A pair is
    within reach when the link is closer than ``influence`` or could come within ``stop`` in
    one step (:func:`_reach`, plus the obstacle's own motion). A row's id names its obstacle,
    link and end."""
    influence, stop, gain, lrad, dt = data[0], data[1], data[2], data[3], data[4]
    _reach(pts, axes, lb, ub, dt)
    n = axes.shape[0]
    nx = G.shape[1]
    for j in range(n):  # the joint bounds before any row slowed a joint
        axes[j, 7], axes[j, 8] = lb[j], ub[j]
    for o in range(int(data[5])):
        at = HEADER + o * STRIDE
        r = data[at + 6] + lrad
        vx, vy, vz = data[at + 7], data[at + 8], data[at + 9]
        drift = dt * math.sqrt(vx * vx + vy * vy + vz * vz)
        for i in range(pts.shape[0] - 1):
            gap = gaps[o, i]
            d, nx_, ny_, nz_, cx, cy, cz = gap[0], gap[1], gap[2], gap[3], gap[4], gap[5], gap[6]
            reach = max(pts[i, 4], pts[i + 1, 4]) + drift
            if (d >= influence and d - stop >= reach) or (nx_ == 0.0 and ny_ == 0.0 and nz_ == 0.0):
                continue
            approach = nx_ * vx + ny_ * vy + nz_ * vz
            for e in (i, i + 1):
                if e == 0:
                    continue  # the base never moves
                if e == i + 1 and pts[e, 0] == pts[i, 0] and pts[e, 1] == pts[i, 1]:
                    if pts[e, 2] == pts[i, 2]:
                        continue  # a link of length 0: one point, one row
                d_e = (nx_ * (pts[e, 0] - cx) + ny_ * (pts[e, 1] - cy) + nz_ * (pts[e, 2] - cz)) - r
                top = 0.0  # the largest G_i x the joint bounds allow (they only shrink from
                for j in range(min(e, n)):  # here on): a row above it is implied, left out
                    ax, ay, az = axes[j, 3], axes[j, 4], axes[j, 5]
                    rx, ry, rz = (
                        pts[e, 0] - axes[j, 0],
                        pts[e, 1] - axes[j, 1],
                        pts[e, 2] - axes[j, 2],
                    )
                    g = -(
                        nx_ * (ay * rz - az * ry)
                        + ny_ * (az * rx - ax * rz)
                        + nz_ * (ax * ry - ay * rx)
                    )
                    G[rows, j] = g
                    top += max(g * lb[j], g * ub[j])
                for j in range(min(e, n), nx):
                    G[rows, j] = 0.0
                damp = gain * (d_e - stop) / (influence - stop)
                c_e = pts[e, 3]
                if c_e > 0.5 * damp:  # the worst second-order motion takes more than half
                    # the damper's allowance: slow the joints that move E (c_E scales with
                    # their speed squared) until it takes half, but not below ``floor``
                    scale = max(floor, math.sqrt(max(0.5 * damp, 0.0) / c_e))
                    for j in range(min(e, n)):  # the smallest scale any row asks of joint j
                        lb[j] = max(lb[j], scale * axes[j, 7])
                        ub[j] = min(ub[j], scale * axes[j, 8])
                    c_e *= scale * scale
                h[rows] = damp - approach - c_e
                if h[rows] > top:
                    continue
                ids[rows] = OBSTACLE * ROW_ID + 2 * (o * pts.shape[0] + i) + (e - i)
                rows += 1
    return rows


def pack(scenario: Scenario) -> list[float]:
    """The packed obstacle data of :mod:`emdm.core.distance` (empty without obstacles)."""
    return scenario.obstacle_data
