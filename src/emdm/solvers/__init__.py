"""Solvers of the per-step programs: a registry of plain functions, and a fallback chain.

``active-set`` (the default, custom, exact) and ``kkt`` (equality-only programs) are written here;
the qpsolvers backends are registered by name. See :mod:`emdm.solvers.base` for the contract.
"""

from __future__ import annotations

from .active_set import solve_active_set, solve_kkt
from .base import (
    BOUND_TOL,
    KKT_TOL,
    ChainResult,
    KKTReport,
    SolverResult,
    SolverSpec,
    available_solvers,
    get_solver,
    kkt_report,
    register,
    registered_solvers,
    solve_chain,
)
from .qpsolvers_backend import register_backends

DEFAULT_SOLVER = "active-set"
DEFAULT_FALLBACK = ("daqp", "quadprog")

register(
    SolverSpec(
        "active-set",
        "exact",
        solve_active_set,
        "primal active-set method (custom, exact, finite termination)",
    )
)
register(
    SolverSpec(
        "kkt",
        "exact",
        solve_kkt,
        "one KKT solve of the equality-constrained program (custom; ignores bounds)",
    )
)
register_backends()

__all__ = [
    "BOUND_TOL",
    "DEFAULT_FALLBACK",
    "DEFAULT_SOLVER",
    "KKT_TOL",
    "ChainResult",
    "KKTReport",
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
