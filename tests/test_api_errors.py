"""Bad arguments to the public Python API (issue 25, item 4): each gets a documented exception
whose one-line message names the argument, never a raw numpy or numba error, an AttributeError,
a crash or a silent answer.

Every row of :data:`CASES` is one bad call: the exception type it must raise (exactly), and the
argument's name, which the message must hold as a word of its own. The rows marked ``before``
raised something else before the arguments were checked at the API's entry (a numpy or numba
error, an AttributeError, no exception at all, a message not naming the argument, or an
out-of-bounds write in a compiled kernel); the others already did and stay as they are.
"""

from __future__ import annotations

import math
import re
from types import SimpleNamespace

import numpy as np
import pytest

import emdm
from emdm import EmdmError, ScenarioError, SolverNotFound
from emdm.core.controllers import state_at

NAN, INF = math.nan, math.inf


@pytest.fixture(scope="module")
def E():
    t1 = emdm.load_scenario("task1")
    ctrl = emdm.get_controller("C-EMDM")
    st = state_at(t1, t1.motion.q0)
    qp = emdm.step_program(ctrl, t1, t1.motion.q0, st.kin, st.v, st.error_norm)
    panda = emdm.load_scenario("panda")
    return SimpleNamespace(
        em=emdm,
        t1=t1,
        q0=t1.motion.q0,
        ctrl=ctrl,
        st=st,
        qp=qp,
        arm=emdm.PlanarArm([1.0, 1.0, 1.0]),
        panda=panda,
        sarm=panda.serial_arm,
        obstacle=emdm.load_scenario("obstacle"),
    )


def _qp(E, **changes):
    qp = E.qp
    fields = dict(P=qp.P, c=qp.c, A=qp.A, b=qp.b, lb=qp.lb, ub=qp.ub, n_joints=qp.n_joints)
    fields |= dict(G=qp.G, h=qp.h)
    return emdm.QP(**(fields | changes))


def _step(E, **changes):
    args = dict(controller=E.ctrl, scenario=E.t1, q=E.q0, kin=E.st.kin, v=E.st.v, error_norm=1.0)
    keywords = {k: changes.pop(k) for k in ("t", "floor", "weights") if k in changes}
    args |= changes
    return emdm.step_program(*args.values(), **keywords)


def _feas(E, name, **changes):
    """``task_scale`` or ``feasible_point`` of the program ``E.qp``, with ``changes``."""
    args = dict(A=E.qp.A, b=E.qp.b, lb=E.qp.lb, ub=E.qp.ub) | changes
    return getattr(emdm, name)(**args)


def _with(E, section, key, value):
    data = E.t1.to_dict()
    data[section] = {**data[section], key: value}
    return data


# fmt: off
SE, BEFORE = ScenarioError, True
CASES = [
    # ------------------------------------------------------------------ load_scenario
    ("load_scenario(None)", lambda E: E.em.load_scenario(None), SE, "name_or_path", BEFORE),
    ("load_scenario(123)", lambda E: E.em.load_scenario(123), SE, "name_or_path", BEFORE),
    ("load_scenario([str])", lambda E: E.em.load_scenario(["task1"]), SE, "name_or_path", BEFORE),
    ("load_scenario(unknown)", lambda E: E.em.load_scenario("nope"), SE, "nope", False),
    ("load_scenario(overrides=str)", lambda E: E.em.load_scenario("task1", "motion.dt=1"), SE,
     "overrides", BEFORE),
    ("load_scenario(overrides=list)",
     lambda E: E.em.load_scenario("task1", [("motion.dt", 0.01)]), SE, "overrides", BEFORE),
    ("load_scenario(overrides={1: 2})", lambda E: E.em.load_scenario("task1", {1: 2}), SE,
     "overrides", BEFORE),
    ("load_scenario(q0 ndarray)",
     lambda E: E.em.load_scenario("task1", {"motion.q0": np.array([0.0, 0.5, 0.5])}), SE,
     "motion.q0", BEFORE),
    ("load_scenario(dt nan)", lambda E: E.em.load_scenario("task1", {"motion.dt": NAN}), SE,
     "motion.dt", False),
    ("load_scenario(dt True)", lambda E: E.em.load_scenario("task1", {"motion.dt": True}), SE,
     "motion.dt", False),
    ("load_scenario(dt -1)", lambda E: E.em.load_scenario("task1", {"motion.dt": -1.0}), SE,
     "motion.dt", False),
    # ------------------------------------------------------------- scenario_from_dict
    ("scenario_from_dict(source=None)",
     lambda E: E.em.scenario_from_dict(
         {k: v for k, v in E.t1.to_dict().items() if k != "name"}, source=None), SE, "source",
     BEFORE),
    ("scenario_from_dict(source=123)",
     lambda E: E.em.scenario_from_dict(
         {k: v for k, v in E.t1.to_dict().items() if k != "name"}, source=123), SE, "source",
     BEFORE),
    ("scenario_from_dict(None)", lambda E: E.em.scenario_from_dict(None), SE, "data", BEFORE),
    ("scenario_from_dict(q0 ndarray)",
     lambda E: E.em.scenario_from_dict(_with(E, "motion", "q0", np.array([0.0, 0.5, 0.5]))), SE,
     "motion.q0", BEFORE),
    ("scenario_from_dict(lengths ndarray)",
     lambda E: E.em.scenario_from_dict(_with(E, "arm", "lengths", np.ones(3))), SE,
     "arm.lengths", BEFORE),
    ("scenario_from_dict(goal ndarray)",
     lambda E: E.em.scenario_from_dict(_with(E, "motion", "goal", np.ones(2))), SE,
     "motion.goal", BEFORE),
    ("scenario_from_dict(q0 [str])",
     lambda E: E.em.scenario_from_dict(_with(E, "motion", "q0", ["a", "b", "c"])), SE,
     "motion.q0", False),
    ("scenario_from_dict(on_infeasible x)",
     lambda E: E.em.scenario_from_dict(_with(E, "controller", "on_infeasible", "x")), SE,
     "controller.on_infeasible", False),
    ("scenario_from_dict(slack x)",
     lambda E: E.em.scenario_from_dict(_with(E, "controller", "slack", "x")), SE,
     "controller.slack", False),
    # ------------------------------------------------------------------ Scenario methods
    ("with_overrides(None)", lambda E: E.t1.with_overrides(None), SE, "overrides", BEFORE),
    ("with_overrides(str)", lambda E: E.t1.with_overrides("motion.dt=1"), SE, "overrides",
     BEFORE),
    ("with_overrides({1: 2})", lambda E: E.t1.with_overrides({1: 2}), SE, "overrides", BEFORE),
    ("with_overrides(kp inf)", lambda E: E.t1.with_overrides({"motion.kp": INF}), SE,
     "motion.kp", False),
    ("plane_distances(str)", lambda E: E.t1.plane_distances("abc"), SE, "q", BEFORE),
    ("plane_distances(short)", lambda E: E.t1.plane_distances([0.0, 0.0]), SE, "q", False),
    ("obstacle_distances(short)", lambda E: E.obstacle.obstacle_distances([0.0, 0.0]), SE, "q",
     BEFORE),
    ("obstacle_distances(t str)",
     lambda E: E.obstacle.obstacle_distances(E.obstacle.motion.q0, "x"), SE, "t", BEFORE),
    ("obstacle_distances(t nan)",
     lambda E: E.obstacle.obstacle_distances(E.obstacle.motion.q0, NAN), SE, "t", BEFORE),
    # ---------------------------------------------------------- get_controller / get_solver
    ("get_controller(None)", lambda E: E.em.get_controller(None), SE, "name", BEFORE),
    ("get_controller(5)", lambda E: E.em.get_controller(5), SE, "name", BEFORE),
    ("get_controller([str])", lambda E: E.em.get_controller(["C-EMDM"]), SE, "name", BEFORE),
    ("get_controller(unknown)", lambda E: E.em.get_controller("X-EMDM"), EmdmError, "X-EMDM",
     False),
    ("get_solver(None)", lambda E: E.em.get_solver(None), SE, "name", BEFORE),
    ("get_solver(3)", lambda E: E.em.get_solver(3), SE, "name", BEFORE),
    ("get_solver(unknown)", lambda E: E.em.get_solver("nope"), SolverNotFound, "nope", False),
    # ------------------------------------------------------------------------ simulate
    ("simulate(None)", lambda E: E.em.simulate(None, "C-EMDM"), SE, "scenario", BEFORE),
    ("simulate(str)", lambda E: E.em.simulate("task1", "C-EMDM"), SE, "scenario", BEFORE),
    ("simulate(dict)", lambda E: E.em.simulate(E.t1.to_dict(), "C-EMDM"), SE, "scenario",
     BEFORE),
    ("simulate(controller None)", lambda E: E.em.simulate(E.t1, None), SE, "controller", BEFORE),
    ("simulate(controller 3)", lambda E: E.em.simulate(E.t1, 3), SE, "controller", BEFORE),
    ("simulate(controller unknown)", lambda E: E.em.simulate(E.t1, "nope"), EmdmError, "nope",
     False),
    ("simulate(solver None)", lambda E: E.em.simulate(E.t1, "C-EMDM", solver=None), SE, "solver",
     BEFORE),
    ("simulate(solver unknown)", lambda E: E.em.simulate(E.t1, "C-EMDM", solver="nope"),
     SolverNotFound, "nope", False),
    ("simulate(fallback None)", lambda E: E.em.simulate(E.t1, "C-EMDM", fallback=None), SE,
     "fallback", BEFORE),
    ("simulate(fallback str)", lambda E: E.em.simulate(E.t1, "C-EMDM", fallback="daqp"), SE,
     "fallback", BEFORE),
    ("simulate(fallback [1])", lambda E: E.em.simulate(E.t1, "C-EMDM", fallback=[1]), SE,
     "fallback", BEFORE),
    ("simulate(certify str)", lambda E: E.em.simulate(E.t1, "C-EMDM", certify="no"), SE,
     "certify", BEFORE),
    ("simulate(budget 0)", lambda E: E.em.simulate(E.t1, "C-EMDM", budget=0), SE, "budget",
     BEFORE),
    ("simulate(budget 2.5)", lambda E: E.em.simulate(E.t1, "C-EMDM", budget=2.5), SE, "budget",
     BEFORE),
    ("simulate(budget True)", lambda E: E.em.simulate(E.t1, "C-EMDM", budget=True), SE,
     "budget", BEFORE),
    # ------------------------------------------------------------------ simulate_batch
    ("simulate_batch(None)", lambda E: E.em.simulate_batch(None, "C-EMDM"), SE, "scenario",
     BEFORE),
    ("simulate_batch(controller None)", lambda E: E.em.simulate_batch(E.t1, None), SE,
     "controller", BEFORE),
    ("simulate_batch(goals str)", lambda E: E.em.simulate_batch(E.t1, "C-EMDM", goals="abc"), SE,
     "goals", BEFORE),
    ("simulate_batch(goals [[str]])",
     lambda E: E.em.simulate_batch(E.t1, "C-EMDM", goals=[["a", "b"]]), SE, "goals", BEFORE),
    ("simulate_batch(goals R x 3)",
     lambda E: E.em.simulate_batch(E.t1, "C-EMDM", goals=np.ones((4, 3))), SE, "goals", BEFORE),
    ("simulate_batch(goals 3-D)",
     lambda E: E.em.simulate_batch(E.t1, "C-EMDM", goals=np.ones((4, 2, 1))), SE, "goals",
     BEFORE),
    ("simulate_batch(goals nan)",
     lambda E: E.em.simulate_batch(E.t1, "C-EMDM", goals=[[NAN, 1.0]]), SE, "goals", BEFORE),
    ("simulate_batch(goals inf)",
     lambda E: E.em.simulate_batch(E.t1, "C-EMDM", goals=[[INF, 1.0]]), SE, "goals", BEFORE),
    ("simulate_batch(goals [None])",
     lambda E: E.em.simulate_batch(E.t1, "C-EMDM", goals=[None, None]), SE, "goals", BEFORE),
    ("simulate_batch(goals 1e300)",
     lambda E: E.em.simulate_batch(E.t1, "C-EMDM", goals=[[1e300, 0.0]]), SE, "goals", BEFORE),
    ("simulate_batch(3 goals, 2 q0s)",
     lambda E: E.em.simulate_batch(E.t1, "C-EMDM", goals=np.ones((3, 2)),
                                   q0s=np.tile(E.q0, (2, 1))), SE, "q0s", BEFORE),
    ("simulate_batch(q0s R x 2)",
     lambda E: E.em.simulate_batch(E.t1, "C-EMDM", q0s=np.zeros((3, 2))), SE, "q0s", BEFORE),
    ("simulate_batch(q0s nan)",
     lambda E: E.em.simulate_batch(E.t1, "C-EMDM", q0s=[[NAN, 0.5, 0.5]]), SE, "q0s", BEFORE),
    ("simulate_batch(q0s dict)",
     lambda E: E.em.simulate_batch(E.t1, "C-EMDM", q0s={"a": 1}), SE, "q0s", BEFORE),
    ("simulate_batch(q0s bool)",
     lambda E: E.em.simulate_batch(E.t1, "C-EMDM", q0s=[[True, False, True]]), SE, "q0s", BEFORE),
    ("simulate_batch(q0s outside limits)",
     lambda E: E.em.simulate_batch(E.t1, "C-EMDM", q0s=[[10.0, 0.5, 0.5]]), SE, "q0s", BEFORE),
    # ------------------------------------------------------------------------- metrics
    ("metrics(None)", lambda E: E.em.metrics(None), SE, "run", BEFORE),
    ("metrics(Scenario)", lambda E: E.em.metrics(E.t1), SE, "run", BEFORE),
    ("metrics({})", lambda E: E.em.metrics({}), SE, "run", BEFORE),
    # ----------------------------------------------------------------------- PlanarArm
    ("PlanarArm(str)", lambda E: E.em.PlanarArm("abc"), SE, "lengths", BEFORE),
    ("PlanarArm([1, str])", lambda E: E.em.PlanarArm([1.0, "a"]), SE, "lengths", BEFORE),
    ("PlanarArm(dict)", lambda E: E.em.PlanarArm({"a": 1}), SE, "lengths", BEFORE),
    ("PlanarArm([bool])", lambda E: E.em.PlanarArm([True, True]), SE, "lengths", BEFORE),
    ("PlanarArm(None)", lambda E: E.em.PlanarArm(None), SE, "lengths", False),
    ("PlanarArm([1])", lambda E: E.em.PlanarArm([1.0]), SE, "lengths", False),
    ("PlanarArm([])", lambda E: E.em.PlanarArm([]), SE, "lengths", False),
    ("PlanarArm(nan)", lambda E: E.em.PlanarArm([1.0, NAN]), SE, "lengths", False),
    ("PlanarArm(-1)", lambda E: E.em.PlanarArm([1.0, -1.0]), SE, "lengths", False),
    ("PlanarArm(200000 links)", lambda E: E.em.PlanarArm([0.01] * 200_000), SE, "lengths",
     BEFORE),
    ("PlanarArm.kinematics(str)", lambda E: E.arm.kinematics("abc"), SE, "q", BEFORE),
    ("PlanarArm.kinematics(nan)", lambda E: E.arm.kinematics([NAN, 0.0, 0.0]), SE, "q", BEFORE),
    ("PlanarArm.forward(dict)", lambda E: E.arm.forward({"a": 1}), SE, "q", BEFORE),
    ("PlanarArm.joint_positions([str])", lambda E: E.arm.joint_positions(["a", "b", "c"]), SE,
     "q", BEFORE),
    ("PlanarArm.kinematics(short)", lambda E: E.arm.kinematics([0.0, 0.0]), SE, "q", False),
    ("PlanarArm.hessian(short)", lambda E: E.arm.hessian([0.0, 0.0]), SE, "q", False),
    # ----------------------------------------------------------------------- SerialArm
    ("SerialArm(str)", lambda E: E.em.SerialArm("abc"), SE, "dh", BEFORE),
    ("SerialArm([[1, str, 0, 0]])", lambda E: E.em.SerialArm([[1.0, "a", 0.0, 0.0]]), SE, "dh",
     BEFORE),
    ("SerialArm([[1, 2, 3]])", lambda E: E.em.SerialArm([[1.0, 2.0, 3.0]]), SE, "dh", False),
    ("SerialArm(nan)", lambda E: E.em.SerialArm([[NAN, 0.0, 0.0, 0.0]]), SE, "dh", False),
    ("SerialArm(convention None)", lambda E: E.em.SerialArm(E.sarm.dh, None), SE, "convention",
     False),
    ("SerialArm(tool str)", lambda E: E.em.SerialArm(E.sarm.dh, tool="abc"), SE, "tool", BEFORE),
    ("SerialArm(tool [1, 2])", lambda E: E.em.SerialArm(E.sarm.dh, tool=[1.0, 2.0]), SE, "tool",
     False),
    ("SerialArm.from_urdf(None)", lambda E: E.em.SerialArm.from_urdf(None), SE, "path", BEFORE),
    ("SerialArm.from_chain(None)", lambda E: E.em.SerialArm.from_chain(None), SE, "chain",
     BEFORE),
    ("SerialArm.forward(str)", lambda E: E.sarm.forward("abc"), SE, "q", BEFORE),
    ("SerialArm.forward(nan)", lambda E: E.sarm.forward([NAN] * 7), SE, "q", BEFORE),
    ("SerialArm.forward(short)", lambda E: E.sarm.forward([0.0] * 3), SE, "q", False),
    ("SerialArm.manipulability(axes list)",
     lambda E: E.sarm.manipulability(E.panda.motion.q0, ["all"]), SE, "axes", BEFORE),
    ("SerialArm.manipulability(axes x)", lambda E: E.sarm.manipulability(E.panda.motion.q0, "x"),
     SE, "axes", False),
    # ----------------------------------------------------------------- QP / Objective
    ("QP(P 2 x 2)", lambda E: _qp(E, P=np.eye(2)), SE, "P", BEFORE),
    ("QP(c short)", lambda E: _qp(E, c=np.zeros(2)), SE, "c", BEFORE),
    ("QP(A 2 columns)", lambda E: _qp(E, A=np.zeros((2, 2))), SE, "A", BEFORE),
    ("QP(b long)", lambda E: _qp(E, b=np.zeros(3)), SE, "b", BEFORE),
    ("QP(lb short)", lambda E: _qp(E, lb=np.zeros(1)), SE, "lb", BEFORE),
    ("QP(ub long)", lambda E: _qp(E, ub=np.zeros(7)), SE, "ub", BEFORE),
    ("QP(n_joints -1)", lambda E: _qp(E, n_joints=-1), SE, "n_joints", BEFORE),
    ("QP(n_joints 99)", lambda E: _qp(E, n_joints=99), SE, "n_joints", BEFORE),
    ("QP(n_joints str)", lambda E: _qp(E, n_joints="3"), SE, "n_joints", BEFORE),
    ("QP(n_joints True)", lambda E: _qp(E, n_joints=True), SE, "n_joints", BEFORE),
    ("QP(P nan)", lambda E: _qp(E, P=np.full((3, 3), NAN)), SE, "P", BEFORE),
    ("QP(c inf)", lambda E: _qp(E, c=np.full(3, INF)), SE, "c", BEFORE),
    ("QP(lb nan)", lambda E: _qp(E, lb=np.full(3, NAN)), SE, "lb", BEFORE),
    ("QP(G None)", lambda E: _qp(E, G=None), SE, "G", BEFORE),
    ("QP(P str)", lambda E: _qp(E, P="abc"), SE, "P", BEFORE),
    ("QP(G 2 columns)", lambda E: _qp(E, G=np.zeros((1, 2)), h=np.zeros(1)), SE, "G",
     BEFORE),  # a plain ValueError before: now the ScenarioError (a ValueError) of every field
    ("QP.objective(short)", lambda E: E.qp.objective(np.zeros(2)), SE, "x", BEFORE),
    ("QP.bound_excess(one value)", lambda E: E.qp.bound_excess(np.zeros(1)), SE, "x", BEFORE),
    ("QP.violation(str)", lambda E: E.qp.violation("abc"), SE, "x", BEFORE),
    ("QP.with_rhs(long)", lambda E: E.qp.with_rhs([1.0, 2.0, 3.0]), SE, "b", BEFORE),
    ("QP.with_free_slack(nan)", lambda E: E.qp.with_free_slack(NAN), SE, "weight", BEFORE),
    ("QP.with_free_slack(str)", lambda E: E.qp.with_free_slack("x"), SE, "weight", BEFORE),
    ("Objective(str, str)", lambda E: E.em.Objective("a", "b"), SE, "P", BEFORE),
    ("Objective(2 x 2, 3)", lambda E: E.em.Objective(np.eye(2), np.zeros(3)), SE, "c", BEFORE),
    ("Objective + other size",
     lambda E: E.em.Objective(np.eye(2), np.zeros(2)) + E.em.Objective(np.eye(3), np.zeros(3)),
     SE, "other", BEFORE),
    ("Objective.stack(None)", lambda E: E.em.Objective(np.eye(2), np.zeros(2)).stack(None), SE,
     "other", BEFORE),
    # ------------------------------------------------------------ kkt_report / solve_chain
    ("kkt_report(x short)", lambda E: E.em.kkt_report(E.qp, np.zeros(2)), SE, "x", BEFORE),
    ("kkt_report(x long)", lambda E: E.em.kkt_report(E.qp, np.zeros(50)), SE, "x", BEFORE),
    ("kkt_report(x None)", lambda E: E.em.kkt_report(E.qp, None), SE, "x", BEFORE),
    ("kkt_report(x str)", lambda E: E.em.kkt_report(E.qp, "abc"), SE, "x", BEFORE),
    ("kkt_report(x 2-D)", lambda E: E.em.kkt_report(E.qp, np.zeros((3, 1))), SE, "x", BEFORE),
    ("kkt_report(qp None)", lambda E: E.em.kkt_report(None, np.zeros(3)), SE, "qp", BEFORE),
    ("solve_chain(qp None)", lambda E: E.em.solve_chain(None, ["active-set"]), SE, "qp", BEFORE),
    ("solve_chain(chain str)", lambda E: E.em.solve_chain(E.qp, "active-set"), SE, "chain",
     BEFORE),
    ("solve_chain(chain [])", lambda E: E.em.solve_chain(E.qp, []), SE, "chain", BEFORE),
    ("solve_chain(chain None)", lambda E: E.em.solve_chain(E.qp, None), SE, "chain", BEFORE),
    ("solve_chain(chain [None])", lambda E: E.em.solve_chain(E.qp, [None]), SE, "chain", BEFORE),
    ("solve_chain(tol str)", lambda E: E.em.solve_chain(E.qp, ["active-set"], tol="x"), SE,
     "tol", BEFORE),
    ("solve_chain(tol nan)", lambda E: E.em.solve_chain(E.qp, ["active-set"], tol=NAN), SE,
     "tol", BEFORE),
    ("solve_chain(tol -1)", lambda E: E.em.solve_chain(E.qp, ["active-set"], tol=-1.0), SE,
     "tol", BEFORE),
    ("solve_chain(budget -3)", lambda E: E.em.solve_chain(E.qp, ["active-set"], budget=-3), SE,
     "budget", BEFORE),
    ("solve_chain(chain unknown)", lambda E: E.em.solve_chain(E.qp, ["nope"]), SolverNotFound,
     "nope", False),
    # -------------------------------------------------------------------- step_program
    ("step_program(controller str)", lambda E: _step(E, controller="C-EMDM"), SE, "controller",
     BEFORE),
    ("step_program(scenario None)", lambda E: _step(E, scenario=None), SE, "scenario", BEFORE),
    ("step_program(q short)", lambda E: _step(E, q=E.q0[:2]), SE, "q", BEFORE),
    ("step_program(q str)", lambda E: _step(E, q="abc"), SE, "q", BEFORE),
    ("step_program(q nan)", lambda E: _step(E, q=np.full(3, NAN)), SE, "q", BEFORE),
    ("step_program(kin None)", lambda E: _step(E, kin=None), SE, "kin", BEFORE),
    ("step_program(kin of a 2-link arm)",
     lambda E: _step(E, kin=emdm.PlanarArm([1.0, 1.0]).kinematics([0.1, 0.2])), SE, "kin.J",
     BEFORE),
    ("step_program(v short)", lambda E: _step(E, v=E.st.v[:1]), SE, "v", BEFORE),
    ("step_program(v nan)", lambda E: _step(E, v=np.full(2, NAN)), SE, "v", BEFORE),
    ("step_program(error_norm str)", lambda E: _step(E, error_norm="x"), SE, "error_norm",
     BEFORE),
    ("step_program(error_norm -1)", lambda E: _step(E, error_norm=-1.0), SE, "error_norm",
     BEFORE),
    ("step_program(error_norm nan)", lambda E: _step(E, error_norm=NAN), SE, "error_norm",
     BEFORE),
    ("step_program(t str)", lambda E: _step(E, t="x"), SE, "t", BEFORE),
    ("step_program(t nan)", lambda E: _step(E, t=NAN), SE, "t", BEFORE),
    ("step_program(weights dict)", lambda E: _step(E, weights={}), SE, "weights", BEFORE),
    ("step_program(floor -1)", lambda E: _step(E, floor=-1.0), SE, "floor", BEFORE),
    ("step_program(floor str)", lambda E: _step(E, floor="x"), SE, "floor", BEFORE),
    # -------------------------------------------------------------------- joint_bounds
    ("joint_bounds(q short)", lambda E: E.em.joint_bounds(E.t1, [0.0]), SE, "q", BEFORE),
    ("joint_bounds(q long)", lambda E: E.em.joint_bounds(E.t1, np.zeros(50)), SE, "q", BEFORE),
    ("joint_bounds(q str)", lambda E: E.em.joint_bounds(E.t1, "abc"), SE, "q", BEFORE),
    ("joint_bounds(q None)", lambda E: E.em.joint_bounds(E.t1, None), SE, "q", BEFORE),
    ("joint_bounds(q nan)", lambda E: E.em.joint_bounds(E.t1, np.full(3, NAN)), SE, "q", BEFORE),
    ("joint_bounds(q 2-D)", lambda E: E.em.joint_bounds(E.t1, [[0.0] * 3]), SE, "q", BEFORE),
    ("joint_bounds(scenario None)", lambda E: E.em.joint_bounds(None, E.q0), SE, "scenario",
     BEFORE),
    # ---------------------------------------------------------------------- admissible
    ("admissible(policy unknown)", lambda E: E.em.admissible(E.qp, "bogus", slack_weight=1.0),
     SE, "policy", BEFORE),
    ("admissible(policy None)", lambda E: E.em.admissible(E.qp, None, slack_weight=1.0), SE,
     "policy", BEFORE),
    ("admissible(qp None)", lambda E: E.em.admissible(None, "scale", slack_weight=1.0), SE, "qp",
     BEFORE),
    ("admissible(slack_weight nan)", lambda E: E.em.admissible(E.qp, "slack", slack_weight=NAN),
     SE, "slack_weight", BEFORE),
    ("admissible(slack_weight 0)", lambda E: E.em.admissible(E.qp, "slack", slack_weight=0.0),
     SE, "slack_weight", BEFORE),
    ("admissible(slack_weight str)",
     lambda E: E.em.admissible(E.qp, "slack", slack_weight="x"), SE, "slack_weight", BEFORE),
    ("admissible(step str)",
     lambda E: E.em.admissible(E.qp, "scale", slack_weight=1.0, step="x"), SE, "step", BEFORE),
    # ------------------------------------------------------------------ Controller
    ("Controller.program_data(None)", lambda E: E.ctrl.program_data(None), SE, "scenario",
     BEFORE),
    ("Controller(terms str)", lambda E: E.em.Controller("x", "abc"), SE, "terms", BEFORE),
]
for _f in ("task_scale", "feasible_point"):  # the same rows for both
    CASES += [
        (f"{_f}(A 1-D)", lambda E, f=_f: _feas(E, f, A=E.qp.A[0]), SE, "A", BEFORE),
        (f"{_f}(A 2 columns)", lambda E, f=_f: _feas(E, f, A=E.qp.A[:, :2]), SE, "lb", BEFORE),
        (f"{_f}(b short)", lambda E, f=_f: _feas(E, f, b=E.qp.b[:1]), SE, "b", BEFORE),
        (f"{_f}(lb short)", lambda E, f=_f: _feas(E, f, lb=E.qp.lb[:1]), SE, "lb", BEFORE),
        (f"{_f}(ub long)", lambda E, f=_f: _feas(E, f, ub=np.ones(9)), SE, "ub", BEFORE),
        (f"{_f}(A str)", lambda E, f=_f: _feas(E, f, A="abc"), SE, "A", BEFORE),
        (f"{_f}(A None)", lambda E, f=_f: _feas(E, f, A=None), SE, "A", BEFORE),
        (f"{_f}(b nan)", lambda E, f=_f: _feas(E, f, b=np.full(2, NAN)), SE, "b", BEFORE),
        (f"{_f}(A inf)", lambda E, f=_f: _feas(E, f, A=np.full((2, 3), INF)), SE, "A", BEFORE),
        (f"{_f}(lb nan)", lambda E, f=_f: _feas(E, f, lb=np.full(3, NAN)), SE, "lb", BEFORE),
        (f"{_f}(G 2 columns)", lambda E, f=_f: _feas(E, f, G=np.zeros((1, 2)), h=np.zeros(1)),
         SE, "G", BEFORE),
        (f"{_f}(G, 2 entries of h)",
         lambda E, f=_f: _feas(E, f, G=np.zeros((1, 3)), h=np.zeros(2)), SE, "G", BEFORE),
        (f"{_f}(G without h)", lambda E, f=_f: _feas(E, f, G=np.zeros((1, 3))), SE, "h", BEFORE),
    ]
# fmt: on


def _names(text: str, word: str) -> bool:
    """Whether ``text`` holds ``word`` as a word of its own (``q`` is not the q of ``q0s``)."""
    return re.search(rf"(?<![\w.]){re.escape(word)}(?![\w])", text) is not None


@pytest.mark.parametrize(
    ("call", "expected", "word"),
    [pytest.param(call, expected, word, id=name) for name, call, expected, word, _ in CASES],
)
def test_a_bad_argument_gets_a_one_line_error_naming_it(E, call, expected, word):
    with pytest.raises(Exception) as info:  # the exact type is asserted below
        call(E)
    exc = info.value
    assert type(exc) is expected, f"{type(exc).__module__}.{type(exc).__name__}: {exc}"
    text = str(exc)
    assert "\n" not in text and text == text.strip(), text
    assert _names(text, word), text


def test_the_table_covers_every_public_callable():
    """Every callable of ``emdm.__all__`` that takes arguments has a row (precompile and
    available_solvers take none; the exceptions and data are not called)."""
    named = " ".join(name for name, *_ in CASES)
    takes_none = {"precompile", "available_solvers"}
    not_called = {"CONTROLLERS", "PRESETS", "__version__", "BatchResult", "Run", "Kinematics",
                  "Scenario", "ScenarioWarning"}  # fmt: skip
    callables = [
        n
        for n in emdm.__all__
        if n not in takes_none | not_called and not n.endswith(("Error", "Solution", "Found"))
    ]
    missing = [n for n in callables if not re.search(rf"\b{n}\b", named)]
    assert not missing, missing
    assert sum(before for *_, before in CASES) >= 150  # the defects of the audit, fixed


def test_a_wrong_answer_shape_from_a_solver_is_a_failed_attempt(E, monkeypatch):
    """A solver whose answer has the wrong shape is recorded and skipped (the certificate's
    kernel would read past the end of it)."""
    from emdm.solvers import base

    spec = base.get_solver("kkt")
    short = base.SolverSpec("short", spec.family, lambda qp, **_: base.SolverResult(
        np.zeros(qp.n - 1), "optimal", 1, 0.0), "answers one value short")  # fmt: skip
    monkeypatch.setitem(base._REGISTRY, "short", short)
    program = emdm.admissible(E.qp, "scale", slack_weight=1.0).qp
    result = emdm.solve_chain(program, ["short", "active-set"])
    assert result.solver == "active-set" and result.fallback
    assert result.attempts[0] == (
        "short",
        f"an answer of shape ({program.n - 1},), not ({program.n},)",
    )


def test_unusual_but_valid_calls_still_answer(E):
    """What the checks must not refuse: an empty batch, a program given as lists, an empty
    feasibility problem, numpy scalars and integers where numbers are expected, a single row of
    goals as a vector, infinite bounds, large finite values."""
    empty = emdm.simulate_batch(E.t1, "C-EMDM", goals=np.empty((0, 2)))
    assert len(empty) == 0 and empty.steps.shape == (0,)
    huge = emdm.QP(
        np.eye(2), [1e200, 0.0], [[1e200, 1.0]], [1e200], [-np.inf, -1.0], [np.inf, 1.0], 2
    )
    assert emdm.kkt_report(huge, np.array([1.0, 0.0])).bound_excess == 0.0
    listed = emdm.QP([[1.0]], [0.0], [[1.0]], [0.5], [-1.0], [1.0], 1)
    assert emdm.solve_chain(listed, ["active-set"]).x.tolist() == [0.5]
    assert emdm.task_scale(np.zeros((0, 0)), np.zeros(0), np.zeros(0), np.zeros(0)) == 1.0
    assert emdm.feasible_point(np.zeros((0, 0)), np.zeros(0), np.zeros(0), np.zeros(0)).size == 0
    q = E.q0.tolist()
    a = _step(E, q=q, error_norm=np.float32(1.0), t=np.int64(0), floor=0)
    b = _step(E, error_norm=1.0, t=0.0)
    np.testing.assert_array_equal(a.P, b.P)
    np.testing.assert_array_equal(a.b, b.b)
    one = emdm.simulate_batch(E.t1, "C-EMDM", goals=list(E.t1.motion.goal))
    assert one.steps.tolist() == [emdm.simulate(E.t1, "C-EMDM").steps]
