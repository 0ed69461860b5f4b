"""The playground's server: Bokeh on 127.0.0.1, BokehJS served from the installed package.

One process, one thread: sessions (browser tabs) take turns on the event loop, each with its own
document. SIGINT (Ctrl-C) and SIGTERM stop the loop; the server then closes its sessions and
sockets and :func:`serve` returns 0.
"""

from __future__ import annotations

import asyncio
import logging
import signal
import sys
import time
import webbrowser
from functools import partial

from bokeh.application import Application
from bokeh.application.handlers.function import FunctionHandler
from bokeh.server.server import Server
from bokeh.server.util import bind_sockets

from ..core.scenario import Scenario
from ..errors import EmdmError
from . import page
from .logic import PAIRS, front, run_pair


def free_port() -> int:
    """A port the system says is free on 127.0.0.1 (for ``--port 0``)."""
    sockets, port = bind_sockets("127.0.0.1", 0)
    for s in sockets:
        s.close()
    return port


def serve(bases: dict[str, Scenario], *, port: int = 5006, open_browser: bool = True) -> int:
    """Serve the playground of ``bases`` (name -> scenario, the first shown) until a signal."""
    for name in ("bokeh", "tornado"):
        logging.getLogger(name).setLevel(logging.ERROR)
    first = next(iter(bases.values()))
    start = time.perf_counter()
    for pair in PAIRS:  # compile and warm everything a page computes before serving
        outcomes = run_pair(first, pair)
        front(first, outcomes[0], 0.0)
    warm = time.perf_counter() - start
    port = port or free_port()
    try:
        server = Server(
            {"/": Application(FunctionHandler(partial(page.build, bases=bases)))},
            address="127.0.0.1",
            port=port,
            allow_websocket_origin=[f"127.0.0.1:{port}", f"localhost:{port}"],
            num_procs=1,
        )
    except OSError as exc:
        raise EmdmError(
            f"cannot listen on 127.0.0.1:{port}: {exc.strerror or exc} "
            "(another --port, or --port 0 for any free one)"
        ) from None
    server.start()
    url = f"http://127.0.0.1:{port}/"
    loop: asyncio.AbstractEventLoop = getattr(server.io_loop, "asyncio_loop")  # noqa: B009
    for sig in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(sig, server.io_loop.stop)
    print(f"emdm play: {url} (warm-up {warm:.1f} s; Ctrl-C to stop)", flush=True)
    if open_browser:
        server.io_loop.add_callback(webbrowser.open, url)
    try:
        server.io_loop.start()
    finally:
        server.stop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.remove_signal_handler(sig)
    print("emdm play: stopped", file=sys.stderr, flush=True)
    return 0
