"""The one interface every arm model implements: what the control loop, the figures and the
studies ask of a robot, whatever its kinematics.

:class:`~emdm.core.arm.PlanarArm` (links in a plane, ``dim = 2``) and
:class:`~emdm.core.serial.SerialArm` (a DH chain in space, ``dim = 3``) implement it; a
scenario's ``[arm]`` section chooses the model (:attr:`emdm.core.scenario.Scenario.robot`). The
compiled loop reaches both through one kernel, :func:`emdm.core.kernels.task_kinematics`, which
dispatches on the arm's chain; the Python side reaches them through this protocol, so call sites
need not know which model they hold.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

from numpy.typing import ArrayLike

from .arm import Matrix, Vector


@runtime_checkable
class Robot(Protocol):
    """A serial arm of ``n`` joints moving its end effector in a workspace of ``dim`` axes."""

    n: int

    @property
    def dim(self) -> int:
        """Axes of the workspace: 2 for a planar arm, 3 in space."""

    @property
    def reach(self) -> float:
        """Farthest the end effector can be from the base (m)."""

    def joint_positions(self, q: ArrayLike) -> Matrix:
        """The arm's polyline for drawing: base, every joint, end effector (m; rows of ``dim``)."""

    def position(self, q: ArrayLike) -> Vector:
        """End-effector position (m; ``dim`` values)."""

    def position_jacobian(self, q: ArrayLike) -> Matrix:
        """``d position / dq`` (``dim`` x n; m/rad)."""

    def manipulability(self, q: ArrayLike) -> float:
        """Yoshikawa's ``m = sqrt(det(J J^T))`` over the model's Jacobian rows of the task."""

    def manipulability_jacobian(self, q: ArrayLike) -> Vector:
        """``dm/dq`` (n,), finite everywhere (docs/mathematics.md)."""


__all__ = ["Robot"]
