"""Planar n-link arm with revolute joints: kinematics, manipulability and its Jacobian.

Conventions (docs/mathematics.md): link lengths ``l`` (m), joint angles ``q`` (rad), absolute angles
``th_i = q_1 + ... + q_i``, base at the origin.

Everything is built on the *tip vectors* ``r_j = sum_{i >= j} l_i (cos th_i, sin th_i)``, the vector
from joint ``j`` to the end effector:

- Jacobian column ``j``: ``J_j = perp(r_j)`` with ``perp(x, y) = (-y, x)``.
- Hessian slices ``H_j = dJ/dq_j``: column ``k`` of ``H_j`` is ``-r_max(j,k)``.
- Manipulability ``m = sqrt(det(J J^T))``. By the Cauchy-Binet formula ``det(J J^T) = sum_{i<k} c_ik^2``
  with the 2x2 minors ``c_ik = det[J_i, J_k] = cross(r_i, r_k)``, so ``m = ||c||``: a sum of squares,
  never negative, accurate near singular configurations where ``a11 a22 - a12^2`` cancels.
- Manipulability Jacobian ``Jm = G^T c / m`` with ``G = dc/dq``; since ``dr_i/dq_j = perp(r_max(i,j))``,
  ``dc_ik/dq_j = R[i, max(k,j)] - R[max(i,j), k]`` with the Gram matrix ``R = r^T r``. This equals the
  textbook ``Jm_j = m trace((J J^T)^-1 J H_j^T)`` wherever ``m > 0`` (tested), and is bounded by
  ``||G||`` however close to a singularity.

Singular configurations (``m = 0``): ``m`` is not differentiable there (it behaves like ``|x|``), so the
formula is 0/0. We return the *steepest one-sided ascent direction* ``Jm = s1 v1``, where ``(s1, v1)``
is the leading singular pair of ``G``: for unit ``d``, the one-sided derivative of ``m`` along ``d`` is
``||G d||``, largest along ``+-v1``, and equal to ``Jm . d`` along ``v1``. This is the limit of the
gradient when leaving the singularity along ``v1``. ``v1`` is signed so that its largest-magnitude
component is positive (the two senses are symmetric). This keeps EMDM able to leave a singularity,
never produces NaN and never raises. "Singular" means ``m <= 1e-14 * (sum l)^2``: below that the
minors are rounding noise. Two-link check: ``m = l1 l2 |sin q2|``,
``Jm = (0, l1 l2 cos q2 sign(sin q2))``, and at ``q2 = 0``: ``Jm = (0, l1 l2)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import ScenarioError
from .checks import _Checker, memory_available
from .kernels import kinematics_of

Vector = NDArray[np.float64]
Matrix = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class Kinematics:
    """Everything the controllers need at one configuration.

    ``p`` end-effector position (m, shape 2), ``J`` Jacobian (m/rad, 2 x n), ``m`` manipulability
    (m^2/rad^2 for n = 2; in general the product of the singular values of J), ``Jm`` manipulability
    Jacobian (d m / d q, shape n).
    """

    p: Vector
    J: Matrix
    m: float
    Jm: Vector


class PlanarArm:
    """A planar arm with ``n >= 2`` revolute joints and link lengths ``lengths`` (m, all > 0).

    Raises :class:`~emdm.errors.ScenarioError` naming ``lengths`` (or, in the methods, ``q``:
    ``n`` finite joint angles) when it is not a valid argument.
    """

    def __init__(self, lengths: ArrayLike) -> None:
        if lengths is not None:  # the kind of its entries (None: refused below)
            _Checker("PlanarArm").array(
                "lengths", lengths, None, finite=None, what="a list of link lengths (m)"
            )
        lengths_arr = np.array(lengths, dtype=float)
        if lengths_arr.ndim != 1 or lengths_arr.size < 2:
            raise ScenarioError("PlanarArm", "lengths", "needs a list of at least 2 link lengths")
        if not np.all(np.isfinite(lengths_arr)) or np.any(lengths_arr <= 0):
            raise ScenarioError(
                "PlanarArm", "lengths", f"must be finite and > 0, got {lengths_arr}"
            )
        n = lengths_arr.size
        need, have = 8 * (n * (n - 1) // 2 * (n + 1) + 2 * n), memory_available()
        if have and need > have // 2:  # the kinematics' buffers (kernels.kin_work)
            raise ScenarioError(
                "PlanarArm",
                "lengths",
                f"{n} links need about {need / 1e9:.3g} GB for the kinematics' buffers, more "
                f"than half of this machine's {have / 1e9:.3g} GB: use fewer links",
            )
        self._kernel_lengths = lengths_arr.copy()  # writable: one compiled signature
        lengths_arr.setflags(write=False)
        self.lengths: Vector = lengths_arr
        self.n: int = int(lengths_arr.size)

    def __repr__(self) -> str:
        return f"PlanarArm(lengths={self.lengths.tolist()})"

    # ----------------------------------------------------------------- geometry
    dim = 2
    """Axes of the workspace (the :class:`~emdm.core.robot.Robot` interface)."""

    def position(self, q: ArrayLike) -> Vector:
        """End-effector position (m): :meth:`forward` (the Robot interface)."""
        return self.forward(q)

    def position_jacobian(self, q: ArrayLike) -> Matrix:
        """``dp/dq`` (2 x n): :meth:`jacobian` (the Robot interface)."""
        return self.jacobian(q)

    @property
    def reach(self) -> float:
        """Outer radius of the reachable workspace (m): the sum of the link lengths."""
        return float(self.lengths.sum())

    @property
    def inner_reach(self) -> float:
        """Inner radius of the reachable annulus (m): ``max(0, 2 max(l) - sum(l))``."""
        return max(0.0, float(2.0 * self.lengths.max() - self.lengths.sum()))

    def _check_q(self, q: ArrayLike) -> Vector:
        check = _Checker("PlanarArm")
        q_arr = check.array("q", q, None, what=lambda: f"{self.n} joint angles (rad)")
        if q_arr.shape != (self.n,):
            raise ScenarioError(
                "PlanarArm", "q", f"expected {self.n} joint angles, got {q_arr.shape}"
            )
        return q_arr

    def link_vectors(self, q: ArrayLike) -> Matrix:
        """Link vectors ``l_i (cos th_i, sin th_i)`` as the columns of a 2 x n array (m)."""
        th = np.cumsum(self._check_q(q))
        return np.stack((np.cos(th), np.sin(th))) * self.lengths

    def tip_vectors(self, q: ArrayLike) -> Matrix:
        """Tip vectors ``r_j`` (joint j to end effector) as the columns of a 2 x n array (m)."""
        links = self.link_vectors(q)
        return np.cumsum(links[:, ::-1], axis=1)[:, ::-1]

    def joint_positions(self, q: ArrayLike) -> Matrix:
        """Positions of the base, every joint and the end effector: an (n + 1) x 2 array (m)."""
        links = self.link_vectors(q)
        points: Matrix = np.zeros((self.n + 1, 2))
        points[1:] = np.cumsum(links, axis=1).T
        return points

    def forward(self, q: ArrayLike) -> Vector:
        """End-effector position ``p = f(q)`` (m), mathematics.md eq. (1)."""
        return self.kinematics(q).p

    def jacobian(self, q: ArrayLike) -> Matrix:
        """Manipulator Jacobian ``J = dp/dq`` (2 x n, m/rad), mathematics.md eq. (3)."""
        return self.kinematics(q).J

    def hessian(self, q: ArrayLike) -> NDArray[np.float64]:
        """Hessian slices ``H[j] = dJ/dq_j`` (n x 2 x n): column k of ``H[j]`` is ``-r_max(j,k)``."""
        r = self.tip_vectors(q)
        joints = np.arange(self.n)
        max_jk = np.maximum(joints[:, None], joints[None, :])
        return np.transpose(-r[:, max_jk], (1, 0, 2))

    def manipulability(self, q: ArrayLike) -> float:
        """Manipulability ``m(q) = sqrt(det(J J^T))``, mathematics.md eq. (6)."""
        return self.kinematics(q).m

    def manipulability_jacobian(self, q: ArrayLike) -> Vector:
        """Manipulability Jacobian ``Jm = dm/dq`` (n,), mathematics.md eq. (8); see the module
        notes at m = 0."""
        return self.kinematics(q).Jm

    def kinematics(self, q: ArrayLike) -> Kinematics:
        """Position, Jacobian, manipulability and its Jacobian, computed together by the compiled
        kernel :func:`emdm.core.kernels.kinematics` (the one implementation of these formulas)."""
        q_arr = np.ascontiguousarray(self._check_q(q))
        p, J, Jm = np.empty(2), np.empty((2, self.n)), np.empty(self.n)
        m = kinematics_of(self._kernel_lengths, q_arr, p, J, Jm)
        return Kinematics(p=p, J=J, m=m, Jm=Jm)
