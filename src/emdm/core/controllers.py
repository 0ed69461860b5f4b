"""The four controllers of the brief as per-step programs, and the infeasibility policy.

============  =========================================  ==========================================
controller    redundant arm (n > 2)                      non-redundant arm (n = 2)
============  =========================================  ==========================================
UC-IVKC       min E  s.t. J qd = v   (= J^+ v, eq. 4)    same (= J^-1 v)
C-IVKC        same + lo(q) <= qd <= hi(q)                same
UC-EMDM       min w_E E - w_M M  s.t. J qd = v           slack program, no joint bounds
C-EMDM        same + lo(q) <= qd <= hi(q)                slack program + joint bounds
============  =========================================  ==========================================

Slack program (mathematics.md eq. 12-14): variables ``(qd, delta)``, minimise
``w_E E(qd) - w_M M(qd) + 1/2 w_S ||delta||^2`` subject to ``J qd + delta = v`` and
``delta_min <= delta <= delta_max``, with ``w_S = c_S / max(||e||, 1e-9 m)``.

Spatial arms track a position (3 rows) or a pose (6 rows) with the same programs; "redundant"
means more joints than task rows. Three baselines of the manipulability literature are the same
programs with the slack fixed (Haviland & Corke's comparison): ``RRMC`` (resolved-rate motion
control, ``qd = J^+ v``) is UC-IVKC without slack; ``PARK`` (gradient projection,
``qd = J^+ v + (w_M / w_E)(I - J^+ J) Jm``) is UC-EMDM without slack; ``MMC`` (the
manipulability-maximising controller) is C-EMDM with the slack program on every arm.

When a program is infeasible (the bounds cannot deliver the task) the scenario's ``on_infeasible``
decides: ``scale`` solves the same program for ``alpha v`` with the largest feasible ``alpha`` in
[0, 1] (direction-preserving task scaling, as in the SNS method of Flacco, De Luca and Khatib);
``slack`` re-solves with unbounded task slack; ``error`` stops the run. A solution is never clipped
into its bounds after the fact.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import numpy as np

from ..errors import EmdmError, NoSolution
from .arm import Kinematics, Vector
from .checks import _Checker, _show
from .distance import AXIS, GAP, POINT, chain_points_of, link_gaps
from .feasibility import _task_scale
from .kernels import task_kinematics_of
from .limits import Bounds
from .problem import QP
from .scenario import Scenario
from .sections import Weights
from .terms import CODE, PACK, ProgramData, ProgramOut, StepInput, TermKind, build_program
from .terms.damper import joint_bounds as _joint_bounds
from .terms.obstacle import SLOWEST
from .tolerances import ERROR_FLOOR
from .validation import POLICIES, SlackUse


class When(StrEnum):
    """When a term is part of the program: always, or only on an arm that is not redundant
    (no more joints than task rows: the brief's slack program)."""

    ALWAYS = "always"
    NON_REDUNDANT = "non-redundant"
    NON_REDUNDANT_OR_OBSTACLES = "non-redundant or obstacles"


@dataclass(frozen=True)
class Term:
    """A term of a controller: its kind (a module of :mod:`emdm.core.terms`), its weight (a key of
    ``[weights]`` or a number), when it applies, and whether a zero weight leaves it out."""

    kind: TermKind
    weight: str | float = 1.0
    when: When = When.ALWAYS
    optional: bool = False


@dataclass(frozen=True)
class Controller:
    """A controller is data: a name and the terms of its per-step program.

    :meth:`program_data` turns it and a scenario into the input of the compiled program builder
    (:func:`emdm.core.terms.build_program`), so adding a controller means adding its list of
    terms below, in this module only.
    """

    name: str
    terms: tuple[Term, ...]

    def __post_init__(self) -> None:
        check = _Checker("Controller")
        check.text("name", self.name, "a name (a non-empty string)")
        terms: Any = self.terms
        if not isinstance(terms, tuple) or not all(isinstance(t, Term) for t in terms):
            raise check.fail("terms", f"must be a tuple of Term, got {_show(terms)}")

    def has(self, kind: TermKind) -> bool:
        """Whether the controller holds a term of ``kind`` (on some arm)."""
        return any(t.kind is kind for t in self.terms)

    @property
    def constrained(self) -> bool:
        """Whether the joint bounds (velocity box and dampers) apply: the ``C-`` controllers."""
        return self.has(TermKind.VELOCITY_BOX)

    def applies(self, term: Term, scenario: Scenario) -> bool:
        """Whether ``term`` is part of this controller's program on ``scenario``'s arm."""
        if term.when is When.NON_REDUNDANT_OR_OBSTACLES and scenario.obstacles:
            return True
        if term.kind is TermKind.SLACK and scenario.controller.slack is SlackUse.ALWAYS:
            return True  # the slack on every arm (``controller.slack = "always"``)
        return term.when is When.ALWAYS or not scenario.redundant

    def program_data(self, scenario: Scenario, weights: Weights | None = None) -> ProgramData:
        """The terms, weights and numbers of this controller's program on ``scenario`` (with the
        scenario's weights: built once per scenario and kept in its :attr:`Scenario.memo`).
        Raises :class:`~emdm.errors.ScenarioError` unless ``scenario`` is a Scenario and
        ``weights`` None or Weights."""
        _inputs("Controller.program_data", scenario, weights)
        if weights is None:  # keyed by name, checked by identity first (hashing the terms costs)
            key = ("program", self.name)
            kept = scenario.memo.get(key)
            if kept is None or (kept[0] is not self and kept[0] != self):
                kept = scenario.memo[key] = (self, self._program_data(scenario, scenario.weights))
            return kept[1]
        return self._program_data(scenario, weights)

    def _program_data(self, scenario: Scenario, w: Weights) -> ProgramData:
        codes: list[int] = []
        values: list[float] = []
        data: list[float] = []
        start = [0]
        slack = False
        kinds: set[TermKind] = set()
        for term in self.terms:
            if not self.applies(term, scenario):
                continue
            weight = float(getattr(w, term.weight) if isinstance(term.weight, str) else term.weight)
            if term.optional and weight == 0.0:
                continue
            if term.kind is TermKind.PLANE and not scenario.planes.count:
                continue
            if term.kind in (TermKind.OBSTACLE, TermKind.CLEARANCE) and not scenario.obstacles:
                continue
            kinds.add(term.kind)
            codes.append(CODE[term.kind])
            values.append(weight)
            data += PACK[term.kind](scenario)
            slack = slack or term.kind is TermKind.SLACK
            start.append(len(data))
        return ProgramData(
            np.array(codes, dtype=np.int64),
            np.array(values, dtype=float),
            np.array(start, dtype=np.int64),
            np.array(data, dtype=float),
            slack,
            (scenario.planes.count if TermKind.PLANE in kinds else 0)
            + (2 * (scenario.n + 1) * len(scenario.obstacles) if TermKind.OBSTACLE in kinds else 0),
        )

    def blind(self) -> Controller:
        """This controller without its obstacle rows (``"<name> blind"``): what it does when it
        does not see the obstacles, for comparisons."""
        terms = tuple(t for t in self.terms if t.kind is not TermKind.OBSTACLE)
        return Controller(f"{self.name} blind", terms)


_TASK = Term(TermKind.TASK)
_EFFORT = Term(TermKind.EFFORT)  # weight 1: the IVKC objective E alone
_EFFORT_W = Term(TermKind.EFFORT, "effort")
_MANIP = Term(TermKind.MANIPULABILITY, "manipulability")
_CENTRING = Term(TermKind.CENTRING, "centring", optional=True)
_CLEARANCE = Term(TermKind.CLEARANCE, "clearance", optional=True)
_SLACK = Term(TermKind.SLACK, "slack", When.NON_REDUNDANT)
_SLACK_ALWAYS = Term(TermKind.SLACK, "slack")
_SLACK_AROUND = Term(TermKind.SLACK, "slack", When.NON_REDUNDANT_OR_OBSTACLES)
"""C-EMDM's slack: the brief's on a non-redundant arm, and on every arm in a scene with
obstacles, where a task held exactly cannot go around an obstacle (docs/mathematics.md,
"Obstacles")."""
_JOINTS = (
    Term(TermKind.VELOCITY_BOX),
    Term(TermKind.DAMPER),
    Term(TermKind.PLANE),
    Term(TermKind.OBSTACLE),
)
"""What the constrained controllers add: the joint limits, and the planes and obstacles of a
scenario that has some (the unconstrained ones ignore them as they ignore joint limits). The
obstacle rows come last: their tightening reads the joint bounds."""


class Name(StrEnum):
    """The controllers' names: the brief's four and the baselines."""

    UC_IVKC = "UC-IVKC"
    C_IVKC = "C-IVKC"
    UC_EMDM = "UC-EMDM"
    C_EMDM = "C-EMDM"
    RRMC = "RRMC"
    PARK = "PARK"
    MMC = "MMC"
    NEO = "NEO"


CONTROLLERS: dict[str, Controller] = {
    Name.UC_IVKC: Controller(Name.UC_IVKC, (_TASK, _EFFORT)),
    Name.C_IVKC: Controller(Name.C_IVKC, (_TASK, _EFFORT, *_JOINTS)),
    Name.UC_EMDM: Controller(Name.UC_EMDM, (_TASK, _EFFORT_W, _MANIP, _CENTRING, _SLACK)),
    Name.C_EMDM: Controller(
        Name.C_EMDM, (_TASK, _EFFORT_W, _MANIP, _CENTRING, _CLEARANCE, _SLACK_AROUND, *_JOINTS)
    ),
}
"""The brief's four controllers (module docstring)."""


BASELINES: dict[str, Controller] = {
    Name.RRMC: Controller(Name.RRMC, (_TASK, _EFFORT)),
    Name.PARK: Controller(Name.PARK, (_TASK, _EFFORT_W, _MANIP)),
    Name.MMC: Controller(Name.MMC, (_TASK, _EFFORT_W, _MANIP, _SLACK_ALWAYS, *_JOINTS[:3])),
    Name.NEO: Controller(Name.NEO, (_TASK, _EFFORT_W, _MANIP, _SLACK_ALWAYS, *_JOINTS)),
}
"""The controllers of the manipulability benchmark besides the brief's four (module docstring)."""


def get_controller(name: str) -> Controller:
    """The controller called ``name`` (case-insensitive), or an :class:`EmdmError` listing them
    (a :class:`~emdm.errors.ScenarioError` when ``name`` is not a string)."""
    _Checker("get_controller").text("name", name, "a controller's name")
    exact = CONTROLLERS.get(name) or BASELINES.get(name)  # the usual call: a name as printed
    if exact is not None:
        return exact
    for key, controller in (CONTROLLERS | BASELINES).items():
        if key.lower() == name.lower():
            return controller
    known = ", ".join([*CONTROLLERS, *BASELINES])
    raise EmdmError(f"unknown controller {name!r} (known: {known})")


def controller_of(source: str, controller: Any) -> Controller:
    """``controller`` (a name or a :class:`Controller`) as a Controller, for the function
    ``source``: a ScenarioError naming ``controller`` when it is neither, an :class:`EmdmError`
    for an unknown name."""
    if isinstance(controller, Controller):
        return controller
    _Checker(source).text("controller", controller, "a controller's name or a Controller")
    return get_controller(controller)


def _scenario(check: _Checker, scenario: Any) -> None:
    check.instance("scenario", scenario, Scenario, "a Scenario (from emdm.load_scenario)")


def _inputs(source: str, scenario: Any, weights: Any) -> None:
    """``scenario`` a Scenario and ``weights`` None or Weights, for the function ``source``."""
    if isinstance(scenario, Scenario) and isinstance(weights, Weights | None):
        return
    check = _Checker(source)
    _scenario(check, scenario)
    check.instance("weights", weights, (Weights, type(None)), "None or a Weights")


def _joints(check: _Checker, scenario: Scenario, q: Any) -> Vector:
    """``q`` (rad): ``n`` finite joint values of ``scenario``'s arm."""
    n = scenario.n
    return check.array("q", q, (n,), what=lambda: f"{n} joint values")


def joint_bounds(scenario: Scenario, q: Vector) -> Bounds:
    """The velocity box intersected with the position dampers at ``q`` (the C- bounds).

    Raises :class:`~emdm.errors.ScenarioError` unless ``scenario`` is a Scenario and ``q`` its
    ``n`` finite joint values."""
    check = _Checker("joint_bounds")
    _scenario(check, scenario)
    q_arr = _joints(check, scenario, q)
    lo, hi = np.empty(scenario.n), np.empty(scenario.n)
    _joint_bounds(scenario.arm_data, q_arr, lo, hi)
    return Bounds(lo, hi)


def slack_weight(scenario: Scenario, error_norm: float, weights: Weights | None = None) -> float:
    """``w_S = c_S / max(||e||, 1e-9 m)``: heavier as the end effector nears the goal."""
    c_s = (weights or scenario.weights).slack
    return c_s / max(error_norm, ERROR_FLOOR)


def step_program(
    controller: Controller,
    scenario: Scenario,
    q: Vector,
    kin: Kinematics,
    v: Vector,
    error_norm: float,
    *,
    weights: Weights | None = None,
    t: float = 0.0,
    floor: float = SLOWEST,
) -> QP:
    """The program of ``controller`` at configuration ``q`` and time ``t`` (s; where obstacles
    move) for the desired velocity ``v``.

    Raises :class:`~emdm.errors.ScenarioError` naming the argument that is not valid:
    ``controller`` a Controller, ``scenario`` a Scenario, ``q`` its ``n`` finite joint values,
    ``kin`` the Kinematics of its task (``p``: task rows, ``J``: task rows x n, ``Jm``: n, all
    finite), ``v`` finite task rows, ``error_norm``, ``floor`` finite and >= 0, ``t`` finite,
    ``weights`` None or Weights.
    """
    check = _Checker("step_program")
    check.instance("controller", controller, Controller, "a Controller (emdm.get_controller)")
    _scenario(check, scenario)
    n, nt = scenario.n, scenario.nt
    q_arr = _joints(check, scenario, q)
    check.instance("kin", kin, Kinematics, "the Kinematics at q")
    for key, value, shape in (
        ("kin.p", kin.p, (nt,)),
        ("kin.J", kin.J, (nt, n)),
        ("kin.Jm", kin.Jm, (n,)),
    ):
        check.array(key, value, shape)
    v_arr = check.array("v", v, (nt,), what=lambda: f"{nt} numbers (one per task row)")
    error = check.real("error_norm", error_norm, nonnegative=True)
    _inputs("step_program", scenario, weights)
    time = check.real("t", t)
    least = check.real("floor", floor, nonnegative=True)
    return _step_program(
        controller, scenario, q_arr, kin, v_arr, error, weights=weights, t=time, floor=least
    )


def _step_program(
    controller: Controller,
    scenario: Scenario,
    q: Vector,
    kin: Kinematics,
    v: Vector,
    error_norm: float,
    *,
    weights: Weights | None = None,
    t: float = 0.0,
    floor: float = SLOWEST,
) -> QP:
    """:func:`step_program` for checked arguments (the per-step path)."""
    data = controller.program_data(scenario, weights)
    n, nt = scenario.n, scenario.nt
    pts, axes = np.zeros((n + 2, POINT)), np.zeros((n, AXIS))
    gaps = np.zeros((len(scenario.obstacles), n + 1, GAP))
    if scenario.obstacles:
        chain_points_of(
            scenario.arm_data.lengths, scenario.geometry, np.asarray(q, dtype=float), pts, axes
        )
        link_gaps(np.array(scenario.obstacle_data), float(t), pts, gaps)
    nx = n + nt if data.slack else n
    out = ProgramOut(
        np.empty((nx, nx)),
        np.empty(nx),
        np.zeros((nt, nx)),
        np.empty(nt),
        np.zeros((data.rows, nx)),
        np.zeros(data.rows),
        np.empty(nx),
        np.empty(nx),
        np.zeros(data.rows),
    )
    state = StepInput(
        np.asarray(q, dtype=float),
        np.ascontiguousarray(kin.J, dtype=float),
        np.ascontiguousarray(kin.Jm, dtype=float),
        np.asarray(v, dtype=float),
        float(error_norm),
        np.ascontiguousarray(kin.p, dtype=float),
        float(t),
        pts,
        axes,
        gaps,
        float(floor),
    )
    rows = build_program(data, state, out, True)
    return QP._trusted(out.P, out.c, out.A, out.b, out.lb, out.ub, n, out.G[:rows], out.h[:rows])


@dataclass(frozen=True, eq=False)
class Admissible:
    """The program actually solved at a step, after the infeasibility policy.

    ``alpha`` is the task scale (1 when the nominal program is feasible); ``policy`` names the policy
    that changed the program (``None`` when it was feasible as built).
    """

    qp: QP
    alpha: float
    policy: str | None


def admissible(qp: QP, policy: str, *, slack_weight: float, step: int | None = None) -> Admissible:
    """Apply the infeasibility policy ``policy`` (``scale``, ``slack`` or ``error``) to ``qp``.

    Raises :class:`~emdm.errors.NoSolution` when no admissible program exists under the policy,
    and :class:`~emdm.errors.ScenarioError` naming the argument that is not valid: ``qp`` a QP,
    ``policy`` one of the policies, ``slack_weight`` a finite number > 0, ``step`` None or an
    integer >= 0.
    """
    check = _Checker("admissible")
    check.instance("qp", qp, QP, "a QP")
    if not isinstance(policy, str) or policy not in POLICIES:
        raise check.fail("policy", f"must be one of {', '.join(POLICIES)}, got {_show(policy)}")
    weight = check.real("slack_weight", slack_weight, positive=True)
    if step is not None:
        check.count("step", step, 0, 2**62)
    return _admissible(qp, policy, slack_weight=weight, step=step)


def _admissible(qp: QP, policy: str, *, slack_weight: float, step: int | None = None) -> Admissible:
    """:func:`admissible` for checked arguments (the per-step path)."""
    alpha = _task_scale(qp.A, qp.b, qp.lb, qp.ub, qp.G, qp.h)
    if alpha == 1.0:
        return Admissible(qp, 1.0, None)
    where = f"step {step}: " if step is not None else ""
    reach = (
        "no task scale in [0, 1] is feasible"
        if alpha is None
        else (f"the bounds deliver at most alpha = {alpha:.6g} of the desired velocity")
    )
    if policy == "scale":
        if alpha is None:
            forced = np.flatnonzero((qp.lb[: qp.n_joints] > 0) | (qp.ub[: qp.n_joints] < 0))
            if forced.size:
                j = int(forced[0])
                raise NoSolution(
                    f"{where}joint {j + 1} is inside a stop zone: its damper forces a speed in "
                    f"[{qp.lb[j]:.3g}, {qp.ub[j]:.3g}] rad/s that no task scale in [0, 1] allows "
                    "(dt >= gain * (influence - stop) lets the damper overshoot)",
                    problem=qp,
                )
            limits = "the joint bounds"
            if qp.n_rows and np.any(qp.h < 0):  # a plane or obstacle damper asks to move away
                limits = (
                    f"the joint bounds and {qp.n_rows} damper row(s) of planes or obstacles, one "
                    "of them asking to move away from a plane or an obstacle"
                )
            raise NoSolution(
                f"{where}the program is infeasible even with the task scaled to zero "
                f"({limits} exclude every motion that keeps the task direction)",
                problem=qp,
            )
        return Admissible(qp._rhs(alpha * qp.b), alpha, "scale")
    if policy == "slack":
        relaxed = qp._free_slack(slack_weight)
        if _task_scale(relaxed.A, relaxed.b, relaxed.lb, relaxed.ub, relaxed.G, relaxed.h) != 1.0:
            raise NoSolution(
                f"{where}the program is infeasible even with free slack "
                "(the joint bounds are empty)",
                problem=qp,
            )
        return Admissible(relaxed, 1.0, "slack")
    raise NoSolution(
        f"{where}the task is infeasible under the joint bounds: {reach} "
        '(controller.on_infeasible = "error"; use "scale" or "slack" to continue)',
        problem=qp,
    )


@dataclass(frozen=True, eq=False)
class StepState:
    """What the loop knows at a state: kinematics, error ``e`` (m), desired velocity ``v`` (m/s)."""

    kin: Kinematics
    e: Vector
    v: Vector

    @property
    def error_norm(self) -> float:
        if self.e.size == 2:
            return float(np.hypot(self.e[0], self.e[1]))
        return float(np.linalg.norm(self.e))


def state_at(scenario: Scenario, q: Vector) -> StepState:
    """Brief Algorithm 1, lines 5-8: ``p = f(q)``, ``e = p_goal - p``, ``v = Kp e``, ``J``, ``Jm``:
    the task's rows of any arm, by the one compiled dispatch
    (:func:`emdm.core.kernels.task_kinematics`)."""
    n, nt = scenario.n, scenario.nt
    p, e, J, Jm = np.empty(nt), np.empty(nt), np.empty((nt, n)), np.empty(n)
    m = task_kinematics_of(
        scenario.arm_data.lengths,
        scenario.geometry,
        scenario.task_code,
        np.asarray(scenario.motion.goal, dtype=float),
        np.asarray(q, dtype=float),
        p,
        e,
        J,
        Jm,
    )
    return StepState(Kinematics(p, J, float(m), Jm), e, scenario.motion.kp * e)


def task_jacobians(scenario: Scenario, q: np.ndarray) -> np.ndarray:
    """:func:`state_at`'s task Jacobian ``J`` at every row of ``q`` (``(K, n)`` to
    ``(K, nt, n)``), by the same compiled dispatch with one set of buffers: a 600-state run in
    1.2 ms, not the 2.9 ms of a :class:`StepState` per row."""
    n, nt = scenario.n, scenario.nt
    rows = np.ascontiguousarray(q, dtype=float)
    J = np.empty((rows.shape[0], nt, n))
    p, e, Jm = np.empty(nt), np.empty(nt), np.empty(n)
    lengths, geometry, task = scenario.arm_data.lengths, scenario.geometry, scenario.task_code
    goal = np.asarray(scenario.motion.goal, dtype=float)
    for k in range(rows.shape[0]):
        task_kinematics_of(lengths, geometry, task, goal, rows[k], p, e, J[k], Jm)
    return J


def goal_of(scenario: Scenario, q: Vector) -> Vector:
    """The task value at ``q``: a goal that ``q`` reaches exactly (planar tip position, spatial
    position, or position and rotation vector of the pose)."""
    return state_at(scenario, q).kin.p


def program_at(
    controller: Controller,
    scenario: Scenario,
    q: Vector,
    state: StepState | None = None,
    *,
    weights: Weights | None = None,
    step: int | None = None,
) -> Admissible:
    """The admissible program of ``controller`` at ``q``: built, then the policy applied."""
    st = state or state_at(scenario, q)
    nominal = _step_program(controller, scenario, q, st.kin, st.v, st.error_norm, weights=weights)
    return _admissible(
        nominal,
        scenario.controller.on_infeasible,
        slack_weight=slack_weight(scenario, st.error_norm, weights),
        step=step,
    )
