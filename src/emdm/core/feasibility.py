"""Exact feasibility of the per-step programs: the Python entry points.

Two questions, answered exactly by the compiled kernels (:mod:`emdm.core.zonotope` for the planar
task's two rows, in O(n) work on the zonotope ``Z = {A x : lb <= x <= ub}``, and
:mod:`emdm.core.simplex` for any number of rows and for inequality rows ``G x <= h``):

- :func:`task_scale`: the largest ``alpha`` in [0, 1] with ``A x = alpha b`` feasible (the SNS task
  scaling of docs/mathematics.md), or ``None`` when no ``alpha`` in [0, 1] is;
- :func:`feasible_point`: some ``x`` with ``A x = b``, ``G x <= h`` and ``lb <= x <= ub``, or
  ``None``.

What the kernels leave (unbounded variables whose columns do not span the task space) goes to
HiGHS through :func:`scipy.optimize.linprog`, checked against the constraints before it is
returned.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from . import simplex
from .arm import Matrix, Vector
from .checks import _Checker
from .tolerances import FEASIBILITY_TOL, RANK_TOL
from .zonotope import NEEDS_REFERENCE, OK

__all__ = ["FEASIBILITY_TOL", "RANK_TOL", "feasible_point", "task_scale", "velocity_set"]


def _contiguous(*arrays: Vector) -> tuple[Vector, ...]:
    return tuple(np.ascontiguousarray(a, dtype=float) for a in arrays)


def _rows(A: Matrix, G: Matrix | None, h: Vector | None) -> tuple[Matrix, Vector]:
    if G is None or h is None:
        return np.zeros((0, A.shape[1])), np.zeros(0)
    return _contiguous(np.asarray(G, dtype=float).reshape(-1, A.shape[1]), h)  # type: ignore[return-value]


def _arguments(
    source: str, A: Any, b: Any, lb: Any, ub: Any, G: Any, h: Any
) -> tuple[Matrix, Vector, Vector, Vector, Matrix | None, Vector | None]:
    """The arguments of :func:`task_scale` and :func:`feasible_point`, checked: ``A`` finite
    k x n, ``b`` finite k, ``lb`` and ``ub`` n entries (never NaN), ``G`` finite m x n and ``h``
    finite m, both given or neither."""
    check = _Checker(source)
    A = check.array("A", A, (None, None), what="a matrix (one row per task row)")
    k, n = A.shape
    b = check.array("b", b, (k,), what=lambda: f"{k} entries (one per row of A)")
    lb = check.array(
        "lb", lb, (n,), finite=False, what=lambda: f"{n} entries (one per column of A)"
    )
    ub = check.array(
        "ub", ub, (n,), finite=False, what=lambda: f"{n} entries (one per column of A)"
    )
    if (G is None) != (h is None):
        raise check.fail(
            "h" if h is None else "G", "must be given with " + ("G" if h is None else "h")
        )
    if G is not None:
        h = check.array("h", h, (None,), what="a vector (one entry per row of G)")
        G = check.array(
            "G", G, None, what=lambda: f"{h.size} x {n} numbers (one row per entry of h)"
        )
        if G.size != h.size * n:
            raise check.fail(
                "G", f"must be {h.size} x {n} (one row per entry of h), got shape {G.shape}"
            )
    return A, b, lb, ub, G, h


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
    answers first, HiGHS what it leaves. Raises :class:`~emdm.errors.ScenarioError` naming the
    argument that is not valid: ``A`` finite k x n, ``b`` finite k, ``lb`` and ``ub`` n entries,
    finite or infinite but never NaN, ``G`` finite m x n and ``h`` finite m (both or neither).
    """
    return _task_scale(*_arguments("task_scale", A, b, lb, ub, G, h))


def _task_scale(
    A: Matrix,
    b: Vector,
    lb: Vector,
    ub: Vector,
    G: Matrix | None = None,
    h: Vector | None = None,
) -> float | None:
    """:func:`task_scale` of checked arguments (the per-step path)."""
    Gc, hc = _rows(A, G, h)
    Ac, bc, lbc, ubc = _contiguous(A, b, lb, ub)
    alpha = simplex.task_scale_of(Ac, bc, Gc, hc, lbc, ubc)
    if alpha != -2.0:
        return None if alpha == -1.0 else alpha
    found = _linprog(A, b, lb, ub, scale=True, G=Gc, h=hc)
    return None if found is None else found[0]


def feasible_point(
    A: Matrix,
    b: Vector,
    lb: Vector,
    ub: Vector,
    G: Matrix | None = None,
    h: Vector | None = None,
) -> Vector | None:
    """Some ``x`` with ``A x = b``, ``G x <= h`` and ``lb <= x <= ub`` (exact up to rounding), or
    ``None``. Raises :class:`~emdm.errors.ScenarioError` naming the argument that is not valid
    (as :func:`task_scale`)."""
    return _feasible_point(*_arguments("feasible_point", A, b, lb, ub, G, h))


def _feasible_point(
    A: Matrix,
    b: Vector,
    lb: Vector,
    ub: Vector,
    G: Matrix | None = None,
    h: Vector | None = None,
) -> Vector | None:
    """:func:`feasible_point` of checked arguments."""
    x = np.empty(A.shape[1])
    Gc, hc = _rows(A, G, h)
    Ac, bc, lbc, ubc = _contiguous(A, b, lb, ub)
    code, _ = simplex.feasible_point_of(Ac, bc, Gc, hc, lbc, ubc, x)
    if code != NEEDS_REFERENCE:
        return x if code == OK else None
    alpha_x = _linprog(A, b, lb, ub, scale=False, G=Gc, h=hc)
    return None if alpha_x is None else alpha_x[1]


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


def velocity_set(J: Matrix, lb: Vector, ub: Vector) -> Matrix:
    """The corners, counter-clockwise, of the set of task velocities ``{J x : lb <= x <= ub}``
    of a two-row task (a zonotope: the polygon of tip velocities the joint bounds allow):
    ``(2n, 2)`` for ``J`` ``(2, n)``, or ``(..., 2n, 2)`` for a stack of them (``J`` ``(..., 2,
    n)``, ``lb`` and ``ub`` ``(..., n)``); NaN where a bound is infinite (the set is unbounded).

    Each joint adds the segment ``J_j [lb_j, ub_j]``; with the segments' half-vectors ``g_j``
    turned into ``[0, pi)`` and sorted by angle, the boundary walks ``+2 g_j`` in that order from
    the lowest-rightmost corner, then ``-2 g_j`` (the Minkowski sum of segments). A joint with a
    zero column or interval repeats a corner."""
    J, lb, ub = (np.asarray(a, dtype=float) for a in (J, lb, ub))
    if (
        J.ndim < 2
        or J.shape[-2] != 2
        or lb.shape != ub.shape
        or lb.shape != J.shape[:-2] + J.shape[-1:]
    ):
        raise ValueError("velocity_set: J is (..., 2, n) and lb, ub are (..., n)")
    finite = np.asarray(np.isfinite(lb).all(axis=-1) & np.isfinite(ub).all(axis=-1))
    lo = np.where(finite[..., None], lb, 0.0)
    hi = np.where(finite[..., None], ub, 0.0)
    centre = np.einsum("...ij,...j->...i", J, (lo + hi) / 2)
    g = J * ((hi - lo) / 2)[..., None, :]
    angle = np.arctan2(g[..., 1, :], g[..., 0, :])
    g = np.where(((angle < 0.0) | (angle >= np.pi))[..., None, :], -g, g)
    order = np.argsort(np.arctan2(g[..., 1, :], g[..., 0, :]), axis=-1, kind="stable")
    g = np.take_along_axis(g, order[..., None, :], axis=-1)
    steps = np.concatenate((2 * g, -2 * g), axis=-1)  # (..., 2, 2n)
    start = centre - g.sum(axis=-1)
    corners = np.swapaxes(start[..., None] + np.cumsum(steps, axis=-1) - steps, -1, -2)
    corners[~finite] = np.nan
    return np.asarray(corners)
