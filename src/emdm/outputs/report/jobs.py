"""The report's work: closed-loop runs, evidence runs, solver labs, Pareto sweeps, figures,
animations, then the documents and their compilation.

The closed-loop and evidence runs are fast (compiled) and run first, in this process; their
records and detected events are written to ``data/``. The rest is a flat list of jobs spread over
the machine's cores, longest first; the figures that need the labs' and sweeps' records are drawn
in this process once those are written, while the workers go on. Every document is rendered from
the files on disk, never from memory.
"""

from __future__ import annotations

import csv
import datetime as dt
import os
import platform
import shutil
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Future
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from ... import __version__
from ...core.controllers import CONTROLLERS, Name, get_controller
from ...core.loading import load_scenario
from ...core.scenario import Scenario
from ...errors import EmdmError, NoSolution
from ...sim.loop import Run, simulate
from ...sim.metrics import metrics
from ...solvers import DEFAULT_FALLBACK, available_solvers
from ...studies.lab import (
    LIKE_FOR_LIKE,
    LabResult,
    lab_header,
    lab_histories,
    lab_json,
    lab_rows,
    merge_labs,
    run_lab,
    worker_pool,
)
from ...studies.pareto import default_grid, front_at, pareto_study, ratios, weight_grid
from .. import paper_figures as pf
from ..animate import animate
from ..records import atomic_output, cell, write_csv, write_json, write_run_folder
from . import explain
from .config import (
    BYLINE,
    EVIDENCE,
    FOURTH_PANEL,
    FULL,
    GLYPHS,
    MANY_GOALS,
    PAIRS,
    QUICK,
    SLACK_POLICIES,
    TASKS,
    Evidence,
    ReportConfig,
    byline,
)

PAPER_FIGURES = "paper/figures"
SLIDE_FIGURES = "paper/slides"
SLIDE_PARETO_WIDTH = 0.55 * 398.34 / 72.27
"""in: the pitch's Pareto figure, shown at its own size (its column of the 16:9 slide's
398.34 pt text width, the bullets beside it): drawn so, its text is printed at its set size."""


# ------------------------------------------------------------------------ in-process runs
def _evidence_run(ev: Evidence, nominal: dict[str, Run]) -> dict[str, Any]:
    entry: dict[str, Any] = {
        "task": ev.task,
        "controllers": list(ev.controllers),
        "overrides": ev.overrides,
        "controller_overrides": {},
        "runs": {},
    }
    runs: dict[str, Run] = {}
    for name in ev.controllers:
        own = ev.controller_overrides(name)
        if own:
            entry["controller_overrides"][name] = own
        try:
            run = simulate(ev.scenario(name), name)
        except NoSolution as exc:
            entry["runs"][name] = {"error": str(exc)}
            continue
        runs[name] = run
        mt = metrics(run)
        ev_run = explain.run_events(run)
        entry["runs"][name] = {
            **{
                k: mt[k]
                for k in (
                    "reached",
                    "time_to_goal",
                    "final_time",
                    "final_error",
                    "mean_manipulability",
                    "total_effort",
                    "max_abs_qd",
                    "path_length",
                    "scaled_steps",
                    "max_abs_slack",
                )
            },
            "events": {k: ev_run[k] for k in ("stall", "singular", "scaling")},
        }
    if ev.reference and ev.controllers[0] in runs:
        ours, ref = runs[ev.controllers[0]], nominal[ev.reference]
        n = min(ours.steps, ref.steps)
        entry["reference"] = {
            "controller": ev.reference,
            "same_steps": ours.steps == ref.steps,
            "max_abs_qd_difference": float(np.abs(ours.qd[:n] - ref.qd[:n]).max()) if n else 0.0,
            # each mean over the states both runs have: a shorter run's own mean covers less
            "common_until_t": float(ours.t[n]),
            "mean_m_common": {
                "run": float(np.mean(ours.m[: n + 1])),
                "reference": float(np.mean(ref.m[: n + 1])),
            },
        }
    if len(ev.controllers) == 2 and all(c in runs for c in ev.controllers):
        entry["pair"] = explain.pair_events(runs[ev.controllers[0]], runs[ev.controllers[1]])
    return entry


def _events(stage: Path, scenarios: dict[str, Scenario], runs: dict[str, dict[str, Run]]) -> None:
    for task, task_runs in runs.items():
        first = next(iter(task_runs.values()))
        write_json(
            stage / "data" / task / "events.json",
            {
                "scenario": task,
                "controllers": {name: explain.run_events(run) for name, run in task_runs.items()},
                "pairs": {
                    group: explain.pair_events(task_runs[a], task_runs[b])
                    for group, (a, b) in PAIRS.items()
                },
                "geometry": explain.geometry(scenarios[task], first.p[0]),
            },
        )
    write_json(
        stage / "data" / "evidence.json",
        {
            "rows": _rows_index(),
            "runs": {ev.key: _evidence_run(ev, runs[ev.task]) for ev in EVIDENCE},
        },
    )


def _rows_index() -> dict[str, str]:
    """Where each of Table I's A-rows is recorded: an entry of ``runs`` here, or (A2a, A2b) the
    weight grid of Fig. 2, whose run it is."""
    from .findings.base import ABLATIONS, FINER_STEP, GRID_MISS, run_label
    from .findings.records import GRID_FILE

    grid = GRID_FILE.format(ctrl=Name.UC_EMDM).removeprefix("data/")
    where = {
        GRID_MISS: f"{grid}: the first run with reached false",
        FINER_STEP: f"{grid}: that run's finer_dt (its nominal: the nominal weights there)",
    }
    keys = [k for entry in ABLATIONS for k in (entry if isinstance(entry, tuple) else (entry,))]
    return {run_label(k): where.get(k, f"evidence.json: runs/{k}") for k in keys}


# ------------------------------------------------------------------------------- pool jobs
def _job_lab(task: str, controller: str, solvers: Sequence[str], cfg: ReportConfig) -> LabResult:
    return run_lab(
        load_scenario(task),
        controller,
        solvers,
        sample=cfg.lab_sample,
        repeats=cfg.lab_repeats,
        budget=cfg.lab_budget,
        workers=1,
    )


def _write_lab(folder: Path, lab: LabResult, fig_dir: Path | None) -> None:
    record = lab_json(lab)
    # where each solver failed: on task-scaled steps (a single admissible point) or not
    record["notes"] = {
        name: {
            "failures_on_scaled_steps": sum(
                1 for st in study.solves if st.x is None and lab.reference.alpha[st.step] < 1.0
            )
        }
        for name, study in lab.studies.items()
    }
    write_json(folder / "solvers.json", record)
    write_json(folder / "histories.json", lab_histories(lab))
    for name in lab.studies:
        write_csv(
            folder / "solvers" / f"{name}.csv",
            lab_header(lab),
            ([cell(v) for v in row] for row in lab_rows(lab, name)),
        )
    if fig_dir is not None:
        from ..lab_plots import convergence_figure
        from ..style import formats

        with formats((".png",)):
            convergence_figure(lab, fig_dir)


def _job_lab_written(
    task: str,
    controller: str,
    solvers: Sequence[str],
    cfg: ReportConfig,
    data_dir: Path,
    fig_dir: Path | None,
) -> str:
    """A whole lab, its data (and convergence figures) written by the worker."""
    _write_lab(data_dir, _job_lab(task, controller, solvers, cfg), fig_dir)
    return controller


def _outcome(run: Any, done: dict[str, Any]) -> dict[str, Any]:
    """A whole run's outcomes as the weight grid's rows keep them."""
    return {
        "reached": run.reached,
        "time_to_goal": run.time_to_goal,
        "max_abs_qd": done["max_abs_qd"],
        "mean_manipulability": done["mean_manipulability"],
        "total_effort": done["total_effort"],
        "scaled_steps": done["scaled_steps"],
    }


def _job_pareto(task: str, controller: str, cfg: ReportConfig, data_dir: Path) -> str:
    """The per-step fronts and the whole-run weight grid; a setting that fails to reach is re-run
    with a five times smaller time step (does the discretisation cause it?)."""
    scenario = load_scenario(task)
    nominal = scenario.weights.manipulability / scenario.weights.effort
    sweep = np.unique(np.append(ratios(per_decade=cfg.pareto_per_decade), nominal))
    data, _ = pareto_study(scenario, controller, sweep=sweep)
    slack = load_scenario(task, {"controller.on_infeasible": "slack"})
    for step in data["steps"]:  # a scaled step's one point: the front Table I's slack row sees
        if all(p["alpha"] < 1.0 for p in step["points"]):
            step["slack_points"] = front_at(slack, get_controller(controller), step["q"], sweep)
    grid = weight_grid(scenario, controller, default_grid(scenario, cfg.grid))
    control: dict[str, Any] | None = None  # nominal weights at the finer step (Table II brackets)
    for row in grid:
        if row.get("reached", False):
            continue
        over = {"weights.effort": row["w_effort"], "weights.manipulability": row["w_manip"]}
        try:
            failing = simulate(load_scenario(task, over), controller)
            row["max_abs_qd"] = metrics(failing)["max_abs_qd"]
            row["final_error"] = float(failing.error_norm[-1])
            finer = simulate(
                load_scenario(task, {**over, "motion.dt": scenario.motion.dt / 5}), controller
            )
            done = metrics(finer)
            if control is None:
                base = simulate(
                    load_scenario(task, {"motion.dt": scenario.motion.dt / 5}), controller
                )
                control = _outcome(base, metrics(base))
            row["finer_dt"] = {
                "dt": scenario.motion.dt / 5,
                **_outcome(finer, done),
                "nominal": control,
            }
        except (NoSolution, EmdmError) as exc:
            row["finer_dt"] = {"error": str(exc)}
    fronts = explain.front_events(data)
    for step, info in zip(data["steps"], fronts, strict=True):
        pts = step["points"]
        ratio = [p["w_manip"] / p["w_effort"] for p in pts]
        i = int(np.argmin([abs(np.log10(max(r, 1e-12)) - np.log10(nominal)) for r in ratio]))
        info["nominal_index"] = i
        info["nominal_E"] = pts[i]["E"]
        info["nominal_M"] = pts[i]["M"]
        info["zero_E"] = pts[0]["E"]
        info["zero_M"] = pts[0]["M"]
        span = info["M_max"] - info["M_min"]
        info["nominal_M_share"] = (pts[i]["M"] - info["M_min"]) / span if span > 0 else None
        lo, hi = info["E_min"], info["E_max"]
        info["nominal_E_log_pct"] = (  # where the nominal effort sits on a log scale, 0-100 %
            100.0 * np.log(pts[i]["E"] / lo) / np.log(hi / lo) if 0 < lo < hi else None
        )
    write_json(data_dir / "pareto.json", data)
    write_json(
        data_dir / "weight_grid.json",
        {"scenario": scenario.name, "controller": controller, "runs": grid},
    )
    write_json(data_dir / "fronts.json", {"controller": controller, "steps": fronts})
    return controller


def _load_runs(task: str) -> dict[str, Run]:
    scenario = load_scenario(task)
    return {c: simulate(scenario, c) for c in CONTROLLERS}


def _job_pair_figures(task: str, group: str, stage: Path, cfg: ReportConfig) -> list[str]:
    """A pair's composite for the paper (and, in the full study, for the pitch's backup)."""
    runs = _load_runs(task)
    ivkc, emdm = PAIRS[group]
    pair = [runs[ivkc], runs[emdm]]
    with pf.png_only(cfg.quick):
        # a fourth panel: Task 2's tracking gap (the slack, or the scaled-off part), Task 1's
        # tip paths (its task imposed: the tracking overlaid)
        fourth = FOURTH_PANEL[task]
        stem = stage / PAPER_FIGURES / f"{task}-{group}"
        # Task 2.2's pair beside its run without the dexterity term (its answer's evidence),
        # with the joint strips the other pairs have (readings 152-159 asked them back)
        extra = _without_term(emdm) if (task, group) == ("task2", "UC") else None
        if extra is not None:
            from .findings.base import run_label

            extra = (f"{extra[0]} ({run_label(WITHOUT_TERM)})", extra[1])
        if (task, group) == ("task2", "C"):  # Task 2.1's like-for-like run, plotted (reading
            # 169: the fair comparison was two table rows only)
            run = _rerun_evidence(SLACK_POLICIES["task2"], ivkc)
            extra = (f"{ivkc}, free slack", run) if run is not None else None
        out = [
            str(
                pf.pair_figure(
                    pair, stem, gap=fourth == "gap", path=fourth == "path", without=extra
                )
            )
        ]
        if not cfg.quick:
            out.append(
                str(pf.pair_figure(pair, stage / SLIDE_FIGURES / f"{task}-{group}", pf.SLIDE))
            )
            if (task, group) == ("task2", "UC"):  # the pitch's Task 2.2 slide: two big panels
                stem = stage / SLIDE_FIGURES / "task2-UC-effort"
                out.append(str(pf.slack_figure(pair, stem, without=_without_term(emdm))))
    return out


WITHOUT_TERM = "t2-uc-emdm-no-manip"
"""The evidence run the pitch's Task 2.2 slide draws beside its pair: UC-EMDM without its
dexterity term."""


def _rerun_evidence(key: str, ctrl: str) -> Run | None:
    """``ctrl``'s run in the evidence run ``key`` again, as :func:`_evidence_run` ran it for the
    record (the overrides of :data:`EVIDENCE` and its own, a like-for-like slack weight), for a
    figure; None if it does not run."""
    ev = next((e for e in EVIDENCE if e.key == key), None)
    if ev is None or ctrl not in ev.controllers:
        return None
    try:  # (the record keeps outcomes, not runs: a figure simulates it again, in milliseconds)
        return simulate(ev.scenario(ctrl), ctrl)
    except NoSolution:
        return None


def _without_term(emdm: str) -> tuple[str, Run] | None:
    """Task 2's UC-EMDM run without the dexterity term (:func:`_rerun_evidence`), labelled for
    the slide; None if it does not run."""
    run = _rerun_evidence(WITHOUT_TERM, emdm)
    return (f"{emdm}, $w_M=0$", run) if run is not None else None


def _job_mmc(stage: Path, cfg: ReportConfig) -> list[str]:
    """Beyond the brief: the manipulability benchmark on the Panda and the UR5 (``data/mmc.json``)
    and the Panda's baselines on its preset task (a figure for the page)."""
    from ...studies.mmc import CONTROLLERS as BENCH
    from ...studies.mmc import PUBLISHED, run_mmc_benchmark
    from ...studies.mmc_paper import run_paper_protocol
    from ..plots import spatial_path_figure

    data = run_mmc_benchmark(trials=cfg.mmc_trials, seed=0)
    data["published"] = PUBLISHED
    data["paper"] = run_paper_protocol(trials=cfg.mmc_trials, seed=0)
    sc = load_scenario("panda")
    runs = {name: simulate(sc, name) for name in BENCH}
    data["panda_preset"] = {name: metrics(run) for name, run in runs.items()}
    write_json(stage / "data" / "mmc.json", data)
    with pf.png_only(cfg.quick):
        stem = spatial_path_figure(list(runs.values()), stage / PAPER_FIGURES / "panda-baselines")
    return [str(stem)]


def _job_many_goals(stage: Path, cfg: ReportConfig) -> str:
    """Whether the one-goal answers hold elsewhere: each task's controllers, with their
    nominal task scaling and with the free slack of its policy run, on the same random starts
    and goals; Task 1's UC-EMDM at each weight of its whole-run sweep (``data/many-goals.json``)."""
    from ...studies.goals import policy_study, term_study, weight_study

    tasks: dict[str, Any] = {}
    for task in TASKS:
        sc = load_scenario(task)
        ev = next(e for e in EVIDENCE if e.key == SLACK_POLICIES[task])
        pairs = {group: (str(a), str(b)) for group, (a, b) in PAIRS.items()}
        tasks[task] = {
            "reach": sc.reach,
            "policies": {
                # where UC-EMDM rests when it misses (Section V's explanation, on the page)
                "scale": policy_study(
                    {c: sc for c in CONTROLLERS}, pairs, cfg.goal_runs, 0, rest=(Name.UC_EMDM,)
                ),
                "slack": policy_study(
                    {c: ev.scenario(c) for c in ev.controllers},
                    {"C": (str(ev.controllers[0]), str(ev.controllers[1]))},
                    cfg.goal_runs,
                    0,
                ),
            },
        }
    for task in TASKS:  # what the dexterity term costs in arrivals (reading 179: C-EMDM's
        # misses in Task 2 were left unexplained), counted beyond UC-EMDM's farthest-reach
        # boundary where its misses have one
        uc = tasks[task]["policies"]["scale"]["controllers"][Name.UC_EMDM]["missed"]
        beyond = (
            uc["goal_radius"][0]
            if uc
            and uc["arrived_goal_radius_max"] is not None
            and uc["goal_radius"][0] > uc["arrived_goal_radius_max"]
            else None
        )
        tasks[task]["no_term"] = {
            str(c): term_study(
                load_scenario(task), c, {"weights.manipulability": 0.0}, cfg.goal_runs, 0, beyond
            )
            for c in (Name.UC_EMDM, Name.C_EMDM)
        }
    task1 = load_scenario("task1")  # the whole-run sweep's weights (Fig. 3, right)
    grid = default_grid(task1, cfg.grid)
    tasks["task1"]["weights"] = weight_study(task1, Name.UC_EMDM, grid, cfg.goal_runs, 0)
    write_json(stage / MANY_GOALS, {"runs": cfg.goal_runs, "seed": 0, "tasks": tasks})
    return MANY_GOALS


def _job_story_figures(stage: Path, cfg: ReportConfig) -> list[str]:
    """The workspace figure of Task 2, the pitch's headline and its animation stills."""
    with pf.png_only(cfg.quick):
        return _story_figures(stage)


def _story_figures(stage: Path) -> list[str]:
    t1, t2 = _load_runs("task1"), _load_runs("task2")
    geometry = explain.geometry(t2[Name.C_IVKC].scenario, t2[Name.C_IVKC].p[0])
    out = []
    if geometry is not None:
        pair = [t2[Name.C_IVKC], t2[Name.C_EMDM]]
        out.append(str(pf.workspace_figure(pair, geometry, stage / PAPER_FIGURES / "workspace")))
        out.append(
            str(pf.workspace_figure(pair, geometry, stage / SLIDE_FIGURES / "workspace", pf.SLIDE))
        )
    # Task 1's stills in the paper: both pairs' postures and tip paths (the pair figures show
    # time series only)
    arms = {
        "unconstrained": [t1[Name.UC_IVKC], t1[Name.UC_EMDM]],
        "constrained": [t1[Name.C_IVKC], t1[Name.C_EMDM]],
    }
    out.append(str(pf.arms_figure(arms, stage / PAPER_FIGURES / "task1-arms")))
    out.append(
        str(
            pf.manipulability_figure(
                {
                    "unconstrained": [t1[Name.UC_IVKC], t1[Name.UC_EMDM]],
                    "constrained": [t1[Name.C_IVKC], t1[Name.C_EMDM]],
                },
                stage / SLIDE_FIGURES / "task1-m",
            )
        )
    )
    # the pitch's Task 1 slide: the constrained pair's m(t), the same commands shaded
    pair1 = [t1[Name.C_IVKC], t1[Name.C_EMDM]]
    shared = explain.pair_events(*pair1)["coincide_until_t"]
    stem = stage / SLIDE_FIGURES / "task1-C-m"
    out.append(str(pf.mean_m_figure(pair1, stem, width=2.6, height=2.0, shared_until=shared)))
    # the pitch's Task 2 slide: the constrained pair's m(t) and mean m under its bullets
    pair2 = [t2[Name.C_IVKC], t2[Name.C_EMDM]]
    out.append(str(pf.mean_m_figure(pair2, stage / SLIDE_FIGURES / "task2-m")))
    # the pitch's picture of what m measures, on Task 2's C-EMDM (it passes m = 0)
    out.append(str(pf.ellipse_figure(t2[Name.C_EMDM], stage / SLIDE_FIGURES / "ellipses")))
    for task, runs in (("task1", t1), ("task2", t2)):
        out.append(
            str(
                pf.stills_figure(
                    [runs[Name.C_IVKC], runs[Name.C_EMDM]], stage / SLIDE_FIGURES / f"{task}-stills"
                )
            )
        )
    policy = policy_runs(t1, stage / "data" / "evidence.json")
    if policy:
        stem = stage / SLIDE_FIGURES / "task1-policy"
        out.append(str(pf.policy_figure(policy, stem, height=2.8)))
    bars = evidence_bars(t2, stage / "data" / "evidence.json")
    if len(bars) > 2:  # the two as run, and at least one run with a cause changed
        max_time = t2[Name.C_EMDM].scenario.motion.max_time
        stem = stage / SLIDE_FIGURES / "task2-evidence"
        out.append(str(pf.evidence_figure(bars, max_time, stem)))
    return out


POLICY_RUN = SLACK_POLICIES["task1"]
"""The evidence run the pitch's Task 1 policy chart sets beside the constrained pair: the
same runs with a free slack instead of task scaling."""


def policy_runs(runs: dict[str, Run], record: Path) -> list[pf.PolicyRun]:
    """The pitch's Task 1 policy chart: the constrained pair as run (slowed by task scaling),
    each followed by its free-slack run from ``evidence.json``; empty without that record."""
    import json

    ev = json.loads(record.read_text(encoding="utf-8"))["runs"] if record.exists() else {}
    slack = ev.get(POLICY_RUN, {}).get("runs", {})
    out = []
    for ctrl in (Name.C_IVKC, Name.C_EMDM):
        if ctrl not in slack:
            return []
        run, other = metrics(runs[ctrl]), slack[ctrl]  # (the records' outcomes, alike)
        out.append(
            pf.PolicyRun(
                ctrl,
                "slowed",
                run["time_to_goal"] if run["reached"] else None,
                float(run["total_effort"]),
                float(run["mean_manipulability"]),
                float(run["path_length"]),
            )
        )
        out.append(
            pf.PolicyRun(
                ctrl,
                "free slack",
                other["time_to_goal"] if other.get("reached") else None,
                float(other["total_effort"]),
                float(other["mean_manipulability"]),
                float(other["path_length"]),
            )
        )
    return out


def evidence_bars(runs: dict[str, Run], record: Path) -> list[pf.EvidenceBar]:
    """The pitch's Task 2 evidence chart: the constrained pair as run, then each of Task 2's
    runs with one cause changed (``evidence.json``) that the slide names, those present."""
    import json

    ev = json.loads(record.read_text(encoding="utf-8"))["runs"] if record.exists() else {}

    def goal(run: dict[str, Any]) -> float | None:
        return run["time_to_goal"] if run.get("reached") else None

    def arrival(run: Run) -> float | None:
        return run.time_to_goal if run.reached else None

    bars = []
    for ctrl in (Name.C_IVKC, Name.C_EMDM):
        bars.append(pf.EvidenceBar(ctrl, "as run", arrival(runs[ctrl])))
        if ctrl in ev.get(SLACK_POLICIES["task2"], {}).get("runs", {}):
            run = ev[SLACK_POLICIES["task2"]]["runs"][ctrl]
            bars.append(pf.EvidenceBar(ctrl, "free slack", goal(run)))
    if Name.C_EMDM in ev.get("t2-c-emdm-no-manip", {}).get("runs", {}):
        run = ev["t2-c-emdm-no-manip"]["runs"][Name.C_EMDM]
        bars.append(pf.EvidenceBar(Name.C_EMDM, "no dexterity term", goal(run)))
    tight = ev.get("t2-c-emdm-tight-slack", {})
    if Name.C_EMDM in tight.get("runs", {}):
        bound = max(abs(v) for v in tight["overrides"]["slack.max"])
        change = f"slack within ±{bound:g} m/s"
        bars.append(pf.EvidenceBar(Name.C_EMDM, change, goal(tight["runs"][Name.C_EMDM])))
    return bars


def _read_rows(path: Path) -> list[dict[str, str]]:
    with path.open(encoding="utf-8", newline="") as handle:
        return list(csv.DictReader(handle))


def _job_data_figures(stage: Path, dt_task2: float, cfg: ReportConfig) -> list[str]:
    """Figures drawn from the labs' and sweeps' records (second wave)."""
    with pf.png_only(cfg.quick):
        return _data_figures(stage, dt_task2)


def _data_figures(stage: Path, dt_task2: float) -> list[str]:
    import json

    def load(rel: str) -> Any:
        return json.loads((stage / rel).read_text(encoding="utf-8"))

    out = []
    names: tuple[str, ...] = (Name.UC_EMDM, Name.C_EMDM)
    fronts = {c: load(f"data/task1-pareto-{c}/pareto.json") for c in names}
    infos = {c: load(f"data/task1-pareto-{c}/fronts.json")["steps"] for c in names}
    grids = {c: load(f"data/task1-pareto-{c}/weight_grid.json")["runs"] for c in names}
    out.append(str(pf.pareto_figure(fronts, infos, grids, stage / PAPER_FIGURES / "pareto")))
    out.append(
        str(
            pf.pareto_slide_figure(
                float(fronts[Name.UC_EMDM]["nominal_ratio"]),
                grids[Name.UC_EMDM],
                stage / SLIDE_FIGURES / "pareto",
                width=SLIDE_PARETO_WIDTH,
            )
        )
    )
    lab = load("data/task2-lab-C-EMDM/solvers.json")
    out.append(str(pf.solver_figure(lab, dt_task2, stage / PAPER_FIGURES / "solvers")))
    # for peers, the brief's two families and our method: not the like-for-like control nor
    # the fallbacks (readings 209-222: eight solver names meant little to a peer audience)
    aside = (LIKE_FOR_LIKE, *DEFAULT_FALLBACK)
    out.append(
        str(pf.solver_verdict_figure(lab, dt_task2, stage / SLIDE_FIGURES / "solvers", aside))
    )
    run = simulate(load_scenario("task2"), Name.C_EMDM)
    rows = {
        name: _read_rows(stage / "data" / "task2-lab-C-EMDM" / "solvers" / f"{name}.csv")
        for name in ("interior-point", "admm", "slsqp")
        if (stage / "data" / "task2-lab-C-EMDM" / "solvers" / f"{name}.csv").exists()
    }
    out.append(str(pf.conditioning_figure(run, rows, stage / PAPER_FIGURES / "conditioning")))
    panels = [
        panel
        for rel, count in (
            # Task 2.1's comparison only: Task 1's custom solver is told in its section
            # (readings 150-153: its panel, under Task 2's table, was read as out of place)
            (f"data/task2-lab-{Name.C_EMDM}/histories.json", "evaluations"),
        )
        if (stage / rel).exists() and (panel := convergence_panel(load(rel), count)) is not None
    ]
    if panels:  # the paper's: each task's hardest program, every solver that counts there
        # its legend is Table III's rows: each solver's line and marker, beside its name
        stem = stage / PAPER_FIGURES / "convergence"
        out.append(str(pf.convergence_figure(panels, stem, glyphs=stage / "paper" / GLYPHS)))
    return out


CONVERGENCE_PROGRAM = "least dexterous"
"""The program of the paper's convergence figure, each task's hardest (the lab's first, if it
did not record that one): the smallest m, the worst-conditioned."""


def convergence_panel(histories: dict[str, Any], count: str) -> pf.ConvergencePanel | None:
    """A lab's panel of the paper's convergence figure from its ``histories.json``: the running
    best error of every solver whose iterates count ``count`` (``iteration``: the iterations
    done, from 1; ``evaluations``: objective evaluations), on :data:`CONVERGENCE_PROGRAM`."""
    from ..lab_plots import error_curve

    steps = histories["representative_steps"]
    rep = CONVERGENCE_PROGRAM if CONVERGENCE_PROGRAM in steps else next(iter(steps), None)
    if rep is None:
        return None
    f_star = histories["optimum"][rep]
    curves: dict[str, pf.Curve] = {}
    for name, solver in histories["solvers"].items():
        # (iteration 0 is an interior-point method's starting point: nothing done yet)
        history = [h for h in solver["histories"].get(rep, ()) if h.get(count, 0) >= 1]
        if history:
            curves[name] = (
                solver["family"],
                [h[count] for h in history],
                list(error_curve(tuple(history), f_star)),
                solver["returned"][rep],
            )
    if not curves:
        return None
    task = "Task 1" if histories["scenario"] == "task1" else "Task 2"
    return pf.ConvergencePanel(
        f"{task} {histories['controller']}, $k={steps[rep]}$",  # whose program it is
        "iterations" if count == "iteration" else "objective evaluations",
        curves,
        by_family=count == "evaluations",  # the gradient-free ones beside the others
    )


def _job_animation(task: str, group: str, stem: Path, cfg: ReportConfig) -> dict[str, Any]:
    runs = _load_runs(task)
    ivkc, emdm = PAIRS[group]
    pair = [runs[ivkc], runs[emdm]]
    duration = max(float(r.t[-1]) for r in pair)
    speedup = 1.0
    while duration / speedup > cfg.animation_seconds:
        speedup *= 2.0
    files = animate(pair, stem, speedup=speedup, mp4=cfg.mp4, max_fps=cfg.animation_fps)
    return {
        "task": task,
        "pair": group,
        "controllers": [ivkc, emdm],
        "files": [p.name for p in files],
        "speedup": speedup,
        "simulated_s": duration,
        "playing_s": duration / speedup,
    }


# ---------------------------------------------------------------------------------- driver
def provenance(config: ReportConfig, wall: float) -> dict[str, Any]:
    """Versions, parameters, date, machine and wall time of a report."""
    packages = {}
    for name in (
        "numpy",
        "scipy",
        "qpsolvers",
        "daqp",
        "quadprog",
        "matplotlib",
        "jinja2",
        "pillow",
        "numba",
        "cma",
        "imageio-ffmpeg",
        "clarabel",
        "osqp",
        "piqp",
        "proxsuite",
        "highspy",
    ):
        try:
            packages[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
    return {
        "emdm_version": __version__,
        "mode": "quick" if config.quick else "full",
        "date_utc": dt.datetime.now(dt.UTC).strftime("%Y-%m-%d %H:%M:%S"),
        "python": sys.version.split()[0],
        "platform": platform.platform(),
        "machine": platform.machine(),
        "cpus": os.cpu_count(),
        "packages": packages,
        "solvers_installed": available_solvers(),
        "config": {k: (list(v) if isinstance(v, tuple) else v) for k, v in config.__dict__.items()},
        "wall_time_s": wall,
    }


PAGE_LIMIT = 4
"""The brief's limit for the paper; a longer first compile is redone with compact figures."""


def _check_compiled(compiled: dict[str, Any], folder: Path) -> None:
    """Refuse a report whose TeX engine ran but left a document without its PDF (a source it
    cannot compile): nothing is swapped in, the earlier report stays, and the sources and logs
    are kept in a folder of their own, named in the one-line message."""
    failed = [
        name
        for name in ("paper", "pitch")
        if name in compiled
        and (compiled[name]["returncode"] != 0 or not (folder / f"{name}.pdf").exists())
    ]
    if not failed:
        return
    kept = Path(tempfile.mkdtemp(prefix="emdm-report-tex-"))
    for name in failed:
        for suffix in (".tex", ".log"):
            if (folder / f"{name}{suffix}").exists():
                shutil.copy2(folder / f"{name}{suffix}", kept)
    first = compiled[failed[0]]["errors"][:1]
    raise EmdmError(
        f"{failed[0]}.tex did not compile"
        + (f" ({first[0].strip()})" if first else "")
        + f"; nothing was replaced; its source and log are in {kept}"
    )


def build_report(
    out: Path,
    *,
    quick: bool = False,
    workers: int | None = None,
    progress: Callable[[str], None] | None = None,
    compile_pdf: bool = True,
    authors: Sequence[str] = (),
    title: str | None = None,
) -> dict[str, Any]:
    """Run the whole study and write the report into ``out`` (atomically). Returns provenance.

    ``authors`` (names, in order) sign the paper, the pitch and the page, and ``title`` replaces
    the study's own (checked first: a ValueError names the bad one).

    ``out`` receives ``index.html``, ``paper/`` (``paper.tex`` and ``pitch.tex``, and their PDFs
    when a TeX engine is installed and ``compile_pdf``), ``animations/``, ``data/`` and
    ``provenance.json``.
    """
    from .render import compile_documents, write_html, write_latex

    names = byline(authors, title)
    cfg = QUICK if quick else FULL
    say = progress or (lambda _msg: None)
    start = time.perf_counter()
    workers = workers or min(2, os.cpu_count() or 1)
    with atomic_output(Path(out), command="emdm report") as stage:
        write_json(stage / BYLINE, names)
        scenarios = {task: load_scenario(task) for task in TASKS}
        runs = {task: {c: simulate(sc, c) for c in CONTROLLERS} for task, sc in scenarios.items()}
        for task, task_runs in runs.items():
            write_run_folder(stage / "data" / task, scenarios[task], task_runs, solver="active-set")
        _events(stage, scenarios, runs)
        say(f"closed-loop and evidence runs done ({time.perf_counter() - start:.1f} s)")

        solvers2 = [s for s in cfg.lab_solvers if s in available_solvers()]
        solvers1 = [s for s in cfg.fallback_solvers if s in available_solvers()]
        lab_figs = not cfg.quick
        futures: dict[str, Future[Any]] = {}
        results: dict[str, Any] = {}
        with worker_pool(workers) as pool:  # no worker outlives a killed report
            # longest jobs first: the gradient-free closed loops, then the benchmark on the
            # spatial arms (a long job submitted last would run alone at the end)
            for name in reversed(solvers2):
                futures[f"lab2:{name}"] = pool.submit(_job_lab, "task2", Name.C_EMDM, [name], cfg)
            futures["mmc"] = pool.submit(_job_mmc, stage, cfg)
            futures["many-goals"] = pool.submit(_job_many_goals, stage, cfg)
            for ctrl in (Name.UC_EMDM, Name.C_EMDM):
                futures[f"pareto:{ctrl}"] = pool.submit(
                    _job_pareto, "task1", ctrl, cfg, stage / "data" / f"task1-pareto-{ctrl}"
                )
                futures[f"lab1:{ctrl}"] = pool.submit(
                    _job_lab_written,
                    "task1",
                    ctrl,
                    solvers1,
                    cfg,
                    stage / "data" / f"task1-lab-{ctrl}",
                    stage / "figures" / f"task1-lab-{ctrl}" if lab_figs else None,
                )
            for task in TASKS:
                for group in PAIRS:
                    futures[f"figures:{task}:{group}"] = pool.submit(
                        _job_pair_figures, task, group, stage, cfg
                    )
            futures["figures:story"] = pool.submit(_job_story_figures, stage, cfg)
            for task in TASKS:
                for group, (ivkc, emdm) in PAIRS.items():
                    stem = stage / "animations" / task / f"{ivkc}_vs_{emdm}"
                    futures[f"anim:{task}:{group}"] = pool.submit(
                        _job_animation, task, group, stem, cfg
                    )
            # the records the second wave draws from (Task 1's labs: their histories)
            first = [k for k in futures if k.startswith(("lab2:", "pareto:", "lab1:"))]
            for key in first:
                results[key] = futures[key].result()
                say(f"{key} done ({time.perf_counter() - start:.1f} s)")
            lab2 = merge_labs([results[f"lab2:{name}"] for name in solvers2])
            _write_lab(
                stage / "data" / "task2-lab-C-EMDM",
                lab2,
                stage / "figures" / "task2-lab-C-EMDM" if lab_figs else None,
            )
            # drawn here while the workers go on: queued behind them, it ran alone at the end
            results["figures:data"] = _job_data_figures(stage, scenarios["task2"].motion.dt, cfg)
            for key, future in futures.items():
                if key not in results:
                    results[key] = future.result()
                    say(f"{key} done ({time.perf_counter() - start:.1f} s)")
            say(f"figures done ({time.perf_counter() - start:.1f} s)")
        write_json(
            stage / "data" / "animations.json",
            {
                "animations": {
                    f"{v['task']}-{v['pair']}": v
                    for k, v in results.items()
                    if k.startswith("anim:")
                }
            },
        )
        write_latex(stage)
        say(f"paper and pitch written ({time.perf_counter() - start:.1f} s)")
        compiled = (
            compile_documents(stage / "paper", say, final=Path(out) / "paper")
            if compile_pdf and cfg.compile
            else {}
        )
        if compiled.get("paper", {}).get("pages", 0) > PAGE_LIMIT:  # a few lines too many
            write_latex(stage, compact=True, names=("paper",))
            again = compile_documents(stage / "paper", say, names=("paper",))
            compiled.update(paper=again["paper"], compact=True)
            compiled["seconds"] += again["seconds"]
        _check_compiled(compiled, stage / "paper")
        prov = provenance(cfg, time.perf_counter() - start)
        prov["compiled"] = compiled
        write_json(stage / "provenance.json", prov)
        write_html(stage)
        say(f"report written ({time.perf_counter() - start:.1f} s)")
    return prov
