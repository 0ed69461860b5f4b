"""What the playground computes, free of any browser code (tested without a browser).

A session holds a *base* scenario (a preset or the file given to ``emdm play``, optionally with
another number of links) and the *overrides* set on the page (``{"section.key": value}``, the
``--set`` keys). Every change rebuilds the scenario through :meth:`Scenario.with_overrides`, so the
page accepts exactly what a scenario file accepts and explains a refusal in the same words.

For the page, a run becomes flat arrays: the joint positions of every state, the manipulability
ellipse of every state, the joint states (free, in a damper's influence zone, pinned at a bound,
past a limit) and the time series. The page only picks the rows of the scrubbed state; everything
it shows is computed here.
"""

from __future__ import annotations

import functools
import math
import tempfile
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import urlencode

import numpy as np

from ..core.controllers import Controller, Name, get_controller
from ..core.feasibility import velocity_set
from ..core.loading import parse_override
from ..core.scenario import Scenario, scenario_from_dict
from ..core.schema import toml_value
from ..core.tolerances import COINCIDE, NEAR_SINGULAR
from ..core.validation import POLICIES
from ..errors import EmdmError, NoSolution, ScenarioError, one_line
from ..sim import passages
from ..sim.loop import Run, simulate
from ..sim.metrics import metrics
from ..studies.pareto import front_at, ratios

PAIRS: dict[str, tuple[str, str]] = {
    "C": (Name.C_EMDM, Name.C_IVKC),
    "UC": (Name.UC_EMDM, Name.UC_IVKC),
}
"""Controller pairs: EMDM and its IVKC baseline (drawn as a ghost), constrained or not."""

MIN_LINKS, MAX_LINKS = 2, 8
MAX_STEPS = 4000
"""Steps a page computes per controller at most, unless the served scenario itself asks for more
(a page change that asked for 10^12 steps froze the tab; ``emdm run`` has no such cap)."""
ELLIPSE_SHARE = 0.3
"""The largest possible ellipse is drawn this share of the arm's reach (see :func:`ellipse_scale`)."""

FREE, ZONE, PINNED, PAST, TIP = 0, 1, 2, 3, 4
JOINT_STATES = ("free", "in a damper's influence zone", "at a bound", "past its limit", "end")
"""Codes of :func:`joint_states`, in the order of the page's colours."""


# ------------------------------------------------------------------------------------ controls
@dataclass(frozen=True)
class Control:
    """One slider: the scenario key(s) it sets, its range, and log or linear scale.

    A log control's slider holds ``log10(value)``; with ``zero_at_start`` its leftmost position
    means 0. A ``symmetric`` control sets ``key`` to ``value`` and its ``lower`` key to ``-value``.
    """

    name: str
    label: str
    key: str
    start: float
    end: float
    step: float
    log: bool = False
    zero_at_start: bool = False
    lower: str | None = None

    def value(self, scenario: Scenario) -> float:
        """The scenario's value (the first joint's, for a per-joint key)."""
        section, _, key = self.key.partition(".")
        raw = getattr(getattr(scenario, section), key)
        return float(np.ravel(raw)[0])

    def to_slider(self, value: float) -> float:
        """The slider position showing ``value`` (clamped to the slider's range)."""
        if self.log:
            pos = self.start if value <= 0 else math.log10(value)
        else:
            pos = value
        return min(self.end, max(self.start, pos))

    def from_slider(self, position: float) -> float:
        """The value at slider ``position``, rounded to what the slider can show."""
        if not math.isfinite(position):
            raise ScenarioError("page", self.key, f"must be a number, got {position}")
        position = min(self.end, max(self.start, position))
        if self.log:
            if self.zero_at_start and position <= self.start + self.step / 2:
                return 0.0
            return float(f"{10.0**position:.3g}")
        snapped = self.start + round((position - self.start) / self.step) * self.step
        return float(f"{min(self.end, snapped):.10g}")

    def overrides(self, value: float) -> dict[str, Any]:
        """The overrides that set this control to ``value``."""
        out: dict[str, Any] = {self.key: value}
        if self.lower is not None:
            out[self.lower] = -value
        return out


CONTROLS: tuple[Control, ...] = (
    Control("w_E", "w_E  effort weight", "weights.effort", -3.0, 2.0, 0.05, log=True),
    Control(
        "w_M",
        "w_M  manipulability weight (left end: 0)",
        "weights.manipulability",
        -3.0,
        3.0,
        0.05,
        log=True,
        zero_at_start=True,
    ),
    Control("c_S", "c_S  slack weight (2 links)", "weights.slack", -2.0, 3.0, 0.05, log=True),
    Control("K_p", "K_p  task gain (1/s)", "motion.kp", 0.1, 5.0, 0.1),
    Control("influence", "damper influence i (rad)", "damper.influence", 0.05, 1.5, 0.01),
    Control("stop", "damper stop s (rad)", "damper.stop", 0.0, 0.5, 0.005),
    Control("gain", "damper gain K_safe (edge speed 1/K_safe)", "damper.gain", 0.1, 5.0, 0.05),
    Control(
        "qd_max", "velocity limit |qd| (rad/s)", "arm.qd_max", 0.1, 5.0, 0.05, lower="arm.qd_min"
    ),
    Control("dt", "dt  sampling time (s)", "motion.dt", 0.01, 0.2, 0.005),
)
CONTROL = {c.name: c for c in CONTROLS}


# ---------------------------------------------------------------------------- the scenario
@dataclass
class Settings:
    """What a session has chosen: the base scenario, the number of links, the pair, the overrides."""

    scenario: str
    links: int | None = None
    pair: str = "C"
    overrides: dict[str, Any] = field(default_factory=dict)


def with_links(scenario: Scenario, n: int) -> Scenario:
    """``scenario`` with ``n`` equal links of the same total reach.

    Per-joint settings take the first joint's value; the start keeps the first angle and spreads
    the others' sum evenly, kept clear of the stop zones. The goal is kept.
    """
    if n == scenario.n:
        return scenario
    if not MIN_LINKS <= n <= MAX_LINKS:
        raise ScenarioError("page", "links", f"must be {MIN_LINKS} to {MAX_LINKS}, got {n}")
    data = scenario.to_dict()
    for section in ("arm", "damper"):
        for key, value in data[section].items():
            data[section][key] = value[0]
    data["arm"]["lengths"] = [float(scenario.link_lengths.sum()) / n] * n
    q0 = scenario.motion.q0
    start = np.array([float(q0[0])] + [float(q0[1:].sum()) / (n - 1)] * (n - 1))
    margin = scenario.damper.stop[0] + 1e-3
    start = np.clip(start, scenario.arm.q_min[0] + margin, scenario.arm.q_max[0] - margin)
    data["motion"]["q0"] = [float(v) for v in start]
    data["name"] = f"{scenario.name}-{n}links"
    return scenario_from_dict(data, source=scenario.source)


def build_scenario(bases: Mapping[str, Scenario], settings: Settings) -> Scenario:
    """The scenario of ``settings``; raises :class:`ScenarioError` with the page's wording."""
    if settings.scenario not in bases:
        raise ScenarioError(
            "page", "scenario", f"unknown {settings.scenario!r} (known: {', '.join(bases)})"
        )
    if settings.pair not in PAIRS:
        raise ScenarioError("page", "pair", f"must be C or UC, got {settings.pair!r}")
    base = bases[settings.scenario]
    if settings.links is not None:
        base = with_links(base, settings.links)
    scenario = base.with_overrides(settings.overrides)
    check_steps(scenario, bases[settings.scenario])
    return scenario


def check_steps(scenario: Scenario, served: Scenario) -> None:
    """A page computes at most :data:`MAX_STEPS` per controller, or the served file's own
    number: a :class:`ScenarioError` naming ``motion.max_time`` beyond that."""
    cap = max(MAX_STEPS, served.max_steps)  # the served file's own stands
    if scenario.max_steps > cap:
        raise ScenarioError(
            "page",
            "motion.max_time",
            f"gives {scenario.max_steps} steps of dt = {scenario.motion.dt:g} s; a page computes "
            f"at most {cap} per controller (max_time <= {cap * scenario.motion.dt:g} s), which "
            "keeps every change interactive",
        )


def parse_query(
    arguments: Mapping[str, Sequence[bytes | str]], bases: Sequence[str]
) -> tuple[Settings, list[str]]:
    """Settings from the page address (``?scenario=task2&pair=UC&links=4&weights.effort=0.2``).

    Returns the settings and one message per value it could not use (those values are ignored).
    """
    errors: list[str] = []
    settings = Settings(scenario=bases[0])
    for name, values in arguments.items():
        if not values:
            continue
        raw = values[-1]
        text = raw.decode("utf-8", "replace") if isinstance(raw, bytes) else str(raw)
        text = one_line(text)[:200]
        if name == "scenario":
            if text in bases:
                settings.scenario = text
            else:
                errors.append(f"scenario: unknown {text!r} (known: {', '.join(bases)})")
        elif name == "pair":
            if text.upper() in PAIRS:
                settings.pair = text.upper()
            else:
                errors.append(f"pair: must be C or UC, got {text!r}")
        elif name == "links":
            if text.isdigit() and MIN_LINKS <= int(text) <= MAX_LINKS:
                settings.links = int(text)
            else:
                errors.append(f"links: must be {MIN_LINKS} to {MAX_LINKS}, got {text!r}")
        elif "." in name:
            try:
                key, value = parse_override(f"{one_line(name)[:100]}={text}")
            except EmdmError as exc:
                errors.append(str(exc))
                continue
            settings.overrides[key] = value
        else:
            errors.append(
                f"{one_line(name)[:100]}: unknown parameter (scenario, pair, links or section.key)"
            )
    return settings, errors


def settings_query(settings: Settings) -> str:
    """The page address's query for ``settings``, which :func:`parse_query` reads back to the
    same settings (values written as TOML, so a text such as ``"scale"`` stays a text)."""
    params = [("scenario", settings.scenario), ("pair", settings.pair)]
    if settings.links is not None:
        params.append(("links", str(settings.links)))
    params += [(key, toml_value(value)) for key, value in sorted(settings.overrides.items())]
    return urlencode(params)


def export_toml(scenario: Scenario) -> str:
    """The scenario as TOML, the layout every command reads (``emdm run FILE``)."""
    return scenario.to_toml()


def message(exc: EmdmError) -> str:
    """An error as the page shows it: the key and the problem, without the source prefix."""
    if isinstance(exc, ScenarioError):
        return f"{exc.key}: {exc.problem}" if exc.key else exc.problem
    return str(exc)


# ------------------------------------------------------------------------------------- runs
@dataclass(frozen=True, eq=False)
class Outcome:
    """One controller's run: the record (partial when a step had no solution), or why none."""

    controller: Controller
    run: Run | None
    error: str | None
    seconds: float

    @property
    def name(self) -> str:
        return self.controller.name


def run_controller(scenario: Scenario, name: str) -> Outcome:
    """Simulate ``name`` on ``scenario``; a step without solution ends the run with its message."""
    controller = get_controller(name)
    start = time.perf_counter()
    try:
        run: Run | None = simulate(scenario, controller)
        error = None
    except NoSolution as exc:
        run, error = getattr(exc, "run", None), str(exc)
    return Outcome(controller, run, error, time.perf_counter() - start)


CLIP_SECONDS = 20.0
"""A clip lasts at most this long: a longer run is recorded faster than the playback speed."""


def clip_gif(runs: Sequence[Run], speed: float) -> tuple[bytes, float]:
    """A GIF of ``runs`` side by side, as :func:`emdm.outputs.animate.animate` draws them (the
    animations of ``emdm animate`` and the report), at ``speed`` times real time or faster, so
    that it lasts at most :data:`CLIP_SECONDS`; returns its bytes and the speed-up used."""
    from ..outputs.animate import animate

    duration = max(float(run.t[-1]) for run in runs)
    speedup = max(float(speed), duration / CLIP_SECONDS)
    with tempfile.TemporaryDirectory(prefix="emdm-clip-") as folder:
        (path,) = animate(runs, Path(folder) / "clip", speedup=speedup, mp4=False)
        return path.read_bytes(), speedup


def run_pair(scenario: Scenario, pair: str) -> tuple[Outcome, Outcome]:
    """EMDM and its IVKC baseline of ``pair`` (``C`` or ``UC``) on ``scenario``."""
    emdm, ivkc = PAIRS[pair]
    return run_controller(scenario, emdm), run_controller(scenario, ivkc)


def step_at(t: float, dt: float, steps: int) -> int:
    """The state index shown at time ``t`` (s): the nearest, clipped to ``0..steps``."""
    if not math.isfinite(t):
        return 0
    return min(max(0, round(t / dt)), steps)


# ---------------------------------------------------------------------------- scene arrays
def joint_positions(lengths: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Base, joints and end effector for every row of ``q``: ``(K, n + 1, 2)`` (m).

    The whole run at once (as :meth:`PlanarArm.joint_positions` does one state; tested equal).
    """
    th = np.cumsum(q, axis=1)
    links = np.stack((np.cos(th), np.sin(th)), axis=-1) * lengths[None, :, None]
    out = np.zeros((q.shape[0], q.shape[1] + 1, 2))
    out[:, 1:] = np.cumsum(links, axis=1)
    return out


def ellipse_scale(scenario: Scenario) -> float:
    """Drawing scale of the manipulability ellipse (m per m/s), fixed for an arm.

    The largest singular value of ``J`` is at most ``||J||_F = sqrt(sum_j r_j^2)`` with ``r_j`` the
    length from joint ``j`` to the tip, reached when the arm is stretched; that ellipse is drawn
    ``ELLIPSE_SHARE`` of the reach long, so sizes compare across runs, drags and time.
    """
    lengths = scenario.link_lengths
    tips = np.cumsum(lengths[::-1])[::-1]
    return ELLIPSE_SHARE * float(lengths.sum()) / float(np.sqrt(tips @ tips))


def jacobians(points: np.ndarray) -> np.ndarray:
    """The planar Jacobian ``(K, 2, n)`` at every state, from the joint positions ``(K, n + 1,
    2)``: column ``j`` is the tip vector ``r_j = p - P_j`` turned by 90 degrees."""
    r = points[:, -1:, :] - points[:, :-1, :]
    return np.stack((-r[..., 1], r[..., 0]), axis=1)


def ellipses(points: np.ndarray, scale: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Width, height (m) and angle (rad) of the scaled ellipse ``{x : x^T (J J^T)^-1 x <= 1}``
    at every state, from the joint positions ``(K, n + 1, 2)``.

    Column ``j`` of ``J`` is the tip vector ``r_j = p - P_j`` turned by 90 degrees, so
    ``J J^T = [[sum ry^2, -sum rx ry], [-sum rx ry, sum rx^2]]``; its eigenvalues are the squared
    semi-axes (the ellipse of :func:`emdm.outputs.animate.ellipse_points`; tested equal).
    """
    J = jacobians(points)
    a, c, b = (
        (J[:, 0] ** 2).sum(axis=1),
        (J[:, 1] ** 2).sum(axis=1),
        (J[:, 0] * J[:, 1]).sum(axis=1),
    )
    mean, half = (a + c) / 2, np.hypot((a - c) / 2, b)
    major, minor = np.sqrt(mean + half), np.sqrt(np.maximum(mean - half, 0.0))
    angle = 0.5 * np.arctan2(2 * b, a - c)
    return 2 * scale * major, 2 * scale * minor, angle


def at_bounds(run: Run) -> np.ndarray:
    """Per command and joint: -1 at the lower bound, +1 at the upper, 0 free; ``(K, n)``: the
    record's ``active`` column, the one definition of a joint at a bound (``sim.buffers.mark_active``)."""
    return np.asarray(run.active, dtype=np.int8)


def joint_states(run: Run) -> np.ndarray:
    """Per state and joint: FREE, ZONE (inside the damper's influence zone), PINNED (its command
    sits at a bound of the program; the final state shows the last command's) or PAST (outside
    its position limits); ``(K + 1, n)``."""
    sc = run.scenario
    q = run.q
    margin = np.minimum(q - sc.arm.q_min, sc.arm.q_max - q)
    states = np.where(margin < sc.damper.influence, ZONE, FREE)
    pinned = np.zeros(q.shape, dtype=bool)
    pinned[: run.steps] = at_bounds(run) != 0
    if run.steps:
        pinned[-1] = pinned[-2]  # the final state has no command: it shows the last one's
    states = np.where(pinned, PINNED, states)
    states = np.where(margin < 0, PAST, states)
    return np.asarray(states, dtype=np.int8)


def scene_data(run: Run, scale: float) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The arrays the page draws from: ``(points, steps)``.

    ``points`` has ``(K + 1)(n + 1)`` rows (state by state: base, joints, end effector) with
    ``x, y, s`` (joint state code, TIP for the end effector). ``steps`` has ``K + 1`` rows: ``t``,
    the ellipse ``ex, ey, ew, eh, ea``, the series ``m, E, err, alpha`` (``E`` and ``alpha`` are
    per command: NaN at the final state) and ``q1..qn``.
    """
    sc = run.scenario
    K, n = run.steps, sc.n
    pts = joint_positions(sc.link_lengths, run.q)
    codes = np.full((K + 1, n + 1), TIP, dtype=np.int8)
    codes[:, :n] = joint_states(run)
    ew, eh, ea = ellipses(pts, scale)
    pad = np.full(1, np.nan)
    steps: dict[str, np.ndarray] = {
        "t": run.t,
        "ex": run.p[:, 0],
        "ey": run.p[:, 1],
        "ew": ew,
        "eh": eh,
        "ea": ea,
        "m": run.m,
        "E": np.concatenate((run.effort, pad)),
        "err": run.error_norm,
        "alpha": np.concatenate((run.alpha, pad)),
    }
    for j in range(n):
        steps[f"q{j + 1}"] = run.q[:, j]
    points = {"x": pts[..., 0].ravel(), "y": pts[..., 1].ravel(), "s": codes.ravel()}
    return points, steps


def velocity_data(run: Run, scale: float) -> dict[str, np.ndarray]:
    """The step's program drawn at the tip, at the ellipse's ``scale`` (m per m/s), state by
    state: ``px, py``, the ``2n`` corners of the tip velocities the step's joint bounds allow
    (:func:`emdm.core.feasibility.velocity_set`; NaN where a bound is infinite, as in UC
    programs, and the last command's at the final state), and ``vx, vy`` (the P controller's
    velocity) and ``ax, ay`` (the tip velocity ``J qd`` of the command), as points."""
    sc = run.scenario
    K, n = run.steps, sc.n
    pts = joint_positions(sc.link_lengths, run.q)
    tip = pts[:, -1]
    J = jacobians(pts)
    corners = np.full((K + 1, 2 * n, 2), np.nan)
    corners[:K] = velocity_set(J[:K], run.lo, run.hi)
    if K:
        corners[K] = corners[K - 1]
    drawn = tip[:, None, :] + scale * corners
    achieved = np.full((K + 1, 2), np.nan)
    achieved[:K] = np.einsum("kij,kj->ki", J[:K], run.qd)
    desired = np.full((K + 1, 2), np.nan)
    desired[:K] = run.v[:K]
    return {
        "px": drawn[..., 0].ravel(),
        "py": drawn[..., 1].ravel(),
        "vx": tip[:, 0] + scale * desired[:, 0],
        "vy": tip[:, 1] + scale * desired[:, 1],
        "ax": tip[:, 0] + scale * achieved[:, 0],
        "ay": tip[:, 1] + scale * achieved[:, 1],
    }


# ------------------------------------------------------------------------------------ status
def _joints(indices: Sequence[int]) -> str:
    names = [str(j + 1) for j in indices]
    if len(names) == 1:
        return f"joint {names[0]}"
    return "joints " + ", ".join(names[:-1]) + " and " + names[-1]


def explain(scenario: Scenario, outcome: Outcome) -> str:
    """Why the run ended as it did, in one or two sentences read from its record."""
    run = outcome.run
    if outcome.error is not None:
        where = f" after {run.t[-1]:.2f} s" if run is not None else ""
        return f"stopped{where}: {outcome.error}"
    assert run is not None
    notes = []
    past = np.flatnonzero((run.q < scenario.arm.q_min) | (run.q > scenario.arm.q_max))
    if past.size:
        k = int(past[0]) // scenario.n
        joints = np.flatnonzero(
            np.any((run.q < scenario.arm.q_min) | (run.q > scenario.arm.q_max), axis=0)
        )
        notes.append(
            f"{_joints(joints.tolist())} passed {'its' if joints.size == 1 else 'their'} "
            f"position limit from t = {run.t[k]:.2f} s (no limits in UC programs)"
        )
    scaled = np.flatnonzero(run.scaled)
    if scaled.size and run.reached:
        notes.append(
            f"the task was scaled down (alpha < 1) on {scaled.size} of {run.steps} steps, "
            f"from t = {run.t[scaled[0]]:.2f} s"
        )
    notes += _passages(run)
    if run.reached:
        head = f"reached the goal at t = {run.t[-1]:.2f} s"
        return head + ("; " + "; ".join(notes) if notes else "") + "."
    err = run.error_norm
    head = f"did not reach the goal: ||e|| = {err[-1]:.3g} m at t = {run.t[-1]:.2f} s (max_time)"
    arm = scenario.planar_arm
    radius = float(np.hypot(*scenario.motion.goal))
    if radius > arm.reach or radius < arm.inner_reach:
        why = (
            f"the goal is {radius:.3g} m from the base, outside the reachable annulus "
            f"[{arm.inner_reach:.3g}, {arm.reach:.3g}] m"
        )
    elif run.steps and run.alpha[-1] < 0.01 and run.stalled_from is not None:
        stalled = run.stalled_from  # the record's one definition, as in the report
        sides = at_bounds(run)[-1]
        held = [_held(run, int(j), int(sides[j])) for j in np.flatnonzero(sides)]
        who = " and ".join(held) if held else "the joint bounds close every direction"
        why = (
            f"stalled from t = {run.t[stalled]:.2f} s: {who}, so no admissible motion keeps the "
            f"task direction and the task is scaled to alpha = {run.alpha[-1]:.2g}"
        )
    else:
        tail = max(1, run.steps // 10)
        if err[-1] < err[-1 - tail] * 0.98:
            why = "still approaching when time ran out (raise K_p, or max_time in the file)"
        else:
            why = f"||e|| stopped falling (it was {err[-1 - tail]:.3g} m at t = {run.t[-1 - tail]:.2f} s)"
    return f"{head}: {why}" + ("; " + "; ".join(notes) if notes else "") + "."


@functools.lru_cache(maxsize=32)  # a Run hashes by identity: one entry per computed run
def _dexterity(run: Run) -> np.ndarray:
    return passages.dexterity(run)


def _passages(run: Run) -> list[str]:
    """Chattering, the slack in use and near-singular passages, each in a clause with its times
    (their one definition is :mod:`emdm.sim.passages`)."""
    notes = []
    chatter = passages.chattering(run)
    if chatter:
        joints = sorted({c.joint for c in chatter})
        first, last = min(c.start for c in chatter), max(c.stop for c in chatter)
        verb = "chatters" if len(joints) == 1 else "chatter"
        notes.append(
            f"{_joints(joints)} {verb} from t = {run.t[first]:.2f} s to {run.t[last]:.2f} s: "
            f"the command reverses sign on every step, up to "
            f"{max(c.peak for c in chatter):.2f} rad/s"
        )
    used = passages.slack_in_use(run)
    if used.any():
        size = np.linalg.norm(run.delta, axis=1)
        k = int(np.argmax(size))
        notes.append(
            f"the task slack was in use on {int(used.sum())} of {run.steps} steps (largest "
            f"||delta|| = {size[k]:.3g} m/s at t = {run.t[k]:.2f} s): there the end effector "
            f"moves off the P controller's velocity by the slack"
        )
    dex = _dexterity(run)
    near = passages.spans(dex < NEAR_SINGULAR)
    if near:
        a, b = near[0]
        k = a + int(np.argmin(dex[a : b + 1]))
        more = (
            f" (and {len(near) - 1} more passage{'s' if len(near) > 2 else ''})"
            if len(near) > 1
            else ""
        )
        notes.append(
            f"near-singular from t = {run.t[a]:.2f} s to {run.t[b]:.2f} s{more}: the smallest "
            f"singular value of J fell to {100 * dex[k]:.2g} % of the reach (m = {run.m[k]:.3g} "
            f"at t = {run.t[k]:.2f} s)"
        )
    return notes


def explain_pair(first: Outcome, second: Outcome) -> str:
    """A sentence when two runs coincide, from the start for a while or throughout (the ghost
    arm is then hidden under the first), else ``""``."""
    a, b = first.run, second.run
    if a is None or b is None or a.steps == 0:
        return ""
    shared = passages.coinciding(a, b)
    if shared == a.q.shape[0] == b.q.shape[0]:
        return (
            f"{first.name} and {second.name} coincide throughout (joint angles within "
            f"{COINCIDE:g} rad): one arm hides the other."
        )
    if shared >= 2 and a.t[shared - 1] >= 0.5:
        return (
            f"{first.name} and {second.name} coincide until t = {a.t[shared - 1]:.2f} s (joint "
            f"angles within {COINCIDE:g} rad): the ghost arm is hidden until then."
        )
    return ""


def _held(run: Run, j: int, side: int) -> str:
    """How joint ``j`` is held at the last command (``side``: +1 upper bound, -1 lower)."""
    value = run.hi[-1, j] if side > 0 else run.lo[-1, j]
    q = run.q[-1, j]
    if abs(value) < 1e-6:
        return f"joint {j + 1} is at its damper stop (q{j + 1} = {q:.3g} rad)"
    return f"joint {j + 1} is at its {'upper' if side > 0 else 'lower'} bound ({value:+.2f} rad/s)"


def _bound_kind(run: Run, k: int, j: int, side: int) -> str:
    sc = run.scenario
    limit = sc.arm.qd_max[j] if side > 0 else sc.arm.qd_min[j]
    value = run.hi[k, j] if side > 0 else run.lo[k, j]
    kind = "velocity limit" if value == limit else "damper"
    return f"{j + 1}: {kind} {value:+.2f} rad/s"


def status_rows(outcome: Outcome, t: float) -> list[tuple[str, str]]:
    """The state of one run at time ``t``: (label, value) rows for the status table."""
    run = outcome.run
    if run is None:
        return [("time to goal", time_to_goal(outcome))]
    K = run.steps
    k = step_at(t, run.scenario.motion.dt, K)
    rows = [
        ("time to goal", time_to_goal(outcome)),
        ("t", f"{run.t[k]:.2f} s (step {k} of {K})"),
        ("||e||", f"{run.error_norm[k]:.3g} m"),
        ("m", f"{run.m[k]:.4f}" if run.m[k] >= 1e-3 else f"{run.m[k]:.3g}"),
    ]
    if _dexterity(run)[k] < NEAR_SINGULAR:
        rows[-1] = ("m", rows[-1][1] + " (near-singular)")
    if k == K:
        end = "goal reached" if run.reached else ("stopped" if outcome.error else "time out")
        rows += [("command", f"none: final state ({end})")]
        return rows
    alpha = run.alpha[k]
    rows.append(("alpha", "1 (full task)" if alpha >= 1.0 else f"{alpha:.3f} (task scaled)"))
    if run.policy[k] == "slack":
        rows[-1] = ("alpha", "1 (free slack: the task is relaxed)")
    if passages.slack_in_use(run)[k]:
        delta = float(np.linalg.norm(run.delta[k]))
        rows.append(("task slack", f"||delta|| = {delta:.3g} m/s (the task is relaxed)"))
        if alpha >= 1.0 and run.policy[k] != "slack":
            rows[-2] = ("alpha", "1 (not scaled; the slack relaxes the task)")
    sides = at_bounds(run)[k]
    active = np.flatnonzero(sides).tolist()
    text = "; ".join(_bound_kind(run, k, j, int(sides[j])) for j in active)
    rows.append(("joints at a bound", text or "none"))
    solver = run.solver[k] + (" (fallback)" if run.fallback[k] else "")
    its = int(run.iterations[k])
    rows.append(("solver", f"{solver}, {its} iteration{'' if its == 1 else 's'}"))
    rows.append(("KKT residual", f"{run.kkt[k]:.1e}"))
    return rows


def time_to_goal(outcome: Outcome) -> str:
    """``8.15 s``, ``not reached`` or ``stopped at step k``."""
    run = outcome.run
    if outcome.error is not None:
        return "no run" if run is None else f"stopped at t = {run.t[-1]:.2f} s"
    if run is None or not run.reached:
        return "not reached"
    return f"{run.t[-1]:.2f} s"


# ------------------------------------------------------------------------------ pinned run
COMPARED = (
    ("time to goal (s)", "time_to_goal", ".2f"),
    ("mean m", "mean_manipulability", ".4g"),
    ("min m", "min_manipulability", ".4g"),
    ("effort \u222bE dt (rad\u00b2/s)", "total_effort", ".4g"),
    ("final \u2016e\u2016 (m)", "final_error", ".2g"),
    ("scaled steps", "scaled_steps", "d"),
    ("min joint margin (rad)", "min_joint_margin", ".3f"),
)
"""The outcomes compared with a pinned run: label, key of :func:`emdm.sim.metrics.metrics`,
format."""


def compare(now: Outcome, pinned: Outcome) -> list[tuple[str, str, str, str]]:
    """Rows ``(outcome, now, pinned, change)`` of two runs, from their records
    (:func:`emdm.sim.metrics.metrics`): the change is ``now - pinned``, with its percentage of
    the pinned value where that is not zero."""
    if now.run is None or pinned.run is None:
        return []
    a, b = metrics(now.run), metrics(pinned.run)
    rows = []
    for label, key, spec in COMPARED:
        x, y = a[key], b[key]
        if x is None or y is None:  # a run that did not reach the goal has no time to it
            rows.append((label, "not reached" if x is None else format(x, spec),
                         "not reached" if y is None else format(y, spec), "\u2013"))  # fmt: skip
            continue
        change = "same" if x == y else format(x - y, "+" + spec)
        if y != 0 and x != y and key != "scaled_steps":
            change += f" ({(x - y) / abs(y):+.0%})"
        rows.append((label, format(x, spec), format(y, spec), change))
    return rows


def scenario_changes(pinned: Scenario, now: Scenario) -> list[str]:
    """The scenario keys whose values differ, as ``key: pinned -> now`` (the name aside)."""
    old, new = pinned.to_dict(), now.to_dict()
    changes = []
    for section in sorted(set(old) | set(new)):
        a, b = old.get(section), new.get(section)
        if section == "name" or a == b:
            continue
        if not (isinstance(a, dict) and isinstance(b, dict)):
            changes.append(f"{section}: {toml_value(a)} \u2192 {toml_value(b)}")
            continue
        for key in sorted(set(a) | set(b)):
            if a.get(key) != b.get(key):
                before = toml_value(a[key]) if key in a else "(none)"
                after = toml_value(b[key]) if key in b else "(none)"
                changes.append(f"{section}.{key}: {before} \u2192 {after}")
    return changes


# ------------------------------------------------------------------------------------ Pareto
@dataclass(frozen=True, eq=False)
class Front:
    """The Pareto front of the program at one state: ``E`` and ``M`` for each ``w_M / w_E``."""

    t: float
    E: np.ndarray
    M: np.ndarray
    ratio: np.ndarray
    dominated: np.ndarray
    current: int
    message: str = ""

    @property
    def single(self) -> bool:
        """True when every weight gives the same command (the bounds leave one, or the task
        fixes it): the front is one point."""
        if self.E.size == 0:
            return False
        size = max(1.0, float(np.abs(self.E).max()), float(np.abs(self.M).max()))
        return bool(np.ptp(self.E) <= 1e-9 * size and np.ptp(self.M) <= 1e-9 * size)


def front(scenario: Scenario, outcome: Outcome, t: float) -> Front:
    """The front of EMDM's program at the state shown at ``t``, the current weights marked.

    The weight sweep of :func:`emdm.studies.pareto.ratios` with the current ratio added, solved by
    :func:`emdm.studies.pareto.front_at` (``w_E`` fixed, ``w_M = ratio w_E``).
    """
    empty = np.zeros(0)
    run = outcome.run
    if run is None:
        return Front(t, empty, empty, empty, empty.astype(bool), -1, "no run")
    k = step_at(t, scenario.motion.dt, run.steps)
    current = scenario.weights.manipulability / scenario.weights.effort
    sweep = ratios()
    if current > 0:
        sweep = np.unique(np.append(sweep, current))
    try:
        points = front_at(scenario, outcome.controller, run.q[k], sweep)
    except EmdmError as exc:
        return Front(float(run.t[k]), empty, empty, empty, empty.astype(bool), -1, message(exc))
    ratio = np.array([p["w_manip"] / p["w_effort"] for p in points])
    index = int(np.argmin(np.abs(ratio - current)))
    return Front(
        float(run.t[k]),
        np.array([p["E"] for p in points]),
        np.array([p["M"] for p in points]),
        ratio,
        np.array([p["dominated"] for p in points]),
        index,
    )


# ------------------------------------------------------------------------------- start pose
def moved_point(old: np.ndarray, new: np.ndarray, tol: float = 1e-9) -> int | None:
    """Index of the point that moved most between ``old`` and ``new`` (``(N, 2)``), or None."""
    if old.shape != new.shape or old.size == 0:
        return None
    shift = np.hypot(*(new - old).T)
    i = int(np.argmax(shift))
    return i if shift[i] > tol else None


def drag_start(scenario: Scenario, index: int, point: Sequence[float]) -> np.ndarray:
    """The start configuration after dragging point ``index`` (1: second joint, ..., n: the end
    effector) to ``point``: the link ending there turns about its joint, the links beyond it
    follow rigidly. The angle is kept out of the stop zones (the scenario would refuse it)."""
    q0 = np.array(scenario.motion.q0, dtype=float)
    n = q0.size
    if not 1 <= index <= n:
        raise ScenarioError(
            "page", "motion.q0", f"point {index} is not a joint that can be dragged"
        )
    x, y = float(point[0]), float(point[1])
    if not (math.isfinite(x) and math.isfinite(y)):
        raise ScenarioError("page", "motion.q0", "the dragged point is not a finite position")
    pts = scenario.planar_arm.joint_positions(q0)
    j = index - 1
    pivot = pts[j]
    if math.hypot(x - pivot[0], y - pivot[1]) < 1e-12:
        return q0
    before = float(q0[:j].sum())
    absolute = math.atan2(y - pivot[1], x - pivot[0])
    turn = math.remainder(absolute - before - q0[j], 2 * math.pi)
    low = scenario.arm.q_min[j] + scenario.damper.stop[j] + 1e-3
    high = scenario.arm.q_max[j] - scenario.damper.stop[j] - 1e-3
    q0[j] = float(np.clip(q0[j] + turn, low, high))
    return q0


__all__ = [
    "CONTROL",
    "CONTROLS",
    "JOINT_STATES",
    "PAIRS",
    "POLICIES",
    "Control",
    "Front",
    "Outcome",
    "Settings",
    "build_scenario",
    "drag_start",
    "ellipse_scale",
    "ellipses",
    "explain",
    "explain_pair",
    "export_toml",
    "front",
    "jacobians",
    "joint_positions",
    "joint_states",
    "message",
    "moved_point",
    "parse_query",
    "run_pair",
    "scene_data",
    "status_rows",
    "step_at",
    "velocity_data",
    "with_links",
]
