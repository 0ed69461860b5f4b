"""The independent reference: numpy statements of what the compiled kernels compute.

Nothing here imports emdm's kernels. The tests cross-check the kernels against these functions:
kinematics from tip vectors and Cauchy-Binet minors (and, separately, from the textbook formulas),
the certificate by scipy's non-negative least squares, and a whole control loop built from
:func:`conftest.reference_program` and quadprog.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linprog, nnls


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


def textbook_kinematics(lengths, q):
    """(p, J, m, Jm) from m = sqrt(det(J J^T)) and Jm_j = m trace((J J^T)^-1 J H_j^T)."""
    lengths = np.asarray(lengths, float)
    n = lengths.size
    th = np.cumsum(q)
    p = np.array([np.sum(lengths * np.cos(th)), np.sum(lengths * np.sin(th))])
    J = np.array([[-np.sum(lengths[j:] * np.sin(th[j:])) for j in range(n)],
                  [np.sum(lengths[j:] * np.cos(th[j:])) for j in range(n)]])  # fmt: skip
    H = np.zeros((n, 2, n))
    for j in range(n):
        for k in range(n):
            i0 = max(j, k)
            H[j, :, k] = -np.array(
                [np.sum(lengths[i0:] * np.cos(th[i0:])), np.sum(lengths[i0:] * np.sin(th[i0:]))]
            )
    JJt = J @ J.T
    m = float(np.sqrt(np.linalg.det(JJt)))
    inv = np.linalg.inv(JJt)
    return p, J, m, np.array([m * np.trace(inv @ J @ H[j].T) for j in range(n)])


def kkt_residual(P, c, A, b, lb, ub, x, active_tol=1e-9):
    """Largest relative KKT residual of x with scipy-NNLS multipliers over the active bounds."""
    g = P @ x + c
    with np.errstate(invalid="ignore"):
        at_lo = np.isfinite(lb) & (x - lb <= active_tol * (1.0 + np.abs(lb)))
        at_hi = np.isfinite(ub) & (ub - x <= active_tol * (1.0 + np.abs(ub)))
    eye = np.eye(x.size)
    M = np.hstack((A.T, -A.T, eye[:, at_lo], -eye[:, at_hi]))
    z, _ = nnls(M, g, maxiter=50 * M.shape[1])
    scale_g = max(1.0, float(np.abs(P @ x).max()), float(np.abs(c).max()))
    stationarity = float(np.abs(g - M @ z).max()) / scale_g
    scale_eq = max(1.0, float(np.abs(b).max()), float((np.abs(A) @ np.abs(x)).max()))
    equality = float(np.abs(A @ x - b).max()) / scale_eq
    k = A.shape[0]
    mu_lo = z[2 * k : 2 * k + int(at_lo.sum())]
    mu_hi = z[2 * k + int(at_lo.sum()) :]
    comp = max(
        np.abs(mu_lo * (x - lb)[at_lo]).max(initial=0.0),
        np.abs(mu_hi * (ub - x)[at_hi]).max(initial=0.0),
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
