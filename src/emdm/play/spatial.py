"""The 3-D playground (``emdm play panda``): a viser page on 127.0.0.1, its client served from the
installed package (no CDN).

What it shows comes from :mod:`emdm.play.scene3d` (tested without a browser); this module draws
it and wires the controls. Each tab is a page of its own (:class:`Pages`: viser gives every
client its own scene and panel), with its own settings and runs. Gizmo drags and slider moves are
queued and computed by the page's worker thread at most :data:`RATE` times a second (the last
change always gets computed); the player thread moves the time on. Every callback is guarded: a
failure becomes a line in the status, never a traceback, and never stops the server.
"""

from __future__ import annotations

import contextlib
import http
import io
import math
import signal
import sys
import threading
import time
import webbrowser
from collections.abc import Callable, Iterator, Mapping
from functools import partial
from typing import Any

import numpy as np
import viser
import websockets.asyncio.server as ws_server
from websockets.http11 import Request, Response

from ..core.scenario import Scenario
from ..core.sections import Task
from ..errors import EmdmError
from ..outputs.style import CONTROLLER_STYLE
from .scene3d import (
    CONTROL_KEYS,
    NAMES,
    SPEED_SCALE,
    Computed,
    Session3D,
    obstacle_center,
    segment_instances,
)

LOCAL_HOSTS = ("127.0.0.1", "localhost")
"""The only Host headers the server answers (a page of another name that resolves to this
machine, DNS rebinding, gets 403), and the only origins whose pages may open its websocket."""
REFUSAL = "emdm play answers only http://127.0.0.1 and http://localhost\n"
RATE = 20.0
"""At most this many computations a second while a gizmo or a slider moves."""
FPS = 30.0
"""Frames a second while playing."""
SPEEDS = ("0.25", "0.5", "1", "2", "4")
LINK_RADIUS = 0.022
"""Radius (m) the links are drawn with (a share of a Panda's; scaled with the reach)."""
GHOST_OPACITY = 0.35


# ------------------------------------------------------------------------------- the server
def refused(request: Request, port: int) -> bool:
    """True for a request this server must not answer: a Host other than :data:`LOCAL_HOSTS`
    (DNS rebinding), or a websocket opened by a page of another origin."""
    host = request.headers.get("Host", "")
    name = host.rsplit(":", 1)[0] if not host.endswith("]") else host
    if name.lower() not in LOCAL_HOSTS:
        return True
    origin = request.headers.get("Origin")
    if origin is None:  # not a browser page (curl, a script on this machine)
        return False
    allowed = {f"http://{h}:{port}" for h in LOCAL_HOSTS}
    return origin.lower() not in allowed


@contextlib.contextmanager
def loopback_only(port: Callable[[], int]) -> Iterator[None]:
    """While viser starts its server, wrap the request hook it gives websockets with
    :func:`refused` (viser has no option for it; the hook is read once, when the server
    starts, so the wrapper stays in force after this block)."""
    original = ws_server.serve

    def serve(*args: Any, process_request: Any = None, **kwargs: Any) -> Any:
        def guard(connection: ws_server.ServerConnection, request: Request) -> Response | None:
            if refused(request, port()):
                return connection.respond(http.HTTPStatus.FORBIDDEN, REFUSAL)
            return process_request(connection, request) if process_request else None

        return original(*args, process_request=guard, **kwargs)

    ws_server.serve = serve  # type: ignore[misc,assignment]
    try:
        yield
    finally:
        ws_server.serve = original  # type: ignore[misc]


@contextlib.contextmanager
def quiet() -> Iterator[None]:
    """Keep viser's banner and its "Server stopped" off the standard output, where the
    playground prints its one address line."""
    with contextlib.redirect_stdout(io.StringIO()):
        yield


def start(port: int) -> viser.ViserServer:
    """A viser server on 127.0.0.1:``port`` (0: any free one), answering local names only."""
    bound = {"port": port}
    try:
        with quiet(), loopback_only(lambda: bound["port"]):
            server = viser.ViserServer(
                host="127.0.0.1", port=port, label="emdm play", verbose=False
            )
    except OSError as exc:
        raise EmdmError(f"cannot listen on 127.0.0.1:{port}: {exc.strerror or exc}") from None
    bound["port"] = server.get_port()
    if port and bound["port"] != port:  # viser moves on to the next free port: refuse that
        with quiet():
            server.stop()
        raise EmdmError(
            f"cannot listen on 127.0.0.1:{port}: it is in use "
            "(another --port, or --port 0 for any free one)"
        )
    return server


def serve(bases: Mapping[str, Scenario], *, port: int = 8080, open_browser: bool = True) -> int:
    """Serve the 3-D playground of ``bases`` (name -> spatial scenario, the first shown) until
    SIGINT or SIGTERM; returns 0."""
    began = time.perf_counter()
    session = Session3D(bases)  # compiles and warms what a page computes
    warm = time.perf_counter() - began
    server = start(port)
    pages = Pages(server, bases, session)
    url = f"http://127.0.0.1:{server.get_port()}/"
    stop = threading.Event()
    handlers = {
        sig: signal.signal(sig, lambda signum, frame: stop.set())
        for sig in (signal.SIGINT, signal.SIGTERM)
    }
    try:
        print(f"emdm play: {url} (warm-up {warm:.1f} s; Ctrl-C to stop)", flush=True)
        if open_browser:
            threading.Thread(target=webbrowser.open, args=(url,), daemon=True).start()
        while not stop.wait(0.5):
            pass
    finally:
        pages.close()
        with quiet():
            server.stop()
        for sig, handler in handlers.items():
            signal.signal(sig, handler)
    print("emdm play: stopped", file=sys.stderr, flush=True)
    return 0


# --------------------------------------------------------------------------------- meshes
def cylinder_mesh(segments: int = 20) -> tuple[np.ndarray, np.ndarray]:
    """A closed cylinder of radius 1 and height 1 along ``z``, centred at the origin."""
    a = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    ring = np.stack((np.cos(a), np.sin(a)), axis=1)
    bottom = np.hstack((ring, np.full((segments, 1), -0.5)))
    top = np.hstack((ring, np.full((segments, 1), 0.5)))
    vertices = np.vstack((bottom, top, [[0, 0, -0.5], [0, 0, 0.5]]))
    faces = []
    for i in range(segments):
        j = (i + 1) % segments
        faces += [[i, j, segments + j], [i, segments + j, segments + i]]
        faces += [[2 * segments, j, i], [2 * segments + 1, segments + i, segments + j]]
    return vertices.astype(np.float32), np.array(faces, dtype=np.uint32)


def sphere_mesh(rings: int = 10, segments: int = 16) -> tuple[np.ndarray, np.ndarray]:
    """A sphere of radius 1 (latitude and longitude lines)."""
    theta = np.linspace(0.0, np.pi, rings + 1)
    phi = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    vertices = np.stack((np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)), axis=-1)
    faces = []
    for r in range(rings):
        for s in range(segments):
            a, b = r * segments + s, r * segments + (s + 1) % segments
            c, d = a + segments, b + segments
            faces += [[a, c, b], [b, c, d]]
    return vertices.reshape(-1, 3).astype(np.float32), np.array(faces, dtype=np.uint32)


def rgb(color: str) -> tuple[int, int, int]:
    """``#RRGGBB`` as integers."""
    value = color.lstrip("#")
    return int(value[0:2], 16), int(value[2:4], 16), int(value[4:6], 16)


def controller_color(name: str) -> tuple[int, int, int]:
    """The figures' colour of a controller (:data:`emdm.outputs.style.CONTROLLER_STYLE`)."""
    return rgb(CONTROLLER_STYLE.get(name, {}).get("color", "#777777"))


def segments_of(path: np.ndarray) -> np.ndarray:
    """Consecutive points of ``path`` ``(K, 3)`` as line segments ``(K - 1, 2, 3)``."""
    if len(path) < 2:
        return np.zeros((1, 2, 3), dtype=np.float32)
    return np.stack((path[:-1], path[1:]), axis=1).astype(np.float32)


# ----------------------------------------------------------------------------------- page
class Pages:
    """A :class:`Page` for every tab of ``server``, opened when the tab connects (the first on
    the session the server warmed up with) and closed when it leaves."""

    def __init__(
        self, server: viser.ViserServer, bases: Mapping[str, Scenario], first: Session3D
    ) -> None:
        self.server, self.bases = server, dict(bases)
        self.pages: dict[int, Page] = {}
        self.lock = threading.Lock()
        self.spare: Session3D | None = first
        server.on_client_connect(self.opened)
        server.on_client_disconnect(self.closed)

    def opened(self, client: viser.ClientHandle) -> None:
        with self.lock:
            session, self.spare = self.spare, None
        try:
            page = Page(self.server, session or Session3D(self.bases), client=client)
        except Exception as exc:  # a tab that cannot be drawn must not stop the server
            print(f"emdm play: a tab could not be opened: {exc}", file=sys.stderr, flush=True)
            return
        with self.lock:
            self.pages[client.client_id] = page

    def closed(self, client: viser.ClientHandle) -> None:
        with self.lock:
            page = self.pages.pop(client.client_id, None)
        if page is not None:
            page.close()

    def close(self) -> None:
        with self.lock:
            pages, self.pages = list(self.pages.values()), {}
        for page in pages:
            page.close()


class Page:
    """The scene and the panel of one tab (``client``; without it, of every tab of ``server``),
    drawn from a :class:`Session3D`.

    :meth:`set_goal`, :meth:`move_obstacle`, :meth:`set_override`, ... queue a change as the
    page's controls do; :meth:`flush` computes the queued changes at once (tests call it)."""

    def __init__(
        self,
        server: viser.ViserServer,
        session: Session3D,
        *,
        client: viser.ClientHandle | None = None,
    ) -> None:
        self.server, self.client = server, client
        self.target: viser.ViserServer | viser.ClientHandle = server if client is None else client
        self.session = session
        self.lock = threading.RLock()
        self.pending: dict[str, Callable[[], bool]] = {}
        self.wake = threading.Event()
        self.closing = False
        self.playing = False
        self.place = False
        self.t = session.computed.duration if session.computed else 0.0
        self.duration = self.t
        self.note = ""
        self.failures = 0
        self.accepted = True  # the outcome of the last flush
        self.cylinder = cylinder_mesh()
        self.sphere = sphere_mesh()
        self.nodes: dict[str, Any] = {}
        self.obstacle_nodes: list[Any] = []
        self._gui()
        self._scene()
        self.draw()
        self.worker = threading.Thread(target=self._work, name="emdm-play3d", daemon=True)
        self.player = threading.Thread(target=self._play, name="emdm-play3d-clock", daemon=True)
        self.worker.start()
        self.player.start()

    # ------------------------------------------------------------------- guarded calls
    def guarded(self, what: str, action: Callable[[], object]) -> None:
        """Run ``action``; an exception becomes the status line ``what failed: ...``."""
        try:
            action()
        except Exception as exc:  # a callback must never kill the server
            self.failures += 1
            self.note = f"{what} failed: {type(exc).__name__}: {exc}".splitlines()[0][:300]
            with contextlib.suppress(Exception):
                self.status.content = self._status_text()

    def callback(self, what: str, action: Callable[[Any], None]) -> Callable[[Any], None]:
        """A viser callback running ``action(event)`` guarded."""

        def run(event: Any) -> None:
            self.guarded(what, lambda: action(event))

        return run

    # --------------------------------------------------------------------- changes
    def change(self, key: str, apply: Callable[[], bool]) -> None:
        """Queue ``apply`` (a change of the session's settings) under ``key``: a later change
        of the same key replaces it; the worker computes at most :data:`RATE` times a second."""
        with self.lock:
            self.pending[key] = apply
        self.wake.set()

    def flush(self) -> bool:
        """Apply the queued changes, compute and draw now; True when the session accepted them.

        With nothing queued (the worker took the changes first) it is the last outcome."""
        with self.lock:
            changes, self.pending = list(self.pending.values()), {}
            if not changes:
                return self.accepted
            refusals = [self.session.error for apply in changes if not apply()]
            accepted = self.session.compute()
            if refusals:  # a change refused before the computation (a malformed value)
                self.session.error, accepted = refusals[-1], False
            self.note = ""
            if self.place:
                self._place()
            self.draw(geometry=accepted)
            self.accepted = accepted
            return accepted

    def set_goal(self, position: Any, wxyz: Any = None, *, gizmo: bool = False) -> None:
        """The goal at ``position`` with orientation ``wxyz``; the goal gizmo is moved there
        unless the change comes from it (``gizmo``)."""

        def apply() -> bool:
            self.place = self.place or not gizmo
            return self.session.set_goal(position, wxyz, compute=False)

        self.change("goal", apply)

    def move_obstacle(self, index: int, center: Any, *, gizmo: bool = False) -> None:
        """Obstacle ``index`` to ``center``; its gizmo follows unless the change comes from it."""

        def apply() -> bool:
            self.place = self.place or not gizmo
            return self.session.move_obstacle(index, center, compute=False)

        self.change(f"obstacle {index}", apply)

    def _place(self) -> None:
        """The gizmos where the session's goal and obstacles are."""
        self.place = False
        self.goal.position = tuple(self.session.goal()[:3])
        self.goal.wxyz = tuple(self.session.goal_wxyz())
        for gizmo, center in zip(self.obstacle_nodes, self.session.centers(), strict=True):
            gizmo.position = center

    def set_override(self, key: str, value: Any) -> None:
        s = self.session
        self.change(key, lambda: s.set_override(key, value, compute=False))

    def _work(self) -> None:
        last = -math.inf
        while True:
            self.wake.wait()
            if self.closing:
                return
            pause = last + 1.0 / RATE - time.monotonic()
            if pause > 0:
                time.sleep(pause)
            self.wake.clear()
            last = time.monotonic()
            self.guarded("the computation", self.flush)

    def _play(self) -> None:
        before = time.monotonic()
        while not self.closing:
            time.sleep(1.0 / FPS)
            now = time.monotonic()
            elapsed, before = now - before, now
            if self.playing:
                self.guarded("playing", partial(self._advance, elapsed))

    def _advance(self, elapsed: float) -> None:
        with self.lock:
            computed = self.session.computed
            if computed is None:
                return
            self.t = min(self.t + elapsed * float(self.speed.value), computed.duration)
            if self.t >= computed.duration:
                self.playing = False
                self.play.label = "Play"
            self._show_time()

    def close(self) -> None:
        """Stop the worker and the player (the server is stopped by its owner)."""
        self.closing = True
        self.wake.set()
        self.worker.join(timeout=2.0)
        self.player.join(timeout=2.0)

    # ------------------------------------------------------------------------ panel
    def _gui(self) -> None:
        gui = self.target.gui
        s = self.session
        gui.configure_theme(control_width="medium", show_share_button=False)
        self.intro = gui.add_markdown("")
        with gui.add_folder("Time"):
            self.time = gui.add_slider("t (s)", 0.0, 1.0, 0.01, 0.0)
            self.play = gui.add_button("Play")
            self.speed = gui.add_dropdown("speed (x)", SPEEDS, initial_value="1")
            self.frame_line = gui.add_markdown("")
        with gui.add_folder("Status"):
            self.status = gui.add_markdown("")
            self.plot = gui.add_uplot(
                data=(np.zeros(2), np.zeros(2), np.zeros(2)),
                series=(
                    {"label": "t (s)"},
                    {"label": "first", "stroke": "#0072B2", "width": 2},
                    {"label": "ghost", "stroke": "#D55E00", "width": 2, "dash": (6.0, 4.0)},
                ),
                title="manipulability m(t)",
                scales={"x": {"time": False}},
                aspect=1.6,
            )
        with gui.add_folder("Scene"):
            names = tuple(s.bases)
            self.scenario = gui.add_dropdown("scenario", names, initial_value=s.settings.scenario)
            self.first = gui.add_dropdown(
                "controller", NAMES, initial_value=s.settings.controllers[0]
            )
            self.second = gui.add_dropdown("ghost", NAMES, initial_value=s.settings.controllers[1])
            self.reset = gui.add_button("Reset goal, obstacles, sliders")
        with gui.add_folder("Weights and limits"):
            self.sliders: dict[str, Any] = {}
            for name, control in CONTROL_KEYS.items():
                label = {
                    "w_E": "log10 w_E",
                    "w_M": "log10 w_M (left: 0)",
                    "influence": "damper influence (rad)",
                }[name]
                value = control.to_slider(s.value(control.key))
                self.sliders[name] = gui.add_slider(
                    label, control.start, control.end, control.step, value
                )
            low, high, step = SPEED_SCALE
            self.limits = gui.add_slider("velocity limits (x)", low, high, step, 1.0)

        self.time.on_update(self.callback("the time slider", self._scrub))
        self.play.on_click(self.callback("Play", self._toggle))
        self.scenario.on_update(self.callback("the scenario", self._select))
        self.first.on_update(self.callback("the controller", self._controllers))
        self.second.on_update(self.callback("the ghost", self._controllers))
        self.reset.on_click(self.callback("Reset", self._reset))
        for name, slider in self.sliders.items():
            control = CONTROL_KEYS[name]

            def moved(event: Any, control: Any = control, slider: Any = slider) -> None:
                if event.client is None:  # set by the page itself
                    return
                self.set_override(control.key, control.from_slider(float(slider.value)))

            slider.on_update(self.callback(name, moved))

        def limits(event: Any) -> None:
            if event.client is not None:
                value = float(self.limits.value)
                self.change("speed", lambda: self.session.set_speed(value, compute=False))

        self.limits.on_update(self.callback("the velocity limits", limits))

    def _scrub(self, event: Any) -> None:
        if event.client is None:  # the player or a computation moved it
            return
        with self.lock:
            self.t = float(self.time.value)
            self._show_time()

    def _toggle(self, event: Any) -> None:
        with self.lock:
            computed = self.session.computed
            if self.playing:
                self.playing = False
                self.play.label = "Play"
                return
            if computed is not None and self.t >= computed.duration - 1e-9:
                self.t = 0.0
            self.playing = True
            self.play.label = "Pause"

    def _select(self, event: Any) -> None:
        if event.client is None:
            return
        name = str(self.scenario.value)
        with self.lock:
            self.pending.clear()
            accepted = self.session.select(name)
            self._rebuild(accepted)

    def _reset(self, event: Any) -> None:
        with self.lock:
            self.pending.clear()
            accepted = self.session.reset()
            self._rebuild(accepted)

    def _controllers(self, event: Any) -> None:
        if event.client is None:
            return
        first, second = str(self.first.value), str(self.second.value)
        self.change(
            "controllers", lambda: self.session.set_controllers(first, second, compute=False)
        )

    def _rebuild(self, accepted: bool) -> None:
        """After another scenario or a reset: the scene's nodes and the sliders anew."""
        s = self.session
        self.scenario.value = s.settings.scenario  # type: ignore[misc]  # the one shown
        for name, control in CONTROL_KEYS.items():
            self.sliders[name].value = control.to_slider(s.value(control.key))
        self.limits.value = 1.0  # type: ignore[misc]  # viser's setter; mypy sees the getter
        computed = s.computed
        self.t = computed.duration if computed else 0.0
        self._scene()
        self.draw(geometry=accepted)
        self.accepted = accepted

    # ------------------------------------------------------------------------ scene
    def _scene(self) -> None:
        """Every node of the scene for the session's scenario (replacing those there)."""
        scene = self.target.scene
        s = self.session
        computed = s.computed
        assert computed is not None
        scenario = computed.scenario
        reach = scenario.reach
        radius = LINK_RADIUS * reach / 1.4
        self.radius = radius
        for node in self.obstacle_nodes:
            with contextlib.suppress(Exception):
                node.remove()
        self.obstacle_nodes = []
        scene.add_grid(
            "/grid",
            width=2.0 * reach,
            height=2.0 * reach,
            cell_size=0.1,
            section_size=0.5,
            plane="xy",
        )
        start = scenario.serial_arm.joint_positions(scenario.motion.q0)
        self.nodes["start"] = scene.add_line_segments(
            "/start", segments_of(start), (150, 150, 150), thickness=2.0, thickness_units="screen"
        )
        count = len(start)
        identity = np.tile(np.array([1.0, 0, 0, 0], dtype=np.float32), (count, 1))
        for i, opacity in enumerate((None, GHOST_OPACITY)):
            self.nodes[f"links{i}"] = scene.add_batched_meshes_simple(
                f"/arm{i}/links",
                *self.cylinder,
                identity[:-1],
                np.zeros((count - 1, 3)),
                batched_scales=np.zeros((count - 1, 3)),
                batched_colors=(40, 40, 40),
                opacity=opacity,
                lod="off",
                cast_shadow=False,
                receive_shadow=False,
            )
            self.nodes[f"joints{i}"] = scene.add_batched_meshes_simple(
                f"/arm{i}/joints",
                *self.sphere,
                identity,
                np.zeros((count, 3)),
                batched_scales=np.full(count, 1.35 * radius),
                batched_colors=(40, 40, 40),
                opacity=opacity,
                lod="off",
                cast_shadow=False,
                receive_shadow=False,
            )
            self.nodes[f"path{i}"] = scene.add_line_segments(
                f"/path{i}",
                segments_of(np.zeros((0, 3))),
                (0, 0, 0),
                thickness=3.0,
                thickness_units="screen",
            )
        self.nodes["ellipsoid"] = scene.add_icosphere(
            "/ellipsoid",
            1.0,
            (86, 180, 233),
            opacity=0.25,
            subdivisions=3,
            cast_shadow=False,
            receive_shadow=False,
        )
        goal = s.goal()
        pose = scenario.motion.task == Task.POSE
        self.goal = scene.add_transform_controls(
            "/goal",
            scale=0.13 * reach,
            position=goal[:3],
            wxyz=s.goal_wxyz(),
            disable_rotations=not pose,
            depth_test=False,
        )
        if pose:
            scene.add_frame("/goal/axes", axes_length=0.09 * reach, axes_radius=0.006 * reach)
        else:
            scene.add_icosphere("/goal/dot", 0.02 * reach, (255, 215, 0))

        def goal_moved(event: Any) -> None:
            self.set_goal(np.array(self.goal.position), np.array(self.goal.wxyz), gizmo=True)

        self.goal.on_update(self.callback("the goal", goal_moved))
        stop = scenario.obstacle_damper.stop
        for o, (obstacle, center) in enumerate(zip(scenario.obstacles, s.centers(), strict=True)):
            gizmo = scene.add_transform_controls(
                f"/obstacle{o}",
                scale=0.09 * reach,
                position=center,
                disable_rotations=True,
                depth_test=False,
            )
            body = scene.add_frame(f"/obstacle{o}/body", show_axes=False)
            ends = np.array([obstacle.a, obstacle.b]) - obstacle_center(obstacle)
            for e, end in enumerate(ends if obstacle.shape == "capsule" else ends[:1]):
                scene.add_icosphere(
                    f"/obstacle{o}/body/end{e}", obstacle.radius, (213, 60, 40), position=end
                )
                scene.add_icosphere(
                    f"/obstacle{o}/body/stop{e}",
                    obstacle.radius + stop,
                    (213, 60, 40),
                    opacity=0.18,
                    position=end,
                    cast_shadow=False,
                    receive_shadow=False,
                )
            if obstacle.shape == "capsule":
                centres, quats, scales = segment_instances(ends, obstacle.radius)
                scene.add_cylinder(
                    f"/obstacle{o}/body/shaft",
                    obstacle.radius,
                    float(scales[0, 2]),
                    (213, 60, 40),
                    position=centres[0],
                    wxyz=quats[0],
                )

            def obstacle_moved(event: Any, o: int = o, gizmo: Any = gizmo) -> None:
                self.move_obstacle(o, np.array(gizmo.position), gizmo=True)

            gizmo.on_update(self.callback(f"obstacle {o + 1}", obstacle_moved))
            self.obstacle_nodes += [gizmo]
            self.nodes[f"body{o}"] = body
        self._camera()
        drag = "the **goal** gizmo" + (" and the **red obstacles**" if scenario.obstacles else "")
        self.intro.content = (
            f"Drag {drag}: both controllers run again. Solid arm: the controller; translucent: "
            "the ghost; lines: their end effectors; blue: the manipulability ellipsoid."
        )

    def _camera(self) -> None:
        """The first view of every tab (and of open tabs, after another scenario)."""
        position, look = self.session.camera()
        clients = [self.client] if self.client is not None else self.server.get_clients().values()
        if self.client is None:
            self.server.initial_camera.position = tuple(position)
            self.server.initial_camera.look_at = tuple(look)
            self.server.initial_camera.up = (0.0, 0.0, 1.0)
        for client in clients:
            with contextlib.suppress(Exception):
                client.camera.position = tuple(position)
                client.camera.look_at = tuple(look)
                client.camera.up_direction = (0.0, 0.0, 1.0)

    # ------------------------------------------------------------------------- draw
    def draw(self, geometry: bool = True) -> None:
        """Everything a computation changes (``geometry``: the runs, paths, plot; else only
        the status), then the frame at the page's time."""
        with self.lock:
            computed = self.session.computed
            assert computed is not None
            if geometry:
                self._draw_runs(computed)
            self.status.content = self._status_text()
            self._show_time()

    def _draw_runs(self, computed: Computed) -> None:
        names = [o.name for o in computed.outcomes]
        for i, (name, path) in enumerate(zip(names, computed.paths, strict=True)):
            color = controller_color(name)
            node = self.nodes[f"path{i}"]
            node.points = segments_of(path)
            node.colors = np.tile(np.array(color, dtype=np.uint8), (max(len(path) - 1, 1), 2, 1))
            self.nodes[f"links{i}"].batched_colors = np.array(color, dtype=np.uint8)
            self.nodes[f"joints{i}"].batched_colors = np.array(
                [min(255, int(c * 0.7)) for c in color], dtype=np.uint8
            )
        m0, m1 = (np.nan_to_num(m, nan=0.0) for m in computed.m)
        t = computed.t if computed.t.size >= 2 else np.zeros(2)
        if computed.t.size < 2:
            m0, m1 = np.zeros(2), np.zeros(2)
        self.plot.series = (
            {"label": "t (s)"},
            {
                "label": names[0],
                "stroke": CONTROLLER_STYLE.get(names[0], {}).get("color", "#777"),
                "width": 2,
            },
            {
                "label": f"{names[1]} (ghost)",
                "stroke": CONTROLLER_STYLE.get(names[1], {}).get("color", "#777"),
                "width": 2,
                "dash": (6.0, 4.0),
            },
        )
        self.plot.data = (t, m0, m1)
        duration = max(computed.duration, computed.scenario.motion.dt)
        self.time.max = duration
        self.time.step = computed.scenario.motion.dt
        at_end = self.t >= self.duration - 1e-9  # the end stays shown: the runs' final poses
        self.duration = computed.duration
        self.t = computed.duration if at_end else min(self.t, computed.duration)

    def _status_text(self) -> str:
        s = self.session
        computed = s.computed
        parts = []
        if s.error:
            parts.append(f"**refused** ({s.error}); showing the last valid runs.")
        if self.note:
            parts.append(f"**{self.note}**")
        if computed is not None:
            w = computed.scenario.weights
            parts.append(
                f"{computed.scenario.name}: w_E = {w.effort:g}, w_M = {w.manipulability:g}; "
                f"both runs in {1000 * computed.seconds:.0f} ms"
            )
            parts.append(computed.status)
        return "\n\n".join(parts)

    def _show_time(self) -> None:
        """The arms, the ellipsoid and the moving obstacles at the page's time."""
        frame = self.session.frame(self.t)
        value = round(frame.t, 6)
        if abs(float(self.time.value) - value) > 1e-9:
            self.time.value = value  # type: ignore[misc]  # viser's setter; mypy sees the getter
        self.frame_line.content = frame.line
        for i, arm in enumerate(frame.arms):
            centres, quats, scales = segment_instances(arm, self.radius)
            links = self.nodes[f"links{i}"]
            links.batched_positions = centres.astype(np.float32)
            links.batched_wxyzs = quats.astype(np.float32)
            links.batched_scales = scales.astype(np.float32)
            self.nodes[f"joints{i}"].batched_positions = arm.astype(np.float32)
        ellipsoid = self.nodes["ellipsoid"]
        if frame.ellipsoid is None:
            ellipsoid.visible = False
        else:
            ellipsoid.visible = True
            ellipsoid.position = tuple(frame.ellipsoid.center)
            ellipsoid.wxyz = tuple(frame.ellipsoid.wxyz)
            ellipsoid.scale = tuple(float(a) for a in np.maximum(frame.ellipsoid.axes, 1e-4))
        scenario = self.session.scenario
        for o, obstacle in enumerate(scenario.obstacles):
            if np.any(obstacle.velocity != 0.0):
                self.nodes[f"body{o}"].position = tuple(obstacle.velocity * frame.t)


__all__ = ["LOCAL_HOSTS", "Page", "refused", "serve", "start"]
