"""The one robot interface: the planar and the DH chain behind the same methods, chosen by the
scenario's [arm] section, each method checked against finite differences or the model's own."""

from __future__ import annotations

import numpy as np
import pytest

import emdm
from emdm.core.robot import Robot


@pytest.mark.parametrize("name", ["task1", "task2", "panda", "ur5"])
def test_every_preset_arm_is_a_robot(name, rng):
    sc = emdm.load_scenario(name)
    robot = sc.robot
    assert isinstance(robot, Robot)
    assert robot.dim == (3 if sc.spatial else 2) and robot.n == sc.n
    for _ in range(5):
        q = rng.uniform(sc.arm.q_min, sc.arm.q_max)
        p = robot.position(q)
        pts = robot.joint_positions(q)
        assert p.shape == (robot.dim,) and pts.shape[1] == robot.dim
        np.testing.assert_allclose(pts[0], 0.0, atol=1e-15)
        np.testing.assert_allclose(pts[-1], p, atol=1e-15)
        h = 1e-6
        fd = np.stack(
            [
                (robot.position(q + h * e) - robot.position(q - h * e)) / (2 * h)
                for e in np.eye(sc.n)
            ],
            axis=1,
        )
        np.testing.assert_allclose(robot.position_jacobian(q), fd, atol=1e-8)
        assert np.linalg.norm(p) <= robot.reach + 1e-12
        # the compiled step sees the same model: its task value starts with this position
        np.testing.assert_allclose(
            emdm.core.controllers.state_at(sc, q).kin.p[: robot.dim], p, atol=1e-14
        )
