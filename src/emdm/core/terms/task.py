"""The task equality ``J qd + delta = v`` (constraint; brief eq. 13): rows ``A = [J, I]``,
``b = v`` (the slack's identity columns are the slack term's). Reads nothing from the scenario
but the task itself ([motion]); mathematics: "The four programs"."""

from __future__ import annotations

from ..jit import kernel
from ..kernels import ArmData
from .base import F64, ProgramOut, StepInput


@kernel
def write(arm: ArmData, weight: float, data: F64, s: StepInput, out: ProgramOut, rows: int) -> int:
    """``A[:, :n] = J``, ``b = v``."""
    n = s.q.size
    for j in range(n):
        for i in range(out.b.size):
            out.A[i, j] = s.J[i, j]
    for i in range(out.b.size):
        out.b[i] = s.v[i]
    return rows
