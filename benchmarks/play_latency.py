"""Latency of the playground in a real browser: `python benchmarks/play_latency.py`.

Starts `emdm play --port 0 --no-browser` (warmed up before it serves), drives headless chromium
with selenium and measures, medians over repeats:

- page load from the warm server: from navigation start to the first trajectory and status on
  screen (the next animation frame after both arrived);
- drag of the goal: from the release of the pointer (``pointerup``) to the frame that shows the
  new trajectory;
- drag of a slider (w_M): from the release to the frame that shows the last trajectory (the
  slider recomputes while it moves; the last one is the value at the release);
- server compute for each change, as the page reports it: both runs, and the arrays, status and
  export the page needs (the Pareto front of the scrubbed step is computed after the trajectory
  has gone to the page, and reported apart).

Targets (issue 14): release to screen under 100 ms median, server compute under 5 ms, page load
under 2 s. Options: ``--repeats N`` (default 15), ``--json`` (print JSON), ``--screenshot PNG``
(the page after a goal drag, for the README), ``--scenario NAME``.
"""

from __future__ import annotations

import argparse
import json
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
  window.__emdm = {up: null, shown: []};
  window.addEventListener('pointerup', () => { window.__emdm.up = performance.now(); }, true);
  const steps = Bokeh.documents[0].get_model_by_name('steps0');
  steps.properties.data.change.connect(() => {
    requestAnimationFrame(() => window.__emdm.shown.push(performance.now()));
  });
}
window.__emdm.up = null;
window.__emdm.shown = [];
"""
LOADED = """
const done = arguments[arguments.length - 1];
const check = () => {
  const doc = window.Bokeh && Bokeh.documents[0];
  const status = doc && doc.get_model_by_name('status');
  const steps = doc && doc.get_model_by_name('steps0');
  if (status && status.text.includes('C-EMDM') && steps && steps.data.ex && steps.data.ex.length) {
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
TIMING = "return Bokeh.documents[0].get_model_by_name('status').text"


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


def drag(driver: Any, start: tuple[float, float], end: tuple[float, float], steps: int = 8) -> None:
    from selenium.webdriver.common.actions.action_builder import ActionBuilder

    actions = ActionBuilder(driver, duration=10)
    actions.pointer_action.move_to_location(round(start[0]), round(start[1])).pointer_down()
    for i in range(1, steps + 1):
        f = i / steps
        actions.pointer_action.move_to_location(
            round(start[0] + f * (end[0] - start[0])), round(start[1] + f * (end[1] - start[1]))
        )
    actions.pointer_action.pointer_up()
    actions.perform()


def settled(driver: Any, quiet: float = 0.4, timeout: float = 10.0) -> tuple[float, list[float]]:
    """Wait until no new trajectory arrived for ``quiet`` s; returns (release, frames shown)."""
    end = time.monotonic() + timeout
    count, since = -1, time.monotonic()
    while time.monotonic() < end:
        up, shown = driver.execute_script("return [window.__emdm.up, window.__emdm.shown]")
        if len(shown) != count:
            count, since = len(shown), time.monotonic()
        elif shown and time.monotonic() - since > quiet:
            return float(up), [float(s) for s in shown]
        time.sleep(0.02)
    raise RuntimeError("no new trajectory on screen")


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


def measure(url: str, repeats: int, screenshot: Path | None) -> dict[str, Any]:
    driver = browser()
    try:
        loads = []
        for _ in range(max(3, repeats // 3)):
            driver.get("about:blank")
            driver.get(url)
            loads.append(float(driver.execute_async_script(LOADED)))  # ms since navigation start
        time.sleep(1.0)  # let the first front and the page settle
        driver.execute_script(HOOK)
        goal_ms, goal_server, goals = [], [], [(0.3, 0.7), (-0.7, 0.5)]
        where = (-0.7, 0.5)
        for i in range(repeats):
            target = goals[i % 2]
            driver.execute_script(HOOK)
            drag(driver, point(driver, *where), point(driver, *target))
            up, shown = settled(driver)
            goal_ms.append(shown[-1] - up)
            goal_server.append(server_ms(driver))
            where = target
        if screenshot is not None:
            driver.execute_script(HOOK)
            drag(driver, point(driver, *where), point(driver, 0.35, 0.75))
            settled(driver)
            time.sleep(2.5)  # the motion replays: show it mid-way
            driver.execute_script("document.activeElement && document.activeElement.blur()")
            screenshot.parent.mkdir(parents=True, exist_ok=True)
            driver.save_screenshot(str(screenshot))
        slider_ms, slider_server = [], []
        for i in range(repeats):
            x, y, left, width = driver.execute_script(HANDLE, "slider-w_M")
            driver.execute_script(HOOK)
            target = x - 0.15 * width if i % 2 == 0 else x + 0.15 * width
            drag(driver, (x, y), (max(left + 1, target), y), steps=4)
            up, shown = settled(driver)
            slider_ms.append(max(0.0, shown[-1] - up))
            slider_server.append(server_ms(driver))
    finally:
        driver.quit()

    def server(rows: list[dict[str, float]], *keys: str) -> float:
        return median([sum(r.get(k, 0.0) for k in keys) for r in rows])

    return {
        "repeats": repeats,
        "page_load_ms": median(loads),
        "goal_drag_ms": median(goal_ms),
        "goal_drag_max_ms": max(goal_ms),
        "slider_ms": median(slider_ms),
        "slider_max_ms": max(slider_ms),
        "server_runs_ms": server(goal_server + slider_server, "runs"),
        "server_compute_ms": server(goal_server + slider_server, "change"),
        "server_front_ms": server(goal_server + slider_server, "front"),
    }


def table(data: dict[str, Any]) -> str:
    rows = [
        ("page load, warm server", "page_load_ms", "< 2000"),
        ("goal drag: release to new trajectory on screen", "goal_drag_ms", "< 100"),
        ("slider (w_M): release to new trajectory on screen", "slider_ms", "< 100"),
        ("server compute of a change (scenario, runs, page data)", "server_compute_ms", "< 5"),
        ("  of which both runs", "server_runs_ms", ""),
        ("Pareto front of the scrubbed step (after the trajectory)", "server_front_ms", ""),
    ]
    lines = [f"| measure (median of {data['repeats']}) | ms | target |", "|---|---:|---|"]
    lines += [f"| {label} | {data[key]:.1f} | {target} |" for label, key, target in rows]
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--scenario", default="task1")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--screenshot", type=Path)
    args = parser.parse_args()
    proc, url = start_server(args.scenario)
    try:
        data = measure(url, args.repeats, args.screenshot)
    finally:
        proc.terminate()
        proc.wait(timeout=10)
    print(json.dumps(data, indent=2) if args.json else table(data))
    return 0


if __name__ == "__main__":
    sys.exit(main())
