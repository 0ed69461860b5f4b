"""Shared fixtures; the independent reference of the tests is the module ``reference``."""

from __future__ import annotations

import numpy as np
import pytest
from reference import (
    assert_step_optimal,
    fd_jacobian,
    reference_bounds,
    reference_program,
    reference_solve,
)


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture(scope="session")
def quick_report(tmp_path_factory, worker_id):
    """One ``emdm report --quick`` for every test that reads a report (test_report, test_paper),
    signed by two authors whose names hold TeX's special characters.

    Built once per run: under pytest-xdist the first worker to need it builds it in the run's
    shared temporary folder, and the other waits for it (a lock) and reads the same one. Tests
    only read it; one that changes a report works on a copy."""
    import fcntl

    from emdm.cli import main

    shared = tmp_path_factory.getbasetemp()
    if worker_id != "master":  # (the workers' folders sit side by side in the run's folder)
        shared = shared.parent
    out = shared / "quick-report" / "report"
    with open(shared / "quick-report.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        if not (out / "index.html").exists():
            authors = ["--author", "Émilie du Châtelet", "--author", "R&D 100% $x_1$ #2"]
            assert main(["report", "--quick", *authors, "--out", str(out)]) == 0
    return out


def headless_chromium(width: int = 1500, height: int = 1000):
    """A headless Debian chromium driven by selenium, with the page's console logged; skips the
    test where chromium, chromedriver or selenium is missing (.ci/run installs them)."""
    import shutil

    chromium, driver_path = shutil.which("chromium"), shutil.which("chromedriver")
    if not chromium or not driver_path:
        pytest.skip("no chromium/chromedriver installed (.ci/run installs them)")
    webdriver = pytest.importorskip("selenium.webdriver")
    from selenium.webdriver.chrome.service import Service

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
        f"--window-size={width},{height}",
    ):
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    return webdriver.Chrome(service=Service(driver_path), options=options)


__all__ = [
    "assert_step_optimal",
    "fd_jacobian",
    "headless_chromium",
    "reference_bounds",
    "reference_program",
    "reference_solve",
]


@pytest.fixture(scope="session")
def numpy_solver():
    """The numpy active set (null-space steps by SVD) as a solver the loop hands every step to."""
    from emdm.solvers import Family, SolverSpec, register, solve_active_set
    from emdm.solvers.base import _REGISTRY

    def solve(qp, *, history=False):
        return solve_active_set(qp, history=True)

    register(SolverSpec("numpy-active-set", Family.EXACT, solve, "test: the numpy method"))
    yield "numpy-active-set"
    _REGISTRY.pop("numpy-active-set")
