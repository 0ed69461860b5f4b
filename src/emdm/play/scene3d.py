"""What the 3-D playground computes, free of any browser code (tested without a browser).

A :class:`Session3D` holds the served scenarios (name -> spatial scenario), what the page has
chosen (:class:`Settings3D`: the scenario, the two controllers, the goal, where each obstacle
was dragged, the weights and limits) and the last two runs. Every change rebuilds the scenario:
moved obstacles through :func:`~emdm.core.scenario.scenario_from_dict` (``[[obstacles]]`` has no
``--set`` key), everything else through :meth:`Scenario.with_overrides`, so the page accepts
exactly what a scenario file accepts and explains a refusal in the same words. A refused change
keeps the last valid runs on the page, with the reason in the status.

:meth:`Session3D.frame` gives what the page draws at one time: each arm's joint origins, the
end effector's manipulability ellipsoid (translational rows), the obstacles; the rest
(trajectories, the m(t) series, the status text) is fixed per computation.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core.controllers import CONTROLLERS, Name
from ..core.obstacles import Obstacle
from ..core.scenario import Scenario, scenario_from_dict
from ..core.sections import Task
from ..errors import EmdmError, ScenarioError
from ..sim.metrics import metrics
from .logic import CONTROL, Outcome, check_steps, message, run_controller, step_at

Array = NDArray[np.float64]

PAIR: tuple[str, str] = (Name.C_EMDM, Name.C_IVKC)
"""The two controllers a page shows first: EMDM, and its IVKC baseline as the ghost."""
NAMES: tuple[str, ...] = tuple(str(name) for name in CONTROLLERS)
"""The controllers the page offers (:data:`emdm.CONTROLLERS`)."""
ELLIPSOID_SHARE = 0.08
"""The ellipsoid's longest semi-axis at the start pose is drawn this share of the arm's reach
(a fixed scale per arm and start, so sizes compare across time, drags and controllers)."""
VIEW_DISTANCE = 0.72
"""The first view is this share of the arm's reach away from the middle of the scene."""
SPEED_SCALE = (0.1, 2.0, 0.05)
"""The velocity-limits slider: the scenario's limits times this (from, to, step)."""
CONTROL_KEYS = {name: CONTROL[name] for name in ("w_E", "w_M", "influence")}
"""The sliders the 3-D page shares with the planar one (:data:`emdm.play.logic.CONTROLS`)."""


# ---------------------------------------------------------------------------- rotations
def quat_from_rotvec(r: ArrayLike) -> Array:
    """The unit quaternion ``(w, x, y, z)`` of rotation vector ``r`` (rad)."""
    v = np.asarray(r, dtype=float)
    theta = float(np.linalg.norm(v))
    if theta < 1e-12:
        return np.array([1.0, 0.0, 0.0, 0.0])
    return np.concatenate(([math.cos(theta / 2)], math.sin(theta / 2) * v / theta))


def rotvec_from_quat(q: ArrayLike) -> Array:
    """The rotation vector (angle in [0, pi], rad) of quaternion ``(w, x, y, z)``."""
    w, *xyz = (float(v) for v in np.ravel(q))
    v = np.array(xyz)
    norm = math.sqrt(w * w + float(v @ v))
    if not math.isfinite(norm) or norm < 1e-12:
        raise ScenarioError("page", "motion.goal", "the goal's orientation is not a rotation")
    w, v = w / norm, v / norm
    if w < 0:
        w, v = -w, -v
    s = float(np.linalg.norm(v))
    if s < 1e-12:
        return np.zeros(3)
    return np.asarray(2.0 * math.atan2(s, w) * v / s)


def rotation(wxyz: ArrayLike) -> Array:
    """The rotation matrix of the unit quaternion ``(w, x, y, z)``."""
    w, x, y, z = (float(v) for v in np.ravel(wxyz))
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def quat_from_matrix(R: Array) -> Array:
    """The unit quaternion ``(w, x, y, z)`` of the rotation matrix ``R`` (Shepperd's method)."""
    t = float(np.trace(R))
    if t > 0:
        s = 2.0 * math.sqrt(t + 1.0)
        q = [0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s]
    else:
        i = int(np.argmax(np.diag(R)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(max(1.0 + R[i, i] - R[j, j] - R[k, k], 1e-300))
        q = [0.0] * 4
        q[0] = (R[k, j] - R[j, k]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (R[j, i] + R[i, j]) / s
        q[1 + k] = (R[k, i] + R[i, k]) / s
    out = np.array(q)
    return np.asarray(out / np.linalg.norm(out))


def segment_instances(points: Array, radius: float) -> tuple[Array, Array, Array]:
    """Cylinders along the segments between consecutive ``points`` ``(P, 3)``: the centres
    ``(P - 1, 3)``, the quaternions turning ``+z`` onto each segment ``(P - 1, 4)`` and the scales
    ``(radius, radius, length)`` of a cylinder of radius 1 and height 1 along ``z`` (zero for a
    segment of no length, which then is not drawn)."""
    a, b = points[:-1], points[1:]
    d = b - a
    length = np.linalg.norm(d, axis=1)
    u = np.divide(
        d, length[:, None], out=np.tile([0.0, 0.0, 1.0], (len(d), 1)), where=length[:, None] > 1e-9
    )
    # the half-way quaternion between +z and u: (1 + z.u, z x u), normalised
    w = 1.0 + u[:, 2]
    quat = np.stack((w, -u[:, 1], u[:, 0], np.zeros(len(d))), axis=1)
    flipped = w < 1e-9  # u = -z: half a turn about x
    quat[flipped] = [0.0, 1.0, 0.0, 0.0]
    quat /= np.linalg.norm(quat, axis=1)[:, None]
    scale = np.stack((np.full(len(d), radius), np.full(len(d), radius), length), axis=1)
    scale[length <= 1e-9] = 0.0
    return (a + b) / 2, quat, scale


# ----------------------------------------------------------------------------- settings
@dataclass
class Settings3D:
    """What a page has chosen. ``goal`` None: the scenario's; ``centers`` None: the obstacles
    where the scenario puts them; ``overrides``: ``--set`` keys from the sliders."""

    scenario: str
    controllers: tuple[str, str] = PAIR
    goal: tuple[float, ...] | None = None
    centers: tuple[tuple[float, float, float], ...] | None = None
    overrides: dict[str, Any] = field(default_factory=dict)
    speed: float = 1.0


def obstacle_center(obstacle: Obstacle) -> Array:
    """Where an obstacle's gizmo sits: a sphere's centre, a capsule's mid-point (m, at t = 0)."""
    return np.asarray((obstacle.a + obstacle.b) / 2)


def build(bases: Mapping[str, Scenario], settings: Settings3D) -> Scenario:
    """The scenario of ``settings``; raises :class:`ScenarioError` with the page's wording."""
    if settings.scenario not in bases:
        raise ScenarioError(
            "page", "scenario", f"unknown {settings.scenario!r} (known: {', '.join(bases)})"
        )
    for name in settings.controllers:
        if name not in NAMES:
            raise ScenarioError(
                "page", "controller", f"unknown {name!r} (known: {', '.join(NAMES)})"
            )
    base = bases[settings.scenario]
    if settings.centers is not None:
        if len(settings.centers) != len(base.obstacles):
            raise ScenarioError(
                "page",
                "obstacles",
                f"{len(settings.centers)} positions for {len(base.obstacles)} obstacles",
            )
        data = base.to_dict()
        tables = []
        for obstacle, center in zip(base.obstacles, settings.centers, strict=True):
            shift = np.asarray(center, dtype=float) - obstacle_center(obstacle)
            moved = Obstacle(
                obstacle.shape,
                obstacle.a + shift,
                obstacle.b + shift,
                obstacle.radius,
                obstacle.velocity,
            )
            tables.append(moved.to_dict())
        data["obstacles"] = tables
        base = scenario_from_dict(data, source=base.source)
    overrides = dict(settings.overrides)
    if settings.goal is not None:
        overrides["motion.goal"] = [float(v) for v in settings.goal]
    if settings.speed != 1.0:
        speed = settings.speed
        low, high, _ = SPEED_SCALE
        if not (math.isfinite(speed) and low <= speed <= high):
            raise ScenarioError("page", "speed", f"must be {low:g} to {high:g}, got {speed}")
        overrides["arm.qd_max"] = [float(v) * speed for v in bases[settings.scenario].arm.qd_max]
        overrides["arm.qd_min"] = [float(v) * speed for v in bases[settings.scenario].arm.qd_min]
    scenario = base.with_overrides(overrides) if overrides else base
    if not scenario.spatial:
        raise ScenarioError("page", "arm", "the 3-D playground takes spatial arms only")
    check_steps(scenario, bases[settings.scenario])
    return scenario


# --------------------------------------------------------------------------------- views
@dataclass(frozen=True, eq=False)
class Ellipsoid:
    """The manipulability ellipsoid of the translational rows ``{v : v^T (J_v J_v^T)^-1 v <= 1}``
    drawn at ``center`` (m): semi-axes (m, at the page's fixed scale) along the columns of
    ``rotation``, and ``wxyz`` the same rotation as a quaternion."""

    center: Array
    axes: Array
    rotation: Array
    wxyz: Array


@dataclass(frozen=True, eq=False)
class Frame:
    """What the page draws at time ``t`` (s): for each controller the state index shown
    (``-1``: no run) and its joint origins ``(n + 2, 3)`` (base, every joint, end effector), the
    first controller's ellipsoid, the obstacles' centres at ``t`` and a one-line summary."""

    t: float
    steps: tuple[int, int]
    arms: tuple[Array, Array]
    ellipsoid: Ellipsoid | None
    obstacles: Array
    line: str


@dataclass(frozen=True, eq=False)
class Computed:
    """One computation of the page: the scenario, the two outcomes, the end effector's path of
    each (``(K + 1, 3)``; empty without a run), the series for the m(t) plot (a common time grid,
    a run's last value held after it ends, as its arm holds still) and the status text."""

    scenario: Scenario
    outcomes: tuple[Outcome, Outcome]
    paths: tuple[Array, Array]
    t: Array
    m: tuple[Array, Array]
    status: str
    seconds: float

    @property
    def duration(self) -> float:
        """The longer run's length (s)."""
        return float(self.t[-1]) if self.t.size else 0.0


class Session3D:
    """One page's settings and runs (see the module's docstring). Not thread-safe: the page
    holds a lock around every call."""

    def __init__(self, bases: Mapping[str, Scenario], scenario: str | None = None) -> None:
        if not bases:
            raise ScenarioError("page", "scenario", "no scenario to show")
        self.bases = dict(bases)
        self.settings = Settings3D(scenario=scenario or next(iter(self.bases)))
        self.error = ""
        self.computed: Computed | None = None
        self.scale = 1.0
        self.compute()
        if self.computed is None:  # the served scenario itself cannot be shown
            raise ScenarioError("page", "scenario", self.error)

    # ------------------------------------------------------------------ changes
    @property
    def base(self) -> Scenario:
        return self.bases[self.settings.scenario]

    @property
    def scenario(self) -> Scenario:
        """The scenario of the runs shown (the last valid one)."""
        assert self.computed is not None
        return self.computed.scenario

    def select(self, name: str) -> bool:
        """Show scenario ``name`` with its own goal, obstacles and settings."""
        if name not in self.bases:
            self.error = f"scenario: unknown {name!r} (known: {', '.join(self.bases)})"
            return False
        before = (self.settings, self.computed)
        self.settings = Settings3D(scenario=name, controllers=self.settings.controllers)
        self.computed = None
        if self.compute():
            return True
        error = self.error
        self.settings, self.computed = before  # the page keeps what it showed
        self.error = error
        return False

    def reset(self) -> bool:
        """The scenario's own goal, obstacles and settings again (the controllers stay)."""
        return self.select(self.settings.scenario)

    def set_goal(
        self, position: Sequence[float], wxyz: Sequence[float] | None = None, compute: bool = True
    ) -> bool:
        """The goal at ``position`` (m) with orientation ``wxyz`` (a pose task; ignored for a
        position task). Each setter computes the runs unless ``compute`` is False; it returns
        False (and sets :attr:`error`) for a refused change."""
        p = [float(v) for v in position]
        if len(p) != 3:
            self.error = f"motion.goal: expected a position of 3 values, got {len(p)}"
            return False
        goal: list[float] = p
        if self.base.motion.task == Task.POSE:
            try:
                rotvec = rotvec_from_quat(wxyz if wxyz is not None else self.goal_wxyz())
            except ScenarioError as exc:
                self.error = message(exc)
                return False
            goal = p + rotvec.tolist()
        self.settings.goal = tuple(goal)
        return self.compute() if compute else True

    def move_obstacle(self, index: int, center: Sequence[float], compute: bool = True) -> bool:
        """Obstacle ``index`` (from 0) to ``center`` (m; a capsule's mid-point)."""
        obstacles = self.base.obstacles
        if not 0 <= index < len(obstacles):
            self.error = f"obstacles: no obstacle {index} (there are {len(obstacles)})"
            return False
        c = tuple(float(v) for v in center)
        if len(c) != 3:
            self.error = f"obstacles[{index}]: expected a position of 3 values, got {len(c)}"
            return False
        centers = list(self.centers())
        centers[index] = (c[0], c[1], c[2])
        self.settings.centers = tuple(centers)
        return self.compute() if compute else True

    def set_override(self, key: str, value: Any, compute: bool = True) -> bool:
        """One ``--set`` key (``weights.effort``, ``damper.influence``, ...)."""
        self.settings.overrides[key] = value
        return self.compute() if compute else True

    def set_speed(self, speed: float, compute: bool = True) -> bool:
        """The velocity limits: the scenario's times ``speed``."""
        self.settings.speed = float(speed)
        return self.compute() if compute else True

    def set_controllers(self, first: str, second: str, compute: bool = True) -> bool:
        """The controller drawn solid and the one drawn as a ghost."""
        self.settings.controllers = (first, second)
        return self.compute() if compute else True

    # -------------------------------------------------------------- the shown values
    def goal(self) -> Array:
        """The goal in force (position, then rotation vector for a pose task)."""
        if self.settings.goal is not None:
            return np.array(self.settings.goal)
        return np.array(self.base.motion.goal, dtype=float)

    def goal_wxyz(self) -> Array:
        goal = self.goal()
        return quat_from_rotvec(goal[3:6]) if goal.size >= 6 else np.array([1.0, 0, 0, 0])

    def centers(self) -> tuple[tuple[float, float, float], ...]:
        """Where each obstacle's gizmo sits (m)."""
        if self.settings.centers is not None:
            return self.settings.centers
        return tuple(
            (float(c[0]), float(c[1]), float(c[2]))
            for c in (obstacle_center(o) for o in self.base.obstacles)
        )

    def value(self, key: str) -> float:
        """A slider's value in force: the override, else the scenario's (first joint's)."""
        if key in self.settings.overrides:
            return float(np.ravel(self.settings.overrides[key])[0])
        section, _, name = key.partition(".")
        return float(np.ravel(getattr(getattr(self.base, section), name))[0])

    # --------------------------------------------------------------------- compute
    def compute(self) -> bool:
        """Rebuild the scenario and run both controllers. False (and :attr:`error` set) when
        the settings are refused: the last valid runs stay."""
        start = time.perf_counter()
        try:
            scenario = build(self.bases, self.settings)
            outcomes = tuple(run_controller(scenario, name) for name in self.settings.controllers)
        except EmdmError as exc:
            self.error = message(exc)
            return False
        first, second = outcomes
        if self.computed is None or self.computed.scenario.name != scenario.name:
            self.scale = ellipsoid_scale(scenario)
        self.error = ""
        self.computed = summarise(scenario, (first, second), time.perf_counter() - start)
        return True

    def frame(self, t: float) -> Frame:
        """What the page draws at time ``t`` (s), clipped to the runs."""
        computed = self.computed
        assert computed is not None
        scenario = computed.scenario
        arm = scenario.serial_arm
        steps: list[int] = []
        arms: list[Array] = []
        for outcome in computed.outcomes:
            run = outcome.run
            if run is None:
                steps.append(-1)
                arms.append(arm.joint_positions(scenario.motion.q0))
                continue
            k = step_at(t, scenario.motion.dt, run.steps)
            steps.append(k)
            arms.append(arm.joint_positions(run.q[k]))
        first = computed.outcomes[0].run
        ellipsoid = None
        if first is not None:
            ellipsoid = self.ellipsoid(first.q[steps[0]])
        shown = min(max(0.0, t), computed.duration) if math.isfinite(t) else 0.0
        obstacles = np.array(
            [obstacle_center(o) + o.velocity * shown for o in scenario.obstacles]
        ).reshape(-1, 3)
        parts = []
        for outcome, k in zip(computed.outcomes, steps, strict=True):
            if outcome.run is not None:
                parts.append(f"m = {outcome.run.m[k]:.4f} ({outcome.name})")
        line = f"t = {shown:.2f} s: " + ", ".join(parts) if parts else f"t = {shown:.2f} s"
        return Frame(shown, (steps[0], steps[1]), (arms[0], arms[1]), ellipsoid, obstacles, line)

    def camera(self) -> tuple[Array, Array]:
        """A first view ``(position, look_at)`` (m): the middle of the start pose, the goal and
        the obstacles, seen from 45 degrees beside the direction the arm reaches in, from above,
        :data:`VIEW_DISTANCE` of the reach away."""
        scenario = self.base
        start = scenario.serial_arm.joint_positions(scenario.motion.q0)
        points = np.vstack((start, self.goal()[None, :3], np.reshape(self.centers(), (-1, 3))))
        look = (points.min(axis=0) + points.max(axis=0)) / 2
        look[2] *= 0.9
        ahead = (start[-1] + self.goal()[:3]) / 2
        heading = math.atan2(ahead[1], ahead[0]) if np.hypot(*ahead[:2]) > 1e-6 else 0.0
        side = heading + math.pi / 4
        direction = np.array([0.885 * math.cos(side), 0.885 * math.sin(side), 0.466])
        return look + VIEW_DISTANCE * scenario.reach * direction, look

    def ellipsoid(self, q: Array) -> Ellipsoid:
        """The translational manipulability ellipsoid at ``q``, at the page's fixed scale."""
        arm = self.scenario.serial_arm
        J = arm.position_jacobian(q)
        values, vectors = np.linalg.eigh(J @ J.T)
        if np.linalg.det(vectors) < 0:
            vectors[:, 0] = -vectors[:, 0]
        axes = self.scale * np.sqrt(np.maximum(values, 0.0))
        return Ellipsoid(arm.position(q), axes, vectors, quat_from_matrix(vectors))


def ellipsoid_scale(scenario: Scenario) -> float:
    """Drawing scale (m per m/s) of the ellipsoid: its longest semi-axis at the start is
    :data:`ELLIPSOID_SHARE` of the reach."""
    J = scenario.serial_arm.position_jacobian(scenario.motion.q0)
    largest = float(np.sqrt(max(np.linalg.eigvalsh(J @ J.T)[-1], 1e-12)))
    return ELLIPSOID_SHARE * scenario.reach / largest


def summarise(scenario: Scenario, outcomes: tuple[Outcome, Outcome], seconds: float) -> Computed:
    """The paths, the m(t) series and the status text of two outcomes."""
    paths = tuple(
        np.asarray(o.run.p[:, :3]) if o.run is not None else np.zeros((0, 3)) for o in outcomes
    )
    runs = [o.run for o in outcomes if o.run is not None]
    t = max((r.t for r in runs), key=len) if runs else np.zeros(0)
    series = []
    for outcome in outcomes:
        run = outcome.run
        if run is None:
            series.append(np.full(t.size, np.nan))
            continue
        m = np.full(t.size, run.m[-1])
        m[: run.m.size] = run.m
        series.append(m)
    lines = [
        f"**{o.name}**{' (ghost)' if i else ''}: {ending(scenario, o)}"
        for i, o in enumerate(outcomes)
    ]
    lines += [f"*{w}*" for w in scenario.warnings]
    return Computed(
        scenario,
        outcomes,
        (paths[0], paths[1]),
        np.asarray(t, dtype=float),
        (series[0], series[1]),
        "\n\n".join(lines),
        seconds,
    )


def ending(scenario: Scenario, outcome: Outcome) -> str:
    """How a run ended and its numbers: time to goal or why not, mean m, effort, clearance."""
    run = outcome.run
    if run is None:
        return f"no run: {outcome.error}"
    if outcome.error is not None:
        head = f"stopped at t = {run.t[-1]:.2f} s: {outcome.error}"
    elif run.reached:
        head = f"reached the goal at t = {run.t[-1]:.2f} s"
    else:
        head = (
            f"did not reach the goal: ||e|| = {run.error_norm[-1]:.3g} at t = {run.t[-1]:.2f} s "
            f"(max_time): {_why(scenario, run)}"
        )
    try:
        numbers = metrics(run)
    except EmdmError:
        return head
    tail = [
        f"mean m = {numbers['mean_manipulability']:.4f}",
        f"effort = {numbers['total_effort']:.3g}",
    ]
    clearance = numbers.get("min_clearance")
    if scenario.obstacles and clearance is not None and math.isfinite(clearance):
        tail.append(f"clearance = {100 * clearance:.1f} cm")
    return head + " · " + " · ".join(tail)


def _why(scenario: Scenario, run: Any) -> str:
    """Why a run that ran out of time did not arrive, in a few words."""
    radius = float(np.linalg.norm(scenario.motion.goal[:3]))
    if radius > scenario.reach:
        return (
            f"the goal is {radius:.3g} m from the base, beyond the reach ({scenario.reach:.3g} m)"
        )
    if run.stalled_from is not None:
        return (
            f"stalled from t = {run.t[run.stalled_from]:.2f} s (the joint and obstacle "
            "bounds leave no admissible motion toward the goal)"
        )
    err = run.error_norm
    tail = max(1, run.steps // 10)
    if err[-1] < err[-1 - tail] * 0.98:
        return "still approaching when time ran out"
    return "||e|| stopped falling"


__all__ = [
    "CONTROL_KEYS",
    "NAMES",
    "PAIR",
    "Computed",
    "Ellipsoid",
    "Frame",
    "Session3D",
    "Settings3D",
    "build",
    "ellipsoid_scale",
    "ending",
    "obstacle_center",
    "quat_from_matrix",
    "quat_from_rotvec",
    "rotation",
    "rotvec_from_quat",
    "segment_instances",
]
