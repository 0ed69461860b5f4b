"""``emdm mmc --protocol paper``: Haviland & Corke's manipulability benchmark under its authors'
protocol, as their experiment scripts state it (robotics-toolbox-python, ``examples/exp1.py`` for
the Panda and ``examples/expUR.py`` for the UR5, commit 733f395 of that repository).

Per trial, every controller starts from the same joint angles and servos to the same pose:

- start and goal angles uniform inside the limits shrunk by 0.27 times each joint's range
  ``|q_min| + |q_max|`` on each side; the goal pose is the forward kinematics of the goal angles.
  The limits are the model's: the Panda's, and for the UR5 those of the model ``expUR.py`` loads
  (``rp.models.UR5()``, built from ur_description's ``ur5_joint_limited_robot.urdf.xacro``:
  +-pi on every joint), not the +-2 pi of emdm's ``ur5`` preset;
- every step (50 ms, Euler): ``p_servo`` with gain 1: the error ``e`` is the translation and the
  roll-pitch-yaw angles (``zyx``) of ``T^-1 T*`` in the end-effector frame, ``v = e``, and the
  controller has *arrived* once ``sum |e| < 0.17``; the joint velocity comes from the
  end-effector-frame Jacobian ``J_e``:

  - ``RRMC``: ``qd = J_e^+ v``;
  - ``PARK`` (gradient projection, a QP ``min Y/2 |qd|^2 - J_m^T qd`` s.t. ``J_e qd = v``):
    ``qd = J_e^+ v + (I - J_e^+ J_e) J_m / Y``, its exact optimum;
  - ``BAUR``: ``qd = J_e^+ v + (I - J_e^+ J_e)(J_m - b) / Y``, with ``b_i = -((q_i - q_min,i) -
    pi)^2 / (ps - pi)^2`` within ``pi`` of the lower limit and ``+((q_max,i - q_i) - pi)^2 /
    (ps - pi)^2`` within ``pi`` of the upper one;
  - ``MMC``: ``min Y/2 |qd|^2 + 1/(2 e_s) |delta|^2 - J_m^T qd`` s.t. ``J_e qd + delta = v`` and
    the velocity damper ``-qd_i <= (q_i - q_min,i - ps)/(pi - ps)``, ``qd_i <= (q_max,i - q_i -
    ps)/(pi - ps)`` for a joint within ``pi`` of a limit; no velocity limits, no slack bounds;
    ``e_s`` is the script's ``sum |[t, rpy * pi/180]|`` (its rotation in radians scaled once more
    by ``pi/180``, kept as written), solved by daqp;

  with ``Y = 0.01``, ``ps = 0.05``, ``pi = 0.9`` rad and ``J_m`` the manipulability's gradient;
- a controller *fails* at a step where one of the first ``n - 2`` joints is at or beyond a limit,
  or where its step has no solution or a NaN (*singular*); one that has arrived or failed stands
  still;
- a trial ends when both RRMC and MMC have arrived or failed, or after 100 steps (the scripts'
  ``itmax``); a controller still moving then has *missed*;
- the mean manipulability of a controller (its mean ``m`` over its steps) and its final
  manipulability are averaged over the trials in which every controller arrived (RRMC and MMC on
  the UR5, the two its script runs); its failure rate counts every trial it did not arrive in.

The kinematics are emdm's (:class:`~emdm.core.serial.SerialArm` of the presets, equal to
robotics-toolbox-python's models to 1e-15); nothing else of emdm's loop takes part.
"""

from __future__ import annotations

import math
import time
import zlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..core.loading import load_scenario
from .stats import mean_interval, wilson

Vector = NDArray[np.float64]
Y, PS, PI, GAIN, THRESHOLD, DT = 0.01, 0.05, 0.9, 1.0, 0.17, 0.05


class Paper(StrEnum):
    """The controllers of the authors' script, named as in its table (Baur's is theirs only)."""

    RRMC = "RRMC"
    PARK = "PARK"
    BAUR = "BAUR"
    MMC = "MMC"


CONTROLLERS = tuple(Paper)


@dataclass(frozen=True)
class Protocol:
    """The numbers of the authors' scripts for one arm: the shrink of the limits for starts and
    goals, the step cap, and the joint limits when the script's model has other ones than the
    preset (rad, symmetric; ``None``: the preset's)."""

    shrink: float
    cap: int
    limit: float | None = None
    subset: tuple[str, ...] = tuple(Paper)
    """The controllers whose arrival puts a trial in the averaged subset: all four in exp1.py
    (``rarr == 4``), RRMC and MMC in expUR.py (``rarr == 2``: the only two it runs; on the
    non-redundant UR5 PARK and BAUR are RRMC, as the published table's equal columns show)."""


PROTOCOLS = {
    "panda": Protocol(0.27, 100),
    "ur5": Protocol(0.27, 100, math.pi, (Paper.RRMC, Paper.MMC)),
}


def rpy_zyx(R: np.ndarray) -> np.ndarray:
    """Roll, pitch, yaw (rad) of each rotation of the stack ``R`` (K x 3 x 3) with
    ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (spatialmath's ``zyx``): K x 3."""
    r20 = R[:, 2, 0]
    gimbal = np.abs(np.abs(r20) - 1.0) < 1e-12  # pitch at +-90 degrees: roll taken as 0
    out = np.empty((R.shape[0], 3))
    out[:, 0] = np.where(gimbal, 0.0, np.arctan2(R[:, 2, 1], R[:, 2, 2]))
    out[:, 1] = np.where(gimbal, -np.copysign(np.pi / 2, r20), -np.arcsin(np.clip(r20, -1, 1)))
    out[:, 2] = np.where(
        gimbal, np.arctan2(-R[:, 0, 1], R[:, 1, 1]), np.arctan2(R[:, 1, 0], R[:, 0, 0])
    )
    return out


def servos(T: np.ndarray, goals: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`servo` of each pose of the stack ``T`` (K x 4 x 4) towards its goal (K x 4 x 4):
    ``(v, arrived, e_s)`` as K x 6, K and K arrays."""
    Rt = np.swapaxes(T[:, :3, :3], 1, 2)
    t = (Rt @ (goals[:, :3, 3] - T[:, :3, 3])[:, :, None])[:, :, 0]
    rpy = rpy_zyx(Rt @ goals[:, :3, :3])
    moved = np.abs(t).sum(axis=1)
    turned = np.abs(rpy).sum(axis=1)
    e = np.concatenate((t, rpy), axis=1)
    return GAIN * e, moved + turned < THRESHOLD, moved + turned * math.pi / 180.0


def servo(T: np.ndarray, goal: np.ndarray) -> tuple[np.ndarray, bool, float]:
    """``(v, arrived, e_s)``: robotics-toolbox-python's ``p_servo`` (method ``rpy``, gain 1,
    threshold 0.17) and the script's slack error ``e_s`` (module notes). ``T^-1 T*`` is taken
    as the rigid transform it is (spatialmath's inverse: ``R^T``, ``-R^T t``)."""
    v, arrived, e_s = servos(T[None], goal[None])
    return v[0], bool(arrived[0]), float(e_s[0])


class Singular(Exception):
    """A step without a usable command (no solution, or NaN)."""


def _joint_limit_terms(q: np.ndarray, lo: Vector, hi: Vector) -> np.ndarray:
    """Baur's ``b`` (module notes), for a configuration or a stack of them."""
    b = np.zeros(q.shape)
    low, high = q - lo <= PI, hi - q <= PI
    b[low] = -(((q - lo)[low] - PI) ** 2) / (PS - PI) ** 2
    b[high] = (((hi - q)[high] - PI) ** 2) / (PS - PI) ** 2
    return b


def _mmc_step(
    J: Vector, Jm: Vector, v: Vector, e_s: float, q: Vector, lo: Vector, hi: Vector
) -> Vector | None:
    """MMC's command at one configuration (module notes), or None where daqp finds none."""
    import daqp

    n = q.size
    # n + 6 simple bounds (qd's dampers, delta free), then the 6 rows J qd + delta = v
    upper, lower = np.full(n + 12, 1e30), np.full(n + 12, -1e30)
    near_low, near_high = q - lo <= PI, hi - q <= PI
    lower[:n][near_low] = -((q - lo - PS) / (PI - PS))[near_low]
    upper[:n][near_high] = ((hi - q - PS) / (PI - PS))[near_high]
    upper[n + 6 :] = lower[n + 6 :] = v
    sense = np.zeros(n + 12, dtype=np.int32)
    sense[n + 6 :] = 5
    weights = np.full(n + 6, Y)
    weights[n:] = 1.0 / max(e_s, 1e-300)
    f = np.zeros(n + 6)
    f[:n] = -Jm
    A = np.zeros((6, n + 6))
    A[:, :n] = J
    A[:, n:] = np.eye(6)
    x, _, flag, _ = daqp.solve(np.diag(weights), f, A, upper, lower, sense)
    if flag < 1:
        return None
    qd: Vector = np.array(x[:n], dtype=float)
    return qd


def _pinv(J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """numpy's pseudoinverse of each Jacobian of the stack, and where it failed (an SVD that
    does not converge raises for the whole stack: then each is taken alone)."""
    try:
        return np.linalg.pinv(J), np.zeros(J.shape[0], dtype=bool)
    except np.linalg.LinAlgError:
        out, failed = np.zeros(np.swapaxes(J, 1, 2).shape), np.zeros(J.shape[0], dtype=bool)
        for j in range(J.shape[0]):
            try:
                out[j] = np.linalg.pinv(J[j])
            except np.linalg.LinAlgError:
                failed[j] = True
        return out, failed


def commands(
    name: str,
    J: np.ndarray,
    Jm: np.ndarray,
    v: np.ndarray,
    e_s: np.ndarray,
    q: np.ndarray,
    lo: Vector,
    hi: Vector,
) -> tuple[np.ndarray, np.ndarray]:
    """One step of controller ``name`` (module notes) at each of K configurations (stacks: J
    K x 6 x n, Jm, q K x n, v K x 6, e_s K): the commands (K x n, zero where none) and where
    the step is singular (no solution, or NaN)."""
    K, n = q.shape
    qd = np.zeros((K, n))
    singular = np.zeros(K, dtype=bool)
    if name == Paper.MMC:
        for j in range(K):
            x = _mmc_step(J[j], Jm[j], v[j], float(e_s[j]), q[j], lo, hi)
            if x is None:
                singular[j] = True
            else:
                qd[j] = x
    else:
        pinv, singular = _pinv(J)
        qd = (pinv @ v[:, :, None])[:, :, 0]
        if name in (Paper.PARK, Paper.BAUR):  # (I - J^+ J) g, without forming I - J^+ J
            g = Jm - (_joint_limit_terms(q, lo, hi) if name == Paper.BAUR else 0.0)
            qd = qd + (g - (pinv @ (J @ g[:, :, None]))[:, :, 0]) / Y
    singular |= ~np.all(np.isfinite(qd), axis=1)
    qd[singular] = 0.0
    return qd, singular


def command(
    name: str,
    J: Vector,
    Jm: Vector,
    v: Vector,
    e_s: float,
    q: Vector,
    lo: Vector,
    hi: Vector,
) -> Vector:
    """One step of controller ``name`` at one configuration (:func:`commands` of one);
    raises :class:`Singular`."""
    qd, singular = commands(name, J[None], Jm[None], v[None], np.array([e_s]), q[None], lo, hi)
    if singular[0]:
        raise Singular
    one: Vector = qd[0]
    return one


def run_trials(
    arm: Any,
    lo: Vector,
    hi: Vector,
    q0s: np.ndarray,
    goals: np.ndarray,
    cap: int,
    controllers: Sequence[str] = CONTROLLERS,
) -> list[dict[str, dict[str, Any]]]:
    """Every trial (starts ``q0s`` R x n, goal poses ``goals`` R x 4 x 4) of every controller,
    stepped together (module notes): per trial and controller its outcome (``arrived``,
    ``failed``, ``singular``, ``missed``, ``joint_limit``), mean ``m`` over its steps and final
    ``m``. A trial's steps are those of the authors' loop, one trial at a time (the tests'
    oracle); taken together, each controller's step is one stacked computation."""
    R, n = q0s.shape
    limit = n - 2
    state = {
        c: {
            "q": q0s.astype(float),
            "arrived": np.zeros(R, dtype=bool),
            "failed": np.zeros(R, dtype=bool),
            "singular": np.zeros(R, dtype=bool),
            "m": np.zeros(R),
            "it": np.zeros(R, dtype=int),
        }
        for c in controllers
    }
    running = np.ones(R, dtype=bool)
    it = 0
    while running.any():
        steps: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        for c in controllers:
            s = state[c]
            idx = np.flatnonzero(running & ~s["arrived"] & ~s["failed"])
            if not idx.size:
                continue
            q = s["q"][idx]
            T, J0, m, Jm = (
                np.empty((idx.size, 4, 4)),
                np.empty((idx.size, 6, n)),
                np.empty(idx.size),
                np.empty((idx.size, n)),
            )
            for j in range(idx.size):
                T[j], J0[j], m[j], Jm[j] = arm.state(q[j])
            Rt = np.swapaxes(T[:, :3, :3], 1, 2)
            J = (Rt[:, None] @ J0.reshape(idx.size, 2, 3, n)).reshape(idx.size, 6, n)
            v, s["arrived"][idx], e_s = servos(T, goals[idx])
            qd, singular = commands(c, J, Jm, v, e_s, q, lo, hi)
            s["failed"][idx] |= singular
            s["singular"][idx] |= singular
            s["m"][idx] += m
            s["it"][idx] += 1
            at_limit = np.any(q[:, :limit] <= lo[:limit], axis=1) | np.any(
                q[:, :limit] >= hi[:limit], axis=1
            )
            s["failed"][idx] |= at_limit
            steps[c] = (idx, qd)
        for c, (idx, qd) in steps.items():  # the simulator integrates every robot together
            state[c]["q"][idx] = state[c]["q"][idx] + DT * qd
        it += 1
        ended = np.ones(R, dtype=bool)
        for c in (Paper.RRMC, Paper.MMC):
            ended &= state[c]["arrived"] | state[c]["failed"]
        running &= ~ended
        if it > cap:
            break
    out: list[dict[str, dict[str, Any]]] = [{} for _ in range(R)]
    for c in controllers:
        s = state[c]
        for r in range(R):
            arrived, failed = bool(s["arrived"][r]), bool(s["failed"][r])
            out[r][c] = {
                "arrived": arrived,
                "failed": failed and not arrived,
                "singular": bool(s["singular"][r]),
                "missed": not arrived and not failed,
                "joint_limit": failed and not arrived and not bool(s["singular"][r]),
                "mean_m": s["m"][r] / s["it"][r] if s["it"][r] else math.nan,
                "final_m": arm.manipulability(s["q"][r]),
            }
    return out


def run_paper_protocol(
    *,
    arms: Sequence[str] = ("panda", "ur5"),
    trials: int = 1000,
    seed: int = 0,
    progress: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """The benchmark under the authors' protocol, as a JSON-friendly dict (``results[arm][c]``
    with ``mean_manipulability``, ``mean_final_manipulability``, ``failure_rate`` and counts)."""
    from .mmc import PUBLISHED

    say = progress or (lambda _m: None)
    results: dict[str, Any] = {}
    for name in arms:
        if name not in PROTOCOLS:
            raise ValueError(f"the paper protocol is stated for panda and ur5, not {name!r}")
        protocol = PROTOCOLS[name]
        sc = load_scenario(name)
        arm = sc.serial_arm
        lo, hi = np.asarray(sc.arm.q_min, float), np.asarray(sc.arm.q_max, float)
        if protocol.limit is not None:
            lo, hi = np.full(sc.n, -protocol.limit), np.full(sc.n, protocol.limit)
        off = protocol.shrink * (np.abs(lo) + np.abs(hi))
        # seeded by the arm's name, so that one arm's tasks do not depend on the others run
        rng = np.random.default_rng(np.random.SeedSequence([seed, zlib.crc32(name.encode())]))
        start = time.perf_counter()
        q0s, goals = np.empty((trials, sc.n)), np.empty((trials, 4, 4))
        for i in range(trials):  # drawn as the one-at-a-time loop drew them: start, then goal
            q0s[i] = rng.uniform(lo + off, hi - off)
            goals[i] = arm.forward(rng.uniform(lo + off, hi - off))
        trials_out = run_trials(arm, lo, hi, q0s, goals, protocol.cap)
        seconds = time.perf_counter() - start
        every = [all(t[c]["arrived"] for c in protocol.subset) for t in trials_out]
        kept_trials = [t for t, ok in zip(trials_out, every, strict=True) if ok]
        results[name] = {}
        for c in CONTROLLERS:
            rows = [t[c] for t in trials_out]
            kept = [t[c] for t in kept_trials]
            keys = ("arrived", "failed", "joint_limit", "singular", "missed")
            count = {k: int(sum(r[k] for r in rows)) for k in keys}
            # paired: the same tasks for every controller, so differences to MMC per trial
            diff = [t[c]["mean_m"] - t[Paper.MMC]["mean_m"] for t in kept_trials]
            results[name][c] = {
                "trials": trials,
                "mean_manipulability": float(np.mean([r["mean_m"] for r in kept]))
                if kept
                else None,
                "mean_manipulability_ci": mean_interval([r["mean_m"] for r in kept]),
                "mean_final_manipulability": float(np.mean([r["final_m"] for r in kept]))
                if kept
                else None,
                "mean_final_manipulability_ci": mean_interval([r["final_m"] for r in kept]),
                "mean_manipulability_minus_mmc": float(np.mean(diff)) if diff else None,
                "mean_manipulability_minus_mmc_ci": mean_interval(diff),
                "failure_rate": 100.0 * (trials - count["arrived"]) / trials,
                "failure_rate_ci": tuple(
                    100.0 * b for b in wilson(trials - count["arrived"], trials)
                ),
                **count,
                "all_arrived_trials": int(sum(every)),
                "subset": list(protocol.subset),
                "published": PUBLISHED.get(name, {}).get(c),
            }
        say(f"{name}: {trials} trials in {seconds:.1f} s")
    return {"protocol": "paper", "trials": trials, "seed": seed, "results": results}


def paper_table(data: dict[str, Any]) -> str:
    """The benchmark under the authors' protocol beside the published table, as Markdown."""
    lines = [
        f"Manipulability benchmark under Haviland & Corke's protocol (their exp1.py and expUR.py): "
        f"{data['trials']} random tasks per arm (seed {data['seed']}), published values in "
        "brackets (the Baur column of the published table is not in emdm's copy). Mean and final "
        "m over the trials in which every controller arrived (on the UR5 RRMC and MMC, the "
        "two its script runs; the same tasks for every controller), with Student's 95 % "
        "interval; the paired difference to MMC over those "
        "trials; failed: did not arrive (a joint at a limit, a singular step, or the step cap), "
        "with Wilson's 95 % interval.",
        "",
        "| arm | controller | mean m | 95 % CI | mean final m | m - m(MMC), paired | 95 % CI "
        "| failed % | 95 % CI | joint limit | singular | missed (cap) | trials all arrived |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]

    def show(value: float | None, published: float | None, fmt: str) -> str:
        text = "-" if value is None else format(value, fmt)
        return text + (f" ({format(published, fmt)})" if published is not None else "")

    def interval(bounds: Sequence[float], fmt: str) -> str:
        lo, hi = bounds
        return "-" if math.isnan(lo) else f"{format(lo, fmt)} to {format(hi, fmt)}"

    for arm, rows in data["results"].items():
        for c, r in rows.items():
            pub = r["published"] or (None, None, None)
            paired = (
                "0 (itself)"
                if c == Paper.MMC
                else show(r["mean_manipulability_minus_mmc"], None, "+.4f")
            )
            lines.append(
                f"| {arm} | {c} | {show(r['mean_manipulability'], pub[0], '.4f')} | "
                f"{interval(r['mean_manipulability_ci'], '.4f')} | "
                f"{show(r['mean_final_manipulability'], pub[1], '.4f')} | {paired} | "
                f"{'-' if c == Paper.MMC else interval(r['mean_manipulability_minus_mmc_ci'], '+.4f')} | "
                f"{show(r['failure_rate'], pub[2], '.1f')} | "
                f"{interval(r['failure_rate_ci'], '.1f')} | {r['joint_limit']} | "
                f"{r['singular']} | {r['missed']} | {r['all_arrived_trials']} |"
            )
    return "\n".join(lines)


__all__ = [
    "CONTROLLERS",
    "PROTOCOLS",
    "command",
    "commands",
    "paper_table",
    "run_paper_protocol",
    "run_trials",
    "servo",
    "servos",
]
