"""Rendering: the paper and the pitch (LaTeX) and the page (HTML) from Jinja2 templates, and the
compilation of the LaTeX with ``pdflatex`` when it is installed.

LaTeX templates use ``((* ... *))`` for blocks and ``((( ... )))`` for values, so that braces stay
LaTeX's; the ``tex`` and ``html`` filters render a sentence (a list of segments) or a string.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import jinja2
import markupsafe

from ...core.tolerances import KKT_TOL, STALL_BAND, STALL_TIME
from ...solvers import registered_solvers
from ...solvers.nlp import PENALISED
from .document import Document, roman
from .findings import Story
from .findings.base import glossed, square_box
from .pitch import Pitch
from .trace import (
    Cite,
    Data,
    Segment,
    Text,
    latex_escape,
    number_html,
    number_latex,
    render_html,
    render_latex,
)

TEMPLATES = Path(__file__).with_name("templates")


def _tex(value: Any) -> str:
    if isinstance(value, str):
        return latex_escape(value)
    if isinstance(value, Segment):
        return value.latex()
    return render_latex(value)


def _html(value: Any) -> str:
    if isinstance(value, str):
        return Text(value).html()
    if isinstance(value, Segment):
        return value.html()
    return render_html(value)


def _plain(value: Any) -> str:
    if isinstance(value, str):
        return value
    return "".join(seg.plain() for seg in value)


def latex_environment() -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(TEMPLATES),
        block_start_string="((*",
        block_end_string="*))",
        variable_start_string="(((",
        variable_end_string=")))",
        comment_start_string="((=",
        comment_end_string="=))",
        trim_blocks=True,
        lstrip_blocks=True,
        autoescape=False,
        undefined=jinja2.StrictUndefined,
        keep_trailing_newline=True,
    )
    env.filters["tex"] = _tex
    env.filters["plain"] = _plain
    env.globals["kkt_tol"] = number_latex(format(KKT_TOL, ".0e"))
    env.globals["penalised"] = PENALISED  # (282: "unconstrained methods" named)
    env.globals["stall_band_mm"] = format(STALL_BAND * 1e3, "g")
    env.globals["stall_time"] = format(STALL_TIME, "g")
    env.filters["glossed"] = glossed
    env.globals["square_box"] = square_box
    env.filters["method"] = lambda name: registered_solvers()[name].method
    return env


def html_environment() -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(TEMPLATES),
        autoescape=jinja2.select_autoescape(["html", "j2"]),
        trim_blocks=True,
        lstrip_blocks=True,
        undefined=jinja2.StrictUndefined,
    )
    env.filters["h"] = lambda v: markupsafe.Markup(_html(v))
    env.filters["plain"] = _plain
    env.globals["kkt_tol"] = markupsafe.Markup(number_html(format(KKT_TOL, ".0e")))
    env.globals["cite"] = lambda key: markupsafe.Markup(Cite(key).html().removeprefix("&nbsp;"))
    return env


def document(stage: Path) -> Document:
    """The study's document, built from the files in ``stage`` (never from memory)."""
    return Story(Data(stage)).build()


def write_latex(
    stage: Path, *, compact: bool = False, names: Sequence[str] = ("paper", "pitch")
) -> None:
    """``paper/paper.tex`` and ``paper/pitch.tex`` (or the ``names`` among them) from the
    records in ``stage``; ``compact`` draws the paper's figures at 92 % of their width (the
    fallback when the first compile runs over the page limit)."""
    data = Data(stage)
    doc = Story(data).build()
    env = latex_environment()
    folder = stage / "paper"
    folder.mkdir(parents=True, exist_ok=True)
    if "paper" in names:
        (folder / "paper.tex").write_text(
            env.get_template("paper.tex.j2").render(doc=doc, data=data, compact=compact),
            encoding="utf-8",
        )
    if "pitch" in names:
        pitch = Pitch(data, doc).build()
        (folder / "pitch.tex").write_text(
            env.get_template("pitch.tex.j2").render(doc=doc, pitch=pitch, data=data),
            encoding="utf-8",
        )


def write_html(stage: Path) -> None:
    """``index.html``: the same document, with the animations and every table in full."""
    data = Data(stage)
    doc = Story(data).build()
    prov = data.load("provenance.json")
    anims = (
        data.value("data/animations.json", "animations")
        if data.exists("data/animations.json")
        else {}
    )
    labs = (
        sorted(str(p.relative_to(stage)) for p in (stage / "figures").rglob("*.png"))
        if (stage / "figures").exists()
        else []
    )
    anim_of = {"t1-uc": "task1-UC", "t1-c": "task1-C", "t2-c": "task2-C", "t2-uc": "task2-UC"}
    html = (
        html_environment()
        .get_template("index.html.j2")
        .render(doc=doc, prov=prov, anims=anims, labs=labs, data=data, anim_of=anim_of, roman=roman)
    )
    (stage / "index.html").write_text(html, encoding="utf-8")


# -------------------------------------------------------------------------- compilation
def tex_engine() -> str | None:
    """``pdflatex`` (or ``latexmk``) when installed, else ``None``."""
    return shutil.which("pdflatex") or shutil.which("latexmk")


def _command(engine: str, name: str) -> list[str]:
    if Path(engine).name == "latexmk":
        return [engine, "-pdf", "-interaction=nonstopmode", "-halt-on-error", "-quiet", name]
    return [engine, "-interaction=nonstopmode", "-halt-on-error", "-file-line-error", name]


def log_problems(log: str) -> dict[str, Any]:
    """Errors, undefined references and overfull boxes (with their size in pt) of a LaTeX log."""
    errors = [line for line in log.splitlines() if re.match(r"^(! |.*:\d+: )", line)]
    overfull = [float(x) for x in re.findall(r"Overfull \\[hv]box \(([0-9.]+)pt too", log)]
    undefined = bool(re.search(r"(Reference|Citation) `[^']*' on page \d+ undefined", log)) or (
        "There were undefined references" in log
    )
    pages = re.search(r"Output written on \S+ \((\d+) pages?", log)
    return {
        "errors": errors,
        "overfull_pt": overfull,
        "undefined_references": undefined,
        "pages": int(pages.group(1)) if pages else 0,
        "rerun": "Rerun to get" in log or "Label(s) may have changed" in log,
    }


def compile_documents(
    folder: Path,
    say: Callable[[str], None],
    names: Sequence[str] = ("paper", "pitch"),
    *,
    final: Path | None = None,
) -> dict[str, Any]:
    """Compile ``paper.tex`` and ``pitch.tex`` in ``folder`` (in parallel, each until its
    references settle, at most three passes); without a TeX engine say how to compile, in the
    folder where the sources will be (``final``: the staging folder is gone by then)."""
    engine = tex_engine()
    if engine is None:
        hint = (
            f"no TeX engine (pdflatex) found, so no PDFs: to build them, run "
            f"`pdflatex paper.tex` and `pdflatex pitch.tex` twice in {final or folder}"
        )
        say(hint)
        return {"engine": None, "hint": hint}
    start = time.perf_counter()
    out: dict[str, Any] = {"engine": Path(engine).name}
    pending = list(names)
    passes = dict.fromkeys(names, 0)
    while pending:
        procs = {
            name: subprocess.Popen(
                _command(engine, f"{name}.tex"),
                cwd=folder,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
                stdin=subprocess.DEVNULL,
            )
            for name in pending
        }
        again = []
        for name, proc in procs.items():
            code = proc.wait()
            passes[name] += 1
            log_file = folder / f"{name}.log"  # none when the engine could not even start
            log = (
                log_file.read_text(encoding="utf-8", errors="replace") if log_file.exists() else ""
            )
            info = log_problems(log)
            info.update(returncode=code, passes=passes[name])
            out[name] = info
            if code == 0 and (passes[name] == 1 or info["rerun"]) and passes[name] < 3:
                again.append(name)
        pending = again
    for name in names:
        for suffix in (".aux", ".out", ".nav", ".snm", ".toc", ".vrb", ".fls", ".fdb_latexmk"):
            (folder / f"{name}{suffix}").unlink(missing_ok=True)
        info = out[name]
        if info["returncode"] != 0 or info["errors"]:
            say(f"{name}.tex did not compile cleanly: see {folder / (name + '.log')}")
    out["seconds"] = time.perf_counter() - start
    return out
