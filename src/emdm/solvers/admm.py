"""ADMM (the splitting behind OSQP), a first-order method for the per-step programs.

Split ``x`` (carrying ``A x = b``) from ``z`` (carrying ``lb <= z <= ub``) with ``x = z``:

    x+ = argmin 1/2 x^T P x + c^T x + rho/2 ||x - z + u||^2  s.t.  A x = b   (one KKT solve, factored once)
    z+ = clip(x+ + u, lb, ub)
    u+ = u + x+ - z+

Stops when the primal residual ``||x - z||`` and the dual residual ``rho ||z - z_prev||`` fall below
``eps_abs + eps_rel * scale``. It returns ``z`` (inside the bounds); its equality residual is what is
left of ``x - z`` and is reported, never hidden. The rate is linear, governed by the conditioning of
``P`` on the active face: ``w_S = c_S / ||e||`` near the goal makes it large, and the iteration count
grows with it. ``rho`` is the geometric mean of the extreme eigenvalues of ``P``.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.linalg

from ..core.problem import QP
from .active_set import independent_rows
from .base import UNSUPPORTED_ROWS, SolverResult, infeasible


def solve_admm(
    qp: QP,
    *,
    eps_abs: float = 1e-10,
    eps_rel: float = 1e-10,
    max_iter: int = 20000,
    history: bool = False,
) -> SolverResult:
    """Solve ``qp`` by ADMM; ``status`` is ``"optimal"`` on convergence, else ``"max_iter"``."""
    start = time.perf_counter()
    if qp.n_rows:  # this method is written for bounds only: it declines rather than ignore rows
        return SolverResult(None, UNSUPPORTED_ROWS, 0, time.perf_counter() - start)
    if infeasible(qp):
        return SolverResult(None, "infeasible", 0, time.perf_counter() - start)
    P, c = qp.P, qp.c
    A, b = independent_rows(qp.A, qp.b)
    n, m = qp.n, A.shape[0]
    eig = np.linalg.eigvalsh(P)
    rho = float(np.sqrt(max(eig[0], 1e-12) * eig[-1]))
    K = np.zeros((n + m, n + m))
    K[:n, :n], K[:n, n:], K[n:, :n] = P + rho * np.eye(n), A.T, A
    try:
        factor = scipy.linalg.lu_factor(K)
    except (ValueError, np.linalg.LinAlgError) as exc:
        return SolverResult(None, f"error: {exc}", 0, time.perf_counter() - start)
    z = np.clip(np.zeros(n), qp.lb, qp.ub)
    u = np.zeros(n)
    trace: list[dict[str, float]] = []
    rhs = np.empty(n + m)
    rhs[n:] = b
    for iteration in range(1, max_iter + 1):
        rhs[:n] = -c + rho * (z - u)
        x = scipy.linalg.lu_solve(factor, rhs)[:n]
        z_prev = z
        z = np.clip(x + u, qp.lb, qp.ub)
        u = u + x - z
        r_prim = float(np.abs(x - z).max())
        r_dual = rho * float(np.abs(z - z_prev).max())
        if history:
            trace.append(
                {
                    "iteration": float(iteration),
                    "objective": qp.objective(z),
                    "primal_residual": r_prim,
                    "dual_residual": r_dual,
                }
            )
        if r_prim <= eps_abs + eps_rel * max(
            float(np.abs(x).max()), float(np.abs(z).max())
        ) and r_dual <= eps_abs + eps_rel * rho * float(np.abs(u).max()):
            return SolverResult(z, "optimal", iteration, time.perf_counter() - start, tuple(trace))
    return SolverResult(z, "max_iter", max_iter, time.perf_counter() - start, tuple(trace))
