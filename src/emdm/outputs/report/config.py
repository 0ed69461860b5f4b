"""What the report runs: the full and the quick study, the controller pairs, the evidence runs."""

from __future__ import annotations

import tomllib
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ...core.controllers import Name
from ...core.loading import load_scenario
from ...core.scenario import Scenario
from ...errors import ScenarioError


@dataclass(frozen=True)
class ReportConfig:
    """How much of each experiment the report runs."""

    quick: bool
    lab_solvers: tuple[str, ...]
    lab_sample: int
    lab_budget: int
    lab_repeats: int
    fallback_solvers: tuple[str, ...]
    pareto_per_decade: int
    grid: int
    animation_seconds: float
    mp4: bool
    compile: bool = True
    mmc_trials: int = 500
    animation_fps: float = 20.0
    """The animations' highest frame rate (the quick preview draws half the frames)."""
    goal_runs: int = 256
    """Random starts and goals per task of the many-goals study (``data/many-goals.json``)."""


STUDY_SOLVERS = (
    "active-set",
    "daqp",
    "admm",
    "slsqp",
    "slsqp-reduced",
    "nelder-mead",
    "cobyla",
    "cma-es",
)
"""The study's solver comparison (Task 2.1, Table III): one or two of each kind, the ones its
answer speaks of. Exact QP: ours (active set, certified) and the compiled peer (daqp, the
fallback); first-order: ADMM; gradient-based: slsqp, and slsqp on the gradient-free methods'
reduced program (the control that separates the method from the formulation); gradient-free:
a simplex (nelder-mead, the bounds as a penalty), a model-based method taking the constraints
(cobyla) and an evolution strategy (cma-es, seeded). The fourteen of ``emdm lab`` made a
table readers found too dense for four pages (readings 138-141)."""

FULL = ReportConfig(
    quick=False,
    lab_solvers=STUDY_SOLVERS,
    lab_sample=40,
    lab_budget=600,
    lab_repeats=3,
    # Task 1's lab: the chain's solvers and those of Table III the answer names (Fig. 6's
    # Task 1 panel draws them: each has its glyph in that table)
    fallback_solvers=("active-set", "admm", "daqp", "quadprog", "slsqp"),
    pareto_per_decade=4,
    grid=13,
    animation_seconds=10.0,
    mp4=True,
)
QUICK = ReportConfig(
    quick=True,
    lab_solvers=("active-set", "interior-point", "daqp", "slsqp", "nelder-mead", "powell"),
    lab_sample=8,
    lab_budget=150,
    lab_repeats=1,
    fallback_solvers=("active-set", "daqp", "quadprog"),
    pareto_per_decade=1,
    grid=4,
    animation_seconds=4.0,
    mp4=False,
    mmc_trials=20,
    animation_fps=10.0,
    goal_runs=64,
)

GLYPHS = "figures/glyphs"
"""Under ``paper/``: each solver's line and marker in the convergence figure, drawn beside its
name in the solver table (the figure's legend)."""

BYLINE = "data/byline.json"
"""The authors and title given to ``emdm report`` (:func:`byline`), read by the paper, the pitch
and the page."""
LONGEST_NAME, LONGEST_TITLE = 120, 200


def check_text(what: str, text: str, longest: int) -> str:
    """``text`` stripped, or a ValueError naming ``what``: empty, longer than ``longest``
    characters, or holding a control character (a newline would break the title page)."""
    clean = text.strip()
    if not clean:
        raise ValueError(f"{what} must not be empty")
    if len(clean) > longest:
        raise ValueError(f"{what} must be at most {longest} characters, got {len(clean)}")
    if not clean.isprintable():
        raise ValueError(f"{what} must be one line of printable characters")
    return clean


def byline(authors: Sequence[str] = (), title: str | None = None) -> dict[str, Any]:
    """The record behind the title page: ``authors`` in order (at most 20) and an optional
    ``title`` replacing the study's own, each checked by :func:`check_text`."""
    if isinstance(authors, str) or len(authors) > 20:
        raise ValueError("authors must be a list of at most 20 names")
    out: dict[str, Any] = {
        "authors": [check_text("an author's name", a, LONGEST_NAME) for a in authors]
    }
    if title is not None:
        out["title"] = check_text("the title", title, LONGEST_TITLE)
    return out


def read_byline(path: str | Path) -> dict[str, Any]:
    """The byline of a TOML file with the keys ``authors`` (a list of names, in order) and
    ``title`` (optional), as in::

        authors = ["Ada Lovelace", "Alan Turing"]
        title = "Dexterity at a price"

    Raises :class:`~emdm.errors.ScenarioError` (one line naming the file and the key) when the
    file cannot be read or parsed, holds another key, or a value is not what :func:`byline`
    accepts."""
    source = str(path)
    try:
        data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as exc:
        raise ScenarioError(source, "", f"cannot be read: {exc}") from None
    except (ValueError, RecursionError) as exc:  # TOMLDecodeError, or nested too deeply
        raise ScenarioError(source, "", f"not a valid TOML file: {exc}") from None
    unknown = sorted(set(data) - {"authors", "title"})
    if unknown:
        raise ScenarioError(source, unknown[0], "unknown key (the keys are authors and title)")
    authors, title = data.get("authors", []), data.get("title")
    if not isinstance(authors, list) or not all(isinstance(a, str) for a in authors):
        raise ScenarioError(source, "authors", "must be a list of names (strings)")
    if title is not None and not isinstance(title, str):
        raise ScenarioError(source, "title", "must be a string")
    try:
        return byline(authors, title)
    except ValueError as exc:
        key = "title" if str(exc).startswith("the title") else "authors"
        raise ScenarioError(source, key, str(exc)) from None


TASKS = ("task1", "task2")
PAIRS = {"UC": (Name.UC_IVKC, Name.UC_EMDM), "C": (Name.C_IVKC, Name.C_EMDM)}
"""Each pair as (IVKC, EMDM): the brief compares them pair by pair."""

FOURTH_PANEL: dict[str, str | None] = {"task1": None, "task2": "gap"}
"""Each task's fourth panel in its pair figures: Task 2's tracking gap (its slack at work);
Task 1's tip paths are drawn in the plane with the arms (``task1-arms``: readings 144-147
missed an x-y view and the arms, readings 140, 141, 148 and 149 found a fourth panel too small)."""


@dataclass(frozen=True)
class Evidence:
    """A run that isolates the cause of something the report claims.

    ``controllers`` run on ``task`` with ``overrides``; with ``reference`` the first of them is
    compared command by command with that controller's nominal run; with two controllers the pair
    is compared (the steps on which they coincide).
    """

    key: str
    task: str
    controllers: tuple[str, ...]
    overrides: dict[str, Any] = field(default_factory=dict)
    reference: str | None = None
    like_for_like_slack: bool = False
    """IVKC's slack weight ``c_S / w_E``: IVKC's effort has weight 1 and EMDM's ``w_E``, so with
    the same ``c_S`` IVKC's slack would cost ``w_E`` times less against its effort than EMDM's."""

    def controller_overrides(self, name: str) -> dict[str, Any]:
        """What ``name`` runs with besides :attr:`overrides` (its like-for-like slack weight)."""
        if not (self.like_for_like_slack and name in (Name.UC_IVKC, Name.C_IVKC)):
            return {}
        weights = load_scenario(self.task, self.overrides).weights
        return {"weights.slack": weights.slack / weights.effort}

    def scenario(self, name: str) -> Scenario:
        """The scenario ``name`` runs in this evidence run: the task with :attr:`overrides`
        and its own (:meth:`controller_overrides`)."""
        return load_scenario(self.task, {**self.overrides, **self.controller_overrides(name)})


FREE_SLACK = 1e3
"""m/s: the slack bound of a "free" slack, the program (3) with alpha* = 1 of the slack rows.
Scenarios take finite bounds only; a test checks that no evidence run comes near it."""

_FREE = {"slack.min": [-FREE_SLACK] * 2, "slack.max": [FREE_SLACK] * 2}
"""The overrides that lift a planar task's slack bounds to :data:`FREE_SLACK`."""

EVIDENCE = (
    Evidence(
        "t1-uc-no-manip", "task1", (Name.UC_EMDM,), {"weights.manipulability": 0.0}, Name.UC_IVKC
    ),
    Evidence(  # the UC pair's trade at a five times finer step: most of their effort comes in
        # the first second, so its total depends on dt (readings 213, 227; 228: A2b's own
        # baseline)
        "t1-uc-finer-dt",
        "task1",
        (Name.UC_IVKC, Name.UC_EMDM),
        {"motion.dt": 0.01},
    ),
    Evidence(
        "t1-c-slack-policy",
        "task1",
        (Name.C_IVKC, Name.C_EMDM),
        {"controller.on_infeasible": "slack", **_FREE},  # (6): the slack free, as in Task 2
        like_for_like_slack=True,
    ),
    Evidence(  # the brief's slack box on the redundant arm too: its Table 1 lists it for Task 1
        # (readings 269, 277: never tried)
        "t1-brief-slack",
        "task1",
        (Name.UC_EMDM, Name.C_EMDM),
        {"controller.slack": "always"},
    ),
    Evidence(  # both with a free slack: C-EMDM's bound lifted to one no run comes near
        "t2-c-slack-policy",
        "task2",
        (Name.C_IVKC, Name.C_EMDM),
        {"controller.on_infeasible": "slack", **_FREE},
        like_for_like_slack=True,
    ),
    Evidence(
        "t2-c-ivkc-wide-limits", "task2", (Name.C_IVKC,), {"arm.q_min": -3.0, "arm.q_max": 3.0}
    ),
    Evidence(  # its mean m against the nominal's over the same time (a shorter run)
        "t2-c-emdm-no-manip",
        "task2",
        (Name.C_EMDM,),
        {"weights.manipulability": 0.0},
        Name.C_EMDM,
    ),
    Evidence(
        "t2-c-emdm-tight-slack",
        "task2",
        (Name.C_EMDM,),
        {"slack.min": [-0.1, -0.1], "slack.max": [0.1, 0.1]},
    ),
    Evidence(  # which of UC-EMDM's gains is the slack's and which the term's (reading 130)
        "t2-uc-emdm-no-manip",
        "task2",
        (Name.UC_EMDM,),
        {"weights.manipulability": 0.0},
        Name.UC_EMDM,
    ),
)
"""The evidence runs (each isolates one cause; the report says what each shows)."""

SLACK_POLICIES = {"task1": "t1-c-slack-policy", "task2": "t2-c-slack-policy"}
"""Each task's free-slack policy run (:data:`EVIDENCE`), also run on the many goals."""

MANY_GOALS = "data/many-goals.json"
"""The many-goals study: each task's controllers on the same random starts and goals."""
