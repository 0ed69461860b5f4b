"""The document model shared by the paper, the pitch and the HTML page.

A :class:`Document` is a title, an abstract and a list of :class:`Section` objects; a section has
a direct answer (one sentence, first), paragraphs of explanations, and the keys of its figures and
tables. Figures and tables are numbered once, in order of first appearance, so that the HTML
page's numbers equal LaTeX's ``\\ref`` numbers.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .trace import Ref, Segment, Sentence


@dataclass
class Figure:
    """A figure: ``stem`` is its path without suffix below ``paper/`` (``figures/pareto``)."""

    key: str
    stem: str
    caption: Sentence
    wide: bool = False
    number: int = 0
    paper: bool = True

    @property
    def label(self) -> str:
        """``3`` in the paper's numbering; ``W1``, ``W2``... for figures only on the page."""
        return str(self.number) if self.paper else f"W{self.number}"


@dataclass
class Table:
    """A table: ``header`` and ``rows`` of sentences; a row of one cell is a group heading."""

    key: str
    caption: Sentence
    header: list[Sentence]
    rows: list[list[Sentence]] = field(default_factory=list)
    align: str = ""
    wide: bool = False
    number: int = 0
    html_only: bool = False
    font: str = "footnotesize"
    colsep: float = 4.0
    """Space either side of a column (pt, LaTeX's ``\\tabcolsep``): less for a wide table."""
    stretch: float = 1.0
    """Row height factor (LaTeX's ``\\arraystretch``): more for rows of superscripts."""
    placement: str = "t"
    """Where LaTeX may float it: ``t`` (a column's top) or ``b`` (its bottom: the programs,
    under the formulation that defines them)."""


@dataclass
class Section:
    """One section (level 1) or subsection (level 2) of the study."""

    key: str
    title: str
    level: int = 1
    answer: Sentence | None = None
    paragraphs: list[Sentence] = field(default_factory=list)
    figures: list[str] = field(default_factory=list)
    tables: list[str] = field(default_factory=list)
    partial: str | None = None
    brief: str | None = None
    html_extra: list[str] = field(default_factory=list)
    html_only: bool = False


@dataclass
class Document:
    """The whole study, as both the paper and the page tell it."""

    title: str
    abstract: Sentence
    sections: list[Section]
    figures: dict[str, Figure]
    tables: dict[str, Table]
    answers: list[tuple[str, Sentence]] = field(default_factory=list)
    authors: tuple[str, ...] = ()
    """The names on the paper, the pitch and the page (``emdm report --author``); none: the
    paper and the pitch say "Anonymous authors"."""

    def number(self) -> None:
        """Number figures and tables by first appearance; fill in the references' numbers."""
        fig = tab = web = 0
        for section in self.sections:
            for key in section.figures:
                figure = self.figures[key]
                if figure.number == 0 and figure.paper:
                    fig += 1
                    figure.number = fig
                elif figure.number == 0:
                    web += 1
                    figure.number = web
            for key in section.tables:
                table = self.tables[key]
                if table.number == 0 and not table.html_only:
                    tab += 1
                    table.number = tab
        # the page's own tables next, by first appearance (a table in no section, such as the
        # pitch's, last: numbering them in the dictionary's order left gaps on the page)
        shown = [key for section in self.sections for key in section.tables]
        for key in (*shown, *self.tables):
            table = self.tables[key]
            if table.number == 0:
                tab += 1
                table.number = tab
        for sentence in self._sentences():
            for i, seg in enumerate(sentence):
                if isinstance(seg, Ref):
                    sentence[i] = Ref(seg.kind, seg.key, self._label(seg))

    def _label(self, ref: Ref) -> str:
        if ref.kind == "fig":
            return self.figures[ref.key].label
        if ref.kind == "tab":
            return roman(self.tables[ref.key].number)
        major = minor = 0
        for section in self.sections:
            if section.level == 1:
                major, minor = major + 1, 0
            else:
                minor += 1
            if section.key == ref.key:
                return roman(major) + (f"-{chr(64 + minor)}" if section.level == 2 else "")
        raise KeyError(ref.key)

    def _sentences(self) -> list[list[Segment]]:
        out: list[list[Segment]] = [self.abstract]
        for section in self.sections:
            if section.answer:
                out.append(section.answer)
            out.extend(section.paragraphs)
        for figure in self.figures.values():
            out.append(figure.caption)
        for table in self.tables.values():
            out.append(table.caption)
            for row in table.rows:
                out.extend(row)
        out.extend(sentence for _, sentence in self.answers)
        return out


def roman(number: int) -> str:
    """IEEE numbers tables in upper-case Roman numerals."""
    out = ""
    for value, digits in ((10, "X"), (9, "IX"), (5, "V"), (4, "IV"), (1, "I")):
        while number >= value:
            out += digits
            number -= value
    return out
