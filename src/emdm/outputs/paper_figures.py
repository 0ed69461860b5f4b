"""Figures of the paper and of the pitch, designed for where they are printed.

Two media: :data:`PAPER` draws for an IEEE column (3.5 in, text at 7-8 pt when included at its
natural width, ``width=\\columnwidth``) or the full page width (``figure*``, 7.16 in);
:data:`SLIDE` draws for a 16:9 Beamer slide (16 cm x 9 cm, text at 10-11 pt, like the slide's own
text). Every figure is saved as PDF (vector, for LaTeX) and PNG (for the HTML page).

Figures (each a function of measured records only):

- :func:`pair_figure`: a controller pair in one composite: m(t), E(t), q(t) and qd(t) per joint,
  with the joint limits, the damper zones and the task-scaled interval both share;
- :func:`workspace_figure`: a two-link pair in the workspace, with the disc the arm cannot reach
  with its elbow outside the stop zone, the straight line a direction-preserving controller must
  follow, the goal's two inverse-kinematics solutions and where each run stalls or flips;
- :func:`pareto_figure`: the four per-step fronts of UC- and C-EMDM and the whole-run trade-off,
  degenerate and saturated fronts and failed weight settings marked;
- :func:`solver_figure`: time per program against the gap to the exact optimum, per solver family;
- :func:`conditioning_figure`: cond(J), the slack weight and the solvers' iterations along a run;
- :func:`manipulability_figure`, :func:`stills_figure`: the pitch's headline and animation stills.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.layout_engine import ConstrainedLayoutEngine
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Patch
from matplotlib.ticker import LogLocator, MaxNLocator, NullLocator

from ..sim.loop import Run
from ..sim.metrics import limit_excess
from ..sim.metrics import metrics as metrics_of
from ..solvers.base import Family
from ..studies.lab import exact_answer
from .animate import ellipse_points
from .style import CONTROLLER_STYLE, FAMILY_COLOR, OKABE_ITO, RC


@dataclass(frozen=True)
class Medium:
    """Where a figure is printed: its widths (in) and font sizes (pt)."""

    name: str
    column: float
    wide: float
    font: float
    small: float
    line: float
    tiny: float = 7.0


PAPER = Medium("paper", column=3.5, wide=7.16, font=8.0, small=8.0, line=1.1, tiny=7.0)
"""Text at 8 pt at print size (ticks, labels, panel titles), 7 pt in legends and notes."""
SLIDE = Medium("slide", column=5.9, wide=5.9, font=11.0, small=10.0, line=1.8, tiny=9.0)

SLIDE_COLUMN = 0.62 * 398.34 / 72.27
"""in: a slide column of 0.62 of the pitch's text width (398.34 pt), for a figure set beside
its bullets at its own size."""

FORMATS: tuple[str, ...] = (".pdf", ".png")
"""Formats every figure is saved in: PDF (LaTeX) and PNG (HTML); :func:`png_only` for drafts."""


@contextmanager
def png_only(enabled: bool = True) -> Iterator[None]:
    """Inside the block (when ``enabled``) save PNG only: LaTeX then includes the PNGs."""
    global FORMATS
    saved = FORMATS
    if enabled:
        FORMATS = (".png",)
    try:
        yield
    finally:
        FORMATS = saved


@contextmanager
def _figure(stem: Path, medium: Medium, width: float, height: float) -> Iterator[Figure]:
    rc = {
        **RC,
        "font.size": medium.font,
        "axes.titlesize": medium.font,
        "axes.labelsize": medium.font,
        "legend.fontsize": medium.small,
        "xtick.labelsize": medium.small,
        "ytick.labelsize": medium.small,
        "lines.linewidth": medium.line,
        "axes.titlepad": 3.0,
        "axes.labelpad": 2.0,
        "xtick.major.pad": 2.0,
        "ytick.major.pad": 2.0,
        "legend.handlelength": 1.8,
        "legend.borderaxespad": 0.3,
        "figure.constrained_layout.h_pad": 0.02,
        "figure.constrained_layout.w_pad": 0.02,
        "savefig.dpi": 170,
        "pdf.fonttype": 42,
        "mathtext.fontset": "stix",
        "font.family": "STIXGeneral",
    }
    with matplotlib.rc_context(rc):
        fig = Figure(figsize=(width, height), layout="constrained")
        FigureCanvasAgg(fig)
        yield fig
        stem.parent.mkdir(parents=True, exist_ok=True)
        fig.canvas.draw()  # lay out once (constrained), then keep the positions for every format
        fig.set_layout_engine("none")
        for suffix in FORMATS:
            fig.savefig(stem.with_suffix(suffix))


def _style(run: Run, medium: Medium) -> dict[str, Any]:
    base = CONTROLLER_STYLE.get(run.controller.name, {"color": OKABE_ITO[0], "linestyle": "-"})
    # in a pair both runs are drawn solid; the EMDM run dashed over the IVKC run reads better
    dashed = run.controller.name.endswith("EMDM")
    return {
        "color": base["color"],
        "linestyle": (0, (4, 1.5)) if dashed else "-",
        "linewidth": medium.line,
        "label": run.controller.name,
    }


def _label(ax: Any, text: str, medium: Medium) -> None:
    ax.text(
        0.015,
        0.96,
        text,
        transform=ax.transAxes,
        va="top",
        ha="left",
        fontsize=medium.small,
        fontweight="bold",
        bbox={"facecolor": "white", "edgecolor": "none", "pad": 0.6, "alpha": 0.8},
    )


def _common_scaled(runs: Sequence[Run]) -> list[tuple[float, float]]:
    """Time intervals on which every run of the pair is task-scaled (alpha < 1), if not all of it."""
    n = min(r.steps for r in runs)
    if n == 0:
        return []
    mask = np.all([r.scaled[:n] for r in runs], axis=0)
    if not mask.any() or mask.mean() > 0.6:
        return []
    dt = runs[0].scenario.motion.dt
    out = []
    padded = np.concatenate(([False], mask, [False])).astype(np.int8)
    edges = np.flatnonzero(np.diff(padded))
    for a, b in zip(edges[::2], edges[1::2], strict=True):
        out.append((a * dt, b * dt))
    return out


SCALED_SPAN: dict[str, Any] = {
    "facecolor": "#F0F0F0",
    "edgecolor": "#A8A8A8",
    "hatch": "////",
    "hatch_linewidth": 0.4,
    "linewidth": 0,
}
"""How the task-scaled time spans are drawn, and their legend patch: light grey hatched, so
that in a greyscale print they stay apart from the damper zones' plain tint."""


def _scaled_patch(label: str) -> Patch:
    """The legend entry of :func:`_shade`'s spans."""
    return Patch(**SCALED_SPAN, label=label)


def _shade(ax: Any, spans: list[tuple[float, float]]) -> None:
    for a, b in spans:
        ax.axvspan(a, b, **SCALED_SPAN, zorder=0)


def _column(fig: Figure, cell: Any, n: int) -> list[Axes]:
    """``n`` axes stacked without gaps in one grid cell, sharing the time axis."""
    grid = cell.subgridspec(n, 1, hspace=0.0)
    first = fig.add_subplot(grid[0, 0])
    return [first] + [fig.add_subplot(grid[j, 0], sharex=first) for j in range(1, n)]


EFFORT_FLOOR = 1e-9
"""Where :func:`pair_figure`'s log axis of the effort is floored (rad²/s²): a run at rest has
zero effort, which a log axis cannot draw."""


def time_end(runs: Sequence[Run]) -> float | None:
    """Where a figure's time axes end when some runs arrived and every other one had stalled by
    the last arrival (their records run on unchanged, within the stall band, to the time limit):
    the last arrival. ``None``: the whole records (nothing stalled, or nothing arrived)."""
    arrived = [float(r.t[-1]) for r in runs if r.reached]
    stalls = [(r, r.stalled_from) for r in runs if not r.reached]
    if not arrived or not stalls or any(k is None for _, k in stalls):
        return None
    end = max(arrived)
    return end if max(float(r.t[k]) for r, k in stalls if k is not None) <= end else None


BEYOND = "#E8E8E8"
"""The grey of what lies beyond a joint's position or speed limits in the pair figures' strips."""

FAR_BEYOND = 1.5
"""A joint whose speeds go beyond this multiple of its limit has its speed strip cut there (a
plain linear axis; :func:`pair_figure`): a spike of a step or two does not squash the motion
within the limits into a thin band, and no axis changes its scale part-way (readings found a
log band beyond the limits hard to read). The runs' peak speeds are Table I's column."""


GAP_FLOOR = 1e-6
"""Where :func:`pair_figure`'s log axis of the tracking gap is floored (m/s): a task imposed
exactly misses by rounding only (about 1e-16), drawn on the floor."""


def _damper_zones(ax: Any, lo: float, hi: float, influence: float, stop: float) -> None:
    """Shade a joint's damper zones against its position limits ``lo``, ``hi``: the influence
    zone light, the stop zone dark (the pair figures' (d) and Fig. 7's (c))."""
    for a, b, shade in (
        (hi - influence, hi, 0.3),
        (lo, lo + influence, 0.3),
        (hi - stop, hi, 0.55),
        (lo, lo + stop, 0.55),
    ):
        ax.axhspan(a, b, color="#D55E00", alpha=shade, linewidth=0, zorder=0)


def _beyond(ax: Any, lo: float, hi: float) -> None:
    """Shade grey what lies beyond a joint's limits ``lo``, ``hi`` in the strip ``ax`` (after
    its view is set)."""
    bottom, top = ax.get_ylim()
    for start, stop in ((hi, top), (bottom, lo)):
        if stop > start:
            ax.axhspan(start, stop, color=BEYOND, linewidth=0, zorder=0)


def tracking_gap(run: Run) -> np.ndarray:
    """Per command: how far the achieved tip velocity misses the desired one, ``||J(q_k) qd_k -
    v_d,k||`` (m/s), from the recorded states and commands (0 up to rounding for a run that
    imposes the task; the slack, or the scaled-off part ``(1 - alpha) ||v_d||``, otherwise)."""
    arm = run.scenario.planar_arm
    out = np.empty(run.steps)
    for k in range(run.steps):
        out[k] = np.linalg.norm(arm.jacobian(run.q[k]) @ run.qd[k] - run.v[k])
    return out


def pair_figure(
    runs: Sequence[Run],
    stem: Path,
    medium: Medium = PAPER,
    *,
    gap: bool = False,
    path: bool = False,
    without: tuple[str, Run] | None = None,
) -> Path:
    """A pair in one composite: (a) m(t), (b) the effort E(t) (log: the brief's "effort over
    time", readings 162-163; in-panel totals hid the curves: Table II has them),
    (c) the distance to the goal ||e||(t)
    above, (d) q(t) and (e) qd(t) below, one strip per joint. A fourth panel above, the joints
    then (e) and (f): ``gap``, (d) the velocity-tracking gap of :func:`tracking_gap` (the slack
    at work); ``path``, (d) the tip paths in the plane, start and goal marked (the tracking
    overlaid where it is exact). ``without``: ``(label, run)``, a run with one cause removed,
    drawn grey and dotted in every panel (Task 2.2's run without the dexterity term)."""
    if gap and path:
        raise ValueError("pair_figure: one fourth panel, the gap or the path")
    sc = runs[0].scenario
    n = sc.n
    spans = _common_scaled(runs)
    drawn = [(r, _style(r, medium)) for r in runs]
    if without is not None:
        label, extra = without
        drawn.append(
            (
                extra,
                {"color": "#666666", "linestyle": ":", "linewidth": medium.line, "label": label},
            )
        )
    every = [r for r, _ in drawn]
    upper_row = gap or path  # four panels above: narrower, so taller to stay legible
    height = ((2.5 if upper_row else 2.35) if n == 3 else 2.0) if medium is PAPER else 3.4
    with _figure(stem, medium, medium.column, height) as fig:
        # the joint strips get most of the height: limits, influence zones and a joint held near its
        # limit must be readable at column width (about 9 mm per strip in the paper), and the
        # panels above about 9 mm too (at 6 mm their three ticks crowded)
        outer = fig.add_gridspec(
            2, 1, height_ratios=[1.25 if upper_row else 1.1, 2.2 if n == 3 else 1.6]
        )
        upper = outer[0].subgridspec(1, 4 if gap or path else 3, wspace=0.12)  # labels clear
        # per joint: every run's lowest and highest speed, and the limit; a joint whose speed
        # goes far beyond its limit gets a strip cut at FAR_BEYOND times it
        extents = [_speed_extent(every, j) for j in range(n)]
        far_joints = {j for j, (lo_, hi_, lim) in enumerate(extents) if _far(lo_, hi_, lim)}
        lower = outer[1].subgridspec(1, 2)
        ax_m = fig.add_subplot(upper[0, 0])
        ax_e = fig.add_subplot(upper[0, 1], sharex=ax_m)
        ax_err = fig.add_subplot(upper[0, 2], sharex=ax_m)
        ax_gap = fig.add_subplot(upper[0, 3], sharex=ax_m) if gap else None
        ax_path = fig.add_subplot(upper[0, 3]) if path else None
        q_axes = _column(fig, lower[0, 0], n)
        qd_axes = _column(fig, lower[0, 1], n)
        for run, st in drawn:
            ax_m.plot(run.t, run.m, **st)
            ax_e.semilogy(run.t[:-1], np.maximum(run.effort, EFFORT_FLOOR), **st)
            ax_err.semilogy(run.t, np.maximum(run.error_norm, 1e-4), **st)
            if ax_gap is not None:
                ax_gap.semilogy(run.t[:-1], np.maximum(tracking_gap(run), GAP_FLOOR), **st)
            if ax_path is not None:
                ax_path.plot(run.p[:, 0], run.p[:, 1], **st)
            for j in range(n):
                q_axes[j].plot(run.t, run.q[:, j], **st)
                qd_axes[j].plot(run.t[:-1], run.qd[:, j], **st)
        upper_axes = [ax_m, ax_e, ax_err, *([ax_gap] if ax_gap is not None else [])]
        for ax in (*upper_axes, *q_axes, *qd_axes):
            _shade(ax, spans)
        if ax_path is not None:  # in the plane, not in time: start (circle) and goal (star)
            start, goal = runs[0].p[0], runs[0].p[0] + runs[0].e[0]
            # the straight line a continuous-time P controller would follow, under the paths
            ax_path.plot(*zip(start, goal, strict=True), ":", color="black", lw=0.6, zorder=1)
            ax_path.plot(*start, "o", color="black", markersize=3, zorder=4, clip_on=False)
            ax_path.plot(*goal, "*", color="black", markersize=5, zorder=4, clip_on=False)
            ax_path.margins(0.1)
            ax_path.set_xlabel(r"$x$ (m)", labelpad=1)
            ax_path.set_ylabel(r"$y$ (m)", labelpad=1)
            ends = sorted(round(float(v), 1) for v in (start[0], goal[0]))
            if ends[1] - ends[0] > 0.5 * np.ptp(np.concatenate([r.p[:, 0] for r in runs])):
                ax_path.set_xticks(ends, [_plain(v) for v in ends])  # where the tip starts, ends
            else:
                ax_path.xaxis.set_major_locator(MaxNLocator(2))
            ax_path.yaxis.set_major_locator(MaxNLocator(3))
            ax_path.set_title("(d)", loc="left", fontsize=medium.small, fontweight="bold", pad=2)
        ax_err.axhline(sc.motion.tolerance, color="black", linewidth=0.6, linestyle=":")
        ax_m.set_ylabel(r"$m$ (m$^2$)", labelpad=1)
        ax_e.set_ylabel(r"$E$ (rad$^2$/s$^2$)", labelpad=1)
        ax_err.set_ylabel(r"$\|e\|$ (m)", labelpad=1)
        if ax_gap is not None:
            ax_gap.set_ylabel("gap (m/s)", labelpad=1)  # the caption names it
            # the floor inside the frame: a run on it (an exact task) is a line, not the frame
            ax_gap.set_ylim(bottom=GAP_FLOOR / 4)
        for ax in upper_axes:  # in print the strips' time label serves (its height went to the
            # panels, readings 150-155: too small); a slide has room for each
            if medium is not PAPER:
                ax.set_xlabel(r"$t$ (s)", labelpad=1)
        ax_m.yaxis.set_major_locator(MaxNLocator(3))
        for ax in upper_axes[1:]:
            ax.yaxis.set_major_locator(LogLocator(numticks=3))
            ax.yaxis.set_minor_locator(NullLocator())
        # time in seconds on every panel: its label only under the joint strips
        lo, hi = sc.arm.q_min, sc.arm.q_max
        for j in range(n):
            ax = q_axes[j]
            _damper_zones(ax, lo[j], hi[j], sc.damper.influence[j], sc.damper.stop[j])
            for bound in (lo[j], hi[j]):
                ax.axhline(bound, color="black", linewidth=0.6)
            ax.set_ylabel(rf"$q_{j + 1}$", labelpad=1)
            qd_axes[j].set_ylabel(rf"$\dot q_{j + 1}$", labelpad=1)
            for bound in (sc.arm.qd_min[j], sc.arm.qd_max[j]):
                qd_axes[j].axhline(bound, color="black", linewidth=0.6, linestyle=":")
            low, high, limit = extents[j]
            far = j in far_joints
            # a run far beyond the limits (dotted) is cut at FAR_BEYOND times them, so the
            # motion within the limits keeps the strip (the runs' peak speeds are Table I's).
            # Cut at FAR_BEYOND, not at the limit: an excursion just past the limit on the
            # other side stays in view
            lo_view, hi_view = 1.15 * min(low, -limit), 1.15 * max(high, limit)
            if far:  # cut at FAR_BEYOND times the limit, beyond the limits lightly shaded
                lo_view = max(lo_view, -FAR_BEYOND * limit)
                hi_view = min(hi_view, FAR_BEYOND * limit)
            qd_axes[j].set_ylim(lo_view, hi_view)
            _beyond(qd_axes[j], -limit, limit)
            if far:
                # the peak the cut hides, written at the cut edge's right end, where the runs
                # have settled (readings 209, 212, 214: the limit violations could not be seen)
                # in the colour of the run it is (reading 216: the labels mixed controllers)
                for side, pick in (("top", max), ("bottom", min)):
                    peak, st = pick(
                        ((float(pick(r.qd[:, j])) if r.steps else 0.0, st) for r, st in drawn),
                        key=lambda pair: pair[0],
                    )
                    if abs(peak) > FAR_BEYOND * limit:
                        qd_axes[j].text(
                            0.99,
                            0.96 if side == "top" else 0.04,
                            f"peak {_plain(float(f'{peak:.3g}'))}",
                            color=st["color"],
                            transform=qd_axes[j].transAxes,
                            ha="right",
                            va=side,
                            fontsize=medium.tiny - 1,
                            bbox={"facecolor": "white", "edgecolor": "none", "pad": 0.3},
                            zorder=5,
                        )
            bottom = min(float(lo[j]), min(float(r.q[:, j].min()) for r in every))
            top_q = max(float(hi[j]), max(float(r.q[:, j].max()) for r in every))
            margin = 0.12 * (top_q - bottom)  # the limit lines stay clear of the frame
            qspan = [bottom - margin, top_q + margin]
            ax.set_ylim(*qspan)
            # beyond the limits grey, as in the speed strips (reading 220: UC-EMDM's q1, 0.71 rad
            # past its limit in Task 2, did not read as a violation)
            _beyond(ax, float(lo[j]), float(hi[j]))
            # two ticks per strip (three collide at this height): the position limits and the
            # velocity limits
            q_tick = float(max(abs(lo[j]), abs(hi[j])))
            qd_tick = limit
            for a, tick in ((ax, q_tick), (qd_axes[j], qd_tick)):
                a.set_yticks([-tick, tick], [_plain(-tick), _plain(tick)])
                a.yaxis.set_minor_locator(matplotlib.ticker.NullLocator())
                if j < n - 1:
                    a.tick_params(labelbottom=False)
        end = time_end(runs)
        if end is not None:  # the stalled runs' flat tails add nothing: the arrivals get room
            for ax in (ax_m, q_axes[0], qd_axes[0]):  # each shares its time axis with others
                ax.set_xlim(-0.02 * end, 1.03 * end)
        # the two joint columns side by side read one time axis: the same ticks (each column
        # would pick its own for its width, 0/5/10/15 beside 0/10)
        for ax in (q_axes[0], qd_axes[0]):
            ax.xaxis.set_major_locator(MaxNLocator(nbins=3, steps=[1, 2, 5, 10]))
        q_axes[-1].set_xlabel(r"$t$ (s)")
        qd_axes[-1].set_xlabel(r"$t$ (s)")
        joint_q, joint_qd = ("(e)", "(f)") if gap or path else ("(d)", "(e)")
        q_axes[0].set_title(
            rf"$\bf {joint_q}$ $q$ (rad), limits, influence zones", fontsize=medium.small, pad=2
        )
        qd_axes[0].set_title(
            rf"$\bf {joint_qd}$ $\dot q$ (rad/s), limits dotted", fontsize=medium.small, pad=2
        )
        # panel letters above the axes, where no curve can hide them
        for ax, letter in zip(upper_axes, ("(a)", "(b)", "(c)", "(d)"), strict=False):
            ax.set_title(letter, loc="left", fontsize=medium.small, fontweight="bold", pad=2)
        handles: list[Artist] = [Line2D([], [], **st) for _, st in drawn]
        if spans:
            handles.append(_scaled_patch(r"both task-scaled ($\alpha^*<1$)"))
        fig.legend(
            handles=handles,
            loc="outside upper center",
            ncols=min(len(handles), 4),
            frameon=False,
            columnspacing=1.0,
        )
    return stem


def _speed_extent(runs: Sequence[Run], j: int) -> tuple[float, float, float]:
    """Joint ``j``'s lowest and highest speed over ``runs`` (0 for a run without steps) and its
    speed limit (the larger of the two bounds' magnitudes)."""
    arm = runs[0].scenario.arm
    high = max(float(r.qd[:, j].max()) if r.steps else 0.0 for r in runs)
    low = min(float(r.qd[:, j].min()) if r.steps else 0.0 for r in runs)
    return low, high, float(max(abs(arm.qd_min[j]), abs(arm.qd_max[j])))


def _far(low: float, high: float, limit: float) -> bool:
    """Whether a speed range goes far beyond its limit (:data:`FAR_BEYOND` times it)."""
    return max(high, -low) > FAR_BEYOND * limit


def _arm_points(run: Run, q: np.ndarray) -> np.ndarray:
    return np.asarray(run.scenario.planar_arm.joint_positions(q))


def workspace_figure(
    runs: Sequence[Run], geometry: dict[str, Any], stem: Path, medium: Medium = PAPER
) -> Path:
    """A two-link pair in the workspace: the blocked disc, the straight line, the goal's two
    inverse-kinematics solutions, each run's path, its stall point and its elbow flip."""
    sc = runs[0].scenario
    reach = geometry["reach"]
    inner = geometry["inner_reach"]
    width = medium.column if medium is PAPER else 3.9  # on a slide: 0.62 of its width
    height = 1.3 if medium is PAPER else 3.3
    with _figure(stem, medium, width, height) as fig:
        ax = fig.add_subplot()
        ax.add_patch(Circle((0, 0), reach, color="#BBBBBB", alpha=0.25, linewidth=0))
        ax.add_patch(
            Circle(
                (0, 0),
                inner,
                facecolor="none",
                edgecolor="#D55E00",
                hatch="////",
                linewidth=0.6,
                alpha=0.4,  # light: C-IVKC's path, in the same hue, stays clear of it in grey
            )
        )
        p0 = runs[0].p[0]
        goal = np.asarray(sc.motion.goal)
        # the line C-IVKC keeps to: dark, above the hatching, under the paths (the stalled run
        # drawn along it stays visible, and the line beyond its stall too)
        line_style: dict[str, Any] = {
            "color": "black",
            "linestyle": (0, (1, 1.2)),
            "linewidth": 1.0,
        }
        ax.plot([p0[0], goal[0]], [p0[1], goal[1]], **line_style, zorder=2.5)
        drawn = [runs[0].p[:1], goal[None, :], *(r.p[:, :2] for r in runs)]
        for sol in geometry["solutions"]:
            pts = _arm_points(runs[0], np.array([sol["q1"], sol["q2"]]))
            drawn.append(pts[:, :2])
            ax.plot(
                pts[:, 0],
                pts[:, 1],
                color="black" if sol["within_limits"] else "#888888",
                # dash-dot: in a greyscale print, not to be taken for a dashed run's path
                linestyle="-" if sol["within_limits"] else "-.",
                linewidth=0.8 * medium.line,
                marker="o",
                markersize=2.5,
            )
        start = _arm_points(runs[0], runs[0].q[0])
        drawn.append(start[:, :2])
        ax.plot(  # thinner than the paths, which may run along its links (C-IVKC's does)
            start[:, 0],
            start[:, 1],
            color="black",
            linewidth=medium.line * 0.8,
            marker="o",
            markersize=3,
        )
        for run in runs:
            st = _style(run, medium)
            # above the dotted straight line it may run along (C-IVKC's stalled path does)
            ax.plot(
                run.p[:, 0], run.p[:, 1], **{**st, "linewidth": 1.4 * st["linewidth"]}, zorder=3
            )
            if not run.reached:
                ax.plot(
                    *run.p[-1],
                    marker="X",
                    color=st["color"],
                    markersize=7 if medium is PAPER else 10,
                    linestyle="none",
                    markeredgecolor="black",
                    markeredgewidth=0.5,
                )
            s = np.sign(np.sin(run.q[:, 1]))
            flips = np.flatnonzero(s[1:] * s[:-1] < 0) + 1
            for f in flips:
                ax.plot(
                    *run.p[f],
                    marker="o",
                    markersize=6 if medium is PAPER else 9,
                    markerfacecolor="white",
                    markeredgecolor=st["color"],
                    markeredgewidth=1.2,
                    linestyle="none",
                    clip_on=False,  # whole even where it meets the frame (reading 195)
                )
        ax.plot(
            *goal,
            marker="*",
            color="black",
            markersize=9 if medium is PAPER else 13,
            linestyle="none",
        )
        ax.set_aspect("equal")
        # the view fits what is drawn (arms, paths, goal), not the whole reachable disc: at
        # column width every millimetre of the square goes to the paths
        box = np.concatenate(drawn)
        pad = 0.1 * reach  # (at 0.08 the elbow flip's marker met the frame: reading 195)
        ax.set_xlim(box[:, 0].min() - pad, box[:, 0].max() + pad)
        ax.set_ylim(box[:, 1].min() - pad, box[:, 1].max() + pad)
        ax.set_xlabel(r"$x$ (m)")
        ax.set_ylabel(r"$y$ (m)")
        handles: list[Artist] = [Line2D([], [], **_style(r, medium)) for r in runs]
        if medium is not PAPER:  # a slide names the start and the goal where they are, and
            # leaves the grey disc unnamed: a legend of ten entries was too much to read in a talk
            for xy, name, offset, ha in (
                (p0[:2], "start", (5, -8), "left"),  # right of it: above, the frame cut it
                (goal, "goal", (-7, 8), "right"),
            ):
                ax.annotate(
                    name,
                    (float(xy[0]), float(xy[1])),
                    xytext=offset,
                    textcoords="offset points",
                    fontsize=medium.tiny,
                    ha=ha,
                    va="center",
                    # on white: a name that reaches over the frame is not struck through
                    bbox={"facecolor": "white", "edgecolor": "none", "pad": 0.6},
                )
        handles += [
            *([Patch(color="#BBBBBB", alpha=0.25, label="reachable")] if medium is PAPER else []),
            Line2D([], [], **line_style, label="straight line"),
            Patch(
                facecolor="none",
                edgecolor="#D55E00",
                hatch="////",
                label=rf"blocked: $\|p\|<{inner:.3f}$ m",
            ),
            Line2D(  # (a slide names them too: its legend had not, reading 163)
                [],
                [],
                color="black",
                linewidth=0.8 * medium.line,
                marker="o",
                markersize=2.5,
                label="arm: start, goal",
            ),
            *(
                [
                    Line2D(
                        [],
                        [],
                        color="black",
                        marker="*",
                        markersize=6,
                        linestyle="none",
                        label="goal",
                    ),
                ]
                if medium is PAPER
                else []
            ),
            Line2D(
                [],
                [],
                color="#888888",
                linestyle="-.",
                marker="o",
                markersize=2.5,
                label="elbow-up goal (past $q_1$ limit)",
            ),
            Line2D(  # in the colour of the run that stalls, as drawn
                [],
                [],
                color=next((_style(r, medium)["color"] for r in runs if not r.reached), "black"),
                marker="X",
                linestyle="none",
                label="stall",
            ),
            Line2D(
                [],
                [],
                marker="o",
                markerfacecolor="white",
                markeredgecolor="black",
                linestyle="none",
                label=r"elbow flip",
            ),
        ]
        fig.legend(  # on a slide under the axes, in two columns: beside them it took their width
            handles=handles,
            loc="outside right center" if medium is PAPER else "outside lower center",
            ncols=1 if medium is PAPER else 2,
            frameon=False,
            fontsize=medium.tiny,
            handlelength=1.6,
            labelspacing=0.35,
            columnspacing=1.0,
        )
    return stem


NOTE_COLOR = "#A0410A"
"""A warning note in a figure (runs not reached): a dark vermilion, which prints at about a
third of full grey, where the vermilion of the lines (#D55E00) printed pale."""


def _missed_note(
    ax: Axes, bad: Sequence[dict[str, Any]], what: str, top: float, medium: Medium
) -> None:
    """Name the weight settings whose runs are not drawn, at the axes' left from ``top``
    (an axes fraction): ``w_M/w_E = 10^3:`` and, below, ``what`` befell them."""
    text = ", ".join(_ratio_tex(r["w_manip"] / r["w_effort"]) for r in bad)
    ax.text(
        0.03,
        top,
        rf"$w_M/w_E={text}$:" + "\n" + what,
        transform=ax.transAxes,
        ha="left",
        va="top",
        fontsize=medium.tiny,
        color=NOTE_COLOR,
    )


def _plain(v: float) -> str:
    """A tick label in shortest form with a true minus sign, as matplotlib's own ticks have
    (a fixed label is written as given: ``f"{-2:g}"`` would print a hyphen)."""
    return f"{v:g}".replace("-", "\N{MINUS SIGN}")


def _ratio_tex(ratio: float) -> str:
    """A weight ratio as math: ``10^{3}`` for powers of ten, ``5.62\times10^{3}`` for others
    beyond [0.01, 1000), else three digits (never a computer's ``5.62e+03``)."""
    if ratio > 0 and abs(math.log10(ratio) - round(math.log10(ratio))) < 1e-9:
        return rf"10^{{{round(math.log10(ratio))}}}"
    if ratio > 0 and not 0.01 <= ratio < 1000:
        mantissa, exponent = f"{ratio:.2e}".split("e")
        return rf"{mantissa}\times10^{{{int(exponent)}}}"
    return f"{ratio:.3g}"


def _value_axis(ax: Any, values: Any) -> None:
    """A log y axis with labelled decades where the values span more than a factor of 30, else a
    linear one with three plain ticks: a log axis within one decade shows no label at all."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v) & (v > 0)]
    if v.size and v.max() > 30 * v.min():
        ax.set_yscale("log")
        _log_axis(ax.yaxis)
    else:
        ax.yaxis.set_major_locator(matplotlib.ticker.MaxNLocator(3))


def _log_axis(axis: Any) -> None:
    """Major decades only, no minor labels (they crowd small panels)."""
    axis.set_major_locator(matplotlib.ticker.LogLocator(numticks=4))
    axis.set_minor_formatter(matplotlib.ticker.NullFormatter())


def _ring(ax: Any, x: float, y: float, medium: Medium) -> None:
    """The orange ring that marks the nominal weights."""
    ax.scatter(
        [x],
        [y],
        s=45 if medium is PAPER else 110,
        facecolors="none",
        edgecolors="#D55E00",
        linewidths=1.1,
        zorder=3,
        clip_on=False,  # whole even where the nominal point lies on the axes' edge
    )


def _front_axes(
    ax: Any,
    step: dict[str, Any],
    info: dict[str, Any],
    medium: Medium,
    norm: Any,
) -> Any:
    pts = step["points"]
    slack = step.get("slack_points")  # a scaled step's front under the free slack (6)
    ratio = np.array([p["w_manip"] / p["w_effort"] for p in pts])
    E = np.array([p["E"] for p in pts])
    M = np.array([p["M"] for p in pts])
    ax.plot(M, E, color="grey", linewidth=0.5, zorder=1)
    sc = ax.scatter(
        M,
        E,
        c=np.log10(np.maximum(ratio, 1e-4)),
        cmap="viridis",
        norm=norm,
        s=9 if medium is PAPER else 22,
        zorder=2,
        linewidths=0,
    )
    near = int(info["nominal_index"])  # the point of the nominal ratio, found with the data
    _ring(ax, M[near], E[near], medium)
    _value_axis(ax, E)
    note = ""
    if info["degenerate"]:
        note = "one point\n" + rf"($\alpha^*={info['alpha']:.2f}$)"
        if slack:  # the hollow point beside it is another program's: one point each (readings
            # 227-229 counted two markers under "one point")
            note = (
                "one point each:\n"
                + rf"scaled ($\alpha^*={info['alpha']:.2f}$),"
                + "\nhollow: free slack"
            )
    elif info["saturated_from_ratio"] is not None:
        # three short lines: a note as wide as its ratio ran into the front's nominal ring
        least = _ratio_tex(info["saturated_from_ratio"])
        note = "saturated\nfor $w_M/w_E$\n" + rf"$\geq{least}$"
    if note:  # where it covers fewest points (a front runs from lower left to upper right)
        drawn = [(p["M"], p["E"]) for p in step.get("slack_points", [])]
        points = np.vstack((np.column_stack((M, E)), np.reshape(drawn, (-1, 2))))
        ax.get_xlim(), ax.get_ylim()  # the limits settled, so that transData places the points
        renderer = ax.figure.canvas.get_renderer()
        covered: list[tuple[int, Artist]] = []
        corners = (  # in this order of preference where they cover as few points
            (0.04, 0.95, "left", "top"),
            (0.97, 0.05, "right", "bottom"),
            (0.97, 0.45, "right", "center"),
        )
        for x, y, ha, va in corners:
            text = ax.text(
                x,
                y,
                note,
                transform=ax.transAxes,
                ha=ha,
                va=va,
                fontsize=medium.tiny,
                linespacing=1.05,  # three lines in a panel under 0.5 in tall
                bbox={"facecolor": "white", "edgecolor": "none", "pad": 0.5, "alpha": 0.85},
                zorder=1.5,  # under the front's points (zorder 2): a note never hides one
            )
            # a point counts as covered when its marker would touch the note: the box is
            # padded by the nominal ring's radius (the largest marker, about 4 pt)
            box = text.get_window_extent(renderer).padded(4.0 * ax.figure.dpi / 72.0)
            inside = sum(box.contains(*xy) for xy in ax.transData.transform(points))
            covered.append((int(inside), text))
        for _, text in sorted(covered, key=lambda c: c[0])[1:]:  # keep the one covering fewest
            text.remove()
    if slack and info["degenerate"]:  # the points to the right, the note beside them on the left
        x = float(np.mean([M[0], *(p["M"] for p in slack)]))
        span = 0.1 * abs(x) + 1e-3
        ax.set_xlim(x - 0.88 * span, x + 0.12 * span)
        energies = [E[0], *(p["E"] for p in slack)]
        low, high = min(energies), max(energies)
        ax.set_ylim(low - 0.3 * (high - low) - 1e-3, high + 0.3 * (high - low) + 1e-3)
    if slack:  # the same state under the free slack (6): a front again, hollow
        ax.plot([p["M"] for p in slack], [p["E"] for p in slack], color="grey", lw=0.5, zorder=1)
        size = 14 if medium is PAPER else 30
        ax.scatter(  # a thin dark ring around each (a light colour stays visible in grey),
            # white within: points that overlap (a front of nearly one point) stay hollow
            [p["M"] for p in slack],
            [p["E"] for p in slack],
            facecolors="white",
            edgecolors="#333333",
            s=size * 4.0,
            linewidths=0.35,
            zorder=2,
        )
        ax.scatter(
            [p["M"] for p in slack],
            [p["E"] for p in slack],
            facecolors="none",
            edgecolors=matplotlib.colormaps["viridis"](
                norm(np.log10(np.maximum([p["w_manip"] / p["w_effort"] for p in slack], 1e-4)))
            ),
            s=size * 3.0,  # a ring much wider than its line: it reads as hollow in print
            linewidths=0.8,
            zorder=2,
        )
    elif info["degenerate"]:
        x, y = M[0], E[0]
        ax.set_xlim(x - 0.5 * abs(x) - 1e-3, x + 0.5 * abs(x) + 1e-3)
        ax.set_ylim(0.5 * y, 1.5 * y)
    ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(3))
    ax.ticklabel_format(axis="x", style="sci", scilimits=(-2, 3), useMathText=True)
    ax.xaxis.get_offset_text().set_fontsize(medium.tiny)
    return sc


def pareto_figure(
    fronts: dict[str, dict[str, Any]],
    infos: dict[str, list[dict[str, Any]]],
    grids: dict[str, list[dict[str, Any]]],
    stem: Path,
    medium: Medium = PAPER,
) -> Path:
    """Rows: controllers (``fronts`` keys); columns: the fronts of the brief's four steps and the
    whole-run trade-off (mean m against total effort per weight setting; the settings that fail
    to reach are named). The paper's Fig. 2 (the pitch's is :func:`pareto_slide_figure`)."""
    names = list(fronts)
    norm = matplotlib.colors.Normalize(vmin=-3, vmax=4)
    width = medium.wide
    height = (0.92 * len(names) + 0.2) if medium is PAPER else 2.7
    steps = range(len(next(iter(fronts.values()))["steps"]))
    whole = len(steps)
    with _figure(stem, medium, width, height) as fig:
        axes = fig.subplots(len(names), whole + 1, squeeze=False)
        sc = None
        for row, name in enumerate(names):
            data = fronts[name]
            for col, index in enumerate(steps):
                step, info = data["steps"][index], infos[name][index]
                ax = axes[row, col]
                sc = _front_axes(ax, step, info, medium, norm)
                # (on a slide's narrower panels, two lines: side by side the titles touched)
                sep = ",\n" if medium is SLIDE else ", "
                ax.set_title(rf"$k={step['k']}${sep}$t={step['t']:.2f}$ s", fontsize=medium.small)
                if col == 0:
                    ax.set_ylabel(f"{name}\n" + r"$E$ (rad$^2$/s$^2$)")
                ax.set_xlabel(r"$M$ (m$^2$/s)", labelpad=1)  # every row: its own scale
            ax = axes[row, whole]
            rows = grids[name]
            ok = [r for r in rows if "error" not in r and r.get("reached")]
            bad = [r for r in rows if "error" in r or not r.get("reached")]
            ratio = np.array([r["w_manip"] / r["w_effort"] for r in ok])
            ax.plot(
                [r["mean_manipulability"] for r in ok],
                [r["total_effort"] for r in ok],
                color="grey",
                linewidth=0.5,
                zorder=1,
            )
            ax.scatter(
                [r["mean_manipulability"] for r in ok],
                [r["total_effort"] for r in ok],
                c=np.log10(np.maximum(ratio, 1e-4)),
                cmap="viridis",
                norm=norm,
                s=12 if medium is PAPER else 26,
                zorder=2,
                linewidths=0,
            )
            nominal = fronts[name]["nominal_ratio"]
            nom = [r for r in ok if np.isclose(r["w_manip"] / r["w_effort"], nominal)]
            if nom:
                _ring(ax, nom[0]["mean_manipulability"], nom[0]["total_effort"], medium)
            _value_axis(ax, [r["total_effort"] for r in ok])
            if bad:  # the runs that fail are not drawn (their effort would flatten the others)
                _missed_note(ax, bad, "not reached,\nnot drawn", 0.97, medium)
            ax.set_title("whole runs", fontsize=medium.small)
            ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(3))
            ax.set_xlabel(r"mean $m$ (m$^2$)", labelpad=1)
            ax.set_ylabel(r"$\sum E\,\Delta t$ (rad$^2$/s)", labelpad=1)
        assert sc is not None
        bar = fig.colorbar(sc, ax=axes, shrink=0.8, pad=0.01, aspect=30)
        bar.set_label(r"$\log_{10} w_M/w_E$ (circle: nominal)")
        fig.canvas.draw()  # the formatters now know their scale: fold it into the labels
        for ax in axes[:, :whole].ravel():
            power = _offset_power(ax.xaxis.get_major_formatter())
            if power:
                ax.xaxis.get_offset_text().set_visible(False)
                ax.set_xlabel(rf"$M$ ($10^{{{power}}}$ m$^2$/s)")
    return stem


def pareto_slide_figure(
    nominal: float,
    grid: list[dict[str, Any]],
    stem: Path,
    width: float | None = None,
    height: float = 2.5,
    medium: Medium = SLIDE,
) -> Path:
    """The pitch's trade-off, for peers: one idea, the whole runs' mean m against their total
    effort, one run per weight ratio (``grid``, the sweep's records), on linear axes with no
    colour scale; the ends and the ``nominal`` ratio's run named where they are (effort only,
    nominal, the most dexterity-weighted that arrives), the settings that miss the goal named
    in a note and not drawn (readings 209-222: the slide's three panels, with one step's front
    and the nominal weights' price per step, were too technical for a peer talk). The paper's
    :func:`pareto_figure` shows every front."""
    width = 0.55 * medium.wide if width is None else width
    ok = [r for r in grid if "error" not in r and r.get("reached")]
    bad = [r for r in grid if "error" in r or not r.get("reached")]

    def ratio(r: dict[str, Any]) -> float:
        return float(r["w_manip"] / r["w_effort"])

    x = [float(r["mean_manipulability"]) for r in ok]
    y = [float(r["total_effort"]) for r in ok]
    nom = next((i for i, r in enumerate(ok) if np.isclose(ratio(r), nominal)), None)
    with _figure(stem, medium, width, height) as fig:
        ax = fig.subplots()
        ax.plot(x, y, color="grey", linewidth=0.6, zorder=1)
        ax.scatter(x, y, s=14, color="#0072B2", zorder=2, linewidths=0)
        if nom is not None:
            _ring(ax, x[nom], y[nom], medium)
        ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(4))
        ax.set_xlim(min(x) - 0.06 * (max(x) - min(x)), max(x) + 0.06 * (max(x) - min(x)))
        ends = [(0, "effort only", (0.05, 0.22, "left"))]
        if nom is not None:
            ends.append((nom, "nominal", (0.78, 0.32, "right")))
        ends.append((len(x) - 1, rf"$w_M/w_E={_ratio_tex(ratio(ok[-1]))}$", (0.62, 0.92, "right")))
        to_axes = ax.transAxes + ax.transData.inverted()
        for at, label, (x_text, y_text, ha) in ends:
            ax.annotate(
                label,
                (x[at], y[at]),
                xytext=tuple(to_axes.transform((x_text, y_text))),
                fontsize=medium.tiny,
                ha=ha,
                va="center",
                arrowprops={"arrowstyle": "-", "color": "grey", "linewidth": 0.6},
            )
        ax.set_xlabel(r"mean manipulability $m$ (m$^2$)")
        ax.set_ylabel(r"total effort (rad$^2$/s)")
        if bad:  # not drawn: their effort would flatten the others
            _missed_note(ax, bad, "misses the goal", 0.78, medium)
    return stem


def _offset_power(formatter: Any) -> int:
    """The power of ten a scalar formatter has taken out of its tick labels (0: none), read
    from the offset text it draws (``×10^{-5}``; the attribute that held it is private since
    Matplotlib 3.11)."""
    found = re.search(r"10\^\{([-\u2212]?\d+)\}", formatter.get_offset() if formatter else "")
    return int(found.group(1).replace("\u2212", "-")) if found else 0  # (a typographic minus)


FAMILY_MARKER = {"exact": "s", "gradient": "o", "gradient-free": "^"}


def _family_handles(rows: Mapping[str, Any], order: Sequence[str]) -> list[Artist]:
    """One legend entry per solver family drawn (its marker and colour), in family order."""
    return [
        Line2D(
            [],
            [],
            marker=FAMILY_MARKER[f],
            color=FAMILY_COLOR[f],
            linestyle="none",
            label=Family(f).label,
        )
        for f in ("exact", "gradient", "gradient-free")
        if any(rows[k]["family"] == f for k in order)
    ]


def solver_figure(lab: dict[str, Any], dt: float, stem: Path, medium: Medium = PAPER) -> Path:
    """Per solver (rows, grouped by family): median time per program (left, with the control
    period) and the largest gap to the exact optimum (right; bound violations marked)."""
    rows = lab["solvers"]
    order = [
        k
        for f in ("exact", "gradient", "gradient-free")
        for k, r in rows.items()
        if r["family"] == f
    ]
    floor = 1e-12
    height = (0.5 + 0.15 * len(order)) if medium is PAPER else 2.7
    width = medium.column if medium is PAPER else 3.3  # on a slide: half its width
    with _figure(stem, medium, width, height) as fig:
        left, right = fig.subplots(1, 2, sharey=True)
        y = np.arange(len(order))[::-1]
        for yi, name in zip(y, order, strict=True):
            r = rows[name]
            style = {
                "marker": FAMILY_MARKER.get(r["family"], "o"),
                "color": FAMILY_COLOR.get(r["family"], "grey"),
                "markersize": 4.5 if medium is PAPER else 7,
                "linestyle": "none",
            }
            left.plot([r["median_time"] * 1e3], [yi], **style)
            gap = r["max_abs_gap"]
            right.plot([max(gap, floor) if math.isfinite(gap) else floor], [yi], **style)
            if math.isfinite(r["max_violation"]) and r["max_violation"] > 1e-6:
                right.plot(
                    [max(r["max_violation"], floor)],
                    [yi],
                    marker="x",
                    color="#D55E00",
                    markersize=5 if medium is PAPER else 8,
                    linestyle="none",
                )
        left.set_yticks(y, order)
        left.set_xscale("log")
        right.set_xscale("log")
        _log_axis(right.xaxis)
        # three labelled decades at most on the gap axis: more run together at this width
        right.xaxis.set_major_locator(matplotlib.ticker.LogLocator(numticks=3))
        left.axvline(dt * 1e3, color="black", linestyle="--", linewidth=0.8)
        left.text(dt * 1e3, y[0], r"$\Delta t$ ", fontsize=medium.small, va="center", ha="right")
        left.set_xlabel("median time (ms)")
        slowest = max(r["median_time"] for r in rows.values() if math.isfinite(r["median_time"]))
        left.set_xlim(None, 3e3 * max(slowest, dt))  # no marker clipped at the edge
        right.set_xlabel(r"gap $f-f^{*}$")
        right.axvspan(floor / 4, floor * 4, color="#0072B2", alpha=0.10, linewidth=0)
        finite = [
            v
            for r in rows.values()
            for v in (r["max_abs_gap"], r["max_violation"])
            if math.isfinite(v) and v > 0
        ]
        right.set_xlim(floor / 10, 30 * max([1.0, *finite]))  # no marker clipped at the edge
        left.set_ylim(-0.6, len(order) - 0.1)
        handles = _family_handles(rows, order)  # first: a reader must not guess them
        handles.append(
            Line2D([], [], color="#D55E00", marker="x", linestyle="none", label="bound violation")
        )
        fig.legend(  # below the panels, where it hides no marker
            handles=[
                *handles,
                Patch(color="#0072B2", alpha=0.25, label=r"gap $\leq 10^{-12}$"),
            ],
            loc="outside lower center",
            ncols=3,
            frameon=False,
            fontsize=medium.tiny,
            handletextpad=0.3,
            columnspacing=1.0,
        )
    return stem


def solver_verdict_figure(
    lab: dict[str, Any], dt: float, stem: Path, omit: Sequence[str] = ()
) -> Path:
    """The pitch's solver slide: one axis, the median time per program of each solver (rows by
    family, the control period dashed), and in a column beside the axes, in words, whether its
    answer is the optimum: ``exact`` (:func:`~emdm.studies.lab.exact_answer`, filled), else
    hollow with ``within 10^-k``, ``off by g``, and ``out of bounds`` (violation above 1e-6),
    then the median objective evaluations of the solvers that count them (``522 evals``), and
    a gradient method's gradient evaluations (``6 evals + 5 grads``). The solvers in ``omit``
    are left out (the pitch's: the controls and fallbacks a peer need not meet). The paper's
    :func:`solver_figure` plots the gaps on an axis."""
    rows = {k: r for k, r in lab["solvers"].items() if k not in omit}
    order = [
        k
        for f in ("exact", "gradient", "gradient-free")
        for k, r in rows.items()
        if r["family"] == f
    ]
    medium = SLIDE
    with _figure(stem, medium, 3.8, 3.0) as fig:  # beside the slide's bullets (0.64 of its width)
        # the verdicts in an axes of their own, so that the layout keeps room for them
        ax, words = fig.subplots(
            1, 2, sharey=True, gridspec_kw={"width_ratios": (1.5, 1.15), "wspace": 0}
        )
        words.axis("off")
        y = np.arange(len(order))[::-1]
        times = [rows[k]["median_time"] * 1e3 for k in order]
        for yi, name, t in zip(y, order, times, strict=True):
            r = rows[name]
            gap, violation = abs(r["max_abs_gap"]), r["max_violation"]
            exact = exact_answer(gap, violation)  # the paper's criterion: filled
            colour = FAMILY_COLOR.get(r["family"], "grey")
            ax.plot(
                [t],
                [yi],
                marker=FAMILY_MARKER.get(r["family"], "o"),
                color=colour,
                markerfacecolor=colour if exact else "white",
                markersize=7,
                linestyle="none",
            )
            if exact:
                word = "exact"
            elif gap <= 1e-4:
                worst = max(gap, violation)  # exact in one of the two, not in both
                word = rf"within $10^{{{math.ceil(math.log10(worst))}}}$"
            else:
                word = f"off by {gap:.2g}"
            if violation > 1e-6:
                word += ", out of bounds"
            evaluations = r.get("median_evaluations")
            if evaluations:  # what it costs, in the methods' own unit (the slide's bullets)
                word += f", {evaluations:g} evals"
            if r.get("median_gradients"):  # and a gradient method's gradients (reading 175)
                word += f" + {r['median_gradients']:g} grads"
            words.text(-0.1, yi, word, va="center", fontsize=medium.tiny)
        # the one long name shortened: the axes keep the slide's width; a star marks a compiled
        # inner loop, as in the paper's Table III (its times compare implementations too)
        ax.set_yticks(
            y,
            [
                k.replace("differential-", "diff. ")
                + ("*" if rows[k].get("loop") == "compiled" else "")
                for k in order
            ],
        )
        ax.set_xscale("log")
        ax.xaxis.set_major_formatter(
            matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}")  # 0.01, 1, 100: plain
        )
        ax.axvline(dt * 1e3, color="black", linestyle="--", linewidth=1.0)
        ax.text(
            dt * 1e3,
            len(order) - 0.4,
            f"period {dt * 1e3:g} ms",
            fontsize=medium.tiny,
            ha="center",
            va="bottom",
        )
        ax.set_xlabel("median time per program (ms)")
        ax.set_xlim(min(times) / 3, 3 * max(max(times), dt * 1e3))
        ax.set_ylim(-0.6, len(order) - 0.4)
        ax.grid(axis="y", visible=False)
        handles = _family_handles(rows, order)
        if any(
            not exact_answer(abs(rows[k]["max_abs_gap"]), rows[k]["max_violation"]) for k in order
        ):
            handles.append(  # the verdicts' fill, said once here rather than on the slide
                Line2D(
                    [],
                    [],
                    marker="o",
                    color="#666666",
                    markerfacecolor="white",
                    linestyle="none",
                    label="hollow: not exact",
                )
            )
        fig.legend(  # two columns: three family names in one row overrun the figure
            handles=handles,
            loc="outside lower center",
            ncols=2,
            fontsize=medium.tiny,
            frameon=False,
            handletextpad=0.2,
        )
    return stem


SOLVER_COLORS = (
    "#0072B2",
    "#E69F00",
    "#009E73",
    "#D55E00",
    "#CC79A7",
    "#56B4E9",
    "#000000",
    "#999999",
    "#882255",
    "#44AA99",
    "#117733",
    "#AA4499",
)
"""One colour per solver of a figure (Okabe-Ito without its yellow, grey, then four of Tol's):
six shades of one family colour could not be told apart in print; twelve, so that the paper's
convergence figure repeats none (cma-es had interior-point's gold)."""
FREE_DASHES: tuple[Any, ...] = (
    (0, (4.0, 1.5)),
    (0, (1.0, 1.2)),
    (0, (4.0, 1.5, 1.0, 1.5)),
    (0, (7.0, 1.5)),
    (0, (4.0, 1.2, 1.0, 1.2, 1.0, 1.2)),
    (0, (2.0, 1.2)),
    (0, (7.0, 1.5, 1.0, 1.5)),
)
"""The gradient-free solvers' line patterns, one each (in units of the line width): broken
lines all, so that they read as one family, and each its own, so that their curves are told apart
in a greyscale print, where their colours are not."""


def solver_dashes(family: Mapping[str, str]) -> dict[str, Any]:
    """Each solver's line pattern (``family``: name -> family, in the figure's order): solid
    for exact and gradient-based methods, one of :data:`FREE_DASHES` per gradient-free one."""
    free = [name for name, kind in family.items() if kind == "gradient-free"]
    return {
        name: FREE_DASHES[free.index(name) % len(FREE_DASHES)] if name in free else "-"
        for name in family
    }


Curve = tuple[str, Sequence[float], Sequence[float], float | None]
"""A solver's convergence: (family, x (iterations or evaluations), error, returned error)."""


@dataclass(frozen=True)
class ConvergencePanel:
    """One program of :func:`convergence_figure`: its title, what its x axis counts and every
    solver's curve (name -> :data:`Curve`)."""

    title: str
    xlabel: str
    curves: Mapping[str, Curve]
    by_family: bool = False
    """Draw the gradient-free solvers in an axes of their own beside the others (under one
    title): nine curves in one column-wide panel could not be told apart."""

    def parts(self) -> list[tuple[str, Mapping[str, Curve]]]:
        """The panel's axes: (name, curves) each, the name empty for a whole panel; two when
        split by family and both are present, the gradient-free ones second."""
        if not self.by_family:
            return [("", self.curves)]
        free = {k: c for k, c in self.curves.items() if c[0] == "gradient-free"}
        rest = {k: c for k, c in self.curves.items() if c[0] != "gradient-free"}
        if not free or not rest:
            return [("", self.curves)]
        return [("gradient-based", rest), ("gradient-free", free)]


def solver_styles(names: Sequence[str]) -> dict[str, tuple[str, str]]:
    """Each solver's colour and marker, in the order given (every pair distinct for up to
    12 solvers)."""
    marks = ("o", "s", "^", "D", "v", "P", "X", "*", "h", "<", ">", "p")
    return {
        name: (SOLVER_COLORS[i % len(SOLVER_COLORS)], marks[i % len(marks)])
        for i, name in enumerate(names)
    }


def convergence_figure(
    panels: Sequence[ConvergencePanel],
    stem: Path,
    medium: Medium = PAPER,
    glyphs: Path | None = None,
) -> Path:
    """Programs side by side, every solver: the running best of |f - f*| + bound violation
    against the panel's count (iterations or objective evaluations), each solver in its own
    colour and marker (the same in every panel), solid for exact and gradient-based and dashed
    for gradient-free methods; the marker at the last count shows the error of the answer the
    solver returns (the curve's end where it is None), which need not be the best point it
    evaluated (the paper's Fig. 6; the lab's own figure has every representative step).

    With ``glyphs`` (a folder), each solver's line and marker is saved there as ``NAME`` (a
    table's rows become the legend) and the figure has none; else one legend beside it.
    """
    names = list(dict.fromkeys(name for panel in panels for name in panel.curves))
    styles = solver_styles(names)
    family = {name: f for panel in panels for name, (f, *_rest) in panel.curves.items()}
    dashes = solver_dashes(family)
    size = 3.5 if medium is PAPER else 6
    height = 1.1 if medium is PAPER else 2.7  # (0.85 in was illegible: readings 190, 193, 195)
    width = medium.column if medium is PAPER else 3.3 * len(panels)
    with _figure(stem, medium, width, height) as fig:
        # a busier panel gets more room (Task 2's nine solvers against Task 1's four)
        parts = [panel.parts() for panel in panels]
        widths = [sum(max(1, len(c)) ** 0.5 for _, c in part) for part in parts]
        # a gap between the programs' panels: their end ticks (10^2, 10^0) met (readings 150-151)
        subs = fig.subfigures(1, len(panels), squeeze=False, width_ratios=widths, wspace=0.06)[0]
        engine = fig.get_layout_engine()
        if isinstance(engine, ConstrainedLayoutEngine) and any(len(p) > 1 for p in parts):
            # split axes side by side: room between them, or their end ticks (10^1, 10^0) meet
            # (0.08 left them touching: reading 246)
            engine.set(wspace=0.12)
        axes: list[Axes] = []
        for sub, panel, part in zip(subs, panels, parts, strict=True):
            own = sub.subplots(
                1,
                len(part),
                squeeze=False,
                sharey=True,
                width_ratios=[max(1, len(c)) ** 0.5 for _, c in part],
            )[0]
            for ax, (name, curves) in zip(own, part, strict=True):
                _convergence_axes(ax, curves, styles, dashes, medium, size)
                if name:  # which family, over its axes (inside, it sat on the curves and
                    # cost them four decades of the axes' height: readings 190, 193, 195)
                    ax.set_title(name, fontsize=medium.small, pad=2)
            if len(own) == 1:  # over the axes (a subfigure's title would centre on its label too)
                own[0].set_title(panel.title, fontsize=medium.small, pad=2)
                own[0].set_xlabel(panel.xlabel, labelpad=1)
            else:
                if len(panels) > 1:  # a lone program's title is its caption's
                    sub.suptitle(panel.title, fontsize=medium.small)
                sub.supxlabel(panel.xlabel, fontsize=matplotlib.rcParams["axes.labelsize"])
            axes.extend(own)
        bottom = min(min(ax.get_ylim()) for ax in axes)
        top = max(max(ax.get_ylim()) for ax in axes)
        # every fifth decade (four labels in 0.45 in ran together at every tenth's half:
        # readings 156-157)
        ticks = [10.0**e for e in range(-30, 10, 5) if bottom <= 10.0**e <= top]
        for ax in axes:  # one error scale across the programs, its ticks labelled once
            ax.set_ylim(bottom, top)
            ax.tick_params(labelleft=ax is axes[0])
            ax.yaxis.set_major_locator(matplotlib.ticker.FixedLocator(ticks))
        axes[0].set_ylabel(
            r"best $|f-f^*|$ + viol." if medium is not PAPER else r"$|f-f^*|$ + viol.", labelpad=1
        )
        if glyphs is None:
            # a figure legend: the layout gives the axes the figure's whole height beside it
            # (an axes legend taller than the axes shrank them to half the figure)
            fig.legend(
                loc="outside right center",
                fontsize=medium.tiny,
                frameon=False,
                handlelength=2.2,
                labelspacing=0.15 if medium is PAPER else 0.5,
            )
    if glyphs is not None:
        for name, (colour, mark) in styles.items():
            solver_glyph(colour, mark, dashes[name], glyphs / name, medium)
    return stem


def _convergence_axes(
    ax: Axes,
    curves: Mapping[str, Curve],
    styles: Mapping[str, tuple[str, str]],
    dashes: Mapping[str, Any],
    medium: Medium,
    size: float,
) -> None:
    """One axes of :func:`convergence_figure`: each solver's running best and, at its last
    count, the error of the answer it returns."""
    for name, (_kind, counts, error, returned) in curves.items():
        # the marker at the solver's last count, at its returned answer's error: one done in a
        # few evaluations (slsqp) is a short trace ending in its marker
        colour, mark = styles[name]
        ax.loglog(
            counts,
            error,
            color=colour,
            linestyle=dashes[name],
            linewidth=medium.line,
            marker=mark,
            markevery=[],  # the legend's marker; the plotted one below
            markersize=size,
            label=name,
        )
        end = error[-1] if returned is None else max(returned, 1e-17)  # (the floor)
        ax.plot([counts[-1]], [end], linestyle="none", color=colour, marker=mark, markersize=size)
    # every fifth decade (10^0, 10^-5, ...): a tick per decade runs together at this size
    ax.yaxis.set_major_locator(matplotlib.ticker.FixedLocator([10.0**e for e in range(-30, 10, 5)]))
    ax.yaxis.set_minor_locator(matplotlib.ticker.NullLocator())
    # the counts from a power of ten to a power of ten: within less than a decade (slsqp's few
    # evaluations) matplotlib labels its minor ticks, and at this size they ran together
    counts = [c for _kind, cs, _e, _r in curves.values() for c in cs if c > 0]
    if counts:
        low = 10.0 ** np.floor(np.log10(min(counts)))
        ax.set_xlim(low, max(10.0 ** np.ceil(np.log10(max(counts))), 10.0 * low))
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())


def solver_glyph(colour: str, mark: str, dash: Any, stem: Path, medium: Medium = PAPER) -> Path:
    """A curve's line and marker alone, as a legend draws them (0.17 x 0.08 in: set about
    1.3 em wide in 7 pt text, its marker keeps about the figure's size; 0.06 in tall cut a
    diamond's corners into a hexagon)."""
    with _figure(stem, medium, 0.17, 0.08) as fig:
        fig.set_layout_engine("none")
        ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
        ax.set_axis_off()
        ax.plot([0.0, 1.0], [0.5, 0.5], color=colour, linestyle=dash, linewidth=medium.line)
        # (a marker a little larger than the figure's: the glyph is printed at 0.85 of its size)
        ax.plot([0.5], [0.5], color=colour, marker=mark, markersize=4.2, linestyle="none")
        ax.set_xlim(0.0, 1.0)
        ax.set_ylim(0.0, 1.0)
    return stem


def conditioning_figure(
    run: Run, lab_rows: dict[str, list[dict[str, Any]]], stem: Path, medium: Medium = PAPER
) -> Path:
    """Along a run: cond(J) and w_S = c_S/||e|| (top); iterations of the solvers (bottom)."""
    arm = run.scenario.planar_arm
    cond = []
    for q in run.q:
        s = np.linalg.svd(arm.jacobian(q), compute_uv=False)
        cond.append(s[0] / s[-1] if s[-1] > 1e-14 else np.nan)
    w_s = run.scenario.weights.slack / np.maximum(run.error_norm, 1e-9)
    height = 2.15 if medium is PAPER else 3.2
    with _figure(stem, medium, medium.column, height) as fig:
        top, bottom = fig.subplots(2, 1, sharex=True)
        top.semilogy(run.t, cond, color=OKABE_ITO[0], label=r"cond $J$")
        top.semilogy(run.t, w_s, color=OKABE_ITO[3], linestyle="--", label=r"$w_S=c_S/\|e\|$")
        top.legend(loc="upper left", ncols=2, frameon=False)
        top.set_ylabel("cond $J$, $w_S$")
        bottom.step(
            run.t[:-1],
            np.maximum(run.iterations, 0.8),
            where="post",
            color="black",
            linewidth=medium.line * 0.8,
            label=f"{run.solver[0]} (closed loop)",
        )
        for i, (name, rows) in enumerate(lab_rows.items()):
            t = [run.t[int(r["step"])] for r in rows]
            its = [max(float(r["iterations"]), 0.8) for r in rows]
            bottom.plot(
                t,
                its,
                marker="o",
                markersize=2.5 if medium is PAPER else 5,
                linestyle="none",
                color=OKABE_ITO[(i + 1) % 8],
                label=name,
            )
        bottom.set_yscale("log")
        bottom.yaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        bottom.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        _log_axis(top.yaxis)
        bottom.set_ylabel("iterations")
        bottom.set_xlabel(r"$t$ (s)")
        bottom.legend(loc="upper right", ncols=2, frameon=False, fontsize=medium.tiny)
        for ax in (top, bottom):
            for f in np.flatnonzero(np.isnan(cond)):
                ax.axvline(run.t[f], color="#D55E00", linewidth=0.8)
            k = int(np.nanargmax(cond)) if np.isfinite(cond).any() else 0
            ax.axvline(run.t[k], color="#D55E00", linewidth=0.6, linestyle=":")
    return stem


def _effort_so_far(run: Run) -> np.ndarray:
    """The effort a run has spent up to each sample, sum E dt (rad^2/s), from 0 at t = 0."""
    return np.concatenate(([0.0], np.cumsum(run.effort) * run.scenario.motion.dt))


def manipulability_figure(
    pairs: dict[str, Sequence[Run]],
    stem: Path,
    medium: Medium = SLIDE,
    width: float = SLIDE_COLUMN,
) -> Path:
    """m(t) of each pair side by side, under it the effort spent so far, and under that the
    distance to the goal (the pitch's headline for a task: what EMDM buys, what it pays, and
    that tracking does not pay: reading 133 asked to see 'not with tracking', not only read it)."""
    height = 2.85 if medium is SLIDE else 2.8
    with _figure(stem, medium, width, height) as fig:
        grid = fig.subplots(3, len(pairs), squeeze=False, sharex="col", sharey="row")
        handles: list[Artist] = []
        for col, (title, runs) in enumerate(pairs.items()):
            ax, ax_e, ax_d = grid[0, col], grid[1, col], grid[2, col]
            spans = _common_scaled(runs)
            for a in (ax, ax_e, ax_d):
                _shade(a, spans)
            for run in runs:
                ax.plot(run.t, run.m, **_style(run, medium))
                ax_e.plot(run.t, _effort_so_far(run), **_style(run, medium))
                ax_d.semilogy(run.t, run.error_norm, **_style(run, medium))
            ax.set_title(title)
            ax_d.set_xlabel(r"$t$ (s)")
            handles += ax.get_legend_handles_labels()[0]
            if spans and not any(isinstance(h, Patch) for h in handles):
                handles.append(_scaled_patch("tip slowed (both)"))
        # one row above the panels, clear of every curve (a legend inside sat on C-IVKC's
        # falling curve, reading 125)
        fig.legend(
            handles=handles,
            loc="outside upper center",
            ncols=math.ceil(len(handles) / 2),  # two rows: the figure is a column's width
            frameon=False,
            handlelength=1.8,
            columnspacing=1.0,
            fontsize=medium.tiny,
        )
        grid[0, 0].set_ylabel(r"$m$ (m$^2$)")
        grid[1, 0].set_ylabel("effort so far\n" + r"(rad$^2$/s)")  # cumulative (reading 143)
        grid[2, 0].set_ylabel(r"$\|e\|$ (m)")
        fig.align_ylabels(grid[:, 0])  # one column of labels whatever the tick labels' widths
    return stem


def slack_figure(
    runs: Sequence[Run],
    stem: Path,
    without: tuple[str, Run] | None = None,
    medium: Medium = SLIDE,
) -> Path:
    """The pitch's Task 2.2 slide, what its bullets say, in one row: (a) m(t), (b) the effort
    spent so far, sum E dt up to t (linear: a saving is a gap that stays), (c) the slack at
    work, the tracking gap ||J qd - v_d|| of :func:`tracking_gap` (log, floored at
    :data:`GAP_FLOOR`), and, when a run leaves its joint limits (the unconstrained controllers
    ignore them), (d) how far past them its deepest joint is
    (:func:`~emdm.sim.metrics.limit_excess`). ``without``: ``(label, run)`` with one cause
    removed, drawn grey and dotted in every panel, so that what its removal changes is seen
    (reading 135: the slide said it without showing it). In the paper, Task 2.2 is a pair
    composite (:func:`pair_figure` with ``without``)."""
    drawn = [(run, _style(run, medium)) for run in runs]
    if without is not None:
        label, run = without
        st = {"color": "#666666", "linestyle": ":", "linewidth": medium.line, "label": label}
        drawn.append((run, st))
    beyond = [limit_excess(run).max(axis=1) for run, _ in drawn]
    outside = any(b.max() > 0.0 for b in beyond)
    with _figure(stem, medium, medium.column, 2.3) as fig:
        axes = list(fig.subplots(1, 4 if outside else 3, sharex=True))
        ax_m, ax_e, ax_gap = axes[:3]
        for (run, st), over in zip(drawn, beyond, strict=True):
            ax_m.plot(run.t, run.m, **st)
            ax_e.plot(run.t, _effort_so_far(run), **st)
            ax_gap.semilogy(run.t[:-1], np.maximum(tracking_gap(run), GAP_FLOOR), **st)
            if outside:
                axes[3].plot(run.t, over, **st)
        ax_m.set_ylabel(r"$m$ (m$^2$)", labelpad=1)
        ax_e.set_ylabel(r"$\Sigma E\Delta t$ (rad$^2$/s)", labelpad=1)  # (a short Sigma)
        ax_gap.set_ylabel("tracking gap (m/s)", labelpad=1)
        ax_gap.set_ylim(bottom=GAP_FLOOR / 4)  # a run on the floor (an exact task) is a line
        ax_gap.yaxis.set_major_locator(LogLocator(numticks=4))
        ax_gap.yaxis.set_minor_locator(NullLocator())
        if outside:
            axes[3].set_ylabel("past a joint limit (rad)", labelpad=1)
        for ax, letter in zip(axes, ("(a)", "(b)", "(c)", "(d)"), strict=False):
            ax.set_title(letter, loc="left", fontsize=medium.small, fontweight="bold", pad=2)
            if ax is not ax_gap:
                ax.yaxis.set_major_locator(MaxNLocator(3))
            ax.set_xlabel(r"$t$ (s)", labelpad=1)
        fig.legend(  # under the panels, as the other slides': inside one it hid a curve
            handles=[Line2D([], [], **st) for _, st in drawn],
            loc="outside lower center",
            ncols=len(drawn),
            frameon=False,
            columnspacing=1.0,
            handlelength=2.0,
        )
    return stem


def _plain_tex(x: float) -> str:
    """``0.100``, or ``3.4\times10^{-5}`` for a value below 10^-3 (mathtext)."""
    if x == 0 or abs(x) >= 1e-3:
        return f"{x:.3f}"
    mant, exp = f"{x:.1e}".split("e")
    return rf"{mant}\times10^{{{int(exp)}}}"


def ellipse_figure(run: Run, stem: Path, medium: Medium = SLIDE) -> Path:
    """What manipulability measures, on a run's own arm: at its start and at its most and
    least dexterous states, the arm and the tip velocities unit joint speeds reach (the ellipse
    of ``J J^T``, one scale for all three), each titled with its ``m``."""
    arm = run.scenario.planar_arm
    reach = arm.reach
    picks = [0, int(np.argmax(run.m)), int(np.argmin(run.m))]
    titles = ["start", "most dexterous", "least dexterous"]
    biggest = max(
        float(np.sqrt(np.linalg.eigvalsh(arm.jacobian(run.q[k]) @ arm.jacobian(run.q[k]).T)[-1]))
        for k in picks
    )
    scale = 0.35 * reach / biggest if biggest > 0 else 1.0
    st = _style(run, medium)
    height = 2.1 if medium is SLIDE else 1.5
    ells = [
        ellipse_points(arm.jacobian(run.q[k]), arm.joint_positions(run.q[k])[-1], scale)
        for k in picks
    ]
    half = 1.05 * max(reach, *(float(np.abs(e).max()) for e in ells))  # no ellipse clipped
    with _figure(stem, medium, medium.wide, height) as fig:
        axes = fig.subplots(1, 3)
        for ax, k, title, ell in zip(axes, picks, titles, ells, strict=True):
            pts = arm.joint_positions(run.q[k])
            ax.add_patch(Circle((0, 0), reach, color="#BBBBBB", alpha=0.2, linewidth=0))
            ax.fill(ell[:, 0], ell[:, 1], color=st["color"], alpha=0.35, linewidth=0)
            ax.plot(ell[:, 0], ell[:, 1], color=st["color"], linewidth=medium.line * 0.6)
            ax.plot(
                pts[:, 0],
                pts[:, 1],
                color="black",
                linewidth=medium.line * 1.3,
                marker="o",
                markersize=3,
                markerfacecolor="white",
            )
            ax.set_title(
                f"{title}\n" + rf"$m={_plain_tex(float(run.m[k]))}$ m$^2$, $t$ = {run.t[k]:.2f} s",
                fontsize=medium.small,
            )
            ax.set_aspect("equal")
            ax.set_xlim(-half, half)
            ax.set_ylim(-half, half)
            ax.set_xticks([])
            ax.set_yticks([])
    return stem


def stills_figure(runs: Sequence[Run], stem: Path, times: int = 6, medium: Medium = SLIDE) -> Path:
    """Animation stills: each run's arm at ``times`` instants (darker = later), path, goal and
    the manipulability ellipse at the last state, the runs side by side."""
    sc = runs[0].scenario
    arm = sc.planar_arm
    reach = arm.reach
    # on a slide: drawn at about the size shown (0.72-0.78 of the text width), so that its
    # text is projected at its own size (at the full width it shrank to about 7 pt)
    width = 4.4 if medium is SLIDE else medium.column
    height = 2.3 if medium is SLIDE else 1.9
    biggest = max(
        float(np.sqrt(np.linalg.eigvalsh(arm.jacobian(q) @ arm.jacobian(q).T)[-1]))
        for run in runs
        for q in run.q[:: max(1, run.steps // 50)]
    )
    scale = 0.3 * reach / biggest if biggest > 0 else 1.0
    circle = np.stack(
        (np.cos(np.linspace(0, 2 * np.pi, 73)), np.sin(np.linspace(0, 2 * np.pi, 73)))
    )
    with _figure(stem, medium, width, height) as fig:
        axes = fig.subplots(1, len(runs), squeeze=False)[0]
        for ax, run in zip(axes, runs, strict=True):
            # each run's own instants: a run that ends early is not drawn at times it never had,
            # and one that stalls only until it does (the record's stall, as the paper dates
            # it), not as copies of one pose
            stalled = run.stalled_from
            last = stalled if stalled is not None else run.steps
            instants = np.linspace(0.0, float(run.t[last]), times)
            drawn = [min(round(t / sc.motion.dt), last) for t in instants]
            st = _style(run, medium)
            ax.add_patch(Circle((0, 0), reach, color="#BBBBBB", alpha=0.2, linewidth=0))
            ax.plot(run.p[:, 0], run.p[:, 1], color=st["color"], linewidth=medium.line * 0.8)
            for i, k in enumerate(drawn):
                pts = arm.joint_positions(run.q[k])
                shade = 0.25 + 0.75 * i / max(times - 1, 1)
                ax.plot(
                    pts[:, 0],
                    pts[:, 1],
                    color="black",
                    alpha=shade,
                    linewidth=medium.line * 1.1,
                    marker="o",
                    markersize=2.5,
                    markerfacecolor="white",
                )
            k = run.steps
            J = arm.jacobian(run.q[k])
            lam, U = np.linalg.eigh(J @ J.T)
            ell = run.p[k][:, None] + scale * (U * np.sqrt(np.maximum(lam, 0.0))) @ circle
            ax.fill(ell[0], ell[1], color=st["color"], alpha=0.3, linewidth=0)
            ax.plot(*sc.motion.goal, marker="*", color="black", markersize=10, linestyle="none")
            outcome = (
                f"goal at {run.time_to_goal:.2f} s"
                if run.reached
                else f"not reached in {run.t[-1]:.0f} s"
            )
            ax.set_title(f"{run.controller.name}: {outcome}", fontsize=medium.small)
            ax.set_aspect("equal")
            ax.set_xlim(-reach * 1.05, reach * 1.05)
            ax.set_ylim(-reach * 1.05, reach * 1.05)
            ax.set_xticks([])
            ax.set_yticks([])
            ax.set_xlabel(  # below the workspace, where no arm can cover it; short enough to
                # be set large (the list of every instant was unreadable from a room)
                f"arm at {len(drawn)} instants, darker later\n"
                + rf"$t$ = 0 to {run.t[drawn[-1]]:.2f} s"  # as the title's times (8.20 s)
                + (", then still" if last < run.steps else ""),
                fontsize=medium.font,
                color="#444444",
            )
    return stem


_ARM_STYLE: dict[bool, dict[str, Any]] = {
    True: {"linewidth": 2.6, "marker": "s", "markersize": 3.2, "zorder": 2},
    False: {"linewidth": 1.1, "marker": "o", "markersize": 2.2, "zorder": 2.5},
}
"""The stills' arms by whether the run is constrained (its joints' marker and the line's width)."""


def arms_figure(pairs: Mapping[str, Sequence[Run]], stem: Path, medium: Medium = PAPER) -> Path:
    """Animation stills of a task's pairs in one view of the whole motion (readings 150, 154:
    two cropped panels cut the start arm and the paths, and looked alike): the start arm
    (grey), each run's arm at its end (its stall, if it stalled) in its own colour and dash,
    its tip path (dotted) and its manipulability ellipse there (one scale), the goal; the
    legend gives each run's final m (the ellipses' difference, reading 152)."""
    runs = [r for pair in pairs.values() for r in pair]
    sc = runs[0].scenario
    arm = sc.planar_arm
    ends = [r.stalled_from if r.stalled_from is not None else r.steps for r in runs]
    biggest = max(
        float(np.sqrt(np.linalg.eigvalsh(arm.jacobian(r.q[k]) @ arm.jacobian(r.q[k]).T)[-1]))
        for r, k in zip(runs, ends, strict=True)
    )
    scale = 0.22 * arm.reach / biggest if biggest > 0 else 1.0
    width = medium.column if medium is PAPER else 4.4
    height = 1.05 if medium is PAPER else 2.4  # (its view takes the slot: datalim)
    with _figure(stem, medium, width, height) as fig:
        ax = fig.add_subplot()
        start = _arm_points(runs[0], runs[0].q[0])
        ax.plot(*start[:, :2].T, color="#999999", linewidth=medium.line, marker="o", markersize=2)
        handles: list[Artist] = []
        for run, last in zip(runs, ends, strict=True):
            # a constrained run thick with square joints under an unconstrained one, thin with
            # round joints: two that end in one pose both show (reading 156), and the pairs'
            # near hues differ in grey (reading 157)
            st = {**_style(run, medium), **_ARM_STYLE[run.controller.constrained]}
            pts = _arm_points(run, run.q[last])
            ax.plot(*pts[:, :2].T, **{**st, "label": None})
            ell = ellipse_points(arm.jacobian(run.q[last]), run.p[last, :2], scale)
            ax.fill(*ell.T, color=st["color"], alpha=0.12, linewidth=0)
            ax.plot(
                *ell.T, color=st["color"], linestyle=st["linestyle"], linewidth=0.6 * medium.line
            )
            ax.plot(
                *run.p[: last + 1, :2].T,
                color=st["color"],
                linewidth=0.6 * medium.line,
                linestyle=":",
                zorder=3,
            )
            handles.append(
                Line2D([], [], **{**st, "label": f"{run.controller.name}  {run.m[last]:.3f}"})
            )
        ax.plot(
            *sc.motion.goal, marker="*", color="black", markersize=6, linestyle="none", zorder=4
        )
        handles.append(Line2D([], [], color="#999999", marker="o", markersize=2, label="start"))
        # the view, not the box, takes the slot's shape: a box shrunk to the data's aspect
        # left its y label outside the figure (reading 161)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(r"$x$ (m)", labelpad=1)
        ax.set_ylabel(r"$y$ (m)", labelpad=1)
        ax.xaxis.set_major_locator(MaxNLocator(4))
        ax.yaxis.set_major_locator(MaxNLocator(3))
        fig.legend(  # beside the view: over it, it hid the arms
            handles=handles,
            loc="outside right center",
            fontsize=medium.tiny,
            frameon=False,
            handlelength=1.8,
            labelspacing=0.3,
            title=r"final $m$ (m$^2$)",
            title_fontsize=medium.tiny,
        )
    return stem


@dataclass(frozen=True)
class EvidenceBar:
    """One closed-loop run of the pitch's Task 2 evidence chart: whose, what was changed (or
    ``as run``), and when it reached the goal (``None``: it did not, within ``max_time``)."""

    controller: str
    change: str
    time_to_goal: float | None


def mean_m_figure(
    runs: Sequence[Run],
    stem: Path,
    medium: Medium = SLIDE,
    width: float = 2.1,
    height: float = 0.98,
    shared_until: float | None = None,
) -> Path:
    """A pair's m(t) with each run's mean m over its run as a thin line of its style, the
    mean written at its right (the pitch's Task 2 slide: its "mean m 0.137 against 0.188" had
    been said, not drawn, reading 140). The time axis ends at the last arrival when the other
    run had stalled by then (:func:`time_end`); the means are the whole runs' (Table II's).
    ``shared_until``: the time up to which the pair gave the same commands, shaded (the Task 1
    slide's title, readings 152-153: said, not shown)."""
    with _figure(stem, medium, width, height) as fig:
        ax = fig.subplots()
        if shared_until:
            ax.axvspan(0.0, shared_until, color="#DDDDDD", linewidth=0, zorder=0)
            ax.annotate(
                "same\ncommands",
                (shared_until, 0.04),
                xycoords=("data", "axes fraction"),
                xytext=(3, 0),
                textcoords="offset points",
                va="bottom",
                fontsize=medium.tiny,
                color="#555555",
            )
        for run in runs:
            st = _style(run, medium)
            ax.plot(run.t, run.m, **st)
            mean = float(metrics_of(run)["mean_manipulability"])
            ax.axhline(mean, color=st["color"], linestyle=st["linestyle"], linewidth=0.7)
            ax.annotate(
                f"{mean:.3f}",
                (1.0, mean),
                xycoords=("axes fraction", "data"),
                xytext=(2, 0),
                textcoords="offset points",
                va="center",
                fontsize=medium.tiny,
                color=st["color"],
                annotation_clip=False,
            )
        end = time_end(runs)
        if end is not None:
            ax.set_xlim(0.0, end)
        # the units in the title: axis labels would take the slide's last lines
        ax.set_title(r"$m$ (m$^2$) over $t$ (s); thin: mean $m$", fontsize=medium.tiny, pad=2)
        ax.yaxis.set_major_locator(MaxNLocator(3))
    return stem


@dataclass(frozen=True)
class PolicyRun:
    """One run of the pitch's Task 1 policy chart: whose, under which infeasibility policy
    (``slowed``: task scaling, as run; ``free slack``), and its outcomes (``time_to_goal`` None:
    it did not arrive)."""

    controller: str
    policy: str
    time_to_goal: float | None
    total_effort: float
    mean_manipulability: float
    path_length: float


POLICY_PANELS = (
    ("time_to_goal", "time to goal (s)", "{:.2f}"),
    ("total_effort", r"effort (rad$^2$/s)", "{:.2f}"),  # (a panel's width: no sum)
    ("mean_manipulability", r"mean $m$ (m$^2$)", "{:.3f}"),
    # what slowing keeps, drawn beside what it costs (readings 154, 156: said, not shown)
    ("path_length", "tip path (m)", "{:.2f}"),
)
"""The policy chart's panels, top to bottom: outcome, axis title, value format."""


def policy_figure(
    runs: Sequence[PolicyRun],
    stem: Path,
    medium: Medium = SLIDE,
    width: float = 2.6,
    height: float = 2.5,
) -> Path:
    """The pitch's Task 1 policy evidence: the constrained pair slowed (task scaling, as run)
    and with a free slack instead, each outcome a panel of bars in the controllers' colours,
    the free slack hatched, each bar's value written at its end (take-away 2 had rested on a
    backup table, reading 141). Drawn at the size shown beside the stills."""
    with _figure(stem, medium, width, height) as fig:
        # two by two: in one column of four panels the value labels of adjacent bars ran
        # into each other (reading 199)
        axes = fig.subplots(2, (len(POLICY_PANELS) + 1) // 2).ravel()[: len(POLICY_PANELS)]
        ys = np.arange(len(runs))[::-1]
        for ax, (key, title, fmt) in zip(axes, POLICY_PANELS, strict=True):
            values = [getattr(r, key) for r in runs]
            top = max(v for v in values if v is not None)
            for y, run, v in zip(ys, runs, values, strict=True):
                colour = CONTROLLER_STYLE.get(run.controller, {"color": OKABE_ITO[0]})["color"]
                slack = run.policy != "slowed"
                if v is None:  # never arrived: no bar, said
                    ax.text(0.0, y, "no arrival", va="center", fontsize=medium.tiny)
                    continue
                ax.barh(
                    y,
                    v,
                    height=0.7,
                    color="white" if slack else colour,
                    edgecolor=colour,
                    hatch="////" if slack else None,
                    linewidth=0.8,
                )
                ax.text(v + 0.02 * top, y, fmt.format(v), va="center", fontsize=medium.tiny)
            ax.set_xlim(0.0, 1.55 * top)  # (room for the longest bar's label)
            ax.set_yticks([])
            ax.set_xticks([])
            ax.set_title(title, fontsize=medium.tiny, pad=2, loc="left")
            for side in ("top", "right", "left", "bottom"):
                ax.spines[side].set_visible(False)
        # the legend in two short columns: the controllers' colours, then the policies' fills
        handles: list[Artist] = [
            Patch(color=CONTROLLER_STYLE.get(c, {"color": OKABE_ITO[0]})["color"], label=c)
            for c in dict.fromkeys(r.controller for r in runs)
        ]
        for policy in dict.fromkeys(r.policy for r in runs):
            slack = policy != "slowed"
            handles.append(
                Patch(
                    facecolor="white" if slack else "#777777",
                    edgecolor="#777777",
                    hatch="////" if slack else None,
                    label=policy,
                )
            )
        fig.legend(  # two columns (the controllers, the policies): one row ran past the edge
            handles=handles,
            loc="outside upper center",
            ncols=2,
            fontsize=medium.tiny,
            frameon=False,
            columnspacing=1.0,
            handlelength=1.0,
            handletextpad=0.3,
        )
    return stem


def evidence_figure(
    bars: Sequence[EvidenceBar],
    max_time: float,
    stem: Path,
    medium: Medium = SLIDE,
    width: float = 2.6,
    height: float = 2.5,
) -> Path:
    """The pitch's Task 2 evidence: each run's time to the goal as a bar, top to bottom in the
    order given, in its controller's colour; a run that never arrives is an empty dashed bar to
    the end of the run marked 'no arrival', so a stall is seen beside the arrivals (the slide had
    said the runs in bullets, without drawing them). Drawn at the size shown beside the stills."""
    with _figure(stem, medium, width, height) as fig:
        ax = fig.subplots()
        ys = np.arange(len(bars))[::-1]
        for y, bar in zip(ys, bars, strict=True):
            colour = CONTROLLER_STYLE.get(bar.controller, {"color": OKABE_ITO[0]})["color"]
            # named above its bar, so that the bars keep the axes' whole width
            name = f"{bar.controller}, {bar.change}"
            ax.text(0.0, y + 0.27, name, ha="left", va="bottom", fontsize=medium.small)
            if bar.time_to_goal is None:
                ax.barh(
                    y,
                    max_time,
                    height=0.46,
                    color="white",
                    edgecolor=colour,
                    linestyle=(0, (2, 1.5)),  # empty, dashed: hatching is the policy
                    linewidth=0.9,  # slide's free slack (reading 161)
                )
                ax.text(
                    0.5 * max_time,
                    y,
                    "no arrival",
                    ha="center",
                    va="center",
                    fontsize=medium.small,
                    bbox={"facecolor": "white", "edgecolor": "none", "pad": 1.0},
                )
            else:
                ax.barh(y, bar.time_to_goal, height=0.46, color=colour, linewidth=0)
                ax.text(
                    bar.time_to_goal + 0.02 * max_time,
                    y,
                    f"{bar.time_to_goal:.2f}",
                    ha="left",
                    va="center",
                    fontsize=medium.small,
                )
        ax.set_yticks([])
        ax.set_xlim(0.0, max_time * 1.001)
        ax.set_ylim(-0.4, len(bars) - 0.2)
        ax.set_xlabel(r"time to the goal (s)")
        for side in ("top", "right", "left"):
            ax.spines[side].set_visible(False)
    return stem
