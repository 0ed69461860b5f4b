"""Joint limits as velocity bounds: the velocity box and the position dampers (mathematics.md eq. 10, 11).

For joint ``j`` with distances ``d+ = q_max - q`` and ``d- = q - q_min`` to its limits, the damper
bounds are applied on each side independently, only inside the influence zone:

    qd_j <=  (1/K_safe) (d+ - s) / (i - s)     when d+ < i
    qd_j >= -(1/K_safe) (d- - s) / (i - s)     when d- < i

A joint that starts outside its stop zone never enters it when two conditions hold: inside the
influence zone, ``dt < K_safe (i - s)`` (every step multiplies ``d - s`` by at least
``1 - dt / (K_safe (i - s)) > 0``); outside it, ``max |qd| dt <= i - s`` (one step at the velocity
limit cannot jump over the zone). The scenario loader warns when either fails.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .arm import Vector
from .terms.damper import bounds as damper_bounds


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
    """``qd_min <= qd <= qd_max`` (mathematics.md eq. 10)."""
    return Bounds(np.array(qd_min, dtype=float), np.array(qd_max, dtype=float))


def position_damper(
    q: Vector, *, q_min: Vector, q_max: Vector, influence: Vector, stop: Vector, gain: Vector
) -> Bounds:
    """Velocity bounds from the joint-position dampers (mathematics.md eq. 11), both sides independently
    (the compiled :func:`emdm.core.terms.damper.bounds`)."""
    q_arr = np.ascontiguousarray(q, dtype=float)
    lo, hi = np.empty(q_arr.size), np.empty(q_arr.size)
    q_lo, q_hi, inf, stp, gn = (
        np.array(a, dtype=float) for a in (q_min, q_max, influence, stop, gain)
    )
    damper_bounds(q_arr, q_lo, q_hi, inf, stp, gn, lo, hi)
    return Bounds(lo, hi)
