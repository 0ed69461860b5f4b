"""Plane dampers (constraint): the end effector keeps its distance to each plane of the scenario's
``[planes]`` above ``stop``. With ``d = n . p - offset`` (m; ``n`` the plane's unit normal toward
the free side, ``p`` the tip's position) and ``d_dot = n^T J_p qd``, a plane within ``influence``
adds the row of the velocity damper (Haviland and Corke's NEO form)

    -n^T J_p qd <= gain (d - stop) / (influence - stop),

so the approach speed falls linearly to zero at the stop distance. ``d`` is not linear in ``q``:
an Euler step can still cross ``stop`` by a second-order term (docs/mathematics.md, "Plane
dampers"). Data: ``[dim, influence, stop, gain, n_1..., offset_1, ...]``."""

from __future__ import annotations

from ..jit import kernel
from ..scenario import Scenario
from .base import F64, PLANE, ROW_ID


@kernel(refcount=False, internal=True)
def write(data: F64, p: F64, J: F64, G: F64, h: F64, ids: F64, rows: int) -> int:
    """One row of ``G x <= h`` at ``G[rows:]`` per plane within its influence distance; returns
    the new row count (the task slack's columns of a row are 0). A row's id is its plane's."""
    dim = int(data[0])
    influence, stop, gain = data[1], data[2], data[3]
    n = J.shape[1]
    for i in range((data.size - 4) // (dim + 1)):
        at = 4 + i * (dim + 1)
        d = -data[at + dim]
        for a in range(dim):
            d += data[at + a] * p[a]
        if d >= influence:
            continue
        for j in range(n):
            acc = 0.0
            for a in range(dim):
                acc += data[at + a] * J[a, j]
            G[rows, j] = -acc
        for j in range(n, G.shape[1]):
            G[rows, j] = 0.0
        h[rows] = gain * (d - stop) / (influence - stop)
        ids[rows] = PLANE * ROW_ID + i
        rows += 1
    return rows


def pack(scenario: Scenario) -> list[float]:
    """``[dim, influence, stop, gain]``, then per plane its unit normal and offset."""
    pl = scenario.planes
    out = [float(pl.normals.shape[1] if pl.count else 0), pl.influence, pl.stop, pl.gain]
    for normal, offset in zip(pl.normals, pl.offsets, strict=True):
        out += [*map(float, normal), float(offset)]
    return out
