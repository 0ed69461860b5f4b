"""Pareto fronts between effort ``E(qd)`` and manipulability rate ``M(qd)`` (brief Task 1).

*Per step*: at the states ``k = 0, floor(T/3), floor(2T/3), T`` of a run (``T`` the index of its final
state), the step's program is solved for a sweep of weights: ``w_E`` fixed at the scenario's value
and ``w_M = r w_E`` for ratios ``r`` log-spaced over ``decades`` decades, plus ``w_M = 0``. Each
optimum gives a point ``(E(qd*), M(qd*))``; a point is *dominated* when another has no more effort
and no less manipulability rate, one of them strictly. For UC-EMDM on a redundant arm the points lie
on the parabola ``E = E0 + (M - M0)^2 / (2 ||N Jm||^2)`` (docs/mathematics.md).

*Per trajectory*: the whole controller is re-run for a grid of ``(w_E, w_M)``, giving total effort,
mean manipulability and time to goal for each: the trade-off a user actually feels.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from ..core.controllers import Controller, get_controller, program_at, state_at
from ..core.scenario import Scenario
from ..errors import NoSolution
from ..sim.loop import Run, simulate
from ..sim.metrics import metrics
from ..solvers import DEFAULT_FALLBACK, DEFAULT_SOLVER, solve_chain


def pareto_steps(run: Run) -> list[int]:
    """``0, floor(T/3), floor(2T/3), T`` with ``T`` the index of the run's final state."""
    T = run.steps
    return [0, T // 3, (2 * T) // 3, T]


def ratios(decades: float = 7.0, per_decade: int = 4, low: float = -3.0) -> np.ndarray:
    """``w_M / w_E`` ratios, log-spaced from ``10^low`` over ``decades`` decades."""
    return np.asarray(np.logspace(low, low + decades, int(decades * per_decade) + 1))


def front_at(
    scenario: Scenario, controller: Controller, q: np.ndarray, sweep: np.ndarray
) -> list[dict[str, Any]]:
    """The points of the front at configuration ``q`` (``w_M = 0`` first, then each ratio)."""
    w0 = scenario.weights
    Jm = state_at(scenario, q).kin.Jm
    points = []
    for ratio in [0.0, *sweep]:
        weights = replace(w0, manipulability=ratio * w0.effort)
        program = program_at(controller, scenario, q, weights=weights)
        result = solve_chain(program.qp, [DEFAULT_SOLVER, *DEFAULT_FALLBACK])
        qd = result.x[: scenario.n]
        points.append(
            {
                "w_effort": weights.effort,
                "w_manip": weights.manipulability,
                "E": 0.5 * float(qd @ qd),
                "M": float(Jm @ qd),
                "qd": [float(x) for x in qd],
                "alpha": program.alpha,
                "kkt": result.kkt.residual,
            }
        )
    _mark_dominated(points)
    return points


def _mark_dominated(points: list[dict[str, Any]]) -> None:
    """Mark points with another of no more effort and no less rate, one strictly (exact values:
    the points are certified optima, and E can differ by 1e-15 between neighbours near the goal)."""
    for p in points:
        p["dominated"] = any(
            o["E"] <= p["E"] and o["M"] >= p["M"] and (o["E"] < p["E"] or o["M"] > p["M"])
            for o in points
        )


def pareto_study(
    scenario: Scenario, controller: str | Controller, *, sweep: np.ndarray | None = None
) -> tuple[dict[str, Any], Run]:
    """``pareto.json`` (its format is in the README) for ``controller`` on ``scenario``, and its run."""
    ctrl = controller if isinstance(controller, Controller) else get_controller(controller)
    run = simulate(scenario, ctrl)
    sweep = ratios() if sweep is None else sweep
    nominal = scenario.weights.manipulability / scenario.weights.effort
    steps = []
    for k in pareto_steps(run):
        steps.append(
            {
                "k": k,
                "t": float(run.t[k]),
                "q": [float(x) for x in run.q[k]],
                "points": front_at(scenario, ctrl, run.q[k], sweep),
            }
        )
    data = {
        "scenario": scenario.name,
        "controller": ctrl.name,
        "T": run.steps,
        "nominal_ratio": nominal,
        "ratios": [0.0, *map(float, sweep)],
        "steps": steps,
    }
    return data, run


def weight_grid(
    scenario: Scenario, controller: str | Controller, grid: list[tuple[float, float]]
) -> list[dict[str, Any]]:
    """Re-run the whole controller for each ``(w_E, w_M)``: total effort, mean m, time to goal."""
    ctrl = controller if isinstance(controller, Controller) else get_controller(controller)
    rows = []
    for w_e, w_m in grid:
        sc = replace(scenario, weights=replace(scenario.weights, effort=w_e, manipulability=w_m))
        try:
            mt = metrics(simulate(sc, ctrl))
        except NoSolution as exc:
            rows.append({"w_effort": w_e, "w_manip": w_m, "error": str(exc)})
            continue
        rows.append(
            {
                "w_effort": w_e,
                "w_manip": w_m,
                **{
                    key: mt[key]
                    for key in (
                        "reached",
                        "time_to_goal",
                        "total_effort",
                        "mean_manipulability",
                        "min_manipulability",
                        "final_manipulability",
                        "scaled_steps",
                    )
                },
            }
        )
    return rows


def default_grid(scenario: Scenario, points: int = 13) -> list[tuple[float, float]]:
    """``w_E`` fixed, ``w_M / w_E`` from 0 then log-spaced over 1e-2 .. 1e3 (plus the nominal)."""
    w_e = scenario.weights.effort
    ratio_values = [0.0, *np.logspace(-2, 3, points - 1)]
    nominal = scenario.weights.manipulability / w_e
    if nominal not in ratio_values:
        ratio_values.append(nominal)
    return [(w_e, float(r * w_e)) for r in sorted(ratio_values)]
