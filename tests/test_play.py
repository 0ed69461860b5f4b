"""emdm play: the playground's logic without a browser, its page as a Bokeh document, its server
as a process, and the page in a real browser (Debian's chromium and chromedriver)."""

from __future__ import annotations

import base64
import html
import io
import math
import re
import signal
import subprocess
import sys
import time
import tomllib
import urllib.error
import urllib.parse
import urllib.request
import warnings
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from conftest import headless_chromium

import emdm
from emdm.cli import main
from emdm.errors import ScenarioError
from emdm.outputs.animate import ellipse_points
from emdm.play import logic
from emdm.play.logic import CONTROL, PAST, PINNED, TIP, ZONE, Settings
from emdm.studies.pareto import front_at


@pytest.fixture(scope="module")
def bases():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return {name: emdm.load_scenario(name) for name in ("task1", "task2")}


@pytest.fixture(scope="module")
def task2_c(bases):
    return logic.run_pair(bases["task2"], "C")


# ------------------------------------------------------------------------------- controls
def test_sliders_show_and_set_scenario_values(bases):
    sc = bases["task1"]
    for control in logic.CONTROLS:
        value = control.value(sc)
        back = control.from_slider(control.to_slider(value))
        assert back == pytest.approx(value, rel=0.02, abs=control.step), control.name
        assert control.start <= control.to_slider(value) <= control.end
    w_m = CONTROL["w_M"]
    assert w_m.from_slider(w_m.start) == 0.0  # the left end of the manipulability weight is 0
    assert w_m.from_slider(1.0) == 10.0
    assert CONTROL["qd_max"].overrides(2.0) == {"arm.qd_max": 2.0, "arm.qd_min": -2.0}
    assert CONTROL["dt"].from_slider(0.0351) == 0.035
    with pytest.raises(ScenarioError, match="must be a number"):
        CONTROL["K_p"].from_slider(math.nan)


def test_a_refused_combination_is_explained_in_the_scenario_words(bases):
    settings = Settings("task1", overrides={"damper.stop": 0.9})
    with pytest.raises(ScenarioError) as info:
        logic.build_scenario(bases, settings)
    assert logic.message(info.value).startswith("damper.stop: must be < damper.influence")
    with pytest.raises(ScenarioError, match="unknown 'nope'"):
        logic.build_scenario(bases, Settings("nope"))
    with pytest.raises(ScenarioError, match="pair"):
        logic.build_scenario(bases, Settings("task1", pair="X"))


def test_the_address_may_carry_settings_and_bad_values_get_a_message():
    settings, errors = logic.parse_query(
        {
            "scenario": [b"task2"],
            "pair": [b"uc"],
            "links": [b"4"],
            "weights.effort": [b"0.3"],
            "motion.goal": [b"[0.1, 0.5]"],
        },
        ["task1", "task2"],
    )
    assert errors == []
    assert settings == Settings(
        "task2", 4, "UC", {"weights.effort": 0.3, "motion.goal": [0.1, 0.5]}
    )
    settings, errors = logic.parse_query(
        {"scenario": [b"/etc/passwd"], "links": [b"99"], "pair": [b"Z"], "x": [b"\n1"]},
        ["task1"],
    )
    assert settings == Settings("task1")
    assert len(errors) == 4 and all("\n" not in e for e in errors)
    assert "scenario: unknown '/etc/passwd'" in errors[0]


def test_the_address_written_by_the_page_reads_back_to_the_same_settings():
    settings = Settings(
        "task2",
        5,
        "UC",
        {
            "weights.effort": 0.1 + 0.2,  # every digit of a float survives
            "motion.goal": [-0.3, 0.6000000001],
            "controller.on_infeasible": "slack",
        },
    )
    query = logic.settings_query(settings)
    arguments: dict[str, list[bytes]] = {}
    for key, value in urllib.parse.parse_qsl(query):
        arguments.setdefault(key, []).append(value.encode())
    again, errors = logic.parse_query(arguments, ["task1", "task2"])
    assert errors == [] and again == settings


def test_links_keep_the_reach_and_a_valid_start(bases):
    sc = bases["task1"]
    for n in range(logic.MIN_LINKS, logic.MAX_LINKS + 1):
        arm = logic.with_links(sc, n)
        assert arm.n == n and arm.arm.lengths.sum() == pytest.approx(sc.arm.lengths.sum())
        assert np.all(np.abs(arm.motion.q0) < sc.arm.q_max[0] - sc.damper.stop[0])
        assert arm.motion.goal.tolist() == sc.motion.goal.tolist()
    assert logic.with_links(sc, 3) is sc
    with pytest.raises(ScenarioError, match="links"):
        logic.with_links(sc, 9)


# ----------------------------------------------------------------------------- scene arrays
def test_scene_geometry_equals_the_arm_model_and_the_animation_ellipse(bases):
    sc = logic.with_links(bases["task1"], 5)
    q = np.random.default_rng(1).uniform(-2, 2, (20, 5))
    points = logic.joint_positions(sc.arm.lengths, q)
    scale = logic.ellipse_scale(sc)
    w, h, a = logic.ellipses(points, scale)
    arm = sc.planar_arm
    for k in range(q.shape[0]):
        np.testing.assert_allclose(points[k], arm.joint_positions(q[k]), atol=1e-14)
        boundary = ellipse_points(arm.jacobian(q[k]), points[k, -1], scale) - points[k, -1]
        c, s = math.cos(a[k]), math.sin(a[k])
        u = (c * boundary[:, 0] + s * boundary[:, 1]) / (w[k] / 2)
        v = (-s * boundary[:, 0] + c * boundary[:, 1]) / (h[k] / 2)
        np.testing.assert_allclose(u**2 + v**2, 1.0, atol=1e-9)
    stretched = logic.ellipses(logic.joint_positions(sc.arm.lengths, np.zeros((1, 5))), scale)
    assert stretched[0][0] == pytest.approx(2 * logic.ELLIPSE_SHARE * arm.reach)


def test_joint_states_show_zones_pins_and_broken_limits(bases, task2_c):
    emdm_run, ivkc = task2_c
    states = logic.joint_states(ivkc.run)
    assert states[-1, 1] == PINNED  # C-IVKC ends held at joint 2's damper stop
    assert np.any(logic.joint_states(emdm_run.run) == ZONE)
    uc = logic.run_controller(bases["task2"], "UC-IVKC").run
    assert np.any(logic.joint_states(uc) == PAST)  # UC programs ignore the limits
    points, steps = logic.scene_data(emdm_run.run, 0.2)
    K, n = emdm_run.run.steps, 2
    assert points["x"].size == (K + 1) * (n + 1) and np.all(points["s"][n :: n + 1] == TIP)
    assert all(v.size == K + 1 for v in steps.values())
    assert math.isnan(steps["E"][-1]) and math.isnan(steps["alpha"][-1])


def test_the_drawn_program_is_the_step_s_program(bases):
    """The velocity set drawn at the tip holds the P velocity when the step keeps the full task
    and not when it scales it, and its arrows are the P velocity and J qd of the command."""
    run = logic.run_controller(bases["task1"], "C-EMDM").run
    scale = 0.2
    drawn = logic.velocity_data(run, scale)
    K, n = run.steps, bases["task1"].n
    corners = np.column_stack((drawn["px"], drawn["py"])).reshape(K + 1, 2 * n, 2)
    tip = run.p[:, :2]
    assert np.allclose(drawn["vx"][:K], tip[:K, 0] + scale * run.v[:K, 0])
    arm = bases["task1"].planar_arm
    for k in (0, 60, K - 1):
        Jqd = arm.jacobian(run.q[k]) @ run.qd[k]
        assert np.allclose([drawn["ax"][k], drawn["ay"][k]], tip[k] + scale * Jqd)
    inside = []
    for k in range(K):
        V = (corners[k] - tip[k]) / scale
        edges = np.roll(V, -1, axis=0) - V
        v = run.v[k]
        cross = edges[:, 0] * (v[1] - V[:, 1]) - edges[:, 1] * (v[0] - V[:, 0])
        keep = np.linalg.norm(edges, axis=1) > 1e-12  # padded corners repeat the last one
        inside.append(cross[keep].min() >= -1e-9)
    inside = np.array(inside)
    assert np.array_equal(inside, ~run.scaled)  # task1 scales its first 38 steps
    assert run.scaled.sum() == 38 and math.isnan(drawn["ax"][K])
    uc = logic.run_controller(bases["task1"], "UC-EMDM").run
    assert np.all(np.isnan(logic.velocity_data(uc, scale)["px"]))  # no bounds: no polygon


# ------------------------------------------------------------------------------ status text
def test_status_says_why_a_run_ended(bases, task2_c):
    emdm_run, ivkc = task2_c
    assert logic.explain(bases["task2"], emdm_run).startswith("reached the goal at t = 16.45 s")
    why = logic.explain(bases["task2"], ivkc)
    # the stall starts where the record's definition (Run.stalled_from) puts it, as in the report
    assert "did not reach the goal" in why and "stalled from t = 4.35 s" in why
    assert "joint 2 is at its damper stop" in why
    far = bases["task2"].with_overrides({"motion.goal": [2.0, 0.0], "motion.max_time": 2.0})
    assert "outside the reachable annulus [0.1, 0.9] m" in logic.explain(
        far, logic.run_controller(far, "C-EMDM")
    )
    strict = bases["task2"].with_overrides({"controller.on_infeasible": "error"})
    stopped = logic.run_controller(strict, "C-IVKC")
    assert stopped.error is not None and "stopped" in logic.explain(strict, stopped)
    uc = logic.run_controller(bases["task2"], "UC-EMDM")
    assert "passed their position limit" in logic.explain(bases["task2"], uc)


def test_status_rows_at_the_scrubbed_step(task2_c):
    emdm_run, ivkc = task2_c
    rows = dict(logic.status_rows(ivkc, 25.0))
    assert rows["t"] == "25.00 s (step 500 of 600)"
    assert rows["alpha"].endswith("(task scaled)")
    assert rows["joints at a bound"].startswith("2: damper")
    assert rows["solver"].startswith("active-set") and "e-" in rows["KKT residual"]
    end = dict(logic.status_rows(emdm_run, 1e9))
    assert end["command"] == "none: final state (goal reached)"
    assert logic.step_at(math.nan, 0.05, 10) == 0 and logic.step_at(0.074, 0.05, 10) == 1


def test_the_front_at_the_scrubbed_step_marks_the_current_weights(bases):
    sc = bases["task1"].with_overrides({"weights.manipulability": 0.7})
    outcome = logic.run_controller(sc, "UC-EMDM")
    result = logic.front(sc, outcome, 2.0)
    k = logic.step_at(2.0, sc.motion.dt, outcome.run.steps)
    assert result.t == pytest.approx(outcome.run.t[k])
    assert result.ratio[result.current] == pytest.approx(7.0)
    reference = front_at(sc, outcome.controller, outcome.run.q[k], np.array([7.0]))
    assert result.E[result.current] == pytest.approx(reference[1]["E"], abs=1e-12)
    assert result.M[result.current] == pytest.approx(reference[1]["M"], abs=1e-12)
    assert not result.single and np.any(~result.dominated)
    c_emdm = logic.run_controller(bases["task1"], "C-EMDM")
    assert logic.front(bases["task1"], c_emdm, 0.0).single  # the velocity box leaves one command


# ------------------------------------------------------------------------------ start pose
def test_dragging_a_joint_turns_its_link_and_stays_out_of_the_stop_zones(bases):
    sc = bases["task1"]
    q0 = sc.motion.q0
    pts = sc.planar_arm.joint_positions(q0)
    tip = pts[2] + 0.3 * np.array([math.cos(0.2), math.sin(0.2)])  # turn the last link to 0.2 rad
    q = logic.drag_start(sc, 3, tip)
    np.testing.assert_allclose(q[:2], q0[:2])
    assert q[:3].sum() == pytest.approx(0.2)
    elbow = logic.drag_start(sc, 1, [-0.2, 0.0])  # the first link would point backwards: clipped
    assert elbow[0] == pytest.approx(sc.arm.q_max[0] - sc.damper.stop[0] - 1e-3)
    np.testing.assert_allclose(elbow[1:], q0[1:])
    assert logic.moved_point(pts, pts) is None
    moved = pts.copy()
    moved[2] += 0.1
    assert logic.moved_point(pts, moved) == 2
    with pytest.raises(ScenarioError):
        logic.drag_start(sc, 0, [0.0, 0.0])


def test_the_exported_scenario_loads_back_identically(bases, tmp_path):
    sc = logic.build_scenario(
        bases, Settings("task2", links=4, overrides={"weights.manipulability": 0.5})
    )
    path = tmp_path / "play.toml"
    path.write_text(logic.export_toml(sc))
    back = emdm.load_scenario(path)
    assert back.to_dict() == sc.to_dict()
    assert tomllib.loads(path.read_text())["arm"]["lengths"] == [0.225] * 4


# ------------------------------------------------------------------- the page, no browser
@pytest.fixture
def session(bases):
    pytest.importorskip("bokeh")
    from bokeh.document import Document

    from emdm.play.page import Session

    def make(**query):
        doc = Document()
        arguments = {k: [v.encode()] for k, v in query.items()}
        context = SimpleNamespace(request=SimpleNamespace(arguments=arguments))
        doc._session_context = lambda: context
        return Session(doc, dict(bases))

    return make


def _settle(s) -> None:
    """Run what the server loop would run on its next ticks, and the throttled refreshes that
    would follow when their interval has passed."""
    for _ in range(3):
        for what in sorted(s._due):
            s._safe(s._due_now, what)
        if s._scheduled:
            s._safe(s._flush)


def test_the_page_recomputes_on_a_goal_drag(session):
    s = session()
    before, restarts = s.status_text, s.restarts
    assert "C-EMDM" in before and "C-IVKC" in before and s.banner.text == ""
    s.goal.data = {"x": [0.3], "y": [0.7]}
    _settle(s)
    assert s.scenario.motion.goal.tolist() == [0.3, 0.7]
    assert s.shown["steps0"]["ex"][-1] == pytest.approx(0.3, abs=2e-3)
    # the new motion plays from the start (apply.js)
    assert s.status_text != before and s.restarts == restarts + 1
    toml, name = s.shown_props["save-toml"]["tags"]
    assert name == "task1-play.toml" and "goal = [0.3, 0.7]" in toml


def _unpack(s) -> tuple[dict, dict]:
    """The last change message as apply.js reads it: (sources, meta)."""
    import json

    values = np.asarray(s.change.data["values"][0])
    meta = json.loads(s.change.data["meta"][0])

    def column(spec):
        if "f" in spec:
            return values[spec["f"][0] : spec["f"][0] + spec["f"][1]]
        if "fs" in spec:
            return [values[o : o + n] for o, n in spec["fs"]]
        return spec["v"]

    sources = {
        name: {key: column(spec) for key, spec in columns.items()}
        for name, columns in meta["sources"].items()
    }
    return sources, meta


def test_a_change_goes_to_the_page_as_one_message_that_reads_back_exactly(session):
    s = session()
    sent = []
    s.change.on_change("data", lambda attr, old, new: sent.append(new))
    s.goal.data = {"x": [0.3], "y": [0.7]}
    _settle(s)
    assert len(sent) == 1  # the runs, the status and the front together
    sources, meta = _unpack(s)
    assert meta["restart"] and not meta["live"]
    assert {"points0", "steps1", "qlines0", "velocity", "front", "status-html"} <= set(sources)
    for name, data in sources.items():
        for key, value in data.items():
            expected = s.shown[name][key]
            if isinstance(value, list) and value and isinstance(value[0], np.ndarray):
                for got, want in zip(value, expected, strict=True):
                    np.testing.assert_array_equal(got, np.asarray(want, dtype=float))
            elif isinstance(value, np.ndarray):  # NaN where the record has NaN, bit for bit
                np.testing.assert_array_equal(value, np.asarray(expected, dtype=float))
            else:
                assert value == list(np.asarray(expected).tolist())
    end = max(float(s.shown[f"steps{i}"]["t"][-1]) for i in range(2))
    assert meta["props"]["scrub"]["end"] == pytest.approx(end)


def test_the_value_ranges_are_fitted_on_the_server_as_bokeh_fits_them(session):
    """Sent with the change (a range fitted in the page was sent back to the server, a message per
    plot): the finite values with 10 % padding, a span of 2 about a constant, kept without any."""
    from emdm.play.page import _fitted

    assert _fitted([1.0, 2.0, np.nan], []) == pytest.approx({"start": 0.95, "end": 2.05})
    assert _fitted(np.full(3, 3.0)) == {"start": 2.0, "end": 4.0}
    assert _fitted([], [np.nan, np.inf]) is None
    s = session(scenario="task2")
    for key in ("m", "E", "err", "alpha"):
        drawn = [s.shown[f"steps{i}"][key] for i in range(2)]
        assert s.shown_props[f"y-{key}"] == _fitted(*drawn)
    assert s.shown_props["y-q"] == _fitted(*s.shown["qlines0"]["ys"], *s.shown["qlines1"]["ys"])
    front = s.shown["front"]
    assert s.shown_props["x-pareto"] == _fitted(front["M"])
    assert s.shown_props["y-pareto"] == _fitted(front["E"])
    low, high = np.nanmin(front["E"]), np.nanmax(front["E"])
    assert s.shown_props["y-pareto"]["start"] <= low <= high <= s.shown_props["y-pareto"]["end"]


def test_a_goal_being_dragged_is_followed_without_replaying(session):
    s = session()
    restarts, goal = s.restarts, dict(s.goal.data)
    s.live.data = {"what": ["goal"], "x": [0.3], "y": [0.7]}  # live.js, mid-drag
    _settle(s)
    assert s.scenario.motion.goal.tolist() == [0.3, 0.7]
    assert s.shown["steps0"]["ex"][-1] == pytest.approx(0.3, abs=2e-3)
    # the drag tool keeps the goal and the motion goes on: nothing that would end the drag
    assert s.goal.data == goal and s.restarts == restarts
    s.live.data = {"what": ["nonsense"], "x": [0.0], "y": [0.0]}
    _settle(s)
    assert s.scenario.motion.goal.tolist() == [0.3, 0.7]
    s.goal.data = {"x": [0.3], "y": [0.7]}  # the release there: the motion plays from the start
    _settle(s)
    assert s.restarts == restarts + 1
    s.goal.data = {"x": [0.3], "y": [0.7]}  # the same goal again, no drag: nothing to do
    _settle(s)
    assert s.restarts == restarts + 1


def test_a_clip_of_the_runs_shown_is_a_gif_at_the_playback_speed_or_faster(bases):
    from PIL import Image

    long = bases["task1"].with_overrides({"motion.max_time": 60.0, "motion.goal": [3.0, 3.0]})
    for scenario, speed in ((bases["task1"], 2.0), (long, 1.0)):
        runs = [o.run for o in logic.run_pair(scenario, "C")]
        gif, speedup = logic.clip_gif(runs, speed)
        duration = max(float(run.t[-1]) for run in runs)
        assert speedup == max(speed, duration / logic.CLIP_SECONDS)
        with Image.open(io.BytesIO(gif)) as image:
            assert image.format == "GIF" and image.n_frames > 10
            shown = 0.0
            for frame in range(image.n_frames):
                image.seek(frame)
                shown += image.info["duration"] / 1e3
        # the motion at that speed-up, and the last frame held 1 s
        assert shown == pytest.approx(duration / speedup + 1.0, abs=0.1)
        assert shown <= logic.CLIP_SECONDS + 1.1


def test_the_clip_button_writes_it_in_a_worker_and_sends_it_once(session):
    s = session()
    ticks, sent = [], []
    s.doc.add_next_tick_callback = ticks.append  # the server loop, run by hand below
    s.clip.on_change("data", lambda attr, old, new: sent.append(dict(new)))
    s._on_clip()
    assert s.save_gif.disabled and "Writing" in s.save_gif.label
    s._on_clip()  # a second press while it works is ignored
    end = time.monotonic() + 60
    while not ticks and time.monotonic() < end:
        time.sleep(0.05)
    assert len(ticks) == 1
    ticks[0]()
    assert not s.save_gif.disabled and s.save_gif.label == "Export clip (GIF)"
    assert [d["name"] for d in sent] == [["task1-play.gif"], []]  # then no copy is kept
    assert base64.b64decode(sent[0]["gif"][0])[:6] == b"GIF89a"


def test_a_run_is_compared_with_a_pinned_one_from_their_records(bases):
    from emdm.sim.metrics import metrics

    base = bases["task1"]
    pinned = logic.run_pair(base, "C")[0]
    lighter = base.with_overrides({"weights.manipulability": 0.5})
    now = logic.run_pair(lighter, "C")[0]
    rows = {row[0]: row[1:] for row in logic.compare(now, pinned)}
    a, b = metrics(now.run), metrics(pinned.run)
    assert rows["time to goal (s)"][:2] == (f"{a['time_to_goal']:.2f}", f"{b['time_to_goal']:.2f}")
    effort = rows["effort \u222bE dt (rad\u00b2/s)"]
    change = a["total_effort"] - b["total_effort"]
    assert effort[2] == f"{change:+.4g} ({change / b['total_effort']:+.0%})"
    assert rows["scaled steps"][2] in ("same", f"{a['scaled_steps'] - b['scaled_steps']:+d}")
    assert logic.compare(pinned, pinned)[0][3] == "same"
    assert logic.scenario_changes(base, lighter) == ["weights.manipulability: 5.0 \u2192 0.5"]
    assert logic.scenario_changes(base, base) == []
    far = base.with_overrides({"motion.goal": [3.0, 3.0], "motion.max_time": 2.0})
    unreached = logic.run_pair(far, "C")[0]
    assert logic.compare(unreached, pinned)[0][1:] == (
        "not reached",
        rows["time to goal (s)"][1],
        "\u2013",
    )


def test_the_page_pins_a_reference_and_compares_with_it(session):
    s = session()
    s._on_pin()
    assert s.pin.label == "Unpin the reference" and len(s.shown["pinned"]["t"]) == len(
        s.shown["steps0"]["t"]
    )
    assert "Against the pinned run" in s.status_text
    assert "the same scenario" in s.status_text and "pinned C-EMDM" in s.legend.text
    s.sliders["w_M"].value = s.sliders["w_M"].start  # w_M = 0: EMDM becomes IVKC
    _settle(s)
    text = html.unescape(s.status_text)
    assert "weights.manipulability: 5.0 \u2192 0.0" in text and "C-EMDM now" in text
    assert len(s.shown["pinned"]["t"]) != 0  # the reference stays while the settings change
    s._on_pin()
    assert s.pin.label == "Pin as reference" and len(s.shown["pinned"]["t"]) == 0
    assert "Against the pinned run" not in s.status_text


def test_the_page_drags_the_start_and_switches_pair_links_and_scenario(session):
    s = session(scenario="task2")
    q0 = s.scenario.motion.q0.copy()
    x, y = list(s.handles.data["x"]), list(s.handles.data["y"])
    x[1], y[1] = x[0] + 0.4, y[0]  # the end effector, straight out from the elbow
    s.handles.data = {"x": x, "y": y}
    _settle(s)
    assert s.scenario.motion.q0[0] == q0[0] and s.scenario.motion.q0.sum() == pytest.approx(0)
    s.pair.active = 1
    _settle(s)
    assert [o.name for o in s.outcomes] == ["UC-EMDM", "UC-IVKC"]
    s.links.value = 4
    _settle(s)
    assert s.scenario.n == 4 and len(s.shown["qlines0"]["ys"]) == 4
    s.choose.value = "task1"
    _settle(s)
    assert s.scenario.name == "task1" and s.settings.pair == "UC"


def test_the_page_explains_a_refused_slider_and_keeps_the_last_valid_view(session):
    s = session()
    good = s.scenario
    s.sliders["stop"].value = 0.5
    s.sliders["influence"].value = 0.3
    _settle(s)
    assert "Not applied: damper.stop: must be < damper.influence" in html.unescape(s.banner.text)
    assert s.scenario is good
    for name in ("stop", "influence"):  # every slider shows the settings in force again
        control = CONTROL[name]
        shown = control.from_slider(s.sliders[name].value)
        assert shown == pytest.approx(control.value(good), rel=0.02, abs=control.step), name
    s._dirty = True  # the refused slider is let go: the page recomputes what is in force
    s._on_release("value_throttled", None, None)
    _settle(s)
    assert "Not applied: damper.stop" in html.unescape(s.banner.text)  # still explained
    s.sliders["stop"].value = 0.1
    s.sliders["influence"].value = 0.3
    _settle(s)
    assert s.banner.text == "" and s.scenario.damper.influence[0] == 0.3


def test_bad_address_values_are_listed_on_the_page(session):
    s = session(links="nine", **{"weights.effort": "-1", "damper.stop": "x"})
    assert "links: must be 2 to 8" in s.banner.text
    assert "Not applied" in s.banner.text and s.scenario is not None
    assert '<div class="note">' not in s.banner.text  # refusals look like errors, not notes
    assert s.scenario.weights.effort == 0.1  # the defaults are shown


def test_one_refused_address_value_keeps_the_others(session):
    """A teacher's link with one bad value: the page says which, and applies the rest."""
    s = session(**{"weights.manipulability": "0.5", "weights.effort": "abc"})
    text = html.unescape(s.banner.text)
    assert "Not applied: weights.effort: must be a number" in text
    assert s.scenario.weights.manipulability == 0.5 and s.scenario.weights.effort == 0.1
    s = session(**{"motion.goal": "[0.2, 0.6]", "damper.stop": "2"})
    assert "Not applied: damper.stop" in html.unescape(s.banner.text)
    assert s.scenario.motion.goal.tolist() == [0.2, 0.6]


def test_a_failing_callback_is_shown_and_the_session_survives(session, monkeypatch):
    s = session()

    def broken(*args):
        raise RuntimeError("boom")

    monkeypatch.setattr(logic, "run_pair", broken)
    s.sliders["w_M"].value = 1.0
    _settle(s)
    assert "internal error: RuntimeError: boom" in s.banner.text
    monkeypatch.undo()
    s.sliders["w_M"].value = 1.5
    _settle(s)
    assert s.banner.text == "" and s.scenario.weights.manipulability == pytest.approx(31.6)


def test_the_scrub_bar_moves_the_status_and_the_front(session):
    s = session()
    s.scrub.value = 2.0
    _settle(s)
    assert "2.00 s (step 40 of 163)" in s.status_text
    assert s.shown_props["pareto-title"]["text"] == "Pareto, t = 2.00 s"
    assert len(s.shown["front"]["E"]) == len(emdm.studies.pareto.ratios()) + 2  # w_M = 0, 50


# ------------------------------------------------------------------------------ the server
def test_command_line_errors_are_one_line(capsys):
    assert main(["play", "--port", "70000", "--no-browser"]) == 2
    assert main(["play", "nope.toml", "--no-browser"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and "--port" in err[0] and "65535" in err[0] and "nope.toml" in err[1]


def start_server(*args: str) -> tuple[subprocess.Popen[str], str]:
    """``emdm play --port 0 --no-browser ARGS`` in its own process; returns it and its address."""
    pytest.importorskip("bokeh")
    proc = subprocess.Popen(
        [sys.executable, "-m", "emdm.cli", "play", "--port", "0", "--no-browser", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    line = proc.stdout.readline() if proc.stdout else ""
    found = re.search(r"http://127\.0\.0\.1:\d+/", line)
    if not found:
        proc.kill()
        pytest.fail(f"no address printed: {line!r} {proc.stderr.read() if proc.stderr else ''}")
    return proc, found.group(0)


def stop_server(proc: subprocess.Popen[str], sig: int) -> str:
    """Send ``sig``; the server must exit with status 0 and say so. Returns its stderr."""
    proc.send_signal(sig)
    try:
        _, err = proc.communicate(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        raise
    assert proc.returncode == 0, err
    assert "emdm play: stopped" in err and "Traceback" not in err
    assert "ERROR" not in err, err  # e.g. Bokeh's check of the columns every glyph reads
    return err


@pytest.mark.slow
def test_the_server_is_local_offline_and_stops_on_sigterm():
    proc, url = start_server("task2")
    try:
        page = urllib.request.urlopen(url, timeout=10).read().decode()
        scripts = re.findall(r'<script[^>]*src="([^"]+)"', page)
        assert scripts and all(s.startswith(("/static/", url)) for s in scripts), scripts
        assert "cdn." not in page
        for src in scripts:
            full = src if src.startswith("http") else url.rstrip("/") + src
            assert urllib.request.urlopen(full, timeout=10).status == 200
        with pytest.raises(urllib.error.HTTPError) as info:
            urllib.request.urlopen(url + "nothing-here", timeout=10)
        assert info.value.code == 404
        for host in ("evil.example", "127.0.0.1.evil.example"):  # DNS rebinding: refused
            request = urllib.request.Request(url, headers={"Host": host})
            with pytest.raises(urllib.error.HTTPError) as info:
                urllib.request.urlopen(request, timeout=10)
            assert info.value.code == 403 and b"Bokeh" not in info.value.read()
        local = urllib.request.Request(url.replace("127.0.0.1", "localhost"))
        assert urllib.request.urlopen(local, timeout=10).status == 200
    finally:
        stop_server(proc, signal.SIGTERM)


# ------------------------------------------------------------------------- in a real browser
def _browser(download: Path):
    driver = headless_chromium(1500, 1000)
    driver.execute_cdp_cmd(
        "Browser.setDownloadBehavior", {"behavior": "allow", "downloadPath": str(download)}
    )
    return driver


READY = "return window.Bokeh != null && Bokeh.documents.length > 0 && Bokeh.index.roots.length > 0"
MODEL = "return Bokeh.documents[0].get_model_by_name(arguments[0])"
STATUS = (  # what the status box shows (status.js writes it in place)
    "return Bokeh.index.find_one(Bokeh.documents[0].get_model_by_name('status')).markup_el.innerHTML"
)
WHERE = """
const [name, x, y] = arguments;
const view = Bokeh.index.find_one(Bokeh.documents[0].get_model_by_name(name));
const box = view.el.getBoundingClientRect();
return [box.left + view.frame.x_scale.compute(x), box.top + view.frame.y_scale.compute(y)];
"""
HANDLE = """
const view = Bokeh.index.find_one(Bokeh.documents[0].get_model_by_name(arguments[0]));
const handle = view.shadow_el.querySelector('.noUi-handle').getBoundingClientRect();
const bar = view.shadow_el.querySelector('.noUi-base').getBoundingClientRect();
return [handle.left + handle.width / 2, handle.top + handle.height / 2, bar.left];
"""


def _wait(driver, script: str, *args, timeout: float = 5.0):
    """Poll ``script`` until it returns something truthy."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = driver.execute_script(script, *args)
        if value:
            return value
        time.sleep(0.05)
    raise AssertionError(f"timed out waiting for: {script.strip()[:80]}")


def _downloaded(path, marker: bytes, timeout: float) -> bytes:
    """The bytes of a file the browser downloads, once it holds ``marker`` and its size has
    stopped changing: the browser may create the file before it has written all of it."""
    end, seen = time.monotonic() + timeout, None
    while time.monotonic() < end:
        data = path.read_bytes() if path.is_file() else b""
        if marker in data and len(data) == seen:
            return data
        seen = len(data) if marker in data else None
        time.sleep(0.2)
    raise AssertionError(f"{path.name}: not downloaded whole in {timeout} s")


def _drag(driver, start, end, steps: int = 8) -> None:
    from selenium.webdriver.common.actions.action_builder import ActionBuilder

    actions = ActionBuilder(driver)
    actions.pointer_action.move_to_location(round(start[0]), round(start[1])).pointer_down()
    for i in range(1, steps + 1):
        f = i / steps
        x, y = start[0] + f * (end[0] - start[0]), start[1] + f * (end[1] - start[1])
        actions.pointer_action.move_to_location(round(x), round(y))
    actions.pointer_action.pointer_up()
    actions.perform()


def _text(driver, name: str) -> str:
    return str(driver.execute_script(MODEL + ".text", name))


def _series(driver, column: str) -> list[float]:
    return list(driver.execute_script(MODEL + f".data.{column}", "steps0"))


CHANGED = """
const [name, column, before] = arguments;
const now = Bokeh.documents[0].get_model_by_name(name).data[column];
return now.length != before.length || now.some((v, i) => Math.abs(v - before[i]) > 1e-9);
"""


@pytest.mark.slow
def test_the_page_in_a_real_browser(tmp_path):
    driver = _browser(tmp_path)
    proc, url = start_server()
    try:
        driver.get(url)
        _wait(driver, READY)
        _wait(driver, STATUS + ".includes('C-EMDM')")
        status, trace = driver.execute_script(STATUS), _series(driver, "ex")
        assert "0.00 s (step 0 of 163)" in status
        # the program at the step shown: its velocity set (6 corners) and both arrows
        assert len(driver.execute_script(MODEL + ".data.x", "velocity-set")) == 6
        assert len(driver.execute_script(MODEL + ".data.x1", "want")) == 1
        assert len(driver.execute_script(MODEL + ".data.x1", "got")) == 1

        # between two states the arm is drawn in between (smooth playback at any speed)
        driver.execute_script(
            "const s = Bokeh.documents[0].get_model_by_name('scrub'); s.value = 10.25 * s.step"
        )
        assert driver.execute_script(MODEL + ".value", "scrub") == pytest.approx(0.5125)
        xs = np.array(driver.execute_script(MODEL + ".data.x", "points0"))
        per = len(xs) // len(trace)  # points per state
        drawn = np.array(driver.execute_script(MODEL + ".data.x", "arm-state0"))
        assert drawn == pytest.approx(
            0.75 * xs[10 * per : 11 * per] + 0.25 * xs[11 * per : 12 * per]
        )
        driver.execute_script(MODEL + ".value = 0", "scrub")

        # drag the goal: the trajectory follows while the button is held (live.js) ...
        from selenium.webdriver.common.actions.action_builder import ActionBuilder

        goal = driver.execute_script(WHERE, "scene", -0.7, 0.5)
        middle = driver.execute_script(WHERE, "scene", -0.2, 0.6)
        actions = ActionBuilder(driver)
        actions.pointer_action.move_to_location(round(goal[0]), round(goal[1])).pointer_down()
        for f in (0.25, 0.5, 0.75, 1.0):
            actions.pointer_action.move_to_location(
                round(goal[0] + f * (middle[0] - goal[0])),
                round(goal[1] + f * (middle[1] - goal[1])),
            )
        actions.perform()
        _wait(driver, CHANGED, "steps0", "ex", trace)
        assert not driver.execute_script(MODEL + ".active", "play")  # followed, not replayed
        ex, ey = (driver.execute_script(MODEL + f".data.{c}", "steps0") for c in ("ex", "ey"))
        assert math.hypot(ex[-1] + 0.2, ey[-1] - 0.6) < 0.02
        # ... the release replays it from the start, and a drag elsewhere goes there
        actions = ActionBuilder(driver)
        actions.pointer_action.pointer_up()
        actions.perform()
        _wait(driver, MODEL + ".active", "play")
        target = driver.execute_script(WHERE, "scene", 0.3, 0.7)
        trace = _series(driver, "ex")
        _drag(driver, middle, target)
        _wait(driver, CHANGED, "steps0", "ex", trace)
        ex, ey = (driver.execute_script(MODEL + f".data.{c}", "steps0") for c in ("ex", "ey"))
        assert math.hypot(ex[-1] - 0.3, ey[-1] - 0.7) < 0.02
        _wait(driver, STATUS + " != arguments[0]", status)
        assert "of 163" not in driver.execute_script(STATUS)
        _wait(driver, MODEL + ".active", "play")  # the new run plays from its start (apply.js)

        # move the manipulability-weight slider to its left end (w_M = 0): EMDM becomes IVKC
        x, y, left = driver.execute_script(HANDLE, "slider-w_M")
        before = _series(driver, "m")
        _drag(driver, (x, y), (max(1, left - 10), y), steps=4)
        _wait(driver, "const m = Bokeh.documents[0].get_model_by_name(arguments[0]); "
              "return m.value == m.start", "slider-w_M")  # fmt: skip
        _wait(driver, CHANGED, "steps0", "m", before)
        _wait(driver, MODEL + ".tags[0].includes('manipulability = 0.0\\n')", "save-toml")
        assert "w_M = 0," in driver.execute_script(MODEL + ".tags[1]", "save-png")

        # the address holds the settings in force, and a reload restores them
        _wait(driver, "return location.search.includes('weights.manipulability=0.0')")
        assert "motion.goal=" in driver.execute_script("return location.search")
        driver.refresh()
        _wait(driver, READY)
        _wait(driver, STATUS + ".includes('C-EMDM')")
        assert driver.execute_script(MODEL + ".data.x[0]", "goal") == pytest.approx(0.3, abs=4e-3)
        assert "manipulability = 0.0\n" in driver.execute_script(MODEL + ".tags[0]", "save-toml")

        # export the scenario and run it with emdm run
        driver.execute_script(
            "Bokeh.index.find_one(Bokeh.documents[0].get_model_by_name('save-toml'))"
            ".shadow_el.querySelector('button').click()"
        )
        exported = tmp_path / "task1-play.toml"
        data = tomllib.loads(_downloaded(exported, b"[weights]", 10).decode())
        assert data["weights"]["manipulability"] == 0.0
        # within half a pixel of the scene (460 px across about 2.4 m)
        assert data["motion"]["goal"] == pytest.approx([0.3, 0.7], abs=4e-3)
        out = tmp_path / "run"
        done = subprocess.run(
            [sys.executable, "-m", "emdm.cli", "run", str(exported), "--out", str(out),
             "--controller", "C-EMDM"],
            capture_output=True, text=True, timeout=120,
        )  # fmt: skip
        assert done.returncode == 0, done.stderr
        assert (out / "metrics.json").is_file()

        # the clip: a GIF of the runs shown, downloaded by the page
        driver.execute_script(
            "Bokeh.index.find_one(Bokeh.documents[0].get_model_by_name('save-gif'))"
            ".shadow_el.querySelector('button').click()"
        )
        clip = _downloaded(tmp_path / "task1-play.gif", b"GIF89a", 30)
        assert clip.endswith(b";")  # a GIF's trailer: the file is whole

        # a second tab is a session of its own
        driver.switch_to.new_window("tab")
        driver.get(url + "?scenario=task2&links=x")
        _wait(driver, READY)
        _wait(driver, STATUS + ".includes('C-EMDM')")
        assert "links: must be 2 to 8" in _text(driver, "banner")
        assert driver.execute_script(MODEL + ".data.x[0]", "goal") == -0.3
        driver.switch_to.window(driver.window_handles[0])
        assert driver.execute_script(MODEL + ".data.x[0]", "goal") == pytest.approx(0.3, abs=4e-3)
        severe = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
        assert not severe, severe
    finally:
        driver.quit()
        stop_server(proc, signal.SIGINT)


@pytest.mark.slow
def test_the_page_reconnects_after_a_server_restart(tmp_path):
    """The server stops: the page says so; it comes back on the same port: the page reloads
    itself with the settings of its address."""
    from emdm.play.server import free_port

    port = str(free_port())
    driver = _browser(tmp_path)
    proc, url = start_server("--port", port, "task2")
    try:
        driver.get(url + "?scenario=task2&pair=UC&weights.effort=0.2")
        _wait(driver, READY)
        _wait(driver, STATUS + ".includes('UC-EMDM')")
        stop_server(proc, signal.SIGTERM)
        _wait(driver, MODEL + ".text.includes('Connection to emdm play lost')", "banner")
        driver.execute_script("window.emdm_before_restart = true")
        proc, _ = start_server("--port", port, "task2")
        _wait(driver, "return window.emdm_before_restart == null && " + READY[7:], timeout=30)
        _wait(driver, STATUS + ".includes('UC-EMDM')", timeout=30)
        assert "effort = 0.2\n" in driver.execute_script(MODEL + ".tags[0]", "save-toml")
        assert "lost" not in _text(driver, "banner")
    finally:
        driver.quit()
        if proc.poll() is None:
            stop_server(proc, signal.SIGTERM)


def test_a_moving_slider_and_a_playing_motion_are_throttled(session):
    """While a slider moves, runs are recomputed at most every LIVE_INTERVAL and its release at
    once; while the motion plays, the front follows at most every FRONT_INTERVAL."""
    s = session()
    runs = []

    def recompute(**kw):  # count, do not compute
        runs.append(kw)
        s._ran_at, s._dirty = time.monotonic(), False

    s._recompute = recompute
    s._ran_at = -math.inf  # long ago: the first move is computed at once
    for value in (1.0, 1.2, 1.4):  # three moves within one interval
        s.sliders["w_M"].value = value
        if s._scheduled:
            s._flush()
    assert len(runs) == 1 and s._due == {"run"} and s._dirty
    s.sliders["w_M"].trigger("value_throttled", 1.0, 1.4)  # the release (as the browser sends it)
    s._flush()
    assert len(runs) == 2
    s._dirty = False
    s._due_now("run")  # the scheduled live tick finds nothing new to compute
    assert len(runs) == 2 and not s._due
    fronts = []
    s._refresh_front = lambda: fronts.append(s.t)
    s._front_at = float("inf")  # a refresh has just happened
    s.scrub.value = 1.0
    s.scrub.value = 1.5
    assert s._due == {"front"} and not fronts
    s._due_now("front")
    s._flush()
    assert fronts == [1.5]


def test_the_playground_draws_a_scenes_obstacles(bases):
    """A scene with obstacles shows each one and its stop distance in the workspace (the same
    outlines as the figures); a scene without obstacles shows none."""
    pytest.importorskip("bokeh")
    from bokeh.document import Document

    from emdm.outputs.views import Views
    from emdm.play.page import Session

    sc = emdm.load_scenario("obstacle")

    def make(name):
        doc = Document()
        context = SimpleNamespace(request=SimpleNamespace(arguments={"scenario": [name.encode()]}))
        doc._session_context = lambda: context
        return Session(doc, {"obstacle": sc, **bases})

    (body,) = Views(sc).obstacle_outlines(np.eye(2))
    s = make("obstacle")
    assert s.obstacles.data["xs"] == [body[:, 0].tolist()]
    assert len(s.stop_zones.data["xs"]) == 1
    assert make("task1").obstacles.data["xs"] == []


def test_a_bad_number_of_links_is_a_message_on_the_page(session):
    """Typing "abc" (no value), nothing, 2.5 or 99 in Number of links: a message naming the field
    and its range, the spinner back at the value in force, no "internal error"."""
    s = session()
    n = s.scenario.n
    for bad in (None, 2.5, 99, float("nan")):
        s.links.value = bad
        _settle(s)
        assert "Number of links must be a whole number from 2 to 8" in s.banner.text, bad
        assert "internal error" not in s.banner.text
        assert s.links.value == n and s.scenario.n == n
    s.links.value = 4
    _settle(s)
    assert s.scenario.n == 4 and "Not applied" not in s.banner.text


def test_a_page_computes_a_bounded_number_of_steps(bases, session):
    """``?motion.max_time=6000`` (an unreachable goal ran 120,000 steps per controller and froze
    the tab) is refused in the page's words; the served scenario's own max_time stands."""
    with pytest.raises(ScenarioError, match=r"at most 4000 per controller \(max_time <= 200 s\)"):
        logic.build_scenario(bases, Settings("task1", overrides={"motion.max_time": 6000.0}))
    assert logic.build_scenario(bases, Settings("task1")).max_steps == 600
    long = {"task1": bases["task1"].with_overrides({"motion.max_time": 300.0})}
    assert logic.build_scenario(long, Settings("task1")).max_steps == 6000
    s = session(**{"motion.max_time": "6000"})
    assert "at most 4000" in s.banner.text and s.scenario.motion.max_time == 30.0


def test_inert_controls_are_greyed_out(session):
    """The infeasibility policy acts on the C pair only; the slack weight only where the EMDM
    controllers carry a slack (two links, or obstacles)."""
    s = session()  # task1: three links, C pair
    assert not s.policy.disabled and s.sliders["c_S"].disabled
    s.pair.active = 1
    _settle(s)
    assert s.policy.disabled
    s = session(scenario="task2")
    assert not s.sliders["c_S"].disabled
