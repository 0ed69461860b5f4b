"""Joint centring (objective; the worked example of docs/architecture.md): minimise the rate of
Liegeois' joint-range index ``H(q) = 1/2 sum_j ((q_j - m_j) / r_j)^2``, ``m = (q_min + q_max)/2``,
``r = q_max - q_min`` (rad): ``w_C grad(H)^T qd`` with ``grad(H)_j = (q_j - m_j) / r_j^2`` (1/rad),
so ``c[j] += w_C (q_j - m_j) / r_j^2``. Along it the joints drift toward the middle of their range
in the task's null space. Weight: ``[weights] centring`` (``w_C``, default 0: the term is left
out of the program). Reads ``[arm] q_min, q_max``."""

from __future__ import annotations

from ..jit import kernel
from ..kernels import ArmData
from .base import F64, ProgramOut, StepInput


@kernel
def slope(q: float, q_min: float, q_max: float) -> float:
    """``dH/dq_j = (q_j - m_j) / r_j^2`` of one joint (1/rad)."""
    r = q_max - q_min
    return (q - 0.5 * (q_min + q_max)) / (r * r)


@kernel
def gradient(q: F64, q_min: F64, q_max: F64, out: F64) -> None:
    """``out = grad H(q)`` (1/rad), the Python API's kernel."""
    for j in range(q.size):
        out[j] = slope(q[j], q_min[j], q_max[j])


@kernel
def write(arm: ArmData, weight: float, data: F64, s: StepInput, out: ProgramOut, rows: int) -> int:
    """``c[j] += weight grad(H)_j`` for every joint."""
    for j in range(s.q.size):
        out.c[j] += weight * slope(s.q[j], arm.q_min[j], arm.q_max[j])
    return rows
