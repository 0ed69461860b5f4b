"""Scenarios: frozen, validated descriptions of one control task (schema: README, "Scenario files";
its keys: :mod:`emdm.core.schema`).

A scenario comes from a TOML file, a built-in preset (``task1``, ``task2``: Tables 1 and 2 of the
brief), ``--set section.key=value`` overrides or the Python API (reading them:
:mod:`emdm.core.loading`); all of them go through the same validation in
:func:`scenario_from_dict`, which raises :class:`~emdm.errors.ScenarioError` naming the
source, the key and the problem. Per-joint values may be given as one scalar.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ScenarioError
from .arm import PlanarArm, Vector
from .checks import _Checker, _name, _show
from .distance import pack as pack_obstacles
from .kernels import ArmData, Geometry
from .obstacles import Obstacle, check_damper, check_start, pack_rows, parse_obstacles
from .obstacles import distances as obstacle_distances
from .robot import Robot
from .schema import (
    AXES,
    SCHEMA,
    SECTION_TYPES,
    SPATIAL_ONLY,
    TASK_CODES,
    TASK_ROWS,
    plain,
    toml_value,
)
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
from .serial import SerialArm, _tool
from .serial_kernels import ROWS_ALL, ROWS_ROT, ROWS_TRANS
from .urdf import UrdfArm, read_urdf
from .validation import Policy, SlackUse, _check_consistency


@dataclass(frozen=True, eq=False)
class Scenario:
    """A complete, validated control task. Build with :func:`load_scenario` or :func:`scenario_from_dict`."""

    name: str
    arm: ArmSpec
    motion: Motion
    weights: Weights
    slack: SlackBounds
    damper: Damper
    controller: ControllerSettings
    planes: Planes
    obstacle_damper: ObstacleDamper
    source: str = "<python>"
    warnings: tuple[str, ...] = field(default=())
    obstacles: tuple[Obstacle, ...] = field(default=())
    """The ``[[obstacles]]`` (:mod:`emdm.core.obstacles`)."""

    @cached_property
    def obstacle_data(self) -> list[float]:
        """The obstacles and their damper packed for the kernels (:mod:`emdm.core.distance`;
        empty without obstacles)."""
        if not self.obstacles:
            return []
        od = self.obstacle_damper
        return pack_obstacles(
            *pack_rows(self.obstacles),
            influence=od.influence,
            stop=od.stop,
            gain=od.gain,
            link_radius=od.link_radius,
            dt=self.motion.dt,
        )

    def plane_distances(self, q: Vector) -> Vector:
        """``d_i = n_i . p - offset_i`` (m): the end effector's distance to each plane at ``q``
        (``n`` finite joint values, else a :class:`~emdm.errors.ScenarioError` naming ``q``)."""
        p = self.robot.position(q)
        return np.asarray(self.planes.normals @ p - self.planes.offsets, dtype=float)

    def obstacle_distances(self, q: Vector, t: float = 0.0) -> Vector:
        """``D[i, o]`` (m): link ``i``'s distance to obstacle ``o`` at ``q`` and time ``t`` (s).

        Raises :class:`~emdm.errors.ScenarioError` unless ``q`` is ``n`` finite joint values
        and ``t`` a finite number."""
        check = _Checker("Scenario.obstacle_distances")
        q = check.array("q", q, (self.n,), what=lambda: f"{self.n} joint values")
        return obstacle_distances(self, q, check.real("t", t))

    @property
    def n(self) -> int:
        """Number of joints."""
        return int(self.arm.q_min.size)

    @property
    def spatial(self) -> bool:
        """True for an arm in 3-D (given by DH rows or a URDF file)."""
        return self.arm.dh is not None or self.arm.chain is not None

    @property
    def nt(self) -> int:
        """Number of task rows: 2 (planar), 3 (position) or 6 (pose)."""
        return TASK_ROWS[self.motion.task]

    @property
    def task_code(self) -> int:
        """The task as the kernels know it (``core.kernels.TASK_*``)."""
        return TASK_CODES[self.motion.task]

    @property
    def redundant(self) -> bool:
        """True when the arm has more joints than task rows."""
        return self.n > self.nt

    @cached_property
    def planar_arm(self) -> PlanarArm:
        """The kinematic model of this scenario's planar arm."""
        if self.arm.lengths is None:
            raise ScenarioError(
                self.source,
                "arm",
                "is a spatial arm (arm.dh), and this needs a planar one (arm.lengths)",
            )
        return PlanarArm(self.arm.lengths)

    @cached_property
    def serial_arm(self) -> SerialArm:
        """The kinematic model of this scenario's spatial arm."""
        if self.arm.chain is not None:
            return SerialArm.from_chain(self.arm.chain, self.arm.tool)
        if self.arm.dh is None:
            raise ScenarioError(
                self.source, "arm", "is a planar arm (arm.lengths), not a spatial one"
            )
        return SerialArm(self.arm.dh, self.arm.convention, self.arm.tool)  # type: ignore[arg-type]

    @property
    def robot(self) -> Robot:
        """The arm's model behind the one :class:`~emdm.core.robot.Robot` interface: the planar
        chain or the DH chain, as the ``[arm]`` section says."""
        return self.serial_arm if self.spatial else self.planar_arm

    @property
    def reach(self) -> float:
        """Farthest the end effector can be from the base (m): the sum of the link lengths, or
        of ``|a| + |d|`` over the DH rows plus the tool's length."""
        return self.robot.reach

    @property
    def link_lengths(self) -> Vector:
        """Length of each link (m): the planar lengths, ``hypot(a, d)`` of each DH row, or the
        length of each joint's fixed origin in a URDF chain."""
        if self.arm.lengths is not None:
            return self.arm.lengths
        if self.arm.chain is not None:
            return np.asarray(np.linalg.norm(self.arm.chain.origins[:, :3, 3], axis=1))
        return np.hypot(self.arm.dh[:, 0], self.arm.dh[:, 2])  # type: ignore[index]

    @cached_property
    def memo(self) -> dict[Any, Any]:
        """Kernel inputs built from this scenario, kept for its next run (a scenario is immutable,
        as :attr:`arm_data` and :attr:`geometry` assume): each controller's program data and the
        motion, which cost a run of a few steps more than its steps do."""
        return {}

    @cached_property
    def arm_data(self) -> ArmData:
        """The arm's links, limits and dampers as input of the compiled kernels."""
        a, d = self.arm, self.damper
        return ArmData(
            *(
                np.array(x, dtype=float)
                for x in (
                    self.link_lengths,
                    a.q_min,
                    a.q_max,
                    a.qd_min,
                    a.qd_max,
                    d.influence,
                    d.stop,
                    d.gain,
                )
            )
        )

    @cached_property
    def geometry(self) -> Geometry:
        """A spatial arm's chain (DH rows, convention, tool, manipulability rows) as kernel
        input; a planar arm has no DH rows."""
        rows = {"all": ROWS_ALL, "trans": ROWS_TRANS, "rot": ROWS_ROT}[self.motion.axes]
        if not self.spatial:
            return Geometry(
                np.zeros((0, 4, 4)), np.zeros((0, 3)), np.zeros(0, bool), np.eye(4), rows
            )
        return self.serial_arm.geometry(rows)

    @property
    def max_steps(self) -> int:
        """Number of control steps that fit in ``max_time``: ``floor(max_time / dt)``."""
        return math.floor(self.motion.max_time / self.motion.dt + 1e-9)

    def to_dict(self) -> dict[str, Any]:
        """The scenario as plain data (the TOML layout), every per-joint value written out."""
        out: dict[str, Any] = {"name": self.name}
        for section in SCHEMA:
            if (section == "planes" and not self.planes.count) or (
                section == "obstacle_damper" and not self.obstacles
            ):
                continue  # none: the file stays as it was before planes and obstacles existed
            obj = getattr(self, section)
            out[section] = {
                key: plain(getattr(obj, key))
                for key in SCHEMA[section]
                if getattr(obj, key) is not None
                and not (SCHEMA[section][key].kind == "str" and getattr(obj, key) == "")
                and (self.spatial or f"{section}.{key}" not in SPATIAL_ONLY)
                and not (self.arm.chain is not None and f"{section}.{key}" == "arm.convention")
            }
            if (
                self.spatial
            ):  # one value per task row, when uniform: the file then takes another task
                for key, spec in SCHEMA[section].items():
                    value = out[section].get(key)
                    if spec.kind == "task" and spec.scalar_ok and len(set(value)) == 1:
                        out[section][key] = value[0]
        if self.obstacles:
            out["obstacles"] = [o.to_dict() for o in self.obstacles]
        return out

    def to_toml(self) -> str:
        """The scenario as a TOML document that :func:`load_scenario` reads back identically."""
        lines = [f"name = {toml_value(self.name)}"]
        for section, values in self.to_dict().items():
            if section == "name":
                continue
            if section == "obstacles":
                for table in values:
                    lines.append("\n[[obstacles]]")
                    lines.extend(f"{key} = {toml_value(v)}" for key, v in table.items())
                continue
            lines.append(f"\n[{section}]")
            lines.extend(f"{key} = {toml_value(value)}" for key, value in values.items())
        return "\n".join(lines) + "\n"

    def with_overrides(self, overrides: Mapping[str, Any]) -> Scenario:
        """A new scenario with ``{"section.key": value}`` replaced, validated like a file.

        Raises :class:`~emdm.errors.ScenarioError` for ``overrides`` that are not such a
        mapping, an unknown key or an invalid value.
        """
        _Checker("Scenario.with_overrides").mapping(
            "overrides", overrides, "'section.key' to values"
        )
        data = self.to_dict()
        for dotted, value in overrides.items():
            section, _, key = dotted.partition(".")
            if section == "name" and not key:
                data["name"] = value
                continue
            if section not in SCHEMA or key not in SCHEMA[section]:
                known = ", ".join(f"{s}.{k}" for s in SCHEMA for k in SCHEMA[s])
                raise ScenarioError(
                    "--set",
                    _name(dotted)
                    if not all(part.isidentifier() for part in dotted.split("."))
                    else dotted,
                    f"unknown key (known: name, {known})",
                )
            data.setdefault(section, {})[key] = value
        for key in ("arm.lengths", "arm.dh"):
            rows = overrides.get(key)
            if (key == "arm.dh") != self.spatial:
                continue  # the other kind of arm: scenario_from_dict names the conflict
            if isinstance(rows, list) and len(rows) != self.n:
                self._resize(data, overrides, len(rows), key)
        task = overrides.get("motion.task")
        if isinstance(task, str) and task in Task.__members__.values() and task != self.motion.task:
            for section, keys in SCHEMA.items():  # per-row values follow when they are uniform
                for key, spec in keys.items():
                    dotted = f"{section}.{key}"
                    if spec.kind == "task" and spec.scalar_ok and dotted not in overrides:
                        values = data[section][key]
                        if not isinstance(values, list):
                            continue
                        if len(set(values)) != 1:
                            raise ScenarioError(
                                self.source,
                                "motion.task",
                                f"changes the task rows, and {dotted} differs per row: set "
                                f"{dotted} as well",
                            )
                        data[section][key] = values[0]
        return scenario_from_dict(data, source=self.source)

    def _resize(self, data: dict[str, Any], overrides: Mapping[str, Any], n: int, by: str) -> None:
        """``arm.lengths`` (or ``arm.dh``) overridden with another number of joints: the per-joint
        values not overridden follow when they are one value for every joint, else ``by`` is
        blamed."""
        for section, keys in SCHEMA.items():
            for key, spec in keys.items():
                dotted = f"{section}.{key}"
                if spec.kind != "joints" or dotted in overrides or key not in data[section]:
                    continue
                if dotted in ("arm.lengths", "arm.dh"):
                    continue
                values = data[section][key]
                if spec.scalar_ok and len(set(values)) == 1:
                    data[section][key] = values[0]
                else:
                    raise ScenarioError(
                        self.source,
                        by,
                        f"gives {n} joints where the scenario has {self.n}, and {dotted} "
                        f"differs per joint: set {dotted} ({n} values) as well",
                    )


# ------------------------------------------------------------------------------ validation


def scenario_from_dict(data: Mapping[str, Any], *, source: str = "<python>") -> Scenario:
    """Validate raw scenario data (the TOML layout) and build a :class:`Scenario`.

    Raises :class:`~emdm.errors.ScenarioError` naming the source, the key and the problem (a
    ``source`` that is not a string is named as the argument).
    """
    _Checker("scenario_from_dict").text("source", source, "a string (the data's file or name)")
    check = _Checker(source)
    if not isinstance(data, Mapping):
        raise check.fail(
            "data", f"a scenario must be a table of sections (a dict), got {type(data).__name__}"
        )
    for key, value in data.items():
        if key == "name":
            if not isinstance(value, str) or not value:
                raise check.fail("name", f"must be a non-empty string, got {_show(value)}")
        elif key == "obstacles":
            continue  # a list of tables, read below
        elif key not in SCHEMA:
            raise check.fail(_name(key), f"unknown section (known: name, {', '.join(SCHEMA)})")
        elif not isinstance(value, Mapping):
            raise check.fail(key, f"must be a table ([{key}]), got {_show(value)}")
        else:
            for sub in value:
                if sub not in SCHEMA[key]:
                    raise check.fail(
                        f"{key}.{_name(sub)}",
                        f"unknown key (known in [{key}]: {', '.join(SCHEMA[key])})",
                    )

    raw_arm = dict(data.get("arm", {}))
    raw_lengths, raw_dh, raw_urdf = raw_arm.get("lengths"), raw_arm.get("dh"), raw_arm.get("urdf")
    given = [
        k
        for k, v in (("lengths", raw_lengths), ("dh", raw_dh), ("urdf", raw_urdf))
        if (v is not None if isinstance(v, np.ndarray) else v)  # an array: refused below
    ]
    if len(given) > 1:
        raise check.fail(
            f"arm.{given[1]}",
            "a planar arm has arm.lengths, a spatial one arm.dh or arm.urdf: give one of them",
        )
    spatial = raw_dh is not None or raw_urdf is not None
    robot = None
    if raw_urdf is not None:
        robot = _read_robot(check, raw_arm, source)
        n = robot.chain.n
        data = {**data, "arm": raw_arm}  # the file's limits where the scenario gives none
    elif spatial:
        if not isinstance(raw_dh, list) or len(raw_dh) < 1:
            raise check.fail(
                "arm.dh", "must be a list of rows [a, alpha, d, offset], one per joint"
            )
        n = len(raw_dh)
    else:
        if raw_lengths is None:
            raise check.fail("arm.lengths", "is required (or arm.dh for a spatial arm)")
        if not isinstance(raw_lengths, list) or len(raw_lengths) < 2:
            raise check.fail("arm.lengths", "must be a list of at least 2 link lengths")
        n = len(raw_lengths)
        for dotted in SPATIAL_ONLY:
            section, key = dotted.split(".")
            if key in data.get(section, {}):
                raise check.fail(dotted, "is for spatial arms only (given by arm.dh)")
    raw_task = data.get("motion", {}).get("task", "pose" if spatial else "planar")
    tasks = ("position", "pose") if spatial else ("planar",)
    if not isinstance(raw_task, str) or raw_task not in tasks:
        raise check.fail(
            "motion.task", f"must be {' or '.join(repr(t) for t in tasks)}, got {_show(raw_task)}"
        )
    task = Task(raw_task)
    nt = TASK_ROWS[task]

    parsed: dict[str, dict[str, Any]] = {}
    for section, keys in SCHEMA.items():
        raw_section = data.get(section, {})
        parsed[section] = {}
        for key, spec in keys.items():
            dotted = f"{section}.{key}"
            value = raw_section.get(key, spec.default)
            if value is None:
                raise check.fail(dotted, "is required")
            if isinstance(value, str) and value == "" and spec.kind != "str" and spec.default == "":
                parsed[section][key] = None  # an optional key left out (arm.lengths or arm.dh)
            elif spec.kind == "joints":
                parsed[section][key] = check.vector(dotted, value, n, spec.scalar_ok)
            elif spec.kind == "task":
                parsed[section][key] = check.vector(dotted, value, nt, spec.scalar_ok)
            elif spec.kind == "vec3":
                parsed[section][key] = check.vector(dotted, value, 3, False)
            elif spec.kind == "tool":
                if isinstance(value, list) and len(value) == 4:
                    parsed[section][key] = check.table(dotted, value, 4, 4).reshape(4, 4)
                else:
                    parsed[section][key] = check.vector(dotted, value, 3, False)
            elif spec.kind == "dh":
                parsed[section][key] = check.table(dotted, value, n, 4)
            elif spec.kind == "rows":
                dim = 3 if spatial else 2
                rows = value if isinstance(value, list) else None
                if rows is None:
                    raise check.fail(dotted, f"must be a list of rows of {dim} numbers")
                table = check.table(dotted, rows, len(rows), dim)
                parsed[section][key] = table.reshape(len(rows), dim)
            elif spec.kind == "list":
                if not isinstance(value, list):
                    raise check.fail(dotted, f"must be a list of numbers, got {_show(value)}")
                parsed[section][key] = check.vector(dotted, value, len(value), False)
            elif spec.kind == "number":
                parsed[section][key] = check.number(dotted, value)
            else:
                if not isinstance(value, str):
                    raise check.fail(dotted, f"must be a string, got {_show(value)}")
                parsed[section][key] = value
    parsed["motion"]["task"] = task
    parsed["arm"]["chain"] = None if robot is None else robot.chain
    if robot is None and (parsed["arm"]["base_link"] or parsed["arm"]["tip_link"]):
        key = "arm.base_link" if parsed["arm"]["base_link"] else "arm.tip_link"
        raise check.fail(key, "is for a robot from a URDF file (arm.urdf)")
    if spatial:
        try:
            _tool(parsed["arm"]["tool"], source, "arm.tool")
        except ScenarioError:
            raise check.fail(
                "arm.tool",
                "must be a translation [x, y, z] (m) or a rigid 4 x 4 transform (rows)",
            ) from None
    if parsed["arm"]["convention"] not in ("standard", "modified"):
        raise check.fail(
            "arm.convention",
            f'must be "standard" or "modified", got {_show(parsed["arm"]["convention"])}',
        )
    if parsed["motion"]["axes"] not in AXES:
        raise check.fail(
            "motion.axes",
            f"must be one of {', '.join(AXES)}, got {_show(parsed['motion']['axes'])}",
        )

    warnings_found = _check_consistency(check, parsed, n)
    parsed["controller"]["on_infeasible"] = Policy(parsed["controller"]["on_infeasible"])
    parsed["controller"]["slack"] = SlackUse(parsed["controller"]["slack"])
    name = data.get("name") or Path(source).stem or "scenario"
    sections = {s: SECTION_TYPES[s](**values) for s, values in parsed.items()}
    obstacles = (
        parse_obstacles(check, data["obstacles"], 3 if spatial else 2)
        if "obstacles" in data
        else ()
    )
    if obstacles:
        check_damper(check, parsed["obstacle_damper"], parsed["motion"]["dt"])
        if robot is not None and robot.chain.prismatic.any():
            joint = robot.chain.names[int(np.flatnonzero(robot.chain.prismatic)[0])]
            raise check.fail(
                "obstacles",
                f"need an arm of revolute joints, and {joint} is prismatic (the damper's "
                "tightening bounds rotations only)",
            )
    scenario = Scenario(
        name=str(name),
        source=source,
        warnings=tuple(warnings_found),
        obstacles=obstacles,
        **sections,
    )
    check_start(check, scenario)
    return scenario


def _read_robot(check: _Checker, raw_arm: dict[str, Any], source: str) -> UrdfArm:
    """The URDF file of ``arm.urdf`` (relative to the scenario file), read into its chain; the
    file's joint limits fill the ``arm`` keys the scenario leaves out (in place)."""
    raw = raw_arm["urdf"]
    if not isinstance(raw, str) or not raw:
        raise check.fail("arm.urdf", f"must be the path of a URDF file, got {_show(raw)}")
    names = {}
    for key in ("base_link", "tip_link"):
        value = raw_arm.get(key)
        if value is not None and (not isinstance(value, str) or not value):
            raise check.fail(f"arm.{key}", f"must be a link's name, got {_show(value)}")
        names[key] = value or None
    if "convention" in raw_arm:
        raise check.fail("arm.convention", "is for DH rows (arm.dh), not a URDF file")
    path = Path(raw).expanduser()
    if not path.is_absolute():
        here = Path(source)
        path = (here.parent if here.is_file() else Path.cwd()) / path
    path = path.resolve()
    try:
        robot = read_urdf(path, names["base_link"], names["tip_link"])
    except ScenarioError as exc:
        where = f"arm.urdf ({path.name})" if not exc.key else f"arm.urdf ({path.name}): {exc.key}"
        raise check.fail(where, exc.problem) from None
    raw_arm["urdf"] = str(path)
    raw_arm["base_link"], raw_arm["tip_link"] = robot.base_link, robot.tip_link
    defaults = {"q_min": robot.q_min, "q_max": robot.q_max, "qd_max": robot.qd_max}
    defaults["qd_min"] = -robot.qd_max
    for key, values in defaults.items():
        if key in raw_arm:
            continue
        missing = [robot.chain.names[j] for j in np.flatnonzero(~np.isfinite(values))]
        if missing:
            raise check.fail(
                f"arm.{key}",
                f"is required: the file gives none for {', '.join(missing)}",
            )
        raw_arm[key] = [float(v) for v in values]
    return robot
