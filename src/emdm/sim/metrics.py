"""Outcomes of a run, computed from its record only (never by separate code paths)."""

from __future__ import annotations

from collections import Counter
from typing import Any

import numpy as np

from .loop import Run


def metrics(run: Run) -> dict[str, Any]:
    """The metrics of DESIGN.md section 3 and a few more, all from the run's record.

    ``total_effort`` is ``sum_k E(qd_k) dt`` (rad^2/s); ``min_joint_margin`` the smallest distance of
    any joint to its position limit over the run (rad); ``min_stop_margin`` the same minus the stop
    distance (negative only if a joint entered its stop zone); ``scaled_steps`` the steps whose task
    was scaled (``alpha < 1``); ``fallback_steps`` the steps solved by a fallback solver.
    """
    sc = run.scenario
    dt = sc.motion.dt
    margin = np.minimum(run.q - sc.arm.q_min, sc.arm.q_max - run.q)
    has_cmd = run.steps > 0
    out: dict[str, Any] = {
        "reached": run.reached,
        "steps": run.steps,
        "time_to_goal": run.time_to_goal,
        "final_time": float(run.t[-1]),
        "final_error": float(run.error_norm[-1]),
        "min_manipulability": float(run.m.min()),
        "mean_manipulability": float(run.m.mean()),
        "final_manipulability": float(run.m[-1]),
        "total_effort": float(run.effort.sum() * dt),
        "mean_manip_rate": float(run.manip_rate.mean()) if has_cmd else 0.0,
        "max_abs_qd": float(np.abs(run.qd).max()) if has_cmd else 0.0,
        "min_joint_margin": float(margin.min()),
        "min_stop_margin": float((margin - sc.damper.stop).min()),
        "path_length": float(np.linalg.norm(np.diff(run.p, axis=0), axis=1).sum()),
        "scaled_steps": int(np.count_nonzero(run.alpha < 1.0)),
        "min_alpha": float(run.alpha.min()) if has_cmd else 1.0,
        "slack_steps": int(np.count_nonzero(np.any(run.delta != 0.0, axis=1))),
        "max_abs_slack": float(np.abs(run.delta).max()) if has_cmd else 0.0,
        "fallback_steps": int(np.count_nonzero(run.fallback)),
        "solvers": dict(Counter(run.solver)),
        "max_kkt_residual": float(run.kkt.max()) if has_cmd else 0.0,
        "max_bound_excess": float(run.bound_excess.max()) if has_cmd else 0.0,
        "median_solve_time": float(np.median(run.solve_time)) if has_cmd else 0.0,
        "median_iterations": float(np.median(run.iterations)) if has_cmd else 0.0,
        "final_q": [float(x) for x in run.q[-1]],
    }
    return out
