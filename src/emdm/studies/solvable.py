"""Is a planar obstacle scene solvable at all? A sufficient test on a grid of joint space.

A reactive controller is local: it can stall in a scene that no motion solves (an obstacle in the
sweep of a link between start and goal) and in one that a planner would solve. To tell the two
apart, :func:`proved_solvable` searches joint space for a collision-free path, conservatively:

- the joint box (inside the position dampers' stop distances, which the C- controllers never
  cross) is cut into ``cells`` cells per joint of width ``h_j``;
- a cell is free when, at its centre, every link ``k`` keeps a distance of at least
  ``d_s + m_k`` to every obstacle, with ``m_k = sum_{j<=k} (h_j / 2) sum_{i=j..k} l_i``: moving
  joint ``j`` by ``h_j / 2`` moves no point of link ``k`` by more than ``h_j / 2`` times its
  distance to joint ``j``, so every configuration within half a cell of the centre keeps every
  link at least ``d_s`` away;
- the straight segment between the centres of two face-adjacent free cells stays within half a
  cell of one of them, so a 6-connected chain of free cells from the start's cell to the cell of
  a goal configuration (inverse kinematics over the tool angle) is a collision-free motion.

"Proved" is therefore a lower bound: a scene whose passages are narrower than the margins is
reported as not proved, never the reverse. Circles only (the random scenes' shape).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import ndimage

from ..core.scenario import Scenario
from ..errors import ScenarioError

IK_ANGLES = 2048
"""Tool angles sampled for the goal configurations."""


def _segment_distance(
    ax: np.ndarray, ay: np.ndarray, bx: np.ndarray, by: np.ndarray, c: np.ndarray
) -> np.ndarray:
    """Distance from the point ``c`` to the segments from ``(ax, ay)`` to ``(bx, by)``."""
    ux, uy = bx - ax, by - ay
    wx, wy = c[0] - ax, c[1] - ay
    t = np.clip((wx * ux + wy * uy) / np.maximum(ux * ux + uy * uy, 1e-300), 0.0, 1.0)
    out: np.ndarray = np.hypot(wx - t * ux, wy - t * uy)
    return out


def _grid(scenario: Scenario, cells: int) -> tuple[list[np.ndarray], np.ndarray, np.ndarray]:
    lo = scenario.arm.q_min + scenario.damper.stop
    hi = scenario.arm.q_max - scenario.damper.stop
    h = (hi - lo) / cells
    axes = [lo[j] + (np.arange(cells) + 0.5) * h[j] for j in range(scenario.n)]
    return axes, lo, h


def free_cells(scenario: Scenario, cells: int = 128) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The boolean grid of free cells (shape ``(cells,) * n``), the box's lower corner and the
    cell widths (module docstring)."""
    if scenario.robot.dim != 2 or any(o.shape != "circle" for o in scenario.obstacles):
        raise ScenarioError(
            scenario.name, "obstacles", "proved_solvable: a planar arm among circles only"
        )
    axes, lo, h = _grid(scenario, cells)
    lengths = scenario.planar_arm.lengths
    n = scenario.n
    grids = np.meshgrid(*axes, indexing="ij", sparse=True)
    angle = np.zeros((1,) * n)
    x, y = np.zeros((1,) * n), np.zeros((1,) * n)
    free = np.ones((cells,) * n, dtype=bool)
    stop = scenario.obstacle_damper.stop + scenario.obstacle_damper.link_radius
    for k in range(n):
        angle = angle + grids[k]
        ex, ey = x + lengths[k] * np.cos(angle), y + lengths[k] * np.sin(angle)
        margin = sum(h[j] / 2 * lengths[j : k + 1].sum() for j in range(k + 1))
        for ob in scenario.obstacles:
            free &= _segment_distance(x, y, ex, ey, ob.a) >= stop + margin + ob.radius
        x, y = ex, ey
    return free, lo, h


def goal_configurations(scenario: Scenario) -> np.ndarray:
    """Configurations inside the grid's box that put a 3-link tool at the goal (both elbows,
    :data:`IK_ANGLES` tool angles, each joint wrapped into the box when a turn does)."""
    if scenario.n != 3:
        raise ScenarioError(scenario.name, "arm", "proved_solvable: a 3-link planar arm only")
    l1, l2, l3 = scenario.planar_arm.lengths
    lo = scenario.arm.q_min + scenario.damper.stop
    hi = scenario.arm.q_max - scenario.damper.stop
    out = []
    for phi in np.linspace(-np.pi, np.pi, IK_ANGLES, endpoint=False):
        w = np.asarray(scenario.motion.goal[:2]) - l3 * np.array([np.cos(phi), np.sin(phi)])
        c2 = (w @ w - l1 * l1 - l2 * l2) / (2 * l1 * l2)
        if abs(c2) > 1:
            continue
        for q2 in (np.arccos(c2), -np.arccos(c2)):
            q1 = np.arctan2(w[1], w[0]) - np.arctan2(l2 * np.sin(q2), l1 + l2 * np.cos(q2))
            q = np.array([q1, q2, phi - q1 - q2])
            q = (q - lo) % (2 * np.pi) + lo  # the first turn at or above lo
            if np.all(q <= hi):
                out.append(q)
    return np.array(out).reshape(-1, 3)


def proved_solvable(scenario: Scenario, cells: int = 128) -> dict[str, Any]:
    """Whether a collision-free motion from the start to the goal exists on the grid (module
    docstring): ``{"proved": bool, "free_fraction": float, "cells": cells, "margin": [m_k]}``."""
    free, lo, h = free_cells(scenario, cells)
    labels, _ = ndimage.label(free)

    def cell(q: np.ndarray) -> tuple[int, ...]:
        return tuple(np.clip(((q - lo) // h).astype(int), 0, cells - 1))

    start = labels[cell(scenario.motion.q0)]
    goals = {labels[cell(q)] for q in goal_configurations(scenario)} - {0}
    lengths = scenario.planar_arm.lengths
    return {
        "proved": bool(start != 0 and start in goals),
        "free_fraction": float(free.mean()),
        "cells": cells,
        "margin": [
            float(sum(h[j] / 2 * lengths[j : k + 1].sum() for j in range(k + 1)))
            for k in range(scenario.n)
        ],
    }
