"""The task equality ``J qd + delta = v`` (constraint; mathematics.md eq. 12): rows ``A = [J, I]``,
``b = v`` (the slack's identity columns are the slack term's). Reads nothing from the scenario
but the task itself ([motion]); mathematics: "The four programs"."""

from __future__ import annotations

from ..jit import kernel
from ..scenario import Scenario
from .base import F64


@kernel(refcount=False, internal=True)
def write(J: F64, v: F64, A: F64, b: F64) -> None:
    """``A[:, :n] = J``, ``b = v``."""
    for j in range(J.shape[1]):
        for i in range(b.size):
            A[i, j] = J[i, j]
    for i in range(b.size):
        b[i] = v[i]


def pack(scenario: Scenario) -> list[float]:
    """No numbers of its own."""
    return []
