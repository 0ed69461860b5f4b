"""Writing results: CSV with round-trip precision, JSON, and atomic output folders.

Everything a command writes goes first to a hidden staging folder beside ``--out`` (same
filesystem); only when the whole command has succeeded does it replace ``--out``, in one rename
where the filesystem allows it (:func:`atomic_output`). A failed or interrupted command leaves the
earlier results in ``--out`` byte for byte, and no staging folder behind.
"""

from __future__ import annotations

import contextlib
import csv
import ctypes
import errno
import json
import math
import os
import re
import shutil
import signal
import sys
import tempfile
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import EmdmError, check_stop, one_line
from ..sim.loop import Run


def cell(value: Any) -> str:
    if isinstance(value, float | np.floating):
        return repr(float(value))
    if isinstance(value, np.integer | np.bool_):
        return str(value.item())
    return str(value)


TASK_AXES = {2: ("x", "y"), 3: ("x", "y", "z"), 6: ("x", "y", "z", "rx", "ry", "rz")}
"""The task's coordinates by row count: planar tip, spatial position, or position and rotation
vector (the columns of the value ``p``; the error, velocity and slack take ``e``, ``v`` and
``delta_`` before them)."""


def trajectory_header(n: int, nt: int = 2, clearance: bool = False) -> list[str]:
    """Columns of ``trajectories/<controller>.csv`` (the README lists them) for an ``n``-joint
    arm on an ``nt``-row task; with ``clearance`` (a scene with obstacles) a last column, the
    smallest distance of a link to an obstacle at each state (m)."""
    axes = TASK_AXES[nt]
    return [
        "t",
        *[f"q{i}" for i in range(1, n + 1)],
        *[f"qd{i}" for i in range(1, n + 1)],
        *axes,
        *[f"e{a}" for a in axes],
        *[f"v{a}" for a in axes],
        "m",
        "effort",
        "manip_rate",
        "alpha",
        *[f"delta_{a}" for a in axes],
        "status",
        "solver",
        "iterations",
        "solve_time",
        *(["clearance"] if clearance else []),
    ]


def trajectory_rows(run: Run) -> Iterator[list[str]]:
    """One row per state; the final state's command fields are empty."""
    n = run.scenario.n
    for k in range(run.steps + 1):
        state = [run.t[k], *run.q[k]]
        where = [*run.p[k], *run.e[k], *run.v[k], run.m[k]]
        if k < run.steps:
            cmd = [*run.qd[k]]
            rest = [
                run.effort[k],
                run.manip_rate[k],
                run.alpha[k],
                *run.delta[k],
                run.status[k],
                run.solver[k],
                run.iterations[k],
                run.solve_time[k],
            ]
        else:
            cmd, rest = [""] * n, [""] * (7 + run.e.shape[1])
        if run.scenario.obstacles:
            rest = [*rest, run.clearance[k]]
        yield [cell(x) for x in (*state, *cmd, *where, *rest)]


def has_rows(scenario: Any) -> bool:
    """Whether a scenario's programs may carry inequality rows (planes or obstacles)."""
    return bool(scenario.planes.count or scenario.obstacles)


def diagnostics_header(n: int, rows: bool = False) -> list[str]:
    """Columns of ``diagnostics/<controller>.csv``: how every command was obtained; with
    ``rows`` (a scenario with planes or obstacles) also how many inequality rows the program had and how many
    the command holds with equality."""
    return [
        "step",
        "kkt_residual",
        "bound_excess",
        "fallback",
        "policy",
        "attempts",
        *[f"lo{i}" for i in range(1, n + 1)],
        *[f"hi{i}" for i in range(1, n + 1)],
        *[f"active{i}" for i in range(1, n + 1)],
        *(["rows", "rows_active"] if rows else []),
    ]


def diagnostics_rows(run: Run) -> Iterator[list[str]]:
    """One row per command (with the rows' counts when the scenario has planes or obstacles)."""
    rows = has_rows(run.scenario)
    for k in range(run.steps):
        yield [
            cell(x)
            for x in (
                k,
                run.kkt[k],
                run.bound_excess[k],
                bool(run.fallback[k]),
                run.policy[k],
                run.attempts[k],
                *run.lo[k],
                *run.hi[k],
                *run.active[k],
                *((run.rows[k], run.rows_active[k]) if rows else ()),
            )
        ]


def write_csv(path: Path, header: Sequence[str], rows: Iterator[list[str]]) -> None:
    """Write a CSV file (creating its folder)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        writer.writerows(rows)


def _json_safe(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_json_safe(v) for v in value]
    if isinstance(value, np.ndarray):
        return _json_safe(value.tolist())
    if isinstance(value, np.floating | float):
        f = float(value)
        return f if math.isfinite(f) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def write_json(path: Path, data: Any) -> None:
    """Write JSON (non-finite floats become null), floats with round-trip precision."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(_json_safe(data), indent=2) + "\n", encoding="utf-8")


# ------------------------------------------------------------------------- atomic output folders
MARKER = ".emdm-results"
"""The file emdm leaves in every folder it writes: only such folders (or empty ones) are replaced."""
IGNORED = frozenset({"lost+found"})
"""Entries of an output folder that is a mount point that emdm neither counts nor moves (its
lost+found). In any other folder they are the user's: the folder is replaced as a whole."""
DESKTOP_FILES = frozenset({".DS_Store", "Thumbs.db", "desktop.ini"})
"""Files a file browser leaves in any folder it shows: not the user's, replaced with the rest."""
_OURS = re.compile(r"\.emdm-(partial|old|copy|probe)-(\d+)-")
"""The folders emdm makes inside an output folder while it works (staging inside a mount point,
the earlier results moved aside, a copy across filesystems, a probe): named with the process id,
so that only those of a live emdm are passed over; any other name is the user's."""
_NO_EXCHANGE = {errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP, errno.ENOTSUP, errno.EXDEV}
COMMITTED: list[Path] = []
"""Every folder :func:`atomic_output` has put in place in this process, in order."""
MIN_FREE = 1 << 20
"""Free space ``--out`` must offer before any work starts (bytes)."""


class OutputError(EmdmError):
    """An output folder that cannot receive the results; says which folder and why."""

    def __init__(self, out: Path | str, problem: str) -> None:
        self.out, self.problem = Path(out), problem
        super().__init__(one_line(f"{out}: {problem}"))


def _reason(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror[0].lower() + exc.strerror[1:]
    return str(exc) or type(exc).__name__


def _is_mount(path: Path) -> bool:
    """``path`` is a folder on another filesystem than its parent (a mount point, a volume)."""
    try:
        return path.is_dir() and path.stat().st_dev != path.parent.resolve().stat().st_dev
    except OSError:
        return False


def _in_flight(name: str) -> bool:
    """``name`` is a folder a live emdm is working in (:data:`_OURS`)."""
    found = _OURS.match(name)
    return found is not None and _alive(int(found.group(2)))


def _passed_over(folder: Path, name: str) -> bool:
    """An entry of the output folder ``folder`` that is not results: ours in flight, or a mount
    point's lost+found."""
    return _in_flight(name) or (name in IGNORED and _is_mount(folder))


def _entries(folder: Path) -> list[str]:
    """The entries of an output folder that are results (see :func:`_passed_over`)."""
    return sorted(name for name in os.listdir(folder) if not _passed_over(folder, name))


def _size(number: float) -> str:
    for unit in ("bytes", "kB", "MB", "GB"):
        if number < 1000 or unit == "GB":
            return f"{number:.0f} {unit}" if unit == "bytes" else f"{number:.1f} {unit}"
        number /= 1000
    raise AssertionError  # pragma: no cover


def _target(out: Path) -> Path:
    """The folder ``out`` names: absolute, and where a symbolic link points (the link is kept)."""
    try:
        return Path(os.path.realpath(out) if os.path.islink(out) else os.path.abspath(out))
    except ValueError:  # an embedded NUL
        raise OutputError(out, "is not a valid path") from None


def _manifest(folder: Path) -> set[str] | None:
    """The files listed in ``folder``'s :data:`MARKER` (``None`` without one)."""
    try:
        text = (folder / MARKER).read_text(encoding="utf-8", errors="replace")
    except OSError:
        return None
    return {line for line in text.splitlines() if line and not line.startswith("#")}


def _files(folder: Path) -> list[str]:
    """Every file under ``folder`` (POSIX paths, sorted), not counting the marker, lost+found and
    emdm's folders in flight."""
    found = []
    for root, subfolders, files in os.walk(folder):
        here = Path(root).relative_to(folder)
        if root == str(folder):
            subfolders[:] = [d for d in subfolders if not _passed_over(folder, d)]
            files = [f for f in files if f != MARKER and not _passed_over(folder, f)]
        found += [(here / name).as_posix() for name in files]
        found += [(here / d).as_posix() for d in subfolders if os.path.islink(Path(root) / d)]
    return sorted(found)


def _foreign(out: Path, target: Path) -> str:
    """What in the output folder ``target`` (named ``out`` to the user) emdm did not write, against
    the list in its marker ("" when nothing)."""
    try:
        files, entries = _files(target), _entries(target)
    except OSError as exc:
        raise OutputError(out, f"cannot be read ({_reason(exc)})") from None
    listed = _manifest(target)
    if entries and listed is None:
        return f"holds {len(entries)} file(s) or folder(s) emdm did not write (no {MARKER})"
    foreign = [
        name
        for name in files
        if name not in (listed or set()) and Path(name).name not in DESKTOP_FILES
    ]
    if not foreign:
        return ""
    more = f" and {len(foreign) - 1} more" if len(foreign) > 1 else ""
    return f"holds {foreign[0]}{more}, which emdm did not write"


def _recheck(out: Path) -> None:
    """Just before the swap: ``out`` still holds nothing but emdm's results (a file may have been
    put there while the work ran: refused, not replaced). The staging folder, inside ``out`` when
    it is a mount point, is in flight and passed over."""
    if not os.path.lexists(out):
        return
    problem = _foreign(out, out)
    if problem:
        raise OutputError(
            out,
            f"{problem} (it appeared while emdm was working); the new results were not put "
            "in place and the earlier ones are unchanged: move it away and run again",
        )


def check_out(out: Path, *, need: int | None = None) -> None:
    """Check, before any work, that ``out`` can receive results; raise :class:`OutputError` if not.

    ``out`` must be a folder or not exist yet, and not the root. An existing folder is replaced
    as a whole, so it must be empty or written by emdm (it holds :data:`MARKER`) and hold no file
    that emdm did not write there (the marker lists them); every folder in it must be writable
    (the earlier results are removed once the new ones are in). The nearest existing ancestor
    must be a folder in which a folder can be created, and its filesystem must have ``need``
    bytes free (default :data:`MIN_FREE`). Nothing is left behind by the check.
    """
    target = _target(out)
    if target.name in ("", ".", ".."):
        raise OutputError(out, "is the root folder: give a folder below it")
    existing = target
    while not os.path.lexists(existing) and existing != existing.parent:
        existing = existing.parent
    name_max, path_max = _limits(existing)
    for part in (*target.parts, f".{target.name[:80]}.partial-{os.getpid()}-xxxxxxxx"):
        if len(os.fsencode(part)) > name_max:
            raise OutputError(out, f"a folder name in it is longer than {name_max} bytes")
    if len(os.fsencode(str(target))) + 120 > path_max:  # its staging and results inside too
        raise OutputError(out, f"its path is too long (this system allows {path_max} bytes)")
    if os.path.lexists(target):
        if not target.is_dir():
            raise OutputError(out, "exists and is not a folder")
        problem = _foreign(out, target)
        if problem:
            raise OutputError(
                out,
                f"{problem}; emdm replaces its output folder as a whole, so move it away or "
                "give another folder",
            )
        for folder, subfolders, _ in os.walk(target):
            for sub in (folder, *(os.path.join(folder, s) for s in subfolders)):
                if not os.access(sub, os.W_OK | os.X_OK):
                    raise OutputError(
                        out, f"{sub} is read-only: the earlier results in it could not be replaced"
                    )
    ancestor = target.parent
    while not os.path.lexists(ancestor):
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise OutputError(out, f"{ancestor} is not a folder")
    places = [ancestor, target] if _is_mount(target) else [ancestor]
    for place in places:
        try:
            os.rmdir(tempfile.mkdtemp(prefix=f".emdm-probe-{os.getpid()}-", dir=place))
        except OSError as exc:
            raise OutputError(out, f"cannot create folders in {place} ({_reason(exc)})") from None
    free = shutil.disk_usage(places[-1]).free
    need = MIN_FREE if need is None else need
    if free < need:
        raise OutputError(
            out, f"only {_size(free)} free on its filesystem, at least {_size(need)} needed"
        )


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process
        return True
    return True


def _sweep(out: Path) -> None:
    """Tidy what an emdm killed outright (SIGKILL, a power cut) left beside ``out``, or inside it
    (a staging folder or a copy named :data:`_OURS` with the id of a process that is gone): its
    staging folder is removed; the earlier results it had moved aside are put back if ``out`` is missing
    (killed between two renames), else removed (killed after the swap)."""
    pattern = re.compile(rf"\.{re.escape(out.name[:80])}\.(partial|old)-(\d+)-")
    try:
        names = sorted(os.listdir(out.parent))
    except OSError:
        return
    with contextlib.suppress(OSError):  # inside a mount point: staging and copies of dead runs
        for name in os.listdir(out):
            found = _OURS.match(name)
            if found and found.group(1) != "old" and not _alive(int(found.group(2))):
                _remove(out / name)
    for name in names:
        found = pattern.match(name)
        if not found or _alive(int(found.group(2))):
            continue
        left = out.parent / name
        if found.group(1) == "old" and not os.path.lexists(out):
            with contextlib.suppress(OSError):
                os.rename(left, out)
                continue
        _remove(left)


class _Critical:
    """Signals that arrive while results are being swapped in wait until the swap is done."""

    depth = 0
    pending: list[int] = []  # noqa: RUF012


def deferring() -> bool:
    """True while a swap is in progress: a signal handler should call :func:`defer` and return."""
    return _Critical.depth > 0


def defer(signum: int) -> None:
    """Remember ``signum``; it is raised again as soon as the swap is done."""
    _Critical.pending.append(signum)


@contextmanager
def critical_section() -> Iterator[None]:
    """A section that a signal handler honouring :func:`deferring` does not interrupt."""
    _Critical.depth += 1
    try:
        yield
    finally:
        _Critical.depth -= 1
        if not _Critical.depth and _Critical.pending:
            signum = _Critical.pending[0]
            _Critical.pending.clear()
            signal.raise_signal(signum)


def _exchange(a: Path, b: Path) -> None:
    """Swap two paths in one step (Linux ``renameat2(RENAME_EXCHANGE)``); OSError where unsupported."""
    if not sys.platform.startswith("linux"):
        raise OSError(errno.ENOSYS, "renameat2 is Linux only")
    libc = ctypes.CDLL(None, use_errno=True)
    renameat2 = getattr(libc, "renameat2", None)
    if renameat2 is None:
        raise OSError(errno.ENOSYS, "no renameat2 in this C library")
    at_fdcwd, rename_exchange = -100, 2
    if renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange) != 0:
        code = ctypes.get_errno()
        raise OSError(code, os.strerror(code), str(a), None, str(b))


def _remove(path: Path) -> None:
    if os.path.lexists(path):
        shutil.rmtree(path, ignore_errors=True)


def _limits(folder: Path) -> tuple[int, int]:
    """The longest file name and path (bytes) the filesystem of ``folder`` allows."""
    try:
        return os.pathconf(folder, "PC_NAME_MAX"), os.pathconf(folder, "PC_PATH_MAX")
    except (OSError, ValueError):
        return 255, 4096


def _make_parents(folder: Path) -> list[Path]:
    """Create ``folder`` and its missing ancestors; the ones created, outermost first (on a
    failure, the ones it created are removed before the error goes on)."""
    missing = []
    while not os.path.lexists(folder):
        missing.append(folder)
        folder = folder.parent
    created: list[Path] = []
    try:
        for path in reversed(missing):
            path.mkdir()
            created.append(path)
    except OSError:
        for path in reversed(created):
            with contextlib.suppress(OSError):
                path.rmdir()
        raise
    return created


def _swap_entries(new: Path, out: Path) -> None:
    """Replace the entries of ``out`` by those of ``new`` (same filesystem), undoing it all on any
    failure: for an ``out`` that cannot itself be renamed (a mount point)."""
    old = Path(tempfile.mkdtemp(prefix=f".emdm-old-{os.getpid()}-", dir=out))
    moved_old: list[str] = []
    moved_new: list[str] = []
    try:
        for name in _entries(out):
            os.rename(out / name, old / name)
            moved_old.append(name)
        for name in sorted(os.listdir(new)):
            os.rename(new / name, out / name)
            moved_new.append(name)
    except BaseException:
        stuck = []
        for name in reversed(moved_new):
            try:
                os.rename(out / name, new / name)
            except OSError:
                stuck.append(out / name)
        for name in reversed(moved_old):
            try:
                os.rename(old / name, out / name)
            except OSError:
                stuck.append(old / name)
        if stuck:
            raise OutputError(
                out, f"could not undo a failed swap; the earlier results are in {old}"
            ) from None
        _remove(old)
        raise
    _remove(old)


def _copy_and_swap(staging: Path, out: Path) -> None:
    """Copy ``staging`` onto the filesystem of ``out``, then swap the entries in."""
    copy = Path(tempfile.mkdtemp(prefix=f".emdm-copy-{os.getpid()}-", dir=out))
    try:
        shutil.copytree(staging, copy, dirs_exist_ok=True)
        _swap_entries(copy, out)
    finally:
        _remove(copy)


def _commit(staging: Path, out: Path, inside: bool) -> None:
    """Put the staged results in place of ``out`` in one step where the filesystem allows it."""
    if inside:  # staged inside a mount point: swap its entries
        _swap_entries(staging, out)
        return
    if not os.path.lexists(out):
        try:
            os.rename(staging, out)
        except OSError as exc:
            if exc.errno != errno.EXDEV:
                raise
            out.mkdir()
            try:
                _copy_and_swap(staging, out)
            except BaseException:
                _remove(out)
                raise
        return
    try:
        _exchange(staging, out)  # staging now holds the earlier results, removed by the caller
        return
    except OSError as exc:
        if exc.errno not in _NO_EXCHANGE:
            raise
    backup = Path(tempfile.mkdtemp(prefix=f".{out.name[:80]}.old-{os.getpid()}-", dir=out.parent))
    os.rmdir(backup)
    try:
        os.rename(out, backup)
    except OSError as exc:
        if exc.errno not in (errno.EXDEV, errno.EBUSY):
            raise
        _copy_and_swap(staging, out)
        return
    try:
        os.rename(staging, out)
    except BaseException as exc:
        try:
            os.rename(backup, out)
        except OSError:
            raise OutputError(
                out, f"could not put the earlier results back; they are in {backup}"
            ) from None
        if isinstance(exc, OSError) and exc.errno == errno.EXDEV:
            _copy_and_swap(staging, out)
            return
        raise
    _remove(backup)


@contextmanager
def atomic_output(out: Path, *, command: str = "") -> Iterator[Path]:
    """Yield a staging folder; when the block succeeds, its content replaces ``out`` as a whole.

    The staging folder is hidden beside ``out`` (inside it when ``out`` is a mount point), on the
    same filesystem, and swapped in with one rename (``renameat2(RENAME_EXCHANGE)`` on Linux, else
    two renames, undone on failure); where the filesystem refuses (``EXDEV``), the results are
    copied next to the earlier ones first, then swapped in entry by entry, undone on failure. So
    whatever fails, at whatever point, ``out`` holds either the earlier results byte for byte or
    the new ones complete, and no staging folder is left behind. Signals that arrive during the
    swap are deferred (:func:`critical_section`). Raises :class:`OutputError` when ``out`` cannot
    receive results, before the block runs.
    """
    check_out(out, need=0)
    out = _target(out)
    created = _make_parents(out.parent)
    _sweep(out)
    existed = os.path.lexists(out)
    inside = _is_mount(out)
    staging = Path(
        tempfile.mkdtemp(
            prefix=f".emdm-partial-{os.getpid()}-"
            if inside
            else f".{out.name[:80]}.partial-{os.getpid()}-",
            dir=out if inside else out.parent,
        )
    )
    os.chmod(staging, 0o777 & ~_umask())  # mkdtemp makes it private; results are not
    done = False
    try:
        try:
            yield staging
        except OSError as exc:
            if exc.filename is None or _within(exc.filename, (staging, out)):
                raise _write_error(out, existed, exc) from exc
            raise  # not about the results (an input file, say): reported as it is
        try:
            written = _files(staging)
            (staging / MARKER).write_text(
                f"# Written by emdm {_version()}{f' ({command})' if command else ''}. emdm "
                "replaces this folder as a whole when it writes here again,\n# and refuses to "
                "while it holds files not listed here (yours).\n"
                + "".join(f"{name}\n" for name in written),
                encoding="utf-8",
            )
            sys.stdout.flush()  # what the command printed: a failing stdout keeps the old
            with critical_section():  # no signal lands from here to the end of the swap
                check_stop()  # a signal whose exception was dropped: the earlier results stay
                _recheck(out)
                _commit(staging, out, inside)
                done = True
                COMMITTED.append(out)
                _remove(staging)  # after an exchange: the earlier results
        except OSError as exc:
            raise _write_error(out, existed, exc) from exc
    finally:
        _remove(staging)
        if not done:
            for folder in reversed(created):
                try:
                    folder.rmdir()
                except OSError:
                    break


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _write_error(out: Path, existed: bool, exc: OSError) -> OutputError:
    kept = "the earlier results are unchanged" if existed else "nothing was written"
    return OutputError(out, f"could not write the results ({_reason(exc)}); {kept}")


def _within(path: str | bytes | os.PathLike[str], folders: tuple[Path, ...]) -> bool:
    text = os.path.abspath(os.fsdecode(path))
    return any(text.startswith(os.path.abspath(folder)) for folder in folders)


def _version() -> str:
    from .. import __version__

    return __version__


def _float(text: str) -> float:
    return float(text) if text != "" else float("nan")


class RunFolderError(EmdmError):
    """A folder that is not (or no longer) a complete record written by ``emdm run``."""


def read_scenario(folder: Path) -> Any:
    """The scenario of a folder written by ``emdm run`` (from its ``metrics.json``)."""
    from ..core.scenario import scenario_from_dict

    path = Path(folder) / "metrics.json"
    if not path.is_file():
        raise RunFolderError(
            f"{folder}: not a run folder (no metrics.json; write one with emdm run)"
        )
    try:
        meta = json.loads(path.read_text(encoding="utf-8"))
        return scenario_from_dict(meta["scenario"], source=str(path))
    except EmdmError:
        raise
    except (OSError, ValueError, TypeError, KeyError) as exc:
        raise RunFolderError(
            f"{path}: not a metrics.json written by emdm run ({_problem(exc)})"
        ) from None


def _problem(exc: BaseException) -> str:
    if isinstance(exc, KeyError):
        return f"missing {exc}"
    if isinstance(exc, OSError):
        return exc.strerror or str(exc)
    return str(exc).splitlines()[0] if str(exc) else type(exc).__name__


def read_run(folder: Path, controller: str) -> Run:
    """Read back the run of ``controller`` written by ``emdm run`` into ``folder``.

    The CSVs hold every value at full precision, so the arrays equal the simulated ones exactly.
    A file that is truncated, edited out of shape or inconsistent with ``metrics.json`` raises
    :class:`RunFolderError` naming it.
    """
    from ..core.controllers import get_controller

    folder = Path(folder)
    scenario = read_scenario(folder)
    where = folder / "metrics.json"
    try:
        meta = json.loads(where.read_text(encoding="utf-8"))
        steps = int(meta["controllers"][controller]["steps"])
        reached = bool(meta["controllers"][controller]["reached"])
        where = folder / "trajectories" / f"{controller}.csv"
        rows = _rows(
            where,
            trajectory_header(scenario.n, scenario.nt, bool(scenario.obstacles)),
            steps + 1,
        )
        where = folder / "diagnostics" / f"{controller}.csv"
        diag = _rows(where, diagnostics_header(scenario.n, has_rows(scenario)), steps)
        where = folder / "trajectories" / f"{controller}.csv"
        return _run_from_rows(scenario, get_controller(controller), rows, diag, reached)
    except EmdmError:
        raise
    except (OSError, ValueError, TypeError, KeyError, IndexError, csv.Error) as exc:
        raise RunFolderError(
            f"{where}: not a complete run record ({_problem(exc)}); write it again with emdm run"
        ) from None


def _rows(path: Path, header: list[str], count: int) -> list[dict[str, str]]:
    with path.open(encoding="utf-8", newline="") as handle:
        reader = csv.reader(handle)
        found = next(reader, None)
        if found != header:
            raise ValueError("its header is not the one emdm writes")
        rows = list(reader)
    if len(rows) != count:
        raise ValueError(f"{len(rows)} rows where metrics.json says {count}")
    for number, row in enumerate(rows, start=2):
        if len(row) != len(header):
            raise ValueError(f"line {number} has {len(row)} fields, not {len(header)}")
    return [dict(zip(header, row, strict=True)) for row in rows]


def _run_from_rows(
    scenario: Any,
    controller: Any,
    rows: list[dict[str, str]],
    diag: list[dict[str, str]],
    reached: bool,
) -> Run:
    n = scenario.n
    K = len(rows) - 1

    def column(*names: str, last: bool = True) -> np.ndarray:
        used = rows if last else rows[:-1]
        return np.array([[_float(r[name]) for name in names] for r in used]).reshape(
            len(used), len(names)
        )

    joints = [str(i) for i in range(1, n + 1)]
    axes = TASK_AXES[scenario.nt]
    return Run(
        scenario=scenario,
        controller=controller,
        t=column("t")[:, 0],
        q=column(*[f"q{j}" for j in joints]),
        p=column(*axes),
        e=column(*[f"e{a}" for a in axes]),
        v=column(*[f"v{a}" for a in axes]),
        m=column("m")[:, 0],
        qd=column(*[f"qd{j}" for j in joints], last=False).reshape(K, n),
        effort=column("effort", last=False).reshape(K),
        manip_rate=column("manip_rate", last=False).reshape(K),
        alpha=column("alpha", last=False).reshape(K),
        delta=column(*[f"delta_{a}" for a in axes], last=False).reshape(K, len(axes)),
        lo=np.array([[_float(d[f"lo{j}"]) for j in joints] for d in diag]).reshape(K, n),
        hi=np.array([[_float(d[f"hi{j}"]) for j in joints] for d in diag]).reshape(K, n),
        active=np.array(
            [[int(d[f"active{j}"]) for j in joints] for d in diag], dtype=np.int8
        ).reshape(K, n),
        iterations=np.array([int(r["iterations"]) for r in rows[:-1]], dtype=np.int64),
        solve_time=column("solve_time", last=False).reshape(K),
        kkt=np.array([_float(d["kkt_residual"]) for d in diag]).reshape(K),
        bound_excess=np.array([_float(d["bound_excess"]) for d in diag]).reshape(K),
        rows=np.array([int(d.get("rows", 0)) for d in diag], dtype=np.int64).reshape(K),
        rows_active=np.array([int(d.get("rows_active", 0)) for d in diag], dtype=np.int64).reshape(
            K
        ),
        fallback=np.array([d["fallback"] == "True" for d in diag], dtype=bool).reshape(K),
        clearance=column("clearance").reshape(K + 1)
        if scenario.obstacles
        else np.full(K + 1, np.inf),
        solver=[r["solver"] for r in rows[:-1]],
        status=[r["status"] for r in rows[:-1]],
        attempts=[d["attempts"] for d in diag],
        policy=[d["policy"] for d in diag],
        reached=reached,
    )


def write_run_folder(
    folder: Path,
    scenario: Any,
    runs: dict[str, Run],
    *,
    stopped: dict[str, dict[str, Any]] | None = None,
    **meta: Any,
) -> dict[str, dict[str, Any]]:
    """What ``emdm run`` writes: trajectories and diagnostics CSVs, and metrics.json.

    ``stopped`` names the runs that stopped part-way (``{controller: {"step", "reason"}}``): their
    records end at the failing step and their metrics say so (``"stopped"``). Returns the metrics
    of every run (as written)."""
    from .. import __version__
    from ..sim.metrics import metrics

    for name, run in runs.items():
        write_csv(
            folder / "trajectories" / f"{name}.csv",
            trajectory_header(scenario.n, scenario.nt, bool(scenario.obstacles)),
            trajectory_rows(run),
        )
        write_csv(
            folder / "diagnostics" / f"{name}.csv",
            diagnostics_header(scenario.n, has_rows(scenario)),
            diagnostics_rows(run),
        )
    results = {name: metrics(run) for name, run in runs.items()}
    for name, why in (stopped or {}).items():
        if name in results:
            results[name]["stopped"] = dict(why)
    write_json(
        folder / "metrics.json",
        {
            "scenario": scenario.to_dict(),
            **meta,
            "emdm_version": __version__,
            "controllers": results,
        },
    )
    return results
