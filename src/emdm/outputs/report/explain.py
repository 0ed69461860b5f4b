"""What shaped each run, detected from its record (never canned): the report's explanations.

:func:`run_events` reduces one :class:`~emdm.sim.loop.Run` to the events that explain it: task
scaling (``alpha < 1``) and for how long, joints pinned at a velocity limit, a damper or a stop,
a stall and the joint that causes it, near-singular passages (and elbow flips of a two-link arm),
where the effort was spent, the conditioning along the whole trajectory (``cond J`` and the slack
weight ``w_S = c_S/||e||`` at every state, not at a sample), and the solver's work.
:func:`pair_events` compares two runs of a pair (the steps on which they must coincide, the
largest distance between their end-effector paths). :func:`geometry` gives, for a two-link arm,
the two inverse-kinematics solutions of the goal, whether each lies within the joint limits, and
the innermost point the arm reaches with its joints outside the stop zones.
:func:`front_events` classifies the Pareto fronts (degenerate, saturated). All of it is written to
JSON beside the records (``events.json``) and read back by the report like any other number.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ...core.scenario import Scenario
from ...sim.loop import Run
from ...sim.metrics import limit_excess, metrics

SAME = 1e-9
"""Two commands coincide when they differ by at most this (rad/s)."""


def _episodes(mask: np.ndarray) -> list[tuple[int, int]]:
    """Maximal runs ``[start, end]`` (inclusive) of True in a boolean vector."""
    if not mask.any():
        return []
    padded = np.concatenate(([False], mask, [False])).astype(np.int8)
    edges = np.flatnonzero(np.diff(padded))
    return [(int(a), int(b) - 1) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def _cond(J: np.ndarray) -> float:
    s = np.linalg.svd(J, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 1e-12 * max(s[0], 1e-300) else math.inf


ZERO_ALPHA = 1e-12
"""A task scale at or below this counts as zero (``zero_from_t``): a damper bound shrinks
geometrically and never reaches 0 exactly."""


def scaling(run: Run) -> dict[str, Any] | None:
    """Steps whose task was scaled (``alpha < 1``): when, how long, how deep, where it hit 0."""
    a = run.alpha
    mask = run.scaled
    if not mask.any():
        return None
    dt = run.scenario.motion.dt
    eps = _episodes(mask)
    first, last = eps[0][0], eps[-1][1]
    zero = np.flatnonzero(a <= ZERO_ALPHA)
    k_min = int(np.argmin(a))
    return {
        "steps": int(mask.sum()),
        "episodes": len(eps),
        "first_t": float(run.t[first]),
        "last_t": float(run.t[last]),
        "duration": float(mask.sum() * dt),
        "first_duration": float((eps[0][1] - eps[0][0] + 1) * dt),
        "end_t": float(run.t[eps[0][1] + 1]),
        "min_alpha": float(a[k_min]),
        "t_min_alpha": float(run.t[k_min]),
        "initial_alpha": float(a[0]),
        "zero_steps": int(zero.size),
        "zero_from_t": float(run.t[zero[0]]) if zero.size else None,
        "whole_run": bool(mask.all()),
    }


def pinned(run: Run) -> list[dict[str, Any]]:
    """Episodes of joints commanded at a bound, longest first.

    ``kind`` is ``velocity`` when the bound is the joint-velocity limit and ``damper`` when the
    position damper set it (tighter than the velocity limit); ``side`` is ``upper`` or ``lower``.
    """
    sc = run.scenario
    if run.steps == 0 or not np.isfinite(run.hi).any():
        return []
    dt = sc.motion.dt
    out: list[dict[str, Any]] = []
    for j in range(sc.n):
        for side, bound, limit in (
            ("upper", run.hi[:, j], sc.arm.qd_max[j]),
            ("lower", run.lo[:, j], sc.arm.qd_min[j]),
        ):
            at = run.active[:, j] == (1 if side == "upper" else -1)  # the record's definition
            for kind, mask in (
                ("velocity", at & np.isclose(bound, limit, rtol=0, atol=1e-12)),
                ("damper", at & ~np.isclose(bound, limit, rtol=0, atol=1e-12)),
            ):
                for a, b in _episodes(mask):
                    out.append(
                        {
                            "joint": j + 1,
                            "side": side,
                            "kind": kind,
                            "t0": float(run.t[a]),
                            "t1": float(run.t[b + 1]),  # the last command's end
                            "t_last": float(run.t[b]),  # the last step on the bound
                            "steps": b - a + 1,
                            "duration": float((b - a + 1) * dt),
                        }
                    )
    out.sort(key=lambda e: (-e["steps"], e["t0"]))
    return out


def stall(run: Run) -> dict[str, Any] | None:
    """A run that stops making progress: from when, at which error, and which joint blocks it."""
    k = run.stalled_from  # the record's one definition of a stall
    if k is None:
        return None
    sc = run.scenario
    err = run.error_norm
    q = run.q[-1]
    upper = sc.arm.q_max - sc.damper.stop - q
    lower = q - (sc.arm.q_min + sc.damper.stop)
    j = int(np.argmin(np.minimum(upper, lower)))
    side = "upper" if upper[j] <= lower[j] else "lower"
    return {
        "t": float(run.t[k]),
        "error": float(err[-1]),
        "progress": float(err[0] - err[-1]),
        "joint": j + 1,
        "side": side,
        "q": float(q[j]),
        "stop_edge": float(sc.arm.q_max[j] - sc.damper.stop[j])
        if side == "upper"
        else float(sc.arm.q_min[j] + sc.damper.stop[j]),
        "distance_to_stop": float(min(upper[j], lower[j])),
        "final_alpha": float(run.alpha[-1]),
        "final_hi": float(run.hi[-1, j]),
        "final_lo": float(run.lo[-1, j]),
    }


def obstacles(run: Run) -> dict[str, Any] | None:
    """In a scene with obstacles: the smallest clearance, when, between which link and obstacle,
    the steps with obstacle rows active, and whether a stall happened at an obstacle (the final
    clearance within the influence distance) rather than at a joint."""
    sc = run.scenario
    if not sc.obstacles:
        return None
    k = int(np.argmin(run.clearance))
    D = sc.obstacle_distances(run.q[k], float(run.t[k]))
    link, o = (int(v) for v in np.unravel_index(int(np.argmin(D)), D.shape))
    od = sc.obstacle_damper
    final = float(run.clearance[-1])
    stalled = run.stalled_from is not None
    at_obstacle = stalled and final < od.influence
    return {
        "min_clearance": float(run.clearance[k]),
        "t_min": float(run.t[k]),
        "link": link + 1,
        "obstacle": o + 1,
        "shape": sc.obstacles[o].shape,
        "stop": od.stop,
        "entered": bool(run.clearance.min() < od.stop),
        "sees_obstacles": bool(run.rows.max(initial=0) > 0) if run.steps else False,
        "active_row_steps": int(np.count_nonzero(run.rows_active)),
        "stalled_at_obstacle": bool(at_obstacle),
        "final_clearance": final,
    }


def obstacle_sentence(name: str, event: dict[str, Any] | None) -> str | None:
    """One line on a run among obstacles, from :func:`obstacles` (``None`` without them)."""
    if event is None:
        return None
    where = (
        f"link {event['link']} came within {event['min_clearance']:.4f} m of obstacle "
        f"{event['obstacle']} (a {event['shape']}) at t = {event['t_min']:.2f} s"
    )
    return _verdict(
        name, where, event, "obstacles", event["sees_obstacles"],
        "in front of an obstacle" if event["stalled_at_obstacle"] else None,
    )  # fmt: skip


def _verdict(
    name: str, where: str, event: dict[str, Any], what: str, sees: bool, stalled: str | None
) -> str:
    """The line shared by obstacles and planes: entered (and whether the controller sees the
    rows), stalled at them, or kept outside the stop distance."""
    if event["entered"]:
        return f"{name}: {where}, inside the stop distance ({event['stop']:g} m): it " + (
            f"does not see the {what}." if not sees else "was entered."
        )
    if stalled:
        return (
            f"{name}: stalled {stalled} ({where}; its rows held the task back on "
            f"{event['active_row_steps']} steps)."
        )
    return f"{name}: {where}, outside the stop distance ({event['stop']:g} m)."


def planes(run: Run) -> dict[str, Any] | None:
    """With a ``[planes]`` section: the end effector's smallest distance to any plane, when and to
    which, whether the stop distance was crossed, the steps with a row held, and whether the run
    stalled within a plane's influence (its rows, not a joint, held the task back)."""
    sc = run.scenario
    if not sc.planes.count:
        return None
    D = np.array([sc.plane_distances(q) for q in run.q])  # states x planes
    k, i = (int(v) for v in np.unravel_index(int(np.argmin(D)), D.shape))
    pl = sc.planes
    final = float(D[-1].min())
    return {
        "min_distance": float(D[k, i]),
        "t_min": float(run.t[k]),
        "plane": i + 1,
        "stop": pl.stop,
        "entered": bool(D[k, i] < pl.stop),
        "sees_planes": bool(run.rows.max(initial=0) > 0) if run.steps else False,
        "active_row_steps": int(np.count_nonzero(run.rows_active)),
        "stalled_at_plane": bool(run.stalled_from is not None and final < pl.influence),
        "final_distance": final,
    }


def plane_sentence(name: str, event: dict[str, Any] | None) -> str | None:
    """One line on a run beside planes, from :func:`planes` (``None`` without them)."""
    if event is None:
        return None
    where = (
        f"the end effector came within {event['min_distance']:.4f} m of plane {event['plane']} "
        f"at t = {event['t_min']:.2f} s"
    )
    return _verdict(
        name, where, event, "planes", event["sees_planes"],
        "at a plane" if event["stalled_at_plane"] else None,
    )  # fmt: skip


def singular(run: Run) -> dict[str, Any]:
    """The smallest manipulability, when, and (two-link arm) the elbow flips through ``q2 = 0``."""
    k = int(np.argmin(run.m))
    out: dict[str, Any] = {
        "m_min": float(run.m[k]),
        "t": float(run.t[k]),
        "m0": float(run.m[0]),
        "m_max": float(run.m.max()),
        "near": bool(run.m[k] < 0.05 * run.m.max()),
    }
    if run.scenario.n == 2:
        s = np.sign(np.sin(run.q[:, 1]))
        flips = np.flatnonzero(s[1:] * s[:-1] < 0) + 1
        out["elbow_flips"] = [float(run.t[f]) for f in flips]
        out["elbow_final"] = "up" if run.q[-1, 1] > 0 else "down"
    return out


def conditioning(run: Run) -> dict[str, Any]:
    """``cond J`` and ``w_S = c_S/||e||`` at every state of the run (the worst, and when)."""
    arm = run.scenario.planar_arm
    cond = np.array([_cond(arm.jacobian(q)) for q in run.q])
    finite = np.where(np.isfinite(cond), cond, np.inf)
    k = int(np.argmax(finite))
    w_s = run.scenario.weights.slack / np.maximum(run.error_norm, 1e-9)
    return {
        "cond_J_max": float(cond[k]) if math.isfinite(cond[k]) else None,
        "t_cond_J_max": float(run.t[k]),
        "cond_J_start": float(cond[0]),
        "cond_J_median": float(np.median(cond[np.isfinite(cond)]))
        if np.isfinite(cond).any()
        else None,
        "singular_states": int((~np.isfinite(cond)).sum()),
        "w_slack_start": float(w_s[0]),
        "w_slack_end": float(w_s[-1]),
        # the largest weight a solved program had: the states before the last (at the last the
        # goal is reached and nothing is solved)
        "w_slack_max_solved": float(w_s[: run.steps].max()) if run.steps else float(w_s[0]),
    }


def effort(run: Run) -> dict[str, Any]:
    """Where the effort ``sum E dt`` was spent: half of it by when, the share of the first second."""
    dt = run.scenario.motion.dt
    if run.steps == 0:
        return {"total": 0.0}
    cum = np.cumsum(run.effort) * dt
    total = float(cum[-1])
    k_half = int(np.searchsorted(cum, 0.5 * total))
    first = min(run.steps, round(1.0 / dt))
    k_peak = int(np.argmax(run.effort))
    return {
        "total": total,
        "t_half": float(run.t[k_half + 1]),
        "share_first_second": float(cum[first - 1] / total) if total > 0 else 0.0,
        "peak": float(run.effort[k_peak]),
        "t_peak": float(run.t[k_peak]),
    }


def limits(run: Run) -> dict[str, Any]:
    """The deepest excursion past a joint limit (UC controllers ignore them) and the fastest joint."""
    sc = run.scenario
    over = limit_excess(run)
    k, j = np.unravel_index(int(np.argmax(over)), over.shape)
    out: dict[str, Any] = {
        "max_excess": float(over[k, j]),
        "excess_joint": int(j) + 1,
        "t_excess": float(run.t[k]),
        "time_outside": float((over.max(axis=1) > 0).sum() * sc.motion.dt),
        # every joint's deepest excursion (0: it stayed within its limits)
        "excess_by_joint": [float(x) for x in over.max(axis=0)],
    }
    if run.steps:
        kq, jq = np.unravel_index(int(np.argmax(np.abs(run.qd))), run.qd.shape)
        out.update(
            max_abs_qd=float(abs(run.qd[kq, jq])), qd_joint=int(jq) + 1, t_qd=float(run.t[kq])
        )
    return out


def solver_work(run: Run) -> dict[str, Any]:
    """Iterations, fallbacks and the certificate of the run's solver; ``_warm``: over the steps
    after the first, which start from the last step's working set (the first starts cold,
    reading 163: its count had been said as a warm start's)."""
    if run.steps == 0:
        return {}
    its = np.asarray(run.iterations)
    warm = its[1:] if its.size > 1 else its
    return {
        "median_iterations": float(np.median(its)),
        "max_iterations": int(its.max()),
        "median_iterations_warm": float(np.median(warm)),
        "max_iterations_warm": int(warm.max()),
        "t_max_iterations": float(run.t[int(np.argmax(its))]),
        "fallback_steps": int(np.count_nonzero(run.fallback)),
        "max_kkt": float(np.max(run.kkt)),
        "median_solve_time": float(np.median(run.solve_time)),
    }


FD_STEP = 1e-6
"""Step (rad) of the central differences that check a run's Jacobians (:func:`derivatives`):
truncation about ``h^2`` and rounding about ``eps/h``, both below 1e-9 here."""


def derivatives(run: Run) -> dict[str, Any]:
    """``J`` and ``J_m`` as the compiled kinematics give them, against central differences of
    the tip position ``f(q)`` and of ``m(q)``, at every state of the run: the largest absolute
    differences (m/rad and m^2/rad), so that a reader without the brief's code knows the
    derivatives the controllers used are right."""
    arm = run.scenario.planar_arm
    h, n = FD_STEP, run.scenario.n
    worst_J = worst_Jm = 0.0
    for q in run.q:
        kin = arm.kinematics(q)
        for i in range(n):
            step = np.zeros(n)
            step[i] = h
            up, down = arm.kinematics(q + step), arm.kinematics(q - step)
            worst_J = max(worst_J, float(np.abs((up.p - down.p) / (2 * h) - kin.J[:, i]).max()))
            worst_Jm = max(worst_Jm, abs((up.m - down.m) / (2 * h) - float(kin.Jm[i])))
    return {
        "states": int(run.q.shape[0]),
        "step": h,
        "max_error_J": worst_J,
        "max_error_Jm": worst_Jm,
    }


def run_events(run: Run) -> dict[str, Any]:
    """Every detected event of one run (see the module docstring)."""
    mt = metrics(run)
    straight = float(np.linalg.norm(run.scenario.motion.goal - run.p[0]))
    slack = np.linalg.norm(run.delta, axis=1) if run.steps else np.zeros(0)
    return {
        "reached": bool(run.reached),
        "time_to_goal": run.time_to_goal,
        "final_time": float(run.t[-1]),
        "final_error": float(run.error_norm[-1]),
        "initial_error": float(run.error_norm[0]),
        "mean_manipulability": mt["mean_manipulability"],
        "total_effort": mt["total_effort"],
        "path_length": mt["path_length"],
        "straight_length": straight,
        "detour": mt["path_length"] / straight - 1.0 if straight > 0 else 0.0,
        "scaling": scaling(run),
        "pinned": pinned(run)[:6],
        "stall": stall(run),
        "obstacles": obstacles(run),
        "planes": planes(run),
        "singular": singular(run),
        "conditioning": conditioning(run),
        "derivatives": derivatives(run),
        "effort": effort(run),
        "limits": limits(run),
        "solver": solver_work(run),
        "slack": {
            "max": float(slack.max()) if slack.size else 0.0,
            "t_max": float(run.t[int(np.argmax(slack))]) if slack.size else 0.0,
            "saturated_steps": int(
                np.count_nonzero(
                    np.any(
                        np.isclose(run.delta, run.scenario.slack.max, rtol=0, atol=1e-9)
                        | np.isclose(run.delta, run.scenario.slack.min, rtol=0, atol=1e-9),
                        axis=1,
                    )
                    & np.any(run.delta != 0, axis=1)
                )
            )
            if slack.size
            else 0,
        },
    }


def pair_events(a: Run, b: Run) -> dict[str, Any]:
    """How two runs of a pair relate: the leading steps on which their commands coincide (and
    whether those are all task-scaled steps, where the admissible set is a single point), and the
    largest distance between their end-effector paths over the common states."""
    n = min(a.steps, b.steps)
    diff = np.abs(a.qd[:n] - b.qd[:n]).max(axis=1) if n else np.zeros(0)
    apart = np.flatnonzero(diff > SAME)
    same = int(apart[0]) if apart.size else n
    scaled = bool(same > 0 and np.all(a.alpha[:same] < 1.0) and np.all(b.alpha[:same] < 1.0))
    scaled_steps = int(np.count_nonzero((a.alpha[:same] < 1.0) & (b.alpha[:same] < 1.0)))
    states = min(a.q.shape[0], b.q.shape[0])
    gap = np.linalg.norm(a.p[:states] - b.p[:states], axis=1)
    determined = 0
    if same and np.isfinite(a.hi[:same]).any():
        at = a.active[:same] != 0  # the record's definition of a joint at a bound
        free = a.scenario.n - at.sum(axis=1)
        determined = int(np.count_nonzero(free <= 2))  # two task equations fix two free joints
    return {
        "coincide_steps": same,
        "coincide_until_t": float(a.t[same]) if same < a.t.size else float(a.t[-1]),
        "coincide_scaled_steps": scaled_steps,
        "coincide_all_scaled": scaled,
        "coincide_determined_steps": determined,
        "max_path_gap": float(gap.max()) if gap.size else 0.0,
        "t_max_path_gap": float(a.t[int(np.argmax(gap))]) if gap.size else 0.0,
        # the mean manipulability over the states both runs have (each run's own mean, in its
        # metrics, covers its own horizon: a run that stands still to the time limit weighs in
        # its standstill)
        "common_until_t": float(a.t[states - 1]),
        "mean_m_common": {r.controller.name: float(np.mean(r.m[:states])) for r in (a, b)},
    }


def geometry(scenario: Scenario, start: np.ndarray) -> dict[str, Any] | None:
    """Two-link arm: the goal's two inverse-kinematics solutions and what the joint stops allow."""
    if scenario.n != 2:
        return None
    l1, l2 = (float(x) for x in scenario.link_lengths)
    goal = np.asarray(scenario.motion.goal, dtype=float)
    r2 = float(goal @ goal)
    c2 = (r2 - l1 * l1 - l2 * l2) / (2 * l1 * l2)
    solutions = []
    if abs(c2) <= 1.0:
        for elbow, sign in (("up", 1.0), ("down", -1.0)):
            q2 = sign * math.acos(c2)
            q1 = math.atan2(goal[1], goal[0]) - math.atan2(
                l2 * math.sin(q2), l1 + l2 * math.cos(q2)
            )
            q1 = (q1 + math.pi) % (2 * math.pi) - math.pi
            q = np.array([q1, q2])
            lo, hi = scenario.arm.q_min, scenario.arm.q_max
            inside = bool(np.all(q >= lo) and np.all(q <= hi))
            worst = int(np.argmax(np.maximum(q - hi, lo - q)))
            solutions.append(
                {
                    "elbow": elbow,
                    "q1": q1,
                    "q2": q2,
                    "within_limits": inside,
                    "outside_joint": None if inside else worst + 1,
                    "outside_by": float(max(q[worst] - hi[worst], lo[worst] - q[worst], 0.0)),
                }
            )
    # innermost reach with |q2| outside the stop zone (folding is limited by joint 2's stop)
    fold = min(
        abs(float(scenario.arm.q_max[1] - scenario.damper.stop[1])),
        abs(float(scenario.arm.q_min[1] + scenario.damper.stop[1])),
    )
    inner = math.sqrt(max(l1 * l1 + l2 * l2 + 2 * l1 * l2 * math.cos(min(fold, math.pi)), 0.0))
    p0 = np.asarray(start, dtype=float)
    d = goal - p0
    s = float(np.clip(-(p0 @ d) / (d @ d), 0.0, 1.0))
    closest = p0 + s * d
    line_min = float(np.linalg.norm(closest))
    # where the straight line first enters the disc the folded arm cannot reach
    enter = None
    if line_min < inner:
        a, b, c = float(d @ d), float(2 * p0 @ d), float(p0 @ p0) - inner * inner
        disc = b * b - 4 * a * c
        if disc >= 0:
            enter = float((-b - math.sqrt(disc)) / (2 * a) * math.sqrt(a))
    return {
        "start_elbow": "up" if scenario.motion.q0[1] > 0 else "down",
        "solutions": solutions,
        "max_fold": fold,
        "inner_reach": inner,
        "line_min_distance": line_min,
        "line_blocked": bool(line_min < inner),
        "line_enters_at": enter,
        "reach": l1 + l2,
    }


def front_events(data: dict[str, Any]) -> list[dict[str, Any]]:
    """Each Pareto front of ``pareto.json``: how many distinct optima it has, whether it is one
    point (degenerate: a task-scaled step, whose admissible set is a single point) and the weight
    ratio from which every larger ratio gives the same optimum (saturated: bounds active)."""
    out = []
    for step in data["steps"]:
        pts = step["points"]
        E = np.array([p["E"] for p in pts])
        M = np.array([p["M"] for p in pts])
        ratio = [p["w_manip"] / p["w_effort"] for p in pts]
        scale = max(float(np.abs(E).max()), float(np.abs(M).max()), 1e-300)

        def same(
            i: int, k: int, E: np.ndarray = E, M: np.ndarray = M, scale: float = scale
        ) -> bool:
            return bool(abs(E[i] - E[k]) <= 1e-9 * scale and abs(M[i] - M[k]) <= 1e-9 * scale)

        distinct: list[int] = []
        for i in range(len(pts)):
            if not any(same(i, k) for k in distinct):
                distinct.append(i)
        last = len(pts) - 1
        sat = last
        while sat > 0 and same(sat - 1, last):
            sat -= 1
        nondominated = [
            i
            for i in distinct
            if not any(E[k] <= E[i] and M[k] >= M[i] and not same(i, k) for k in range(len(pts)))
        ]
        out.append(
            {
                "k": step["k"],
                "t": step["t"],
                "points": len(pts),
                "distinct": len(distinct),
                "nondominated": len(nondominated),
                "degenerate": len(distinct) == 1,
                "alpha": float(min(p["alpha"] for p in pts)),
                "saturated_from_ratio": ratio[sat] if 0 < sat < last else None,
                "saturated_points": last - sat + 1 if 0 < sat < last else 0,
                "E_min": float(E.min()),
                "E_max": float(E.max()),
                "M_min": float(M.min()),
                "M_max": float(M.max()),
                # a task-scaled step's front under the free slack (6) instead, when computed
                "slack_distinct": _distinct(step["slack_points"])
                if "slack_points" in step
                else None,
            }
        )
    return out


def _distinct(points: list[dict[str, Any]]) -> int:
    """How many different optima (E, M) ``points`` hold (relative tolerance 1e-9)."""
    scale = max(max(abs(p["E"]), abs(p["M"])) for p in points) or 1e-300
    seen: list[tuple[float, float]] = []
    for p in points:
        if not any(
            abs(p["E"] - e) <= 1e-9 * scale and abs(p["M"] - m) <= 1e-9 * scale for e, m in seen
        ):
            seen.append((p["E"], p["M"]))
    return len(seen)
