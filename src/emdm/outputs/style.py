"""One look for every figure: IEEE column widths, a colour-blind-safe palette, units on every axis.

Colours are the Okabe-Ito palette (safe for the common colour-vision deficiencies). Every figure is
saved as PNG (for screens and the HTML report) and as PDF and SVG (vector, for LaTeX).

Figures are drawn on their own Agg canvas, without pyplot: importing emdm changes no matplotlib
state (no backend is chosen, no figure is registered), and no display is needed.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import matplotlib
from cycler import cycler
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ..core.controllers import Name

COLUMN = 3.5
"""IEEE single-column width (in)."""
DOUBLE = 7.16
"""IEEE double-column width (in)."""

OKABE_ITO = ["#0072B2", "#E69F00", "#009E73", "#D55E00", "#CC79A7", "#56B4E9", "#F0E442", "#000000"]

CONTROLLER_STYLE: dict[str, dict[str, Any]] = {
    Name.UC_IVKC: {"color": "#C17A00", "linestyle": "--"},  # a dark orange: Okabe-Ito's
    # (#E69F00) printed at about 160 of 255, its peak labels faint in greyscale; this one at 130
    Name.C_IVKC: {"color": "#D55E00", "linestyle": "-"},
    Name.UC_EMDM: {"color": "#332288", "linestyle": "--"},  # Tol's indigo: sky blue printed as
    # UC-IVKC's orange does in greyscale (both about 160 of 255); indigo prints at about 50
    Name.C_EMDM: {"color": "#0072B2", "linestyle": "-"},
    Name.RRMC: {"color": "#999999", "linestyle": ":"},
    Name.PARK: {"color": "#CC79A7", "linestyle": "-."},
    Name.MMC: {"color": "#009E73", "linestyle": "-"},
}
FAMILY_COLOR = {"exact": "#0072B2", "gradient": "#009E73", "gradient-free": "#D55E00"}

RC: Any = {
    "font.size": 8,
    "axes.titlesize": 8,
    "axes.labelsize": 8,
    "legend.fontsize": 7,
    "xtick.labelsize": 7,
    "ytick.labelsize": 7,
    "lines.linewidth": 1.2,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "grid.linewidth": 0.5,
    "axes.prop_cycle": cycler(color=OKABE_ITO),
    "savefig.dpi": 200,
    "figure.constrained_layout.use": True,
    "svg.fonttype": "none",
    "pdf.fonttype": 42,
}


FORMATS: tuple[str, ...] = (".png", ".pdf", ".svg")
"""Formats every figure is saved in; :func:`formats` changes them for a block (the report skips SVG)."""


@contextmanager
def formats(suffixes: tuple[str, ...]) -> Iterator[None]:
    """Save figures in ``suffixes`` (e.g. ``(".png", ".pdf")``) inside the block."""
    global FORMATS
    saved, FORMATS = FORMATS, suffixes
    try:
        yield
    finally:
        FORMATS = saved


def color(index: int) -> str:
    """The ``index``-th palette colour (cycling)."""
    return OKABE_ITO[index % len(OKABE_ITO)]


@contextmanager
def figure(
    path_stem: Path, width: float = COLUMN, height: float = 2.4, **subplots: Any
) -> Iterator[tuple[Any, Any]]:
    """Create a styled figure; on exit save it in every format of :data:`FORMATS`.

    ``subplots`` go to :meth:`matplotlib.figure.Figure.subplots` (``nrows``, ``sharex``, ...).
    """
    with matplotlib.rc_context(RC):
        fig = Figure(figsize=(width, height))
        FigureCanvasAgg(fig)
        axes = fig.subplots(**subplots)
        yield fig, axes
        path_stem.parent.mkdir(parents=True, exist_ok=True)
        for suffix in FORMATS:
            fig.savefig(path_stem.with_suffix(suffix))


def figure_canvas(width: float, height: float, dpi: float = 110) -> tuple[Any, Any]:
    """A figure with its Agg canvas, for frame-by-frame rendering (animations); draw it inside
    ``matplotlib.rc_context(RC)`` for the shared style."""
    fig = Figure(figsize=(width, height), dpi=dpi, layout="constrained")
    return fig, FigureCanvasAgg(fig)
