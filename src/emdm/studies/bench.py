"""``emdm bench``: what a control step costs through ``emdm.simulate`` (the compiled loop with the
full record), through the per-step Python API and through the standard stack a user would write
today, measured in one process so every figure is also a ratio.

Standard stack (the baseline): numpy kinematics written from the textbook formulas (J by columns,
``m = sqrt(det(J J^T))``, ``Jm_j = m trace((J J^T)^-1 J H_j^T)``), the QP arrays built with numpy,
and qpsolvers with daqp or quadprog, on the same programs (the same task scale) as emdm.

Every time is the median over repeats, after a warm-up that is not counted.
"""

from __future__ import annotations

import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from functools import partial
from importlib import metadata
from typing import Any

import numpy as np

from .. import __version__
from ..core.controllers import CONTROLLERS, Name, get_controller, program_at, state_at
from ..core.loading import load_scenario
from ..sim.batch import simulate_batch
from ..sim.loop import simulate
from ..solvers import DEFAULT_FALLBACK, DEFAULT_SOLVER, solve_chain


def _median_time(function: Callable[[], Any], repeats: int) -> float:
    function()  # warm-up
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


# ---------------------------------------------------------------- the standard-stack baseline
def textbook_kinematics(lengths: np.ndarray, q: np.ndarray) -> tuple[Any, Any, float, Any]:
    """p, J, m, Jm as a user would write them from the textbook (numpy, no tricks)."""
    n = q.size
    th = np.cumsum(q)
    p = np.array([np.sum(lengths * np.cos(th)), np.sum(lengths * np.sin(th))])
    J = np.zeros((2, n))
    for j in range(n):
        J[0, j] = -np.sum(lengths[j:] * np.sin(th[j:]))
        J[1, j] = np.sum(lengths[j:] * np.cos(th[j:]))
    H = np.zeros((n, 2, n))
    for j in range(n):
        for k in range(n):
            i0 = max(j, k)
            H[j, 0, k] = -np.sum(lengths[i0:] * np.cos(th[i0:]))
            H[j, 1, k] = -np.sum(lengths[i0:] * np.sin(th[i0:]))
    JJt = J @ J.T
    m = float(np.sqrt(np.linalg.det(JJt)))
    inv = np.linalg.inv(JJt)
    Jm = np.array([m * np.trace(inv @ J @ H[j].T) for j in range(n)])
    return p, J, m, Jm


def _baseline_step(sc: Any, q: np.ndarray, alpha: float, solver: str) -> dict[str, float]:
    from qpsolvers import solve_qp

    lengths = np.asarray(sc.arm.lengths)
    t0 = time.perf_counter()
    p, J, _, Jm = textbook_kinematics(lengths, q)
    t1 = time.perf_counter()
    n = q.size
    e = sc.motion.goal - p
    v = alpha * sc.motion.kp * e
    P = sc.weights.effort * np.eye(n)
    c = -sc.weights.manipulability * Jm
    lo = np.array(sc.arm.qd_min, dtype=float)
    hi = np.array(sc.arm.qd_max, dtype=float)
    for j in range(n):
        i, s, K = sc.damper.influence[j], sc.damper.stop[j], sc.damper.gain[j]
        d_up, d_dn = sc.arm.q_max[j] - q[j], q[j] - sc.arm.q_min[j]
        if d_up < i:
            hi[j] = min(hi[j], (d_up - s) / (K * (i - s)))
        if d_dn < i:
            lo[j] = max(lo[j], -(d_dn - s) / (K * (i - s)))
    t2 = time.perf_counter()
    qd = solve_qp(P, c, None, None, J, v, lo, hi, solver=solver)
    t3 = time.perf_counter()
    failed = qd is None  # what this stack returns on programs it declines (a user's crash)
    _ = q + (np.zeros(n) if failed else qd) * sc.motion.dt
    t4 = time.perf_counter()
    return {
        "kinematics": t1 - t0,
        "build": t2 - t1,
        "solve": t3 - t2,
        "integrate": t4 - t3,
        "failed": float(failed),
    }


def _api_step(sc: Any, ctrl: Any, q: np.ndarray) -> dict[str, float]:
    """One step through the per-step Python API (what the solver lab and the Pareto study use)."""
    t0 = time.perf_counter()
    state = state_at(sc, q)
    t1 = time.perf_counter()
    program = program_at(ctrl, sc, q, state)
    t2 = time.perf_counter()
    result = solve_chain(program.qp, [DEFAULT_SOLVER, *DEFAULT_FALLBACK])
    t3 = time.perf_counter()
    _ = q + result.x[: q.size] * sc.motion.dt
    t4 = time.perf_counter()
    return {"kinematics": t1 - t0, "build": t2 - t1, "solve": t3 - t2, "integrate": t4 - t3}


def first_use(*, cold: bool) -> dict[str, float]:
    """Seconds of a first use in a new process: ``cache_load_s``, the first ``emdm.simulate``
    with the compiled kernels loaded from the on-disk cache; ``compile_s`` (``cold``), the whole
    command ``emdm run task1`` (interpreter start and import included) on a fresh machine's empty
    kernel cache, as a new user meets it (its second process compiling a share meanwhile)."""
    script = (
        "import time, emdm; s = emdm.load_scenario('task1'); t = time.perf_counter(); "
        "emdm.simulate(s, 'C-EMDM'); print(time.perf_counter() - t)"
    )
    out: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as empty:
        if cold:
            env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
            env["XDG_CACHE_HOME"] = empty  # an empty kernel cache where a new user's would be
            command = [sys.executable, "-m", "emdm", "run", "task1", "--out", f"{empty}/run"]
            start = time.perf_counter()
            subprocess.run(command, env=env, capture_output=True, text=True, check=True)
            out["compile_s"] = time.perf_counter() - start
        done = subprocess.run(
            [sys.executable, "-c", script],
            env=dict(os.environ),
            capture_output=True,
            text=True,
            check=True,
        )
        out["cache_load_s"] = float(done.stdout.strip().splitlines()[-1])
    return out


def _split(
    step: Callable[[np.ndarray, float], dict[str, float]],
    states: np.ndarray,
    alphas: np.ndarray,
    repeats: int,
) -> dict[str, float]:
    """Median over repeats of the per-step mean of each part (warm-up excluded)."""
    step(states[0], alphas[0])
    parts: dict[str, list[float]] = {}
    failed = 0.0
    for _ in range(repeats):
        sums: dict[str, float] = {}
        failed = 0.0
        for q, a in zip(states, alphas, strict=True):
            for key, value in step(q, a).items():
                if key == "failed":
                    failed += value
                else:
                    sums[key] = sums.get(key, 0.0) + value
        for key, value in sums.items():
            parts.setdefault(key, []).append(value / len(states))
    out = {key: statistics.median(values) for key, values in parts.items()}
    out["total"] = sum(out.values())
    out["failed_steps"] = failed
    return out


def _rtb_step(model: Any, sc: Any, ctrl: Any, q: np.ndarray, alpha: float) -> dict[str, float]:
    """One C-EMDM step on a spatial preset as a robotics-toolbox-python user writes it: ``fkine``,
    ``p_servo`` (angle-axis error), ``jacob0``, ``jacobm`` and ``joint_velocity_damper`` for the
    kinematics, then qpsolvers with daqp (the same program and task scale as emdm)."""
    import roboticstoolbox as rtb
    from qpsolvers import solve_qp
    from spatialmath import SE3
    from spatialmath.base import trexp

    t0 = time.perf_counter()
    goal = np.asarray(sc.motion.goal)
    Tep = SE3.Rt(trexp(goal[3:]), goal[:3])
    v, _ = rtb.p_servo(model.fkine(q), Tep, gain=float(sc.motion.kp[0]), method="angle-axis")
    J = model.jacob0(q)
    Jm = model.jacobm(q).ravel()
    d = sc.damper
    Ain, bin_ = model.joint_velocity_damper(
        q=q, ps=float(d.stop[0]), pi=float(d.influence[0]), n=sc.n, gain=float(d.gain[0])
    )
    t1 = time.perf_counter()
    w = sc.weights
    qd = solve_qp(
        w.effort * np.eye(sc.n),
        -w.manipulability * Jm,
        Ain,
        bin_,
        J,
        alpha * np.asarray(v),
        np.asarray(sc.arm.qd_min),
        np.asarray(sc.arm.qd_max),
        solver="daqp",
    )
    t2 = time.perf_counter()
    return {"kinematics": t1 - t0, "solve": t2 - t1, "failed": float(qd is None)}


RTB_END = "panda_link8"
"""The flange: where emdm's Panda preset ends, so that both stacks track the same point."""


def _rtb_best_step(
    model: Any,
    ets: Any,
    Tep: np.ndarray,
    sc: Any,
    q: np.ndarray,
    alpha: float,
    command: np.ndarray | None = None,
) -> dict[str, float]:
    """One C-EMDM step on the Panda as robotics-toolbox-python's own examples would have it, at
    its fastest: the compiled URDF model (``rtb.models.Panda()``), its C kinematics through the
    chain to the flange (``ets.eval``, ``ets.jacob0``), ``jacobm`` given that Jacobian,
    ``p_servo`` (angle-axis error), the joint-velocity damper folded into the velocity bounds
    (``joint_velocity_damper``'s rows, without rebuilding its arrays), and daqp called directly
    (no qpsolvers conversion): the same program and task scale as emdm (``command`` receives the
    solution)."""
    import daqp
    import roboticstoolbox as rtb

    t0 = time.perf_counter()
    Te = ets.eval(q)
    v, _ = rtb.p_servo(Te, Tep, gain=float(sc.motion.kp[0]), method="angle-axis")
    J = ets.jacob0(q)
    Jm = model.jacobm(q, J=J, end=RTB_END).ravel()
    a, d, w = sc.arm, sc.damper, sc.weights
    upper = np.minimum(a.qd_max, d.gain * (a.q_max - q - d.stop) / (d.influence - d.stop))
    lower = np.maximum(a.qd_min, -d.gain * (q - a.q_min - d.stop) / (d.influence - d.stop))
    upper = np.where(a.q_max - q <= d.influence, upper, a.qd_max)
    lower = np.where(q - a.q_min <= d.influence, lower, a.qd_min)
    task = alpha * np.asarray(v, dtype=float)
    t1 = time.perf_counter()
    x, _, flag, _ = daqp.solve(
        w.effort * np.eye(sc.n),
        -w.manipulability * Jm,
        J,
        np.concatenate((upper, task)),
        np.concatenate((lower, task)),
        np.concatenate((np.zeros(sc.n), np.full(6, 5))).astype(np.int32),
    )
    t2 = time.perf_counter()
    if command is not None:
        command[:] = x
    return {"kinematics": t1 - t0, "solve": t2 - t1, "failed": float(flag < 1)}


def _versions(*names: str) -> str:
    return ", ".join(f"{n} {_version(n) or 'missing'}" for n in names)


def run_spatial_bench(*, repeats: int = 3, batch_runs: int = 2000) -> dict[str, Any]:
    """Panda, pose task, C-EMDM: ``emdm.simulate`` per step against robotics-toolbox-python +
    qpsolvers (when installed), and batch throughput on random tasks of ``emdm mmc``."""
    from ..studies.mmc import draw_tasks

    sc = load_scenario("panda")
    ctrl = get_controller(Name.C_EMDM)
    run = simulate(sc, ctrl)
    whole = _median_time(lambda: simulate(sc, ctrl), max(repeats, 5) * 4)
    out: dict[str, Any] = {
        "scenario": "panda C-EMDM, pose task",
        "steps": run.steps,
        "simulate_us_per_step": whole / run.steps * 1e6,
    }
    try:
        import roboticstoolbox as rtb
        from spatialmath import SE3
    except ImportError:
        out["rtb_stack"] = None
    else:
        from spatialmath.base import trexp

        best = rtb.models.Panda()
        ets = best.ets(end=RTB_END)
        goal = np.asarray(sc.motion.goal)
        Tep = np.eye(4)
        Tep[:3, :3], Tep[:3, 3] = trexp(goal[3:]), goal[:3]
        split = _split(
            lambda q, a: _rtb_best_step(best, ets, Tep, sc, q, a), run.q[:-1], run.alpha, repeats
        )
        out["rtb_stack"] = {k: v * 1e6 if k != "failed_steps" else v for k, v in split.items()}
        out["ratio"] = split["total"] / (whole / run.steps)
        out["rtb_stack"]["path"] = (
            "rtb.models.Panda() (compiled URDF model): ets.eval, ets.jacob0, jacobm(J=...), "
            "p_servo, damper folded into the bounds, daqp.solve directly"
        )
        out["rtb_stack"]["versions"] = _versions("roboticstoolbox-python", "daqp", "numpy")
        x = np.empty(sc.n)  # the same program: its commands are emdm's
        gap = 0.0
        for k in range(run.steps):
            _rtb_best_step(best, ets, Tep, sc, run.q[k], float(run.alpha[k]), x)
            gap = max(gap, float(np.abs(x - run.qd[k]).max()))
        out["rtb_stack"]["max_command_difference"] = gap
        model = rtb.models.DH.Panda()  # the pure-Python DH model, as an extra row
        model.tool = SE3()  # emdm's preset stops at the flange
        slow = _split(lambda q, a: _rtb_step(model, sc, ctrl, q, a), run.q[:-1], run.alpha, repeats)
        out["rtb_dh_stack"] = {k: v * 1e6 if k != "failed_steps" else v for k, v in slow.items()}
        out["rtb_dh_stack"]["path"] = (
            "rtb.models.DH.Panda() (pure-Python DH): fkine, jacob0, jacobm, "
            "joint_velocity_damper, qpsolvers.solve_qp(solver='daqp')"
        )
        out["rtb_dh_stack"]["versions"] = _versions(
            "roboticstoolbox-python", "qpsolvers", "daqp", "numpy"
        )
        out["ratio_dh"] = slow["total"] / (whole / run.steps)
    q0s, goals = draw_tasks("panda", batch_runs, 0)
    simulate_batch(sc, ctrl, goals=goals[:4], q0s=q0s[:4])
    t0 = time.perf_counter()
    result = simulate_batch(sc, ctrl, goals=goals, q0s=q0s)
    seconds = time.perf_counter() - t0
    out["batch"] = {
        "runs": batch_runs,
        "steps": int(result.steps.sum()),
        "seconds": seconds,
        "steps_per_second": int(result.steps.sum()) / seconds,
    }
    return out


STACK = "standard stack, daqp"
SIMULATE = "emdm.simulate (full record, certified)"
TARGETS = (
    "emdm.simulate task1 C-EMDM <= 5 us/step",
    "emdm.simulate vs the standard stack >= 20x",
    "batch >= 1.5e6 steps/s",
)


ROW_PLANES = 20
"""Planes of the inequality-row benchmark: each adds one row to every step's program."""


def _rows_bench(sc: Any, ctrl: Any, run: Any, whole: float, repeats: int) -> dict[str, Any]:
    """The cost of ``ROW_PLANES`` inequality rows on task1 C-EMDM: planes around the arm, 5 m
    from the base, within their influence distance (10 m) at every step, so that every program
    carries all the rows; their gain (100 1/s) keeps them loose, so the commands stay those of
    the run without rows (the difference is reported)."""
    angles = np.linspace(0.0, 2.0 * np.pi, ROW_PLANES, endpoint=False)
    planes = {
        "planes.normals": [[float(np.cos(a)), float(np.sin(a))] for a in angles],
        "planes.offsets": [-5.0] * ROW_PLANES,
        "planes.influence": 10.0,
        "planes.stop": 0.0,
        "planes.gain": 100.0,
    }
    scr = sc.with_overrides(planes)
    with_rows = simulate(scr, ctrl)
    seconds = _median_time(lambda: simulate(scr, ctrl), max(repeats, 5) * 4)
    same = with_rows.steps == run.steps
    return {
        "planes": ROW_PLANES,
        "steps": with_rows.steps,
        "rows_per_step": float(with_rows.rows.mean()),
        "active_rows": int(with_rows.rows_active.sum()),
        "us_per_step": seconds / with_rows.steps * 1e6,
        "extra_us_per_step": float(seconds / with_rows.steps * 1e6 - whole / run.steps * 1e6),
        "max_command_difference": float(np.abs(with_rows.qd - run.qd).max()) if same else math.inf,
    }


def run_bench(
    *,
    repeats: int = 5,
    batch_runs: int = 4000,
    quick: bool = False,
    progress: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """Every measurement of the benchmark, as a JSON-friendly dict (all in this process, except
    the first-use times, which need a new process each)."""
    say = progress or (lambda _m: None)
    if quick:
        repeats, batch_runs = 1, 200
    start = time.perf_counter()
    first = first_use(cold=not quick)
    say("first use measured: " + ", ".join(f"{k} {v:.1f} s" for k, v in first.items()))

    sc = load_scenario("task1")
    ctrl = get_controller(Name.C_EMDM)
    run = simulate(sc, ctrl)
    states, alphas = run.q[:-1], run.alpha
    steps: dict[str, dict[str, float]] = {
        "per-step API (state_at, program_at, solve_chain)": _split(
            lambda q, a: _api_step(sc, ctrl, q), states, alphas, repeats
        ),
        STACK: _split(lambda q, a: _baseline_step(sc, q, a, "daqp"), states, alphas, repeats),
        "standard stack, quadprog": _split(
            lambda q, a: _baseline_step(sc, q, a, "quadprog"), states, alphas, repeats
        ),
    }
    whole = _median_time(lambda: simulate(sc, ctrl), max(repeats, 5) * 4)
    steps[SIMULATE] = {"total": whole / run.steps}
    say("per-step split done")

    rows = _rows_bench(sc, ctrl, run, whole, repeats)
    say("inequality rows done")

    runs: dict[str, dict[str, Any]] = {}
    for task in ("task1", "task2"):
        scn = load_scenario(task)
        for name in CONTROLLERS:
            seconds = _median_time(partial(simulate, scn, name), repeats * 4)
            k = simulate(scn, name).steps
            runs[f"{task} {name}"] = {
                "steps": k,
                "simulate_s": seconds,
                "us_per_step": seconds / max(k, 1) * 1e6,
            }
    say("whole runs done")

    rng = np.random.default_rng(0)
    arm = sc.planar_arm
    targets = rng.uniform(sc.arm.q_min + 0.8, sc.arm.q_max - 0.8, (batch_runs, sc.n))
    goals = np.array([arm.forward(t) for t in targets])
    simulate_batch(sc, ctrl, goals=goals[:10])  # warm-up
    times, total_steps = [], 0
    for _ in range(max(1, repeats // 2)):
        t0 = time.perf_counter()
        out = simulate_batch(sc, ctrl, goals=goals)
        times.append(time.perf_counter() - t0)
        total_steps = int(out.steps.sum())
    batch_t = statistics.median(times)
    say("batch done")

    spatial = run_spatial_bench(repeats=repeats, batch_runs=100 if quick else 2000)
    say("spatial done")

    base = steps[STACK]["total"]
    per_step = steps[SIMULATE]["total"]
    return {
        "emdm_version": __version__,
        "machine": {
            "platform": platform.platform(),
            "python": sys.version.split()[0],
            "cpus": os.cpu_count(),
            "packages": {
                p: _version(p) for p in ("numpy", "scipy", "qpsolvers", "daqp", "quadprog", "numba")
            },
        },
        "repeats": repeats,
        "first_use": first,
        "per_step": {
            "scenario": "task1 C-EMDM",
            "steps": run.steps,
            "seconds": steps,
            "ratio_to_standard_stack_daqp": {k: base / v["total"] for k, v in steps.items()},
        },
        "runs": runs,
        "rows": rows,
        "batch": {
            "scenario": "task1 C-EMDM, random reachable goals",
            "runs": batch_runs,
            "steps": total_steps,
            "seconds": batch_t,
            "steps_per_second": total_steps / batch_t,
        },
        "spatial": spatial,
        "targets": dict(
            zip(TARGETS, (per_step * 1e6, base / per_step, total_steps / batch_t), strict=True)
        )
        | {
            "Panda pose C-EMDM <= 10 us/step": spatial["simulate_us_per_step"],
            "Panda vs robotics-toolbox-python at its fastest >= 50x": spatial.get(
                "ratio", math.nan
            ),
            "Panda batch >= 2e5 steps/s": spatial["batch"]["steps_per_second"],
            "20 inequality rows: extra cost <= 1 us/step": rows["extra_us_per_step"],
            "later process: kernels loaded from the cache <= 0.5 s": first["cache_load_s"],
        }
        | (
            {"first use, emdm run task1 on an empty cache <= 15 s": first["compile_s"]}
            if "compile_s" in first
            else {}
        ),
        "wall_time_s": time.perf_counter() - start,
    }


def run_dask_bench(
    runs: int = 8000, progress: Callable[[str], None] | None = None
) -> dict[str, Any]:
    """Study throughput on 1- and 2-worker LocalClusters (started and warmed outside the timing)."""
    from dask.distributed import LocalCluster

    from .montecarlo import BLOCK, DEFAULT_CHUNK_BLOCKS, Engine, EngineKind, run_study

    say = progress or (lambda _m: None)
    sc = load_scenario("task1")
    out: dict[str, Any] = {
        "scenario": "task1 study",
        "runs": runs,
        "chunk_runs": DEFAULT_CHUNK_BLOCKS * BLOCK,
        "chunk_reason": "2048 runs x 4 controllers, about 1.3e6 steps or 1 s on one core, "
        "against 1-3 ms of scheduling per task",
    }
    local = run_study(sc, runs, 0, progress=False)
    out["local"] = {
        "seconds": local["wall_time_s"],
        "steps": local["steps"],
        "steps_per_second": local["steps_per_second"],
    }
    for workers in (1, 2):
        with LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster:
            engine = Engine(EngineKind.DASK, scheduler=cluster.scheduler_address)
            # warm-up, not timed: every worker loads the compiled kernels
            run_study(sc, 2 * workers * BLOCK, 1, engine=engine, chunk_blocks=1, progress=False)
            result = run_study(sc, runs, 0, engine=engine, progress=False)
        overhead = 1.0 - result["compute_s"] / (result["wall_time_s"] * workers)
        out[f"dask_{workers}"] = {
            "seconds": result["wall_time_s"],
            "steps": result["steps"],
            "steps_per_second": result["steps_per_second"],
            "compute_s": result["compute_s"],
            "scheduling_overhead": overhead,
        }
        say(f"dask with {workers} worker(s) done")
    one, two = out["dask_1"]["steps_per_second"], out["dask_2"]["steps_per_second"]
    out["targets"] = {
        "2 workers / (2 x 1 worker) >= 0.8": two / (2 * one),
        "scheduling overhead (2 workers) < 5%": out["dask_2"]["scheduling_overhead"],
    }
    return out


def dask_table(data: dict[str, Any]) -> str:
    """The Dask benchmark as a Markdown table."""
    lines = [
        f"Study on Dask ({data['scenario']}, {data['runs']} runs per controller, chunks of "
        f"{data['chunk_runs']} runs: {data['chunk_reason']}):",
        "",
        "| engine | steps | seconds | steps/s | scheduling overhead |",
        "|---|---:|---:|---:|---:|",
    ]
    for key, label in (
        ("local", "local (this process, numba on every core)"),
        ("dask_1", "LocalCluster, 1 worker"),
        ("dask_2", "LocalCluster, 2 workers"),
    ):
        r = data[key]
        over = f"{r['scheduling_overhead']:.1%}" if "scheduling_overhead" in r else ""
        lines.append(
            f"| {label} | {r['steps']} | {r['seconds']:.2f} | "
            f"{r['steps_per_second']:.3g} | {over} |"
        )
    t = data["targets"]
    lines += [
        "",
        f"2 workers reach {t['2 workers / (2 x 1 worker) >= 0.8']:.2f} of twice the "
        f"single-worker throughput (target >= 0.8); scheduling overhead "
        f"{t['scheduling overhead (2 workers) < 5%']:.1%} (target < 5%).",
    ]
    return "\n".join(lines)


def _version(name: str) -> str | None:
    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return None


def bench_table(data: dict[str, Any]) -> str:
    """The benchmark as Markdown tables (what the README shows)."""
    per = data["per_step"]
    lines = [
        f"Per control step, {per['scenario']} ({per['steps']} steps; microseconds, medians "
        f"over {data['repeats']} repeats):",
        "",
        "| path | kinematics | program build | solve | integration | total | vs standard stack |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for name, row in per["seconds"].items():
        cells = [
            f"{row[k] * 1e6:.2f}" if k in row else ""
            for k in ("kinematics", "build", "solve", "integrate")
        ]
        ratio = per["ratio_to_standard_stack_daqp"][name]
        failed = f" ({row['failed_steps']:.0f} steps declined)" if row.get("failed_steps") else ""
        lines.append(
            f"| {name}{failed} | "
            + " | ".join(cells)
            + f" | {row['total'] * 1e6:.2f} | {ratio:.1f}x |"
        )
    lines += [
        "",
        "Whole runs through `emdm.simulate` (median wall time, full record, every step certified):",
        "",
        "| run | steps | ms | us/step |",
        "|---|---:|---:|---:|",
    ]
    for name, r in data["runs"].items():
        lines.append(
            f"| {name} | {r['steps']} | {r['simulate_s'] * 1e3:.3f} | {r['us_per_step']:.2f} |"
        )
    sp = data["spatial"]
    stack = sp["rtb_stack"]
    lines += [
        "",
        f"Spatial ({sp['scenario']}, {sp['steps']} steps): emdm.simulate "
        f"{sp['simulate_us_per_step']:.2f} us/step"
        + (
            f"; robotics-toolbox-python at its fastest ({stack['path']}; {stack['versions']}) "
            f"{stack['total']:.0f} us/step (kinematics {stack['kinematics']:.0f}, solve "
            f"{stack['solve']:.0f}) = {sp['ratio']:.0f}x; its pure-Python DH model "
            f"({sp['rtb_dh_stack']['path']}) {sp['rtb_dh_stack']['total']:.0f} us/step = "
            f"{sp['ratio_dh']:.0f}x"
            if stack
            else "; robotics-toolbox-python is not installed (no ratio)"
        )
        + f". Batch: {sp['batch']['runs']} random tasks, {sp['batch']['steps']} steps in "
        f"{sp['batch']['seconds']:.3f} s = {sp['batch']['steps_per_second']:.3g} steps/s.",
    ]
    rw = data["rows"]
    lines += [
        "",
        f"Inequality rows (task1 C-EMDM with {rw['planes']} loose plane dampers, "
        f"{rw['rows_per_step']:.0f} rows in every program, {rw['active_rows']} active): "
        f"{rw['us_per_step']:.2f} us/step, {rw['extra_us_per_step']:+.2f} us/step over the run "
        f"without rows; largest difference in a command {rw['max_command_difference']:.1e} rad/s.",
    ]
    b, first = data["batch"], data["first_use"]
    lines += [
        "",
        f"Batch ({b['scenario']}): {b['runs']} runs, {b['steps']} steps in "
        f"{b['seconds']:.3f} s = {b['steps_per_second']:.3g} steps/s on "
        f"{data['machine']['cpus']} CPUs.",
        "First use: "
        + ", ".join(
            (
                "`emdm run task1` on an empty kernel cache (the whole command, compiling) "
                if k == "compile_s"
                else "the first `emdm.simulate` of a later process (loading them from the cache) "
            )
            + f"{v:.1f} s"
            for k, v in first.items()
        )
        + ".",
        "",
        "| target | measured |",
        "|---|---:|",
    ]
    units = ("us/step", "x", "steps/s", "us/step", "x", "steps/s", "us/step", "s", "s")
    for (name, value), unit in zip(data["targets"].items(), units, strict=False):
        lines.append(f"| {name} | {value:.3g} {unit} |")
    m = data["machine"]
    lines += [
        "",
        f"Machine: {m['platform']}, Python {m['python']}, "
        + ", ".join(f"{k} {v}" for k, v in m["packages"].items() if v)
        + ".",
    ]
    return "\n".join(lines)


__all__ = ["bench_table", "dask_table", "run_bench", "run_dask_bench", "textbook_kinematics"]
