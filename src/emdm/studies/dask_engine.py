"""Running work on Dask (``pip install 'emdm[dask]'``): a LocalCluster or a real cluster.

The engine knows nothing of what it runs: it is given a work function and the arguments of each
task (plain data, since they travel to the workers). A worker that dies costs a retry of its
tasks (Dask reschedules them on the others), not the whole job. Results are yielded as they
complete, with the key of their task; the caller puts them in order.
"""

from __future__ import annotations

import uuid
from collections.abc import Callable, Hashable, Iterator, Sequence
from typing import Any, TypeVar

from ..errors import EmdmError

K = TypeVar("K", bound=Hashable)
R = TypeVar("R")


def local_cluster(workers: int | None) -> Any:
    """A LocalCluster of ``workers`` single-threaded worker processes (default 2)."""
    try:
        from dask.distributed import LocalCluster
    except ImportError:
        raise EmdmError("the dask engine needs pip install 'emdm[dask]'") from None
    return LocalCluster(
        n_workers=workers or 2, threads_per_worker=1, processes=True, dashboard_address=None
    )


def connect(scheduler: str | None, workers: int | None) -> tuple[Any, Any]:
    """A Dask client for ``scheduler`` (or for a LocalCluster of ``workers`` started here) and
    the LocalCluster it started (``None`` for a scheduler)."""
    try:
        from dask.distributed import Client
    except ImportError:
        raise EmdmError("the dask engine needs pip install 'emdm[dask]'") from None
    if scheduler:
        try:
            return Client(scheduler, timeout="5s"), None
        except (OSError, TimeoutError) as exc:
            reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise EmdmError(f"cannot reach the Dask scheduler at {scheduler}: {reason}") from None
    cluster = local_cluster(workers)
    return Client(cluster), cluster


def submit(
    scheduler: str | None,
    workers: int | None,
    work: Callable[..., R],
    tasks: Sequence[tuple[K, tuple[Any, ...]]],
    *,
    name: str = "emdm-task",
) -> Iterator[tuple[K, R]]:
    """``(key, work(*args))`` for every ``(key, args)`` of ``tasks``, in the order they complete.

    ``work`` must be importable by the workers (a module-level function); each task is retried
    up to three times when its worker dies.
    """
    from dask.distributed import as_completed

    client, cluster = connect(scheduler, workers)
    try:
        tag = uuid.uuid4().hex[:8]
        futures = {
            client.submit(work, *args, key=f"{name}-{tag}-{key}", pure=False, retries=3): key
            for key, args in tasks
        }
        for future in as_completed(futures):
            yield futures[future], future.result()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
