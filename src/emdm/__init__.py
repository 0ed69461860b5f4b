"""emdm: effort-minimising, dexterity-maximising velocity control of planar manipulators.

>>> import emdm
>>> scenario = emdm.load_scenario("task1")
>>> run = emdm.simulate(scenario, "C-EMDM")
>>> run.reached, round(run.time_to_goal, 2)
(True, 8.15)
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

if TYPE_CHECKING:
    from .core.arm import Kinematics, PlanarArm
    from .core.controllers import (
        CONTROLLERS,
        Controller,
        admissible,
        get_controller,
        joint_bounds,
        step_program,
    )
    from .core.feasibility import feasible_point, task_scale
    from .core.loading import PRESETS, ScenarioWarning, load_scenario
    from .core.problem import QP, Objective
    from .core.scenario import Scenario, scenario_from_dict
    from .core.serial import SerialArm
    from .errors import EmdmError, NoSolution, ScenarioError, SolverNotFound
    from .sim.batch import BatchResult, precompile, simulate_batch
    from .sim.loop import Run, simulate
    from .sim.metrics import metrics
    from .solvers import available_solvers, get_solver, kkt_report, solve_chain

_WHERE = {
    "BatchResult": ".sim.batch",
    "CONTROLLERS": ".core.controllers",
    "Controller": ".core.controllers",
    "EmdmError": ".errors",
    "Kinematics": ".core.arm",
    "NoSolution": ".errors",
    "Objective": ".core.problem",
    "PRESETS": ".core.loading",
    "PlanarArm": ".core.arm",
    "QP": ".core.problem",
    "Run": ".sim.loop",
    "Scenario": ".core.scenario",
    "ScenarioError": ".errors",
    "ScenarioWarning": ".core.loading",
    "SerialArm": ".core.serial",
    "SolverNotFound": ".errors",
    "admissible": ".core.controllers",
    "available_solvers": ".solvers",
    "feasible_point": ".core.feasibility",
    "get_controller": ".core.controllers",
    "get_solver": ".solvers",
    "joint_bounds": ".core.controllers",
    "kkt_report": ".solvers",
    "load_scenario": ".core.loading",
    "metrics": ".sim.metrics",
    "precompile": ".sim.batch",
    "scenario_from_dict": ".core.scenario",
    "simulate": ".sim.loop",
    "simulate_batch": ".sim.batch",
    "solve_chain": ".solvers",
    "step_program": ".core.controllers",
    "task_scale": ".core.feasibility",
}
"""Where each public name lives: imported on first use (PEP 562), so that ``import emdm`` is
light and the ``emdm`` command can install its signal handlers before numba loads."""

__all__ = [
    "CONTROLLERS",
    "PRESETS",
    "QP",
    "BatchResult",
    "Controller",
    "EmdmError",
    "Kinematics",
    "NoSolution",
    "Objective",
    "PlanarArm",
    "Run",
    "Scenario",
    "ScenarioError",
    "ScenarioWarning",
    "SerialArm",
    "SolverNotFound",
    "__version__",
    "admissible",
    "available_solvers",
    "feasible_point",
    "get_controller",
    "get_solver",
    "joint_bounds",
    "kkt_report",
    "load_scenario",
    "metrics",
    "precompile",
    "scenario_from_dict",
    "simulate",
    "simulate_batch",
    "solve_chain",
    "step_program",
    "task_scale",
]


_PACKAGES = frozenset({"cli", "core", "errors", "outputs", "play", "sim", "solvers", "studies"})


def __getattr__(name: str) -> Any:
    if name in _PACKAGES:  # ``emdm.core.schema`` after a bare ``import emdm``
        return importlib.import_module(f".{name}", __name__)
    where = _WHERE.get(name)
    if where is None:
        raise AttributeError(f"module 'emdm' has no attribute {name!r}")
    value = getattr(importlib.import_module(where, __name__), name)
    globals()[name] = value  # later uses find it directly
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_WHERE])
