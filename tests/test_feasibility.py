"""The exact task scale and feasible point against an LP solver (HiGHS) on random programs."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog

from emdm import feasible_point, task_scale


def random_instance(rng, trial):
    n = int(rng.integers(1, 8))
    A = rng.normal(size=(2, n))
    if trial % 5 == 0 and n > 1:
        A[:, 1] = A[:, 0] * rng.normal()  # parallel generators
    if trial % 7 == 0:
        A[1] = 0.5 * A[0]  # rank-one task (singular Jacobian)
    if trial % 11 == 0:
        A[:, rng.integers(n)] = 0.0
    lb, ub = -rng.uniform(0, 2, n), rng.uniform(0, 2, n)
    if trial % 3 == 0:  # boxes that exclude zero
        lb = lb + rng.uniform(-1, 1, n)
        ub = np.maximum(ub, lb) + rng.uniform(0, 0.5, n)
    if trial % 13 == 0:
        ub = lb.copy()  # a fixed variable
    free = rng.random(n) < 0.2
    lb[free], ub[free] = -np.inf, np.inf
    b = rng.normal(size=2) * rng.uniform(0.1, 5)
    return A, b, lb, ub


def lp_max_scale(A, b, lb, ub):
    n = A.shape[1]
    bounds = [
        (lo if np.isfinite(lo) else None, hi if np.isfinite(hi) else None)
        for lo, hi in zip(lb, ub, strict=True)
    ] + [(0, 1)]
    res = linprog(
        np.r_[np.zeros(n), -1.0], A_eq=np.c_[A, -b], b_eq=np.zeros(2), bounds=bounds, method="highs"
    )
    return None if res.status == 2 else -res.fun


def test_task_scale_and_feasible_point_match_lp(rng):
    feasible = 0
    for trial in range(1500):
        A, b, lb, ub = random_instance(rng, trial)
        ref = lp_max_scale(A, b, lb, ub)
        alpha = task_scale(A, b, lb, ub)
        if ref is None:
            assert alpha is None, trial
            assert feasible_point(A, b, lb, ub) is None
            continue
        feasible += 1
        assert alpha == pytest.approx(ref, abs=1e-9), trial
        x = feasible_point(A, alpha * b, lb, ub)
        assert x is not None, trial
        assert np.all(x >= lb) and np.all(x <= ub), trial
        np.testing.assert_allclose(A @ x, alpha * b, atol=1e-10)
        if alpha < 1 - 1e-6:  # slightly more than the largest scale is infeasible
            assert feasible_point(A, min(1.0, alpha + 1e-6) * b, lb, ub) is None, trial
    assert feasible > 1000


def test_brief_task1_start_is_infeasible_with_scale_about_018():
    from emdm import load_scenario
    from emdm.core.controllers import joint_bounds

    sc = load_scenario("task1")
    q0 = np.asarray(sc.motion.q0)
    J = sc.planar_arm.jacobian(q0)
    v = sc.motion.kp * (sc.motion.goal - sc.planar_arm.forward(q0))
    bounds = joint_bounds(sc, q0)
    alpha = task_scale(J, v, bounds.lo, bounds.hi)
    assert np.linalg.norm(v) == pytest.approx(1.5707, abs=1e-3)
    assert alpha == pytest.approx(lp_max_scale(J, v, bounds.lo, bounds.hi), abs=1e-12)
    assert 0.17 < alpha < 0.19


def test_free_variables_only():
    A = np.array([[1.0, 0.0], [0.0, 2.0]])
    assert task_scale(A, np.array([1.0, 1.0]), np.full(2, -np.inf), np.full(2, np.inf)) == 1.0
    singular = np.array([[1.0, 1.0], [2.0, 2.0]])
    inf = np.full(2, np.inf)
    assert task_scale(singular, np.array([1.0, 0.0]), -inf, inf) == 0.0
    assert feasible_point(singular, np.array([1.0, 0.0]), -inf, inf) is None
    x = feasible_point(singular, np.array([1.0, 2.0]), -inf, inf)
    np.testing.assert_allclose(singular @ x, [1.0, 2.0])


def test_half_bounded_variables_go_to_highs():
    """The kernels take variables bounded on both sides or free; a half-bounded one is left to
    HiGHS, whose answer is checked: x0 >= 0 allows the direction (1, 1) in full and (-1, 1) not
    at all."""
    lb, ub = np.array([0.0, -np.inf]), np.array([np.inf, np.inf])
    assert task_scale(np.eye(2), np.ones(2), lb, ub) == 1.0
    assert task_scale(np.eye(2), np.array([-1.0, 1.0]), lb, ub) == 0.0
    x = feasible_point(np.eye(2), np.array([2.0, -3.0]), lb, ub)
    np.testing.assert_allclose(x, [2.0, -3.0])
    assert feasible_point(np.eye(2), np.array([-2.0, 3.0]), lb, ub) is None


def test_velocity_set_is_the_hull_of_the_box_corners():
    import itertools

    from scipy.spatial import ConvexHull

    from emdm.core.feasibility import velocity_set

    rng = np.random.default_rng(3)
    for trial in range(100):
        n = int(rng.integers(1, 7))
        J = rng.normal(size=(2, n))
        lb, ub = -rng.uniform(0.1, 2, n), rng.uniform(0.1, 2, n)
        if trial % 4 == 0:
            lb[0] = ub[0]  # a joint held at one speed: a translation, no side
        V = velocity_set(J, lb, ub)
        corners = np.array(
            [J @ np.where(np.array(c, bool), ub, lb) for c in itertools.product((0, 1), repeat=n)]
        )
        x, y = V[:, 0], V[:, 1]
        signed = 0.5 * float(x @ np.roll(y, -1) - y @ np.roll(x, -1))
        if n - (trial % 4 == 0) >= 2:
            assert signed == pytest.approx(ConvexHull(corners).volume, rel=1e-9)  # area, CCW
        # every corner of the box maps inside, and every vertex is a corner's image
        edges = np.roll(V, -1, axis=0) - V
        for c in corners:
            cross = edges[:, 0] * (c[1] - V[:, 1]) - edges[:, 1] * (c[0] - V[:, 0])
            assert cross.min() >= -1e-9
        assert all(np.min(np.linalg.norm(corners - v, axis=1)) < 1e-9 for v in V)
    assert np.isnan(velocity_set(np.eye(2), np.array([-np.inf, 0.0]), np.ones(2))).all()
    with pytest.raises(ValueError):
        velocity_set(np.eye(3), np.zeros(3), np.ones(3))
    # a stack is the sets one by one
    Js, lbs, ubs = rng.normal(size=(5, 2, 4)), -rng.uniform(0, 1, (5, 4)), rng.uniform(0, 1, (5, 4))
    lbs[2, 1] = -np.inf
    stacked = velocity_set(Js, lbs, ubs)
    for k in range(5):
        assert np.array_equal(stacked[k], velocity_set(Js[k], lbs[k], ubs[k]), equal_nan=True)
