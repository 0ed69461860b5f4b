"""Monte-Carlo studies on the batch fast path (``emdm study``).

Each run draws a start ``q0`` uniformly inside the joint limits (outside the dampers' stop zones)
and a goal ``f(q_target)`` with ``q_target`` uniform inside the limits, so every goal is reachable
by a configuration within the limits. The same draws serve every controller (paired comparison),
and depend only on the seed.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from .controllers import CONTROLLERS
from .scenario import Scenario
from .style import COLUMN, figure


def draw(scenario: Scenario, runs: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Starts (runs x n) and reachable goals (runs x 2), reproducible from ``seed``."""
    rng = np.random.default_rng(seed)
    arm, lim, stop = scenario.arm, scenario.arm, scenario.damper.stop
    lo, hi = np.asarray(lim.q_min) + 1.01 * stop, np.asarray(lim.q_max) - 1.01 * stop
    q0s = rng.uniform(lo, hi, (runs, scenario.n))
    targets = rng.uniform(arm.q_min, arm.q_max, (runs, scenario.n))
    planar = scenario.planar_arm
    goals = np.array([planar.forward(t) for t in targets])
    return q0s, goals


def run_study(
    scenario: Scenario, runs: int, seed: int, *, chunk: int = 2000, progress: bool = True
) -> dict[str, Any]:
    """Every controller on the same ``runs`` draws; per-run outcomes and a summary."""
    from .fast import simulate_batch

    q0s, goals = draw(scenario, runs, seed)
    outcomes: dict[str, dict[str, np.ndarray]] = {}
    start = time.perf_counter()
    total = len(CONTROLLERS) * runs
    done = 0
    for name in CONTROLLERS:
        parts = []
        for lo in range(0, runs, chunk):
            parts.append(
                simulate_batch(
                    scenario, name, goals=goals[lo : lo + chunk], q0s=q0s[lo : lo + chunk]
                )
            )
            done += min(chunk, runs - lo)
            if progress:
                bar = "#" * int(30 * done / total)
                print(
                    f"\r  [{bar:<30}] {done}/{total} runs, {time.perf_counter() - start:.1f} s",
                    end="",
                    file=sys.stderr,
                    flush=True,
                )
        outcomes[name] = {
            key: np.concatenate([p[key] for p in parts])
            for key in parts[0]
            if key != "reference_runs"
        }
    if progress:
        print(file=sys.stderr)
    elapsed = time.perf_counter() - start
    summary: dict[str, Any] = {}
    for name, out in outcomes.items():
        reached = out["reached"]
        ttg = out["time_to_goal"][reached]
        summary[name] = {
            "success_rate": float(reached.mean()),
            "median_time_to_goal": float(np.median(ttg)) if ttg.size else None,
            "mean_manipulability": float(out["mean_manipulability"].mean()),
            "median_total_effort": float(np.median(out["total_effort"])),
            "steps": int(out["steps"].sum()),
        }
    gains = {}
    for prefix in ("UC-", "C-"):
        a = outcomes[prefix + "EMDM"]["mean_manipulability"]
        b = outcomes[prefix + "IVKC"]["mean_manipulability"]
        gain = a / b - 1.0
        gains[prefix + "EMDM over " + prefix + "IVKC"] = {
            "median_gain": float(np.median(gain)),
            "mean_gain": float(gain.mean()),
            "share_of_runs_improved": float((gain > 0).mean()),
        }
    steps = sum(s["steps"] for s in summary.values())
    return {
        "scenario": scenario.name,
        "runs": runs,
        "seed": seed,
        "controllers": summary,
        "manipulability_gain": gains,
        "wall_time_s": elapsed,
        "steps": steps,
        "steps_per_second": steps / elapsed,
        "goals": goals,
        "q0s": q0s,
        "outcomes": outcomes,
    }


def study_table(data: dict[str, Any]) -> str:
    rows = [
        f"{data['scenario']}: {data['runs']} runs per controller (seed {data['seed']}), "
        f"{data['steps']} steps in {data['wall_time_s']:.2f} s "
        f"({data['steps_per_second']:.3g} steps/s)",
        "",
        f"{'controller':<10} {'success':>8} {'median t_goal[s]':>17} {'mean m':>8} "
        f"{'median effort':>14}",
    ]
    for name, s in data["controllers"].items():
        ttg = f"{s['median_time_to_goal']:.2f}" if s["median_time_to_goal"] is not None else "-"
        rows.append(
            f"{name:<10} {s['success_rate']:>8.1%} {ttg:>17} "
            f"{s['mean_manipulability']:>8.4f} {s['median_total_effort']:>14.3f}"
        )
    rows.append("")
    for name, g in data["manipulability_gain"].items():
        rows.append(
            f"{name}: median manipulability gain {g['median_gain']:+.1%}, improved in "
            f"{g['share_of_runs_improved']:.1%} of the runs"
        )
    return "\n".join(rows)


def workspace_maps(data: dict[str, Any], scenario: Scenario, out: Path, bins: int = 24) -> Path:
    """Heat maps over goal positions: C-EMDM time to goal, and its gain over C-IVKC."""
    goals = data["goals"]
    reach = scenario.planar_arm.reach
    edges = np.linspace(-reach, reach, bins + 1)
    ix = np.clip(np.digitize(goals[:, 0], edges) - 1, 0, bins - 1)
    iy = np.clip(np.digitize(goals[:, 1], edges) - 1, 0, bins - 1)
    emdm_ = data["outcomes"]["C-EMDM"]
    ivkc = data["outcomes"]["C-IVKC"]
    maps = {
        "C-EMDM time to goal (s)": emdm_["time_to_goal"],
        "C-EMDM mean m gain over C-IVKC (%)": 100
        * (emdm_["mean_manipulability"] / ivkc["mean_manipulability"] - 1),
    }
    stem = out / "workspace_maps"
    with figure(stem, width=COLUMN, height=5.2, nrows=2) as (_, axes):
        for ax, (title, values) in zip(axes, maps.items(), strict=True):
            grid = np.full((bins, bins), np.nan)
            for b in range(bins * bins):
                sel = (ix == b % bins) & (iy == b // bins) & np.isfinite(values)
                if sel.any():
                    grid[b // bins, b % bins] = np.median(values[sel])
            mesh = ax.pcolormesh(edges, edges, grid, cmap="viridis", shading="flat")
            ax.set_aspect("equal")
            ax.set_xlabel("goal x (m)")
            ax.set_ylabel("goal y (m)")
            ax.set_title(f"{title}, median per cell", fontsize=7)
            ax.figure.colorbar(mesh, ax=ax)
    return stem
