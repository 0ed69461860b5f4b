"""The joint-velocity box ``qd_min <= qd <= qd_max`` (constraint; brief eq. 10): tightens ``lb,
ub`` of the joints. Reads ``[arm] qd_min, qd_max`` (rad/s)."""

from __future__ import annotations

from ..jit import kernel
from ..kernels import ArmData
from .base import F64, ProgramOut, StepInput


@kernel
def write(arm: ArmData, weight: float, data: F64, s: StepInput, out: ProgramOut, rows: int) -> int:
    """``lb_j = max(lb_j, qd_min_j)``, ``ub_j = min(ub_j, qd_max_j)``."""
    for j in range(s.q.size):
        out.lb[j] = max(out.lb[j], arm.qd_min[j])
        out.ub[j] = min(out.ub[j], arm.qd_max[j])
    return rows
