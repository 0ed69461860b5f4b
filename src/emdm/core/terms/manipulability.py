"""Manipulability rate ``-w_M M(qd) = -w_M Jm^T qd`` (objective; mathematics.md eq. 8): ``c[j] -= w_M
Jm_j``, so minimising the program maximises the rate of change of manipulability. Weight:
``[weights] manipulability``."""

from __future__ import annotations

from ..jit import kernel
from ..scenario import Scenario
from .base import F64


@kernel(refcount=False, internal=True)
def write(weight: float, Jm: F64, c: F64) -> None:
    """``c[j] += -weight Jm_j`` for every joint."""
    for j in range(Jm.size):
        c[j] += -weight * Jm[j]


def pack(scenario: Scenario) -> list[float]:
    """No numbers of its own."""
    return []
