"""How an arm is drawn: its plane, or three orthogonal projections of a spatial arm.

Figures and animations of spatial arms show the base frame from the top (x-y), the front (x-z)
and the side (y-z); every point, path and the translational manipulability ellipsoid is projected
by the same 2 x 3 matrix ``P`` (an ellipsoid ``{J_v qd : ||qd|| <= 1}`` projects onto the ellipse
of ``P J_v``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

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
        stacked = np.vstack(points)
        lo, hi = stacked.min(axis=0), stacked.max(axis=0)
        margin = 0.12 * float((hi - lo).max())
        return np.stack((lo - margin, hi + margin), axis=1)
