"""General inequality rows ``G x <= h`` in the per-step program: the compiled active set (cold and
warm), its certificate and multipliers, the task scale and the feasible point, and the Python
solver chain, against quadprog, HiGHS and the independent NNLS certificate of tests/reference.py."""

from __future__ import annotations

import numpy as np
import pytest
import reference
from qpsolvers import Problem, solve_problem
from scipy.optimize import linprog

from emdm.core import simplex as core
from emdm.core.feasibility import feasible_point, task_scale
from emdm.core.problem import QP
from emdm.solvers import kernels, kkt_report, solve_chain
from emdm.solvers.base import multipliers


def random_program(rng, nt, n, ng, slack=False, reach=1.0):
    """A strictly convex program with nt task rows, n joints in a box, ng rows G x <= h cutting
    through the box (some active at the optimum), optional task slack; the task is ``reach``
    times the image of an interior point that keeps every row."""
    J = rng.normal(size=(nt, n))
    lo, hi = -rng.uniform(0.3, 1.5, n), rng.uniform(0.3, 1.5, n)
    x_in = rng.uniform(0.5 * lo, 0.5 * hi)
    G = rng.normal(size=(ng, n))
    h = G @ x_in + rng.uniform(0.0, 0.4, ng)
    b = J @ x_in * reach
    P = np.diag(rng.uniform(0.05, 2.0, n))
    c = rng.normal(size=n) * 2.0
    if slack:
        P = np.block([[P, np.zeros((n, nt))], [np.zeros((nt, n)), 3.0 * np.eye(nt)]])
        c = np.concatenate((c, np.zeros(nt)))
        J = np.hstack((J, np.eye(nt)))
        G = np.hstack((G, np.zeros((ng, nt))))
        lo, hi = np.concatenate((lo, -np.full(nt, 0.3))), np.concatenate((hi, np.full(nt, 0.3)))
    return QP(P, c, np.ascontiguousarray(J), b, lo, hi, n, G=np.ascontiguousarray(G), h=h)


def quadprog(qp):
    problem = Problem(qp.P, qp.c, qp.G, qp.h, qp.A, qp.b, qp.lb, qp.ub)
    return solve_problem(problem, solver="quadprog")


def highs_scale(qp):
    """max alpha in [0, 1] with A x = alpha b, G x <= h, lb <= x <= ub (HiGHS); None if none."""
    n = qp.n
    res = linprog(
        np.r_[np.zeros(n), -1.0],
        A_eq=np.hstack((qp.A, -qp.b[:, None])),
        b_eq=np.zeros(qp.A.shape[0]),
        A_ub=np.hstack((qp.G, np.zeros((qp.n_rows, 1)))),
        b_ub=qp.h,
        bounds=[*zip(qp.lb, qp.ub, strict=True), (0.0, 1.0)],
        method="highs",
    )
    return None if res.status != 0 else float(res.x[-1])


def arrays(qp):
    return tuple(
        np.ascontiguousarray(a, dtype=float)
        for a in (qp.P, qp.c, qp.A, qp.b, qp.G, qp.h, qp.lb, qp.ub)
    )


@pytest.mark.parametrize(("nt", "ng"), [(2, 1), (2, 4), (2, 20), (3, 5), (6, 8)])
def test_active_set_with_rows_equals_quadprog_and_is_certified(nt, ng):
    rng = np.random.default_rng(100 * nt + ng)
    solved = rows_active = 0
    for trial in range(60):
        n = nt + int(rng.integers(1, 5))
        qp = random_program(rng, nt, n, ng, slack=trial % 3 == 0)
        x, out = np.empty(qp.n), np.empty(4)
        code, _ = kernels.active_set_of(*arrays(qp), x, out)
        ref = quadprog(qp)
        assert ref.found
        assert code == kernels.OK
        np.testing.assert_allclose(x, ref.x, atol=1e-8)
        assert max(out[:3]) <= 1e-9 and out[3] <= 1e-12
        args = (qp.P, qp.c, qp.A, qp.b, qp.lb, qp.ub, x)
        assert reference.kkt_residual(*args, G=qp.G, h=qp.h) <= 1e-9
        found = multipliers(qp, x)
        assert found.report.is_optimal()
        assert np.all(found.nu >= 0.0)
        # complementarity: a row with a multiplier is active
        assert np.all(np.abs(found.nu * qp.row_slack(x)) <= 1e-9 * (1 + np.abs(found.nu).max()))
        rows_active += int(found.active_rows.size > 0)
        solved += 1
    assert solved == 60
    assert rows_active >= 10  # the rows shape the optimum, not only sit beside it


@pytest.mark.parametrize(("nt", "ng"), [(2, 3), (2, 20), (3, 4), (6, 6)])
def test_task_scale_and_feasible_point_with_rows_equal_highs(nt, ng):
    rng = np.random.default_rng(7 * nt + ng)
    infeasible = scaled = 0
    for trial in range(60):
        n = nt + int(rng.integers(1, 5))
        qp = random_program(rng, nt, n, ng, slack=trial % 4 == 0, reach=rng.uniform(0.5, 4.0))
        if trial % 5 == 0:  # rows that no point of the box keeps
            qp = QP(qp.P, qp.c, qp.A, qp.b, qp.lb, qp.ub, n, G=qp.G, h=qp.h - 10.0)
        alpha = task_scale(qp.A, qp.b, qp.lb, qp.ub, qp.G, qp.h)
        expected = highs_scale(qp)
        if expected is None:
            assert alpha is None
            infeasible += 1
            continue
        assert alpha == pytest.approx(expected, abs=1e-9)
        scaled += expected < 1.0
        x = feasible_point(qp.A, alpha * qp.b, qp.lb, qp.ub, qp.G, qp.h)
        assert x is not None
        assert np.all(x >= qp.lb - 1e-12) and np.all(x <= qp.ub + 1e-12)
        assert np.all(qp.G @ x <= qp.h + 1e-10)
        np.testing.assert_allclose(qp.A @ x, alpha * qp.b, atol=1e-9 * (1 + np.abs(qp.b).max()))
    assert infeasible >= 5 and scaled >= 5


def test_warm_start_with_rows_follows_a_moving_program():
    """One buffer set over a slowly moving program, as in a control loop: every answer equals
    quadprog's, and the previous working set (bounds and rows) is accepted on most steps."""
    rng = np.random.default_rng(3)
    base = random_program(rng, 2, 5, 6)
    w = kernels.qp_work(base.n, 2, 6)
    warm = 0
    for k in range(80):
        drift = 0.02 * k
        qp = QP(
            base.P, base.c + 0.1 * np.sin(drift), base.A, base.b * (1 + 0.1 * np.cos(drift)),
            base.lb, base.ub, base.n, G=base.G, h=base.h + 0.05 * np.sin(3 * drift),
        )  # fmt: skip
        x, out = np.empty(qp.n), np.empty(4)
        code, iterations = kernels.active_set(*arrays(qp), x, w, out, True)
        assert code == kernels.OK
        np.testing.assert_allclose(x, quadprog(qp).x, atol=1e-8)
        warm += iterations == 1
    assert warm >= 40


def test_degenerate_rows_are_certified():
    """A row repeated, a row equal to a bound and a row through the feasible point's vertex:
    dependent constraints the working set cannot hold together."""
    P, c = np.eye(3), np.array([-2.0, -2.0, -1.0])
    A, b = np.array([[1.0, 1.0, 1.0]]), np.array([1.0])
    lb, ub = -np.ones(3), np.full(3, 0.5)
    G = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]])
    h = np.array([0.4, 0.4, 0.5, 0.8])
    qp = QP(P, c, A, b, lb, ub, 3, G=G, h=h)
    x, out = np.empty(3), np.empty(4)
    code, _ = kernels.active_set_of(*arrays(qp), x, out)
    assert code == kernels.OK
    np.testing.assert_allclose(x, quadprog(qp).x, atol=1e-9)
    assert reference.kkt_residual(P, c, A, b, lb, ub, x, G=G, h=h) <= 1e-9


def test_inactive_rows_change_nothing():
    """Rows far from the box leave the answer of the program without them, bit for bit."""
    rng = np.random.default_rng(11)
    for _ in range(20):
        qp = random_program(rng, 2, 4, 3)
        far = QP(qp.P, qp.c, qp.A, qp.b, qp.lb, qp.ub, qp.n, G=qp.G, h=qp.h + 100.0)
        bare = QP(qp.P, qp.c, qp.A, qp.b, qp.lb, qp.ub, qp.n)
        x1, x2, out = np.empty(qp.n), np.empty(qp.n), np.empty(4)
        assert kernels.active_set_of(*arrays(far), x1, out)[0] == kernels.OK
        assert kernels.active_set_of(*arrays(bare), x2, out)[0] == kernels.OK
        np.testing.assert_array_equal(x1, x2)


def test_rows_through_the_solver_chain():
    """The Python chain carries the rows: the kernel answers, an off-the-shelf solver agrees, a
    point that crosses a row is refused by the certificate, and a method that knows only bounds
    declines instead of ignoring them."""
    rng = np.random.default_rng(5)
    qp = random_program(rng, 2, 4, 5)
    ours = solve_chain(qp, ["active-set"])
    theirs = solve_chain(qp, ["daqp"])
    np.testing.assert_allclose(ours.x, theirs.x, atol=1e-8)
    assert kkt_report(qp, ours.x).is_optimal()
    bare = solve_chain(QP(qp.P, qp.c, qp.A, qp.b, qp.lb, qp.ub, qp.n), ["active-set"]).x
    if np.any(qp.G @ bare > qp.h + 1e-9):  # the optimum without rows crosses one
        assert kkt_report(qp, bare).bound_excess > 1e-9
    from emdm.solvers import solve_active_set, solve_kkt

    traced = solve_active_set(qp, history=True)  # the lab's call: the same kernel, with its trace
    np.testing.assert_array_equal(traced.x, ours.x)
    assert len(traced.history) == traced.iterations and traced.history[-1]["step"] == 0.0
    declined = solve_kkt(qp)
    assert declined.x is None and declined.status.startswith("unsupported")


def test_qp_checks_the_shape_of_its_rows():
    with pytest.raises(ValueError, match="G: must be 2 x 3"):
        QP(np.eye(3), np.zeros(3), np.ones((1, 3)), np.ones(1), -np.ones(3), np.ones(3), 3,
           G=np.ones((2, 2)), h=np.ones(2))  # fmt: skip
    qp = QP(np.eye(3), np.zeros(3), np.ones((1, 3)), np.ones(1), -np.ones(3), np.ones(3), 3)
    assert qp.G.shape == (0, 3) and qp.n_rows == 0
    assert core.rows_hold(np.ones((1, 2)), np.array([1.0]), np.array([0.5, 0.5]))


def test_interior_point_with_rows_equals_quadprog():
    """Mehrotra's method with the rows' slacks ``s_g = h - G x`` and multipliers in the barrier:
    every answer it calls optimal is quadprog's; it may fail (measured: 5 of 200 such programs,
    by its iteration limit or a non-finite step), and then it says so and the chain moves on."""
    from emdm.solvers.interior_point import solve_interior_point

    rng = np.random.default_rng(8)
    solved = 0
    for trial in range(40):
        qp = random_program(rng, 2 + trial % 2, 5, 4, slack=trial % 3 == 0)
        with np.errstate(all="ignore"):
            result = solve_interior_point(qp)
        if result.status == "optimal":
            np.testing.assert_allclose(result.x, quadprog(qp).x, atol=1e-7)
            solved += 1
        else:
            assert result.status.startswith(("max_iter", "error"))
    assert solved >= 36


def test_every_solver_answers_rows_or_declines_them():
    """Each available solver either answers a program with rows (checked by the certificate, to
    its family's accuracy) or declines it with UNSUPPORTED_ROWS: none ignores the rows."""
    from emdm.solvers import Family, available_solvers, get_solver
    from emdm.solvers.base import UNSUPPORTED_ROWS

    rng = np.random.default_rng(21)
    qp = random_program(rng, 2, 4, 4)
    exact = quadprog(qp).x
    declined = []
    for name in available_solvers():
        spec = get_solver(name)
        result = spec.solve(qp)
        if result.status == UNSUPPORTED_ROWS:
            declined.append(name)
            continue
        assert result.x is not None, name
        if spec.family is Family.EXACT:
            assert kkt_report(qp, result.x).residual <= 1e-6, name
            np.testing.assert_allclose(result.x, exact, atol=1e-5, err_msg=name)
        elif spec.family is Family.GRADIENT:
            assert qp.violation(result.x) <= 1e-4, name
    assert set(declined) <= {"kkt"}  # equality-only by design
    admm = get_solver("admm").solve(qp)  # first order: close, not exact
    np.testing.assert_allclose(admm.x, exact, atol=1e-6)
