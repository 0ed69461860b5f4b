"""Figures of the solver lab: convergence, solve times, closed-loop trajectories."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.patches import Patch
from matplotlib.ticker import MaxNLocator, NullFormatter

from ..studies.lab import LabResult, Representative
from .style import COLUMN, DOUBLE, FAMILY_COLOR, color, figure

FLOOR = 1e-17


def error_curve(history: tuple[dict[str, float], ...], f_star: float) -> np.ndarray:
    """Running best of ``|f - f*| + violation`` along a history (floored for log axes)."""
    values = [
        abs(h["objective"] - f_star) + h.get("violation", h.get("primal_residual", 0.0))
        for h in history
    ]
    return np.maximum(np.minimum.accumulate(np.array(values)), FLOOR)


def _line_style(index: int) -> dict[str, object]:
    """Colour and dash pattern for the ``index``-th solver: 8 colours x 3 dash patterns."""
    return {"color": color(index), "linestyle": ("-", "--", ":")[(index // 8) % 3]}


def convergence_figure(lab: LabResult, out: Path) -> Path:
    """Optimality error against iterations (top) and evaluations (bottom) at representative steps."""
    # one column per step: a step that is two representatives at once (the first step of Task 1
    # is also its least dexterous) is drawn once, with both names
    steps: dict[int, list[Representative]] = {}
    for rep, k in lab.representative.items():
        steps.setdefault(k, []).append(rep)
    reps = {" and ".join(map(str, names)): (names[0], k) for k, names in steps.items()}
    stem = out / "convergence"
    with figure(stem, width=DOUBLE, height=4.4, nrows=2, ncols=len(reps), squeeze=False) as (
        fig,
        ax,
    ):
        for col, (label, (key, k)) in enumerate(reps.items()):
            f_star = lab.optimum[k][1]
            for i, (name, study) in enumerate(lab.studies.items()):
                hist = study.histories.get(key, ())  # recorded under the step's first name
                if not hist:
                    continue
                err = error_curve(hist, f_star)
                style = {
                    **_line_style(i),
                    "label": name,
                    "linewidth": 1.0,
                    "marker": ".",
                    "markersize": 4,
                }
                if "iteration" in hist[0]:
                    ax[0, col].loglog([h["iteration"] + 1 for h in hist], err, **style)
                if "evaluations" in hist[0]:
                    ax[1, col].loglog([h["evaluations"] for h in hist], err, **style)
            alpha = lab.reference.alpha[k]
            # two short lines: one line per panel ran into its neighbours' titles
            ax[0, col].set_title(f"{label} step\n$k = {k}$, $\\alpha = {alpha:.2f}$", fontsize=9)
            ax[0, col].set_xlabel("iteration + 1")
            ax[1, col].set_xlabel("objective evaluations")
            for row in range(2):  # 2x10^0, 3x10^0... ran together
                ax[row, col].xaxis.set_minor_formatter(NullFormatter())
            for row in range(2):
                ax[row, col].set_ylabel("best |f - f*| + violation")
                if not ax[row, col].lines:  # say why a panel is empty instead of a blank frame
                    ax[row, col].text(
                        0.5, 0.5, "no " + ("iterative" if row == 0 else "gradient-free")
                        + " solver\nin this comparison", ha="center", va="center",
                        transform=ax[row, col].transAxes, color="0.4",
                    )  # fmt: skip
                    ax[row, col].set_xticks([])
                    ax[row, col].set_yticks([])
                    continue
                ax[row, col].set_ylim(1e-17, None)
                counts = np.concatenate([line.get_xdata() for line in ax[row, col].lines])
                if counts.max() < 10 * counts.min():  # within a decade: plain integer ticks
                    ax[row, col].set_xscale("linear")
                    ax[row, col].xaxis.set_major_locator(MaxNLocator(integer=True))
                    if np.ptp(counts) == 0:  # one count (a search that ends at once): its tick
                        ax[row, col].set_xlim(counts[0] - 1, counts[0] + 1)
                        ax[row, col].set_xticks([counts[0]])
        handles, labels = [], []
        for axis in ax.flat:
            for h, lab_ in zip(*axis.get_legend_handles_labels(), strict=True):
                if lab_ not in labels:
                    handles.append(h)
                    labels.append(lab_)
        fig.legend(handles, labels, loc="outside right center", ncols=1)
        fig.suptitle(f"Convergence on {lab.scenario.name} {lab.controller.name} programs")
    return stem


def times_figure(lab: LabResult, out: Path) -> Path:
    """Distribution of per-step solve times, one box per solver, coloured by family."""
    stem = out / "solve_times"
    names = list(lab.studies)
    with figure(stem, width=COLUMN, height=0.22 * len(names) + 0.8) as (fig, ax):
        data = [np.array([s.time for s in lab.studies[n].solves]) * 1e3 for n in names]
        box = ax.boxplot(
            data,
            orientation="horizontal",
            tick_labels=names,
            showfliers=False,
            patch_artist=True,
            medianprops={"color": "black"},
        )
        for patch, name in zip(box["boxes"], names, strict=True):
            patch.set_facecolor(FAMILY_COLOR.get(lab.studies[name].spec.family, "grey"))
            patch.set_alpha(0.7)
        ax.set_xscale("log")
        ax.set_xlabel("solve time per step (ms)")
        ax.invert_yaxis()
        ax.set_title(f"{lab.scenario.name} {lab.controller.name}: time per solve")
        families = [Patch(facecolor=c, alpha=0.7, label=f) for f, c in FAMILY_COLOR.items()]
        fig.legend(handles=families, loc="outside lower center", ncols=3, fontsize=6)
    return stem


def trajectories_figure(lab: LabResult, out: Path) -> Path:
    """End-effector paths and error norms of the closed loop with each solver."""
    stem = out / "trajectories"
    with figure(stem, width=DOUBLE, height=2.6, ncols=2) as (fig, (path_ax, err_ax)):
        for i, (name, study) in enumerate(lab.studies.items()):
            run = study.closed_loop
            if run is None:
                continue
            style = {
                **_line_style(i),
                "label": name,
                "linewidth": 1.0,
                "marker": ".",
                "markersize": 2,
            }
            path_ax.plot(run.p[:, 0], run.p[:, 1], **style)
            err_ax.semilogy(run.t, np.maximum(run.error_norm, 1e-6), **style)
        goal = lab.scenario.motion.goal
        path_ax.plot(*goal, marker="*", color="black", markersize=9, linestyle="none", label="goal")
        start = lab.reference.p[0]
        path_ax.plot(
            *start, marker="o", color="black", markersize=4, linestyle="none", label="start"
        )
        path_ax.set_aspect("equal", adjustable="datalim")
        path_ax.set_xlabel("x (m)")
        path_ax.set_ylabel("y (m)")
        path_ax.set_title("end-effector path, closed loop per solver")
        err_ax.axhline(lab.scenario.motion.tolerance, color="grey", linewidth=0.8, linestyle=":")
        err_ax.set_xlabel("t (s)")
        err_ax.set_ylabel("||e|| (m)")
        err_ax.set_title("tracking error")
        fig.legend(*path_ax.get_legend_handles_labels(), loc="outside right center", fontsize=6)
    return stem


def challenges_figure(lab: LabResult, out: Path) -> Path:
    """Iterations against the reduced-Hessian condition number, and the features along the run."""
    stem = out / "challenges"
    steps = lab.steps
    cond = np.array([lab.features[k]["cond_reduced"] for k in steps])
    with figure(stem, width=DOUBLE, height=2.6, ncols=2) as (fig, (left, right)):
        for i, (name, study) in enumerate(lab.studies.items()):
            its = np.array([s.iterations for s in study.solves], dtype=float)
            if study.spec.family == "gradient-free" or np.ptp(its) == 0:
                continue
            left.loglog(
                cond,
                np.maximum(its, 1),
                linestyle="none",
                marker="o",
                markersize=2.5,
                color=color(i),
                label=name,
            )
        left.set_xlabel("condition number of Z^T P Z")
        left.set_ylabel("iterations")
        left.set_title("iterations against conditioning")
        if left.get_legend_handles_labels()[0]:
            left.legend(fontsize=6)
        t = lab.reference.t[steps]
        for j, (label, key) in enumerate(
            (("m (manipulability)", "m"), ("alpha (task scale)", "alpha"))
        ):
            right.plot(t, [lab.features[k][key] for k in steps], color=color(j), label=label)
        right.set_xlabel("t (s)")
        right.set_ylabel("m, alpha")
        twin = right.twinx()
        twin.semilogy(t, cond, color=color(3), linestyle="--", label="cond(Z^T P Z)")
        w_s = [lab.features[k]["w_slack"] for k in steps]
        if max(w_s) > 0:
            twin.semilogy(t, w_s, color=color(4), linestyle=":", label="w_S = c_S / ||e||")
        twin.set_ylabel("condition number, w_S")
        twin.grid(False)
        right.set_title("along the reference run")
        handles = right.get_legend_handles_labels()[0] + twin.get_legend_handles_labels()[0]
        labels = right.get_legend_handles_labels()[1] + twin.get_legend_handles_labels()[1]
        fig.legend(handles, labels, loc="outside right center", fontsize=6)
    return stem


def lab_figures(lab: LabResult, out: Path) -> list[Path]:
    """Every lab figure (PNG, PDF and SVG each); returns the stems."""
    return [
        convergence_figure(lab, out),
        times_figure(lab, out),
        trajectories_figure(lab, out),
        challenges_figure(lab, out),
    ]
