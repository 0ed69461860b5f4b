"""Joint limits as velocity bounds: the velocity box and the position dampers (brief eq. 10, 11).

For joint ``j`` with distances ``d+ = q_max - q`` and ``d- = q - q_min`` to its limits, the damper
bounds are applied on each side independently, only inside the influence zone:

    qd_j <=  (1/K_safe) (d+ - s) / (i - s)     when d+ < i
    qd_j >= -(1/K_safe) (d- - s) / (i - s)     when d- < i

With ``dt < K_safe (i - s)`` a joint that starts outside its stop zone never enters it: every step
multiplies ``d - s`` by at least ``1 - dt / (K_safe (i - s)) > 0``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .arm import Vector


@dataclass(frozen=True, eq=False, slots=True)
class Bounds:
    """Per-joint velocity bounds ``lo <= qd <= hi`` (rad/s); +-inf where a side is unbounded."""

    lo: Vector
    hi: Vector

    def __and__(self, other: Bounds) -> Bounds:
        """The intersection of two sets of bounds."""
        return Bounds(np.maximum(self.lo, other.lo), np.minimum(self.hi, other.hi))

    @classmethod
    def free(cls, n: int) -> Bounds:
        """No bounds at all (the unconstrained, UC, controllers)."""
        return cls(np.full(n, -np.inf), np.full(n, np.inf))


def velocity_box(qd_min: Vector, qd_max: Vector) -> Bounds:
    """``qd_min <= qd <= qd_max`` (brief eq. 10)."""
    return Bounds(np.array(qd_min, dtype=float), np.array(qd_max, dtype=float))


def position_damper(
    q: Vector, *, q_min: Vector, q_max: Vector, influence: Vector, stop: Vector, gain: Vector
) -> Bounds:
    """Velocity bounds from the joint-position dampers (brief eq. 11), both sides independently."""
    d_up, d_down = q_max - q, q - q_min
    span = gain * (influence - stop)
    hi = np.where(d_up < influence, (d_up - stop) / span, np.inf)
    lo = np.where(d_down < influence, -(d_down - stop) / span, -np.inf)
    return Bounds(lo, hi)
