"""Joint centring (objective; the worked example of docs/architecture.md): minimise the rate of
Liegeois' joint-range index ``H(q) = 1/2 sum_j ((q_j - m_j) / r_j)^2``, ``m = (q_min + q_max)/2``,
``r = q_max - q_min`` (rad): ``w_C grad(H)^T qd`` with ``grad(H)_j = (q_j - m_j) / r_j^2`` (1/rad),
so ``c[j] += w_C (q_j - m_j) / r_j^2``. Along it the joints drift toward the middle of their range
in the task's null space. Weight: ``[weights] centring`` (``w_C``, default 0: the term is left
out of the program). Reads ``[arm] q_min, q_max``."""

from __future__ import annotations

from ..jit import kernel
from ..scenario import Scenario
from .base import F64


@kernel(refcount=False)
def slope(q: float, q_min: float, q_max: float) -> float:
    """``dH/dq_j = (q_j - m_j) / r_j^2`` of one joint (1/rad)."""
    r = q_max - q_min
    return (q - 0.5 * (q_min + q_max)) / (r * r)


@kernel(refcount=False)
def gradient(q: F64, q_min: F64, q_max: F64, out: F64) -> None:
    """``out = grad H(q)`` (1/rad), the Python API's kernel."""
    for j in range(q.size):
        out[j] = slope(q[j], q_min[j], q_max[j])


@kernel(refcount=False, internal=True)
def write(weight: float, data: F64, q: F64, c: F64) -> None:
    """``c[j] += weight grad(H)_j`` for every joint (``data = [q_min, q_max]``)."""
    n = q.size
    for j in range(n):
        c[j] += weight * slope(q[j], data[j], data[n + j])


def pack(scenario: Scenario) -> list[float]:
    """``[arm] q_min`` then ``q_max`` (rad, per joint)."""
    return [*map(float, scenario.arm.q_min), *map(float, scenario.arm.q_max)]
