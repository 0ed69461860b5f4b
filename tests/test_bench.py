"""The benchmark harness runs and reports every figure (no timing is asserted)."""

from __future__ import annotations

import json

import numpy as np

import emdm
from emdm.cli import main
from emdm.studies.bench import textbook_kinematics


def test_the_baseline_computes_the_same_kinematics(rng):
    for n in (2, 3, 5):
        arm = emdm.PlanarArm(rng.uniform(0.2, 1.0, n))
        for q in rng.uniform(-2, 2, (10, n)):
            p, J, m, Jm = textbook_kinematics(np.asarray(arm.lengths), q)
            kin = arm.kinematics(q)
            np.testing.assert_allclose(p, kin.p, atol=1e-14)
            np.testing.assert_allclose(J, kin.J, atol=1e-14)
            np.testing.assert_allclose(m, kin.m, atol=1e-12)
            np.testing.assert_allclose(Jm, kin.Jm, atol=1e-10)


def test_bench_quick_reports_every_figure(tmp_path, capsys):
    assert main(["bench", "--quick", "--out", str(tmp_path)]) == 0
    data = json.loads((tmp_path / "bench.json").read_text())
    per = data["per_step"]["seconds"]
    assert set(per) == {
        "per-step API (state_at, program_at, solve_chain)",
        "standard stack, daqp",
        "standard stack, quadprog",
        "emdm.simulate (full record, certified)",
    }
    for row in per.values():
        assert row["total"] > 0
    assert len(data["runs"]) == 8 and data["batch"]["steps"] > 0
    assert set(data["targets"]) == {
        "emdm.simulate task1 C-EMDM <= 5 us/step",
        "emdm.simulate vs the standard stack >= 20x",
        "batch >= 1.5e6 steps/s",
        "Panda pose C-EMDM <= 10 us/step",
        "Panda vs robotics-toolbox-python at its fastest >= 50x",
        "Panda batch >= 2e5 steps/s",
        "20 inequality rows: extra cost <= 1 us/step",
        "later process: kernels loaded from the cache <= 0.5 s",
    }  # (the quick benchmark does not time a first use on an empty cache)
    rows = data["rows"]
    assert rows["rows_per_step"] == 20 and rows["us_per_step"] > 0
    assert rows["max_command_difference"] <= 1e-12  # loose rows change no command
    spatial = data["spatial"]
    assert spatial["simulate_us_per_step"] > 0 and spatial["batch"]["steps"] > 0
    assert spatial["rtb_stack"]["failed_steps"] == 0 and spatial["ratio"] > 1
    assert spatial["rtb_stack"]["max_command_difference"] < 1e-9  # the same program, solved
    assert spatial["ratio_dh"] > spatial["ratio"]
    assert data["first_use"]["cache_load_s"] > 0
    table = (tmp_path / "bench.md").read_text()
    assert "| emdm.simulate (full record, certified) |" in table and "steps/s" in table
    assert "robotics-toolbox-python at its fastest (rtb.models.Panda()" in table
    assert "emdm.simulate" in capsys.readouterr().out
