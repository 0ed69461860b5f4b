"""Writing results: CSV with round-trip precision, JSON, and atomic output folders.

Everything a command writes goes first to a hidden staging folder beside ``--out``; only when the
whole command has succeeded are the files moved into place (``os.replace``, atomic per file). A
failed or interrupted command leaves the previous results in ``--out`` untouched.
"""

from __future__ import annotations

import csv
import json
import math
import os
import shutil
import tempfile
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from ..sim.loop import Run


def cell(value: Any) -> str:
    if isinstance(value, float | np.floating):
        return repr(float(value))
    if isinstance(value, np.integer | np.bool_):
        return str(value.item())
    return str(value)


def trajectory_header(n: int) -> list[str]:
    """Columns of ``trajectories/<controller>.csv`` (DESIGN.md section 3)."""
    return [
        "t",
        *[f"q{i}" for i in range(1, n + 1)],
        *[f"qd{i}" for i in range(1, n + 1)],
        "x",
        "y",
        "ex",
        "ey",
        "vx",
        "vy",
        "m",
        "effort",
        "manip_rate",
        "alpha",
        "delta_x",
        "delta_y",
        "status",
        "solver",
        "iterations",
        "solve_time",
    ]


def trajectory_rows(run: Run) -> Iterator[list[str]]:
    """One row per state; the final state's command fields are empty."""
    n = run.scenario.n
    for k in range(run.steps + 1):
        state = [run.t[k], *run.q[k]]
        where = [*run.p[k], *run.e[k], *run.v[k], run.m[k]]
        if k < run.steps:
            cmd = [*run.qd[k]]
            rest = [
                run.effort[k],
                run.manip_rate[k],
                run.alpha[k],
                *run.delta[k],
                run.status[k],
                run.solver[k],
                run.iterations[k],
                run.solve_time[k],
            ]
        else:
            cmd, rest = [""] * n, [""] * 9
        yield [cell(x) for x in (*state, *cmd, *where, *rest)]


def diagnostics_header(n: int) -> list[str]:
    """Columns of ``diagnostics/<controller>.csv``: how every command was obtained."""
    return [
        "step",
        "kkt_residual",
        "bound_excess",
        "fallback",
        "policy",
        "attempts",
        *[f"lo{i}" for i in range(1, n + 1)],
        *[f"hi{i}" for i in range(1, n + 1)],
        *[f"active{i}" for i in range(1, n + 1)],
    ]


def diagnostics_rows(run: Run) -> Iterator[list[str]]:
    """One row per command."""
    for k in range(run.steps):
        yield [
            cell(x)
            for x in (
                k,
                run.kkt[k],
                run.bound_excess[k],
                bool(run.fallback[k]),
                run.policy[k],
                run.attempts[k],
                *run.lo[k],
                *run.hi[k],
                *run.active[k],
            )
        ]


def write_csv(path: Path, header: Sequence[str], rows: Iterator[list[str]]) -> None:
    """Write a CSV file (creating its folder)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        writer.writerows(rows)


def _json_safe(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_json_safe(v) for v in value]
    if isinstance(value, np.ndarray):
        return _json_safe(value.tolist())
    if isinstance(value, np.floating | float):
        f = float(value)
        return f if math.isfinite(f) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def write_json(path: Path, data: Any) -> None:
    """Write JSON (non-finite floats become null), floats with round-trip precision."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(_json_safe(data), indent=2) + "\n", encoding="utf-8")


@contextmanager
def atomic_output(out: Path) -> Iterator[Path]:
    """Yield a staging folder; on success move its files into ``out``, on any failure discard it."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise NotADirectoryError(f"--out {out} exists and is not a folder")
    out.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=out.parent))
    try:
        yield staging
        for file in sorted(p for p in staging.rglob("*") if p.is_file()):
            target = out / file.relative_to(staging)
            target.parent.mkdir(parents=True, exist_ok=True)
            os.replace(file, target)
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def _float(text: str) -> float:
    return float(text) if text != "" else float("nan")


def read_run(folder: Path, controller: str) -> Run:
    """Read back the run of ``controller`` written by ``emdm run`` into ``folder``.

    The CSVs hold every value at full precision, so the arrays equal the simulated ones exactly.
    """
    from ..core.controllers import get_controller
    from ..core.scenario import scenario_from_dict

    folder = Path(folder)
    meta = json.loads((folder / "metrics.json").read_text(encoding="utf-8"))
    scenario = scenario_from_dict(meta["scenario"], source=str(folder / "metrics.json"))
    n = scenario.n
    with (folder / "trajectories" / f"{controller}.csv").open(encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    with (folder / "diagnostics" / f"{controller}.csv").open(encoding="utf-8") as handle:
        diag = list(csv.DictReader(handle))
    K = len(rows) - 1

    def column(*names: str, last: bool = True) -> np.ndarray:
        used = rows if last else rows[:-1]
        return np.array([[_float(r[name]) for name in names] for r in used])

    joints = [str(i) for i in range(1, n + 1)]
    return Run(
        scenario=scenario,
        controller=get_controller(controller),
        t=column("t")[:, 0],
        q=column(*[f"q{j}" for j in joints]),
        p=column("x", "y"),
        e=column("ex", "ey"),
        v=column("vx", "vy"),
        m=column("m")[:, 0],
        qd=column(*[f"qd{j}" for j in joints], last=False).reshape(K, n),
        effort=column("effort", last=False).reshape(K),
        manip_rate=column("manip_rate", last=False).reshape(K),
        alpha=column("alpha", last=False).reshape(K),
        delta=column("delta_x", "delta_y", last=False).reshape(K, 2),
        lo=np.array([[_float(d[f"lo{j}"]) for j in joints] for d in diag]).reshape(K, n),
        hi=np.array([[_float(d[f"hi{j}"]) for j in joints] for d in diag]).reshape(K, n),
        active=np.array(
            [[int(d[f"active{j}"]) for j in joints] for d in diag], dtype=np.int8
        ).reshape(K, n),
        iterations=np.array([int(r["iterations"]) for r in rows[:-1]], dtype=np.int64),
        solve_time=column("solve_time", last=False).reshape(K),
        kkt=np.array([_float(d["kkt_residual"]) for d in diag]),
        bound_excess=np.array([_float(d["bound_excess"]) for d in diag]),
        fallback=np.array([d["fallback"] == "True" for d in diag], dtype=bool),
        solver=[r["solver"] for r in rows[:-1]],
        status=[r["status"] for r in rows[:-1]],
        attempts=[d["attempts"] for d in diag],
        policy=[d["policy"] for d in diag],
        reached=bool(meta["controllers"][controller]["reached"]),
    )


def write_run_folder(
    folder: Path, scenario: Any, runs: dict[str, Run], **meta: Any
) -> dict[str, dict[str, Any]]:
    """What ``emdm run`` writes: trajectories and diagnostics CSVs, and metrics.json.

    Returns the metrics of every run (as written)."""
    from .. import __version__
    from ..sim.metrics import metrics

    for name, run in runs.items():
        write_csv(
            folder / "trajectories" / f"{name}.csv",
            trajectory_header(scenario.n),
            trajectory_rows(run),
        )
        write_csv(
            folder / "diagnostics" / f"{name}.csv",
            diagnostics_header(scenario.n),
            diagnostics_rows(run),
        )
    results = {name: metrics(run) for name, run in runs.items()}
    write_json(
        folder / "metrics.json",
        {
            "scenario": scenario.to_dict(),
            **meta,
            "emdm_version": __version__,
            "controllers": results,
        },
    )
    return results
