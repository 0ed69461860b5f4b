"""Monte-Carlo studies on the batch fast path (``emdm study``), on this machine or on Dask.

Each run draws a start ``q0`` uniformly inside the joint limits (outside the dampers' stop zones)
and a goal ``f(q_target)`` with ``q_target`` uniform inside the limits, so every goal is reachable
by a configuration within the limits. Every controller gets the same draws (paired comparison).

Determinism: the draws are defined per *block* of :data:`BLOCK` runs, block ``b`` from the random
stream ``SeedSequence([seed, b])``; work is split into chunks of whole blocks, each chunk reduced
to sums and counts (and fixed-grid workspace maps), and the chunks are combined in block order.
So a study's results depend only on its parameters and seed: never on the engine, the number of
workers, the chunk size or the order in which chunks finish. Memory is bounded by the chunk size;
per-run records are kept only when asked.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import numpy as np

from ..core.controllers import CONTROLLERS, goal_of
from ..core.scenario import Scenario, scenario_from_dict
from ..errors import EmdmError, check_stop

BLOCK = 256
"""Runs per random block: the unit of the draws (chunks are whole numbers of blocks)."""
SLICE_RUNS = 8 * BLOCK
"""Runs per call of the compiled batch within a chunk (a signal waits for the call it lands in:
about 0.2 s for task1, 2-3 s for the Panda), whatever ``--chunk`` asks; each run is independent,
so the outcomes are the same as in one call."""
GRID = 24
"""Cells per side of the workspace maps."""
DEFAULT_CHUNK_BLOCKS = 8
"""Blocks per chunk (2048 runs): long enough that scheduling costs under 1% of a chunk's time
(a chunk of task1 C-EMDM takes about 0.3-0.5 s on one core; Dask adds about 1-3 ms per task)."""


def draw_block(
    scenario: Scenario, seed: int, block: int, runs: int
) -> tuple[np.ndarray, np.ndarray]:
    """Starts (runs x n) and reachable goals (runs x task rows): the first ``runs`` of block
    ``block``.

    A block always draws all its :data:`BLOCK` runs, so run ``r`` gets the same draw in every
    study of the same seed, whatever its size (a smaller study is a prefix of a larger one).
    """
    rng = np.random.default_rng(np.random.SeedSequence([seed, block]))
    arm, stop = scenario.arm, scenario.damper.stop
    lo, hi = np.asarray(arm.q_min) + 1.01 * stop, np.asarray(arm.q_max) - 1.01 * stop
    q0s = rng.uniform(lo, hi, (BLOCK, scenario.n))[:runs]
    targets = rng.uniform(arm.q_min, arm.q_max, (BLOCK, scenario.n))[:runs]
    goals = np.array([goal_of(scenario, t) for t in targets]).reshape(runs, scenario.nt)
    return q0s, goals


def draw(scenario: Scenario, runs: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The first ``runs`` draws of a study (its blocks, concatenated)."""
    parts = [
        draw_block(scenario, seed, b, min(BLOCK, runs - b * BLOCK))
        for b in range(math.ceil(runs / BLOCK))
    ]
    return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])


# ------------------------------------------------------------------------------ one chunk


def run_chunk(
    scenario_data: dict[str, Any],
    seed: int,
    first_block: int,
    last_block: int,
    runs: int,
    keep_runs: bool = False,
    threads: int | None = None,
) -> dict[str, Any]:
    """Blocks ``[first_block, last_block)`` of a study, reduced to sums, counts and map cells.

    Plain data in and out (it runs on Dask workers). ``threads`` caps numba's threads (one per
    worker process on a cluster, so workers do not compete for cores).
    """
    from ..sim.batch import simulate_batch

    started = time.perf_counter()
    if threads is not None:
        try:
            import numba

            most = int(getattr(numba.config, "NUMBA_NUM_THREADS", 1))
            numba.set_num_threads(max(1, min(threads, most)))
        except ImportError:  # pragma: no cover
            pass
    scenario = scenario_from_dict(scenario_data, source="study")
    blocks = []
    for b in range(first_block, last_block):
        count = min(BLOCK, runs - b * BLOCK)
        if count > 0:
            blocks.append(draw_block(scenario, seed, b, count))
    q0s = np.concatenate([b[0] for b in blocks])
    goals = np.concatenate([b[1] for b in blocks])
    reach = scenario.reach
    edges = np.linspace(-reach, reach, GRID + 1)
    cell = np.clip(np.digitize(goals[:, 1], edges) - 1, 0, GRID - 1) * GRID + np.clip(
        np.digitize(goals[:, 0], edges) - 1, 0, GRID - 1
    )
    outcomes: dict[str, dict[str, np.ndarray]] = {}
    for name in CONTROLLERS:  # in slices: a signal is honoured between two batch calls
        parts = [
            simulate_batch(
                scenario, name, goals=goals[i : i + SLICE_RUNS], q0s=q0s[i : i + SLICE_RUNS]
            ).outcomes()
            for i in range(0, len(goals), SLICE_RUNS)
        ]
        outcomes[name] = {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}
    # reduce block by block: the same 256 runs make a block whatever the chunking, so sums
    # combined in block order do not depend on how the study was split
    reduced = []
    lo = 0
    for q0_block, _ in blocks:
        hi = lo + len(q0_block)
        reduced.append(
            _reduce_block(
                {
                    k: {key: v[lo:hi] for key, v in o.items() if key != "reference_runs"}
                    for k, o in outcomes.items()
                },
                cell[lo:hi],
            )
        )
        lo = hi
    out: dict[str, Any] = {
        "first_block": first_block,
        "blocks": reduced,
        "compute_s": time.perf_counter() - started,
    }
    if keep_runs:
        out["records"] = {
            "goals": goals,
            "q0s": q0s,
            **{
                f"{c}__{k}": v
                for c, o in outcomes.items()
                for k, v in o.items()
                if k != "reference_runs"
            },
        }
    return out


def _reduce_block(outcomes: dict[str, dict[str, np.ndarray]], cell: np.ndarray) -> dict[str, Any]:
    """Sums, counts and map cells of one block of runs."""
    out: dict[str, Any] = {"controllers": {}}
    for name, o in outcomes.items():
        reached = o["reached"]
        out["controllers"][name] = {
            "reached": int(reached.sum()),
            "time_to_goal": float(np.sum(o["time_to_goal"][reached])),
            "mean_manipulability": float(np.sum(o["mean_manipulability"])),
            "min_manipulability": float(np.sum(o["min_manipulability"])),
            "total_effort": float(np.sum(o["total_effort"])),
            "steps": int(np.sum(o["steps"])),
            "final_error": float(np.sum(o["final_error"])),
            "map_time_sum": np.bincount(cell[reached], o["time_to_goal"][reached], GRID * GRID),
            "map_time_count": np.bincount(cell[reached], minlength=GRID * GRID),
        }
    gains = {}
    for prefix in ("UC-", "C-"):
        gain = (
            outcomes[prefix + "EMDM"]["mean_manipulability"]
            / outcomes[prefix + "IVKC"]["mean_manipulability"]
            - 1.0
        )
        gains[prefix] = {
            "sum": float(gain.sum()),
            "improved": int((gain > 0).sum()),
            "map_sum": np.bincount(cell, gain, GRID * GRID),
            "map_count": np.bincount(cell, minlength=GRID * GRID),
        }
    out["gains"] = gains
    return out


PILOT_FROM = 64 * BLOCK
"""Runs per study from which ``emdm study`` times a pilot block before the work, to estimate
how long the whole study takes (below, a study takes seconds: 16,384 task1 runs about 3 s)."""


def seconds_per_run(scenario: Scenario, seed: int) -> float:
    """Seconds one run of every controller takes in this process, measured on the study's own
    first block (:data:`BLOCK` runs of ``scenario`` drawn from ``seed``), after a few runs that
    compile or load the kernels. The study itself runs that block again (it is deterministic)."""
    data = scenario.to_dict()
    run_chunk(data, seed, 0, 1, 4)  # compile (or load) outside the timing
    return float(run_chunk(data, seed, 0, 1, BLOCK)["compute_s"]) / BLOCK


# --------------------------------------------------------------------------------- engines
class EngineKind(StrEnum):
    """Where a study runs: this process (numba on every core) or a Dask cluster."""

    LOCAL = "local"
    DASK = "dask"


@dataclass(frozen=True)
class Engine:
    """Where a study runs: ``local`` or ``dask`` (at ``scheduler``, or on a LocalCluster of
    ``workers`` processes started for the study)."""

    kind: EngineKind = EngineKind.LOCAL
    scheduler: str | None = None
    workers: int | None = None

    def __post_init__(self) -> None:
        try:
            kind = EngineKind(self.kind)
        except ValueError:
            choices = " or ".join(EngineKind)
            raise EmdmError(f"unknown engine {self.kind!r} ({choices})") from None
        object.__setattr__(self, "kind", kind)


def _chunks(runs: int, chunk_blocks: int) -> list[tuple[int, int]]:
    blocks = math.ceil(runs / BLOCK)
    return [(b, min(b + chunk_blocks, blocks)) for b in range(0, blocks, chunk_blocks)]


def run_chunks(
    scenario: Scenario,
    runs: int,
    seed: int,
    engine: Engine,
    *,
    chunk_blocks: int = DEFAULT_CHUNK_BLOCKS,
    keep_runs: bool = False,
    progress: Callable[[int, int], None] | None = None,
) -> Iterator[dict[str, Any]]:
    """Every chunk's reduction, yielded in block order as soon as it can be.

    Chunks that finish early wait in a buffer until the chunks before them are in, so memory is
    bounded by how far out of order the engine completes them, not by the study's size.
    """
    data = scenario.to_dict()
    chunks = _chunks(runs, chunk_blocks)
    order = [first for first, _ in chunks]
    if engine.kind is EngineKind.LOCAL:
        source: Iterator[tuple[int, dict[str, Any]]] = (
            (first, run_chunk(data, seed, first, last, runs, keep_runs)) for first, last in chunks
        )
    else:
        from .dask_engine import submit

        # one numba thread per worker process, so that workers do not compete for cores
        tasks = [(first, (data, seed, first, last, runs, keep_runs, 1)) for first, last in chunks]
        source = submit(engine.scheduler, engine.workers, run_chunk, tasks, name="emdm-chunk")
    pending: dict[int, dict[str, Any]] = {}
    position = done = 0
    for first, result in source:
        check_stop()  # a safe point between chunks (a signal's exception may have been dropped)
        pending[first] = result
        done += 1
        if progress:
            progress(done, len(chunks))
        while position < len(order) and order[position] in pending:
            yield pending.pop(order[position])
            position += 1


class Accumulator:
    """Sums, counts and map cells of a study, added block by block in block order."""

    def __init__(self) -> None:
        self.acc: dict[str, dict[str, Any]] = {}

    def add(self, part: dict[str, Any]) -> None:
        for block in part["blocks"]:
            for group, rows in (("", block["controllers"]), ("gain ", block["gains"])):
                for name, row in rows.items():
                    into = self.acc.setdefault(group + name, {})
                    for key, value in row.items():
                        into[key] = into[key] + value if key in into else value

    def result(self, runs: int) -> dict[str, Any]:
        acc = self.acc
        summary: dict[str, Any] = {}
        maps: dict[str, np.ndarray] = {}
        for name in CONTROLLERS:
            r = acc[name]
            summary[name] = {
                "success_rate": r["reached"] / runs,
                "mean_time_to_goal": r["time_to_goal"] / r["reached"] if r["reached"] else None,
                "mean_manipulability": r["mean_manipulability"] / runs,
                "mean_min_manipulability": r["min_manipulability"] / runs,
                "mean_total_effort": r["total_effort"] / runs,
                "mean_final_error": r["final_error"] / runs,
                "steps": r["steps"],
            }
            with np.errstate(invalid="ignore", divide="ignore"):
                maps[f"{name} time to goal"] = np.where(
                    r["map_time_count"] > 0, r["map_time_sum"] / r["map_time_count"], np.nan
                )
        gains = {}
        for prefix in ("UC-", "C-"):
            r = acc["gain " + prefix]
            gains[f"{prefix}EMDM over {prefix}IVKC"] = {
                "mean_gain": r["sum"] / runs,
                "share_of_runs_improved": r["improved"] / runs,
            }
            with np.errstate(invalid="ignore", divide="ignore"):
                maps[f"{prefix}EMDM gain over {prefix}IVKC"] = np.where(
                    r["map_count"] > 0, r["map_sum"] / r["map_count"], np.nan
                )
        return {
            "controllers": summary,
            "manipulability_gain": gains,
            "steps": sum(s["steps"] for s in summary.values()),
            "maps": maps,
        }


def run_study(
    scenario: Scenario,
    runs: int,
    seed: int,
    *,
    engine: Engine | None = None,
    chunk_blocks: int = DEFAULT_CHUNK_BLOCKS,
    keep_runs: bool = False,
    progress: bool | Callable[[int, int], None] = True,
) -> dict[str, Any]:
    """A whole study: every controller on the same ``runs`` draws, reduced.

    ``progress``: a bar on stderr (``True``), none, or ``progress(chunks_done, chunks)``."""
    engine = engine or Engine()
    start = time.perf_counter()

    def bar(done: int, total: int) -> None:
        if callable(progress):
            progress(done, total)
        elif progress:
            fill = "#" * int(30 * done / total)
            print(
                f"\r  [{fill:<30}] {done}/{total} chunks, {time.perf_counter() - start:.1f} s",
                end="" if done < total else "\n",
                file=sys.stderr,
                flush=True,
            )

    acc = Accumulator()
    records: list[dict[str, np.ndarray]] = []
    compute = 0.0
    chunks = 0
    for part in run_chunks(
        scenario, runs, seed, engine, chunk_blocks=chunk_blocks, keep_runs=keep_runs, progress=bar
    ):
        acc.add(part)  # the part is then dropped: memory stays bounded by the chunk
        compute += part["compute_s"]
        chunks += 1
        if keep_runs:
            records.append(part["records"])
    elapsed = time.perf_counter() - start
    result = acc.result(runs)
    result.update(
        scenario=scenario.name,
        runs=runs,
        seed=seed,
        wall_time_s=elapsed,
        steps_per_second=result["steps"] / elapsed,
        engine=engine.kind.value,
        chunk_runs=chunk_blocks * BLOCK,
        chunks=chunks,
        compute_s=compute,
    )
    if keep_runs:
        result["records"] = {k: np.concatenate([r[k] for r in records]) for k in records[0]}
    return result


TIMING = ("wall_time_s", "steps_per_second", "engine", "chunk_runs", "chunks", "compute_s")
"""What depends on where a study ran: kept out of study.json (which must not), in timing.json."""


def study_json(result: dict[str, Any]) -> dict[str, Any]:
    """The study's JSON: everything but the engine-specific timings and the arrays."""
    skip = {"maps", "records", *TIMING}
    out = {k: v for k, v in result.items() if k not in skip}
    out["maps"] = {
        k: [[None if math.isnan(x) else x for x in row] for row in v.reshape(GRID, GRID).tolist()]
        for k, v in result["maps"].items()
    }
    return out


def study_table(data: dict[str, Any]) -> str:
    rows = [
        f"{data['scenario']}: {data['runs']} runs per controller (seed {data['seed']}), "
        f"{data['steps']} steps in {data['wall_time_s']:.2f} s on {data['engine']} "
        f"({data['steps_per_second']:.3g} steps/s, {data['chunks']} chunks of "
        f"{data['chunk_runs']} runs)",
        "",
        f"{'controller':<10} {'success':>8} {'mean t_goal[s]':>15} {'mean m':>8} "
        f"{'mean effort':>12}",
    ]
    for name, s in data["controllers"].items():
        ttg = f"{s['mean_time_to_goal']:.2f}" if s["mean_time_to_goal"] is not None else "-"
        rows.append(
            f"{name:<10} {s['success_rate']:>8.1%} {ttg:>15} "
            f"{s['mean_manipulability']:>8.4f} {s['mean_total_effort']:>12.3f}"
        )
    rows.append("")
    for name, g in data["manipulability_gain"].items():
        rows.append(
            f"{name}: mean manipulability gain {g['mean_gain']:+.1%}, improved in "
            f"{g['share_of_runs_improved']:.1%} of the runs"
        )
    return "\n".join(rows)


def parse_weights(text: str) -> list[tuple[float, float]]:
    """``"0.1:0,0.1:5"`` -> ``[(0.1, 0.0), (0.1, 5.0)]`` (w_E:w_M pairs)."""
    pairs = []
    for item in text.split(","):
        effort, sep, manip = item.partition(":")
        try:
            pair = (float(effort), float(manip))
        except ValueError:
            raise EmdmError(f"--weights: {item!r} is not w_E:w_M (e.g. 0.1:5)") from None
        if not sep or not all(math.isfinite(v) for v in pair) or pair[0] <= 0 or pair[1] < 0:
            raise EmdmError(f"--weights: {item!r} needs w_E > 0 and w_M >= 0, finite")
        pairs.append(pair)
    return pairs


def sweep_scenarios(
    scenarios: Sequence[Scenario], weights: Sequence[tuple[float, float]] | None
) -> list[Scenario]:
    """The scenario of each study of a sweep, in order: every scenario with each weight pair
    ``(w_E, w_M)``, or as it is without ``weights``."""
    if not weights:
        return list(scenarios)
    return [
        sc.with_overrides({"weights.effort": w_e, "weights.manipulability": w_m})
        for sc in scenarios
        for w_e, w_m in weights
    ]


def run_sweep(
    scenarios: Sequence[Scenario],
    weights: Sequence[tuple[float, float]] | None,
    runs: int,
    seed: int,
    engine: Engine,
    *,
    chunk_blocks: int = DEFAULT_CHUNK_BLOCKS,
    keep_runs: bool = False,
    progress: bool | Callable[[int, int], None] = True,
) -> list[dict[str, Any]]:
    """A study for every scenario and weight pair, on one engine (one cluster for all)."""
    cluster = None
    if engine.kind is EngineKind.DASK and not engine.scheduler:
        from .dask_engine import local_cluster

        cluster = local_cluster(engine.workers)
        engine = Engine(EngineKind.DASK, scheduler=cluster.scheduler_address)
    try:
        results = []
        for sc in sweep_scenarios(scenarios, weights):
            result = run_study(
                sc,
                runs,
                seed,
                engine=engine,
                chunk_blocks=chunk_blocks,
                keep_runs=keep_runs,
                progress=progress,
            )
            result["weights"] = {
                "effort": sc.weights.effort,
                "manipulability": sc.weights.manipulability,
            }
            results.append(result)
        return results
    finally:
        if cluster is not None:
            cluster.close()


def trade_off_rows(
    results: Sequence[dict[str, Any]], scenario: str, controller: str
) -> list[dict[str, Any]]:
    """One row per weight pair of a sweep for ``scenario``: ``controller``'s study means, in the
    shape of :func:`emdm.studies.pareto.weight_grid`'s rows (whole-run trade-off)."""
    return [
        {
            "w_effort": r["weights"]["effort"],
            "w_manip": r["weights"]["manipulability"],
            "total_effort": r["controllers"][controller]["mean_total_effort"],
            "mean_manipulability": r["controllers"][controller]["mean_manipulability"],
            "time_to_goal": r["controllers"][controller]["mean_time_to_goal"],
        }
        for r in results
        if r["scenario"] == scenario
    ]
