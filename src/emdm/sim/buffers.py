"""The compiled loop's inputs and buffers: the task (:class:`Motion`), the record of a run
(:class:`Record`, grown in chunks), one step's buffers (:class:`StepWork`), and the record's one
definition of a joint at a bound (:func:`mark_active`)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..core.checks import memory_available
from ..core.distance import AXIS, GAP, POINT
from ..core.jit import kernel
from ..core.kernels import KinWork, SpatialWork, kin_work, spatial_work
from ..core.tolerances import AT_BOUND
from ..errors import ScenarioError
from ..solvers.kernels import QPWork, qp_work

F64 = NDArray[np.float64]


class Motion(NamedTuple):
    """The task as kernel input: goal (m; a pose's orientation as a rotation vector, rad), gain
    (1/s, per task row), dt (s), tolerance (m, and rad for a pose), steps, and the kind of task
    (``core.kernels.TASK_*``)."""

    goal: F64
    kp: F64
    dt: float
    tolerance: float
    n_steps: int
    task: int
    obstacles: F64
    """The scenario's obstacles, packed (:mod:`emdm.core.distance`; empty without them)."""


class Record(NamedTuple):
    """Every recorded quantity, preallocated: states ``0..cap`` and commands ``0..cap-1``."""

    q: F64
    p: F64
    e: F64
    v: F64
    m: F64
    qd: F64
    effort: F64
    manip: F64
    delta: F64
    alpha: F64
    lo: F64
    hi: F64
    active: NDArray[np.int8]
    iterations: NDArray[np.int64]
    ticks: NDArray[np.int64]
    kkt: F64
    excess: F64
    rows: NDArray[np.int64]
    rows_active: NDArray[np.int64]
    clearance: F64


class StepWork(NamedTuple):
    """One step's buffers: kinematics (planar, and spatial: empty for a planar arm), the program
    ``(P, c, A, b, G, h, lb, ub)``, answer and residuals; ``rows`` holds the step's row count
    and how many rows the last answer held (their ids in ``held``, :mod:`emdm.sim.rows`)."""

    kin: KinWork
    sp: SpatialWork
    qp: QPWork
    J: F64
    Jm: F64
    P: F64
    c: F64
    A: F64
    b: F64
    G: F64
    h: F64
    lb: F64
    ub: F64
    x: F64
    res: F64
    rows: NDArray[np.int64]
    pts: F64
    axes: F64
    gaps: F64
    ids: F64
    held: F64


@kernel
def new_record(cap: int, n: int, nt: int) -> Record:
    """A record with room for ``cap`` commands of an ``n``-joint arm on an ``nt``-row task."""
    return Record(
        np.empty((cap + 1, n)),
        np.empty((cap + 1, nt)),
        np.empty((cap + 1, nt)),
        np.empty((cap + 1, nt)),
        np.empty(cap + 1),
        np.empty((cap, n)),
        np.empty(cap),
        np.empty(cap),
        np.zeros((cap, nt)),
        np.empty(cap),
        np.empty((cap, n)),
        np.empty((cap, n)),
        np.zeros((cap, n), dtype=np.int8),
        np.zeros(cap, dtype=np.int64),
        np.zeros(cap, dtype=np.int64),
        np.empty(cap),
        np.empty(cap),
        np.zeros(cap, dtype=np.int64),
        np.zeros(cap, dtype=np.int64),
        np.full(cap + 1, np.inf),
    )


@kernel
def step_work(n: int, nx: int, nt: int, ng: int, no: int) -> StepWork:
    """Buffers for one step of an ``n``-joint arm whose program has ``nx`` variables, ``nt``
    task rows and ``ng`` inequality rows, among ``no`` obstacles."""
    return StepWork(
        kin_work(n),
        spatial_work(n if nt != 2 else 0),
        qp_work(nx, nt, ng),
        np.empty((nt, n)),
        np.empty(n),
        np.empty((nx, nx)),
        np.empty(nx),
        np.zeros((nt, nx)),
        np.empty(nt),
        np.zeros((ng, nx)),
        np.zeros(ng),
        np.empty(nx),
        np.empty(nx),
        np.empty(nx),
        np.empty(4),
        np.zeros(2, dtype=np.int64),
        np.zeros((n + 2, POINT)),
        np.zeros((n, AXIS)),
        np.zeros((no, n + 1, GAP)),
        np.zeros(ng),
        np.zeros(ng),
    )


@kernel(refcount=False)
def mark_active(qd: F64, lo: F64, hi: F64, active: NDArray[np.int8]) -> None:
    """``active_j`` = -1 when ``qd_j`` is at its lower bound, +1 at its upper bound, else 0: the
    one definition of "at a bound" (:data:`emdm.core.tolerances.AT_BOUND`), recorded in
    ``Run.active`` and read from there by the report and the playground."""
    for j in range(qd.size):
        if qd[j] <= lo[j] + AT_BOUND * (1.0 + abs(lo[j])):
            active[j] = -1
        elif qd[j] >= hi[j] - AT_BOUND * (1.0 + abs(hi[j])):
            active[j] = 1
        else:
            active[j] = 0


def work_bytes(n: int, nx: int, nt: int, ng: int, spatial: bool) -> int:
    """About the bytes :func:`step_work` allocates (within 25 %, tested): the planar gradient's
    ``n (n - 1) / 2`` minors by ``n`` joints, the spatial Hessian, and the program's matrices."""
    pairs = n * (n - 1) // 2  # the planar kinematics buffers exist for every arm
    cols = 2 * nt + 2 * nx + ng
    size = nx + nt + ng
    words = pairs * (n + 1) + (6 * n * n if spatial else 0)
    words += (
        2 * (nx + ng) * (cols + 1) + size * size + nx * nx + (nt + ng) * nx + 40 * (size + cols)
    )
    return 8 * words


def record_bytes(steps: int, n: int, nt: int) -> int:
    """About the bytes :func:`new_record` allocates for ``steps`` commands."""
    return 8 * (steps + 1) * (5 * n + 4 * nt + 14)


def require_memory(
    source: str, n: int, nx: int, nt: int, ng: int, spatial: bool, *, copies: int, steps: int
) -> None:
    """Refuse, in one line naming the key to change, a run whose buffers (``copies`` sets of
    work and of a record of ``steps`` commands) would take more than half of this machine's
    memory, before anything is allocated."""
    have = memory_available()
    work = copies * work_bytes(n, nx, nt, ng, spatial)
    record = copies * record_bytes(steps, n, nt)
    if not have or work + record <= have // 2:
        return
    key, what, hint = (
        ("arm", f"{n} joints need", "use fewer joints")
        if work >= record
        else ("motion.max_time", f"a record of {steps} steps needs", "use a shorter one")
    )
    sets = f"{copies} sets, one per thread" if copies > 1 else "1 set"
    raise ScenarioError(
        source,
        key,
        f"{what} about {(work + record) / 1e9:.3g} GB of buffers ({sets}), more than half of "
        f"this machine's {have / 1e9:.3g} GB: {hint}",
    )
