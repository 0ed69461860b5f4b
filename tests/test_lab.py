"""The solver lab: exact solvers exact, every solver honest about infeasibility, measured records."""

from __future__ import annotations

import csv
import json
import warnings

import numpy as np
import pytest
from conftest import reference_solve
from test_solvers import random_qp

import emdm
from emdm import QP
from emdm.cli import main
from emdm.core.controllers import program_at
from emdm.solvers import available_solvers, get_solver, kkt_report
from emdm.studies.lab import lab_histories, lab_json, merge_labs, run_lab

# solvers whose answers are exact to 1e-8 (measured; piqp and highs reach about 1e-7, osqp 1e-2)
EXACT = [
    s for s in ("active-set", "interior-point", "daqp", "clarabel") if s in available_solvers()
]
# exact when they answer, but they decline some feasible (degenerate) programs
DECLINING = [s for s in ("quadprog", "proxqp") if s in available_solvers()]


@pytest.fixture(scope="module")
def preset_programs():
    programs = []
    for task in ("task1", "task2"):
        sc = emdm.load_scenario(task)
        for name in ("C-EMDM", "C-IVKC", "UC-EMDM"):
            run = emdm.simulate(sc, name)
            ctrl = emdm.get_controller(name)
            for k in range(run.steps):
                qp = program_at(ctrl, sc, run.q[k]).qp
                x_star = np.concatenate((run.qd[k], run.delta[k][: qp.n_slack]))
                programs.append((qp, x_star))
    return programs


@pytest.mark.parametrize("solver", EXACT)
def test_exact_solvers_on_every_step_of_both_presets(preset_programs, solver):
    spec = get_solver(solver)
    for qp, x_star in preset_programs:
        result = spec.solve(qp)
        assert result.x is not None, (solver, result.status)
        scale = max(1.0, np.abs(x_star).max())
        assert np.abs(result.x - x_star).max() <= 1e-8 * scale, solver
        assert qp.bound_excess(result.x) <= 1e-9


@pytest.mark.parametrize("solver", DECLINING)
def test_declining_solvers_never_answer_wrong(preset_programs, rng, solver):
    spec = get_solver(solver)
    declined = 0
    random_programs = []
    for trial in range(200):
        qp = random_qp(rng, trial)
        if qp is not None:
            random_programs.append((qp, reference_solve(qp.P, qp.c, qp.A, qp.b, qp.lb, qp.ub)))
    for qp, x_star in preset_programs + random_programs:
        result = spec.solve(qp)
        if result.x is None:
            declined += 1
            continue
        assert np.abs(result.x - x_star).max() <= 1e-8 * max(1.0, np.abs(x_star).max())
    assert declined < len(preset_programs) / 4, declined


@pytest.mark.parametrize("solver", EXACT)
def test_exact_solvers_on_random_programs(rng, solver):
    spec = get_solver(solver)
    count = 0
    for trial in range(300):
        qp = random_qp(rng, trial)
        if qp is None:
            continue
        ref = reference_solve(qp.P, qp.c, qp.A, qp.b, qp.lb, qp.ub)
        result = spec.solve(qp)
        assert result.x is not None, (trial, result.status)
        assert np.abs(result.x - ref).max() <= 1e-8 * max(1.0, np.abs(ref).max()), trial
        count += 1
    assert count > 200


def test_admm_converges_or_says_so(rng):
    spec = get_solver("admm")
    for trial in range(60):
        qp = random_qp(rng, trial)
        if qp is None:
            continue
        result = spec.solve(qp)
        if result.status == "optimal":
            ref = reference_solve(qp.P, qp.c, qp.A, qp.b, qp.lb, qp.ub)
            assert np.abs(result.x - ref).max() <= 1e-6 * max(1.0, np.abs(ref).max())
            assert qp.bound_excess(result.x) == 0.0  # ADMM returns the clipped iterate z
        else:
            assert result.status == "max_iter"


def test_every_solver_reports_an_infeasible_program_as_infeasible():
    qp = QP(
        np.eye(3),
        np.ones(3),
        np.array([[1.0, 1.0, 1.0], [0.0, 1.0, -1.0]]),
        np.array([10.0, 0.0]),
        -np.ones(3),
        np.ones(3),
        3,
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name in available_solvers():
            result = get_solver(name).solve(qp)
            assert result.x is None, (name, result.status, result.x)


def test_histories_show_convergence():
    sc = emdm.load_scenario("task2")
    qp = program_at(emdm.get_controller("C-EMDM"), sc, np.asarray(sc.motion.q0)).qp
    ip = get_solver("interior-point").solve(qp, history=True)
    mus = [h["mu"] for h in ip.history]
    assert mus[-1] < 1e-10 < mus[0]
    admm = get_solver("admm").solve(qp, history=True)
    assert admm.history[-1]["primal_residual"] <= 1e-9
    nm = get_solver("nelder-mead").solve(qp, history=True, budget=300)
    assert len(nm.history) == nm.evaluations <= 300 + 5


@pytest.fixture(scope="module")
def small_lab():
    names = ["active-set", "daqp", "slsqp", "nelder-mead", "cobyla"]
    scenario = emdm.load_scenario("task2", {"motion.max_time": 3.0})
    return run_lab(scenario, "C-EMDM", names, sample=6, repeats=2, budget=200, workers=1)


def test_lab_measures_gaps_against_the_exact_optimum(small_lab):
    lab = small_lab
    assert lab.steps[0] == 0 and lab.steps[-1] == lab.reference.steps - 1
    sc = lab.scenario
    for name, study in lab.studies.items():
        assert [s.step for s in study.solves] == lab.steps
        for s in study.solves:
            qp = program_at(lab.controller, sc, lab.reference.q[s.step]).qp
            ref = reference_solve(qp.P, qp.c, qp.A, qp.b, qp.lb, qp.ub)
            assert s.gap == pytest.approx(qp.objective(s.x) - qp.objective(ref), abs=1e-9)
            assert s.violation == pytest.approx(qp.violation(s.x), abs=1e-15)
            assert s.time > 0
            if name in ("active-set", "daqp"):
                assert abs(s.gap) < 1e-10 and kkt_report(qp, s.x).is_optimal()
    summary = lab_json(lab)["solvers"]
    for name, row in summary.items():
        for key in (
            "family",
            "loop",
            "median_time",
            "p95_time",
            "median_iterations",
            "median_evaluations",
            "max_gap",
            "max_violation",
            "reached",
            "time_to_goal",
        ):
            assert key in row, (name, key)
        assert row["median_time"] <= row["p95_time"]
    assert summary["nelder-mead"]["family"] == "gradient-free"
    assert summary["slsqp"]["family"] == "gradient"
    assert summary["nelder-mead"]["median_evaluations"] > 10
    # gradients counted beside the evaluations: SLSQP takes some, the others none
    assert summary["slsqp"]["median_gradients"] >= 1
    for name in ("active-set", "daqp", "nelder-mead", "cobyla"):
        assert summary[name]["median_gradients"] == 0, name


def test_closed_loop_records_inexact_solvers_honestly(small_lab):
    study = small_lab.studies["nelder-mead"]
    run = study.closed_loop
    assert run is not None
    # its answers are used as they are; their KKT residuals are recorded, not hidden
    assert run.kkt.max() > 1e-9
    assert set(run.solver) <= {"nelder-mead", "active-set"}
    # run at the budget its table row was measured at (200), not at its own default (2000)
    assert run.iterations.max() <= small_lab.budget


def test_lab_is_parallel_and_serial_alike():
    kwargs = {"sample": 3, "repeats": 1, "budget": 100, "closed_loop": False}
    names = ["active-set", "daqp", "powell"]
    sc = emdm.load_scenario("task2")
    serial = run_lab(sc, "C-EMDM", names, workers=1, **kwargs)
    parallel = run_lab(sc, "C-EMDM", names, workers=2, **kwargs)
    for name in names:
        a = [s.x for s in serial.studies[name].solves]
        b = [s.x for s in parallel.studies[name].solves]
        assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))


def test_a_search_its_budget_ends_says_so(small_lab):
    """A gradient-free search stopped by its evaluation budget reports ``max_iter`` (the lab
    counts these as ``limit_stops``), differential evolution's and cma-es's budgets counted in
    whole generations (reading 259: cma-es took 606 evaluations of a 600 budget)."""
    lab = small_lab
    qp = program_at(lab.controller, lab.scenario, lab.reference.q[0]).qp
    for name, budget in (("nelder-mead", 40), ("differential-evolution", 200), ("cma-es", 41)):
        short = get_solver(name).solve(qp, budget=budget)
        assert short.status == "max_iter", name
        # within the budget: a simplex's last shrink may pass it by n + 1 points, a generation
        # of differential evolution or cma-es may not (each stops at the last whole one within
        # it: 41 is no multiple of cma-es's 6 points)
        slack = qp.n + 1 if name == "nelder-mead" else 0
        assert budget / 2 < short.evaluations <= budget + slack, name
    long = get_solver("nelder-mead").solve(qp, budget=100_000)
    assert long.status == "optimal" and long.evaluations < 100_000


def test_the_seeded_methods_repeat_themselves(small_lab):
    """The stochastic solvers give the same answer on every call with one seed (so Table III's
    row, seed 0, is reproducible), and another answer with another seed (the spread is real)."""
    from emdm.solvers.nlp import SEEDED

    lab = small_lab
    qp = program_at(lab.controller, lab.scenario, lab.reference.q[0]).qp
    for name in SEEDED:
        a, b = (get_solver(name).solve(qp, budget=120) for _ in range(2))
        assert np.array_equal(a.x, b.x) and a.evaluations == b.evaluations, name
        c = get_solver(name).solve(qp, budget=120, seed=0)
        assert np.array_equal(a.x, c.x), name  # seed 0 is the default
        d = get_solver(name).solve(qp, budget=120, seed=3)
        assert not np.array_equal(a.x, d.x), name


def test_the_lab_runs_each_stochastic_method_over_seeds():
    """A stochastic method's row keeps seed 0's measurements and, in ``seeds``, every seed's
    summary over the same programs (the others have none): its spread is measured, not assumed."""
    from emdm.studies.lab import SEEDS, seed_summary

    scenario = emdm.load_scenario("task2", {"motion.max_time": 1.0})
    lab = run_lab(
        scenario, "C-EMDM", ["cma-es", "slsqp"], sample=3, repeats=1, budget=600, closed_loop=False
    )
    record = lab_json(lab)["solvers"]
    assert "seeds" not in record["slsqp"]
    seeds = record["cma-es"]["seeds"]
    assert [s["seed"] for s in seeds] == list(range(SEEDS))
    study = lab.studies["cma-es"]
    assert seeds[0] == seed_summary(0, study.solves, scenario.motion.dt)
    assert seeds[0]["median_evaluations"] == record["cma-es"]["median_evaluations"]
    assert len({s["median_evaluations"] for s in seeds}) > 1
    for s in seeds:
        assert s["failures"] == 0 and 0 <= s["over_period"] <= len(lab.steps)
        assert 0 <= s["max_abs_gap"] and s["max_violation"] <= 1e-9


def test_the_lab_records_its_budget_and_the_searches_it_ended(small_lab):
    record = lab_json(small_lab)
    assert record["budget"] == 200
    for name in ("nelder-mead", "cobyla"):
        study = small_lab.studies[name]
        ended = sum(s.evaluations >= 200 for s in study.solves)  # nelder-mead, cobyla: by count
        assert record["solvers"][name]["limit_stops"] == ended
    assert record["solvers"]["active-set"]["limit_stops"] == 0


def test_merged_labs_keep_their_budget_and_refuse_another(small_lab):
    import dataclasses

    merged = merge_labs([small_lab, small_lab])
    assert merged.budget == small_lab.budget == 200
    with pytest.raises(ValueError, match="budget"):
        merge_labs([small_lab, dataclasses.replace(small_lab, budget=100)])


def test_solvers_command_writes_the_files(tmp_path, capsys):
    out = tmp_path / "lab"
    args = [
        "solvers",
        "task1",
        "--controller",
        "C-EMDM",
        "--solvers",
        "active-set,interior-point,slsqp,cobyqa",
        "--sample",
        "4",
        "--repeats",
        "1",
        "--budget",
        "60",
        "--workers",
        "1",
        "--set",
        "motion.max_time=2",
        "--out",
        str(out),
    ]
    assert main(args) == 0
    assert "interior-point" in capsys.readouterr().out
    data = json.loads((out / "solvers.json").read_text())
    assert data["scenario"] == "task1" and data["controller"] == "C-EMDM"
    assert set(data["solvers"]) == {"active-set", "interior-point", "slsqp", "cobyqa"}
    assert data["solvers"]["active-set"]["reached"] is False  # 2 s are not enough: a result
    assert data["solvers"]["active-set"]["closed_loop_steps"] == 40
    with (out / "solvers" / "cobyqa.csv").open() as handle:
        rows = list(csv.reader(handle))
    assert rows[0][:14] == [
        "step",
        "q1",
        "q2",
        "q3",
        "x1",
        "x2",
        "x3",
        "objective",
        "gap",
        "violation",
        "iterations",
        "evaluations",
        "time",
        "status",
    ]
    assert len(rows) - 1 == len(data["resolved_steps"])
    assert rows[0][14:] == ["cond_reduced", "w_slack", "cond_J", "m", "alpha", "active"]
    assert "challenges" in data
    for stem in ("convergence", "solve_times", "trajectories", "challenges"):
        for suffix in (".png", ".pdf", ".svg"):
            assert (out / "figures" / f"{stem}{suffix}").stat().st_size > 1000


def test_solvers_command_rejects_unknown_solver(tmp_path, capsys):
    assert main(["solvers", "--solvers", "active-set,nope", "--out", str(tmp_path / "x")]) == 2
    assert "unknown solver 'nope'" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_a_sample_of_steps_keeps_the_least_dexterous_one():
    """An even spacing of Task 2's 329 steps would miss its singular passage; the lab's sample
    always holds it, with the first, the first scaled and the last step."""
    from emdm.studies.lab import representative_steps, sample_made_of, sample_steps

    run = emdm.simulate(emdm.load_scenario("task2"), "C-EMDM")
    worst = int(np.argmin(run.m[: run.steps]))
    even = {round(i) for i in np.linspace(0, run.steps - 1, 40)}
    assert worst not in even  # the case this guards
    chosen = sample_steps(run, 40)
    assert worst in chosen and set(representative_steps(run).values()) <= set(chosen)
    assert sample_steps(run, None) == list(range(run.steps))
    # read back from the record: 40 evenly spaced steps plus the ones the spacing missed
    reps = list(representative_steps(run).values())
    assert sample_made_of(chosen, reps, run.steps) == (40, sorted(set(chosen) - even))
    assert worst in sample_made_of(chosen, reps, run.steps)[1]
    assert sample_made_of(list(range(run.steps)), reps, run.steps) == (run.steps, [])
    with pytest.raises(ValueError, match="not an even sample"):
        sample_made_of([*chosen[:-2], chosen[-1]], reps, run.steps)


def test_the_lab_record_is_the_typed_record_the_report_reads(small_lab, tmp_path):
    """Issue 24, item 6: the report reads a solver lab through typed records (LabRecord,
    SolverRow) whose fields the lab writes; a renamed field stops the story in one line."""
    import dataclasses
    import typing

    from emdm.outputs.report.findings import records as r
    from emdm.outputs.report.trace import Data

    def names(cls):
        return {f.name for f in dataclasses.fields(cls)}

    assert set(typing.get_args(r.SolverKey)) == names(r.SolverRow)
    assert set(typing.get_args(r.LabKey)) == names(r.LabRecord) - {"solvers"}
    record = {**lab_json(small_lab), "notes": {}}
    folder = tmp_path / "data" / "task2-lab-C-EMDM"
    folder.mkdir(parents=True)
    (folder / "solvers.json").write_text(json.dumps(record), encoding="utf-8")
    lab = r.load_record(r.LabRecord, Data(tmp_path), "data/task2-lab-C-EMDM/solvers.json")
    assert set(lab.solvers) == set(small_lab.studies)
    assert lab.solvers["slsqp"].loop == "Python" and lab.solvers["daqp"].loop == "compiled"
    assert lab.solvers["nelder-mead"].median_evaluations > 10
    del record["solvers"]["cobyla"]["max_abs_gap"]
    (folder / "solvers.json").write_text(json.dumps(record), encoding="utf-8")
    with pytest.raises(r.RecordError, match=r"solvers/cobyla: no field 'max_abs_gap'"):
        r.load_record(r.LabRecord, Data(tmp_path), "data/task2-lab-C-EMDM/solvers.json")


@pytest.mark.parametrize("task", ["task1", "task2"])
def test_slsqp_on_the_reduced_program_reaches_the_exact_optimum(task):
    """The like-for-like control of the lab: SLSQP on the gradient-free methods' reduced program
    (null-space variables for task1, the slack eliminated for task2) reaches the certified
    optimum of the full program, and counts its evaluations as they do."""
    sc = emdm.load_scenario(task)
    run = emdm.simulate(sc, "C-EMDM")
    ctrl = emdm.get_controller("C-EMDM")
    for k in np.linspace(0, run.steps - 1, 6).astype(int):
        qp = program_at(ctrl, sc, run.q[k]).qp
        exact = get_solver("active-set").solve(qp)
        if exact.x is None:
            continue
        got = get_solver("slsqp-reduced").solve(qp, history=True)
        assert got.status == "optimal", (k, got.status)
        assert abs(qp.objective(got.x) - qp.objective(exact.x)) <= 1e-10 * (
            1 + abs(qp.objective(exact.x))
        ), k
        assert qp.violation(got.x) <= 1e-9, k
        assert 0 < got.evaluations == len(got.history), k


@pytest.mark.parametrize("name", ["slsqp", "slsqp-reduced"])
def test_the_gradient_based_methods_count_their_gradients_as_scipy_does(name, monkeypatch):
    """Table III's fair count (reading 160): a gradient-based method's objective and gradient
    evaluations are scipy's own tallies (nfev, njev) of the same search, on every kind of step."""
    import scipy.optimize

    tallies = []
    minimize = scipy.optimize.minimize

    def spy(*args, **kwargs):
        res = minimize(*args, **kwargs)
        tallies.append((res.nfev, res.njev))
        return res

    monkeypatch.setattr(scipy.optimize, "minimize", spy)
    sc = emdm.load_scenario("task2")
    run = emdm.simulate(sc, "C-EMDM")
    ctrl = emdm.get_controller("C-EMDM")
    for k in np.linspace(0, run.steps - 1, 5).astype(int):
        tallies.clear()
        got = get_solver(name).solve(program_at(ctrl, sc, run.q[k]).qp)
        assert tallies == [(got.evaluations, got.gradients)], k
        assert got.gradients >= 1, k


def test_the_gradient_free_l1_penalty_is_exact_on_every_preset_program(preset_programs, small_lab):
    """The penalised gradient-free methods (nelder-mead, powell, cma-es) minimise the exact
    optimum only if rho exceeds every optimal multiplier of the bounds (the paper says the
    penalty is exact, and by what margin): checked on every step of both presets."""
    from emdm.solvers.base import multipliers
    from emdm.solvers.nlp import PENALTY

    for qp, x_star in preset_programs:
        mult = multipliers(qp, x_star)
        assert mult.report.stationarity < 1e-8  # real multipliers, certified at the optimum
        largest = max(np.abs(mult.mu).max(initial=0.0), mult.nu.max(initial=0.0))
        assert largest < PENALTY * (1.0 + np.abs(qp.P).max())
    # the lab records the margin rho / largest multiplier of each re-solved program
    lab = small_lab
    for k, features in lab.features.items():
        qp = program_at(lab.controller, lab.scenario, lab.reference.q[k]).qp
        x_star = np.concatenate((lab.reference.qd[k], lab.reference.delta[k][: qp.n_slack]))
        mult = multipliers(qp, x_star)
        largest = max(np.abs(mult.mu).max(initial=0.0), mult.nu.max(initial=0.0))
        rho = PENALTY * (1.0 + np.abs(qp.P).max())
        assert features["penalty_margin"] == (rho / largest if largest > 0 else np.inf)


def test_the_penalised_methods_are_measured_again_with_a_smaller_weight(small_lab):
    """Reading 275: a large l1 weight may make the penalised program badly scaled for the
    gradient-free methods. The lab re-solves its programs with the weight scaled by
    PENALTY_CHECK for each penalised method (and for no other), records the gaps and the
    smaller weight's margin over the multipliers, and the solver honours the weight it is
    given (a penalty below the multipliers is no longer exact)."""
    from emdm.solvers.nlp import PENALISED, PENALTY
    from emdm.studies.lab import PENALTY_CHECK

    record = lab_json(small_lab)["solvers"]
    margin = min(f["penalty_margin"] for f in small_lab.features.values())
    for name, row in record.items():
        check = row.get("penalty_check")
        assert (check is not None) == (name in PENALISED), name
        if check is None:
            continue
        assert check["penalty_weight"] == PENALTY * PENALTY_CHECK
        assert check["penalty_margin"] == pytest.approx(margin * PENALTY_CHECK, rel=1e-12)
        assert check["max_abs_gap"] >= 0 and check["failures"] == 0
    # the weight reaches the search: far below the multipliers, the answer breaks a bound
    solve = get_solver("nelder-mead").solve
    qp = next(
        program_at(small_lab.controller, small_lab.scenario, small_lab.reference.q[k]).qp
        for k, f in small_lab.features.items()
        if np.isfinite(f["penalty_margin"])
    )
    loose = solve(qp, penalty=1e-6)
    assert loose.x is not None and qp.violation(loose.x) > 1e-6


def test_admissible_width_is_the_feasible_sets_extent():
    """A segment has its length as width, a single point zero, and a free direction infinity:
    the measure behind "each admissible set is one point" (Task 1's scaled steps)."""
    from emdm.studies.lab import admissible_width

    def box(b: float, lo: float = 0.0) -> QP:  # x1 + x2 = b in [lo, 1]^2, a slack-free program
        return QP(np.eye(2), np.zeros(2), np.ones((1, 2)), np.array([b]), [lo, lo], [1.0, 1.0], 2)

    assert admissible_width(box(1.0)) == pytest.approx(1.0)  # the segment (0, 1) to (1, 0)
    assert admissible_width(box(1.5)) == pytest.approx(0.5)
    assert admissible_width(box(2.0)) == pytest.approx(0.0, abs=1e-12)  # the corner (1, 1)

    def line(upper: float) -> QP:  # x1 + x2 = 0, x <= upper
        return QP(np.eye(2), np.zeros(2), np.ones((1, 2)), [0.0], [-np.inf] * 2, [upper] * 2, 2)

    assert admissible_width(line(1.0)) == pytest.approx(2.0)  # (1, -1) to (-1, 1)
    assert admissible_width(line(np.inf)) == np.inf


def test_task1_scaled_steps_are_single_degenerate_vertices():
    """Every task-scaled step of Task 1's C-EMDM leaves one admissible command, held by more
    bounds than a vertex needs (the paper's "degenerate vertex"): measured on the run, and the
    lab's record says the same of the steps it re-solves."""
    from emdm.studies.lab import admissible_width, challenges

    sc = emdm.load_scenario("task1")
    ctrl = emdm.get_controller("C-EMDM")
    run = emdm.simulate(sc, ctrl)
    scaled = [k for k in range(run.steps) if run.alpha[k] < 1.0]
    assert scaled
    for k in scaled:
        qp = program_at(ctrl, sc, run.q[k]).qp
        assert admissible_width(qp) <= 1e-9, k
        assert np.count_nonzero(run.active[k]) > qp.P.shape[0] - qp.A.shape[0], k
    lab = run_lab(sc, ctrl, ["active-set"], sample=8, repeats=1, closed_loop=False)
    assert any(run.alpha[k] < 1.0 for k in lab.steps)  # the sample holds scaled steps
    vertex = challenges(lab)["scaled_vertex"]
    assert vertex["max_width"] <= 1e-9 and vertex["unknowns"] == 3 and vertex["task_rows"] == 2
    assert vertex["active"][0] > vertex["unknowns"] - vertex["task_rows"]


def test_the_histories_record_keeps_every_iterate_and_the_returned_answer(small_lab):
    """``histories.json`` (the paper's convergence figure is drawn from it): per
    representative program its exact optimum, and per solver its iterates and the error of the
    answer it returned there, the same error the solver's row measures."""
    record = json.loads(json.dumps(lab_histories(small_lab)))  # as written and read back
    reps = record["representative_steps"]
    assert reps == {str(rep): k for rep, k in small_lab.representative.items()}
    for rep, k in reps.items():
        assert record["optimum"][rep] == small_lab.optimum[k][1]
    for name, study in small_lab.studies.items():
        entry = record["solvers"][name]
        assert entry["family"] == study.spec.family
        for rep, k in reps.items():
            solve = next(st for st in study.solves if st.step == k)
            expected = None if solve.x is None else abs(solve.gap) + solve.violation
            assert entry["returned"][rep] == expected
            assert entry["histories"][rep] == [dict(h) for h in study.histories[rep]]
    # the gradient-free methods count their evaluations, one more per iterate at least
    evaluations = [h["evaluations"] for h in record["solvers"]["nelder-mead"]["histories"]["first"]]
    assert evaluations == sorted(evaluations) and evaluations[-1] > 10
