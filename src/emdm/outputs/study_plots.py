"""Figures of Monte-Carlo studies: workspace heat maps and the trade-off of a weight sweep."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..core.controllers import Name
from ..core.scenario import Scenario
from ..studies.montecarlo import GRID, trade_off_rows
from .pareto_plots import trade_off_figure
from .style import COLUMN, figure


def workspace_maps(data: dict[str, Any], scenario: Scenario, out: Path) -> Path:
    """Heat maps over goal positions: C-EMDM time to goal, and its gain over C-IVKC."""
    reach = scenario.reach
    edges = np.linspace(-reach, reach, GRID + 1)
    chosen = {
        "C-EMDM mean time to goal (s)": data["maps"]["C-EMDM time to goal"],
        "C-EMDM mean m gain over C-IVKC (%)": 100 * data["maps"]["C-EMDM gain over C-IVKC"],
    }
    stem = out / "workspace_maps"
    with figure(stem, width=COLUMN, height=5.2, nrows=2) as (_, axes):
        for ax, (title, values) in zip(axes, chosen.items(), strict=True):
            mesh = ax.pcolormesh(
                edges, edges, values.reshape(GRID, GRID), cmap="viridis", shading="flat"
            )
            ax.set_aspect("equal")
            ax.set_xlabel("goal x (m)")
            ax.set_ylabel("goal y (m)")
            ax.set_title(f"{title}, per cell", fontsize=7)
            ax.figure.colorbar(mesh, ax=ax)
    return stem


def sweep_trade_off(
    results: Sequence[dict[str, Any]], scenarios: Sequence[Scenario], out: Path
) -> list[Path]:
    """Whole-run trade-off figures (:func:`trade_off_figure`) from a weight sweep, one per
    scenario with at least two weight pairs and per EMDM controller."""
    stems = []
    for scenario in scenarios:
        for controller in (Name.UC_EMDM, Name.C_EMDM):
            rows = trade_off_rows(results, scenario.name, controller)
            if len(rows) >= 2:
                folder = out / f"trade_off-{scenario.name}-{controller}"
                title = f"{controller} (study means)"
                stems.append(trade_off_figure(rows, scenario, title, folder))
    return stems
