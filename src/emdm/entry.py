"""The ``emdm`` executable's first lines: a signal while Python still loads emdm (numba takes
about a second) is one line and the signal's exit status, not Python's traceback."""

from __future__ import annotations

import os
import signal
from types import FrameType

STARTING: dict[int, str] = {
    signal.SIGINT: "interrupted",
    signal.SIGTERM: "terminated (SIGTERM)",
    signal.SIGHUP: "hung up (SIGHUP)",
}


def _starting(signum: int, frame: FrameType | None) -> None:
    name = STARTING.get(signum, "stopped")
    os.write(2, f"emdm: {name} while starting; nothing was written\n".encode())
    os._exit(128 + signum)


def console() -> None:
    """Entry point of the ``emdm`` executable and of ``python -m emdm`` (``python -m emdm.cli``
    loads the command line before it can install anything)."""
    for signum in STARTING:
        signal.signal(signum, _starting)
    from .cli.main import console as run  # the command's own boundary takes the signals over

    run()
