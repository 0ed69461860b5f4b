"""Solvers: exact optima on random programs, the KKT certificate, and the fallback chain."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import reference_solve

from emdm import QP, NoSolution, SolverNotFound, get_solver, kkt_report, solve_chain, task_scale
from emdm.solvers import SolverResult, SolverSpec, register, solve_active_set, solve_kkt
from emdm.solvers.base import _REGISTRY


def random_qp(rng, trial):
    n = int(rng.integers(2, 9))
    A = rng.normal(size=(2, n))
    if trial % 7 == 0:
        A[:, 1] = 0.3 * A[:, 0]
    P = np.diag(rng.uniform(0.05, 10, n))
    if trial % 4 == 0:
        M = rng.normal(size=(n, n))
        P = M @ M.T + 0.1 * np.eye(n)
    c = rng.normal(size=n) * rng.uniform(0.1, 10)
    lb, ub = -rng.uniform(0, 2, n), rng.uniform(0, 2, n)
    if trial % 5 == 0:
        lb[-2:], ub[-2:] = -np.inf, np.inf
    b = rng.normal(size=2) * rng.uniform(0.1, 4)
    alpha = task_scale(A, b, lb, ub)
    if alpha is None:
        return None
    return QP(P, c, A, alpha * b, lb, ub, n_joints=n)


def test_active_set_is_exact_on_random_programs(rng):
    solved = 0
    for trial in range(1500):
        qp = random_qp(rng, trial)
        if qp is None:
            continue
        result = solve_active_set(qp)
        assert result.status == "optimal", trial
        ref = reference_solve(qp.P, qp.c, qp.A, qp.b, qp.lb, qp.ub)
        np.testing.assert_allclose(result.x, ref, atol=1e-8 * max(1, np.abs(ref).max()))
        report = kkt_report(qp, result.x)
        assert report.is_optimal(1e-9), (trial, report)
        assert qp.bound_excess(result.x) <= 1e-12
        solved += 1
    assert solved > 1000


def test_kkt_solver_is_the_pseudoinverse(rng):
    for _ in range(20):
        J = rng.normal(size=(2, 3))
        v = rng.normal(size=2)
        inf = np.full(3, np.inf)
        qp = QP(np.eye(3), np.zeros(3), J, v, -inf, inf, 3)
        np.testing.assert_allclose(solve_kkt(qp).x, np.linalg.pinv(J) @ v, atol=1e-13)
        np.testing.assert_allclose(solve_active_set(qp).x, np.linalg.pinv(J) @ v, atol=1e-13)


def test_kkt_report_rejects_non_optimal_points(rng):
    qp = None
    while qp is None:
        qp = random_qp(rng, 1)
    x = solve_active_set(qp).x
    assert kkt_report(qp, x).is_optimal()
    # a feasible but non-optimal point: move along the null space of A, inside the box
    null = np.linalg.svd(qp.A)[2][-1]
    worse = x + 1e-4 * null
    if qp.bound_excess(worse) == 0:
        assert not kkt_report(qp, worse).is_optimal()
    assert not kkt_report(qp, x + 1e-3).is_optimal()
    assert not kkt_report(qp, np.full_like(x, np.nan)).is_optimal()


def test_infeasible_program_is_reported_not_answered():
    qp = QP(np.eye(2), np.zeros(2), np.eye(2), np.array([5.0, 0.0]), -np.ones(2), np.ones(2), 2)
    assert solve_active_set(qp).status == "infeasible"
    assert solve_active_set(qp).x is None
    with pytest.raises(NoSolution, match="no solver found the optimum"):
        solve_chain(qp, ["active-set", "daqp", "quadprog"])


def test_unknown_solver_lists_installed_ones():
    with pytest.raises(SolverNotFound, match=r"unknown solver 'nope' \(installed: active-set, kkt"):
        get_solver("nope")


# ------------------------------------------------------------------------------ fault injection
def _faulty(name, behaviour):
    def solve(qp):
        if behaviour == "raise":
            raise RuntimeError("boom")
        good = solve_active_set(qp)
        if behaviour == "nan":
            return SolverResult(np.full(qp.n, np.nan), "optimal", 1, 0.0)
        if behaviour == "wrong":
            return SolverResult(good.x + 0.01, "optimal", 1, 0.0)
        if behaviour == "budget":
            return SolverResult(good.x + 0.01, "max_iter", 100, 0.0)
        return SolverResult(None, "infeasible", 1, 0.0)

    register(SolverSpec(name, "exact", solve, "fault injection"))
    return name


@pytest.mark.parametrize("behaviour", ["raise", "nan", "wrong", "budget", "none"])
def test_faulty_solver_triggers_the_fallback(behaviour, rng):
    name = _faulty(f"faulty-{behaviour}", behaviour)
    try:
        qp = None
        while qp is None:
            qp = random_qp(rng, 2)
        result = solve_chain(qp, [name, "daqp"])
        assert result.fallback and result.solver == "daqp"
        assert result.attempts[0][0] == name and result.attempts[0][1] != "optimal"
        assert result.kkt.is_optimal()
    finally:
        del _REGISTRY[name]


def test_faulty_solver_in_a_run_is_recorded():
    import emdm

    name = _faulty("faulty-run", "wrong")
    try:
        run = emdm.simulate(
            emdm.load_scenario("task2"), "C-EMDM", solver=name, fallback=["quadprog"]
        )
        assert run.reached
        assert run.fallback.all()
        assert set(run.solver) == {"quadprog"}
        assert all(a.startswith("faulty-run: not certified") for a in run.attempts)
    finally:
        del _REGISTRY[name]


def test_compiled_certificate_matches_scipy_nnls(rng):
    import reference

    for trial in range(300):
        qp = random_qp(rng, trial)
        if qp is None:
            continue
        exact = solve_active_set(qp).x
        for x in (exact, exact + rng.normal(size=exact.size) * 10.0 ** rng.uniform(-12, -1)):
            mine = kkt_report(qp, x).residual
            ref = reference.kkt_residual(qp.P, qp.c, qp.A, qp.b, qp.lb, qp.ub, x)
            assert (mine <= 1e-9) == (ref <= 1e-9) or abs(np.log10(mine / ref)) < 1, trial
            assert mine == pytest.approx(ref, rel=1e-3, abs=1e-12), trial


def test_huge_multipliers_do_not_certify_a_wrong_point():
    """Dependent task rows with b = 0: multipliers of 1e17 once made any point look stationary."""
    A = np.array([[-0.22729749, -0.3 * 0.22729749], [-0.26173735, -0.3 * 0.26173735]])
    qp = QP(np.diag([7.27, 1.72]), np.array([0.6, -3.5]), A, np.zeros(2),
            np.array([-1.39, -1.71]), np.array([1.93, 0.61]), n_joints=2)  # fmt: skip
    wrong = np.array([0.18382841757620333, -0.612761391920678])
    assert np.abs(A @ wrong).max() < 1e-12
    assert not kkt_report(qp, wrong).is_optimal()
    result = solve_active_set(qp)
    assert kkt_report(qp, result.x).is_optimal()
    np.testing.assert_allclose(
        result.x, reference_solve(qp.P, qp.c, qp.A, qp.b, qp.lb, qp.ub), atol=1e-8
    )


def test_a_vertex_where_task_rows_and_two_bounds_meet_is_certified():
    """Three joints, two task rows and two joints at their upper bounds: the scaled task leaves
    one point, and its multipliers need a bound column the task rows nearly span. The NNLS once
    kept a 1e-289 coefficient on a task column, found the entering column dependent and stopped
    at a stationarity residual of 3e-2 (a random study goal of task1, C-EMDM, step 5)."""
    A = np.array(
        [
            [-0.8682595613619262, -0.8830029922987822, -0.2999665071436429],
            [0.3366363200856075, 0.13718048225625204, -0.00448269919164926],
        ]
    )
    qp = QP(np.eye(3) * 0.1, np.array([0.0, -0.04720420215796386, -0.582044603968533]), A,
            np.array([-0.5285428887973733, -0.06471706987635965]), -np.ones(3),
            np.array([1.0, 0.725520852990033, 1.0]), n_joints=3)  # fmt: skip
    import reference

    for x2 in (0.725520852990033, 0.7255208529900328):  # at the bound, and one ulp inside
        x = np.array([-0.4745823954593569, x2, 1.0])
        assert reference.kkt_residual(qp.P, qp.c, qp.A, qp.b, qp.lb, qp.ub, x) <= 1e-12
        assert kkt_report(qp, x).is_optimal(), x2
    result = solve_active_set(qp)
    assert kkt_report(qp, result.x).is_optimal()
    np.testing.assert_allclose(result.x, x, atol=1e-12)


def test_compiled_active_set_follows_the_numpy_method(rng):
    """The kernel and its numpy statement (tests/reference_active_set.py) take the same path:
    the same number of iterations, the same objective, step length and working-set size at every
    iteration, and the same optimum; an iteration limit stops both at the same iterate."""
    from reference_active_set import numpy_active_set

    compared = limited = 0
    for trial in range(400):
        qp = random_qp(rng, trial)
        if qp is None:
            continue
        x_ref, status, trace = numpy_active_set(qp)
        ours = solve_active_set(qp, history=True)
        assert ours.status == status == "optimal", trial
        np.testing.assert_allclose(ours.x, x_ref, atol=1e-9 * max(1.0, np.abs(x_ref).max()))
        got = np.array([[h["objective"], h["step"], h["working_set"]] for h in ours.history])
        if got.shape[0] == len(trace):  # a unique feasible point is settled by both at once
            want = np.array(trace)
            np.testing.assert_allclose(got[:, 0], want[:, 0], rtol=1e-9, atol=1e-9)
            np.testing.assert_allclose(got[:, 1], want[:, 1], rtol=1e-6, atol=1e-9)
            if len(trace) > 1:  # a unique point: the oracle holds what the rank allows
                np.testing.assert_array_equal(got[:, 2], want[:, 2])
            compared += 1
        if len(trace) >= 3:
            cut = solve_active_set(qp, max_iter=2)
            x_cut, status_cut, _ = numpy_active_set(qp, max_iter=2)
            assert cut.status == status_cut == "max_iter" and cut.iterations == 2
            np.testing.assert_allclose(cut.x, x_cut, atol=1e-9 * max(1.0, np.abs(x_cut).max()))
            limited += 1
    assert compared > 250 and limited > 20


def test_active_set_reduces_dependent_task_rows():
    """A singular Jacobian (parallel rows, a consistent target): the kernel meets dependent rows,
    the wrapper reduces them and the answer is the bounded minimum-norm solution."""
    A = np.array([[1.0, 2.0, 0.5], [2.0, 4.0, 1.0]])
    b = np.array([1.0, 2.0])
    lb, ub = -0.3 * np.ones(3), np.ones(3)
    qp = QP(np.eye(3), np.zeros(3), A, b, lb, ub, 3)
    result = solve_active_set(qp)
    assert result.status == "optimal"
    ref = reference_solve(qp.P, qp.c, A[:1], b[:1], lb, ub)
    np.testing.assert_allclose(result.x, ref, atol=1e-9)


def test_range_space_step_solves_the_kkt_system(rng):
    """The active set's step system with a diagonal ``P_FF`` (range-space form, Householder
    factor) solves the whole KKT matrix with a backward error at rounding level and agrees with
    numpy's dense solve; other ``P`` take the dense elimination."""
    from emdm.solvers.kernels import _kkt_matrix, _kkt_solve

    checked = {True: 0, False: 0}
    for trial in range(400):
        n, nt, ng = int(rng.integers(3, 10)), int(rng.integers(1, 4)), int(rng.integers(0, 5))
        diagonal = trial % 3 != 0
        if diagonal:
            P = np.diag(10.0 ** rng.uniform(-3, 3, n))
        else:
            M = rng.normal(size=(n, n))
            P = M @ M.T + 0.1 * np.eye(n)
        A, G = rng.normal(size=(nt, n)), rng.normal(size=(ng, n))
        gwork = (rng.uniform(size=ng) < 0.5).astype(np.int8)
        f = int(rng.integers(1, n + 1))
        idx = np.sort(rng.permutation(n)[:f]).astype(np.int64)
        size = f + nt + int(gwork.sum())
        N = n + nt + ng
        rhs = rng.normal(size=N)
        K = np.zeros((N, N))
        out = rhs.copy()
        if size - f > f:
            continue  # more held rows than free variables: the method never asks
        got = _kkt_solve(P, A, G, gwork, idx, f, K, out)
        dense = np.zeros((N, N))
        _kkt_matrix(P, A, G, gwork, idx, f, dense)
        Kd, x = dense[:size, :size], out[:size]
        assert got == size
        # backward error of the answer (what the dense elimination guarantees too) and the
        # answer itself against numpy's
        residual = np.abs(Kd @ x - rhs[:size]).max()
        assert residual <= 1e-13 * (np.abs(Kd).max() * np.abs(x).max() + np.abs(rhs).max())
        want = np.linalg.solve(Kd, rhs[:size])
        assert np.abs(x - want).max() <= 1e-8 * np.abs(want).max(), trial
        checked[diagonal] += 1
    assert checked[True] > 100 and checked[False] > 50


def test_backends_found_installed_exactly_when_qpsolvers_lists_them():
    """emdm finds a backend's module without importing qpsolvers; the answer must be the one
    qpsolvers itself gives after importing every backend."""
    import qpsolvers

    from emdm.solvers.qpsolvers_backend import BACKENDS, MODULES, _installed

    assert set(MODULES) == set(BACKENDS)
    for name in BACKENDS:
        assert _installed(name) == (name in qpsolvers.available_solvers), name
