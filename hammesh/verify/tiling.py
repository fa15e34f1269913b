"""One step the point-set and polygon certificates share: a triangulation's own boundary.

Both certificates (``hammesh.pointset.verify``, ``hammesh.polygon.verify``) prove that
their output tiles a known region: every point used, every triangle positive by the
exact predicate, every directed edge used once; then its unpaired half-edges must be
the region's boundary and the areas must agree. This module does the first part with
the certificate's own pairing (``hammesh.verify._kernels``), never the constructions'.
"""

from __future__ import annotations

import numpy as np

from hammesh.errors import VerificationError
from hammesh.predicates import orient_many
from hammesh.verify import _kernels

__all__ = ["triangulation_boundary_keys"]


def triangulation_boundary_keys(pts: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Sorted keys ``a * n + b`` of the directed boundary edges of a checked triangulation.

    Parameters
    ----------
    pts : (n, 2) float64
    tri : (m, 3) int64, indices already checked to lie in ``0..n-1``

    Raises
    ------
    VerificationError
        A point no triangle uses, a degenerate or clockwise triangle (exact test), or a
        directed edge used twice (message names it).
    """
    n = len(pts)
    used = np.bincount(tri.reshape(-1), minlength=n) > 0
    if not used.all():
        raise VerificationError(f"point {int(np.argmin(used))} is not a vertex of the triangulation", check="domain")
    sign = orient_many(pts, tri)
    if (sign <= 0).any():
        t = int(np.argmax(sign <= 0))
        raise VerificationError(
            f"triangle {t} {tri[t].tolist()} is {'degenerate' if sign[t] == 0 else 'clockwise'}", check="orientation"
        )
    twin, dup = _kernels.half_edge_twins(tri, n)
    if dup >= 0:
        t, k = divmod(int(dup), 3)
        raise VerificationError(
            f"edge ({tri[t, k]}, {tri[t, (k + 1) % 3]}) of triangle {t} is used twice in the same direction", check="overlap"
        )
    free = _kernels.boundary_half_edges(tri, twin)
    return np.sort(free[:, 0].astype(np.int64) * n + free[:, 1])
