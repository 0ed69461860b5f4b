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


def rpy_zyx(R: np.ndarray) -> tuple[float, float, float]:
    """Roll, pitch, yaw (rad) with ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (spatialmath's ``zyx``)."""
    r20 = float(R[2, 0])
    if abs(abs(r20) - 1.0) < 1e-12:  # pitch at +-90 degrees: roll taken as 0
        return 0.0, -math.copysign(math.pi / 2, r20), math.atan2(-R[0, 1], R[1, 1])
    return (
        math.atan2(R[2, 1], R[2, 2]),
        -math.asin(max(-1.0, min(1.0, r20))),
        math.atan2(R[1, 0], R[0, 0]),
    )


def servo(T: np.ndarray, goal: np.ndarray) -> tuple[np.ndarray, bool, float]:
    """``(v, arrived, e_s)``: robotics-toolbox-python's ``p_servo`` (method ``rpy``, gain 1,
    threshold 0.17) and the script's slack error ``e_s`` (module notes). ``T^-1 T*`` is taken
    as the rigid transform it is (spatialmath's inverse: ``R^T``, ``-R^T t``)."""
    Rt = T[:3, :3].T
    t = Rt @ (goal[:3, 3] - T[:3, 3])
    rpy = rpy_zyx(Rt @ goal[:3, :3])
    e = np.array((t[0], t[1], t[2], *rpy))
    moved = abs(e[0]) + abs(e[1]) + abs(e[2])
    turned = abs(rpy[0]) + abs(rpy[1]) + abs(rpy[2])
    e_s = moved + turned * math.pi / 180.0
    return GAIN * e, bool(moved + turned < THRESHOLD), e_s


class Singular(Exception):
    """A step without a usable command (no solution, or NaN)."""


def _joint_limit_terms(q: Vector, lo: Vector, hi: Vector) -> Vector:
    """Baur's ``b`` (module notes)."""
    b = np.zeros(q.size)
    low, high = q - lo <= PI, hi - q <= PI
    b[low] = -(((q - lo)[low] - PI) ** 2) / (PS - PI) ** 2
    b[high] = (((hi - q)[high] - PI) ** 2) / (PS - PI) ** 2
    return b


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
    """One step of controller ``name`` (module notes); raises :class:`Singular`."""
    n = q.size
    try:
        if name == Paper.MMC:
            import daqp

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
                raise Singular
            qd = np.asarray(x[:n], dtype=float)
        else:
            pinv = np.linalg.pinv(J)
            qd = pinv @ v
            if name in (Paper.PARK, Paper.BAUR):  # (I - J^+ J) g, without forming I - J^+ J
                gradient = Jm - (_joint_limit_terms(q, lo, hi) if name == Paper.BAUR else 0.0)
                qd = qd + (gradient - pinv @ (J @ gradient)) / Y
    except np.linalg.LinAlgError:
        raise Singular from None
    if not np.all(np.isfinite(qd)):
        raise Singular
    return qd


def run_trial(
    arm: Any,
    lo: Vector,
    hi: Vector,
    q0: Vector,
    goal: Vector,
    cap: int,
    controllers: Sequence[str] = CONTROLLERS,
) -> dict[str, dict[str, Any]]:
    """One trial of every controller (module notes): per controller its outcome (``arrived``,
    ``failed``, ``singular``, ``missed``), mean ``m`` over its steps and final ``m``."""
    n = q0.size
    state: dict[str, dict[str, Any]] = {
        c: {"q": q0.copy(), "arrived": False, "failed": False, "singular": False, "m": 0.0, "it": 0}
        for c in controllers
    }
    it = 0
    while True:
        for c in controllers:
            s = state[c]
            if s["arrived"] or s["failed"]:
                continue
            q = s["q"]
            T, J0, m, Jm = arm.state(q)
            J = (T[:3, :3].T @ J0.reshape(2, 3, n)).reshape(6, n)  # the end-effector frame
            v, s["arrived"], e_s = servo(T, goal)
            try:
                qd = command(c, J, Jm, v, e_s, q, lo, hi)
            except Singular:
                s["failed"] = s["singular"] = True
                qd = np.zeros(n)
            s["m"] += m
            s["it"] += 1
            limit = n - 2
            if (q[:limit] <= lo[:limit]).any() or (q[:limit] >= hi[:limit]).any():
                s["failed"] = True
            s["qd"] = qd
        for c in controllers:  # the simulator integrates every robot's command together
            s = state[c]
            if "qd" in s:
                s["q"] = s["q"] + DT * s.pop("qd")
        it += 1
        ended = [state[c]["arrived"] or state[c]["failed"] for c in (Paper.RRMC, Paper.MMC)]
        if all(ended) or it > cap:
            break
    out = {}
    for c in controllers:
        s = state[c]
        out[c] = {
            "arrived": s["arrived"],
            "failed": s["failed"] and not s["arrived"],
            "singular": s["singular"],
            "missed": not s["arrived"] and not s["failed"],
            "joint_limit": s["failed"] and not s["arrived"] and not s["singular"],
            "mean_m": s["m"] / s["it"] if s["it"] else math.nan,
            "final_m": arm.manipulability(s["q"]),
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
        trials_out = []
        for _ in range(trials):
            q0 = rng.uniform(lo + off, hi - off)
            goal = arm.forward(rng.uniform(lo + off, hi - off))
            trials_out.append(run_trial(arm, lo, hi, q0, goal, protocol.cap))
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


__all__ = ["CONTROLLERS", "PROTOCOLS", "paper_table", "run_paper_protocol", "servo"]
