"""Spatial arms in the loop: the k-row kernels (simplex feasibility, active set, certificate)
against independent references, the pose error, the presets, the baselines and the scenario
schema of spatial arms."""

from __future__ import annotations

import numpy as np
import pytest
import reference
from qpsolvers import Problem, solve_problem
from scipy.optimize import linprog
from scipy.spatial.transform import Rotation
from test_sim import assert_same_run

import emdm
from emdm.core import kernels as core_kernels
from emdm.core import simplex as kernels
from emdm.core.controllers import get_controller, program_at, state_at
from emdm.errors import ScenarioError
from emdm.solvers import solve_active_set
from emdm.solvers.kernels import OK, active_set_of

SPATIAL = ["panda", "ur5"]
ALL = ["UC-IVKC", "C-IVKC", "UC-EMDM", "C-EMDM", "RRMC", "PARK", "MMC"]


def random_program(rng, nt, n, slack=False):
    """A strictly convex program with nt task rows, n joints in a box, optional slack."""
    J = rng.normal(size=(nt, n))
    lo, hi = -rng.uniform(0.2, 1.5, n), rng.uniform(0.2, 1.5, n)
    x_in = rng.uniform(lo, hi)
    b = J @ x_in * rng.uniform(0.5, 3.0)  # often beyond the box: infeasible or scaled
    P = np.diag(rng.uniform(0.05, 2.0, n))
    c = rng.normal(size=n)
    if slack:
        P = np.block([[P, np.zeros((n, nt))], [np.zeros((nt, n)), 3.0 * np.eye(nt)]])
        c = np.concatenate((c, np.zeros(nt)))
        J = np.hstack((J, np.eye(nt)))
        lo, hi = np.concatenate((lo, -np.full(nt, 0.3))), np.concatenate((hi, np.full(nt, 0.3)))
    return P, c, np.ascontiguousarray(J), b, lo, hi


def linprog_scale(A, b, lb, ub):
    n = A.shape[1]
    res = linprog(
        np.r_[np.zeros(n), -1.0],
        A_eq=np.hstack((A, -b[:, None])),
        b_eq=np.zeros(A.shape[0]),
        bounds=[*zip(lb, ub, strict=True), (0.0, 1.0)],
        method="highs",
    )
    return None if res.status != 0 else float(res.x[n])


def NO_ROWS(A):
    """No inequality rows ``G x <= h`` (G is 0 x n)."""
    return np.zeros((0, A.shape[1])), np.zeros(0)


@pytest.mark.parametrize("nt", [1, 3, 4, 6])
def test_simplex_task_scale_equals_highs(nt, rng):
    for _ in range(60):
        n = nt + int(rng.integers(0, 4))
        _, _, A, b, lb, ub = random_program(rng, nt, n, slack=bool(rng.integers(0, 2)))
        if rng.uniform() < 0.2:  # a box that excludes 0: sometimes no scale works
            lb, ub = lb + 1.6, ub + 1.6
        alpha = kernels.task_scale_of(A, b, *NO_ROWS(A), lb, ub)
        expected = linprog_scale(A, b, lb, ub)
        if expected is None:
            assert alpha == -1.0
        else:
            assert alpha == pytest.approx(expected, abs=1e-9)
        x = np.empty(A.shape[1])
        code, unique = kernels.feasible_point_of(A, b, *NO_ROWS(A), lb, ub, x)
        assert not unique
        if expected is not None and expected >= 1.0 - 1e-12:
            assert code == kernels.OK
            assert np.all(x >= lb) and np.all(x <= ub)
            np.testing.assert_allclose(A @ x, b, atol=1e-10 * (1 + np.abs(b).max()))
        elif expected is not None and expected < 1.0 - 1e-7:
            assert code == kernels.INFEASIBLE


@pytest.mark.parametrize("nt", [3, 6])
def test_active_set_with_k_rows_equals_quadprog_and_is_certified(nt, rng):
    solved = 0
    for _ in range(80):
        n = nt + int(rng.integers(0, 4))
        P, c, A, b, lb, ub = random_program(rng, nt, n, slack=bool(rng.integers(0, 2)))
        alpha = kernels.task_scale_of(A, b, *NO_ROWS(A), lb, ub)
        if alpha < 0:
            continue
        b = alpha * b
        x, out = np.empty(c.size), np.empty(4)
        code, _ = active_set_of(P, c, A, b, *NO_ROWS(A), lb, ub, x, out)
        ref = solve_problem(Problem(P, c, A=A, b=b, lb=lb, ub=ub), solver="quadprog")
        if not ref.found:
            continue
        assert code == OK
        np.testing.assert_allclose(x, ref.x, atol=1e-8)
        assert reference.kkt_residual(P, c, A, b, lb, ub, x) <= 1e-9
        solved += 1
    assert solved >= 40


def test_rotation_vector_and_matrix_agree_with_scipy(rng):
    vectors = [rng.normal(size=3) for _ in range(50)]
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    vectors += [axis * angle for angle in (0.0, 1e-9, np.pi - 1e-7, np.pi - 1e-3, np.pi, 2.5)]
    for rv in vectors:
        R = np.empty((3, 3))
        core_kernels.rotation_matrix(*rv, R)
        np.testing.assert_allclose(R, Rotation.from_rotvec(rv).as_matrix(), atol=1e-14)
        out = np.empty(3)
        core_kernels.rotation_vector(R, out, 0)
        expected = Rotation.from_matrix(R).as_rotvec()
        if np.linalg.norm(expected) > np.pi - 1e-6:  # theta = pi: u and -u are the same rotation
            assert np.allclose(out, expected, atol=1e-6) or np.allclose(out, -expected, atol=1e-6)
        else:
            np.testing.assert_allclose(out, expected, atol=1e-10)


@pytest.mark.parametrize("task", SPATIAL)
def test_pose_error_is_zero_at_the_goal_and_its_rate_is_minus_the_jacobian(task):
    sc = emdm.load_scenario(task)
    arm = sc.serial_arm
    T = arm.forward(sc.motion.q0)
    goal = np.r_[T[:3, 3], Rotation.from_matrix(T[:3, :3]).as_rotvec()]
    at_goal = state_at(sc.with_overrides({"motion.goal": goal.tolist()}), sc.motion.q0)
    np.testing.assert_allclose(at_goal.e, 0.0, atol=1e-12)
    np.testing.assert_allclose(at_goal.kin.J, arm.jacobian(sc.motion.q0), atol=1e-15)
    # d e / dt = -J qd at the goal (the error's rate is the twist, sign reversed)
    qd = np.linspace(-0.5, 0.5, sc.n)
    h = 1e-6
    ahead = state_at(sc.with_overrides({"motion.goal": goal.tolist()}), sc.motion.q0 + h * qd)
    behind = state_at(sc.with_overrides({"motion.goal": goal.tolist()}), sc.motion.q0 - h * qd)
    np.testing.assert_allclose((ahead.e - behind.e) / (2 * h), -at_goal.kin.J @ qd, atol=1e-7)
    m, Jm = arm.manipulability_and_jacobian(sc.motion.q0)
    assert at_goal.kin.m == pytest.approx(m, rel=1e-14)
    np.testing.assert_allclose(at_goal.kin.Jm, Jm, atol=1e-15)


@pytest.mark.parametrize("task", SPATIAL)
def test_presets_match_the_published_arms(task):
    """The preset's DH rows and limits are robotics-toolbox-python's model of the same arm."""
    rtb = pytest.importorskip("roboticstoolbox")
    model = rtb.models.DH.Panda() if task == "panda" else rtb.models.DH.UR5()
    sc = emdm.load_scenario(task)
    table = np.array([[L.a, L.alpha, L.d, L.offset] for L in model.links])
    np.testing.assert_allclose(sc.arm.dh, table, atol=1e-12)
    q = np.linspace(-0.4, 0.6, sc.n) + sc.motion.q0
    flange = model.fkine(q).A @ np.linalg.inv(model.tool.A)
    np.testing.assert_allclose(sc.serial_arm.forward(q), flange, atol=1e-12)
    if task == "panda":
        np.testing.assert_allclose(np.c_[sc.arm.q_min, sc.arm.q_max].T, model.qlim, atol=1e-12)


@pytest.mark.parametrize("task", SPATIAL)
@pytest.mark.parametrize("controller", ALL)
def test_spatial_runs_reach_the_goal_certified_within_bounds(task, controller):
    sc = emdm.load_scenario(task)
    run = emdm.simulate(sc, controller)
    assert run.reached and run.p.shape[1] == 6 and run.delta.shape[1] == 6
    assert set(run.solver) == {"active-set"}
    assert np.max(run.kkt) <= 1e-9
    if get_controller(controller).constrained:
        assert np.all(run.qd >= run.lo - 1e-12) and np.all(run.qd <= run.hi + 1e-12)
        assert np.all(run.q >= sc.arm.q_min) and np.all(run.q <= sc.arm.q_max)


@pytest.mark.parametrize("task", SPATIAL)
@pytest.mark.parametrize("controller", ["UC-EMDM", "C-EMDM", "MMC"])
def test_spatial_compiled_loop_equals_the_numpy_solver_path(task, controller, numpy_solver):
    sc = emdm.load_scenario(task, {"motion.max_time": 3.0})
    fast = emdm.simulate(sc, controller)
    slow = emdm.simulate(sc, controller, solver=numpy_solver, fallback=())
    assert set(slow.solver) == {numpy_solver}
    assert_same_run(fast, slow, tol=1e-10)


def test_a_position_task_uses_three_rows_and_the_translational_manipulability():
    sc = emdm.load_scenario(
        "panda",
        {"motion.task": "position", "motion.goal": [0.4, 0.2, 0.5], "motion.axes": "trans"},
    )
    assert sc.nt == 3 and sc.redundant
    run = emdm.simulate(sc, "C-EMDM")
    assert run.reached and run.p.shape[1] == 3
    m = [sc.serial_arm.manipulability(q, "trans") for q in run.q[::20]]
    np.testing.assert_allclose(run.m[::20], m, rtol=1e-12)


def test_baselines_are_the_textbook_laws():
    """RRMC = J^+ v; Park = J^+ v + (w_M / w_E)(I - J^+ J) Jm; MMC = the slack program."""
    sc = emdm.load_scenario("panda")
    q = sc.motion.q0
    st = state_at(sc, q)
    J, v, Jm = st.kin.J, st.v, st.kin.Jm
    pinv = np.linalg.pinv(J)
    rrmc = solve_active_set(program_at(get_controller("RRMC"), sc, q).qp).x
    np.testing.assert_allclose(rrmc, pinv @ v, atol=1e-12)
    k = sc.weights.manipulability / sc.weights.effort
    park = solve_active_set(program_at(get_controller("PARK"), sc, q).qp).x
    np.testing.assert_allclose(park, pinv @ v + k * (np.eye(sc.n) - pinv @ J) @ Jm, atol=1e-10)
    mmc = program_at(get_controller("MMC"), sc, q).qp
    assert mmc.n_slack == 6 and np.all(np.isfinite(mmc.lb[:7]))


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"arm.lengths": [0.5, 0.5]}, "give one of them"),
        ({"motion.task": "planar"}, "motion.task"),
        ({"motion.goal": [0.1, 0.2, 0.3]}, "must have 6 values"),
        ({"arm.convention": "craig"}, '"standard" or "modified"'),
        ({"motion.axes": "some"}, "motion.axes"),
        ({"arm.dh": [[0.0, 0.0, 0.3]] * 7}, "arm.dh[0]"),
        ({"arm.tool": [0.0, 0.0]}, "arm.tool"),
    ],
)
def test_spatial_scenario_errors_name_the_key(overrides, message):
    with pytest.raises(ScenarioError, match=message.replace("[", r"\[").replace("]", r"\]")):
        emdm.load_scenario("panda", overrides)


def test_spatial_only_keys_are_refused_on_a_planar_arm():
    with pytest.raises(ScenarioError, match=r"motion\.task.*spatial arms only"):
        emdm.load_scenario("task1", {"motion.task": "pose"})


def test_spatial_scenario_round_trips_through_toml(tmp_path):
    sc = emdm.load_scenario("ur5", {"motion.task": "position", "motion.goal": [-0.3, -0.4, 0.5]})
    path = tmp_path / "arm.toml"
    path.write_text(sc.to_toml())
    again = emdm.load_scenario(path)
    assert again.to_dict() == {**sc.to_dict(), "name": again.name}
    np.testing.assert_array_equal(again.arm.dh, sc.arm.dh)
    assert "dh" not in emdm.load_scenario("task1").to_dict()["arm"]


def test_an_unreachable_spatial_goal_warns():
    with pytest.warns(emdm.ScenarioWarning, match="beyond the arm's reach"):
        emdm.load_scenario("ur5", {"motion.goal": [3.0, 0.0, 0.0, 0.0, 0.0, 0.0]})


def test_mmc_benchmark_counts_failures_from_the_runs_themselves():
    from emdm.studies.mmc import draw_tasks, mmc_table, run_mmc_benchmark

    data = run_mmc_benchmark(arms=["ur5"], controllers=["RRMC", "MMC"], trials=12, seed=3)
    q0s, goals = draw_tasks("ur5", 12, 3)
    sc = emdm.load_scenario("ur5")
    for name in ("RRMC", "MMC"):
        failed, means = 0, []
        for q0, goal in zip(q0s, goals, strict=True):
            one = sc.with_overrides({"motion.q0": q0.tolist(), "motion.goal": goal.tolist()})
            run = emdm.simulate(one, name)
            outside = np.any(run.q < sc.arm.q_min) or np.any(run.q > sc.arm.q_max)
            failed += (not run.reached) or outside
            means.append(run.m.mean())
        row = data["results"]["ur5"][name]
        assert row["failure_rate"] == pytest.approx(100.0 * failed / 12)
        assert row["mean_manipulability"] == pytest.approx(np.mean(means), rel=1e-12)
        assert row["published"] is not None
    assert data["results"]["ur5"]["MMC"]["left_joint_limits"] == 0
    assert "(0.0563)" in mmc_table(data)


def test_mmc_command_writes_its_table(tmp_path, capsys):
    from emdm.cli.main import main

    assert main(["mmc", "--arm", "ur5", "--trials", "3", "--out", str(tmp_path / "m")]) == 0
    assert "| ur5 | MMC |" in capsys.readouterr().out
    assert (tmp_path / "m" / "mmc.json").is_file() and (tmp_path / "m" / "mmc.md").is_file()
    assert main(["mmc", "--trials", "0"]) == 2


def test_spatial_animation_projects_the_ellipsoid_in_three_views():
    from emdm.outputs.animate import Animator

    sc = emdm.load_scenario("ur5", {"motion.max_time": 1.0})
    run = emdm.simulate(sc, "MMC")
    animator = Animator([run], speedup=4.0)
    try:
        frame = animator.draw(0)
        assert frame.shape[1] > 2 * frame.shape[0]  # three views side by side
        top = animator.ellipse_at(2)
        k = animator.indices[2]
        Jv = sc.serial_arm.jacobian(run.q[k])[:3]
        shape = Jv[:2] @ Jv[:2].T  # the top view drops z
        d = top - run.p[k, :2]
        radii = np.einsum("ij,jk,ik->i", d, np.linalg.inv(shape), d)
        np.testing.assert_allclose(radii, animator.scale**2, rtol=1e-9)
    finally:
        animator.close()


def test_spatial_figures_are_written(tmp_path):
    from emdm.cli.main import main
    from emdm.outputs.style import formats

    out = tmp_path / "figs"
    short = ["--set", "motion.max_time=1.5"]
    with formats((".png",)):
        plot = ["plot", "ur5", "--controller", "C-EMDM,MMC,RRMC", *short]
        assert main([*plot, "--out", str(out)]) == 0
        pareto = ["pareto", "ur5", "--controller", "C-EMDM", "--grid", "2", *short]
        assert main([*pareto, "--out", str(tmp_path / "p")]) == 0
    assert (out / "baselines" / "path.png").is_file() and (out / "C" / "error.png").is_file()
    assert (tmp_path / "p" / "pareto_front.png").is_file()


def test_a_written_spatial_scenario_takes_another_task_when_edited(tmp_path):
    """`emdm scenario panda` writes uniform per-row values once, so a user who switches the file
    to a position task gives only the new goal."""
    text = emdm.load_scenario("panda").to_toml()
    text = text.replace('task = "pose"', 'task = "position"')
    lines = [
        "goal = [0.4, 0.2, 0.5]" if line.startswith("goal = ") else line
        for line in text.splitlines()
    ]
    path = tmp_path / "pos.toml"
    path.write_text("\n".join(lines) + "\n")
    sc = emdm.load_scenario(path)
    assert sc.nt == 3 and sc.motion.kp.tolist() == [1.0, 1.0, 1.0]


def test_a_spatial_run_folder_reads_back_exactly_and_plots(tmp_path):
    from emdm.cli.main import main
    from emdm.outputs.records import read_run
    from emdm.outputs.style import formats

    folder = tmp_path / "run"
    short = ["--set", "motion.max_time=1.0"]
    assert main(["run", "ur5", "--controller", "MMC,RRMC", *short, "--out", str(folder)]) == 0
    again = read_run(folder, "MMC")
    fresh = emdm.simulate(emdm.load_scenario("ur5", {"motion.max_time": 1.0}), "MMC")
    assert_same_run(again, fresh, tol=0.0)
    with formats((".png",)):  # no --controller: the runs the folder holds
        assert main(["plot", str(folder), "--out", str(tmp_path / "figs")]) == 0
    assert (tmp_path / "figs" / "baselines" / "path.png").is_file()
