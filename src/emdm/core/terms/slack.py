"""Task slack ``delta`` (objective and bounds; brief section 4): ``1/2 w_S ||delta||^2`` with
``w_S = c_S / max(||e||, ERROR_FLOOR)``, the identity columns of the task rows (``J qd + delta =
v``) and ``s_min <= delta <= s_max``. Weight: ``[weights] slack`` (``c_S``); data: ``[slack] min``
then ``[slack] max`` (m/s, one per task row)."""

from __future__ import annotations

from ..jit import kernel
from ..kernels import ArmData
from .base import F64, ProgramOut, StepInput

ERROR_FLOOR = 1e-9
"""Smallest ``||e||`` (m) used in ``w_S = c_S / ||e||``."""


@kernel
def write(arm: ArmData, weight: float, data: F64, s: StepInput, out: ProgramOut, rows: int) -> int:
    """The slack's block of ``P``, its columns of ``A`` and its bounds (``data = [min, max]``)."""
    n = s.q.size
    nt = out.b.size
    w_s = weight / max(s.error_norm, ERROR_FLOOR)
    for i in range(nt):
        out.P[n + i, n + i] += w_s
        for r in range(nt):
            out.A[r, n + i] = 1.0 if r == i else 0.0
        out.lb[n + i] = max(out.lb[n + i], data[i])
        out.ub[n + i] = min(out.ub[n + i], data[nt + i])
    return rows
