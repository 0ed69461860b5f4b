"""The feasibility of a two-row task, compiled: the 2-D zonotope geometry, and the buffers every
feasibility kernel shares.

``task_scale`` gives the largest ``alpha`` in [0, 1] with ``A x = alpha b``, ``lb <= x <= ub``
feasible, ``feasible_point`` a point of that set; both exact, in O(n) work, for the planar task
(docs/mathematics.md, "Infeasible programs"). Other row counts and programs with inequality rows
take the simplex method of :mod:`emdm.core.simplex`. What a feasibility kernel returns: ``OK``,
``NEEDS_REFERENCE`` (a case left to the numpy or HiGHS reference) or ``INFEASIBLE``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from .jit import kernel
from .kernels import matrix_rank
from .tolerances import FEASIBILITY_TOL, RANK_TOL

F64 = NDArray[np.float64]

# what a feasibility kernel returns
OK, NEEDS_REFERENCE, INFEASIBLE = 0, 1, 2


class FeasWork(NamedTuple):
    """Scratch buffers of the feasibility kernels (for programs of ``nx`` variables, ``nt`` task
    rows and ``ng`` inequality rows): the 2-D zonotope geometry, the simplex method of programs
    with other row counts, and at the end of ``lpf`` the program with its inequality rows made
    equalities (:func:`_augment`, :class:`AugViews`) for the rows marked in ``pick`` (the rows
    the simplex method sees in a round of :func:`emdm.core.simplex._lp_rows`)."""

    cand: F64
    base: F64
    free: NDArray[np.bool_]
    parallel: NDArray[np.bool_]
    centre: F64
    lpf: F64
    lpi: NDArray[np.int64]
    pick: NDArray[np.bool_]


class AugViews(NamedTuple):
    """The augmented program of :func:`_augment` (views of the end of ``FeasWork.lpf``): ``A``
    and ``b`` of ``A x = alpha b``, bounds ``lb``, ``ub`` and the answer ``x``."""

    A: F64
    b: F64
    lb: F64
    ub: F64
    x: F64


@kernel(refcount=False, internal=True)
def _lp_size(nx: int, nt: int) -> int:
    """Length of the simplex method's part of ``lpf`` for ``nx`` variables and ``nt`` rows."""
    nv = nx + 1 + nt
    return 4 * nv + 3 * nt + nt * nt + nt * nx


@kernel(inline=True)
def _aug_views(w: FeasWork, nx: int, nt: int, ng: int) -> AugViews:
    """Views of the augmented program (``nx + ng + 1`` variables, ``nt + ng`` rows)."""
    nxa, nta = nx + ng + 1, nt + ng
    f = w.lpf
    a = _lp_size(nxa, nta)
    b = a + nta * nxa
    return AugViews(
        f[a:b].reshape((nta, nxa)),
        f[b : b + nta],
        f[b + nta : b + nta + nxa],
        f[b + nta + nxa : b + nta + 2 * nxa],
        f[b + nta + 2 * nxa : b + nta + 3 * nxa],
    )


class LPViews(NamedTuple):
    """Views of :class:`FeasWork`'s flat buffers for the simplex method (:func:`_lp_views`):
    per variable its status (0 basic, -1 / +1 at a bound), value, bounds and cost; per row the
    artificial's sign, the basis, and scratch; the basis matrix; the free columns."""

    status: NDArray[np.int64]
    val: F64
    vlo: F64
    vhi: F64
    cost: F64
    sigma: F64
    basis: NDArray[np.int64]
    Bm: F64
    y: F64
    d: F64
    Af: F64


@kernel
def feas_work(nx: int, nt: int, ng: int) -> FeasWork:
    """Buffers for the feasibility kernels of a program with ``nx`` variables, ``nt`` task rows
    and ``ng`` inequality rows (the simplex method's buffers fit the augmented program of
    :func:`_augment`: ``nx + ng + 1`` variables, ``nt + ng`` rows)."""
    nxa = nx + ng + 1 if ng > 0 else nx
    nta = nt + ng
    nv = nxa + 1 + nta
    aug = nta * nxa + nta + 3 * nxa if ng > 0 else 0
    return FeasWork(
        np.empty((4 * (nx + 3), 2)),
        np.empty((nx + 3, 2)),
        np.empty(nxa, dtype=np.bool_),
        np.empty(nx, dtype=np.bool_),
        np.empty(nxa),
        np.empty(_lp_size(nxa, nta) + aug),
        np.empty(nv + nta, dtype=np.int64),
        np.empty(ng, dtype=np.bool_),
    )


@kernel(inline=True)
def _lp_views(w: FeasWork, nx: int, nt: int) -> LPViews:
    """The simplex method's arrays as views of ``w.lpf`` and ``w.lpi`` (see :class:`LPViews`)."""
    nv = nx + 1 + nt
    f = w.lpf
    a = 4 * nv
    b = a + 3 * nt
    c = b + nt * nt
    return LPViews(
        w.lpi[:nv],
        f[:nv],
        f[nv : 2 * nv],
        f[2 * nv : 3 * nv],
        f[3 * nv : a],
        f[a : a + nt],
        w.lpi[nv : nv + nt],
        f[b:c].reshape((nt, nt)),
        f[a + nt : a + 2 * nt],
        f[a + 2 * nt : b],
        f[c : c + nt * nx].reshape((nt, nx)),
    )


@kernel(refcount=False, internal=True)
def _ray_interval(
    G: F64, lb: F64, ub: F64, y0x: float, y0y: float, dx: float, dy: float, w: FeasWork
) -> tuple[float, float, float, float, bool]:
    """``(t_lo, t_hi, wx, wy, found)``: ``y0 + t d`` lies in the zonotope ``{G x : lb <= x <= ub}``
    for ``t`` in [t_lo, t_hi]; ``(wx, wy)`` is the normal of the half-plane that sets ``t_hi``."""
    cand, base = w.cand, w.base
    nb = G.shape[1]
    nbase = 0
    for j in range(nb + 3):
        if j < nb:
            vx, vy = G[0, j], G[1, j]
        elif j == nb:
            vx, vy = 1.0, 0.0
        elif j == nb + 1:
            vx, vy = 0.0, 1.0
        else:
            vx, vy = dx, dy
        norm = math.sqrt(vx * vx + vy * vy)  # not hypot: of order 1 here, and hypot's care for
        # overflow costs about 5 % of a batch's step (libm's hypot is a call of ~20 ns)
        if norm > 0:
            base[nbase, 0] = vx / norm
            base[nbase, 1] = vy / norm
            nbase += 1
    count = 0
    for j in range(nbase):
        vx, vy = base[j, 0], base[j, 1]
        cand[count, 0], cand[count, 1] = vx, vy
        cand[count + 1, 0], cand[count + 1, 1] = -vy, vx
        cand[count + 2, 0], cand[count + 2, 1] = -vx, -vy
        cand[count + 3, 0], cand[count + 3, 1] = vy, -vx
        count += 4
    size = 1.0 + abs(y0x) + abs(y0y)
    for j in range(nb):
        size += (abs(G[0, j]) + abs(G[1, j])) * max(abs(lb[j]), abs(ub[j]))
    dsum = abs(dx) + abs(dy)
    t_lo, t_hi = -math.inf, math.inf
    bwx, bwy = 0.0, 0.0
    found = False
    for c in range(count):
        wx, wy = cand[c, 0], cand[c, 1]
        h = -(wx * y0x + wy * y0y)
        for j in range(nb):
            s = wx * G[0, j] + wy * G[1, j]
            h += max(s * lb[j], s * ub[j])
        a = wx * dx + wy * dy
        if abs(a) <= 1e-13 * max(dsum, 1e-300):
            if h < -FEASIBILITY_TOL * size:
                return math.inf, -math.inf, 0.0, 0.0, False
        elif a > 0:
            r = h / a
            if r < t_hi:
                t_hi, bwx, bwy, found = r, wx, wy, True
        else:
            r = h / a
            if r > t_lo:
                t_lo = r
    return t_lo, t_hi, bwx, bwy, found


@kernel(refcount=False, internal=True)
def _boundary_preimage(
    G: F64,
    lb: F64,
    ub: F64,
    tx: float,
    ty: float,
    wx: float,
    wy: float,
    x: F64,
    w: FeasWork,
) -> int:
    """A box point ``x`` with ``G x = t`` for ``t`` on the supporting line of normal ``w``.

    Returns how many generators are parallel to that edge (they share its length).
    """
    centre, parallel = w.centre, w.parallel
    nb = G.shape[1]
    ux, uy = -wy, wx
    rx, ry = tx, ty
    count = 0
    for j in range(nb):
        s = wx * G[0, j] + wy * G[1, j]
        gn = math.sqrt(G[0, j] * G[0, j] + G[1, j] * G[1, j])
        parallel[j] = abs(s) <= 1e-12 * max(gn, 1e-300)
        if parallel[j]:
            x[j] = centre[j]
            count += 1
        else:
            x[j] = ub[j] if s > 0 else lb[j]
        rx -= G[0, j] * x[j]
        ry -= G[1, j] * x[j]
    denom = 0.0
    for j in range(nb):
        if parallel[j]:
            denom += abs(ux * G[0, j] + uy * G[1, j]) * 0.5 * (ub[j] - lb[j])
    if denom > 0:
        tau = min(1.0, max(-1.0, (ux * rx + uy * ry) / denom))
        for j in range(nb):
            if parallel[j]:
                gu = ux * G[0, j] + uy * G[1, j]
                sgn = 1.0 if gu > 0 else (-1.0 if gu < 0 else 0.0)
                x[j] += tau * 0.5 * (ub[j] - lb[j]) * sgn
    return count


@kernel(refcount=False, internal=True)
def free_rank(A: F64, free: NDArray[np.bool_], w: FeasWork) -> int:
    """Rank of the columns of ``A`` marked free (at most the row count ``nt``).

    Two rows: rank 2 when some pair of columns has a 2x2 minor above ``RANK_TOL`` times the squared
    size of the columns (minors are exact zero for parallel columns and accurate to rounding
    otherwise). Other row counts: Gaussian elimination with complete pivoting on a copy, a pivot
    counting when above ``RANK_TOL`` times the largest entry times the row count.
    """
    nt, n = A.shape
    if nt == 2:
        scale = 0.0
        for j in range(n):
            if free[j]:
                scale += A[0, j] * A[0, j] + A[1, j] * A[1, j]
        if scale <= 0:
            return 0
        for i in range(n):
            if not free[i]:
                continue
            for k in range(i + 1, n):
                if free[k] and abs(A[0, i] * A[1, k] - A[1, i] * A[0, k]) > RANK_TOL * scale:
                    return 2
        return 1
    M = _lp_views(w, n, nt).Af
    cols = 0
    big = 0.0
    for j in range(n):
        if free[j]:
            for i in range(nt):
                M[i, cols] = A[i, j]
                big = max(big, abs(A[i, j]))
            cols += 1
    if big <= 0:
        return 0
    return matrix_rank(M, nt, cols, RANK_TOL * big * nt)


@kernel(refcount=False, internal=True)
def _mark_free(lb: F64, ub: F64, free: NDArray[np.bool_]) -> int:
    count = 0
    for j in range(lb.size):
        free[j] = math.isinf(lb[j]) and math.isinf(ub[j])
        count += free[j]
    return count


@kernel(refcount=False)
def task_scale(A: F64, b: F64, lb: F64, ub: F64, w: FeasWork) -> float:
    """Largest ``alpha`` in [0, 1] with ``A x = alpha b``, ``lb <= x <= ub`` feasible (two rows;
    :func:`task_scale_rows` takes any).

    Returns -1 when no ``alpha`` in [0, 1] is, and -2 for the case left to the numpy reference
    (unbounded variables whose columns have rank < 2).
    """
    if _mark_free(lb, ub, w.free) > 0:
        return 1.0 if free_rank(A, w.free, w) == A.shape[0] else -2.0
    t_lo, t_hi, _, _, _ = _ray_interval(A, lb, ub, 0.0, 0.0, b[0], b[1], w)
    lo = max(0.0, t_lo)
    hi = min(1.0, t_hi)
    if hi < lo - 1e-12:
        return -1.0
    return hi if hi >= lo else lo


@kernel(refcount=False)
def feasible_point(A: F64, b: F64, lb: F64, ub: F64, x: F64, w: FeasWork) -> tuple[int, bool]:
    """Fill ``x`` with a feasible point; returns ``(OK | INFEASIBLE | NEEDS_REFERENCE, unique)``.

    Walks from the box centre towards ``b``, leaves the zonotope through an edge, reads the box
    vertex (or edge) that maps there and takes the convex combination that lands on ``b``.
    ``unique`` is True when ``b`` lies on an edge whose preimage is one point (at most one
    generator parallel to the edge): then ``x`` is the only feasible point, hence the optimum.
    Two task rows; :func:`feasible_point_rows` takes any.
    """
    free, centre = w.free, w.centre
    n = A.shape[1]
    if _mark_free(lb, ub, free) > 0:
        if free_rank(A, free, w) != 2:
            return NEEDS_REFERENCE, False
        rx, ry = b[0], b[1]
        g00 = g01 = g11 = 0.0
        for j in range(n):
            if not free[j]:
                x[j] = min(max(0.0, lb[j]), ub[j])
                rx -= A[0, j] * x[j]
                ry -= A[1, j] * x[j]
            else:
                g00 += A[0, j] * A[0, j]
                g01 += A[0, j] * A[1, j]
                g11 += A[1, j] * A[1, j]
        det = g00 * g11 - g01 * g01
        l0 = (g11 * rx - g01 * ry) / det
        l1 = (g00 * ry - g01 * rx) / det
        for j in range(n):
            if free[j]:
                x[j] = A[0, j] * l0 + A[1, j] * l1
        return OK, False
    y0x = y0y = 0.0
    for j in range(n):
        centre[j] = 0.5 * (lb[j] + ub[j])
        x[j] = centre[j]
        y0x += A[0, j] * centre[j]
        y0y += A[1, j] * centre[j]
    dx, dy = b[0] - y0x, b[1] - y0y
    noise = RANK_TOL * (1.0 + max(abs(b[0]), abs(b[1])) + max(abs(y0x), abs(y0y)))
    unique = False
    if max(abs(dx), abs(dy)) > noise:
        t_lo, t_hi, wx, wy, found = _ray_interval(A, lb, ub, y0x, y0y, dx, dy, w)
        if not found or t_hi < 1.0 - 1e-9 or t_lo > t_hi:
            return INFEASIBLE, False
        count = _boundary_preimage(A, lb, ub, y0x + t_hi * dx, y0y + t_hi * dy, wx, wy, x, w)
        unique = t_hi <= 1.0 + 1e-12 and count <= 1
        if t_hi > 1.0:
            for j in range(n):
                x[j] = centre[j] + (x[j] - centre[j]) / t_hi
    amax = xsum = 0.0
    r0, r1 = -b[0], -b[1]
    for j in range(n):
        amax = max(amax, abs(A[0, j]), abs(A[1, j]))
        xsum += abs(x[j])
        r0 += A[0, j] * x[j]
        r1 += A[1, j] * x[j]
    if max(abs(r0), abs(r1)) > FEASIBILITY_TOL * (1.0 + max(abs(b[0]), abs(b[1])) + amax * xsum):
        return INFEASIBLE, False
    return OK, unique
