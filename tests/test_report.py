"""emdm report --quick end to end: every number traced to the data, the page telling the paper's
story (same sections, answers and explanations), every link local, and the page checked in a real
headless browser."""

from __future__ import annotations

import json
import re
import shutil
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest
from conftest import headless_chromium

import emdm
from emdm.outputs.records import read_run
from emdm.outputs.report import format_value
from emdm.outputs.report.config import FREE_SLACK
from emdm.outputs.report.render import compile_documents, document, latex_environment
from emdm.outputs.report.trace import expected_text, number_html, render_latex

pytestmark = pytest.mark.slow  # one quick study (about 20 s) shared by the whole session


class Page(HTMLParser):
    """Collects traced numbers, tables, headings, image sources and links of the report page."""

    def __init__(self) -> None:
        super().__init__()
        self.spans: list[dict[str, str]] = []
        self.tables: dict[str, list[list[str]]] = {}
        self.headings: list[str] = []
        self.sources: list[str] = []
        self.links: list[str] = []
        self._span: dict[str, str] | None = None
        self._table: str | None = None
        self._cell: list[str] | None = None
        self._heading: list[str] | None = None

    def handle_starttag(self, tag, attrs):
        a = {k: v or "" for k, v in attrs}
        if tag == "span" and "data-src" in a:
            self._span = {**a, "text": ""}
        elif tag == "table" and "id" in a:
            self._table = a["id"]
            self.tables[self._table] = []
        elif tag == "tr" and self._table:
            self.tables[self._table].append([])
        elif tag in ("td", "th") and self._table:
            self._cell = []
        elif tag in ("h2", "h3"):
            self._heading = []
        elif tag == "img":
            self.sources.append(a["src"])
        elif tag == "a":
            self.links.append(a.get("href", ""))
        elif tag in ("script", "link", "iframe", "video", "source"):
            self.links.append(a.get("src", a.get("href", "")))

    def handle_endtag(self, tag):
        if tag == "span" and self._span is not None:
            self.spans.append(self._span)
            self._span = None
        elif tag in ("td", "th") and self._cell is not None and self._table:
            self.tables[self._table][-1].append("".join(self._cell).strip())
            self._cell = None
        elif tag == "table":
            self._table = None
        elif tag in ("h2", "h3") and self._heading is not None:
            self.headings.append("".join(self._heading).strip())
            self._heading = None

    def handle_data(self, data):
        if self._span is not None:
            self._span["text"] += data
        if self._cell is not None:
            self._cell.append(data)
        if self._heading is not None:
            self._heading.append(data)


@pytest.fixture(scope="module")
def report(quick_report):
    page = Page()
    page.feed((quick_report / "index.html").read_text(encoding="utf-8"))
    return quick_report, page


def _strip(html: str) -> str:
    return re.sub(r"<[^>]+>", "", html)


def test_every_number_traces_to_the_data(report):
    root, page = report
    assert len(page.spans) > 150
    for span in page.spans:
        expected = expected_text(root, span["data-src"], span["data-fmt"], span.get("data-op"))
        assert span["text"] == _strip(number_html(expected)), span


def test_format_value_writes_missing_values_as_a_dash():
    assert format_value(None, ".2f") == "–"
    assert format_value(float("nan"), ".2f") == "–"
    assert format_value(True, "bool") == "yes"
    assert format_value(3.0, "d") == "3"


def test_format_value_keeps_significant_zeros_without_a_bare_point():
    """Table III's times at three significant digits: 74.0 beside 61.9 (reading 165 took 74 for a
    rounding slip), and never Python's bare '100.'."""
    assert [format_value(v, "#.3g") for v in (74.0, 61.94, 0.00869, 100.0)] == [
        "74.0",
        "61.9",
        "0.00869",
        "100",
    ]


def test_the_page_tells_the_papers_story(report):
    """Same sections in the same order, and every answer of the paper on the page."""
    root, page = report
    doc = document(root)
    titles = [s.title for s in doc.sections]
    found = [h for h in page.headings if h in titles]
    assert found == titles
    tex = (root / "paper" / "paper.tex").read_text(encoding="utf-8")
    for section in doc.sections:
        if section.html_only:  # beyond the brief: the page only
            assert f"{{{latex_environment().filters['tex'](section.title)}}}" not in tex
            continue
        assert f"{{{latex_environment().filters['tex'](section.title)}}}" in tex, section.title
        if section.answer:
            assert render_latex(section.answer) in tex, section.key
    answered = [item for item, _ in doc.answers]
    for brief_item in ("Task 1.1", "Task 1.2", "Task 2.1", "Task 2.2"):
        assert any(item.startswith(brief_item) for item in answered), brief_item
    assert len(page.tables["tab-answers"]) - 1 == len(doc.answers)


def test_beyond_the_brief_puts_the_benchmark_beside_the_published_table(report):
    root, page = report
    rows = page.tables["tab-mmc"]
    data = json.loads((root / "data" / "mmc.json").read_text(encoding="utf-8"))
    assert len(rows) - 1 == sum(len(v) for v in data["results"].values())
    mmc = next(r for r in rows if r[:2] == ["Panda", "MMC"])
    assert "(8.0 %)" in mmc[4].replace("\u202f", " ")
    assert (root / "paper" / "figures" / "panda-baselines.png").is_file()


def test_task2_c_ivkc_is_explained_not_just_compared(report):
    """The stall of C-IVKC is detected and explained (blocked line, evidence runs), from data."""
    root, _ = report
    events = json.loads((root / "data" / "task2" / "events.json").read_text())
    stall = events["controllers"]["C-IVKC"]["stall"]
    assert stall and stall["joint"] == 2 and stall["distance_to_stop"] < 1e-6
    assert events["geometry"]["line_blocked"]
    evidence = json.loads((root / "data" / "evidence.json").read_text())["runs"]
    assert evidence["t2-c-slack-policy"]["runs"]["C-IVKC"]["reached"]
    # the slack rows solve (6), the slack free: its bound lifted to one no run comes near
    for key in ("t1-c-slack-policy", "t2-c-slack-policy"):
        free = evidence[key]
        assert free["overrides"]["slack.max"] == [FREE_SLACK, FREE_SLACK], key
        assert free["overrides"]["slack.min"] == [-FREE_SLACK, -FREE_SLACK], key
        for name in ("C-IVKC", "C-EMDM"):
            assert 0 < free["runs"][name]["max_abs_slack"] < 0.01 * FREE_SLACK, (key, name)
    assert evidence["t1-uc-no-manip"]["reference"]["max_abs_qd_difference"] < 1e-12
    # A4 ends sooner than its nominal run: the nominal's mean m over A4's time is recorded
    # (reading 94: each run's own mean covers its own horizon), from the nominal trajectory
    ref = evidence["t2-c-emdm-no-manip"]["reference"]
    e4 = evidence["t2-c-emdm-no-manip"]["runs"]["C-EMDM"]
    nominal = read_run(root / "data" / "task2", "C-EMDM")
    upto = nominal.t <= ref["common_until_t"] + 1e-9
    assert ref["controller"] == "C-EMDM"
    assert ref["common_until_t"] == pytest.approx(min(e4["final_time"], nominal.t[-1]))
    assert ref["mean_m_common"]["reference"] == pytest.approx(nominal.m[upto].mean(), rel=1e-12)
    # the identical commands are scaling's (one admissible command): a free slack has fewer
    t1 = json.loads((root / "data" / "task1" / "events.json").read_text())["pairs"]["C"]
    assert evidence["t1-c-slack-policy"]["pair"]["coincide_steps"] < t1["coincide_steps"]
    # like for like: IVKC's effort has weight 1, so its slack weight is divided by w_E
    for key in ("t1-c-slack-policy", "t2-c-slack-policy"):
        w = emdm.load_scenario(evidence[key]["task"]).weights
        own = evidence[key]["controller_overrides"]
        assert own == {"C-IVKC": {"weights.slack": w.slack / w.effort}}, key
    assert events["controllers"]["C-EMDM"]["singular"]["elbow_flips"]
    text = (root / "index.html").read_text(encoding="utf-8")
    # the brief's pair first, its stall the policy's (where and when), then the like-for-like
    # runs
    assert "Only C-EMDM, which has a slack in the brief, leaves the straight line" in text
    assert re.search(
        r"Under our task scaling, it stalls .{0,400}? short of the goal from .{0,400}?\. With a "
        r"free slack each, both arrive: C-IVKC sooner",
        text,
    ), "the stall told before the free-slack runs"
    scaled_at_start = events["controllers"]["C-IVKC"]["scaling"]["initial_alpha"] < 1
    assert ("C-IVKC cannot meet its task constraint from step 0" in text) == scaled_at_start
    assert "evidence" in text.lower()


def test_the_page_numbers_its_tables_without_gaps(report):
    """The page's tables are numbered I, II, ... with none skipped: the paper's first, then the
    page's own by appearance (the pitch's tables, shown on no page, took V and VII once)."""
    from emdm.outputs.report.document import roman

    root, _ = report
    text = (root / "index.html").read_text(encoding="utf-8")
    numbers = re.findall(r"<caption>Table ([IVXL]+)\. ", text)
    assert sorted(numbers, key=[roman(i) for i in range(1, 30)].index) == [
        roman(i) for i in range(1, len(numbers) + 1)
    ], numbers


def test_evidence_json_says_where_every_evidence_row_is_recorded(report):
    """A reader of the data finds each of Table I's evidence rows (indented under the run each
    changes) from evidence.json: an entry of its runs, or (A2a, A2b) the weight grid's first run
    that misses the goal and its finer step (under ``rows``, no table number: 262 met Table I's
    rows under a stale ``table_ii``)."""
    root, _ = report
    evidence = json.loads((root / "data" / "evidence.json").read_text())
    index = evidence["rows"]
    paper = (root / "paper" / "paper.tex").read_text(encoding="utf-8")
    table = paper[paper.index(r"\label{tab:outcomes}") :].split(r"\end{table}", 1)[0]
    rows = re.findall(r"^\$\\quad\$(A\d[a-z]?): ", table, flags=re.M)
    assert rows and sorted(rows) == sorted(index), (rows, index)
    for label, where in index.items():
        file, what = where.split(": ", 1)
        if file == "evidence.json":
            assert what.removeprefix("runs/") in evidence["runs"], label
            continue
        grid = json.loads((root / "data" / file).read_text())["runs"]
        miss = next(r for r in grid if not r["reached"])
        assert ("finer_dt" in what) == (label == "A2b") and miss["finer_dt"]["nominal"], label


def test_the_pair_coincidence_of_task1_c_is_detected(report):
    root, _ = report
    events = json.loads((root / "data" / "task1" / "events.json").read_text())
    pair = events["pairs"]["C"]
    assert pair["coincide_steps"] == pair["coincide_determined_steps"] > 0
    assert pair["coincide_scaled_steps"] == events["controllers"]["C-EMDM"]["scaling"]["steps"]


def test_every_animation_states_its_speed(report):
    root, _ = report
    text = (root / "index.html").read_text(encoding="utf-8")
    anims = json.loads((root / "data" / "animations.json").read_text())["animations"]
    assert len(anims) == 4
    for a in anims.values():
        assert (root / "animations" / a["task"] / a["files"][0]).is_file()
        assert a["playing_s"] <= 4.0 + 1e-9
    assert text.count("× real time") == 4


def test_no_template_placeholder_is_left_in_the_page(report):
    """Every template's expressions are rendered: none of either environment's delimiters (the
    LaTeX templates' ``((( )))`` or the page's ``{{ }}``) reaches the page or the sources."""
    root, _ = report
    page = (root / "index.html").read_text(encoding="utf-8")
    for mark in ("(((", "((*", "{{", "{%"):
        assert mark not in page, mark
    for name in ("paper.tex", "pitch.tex"):  # (TeX itself writes "}}" and "{{")
        text = (root / "paper" / name).read_text(encoding="utf-8")
        for mark in ("(((", "((*", "((="):
            assert mark not in text, (name, mark)


def test_everything_is_local(report):
    root, page = report
    assert page.sources, "no images"
    for src in page.sources:
        assert not src.startswith(("http:", "https:", "//")) and (root / src).is_file(), src
    for href in page.links:
        if href.startswith("#"):
            continue
        assert not href.startswith(("http:", "https:", "//")), href
        assert (root / href).exists(), href
    prov = json.loads((root / "provenance.json").read_text())
    assert prov["mode"] == "quick" and prov["wall_time_s"] > 0 and "jinja2" in prov["packages"]


def test_without_a_tex_engine_the_study_says_how_to_compile(tmp_path, monkeypatch):
    from emdm.outputs.report import render

    monkeypatch.setattr(render.shutil, "which", lambda _name: None)
    said: list[str] = []
    assert compile_documents(tmp_path, said.append)["engine"] is None
    assert len(said) == 1 and "pdflatex paper.tex" in said[0] and str(tmp_path) in said[0]
    # the study compiles in its staging folder, gone after the swap: the hint names the result's
    final = tmp_path / "results" / "paper"
    said.clear()
    compile_documents(tmp_path / ".staging" / "paper", said.append, final=final)
    assert str(final) in said[0] and ".staging" not in said[0]


def test_the_page_loads_in_a_real_browser(report):
    driver = headless_chromium(1200, 900)
    root, page = report
    try:
        driver.get((Path(root) / "index.html").as_uri())
        driver.execute_script("window.scrollTo(0, document.body.scrollHeight)")
        state = driver.execute_async_script("""
            const done = arguments[arguments.length - 1];
            const images = Array.from(document.images);
            Promise.all(images.map(i => i.complete ? null : new Promise(r => {
                i.onload = r; i.onerror = r; }))).then(() => done(images.map(i => [
                i.getAttribute('src'), i.complete, i.naturalWidth])));
        """)
        assert len(state) == len(page.sources)
        broken = [src for src, complete, width in state if not complete or width == 0]
        assert not broken, broken
        errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
        assert not errors, errors
        assert driver.title.startswith("emdm report")
    finally:
        driver.quit()


def test_the_authors_sign_the_paper_the_pitch_and_the_page(report, tmp_path):
    """``emdm report --author`` (the session's quick report has two): the names, TeX-escaped, on
    the paper's and the pitch's title pages and the page; ``--title`` replaces the title."""
    root, _ = report
    paper = (root / "paper" / "paper.tex").read_text(encoding="utf-8")
    pitch = (root / "paper" / "pitch.tex").read_text(encoding="utf-8")
    page = (root / "index.html").read_text(encoding="utf-8")
    signed = r"Émilie du Châtelet, R\&D 100\% \$x\_1\$ \#2"
    assert signed in paper and signed in pitch
    assert "Anonymous authors" not in paper
    assert "Émilie du Châtelet, R&amp;D 100% $x_1$ #2</p>" in page
    from emdm.outputs.report.config import BYLINE, byline
    from emdm.outputs.report.render import write_latex

    copy = tmp_path / "report"
    shutil.copytree(root, copy)
    (copy / BYLINE).write_text(json.dumps(byline([], "A Title of Our Own")), encoding="utf-8")
    write_latex(copy)
    retitled = (copy / "paper" / "paper.tex").read_text(encoding="utf-8")
    assert r"\title{A Title of Our Own}" in retitled and "Anonymous authors" in retitled
    for bad, message in ((["ok", " "], "must not be empty"), (["x" * 121], "at most 120")):
        with pytest.raises(ValueError, match=message):
            byline(bad)


def test_a_bad_title_is_one_line_and_nothing_runs(tmp_path, capsys):
    from emdm.cli import main

    out = tmp_path / "r"
    assert main(["report", "--quick", "--title", "a\nb", "--out", str(out)]) == 2
    assert "--title: the title must be one line" in capsys.readouterr().err
    assert not out.exists()


def test_the_byline_from_a_config_file(tmp_path, capsys):
    """``emdm report --config FILE`` reads ``authors`` and ``title``; a bad file is one line with
    exit status 2 naming the file and the key, before anything runs."""
    from emdm.cli import main
    from emdm.errors import ScenarioError
    from emdm.outputs.report.config import read_byline

    good = tmp_path / "byline.toml"
    good.write_text('authors = ["Ada Lovelace", "Alan Turing"]\ntitle = "Ours"\n', "utf-8")
    assert read_byline(good) == {"authors": ["Ada Lovelace", "Alan Turing"], "title": "Ours"}
    cases = {
        'authors = "Ada"': "authors: must be a list",
        "authors = [1]": "authors: must be a list",
        'title = ["x"]': "title: must be a string",
        'title = "a\\nb"': "title: the title must be one line",
        'authors = [" "]': "authors: an author's name must not be empty",
        'author = ["Ada"]': "author: unknown key",
        "authors = [": "not a valid TOML file",
    }
    for text, message in cases.items():
        bad = tmp_path / "bad.toml"
        bad.write_text(text, "utf-8")
        with pytest.raises(ScenarioError, match=message):
            read_byline(bad)
        out = tmp_path / "r"
        assert main(["report", "--quick", "--config", str(bad), "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert f"{bad}: " in err and message in err and len(err.strip().splitlines()) == 1
        assert not out.exists()
    with pytest.raises(ScenarioError, match="cannot be read"):
        read_byline(tmp_path / "missing.toml")


def test_the_derivative_check_finds_a_wrong_jacobian(monkeypatch):
    """The paper's 'J and J_m match central differences within X at every state' is measured
    on every state of a run, and a Jacobian off by 1e-6 at one state shows in it."""
    from emdm.core.arm import Kinematics, PlanarArm
    from emdm.outputs.report import explain

    run = emdm.simulate(emdm.load_scenario("task1", {"motion.max_time": 1.0}), "C-EMDM")
    right = explain.derivatives(run)
    assert right["states"] == run.q.shape[0]
    assert 0 < right["max_error_J"] < 1e-8 and 0 < right["max_error_Jm"] < 1e-8
    exact = PlanarArm.kinematics
    odd = run.q[run.q.shape[0] // 2]

    def wrong(self: PlanarArm, q: np.ndarray) -> Kinematics:
        kin = exact(self, q)
        if np.array_equal(q, odd):  # one state's J_m, 1e-6 off
            return Kinematics(p=kin.p, J=kin.J, m=kin.m, Jm=kin.Jm + 1e-6)
        return kin

    monkeypatch.setattr(PlanarArm, "kinematics", wrong)
    found = explain.derivatives(run)
    assert found["max_error_Jm"] == pytest.approx(1e-6, rel=1e-3)
    assert found["max_error_J"] == right["max_error_J"]


def test_limits_and_pair_events_per_joint_and_over_a_common_window():
    """The excursion past each joint's limits, and a pair's mean manipulability over the states
    both runs have, from the records (the paper quotes them for Task 2)."""
    from emdm.outputs.report import explain

    sc = emdm.load_scenario("task2")
    a, b = emdm.simulate(sc, "C-EMDM"), emdm.simulate(sc, "C-IVKC")
    states = min(a.q.shape[0], b.q.shape[0])
    ev = explain.pair_events(a, b)
    assert ev["common_until_t"] == a.t[states - 1]
    assert ev["mean_m_common"]["C-EMDM"] == pytest.approx(a.m[:states].mean(), rel=1e-15)
    assert ev["mean_m_common"]["C-IVKC"] == pytest.approx(b.m[:states].mean(), rel=1e-15)
    same = explain.pair_events(a, a)
    assert same["mean_m_common"]["C-EMDM"] == pytest.approx(emdm.metrics(a)["mean_manipulability"])
    uc = emdm.simulate(sc, "UC-IVKC")
    lim = explain.limits(uc)
    over = np.maximum(uc.q - sc.arm.q_max, sc.arm.q_min - uc.q).max(axis=0)
    assert lim["excess_by_joint"] == [max(float(x), 0.0) for x in over]
    assert max(lim["excess_by_joint"]) == lim["max_excess"] > 0
    assert explain.limits(a)["excess_by_joint"] == [0.0, 0.0]  # C-: within the limits
    # a pinned episode names its first and last step on the bound, as the CSV's rows show them
    pin = explain.pinned(a)[0]
    j, side = pin["joint"] - 1, 1 if pin["side"] == "upper" else -1
    k0, k1 = np.searchsorted(a.t, [pin["t0"], pin["t_last"]])
    assert np.all(a.active[k0 : k1 + 1, j] == side) and k1 - k0 + 1 == pin["steps"]
    assert a.active[k1 + 1, j] != side and pin["t1"] == a.t[k1 + 1]


def test_a_paper_that_does_not_compile_replaces_nothing(
    quick_report, tmp_path, monkeypatch, capsys
):
    """With a TeX engine that fails, the report is refused in one line (exit 2): the earlier
    report stays byte for byte, and the failing source and its log are kept where it says."""
    from emdm.cli import main
    from emdm.outputs.report import render

    out = tmp_path / "report"
    shutil.copytree(quick_report, out)
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    monkeypatch.setattr(render, "tex_engine", lambda: "pdflatex")
    monkeypatch.setattr(render, "_command", lambda engine, name: ["false", name])
    assert main(["report", "--quick", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "paper.tex did not compile; nothing was replaced" in err[0], err
    kept = Path(err[0].rsplit(" ", 1)[1])
    assert (kept / "paper.tex").read_text(encoding="utf-8").startswith("%")
    shutil.rmtree(kept)
    after = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    assert after == before


def test_the_story_reads_typed_records_that_the_producers_write():
    """Issue 24, item 6: each literal key type is its dataclass's fields, the producers write
    every field (a renamed key fails here, not when the paper renders), and the evidence keys
    are the configured evidence runs."""
    import dataclasses
    import typing

    from emdm.outputs.report import explain
    from emdm.outputs.report.config import EVIDENCE
    from emdm.outputs.report.findings import records as r

    def names(cls):
        return {f.name for f in dataclasses.fields(cls)}

    assert set(typing.get_args(r.MetricKey)) == names(r.Outcomes)
    assert set(typing.get_args(r.EventKey)) == names(r.RunEvents)
    assert set(typing.get_args(r.PairKey)) == names(r.PairEvents)
    assert set(typing.get_args(r.EvidenceKey)) == {ev.key for ev in EVIDENCE}
    assert set(typing.get_args(r.FrontKey)) == names(r.FrontStep)
    assert set(typing.get_args(r.GridKey)) == names(r.GridRun)
    assert set(typing.get_args(r.SeedKey)) == names(r.SeedRun)
    assert set(typing.get_args(r.GeometryKey)) == names(r.Geometry)
    assert set(typing.get_args(r.MmcKey)) == names(r.MmcRow)
    assert set(typing.get_args(r.PaperKey)) == names(r.PaperRow)
    assert set(typing.get_args(r.RunOutcome)) <= names(r.Outcomes) & names(r.GridRun)
    sc = emdm.load_scenario("task2", {"motion.max_time": 2.0})
    a, b = emdm.simulate(sc, "C-EMDM"), emdm.simulate(sc, "C-IVKC")
    assert names(r.Outcomes) <= set(emdm.metrics(a))
    assert names(r.RunEvents) <= set(explain.run_events(a))
    assert names(r.PairEvents) <= set(explain.pair_events(a, b))
    geometry = explain.geometry(sc, a.p[0])
    assert names(r.Geometry) <= set(geometry)
    assert all(names(r.GoalSolution) <= set(s) for s in geometry["solutions"])


def test_a_renamed_record_field_stops_the_story_before_any_sentence(quick_report, tmp_path):
    """The records are typed and checked once, when the story starts: a field that is missing
    or of the wrong type is named in one line (file, key), before anything is rendered."""
    from emdm.outputs.report.findings import Story
    from emdm.outputs.report.findings.records import RecordError, Records
    from emdm.outputs.report.trace import Data

    root = tmp_path / "report"
    shutil.copytree(quick_report / "data", root / "data")
    records = Records.load(Data(root))
    assert records.outcomes["task1"]["C-EMDM"].reached is True
    assert records.pairs["task2"]["C"].common_until_t > 0
    assert records.evidence["t2-c-slack-policy"].runs["C-IVKC"]["reached"] is True
    # the solver labs and Task 1's Pareto records are typed too (fronts at k = 0 first)
    assert records.fronts["UC-EMDM"][0].k == 0 and records.fronts["C-EMDM"][0].degenerate
    assert records.grids["UC-EMDM"] and records.labs["task2-lab-C-EMDM"].solvers
    assert "task1" not in records.geometry  # three links: no geometry record
    assert sum(s.within_limits for s in records.geometry["task2"].solutions) == 1
    assert records.mmc is not None and records.mmc.paper is not None  # the benchmark, typed
    assert set(records.mmc.paper.results["panda"]) >= {"RRMC", "MMC"}
    mmc_file = root / "data" / "mmc.json"
    mmc = json.loads(mmc_file.read_text(encoding="utf-8"))
    mmc["paper"]["results"]["ur5"]["MMC"]["failure_rate"] = None
    mmc_file.write_text(json.dumps(mmc), encoding="utf-8")
    with pytest.raises(RecordError, match=r"paper/results/ur5/MMC/failure_rate: expected float"):
        Records.load(Data(root))
    mmc_file.write_text(json.dumps(json.loads((quick_report / "data" / "mmc.json").read_text())))
    metrics_file = root / "data" / "task2" / "metrics.json"
    data = json.loads(metrics_file.read_text(encoding="utf-8"))
    entry = data["controllers"]["C-IVKC"]
    entry["mean_m"] = entry.pop("mean_manipulability")
    metrics_file.write_text(json.dumps(data), encoding="utf-8")
    with pytest.raises(RecordError, match=r"task2/metrics.json#controllers/C-IVKC: no field "):
        Story(Data(root))
    entry["mean_manipulability"] = "high"
    metrics_file.write_text(json.dumps(data), encoding="utf-8")
    with pytest.raises(RecordError, match=r"C-IVKC/mean_manipulability: expected float"):
        Story(Data(root))
    # the scenario as its runs recorded it is read back by its own schema
    assert records.scenarios["task1"].motion.dt > 0
    entry["mean_manipulability"] = 0.1
    data["scenario"]["motion"]["step"] = data["scenario"]["motion"].pop("dt")
    metrics_file.write_text(json.dumps(data), encoding="utf-8")
    with pytest.raises(RecordError, match=r"task2/metrics.json#scenario: .*step"):
        Records.load(Data(root))


def test_each_shared_claim_is_written_once_and_said_by_the_paper_and_the_pitch(quick_report):
    """Issue 24, item 6: a claim the abstract, the sections, the conclusion and the slides all
    make comes from one method (findings/claims.py), so the paper and the pitch say it in the
    same words with the same numbers."""
    from emdm.outputs.report.findings import Story
    from emdm.outputs.report.trace import Data, cap

    story = Story(Data(quick_report))
    paper = (quick_report / "paper" / "paper.tex").read_text(encoding="utf-8")
    pitch = (quick_report / "paper" / "pitch.tex").read_text(encoding="utf-8")
    claims = {  # (as the paper says it, as the talk says it: without the evidence label)
        # (the abstract says "the mean m", m named just before; the talk names it)
        "dexterity_gain": (story.dexterity_gain(named=False), story.dexterity_gain()),
        # (ivkc_with_slack: the talk draws it, slide 9's chart, from the same record)
        "uc_slack_saving": (story.uc_slack_saving(), story.uc_slack_saving()),
    }
    for name, (written, said) in claims.items():
        assert written and said, name
        assert any(render_latex(c) in paper for c in (written, cap(written))), name
        assert any(render_latex(c) in pitch for c in (said, cap(said))), name
    assert render_latex(story.dexterity_gain(named=False)) in paper.split(r"\end{abstract}")[0]


def test_the_pareto_bound_on_late_fronts_is_the_largest_of_them(quick_report):
    """Fifteenth reading: 'every C-EMDM optimum has M < 0 (at most X)' must give the largest
    M of every late front, not the first one's."""
    from emdm.outputs.report.findings import Story
    from emdm.outputs.report.trace import Data

    story = Story(Data(quick_report))
    steps = story.rec.fronts["C-EMDM"]
    late = [i for i, st in enumerate(steps) if i > 0 and st.M_max < 0]
    paragraphs = [p for s in story.build().sections for p in s.paragraphs]
    from emdm.outputs.report.trace import PageOnly

    def segments(parts):  # (the bound is on the page only since readings 190-191)
        for seg in parts:
            yield from segments(seg.parts) if isinstance(seg, PageOnly) else (seg,)

    said = [
        seg
        for p in paragraphs
        for seg in segments(p)
        if getattr(seg, "src", "").endswith("/M_max") and "task1-pareto-C-EMDM" in seg.src
    ]
    if not late or late != list(range(late[0], len(steps))):
        assert not said  # no such claim without it holding
        return
    assert len(said) == 1
    top = max(steps[i].M_max for i in late)
    assert float(said[0].text) == pytest.approx(top, rel=0.06)  # the bound, to its 2 digits


@pytest.mark.parametrize("gain", [0.002, 0.05])
def test_the_whole_run_sweep_is_read_against_the_nominal_ratio(quick_report, tmp_path, gain):
    """Nineteenth reading: Fig. 2's whole-run panels were not interpreted. The answer quotes the
    nominal run's effort and the dearest larger ratio that still arrives, and says the mean m
    levels off only when the larger ratios add less than 1 %. The quick grid has no arriving
    ratio above the nominal one, so two are added to a copy of its record."""
    import json
    import shutil

    from emdm.outputs.report.findings import Story
    from emdm.outputs.report.trace import Data, render_latex

    root = tmp_path / "report"
    shutil.copytree(quick_report / "data", root / "data")
    path = root / "data" / "task1-pareto-UC-EMDM" / "weight_grid.json"
    record = json.loads(path.read_text(encoding="utf-8"))
    assert Story(Data(root)).whole_runs_levelled() == []  # nothing above the nominal arrives
    nominal = next(r for r in record["runs"] if r["w_manip"] == 5.0)
    for factor, effort, m in ((2.0, 1.3, 1.0 + gain / 2), (4.0, 2.9, 1.0 + gain)):
        run = dict(nominal, w_manip=5.0 * factor)
        run["total_effort"] = nominal["total_effort"] * effort
        run["mean_manipulability"] = nominal["mean_manipulability"] * m
        record["runs"].append(run)
    path.write_text(json.dumps(record), encoding="utf-8")
    said = Story(Data(root)).whole_runs_levelled()
    efforts = [float(s.text) for s in said if getattr(s, "src", "").endswith("/total_effort")]
    assert efforts == [
        pytest.approx(nominal["total_effort"], rel=5e-3),
        pytest.approx(nominal["total_effort"] * 2.9, rel=5e-3),
    ]
    text = render_latex(said)
    assert ("levels off" in text) == (gain < 0.01)
    assert f"{100 * gain:+.1f}" in text


def test_the_sweep_levels_off_where_a_smaller_ratio_comes_within_one_percent(
    quick_report, tmp_path
):
    """Readings 166-167: the nominal ratio had been called the knee, yet a smaller ratio came
    within 1 % of its mean m for less effort. Where one does, Section III-B names it and the
    conclusion recommends it with the effort saved; where none does (the quick grid), neither
    does. The ratios are added to a copy of the record."""
    import json
    import shutil

    from emdm.outputs.report.findings import Story
    from emdm.outputs.report.trace import Data, render_html, render_latex

    root = tmp_path / "report"
    shutil.copytree(quick_report / "data", root / "data")
    path = root / "data" / "task1-pareto-UC-EMDM" / "weight_grid.json"
    record = json.loads(path.read_text(encoding="utf-8"))
    nominal = next(r for r in record["runs"] if r["w_manip"] == 5.0)

    def conclusion() -> str:
        story = Story(Data(root))
        return " ".join(render_latex(p) for p in story.conclusion().paragraphs)

    assert "We would lower" not in conclusion()
    for w_manip, effort, m in ((1.5, 0.8, 0.995), (0.5, 0.7, 0.95), (20.0, 2.0, 1.001)):
        run = dict(nominal, w_manip=w_manip, reached=True)
        run["total_effort"] = nominal["total_effort"] * effort
        run["mean_manipulability"] = nominal["mean_manipulability"] * m
        record["runs"].append(run)
    path.write_text(json.dumps(record), encoding="utf-8")
    story = Story(Data(root))
    said = render_latex(story.whole_runs_levelled())
    assert "$w_M$ = 1.5 comes within 1\\% of the nominal" in said  # not 0.5: 5 % below
    assert "We would lower UC-EMDM's $w_M$ from 5 to 1.5 for Task 1's goal." in conclusion()
    page = " ".join(render_html(p) for p in Story(Data(root)).conclusion().paragraphs)
    assert re.search(
        r"with <span[^>]*>20%</span> less effort", page
    )  # the reason: Section III-B's in the paper, the page's here


def test_the_parameters_sentence_states_one_value_where_every_joint_shares_it():
    """Section II gives one |q_j| bound, one damper (i_j, s_j, K_safe), one q_dot_max per task,
    one K_p and one slack bound: true only while every joint (and axis) shares them."""
    for task in ("task1", "task2"):
        sc = emdm.load_scenario(task)
        arm, damper, motion = sc.arm, sc.damper, sc.motion
        for values in (
            arm.q_max,
            -arm.q_min,
            arm.qd_max,
            -arm.qd_min,
            damper.influence,
            damper.stop,
            damper.gain,
            motion.kp,
            sc.slack.max,
            -sc.slack.min,
        ):
            assert np.all(np.asarray(values) == np.asarray(values)[0]), (task, values)
        assert sc.slack.max[0] == -sc.slack.min[0]  # "delta_max = -delta_min"
        if task == "task2":  # the bounds, the damper, K_p and the slack are both tasks' own
            one = emdm.load_scenario("task1")
            assert arm.q_max[0] == one.arm.q_max[0] and damper.stop[0] == one.damper.stop[0]
            assert damper.influence[0] == one.damper.influence[0]
            assert damper.gain[0] == one.damper.gain[0] and motion.kp[0] == one.motion.kp[0]
            assert sc.slack.max[0] == one.slack.max[0] and sc.weights == one.weights
            assert (motion.dt, motion.tolerance, motion.max_time) == (
                one.motion.dt,
                one.motion.tolerance,
                one.motion.max_time,
            )


def test_units_stay_lower_case_in_small_caps_captions():
    """IEEE sets table captions in small caps: a unit is wrapped in \\textnormal, or the metre
    reads as the manipulability rate M (and ms as MS)."""
    from emdm.outputs.report.trace import Num, Unit, sentence

    assert render_latex(sentence("(", Unit("m²"), ")")) == r"(\textnormal{m\textsuperscript{2}})"
    assert render_latex([Num("0.05", "f", ("a",), ".2f", unit="s")]).endswith(r"~\textnormal{s}")


def test_run_labels_keep_their_case_in_captions():
    """Table II's paired runs are A2a and A2b: in a caption their letters stay lower-case, and each
    label names exactly one run of the table's list."""
    from emdm.outputs.report.findings.base import ABLATIONS, FINER_STEP, GRID_MISS, run_label
    from emdm.outputs.report.trace import Upright, sentence

    assert render_latex(sentence(Upright(run_label(GRID_MISS)))) == r"\textnormal{A2a}"
    assert run_label(FINER_STEP) == "A2b" and run_label("t1-uc-no-manip") == "A1"
    flat = [k for e in ABLATIONS for k in (e if isinstance(e, tuple) else (e,))]
    labels = [run_label(k) for k in flat]
    assert len(set(labels)) == len(flat)
    with pytest.raises(KeyError):
        run_label("no-such-run")


def test_the_terms_table_sets_each_controllers_terms_in_the_one_program(report):
    """Table I gives each controller's terms in program (3) (readings 221, 222: one displayed
    program left the reader to rebuild each controller's): from each controller's terms on each
    task's arm, the slack only on the non-redundant arm's EMDM, the box and the task scale only
    in the C- programs, the weights the scenario's. The formulation's displays are numbered
    alike in the paper (its labels' order) and the page."""
    from emdm.outputs.report.trace import EQUATIONS

    folder = Path(emdm.outputs.report.__file__).parent / "templates"
    tex = (folder / "formulation.tex.j2").read_text(encoding="utf-8")
    assert tuple(re.findall(r"\\label\{eq:(\w+)\}", tex)) == EQUATIONS
    html = (folder / "formulation.html.j2").read_text(encoding="utf-8")
    assert re.findall(r'<div class="eq">\((\d)\)', html) == [
        str(i + 1) for i in range(len(EQUATIONS))
    ]
    root, page = report
    weights = json.loads((root / "data/task1/metrics.json").read_text())["scenario"]["weights"]
    rows = {row[0]: row[1:] for row in page.tables["tab-programs"][1:]}
    assert list(rows) == ["UC-IVKC", "UC-EMDM", "C-IVKC", "C-EMDM", "free slack"]
    for name, (w_e, w_m, slack, box) in rows.items():
        if name == "free slack":
            # its bound the records' (the free-slack runs' overrides: 10^3, "103" as text),
            # where it acts in the cell (237, 238: simulated at every step)
            power = round(np.log10(FREE_SLACK))
            assert (w_e, w_m, slack, box) == (
                "same",
                "same",
                f"|δi| ≤ 10{power} if α* < 1",
                "(1), 1",
            )
            continue
        is_emdm = "EMDM" in name
        assert (w_e, w_m) == (
            (f"{weights['effort']:g}", f"{weights['manipulability']:g}") if is_emdm else ("1", "0")
        ), name
        # the slack only on the non-redundant arm's EMDM: the cell names both tasks
        assert slack == ("T1: {0}; T2: [δmin, δmax]" if is_emdm else "{0}"), (name, slack)
        assert box == ("(1), (2)" if name.startswith("C-") else "none, 1"), (name, box)


def test_a_diverging_runs_digits_are_not_printed(report):
    """Readings 177, 235-248: the run that diverges (A2a) gives digits its readers' simulators
    could not reproduce, so Table II prints "miss" and dashes for it, and its caption says why;
    its finer-step twin (A2b) arrives and keeps its digits."""
    root, page = report
    rows = {row[0]: row[1:] for row in page.tables["tab-outcomes"][1:] if len(row) > 1}
    a2a = next(v for k, v in rows.items() if k.strip().startswith("A2a"))
    a2b = next(v for k, v in rows.items() if k.strip().startswith("A2b"))
    grid = json.loads((root / "data/task1-pareto-UC-EMDM/weight_grid.json").read_text())
    assert any(not r["reached"] for r in grid["runs"])
    assert a2a[0] == "miss" and a2a[1:4] == ["–", "–", "–"], a2a
    assert a2a[4].isdigit(), a2a  # its scaled steps: a count, exact whatever the rounding
    assert all(c not in ("–", "miss") for c in a2b[:4]), a2b
    assert "never settles, so its digits (–) depend on rounding" in (root / "index.html").read_text(
        encoding="utf-8"
    )


def test_references_are_numbered_alike_in_the_paper_and_the_page():
    """The bibliography's order (IEEE: order of first citation) is one list, REFERENCES: the
    LaTeX bibliography and the page's list give the same order, so [n] means one work in both."""
    from emdm.outputs.report.trace import REFERENCES

    folder = Path(emdm.outputs.report.__file__).parent / "templates"
    tex = (folder / "references.tex.j2").read_text(encoding="utf-8")
    assert tuple(re.findall(r"\\bibitem\{(\w+)\}", tex)) == REFERENCES
    html = (folder / "index.html.j2").read_text(encoding="utf-8")
    assert tuple(re.findall(r'<li id="ref-(\w+)">', html)) == REFERENCES
    # the page's formulation cites through the same list, never by a typed number
    assert not re.search(r"\[\d\]", (folder / "formulation.html.j2").read_text(encoding="utf-8"))


def test_a_scaled_steps_front_is_also_drawn_under_the_free_slack(report):
    """C-EMDM's first front is one point (a scaled step): the same state under the free slack
    is solved for every ratio too, at full task scale, and how many optima it has is recorded."""
    root, _ = report
    data = json.loads((root / "data" / "task1-pareto-C-EMDM" / "pareto.json").read_text())
    fronts = json.loads((root / "data" / "task1-pareto-C-EMDM" / "fronts.json").read_text())
    first = data["steps"][0]
    assert all(p["alpha"] < 1.0 for p in first["points"])
    slack = first["slack_points"]
    assert len(slack) == len(first["points"]) and all(p["alpha"] == 1.0 for p in slack)
    assert all(p["kkt"] <= 1e-9 for p in slack)
    distinct = {(round(p["E"], 12), round(p["M"], 12)) for p in slack}
    assert fronts["steps"][0]["slack_distinct"] == len(distinct)
    assert all("slack_points" not in s for s in data["steps"][1:] if s["points"][0]["alpha"] == 1)


def test_table_iii_says_which_solvers_iterate_without_evaluating(report):
    """it./ev. reads oddly where iterations outnumber evaluations (a trust-region method's short
    steps evaluate nothing): the caption names exactly those solvers."""
    root, _ = report
    lab = json.loads((root / "data" / "task2-lab-C-EMDM" / "solvers.json").read_text())
    skip = [
        k for k, r in lab["solvers"].items() if r["median_iterations"] > r["median_evaluations"] > 0
    ]
    paper = (root / "paper" / "paper.tex").read_text(encoding="utf-8")
    caption = paper[: paper.index(r"\label{tab:solvers}")].rsplit(r"\caption{", 1)[1]
    assert ("not every iteration evaluates" in caption) == bool(skip)
    for k in skip:
        assert k in caption.split("not every iteration evaluates")[0].rsplit(";", 1)[1], k


def test_fig2_caption_states_the_swept_ratios_from_the_records(report):
    """The Pareto figure's caption on the page gives both sweeps (the paper has no room): the
    fronts' ratios (per decade) and the whole runs' count, each read from its record (the
    nominal ratio is the circle, in neither count)."""
    root, _ = report
    pareto = json.loads((root / "data" / "task1-pareto-UC-EMDM" / "pareto.json").read_text())
    grid = json.loads((root / "data" / "task1-pareto-UC-EMDM" / "weight_grid.json").read_text())
    nominal = pareto["nominal_ratio"]
    runs = [r["w_manip"] / r["w_effort"] for r in grid["runs"]]
    count = sum(1 for r in runs if r > 0 and not np.isclose(r, nominal))
    page = (root / "index.html").read_text(encoding="utf-8")
    caption = page[page.index("Pareto fronts, effort") :].split("</figcaption>", 1)[0]
    assert "Ratios: 0 and " in caption and f"; 0 and {count} from " in caption


def test_seed_dependent_overruns_and_the_penalty_margin_are_read_from_the_lab(
    quick_report, tmp_path
):
    """Reading 93: cma-es's time is near the control period, so how many programs it overruns
    depends on the seed (6 to 41 of 41), and the paper gave seed 0's count alone. The paper
    and the seed spread now give that range whenever it varies (forced in a copy of the record), and
    the page's penalty weight is the lab's smallest margin over the multipliers (the paper says
    only that the penalty is exact)."""
    import json
    import shutil

    from emdm.outputs.report.findings import Story
    from emdm.outputs.report.trace import Data, render_latex

    root = tmp_path / "report"
    shutil.copytree(quick_report / "data", root / "data")
    path = root / "data" / "task2-lab-C-EMDM" / "solvers.json"
    lab = json.loads(path.read_text(encoding="utf-8"))
    seeded = [k for k, r in lab["solvers"].items() if r.get("seeds")]
    if not seeded:  # the quick lab runs no stochastic solver: one gradient-free row gets seeds
        seeded = [next(k for k, r in lab["solvers"].items() if r["family"] == "gradient-free")]
        row = lab["solvers"][seeded[0]]
        row["seeds"] = [
            {
                "seed": i,
                "median_evaluations": row["median_evaluations"],
                "failures": 0,
            }
            for i in range(5)
        ]

    def spread() -> str:
        rows = Story(Data(root)).solvers("task2-lab-C-EMDM")
        return render_latex(Story(Data(root)).seed_spread("task2-lab-C-EMDM", rows))

    for name in seeded:
        for i, s in enumerate(lab["solvers"][name]["seeds"]):
            s.update(max_abs_gap=0.0, max_violation=0.0, over_period=i)
        lab["solvers"][name]["over_period"] = 2  # seed 0's count, in the table and the text
        path.write_text(json.dumps(lab), encoding="utf-8")
        last = len(lab["solvers"][name]["seeds"]) - 1
        assert f", 0--{last} overruns" in spread().split(f"{name} stays exact", 1)[1].split(")")[0]
        # the paper's count is then the range over the seeds (readings 174, 179)
        story = Story(Data(root))
        rows = story.solvers("task2-lab-C-EMDM")
        said = render_latex(story.overruns("task2-lab-C-EMDM", [name], rows))
        assert f"on 0--{last} of" in said and said.endswith(f"programs (seeds 0--{last})"), said
        for s in lab["solvers"][name]["seeds"]:
            s.update(over_period=3)  # the same count for every seed: no range
        path.write_text(json.dumps(lab), encoding="utf-8")
        assert "overruns" not in spread().split(f"{name} stays exact", 1)[1].split(")")[0]
        story = Story(Data(root))
        said = render_latex(
            story.overruns("task2-lab-C-EMDM", [name], story.solvers("task2-lab-C-EMDM"))
        )
        assert "seeds" not in said, said

    page = " ".join((quick_report / "index.html").read_text(encoding="utf-8").split())
    margin = lab["challenges"]["feature_ranges"]["penalty_margin"][0]
    mantissa, exponent = f"{margin:.2g}".split("e+")
    assert f"at least {mantissa}×10<sup>{int(exponent)}</sup>" in re.sub(
        r"<span[^>]*>|</span>", "", page
    )


def test_table_iii_rows_are_the_convergence_figures_legend(report):
    """The convergence figure has no legend of its own: each solver it draws has its line and
    marker beside its name in Table III, drawn with the figure; a solver it does not draw (the
    QP methods: no objective evaluations) keeps a blank of the same width. Its panels are Task
    2's lab, read from its histories.json. The figure is on the page only (readings 176-177),
    so the paper's Table III carries no glyphs and cites no figure; the page's does both."""
    from emdm.outputs.report.findings.solvers import CONVERGENCE_IN_PAPER

    root, page = report
    histories = {
        "task2": json.loads((root / "data" / "task2-lab-C-EMDM" / "histories.json").read_text())
    }
    drawn = {
        name
        for name, entry in histories["task2"]["solvers"].items()
        if any(h.get("evaluations", 0) >= 1 for h in entry["histories"].get("least dexterous", ()))
    }
    assert drawn and (root / "paper" / "figures" / "convergence.png").exists()
    glyphs = root / "paper" / "figures" / "glyphs"
    assert {p.stem for p in glyphs.glob("*.png")} == drawn
    paper = (root / "paper" / "paper.tex").read_text(encoding="utf-8")
    table = paper[paper.index(r"\label{tab:solvers}") :].split(r"\end{tabular}")[0]
    lab = histories["task2"]["solvers"]
    for name in lab:
        row = next(
            ln for ln in table.splitlines() if re.search(rf"(^|}}){re.escape(name)}\*? &", ln)
        )
        assert (f"figures/glyphs/{name}}}" in row) == (name in drawn and CONVERGENCE_IN_PAPER)
    for name in drawn & set(lab):
        assert f"paper/figures/glyphs/{name}.png" in page.sources
    assert (r"\label{fig:convergence}" in paper) == CONVERGENCE_IN_PAPER
    # the caption names the table's solvers the figure has no curve of
    html = (root / "index.html").read_text(encoding="utf-8")
    missing = [name for name in lab if name not in drawn]
    assert (f"; {', '.join(missing)}: none;" in html) == bool(missing)


def test_the_single_point_claim_is_made_only_where_measured(quick_report, tmp_path):
    """'At that alpha the admissible set was a single point' (the pitch's backup, the paper's
    Section III-D) stands on the Task 1 lab's measured widths: a wider set, or no measurement,
    and neither document says it."""
    from emdm.outputs.report.pitch import Pitch
    from emdm.outputs.report.render import document
    from emdm.outputs.report.trace import Data

    root = tmp_path / "report"
    shutil.copytree(quick_report, root)
    path = root / "data" / "task1-lab-C-EMDM" / "solvers.json"
    lab = json.loads(path.read_text(encoding="utf-8"))
    vertex = lab["challenges"]["scaled_vertex"]
    assert vertex and vertex["max_width"] <= 1e-9  # the quick study's scaled steps: one point
    assert Pitch(Data(root), document(root)).build().single_point

    def said() -> str:
        return " ".join(render_latex(p) for s in document(root).sections for p in s.paragraphs)

    assert "allow only one command: their feasible set is up to" in said()
    vertex["max_width"] = 1e-3  # a segment, not a point
    path.write_text(json.dumps(lab), encoding="utf-8")
    assert not Pitch(Data(root), document(root)).build().single_point
    assert "allow only one command: their feasible set" not in said()


def test_task1_slide_title_says_its_idea_only_where_measured(quick_report, tmp_path):
    """The pitch's Task 1 title is an idea in words ('EMDM pays for dexterity with effort, not
    with tracking') only while both pairs measure it: more m and more effort, arriving within
    one control period of each other; otherwise the slide is titled with the numbers."""
    from emdm.outputs.report.pitch import Pitch
    from emdm.outputs.report.trace import Data

    root = tmp_path / "report"
    shutil.copytree(quick_report, root)
    path = root / "data" / "task1" / "metrics.json"
    metrics = json.loads(path.read_text(encoding="utf-8"))
    runs = metrics["controllers"]
    dt = metrics["scenario"]["motion"]["dt"]

    def title() -> str:
        return render_latex(Pitch(Data(root), document(root)).task1_title())

    holds = all(
        runs[e]["reached"]
        and runs[i]["reached"]
        and runs[e]["mean_manipulability"] > runs[i]["mean_manipulability"]
        and runs[e]["total_effort"] > runs[i]["total_effort"]
        and abs(runs[e]["time_to_goal"] - runs[i]["time_to_goal"]) <= dt + 1e-9
        for i, e in (("UC-IVKC", "UC-EMDM"), ("C-IVKC", "C-EMDM"))
    )
    assert ("not with tracking" in title()) == holds
    runs["C-EMDM"]["time_to_goal"] = runs["C-IVKC"]["time_to_goal"] + 2 * dt  # tracking differs
    path.write_text(json.dumps(metrics), encoding="utf-8")
    assert "not with tracking" not in title() and "dexterity for" in title()


def test_task2_slack_headline_stands_on_its_three_evidence_runs(quick_report, tmp_path):
    """'The slack, not the dexterity term, gets the arm there' (the pitch's Task 2 title and
    third take-away) needs its three evidence runs: C-IVKC arrives with a free slack, C-EMDM
    arrives sooner without the term, C-EMDM with too little slack stalls. A tight-slack run
    that arrives takes the claim off both slides."""
    from emdm.outputs.report.pitch import Pitch
    from emdm.outputs.report.trace import Data

    root = tmp_path / "report"
    shutil.copytree(quick_report, root)
    path = root / "data" / "evidence.json"
    evidence = json.loads(path.read_text(encoding="utf-8"))

    def slides() -> tuple[str, list[str]]:
        built = Pitch(Data(root), document(root)).build()
        return render_latex(built.titles["evidence"]), [
            render_latex(b) for b in built.bullets["takeaways"]
        ]

    tight = evidence["runs"]["t2-c-emdm-tight-slack"]["runs"]["C-EMDM"]
    story = Pitch(Data(root), document(root))
    holds = bool(story.s.ivkc_with_slack() and story.s.emdm_without_term()) and not tight["reached"]
    title, takeaways = slides()
    assert ("not the dexterity term" in title) == holds
    assert any("not the dexterity term" in t for t in takeaways) == holds
    tight["reached"], tight["time_to_goal"] = True, 20.0  # too little slack, yet it arrives
    path.write_text(json.dumps(evidence), encoding="utf-8")
    title, takeaways = slides()
    assert "not the dexterity term" not in title and "what changes it" in title
    assert not any("not the dexterity term" in t for t in takeaways)


def test_the_policy_take_away_is_one_message_from_the_free_slack_runs(quick_report, tmp_path):
    """Take-away 2 says one thing, a slack did better than slowing the tip, with what it
    gained in Task 1 and whether Task 2's C-IVKC arrives with one; 'slowing only keeps the
    path straight' only while the slack wins on every outcome (as the paper's conclusion)."""
    from emdm.outputs.report.pitch import Pitch
    from emdm.outputs.report.trace import Data

    root = tmp_path / "report"
    shutil.copytree(quick_report, root)
    path = root / "data" / "evidence.json"
    evidence = json.loads(path.read_text(encoding="utf-8"))

    def policy() -> str:
        return " ".join(render_latex(b) for b in Pitch(Data(root), document(root)).policy())

    story = Pitch(Data(root), document(root)).s
    gains = story.slack_gains()
    text = policy()
    if gains:
        assert text.startswith("Where the limits forbid the asked tip velocity, a slack did better")
        assert ("let Task 2's C-IVKC arrive" in text) == bool(story.ivkc_with_slack())
        assert ("Slowing only keeps" in text) == (len(gains) == 3)
    slack = evidence["runs"]["t1-c-slack-policy"]["runs"]["C-EMDM"]
    metrics = json.loads((root / "data" / "task1" / "metrics.json").read_text(encoding="utf-8"))
    nominal = metrics["controllers"]["C-EMDM"]
    slack["time_to_goal"] = nominal["time_to_goal"] - 1.0  # faster
    slack["total_effort"] = nominal["total_effort"] * 2.0  # dearer
    slack["mean_manipulability"] = nominal["mean_manipulability"] * 1.1  # more dexterous
    path.write_text(json.dumps(evidence), encoding="utf-8")
    text = policy()
    assert "C-EMDM faster and more dexterous" in text
    assert "Slowing keeps the path straighter" in text and "only" not in text


def test_the_paper_quotes_the_largest_derivative_error_of_every_run(quick_report):
    """Section I's derivative check quotes the largest difference over every run's states and
    both Jacobians (a reader without the brief's code checks the derivatives by it): on the page
    (reading 187 gave its room in the paper to the definitions)."""
    from emdm.outputs.report.findings import Story
    from emdm.outputs.report.trace import Data, render_html

    story = Story(Data(quick_report))
    said = story.derivatives_checked()
    page = (quick_report / "index.html").read_text(encoding="utf-8")
    assert said and render_html(said) in page
    worst = max(
        json.loads((quick_report / "data" / task / "events.json").read_text())["controllers"][c][
            "derivatives"
        ][key]
        for task in ("task1", "task2")
        for c in ("UC-IVKC", "UC-EMDM", "C-IVKC", "C-EMDM")
        for key in ("max_error_J", "max_error_Jm")
    )
    (src,) = [seg.src for seg in said if hasattr(seg, "src")]
    file, path = src.split("#")
    quoted = json.loads((quick_report / file).read_text())
    for key in path.split("/"):
        quoted = quoted[key]
    assert quoted == worst < 1e-8


def test_park_is_called_rrmc_on_the_ur5_only_when_their_outcomes_are_equal(quick_report, tmp_path):
    """Reading 112: the page said 'PARK is RRMC' on the UR5 while its own table showed 31 and
    33 runs not reached. The sentence says 'is' only when every outcome agrees, and otherwise
    'nearly matches', with both counts."""
    from emdm.outputs.report.findings import Story
    from emdm.outputs.report.trace import Data

    root = tmp_path / "report"
    shutil.copytree(quick_report, root)
    path = root / "data" / "mmc.json"
    record = json.loads(path.read_text(encoding="utf-8"))
    if "ur5" not in record["results"]:
        pytest.skip("the quick study has no UR5 benchmark")

    def said() -> str:
        section = Story(Data(root)).beyond()
        return " ".join(render_latex(p) for p in section.paragraphs)

    ur5 = record["results"]["ur5"]
    ur5["PARK"] = dict(ur5["RRMC"])  # equal outcomes
    path.write_text(json.dumps(record), encoding="utf-8")
    assert "PARK is RRMC" in said()
    ur5["PARK"]["not_reached"] = ur5["RRMC"]["not_reached"] - 2
    path.write_text(json.dumps(record), encoding="utf-8")
    text = said()
    assert "PARK is RRMC" not in text and "nearly matches RRMC" in text


def test_the_benchmark_sentences_name_whom_they_compare(quick_report, tmp_path):
    """Reading 114: 'MMC fails least on both arms' while C-EMDM tied it on the UR5, and 'its
    manipulability' (PARK's, by the sentence) quoted RRMC's value. MMC is compared with the
    published table's RRMC and PARK, strictly, and the UR5 value is said to be RRMC's."""
    from emdm.outputs.report.findings import Story
    from emdm.outputs.report.trace import Data

    root = tmp_path / "report"
    shutil.copytree(quick_report, root)
    path = root / "data" / "mmc.json"
    record = json.loads(path.read_text(encoding="utf-8"))
    arms = [a for a in ("panda", "ur5") if a in record["results"]]
    if not arms:
        pytest.skip("the quick study has no benchmark")

    def said() -> str:
        section = Story(Data(root)).beyond()
        return " ".join(render_latex(p) for p in (section.answer, *section.paragraphs))

    for a in arms:
        results = record["results"][a]
        results["MMC"]["failure_rate"] = (
            min(results[c]["failure_rate"] for c in ("RRMC", "PARK")) - 1.0
        )
    path.write_text(json.dumps(record), encoding="utf-8")
    assert "fails less often than RRMC and PARK on both arms" in said()
    results = record["results"][arms[-1]]
    results["MMC"]["failure_rate"] = results["RRMC"]["failure_rate"]  # a tie is not 'less'
    path.write_text(json.dumps(record), encoding="utf-8")
    assert "not always less often than RRMC and PARK" in said()
    if "ur5" in arms:
        assert "RRMC's manipulability is lower than published" in said()


def test_a_solver_is_named_with_what_kind_of_method_it_is():
    """The paper glosses a solver at its first mention from the registry (reading 119: slsqp,
    cma-es were never explained); a solver whose name says it, or one not registered, is left
    as it is."""
    from emdm.outputs.report.findings.base import glossed
    from emdm.solvers import registered_solvers

    assert glossed("slsqp") == "slsqp (sequential quadratic programming)"
    assert glossed("active-set") == "active-set"
    assert glossed("no-such-solver") == "no-such-solver"
    free = [spec for spec in registered_solvers().values() if spec.family == "gradient-free"]
    assert free and all(spec.method for spec in free)  # the family the paper compares


def test_the_constrained_stills_slide_is_titled_with_its_message_when_measured(
    quick_report, tmp_path
):
    """Slide 6's title says what the constrained pair shows (the same first commands, then
    EMDM raises m) only while the records say both; otherwise it names the slide."""
    from emdm.outputs.report.pitch import Pitch
    from emdm.outputs.report.trace import Data

    root = tmp_path / "report"
    shutil.copytree(quick_report, root)
    path = root / "data" / "task1" / "metrics.json"
    metrics = json.loads(path.read_text(encoding="utf-8"))

    def title() -> str:
        built = Pitch(Data(root), document(root)).build()
        bullets = [render_latex(b) for b in built.bullets["task1-stills"]]
        said = any(b.startswith("Then EMDM raises") for b in bullets)  # the title's evidence
        assert said == ("then EMDM raises" in render_latex(built.titles["task1-stills"]))
        return render_latex(built.titles["task1-stills"])

    runs = metrics["controllers"]
    story = Pitch(Data(root), document(root)).s
    holds = bool(story.pair("task1", "C", "coincide_steps")) and (
        runs["C-EMDM"]["mean_manipulability"] > runs["C-IVKC"]["mean_manipulability"]
    )
    assert ("then EMDM raises" in title()) == holds
    runs["C-EMDM"]["mean_manipulability"] = runs["C-IVKC"]["mean_manipulability"] * 0.9
    path.write_text(json.dumps(metrics), encoding="utf-8")
    assert title() == "Task 1: the constrained pair in motion"


def test_the_task2_slide_is_titled_with_the_blocked_line_only_when_the_geometry_says_so(
    quick_report, tmp_path
):
    """Slide 8 names the problem (the straight line is blocked) only when events.json's
    geometry found it blocked; slide 9 gives the cause (reading 127: both said 'the slack')."""
    from emdm.outputs.report.pitch import Pitch
    from emdm.outputs.report.trace import Data

    root = tmp_path / "report"
    shutil.copytree(quick_report, root)
    path = root / "data" / "task2" / "events.json"
    events = json.loads(path.read_text(encoding="utf-8"))

    def title() -> str:
        return render_latex(Pitch(Data(root), document(root)).build().titles["task2"])

    blocked = bool(events.get("geometry") and events["geometry"]["line_blocked"])
    assert ("is blocked" in title()) == blocked
    if events.get("geometry"):
        events["geometry"]["line_blocked"] = not blocked
        path.write_text(json.dumps(events), encoding="utf-8")
        assert ("is blocked" in title()) == (not blocked)


def test_the_closed_loop_arrivals_name_every_way_a_solver_differs():
    """The solver answer names the gradient-free closed loops that arrive later, sooner or not
    at all than the exact one (a budget-limited differential-evolution arrived sooner, and the
    sentence had said only 'later')."""
    from emdm.outputs.report.findings.records import SolverRow
    from emdm.outputs.report.findings.solvers import Solvers

    def row(reached, t):
        fields = dict.fromkeys(("family", "loop", "description"), "x") | dict.fromkeys(
            ("resolved_steps", "failures", "over_period", "limit_stops", "optimal_claims"), 0
        )
        numbers = ("median_time", "p95_time", "max_time", "median_iterations")
        more = ("median_evaluations", "median_gradients", "max_gap", "max_abs_gap", "max_violation")
        return SolverRow(
            **fields, **dict.fromkeys(numbers + more, 0.0), reached=reached, time_to_goal=t
        )

    def said(free, times):
        rows = {k: row(t is not None, t) for k, t in times.items()}
        return "".join(part.plain() for part in Solvers.closed_loop_arrivals(free, rows))

    free = ["nelder-mead", "powell", "differential-evolution", "cobyla"]
    base = {"active-set": 16.45, "nelder-mead": 16.8, "powell": 19.35}
    assert said(free, base | {"differential-evolution": 16.3, "cobyla": None}) == (
        "nelder-mead and powell arrive later, differential-evolution sooner, cobyla does not "
        "arrive. "
    )
    assert said(free, base | {"differential-evolution": 16.45, "cobyla": 16.45}) == (
        "nelder-mead and powell arrive later. "
    )
    same = dict.fromkeys(["active-set", *free], 16.45)
    assert said(free, same) == "every solver reaches the goal at the same time. "
    assert said(free, same | {"powell": 16.0}) == "powell arrives sooner. "


def test_the_task2_evidence_slide_draws_each_run_from_its_record(quick_report):
    """Slide 9 draws its runs (readings 121-129: the causes were bullets about runs not drawn):
    the constrained pair as run, then each run with one cause changed, its bar the time to the
    goal of its record, a run that does not arrive marked as such; the slide shows the chart."""
    from emdm.outputs.report.jobs import _load_runs, evidence_bars

    record = quick_report / "data" / "evidence.json"
    ev = json.loads(record.read_text(encoding="utf-8"))["runs"]
    runs = _load_runs("task2")
    bars = evidence_bars(runs, record)
    said = [(str(b.controller), b.change, b.time_to_goal) for b in bars]

    def goal(key, ctrl):
        run = ev[key]["runs"][ctrl]
        return run["time_to_goal"] if run["reached"] else None

    bound = max(abs(v) for v in ev["t2-c-emdm-tight-slack"]["overrides"]["slack.max"])
    as_run = {c: (r.time_to_goal if r.reached else None) for c, r in runs.items()}
    assert said == [
        ("C-IVKC", "as run", as_run["C-IVKC"]),
        ("C-IVKC", "free slack", goal("t2-c-slack-policy", "C-IVKC")),
        ("C-EMDM", "as run", as_run["C-EMDM"]),
        ("C-EMDM", "free slack", goal("t2-c-slack-policy", "C-EMDM")),
        ("C-EMDM", "no dexterity term", goal("t2-c-emdm-no-manip", "C-EMDM")),
        ("C-EMDM", f"slack within ±{bound:g} m/s", goal("t2-c-emdm-tight-slack", "C-EMDM")),
    ]
    assert (quick_report / "paper" / "slides" / "task2-evidence.png").exists()
    assert r"\fig{\textwidth}{task2-evidence}" in (quick_report / "paper" / "pitch.tex").read_text()
    alone = evidence_bars(runs, quick_report / "no-such.json")  # no record: the pair alone
    assert [b.change for b in alone] == ["as run", "as run"]


def test_the_task1_policy_slide_draws_both_policies_from_the_records(
    quick_report, tmp_path, monkeypatch
):
    """Slide 6 draws what take-away 2 says (reading 141: it rested on a backup table): Task 1's
    constrained pair slowed (as run: Table II's rows) and with a free slack (evidence.json),
    each outcome a panel whose bars are those records' values; the slide shows the chart."""
    from matplotlib.figure import Figure

    from emdm.outputs import paper_figures as pf
    from emdm.outputs.report.jobs import POLICY_RUN, _load_runs, policy_runs

    record = quick_report / "data" / "evidence.json"
    slack = json.loads(record.read_text(encoding="utf-8"))["runs"][POLICY_RUN]["runs"]
    table = json.loads((quick_report / "data" / "task1" / "metrics.json").read_text())
    runs = policy_runs(_load_runs("task1"), record)
    expected = []
    for ctrl in ("C-IVKC", "C-EMDM"):
        for policy, rec in (("slowed", table["controllers"][ctrl]), ("free slack", slack[ctrl])):
            keys = ("time_to_goal", "total_effort", "mean_manipulability", "path_length")
            expected.append((ctrl, policy, *(rec[k] for k in keys)))
    got = [
        (
            str(r.controller),
            r.policy,
            r.time_to_goal,
            r.total_effort,
            r.mean_manipulability,
            r.path_length,
        )
        for r in runs
    ]
    assert [g[:2] for g in got] == [e[:2] for e in expected]
    assert np.allclose([g[2:] for g in got], [e[2:] for e in expected], rtol=1e-12)
    drawn: list[Figure] = []
    save = Figure.savefig
    monkeypatch.setattr(
        Figure, "savefig", lambda self, *a, **k: drawn.append(self) or save(self, *a, **k)
    )
    with pf.png_only():
        pf.policy_figure(runs, tmp_path / "policy")
    for ax, (key, _title, _fmt) in zip(drawn[0].axes, pf.POLICY_PANELS, strict=True):
        widths = [p.get_width() for p in ax.patches]
        assert np.allclose(widths, [getattr(r, key) for r in runs]), key
    assert (quick_report / "paper" / "slides" / "task1-policy.png").exists()
    assert r"\fig{\textwidth}{task1-policy}" in (quick_report / "paper" / "pitch.tex").read_text()
    assert policy_runs(_load_runs("task1"), quick_report / "no-such.json") == []


def test_the_abstract_calls_task_scaling_a_design_choice_and_orders_the_slack_runs(
    quick_report, tmp_path
):
    """Reading 128: the abstract says that C-IVKC's stall comes from task scaling, the paper's
    own choice (in words, reading 170: the terms are the body's), and what a free slack
    changes: both arrive, whichever is sooner and more dexterous, or C-IVKC alone when C-EMDM's
    slack run does not arrive (as its record says)."""
    from emdm.outputs.report.findings import Story
    from emdm.outputs.report.trace import Data

    root = tmp_path / "report"
    shutil.copytree(quick_report, root)
    path = root / "data" / "evidence.json"
    record = json.loads(path.read_text(encoding="utf-8"))
    runs = record["runs"]["t2-c-slack-policy"]["runs"]

    def abstract() -> str:
        return "".join(p.plain() for p in Story(Data(root)).abstract())

    said = abstract()
    assert "IVKC, which we let only slow down along the line, stops short." in said
    first = runs["C-IVKC"]["time_to_goal"] < runs["C-EMDM"]["time_to_goal"]
    assert ("both arrive: IVKC sooner" in said) == first
    # the order and the mean m as the records have them (readings 209, 210: one clause each)
    i, e = runs["C-IVKC"], runs["C-EMDM"]
    i["time_to_goal"], e["time_to_goal"] = 20.0, 10.0
    i["mean_manipulability"], e["mean_manipulability"] = 0.2, 0.1
    path.write_text(json.dumps(record), encoding="utf-8")
    assert "both arrive: EMDM sooner, IVKC with a higher mean m." in abstract()
    e["mean_manipulability"] = 0.3
    path.write_text(json.dumps(record), encoding="utf-8")
    assert "both arrive: EMDM sooner and with a higher mean m." in abstract()
    runs["C-EMDM"].update(reached=False, time_to_goal=None)
    path.write_text(json.dumps(record), encoding="utf-8")
    said = abstract()
    assert (
        "With a practically unbounded slack each, IVKC arrives." in said
        and "both arrive" not in said
    )


def _lab_copy(quick_report: Path, tmp_path: Path) -> tuple[Path, Path, dict]:
    """A copy of the quick report, its Task 2 solver lab's record path and that record (the
    tests below rewrite it to force the cases the quick lab does not hold)."""
    root = tmp_path / "report"
    shutil.copytree(quick_report, root)
    path = root / "data" / "task2-lab-C-EMDM" / "solvers.json"
    return root, path, json.loads(path.read_text(encoding="utf-8"))


def test_the_abstract_compares_the_solvers_on_the_same_program(quick_report, tmp_path):
    """Readings 198, 236-240, 263-266: the abstract gives slsqp's own counts (Table II's slsqp
    row), then in brackets its counts on the program with the slack eliminated (the lab's
    slsqp-reduced), the one the exact gradient-free method searches, each read from the lab's
    record (the quick lab has neither, so a copy of its record is given both)."""
    from emdm.outputs.report.findings import Story
    from emdm.outputs.report.trace import Data

    root, path, record = _lab_copy(quick_report, tmp_path)
    lab = record["solvers"]
    lab["slsqp-reduced"] = {**lab["slsqp"], "median_evaluations": 7.0, "median_gradients": 4.0}
    free = next(n for n, r in lab.items() if r["family"] == "gradient-free")
    for r in lab.values():
        if r["family"] == "gradient-free":
            r.update(max_abs_gap=1e-3, max_violation=0.0)
    lab[free].update(max_abs_gap=0.0, max_violation=0.0, median_evaluations=321.0)
    path.write_text(json.dumps(record), encoding="utf-8")
    said = "".join(p.plain() for p in Story(Data(root)).abstract())
    own = lab["slsqp"]
    assert (
        "Offline, on the two-link programs, the gradient-based slsqp finds the exact optimum in a median "
        f"of {own['median_evaluations']:.4g} objective and {own['median_gradients']:.4g} "
        "gradient evaluations (7 and 4 with δ eliminated); the only exact gradient-free method, "
        f"{free}, needs 321 evaluations." in said
    ), said


def test_task2_1_says_the_gradient_methods_residual_in_the_loop(quick_report, tmp_path):
    """Reading 271: "slsqp finds the exact optimum" rested on the re-solved programs, while in
    the loop its own iterates left KKT residuals up to 2.4e-6, above the 1e-9 that certifies
    our answers. Section IV-B gives that residual beside its counts when it is above the
    tolerance (read from a copy of the lab's record), and nothing when it is below."""
    from emdm.core.tolerances import KKT_TOL
    from emdm.outputs.report.findings import Story
    from emdm.outputs.report.trace import Data

    root, path, record = _lab_copy(quick_report, tmp_path)
    lab = record["solvers"]

    def said() -> str:
        path.write_text(json.dumps(record), encoding="utf-8")
        story = Story(Data(root))
        sec = story.task2_solvers()
        return render_latex(sec.answer or [])

    lab["slsqp"]["closed_loop_max_kkt"] = 3.14e-6
    text = said()
    assert "iterations (" in text and "; in the loop, its KKT residual reaches $3.1" in text
    lab["slsqp"]["closed_loop_max_kkt"] = KKT_TOL / 10
    assert "in the loop, its KKT residual" not in said()


def test_the_page_tries_the_gradient_free_penalty_smaller(quick_report, tmp_path):
    """Reading 275: does the large l1 weight handicap the gradient-free methods? The page's
    Task 2.1 answer gives each penalised method's gap with the lab's smaller weight beside its
    nominal one, and says the weight does not handicap them only while none comes closer with
    the smaller weight (forced in a copy of the record); the paper has no room for it."""
    from emdm.outputs.report.findings import Story
    from emdm.outputs.report.trace import Data, render_html

    root, path, record = _lab_copy(quick_report, tmp_path)
    checked = [n for n, r in record["solvers"].items() if "penalty_check" in r]
    assert checked, "the quick lab runs a penalised method"

    def said() -> tuple[str, str]:
        path.write_text(json.dumps(record), encoding="utf-8")
        answer = Story(Data(root)).task2_solvers().answer or []
        return re.sub(r"<[^>]+>", "", render_html(answer)), render_latex(answer)

    for n in checked:
        check = record["solvers"][n]["penalty_check"]
        check.update(penalty_margin=6.4, max_abs_gap=record["solvers"][n]["max_abs_gap"] + 0.1)
    page, paper = said()
    assert "still exact (at least 6.4 times every optimal multiplier)" in page
    assert "the large weight does not handicap them" in page
    assert "handicap" not in paper  # (page only)
    first = record["solvers"][checked[0]]
    if first["max_abs_gap"] > 1e-9:  # an inexact method that comes closer: no verdict
        first["penalty_check"]["max_abs_gap"] = first["max_abs_gap"] / 10
        assert "handicap" not in said()[0]


def test_the_page_tries_the_brief_slack_on_task_1(quick_report):
    """Readings 269, 277: the brief's Table 1 lists a slack box for the three-link arm, which
    the paper's Task 1 programs leave out (D = {0}). An evidence run puts it in (``controller.
    slack = "always"``); the page's Task 1.2 answer gives each EMDM's outcomes beside its
    nominal ones, and says C-EMDM needs no scaling only when none of its steps was scaled."""
    from emdm.outputs.report.findings import Story
    from emdm.outputs.report.trace import Data, render_html

    record = json.loads((quick_report / "data" / "evidence.json").read_text(encoding="utf-8"))
    run = record["runs"]["t1-brief-slack"]
    assert run["overrides"] == {"controller.slack": "always"}
    said = re.sub(r"<[^>]+>", "", render_html(Story(Data(quick_report)).brief_slack()))
    c = run["runs"]["C-EMDM"]
    assert said.startswith(" With the brief's slack box")
    assert (" C-EMDM needs no scaling" in said) == (c["scaled_steps"] == 0)
    assert f"{c['mean_manipulability']:.3f}" in said
    assert f"{run['runs']['UC-EMDM']['total_effort']:.3f}" in said
    paper = (quick_report / "paper" / "paper.tex").read_text(encoding="utf-8")
    assert "brief's slack box" not in paper  # (the page only: the paper has no room)
    assert "brief's slack box" in (quick_report / "index.html").read_text(encoding="utf-8")


def test_the_conclusion_gives_the_solver_verdict_only_while_table_iii_holds_it(
    quick_report, tmp_path
):
    """Readings 218, 236: the conclusion answers Task 2.1 in one sentence, said only while the
    lab's record has the fastest exact gradient-based method faster than every gradient-free
    one (238: the compiled QP methods are not compared with them there)."""
    from emdm.outputs.report.findings import Story
    from emdm.outputs.report.trace import Data

    root, path, record = _lab_copy(quick_report, tmp_path)
    lab = record["solvers"]

    def said() -> str:
        path.write_text(json.dumps(record), encoding="utf-8")
        return "".join(p.plain() for p in Story(Data(root)).conclusion().paragraphs[0])

    lab["slsqp"]["median_time"] = 1e-3
    for r in lab.values():
        if r["family"] == "gradient-free":
            r["median_time"] = 1e-2
    verdict = "Offline, gradient-based slsqp is exact and faster than every gradient-free method."
    assert verdict in said()
    free = next(n for n, r in lab.items() if r["family"] == "gradient-free")
    lab[free]["median_time"] = 1e-4
    assert "is exact and faster than every" not in said()
    lab[free]["median_time"], lab["slsqp"]["max_abs_gap"] = 1e-2, 1.0
    assert "is exact and faster than every" not in said()


def test_task2_2_says_whose_gain_is_the_slacks_and_whose_the_terms(quick_report, tmp_path):
    """Reading 130: UC-EMDM's -21 % effort and +2 % mean m were both put to its slack. The run
    without the dexterity term (Table II) splits them: while it still saves effort at about
    UC-IVKC's mean m, the abstract and Section IV-C give the m to the term; otherwise not."""
    from emdm.outputs.report.findings import Story
    from emdm.outputs.report.trace import Data

    root = tmp_path / "report"
    shutil.copytree(quick_report, root)
    path = root / "data" / "evidence.json"
    record = json.loads(path.read_text(encoding="utf-8"))
    run = record["runs"]["t2-uc-emdm-no-manip"]["runs"]["UC-EMDM"]
    metrics = json.loads((root / "data" / "task2" / "metrics.json").read_text(encoding="utf-8"))
    m = {c: metrics["controllers"][c]["mean_manipulability"] for c in ("UC-IVKC", "UC-EMDM")}
    effort_ivkc = metrics["controllers"]["UC-IVKC"]["total_effort"]

    def said() -> tuple[bool, str, str]:
        from emdm.outputs.report.pitch import Pitch

        story = Story(Data(root))
        share = "".join(p.plain() for p in story.uc_term_share())
        slide = Pitch(Data(root), document(root)).build().bullets["task2-uc"]
        on_slide = any("the term buys" in render_latex(b) for b in slide)
        assert on_slide == story.uc_term_raises_m()  # the pitch's slide 10 says it too
        return story.uc_term_raises_m(), "".join(p.plain() for p in story.abstract()), share

    expected = (
        run["total_effort"] < effort_ivkc
        and abs(run["mean_manipulability"] - m["UC-IVKC"]) < abs(m["UC-EMDM"] - m["UC-IVKC"]) / 2
    )
    by_term, abstract, share = said()
    assert by_term == expected
    # whose saving it is in the abstract, each cause's share sized in Section IV-C (reading
    # 144; readings 203, 204: the abstract read as a list of percentages)
    assert ("EMDM's slack, not its dexterity term, saves effort" in abstract) == by_term
    if by_term:
        effort_emdm = metrics["controllers"]["UC-EMDM"]["total_effort"]
        cost = 100 * (effort_emdm / run["total_effort"] - 1)
        assert f"for {cost:.0f}% more effort" in share
    assert ("the dexterity term buys" in share) == by_term
    # the finding, then its run
    lead = "The saving comes from the slack: without" if by_term else "Without"
    assert share.startswith(lead + " the dexterity term (A6), UC-EMDM ")
    run["mean_manipulability"] = m["UC-EMDM"]  # as dexterous without the term: not the term's
    path.write_text(json.dumps(record), encoding="utf-8")
    by_term, abstract, share = said()
    assert not by_term and "effort and" in abstract and "the term buys" not in share
    assert share.startswith("Without the dexterity term (A6), UC-EMDM ")


def test_page_only_words_are_on_the_page_and_not_in_the_paper(quick_report):
    """A PageOnly segment prints on the page and nowhere in the LaTeX (the paper has no room
    for it); it holds no reference (the paper numbers references over its own sentences). The
    seeds' spread and the closed loops' arrivals are such words: on the page, not the paper."""
    from emdm.outputs.report.trace import PageOnly, Ref, Text, render_html, render_latex

    seg = PageOnly((Text("over seeds 0–4"),))
    assert render_html([Text("a"), seg]) == "aover seeds 0–4" and render_latex([seg]) == ""
    assert seg.plain() == "over seeds 0–4"
    with pytest.raises(ValueError, match="no reference"):
        PageOnly((Ref("tab", "solvers"),))
    page = (quick_report / "index.html").read_text(encoding="utf-8")
    paper = (quick_report / "paper" / "paper.tex").read_text(encoding="utf-8")
    for words in ("In closed loop ",):
        assert words in page and words not in paper


def test_the_uc_trade_at_a_finer_step_is_told_as_its_record_has_it(quick_report, tmp_path):
    """Readings 213, 227, 228: most of a UC run's effort comes in its first second, so the UC
    pair's 17%/25% trade depends on the step. Section III-A gives the trade at a five times
    finer step from its evidence run, and only while each run spends most of its effort in its
    first second and EMDM's changes are both rises."""
    from emdm.outputs.report.findings import Story
    from emdm.outputs.report.trace import Data

    root = tmp_path / "report"
    shutil.copytree(quick_report, root)
    path = root / "data" / "evidence.json"
    record = json.loads(path.read_text(encoding="utf-8"))
    entry = record["runs"]["t1-uc-finer-dt"]
    assert entry["overrides"] == {"motion.dt": 0.01}
    runs = entry["runs"]

    def told() -> str:
        return "".join(p.plain() for p in Story(Data(root)).finer_dt_trade())

    ivkc, emdm = runs["UC-IVKC"], runs["UC-EMDM"]
    m = round(100 * (emdm["mean_manipulability"] / ivkc["mean_manipulability"] - 1))
    e = round(100 * (emdm["total_effort"] / ivkc["total_effort"] - 1))
    assert f"at Δt = 0.01 s, it is {m}% more mean m for {e}% more effort." in told()
    emdm["total_effort"] = 0.5 * ivkc["total_effort"]  # a saving is not "more effort"
    path.write_text(json.dumps(record), encoding="utf-8")
    assert told() == ""
    emdm["total_effort"] = 2.0 * ivkc["total_effort"]
    runs["UC-IVKC"]["reached"] = False
    path.write_text(json.dumps(record), encoding="utf-8")
    assert told() == ""
