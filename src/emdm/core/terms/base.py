"""What every term of the per-step program reads and writes.

A term is one module of this package holding one compiled writer with the signature

    write(arm: ArmData, weight: float, data: F64, s: StepInput, out: ProgramOut, rows: int) -> int

``weight`` is the term's weight in the controller (1 where it has none), ``data`` its own numbers
from the scenario (:func:`emdm.core.terms.program_data` packs them), ``s`` the state of the step,
``out`` the program's arrays, and ``rows`` the number of inequality rows ``G x <= h`` written so
far; it returns the new count (a term that adds rows writes them at ``G[rows:]``). Objective terms
add to ``P`` and ``c``; constraint terms write rows of ``A, b`` or ``G, h`` or tighten ``lb, ub``.
:func:`emdm.core.terms.program.build_program` starts from ``P = 0``, ``c = 0``, ``lb = -inf``,
``ub = +inf`` and calls the controller's terms in order.
"""

from __future__ import annotations

from enum import StrEnum
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

F64 = NDArray[np.float64]


class StepInput(NamedTuple):
    """The state a term reads: joint angles ``q`` (rad), the task Jacobian ``J`` (nt x n), the
    manipulability Jacobian ``Jm`` (n), the desired task velocity ``v`` (nt; m/s, rad/s for a
    pose's rotation), the task error's norm ``error_norm`` (m), the task's value ``p`` (its first
    entries are the end effector's position, m), the time ``t`` (s), and the arm as points and
    joint axes ``pts``, ``axes`` and the links' ``gaps`` to the obstacles
    (:mod:`emdm.core.distance`; filled only in a scenario with obstacles), and ``floor``, the
    smallest fraction of its bound the obstacle rows may slow a joint to
    (:data:`emdm.core.terms.obstacle.SLOWEST`; 0 on the loop's second try of a step whose rows
    left no admissible command)."""

    q: F64
    J: F64
    Jm: F64
    v: F64
    error_norm: float
    p: F64
    t: float
    pts: F64
    axes: F64
    gaps: F64
    floor: float


class ProgramOut(NamedTuple):
    """The program ``min 1/2 x^T P x + c^T x  s.t.  A x = b, G x <= h, lb <= x <= ub`` being
    built, ``x = (qd, delta)``."""

    P: F64
    c: F64
    A: F64
    b: F64
    G: F64
    h: F64
    lb: F64
    ub: F64
    ids: F64
    """Per row, who wrote it: ``ROW_ID * code + the writer's own index`` of the row (a plane, an
    obstacle, link and end), so that the loop recognises a row from one step to the next
    (:func:`emdm.sim.rows.recall_rows`) whatever the rows before it."""


ROW_ID = float(2**24)
"""The id of a row written by the term of code ``k`` lies in ``[k ROW_ID, (k + 1) ROW_ID)``."""


class TermKind(StrEnum):
    """Every term a controller can hold (one module each in :mod:`emdm.core.terms`)."""

    TASK = "task"
    EFFORT = "effort"
    MANIPULABILITY = "manipulability"
    SLACK = "slack"
    VELOCITY_BOX = "velocity-box"
    DAMPER = "damper"
    CENTRING = "centring"
    PLANE = "plane"
    OBSTACLE = "obstacle"
    CLEARANCE = "clearance"


# the compiled dispatch reads these integers (numba freezes module-level ints as constants)
(
    TASK,
    EFFORT,
    MANIPULABILITY,
    SLACK,
    VELOCITY_BOX,
    DAMPER,
    CENTRING,
    PLANE,
    OBSTACLE,
    CLEARANCE,
) = range(10)
CODE: dict[TermKind, int] = {kind: code for code, kind in enumerate(TermKind)}
"""The integer of each term in :class:`ProgramData` (the order of :class:`TermKind`)."""
