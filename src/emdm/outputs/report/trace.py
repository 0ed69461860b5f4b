"""Traced numbers: every number the report states is read from a data file it wrote.

A sentence is a list of segments: plain :class:`Text`, traced numbers (:class:`Num`, read by
:class:`Data` from a JSON file of the report), inline math (:class:`Math`) and references to
figures, tables and sections (:class:`Ref`). Each segment renders to HTML and to LaTeX, so the
page and the paper say the same thing from the same records. In the HTML a number is a
``<span data-src="FILE#KEY/KEY" data-fmt="SPEC">`` (a derived percentage names both operands and
``data-op="pct"``), so a test can recompute every one of them.
"""

from __future__ import annotations

import html
import json
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any


def format_value(value: Any, fmt: str) -> str:
    """How every traced number is written (shared by the report and its tests)."""
    if value is None:
        return "–"
    if fmt == "bool":
        return "yes" if value else "no"
    if fmt == "d":
        return str(int(value))
    if isinstance(value, float) and not math.isfinite(value):
        return "–"
    if fmt.startswith("#"):  # significant digits kept ("74.0" beside "61.9"), no bare point
        return format(float(value), fmt).rstrip(".")
    return format(float(value), fmt)


_EXP = re.compile(r"^([+-]?[0-9.]+)e([+-])0*([0-9]+)$")


def _minus(text: str) -> str:
    return text.replace("-", "−")


def number_html(text: str) -> str:
    """A formatted number as HTML: ``1.2e-03`` as 1.2×10<sup>−3</sup>, a true minus sign."""
    match = _EXP.match(text)
    if match:
        mant, sign, exp = match.groups()
        exp_text = ("−" if sign == "-" else "") + exp
        if mant in ("1", "1.0"):
            return f"10<sup>{exp_text}</sup>"
        return f"{_minus(mant)}×10<sup>{exp_text}</sup>"
    return html.escape(_minus(text))


def number_latex(text: str) -> str:
    """A formatted number as LaTeX: exponents and signs as math, ``%`` escaped."""
    if text == "–":
        return "--"
    pct = text.endswith("%")
    core = text[:-1] if pct else text
    match = _EXP.match(core)
    if match:
        mant, sign, exp = match.groups()
        exp_text = ("-" if sign == "-" else "") + exp
        body = f"10^{{{exp_text}}}" if mant in ("1", "1.0") else f"{mant}\\times10^{{{exp_text}}}"
        out = f"${body}$"
    elif core.startswith(("-", "+")):
        out = f"${core}$"
    else:
        out = core
    return out + ("\\%" if pct else "")


def latex_escape(text: str) -> str:
    """Escape LaTeX's special characters in running text."""
    out = []
    for char in text:
        out.append(
            {
                "\\": r"\textbackslash{}",
                "&": r"\&",
                "%": r"\%",
                "$": r"\$",
                "#": r"\#",
                "_": r"\_",
                "{": r"\{",
                "}": r"\}",
                "~": r"\textasciitilde{}",
                "^": r"\textasciicircum{}",
                "\u2011": r"\mbox{-}",  # a hyphen no line breaks at: "(UC-)" in one piece
                "–": "--",
                "—": "---",
                "<": r"\textless{}",
                ">": r"\textgreater{}",
                "|": r"\textbar{}",
                "²": r"\textsuperscript{2}",
                "×": r"$\times$",
                "≈": r"$\approx$",
                "≤": r"$\leq$",
                "≥": r"$\geq$",
                "→": r"$\to$",
                "−": "--",
            }.get(char, char)
        )
    return "".join(out)


class Segment:
    """A piece of a sentence, rendered the same way in HTML and LaTeX."""

    def html(self) -> str:
        raise NotImplementedError

    def latex(self) -> str:
        raise NotImplementedError

    def plain(self) -> str:
        raise NotImplementedError


@dataclass(frozen=True)
class Text(Segment):
    """Plain prose."""

    text: str

    def html(self) -> str:
        return html.escape(self.text, quote=False)

    def latex(self) -> str:
        return latex_escape(self.text)

    def plain(self) -> str:
        return self.text


@dataclass(frozen=True)
class Num(Segment):
    """A number with the data it comes from (``src`` = ``FILE#KEY/KEY``, or two joined by ``|``)."""

    text: str
    src: str
    fmt: str
    op: str | None = None
    unit: str = ""

    def html(self) -> str:
        op = f' data-op="{self.op}"' if self.op else ""
        span = (
            f'<span class="num" data-src="{html.escape(self.src)}" '
            f'data-fmt="{html.escape(self.fmt)}"{op}>{number_html(self.text)}</span>'
        )
        return span + (f"\u202f{html.escape(self.unit)}" if self.unit else "")

    def latex(self) -> str:
        unit = f"~{latex_unit(self.unit)}" if self.unit else ""
        return number_latex(self.text) + unit

    def plain(self) -> str:
        return self.text + (f" {self.unit}" if self.unit else "")


UNITS_LATEX = {
    "s": "s",
    "m": "m",
    "m/s": "m/s",
    "rad": "rad",
    "rad/s": "rad/s",
    "ms": "ms",
    "µs": r"$\mu$s",
    "rad²/s": r"rad\textsuperscript{2}/s",
    "rad²/s²": r"rad\textsuperscript{2}/s\textsuperscript{2}",
    "m²": r"m\textsuperscript{2}",
    "m²/s": r"m\textsuperscript{2}/s",
}


def latex_unit(unit: str) -> str:
    """A unit in LaTeX text mode, upright and lower-case even in IEEE's small-caps table
    captions (where a metre read as the manipulability rate M)."""
    return rf"\textnormal{{{UNITS_LATEX.get(unit, latex_escape(unit))}}}"


@dataclass(frozen=True)
class Unit(Segment):
    """A unit standing alone in a sentence, ``(m²)``: as a number's unit would be written."""

    unit: str

    def html(self) -> str:
        return html.escape(self.unit)

    def latex(self) -> str:
        return latex_unit(self.unit)

    def plain(self) -> str:
        return self.unit


@dataclass(frozen=True)
class Upright(Segment):
    """Text kept upright and in its own case in IEEE's small-caps captions: a run label, ``A2a``,
    whose ``a`` would otherwise read as a capital."""

    text: str

    def html(self) -> str:
        return html.escape(self.text)

    def latex(self) -> str:
        return rf"\textnormal{{{latex_escape(self.text)}}}"

    def plain(self) -> str:
        return self.text


@dataclass(frozen=True)
class File(Segment):
    """A file's path, never broken across lines (a break at its hyphen reads as part of it)."""

    path: str

    def html(self) -> str:
        return f'<span class="file">{html.escape(self.path)}</span>'

    def latex(self) -> str:
        return rf"\mbox{{{latex_escape(self.path)}}}"

    def plain(self) -> str:
        return self.path


@dataclass(frozen=True)
class Math(Segment):
    """Inline math, given once for each output (LaTeX source and HTML)."""

    tex: str
    html_text: str

    def html(self) -> str:
        return f'<span class="math">{self.html_text}</span>'

    def latex(self) -> str:
        return f"${self.tex}$"

    def plain(self) -> str:
        return re.sub(r"<[^>]+>", "", self.html_text)


@dataclass(frozen=True)
class Ref(Segment):
    """``Fig. 3``, ``Table II`` or ``Section IV``: ``\\ref`` in LaTeX, a numbered link in HTML."""

    kind: str  # "fig", "tab" or "sec"
    key: str
    number: str = "?"

    def html(self) -> str:
        word = {"fig": "Fig.", "tab": "Table", "sec": "Section"}[self.kind]
        return f'<a href="#{self.kind}-{html.escape(self.key)}">{word}&nbsp;{self.number}</a>'

    def latex(self) -> str:
        word = {"fig": "Fig.", "tab": "Table", "sec": "Section"}[self.kind]
        return f"{word}~\\ref{{{self.kind}:{self.key}}}"

    def plain(self) -> str:
        return f"{self.kind} {self.key}"


GLYPH_WIDTH = "1.65em"
"""The width a :class:`Glyph` takes in a line, the same with or without a drawing."""


@dataclass(frozen=True)
class Glyph(Segment):
    """A figure's line and marker for one curve, inline (a table row as the figure's legend):
    ``stem`` is the drawing's path under ``paper/`` without its suffix; ``None`` keeps its
    width blank, so that the names after it stay aligned."""

    stem: str | None

    def html(self) -> str:
        if self.stem is None:
            return '<span class="glyph"></span>'
        return f'<img class="glyph" src="paper/{html.escape(self.stem)}.png" alt="">'

    def latex(self) -> str:
        if self.stem is None:
            return rf"\makebox[{GLYPH_WIDTH}]{{}}"
        return (
            rf"\makebox[{GLYPH_WIDTH}][l]{{\raisebox{{0.15ex}}"
            rf"{{\includegraphics[width=1.45em]{{{self.stem}}}}}}}"
        )

    def plain(self) -> str:
        return ""


EQUATIONS = ("bounds", "scale", "qp")
"""The formulation's displayed equations in their order (``\\label{eq:KEY}`` in
``templates/formulation.tex.j2``, numbered alike in ``formulation.html.j2``)."""


@dataclass(frozen=True)
class Eqs(Segment):
    """The numbers of some of the formulation's equations, ``1, 4, 5``: what a program solves."""

    keys: tuple[str, ...]

    def html(self) -> str:
        return ", ".join(str(EQUATIONS.index(k) + 1) for k in self.keys)

    def latex(self) -> str:
        return ", ".join(f"\\ref{{eq:{k}}}" for k in self.keys)

    def plain(self) -> str:
        return self.html()


REFERENCES = ("yoshikawa", "whitney", "liegeois", "flacco", "haviland", "nocedal")
"""The bibliography in the order of first citation, as ``templates/references.tex.j2`` and the
page's list give it."""


@dataclass(frozen=True)
class Cite(Segment):
    """A citation: ``\\cite{key}`` in LaTeX, ``[n]`` in HTML."""

    key: str

    def html(self) -> str:
        n = REFERENCES.index(self.key) + 1
        return f'&nbsp;<a href="#ref-{self.key}">[{n}]</a>'

    def latex(self) -> str:
        return f"~\\cite{{{self.key}}}"

    def plain(self) -> str:
        return f"[{REFERENCES.index(self.key) + 1}]"


Sentence = list[Segment]


@dataclass(frozen=True)
class PageOnly(Segment):
    """Words the page prints and the paper leaves out: its four pages have no room for them
    (the stochastic solvers' spread over seeds, say). Its segments are numbers and prose, never
    a reference (references are numbered over the paper's sentences)."""

    parts: tuple[Segment, ...]

    def __post_init__(self) -> None:
        if any(isinstance(p, Ref) for p in self.parts):
            raise ValueError("PageOnly holds no reference: the paper would not number it")

    def html(self) -> str:
        return render_html(self.parts)

    def latex(self) -> str:
        return ""

    def plain(self) -> str:
        return "".join(p.plain() for p in self.parts)


def sentence(*parts: Segment | str) -> Sentence:
    """A sentence from segments and strings (strings become :class:`Text`)."""
    return [Text(p) if isinstance(p, str) else p for p in parts]


def cap(parts: Sentence) -> Sentence:
    """The claim at the start of a sentence: its first letter a capital."""
    if not parts or not isinstance(parts[0], Text):
        return parts
    first = parts[0].text
    return [Text(first[:1].upper() + first[1:]), *parts[1:]]


def render_html(parts: Sequence[Segment]) -> str:
    return "".join(p.html() for p in parts)


def render_latex(parts: Sequence[Segment]) -> str:
    return "".join(p.latex() for p in parts)


class Data:
    """The report's data files, read back from disk (numbers are taken from here only)."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self._cache: dict[str, Any] = {}

    def exists(self, file: str) -> bool:
        return (self.root / file).is_file()

    def load(self, file: str) -> Any:
        if file not in self._cache:
            self._cache[file] = json.loads((self.root / file).read_text(encoding="utf-8"))
        return self._cache[file]

    def value(self, file: str, *path: str | int) -> Any:
        node = self.load(file)
        for key in path:
            node = node[int(key)] if isinstance(node, list) else node[str(key)]
        return node

    def num(self, file: str, *path: str | int, fmt: str = ".4g", unit: str = "") -> Num:
        """The value at ``file#path``, formatted with ``fmt``."""
        return traced(self.value(file, *path), file, path, fmt, unit)

    def ms(self, file: str, *path: str | int, fmt: str = ".3g") -> Num:
        """A time in seconds at ``file#path``, written in milliseconds."""
        return traced(self.value(file, *path), file, path, fmt, "ms", op="ms")

    def us(self, file: str, *path: str | int, fmt: str = ".2g") -> Num:
        """A time in seconds at ``file#path``, written in microseconds."""
        return traced(self.value(file, *path), file, path, fmt, "µs", op="us")

    def count(self, file: str, *path: str | int) -> Num:
        """How many entries the list at ``file#path`` has."""
        return traced(self.value(file, *path), file, path, "d", op="len")

    def _ratio(self, a: tuple[str | int, ...], b: tuple[str | int, ...]) -> tuple[float, str]:
        """``a / b`` read from the files, and the two operands' trace (``FILE#PATH|FILE#PATH``)."""
        va, vb = self.value(str(a[0]), *a[1:]), self.value(str(b[0]), *b[1:])
        src = f"{a[0]}#{'/'.join(map(str, a[1:]))}|{b[0]}#{'/'.join(map(str, b[1:]))}"
        return va / vb, src

    def pct(self, a: tuple[str | int, ...], b: tuple[str | int, ...], fmt: str = "+.0f") -> Num:
        """``100 (a / b - 1)`` as a signed percentage, tracing both operands."""
        ratio, src = self._ratio(a, b)
        return Num(format(100.0 * (ratio - 1.0), fmt) + "%", src, fmt, "pct")

    def cut(self, a: tuple[str | int, ...], b: tuple[str | int, ...], fmt: str = ".0f") -> Num:
        """``100 (1 - a / b)``: how much less ``a`` is than ``b``, in percent (``cuts ... by 35%``
        where :meth:`pct` would write ``-35%``)."""
        ratio, src = self._ratio(a, b)
        return Num(format(100.0 * (1.0 - ratio), fmt) + "%", src, fmt, "cut")


SCALE = {"ms": 1e3, "us": 1e6}
"""The operations that write a value in seconds in another unit, and their factor."""


def traced(
    value: Any,
    file: str,
    path: tuple[str | int, ...],
    fmt: str,
    unit: str = "",
    op: str | None = None,
) -> Num:
    """The value read at ``file#path`` as a traced number: formatted with ``fmt`` after ``op``
    (``ms``/``us``: seconds scaled, ``len``: the length of a list; see :func:`expected_text`)."""
    if op == "len":
        text = str(len(value))
    else:
        text = format_value(value * SCALE[op] if op in SCALE else value, fmt)
    return Num(text, f"{file}#{'/'.join(map(str, path))}", fmt, op, unit=unit)


def expected_text(root: Path, src: str, fmt: str, op: str | None) -> str:
    """What a traced number must read, recomputed from the files (used by the tests)."""

    def value(ref: str) -> Any:
        file, _, path = ref.partition("#")
        node = json.loads((root / file).read_text(encoding="utf-8"))
        for key in path.split("/") if path else []:
            node = node[int(key)] if isinstance(node, list) else node[key]
        return node

    refs = src.split("|")
    if op == "pct":
        a, b = (value(r) for r in refs)
        return format(100.0 * (a / b - 1.0), fmt) + "%"
    if op == "cut":
        a, b = (value(r) for r in refs)
        return format(100.0 * (1.0 - a / b), fmt) + "%"
    if op == "len":
        return str(len(value(refs[0])))
    if op in SCALE:
        return format_value(value(refs[0]) * SCALE[op], fmt)
    return format_value(value(refs[0]), fmt)
