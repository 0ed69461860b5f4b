"""The one error boundary of the command line, and its signals.

Every failure becomes one line on stderr and an exit status: 2 for what the user can act on (the
input, the environment: a full disk, a permission, a missing program; a run that stopped), 1 and
"internal error" only for a bug. SIGINT, SIGTERM and SIGHUP stop the command the same way: worker
processes (process pools, Dask workers, ffmpeg) are stopped, the staging folder is removed, the
earlier results stay, and the exit status is 128 + the signal (130, 143, 129). The handler
records the signal before it raises, so a signal whose exception Python drops (it landed in a
finalizer or a callback) still stops the command at its next safe point
(:func:`emdm.errors.check_stop`: before results are put in place, between chunks, at the end);
a second signal stops it at once.
"""

from __future__ import annotations

import contextlib
import logging
import multiprocessing
import os
import select
import signal
import sys
import time
import warnings
from collections.abc import Callable, Iterator
from types import FrameType
from typing import Any

from ..errors import (
    EmdmError,
    Interrupted,
    NoSolution,
    check_stop,
    clear_stop,
    one_line,
    request_stop,
)
from ..outputs import records
from .args import ArgumentsError

HANDLED: dict[int, str] = {
    signal.SIGINT: "interrupted",
    signal.SIGTERM: "terminated (SIGTERM)",
    signal.SIGHUP: "hung up (SIGHUP)",
}


class RunStopped(EmdmError):
    """A run stopped part-way; what finished was kept (the message says what and where)."""


class _State:
    owner = 0
    stopping = False
    late = False  # a signal came after the command (_late)


# ------------------------------------------------------------------------------ child processes
def _parent_of(pid: int) -> tuple[int, str] | None:
    """``(parent pid, state)`` of ``pid`` from /proc, ``None`` when it is gone."""
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii", errors="replace") as handle:
            fields = handle.read().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return None
    return int(fields[1]), fields[0]


def _helpers() -> set[int]:
    """multiprocessing's resource tracker: it ignores SIGTERM and ends when this process does."""
    from multiprocessing import resource_tracker

    pid = getattr(resource_tracker._resource_tracker, "_pid", None)
    return {pid} if isinstance(pid, int) else set()


def descendants(pid: int | None = None) -> list[int]:
    """Live processes started by ``pid`` (default: this one, not counting multiprocessing's
    resource tracker), at any depth, nearest first."""
    root = os.getpid() if pid is None else pid
    if not os.path.isdir("/proc/self"):
        return [p.pid for p in multiprocessing.active_children() if p.pid is not None]
    parents: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            info = _parent_of(int(entry))
            if info is not None and info[1] != "Z":
                parents.setdefault(info[0], []).append(int(entry))
    helpers = _helpers() if pid is None else set()
    found, queue = [], [root]
    while queue:
        children = [c for c in parents.get(queue.pop(0), []) if c not in helpers]
        found += children
        queue += children
    return found


def _alive(pid: int) -> bool:
    info = _parent_of(pid)
    return info is not None and info[1] != "Z"


def stop_children(grace: float = 2.0) -> None:
    """Stop every process this one started (SIGTERM, then SIGKILL after ``grace`` seconds)."""
    pids = descendants()
    for pid in pids:
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGTERM)
    deadline = time.monotonic() + grace
    while any(_alive(pid) for pid in pids) and time.monotonic() < deadline:
        time.sleep(0.02)
    for pid in pids:
        if _alive(pid):
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
    for child in multiprocessing.active_children():  # reaps the ones multiprocessing started
        child.join(timeout=0.1)


def _no_dask_restarts() -> None:
    """Tell the nannies of this process's Dask clusters not to restart the workers stopped now."""
    spec = sys.modules.get("distributed.deploy.spec")
    if spec is None:
        return
    for cluster in list(spec.SpecCluster._instances):
        for nanny in list(getattr(cluster, "workers", {}).values()):
            with contextlib.suppress(Exception):
                nanny.close_gracefully()


def _close_dask() -> None:
    """Close the Dask clusters a failed or stopped command left open (quietly: their workers may
    be gone already), so that Dask's exit hook does not try again and print a traceback."""
    spec = sys.modules.get("distributed.deploy.spec")
    if spec is None:
        return
    for cluster in list(spec.SpecCluster._instances):
        with contextlib.suppress(Exception):
            cluster.close(timeout=5)
        spec.SpecCluster._instances.discard(cluster)


# ------------------------------------------------------------------------------------ signals
def _handler(signum: int, frame: FrameType | None) -> None:
    if os.getpid() != _State.owner:  # a forked worker process: stop at once, as by default
        os._exit(128 + signum)
    if records.deferring():  # results are being swapped in: finish that first
        records.defer(signum)
        return
    if _State.stopping:  # a second signal: the first one's cleanup hangs, or its exception was
        # dropped where it landed and the work runs on; stop at once (a staging folder left
        # behind is swept by the next command that writes there)
        stop_children(grace=0.0)
        _print(f"emdm: {HANDLED.get(signum, 'stopped')} again; stopped at once")
        os._exit(128 + signum)
    _State.stopping = True
    request_stop(signum)
    logging.disable(logging.CRITICAL)  # workers that vanish are expected now, not news
    for name in ("asyncio", "distributed"):  # a worker stopped while starting is reported by
        logging.getLogger(name).disabled = True  # asyncio when its task is collected, at exit
    warnings.simplefilter("ignore")
    _no_dask_restarts()
    stop_children()
    raise Interrupted(signum)


def _late(signum: int, frame: FrameType | None) -> None:
    """After the command of a process that ends with it: its outcome and exit status are
    decided (and its results in place), so a first signal is ignored rather than let kill the
    process with a status that says it stopped; a second one stops at once."""
    if _State.late:
        os._exit(128 + signum)
    _State.late = True


@contextlib.contextmanager
def handling_signals(final: bool = False) -> Iterator[None]:
    """SIGINT, SIGTERM and SIGHUP raise :class:`Interrupted` (in the main thread only). With
    ``final`` (the ``emdm`` process, which ends with the command), :func:`_late` handles them
    afterwards instead of the handlers in force before."""
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _State.owner, _State.stopping = os.getpid(), False
    previous = {}
    for signum in HANDLED:
        with contextlib.suppress(ValueError, OSError):
            previous[signum] = signal.signal(signum, _handler)
    filters = list(warnings.filters)
    try:
        yield
    finally:
        for signum, old in previous.items():
            signal.signal(signum, _late if final else old)
        if _State.stopping:  # the handler silenced logging and warnings while stopping
            logging.disable(logging.NOTSET)
            warnings.filters[:] = filters  # type: ignore[index]


# ----------------------------------------------------------------------------------- boundary
def _print(line: str) -> None:
    with contextlib.suppress(OSError, ValueError):
        print(one_line(line), file=sys.stderr, flush=True)


def _os_message(exc: OSError) -> str:
    reason = exc.strerror or str(exc) or type(exc).__name__
    reason = reason[0].lower() + reason[1:]
    if exc.filename is None:
        return reason
    where = os.fsdecode(exc.filename)
    if exc.filename2 is not None:
        where += f" -> {os.fsdecode(exc.filename2)}"
    return f"{where}: {reason}"


def _stdout_broken() -> bool:
    """The standard output is a pipe whose reader has gone."""
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        return True
    except (OSError, ValueError, AttributeError):
        pass
    try:
        poller = select.poll()
        poller.register(sys.stdout.fileno(), select.POLLOUT)
        return any(event & select.POLLERR for _, event in poller.poll(0))
    except (OSError, ValueError, AttributeError):
        return False


def _stdout_failed(exc: OSError) -> bool:
    """``exc`` came from writing the standard output (no file name, stdout still unflushed)."""
    if exc.filename is not None:
        return False
    try:
        sys.stdout.flush()
    except OSError:
        return True
    except (ValueError, AttributeError):
        return False
    return False


class _StdoutFailed(Exception):
    """Writing the standard output failed (a full disk, an I/O error)."""

    def __init__(self, error: OSError) -> None:
        super().__init__(str(error))
        self.error = error


class _GuardedStdout:
    """The standard output, whose write errors (other than a closed pipe) say where they come
    from: an ``OSError`` without a file name would otherwise read like a failure of the disk."""

    def __init__(self, stream: Any) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        try:
            return int(self._stream.write(text))
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise _StdoutFailed(exc) from None

    def flush(self) -> None:
        try:
            self._stream.flush()
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise _StdoutFailed(exc) from None

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


def _quiet_stdout() -> None:
    """After a broken pipe on stdout, send what is left to /dev/null (no message at exit)."""
    with contextlib.suppress(OSError, ValueError, AttributeError):
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())


def run_command(command: Callable[[], int], *, final: bool = False) -> int:
    """Run ``command`` inside the boundary; returns the exit status (``final``: the process
    ends with it, :func:`handling_signals`)."""
    records.COMMITTED.clear()
    clear_stop()
    if sys.stdout is None:  # started with its standard output closed (>&-)
        _print(
            "emdm: error: the standard output is closed; nothing was run (send it to /dev/null "
            "to discard what emdm prints)"
        )
        return 2
    try:
        with handling_signals(final):
            try:
                with contextlib.redirect_stdout(_GuardedStdout(sys.stdout)):
                    status = int(command())
                    sys.stdout.flush()  # a full disk or a closed pipe shows here, not at exit
                check_stop()  # a signal whose exception was dropped still stops the command
                return status
            except BaseException as exc:
                _close_dask()
                if not isinstance(exc, KeyboardInterrupt):
                    # a signal whose exception was dropped (in a finalizer, a fork handler)
                    # stopped the workers; the failure that followed is the signal's doing
                    check_stop()
                raise
            finally:
                clear_stop()  # the record is this command's (library calls check it too)
                if descendants():  # nothing this command started outlives it
                    stop_children()
    except SystemExit as exc:  # --help, --version
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
    except ArgumentsError as exc:
        _print(str(exc))
        return 2
    except NoSolution as exc:
        _print(f"emdm: error: run stopped: {exc}")
        return 2
    except EmdmError as exc:
        _print(f"emdm: error: {exc}")
        return 2
    except KeyboardInterrupt as exc:
        signum = exc.signum if isinstance(exc, Interrupted) else signal.SIGINT
        written = ", ".join(str(p) for p in records.COMMITTED)
        outcome = f"{written} was written before that" if written else "nothing was written"
        _print(f"emdm: {HANDLED.get(signum, 'stopped')}; {outcome}")
        return 128 + signum
    except BrokenPipeError as exc:
        if _stdout_broken():  # the reader went away (emdm list | head -1): nothing to say
            _quiet_stdout()
            return 0
        _print(f"emdm: error: a program emdm was writing to has stopped ({_os_message(exc)})")
        return 2
    except MemoryError:
        _print("emdm: error: out of memory (try a shorter motion.max_time or fewer runs)")
        return 2
    except (OSError, _StdoutFailed) as exc:
        if isinstance(exc, _StdoutFailed) or _stdout_failed(exc):
            reason = exc.error if isinstance(exc, _StdoutFailed) else exc
            _quiet_stdout()
            _print(f"emdm: error: cannot write to the standard output: {_os_message(reason)}")
            return 2
        _print(f"emdm: error: {_os_message(exc)}")
        return 2
    except Exception as exc:  # a bug: one line, the traceback on request
        if os.environ.get("EMDM_DEBUG"):
            raise
        _print(
            f"emdm: internal error: {type(exc).__name__}: {exc} (EMDM_DEBUG=1 shows the traceback)"
        )
        return 1
