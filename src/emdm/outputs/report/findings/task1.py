"""Task 1: the redundant three-link arm (Tasks 1.1 and 1.2, the Pareto fronts, the custom solver)."""

from __future__ import annotations

import math
from typing import Any

from ....core.controllers import Name
from ....core.tolerances import KKT_TOL
from ..config import FOURTH_PANEL, PAIRS
from ..document import Section
from ..trace import File, Math, Num, PageOnly, Ref, Segment, Sentence, Text, sentence
from ..trace import cap as capitalised
from .base import (
    ALPHA,
    ARMS_IN_PAPER,
    COND_J,
    DT,
    E_SYM,
    FINER_STEP,
    GRID_MISS,
    K_EQ,
    M_SYM,
    MRATE,
    RATIO,
    SCALED_LAB,
    VD,
    W_M,
    eq,
    more_for_more,
    run_label,
)
from .claims import LEVEL, Claims
from .records import GRID_FILE, EvidenceKey, MetricKey

KKT_EXP = round(math.log10(KKT_TOL))
"""The exponent of the KKT check's acceptance threshold, as the paper writes it."""

PARETO_RECORD = "data/task1-pareto-UC-EMDM/pareto.json"
"""UC-EMDM's Pareto sweep of Task 1 (its ratios and the nominal one)."""


class Task1(Claims):
    def arms_caption(self) -> Sentence:
        """The caption of Task 1's stills: what is drawn and the animations they come from
        (each run's final m is in the legend)."""
        return sentence(
            "Stills of Task 1's animations",
            # (the folder holds every pair's, Task 2's too: named once, here)
            *((" (", File("animations/"), ")") if self.anim("task1", "UC") else ()),
            ": the start arm (grey) and each run's arm at its end, with its tip path (dotted) "
            "and velocity ellipse there (one scale); legend: final ",
            M_SYM,
            ".",
        )

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
        # the result first, then how closely the two track
        answer = sentence(  # the trade last, where it gets the stress (a copy editor's order)
            f"{emdm} tracks as well as {ivkc} ",
            "but " if self.pair_rises(t, "UC") else "and ",
            *self.pair_trade(t, "UC"),
            ". ",
        )
        # the figure where it shows what is said: the arrivals in (c), the tips' gap in (d)'s
        # paths when drawn (reading 146: (c) shows the distance to the goal, not the gap)
        where = sentence(" (", Ref("fig", "t1-uc"), "(c))")
        arms = self.figure(
            "t1-arms", "figures/task1-arms", self.arms_caption(), paper=ARMS_IN_PAPER
        )
        if same_time and self.mv(t, emdm, "reached"):
            answer += sentence("Both reach the goal at the same time", *where)
        else:
            answer += sentence(
                f"{emdm} ", *self.outcome(t, emdm), f", {ivkc} ", *self.outcome(t, ivkc), *where
            )
        answer += sentence(
            ", with their tips never more than ",  # (248: a comma splice)
            gap,
            " apart",
            *(
                (" (", Ref("fig", "t1-uc"), "(d))")
                if FOURTH_PANEL[t] == "path"
                # (the paths it draws coincide: a per-step distance is not drawn, reading 163)
                else (" (paths: ", Ref("fig", "t1-arms"), ")")
                if self.has_figure("t1-arms") and ARMS_IN_PAPER
                else ()
            ),
            ".",
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
        sec.figures.append(arms)
        # why the tracking is the same
        p = sentence(
            # why the tips stay together: on the page (Fig. 1(d) overlays them in the paper)
            PageOnly(
                tuple(
                    sentence(
                        "Both impose ",
                        Math(r"J\dot q=v_d", "<i>J q̇</i> = <i>v</i><sub>d</sub>"),
                        " exactly, so their tips differ only through the Euler steps' ",
                        Math(r"O(\Delta t^2)", "<i>O</i>(Δ<i>t</i><sup>2</sup>)"),
                        " terms. ",
                    )
                )
            ),
            # why (reading 183: say why null-space motion raises m)
            "Without bounds, EMDM's program has the closed-form solution ",
            Math(
                r"\dot q=J^+v_d+\tfrac{w_M}{w_E}(I-J^+J)J_m",
                "<i>q̇</i> = <i>J</i><sup>+</sup><i>v</i><sub>d</sub> + (<i>w</i><sub>M</sub>/"
                "<i>w</i><sub>E</sub>)(<i>I</i> − <i>J</i><sup>+</sup><i>J</i>)<i>J</i><sub>m</sub>",
            ),
            ": IVKC's command plus the manipulability gradient projected into ",
            Math("J", "<i>J</i>"),
            "'s null space. That motion raises ",
            M_SYM,
            " without moving the tip. With ",
            W_M,
            " = 0 (",
            run_label("t1-uc-no-manip"),
            ", ",  # the first ablation named: where its row is (editor after 209, 210)
            Ref("tab", "outcomes"),
            "), ",
        )
        ref = self.evid("t1-uc-no-manip", "reference")
        if ref["max_abs_qd_difference"] == 0.0 and ref["same_steps"]:
            p += sentence(
                f"{emdm} reproduces {ivkc} command for command. ",
            )
        else:  # what the bound means: the two are one controller up to rounding
            p += sentence(
                "the two commands agree to within ",
                self.evidn(
                    "t1-uc-no-manip", "reference", "max_abs_qd_difference", fmt=".1e", unit="rad/s"
                ),
                ", rounding error. ",
            )
        p += sentence("Neither controller sees the limits: ")
        for name in (ivkc, emdm):
            if self.evv(t, name, "limits", "max_excess") > 0:
                p += sentence(
                    f"{name} overshoots joint ",
                    self.ev(t, name, "limits", "excess_joint", fmt="d"),
                    "'s range by ",
                    self.ev(t, name, "limits", "max_excess", fmt=".3f", unit="rad"),
                    ", and ",
                )
        p += sentence(
            "both exceed the ",
            self.scn(t, "arm", "qd_max", 0, fmt=".1f", unit="rad/s"),
            " speed limit",
            " (",
            Ref("tab", "outcomes"),
            ").",
        )
        sec.paragraphs.append(p + self.finer_dt_trade())
        return sec

    def finer_dt_trade(self) -> Sentence:
        """`` Most of each UC run's effort comes in its first second, so the trade depends on dt:
        at dt = 0.01 s, it is 16% more mean m for 21% more effort.``: the UC pair at a finer
        step (readings 213, 227: the headline percentages are dt's; 228: A2b's own baseline),
        where both arrive, every change is a rise and each run spends most in its first
        second (empty otherwise)."""
        key: EvidenceKey = "t1-uc-finer-dt"
        t = "task1"
        ivkc, emdm = PAIRS["UC"]
        if key not in self.rec.evidence:
            return []
        runs = {c: self.evid(key, "runs", c) for c in (ivkc, emdm)}
        if not all(r.get("reached") for r in runs.values()):
            return []
        keys: tuple[MetricKey, MetricKey] = ("mean_manipulability", "total_effort")
        if not all(runs[emdm][k] > runs[ivkc][k] for k in keys):
            return []
        if min(self.evv(t, c, "effort", "share_first_second") for c in (ivkc, emdm)) <= 0.5:
            return []
        f = "data/evidence.json"

        def rise(k: MetricKey) -> Num:
            return self.d.pct(
                (f, "runs", key, "runs", emdm, k), (f, "runs", key, "runs", ivkc, k), fmt=".0f"
            )

        return sentence(
            # (229: "each run" read as every run of the paper; C-EMDM spends 44 % there)
            " Most of each UC run's effort comes in its first second, so the trade depends on ",
            DT,
            ": at ",
            # one piece, as k = 144 is (234: "dt" and "= 0.01 s" fell on two lines)
            Math(r"\Delta t={}", "Δ<i>t</i> = "),
            self.evidn(key, "overrides", "motion.dt", fmt="g", unit="s"),
            ", it is ",
            *more_for_more(rise(keys[0]), rise(keys[1])),
            ".",
        )

    def task1_c(self) -> Section:
        t = "task1"
        ivkc, emdm = PAIRS["C"]
        sec = Section("t1-c", "Task 1.2: C-EMDM against C-IVKC", level=2, brief="1.2")
        # the result first, then safety, then the arrivals
        answer = sentence(
            f"{emdm} again ",
            *self.pair_trade(t, "C"),
            ". ",
            "Both (",
            Ref("fig", "t1-c"),
            ") obey every speed limit and keep each joint at least ",
            self.mt(t, ivkc, "min_stop_margin", ".3f", "rad"),
            f" ({ivkc}) or ",
            self.mt(t, emdm, "min_stop_margin", ".3f", "rad"),
            f" ({emdm}) outside its stop zone. ",
            *(  # the arrival times are Table II's (readings 190-195: prose too dense)
                sentence("Both reach the goal (", Ref("tab", "outcomes"), "), their tips")
                if self.mv(t, ivkc, "reached") and self.mv(t, emdm, "reached")
                else sentence(
                    f"{emdm} ", *self.outcome(t, emdm), f" and {ivkc} ", *self.outcome(t, ivkc)
                )
                + sentence(", the end effectors")
            ),
            " at most ",
            self.pairn(t, "C", "max_path_gap", ".4f", "m"),
            " apart at equal times",
        )
        scaled = self.evv(t, emdm, "scaling")
        times = [self.mv(t, c, "time_to_goal") for c in (*PAIRS["UC"], *PAIRS["C"])]
        if scaled and None not in times and min(times[2:]) > max(times[:2]):
            answer += sentence(
                # on the page only (the arrival times are Table II's: room for the per-
                # controller terms table, readings 221, 222)
                PageOnly(
                    tuple(
                        sentence(
                            ". The ",
                            self.scn(t, "arm", "qd_max", 0, fmt="g", unit="rad/s"),
                            " speed limit makes both slower than the UC pair",
                            " (the task is scaled for the first ",
                            self.ev(t, emdm, "scaling", "first_duration", fmt=".2f", unit="s"),
                            ")",
                        )
                    )
                ),
            )
        answer += sentence(".")
        sec.answer = answer
        self.answers.append(
            ("Task 1.2: implement and compare C-EMDM and C-IVKC, same analysis", answer)
        )
        sec.figures.append(self.figure("t1-c", "figures/task1-C", self.pair_caption(t, "C")))
        same = self.pair(t, "C", "coincide_steps")
        # every common step is one where the joints at their bounds leave at most two free
        # joints, which the two task equations fix: the reason is stated only when it holds
        if same and self.pair(t, "C", "coincide_determined_steps") == same:
            p = sentence(
                "In the first ",
                self.pairn(t, "C", "coincide_until_t", ".2f", "s"),
                PageOnly(  # (the counts on the page: room for the random goals, 192-193)
                    tuple(
                        sentence(
                            " (",
                            self.pairn(t, "C", "coincide_steps", "d"),
                            " steps, ",
                            self.pairn(t, "C", "coincide_scaled_steps", "d"),
                            " of them scaled)",
                        )
                    )
                ),
                # (222, 225 took it for the scaled steps' alone: it holds after them too;
                # 243: plainer)
                ", both send the same commands: the speed bounds leave one feasible command "
                "per step, scaled or not",
            )
            # one paragraph with the policy weighed: both tell what scaling does to the pair
            sec.paragraphs.append(
                p
                + sentence(". ")
                + self.policy_weighed()
                + sentence(PageOnly(tuple(self.brief_slack())))
            )
        else:
            sec.paragraphs.append(
                self.policy_weighed() + sentence(PageOnly(tuple(self.brief_slack())))
            )
        return sec

    def ratios_swept(self) -> Sentence:
        """``. Ratios: 0 and 10^-3 to 10^4, 4 per decade, in the fronts; 0 and 12 from 10^-2 to
        10^3 in the runs`` (and the nominal ratio): Fig. 2's sweeps, from their records (empty where
        either is missing)."""
        f = PARETO_RECORD
        grid = self.rec.grids.get("UC-EMDM", [])
        if not (self.d.exists(f) and grid):
            return []
        nominal = float(self.d.value(f, "nominal_ratio"))

        def spread(ratios: list[float]) -> tuple[Sentence, int, float]:
            pos = sorted(r for r in ratios if r > 0 and not math.isclose(r, nominal))
            lo, hi = pos[0], pos[-1]

            def power(x: float) -> Segment:
                e = math.log10(x)
                if abs(e - round(e)) < 1e-9:
                    return Math(f"10^{{{round(e)}}}", f"10<sup>{round(e)}</sup>".replace("-", "−"))
                return Text(f"{x:.3g}")

            return (
                sentence(power(lo), " to ", power(hi)),
                len(pos),
                (len(pos) - 1) / math.log10(hi / lo),
            )

        fronts, _, per = spread([float(r) for r in self.d.value(f, "ratios")])
        runs, count, _ = spread([r.w_manip / r.w_effort for r in grid])
        return sentence(
            ". Ratios: 0 and ",
            *fronts,
            f", {per:.2g} per decade, in the fronts; 0 and {count} from ",
            *runs,
            " in the runs",
        )

    def pareto(self) -> Section:
        sec = Section("t1-pareto", "Task 1: Pareto fronts and weights", level=2, brief="1.1-1.2")
        uc = "data/task1-pareto-UC-EMDM/fronts.json"  # (the percentages trace both operands)
        if "UC-EMDM" not in self.rec.fronts:
            return sec
        cap = sentence(
            # (two lines, not three: room for the per-controller terms table, 221, 222)
            # (283: in sentences, the axes first)
            "Pareto fronts, effort ",
            E_SYM,
            " against rate ",
            MRATE,
            ", at ",
            Math(
                r"k=0,\lfloor T/3\rfloor,\lfloor 2T/3\rfloor,T",
                "<i>k</i> = 0, ⌊<i>T</i>/3⌋, ⌊2<i>T</i>/3⌋, <i>T</i>",
            ),
            # (227, 228: the text calls them convex; on these axes they look concave)
            # (280: two narrow panels are linear)
            " (log ",
            E_SYM,
            " axes, where it spans decades, can make convex fronts look concave). Each point: "
            "the optimum at the nominal run's ",
            Math("q_k", "<i>q</i><sub>k</sub>"),
            " for one ",
            RATIO,
            ", coloured by its log (",
            Math("w_M=0", "<i>w</i><sub>M</sub> = 0"),
            " at the bar's foot; circle: nominal",
            *(  # the nominal ratio, in neither sweep's count (readings took it for missing;
                # 238: ", 50" cryptic)
                (" ", RATIO, " = ", self.d.num(PARETO_RECORD, "nominal_ratio", fmt=".3g"))
                if self.d.exists(PARETO_RECORD)
                else ()
            ),
            "). Right: whole runs. Without a slack, only the ratio matters",
        )
        cap += sentence(PageOnly(tuple(self.ratios_swept())))  # the sweeps: on the page
        fronts = self.rec.fronts.get("C-EMDM", [])
        if any(f.slack_distinct is not None for f in fronts):  # jobs._job_pareto drew them
            cap += sentence("; hollow: a scaled step's free-slack optimum")
        cap += sentence(".")
        sec.figures.append(self.figure("pareto", "figures/pareto", cap, wide=True))
        answer = sentence(  # the finding, then its evidence (editor after readings 209, 210);
            # what the fronts say (reading 183: never interpreted): the weighted sum's optima
            # lie on the convex hull of the attainable (M, E) set
            # each step's, not the whole runs' (231: a ratio there is dominated); a consequence,
            # not a finding (215: E convex, M linear in q-dot)
            # (a plain-language edit: the finding in words first, then why)
            "Each gain in ",
            MRATE,
            " costs more effort than the last: every step's front (",
            Ref("fig", "pareto"),
            ") is convex, as ",
            E_SYM,
            " is convex and ",
            MRATE,
            " linear. At ",
            K_EQ,
            "0, raising ",
            RATIO,
            " from 0 to ",
            self.d.num(PARETO_RECORD, "ratios", -1, fmt=".0e"),
            " lifts UC-EMDM's optimal ",
            MRATE,
            " from ",
            self.frontn("UC-EMDM", 0, "M_min", ".3g"),
            " to ",
            self.frontn("UC-EMDM", 0, "M_max", ".3g", "m²/s"),
            ", and its effort from ",
            self.frontn("UC-EMDM", 0, "E_min", ".3g"),
            " to ",
            self.frontn("UC-EMDM", 0, "E_max", ".3g", "rad²/s²"),
            ". ",
        )
        answer += sentence("The nominal weights need ")  # (235: plainer than "ratio costs")
        e0 = self.front("UC-EMDM", 0, "zero_E")
        en = self.front("UC-EMDM", 0, "nominal_E")
        answer += sentence(
            *(
                (
                    self.d.pct((uc, "steps", 0, "nominal_E"), (uc, "steps", 0, "zero_E"), ".1f"),
                    " more effort than the minimum at ",
                    K_EQ,
                    "0",
                )
                if e0 > 0 and en >= e0
                else ("little in effort",)
            ),
            ".",
        )
        i = self.dearest_later("UC-EMDM")
        if i is not None:  # dearer later: say so
            last = i == len(self.rec.fronts["UC-EMDM"]) - 1
            answer += sentence(
                " At the goal (" if last else " Near the goal (",
                K_EQ,
                self.frontn("UC-EMDM", i, "k", "d"),
                # (221: the brief's k = T front is at the arrived state, whose command the
                # loop never sends)
                ", no command sent" if last else "",
                # a percentage of a vanishing effort near the goal: its size in rad^2/s^2 too
                # (225: "it" had no clear referent; 223-226: the minimum after the price)
                # (238: which of the two the number was)
                "), their effort is ",
                self.d.pct((uc, "steps", i, "nominal_E"), (uc, "steps", i, "zero_E"), ".0f"),
                " above the minimum of ",
                self.frontn("UC-EMDM", i, "zero_E", ".1e", "rad²/s²"),
            )
            answer += sentence(".")
        answer += self.whole_runs_levelled()
        sec.answer = answer
        self.answers.append(("Task 1: Pareto front between E and M at t = 0, T/3, 2T/3, T", answer))
        # degenerate and saturated fronts of C-EMDM, one clause each
        p: Sentence = []
        if "C-EMDM" in self.rec.fronts:
            csteps = self.rec.fronts["C-EMDM"]
            clauses: list[Sentence] = []
            page_only: set[int] = set()
            for i, info in enumerate(csteps):
                if info.degenerate:
                    clauses.append(
                        sentence(  # what "the front is one point" means (reading 151)
                            "at ",
                            K_EQ,
                            self.frontn("C-EMDM", i, "k", "d"),
                            # (readings 197, 200: plainer, the reason in its own clause)
                            # (editor after 209, 210: Section II's plain words, not "the
                            # scaled step")
                            ", C-EMDM's front is one point. Whatever the weights, the speed "
                            "limits allow one command, delivering only ",
                            *eq(ALPHA, self.frontn("C-EMDM", i, "alpha", ".2f")),
                            " of ",
                            VD,
                        )
                    )
                    if info.slack_distinct == 1:  # not the policy's doing: the bounds'
                        clauses[-1] += sentence(  # (Fig. 2 cited in the answer above)
                            ". A free slack also gives one point (hollow)",
                        )
            sat = [(i, s) for i, s in enumerate(csteps) if s.saturated_from_ratio is not None]
            if sat:
                i, _ = sat[0]
                clauses.append(
                    sentence(
                        "at ",
                        K_EQ,
                        self.frontn("C-EMDM", i, "k", "d"),
                        ", ratios ",
                        RATIO,
                        " ",
                        Math(r"\geq", "≥"),
                        " ",
                        self.frontn("C-EMDM", i, "saturated_from_ratio", ".3g"),
                        " all give one optimum, a vertex of the feasible set",
                    )
                )
                page_only.add(len(clauses) - 1)  # Fig. 3 notes it (reading 165): room
            late = [i for i, st in enumerate(csteps) if i > 0 and st.M_max < 0]
            if late and late == list(range(late[0], len(csteps))):  # m falls, whatever w_M
                top = max(late, key=lambda i: csteps[i].M_max)  # the least negative of them all
                ks: Sentence = []
                for j, i in enumerate(late):  # the fronts computed, not the steps between them
                    sep = "" if j == 0 else (" and " if j == len(late) - 1 else ", ")
                    ks += sentence(sep, self.frontn("C-EMDM", i, "k", "d"))
                clauses.append(
                    sentence(
                        "at ",
                        K_EQ,
                        *ks,
                        ", every optimum has ",
                        MRATE,
                        " < 0",
                        # the largest, rounded (reading 178: "at most -4.8e-5" under it), on
                        # the page: room for Section II's definitions (readings 190, 191)
                        PageOnly(
                            tuple(
                                sentence(
                                    " (the largest is ",
                                    self.frontn("C-EMDM", top, "M_max", ".2e", "m²/s"),
                                    ")",
                                )
                            )
                        ),
                        ": late in the run, ",
                        M_SYM,
                        " falls whatever the weights",
                    )
                )
                # Fig. 2's negative M axes show it; on the page only (room for the UC pair's
                # trade at a finer step, readings 213, 227, 228)
                page_only.add(len(clauses) - 1)
            for c, clause in enumerate(clauses):  # one sentence each
                said = capitalised(clause) if c == 0 else sentence(". ") + capitalised(clause)
                p += [PageOnly(tuple(said))] if c in page_only and c > 0 else said
            if clauses:
                p += sentence(". ")
        # the weight grid: failures
        for i, r in enumerate(self.rec.grids.get("UC-EMDM", [])):
            if r.reached or r.finer_dt is None:
                continue
            said = sentence(
                "UC-EMDM",
                # its peak on the page only: the digits of a diverging run depend on rounding
                # (Table I prints dashes)
                PageOnly(
                    tuple(
                        sentence(
                            "'s joints reach ",
                            self.gridn("UC-EMDM", i, "max_abs_qd", fmt=".0f", unit="rad/s"),
                            " and it",
                        )
                    )
                ),
                " misses the goal at ",
                *eq(W_M, self.gridn("UC-EMDM", i, "w_manip", fmt=".4g")),
                " (",
                run_label(GRID_MISS),
                ")",
            )
            finer = r.finer_dt
            if finer.get("reached"):
                said += sentence(
                    " but arrives at ",
                    *eq(DT, self.gridn("UC-EMDM", i, "finer_dt", "dt", fmt=".2f", unit="s")),
                    " (",
                    run_label(FINER_STEP),
                    # (263, 264: "the Euler step, not w_M" overclaimed: the weight's fast
                    # commands and the coarse step miss together)
                    "): its speeds need a finer Euler step",
                    PageOnly(  # (its effort on the page only)
                        tuple(
                            sentence(
                                ", spending ",
                                self.gridn(
                                    "UC-EMDM",
                                    i,
                                    "finer_dt",
                                    "total_effort",
                                    fmt=".3g",
                                    unit="rad²/s",
                                ),
                                " against ",
                                self.gridn(
                                    "UC-EMDM", i, "finer_dt", "nominal", "total_effort", fmt=".3g"
                                ),
                                " at nominal weights and that step (the weights' extra effort)",
                            )
                        )
                    ),
                )
            # in the paper again since the programs' displays made room (258, 260: Table I's
            # A2a and A2b rows were told nowhere)
            p += said + sentence(". ")
            break
        if p:
            sec.paragraphs.append(p)
        return sec

    def whole_runs_levelled(self) -> Sentence:
        """What the whole-run sweep (Fig. 2, right) says of the nominal ratio: how much more mean
        m and effort the larger ratios that still reach the goal give UC-EMDM."""
        found = self.beyond_nominal()
        if found is None:
            return []
        n, best, dearest = found
        grid = self.rec.grids["UC-EMDM"]
        f = GRID_FILE.format(ctrl=Name.UC_EMDM)
        gain = grid[best].mean_manipulability / grid[n].mean_manipulability - 1.0
        more: Sentence = (
            sentence(
                "add at most ",
                self.d.pct(
                    (f, "runs", best, "mean_manipulability"),
                    (f, "runs", n, "mean_manipulability"),
                    fmt="+.1f",
                ),
                " to",
            )
            if gain > 0
            else sentence("add nothing to")
        )
        knee = self.levels_off_at()
        if knee is not None and gain < LEVEL:  # where it levels off, measured (readings
            # 166-167: not at the nominal ratio, which the text had called the knee)
            return sentence(
                " Over whole runs (",
                Ref("fig", "pareto"),
                ", right), the mean ",
                M_SYM,
                " levels off: ",
                *eq(W_M, self.gridn("UC-EMDM", knee[1], "w_manip", fmt=".3g")),
                f" comes within {LEVEL:.0%} of the nominal mean with ",
                self.gridn("UC-EMDM", knee[1], "total_effort", fmt=".3g"),
                " instead of ",
                self.gridn("UC-EMDM", n, "total_effort", fmt=".3g", unit="rad²/s"),
                " of total effort",  # (reading 209: E is effort too)
                PageOnly(  # (reading 178 found it cryptic at the paper's length; room)
                    tuple(
                        sentence(
                            "; larger ratios ",
                            *more,
                            " its mean ",
                            M_SYM,
                            " for up to ",
                            self.gridn("UC-EMDM", dearest, "total_effort", fmt=".3g"),
                            " of total effort",
                        )
                    )
                ),
                ".",
            )
        return sentence(
            " Over whole runs (",
            Ref("fig", "pareto"),
            ", right)",
            *(
                (
                    " the mean ",
                    M_SYM,
                    " levels off at the nominal ratio. In runs that reach the goal,",
                )
                if gain < LEVEL
                else (", in runs that reach the goal,",)
            ),
            " larger ratios ",
            *more,
            " its mean ",
            M_SYM,
            " but raise its total effort from ",
            self.gridn("UC-EMDM", n, "total_effort", fmt=".3g"),
            " to ",
            self.gridn("UC-EMDM", dearest, "total_effort", fmt=".3g", unit="rad²/s"),
            ".",
        )

    def task1_solver(self) -> Section:
        t = "task1"
        sec = Section(
            "t1-solver", "Task 1: custom solver, fallback, convergence", level=2, brief="1.1"
        )
        fallbacks = self.mv(t, Name.UC_EMDM, "fallback_steps") + self.mv(
            t, Name.C_EMDM, "fallback_steps"
        )
        answer = sentence(  # (one fact per clause: a reader stalled on four parentheses)
            "Our custom active-set solver certified the optimum at all ",
            self.mt(t, Name.UC_EMDM, "steps", "d"),
            " UC-EMDM and all ",
            self.mt(t, Name.C_EMDM, "steps", "d"),
            " C-EMDM steps. Its largest relative KKT violations, ",
            self.mt(t, Name.UC_EMDM, "max_kkt_residual", ".2g"),
            " and ",
            self.mt(t, Name.C_EMDM, "max_kkt_residual", ".2g"),
            ", lie far below the ",
            Math(rf"10^{{{KKT_EXP}}}", f"10<sup>−{-KKT_EXP}</sup>"),
            " limit. The fallback",
            PageOnly(tuple(sentence(" (daqp, then quadprog)"))),  # (Section II names it)
            " ",
        )
        if fallbacks == 0:
            answer += sentence("never ran.")
        else:
            answer += sentence(
                "answered ",
                self.mt(t, Name.UC_EMDM, "fallback_steps", "d"),
                " and ",
                self.mt(t, Name.C_EMDM, "fallback_steps", "d"),
                " of those steps.",
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
            "Warm-started, the solver takes a median of ",
            self.ev(t, Name.C_EMDM, "solver", "median_iterations_warm", fmt=".4g"),
            " and at most ",
            self.ev(t, Name.C_EMDM, "solver", "max_iterations_warm", fmt="d"),
            " iterations per step.",
        )
        lab = SCALED_LAB
        ch: dict[str, Any] = {}
        if self.d.exists(lab):
            ch = self.d.value(lab, "challenges", "solvers")
        vertex = self.single_point_vertex()
        sampled = vertex is not None and "steps" in vertex
        if "median_iterations_scaled" in ch.get("active-set", {}):
            # (editor after readings 209, 210: the paradox flagged, then explained)
            p += sentence(
                " Scaled steps need ",
                self.d.num(
                    lab,
                    "challenges",
                    "solvers",
                    "active-set",
                    "median_iterations_scaled",
                    fmt=".0f",
                ),
                " iterations, yet they are Task 1's numerical challenge."
                if sampled
                else " iterations.",
            )
        elif sampled:
            p += sentence(" Task 1's numerical challenge is its scaled steps.")
        if vertex:  # measured: one point, and how degenerate
            low, high = vertex["active"]
            fixed = vertex["unknowns"] - vertex["task_rows"]  # the bounds a vertex needs
            p += sentence(
                # (the widest, rounded: a bound "<=" would understate it)
                # on how many scaled steps it was measured (reading 178: the lab's sample)
                *(
                    (  # the sample first (readings 197, 198: 11 beside 41 and 38 confused)
                        " Of ",
                        self.d.count(lab, "resolved_steps"),
                        # (not "evenly spaced", reading 209: step 1 is added to them)
                        " C-EMDM programs re-solved offline, the ",
                        self.d.num(lab, "challenges", "scaled_vertex", "steps", fmt="d"),
                        # ("up to", not "<=": the width is rounded, 246: 2.44e-15 under 2.4e-15)
                        " scaled ones allow only one command: their feasible set is up to ",
                    )
                    if "steps" in vertex
                    else (
                        " These are Task 1's challenge: only one command is feasible, the "
                        "feasible set up to ",
                    )
                ),
                self.d.num(
                    lab, "challenges", "scaled_vertex", "max_width", fmt=".1e", unit="rad/s"
                ),
                " wide. That point is degenerate: ",
                self.d.num(lab, "challenges", "scaled_vertex", "active", 0, fmt="d"),
                *(
                    ("–", self.d.num(lab, "challenges", "scaled_vertex", "active", 1, fmt="d"))
                    if high > low
                    else ()
                ),
                # (in words: readings 174-177 found "2 bounds hold it where 1 would" cryptic)
                f" speed bounds are active where {fixed} suffices, so active-set methods can cycle.",
            )
        rows = self.solvers("task1-lab-C-EMDM")
        lab1 = self.rec.labs.get("task1-lab-C-EMDM")
        notes = lab1.notes if lab1 else {}
        qp = rows.get("quadprog")
        if qp and qp.failures:  # the fallback's last resort (reading 142): on the page, as
            # it never ran in the loop (reading 149 asked for the room)
            declines = sentence(  # (offline: the loop's fallback never ran, reading 173)
                " The last fallback, quadprog, fails on ",
                self.sn("task1-lab-C-EMDM", "quadprog", "failures", "d"),
                " of the ",
                self.sn("task1-lab-C-EMDM", "quadprog", "resolved_steps", "d"),
                " programs",
            )
            if notes.get("quadprog", {}).get("failures_on_scaled_steps") == qp.failures:
                declines += sentence(", both scaled" if qp.failures == 2 else ", all scaled")
            declines += sentence(".")
            # (reading 150, 154: the fallback's behaviour is the brief's question; 182, 183
            # missed it while it was on the page only)
            p += declines
        p += sentence(
            " Otherwise, Task 1 is well conditioned (",
            COND_J,
            " ",
            Math(r"\leq", "≤"),
            " ",
            self.ev(t, Name.C_EMDM, "conditioning", "cond_J_max", fmt=".3g"),
            ") and has no slack.",
        )
        sec.paragraphs.append(p)
        return sec
