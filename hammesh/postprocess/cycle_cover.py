"""A cycle cover of the dual graph: vertex-disjoint cycles through most triangles.

Gopi & Eppstein (*Single-strip triangulation of manifolds with arbitrary topology*,
2004): in a cubic graph the edges outside a perfect matching form a 2-factor (disjoint
cycles through every vertex). The dual graph of a mesh with boundary has degrees 1-3;
here ears (and what peeling them leaves) stay uncovered, the degree-3 triangles are
matched among themselves, the rest of the dual edges are the cover, and the few
defects a maximum matching leaves are repaired locally (see
``_sparse_kernels.dual_cover``). Everything is O(m) in numba; the augmenting searches
are bounded by ``budget`` labelled triangles each. Finally cycles are merged for free
where the matching can be rotated around a vertex (``rotate``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hammesh.postprocess import _cover_kernels as _k

__all__ = ["CycleCover", "cycle_cover", "ONLINE_BUDGET", "ONLINE_MIN_TRIANGLES"]

#: Triangles an augmenting search started by the greedy matching may label (``online``).
ONLINE_BUDGET = 256
#: Meshes from this size on use the breadth-first greedy with online searches by
#: default; below it the searches cost little either way and the matching of
#: Triangle's numbering is kept (the small meshes' figures stay as they were).
ONLINE_MIN_TRIANGLES = 100_000


@dataclass(frozen=True, eq=False)
class CycleCover:
    """Cycles of the dual graph.

    Attributes
    ----------
    is_cov : (3 m,) bool
        Half-edges whose dual edge is on a cover cycle (symmetric under ``twin``);
        every covered triangle has exactly two.
    cycle : (m,) int64
        Cycle id of each triangle, -1 for an uncovered one.
    n_cycles : int
    n_uncovered : int
    n_unmatched : int
        Degree-3 triangles the matching left free (before the local repair).
    n_rotations : int
        Cycles merged away by re-matching around vertices.
    """

    is_cov: np.ndarray
    cycle: np.ndarray
    n_cycles: int
    n_uncovered: int
    n_unmatched: int
    n_rotations: int = 0


def cycle_cover(
    triangles: np.ndarray,
    twin: np.ndarray,
    *,
    budget: int = 2000,
    online: int | None = None,
    arc_limit: int | None = None,
    rotate: bool = True,
    good: np.ndarray | None = None,
) -> CycleCover:
    """Cover the dual graph of a triangle mesh with vertex-disjoint cycles.

    Parameters
    ----------
    triangles : (m, 3) int64
    twin : (3 m,) int64
        Half-edge twins (``-1`` on the boundary), ``h = 3 t + k``.
    budget : int
        Triangles one augmenting search may label before it gives up.
    online : int, optional
        The greedy matching sweeps the dual graph breadth-first and starts an
        augmenting search of at most this many triangles from each triangle it
        strands, at once (``_cover_kernels._greedy_matching``); 0: Triangle's
        numbering and the searches afterwards (the matching before session 6).
        Default: ``ONLINE_BUDGET`` from ``ONLINE_MIN_TRIANGLES`` triangles on, else 0.
    arc_limit : int, optional
        Longest cover arc the repair may drop to fix a triangle left unmatched (default:
        any; the alternative, peeling, would drop whole cycles).
    rotate : bool
        Merge cycles by re-matching around vertices (``_sparse_kernels.rotate_stars``):
        fewer cycles, same geometry.
    good : (3 m,) bool, optional
        Half-edges preferred as matching (non-cover) edges where the greedy matching
        has a choice: the non-cover edges are where cycles get joined, so sparse mode
        marks the edges whose join would keep its quality rule.

    Returns
    -------
    CycleCover

    Examples
    --------
    >>> import numpy as np
    >>> from hammesh.halfedge import half_edges
    >>> tri = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]])  # a fan around 0
    >>> c = cycle_cover(tri, half_edges(tri, 5).twin)
    >>> c.n_cycles, c.n_uncovered
    (1, 0)
    """
    tw = np.ascontiguousarray(twin, dtype=np.int64)
    m = len(tw) // 3
    limit = m if arc_limit is None else int(arc_limit)
    if online is None:
        online = ONLINE_BUDGET if m >= ONLINE_MIN_TRIANGLES else 0
    g = np.zeros((m, 3), np.bool_) if good is None else np.ascontiguousarray(good, dtype=np.bool_).reshape(m, 3)
    is_cov, n_free, n_unc = _k.dual_cover(tw, m, int(budget), limit, g, int(online))
    cyc, n_cyc = _k.cycle_ids(tw, is_cov, m)
    n_rot = 0
    if rotate and n_cyc > 1:
        tri = np.ascontiguousarray(triangles, dtype=np.int64)
        n_rot = int(_k.rotate_stars(tri, tw, is_cov, cyc, n_cyc, int(tri.max()) + 1, 2))
        n_cyc -= n_rot
    return CycleCover(
        is_cov=is_cov,
        cycle=cyc,
        n_cycles=int(n_cyc),
        n_uncovered=int(n_unc),
        n_unmatched=int(n_free),
        n_rotations=n_rot,
    )
