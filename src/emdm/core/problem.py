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

from dataclasses import dataclass, field

import numpy as np

from ..errors import ScenarioError
from .arm import Matrix, Vector
from .checks import _Checker, _show


def _stack(P1: Matrix, c1: Vector, P2: Matrix, c2: Vector) -> tuple[Matrix, Vector]:
    """The block-diagonal sum of two quadratic terms over consecutive blocks of variables."""
    n1, n2 = c1.size, c2.size
    P = np.zeros((n1 + n2, n1 + n2))
    P[:n1, :n1], P[n1:, n1:] = P1, P2
    return P, np.concatenate((c1, c2))


@dataclass(frozen=True, eq=False, slots=True)
class Objective:
    """A quadratic term ``1/2 x^T P x + c^T x`` over some block of variables.

    Raises :class:`~emdm.errors.ScenarioError` naming ``P`` or ``c`` unless ``P`` is a finite
    k x k matrix and ``c`` a finite vector of k entries (and, in ``+`` and :meth:`stack`, naming
    ``other`` unless it is an Objective, of the same size for ``+``).
    """

    P: Matrix
    c: Vector

    def __post_init__(self) -> None:
        check = _Checker("Objective")
        P = check.array("P", self.P, (None, None), what="a square matrix")
        k = P.shape[0]
        P = check.array("P", P, (k, k), what="a square matrix")
        c = check.array("c", self.c, (k,), what=lambda: f"{k} numbers (one per row of P)")
        object.__setattr__(self, "P", P)
        object.__setattr__(self, "c", c)

    def __add__(self, other: Objective) -> Objective:
        _Checker("Objective +").instance("other", other, Objective, "an Objective")
        if other.c.size != self.c.size:
            raise ScenarioError(
                "Objective +", "other", f"must have {self.c.size} variables, got {other.c.size}"
            )
        return Objective(self.P + other.P, self.c + other.c)

    def stack(self, other: Objective) -> Objective:
        """The sum of two terms over consecutive, disjoint blocks of variables (block diagonal)."""
        _Checker("Objective.stack").instance("other", other, Objective, "an Objective")
        return Objective(*_stack(self.P, self.c, other.P, other.c))


_ARRAYS = ("P", "c", "A", "b", "lb", "ub", "G", "h")
"""The arrays of a :class:`QP`, in the order of its fields."""


@dataclass(frozen=True, eq=False, slots=True)
class QP:
    """``min 1/2 x^T P x + c^T x  s.t.  A x = b, G x <= h, lb <= x <= ub``; the first ``n_joints``
    entries are qd. ``G`` and ``h`` default to no rows (``G`` is 0 x n).

    Raises :class:`~emdm.errors.ScenarioError` naming the field that is not valid: ``c`` a finite
    vector of n entries, ``P`` finite n x n, ``A`` finite k x n, ``b`` finite of k entries,
    ``lb`` and ``ub`` of n entries (each finite or infinite, never NaN), ``n_joints`` an integer
    in [0, n], ``G`` finite m x n and ``h`` finite of m entries. Lists are taken as arrays.
    """

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
        check = _Checker("QP")
        for name in _ARRAYS:  # lists and integer arrays become float arrays
            value = getattr(self, name)
            if not isinstance(value, np.ndarray) or value.dtype != np.float64:
                object.__setattr__(self, name, check.array(name, value, None, finite=None))
        n = check.array("c", self.c, (None,), what="a vector (one entry per variable)").size
        check.array(
            "P", self.P, (n, n), what=lambda: f"{n} x {n} (one row and column per entry of c)"
        )
        A = check.array(
            "A", self.A, (None, n), what=lambda: f"rows of {n} (one column per entry of c)"
        )
        k = A.shape[0]
        check.array("b", self.b, (k,), what=lambda: f"{k} entries (one per row of A)")
        for name in ("lb", "ub"):
            check.array(name, getattr(self, name), (n,), finite=False, what=lambda: f"{n} entries")
        check.count("n_joints", self.n_joints, 0, n)
        if self.G.shape[0] == 0 and self.G.shape[1:] != (n,) and self.h.size == 0:  # no rows
            object.__setattr__(self, "G", np.zeros((0, n)))
            object.__setattr__(self, "h", np.zeros(0))
        rows = self.h.size
        check.array("h", self.h, (rows,), what="a vector (one entry per row of G)")
        check.array("G", self.G, (rows, n), what=lambda: f"{rows} x {n} (one row per entry of h)")

    @classmethod
    def _trusted(
        cls,
        P: Matrix,
        c: Vector,
        A: Matrix,
        b: Vector,
        lb: Vector,
        ub: Vector,
        n_joints: int,
        G: Matrix,
        h: Vector,
    ) -> QP:
        """A program of arrays the program builder made (float64, of consistent shapes, ``G``
        m x n), without the constructor's checks: the per-step path checks nothing twice."""
        qp = object.__new__(cls)
        for name, value in zip(_ARRAYS, (P, c, A, b, lb, ub, G, h), strict=True):
            object.__setattr__(qp, name, value)
        object.__setattr__(qp, "n_joints", n_joints)
        return qp

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
        try:
            return float(0.5 * x @ self.P @ x + self.c @ x)
        except (ValueError, TypeError):  # checked on failure only: solvers call this often
            raise self._not_a_point("objective", x) from None

    def equality_residual(self, x: Vector) -> float:
        """``||A x - b||_inf``."""
        try:
            return float(np.max(np.abs(self.A @ x - self.b)))
        except (ValueError, TypeError):
            raise self._not_a_point("equality_residual", x) from None

    def bound_excess(self, x: Vector) -> float:
        """Largest amount by which ``x`` leaves its bounds or a row ``G x <= h`` (0 when inside)."""
        if np.shape(x) != (self.n,):  # a single value would broadcast
            raise self._not_a_point("bound_excess", x)
        rows = float(np.max(self.G @ x - self.h)) if self.n_rows else 0.0
        return float(max(0.0, np.max(self.lb - x), np.max(x - self.ub), rows))

    def row_slack(self, x: Vector) -> Vector:
        """``h - G x`` (>= 0 where ``x`` keeps the rows; 0 where a row is active)."""
        try:
            return np.asarray(self.h - self.G @ x, dtype=float)
        except (ValueError, TypeError):
            raise self._not_a_point("row_slack", x) from None

    def violation(self, x: Vector) -> float:
        """Largest equality residual or bound excess."""
        return max(self.equality_residual(x), self.bound_excess(x))

    def _not_a_point(self, method: str, x: object) -> ScenarioError:
        """The error of a method given an ``x`` that is not a point of the program."""
        return ScenarioError(
            f"QP.{method}",
            "x",
            f"must be an array of {self.n} numbers (one per variable), got "
            + (f"shape {np.shape(x)}" if isinstance(x, np.ndarray) else _show(x)),
        )

    def with_rhs(self, b: Vector) -> QP:
        """The same program with the task right-hand side ``b`` (e.g. a scaled task ``alpha v``).

        Raises :class:`~emdm.errors.ScenarioError` unless ``b`` is finite, one entry per row of
        ``A``."""
        rows = self.A.shape[0]
        return self._rhs(
            _Checker("QP.with_rhs").array("b", b, (rows,), what=lambda: f"{rows} entries")
        )

    def _rhs(self, b: Vector) -> QP:
        """:meth:`with_rhs` for a checked ``b``."""
        return QP._trusted(
            self.P, self.c, self.A, b, self.lb, self.ub, self.n_joints, self.G, self.h
        )

    def with_free_slack(self, weight: float) -> QP:
        """The program with unbounded task slack ``delta`` (``A x + delta = b``, cost ``w/2 ||delta||^2``).

        A program that already has slack keeps its variables and loses the slack bounds.
        Raises :class:`~emdm.errors.ScenarioError` unless ``weight`` is a finite number > 0.
        """
        return self._free_slack(
            _Checker("QP.with_free_slack").real("weight", weight, positive=True)
        )

    def _free_slack(self, weight: float) -> QP:
        """:meth:`with_free_slack` for a checked ``weight``."""
        if self.n_slack:
            lb, ub = self.lb.copy(), self.ub.copy()
            lb[self.n_joints :], ub[self.n_joints :] = -np.inf, np.inf
            return QP._trusted(
                self.P, self.c, self.A, self.b, lb, ub, self.n_joints, self.G, self.h
            )
        k = self.A.shape[0]
        penalty = slack_penalty(weight, k)
        P, c = _stack(self.P, self.c, penalty.P, penalty.c)
        return QP._trusted(
            P,
            c,
            np.hstack((self.A, np.eye(k))),
            self.b,
            np.concatenate((self.lb, np.full(k, -np.inf))),
            np.concatenate((self.ub, np.full(k, np.inf))),
            self.n_joints,
            np.hstack((self.G, np.zeros((self.n_rows, k)))),
            self.h,
        )


def slack_penalty(weight: float, k: int = 2) -> Objective:
    """``w_S/2 ||delta||^2`` over the ``k`` task-slack variables."""
    return Objective(weight * np.eye(k), np.zeros(k))
