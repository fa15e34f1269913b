"""Plain threads for compiled kernels that release the GIL (``nogil=True``).

The machine's cores share a pass over row ranges; a kernel call holds no Python
state, so threads need no more than a pool. Below ``min_rows`` rows per thread the
pass runs in the calling thread (thread start-up would cost more than it saves).
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Callable

__all__ = ["row_ranges", "run_all", "THREAD_MIN_ROWS"]

#: Rows per thread below which a row pass runs in one call (tests lower it to exercise
#: the threaded paths on small meshes).
THREAD_MIN_ROWS = 200_000


def row_ranges(m: int, min_rows: int) -> list[tuple[int, int]]:
    """Split ``range(m)`` into one contiguous range per core, each >= ``min_rows``."""
    k = max(1, min(os.cpu_count() or 1, m // max(1, min_rows)))
    cuts = [m * i // k for i in range(k + 1)]
    return [(cuts[i], cuts[i + 1]) for i in range(k)]


def run_all(calls: list[Callable[[], Any]]) -> list[Any]:
    """Results of ``calls``, run side by side (in the caller's thread if just one)."""
    if len(calls) == 1:
        return [calls[0]()]
    with ThreadPoolExecutor(min(len(calls), os.cpu_count() or 1)) as pool:
        return [f.result() for f in [pool.submit(c) for c in calls]]
