"""The paper's tables: closed-loop outcomes, solvers and evidence runs."""

from __future__ import annotations

from typing import Any, ClassVar, cast

from ....core.controllers import CONTROLLERS, Name
from ....core.terms import TermKind
from ..config import SLACK_POLICIES
from ..document import Section, Table
from ..trace import Eqs, Math, Num, Ref, Sentence, Text, Unit, Upright, render_latex, sentence
from .base import (
    DT,
    FINER_STEP,
    GRID_MISS,
    M_SYM,
    SUM_E,
    W_M,
    ablation_span,
    bare,
    eq,
    run_label,
)
from .claims import Claims
from .records import EvidenceKey, GridKey, MetricKey, RunOutcome

MISS_NOTE = Text("; miss: not reached")
STALL_NOTE = "stall: stopped short"
"""What "stall" means in Tables I and II (a run's record has a stall event)."""
"""Table II's caption names a miss only where the table has one."""


STALL, MISS = Text("stall"), Text("miss")
INDENT = Math(r"\quad", "\u2003")
"""Table II: an evidence run's row starts indented under the nominal run it changes."""


def unreached(stalled: bool) -> Sentence:
    """A run that does not reach the goal: ``stall`` where it came to rest short of it (its
    record's stall event), ``miss`` otherwise (or where no events are recorded)."""
    return [STALL if stalled else MISS]


class Tables(Claims):
    OUTCOME_COLUMNS: tuple[tuple[MetricKey, str], ...] = (
        ("mean_manipulability", ".3f"),
        ("total_effort", ".3f"),  # (223: the percentages checkable from the table)
        ("max_abs_qd", ".2f"),
        ("scaled_steps", "d"),
    )
    """Table I's outcome columns after the time to goal, with their formats."""

    # ------------------------------------------------------------------ tables
    BRIEF_TERMS: ClassVar[frozenset[TermKind]] = frozenset(
        {
            TermKind.TASK,
            TermKind.EFFORT,
            TermKind.MANIPULABILITY,
            TermKind.SLACK,
            TermKind.VELOCITY_BOX,
            TermKind.DAMPER,
        }
    )
    """The terms program (3) writes; any other a controller takes is named after it."""

    def term_cells(self, task: str, name: str) -> list[Sentence]:
        """What ``name``'s program on ``task`` sets in (3): w_E, w_M, the slack set D, and the
        box B with the task scale alpha*, read from the controller's terms as the code builds
        them on the task's arm (:meth:`~emdm.core.controllers.Controller.program_data`): a term
        the arm does not take (the slack of a redundant arm) or of zero weight is not in it.
        The controller's name first, with any term beyond (3)'s."""
        sc = self.rec.scenarios[task]
        ctrl = CONTROLLERS[name]
        kinds = [list(TermKind)[int(c)] for c in ctrl.program_data(sc).codes]
        effort = next(t for t in ctrl.terms if t.kind is TermKind.EFFORT)
        manip = next((t for t in ctrl.terms if t.kind is TermKind.MANIPULABILITY), None)

        def weight(w: str | float) -> Sentence:
            return sentence(
                self.scn(task, "weights", w, fmt="g") if isinstance(w, str) else f"{w:g}"
            )

        others = [k for k in kinds if k not in self.BRIEF_TERMS]
        scaled = ctrl.constrained and sc.controller.on_infeasible == "scale"
        boxed = TermKind.VELOCITY_BOX in kinds or TermKind.DAMPER in kinds
        return [
            sentence(name, "".join(f" + {k.value}" for k in others)),
            weight(effort.weight),
            weight(manip.weight)
            if manip is not None and TermKind.MANIPULABILITY in kinds
            else sentence("0"),
            sentence(
                Math(r"[\delta_{\min},\delta_{\max}]", "[δ<sub>min</sub>, δ<sub>max</sub>]")
                if TermKind.SLACK in kinds
                else Math(r"\{0\}", "{0}")
            ),
            sentence(
                "(", Eqs(("bounds",)), "), ", *(("(", Eqs(("scale",)), ")") if scaled else ("1",))
            )
            if boxed
            else sentence("none, 1"),
        ]

    def terms_table(self, sections: list[Section]) -> None:
        """Each controller's terms in the one program (3) they all solve (reading 220: no
        displayed program; 221, 222: then no per-controller view), from the controllers' terms
        on both tasks' arms: a cell that differs between the tasks gives both (T1, T2); the
        free slack's row where its runs were made."""
        table = Table(
            "programs",
            sentence(
                "Each controller's terms in (",
                Eqs(("qp",)),
                # (227, 232: the row read as every step's; 233: "T2's C-EMDM: at every step"
                # read as the nominal run's; in its free-slack run, its own slack is unbounded;
                # 235, 236: "own slack unbounded" cryptic; 237, 238: where it acts is the row's)
                "); T1, T2: Tasks 1, 2. Free slack: T2's C-EMDM uses it instead of ",
                Math("D", "<i>D</i>"),
                " at every step.",
            ),
            [
                sentence("ctrl."),
                sentence(Math("w_E", "<i>w</i><sub>E</sub>")),
                sentence(Math("w_M", "<i>w</i><sub>M</sub>")),
                sentence("slack set ", Math("D", "<i>D</i>")),
                sentence(Math("B", "<i>B</i>"), ", ", Math(r"\alpha^*", "α*")),
            ],
            align="lllll",
            font="scriptsize",
            colsep=3.0,
            placement="b",  # under the formulation's first column, beside what it sets
            # the paper writes each task's programs out instead (readings 221-242)
            html_only=True,
        )
        for name in (Name.UC_IVKC, Name.UC_EMDM, Name.C_IVKC, Name.C_EMDM):
            one, two = (self.term_cells(t, name) for t in ("task1", "task2"))
            row = [one[0]]
            for a, b in zip(one[1:], two[1:], strict=True):
                same = render_latex(a) == render_latex(b)
                row.append(a if same else sentence("T1: ", *a, "; T2: ", *b))
            table.rows.append(row)
        made = [k for k in SLACK_POLICIES.values() if k in self.rec.evidence]
        if made:  # its bound as the records have it (221, 224: "R^2" against their 10^3)
            table.rows.append(
                [
                    sentence("free slack"),
                    sentence("same"),
                    sentence("same"),
                    sentence(
                        Math(r"|\delta_i|\le{}", "|δ<sub>i</sub>| ≤ "),
                        self.d.num(
                            "data/evidence.json",
                            "runs",
                            made[0],
                            "overrides",
                            "slack.max",
                            0,
                            fmt=".0e",
                        ),
                        # (237, 238: simulated at every step from the caption alone)
                        " if ",
                        Math(r"\alpha^*<1", "α* &lt; 1"),
                    ),
                    sentence("(", Eqs(("bounds",)), "), 1"),
                ]
            )
        self.tables["programs"] = table
        for s in sections:
            if s.key == "formulation":
                s.tables.append("programs")

    def outcome_table(self, sections: list[Section]) -> None:
        """Table II: every closed-loop run of the study, each evidence run (A1-A6) and free-slack
        run indented under the nominal run it changes in one thing (readings 147-149: a separate
        evidence table repeated the nominal runs and was read twice); the pitch's backup keeps
        the nominal runs and the free-slack rows only (``outcomes-backup``)."""
        header = [
            sentence("run"),
            sentence("arrival"),  # (reading 204: "goal" read as a place, not a time)
            sentence("mean ", M_SYM),
            sentence(SUM_E),
            sentence("max ", Math(r"|\dot q|", "|<i>q̇</i>|")),
            sentence("scaled"),
        ]
        # a run that stalls reads "stall" (the text gives its distance); one that ends elsewhere
        # without arriving gives its final error
        missed = [
            (task, name)
            for task in ("task1", "task2")
            for name in (Name.UC_IVKC, Name.UC_EMDM, Name.C_IVKC, Name.C_EMDM)
            if not self.mv(task, name, "reached")
        ]
        drifted = [m for m in missed if not self.evv(*m, "stall")]

        indented = sentence(
            " Indented rows vary the nominal run above: ",
            Upright(ablation_span()),
            # (the free slack's terms are the programs table's last row)
            " test a cause; free slack (",
            Ref("sec", "formulation"),
            ") replaces scaling.",
        )
        if self.grid_miss() is not None:  # (readings 194, 195: their own A2a differed)
            indented += sentence(
                " ",
                Upright(run_label(GRID_MISS)),
                # (reading 197: "sensitive to rounding" was cryptic; 247: then do not print them)
                # (265, 266: "(-: digits that depend on rounding)" awkward)
                # (281: "diverges" overclaimed: it stays bounded, misses and never settles)
                " never settles, so its digits (–) depend on rounding.",
            )

        def caption(evidence: bool) -> Sentence:
            # (the arrival tolerance is the formulation's: "runs end at ||e|| < 1e-3 m")
            return sentence(
                "Closed-loop runs" if evidence else "Outcomes",
                ": arrival time (",
                Unit("s"),
                # (a stall is defined with the task scale, Section II, and again here: a reader
                # of the table alone met it undefined, reading 162)
                *(("; " + STALL_NOTE,) if len(drifted) < len(missed) else ()),
                *((MISS_NOTE,) if evidence and self.grid_miss() is not None else ()),
                ")",
                *((" or final error (m)",) if drifted else ()),
                ", mean ",
                M_SYM,
                " (",
                Unit("m²"),
                # what is averaged (reading 199: inferred to reproduce it)
                # (T, a run's last step, is Section II's: arrival or the time limit)
                ", over steps 0 to ",
                Math("T", "<i>T</i>"),
                "), effort (",
                Unit("rad²/s"),
                "), peak speed (",
                Unit("rad/s"),
                "), scaled steps.",
                *(indented if evidence else sentence()),
            )

        full = Table(
            "outcomes",
            caption(True),
            header,
            align="lrrrrr",
            font="scriptsize",
            colsep=3.0,
        )
        backup = Table("outcomes-backup", caption(False), header, align="lrrrrr")
        policy: dict[str, EvidenceKey] = {
            "task1": "t1-c-slack-policy",
            "task2": "t2-c-slack-policy",
        }
        evidence = self.evidence_rows()
        for task, title in (("task1", "Task 1 (three links)"), ("task2", "Task 2 (two links)")):
            for table in (full, backup):
                table.rows.append([sentence(title)])
            for name in (Name.UC_IVKC, Name.UC_EMDM, Name.C_IVKC, Name.C_EMDM):
                goal = (
                    sentence(bare(self.ttg(task, name)))
                    if self.mv(task, name, "reached")
                    else sentence("stall")
                    if self.evv(task, name, "stall")
                    else sentence("(", self.mt(task, name, "final_error", ".3f"), " m)")
                )
                row = [
                    sentence(name),
                    goal,
                    *(
                        sentence(self.mt(task, name, metric, fmt))
                        for metric, fmt in self.OUTCOME_COLUMNS
                    ),
                ]
                full.rows.append(row)
                backup.rows.append(row)
                full.rows.extend(evidence.get((task, name), []))
                if name not in (Name.C_IVKC, Name.C_EMDM):
                    continue
                # the constrained run again under the other infeasibility policy: a free slack
                key = policy[task]
                cells = [
                    sentence(bare(self.evid_goal(key, name)))
                    if self.evid(key, "runs", name)["reached"]
                    else sentence("stall"),
                    *(
                        sentence(self.evidn(key, "runs", name, metric, fmt=fmt))
                        for metric, fmt in self.OUTCOME_COLUMNS
                    ),
                ]
                full.rows.append([sentence(INDENT, "free slack"), *cells])
                backup.rows.append([sentence(name, ", free slack"), *cells])
        if not any(MISS in cell for row in full.rows for cell in row):  # none to explain
            full.caption = [seg for seg in full.caption if seg is not MISS_NOTE]
        self.tables["outcomes"] = full
        self.tables["outcomes-backup"] = backup
        for s in sections:
            if s.key == "task1":
                s.tables.append("outcomes")

    def evidence_rows(self) -> dict[tuple[str, str], list[list[Sentence]]]:
        """Table II's evidence rows in its columns, under the nominal run each one changes:
        ``{(task, controller): [row, ...]}``."""
        out: dict[tuple[str, str], list[list[Sentence]]] = {}
        for key, ctrl, change in self.evidence_items():
            entry = self.evid(key)
            run = entry["runs"].get(ctrl, {})
            label = sentence(INDENT, run_label(key), ": ", *change)
            rows = out.setdefault((entry["task"], ctrl), [])
            if "error" in run:
                rows.append([label, sentence("no solution"), *([sentence("–")] * 4)])
            else:
                goal = (
                    sentence(bare(self.evid_goal(key, ctrl)))
                    if run["reached"]
                    else unreached(bool(run.get("events", {}).get("stall")))
                )
                rows.append(
                    [
                        label,
                        goal,
                        *(
                            sentence(self.evidn(key, "runs", ctrl, metric, fmt=fmt))
                            for metric, fmt in self.OUTCOME_COLUMNS
                        ),
                    ]
                )
            if key == "t1-uc-no-manip":
                rows.extend(self.grid_outcome_rows())
        return out

    def grid_miss(self) -> int | None:
        """The index of the first run of Task 1's UC-EMDM weight grid that misses the goal."""
        runs = self.rec.grids.get(Name.UC_EMDM, [])
        return next((i for i, r in enumerate(runs) if not r.reached), None)

    def grid_outcome_rows(self) -> list[list[Sentence]]:
        """A2a and A2b in Table II's columns: the weight grid's first run that misses the goal,
        and the same weights at a five times smaller step."""
        i = self.grid_miss()
        if i is None:
            return []
        ctrl = Name.UC_EMDM
        w_m = sentence(*eq(W_M, self.gridn(ctrl, i, "w_manip", fmt=".4g")))

        def cells(*path: str) -> list[Sentence]:
            """The run's cells; ``path``: where in the grid run it is (``finer_dt``)."""

            def value(metric: str) -> Any:
                return self.grid(ctrl, i, *cast(tuple[GridKey], (*path, metric)))

            def num(metric: str, fmt: str) -> Num:
                return self.gridn(ctrl, i, *cast(tuple[GridKey], (*path, metric)), fmt=fmt)

            out = [sentence(num("time_to_goal", ".2f")) if value("reached") else unreached(False)]
            for metric, fmt in self.OUTCOME_COLUMNS:
                if not value("reached") and fmt != "d":
                    # a run that blew up: its digits depend on rounding (reading 177 got
                    # 10,674 where the record has 11,749; 235-248 got efforts of 1.09e4 to
                    # 1.26e4 and peaks of 49 to 125 rad/s), so none printed; the page's
                    # text gives the record's
                    out.append(sentence("–"))
                    continue
                big = fmt.endswith("f") and abs(value(metric)) >= 1e3  # 11749 read as 117.49
                out.append(sentence(num(metric, ",.0f" if big else fmt)))
            return out

        rows = [[sentence(INDENT, run_label(GRID_MISS), ": ", *w_m), *cells()]]
        finer = self.grid(ctrl, i, "finer_dt") or {}
        if "nominal" in finer:
            rows.append(
                [
                    sentence(
                        INDENT,
                        run_label(FINER_STEP),
                        ": ",
                        run_label(GRID_MISS),
                        " at ",
                        *self.e3_step(),
                    ),
                    *cells("finer_dt"),
                ]
            )
        return rows

    def e3_step(self) -> Sentence:
        """The finer-step run's time step, as its row writes it (``Δt/5``)."""
        runs = self.rec.grids.get("UC-EMDM", [])
        finer = next((r.finer_dt for r in runs if not r.reached and r.finer_dt), None)
        if not finer or "dt" not in finer:
            return sentence(DT)
        return sentence(DT, f"/{self.rec.scenarios['task1'].motion.dt / finer['dt']:.0f}")

    def grid_rows(self) -> list[list[Sentence]]:
        """The pitch's evidence table's two runs from the weight grid (Section III-B): its first
        setting that misses the goal, against the nominal run (A2a); the same weights at a five
        times smaller time step, against the nominal weights at that step (A2b)."""
        i = self.grid_miss()
        if i is None:
            return []
        runs = self.rec.grids["UC-EMDM"]
        ctrl = Name.UC_EMDM
        finer = runs[i].finer_dt or {}
        columns: tuple[tuple[RunOutcome, str], ...] = (
            ("time_to_goal", ".2f"),
            ("mean_manipulability", ".3f"),
            ("total_effort", ".3g"),
        )

        def stall(metric: RunOutcome, reached: Any) -> bool:
            return metric == "time_to_goal" and not reached

        def pair(new: Sentence, old: Sentence) -> Sentence:
            return new + sentence(" (") + old + sentence(")")

        def plain(fmt: str, metric: RunOutcome) -> str:
            """Whole numbers from 1000 on, their thousands marked (a power of ten does not fit
            the column; 11749 was read as a typo for 117.49)."""
            value = self.grid(ctrl, i, metric)
            return ",.0f" if fmt.endswith("g") and abs(value) >= 1e3 else fmt

        w_m = sentence(*eq(W_M, self.gridn(ctrl, i, "w_manip", fmt=".4g")))
        # the weight grid keeps no events: a run of it that does not arrive is a miss
        nominal = unreached(bool(self.evv("task1", ctrl, "stall")))
        miss = [
            pair(
                unreached(False)
                if stall(metric, runs[i].reached)
                # a run that blew up: no digits, as Table II (reading 198: the backup slide's
                # 11,749 claimed digits its caption calls unreliable; 247: none are)
                else sentence(self.gridn(ctrl, i, metric, fmt=plain(fmt, metric)))
                if runs[i].reached
                else sentence("–"),
                nominal
                if stall(metric, self.mv("task1", ctrl, "reached"))
                else sentence(self.mt("task1", ctrl, metric, fmt)),
            )
            for metric, fmt in columns
        ]
        out = [[sentence(run_label(GRID_MISS)), sentence("1, ", ctrl), w_m, *miss]]
        if "nominal" not in finer:
            return out
        cells = [
            pair(
                unreached(False)
                if stall(metric, finer.get("reached"))
                else sentence(self.gridn(ctrl, i, "finer_dt", metric, fmt=fmt)),
                unreached(False)
                if stall(metric, finer["nominal"].get("reached"))
                else sentence(self.gridn(ctrl, i, "finer_dt", "nominal", metric, fmt=fmt)),
            )
            for metric, fmt in columns
        ]
        change = w_m + sentence(" at ") + self.e3_step()
        return [*out, [sentence(run_label(FINER_STEP)), sentence("1, ", ctrl), change, *cells]]

    def evidence_items(self) -> list[tuple[EvidenceKey, str, Sentence]]:
        """The evidence runs A1, A3-A6: each one's record, the controller it changes and the
        change as its row says it (A2a and A2b come from the weight grid)."""
        return [
            ("t1-uc-no-manip", Name.UC_EMDM, self.weight_off("t1-uc-no-manip")),
            ("t2-c-ivkc-wide-limits", Name.C_IVKC, self.limits_widened()),
            ("t2-c-emdm-no-manip", Name.C_EMDM, self.weight_off("t2-c-emdm-no-manip")),
            (
                "t2-c-emdm-tight-slack",
                Name.C_EMDM,
                sentence(
                    Math(r"|\delta|\leq", "|δ| ≤ "),
                    self.override("t2-c-emdm-tight-slack", "slack.max", 0, fmt=".3g", unit="m/s"),
                ),
            ),
            ("t2-uc-emdm-no-manip", Name.UC_EMDM, self.weight_off("t2-uc-emdm-no-manip")),
        ]

    def evidence_table(self) -> None:
        """The pitch's backup slide of evidence runs, each beside its nominal run's outcomes
        (in the paper they are Table II's indented rows)."""
        items = self.evidence_items()
        table = Table(
            "evidence",
            sentence(
                "Evidence runs, each changing one thing in a nominal run (the nominal's "
                "outcomes in brackets; stall as in ",
                Ref("tab", "outcomes"),
                MISS_NOTE,
                "). ",
                Upright(run_label(GRID_MISS)),
                " is from ",
                Ref("fig", "pareto"),
                "'s sweep and never settles (–: digits that depend on rounding); for ",
                Upright(run_label(FINER_STEP)),
                ", the nominal weights at ",
                *self.e3_step(),
                ".",
            ),
            [
                sentence("run"),
                sentence("task, ctrl."),
                sentence("change"),
                sentence("goal (s)"),
                sentence("mean ", M_SYM),
                sentence(SUM_E),
            ],
            align="lllrrr",
            font="scriptsize",
            colsep=2.3,  # six columns of two numbers each at column width
        )
        for key, ctrl, change in items:
            entry = self.evid(key)
            task = entry["task"]
            run = entry["runs"].get(ctrl, {})
            cells: list[Sentence] = []
            columns: tuple[tuple[MetricKey, str], ...] = (
                ("time_to_goal", ".2f"),
                ("mean_manipulability", ".3f"),
                ("total_effort", ".2f"),
            )
            for metric, fmt in columns:
                if "error" in run:
                    cells.append(sentence("no solution"))
                    continue
                stall = metric == "time_to_goal"
                new = (
                    unreached(bool(run.get("events", {}).get("stall")))
                    if stall and not run["reached"]
                    else sentence(self.evidn(key, "runs", ctrl, metric, fmt=fmt))
                )
                old = (
                    unreached(bool(self.evv(task, ctrl, "stall")))
                    if stall and not self.mv(task, ctrl, "reached")
                    else sentence(self.mt(task, ctrl, metric, fmt))
                )
                cells.append(new + sentence(" (") + old + sentence(")"))
            table.rows.append(
                [
                    sentence(run_label(key)),
                    sentence("1" if task == "task1" else "2", ", ", ctrl),
                    change,
                    *cells,
                ]
            )
            if key == "t1-uc-no-manip":
                table.rows.extend(self.grid_rows())
        if not any(MISS in cell for row in table.rows for cell in row):  # none to explain
            table.caption = [seg for seg in table.caption if seg is not MISS_NOTE]
        self.tables["evidence"] = table
