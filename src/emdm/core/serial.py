"""Serial arm in 3-D: a chain of revolute and prismatic joints, from Denavit-Hartenberg parameters or
a URDF file.

Every arm is held as one chain (:class:`~emdm.core.chain.Chain`): per joint a fixed transform
``origin`` from the frame of the previous joint, then the joint's motion, a rotation by ``q``
about its unit ``axis`` (revolute) or a translation by ``q`` along it (prismatic), in that frame;
a fixed ``tail`` after the last joint. These are URDF's joint semantics (:mod:`emdm.core.urdf`
reads a file into a chain), and DH rows are one case of them:

- ``SerialArm(dh=[[a, alpha, d, offset], ...], convention="standard" | "modified", tool=...)``
  (m, rad), with the conventions of robotics-toolbox-python's ``DHRobot``: a standard DH link is
  ``Rz(theta) Tz(d) Tx(a) Rx(alpha)``, a modified (Craig) DH link ``Rx(alpha) Tx(a) Rz(theta)
  Tz(d)``, ``theta = q + offset``. As a chain (``Tz`` and ``Rz`` commute): standard, joint ``i``'s
  origin is ``Tx(a_(i-1)) Rx(alpha_(i-1)) Tz(d_i) Rz(offset_i)`` and the tail ``Tx(a_n)
  Rx(alpha_n)``; modified, joint ``i``'s origin is ``Rx(alpha_i) Tx(a_i) Rz(offset_i) Tz(d_i)``
  and the tail the identity; every axis is ``z``;
- ``SerialArm.from_urdf(path, base_link=..., tip_link=..., tool=...)``: the chain of a URDF file;
- ``forward(q)``: the 4 x 4 pose of the end effector in the base frame, the tool transform last;
- ``jacobian(q)``: the 6 x n geometric Jacobian in the base frame, linear rows first (``jacob0``):
  column ``k`` is ``(z_k x (p_e - o_k), z_k)`` for a revolute joint ``k``'s axis ``z_k`` through
  ``o_k``, ``(z_k, 0)`` for a prismatic one;
- ``hessian(q)``: ``H[i] = dJ/dq_i`` (n x 6 x n, ``hessian0``), from the Jacobian alone; for
  revolute joints ``dv_k/dq_i = z_min(i,k) x v_max(i,k)``, ``dz_k/dq_i = z_i x z_k`` for
  ``i < k`` (else 0); prismatic joints in :func:`emdm.core.serial_kernels.serial_hessian`;
- ``manipulability(q, axes)``: ``m = sqrt(det(Ja Ja^T))`` over the rows ``axes`` selects (``"all"``,
  ``"trans"``: the three linear rows, ``"rot"``: the three angular rows);
- ``manipulability_jacobian(q, axes)``: ``Jm_i = dm/dq_i = m trace((Ja Ja^T)^-1 Ja Ha_i^T)``
  (``jacobm``), computed from the singular values so that it stays finite at a singularity
  (see :func:`emdm.core.serial_kernels.manipulability_gradient`).

Every formula is one compiled kernel in :mod:`emdm.core.serial_kernels`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import ScenarioError
from .chain import Chain
from .checks import _Checker
from .kernels import Geometry
from .serial_kernels import (
    ROWS_ALL,
    ROWS_ROT,
    ROWS_TRANS,
    chain_kinematics,
    manipulability_gradient,
    serial_hessian,
)
from .urdf import read_urdf

Matrix = NDArray[np.float64]
Axes = Literal["all", "trans", "rot"]
_ROWS = {"all": ROWS_ALL, "trans": ROWS_TRANS, "rot": ROWS_ROT}


def _tool(tool: ArrayLike | None, source: str = "SerialArm", key: str = "tool") -> Matrix:
    """The tool transform: ``None`` (identity), a translation ``(x, y, z)`` (m) or a 4 x 4 pose."""
    if tool is None:
        return np.eye(4)
    what = "a translation [x, y, z] (m) or a finite 4 x 4 transform"
    arr = np.array(_Checker(source).array(key, tool, None, finite=None, what=what))
    if arr.shape == (3,):
        out = np.eye(4)
        out[:3, 3] = arr
        arr = out
    if arr.shape != (4, 4) or not np.all(np.isfinite(arr)):
        raise ScenarioError(
            source, key, "must be a translation [x, y, z] (m) or a finite 4 x 4 transform"
        )
    rotation = arr[:3, :3]
    if not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-9) or not np.allclose(
        arr[3], [0.0, 0.0, 0.0, 1.0]
    ):
        raise ScenarioError(
            source,
            key,
            "must be a rigid transform (orthonormal rotation, last row 0 0 0 1)",
        )
    return np.ascontiguousarray(arr)


class SerialArm:
    """A serial chain of ``n >= 1`` joints: DH rows ``[a, alpha, d, offset]`` (revolute joints)
    or, through :meth:`from_urdf` and :meth:`from_chain`, any chain of revolute and prismatic
    joints.

    Raises :class:`~emdm.errors.ScenarioError` naming the argument (``dh``, ``convention``,
    ``tool``, ``path``, ``chain``; in the methods ``q``, ``n`` finite joint values, and
    ``axes``) when it is not valid.
    """

    dh: Matrix | None
    """The DH rows (None for an arm from a URDF file or a chain)."""

    def __init__(
        self,
        dh: ArrayLike,
        convention: Literal["standard", "modified"] = "standard",
        tool: ArrayLike | None = None,
    ) -> None:
        what = "one row [a, alpha, d, offset] (m, rad, m, rad) per joint"
        table = np.array(_Checker("SerialArm").array("dh", dh, None, finite=None, what=what))
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
        self._set_chain(Chain.from_dh(table, convention == "modified"), _tool(tool))
        self.dh = np.ascontiguousarray(table)
        self.dh.setflags(write=False)
        self.convention: str = convention

    @classmethod
    def from_chain(cls, chain: Chain, tool: ArrayLike | None = None) -> SerialArm:
        """The arm of a :class:`Chain`, with a ``tool`` (translation or 4 x 4) after its tail."""
        _Checker("SerialArm.from_chain").instance("chain", chain, Chain, "a Chain")
        arm = cls.__new__(cls)
        arm._set_chain(chain, _tool(tool))
        arm.dh = None
        arm.convention = "urdf"
        return arm

    @classmethod
    def from_urdf(
        cls,
        path: str | Path,
        *,
        base_link: str | None = None,
        tip_link: str | None = None,
        tool: ArrayLike | None = None,
    ) -> SerialArm:
        """The arm of a URDF file from ``base_link`` to ``tip_link`` (:func:`emdm.core.urdf.read_urdf`;
        each may be omitted where the file leaves one choice)."""
        check = _Checker("SerialArm.from_urdf")
        check.instance("path", path, (str, Path), "the path of a URDF file")
        for key, link in (("base_link", base_link), ("tip_link", tip_link)):
            if link is not None:
                check.text(key, link, "a link's name")
        return cls.from_chain(read_urdf(path, base_link, tip_link).chain, tool)

    def _set_chain(self, chain: Chain, tool: Matrix) -> None:
        self.chain = chain
        self.n: int = chain.n
        self.tool: Matrix = tool
        self._origins = np.ascontiguousarray(chain.origins, dtype=float)
        self._axes = np.ascontiguousarray(chain.axes, dtype=float)
        self._prismatic = np.ascontiguousarray(chain.prismatic, dtype=np.bool_)
        self._end = np.ascontiguousarray(chain.tail @ tool)  # the tail, then the tool

    def geometry(self, rows: int) -> Geometry:
        """The chain as kernel input, with the manipulability's Jacobian ``rows``
        (``serial_kernels.ROWS_*``); the tool is the chain's tail, then the tool."""
        return Geometry(self._origins, self._axes, self._prismatic, self._end, rows)

    def __repr__(self) -> str:
        if self.dh is None:
            return f"SerialArm(chain of {self.n} joints: {', '.join(self.chain.names)})"
        return f"SerialArm(dh={self.dh.tolist()}, convention={self.convention!r})"

    dim = 3
    """Axes of the workspace (the :class:`~emdm.core.robot.Robot` interface)."""

    @property
    def reach(self) -> float:
        """Farthest the end effector can be from the base (m): ``|a| + |d|`` over the DH rows plus
        the tool's length; for any other chain, the lengths of its fixed translations plus the
        largest travel of each prismatic joint (:attr:`~emdm.core.chain.Chain.travel`)."""
        if self.dh is not None:
            return float(
                np.sum(np.abs(self.dh[:, 0]) + np.abs(self.dh[:, 2]))
                + np.linalg.norm(self.tool[:3, 3])
            )
        fixed = np.linalg.norm(self._origins[:, :3, 3], axis=1).sum()
        return float(fixed + np.linalg.norm(self._end[:3, 3]) + self.chain.travel.sum())

    def joint_positions(self, q: ArrayLike) -> Matrix:
        """The base, the origin of every joint's frame (on its axis), then the end effector:
        (n + 2) x 3 (m)."""
        origins = self.link_frames(q)[:, :3, 3]
        return np.vstack((origins, self.forward(q)[:3, 3]))

    def position(self, q: ArrayLike) -> Matrix:
        """End-effector position (m, 3 values)."""
        return np.asarray(self.forward(q)[:3, 3])

    def position_jacobian(self, q: ArrayLike) -> Matrix:
        """The linear rows of the geometric Jacobian (3 x n; m/rad)."""
        return np.asarray(self.jacobian(q)[:3])

    def _check_q(self, q: ArrayLike) -> Matrix:
        check = _Checker("SerialArm")
        q_arr = check.array("q", q, None, what=lambda: f"{self.n} joint values")
        if q_arr.shape != (self.n,):
            raise ScenarioError(
                "SerialArm", "q", f"expected {self.n} joint values, got shape {q_arr.shape}"
            )
        return np.ascontiguousarray(q_arr)

    def _kinematics(self, q: ArrayLike) -> tuple[Matrix, Matrix, Matrix]:
        """Link frames ((n + 1) x 4 x 4), end-effector pose and Jacobian at ``q``."""
        frames = np.empty((self.n + 1, 4, 4))
        T, J = np.empty((4, 4)), np.empty((6, self.n))
        chain_kinematics(
            self._origins,
            self._axes,
            self._prismatic,
            self._end,
            self._check_q(q),
            frames,
            np.empty((4, 4)),
            T,
            J,
        )
        return frames, T, J

    def link_frames(self, q: ArrayLike) -> Matrix:
        """Poses of the base and of the frame after every joint ((n + 1) x 4 x 4, base frame)."""
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
        serial_hessian(self.jacobian(q), self._prismatic, H)
        return H

    def manipulability(self, q: ArrayLike, axes: Axes = "all") -> float:
        """``m = sqrt(det(Ja Ja^T))`` over the Jacobian rows ``axes`` selects."""
        return self.manipulability_and_jacobian(q, axes)[0]

    def manipulability_jacobian(self, q: ArrayLike, axes: Axes = "all") -> Matrix:
        """``Jm = dm/dq`` (n,) for the manipulability over the rows ``axes`` selects."""
        return self.manipulability_and_jacobian(q, axes)[1]

    def manipulability_and_jacobian(self, q: ArrayLike, axes: Axes = "all") -> tuple[float, Matrix]:
        """``(m, Jm)`` together, from one Jacobian and Hessian."""
        if not isinstance(axes, str) or axes not in _ROWS:
            raise ScenarioError(
                "SerialArm", "axes", f'must be "all", "trans" or "rot", got {axes!r}'
            )
        return self._manipulability(self.jacobian(q), axes)

    def state(self, q: ArrayLike) -> tuple[Matrix, Matrix, float, Matrix]:
        """``(T, J, m, Jm)`` at ``q`` from one pass of the kinematics: the end-effector pose,
        the geometric Jacobian, the manipulability over all six rows and its gradient (what
        :meth:`forward`, :meth:`jacobian` and :meth:`manipulability_and_jacobian` give, each
        computing the kinematics again)."""
        _, T, J = self._kinematics(q)
        m, Jm = self._manipulability(J, "all")
        return T, J, m, Jm

    def _manipulability(self, J: Matrix, axes: Axes) -> tuple[float, Matrix]:
        H = np.empty((self.n, 6, self.n))
        Jm = np.empty(self.n)
        m = manipulability_gradient(
            J, self._prismatic, H, _ROWS[axes], Jm, np.empty((2 * self.n + 2, 6))
        )
        return float(m), Jm
