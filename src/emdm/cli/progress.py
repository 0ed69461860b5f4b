"""Progress on stderr (tqdm): shown on a terminal, silent otherwise (pipes, logs, tests)."""

from __future__ import annotations

import os
import sys
import threading
from types import TracebackType
from typing import Any

from tqdm import tqdm

from ..errors import check_stop


def shown() -> bool:
    """Progress is drawn when stderr is a terminal (and ``EMDM_PROGRESS`` is not ``0``)."""
    if os.environ.get("EMDM_PROGRESS") == "0":
        return False
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


class Progress:
    """A progress bar whose elapsed time keeps ticking while one long item runs.

    ``total`` may be ``None`` (a count without an end). ``step()`` marks one item done;
    ``note(text)`` says what runs now. Nothing is drawn when :func:`shown` is false.
    """

    def __init__(self, desc: str, total: int | None = None, unit: str = "it") -> None:
        self.enabled = shown()
        self.bar: Any = tqdm(
            total=total,
            desc=desc,
            unit=f" {unit}",
            leave=False,
            disable=not self.enabled,
            file=sys.stderr,
            dynamic_ncols=True,
            bar_format=(
                "{desc}: {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt}{unit} "
                "[{elapsed}<{remaining}] {postfix}"
                if total
                else "{desc}: {n_fmt}{unit} [{elapsed}] {postfix}"
            ),
        )
        self._stop = threading.Event()
        self._ticker: threading.Thread | None = None
        if self.enabled:
            self._ticker = threading.Thread(target=self._tick, name="emdm-progress", daemon=True)
            self._ticker.start()

    def _tick(self) -> None:
        while not self._stop.wait(0.5):
            try:
                self.bar.refresh()
            except Exception:  # a bar closed under our feet: stop ticking
                return

    def note(self, text: str) -> None:
        check_stop()  # a safe point: every long command reports its progress
        if self.enabled:
            self.bar.set_postfix_str(text, refresh=True)

    def step(self, count: int = 1, note: str | None = None) -> None:
        check_stop()
        if note is not None and self.enabled:
            self.bar.set_postfix_str(note, refresh=False)
        self.bar.update(count)

    def close(self) -> None:
        self._stop.set()
        if self._ticker is not None:
            self._ticker.join(timeout=1.0)
        self.bar.close()

    def __enter__(self) -> Progress:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        value: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()


def say(text: str) -> None:
    """A line of information on stderr, only on a terminal (above any progress bar)."""
    if shown():
        tqdm.write(text, file=sys.stderr)
