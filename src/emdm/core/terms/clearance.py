"""Clearance (objective): in the task's null space, move the links away from the obstacles
they are close to. With ``V(q) = 1/2 sum ((influence - d) / (influence - stop))^2`` over the
link/obstacle pairs closer than ``influence`` (``d`` their distance, :mod:`emdm.core.distance`),
the term adds ``w_O dV/dt = w_O grad(V)^T qd``, that is ``c[j] -= w_O sum (influence - d) /
(influence - stop)^2 (J_d)_j`` (Maciejewski and Klein's obstacle avoidance as a secondary task,
beside the hard rows of :mod:`.obstacle`). Weight: ``[weights] clearance`` (``w_O``, 0: left
out). Data: the packed obstacles."""

from __future__ import annotations

import numpy as np

from ..distance import distance_jacobian
from ..jit import kernel
from ..scenario import Scenario
from .base import F64


@kernel(internal=True)
def write(weight: float, data: F64, t: float, pts: F64, axes: F64, c: F64) -> None:
    """``c[j] -= weight sum_pairs (influence - d) / (influence - stop)^2 (J_d)_j``."""
    influence, stop = data[0], data[1]
    n = axes.shape[0]
    Jd, x, y = np.empty(n), np.empty(3), np.empty(3)
    scale = weight / ((influence - stop) * (influence - stop))
    for o in range(int(data[5])):
        for i in range(pts.shape[0] - 1):
            d = distance_jacobian(data, t, pts, axes, i, o, Jd, x, y)
            if d >= influence:
                continue
            for j in range(n):
                c[j] -= scale * (influence - d) * Jd[j]


def pack(scenario: Scenario) -> list[float]:
    """The packed obstacle data of :mod:`emdm.core.distance`."""
    return scenario.obstacle_data
