"""A primal-dual interior-point method (Mehrotra predictor-corrector) for the per-step programs.

Program: ``min 1/2 x^T P x + c^T x`` s.t. ``A x = b``, ``G x <= h``, ``x_j >= lb_j`` (finite
``lb_j``), ``x_j <= ub_j`` (finite ``ub_j``). With slacks ``s_l = x - lb``, ``s_u = ub - x``,
``s_g`` (rows, kept as variables: ``G x + s_g = h`` is a residual like ``A x = b``) and multipliers
``y`` (equalities), ``z_l, z_u, z_g >= 0``, the perturbed KKT conditions are

    P x + c - A^T y - z_l + z_u + G^T z_g = 0,   A x = b,   G x + s_g = h,
    s_l z_l = sigma mu,   s_u z_u = sigma mu,   s_g z_g = sigma mu.

Each iteration eliminates ``dz`` and ``ds_g`` and solves one symmetric system in ``(dx, dy)``:
``(P + Z_l/S_l + Z_u/S_u + G^T (Z_g/S_g) G) dx - A^T dy = rhs``, ``A dx = -(A x - b)``. Mehrotra's predictor
(``sigma = 0``) sets ``sigma = (mu_aff / mu)^3``; the corrector adds the second-order term
``ds_aff dz_aff``. Steps keep 0.995 of the distance to the boundary. The start is infeasible
(box centres), so no phase 1 is needed. Stops when the relative primal and dual residuals and
``mu`` are below ``tol``.

Numerical behaviour worth knowing: when the feasible set has no interior (a scaled, boundary-feasible
task, the usual case under the ``scale`` policy), ``S^-1 Z`` grows without bound for the active
bounds and the system becomes ill-conditioned; convergence then slows and the attainable accuracy is
about ``sqrt(eps)`` in the worst case. The solver lab measures this.
"""

from __future__ import annotations

import time
from typing import NamedTuple

import numpy as np

from ..core.arm import Matrix, Vector
from ..core.problem import QP
from .active_set import independent_rows
from .base import SolverResult, infeasible


class _Newton(NamedTuple):
    """The reduced Newton system of one iteration and the quantities that recover ``dz``."""

    K: Matrix
    free: np.ndarray
    r_d: Vector
    r_p: Vector
    lo: np.ndarray
    hi: np.ndarray
    sl: Vector
    su: Vector
    zl: Vector
    zu: Vector
    G: Matrix
    r_g: Vector
    sg: Vector
    zg: Vector


def _direction(
    nt: _Newton, rl: Vector, ru: Vector, rg: Vector
) -> tuple[Vector, Vector, Vector, Vector, Vector, Vector]:
    """Newton direction for complementarity targets ``rl`` (lower), ``ru`` (upper) and ``rg``
    (rows): ``(dx, dy, dz_l, dz_u, ds_g, dz_g)``.

    ``dz_l = (rl - z_l dx) / s_l``, ``dz_u = (ru + z_u dx) / s_u``, ``ds_g = -r_g - G dx`` and
    ``dz_g = (rg - z_g ds_g) / s_g`` are eliminated, leaving ``(P + Z_l/S_l + Z_u/S_u +
    G^T (Z_g/S_g) G) dx - A^T dy = -r_d + rl/s_l - ru/s_u - G^T (rg + z_g r_g)/s_g`` and
    ``A dx = -r_p`` (without rows the last terms vanish).
    """
    nf = int(nt.free.sum())
    rhs_x = -nt.r_d + np.where(nt.lo, rl / nt.sl, 0.0) - np.where(nt.hi, ru / nt.su, 0.0)
    if nt.G.shape[0]:
        rhs_x = rhs_x - nt.G.T @ ((rg + nt.zg * nt.r_g) / nt.sg)
    sol = np.linalg.solve(nt.K, np.concatenate((rhs_x[nt.free], -nt.r_p)))
    dx = np.zeros(nt.free.size)
    dx[nt.free] = sol[:nf]
    dzl = np.where(nt.lo, (rl - nt.zl * dx) / nt.sl, 0.0)
    dzu = np.where(nt.hi, (ru + nt.zu * dx) / nt.su, 0.0)
    dsg = -nt.r_g - nt.G @ dx
    dzg = (rg - nt.zg * dsg) / nt.sg
    return dx, sol[nf:], dzl, dzu, dsg, dzg


def solve_interior_point(
    qp: QP, *, tol: float = 1e-12, max_iter: int = 80, history: bool = False
) -> SolverResult:
    """Solve ``qp`` by Mehrotra's predictor-corrector interior-point method."""
    start = time.perf_counter()
    if infeasible(qp):
        return SolverResult(None, "infeasible", 0, time.perf_counter() - start)
    P, c = qp.P, qp.c
    A, b = independent_rows(qp.A, qp.b)
    m = A.shape[0]
    has_lo, has_hi = np.isfinite(qp.lb), np.isfinite(qp.ub)
    lb, ub = np.where(has_lo, qp.lb, 0.0), np.where(has_hi, qp.ub, 0.0)
    x = np.where(
        has_lo & has_hi,
        0.5 * (lb + ub),
        np.where(has_lo, lb + 1.0, np.where(has_hi, ub - 1.0, 0.0)),
    )
    width = np.where(has_lo & has_hi, ub - lb, 1.0)
    if np.any(width < 0):
        return SolverResult(None, "infeasible", 0, time.perf_counter() - start)
    fixed = has_lo & has_hi & (width <= 1e-14)
    x[fixed] = lb[fixed]  # a fixed variable: keep it out of the barrier
    lo_act, hi_act = has_lo & ~fixed, has_hi & ~fixed
    y = np.zeros(m)
    zl, zu = lo_act.astype(float), hi_act.astype(float)
    G, h, ng = qp.G, qp.h, qp.n_rows
    sg, zg = np.maximum(h - G @ x, 1.0), np.ones(ng)  # the rows' slacks s_g = h - G x > 0
    all_g = np.ones(ng, dtype=bool)
    n_c = max(int(lo_act.sum() + hi_act.sum()) + ng, 1)
    scale_b = 1.0 + float(np.abs(b).max())
    scale_c = 1.0 + float(np.abs(c).max()) + float(np.abs(P).max())
    trace: list[dict[str, float]] = []

    def slacks(x: Vector) -> tuple[Vector, Vector]:
        return np.where(lo_act, x - lb, 1.0), np.where(hi_act, ub - x, 1.0)

    def max_step(v: Vector, dv: Vector, mask: np.ndarray) -> float:
        neg = mask & (dv < 0)
        return float(min(1.0, np.min(-v[neg] / dv[neg]))) if neg.any() else 1.0

    for iteration in range(1, max_iter + 1):
        sl, su = slacks(x)
        r_d = P @ x + c - A.T @ y - zl + zu
        if ng:
            r_d = r_d + G.T @ zg
        r_d[fixed] = 0.0
        r_p = A @ x - b
        r_g = G @ x + sg - h
        mu = float((sl * zl)[lo_act].sum() + (su * zu)[hi_act].sum() + (sg * zg).sum()) / n_c
        res_p, res_d = float(np.abs(r_p).max()) / scale_b, float(np.abs(r_d).max()) / scale_c
        if ng:
            res_p = max(res_p, float(np.abs(r_g).max()) / (1.0 + float(np.abs(h).max())))
        if history:
            trace.append(
                {
                    "iteration": float(iteration - 1),
                    "objective": qp.objective(x),
                    "primal_residual": res_p,
                    "dual_residual": res_d,
                    "mu": mu,
                }
            )
        if res_p <= tol and res_d <= tol and mu <= tol * scale_c:
            return SolverResult(
                x, "optimal", iteration - 1, time.perf_counter() - start, tuple(trace)
            )
        d_l = np.where(lo_act, zl / sl, 0.0)
        d_u = np.where(hi_act, zu / su, 0.0)
        free_mask = ~fixed
        nf = int(free_mask.sum())
        K = np.zeros((nf + m, nf + m))
        K[:nf, :nf] = P[np.ix_(free_mask, free_mask)] + np.diag((d_l + d_u)[free_mask])
        if ng:
            Gf = G[:, free_mask]
            K[:nf, :nf] += Gf.T @ ((zg / sg)[:, None] * Gf)
        K[:nf, nf:] = -A[:, free_mask].T
        K[nf:, :nf] = A[:, free_mask]
        newton = _Newton(K, free_mask, r_d, r_p, lo_act, hi_act, sl, su, zl, zu, G, r_g, sg, zg)

        try:
            dx, dy, dzl, dzu, dsg, dzg = _direction(newton, -sl * zl, -su * zu, -sg * zg)
            a_p = min(max_step(sl, dx, lo_act), max_step(su, -dx, hi_act), max_step(sg, dsg, all_g))
            a_d = min(
                max_step(zl, dzl, lo_act), max_step(zu, dzu, hi_act), max_step(zg, dzg, all_g)
            )
            a = min(a_p, a_d)
            mu_aff = (
                float(
                    ((sl + a * dx) * (zl + a * dzl))[lo_act].sum()
                    + ((su - a * dx) * (zu + a * dzu))[hi_act].sum()
                    + ((sg + a * dsg) * (zg + a * dzg)).sum()
                )
                / n_c
            )
            sigma = (mu_aff / mu) ** 3 if mu > 0 else 0.0
            rl = -sl * zl + sigma * mu - dx * dzl
            ru = -su * zu + sigma * mu + dx * dzu
            rg = -sg * zg + sigma * mu - dsg * dzg
            dx, dy, dzl, dzu, dsg, dzg = _direction(newton, rl, ru, rg)
        except np.linalg.LinAlgError as exc:
            return SolverResult(
                x, f"error: {exc}", iteration, time.perf_counter() - start, tuple(trace)
            )
        a_p = min(max_step(sl, dx, lo_act), max_step(su, -dx, hi_act), max_step(sg, dsg, all_g))
        a_d = min(max_step(zl, dzl, lo_act), max_step(zu, dzu, hi_act), max_step(zg, dzg, all_g))
        a = min(1.0, 0.995 * min(a_p, a_d))
        if not np.all(np.isfinite(dx)):
            return SolverResult(x, "error: non-finite step", iteration, time.perf_counter() - start)
        x, y, zl, zu = x + a * dx, y + a * dy, zl + a * dzl, zu + a * dzu
        sg, zg = sg + a * dsg, zg + a * dzg
    return SolverResult(x, "max_iter", max_iter, time.perf_counter() - start, tuple(trace))
