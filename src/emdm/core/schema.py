"""The scenario file's layout: its sections, their keys and each key's kind and default (README,
"Scenario files"); :func:`~emdm.core.scenario.scenario_from_dict` validates against it and
:meth:`~emdm.core.scenario.Scenario.to_toml` writes it."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import numpy as np

from .kernels import TASK_PLANAR, TASK_POSE, TASK_POSITION
from .sections import (
    ArmSpec,
    ControllerSettings,
    Damper,
    Motion,
    ObstacleDamper,
    Planes,
    SlackBounds,
    Task,
    Weights,
)

TASK_ROWS = {Task.PLANAR: 2, Task.POSITION: 3, Task.POSE: 6}
TASK_CODES = {Task.PLANAR: TASK_PLANAR, Task.POSITION: TASK_POSITION, Task.POSE: TASK_POSE}
AXES = ("all", "trans", "rot")
SPATIAL_ONLY = (
    "arm.dh",
    "arm.convention",
    "arm.urdf",
    "arm.base_link",
    "arm.tip_link",
    "arm.tool",
    "motion.task",
    "motion.axes",
)
"""Keys of spatial arms only (a planar scenario neither needs nor writes them)."""


# ---------------------------------------------------------------------------------------- schema
# kind: "joints" (n values, scalar allowed), "task" (one value per task row: 2 planar, 3 position,
# 6 pose), "dh" (n rows of 4), "tool" (3 numbers or 4 rows of 4), "number", "str", "rows" (any
# number of rows of one value per axis of the workspace: 2 planar, 3 spatial), "list" (any number
# of values). Missing optional keys take the default (the brief's values); "" marks a key that
# is optional without a default.
@dataclass(frozen=True)
class Key:
    kind: str
    default: Any = None  # None: required
    scalar_ok: bool = True


SCHEMA: dict[str, dict[str, Key]] = {
    "arm": {
        "lengths": Key("joints", "", scalar_ok=False),
        "dh": Key("dh", ""),
        "convention": Key("str", "standard"),
        "urdf": Key("str", ""),
        "base_link": Key("str", ""),
        "tip_link": Key("str", ""),
        "tool": Key("tool", [0.0, 0.0, 0.0]),
        "q_min": Key("joints"),
        "q_max": Key("joints"),
        "qd_min": Key("joints"),
        "qd_max": Key("joints"),
    },
    "motion": {
        "q0": Key("joints", scalar_ok=False),
        "task": Key("str", ""),
        "axes": Key("str", "all"),
        "goal": Key("task", scalar_ok=False),
        "dt": Key("number", 0.05),
        "kp": Key("task", 1.0),
        "tolerance": Key("number", 1e-3),
        "max_time": Key("number", 30.0),
    },
    "weights": {
        "effort": Key("number", 0.1),
        "manipulability": Key("number", 5.0),
        "slack": Key("number", 10.0),
        "centring": Key("number", 0.0),
        "clearance": Key("number", 0.0),
    },
    "slack": {"min": Key("task", -1.0), "max": Key("task", 1.0)},
    "damper": {
        "influence": Key("joints", 0.785398),
        "stop": Key("joints", 0.0872665),
        "gain": Key("joints", 1.0),
    },
    "controller": {"on_infeasible": Key("str", "scale"), "slack": Key("str", "auto")},
    "planes": {
        "normals": Key("rows", []),
        "offsets": Key("list", []),
        "influence": Key("number", 0.1),
        "stop": Key("number", 0.02),
        "gain": Key("number", 1.0),
    },
    "obstacle_damper": {
        "influence": Key("number", 0.15),
        "stop": Key("number", 0.03),
        "gain": Key("number", 1.0),
        "link_radius": Key("number", 0.0),
    },
}


SECTION_TYPES: dict[str, Callable[..., Any]] = {
    "arm": ArmSpec,
    "motion": Motion,
    "weights": Weights,
    "slack": SlackBounds,
    "damper": Damper,
    "controller": ControllerSettings,
    "planes": Planes,
    "obstacle_damper": ObstacleDamper,
}


def plain(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return [plain(v) if isinstance(v, np.ndarray) else float(v) for v in value]
    return str(value) if isinstance(value, StrEnum) else value


def toml_value(value: Any) -> str:
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    return repr(float(value))
