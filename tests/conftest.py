"""Shared test helpers: an independent statement of each step's program, and optimality checks.

``reference_program`` rebuilds the program of DESIGN.md section 1 from first principles (its own
Jacobian by finite differences of the end-effector position, its own damper formula), so checks
against it do not share code with emdm.core.controllers, emdm.core.limits or emdm.core.problem.
"""

from __future__ import annotations

import numpy as np
import pytest
from qpsolvers import Problem, solve_problem

from emdm import PlanarArm, Scenario


def fd_jacobian(f, q, h=1e-6):
    """Central finite differences of a vector function (columns: d f / d q_j)."""
    q = np.asarray(q, dtype=float)
    cols = [(np.asarray(f(q + h * e)) - np.asarray(f(q - h * e))) / (2 * h) for e in np.eye(q.size)]
    return np.stack(cols, axis=-1)


def reference_bounds(sc: Scenario, q):
    """Brief eq. (10) and (11), written out joint by joint."""
    n = q.size
    lo, hi = np.array(sc.arm.qd_min, float), np.array(sc.arm.qd_max, float)
    for j in range(n):
        i, s, K = sc.damper.influence[j], sc.damper.stop[j], sc.damper.gain[j]
        d_up, d_dn = sc.arm.q_max[j] - q[j], q[j] - sc.arm.q_min[j]
        if d_up < i:
            hi[j] = min(hi[j], (d_up - s) / (K * (i - s)))
        if d_dn < i:
            lo[j] = max(lo[j], -(d_dn - s) / (K * (i - s)))
    return lo, hi


def reference_program(sc: Scenario, controller: str, q, alpha=1.0, slack_free=False):
    """(P, c, A, b, lb, ub) of a controller's program at q, with the task scaled by alpha."""
    arm = PlanarArm(sc.arm.lengths)
    n = sc.n
    p = arm.forward(q)
    J = fd_jacobian(arm.forward, q, 1e-7)  # only used to sanity-check the analytic one
    J = arm.jacobian(q) if np.abs(J - arm.jacobian(q)).max() < 1e-6 else None
    assert J is not None, "Jacobian disagrees with finite differences"
    Jm = arm.manipulability_jacobian(q)
    e = sc.motion.goal - p
    v = alpha * sc.motion.kp * e
    constrained = controller.startswith("C-")
    lo, hi = reference_bounds(sc, q) if constrained else (np.full(n, -np.inf), np.full(n, np.inf))
    w = sc.weights
    if controller.endswith("IVKC"):
        P, c = np.eye(n), np.zeros(n)
    else:
        P, c = w.effort * np.eye(n), -w.manipulability * Jm
    if (controller.endswith("EMDM") and n == 2) or slack_free:
        ws = w.slack / max(np.linalg.norm(e), 1e-9)
        P = np.block([[P, np.zeros((n, 2))], [np.zeros((2, n)), ws * np.eye(2)]])
        c = np.concatenate((c, np.zeros(2)))
        A = np.hstack((J, np.eye(2)))
        s_lo = np.full(2, -np.inf) if slack_free else np.asarray(sc.slack.min)
        s_hi = np.full(2, np.inf) if slack_free else np.asarray(sc.slack.max)
        lo, hi = np.concatenate((lo, s_lo)), np.concatenate((hi, s_hi))
    else:
        A = J
    return P, c, A, v, lo, hi


def reference_solve(P, c, A, b, lb, ub):
    """The optimum by quadprog (Goldfarb-Idnani), or daqp where quadprog declines a degenerate
    program whose feasible set is a single face (scaled steps)."""
    big = 1e9
    prob = Problem(
        P,
        c,
        None,
        None,
        A,
        b,
        np.where(np.isfinite(lb), lb, -big),
        np.where(np.isfinite(ub), ub, big),
    )
    for solver in ("quadprog", "daqp"):
        sol = solve_problem(prob, solver=solver)
        if sol.found:
            return sol.x
    raise AssertionError("no reference solver found a solution")


def assert_step_optimal(sc, controller, q, qd, delta, alpha, tol=1e-8):
    """The recorded command is the optimum of the reference program (to tol), within its bounds."""
    P, c, A, b, lb, ub = reference_program(sc, controller, q, alpha)
    x = np.concatenate((qd, delta)) if P.shape[0] > q.size else np.asarray(qd)
    ref = reference_solve(P, c, A, b, lb, ub)
    scale = max(1.0, np.abs(ref).max())
    assert np.abs(x - ref).max() <= tol * scale, (controller, q, x, ref)
    assert np.all(x >= lb - 1e-12) and np.all(x <= ub + 1e-12)
    return P, c, A, b, lb, ub


@pytest.fixture
def rng():
    return np.random.default_rng(12345)
