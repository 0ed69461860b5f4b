"""The command line end to end: outputs as specified, bad input rejected, results never lost."""

from __future__ import annotations

import argparse
import csv
import json
import math
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import assert_step_optimal, reference_bounds
from test_scenario import BAD, write_bad_scenario

import emdm
from emdm.cli import main

CONTROLLERS = ["UC-IVKC", "C-IVKC", "UC-EMDM", "C-EMDM"]


def read_csv(path: Path) -> tuple[list[str], list[dict[str, str]]]:
    with path.open() as handle:
        reader = csv.DictReader(handle)
        return list(reader.fieldnames or []), list(reader)


def snapshot(folder: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()
    }


@pytest.fixture(scope="module")
def task_outputs(tmp_path_factory):
    out = {}
    for task in ("task1", "task2"):
        folder = tmp_path_factory.mktemp(task)
        assert main(["run", task, "--out", str(folder)]) == 0
        out[task] = folder
    return out


@pytest.mark.parametrize("task", ["task1", "task2"])
def test_run_writes_metrics_and_trajectories(task_outputs, task):
    folder = task_outputs[task]
    data = json.loads((folder / "metrics.json").read_text())
    assert data["scenario"]["name"] == task
    assert set(data["controllers"]) == set(CONTROLLERS)
    required = {
        "reached",
        "steps",
        "time_to_goal",
        "final_error",
        "min_manipulability",
        "mean_manipulability",
        "final_manipulability",
        "total_effort",
        "max_abs_qd",
        "min_joint_margin",
        "scaled_steps",
        "fallback_steps",
    }
    sc = emdm.load_scenario(task)
    n = sc.n
    header_expected = [
        "t",
        *[f"q{i}" for i in range(1, n + 1)],
        *[f"qd{i}" for i in range(1, n + 1)],
        "x",
        "y",
        "ex",
        "ey",
        "vx",
        "vy",
        "m",
        "effort",
        "manip_rate",
        "alpha",
        "delta_x",
        "delta_y",
        "status",
        "solver",
        "iterations",
        "solve_time",
    ]
    for name, mt in data["controllers"].items():
        assert required <= set(mt)
        header, rows = read_csv(folder / "trajectories" / f"{name}.csv")
        assert header == header_expected
        assert len(rows) == mt["steps"] + 1
        assert all(rows[-1][f"qd{i}"] == "" for i in range(1, n + 1)) and rows[-1]["status"] == ""
        # full precision: the CSV reproduces the simulation bit for bit
        run = emdm.simulate(sc, name)
        q = np.array([[float(r[f"q{i}"]) for i in range(1, n + 1)] for r in rows])
        assert np.array_equal(q, run.q)
        assert mt["reached"] == run.reached and mt["steps"] == run.steps
        if mt["reached"]:
            assert mt["time_to_goal"] == pytest.approx(float(rows[-1]["t"]))
            assert mt["final_error"] < sc.motion.tolerance
        else:
            assert mt["time_to_goal"] is None
        assert mt["total_effort"] == pytest.approx(
            sum(float(r["effort"]) for r in rows[:-1]) * sc.motion.dt, rel=1e-12
        )
        assert mt["min_manipulability"] == pytest.approx(
            min(float(r["m"]) for r in rows), rel=1e-12
        )
        assert mt["scaled_steps"] == sum(float(r["alpha"]) < 1 for r in rows[:-1])


def test_summary_table_is_printed(capsys, tmp_path):
    assert main(["run", "task2", "--controller", "C-EMDM", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "C-EMDM" in out and "reached" in out and "UC-IVKC" not in out


def test_set_overrides_reach_the_run(tmp_path):
    assert (
        main(
            [
                "run",
                "task1",
                "--controller",
                "UC-EMDM",
                "--set",
                "weights.manipulability=0",
                "--out",
                str(tmp_path),
            ]
        )
        == 0
    )
    data = json.loads((tmp_path / "metrics.json").read_text())
    assert data["scenario"]["weights"]["manipulability"] == 0.0


def test_solver_choice_and_fallback_are_recorded(tmp_path):
    assert (
        main(
            [
                "run",
                "task2",
                "--controller",
                "C-EMDM",
                "--solver",
                "daqp",
                "--fallback",
                "quadprog",
                "--out",
                str(tmp_path),
            ]
        )
        == 0
    )
    _, rows = read_csv(tmp_path / "trajectories" / "C-EMDM.csv")
    assert {r["solver"] for r in rows[:-1]} == {"daqp"}
    data = json.loads((tmp_path / "metrics.json").read_text())
    assert data["solver"] == "daqp" and data["fallback"] == ["quadprog"]


BAD_ARGS = [
    (["run", "task9"], "no such scenario file"),
    (["run", "task1", "--controller", "X"], "unknown controller"),
    (["run", "task1", "--solver", "nope"], "unknown solver"),
    (["run", "task1", "--set", "weights.effort=-1"], "weights.effort: must be > 0"),
    (["run", "task1", "--set", "arm.lengths=[0.2, 0.6]"], "arm.lengths: gives 2 joints"),
    (["run", "task1", "--set", "bogus"], "expected section.key=value"),
    (["run", "task1", "--set", "motion.q0=[0, 3, 0]"], "motion.q0"),
    (["run", "task1", "--set", "damper.stop=1.0"], "damper.stop: must be < damper.influence"),
    (["run", "task1", "--set", "motion.goal=[nan, 0]"], "motion.goal[0]: must be finite"),
]


@pytest.mark.parametrize(("args", "message"), BAD_ARGS, ids=[" ".join(a) for a, _ in BAD_ARGS])
def test_bad_input_exit_2_one_line_nothing_written(tmp_path, capsys, args, message):
    out = tmp_path / "out"
    assert main([*args, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and "Traceback" not in err
    assert not out.exists() and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("key", "value", "message"), BAD, ids=[f"{k}={v}" for k, v, _ in BAD])
def test_every_bad_scenario_value_exits_2_through_the_cli(tmp_path, capsys, key, value, message):
    path = tmp_path / "bad.toml"
    write_bad_scenario(path, key, value)
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"emdm: error: {path}: {key}") and message in err
    assert err.count("\n") == 1 and not out.exists()


def test_bad_file_names_the_file(tmp_path, capsys):
    bad = tmp_path / "arm.toml"
    bad.write_text(
        emdm.load_scenario("task1").to_toml().replace("lengths = [0.2,", "lengths = [-0.2,")
    )
    assert main(["run", str(bad), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f"{bad}: arm.lengths: must be > 0" in err


def test_bad_input_keeps_previous_results(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", "task2", "--controller", "C-EMDM", "--out", str(out)]) == 0
    before = snapshot(out)
    for args in BAD_ARGS:
        assert main([*args[0], "--out", str(out)]) == 2
    assert snapshot(out) == before
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # no staging folder left behind


def test_run_stopped_part_way_keeps_what_finished(tmp_path, capsys):
    """C- controllers stop at step 0 (task 1's start is infeasible, on_infeasible = error): the
    UC ones finish; all is written, the stop named in one line, exit status 2."""
    out = tmp_path / "out"
    code = main(["run", "task1", "--set", "controller.on_infeasible=error", "--out", str(out)])
    assert code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("emdm: error: run stopped: C-IVKC at step 0:")
    assert "infeasible" in err and "C-EMDM at step 0" in err
    assert "UC-IVKC, UC-EMDM finished" in err and str(out) in err
    data = json.loads((out / "metrics.json").read_text())
    assert (
        data["controllers"]["UC-EMDM"]["reached"]
        and "stopped" not in data["controllers"]["UC-EMDM"]
    )
    stopped = data["controllers"]["C-EMDM"]["stopped"]
    assert stopped["step"] == 0 and "infeasible" in stopped["reason"]
    _, rows = read_csv(out / "trajectories" / "C-EMDM.csv")
    assert len(rows) == 1  # the partial run: the state it stopped at
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_interrupted_run_keeps_previous_results(tmp_path, monkeypatch, capsys):
    out = tmp_path / "out"
    assert main(["run", "task2", "--controller", "C-EMDM", "--out", str(out)]) == 0
    before = snapshot(out)

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr("emdm.outputs.records.write_json", interrupted)
    assert main(["run", "task2", "--controller", "C-EMDM", "--out", str(out)]) == 130
    assert snapshot(out) == before
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_console_script_entry_point(tmp_path):
    exe = Path(sys.executable).with_name("emdm")
    command = [str(exe)] if exe.exists() else [sys.executable, "-m", "emdm.cli"]
    ok = subprocess.run(
        [*command, "run", "task2", "--controller", "UC-IVKC", "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert ok.returncode == 0, ok.stderr
    bad = subprocess.run(
        [*command, "run", "task2", "--set", "arm.qd_max=-1"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1
    helped = subprocess.run([*command, "--help"], capture_output=True, text=True, check=False)
    assert helped.returncode == 0 and "run" in helped.stdout


def test_scenario_and_list_commands(capsys):
    assert main(["scenario", "task2", "--set", "weights.effort=0.3"]) == 0
    text = capsys.readouterr().out
    assert "effort = 0.3" in text and "[damper]" in text
    assert main(["list"]) == 0
    assert "active-set" in capsys.readouterr().out


# --------------------------------------------------------------------- randomised scenarios
def random_scenario(rng, index: int) -> emdm.Scenario:
    n = 2 + index % 6
    lengths = rng.uniform(0.15, 0.8, n)
    q_lim = rng.uniform(1.5, 3.0, n)
    qd_lim = rng.uniform(0.5, 2.0, n)
    stop, influence = 0.08, 0.6
    q0 = rng.uniform(-q_lim + influence, q_lim - influence)
    target = rng.uniform(-q_lim + influence, q_lim - influence)
    goal = emdm.PlanarArm(lengths).forward(target)
    base = emdm.load_scenario("task1").to_dict()
    base.update(name=f"random{index}")
    base["arm"] = {
        "lengths": lengths.tolist(),
        "q_min": (-q_lim).tolist(),
        "q_max": q_lim.tolist(),
        "qd_min": (-qd_lim).tolist(),
        "qd_max": qd_lim.tolist(),
    }
    base["motion"].update(
        q0=q0.tolist(), goal=goal.tolist(), max_time=6.0, kp=float(rng.uniform(0.5, 2.0))
    )
    base["weights"] = {
        "effort": float(10 ** rng.uniform(-2, 0)),
        "manipulability": float(10 ** rng.uniform(-1, 1)),
        "slack": float(rng.uniform(1, 20)),
    }
    base["damper"] = {"influence": influence, "stop": stop, "gain": float(rng.uniform(0.5, 2.0))}
    return emdm.scenario_from_dict(base, source=f"random{index}")


def test_random_scenarios_through_the_command_line(tmp_path):
    rng = np.random.default_rng(2024)
    checked = 0
    for index in range(12):
        sc = random_scenario(rng, index)
        path = tmp_path / f"random{index}.toml"
        path.write_text(sc.to_toml())
        out = tmp_path / f"out{index}"
        assert main(["run", str(path), "--out", str(out)]) == 0
        data = json.loads((out / "metrics.json").read_text())
        for name in CONTROLLERS:
            mt = data["controllers"][name]
            assert mt["max_kkt_residual"] <= 1e-9 and mt["max_bound_excess"] <= 1e-12
            _, rows = read_csv(out / "trajectories" / f"{name}.csv")
            n = sc.n
            for row in rows[:-1]:
                q = np.array([float(row[f"q{i}"]) for i in range(1, n + 1)])
                qd = np.array([float(row[f"qd{i}"]) for i in range(1, n + 1)])
                delta = np.array([float(row["delta_x"]), float(row["delta_y"])])
                assert_step_optimal(sc, name, q, qd, delta, float(row["alpha"]))
                if name.startswith("C-"):
                    lo, hi = reference_bounds(sc, q)
                    assert np.all(qd >= lo - 1e-12) and np.all(qd <= hi + 1e-12)
                    margin = np.minimum(q - sc.arm.q_min, sc.arm.q_max - q)
                    assert margin.min() > sc.damper.stop.min()
                checked += 1
            assert all(math.isfinite(float(r["m"])) for r in rows)
        shutil.rmtree(out)
    assert checked > 1000


@pytest.mark.parametrize(
    "args",
    [
        ["run"],
        ["run", "task1", "--bogus"],
        ["frobnicate"],
        ["animate", "task1", "--pair", "X"],
        ["study", "task1", "--runs", "x"],
    ],
)
def test_argument_errors_are_one_line(args, capsys):
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "error:" in err and "usage" not in err


# ------------------------------------------------------------- meaningless values, their range
MEANINGLESS = [
    (["run", "task1", "--set", "motion.dt=" + "1" * 400], "motion.dt: must be finite"),
    (["run", "task1", "--set", "motion.dt=" + "1" * 5000], "motion.dt: must be a number"),
    (["run", "task1", "--set", "weights.effort=1e-300"], "weights.effort: must be between 1e-08"),
    (["run", "task1", "--set", "motion.kp=1e6"], "motion.kp: must be < 2 / motion.dt = 40"),
    (["run", "task1", "--set", "arm.lengths=[1e200, 1e200, 1e200]"], "arm.lengths: must be"),
    (["run", "task1", "--set", "motion.max_time=1e300"], "motion.max_time: must be at most"),
    (
        ["run", "task1", "--set", "weights.effort=1e-8", "--set", "weights.manipulability=1e3"],
        "weights.manipulability: must be at most 1e+10 x weights.effort",
    ),
    (["run", "task1", "--set", "damper.gain=1e300"], "damper.gain: must be between"),
    (["run", "task1", "--controller", ","], "--controller must name at least one"),
    (["run", "task1", "--solver", "nope"], "unknown solver 'nope'"),
    (["study", "task1", "--runs", "10", "--seed", "-1"], "--seed must be between 0 and"),
    (["study", "task1", "--runs", "0"], "--runs must be between 1"),
    (["study", "task1", "--chunk", "0"], "--chunk must be between 1"),
    (["study", "task1", "--workers", "0"], "--workers must be between 1"),
    (["pareto", "task1", "--grid", "0"], "--grid must be between 2"),
    (["pareto", "task1", "--controller", "C-IVKC"], "--controller must weigh manipulability"),
    (["animate", "task2", "--speedup", "nan"], "--speedup must be > 0"),
    (["animate", "task2", "--speedup", "inf"], "--speedup must be > 0"),
    (["animate", "task2", "--speedup", "0.123457", "--no-mp4"], "no frame duration"),
    (["animate", "task2", "--controller", "C-EMDM", "--pair", "UC"], "not both"),
    (["solvers", "task2", "--solvers", ","], "--solvers must name at least one solver"),
    (["solvers", "task2", "--solver", "daqp,,quadprog"], "empty solver name"),
    (["solvers", "task2", "--repeats", "0"], "--repeats must be between 1"),
    (["solvers", "task2", "--sample", "-3"], "--sample must be >= 0"),
    (["solvers", "task2", "--workers", "0"], "--workers must be between 1"),
    (["report", "--workers", "0"], "--workers must be between 1"),
    (["scenario", "task1", "--out", "x"], "unrecognized arguments: --out"),
    (["list", "--out", "x"], "unrecognized arguments: --out"),
]


@pytest.mark.parametrize(
    ("args", "message"), MEANINGLESS, ids=[" ".join(a)[:60] for a, _ in MEANINGLESS]
)
def test_meaningless_values_are_refused_with_their_range(
    tmp_path, monkeypatch, capsys, args, message
):
    monkeypatch.chdir(tmp_path)  # the default --out would be under results/ here

    def no_work(*args, **kwargs):
        raise AssertionError("work started before the arguments were checked")

    monkeypatch.setattr(sys.modules["emdm.cli.main"], "simulate", no_work)
    monkeypatch.setattr("emdm.studies.montecarlo.run_sweep", no_work)
    assert main(args) == 2
    err = capsys.readouterr().err
    assert message in err, err
    assert err.count("\n") == 1 and "internal error" not in err
    assert list(tmp_path.iterdir()) == []


def test_long_runs_allocate_what_they_use(tmp_path):
    """max_time = 1e8 s (2e9 steps): the goal is reached at 8 s, memory follows the run."""
    import resource

    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    out = tmp_path / "o"
    args = ["run", "task1", "--controller", "C-EMDM", "--set", "motion.max_time=1e8"]
    assert main([*args, "--out", str(out)]) == 0
    grown_kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before
    assert grown_kib < 200_000  # not the 15-45 GiB of max_time / dt up front
    assert json.loads((out / "metrics.json").read_text())["controllers"]["C-EMDM"]["reached"]


def test_a_truncated_run_folder_is_named(tmp_path, capsys):
    run_dir = tmp_path / "r"
    assert main(["run", "task2", "--controller", "C-EMDM", "--out", str(run_dir)]) == 0
    csv_file = run_dir / "trajectories" / "C-EMDM.csv"
    text = csv_file.read_bytes()
    for cut in (len(text) // 2, text.rindex(b"\n", 0, len(text) // 2) + 1):  # mid-row, at a row
        csv_file.write_bytes(text[:cut])
        capsys.readouterr()
        assert main(["plot", str(run_dir), "--out", str(tmp_path / "f")]) == 2
        err = capsys.readouterr().err
        assert f"{csv_file}: not a complete run record" in err and err.count("\n") == 1
    (run_dir / "metrics.json").write_text("{")
    assert main(["plot", str(run_dir), "--out", str(tmp_path / "f")]) == 2
    assert "not a metrics.json written by emdm run" in capsys.readouterr().err
    assert not (tmp_path / "f").exists()


def test_missing_ffmpeg_is_one_line_before_any_work(tmp_path, monkeypatch, capsys):
    imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg")

    def missing():
        raise RuntimeError("No ffmpeg exe could be found")

    monkeypatch.setattr(imageio_ffmpeg, "get_ffmpeg_exe", missing)
    assert main(["animate", "task2", "--out", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err
    assert "ffmpeg cannot be found" in err and "--no-mp4" in err and err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


def test_scenario_names_never_leave_the_results_folder(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    args = ["run", "task2", "--controller", "UC-IVKC", "--set", "name=../../escape"]
    assert main(args) == 0
    assert [p.relative_to(tmp_path).as_posix() for p in tmp_path.iterdir()] == ["results"]
    assert (tmp_path / "results" / "escape" / "metrics.json").is_file()


def test_preset_names_are_case_insensitive(capsys):
    assert main(["scenario", "TASK1"]) == 0
    assert 'name = "task1"' in capsys.readouterr().out


def test_controllers_repeat_and_deduplicate(tmp_path, capsys):
    out = tmp_path / "o"
    args = ["run", "task2", "--controller", "c-emdm", "--controller", "C-EMDM,uc-ivkc"]
    assert main([*args, "--out", str(out)]) == 0
    data = json.loads((out / "metrics.json").read_text())
    assert list(data["controllers"]) == ["C-EMDM", "UC-IVKC"]


def test_solver_chain_from_repeated_solvers(tmp_path):
    out = tmp_path / "o"
    args = ["run", "task2", "--controller", "C-EMDM", "--solver", "daqp", "--solver", "quadprog"]
    assert main([*args, "--fallback", "none", "--out", str(out)]) == 0
    data = json.loads((out / "metrics.json").read_text())
    assert data["solver"] == "daqp" and data["fallback"] == ["quadprog"]


def test_every_command_is_described_and_options_mean_one_thing():
    from emdm.cli.main import build_parser

    parser = build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    helps = {}
    for name, sub in commands.choices.items():
        assert sub.description and len(sub.description) > 20, name
        for action in sub._actions:
            for option in action.option_strings:
                if action.help is argparse.SUPPRESS or option in ("-h", "--help"):
                    continue
                helps.setdefault(option, {})[name] = action
    for option in ("--controller", "--solver"):
        assert all(
            a.type.__name__ == "parse" and isinstance(a, argparse._ExtendAction)
            for a in helps[option].values()
        ), option
    assert all(a.help.startswith("worker processes") for a in helps["--workers"].values())
    assert all(
        a.help.startswith("output folder") for c, a in helps["--out"].items() if c != "bench"
    )
    assert "scenario" not in helps["--out"] and "list" not in helps["--out"]
    assert set(helps["--quick"]) == {"report", "bench"}


def test_progress_is_drawn_on_a_terminal_only(tmp_path, monkeypatch, capsys):
    assert main(["run", "task2", "--controller", "C-EMDM", "--out", str(tmp_path / "a")]) == 0
    assert capsys.readouterr().err == ""  # stderr is not a terminal here: silent
    monkeypatch.setattr("emdm.cli.progress.shown", lambda: True)
    assert main(["run", "task2", "--controller", "C-EMDM", "--out", str(tmp_path / "b")]) == 0
    err = capsys.readouterr().err
    assert "run task2" in err and "controller" in err


def test_piping_into_head_is_quiet(tmp_path):
    """The reader goes away first (head -1 after a line, true at once): no "Broken pipe"."""
    exe = Path(sys.executable).with_name("emdm")
    command = str(exe) if exe.exists() else f"{sys.executable} -m emdm.cli"
    for reader in ("head -1", "true"):
        done = subprocess.run(
            f"set -o pipefail; {command} list | {reader}",
            shell=True,
            executable="/bin/bash",
            capture_output=True,
            text=True,
            check=False,
        )
        assert done.stderr == "" and done.returncode == 0, (reader, done.stderr)


def test_study_sweep_folders_are_unique_and_read_back(tmp_path, capsys):
    """Found by the hostile re-test: weights that print alike, and two scenarios of one name,
    shared one sweep folder and the last study overwrote the others."""
    out = tmp_path / "s"
    argv = [
        "study",
        "task1",
        "--runs",
        "20",
        "--weights",
        "0.1:5,0.1000000001:5",
        "--out",
        str(out),
    ]
    assert main(argv) == 0
    folders = sorted(p.name for p in out.iterdir() if p.name.startswith("task1-wE"))
    assert folders == ["task1-wE0.1-wM5", "task1-wE0.1000000001-wM5"]
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    for folder in ("a", "b"):
        text = emdm.load_scenario("task1").to_toml().replace('name = "task1"', 'name = "same"')
        (tmp_path / folder / "s.toml").write_text(text, encoding="utf-8")
    capsys.readouterr()
    argv = ["study", str(tmp_path / "a" / "s.toml"), str(tmp_path / "b" / "s.toml"), "--runs", "20"]
    assert main([*argv, "--out", str(tmp_path / "t")]) == 2
    err = capsys.readouterr().err
    assert "would share the folder same-wE0.1-wM5" in err and not (tmp_path / "t").exists()


def test_unicode_names_stay_in_folder_names():
    from emdm.cli.main import safe

    assert safe("αβγ 日本") == "αβγ_日本" and safe("../x") == "x" and safe("///") == "scenario"


def test_study_refuses_what_would_not_fit_before_any_work(tmp_path, capsys, monkeypatch):
    """Found by the hostile re-test: --runs 1e9 with --keep-runs and 256 local Dask workers
    were accepted and ran on; both are one line with the estimate now."""
    from emdm.core import checks

    monkeypatch.setattr(checks, "memory_available", lambda: 24_000_000_000)  # this machine's
    out = tmp_path / "s"
    assert main(["study", "task1", "--runs", "1000000000", "--keep-runs", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--keep-runs with --runs 1000000000: keeping every run needs about" in err
    assert "use at most --runs" in err and len(err.strip().splitlines()) == 1
    argv = ["study", "task1", "--engine", "dask", "--workers", "256", "--out", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "--workers 256: a local Dask cluster of 256 workers needs about 64 GB" in err
    assert not out.exists()


def test_study_refuses_what_would_take_too_long_before_any_work(tmp_path, capsys, monkeypatch):
    """Issue 25: a time bomb (--runs 1e9 takes days) is refused up front with the estimate
    from a pilot block and the largest --runs within --max-hours; that largest value is
    accepted by the same estimate."""
    from emdm.studies import montecarlo

    monkeypatch.setattr(montecarlo, "seconds_per_run", lambda scenario, seed: 2e-4)
    out = tmp_path / "s"
    assert main(["study", "task1", "--runs", "1000000000", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and not out.exists()
    assert "--runs 1000000000: the study would take about 2.3 days here" in err
    assert "0.2 ms per run of every controller), more than --max-hours 1" in err
    fits = int(re.search(r"use at most --runs (\d+)", err).group(1))
    assert fits == 18_000_000  # 3600 s / 0.2 ms
    argv = ["study", "task1", "--runs", "20000", "--max-hours", "1e-3", "--out", str(out)]
    assert main(argv) == 2  # 4 s against 3.6 s
    assert "more than --max-hours 0.001: use at most --runs 18000" in capsys.readouterr().err


def test_study_time_pilot_is_the_study_own_first_block(monkeypatch):
    """The pilot times the study's own first block of runs (after a few runs that compile), and
    the estimate per run is that block's time over its runs."""
    from emdm.studies import montecarlo

    calls = []
    real = montecarlo.run_chunk

    def spy(data, seed, first, last, runs, *rest):
        calls.append((data["name"], seed, first, last, runs))
        return real(data, seed, first, last, runs, *rest)

    monkeypatch.setattr(montecarlo, "run_chunk", spy)
    per_run = montecarlo.seconds_per_run(emdm.load_scenario("task1"), 7)
    assert calls == [("task1", 7, 0, 1, 4), ("task1", 7, 0, 1, montecarlo.BLOCK)]
    assert 0.0 < per_run < 1.0


def test_a_refused_command_says_one_line_even_after_a_scenario_warning(tmp_path, capsys):
    """Found by the long fuzz run: a scenario that warns (its goal out of reach) with an --out
    holding a user's file said the warning, then the refusal: two lines. The warning waits for
    the up-front checks: a refused command says only its error; one that runs says both."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "mine.txt").write_text("the user's", encoding="utf-8")
    argv = ["run", "task2", "--set", "arm.lengths=[1, 2]", "--set", "motion.max_time=0.3"]
    assert main([*argv, "--out", str(out)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "emdm did not write" in lines[0], lines
    assert main([*argv, "--out", str(tmp_path / "fresh")]) == 0
    err = capsys.readouterr().err
    assert "emdm: warning: task2: motion.goal:" in err and "outside the reachable annulus" in err
