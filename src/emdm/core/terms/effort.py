"""Joint-velocity effort ``w_E E(qd) = w_E/2 ||qd||^2`` (objective; mathematics.md, "Effort and
manipulability rate"): ``P[j, j] += w_E``. Weight: ``[weights] effort`` (1 for IVKC, whose
objective is E alone)."""

from __future__ import annotations

from ..jit import kernel
from ..scenario import Scenario
from .base import F64


@kernel(refcount=False, internal=True)
def write(weight: float, n: int, P: F64) -> None:
    """``P[j, j] += weight`` for the ``n`` joints."""
    for j in range(n):
        P[j, j] += weight


def pack(scenario: Scenario) -> list[float]:
    """No numbers of its own."""
    return []
