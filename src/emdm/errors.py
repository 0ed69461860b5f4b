"""Exceptions of emdm. Every error a user can cause is an :class:`EmdmError` with a one-line message."""

from __future__ import annotations

from typing import Any


class EmdmError(Exception):
    """Base class: a problem the user can act on, reported in one line."""


class ScenarioError(EmdmError, ValueError):
    """A scenario (file, preset, override or Python argument) is invalid.

    The message names the source, the key and what is wrong: ``"bad.toml: arm.lengths: must be > 0"``.
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
