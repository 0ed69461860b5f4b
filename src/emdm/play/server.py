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
from tornado.httputil import HTTPHeaders, HTTPServerRequest
from tornado.web import OutputTransform

from ..core.scenario import Scenario
from ..errors import EmdmError
from . import page
from .logic import PAIRS, front, run_pair

LOCAL_HOSTS = ("127.0.0.1", "localhost")
"""The only Host headers the server answers: a page from another name that resolves to this
machine (DNS rebinding) gets 403 and nothing of the playground."""


class LoopbackOnly(OutputTransform):
    """Replace every response to a request whose Host is not :data:`LOCAL_HOSTS` by a 403."""

    REFUSAL = b"emdm play answers only http://127.0.0.1 and http://localhost\n"

    def __init__(self, request: HTTPServerRequest) -> None:
        self.refused = request.host_name not in LOCAL_HOSTS

    def transform_first_chunk(
        self, status_code: int, headers: HTTPHeaders, chunk: bytes, finishing: bool
    ) -> tuple[int, HTTPHeaders, bytes]:
        if not self.refused:
            return status_code, headers, chunk
        refused = HTTPHeaders()
        refused["Content-Type"] = "text/plain; charset=utf-8"
        if finishing:
            refused["Content-Length"] = str(len(self.REFUSAL))
        return 403, refused, self.REFUSAL

    def transform_chunk(self, chunk: bytes, finishing: bool) -> bytes:
        return b"" if self.refused else chunk


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
            allow_websocket_origin=[f"{host}:{port}" for host in LOCAL_HOSTS],
            num_procs=1,
            transforms=[LoopbackOnly],
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
