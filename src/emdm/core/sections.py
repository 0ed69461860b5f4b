"""The sections of a scenario as frozen dataclasses (one per TOML section), and the task kinds.

:mod:`emdm.core.scenario` validates raw data into these; they hold numbers only.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

from .arm import Vector
from .chain import Chain
from .validation import Policy, SlackUse


class Task(StrEnum):
    """What the controller tracks: the planar tip, or a spatial arm's position or pose."""

    PLANAR = "planar"  # 2 rows: tip position in the plane
    POSITION = "position"  # 3 rows: end-effector position
    POSE = "pose"  # 6 rows: position and orientation (rotation vector of R_goal R^T)


@dataclass(frozen=True, eq=False)
class ArmSpec:
    """The arm: planar link ``lengths`` (m), spatial DH rows ``dh`` (``[a, alpha, d, offset]``;
    m, rad) with their ``convention``, or the chain of a ``urdf`` file from ``base_link`` to
    ``tip_link`` (read into ``chain``); a spatial arm's ``tool`` (a translation, m, or a 4 x 4
    transform); joint limits ``q_min, q_max`` (rad, or m for a prismatic joint) and velocity
    limits (rad/s or m/s), per joint."""

    lengths: Vector | None
    dh: Vector | None
    convention: str
    tool: Vector
    q_min: Vector
    q_max: Vector
    qd_min: Vector
    qd_max: Vector
    urdf: str = ""
    base_link: str = ""
    tip_link: str = ""
    chain: Chain | None = None


@dataclass(frozen=True, eq=False)
class Motion:
    """Start ``q0`` (rad), the ``task`` and its goal (m; a pose's orientation as a rotation vector,
    rad), the manipulability's Jacobian rows ``axes``, sampling time ``dt`` (s), gain ``kp`` (1/s,
    diagonal), stop rules."""

    q0: Vector
    task: Task
    axes: str
    goal: Vector
    dt: float
    kp: Vector
    tolerance: float
    max_time: float


@dataclass(frozen=True)
class Weights:
    """``w_E`` (effort), ``w_M`` (manipulability rate), ``c_S`` (slack: ``w_S = c_S / ||e||``) and
    ``w_C`` (joint centring, 0: off; :mod:`emdm.core.terms.centring`)."""

    effort: float
    manipulability: float
    slack: float
    centring: float = 0.0
    clearance: float = 0.0


@dataclass(frozen=True, eq=False)
class SlackBounds:
    """``delta_min <= delta <= delta_max`` (m/s) for the non-redundant slack program."""

    min: Vector
    max: Vector


@dataclass(frozen=True, eq=False)
class Damper:
    """Joint-position damper (mathematics.md eq. 11), per joint: influence ``i`` and stop ``s``
    (rad), gain."""

    influence: Vector
    stop: Vector
    gain: Vector


@dataclass(frozen=True, eq=False)
class Planes:
    """Planes the end effector keeps away from (the ``plane`` term): unit ``normals`` (one row per
    plane, pointing to the free side) and ``offsets`` (m), so that the distance of the tip ``p`` is
    ``d = n . p - offset``; the velocity damper keeps ``d`` above ``stop`` from within
    ``influence`` (m), with ``gain`` (1/s)."""

    normals: Vector
    offsets: Vector
    influence: float
    stop: float
    gain: float

    @property
    def count(self) -> int:
        """Number of planes."""
        return int(self.offsets.size)


@dataclass(frozen=True)
class ObstacleDamper:
    """The obstacle damper (:mod:`emdm.core.terms.obstacle`): no link comes within ``stop`` (m)
    of an obstacle; within ``influence`` (m) its approach speed is at most ``gain (d - stop) /
    (influence - stop)`` (``gain`` in m/s); links are capsules of radius ``link_radius`` (m)."""

    influence: float
    stop: float
    gain: float
    link_radius: float


@dataclass(frozen=True)
class ControllerSettings:
    """``on_infeasible``: ``scale`` (SNS task scaling), ``slack`` or ``error`` (docs/mathematics.md);
    ``slack``: where EMDM's task slack applies, ``auto`` (the brief's: a non-redundant arm, or a
    scene with obstacles) or ``always`` (every arm)."""

    on_infeasible: Policy
    slack: SlackUse = SlackUse.AUTO
