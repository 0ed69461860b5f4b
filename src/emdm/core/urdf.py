"""Robots from URDF files: the chain from a base link to a tip link, and its joint limits.

The file is read by yourdfpy (the ``urdf`` extra: ``pip install 'emdm[urdf]'``), a small, kept
pure-Python URDF library, with its meshes and scene graphs left unloaded: emdm needs the joints
only. The chain from ``base_link`` to ``tip_link`` becomes a :class:`~emdm.core.serial.Chain`
with URDF's semantics: per joint its parent-to-child ``origin`` (``xyz``, then ``rpy`` as
fixed-axis roll, pitch, yaw), then its motion by ``q`` about (revolute, continuous) or along
(prismatic) its unit ``axis``, in the joint's frame. Fixed joints fold into the next joint's
origin, or into the chain's tail after the last joint.

Supported: revolute, continuous (a revolute joint whose position limits the scenario must give)
and prismatic joints in the chain, fixed joints anywhere. Not supported, each a one-line
:class:`~emdm.errors.ScenarioError`: floating and planar joints in the chain, mimic joints in the
chain (joints outside it, such as a gripper's fingers, are ignored), a link with two parents or a
loop, a branching tree without a chosen ``tip_link``, inverted limits, an axis of length 0.
"""

from __future__ import annotations

import logging
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import ScenarioError
from .chain import Chain

Vector = NDArray[np.float64]

MOVING = ("revolute", "continuous", "prismatic")
"""Joint types the chain can hold besides ``fixed``."""


@dataclass(frozen=True, eq=False)
class UrdfArm:
    """The chain of a URDF file from ``base_link`` to ``tip_link`` and its joints' limits as the
    file gives them (NaN where it gives none: a continuous joint's position, a missing or zero
    velocity): positions ``q_min, q_max`` (rad or m), speed ``qd_max`` (rad/s or m/s)."""

    path: Path
    base_link: str
    tip_link: str
    chain: Chain
    q_min: Vector
    q_max: Vector
    qd_max: Vector
    types: tuple[str, ...]


def _load(path: Path) -> Any:
    """The yourdfpy model of ``path``, with nothing but its structure loaded."""
    try:
        import yourdfpy
    except ImportError:  # pragma: no cover - the extra is part of every install the README makes
        raise ScenarioError(
            str(path), "arm.urdf", "needs the urdf extra: pip install 'emdm[urdf]'"
        ) from None
    try:
        ET.parse(path)  # yourdfpy would recover from malformed XML silently
    except ET.ParseError as exc:
        raise ScenarioError(str(path), "", f"not a well-formed XML file: {exc}") from None
    except OSError as exc:
        raise ScenarioError(str(path), "", f"cannot be read: {exc.strerror or exc}") from None
    quiet = logging.getLogger("yourdfpy")
    level = quiet.level
    quiet.setLevel(logging.CRITICAL)
    try:
        return yourdfpy.URDF.load(
            str(path),
            build_scene_graph=False,
            load_meshes=False,
            build_collision_scene_graph=False,
            load_collision_meshes=False,
        )
    except Exception as exc:  # a malformed element: yourdfpy raises what its parser met
        raise ScenarioError(str(path), "", f"not a valid URDF file: {exc}") from None
    finally:
        quiet.setLevel(level)


def _number(value: Any) -> float:
    return math.nan if value is None else float(value)


def read_urdf(
    path: str | Path, base_link: str | None = None, tip_link: str | None = None
) -> UrdfArm:
    """The chain of the URDF file ``path`` from ``base_link`` (default: the tree's root) to
    ``tip_link`` (default: its only leaf), with the file's joint limits (module notes)."""
    path = Path(path)
    source = str(path)
    if not path.is_file():
        raise ScenarioError(source, "arm.urdf", "no such URDF file")
    model = _load(path).robot
    links = [link.name for link in model.links]
    joints = list(model.joints)
    if not links:
        raise ScenarioError(source, "", "has no <link>: not a robot description")
    by_child: dict[str, Any] = {}
    children: dict[str, list[Any]] = {name: [] for name in links}
    for joint in joints:
        for end in (joint.parent, joint.child):
            if end not in children:
                raise ScenarioError(
                    source, f"joint {joint.name}", f"names the link {end!r}, which has no <link>"
                )
        if joint.child in by_child:
            raise ScenarioError(
                source,
                f"link {joint.child}",
                f"has two parent joints ({by_child[joint.child].name}, {joint.name}): "
                "a loop, not a tree",
            )
        by_child[joint.child] = joint
        children[joint.parent].append(joint)
    roots = [name for name in links if name not in by_child]
    if len(roots) != 1:
        raise ScenarioError(
            source,
            "",
            "has no root link (the joints form a loop)"
            if not roots
            else f"has {len(roots)} root links ({', '.join(roots[:4])}): not one tree",
        )
    base = base_link if base_link is not None else roots[0]
    for key, name in (("arm.base_link", base), ("arm.tip_link", tip_link)):
        if name is not None and name not in children:
            raise ScenarioError(
                source, key, f"no link {name!r} in the file (links: {', '.join(links[:12])}...)"
            )
    if tip_link is None:
        tip_link = _only_leaf(source, base, children)
    path_joints: list[Any] = []
    at = tip_link
    while at != base:
        joint = by_child.get(at)
        if joint is None:
            raise ScenarioError(
                source, "arm.tip_link", f"{tip_link!r} does not descend from {base!r}"
            )
        path_joints.append(joint)
        at = joint.parent
    path_joints.reverse()
    return _chain(source, base, tip_link, path_joints, path)


def _only_leaf(source: str, base: str, children: dict[str, list[Any]]) -> str:
    """The one leaf below ``base``, or an error naming where the tree branches."""
    at = base
    while children[at]:
        if len(children[at]) > 1:
            leaves = _leaves(at, children)
            raise ScenarioError(
                source,
                "arm.tip_link",
                f"is needed: the tree branches at {at!r} (leaves: {', '.join(leaves[:8])})",
            )
        at = children[at][0].child
    return at


def _leaves(at: str, children: dict[str, list[Any]]) -> list[str]:
    out, stack = [], [at]
    while stack:
        link = stack.pop()
        below = [joint.child for joint in children[link]]
        if not below:
            out.append(link)
        stack.extend(reversed(below))
    return out


def _chain(source: str, base: str, tip: str, path_joints: list[Any], path: Path) -> UrdfArm:
    """Fold fixed joints and collect the moving ones (module notes)."""
    pending = np.eye(4)
    origins, axes, prismatic, names, types = [], [], [], [], []
    q_min, q_max, qd_max = [], [], []
    for joint in path_joints:
        key = f"joint {joint.name}"
        origin = np.eye(4) if joint.origin is None else np.asarray(joint.origin, dtype=float)
        if not np.all(np.isfinite(origin)):
            raise ScenarioError(source, key, "has an origin that is not finite")
        if joint.type == "fixed":
            pending = pending @ origin
            continue
        if joint.type not in MOVING:
            raise ScenarioError(
                source,
                key,
                f"is {joint.type}: the chain takes revolute, continuous, prismatic and fixed "
                "joints",
            )
        if joint.mimic is not None:
            raise ScenarioError(
                source,
                key,
                f"mimics {joint.mimic.joint}: mimic joints in the chain are not supported",
            )
        axis = np.asarray(joint.axis, dtype=float)
        norm = float(np.linalg.norm(axis))
        if axis.shape != (3,) or not math.isfinite(norm) or norm < 1e-12:
            raise ScenarioError(source, key, "has an axis of length 0 (or not 3 numbers)")
        limit = joint.limit
        lower = math.nan if limit is None or joint.type == "continuous" else _number(limit.lower)
        upper = math.nan if limit is None or joint.type == "continuous" else _number(limit.upper)
        speed = math.nan if limit is None else _number(limit.velocity)
        if lower > upper:
            raise ScenarioError(
                source, key, f"has inverted limits: lower {lower:g} > upper {upper:g}"
            )
        if speed <= 0:  # some files write velocity="0" for "not given"
            speed = math.nan
        origins.append(pending @ origin)
        axes.append(axis / norm)
        prismatic.append(joint.type == "prismatic")
        names.append(joint.name)
        types.append(joint.type)
        q_min.append(lower)
        q_max.append(upper)
        qd_max.append(speed)
        pending = np.eye(4)
    if not origins:
        raise ScenarioError(source, "arm.tip_link", f"no moving joint between {base!r} and {tip!r}")
    lo, hi = np.array(q_min), np.array(q_max)
    is_prismatic = np.array(prismatic, dtype=bool)
    travel = np.where(is_prismatic, np.fmax(np.abs(lo), np.abs(hi)), 0.0)
    chain = Chain(
        np.ascontiguousarray(origins),
        np.ascontiguousarray(axes),
        is_prismatic,
        np.ascontiguousarray(pending),
        tuple(names),
        np.nan_to_num(travel, nan=0.0),
    )
    return UrdfArm(path, base, tip, chain, lo, hi, np.array(qd_max), tuple(types))


__all__ = ["MOVING", "UrdfArm", "read_urdf"]
