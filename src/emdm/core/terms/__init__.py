"""The terms of the per-step program: one module per objective or constraint.

==================  ===========  =============================================  =================
module              kind         writes                                         scenario keys
==================  ===========  =============================================  =================
``task``            constraint   ``A[:, :n] = J``, ``b = v``                    [motion]
``effort``          objective    ``P[j, j] += w_E``                             weights.effort
``manipulability``  objective    ``c[j] -= w_M Jm_j``                           weights.manipulability
``slack``           objective,   ``P += w_S I`` on delta, ``A[:, n:] = I``,     weights.slack,
                    bounds       ``s_min <= delta <= s_max``                    [slack]
``velocity_box``    bounds       ``qd_min <= qd <= qd_max``                     arm.qd_min, qd_max
``damper``          bounds       the joint-position dampers                     [damper], arm.q_*
``centring``        objective    ``c[j] += w_C grad(H)_j`` (joint range index)  weights.centring
``plane``           rows         ``-n^T J_p qd <= gain (d - stop)/(i - stop)``  [planes]
==================  ===========  =============================================  =================

A controller is a list of these (:mod:`emdm.core.controllers`); :mod:`.program` builds its
program at a state in one compiled pass. docs/architecture.md shows how to add one.
"""

from __future__ import annotations

from collections.abc import Callable

from ..scenario import Scenario
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
from .base import CODE, ProgramOut, StepInput, TermKind
from .program import ProgramData, build_program

PACK: dict[TermKind, Callable[[Scenario], list[float]]] = {
    TermKind.TASK: task.pack,
    TermKind.EFFORT: effort.pack,
    TermKind.MANIPULABILITY: manipulability.pack,
    TermKind.SLACK: slack.pack,
    TermKind.VELOCITY_BOX: velocity_box.pack,
    TermKind.DAMPER: damper.pack,
    TermKind.CENTRING: centring.pack,
    TermKind.PLANE: plane.pack,
    TermKind.OBSTACLE: obstacle.pack,
    TermKind.CLEARANCE: clearance.pack,
}
"""Each term's numbers from the scenario, as its writer reads them (``data``)."""

__all__ = [
    "CODE",
    "PACK",
    "ProgramData",
    "ProgramOut",
    "StepInput",
    "TermKind",
    "build_program",
]
