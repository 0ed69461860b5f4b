"""The quick study's paper and pitch compile cleanly: no LaTeX error, no undefined reference, no
overfull box wider than 5 pt, at most four letter pages for the paper, 16:9 slides for the pitch."""

from __future__ import annotations

import re
import shutil
import subprocess
import zlib

import pytest

from emdm.outputs.report.render import log_problems, tex_engine

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(
        tex_engine() is None,
        reason="no TeX engine (pdflatex); .ci/run installs texlive to compile the paper",
    ),
]


def _page_size(pdf):
    """Width and height (pt) of the first page, from the PDF's MediaBox."""
    if shutil.which("pdfinfo"):
        info = subprocess.run(["pdfinfo", str(pdf)], capture_output=True, text=True).stdout
        w, h = re.search(r"Page size:\s+([0-9.]+) x ([0-9.]+) pts", info).groups()
        return float(w), float(h)
    data = pdf.read_bytes()  # without pdfinfo: the MediaBox, also inside compressed streams
    texts = [data]
    for stream in re.finditer(rb"stream\r?\n(.*?)\r?\nendstream", data, re.S):
        try:
            texts.append(zlib.decompress(stream.group(1)))
        except zlib.error:
            continue
    for text in texts:
        box = re.search(rb"/MediaBox\s*\[\s*0 0 ([0-9.]+) ([0-9.]+)\s*\]", text)
        if box:
            return float(box.group(1)), float(box.group(2))
    raise AssertionError(f"{pdf}: no MediaBox found")


@pytest.mark.parametrize("name", ["paper", "pitch"])
def test_compiles_cleanly(quick_report, name):
    folder = quick_report / "paper"
    assert (folder / f"{name}.pdf").is_file(), f"{name}.pdf was not built"
    problems = log_problems((folder / f"{name}.log").read_text(encoding="utf-8", errors="replace"))
    assert not problems["errors"], problems["errors"]
    assert not problems["undefined_references"]
    assert all(width <= 5.0 for width in problems["overfull_pt"]), problems["overfull_pt"]


def test_the_paper_is_at_most_four_letter_pages(quick_report):
    """IEEE's own page: on A4 the template keeps the letter text block and leaves a fifth of
    every page blank at the bottom (a reader took it for missing text)."""
    folder = quick_report / "paper"
    log = (folder / "paper.log").read_text(encoding="utf-8", errors="replace")
    assert 1 <= log_problems(log)["pages"] <= 4
    w, h = _page_size(folder / "paper.pdf")
    assert abs(w - 612.0) < 1.5 and abs(h - 792.0) < 1.5  # US letter
    tex = (folder / "paper.tex").read_text(encoding="utf-8")
    assert r"\documentclass[conference,letterpaper]{IEEEtran}" in tex
    for section in ("Introduction", "Formulation", "Conclusion"):
        assert f"\\section{{{section}}}" in tex


def test_the_formulations_run_in_headings_each_open_a_paragraph(quick_report):
    """Section II's run-in headings start paragraphs of their own: a template's closing tag
    before the blank line ate the break once, and "Infeasible steps" ran on after the stop zone's
    sentence."""
    tex = (quick_report / "paper" / "paper.tex").read_text(encoding="utf-8")
    for heading in ("Programs.", "Infeasible steps: a departure from the brief.", "Solvers."):
        assert f"\n\n\\emph{{{heading}}}" in tex, heading


def test_the_paper_writes_each_controllers_program_out(quick_report):
    """Readings 221-262: each controller's program is written out in the paper, one display
    row each (Task 2's C-EMDM numbered (3), the UC- ones no longer "by deletion"), EMDM's
    objective f with the scenario's weights, Task 1's D = {0}; the table of each controller's
    terms is the page's alone, and nothing in the paper cites it."""
    import json

    tex = (quick_report / "paper" / "paper.tex").read_text(encoding="utf-8")
    weights = json.loads(
        (quick_report / "data" / "task1" / "metrics.json").read_text(encoding="utf-8")
    )["scenario"]["weights"]
    f = r"$f=\tfrac12w_E\|\dot q\|^2-w_MJ_m^\top\dot q+\tfrac12w_S\|\delta\|^2$"
    assert f + f", $w_E={weights['effort']:g}$ and $w_M={weights['manipulability']:g}$" in tex
    display = tex[tex.index(r"\begin{alignat}") : tex.index(r"\end{alignat}")]
    rows = {
        "C-EMDM": r"\min_{\dot q,\,\delta}f\ \text{s.t. }J\dot q+\delta=\alpha^*v_d,\ \dot q\in B,"
        r"\ \delta\in D,\label{eq:qp}",
        "UC-EMDM": r"\min_{\dot q,\,\delta}f\ \text{s.t. }J\dot q+\delta=v_d,\ \delta\in D,",
        "C-IVKC": r"\min_{\dot q}\tfrac12\|\dot q\|^2\ \text{s.t. }J\dot q=\alpha^*v_d,\ \dot q\in B,",
        "UC-IVKC": r"\min_{\dot q}\tfrac12\|\dot q\|^2\ \text{s.t. }J\dot q=v_d\quad(\dot q=J^+v_d),",
    }
    for name, row in rows.items():
        assert f"\\text{{{name}: }}&{row}" in display, name
    assert "where $D=\\{0\\}$ on Task~1's arm and for IVKC." in tex
    assert "tab:programs" not in tex
    page = (quick_report / "index.html").read_text(encoding="utf-8")
    assert 'id="tab-programs"' in page


def test_the_pitch_is_16_9_with_8_to_13_slides_and_backups(quick_report):
    """A 10-minute talk: at most 13 frames before the backups, the title's included (Task 1's
    policy has a slide of its own since readings 152-153 found it a second idea beside the
    stills), about 45 s each."""
    folder = quick_report / "paper"
    w, h = _page_size(folder / "pitch.pdf")
    assert abs(w / h - 16 / 9) < 0.01
    tex = (folder / "pitch.tex").read_text(encoding="utf-8")
    main, _, backup = tex.partition("\\appendix")
    assert 8 <= main.count("\\begin{frame}") <= 13
    assert backup.count("\\begin{frame}") <= 8
    # the brief's Task 1 deliverable, the per-step fronts, among them (274: on no slide)
    fronts = backup.split("Backup: Task 1 Pareto fronts at four steps", 1)[1].split("\\end{frame}")[
        0
    ]
    assert "\\includegraphics[width=\\textwidth]{figures/pareto}" in fronts


def test_the_compact_fallback_compiles(quick_report, tmp_path):
    """When a first compile runs past four pages, the report redoes the paper with its figures
    at 92 % width: that version compiles cleanly too, and is no longer."""
    from emdm.outputs.report.render import compile_documents, write_latex

    stage = tmp_path / "report"
    shutil.copytree(quick_report, stage)
    write_latex(stage, compact=True, names=("paper",))
    tex = (stage / "paper" / "paper.tex").read_text(encoding="utf-8")
    assert r"width=0.92\columnwidth" in tex and r"width=0.92\textwidth" in tex
    said: list[str] = []
    info = compile_documents(stage / "paper", said.append, names=("paper",))["paper"]
    assert info["returncode"] == 0 and not info["errors"] and not said
    normal = log_problems((quick_report / "paper" / "paper.log").read_text(errors="replace"))
    assert 1 <= info["pages"] <= normal["pages"] <= 4
