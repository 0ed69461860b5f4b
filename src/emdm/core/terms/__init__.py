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
==================  ===========  =============================================  =================

A controller is a list of these (:mod:`emdm.core.controllers`); :mod:`.program` builds its
program at a state in one compiled pass. docs/architecture.md shows how to add one.
"""

from __future__ import annotations

from .base import CODE, ProgramOut, StepInput, TermKind
from .program import ProgramData, build_program

__all__ = ["CODE", "ProgramData", "ProgramOut", "StepInput", "TermKind", "build_program"]
