"""Reliability: invariants under random and adversarial inputs, and a fuzzed scenario loader."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from conftest import reference_bounds
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import emdm
from emdm import NoSolution, ScenarioError, load_scenario, scenario_from_dict
from emdm.cli import main

CONTROLLERS = ["UC-IVKC", "C-IVKC", "UC-EMDM", "C-EMDM"]


@st.composite
def scenarios(draw: st.DrawFn) -> emdm.Scenario:
    """Random valid scenarios: 2 to 8 links, limits, starts, reachable goals, weights, gains."""
    n = draw(st.integers(2, 8))
    floats = st.floats(allow_nan=False, allow_infinity=False)
    lengths = [draw(floats.filter(lambda x: 0.05 <= x <= 1.0)) for _ in range(n)]
    q_lim = draw(st.floats(1.2, 3.1))
    qd_lim = draw(st.floats(0.2, 3.0))
    influence = draw(st.floats(0.3, 0.9))
    stop = draw(st.floats(0.0, 0.25))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    q0 = rng.uniform(-q_lim + stop + 1e-3, q_lim - stop - 1e-3, n)
    target = rng.uniform(-q_lim, q_lim, n)
    goal = emdm.PlanarArm(lengths).forward(target)
    data = {
        "name": "hypothesis",
        "arm": {
            "lengths": lengths,
            "q_min": -q_lim,
            "q_max": q_lim,
            "qd_min": -qd_lim,
            "qd_max": qd_lim,
        },
        "motion": {
            "q0": q0.tolist(),
            "goal": goal.tolist(),
            "dt": 0.05,
            "max_time": 1.5,
            "kp": draw(st.floats(0.2, 5.0)),
        },
        "weights": {
            "effort": draw(st.floats(1e-3, 10.0)),
            "manipulability": draw(st.floats(0.0, 100.0)),
            "slack": draw(st.floats(0.1, 100.0)),
        },
        "damper": {
            "influence": influence,
            "stop": min(stop, influence / 2),
            "gain": draw(st.floats(0.2, 5.0)),
        },
        "controller": {"on_infeasible": draw(st.sampled_from(["scale", "slack"]))},
    }
    return scenario_from_dict(data, source="hypothesis")


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scenarios())
def test_runs_hold_every_invariant(sc):
    overshoot = np.any(sc.motion.dt >= sc.damper.gain * (sc.damper.influence - sc.damper.stop))
    assert overshoot == any("overshoot" in w for w in sc.warnings)
    for name in CONTROLLERS:
        try:
            run = emdm.simulate(sc, name)
        except NoSolution as exc:
            # only an overshooting damper (warned about) can push a joint into its stop zone,
            # where the forced motion may conflict with the task: a clean, explained stop
            assert overshoot and name.startswith("C-") and "stop zone" in str(exc), exc
            continue
        for array in (run.q, run.qd, run.p, run.m, run.alpha, run.delta, run.effort):
            assert np.all(np.isfinite(array)), name
        assert run.kkt.max(initial=0.0) <= 1e-9 and run.bound_excess.max(initial=0.0) <= 1e-12
        if name.startswith("C-"):
            for k in range(run.steps):
                lo, hi = reference_bounds(sc, run.q[k])
                assert np.all(run.qd[k] >= lo - 1e-12) and np.all(run.qd[k] <= hi + 1e-12)
            if not overshoot:
                margin = np.minimum(run.q - sc.arm.q_min, sc.arm.q_max - run.q)
                assert np.all(margin >= sc.damper.stop - 1e-12), name
        again = emdm.simulate(sc, name)
        assert np.array_equal(again.q, run.q) and np.array_equal(again.qd, run.qd)


# ------------------------------------------------------------------------------ loader fuzzing
SECTION_KEYS = {s: list(keys) for s, keys in emdm.core.schema.SCHEMA.items()}
json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-(10**6), 10**6) | st.floats() | st.text(max_size=8),
    lambda children: (
        st.lists(children, max_size=5) | st.dictionaries(st.text(max_size=6), children, max_size=3)
    ),
    max_leaves=10,
)


@settings(max_examples=300, deadline=None)
@given(
    st.dictionaries(
        st.sampled_from([*SECTION_KEYS, "name", "extra"]),
        st.dictionaries(
            st.sampled_from([k for ks in SECTION_KEYS.values() for k in ks] + ["x"]),
            json_values,
            max_size=6,
        )
        | json_values,
        max_size=7,
    )
)
def test_fuzzed_scenario_data_gives_a_scenario_or_one_line_error(data):
    base = load_scenario("task1").to_dict()
    for section, value in data.items():
        if isinstance(value, dict) and isinstance(base.get(section), dict):
            base[section] = {**base[section], **value}
        else:
            base[section] = value
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            scenario_from_dict(base, source="fuzz")
    except ScenarioError as exc:
        assert str(exc).startswith("fuzz") and "\n" not in str(exc) and str(exc).isprintable()


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=200) | st.binary(max_size=200).map(lambda b: b.decode("latin-1")))
def test_fuzzed_files_give_a_scenario_or_one_line_error(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("fuzz") / "s.toml"
    path.write_text(text, encoding="utf-8", errors="surrogateescape")
    try:
        load_scenario(path)
    except ScenarioError as exc:
        assert str(exc).isprintable()  # one line, whatever the file held


# ------------------------------------------------------------------------------- adversarial
@pytest.mark.parametrize(
    ("goal", "reachable"),
    [
        ([0.9, 0.0], True),  # exactly on the outer boundary (stretched arm)
        ([0.0, 0.1], True),  # exactly on the inner boundary (folded arm)
        ([1.5, 0.5], False),  # beyond the workspace
        ([0.0, 0.0], False),  # at the base, inside the hole of the annulus
    ],
)
@pytest.mark.parametrize("controller", CONTROLLERS)
def test_goals_on_and_beyond_the_workspace_boundary(goal, reachable, controller):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sc = load_scenario("task2", {"motion.goal": goal, "motion.max_time": 6.0})
    assert bool(sc.warnings) != reachable
    run = emdm.simulate(sc, controller)
    assert np.all(np.isfinite(run.q)) and np.all(np.isfinite(run.qd))
    assert run.kkt.max(initial=0.0) <= 1e-9
    if not reachable:
        assert not run.reached


@pytest.mark.parametrize("weights", [(1e-8, 5.0), (1e6, 5.0), (0.1, 1e6), (0.1, 0.0), (0.1, 1e-9)])
@pytest.mark.parametrize("task", ["task1", "task2"])
def test_huge_and_tiny_weights(task, weights):
    sc = load_scenario(
        task,
        {
            "weights.effort": weights[0],
            "weights.manipulability": weights[1],
            "motion.max_time": 3.0,
        },
    )
    for controller in ("UC-EMDM", "C-EMDM"):
        run = emdm.simulate(sc, controller)
        assert np.all(np.isfinite(run.qd)) and run.kkt.max(initial=0.0) <= 1e-9


def test_slack_weight_as_the_error_vanishes():
    sc = load_scenario("task2", {"motion.tolerance": 1e-8, "motion.max_time": 40.0})
    run = emdm.simulate(sc, "C-EMDM")
    assert run.reached and run.error_norm[-1] < 1e-8
    w_slack = sc.weights.slack / run.error_norm[:-1]
    assert w_slack.max() > 1e8  # w_S = c_S / ||e|| grows without bound near the goal
    assert run.kkt.max() <= 1e-9  # and every command is still certified


def test_overshooting_damper_stops_cleanly_or_runs():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sc = load_scenario(
            "task1",
            {"motion.dt": 0.9, "motion.max_time": 9.0, "arm.qd_max": 5.0, "arm.qd_min": -5.0},
        )
    assert any("overshoot" in w for w in sc.warnings)
    try:
        run = emdm.simulate(sc, "C-EMDM")
    except NoSolution as exc:
        assert "step" in str(exc)
    else:
        assert np.all(np.isfinite(run.qd))


def test_command_line_never_shows_a_traceback_for_a_stopped_run(tmp_path, capsys):
    code = main(
        ["run", "task1", "--set", "controller.on_infeasible=error", "--out", str(tmp_path / "o")]
    )
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err and err.count("\n") == 1
    assert "C-IVKC at step 0" in err and "infeasible" in err
