"""Compiled kernels of the parallel path (one job each)."""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["area_sum"]


@njit(cache=True, nogil=True)
def area_sum(points: np.ndarray, triangles: np.ndarray) -> float:
    """Sum of the triangles' signed areas (counter-clockwise positive), in one pass:
    numpy's three corner gathers cost ~0.35 s per 2M triangles, this ~10 ms."""
    total = 0.0
    for r in range(triangles.shape[0]):
        a, b, c = triangles[r, 0], triangles[r, 1], triangles[r, 2]
        total += (points[b, 0] - points[a, 0]) * (points[c, 1] - points[a, 1]) \
            - (points[b, 1] - points[a, 1]) * (points[c, 0] - points[a, 0])
    return 0.5 * total
