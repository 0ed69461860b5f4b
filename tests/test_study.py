"""Monte-Carlo studies: reproducible, equal to single runs, identical on any engine and split."""

from __future__ import annotations

import json
import os
import signal

import numpy as np
import pytest

import emdm
from emdm.cli import main
from emdm.errors import EmdmError
from emdm.outputs.style import formats
from emdm.studies.montecarlo import (
    BLOCK,
    Accumulator,
    Engine,
    EngineKind,
    draw,
    run_chunks,
    run_study,
    study_json,
)


def small(task: str = "task1") -> emdm.Scenario:
    return emdm.load_scenario(task, {"motion.max_time": 6.0})


def test_draws_are_reproducible_reachable_and_outside_stop_zones():
    sc = emdm.load_scenario("task1")
    q0s, goals = draw(sc, 600, seed=7)
    again_q0s, again_goals = draw(sc, 600, seed=7)
    assert np.array_equal(q0s, again_q0s) and np.array_equal(goals, again_goals)
    assert not np.array_equal(goals, draw(sc, 600, seed=8)[1])
    assert np.array_equal(draw(sc, 300, seed=7)[1], goals[:300])  # a prefix of the same study
    margin = np.minimum(q0s - sc.arm.q_min, sc.arm.q_max - q0s)
    assert margin.min() > sc.damper.stop.min()
    assert np.hypot(goals[:, 0], goals[:, 1]).max() <= sc.planar_arm.reach + 1e-12


def test_kept_records_equal_single_runs():
    sc = small()
    data = run_study(sc, 40, seed=3, keep_runs=True, progress=False)
    rec = data["records"]
    for name in ("C-EMDM", "UC-IVKC"):
        for r in (0, 17, 39):
            one = sc.with_overrides(
                {"motion.goal": list(rec["goals"][r]), "motion.q0": list(rec["q0s"][r])}
            )
            mt = emdm.metrics(emdm.simulate(one, name))
            assert rec[f"{name}__reached"][r] == mt["reached"]
            assert rec[f"{name}__steps"][r] == mt["steps"]
            assert abs(rec[f"{name}__mean_manipulability"][r] - mt["mean_manipulability"]) < 1e-12
    assert data["controllers"]["UC-IVKC"]["success_rate"] == rec["UC-IVKC__reached"].mean()


def test_results_do_not_depend_on_the_chunking():
    sc = small()
    runs = 3 * BLOCK + 17
    reference = study_json(run_study(sc, runs, seed=5, chunk_blocks=4, progress=False))
    for chunk_blocks in (1, 2):
        again = study_json(run_study(sc, runs, seed=5, chunk_blocks=chunk_blocks, progress=False))
        assert json.dumps(again, sort_keys=True) == json.dumps(reference, sort_keys=True)


def test_a_chunk_runs_in_slices_with_the_same_result(monkeypatch):
    """A chunk's runs go to the compiled batch in slices of SLICE_RUNS (a signal is honoured
    between two, whatever --chunk asks; a chunk of 200,000 runs held a SIGTERM for 13.6 s)."""
    from emdm.studies import montecarlo

    sc = small()
    runs = 3 * BLOCK + 17
    whole = study_json(run_study(sc, runs, seed=5, chunk_blocks=4, progress=False))
    monkeypatch.setattr(montecarlo, "SLICE_RUNS", 100)  # not even a whole block
    sliced = study_json(run_study(sc, runs, seed=5, chunk_blocks=4, progress=False))
    assert json.dumps(sliced, sort_keys=True) == json.dumps(whole, sort_keys=True)


def test_engine_kind_is_a_closed_set():
    assert Engine("dask").kind is EngineKind.DASK and Engine().kind is EngineKind.LOCAL
    with pytest.raises(EmdmError, match="unknown engine 'cloud' \\(local or dask\\)"):
        Engine("cloud")


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as local:
        yield local


@pytest.mark.slow  # starts a LocalCluster of two worker processes
def test_dask_gives_the_same_json_as_local(cluster):
    sc = small()
    runs = 2 * BLOCK + 5
    local = study_json(run_study(sc, runs, seed=11, chunk_blocks=2, progress=False))
    engine = Engine("dask", scheduler=cluster.scheduler_address)
    remote = study_json(run_study(sc, runs, seed=11, engine=engine, chunk_blocks=1, progress=False))
    assert json.dumps(remote, sort_keys=True) == json.dumps(local, sort_keys=True)


@pytest.mark.slow
def test_a_worker_dying_mid_study_costs_a_retry_not_the_study(cluster):
    from dask.distributed import Client

    sc = small()
    runs = 6 * BLOCK
    expected = study_json(run_study(sc, runs, seed=13, chunk_blocks=1, progress=False))
    with Client(cluster.scheduler_address) as client:
        pids = list(client.run(os.getpid).values())
    killed = []

    def kill_one(done: int, total: int) -> None:
        if done == 1 and not killed:
            os.kill(pids[0], signal.SIGKILL)
            killed.append(pids[0])

    engine = Engine("dask", scheduler=cluster.scheduler_address)
    acc = Accumulator()
    for part in run_chunks(sc, runs, 13, engine, chunk_blocks=1, progress=kill_one):
        acc.add(part)
    got = acc.result(runs)
    assert killed
    assert got["controllers"] == expected["controllers"]
    assert got["manipulability_gain"] == expected["manipulability_gain"]


def test_unreachable_scheduler_is_one_line(tmp_path, capsys):
    pytest.importorskip("dask.distributed")
    code = main(
        [
            "study",
            "task2",
            "--runs",
            "10",
            "--engine",
            "dask",
            "--scheduler",
            "tcp://127.0.0.1:9",
            "--out",
            str(tmp_path / "s"),
        ]
    )
    err = capsys.readouterr().err
    assert code == 2 and "cannot reach the Dask scheduler at tcp://127.0.0.1:9" in err
    assert err.count("\n") == 1 and not (tmp_path / "s").exists()


def test_study_command(tmp_path, capsys):
    out = tmp_path / "study"
    with formats((".png",)):
        assert (
            main(
                ["study", "task2", "--runs", "40", "--seed", "1", "--keep-runs", "--out", str(out)]
            )
            == 0
        )
    data = json.loads((out / "study.json").read_text())
    assert data["runs"] == 40 and set(data["controllers"]) == set(emdm.CONTROLLERS)
    assert "C-EMDM over C-IVKC" in data["manipulability_gain"]
    assert np.load(out / "runs.npz")["goals"].shape == (40, 2)
    assert (out / "workspace_maps.png").stat().st_size > 5000
    assert "success" in capsys.readouterr().out
    assert main(["study", "task2", "--runs", "0", "--out", str(tmp_path / "x")]) == 2
    assert main(["study", "task2", "--workers", "2", "--out", str(tmp_path / "y")]) == 2


def test_weight_and_scenario_sweep(tmp_path, capsys):
    out = tmp_path / "sweep"
    args = ["study", "task1", "task2", "--weights", "0.1:0,0.1:5", "--runs", "30"]
    with formats((".png",)):  # eight figures: PNG is enough here (vector formats: test_figures)
        assert main([*args, "--set", "motion.max_time=4", "--out", str(out)]) == 0
    sweep = json.loads((out / "sweep.json").read_text())
    assert [(s["scenario"], s["weights"]["manipulability"]) for s in sweep] == [
        ("task1", 0.0),
        ("task1", 5.0),
        ("task2", 0.0),
        ("task2", 5.0),
    ]
    assert (out / "task2-wE0.1-wM5" / "study.json").exists()
    assert (out / "trade_off-task1-C-EMDM" / "trade_off.png").exists()
    # w_M = 0 makes EMDM minimise effort alone: the same commands as IVKC, scaled by w_E
    zero = next(
        s for s in sweep if s["scenario"] == "task1" and s["weights"]["manipulability"] == 0
    )
    gain = zero["manipulability_gain"]["UC-EMDM over UC-IVKC"]["mean_gain"]
    assert abs(gain) < 1e-12
    capsys.readouterr()


def test_bad_weights_are_one_line(tmp_path, capsys):
    assert main(["study", "task2", "--weights", "0.1:x", "--out", str(tmp_path / "a")]) == 2
    assert main(["study", "task2", "--weights=-1:5", "--out", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 2 and "--weights" in err and not (tmp_path / "a").exists()
