"""Dask (``dask.distributed``) as the optional runner of the tiles (``pip install hammesh[dask]``)."""

from __future__ import annotations

import contextlib
from typing import Iterator

from hammesh.errors import InvalidOptionError

__all__ = ["runner_for", "DASK_MISSING"]

DASK_MISSING = "parallel meshing on workers needs Dask: pip install hammesh[dask]"


def _distributed():
    try:
        import distributed
    except ImportError:
        raise InvalidOptionError(DASK_MISSING) from None
    return distributed


@contextlib.contextmanager
def runner_for(*, workers: int | None = None, client=None, scheduler: str | None = None) -> Iterator[tuple[object, int]]:
    """``(runner, n_workers)``: a Dask client (given, connected to ``scheduler``, or a
    local cluster of ``workers`` processes started here and closed on exit), or the
    in-process :class:`~hammesh.parallel.run.LocalRunner` when none is asked for."""
    from hammesh.parallel.run import LocalRunner

    if client is not None:
        yield client, max(1, len(client.scheduler_info().get("workers", {})))
        return
    if scheduler is not None:
        distributed = _distributed()
        with distributed.Client(scheduler) as c:
            yield c, max(1, len(c.scheduler_info().get("workers", {})))
        return
    if workers is None:
        yield LocalRunner(), 1
        return
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InvalidOptionError(f"workers must be a positive integer, got {workers!r}")
    distributed = _distributed()
    import logging

    # one process per worker, one thread each: Triangle and the kernels hold their core;
    # Dask's shutdown chatter (nanny warnings) is not the user's business
    with distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                  dashboard_address=None, silence_logs=logging.ERROR) as cluster, \
            distributed.Client(cluster) as c:
        yield c, workers
