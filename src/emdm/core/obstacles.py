"""Obstacles of a scenario: the ``[[obstacles]]`` tables, their validation and their TOML.

A planar scenario takes ``circle`` (``center``, ``radius``) and ``segment`` (a wall: ``points =
[[x, y], [x, y]]``, optional ``radius`` for its thickness); a spatial one ``sphere`` and
``capsule`` in the same form with 3-D points. Every obstacle may move at a constant
``velocity`` (m/s). The damper's numbers are the ``[obstacle_damper]`` section (``influence``,
``stop``, ``gain``, ``link_radius``). All shapes are capsules to the kernels
(:mod:`emdm.core.distance`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from .arm import Vector
from .checks import _Checker, _frozen, _show

SHAPES = {2: ("circle", "segment"), 3: ("sphere", "capsule")}
"""The shapes of a planar (2) and a spatial (3) scenario; the first of each is a point with a
radius, the second a segment with a radius."""
KEYS = ("shape", "center", "points", "radius", "velocity")
MAX_OBSTACLES = 64
"""At most this many obstacles (each adds up to two rows per link to every program)."""
MAX_COORDINATE = 1e6
"""Coordinates, radii and speeds beyond this (m, m/s) mean nothing for an arm."""


@dataclass(frozen=True, eq=False)
class Obstacle:
    """One obstacle: its ``shape``, the segment ``a`` to ``b`` (equal for a circle or sphere; m),
    its ``radius`` (m) and ``velocity`` (m/s), in the scenario's workspace axes."""

    shape: str
    a: Vector
    b: Vector
    radius: float
    velocity: Vector

    def to_dict(self) -> dict[str, Any]:
        """The obstacle as a ``[[obstacles]]`` table."""
        out: dict[str, Any] = {"shape": self.shape}
        if self.shape in ("circle", "sphere"):
            out["center"] = [float(v) for v in self.a]
        else:
            out["points"] = [[float(v) for v in self.a], [float(v) for v in self.b]]
        out["radius"] = float(self.radius)
        if np.any(self.velocity != 0.0):
            out["velocity"] = [float(v) for v in self.velocity]
        return out


def parse_obstacles(check: _Checker, raw: Any, dim: int) -> tuple[Obstacle, ...]:
    """The ``[[obstacles]]`` tables of a scenario with a ``dim``-axis workspace, validated."""
    if not isinstance(raw, list):
        raise check.fail("obstacles", f"must be a list of tables ([[obstacles]]), got {_show(raw)}")
    if len(raw) > MAX_OBSTACLES:
        raise check.fail("obstacles", f"must be at most {MAX_OBSTACLES} tables, got {len(raw)}")
    return tuple(_parse_one(check, table, f"obstacles[{i}]", dim) for i, table in enumerate(raw))


def _parse_one(check: _Checker, table: Any, where: str, dim: int) -> Obstacle:
    if not isinstance(table, Mapping):
        raise check.fail(where, f"must be a table ([[obstacles]]), got {_show(table)}")
    for key in table:
        if key not in KEYS:
            raise check.fail(f"{where}.{key}", f"unknown key (known: {', '.join(KEYS)})")
    point, segment = SHAPES[dim]
    shape = table.get("shape")
    if shape not in SHAPES[dim]:
        kind = "planar" if dim == 2 else "spatial"
        other = SHAPES[5 - dim]
        hint = f" ({' and '.join(other)} are for {'spatial' if dim == 2 else 'planar'} arms)"
        raise check.fail(
            f"{where}.shape",
            f'must be "{point}" or "{segment}" in a {kind} scenario, got {_show(shape)}'
            + (hint if shape in other else ""),
        )
    if shape == point:
        if "points" in table:
            raise check.fail(f"{where}.points", f"is for a {segment}; a {point} has a center")
        if "center" not in table:
            raise check.fail(f"{where}.center", "is required")
        a = _coordinates(check, f"{where}.center", table["center"], dim)
        b = a
        if "radius" not in table:
            raise check.fail(f"{where}.radius", "is required")
    else:
        if "center" in table:
            raise check.fail(f"{where}.center", f"is for a {point}; a {segment} has points")
        if "points" not in table:
            raise check.fail(f"{where}.points", f"is required (two points of {dim} numbers)")
        rows = check.table(f"{where}.points", table["points"], 2, dim)
        _in_range(check, f"{where}.points", rows)
        a, b = _frozen(rows[0]), _frozen(rows[1])
    radius = check.number(f"{where}.radius", table.get("radius", 0.0))
    if not 0.0 <= radius <= MAX_COORDINATE:
        raise check.fail(
            f"{where}.radius", f"must be between 0 and {MAX_COORDINATE:g} m, got {radius:g}"
        )
    if shape == point and radius == 0.0:
        raise check.fail(f"{where}.radius", f"must be > 0 for a {point}, got 0")
    velocity = _coordinates(check, f"{where}.velocity", table.get("velocity", [0.0] * dim), dim)
    return Obstacle(str(shape), a, b, radius, velocity)


def _coordinates(check: _Checker, key: str, value: Any, dim: int) -> Vector:
    out = check.vector(key, value, dim, False)
    _in_range(check, key, out)
    return out


def _in_range(check: _Checker, key: str, values: Vector) -> None:
    bad = np.abs(values.ravel()) > MAX_COORDINATE
    if np.any(bad):
        value = float(values.ravel()[int(np.argmax(bad))])
        raise check.fail(
            key, f"must be between {-MAX_COORDINATE:g} and {MAX_COORDINATE:g}, got {value:g}"
        )


def check_damper(check: _Checker, damper: dict[str, float], dt: float) -> None:
    """``0 <= stop < influence``, ``gain > 0`` and ``gain dt < influence - stop`` (else one step
    of the damper itself could pass the stop distance; docs/mathematics.md, "Obstacles")."""
    if not damper["stop"] < damper["influence"]:
        raise check.fail(
            "obstacle_damper.stop",
            f"must be below obstacle_damper.influence ({damper['influence']:g} m), "
            f"got {damper['stop']:g}",
        )
    if not damper["gain"] > 0.0:
        raise check.fail("obstacle_damper.gain", f"must be positive, got {damper['gain']:g}")
    room = damper["influence"] - damper["stop"]
    if not damper["gain"] * dt < room:
        raise check.fail(
            "obstacle_damper.gain",
            f"must be below (influence - stop) / motion.dt = {room / dt:g} m/s, or one step of "
            f"the damper could pass the stop distance, got {damper['gain']:g}",
        )


def distances(scenario: Any, q: Vector, t: float = 0.0) -> Vector:
    """``D[i, o]``: the distance (m) of link ``i`` (base to first joint first; a last row for the
    tool's segment) to obstacle ``o`` at configuration ``q`` and time ``t`` (s)."""
    from .distance import AXIS, GAP, POINT, chain_points_of, link_gaps

    n = scenario.n
    pts, axes = np.zeros((n + 2, POINT)), np.zeros((n, AXIS))
    chain_points_of(
        scenario.arm_data.lengths, scenario.geometry, np.asarray(q, dtype=float), pts, axes
    )
    gaps = np.zeros((len(scenario.obstacles), n + 1, GAP))
    if scenario.obstacles:
        link_gaps(np.array(scenario.obstacle_data), float(t), pts, gaps)
    return gaps[:, :, 0].T.copy()


def distance_jacobian(
    scenario: Any, q: Vector, link: int, obstacle: int, t: float = 0.0
) -> tuple[float, Vector, Vector, Vector]:
    """``(d, J_d, x, w)``: link ``link``'s distance (m) to obstacle ``obstacle`` at ``q`` and time
    ``t``, its Jacobian ``d d / d q`` (m/rad; a moving obstacle adds ``-n . v`` to ``d d / d t``),
    and the closest points on the link and on the obstacle's segment (3-D; ``z = 0`` in a plane)."""
    from .distance import AXIS, POINT, chain_points_of
    from .distance import distance_jacobian as kernel

    n = scenario.n
    pts, axes = np.zeros((n + 2, POINT)), np.zeros((n, AXIS))
    chain_points_of(
        scenario.arm_data.lengths, scenario.geometry, np.asarray(q, dtype=float), pts, axes
    )
    Jd, x, w = np.zeros(n), np.zeros(3), np.zeros(3)
    data = np.array(scenario.obstacle_data)
    d = kernel(data, float(t), pts, axes, int(link), int(obstacle), Jd, x, w)
    return float(d), Jd, x, w


def check_start(check: _Checker, scenario: Any) -> None:
    """No plane and no obstacle starts within its stop distance of the arm (the dampers forbid
    the stop zones, so a run could not begin)."""
    if scenario.planes.count:
        d = scenario.plane_distances(scenario.motion.q0)
        inside = np.flatnonzero(~(d > scenario.planes.stop))
        if inside.size:
            i = int(inside[0])
            raise check.fail(
                f"planes.offsets[{i}]",
                f"the end effector starts {d[i]:g} m from plane {i + 1}, within its stop distance "
                f"({scenario.planes.stop:g} m), which the plane damper forbids",
            )
    if scenario.obstacles:
        D = distances(scenario, scenario.motion.q0)
        stop = scenario.obstacle_damper.stop
        pairs = np.argwhere(~(D > stop))
        if pairs.size:
            link, o = (int(v) for v in pairs[0])
            raise check.fail(
                f"obstacles[{o}]",
                f"link {link + 1} starts {D[link, o]:g} m from this {scenario.obstacles[o].shape}, "
                f"within the stop distance (obstacle_damper.stop = {stop:g} m), which the "
                "obstacle damper forbids",
            )


def pack_rows(obstacles: tuple[Obstacle, ...]) -> tuple[Vector, Vector, Vector, Vector]:
    """Per obstacle: ``a``, ``b`` (rows), radius, velocity (rows), for :func:`distance.pack`."""
    if not obstacles:
        return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), np.zeros((0, 3))
    return (
        np.array([o.a for o in obstacles]),
        np.array([o.b for o in obstacles]),
        np.array([o.radius for o in obstacles]),
        np.array([o.velocity for o in obstacles]),
    )


__all__ = [
    "SHAPES",
    "Obstacle",
    "check_damper",
    "check_start",
    "distance_jacobian",
    "distances",
    "pack_rows",
    "parse_obstacles",
]
