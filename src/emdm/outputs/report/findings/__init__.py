"""The study's story: direct answers and explanations, every number read from the records.

One module per part of the paper (:mod:`.front`, :mod:`.task1`, :mod:`.task2`, :mod:`.solvers`,
:mod:`.beyond`, :mod:`.tables`), on the accessors and shared rules of :mod:`.base`. Each section
opens with a one-sentence direct answer to its brief item, then explains what shaped the runs
from the detected events (``events.json``), backed by evidence runs (``evidence.json``) that
isolate each cause. Sentences are chosen by the data (a stall is only described when one was
detected, a comparison says "more" or "less" by the sign), never canned.
"""

from __future__ import annotations

from ..config import BYLINE
from ..document import Document, Section
from .base import (
    ALPHA,
    C_S,
    COND_J,
    DELTA,
    DT,
    E_SYM,
    ERR,
    M_SYM,
    MRATE,
    RATIO,
    T_EQ,
    VD,
    W_E,
    W_M,
    W_S,
    W_S_SYM,
    bare,
    eq,
    q,
    qd,
)
from .beyond import Beyond
from .front import Front
from .goals import GOALS_IN_PAPER
from .solvers import Solvers
from .tables import Tables
from .task1 import Task1
from .task2 import Task2


class Story(Front, Task1, Task2, Solvers, Beyond, Tables):
    """Builds the :class:`Document` from the report's data files."""

    def build(self) -> Document:
        maybe = [
            self.introduction(),
            Section("formulation", "Formulation", partial="formulation"),
            Section("task1", "Task 1: the redundant three-link arm"),
            self.task1_uc(),
            self.pareto(),
            self.task1_c(),
            self.task1_solver(),
            Section("task2", "Task 2: the non-redundant two-link arm"),
            self.task2_c(),
            self.task2_challenges(self.task2_solvers()),
            self.task2_uc(),
            *((self.goals_section(),) if GOALS_IN_PAPER else ()),
            self.conclusion(),
            *(() if GOALS_IN_PAPER else (self.goals_section(),)),  # the page's, after
            self.beyond(),
        ]
        sections = [s for s in maybe if s is not None]
        self.outcome_table(sections)
        self.terms_table(sections)
        self.evidence_table()
        self.goals_table()
        self.goals_in_body(sections)
        for sec in sections:
            sec.figures = [k for k in sec.figures if k in self.figures]
        byline = self.d.load(BYLINE) if self.d.exists(BYLINE) else {}
        doc = Document(
            title=byline.get("title")
            or "Effort-Minimising, Dexterity-Maximising Velocity Control of Planar Arms",
            authors=tuple(byline.get("authors", ())),
            abstract=self.abstract(),
            sections=sections,
            figures=self.figures,
            tables=self.tables,
            answers=self.answers,
        )
        doc.number()
        return doc


__all__ = [
    "ALPHA",
    "COND_J",
    "C_S",
    "DELTA",
    "DT",
    "ERR",
    "E_SYM",
    "MRATE",
    "M_SYM",
    "RATIO",
    "T_EQ",
    "VD",
    "W_E",
    "W_M",
    "W_S",
    "W_S_SYM",
    "Story",
    "bare",
    "eq",
    "q",
    "qd",
]
