"""Latency of the playground in a real browser: `python benchmarks/play_latency.py`.

Starts `emdm play SCENARIO --port 0 --no-browser` (warmed up before it serves), drives headless
chromium with selenium and measures, for each input, from the input event to the painted frame:

- the clock starts at the release of the pointer, read as the event's own ``timeStamp`` (when
  the browser received it, not when a script saw it); for a goal held mid-drag, at its last
  pointer move (the page sends a drag's position at most every 0.05 s, so this includes that
  wait);
- it stops after the frame that shows the new trajectory has been painted: after the scene's
  own repaint (Bokeh paints a plot at most 60 times a second, so a change can wait a frame for
  it), then after the browser's paint of that frame (a ``setTimeout`` queued from
  ``requestAnimationFrame``); likewise for the Pareto front (its plot's repaint) and the status
  table: an input counts as done when all three show the change;
- inputs: a flick of the goal (to a point near the scenario's own goal, and back, in 4 moves:
  shorter than the 0.1 s after which the page follows a drag), the goal dragged in 6 moves 50 ms
  apart and held there, and a drag of the w_M slider, each with the motion paused and while it
  plays (Play pressed before the drag);
- medians and 90th percentiles over ``--repeats`` inputs; the server's own compute per change as
  the page reports it.

Targets (issue 23): input to new pixels under 100 ms median and 150 ms at p90, paused or playing.
Options: ``--repeats N`` (default 15), ``--scenario NAME`` (repeatable; default task1 and task2),
``--json``, ``--screenshot PNG`` (the first scenario's page after a goal drag).
"""

from __future__ import annotations

import argparse
import json
import math
import re
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

HOOK = """
if (!window.__emdm) {
  window.__emdm = {up: null, shown: {steps: [], status: [], front: []}, waiting: {}};
  window.addEventListener('pointerup', (e) => { window.__emdm.up = e.timeStamp; }, true);
  window.addEventListener('pointermove', (e) => { window.__emdm.moved = e.timeStamp; }, true);
  // a plot paints a change at most 60 times a second (a throttle): wait for its own repaint
  const plot = Bokeh.require('models/plots/plot_canvas').PlotView.prototype;
  const repaint = plot.repaint;
  plot.repaint = function () {
    repaint.call(this);
    const waiting = window.__emdm.waiting[this.model.name] || [];
    window.__emdm.waiting[this.model.name] = [];
    waiting.forEach((then) => then());
  };
  const doc = Bokeh.documents[0];
  for (const [key, name, prop, figure] of [['steps', 'steps0', 'data', 'scene'],
                                           ['status', 'status-html', 'data', null],
                                           ['front', 'front', 'data', 'plot-pareto']]) {
    doc.get_model_by_name(name).properties[prop].change.connect(() => {
      // after the paint of the frame that shows the change: the plot's repaint, then the
      // browser's paint of that frame (a setTimeout queued from requestAnimationFrame); kept
      // with the time the change arrived, which ties a status and a front to their run
      const arrived = performance.now();
      const shown = () => requestAnimationFrame(
        () => setTimeout(() => window.__emdm.shown[key].push([arrived, performance.now()])));
      if (figure == null) {
        shown();
      } else {
        (window.__emdm.waiting[figure] = window.__emdm.waiting[figure] || []).push(shown);
      }
    });
  }
}
window.__emdm.up = null;
window.__emdm.moved = null;
window.__emdm.shown = {steps: [], status: [], front: []};
"""
GOAL = "return Bokeh.documents[0].get_model_by_name('goal').data"
LOADED = """
const done = arguments[arguments.length - 1];
const check = () => {
  const doc = window.Bokeh && Bokeh.documents[0];
  const status = doc && doc.get_model_by_name('status-html');
  const steps = doc && doc.get_model_by_name('steps0');
  if (status && status.data.html[0].includes('C-EMDM') && steps && steps.data.ex && steps.data.ex.length) {
    requestAnimationFrame(() => done(performance.now()));
  } else {
    setTimeout(check, 5);
  }
};
check();
"""
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
return [handle.left + handle.width / 2, handle.top + handle.height / 2, bar.left, bar.width];
"""
TIMING = "return Bokeh.documents[0].get_model_by_name('status-html').data.html[0]"


def browser(width: int = 1500, height: int = 1000) -> Any:
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    chromium, driver_path = shutil.which("chromium"), shutil.which("chromedriver")
    if not chromium or not driver_path:
        sys.exit(
            "needs chromium and chromedriver (Debian: apt-get install chromium chromium-driver)"
        )
    options = webdriver.ChromeOptions()
    options.binary_location = chromium
    for flag in (
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-dev-shm-usage",
        "--disable-background-networking",
        "--disable-component-update",
        "--no-first-run",
        f"--window-size={width},{height}",
    ):
        options.add_argument(flag)
    return webdriver.Chrome(service=Service(driver_path), options=options)


def point(driver: Any, x: float, y: float) -> tuple[float, float]:
    """Where the scene's point (x, y) (m) is in the window (CSS pixels)."""
    sx, sy = driver.execute_script(WHERE, "scene", x, y)
    return float(sx), float(sy)


def drag(
    driver: Any,
    start: tuple[float, float],
    end: tuple[float, float],
    steps: int = 4,
    pause: float = 0.0,
    release: bool = True,
) -> None:
    """Press at ``start``, move to ``end`` in ``steps`` moves ``pause`` s apart, release. The
    default is a flick, shorter than the 0.1 s after which the page follows a drag (live.js)."""
    from selenium.webdriver.common.actions.action_builder import ActionBuilder

    actions = ActionBuilder(driver, duration=10)
    actions.pointer_action.move_to_location(round(start[0]), round(start[1])).pointer_down()
    for i in range(1, steps + 1):
        f = i / steps
        actions.pointer_action.move_to_location(
            round(start[0] + f * (end[0] - start[0])), round(start[1] + f * (end[1] - start[1]))
        )
        if pause:
            actions.pointer_action.pause(pause)
    if release:
        actions.pointer_action.pointer_up()
    actions.perform()


SETTLED = """
const [quiet, timeout, start] = arguments;
const done = arguments[arguments.length - 1];
const began = performance.now();
let count = -1, since = began;
const check = () => {
  const now = performance.now(), shown = window.__emdm.shown;
  if (shown.steps.length != count) {
    count = shown.steps.length;
    since = now;
  } else if (count > 0 && window.__emdm[start] != null && now - since > quiet) {
    done([window.__emdm[start], shown]);
    return;
  }
  if (now - began > timeout) {
    done(null);
    return;
  }
  setTimeout(check, 50);
};
check();
"""


def shown(driver: Any, start: str = "up") -> dict[str, float]:
    """:func:`settled`, or an empty row (counted as missed) when no new trajectory came."""
    try:
        return settled(driver, start=start)
    except RuntimeError:
        return {}


def drag_release(driver: Any) -> None:
    from selenium.webdriver.common.actions.action_builder import ActionBuilder

    actions = ActionBuilder(driver)
    actions.pointer_action.pointer_up()
    actions.perform()


def settled(
    driver: Any, quiet: float = 0.5, timeout: float = 10.0, start: str = "up"
) -> dict[str, float]:
    """Wait until no new trajectory arrived for ``quiet`` s; returns the latencies (ms) from the
    release (``start="up"``; ``"moved"``: the last pointer move) to the painted frame of the last
    trajectory, of the status and of the front that followed it, and of all three. The wait runs
    in the page (a timer every 50 ms) rather than as WebDriver calls every 20 ms, each of which
    ran a script on the page's main thread while it drew the change being measured."""
    driver.set_script_timeout(timeout + 5)
    found = driver.execute_async_script(SETTLED, quiet * 1e3, timeout * 1e3, start)
    if not found:
        raise RuntimeError("no new trajectory on screen")
    up, shown = found
    arrived, last = (float(t) for t in shown["steps"][-1])
    out = {"trajectory": last - float(up)}
    for key in ("status", "front"):
        # the first paint of one that arrived with the new trajectory or after it
        after = [float(p) for a, p in shown[key] if float(a) >= arrived]
        out[key] = (after[0] if after else last) - float(up)
    out["all"] = max(out.values())
    return out


def server_ms(driver: Any) -> dict[str, float]:
    text = driver.execute_script(TIMING)
    return {
        key: float(m.group(1))
        for key in ("change", "runs", "front")
        if (m := re.search(rf'class="{key}">([0-9.]+)<', text))
    }


def start_server(scenario: str) -> tuple[subprocess.Popen[str], str]:
    proc = subprocess.Popen(
        [sys.executable, "-m", "emdm.cli", "play", scenario, "--port", "0", "--no-browser"],
        stdout=subprocess.PIPE,
        text=True,
    )
    line = proc.stdout.readline() if proc.stdout else ""
    found = re.search(r"http://127\.0\.0\.1:\d+/", line)
    if not found:
        proc.kill()
        sys.exit(f"the server did not start: {line!r}")
    return proc, found.group(0)


def median(values: list[float]) -> float:
    return float(statistics.median(values)) if values else float("nan")


def p90(values: list[float]) -> float:
    return float(statistics.quantiles(values, n=10, method="inclusive")[-1]) if values else 0.0


def play(driver: Any, on: bool) -> None:
    driver.execute_script("Bokeh.documents[0].get_model_by_name('play').active = arguments[0]", on)


def measure(url: str, repeats: int, screenshot: Path | None) -> dict[str, Any]:
    driver = browser()
    out: dict[str, Any] = {}
    try:
        loads = []
        for _ in range(max(3, repeats // 3)):
            driver.get("about:blank")
            driver.get(url)
            loads.append(float(driver.execute_async_script(LOADED)))  # ms since navigation start
        out["page_load_ms"] = median(loads)
        time.sleep(1.0)  # let the first front and the page settle
        driver.execute_script(HOOK)
        goal = driver.execute_script(GOAL)
        base = (float(goal["x"][0]), float(goal["y"][0]))
        targets = [(0.85 * base[0], 0.85 * base[1]), base]
        server_rows: list[dict[str, float]] = []

        def goal_move() -> tuple[tuple[float, float], tuple[float, float]]:
            """Where the goal is, and the other of the two places it is dragged between."""
            now = driver.execute_script(GOAL)
            at = (float(now["x"][0]), float(now["y"][0]))
            return at, targets[0] if math.dist(at, base) < math.dist(at, targets[0]) else base

        for playing in (False, True):
            mode = "playing" if playing else "paused"
            rows: list[dict[str, float]] = []
            for _ in range(repeats):
                where, target = goal_move()
                play(driver, playing)
                driver.execute_script(HOOK)
                drag(driver, point(driver, *where), point(driver, *target))
                rows.append(shown(driver))
                server_rows.append(server_ms(driver))
            out[f"goal_{mode}"] = rows
            rows = []
            for _ in range(repeats):  # a drag in progress: the last move to its painted run
                where, target = goal_move()
                play(driver, playing)
                driver.execute_script(HOOK)
                drag(driver, point(driver, *where), point(driver, *target), 6, 0.05, False)
                rows.append(shown(driver, start="moved"))
                drag_release(driver)
                time.sleep(1.0)  # the release replays the same run: not measured here
            out[f"held_{mode}"] = rows
            rows = []
            for i in range(repeats):
                x, y, left, width = driver.execute_script(HANDLE, "slider-w_M")
                play(driver, playing)
                driver.execute_script(HOOK)
                target = x - 0.15 * width if i % 2 == 0 else x + 0.15 * width
                drag(driver, (x, y), (max(left + 1, target), y), steps=4)
                rows.append(shown(driver))
                server_rows.append(server_ms(driver))
            out[f"slider_{mode}"] = rows
        play(driver, False)
        if screenshot is not None:
            at, other = goal_move()
            driver.execute_script(HOOK)
            drag(driver, point(driver, *at), point(driver, *other))
            settled(driver)
            time.sleep(2.5)  # the motion replays: show it mid-way
            driver.execute_script("document.activeElement && document.activeElement.blur()")
            screenshot.parent.mkdir(parents=True, exist_ok=True)
            driver.save_screenshot(str(screenshot))
    finally:
        driver.quit()
    out["server_runs_ms"] = median([r.get("runs", 0.0) for r in server_rows])
    out["server_compute_ms"] = median([r.get("change", 0.0) for r in server_rows])
    out["server_front_ms"] = median([r.get("front", 0.0) for r in server_rows])
    return out


INPUTS = (
    ("goal_paused", "goal drag, paused"),
    ("goal_playing", "goal drag, playing"),
    ("held_paused", "goal held mid-drag, paused"),
    ("held_playing", "goal held mid-drag, playing"),
    ("slider_paused", "w_M slider, paused"),
    ("slider_playing", "w_M slider, playing"),
)


def table(results: dict[str, dict[str, Any]], repeats: int) -> str:
    lines = [
        f"Input (the release of the pointer; for a goal held mid-drag, its last move, which the "
        "page sends at most 0.05 s later) to the painted frame (ms), "
        f"{repeats} inputs each: median / p90 "
        "of the trajectory, and of trajectory, status and Pareto front all shown (target: all "
        "shown < 100 median, < 150 p90).",
        "",
        "| scenario | input | trajectory | all three shown | no new run within 10 s |",
        "|---|---|---:|---:|---:|",
    ]
    for name, data in results.items():
        for key, label in INPUTS:
            rows = [r for r in data[key] if r]
            missed = len(data[key]) - len(rows)
            traj = [r["trajectory"] for r in rows]
            full = [r["all"] for r in rows]
            lines.append(
                f"| {name} | {label} | {median(traj):.0f} / {p90(traj):.0f} "
                f"| {median(full):.0f} / {p90(full):.0f} | {missed} |"
            )
    lines += [
        "",
        "| scenario | page load, warm server (ms) | server: change / both runs / front (ms) |",
        "|---|---:|---:|",
    ]
    for name, data in results.items():
        lines.append(
            f"| {name} | {data['page_load_ms']:.0f} | {data['server_compute_ms']:.1f} / "
            f"{data['server_runs_ms']:.1f} / {data['server_front_ms']:.1f} |"
        )
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--scenario", action="append")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--screenshot", type=Path)
    args = parser.parse_args()
    results = {}
    for i, name in enumerate(args.scenario or ["task1", "task2"]):
        proc, url = start_server(name)
        try:
            results[name] = measure(url, args.repeats, args.screenshot if i == 0 else None)
        finally:
            proc.terminate()
            proc.wait(timeout=10)
    print(json.dumps(results, indent=2) if args.json else table(results, args.repeats))
    return 0


if __name__ == "__main__":
    sys.exit(main())
