"""The joint-velocity box ``qd_min <= qd <= qd_max`` (constraint; mathematics.md eq. 10): tightens ``lb,
ub`` of the joints. Reads ``[arm] qd_min, qd_max`` (rad/s)."""

from __future__ import annotations

from ..jit import kernel
from ..scenario import Scenario
from .base import F64


@kernel(refcount=False, internal=True)
def write(data: F64, n: int, lb: F64, ub: F64) -> None:
    """``lb_j = max(lb_j, qd_min_j)``, ``ub_j = min(ub_j, qd_max_j)`` for the ``n`` joints
    (``data = [qd_min, qd_max]``)."""
    for j in range(n):
        lb[j] = max(lb[j], data[j])
        ub[j] = min(ub[j], data[n + j])


def pack(scenario: Scenario) -> list[float]:
    """``[arm] qd_min`` then ``qd_max`` (rad/s, per joint)."""
    return [*map(float, scenario.arm.qd_min), *map(float, scenario.arm.qd_max)]
