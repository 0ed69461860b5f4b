"""URDF arms: the chain read from real robot descriptions and from random generated files equals
an independent numpy statement of URDF's semantics (tests/urdf_reference.py: complex steps for
the Hessian, 40 digits for the manipulability and its gradient) and Pinocchio, to 1e-12; the
URDF Panda equals the DH preset; scenarios name URDF robots; bad files are one-line errors."""

from __future__ import annotations

import importlib.metadata
import json
import math
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
import urdf_reference as ref

import emdm
from emdm import ScenarioError, SerialArm
from emdm.core.loading import load_scenario
from emdm.core.scenario import scenario_from_dict
from emdm.core.urdf import read_urdf

pin = pytest.importorskip("pinocchio")


def _shipped(package: str, tail: str) -> Path:
    """A file a package ships (nothing downloads)."""
    dist = importlib.metadata.distribution(package)
    hits = [f for f in dist.files or () if str(f).endswith(tail)]
    assert hits, f"{package} ships no {tail}"
    return Path(str(hits[0].locate()))


ERD = "example-robot-data"
ROBOTS = {  # name: (package, file, base_link, tip_link); None: the file's root or only leaf
    "panda": (ERD, "panda_description/urdf/panda.urdf", "panda_link0", "panda_link8"),
    "panda-tcp": (ERD, "panda_description/urdf/panda.urdf", None, "panda_hand_tcp"),
    "ur5": (ERD, "ur_description/urdf/ur5_robot.urdf", None, "tool0"),
    "ur10": (ERD, "ur_description/urdf/ur10_robot.urdf", None, "tool0"),
    "z1": (ERD, "z1_description/urdf/z1.urdf", None, None),
    "so100": (ERD, "so_arm_description/urdf/so100.urdf", None, None),
    "iiwa14": ("rtb-data", "kuka_lbr_iiwa/urdf/lbr_iiwa_14_r820.urdf", None, "tool0"),
    "irb140": ("rtb-data", "abb_irb140_description/urdf/irb140.urdf", None, "tool0"),
    "kr16": ("rtb-data", "kuka_kr16/urdf/kr16_2.urdf", None, "tool0"),
}


def robot(name: str) -> tuple[Path, str | None, str | None]:
    package, tail, base, tip = ROBOTS[name]
    return _shipped(package, tail), base, tip


def pinocchio_reference(path: Path, base: str, tip: str, names, q):
    """Pose of ``tip`` in ``base`` and the 6 x n Jacobian (linear rows first, base axes) at the
    tip's origin, by Pinocchio; the chain's joints take ``q``, every other joint 0."""
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    x = pin.neutral(model)
    columns = []
    for name, value in zip(names, q, strict=True):
        j = model.getJointId(name)
        joint = model.joints[j]
        if joint.nq == 2:  # continuous: cos, sin
            x[joint.idx_q : joint.idx_q + 2] = math.cos(value), math.sin(value)
        else:
            x[joint.idx_q] = value
        columns.append(joint.idx_v)
    pin.framesForwardKinematics(model, data, x)
    tip_id, base_id = model.getFrameId(tip), model.getFrameId(base)
    oMb, oMt = data.oMf[base_id], data.oMf[tip_id]
    J = pin.computeFrameJacobian(model, data, x, tip_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
    R = oMb.rotation.T
    J = np.vstack((R @ J[:3, columns], R @ J[3:, columns]))
    return (oMb.inverse() * oMt).homogeneous, J


def random_q(arm: SerialArm, rng: np.random.Generator) -> np.ndarray:
    return rng.uniform(-2.5, 2.5, arm.n) * np.where(arm.chain.prismatic, 0.1, 1.0)


@pytest.mark.parametrize("name", list(ROBOTS))
def test_robot_descriptions_equal_the_reference_and_pinocchio(name: str) -> None:
    path, base, tip = robot(name)
    read = read_urdf(path, base, tip)
    arm = SerialArm.from_chain(read.chain)
    joints = ref.chain(path, read.base_link, read.tip_link)
    assert [j.name for j in ref.moving(joints)] == list(read.chain.names)
    rng = np.random.default_rng(7)
    errors = np.zeros(6)
    for _ in range(5):
        q = random_q(arm, rng)
        T_ref, J_ref = ref.forward(joints, q)
        T_pin, J_pin = pinocchio_reference(path, read.base_link, read.tip_link, read.chain.names, q)
        H_ref = ref.hessian(joints, q)
        rows = slice(None) if arm.n >= 6 else slice(0, 3)
        axes = "all" if arm.n >= 6 else "trans"
        m, Jm = arm.manipulability_and_jacobian(q, axes)
        errors = np.maximum(
            errors,
            [
                np.abs(arm.forward(q) - T_ref).max(),
                np.abs(arm.jacobian(q) - J_ref).max(),
                np.abs(arm.forward(q) - T_pin).max(),
                np.abs(arm.jacobian(q) - J_pin).max(),
                np.abs(arm.hessian(q) - H_ref).max(),
                max(
                    abs(m - ref.manipulability(joints, q, rows)),
                    np.abs(Jm - ref.manipulability_gradient(joints, q, rows)).max(),
                ),
            ],
        )
    assert np.all(errors < 1e-12), dict(
        zip(("pose", "J", "pose pin", "J pin", "H", "m, Jm"), errors, strict=True)
    )


def test_urdf_panda_equals_the_dh_preset() -> None:
    path, base, tip = robot("panda")
    urdf = SerialArm.from_urdf(path, base_link=base, tip_link=tip)
    sc = load_scenario("panda")
    dh = sc.serial_arm
    rng = np.random.default_rng(3)
    for _ in range(10):
        q = rng.uniform(sc.arm.q_min, sc.arm.q_max)
        assert np.abs(urdf.forward(q) - dh.forward(q)).max() < 1e-12
        assert np.abs(urdf.jacobian(q) - dh.jacobian(q)).max() < 1e-12
        assert np.abs(urdf.hessian(q) - dh.hessian(q)).max() < 1e-12
        assert abs(urdf.manipulability(q) - dh.manipulability(q)) < 1e-12
        assert np.abs(urdf.manipulability_jacobian(q) - dh.manipulability_jacobian(q)).max() < 1e-12


def _rpy(rng: np.random.Generator) -> str:
    return " ".join(f"{v:.17g}" for v in rng.uniform(-math.pi, math.pi, 3))


def random_urdf(rng: np.random.Generator, n: int) -> str:
    """A chain of ``n`` moving joints (revolute, continuous, prismatic) with fixed joints between,
    rotated origins and axes that are not coordinate axes; a branch off the chain."""
    lines = ['<robot name="random">', '<link name="l0"/>']
    link = 0
    for i in range(n):
        if rng.random() < 0.5:  # a fixed joint first
            lines += [
                f'<link name="l{link + 1}"/>',
                f'<joint name="fixed{i}" type="fixed"><parent link="l{link}"/>'
                f'<child link="l{link + 1}"/><origin xyz="{_xyz(rng)}" rpy="{_rpy(rng)}"/></joint>',
            ]
            link += 1
        kind = rng.choice(["revolute", "continuous", "prismatic"], p=[0.5, 0.2, 0.3])
        axis = rng.normal(size=3) if rng.random() < 0.7 else np.eye(3)[rng.integers(3)]
        limit = '<limit lower="-1" upper="1.5" velocity="2" effort="1"/>'
        if kind == "continuous":
            limit = '<limit velocity="2" effort="1"/>'
        lines += [
            f'<link name="l{link + 1}"/>',
            f'<joint name="j{i}" type="{kind}"><parent link="l{link}"/><child link="l{link + 1}"/>'
            f'<origin xyz="{_xyz(rng)}" rpy="{_rpy(rng)}"/>'
            f'<axis xyz="{" ".join(f"{v:.17g}" for v in axis)}"/>'
            f"{limit}</joint>",
        ]
        link += 1
    lines += [
        f'<link name="tip"/><joint name="tip_joint" type="fixed"><parent link="l{link}"/>'
        f'<child link="tip"/><origin xyz="{_xyz(rng)}" rpy="{_rpy(rng)}"/></joint>',
        '<link name="side"/><joint name="side_joint" type="revolute"><parent link="l1"/>'
        '<child link="side"/><axis xyz="0 1 0"/>'
        '<limit lower="-1" upper="1" velocity="1" effort="1"/></joint>',
        "</robot>",
    ]
    return "\n".join(lines)


def _xyz(rng: np.random.Generator) -> str:
    return " ".join(f"{v:.17g}" for v in rng.uniform(-0.3, 0.3, 3))


def test_random_chains_with_prismatic_fixed_and_tilted_joints(tmp_path: Path) -> None:
    rng = np.random.default_rng(11)
    worst = np.zeros(6)
    for k in range(12):
        path = tmp_path / f"r{k}.urdf"
        path.write_text(random_urdf(rng, int(rng.integers(2, 8))))
        read = read_urdf(path, tip_link="tip")
        tool = np.eye(4)
        tool[:3, :3] = ref._rot(rng.normal(size=3), 0.7)
        tool[:3, 3] = rng.normal(size=3) * 0.1
        arm = SerialArm.from_chain(read.chain, tool)
        joints = ref.chain(path, "l0", "tip")
        for _ in range(3):
            q = random_q(arm, rng)
            T_ref, J_ref = ref.forward(joints, q, tool)
            T_pin, J_pin = pinocchio_reference(path, "l0", "tip", read.chain.names, q)
            worst = np.maximum(
                worst,
                [
                    np.abs(arm.forward(q) - T_ref).max(),
                    np.abs(arm.jacobian(q) - J_ref).max(),
                    np.abs(SerialArm.from_chain(read.chain).forward(q) - T_pin).max(),
                    np.abs(SerialArm.from_chain(read.chain).jacobian(q) - J_pin).max(),
                    np.abs(arm.hessian(q) - ref.hessian(joints, q, tool)).max(),
                    0.0  # with fewer joints than rows, m = 0 everywhere (not differentiable)
                    if arm.n < 3
                    else np.abs(
                        arm.manipulability_jacobian(q, "trans")
                        - ref.manipulability_gradient(joints, q, slice(0, 3), tool)
                    ).max(),
                ],
            )
    assert np.all(worst < 1e-12), worst


def test_hessian_of_a_prismatic_chain_by_finite_differences(tmp_path: Path) -> None:
    path = tmp_path / "p.urdf"
    path.write_text(random_urdf(np.random.default_rng(5), 6))
    arm = SerialArm.from_urdf(path, tip_link="tip")
    q = random_q(arm, np.random.default_rng(1))
    h = 1e-6
    for i in range(arm.n):
        e = np.eye(arm.n)[i] * h
        fd = (arm.jacobian(q + e) - arm.jacobian(q - e)) / (2 * h)
        assert np.abs(fd - arm.hessian(q)[i]).max() < 1e-8


def test_a_scenario_names_a_urdf_robot_and_runs_like_the_dh_preset(tmp_path: Path) -> None:
    path, _, _ = robot("panda")
    (tmp_path / "robot.urdf").write_text(path.read_text())
    dh = load_scenario("panda")
    data = dh.to_dict()
    absolute = str((tmp_path / "robot.urdf").resolve())
    data["arm"] = {"urdf": absolute, "base_link": "panda_link0", "tip_link": "panda_link8"}
    file = tmp_path / "panda.toml"  # the path is relative to the scenario file
    file.write_text(
        scenario_from_dict(data, source=str(file))
        .to_toml()
        .replace(str((tmp_path / "robot.urdf").resolve()), "robot.urdf")
    )
    file.write_text(
        "\n".join(
            line for line in file.read_text().splitlines() if not line.startswith(("q_", "qd_"))
        )
    )
    sc = load_scenario(file)  # limits from the file
    assert sc.spatial and sc.n == 7
    assert sc.arm.q_max[3] == pytest.approx(-0.0698)
    assert sc.arm.qd_max[0] == pytest.approx(2.175)
    same = dh.with_overrides(
        {f"arm.{k}": getattr(sc.arm, k).tolist() for k in ("q_min", "q_max", "qd_min", "qd_max")}
    )
    for ctrl in ("C-EMDM", "UC-IVKC", "C-IVKC"):
        a, b = emdm.simulate(sc, ctrl), emdm.simulate(same, ctrl)
        assert a.q.shape == b.q.shape
        assert np.abs(a.q - b.q).max() < 1e-9
    again = scenario_from_dict(tomllib.loads(sc.to_toml()), source="copy")
    assert np.array_equal(again.arm.q_min, sc.arm.q_min)
    assert again.arm.urdf == str((tmp_path / "robot.urdf").resolve())


def _write(tmp_path: Path, text: str, name: str = "bad.urdf") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


LINK = '<link name="{}"/>'
JOINT = (
    '<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
    '<axis xyz="{axis}"/>{limit}</joint>'
)
LIMIT = '<limit lower="{lo}" upper="{hi}" velocity="1" effort="1"/>'


def _robot(*joints: tuple[str, str, str, str], links=None, axis="0 0 1", lo=-1, hi=1) -> str:
    names = links or sorted({j[2] for j in joints} | {j[3] for j in joints})
    body = [LINK.format(n) for n in names]
    for name, kind, parent, child in joints:
        limit = LIMIT.format(lo=lo, hi=hi) if kind in ("revolute", "prismatic") else ""
        if kind == "continuous":
            limit = '<limit velocity="1" effort="1"/>'
        body.append(
            JOINT.format(name=name, kind=kind, parent=parent, child=child, axis=axis, limit=limit)
        )
    return "<robot name='r'>" + "".join(body) + "</robot>"


@pytest.mark.parametrize(
    ("text", "tip", "message"),
    [
        ("<robot><link name='a'>", None, "not a well-formed XML file"),
        (
            _robot(("j1", "revolute", "a", "b"), ("j2", "revolute", "a", "c")),
            None,
            "branches at 'a'",
        ),
        (
            _robot(("j1", "revolute", "a", "b"), ("j2", "revolute", "b", "a")),
            None,
            "two parent joints|no root link",
        ),
        (_robot(("j1", "floating", "a", "b")), None, "is floating"),
        (_robot(("j1", "planar", "a", "b")), None, "is planar"),
        (_robot(("j1", "revolute", "a", "b"), lo=1, hi=-1), None, "inverted limits"),
        (_robot(("j1", "revolute", "a", "b"), axis="0 0 0"), None, "axis of length 0"),
        (_robot(("j1", "fixed", "a", "b")), None, "no moving joint"),
        (_robot(("j1", "revolute", "a", "b")), "nowhere", "no link 'nowhere'"),
        (
            _robot(("j1", "revolute", "a", "b"), ("j2", "revolute", "b", "c"))[:-8]
            + '<joint name="j3" type="revolute"><parent link="c"/><child link="d"/>'
            '<mimic joint="j1"/><limit lower="-1" upper="1" velocity="1"/></joint>'
            '<link name="d"/></robot>',
            "d",
            "mimic",
        ),
    ],
)
def test_bad_files_are_one_line_errors(tmp_path: Path, text: str, tip, message: str) -> None:
    path = _write(tmp_path, text)
    with pytest.raises(ScenarioError, match=message) as caught:
        read_urdf(path, tip_link=tip)
    assert "\n" not in str(caught.value)


def test_missing_file_and_continuous_limits_in_a_scenario(tmp_path: Path) -> None:
    base = {"motion": {"q0": [0.0, 0.0], "goal": [0.1, 0.0, 0.0]}}
    with pytest.raises(ScenarioError, match="no such URDF file"):
        scenario_from_dict({**base, "arm": {"urdf": str(tmp_path / "none.urdf")}})
    path = _write(
        tmp_path,
        _robot(("j1", "continuous", "a", "b"), ("j2", "revolute", "b", "c")),
        "c.urdf",
    )
    data = {"motion": {**base["motion"], "task": "position"}, "arm": {"urdf": str(path)}}
    with pytest.raises(ScenarioError, match=r"arm\.q_min: is required: the file gives none for j1"):
        scenario_from_dict(data)
    data["arm"].update(q_min=-3.0, q_max=3.0)
    sc = scenario_from_dict(data)
    assert sc.n == 2 and sc.arm.qd_max.tolist() == [1.0, 1.0]
    with pytest.raises(ScenarioError, match=r"arm\.dh"):
        scenario_from_dict({**data, "arm": {**data["arm"], "dh": [[0, 0, 0, 0]] * 2}})


def test_the_command_line_says_one_line_and_exits_2(tmp_path: Path) -> None:
    bad = _write(tmp_path, "<robot><link", "broken.urdf")
    scenario = tmp_path / "s.toml"
    scenario.write_text(
        f'[arm]\nurdf = "{bad.name}"\n[motion]\ntask = "position"\nq0 = [0.0]\ngoal = [0.1, 0, 0]\n'
    )
    proc = subprocess.run(
        [sys.executable, "-m", "emdm.cli", "run", str(scenario)], capture_output=True, text=True
    )
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "well-formed" in proc.stderr


TAIL = ("--trials", "4", "--json")


def test_a_urdf_file_is_a_template_scenario_and_every_command_takes_it(tmp_path: Path) -> None:
    path, _, _ = robot("iiwa14")
    with pytest.raises(ScenarioError, match=r"tip_link: is needed: the tree branches"):
        load_scenario(path)
    sc = load_scenario(path, {"arm.tip_link": "tool0", "motion.max_time": 12.0})
    assert sc.n == 7 and sc.motion.task == "pose" and sc.motion.max_time == 12.0
    arm = sc.serial_arm
    assert arm.manipulability(sc.motion.q0) > 0.01  # not the straight, singular zero
    run = emdm.simulate(sc, "C-EMDM")
    assert run.reached
    file = tmp_path / "iiwa.toml"
    file.write_text(sc.to_toml())
    proc = subprocess.run(
        [sys.executable, "-m", "emdm.cli", "mmc", "--protocol", "emdm", "--arm", str(file), *TAIL],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stderr
    assert set(json.loads(proc.stdout)["results"][str(file)]) == {"RRMC", "PARK", "MMC", "C-EMDM"}
    batch = emdm.simulate_batch(sc, "C-EMDM", goals=np.tile(sc.motion.goal, (3, 1)))
    assert batch.reached.all()


def test_a_template_for_fewer_than_six_joints_measures_the_rows_it_tracks() -> None:
    """A position task's manipulability is that of the three linear rows: with all six, a
    five-joint arm's m is 0 on every step (found by the example notebooks)."""
    path, _, _ = robot("so100")
    sc = load_scenario(path, {"arm.tip_link": "gripper"})  # the arm without its jaw: 5 joints
    assert sc.n == 5 and sc.motion.task == "position" and sc.motion.axes == "trans"
    run = emdm.simulate(sc, "C-EMDM")
    assert run.reached and run.m.min() > 0


def test_obstacles_need_revolute_joints(tmp_path: Path) -> None:
    path = _write(
        tmp_path, _robot(("j1", "revolute", "a", "b"), ("j2", "prismatic", "b", "c")), "p.urdf"
    )
    data = {
        "arm": {"urdf": str(path)},
        "motion": {"task": "position", "q0": [0.0, 0.0], "goal": [0.0, 0.0, 0.1]},
        "obstacles": [{"shape": "sphere", "center": [1.0, 1.0, 1.0], "radius": 0.1}],
    }
    with pytest.raises(ScenarioError, match="j2 is prismatic"):
        scenario_from_dict(data)
    del data["obstacles"]
    assert scenario_from_dict(data).serial_arm.chain.prismatic.tolist() == [False, True]


def test_the_urdf_panda_goes_around_obstacles() -> None:
    """The URDF's polyline has joint 7's origin 0.107 m before the flange, where the DH frame 7 sits
    at the flange: the links differ, so the runs do too, and both stay outside the stop distance."""
    path, base, tip = robot("panda")
    dh = load_scenario("panda-obstacles")
    data = dh.to_dict()
    data["arm"] = {"urdf": str(path), "base_link": base, "tip_link": tip}
    urdf = scenario_from_dict(data, source="urdf")
    stop = urdf.obstacle_damper.stop
    for ctrl in ("C-EMDM", "NEO"):
        run = emdm.simulate(urdf, ctrl)
        assert run.reached and run.clearance.min() >= stop - 1e-12
    assert emdm.simulate(urdf, "MMC").clearance.min() < stop  # the blind baseline enters it
