"""Arguments of the ``emdm`` command line: one name and one meaning per idea, ranges checked by the
parser, and errors in one line (``emdm run: error: --repeats must be >= 1, got 0``)."""

from __future__ import annotations

import argparse
import re
from collections.abc import Callable
from pathlib import Path
from typing import NoReturn

from ..core.controllers import BASELINES, CONTROLLERS, get_controller
from ..core.loading import PRESETS
from ..errors import EmdmError, one_line
from ..solvers import get_solver


class ArgumentsError(EmdmError):
    """A command line that argparse (or a range check) rejects."""

    def __init__(self, prog: str, message: str) -> None:
        self.prog, self.message = prog, message
        super().__init__(one_line(f"{prog}: error: {message} (see {prog} --help)"))


class Parser(argparse.ArgumentParser):
    """argparse raising :class:`ArgumentsError` (one line, exit status 2) instead of exiting."""

    def error(self, message: str) -> NoReturn:
        raise ArgumentsError(self.prog, _tidy(message))


def _tidy(message: str) -> str:
    """``argument --speedup: must be > 0`` -> ``--speedup must be > 0``."""
    found = re.fullmatch(r"argument ([^:]+): (.*)", message, re.S)
    if not found:
        return message
    option, problem = found.group(1).split("/")[0], found.group(2)
    return f"{option} {problem}" if problem.startswith("must") else f"{option}: {problem}"


def _shown(text: str) -> str:
    text = text.strip()
    return text if len(text) <= 24 else f"{text[:12]}...({len(text)} characters)"


def integer(minimum: int, maximum: int | None = None) -> Callable[[str], int]:
    """A whole number in ``[minimum, maximum]``."""

    def parse(text: str) -> int:
        try:
            value = int(text.strip())
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"must be a whole number, got {_shown(text)!r}"
            ) from None
        if value < minimum or (maximum is not None and value > maximum):
            span = f">= {minimum}" if maximum is None else f"between {minimum} and {maximum}"
            raise argparse.ArgumentTypeError(f"must be {span}, got {_shown(text)}")
        return value

    return parse


def positive(maximum: float) -> Callable[[str], float]:
    """A number in ``(0, maximum]``."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be a number, got {_shown(text)!r}") from None
        if not (0 < value <= maximum):  # also false for nan
            raise argparse.ArgumentTypeError(
                f"must be > 0 and at most {maximum:g}, got {_shown(text)}"
            )
        return value

    return parse


def text(what: str, longest: int) -> Callable[[str], str]:
    """One line of printable text, not empty, at most ``longest`` characters."""

    def parse(value: str) -> str:
        from ..outputs.report.config import check_text

        try:
            return check_text(what, value, longest)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    return parse


def names(kind: str) -> Callable[[str], list[str]]:
    """One or more controller or solver names, comma-separated; each checked, case-insensitive."""
    canonical: Callable[[str], str] = (
        (lambda name: get_controller(name).name)
        if kind == "controller"
        else (lambda name: get_solver(name).name)
    )

    def parse(text: str) -> list[str]:
        items = [item.strip() for item in text.split(",")]
        if not any(items):
            raise argparse.ArgumentTypeError(f"must name at least one {kind}, got {text!r}")
        if not all(items):
            raise argparse.ArgumentTypeError(f"has an empty {kind} name in {text!r}")
        try:
            return [canonical(item) for item in items]
        except EmdmError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    return parse


def scenario_name(text: str) -> str:
    """A preset (any case: ``TASK1``) or a path; presets are looked up in lower case."""
    if text.lower() in PRESETS and not Path(text).exists():
        return text.lower()
    return text


def add_scenario(
    parser: argparse.ArgumentParser,
    *,
    run_dir: bool = False,
    default: str | None = None,
    many: bool = False,
) -> None:
    """The scenario argument (a preset or TOML file, optionally a run folder) and ``--set``."""
    what = "a preset (" + ", ".join(PRESETS) + ") or a scenario TOML file"
    if run_dir:
        what += ", or a folder written by emdm run"
    if many:
        parser.add_argument(
            "scenario", nargs="+", type=scenario_name, help=f"{what}; several make a sweep"
        )
    elif default is None:
        parser.add_argument("scenario", type=scenario_name, help=what)
    else:
        parser.add_argument(
            "scenario",
            nargs="?",
            default=default,
            type=scenario_name,
            help=f"{what} (default {default})",
        )
    parser.add_argument(
        "--set",
        action="append",
        metavar="SECTION.KEY=VALUE",
        help="override one scenario value (repeatable), e.g. --set weights.effort=0.2",
    )


def add_out(parser: argparse.ArgumentParser, default: str) -> None:
    parser.add_argument(
        "--out",
        metavar="DIR",
        help=f"output folder, replaced as a whole when the command succeeds (default {default})",
    )


def add_controllers(parser: argparse.ArgumentParser, what: str, default: str = "all four") -> None:
    """``--controller NAME`` (repeatable, or comma-separated), case-insensitive."""
    parser.add_argument(
        "--controller",
        action="extend",
        type=names("controller"),
        metavar="NAME",
        help=f"{what} (repeatable; default {default}; names: "
        f"{', '.join([*CONTROLLERS, *BASELINES])})",
    )


def add_workers(parser: argparse.ArgumentParser, default: str) -> None:
    """``--workers N``: worker processes, everywhere."""
    parser.add_argument(
        "--workers",
        type=integer(1, 256),
        metavar="N",
        help=f"worker processes (default {default})",
    )


def add_quick(parser: argparse.ArgumentParser, what: str) -> None:
    parser.add_argument("--quick", action="store_true", help=f"a reduced run: {what}")
