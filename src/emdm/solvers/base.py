"""Solver results, the independent KKT certificate, the registry and the fallback chain.

A solver is a plain function ``solve(qp) -> SolverResult``. Whatever it claims, the chain checks its
answer with :func:`kkt_report`, which knows nothing of the solver: it finds the best multipliers for
``x`` by non-negative least squares and measures how far ``x`` is from satisfying the KKT conditions

    P x + c = A^T lam + mu_lower - mu_upper - G^T nu,   mu >= 0,   nu >= 0,
    A x = b,   G x <= h,   lb <= x <= ub,
    mu_lower_j (x_j - lb_j) = 0,   mu_upper_j (ub_j - x_j) = 0,   nu_i (h_i - G_i x) = 0.

For a strictly convex QP these conditions characterise the unique optimum, so a small report proves
the answer optimal. A solver that raises, returns NaN, a non-optimal point or runs out of budget
hands the program to the next solver in the chain, and the record says so.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any, Protocol

import numpy as np

from ..core.arm import Vector
from ..core.checks import _Checker
from ..core.problem import QP
from ..errors import NoSolution, SolverNotFound
from .kernels import BOUND_TOL, KKT_TOL, certify_of, multipliers_of

UNSUPPORTED_ROWS = "unsupported: inequality rows G x <= h"
"""Status of a solver written for bounds only, given a program with inequality rows."""


@dataclass(frozen=True, slots=True)
class SolverResult:
    """What one solver returned for one program.

    ``status`` is ``"optimal"`` when the solver claims optimality, else a short reason
    (``"infeasible"``, ``"max_iter"``, ``"error: ..."``, ``"unsupported"``).
    """

    x: Vector | None
    status: str
    iterations: int
    time: float
    history: tuple[dict[str, float], ...] = ()
    evaluations: int = 0
    """Objective evaluations (a method that evaluates none: 0)."""
    gradients: int = 0
    """Gradient evaluations (a gradient-based method's; gradient-free and QP methods: 0)."""


@dataclass(frozen=True, slots=True)
class KKTReport:
    """Residuals of the KKT conditions at a point (relative, except ``bound_excess``)."""

    stationarity: float
    equality: float
    complementarity: float
    bound_excess: float

    @property
    def residual(self) -> float:
        """The largest relative residual."""
        return max(self.stationarity, self.equality, self.complementarity)

    def is_optimal(self, tol: float = KKT_TOL, bound_tol: float = BOUND_TOL) -> bool:
        """True when every residual is within tolerance."""
        return self.residual <= tol and self.bound_excess <= bound_tol


def kkt_report(qp: QP, x: Vector) -> KKTReport:
    """Measure how far ``x`` is from the optimum of ``qp``, with the best sign-feasible multipliers.

    The compiled certificate (:func:`emdm.solvers.kernels.certify`): non-negative least squares
    over the bounds active at ``x`` finds the multipliers, so nothing the solver claims is used.
    A non-finite ``x`` has an infinite report. Raises :class:`~emdm.errors.ScenarioError` unless
    ``qp`` is a QP and ``x`` a vector of its ``qp.n`` variables.
    """
    check = _Checker("kkt_report")
    check.instance("qp", qp, QP, "a QP")
    x = check.array("x", x, (qp.n,), finite=None, what=lambda: f"{qp.n} numbers (one per variable)")
    return _kkt_report(qp, x)


def _kkt_report(qp: QP, x: Vector) -> KKTReport:
    """:func:`kkt_report` of checked arguments."""
    if not np.all(np.isfinite(x)):
        return KKTReport(math.inf, math.inf, math.inf, math.inf)
    out = np.empty(4)
    certify_of(*_arrays(qp), np.ascontiguousarray(x, dtype=float), out)
    return KKTReport(*map(float, out))


@dataclass(frozen=True, slots=True)
class Multipliers:
    """The certificate's multipliers at a point: ``lam`` of the task rows, signed ``mu`` of the
    bounds (> 0 at the lower, < 0 at the upper bound), ``nu >= 0`` of the rows ``G x <= h``."""

    lam: Vector
    mu: Vector
    nu: Vector
    report: KKTReport

    @property
    def active_rows(self) -> np.ndarray:
        """Indices of the rows ``G x <= h`` with a positive multiplier."""
        return np.flatnonzero(self.nu > 0.0)


def multipliers(qp: QP, x: Vector) -> Multipliers:
    """The best sign-feasible multipliers at ``x`` and the KKT report they give (the certificate
    of :func:`kkt_report`, with what it found)."""
    out = np.empty(4)
    lam, mu, nu = multipliers_of(*_arrays(qp), np.ascontiguousarray(x, dtype=float), out)
    return Multipliers(lam, mu, nu, KKTReport(*map(float, out)))


def _arrays(
    qp: QP,
) -> tuple[Vector, Vector, Vector, Vector, Vector, Vector, Vector, Vector]:
    """The program's arrays as the kernels take them: ``(P, c, A, b, G, h, lb, ub)``."""
    P, c, A, b, G, h, lb, ub = (
        np.ascontiguousarray(a, dtype=float)
        for a in (qp.P, qp.c, qp.A, qp.b, qp.G, qp.h, qp.lb, qp.ub)
    )
    return P, c, A, b, G, h, lb, ub


# --------------------------------------------------------------------------------- registry
class Family(StrEnum):
    """How a solver searches: exactly (finite termination), with gradients, or without."""

    EXACT = "exact"
    GRADIENT = "gradient"
    GRADIENT_FREE = "gradient-free"

    @property
    def label(self) -> str:
        """The family as a table or legend names it (ADMM is first-order, not an NLP method)."""
        return {
            Family.EXACT: "exact QP methods",
            Family.GRADIENT: "first-order (admm) and gradient-based",
            Family.GRADIENT_FREE: "gradient-free",
        }[self]


class Loop(StrEnum):
    """Where a solver's loop runs: wholly in compiled code, or with Python in it (a Python
    driver around compiled steps, as scipy's SLSQP, numpy calls, or the objective called back
    from Python at each evaluation). Solve times compare these implementations as well as the
    methods; evaluation and iteration counts compare the methods alone."""

    COMPILED = "compiled"
    PYTHON = "Python"


class SolveFunction(Protocol):
    """A solver: the program in, a :class:`SolverResult` out; ``history=True`` asks for a
    per-iteration trace. Gradient-free solvers also take ``budget`` (function evaluations)."""

    def __call__(self, qp: QP, /, *, history: bool = ...) -> SolverResult: ...


@dataclass(frozen=True)
class SolverSpec:
    """A registered solver: its name, family (exact, gradient, gradient-free), where its
    iterations run (:class:`Loop`) and how to get it."""

    name: str
    family: Family
    solve: SolveFunction
    description: str
    extra: str | None = None
    is_available: Callable[[], bool] = field(default=lambda: True)
    loop: Loop = Loop.COMPILED
    method: str = ""
    """What kind of method it is, in a few plain words, for a reader who does not know its name
    ("sequential quadratic programming"); empty where the name says it (active-set)."""


_REGISTRY: dict[str, SolverSpec] = {}


def register(spec: SolverSpec) -> SolverSpec:
    """Add a solver to the registry (names are unique, lower case)."""
    _REGISTRY[spec.name] = spec
    return spec


def registered_solvers() -> dict[str, SolverSpec]:
    """Every registered solver, installed or not."""
    return dict(_REGISTRY)


def available_solvers() -> list[str]:
    """Names of the solvers that can run on this machine."""
    return [name for name, spec in _REGISTRY.items() if spec.is_available()]


def get_solver(name: str) -> SolverSpec:
    """The solver called ``name``; an unknown or missing one raises :class:`SolverNotFound`, a
    ``name`` that is not a string :class:`~emdm.errors.ScenarioError`."""
    if not isinstance(name, str) or not name:
        _Checker("get_solver").text("name", name, "a solver's name")
    spec = _REGISTRY.get(name.lower())
    if spec is None or not spec.is_available():
        extras: dict[str, list[str]] = {}
        for other in _REGISTRY.values():
            if other.extra and not other.is_available():
                extras.setdefault(other.extra, []).append(other.name)
        how = "".join(
            f"; {', '.join(names)} with pip install 'emdm[{extra}]'"
            for extra, names in extras.items()
        )
        what = "not installed" if spec is not None else "unknown solver"
        raise SolverNotFound(f"{what} {name!r} (installed: {', '.join(available_solvers())}{how})")
    return spec


def infeasible(qp: QP) -> bool:
    """True when no point satisfies ``A x = b`` and ``G x <= h`` within the bounds (exact test,
    emdm.feasibility).

    The iterative and general-purpose solvers call this first (their phase 1), so an infeasible
    program is reported infeasible, never answered with a wrong point.
    """
    from ..core.feasibility import _feasible_point

    return _feasible_point(qp.A, qp.b, qp.lb, qp.ub, qp.G, qp.h) is None


# ------------------------------------------------------------------------------ the chain
@dataclass(frozen=True, slots=True)
class ChainResult:
    """The accepted answer of a fallback chain, with everything a record needs."""

    x: Vector
    solver: str
    status: str
    iterations: int
    time: float
    kkt: KKTReport
    fallback: bool
    attempts: tuple[tuple[str, str], ...]


def solve_chain(
    qp: QP,
    chain: Sequence[str],
    *,
    tol: float = KKT_TOL,
    context: str = "",
    certify: bool = True,
    budget: int | None = None,
) -> ChainResult:
    """Try each solver of ``chain`` in turn; accept the first answer whose KKT report is optimal.

    With ``certify=False`` the first finite answer is accepted whatever its KKT report (used to
    study inexact solvers in closed loop; the report is still recorded). ``budget`` is the
    evaluation budget of the chain's gradient-free solvers (None: each one's default). Raises
    :class:`~emdm.errors.NoSolution` when no answer is accepted, naming every attempt;
    :class:`~emdm.errors.SolverNotFound` for an unknown solver; and
    :class:`~emdm.errors.ScenarioError` naming the argument that is not valid: ``qp`` a QP,
    ``chain`` a non-empty list of solver names, ``tol`` a finite number > 0, ``context`` a
    string, ``certify`` True or False, ``budget`` None or an integer >= 1.
    """
    check = _Checker("solve_chain")
    check.instance("qp", qp, QP, "a QP")
    if not check.names("chain", chain, "solver names"):
        raise check.fail("chain", "must name at least one solver")
    tol = check.real("tol", tol, positive=True)
    check.instance("context", context, str, "a string")
    check.flag("certify", certify)
    if budget is not None:
        budget = check.count("budget", budget, 1, MAX_BUDGET)
    return _solve_chain(qp, chain, tol=tol, context=context, certify=certify, budget=budget)


MAX_BUDGET = 10**9
"""The largest evaluation budget a caller may give (a typo's guard, far above any use)."""


def _solve_chain(
    qp: QP,
    chain: Sequence[str],
    *,
    tol: float = KKT_TOL,
    context: str = "",
    certify: bool = True,
    budget: int | None = None,
) -> ChainResult:
    """:func:`solve_chain` of checked arguments (the per-step path)."""
    attempts: list[tuple[str, str]] = []
    total = 0.0
    for position, name in enumerate(chain):
        spec = get_solver(name)
        try:
            options: dict[str, Any] = {}
            if budget is not None and spec.family == "gradient-free":
                options["budget"] = budget
            result = spec.solve(qp, **options)
        except Exception as exc:  # a faulty solver must not end the run: record and fall back
            attempts.append((name, f"raised {type(exc).__name__}: {exc}"))
            continue
        total += result.time
        if result.x is None or not np.all(np.isfinite(result.x)):
            attempts.append((name, result.status if result.x is None else "non-finite answer"))
            continue
        if np.shape(result.x) != qp.c.shape:  # the certificate's kernel would read past it
            attempts.append((name, f"an answer of shape {np.shape(result.x)}, not ({qp.n},)"))
            continue
        report = _kkt_report(qp, result.x)
        if certify and not report.is_optimal(tol):
            attempts.append(
                (
                    name,
                    f"not certified (it says {result.status}; KKT residual "
                    f"{report.residual:.1e}, limit {tol:.0e}; bound excess "
                    f"{report.bound_excess:.1e}, limit {BOUND_TOL:.0e})",
                )
            )
            continue
        attempts.append(
            (name, "optimal" if report.is_optimal(tol) else f"accepted ({result.status})")
        )
        return ChainResult(
            result.x,
            name,
            result.status,
            result.iterations,
            total,
            report,
            position > 0,
            tuple(attempts),
        )
    detail = "; ".join(f"{n}: {s}" for n, s in attempts)
    raise NoSolution(f"{context}no solver found the optimum ({detail})", problem=qp)
