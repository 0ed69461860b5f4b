"""Many goals: controllers compared run by run on the same random starts and goals.

A run of the report answers the brief for one start and one goal. This study asks whether its
answers hold elsewhere: every controller runs from the same draws of
:func:`emdm.studies.montecarlo.draw` (starts uniform inside the joint limits, outside the stop
zones; goals ``f(q)`` of ``q`` uniform inside the limits), on the compiled batch loop, and a pair
is compared run by run (paired ratios, summarised by their quartiles).

Where a controller misses goals, its missed runs are run again one by one (:func:`emdm.simulate`)
to record where the arm came to rest: its tip's distance from the base and its last joint.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..core.scenario import Scenario
from ..sim.batch import simulate_batch
from ..sim.loop import simulate
from .montecarlo import draw

AT_STOP = 1e-4
"""rad: a missed run whose smallest joint margin came within this of the stop distance ended
with a joint at its stop (the damper lets it no closer)."""


def quartiles(values: np.ndarray) -> list[float] | None:
    """``[first quartile, median, third quartile]`` of ``values`` (None: no values)."""
    if values.size == 0:
        return None
    return [float(v) for v in np.percentile(values, [25.0, 50.0, 75.0])]


def run_on_draws(
    controllers: Mapping[str, Scenario], runs: int, seed: int
) -> tuple[np.ndarray, np.ndarray, dict[str, dict[str, np.ndarray]]]:
    """Starts, goals and every controller's outcome arrays on the same ``runs`` draws.

    ``controllers`` maps each controller to the scenario it runs in; the draws are those of the
    first one's (its arm and dampers: the scenarios must share them)."""
    first = next(iter(controllers.values()))
    q0s, goals = draw(first, runs, seed)
    out = {
        name: simulate_batch(sc, name, goals=goals, q0s=q0s).outcomes()
        for name, sc in controllers.items()
    }
    return q0s, goals, out


def _wrapped(angle: np.ndarray) -> np.ndarray:
    """Angles in (-pi, pi]."""
    return np.asarray(np.pi - np.mod(np.pi - angle, 2.0 * np.pi))


def controller_summary(
    scenario: Scenario,
    name: str,
    q0s: np.ndarray,
    goals: np.ndarray,
    o: Mapping[str, Any],
    rest: bool = True,
) -> dict[str, Any]:
    """One controller's arrivals and, where it missed, how far its goals and final errors
    were; with ``rest``, its missed runs are run again one by one to record where the arm came
    to rest (its tip's distance from the base and its last joint; None without)."""
    reached = np.asarray(o["reached"], dtype=bool)
    radius = np.linalg.norm(goals[:, :2], axis=1)
    out: dict[str, Any] = {
        "runs": int(reached.size),
        "arrived": int(reached.sum()),
        "time_to_goal": quartiles(np.asarray(o["time_to_goal"])[reached]),
        "missed": None,
    }
    missed = np.flatnonzero(~reached)
    if missed.size:
        tips, last = [], []
        for r in missed if rest else ():
            sc = scenario.with_overrides(
                {"motion.goal": goals[r].tolist(), "motion.q0": q0s[r].tolist()}
            )
            run = simulate(sc, name)
            tips.append(float(np.linalg.norm(run.p[-1][:2])))
            last.append(float(abs(_wrapped(run.q[-1][-1]))))
        margin = np.asarray(o["min_joint_margin"])[missed]
        out["missed"] = {
            "count": int(missed.size),
            # how many came to rest with a joint at its stop distance (the dampers' floor)
            "at_stop": int(np.sum(margin <= float(np.min(scenario.damper.stop)) + AT_STOP)),
            "goal_radius": [float(radius[missed].min()), float(radius[missed].max())],
            "arrived_goal_radius_max": float(radius[reached].max()) if reached.any() else None,
            "final_error": [
                float(np.min(o["final_error"][missed])),
                float(np.max(o["final_error"][missed])),
            ],
            "rest_tip_radius": [min(tips), max(tips)] if tips else None,
            "rest_last_joint": [min(last), max(last)] if last else None,
        }
    return out


def pair_summary(base: Mapping[str, Any], other: Mapping[str, Any]) -> dict[str, Any]:
    """``other`` against ``base`` on the runs both reach the goal: quartiles of the paired
    relative changes of mean manipulability, total effort and time to the goal, and on how many
    of them ``other`` has the higher mean manipulability."""
    both = np.asarray(base["reached"], dtype=bool) & np.asarray(other["reached"], dtype=bool)

    def change(key: str) -> list[float] | None:
        return quartiles(np.asarray(other[key])[both] / np.asarray(base[key])[both] - 1.0)

    higher = np.asarray(other["mean_manipulability"]) > np.asarray(base["mean_manipulability"])
    return {
        "both_arrived": int(both.sum()),
        "mean_manipulability": change("mean_manipulability"),
        "total_effort": change("total_effort"),
        "time_to_goal": change("time_to_goal"),
        "higher_mean_manipulability": int((higher & both).sum()),
    }


def policy_study(
    controllers: Mapping[str, Scenario],
    pairs: Mapping[str, tuple[str, str]],
    runs: int,
    seed: int,
    rest: tuple[str, ...] = (),
) -> dict[str, Any]:
    """Every controller of ``controllers`` on the same draws, summarised, and each pair
    ``label -> (base, other)`` compared run by run; the missed runs of the controllers in
    ``rest`` are run again to record where they came to rest (one by one: seconds)."""
    q0s, goals, out = run_on_draws(controllers, runs, seed)
    return {
        "controllers": {
            name: controller_summary(sc, name, q0s, goals, out[name], rest=name in rest)
            for name, sc in controllers.items()
        },
        "pairs": {
            label: pair_summary(out[base], out[other]) for label, (base, other) in pairs.items()
        },
    }


def weight_study(
    scenario: Scenario, controller: str, weights: list[tuple[float, float]], runs: int, seed: int
) -> list[dict[str, Any]]:
    """``controller`` on the same draws at each ``(w_E, w_M)`` of ``weights``, each compared
    run by run with the scenario's own weights."""
    nominal = {controller: scenario}
    q0s, goals, base = run_on_draws(nominal, runs, seed)
    rows = []
    for w_e, w_m in weights:
        sc = scenario.with_overrides({"weights.effort": w_e, "weights.manipulability": w_m})
        o = simulate_batch(sc, controller, goals=goals, q0s=q0s).outcomes()
        rows.append(
            {
                "w_effort": w_e,
                "w_manip": w_m,
                "arrived": int(np.sum(o["reached"])),
                **pair_summary(base[controller], o),
            }
        )
    return rows


def term_study(
    scenario: Scenario,
    controller: str,
    overrides: Mapping[str, Any],
    runs: int,
    seed: int,
    beyond: float | None = None,
) -> dict[str, Any]:
    """What a change (``overrides``: a term's weight set to 0, say) does to ``controller``'s
    arrivals on the same draws: how many arrive with it, how many goals the scenario's own
    controller reaches that the changed one does not (``gained``) and the reverse (``lost``:
    the goals the unchanged one misses and the changed one reaches), and of those lost, how
    many lie farther than ``beyond`` from the base (None: not asked)."""
    changed = scenario.with_overrides(dict(overrides))
    q0s, goals, out = run_on_draws({controller: scenario}, runs, seed)
    other = simulate_batch(changed, controller, goals=goals, q0s=q0s).outcomes()
    base = np.asarray(out[controller]["reached"], dtype=bool)
    new = np.asarray(other["reached"], dtype=bool)
    lost = new & ~base
    radius = np.linalg.norm(goals[:, :2], axis=1)
    return {
        "overrides": dict(overrides),
        "arrived": int(new.sum()),
        "lost": int(lost.sum()),
        "gained": int((base & ~new).sum()),
        "lost_beyond": int((lost & (radius >= beyond)).sum()) if beyond is not None else None,
        "beyond": beyond,
    }
