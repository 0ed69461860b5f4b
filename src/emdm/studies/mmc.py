"""``emdm mmc``: the manipulability benchmark of Haviland & Corke (2020), reproduced.

Their table compares three reactive controllers on random tasks for the Panda and the UR5: mean
manipulability, mean final manipulability and failure rate. emdm runs the same three (``RRMC``,
``PARK``, ``MMC``; see :mod:`emdm.core.controllers`), and C-EMDM beside them, on the presets
``panda`` and ``ur5``, through :func:`emdm.simulate_batch` (every step certified).

Protocol (``emdm mmc --protocol emdm``: emdm's own, with its compiled controllers and C-EMDM; the
authors' protocol, ``emdm mmc``'s default, is :mod:`emdm.studies.mmc_paper`):

- ``trials`` tasks per arm, the same for every controller (paired), from ``seed``;
- start ``q0`` and goal configuration ``q*`` drawn uniformly inside each joint's limits shrunk by
  the damper's influence distance (so neither starts or ends with a damper acting), the goal
  being the pose of ``q*`` (reachable by construction);
- the preset's control settings (``dt`` 0.05 s, gain 1/s, effort weight 0.01, slack weight
  ``1/||e||``, dampers 0.9 / 0.05 rad) and its time limit (30 s, 600 steps);
- a run *fails* when it does not reach ``||e|| < tolerance`` (1e-3, pose error in m and rad)
  in the time limit, when a joint leaves its position limits (possible only for the unconstrained
  RRMC and PARK), or when a step has no admissible command;
- mean manipulability: the mean over every trial of the run's mean ``m`` over its states; mean
  final manipulability: the mean of ``m`` at the last state. Both over every trial, failed ones
  included, as a failure is a run too.
"""

from __future__ import annotations

import time
import zlib
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..core.controllers import Name, goal_of
from ..core.loading import load_scenario
from ..errors import ScenarioError
from ..sim.batch import simulate_batch

ARMS = ("panda", "ur5")
CONTROLLERS = (Name.RRMC, Name.PARK, Name.MMC, Name.C_EMDM)
PUBLISHED: dict[str, dict[str, tuple[float, float, float]]] = {
    "panda": {
        Name.RRMC: (0.0693, 0.0692, 12.4),
        Name.PARK: (0.0799, 0.0822, 18.5),
        Name.MMC: (0.0942, 0.0955, 8.0),
    },
    "ur5": {
        Name.RRMC: (0.0433, 0.0381, 39.7),
        Name.PARK: (0.0433, 0.0381, 39.7),
        Name.MMC: (0.0563, 0.0460, 25.6),
    },
}
"""Haviland & Corke's table (the MMC project page), per arm and controller: mean manipulability,
mean final manipulability, failure rate (%)."""


def draw_tasks(arm: str, trials: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Starts (trials x n) and goal poses (trials x 6) of the protocol (module docstring), for a
    preset or any spatial scenario (a file, a URDF robot)."""
    sc = load_scenario(arm)
    stream = ARMS.index(arm) if arm in ARMS else zlib.crc32(sc.name.encode())
    rng = np.random.default_rng(np.random.SeedSequence([seed, stream]))
    lo = np.asarray(sc.arm.q_min) + np.asarray(sc.damper.influence)
    hi = np.asarray(sc.arm.q_max) - np.asarray(sc.damper.influence)
    q0s = rng.uniform(lo, hi, (trials, sc.n))
    targets = rng.uniform(lo, hi, (trials, sc.n))
    goals = np.array([goal_of(sc, q) for q in targets]).reshape(trials, sc.nt)
    return q0s, goals


def run_mmc_benchmark(
    *,
    arms: Sequence[str] = ARMS,
    controllers: Sequence[str] = CONTROLLERS,
    trials: int = 1000,
    seed: int = 0,
    progress: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """Every arm and controller of the benchmark, as a JSON-friendly dict."""
    say = progress or (lambda _m: None)
    results: dict[str, dict[str, Any]] = {}
    for arm in arms:
        q0s, goals = draw_tasks(arm, trials, seed)
        sc = load_scenario(arm)
        if not sc.spatial or sc.nt != 6:
            raise ScenarioError(sc.source, "motion.task", "the benchmark needs a spatial pose task")
        results[arm] = {}
        for name in controllers:
            simulate_batch(sc, name, goals=goals[:1], q0s=q0s[:1])  # compiled before timing
            start = time.perf_counter()
            out = simulate_batch(sc, name, goals=goals, q0s=q0s)
            seconds = time.perf_counter() - start
            left_limits = out.min_joint_margin < 0.0
            failed = ~out.reached | left_limits
            stopped = np.zeros(trials, dtype=bool)
            stopped[out.stopped_runs] = True
            results[arm][name] = {
                "trials": trials,
                "mean_manipulability": float(out.mean_manipulability.mean()),
                "mean_final_manipulability": float(out.final_manipulability.mean()),
                "failure_rate": float(100.0 * failed.mean()),
                "not_reached": int(np.count_nonzero(~out.reached & ~stopped)),
                "left_joint_limits": int(np.count_nonzero(left_limits)),
                "no_admissible_command": int(np.count_nonzero(stopped)),
                "mean_manipulability_of_successes": (
                    float(out.mean_manipulability[~failed].mean()) if (~failed).any() else None
                ),
                "median_time_to_goal_s": (
                    float(np.nanmedian(out.time_to_goal)) if out.reached.any() else None
                ),
                "steps": int(out.steps.sum()),
                "seconds": seconds,
                "published": PUBLISHED.get(arm, {}).get(name),
            }
            say(f"{arm} {name}: {100.0 * failed.mean():.1f} % failed")
    return {"trials": trials, "seed": seed, "results": results}


def _fmt(value: float | None) -> str:
    return "-" if value is None else f"{value:.4f}"


def mmc_table(data: dict[str, Any]) -> str:
    """The benchmark beside the published table, as Markdown."""
    lines = [
        f"Manipulability benchmark: {data['trials']} random tasks per arm (seed {data['seed']}); "
        "published values (Haviland & Corke 2020) in brackets. A run fails when it does not reach "
        "the goal or leaves its joint limits (it may do both: the two counts overlap). On the UR5 "
        "(as many joints as task rows) C-EMDM is the slack program, hence MMC.",
        "",
        "| arm | controller | mean m | mean final m | failed % | mean m of successes "
        "| not reached | left limits | no command | steps/s |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for arm, rows in data["results"].items():
        for name, r in rows.items():
            pub = r["published"]
            m_pub = f" ({pub[0]:.4f})" if pub else ""
            final_pub = f" ({pub[1]:.4f})" if pub else ""
            f_pub = f" ({pub[2]:.1f})" if pub else ""
            lines.append(
                f"| {arm} | {name} | {r['mean_manipulability']:.4f}{m_pub} | "
                f"{r['mean_final_manipulability']:.4f}{final_pub} | "
                f"{r['failure_rate']:.1f}{f_pub} | {_fmt(r['mean_manipulability_of_successes'])} | "
                f"{r['not_reached']} | {r['left_joint_limits']} | {r['no_admissible_command']} | "
                f"{r['steps'] / max(r['seconds'], 1e-12):.3g} |"
            )
    return "\n".join(lines)


__all__ = ["CONTROLLERS", "PUBLISHED", "draw_tasks", "mmc_table", "run_mmc_benchmark"]
