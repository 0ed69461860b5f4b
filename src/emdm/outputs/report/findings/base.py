"""The story's shared part: symbols, the data accessors and the rules several sections use.

The study's story: direct answers and explanations, every number read from the records.

Each section opens with a one-sentence direct answer to its brief item, then explains what
shaped the runs from the detected events (``events.json``), backed by evidence runs
(``evidence.json``) that isolate each cause. Sentences are chosen by the data (a stall is only
described when one was detected, a comparison says "more" or "less" by the sign), never canned.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ....core.controllers import Name
from ....core.tolerances import STALL_BAND
from ....solvers import registered_solvers
from ....studies.lab import LIKE_FOR_LIKE, exact_answer
from ...paper_figures import EFFORT_FLOOR, FAR_BEYOND, GAP_FLOOR
from ..config import FOURTH_PANEL, PAIRS
from ..document import Figure, Table
from ..trace import Data, File, Math, Num, PageOnly, Ref, Sentence, Text, cap, sentence, traced
from .records import (
    GRID_FILE,
    EventKey,
    EvidenceKey,
    FrontKey,
    GeometryKey,
    GridKey,
    LabName,
    MetricKey,
    PairKey,
    Records,
    SolverKey,
    SolverRow,
)

EFFORT_FLOOR_EXP = round(math.log10(EFFORT_FLOOR))
"""The decade the pair figures' effort axis is floored at (Fig. 1's caption says it)."""

GAP_FLOOR_EXP = round(math.log10(GAP_FLOOR))
"""The decade the tracking-gap axis is floored at (Fig. 5's caption says it)."""
GAP_MATH = Math(r"\|J\dot q-v_d\|", "‖<i>J q̇</i> − <i>v</i><sub>d</sub>‖")
"""The tracking gap, as the captions of the figures that draw it write it."""
GAP_FLOOR_MATH = Math(rf"10^{{{GAP_FLOOR_EXP}}}", f"10<sup>−{-GAP_FLOOR_EXP}</sup>")
"""Its axis' floor, as they write it."""

# ---------------------------------------------------------------------------- inline math
ALPHA = Math(r"\alpha^*", "α*")
"""The task scale of (2), α* wherever a value is given (editor after readings 209, 210: α and
α* were one thing under two names)."""
W_M = Math("w_M", "<i>w</i><sub>M</sub>")
W_E = Math("w_E", "<i>w</i><sub>E</sub>")
W_S = Math(r"w_S=c_S/\|e\|", "<i>w</i><sub>S</sub>&nbsp;=&nbsp;<i>c</i><sub>S</sub>/‖<i>e</i>‖")
W_S_SYM = Math("w_S", "<i>w</i><sub>S</sub>")
C_S = Math("c_S", "<i>c</i><sub>S</sub>")
RATIO = Math("w_M/w_E", "<i>w</i><sub>M</sub>/<i>w</i><sub>E</sub>")
M_SYM = Math("m", "<i>m</i>")
E_SYM = Math("E", "<i>E</i>")
SUM_E = Math(r"\sum E\Delta t", "Σ<i>E</i>Δ<i>t</i>")
"""A run's total effort (rad²/s), Table II's column; spent so far, the pair figures' (b)."""
MRATE = Math("M", "<i>M</i>")
ERR = Math(r"\|e\|", "‖<i>e</i>‖")
DELTA = Math(r"\|\delta\|", "‖δ‖")
DT = Math(r"\Delta t", "Δ<i>t</i>")
COND_J = Math(r"\operatorname{cond}J", "cond&nbsp;<i>J</i>")
VD = Math(r"v_d", "<i>v</i><sub>d</sub>")
T_EQ = Math("t={}", "<i>t</i>&nbsp;=&nbsp;")
K_EQ = Math("k={}", "<i>k</i>&nbsp;=&nbsp;")
QDOT = Math(r"\dot q", "<i>q̇</i>")


def q(j: int) -> Math:
    return Math(f"q_{j}", f"<i>q</i><sub>{j}</sub>")


def qd(j: int) -> Math:
    return Math(rf"\dot q_{j}", f"<i>q̇</i><sub>{j}</sub>")


def eq(symbol: Math, value: Num) -> list[Any]:
    """``symbol = value`` as one piece of a sentence."""
    return [symbol, Text(" = "), value]


def more_for_more(gain: Num, cost: Num) -> Sentence:
    """``1% more mean m for 21% more effort``: a rise in mean m and the rise in effort it costs
    (both unsigned: the caller has checked that both rise)."""
    return sentence(gain, " more mean ", M_SYM, " for ", cost, " more effort")


def bare(num: Num) -> Num:
    """The number without its unit (a table states the unit in its header)."""
    return Num(num.text, num.src, num.fmt, num.op)


def _flat(*parts: Any) -> Sentence:
    out: list[Any] = []
    for p in parts:
        if isinstance(p, list):
            out.extend(p)
        else:
            out.append(p)
    return sentence(*out)


GRID_MISS = "t1-uc-grid-miss"
"""Table II's run from the weight grid: its first setting that misses the goal (Fig. 2, right)."""

FINER_STEP = "t1-uc-finer-step"
"""Table II's run of :data:`GRID_MISS`'s weights at a five times finer time step."""

ABLATIONS: tuple[str | tuple[str, ...], ...] = (
    "t1-uc-no-manip",
    (GRID_MISS, FINER_STEP),
    "t2-c-ivkc-wide-limits",
    "t2-c-emdm-no-manip",
    "t2-c-emdm-tight-slack",
    "t2-uc-emdm-no-manip",
)
"""Table II's runs in order, each changing one thing in a nominal run; :func:`run_label` names
them A1, A2, ..., and the runs of a group A2a, A2b, ... (A for ablation: E is the effort; the
free-slack policy runs are Table II's rows, not ablations)."""


def square_box(lo: Sequence[float], hi: Sequence[float]) -> bool:
    """Whether a slack box is one symmetric interval on every axis, ``[-b, b]^n``: the paper
    and the page then write it so (the formulation's ``D``, the Task 1 brief-slack run)."""
    return len(set(hi)) == 1 and all(-float(v) == float(hi[0]) for v in lo)


def glossed(solver: str) -> str:
    """A solver's name with what kind of method it is, at its first mention in the paper's
    text ("slsqp (sequential quadratic programming)"); the name alone where the registry says
    nothing more (:attr:`SolverSpec.method`)."""
    spec = registered_solvers().get(solver)
    return f"{solver} ({spec.method})" if spec is not None and spec.method else solver


ABLATION_PREFIX = "A"
"""The letter of Table II's ablation labels (A for ablation; E is the effort, readings 190)."""


def ablation_span() -> str:
    """Table II's ablation labels as one range, ``A1–A6``."""
    return f"{ABLATION_PREFIX}1–{ABLATION_PREFIX}{len(ABLATIONS)}"


def run_label(key: str) -> str:
    """Table II's label of an ablation: ``A1`` for the first of :data:`ABLATIONS`, ``A2b`` for
    the second run of the second entry when that entry is a group."""
    for n, entry in enumerate(ABLATIONS, 1):
        if entry == key:
            return f"{ABLATION_PREFIX}{n}"
        if isinstance(entry, tuple) and key in entry:
            return f"{ABLATION_PREFIX}{n}{'abcdefgh'[entry.index(key)]}"
    raise KeyError(f"{key!r} is not one of Table II's runs")


def _dig(node: Any, path: tuple[str | int, ...]) -> Any:
    """``node[path[0]][path[1]]...`` (an index into a list, a key into an object)."""
    for key in path:
        node = node[int(key)] if isinstance(node, list) else node[str(key)]
    return node


ARMS_IN_PAPER = False
"""Whether Task 1's stills (the arms at the end of each run, their tip paths) are printed in
the paper. Every reading finds the four end poses piled up (UC-EMDM's and C-EMDM's coincide);
taken out for the convergence figure (readings 178-180), they were missed (183: no picture of
Task 1's arm) and put back; readings 176, 179 and 184 asked them cut. They are on the page
(Fig. 1's caption names the animations) so that the paper has room for its definitions and
plainer sentences (readability: the MAJOR of readings 176-185)."""

SINGLE_POINT = 1e-9
"""rad/s: an admissible set no wider than this (by linear programming) is one point."""

SCALED_LAB = "data/task1-lab-C-EMDM/solvers.json"
"""The lab whose task-scaled steps are measured (Task 1's C-EMDM: 38 of them)."""


class StoryBase:
    """The data, the figures and tables made so far, and what every section reads them with."""

    """Builds the :class:`Document` from the report's data files."""

    def __init__(self, data: Data) -> None:
        self.d = data
        self.rec = Records.load(data)  # typed, checked once: a missing field stops here
        self.figures: dict[str, Figure] = {}
        self.tables: dict[str, Table] = {}
        self.answers: list[tuple[str, Sentence]] = []

    # ------------------------------------------------------------------ data accessors
    # (keys are literal types: mypy refuses one the records do not have)
    def mt(self, task: str, ctrl: str, key: MetricKey, fmt: str, unit: str = "") -> Num:
        value = self.mv(task, ctrl, key)
        return traced(value, f"data/{task}/metrics.json", ("controllers", ctrl, key), fmt, unit)

    def single_point_vertex(self) -> dict[str, Any] | None:
        """Task 1's measured scaled vertex (``challenges.scaled_vertex``) when every scaled step
        had a single admissible command, else None (not measured, or a wider set)."""
        if not self.d.exists(SCALED_LAB):
            return None
        vertex = self.d.value(SCALED_LAB, "challenges", "scaled_vertex")
        return vertex if vertex and vertex["max_width"] <= SINGLE_POINT else None

    def mv(self, task: str, ctrl: str, key: MetricKey) -> Any:
        return getattr(self.rec.outcomes[task][ctrl], key)

    def ev(
        self, task: str, ctrl: str, key: EventKey, *path: str | int, fmt: str, unit: str = ""
    ) -> Num:
        value = self.evv(task, ctrl, key, *path)
        where = ("controllers", ctrl, key, *path)
        return traced(value, f"data/{task}/events.json", where, fmt, unit)

    def evv(self, task: str, ctrl: str, key: EventKey, *path: str | int) -> Any:
        return _dig(getattr(self.rec.events[task][ctrl], key), path)

    def pair(self, task: str, group: str, key: PairKey) -> Any:
        return getattr(self.rec.pairs[task][group], key)

    def pairn(self, task: str, group: str, key: PairKey, fmt: str, unit: str = "") -> Num:
        value = self.pair(task, group, key)
        return traced(value, f"data/{task}/events.json", ("pairs", group, key), fmt, unit)

    def evid(self, key: EvidenceKey, *path: str | int) -> Any:
        if not path:
            return dataclasses.asdict(self.rec.evidence[key])
        return _dig(getattr(self.rec.evidence[key], str(path[0])), path[1:])

    def evidn(self, key: EvidenceKey, *path: str | int, fmt: str, unit: str = "") -> Num:
        value = self.evid(key, *path)
        return traced(value, "data/evidence.json", ("runs", key, *path), fmt, unit)

    def override(self, key: EvidenceKey, field: str, *index: int, fmt: str, unit: str = "") -> Num:
        """The value the evidence run ``key`` sets in place of the nominal one (``"arm.q_max"``,
        ``"slack.max", 0``), traced to its record."""
        return self.evidn(key, "overrides", field, *index, fmt=fmt, unit=unit)

    def weight_off(self, key: EvidenceKey) -> Sentence:
        """An evidence run's dexterity weight, as its change: ``w_M = 0``."""
        return sentence(*eq(W_M, self.override(key, "weights.manipulability", fmt="g")))

    def limits_widened(self, text: bool = False) -> Sentence:
        """The widened joint limits of Table II's run: ``|q| <= 3 rad`` in a table cell, ``±3 rad``
        in a sentence (``text``); the interval where they are not symmetric."""
        key: EvidenceKey = "t2-c-ivkc-wide-limits"
        lo, hi = (self.evid(key, "overrides", f) for f in ("arm.q_min", "arm.q_max"))
        top = self.override(key, "arm.q_max", fmt=".3g", unit="rad")
        if lo != -hi:
            return sentence("[", self.override(key, "arm.q_min", fmt=".3g"), ", ", top, "]")
        if text:
            return sentence("±", top)
        return sentence(Math(r"|q|\leq", "|<i>q</i>| ≤ "), top)

    def solvers(self, lab: LabName) -> dict[str, SolverRow]:
        """A solver lab's rows by solver (empty when the report ran no such lab)."""
        found = self.rec.labs.get(lab)
        return found.solvers if found else {}

    def sn(
        self, lab: LabName, solver: str, key: SolverKey, fmt: str = ".4g", unit: str = ""
    ) -> Num:
        """A solver's field in a lab, traced; ``unit="ms"`` writes a time in milliseconds."""
        value = getattr(self.rec.labs[lab].solvers[solver], key)
        op = "ms" if unit == "ms" else None
        if op and fmt == ".4g":  # three significant digits, trailing zeros kept (reading 165:
            fmt = "#.3g"  # a median of 74 beside 61.9 read as a rounding slip)
        return traced(value, f"data/{lab}/solvers.json", ("solvers", solver, key), fmt, unit, op)

    def evaluations(self, lab: LabName, solver: str) -> Sentence:
        """A solver's median count on a lab's programs: ``6 objective and 5 gradient
        evaluations`` for a gradient-based method (its gradients counted too, reading 160),
        ``522 evaluations`` for the others."""
        gradients = self.solvers(lab)[solver].median_gradients
        return sentence(
            self.sn(lab, solver, "median_evaluations", ".4g"),
            *(
                (" objective and ", self.sn(lab, solver, "median_gradients", ".4g"), " gradient")
                if gradients
                else ()
            ),
            " evaluations",
        )

    def scn(self, task: str, *path: str | int, fmt: str, unit: str = "") -> Num:
        """A parameter of a task's scenario (``"motion", "dt"``; ``"arm", "qd_max", 0``), read
        from the typed :class:`~emdm.core.scenario.Scenario` and traced to its record."""
        value: Any = self.rec.scenarios[task]
        for step in path:
            value = value[step] if isinstance(step, int) else getattr(value, step)
        value = value.item() if hasattr(value, "item") else value
        return traced(value, f"data/{task}/metrics.json", ("scenario", *path), fmt, unit)

    def geon(self, task: str, key: GeometryKey, *path: str | int, fmt: str, unit: str = "") -> Num:
        """A field of a two-link task's geometry (``solutions``: index, then field), traced."""
        value = _dig(dataclasses.asdict(self.rec.geometry[task])[key], path)
        return traced(value, f"data/{task}/events.json", ("geometry", key, *path), fmt, unit)

    def front(self, ctrl: str, i: int, key: FrontKey) -> Any:
        """A field of Task 1's Pareto front at its ``i``-th studied step (``ctrl``'s)."""
        return getattr(self.rec.fronts[ctrl][i], key)

    def frontn(self, ctrl: str, i: int, key: FrontKey, fmt: str, unit: str = "") -> Num:
        file = f"data/task1-pareto-{ctrl}/fronts.json"
        return traced(self.front(ctrl, i, key), file, ("steps", i, key), fmt, unit)

    def grid(self, ctrl: str, i: int, key: GridKey, *path: str) -> Any:
        """A field of the ``i``-th run of Task 1's weight grid (``ctrl``'s)."""
        return _dig(getattr(self.rec.grids[ctrl][i], key), path)

    def gridn(self, ctrl: str, i: int, key: GridKey, *path: str, fmt: str, unit: str = "") -> Num:
        file = GRID_FILE.format(ctrl=ctrl)
        return traced(self.grid(ctrl, i, key, *path), file, ("runs", i, key, *path), fmt, unit)

    def evid_goal(self, key: EvidenceKey, ctrl: str) -> Num:
        """The time to goal of ``ctrl`` in the evidence run ``key``."""
        return self.evidn(key, "runs", ctrl, "time_to_goal", fmt=".2f", unit="s")

    def elbow_flip_forced(self, task: str) -> bool:
        """Whether every goal configuration within the limits has its elbow on the other side
        from the start (a two-link arm's ``m = l1 l2 |sin q2|`` must then pass through 0)."""
        geo = self.rec.geometry.get(task)
        if geo is None:
            return False
        inside = [s for s in geo.solutions if s.within_limits]
        return bool(inside) and all(s.elbow != geo.start_elbow for s in inside)

    def goal_pose(self, task: str) -> str:
        """``the elbow-down goal configuration``: the one goal configuration within the joint
        limits, named by its elbow (readings 190, 191: "admissible" was undefined); "the
        admissible goal configuration" where the limits leave more than one or none."""
        geo = self.rec.geometry.get(task)
        inside = [s for s in geo.solutions if s.within_limits] if geo is not None else []
        if len(inside) == 1:
            return f"the elbow-{inside[0].elbow} goal configuration"
        return "the admissible goal configuration"

    def pct(self, task: str, a: str, b: str, key: MetricKey, fmt: str = "+.0f") -> Num:
        f = f"data/{task}/metrics.json"
        return self.d.pct((f, "controllers", a, key), (f, "controllers", b, key), fmt)

    def cut(self, task: str, a: str, b: str, key: MetricKey) -> Num:
        """How much less ``a``'s ``key`` is than ``b``'s, in percent (``27%`` below)."""
        f = f"data/{task}/metrics.json"
        return self.d.cut((f, "controllers", a, key), (f, "controllers", b, key))

    def ttg(self, task: str, ctrl: str) -> Num:
        return self.mt(task, ctrl, "time_to_goal", ".2f", "s")

    def anim(self, task: str, group: str) -> dict[str, Any] | None:
        if not self.d.exists("data/animations.json"):
            return None
        found: dict[str, Any] | None = self.d.value("data/animations.json", "animations").get(
            f"{task}-{group}"
        )
        return found

    # ------------------------------------------------------------------ comparisons
    def more_less(self, task: str, a: str, b: str, key: MetricKey) -> str:
        return "more" if self.mv(task, a, key) > self.mv(task, b, key) else "less"

    def higher_lower(self, task: str, a: str, b: str, key: MetricKey) -> str:
        return "higher" if self.mv(task, a, key) > self.mv(task, b, key) else "lower"

    def outcome(self, task: str, ctrl: str) -> Sentence:
        """``reaches the goal in X s`` or ``stalls at Y m from the goal``."""
        if self.mv(task, ctrl, "reached"):
            return sentence("reaches the goal in ", self.ttg(task, ctrl))
        stall = self.evv(task, ctrl, "stall")
        if stall:
            return sentence(
                "never reaches the goal: it stalls, its distance to the goal staying at ",
                self.ev(task, ctrl, "stall", "error", fmt=".3f", unit="m"),
                f" (±{STALL_BAND * 1e3:g} mm) from ",
                self.ev(task, ctrl, "stall", "t", fmt=".2f", unit="s"),
                " on",
            )
        return sentence(
            "does not reach the goal within ",
            self.mt(task, ctrl, "final_time", ".0f", "s"),
            " (final error ",
            self.mt(task, ctrl, "final_error", ".3f", "m"),
            ")",
        )

    # ------------------------------------------------------------------ figures, tables
    def figure(
        self, key: str, stem: str, caption: Sentence, wide: bool = False, paper: bool = True
    ) -> str:
        if self.d.exists(f"paper/{stem}.png"):
            self.figures[key] = Figure(key, stem, caption, wide, paper=paper)
        return key

    def has_figure(self, key: str) -> bool:
        return key in self.figures

    def dearest_later(self, ctrl: str = "UC-EMDM") -> int | None:
        """The later Pareto step whose nominal optimum costs most over its effort-minimal one,
        when that is more than at k = 0 (else None): the nominal weights' price grows."""
        steps = self.rec.fronts.get(ctrl, [])
        if not steps or not steps[0].zero_E:
            return None
        later = [
            (info.nominal_E / info.zero_E, i)
            for i, info in enumerate(steps)
            if i > 0 and info.zero_E
        ]
        if not later or max(later)[0] <= steps[0].nominal_E / steps[0].zero_E:
            return None
        return max(later)[1]

    @staticmethod
    def exact(rows: dict[str, SolverRow], family: str) -> list[str]:
        """The solvers of ``family`` whose answers are exact (gap and violation tiny)."""
        return [
            k
            for k, r in rows.items()
            if r.family == family
            and r.failures == 0
            and exact_answer(r.max_abs_gap, r.max_violation)
        ]

    @staticmethod
    def best(rows: dict[str, SolverRow], family: str) -> str | None:
        """The fastest of :meth:`exact`'s solvers of ``family`` (the like-for-like control
        :data:`~emdm.studies.lab.LIKE_FOR_LIKE` aside)."""
        exact = [k for k in StoryBase.exact(rows, family) if k != LIKE_FOR_LIKE]
        return min(exact, key=lambda k: rows[k].median_time) if exact else None

    def _policy_terms(self) -> list[tuple[MetricKey, bool]]:
        """Task 1's C-EMDM under the slack policy (Table I) against scaling, per outcome: (metric,
        whether the slack run is better on it)."""
        run = self.evid("t1-c-slack-policy", "runs", Name.C_EMDM)
        out = []
        terms: tuple[tuple[MetricKey, bool], ...] = (
            ("time_to_goal", False),
            ("total_effort", False),
            ("mean_manipulability", True),
        )
        for metric, higher_better in terms:
            new, old = run[metric], self.mv("task1", Name.C_EMDM, metric)
            out.append((metric, new > old if higher_better else new < old))
        return out

    def policy_weighed(self) -> Sentence:
        """Task scaling, the paper's own choice, weighed against the free slack (Table I)."""
        e2: EvidenceKey = "t1-c-slack-policy"
        emdm = Name.C_EMDM
        words = {
            "time_to_goal": (sentence("arrives sooner"), sentence("arrives later")),
            "total_effort": (sentence(", with less effort"), sentence(", with more effort")),
            "mean_manipulability": (
                sentence(" and a higher mean ", M_SYM),
                sentence(" and a lower mean ", M_SYM),
            ),
        }
        terms = self._policy_terms()
        # the finding first (a plain-language edit), said only when it holds on every outcome
        p = sentence(
            "Here, a free slack beats scaling: with it, C-EMDM "
            if all(better for _, better in terms)
            else "Scaling has a price: with a free slack instead, C-EMDM "
        )
        for metric, better in terms:
            p += words[metric][0 if better else 1]
        p += sentence(
            " (",
            Ref("tab", "outcomes"),
            "). Scaling only keeps its path straighter (",
            self.mt("task1", emdm, "path_length", ".2f", "m"),
            " against ",
            self.evidn(e2, "runs", emdm, "path_length", fmt=".2f", unit="m"),
            ")",
            PageOnly(  # (on the page: room for the many goals)
                tuple(
                    sentence(
                        "; the slack, up to ",
                        self.evidn(e2, "runs", emdm, "max_abs_slack", fmt=".2f", unit="m/s"),
                        # per axis: the record's largest |delta_i| (Task 2 quotes norms; 172)
                        " per axis, bends it",
                    )
                )
            ),
            ".",
        )
        return p

    def brief_slack(self) -> Sentence:
        """`` With the brief's slack box D = [-delta_max, delta_max]^2, delta_max = 1 m/s, on
        this arm too (its Table 1 lists it), C-EMDM needs no scaling: it arrives in 7.65 s with
        mean m 0.309 and effort 1.563 (nominal: 8.15 s, 0.300, 2.631); UC-EMDM arrives in 7.40 s
        ...`` (readings 269, 277: the brief's Task 1 slack was never tried); the page only,
        each run's outcomes beside its nominal ones, its arrival or stall said as Table I's."""
        key: EvidenceKey = "t1-brief-slack"
        if key not in self.rec.evidence:
            return []
        runs = self.evid(key, "runs")
        done = [c for c in (Name.C_EMDM, Name.UC_EMDM) if c in runs and "error" not in runs[c]]
        if not done:
            return []
        box = self.rec.scenarios["task1"].slack
        out = sentence(" With the brief's slack box ")
        if square_box(list(box.min), list(box.max)):
            out += sentence(
                Math(
                    r"D=[-\delta_{\max},\delta_{\max}]^2",
                    "<i>D</i> = [−<i>δ</i><sub>max</sub>, <i>δ</i><sub>max</sub>]²",
                ),
                ", ",
                Math(r"\delta_{\max}=", "<i>δ</i><sub>max</sub> = "),
                self.scn("task1", "slack", "max", 0, fmt="g", unit="m/s"),
            )
        else:
            out += sentence(Math("D", "<i>D</i>"))
        out += sentence(", on this arm too (its Table 1 lists it), ")
        for i, c in enumerate(done):
            run = runs[c]
            head = sentence(c)
            if i == 0 and c == Name.C_EMDM and run["scaled_steps"] == 0:
                head += sentence(" needs no scaling: it")
            if run["reached"]:
                head += sentence(
                    " arrives in ",
                    self.evidn(key, "runs", c, "time_to_goal", fmt=".2f", unit="s"),
                )
            else:
                head += sentence(" stalls" if run["events"]["stall"] else " misses the goal")
            out += head + sentence(
                " with mean ",
                M_SYM,
                " ",
                self.evidn(key, "runs", c, "mean_manipulability", fmt=".3f"),
                " and effort ",
                self.evidn(key, "runs", c, "total_effort", fmt=".3f"),
                " (nominal: ",
                *(
                    sentence(self.mt("task1", c, "time_to_goal", ".2f", "s"))
                    if self.mv("task1", c, "reached")
                    else sentence("stall")
                ),
                ", ",
                self.mt("task1", c, "mean_manipulability", ".3f"),
                ", ",
                self.mt("task1", c, "total_effort", ".3f"),
                ")",
                "; " if i < len(done) - 1 else ".",
            )
        return out

    # ------------------------------------------------------------------ Task 1
    @staticmethod
    def panels(far: bool = False, path: bool = False) -> Sentence:
        """The panels of a pair figure (:func:`emdm.outputs.paper_figures.pair_figure`), as its
        captions name them (without the final stop); ``path``: its fourth panel, the tip paths,
        the joints then (e) and (f)."""
        joints = ("(e)", "(f)") if path else ("(d)", "(e)")
        out = sentence(
            "(a) manipulability ",
            M_SYM,
            ", (b) effort ",
            E_SYM,
            " (log, floored at ",
            Math(rf"10^{{{EFFORT_FLOOR_EXP}}}", f"10<sup>−{-EFFORT_FLOOR_EXP}</sup>"),
            "), (c) distance to goal ",
            ERR,
            " (log; dotted: tolerance), ",
        )
        if path:
            out += sentence("(d) tip paths (dotted: the straight line), ")
        out += sentence(
            f"{joints[0]} joint positions with limits and influence zones (orange), {joints[1]} "
            # grey beyond both kinds of limit (reading 220: a position past its limit did not
            # read as a violation); the notes as sentences (a plain-language edit)
            "joint velocities, limits dotted. Grey: beyond a limit"
        )
        if far:  # each cut joint's peak written at its cut (the runs' peaks: Table II's column)
            out += sentence(  # (245, 248, 250, 255: "speeds cut at 1.5x ..." cryptic)
                f". Speed axes stop at {FAR_BEYOND:g}× the limit; the largest clipped peak is "
                "labelled in its run's colour"
            )
        return out

    def far_beyond(self, task: str, controllers: Sequence[str]) -> bool:
        """Whether a pair figure of ``controllers`` ticks a joint's peak speeds beyond the
        limits (:data:`~emdm.outputs.paper_figures.FAR_BEYOND`): a run's peak speed far beyond
        the joints' smallest limit."""
        limit = float(np.min(np.abs(self.rec.scenarios[task].arm.qd_max)))
        return any(self.mv(task, c, "max_abs_qd") > FAR_BEYOND * limit for c in controllers)

    def pair_caption(self, task: str, group: str) -> Sentence:
        """A pair figure's caption: its panels in full for the first (Task 1.1's), by reference
        to it for the others, then what this pair's figure adds (the scaled span, the time axes'
        end)."""
        ivkc, emdm = PAIRS[group]
        notes: list[Sentence] = []
        if (
            self.pair(task, group, "coincide_scaled_steps")
            and self.pair(task, group, "coincide_all_scaled") is not None
        ):
            scaled = self.evv(task, emdm, "scaling")
            if scaled and not scaled["whole_run"]:
                notes.append(sentence("hatched: both scaled"))
        # time axes end at the last arrival when the one run that missed had stalled by then
        # (paper_figures.time_end, the same rule on the same records)
        missed = [c for c in (ivkc, emdm) if not self.mv(task, c, "reached")]
        if len(missed) == 1:
            arrived = emdm if missed == [ivkc] else ivkc
            stall = self.evv(task, missed[0], "stall")
            if stall and stall["t"] <= self.mv(task, arrived, "time_to_goal"):
                notes.append(
                    sentence(f"time axes end at {arrived}'s arrival ({missed[0]} stalled)")
                )
        out = sentence(f"{ivkc} (solid), {emdm} (dashed)")
        if (task, group) == ("task1", "UC"):
            far = self.far_beyond(task, PAIRS[group])
            out += sentence(": ") + self.panels(far, path=FOURTH_PANEL[task] == "path")
            if not ARMS_IN_PAPER and self.anim(task, group):  # (the stills' caption named them)
                out += sentence(". Animations: ", File(f"animations/{task}/"))
        elif (task, group) == ("task2", "UC"):  # as Task 2.1's, its run without the term dotted
            key: EvidenceKey = "t2-uc-emdm-no-manip"
            out += sentence(", as in ", Ref("fig", "t2-c"))
            if key in self.rec.evidence and not self.evid(key, "runs", emdm).get("error"):
                out += sentence(f"; dotted: {run_label(key)}")  # (its legend says w_M = 0)
        else:
            out += sentence(", as in ", Ref("fig", "t1-uc"))
        if (task, group) == ("task2", "C"):  # pair_figure(..., gap=True): the fourth panel
            # one short sentence per part, no nested parentheses (editor after readings 209, 210)
            key = "t2-c-slack-policy"  # its like-for-like run, dotted (reading 169)
            if key in self.rec.evidence and self.evid(key, "runs", ivkc).get("reached"):
                out += sentence(f"; dotted: {ivkc} with a free slack")
            out += sentence(
                ". Panel (d): the tracking gap ",
                GAP_MATH,
                ", the slack or ",
                Math(r"(1-\alpha^*)\|v_d\|", "(1 − α*)‖<i>v</i><sub>d</sub>‖"),
                " lost to scaling",
                "; log, floored at ",
                GAP_FLOOR_MATH,
                "" if FOURTH_PANEL["task1"] == "path" else ". Joints: (e), (f)",
            )
            # its notes as sentences too, after the panel's
            notes = [sentence(". ") + cap(note) for note in notes]
        else:
            notes = [sentence("; ") + note for note in notes]
        for note in notes:
            out += note
        return out + sentence(".")
