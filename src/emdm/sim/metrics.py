"""Outcomes of a run, computed from its record only, by one compiled function for runs and batches.

:func:`outcomes` reduces a record to the outcomes a study compares; :func:`metrics` adds what a
single run's report needs (margins, slack, solvers, certificate) from the same :class:`Run`. The
batch kernel of :mod:`emdm.sim.batch` calls :func:`outcomes` on its records, so a Monte-Carlo
study and a single run can never disagree on what "mean manipulability" means.
"""

from __future__ import annotations

import math
from collections import Counter
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..core.checks import _Checker
from ..core.jit import kernel
from .loop import Run

F64 = NDArray[np.float64]

OUTCOMES = (
    "steps",
    "reached",
    "time_to_goal",
    "min_manipulability",
    "mean_manipulability",
    "total_effort",
    "final_error",
    "max_abs_qd",
    "final_manipulability",
    "min_joint_margin",
    "min_clearance",
)
"""The outcomes :func:`outcomes` writes, in order."""


@kernel(refcount=False)
def outcomes(
    m: F64,
    effort: F64,
    qd: F64,
    e: F64,
    q: F64,
    clearance: F64,
    q_min: F64,
    q_max: F64,
    K: int,
    reached: bool,
    dt: float,
    out: F64,
) -> None:
    """``out[:11]`` = the :data:`OUTCOMES` of states ``0..K`` and commands ``0..K-1``.

    ``time_to_goal = K dt`` (NaN when not reached); ``total_effort = sum_k E(qd_k) dt``
    (rad^2/s); ``final_error = ||e_K||`` (m; and rad for a pose); manipulability over the states
    ``0..K``, and at state ``K``; ``min_joint_margin``: the smallest distance of any joint to
    its position limits over the states ``0..K`` (rad; negative where a joint left them);
    ``min_clearance``: the smallest distance of any link to any obstacle over the states (m;
    ``inf`` without obstacles).
    """
    mmin, msum = math.inf, 0.0
    for k in range(K + 1):
        mmin = min(mmin, m[k])
        msum += m[k]
    total = 0.0
    qmax = 0.0
    for k in range(K):
        total += effort[k]
        for j in range(qd.shape[1]):
            qmax = max(qmax, abs(qd[k, j]))
    out[0] = K
    out[1] = 1.0 if reached else 0.0
    out[2] = K * dt if reached else math.nan
    out[3] = mmin
    out[4] = msum / (K + 1)
    out[5] = total * dt
    if e.shape[1] == 2:
        out[6] = math.hypot(e[K, 0], e[K, 1])
    else:
        acc = 0.0
        for i in range(e.shape[1]):
            acc += e[K, i] * e[K, i]
        out[6] = math.sqrt(acc)
    out[7] = qmax
    out[8] = m[K]
    margin = math.inf
    for k in range(K + 1):
        for j in range(q.shape[1]):
            margin = min(margin, q[k, j] - q_min[j], q_max[j] - q[k, j])
    out[9] = margin
    least = math.inf
    for k in range(K + 1):
        least = min(least, clearance[k])
    out[10] = least


def run_outcomes(run: Run, out: F64) -> None:
    """``out`` = the :data:`OUTCOMES` of a :class:`Run` (the batch kernel's, from its record)."""
    arm = run.scenario.arm_data
    outcomes(
        run.m,
        run.effort,
        run.qd,
        run.e,
        run.q,
        run.clearance,
        arm.q_min,
        arm.q_max,
        run.steps,
        run.reached,
        run.scenario.motion.dt,
        out,
    )


def limit_excess(run: Run) -> F64:
    """Per recorded state and joint: how far the joint is past its position limit (rad; 0
    within its limits), the excursions of the controllers that ignore the limits."""
    sc = run.scenario
    return np.maximum(np.maximum(run.q - sc.arm.q_max, sc.arm.q_min - run.q), 0.0)


def metrics(run: Run) -> dict[str, Any]:
    """Every outcome of a run, all from its record.

    The :data:`OUTCOMES`, plus: ``final_manipulability``; ``min_joint_margin``, the smallest
    distance of any joint to its position limit over the run (rad); ``min_stop_margin``, the same
    minus the stop distance (negative only if a joint entered its stop zone); ``scaled_steps``, the
    steps whose task was scaled (``alpha < 1``); ``fallback_steps``, the steps a fallback solver
    answered; the solvers used, the largest KKT residual and bound excess, and solve statistics;
    in a scene with obstacles ``min_clearance``, the smallest distance of a link to an obstacle
    (m). Raises :class:`~emdm.errors.ScenarioError` unless ``run`` is a Run.
    """
    _Checker("metrics").instance("run", run, Run, "a Run (from emdm.simulate)")
    sc = run.scenario
    K = run.steps
    out = np.empty(len(OUTCOMES))
    run_outcomes(run, out)
    base = dict(zip(OUTCOMES, out.tolist(), strict=True))
    margin = np.minimum(run.q - sc.arm.q_min, sc.arm.q_max - run.q)
    has_cmd = K > 0
    return {
        "reached": run.reached,
        "steps": K,
        "time_to_goal": run.time_to_goal,
        "final_time": float(run.t[-1]),
        "final_error": base["final_error"],
        "min_manipulability": base["min_manipulability"],
        "mean_manipulability": base["mean_manipulability"],
        "final_manipulability": base["final_manipulability"],
        "total_effort": base["total_effort"],
        "mean_manip_rate": float(run.manip_rate.mean()) if has_cmd else 0.0,
        "max_abs_qd": base["max_abs_qd"],
        "min_joint_margin": float(margin.min()),
        "min_stop_margin": float((margin - sc.damper.stop).min()),
        "path_length": float(np.linalg.norm(np.diff(run.p[:, :3], axis=0), axis=1).sum()),
        "scaled_steps": int(np.count_nonzero(run.scaled)),
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
    } | ({"min_clearance": base["min_clearance"]} if sc.obstacles else {})
