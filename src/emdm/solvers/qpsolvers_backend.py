"""Off-the-shelf QP solvers through qpsolvers (https://github.com/qpsolvers/qpsolvers).

Each backend that qpsolvers finds installed is registered under its own name (``daqp``,
``quadprog``, and with ``pip install 'emdm[solvers]'`` also ``proxqp``, ``piqp``, ``clarabel``,
``osqp``, ``highs``). Unbounded variables are passed as +-inf bounds, or no bounds at all.
"""

from __future__ import annotations

import functools
import importlib.util
import time
import warnings
from functools import partial
from typing import Any

import numpy as np

from ..core.problem import QP
from .base import Family, SolverResult, SolverSpec, register

BACKENDS = {
    "daqp": (Family.EXACT, "dual active-set (DAQP), dense"),
    "quadprog": (
        Family.EXACT,
        "Goldfarb-Idnani dual active-set (quadprog); declines some degenerate programs",
    ),
    "proxqp": (Family.EXACT, "proximal augmented Lagrangian (ProxQP), eps 1e-12"),
    "piqp": (
        Family.EXACT,
        "proximal interior point (PIQP), eps 1e-12; about 1e-7 accurate on these programs",
    ),
    "clarabel": (Family.EXACT, "interior point (Clarabel), tolerances 1e-12"),
    "osqp": (Family.GRADIENT, "ADMM (OSQP), first order, default tolerances"),
    "highs": (Family.EXACT, "HiGHS QP active set; about 1e-7 accurate on these programs"),
}
TIGHT: dict[str, dict[str, Any]] = {
    "proxqp": {"eps_abs": 1e-12, "eps_rel": 0.0},
    "piqp": {"eps_abs": 1e-12, "eps_rel": 1e-12},
    "clarabel": {
        "tol_gap_abs": 1e-12,
        "tol_gap_rel": 1e-12,
        "tol_feas": 1e-12,
        "tol_ktratio": 1e-10,
    },
}
"""Tolerances passed to the iterative backends so that they solve to the precision emdm certifies."""


METHODS = {
    "daqp": "a dual active-set method",
    "quadprog": "a dual active-set method",
    "proxqp": "a proximal augmented Lagrangian method",
    "piqp": "a proximal interior-point method",
    "clarabel": "an interior-point method",
    "osqp": "operator splitting",
    "highs": "an active-set method",
}
"""What kind of method each backend is, in plain words (:attr:`SolverSpec.method`)."""


MODULES = {
    "daqp": "daqp",
    "quadprog": "quadprog",
    "proxqp": "proxsuite",
    "piqp": "piqp",
    "clarabel": "clarabel",
    "osqp": "osqp",
    "highs": "highspy",
}
"""The module each backend needs: qpsolvers lists a backend as available when it imports."""


@functools.cache
def _installed(name: str) -> bool:
    """Whether qpsolvers and ``name``'s module are installed, found without importing them
    (importing qpsolvers imports every backend, 0.14 s that a run on the default solver never
    needs)."""
    return all(importlib.util.find_spec(m) is not None for m in ("qpsolvers", MODULES[name]))


def solve_qpsolvers(qp: QP, backend: str, *, history: bool = False) -> SolverResult:
    """Solve ``qp`` with one qpsolvers backend; an unsolved program has ``x = None``."""
    from qpsolvers import Problem, solve_problem

    lb = qp.lb if np.isfinite(qp.lb).any() else None
    ub = qp.ub if np.isfinite(qp.ub).any() else None
    if backend == "quadprog" and lb is not None:
        # quadprog cannot take infinite bounds: free variables get none
        lb = np.where(np.isfinite(qp.lb), qp.lb, -1e30)
        ub = np.where(np.isfinite(qp.ub), qp.ub, 1e30)
    G, h = (qp.G, qp.h) if qp.n_rows else (None, None)
    problem = Problem(qp.P, qp.c, G, h, qp.A, qp.b, lb, ub)
    start = time.perf_counter()
    with warnings.catch_warnings():  # dense to sparse conversion notices for sparse backends
        warnings.simplefilter("ignore")
        solution = solve_problem(problem, solver=backend, **TIGHT.get(backend, {}))
    elapsed = time.perf_counter() - start
    if not solution.found or solution.x is None:
        return SolverResult(None, "infeasible or failed", 0, elapsed)
    raw = solution.extras.get("iter", solution.extras.get("iterations", 0))
    iterations = int(np.atleast_1d(raw)[0]) if raw is not None else 0
    return SolverResult(np.asarray(solution.x, dtype=float), "optimal", iterations, elapsed)


def register_backends() -> None:
    """Register every qpsolvers backend this module knows (available or not)."""
    for name, (family, description) in BACKENDS.items():
        register(
            SolverSpec(
                name=name,
                family=family,
                solve=partial(solve_qpsolvers, backend=name),
                description=description,
                extra=None if name in ("daqp", "quadprog") else "solvers",
                is_available=partial(_installed, name),
                method=METHODS[name],
            )
        )
