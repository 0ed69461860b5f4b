"""SerialArm: pose, geometric Jacobian, Hessian, manipulability and its Jacobian of random 3-D
revolute chains in both DH conventions, against finite differences and robotics-toolbox-python."""

from __future__ import annotations

import numpy as np
import pytest

import emdm
from emdm import ScenarioError, SerialArm


def random_arm(rng: np.random.Generator, n: int, convention: str) -> SerialArm:
    dh = np.column_stack(
        (
            rng.uniform(-0.5, 0.5, n),
            rng.uniform(-np.pi, np.pi, n),
            rng.uniform(-0.5, 0.5, n),
            rng.uniform(-1.0, 1.0, n),
        )
    )
    tool = np.eye(4)
    c, s = np.cos(0.4), np.sin(0.4)
    tool[:3, :3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    tool[:3, 3] = rng.uniform(-0.1, 0.1, 3)
    return SerialArm(dh, convention, tool=tool)


CASES = [
    (n, conv, seed) for n in (1, 2, 3, 6, 7) for conv in ("standard", "modified") for seed in (0, 1)
]


def _vee(S: np.ndarray) -> np.ndarray:
    return np.array([S[2, 1] - S[1, 2], S[0, 2] - S[2, 0], S[1, 0] - S[0, 1]]) / 2


@pytest.mark.parametrize(("n", "convention", "seed"), CASES)
def test_derivatives_match_central_differences(n, convention, seed):
    rng = np.random.default_rng(seed)
    arm = random_arm(rng, n, convention)
    q = rng.uniform(-2.5, 2.5, n)
    h = 1e-6
    J, H = arm.jacobian(q), arm.hessian(q)
    R = arm.forward(q)[:3, :3]
    for i in range(n):
        e = np.zeros(n)
        e[i] = h
        plus, minus = arm.forward(q + e), arm.forward(q - e)
        np.testing.assert_allclose(J[:3, i], (plus[:3, 3] - minus[:3, 3]) / (2 * h), atol=1e-8)
        omega = _vee((plus[:3, :3] - minus[:3, :3]) / (2 * h) @ R.T)  # dR/dq R^T = [z]x
        np.testing.assert_allclose(J[3:, i], omega, atol=1e-8)
        dJ = (arm.jacobian(q + e) - arm.jacobian(q - e)) / (2 * h)
        np.testing.assert_allclose(H[i], dJ, atol=1e-8)
    for axes in ("all", "trans", "rot"):
        m, Jm = arm.manipulability_and_jacobian(q, axes)
        rows = {"all": slice(0, 6), "trans": slice(0, 3), "rot": slice(3, 6)}[axes]
        Ja = J[rows]
        expected = np.sqrt(max(np.linalg.det(Ja @ Ja.T), 0.0)) if Ja.shape[0] <= n else 0.0
        assert m == pytest.approx(expected, rel=1e-9, abs=1e-12)
        fd = [
            (
                arm.manipulability(q + h * np.eye(n)[i], axes)
                - arm.manipulability(q - h * np.eye(n)[i], axes)
            )
            / (2 * h)
            for i in range(n)
        ]
        np.testing.assert_allclose(Jm, fd, atol=1e-7)


@pytest.mark.parametrize("convention", ["standard", "modified"])
def test_equal_to_robotics_toolbox(convention):
    rtb = pytest.importorskip("roboticstoolbox")
    rng = np.random.default_rng(7)
    for n in (3, 6, 7):
        arm = random_arm(rng, n, convention)
        link = rtb.RevoluteDH if convention == "standard" else rtb.RevoluteMDH
        robot = rtb.DHRobot(
            [link(a=a, alpha=al, d=d, offset=o) for a, al, d, o in arm.dh], tool=arm.tool
        )
        for _ in range(5):
            q = rng.uniform(-np.pi, np.pi, n)
            np.testing.assert_allclose(arm.forward(q), robot.fkine(q).A, atol=1e-13)
            np.testing.assert_allclose(arm.jacobian(q), robot.jacob0(q), atol=1e-13)
            np.testing.assert_allclose(arm.hessian(q), robot.hessian0(q), atol=1e-13)
            for axes in ("all", "trans", "rot") if n >= 6 else ("trans", "rot"):
                assert arm.manipulability(q, axes) == pytest.approx(
                    robot.manipulability(q, axes=axes), rel=1e-12, abs=1e-14
                )
                np.testing.assert_allclose(
                    arm.manipulability_jacobian(q, axes),
                    robot.jacobm(q, axes=axes).ravel(),
                    atol=1e-12,
                )


def test_a_planar_chain_equals_planar_arm():
    """Three links in the plane (alpha = d = 0): the linear rows and m of the translational xy
    task are PlanarArm's."""
    lengths = [0.2, 0.6, 0.3]
    arm = SerialArm([[a, 0.0, 0.0, 0.0] for a in lengths])
    planar = emdm.PlanarArm(lengths)
    q = np.array([0.3, -0.7, 1.1])
    np.testing.assert_allclose(arm.forward(q)[:2, 3], planar.forward(q), atol=1e-15)
    np.testing.assert_allclose(arm.jacobian(q)[:2], planar.jacobian(q), atol=1e-15)
    np.testing.assert_allclose(arm.hessian(q)[:, :2], planar.hessian(q), atol=1e-15)


def test_singular_configurations_give_finite_values():
    arm = SerialArm([[0.5, 0.0, 0.0, 0.0], [0.4, 0.0, 0.0, 0.0], [0.3, np.pi / 2, 0.0, 0.0]])
    q = np.zeros(3)  # stretched: the translational Jacobian loses rank
    m, Jm = arm.manipulability_and_jacobian(q, "trans")
    assert m == pytest.approx(0.0, abs=1e-15) and np.all(np.isfinite(Jm))


def test_bad_input_is_one_clear_error():
    with pytest.raises(ScenarioError, match="dh"):
        SerialArm([[0.1, 0.0, 0.0]])
    with pytest.raises(ScenarioError, match="finite"):
        SerialArm([[np.nan, 0.0, 0.0, 0.0]])
    with pytest.raises(ScenarioError, match="convention"):
        SerialArm([[0.1, 0.0, 0.0, 0.0]], "craig")  # type: ignore[arg-type]
    with pytest.raises(ScenarioError, match="rigid"):
        SerialArm([[0.1, 0.0, 0.0, 0.0]], tool=np.diag([2.0, 1.0, 1.0, 1.0]))
    arm = SerialArm([[0.1, 0.0, 0.0, 0.0]] * 2)
    with pytest.raises(ScenarioError, match="2 joint values"):
        arm.forward([0.0])
    with pytest.raises(ScenarioError, match="axes"):
        arm.manipulability([0.0, 0.0], "xyz")  # type: ignore[arg-type]


@pytest.mark.parametrize("seed", range(4))
def test_accurate_next_to_the_ur5_wrist_singularity(seed):
    """Within 1e-3..1e-9 rad of the UR5's wrist singularity (q5 = 0), ``m`` equals ``|det J|``
    (LU of the square Jacobian, an independent and accurate reference) to 1e-8 relative down to
    1e-7 rad, and ``Jm`` equals central differences of ``|det J|``. The old Cholesky cut-off took
    rounding for a pivot there (``m`` off by 3e-2 at 1e-7 rad, by 40x at 1e-9 rad)."""
    arm = emdm.load_scenario("ur5").serial_arm
    rng = np.random.default_rng(seed)
    q = rng.uniform(-3.0, 3.0, 6)

    def mdet(x: np.ndarray) -> float:
        return float(abs(np.linalg.det(arm.jacobian(x))))

    for k in (3, 5, 7, 9):
        q[4] = 10.0**-k
        m, Jm = arm.manipulability_and_jacobian(q, "all")
        assert m == pytest.approx(mdet(q), rel=1e-8 if k <= 7 else 1e-5)
        h = q[4] * 1e-2
        fd = np.array([(mdet(q + h * e) - mdet(q - h * e)) / (2 * h) for e in np.eye(6)])
        np.testing.assert_allclose(Jm, fd, rtol=0, atol=(1e-7 if k <= 7 else 1e-4) * abs(fd[4]))


def test_near_singular_values_equal_robotics_toolbox():
    """Beside the UR5's wrist singularity rtb's ``manipulability`` (a determinant) stays accurate
    and agrees to 1e-8; its ``jacobm`` inverts ``J J^T`` and loses digits as cond(J)^2 grows, so
    it is compared only where that leaves it 1e-8 (``q5 >= 1e-3``; at 1e-7 rad it is 1e-2 off
    the central differences of test_accurate_next_to_the_ur5_wrist_singularity)."""
    rtb = pytest.importorskip("roboticstoolbox")
    robot = rtb.models.DH.UR5()
    arm = emdm.load_scenario("ur5").serial_arm
    rng = np.random.default_rng(5)
    for _ in range(4):
        q = rng.uniform(-3.0, 3.0, 6)
        for k in (1, 3, 5, 7):
            q[4] = 10.0**-k
            assert arm.manipulability(q) == pytest.approx(robot.manipulability(q), rel=1e-8)
            if k <= 3:
                np.testing.assert_allclose(
                    arm.manipulability_jacobian(q), robot.jacobm(q).ravel(), rtol=1e-8, atol=1e-12
                )


@pytest.mark.parametrize("preset", ["panda", "ur5"])
def test_state_is_pose_jacobian_and_manipulability_in_one_pass(preset, rng):
    """``state(q)``: the pose, the Jacobian, m and its gradient from one kinematics pass, the
    same values, bit for bit, as forward, jacobian and manipulability_and_jacobian each give."""
    arm = emdm.load_scenario(preset).serial_arm
    for q in rng.uniform(-2.0, 2.0, (5, arm.n)):
        T, J, m, Jm = arm.state(q)
        m_alone, Jm_alone = arm.manipulability_and_jacobian(q)
        assert np.array_equal(T, arm.forward(q)) and np.array_equal(J, arm.jacobian(q))
        assert m == m_alone and np.array_equal(Jm, Jm_alone)
    with pytest.raises(ScenarioError, match="joint values"):
        arm.state(np.zeros(arm.n + 1))
