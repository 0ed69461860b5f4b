"""The independent reference for URDF arms: the file read with the standard library's XML parser
and URDF's semantics written out in numpy, in complex arithmetic so that complex-step
differentiation gives the Hessian to rounding; the manipulability and its gradient follow from
them in 40-digit arithmetic (mpmath).

Nothing here calls emdm or yourdfpy. The semantics (the URDF specification): each joint's
``<origin xyz rpy>`` places its frame in its parent link's frame, ``rpy`` being fixed-axis roll
about x, then pitch about y, then yaw about z (``R = Rz(yaw) Ry(pitch) Rx(roll)``); the joint
then rotates by ``q`` about its ``<axis xyz>`` (revolute, continuous) or translates by ``q`` along
it (prismatic), in its own frame; fixed joints do not move.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import mpmath
import numpy as np


@dataclass
class Joint:
    name: str
    kind: str
    parent: str
    child: str
    xyz: np.ndarray
    rpy: np.ndarray
    axis: np.ndarray


def parse(path) -> dict[str, Joint]:
    """Joints of a URDF file by child link."""
    out = {}
    for el in ET.parse(path).getroot().findall("joint"):  # not a <transmission>'s
        origin = el.find("origin")
        axis = el.find("axis")

        def numbers(node, key, default):
            return np.array(
                [
                    float(v)
                    for v in (node.get(key, default) if node is not None else default).split()
                ]
            )

        joint = Joint(
            el.get("name"),
            el.get("type"),
            el.find("parent").get("link"),
            el.find("child").get("link"),
            numbers(origin, "xyz", "0 0 0"),
            numbers(origin, "rpy", "0 0 0"),
            numbers(axis, "xyz", "1 0 0"),
        )
        out[joint.child] = joint
    return out


def chain(path, base: str, tip: str) -> list[Joint]:
    """The joints from ``base`` to ``tip``, in order."""
    joints = parse(path)
    out, at = [], tip
    while at != base:
        out.append(joints[at])
        at = joints[at].parent
    return out[::-1]


def _rot(axis, angle):
    """Rotation by ``angle`` about the unit ``axis`` (Rodrigues; complex ``angle`` allowed)."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) * np.cos(angle) + np.sin(angle) * K + (1 - np.cos(angle)) * np.outer(a, a)


def _origin(joint: Joint) -> np.ndarray:
    r, p, y = joint.rpy
    T = np.eye(4)
    T[:3, :3] = _rot([0, 0, 1], y) @ _rot([0, 1, 0], p) @ _rot([1, 0, 0], r)
    T[:3, 3] = joint.xyz
    return T


def moving(joints: list[Joint]) -> list[Joint]:
    return [j for j in joints if j.kind != "fixed"]


def forward(joints: list[Joint], q, tool=None):
    """``(T, J)``: the tip's pose (4 x 4) and geometric Jacobian (6 x n, linear rows first) in the
    base frame; complex ``q`` allowed."""
    q = np.asarray(q)
    dtype = complex if np.iscomplexobj(q) else float
    T = np.eye(4, dtype=dtype)
    axes, origins, kinds = [], [], []
    k = 0
    for joint in joints:
        T = T @ _origin(joint)
        if joint.kind == "fixed":
            continue
        a = joint.axis / np.linalg.norm(joint.axis)
        M = np.eye(4, dtype=dtype)
        if joint.kind == "prismatic":
            M[:3, 3] = q[k] * a
        else:
            M[:3, :3] = _rot(a, q[k])
        axes.append(T[:3, :3] @ a)
        T = T @ M
        origins.append(T[:3, 3].copy())
        kinds.append(joint.kind)
        k += 1
    if tool is not None:
        T = T @ tool
    J = np.zeros((6, k), dtype=dtype)
    for i, (z, o, kind) in enumerate(zip(axes, origins, kinds, strict=True)):
        if kind == "prismatic":
            J[:3, i] = z
        else:
            J[:3, i] = np.cross(z, T[:3, 3] - o)
            J[3:, i] = z
    return T, J


def _high_precision(J, rows):
    """``J_a`` (the rows ``rows``) of a float Jacobian as a 40-digit mpmath matrix."""
    return mpmath.matrix(np.asarray(J, float)[rows].tolist())


def manipulability(joints, q, rows=slice(None), tool=None):
    """``sqrt(det(J_a J_a^T))`` in 40-digit arithmetic from the reference Jacobian: near a
    singularity, forming ``J_a J_a^T`` in double precision squares the condition number."""
    with mpmath.workdps(40):
        Ja = _high_precision(forward(joints, q, tool)[1], rows)
        return float(mpmath.sqrt(mpmath.det(Ja * Ja.T)))


def complex_step(f, q, h=1e-30):
    """``df/dq_i`` for every ``i`` by the complex step ``Im f(q + i h e_i) / h`` (no cancellation)."""
    q = np.asarray(q, float)
    return np.array([np.imag(f(q + 1j * h * e)) / h for e in np.eye(q.size)])


def hessian(joints, q, tool=None):
    """``H[i] = dJ/dq_i`` (n x 6 x n) by complex steps of :func:`forward`."""
    return complex_step(lambda x: forward(joints, x, tool)[1], q)


def manipulability_gradient(joints, q, rows=slice(None), tool=None):
    """``dm/dq_i = m tr((J_a J_a^T)^-1 J_a H_a,i^T)`` in 40-digit arithmetic from the reference
    ``J`` and its complex-step Hessian (both exact to rounding)."""
    J = forward(joints, q, tool)[1]
    H = hessian(joints, q, tool)
    with mpmath.workdps(40):
        Ja = _high_precision(J, rows)
        A = Ja * Ja.T
        m = mpmath.sqrt(mpmath.det(A))
        B = A**-1 * Ja
        out = []
        for Hi in H:
            Ha = _high_precision(Hi, rows)
            out.append(float(m * sum((B * Ha.T)[a, a] for a in range(Ja.rows))))
    return np.array(out)
