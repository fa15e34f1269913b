"""Kernels of ``hammesh.postprocess.sparse_cells`` (numba): the bands round the
fishbone's spines, the cells the cover is confined to, and the joins' classes.

Conventions as in ``_thm24_kernels``: small kernels named by what they do, fill
kernels (``_into``) behind the module's thin wrappers.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from hammesh.postprocess._thm24_kernels import FISH_SHIFT, LEAF_CLASSES, edge_class_of

__all__ = ["widen_bands_into", "confinement_ids_into", "join_classes_into", "sever_cell_borders"]


@njit(cache=True, nogil=True)
def widen_bands_into(nb, word, depth, steps, frontier, nxt):
    """Widen every spine of the fishbone (``word``: ``cell | spine level << FISH_SHIFT``
    per triangle, ``depth``: on no spine) by ``steps`` dual steps, in place.

    A spine is the chain of triangles its line crosses: its dual is a path, and a
    cover cycle cannot stay inside it. ``steps`` layers of edge neighbours on each
    side make a band two to three triangles wide whose dual holds the stars of the
    line's vertices (cycles). A triangle joins the band of level ``L`` only if it is
    on no spine of a level up to ``L`` and lies in the same level-``L`` cell (its
    cell's top ``L`` digits): a band never leaks across its cell's walls. Levels go
    from the top down, so an ancestor's band keeps what it reached.
    ``frontier``, ``nxt``: (m,) int64 work arrays. Returns the triangles added."""
    m = word.shape[0]
    low = (1 << FISH_SHIFT) - 1
    added = 0
    for level in range(depth):
        n = 0
        for t in range(m):
            if (word[t] >> FISH_SHIFT) == level:
                frontier[n] = t
                n += 1
        shift = 2 * (depth - level)
        for _ in range(steps):
            k = 0
            for i in range(n):
                t = frontier[i]
                prefix = (word[t] & low) >> shift
                for j in range(3):
                    u = nb[t, j]
                    if u < 0 or (word[u] >> FISH_SHIFT) <= level or ((word[u] & low) >> shift) != prefix:
                        continue
                    word[u] = (word[u] & low) | (level << FISH_SHIFT)
                    nxt[k] = u
                    k += 1
            added += k
            for i in range(k):
                frontier[i] = nxt[i]
            n = k
    return added


@njit(cache=True, nogil=True)
def confinement_ids_into(word, depth, cell):
    """The cover's cell of each triangle: its deepest fishbone cell off every band,
    else the band of its spine level ``L`` in its level-``L`` cell
    (``L << 32 | the cell's top L digits``)."""
    low = (1 << FISH_SHIFT) - 1
    for t in range(word.shape[0]):
        level = word[t] >> FISH_SHIFT
        cell[t] = (np.int64(level) << 32) | (np.int64(word[t] & low) >> (2 * (depth - level)))


@njit(cache=True, nogil=True)
def join_classes_into(points, tri, ca, sa, span, qr, lines, extent, depth, t, u, merge_leaf, out):
    """``_thm24_kernels.edge_class_of`` of each pair ``(t[i], u[i])`` (any two input
    triangles: a join's, through the rows it replaced). ``merge_leaf``: every class
    inside one deepest cell (the count quadtree's, below ``LEAF_CLASSES``) counted as
    one, so that inside a cell the tiers and the slack alone choose the joins."""
    for i in range(t.shape[0]):
        c = edge_class_of(points, tri, ca, sa, span, qr, t[i], u[i], lines, extent, depth)
        out[i] = 0 if merge_leaf and c < LEAF_CLASSES else c


@njit(cache=True, nogil=True)
def sever_cell_borders(nb, cell):
    """Remove every dual edge between two cells from ``nb`` (in place): the cover then
    sees each cell as a domain of its own, and no augmenting search of the matching
    can carry a cycle across a border (``cycle_cover``'s pinned border edges are
    unpinned where a cell's parity needs it). Returns the edges removed."""
    n = 0
    for t in range(nb.shape[0]):
        for k in range(3):
            u = nb[t, k]
            if u >= 0 and cell[u] != cell[t]:
                nb[t, k] = -1
                n += 1
    return n // 2
