"""The per-step program: a small strictly convex QP, built separately from solving it.

Every program of docs/mathematics.md has the form::

    minimise   1/2 x^T P x + c^T x
    subject to A x = b,   G x <= h,   lb <= x <= ub

with ``x = (qd, delta)``: the joint velocities (rad/s) first, then the task slack (m/s) when the
program has one. ``A`` has one row per task dimension (2 planar, 3 position, 6 pose), ``G`` one row
per general inequality (none in the brief's programs: box bounds stay boxes, the fast path), ``P``
is positive definite (``w_E > 0``, ``w_S > 0``), so the optimum is unique. Bounds are either finite
on both sides or absent (+-inf).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .arm import Matrix, Vector


@dataclass(frozen=True, eq=False, slots=True)
class Objective:
    """A quadratic term ``1/2 x^T P x + c^T x`` over some block of variables."""

    P: Matrix
    c: Vector

    def __add__(self, other: Objective) -> Objective:
        return Objective(self.P + other.P, self.c + other.c)

    def stack(self, other: Objective) -> Objective:
        """The sum of two terms over consecutive, disjoint blocks of variables (block diagonal)."""
        n1, n2 = self.c.size, other.c.size
        P = np.zeros((n1 + n2, n1 + n2))
        P[:n1, :n1], P[n1:, n1:] = self.P, other.P
        return Objective(P, np.concatenate((self.c, other.c)))


@dataclass(frozen=True, eq=False, slots=True)
class QP:
    """``min 1/2 x^T P x + c^T x  s.t.  A x = b, G x <= h, lb <= x <= ub``; the first ``n_joints``
    entries are qd. ``G`` and ``h`` default to no rows (``G`` is 0 x n)."""

    P: Matrix
    c: Vector
    A: Matrix
    b: Vector
    lb: Vector
    ub: Vector
    n_joints: int
    G: Matrix = field(default_factory=lambda: np.zeros((0, 0)))
    h: Vector = field(default_factory=lambda: np.zeros(0))

    def __post_init__(self) -> None:
        if self.G.shape[0] == 0 and self.G.shape[1] != self.c.size:
            object.__setattr__(self, "G", np.zeros((0, self.c.size)))
            object.__setattr__(self, "h", np.zeros(0))
        if self.G.shape != (self.h.size, self.c.size):
            raise ValueError(
                f"G must be {self.h.size} x {self.c.size} (one row per entry of h), "
                f"got {self.G.shape[0]} x {self.G.shape[1]}"
            )

    @property
    def n_rows(self) -> int:
        """Number of inequality rows ``G x <= h``."""
        return int(self.h.size)

    @property
    def n(self) -> int:
        """Number of variables."""
        return int(self.c.size)

    @property
    def n_slack(self) -> int:
        """Number of slack variables (0, or one per task row)."""
        return self.n - self.n_joints

    @property
    def bounded(self) -> bool:
        """True when any variable has finite bounds."""
        return bool(np.isfinite(self.lb).any() or np.isfinite(self.ub).any())

    def objective(self, x: Vector) -> float:
        """``1/2 x^T P x + c^T x``."""
        return float(0.5 * x @ self.P @ x + self.c @ x)

    def equality_residual(self, x: Vector) -> float:
        """``||A x - b||_inf``."""
        return float(np.max(np.abs(self.A @ x - self.b)))

    def bound_excess(self, x: Vector) -> float:
        """Largest amount by which ``x`` leaves its bounds or a row ``G x <= h`` (0 when inside)."""
        rows = float(np.max(self.G @ x - self.h)) if self.n_rows else 0.0
        return float(max(0.0, np.max(self.lb - x), np.max(x - self.ub), rows))

    def row_slack(self, x: Vector) -> Vector:
        """``h - G x`` (>= 0 where ``x`` keeps the rows; 0 where a row is active)."""
        return np.asarray(self.h - self.G @ x, dtype=float)

    def violation(self, x: Vector) -> float:
        """Largest equality residual or bound excess."""
        return max(self.equality_residual(x), self.bound_excess(x))

    def with_rhs(self, b: Vector) -> QP:
        """The same program with the task right-hand side ``b`` (e.g. a scaled task ``alpha v``)."""
        return replace(self, b=np.asarray(b, dtype=float))

    def with_free_slack(self, weight: float) -> QP:
        """The program with unbounded task slack ``delta`` (``A x + delta = b``, cost ``w/2 ||delta||^2``).

        A program that already has slack keeps its variables and loses the slack bounds.
        """
        if self.n_slack:
            lb, ub = self.lb.copy(), self.ub.copy()
            lb[self.n_joints :], ub[self.n_joints :] = -np.inf, np.inf
            return replace(self, lb=lb, ub=ub)
        k = self.A.shape[0]
        objective = Objective(self.P, self.c).stack(slack_penalty(weight, k))
        return QP(
            P=objective.P,
            c=objective.c,
            A=np.hstack((self.A, np.eye(k))),
            b=self.b,
            lb=np.concatenate((self.lb, np.full(k, -np.inf))),
            ub=np.concatenate((self.ub, np.full(k, np.inf))),
            n_joints=self.n_joints,
            G=np.hstack((self.G, np.zeros((self.n_rows, k)))),
            h=self.h,
        )


def slack_penalty(weight: float, k: int = 2) -> Objective:
    """``w_S/2 ||delta||^2`` over the ``k`` task-slack variables."""
    return Objective(weight * np.eye(k), np.zeros(k))
