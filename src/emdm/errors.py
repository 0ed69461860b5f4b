"""Exceptions of emdm. Every error a user can cause is an :class:`EmdmError` with a one-line message."""

from __future__ import annotations

import os
import signal
import sys
import threading
from typing import Any


class EmdmError(Exception):
    """Base class: a problem the user can act on, reported in one line."""


class ScenarioError(EmdmError, ValueError):
    """A scenario (file, preset, override or Python argument) is invalid, or an argument of the
    Python API (a wrong type, shape, NaN, sign or name).

    The message names the source, the key and what is wrong: ``"bad.toml: arm.lengths: must be > 0"``;
    for an argument the source is the function and the key the argument:
    ``"simulate: fallback: must be a list of solver names, got 'daqp'"``.
    """

    def __init__(self, source: str, key: str, problem: str) -> None:
        self.source, self.key, self.problem = source, key, problem
        where = f"{source}: {key}" if key else source
        super().__init__(one_line(f"{where}: {problem}"))


def one_line(text: str) -> str:
    """``text`` with control characters (newlines included) escaped, so it prints as one line."""
    return "".join(ch if ch.isprintable() else repr(ch)[1:-1] for ch in text)


class SolverNotFound(EmdmError, KeyError):
    """An unknown solver name; the message lists the installed solvers and how to get the rest."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0])


class NoSolution(EmdmError):
    """A control step has no admissible command (infeasible program under the chosen policy)."""

    def __init__(self, message: str, problem: Any = None, result: Any = None) -> None:
        super().__init__(message)
        self.problem = problem
        self.result = result
        self.run: Any = None  # the run up to the failing step, set by emdm.simulate
        self.controller: str | None = None
        self.step: int | None = None


class Interrupted(KeyboardInterrupt):
    """The command was stopped by the signal ``signum`` (SIGINT, SIGTERM or SIGHUP)."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum


class _Stop:
    signum = 0  # the first stopping signal of this command (0: none)


def request_stop(signum: int) -> None:
    """Record a stopping signal (the signal handler does, before it raises :class:`Interrupted`):
    where its exception lands in a finalizer or a callback, Python drops it, but the record
    stays, and :func:`check_stop` raises it again at the next safe point."""
    if not _Stop.signum:
        _Stop.signum = signum


def clear_stop() -> None:
    """Forget a recorded signal (a new command starts)."""
    _Stop.signum = 0


def check_stop() -> None:
    """A safe point: raise :class:`Interrupted` when a stopping signal has arrived (in the main
    thread only; elsewhere it waits for the main thread's next safe point). Called before results
    are put in place, between chunks of work and when a command returns."""
    if _Stop.signum and threading.current_thread() is threading.main_thread():
        raise Interrupted(_Stop.signum)


def die_with_parent(parent: int) -> None:
    """The initializer of a pool's worker process: the worker is killed when ``parent`` dies, even
    by SIGKILL (which no handler of the parent sees), so no worker outlives its command. Linux:
    ``prctl(PR_SET_PDEATHSIG, SIGKILL)``; elsewhere the pool's own shutdown stops the workers. A
    parent already gone when this runs ends the worker at once."""
    if sys.platform.startswith("linux"):
        import ctypes

        try:
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)  # 1: PR_SET_PDEATHSIG
        except (OSError, AttributeError):  # no prctl here: the pool's shutdown remains
            pass
    if os.getppid() != parent:
        os._exit(1)
