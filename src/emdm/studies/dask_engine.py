"""Running studies on Dask (``pip install 'emdm[dask]'``): a LocalCluster or a real cluster.

Each chunk is one task, ``emdm.study.run_chunk`` on plain data; a worker that dies costs a retry
of its tasks (Dask reschedules them on the others), not the study. Results are yielded as they
complete and combined by the caller in block order, so they do not depend on the cluster.
"""

from __future__ import annotations

import uuid
from collections.abc import Iterator, Sequence
from typing import Any

from ..errors import EmdmError
from .montecarlo import Engine, run_chunk


def local_cluster(workers: int | None) -> Any:
    """A LocalCluster of ``workers`` single-threaded worker processes (default 2)."""
    try:
        from dask.distributed import LocalCluster
    except ImportError:
        raise EmdmError("the dask engine needs pip install 'emdm[dask]'") from None
    return LocalCluster(
        n_workers=workers or 2, threads_per_worker=1, processes=True, dashboard_address=None
    )


def connect(engine: Engine) -> tuple[Any, Any]:
    """A Dask client for ``engine`` and the LocalCluster it started (``None`` for a scheduler)."""
    try:
        from dask.distributed import Client
    except ImportError:
        raise EmdmError("the dask engine needs pip install 'emdm[dask]'") from None
    if engine.scheduler:
        try:
            return Client(engine.scheduler, timeout="5s"), None
        except (OSError, TimeoutError) as exc:
            reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise EmdmError(
                f"cannot reach the Dask scheduler at {engine.scheduler}: {reason}"
            ) from None
    cluster = local_cluster(engine.workers)
    return Client(cluster), cluster


def submit_chunks(
    engine: Engine,
    scenario_data: dict[str, Any],
    seed: int,
    chunks: Sequence[tuple[int, int]],
    runs: int,
    keep_runs: bool,
) -> Iterator[tuple[int, dict[str, Any]]]:
    """``(first_block, result)`` for every chunk, in the order they complete."""
    from dask.distributed import as_completed

    client, cluster = connect(engine)
    try:
        tag = uuid.uuid4().hex[:8]
        futures = {
            client.submit(
                run_chunk,
                scenario_data,
                seed,
                first,
                last,
                runs,
                keep_runs,
                1,
                key=f"emdm-chunk-{tag}-{first}",
                pure=False,
                retries=3,
            ): first
            for first, last in chunks
        }
        for future in as_completed(futures):
            yield futures[future], future.result()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
