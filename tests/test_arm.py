"""Kinematics against finite differences, the textbook formulas and the 2-link closed forms."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import fd_jacobian

from emdm import PlanarArm, ScenarioError


@pytest.mark.parametrize("n", range(2, 9))
def test_derivatives_match_central_differences(n, rng):
    for _ in range(5):
        arm = PlanarArm(rng.uniform(0.1, 1.0, n))
        q = rng.uniform(-np.pi, np.pi, n)
        np.testing.assert_allclose(arm.jacobian(q), fd_jacobian(arm.forward, q), atol=1e-8)
        H_fd = np.moveaxis(fd_jacobian(arm.jacobian, q), -1, 0)
        np.testing.assert_allclose(arm.hessian(q), H_fd, atol=1e-8)
        if arm.manipulability(q) > 1e-3:
            Jm_fd = fd_jacobian(lambda x, a=arm: np.array([a.manipulability(x)]), q)[0]
            np.testing.assert_allclose(arm.manipulability_jacobian(q), Jm_fd, atol=1e-8)


@pytest.mark.parametrize("n", range(2, 9))
def test_manipulability_matches_textbook_formulas(n, rng):
    arm = PlanarArm(rng.uniform(0.1, 1.0, n))
    for _ in range(10):
        q = rng.uniform(-np.pi, np.pi, n)
        J, H = arm.jacobian(q), arm.hessian(q)
        A = J @ J.T
        m = np.sqrt(np.linalg.det(A))
        assert arm.manipulability(q) == pytest.approx(m, abs=1e-14)
        textbook = [m * np.trace(np.linalg.solve(A, J @ H[j].T)) for j in range(n)]
        np.testing.assert_allclose(arm.manipulability_jacobian(q), textbook, atol=1e-12)


def test_forward_kinematics_by_hand():
    arm = PlanarArm([0.2, 0.6, 0.3])
    q = np.array([0.0, np.pi / 6, np.pi / 6])
    expected = [
        0.2 + 0.6 * np.cos(np.pi / 6) + 0.3 * np.cos(np.pi / 3),
        0.6 * np.sin(np.pi / 6) + 0.3 * np.sin(np.pi / 3),
    ]
    np.testing.assert_allclose(arm.forward(q), expected, atol=1e-15)
    points = arm.joint_positions(q)
    assert points.shape == (4, 2)
    np.testing.assert_allclose(points[-1], expected, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(np.diff(points, axis=0), axis=1), arm.lengths)


def test_two_link_closed_forms(rng):
    l1, l2 = 0.5, 0.4
    arm = PlanarArm([l1, l2])
    for q in rng.uniform(-3, 3, (50, 2)):
        assert arm.manipulability(q) == pytest.approx(l1 * l2 * abs(np.sin(q[1])), abs=1e-15)
        np.testing.assert_allclose(
            arm.manipulability_jacobian(q),
            [0.0, l1 * l2 * np.cos(q[1]) * np.sign(np.sin(q[1]))],
            atol=1e-14,
        )


@pytest.mark.parametrize(
    "q", [[0.3, 0.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.2, np.pi, 0.0]]
)
def test_singular_configurations_give_steepest_one_sided_ascent(q):
    q = np.asarray(q, dtype=float)
    arm = PlanarArm(np.linspace(0.3, 0.7, q.size))
    kin = arm.kinematics(q)
    assert kin.m < 1e-12
    assert np.all(np.isfinite(kin.Jm)) and np.linalg.norm(kin.Jm) > 0
    # Along Jm the one-sided derivative of m equals ||Jm||, and no unit direction does better.
    direction = kin.Jm / np.linalg.norm(kin.Jm)
    h = 1e-7
    slope = (arm.manipulability(q + h * direction) - kin.m) / h
    assert slope == pytest.approx(np.linalg.norm(kin.Jm), rel=1e-5)
    rng = np.random.default_rng(0)
    for d in rng.normal(size=(200, q.size)):
        d /= np.linalg.norm(d)
        assert (arm.manipulability(q + h * d) - kin.m) / h <= slope * (1 + 1e-5)


def test_two_link_stretched_gradient_is_the_limit_from_positive_q2():
    arm = PlanarArm([0.5, 0.4])
    np.testing.assert_allclose(arm.manipulability_jacobian([0.7, 0.0]), [0.0, 0.2], atol=1e-15)
    np.testing.assert_allclose(arm.manipulability_jacobian([0.7, 1e-9]), [0.0, 0.2], atol=1e-12)


def test_near_singular_values_stay_accurate():
    arm = PlanarArm([0.5, 0.4])
    for eps in [1e-4, 1e-8, 1e-12]:
        assert arm.manipulability([0.1, eps]) == pytest.approx(0.2 * np.sin(eps), rel=1e-10)
        assert arm.manipulability_jacobian([0.1, eps])[1] == pytest.approx(
            0.2 * np.cos(eps), rel=1e-12
        )


@pytest.mark.parametrize("lengths", [[1.0], [1.0, -0.5], [1.0, 0.0], [1.0, np.nan], [[1.0, 2.0]]])
def test_invalid_lengths_are_rejected(lengths):
    with pytest.raises(ScenarioError):
        PlanarArm(lengths)


def test_wrong_number_of_angles_is_rejected():
    with pytest.raises(ScenarioError, match="expected 3 joint angles"):
        PlanarArm([1, 1, 1]).forward([0.0, 0.0])


def test_reachable_annulus():
    assert PlanarArm([0.5, 0.4]).inner_reach == pytest.approx(0.1)
    assert PlanarArm([0.2, 0.6, 0.3]).inner_reach == pytest.approx(0.1)
    assert PlanarArm([0.3, 0.3]).inner_reach == 0.0
    assert PlanarArm([0.5, 0.4]).reach == pytest.approx(0.9)


@pytest.mark.parametrize("n", [2, 3, 5, 8])
def test_compiled_kinematics_match_the_numpy_references(n, rng):
    import reference

    arm = PlanarArm(rng.uniform(0.1, 1.0, n))
    configurations = [*rng.uniform(-3, 3, (20, n)), np.zeros(n), np.r_[0.3, np.zeros(n - 1)]]
    for q in configurations:
        kin = arm.kinematics(q)
        p, J, m, Jm = reference.kinematics(arm.lengths, q)
        np.testing.assert_allclose(kin.p, p, atol=1e-15)
        np.testing.assert_allclose(kin.J, J, atol=1e-15)
        assert kin.m == pytest.approx(m, abs=1e-15)
        np.testing.assert_allclose(kin.Jm, Jm, atol=1e-13)
