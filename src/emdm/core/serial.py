"""Serial arm with revolute joints in 3-D, from Denavit-Hartenberg parameters.

``SerialArm(dh=[[a, alpha, d, offset], ...], convention="standard" | "modified", tool=...)`` (m,
rad), with the conventions of robotics-toolbox-python's ``DHRobot``:

- a standard DH link is ``Rz(theta) Tz(d) Tx(a) Rx(alpha)``; a modified (Craig) DH link is
  ``Rx(alpha) Tx(a) Rz(theta) Tz(d)``; ``theta = q + offset``;
- ``forward(q)``: the 4 x 4 pose of the end effector in the base frame, the tool transform last;
- ``jacobian(q)``: the 6 x n geometric Jacobian in the base frame, linear rows first (``jacob0``):
  column ``k`` is ``(z_k x (p_e - o_k), z_k)`` for joint ``k``'s axis ``z_k`` through ``o_k``;
- ``hessian(q)``: ``H[i] = dJ/dq_i`` (n x 6 x n, ``hessian0``), from the Jacobian alone:
  ``dv_k/dq_i = z_min(i,k) x v_max(i,k)``, ``dz_k/dq_i = z_i x z_k`` for ``i < k`` (else 0);
- ``manipulability(q, axes)``: ``m = sqrt(det(Ja Ja^T))`` over the rows ``axes`` selects (``"all"``,
  ``"trans"``: the three linear rows, ``"rot"``: the three angular rows);
- ``manipulability_jacobian(q, axes)``: ``Jm_i = dm/dq_i = m trace((Ja Ja^T)^-1 Ja Ha_i^T)``
  (``jacobm``), computed from the singular values so that it stays finite at a singularity
  (see :func:`emdm.core.serial_kernels.manipulability_gradient`).

Every formula is one compiled kernel in :mod:`emdm.core.serial_kernels`.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import ScenarioError
from .serial_kernels import (
    ROWS_ALL,
    ROWS_ROT,
    ROWS_TRANS,
    manipulability_gradient,
    serial_hessian,
    serial_kinematics,
)

Matrix = NDArray[np.float64]
Axes = Literal["all", "trans", "rot"]
_ROWS = {"all": ROWS_ALL, "trans": ROWS_TRANS, "rot": ROWS_ROT}


def _tool(tool: ArrayLike | None) -> Matrix:
    """The tool transform: ``None`` (identity), a translation ``(x, y, z)`` (m) or a 4 x 4 pose."""
    if tool is None:
        return np.eye(4)
    arr = np.array(tool, dtype=float)
    if arr.shape == (3,):
        out = np.eye(4)
        out[:3, 3] = arr
        arr = out
    if arr.shape != (4, 4) or not np.all(np.isfinite(arr)):
        raise ScenarioError(
            "SerialArm", "tool", "must be a translation [x, y, z] (m) or a finite 4 x 4 transform"
        )
    rotation = arr[:3, :3]
    if not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-9) or not np.allclose(
        arr[3], [0.0, 0.0, 0.0, 1.0]
    ):
        raise ScenarioError(
            "SerialArm",
            "tool",
            "must be a rigid transform (orthonormal rotation, last row 0 0 0 1)",
        )
    return np.ascontiguousarray(arr)


class SerialArm:
    """A serial chain of ``n >= 1`` revolute joints from DH rows ``[a, alpha, d, offset]``."""

    def __init__(
        self,
        dh: ArrayLike,
        convention: Literal["standard", "modified"] = "standard",
        tool: ArrayLike | None = None,
    ) -> None:
        table = np.array(dh, dtype=float)
        if table.ndim != 2 or table.shape[1] != 4 or table.shape[0] < 1:
            raise ScenarioError(
                "SerialArm", "dh", "needs one row [a, alpha, d, offset] (m, rad, m, rad) per joint"
            )
        if not np.all(np.isfinite(table)):
            raise ScenarioError("SerialArm", "dh", "every DH parameter must be finite")
        if convention not in ("standard", "modified"):
            raise ScenarioError(
                "SerialArm", "convention", f'must be "standard" or "modified", got {convention!r}'
            )
        self.dh: Matrix = np.ascontiguousarray(table)
        self.dh.setflags(write=False)
        self._dh = self.dh.copy()  # writable: one compiled signature
        self.convention = convention
        self.modified = convention == "modified"
        self.tool: Matrix = _tool(tool)
        self.n: int = int(table.shape[0])

    def __repr__(self) -> str:
        return f"SerialArm(dh={self.dh.tolist()}, convention={self.convention!r})"

    dim = 3
    """Axes of the workspace (the :class:`~emdm.core.robot.Robot` interface)."""

    @property
    def reach(self) -> float:
        """Farthest the end effector can be from the base (m): ``|a| + |d|`` over the DH rows plus
        the tool's length."""
        return float(
            np.sum(np.abs(self.dh[:, 0]) + np.abs(self.dh[:, 2])) + np.linalg.norm(self.tool[:3, 3])
        )

    def joint_positions(self, q: ArrayLike) -> Matrix:
        """Origins of the base and of every link frame, then the end effector: (n + 2) x 3 (m)."""
        origins = self.link_frames(q)[:, :3, 3]
        return np.vstack((origins, self.forward(q)[:3, 3]))

    def position(self, q: ArrayLike) -> Matrix:
        """End-effector position (m, 3 values)."""
        return np.asarray(self.forward(q)[:3, 3])

    def position_jacobian(self, q: ArrayLike) -> Matrix:
        """The linear rows of the geometric Jacobian (3 x n; m/rad)."""
        return np.asarray(self.jacobian(q)[:3])

    def _check_q(self, q: ArrayLike) -> Matrix:
        q_arr = np.ascontiguousarray(q, dtype=float)
        if q_arr.shape != (self.n,):
            raise ScenarioError(
                "SerialArm", "q", f"expected {self.n} joint angles, got shape {q_arr.shape}"
            )
        return q_arr

    def _kinematics(self, q: ArrayLike) -> tuple[Matrix, Matrix, Matrix]:
        """Link frames ((n + 1) x 4 x 4), end-effector pose and Jacobian at ``q``."""
        frames = np.empty((self.n + 1, 4, 4))
        T, J = np.empty((4, 4)), np.empty((6, self.n))
        serial_kinematics(
            self._dh, self.modified, self.tool, self._check_q(q), frames, np.empty((4, 4)), T, J
        )
        return frames, T, J

    def link_frames(self, q: ArrayLike) -> Matrix:
        """Poses of the base and of every link frame ((n + 1) x 4 x 4, base frame), for drawing."""
        return self._kinematics(q)[0]

    def forward(self, q: ArrayLike) -> Matrix:
        """Pose of the end effector in the base frame (4 x 4; m)."""
        return self._kinematics(q)[1]

    def jacobian(self, q: ArrayLike) -> Matrix:
        """Geometric Jacobian in the base frame (6 x n), linear rows (m/rad) first."""
        return self._kinematics(q)[2]

    def hessian(self, q: ArrayLike) -> NDArray[np.float64]:
        """Kinematic Hessian ``H[i] = dJ/dq_i`` (n x 6 x n) in the base frame."""
        H = np.empty((self.n, 6, self.n))
        serial_hessian(self.jacobian(q), H)
        return H

    def manipulability(self, q: ArrayLike, axes: Axes = "all") -> float:
        """``m = sqrt(det(Ja Ja^T))`` over the Jacobian rows ``axes`` selects."""
        return self.manipulability_and_jacobian(q, axes)[0]

    def manipulability_jacobian(self, q: ArrayLike, axes: Axes = "all") -> Matrix:
        """``Jm = dm/dq`` (n,) for the manipulability over the rows ``axes`` selects."""
        return self.manipulability_and_jacobian(q, axes)[1]

    def manipulability_and_jacobian(self, q: ArrayLike, axes: Axes = "all") -> tuple[float, Matrix]:
        """``(m, Jm)`` together, from one Jacobian and Hessian."""
        if axes not in _ROWS:
            raise ScenarioError(
                "SerialArm", "axes", f'must be "all", "trans" or "rot", got {axes!r}'
            )
        J = self.jacobian(q)
        H = np.empty((self.n, 6, self.n))
        serial_hessian(J, H)
        Jm = np.empty(self.n)
        m = manipulability_gradient(J, H, _ROWS[axes], Jm)
        return float(m), Jm
