"""The independent reference: numpy statements of what the compiled kernels compute.

Nothing here calls emdm's kernels except ``PlanarArm`` in :func:`reference_program`, whose
Jacobian is checked there against finite differences of the end-effector position. The tests
cross-check the kernels against these functions: kinematics from tip vectors and Cauchy-Binet
minors, the damper bounds joint by joint, each controller's program written out, the optimum by
quadprog or daqp, the certificate by scipy's non-negative least squares, the task scale by an LP.
"""

from __future__ import annotations

import numpy as np
from qpsolvers import Problem, solve_problem
from scipy.optimize import linprog, nnls

from emdm import PlanarArm, Scenario


def tip_vectors(lengths, q):
    th = np.cumsum(q)
    links = np.stack((np.cos(th), np.sin(th))) * lengths
    return np.cumsum(links[:, ::-1], axis=1)[:, ::-1]


def kinematics(lengths, q, singular=1e-14):
    """(p, J, m, Jm) with m = ||c|| over the 2x2 minors and Jm = G^T c / m (numpy)."""
    lengths = np.asarray(lengths, float)
    n = lengths.size
    r = tip_vectors(lengths, q)
    p = r[:, 0].copy()
    J = np.stack((-r[1], r[0]))
    pi, pk = np.triu_indices(n, 1)
    joints = np.arange(n)
    minors = r[0, pi] * r[1, pk] - r[1, pi] * r[0, pk]
    m = float(np.sqrt(minors @ minors))
    gram = r.T @ r
    max_kj = np.maximum(pk[:, None], joints[None, :])
    max_ij = np.maximum(pi[:, None], joints[None, :])
    G = gram[pi[:, None], max_kj] - gram[max_ij, pk[:, None]]
    if m > singular * lengths.sum() ** 2:
        return p, J, m, (G.T @ minors) / m
    _, s, vt = np.linalg.svd(G)
    if s[0] == 0.0:
        return p, J, m, np.zeros(n)
    v1 = vt[0] if vt[0][np.argmax(np.abs(vt[0]))] >= 0 else -vt[0]
    return p, J, m, s[0] * v1 + 0.0


def kkt_residual(P, c, A, b, lb, ub, x, active_tol=1e-9, G=None, h=None):
    """Largest relative KKT residual of x with scipy-NNLS multipliers over the active bounds (and
    the active rows of G x <= h, whose multipliers enter as P x + c = ... - G^T nu, nu >= 0)."""
    g = P @ x + c
    G = np.zeros((0, x.size)) if G is None else np.asarray(G, float)
    h = np.zeros(0) if h is None else np.asarray(h, float)
    with np.errstate(invalid="ignore"):
        at_lo = np.isfinite(lb) & (x - lb <= active_tol * (1.0 + np.abs(lb)))
        at_hi = np.isfinite(ub) & (ub - x <= active_tol * (1.0 + np.abs(ub)))
    on_row = h - G @ x <= active_tol * (1.0 + np.abs(h))
    eye = np.eye(x.size)
    M = np.hstack((A.T, -A.T, eye[:, at_lo], -eye[:, at_hi], -G[on_row].T))
    z, _ = nnls(M, g, maxiter=50 * M.shape[1])
    scale_g = max(1.0, float(np.abs(P @ x).max()), float(np.abs(c).max()))
    stationarity = float(np.abs(g - M @ z).max()) / scale_g
    scale_eq = max(1.0, float(np.abs(b).max()), float((np.abs(A) @ np.abs(x)).max()))
    equality = float(np.abs(A @ x - b).max()) / scale_eq
    k = A.shape[0]
    n_lo, n_hi = int(at_lo.sum()), int(at_hi.sum())
    mu_lo = z[2 * k : 2 * k + n_lo]
    mu_hi = z[2 * k + n_lo : 2 * k + n_lo + n_hi]
    nu = z[2 * k + n_lo + n_hi :]
    comp = max(
        np.abs(mu_lo * (x - lb)[at_lo]).max(initial=0.0),
        np.abs(mu_hi * (ub - x)[at_hi]).max(initial=0.0),
        np.abs(nu * (h - G @ x)[on_row]).max(initial=0.0),
    )
    return max(stationarity, equality, comp / scale_g)


def lp_task_scale(A, b, lb, ub):
    """max alpha in [0, 1] with A x = alpha b, lb <= x <= ub, by an LP (HiGHS); None if none."""
    n = A.shape[1]
    cost = np.zeros(n + 1)
    cost[-1] = -1.0
    A_eq = np.hstack((A, -b.reshape(-1, 1)))
    bounds = [(lo if np.isfinite(lo) else None, hi if np.isfinite(hi) else None)
              for lo, hi in zip(lb, ub, strict=True)] + [(0.0, 1.0)]  # fmt: skip
    res = linprog(cost, A_eq=A_eq, b_eq=np.zeros(A.shape[0]), bounds=bounds, method="highs")
    return float(res.x[-1]) if res.status == 0 else None


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
