"""Task slack ``delta`` (objective and bounds; mathematics.md eq. 12-14, 27): ``1/2 w_S ||delta||^2`` with
``w_S = c_S / max(||e||, ERROR_FLOOR)``, the identity columns of the task rows (``J qd + delta =
v``) and ``s_min <= delta <= s_max``. Weight: ``[weights] slack`` (``c_S``); data: ``[slack] min``
then ``[slack] max`` (m/s, one per task row)."""

from __future__ import annotations

from ..jit import kernel
from ..scenario import Scenario
from ..tolerances import ERROR_FLOOR
from .base import F64


@kernel(refcount=False, internal=True)
def write(
    weight: float, data: F64, error_norm: float, n: int, P: F64, A: F64, lb: F64, ub: F64
) -> None:
    """The slack's block of ``P``, its columns of ``A`` and its bounds (``data = [min, max]``),
    after the ``n`` joints."""
    nt = A.shape[0]
    w_s = weight / max(error_norm, ERROR_FLOOR)
    for i in range(nt):
        P[n + i, n + i] += w_s
        for r in range(nt):
            A[r, n + i] = 1.0 if r == i else 0.0
        lb[n + i] = max(lb[n + i], data[i])
        ub[n + i] = min(ub[n + i], data[nt + i])


def pack(scenario: Scenario) -> list[float]:
    """``[slack] min`` then ``[slack] max`` (m/s, one per task row)."""
    return [*map(float, scenario.slack.min), *map(float, scenario.slack.max)]
