"""Signals: SIGTERM (schedulers, timeout, docker stop) and SIGHUP stop a command like SIGINT. The
workers it started stop with it, its staging is removed, the earlier results stay, and it exits
with 128 + the signal and one line."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from emdm.cli import main
from emdm.cli.boundary import _alive, descendants

COMMAND = [sys.executable, "-m", "emdm.cli"]


@pytest.fixture(scope="module", autouse=True)
def compiled():
    """The control loop compiled (or loaded) before any test reads stderr."""
    import emdm

    emdm.simulate(emdm.load_scenario("task2"), "C-EMDM")


def snapshot(folder: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()
    }


def stop_when(args: list[str], ready, sig: int, timeout: float = 240.0):
    """Start ``emdm args``; once ``ready(children)`` holds, send ``sig``. Returns the finished
    process, its stderr and every process it had started."""
    env = {**os.environ, "EMDM_PROGRESS": "0"}
    process = subprocess.Popen(
        [*COMMAND, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
    )
    seen: set[int] = set()
    deadline = time.monotonic() + timeout
    try:
        while time.monotonic() < deadline and process.poll() is None:
            children = descendants(process.pid)
            seen.update(children)
            if ready(children):
                break
            time.sleep(0.05)
        assert process.poll() is None, "the command ended before the signal"
        seen.update(descendants(process.pid))
        process.send_signal(sig)
        _, err = process.communicate(timeout=30)
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    return process, err, seen


def gone(pids: set[int], wait: float = 5.0) -> list[int]:
    deadline = time.monotonic() + wait
    while any(_alive(p) for p in pids) and time.monotonic() < deadline:
        time.sleep(0.05)
    return [p for p in pids if _alive(p)]


def last_line(err: str) -> str:
    """The command's own message (a compile notice may come before it)."""
    return err.strip().splitlines()[-1]


@pytest.mark.slow
def test_sigterm_stops_report_and_its_pool(tmp_path):
    out = tmp_path / "report"
    process, err, seen = stop_when(
        ["report", "--quick", "--out", str(out)], lambda kids: len(kids) >= 2, signal.SIGTERM
    )
    assert process.returncode == 143, err
    assert last_line(err) == "emdm: terminated (SIGTERM); nothing was written"
    assert len(seen) >= 2 and gone(seen) == []  # the pool's workers went with it
    assert list(tmp_path.iterdir()) == []  # no staging, nothing half-written


@pytest.mark.slow
def test_sigkill_of_report_leaves_no_worker(tmp_path):
    """SIGKILL reaches no handler of the report: its pool's workers end with it anyway (they ran
    on for good before), and nothing is written to --out."""
    out = tmp_path / "report"
    process, _, seen = stop_when(
        ["report", "--quick", "--out", str(out)], lambda kids: len(kids) >= 2, signal.SIGKILL
    )
    assert process.returncode == -signal.SIGKILL
    assert len(seen) >= 2 and gone(seen) == []
    assert not out.exists()


@pytest.mark.slow
def test_sighup_stops_the_solver_lab_and_keeps_earlier_results(tmp_path):
    out = tmp_path / "lab"
    assert main(["run", "task2", "--controller", "UC-IVKC", "--out", str(out)]) == 0
    before = snapshot(out)  # earlier results, to be replaced only by a complete lab
    args = ["solvers", "task2", "--solver", "slsqp,nelder-mead", "--sample", "5", "--no-figures"]
    process, err, seen = stop_when(
        [*args, "--out", str(out)],
        lambda kids: len(kids) >= 2,
        signal.SIGHUP,
    )
    assert process.returncode == 129, err
    assert last_line(err) == "emdm: hung up (SIGHUP); nothing was written"
    assert gone(seen) == []
    assert snapshot(out) == before and [p.name for p in tmp_path.iterdir()] == ["lab"]


@pytest.mark.slow
def test_sigterm_stops_a_dask_study(tmp_path):
    pytest.importorskip("distributed")
    out = tmp_path / "study"
    args = ["study", "task1", "--runs", "100000", "--engine", "dask", "--workers", "2"]
    process, err, seen = stop_when(
        [*args, "--out", str(out)], lambda kids: len(kids) >= 3, signal.SIGTERM
    )
    assert process.returncode == 143, err
    assert err.strip().endswith("emdm: terminated (SIGTERM); nothing was written"), err
    assert "Traceback" not in err and gone(seen) == []
    assert list(tmp_path.iterdir()) == []


def test_sigterm_in_process_removes_the_staging(tmp_path, monkeypatch, capsys):
    """The handler itself, without a subprocess: SIGTERM while results are being written."""
    out = tmp_path / "out"
    assert main(["run", "task2", "--controller", "C-EMDM", "--out", str(out)]) == 0
    before = snapshot(out)
    from emdm.outputs import records

    real = records.write_csv

    def terminated(*args, **kwargs):
        real(*args, **kwargs)
        signal.raise_signal(signal.SIGTERM)

    monkeypatch.setattr(records, "write_csv", terminated)
    assert main(["run", "task2", "--controller", "C-EMDM", "--out", str(out)]) == 143
    err = capsys.readouterr().err
    assert err == "emdm: terminated (SIGTERM); nothing was written\n"
    assert snapshot(out) == before and [p.name for p in tmp_path.iterdir()] == ["out"]
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL  # restored after the command


def test_a_signal_during_the_swap_waits_for_it(tmp_path, monkeypatch, capsys):
    """SIGTERM in the middle of the swap: the swap finishes, then the command stops; the
    message says the results were written."""
    from emdm.outputs import records

    out = tmp_path / "out"
    real = records._commit

    def commit(*args, **kwargs):
        signal.raise_signal(signal.SIGTERM)
        real(*args, **kwargs)

    monkeypatch.setattr(records, "_commit", commit)
    assert main(["run", "task2", "--controller", "C-EMDM", "--out", str(out)]) == 143
    err = capsys.readouterr().err
    assert err == f"emdm: terminated (SIGTERM); {out} was written before that\n"
    assert (out / "metrics.json").is_file() and [p.name for p in tmp_path.iterdir()] == ["out"]


class _Finalized:
    """An object whose finalizer receives SIGTERM: the handler's exception is raised inside
    ``__del__``, where Python prints "Exception ignored" and drops it."""

    def __del__(self):
        signal.raise_signal(signal.SIGTERM)


def test_a_signal_whose_exception_is_dropped_still_stops_the_command(tmp_path, monkeypatch, capsys):
    """Issue 25: SIGTERM landing in a finalizer (numba's cache loading, matplotlib) used to be
    dropped; the command ran on, replaced --out and exited 0. The handler records the signal, so
    the swap refuses and the command exits 143 with the earlier results intact."""
    from emdm.outputs import records

    out = tmp_path / "out"
    assert main(["run", "task2", "--controller", "C-EMDM", "--out", str(out)]) == 0
    before = snapshot(out)
    capsys.readouterr()
    real = records.write_csv

    fired = []

    def dropped(*args, **kwargs):
        real(*args, **kwargs)
        if not fired:  # once: a second signal would stop the process at once
            fired.append(True)
            _Finalized()  # collected at once: the signal lands in its finalizer

    monkeypatch.setattr(records, "write_csv", dropped)
    unraisable = []
    monkeypatch.setattr(sys, "unraisablehook", lambda info: unraisable.append(info.exc_type))
    assert main(["run", "task2", "--controller", "C-EMDM", "--out", str(out)]) == 143
    assert [t.__name__ for t in unraisable] == ["Interrupted"]  # Python did drop it
    err = capsys.readouterr().err
    assert err == "emdm: terminated (SIGTERM); nothing was written\n"
    assert snapshot(out) == before and [p.name for p in tmp_path.iterdir()] == ["out"]


def test_a_failure_after_a_dropped_signal_is_reported_as_the_signal(monkeypatch, capsys):
    """A SIGTERM whose exception Python dropped (in logging's fork handler) stopped the workers;
    the pool then broke and the command used to end in 'internal error: BrokenProcessPool' with
    status 1. A failure after a recorded signal is the signal's doing: 143, one line."""
    from concurrent.futures.process import BrokenProcessPool

    from emdm.cli.boundary import run_command
    from emdm.errors import request_stop

    def command() -> int:
        request_stop(signal.SIGTERM)  # as the handler does before its exception is dropped
        raise BrokenProcessPool("A process in the process pool was terminated abruptly")

    assert run_command(command) == 143
    assert capsys.readouterr().err == "emdm: terminated (SIGTERM); nothing was written\n"

    def failing() -> int:  # without a signal, a failure stays what it is
        raise BrokenProcessPool("gone")

    assert run_command(failing) == 1
    assert "internal error: BrokenProcessPool" in capsys.readouterr().err


def test_a_second_signal_stops_at_once(tmp_path):
    """A command that does not stop on the first signal (its exception dropped, a cleanup that
    hangs) stops on the second, with its status and one line."""
    script = (
        "import time\n"
        "from emdm.cli.boundary import run_command\n"
        "def command():\n"
        "    try:\n"
        "        print('ready', flush=True); time.sleep(60)\n"
        "    except KeyboardInterrupt:\n"
        "        time.sleep(60)  # a cleanup that hangs\n"
        "    return 0\n"
        "raise SystemExit(run_command(command))\n"
    )
    process = subprocess.Popen(
        [sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        assert process.stdout.readline().strip() == "ready"
        process.send_signal(signal.SIGTERM)
        time.sleep(0.5)
        assert process.poll() is None  # the first one is handled, and the cleanup hangs
        start = time.monotonic()
        process.send_signal(signal.SIGINT)
        _, err = process.communicate(timeout=20)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == 130 and time.monotonic() - start < 10
    assert err.strip() == "emdm: interrupted again; stopped at once"


MOMENTS = int(os.environ.get("EMDM_SIGNAL_MOMENTS", "3"))


def handled(process: subprocess.Popen[str], timeout: float) -> None:
    """Wait until ``process`` catches SIGTERM (Linux: its ``SigCgt`` mask), i.e. until the
    command's handler is installed, or it has ended."""
    deadline = time.monotonic() + timeout
    while process.poll() is None and time.monotonic() < deadline:
        try:
            status = Path(f"/proc/{process.pid}/status").read_text()
        except OSError:
            return
        mask = next(
            (int(line.split()[1], 16) for line in status.splitlines() if line.startswith("SigCgt")),
            0,
        )
        if mask & (1 << (signal.SIGTERM - 1)):
            return
        time.sleep(0.01)


"""Random moments per run of :func:`test_a_signal_at_a_random_moment_loses_nothing` (``make fuzz``
sets 200)."""


def test_a_signal_at_a_random_moment_loses_nothing(tmp_path):
    """SIGINT, SIGTERM, SIGHUP or SIGKILL at a random moment of ``emdm run`` (imports, kernels
    loading, the runs, writing, the swap) over earlier results: the command either finished (exit 0,
    complete new results) or stopped (128 + signal and one line, or killed) with the earlier
    results byte for byte; no staging folder survives a catchable signal, no process is left.

    The moment is drawn from when the executable's first lines have installed their handler
    (:mod:`emdm.entry`, before ``import emdm`` loads numba): loading, the runs, writing, the
    swap and the exit are all covered."""
    rng = np.random.default_rng(int.from_bytes(os.urandom(4), "little"))
    out = tmp_path / "out"
    assert main(["run", "task1", "--controller", "C-EMDM", "--out", str(out)]) == 0
    env = {**os.environ, "EMDM_PROGRESS": "0"}
    signals = [signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGKILL]
    for _ in range(MOMENTS):
        before = snapshot(out)
        sig = signals[int(rng.integers(len(signals)))]
        delay = float(rng.uniform(0.0, 2.8))
        argv = ["run", "task1", "--controller", "C-EMDM,C-IVKC", "--out", str(out)]
        process = subprocess.Popen(  # python -m emdm: the executable's own first lines
            [sys.executable, "-m", "emdm", *argv],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )
        handled(process, timeout=60.0)
        time.sleep(delay)
        kids = descendants(process.pid) if process.poll() is None else set()
        if process.poll() is None:
            process.send_signal(sig)
        _, err = process.communicate(timeout=60)
        code = process.returncode
        moment = f"{sig.name} after {delay:.2f} s: exit {code}, {err!r}"
        assert "Traceback" not in err, moment
        assert gone(kids) == [], moment
        after = snapshot(out)
        if code == 0:
            assert "trajectories/C-IVKC.csv" in after and ".emdm-results" in after, moment
        else:
            complete = "trajectories/C-IVKC.csv" in after and ".emdm-results" in after
            if sig == signal.SIGKILL:  # killed at once: the earlier results or the new ones
                assert code == -signal.SIGKILL and (after == before or complete), moment
            else:  # 128 + signal and one line that says what is on disk
                assert code == 128 + sig, moment
                line = err.strip().splitlines()[-1]
                assert line.startswith("emdm: "), moment
                if after != before:  # the signal came during or after the swap
                    assert complete and "was written before that" in line, moment
        if sig != signal.SIGKILL:
            left = [p.name for p in tmp_path.iterdir() if p.name != "out"]
            assert left == [], moment
        # what a killed command left is tidied by the next one (tested above); start clean
        for p in tmp_path.iterdir():
            if p.name != "out":
                subprocess.run(["rm", "-rf", str(p)], check=True)


PARALLEL = {  # a command with workers, the longest it runs here (s) and a file of its results
    "report": (["report", "--quick"], 13.0, "index.html"),
    "lab": (
        ["solvers", "task2", "--solver", "slsqp,nelder-mead", "--sample", "5", "--no-figures"],
        4.0,
        "solvers.json",
    ),
    "dask": (
        ["study", "task1", "--runs", "2000", "--engine", "dask", "--workers", "2"],
        6.0,
        "study.json",
    ),
}
PARALLEL_MOMENTS = int(os.environ.get("EMDM_PARALLEL_MOMENTS", "1"))
"""Random moments per run of :func:`test_a_signal_at_a_random_moment_of_a_command_with_workers`:
one in ``make test`` (on one of its commands, drawn at random), 20 per command in ``make fuzz``."""


@pytest.mark.slow
def test_a_signal_at_a_random_moment_of_a_command_with_workers(tmp_path):
    """SIGINT, SIGTERM, SIGHUP or SIGKILL at a random moment of a command that starts workers
    (the report's pool, the solver lab's pool, a Dask cluster), over earlier results: it finished
    (exit 0, complete results), or it stopped with its status and one line and the earlier results
    byte for byte (or the new ones, complete, when the signal came at the swap); no process it
    started survives it, not even after SIGKILL; nothing is left beside --out after a catchable
    signal."""
    rng = np.random.default_rng(int.from_bytes(os.urandom(4), "little"))
    if PARALLEL_MOMENTS == 1:  # make test: one moment, of one command
        plan = [rng.choice(sorted(PARALLEL))]
    else:
        plan = [name for name in sorted(PARALLEL) for _ in range(PARALLEL_MOMENTS)]
    if "dask" in plan:
        pytest.importorskip("distributed")
    out = tmp_path / "out"
    assert main(["run", "task1", "--controller", "C-EMDM", "--out", str(out)]) == 0
    env = {**os.environ, "EMDM_PROGRESS": "0"}
    signals = [signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGKILL]
    for name in plan:
        argv, longest, result = PARALLEL[name]
        before = snapshot(out)
        sig = signals[int(rng.integers(len(signals)))]
        delay = float(rng.uniform(0.0, longest))
        process = subprocess.Popen(
            [sys.executable, "-m", "emdm", *argv, "--out", str(out)],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )
        handled(process, timeout=60.0)
        seen: set[int] = set()
        deadline = time.monotonic() + delay
        while time.monotonic() < deadline and process.poll() is None:
            seen.update(descendants(process.pid))  # every worker it starts, however briefly
            time.sleep(0.02)
        if process.poll() is None:
            seen.update(descendants(process.pid))
            process.send_signal(sig)
        _, err = process.communicate(timeout=120)
        code = process.returncode
        moment = f"{name}: {sig.name} after {delay:.2f} s: exit {code}, {err[-600:]!r}"
        assert "Traceback" not in err, moment
        assert gone(seen, wait=10.0) == [], moment
        after = snapshot(out)
        complete = result in after and ".emdm-results" in after and after != before
        if code == 0:
            assert complete, moment
        elif sig == signal.SIGKILL:
            assert code == -signal.SIGKILL and (after == before or complete), moment
        else:
            assert code == 128 + sig, moment
            assert last_line(err).startswith("emdm: "), moment
            if after != before:
                assert complete and "was written before that" in last_line(err), moment
        if sig != signal.SIGKILL:
            assert [p.name for p in tmp_path.iterdir()] == ["out"], moment
        for p in tmp_path.iterdir():  # what SIGKILL left is tidied by the next command; start clean
            if p.name != "out":
                subprocess.run(["rm", "-rf", str(p)], check=True)
