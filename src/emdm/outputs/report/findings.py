"""The study's story: direct answers and explanations, every number read from the records.

Each section opens with a one-sentence direct answer to its brief item, then explains what
shaped the runs from the detected events (``events.json``), backed by evidence runs
(``evidence.json``) that isolate each cause. Sentences are chosen by the data (a stall is only
described when one was detected, a comparison says "more" or "less" by the sign), never canned.
"""

from __future__ import annotations

import math
from typing import Any

from ...core.controllers import Name
from ...core.tolerances import STALL_BAND
from ..paper_figures import GAP_FLOOR
from .config import BYLINE, PAIRS
from .document import Document, Figure, Section, Table
from .trace import Cite, Data, Math, Num, Ref, Sentence, Text, format_value, sentence

FLOOR_EXP = round(math.log10(GAP_FLOOR))
"""The decade the paper's tracking-gap axis is floored at (its caption says it)."""

# ---------------------------------------------------------------------------- inline math
ALPHA = Math(r"\alpha", "α")
ALPHA_LT1 = Math(r"\alpha<1", "α&nbsp;&lt;&nbsp;1")
W_M = Math("w_M", "<i>w</i><sub>M</sub>")
W_E = Math("w_E", "<i>w</i><sub>E</sub>")
W_S = Math(r"w_S=c_S/\|e\|", "<i>w</i><sub>S</sub>&nbsp;=&nbsp;<i>c</i><sub>S</sub>/‖<i>e</i>‖")
W_S_SYM = Math("w_S", "<i>w</i><sub>S</sub>")
C_S = Math("c_S", "<i>c</i><sub>S</sub>")
RATIO = Math("w_M/w_E", "<i>w</i><sub>M</sub>/<i>w</i><sub>E</sub>")
M_SYM = Math("m", "<i>m</i>")
E_SYM = Math("E", "<i>E</i>")
MRATE = Math("M", "<i>M</i>")
ERR = Math(r"\|e\|", "‖<i>e</i>‖")
DELTA = Math(r"\|\delta\|", "‖δ‖")
DT = Math(r"\Delta t", "Δ<i>t</i>")
COND_J = Math(r"\operatorname{cond}J", "cond&nbsp;<i>J</i>")
VD = Math(r"v_d", "<i>v</i><sub>d</sub>")
T_EQ = Math("t={}", "<i>t</i>&nbsp;=&nbsp;")


def q(j: int) -> Math:
    return Math(f"q_{j}", f"<i>q</i><sub>{j}</sub>")


def qd(j: int) -> Math:
    return Math(rf"\dot q_{j}", f"<i>q̇</i><sub>{j}</sub>")


def eq(symbol: Math, value: Num) -> list[Any]:
    """``symbol = value`` as one piece of a sentence."""
    return [symbol, Text(" = "), value]


def bare(num: Num) -> Num:
    """The number without its unit (a table states the unit in its header)."""
    return Num(num.text, num.src, num.fmt, num.op)


def _words(count: int) -> str:
    return {1: "one", 2: "two", 3: "three", 4: "four"}.get(count, str(count))


def _flat(*parts: Any) -> Sentence:
    out: list[Any] = []
    for p in parts:
        if isinstance(p, list):
            out.extend(p)
        else:
            out.append(p)
    return sentence(*out)


class Story:
    """Builds the :class:`Document` from the report's data files."""

    def __init__(self, data: Data) -> None:
        self.d = data
        self.figures: dict[str, Figure] = {}
        self.tables: dict[str, Table] = {}
        self.answers: list[tuple[str, Sentence]] = []

    # ------------------------------------------------------------------ data accessors
    def mt(self, task: str, ctrl: str, key: str, fmt: str, unit: str = "") -> Num:
        return self.d.num(f"data/{task}/metrics.json", "controllers", ctrl, key, fmt=fmt, unit=unit)

    def mv(self, task: str, ctrl: str, key: str) -> Any:
        return self.d.value(f"data/{task}/metrics.json", "controllers", ctrl, key)

    def ev(self, task: str, ctrl: str, *path: str | int, fmt: str, unit: str = "") -> Num:
        return self.d.num(
            f"data/{task}/events.json", "controllers", ctrl, *path, fmt=fmt, unit=unit
        )

    def evv(self, task: str, ctrl: str, *path: str | int) -> Any:
        return self.d.value(f"data/{task}/events.json", "controllers", ctrl, *path)

    def pair(self, task: str, group: str, key: str) -> Any:
        return self.d.value(f"data/{task}/events.json", "pairs", group, key)

    def pairn(self, task: str, group: str, key: str, fmt: str, unit: str = "") -> Num:
        return self.d.num(f"data/{task}/events.json", "pairs", group, key, fmt=fmt, unit=unit)

    def evid(self, key: str, *path: str | int) -> Any:
        return self.d.value("data/evidence.json", "runs", key, *path)

    def evidn(self, key: str, *path: str | int, fmt: str, unit: str = "") -> Num:
        return self.d.num("data/evidence.json", "runs", key, *path, fmt=fmt, unit=unit)

    def evid_goal(self, key: str, ctrl: str) -> Num:
        """The time to goal of ``ctrl`` in the evidence run ``key``."""
        return self.evidn(key, "runs", ctrl, "time_to_goal", fmt=".2f", unit="s")

    def pct(self, task: str, a: str, b: str, key: str) -> Num:
        f = f"data/{task}/metrics.json"
        return self.d.pct((f, "controllers", a, key), (f, "controllers", b, key))

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
    def more_less(self, task: str, a: str, b: str, key: str) -> str:
        return "more" if self.mv(task, a, key) > self.mv(task, b, key) else "less"

    def higher_lower(self, task: str, a: str, b: str, key: str) -> str:
        return "higher" if self.mv(task, a, key) > self.mv(task, b, key) else "lower"

    def outcome(self, task: str, ctrl: str) -> Sentence:
        """``reaches the goal in X s`` or ``stalls at Y m from the goal``."""
        if self.mv(task, ctrl, "reached"):
            return sentence("reaches the goal in ", self.ttg(task, ctrl))
        stall = self.evv(task, ctrl, "stall")
        if stall:
            return sentence(
                "never reaches the goal: it stalls after ",
                self.ev(task, ctrl, "stall", "t", fmt=".2f", unit="s"),
                " at ",
                self.ev(task, ctrl, "stall", "error", fmt=".3f", unit="m"),
                f" from it, its distance staying within {STALL_BAND * 1e3:g} mm from then on",
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

    # ================================================================== the document
    def build(self) -> Document:
        sections = [
            self.introduction(),
            Section("formulation", "Formulation", partial="formulation"),
            Section("task1", "Task 1: the redundant three-link arm"),
            self.task1_uc(),
            self.pareto(),
            self.task1_c(),
            self.task1_solver(),
            Section("task2", "Task 2: the non-redundant two-link arm"),
            self.task2_c(),
            self.task2_solvers(),
            self.task2_uc(),
            self.task2_challenges(),
            self.conclusion(),
            self.beyond(),
        ]
        self.outcome_table(sections)
        self.evidence_table(sections)
        for sec in sections:
            sec.figures = [k for k in sec.figures if k in self.figures]
        byline = self.d.load(BYLINE) if self.d.exists(BYLINE) else {}
        doc = Document(
            title=byline.get("title")
            or "Effort-Minimising, Dexterity-Maximising Velocity Control of Planar Arms",
            authors=tuple(byline.get("authors", ())),
            abstract=self.abstract(),
            sections=[s for s in sections if s is not None],
            figures=self.figures,
            tables=self.tables,
            answers=self.answers,
        )
        doc.number()
        return doc

    # ------------------------------------------------------------------ abstract, intro
    def abstract(self) -> Sentence:
        t1, t2 = "task1", "task2"
        out = sentence(
            "We pose velocity control of planar arms as one quadratic program per step that tracks "
            "a proportional controller's end-effector velocity, minimises joint-velocity effort "
            "and maximises the manipulability rate (EMDM), and compare it with inverse velocity "
            "kinematics (IVKC). On a redundant three-link arm EMDM tracks as IVKC does and raises "
            "the mean manipulability by ",
            self.pct(t1, Name.UC_EMDM, Name.UC_IVKC, "mean_manipulability"),
            " without and ",
            self.pct(t1, Name.C_EMDM, Name.C_IVKC, "mean_manipulability"),
            " with joint limits, for ",
            self.pct(t1, Name.UC_EMDM, Name.UC_IVKC, "total_effort"),
            " and ",
            self.pct(t1, Name.C_EMDM, Name.C_IVKC, "total_effort"),
            " effort. ",
        )
        if not self.mv(t2, Name.C_IVKC, "reached") and self.mv(t2, Name.C_EMDM, "reached"):
            out += sentence(
                "On a two-link arm with limits, C-IVKC under our task scaling stalls ",
                self.ev(t2, Name.C_IVKC, "stall", "error", fmt=".2f", unit="m"),
                " from the goal",
            )
            e4 = self.evid("t2-c-ivkc-slack-policy", "runs", Name.C_IVKC)
            if e4.get("reached"):
                out += sentence(
                    " (with a slack instead it arrives in ",
                    self.evid_goal("t2-c-ivkc-slack-policy", Name.C_IVKC),
                    ")",
                )
            out += sentence(
                "; C-EMDM's slack leaves the blocked straight line and arrives in ",
                self.ttg(t2, Name.C_EMDM),
            )
            e6 = self.evid("t2-c-emdm-no-manip", "runs", Name.C_EMDM)
            if e6.get("reached") and e6["time_to_goal"] < self.mv(t2, Name.C_EMDM, "time_to_goal"):
                out += sentence(
                    "; without the dexterity term it arrives sooner (",
                    self.evid_goal("t2-c-emdm-no-manip", Name.C_EMDM),
                    ")",
                )
            out += sentence(". ")
        f = "data/task2-lab-C-EMDM/solvers.json"
        if self.d.exists(f):
            rows = self.d.value(f, "solvers")
            grad = self.best(rows, "gradient")
            free = self.best(rows, "gradient-free")
            if grad:
                out += sentence(
                    "Gradient-based ",
                    grad,
                    " solves each program exactly in a median ",
                    self.d.ms(f, "solvers", grad, "median_time"),
                )
                if free:
                    out += sentence(
                        "; the only exact gradient-free method, "
                        if len(self.exact(rows, "gradient-free")) == 1
                        else "; the fastest exact gradient-free method, ",
                        free,
                        ", needs ",
                        self.d.ms(f, "solvers", free, "median_time"),
                        " (",
                        self.d.ms(f, "solvers", free, "p95_time"),
                        " at the 95th percentile).",
                    )
                else:
                    out += sentence("; every gradient-free method is inexact.")
        return out

    def introduction(self) -> Section:
        sec = Section("intro", "Introduction")
        sec.paragraphs.append(
            sentence(
                "A planar arm must bring its end effector to a goal while spending little "
                "joint-velocity effort and staying dexterous, i.e. keeping a large manipulability ",
                M_SYM,
                ". A redundant arm (three joints for a planar task) can do both; a non-redundant "
                "arm (two joints) can only trade tracking for dexterity through a task slack. As "
                "in",
                Cite("haviland"),
                ", we write each control step as a strictly convex quadratic program (QP), solve it "
                "with a certified custom active-set method, and compare this EMDM controller with "
                "IVKC, each unconstrained (UC-) or constrained by joint limits (C-). Every number "
                "is read from the study's records, and every explanation is backed by an evidence "
                "run that changes one thing (",
                Ref("tab", "evidence"),
                ").",
            )
        )
        anims = [a for a in (self.anim(t, g) for t in ("task1", "task2") for g in PAIRS) if a]
        if anims:
            last = anims[-1]
            p = sentence(
                "Animations of every pair, with the manipulability ellipse, lie in animations/ "
                "beside this paper (e.g. ",
                f"{last['task']}/{last['files'][-1]}",
            )
            if last["speedup"] != 1.0:
                p += sentence(
                    ", played ",
                    self.d.num(
                        "data/animations.json",
                        "animations",
                        f"{last['task']}-{last['pair']}",
                        "speedup",
                        fmt=".0f",
                    ),
                    " times faster",
                )
            p += sentence(")")
            if self.d.exists("figures/task2-lab-C-EMDM/convergence.png"):
                p += sentence("; index.html beside it adds the solvers' convergence histories")
            sec.paragraphs.append(p + sentence("."))
        return sec

    # ------------------------------------------------------------------ Task 1
    @staticmethod
    def panels(gap: bool = False) -> Sentence:
        """The five panels of a pair figure (:func:`emdm.outputs.paper_figures.pair_figure`),
        as its captions name them (without the final stop); ``gap``: panel (c) is the
        velocity-tracking gap (``pair_figure(..., gap=True)``)."""
        third = (
            sentence(
                "(c) velocity-tracking gap ",
                Math(r"\|J\dot q-v_d\|", "‖<i>J q̇</i> − <i>v</i><sub>d</sub>‖"),
                " (log axis, floored at ",
                Math(rf"10^{{{FLOOR_EXP}}}", f"10<sup>−{-FLOOR_EXP}</sup>"),
                ": the slack ",
                DELTA,
                ", or the scaled-off part ",
                Math(r"(1-\alpha)\|v_d\|", "(1 − α)‖<i>v</i><sub>d</sub>‖"),
                ")",
            )
            if gap
            else sentence(
                "(c) distance to the goal ", ERR, " (log axis; dotted: the arrival tolerance)"
            )
        )
        return (
            sentence(
                "(a) manipulability ",
                M_SYM,
                ", (b) effort ",
                E_SYM,
                " (log axis, floored at ",
                Math(r"10^{-9}", "10<sup>−9</sup>"),
                "), ",
            )
            + third
            + sentence(
                ", (d) joint positions with their limits and damper influence and stop zones, "
                "(e) joint velocities with their limits"
            )
        )

    def pair_caption(self, task: str, group: str) -> Sentence:
        ivkc, emdm = PAIRS[group]
        out = sentence(f"{ivkc} (solid) against {emdm} (dashed): ") + self.panels() + sentence(".")
        if (
            self.pair(task, group, "coincide_scaled_steps")
            and self.pair(task, group, "coincide_all_scaled") is not None
        ):
            scaled = self.evv(task, emdm, "scaling")
            if scaled and not scaled["whole_run"]:
                out += sentence(" Grey: both task-scaled (", ALPHA_LT1, ").")
        return out

    def task1_uc(self) -> Section:
        t = "task1"
        ivkc, emdm = PAIRS["UC"]
        sec = Section("t1-uc", "Task 1.1: UC-EMDM against UC-IVKC", level=2, brief="1.1")
        same_time = self.mv(t, ivkc, "time_to_goal") == self.mv(t, emdm, "time_to_goal")
        gap = self.pairn(
            t,
            "UC",
            "max_path_gap",
            ".1e" if self.pair(t, "UC", "max_path_gap") < 1e-3 else ".4f",
            "m",
        )
        answer = sentence(f"{emdm} tracks the goal as {ivkc} does (")
        if same_time and self.mv(t, emdm, "reached"):
            answer += sentence("both reach it in ", self.ttg(t, emdm))
        else:
            answer += sentence(
                f"{emdm} ", *self.outcome(t, emdm), f", {ivkc} ", *self.outcome(t, ivkc)
            )
        answer += sentence(
            "; their end-effector paths differ by at most ",
            gap,
            "; distances to the goal in ",
            Ref("fig", "t1-uc"),
            "(c)) and raises the mean manipulability by ",
            self.pct(t, emdm, ivkc, "mean_manipulability"),
            " (",
            self.mt(t, emdm, "mean_manipulability", ".3f"),
            " against ",
            self.mt(t, ivkc, "mean_manipulability", ".3f", "m²"),
            f") for {self.more_less(t, emdm, ivkc, 'total_effort')} effort (",
            self.pct(t, emdm, ivkc, "total_effort"),
            ").",
        )
        sec.answer = answer
        self.answers.append(
            (
                "Task 1.1: implement and compare UC-EMDM and UC-IVKC; discuss tracking "
                "and manipulability",
                answer,
            )
        )
        sec.figures.append(self.figure("t1-uc", "figures/task1-UC", self.pair_caption(t, "UC")))
        # why the tracking is the same
        p = sentence(
            "Both programs impose ",
            Math(r"J\dot q=v_d", "<i>J q̇</i> = <i>v</i><sub>d</sub>"),
            " exactly, so the end effector follows the same path; only the second-order term of "
            "the Euler step separates the two. The controllers differ in their null-space motion "
            "alone: with ",
            W_M,
            " = 0 (E1) ",
        )
        ref = self.evid("t1-uc-no-manip", "reference")
        if ref["max_abs_qd_difference"] == 0.0 and ref["same_steps"]:
            p += sentence(f"{emdm} reproduces {ivkc} command for command. ")
        else:
            p += sentence(
                f"{emdm} differs from {ivkc} by at most ",
                self.evidn(
                    "t1-uc-no-manip", "reference", "max_abs_qd_difference", fmt=".1e", unit="rad/s"
                ),
                ". ",
            )
        p += sentence(
            "That motion raises ",
            M_SYM,
            " to ",
            self.mt(t, emdm, "final_manipulability", ".3f", "m²"),
            f" ({ivkc}: ",
            self.mt(t, ivkc, "final_manipulability", ".3f", "m²"),
            ") and is paid for early: ",
            self.ev(t, ivkc, "effort", "share_first_second", fmt=".0%"),
            " and ",
            self.ev(t, emdm, "effort", "share_first_second", fmt=".0%"),
            " of the total effort fall in the first second, where ",
            ERR,
            " is largest. Neither controller sees the joint limits: ",
        )
        for name in (ivkc, emdm):
            if self.evv(t, name, "limits", "max_excess") > 0:
                p += sentence(
                    f"{name} leaves joint ",
                    self.ev(t, name, "limits", "excess_joint", fmt="d"),
                    "'s range by ",
                    self.ev(t, name, "limits", "max_excess", fmt=".3f", unit="rad"),
                    ", ",
                )
        p += sentence(
            "and the two command up to ",
            self.ev(t, ivkc, "limits", "max_abs_qd", fmt=".2f"),
            " and ",
            self.ev(t, emdm, "limits", "max_abs_qd", fmt=".2f", unit="rad/s"),
            " (limit ",
            self.d.num(
                f"data/{t}/metrics.json", "scenario", "arm", "qd_max", 0, fmt=".1f", unit="rad/s"
            ),
            ").",
        )
        sec.paragraphs.append(p)
        return sec

    def task1_c(self) -> Section:
        t = "task1"
        ivkc, emdm = PAIRS["C"]
        sec = Section("t1-c", "Task 1.2: C-EMDM against C-IVKC", level=2, brief="1.2")
        answer = sentence(
            "Both constrained controllers (",
            Ref("fig", "t1-c"),
            f") keep every joint outside its stop zone and within its speed limit; {emdm} ",
            *self.outcome(t, emdm),
            f" and {ivkc} ",
            *self.outcome(t, ivkc),
        )
        scaled = self.evv(t, emdm, "scaling")
        if scaled:
            answer += sentence(
                ", later than the UC pair because the task is scaled for the first ",
                self.ev(t, emdm, "scaling", "first_duration", fmt=".2f", unit="s"),
            )
        answer += sentence(
            f", and {emdm} again raises the mean manipulability (",
            self.pct(t, emdm, ivkc, "mean_manipulability"),
            f") for {self.more_less(t, emdm, ivkc, 'total_effort')} effort (",
            self.pct(t, emdm, ivkc, "total_effort"),
            ").",
        )
        sec.answer = answer
        self.answers.append(
            ("Task 1.2: implement and compare C-EMDM and C-IVKC, same analysis", answer)
        )
        sec.figures.append(self.figure("t1-c", "figures/task1-C", self.pair_caption(t, "C")))
        same = self.pair(t, "C", "coincide_steps")
        if same:
            p = sentence(
                "The commands are identical for the first ",
                self.pairn(t, "C", "coincide_steps", "d"),
                " steps (until ",
                T_EQ,
                self.pairn(t, "C", "coincide_until_t", ".2f", "s"),
                ") because the bounds leave no choice: at the largest feasible ",
                ALPHA,
                " the admissible set is a single point (two joints at their bounds leave one "
                "unknown for two task equations), so the objective has nothing to choose. ",
            )
            scaled_steps = self.pair(t, "C", "coincide_scaled_steps")
            determined = self.pair(t, "C", "coincide_determined_steps")
            p += sentence(
                self.pairn(t, "C", "coincide_scaled_steps", "d"),
                " of these steps are scaled",
            )
            if determined == same and scaled_steps < same:
                p += sentence(
                    "; on the other ",
                    _words(same - scaled_steps),
                    " joints at their bounds again fix the command",
                )
            coincide = self.evid("t1-c-slack-policy", "pair", "coincide_steps")
            if coincide:  # (with none in common, the next paragraph's E2 says enough)
                p += sentence(
                    ". With the slack policy instead of scaling (E2) the commands coincide for "
                    "only ",
                    self.evidn("t1-c-slack-policy", "pair", "coincide_steps", fmt="d"),
                    " steps",
                )
            p += sentence(".")
            sec.paragraphs.append(p)
            sec.paragraphs.append(self.policy_weighed())
        pinned = self.evv(t, emdm, "pinned")
        p = sentence()
        if pinned:
            p += sentence("Over the run, ")
            shown = min(len(pinned), 2)
            for i, e in enumerate(pinned[:shown]):
                p += sentence(
                    "joint ",
                    self.ev(t, emdm, "pinned", i, "joint", fmt="d"),
                    f" of {emdm} runs along its {e['side']} {e['kind']} bound from ",
                    self.ev(t, emdm, "pinned", i, "t0", fmt=".2f"),
                    " to ",
                    self.ev(t, emdm, "pinned", i, "t1", fmt=".2f", unit="s"),
                    " and " if i < shown - 1 else ". ",
                )
        p += sentence(
            "Against the UC pair, capped speeds change the effort by ",
            self.pct(t, ivkc, Name.UC_IVKC, "total_effort"),
            " (IVKC) and ",
            self.pct(t, emdm, Name.UC_EMDM, "total_effort"),
            " (EMDM)",
        )
        qa, qb = self.mv(t, emdm, "final_q"), self.mv(t, Name.UC_EMDM, "final_q")
        if all(abs(a - b) < 1e-3 for a, b in zip(qa, qb, strict=True)):
            p += sentence(
                f", and {emdm} ends in the configuration UC-EMDM reaches (",
                M_SYM,
                " = ",
                self.mt(t, emdm, "final_manipulability", ".3f", "m²"),
                ")",
            )
        p += sentence(".")
        sec.paragraphs.append(p)
        return sec

    def pareto(self) -> Section:
        sec = Section("t1-pareto", "Task 1: Pareto fronts and weights", level=2, brief="1.1-1.2")
        uc, c = "data/task1-pareto-UC-EMDM/fronts.json", "data/task1-pareto-C-EMDM/fronts.json"
        if not self.d.exists(uc):
            return sec
        cap = sentence(
            "Pareto fronts between effort ",
            E_SYM,
            " and manipulability rate ",
            MRATE,
            " at ",
            Math(
                r"k=0,\lfloor T/3\rfloor,\lfloor 2T/3\rfloor,T",
                "<i>k</i> = 0, ⌊<i>T</i>/3⌋, ⌊2<i>T</i>/3⌋, <i>T</i>",
            ),
            " (columns 1-4), each point the step's optimum for one ",
            RATIO,
            " (colour; circle: the nominal 50); right: whole runs per weight setting.",
        )
        sec.figures.append(self.figure("pareto", "figures/pareto", cap, wide=True))
        answer = sentence(
            "The fronts (",
            Ref("fig", "pareto"),
            ") show what the weights buy: at k = 0, raising ",
            RATIO,
            " from 0 to its largest value moves UC-EMDM's optimum from ",
            *eq(MRATE, self.d.num(uc, "steps", 0, "M_min", fmt=".3g")),
            " to ",
            self.d.num(uc, "steps", 0, "M_max", fmt=".3g", unit="m²/s"),
            " at an effort growing from ",
            self.d.num(uc, "steps", 0, "E_min", fmt=".3g"),
            " to ",
            self.d.num(uc, "steps", 0, "E_max", fmt=".3g", unit="rad²/s²"),
            "; ",
        )
        shares = [
            (info["nominal_E_log_pct"], i)
            for i, info in enumerate(self.d.value(uc, "steps"))
            if info.get("nominal_E_log_pct") is not None
        ]
        if shares:
            answer += sentence(
                "on every UC-EMDM front the nominal ratio lies in the lowest ",
                self.d.num(uc, "steps", max(shares)[1], "nominal_E_log_pct", fmt=".0f"),
                "% of the effort range (log scale), costing ",
            )
        else:
            answer += sentence("the nominal ratio costs ")
        e0 = self.d.value(uc, "steps", 0, "zero_E")
        en = self.d.value(uc, "steps", 0, "nominal_E")
        answer += sentence(
            self.d.pct((uc, "steps", 0, "nominal_E"), (uc, "steps", 0, "zero_E"), fmt="+.1f")
            if e0 > 0
            else Text("little"),
            " effort over the effort-minimal optimum (ratio 0) at k = 0" if en >= e0 else " effort",
        )
        i = self.dearest_later(uc)
        if i is not None:  # dearer later: say so
            answer += sentence(
                " but up to ",
                self.d.pct((uc, "steps", i, "nominal_E"), (uc, "steps", i, "zero_E")),
                " at k = ",
                self.d.num(uc, "steps", i, "k", fmt="d"),
            )
        answer += sentence(".")
        sec.answer = answer
        self.answers.append(("Task 1: Pareto front between E and M at t = 0, T/3, 2T/3, T", answer))
        # degenerate and saturated fronts of C-EMDM
        p: Sentence = []
        if self.d.exists(c):
            csteps = self.d.value(c, "steps")
            for i, info in enumerate(csteps):
                if info["degenerate"]:
                    p += sentence(
                        "C-EMDM's front at k = ",
                        self.d.num(c, "steps", i, "k", fmt="d"),
                        " is a single point no weight can move (the task-scaled step, ",
                        *eq(ALPHA, self.d.num(c, "steps", i, "alpha", fmt=".2f")),
                        "). ",
                    )
            sat = [(i, s) for i, s in enumerate(csteps) if s["saturated_from_ratio"] is not None]
            if sat:
                i, _ = sat[0]
                p += sentence(
                    "At k = ",
                    self.d.num(c, "steps", i, "k", fmt="d"),
                    " the front saturates: every ",
                    RATIO,
                    " from ",
                    self.d.num(c, "steps", i, "saturated_from_ratio", fmt=".3g"),
                    " on gives the same optimum, a vertex of the joint bounds, so more weight on ",
                    MRATE,
                    " buys nothing. ",
                )
        # the weight grid: failures
        grid_file = "data/task1-pareto-UC-EMDM/weight_grid.json"
        rows = self.d.value(grid_file, "runs")
        for i, r in enumerate(rows):
            if r.get("reached") or "finer_dt" not in r:
                continue
            p += sentence(
                "At ",
                *eq(RATIO, self.d.num(grid_file, "runs", i, "w_manip", fmt=".4g")),
                Text("/"),
                self.d.num(grid_file, "runs", i, "w_effort", fmt=".2g"),
                " UC-EMDM fails to reach the goal (final error ",
                self.d.num(grid_file, "runs", i, "final_error", fmt=".3f", unit="m"),
                "): its largest joint speed reaches ",
                self.d.num(grid_file, "runs", i, "max_abs_qd", fmt=".0f", unit="rad/s"),
                ", and a step of ",
                self.d.num(
                    "data/task1/metrics.json", "scenario", "motion", "dt", fmt=".2f", unit="s"
                ),
                " at that speed leaves the linearisation ",
                Math(r"J\dot q=v_d", "<i>J q̇</i> = <i>v</i><sub>d</sub>"),
                " far behind. ",
            )
            finer = r["finer_dt"]
            if finer.get("reached"):
                p += sentence(
                    "The same weights with ",
                    *eq(
                        DT, self.d.num(grid_file, "runs", i, "finer_dt", "dt", fmt=".2f", unit="s")
                    ),
                    " reach the goal in ",
                    self.d.num(
                        grid_file, "runs", i, "finer_dt", "time_to_goal", fmt=".2f", unit="s"
                    ),
                    " (evidence E3): the failure is the discretisation, not the program. ",
                )
            break
        if p:
            sec.paragraphs.append(p)
        return sec

    def task1_solver(self) -> Section:
        t = "task1"
        sec = Section(
            "t1-solver", "Task 1: custom solver, fallback, convergence", level=2, brief="1.1"
        )
        fallbacks = self.mv(t, Name.UC_EMDM, "fallback_steps") + self.mv(
            t, Name.C_EMDM, "fallback_steps"
        )
        answer = sentence(
            "The custom active-set solver returned a certified optimum (relative KKT residual at "
            "most ",
            Math("10^{-9}", "10<sup>−9</sup>"),
            ") at every step of UC-EMDM (",
            self.mt(t, Name.UC_EMDM, "steps", "d"),
            ") and C-EMDM (",
            self.mt(t, Name.C_EMDM, "steps", "d"),
            "), so the off-the-shelf fallback (daqp, then quadprog) ",
        )
        if fallbacks == 0:
            answer += sentence("was never needed.")
        else:
            answer += sentence(
                "answered ",
                self.mt(t, Name.UC_EMDM, "fallback_steps", "d"),
                " and ",
                self.mt(t, Name.C_EMDM, "fallback_steps", "d"),
                " of them.",
            )
        sec.answer = answer
        self.answers.append(
            (
                "Task 1.1: custom solver, off-the-shelf fallback, convergence "
                "behaviour, numerical challenges",
                answer,
            )
        )
        p = sentence(
            "Started from the previous step's working set where that is still optimal, else "
            "from an exact feasible point, it takes a median of ",
            self.ev(t, Name.C_EMDM, "solver", "median_iterations", fmt=".4g"),
            " and at most ",
            self.ev(t, Name.C_EMDM, "solver", "max_iterations", fmt="d"),
            " iterations, each an exact equality-constrained solve",
        )
        lab = "data/task1-lab-C-EMDM/solvers.json"
        ch: dict[str, Any] = {}
        if self.d.exists(lab):
            ch = self.d.value(lab, "challenges", "solvers")
        if "median_iterations_scaled" in ch.get("active-set", {}):
            p += sentence(
                "; on scaled steps it takes ",
                self.d.num(
                    lab,
                    "challenges",
                    "solvers",
                    "active-set",
                    "median_iterations_scaled",
                    fmt=".0f",
                ),
                ", the feasible point being the optimum",
            )
        p += sentence(
            ". Those scaled steps are Task 1's numerical challenge: their admissible set is a "
            "single, degenerate vertex",
        )
        if "median_iterations_scaled" in ch.get("admm", {}):
            p += sentence(
                ". First-order ADMM needs ",
                self.d.num(
                    lab, "challenges", "solvers", "admm", "median_iterations_scaled", fmt=".4g"
                ),
                " iterations there against ",
                self.d.num(
                    lab, "challenges", "solvers", "admm", "median_iterations_unscaled", fmt=".4g"
                ),
                " elsewhere",
            )
        rows = self.d.value(lab, "solvers") if self.d.exists(lab) else {}
        notes = (
            self.d.value(lab, "notes") if self.d.exists(lab) and "notes" in self.d.load(lab) else {}
        )
        qp = rows.get("quadprog", {})
        if qp.get("failures"):
            p += sentence(
                ", and quadprog declines "
                if "median_iterations_scaled" in ch.get("admm", {})
                else ". The quadprog solver declines ",
                self.d.num(lab, "solvers", "quadprog", "failures", fmt="d"),
                " of the ",
                self.d.num(lab, "solvers", "quadprog", "resolved_steps", fmt="d"),
                " C-EMDM programs the solver lab re-solves",
            )
            if notes.get("quadprog", {}).get("failures_on_scaled_steps") == qp["failures"]:
                p += sentence(", all scaled ones")
        p += sentence(
            ". Otherwise Task 1 is benign: ",
            COND_J,
            " peaks at ",
            self.ev(t, Name.C_EMDM, "conditioning", "cond_J_max", fmt=".3g"),
            " along the whole runs and the programs have no slack.",
        )
        sec.paragraphs.append(p)
        return sec

    # ------------------------------------------------------------------ Task 2
    def task2_c(self) -> Section:
        t = "task2"
        ivkc, emdm = PAIRS["C"]
        sec = Section("t2-c", "Task 2.1: C-EMDM against C-IVKC", level=2, brief="2.1")
        reached_e, reached_i = self.mv(t, emdm, "reached"), self.mv(t, ivkc, "reached")
        answer = sentence(
            f"{emdm} ",
            *self.outcome(t, emdm),
            f"; {ivkc} ",
            *self.outcome(t, ivkc),
            " (",
            Ref("fig", "t2-c"),
            ", ",
            Ref("tab", "outcomes"),
            ")",
        )
        if reached_e and not reached_i:
            answer += sentence(": one can leave the straight line to the goal, the other cannot")
            e4 = self.evid("t2-c-ivkc-slack-policy", "runs", ivkc)
            if e4.get("reached"):  # the like-for-like comparison, beside the headline
                answer += sentence(
                    f". With a slack like {emdm}'s instead of task scaling (E4), {ivkc} "
                    "arrives as well, in ",
                    self.evid_goal("t2-c-ivkc-slack-policy", ivkc),
                )
            answer += sentence(".")
        else:
            answer += sentence(".")
        sec.answer = answer
        self.answers.append(
            (
                "Task 2.1: compare C-EMDM and C-IVKC in tracking, manipulability and time to goal",
                answer,
            )
        )
        geo = self.d.value(f"data/{t}/events.json", "geometry")
        g = f"data/{t}/events.json"
        if geo:
            sec.figures.append(
                self.figure(
                    "workspace",
                    "figures/workspace",
                    sentence(
                        "Task 2 in the workspace: the straight line to the goal enters the disc "
                        "the arm cannot reach with ",
                        Math(r"|q_2|", "|<i>q</i><sub>2</sub>|"),
                        " outside its stop zone (hatched); C-IVKC stalls on its edge, C-EMDM "
                        "goes around and flips its elbow into the only goal configuration within "
                        "the limits.",
                    ),
                )
            )
            sols = geo["solutions"]
            inside = [i for i, s in enumerate(sols) if s["within_limits"]]
            outside = [i for i, s in enumerate(sols) if not s["within_limits"]]
            p: Sentence = []
            if inside and outside:
                i, o = inside[0], outside[0]
                p += sentence(
                    "Within the joint limits the goal has one configuration, elbow ",
                    sols[i]["elbow"],
                    ", ",
                    Math("q", "<i>q</i>"),
                    " = (",
                    self.d.num(g, "geometry", "solutions", i, "q1", fmt=".2f"),
                    ", ",
                    self.d.num(g, "geometry", "solutions", i, "q2", fmt=".2f"),
                    ") rad; the elbow-",
                    sols[o]["elbow"],
                    " one",
                    " (the side the arm starts on)"
                    if geo.get("start_elbow") == sols[o]["elbow"]
                    else "",
                    " needs ",
                    q(sols[o]["outside_joint"]),
                    " = ",
                    self.d.num(
                        g,
                        "geometry",
                        "solutions",
                        o,
                        f"q{sols[o]['outside_joint']}",
                        fmt=".2f",
                        unit="rad",
                    ),
                    ", ",
                    self.d.num(g, "geometry", "solutions", o, "outside_by", fmt=".2f", unit="rad"),
                    " beyond its limit. ",
                )
            if geo["line_blocked"]:
                p += sentence(
                    "With ",
                    Math(r"|q_2|", "|<i>q</i><sub>2</sub>|"),
                    " outside its stop zone (at most ",
                    self.d.num(g, "geometry", "max_fold", fmt=".3f", unit="rad"),
                    ") the end effector cannot come closer than ",
                    self.d.num(g, "geometry", "inner_reach", fmt=".3f", unit="m"),
                    " to the base, yet the straight line to the goal passes ",
                    self.d.num(g, "geometry", "line_min_distance", fmt=".3f", unit="m"),
                    " from it and enters that disc ",
                    self.d.num(g, "geometry", "line_enters_at", fmt=".3f", unit="m"),
                    " after the start (",
                    Ref("fig", "workspace"),
                    ").",
                )
            if p:
                sec.paragraphs.append(p)
        stall = self.evv(t, ivkc, "stall")
        if stall:
            p = sentence(
                "A non-redundant arm without slack has one command per task velocity, and scaling "
                f"keeps its direction: {ivkc} can only slow down along the line. ",
            )
            sc = self.evv(t, ivkc, "scaling")
            if sc:
                p += sentence(
                    "Scaled from the first step (",
                    *eq(ALPHA, self.ev(t, ivkc, "scaling", "initial_alpha", fmt=".2f")),
                    ")",
                )
            pins = self.evv(t, ivkc, "pinned")
            if pins:
                p += sentence(
                    ", joint ",
                    self.ev(t, ivkc, "pinned", 0, "joint", fmt="d"),
                    f" runs on its {pins[0]['side']} {pins[0]['kind']} bound from ",
                    self.ev(t, ivkc, "pinned", 0, "t0", fmt=".2f", unit="s"),
                    " to the end",
                )
            p += sentence(
                ", it freezes ",
                self.ev(t, ivkc, "stall", "error", fmt=".3f", unit="m"),
                " from the goal after ",
                self.ev(t, ivkc, "stall", "progress", fmt=".3f", unit="m"),
                " of progress (",
                T_EQ,
                self.ev(t, ivkc, "stall", "t", fmt=".2f", unit="s"),
                "), joint ",
                self.ev(t, ivkc, "stall", "joint", fmt="d"),
                " at the edge of its stop zone",
            )
            if sc and sc["zero_from_t"] is not None:
                p += sentence(
                    "; from ",
                    T_EQ,
                    self.ev(t, ivkc, "scaling", "zero_from_t", fmt=".2f", unit="s"),
                    " on, its damper bound is 0 and so is ",
                    ALPHA,
                    ".",
                )
            else:
                p += sentence(".")
            sec.paragraphs.append(p)
        if reached_e:
            p = sentence(
                "The slack (up to ",
                *eq(DELTA, self.ev(t, emdm, "slack", "max", fmt=".2f", unit="m/s")),
                ") lets ",
                emdm,
                " leave the line: its path is ",
                self.ev(t, emdm, "path_length", fmt=".2f", unit="m"),
                " long, ",
                self.ev(t, emdm, "detour", fmt=".0%"),
                " longer than the line. ",
            )
            pins = self.evv(t, emdm, "pinned")
            if pins:
                p += sentence(
                    "Joint ",
                    self.ev(t, emdm, "pinned", 0, "joint", fmt="d"),
                    f" creeps along its {pins[0]['side']} {pins[0]['kind']} bound for ",
                    self.ev(t, emdm, "pinned", 0, "duration", fmt=".2f", unit="s"),
                    " (",
                    self.ev(t, emdm, "pinned", 0, "t0", fmt=".2f"),
                    "-",
                    self.ev(t, emdm, "pinned", 0, "t1", fmt=".2f", unit="s"),
                    ") while the arm stretches; ",
                )
            flips = self.evv(t, emdm, "singular", "elbow_flips")
            if flips:
                p += sentence(
                    "at ",
                    T_EQ,
                    self.ev(t, emdm, "singular", "t", fmt=".2f", unit="s"),
                    " it passes the singular stretched configuration (",
                    *eq(M_SYM, self.ev(t, emdm, "singular", "m_min", fmt=".1e", unit="m²")),
                    ", ",
                    *eq(COND_J, self.ev(t, emdm, "conditioning", "cond_J_max", fmt=".2g")),
                    ") and flips its elbow into the admissible goal configuration.",
                )
            sec.paragraphs.append(p)
        # evidence (their numbers are in the evidence table)
        p = sentence("The evidence runs (", Ref("tab", "evidence"), ") isolate the causes. ")
        e4 = self.evid("t2-c-ivkc-slack-policy", "runs", ivkc)
        e5 = self.evid("t2-c-ivkc-wide-limits", "runs", ivkc)
        if not reached_i and (e4.get("reached") or e5.get("reached")):
            p += sentence(f"{ivkc} reaches the goal ")
            if e4.get("reached"):
                p += sentence("with a slack (E4, flipping its elbow)")
            if e4.get("reached") and e5.get("reached"):
                p += sentence(" and ")
            if e5.get("reached"):
                p += sentence("with the joint limits widened to ±3 rad (E5)")
            p += sentence(
                ": the stall comes from keeping the task direction under the limits, not from "
                "IVKC. "
            )
        e6 = self.evid("t2-c-emdm-no-manip", "runs", emdm)
        if e6.get("reached") and reached_e:
            if e6["time_to_goal"] < self.mv(t, emdm, "time_to_goal"):
                higher = e6["mean_manipulability"] > self.mv(t, emdm, "mean_manipulability")
                p += sentence(
                    f"Without the dexterity term {emdm} still arrives, and sooner (E6, ",
                    self.evid_goal("t2-c-emdm-no-manip", emdm),
                    ")",
                    *(
                        (
                            ", with a higher mean ",
                            M_SYM,
                            " (",
                            self.evidn(
                                "t2-c-emdm-no-manip",
                                "runs",
                                emdm,
                                "mean_manipulability",
                                fmt=".3f",
                            ),
                            " against ",
                            self.mt(t, emdm, "mean_manipulability", ".3f", "m²"),
                            "): on this arm the term works against its own purpose, and the "
                            "slack, not the term, carries it to the goal, contrary to what the "
                            "brief expects",
                        )
                        if higher
                        else (
                            ": the slack carries it to the goal and the dexterity term slows it "
                            "down, contrary to what the brief expects",
                        )
                    ),
                )
            else:
                p += sentence(
                    f"Without the dexterity term {emdm} still arrives (E6): the slack carries it"
                )
            e7 = self.evid("t2-c-emdm-tight-slack", "runs", emdm)
            if not e7.get("reached", True):
                p += sentence("; with its slack bounded by 0.1 m/s it stalls (E7)")
            p += sentence(".")
        sec.paragraphs.append(p)
        p = sentence(
            emdm,
            "'s mean ",
            M_SYM,
            " is ",
            self.mt(t, emdm, "mean_manipulability", ".3f"),
            " against ",
            self.mt(t, ivkc, "mean_manipulability", ".3f", "m²"),
            " (",
            self.pct(t, emdm, ivkc, "mean_manipulability"),
            ")",
        )
        if reached_e and not reached_i and self.evv(t, emdm, "singular", "near"):
            p += sentence(
                " because its route crosses ",
                M_SYM,
                " = 0 while ",
                ivkc,
                " stands still",
            )
            # each mean is over its own run: the stall's 30 s weigh in, so the common window too
            g = f"data/{t}/events.json"
            p += sentence(
                " (",
                ivkc,
                "'s over its ",
                self.mt(t, ivkc, "final_time", ".0f", "s"),
                "; over the first ",
                self.d.num(g, "pairs", "C", "common_until_t", fmt=".2f", unit="s"),
                " of both, ",
                self.d.num(g, "pairs", "C", "mean_m_common", emdm, fmt=".3f"),
                " against ",
                self.d.num(g, "pairs", "C", "mean_m_common", ivkc, fmt=".3f", unit="m²"),
                ")",
            )
        p += sentence(
            "; its effort is ",
            self.mt(t, emdm, "total_effort", ".2f"),
            " against ",
            self.mt(t, ivkc, "total_effort", ".2f", "rad²/s"),
            ".",
        )
        sec.paragraphs.append(p)
        if self.d.exists("paper/figures/task2-all.png"):  # Tasks 2.1 and 2.2 overlaid
            peak = max(PAIRS["UC"], key=lambda c: self.mv(t, c, "max_abs_qd"))
            caption = sentence(
                "Task 2, the four controllers (constrained dark, unconstrained light; IVKC "
                "solid, EMDM dashed): "
            ) + self.panels(gap=True)
            caption += sentence(
                ", on the constrained runs' scale (unconstrained peaks up to ",
                self.mt(t, peak, "max_abs_qd", ".1f", "rad/s"),
                ")",
            )
            # time axes end at the last arrival when the runs that missed had stalled by then
            # (paper_figures.time_end, the same rule on the same records)
            four = (*PAIRS["UC"], *PAIRS["C"])
            missed = [c for c in four if not self.mv(t, c, "reached")]
            last = max((self.mv(t, c, "time_to_goal") for c in four if c not in missed), default=0)
            if missed and all(
                self.evv(t, c, "stall") and self.evv(t, c, "stall", "t") <= last for c in missed
            ):
                caption += sentence(
                    "; time axes end at the last arrival (",
                    ", ".join(missed),
                    " stalled)",
                )
            caption += sentence(".")
            sec.figures.append(self.figure("t2-c", "figures/task2-all", caption))
        else:
            sec.figures.append(self.figure("t2-c", "figures/task2-C", self.pair_caption(t, "C")))
        return sec

    def dearest_later(self, uc: str) -> int | None:
        """The later Pareto step whose nominal optimum costs most over its effort-minimal one,
        when that is more than at k = 0 (else None): the nominal weights' price grows."""
        steps = self.d.value(uc, "steps")
        e0, en = steps[0].get("zero_E"), steps[0].get("nominal_E")
        later = [
            (info["nominal_E"] / info["zero_E"], i)
            for i, info in enumerate(steps)
            if i > 0 and info.get("zero_E") and info.get("nominal_E") is not None
        ]
        if not later or not e0 or en is None or max(later)[0] <= en / e0:
            return None
        return max(later)[1]

    @staticmethod
    def exact(rows: dict[str, Any], family: str) -> list[str]:
        """The solvers of ``family`` whose answers are exact (gap and violation tiny)."""
        return [
            k
            for k, r in rows.items()
            if r["family"] == family
            and r["failures"] == 0
            and abs(r["max_abs_gap"]) <= 1e-9
            and r["max_violation"] <= 1e-9
        ]

    @staticmethod
    def best(rows: dict[str, Any], family: str) -> str | None:
        """The fastest of :meth:`exact`'s solvers of ``family``."""
        exact = Story.exact(rows, family)
        return min(exact, key=lambda k: rows[k]["median_time"]) if exact else None

    @staticmethod
    def free_verdict(rows: dict[str, Any], period: float = 0.05) -> bool:
        """True when no gradient-free method is both exact and faster than the control period."""
        return not any(
            r["family"] == "gradient-free"
            and abs(r["max_abs_gap"]) <= 1e-9
            and r["max_violation"] <= 1e-9
            and r["median_time"] < period
            for r in rows.values()
        )

    def task2_solvers(self) -> Section:
        f = "data/task2-lab-C-EMDM/solvers.json"
        sec = Section(
            "t2-solvers", "Task 2.1: gradient-based against gradient-free", level=2, brief="2.1"
        )
        if not self.d.exists(f):
            return sec
        rows = self.d.value(f, "solvers")
        dt = self.d.value("data/task2/metrics.json", "scenario", "motion", "dt")
        grad = self.best(rows, "gradient")
        free = [k for k, r in rows.items() if r["family"] == "gradient-free"]
        exact_free = [
            k
            for k in free
            if abs(rows[k]["max_abs_gap"]) <= 1e-9 and rows[k]["max_violation"] <= 1e-9
        ]
        inexact_free = [k for k in free if k not in exact_free]
        answer: Sentence = []
        if grad:
            answer += sentence(
                "The gradient-based ",
                grad,
                " wins on both counts: it",
                " reaches the exact optimum (largest gap ",
                self.d.num(f, "solvers", grad, "max_abs_gap", fmt=".0e"),
                ") in a median ",
                self.d.ms(f, "solvers", grad, "median_time"),
                " after ",
                self.d.num(f, "solvers", grad, "median_iterations", fmt=".4g"),
                " iterations and ",
                self.d.num(f, "solvers", grad, "median_evaluations", fmt=".4g"),
                " evaluations, while ",
            )
        if exact_free:
            answer += sentence(
                "the exact gradient-free "
                + ("methods take a median of " if len(exact_free) > 1 else "method, ")
            )
            for i, k in enumerate(exact_free):
                answer += sentence(
                    *((k, " ") if len(exact_free) > 1 else (k, ", takes a median of ")),
                    self.d.ms(f, "solvers", k, "median_time"),
                    " (95th percentile ",
                    self.d.ms(f, "solvers", k, "p95_time"),
                    ")",
                    "; " if i < len(exact_free) - 1 else "",
                )
            over = [k for k in exact_free if rows[k]["p95_time"] > dt]
            typical = [k for k in exact_free if rows[k]["median_time"] > dt]
            one = len(exact_free) == 1
            answer += sentence(
                "; against the control period of ",
                self.d.num(
                    "data/task2/metrics.json", "scenario", "motion", "dt", fmt=".2f", unit="s"
                ),
                ", "
                + (
                    ("its median already exceeds it" if one else "their medians already exceed it")
                    if len(typical) == len(exact_free)
                    else ("it overruns it" if one else "each overruns it")
                    + " on at least one program in 20"
                    if len(over) == len(exact_free)
                    else "some overrun it on at least one program in 20"
                    if over
                    else "its 95th percentile is within it, but it costs a hundred times the "
                    "gradient-based method or more"
                    if all(
                        rows[k]["median_time"] >= 100 * rows[grad]["median_time"]
                        for k in exact_free
                    )
                    and grad
                    else "within it at the 95th percentile"
                ),
            )
            if inexact_free:
                gaps = [abs(rows[k]["max_abs_gap"]) for k in inexact_free]
                lo = min(inexact_free, key=lambda k: abs(rows[k]["max_abs_gap"]))
                hi = max(inexact_free, key=lambda k: abs(rows[k]["max_abs_gap"]))
                answer += (
                    sentence(
                        "; the others stop short of the optimum by ",
                        self.d.num(f, "solvers", lo, "max_abs_gap", fmt=".2g"),
                        " (",
                        lo,
                        ") to ",
                        self.d.num(f, "solvers", hi, "max_abs_gap", fmt=".2g"),
                        " (",
                        hi,
                        ").",
                    )
                    if max(gaps) > min(gaps)
                    else sentence("; the others are inexact.")
                )
            else:
                answer += sentence(".")
        elif inexact_free:
            answer += sentence("every gradient-free method is inexact (")
            for i, k in enumerate(inexact_free):
                answer += sentence(
                    k,
                    ": gap ",
                    self.d.num(f, "solvers", k, "max_abs_gap", fmt=".2g"),
                    ", " if i < len(inexact_free) - 1 else "",
                )
            answer += sentence(").")
        sec.answer = answer
        self.answers.append(
            (
                "Task 2.1: gradient-based and gradient-free solver, convergence speed "
                "and solution quality",
                answer,
            )
        )
        sec.tables.append("solvers")
        self.solver_table(f, rows)
        sec.figures.append(
            self.figure(
                "solvers",
                "figures/solvers",
                sentence(
                    "Task 2 C-EMDM, each solver on the same re-solved programs: median time per "
                    "program against the largest gap to the exact optimum (",
                    DT,
                    ": the control period).",
                ),
                paper=False,
            )
        )
        conv = self.figure(
            "convergence",
            "figures/convergence",
            sentence(
                "Convergence on one program of the methods that evaluate the objective (green: "
                "gradient-based, orange: gradient-free; marker: last evaluation).",
            ),
            paper=False,  # the page's: the paper's four pages give Table III the comparison
        )
        if self.has_figure("convergence"):
            sec.figures.append(conv)
        p = sentence("Quality (", Ref("tab", "solvers"), "): ")
        violators = [k for k in inexact_free if rows[k]["max_violation"] > 1e-6]
        if violators:  # the gaps are in the answer; every solver's own figures in Table III
            bad = max(violators, key=lambda k: rows[k]["max_violation"])
            p += sentence(
                f"{bad} also violates the bounds by up to ",
                self.d.num(f, "solvers", bad, "max_violation", fmt=".2g"),
                "; ",
            )
        p += sentence(
            "in closed loop ",
        )
        ref_t = rows.get("active-set", {}).get("time_to_goal")
        slower = [
            k
            for k in free
            if rows[k].get("reached")
            and ref_t is not None
            and rows[k]["time_to_goal"] > ref_t + 1e-9
        ]
        if slower:
            p += sentence(
                " and ".join(slower),
                " reach" if len(slower) > 1 else " reaches",
                " the goal later (last column). ",
            )
        else:
            p += sentence("every solver reaches the goal at the same time. ")
        p += (
            sentence(
                "Recommendation: exact active-set QP (ours: ",
                self.d.ms(f, "solvers", "active-set", "median_time"),
                "), else gradient-based.",
            )
            if "active-set" in rows
            else []
        )
        sec.paragraphs.append(p)
        return sec

    def task2_uc(self) -> Section:
        t = "task2"
        ivkc, emdm = PAIRS["UC"]
        sec = Section("t2-uc", "Task 2.2: UC-EMDM against UC-IVKC", level=2, brief="2.2")
        if self.d.exists("paper/figures/task2-UC.png"):  # the page's; the paper's is Fig. t2-c
            sec.figures.append(
                self.figure("t2-uc", "figures/task2-UC", self.pair_caption(t, "UC"), paper=False)
            )
        shown = "t2-c" if self.d.exists("paper/figures/task2-all.png") else "t2-uc"
        answer = (
            sentence(
                f"Both unconstrained controllers reach the goal ({ivkc} in ",
                self.ttg(t, ivkc),
                f", {emdm} in ",
                self.ttg(t, emdm),
                "), but only by leaving the joint limits",
            )
            if self.mv(t, ivkc, "reached") and self.mv(t, emdm, "reached")
            else sentence(
                f"{ivkc} ",
                *self.outcome(t, ivkc),
                f"; {emdm} ",
                *self.outcome(t, emdm),
            )
        )
        outside = [c for c in (ivkc, emdm) if self.evv(t, c, "limits", "max_excess") > 0]
        if outside:
            answer += sentence(" (")
            for i, c in enumerate(outside):
                joints = [
                    j for j, x in enumerate(self.evv(t, c, "limits", "excess_by_joint")) if x > 0
                ]
                answer += sentence("; " if i else "", f"{c}: ")
                for n, j in enumerate(joints):
                    answer += sentence(
                        ", " if n else "",
                        f"joint {j + 1} by up to " if n == 0 else f"joint {j + 1} by ",
                        self.ev(t, c, "limits", "excess_by_joint", j, fmt=".2f", unit="rad"),
                    )
            answer += sentence(") into the elbow-up configuration the constrained pair cannot use")
        answer += sentence(
            f"; against {ivkc}, {emdm}'s total effort differs by ",
            self.pct(t, emdm, ivkc, "total_effort"),
            " and its mean ",
            M_SYM,
            " by ",
            self.pct(t, emdm, ivkc, "mean_manipulability"),
            ", as the slack absorbs up to ",
            *eq(DELTA, self.ev(t, emdm, "slack", "max", fmt=".2f", unit="m/s")),
            " of the desired velocity (",
            Ref("tab", "outcomes"),
            *((", ", Ref("fig", shown), "(c)") if self.has_figure(shown) else ()),
            ").",
        )
        sec.answer = answer
        self.answers.append(("Task 2.2: implement and compare UC-EMDM and UC-IVKC", answer))
        p = sentence()
        e8 = self.evid("t2-uc-emdm-stiff-slack", "runs", emdm)
        if e8.get("reached"):
            p += sentence(
                "E8: with ",
                *eq(
                    C_S,
                    self.d.num(
                        "data/evidence.json",
                        "runs",
                        "t2-uc-emdm-stiff-slack",
                        "overrides",
                        "weights.slack",
                        fmt=".0e",
                    ),
                ),
                " the slack vanishes and ",
                emdm,
                " behaves like ",
                ivkc,
                " (goal in ",
                self.evid_goal("t2-uc-emdm-stiff-slack", emdm),
                ", effort ",
                self.evidn(
                    "t2-uc-emdm-stiff-slack", "runs", emdm, "total_effort", fmt=".2f", unit="rad²/s"
                ),
                "): the slack is what saves effort, by giving up ",
                Math(r"J\dot q=v_d", "<i>J q̇</i> = <i>v</i><sub>d</sub>"),
                " while ",
                ERR,
                " is large.",
            )
        sec.paragraphs.append(p)
        return sec

    def task2_challenges(self) -> Section:
        t = "task2"
        emdm = Name.C_EMDM
        f = "data/task2-lab-C-EMDM/solvers.json"
        sec = Section(
            "t2-challenges", "Task 2: convergence and numerical challenges", level=2, brief="2.1"
        )
        answer = sentence(
            "Two things make Task 2's programs harder than Task 1's: the slack weight ",
            W_S,
            " grows from ",
            self.ev(t, emdm, "conditioning", "w_slack_start", fmt=".3g"),
            " to ",
            self.ev(t, emdm, "conditioning", "w_slack_max_solved", fmt=".3g"),
            " over the solved steps as the error shrinks, and the singular passage drives ",
            COND_J,
            " to ",
            self.ev(t, emdm, "conditioning", "cond_J_max", fmt=".2g"),
            " at ",
            T_EQ,
            self.ev(t, emdm, "conditioning", "t_cond_J_max", fmt=".2f", unit="s"),
            ".",
        )
        sec.answer = answer
        self.answers.append(("Task 2.1: convergence behaviour and numerical challenges", answer))
        sec.figures.append(
            self.figure(
                "conditioning",
                "figures/conditioning",
                sentence(
                    "Task 2 C-EMDM along its run: ",
                    COND_J,
                    " and ",
                    W_S,
                    " at every state (top); iterations of the closed-loop solver at every step "
                    "and of three others on the re-solved steps (bottom).",
                ),
                paper=False,
            )
        )
        p = sentence()
        if self.d.exists(f):
            p += sentence(
                "The reduced Hessian's condition number reaches ",
                self.d.num(f, "challenges", "feature_ranges", "cond_reduced", 1, fmt=".3g"),
                "; at ",
                M_SYM,
                " = 0, where ",
                M_SYM,
                " is not differentiable, ",
                Math("J_m", "<i>J</i><sub>m</sub>"),
                " is the steepest one-sided ascent. The active-set method does not notice (a "
                "median of ",
                self.ev(t, emdm, "solver", "median_iterations", fmt=".4g"),
                " and at most ",
                self.ev(t, emdm, "solver", "max_iterations", fmt=".0f"),
                " iterations warm-started, ",
                self.d.num(f, "solvers", "active-set", "median_iterations", fmt=".4g"),
                " cold in ",
                Ref("tab", "solvers"),
                "; no fallback)" if self.mv(t, emdm, "fallback_steps") == 0 else ")",
            )
            ch = self.d.value(f, "challenges", "solvers")
            if "admm" not in ch or ch["admm"].get("iterations_vs_cond_spearman") is None:
                p += sentence(".")
            else:
                p += sentence(
                    "; ",
                    "ADMM's iterations follow the conditioning (rank correlation ",
                    self.d.num(
                        f, "challenges", "solvers", "admm", "iterations_vs_cond_spearman", fmt=".2f"
                    ),
                    ").",
                )
        sec.paragraphs.append(p)
        return sec

    def _policy_terms(self) -> list[tuple[str, bool]]:
        """Task 1's C-EMDM under the slack policy (E2) against scaling, per outcome: (metric,
        whether the slack run is better on it)."""
        run = self.evid("t1-c-slack-policy", "runs", Name.C_EMDM)
        out = []
        for metric, higher_better in (
            ("time_to_goal", False),
            ("total_effort", False),
            ("mean_manipulability", True),
        ):
            new, old = run[metric], self.mv("task1", Name.C_EMDM, metric)
            out.append((metric, new > old if higher_better else new < old))
        return out

    def policy_weighed(self) -> Sentence:
        """Task scaling, the paper's own choice, weighed against its evidence (E2, E4)."""
        e2, emdm = "t1-c-slack-policy", Name.C_EMDM
        words = {
            "time_to_goal": ("reaches the goal sooner", "reaches the goal later"),
            "total_effort": (", with less effort", ", with more effort"),
            "mean_manipulability": (
                " and a higher mean manipulability",
                " and a lower mean manipulability",
            ),
        }
        p = sentence(
            "Weighed against its evidence, scaling is not free: with a slack (E2, ",
            Ref("tab", "evidence"),
            ") C-EMDM ",
        )
        for metric, better in self._policy_terms():
            p += sentence(words[metric][0 if better else 1])
        e2r = ("data/evidence.json", "runs", e2, "runs")
        ivkc = Name.C_IVKC
        if self.evid(e2, "runs", ivkc, "reached"):  # the pair under the slack policy
            p += sentence(
                ". Under the slack C-EMDM's mean ",
                M_SYM,
                " is ",
                self.d.pct(
                    (*e2r, emdm, "mean_manipulability"), (*e2r, ivkc, "mean_manipulability")
                ),
                " against C-IVKC's for ",
                self.d.pct((*e2r, emdm, "total_effort"), (*e2r, ivkc, "total_effort")),
                " effort (scaled: ",
                self.pct("task1", emdm, ivkc, "mean_manipulability"),
                " for ",
                self.pct("task1", emdm, ivkc, "total_effort"),
                ")",
            )
        p += sentence(
            "; scaling buys the straight line (path ",
            self.mt("task1", emdm, "path_length", ".2f", "m"),
            ", with a slack ",
            self.evidn(e2, "runs", emdm, "path_length", fmt=".2f", unit="m"),
            ").",
        )
        return p

    def conclusion(self) -> Section:
        sec = Section("conclusion", "Conclusion")
        t1 = "task1"
        p = sentence(
            "On the redundant arm EMDM is IVKC plus a null-space motion towards dexterity: the same "
            "tracking, ",
            self.pct(t1, Name.UC_EMDM, Name.UC_IVKC, "mean_manipulability"),
            " and ",
            self.pct(t1, Name.C_EMDM, Name.C_IVKC, "mean_manipulability"),
            " mean manipulability for ",
            self.pct(t1, Name.UC_EMDM, Name.UC_IVKC, "total_effort"),
            " and ",
            self.pct(t1, Name.C_EMDM, Name.C_IVKC, "total_effort"),
            " effort. On the non-redundant arm the slack, not the dexterity term, decides: it lets "
            "C-EMDM leave a straight line that the joint limits block, where task scaling (our "
            "departure from the brief, kept as the closest to its task equation) stalls C-IVKC. ",
        )
        better = [m for m, b in self._policy_terms() if b]
        adjectives = {
            "time_to_goal": "faster",
            "total_effort": "cheaper",
            "mean_manipulability": "more dexterous",
        }
        e4 = self.evid("t2-c-ivkc-slack-policy", "runs", Name.C_IVKC)
        if better:
            named = [adjectives[m] for m in better]
            p += sentence(
                "Scaling buys only that line: with a slack C-EMDM is ",
                ", ".join(named[:-1]) + (" and " if len(named) > 1 else "") + named[-1],
                " (E2)",
                " and C-IVKC arrives (E4)" if e4.get("reached") else "",
                "; in these tasks, where the path does not matter, a slack was the better choice. ",
            )
        p += sentence(
            "Exact active-set QP solvers, certified at every step, are the right tool; "
            "gradient-free methods are not."
        )
        sec.paragraphs.append(p)
        return sec

    # ------------------------------------------------------------------ beyond the brief
    def beyond(self) -> Section:
        """The manipulability benchmark on spatial arms (the page only: the paper is the brief's)."""
        f = "data/mmc.json"
        sec = Section(
            "beyond",
            "Beyond the brief: spatial arms and the manipulability benchmark",
            html_only=True,
        )
        if not self.d.exists(f):
            return sec

        def r(arm: str, ctrl: str, key: str, fmt: str, unit: str = "") -> Num:
            return self.d.num(f, "results", arm, ctrl, key, fmt=fmt, unit=unit)

        def rv(arm: str, ctrl: str, key: str) -> Any:
            return self.d.value(f, "results", arm, ctrl, key)

        def pub(arm: str, ctrl: str, index: int, fmt: str, unit: str = "") -> Num:
            return self.d.num(f, "published", arm, ctrl, index, fmt=fmt, unit=unit)

        def with_pub(
            arm: str, ctrl: str, key: str, index: int, fmt: str, unit: str = ""
        ) -> Sentence:
            """Ours, then the published value in brackets where there is one."""
            ours = r(arm, ctrl, key, fmt, unit)
            if ctrl not in self.d.value(f, "published", arm):
                return sentence(ours)
            return sentence(ours, " (", pub(arm, ctrl, index, fmt, unit), ")")

        arms = [a for a in ("panda", "ur5") if a in self.d.value(f, "results")]
        least = all(
            rv(a, Name.MMC, "failure_rate")
            <= min(rv(a, c, "failure_rate") for c in (Name.RRMC, Name.PARK))
            for a in arms
        )
        answer = sentence(
            "On ",
            self.d.num(f, "trials", fmt="d"),
            " random pose tasks per arm, MMC (the slack program with joint bounds) fails ",
            "least on both arms" if least else "not always least",
            ": ",
        )
        for i, a in enumerate(arms):
            answer += sentence(
                r(a, Name.MMC, "failure_rate", ".1f", "%"),
                " on the ",
                "Panda" if a == "panda" else "UR5",
                " against RRMC's ",
                r(a, Name.RRMC, "failure_rate", ".1f", "%"),
                " (published ",
                pub(a, Name.MMC, 2, ".1f", "%"),
                " and ",
                pub(a, Name.RRMC, 2, ".1f", "%"),
                ")",
                "; " if i < len(arms) - 1 else ".",
            )
        sec.answer = answer
        sec.paragraphs.append(
            sentence(
                "The presets give the Panda (modified DH, to the flange) and the UR5 (standard DH) "
                "their published joint limits and MMC's settings (effort weight 0.01, slack weight "
                "1/||e||, dampers of 0.9 and 0.05 rad). RRMC is UC-IVKC and PARK (gradient "
                "projection) is UC-EMDM, both without slack. Each task starts at a configuration "
                "drawn uniformly inside the joint limits shrunk by the dampers' influence distance "
                "and asks for the pose of another such draw; a run fails when it does not reach "
                "the goal in the time limit, leaves its joint limits, or meets a step without an "
                "admissible command. This is emdm's own protocol, which also runs C-EMDM; the "
                "authors' protocol, from their experiment scripts, follows below."
            )
        )
        if "panda" in arms:
            p = "panda"
            above_all = rv(p, Name.MMC, "mean_manipulability") >= rv(
                p, Name.PARK, "mean_manipulability"
            )
            succ = rv(p, Name.MMC, "mean_manipulability_of_successes") or 0.0
            above_succ = succ >= (rv(p, Name.PARK, "mean_manipulability_of_successes") or 0.0)
            sec.paragraphs.append(
                sentence(
                    "Our failure rates are higher than the published ones because independent start "
                    "and goal draws ask for large motions: ",
                    r(p, Name.RRMC, "left_joint_limits", "d"),
                    " of RRMC's and ",
                    r(p, Name.PARK, "left_joint_limits", "d"),
                    " of PARK's Panda runs leave the joint limits, which nothing in their programs "
                    "prevents, while MMC's ",
                    r(p, Name.MMC, "not_reached", "d"),
                    " failures are stalls with joints held by their dampers. Over all runs MMC's "
                    "mean manipulability (",
                    r(p, Name.MMC, "mean_manipulability", ".4f"),
                    ") is ",
                    "above" if above_all else "below",
                    " PARK's (",
                    r(p, Name.PARK, "mean_manipulability", ".4f"),
                    "; published ",
                    pub(p, Name.MMC, 0, ".4f"),
                    " and ",
                    pub(p, Name.PARK, 0, ".4f"),
                    "); over the runs that reach the goal it is ",
                    "above" if above_succ else "below",
                    " (",
                    r(p, Name.MMC, "mean_manipulability_of_successes", ".4f"),
                    " against ",
                    r(p, Name.PARK, "mean_manipulability_of_successes", ".4f"),
                    ")",
                    (
                        ": a stalled run ends where the dampers hold it, often at low "
                        "manipulability."
                        if above_succ and not above_all
                        else (
                            ": PARK has no joint bounds, so its null-space motion climbs the "
                            "manipulability further than MMC's dampers allow."
                            if not above_succ
                            else "."
                        )
                    ),
                )
            )
        if "ur5" in arms:
            u = "ur5"
            sec.paragraphs.append(
                sentence(
                    "On the non-redundant UR5 the null space is empty, so PARK is RRMC (failure "
                    "rates ",
                    r(u, Name.PARK, "failure_rate", ".1f", "%"),
                    " and ",
                    r(u, Name.RRMC, "failure_rate", ".1f", "%"),
                    "), as in the published table; its manipulability is lower than published (",
                    r(u, Name.RRMC, "mean_manipulability", ".4f"),
                    " against ",
                    pub(u, Name.RRMC, 0, ".4f"),
                    "), which depends on where the tasks lie in the joint space.",
                )
            )
        table = Table(
            "mmc",
            sentence(
                "The manipulability benchmark: mean manipulability, mean final manipulability and "
                "failure rate over every run, the published value in brackets; the mean "
                "manipulability of the runs that reach the goal; why runs failed."
            ),
            [
                sentence("arm"),
                sentence("controller"),
                sentence("mean m"),
                sentence("final m"),
                sentence("failed"),
                sentence("m, reached"),
                sentence("not reached"),
                sentence("left limits"),
            ],
            align="llrrrrrr",
            html_only=True,
        )
        for a in arms:
            for c in self.d.value(f, "results", a):
                table.rows.append(
                    [
                        sentence("Panda" if a == "panda" else "UR5"),
                        sentence(c),
                        with_pub(a, c, "mean_manipulability", 0, ".4f"),
                        with_pub(a, c, "mean_final_manipulability", 1, ".4f"),
                        with_pub(a, c, "failure_rate", 2, ".1f", "%"),
                        sentence(r(a, c, "mean_manipulability_of_successes", ".4f")),
                        sentence(r(a, c, "not_reached", "d")),
                        sentence(r(a, c, "left_joint_limits", "d")),
                    ]
                )
        self.tables["mmc"] = table
        sec.tables.append("mmc")
        if self.d.exists(f) and "paper" in self.d.value(f):
            self._mmc_paper(sec, f, arms)
        pp = "panda_preset"
        sec.figures.append(
            self.figure(
                "panda-baselines",
                "figures/panda-baselines",
                sentence(
                    "The Panda preset task: the end-effector paths of RRMC, PARK, MMC and C-EMDM "
                    "in three projections. Mean manipulability: RRMC ",
                    self.d.num(f, pp, Name.RRMC, "mean_manipulability", fmt=".4f"),
                    ", PARK ",
                    self.d.num(f, pp, Name.PARK, "mean_manipulability", fmt=".4f"),
                    ", MMC ",
                    self.d.num(f, pp, Name.MMC, "mean_manipulability", fmt=".4f"),
                    ", C-EMDM ",
                    self.d.num(f, pp, Name.C_EMDM, "mean_manipulability", fmt=".4f"),
                    ".",
                ),
                wide=True,
                paper=False,
            )
        )
        return sec

    def _mmc_paper(self, sec: Section, f: str, arms: list[str]) -> None:
        """The benchmark under the authors' protocol (``emdm mmc``), beside the published table,
        with intervals and paired differences."""

        def r(arm: str, ctrl: str, *key: str | int, fmt: str, unit: str = "") -> Num:
            return self.d.num(f, "paper", "results", arm, ctrl, *key, fmt=fmt, unit=unit)

        def pub(arm: str, ctrl: str, index: int, fmt: str, unit: str = "") -> Sentence:
            if ctrl not in self.d.value(f, "published", arm):
                return sentence("")
            return sentence(
                " (", self.d.num(f, "published", arm, ctrl, index, fmt=fmt, unit=unit), ")"
            )

        def ci(arm: str, ctrl: str, key: str, fmt: str) -> Sentence:
            return sentence(
                "[", r(arm, ctrl, key, 0, fmt=fmt), ", ", r(arm, ctrl, key, 1, fmt=fmt), "]"
            )

        best = all(
            self.d.value(f, "paper", "results", a, Name.MMC, "mean_manipulability")
            >= max(
                self.d.value(f, "paper", "results", a, c, "mean_manipulability")
                for c in self.d.value(f, "paper", "results", a)
            )
            and self.d.value(f, "paper", "results", a, Name.MMC, "failure_rate")
            <= min(
                self.d.value(f, "paper", "results", a, c, "failure_rate")
                for c in self.d.value(f, "paper", "results", a)
            )
            for a in arms
        )
        text = sentence(
            "Under the authors' protocol (robotics-toolbox-python's exp1.py for the Panda and "
            "expUR.py for the UR5: starts and goals inside the limits shrunk by 0.27 of each range, "
            "the joint-limited UR5 of their script, p_servo arrival at 0.17, at most 100 steps of "
            "50 ms, a failure at a limit of the first n-2 joints; the command emdm mmc), on ",
            self.d.num(f, "paper", "trials", fmt="d"),
            " tasks per arm, MMC has ",
            "the highest mean manipulability and the fewest failures on both arms, the "
            "published order"
            if best
            else "not both the highest mean manipulability and the fewest failures on every arm",
            ". Means are over the trials in which every controller arrived (RRMC and MMC on the "
            "UR5, as its script), with Student's 95 % interval; the paired difference to MMC is "
            "over the same trials; failure rates carry Wilson's interval.",
        )
        outside = [
            a
            for a in arms
            if Name.MMC in self.d.value(f, "published", a)
            and not (
                self.d.value(f, "paper", "results", a, Name.MMC, "mean_manipulability_ci")[0]
                <= self.d.value(f, "published", a, Name.MMC)[0]
                <= self.d.value(f, "paper", "results", a, Name.MMC, "mean_manipulability_ci")[1]
            )
        ]
        if outside:
            text += sentence(
                " The published mean manipulability of MMC lies outside our interval on the ",
                " and the ".join("Panda" if a == "panda" else "UR5" for a in outside),
                ": the scripts' model versions and random tasks are not published, so that gap "
                "is stated, not explained.",
            )
        sec.paragraphs.append(text)
        table = Table(
            "mmc-paper",
            sentence(
                "The manipulability benchmark under the authors' protocol, published values in "
                "brackets: mean and final manipulability over the trials in which every "
                "controller arrived, with the 95 % interval of the mean; the paired difference "
                "of the mean to MMC's; failure rate with its 95 % interval; failures by cause."
            ),
            [
                sentence("arm"),
                sentence("controller"),
                sentence("mean m"),
                sentence("95 % CI"),
                sentence("final m"),
                sentence("m - m(MMC)"),
                sentence("failed"),
                sentence("95 % CI"),
                sentence("at a limit"),
                sentence("singular"),
                sentence("step cap"),
                sentence("trials averaged"),
            ],
            align="llrrrrrrrrrr",
            html_only=True,
        )
        for a in arms:
            for c in self.d.value(f, "paper", "results", a):
                paired = (
                    sentence("0")
                    if c == Name.MMC
                    else sentence(r(a, c, "mean_manipulability_minus_mmc", fmt="+.4f"))
                )
                table.rows.append(
                    [
                        sentence("Panda" if a == "panda" else "UR5"),
                        sentence(c),
                        sentence(r(a, c, "mean_manipulability", fmt=".4f"), *pub(a, c, 0, ".4f")),
                        ci(a, c, "mean_manipulability_ci", ".4f"),
                        sentence(
                            r(a, c, "mean_final_manipulability", fmt=".4f"), *pub(a, c, 1, ".4f")
                        ),
                        paired,
                        sentence(
                            r(a, c, "failure_rate", fmt=".1f", unit="%"), *pub(a, c, 2, ".1f", "%")
                        ),
                        ci(a, c, "failure_rate_ci", ".1f"),
                        sentence(r(a, c, "joint_limit", fmt="d")),
                        sentence(r(a, c, "singular", fmt="d")),
                        sentence(r(a, c, "missed", fmt="d")),
                        sentence(r(a, c, "all_arrived_trials", fmt="d")),
                    ]
                )
        self.tables["mmc-paper"] = table
        sec.tables.append("mmc-paper")

    # ------------------------------------------------------------------ tables
    def outcome_table(self, sections: list[Section]) -> None:
        header = [
            sentence("controller"),
            sentence("goal"),
            sentence("mean ", M_SYM),
            sentence(Math(r"\sum E\Delta t", "Σ<i>E</i>Δ<i>t</i>")),
            sentence("max ", Math(r"|\dot q|", "|<i>q̇</i>|")),
            sentence("scaled"),
        ]
        table = Table(
            "outcomes",
            sentence(
                "Closed-loop outcomes: time to goal (s; ",
                ERR,
                " < 1 mm) or final error (m), mean manipulability (m²), total effort "
                "(rad²/s), largest joint speed (rad/s), task-scaled steps.",
            ),
            header,
            align="lrrrrr",
        )
        for task, title in (("task1", "Task 1 (three links)"), ("task2", "Task 2 (two links)")):
            table.rows.append([sentence(title)])
            for name in (Name.UC_IVKC, Name.UC_EMDM, Name.C_IVKC, Name.C_EMDM):
                goal = (
                    sentence(bare(self.ttg(task, name)))
                    if self.mv(task, name, "reached")
                    else sentence("(", self.mt(task, name, "final_error", ".3f"), " m)")
                )
                table.rows.append(
                    [
                        sentence(name),
                        goal,
                        sentence(self.mt(task, name, "mean_manipulability", ".3f")),
                        sentence(self.mt(task, name, "total_effort", ".2f")),
                        sentence(self.mt(task, name, "max_abs_qd", ".2f")),
                        sentence(self.mt(task, name, "scaled_steps", "d")),
                    ]
                )
        self.tables["outcomes"] = table
        for s in sections:
            if s.key == "task1":
                s.tables.append("outcomes")

    def solver_table(self, f: str, rows: dict[str, Any]) -> None:
        table = Table(
            "solvers",
            sentence(
                "Task 2 C-EMDM solvers on the same programs (medians; largest gap and bound "
                "violation, 0: below ",
                Math(r"10^{-12}", "10<sup>−12</sup>"),
                "; it./ev.: iterations/evaluations, --: none; goal: alone in the loop).",
            ),
            [
                sentence("solver"),
                sentence("ms"),
                sentence("it./ev."),
                sentence("gap"),
                sentence("viol."),
                sentence("goal (s)"),
            ],
            align="lrrrrr",
            font="scriptsize" if len(rows) > 8 else "footnotesize",  # 7 pt fits a column
            colsep=3.0,
        )
        for family, title in (
            ("exact", "exact QP"),
            ("gradient", "gradient-based"),
            ("gradient-free", "gradient-free"),
        ):
            names = [k for k, r in rows.items() if r["family"] == family]
            if not names:
                continue
            table.rows.append([sentence(title)])
            for k in names:
                r = rows[k]
                goal = (
                    sentence(self.d.num(f, "solvers", k, "time_to_goal", fmt=".2f"))
                    if r.get("reached")
                    else sentence("--")
                )
                table.rows.append(
                    [
                        sentence(k),
                        sentence(bare(self.d.ms(f, "solvers", k, "median_time"))),
                        sentence(  # a count of 0: none reported (daqp; a QP's evaluations)
                            *(
                                self.d.num(f, "solvers", k, key, fmt=".4g") if r[key] else "--"
                                for key in ("median_iterations",)
                            ),
                            "/",
                            *(
                                self.d.num(f, "solvers", k, key, fmt=".4g") if r[key] else "--"
                                for key in ("median_evaluations",)
                            ),
                        ),
                        sentence(  # two digits, as the text quotes them
                            self.d.num(f, "solvers", k, "max_abs_gap", fmt=".2g")
                            if abs(r["max_abs_gap"]) >= 1e-12
                            else Text("0")
                        ),
                        sentence(
                            self.d.num(f, "solvers", k, "max_violation", fmt=".0e")
                            if r["max_violation"] >= 1e-12
                            else Text("0")
                        ),
                        goal,
                    ]
                )
        self.tables["solvers"] = table

    def e3_row(self) -> list[Sentence] | None:
        """Table II's E3: the first weight setting of the grid that misses the goal, re-run with
        a five times smaller time step, against itself at the nominal step (Section III-B)."""
        grid = "data/task1-pareto-UC-EMDM/weight_grid.json"
        if not self.d.exists(grid):
            return None
        runs = self.d.value(grid, "runs")
        missed = [i for i, r in enumerate(runs) if not r.get("reached")]
        if not missed or "total_effort" not in runs[missed[0]].get("finer_dt", {}):
            return None
        i = missed[0]
        finer = runs[i]["finer_dt"]
        cells = [
            sentence(
                self.d.num(grid, "runs", i, "finer_dt", "time_to_goal", fmt=".2f")
                if finer["reached"]
                else "stall",
                " (stall)",
            )
        ]
        for metric, fmt, nominal in (
            ("mean_manipulability", ".3f", ".3f"),
            ("total_effort", ".1f", ".0f"),  # one column: 20.1 (11749)
        ):
            cells.append(
                sentence(
                    self.d.num(grid, "runs", i, "finer_dt", metric, fmt=fmt),
                    " (",
                    self.d.num(grid, "runs", i, metric, fmt=nominal),
                    ")",
                )
            )
        # both changes from the nominal run: the weights (Section III-B's failing setting) and
        # the time step (over five)
        slower = self.d.value("data/task1/metrics.json", "scenario", "motion", "dt") / finer["dt"]
        change = sentence(
            DT, f"/{slower:.0f}, ", *eq(W_M, self.d.num(grid, "runs", i, "w_manip", fmt=".4g"))
        )
        return [sentence("E3"), sentence("1, ", Name.UC_EMDM), change, *cells]

    def evidence_table(self, sections: list[Section]) -> None:
        items = [
            ("E1", "t1-uc-no-manip", Name.UC_EMDM, sentence(W_M, " = 0"), "reference"),
            ("E2", "t1-c-slack-policy", Name.C_EMDM, sentence("slack policy"), "pair"),
            ("E4", "t2-c-ivkc-slack-policy", Name.C_IVKC, sentence("slack policy"), None),
            (
                "E5",
                "t2-c-ivkc-wide-limits",
                Name.C_IVKC,
                sentence(Math(r"|q|\leq3", "|<i>q</i>| ≤ 3"), " rad"),
                None,
            ),
            ("E6", "t2-c-emdm-no-manip", Name.C_EMDM, sentence(W_M, " = 0"), None),
            (
                "E7",
                "t2-c-emdm-tight-slack",
                Name.C_EMDM,
                sentence(Math(r"|\delta|\leq0.1", "|δ| ≤ 0.1"), " m/s"),
                None,
            ),
            (
                "E8",
                "t2-uc-emdm-stiff-slack",
                Name.UC_EMDM,
                sentence(Math(r"c_S=10^4", "<i>c</i><sub>S</sub> = 10<sup>4</sup>")),
                None,
            ),
        ]
        table = Table(
            "evidence",
            sentence(
                "Evidence runs: one change to a nominal run, and its outcomes as evidence "
                "(nominal; E3's: its weights at the nominal ",
                DT,
                ", ",
                Ref("sec", "t1-pareto"),
                "); stall: goal not reached.",
            ),
            [
                sentence("run"),
                sentence("task, ctrl."),
                sentence("change"),
                sentence("goal (s)"),
                sentence("mean ", M_SYM),
                sentence(Math(r"\sum E\Delta t", "Σ<i>E</i>Δ<i>t</i>")),
            ],
            align="lllrrr",
            font="scriptsize",
            colsep=2.5,  # six columns of two numbers each at column width
        )
        for label, key, ctrl, change, _kind in items:
            entry = self.evid(key)
            task = entry["task"]
            run = entry["runs"].get(ctrl, {})
            cells: list[Sentence] = []
            for metric, fmt in (
                ("time_to_goal", ".2f"),
                ("mean_manipulability", ".3f"),
                ("total_effort", ".2f"),
            ):
                if "error" in run:
                    cells.append(sentence("no solution"))
                    continue
                stall = metric == "time_to_goal"
                new = (
                    sentence("stall")
                    if stall and not run["reached"]
                    else sentence(self.evidn(key, "runs", ctrl, metric, fmt=fmt))
                )
                old = (
                    sentence("stall")
                    if stall and not self.mv(task, ctrl, "reached")
                    else sentence(self.mt(task, ctrl, metric, fmt))
                )
                cells.append(new + sentence(" (") + old + sentence(")"))
            table.rows.append(
                [
                    sentence(label),
                    sentence("1" if task == "task1" else "2", ", ", ctrl),
                    change,
                    *cells,
                ]
            )
            if label == "E2" and (e3 := self.e3_row()):
                table.rows.append(e3)
        self.tables["evidence"] = table
        for s in sections:
            if s.key == "t2-c":
                s.tables.append("evidence")


__all__ = ["Story", "format_value"]
