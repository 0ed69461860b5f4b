"""emdm play for spatial arms: the 3-D page's logic without a browser, its viser page in this
process, its server as a process, and the page in headless Chromium (WebGL by SwiftShader)."""

from __future__ import annotations

import io
import math
import re
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request
import warnings
from types import SimpleNamespace

import numpy as np
import pytest
from conftest import headless_chromium

import emdm
from emdm.cli import main
from emdm.core.kernels import rotation_matrix
from emdm.core.loading import PRESETS
from emdm.play import scene3d
from emdm.play.scene3d import Session3D


@pytest.fixture(scope="module")
def bases():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return {name: emdm.load_scenario(name) for name in ("panda", "panda-obstacles", "ur5")}


def final_points(session: Session3D) -> list[np.ndarray]:
    assert session.computed is not None
    return [o.run.p[-1, :3] for o in session.computed.outcomes if o.run is not None]


# ----------------------------------------------------------------------- logic, no browser
def test_a_goal_change_redraws_the_scene_and_the_runs_end_nearer_it(bases):
    s = Session3D(bases, "panda")
    before = s.frame(s.computed.duration)
    old_paths = [p.copy() for p in s.computed.paths]
    old_ends = final_points(s)
    goal = s.goal()
    new = goal[:3] + np.array([0.05, -0.2, 0.05])
    assert s.set_goal(new, s.goal_wxyz()) and s.error == ""
    after = s.frame(s.computed.duration)
    assert np.allclose(s.scenario.motion.goal[:3], new)
    assert np.allclose(s.scenario.motion.goal[3:], goal[3:], atol=1e-9)  # the orientation kept
    for old, end in zip(old_ends, final_points(s), strict=True):
        assert np.linalg.norm(end - new) < 0.5 * np.linalg.norm(old - new)
    assert not np.allclose(before.arms[0], after.arms[0])
    assert all(
        p.shape != q.shape or not np.allclose(p, q)
        for p, q in zip(old_paths, s.computed.paths, strict=True)
    )
    # the drawn arm ends where the record's end effector is; the ellipsoid sits there
    run = s.computed.outcomes[0].run
    assert np.allclose(after.arms[0][-1], run.p[-1, :3])
    assert np.allclose(after.ellipsoid.center, run.p[-1, :3])
    assert "C-EMDM" in s.computed.status and "C-IVKC" in s.computed.status


def test_refused_changes_become_messages_and_keep_the_last_runs(bases):
    s = Session3D(bases, "panda-obstacles")
    shown = s.computed
    assert not s.set_override("weights.effort", -1.0)
    assert s.error.startswith("weights.effort") and s.computed is shown
    assert s.set_override("weights.effort", 0.01) and s.error == ""
    start = s.scenario.serial_arm.joint_positions(s.scenario.motion.q0)
    assert not s.move_obstacle(0, start[4])  # onto the arm at the start: the damper forbids it
    assert s.error.startswith("obstacles[0]") and "stop distance" in s.error
    assert s.move_obstacle(0, start[4] + [0.0, 0.4, 0.3]), s.error
    assert not s.set_goal([math.nan, 0.0, 0.5])
    assert "goal" in s.error
    assert s.set_goal(s.bases["panda-obstacles"].motion.goal[:3])
    assert not s.set_controllers("C-EMDM", "nosuch") and "nosuch" in s.error
    assert s.set_controllers("C-EMDM", "C-IVKC")
    assert not s.set_override("motion.max_time", 1e6) and "at most" in s.error
    assert s.set_override("motion.max_time", 30.0)
    assert not s.select("task1") and "unknown" in s.error
    assert s.set_controllers("UC-EMDM", "C-EMDM")
    assert [o.name for o in s.computed.outcomes] == ["UC-EMDM", "C-EMDM"]


def test_the_pose_and_the_position_goal(bases):
    s = Session3D(bases, "ur5")
    wxyz = scene3d.quat_from_rotvec([0.0, 0.0, 0.5])
    assert s.set_goal([-0.3, -0.4, 0.5], wxyz)
    assert np.allclose(s.scenario.motion.goal, [-0.3, -0.4, 0.5, 0.0, 0.0, 0.5])
    position = {
        "p": bases["panda"].with_overrides(
            {"motion.task": "position", "motion.goal": [0.5, 0.2, 0.4]}
        )
    }
    p = Session3D(position)
    assert p.set_goal([0.45, 0.1, 0.5], wxyz)  # a position task ignores the orientation
    assert np.allclose(p.scenario.motion.goal, [0.45, 0.1, 0.5])


def test_rotations_and_link_cylinders():
    rng = np.random.default_rng(3)
    for _ in range(20):
        r = rng.normal(size=3)
        r *= rng.uniform(0, 3.1) / np.linalg.norm(r)
        q = scene3d.quat_from_rotvec(r)
        assert np.allclose(scene3d.rotvec_from_quat(q), r)
        assert np.allclose(scene3d.rotvec_from_quat(-q), r)
        R = np.empty((3, 3))
        rotation_matrix(*r, R)
        m = scene3d.quat_from_matrix(R)
        assert np.allclose(m, q) or np.allclose(m, -q)
        assert np.allclose(scene3d.rotation(q), R)
    points = np.vstack(([0.0, 0, 0], rng.normal(size=(6, 3)), [[0, 0, 0], [0, 0, -1]]))
    points[3] = points[2]  # a link of no length
    centres, quats, scales = scene3d.segment_instances(points, 0.03)
    for a, b, c, q, s in zip(points[:-1], points[1:], centres, quats, scales, strict=True):
        assert np.allclose(c, (a + b) / 2)
        length = np.linalg.norm(b - a)
        if length == 0:
            assert not s.any()
            continue
        R = np.empty((3, 3))
        rotation_matrix(*scene3d.rotvec_from_quat(q), R)
        assert np.allclose(R[:, 2] * length, b - a) and np.allclose(s, [0.03, 0.03, length])


def test_the_ellipsoid_is_the_translational_one(bases):
    s = Session3D(bases, "panda")
    q = s.scenario.motion.q0
    e = s.ellipsoid(q)
    J = s.scenario.serial_arm.position_jacobian(q)
    M = e.rotation @ np.diag((e.axes / s.scale) ** 2) @ e.rotation.T
    assert np.allclose(M, J @ J.T)
    assert np.isclose(e.axes.max(), scene3d.ELLIPSOID_SHARE * s.scenario.reach)


# ------------------------------------------------------------------------ the viser page
@pytest.fixture
def page(bases):
    spatial = pytest.importorskip("emdm.play.spatial")
    server = spatial.start(0)
    page = spatial.Page(server, Session3D(bases, "panda-obstacles"))
    yield page
    page.close()
    with spatial.quiet():
        server.stop()


def test_the_page_draws_the_session_and_survives_failures(page):
    path = page.nodes["path0"].points.copy()
    goal = page.session.goal()
    page.set_goal(goal[:3] + np.array([0.0, -0.15, 0.0]), page.session.goal_wxyz())
    assert page.flush()
    assert page.nodes["path0"].points.shape != path.shape or not np.allclose(
        page.nodes["path0"].points, path
    )
    assert "C-EMDM" in page.status.content
    page.set_override("weights.effort", -1.0)
    assert not page.flush()
    assert "refused" in page.status.content and "weights.effort" in page.status.content
    page.set_override("weights.effort", 0.01)
    assert page.flush() and "refused" not in page.status.content

    def broken() -> None:
        raise RuntimeError("boom")

    page.guarded("a test", broken)  # never raises: the status says it
    assert "a test failed: RuntimeError: boom" in page.status.content
    # the goal gizmo's callback with a pose that is no rotation: a message
    page.set_goal([0.5, 0.1, 0.4], [0.0, 0.0, 0.0, 0.0])
    assert not page.flush() and "orientation" in page.status.content


def test_flush_after_the_worker_took_the_change_reports_its_outcome(page):
    page.set_override("weights.effort", -1.0)
    deadline = time.monotonic() + 10.0
    while page.pending and time.monotonic() < deadline:  # the worker takes it (CI's race)
        time.sleep(0.01)
    assert not page.flush() and "refused" in page.status.content
    page.set_override("weights.effort", 0.01)
    assert page.flush()


def test_the_page_controls_without_a_browser(page):
    user = SimpleNamespace(client=object())  # an event from a tab
    page.scenario.value = "ur5"  # the page's own change: no event from a tab, nothing done
    assert page.session.scenario.name == "panda-obstacles"
    page._select(user)
    assert page.session.scenario.name == "ur5" and page.obstacle_nodes == []
    assert page.nodes["links0"].batched_positions.shape == (7, 3)  # base, 6 joints, tool
    assert "obstacles" not in page.intro.content
    page.first.value, page.second.value = "UC-EMDM", "UC-IVKC"
    page._controllers(user)
    assert page.flush()
    assert [o.name for o in page.session.computed.outcomes] == ["UC-EMDM", "UC-IVKC"]
    assert "UC-IVKC" in page.status.content
    page.set_goal(page.session.goal()[:3] + np.array([0.0, 0.0, 0.1]))
    assert page.flush() and page.session.settings.goal is not None
    assert np.allclose(page.goal.position, page.session.goal()[:3])  # the gizmo follows
    page._reset(user)
    assert page.session.settings.goal is None
    assert np.allclose(page.goal.position, page.session.base.motion.goal[:3])
    page.t = 0.0
    page._toggle(user)
    assert page.playing and page.play.label == "Pause"
    time.sleep(0.4)
    page._toggle(user)
    assert not page.playing and page.play.label == "Play"
    assert 0.1 < page.t < 2.0 and abs(page.time.value - page.t) < 1e-6
    page.scenario.value = "panda-obstacles"
    page._select(user)
    assert len(page.obstacle_nodes) == 2


def test_gizmo_drags_are_throttled(page):
    calls = []
    compute = page.session.compute

    def counted() -> bool:
        calls.append(time.monotonic())
        return compute()

    page.session.compute = counted  # type: ignore[method-assign]
    goal = page.session.goal()
    start = time.monotonic()
    for i in range(60):  # a drag: 60 gizmo updates in about 0.6 s
        page.set_goal(goal[:3] + np.array([0.0, -0.002 * i, 0.0]))
        time.sleep(0.01)
    deadline = time.monotonic() + 3
    while page.pending or page.wake.is_set():
        assert time.monotonic() < deadline
        time.sleep(0.02)
    time.sleep(0.2)
    spent = time.monotonic() - start
    assert 2 <= len(calls) <= spent * 20 + 2
    assert np.allclose(page.session.scenario.motion.goal[:3], goal[:3] + np.array([0, -0.118, 0]))


def test_refused_hosts_and_origins():
    spatial = pytest.importorskip("emdm.play.spatial")
    from websockets.datastructures import Headers
    from websockets.http11 import Request

    def request(**headers: str) -> Request:
        return Request("/", Headers(**headers))

    assert not spatial.refused(request(Host="127.0.0.1:8080"), 8080)
    assert not spatial.refused(request(Host="localhost:8080"), 8080)
    assert not spatial.refused(request(Host="127.0.0.1:8080", Origin="http://localhost:8080"), 8080)
    assert spatial.refused(request(Host="evil.example:8080"), 8080)
    assert spatial.refused(request(Host="127.0.0.1.evil.example"), 8080)
    assert spatial.refused(request(Host="127.0.0.1:8080", Origin="http://evil.example"), 8080)
    assert spatial.refused(request(Host="127.0.0.1:8080", Origin="http://127.0.0.1:9"), 8080)


# -------------------------------------------------------------------------- command line
def test_every_preset_the_message_suggests_is_served(monkeypatch, capsys):
    """``emdm play nosuch`` lists the presets; the playground takes each of them (planar ones
    to the Bokeh page, spatial ones to the 3-D page)."""
    from emdm import play

    server = pytest.importorskip("emdm.play.server")
    spatial = pytest.importorskip("emdm.play.spatial")

    assert main(["play", "nosuch", "--no-browser"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    listed = re.search(r"presets: ([^)]*)", err).group(1).split(", ")
    assert listed == list(PRESETS)
    served = []
    monkeypatch.setattr(server, "serve", lambda bases, **kw: served.append(("2d", *bases)) or 0)
    monkeypatch.setattr(spatial, "serve", lambda bases, **kw: served.append(("3d", *bases)) or 0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name in listed:
            assert play.serve(emdm.load_scenario(name), open_browser=False) == 0
    kinds = {entry[1]: entry[0] for entry in served}
    assert kinds == {
        "task1": "2d",
        "task2": "2d",
        "obstacle": "2d",
        "panda": "3d",
        "ur5": "3d",
        "panda-obstacles": "3d",
    }
    three_d = [entry for entry in served if entry[0] == "3d"]
    assert all(set(entry[1:]) == {"panda", "ur5", "panda-obstacles"} for entry in three_d)


def test_without_viser_emdm_play_panda_says_what_to_install(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "viser", None)  # import viser raises ImportError
    monkeypatch.delitem(sys.modules, "emdm.play.spatial", raising=False)
    assert main(["play", "panda", "--no-browser"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "pip install 'emdm[play3d]'" in err[0]


def start_3d(*args: str) -> tuple[subprocess.Popen[str], str]:
    """``emdm play --port 0 --no-browser ARGS`` in its own process; returns it and its address."""
    pytest.importorskip("viser")
    proc = subprocess.Popen(
        [sys.executable, "-m", "emdm.cli", "play", "--port", "0", "--no-browser", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    line = proc.stdout.readline() if proc.stdout else ""
    found = re.search(r"^emdm play: (http://127\.0\.0\.1:\d+/) ", line)
    if not found:
        proc.kill()
        pytest.fail(f"no address printed: {line!r} {proc.stderr.read() if proc.stderr else ''}")
    return proc, found.group(1)


@pytest.mark.slow
def test_emdm_play_panda_is_local_offline_and_stops_on_sigterm():
    from websockets.exceptions import InvalidStatus
    from websockets.sync.client import connect

    proc, url = start_3d("panda")
    try:
        page = urllib.request.urlopen(url, timeout=10).read().decode()
        assert re.findall(r'<script[^>]*\bsrc="', page) == []  # the client is inlined
        assert not re.search(r'(?:src|href)="(?:https?:)?//', page)
        for host in ("evil.example", "127.0.0.1.evil.example"):  # DNS rebinding: refused
            request = urllib.request.Request(url, headers={"Host": host})
            with pytest.raises(urllib.error.HTTPError) as info:
                urllib.request.urlopen(request, timeout=10)
            assert info.value.code == 403 and b"viser" not in info.value.read()
        local = urllib.request.Request(url.replace("127.0.0.1", "localhost"))
        assert urllib.request.urlopen(local, timeout=10).status == 200
        socket = url.replace("http://", "ws://")
        with pytest.raises(InvalidStatus) as refused:  # a page of another site
            connect(socket, origin="http://evil.example", subprotocols=["viser-v1"]).close()
        assert refused.value.response.status_code == 403
        proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=10)
        assert proc.returncode == 0, err
        assert out == "" and err == "emdm play: stopped\n"  # viser's own prints kept off
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()


# ------------------------------------------------------------------------ in a real browser
def _pixels(driver) -> np.ndarray:
    from PIL import Image

    png = driver.get_screenshot_as_png()
    image = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.int16)
    return image[:, :900]  # the scene, left of the panel


def _colored(image: np.ndarray) -> int:
    """Pixels of a saturated colour (the arms, the gizmo, the obstacles; not the grey grid)."""
    return int(((image.max(axis=2) - image.min(axis=2)) > 60).sum())


@pytest.mark.slow
def test_the_3d_page_draws_in_webgl_and_follows_the_goal(page):
    pytest.importorskip("PIL")
    from selenium.webdriver.common.action_chains import ActionChains

    driver = headless_chromium(1280, 720)
    try:
        driver.execute_cdp_cmd(
            "Emulation.setDeviceMetricsOverride",
            {"width": 1280, "height": 720, "deviceScaleFactor": 1, "mobile": False},
        )
        driver.get(f"http://127.0.0.1:{page.server.get_port()}/")
        deadline = time.monotonic() + 25
        while _colored(_pixels(driver)) < 3000:
            assert time.monotonic() < deadline, "the scene was not drawn"
            time.sleep(0.5)
        sizes = driver.execute_script(
            "return Array.from(document.querySelectorAll('canvas')).map(c => [c.width, c.height,"
            " !!(c.getContext('webgl2') || c.getContext('webgl'))])"
        )
        assert [1280, 720, True] in sizes
        time.sleep(1.0)  # every message of the scene arrived
        before = _pixels(driver)
        goal = page.session.goal()
        page.set_goal(goal[:3] + np.array([0.1, -0.3, -0.05]), page.session.goal_wxyz())
        assert page.flush()
        deadline = time.monotonic() + 10
        while (changed := int((np.abs(_pixels(driver) - before).max(axis=2) > 40).sum())) < 2000:
            assert time.monotonic() < deadline, f"the drawing did not follow ({changed} pixels)"
            time.sleep(0.3)
        # a drag of the goal gizmo's x arrow (found by projecting it with the tab's camera)
        moved = np.array(page.session.settings.goal)
        camera = next(iter(page.server.get_clients().values())).camera
        axis = scene3d.rotation(page.session.goal_wxyz())[:, 0] * page.goal.scale
        a, b = (_screen(camera, moved[:3] + k * axis) for k in (0.0, 0.7))
        step = 50 * (b - a) / np.linalg.norm(b - a)
        drag = ActionChains(driver, duration=40)
        drag.move_to_element_with_offset(canvas(driver), *(b - [640, 360]).round().astype(int))
        drag.pause(0.2).click_and_hold().pause(0.2)
        for _ in range(5):
            drag.move_by_offset(*(step / 5).round().astype(int)).pause(0.05)
        drag.release().perform()
        deadline = time.monotonic() + 5
        while np.allclose(page.session.settings.goal, moved):
            assert time.monotonic() < deadline, "the gizmo did not move the goal"
            time.sleep(0.1)
        time.sleep(0.3)
        shift = np.array(page.session.settings.goal[:3]) - moved[:3]
        assert np.linalg.norm(np.cross(shift, axis)) < 1e-6 * np.linalg.norm(shift) + 1e-9
        assert np.allclose(page.session.scenario.motion.goal, page.session.settings.goal)
        errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
        assert not errors, errors
    finally:
        driver.quit()


def canvas(driver):
    """The scene's canvas (the largest)."""
    from selenium.webdriver.common.by import By

    found = driver.find_elements(By.CSS_SELECTOR, "canvas")
    return max(found, key=lambda c: c.size["width"] * c.size["height"])


def _screen(camera, point: np.ndarray) -> np.ndarray:
    """Pixel of ``point`` (m) in a 1280 x 720 view of the tab's ``camera`` (viser's: OpenCV
    axes, vertical field of view ``fov``)."""
    R = scene3d.rotation(camera.wxyz)
    c = R.T @ (np.asarray(point) - camera.position)
    f = 360 / math.tan(camera.fov / 2)
    return np.array([640 + f * c[0] / c[2], 360 + f * c[1] / c[2]])


def test_each_tab_is_a_page_of_its_own(bases):
    spatial = pytest.importorskip("emdm.play.spatial")
    server = spatial.start(0)
    pages = spatial.Pages(server, bases, Session3D(bases, "panda"))
    driver = headless_chromium(1280, 720)
    url = f"http://127.0.0.1:{server.get_port()}/"

    def wait_for(count: int) -> list:
        deadline = time.monotonic() + 25
        while len(pages.pages) != count:
            assert time.monotonic() < deadline, f"{len(pages.pages)} pages, not {count}"
            time.sleep(0.2)
        return list(pages.pages.values())

    try:
        driver.get(url)
        (first,) = wait_for(1)
        driver.switch_to.new_window("tab")
        driver.get(url)
        second = next(p for p in wait_for(2) if p is not first)
        assert first.client is not None and second.client is not None
        assert first.client.client_id != second.client.client_id
        goal = second.session.goal().copy()
        first.set_goal(goal[:3] + np.array([0.0, -0.2, 0.0]), first.session.goal_wxyz())
        assert first.flush()
        assert not np.allclose(first.session.goal(), goal)
        assert np.allclose(second.session.goal(), goal)  # the other tab keeps its own
        assert first.nodes["path0"] is not second.nodes["path0"]
        driver.close()  # the second tab leaves: its page closes, the first stays
        driver.switch_to.window(driver.window_handles[0])
        assert wait_for(1) == [first] and second.closing
    finally:
        driver.quit()
        pages.close()
        with spatial.quiet():
            server.stop()
