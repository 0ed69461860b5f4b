"""Obstacles measured: the cost of the obstacle rows per step and in batch, and random scenes.

:func:`obstacle_speed` times ``emdm.simulate`` on the obstacle presets with more obstacles drawn
around them (5 circles on task1's arm, 10 spheres on the Panda) and a batch of runs;
:func:`random_scenes` is the benchmark of docs/mathematics.md, "Obstacles": seeded random scenes
for C-EMDM and NEO against the same controllers blind to the obstacles.
"""

from __future__ import annotations

import statistics
import time
from typing import Any

import numpy as np

from ..core.controllers import Controller, Name, Term, When, get_controller
from ..core.loading import load_scenario
from ..core.scenario import Scenario, scenario_from_dict
from ..core.terms.base import TermKind
from ..errors import NoSolution, ScenarioError
from ..sim.batch import simulate_batch
from ..sim.loop import simulate
from .solvable import proved_solvable
from .stats import wilson

SPREAD = 0.3
"""Obstacles of the random scenes lie within this fraction of the path's length of the straight
path of the end effector."""


ROUNDING = 1e-12
"""A clearance this far (m) below the stop distance is rounding, not an entry (the tests' own
tolerance)."""
GOAL_ROOM = 0.01
"""Room (m) an obstacle leaves around the goal beyond its stop distance, so that the end
effector can reach it."""


def scene(
    preset: str, count: int, rng: np.random.Generator, radius: tuple[float, float]
) -> Scenario:
    """``preset`` with obstacles added until it has ``count`` (:func:`scene_from`)."""
    base = load_scenario(preset)
    return scene_from(base.to_dict(), base, count, rng, radius)


def _time(function: Any, repeats: int) -> float:
    out = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        function()
        out.append(time.perf_counter() - t0)
    return statistics.median(out)


def obstacle_speed(*, repeats: int = 20, batch_runs: int = 2000) -> dict[str, Any]:
    """us/step of C-EMDM through ``emdm.simulate`` with 5 circles (task1's arm) and 10 spheres
    (Panda), and planar batch steps/s with the obstacle preset's circle."""
    rng = np.random.default_rng(0)
    ctrl = get_controller(Name.C_EMDM)
    out: dict[str, Any] = {}
    for key, preset, count, radius in (
        ("planar_5_circles", "obstacle", 5, (0.03, 0.08)),
        ("panda_10_spheres", "panda-obstacles", 10, (0.02, 0.05)),
    ):
        sc = scene(preset, count, rng, radius)
        run = simulate(sc, ctrl)
        seconds = _time(lambda sc=sc: simulate(sc, ctrl), repeats)
        out[key] = {
            "obstacles": count,
            "steps": run.steps,
            "reached": run.reached,
            "rows_per_step": float(run.rows.mean()),
            "min_clearance": float(run.clearance.min()),
            "us_per_step": seconds / run.steps * 1e6,
        }
    sc = load_scenario("obstacle")
    arm = sc.planar_arm
    targets = rng.uniform(sc.arm.q_min + 0.8, sc.arm.q_max - 0.8, (batch_runs, sc.n))
    goals = np.array([arm.forward(t) for t in targets])
    simulate_batch(sc, ctrl, goals=goals[:10])
    times, steps = [], 0
    for _ in range(3):
        t0 = time.perf_counter()
        result = simulate_batch(sc, ctrl, goals=goals)
        times.append(time.perf_counter() - t0)
        steps = int(result.steps.sum())
    out["batch"] = {
        "runs": batch_runs,
        "steps": steps,
        "seconds": statistics.median(times),
        "steps_per_second": steps / statistics.median(times),
        "handed_to_the_chain": int(result.reference_runs.size),
    }
    return out


def held(controller: Controller) -> Controller:
    """``controller`` with its task held exactly on a redundant arm (``"<name> task held"``):
    the brief's C-EMDM, whose slack serves only a non-redundant arm, for the evidence that a
    scene with obstacles needs the slack (docs/mathematics.md, "A way around")."""
    terms = tuple(
        Term(t.kind, t.weight, When.NON_REDUNDANT, t.optional) if t.kind is TermKind.SLACK else t
        for t in controller.terms
    )
    return Controller(f"{controller.name} task held", terms)


def random_scenes(
    preset: str,
    scenes: int,
    count: int,
    radius: tuple[float, float],
    seed: int = 0,
    *,
    prove: bool = False,
) -> dict[str, Any]:
    """``scenes`` seeded random scenes of ``count`` obstacles around ``preset``'s start and goal
    (:func:`scene`, the preset's own obstacles removed): per controller (C-EMDM, NEO, C-EMDM
    with its task held, and C-EMDM and NEO blind) success (reached, never inside the stop
    distance), collisions (a state inside the stop distance), clearance, time to goal and mean
    manipulability, with 95 % intervals. With ``prove`` (a 3-link planar arm), each scene is
    also searched for a collision-free motion (:func:`.solvable.proved_solvable`) and success is
    counted again over the scenes proved solvable."""
    rng = np.random.default_rng(seed)
    base = load_scenario(preset)
    data = base.to_dict()
    data.pop("obstacles", None)
    emdm, neo = get_controller(Name.C_EMDM), get_controller(Name.NEO)
    controllers = [emdm, neo, held(emdm), emdm.blind(), neo.blind()]
    rows: dict[str, list[dict[str, float]]] = {c.name: [] for c in controllers}
    stop = base.obstacle_damper.stop
    proved: list[bool] = []
    margin: list[float] = []
    cells = 0
    for _ in range(scenes):
        sc = scene_from(data, base, count, rng, radius)
        if prove:
            grid = proved_solvable(sc)
            proved.append(grid["proved"])
            margin, cells = grid["margin"], grid["cells"]
        for ctrl in controllers:
            try:
                run = simulate(sc, ctrl)
                stopped = False
            except NoSolution as exc:
                run, stopped = exc.run, True
            rows[ctrl.name].append(
                {
                    "reached": float(run.reached),
                    "collided": float(run.clearance.min() < stop - ROUNDING),
                    "stopped": float(stopped),
                    "clearance": float(run.clearance.min()),
                    "time": float(run.t[-1]) if run.reached else float("nan"),
                    "mean_m": float(run.m.mean()),
                }
            )
    summary: dict[str, Any] = {}
    for name, values in rows.items():
        reached = np.array([v["reached"] for v in values])
        collided = np.array([v["collided"] for v in values])
        success = reached * (1 - collided)
        times = np.array([v["time"] for v in values])
        summary[name] = {
            "success": float(success.mean()),
            "success_ci": wilson(int(success.sum()), len(values)),
            "collisions": float(collided.mean()),
            "collisions_ci": wilson(int(collided.sum()), len(values)),
            "stopped": float(np.mean([v["stopped"] for v in values])),
            "min_clearance_median": float(np.median([v["clearance"] for v in values])),
            "time_to_goal_median": float(np.nanmedian(times)) if np.any(success) else float("nan"),
            "mean_manipulability": float(np.mean([v["mean_m"] for v in values])),
        }
        if prove:
            mask = np.array(proved, dtype=bool)
            summary[name]["success_proved"] = float(success[mask].mean()) if mask.any() else 0.0
            summary[name]["success_proved_ci"] = wilson(int(success[mask].sum()), int(mask.sum()))
            summary[name]["success_not_proved"] = int(success[~mask].sum())
    same = all(
        np.array_equal(list(a.values()), list(b.values()), equal_nan=True)
        for a, b in zip(rows[emdm.name], rows[neo.name], strict=True)
    )
    return {
        "preset": preset,
        "scenes": scenes,
        "obstacles": count,
        "radius": radius,
        "seed": seed,
        "controllers": summary,
        "proved_solvable": int(sum(proved)) if prove else None,
        "proof_margin": margin,
        "proof_cells": cells,
        "emdm_equals_neo": bool(same),
    }


def scene_from(
    data: dict[str, Any],
    base: Scenario,
    count: int,
    rng: np.random.Generator,
    radius: tuple[float, float],
) -> Scenario:
    """``data`` (a scenario's TOML layout) with obstacles added until it has ``count``: circles
    (spheres in 3-D) of a radius uniform in ``radius`` (m), centres at a point uniform along the
    straight path of the end effector from its start to the goal, plus an offset uniform in the
    cube of half-width :data:`SPREAD` times the path's length, none within the stop distance of
    the start, nor within its stop distance plus :data:`GOAL_ROOM` of the goal (redrawn until
    so)."""
    dim = base.robot.dim
    shape = "circle" if dim == 2 else "sphere"
    start = base.robot.position(base.motion.q0)[:dim]
    goal = np.asarray(base.motion.goal[:dim])
    spread = SPREAD * float(np.linalg.norm(goal - start))
    obstacles: list[dict[str, Any]] = list(data.get("obstacles", []))
    while len(obstacles) < count:
        centre = start + rng.uniform() * (goal - start) + rng.uniform(-spread, spread, dim)
        new = {"shape": shape, "center": centre.tolist(), "radius": float(rng.uniform(*radius))}
        if np.linalg.norm(centre - goal) < new["radius"] + base.obstacle_damper.stop + GOAL_ROOM:
            continue  # the end effector could not reach the goal
        try:
            scenario_from_dict({**data, "obstacles": [*obstacles, new]})
        except ScenarioError:
            continue
        obstacles.append(new)
    return scenario_from_dict({**data, "obstacles": obstacles})


def never_entered(
    preset: str = "obstacle",
    scenes: int = 50,
    goals: int = 200,
    count: int = 3,
    radius: tuple[float, float] = (0.03, 0.1),
    seed: int = 1,
) -> dict[str, Any]:
    """The discrete-time guarantee at scale: ``scenes`` random scenes (:func:`scene_from`) times
    ``goals`` random reachable goals each, C-EMDM through the batch loop (every step certified,
    or settled by the solver chain and certified there): how many runs, the smallest clearance
    over all of them, and how many ever had a link inside the stop distance by more than
    :data:`ROUNDING`."""
    rng = np.random.default_rng(seed)
    base = load_scenario(preset)
    data = base.to_dict()
    data.pop("obstacles", None)
    arm = base.robot
    ctrl = get_controller(Name.C_EMDM)
    runs = inside = chain = stopped = reached = 0
    least = np.inf
    for _ in range(scenes):
        sc = scene_from(data, base, count, rng, radius)
        targets = rng.uniform(base.arm.q_min + 0.3, base.arm.q_max - 0.3, (goals, base.n))
        result = simulate_batch(sc, ctrl, goals=np.array([arm.position(t) for t in targets]))
        runs += len(result)
        least = min(least, float(result.min_clearance.min()))
        inside += int(np.sum(result.min_clearance < sc.obstacle_damper.stop - ROUNDING))
        chain += int(result.reference_runs.size)
        stopped += int(result.stopped_runs.size)
        reached += int(result.reached.sum())
    return {
        "preset": preset,
        "runs": runs,
        "reached": reached,
        "min_clearance": least,
        "stop": base.obstacle_damper.stop,
        "runs_inside_stop": inside,
        "runs_finished_by_the_chain": chain,
        "runs_stopped": stopped,
    }
