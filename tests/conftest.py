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
def quick_report(tmp_path_factory):
    """One ``emdm report --quick`` for every test that reads a report (test_report, test_paper)."""
    from emdm.cli import main

    out = tmp_path_factory.mktemp("report") / "report"
    assert main(["report", "--quick", "--out", str(out)]) == 0
    return out


__all__ = [
    "assert_step_optimal",
    "fd_jacobian",
    "reference_bounds",
    "reference_program",
    "reference_solve",
]
