"""The terms of the per-step program: each writer against its formula, controllers as lists of
terms, and the worked example of docs/architecture.md (the joint-centring objective)."""

from __future__ import annotations

import numpy as np
import pytest
import reference

import emdm
from emdm.core.controllers import BASELINES, CONTROLLERS, get_controller, step_program
from emdm.core.terms import TermKind
from emdm.core.terms.centring import gradient


def _range_index(sc, q):
    """Liegeois' joint-range index H(q) = 1/2 sum ((q - m) / r)^2, written out (the oracle)."""
    mid = 0.5 * (sc.arm.q_min + sc.arm.q_max)
    r = sc.arm.q_max - sc.arm.q_min
    return 0.5 * float(np.sum(((q - mid) / r) ** 2))


def test_centring_gradient_matches_central_differences(rng):
    sc = emdm.load_scenario("task1")
    for q in rng.uniform(-1.8, 1.8, (10, 3)):
        out = np.empty(3)
        gradient(q, sc.arm.q_min, sc.arm.q_max, out)
        h = 1e-6
        fd = [
            (_range_index(sc, q + h * e) - _range_index(sc, q - h * e)) / (2 * h) for e in np.eye(3)
        ]
        np.testing.assert_allclose(out, fd, atol=1e-9)


def test_centring_enters_the_closed_form_of_uc_emdm(rng):
    """With w_C > 0 the redundant UC-EMDM optimum is ``J^+ v + N (w_M Jm - w_C grad H) / w_E``."""
    sc = emdm.load_scenario("task1", {"weights.centring": 0.7})
    for q in rng.uniform(-1.5, 1.5, (20, 3)):
        kin = sc.planar_arm.kinematics(q)
        e = sc.motion.goal - kin.p
        v = sc.motion.kp * e
        qp = step_program(get_controller("UC-EMDM"), sc, q, kin, v, float(np.linalg.norm(e)))
        x = emdm.solve_chain(qp, ["active-set"]).x
        grad = np.empty(3)
        gradient(q, sc.arm.q_min, sc.arm.q_max, grad)
        Jp = np.linalg.pinv(kin.J)
        N = np.eye(3) - Jp @ kin.J
        w = sc.weights
        expected = Jp @ v + N @ (w.manipulability * kin.Jm - 0.7 * grad) / w.effort
        np.testing.assert_allclose(x, expected, atol=1e-12)


def test_centring_moves_the_joints_toward_the_middle_of_their_range():
    """In closed loop the centring term ends the run at the configuration of the goal's
    self-motion that is nearest the middle of the joint ranges (the minimum of H over the
    configurations that reach the goal, found by SLSQP), while w_C = 0 ends elsewhere."""
    from scipy.optimize import minimize

    base = emdm.load_scenario("task1", {"weights.manipulability": 0.0})
    centred = base.with_overrides({"weights.centring": 2.0})
    arm, goal = base.planar_arm, base.motion.goal
    best = minimize(
        lambda q: _range_index(base, q),
        np.array([1.0, 1.5, 0.6]),
        constraints=[{"type": "eq", "fun": lambda q: arm.forward(q) - goal}],
        method="SLSQP",
        options={"ftol": 1e-14},
    )
    assert best.success
    r0, r1 = emdm.simulate(base, "C-EMDM"), emdm.simulate(centred, "C-EMDM")
    assert r0.reached and r1.reached
    assert _range_index(centred, r1.q[-1]) == pytest.approx(best.fun, abs=2e-4)  # stops 1 mm short
    assert _range_index(base, r0.q[-1]) > best.fun + 1e-3


def test_a_zero_centring_weight_leaves_the_program_unchanged():
    sc = emdm.load_scenario("task2")
    with_zero = sc.with_overrides({"weights.centring": 0.0})
    for name in CONTROLLERS:
        a = get_controller(name).program_data(sc)
        b = get_controller(name).program_data(with_zero)
        np.testing.assert_array_equal(a.codes, b.codes)


@pytest.mark.parametrize("name", [*CONTROLLERS, *BASELINES])
def test_controllers_are_lists_of_terms(name):
    """The brief's four and the baselines are data: what sets them apart is which terms they
    hold, and the C- controllers are exactly those holding the joint bounds."""
    ctrl = get_controller(name)
    kinds = [t.kind for t in ctrl.terms]
    assert kinds[0] is TermKind.TASK and TermKind.EFFORT in kinds
    assert ctrl.constrained == (name.startswith("C-") or name in ("MMC", "NEO"))
    assert ctrl.constrained == ctrl.has(TermKind.DAMPER)
    assert ctrl.has(TermKind.MANIPULABILITY) == (
        name.endswith("EMDM") or name in ("PARK", "MMC", "NEO")
    )
    assert ctrl.has(TermKind.OBSTACLE) == (name.startswith("C-") or name == "NEO")


def test_slack_follows_the_arm():
    """The brief's rule: EMDM carries the task slack on a non-redundant arm only; MMC always."""
    redundant, two_link = emdm.load_scenario("task1"), emdm.load_scenario("task2")
    assert not get_controller("C-EMDM").program_data(redundant).slack
    assert get_controller("C-EMDM").program_data(two_link).slack
    assert get_controller("MMC").program_data(redundant).slack
    assert not get_controller("PARK").program_data(two_link).slack


def test_bad_centring_weight_is_one_clear_error():
    with pytest.raises(emdm.ScenarioError, match=r"weights\.centring"):
        emdm.load_scenario("task1", {"weights.centring": -1.0})


def _with_plane(name, offset, **more):
    sc = emdm.load_scenario(name)
    return sc.with_overrides({"planes.normals": [[0.0, 1.0]], "planes.offsets": [offset], **more})


def test_plane_rows_through_the_loop_equal_an_independent_program():
    """A plane within reach adds one row ``-n^T J qd <= gain (d - stop) / (influence - stop)``
    to the constrained programs: every recorded command is the optimum of that program written
    out here and solved by quadprog, and the UC- controllers ignore the plane."""
    from qpsolvers import Problem, solve_problem

    sc = _with_plane("task1", 0.45)
    pl = sc.planes
    compared = 0
    for name in ("C-EMDM", "C-IVKC", "MMC"):
        run = emdm.simulate(sc, name)
        assert run.reached and run.rows.max() == 1
        for k in np.flatnonzero(run.rows)[::5]:
            kin = sc.planar_arm.kinematics(run.q[k])
            e = sc.motion.goal - kin.p
            qp = step_program(
                get_controller(name), sc, run.q[k], kin, sc.motion.kp * e, float(np.linalg.norm(e))
            )
            d = float(pl.normals[0] @ kin.p - pl.offsets[0])
            row = np.zeros(qp.n)
            row[: sc.n] = -pl.normals[0] @ kin.J
            np.testing.assert_allclose(qp.G, row[None, :], atol=1e-15)
            assert qp.h[0] == pytest.approx(pl.gain * (d - pl.stop) / (pl.influence - pl.stop))
            b = qp.b * run.alpha[k]
            ref = solve_problem(
                Problem(qp.P, qp.c, qp.G, qp.h, qp.A, b, qp.lb, qp.ub), solver="quadprog"
            )
            x = np.concatenate((run.qd[k], run.delta[k])) if qp.n_slack else run.qd[k]
            args = (qp.P, qp.c, qp.A, b, qp.lb, qp.ub, x)
            assert reference.kkt_residual(*args, G=qp.G, h=qp.h) <= 1e-9
            if ref.found:  # quadprog declines some scaled steps, whose feasible set is a point
                np.testing.assert_allclose(run.qd[k], ref.x[: sc.n], atol=1e-8)
                compared += 1
    assert compared > 20
    assert emdm.simulate(sc, "UC-EMDM").rows.max() == 0


def test_a_plane_before_the_goal_stops_the_slack_controller_at_the_stop_distance():
    """The goal lies 0.01 m from the plane, inside its stop distance (0.02 m): MMC, whose task has
    slack, ends on the plane's damper with the row active, within the Euler step's second-order
    overshoot of the stop distance; without the plane it reaches the goal."""
    sc = _with_plane("task1", 0.49)
    run = emdm.simulate(sc, "MMC")
    d = np.array([sc.plane_distances(q)[0] for q in run.q])
    assert not run.reached
    assert run.rows_active.sum() > 100
    assert d.min() > sc.planes.stop - 1e-3
    assert d[-1] == pytest.approx(sc.planes.stop, abs=1e-4)
    assert np.all(run.kkt <= 1e-9)


def test_bad_planes_are_one_clear_error():
    sc = emdm.load_scenario("task1")
    cases = [
        ({"planes.normals": [[0.0, 0.0]], "planes.offsets": [0.0]}, r"planes\.normals\[0\]"),
        ({"planes.normals": [[0.0, 1.0]], "planes.offsets": [0.0, 1.0]}, r"planes\.offsets"),
        ({"planes.normals": [[0.0, 1.0, 0.0]], "planes.offsets": [0.0]}, r"planes\.normals\[0\]"),
        ({"planes.normals": [[0.0, 1.0]], "planes.offsets": [0.55]}, r"stop distance"),
        (
            {"planes.normals": [[0.0, 1.0]], "planes.offsets": [0.0], "planes.stop": 0.2},
            r"planes\.stop",
        ),
    ]
    for overrides, message in cases:
        with pytest.raises(emdm.ScenarioError, match=message):
            sc.with_overrides(overrides)


def test_planes_round_trip_through_toml():
    import tomllib

    sc = _with_plane("task2", 0.1)
    again = emdm.scenario_from_dict(tomllib.loads(sc.to_toml()))
    np.testing.assert_array_equal(again.planes.normals, sc.planes.normals)
    np.testing.assert_array_equal(again.planes.offsets, sc.planes.offsets)
    assert "[planes]" not in emdm.load_scenario("task2").to_toml()


def test_a_scenario_file_with_planes_runs_from_the_command_line_and_reads_back(tmp_path):
    """`emdm run` on a file with a [planes] section writes the rows' counts in the diagnostics,
    and the run folder reads back to the same record."""
    from emdm.cli import main
    from emdm.outputs.records import read_run

    sc = _with_plane("task1", 0.45)
    path = tmp_path / "plane.toml"
    path.write_text(sc.to_toml(), encoding="utf-8")
    out = tmp_path / "out"
    assert main(["run", str(path), "--controller", "C-EMDM", "--out", str(out)]) == 0
    header = (out / "diagnostics" / "C-EMDM.csv").read_text().splitlines()[0]
    assert header.endswith("rows,rows_active")
    back = read_run(out, "C-EMDM")
    run = emdm.simulate(sc, "C-EMDM")
    np.testing.assert_array_equal(back.qd, run.qd)
    np.testing.assert_array_equal(back.rows, run.rows)
    assert back.rows.max() == 1


def test_a_crossed_stop_distance_is_named_when_the_scaled_task_cannot_go_on():
    """Plane rows are not exact in discrete time (documented): with the goal inside the stop
    distance, C-EMDM crosses it by the Euler step's second-order term (d = 0.0196 m < 0.02 m)
    and then stops with one line naming the damper rows, keeping the partial run."""
    sc = _with_plane("task1", 0.49)
    with pytest.raises(emdm.NoSolution, match=r"damper row\(s\) of planes") as caught:
        emdm.simulate(sc, "C-EMDM")
    run = caught.value.run
    d = min(sc.plane_distances(q)[0] for q in run.q)
    assert sc.planes.stop - 1e-3 < d < sc.planes.stop  # crossed, by less than a millimetre


def test_the_explanation_tells_how_a_run_fared_beside_a_plane():
    """The planes event is read from the record: the closest approach, which plane and when, the
    steps with a row held and the verdict; a controller blind to the rows says so."""
    from emdm.outputs.report.explain import plane_sentence, planes

    sc = _with_plane("task1", 0.49)
    run = emdm.simulate(sc, "MMC")
    d = np.array([sc.plane_distances(q)[0] for q in run.q])
    event = planes(run)
    assert event["min_distance"] == d.min() and event["plane"] == 1
    assert event["t_min"] == run.t[int(np.argmin(d))]
    assert event["entered"] == (d.min() < sc.planes.stop)
    assert event["active_row_steps"] == int(np.count_nonzero(run.rows_active)) > 100
    assert event["sees_planes"]
    blind = planes(emdm.simulate(sc, "UC-EMDM"))
    assert blind["entered"] and not blind["sees_planes"]
    assert plane_sentence("UC-EMDM", blind).endswith("does not see the planes.")
    assert planes(emdm.simulate(emdm.load_scenario("task1"), "MMC")) is None


def test_program_data_is_kept_per_scenario_and_controller():
    """A scenario keeps each controller's program data for its next run; another controller of
    the same name (other terms), other weights or another scenario get their own."""
    from dataclasses import replace

    sc = emdm.load_scenario("task1")
    ctrl = emdm.get_controller("C-EMDM")
    first = ctrl.program_data(sc)
    assert ctrl.program_data(sc) is first
    other = replace(ctrl, terms=ctrl.terms[:2])
    assert other.program_data(sc).codes.size == 2 < first.codes.size
    assert ctrl.program_data(sc).codes.size == first.codes.size
    heavier = sc.with_overrides({"weights.manipulability": 7.0})
    assert 7.0 in ctrl.program_data(heavier).weights and 7.0 not in first.weights
    np.testing.assert_array_equal(
        emdm.simulate(heavier, ctrl).qd,
        emdm.simulate(emdm.load_scenario("task1", {"weights.manipulability": 7.0}), "C-EMDM").qd,
    )
