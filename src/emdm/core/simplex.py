"""The feasibility of any task, compiled: the bounded-variable simplex method, and programs with
inequality rows ``G x <= h``.

``task_scale_rows`` and ``feasible_point_rows`` answer the questions of :mod:`emdm.core.zonotope`
for any number of task rows (a spatial arm's position or pose) and for programs with inequality
rows, which :func:`_augment` turns into equalities with bounded slacks (docs/mathematics.md,
"Feasibility in any dimension").
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from .jit import kernel
from .kernels import solve_in_place
from .tolerances import FEASIBILITY_TOL
from .zonotope import (
    INFEASIBLE,
    NEEDS_REFERENCE,
    OK,
    FeasWork,
    LPViews,
    _aug_views,
    _lp_views,
    _mark_free,
    feas_work,
    feasible_point,
    free_rank,
    task_scale,
)

F64 = NDArray[np.float64]


@kernel(refcount=False)
def _column(A: F64, b: F64, sigma: F64, j: int, i: int) -> float:
    """Row ``i`` of column ``j`` of ``[A, -b, diag(sigma)]`` (variables, task scale, artificials)."""
    nx = A.shape[1]
    if j < nx:
        return float(A[i, j])
    if j == nx:
        return float(-b[i])
    return float(sigma[i]) if j - nx - 1 == i else 0.0


@kernel(refcount=False, internal=True)
def _basis_matrix(A: F64, b: F64, w: LPViews, transpose: bool) -> None:
    nt = A.shape[0]
    for i in range(nt):
        for r in range(nt):
            v = _column(A, b, w.sigma, w.basis[r], i)
            if transpose:
                w.Bm[r, i] = v
            else:
                w.Bm[i, r] = v


@kernel(refcount=False, internal=True)
def _simplex(A: F64, b: F64, w: LPViews) -> bool:
    """Minimise ``cost . v`` over ``vlo <= v <= vhi`` with ``A x - alpha b + diag(sigma) a = 0``,
    ``v = (x, alpha, a)``, from the basis ``w.basis`` (``status`` 0: basic, -1 / +1: at the
    lower / upper bound). The bounded-variable primal simplex method with Bland's rule (the first
    improving variable enters, ties leave by smallest index), so it cannot cycle. True at an
    optimum, False when a basis turns singular or the iteration limit runs out."""
    nt, nx = A.shape
    nv = nx + 1 + nt
    status, val, lo, hi, cost, basis, y, d = (
        w.status,
        w.val,
        w.vlo,
        w.vhi,
        w.cost,
        w.basis,
        w.y,
        w.d,
    )
    for _ in range(20 * nv):
        # basic values: B v_B = -(N v_N)
        for i in range(nt):
            acc = 0.0
            for j in range(nv):
                if status[j] != 0 and val[j] != 0.0:
                    acc -= _column(A, b, w.sigma, j, i) * val[j]
            y[i] = acc
        _basis_matrix(A, b, w, False)
        if not solve_in_place(w.Bm, y, nt):
            return False
        for r in range(nt):
            val[basis[r]] = y[r]
        # duals: B^T u = c_B
        for r in range(nt):
            y[r] = cost[basis[r]]
        _basis_matrix(A, b, w, True)
        if not solve_in_place(w.Bm, y, nt):
            return False
        enter = -1
        for j in range(nv):
            if status[j] == 0 or lo[j] == hi[j]:
                continue
            dj = cost[j]
            for i in range(nt):
                dj -= y[i] * _column(A, b, w.sigma, j, i)
            if (status[j] == -1 and dj < -1e-11) or (status[j] == 1 and dj > 1e-11):
                enter = j
                break
        if enter < 0:
            return True
        direction = 1.0 if status[enter] == -1 else -1.0
        for i in range(nt):
            d[i] = _column(A, b, w.sigma, enter, i)
        _basis_matrix(A, b, w, False)
        if not solve_in_place(w.Bm, d, nt):
            return False
        dmax = 0.0
        for r in range(nt):
            dmax = max(dmax, abs(d[r]))
        step = hi[enter] - lo[enter]
        leave, leave_to = -1, 0
        for r in range(nt):
            rate = -direction * d[r]
            if abs(rate) <= 1e-12 * (1.0 + dmax):
                continue
            j = basis[r]
            if rate < 0:
                room, to = (val[j] - lo[j]) / -rate, -1
            elif math.isinf(hi[j]):
                continue
            else:
                room, to = (hi[j] - val[j]) / rate, 1
            room = max(room, 0.0)
            if room < step or (room == step and leave >= 0 and j < basis[leave]):
                step, leave, leave_to = room, r, to
        if math.isinf(step):
            return False
        if leave < 0:  # the entering variable reaches its other bound first
            status[enter] = -status[enter]
            val[enter] = hi[enter] if status[enter] == 1 else lo[enter]
        else:
            j = basis[leave]
            status[j] = leave_to
            val[j] = lo[j] if leave_to < 0 else hi[j]
            basis[leave] = enter
            status[enter] = 0
    return False


@kernel(refcount=False, internal=True)
def _lp(A: F64, b: F64, lb: F64, ub: F64, scale: bool, x: F64, w: FeasWork) -> tuple[int, float]:
    """``A x = alpha b``, ``lb <= x <= ub`` (every bound finite) by the simplex method: with
    ``scale``, the largest ``alpha`` in [0, 1]; without, ``alpha = 1``. Returns ``(code, alpha)``
    and a vertex ``x`` of the feasible set (``OK``), or ``INFEASIBLE`` / ``NEEDS_REFERENCE``.

    Phase 1 starts every variable at its bound nearest zero (``alpha`` at 0, or fixed at 1) and
    minimises the artificial variables that absorb the residual; phase 2 maximises ``alpha``.
    """
    nt, nx = A.shape
    v = _lp_views(w, nx, nt)
    status, val, lo, hi, cost, sigma = v.status, v.val, v.vlo, v.vhi, v.cost, v.sigma
    for j in range(nx):
        lo[j], hi[j] = lb[j], ub[j]
        if abs(lb[j]) <= abs(ub[j]):
            status[j], val[j] = -1, lb[j]
        else:
            status[j], val[j] = 1, ub[j]
        cost[j] = 0.0
    lo[nx], hi[nx] = (0.0, 1.0) if scale else (1.0, 1.0)
    status[nx], val[nx], cost[nx] = -1, lo[nx], 0.0
    size = 1.0
    for i in range(nt):
        r = val[nx] * b[i]
        size += abs(b[i])
        for j in range(nx):
            r -= A[i, j] * val[j]
            size += abs(A[i, j]) * max(abs(lb[j]), abs(ub[j]))
        sigma[i] = 1.0 if r >= 0 else -1.0
        a = nx + 1 + i
        lo[a], hi[a], cost[a] = 0.0, math.inf, 1.0
        status[a], val[a] = 0, abs(r)
        v.basis[i] = a
    if not _simplex(A, b, v):
        return NEEDS_REFERENCE, 0.0
    left = 0.0
    for i in range(nt):
        left += val[nx + 1 + i]
    if left > FEASIBILITY_TOL * size:
        return INFEASIBLE, 0.0
    for i in range(nt):
        a = nx + 1 + i
        hi[a], cost[a] = 0.0, 0.0
        if status[a] != 0:
            val[a] = 0.0
    if scale:
        cost[nx] = -1.0
        if not _simplex(A, b, v):
            return NEEDS_REFERENCE, 0.0
    for j in range(nx):
        x[j] = min(max(val[j], lb[j]), ub[j])
    alpha = min(max(float(val[nx]), 0.0), 1.0)
    for i in range(nt):
        r = -alpha * b[i]
        for j in range(nx):
            r += A[i, j] * x[j]
        if abs(r) > FEASIBILITY_TOL * size:
            return NEEDS_REFERENCE, 0.0
    return OK, alpha


@kernel(refcount=False, internal=True)
def _augment(A: F64, b: F64, G: F64, h: F64, lb: F64, ub: F64, w: FeasWork) -> int:
    """The program with its inequality rows marked in ``w.pick`` made equalities, in
    :func:`_aug_views`: variables ``(x, s, t)``, rows ``A x = alpha b`` and ``G_i x + s_i - h_i t
    = 0``, with ``0 <= s_i <= s_max_i``, ``t = 1``. ``s_max_i = max(0, h_i - min over the box of
    G_i x)`` bounds the slack without cutting off any feasible ``x``. Returns the number of rows
    marked, or -1 when a variable of ``x`` is unbounded (``s_max`` would be infinite; the caller
    hands the case to the reference)."""
    nt, nx = A.shape
    ng = 0
    for i in range(G.shape[0]):
        ng += w.pick[i]
    aug = _aug_views(w, nx, nt, ng)
    Ag, bg, lg, ug = aug.A, aug.b, aug.lb, aug.ub
    for j in range(nx):
        if math.isinf(lb[j]) or math.isinf(ub[j]):
            return -1
        lg[j], ug[j] = lb[j], ub[j]
    for i in range(nt + ng):
        for j in range(nx + ng + 1):
            Ag[i, j] = 0.0
    for i in range(nt):
        bg[i] = b[i]
        for j in range(nx):
            Ag[i, j] = A[i, j]
    r = 0
    for i in range(G.shape[0]):
        if not w.pick[i]:
            continue
        bg[nt + r] = 0.0
        least = 0.0
        for j in range(nx):
            Ag[nt + r, j] = G[i, j]
            least += min(G[i, j] * lb[j], G[i, j] * ub[j])
        Ag[nt + r, nx + r] = 1.0
        Ag[nt + r, nx + ng] = -h[i]
        lg[nx + r], ug[nx + r] = 0.0, max(0.0, h[i] - least)
        r += 1
    lg[nx + ng], ug[nx + ng] = 1.0, 1.0
    return ng


@kernel(refcount=False, internal=True)
def _lp_rows(
    A: F64, b: F64, G: F64, h: F64, lb: F64, ub: F64, scale: bool, x: F64, w: FeasWork
) -> tuple[int, float]:
    """:func:`_lp` for the program with inequality rows ``G x <= h``, by row generation: the
    simplex method sees the rows marked in ``w.pick`` (the caller's first choice), then also
    every row its answer breaks, until the answer keeps them all. A round's program is a
    relaxation of the whole, so INFEASIBLE is final, and an answer that keeps every row is a
    vertex of the whole program (with ``scale``, its largest ``alpha``: no row left out binds).
    The simplex method's basis then has ``nt`` plus the rows that matter (a few) instead of every
    row: on the Panda with 60 obstacle rows, a cold start's feasible point 5.6 ms -> about 0.1 ms.
    """
    nx = A.shape[1]
    for _ in range(G.shape[0] + 1):  # every round marks at least one more row
        ng = _augment(A, b, G, h, lb, ub, w)
        if ng < 0:
            return NEEDS_REFERENCE, 0.0
        aug = _aug_views(w, nx, A.shape[0], ng)
        code, alpha = _lp(aug.A, aug.b, aug.lb, aug.ub, scale, aug.x, w)
        for j in range(nx):
            x[j] = aug.x[j]
        if code != OK:
            return code, alpha
        more = False
        for i in range(G.shape[0]):
            if not w.pick[i] and _breaks(G, h, i, x):
                w.pick[i] = True
                more = True
        if not more:
            return OK, alpha
    return NEEDS_REFERENCE, 0.0


@kernel(refcount=False, internal=True)
def _breaks(G: F64, h: F64, i: int, x: F64) -> bool:
    """True when ``x`` breaks ``G_i x <= h_i`` by more than rounding (``FEASIBILITY_TOL``
    relative to the row's size)."""
    gx = 0.0
    size = 1.0 + abs(h[i])
    for j in range(G.shape[1]):  # x may be longer (a scratch buffer such as ``w.centre``)
        gx += G[i, j] * x[j]
        size += abs(G[i, j] * x[j])
    return bool(gx - h[i] > FEASIBILITY_TOL * size)


@kernel(refcount=False)
def rows_hold(G: F64, h: F64, x: F64) -> bool:
    """True when ``G x <= h`` up to rounding (``FEASIBILITY_TOL`` relative to the row's size)."""
    for i in range(G.shape[0]):
        if _breaks(G, h, i, x):
            return False
    return True


@kernel(refcount=False, internal=True)
def task_scale_rows(A: F64, b: F64, G: F64, h: F64, lb: F64, ub: F64, w: FeasWork) -> float:
    """:func:`task_scale` for programs of any row count and with inequality rows ``G x <= h``,
    by the simplex method (:func:`_lp_rows`); the answer's vertex is left in ``w.centre``. Kept apart
    from the 2-D kernel, whose hot path would otherwise carry the simplex method's code."""
    if G.shape[0] > 0:  # first the rows that the box's point nearest zero breaks
        for j in range(A.shape[1]):
            w.centre[j] = min(max(0.0, lb[j]), ub[j])
        for i in range(G.shape[0]):
            w.pick[i] = _breaks(G, h, i, w.centre)
        code, alpha = _lp_rows(A, b, G, h, lb, ub, True, w.centre, w)
        return alpha if code == OK else (-1.0 if code == INFEASIBLE else -2.0)
    if A.shape[0] == 2:
        return task_scale(A, b, lb, ub, w)
    if _mark_free(lb, ub, w.free) > 0:
        return 1.0 if free_rank(A, w.free, w) == A.shape[0] else -2.0
    code, alpha = _lp(A, b, lb, ub, True, w.centre, w)
    return alpha if code == OK else (-1.0 if code == INFEASIBLE else -2.0)


@kernel
def task_scale_of(A: F64, b: F64, G: F64, h: F64, lb: F64, ub: F64) -> float:
    """:func:`task_scale_rows` with its own buffers (the entry point for callers in Python)."""
    return task_scale_rows(A, b, G, h, lb, ub, feas_work(A.shape[1], A.shape[0], G.shape[0]))


@kernel(refcount=False, internal=True)
def feasible_point_rows(
    A: F64, b: F64, G: F64, h: F64, lb: F64, ub: F64, x: F64, w: FeasWork
) -> tuple[int, bool]:
    """:func:`feasible_point` for programs of any row count and with inequality rows
    ``G x <= h``. Without inequality rows: the 2-D geometry, or a vertex found by the simplex
    method (:func:`_lp`; ``unique`` always False with other than two rows); unbounded variables
    whose columns span the task space take the least-norm solution for the rest of the task, the
    bounded ones the point of their box nearest zero; with no unbounded variable, the least-norm
    correction of that point when it stays in the box, else a vertex. With them: that point when
    it keeps every row (an inactive row changes nothing), else a vertex of the augmented program
    found by row generation from the rows that point breaks (:func:`_lp_rows`). Kept apart from the 2-D
    kernel, whose hot path would otherwise carry the simplex method's code."""
    if G.shape[0] == 0:  # the brief's programs: straight to the task's point (the hot path)
        if A.shape[0] == 2:
            return feasible_point(A, b, lb, ub, x, w)
        return _task_point(A, b, lb, ub, x, w)
    code, unique = _task_point(A, b, lb, ub, x, w)
    if code == INFEASIBLE or (code == OK and rows_hold(G, h, x)):
        return code, unique
    for i in range(G.shape[0]):  # first the rows that point breaks (all when there is none)
        w.pick[i] = code != OK or _breaks(G, h, i, x)
    code, _ = _lp_rows(A, b, G, h, lb, ub, False, x, w)
    return code, False


@kernel(refcount=False, internal=True)
def _task_point(A: F64, b: F64, lb: F64, ub: F64, x: F64, w: FeasWork) -> tuple[int, bool]:
    """A feasible point of ``A x = b``, ``lb <= x <= ub`` (see :func:`feasible_point_rows`)."""
    nt, n = A.shape
    if nt == 2:
        return feasible_point(A, b, lb, ub, x, w)
    free = w.free
    if _mark_free(lb, ub, free) > 0:
        if free_rank(A, free, w) != nt:
            return NEEDS_REFERENCE, False
        lp = _lp_views(w, n, nt)
        for i in range(nt):
            lp.y[i] = b[i]
        for j in range(n):
            if not free[j]:
                x[j] = min(max(0.0, lb[j]), ub[j])
                for i in range(nt):
                    lp.y[i] -= A[i, j] * x[j]
        for i in range(nt):
            for k in range(nt):
                acc = 0.0
                for j in range(n):
                    if free[j]:
                        acc += A[i, j] * A[k, j]
                lp.Bm[i, k] = acc
        if not solve_in_place(lp.Bm, lp.y, nt):
            return NEEDS_REFERENCE, False
        for j in range(n):
            if free[j]:
                acc = 0.0
                for i in range(nt):
                    acc += A[i, j] * lp.y[i]
                x[j] = acc
        return OK, False
    # no free variable: the least-norm correction of the box's point nearest zero, where it
    # stays in the box (no simplex pivot: a cold start's feasible point near the least effort)
    lp = _lp_views(w, n, nt)
    for i in range(nt):
        acc = b[i]
        for j in range(n):
            acc -= A[i, j] * min(max(0.0, lb[j]), ub[j])
        lp.y[i] = acc
        for k in range(nt):
            acc = 0.0
            for j in range(n):
                acc += A[i, j] * A[k, j]
            lp.Bm[i, k] = acc
    inside = solve_in_place(lp.Bm, lp.y, nt)
    for j in range(n):
        if not inside:
            break
        acc = min(max(0.0, lb[j]), ub[j])
        for i in range(nt):
            acc += A[i, j] * lp.y[i]
        inside = lb[j] <= acc <= ub[j]
        lp.val[j] = acc
    for i in range(nt):  # and keeps the task to rounding (A A^T may be close to singular)
        if not inside:
            break
        acc, size = -b[i], 1.0 + abs(b[i])
        for j in range(n):
            acc += A[i, j] * lp.val[j]
            size += abs(A[i, j] * lp.val[j])
        inside = abs(acc) <= FEASIBILITY_TOL * size
    if inside:
        for j in range(n):
            x[j] = lp.val[j]
        return OK, False
    code, _ = _lp(A, b, lb, ub, False, x, w)
    return code, False


@kernel
def feasible_point_of(A: F64, b: F64, G: F64, h: F64, lb: F64, ub: F64, x: F64) -> tuple[int, bool]:
    """:func:`feasible_point_rows` with its own buffers (the entry point for callers in Python)."""
    return feasible_point_rows(A, b, G, h, lb, ub, x, feas_work(x.size, A.shape[0], G.shape[0]))
