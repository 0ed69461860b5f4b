"""The records the story reads, as typed data built once, and checked, from the report's files.

Each dataclass below names the fields the story reads from one kind of record, with their types:
:class:`Outcomes` (a run's ``metrics.json`` entry), :class:`RunEvents` (its ``events.json``
entry), :class:`PairEvents` (a pair's) and :class:`EvidenceRun` (an entry of ``evidence.json``).
:meth:`Records.load` builds all of them when the story starts and refuses a record that lacks a
field or holds a value of the wrong type, in one line naming the file and the key: before any
sentence is written, not while the paper renders.

The story's accessors take the field names as literal types (:data:`MetricKey`,
:data:`EventKey`, :data:`PairKey`, :data:`EvidenceKey`, :data:`SolverKey`, :data:`LabName`,
:data:`FrontKey`, :data:`GridKey`, :data:`GeometryKey`, :data:`MmcKey`, :data:`PaperKey`), so
mypy refuses a misspelt key;
``tests/test_report.py`` checks that these literals are the dataclasses' fields and that the
producers (:func:`emdm.sim.metrics.metrics`, :func:`..explain.run_events`,
:func:`..explain.pair_events`, :data:`..config.EVIDENCE`) write every one of them, so a renamed
key fails a unit test.
"""

from __future__ import annotations

import dataclasses
import types
import typing
from dataclasses import dataclass, field
from typing import Any, Literal, Union

from ....core.scenario import Scenario, scenario_from_dict
from ....errors import EmdmError
from ..config import MANY_GOALS
from ..trace import Data


class RecordError(EmdmError):
    """A record of the report lacks a field the story reads, or holds the wrong type."""


MetricKey = Literal[
    "reached",
    "steps",
    "time_to_goal",
    "final_time",
    "final_error",
    "mean_manipulability",
    "final_manipulability",
    "total_effort",
    "max_abs_qd",
    "path_length",
    "scaled_steps",
    "fallback_steps",
    "final_q",
    "min_stop_margin",
    "max_kkt_residual",
]
"""The fields of :class:`Outcomes`."""


GRID_FILE = "data/task1-pareto-{ctrl}/weight_grid.json"
"""Where Task 1's weight grid of a controller ``ctrl`` is recorded (Fig. 2's whole runs, E2)."""


@dataclass(frozen=True)
class Outcomes:
    """One run's outcomes: ``data/TASK/metrics.json#controllers/NAME``."""

    reached: bool
    steps: int
    time_to_goal: float | None
    final_time: float
    final_error: float
    mean_manipulability: float
    final_manipulability: float
    total_effort: float
    max_abs_qd: float
    path_length: float
    scaled_steps: int
    fallback_steps: int
    final_q: list[Any]
    min_stop_margin: float
    max_kkt_residual: float


EventKey = Literal[
    "reached",
    "time_to_goal",
    "final_time",
    "final_error",
    "initial_error",
    "mean_manipulability",
    "total_effort",
    "path_length",
    "straight_length",
    "detour",
    "scaling",
    "pinned",
    "stall",
    "obstacles",
    "planes",
    "singular",
    "conditioning",
    "derivatives",
    "effort",
    "limits",
    "solver",
    "slack",
]
"""The fields of :class:`RunEvents` (the first key of an event's path)."""


@dataclass(frozen=True)
class RunEvents:
    """What was detected in one run: ``data/TASK/events.json#controllers/NAME``
    (:func:`..explain.run_events`; an event that did not happen is ``None``)."""

    reached: bool
    time_to_goal: float | None
    final_time: float
    final_error: float
    initial_error: float
    mean_manipulability: float
    total_effort: float
    path_length: float
    straight_length: float
    detour: float
    scaling: dict[str, Any] | None
    pinned: list[Any]
    stall: dict[str, Any] | None
    obstacles: dict[str, Any] | None
    planes: dict[str, Any] | None
    singular: dict[str, Any]
    conditioning: dict[str, Any]
    derivatives: dict[str, Any]
    """``J`` and ``J_m`` against central differences at every state (:func:`..explain.derivatives`)."""
    effort: dict[str, Any]
    limits: dict[str, Any]
    solver: dict[str, Any]
    slack: dict[str, Any]


PairKey = Literal[
    "coincide_steps",
    "coincide_until_t",
    "coincide_scaled_steps",
    "coincide_all_scaled",
    "coincide_determined_steps",
    "max_path_gap",
    "t_max_path_gap",
    "common_until_t",
    "mean_m_common",
]
"""The fields of :class:`PairEvents`."""


@dataclass(frozen=True)
class PairEvents:
    """How a pair's two runs relate: ``data/TASK/events.json#pairs/GROUP``
    (:func:`..explain.pair_events`)."""

    coincide_steps: int
    coincide_until_t: float
    coincide_scaled_steps: int
    coincide_all_scaled: bool
    coincide_determined_steps: int
    max_path_gap: float
    t_max_path_gap: float
    common_until_t: float
    mean_m_common: dict[str, Any]


EvidenceKey = Literal[
    "t1-uc-no-manip",
    "t1-uc-finer-dt",
    "t1-c-slack-policy",
    "t1-brief-slack",
    "t2-c-slack-policy",
    "t2-c-ivkc-wide-limits",
    "t2-c-emdm-no-manip",
    "t2-c-emdm-tight-slack",
    "t2-uc-emdm-no-manip",
]
"""The evidence runs the story cites (the keys of :data:`..config.EVIDENCE`)."""


@dataclass(frozen=True)
class EvidenceRun:
    """One evidence run: ``data/evidence.json#runs/KEY`` (each controller's entry in ``runs``
    holds its outcomes and events, or the ``error`` that stopped it)."""

    task: str
    controllers: list[Any]
    overrides: dict[str, Any]
    runs: dict[str, Any]
    controller_overrides: dict[str, Any]
    """What a controller ran with besides ``overrides`` (IVKC's like-for-like slack weight)."""
    reference: dict[str, Any] | None = None
    """With a reference controller: the first controller's commands against its nominal run."""
    pair: dict[str, Any] | None = None
    """With two controllers: how the pair relates (:class:`PairEvents`' fields)."""


LabName = Literal["task1-lab-UC-EMDM", "task1-lab-C-EMDM", "task2-lab-C-EMDM"]
"""The solver labs the report runs (folders of ``data/``)."""

SolverKey = Literal[
    "family",
    "loop",
    "description",
    "resolved_steps",
    "failures",
    "median_time",
    "p95_time",
    "max_time",
    "over_period",
    "median_iterations",
    "median_evaluations",
    "median_gradients",
    "limit_stops",
    "max_gap",
    "max_abs_gap",
    "max_violation",
    "optimal_claims",
    "reached",
    "time_to_goal",
    "closed_loop_max_kkt",
    "seeds",
    "penalty_check",
]
"""The fields of :class:`SolverRow`."""

SeedKey = Literal[
    "seed", "median_evaluations", "max_abs_gap", "max_violation", "failures", "over_period"
]
"""The fields of :class:`SeedRun`."""


@dataclass(frozen=True)
class SeedRun:
    """One seed of a stochastic solver over a lab's programs: ``.../solvers/NAME/seeds/I``
    (:func:`emdm.studies.lab.seed_summary`)."""

    seed: int
    median_evaluations: float
    max_abs_gap: float
    max_violation: float
    failures: int
    over_period: int


@dataclass(frozen=True)
class PenaltyCheck:
    """A penalised method over a lab's programs again, with a smaller l1 weight (reading 275):
    ``.../solvers/NAME/penalty_check`` (:func:`emdm.studies.lab.run_summary`)."""

    penalty_weight: float
    """Its weight per unit of ``1 + max|P|`` (the lab's ``penalty_weight`` is the nominal one)."""
    penalty_margin: float
    """That weight over the largest optimal multiplier, the smallest over the programs (the
    penalty is exact above 1)."""
    median_evaluations: float
    max_abs_gap: float
    max_violation: float
    failures: int
    over_period: int


@dataclass(frozen=True)
class SolverRow:
    """One solver of a solver lab: ``data/LAB/solvers.json#solvers/NAME``
    (:meth:`emdm.studies.lab.SolverStudy.summary`)."""

    family: str
    loop: str
    description: str
    resolved_steps: int
    failures: int
    median_time: float
    p95_time: float
    max_time: float
    over_period: int
    """How many of its programs took longer than the control period."""
    median_iterations: float
    median_evaluations: float
    median_gradients: float
    """Gradient evaluations (a gradient-based method's; 0 for the others)."""
    limit_stops: int
    """How many of its searches an iteration or evaluation limit ended."""
    max_gap: float
    max_abs_gap: float
    max_violation: float
    optimal_claims: int
    reached: bool | None = None
    """Alone in the closed loop: whether the run reached the goal (absent: not run)."""
    time_to_goal: float | None = None
    closed_loop_max_kkt: float | None = None
    """Alone in the closed loop: the largest relative KKT residual of its answers."""
    seeds: list[SeedRun] = field(default_factory=list)
    """A stochastic method's runs over seeds 0, 1, ... (empty for the others)."""
    penalty_check: PenaltyCheck | None = None
    """A penalised method's runs with a smaller l1 weight (None for the others)."""


LabKey = Literal[
    "scenario",
    "controller",
    "reference_solver",
    "resolved_steps",
    "representative_steps",
    "penalty_weight",
    "repeats",
    "budget",
    "challenges",
    "notes",
]
"""The fields of :class:`LabRecord` (its ``solvers`` are :class:`SolverRow`)."""


@dataclass(frozen=True)
class LabRecord:
    """A solver lab: ``data/LAB/solvers.json`` (:func:`emdm.studies.lab.lab_json`, with the
    report's ``notes``)."""

    scenario: str
    controller: str
    reference_solver: str
    resolved_steps: list[Any]
    representative_steps: dict[str, Any]
    penalty_weight: float
    repeats: int
    budget: int
    """The gradient-free methods' evaluation budget per program."""
    challenges: dict[str, Any]
    notes: dict[str, Any]
    solvers: dict[str, SolverRow]


FrontKey = Literal[
    "k",
    "t",
    "points",
    "distinct",
    "nondominated",
    "degenerate",
    "alpha",
    "saturated_from_ratio",
    "saturated_points",
    "E_min",
    "E_max",
    "M_min",
    "M_max",
    "nominal_index",
    "nominal_E",
    "nominal_M",
    "zero_E",
    "zero_M",
    "nominal_M_share",
    "nominal_E_log_pct",
    "slack_distinct",
]
"""The fields of :class:`FrontStep`."""


@dataclass(frozen=True)
class FrontStep:
    """One step's Pareto front: ``data/task1-pareto-CTRL/fronts.json#steps/I``
    (:func:`..explain.front_events`, with the nominal weights' point added by the report)."""

    k: int
    t: float
    points: int
    distinct: int
    nondominated: int
    degenerate: bool
    alpha: float
    saturated_from_ratio: float | None
    saturated_points: int
    E_min: float
    E_max: float
    M_min: float
    M_max: float
    nominal_index: int
    nominal_E: float
    nominal_M: float
    zero_E: float
    zero_M: float
    nominal_M_share: float | None
    nominal_E_log_pct: float | None
    slack_distinct: int | None = None
    """At a task-scaled step: how many optima its front has under the free slack (3 with alpha* = 1)."""


GridKey = Literal[
    "w_effort",
    "w_manip",
    "reached",
    "time_to_goal",
    "total_effort",
    "mean_manipulability",
    "min_manipulability",
    "final_manipulability",
    "scaled_steps",
    "final_error",
    "max_abs_qd",
    "finer_dt",
]
"""The fields of :class:`GridRun`."""

RunOutcome = Literal["time_to_goal", "mean_manipulability", "total_effort"]
"""The outcomes both a nominal run (:data:`MetricKey`) and a weight-grid run (:data:`GridKey`)
keep, which Table II compares."""


@dataclass(frozen=True)
class GridRun:
    """One whole run of the weight grid: ``data/task1-pareto-CTRL/weight_grid.json#runs/I``;
    a run that misses the goal also has its final error, its largest joint speed and its rerun
    at a five times smaller step (``finer_dt``)."""

    w_effort: float
    w_manip: float
    reached: bool
    time_to_goal: float | None
    total_effort: float
    mean_manipulability: float
    min_manipulability: float
    final_manipulability: float
    scaled_steps: int
    final_error: float | None = None
    max_abs_qd: float | None = None
    finer_dt: dict[str, Any] | None = None


GeometryKey = Literal[
    "start_elbow",
    "solutions",
    "max_fold",
    "inner_reach",
    "line_min_distance",
    "line_blocked",
    "line_enters_at",
    "reach",
]
"""The fields of :class:`Geometry`."""


@dataclass(frozen=True)
class GoalSolution:
    """One inverse-kinematics solution of a two-link arm's goal:
    ``data/TASK/events.json#geometry/solutions/I``."""

    elbow: str
    q1: float
    q2: float
    within_limits: bool
    outside_joint: int | None
    outside_by: float


@dataclass(frozen=True)
class Geometry:
    """A two-link task's geometry: ``data/TASK/events.json#geometry``
    (:func:`..explain.geometry`)."""

    start_elbow: str
    solutions: list[GoalSolution]
    max_fold: float
    inner_reach: float
    line_min_distance: float
    line_blocked: bool
    line_enters_at: float | None
    reach: float


MmcKey = Literal[
    "trials",
    "mean_manipulability",
    "mean_final_manipulability",
    "failure_rate",
    "not_reached",
    "left_joint_limits",
    "no_admissible_command",
    "mean_manipulability_of_successes",
    "median_time_to_goal_s",
    "steps",
    "seconds",
    "published",
]
"""The fields of :class:`MmcRow`."""


@dataclass(frozen=True)
class MmcRow:
    """One controller on one arm of the manipulability benchmark under emdm's protocol:
    ``data/mmc.json#results/ARM/CTRL`` (``published``: the paper's mean, final manipulability
    and failure rate, where it has the controller)."""

    trials: int
    mean_manipulability: float
    mean_final_manipulability: float
    failure_rate: float
    not_reached: int
    left_joint_limits: int
    no_admissible_command: int
    mean_manipulability_of_successes: float
    median_time_to_goal_s: float
    steps: int
    seconds: float
    published: list[Any] | None


PaperKey = Literal[
    "trials",
    "mean_manipulability",
    "mean_manipulability_ci",
    "mean_final_manipulability",
    "mean_final_manipulability_ci",
    "mean_manipulability_minus_mmc",
    "mean_manipulability_minus_mmc_ci",
    "failure_rate",
    "failure_rate_ci",
    "arrived",
    "failed",
    "joint_limit",
    "singular",
    "missed",
    "all_arrived_trials",
    "subset",
    "published",
]
"""The fields of :class:`PaperRow`."""


@dataclass(frozen=True)
class PaperRow:
    """One controller on one arm under the authors' protocol (``emdm mmc --protocol paper``):
    ``data/mmc.json#paper/results/ARM/CTRL``, with 95 % intervals (``*_ci``)."""

    trials: int
    mean_manipulability: float
    mean_manipulability_ci: list[Any]
    mean_final_manipulability: float
    mean_final_manipulability_ci: list[Any]
    mean_manipulability_minus_mmc: float
    mean_manipulability_minus_mmc_ci: list[Any]
    failure_rate: float
    failure_rate_ci: list[Any]
    arrived: int
    failed: int
    joint_limit: int
    singular: int
    missed: int
    all_arrived_trials: int
    subset: list[Any]
    published: list[Any] | None


@dataclass(frozen=True)
class PaperProtocol:
    """``data/mmc.json#paper``: the benchmark under the authors' protocol."""

    protocol: str
    trials: int
    seed: int
    results: dict[str, dict[str, PaperRow]]


@dataclass(frozen=True)
class MmcRecord:
    """``data/mmc.json``: the manipulability benchmark on the spatial arms."""

    trials: int
    seed: int
    results: dict[str, dict[str, MmcRow]]
    published: dict[str, dict[str, list[Any]]]
    panda_preset: dict[str, dict[str, Any]]
    paper: PaperProtocol | None = None


@dataclass(frozen=True)
class Missed:
    """Where a controller's missed runs of the many-goals study ended: how many with a joint at
    its stop distance (``at_stop``), the range of their
    goals' and resting tips' distances from the base (m), of their final errors (m) and of
    the last joint's angle at rest (|q_n|, rad; None: not run again); the farthest goal it
    reached."""

    count: int
    at_stop: int
    goal_radius: list[Any]
    arrived_goal_radius_max: float | None
    final_error: list[Any]
    rest_tip_radius: list[Any] | None
    rest_last_joint: list[Any] | None

    def separated(self) -> bool:
        """Whether a distance from the base separates these misses from the arrivals: every
        goal missed lies farther out than every goal reached."""
        reached = self.arrived_goal_radius_max
        return reached is not None and self.goal_radius[0] > reached


@dataclass(frozen=True)
class GoalsRow:
    """One controller in the many-goals study: its arrivals among ``runs`` draws, the
    quartiles of its times to the goal (s) and where its missed runs ended."""

    runs: int
    arrived: int
    time_to_goal: list[Any] | None
    missed: Missed | None


@dataclass(frozen=True)
class PairChange:
    """A pair compared run by run on the draws both reach: quartiles of the second's relative
    change of mean m, total effort and time to the goal against the first's; on how many
    the second has the higher mean m."""

    both_arrived: int
    mean_manipulability: list[Any] | None
    total_effort: list[Any] | None
    time_to_goal: list[Any] | None
    higher_mean_manipulability: int


@dataclass(frozen=True)
class PolicyGoals:
    """One task's controllers under one infeasibility policy, on the many goals."""

    controllers: dict[str, GoalsRow]
    pairs: dict[str, PairChange]


@dataclass(frozen=True)
class WeightGoals(PairChange):
    """Task 1's UC-EMDM at one weight pair, against the nominal weights, on the many goals."""

    w_effort: float = 0.0
    w_manip: float = 0.0
    arrived: int = 0


@dataclass(frozen=True)
class TermGoals:
    """An EMDM controller on the many goals with one change (its dexterity term off): how many
    arrive, the goals the change wins (``lost`` by the controller as it is) and loses
    (``gained``), and how many of those won lie beyond ``beyond`` (m from the base)."""

    overrides: dict[str, Any]
    arrived: int
    lost: int
    gained: int
    lost_beyond: int | None
    beyond: float | None


@dataclass(frozen=True)
class TaskGoals:
    """One task in the many-goals study: its arm's reach (m), each policy's study (``scale``,
    ``slack``) and, for Task 1, its whole-run sweep's weights."""

    reach: float
    policies: dict[str, PolicyGoals]
    weights: list[WeightGoals] = field(default_factory=list)
    no_term: dict[str, TermGoals] = field(default_factory=dict)


@dataclass(frozen=True)
class ManyGoals:
    """``data/many-goals.json``: every task's controllers on the same ``runs`` random starts
    and goals (seed ``seed``)."""

    runs: int
    seed: int
    tasks: dict[str, TaskGoals]


def _accepts(hint: Any, value: Any) -> bool:
    """Whether ``value`` (decoded JSON) has the type ``hint`` (the few kinds used above)."""
    origin = typing.get_origin(hint)
    if origin in (Union, types.UnionType):
        return any(_accepts(h, value) for h in typing.get_args(hint))
    if hint is type(None):
        return value is None
    if hint is bool:
        return isinstance(value, bool)
    if hint is int:
        return isinstance(value, int) and not isinstance(value, bool)
    if hint is float:
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if hint is str:
        return isinstance(value, str)
    return isinstance(value, origin or hint)


def _name(hint: Any) -> str:
    """A type as written in Python (``float``, ``float | None``, ``dict[str, Any]``)."""
    return hint.__name__ if isinstance(hint, type) else str(hint).replace("typing.", "")


def _holds_records(hint: Any) -> bool:
    """Whether the type ``hint`` is a record (a dataclass) or holds records (dict, list)."""
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        return True
    return any(_holds_records(h) for h in typing.get_args(hint))


def _build(hint: Any, data: Data, file: str, path: tuple[str | int, ...], node: Any) -> Any:
    """``node`` (at ``file#path``) as the type ``hint``: records built and checked by
    :func:`load_record`, dictionaries and lists of them element by element."""
    where = f"{file}#{'/'.join(map(str, path))}"
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        return load_record(hint, data, file, *path)
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin in (Union, types.UnionType):
        if node is None and type(None) in args:
            return None
        return _build(next(a for a in args if a is not type(None)), data, file, path, node)
    if origin is dict and isinstance(node, dict):
        return {k: _build(args[1], data, file, (*path, k), v) for k, v in node.items()}
    if origin is list and isinstance(node, list):
        return [_build(args[0], data, file, (*path, i), v) for i, v in enumerate(node)]
    raise RecordError(f"{where}: expected {_name(hint)}, found {node!r:.60}")


def load_record(cls: type[Any], data: Data, file: str, *path: str | int) -> Any:
    """``cls`` built from the JSON object at ``file#path``, every field present and typed."""
    where = f"{file}#{'/'.join(map(str, path))}"
    try:
        node = data.value(file, *path)
    except (KeyError, IndexError, OSError, ValueError) as exc:
        raise RecordError(f"{where}: no such record ({exc})") from None
    if not isinstance(node, dict):
        raise RecordError(f"{where}: expected an object, found {type(node).__name__}")
    hints = typing.get_type_hints(cls)
    values = {}
    for f in dataclasses.fields(cls):
        optional = not (f.default is f.default_factory is dataclasses.MISSING)
        if f.name not in node and optional:
            continue  # an optional field (the dataclass' default)
        if _holds_records(hints[f.name]):
            # records inside a record (a lab's rows, a geometry's solutions): typed in turn
            values[f.name] = _build(hints[f.name], data, file, (*path, f.name), node[f.name])
            continue
        if f.name not in node:
            raise RecordError(f"{where}: no field {f.name!r} (the report reads it)")
        if not _accepts(hints[f.name], node[f.name]):
            raise RecordError(
                f"{where}/{f.name}: expected {_name(hints[f.name])}, found {node[f.name]!r:.60}"
            )
        values[f.name] = node[f.name]
    return cls(**values)


@dataclass(frozen=True)
class Records:
    """Every typed record of the brief's tasks, built once from the report's data."""

    scenarios: dict[str, Scenario]
    """Each task's scenario, as its runs recorded it (``metrics.json#scenario``), read back by
    the scenario's own schema."""
    outcomes: dict[str, dict[str, Outcomes]]
    events: dict[str, dict[str, RunEvents]]
    pairs: dict[str, dict[str, PairEvents]]
    evidence: dict[str, EvidenceRun]
    labs: dict[str, LabRecord]
    """The solver labs the report ran, by folder (``task2-lab-C-EMDM``)."""
    geometry: dict[str, Geometry]
    """The two-link tasks' geometry, by task."""
    mmc: MmcRecord | None
    """The manipulability benchmark (absent: the report ran none)."""
    fronts: dict[str, list[FrontStep]]
    """Task 1's Pareto fronts at the steps studied, by controller."""
    grids: dict[str, list[GridRun]]
    """Task 1's weight grid of whole runs, by controller."""
    goals: ManyGoals | None = None
    """The many-goals study (absent: the report ran none)."""

    @classmethod
    def load(cls, data: Data, tasks: tuple[str, ...] = ("task1", "task2")) -> Records:
        scenarios: dict[str, Scenario] = {}
        outcomes: dict[str, dict[str, Outcomes]] = {}
        events: dict[str, dict[str, RunEvents]] = {}
        pairs: dict[str, dict[str, PairEvents]] = {}
        for task in tasks:
            m, e = f"data/{task}/metrics.json", f"data/{task}/events.json"
            if not data.exists(m):
                continue
            try:
                scenarios[task] = scenario_from_dict(data.value(m, "scenario"))
            except (EmdmError, KeyError, TypeError, ValueError) as exc:
                raise RecordError(f"{m}#scenario: {exc}") from None
            outcomes[task] = {
                c: load_record(Outcomes, data, m, "controllers", c)
                for c in data.value(m, "controllers")
            }
            events[task] = {
                c: load_record(RunEvents, data, e, "controllers", c)
                for c in data.value(e, "controllers")
            }
            pairs[task] = {
                g: load_record(PairEvents, data, e, "pairs", g) for g in data.value(e, "pairs")
            }
        evidence: dict[str, EvidenceRun] = {}
        f = "data/evidence.json"
        if data.exists(f):
            for key in typing.get_args(EvidenceKey):
                evidence[key] = load_record(EvidenceRun, data, f, "runs", key)
        geometry = {
            task: load_record(Geometry, data, f"data/{task}/events.json", "geometry")
            for task in tasks
            if data.exists(f"data/{task}/events.json")
            and data.value(f"data/{task}/events.json").get("geometry")
        }
        labs = {
            lab: load_record(LabRecord, data, f"data/{lab}/solvers.json")
            for lab in typing.get_args(LabName)
            if data.exists(f"data/{lab}/solvers.json")
        }
        fronts: dict[str, list[FrontStep]] = {}
        grids: dict[str, list[GridRun]] = {}
        for ctrl in ("UC-EMDM", "C-EMDM"):
            f, g = (
                f"data/task1-pareto-{ctrl}/fronts.json",
                GRID_FILE.format(ctrl=ctrl),
            )
            if data.exists(f):
                fronts[ctrl] = [
                    load_record(FrontStep, data, f, "steps", i)
                    for i in range(len(data.value(f, "steps")))
                ]
            if data.exists(g):
                grids[ctrl] = [
                    load_record(GridRun, data, g, "runs", i)
                    for i in range(len(data.value(g, "runs")))
                ]
        mmc = (
            load_record(MmcRecord, data, "data/mmc.json") if data.exists("data/mmc.json") else None
        )
        goals = load_record(ManyGoals, data, MANY_GOALS) if data.exists(MANY_GOALS) else None
        return cls(
            scenarios, outcomes, events, pairs, evidence, labs, geometry, mmc, fronts, grids, goals
        )
