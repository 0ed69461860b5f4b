"""The program of a controller at a state, built by its terms in one compiled pass.

A controller is a list of terms (:mod:`emdm.core.controllers`); :class:`ProgramData` is that list
as kernel input: per term its integer (:data:`emdm.core.terms.base.CODE`), weight and numbers.
:func:`build_program` starts from the empty program (``P = 0``, ``c = 0``, ``lb = -inf``,
``ub = +inf``, no rows) and lets each term write its part; it is the only place that lists the
terms' writers, so adding a term means adding its module and one line below.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..jit import kernel
from . import (
    centring,
    clearance,
    damper,
    effort,
    manipulability,
    obstacle,
    plane,
    slack,
    task,
    velocity_box,
)
from .base import (
    CENTRING,
    CLEARANCE,
    DAMPER,
    EFFORT,
    F64,
    MANIPULABILITY,
    OBSTACLE,
    PLANE,
    SLACK,
    TASK,
    VELOCITY_BOX,
    ProgramOut,
    StepInput,
)

SHAPED = frozenset((int(PLANE), int(OBSTACLE), int(CLEARANCE)))
"""The terms that read obstacles or write inequality rows."""


class ProgramData(NamedTuple):
    """A controller's terms as kernel input: ``codes`` (one integer per term, in order),
    ``weights``, and each term's numbers ``data[start[k]:start[k + 1]]``; ``slack`` says whether
    the program has the task slack (``x = (qd, delta)``), ``rows`` how many inequality rows its
    terms may write at most."""

    codes: NDArray[np.int64]
    weights: F64
    start: NDArray[np.int64]
    data: F64
    slack: bool
    rows: int


@kernel(refcount=False)
def build_program(prog: ProgramData, s: StepInput, out: ProgramOut, full: Any) -> int:
    """Write the program of ``prog`` at the state ``s`` into ``out``; returns the number of
    inequality rows written (``G[:rows]``, ``h[:rows]``). ``full`` is ``None`` when ``prog`` has
    no term that reads obstacles or writes rows (:data:`SHAPED`; the loop's plain planar runs):
    numba then compiles none of their writers (see :func:`emdm.sim.loop.run_kernel`)."""
    nx = out.c.size
    for i in range(nx):
        for j in range(nx):
            out.P[i, j] = 0.0
        out.c[i] = 0.0
        out.lb[i] = -math.inf
        out.ub[i] = math.inf
    rows = 0
    n = s.q.size
    for k in range(prog.codes.size):
        code, weight = prog.codes[k], prog.weights[k]
        data = prog.data[prog.start[k] : prog.start[k + 1]]
        # each writer takes what it reads and the parts of the program it writes (a call passes
        # every array's shape and strides: the fewer arrays, the cheaper the step)
        if code == TASK:
            task.write(s.J, s.v, out.A, out.b)
        elif code == EFFORT:
            effort.write(weight, n, out.P)
        elif code == MANIPULABILITY:
            manipulability.write(weight, s.Jm, out.c)
        elif code == SLACK:
            slack.write(weight, data, s.error_norm, n, out.P, out.A, out.lb, out.ub)
        elif code == VELOCITY_BOX:
            velocity_box.write(data, n, out.lb, out.ub)
        elif code == DAMPER:
            damper.write(data, s.q, out.lb, out.ub)
        elif code == CENTRING:
            centring.write(weight, data, s.q, out.c)
        elif full is not None and code == PLANE:
            rows = plane.write(data, s.p, s.J, out.G, out.h, out.ids, rows)
        elif full is not None and code == OBSTACLE:
            rows = obstacle.write(
                data, s.pts, s.axes, s.gaps, out.lb, out.ub, out.G, out.h, out.ids, rows, s.floor
            )
        elif full is not None and code == CLEARANCE:
            clearance.write(weight, data, s.t, s.pts, s.axes, out.c)
    return rows
