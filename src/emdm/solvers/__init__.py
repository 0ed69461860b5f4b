"""Solvers of the per-step programs: a registry of plain functions, and a fallback chain.

``active-set`` (the default, custom, exact) and ``kkt`` (equality-only programs) are written here;
the qpsolvers backends are registered by name. See :mod:`emdm.solvers.base` for the contract.
"""

from __future__ import annotations

import importlib.util

from .active_set import solve_active_set, solve_kkt
from .admm import solve_admm
from .base import (
    ChainResult,
    Family,
    KKTReport,
    Loop,
    SolveFunction,
    SolverResult,
    SolverSpec,
    available_solvers,
    get_solver,
    kkt_report,
    register,
    registered_solvers,
    solve_chain,
)
from .interior_point import solve_interior_point
from .kernels import BOUND_TOL, KKT_TOL
from .nlp import gradient_free, solve_slsqp, solve_slsqp_reduced, solve_trust_constr
from .qpsolvers_backend import register_backends

DEFAULT_SOLVER = "active-set"
DEFAULT_FALLBACK = ("daqp", "quadprog")

register(
    SolverSpec(
        "active-set",
        Family.EXACT,
        solve_active_set,
        "primal active-set method (custom, exact, finite termination)",
    )
)
register(
    SolverSpec(
        "kkt",
        Family.EXACT,
        solve_kkt,
        "one KKT solve of the equality-constrained program (custom; ignores bounds)",
    )
)
register(
    SolverSpec(
        "interior-point",
        Family.EXACT,
        solve_interior_point,
        "primal-dual interior point, Mehrotra predictor-corrector (custom)",
        loop=Loop.PYTHON,
        method="a barrier method",
    )
)
register(
    SolverSpec(
        "admm",
        Family.GRADIENT,
        solve_admm,
        "ADMM operator splitting, first order (custom; OSQP's scheme)",
        loop=Loop.PYTHON,
        method="operator splitting",
    )
)
register_backends()
register(
    SolverSpec(
        "slsqp",
        Family.GRADIENT,
        solve_slsqp,
        "scipy SLSQP, exact gradients and constraint Jacobian",
        loop=Loop.PYTHON,  # scipy's Python driver calls the compiled step once per iteration
        method="sequential quadratic programming",
    )
)
register(
    SolverSpec(
        "slsqp-reduced",
        Family.GRADIENT,
        solve_slsqp_reduced,
        "scipy SLSQP on the reduced program the gradient-free methods search, exact gradient",
        loop=Loop.PYTHON,
        method="sequential quadratic programming",
    )
)
register(
    SolverSpec(
        "trust-constr",
        Family.GRADIENT,
        solve_trust_constr,
        "scipy trust-constr, exact gradient and Hessian",
        loop=Loop.PYTHON,
        method="a trust-region method",
    )
)


def _cma_installed() -> bool:
    """Whether the cma package is installed, found without importing it (it imports
    matplotlib, which a listing of the solvers does not need)."""
    return importlib.util.find_spec("cma") is not None


for _method, _text, _kind in (
    (
        "nelder-mead",
        "scipy Nelder-Mead simplex on the reduced program, l1 penalty",
        "a simplex search",
    ),
    ("powell", "scipy Powell on the reduced program, l1 penalty", "line searches"),
    (
        "cobyqa",
        "scipy COBYQA (quadratic models) on the reduced program, native constraints",
        "quadratic models",
    ),
    (
        "cobyla",
        "scipy COBYLA (linear models) on the reduced program, native constraints",
        "linear models",
    ),
    (
        "differential-evolution",
        "scipy differential evolution, native constraints, seeded",
        "a population search",
    ),
):
    register(
        SolverSpec(
            _method,
            Family.GRADIENT_FREE,
            gradient_free(_method),
            _text,
            loop=Loop.PYTHON,
            method=_kind,
        )
    )
register(
    SolverSpec(
        "cma-es",
        Family.GRADIENT_FREE,
        gradient_free("cma-es"),
        "CMA-ES (the cma package), bounds and l1 penalty, seeded",
        extra="lab",
        is_available=_cma_installed,
        loop=Loop.PYTHON,
        method="an evolution strategy",
    )
)

__all__ = [
    "BOUND_TOL",
    "DEFAULT_FALLBACK",
    "DEFAULT_SOLVER",
    "KKT_TOL",
    "ChainResult",
    "Family",
    "KKTReport",
    "Loop",
    "SolveFunction",
    "SolverResult",
    "SolverSpec",
    "available_solvers",
    "get_solver",
    "kkt_report",
    "register",
    "registered_solvers",
    "solve_active_set",
    "solve_chain",
    "solve_kkt",
]
