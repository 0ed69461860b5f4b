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


__all__ = [
    "assert_step_optimal",
    "fd_jacobian",
    "reference_bounds",
    "reference_program",
    "reference_solve",
]
