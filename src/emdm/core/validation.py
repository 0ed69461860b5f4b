"""Validation of scenario data: one-line errors that name the file, the key and the problem,
the meaningful range of every number, and the warnings for settings that are valid but break an
invariant (docs/mathematics.md, "Joint limits"). :func:`emdm.core.scenario.scenario_from_dict`
calls these.
"""

from __future__ import annotations

import math
from enum import StrEnum
from typing import Any

import numpy as np

from .arm import Vector
from .checks import _Checker
from .serial import SerialArm


class Policy(StrEnum):
    """What a step does when its task is infeasible under the joint bounds."""

    SCALE = "scale"  # the largest feasible task scale alpha in [0, 1] (SNS task scaling)
    SLACK = "slack"  # an unbounded task slack, weighted like the slack program's
    ERROR = "error"  # stop the run, naming the step


POLICIES = tuple(Policy)


class SlackUse(StrEnum):
    """Where EMDM's task slack (the brief's slack program) is part of the program."""

    AUTO = "auto"  # the brief's: on a non-redundant arm (and on any arm in a scene with obstacles)
    ALWAYS = "always"  # on every arm (the brief's Table 1 lists slack limits for Task 1 too)


SLACK_USES = tuple(SlackUse)


def _fmt(values: Vector) -> str:
    return "[" + ", ".join(f"{v:g}" for v in values) + "]"


RANGES: dict[str, tuple[float, float, str]] = {
    "arm.lengths": (1e-6, 1e6, " m"),
    "arm.dh": (-1e6, 1e6, " (m or rad)"),
    "arm.tool": (-1e6, 1e6, " m"),
    "arm.q_min": (-1e6, 1e6, " rad"),
    "arm.q_max": (-1e6, 1e6, " rad"),
    "arm.qd_min": (-1e6, 1e6, " rad/s"),
    "arm.qd_max": (-1e6, 1e6, " rad/s"),
    "motion.goal": (-1e9, 1e9, " m"),
    "motion.dt": (1e-6, 3600.0, " s"),
    "motion.tolerance": (1e-12, 1e9, " m"),
    "weights.effort": (1e-8, 1e8, ""),
    "weights.manipulability": (0.0, 1e8, ""),
    "weights.slack": (1e-8, 1e8, ""),
    "weights.centring": (0.0, 1e8, ""),
    "weights.clearance": (0.0, 1e8, ""),
    "slack.min": (-1e6, 1e6, " m/s"),
    "slack.max": (-1e6, 1e6, " m/s"),
    "damper.influence": (0.0, 1e6, " rad"),
    "damper.gain": (0.0, 1e6, ""),
    "planes.offsets": (-1e9, 1e9, " m"),
    "planes.influence": (0.0, 1e6, " m"),
    "planes.stop": (0.0, 1e6, " m"),
    "planes.gain": (0.0, 1e6, " 1/s"),
    "obstacle_damper.influence": (0.0, 1e6, " m"),
    "obstacle_damper.stop": (0.0, 1e6, " m"),
    "obstacle_damper.gain": (0.0, 1e6, " m/s"),
    "obstacle_damper.link_radius": (0.0, 1e6, " m"),
}
"""Where each value means something (beyond them: overflowing numbers, or a meaningless run)."""
MAX_STEPS = 1e12
"""At most this many control steps (``max_time / dt``)."""
MAX_RATIO = 1e10
"""At most this ``w_M / w_E``: beyond it the unconstrained EMDM command exceeds 1e10 rad/s."""


def _check_ranges(check: _Checker, p: dict[str, dict[str, Any]]) -> None:
    """Values that are valid in sign but make the program meaningless, with their valid range."""
    for dotted, (low, high, unit) in RANGES.items():
        section, key = dotted.split(".")
        if p[section][key] is None:
            continue
        values = np.atleast_1d(p[section][key]).ravel()
        bad = (values < low) | (values > high)
        if np.any(bad):
            value = values[int(np.argmax(bad))]
            raise check.fail(dotted, f"must be between {low:g} and {high:g}{unit}, got {value:g}")
    motion, weights = p["motion"], p["weights"]
    steps = motion["max_time"] / motion["dt"]
    if steps > MAX_STEPS:
        raise check.fail(
            "motion.max_time",
            f"must be at most {MAX_STEPS:g} steps of motion.dt ({MAX_STEPS * motion['dt']:g} s), "
            f"got {motion['max_time']:g} s",
        )
    kp_dt = np.atleast_1d(motion["kp"]) * motion["dt"]
    if np.any(kp_dt >= 2.0):
        raise check.fail(
            "motion.kp",
            f"must be < 2 / motion.dt = {2.0 / motion['dt']:g} 1/s, or the loop diverges, "
            f"got {_fmt(np.atleast_1d(motion['kp']))}",
        )
    ratio = weights["manipulability"] / weights["effort"]
    if ratio > MAX_RATIO:
        raise check.fail(
            "weights.manipulability",
            f"must be at most {MAX_RATIO:g} x weights.effort (the command would exceed "
            f"{MAX_RATIO:g} rad/s), got {ratio:g} x",
        )


def _check_planes(check: _Checker, planes: dict[str, Any]) -> None:
    """One offset per normal, non-zero normals (made unit), ``stop < influence``, ``gain > 0``
    (the ranges of the numbers are in :data:`RANGES`)."""
    normals, offsets = planes["normals"], planes["offsets"]
    if normals.shape[0] != offsets.size:
        raise check.fail(
            "planes.offsets",
            f"must have one value per row of planes.normals ({normals.shape[0]}), got {offsets.size}",
        )
    for i, row in enumerate(normals):
        size = float(np.linalg.norm(row))
        if not size > 1e-12 or not math.isfinite(size):
            raise check.fail(f"planes.normals[{i}]", "must be a non-zero direction")
    if normals.size:
        unit = normals / np.linalg.norm(normals, axis=1, keepdims=True)
        unit.setflags(write=False)
        planes["normals"] = unit
    if not planes["stop"] < planes["influence"]:
        raise check.fail(
            "planes.stop",
            f"must be below planes.influence ({planes['influence']:g} m), got {planes['stop']:g}",
        )
    if not planes["gain"] > 0.0:
        raise check.fail("planes.gain", f"must be positive, got {planes['gain']:g}")


def check_start_angles(
    check: _Checker, key: str, q0: Vector, q_min: Vector, q_max: Vector, stop: Vector
) -> None:
    """A start ``q0`` (rad) within the joint limits and outside the dampers' stop zones
    (``stop``, rad, per joint); ``key`` names it in the message."""
    outside = (q0 < q_min) | (q0 > q_max)
    if np.any(outside):
        j = int(np.argmax(outside))
        raise check.fail(
            key,
            f"joint {j + 1} starts at {q0[j]:g} rad, outside its limits "
            f"[{q_min[j]:g}, {q_max[j]:g}]",
        )
    margin = np.minimum(q_max - q0, q0 - q_min)
    inside_stop = margin < stop
    if np.any(inside_stop):
        j = int(np.argmax(inside_stop))
        raise check.fail(
            key,
            f"joint {j + 1} starts {margin[j]:g} rad from its limit, inside the "
            f"damper's stop zone ({stop[j]:g} rad), which the dampers forbid",
        )


def _check_consistency(check: _Checker, p: dict[str, dict[str, Any]], n: int) -> list[str]:
    """Cross-field rules; returns the warnings (valid but suspicious settings)."""
    _check_planes(check, p["planes"])
    arm, motion, weights, slack, damper = (
        p[s] for s in ("arm", "motion", "weights", "slack", "damper")
    )

    def positive(dotted: str, values: Any) -> None:
        arr = np.atleast_1d(values)
        if np.any(arr <= 0):
            raise check.fail(
                dotted, f"must be > 0, got {_fmt(arr) if arr.size > 1 else f'{arr[0]:g}'}"
            )

    if arm["lengths"] is not None:
        positive("arm.lengths", arm["lengths"])
    if np.any(arm["q_min"] >= arm["q_max"]):
        j = int(np.argmax(arm["q_min"] >= arm["q_max"]))
        raise check.fail(
            "arm.q_min",
            f"must be < arm.q_max (joint {j + 1}: {arm['q_min'][j]:g} >= {arm['q_max'][j]:g})",
        )
    if np.any(arm["qd_min"] >= 0):
        raise check.fail(
            "arm.qd_min", f"must be < 0 (the arm must be able to stop), got {_fmt(arm['qd_min'])}"
        )
    if np.any(arm["qd_max"] <= 0):
        raise check.fail(
            "arm.qd_max", f"must be > 0 (the arm must be able to stop), got {_fmt(arm['qd_max'])}"
        )
    for key in ("dt", "tolerance", "max_time"):
        positive(f"motion.{key}", motion[key])
    positive("motion.kp", motion["kp"])
    if motion["max_time"] < motion["dt"]:
        raise check.fail("motion.max_time", f"must be >= motion.dt ({motion['dt']:g} s)")
    positive("weights.effort", weights["effort"])
    positive("weights.slack", weights["slack"])
    if weights["manipulability"] < 0:
        raise check.fail(
            "weights.manipulability", f"must be >= 0, got {weights['manipulability']:g}"
        )
    if np.any(slack["min"] >= slack["max"]):
        raise check.fail(
            "slack.min", f"must be < slack.max, got {_fmt(slack['min'])} and {_fmt(slack['max'])}"
        )
    if np.any(damper["stop"] < 0):
        raise check.fail("damper.stop", f"must be >= 0, got {_fmt(damper['stop'])}")
    if np.any(damper["stop"] >= damper["influence"]):
        raise check.fail(
            "damper.stop",
            f"must be < damper.influence, got stop {_fmt(damper['stop'])} "
            f"and influence {_fmt(damper['influence'])}",
        )
    positive("damper.gain", damper["gain"])
    _check_ranges(check, p)
    if p["controller"]["on_infeasible"] not in POLICIES:
        raise check.fail(
            "controller.on_infeasible",
            f"must be one of {', '.join(POLICIES)}, got {p['controller']['on_infeasible']!r}",
        )
    if p["controller"]["slack"] not in SLACK_USES:
        raise check.fail(
            "controller.slack",
            f"must be one of {', '.join(SLACK_USES)}, got {p['controller']['slack']!r}",
        )

    check_start_angles(check, "motion.q0", motion["q0"], arm["q_min"], arm["q_max"], damper["stop"])

    found: list[str] = []
    overshoot = motion["dt"] >= damper["gain"] * (damper["influence"] - damper["stop"])
    if np.any(overshoot):
        found.append(
            "damper: dt >= gain * (influence - stop): the position damper can overshoot into the "
            "stop zone in one step"
        )
    step = np.maximum(arm["qd_max"], -arm["qd_min"]) * motion["dt"]
    if np.any(step > damper["influence"] - damper["stop"]):
        found.append(
            "damper: max |qd| * dt > influence - stop: a joint outside its influence zone can "
            "cross the zone and the stop distance in one step"
        )
    if arm["lengths"] is not None:
        lengths = arm["lengths"]
        radius = float(np.hypot(*motion["goal"]))
        reach, inner = float(lengths.sum()), max(0.0, float(2 * lengths.max() - lengths.sum()))
        if radius > reach or radius < inner:
            found.append(
                f"motion.goal: {_fmt(motion['goal'])} is {radius:g} m from the base, outside the "
                f"reachable annulus [{inner:g}, {reach:g}] m: the goal cannot be reached"
            )
    else:
        model = (
            SerialArm(arm["dh"], arm["convention"], arm["tool"])
            if arm["chain"] is None
            else SerialArm.from_chain(arm["chain"], arm["tool"])
        )
        reach = model.reach
        radius = float(np.linalg.norm(motion["goal"][:3]))
        if radius > reach:
            found.append(
                f"motion.goal: {_fmt(motion['goal'][:3])} is {radius:g} m from the base, beyond "
                f"the arm's reach ({reach:g} m, the sum of its links): the goal cannot be reached"
            )
    return found
