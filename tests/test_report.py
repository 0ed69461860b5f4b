"""emdm report --quick end to end: every number traced to the data, LaTeX equal to HTML, and the
page checked in a real headless browser."""

from __future__ import annotations

import json
import re
import shutil
from html.parser import HTMLParser
from pathlib import Path

import pytest

from emdm.cli import main
from emdm.outputs.report import format_value


class Page(HTMLParser):
    """Collects traced numbers, tables, image sources and links of the report page."""

    def __init__(self) -> None:
        super().__init__()
        self.spans: list[dict[str, str]] = []
        self.tables: dict[str, list[list[str]]] = {}
        self.sources: list[str] = []
        self.links: list[str] = []
        self._span: dict[str, str] | None = None
        self._table: str | None = None
        self._cell: list[str] | None = None

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
        elif tag == "img":
            self.sources.append(a["src"])
        elif tag == "a":
            self.links.append(a.get("href", ""))
        elif tag in ("script", "link", "iframe"):
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

    def handle_data(self, data):
        if self._span is not None:
            self._span["text"] += data
        if self._cell is not None:
            self._cell.append(data)


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("report") / "report"
    assert main(["report", "--quick", "--out", str(out)]) == 0
    page = Page()
    page.feed((out / "index.html").read_text(encoding="utf-8"))
    return out, page


def _value(root: Path, ref: str):
    file, _, path = ref.partition("#")
    node = json.loads((root / file).read_text(encoding="utf-8"))
    for key in path.split("/"):
        node = node[int(key)] if isinstance(node, list) else node[key]
    return node


def test_every_number_traces_to_the_data(report):
    root, page = report
    assert len(page.spans) > 200
    for span in page.spans:
        refs = span["data-src"].split("|")
        fmt, op = span["data-fmt"], span.get("data-op")
        if op == "pct":
            a, b = (_value(root, r) for r in refs)
            expected = format(100.0 * (a / b - 1.0), fmt) + "%"
        elif op == "ms":
            expected = format_value(_value(root, refs[0]) * 1e3, fmt)
        else:
            expected = format_value(_value(root, refs[0]), fmt)
        assert span["text"] == expected, span


def test_the_report_follows_the_brief(report):
    root, _ = report
    text = (root / "index.html").read_text(encoding="utf-8")
    order = [
        re.search(r"<h[23][^>]*>" + re.escape(title), text).start()
        for title in (
            "Task 1.1: UC-EMDM against UC-IVKC",
            "UC-EMDM: Pareto fronts",
            "UC-EMDM: custom solver, off-the-shelf fallback",
            "Task 1.2: C-EMDM against C-IVKC",
            "C-EMDM: Pareto fronts",
            "Task 2.1: C-EMDM against C-IVKC",
            "Task 2.1: gradient-based against gradient-free",
            "Task 2.2: UC-EMDM against UC-IVKC",
            "Convergence and numerical challenges",
            "Provenance",
        )
    ]
    assert order == sorted(order)
    assert "did not reach the goal within" in text  # task 2 C-IVKC, stated from the data
    prov = json.loads((root / "provenance.json").read_text())
    assert prov["mode"] == "quick" and prov["wall_time_s"] > 0 and "numpy" in prov["packages"]
    for task in ("task1", "task2"):
        metrics = json.loads((root / "data" / task / "metrics.json").read_text())
        assert set(metrics["controllers"]) == {"UC-IVKC", "C-IVKC", "UC-EMDM", "C-EMDM"}
    assert (root / "data" / "task2-lab-C-EMDM" / "solvers.json").exists()
    assert (root / "data" / "task1-pareto-UC-EMDM" / "pareto.json").exists()


def test_latex_tables_equal_the_html_tables(report):
    root, page = report
    tables = sorted((root / "latex" / "tables").glob("*.tex"))
    assert len(tables) == 7  # four controller pairs, three solver comparisons
    for tex in tables:
        text = tex.read_text(encoding="utf-8")
        assert "\\toprule" in text and "\\bottomrule" in text
        body = text.split("\\midrule")[1].split("\\bottomrule")[0]
        rows = [r.strip() for r in body.split("\\\\") if r.strip()]
        html_rows = page.tables[tex.stem][1:]  # without the header row
        assert len(rows) == len(html_rows), tex.stem
        for row, html_row in zip(rows, html_rows, strict=True):
            cells = [c.strip().replace("--", "–").replace("\\_", "_") for c in row.split(" & ")]
            assert cells == html_row, tex.stem
    for section in (root / "latex" / "sections").glob("*.tex"):
        for name in re.findall(r"\\includegraphics\[[^]]*\]\{([^}]*)\}", section.read_text()):
            assert list((root / "latex").glob(f"{name}.*")), name  # PNG in --quick, PDF in full
    assert (root / "latex" / "report.tex").exists()


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


def test_the_page_loads_in_a_real_browser(report):
    chromium, driver_path = shutil.which("chromium"), shutil.which("chromedriver")
    if not chromium or not driver_path:
        pytest.skip("no chromium/chromedriver installed (.ci/run installs them)")
    webdriver = pytest.importorskip("selenium.webdriver")
    from selenium.webdriver.chrome.service import Service

    root, page = report
    options = webdriver.ChromeOptions()
    options.binary_location = chromium
    for flag in (
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-dev-shm-usage",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--no-first-run",
        "--window-size=1200,900",
    ):
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(driver_path), options=options)
    try:
        driver.get((root / "index.html").as_uri())
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
