"""Monte-Carlo studies: reproducible draws, outcomes equal to the reference, files written."""

from __future__ import annotations

import json

import numpy as np

import emdm
from emdm.cli import main
from emdm.study import draw, run_study


def test_draws_are_reproducible_reachable_and_outside_stop_zones():
    sc = emdm.load_scenario("task1")
    q0s, goals = draw(sc, 200, seed=7)
    again_q0s, again_goals = draw(sc, 200, seed=7)
    assert np.array_equal(q0s, again_q0s) and np.array_equal(goals, again_goals)
    assert not np.array_equal(goals, draw(sc, 200, seed=8)[1])
    margin = np.minimum(q0s - sc.arm.q_min, sc.arm.q_max - q0s)
    assert margin.min() > sc.damper.stop.min()
    radius = np.hypot(goals[:, 0], goals[:, 1])
    assert radius.max() <= sc.planar_arm.reach + 1e-12


def test_study_outcomes_equal_single_runs():
    sc = emdm.load_scenario("task1", {"motion.max_time": 8.0})
    data = run_study(sc, 30, seed=3, progress=False)
    for name in ("C-EMDM", "UC-IVKC"):
        out = data["outcomes"][name]
        for r in (0, 11, 29):
            one = sc.with_overrides(
                {"motion.goal": list(data["goals"][r]), "motion.q0": list(data["q0s"][r])}
            )
            mt = emdm.metrics(emdm.simulate(one, name))
            assert out["reached"][r] == mt["reached"] and out["steps"][r] == mt["steps"]
            assert abs(out["mean_manipulability"][r] - mt["mean_manipulability"]) < 1e-12
    summary = data["controllers"]["UC-IVKC"]
    assert summary["success_rate"] == data["outcomes"]["UC-IVKC"]["reached"].mean()


def test_study_command(tmp_path, capsys):
    out = tmp_path / "study"
    assert main(["study", "task2", "--runs", "40", "--seed", "1", "--out", str(out)]) == 0
    data = json.loads((out / "study.json").read_text())
    assert data["runs"] == 40 and set(data["controllers"]) == set(emdm.CONTROLLERS)
    assert "C-EMDM over C-IVKC" in data["manipulability_gain"]
    runs = np.load(out / "runs.npz")
    assert runs["goals"].shape == (40, 2)
    assert (out / "workspace_maps.png").stat().st_size > 5000
    assert "success" in capsys.readouterr().out
    assert main(["study", "task2", "--runs", "0", "--out", str(tmp_path / "x")]) == 2
