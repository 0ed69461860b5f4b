"""ADMM (the splitting behind OSQP), a first-order method for the per-step programs.

Split ``x`` (carrying ``A x = b``) from ``z`` (carrying ``lb <= z <= ub``, and for the rows
``G x <= h`` their values ``z_G <= h``) with ``C x = z``, ``C = [I; G]``:

    x+ = argmin 1/2 x^T P x + c^T x + rho/2 ||C x - z + u||^2  s.t.  A x = b   (one KKT solve, factored once)
    z+ = clip(C x+ + u, [lb; -inf], [ub; h])
    u+ = u + C x+ - z+

(without rows ``C = I``, the iteration of OSQP on bounds alone).

Stops when the primal residual ``||x - z||`` and the dual residual ``rho ||z - z_prev||`` fall below
``eps_abs + eps_rel * scale``. It returns ``z`` (inside the bounds); its equality residual is what is
left of ``x - z`` and is reported, never hidden. The rate is linear, governed by the conditioning of
``P`` on the active face: ``w_S = c_S / ||e||`` near the goal makes it large, and the iteration count
grows with it. ``rho`` is the geometric mean of the extreme eigenvalues of ``P``.
"""

from __future__ import annotations

import time

import numpy as np

from ..core.problem import QP
from .active_set import independent_rows
from .base import SolverResult, infeasible


def solve_admm(
    qp: QP,
    *,
    eps_abs: float = 1e-10,
    eps_rel: float = 1e-10,
    max_iter: int = 20000,
    history: bool = False,
) -> SolverResult:
    """Solve ``qp`` by ADMM; ``status`` is ``"optimal"`` on convergence, else ``"max_iter"``."""
    import scipy.linalg  # loaded on first use: the control loop never needs it

    start = time.perf_counter()
    if infeasible(qp):
        return SolverResult(None, "infeasible", 0, time.perf_counter() - start)
    P, c = qp.P, qp.c
    A, b = independent_rows(qp.A, qp.b)
    n, m = qp.n, A.shape[0]
    eig = np.linalg.eigvalsh(P)
    rho = float(np.sqrt(max(eig[0], 1e-12) * eig[-1]))
    G, ng = qp.G, qp.n_rows
    lo = np.concatenate((qp.lb, np.full(ng, -np.inf)))
    hi = np.concatenate((qp.ub, qp.h))
    K = np.zeros((n + m, n + m))
    K[:n, :n], K[:n, n:], K[n:, :n] = P + rho * np.eye(n), A.T, A
    if ng:
        K[:n, :n] += rho * (G.T @ G)
    try:
        factor = scipy.linalg.lu_factor(K)
    except (ValueError, np.linalg.LinAlgError) as exc:
        return SolverResult(None, f"error: {exc}", 0, time.perf_counter() - start)
    z = np.clip(np.zeros(n + ng), lo, hi)
    u = np.zeros(n + ng)
    trace: list[dict[str, float]] = []
    rhs = np.empty(n + m)
    rhs[n:] = b
    for iteration in range(1, max_iter + 1):
        w = z - u
        rhs[:n] = -c + rho * (w[:n] + G.T @ w[n:] if ng else w)
        x = scipy.linalg.lu_solve(factor, rhs)[:n]
        cx = np.concatenate((x, G @ x)) if ng else x
        z_prev = z
        z = np.clip(cx + u, lo, hi)
        u = u + cx - z
        r_prim = float(np.abs(cx - z).max())
        r_dual = rho * float(np.abs(z - z_prev).max())
        if history:
            trace.append(
                {
                    "iteration": float(iteration),
                    "objective": qp.objective(z[:n]),
                    "primal_residual": r_prim,
                    "dual_residual": r_dual,
                }
            )
        if r_prim <= eps_abs + eps_rel * max(
            float(np.abs(x).max()), float(np.abs(z).max())
        ) and r_dual <= eps_abs + eps_rel * rho * float(np.abs(u).max()):
            return SolverResult(
                z[:n], "optimal", iteration, time.perf_counter() - start, tuple(trace)
            )
    return SolverResult(z[:n], "max_iter", max_iter, time.perf_counter() - start, tuple(trace))
