"""Work on a Dask distributed cluster: benchmark grids and batches as chunks handed to the cluster's workers.

``scheduler`` is ``"tcp://HOST:PORT"`` for a running cluster (``dask scheduler`` and ``dask worker
tcp://HOST:PORT`` started by hand, on this machine or others that see the same files), or ``"local"`` for a
new cluster of worker processes on this machine. :func:`completed` submits one task per chunk and yields each
chunk's result as soon as it is done, in this process (so only this process writes results files). A worker
that dies mid-chunk loses only that chunk's unfinished work: the scheduler runs the chunk again on another
worker, and its result arrives once.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any

from ..errors import MetaikError


class ClusterError(MetaikError):
    """The cluster cannot be reached, or Dask distributed is not installed."""


@contextmanager
def cluster_client(scheduler: str, workers: int | None = None) -> Iterator[Any]:
    """A ``distributed.Client`` of ``scheduler`` (``"tcp://HOST:PORT"`` or ``"local"``: ``workers`` processes of
    one thread each, default one per core), closed on exit (a local cluster is shut down with it)."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise ClusterError("running on a Dask cluster needs Dask distributed: pip install 'metaik[cluster]'") from None
    if scheduler == "local":
        import os

        cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    else:
        if not scheduler.startswith(("tcp://", "tls://", "inproc://", "ws://", "wss://", "ucx://")):
            raise ClusterError(f"scheduler must be an address like tcp://HOST:PORT, or 'local'; got {scheduler!r}")
        cluster = None
        try:
            client = Client(scheduler, timeout="10s")
        except OSError as err:
            raise ClusterError(f"cannot reach the Dask scheduler at {scheduler}: {err}") from None
    try:
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def completed(client: Any, function: Callable, chunks: Sequence, *args: Any,
              stop: Callable[[], bool] | None = None) -> Iterable[tuple[int, Any]]:
    """Run ``function(chunk, *args)`` for every chunk on the cluster; yield ``(index, result)`` as each finishes.

    ``stop()`` is polled between results: True cancels the chunks not yet finished (and ends the iteration).
    """
    from distributed import as_completed

    shared = [client.scatter(a, broadcast=True) if _large(a) else a for a in args]
    futures = [client.submit(function, chunk, *shared, pure=False) for chunk in chunks]
    index = {f.key: k for k, f in enumerate(futures)}
    pending = as_completed(futures)
    for future in pending:
        if stop is not None and stop():
            client.cancel(futures)
            return
        yield index[future.key], future.result()


def _large(value: Any) -> bool:
    """Whether an argument is worth sending once to every worker rather than with each task."""
    return not isinstance(value, (str, int, float, bool, type(None), dict, tuple, list))
