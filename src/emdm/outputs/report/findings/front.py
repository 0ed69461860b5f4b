"""The abstract, the introduction and the conclusion."""

from __future__ import annotations

from ....core.controllers import Name
from ..config import PAIRS
from ..document import Section
from ..trace import Cite, Ref, Sentence, sentence
from .base import (
    M_SYM,
    StoryBase,
)


class Front(StoryBase):
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
                        ".",
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
                "IVKC, each unconstrained (UC-) or constrained by joint limits (C-); runs that "
                "change one thing test our explanations (",
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
