"""Figures of the Pareto study: fronts per step and the whole-run trade-off.

The data come from :mod:`emdm.studies.pareto` (``pareto_study``, ``weight_grid``) or from a
Monte-Carlo weight sweep (:func:`emdm.studies.montecarlo.trade_off_rows`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.ticker import FormatStrFormatter, MaxNLocator

from ..core.scenario import Scenario
from .style import COLUMN, DOUBLE, color, figure


def pareto_figure(data: dict[str, Any], out: Path) -> Path:
    """E against M at the four steps, the nominal weights circled, dominated points hollow."""
    stem = out / "pareto_front"
    nominal = data["nominal_ratio"]
    with figure(stem, width=DOUBLE, height=2.3, ncols=4) as (fig, axes):
        for ax, step in zip(axes, data["steps"], strict=True):
            pts = step["points"]
            ratio = [p["w_manip"] / p["w_effort"] for p in pts]
            E = np.array([p["E"] for p in pts])
            M = np.array([p["M"] for p in pts])
            dominated = np.array([p["dominated"] for p in pts])
            ax.plot(M, E, color="grey", linewidth=0.6, zorder=1)
            sc = ax.scatter(
                M[~dominated],
                E[~dominated],
                c=np.log10(np.maximum(np.array(ratio)[~dominated], 1e-4)),
                cmap="viridis",
                s=12,
                zorder=2,
            )
            ax.scatter(
                M[dominated],
                E[dominated],
                facecolors="none",
                edgecolors="black",
                s=14,
                linewidths=0.6,
                zorder=2,
                label="dominated",
            )
            near = int(
                np.argmin(
                    [
                        abs(math.log10(max(r, 1e-12)) - math.log10(max(nominal, 1e-12)))
                        for r in ratio
                    ]
                )
            )
            ax.scatter(
                [M[near]],
                [E[near]],
                s=60,
                facecolors="none",
                edgecolors="#D55E00",
                linewidths=1.2,
                zorder=3,
                label=f"nominal w_M/w_E = {nominal:g}",
            )
            alpha = min(p["alpha"] for p in pts)
            scaled = f", alpha = {alpha:.2f}" if alpha < 1.0 else ""
            ax.set_title(f"k = {step['k']} (t = {step['t']:.2f} s{scaled})")
            ax.set_xlabel("manip. rate M (1/s)")
            ax.xaxis.set_major_locator(MaxNLocator(3))
            ax.xaxis.set_major_formatter(FormatStrFormatter("%.3g"))
            ax.tick_params(axis="x", labelrotation=30)
            if np.ptp(E) <= 1e-9 * max(float(np.abs(E).max()), 1e-300) and np.ptp(M) <= 1e-9 * max(
                float(np.abs(M).max()), 1e-300
            ):  # a degenerate front (e.g. Jm orthogonal to the self-motions)
                ax.text(
                    0.5,
                    0.95,
                    "one point: every\nweight gives the\nsame command",
                    transform=ax.transAxes,
                    ha="center",
                    va="top",
                    fontsize=6,
                )
            else:
                ax.set_yscale("log")
        axes[0].set_ylabel("effort E (rad^2/s^2)")
        fig.legend(
            *axes[0].get_legend_handles_labels(), loc="outside lower center", ncols=2, fontsize=6
        )
        fig.colorbar(sc, ax=axes, label="log10 w_M / w_E", shrink=0.9)
        fig.suptitle(
            f"Pareto fronts, {data['scenario']} {data['controller']} (w_M = 0 at the far left)"
        )
    return stem


def trade_off_figure(
    rows: list[dict[str, Any]], scenario: Scenario, controller: str, out: Path
) -> Path:
    """Trajectory-level trade-off: total effort against mean manipulability, and time to goal."""
    stem = out / "trade_off"
    ok = [r for r in rows if "error" not in r]
    ratio = np.array([r["w_manip"] / r["w_effort"] for r in ok])
    effort = np.array([r["total_effort"] for r in ok])
    mean_m = np.array([r["mean_manipulability"] for r in ok])
    ttg = np.array([r["time_to_goal"] if r["time_to_goal"] is not None else np.nan for r in ok])
    nominal = scenario.weights.manipulability / scenario.weights.effort
    with figure(stem, width=COLUMN, height=3.6, nrows=2) as (_, (top, bottom)):
        top.plot(mean_m, effort, color="grey", linewidth=0.6)
        s = top.scatter(mean_m, effort, c=np.log10(np.maximum(ratio, 1e-3)), cmap="viridis", s=14)
        nom = np.isclose(ratio, nominal)
        top.scatter(
            mean_m[nom],
            effort[nom],
            s=60,
            facecolors="none",
            edgecolors="#D55E00",
            linewidths=1.2,
            label="nominal weights",
        )
        top.set_yscale("log")
        top.set_xlabel("mean manipulability over the run")
        top.set_ylabel("total effort (rad^2/s)")
        top.set_title(f"{scenario.name} {controller}: whole runs per weight ratio")
        top.legend(fontsize=6)
        bottom.semilogx(np.maximum(ratio, 1e-3), ttg, marker="o", markersize=3, color=color(0))
        bottom.set_xlabel("w_M / w_E (0 drawn at 1e-3)")
        bottom.set_ylabel("time to goal (s)")
        top.figure.colorbar(s, ax=top, label="log10 w_M / w_E")
    return stem
