"""``emdm report``: the whole study of the brief in one command, as HTML, LaTeX and data.

The report follows the brief's task items in order. Every number it states is read back from the
data files it wrote (``data/``) and carries its source: in the HTML each number is a
``<span data-src="FILE#KEY/KEY" data-fmt="SPEC">`` (derived percentages name both operands and
``data-op="pct"``), so a test can recompute every one of them; the LaTeX tables are rendered from the
same cells. Findings are sentences assembled from those numbers, never canned text.

The work (closed-loop runs, the solver labs split per solver, Pareto sweeps, figures, animations)
is a flat list of jobs spread over the machine's cores; ``--quick`` runs a reduced version of
every part for demos and tests.
"""

from __future__ import annotations

import datetime as dt
import html
import json
import math
import multiprocessing
import os
import platform
import shutil
import sys
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ProcessPoolExecutor
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Any

from .. import __version__
from ..core.controllers import CONTROLLERS
from ..core.scenario import load_scenario
from ..sim.loop import Run, simulate
from ..solvers import available_solvers
from ..studies.lab import (
    DEFAULT_LAB_SOLVERS,
    LabResult,
    lab_header,
    lab_json,
    lab_rows,
    merge_labs,
    run_lab,
)
from ..studies.pareto import (
    default_grid,
    pareto_figure,
    pareto_study,
    ratios,
    trade_off_figure,
    weight_grid,
)
from .animate import animate
from .lab_plots import lab_figures
from .plots import joints_figure, path_figure, series_figure
from .records import atomic_output, cell, write_csv, write_json, write_run_folder
from .style import formats


@dataclass(frozen=True)
class ReportConfig:
    """How much of each experiment the report runs."""

    quick: bool
    lab_solvers: tuple[str, ...]
    lab_sample: int
    lab_budget: int
    lab_repeats: int
    fallback_solvers: tuple[str, ...]
    pareto_per_decade: int
    grid: int
    animation_seconds: float
    mp4: bool
    figure_formats: tuple[str, ...] = (".png", ".pdf")


FULL = ReportConfig(
    quick=False,
    lab_solvers=DEFAULT_LAB_SOLVERS,
    lab_sample=40,
    lab_budget=600,
    lab_repeats=3,
    fallback_solvers=("active-set", "interior-point", "admm", "daqp", "quadprog", "slsqp"),
    pareto_per_decade=4,
    grid=13,
    animation_seconds=10.0,
    mp4=True,
)
QUICK = ReportConfig(
    quick=True,
    lab_solvers=("active-set", "interior-point", "daqp", "slsqp", "nelder-mead", "powell"),
    lab_sample=8,
    lab_budget=150,
    lab_repeats=1,
    fallback_solvers=("active-set", "daqp", "quadprog"),
    pareto_per_decade=1,
    grid=4,
    animation_seconds=4.0,
    mp4=False,
    figure_formats=(".png",),  # LaTeX then includes the PNGs
)
PAIRS = {"UC": ("UC-EMDM", "UC-IVKC"), "C": ("C-EMDM", "C-IVKC")}


# -------------------------------------------------------------------------------------- jobs
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


def _job_lab_written(
    task: str,
    controller: str,
    solvers: Sequence[str],
    cfg: ReportConfig,
    data_dir: Path,
    fig_dir: Path,
) -> str:
    """A whole lab, its data and figures written by the worker (no result to ship back)."""
    _write_lab(data_dir, _job_lab(task, controller, solvers, cfg), fig_dir, cfg)
    return controller


def _job_pareto(
    task: str, controller: str, cfg: ReportConfig, data_dir: Path, fig_dir: Path
) -> dict[str, Any]:
    scenario = load_scenario(task)
    sweep = ratios(per_decade=cfg.pareto_per_decade)
    data, _ = pareto_study(scenario, controller, sweep=sweep)
    grid = weight_grid(scenario, controller, default_grid(scenario, cfg.grid))
    write_json(data_dir / "pareto.json", data)
    write_json(
        data_dir / "weight_grid.json",
        {"scenario": scenario.name, "controller": controller, "runs": grid},
    )
    with formats(cfg.figure_formats):
        pareto_figure(data, fig_dir)
        trade_off_figure(grid, scenario, controller, fig_dir)
    return {"task": task, "controller": controller}


def _job_figures(runs: dict[str, Run], fig_dir: Path, cfg: ReportConfig) -> list[str]:
    stems = []
    with formats(cfg.figure_formats):
        for group, (emdm_name, ivkc_name) in PAIRS.items():
            pair = [runs[ivkc_name], runs[emdm_name]]
            folder = fig_dir / group
            for quantity in ("manipulability", "effort", "error"):
                stems.append(series_figure(pair, quantity, folder / quantity))
            if any(r.alpha.min() < 1 for r in pair):
                stems.append(series_figure(pair, "alpha", folder / "alpha"))
            if any((r.delta != 0).any() for r in pair):
                stems.append(series_figure(pair, "slack", folder / "slack"))
            stems.append(joints_figure(pair, "qd", folder / "joint_velocities"))
            stems.append(joints_figure(pair, "q", folder / "joint_positions"))
            stems.append(path_figure(pair, folder / "path"))
    return [str(s) for s in stems]


def _job_animation(pair: list[Run], stem: Path, cfg: ReportConfig) -> list[str]:
    duration = max(r.t[-1] for r in pair)
    speedup = 1.0
    while duration / speedup > cfg.animation_seconds:
        speedup *= 2.0
    return [str(p) for p in animate(pair, stem, speedup=speedup, mp4=cfg.mp4)]


# ------------------------------------------------------------------------------ traced cells
@dataclass(frozen=True)
class Cell:
    """A table cell or an inline number, with the data it comes from."""

    text: str
    src: str | None = None
    fmt: str | None = None
    op: str | None = None

    def html(self) -> str:
        if self.src is None:
            return html.escape(self.text)
        op = f' data-op="{self.op}"' if self.op else ""
        return (
            f'<span class="num" data-src="{html.escape(self.src)}" '
            f'data-fmt="{html.escape(self.fmt or "")}"{op}>{html.escape(self.text)}</span>'
        )

    def latex(self) -> str:
        return latex_escape(self.text)


def format_value(value: Any, fmt: str) -> str:
    """How every traced number is written (shared by the report and its tests)."""
    if value is None:
        return "–"
    if fmt == "bool":
        return "yes" if value else "no"
    if fmt == "d":
        return str(int(value))
    if isinstance(value, float) and not math.isfinite(value):
        return "–"
    return format(float(value), fmt)


class Data:
    """The report's data files, read back from disk (numbers are taken from here only)."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self._cache: dict[str, Any] = {}

    def load(self, file: str) -> Any:
        if file not in self._cache:
            self._cache[file] = json.loads((self.root / file).read_text(encoding="utf-8"))
        return self._cache[file]

    def value(self, file: str, *path: str) -> Any:
        node = self.load(file)
        for key in path:
            node = node[int(key)] if isinstance(node, list) else node[key]
        return node

    def num(self, file: str, *path: str, fmt: str = ".4g") -> Cell:
        return Cell(format_value(self.value(file, *path), fmt), f"{file}#{'/'.join(path)}", fmt)

    def pct(self, a: tuple[str, ...], b: tuple[str, ...], fmt: str = "+.1f") -> Cell:
        """``100 (a / b - 1)`` as a signed percentage, tracing both operands."""
        va, vb = self.value(*a), self.value(*b)
        text = format(100.0 * (va / vb - 1.0), fmt) + "%"
        src = f"{a[0]}#{'/'.join(a[1:])}|{b[0]}#{'/'.join(b[1:])}"
        return Cell(text, src, fmt, "pct")


@dataclass
class Table:
    """A table rendered to HTML and to a LaTeX booktabs snippet from the same cells."""

    key: str
    caption: str
    header: list[str]
    rows: list[list[Cell]] = field(default_factory=list)

    def html(self) -> str:
        head = "".join(f"<th>{html.escape(h)}</th>" for h in self.header)
        body = "".join(
            "<tr>" + "".join(f"<td>{c.html()}</td>" for c in row) + "</tr>" for row in self.rows
        )
        return (
            f'<table id="{self.key}"><caption>{html.escape(self.caption)}</caption>'
            f"<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"
        )

    def latex(self) -> str:
        cols = "l" + "r" * (len(self.header) - 1)
        lines = [
            "\\begin{table}[t]",
            "\\centering",
            "\\scriptsize",
            f"\\caption{{{latex_escape(self.caption)}}}",
            f"\\label{{tab:{self.key}}}",
            "\\resizebox{\\columnwidth}{!}{%",
            f"\\begin{{tabular}}{{{cols}}}",
            "\\toprule",
            " & ".join(latex_escape(h) for h in self.header) + " \\\\",
            "\\midrule",
        ]
        lines += [" & ".join(c.latex() for c in row) + " \\\\" for row in self.rows]
        lines += ["\\bottomrule", "\\end{tabular}}", "\\end{table}", ""]
        return "\n".join(lines)


def latex_escape(text: str) -> str:
    """Escape LaTeX's special characters (and the en dash used for missing values)."""
    out = text
    for char, repl in (
        ("\\", r"\textbackslash{}"),
        ("&", r"\&"),
        ("%", r"\%"),
        ("$", r"\$"),
        ("#", r"\#"),
        ("_", r"\_"),
        ("{", r"\{"),
        ("}", r"\}"),
        ("~", r"\~{}"),
        ("^", r"\^{}"),
        ("–", "--"),
        ("|", r"$|$"),
    ):
        out = out.replace(char, repl)
    return out


METRIC_COLUMNS = [
    ("reached", "reached", "bool"),
    ("time to goal (s)", "time_to_goal", ".2f"),
    ("final |e| (m)", "final_error", ".2e"),
    ("min m", "min_manipulability", ".4f"),
    ("mean m", "mean_manipulability", ".4f"),
    ("final m", "final_manipulability", ".4f"),
    ("total effort (rad²/s)", "total_effort", ".3f"),
    ("max |qd| (rad/s)", "max_abs_qd", ".3f"),
    ("min joint margin (rad)", "min_joint_margin", ".3f"),
    ("scaled steps", "scaled_steps", "d"),
    ("fallback steps", "fallback_steps", "d"),
]


def metrics_table(data: Data, task: str, names: Sequence[str], key: str, caption: str) -> Table:
    file = f"data/{task}/metrics.json"
    table = Table(key, caption, ["controller", *[c[0] for c in METRIC_COLUMNS]])
    for name in names:
        table.rows.append(
            [Cell(name)]
            + [data.num(file, "controllers", name, k, fmt=f) for _, k, f in METRIC_COLUMNS]
        )
    return table


LAB_COLUMNS = [
    ("family", "family", None),
    ("median time (ms)", "median_time", "ms"),
    ("p95 time (ms)", "p95_time", "ms"),
    ("median iterations", "median_iterations", ".0f"),
    ("median evaluations", "median_evaluations", ".0f"),
    ("max |gap|", "max_abs_gap", ".1e"),
    ("max violation", "max_violation", ".1e"),
    ("closed loop reached", "reached", "bool"),
    ("time to goal (s)", "time_to_goal", ".2f"),
    ("closed-loop fallbacks", "closed_loop_fallback_steps", "d"),
]


def lab_table(data: Data, file: str, key: str, caption: str) -> Table:
    table = Table(key, caption, ["solver", *[c[0] for c in LAB_COLUMNS]])
    for name, row in data.value(file, "solvers").items():
        cells = [Cell(name)]
        for _, k, f in LAB_COLUMNS:
            if f is None:
                cells.append(Cell(str(row[k])))
            elif f == "ms":
                cells.append(
                    Cell(
                        format_value(row[k] * 1e3, ".3f"), f"{file}#solvers/{name}/{k}", ".3f", "ms"
                    )
                )
            else:
                cells.append(data.num(file, "solvers", name, k, fmt=f))
        table.rows.append(cells)
    return table


# -------------------------------------------------------------------------------- findings
def pair_findings(data: Data, task: str, emdm_name: str, ivkc_name: str) -> list[list[Cell]]:
    """Sentences comparing a pair, every number traced to metrics.json."""
    f = f"data/{task}/metrics.json"
    mt = data.value(f, "controllers")
    a, b = mt[emdm_name], mt[ivkc_name]

    def n(name: str, key: str, fmt: str) -> Cell:
        return data.num(f, "controllers", name, key, fmt=fmt)

    out: list[list[Cell]] = []
    for name, m in ((emdm_name, a), (ivkc_name, b)):
        if m["reached"]:
            out.append(
                [
                    Cell(f"{name} reached the goal in "),
                    n(name, "time_to_goal", ".2f"),
                    Cell(" s (final error "),
                    n(name, "final_error", ".2e"),
                    Cell(" m)."),
                ]
            )
        else:
            out.append(
                [
                    Cell(f"{name} did not reach the goal within "),
                    n(name, "final_time", ".0f"),
                    Cell(" s: its final error is "),
                    n(name, "final_error", ".3f"),
                    Cell(" m."),
                ]
            )
    out.append(
        [
            Cell(f"Mean manipulability of {emdm_name} relative to {ivkc_name}: "),
            data.pct(
                (f, "controllers", emdm_name, "mean_manipulability"),
                (f, "controllers", ivkc_name, "mean_manipulability"),
            ),
            Cell(" ("),
            n(emdm_name, "mean_manipulability", ".4f"),
            Cell(" against "),
            n(ivkc_name, "mean_manipulability", ".4f"),
            Cell("), for a total effort of "),
            data.pct(
                (f, "controllers", emdm_name, "total_effort"),
                (f, "controllers", ivkc_name, "total_effort"),
            ),
            Cell(" ("),
            n(emdm_name, "total_effort", ".3f"),
            Cell(" against "),
            n(ivkc_name, "total_effort", ".3f"),
            Cell(" rad²/s)."),
        ]
    )
    out.append(
        [
            Cell(f"Final manipulability: {emdm_name} "),
            n(emdm_name, "final_manipulability", ".4f"),
            Cell(f", {ivkc_name} "),
            n(ivkc_name, "final_manipulability", ".4f"),
            Cell("; the smallest along the way: "),
            n(emdm_name, "min_manipulability", ".4f"),
            Cell(" and "),
            n(ivkc_name, "min_manipulability", ".4f"),
            Cell("."),
        ]
    )
    for name, m in ((emdm_name, a), (ivkc_name, b)):
        if m["min_joint_margin"] < 0:
            out.append(
                [
                    Cell(f"{name} left the joint limits (smallest margin "),
                    n(name, "min_joint_margin", ".3f"),
                    Cell(" rad) and needed joint speeds up to "),
                    n(name, "max_abs_qd", ".2f"),
                    Cell(" rad/s: it ignores the limits by design."),
                ]
            )
        elif name.startswith("C-"):
            out.append(
                [
                    Cell(f"{name} kept every joint at least "),
                    n(name, "min_joint_margin", ".3f"),
                    Cell(
                        " rad from its limit (outside the stop zones) and every speed within "
                        "its bounds (max |qd| "
                    ),
                    n(name, "max_abs_qd", ".3f"),
                    Cell(" rad/s)."),
                ]
            )
        if m["scaled_steps"]:
            out.append(
                [
                    Cell(f"{name}: the bounds could not deliver the desired velocity in "),
                    n(name, "scaled_steps", "d"),
                    Cell(" steps; the task was scaled down to as little as alpha = "),
                    n(name, "min_alpha", ".3f"),
                    Cell(" along its direction."),
                ]
            )
        if m["slack_steps"]:
            out.append(
                [
                    Cell(f"{name} used its task slack in "),
                    n(name, "slack_steps", "d"),
                    Cell(" steps, up to "),
                    n(name, "max_abs_slack", ".3f"),
                    Cell(" m/s."),
                ]
            )
    return out


def lab_findings(data: Data, file: str) -> list[list[Cell]]:
    """Sentences on the solver comparison, from solvers.json."""
    rows = data.value(file, "solvers")
    out: list[list[Cell]] = []

    def n(name: str, key: str, fmt: str) -> Cell:
        return data.num(file, "solvers", name, key, fmt=fmt)

    def ms(name: str, key: str) -> Cell:
        return Cell(
            format_value(rows[name][key] * 1e3, ".3f"), f"{file}#solvers/{name}/{key}", ".3f", "ms"
        )

    exact = [k for k, r in rows.items() if r["family"] == "exact" and r["failures"] == 0]
    if exact:
        fastest = min(exact, key=lambda k: rows[k]["median_time"])
        out.append(
            [
                Cell(f"Fastest exact solver: {fastest}, "),
                ms(fastest, "median_time"),
                Cell(" ms per program (median), largest gap to the exact optimum "),
                n(fastest, "max_abs_gap", ".1e"),
                Cell("."),
            ]
        )
    for family in ("gradient", "gradient-free"):
        for name, r in rows.items():
            if r["family"] != family:
                continue
            sentence = [Cell(f"{name} ({family}): "), ms(name, "median_time"), Cell(" ms, ")]
            if family == "gradient-free":
                sentence += [n(name, "median_evaluations", ".0f"), Cell(" evaluations, ")]
            else:
                sentence += [n(name, "median_iterations", ".0f"), Cell(" iterations, ")]
            sentence += [
                Cell("gap up to "),
                n(name, "max_abs_gap", ".1e"),
                Cell(", constraint violation up to "),
                n(name, "max_violation", ".1e"),
            ]
            if "time_to_goal" in r and r.get("reached"):
                sentence += [
                    Cell("; in closed loop it reached the goal in "),
                    n(name, "time_to_goal", ".2f"),
                    Cell(" s."),
                ]
            else:
                sentence += [Cell("; in closed loop it did not reach the goal.")]
            out.append(sentence)
    return out


def challenge_findings(data: Data, file: str) -> list[list[Cell]]:
    """Sentences on the numerical challenges, from the lab's ``challenges`` record."""
    ch = data.value(file, "challenges")
    if not ch:
        return []
    out: list[list[Cell]] = []
    rng = ch["feature_ranges"]

    def n(*path: str, fmt: str) -> Cell:
        return data.num(file, "challenges", *path, fmt=fmt)

    if rng["w_slack"][1] > 0:
        out.append(
            [
                Cell("The slack weight w_S = c_S/||e|| grew from "),
                n("feature_ranges", "w_slack", "0", fmt=".3g"),
                Cell(" to "),
                n("feature_ranges", "w_slack", "1", fmt=".3g"),
                Cell(" as the error shrank; cond(J) reached "),
                n("feature_ranges", "cond_J", "1", fmt=".3g"),
                Cell(" near a singularity (smallest m "),
                n("feature_ranges", "m", "0", fmt=".2e"),
                Cell("); the reduced Hessian's condition number ranged "),
                n("feature_ranges", "cond_reduced", "0", fmt=".3g"),
                Cell(" to "),
                n("feature_ranges", "cond_reduced", "1", fmt=".3g"),
                Cell("."),
            ]
        )
    if ch["scaled_steps"]:
        out.append(
            [
                Cell("Scaled steps (alpha < 1, a feasible set reduced to a face): "),
                n("scaled_steps", fmt="d"),
                Cell(" of the re-solved steps; alpha down to "),
                n("feature_ranges", "alpha", "0", fmt=".3f"),
                Cell("."),
            ]
        )
    for name, entry in ch["solvers"].items():
        sentence = [Cell(f"{name}: ")]
        rho = entry.get("iterations_vs_cond_spearman")
        if rho is not None and math.isfinite(rho):
            sentence += [
                Cell("iterations rank-correlate with the condition number at "),
                n("solvers", name, "iterations_vs_cond_spearman", fmt=".2f"),
            ]
        if "median_iterations_scaled" in entry:
            if len(sentence) > 1:
                sentence.append(Cell("; "))
            sentence += [
                Cell("median iterations "),
                n("solvers", name, "median_iterations_scaled", fmt=".0f"),
                Cell(" on scaled steps against "),
                n("solvers", name, "median_iterations_unscaled", fmt=".0f"),
                Cell(" on the others"),
            ]
        if len(sentence) > 1:
            out.append([*sentence, Cell(".")])
    return out


def fallback_findings(data: Data, file: str, controller: str) -> list[list[Cell]]:
    rows = data.value(file, "solvers")
    out = []
    never = [
        n for n, r in rows.items() if r.get("closed_loop_fallback_steps") == 0 and not r["failures"]
    ]
    if never:
        out.append(
            [
                Cell(
                    f"First in the chain, {', '.join(never)} never needed the fallback in "
                    f"closed loop and answered every re-solved program of {controller}."
                )
            ]
        )
    for name, r in rows.items():
        if "closed_loop_fallback_steps" not in r or name in never:
            continue
        sentence = [
            Cell(f"With {name} first in the chain, {controller} needed the fallback in "),
            data.num(file, "solvers", name, "closed_loop_fallback_steps", fmt="d"),
            Cell(" closed-loop steps"),
        ]
        reasons = r.get("closed_loop_fallback_reasons") or {}
        if reasons:
            sentence.append(Cell(" (" + "; ".join(f"{k}: {v}" for k, v in reasons.items()) + ")"))
        if r["failures"]:
            sentence += [
                Cell("; it declined "),
                data.num(file, "solvers", name, "failures", fmt="d"),
                Cell(" of the re-solved programs"),
            ]
        out.append([*sentence, Cell(".")])
    return out


# ------------------------------------------------------------------------------ assembling
CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;max-width:1100px;margin:2em auto;
padding:0 1em;color:#222;line-height:1.45}
h1{font-size:1.7em}h2{border-bottom:2px solid #0072B2;padding-bottom:.2em;margin-top:2em}
h3{margin-top:1.6em;color:#0072B2}
table{border-collapse:collapse;margin:1em 0;font-size:.82em;width:100%}
caption{text-align:left;font-weight:600;margin-bottom:.4em}
th,td{padding:.3em .5em;border-bottom:1px solid #ddd;text-align:right}
th:first-child,td:first-child{text-align:left}thead th{border-bottom:2px solid #444}
.figs{display:grid;grid-template-columns:repeat(auto-fill,minmax(320px,1fr));gap:1em}
figure{margin:0}figure img{width:100%;border:1px solid #eee}figure.wide{grid-column:1/-1}
figcaption{font-size:.8em;color:#555}
.anim img{max-width:100%;border:1px solid #eee}
ul.findings li{margin:.3em 0}.num{font-variant-numeric:tabular-nums}
.note{color:#555;font-size:.9em}code{background:#f4f4f4;padding:0 .2em}
"""


WIDE: set[str] = set()
"""Relative paths of the figures wider than one column (they span a whole row of the grid)."""


def _wide(src: str) -> str:
    return ' class="wide"' if src in WIDE else ""


def _sentence_html(parts: list[Cell]) -> str:
    return "".join(p.html() for p in parts)


def _sentence_latex(parts: list[Cell]) -> str:
    return "".join(p.latex() for p in parts)


@dataclass
class Section:
    """One section of the report: prose, findings, tables, figures and animations."""

    key: str
    title: str
    intro: str = ""
    findings: list[list[Cell]] = field(default_factory=list)
    tables: list[Table] = field(default_factory=list)
    figures: list[tuple[str, str]] = field(default_factory=list)  # (relative png path, caption)
    animations: list[tuple[str, str | None]] = field(default_factory=list)  # (gif, mp4)
    level: int = 3

    def html(self) -> str:
        parts = [f'<h{self.level} id="{self.key}">{html.escape(self.title)}</h{self.level}>']
        if self.intro:
            parts.append(f"<p>{self.intro}</p>")
        if self.findings:
            parts.append(
                '<ul class="findings">'
                + "".join(f"<li>{_sentence_html(s)}</li>" for s in self.findings)
                + "</ul>"
            )
        parts += [t.html() for t in self.tables]
        if self.figures:
            parts.append(
                '<div class="figs">'
                + "".join(
                    f'<figure{_wide(src)}><img src="{html.escape(src)}" alt="{html.escape(cap)}" '
                    f"><figcaption>{html.escape(cap)}</figcaption></figure>"
                    for src, cap in self.figures
                )
                + "</div>"
            )
        for gif, mp4 in self.animations:
            link = f' <a href="{html.escape(mp4)}">MP4</a>' if mp4 else ""
            parts.append(
                f'<div class="anim"><img src="{html.escape(gif)}" alt="animation">'
                f'<p class="note">Animation (GIF{link}); the shaded ellipse is the '
                "manipulability ellipse at the end effector.</p></div>"
            )
        return "\n".join(parts)

    def latex(self, figure_names: dict[str, str]) -> str:
        lines = [f"\\subsection{{{latex_escape(self.title)}}}", f"\\label{{sec:{self.key}}}"]
        if self.findings:
            lines.append("\\begin{itemize}")
            lines += [f"  \\item {_sentence_latex(s)}" for s in self.findings]
            lines.append("\\end{itemize}")
        lines += [f"\\input{{tables/{t.key}}}" for t in self.tables]
        for src, cap in self.figures[:4]:
            name = figure_names.get(src)
            if name:
                lines += [
                    "\\begin{figure}[t]",
                    "\\centering",
                    f"\\includegraphics[width=\\columnwidth]{{figures/{name}}}",
                    f"\\caption{{{latex_escape(cap)}}}",
                    "\\end{figure}",
                ]
        return "\n".join(lines) + "\n"


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
        "pillow",
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


def build_report(
    out: Path,
    *,
    quick: bool = False,
    workers: int | None = None,
    progress: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """Run the whole study and write the report into ``out`` (atomically). Returns provenance."""
    cfg = QUICK if quick else FULL
    say = progress or (lambda _msg: None)
    start = time.perf_counter()
    workers = workers or min(2, os.cpu_count() or 1)
    with atomic_output(Path(out)) as stage:
        scenarios = {task: load_scenario(task) for task in ("task1", "task2")}
        runs = {task: {c: simulate(sc, c) for c in CONTROLLERS} for task, sc in scenarios.items()}
        for task, task_runs in runs.items():
            write_run_folder(stage / "data" / task, scenarios[task], task_runs, solver="active-set")
        say(f"closed-loop runs done ({time.perf_counter() - start:.1f} s)")

        solvers2 = [s for s in cfg.lab_solvers if s in available_solvers()]
        solvers1 = [s for s in cfg.fallback_solvers if s in available_solvers()]
        context = multiprocessing.get_context("fork")
        futures: dict[str, Future[Any]] = {}
        with ProcessPoolExecutor(max_workers=workers, mp_context=context) as pool:
            # longest jobs first: the gradient-free closed loops
            for name in reversed(solvers2):
                futures[f"lab2:{name}"] = pool.submit(_job_lab, "task2", "C-EMDM", [name], cfg)
            for ctrl in ("UC-EMDM", "C-EMDM"):
                futures[f"lab1:{ctrl}"] = pool.submit(
                    _job_lab_written,
                    "task1",
                    ctrl,
                    solvers1,
                    cfg,
                    stage / "data" / f"task1-lab-{ctrl}",
                    stage / "figures" / "task1" / f"lab-{ctrl}",
                )
                futures[f"pareto:{ctrl}"] = pool.submit(
                    _job_pareto,
                    "task1",
                    ctrl,
                    cfg,
                    stage / "data" / f"task1-pareto-{ctrl}",
                    stage / "figures" / "task1" / f"pareto-{ctrl}",
                )
            for task in ("task1", "task2"):
                futures[f"figures:{task}"] = pool.submit(
                    _job_figures, runs[task], stage / "figures" / task, cfg
                )
                for group, (emdm_name, ivkc_name) in PAIRS.items():
                    pair = [runs[task][ivkc_name], runs[task][emdm_name]]
                    stem = stage / "animations" / task / f"{ivkc_name}_vs_{emdm_name}"
                    futures[f"anim:{task}:{group}"] = pool.submit(_job_animation, pair, stem, cfg)
            results = {}
            for key, future in futures.items():
                results[key] = future.result()
                say(f"{key} done ({time.perf_counter() - start:.1f} s)")

        lab2 = merge_labs([results[f"lab2:{name}"] for name in solvers2])
        _write_lab(
            stage / "data" / "task2-lab-C-EMDM", lab2, stage / "figures" / "task2" / "lab", cfg
        )
        wall = time.perf_counter() - start
        prov = provenance(cfg, wall)
        write_json(stage / "provenance.json", prov)
        _write_documents(stage, prov, cfg)
        say(f"report written ({time.perf_counter() - start:.1f} s)")
    return prov


def _write_lab(folder: Path, lab: LabResult, fig_dir: Path, cfg: ReportConfig) -> None:
    write_json(folder / "solvers.json", lab_json(lab))
    for name in lab.studies:
        write_csv(
            folder / "solvers" / f"{name}.csv",
            lab_header(lab),
            ([cell(v) for v in row] for row in lab_rows(lab, name)),
        )
    with formats(cfg.figure_formats):
        lab_figures(lab, fig_dir)


def _figs(stage: Path, folder: str, items: Sequence[tuple[str, str]]) -> list[tuple[str, str]]:
    """The figures of ``folder`` that exist, as (relative PNG path, caption); notes the wide ones."""
    from PIL import Image

    found = []
    for name, caption in items:
        path = stage / folder / f"{name}.png"
        if path.exists():
            with Image.open(path) as image:
                if image.size[0] > 1000:  # wider than one column at 200 dpi
                    WIDE.add(f"{folder}/{name}.png")
            found.append((f"{folder}/{name}.png", caption))
    return found


def _sections(stage: Path, data: Data, cfg: ReportConfig) -> list[Section]:
    sections: list[Section] = []
    pair_figs = [
        ("path", "end-effector path"),
        ("manipulability", "manipulability m(t)"),
        ("effort", "effort E(t)"),
        ("error", "tracking error"),
        ("joint_positions", "joint positions and damper zones"),
        ("joint_velocities", "joint velocities and limits"),
        ("alpha", "task scale alpha"),
        ("slack", "task slack"),
    ]
    items = [
        (
            "task1",
            "UC",
            "t1-uc",
            "Task 1.1: UC-EMDM against UC-IVKC (3-link redundant arm)",
            "UC-EMDM",
        ),
        ("task1", "C", "t1-c", "Task 1.2: C-EMDM against C-IVKC (3-link redundant arm)", "C-EMDM"),
        (
            "task2",
            "C",
            "t2-c",
            "Task 2.1: C-EMDM against C-IVKC (2-link arm with task slack)",
            None,
        ),
        ("task2", "UC", "t2-uc", "Task 2.2: UC-EMDM against UC-IVKC (2-link arm)", None),
    ]
    for task, group, key, title, pareto_ctrl in items:
        emdm_name, ivkc_name = PAIRS[group]
        gif = f"animations/{task}/{ivkc_name}_vs_{emdm_name}"
        mp4 = f"{gif}.mp4" if (stage / f"{gif}.mp4").exists() else None
        sec = Section(
            key,
            title,
            level=2,
            findings=pair_findings(data, task, emdm_name, ivkc_name),
            tables=[
                metrics_table(
                    data,
                    task,
                    [emdm_name, ivkc_name],
                    f"{key}-metrics",
                    f"{title}: outcomes of the closed loop",
                )
            ],
            figures=_figs(stage, f"figures/{task}/{group}", pair_figs),
            animations=[(f"{gif}.gif", mp4)],
        )
        sections.append(sec)
        if pareto_ctrl:
            folder = f"figures/task1/pareto-{pareto_ctrl}"
            pareto_file = f"data/task1-pareto-{pareto_ctrl}/pareto.json"
            steps = data.value(pareto_file, "steps")
            p = Section(
                f"{key}-pareto",
                f"{pareto_ctrl}: Pareto fronts between effort and manipulability rate",
                intro=(
                    "At k = 0, floor(T/3), floor(2T/3) and T the step's program is solved "
                    "for w_M/w_E swept log-uniformly over 7 decades plus w_M = 0 "
                    "(w_E fixed); each optimum gives a point (E, M). The whole controller "
                    "is also re-run over a grid of weights."
                ),
                figures=_figs(
                    stage,
                    folder,
                    [
                        ("pareto_front", "Pareto fronts at four steps"),
                        ("trade_off", "whole-run trade-off"),
                    ],
                ),
            )
            for i, st in enumerate(steps):
                pts = st["points"]
                nd = sum(not q["dominated"] for q in pts)
                p.findings.append(
                    [
                        Cell("At k = "),
                        data.num(pareto_file, "steps", str(i), "k", fmt="d"),
                        Cell(" (t = "),
                        data.num(pareto_file, "steps", str(i), "t", fmt=".2f"),
                        Cell(f" s) {nd} of {len(pts)} points are non-dominated; effort ranges "),
                        data.num(pareto_file, "steps", str(i), "points", "0", "E", fmt=".3g"),
                        Cell(" to "),
                        data.num(
                            pareto_file,
                            "steps",
                            str(i),
                            "points",
                            str(len(pts) - 1),
                            "E",
                            fmt=".3g",
                        ),
                        Cell(" and manipulability rate "),
                        data.num(pareto_file, "steps", str(i), "points", "0", "M", fmt=".3g"),
                        Cell(" to "),
                        data.num(
                            pareto_file,
                            "steps",
                            str(i),
                            "points",
                            str(len(pts) - 1),
                            "M",
                            fmt=".3g",
                        ),
                        Cell("."),
                    ]
                )
            sections.append(p)
            lab_file = f"data/task1-lab-{pareto_ctrl}/solvers.json"
            sections.append(
                Section(
                    f"{key}-solvers",
                    f"{pareto_ctrl}: custom solver, off-the-shelf fallback",
                    intro=(
                        "The custom primal active-set method solves every step; each answer is "
                        "certified by its KKT residuals and handed to daqp, then quadprog, when not "
                        "optimal. Below, each solver alone in the loop and on the programs of the "
                        "exact trajectory."
                    ),
                    findings=fallback_findings(data, lab_file, pareto_ctrl)
                    + lab_findings(data, lab_file),
                    tables=[
                        lab_table(
                            data, lab_file, f"{key}-solvers", f"Task 1 {pareto_ctrl}: solvers"
                        )
                    ],
                    figures=_figs(
                        stage,
                        f"figures/task1/lab-{pareto_ctrl}",
                        [
                            ("convergence", "convergence at representative steps"),
                            ("challenges", "iterations against conditioning"),
                        ],
                    ),
                )
            )
        if key == "t2-c":
            lab_file = "data/task2-lab-C-EMDM/solvers.json"
            sections.append(
                Section(
                    "t2-solvers",
                    "Task 2.1: gradient-based against gradient-free solvers (C-EMDM)",
                    intro=(
                        "Gradient-free methods search the reduced program (delta = v - J qd "
                        "eliminated, only linear inequalities left), natively constrained (COBYQA, "
                        "COBYLA, differential evolution) or through an exact l1 penalty "
                        "(Nelder-Mead, Powell, CMA-ES); no answer is clipped. Gaps and violations "
                        "are measured against the exact optimum."
                    ),
                    findings=lab_findings(data, lab_file),
                    tables=[
                        lab_table(data, lab_file, "t2-solvers", "Task 2 C-EMDM: solvers compared")
                    ],
                    figures=_figs(
                        stage,
                        "figures/task2/lab",
                        [
                            ("convergence", "convergence against iterations and evaluations"),
                            ("solve_times", "solve time per step"),
                            ("trajectories", "closed loop with each solver"),
                        ],
                    ),
                )
            )
    challenges = Section(
        "challenges",
        "Convergence and numerical challenges",
        level=2,
        intro=(
            "Measured from the solver lab's records: the conditioning that w_S = c_S/||e|| and "
            "near-singular Jacobians create, the degenerate active sets of scaled steps, and "
            "how each iterative method's work follows them."
        ),
        findings=(
            challenge_findings(data, "data/task2-lab-C-EMDM/solvers.json")
            + challenge_findings(data, "data/task1-lab-C-EMDM/solvers.json")
        ),
        figures=_figs(
            stage, "figures/task2/lab", [("challenges", "task 2: iterations and features")]
        ),
    )
    sections.append(challenges)
    return sections


def _write_documents(stage: Path, prov: dict[str, Any], cfg: ReportConfig) -> None:
    data = Data(stage)
    sections = _sections(stage, data, cfg)
    # LaTeX: figures as PDF, tables as booktabs snippets, one snippet per section
    latex = stage / "latex"
    (latex / "figures").mkdir(parents=True, exist_ok=True)
    figure_names: dict[str, str] = {}
    vector = ".pdf" in cfg.figure_formats
    for png in sorted((stage / "figures").rglob("*.png")):
        source = png.with_suffix(".pdf") if vector else png
        name = "_".join(png.relative_to(stage / "figures").with_suffix("").parts)
        shutil.copyfile(source, latex / "figures" / f"{name}{source.suffix}")
        figure_names[str(png.relative_to(stage))] = name
    for sec in sections:
        for table in sec.tables:
            (latex / "tables").mkdir(exist_ok=True)
            (latex / "tables" / f"{table.key}.tex").write_text(table.latex(), encoding="utf-8")
        (latex / "sections").mkdir(exist_ok=True)
        (latex / "sections" / f"{sec.key}.tex").write_text(
            sec.latex(figure_names), encoding="utf-8"
        )
    (latex / "report.tex").write_text(_latex_main(sections), encoding="utf-8")
    (stage / "index.html").write_text(_html(sections, prov), encoding="utf-8")


def _latex_main(sections: list[Section]) -> str:
    body = "\n".join(f"\\input{{sections/{s.key}}}" for s in sections)
    return (
        "% Generated by emdm report. Every snippet stands alone: \\input the ones you need.\n"
        "\\documentclass[conference]{IEEEtran}\n\\usepackage{booktabs,graphicx,amsmath}\n"
        "\\begin{document}\n\\title{Effort-minimising, dexterity-maximising control: results}\n"
        "\\maketitle\n\\section{Results}\n" + body + "\n\\end{document}\n"
    )


def _html(sections: list[Section], prov: dict[str, Any]) -> str:
    toc = "".join(
        f'<li><a href="#{s.key}">{html.escape(s.title)}</a></li>' for s in sections if s.level == 2
    )
    pkg = ", ".join(f"{k} {v}" for k, v in prov["packages"].items())
    prov_rows = [
        ("emdm", prov["emdm_version"]),
        ("mode", prov["mode"]),
        ("date (UTC)", prov["date_utc"]),
        ("python", prov["python"]),
        ("machine", f"{prov['platform']}, {prov['cpus']} CPUs"),
        ("libraries", pkg),
        ("solvers installed", ", ".join(prov["solvers_installed"])),
        ("wall time", f"{prov['wall_time_s']:.1f} s"),
    ]
    prov_html = "".join(
        f"<tr><th>{html.escape(k)}</th><td>{html.escape(str(v))}</td></tr>" for k, v in prov_rows
    )
    body = "\n".join(s.html() for s in sections)
    data_links = (
        '<p>All data behind this page: <a href="data/">data/</a> (metrics.json, '
        'per-step CSVs, solver lab and Pareto JSON), <a href="latex/">latex/</a> '
        "(figures as PDF, booktabs tables, one snippet per section), "
        '<a href="provenance.json">provenance.json</a>.</p>'
    )
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>emdm report: effort-minimising, dexterity-maximising control</title>
<style>{CSS}</style></head><body>
<h1>Effort-minimising, dexterity-maximising control: the study</h1>
<p>Every number on this page is read from the data files beside it, and every controller command is
the certified optimum of its step's program (KKT residuals at most 1e-9, bounds never exceeded).
Parameters are the brief's Tables 1 and 2.</p>
<ul>{toc}</ul>
{body}
<h2 id="provenance">Provenance</h2>
<table class="prov"><tbody>{prov_html}</tbody></table>
{data_links}
</body></html>
"""
