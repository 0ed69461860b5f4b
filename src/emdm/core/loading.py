"""Loading scenarios: the built-in presets, TOML files, URDF files (a template scenario for the
robot) and ``--set section.key=value`` overrides; all of them go through the validation of
:func:`~emdm.core.scenario.scenario_from_dict`."""

from __future__ import annotations

import tomllib
import warnings
from collections.abc import Mapping
from importlib import resources
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ScenarioError
from .checks import _Checker
from .kernels import rotation_vector
from .scenario import Scenario, _read_robot, scenario_from_dict
from .serial import SerialArm

PLANAR_PRESETS = ("task1", "task2")
"""The brief's planar tasks (Tables 1 and 2)."""
SPATIAL_PRESETS = ("panda", "ur5")
"""Spatial arms: Franka Emika Panda (modified DH) and Universal Robots UR5 (standard DH)."""
OBSTACLE_PRESETS = ("obstacle", "panda-obstacles")
"""Scenes with obstacles (docs/mathematics.md, "Obstacles")."""
PRESETS = PLANAR_PRESETS + SPATIAL_PRESETS + OBSTACLE_PRESETS


class ScenarioWarning(UserWarning):
    """A scenario that is valid but probably not what was meant (e.g. an unreachable goal)."""


def urdf_template(path: str | Path, overrides: Mapping[str, Any] | None = None) -> Scenario:
    """A scenario for the robot of a URDF file: the file's chain and limits (``arm.base_link``,
    ``arm.tip_link`` from ``overrides`` where the file leaves a choice), a start ``q0``, and a
    goal the arm reaches:
    the pose (6 or more joints; else the position) at ``q0`` moved a fifth of the way to the
    upper limits. The other settings are the defaults; ``emdm scenario robot.urdf`` prints it.
    The start is the most dexterous (largest manipulability) of ``q = 0`` and 64 seeded draws in
    the middle of the limits: a straight arm at 0 (many robots' zero) is singular."""
    overrides = dict(overrides or {})
    source = str(path)
    arm: dict[str, Any] = {"urdf": str(Path(path).resolve())}
    for key in ("base_link", "tip_link"):
        if f"arm.{key}" in overrides:
            arm[key] = overrides.pop(f"arm.{key}")
    check = _Checker(source)
    robot = _read_robot(check, arm, "")
    lo, hi = np.asarray(arm["q_min"]), np.asarray(arm["q_max"])
    model = SerialArm.from_chain(robot.chain)
    task = "pose" if robot.chain.n >= 6 else "position"
    axes: Any = "all" if task == "pose" else "trans"
    # the start: of 0 and 64 seeded draws in the middle 60 % of the limits, the most dexterous
    draws = np.random.default_rng(0).uniform(0.2, 0.8, (64, lo.size)) * (hi - lo) + lo
    zero = np.clip(0.0, lo, hi)
    q0 = max((zero, *draws), key=lambda q: model.manipulability(q, axes))
    reach = model.forward(q0 + 0.2 * (hi - q0))
    goal = reach[:3, 3].tolist()
    if task == "pose":
        rotvec = np.empty(3)
        rotation_vector(np.ascontiguousarray(reach), rotvec, 0)
        goal += rotvec.tolist()
    data = {
        "name": Path(path).stem,
        "arm": arm,
        "motion": {"task": task, "axes": axes, "q0": q0.tolist(), "goal": goal},
    }
    scenario = scenario_from_dict(data, source=source)
    return scenario.with_overrides(overrides) if overrides else scenario


# ----------------------------------------------------------------------------------- loading
def parse_override(text: str) -> tuple[str, Any]:
    """``"section.key=value"`` -> ``("section.key", value)``; the value is read as TOML, else a string."""
    dotted, sep, raw = text.partition("=")
    dotted, raw = dotted.strip(), raw.strip()
    if not sep or not dotted:
        raise ScenarioError("--set", text, "expected section.key=value")
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except (ValueError, RecursionError):  # not TOML (or too deep, or an integer of more than
        value = raw  # 4300 digits): kept as text, which validation then refuses by name
    return dotted, value


def load_scenario(name_or_path: str | Path, overrides: Mapping[str, Any] | None = None) -> Scenario:
    """Load a preset (``"task1"``, ``"task2"``), a TOML file or a URDF file (a template scenario
    for the robot, :func:`urdf_template`), apply overrides, validate.

    Raises :class:`~emdm.errors.ScenarioError` for a missing file, a file that is not TOML, or invalid
    content, and for arguments of the wrong kind (``name_or_path`` not a string or a path,
    ``overrides`` not a mapping of ``"section.key"`` to values). Valid but suspicious settings are
    kept in ``scenario.warnings`` and issued as :class:`ScenarioWarning`.
    """
    check = _Checker("load_scenario")
    check.instance(
        "name_or_path", name_or_path, (str, PathLike), "a preset's name or a file's path"
    )
    if overrides is not None:
        check.mapping("overrides", overrides, "'section.key' to values")
    text_name = str(name_or_path)
    if Path(text_name).suffix.lower() == ".urdf":
        scenario = urdf_template(text_name, overrides)
        for message in scenario.warnings:
            warnings.warn(f"{text_name}: {message}", ScenarioWarning, stacklevel=2)
        return scenario
    if text_name in PRESETS and not Path(text_name).exists():
        text = resources.files("emdm.core").joinpath("scenarios", f"{text_name}.toml").read_text()
        source = text_name
    else:
        path = Path(name_or_path)
        source = str(path)
        if not path.is_file():
            hint = f" (presets: {', '.join(PRESETS)})" if path.suffix == "" else ""
            raise ScenarioError(source, "", f"no such scenario file{hint}")
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise ScenarioError(source, "", f"cannot be read: {exc}") from None
    try:
        data = tomllib.loads(text)
    except ValueError as exc:  # TOMLDecodeError, or an integer of more than 4300 digits
        raise ScenarioError(source, "", f"not a valid TOML file: {exc}") from None
    except RecursionError:
        raise ScenarioError(
            source, "", "not a scenario: its arrays or tables nest too deeply"
        ) from None
    data.setdefault("name", Path(source).stem)
    scenario = scenario_from_dict(data, source=source)
    if overrides:
        scenario = scenario.with_overrides(overrides)
    for message in scenario.warnings:
        warnings.warn(f"{source}: {message}", ScenarioWarning, stacklevel=2)
    return scenario
