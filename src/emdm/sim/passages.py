"""What happened during a run, each with its time: the one definition of a chattering joint, of
the task slack in use, of a near-singular passage and of two runs that coincide.

The playground's explanations and status table read them (the record's other events, a scaled
step and a stall, are :attr:`Run.scaled` and :attr:`Run.stalled_from`). Thresholds are in
:mod:`emdm.core.tolerances`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.controllers import task_jacobians
from ..core.tolerances import CHATTER_SPEED, CHATTER_STEPS, COINCIDE, NEAR_SINGULAR, SLACK_USED
from .loop import Run


@dataclass(frozen=True)
class Chatter:
    """Joint ``joint`` (0-based) reverses its command on every step from command ``start`` to
    command ``stop`` (inclusive), at up to ``peak`` rad/s."""

    joint: int
    start: int
    stop: int
    peak: float


def chattering(run: Run) -> list[Chatter]:
    """Every passage in which a joint's command reverses sign on each step, at least
    :data:`CHATTER_SPEED` on both sides, for :data:`CHATTER_STEPS` reversals or more in a row;
    in order of start."""
    qd = run.qd
    if qd.shape[0] < 2:
        return []
    fast = np.abs(qd) >= CHATTER_SPEED
    flips = (qd[1:] * qd[:-1] < 0.0) & fast[1:] & fast[:-1]  # reversal between k-1 and k
    found: list[Chatter] = []
    for j in range(qd.shape[1]):
        k = 0
        column = flips[:, j]
        while k < column.size:
            if not column[k]:
                k += 1
                continue
            end = k
            while end + 1 < column.size and column[end + 1]:
                end += 1
            if end - k + 1 >= CHATTER_STEPS:  # reversals k..end: commands k..end+1
                peak = float(np.abs(qd[k : end + 2, j]).max())
                found.append(Chatter(j, k, end + 1, peak))
            k = end + 1
    return sorted(found, key=lambda c: (c.start, c.joint))


def slack_in_use(run: Run) -> np.ndarray:
    """Per command: whether the task slack was used (``||delta_k|| >`` :data:`SLACK_USED`)."""
    return np.asarray(np.linalg.norm(run.delta, axis=1) > SLACK_USED)


def dexterity(run: Run) -> np.ndarray:
    """Per state: the smallest singular value of the task Jacobian, its position rows divided by
    the arm's reach (dimensionless; 0 at a singularity)."""
    sc = run.scenario
    rows = min(sc.nt, 3)  # planar, position and pose tasks list the position rows first
    scale = np.ones(sc.nt)
    scale[:rows] = 1.0 / sc.reach
    J = task_jacobians(sc, run.q) * scale[None, :, None]
    return np.asarray(np.linalg.svd(J, compute_uv=False)[:, -1])


def near_singular(run: Run) -> np.ndarray:
    """Per state: whether the arm is near a singularity (:func:`dexterity` below
    :data:`NEAR_SINGULAR`)."""
    return np.asarray(dexterity(run) < NEAR_SINGULAR)


def spans(mask: np.ndarray) -> list[tuple[int, int]]:
    """The runs of True in ``mask`` as ``(first, last)`` index pairs."""
    padded = np.concatenate(([False], np.asarray(mask, dtype=bool), [False]))
    edges = np.flatnonzero(padded[1:] != padded[:-1])
    return [(int(a), int(b) - 1) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def coinciding(a: Run, b: Run) -> int:
    """How many states, from the start, two runs share (joint angles within :data:`COINCIDE`
    rad); equal to both runs' length when they coincide throughout."""
    K = min(a.q.shape[0], b.q.shape[0])
    if a.q.shape[1] != b.q.shape[1]:
        return 0
    apart = np.flatnonzero(np.abs(a.q[:K] - b.q[:K]).max(axis=1) > COINCIDE)
    return int(apart[0]) if apart.size else K


__all__ = [
    "Chatter",
    "chattering",
    "coinciding",
    "dexterity",
    "near_singular",
    "slack_in_use",
    "spans",
]
