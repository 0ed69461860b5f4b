"""How an arm is drawn: its plane, or three orthogonal projections of a spatial arm.

Figures and animations of spatial arms show the base frame from the top (x-y), the front (x-z)
and the side (y-z); every point, path and the translational manipulability ellipsoid is projected
by the same 2 x 3 matrix ``P`` (an ellipsoid ``{J_v qd : ||qd|| <= 1}`` projects onto the ellipse
of ``P J_v``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib.patches import Polygon

from ..core.arm import Matrix
from ..core.scenario import Scenario
from ..sim.loop import Run


class Views:
    """How a scenario's arm is drawn: one view of the plane, or three orthogonal projections."""

    def __init__(self, sc: Scenario) -> None:
        self.scenario = sc
        if sc.robot.dim == 3:
            self.projections = [np.eye(3)[[0, 1]], np.eye(3)[[0, 2]], np.eye(3)[[1, 2]]]
            self.names = ["top (x-y)", "front (x-z)", "side (y-z)"]
            self.axes = [("x", "y"), ("x", "z"), ("y", "z")]
        else:
            self.projections = [np.eye(2)]
            self.names = [""]
            self.axes = [("x", "y")]

    def joints(self, q: np.ndarray) -> Matrix:
        """Points of the arm's polyline: base, every joint, the end effector (m; 2 or 3 columns)."""
        return np.asarray(self.scenario.robot.joint_positions(q))

    def jacobian(self, q: np.ndarray) -> Matrix:
        """The translational Jacobian (2 or 3 rows)."""
        return np.asarray(self.scenario.robot.position_jacobian(q))

    def position(self, run: Run) -> Matrix:
        """End-effector positions of a run's states (m; 2 or 3 columns)."""
        return np.asarray(run.p[:, :3])

    def limits(self, runs: Sequence[Run]) -> Matrix:
        """Per coordinate, the range (2 x 2 or 3 x 2, m) of a view that holds every arm, path
        and goal: the reach disc for a planar arm, the points' extent plus a margin in 3-D."""
        sc = self.scenario
        if sc.robot.dim == 2:
            reach = float(sc.robot.reach) * 1.08
            return np.array([[-reach, reach], [-reach, reach]])
        points = [self.joints(q) for run in runs for q in run.q[:: max(1, run.steps // 20)]]
        points += [self.position(run) for run in runs]
        points.append(np.asarray(sc.motion.goal[:3])[None, :])
        for ob in sc.obstacles:  # every obstacle whole, at its start
            for end in (ob.a, ob.b):
                points.append(np.stack((end - ob.radius, end + ob.radius)))
        stacked = np.vstack(points)
        lo, hi = stacked.min(axis=0), stacked.max(axis=0)
        margin = 0.12 * float((hi - lo).max())
        return np.stack((lo - margin, hi + margin), axis=1)

    def obstacle_outlines(self, P: Matrix, t: float = 0.0, grow: float = 0.0) -> list[Matrix]:
        """Each obstacle at time ``t`` (s), grown by ``grow`` (m), as the outline of its
        projection by ``P`` (a disc, or the stadium of a capsule; k x 2 points, m)."""
        out = []
        for ob in self.scenario.obstacles:
            a = P @ _pad(ob.a + ob.velocity * t, P.shape[1])
            b = P @ _pad(ob.b + ob.velocity * t, P.shape[1])
            out.append(_stadium(a, b, ob.radius + grow))
        return out

    def draw_obstacles(self, ax: Any, P: Matrix, *, animated: bool = False) -> list[Any]:
        """Draw the obstacles (grey) and their stop distance (dashed) at ``t = 0``; returns the
        patches, two per obstacle, for :meth:`move_obstacles`."""
        stop = self.scenario.obstacle_damper.stop
        patches = []
        for body, zone in zip(
            self.obstacle_outlines(P), self.obstacle_outlines(P, grow=stop), strict=True
        ):
            patches.append(
                ax.add_patch(
                    Polygon(
                        body,
                        closed=True,
                        facecolor="#777777",
                        edgecolor="#444444",
                        linewidth=0.8,
                        alpha=0.55,
                        animated=animated,
                        zorder=1,
                    )
                )
            )
            patches.append(
                ax.add_patch(
                    Polygon(
                        zone,
                        closed=True,
                        fill=False,
                        edgecolor="#444444",
                        linewidth=0.6,
                        linestyle=(0, (2, 2)),
                        animated=animated,
                        zorder=1,
                    )
                )
            )
        return patches

    def move_obstacles(self, patches: list[Any], P: Matrix, t: float) -> None:
        """Put the patches of :meth:`draw_obstacles` where the obstacles are at time ``t``."""
        stop = self.scenario.obstacle_damper.stop
        outlines = self.obstacle_outlines(P, t)
        zones = self.obstacle_outlines(P, t, grow=stop)
        for i, (body, zone) in enumerate(zip(outlines, zones, strict=True)):
            patches[2 * i].set_xy(body)
            patches[2 * i + 1].set_xy(zone)

    @property
    def moving(self) -> bool:
        """Whether some obstacle moves."""
        return any(np.any(ob.velocity != 0.0) for ob in self.scenario.obstacles)


def _pad(point: np.ndarray, dim: int) -> np.ndarray:
    return np.asarray(point, dtype=float)[:dim]


def _stadium(a: np.ndarray, b: np.ndarray, r: float, k: int = 24) -> Matrix:
    """Outline of the set of points within ``r`` of the segment ``[a, b]`` in the plane."""
    d = b - a
    length = float(np.hypot(*d))
    angle = float(np.arctan2(d[1], d[0])) if length > 0 else 0.0
    half = np.linspace(-np.pi / 2, np.pi / 2, k)
    end_b = b + r * np.stack((np.cos(angle + half), np.sin(angle + half)), axis=1)
    end_a = a + r * np.stack((np.cos(angle + np.pi + half), np.sin(angle + np.pi + half)), axis=1)
    return np.vstack((end_b, end_a))
