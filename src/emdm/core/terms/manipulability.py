"""Manipulability rate ``-w_M M(qd) = -w_M Jm^T qd`` (objective; brief eq. 7): ``c[j] -= w_M
Jm_j``, so minimising the program maximises the rate of change of manipulability. Weight:
``[weights] manipulability``."""

from __future__ import annotations

from ..jit import kernel
from ..kernels import ArmData
from .base import F64, ProgramOut, StepInput


@kernel
def write(arm: ArmData, weight: float, data: F64, s: StepInput, out: ProgramOut, rows: int) -> int:
    """``c[j] += -weight Jm_j`` for every joint."""
    for j in range(s.q.size):
        out.c[j] += -weight * s.Jm[j]
    return rows
