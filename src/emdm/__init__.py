"""emdm: effort-minimising, dexterity-maximising velocity control of planar manipulators.

>>> import emdm
>>> scenario = emdm.load_scenario("task1")
>>> run = emdm.simulate(scenario, "C-EMDM")
>>> run.reached, round(run.time_to_goal, 2)
(True, 8.15)
"""

from __future__ import annotations

__version__ = "0.1.0"

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
