"""The control loop (brief Algorithm 1) and its complete record.

At each state ``k`` (time ``t_k = k dt``): ``p_k = f(q_k)``, ``e_k = p_goal - p_k``, ``v_k = Kp e_k``;
the run stops when ``||e_k|| < tolerance`` (reached) or when ``t_k`` reaches ``max_time``; otherwise
the controller's program is built, made admissible by the infeasibility policy, solved through the
solver chain (the answer certified by its KKT residuals) and ``q_{k+1} = q_k + qd_k dt``.

The :class:`Run` holds ``K + 1`` states and ``K`` commands (row ``k`` of a command array is the
command computed at state ``k``). All arrays are allocated once, for ``max_time / dt`` steps.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..core.arm import Matrix, Vector
from ..core.controllers import Controller, get_controller, program_at, state_at
from ..core.scenario import Scenario
from ..errors import NoSolution
from ..solvers import DEFAULT_FALLBACK, DEFAULT_SOLVER, get_solver, solve_chain


@dataclass(eq=False)
class Run:
    """The record of one closed-loop run (DESIGN.md section 2).

    States (``K + 1`` rows): ``t`` (s), ``q`` (rad), ``p``, ``e`` (m), ``v`` (m/s), ``m``.
    Commands (``K`` rows): ``qd`` (rad/s), ``effort`` ``E = 1/2 ||qd||^2``, ``manip_rate``
    ``M = Jm . qd``, ``alpha`` (task scale), ``delta`` (task slack, m/s), joint bounds ``lo, hi``
    (rad/s, +-inf for UC), ``active`` (-1 at lo, +1 at hi, 0 free), and per solve ``solver``,
    ``status``, ``iterations``, ``solve_time`` (s), ``kkt`` (relative KKT residual), ``fallback``,
    ``attempts`` (every solver tried and its outcome) and ``policy`` (the policy that acted, or "").
    """

    scenario: Scenario
    controller: Controller
    t: Vector
    q: Matrix
    p: Matrix
    e: Matrix
    v: Matrix
    m: Vector
    qd: Matrix
    effort: Vector
    manip_rate: Vector
    alpha: Vector
    delta: Matrix
    lo: Matrix
    hi: Matrix
    active: np.ndarray
    iterations: np.ndarray
    solve_time: Vector
    kkt: Vector
    bound_excess: Vector
    fallback: np.ndarray
    solver: list[str] = field(default_factory=list)
    status: list[str] = field(default_factory=list)
    attempts: list[str] = field(default_factory=list)
    policy: list[str] = field(default_factory=list)
    reached: bool = False

    @property
    def steps(self) -> int:
        """Number of commands ``K`` (the final state has index ``K``)."""
        return int(self.qd.shape[0])

    @property
    def error_norm(self) -> Vector:
        """``||e_k||`` (m) at every state."""
        return np.asarray(np.linalg.norm(self.e, axis=1))

    @property
    def time_to_goal(self) -> float | None:
        """``t_K`` when the goal was reached, else ``None``."""
        return float(self.t[-1]) if self.reached else None


def simulate(
    scenario: Scenario,
    controller: str | Controller,
    *,
    solver: str = DEFAULT_SOLVER,
    fallback: Sequence[str] = DEFAULT_FALLBACK,
    certify: bool = True,
) -> Run:
    """Run ``controller`` on ``scenario`` from ``q0`` until the goal or ``max_time``.

    ``solver`` is tried first at every step, then each of ``fallback`` in order; the first answer
    whose KKT report is optimal is used; with ``certify=False`` the first finite answer is used
    as it is (to study inexact solvers in closed loop; its KKT residual is recorded).
    Raises :class:`~emdm.errors.NoSolution` when a step has no admissible command
    (``on_infeasible = "error"``, or no solver succeeds).
    """
    ctrl = controller if isinstance(controller, Controller) else get_controller(controller)
    chain = [solver, *[f for f in fallback if f != solver]]
    for name in chain:
        get_solver(name)  # fail before the loop on an unknown solver
    n, N = scenario.n, scenario.max_steps
    motion = scenario.motion

    t = np.arange(N + 1, dtype=float) * motion.dt
    q, p, e, v = (
        np.empty((N + 1, n)),
        np.empty((N + 1, 2)),
        np.empty((N + 1, 2)),
        np.empty((N + 1, 2)),
    )
    m = np.empty(N + 1)
    qd, delta = np.empty((N, n)), np.zeros((N, 2))
    lo, hi = np.empty((N, n)), np.empty((N, n))
    effort_, manip, alpha = np.empty(N), np.empty(N), np.empty(N)
    active = np.zeros((N, n), dtype=np.int8)
    iterations = np.zeros(N, dtype=np.int64)
    solve_time, kkt, excess = np.empty(N), np.empty(N), np.empty(N)
    fallback_used = np.zeros(N, dtype=bool)
    solvers_used: list[str] = []
    statuses: list[str] = []
    attempts: list[str] = []
    policies: list[str] = []

    q[0] = motion.q0
    reached = False
    k = 0
    while True:
        state = state_at(scenario, q[k])
        kin = state.kin
        p[k], m[k], e[k], v[k] = kin.p, kin.m, state.e, state.v
        if state.error_norm < motion.tolerance:
            reached = True
            break
        if k >= N:
            break
        program = program_at(ctrl, scenario, q[k], state, step=k)
        result = solve_chain(
            program.qp, chain, context=f"step {k} (t = {t[k]:g} s): ", certify=certify
        )
        x = result.x
        qd[k] = x[:n]
        if program.qp.n_slack:
            delta[k] = x[n : n + 2]
        lo[k], hi[k] = program.qp.lb[:n], program.qp.ub[:n]
        active[k] = np.where(qd[k] <= lo[k], -1, np.where(qd[k] >= hi[k], 1, 0))
        effort_[k] = 0.5 * float(qd[k] @ qd[k])
        manip[k] = float(kin.Jm @ qd[k])
        alpha[k] = program.alpha
        iterations[k], solve_time[k] = result.iterations, result.time
        kkt[k], excess[k] = result.kkt.residual, result.kkt.bound_excess
        fallback_used[k] = result.fallback
        solvers_used.append(result.solver)
        statuses.append(result.status)
        attempts.append("; ".join(f"{s}: {o}" for s, o in result.attempts))
        policies.append(program.policy or "")
        q[k + 1] = q[k] + qd[k] * motion.dt
        k += 1

    K = k
    return Run(
        scenario=scenario,
        controller=ctrl,
        t=t[: K + 1],
        q=q[: K + 1],
        p=p[: K + 1],
        e=e[: K + 1],
        v=v[: K + 1],
        m=m[: K + 1],
        qd=qd[:K],
        effort=effort_[:K],
        manip_rate=manip[:K],
        alpha=alpha[:K],
        delta=delta[:K],
        lo=lo[:K],
        hi=hi[:K],
        active=active[:K],
        iterations=iterations[:K],
        solve_time=solve_time[:K],
        kkt=kkt[:K],
        bound_excess=excess[:K],
        fallback=fallback_used[:K],
        solver=solvers_used,
        status=statuses,
        attempts=attempts,
        policy=policies,
        reached=reached,
    )


__all__ = ["NoSolution", "Run", "simulate"]
