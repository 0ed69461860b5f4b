"""Scenarios: presets equal the brief's tables; every bad input is named precisely."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import emdm
from emdm import ScenarioError, load_scenario, scenario_from_dict
from emdm.core.loading import ScenarioWarning, parse_override


def test_task1_is_table_1_of_the_brief():
    sc = load_scenario("task1")
    np.testing.assert_array_equal(sc.arm.lengths, [0.2, 0.6, 0.3])
    np.testing.assert_array_equal(sc.arm.q_min, [-2.0] * 3)
    np.testing.assert_array_equal(sc.arm.q_max, [2.0] * 3)
    np.testing.assert_array_equal(sc.arm.qd_min, [-1.0] * 3)
    np.testing.assert_array_equal(sc.arm.qd_max, [1.0] * 3)
    np.testing.assert_allclose(sc.motion.q0, [0.0, math.pi / 6, math.pi / 6], rtol=0, atol=1e-16)
    np.testing.assert_array_equal(sc.motion.goal, [-0.7, 0.5])
    assert (sc.motion.dt, sc.motion.tolerance, sc.motion.max_time) == (0.05, 1e-3, 30.0)
    np.testing.assert_array_equal(sc.motion.kp, [1.0, 1.0])
    assert (sc.weights.effort, sc.weights.manipulability, sc.weights.slack) == (0.1, 5.0, 10.0)
    np.testing.assert_array_equal(sc.slack.min, [-1, -1])
    np.testing.assert_array_equal(sc.slack.max, [1, 1])
    np.testing.assert_array_equal(sc.damper.influence, [0.785398] * 3)
    np.testing.assert_array_equal(sc.damper.stop, [0.0872665] * 3)
    np.testing.assert_array_equal(sc.damper.gain, [1.0] * 3)
    assert sc.controller.on_infeasible == "scale" and sc.redundant and sc.max_steps == 600


def test_task2_is_table_2_of_the_brief():
    sc = load_scenario("task2")
    np.testing.assert_array_equal(sc.arm.lengths, [0.5, 0.4])
    np.testing.assert_array_equal(sc.arm.qd_max, [1.5, 1.5])
    np.testing.assert_array_equal(sc.arm.qd_min, [-1.5, -1.5])
    np.testing.assert_allclose(sc.motion.q0, [0.0, math.pi / 6], rtol=0, atol=1e-16)
    np.testing.assert_array_equal(sc.motion.goal, [-0.3, -0.6])
    assert (sc.weights.effort, sc.weights.manipulability, sc.weights.slack) == (0.1, 5.0, 10.0)
    assert not sc.redundant


def test_toml_round_trip(tmp_path):
    for name in ("task1", "task2"):
        sc = load_scenario(name)
        path = tmp_path / f"{name}.toml"
        path.write_text(sc.to_toml())
        again = load_scenario(path)
        assert again.to_dict() == sc.to_dict()


def test_scalars_expand_per_joint_and_defaults_apply():
    sc = scenario_from_dict(
        {
            "arm": {"lengths": [1, 1, 1, 1], "q_min": -3, "q_max": 3, "qd_min": -1, "qd_max": 1},
            "motion": {"q0": [0, 0.5, 0.5, 0.5], "goal": [1, 1]},
        }
    )
    assert sc.n == 4 and sc.arm.q_min.tolist() == [-3.0] * 4
    assert sc.motion.dt == 0.05 and sc.weights.manipulability == 5.0
    assert sc.damper.influence.tolist() == [0.785398] * 4


def test_overrides_revalidate():
    sc = load_scenario("task1", {"weights.effort": 0.5, "motion.goal": [0.1, 0.6]})
    assert sc.weights.effort == 0.5 and sc.motion.goal.tolist() == [0.1, 0.6]
    with pytest.raises(ScenarioError, match=r"weights\.effort: must be > 0"):
        sc.with_overrides({"weights.effort": 0})
    with pytest.raises(ScenarioError, match=r"--set: weights.effrt: unknown key"):
        sc.with_overrides({"weights.effrt": 1})


def test_parse_override():
    assert parse_override("weights.effort=0.2") == ("weights.effort", 0.2)
    assert parse_override("motion.goal=[0.1, 0.2]") == ("motion.goal", [0.1, 0.2])
    assert parse_override("controller.on_infeasible=slack") == ("controller.on_infeasible", "slack")
    with pytest.raises(ScenarioError, match=r"expected section\.key=value"):
        parse_override("weights.effort")


def test_scenarios_are_frozen():
    sc = load_scenario("task1")
    with pytest.raises(AttributeError):
        sc.name = "x"  # type: ignore[misc]
    with pytest.raises(ValueError):
        sc.arm.lengths[0] = 3.0


BAD = [
    ("arm.lengths", "[0.2, -0.6, 0.3]", "must be > 0"),
    ("arm.lengths", "[0.2]", "at least 2"),
    ("arm.lengths", '"long"', "at least 2"),
    ("arm.lengths", "[0.2, nan, 0.3]", "must be finite"),
    ("arm.q_min", "[-2.0, -2.0]", "must have 3 values"),
    ("arm.q_min", "3.0", "must be < arm.q_max"),
    ("arm.q_max", "inf", "must be finite"),
    ("arm.qd_min", "0.5", "must be < 0"),
    ("arm.qd_max", "-0.5", "must be > 0"),
    ("arm.qd_max", "true", "must be a number"),
    ("motion.q0", "[0.0, 2.5, 0.0]", "outside its limits"),
    ("motion.q0", "[0.0, 1.95, 0.0]", "inside the damper's stop zone"),
    ("motion.q0", "0.1", "must be a list of 3 numbers"),
    ("motion.goal", "[1.0]", "must have 2 values"),
    ("motion.dt", "0.0", "must be > 0"),
    ("motion.dt", '"fast"', "must be a number"),
    ("motion.kp", "-1.0", "must be > 0"),
    ("motion.tolerance", "-1e-3", "must be > 0"),
    ("motion.max_time", "0.01", "must be >= motion.dt"),
    ("weights.effort", "0.0", "must be > 0"),
    ("weights.manipulability", "-1.0", "must be >= 0"),
    ("weights.slack", "0.0", "must be > 0"),
    ("slack.min", "[1.0, 1.0]", "must be < slack.max"),
    ("damper.stop", "0.9", "must be < damper.influence"),
    ("damper.stop", "-0.1", "must be >= 0"),
    ("damper.gain", "0.0", "must be > 0"),
    ("controller.on_infeasible", '"ignore"', "must be one of scale, slack, error"),
    ("arm.colour", '"red"', "unknown key"),
]


def write_bad_scenario(path, key, value):
    """task1 as TOML with ``key`` set to the raw TOML text ``value``."""
    text = load_scenario("task1").to_toml()
    section, name = key.split(".")
    lines = text.splitlines()
    start = lines.index(f"[{section}]")
    for i in range(start + 1, len(lines)):
        if lines[i].startswith(f"{name} ="):
            lines[i] = f"{name} = {value}"
            break
    else:
        lines.insert(start + 1, f"{name} = {value}")
    path.write_text("\n".join(lines))


@pytest.mark.parametrize(("key", "value", "message"), BAD, ids=[f"{k}={v}" for k, v, _ in BAD])
def test_bad_values_name_file_key_and_problem(tmp_path, key, value, message):
    path = tmp_path / "bad.toml"
    write_bad_scenario(path, key, value)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    text = str(info.value)
    assert text.startswith(f"{path}: {key}"), text
    assert message in text and "\n" not in text


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("name = [", "not a valid TOML file"),
        ("[arm]\nlengths = [1, 1]\n[motor]\nx = 1", "motor: unknown section"),
        ("arm = 3", "arm: must be a table"),
        ("[motion]\nq0 = [0, 0]", "arm.lengths: is required"),
        (
            "[arm]\nlengths = [1, 1]\nq_min = -1\nq_max = 1\nqd_min = -1\nqd_max = 1\n"
            "[motion]\ngoal = [1, 0]",
            "motion.q0: is required",
        ),
    ],
)
def test_malformed_files(tmp_path, content, message):
    path = tmp_path / "bad.toml"
    path.write_text(content)
    with pytest.raises(ScenarioError, match=message):
        load_scenario(path)


def test_missing_file_and_binary_file(tmp_path):
    with pytest.raises(ScenarioError, match="no such scenario file"):
        load_scenario(tmp_path / "nope.toml")
    with pytest.raises(ScenarioError, match=r"presets: task1, task2"):
        load_scenario("task3")
    binary = tmp_path / "bin.toml"
    binary.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(ScenarioError, match=r"cannot be read|not a valid TOML"):
        load_scenario(binary)


def test_warnings_for_unreachable_goal_and_overshooting_damper():
    with pytest.warns(ScenarioWarning, match="outside the reachable annulus"):
        sc = load_scenario("task2", {"motion.goal": [2.0, 0.0]})
    assert any("reachable" in w for w in sc.warnings)
    with pytest.warns(ScenarioWarning, match="overshoot"):
        load_scenario("task2", {"motion.dt": 0.8, "motion.max_time": 2.0})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        load_scenario("task1")


@pytest.mark.parametrize("task", ["task1", "task2"])
def test_the_papers_stop_zone_argument_holds_for_both_tasks(task):
    """Section II says no joint enters its stop zone because dt < K_safe (i - s) and
    qd_max dt < i - s: both must hold for the brief's tasks, with no loader warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sc = load_scenario(task)
    room = np.asarray(sc.damper.influence) - np.asarray(sc.damper.stop)
    assert np.all(sc.motion.dt < np.asarray(sc.damper.gain) * room)
    top = np.maximum(np.abs(sc.arm.qd_min), np.abs(sc.arm.qd_max))
    assert np.all(top * sc.motion.dt < room)


def test_public_api_is_explicit():
    assert "simulate" in emdm.__all__ and "PlanarArm" in emdm.__all__
    for name in emdm.__all__:
        assert hasattr(emdm, name)


def test_strange_keys_stay_on_one_line():
    base = load_scenario("task1").to_dict()
    base["arm"]["bad\nkey"] = 1
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(base, source="s.toml")
    text = str(info.value)
    assert "\n" not in text and text.startswith("s.toml: arm.'bad\\nkey': unknown key")
    with pytest.raises(ScenarioError) as info:
        load_scenario("task1", {"motion.\tgoal": 1})
    assert str(info.value).isprintable()
