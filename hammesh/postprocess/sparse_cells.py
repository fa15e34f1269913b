"""Sparse mode's compact cycle (issue 14): the cover confined to the fishbone's cells
and bands, the joins taken in the fishbone's class order.

A sparse join inserts one cover cycle whole into another, so the final cycle is the
walk around the tree of joins, each cover cycle a node. Wherever that tree mirrors a
hierarchy of cells (every cell's cycles joined among themselves first, then the cell
joined to the rest by **one** join), each cell is one run of the final cycle, as
each child of the incircle mode's fishbone tree is one run of Thm 2.4's walk
(docs/partition.md, "The fishbone tree" and "Sparse mode": session 12's proposal,
built in session 14). So, with ``hamiltonian(..., mode="sparse", tree="fishbone")``:

1. :func:`fishbone_cells` builds the incircle fishbone's frame
   (``_thm24_kernels.fishbone_frame``: the turn or the ring frame, the kd lines, each
   triangle's cell and spine level) with cells of about ``CELL_TRIANGLES`` triangles,
   widens every spine by ``BAND_STEPS`` dual steps into a *band* (a spine is one
   triangle wide: its dual is a path, no cycle fits in it), and gives every triangle
   its confinement id: its deepest cell, or the band of its spine's level in that
   level's cell. ``cycle_cover(..., cells=)`` keeps every cover cycle inside one id.
2. :func:`join_classes` ranks each join by the fishbone class of the dual edge it
   flips or splits (``_thm24_kernels.edge_class_of`` with the bands as spines):
   inside the deepest cells first, then each level from the deepest up: along the
   band, then the joins that hang a child on its parent's band (the child's own band
   nearest the point where its line meets the parent's first), walls between
   children last. ``sparse._join_order(..., first=True)`` takes the class before
   the tiers and kinds (issue 13's quality rule), which then choose inside a class
   only; Kruskal's rule (``plan_merges``) keeps one join per child.

The price is the confinement's: more cover cycles, more joins across cell borders
that miss the quality rule, more Steiner points. Measured at 300 000 triangles
(docs/partition.md, "Session 14") it cuts plate 3.23 / 2.17 and gear 2.48 / 2.18 x
METIS's at k = 8 / 64 (the default 2.60 / 2.51 and 3.48 / 2.37) for 0.45-0.58 % Steiner
points (0.30 %) and a smallest angle of 15.6-18.3 degrees: an opt-in, short of issue
14's 1.5, because the join tree still does not mirror the cells (pinned borders leak:
one cover cycle crosses most cells; ``STRICT`` borders break the bands into pieces
that ``plan_merges`` joins through the children).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from hammesh.postprocess import _cover_kernels as ck
from hammesh.postprocess import _sparse_cells_kernels as _k
from hammesh.postprocess._thm24_kernels import Frame, fishbone_frame, index_dtype

__all__ = ["FishboneCells", "fishbone_cells", "join_classes", "cell_levels", "CELL_TRIANGLES", "BAND_STEPS",
           "MERGE_LEAF", "SMOOTH_PASSES",
           "STRICT", "confine"]

#: Triangles of a deepest fishbone cell, about (``cell_levels``). Session 10's quadtree
#: cells: about 1 000 triangles is the most confinement the Steiner budget (1 %) allows.
CELL_TRIANGLES = 1024
#: Dual steps a spine is widened by on each side (``_sparse_cells_kernels.widen_bands_into``).
BAND_STEPS = 2
#: Joins inside one deepest cell in one class (the tiers choose there, as without cells).
MERGE_LEAF = True
#: Every dual edge between two cells removed before the cover is matched
#: (``confine``): no cycle crosses a border. False: the border edges are matched
#: first (``cycle_cover``'s pinning), and the matching unpins where a cell's parity
#: needs it.
STRICT = False
#: Passes of ``_cover_kernels.smooth_cells`` over the ids (fewer junction triangles).
SMOOTH_PASSES = 4


class FishboneCells(NamedTuple):
    """Result of :func:`fishbone_cells`.

    Attributes
    ----------
    cell : (m,) int64
        Confinement id of each triangle (``cycle_cover(..., cells=)``).
    fish : (m, 3) int32 or int64
        ``fishbone_frame``'s per-triangle row (quadtree coordinates, -, cell ``|``
        spine level ``<< FISH_SHIFT``), the bands' triangles at their spine's level.
    frame : Frame
        The fishbone's frame (lines, extents, depth, turn).
    triangles : (m, 3) int64
        The triangles the classes are computed on.
    added : int
        Triangles the bands added to the spines.
    """

    cell: np.ndarray
    fish: np.ndarray
    frame: Frame
    triangles: np.ndarray
    added: int


def cell_levels(m: int, cell_triangles: int = CELL_TRIANGLES) -> int:
    """Fishbone levels whose deepest cells hold about ``cell_triangles`` of ``m``
    triangles (the largest ``d`` with ``4^d * cell_triangles <= m``; 0: one cell)."""
    d = 0
    while 4 ** (d + 1) * cell_triangles <= m:
        d += 1
    return d


def fishbone_cells(
    points: np.ndarray,
    triangles: np.ndarray,
    twin: np.ndarray,
    *,
    cell_triangles: int | None = None,
    band_steps: int | None = None,
) -> FishboneCells:
    """The cells and bands sparse mode's cover is confined to (module docstring).

    Parameters
    ----------
    points : (n, 2) float64
    triangles : (m, 3) int64, counter-clockwise
    twin : (3 m,) int64
        Half-edge twins, -1 on the boundary.
    cell_triangles : int, optional
        Triangles of a deepest cell, about (default ``CELL_TRIANGLES``).
    band_steps : int, optional
        Dual steps each spine is widened by (default ``BAND_STEPS``).

    Returns
    -------
    FishboneCells
        Below ``4 * cell_triangles`` triangles one cell (the cover is not confined;
        the joins go by the count quadtree's classes).

    Examples
    --------
    >>> import hammesh
    >>> mesh = hammesh.quality_mesh(hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]]),
    ...                             min_angle=30, max_area=1e-4)
    >>> from hammesh.halfedge import half_edges
    >>> c = fishbone_cells(mesh.points, mesh.triangles, half_edges(mesh.triangles, mesh.n_points).twin,
    ...                    cell_triangles=1000)
    >>> c.frame.depth, len(np.unique(c.cell)) > 4
    (1, True)
    """
    size = CELL_TRIANGLES if cell_triangles is None else int(cell_triangles)
    steps = BAND_STEPS if band_steps is None else int(band_steps)
    pts = np.ascontiguousarray(points, dtype=np.float64)
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    tw = np.ascontiguousarray(twin, dtype=np.int64)
    m = len(tri)
    qr = np.empty((m, 3), index_dtype(m))
    frame = fishbone_frame(tri, tw, pts, qr, levels=cell_levels(m, size))
    nb = ck.neighbors(tw, m)
    word = qr[:, 2].astype(np.int64)
    added = int(_k.widen_bands_into(nb, word, frame.depth, steps, np.empty(m, np.int64), np.empty(m, np.int64)))
    cell = np.empty(m, np.int64)
    _k.confinement_ids_into(word, frame.depth, cell)
    if frame.depth:
        # a triangle with two neighbours in another cell moves there (its word with it)
        ck.smooth_cells(nb, cell, word, SMOOTH_PASSES)
    qr[:, 2] = word
    return FishboneCells(cell, qr, frame, tri, added)


def join_classes(cells: FishboneCells, t: np.ndarray, u: np.ndarray, merge_leaf: bool | None = None) -> np.ndarray:
    """Fishbone class of the join between input triangles ``t[i]`` and ``u[i]``
    (int64 arrays; the join's two rows as ``cells`` numbered them): lower first.
    ``merge_leaf`` (default ``MERGE_LEAF``): the classes inside one deepest cell as one."""
    fr = cells.frame
    out = np.empty(len(t), np.int64)
    merge = MERGE_LEAF if merge_leaf is None else bool(merge_leaf)
    _k.join_classes_into(fr.points, cells.triangles, fr.ca, fr.sa, fr.span, cells.fish, fr.lines, fr.extent, fr.depth,
                         np.ascontiguousarray(t, dtype=np.int64), np.ascontiguousarray(u, dtype=np.int64), merge, out)
    return out


def confine(nb: np.ndarray, cell: np.ndarray) -> int:
    """``cycle_cover``'s hook (``cells=``): with ``STRICT``, remove every dual edge
    between two cells from the neighbour array ``nb`` ((m, 3) int32, in place), so that
    each cell is covered as a domain of its own. Returns the edges removed."""
    return int(_k.sever_cell_borders(nb, cell)) if STRICT else 0
