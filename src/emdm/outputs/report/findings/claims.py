"""The claims the paper, the pitch and the page all make, each written once.

A claim the abstract, a section, the conclusion and a slide repeat is a method here: they call it
and put it into their own sentence, so its words and numbers cannot drift apart between them
(``tests/test_report.py`` finds each one in the paper and in the pitch).
"""

from __future__ import annotations

from ....core.controllers import Name
from ..config import PAIRS
from ..trace import Num, PageOnly, Ref, Sentence, sentence
from .base import M_SYM, VD, W_M, StoryBase, more_for_more, run_label
from .records import GRID_FILE, EvidenceKey, MetricKey

LEVEL = 0.01
"""Where the whole-run sweep's mean m has levelled off: within 1 % of the nominal run's."""


def listed(words: list[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    return ", ".join(words[:-1]) + (" and " if len(words) > 1 else "") + words[-1]


class Claims(StoryBase):
    def weight_advice(self, why: bool = True) -> Sentence:
        """``lower UC-EMDM's w_M from 5 to 1.52 for Task 1's goal: its mean m stays within 1% with
        13% less effort``:
        the whole-run sweep's recommendation (the conclusion's; the page's with it), or
        nothing where no smaller ratio comes within :data:`LEVEL` of the nominal mean m."""
        found = self.levels_off_at()
        if found is None:
            return []
        n, k = found
        f = GRID_FILE.format(ctrl=Name.UC_EMDM)
        return sentence(
            # UC-EMDM's: the sweep ran it alone (reading 185: "Task 1's" read as both pairs')
            "lower UC-EMDM's ",
            W_M,
            " from ",
            self.gridn("UC-EMDM", n, "w_manip", fmt=".3g"),
            " to ",
            self.gridn("UC-EMDM", k, "w_manip", fmt=".3g"),
            # for one start and goal, the sweep's (reading 200: advice from one case)
            " for Task 1's goal",
            *(
                sentence(
                    ": its mean ",
                    M_SYM,
                    f" stays within {LEVEL:.0%} with ",
                    self.d.cut((f, "runs", k, "total_effort"), (f, "runs", n, "total_effort")),
                    " less effort",
                )
                if why
                else []
            ),
        )

    def nominal_in_grid(self) -> int | None:
        """The index of the nominal weights' run in Task 1's whole-run sweep (None: not run)."""
        w = self.rec.scenarios["task1"].weights
        grid = self.rec.grids.get("UC-EMDM", [])
        return next(
            (
                i
                for i, r in enumerate(grid)
                if (r.w_manip, r.w_effort) == (w.manipulability, w.effort)
            ),
            None,
        )

    def beyond_nominal(self) -> tuple[int, int, int] | None:
        """Task 1's whole-run sweep beyond the nominal weight ratio: the nominal run's index,
        the arriving larger ratio with the highest mean m and the one with the most effort
        (None: no nominal run, none larger arrives, or none spends more)."""
        grid = self.rec.grids.get("UC-EMDM", [])
        n = self.nominal_in_grid()
        if n is None:
            return None
        ratio = grid[n].w_manip / grid[n].w_effort
        above = [i for i, r in enumerate(grid) if r.reached and r.w_manip / r.w_effort > ratio]
        if not above:
            return None
        best = max(above, key=lambda i: grid[i].mean_manipulability)
        dearest = max(above, key=lambda i: grid[i].total_effort)
        if grid[dearest].total_effort <= grid[n].total_effort:
            return None
        return n, best, dearest

    def levels_off_at(self) -> tuple[int, int] | None:
        """Where Task 1's whole-run sweep levels off: the nominal run's index and the smallest
        weight ratio's whose run reaches the goal with a mean m within :data:`LEVEL` of the
        nominal's, when that ratio is smaller and spends less (readings 166-167: the nominal
        ratio, called the knee, lies past it). None otherwise."""
        grid = self.rec.grids.get("UC-EMDM", [])
        n = self.nominal_in_grid()
        if n is None:
            return None
        floor = (1.0 - LEVEL) * grid[n].mean_manipulability
        near = [i for i, r in enumerate(grid) if r.reached and r.mean_manipulability >= floor]
        if not near:  # (the nominal run itself missed the goal)
            return None
        k = min(near, key=lambda i: grid[i].w_manip / grid[i].w_effort)
        cheaper = grid[k].total_effort < grid[n].total_effort
        return (n, k) if k != n and cheaper else None

    def dexterity_gain(self, named: bool = True) -> Sentence:
        """Task 1: what EMDM buys over IVKC, without and with limits (its answer in numbers):
        ``raises the mean manipulability m by 17% for 25% more effort without joint limits,
        and by 22% for 26% more with them`` where every change is a rise (readings 190, 191:
        "+17% ... for +25% effort, and +22% for +26%" was four signed numbers in a row).
        ``named=False``: ``the mean m``, where m was just named (the abstract: its room)."""
        what = "manipulability " if named else ""
        t1 = "task1"
        pairs = ((Name.UC_EMDM, Name.UC_IVKC), (Name.C_EMDM, Name.C_IVKC))
        keys: tuple[MetricKey, MetricKey] = ("mean_manipulability", "total_effort")
        rises = all(self.mv(t1, a, k) > self.mv(t1, b, k) for a, b in pairs for k in keys)
        if not rises:  # each change with its sign, each gain beside its cost
            return sentence(
                "buys ",
                self.pct(t1, *pairs[0], keys[0]),
                " mean ",
                what,
                M_SYM,
                " for ",
                self.pct(t1, *pairs[0], keys[1]),
                " effort, and ",
                self.pct(t1, *pairs[1], keys[0]),
                " for ",
                self.pct(t1, *pairs[1], keys[1]),
                " with joint limits",
            )
        return sentence(
            "raises the mean ",
            what,
            M_SYM,
            " by ",
            self.pct(t1, *pairs[0], keys[0], fmt=".0f"),
            " for ",
            self.pct(t1, *pairs[0], keys[1], fmt=".0f"),
            " more effort without joint limits, and by ",
            self.pct(t1, *pairs[1], keys[0], fmt=".0f"),
            " for ",
            self.pct(t1, *pairs[1], keys[1], fmt=".0f"),
            " more with them",
        )

    def pair_rises(self, task: str, group: str) -> bool:
        """Whether a task's EMDM has both more mean manipulability and more effort than its
        IVKC (group ``UC`` or ``C``): what :meth:`pair_trade` says as a trade."""
        ivkc, emdm = PAIRS[group]
        keys: tuple[MetricKey, MetricKey] = ("mean_manipulability", "total_effort")
        return all(self.mv(task, emdm, k) > self.mv(task, ivkc, k) for k in keys)

    def pair_trade(self, task: str, group: str) -> Sentence:
        """What a task's EMDM buys over its IVKC (group ``UC`` or ``C``): ``raises the mean
        manipulability by 17% for 25% more effort`` where both rise, else each change signed
        (Sections III-A and III-C: the means themselves are Table II's)."""
        ivkc, emdm = PAIRS[group]
        keys: tuple[MetricKey, MetricKey] = ("mean_manipulability", "total_effort")
        if self.pair_rises(task, group):
            return sentence(
                "raises the mean manipulability by ",
                self.pct(task, emdm, ivkc, keys[0], fmt=".0f"),
                " for ",
                self.pct(task, emdm, ivkc, keys[1], fmt=".0f"),
                " more effort",
            )
        return sentence(
            "changes the mean manipulability by ",
            self.pct(task, emdm, ivkc, keys[0]),
            " and the effort by ",
            self.pct(task, emdm, ivkc, keys[1]),
        )

    def mean_m_pair(self, task: str) -> Sentence:
        """The constrained pair's mean m side by side: ``0.300 against 0.246 m² (+22%)``."""
        return sentence(
            self.mt(task, Name.C_EMDM, "mean_manipulability", ".3f"),
            " against ",
            self.mt(task, Name.C_IVKC, "mean_manipulability", ".3f", "m²"),
            " (",
            self.pct(task, Name.C_EMDM, Name.C_IVKC, "mean_manipulability"),
            ")",
        )

    def ivkc_with_slack(self, label: bool = True, defined: bool = False) -> Sentence:
        """The like-for-like Task 2 comparison: C-IVKC given a free slack instead of scaling
        (empty when that run did not arrive; ``label``: cite Table I, where its row is;
        ``defined``: say what a free slack is, for a reader without Section II)."""
        key: EvidenceKey = "t2-c-slack-policy"
        if not self.evid(key, "runs", Name.C_IVKC).get("reached"):
            return []
        return sentence(  # free: unbounded (Section II), as C-EMDM's is in the same run
            # (said in one line of a slide: what "free" means, and what it replaces)
            "with an unbounded slack instead of task scaling" if defined else "with a free slack",
            ", C-IVKC arrives in ",
            self.evid_goal(key, Name.C_IVKC),
            *((" (", Ref("tab", "outcomes"), ")") if label else ()),
        )

    def ivkc_first_with_slack(self) -> bool:
        """With a free slack each, C-IVKC arrives before C-EMDM."""
        key: EvidenceKey = "t2-c-slack-policy"
        i, e = (self.evid(key, "runs", c) for c in (Name.C_IVKC, Name.C_EMDM))
        if not i.get("reached"):
            return False
        return not e.get("reached") or i["time_to_goal"] < e["time_to_goal"]

    def slack_race(self, ivkc: str, emdm: str, times: bool = False) -> Sentence:
        """``both arrive: C-IVKC sooner and with a higher mean m``: Task 2's constrained
        pair given a free slack each (the controllers named ``ivkc`` and ``emdm``: the abstract
        says IVKC and EMDM). Who arrives, who first, whose mean m is higher (readings 209, 210:
        one clause each); ``times``: the arrival times after "sooner", on the page only."""
        key: EvidenceKey = "t2-c-slack-policy"
        runs = {c: self.evid(key, "runs", c) for c in (Name.C_IVKC, Name.C_EMDM)}
        named = {Name.C_IVKC: ivkc, Name.C_EMDM: emdm}
        if not runs[Name.C_IVKC].get("reached"):
            return []
        if not runs[Name.C_EMDM].get("reached"):
            return sentence(
                f"{ivkc} arrives", *((" in ", self.evid_goal(key, Name.C_IVKC)) if times else ())
            )
        first = Name.C_IVKC if self.ivkc_first_with_slack() else Name.C_EMDM
        other = Name.C_EMDM if first == Name.C_IVKC else Name.C_IVKC
        # (readings 219, 220: one clause, the verb said once)
        # (235, 236: a colon, not a run of commas)
        told = sentence(f"both arrive: {named[first]} sooner")
        if times:
            told += sentence(
                PageOnly(
                    tuple(
                        sentence(
                            " (",
                            self.evid_goal(key, first),
                            " against ",
                            self.evid_goal(key, other),
                            ")",
                        )
                    )
                )
            )
        m = {c: r.get("mean_manipulability", 0.0) for c, r in runs.items()}
        if m[first] > m[other]:
            told += sentence(" and with a higher mean ", M_SYM)
        elif m[other] > m[first]:
            told += sentence(f", {named[other]} with a higher mean ", M_SYM)
        return told

    def solver_verdict(self) -> Sentence:
        """``Offline, gradient-based slsqp is exact and faster than every gradient-free method.``:
        Task 2.1's answer in one sentence (readings 218, 236: the conclusion had none), said
        only while Table III holds it: the fastest exact gradient-based method beats every
        gradient-free one in median time, all of them run from Python (238: not the compiled
        QP methods, whose times are not like for like)."""
        rows = self.solvers("task2-lab-C-EMDM")
        grad = self.best(rows, "gradient")
        free = [r for r in rows.values() if r.family == "gradient-free"]
        if not (grad and free):
            return []
        t = rows[grad].median_time
        if not all(r.median_time > t for r in free):
            return []
        # ("offline": Table III's programs; 249: in the loop its KKT residual reaches 2.4e-6)
        return sentence(
            "Offline, gradient-based ",
            grad,
            " is exact and faster than every gradient-free method. ",
        )

    def emdm_without_term(self, label: bool = True, when: bool = True) -> Sentence:
        """Task 2's C-EMDM without the dexterity term (empty unless it arrives sooner); its
        arrival time on the page only unless ``when`` (the paper's is Table II's)."""
        key: EvidenceKey = "t2-c-emdm-no-manip"
        run = self.evid(key, "runs", Name.C_EMDM)
        if not run.get("reached") or run["time_to_goal"] >= self.mv(
            "task2", Name.C_EMDM, "time_to_goal"
        ):
            return []
        return sentence(  # (the run's label first: "A4: ..." read as a noun, reading 142's edit)
            "without the dexterity term",
            *((" (", run_label(key), ")") if label else ()),
            ", C-EMDM arrives sooner",
            *(
                sentence(", in ", self.evid_goal(key, Name.C_EMDM))
                if when
                else (PageOnly(tuple(sentence(", in ", self.evid_goal(key, Name.C_EMDM)))),)
            ),
        )

    def slack_gains(self) -> list[str]:
        """What Task 1's C-EMDM gains with a free slack instead of task scaling: ``faster``,
        ``cheaper``, ``more dexterous``, those that hold."""
        adjectives = {
            "time_to_goal": "faster",
            "total_effort": "cheaper",
            "mean_manipulability": "more dexterous",
        }
        return [adjectives[m] for m, better in self._policy_terms() if better]

    def slack_better_on_all(self) -> bool:
        """Task 1's C-EMDM with a free slack beats task scaling on every outcome weighed (time,
        effort, mean m): scaling's only gain is then its straighter path."""
        return all(better for _, better in self._policy_terms())

    def uc_slack_saving(self) -> Sentence:
        """Task 2.2: what UC-EMDM's slack does against UC-IVKC (its peak joint speed is Table
        I's)."""
        t, ivkc, emdm = "task2", Name.UC_IVKC, Name.UC_EMDM
        f = f"data/{t}/metrics.json"
        miss = sentence(
            " slack lets the tip miss ",
            VD,
            " by up to ",
            self.ev(t, emdm, "slack", "max", fmt=".2f", unit="m/s"),
        )
        # the result first, then what the slack does (a plain-language edit; said alike in the
        # paper and the talk: reading 194 found slide 11's too dense)
        if self.mv(t, emdm, "total_effort") < self.mv(t, ivkc, "total_effort") and self.mv(
            t, emdm, "mean_manipulability"
        ) > self.mv(t, ivkc, "mean_manipulability"):
            return sentence(  # the pair's difference is UC-EMDM's, slack and term together
                "UC-EMDM uses ",
                self.d.cut(
                    (f, "controllers", emdm, "total_effort"),
                    (f, "controllers", ivkc, "total_effort"),
                ),
                " less effort than UC-IVKC and gains ",
                self.pct(t, emdm, ivkc, "mean_manipulability", fmt=".0f"),
                " mean ",
                M_SYM,
                ": its",
                *miss,
            )
        return sentence("UC-EMDM's", *miss) + sentence(
            ": against UC-IVKC, ",
            self.pct(t, emdm, ivkc, "total_effort"),
            " effort and ",
            self.pct(t, emdm, ivkc, "mean_manipulability"),
            " mean ",
            M_SYM,
        )

    def uc_term_gain(self, fmt: str = "+.0f") -> Num:
        """``+1%``: Task 2.2's UC-EMDM mean m against its run without the dexterity term, the
        term's share of its gain in m (the abstract's and Section IV-C's number)."""
        emdm = Name.UC_EMDM
        return self.d.pct(
            ("data/task2/metrics.json", "controllers", emdm, "mean_manipulability"),
            (
                "data/evidence.json",
                "runs",
                "t2-uc-emdm-no-manip",
                "runs",
                emdm,
                "mean_manipulability",
            ),
            fmt,
        )

    def uc_term_trade(self) -> Sentence:
        """``1% more mean m for 21% more effort``: what Task 2.2's dexterity term buys and what
        it costs (UC-EMDM against its run without the term), unsigned where both rise; said
        alike by the abstract, Section IV-C and the talk."""
        gain, cost = self.uc_term_gain(), self.uc_term_cost()
        if gain.text.startswith("+") and cost.text.startswith("+"):
            return more_for_more(self.uc_term_gain(".0f"), self.uc_term_cost(".0f"))
        return sentence(gain, " mean ", M_SYM, " for ", cost, " effort")

    def _no_term(self, key: str) -> tuple[str, ...]:
        """Where Task 2.2's UC-EMDM run without the dexterity term keeps outcome ``key``."""
        return ("data/evidence.json", "runs", "t2-uc-emdm-no-manip", "runs", Name.UC_EMDM, key)

    def uc_term_cost(self, fmt: str = "+.0f") -> Num:
        """``+21%``: what Task 2.2's dexterity term costs in effort (UC-EMDM against its run
        without the term), the price of its ``uc_term_gain`` in m."""
        return self.d.pct(
            ("data/task2/metrics.json", "controllers", Name.UC_EMDM, "total_effort"),
            self._no_term("total_effort"),
            fmt,
        )

    def uc_term_raises_m(self) -> bool:
        """Task 2.2: UC-EMDM without the dexterity term (an evidence run) still saves effort
        against UC-IVKC but has a mean m nearer UC-IVKC's than UC-EMDM's: the slack makes the
        saving, the term the gain in m."""
        t, ivkc, emdm = "task2", Name.UC_IVKC, Name.UC_EMDM
        run = self.evid("t2-uc-emdm-no-manip", "runs", emdm)
        if not run.get("reached"):
            return False
        m_i, m_e = (self.mv(t, c, "mean_manipulability") for c in (ivkc, emdm))
        saves = run["total_effort"] < self.mv(t, ivkc, "total_effort")
        return bool(saves and abs(run["mean_manipulability"] - m_i) < abs(m_e - m_i) / 2)
