"""The joint-position dampers (constraint; mathematics.md eq. 11): with ``d+ = q_max - q``, ``d- = q -
q_min``, inside the influence zone ``qd_j <= (d+ - s) / (K (i - s))`` and ``qd_j >= -(d- - s) /
(K (i - s))``, each side independently; they tighten ``lb, ub``. Reads ``[arm] q_min, q_max``
and ``[damper] influence, stop, gain`` (rad, rad, -). A joint that starts outside its stop zone
never enters it when ``dt < K (i - s)`` (docs/mathematics.md, "Joint limits")."""

from __future__ import annotations

import math

from ..jit import kernel
from ..kernels import ArmData
from ..scenario import Scenario
from .base import F64


@kernel(refcount=False)
def sides(
    q: float, q_min: float, q_max: float, influence: float, stop: float, gain: float
) -> tuple[float, float]:
    """``(low, high)``: the damper's bounds of one joint (+-inf outside the influence zones)."""
    d_up = q_max - q
    d_dn = q - q_min
    span = gain * (influence - stop)
    high = (d_up - stop) / span if d_up < influence else math.inf
    low = -(d_dn - stop) / span if d_dn < influence else -math.inf
    return low, high


@kernel(refcount=False, internal=True)
def write(data: F64, q: F64, lb: F64, ub: F64) -> None:
    """``lb_j = max(lb_j, low_j)``, ``ub_j = min(ub_j, high_j)`` (:func:`sides`; ``data =
    [q_min, q_max, influence, stop, gain]``, per joint)."""
    n = q.size
    for j in range(n):
        low, high = sides(
            q[j], data[j], data[n + j], data[2 * n + j], data[3 * n + j], data[4 * n + j]
        )
        lb[j] = max(lb[j], low)
        ub[j] = min(ub[j], high)


@kernel(refcount=False)
def bounds(
    q: F64, q_min: F64, q_max: F64, influence: F64, stop: F64, gain: F64, lo: F64, hi: F64
) -> None:
    """The damper bounds alone, per joint, into ``lo`` and ``hi`` (the Python API's kernel)."""
    for j in range(q.size):
        lo[j], hi[j] = sides(q[j], q_min[j], q_max[j], influence[j], stop[j], gain[j])


@kernel(refcount=False)
def joint_bounds(arm: ArmData, q: F64, lo: F64, hi: F64) -> None:
    """The velocity box intersected with the dampers at ``q``: what a constrained controller's
    joints may do (mathematics.md eq. 10, 11)."""
    for j in range(q.size):
        low, high = sides(
            q[j], arm.q_min[j], arm.q_max[j], arm.influence[j], arm.stop[j], arm.gain[j]
        )
        lo[j] = max(arm.qd_min[j], low)
        hi[j] = min(arm.qd_max[j], high)


def pack(scenario: Scenario) -> list[float]:
    """``[arm] q_min, q_max`` and ``[damper] influence, stop, gain``, per joint."""
    d = scenario.damper
    arrays = (scenario.arm.q_min, scenario.arm.q_max, d.influence, d.stop, d.gain)
    return [float(v) for a in arrays for v in a]
