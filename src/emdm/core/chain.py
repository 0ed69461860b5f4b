"""A serial chain in URDF's semantics, the one form of every spatial arm (:mod:`emdm.core.serial`):
per joint a fixed transform ``origin`` from the frame of the previous joint, then its motion about
(revolute) or along (prismatic) its unit ``axis``; a fixed ``tail`` after the last joint. DH rows
convert to it (:meth:`Chain.from_dh`), URDF files read into it (:mod:`emdm.core.urdf`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Matrix = NDArray[np.float64]


def _rx(angle: float) -> Matrix:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1]])


def _rz(angle: float) -> Matrix:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1.0, 0], [0, 0, 0, 1]])


def _shift(x: float = 0.0, z: float = 0.0) -> Matrix:
    out = np.eye(4)
    out[0, 3], out[2, 3] = x, z
    return out


@dataclass(frozen=True, eq=False)
class Chain:
    """A serial chain in URDF's semantics (module notes): per joint its ``origins`` (n x 4 x 4),
    unit ``axes`` (n x 3, in the joint's frame) and ``prismatic`` flags (n,), the fixed ``tail``
    after the last joint (4 x 4), the joints' ``names``, and ``travel``: the largest ``|q|`` of
    each prismatic joint (m; 0 for a revolute one), so that :attr:`SerialArm.reach` bounds the
    arm."""

    origins: Matrix
    axes: Matrix
    prismatic: NDArray[np.bool_]
    tail: Matrix
    names: tuple[str, ...]
    travel: Matrix

    @property
    def n(self) -> int:
        """Number of joints."""
        return int(self.axes.shape[0])

    @classmethod
    def from_dh(cls, dh: Matrix, modified: bool) -> Chain:
        """The chain of DH rows ``[a, alpha, d, offset]`` (module notes)."""
        n = dh.shape[0]
        origins = np.empty((n, 4, 4))
        for i, (a, alpha, d, offset) in enumerate(dh):
            if modified:
                origins[i] = _rx(alpha) @ _shift(x=a) @ _rz(offset) @ _shift(z=d)
            else:
                before = np.eye(4) if i == 0 else _shift(x=dh[i - 1, 0]) @ _rx(dh[i - 1, 1])
                origins[i] = before @ _shift(z=d) @ _rz(offset)
        tail = np.eye(4) if modified else _shift(x=dh[-1, 0]) @ _rx(dh[-1, 1])
        axes = np.zeros((n, 3))
        axes[:, 2] = 1.0
        names = tuple(f"joint{i + 1}" for i in range(n))
        return cls(origins, axes, np.zeros(n, dtype=bool), tail, names, np.zeros(n))


__all__ = ["Chain"]
