"""Solver results, the independent KKT certificate, the registry and the fallback chain.

A solver is a plain function ``solve(qp) -> SolverResult``. Whatever it claims, the chain checks its
answer with :func:`kkt_report`, which knows nothing of the solver: it finds the best multipliers for
``x`` by non-negative least squares and measures how far ``x`` is from satisfying the KKT conditions

    P x + c = A^T lam + mu_lower - mu_upper,   mu >= 0,   A x = b,   lb <= x <= ub,
    mu_lower_j (x_j - lb_j) = 0,   mu_upper_j (ub_j - x_j) = 0.

For a strictly convex QP these conditions characterise the unique optimum, so a small report proves
the answer optimal. A solver that raises, returns NaN, a non-optimal point or runs out of budget
hands the program to the next solver in the chain, and the record says so.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.optimize import nnls

from ..core.arm import Vector
from ..core.problem import QP
from ..errors import NoSolution, SolverNotFound

KKT_TOL = 1e-9
"""Largest relative KKT residual accepted as optimal."""
BOUND_TOL = 1e-12
"""Largest bound excess accepted (rad/s or m/s)."""


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

    @property
    def found(self) -> bool:
        """True when the solver returned a finite point and claims it optimal."""
        return self.status == "optimal" and self.x is not None and bool(np.all(np.isfinite(self.x)))


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


def kkt_report(qp: QP, x: Vector, *, active_tol: float = 1e-9) -> KKTReport:
    """Measure how far ``x`` is from the optimum of ``qp``, with the best sign-feasible multipliers."""
    if not np.all(np.isfinite(x)):
        return KKTReport(math.inf, math.inf, math.inf, math.inf)
    g = qp.P @ x + qp.c
    with np.errstate(invalid="ignore"):
        at_lo = np.isfinite(qp.lb) & (x - qp.lb <= active_tol * (1.0 + np.abs(qp.lb)))
        at_hi = np.isfinite(qp.ub) & (qp.ub - x <= active_tol * (1.0 + np.abs(qp.ub)))
    eye = np.eye(qp.n)
    # g = A^T lam + sum_lo mu e_j - sum_hi mu e_j with mu >= 0; lam = lam+ - lam-.
    M = np.hstack((qp.A.T, -qp.A.T, eye[:, at_lo], -eye[:, at_hi]))
    z, _ = nnls(M, g, maxiter=50 * M.shape[1])
    m = qp.A.shape[0]
    mu_lo = z[2 * m : 2 * m + int(at_lo.sum())]
    mu_hi = z[2 * m + int(at_lo.sum()) :]
    # Relative to the magnitudes that meet in each condition (a backward error): rounding in
    # A x is eps |A| |x|, and the terms of P x + c = A^T lam + mu cancel at their own size.
    scale_g = max(
        1.0,
        float(np.abs(qp.P @ x).max()),
        float(np.abs(qp.c).max()),
        float(np.abs(M * z).max(initial=0.0)),
    )
    stationarity = float(np.abs(g - M @ z).max()) / scale_g
    scale_eq = max(1.0, float(np.abs(qp.b).max()), float((np.abs(qp.A) @ np.abs(x)).max()))
    equality = float(np.abs(qp.A @ x - qp.b).max()) / scale_eq
    gap_lo = (x - qp.lb)[at_lo]
    gap_hi = (qp.ub - x)[at_hi]
    comp = float(
        max(np.abs(mu_lo * gap_lo).max(initial=0.0), np.abs(mu_hi * gap_hi).max(initial=0.0))
    )
    return KKTReport(stationarity, equality, comp / scale_g, qp.bound_excess(x))


# --------------------------------------------------------------------------------- registry
SolveFunction = Callable[[QP], SolverResult]


@dataclass(frozen=True)
class SolverSpec:
    """A registered solver: its name, family (exact, gradient, gradient-free) and how to get it."""

    name: str
    family: str
    solve: SolveFunction
    description: str
    extra: str | None = None
    is_available: Callable[[], bool] = field(default=lambda: True)


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
    """The solver called ``name``; an unknown or missing one raises :class:`SolverNotFound`."""
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
    """True when no point satisfies ``A x = b`` within the bounds (exact test, emdm.feasibility).

    The iterative and general-purpose solvers call this first (their phase 1), so an infeasible
    program is reported infeasible, never answered with a wrong point.
    """
    from ..core.feasibility import feasible_point

    return feasible_point(qp.A, qp.b, qp.lb, qp.ub) is None


def timed(
    function: Callable[[], tuple[Vector | None, str, int]],
) -> tuple[Vector | None, str, int, float]:
    """Run ``function`` and add its wall time (s, ``time.perf_counter``)."""
    start = time.perf_counter()
    x, status, iterations = function()
    return x, status, iterations, time.perf_counter() - start


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
    qp: QP, chain: Sequence[str], *, tol: float = KKT_TOL, context: str = "", certify: bool = True
) -> ChainResult:
    """Try each solver of ``chain`` in turn; accept the first answer whose KKT report is optimal.

    With ``certify=False`` the first finite answer is accepted whatever its KKT report (used to
    study inexact solvers in closed loop; the report is still recorded). Raises
    :class:`~emdm.errors.NoSolution` when no answer is accepted, naming every attempt.
    """
    attempts: list[tuple[str, str]] = []
    total = 0.0
    for position, name in enumerate(chain):
        spec = get_solver(name)
        try:
            result = spec.solve(qp)
        except Exception as exc:  # a faulty solver must not end the run: record and fall back
            attempts.append((name, f"raised {type(exc).__name__}: {exc}"))
            continue
        total += result.time
        if result.x is None or not np.all(np.isfinite(result.x)):
            attempts.append((name, result.status if result.x is None else "non-finite answer"))
            continue
        report = kkt_report(qp, result.x)
        if certify and not report.is_optimal(tol):
            attempts.append(
                (
                    name,
                    f"not optimal ({result.status}, KKT {report.residual:.1e}, "
                    f"bound excess {report.bound_excess:.1e})",
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


def describe(spec: SolverSpec) -> dict[str, Any]:
    """A JSON-friendly description of a solver."""
    return {
        "name": spec.name,
        "family": spec.family,
        "description": spec.description,
        "available": spec.is_available(),
        "extra": spec.extra,
    }
