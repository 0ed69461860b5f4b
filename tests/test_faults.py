"""Faults injected into writing results: whatever fails, wherever, earlier results stay byte for
byte, and nothing half-written or staged is left behind."""

from __future__ import annotations

import errno
import os
import subprocess
import sys
from pathlib import Path

import pytest

from emdm.cli import main
from emdm.outputs import records
from emdm.outputs.records import MARKER, OutputError, atomic_output, check_out


@pytest.fixture(scope="module", autouse=True)
def compiled():
    """The control loop compiled (or loaded) before any test reads stderr."""
    import emdm

    emdm.simulate(emdm.load_scenario("task2"), "C-EMDM")


def snapshot(folder: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()
    }


def write(out: Path, version: str) -> None:
    """Results in a few files and folders, as a command writes them."""
    with atomic_output(out) as stage:
        (stage / "metrics.json").write_text(f'{{"version": "{version}"}}')
        (stage / "trajectories").mkdir()
        for name in ("a", "b", "c"):
            (stage / "trajectories" / f"{name}.csv").write_text(f"{version},{name}\n" * 50)
        (stage / "figures" / "UC").mkdir(parents=True)
        (stage / "figures" / "UC" / "path.png").write_bytes(version.encode() * 100)


def leftovers(parent: Path) -> list[str]:
    """Hidden staging, backup or copy folders anywhere under ``parent``."""
    return sorted(
        str(p.relative_to(parent))
        for p in parent.rglob(".*")
        if p.name != MARKER and not p.name.startswith(".emdm-results")
    )


class Faults:
    """``os.rename`` that fails once, on call number ``fail_at`` (counting from 0)."""

    def __init__(self, fail_at: int, code: int = errno.EIO) -> None:
        self.fail_at, self.code, self.calls = fail_at, code, 0
        self.real = os.rename

    def __call__(self, src: object, dst: object, *args: object, **kwargs: object) -> None:
        call, self.calls = self.calls, self.calls + 1
        if call == self.fail_at:
            raise OSError(self.code, os.strerror(self.code), str(src))
        self.real(src, dst, *args, **kwargs)  # type: ignore[arg-type]


def no_exchange(a: Path, b: Path) -> None:
    raise OSError(errno.ENOSYS, "not here")


def exdev_exchange(a: Path, b: Path) -> None:
    raise OSError(errno.EXDEV, os.strerror(errno.EXDEV))


# ------------------------------------------------------------------------------ the swap itself
def test_results_replace_the_folder_as_a_whole(tmp_path):
    out = tmp_path / "out"
    with atomic_output(out) as stage:  # an older run wrote a file the next one does not
        (stage / "trajectories").mkdir()
        (stage / "trajectories" / "stale.csv").write_text("from an older run")
    write(out, "v2")
    assert snapshot(out)["metrics.json"] == b'{"version": "v2"}'
    assert "trajectories/stale.csv" not in snapshot(out)
    assert (out / MARKER).is_file() and leftovers(tmp_path) == []


@pytest.mark.parametrize("exchange", [None, no_exchange], ids=["renameat2", "two-renames"])
def test_every_rename_failing_keeps_the_earlier_results(tmp_path, monkeypatch, exchange):
    out = tmp_path / "out"
    write(out, "v1")
    before = snapshot(out)
    if exchange is not None:
        monkeypatch.setattr(records, "_exchange", exchange)
    failures = 0
    for fail_at in range(6):
        faults = Faults(fail_at)
        monkeypatch.setattr(os, "rename", faults)
        try:
            write(out, "v2")
        except OutputError as exc:
            failures += 1
            assert "the earlier results are unchanged" in str(exc)
            assert snapshot(out) == before, fail_at
        else:
            assert snapshot(out)["metrics.json"] == b'{"version": "v2"}'
        finally:
            monkeypatch.setattr(os, "rename", faults.real)
        assert leftovers(tmp_path) == [], fail_at
        write(out, "v1")  # back to the start for the next fault
    # two renames (out -> backup, staged -> out): either may fail; renameat2 needs none
    assert failures == (0 if exchange is None else 2)


def test_a_failing_exchange_changes_nothing(tmp_path, monkeypatch):
    out = tmp_path / "out"
    write(out, "v1")
    before = snapshot(out)

    def broken(a: Path, b: Path) -> None:
        raise OSError(errno.EIO, os.strerror(errno.EIO))

    monkeypatch.setattr(records, "_exchange", broken)
    with pytest.raises(OutputError, match="input/output error"):
        write(out, "v2")
    assert snapshot(out) == before and leftovers(tmp_path) == []


@pytest.mark.parametrize("fail_at", range(12))
def test_cross_device_copy_then_swap_survives_any_failing_rename(tmp_path, monkeypatch, fail_at):
    """EXDEV (another filesystem, an overlay): copy beside the results, then swap entry by entry."""
    out = tmp_path / "out"
    write(out, "v1")
    before = snapshot(out)
    monkeypatch.setattr(records, "_exchange", exdev_exchange)
    real = os.rename
    calls = [0]

    def rename(src: object, dst: object) -> None:
        call, calls[0] = calls[0], calls[0] + 1
        if call == 0:  # out -> backup: refused, another filesystem
            raise OSError(errno.EXDEV, os.strerror(errno.EXDEV))
        if call == fail_at + 1:
            raise OSError(errno.EIO, os.strerror(errno.EIO))
        real(src, dst)  # type: ignore[arg-type]

    monkeypatch.setattr(os, "rename", rename)
    try:
        write(out, "v2")
    except OutputError:
        assert snapshot(out) == before
    else:
        assert snapshot(out)["metrics.json"] == b'{"version": "v2"}'
        assert set(snapshot(out)) == set(before)
    assert leftovers(tmp_path) == []


def test_cross_device_into_a_new_folder(tmp_path, monkeypatch):
    real = os.rename

    def rename(src: object, dst: object) -> None:
        if Path(str(src)).name.startswith(".out.partial-"):
            raise OSError(errno.EXDEV, os.strerror(errno.EXDEV))
        real(src, dst)  # type: ignore[arg-type]

    monkeypatch.setattr(os, "rename", rename)
    write(tmp_path / "out", "v1")
    assert snapshot(tmp_path / "out")["metrics.json"] == b'{"version": "v1"}'
    assert leftovers(tmp_path) == []


def test_a_failure_while_writing_removes_the_staging_and_new_parents(tmp_path):
    out = tmp_path / "new" / "deeper" / "out"
    with pytest.raises(RuntimeError), atomic_output(out) as stage:
        (stage / "x").write_text("half")
        raise RuntimeError("the command failed")
    assert list(tmp_path.iterdir()) == []


def test_interrupt_during_the_swap_is_deferred(tmp_path, monkeypatch):
    """A signal arriving during the swap waits for it: the results are either old or new."""
    import signal

    out = tmp_path / "out"
    write(out, "v1")
    seen = []

    def handler(signum, frame):
        if records.deferring():
            records.defer(signum)
            seen.append("deferred")
            return
        seen.append("raised")
        raise KeyboardInterrupt

    real = records._exchange

    def exchange(a: Path, b: Path) -> None:
        signal.raise_signal(signal.SIGUSR1)  # arrives in the middle of the swap
        real(a, b)

    previous = signal.signal(signal.SIGUSR1, handler)
    try:
        monkeypatch.setattr(records, "_exchange", exchange)
        with pytest.raises(KeyboardInterrupt):
            write(out, "v2")
    finally:
        signal.signal(signal.SIGUSR1, previous)
    assert seen == ["deferred", "raised"]
    assert snapshot(out)["metrics.json"] == b'{"version": "v2"}' and leftovers(tmp_path) == []


# ------------------------------------------------------------------------- checked before work
def test_out_checked_before_any_work(tmp_path, capsys):
    (tmp_path / "file").write_text("x")
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("my own notes")
    cases = {
        "file": "exists and is not a folder",
        "file/sub": "is not a folder",
        "mine": "emdm did not write",
    }
    for where, message in cases.items():
        with pytest.raises(OutputError, match=message):
            check_out(tmp_path / where)
        assert main(["run", "task2", "--out", str(tmp_path / where)]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err
    assert (tmp_path / "mine" / "notes.txt").read_text() == "my own notes"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file", "mine"]


def test_out_without_room_is_refused_before_work(tmp_path, monkeypatch):
    monkeypatch.setattr(records, "MIN_FREE", 1 << 60)
    with pytest.raises(OutputError, match="free on its filesystem"):
        check_out(tmp_path / "out")
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------- real filesystems (tmpfs)
def _mount(path: Path, *options: str) -> None:
    if os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root")
    path.mkdir(parents=True, exist_ok=True)
    done = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", ",".join(options), "tmpfs", str(path)],
        capture_output=True,
        check=False,
    )
    if done.returncode:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.decode().strip()}")


@pytest.fixture
def mounts():
    made: list[Path] = []

    def mount(path: Path, *options: str) -> Path:
        _mount(path, *options)
        made.append(path)
        return path

    yield mount
    for path in reversed(made):
        subprocess.run(["umount", "-l", str(path)], check=False)


def test_out_on_its_own_filesystem(tmp_path, mounts):
    """``--out`` is a mount point (a tmpfs, a Docker volume): staged inside it, swapped in."""
    out = mounts(tmp_path / "out", "size=1m")
    write(out, "v1")
    write(out, "v2")
    assert snapshot(out)["metrics.json"] == b'{"version": "v2"}'
    assert leftovers(tmp_path) == []


def test_read_only_subfolder_is_refused_before_work(tmp_path, mounts, capsys):
    out = tmp_path / "out"
    write(out, "v1")
    mounts(out / "trajectories", "size=64k")
    (out / "trajectories" / "a.csv").write_text("v1,a\n")
    subprocess.run(["mount", "-o", "remount,ro", str(out / "trajectories")], check=True)
    before = snapshot(out)
    assert main(["run", "task2", "--controller", "C-EMDM", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "trajectories is read-only" in err and err.count("\n") == 1
    assert snapshot(out) == before and leftovers(tmp_path) == []


def test_full_disk(tmp_path, mounts, monkeypatch, capsys):
    disk = mounts(tmp_path / "disk", "size=256k")
    assert main(["run", "task2", "--out", str(disk / "r")]) == 2  # refused before any work
    err = capsys.readouterr().err
    assert "free on its filesystem" in err and err.count("\n") == 1
    monkeypatch.setattr(records, "MIN_FREE", 0)  # let it start: the disk fills while writing
    assert main(["run", "task2", "--controller", "UC-IVKC", "--out", str(disk / "r")]) == 0
    before = snapshot(disk / "r")
    assert main(["run", "task2", "--out", str(disk / "r")]) == 2
    err = capsys.readouterr().err
    assert "no space left on device" in err and "earlier results are unchanged" in err
    assert err.count("\n") == 1
    assert snapshot(disk / "r") == before and leftovers(disk) == []


# ---------------------------------------------------------------------- nothing of yours is lost
def test_files_emdm_did_not_write_are_never_replaced(tmp_path, capsys):
    out = tmp_path / "out"
    write(out, "v1")
    (out / "figures" / ".DS_Store").write_bytes(b"browser")  # a file browser's: replaced
    write(out, "v2")
    (out / "trajectories" / "my notes.txt").write_text("mine")
    before = snapshot(out)
    with pytest.raises(OutputError, match=r"holds trajectories/my notes.txt, which emdm did not"):
        write(out, "v3")
    assert main(["run", "task2", "--controller", "C-EMDM", "--out", str(out)]) == 2
    assert "my notes.txt, which emdm did not write" in capsys.readouterr().err
    assert snapshot(out) == before


def test_a_file_that_appears_during_the_work_is_never_replaced(tmp_path, monkeypatch, capsys):
    """Issue 25: --out is checked again just before the swap. A file put in it while the work ran
    (or results of a nested command, emdm run --out OUT/sub during a report into OUT) means
    refusal: the new results are not put in place, nothing of the user's is deleted."""
    out = tmp_path / "out"
    write(out, "v1")
    with pytest.raises(
        OutputError, match=r"holds notes.txt, which emdm did not write \(it appeared"
    ):
        with atomic_output(out) as stage:
            (stage / "metrics.json").write_text("v2")
            (out / "notes.txt").write_text("mine")
    assert (out / "notes.txt").read_text() == "mine"
    assert snapshot(out)["metrics.json"] == b'{"version": "v1"}' and leftovers(tmp_path) == []
    (out / "notes.txt").unlink()
    real = records.write_csv

    def nested(path, *args, **kwargs):  # another emdm writes OUT/sub meanwhile
        real(path, *args, **kwargs)
        if not (out / "sub").exists():
            write(out / "sub", "nested")

    monkeypatch.setattr(records, "write_csv", nested)
    assert main(["run", "task2", "--controller", "C-EMDM", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "it appeared while emdm was working" in err and err.count("\n") == 1, err
    assert snapshot(out / "sub")["metrics.json"] == b'{"version": "nested"}'
    assert snapshot(out)["metrics.json"] == b'{"version": "v1"}'


@pytest.mark.parametrize(
    "name", ["lost+found", ".emdm-old-x", ".emdm-partial-x", ".emdm-old-{dead}-x"]
)
def test_names_like_emdm_s_own_are_the_user_s(tmp_path, name):
    """Issue 25: in a folder that is not a mount point, lost+found is the user's, and so is any
    name like emdm's in-flight folders that no live emdm is working in (earlier results a killed
    emdm had moved aside are shown to the user, not deleted)."""
    gone = subprocess.Popen(["true"])
    gone.wait()
    name = name.format(dead=gone.pid)
    out = tmp_path / "out"
    write(out, "v1")
    (out / name).mkdir()
    (out / name / "kept.txt").write_text("mine")
    with pytest.raises(OutputError, match="which emdm did not write"):
        write(out, "v2")
    assert (out / name / "kept.txt").read_text() == "mine"


def test_out_must_not_hold_the_input(tmp_path, capsys):
    run_dir = tmp_path / "r"
    assert main(["run", "task2", "--controller", "C-EMDM", "--out", str(run_dir)]) == 0
    before = snapshot(run_dir)
    for out in (run_dir, tmp_path):
        assert main(["plot", str(run_dir), "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert "holds the input" in err or "emdm did not write" in err, err
    assert snapshot(run_dir) == before


def test_what_a_killed_emdm_left_is_tidied(tmp_path):
    """SIGKILL or a power cut leaves a staging folder, or the earlier results moved aside."""
    gone = subprocess.Popen(["true"])
    gone.wait()
    dead = gone.pid
    out = tmp_path / "out"
    write(out, "v1")
    (tmp_path / f".out.partial-{dead}-abc").mkdir()  # killed while working
    write(out, "v2")
    assert leftovers(tmp_path) == []
    os.rename(out, tmp_path / f".out.old-{dead}-abc")  # killed between the two renames
    write(tmp_path / "other", "x")  # another folder: not touched
    assert not out.exists()
    write(out, "v3")  # the earlier results came back first, then were replaced
    assert snapshot(out)["metrics.json"] == b'{"version": "v3"}' and leftovers(tmp_path) == []


@pytest.mark.parametrize(
    ("where", "message"), [("/", "is the root folder"), ("x" * 300, "longer than 255 bytes")]
)
def test_impossible_out_names(tmp_path, monkeypatch, where, message):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(OutputError, match=message):
        check_out(Path(where))


def test_a_full_stdout_is_one_line(tmp_path):
    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full here")
    done = subprocess.run(
        [sys.executable, "-m", "emdm.cli", "list"],
        stdout=open("/dev/full", "w"),
        stderr=subprocess.PIPE,
        text=True,
        check=False,
    )
    assert done.returncode == 2
    assert done.stderr == (
        "emdm: error: cannot write to the standard output: no space left on device\n"
    )


def test_a_read_only_place_is_refused_before_work(tmp_path, mounts, capsys):
    place = mounts(tmp_path / "ro", "size=64k", "ro")
    assert main(["run", "task2", "--out", str(place / "r")]) == 2
    err = capsys.readouterr().err
    assert "cannot create folders in" in err and "read-only file system" in err
    assert err.count("\n") == 1


def test_a_read_only_cache_compiles_in_memory_with_one_line(monkeypatch, capsys):
    """With no writable cache folder numba refuses ``cache=True`` ("no locator available"); the
    kernel is compiled in memory instead, and one line says so."""
    from emdm.core import jit

    def refusing(self: object) -> None:
        raise RuntimeError("cannot cache function 'f': no locator available for file 'x.py'")

    monkeypatch.setattr(jit.Kernel, "enable_caching", refusing)
    monkeypatch.setattr(jit, "_uncached", [])

    def twice(x: float) -> float:
        return 2.0 * x

    compiled = jit.kernel(twice)
    assert compiled(3.0) == 6.0
    assert jit.kernel(lambda x: x + 1.0)(1.0) == 2.0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "compiling in memory" in err


def test_hostile_inputs_found_by_the_fuzzing_are_one_line(tmp_path, capsys):
    """Three defects of issue 25, each once an internal error: a TOML nested 2000 deep
    (RecursionError), a speed-up that makes a GIF frame longer than the format holds
    (OverflowError after the work), and Pareto fronts at w_M = 0 (math domain error)."""
    from emdm.cli import main

    deep = tmp_path / "deep.toml"
    deep.write_text("a = " + "[" * 2000 + "]" * 2000 + "\n")
    assert main(["run", str(deep)]) == 2
    assert "nest too deeply" in capsys.readouterr().err
    out = tmp_path / "anim"
    assert main(["animate", "task1", "--speedup", "1e-6", "--out", str(out)]) == 2
    assert "longer than a GIF frame can last" in capsys.readouterr().err and not out.exists()
    args = ["pareto", "task1", "--set", "weights.manipulability=0", "--set", "motion.max_time=2"]
    assert main([*args, "--out", str(tmp_path / "p")]) == 0


def test_a_lab_with_nothing_to_solve_and_a_garbage_scheduler_are_one_line(tmp_path, capsys):
    """Two more internal errors of issue 25: the solver lab when the start is the goal
    (IndexError) and a Dask scheduler address that is not one (ValueError from distributed)."""
    import emdm
    from emdm.cli import main

    start = emdm.load_scenario("task1")
    tip = start.robot.position(start.motion.q0)
    goal = f"motion.goal=[{float(tip[0])!r}, {float(tip[1])!r}]"
    assert main(["solvers", "task1", "--set", goal, "--out", str(tmp_path / "s")]) == 2
    assert "at the goal at the start" in capsys.readouterr().err
    for address in ("garbage", "http://127.0.0.1:1"):  # the second passed the check before
        args = ["study", "task1", "--engine", "dask", "--scheduler", address, "--runs", "10"]
        assert main([*args, "--out", str(tmp_path / "d")]) == 2
        err = capsys.readouterr().err  # the address as typed (it was shown sanitised)
        assert f"--scheduler '{address}': expected a Dask scheduler address" in err
    assert not (tmp_path / "s").exists() and not (tmp_path / "d").exists()


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


@pytest.mark.parametrize(
    "command",
    [
        ["run", "task1", "--set", "weights.effort=0.2"],
        ["pareto", "task1", "--grid", "3", "--set", "weights.effort=0.2"],
        ["study", "task1", "--runs", "20"],
    ],
    ids=["run", "pareto", "study"],
)
def test_a_full_stdout_keeps_the_earlier_results(tmp_path, command):
    """Found by the hostile re-test: `emdm run ... > /dev/full` replaced --out, then exited 2.
    What a command prints goes out before the swap, so a failing stdout keeps the old results."""
    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full here")
    out = tmp_path / "out"
    assert main(["run", "task1", "--controller", "C-EMDM", "--out", str(out)]) == 0
    before = _snapshot(out)
    with open("/dev/full", "w") as full:
        done = subprocess.run(
            [sys.executable, "-m", "emdm", *command, "--out", str(out)],
            stdout=full,
            stderr=subprocess.PIPE,
            text=True,
            check=False,
            env={**os.environ, "EMDM_PROGRESS": "0"},
        )
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines()[-1] == (
        "emdm: error: cannot write to the standard output: no space left on device"
    )
    assert _snapshot(out) == before
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # no staging left


def test_a_closed_stdout_is_one_line_before_any_work(tmp_path):
    out = tmp_path / "out"
    done = subprocess.run(
        [sys.executable, "-m", "emdm", "run", "task1", "--out", str(out)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        check=False,
        preexec_fn=lambda: os.close(1),
    )
    assert done.returncode == 2
    assert done.stderr.startswith("emdm: error: the standard output is closed; nothing was run")
    assert len(done.stderr.strip().splitlines()) == 1 and not out.exists()


def test_a_path_too_long_is_refused_before_any_folder_is_made(tmp_path, capsys):
    deep = tmp_path / "lp" / "/".join(["d" * 200] * 25)
    assert main(["run", "task1", "--out", str(deep)]) == 2
    assert "its path is too long" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []  # the case left 21 empty folders
    long_name = tmp_path / ("x" * 256)
    assert main(["run", "task1", "--out", str(long_name)]) == 2
    assert "longer than 255 bytes" in capsys.readouterr().err


def test_a_failing_mkdir_removes_the_parents_it_made(tmp_path, monkeypatch):
    from emdm.outputs import records

    real = Path.mkdir
    calls = []

    def mkdir(self, *args, **kwargs):
        calls.append(self)
        if len(calls) == 3:
            raise OSError(36, "File name too long")
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Path, "mkdir", mkdir)
    with pytest.raises(OSError):
        records._make_parents(tmp_path / "a" / "b" / "c" / "d")
    assert list(tmp_path.iterdir()) == []
