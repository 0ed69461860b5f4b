"""The playground page: one Bokeh document per browser tab, drawn from :mod:`emdm.play.logic`.

The server computes everything (runs, frames, status, fronts); the page's scripts only pick the
scrubbed row of arrays the server sent, play the scrub bar in real time, and download files.
Changes are coalesced: a burst of slider or drag events costs one recomputation.
"""

from __future__ import annotations

import base64
import contextlib
import copy
import dataclasses
import html
import json
import logging
import math
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from functools import cache, partial
from importlib import resources
from typing import Any

import numpy as np
from bokeh.document import Document
from bokeh.layouts import column, gridplot, row
from bokeh.models import (
    BasicTicker,
    ColumnDataSource,
    CustomJS,
    CustomJSTickFormatter,
    HoverTool,
    InlineStyleSheet,
    LinearColorMapper,
    PanTool,
    PointDrawTool,
    Range1d,
    WheelZoomTool,
)
from bokeh.models.annotations import Arrow, BoxAnnotation, Label, OpenHead, Span, Title, VeeHead
from bokeh.models.widgets import Button, Div, RadioButtonGroup, Select, Slider, Spinner, Toggle
from bokeh.plotting import figure

from ..core.scenario import Scenario
from ..core.validation import POLICIES
from ..errors import EmdmError
from ..outputs.style import CONTROLLER_STYLE
from ..outputs.views import Views
from . import logic
from .logic import CONTROLS, PAIRS, Control, Outcome, Settings

log = logging.getLogger("emdm.play")

SPEEDS = (0.25, 0.5, 1.0, 2.0, 4.0)
VELOCITY_COLOR = "#56B4E9"
"""Outline and fill of the tip velocity set drawn at the tip (a colour no controller uses)."""
PINNED_COLOR = "#9A9A9A"
"""The pinned reference run's trace and curves (grey, dotted: no controller's colour)."""
JOINT_COLORS = ("white", "#F0E442", "#CC79A7", "black", "#444444")
"""Fill of the joint markers by state (see :data:`emdm.play.logic.JOINT_STATES`)."""
JOINT_LINES = (
    "#009E73",
    "#332288",
    "#000000",
    "#882255",
    "#44AA99",
    "#999933",
    "#777777",
    "#AA4499",
)
"""Colours of the joint-angle curves, one per joint (up to the 8 links a page allows): none of
them is a controller's colour (:data:`emdm.outputs.style.CONTROLLER_STYLE`) or a zone's, so a
curve is never read as a run."""
SCENE, PLOT_W, PLOT_H, STATUS_H = 460, 250, 180, 560
"""Sizes (px) that fit a projector's 1280 x 720 with the explanation in view."""


@cache
def asset(name: str) -> str:
    """A file of ``emdm/play/assets`` (scripts and the style sheet)."""
    return resources.files("emdm.play").joinpath("assets", name).read_text(encoding="utf-8")


@cache
def template() -> Any:
    """Bokeh's page without the scripts the playground never uses (MathJax, tables, WebGL):
    about 2.5 MB less to parse at every page load; then ``canvas.js``."""
    from bokeh.core.templates import get_env

    skip = ("bokeh-mathjax", "bokeh-tables", "bokeh-gl")
    return get_env().from_string(
        '{% extends "file.html.jinja" %}{% block js_resources %}'
        '{% for line in bokeh_js.split("\\n") %}'
        "{% if not (" + " or ".join(f"{name!r} in line" for name in skip) + ") %}"
        "{{ line }}\n{% endif %}{% endfor %}"
        "<script>{% raw %}\n" + asset("canvas.js") + "{% endraw %}</script>\n{% endblock %}"
    )


def _style(fig: Any) -> None:
    fig.title.text_font_size = "15px"
    for axis in (*fig.xaxis, *fig.yaxis):
        axis.axis_label_text_font_size = "14px"
        axis.major_label_text_font_size = "12px"
    fig.toolbar.logo = None


def _set(model: Any, **values: Any) -> None:
    """Set only the properties that change (each change is validated and sent to the page)."""
    changed = {key: value for key, value in values.items() if getattr(model, key) != value}
    if changed:
        model.update(**changed)


def _fitted(*columns: Any) -> dict[str, float] | None:
    """The range that shows ``columns`` as Bokeh's DataRange1d fits one (10 % padding, a span of 2
    about a constant), or None without a finite value. Fitted here and sent with the change: a
    DataRange1d fitted in the page sent its range back to the server, a message per plot and
    change that the page built while painting and the server read before the next change."""
    values = np.concatenate([np.ravel(np.asarray(c, dtype=float)) for c in columns] + [[]])
    values = values[np.isfinite(values)]
    if values.size == 0:
        return None
    low, high = float(values.min()), float(values.max())
    span, middle = ((high - low) * 1.1 if high > low else 2.0), (low + high) / 2
    return {"start": middle - span / 2, "end": middle + span / 2}


def _log_format(control: Control) -> CustomJSTickFormatter:
    zero = f"tick <= {control.start + control.step / 2} ? '0' : " if control.zero_at_start else ""
    return CustomJSTickFormatter(code=f"return {zero}Number(Math.pow(10, tick).toPrecision(3))")


class Session:
    """The state and widgets of one tab; every callback goes through :meth:`_guard`."""

    def __init__(self, doc: Document, bases: dict[str, Scenario]) -> None:
        self.doc, self.bases = doc, bases
        request = getattr(doc.session_context, "request", None)
        arguments = dict(request.arguments) if request is not None else {}
        self.settings, refused = logic.parse_query(arguments, list(bases))
        self._valid = copy.deepcopy(self.settings)  # the settings of the scenario shown
        self._refusal: str | None = None  # shown until a change of the settings is applied
        self.scenario: Scenario | None = None
        self.outcomes: tuple[Outcome, ...] = ()
        self.t = 0.0
        self.timing = {"change": 0.0, "runs": 0.0, "front": 0.0}
        self._syncing = False
        self._pending: set[str] = set()
        self._scheduled = False
        self._front_at = -math.inf  # time.monotonic() of the last front and status refresh
        self._ran_at = -math.inf  # time.monotonic() of the last recompute
        self._due: set[str] = set()  # requests scheduled by _soon
        self._dirty = False  # a slider moved since the last recompute
        self._followed = False  # the goal's last change came from a drag in progress
        # what the next message to the page carries (_send), and what the page was last sent
        self._out: dict[str, Any] = {"sources": {}, "props": {}, "restart": False, "live": False}
        self._depth = 0
        self.shown: dict[str, dict[str, Any]] = {}
        self.shown_props: dict[str, dict[str, Any]] = {}
        self.restarts = 0  # messages that played the motion from the start
        layout = self._build()
        self._recompute(replay=False, refused=refused)
        # attached last: every change to a document's model graph walks the whole graph
        self.doc.add_root(layout)
        for source in (self.address, self.change, self.live, self.clip):  # the scripts' messages
            self.doc.add_root(source)
        self.doc.title = "emdm play"
        self.doc.template = template()

    # ------------------------------------------------------------------------- building
    def _build(self) -> Any:
        self.points = [
            ColumnDataSource({"x": [], "y": [], "s": []}, name=f"points{i}") for i in range(2)
        ]
        # the columns the glyphs read, empty here: the page fills them (apply.js)
        columns = ("t", "ex", "ey", "ew", "eh", "ea", "m", "E", "err", "alpha")
        self.steps = [
            ColumnDataSource({key: [] for key in columns}, name=f"steps{i}") for i in range(2)
        ]
        self.arms = [
            ColumnDataSource({"x": [], "y": [], "s": []}, name=f"arm-state{i}") for i in range(2)
        ]
        self.ells = [
            ColumnDataSource({"x": [], "y": [], "w": [], "h": [], "a": []}) for _ in range(2)
        ]
        self.qlines = [
            ColumnDataSource({"xs": [], "ys": [], "color": []}, name=f"qlines{i}") for i in range(2)
        ]
        # the first run's program at the scrubbed step: its tip velocity set, all states
        # (``velocity``) and the one drawn (``polygon``), the P velocity and the tip's velocity
        self.velocity = ColumnDataSource({"px": [], "py": []}, name="velocity")
        self.polygon = ColumnDataSource({"x": [], "y": []}, name="velocity-set")
        self.want = ColumnDataSource({"x0": [], "y0": [], "x1": [], "y1": []}, name="want")
        self.got = ColumnDataSource({"x0": [], "y0": [], "x1": [], "y1": []}, name="got")
        self.goal = ColumnDataSource({"x": [], "y": []}, name="goal")
        self.handles = ColumnDataSource({"x": [], "y": []}, name="handles")
        self.start = ColumnDataSource({"x": [], "y": []}, name="start")
        self.annulus = ColumnDataSource({"x": [0.0], "y": [0.0], "inner": [0.0], "outer": [1.0]})
        self.obstacles = ColumnDataSource({"xs": [], "ys": []})  # bodies, at t = 0
        self.stop_zones = ColumnDataSource({"xs": [], "ys": []})  # within the stop distance
        self.front_src = ColumnDataSource({"M": [], "E": [], "fill": [], "ratio": []}, name="front")
        self.front_now = ColumnDataSource({"M": [], "E": []}, name="front-now")
        # the pinned reference run (the first run when it was pinned), drawn grey and dotted
        self.ref = ColumnDataSource(
            {"t": [], "ex": [], "ey": [], "m": [], "E": [], "err": [], "alpha": []}, name="pinned"
        )
        self.pinned: tuple[Outcome, Scenario] | None = None
        self.coloured: list[list[Any]] = [[], []]  # renderers drawn in each run's colour
        self.goal.on_change("data", self._guard(self._on_goal))
        # a drag of the goal in progress: live.js writes where the hand is
        self.live = ColumnDataSource({"what": [], "x": [], "y": []}, name="live")
        self.live.on_change("data", self._guard(self._on_live))
        self.handles.on_change("data", self._guard(self._on_handles))

        self.scene = self._scene()
        self.plots = self._plots()
        controls = self._controls()
        transport = self._transport()
        sheet: list[Any] = [InlineStyleSheet(css=asset("play.css"))]
        # the status box has a fixed size and its content is written in place (status.js): a
        # Div's new text re-lays out every model of the page (10 ms), and the status changes
        # several times a second while the motion plays
        self.status = Div(
            width=SCENE,
            height=STATUS_H,
            stylesheets=sheet,
            name="status",
            styles={"overflow-y": "auto"},
        )
        self.status_html = ColumnDataSource({"html": [""]}, name="status-html")
        shown = CustomJS(
            args={"status": self.status, "source": self.status_html}, code=asset("status.js")
        )
        self.status_html.js_on_change("data", shown)
        self.doc.js_on_event("document_ready", shown)
        self.banner = Div(width=280 + SCENE + 2 * PLOT_W, stylesheets=sheet, name="banner")
        self.legend = Div(width=2 * PLOT_W, stylesheets=sheet)
        # the settings in force as the page address's query (address.js writes it to the URL);
        # a data source, not a hidden Div: a Div's change re-lays out the whole page (8 ms)
        self.address = ColumnDataSource({"query": [""]}, name="address")
        address = CustomJS(args={"address": self.address}, code=asset("address.js"))
        self.address.js_on_change("data", address)
        self.doc.js_on_event("document_ready", address)
        self.doc.js_on_event(
            "connection_lost", CustomJS(args={"banner": self.banner}, code=asset("reconnect.js"))
        )
        header = Div(
            text="<b>emdm playground</b> &nbsp; drag the &#9733; goal or the hollow joints of "
            "the start pose; move a slider; press Play",
            styles={"font-size": "18px"},
        )
        # the explanation under the scene, in view at 1280 x 720; the legend under the plots
        middle = column(self.scene, transport, self.status)
        layout = column(
            header,
            self.banner,
            row(controls, middle, column(self.plots, self.legend)),
        )
        frame = CustomJS(
            args={
                "scrub": self.scrub,
                "runs": [
                    {"points": p, "steps": s, "arm": a, "ell": e}
                    for p, s, a, e in zip(
                        self.points, self.steps, self.arms, self.ells, strict=True
                    )
                ],
                "cursors": self.cursors,
                "clock": self.clock,
                "velocity": {
                    "all": self.velocity,
                    "now": self.polygon,
                    "want": self.want,
                    "got": self.got,
                    "steps": self.steps[0],
                },
            },
            code=asset("frame.js"),
        )
        self.doc.js_on_event("document_ready", frame)
        self.doc.js_on_event(
            "document_ready",
            CustomJS(
                args={
                    "goal": self.goal,
                    "live": self.live,
                    "interval": DRAG_INTERVAL * 1e3,
                    "delay": LIVE_INTERVAL * 1e3,
                },
                code=asset("live.js"),
            ),
        )
        self.scrub.js_on_change("value", frame)
        self.scrub.js_on_change("step", frame)
        for source in (*self.points, *self.steps, self.velocity):
            source.js_on_change("data", frame)
        # every change of the runs arrives as one message (apply.js): Bokeh sends each changed
        # property as a message of its own, built with a reference to every model of the page
        # (0.8 ms each, 25 per change), and an array column as a websocket frame of its own
        self.models = {
            model.name: model
            for model in (
                *self.points,
                *self.steps,
                *self.qlines,
                self.velocity,
                self.start,
                self.front_src,
                self.front_now,
                self.ref,
                self.status_html,
                self.time_range,
                *(fig.y_range for fig in self.figures),
                self.pareto.x_range,
                self.scrub,
                self.save_toml,
                self.save_png,
                self.front_label,
                self.pareto_title,
            )
        }
        self.change = ColumnDataSource({"values": [np.zeros(0)], "meta": ["{}"]}, name="change")
        apply = CustomJS(
            args={"change": self.change, "models": self.models, "toggle": self.play},
            code=asset("apply.js"),
        )
        self.change.js_on_change("data", apply)
        self.doc.js_on_event("document_ready", apply)
        return layout

    def _scene(self) -> Any:
        fig = figure(
            width=SCENE,
            height=SCENE,
            x_range=Range1d(start=-1, end=1),
            y_range=Range1d(start=-1, end=1),
            match_aspect=True,
            tools=[],
            toolbar_location=None,
            title="workspace",
            x_axis_label="x (m)",
            y_axis_label="y (m)",
            name="scene",
            stylesheets=[":host(:focus), :host(:focus-visible) { outline: none; }"],
        )
        _style(fig)
        fig.annulus(
            "x",
            "y",
            inner_radius="inner",
            outer_radius="outer",
            source=self.annulus,
            fill_color="#000000",
            fill_alpha=0.06,
            line_color=None,
        )
        fig.patches(
            "xs",
            "ys",
            source=self.obstacles,
            fill_color="#777777",
            fill_alpha=0.55,
            line_color="#444444",
        )
        fig.patches(
            "xs",
            "ys",
            source=self.stop_zones,
            fill_alpha=0.0,
            line_color="#444444",
            line_dash="dashed",
        )
        fig.scatter([0], [0], marker="square", size=12, color="#333333")
        fig.line("x", "y", source=self.start, color="#888888", line_width=2, line_dash="dotted")
        fig.patch(  # the tip velocities the step's bounds allow, at the ellipse's scale
            "x",
            "y",
            source=self.polygon,
            fill_color=VELOCITY_COLOR,
            fill_alpha=0.07,
            line_color=VELOCITY_COLOR,
            line_alpha=0.8,
            line_dash="dotted",
            line_width=1.5,
        )
        fig.line(
            "ex", "ey", source=self.ref, color=PINNED_COLOR, line_width=2.5, line_dash="dotted"
        )
        cmap = LinearColorMapper(palette=list(JOINT_COLORS), low=-0.5, high=4.5)
        for i in (1, 0):  # the baseline (ghost) first, under EMDM
            ghost = i == 1
            trace = fig.line(
                "ex",
                "ey",
                source=self.steps[i],
                line_width=2,
                line_dash="dashed" if ghost else "solid",
                name=f"trace{i}",
            )
            ellipse = fig.ellipse(
                "x",
                "y",
                width="w",
                height="h",
                angle="a",
                source=self.ells[i],
                fill_alpha=0.08 if ghost else 0.22,
                line_alpha=0.5 if ghost else 0.9,
                line_dash="dashed" if ghost else "solid",
                name=f"ellipse{i}",
            )
            links = fig.line(
                "x",
                "y",
                source=self.arms[i],
                line_width=5 if ghost else 7,
                line_alpha=0.45 if ghost else 1.0,
                line_cap="round",
                name=f"arm{i}",
            )
            self.coloured[i] += [trace, ellipse, links]
            fig.scatter(
                "x",
                "y",
                source=self.arms[i],
                size=11 if ghost else 14,
                line_color="black",
                line_alpha=0.5 if ghost else 1.0,
                fill_alpha=0.6 if ghost else 1.0,
                fill_color={"field": "s", "transform": cmap},
            )
        heads = (OpenHead(size=9, line_color="#000000"), VeeHead(size=9, fill_color="#000000"))
        for source, dash, head in zip(
            (self.want, self.got), ("dashed", "solid"), heads, strict=True
        ):
            body: dict[str, Any] = {
                "line_width": 2,
                "line_dash": dash,
                "line_color": "#000",
            }  # bokeh's
            # stubs name these body_line_*, which bokeh 3.9 refuses: given as keywords at run time
            fig.add_layout(
                Arrow(
                    end=head,
                    x_start="x0",
                    y_start="y0",
                    x_end="x1",
                    y_end="y1",
                    source=source,
                    **body,
                )
            )
        handles = fig.scatter(
            "x",
            "y",
            source=self.handles,
            size=24,
            fill_alpha=0,
            line_color="#555555",
            line_width=2.5,
            name="handle-markers",
        )
        goal = fig.scatter(
            "x",
            "y",
            source=self.goal,
            marker="star",
            size=30,
            fill_color="#FFD700",
            line_color="black",
            line_width=1.5,
            name="goal-marker",
        )
        draggable: list[Any] = [goal, handles]
        tool = PointDrawTool(renderers=draggable, add=False, drag=True)
        fig.add_tools(tool)
        fig.toolbar.active_multi = tool
        self.clock = Label(
            x=8,
            y=8,
            x_units="screen",
            y_units="screen",
            text="t = 0.00 s",
            text_font_size="16px",
            level="overlay",
            text_color="#222222",
        )
        self.scale_note = Label(
            x=SCENE - 270,
            y=8,
            x_units="screen",
            y_units="screen",
            text="",
            text_font_size="12px",
            text_color="#666666",
        )
        fig.add_layout(self.clock)
        fig.add_layout(self.scale_note)
        return fig

    def _plots(self) -> Any:
        self.time_range = Range1d(start=0, end=1, name="time")
        self.cursors: list[Span] = []
        specs = [
            ("m", "manipulability m", "m"),
            ("E", "effort E = \u00bd\u2016q\u0307\u2016\u00b2 (rad\u00b2/s\u00b2)", "E"),
            ("err", "error \u2016e\u2016 (m)", "err"),
            ("alpha", "task scale \u03b1", "alpha"),
        ]
        figs = []
        # a read-out per run and plot: the time and the value, named by the run (see _draw)
        self.hovers: list[tuple[HoverTool, int, str]] = []
        for key, title, column_name in specs:
            fig = figure(
                width=PLOT_W,
                height=PLOT_H,
                x_range=self.time_range,
                y_range=Range1d(start=0, end=1, name=f"y-{key}"),
                title=title,
                tools=[],
                toolbar_location=None,
                name=f"plot-{key}",
            )
            _style(fig)
            fig.line(
                "t",
                column_name,
                source=self.ref,
                color=PINNED_COLOR,
                line_width=2.5,
                line_dash="dotted",
            )
            for i in (1, 0):
                line = fig.line(
                    "t",
                    column_name,
                    source=self.steps[i],
                    line_width=2.5,
                    line_dash="dashed" if i else "solid",
                    name=f"{key}{i}",
                )
                self.coloured[i].append(line)
                hover = HoverTool(renderers=[line], mode="vline", tooltips=[("t", "@t{0.00} s")])
                fig.add_tools(hover)
                self.hovers.append((hover, i, column_name))
            figs.append(fig)
        joints = figure(
            width=PLOT_W,
            height=PLOT_H,
            x_range=self.time_range,
            y_range=Range1d(start=0, end=1, name="y-q"),
            title="joint angles q (rad)",
            tools=[],
            toolbar_location=None,
            x_axis_label="t (s)",
        )
        _style(joints)
        # the influence zones (yellow) and the stop zones (purple) of joint 1 at both limits
        self.zones = [
            BoxAnnotation(fill_color=color, fill_alpha=0.3)
            for color in ("#F0E442", "#F0E442", "#CC79A7", "#CC79A7")
        ]
        self.limits = [
            Span(dimension="width", line_color="black", line_width=1.5) for _ in range(2)
        ]
        for item in (*self.zones, *self.limits):
            joints.add_layout(item)
        for i in (1, 0):
            joints.multi_line(
                "xs",
                "ys",
                source=self.qlines[i],
                line_color="color",
                line_width=2.5,
                line_dash="dashed" if i else "solid",
                line_alpha=0.6 if i else 1.0,
            )
        joints.add_tools(HoverTool(tooltips=[("t", "$x{0.00} s"), ("q", "$y{0.000} rad")]))
        figs.append(joints)
        pareto = figure(
            width=PLOT_W,
            height=PLOT_H,
            x_range=Range1d(start=0, end=1, name="x-pareto"),
            y_range=Range1d(start=0, end=1, name="y-pareto"),
            title="Pareto front",
            tools=[],
            toolbar_location=None,
            x_axis_label="manip. rate M",
            y_axis_label="effort E",
            name="plot-pareto",
        )
        _style(pareto)
        pareto.line("M", "E", source=self.front_src, color="#999999", line_width=1.5)
        points = pareto.scatter(
            "M",
            "E",
            source=self.front_src,
            size=8,
            fill_color="fill",
            line_color="#0072B2",
        )
        pareto.add_tools(
            HoverTool(
                renderers=[points],
                tooltips=[
                    ("w_M / w_E", "@ratio{0.[000]}"),
                    ("M", "@M{0.0000}"),
                    ("E", "@E{0.0000}"),
                ],
            )
        )
        pareto.scatter(
            "M",
            "E",
            source=self.front_now,
            size=20,
            fill_color=None,
            line_color="#D55E00",
            line_width=3,
        )
        self.front_label = Label(
            name="front-label",
            x=6,
            y=PLOT_H - 95,
            x_units="screen",
            y_units="screen",
            text="",
            text_font_size="13px",
            text_color="#D55E00",
        )
        pareto.add_layout(self.front_label)
        pareto.xaxis[0].ticker = BasicTicker(desired_num_ticks=3)
        pareto.yaxis[0].ticker = BasicTicker(desired_num_ticks=4)
        self.pareto_title = Title(text="Pareto front", text_font_size="15px", name="pareto-title")
        pareto.title = self.pareto_title
        self.pareto = pareto
        for fig in figs:
            # on the overlay layer: a frame that moves only the cursor leaves the curves
            # painted (repainting six plots per frame kept the page busy while playing)
            span = Span(
                location=0,
                dimension="height",
                line_color="#D55E00",
                line_width=1.5,
                level="overlay",
            )
            fig.add_layout(span)
            self.cursors.append(span)
        self.figures = [*figs, pareto]
        # the time axis zooms (Ctrl + wheel) and pans (drag) on every time plot at once; a double
        # click shows the whole run again (reset_start/reset_end, set with each run)
        reset = CustomJS(
            args={"r": self.time_range}, code="r.setv({start: r.reset_start, end: r.reset_end})"
        )
        for fig in figs:
            zoom = WheelZoomTool(dimensions="width", modifiers={"ctrl": True})
            pan = PanTool(dimensions="width")
            fig.add_tools(zoom, pan)
            fig.toolbar.active_scroll = zoom
            fig.toolbar.active_drag = pan
            fig.js_on_event("doubletap", reset)
        figs[2].xaxis.axis_label = "t (s)"
        figs[3].xaxis.axis_label = "t (s)"
        return gridplot(  # each plot keeps its own (hidden) toolbar: its active tools
            [figs[0], figs[1], figs[2], figs[3], figs[4], pareto],
            ncols=2,
            toolbar_location=None,
            merge_tools=False,
        )

    def _controls(self) -> Any:
        self.choose = Select(
            title="Scenario", options=list[Any](self.bases), value=self.settings.scenario, width=260
        )
        # no low/high: the browser would drop an out-of-range value without a word; the server
        # refuses it with a message instead (_on_links)
        self.links = Spinner(title="Number of links", step=1, value=2, width=260)
        self.pair = RadioButtonGroup(
            labels=["C: constrained", "UC: unconstrained"], active=0, width=260
        )
        self.policy = Select(
            title="When infeasible (C pair)",
            options=list[Any](map(str, POLICIES)),
            value="scale",
            width=260,
        )
        self.choose.on_change("value", self._guard(self._on_choose))
        self.links.on_change("value", self._guard(self._on_links))
        self.pair.on_change("active", self._guard(self._on_pair))
        self.policy.on_change("value", self._guard(self._on_policy))
        self.sliders: dict[str, Slider] = {}
        for control in CONTROLS:
            slider = Slider(
                title=control.label,
                start=control.start,
                end=control.end,
                step=control.step,
                value=control.start,
                width=260,
                name=f"slider-{control.name}",
                format=_log_format(control) if control.log else "0[.]000",
            )
            slider.on_change("value", self._guard(partial(self._on_slider, control)))
            slider.on_change("value_throttled", self._guard(self._on_release))
            self.sliders[control.name] = slider
        self.pin = Button(label="Pin as reference", width=260, name="pin")
        self.pin.on_click(lambda: self._safe(self._on_pin))
        reset = Button(label="Reset to the scenario", width=260)
        reset.on_click(lambda: self._safe(self._on_choose, "value", None, self.settings.scenario))
        self.save_toml = Button(
            label="Export scenario (TOML)", width=260, button_type="primary", name="save-toml"
        )
        self.save_png = Button(label="Export view (PNG)", width=260, name="save-png")
        self.save_toml.js_on_click(
            CustomJS(
                args={"button": self.save_toml}, code=asset("download.js") + asset("save_toml.js")
            )
        )
        self.save_png.js_on_click(
            CustomJS(
                args={"button": self.save_png, "scene": self.scene, "plots": self.plots},
                code=asset("download.js") + asset("save_png.js"),
            )
        )
        # the clip is written on the server (emdm.outputs.animate) in a worker thread, and its
        # bytes come back through a data source that save_clip.js downloads
        self.save_gif = Button(label="Export clip (GIF)", width=260, name="save-gif")
        self.save_gif.on_click(lambda: self._safe(self._on_clip))
        self.clip = ColumnDataSource({"gif": [], "name": []}, name="clip")
        self.clip.js_on_change(
            "data",
            CustomJS(args={"clip": self.clip}, code=asset("download.js") + asset("save_clip.js")),
        )
        return column(
            self.choose,
            self.links,
            self.pair,
            self.policy,
            *self.sliders.values(),
            self.pin,
            reset,
            self.save_toml,
            self.save_png,
            self.save_gif,
            width=280,
        )

    def _transport(self) -> Any:
        # one label for both states, pressed while playing: a label that changed re-laid out
        # the whole page (10 ms) whenever a new run started to play
        self.play = Toggle(label="\u25b6 Play", active=False, width=90, name="play")
        self.speed = RadioButtonGroup(labels=[f"{s:g}x" for s in SPEEDS], active=2, width=200)
        self.scrub = Slider(
            title="t (s)", start=0.0, end=1.0, step=0.05, value=0.0, width=SCENE, name="scrub"
        )
        self.play.js_on_change(
            "active",
            CustomJS(
                args={
                    "toggle": self.play,
                    "scrub": self.scrub,
                    "speed": self.speed,
                    "speeds": list(SPEEDS),
                    "interval": FRONT_INTERVAL * 1e3,
                },
                code=asset("play.js"),
            ),
        )
        self.scrub.on_change("value", self._guard(self._on_scrub))
        return column(row(self.play, self.speed), self.scrub)

    # ------------------------------------------------------------------------ callbacks
    def _safe(self, callback: Callable[..., None], *args: Any) -> None:
        """Run ``callback``; any failure is shown on the page and logged, never raised."""
        if self._syncing:
            return
        try:
            callback(*args)
        except Exception as exc:  # the server must survive anything a page sends
            log.exception("playground callback failed")
            self._show([f"internal error: {type(exc).__name__}: {exc}"], [])

    def _guard(self, callback: Callable[[str, Any, Any], None]) -> Callable[[str, Any, Any], None]:
        """``callback`` as a property-change callback run through :meth:`_safe`."""

        def on_change(attr: str, old: Any, new: Any) -> None:
            self._safe(callback, attr, old, new)

        return on_change

    def _request(self, what: str) -> None:
        """Recompute on the next tick; requests arriving before then are served together."""
        self._pending.add(what)
        if not self._scheduled:
            self._scheduled = True
            self.doc.add_next_tick_callback(lambda: self._safe(self._flush))

    def _flush(self) -> None:
        self._scheduled = False
        pending, self._pending = self._pending, set()
        if pending & {"run", "replay", "live"}:
            # "live" alone: a drag in progress, whose dragged point the page already shows
            self._recompute(replay="replay" in pending, live=pending <= {"live", "front"})
        elif "front" in pending:
            self._refresh_front()

    def _on_choose(self, attr: str, old: Any, new: Any) -> None:
        self.settings = Settings(scenario=str(new), pair=self.settings.pair)
        self._request("replay")

    def _on_pin(self) -> None:
        """Pin the first run as the reference the page compares with, or unpin it."""
        outcome = self.outcomes[0] if self.outcomes else None
        keys = ("t", "ex", "ey", "m", "E", "err", "alpha")
        if self.pinned is not None or outcome is None or outcome.run is None:
            self.pinned = None
            data: dict[str, Any] = {key: [] for key in keys}
        else:
            assert self.scenario is not None
            self.pinned = (outcome, self.scenario)
            steps = self.shown["steps0"]
            data = {key: steps[key] for key in keys}
        with self._message():
            self._put("pinned", data)
            self._fit_series()
            _set(self.pin, label="Unpin the reference" if self.pinned else "Pin as reference")
            if self.scenario is not None:
                _set(self.legend, text=self._legend(self.outcomes, self.scenario.n))
            self._refresh_status()

    def _on_clip(self) -> None:
        """Write a GIF of the runs shown, at the playback speed (faster for a long run), in a
        worker thread; the page is told when it is ready (:meth:`_clip_done`)."""
        runs = [o.run for o in self.outcomes if o.run is not None and o.run.steps > 0]
        if self.scenario is None or not runs or self.save_gif.disabled:
            return
        name = f"{self.scenario.name}-play.gif"
        active = self.speed.active
        speed = SPEEDS[active] if active is not None and 0 <= active < len(SPEEDS) else 1.0
        self.save_gif.update(disabled=True, label="Writing the clip\u2026")
        doc = self.doc
        future = _clip_worker().submit(logic.clip_gif, runs, speed)
        future.add_done_callback(
            lambda done: doc.add_next_tick_callback(lambda: self._safe(self._clip_done, done, name))
        )

    def _clip_done(self, done: Future[tuple[bytes, float]], name: str) -> None:
        self.save_gif.update(disabled=False, label="Export clip (GIF)")
        try:
            gif, speedup = done.result()
        except (EmdmError, ValueError, OSError) as exc:
            self._show([f"No clip: {exc}"], [])
            return
        self.clip.data = {"gif": [base64.b64encode(gif).decode("ascii")], "name": [name]}
        self.clip.data = {"gif": [], "name": []}  # the page keeps no copy of the bytes
        log.info("clip %s: %d kB at %gx", name, len(gif) // 1024, speedup)

    def _on_links(self, attr: str, old: Any, new: Any) -> None:
        valid = isinstance(new, int | float) and math.isfinite(new) and float(new).is_integer()
        if not valid or not logic.MIN_LINKS <= int(new) <= logic.MAX_LINKS:
            self._show(
                [
                    f"Not applied: Number of links must be a whole number from {logic.MIN_LINKS} "
                    f"to {logic.MAX_LINKS}, got {'an empty field' if new is None else new!r} (the page "
                    "shows the last valid settings)"
                ],
                [],
            )
            self._syncing = True  # the spinner shows the value in force again
            try:
                _set(
                    self.links,
                    value=self.settings.links or (self.scenario.n if self.scenario else 2),
                )
            finally:
                self._syncing = False
            return
        self.settings.links = int(new)
        self.settings.overrides.pop("motion.q0", None)
        self._request("replay")

    def _on_pair(self, attr: str, old: Any, new: Any) -> None:
        self.settings.pair = list(PAIRS)[int(new)]
        self._request("run")

    def _on_policy(self, attr: str, old: Any, new: Any) -> None:
        self.settings.overrides["controller.on_infeasible"] = str(new)
        self._request("run")

    def _on_slider(self, control: Control, attr: str, old: Any, position: Any) -> None:
        try:
            value = control.from_slider(float(position))
        except EmdmError as exc:
            self._show([logic.message(exc)], [])
            return
        self.settings.overrides.update(control.overrides(value))
        self._dirty = True
        self._soon("run", LIVE_INTERVAL, self._ran_at)  # moving: one recompute per interval

    def _soon(self, what: str, interval: float, last: float) -> None:
        """Request ``what`` now if ``interval`` (s) has passed since ``last`` (monotonic), else
        once, when it has (later calls in between are served by that one)."""
        wait = interval - (time.monotonic() - last)
        if wait <= 0:
            self._request(what)
        elif what not in self._due:
            self._due.add(what)
            self.doc.add_timeout_callback(
                lambda: self._safe(self._due_now, what), max(1, round(wait * 1e3))
            )

    def _due_now(self, what: str) -> None:
        self._due.discard(what)
        if what != "run" or self._dirty:  # a release may have served the slider already
            self._request(what)

    def _on_release(self, attr: str, old: Any, new: Any) -> None:
        """The slider was let go: its last value is shown now, not at the next live tick."""
        if self._dirty:
            self._request("run")

    def _on_live(self, attr: str, old: Any, new: Any) -> None:
        """A drag of the goal in progress (live.js): where the hand is. (A ring of the start pose
        is applied on release: its links beyond move with it, which the drag tool cannot show.)"""
        if list(new.get("what", []))[:1] == ["goal"]:
            self._on_goal(attr, old, new, request="live")

    def _on_goal(self, attr: str, old: Any, new: Any, request: str = "replay") -> None:
        x, y = list(new.get("x", [])), list(new.get("y", []))
        if self.scenario is None or len(x) != 1 or len(y) != 1:
            self._request("run")  # redraw what the page lost
            return
        point = [float(x[0]), float(y[0])]
        if not all(math.isfinite(v) for v in point):
            self._show(["motion.goal: the dragged goal is not a finite position"], [])
            return
        if np.allclose(point, self.scenario.motion.goal, rtol=0, atol=1e-12):
            if request == "replay" and self._followed:  # released where the run already goes
                self._followed = False
                self._request("replay")
            return
        self._followed = request == "live"
        self.settings.overrides["motion.goal"] = [round(v, 4) for v in point]
        self._request(request)

    def _on_handles(self, attr: str, old: Any, new: Any) -> None:
        if self.scenario is None:
            return
        was = self.scenario.planar_arm.joint_positions(self.scenario.motion.q0)[1:]
        try:
            now = np.column_stack((np.asarray(new["x"], float), np.asarray(new["y"], float)))
        except (KeyError, TypeError, ValueError):
            now = np.zeros(0)
        moved = logic.moved_point(was, now)
        if moved is None:
            if now.shape != was.shape:
                self._request("run")
            return
        try:
            q0 = logic.drag_start(self.scenario, moved + 1, now[moved])
        except EmdmError as exc:
            self._show([logic.message(exc)], [])
            return
        self.settings.overrides["motion.q0"] = [round(float(v), 6) for v in q0]
        self._request("replay")

    def _on_scrub(self, attr: str, old: Any, new: Any) -> None:
        self.t = float(new) if math.isfinite(float(new)) else 0.0
        self._soon("front", FRONT_INTERVAL, self._front_at)  # playing: one refresh per interval

    @property
    def status_text(self) -> str:
        """The status box's HTML: the explanations, the table of the step shown, the timing."""
        return str(self.shown.get("status-html", {"html": [""]})["html"][0])

    # ------------------------------------------------------------------------- updating
    def _show(self, errors: Sequence[str], notes: Sequence[str]) -> None:
        items = [f'<div class="error">{html.escape(e)}</div>' for e in errors]
        items += [f'<div class="note">{html.escape(n)}</div>' for n in notes]
        self.banner.text = "".join(items)

    def _recompute(self, *, replay: bool, refused: Sequence[str] = (), live: bool = False) -> None:
        """Run the settings in force and draw them; ``refused``: the page address's values that
        could not be used, shown as errors above the run; ``live``: during a drag (the dragged
        goal or ring is left to the drag tool)."""
        start = time.perf_counter()
        self._ran_at, self._dirty = time.monotonic(), False
        try:
            scenario = logic.build_scenario(self.bases, self.settings)
        except EmdmError as exc:
            shown = "the page shows the last valid settings" if self.scenario else "nothing to show"
            self._refusal = f"Not applied: {logic.message(exc)} ({shown})"
            self._show([*refused, self._refusal], [])
            if self.scenario is None:  # the address's values: drop the refused one, keep the rest
                key = getattr(exc, "key", "")
                if key in self.settings.overrides:
                    del self.settings.overrides[key]
                else:
                    self.settings = Settings(scenario=self.settings.scenario)
                self._recompute(
                    replay=replay, refused=[*refused, f"Not applied: {logic.message(exc)}"]
                )
                return
            # back to the settings in force, and every control showing them (a refused slider
            # value must not stay on screen beside plots of the earlier one)
            self.settings = copy.deepcopy(self._valid)
            end = max(
                [self.scenario.motion.dt] + [float(o.run.t[-1]) for o in self.outcomes if o.run]
            )
            self._syncing = True
            try:
                with self._message():  # what the widgets show goes out now, not with a later change
                    self._sync_widgets(self.scenario, end, replay=False)
            finally:
                self._syncing = False
            return
        if self.settings != self._valid:  # a change applied: an earlier refusal is history
            self._refusal = None
        self._valid = copy.deepcopy(self.settings)
        _set(self.address, data={"query": [logic.settings_query(self.settings)]})
        ran = time.perf_counter()
        outcomes = logic.run_pair(scenario, self.settings.pair)
        self.timing["runs"] = time.perf_counter() - ran
        self.scenario, self.outcomes = scenario, outcomes
        end = max([scenario.motion.dt] + [float(o.run.t[-1]) for o in outcomes if o.run])
        self.t = 0.0 if replay else min(self.t, end)
        with self._message(restart=replay, live=live):  # the runs, status and front: one message
            self.doc.hold("combine")  # the Python callbacks of held changes run later
            try:
                self._draw(scenario, outcomes, end)
                # a refused value stays explained while the page recomputes what is in force
                # (the release of the slider that was refused, the next tick of a playing motion)
                errors = [*refused, *([self._refusal] if self._refusal else [])]
                self._show(errors, list(scenario.warnings))
            finally:
                self.doc.unhold()
            self._syncing = True  # not held: these changes call back now, and are muted
            try:
                self._sync_widgets(scenario, end, replay, live=live)
            finally:
                self._syncing = False
            self.timing["change"] = time.perf_counter() - start
            self._refresh_front()

    # ---------------------------------------------------------------- one message a change
    def _put(self, name: str, data: dict[str, Any]) -> None:
        """The drawn source ``name`` gets ``data`` in the next message (see :meth:`_message`)."""
        self._out["sources"][name] = data
        self.shown[name] = data

    def _prop(self, name: str, **values: Any) -> None:
        """Properties of the model ``name`` set in the next message, if they changed."""
        changed = {k: v for k, v in values.items() if self.shown_props.get(name, {}).get(k) != v}
        if changed:
            self._out["props"].setdefault(name, {}).update(changed)
            self.shown_props.setdefault(name, {}).update(changed)

    @contextlib.contextmanager
    def _message(self, *, restart: bool = False, live: bool = False) -> Iterator[None]:
        """Collect what the block puts (:meth:`_put`, :meth:`_prop`) and send it as one message
        when the outermost block ends; ``restart``: the motion plays from the start; ``live``: a
        change of a drag in progress (a page whose drag has ended since skips it for the
        release's, which follows)."""
        self._out["restart"] |= restart
        self._out["live"] |= live
        self._depth += 1
        try:
            yield
        finally:
            self._depth -= 1
            if self._depth == 0:
                self._send()

    def _send(self) -> None:
        """One message to the page (apply.js): every numeric column end to end in one float64
        array (one websocket frame), the rest as JSON."""
        out = self._out
        self._out = {"sources": {}, "props": {}, "restart": False, "live": False}
        if not (out["sources"] or out["props"] or out["restart"]):
            return
        chunks: list[np.ndarray] = []
        size = 0

        def pack(value: Any) -> dict[str, Any]:
            nonlocal size
            if isinstance(value, list) and value and all(isinstance(v, np.ndarray) for v in value):
                return {"fs": [pack(v)["f"] for v in value]}
            array = np.asarray(value)
            if array.dtype.kind not in "fiub":
                return {"v": array.tolist()}
            chunks.append(array.astype(np.float64).ravel())
            size += chunks[-1].size
            return {"f": [size - chunks[-1].size, chunks[-1].size]}

        sources = {
            name: {key: pack(column) for key, column in data.items()}
            for name, data in out["sources"].items()
        }
        meta = {
            "sources": sources,
            "props": out["props"],
            "restart": out["restart"],
            "live": out["live"],
        }
        self.restarts += out["restart"]
        values = np.concatenate(chunks) if chunks else np.zeros(0)
        self.change.data = {"values": [values], "meta": [json.dumps(meta)]}

    def _draw(self, scenario: Scenario, outcomes: Sequence[Outcome], end: float) -> None:
        scale = logic.ellipse_scale(scenario)
        palette = [JOINT_LINES[j % len(JOINT_LINES)] for j in range(scenario.n)]
        for i, outcome in enumerate(outcomes):
            color = CONTROLLER_STYLE[outcome.name]["color"]
            run = outcome.run
            if run is None:
                if i == 0:
                    self._put("velocity", {"px": [], "py": []})
                self._put(f"points{i}", {"x": [], "y": [], "s": []})
                self._put(f"steps{i}", {"t": [], "ex": [], "ey": []})
                self._put(f"qlines{i}", {"xs": [], "ys": [], "color": []})
                continue
            points, steps = logic.scene_data(run, scale)
            if i == 0:  # the first run's program made visible (frame.js draws its step)
                velocity = logic.velocity_data(run, scale)
                steps |= {key: velocity[key] for key in ("vx", "vy", "ax", "ay")}
                self._put("velocity", {"px": velocity["px"], "py": velocity["py"]})
            self._put(f"points{i}", points)
            self._put(f"steps{i}", steps)
            self._put(
                f"qlines{i}",
                {
                    "xs": [run.t] * scenario.n,
                    "ys": [run.q[:, j] for j in range(scenario.n)],
                    "color": palette,
                },
            )
            for renderer in self.coloured[i]:
                fill = {"fill_color": color} if renderer.name.startswith("ellipse") else {}
                _set(renderer.glyph, line_color=color, **fill)
        self._fit_series()
        arm = scenario.planar_arm
        reach = arm.reach * 1.1
        for rng in (self.scene.x_range, self.scene.y_range):
            _set(rng, start=-reach, end=reach)
        if self.annulus.data["outer"] != [arm.reach] or self.annulus.data["inner"] != [
            arm.inner_reach
        ]:
            self.annulus.data = {
                "x": [0.0],
                "y": [0.0],
                "inner": [arm.inner_reach],
                "outer": [arm.reach],
            }
        views = Views(scenario)  # the obstacles as the figures draw them, at t = 0
        for source, grow in (
            (self.obstacles, 0.0),
            (self.stop_zones, scenario.obstacle_damper.stop),
        ):
            outlines = views.obstacle_outlines(np.eye(2), 0.0, grow) if scenario.obstacles else []
            _set(
                source,
                data={
                    "xs": [o[:, 0].tolist() for o in outlines],
                    "ys": [o[:, 1].tolist() for o in outlines],
                },
            )
        start = arm.joint_positions(scenario.motion.q0)
        self._prop("time", start=0.0, end=end, reset_start=0.0, reset_end=end)
        for hover, i, key in self.hovers:  # the read-out names its run
            name = outcomes[i].name if i < len(outcomes) else ""
            _set(hover, tooltips=[(name, ""), ("t", "@t{0.00} s"), (key, f"@{{{key}}}")])
        self._put("start", {"x": start[:, 0], "y": start[:, 1]})
        _set(self.scale_note, text=f"ellipse: {scale:.2g} m per m/s of tip speed")
        self._limits(scenario)
        name = f"{scenario.name}-play"
        toml = logic.export_toml(dataclasses.replace(scenario, name=name))
        self._prop("save-toml", tags=[toml, f"{name}.toml"])
        self._prop("save-png", tags=[f"{name}.png", self._caption(scenario, outcomes)])
        _set(self.legend, text=self._legend(outcomes, scenario.n))

    def _fit(self, name: str, *columns: Any) -> None:
        """The plot range ``name`` shows ``columns`` (:func:`_fitted`); kept without a value."""
        fitted = _fitted(*columns)
        if fitted is not None:
            self._prop(name, **fitted)

    def _fit_series(self) -> None:
        """The value ranges of the time plots (both runs and the pinned one) and of the joint
        angles, from what they draw."""
        runs = [self.shown.get(name, {}) for name in ("steps0", "steps1", "pinned")]
        for key in ("m", "E", "err", "alpha"):
            self._fit(f"y-{key}", *(data.get(key, []) for data in runs))
        angles = [y for i in range(2) for y in self.shown.get(f"qlines{i}", {}).get("ys", [])]
        self._fit("y-q", *angles)

    def _sync_widgets(
        self, scenario: Scenario, end: float, replay: bool, *, live: bool = False
    ) -> None:
        """Show the scenario's values: goal, start pose, widgets, scrub bar; ``replay`` plays
        the motion from the start; ``live``: a drag of the goal is in progress, and the goal and
        the rings stay as the drag tool moves them (setting them, or clearing their selection, would end
        the drag). Called with the callbacks muted."""
        if not live:
            start = scenario.planar_arm.joint_positions(scenario.motion.q0)
            goal = scenario.motion.goal
            # a dragged goal stays where the page shows it: the scenario's is that point rounded
            # to 0.1 mm (_on_goal), and sending it back cost the page a paint of its own before
            # the change's
            shown = np.asarray([*self.goal.data["x"], *self.goal.data["y"]], dtype=float)
            if shown.shape != (2,) or not np.allclose(shown, goal, rtol=0, atol=1e-4):
                _set(self.goal, data={"x": [float(goal[0])], "y": [float(goal[1])]})
            _set(self.handles, data={"x": start[1:, 0].tolist(), "y": start[1:, 1].tolist()})
            self.goal.selected.indices = []
            self.handles.selected.indices = []
        self._prop("scrub", end=end, step=scenario.motion.dt)
        if replay or self.scrub.value > end:  # the page's time, where the server moved it
            self._out["props"].setdefault("scrub", {})["value"] = self.t
        _set(self.choose, value=self.settings.scenario)
        _set(self.links, value=scenario.n)
        _set(self.pair, active=list(PAIRS).index(self.settings.pair))
        _set(self.policy, value=str(scenario.controller.on_infeasible))
        # controls that change nothing here are greyed out: the policy acts on the C pair only,
        # the slack weight on an arm with as many joints as task rows (or among obstacles) only
        _set(self.policy, disabled=self.settings.pair != "C")
        for control in CONTROLS:
            slider = self.sliders[control.name]
            position = control.to_slider(control.value(scenario))
            if abs(slider.value - position) > control.step / 2:
                slider.value = position
            if control.key == "weights.slack":
                _set(slider, disabled=scenario.redundant and not scenario.obstacles)
        # a replay plays the motion from the start (apply.js; the Toggle is set only if paused)

    def _limits(self, scenario: Scenario) -> None:
        arm, damper = scenario.arm, scenario.damper
        low, high = float(arm.q_min[0]), float(arm.q_max[0])
        inf, stop = float(damper.influence[0]), float(damper.stop[0])
        bands = [
            (high - inf, high - stop),
            (low + stop, low + inf),
            (high - stop, high),
            (low, low + stop),
        ]
        for box, (bottom, top) in zip(self.zones, bands, strict=True):
            _set(box, bottom=bottom, top=top)
        _set(self.limits[0], location=low)
        _set(self.limits[1], location=high)

    def _caption(self, scenario: Scenario, outcomes: Sequence[Outcome]) -> str:
        w = scenario.weights
        parts = [f"{o.name}: {logic.time_to_goal(o)}" for o in outcomes]
        return (
            f"emdm playground: {scenario.name}, {scenario.n} links, w_E = {w.effort:g}, "
            f"w_M = {w.manipulability:g}, goal ({scenario.motion.goal[0]:.2f}, "
            f"{scenario.motion.goal[1]:.2f}) m; " + "; ".join(parts)
        )

    def _legend(self, outcomes: Sequence[Outcome], n: int) -> str:
        line = '<span class="line {}" style="border-color:{}"></span>'
        swatch = '<span class="sw" style="background:{}"></span>'
        items = []
        for outcome, kind, what in zip(outcomes, ("solid", "ghost"), ("", ", ghost"), strict=True):
            color = CONTROLLER_STYLE[outcome.name]["color"]
            items.append(f"{line.format(kind, color)}{outcome.name}{what}")
        for code, text in enumerate(logic.JOINT_STATES[:4]):
            items.append(f"{swatch.format(JOINT_COLORS[code])}{text}")
        first = outcomes[0].name if outcomes else "EMDM"
        items.append(  # the program of the first run at the scrubbed step
            f"{line.format('dotted', VELOCITY_COLOR)}tip velocities {first}'s bounds allow"
        )
        items.append(f"{line.format('ghost', '#000000')}P velocity")
        items.append(f"{line.format('solid', '#000000')}tip velocity J qd")
        if self.pinned is not None:
            items.append(f"{line.format('dotted', PINNED_COLOR)}pinned {self.pinned[0].name}")
        joints = "".join(  # the joint-angle plot's curves
            f"{line.format('solid', JOINT_LINES[j % len(JOINT_LINES)])}q{j + 1} " for j in range(n)
        )
        items.append(joints.strip())
        return (
            '<div class="legend">'
            + "".join(f'<span class="item">{i}</span>' for i in items)
            + "</div>"
        )

    def _refresh_status(self) -> None:
        scenario = self.scenario
        if scenario is None:
            return
        tables = [dict(logic.status_rows(outcome, self.t)) for outcome in self.outcomes]
        labels = list(dict.fromkeys(label for table in tables for label in table))
        rows = {label: [table.get(label, "") for table in tables] for label in labels}
        head = "".join(f"<th>{html.escape(o.name)}</th>" for o in self.outcomes)
        body = "".join(
            f"<tr><td>{html.escape(label)}</td>"
            + "".join(f"<td>{html.escape(v)}</td>" for v in values)
            + "</tr>"
            for label, values in rows.items()
        )
        why = "".join(
            f"<p><b>{html.escape(o.name)}</b>: {html.escape(logic.explain(scenario, o))}</p>"
            for o in self.outcomes
        )
        if len(self.outcomes) == 2:
            pair = logic.explain_pair(*self.outcomes)
            why += f"<p>{html.escape(pair)}</p>" if pair else ""
        ms = {key: f"{value * 1e3:.1f}" for key, value in self.timing.items()}
        timing = (
            f'<p class="timing">server: this change <span class="change">{ms["change"]}</span> ms '
            f'(both runs <span class="runs">{ms["runs"]}</span> ms); Pareto front '
            f'<span class="front">{ms["front"]}</span> ms</p>'
        )
        # the explanation first: it is what a teacher reads out, and it stays in view; the
        # comparison with a pinned run after the table of the step shown
        text = (
            f'{why}<table class="status"><tr><th></th>{head}</tr>{body}</table>'
            f"{self._comparison()}{timing}"
        )
        with self._message():
            self._put("status-html", {"html": [text]})

    def _comparison(self) -> str:
        """The first run against the pinned one: what changed in the scenario, and a table of
        outcomes with their changes."""
        if self.pinned is None or not self.outcomes or self.scenario is None:
            return ""
        (pinned, scenario), now = self.pinned, self.outcomes[0]
        rows = logic.compare(now, pinned)
        if not rows:
            return ""
        changes = logic.scenario_changes(scenario, self.scenario)
        shown = changes[:3] + ([f"and {len(changes) - 3} more"] if len(changes) > 3 else [])
        what = "; ".join(shown) if shown else "the same scenario"
        head = (
            f"<p><b>Against the pinned run</b> ({html.escape(pinned.name)}, grey dotted); "
            f"changed since: {html.escape(what)}</p>"
        )
        body = "".join(
            "<tr>" + "".join(f"<td>{html.escape(cell)}</td>" for cell in row) + "</tr>"
            for row in rows
        )
        return (
            f'{head}<table class="status"><tr><th></th><th>{html.escape(now.name)} now</th>'
            f"<th>pinned</th><th>change</th></tr>{body}</table>"
        )

    def _refresh_front(self) -> None:
        scenario = self.scenario
        if scenario is None or not self.outcomes:
            return
        start = time.perf_counter()
        self._front_at = time.monotonic()
        result = logic.front(scenario, self.outcomes[0], self.t)
        self.timing["front"] = time.perf_counter() - start
        with self._message():
            fill = np.where(result.dominated, "white", "#0072B2")
            self._put("front", {"M": result.M, "E": result.E, "fill": fill, "ratio": result.ratio})
            self._fit("x-pareto", result.M)
            self._fit("y-pareto", result.E)
            if result.current >= 0:
                label = f"\u25ef w_M / w_E = {result.ratio[result.current]:.3g}"
                self._prop("front-label", text=label)
                self._put(
                    "front-now", {"M": [result.M[result.current]], "E": [result.E[result.current]]}
                )
            else:
                self._prop("front-label", text="")
                self._put("front-now", {"M": [], "E": []})
            # short enough for the plot's 250 px: "Pareto, t = 12.35 s (1 point)"
            title = f"Pareto, t = {result.t:.2f} s" + (" (1 point)" if result.single else "")
            self._prop(
                "pareto-title", text=title if not result.message else f"no front: {result.message}"
            )
            self._refresh_status()


LIVE_INTERVAL = 0.1
"""While a slider moves, both runs are recomputed at most this often (s); its release is shown at
once. Recomputing at every move queued work that the release then waited for."""
DRAG_INTERVAL = 0.05
"""While the goal is dragged, the page sends where it is at most this often (s), from
:data:`LIVE_INTERVAL` after the drag began (live.js; a shorter drag is a flick, shown on
release): a change costs the server about 6 ms and the page one paint."""
FRONT_INTERVAL = 0.15
"""While the motion plays, the Pareto front and the status follow the scrub bar at most this
often (s): refreshing them at every frame kept the server and the page busy when a drag came."""


@cache
def _clip_worker() -> ThreadPoolExecutor:
    """One thread for the clips of every tab: a clip takes about 2 s, and the server goes on
    answering meanwhile."""
    return ThreadPoolExecutor(max_workers=1, thread_name_prefix="emdm-clip")


def build(doc: Document, bases: dict[str, Scenario]) -> None:
    """The Bokeh application: a new :class:`Session` for every page load."""
    Session(doc, bases)
