"""Joint-velocity effort ``w_E E(qd) = w_E/2 ||qd||^2`` (objective; brief eq. 6): ``P[j, j] +=
w_E``. Weight: ``[weights] effort`` (1 for IVKC, whose objective is E alone)."""

from __future__ import annotations

from ..jit import kernel
from ..kernels import ArmData
from .base import F64, ProgramOut, StepInput


@kernel
def write(arm: ArmData, weight: float, data: F64, s: StepInput, out: ProgramOut, rows: int) -> int:
    """``P[j, j] += weight`` for every joint."""
    for j in range(s.q.size):
        out.P[j, j] += weight
    return rows
