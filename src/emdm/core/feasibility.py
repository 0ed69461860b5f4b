"""Exact feasibility geometry of the per-step programs.

The set of task velocities the bounds allow, ``Z = {A x : lb <= x <= ub}``, is a zonotope in the
plane (plus whole lines for unbounded variables). Its support function is
``h(w) = sum_j max((w.g_j) lb_j, (w.g_j) ub_j)`` with generators ``g_j`` (the columns of ``A``), and a
2-D zonotope is the intersection of the half-planes ``w.y <= h(w)`` over the normals of its edges,
``+-perp(g_j)``. Extra normals (``+-g_j``, the axes, the query direction) give valid but loose
half-planes and make the same formula exact for degenerate zonotopes (segments, points).

Unbounded variables are projected out: with ``Q`` an orthonormal basis of the complement of the
range of their columns, ``A x = b`` is solvable iff ``Q^T A_B x_B = Q^T b`` is, for bounded ``x_B``.

With other than two task rows (a spatial arm's position or pose), the compiled kernels answer
both questions by the simplex method; what they leave (unbounded variables whose columns do not
span the task space) goes to HiGHS through :func:`scipy.optimize.linprog`, the reference of the
tests as well.

Two questions are answered exactly, in O(n) work:

- :func:`task_scale`: the largest ``alpha`` in [0, 1] with ``A x = alpha b`` feasible (the SNS task
  scaling of docs/mathematics.md), or ``None`` when no ``alpha`` in [0, 1] is;
- :func:`feasible_point`: some ``x`` with ``A x = b`` and ``lb <= x <= ub``, or ``None``. It walks
  from the box centre towards ``b``, leaves ``Z`` through an edge, reads the box vertex (or edge) that
  maps there, and takes the convex combination that lands on ``b``.
"""

from __future__ import annotations

import numpy as np

from . import simplex
from .arm import Matrix, Vector
from .tolerances import FEASIBILITY_TOL, RANK_TOL
from .zonotope import NEEDS_REFERENCE, OK

__all__ = ["FEASIBILITY_TOL", "RANK_TOL", "feasible_point", "task_scale"]


def _contiguous(*arrays: Vector) -> tuple[Vector, ...]:
    return tuple(np.ascontiguousarray(a, dtype=float) for a in arrays)


def _perp(w: Matrix) -> Matrix:
    return np.stack((-w[1], w[0]))


def _project(A: Matrix, lb: Vector, ub: Vector) -> tuple[Matrix, Matrix, np.ndarray]:
    """``(Q, G, bounded)``: complement basis Q (m x k), G = Q^T A_B padded to 2 rows, bounded mask."""
    free = np.isneginf(lb) & np.isposinf(ub)
    bounded = np.isfinite(lb) & np.isfinite(ub)
    if not np.all(free | bounded):
        raise ValueError("every variable must be bounded on both sides or free")
    m = A.shape[0]
    if free.any():
        U, s, _ = np.linalg.svd(A[:, free])
        rank = int(np.sum(s > RANK_TOL * max(s[0], 1.0))) if s.size else 0
        Q = U[:, rank:]
    else:
        Q = np.eye(m)
    G = np.zeros((2, int(bounded.sum())))
    G[: Q.shape[1]] = Q.T @ A[:, bounded]
    G[np.abs(G) <= RANK_TOL * max(float(np.abs(A).max(initial=0.0)), 1e-300)] = (
        0.0  # rounding noise
    )
    return Q, G, bounded


def _pad(Q: Matrix, y: Vector) -> Vector:
    out = np.zeros(2)
    out[: Q.shape[1]] = Q.T @ y
    return out


def _normals(G: Matrix, d: Vector) -> Matrix:
    """Unit candidate normals (rows): +-perp(g_j), +-g_j, +-axes, +-d and +-perp(d)."""
    cols = [G, np.eye(2), d.reshape(2, 1)]
    base = np.hstack(cols)
    norms = np.linalg.norm(base, axis=0)
    base = base[:, norms > 0] / norms[norms > 0]
    both = np.hstack((base, _perp(base)))
    return np.vstack((both.T, -both.T))


def _ray_interval(
    G: Matrix, lb: Vector, ub: Vector, y0: Vector, d: Vector
) -> tuple[float, float, Vector | None]:
    """``(t_lo, t_hi, w)``: ``y0 + t d`` lies in ``Z`` exactly for ``t`` in [t_lo, t_hi]; ``w`` is
    the normal of the half-plane that sets ``t_hi``. Empty interval: ``t_lo > t_hi``."""
    W = _normals(G, d)
    S = W @ G
    h = np.sum(np.maximum(S * lb, S * ub), axis=1) - W @ y0
    a = W @ d
    size = (
        1.0
        + float(np.sum(np.abs(G) * np.maximum(np.abs(lb), np.abs(ub))))
        + float(np.abs(y0).sum())
    )
    flat = np.abs(a) <= 1e-13 * max(float(np.abs(d).sum()), 1e-300)
    if np.any(flat & (h < -FEASIBILITY_TOL * size)):
        return np.inf, -np.inf, None
    up, down = (a > 0) & ~flat, (a < 0) & ~flat
    t_hi, w = np.inf, None
    if up.any():
        ratios = h[up] / a[up]
        k = int(np.argmin(ratios))
        t_hi, w = float(ratios[k]), W[up][k]
    t_lo = float(np.max(h[down] / a[down])) if down.any() else -np.inf
    return t_lo, t_hi, w


def _rows(A: Matrix, G: Matrix | None, h: Vector | None) -> tuple[Matrix, Vector]:
    if G is None or h is None:
        return np.zeros((0, A.shape[1])), np.zeros(0)
    return _contiguous(np.asarray(G, dtype=float).reshape(-1, A.shape[1]), h)  # type: ignore[return-value]


def task_scale(
    A: Matrix,
    b: Vector,
    lb: Vector,
    ub: Vector,
    G: Matrix | None = None,
    h: Vector | None = None,
) -> float | None:
    """Largest ``alpha`` in [0, 1] such that ``A x = alpha b``, ``G x <= h``, ``lb <= x <= ub``
    is feasible.

    Returns 1.0 for a feasible program and ``None`` when no ``alpha`` in [0, 1] works (for instance a
    box that excludes ``x = 0`` and cannot reach the task direction either). The compiled kernel
    answers first; the numpy projection below handles what it leaves for two rows (unbounded
    variables whose columns have rank < 2), HiGHS the rest (more task rows, or inequality rows
    with unbounded variables).
    """
    Gc, hc = _rows(A, G, h)
    Ac, bc, lbc, ubc = _contiguous(A, b, lb, ub)
    alpha = simplex.task_scale_of(Ac, bc, Gc, hc, lbc, ubc)
    if alpha != -2.0:
        return None if alpha == -1.0 else alpha
    if A.shape[0] != 2 or hc.size:
        found = _linprog(A, b, lb, ub, scale=True, G=Gc, h=hc)
        return None if found is None else found[0]
    Q, G, bounded = _project(A, lb, ub)
    if Q.shape[1] == 0:
        return 1.0
    t_lo, t_hi, _ = _ray_interval(G, lb[bounded], ub[bounded], np.zeros(2), _pad(Q, b))
    lo, hi = max(0.0, t_lo), min(1.0, t_hi)
    if hi < lo - 1e-12:
        return None
    return max(lo, hi) if hi >= lo else lo


def feasible_point(
    A: Matrix,
    b: Vector,
    lb: Vector,
    ub: Vector,
    G: Matrix | None = None,
    h: Vector | None = None,
) -> Vector | None:
    """Some ``x`` with ``A x = b``, ``G x <= h`` and ``lb <= x <= ub`` (exact up to rounding), or
    ``None``."""
    x = np.empty(A.shape[1])
    Gc, hc = _rows(A, G, h)
    Ac, bc, lbc, ubc = _contiguous(A, b, lb, ub)
    code, _ = simplex.feasible_point_of(Ac, bc, Gc, hc, lbc, ubc, x)
    if code != NEEDS_REFERENCE:
        return x if code == OK else None
    if A.shape[0] != 2 or hc.size:
        alpha_x = _linprog(A, b, lb, ub, scale=False, G=Gc, h=hc)
        return None if alpha_x is None else alpha_x[1]
    Q, G, bounded = _project(A, lb, ub)
    lbb, ubb = lb[bounded], ub[bounded]
    x = np.zeros(A.shape[1])
    if Q.shape[1] == 0:
        xb = np.clip(0.0, lbb, ubb)
    else:
        centre = 0.5 * (lbb + ubb)
        y0 = G @ centre
        d = _pad(Q, b) - y0
        xb = centre
        noise = RANK_TOL * (1.0 + float(np.abs(b).max()) + float(np.abs(y0).max()))
        if np.abs(d).max() > noise:
            t_lo, t_hi, w = _ray_interval(G, lbb, ubb, y0, d)
            if w is None or t_hi < 1.0 - 1e-9 or t_lo > t_hi:
                return None
            xb = _boundary_preimage(G, lbb, ubb, centre, y0 + t_hi * d, w)
            if t_hi > 1.0:
                xb = centre + (xb - centre) / t_hi
    x[bounded] = xb
    free = ~bounded
    if free.any():
        rhs = b - A[:, bounded] @ xb
        x[free] = np.linalg.lstsq(A[:, free], rhs, rcond=None)[0]
    size = 1.0 + float(np.abs(b).max()) + float(np.abs(A).max() * np.abs(x).sum())
    if np.max(np.abs(A @ x - b)) > FEASIBILITY_TOL * size:
        return None
    return x


def _boundary_preimage(
    G: Matrix, lb: Vector, ub: Vector, centre: Vector, target: Vector, w: Vector
) -> Vector:
    """A box point mapping onto ``target``, which lies on the supporting line of normal ``w``."""
    s = w @ G
    gnorm = np.linalg.norm(G, axis=0)
    parallel = np.abs(s) <= 1e-12 * np.maximum(gnorm, 1e-300)
    x = np.where(s > 0, ub, lb)
    x[parallel] = centre[parallel]
    if parallel.any():
        u = np.array([-w[1], w[0]])
        gu = u @ G[:, parallel]
        half = 0.5 * (ub - lb)[parallel]
        denom = float(np.sum(np.abs(gu) * half))
        if denom > 0:
            tau = float(np.clip(u @ (target - G @ x) / denom, -1.0, 1.0))
            x[parallel] += tau * half * np.sign(gu)
    return x


def _linprog(
    A: Matrix,
    b: Vector,
    lb: Vector,
    ub: Vector,
    *,
    scale: bool,
    G: Matrix | None = None,
    h: Vector | None = None,
) -> tuple[float, Vector] | None:
    """``(alpha, x)`` with ``A x = alpha b``, ``G x <= h`` and ``lb <= x <= ub`` by HiGHS: the
    largest ``alpha`` in [0, 1] (``scale``) or ``alpha = 1``; ``None`` when infeasible."""
    from scipy.optimize import linprog

    n = A.shape[1]
    rows: dict[str, Matrix | Vector] = {}
    if G is not None and h is not None and np.size(h):
        rows = {"A_ub": np.hstack((G, np.zeros((G.shape[0], 1)))), "b_ub": h}
    A_eq = np.hstack((A, -np.asarray(b, dtype=float).reshape(-1, 1)))
    cost = np.zeros(n + 1)
    cost[n] = -1.0
    bounds = [
        (None if np.isneginf(lo) else lo, None if np.isposinf(hi) else hi)
        for lo, hi in zip(lb, ub, strict=True)
    ]
    bounds.append((0.0, 1.0) if scale else (1.0, 1.0))
    result = linprog(
        cost, A_eq=A_eq, b_eq=np.zeros(A.shape[0]), bounds=bounds, method="highs", **rows
    )
    if result.status != 0:
        return None
    x = np.clip(result.x[:n], lb, ub)
    alpha = float(np.clip(result.x[n], 0.0, 1.0))
    size = 1.0 + float(np.abs(b).max()) + float(np.abs(A).max() * np.abs(x).sum())
    if np.max(np.abs(A @ x - alpha * b)) > FEASIBILITY_TOL * size:
        return None
    if rows and not simplex.rows_hold(*_contiguous(G, h, x)):  # type: ignore[arg-type]
        return None
    return alpha, x
