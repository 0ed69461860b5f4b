"""Many goals: whether the one-goal answers hold from other starts to other goals
(``data/many-goals.json``, :func:`emdm.studies.goals.policy_study`)."""

from __future__ import annotations

from typing import Any

from ....core.controllers import Name
from ..config import MANY_GOALS, PAIRS
from ..document import Table
from ..trace import Math, Num, PageOnly, Sentence, Text, sentence, traced
from .base import M_SYM
from .claims import Claims


class Goals(Claims):
    def goal(self, *path: str | int) -> Any:
        """The value at ``path`` of the many-goals record (``tasks/task1/...``)."""
        return self.d.value(MANY_GOALS, *path)

    def goaln(self, *path: str | int, fmt: str = "d", unit: str = "") -> Num:
        return traced(self.goal(*path), MANY_GOALS, path, fmt, unit)

    def arrivals(self, task: str, policy: str, ctrl: str) -> Num:
        return self.goaln("tasks", task, "policies", policy, "controllers", ctrl, "arrived")

    def weight_row(self) -> int | None:
        """The many-goals row of the weights the conclusion recommends (:meth:`levels_off_at`)."""
        found = self.levels_off_at()
        if found is None or self.rec.goals is None:
            return None
        w_m = self.rec.grids["UC-EMDM"][found[1]].w_manip
        rows = self.rec.goals.tasks["task1"].weights
        return next((i for i, r in enumerate(rows) if abs(r.w_manip - w_m) <= 1e-12), None)

    def has_goals(self) -> bool:
        return self.rec.goals is not None and {"task1", "task2"} <= set(self.rec.goals.tasks)

    def goals_gain(self) -> Sentence:
        """``on 256 random start-goal pairs (...), UC-EMDM has the higher mean m in 254 runs
        (median +11%) for +57% effort``: Task 1's pair over the many goals (nothing without
        them)."""
        if not self.has_goals():
            return []
        uc1 = ("tasks", "task1", "policies", "scale", "pairs", "UC")
        return sentence(
            "on ",
            self.goaln("runs"),
            " random start-goal pairs (uniform in joint space, seed ",
            self.goaln("seed"),
            "), UC-EMDM has the higher mean ",
            M_SYM,
            " in ",
            self.goaln(*uc1, "higher_mean_manipulability"),
            " runs (median ",
            self.goaln(*uc1, "mean_manipulability", 1, fmt="+.0%"),
            ") for ",
            self.goaln(*uc1, "total_effort", 1, fmt="+.0%"),
            " effort",
        )

    def goals_policy(self) -> Sentence:
        """`` and on more random goals (217 against 146 C-IVKC runs in Task 1, 216 against 143
        in Task 2)``: how many of the many goals C-IVKC reaches with a free slack and scaled (C-EMDM's
        on the page); nothing where the slack does not bring more in both tasks."""
        if not self.has_goals():
            return []
        more = all(
            self.goal("tasks", t, "policies", "slack", "controllers", Name.C_IVKC, "arrived")
            > self.goal("tasks", t, "policies", "scale", "controllers", Name.C_IVKC, "arrived")
            for t in ("task1", "task2")
        )
        if not more:
            return []
        return sentence(
            " and on more random goals (",
            self.arrivals("task1", "slack", Name.C_IVKC),
            " against ",
            self.arrivals("task1", "scale", Name.C_IVKC),
            " C-IVKC runs in Task 1, ",
            self.arrivals("task2", "slack", Name.C_IVKC),
            " against ",
            self.arrivals("task2", "scale", Name.C_IVKC),
            " in Task 2",
            PageOnly(
                tuple(
                    sentence(
                        "; C-EMDM: ",
                        self.arrivals("task1", "slack", Name.C_EMDM),
                        " against ",
                        self.arrivals("task1", "scale", Name.C_EMDM),
                        ", and ",
                        self.arrivals("task2", "slack", Name.C_EMDM),
                        " against ",
                        self.arrivals("task2", "scale", Name.C_EMDM),
                    )
                )
            ),
            ")",
        )

    def goals_weight(self) -> Sentence:
        """``(over the random goals, -1.7% for -27%)``: the recommended weights against the
        nominal ones, run by run over the many goals (medians)."""
        k = self.weight_row()
        if k is None:
            return []
        row = ("tasks", "task1", "weights", k)
        return sentence(
            " (random goals, medians: ",
            self.goaln(*row, "mean_manipulability", 1, fmt="+.1%"),
            " for ",
            self.goaln(*row, "total_effort", 1, fmt="+.0%"),
            ")",
        )

    def beyond_reach(self) -> Sentence:
        """Task 2's UC-EMDM misses, when it misses exactly the goals beyond some distance: why
        (its slack's pull at rest does not grow as the error shrinks)."""
        if not self.has_goals():
            return []
        row = self.rec.goals.tasks["task2"].policies["scale"] if self.rec.goals else None
        uc = row.controllers.get(Name.UC_EMDM) if row else None
        missed = uc.missed if uc else None
        if missed is None or missed.arrived_goal_radius_max is None:
            return []
        if missed.goal_radius[0] <= missed.arrived_goal_radius_max:
            return []  # no distance separates its misses from its arrivals
        # the distance as printed must separate them too: above every arrival, at most the
        # nearest miss (0.880 between 0.8793 and 0.8805), with more digits where needed
        low, high = missed.arrived_goal_radius_max, missed.goal_radius[0]
        digits = next(
            d for d in range(3, 18) if low < float(format(high, f".{d}f")) <= high or d == 17
        )
        where = ("tasks", "task2", "policies", "scale", "controllers", Name.UC_EMDM)
        return sentence(
            "In Task 2 UC-EMDM misses the ",
            self.goaln(*where, "missed", "count"),
            " random goals beyond ",
            self.goaln(*where, "missed", "goal_radius", 0, fmt=f".{digits}f", unit="m"),
            " (reach ",
            self.goaln("tasks", "task2", "reach", fmt=".2g", unit="m"),
            "): at rest its slack pulls with ",
            Math(r"w_S\|\delta\|=c_S", "<i>w</i><sub>S</sub>‖<i>δ</i>‖ = <i>c</i><sub>S</sub>"),
            " however small ",
            Math(r"\|e\|", "‖<i>e</i>‖"),
            ", and near the reach the dexterity term outweighs it, holding the tip ",
            self.goaln(*where, "missed", "final_error", 0, fmt=".2g"),
            " to ",
            self.goaln(*where, "missed", "final_error", 1, fmt=".2g", unit="m"),
            " short",
            PageOnly(
                (
                    Text(" ("),
                    Math("|q_2|", "|<i>q</i><sub>2</sub>|"),
                    Text(" = "),
                    self.goaln(*where, "missed", "rest_last_joint", 0, fmt=".3f"),
                    Text(" to "),
                    self.goaln(*where, "missed", "rest_last_joint", 1, fmt=".3f", unit="rad"),
                    Text(" at rest)"),
                )
            ),
            ". ",
        )

    def goals_table(self) -> None:
        """The pitch's backup slide of the many goals: each controller's arrivals, scaled and
        with a free slack, and each EMDM against its IVKC run by run (medians, quartiles)."""
        rec = self.rec.goals
        if rec is None or not self.has_goals():
            return
        table = Table(
            "many-goals",
            sentence(
                "Many goals: ",
                self.goaln("runs"),
                " random start-goal pairs per task (joint angles uniform within the limits, seed ",
                self.goaln("seed"),
                "). Arrivals scaled and with a free slack; EMDM against IVKC on the runs both "
                "reach: median (quartiles).",
            ),
            [
                sentence("task, ctrl."),
                sentence("arrive"),
                sentence("free slack"),
                sentence("mean ", M_SYM),
                sentence("effort"),
            ],
            align="lrrrr",
            font="scriptsize",
            html_only=True,
        )
        order = [str(c) for pair in PAIRS.values() for c in pair]  # each pair together
        for task, entry in rec.tasks.items():
            for ctrl in sorted(entry.policies["scale"].controllers, key=order.index):
                here = ("tasks", task, "policies")
                slack = entry.policies.get("slack")
                group = ctrl.split("-")[0]
                pair = entry.policies["scale"].pairs.get(group)
                emdm = ctrl.endswith("EMDM") and pair is not None and pair.both_arrived > 0
                cells = [
                    sentence(task[-1], ", ", ctrl),
                    sentence(self.arrivals(task, "scale", ctrl)),
                    sentence(self.arrivals(task, "slack", ctrl))
                    if slack and ctrl in slack.controllers
                    else sentence("–"),
                ]
                for key in ("mean_manipulability", "total_effort"):
                    where = (*here, "scale", "pairs", group, key)
                    spread = self.goal(*where) if emdm else None
                    # a decimal where the quartiles are small (+0.2%, not +0%)
                    fmt = "+.1%" if spread and max(map(abs, spread)) < 0.1 else "+.0%"
                    cells.append(
                        sentence(
                            self.goaln(*where, 1, fmt=fmt),
                            " (",
                            self.goaln(*where, 0, fmt=fmt),
                            ", ",
                            self.goaln(*where, 2, fmt=fmt),
                            ")",
                        )
                        if emdm
                        else sentence("")
                    )
                table.rows.append(cells)
        self.tables["many-goals"] = table
