"""The ``emdm`` command line.

Bad input: one line on stderr and exit status 2, nothing written. ``--out`` is checked before any
work; results are staged and replace ``--out`` as a whole only when the command succeeds
(:func:`emdm.outputs.records.atomic_output`). Failures and signals go through one boundary
(:mod:`emdm.cli.boundary`).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import re
import shutil
import signal
import sys
import time
import warnings
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__
from ..core.controllers import BASELINES, CONTROLLERS, Name, get_controller
from ..core.loading import PRESETS, load_scenario, parse_override
from ..core.scenario import Scenario
from ..core.terms import TermKind
from ..errors import EmdmError, NoSolution
from ..outputs.records import (
    atomic_output,
    cell,
    check_out,
    write_csv,
    write_json,
    write_run_folder,
)
from ..outputs.report.config import LONGEST_NAME, LONGEST_TITLE
from ..sim.loop import Run, simulate
from ..solvers import DEFAULT_FALLBACK, DEFAULT_SOLVER, registered_solvers
from .args import (
    Parser,
    add_controllers,
    add_out,
    add_quick,
    add_scenario,
    add_workers,
    integer,
    names,
    positive,
    scenario_name,
    text,
)
from .boundary import HANDLED, RunStopped, run_command
from .progress import Progress, say
from .tables import lab_table, summary_table


class UsageError(EmdmError):
    """A combination of command-line arguments that is wrong."""


# ----------------------------------------------------------------------------------- helpers
def safe(text: str) -> str:
    """``text`` as one harmless path component (a scenario name in a default ``--out``)."""
    cleaned = re.sub(r"[^\w.+=-]+", "_", text).strip("._")
    return cleaned[:100] or "scenario"


def _unique(items: Iterable[str] | None) -> list[str]:
    return list(dict.fromkeys(items or []))


def _overrides(args: argparse.Namespace) -> dict[str, Any]:
    return dict(parse_override(text) for text in args.set or [])


_pending: list[str] = []
"""The scenarios' warnings, said once the command's up-front checks have passed (a command
refused before any work says one line, not a warning and then its error)."""


def _load(name: str, overrides: dict[str, Any]) -> Scenario:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scenario = load_scenario(name, overrides)
    _pending.extend(f"emdm: warning: {scenario.source}: {m}" for m in scenario.warnings)
    return scenario


def _say_warnings() -> None:
    """Print the pending scenario warnings (once)."""
    for line in _pending:
        print(line, file=sys.stderr)
    _pending.clear()


def _scenario(args: argparse.Namespace) -> Scenario:
    return _load(args.scenario, _overrides(args))


def _out(args: argparse.Namespace, default: str, inputs: Iterable[str | Path] = ()) -> Path:
    """``--out`` (or ``results/<default>``), checked before any work; it must not hold one of
    the ``inputs`` (a run folder, a scenario file), which replacing it would delete."""
    out = Path(args.out) if args.out else Path("results") / default
    check_out(out)
    where = Path(os.path.realpath(out))
    for given in inputs:
        path = Path(os.path.realpath(given))
        if path == where or where in path.parents:
            raise UsageError(
                f"--out {out} holds the input {given}, which replacing it would delete"
            )
    _say_warnings()  # the folder is fine: the work begins
    return out


def _inputs(args: argparse.Namespace) -> list[str]:
    """The scenario arguments that are files or folders (not presets)."""
    given = args.scenario if isinstance(args.scenario, list) else [args.scenario]
    return [name for name in given if os.path.lexists(name)]


def _simulate(scenario: Scenario, name: str, **options: Any) -> Run:
    try:
        return simulate(scenario, name, **options)
    except NoSolution as exc:
        raise RunStopped(f"run stopped: {_stopped(name, exc)}") from None


def _stopped(name: str, exc: NoSolution) -> str:
    """``"C-EMDM at step 3: <why>"``."""
    text = str(exc)
    step = getattr(exc, "step", None)
    found = re.match(r"step (\d+): ", text)
    if found:
        step = int(found.group(1)) if step is None else step
        text = text[found.end() :]
    return f"{name} at step {step}: {text}" if step is not None else f"{name}: {text}"


# -------------------------------------------------------------------------------------- run
def _chain(args: argparse.Namespace) -> tuple[str, list[str]]:
    """The solver tried first and the fallback chain (``--solver`` repeated, then ``--fallback``)."""
    first = _unique(args.solver) or [DEFAULT_SOLVER]
    rest = list(DEFAULT_FALLBACK) if args.fallback is None else args.fallback
    chain = _unique([*first, *rest])
    return chain[0], chain[1:]


def cmd_run(args: argparse.Namespace) -> int:
    scenario = _scenario(args)
    controllers = _unique(args.controller) or list(CONTROLLERS)
    solver, fallback = _chain(args)
    out = _out(args, safe(scenario.name), _inputs(args))
    runs: dict[str, Run] = {}
    stopped: dict[str, NoSolution] = {}
    start = time.perf_counter()
    with Progress(f"run {scenario.name}", len(controllers), "controller") as bar:
        for name in controllers:
            bar.note(name)
            try:
                runs[name] = simulate(scenario, name, solver=solver, fallback=fallback)
            except NoSolution as exc:
                stopped[name] = exc
                partial = getattr(exc, "run", None)
                if isinstance(partial, Run):
                    runs[name] = partial
            bar.step()
    elapsed = time.perf_counter() - start
    finished = [name for name in runs if name not in stopped]
    if runs:
        details = {
            name: {"step": getattr(exc, "step", None), "reason": str(exc)}
            for name, exc in stopped.items()
        }
        with atomic_output(out, command="emdm run") as staging:
            results = write_run_folder(
                staging, scenario, runs, solver=solver, fallback=fallback, stopped=details
            )
            # printed before the swap: a standard output that fails keeps the earlier results
            print(f"{scenario.name}: {len(runs)} controller(s) in {elapsed:.2f} s -> {out}/")
            print(summary_table(results, "m,rad" if scenario.nt == 6 else "m"))
            if scenario.obstacles or scenario.planes.count:  # how each run fared
                from ..outputs.report.explain import (
                    obstacle_sentence,
                    obstacles,
                    plane_sentence,
                    planes,
                )

                for name, run in runs.items():
                    for line in (
                        obstacle_sentence(name, obstacles(run)),
                        plane_sentence(name, planes(run)),
                    ):
                        if line:
                            print(line)
    if stopped:
        first, *others = stopped.items()
        message = f"run stopped: {_stopped(*first)}"
        if others:
            message += "; also stopped: " + ", ".join(
                _stopped(n, e).split(":")[0] for n, e in others
            )
        if runs:
            kept = f"{', '.join(finished)} finished" if finished else "none finished"
            partial = [n for n in stopped if n in runs]
            message += f"; {kept}; written to {out}/"
            if partial:
                message += f" with the partial run{'s' if len(partial) > 1 else ''} of {', '.join(partial)}"
        else:
            message += "; nothing was written"
        raise RunStopped(message)
    return 0


# ---------------------------------------------------------------------------------- solvers
def cmd_solvers(args: argparse.Namespace) -> int:
    from ..outputs.lab_plots import lab_figures
    from ..solvers import available_solvers
    from ..studies.lab import DEFAULT_LAB_SOLVERS, lab_header, lab_json, lab_rows, run_lab

    scenario = _scenario(args)
    controllers = _unique(args.controller) or [Name.C_EMDM]
    solvers = _unique(args.solver) or [n for n in DEFAULT_LAB_SOLVERS if n in available_solvers()]
    out = _out(args, f"{safe(scenario.name)}-solvers", _inputs(args))
    start = time.perf_counter()
    labs = {}
    with Progress(f"solvers {scenario.name}", len(solvers) * len(controllers), "solver") as bar:
        for controller in controllers:
            bar.note(f"{controller}: reference run and programs")
            labs[controller] = run_lab(
                scenario,
                controller,
                solvers,
                sample=None if args.sample == 0 else args.sample,
                repeats=args.repeats,
                budget=args.budget,
                workers=args.workers or 2,
                progress=lambda name, c=controller: bar.step(note=f"{c}: {name} done"),
            )
    wall = time.perf_counter() - start
    tables = {}
    with atomic_output(out, command="emdm solvers") as staging:
        for controller, lab in labs.items():
            folder = staging if len(labs) == 1 else staging / controller
            data = lab_json(lab)
            data["wall_time"] = wall
            tables[controller] = lab_table(data["solvers"])
            write_json(folder / "solvers.json", data)
            for name in lab.studies:
                write_csv(
                    folder / "solvers" / f"{name}.csv",
                    lab_header(lab),
                    ([cell(v) for v in row] for row in lab_rows(lab, name)),
                )
            (folder / "solvers.txt").write_text(tables[controller] + "\n", encoding="utf-8")
            if not args.no_figures:
                lab_figures(lab, folder / "figures")
        for controller, lab in labs.items():
            print(
                f"{scenario.name} {controller}: {len(solvers)} solvers, {len(lab.steps)} steps "
                f"re-solved in {wall:.1f} s -> {out}/"
            )
            print(tables[controller])
    return 0


# ------------------------------------------------------------------------ plot and animate
def _source(args: argparse.Namespace) -> tuple[Scenario, Path | None]:
    """The scenario, and the run folder when the argument is one (read cheaply: metrics.json)."""
    from ..outputs.records import read_scenario

    folder = Path(args.scenario)
    if not folder.is_dir():
        return _scenario(args), None
    if args.set:
        raise UsageError("--set applies to scenarios, not to a run folder")
    return read_scenario(folder), folder


def _held(folder: Path) -> list[str]:
    """The controllers whose runs ``folder`` holds, in the order of ``emdm list``."""
    known = [*CONTROLLERS, *BASELINES]
    return [n for n in known if (folder / "trajectories" / f"{n}.csv").is_file()]


def _runs(
    scenario: Scenario, folder: Path | None, controllers: Sequence[str], bar: Progress
) -> dict[str, Run]:
    """The runs of ``controllers``: read from ``folder`` (those it holds), or simulated."""
    from ..outputs.records import read_run

    runs: dict[str, Run] = {}
    if folder is not None:
        available = [n for n in controllers if (folder / "trajectories" / f"{n}.csv").is_file()]
        if not available:
            held = _held(folder)
            hint = f" (it holds {', '.join(held)}: pass --controller)" if held else ""
            raise UsageError(f"{folder}: none of {', '.join(controllers)} was run there{hint}")
        for name in available:
            bar.note(f"reading {name}")
            runs[name] = read_run(folder, name)
        return runs
    for name in controllers:
        bar.note(f"simulating {name}")
        runs[name] = _simulate(scenario, name)
    return runs


def cmd_plot(args: argparse.Namespace) -> int:
    from ..outputs.plots import run_figures

    scenario, folder = _source(args)
    default = _held(folder) if folder is not None else list(CONTROLLERS)
    controllers = _unique(args.controller) or default or list(CONTROLLERS)
    out = _out(args, f"{safe(scenario.name)}-figures", _inputs(args))
    with Progress(f"plot {scenario.name}") as bar:
        runs = _runs(scenario, folder, controllers, bar)
        bar.note("drawing the figures")
        with atomic_output(out, command="emdm plot") as staging:
            stems = run_figures(runs, staging)
            print(f"{scenario.name}: {len(stems)} figures (PNG, PDF, SVG) -> {out}/")
    return 0


def _check_mp4() -> None:
    """MP4 needs ffmpeg (the imageio-ffmpeg wheel): say so before any work."""
    try:
        import imageio_ffmpeg
    except ImportError:
        raise EmdmError(
            "animate: MP4 needs ffmpeg: pip install 'emdm[video]', or pass --no-mp4"
        ) from None
    try:
        exe = imageio_ffmpeg.get_ffmpeg_exe()
    except Exception as exc:
        raise EmdmError(
            f"animate: ffmpeg cannot be found ({exc}); pip install 'emdm[video]', or pass --no-mp4"
        ) from None
    if not (os.path.isfile(exe) and os.access(exe, os.X_OK)) and shutil.which(exe) is None:
        raise EmdmError(
            f"animate: ffmpeg cannot be found ({exe} is not a program); pip install "
            "'emdm[video]', or pass --no-mp4"
        )


def cmd_animate(args: argparse.Namespace) -> int:
    from ..outputs.animate import animate, frame_schedule
    from ..outputs.plots import GROUPS

    if args.controller and args.pair:
        raise UsageError("give --controller or --pair, not both")
    if args.controller:
        groups = [tuple(_unique(args.controller))]
    else:
        groups = [GROUPS[p] for p in _unique(args.pair or ["UC", "C"])]
    scenario, folder = _source(args)
    try:
        frame_schedule(1, scenario.motion.dt, args.speedup, 20.0)
    except ValueError as exc:
        why = (
            str(exc)
            if "GIF frame" in str(exc)
            else f"no frame duration in whole centiseconds fits dt = {scenario.motion.dt:g} s "
            "at that speed-up; try 0.5, 1, 2 or 5"
        )
        raise UsageError(f"--speedup {args.speedup:g}: {why}") from None
    if not args.no_mp4:
        _check_mp4()
    out = _out(args, f"{safe(scenario.name)}-animations", _inputs(args))
    controllers = _unique(name for group in groups for name in group)
    written: list[Path] = []
    with Progress(f"animate {scenario.name}", len(groups), "animation") as bar:
        runs = _runs(scenario, folder, controllers, bar)
        with atomic_output(out, command="emdm animate") as staging:
            for group in groups:
                chosen = [runs[n] for n in group if n in runs]
                if chosen:
                    bar.note(" vs ".join(r.controller.name for r in chosen))
                    stem = staging / "_vs_".join(r.controller.name for r in chosen)
                    try:
                        written += animate(chosen, stem, speedup=args.speedup, mp4=not args.no_mp4)
                    except (BrokenPipeError, RuntimeError) as exc:  # from ffmpeg
                        reason = str(exc).strip().splitlines()[-1] if str(exc).strip() else ""
                        raise EmdmError(
                            f"animate: ffmpeg failed on {stem.name}.mp4 "
                            f"({reason or type(exc).__name__}); pass --no-mp4 for the GIF only"
                        ) from None
                bar.step()
            print(f"{scenario.name}: {', '.join(p.name for p in written)} -> {out}/")
    return 0


# ----------------------------------------------------------------------------------- pareto
def cmd_pareto(args: argparse.Namespace) -> int:
    from ..outputs.pareto_plots import pareto_figure, trade_off_figure
    from ..studies.pareto import default_grid, pareto_study, weight_grid

    controllers = _unique(args.controller) or [Name.UC_EMDM]
    for name in controllers:
        if not get_controller(name).has(TermKind.MANIPULABILITY):
            raise UsageError(
                f"--controller must weigh manipulability (UC-EMDM, C-EMDM, PARK, MMC), got {name}"
            )
    scenario = _scenario(args)
    tag = controllers[0] if len(controllers) == 1 else "EMDM"
    out = _out(args, f"{safe(scenario.name)}-pareto-{tag}", _inputs(args))
    grid = default_grid(scenario, args.grid)
    results = {}
    with Progress(f"pareto {scenario.name}", len(controllers) * (1 + len(grid)), "run") as bar:
        for name in controllers:
            bar.note(f"{name}: fronts along the run")
            try:
                data, _ = pareto_study(scenario, name)
            except NoSolution as exc:
                raise RunStopped(f"run stopped: {_stopped(name, exc)}") from None
            bar.step()
            rows = []
            for w_e, w_m in grid:
                bar.note(f"{name}: whole run at w_E={w_e:g}, w_M={w_m:g}")
                rows += weight_grid(scenario, name, [(w_e, w_m)])
                bar.step()
            results[name] = (data, rows)
    with atomic_output(out, command="emdm pareto") as staging:
        for name, (data, rows) in results.items():
            folder = staging if len(results) == 1 else staging / name
            write_json(folder / "pareto.json", data)
            write_json(
                folder / "weight_grid.json",
                {"scenario": scenario.name, "controller": name, "runs": rows},
            )
            pareto_figure(data, folder)
            trade_off_figure(rows, scenario, name, folder)
        for name, (data, rows) in results.items():
            print(
                f"{scenario.name} {name}: Pareto fronts at k = "
                f"{', '.join(str(s['k']) for s in data['steps'])} ({len(data['ratios'])} "
                f"weights each), {len(rows)} whole runs -> {out}/"
            )
    return 0


# ----------------------------------------------------------------------------------- report
def cmd_report(args: argparse.Namespace) -> int:
    from ..outputs.report import build_report
    from ..outputs.report.config import read_byline

    names = read_byline(args.config) if args.config else {}
    out = _out(args, "report")
    start = time.perf_counter()
    with Progress(f"report ({'quick' if args.quick else 'full'})", unit="part") as bar:
        prov = build_report(
            out,
            quick=args.quick,
            workers=args.workers,
            progress=lambda m: bar.step(note=m),
            authors=args.author or names.get("authors", ()),
            title=args.title if args.title is not None else names.get("title"),
        )
    if prov.get("compiled", {}).get("hint"):
        print(prov["compiled"]["hint"], file=sys.stderr)
    print(f"report written in {time.perf_counter() - start:.1f} s: {out / 'index.html'}")
    return 0


# ------------------------------------------------------------------------------------ bench
def cmd_bench(args: argparse.Namespace) -> int:
    import json as _json

    from ..studies.bench import bench_table, run_bench

    out = Path(args.out) if args.out else None
    if out is not None:
        check_out(out)
    with Progress("bench", unit="part") as bar:
        data = run_bench(quick=args.quick, progress=lambda m: bar.step(note=m))
        table = bench_table(data)
        if args.dask:
            from ..studies.bench import dask_table, run_dask_bench

            data["dask"] = run_dask_bench(
                runs=400 if args.quick else 8000, progress=lambda m: bar.step(note=m)
            )
            table += "\n\n" + dask_table(data["dask"])
    text = _json.dumps(data, indent=2) if args.json else table
    if out is not None:
        with atomic_output(out, command="emdm bench") as staging:
            write_json(staging / "bench.json", data)
            (staging / "bench.md").write_text(table + "\n", encoding="utf-8")
            print(text)  # before the swap: a failing standard output keeps earlier results
    else:
        print(text)
    return 0


# -------------------------------------------------------------------------------------- mmc
def cmd_mmc(args: argparse.Namespace) -> int:
    import json as _json

    from ..studies.mmc import mmc_table, run_mmc_benchmark

    out = Path(args.out) if args.out else None
    if out is not None:
        check_out(out)
    arms = _unique(args.arm) or ["panda", "ur5"]
    if args.protocol == "paper":
        from ..studies.mmc_paper import PROTOCOLS, paper_table, run_paper_protocol

        other = [a for a in arms if a not in PROTOCOLS]
        if other:
            raise UsageError(
                f"--protocol paper is the authors' experiment on panda and ur5; for "
                f"{', '.join(other)} use --protocol emdm"
            )
        with Progress("mmc (the authors' protocol)", unit="arm") as bar:
            data = run_paper_protocol(
                arms=arms, trials=args.trials, seed=args.seed, progress=lambda m: bar.step(note=m)
            )
        table = paper_table(data)
    else:
        with Progress("mmc", unit="run set") as bar:
            data = run_mmc_benchmark(
                arms=arms, trials=args.trials, seed=args.seed, progress=lambda m: bar.step(note=m)
            )
        table = mmc_table(data)
    text = _json.dumps(data, indent=2) if args.json else table
    if out is not None:
        with atomic_output(out, command="emdm mmc") as staging:
            write_json(staging / "mmc.json", data)
            (staging / "mmc.md").write_text(table + "\n", encoding="utf-8")
            print(text)  # before the swap: a failing standard output keeps earlier results
    else:
        print(text)
    return 0


# ------------------------------------------------------------------------------------ study
def _number(value: float) -> str:
    """``value`` as short as it reads back exactly (``5``, ``0.1``, ``0.1000000001``)."""
    short = f"{value:g}"
    return short if float(short) == value else repr(value)


def _study_tags(
    scenarios: Sequence[Scenario], weights: Sequence[tuple[float, float]] | None
) -> dict[tuple[str, float, float], str]:
    """The folder of each study of a sweep, ``<scenario>-wE<w_E>-wM<w_M>``, keyed by
    ``(scenario name, w_E, w_M)``: every weight written so that it reads back exactly; two
    studies that would share a folder are refused before any work."""
    tags: dict[tuple[str, float, float], str] = {}
    seen: dict[str, str] = {}
    for sc in scenarios:
        pairs = weights or [(sc.weights.effort, sc.weights.manipulability)]
        for w_e, w_m in pairs:
            tag = safe(f"{sc.name}-wE{_number(w_e)}-wM{_number(w_m)}")
            what = f"{sc.source} at w_E = {_number(w_e)}, w_M = {_number(w_m)}"
            if tag in seen:
                raise UsageError(
                    f"study: {seen[tag]} and {what} would share the folder {tag}: give the "
                    "scenarios different names (name = ...) or drop the repeated weights"
                )
            seen[tag] = what
            tags[sc.name, float(w_e), float(w_m)] = tag
    return tags


WORKER_BYTES = 250e6
"""About the memory of one Dask worker process with emdm loaded (235 MB measured)."""


def _study_fits(args: argparse.Namespace, scenarios: Sequence[Scenario], studies: int) -> None:
    """Refuse, before any work, a local Dask cluster or kept runs that would take more than
    half of this machine's memory, with the estimate and the largest value that fits."""
    from ..core.checks import memory_available
    from ..sim.metrics import OUTCOMES

    have = memory_available()
    if not have:
        return
    if args.engine == "dask" and args.workers and not args.scheduler:
        need = args.workers * WORKER_BYTES
        if need > have / 2:
            fits = max(1, int(have / 2 // WORKER_BYTES))
            raise UsageError(
                f"--workers {args.workers}: a local Dask cluster of {args.workers} workers needs "
                f"about {need / 1e9:.3g} GB (about {WORKER_BYTES / 1e9:.2g} GB each), more than "
                f"half of this machine's {have / 1e9:.3g} GB: use at most {fits}"
            )
    if args.keep_runs:
        width = max(sc.n + sc.nt + 2 * len(CONTROLLERS) * len(OUTCOMES) for sc in scenarios)
        need = 2 * 8 * width * args.runs * studies  # kept, and copied once when written
        if need > have / 2:
            fits = max(1, int(have / 2 // (16 * width * studies)))
            raise UsageError(
                f"--keep-runs with --runs {args.runs}: keeping every run needs about "
                f"{need / 1e9:.3g} GB, more than half of this machine's {have / 1e9:.3g} GB: use "
                f"at most --runs {fits}, or leave out --keep-runs"
            )


def _duration(seconds: float) -> str:
    """A duration as a person reads it: 40 s, 12 min, 3.4 h, 2.1 days."""
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    if seconds < 172800:
        return f"{seconds / 3600:.2g} h"
    return f"{seconds / 86400:.2g} days"


def _study_time(
    args: argparse.Namespace,
    scenarios: Sequence[Scenario],
    weights: Sequence[tuple[float, float]] | None,
) -> float | None:
    """The study's time on this machine, from a pilot block of each study (None: too small to
    need one, or a remote scheduler whose cores are unknown); refused, before the work, beyond
    ``--max-hours``, with the estimate and the largest ``--runs`` that fits."""
    from ..studies.montecarlo import PILOT_FROM, seconds_per_run, sweep_scenarios

    if args.runs < PILOT_FROM or args.scheduler:
        return None
    per_run = sum(seconds_per_run(sc, args.seed) for sc in sweep_scenarios(scenarios, weights))
    if args.engine == "dask":  # single-threaded workers, against a pilot on every thread
        import numba

        per_run *= numba.get_num_threads() / (args.workers or 2)
    need = float(per_run * args.runs)
    limit = args.max_hours * 3600.0
    if need > limit:
        fits = max(1, int(limit / per_run))
        raise UsageError(
            f"--runs {args.runs}: the study would take about {_duration(need)} here (a pilot "
            f"block: {per_run * 1e3:.3g} ms per run of every controller), more than --max-hours "
            f"{args.max_hours:g}: use at most --runs {fits}, or raise --max-hours"
        )
    return need


def cmd_study(args: argparse.Namespace) -> int:
    from ..outputs.study_plots import sweep_trade_off, workspace_maps
    from ..studies.montecarlo import (
        BLOCK,
        TIMING,
        Engine,
        parse_weights,
        run_sweep,
        study_json,
        study_table,
    )

    if args.engine == "local" and (args.scheduler or args.workers):
        raise UsageError("--scheduler and --workers go with --engine dask")
    if args.scheduler and not re.fullmatch(
        r"(tcp|tls|inproc|ucx|ws|wss)://\S+:\d+|[^\s/]+:\d+", args.scheduler
    ):
        raise UsageError(
            f"--scheduler {args.scheduler[:80]!r}: expected a Dask scheduler address such as "
            "tcp://10.0.0.5:8786"
        )
    overrides = _overrides(args)
    scenarios = [_load(name, overrides) for name in _unique(args.scenario)]
    weights = parse_weights(args.weights) if args.weights else None
    engine = Engine(args.engine, args.scheduler, args.workers)
    out = _out(args, f"{safe(scenarios[0].name)}-study", _inputs(args))
    studies = len(scenarios) * (len(weights) if weights else 1)
    tags = _study_tags(scenarios, weights) if studies > 1 else {}
    _study_fits(args, scenarios, studies)
    need = _study_time(args, scenarios, weights)
    about = f", about {_duration(need)}" if need is not None else ""
    with Progress(f"study ({studies} × {args.runs} runs{about})", unit="chunk") as bar:

        def chunk_done(done: int, total: int) -> None:
            if bar.bar.total != total * studies:
                bar.bar.total = total * studies
            bar.step()

        results = run_sweep(
            scenarios,
            weights,
            args.runs,
            args.seed,
            engine,
            chunk_blocks=max(1, -(-args.chunk // BLOCK)),
            keep_runs=args.keep_runs,
            progress=chunk_done,
        )
    single = len(results) == 1
    tables = []
    with atomic_output(out, command="emdm study") as staging:
        for result in results:
            scenario = next(s for s in scenarios if s.name == result["scenario"])
            w = result["weights"]
            tag = "" if single else tags[result["scenario"], w["effort"], w["manipulability"]]
            folder = staging / tag if tag else staging
            write_json(folder / "study.json", {**study_json(result), "weights": result["weights"]})
            write_json(folder / "timing.json", {k: result[k] for k in TIMING})
            workspace_maps(result, scenario, folder)
            if args.keep_runs:
                np.savez_compressed(folder / "runs.npz", **result["records"])
            tables.append(study_table(result) if single else f"[{tag}]\n" + study_table(result))
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


# ------------------------------------------------------------------- scenario, play, list
def cmd_scenario(args: argparse.Namespace) -> int:
    scenario = _scenario(args)
    _say_warnings()
    print(scenario.to_toml(), end="")
    return 0


def cmd_play(args: argparse.Namespace) -> int:
    from ..play import serve  # planar: the Bokeh page; spatial: the 3-D viser page

    scenario = _scenario(args)
    _say_warnings()
    return serve(scenario, port=args.port, open_browser=not args.no_browser)


def cmd_list(args: argparse.Namespace) -> int:
    print("controllers: " + ", ".join(CONTROLLERS))
    print("baselines (manipulability benchmark; NEO: MMC with obstacles): " + ", ".join(BASELINES))
    print("presets:     " + ", ".join(PRESETS))
    print("solvers:")
    for spec in registered_solvers().values():
        state = "installed" if spec.is_available() else f"pip install 'emdm[{spec.extra}]'"
        print(f"  {spec.name:<11} {spec.family:<13} {state:<28} {spec.description}")
    return 0


# ----------------------------------------------------------------------------------- parser
def _fallback(text: str) -> list[str]:
    """``--fallback`` names, or ``none``."""
    if text.strip().lower() == "none":
        return []
    return names("solver")(text)


def _command(sub: Any, name: str, summary: str, description: str) -> argparse.ArgumentParser:
    parser: argparse.ArgumentParser = sub.add_parser(name, help=summary, description=description)
    return parser


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="emdm",
        description="Optimisation-based velocity control of planar manipulators (EMDM vs IVKC).",
    )
    parser.add_argument("--version", action="version", version=f"emdm {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    run = _command(
        sub,
        "run",
        "run controllers on a scenario; write metrics.json and CSVs",
        "Run controllers in closed loop and record every step: metrics.json, "
        "trajectories/<controller>.csv and diagnostics/<controller>.csv.",
    )
    add_scenario(run)
    add_controllers(run, "controller to run")
    run.add_argument(
        "--solver",
        action="extend",
        type=names("solver"),
        metavar="NAME",
        help=f"solver tried first at every step (default {DEFAULT_SOLVER}; repeatable: "
        "tried in order; see emdm list)",
    )
    run.add_argument(
        "--fallback",
        action="extend",
        type=_fallback,
        metavar="NAME",
        help=f"solver tried when those fail (repeatable; default {','.join(DEFAULT_FALLBACK)}; "
        "none: no fallback)",
    )
    add_out(run, "results/<scenario>")
    run.set_defaults(func=cmd_run)

    lab = _command(
        sub,
        "solvers",
        "compare solvers on a controller's per-step programs (the solver lab)",
        "Run the controller with each solver in closed loop, and re-solve the programs along "
        "the exact trajectory with each, against the exact optimum.",
    )
    add_scenario(lab, default="task2")
    add_controllers(lab, "controller whose programs are solved", Name.C_EMDM)
    lab.add_argument(
        "--solver",
        action="extend",
        type=names("solver"),
        metavar="NAME",
        help="solver to compare (repeatable; default every installed one of the standard set)",
    )
    lab.add_argument(
        "--solvers", dest="solver", action="extend", type=names("solver"), help=argparse.SUPPRESS
    )
    lab.add_argument(
        "--sample",
        type=integer(0),
        default=100,
        metavar="N",
        help="re-solve N evenly spaced steps and the representative ones (0: every step; default 100)",
    )
    lab.add_argument(
        "--repeats",
        type=integer(1, 1000),
        default=5,
        metavar="N",
        help="timing repeats per step, median taken (default 5)",
    )
    lab.add_argument(
        "--budget",
        type=integer(1),
        metavar="N",
        help="evaluation budget of the gradient-free methods (default 2000)",
    )
    add_workers(lab, "2")
    lab.add_argument("--no-figures", action="store_true", help="skip the figures")
    add_out(lab, "results/<scenario>-solvers")
    lab.set_defaults(func=cmd_solvers)

    plot = _command(
        sub,
        "plot",
        "time series and workspace figures of the controllers",
        "Figures of runs (PNG, PDF, SVG), from a scenario or from a folder written by emdm run.",
    )
    add_scenario(plot, run_dir=True)
    add_controllers(plot, "controller to include")
    add_out(plot, "results/<scenario>-figures")
    plot.set_defaults(func=cmd_plot)

    anim = _command(
        sub,
        "animate",
        "GIF/MP4 of the arm with its manipulability ellipse",
        "Animate controllers side by side (GIF, and MP4 with ffmpeg), from a scenario or from "
        "a folder written by emdm run.",
    )
    add_scenario(anim, run_dir=True)
    add_controllers(
        anim, "controller drawn side by side with the others given", "the UC and C pairs"
    )
    anim.add_argument(
        "--pair",
        action="append",
        choices=["UC", "C", "all"],
        help="a standard group side by side: UC-IVKC and UC-EMDM, C-IVKC and C-EMDM, or all "
        "four (repeatable; default UC and C)",
    )
    anim.add_argument(
        "--speedup",
        type=positive(100.0),
        default=1.0,
        metavar="X",
        help="playback speed-up, in (0, 100] (default 1)",
    )
    anim.add_argument("--no-mp4", action="store_true", help="write the GIF only")
    add_out(anim, "results/<scenario>-animations")
    anim.set_defaults(func=cmd_animate)

    par = _command(
        sub,
        "pareto",
        "Pareto fronts of effort against manipulability rate",
        "Weight sweeps at four steps of a run, and over whole runs.",
    )
    add_scenario(par)
    add_controllers(
        par, "a controller that weighs manipulability (UC-EMDM, C-EMDM, PARK, MMC)", "UC-EMDM"
    )
    par.add_argument(
        "--grid",
        type=integer(2, 1000),
        default=13,
        metavar="N",
        help="weight ratios in the whole-run sweep (default 13)",
    )
    add_out(par, "results/<scenario>-pareto-<controller>")
    par.set_defaults(func=cmd_pareto)

    rep = _command(
        sub,
        "report",
        "the whole study of the brief: paper, pitch, HTML and data",
        "Run every experiment of the brief and write index.html, paper/ (paper and pitch) and "
        "the data behind every number.",
    )
    add_quick(rep, "a reduced study in about 20 s (demos, tests)")
    add_workers(rep, "up to 2")
    rep.add_argument(
        "--author",
        action="append",
        type=text("an author's name", LONGEST_NAME),
        metavar="NAME",
        help="a name on the paper, the pitch and the page (repeatable, in order)",
    )
    rep.add_argument(
        "--title",
        type=text("the title", LONGEST_TITLE),
        metavar="TEXT",
        help="the paper's and the pitch's title (default: the study's own)",
    )
    rep.add_argument(
        "--config",
        metavar="FILE",
        help='a TOML file with authors = ["...", ...] and title = "..." (the options win)',
    )
    add_out(rep, "results/report")
    rep.set_defaults(func=cmd_report)

    study = _command(
        sub,
        "study",
        "Monte-Carlo study over goals and starts (fast path)",
        "Every controller on the same random reachable goals and starts: success, time to "
        "goal, manipulability gain, workspace maps.",
    )
    add_scenario(study, many=True)
    study.add_argument(
        "--weights",
        metavar="WE:WM,...",
        help="sweep weight pairs, e.g. 0.1:0,0.1:0.5,0.1:5 (one study each)",
    )
    study.add_argument(
        "--runs",
        type=integer(1, 10**9),
        default=1000,
        metavar="N",
        help="runs per controller (default 1000)",
    )
    study.add_argument(
        "--seed",
        type=integer(0, 2**64 - 1),
        default=0,
        metavar="S",
        help="random seed, >= 0 (default 0)",
    )
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
    add_workers(study, "2; the LocalCluster started by --engine dask without --scheduler")
    study.add_argument(
        "--chunk",
        type=integer(1, 10**7),
        default=2048,
        metavar="N",
        help="runs per task, rounded up to whole blocks of 256 (default 2048)",
    )
    study.add_argument(
        "--keep-runs",
        action="store_true",
        help="also keep every run's outcome (runs.npz); memory grows with --runs",
    )
    study.add_argument(
        "--max-hours",
        type=positive(10**4),
        default=1.0,
        metavar="H",
        help="refuse, before any work, a study estimated (from a pilot block, from 16,384 runs) "
        "to take longer (default 1)",
    )
    add_out(study, "results/<scenario>-study")
    study.set_defaults(func=cmd_study)

    bench = _command(
        sub,
        "bench",
        "per-step cost against the standard stack; batch speed",
        "Benchmark the reference and fast paths against numpy + qpsolvers (daqp, quadprog) in "
        "one process; medians over repeats.",
    )
    bench.add_argument("--json", action="store_true", help="print JSON instead of tables")
    add_quick(bench, "one repeat, a small batch (tests)")
    bench.add_argument(
        "--dask",
        action="store_true",
        help="also measure studies on 1- and 2-worker Dask LocalClusters",
    )
    bench.add_argument("--out", metavar="DIR", help="also write bench.json and bench.md there")
    bench.set_defaults(func=cmd_bench)

    mmc = _command(
        sub,
        "mmc",
        "the manipulability benchmark of Haviland & Corke on the Panda and the UR5",
        "Run random pose tasks on the spatial presets with the controllers of Haviland & Corke "
        "(2020), under their protocol (default) or emdm's (with C-EMDM), and print mean "
        "manipulability, mean final manipulability and failure rate beside the published table.",
    )
    mmc.add_argument(
        "--arm",
        action="append",
        type=scenario_name,
        metavar="ARM",
        help="panda, ur5, or a spatial scenario file or URDF robot with a pose task "
        "(repeatable; default panda and ur5)",
    )
    mmc.add_argument(
        "--protocol",
        choices=["paper", "emdm"],
        default="paper",
        help="paper: the authors' experiment (their exp1.py: RRMC, PARK, BAUR, MMC; default); "
        "emdm: emdm's own (the compiled controllers and C-EMDM, any spatial scenario)",
    )
    mmc.add_argument(
        "--trials",
        type=integer(1, 10**7),
        default=1000,
        metavar="N",
        help="random tasks per arm (default 1000)",
    )
    mmc.add_argument(
        "--seed", type=integer(0, 2**64 - 1), default=0, metavar="S", help="random seed (default 0)"
    )
    mmc.add_argument("--json", action="store_true", help="print JSON instead of a table")
    mmc.add_argument(
        "--out", metavar="DIR", help="output folder for mmc.json and mmc.md (optional)"
    )
    mmc.set_defaults(func=cmd_mmc)

    show = _command(
        sub,
        "scenario",
        "print a scenario as validated TOML (a starting point)",
        "Print a preset or a scenario file, with --set applied, as validated TOML: every value "
        "written out, a template for your own scenario.",
    )
    add_scenario(show)
    show.set_defaults(func=cmd_scenario)

    play = _command(
        sub,
        "play",
        "the live playground in the browser (drag the goal, move the weights)",
        "Serve the playground on 127.0.0.1 and open it in the browser: a planar arm on the 2-D "
        "page (Bokeh, the play extra), a spatial one (panda, ur5, panda-obstacles, a URDF or "
        "spatial TOML file) on the 3-D page (viser, the play3d extra).",
    )
    add_scenario(play, default="task1")
    play.add_argument(
        "--port",
        type=integer(0, 65535),
        default=5006,
        metavar="N",
        help="port (default 5006; 0: any free)",
    )
    play.add_argument("--no-browser", action="store_true", help="only print the address")
    play.set_defaults(func=cmd_play)

    lst = _command(
        sub,
        "list",
        "list controllers, presets and solvers",
        "List the controllers, the preset scenarios and the solvers (installed, or the extra "
        "that installs them).",
    )
    lst.set_defaults(func=cmd_list)
    return parser


def main(argv: Sequence[str] | None = None, *, final: bool = False) -> int:
    """The ``emdm`` command; returns the exit status (``final``: this process ends with it,
    :func:`console`)."""

    def command() -> int:
        _pending.clear()
        try:
            args = build_parser().parse_args(argv)
            status = int(args.func(args))
            _say_warnings()  # a command without --out says them here
            return status
        finally:
            _pending.clear()  # a refused command's are dropped: its one line is the error

    return run_command(command, final=final)


def console() -> None:
    """Entry point of the ``emdm`` executable and of ``python -m emdm.cli``: the command, then
    the exit with its status. A signal after the command no longer changes it: Python resets
    every handler written in Python to the default action when it finalizes, which would kill
    the process with its results already in place, so the signals are ignored from here on."""
    status = main(final=True)
    for signum in HANDLED:
        with contextlib.suppress(ValueError, OSError):
            signal.signal(signum, signal.SIG_IGN)
    sys.exit(status)


__all__ = ["build_parser", "console", "main", "safe", "say"]
