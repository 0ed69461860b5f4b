"""Inequality rows in the compiled loop: rows far from binding are left out of the first solve
and checked at its answer (lazy rows, :data:`emdm.core.tolerances.LAZY`), a degenerate vertex is
settled by the certificate or by loosening the rows by about 1e-9, and the active rows are
counted for the record (docs/mathematics.md, "Obstacles")."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..core.jit import kernel
from ..core.tolerances import AT_BOUND, LAZY
from ..solvers.kernels import BOUND_TOL, KKT_TOL, MAX_ITER_EXCEEDED, OK, active_set, certify
from .buffers import StepWork

F64 = NDArray[np.float64]


@kernel(refcount=False)
def count_active_rows(G: F64, h: F64, x: F64) -> int:
    """How many rows of ``G x <= h`` hold with equality at ``x`` (within ``AT_BOUND (1 + |h_i|)``,
    the record's definition of "at a bound")."""
    count = 0
    for i in range(G.shape[0]):
        gx = 0.0
        for j in range(x.size):
            gx += G[i, j] * x[j]
        if h[i] - gx <= AT_BOUND * (1.0 + abs(h[i])):
            count += 1
    return count


@kernel(refcount=False, internal=True)
def partition_rows(G: F64, h: F64, ids: F64, lb: F64, ub: F64, ng: int) -> int:
    """Reorder the rows ``G[:ng] x <= h[:ng]`` so that those that may bind come first; returns
    how many. A row is left for later ("lazy") when it keeps at least half its right-hand side
    against the largest ``G_i x`` the bounds allow: ``h_i >= LAZY * max_box G_i x`` and ``h_i >
    0`` (obstacles beyond their influence distance, as a rule). The order does not change the
    program; :func:`settle_rows` checks the lazy rows at the answer."""
    near = 0
    nx = G.shape[1]
    for i in range(ng):
        reach = 0.0
        for j in range(nx):
            g = G[i, j]
            if g > 0.0:
                reach += g * ub[j]
            elif g < 0.0:
                reach += g * lb[j]
        if h[i] > 0.0 and h[i] >= LAZY * reach:
            continue
        if i != near:
            for j in range(nx):
                G[i, j], G[near, j] = G[near, j], G[i, j]
            h[i], h[near] = h[near], h[i]
            ids[i], ids[near] = ids[near], ids[i]
        near += 1
    return near


@kernel(refcount=False, internal=True)
def recall_rows(w: StepWork, ng: int) -> None:
    """Mark in the active set's working set the rows that the last answer held, found by their
    ids (``w.held``), wherever this step's program put them: rows come and go as links come
    within reach of obstacles, and :func:`partition_rows` moves them, so a row's index is no
    identity. Without it, a row count that changes by one costs a cold start (on the Panda with
    10 spheres, about 0.5 ms against 5 us)."""
    n = w.x.size
    held = w.rows[1]
    for i in range(ng):
        flag = 0
        for r in range(held):
            if w.ids[i] == w.held[r]:
                flag = 1
                break
        w.qp.work[n + i] = flag


@kernel(refcount=False, internal=True)
def hold_rows(w: StepWork, ng: int) -> None:
    """Keep the ids of the rows in the working set of the answer (for :func:`recall_rows`)."""
    n = w.x.size
    held = 0
    for i in range(ng):
        if w.qp.work[n + i]:
            w.held[held] = w.ids[i]
            held += 1
    w.rows[1] = held


@kernel(refcount=False, internal=True)
def settle_rows(w: StepWork, near: int, ng: int, code: int, iterations: int) -> tuple[int, int]:
    """After the active set on the rows ``G[:near]`` returned ``(code, iterations)``: unravel a
    cycle (:func:`_unravel`), and when the answer breaks one of the lazy rows ``G[near:ng]``,
    solve again on all of them (so the answer is the optimum of the whole program). Called only
    for programs with rows: passing the step's buffers costs a reference count per array."""
    if code == MAX_ITER_EXCEEDED and near > 0:
        code, iterations = _unravel(w, near, iterations)
    if code != OK or near == ng:
        return code, iterations
    for i in range(near, ng):
        if _row_excess(w.G, w.h, i, w.x) > 0.0:
            n = w.x.size
            for r in range(near, ng):
                w.qp.work[n + r] = 0
            more, again = active_set(
                w.P, w.c, w.A, w.b, w.G[:ng], w.h[:ng], w.lb, w.ub, w.x, w.qp, w.res, True
            )
            return more, iterations + again
    return code, iterations


@kernel(internal=True)
def _unravel(w: StepWork, near: int, iterations: int) -> tuple[int, int]:
    """After the active set cycled on a degenerate vertex (more constraints active than
    variables, ties in its ratio tests): accept the point where it stopped if the certificate
    (best multipliers over every active constraint) says it is the optimum; else solve the
    program with every row loosened by a distinct amount (about 1e-9 of its size;
    deterministic), then, from the working set found there, the program itself, whose warm
    start accepts that working set only where it is the exact optimum."""
    G, h = w.G[:near], w.h[:near]
    certify(w.P, w.c, w.A, w.b, G, h, w.lb, w.ub, w.x, w.qp, w.res)
    if max(w.res[0], w.res[1], w.res[2]) <= KKT_TOL and w.res[3] <= BOUND_TOL:
        return OK, iterations  # where it stopped is the optimum: a degenerate vertex (more
        # constraints active than variables) whose multipliers the certificate finds
    exact = w.h[:near].copy()  # a rare path: it may allocate
    for i in range(near):
        w.h[i] += 1e-9 * (1.0 + abs(w.h[i])) * (1.0 + (i * 7919) % 97) / 97.0
    code, more = active_set(
        w.P, w.c, w.A, w.b, w.G[:near], w.h[:near], w.lb, w.ub, w.x, w.qp, w.res, True
    )
    for i in range(near):
        w.h[i] = exact[i]
    iterations += more
    if code != OK:
        return MAX_ITER_EXCEEDED, iterations
    w.qp.warm[0] = True
    code, more = active_set(
        w.P, w.c, w.A, w.b, w.G[:near], w.h[:near], w.lb, w.ub, w.x, w.qp, w.res, True
    )
    return code, iterations + more


@kernel(refcount=False, internal=True)
def _row_excess(G: F64, h: F64, i: int, x: F64) -> float:
    acc = -h[i]
    for j in range(x.size):
        acc += G[i, j] * x[j]
    return float(acc)
