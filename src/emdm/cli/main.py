"""The ``emdm`` command line. Bad input: one line on stderr and exit status 2, nothing written."""

from __future__ import annotations

import argparse
import os
import sys
import time
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NoReturn

import numpy as np

from .. import __version__
from ..core.controllers import CONTROLLERS, get_controller
from ..core.scenario import PRESETS, Scenario, load_scenario, parse_override
from ..errors import EmdmError, NoSolution
from ..outputs.records import atomic_output, cell, write_csv, write_json, write_run_folder
from ..sim.loop import Run, simulate
from ..solvers import DEFAULT_FALLBACK, DEFAULT_SOLVER, get_solver, registered_solvers


class UsageError(EmdmError):
    """A command-line argument that is wrong."""


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors: ``emdm: error: ...`` and exit status 2, no usage dump."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _scenario(args: argparse.Namespace) -> Scenario:
    overrides = dict(parse_override(text) for text in args.set or [])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scenario = load_scenario(args.scenario, overrides)
    for message in scenario.warnings:
        print(f"emdm: warning: {scenario.source}: {message}", file=sys.stderr)
    return scenario


def _add_scenario_args(
    parser: argparse.ArgumentParser,
    *,
    run_dir: bool = False,
    default: str | None = None,
    many: bool = False,
) -> None:
    """The scenario argument (a preset or TOML file, optionally a run folder) and ``--set``."""
    what = "a preset (" + ", ".join(PRESETS) + ") or a scenario TOML file"
    if run_dir:
        what += ", or a folder written by emdm run"
    if many:
        parser.add_argument("scenario", nargs="+", help=f"{what}; several make a sweep")
    elif default is None:
        parser.add_argument("scenario", help=what)
    else:
        parser.add_argument(
            "scenario", nargs="?", default=default, help=f"{what} (default {default})"
        )
    parser.add_argument(
        "--set",
        action="append",
        metavar="SECTION.KEY=VALUE",
        help="override one scenario value (repeatable), e.g. --set weights.effort=0.2",
    )


def _add_out(parser: argparse.ArgumentParser, default: str) -> None:
    parser.add_argument("--out", metavar="DIR", help=f"output folder (default {default})")


def _fallback(text: str | None) -> list[str]:
    if text is None:
        return list(DEFAULT_FALLBACK)
    return [name.strip() for name in text.split(",") if name.strip()]


def _table(rows: list[list[str]], header: list[str]) -> str:
    widths = [max(len(str(r[i])) for r in [header, *rows]) for i in range(len(header))]
    line = "  ".join(h.ljust(w) for h, w in zip(header, widths, strict=True))
    body = [
        "  ".join(
            str(c).rjust(w) if i else str(c).ljust(w)
            for i, (c, w) in enumerate(zip(r, widths, strict=True))
        )
        for r in rows
    ]
    return "\n".join([line, "-" * len(line), *body])


def summary_table(results: dict[str, dict[str, Any]]) -> str:
    """A readable table of the main metrics, one row per controller."""
    rows = []
    for name, mt in results.items():
        ttg = mt["time_to_goal"]
        rows.append(
            [
                name,
                "yes" if mt["reached"] else "no",
                str(mt["steps"]),
                f"{ttg:.2f}" if ttg is not None else "-",
                f"{mt['final_error']:.2e}",
                f"{mt['min_manipulability']:.4f}",
                f"{mt['mean_manipulability']:.4f}",
                f"{mt['total_effort']:.4f}",
                f"{mt['max_abs_qd']:.3f}",
                f"{mt['min_joint_margin']:.3f}",
                str(mt["scaled_steps"]),
                str(mt["fallback_steps"]),
                f"{mt['max_kkt_residual']:.1e}",
            ]
        )
    header = [
        "controller",
        "reached",
        "steps",
        "t_goal[s]",
        "final|e|[m]",
        "min m",
        "mean m",
        "effort",
        "max|qd|",
        "margin[rad]",
        "scaled",
        "fallback",
        "max KKT",
    ]
    return _table(rows, header)


def cmd_run(args: argparse.Namespace) -> int:
    scenario = _scenario(args)
    names = args.controller or list(CONTROLLERS)
    controllers = [get_controller(name) for name in names]
    chain = [args.solver, *_fallback(args.fallback)]
    for name in chain:
        get_solver(name)
    out = Path(args.out or f"results/{scenario.name}")
    runs: dict[str, Run] = {}
    start = time.perf_counter()
    for controller in controllers:
        runs[controller.name] = simulate(
            scenario, controller, solver=args.solver, fallback=_fallback(args.fallback)
        )
    elapsed = time.perf_counter() - start
    with atomic_output(out) as staging:
        results = write_run_folder(
            staging, scenario, runs, solver=args.solver, fallback=_fallback(args.fallback)
        )
    print(f"{scenario.name}: {len(runs)} controller(s) in {elapsed:.2f} s -> {out}/")
    print(summary_table(results))
    return 0


def lab_table(summary: dict[str, dict[str, Any]]) -> str:
    """The solver comparison as a readable table."""
    rows = []
    for name, s in summary.items():
        ttg = s.get("time_to_goal")
        rows.append(
            [
                name,
                s["family"],
                f"{s['median_time'] * 1e3:.3f}",
                f"{s['p95_time'] * 1e3:.3f}",
                f"{s['median_iterations']:.0f}",
                f"{s['median_evaluations']:.0f}",
                f"{s['max_abs_gap']:.1e}",
                f"{s['max_violation']:.1e}",
                str(s["failures"]),
                "yes" if s.get("reached") else "no",
                f"{ttg:.2f}" if ttg is not None else "-",
            ]
        )
    header = [
        "solver",
        "family",
        "median[ms]",
        "p95[ms]",
        "iters",
        "evals",
        "max|gap|",
        "max viol",
        "failed",
        "reached",
        "t_goal[s]",
    ]
    return _table(rows, header)


def cmd_solvers(args: argparse.Namespace) -> int:
    from ..outputs.lab_plots import lab_figures
    from ..solvers import available_solvers
    from ..studies.lab import DEFAULT_LAB_SOLVERS, lab_header, lab_json, lab_rows, run_lab

    scenario = _scenario(args)
    controller = get_controller(args.controller)
    if args.solvers:
        names = [n.strip() for n in args.solvers.split(",") if n.strip()]
        for name in names:
            get_solver(name)
    else:
        names = [n for n in DEFAULT_LAB_SOLVERS if n in available_solvers()]
    out = Path(args.out or f"results/{scenario.name}-solvers")
    start = time.perf_counter()

    def progress(name: str) -> None:
        print(f"  {name} done ({time.perf_counter() - start:.1f} s)", file=sys.stderr, flush=True)

    lab = run_lab(
        scenario,
        controller,
        names,
        sample=None if args.sample <= 0 else args.sample,
        repeats=args.repeats,
        budget=args.budget,
        workers=args.workers,
        progress=progress,
    )
    data = lab_json(lab)
    data["wall_time"] = time.perf_counter() - start
    table = lab_table(data["solvers"])
    with atomic_output(out) as staging:
        write_json(staging / "solvers.json", data)
        for name in lab.studies:
            write_csv(
                staging / "solvers" / f"{name}.csv",
                lab_header(lab),
                ([cell(v) for v in row] for row in lab_rows(lab, name)),
            )
        (staging / "solvers.txt").write_text(table + "\n", encoding="utf-8")
        if not args.no_figures:
            lab_figures(lab, staging / "figures")
    print(
        f"{scenario.name} {controller.name}: {len(names)} solvers, {len(lab.steps)} steps "
        f"re-solved in {data['wall_time']:.1f} s -> {out}/"
    )
    print(table)
    return 0


def _runs(args: argparse.Namespace, names: Sequence[str]) -> tuple[Scenario, dict[str, Run]]:
    """The runs of ``names``: read from a folder written by ``emdm run``, or simulated."""
    from ..outputs.records import read_run

    folder = Path(args.scenario)
    if folder.is_dir():
        if not (folder / "metrics.json").is_file():
            raise UsageError(
                f"{folder}: not a run folder (no metrics.json; write one with emdm run)"
            )
        if args.set:
            raise UsageError("--set applies to scenarios, not to a run folder")
        available = [n for n in names if (folder / "trajectories" / f"{n}.csv").is_file()]
        if not available:
            raise UsageError(f"{folder}: none of {', '.join(names)} was run there")
        runs = {n: read_run(folder, n) for n in available}
        return next(iter(runs.values())).scenario, runs
    scenario = _scenario(args)
    return scenario, {n: simulate(scenario, n) for n in names}


def cmd_plot(args: argparse.Namespace) -> int:
    from ..outputs.plots import run_figures

    names = [get_controller(n).name for n in (args.controller or list(CONTROLLERS))]
    scenario, runs = _runs(args, names)
    out = Path(args.out or f"results/{scenario.name}-figures")
    with atomic_output(out) as staging:
        stems = run_figures(runs, staging)
    print(f"{scenario.name}: {len(stems)} figures (PNG, PDF, SVG) -> {out}/")
    return 0


def cmd_animate(args: argparse.Namespace) -> int:
    from ..outputs.animate import animate
    from ..outputs.plots import GROUPS

    if args.speedup <= 0:
        raise UsageError(f"--speedup must be > 0, got {args.speedup}")
    pairs = [GROUPS[p] for p in args.pair] if args.pair else [GROUPS["UC"], GROUPS["C"]]
    names = list(dict.fromkeys(n for pair in pairs for n in pair))
    scenario, runs = _runs(args, names)
    out = Path(args.out or f"results/{scenario.name}-animations")
    written = []
    with atomic_output(out) as staging:
        for pair in pairs:
            chosen = [runs[n] for n in pair if n in runs]
            if chosen:
                stem = staging / "_vs_".join(r.controller.name for r in chosen)
                written += animate(chosen, stem, speedup=args.speedup, mp4=not args.no_mp4)
    print(f"{scenario.name}: {', '.join(p.name for p in written)} -> {out}/")
    return 0


def cmd_pareto(args: argparse.Namespace) -> int:
    from ..studies.pareto import (
        default_grid,
        pareto_figure,
        pareto_study,
        trade_off_figure,
        weight_grid,
    )

    scenario = _scenario(args)
    controller = get_controller(args.controller)
    if controller.method != "EMDM":
        raise UsageError(f"--controller must be UC-EMDM or C-EMDM, got {controller.name}")
    out = Path(args.out or f"results/{scenario.name}-pareto-{controller.name}")
    data, _ = pareto_study(scenario, controller)
    grid = weight_grid(scenario, controller, default_grid(scenario, args.grid))
    with atomic_output(out) as staging:
        write_json(staging / "pareto.json", data)
        write_json(
            staging / "weight_grid.json",
            {"scenario": scenario.name, "controller": controller.name, "runs": grid},
        )
        pareto_figure(data, staging)
        trade_off_figure(grid, scenario, controller.name, staging)
    print(
        f"{scenario.name} {controller.name}: Pareto fronts at k = "
        f"{', '.join(str(s['k']) for s in data['steps'])} ({len(data['ratios'])} weights each), "
        f"{len(grid)} whole runs -> {out}/"
    )
    return 0


def cmd_report(args: argparse.Namespace) -> int:
    from ..outputs.report import build_report

    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers must be >= 1, got {args.workers}")
    out = Path(args.out or "results/report")
    start = time.perf_counter()

    def progress(message: str) -> None:
        print(f"  {message}", file=sys.stderr, flush=True)

    print(f"emdm report ({'quick' if args.quick else 'full'}) -> {out}/", file=sys.stderr)
    build_report(out, quick=args.quick, workers=args.workers, progress=progress)
    print(f"report written in {time.perf_counter() - start:.1f} s: {out / 'index.html'}")
    return 0


def cmd_bench(args: argparse.Namespace) -> int:
    import json as _json

    from ..studies.bench import bench_table, run_bench

    def progress(message: str) -> None:
        print(f"  {message}", file=sys.stderr, flush=True)

    data = run_bench(quick=args.quick, progress=progress)
    table = bench_table(data)
    if args.dask:
        from ..studies.bench import dask_table, run_dask_bench

        data["dask"] = run_dask_bench(runs=400 if args.quick else 8000, progress=progress)
        table += "\n\n" + dask_table(data["dask"])
    if args.out:
        out = Path(args.out)
        with atomic_output(out) as staging:
            write_json(staging / "bench.json", data)
            (staging / "bench.md").write_text(table + "\n", encoding="utf-8")
    print(_json.dumps(data, indent=2) if args.json else table)
    return 0


def cmd_study(args: argparse.Namespace) -> int:
    from ..studies.montecarlo import (
        BLOCK,
        TIMING,
        Engine,
        parse_weights,
        run_sweep,
        study_json,
        study_table,
        sweep_trade_off,
        workspace_maps,
    )

    if args.runs < 1:
        raise UsageError(f"--runs must be >= 1, got {args.runs}")
    if args.chunk < 1:
        raise UsageError(f"--chunk must be >= 1, got {args.chunk}")
    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers must be >= 1, got {args.workers}")
    if args.engine == "local" and (args.scheduler or args.workers):
        raise UsageError("--scheduler and --workers go with --engine dask")
    overrides = dict(parse_override(text) for text in args.set or [])
    scenarios = []
    for name in args.scenario:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            scenarios.append(load_scenario(name, overrides))
    weights = parse_weights(args.weights) if args.weights else None
    engine = Engine(args.engine, args.scheduler, args.workers)
    out = Path(args.out or f"results/{scenarios[0].name}-study")
    results = run_sweep(
        scenarios,
        weights,
        args.runs,
        args.seed,
        engine,
        chunk_blocks=max(1, -(-args.chunk // BLOCK)),
        keep_runs=args.keep_runs,
    )
    single = len(results) == 1
    with atomic_output(out) as staging:
        tables = []
        for result in results:
            scenario = next(s for s in scenarios if s.name == result["scenario"])
            tag = (
                ""
                if single
                else (
                    f"{result['scenario']}-wE{result['weights']['effort']:g}"
                    f"-wM{result['weights']['manipulability']:g}/"
                )
            )
            folder = staging / tag if tag else staging
            write_json(folder / "study.json", {**study_json(result), "weights": result["weights"]})
            write_json(folder / "timing.json", {k: result[k] for k in TIMING})
            workspace_maps(result, scenario, folder)
            if args.keep_runs:
                np.savez_compressed(folder / "runs.npz", **result["records"])
            tables.append(
                study_table(result) if single else f"[{tag.rstrip('/')}]\n" + study_table(result)
            )
        if not single:
            write_json(
                staging / "sweep.json",
                [
                    {
                        "scenario": r["scenario"],
                        "weights": r["weights"],
                        "controllers": r["controllers"],
                        "manipulability_gain": r["manipulability_gain"],
                    }
                    for r in results
                ],
            )
            sweep_trade_off(results, scenarios, staging)
        (staging / "study.txt").write_text("\n\n".join(tables) + "\n", encoding="utf-8")
    print("\n\n".join(tables))
    print(f"-> {out}/")
    return 0


def cmd_scenario(args: argparse.Namespace) -> int:
    print(_scenario(args).to_toml(), end="")
    return 0


def cmd_list(args: argparse.Namespace) -> int:
    print("controllers: " + ", ".join(CONTROLLERS))
    print("presets:     " + ", ".join(PRESETS))
    print("solvers:")
    for spec in registered_solvers().values():
        state = "installed" if spec.is_available() else f"pip install 'emdm[{spec.extra}]'"
        print(f"  {spec.name:<11} {spec.family:<13} {state:<28} {spec.description}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="emdm",
        description="Optimisation-based velocity control of planar manipulators (EMDM vs IVKC).",
    )
    parser.add_argument("--version", action="version", version=f"emdm {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    run = sub.add_parser(
        "run",
        help="run controllers on a scenario; write metrics.json and CSVs",
        description="Run controllers in closed loop and record every step.",
    )
    _add_scenario_args(run)
    run.add_argument(
        "--controller",
        action="append",
        metavar="NAME",
        help=f"controller to run (repeatable; default all: {', '.join(CONTROLLERS)})",
    )
    run.add_argument(
        "--solver",
        default=DEFAULT_SOLVER,
        metavar="NAME",
        help=f"solver tried first at every step (default {DEFAULT_SOLVER}; see emdm list)",
    )
    run.add_argument(
        "--fallback",
        metavar="A,B",
        help=f"fallback chain when it fails (default {','.join(DEFAULT_FALLBACK)})",
    )
    _add_out(run, "results/<scenario name>")
    run.set_defaults(func=cmd_run)

    lab = sub.add_parser(
        "solvers",
        help="compare solvers on a controller's per-step programs (the solver lab)",
        description="Run the controller with each solver in closed loop, and re-solve the "
        "programs along the exact trajectory with each, against the exact optimum.",
    )
    _add_scenario_args(lab, default="task2")
    lab.add_argument(
        "--controller",
        default="C-EMDM",
        metavar="NAME",
        help="controller whose programs are solved (default C-EMDM)",
    )
    lab.add_argument(
        "--solvers",
        metavar="A,B,...",
        help="solvers to compare (default: every installed one of the standard set)",
    )
    lab.add_argument(
        "--sample",
        type=int,
        default=100,
        metavar="N",
        help="re-solve N evenly spaced steps (0: every step; default 100)",
    )
    lab.add_argument(
        "--repeats",
        type=int,
        default=5,
        metavar="R",
        help="timing repeats per step, median taken (default 5)",
    )
    lab.add_argument(
        "--budget",
        type=int,
        metavar="N",
        help="evaluation budget of the gradient-free methods (default 2000)",
    )
    lab.add_argument(
        "--workers",
        type=int,
        default=2,
        metavar="W",
        help="processes to spread the solvers over (default 2)",
    )
    lab.add_argument("--no-figures", action="store_true", help="skip the figures")
    _add_out(lab, "results/<scenario>-solvers")
    lab.set_defaults(func=cmd_solvers)

    plot = sub.add_parser(
        "plot",
        help="time series and workspace figures of the controllers",
        description="Figures of runs, from a scenario or a folder of emdm run.",
    )
    _add_scenario_args(plot, run_dir=True)
    plot.add_argument(
        "--controller",
        action="append",
        metavar="NAME",
        help="controller to include (repeatable; default all four)",
    )
    _add_out(plot, "results/<scenario>-figures")
    plot.set_defaults(func=cmd_plot)

    anim = sub.add_parser(
        "animate",
        help="GIF/MP4 of the arm with its manipulability ellipse",
        description="Animate controller pairs side by side.",
    )
    _add_scenario_args(anim, run_dir=True)
    anim.add_argument(
        "--pair",
        action="append",
        choices=["UC", "C", "all"],
        help="which controllers side by side (repeatable; default UC and C)",
    )
    anim.add_argument("--speedup", type=float, default=1.0, help="playback speed-up (default 1)")
    anim.add_argument("--no-mp4", action="store_true", help="write the GIF only")
    _add_out(anim, "results/<scenario>-animations")
    anim.set_defaults(func=cmd_animate)

    par = sub.add_parser(
        "pareto",
        help="Pareto fronts of effort against manipulability rate",
        description="Weight sweeps at four steps of a run, and over whole runs.",
    )
    _add_scenario_args(par)
    par.add_argument("--controller", default="UC-EMDM", help="UC-EMDM (default) or C-EMDM")
    par.add_argument(
        "--grid",
        type=int,
        default=13,
        metavar="N",
        help="weight ratios in the whole-run sweep (default 13)",
    )
    _add_out(par, "results/<scenario>-pareto-<controller>")
    par.set_defaults(func=cmd_pareto)

    rep = sub.add_parser(
        "report",
        help="the whole study of the brief: HTML, LaTeX and data",
        description="Run every experiment of the brief and write index.html, "
        "latex/ and the data behind every number.",
    )
    rep.add_argument(
        "--quick", action="store_true", help="a reduced study in about 20 s (demos, tests)"
    )
    rep.add_argument(
        "--workers",
        type=int,
        metavar="W",
        help="processes to spread the work over (default: up to 2)",
    )
    _add_out(rep, "results/report")
    rep.set_defaults(func=cmd_report)

    study = sub.add_parser(
        "study",
        help="Monte-Carlo study over goals and starts (fast path)",
        description="Every controller on the same random reachable goals and "
        "starts: success, time to goal, manipulability gain, workspace maps.",
    )
    _add_scenario_args(study, many=True)
    study.add_argument(
        "--weights",
        metavar="WE:WM,...",
        help="sweep weight pairs, e.g. 0.1:0,0.1:0.5,0.1:5 (one study each)",
    )
    study.add_argument("--runs", type=int, default=1000, help="runs per controller (default 1000)")
    study.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    study.add_argument(
        "--engine",
        choices=["local", "dask"],
        default="local",
        help="local (this process, every core) or dask (default local)",
    )
    study.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="a running Dask scheduler, e.g. tcp://10.0.0.5:8786 (dask engine)",
    )
    study.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help="workers of the LocalCluster started when no scheduler is given",
    )
    study.add_argument(
        "--chunk",
        type=int,
        default=2048,
        metavar="RUNS",
        help="runs per task, rounded up to whole blocks of 256 (default 2048)",
    )
    study.add_argument(
        "--keep-runs",
        action="store_true",
        help="also keep every run's outcome (runs.npz); memory grows with --runs",
    )
    _add_out(study, "results/<scenario>-study")
    study.set_defaults(func=cmd_study)

    bench = sub.add_parser(
        "bench",
        help="per-step cost against the standard stack; batch speed",
        description="Benchmark the reference and fast paths against numpy + "
        "qpsolvers (daqp, quadprog) in one process; medians over repeats.",
    )
    bench.add_argument("--json", action="store_true", help="print JSON instead of tables")
    bench.add_argument("--quick", action="store_true", help="one repeat, a small batch (tests)")
    bench.add_argument(
        "--dask",
        action="store_true",
        help="also measure studies on 1- and 2-worker Dask LocalClusters",
    )
    bench.add_argument("--out", metavar="DIR", help="also write bench.json and bench.md there")
    bench.set_defaults(func=cmd_bench)

    show = sub.add_parser("scenario", help="print a scenario as validated TOML (a starting point)")
    _add_scenario_args(show)
    _add_out(show, "none: prints to the terminal")
    show.set_defaults(func=cmd_scenario)

    lst = sub.add_parser("list", help="list controllers, presets and solvers")
    _add_out(lst, "none: prints to the terminal")
    lst.set_defaults(func=cmd_list)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``emdm`` command; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except NoSolution as exc:
        print(f"emdm: run stopped: {exc}", file=sys.stderr)
        return 1
    except EmdmError as exc:
        print(f"emdm: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"emdm: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("emdm: interrupted; nothing was written", file=sys.stderr)
        return 130
    except Exception as exc:  # an internal error: one line, the traceback on request
        if os.environ.get("EMDM_DEBUG"):
            raise
        print(
            f"emdm: internal error: {type(exc).__name__}: {exc} (EMDM_DEBUG=1 shows the traceback)",
            file=sys.stderr,
        )
        return 1
