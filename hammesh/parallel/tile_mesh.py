"""Mesh one tile with Triangle, its boundary (separators included) kept unsplit."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hammesh.domain.validate import holes_in_hull
from hammesh.errors import MeshingError
from hammesh.mesh import Mesh
from hammesh.meshing.options import format_number
from hammesh.parallel.guard import triangulate_guarded
from hammesh.parallel.tiles import Tile

__all__ = ["tile_switches", "mesh_tile", "mesh_band", "region_attributes", "locate_in_triangles", "lattice_points",
           "lattice_grid", "LatticeGrid", "lattice_spacing", "LATTICE_CLEARANCE", "LATTICE_GRADING", "LATTICE_BOX_FILL",
           "LATTICE_BAND", "LATTICE_BLOCK", "LATTICE_ORDER", "lattice_blocks", "load_tile_kernels",
           "outline_hole_points"]

#: lattice points keep this many lattice steps from every segment (Triangle fills the
#: band between the segments' subsegments and the lattice, grading as it does)
LATTICE_CLEARANCE = 1.5
#: ... plus this many times the shortfall ``h - length`` of a subsegment shorter than the
#: step ``h`` (the mesh grows from short subsegments to the lattice's size over that band)
LATTICE_GRADING = 2.0
#: Triangle meshes only the band between the segments and the lattice, whose own
#: triangles are made here (:func:`mesh_band`); False: Triangle gets the lattice's
#: points and triangulates them too (the order before session 10, kept for the A/B)
LATTICE_BAND = True
#: the band's Triangle call of a tile estimated below this many triangles runs in a
#: child process (``guard.triangulate_guarded``'s ``isolate``): it crashed the
#: interpreter twice (SIGSEGV in ``mesh_band``, clean checkouts: CI of session 16, a
#: fresh venv of session 17, both in the random coarse-domain tests) on input the guard
#: does not flag. Not above: at 6M (tiles of 0.75M) a child per band took the sparse
#: command from 1.05 to 1.53 x raw Triangle (the fork of a ~700 MB worker, the result's
#: copy); a small tile's fork costs ~10 ms
BAND_ISOLATED_BELOW = 200_000
#: the lattice's triangles are numbered in blocks of this many strips and cells
#: (:func:`~hammesh.parallel._kernels.lattice_triangles_into`: neighbours close in memory)
LATTICE_BLOCK = 2
#: the order of those blocks: ``"rows"`` (row by row) or ``"hilbert"`` (a Hilbert
#: curve over the blocks, session 10's). Session 12, one 1.5M-triangle tile of the 6M
#: demo, same process, two tiles x two rounds (CPU s): the mesh step 0.13-0.27 rows
#: against 0.21-0.34 hilbert (the curve's keys and sort, and the scattered writes),
#: ``hamiltonian()`` the same or less (sparse 1.19-1.48 against 1.28-1.52, incircle
#: 0.48-0.77 against 0.52-0.85): sparse mode now renumbers big meshes by cells itself
#: (``sparse.LOCAL_MIN_TRIANGLES``), so the curve no longer pays for itself.
LATTICE_ORDER = "rows"
#: no lattice when the tile's box holds more than this many lattice points per
#: estimated triangle of the tile (about 0.5 of them are inside when the tile fills it)
LATTICE_BOX_FILL = 8.0


def region_attributes(tile: Tile, points: np.ndarray, triangles: np.ndarray, neighbors: np.ndarray,
                      segments: np.ndarray) -> np.ndarray:
    """Regional attribute of every triangle, read off the coarse mesh once per region piece.

    Triangle spreads a region's attribute from its point up to the segments around it;
    a tile's part of a region need not hold the point, so the attribute comes from the
    coarse mesh (which Triangle gave the attributes). Region boundaries are segments, so
    the tile's triangles fall into pieces (dual components, never crossing a segment)
    that each lie in one region: one coarse point location per piece, not per
    triangle (locating all of them cost ~1 s per 750k triangles plus the locator).
    """
    from hammesh.parallel._kernels import label_pieces_into

    m, n = len(triangles), len(points)
    values = np.unique(tile.region_attribute)
    if len(values) == 1:  # the tile lies in one region (or in none)
        return np.full(m, values[0])
    seg_keys = np.unique(np.sort(segments, axis=1) @ np.array([n, 1], np.int64))
    on_seg = np.zeros(n, np.bool_)
    on_seg[segments.ravel()] = True
    label = np.empty(m, np.int64)
    seeds = np.empty(m, np.int64)  # (only the first few entries are ever touched)
    count = label_pieces_into(np.ascontiguousarray(triangles, dtype=np.int64),
                              np.ascontiguousarray(neighbors, dtype=np.int64), seg_keys, on_seg, label, seeds)
    first = seeds[:count]
    where = locate_in_triangles(tile.region_points, tile.region_triangles, points[triangles[first]].mean(axis=1))
    if (where < 0).any():
        raise MeshingError(f"tile {tile.index}: a triangle lies outside the coarse mesh (regions)")
    return tile.region_attribute[where][label]


def locate_in_triangles(p: np.ndarray, t: np.ndarray, q: np.ndarray, chunk: int = 64) -> np.ndarray:
    """For each query point, the triangle of ``(p, t)`` holding it most deeply (largest
    smallest barycentric coordinate), -1 if none holds it (tolerance 1e-9). Brute force
    over the triangles, ``chunk`` points at a time: meant for few queries."""
    a, b, c = p[t[:, 0]], p[t[:, 1]], p[t[:, 2]]
    det = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    det = np.where(det == 0, np.inf, det)
    out = np.full(len(q), -1, np.int64)
    for i in range(0, len(q), chunk):
        x, y = q[i:i + chunk, 0:1], q[i:i + chunk, 1:2]
        l1 = ((b[:, 0] - x) * (c[:, 1] - y) - (b[:, 1] - y) * (c[:, 0] - x)) / det
        l2 = ((c[:, 0] - x) * (a[:, 1] - y) - (c[:, 1] - y) * (a[:, 0] - x)) / det
        depth = np.minimum(np.minimum(l1, l2), 1 - l1 - l2)
        best = depth.argmax(axis=1) if len(t) else np.zeros(len(x), np.int64)
        ok = depth[np.arange(len(x)), best] >= -1e-9 if len(t) else np.zeros(len(x), bool)
        out[i:i + chunk] = np.where(ok, best, -1)
    return out


def lattice_spacing(max_area: float) -> float:
    """Step ``h`` of the equilateral lattice whose triangles have area ``AREA_FILL x max_area``:
    a ``q30 a A`` Triangle mesh's mean triangle, so the tile has as many triangles as one
    Triangle run would make (``sqrt(3) / 4 h^2 = AREA_FILL A``)."""
    from hammesh.parallel.sizing import AREA_FILL

    return float(np.sqrt(4.0 * AREA_FILL * float(max_area) / np.sqrt(3.0)))


def lattice_points(tile: Tile, max_area: float) -> np.ndarray:
    """Points of an equilateral triangular lattice filling the tile's interior, to be
    given to Triangle with the tile's PSLG: ``(n, 2)`` float64.

    Why: Triangle's refinement inserts its Steiner points one at a time (find the
    circumcentre, dig the cavity, re-queue the new triangles): about 2/3 of the CPU
    of a ``q30 a A`` run. Input vertices go through its divide-and-conquer Delaunay
    instead, and lattice triangles (60 degrees, area ``AREA_FILL x A`` <= A) already
    meet the bounds, so Triangle refines only the band between the tile's segments and
    the lattice (measured on a 1.5M-triangle square: 0.65x the CPU, +0.2 % triangles).
    The idea is isosurface stuffing's (Labelle & Shewchuk, SIGGRAPH 2007: a lattice of
    good elements fills the interior, only the layer at the boundary is special); here
    Triangle makes that layer, so its guarantees hold unchanged: every triangle of the
    output is Triangle's, at least ``min_angle``, at most ``max_area``.

    A point is kept when it lies in the domain (one of the tile's coarse triangles,
    holes and the outside are not), in the tile's box, at least ``LATTICE_CLEARANCE``
    steps from every segment of the tile (more near subsegments shorter than a step,
    ``LATTICE_GRADING``) and two steps from every vertex on no segment. No kept
    point is near a separator, so neighbouring tiles never see each other's lattice.
    None when the domain fills less than about 1/16 of the tile's box
    (``LATTICE_BOX_FILL``: the mask over the box would then cost more than it saves).
    """
    grid = lattice_grid(tile, max_area)
    if grid is None:
        return np.zeros((0, 2))
    j, i = np.nonzero(grid.keep)
    return grid.coords(j, i)


@dataclass(frozen=True)
class LatticeGrid:
    """The lattice of a tile: point ``(i, j)`` at ``(x0 + (i + (j & 1) / 2) h, y0 + j dy)``,
    ``keep[j, i]`` where :func:`lattice_points` keeps it."""

    keep: np.ndarray
    x0: float
    y0: float
    h: float
    dy: float

    def coords(self, j: np.ndarray, i: np.ndarray) -> np.ndarray:
        out = np.empty((len(j), 2))
        self.coords_into(j, i, out)
        return out

    def coords_into(self, j: np.ndarray, i: np.ndarray, out: np.ndarray) -> None:
        """:meth:`coords` written into ``out`` (``(len(j), 2)`` float64)."""
        x, y = out[:, 0], out[:, 1]
        np.bitwise_and(j, 1, out=y, casting="unsafe")  # (y as scratch: the row's half step)
        np.multiply(y, 0.5, out=x)
        np.add(x, i, out=x)
        np.multiply(x, self.h, out=x)
        np.add(x, self.x0, out=x)
        np.multiply(j, self.dy, out=y)
        np.add(y, self.y0, out=y)


def outline_hole_points(grid: LatticeGrid, corners: np.ndarray, out_t: np.ndarray, outline: np.ndarray,
                        nx: int) -> np.ndarray:
    """Centroid of one lattice triangle on each closed loop of the lattice's outline
    (its edges ``outline``, the lattice triangles ``out_t`` they bound): a point inside
    every piece of the lattice, for Triangle's holes (a piece with holes or pinched
    loops gets several: Triangle eats the same piece from each).

    Why not one per piece by a flood fill over the lattice (the order before session
    14): that pass visited every lattice triangle (~1M per tile, ~18 % of the band
    step's CPU) for a handful of points; the outline has a few thousand edges.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    if not len(outline):
        return np.zeros((0, 2))
    # the loops, joined through points with two outline edges only: at a point where
    # pieces touch (four or six edges) the loops are cut (each edge end its own node),
    # so no two pieces are ever one loop; a loop cut into arcs gets a point per arc
    ends = outline.ravel()
    deg = np.bincount(ends)
    node = np.where(deg[ends] == 2, ends, len(deg) + np.arange(len(ends)))
    nodes, inv = np.unique(node, return_inverse=True)
    inv = inv.reshape(-1, 2)
    u = len(nodes)
    graph = coo_matrix((np.ones(len(inv), np.int8), (inv[:, 0], inv[:, 1])), shape=(u, u))
    _, lab = connected_components(graph, directed=False)
    _, first = np.unique(lab[inv[:, 0]], return_index=True)
    c = corners[out_t[first]].ravel()
    return grid.coords(c // nx, c % nx).reshape(-1, 3, 2).mean(axis=1)


def lattice_grid(tile: Tile, max_area: float) -> LatticeGrid | None:
    """The tile's lattice (:func:`lattice_points`'s rules) as a grid; None when it has none."""
    from hammesh.parallel._kernels import (lattice_clear_near_points_into, lattice_clear_near_segments_into,
                                           lattice_mark_inside_into)

    h = lattice_spacing(max_area)
    dy = h * np.sqrt(3.0) / 2.0
    x0, x1, y0, y1 = (float(v) for v in tile.box)
    x0, y0 = x0 + 0.5 * h, y0 + 0.5 * dy
    nx, ny = int((x1 - x0) // h), int((y1 - y0) // dy)
    if nx < 2 or ny < 2 or len(tile.coarse_triangles) == 0 or len(tile.segments) == 0:
        return None
    if nx * ny > LATTICE_BOX_FILL * max(float(tile.estimate), 1e5):
        # the domain fills little of the box (a thin slanted strip): a mask over the
        # whole box would cost more than the lattice saves; Triangle alone then
        return None
    keep = np.zeros((ny, nx), np.bool_)
    lattice_mark_inside_into(x0, y0, h, dy, np.ascontiguousarray(tile.coarse_points, dtype=np.float64),
                             np.ascontiguousarray(tile.coarse_triangles, dtype=np.int64), keep)
    v = np.ascontiguousarray(tile.vertices, dtype=np.float64)
    seg = np.ascontiguousarray(tile.segments, dtype=np.int64)
    length = np.linalg.norm(v[seg[:, 0]] - v[seg[:, 1]], axis=1)
    radius = LATTICE_CLEARANCE * h + LATTICE_GRADING * np.maximum(0.0, h - length)
    lattice_clear_near_segments_into(x0, y0, h, dy, v, seg, radius, keep)
    on_seg = np.zeros(len(v), bool)
    on_seg[seg.ravel()] = True
    if not on_seg.all():
        lattice_clear_near_points_into(x0, y0, h, dy, np.ascontiguousarray(v[~on_seg]), 2.0 * h, keep)
    return LatticeGrid(keep=keep, x0=x0, y0=y0, h=h, dy=dy)


def tile_switches(min_angle: float | None, max_area: float) -> str:
    """Triangle's switches for a tile: ``-Y`` keeps every boundary segment unsplit.

    ``-Y`` ("no Steiner point on the mesh boundary", Triangle's documentation; ``-YY``
    would also forbid them on interior segments, which the tile does not need): the
    separators are on the tile's boundary, so both tiles along one keep exactly its
    given subsegments. Internal user segments may still be split.
    """
    sw = "p"
    if min_angle is not None:
        sw += "q" + format_number(min_angle)
    return sw + "a" + format_number(max_area) + "YnQ"


def lattice_blocks(strips: int, cells: int, block: int, order: str | None = None) -> np.ndarray:
    """``(k, 2)`` block row and column of every ``block`` x ``block`` block of a
    ``strips`` x ``cells`` grid, in the order
    :func:`~hammesh.parallel._kernels.lattice_triangles_into` numbers them in:
    ``order`` (default :data:`LATTICE_ORDER`) ``"rows"``, row by row, or ``"hilbert"``,
    a Hilbert order of the blocks' centres."""
    order = LATTICE_ORDER if order is None else order
    bj, bi = np.divmod(np.arange(-(-strips // block) * -(-cells // block)), -(-cells // block))
    if order == "rows":
        return np.ascontiguousarray(np.stack([bj, bi], axis=1), dtype=np.int64)
    from hammesh.numbering import hilbert_keys

    # (centres in the plane: a strip is sqrt(3)/2 of a cell high)
    keys = np.argsort(hilbert_keys(np.stack([bi, bj * (np.sqrt(3.0) / 2.0)], axis=1)), kind="stable")
    return np.ascontiguousarray(np.stack([bj, bi], axis=1)[keys], dtype=np.int64)


def mesh_band(tile: Tile, grid: LatticeGrid, min_angle: float | None, max_area: float) -> Mesh | None:
    """The tile's mesh made of the lattice's own triangles inside and Triangle's mesh
    of the band between them and the tile's segments; None when that band mesh is not
    good enough (then :func:`mesh_tile` has Triangle mesh the lattice's points too).

    Why: given the lattice's points, Triangle spent nearly all of a tile's run on
    their Delaunay triangulation (divide and conquer over ~1.5M points, ~2 s CPU per
    3M-triangle tile), to find the lattice's own triangles: it inserted only ~0.7 %
    more points. Those triangles are known: strip by strip, two equilateral triangles
    of area ``AREA_FILL x max_area`` per cell (:func:`~hammesh.parallel._kernels.lattice_mesh_into`).
    Triangle gets the band alone, with the lattice's outline as segments it may not
    split (``-Y``, as the separators) and one hole point in each piece of the lattice
    (Triangle removes what is inside the outline): ~35k triangles, ~0.03 s.

    Kept only when checked here, else None: every band triangle meets ``min_angle``
    (one below it only at the tile's own points, what the repair rounds look at, as
    without the band) and ``max_area``; Triangle kept the given points in order;
    every outline edge is an edge of exactly one band triangle, in the opposite
    direction (the band and the lattice conform: no point of either on the other's
    edges). The lattice's triangles have 60-degree angles and area ``AREA_FILL x
    max_area``, so the whole mesh meets both bounds, as Triangle's own run would.
    """
    from hammesh.parallel._kernels import label_pieces_into, lattice_mesh_into, lattice_triangles_into
    from hammesh.parallel.union import min_angles_deg

    keep = grid.keep
    ny, nx = keep.shape
    index = np.empty((ny - 1, 2 * (nx - 1)), np.int64)
    count = lattice_triangles_into(keep, LATTICE_BLOCK, lattice_blocks(ny - 1, nx - 1, LATTICE_BLOCK), index)
    if count == 0:
        return None
    corners = np.empty((count, 3), np.int64)
    lnbr = np.empty((count, 3), np.int64)
    incident = np.empty(nx * ny, np.int64)
    lattice_mesh_into(index, nx, corners, lnbr, incident)
    interior = incident == 6  # (every triangle around it kept: not on the outline)
    band_ids = np.flatnonzero(keep.ravel() & ~interior)
    inner_ids = np.flatnonzero(interior)
    k, nb = len(tile.vertices), len(band_ids)
    pid = np.full(nx * ny, -1, np.int64)
    pid[band_ids] = k + np.arange(nb)
    out_t, out_s = np.nonzero(lnbr < 0)  # the outline, from the lattice's side
    outline = np.stack([pid[corners[out_t, out_s]], pid[corners[out_t, (out_s + 1) % 3]]], axis=1)
    # a hole point inside every piece of the lattice: the centroid of one outline
    # triangle per loop of the outline
    hole_xy = outline_hole_points(grid, corners, out_t, outline, nx)
    verts = np.concatenate([tile.vertices, grid.coords(band_ids // nx, band_ids % nx)])
    data = {
        "vertices": np.ascontiguousarray(verts, dtype=np.float64),
        "segments": np.ascontiguousarray(np.concatenate([tile.segments, outline]), dtype=np.int32),
        "segment_markers": np.ascontiguousarray(np.concatenate([tile.segment_markers, np.zeros(len(outline), np.int64)]),
                                                dtype=np.int32)[:, None],
    }
    # (the lattice's points lie inside the tile: the hull of the tile's own vertices is the input's)
    holes = np.concatenate([holes_in_hull(tile.vertices, tile.holes), hole_xy])
    if len(holes):
        data["holes"] = np.ascontiguousarray(holes)
    # (in a child process, always: the band's Triangle call crashed the interpreter twice
    # on clean checkouts -- CI session 16, a fresh venv session 17 -- on input the guard
    # does not flag, heap-dependent, never reproduced in forked children; a failure
    # there falls back to the tile's plain run below)
    try:
        out = triangulate_guarded(data, tile_switches(min_angle, max_area), f"tile {tile.index}'s band",
                                  isolate=tile.estimate < BAND_ISOLATED_BELOW)
    except MeshingError:
        return None
    bt = np.asarray(out.get("triangles", np.zeros((0, 3))), dtype=np.int64).reshape(-1, 3)
    bp = np.asarray(out["vertices"], dtype=np.float64)
    if len(bt) == 0 or len(bp) < k + nb or not np.array_equal(bp[: k + nb], verts):
        return None
    raw_nbr = np.asarray(out["neighbors"]).reshape(-1, 3)
    bnbr = np.empty(raw_nbr.shape, np.int64)  # ours: across edge (s, s + 1); Triangle's: opposite corner s
    bnbr[:, 0], bnbr[:, 1], bnbr[:, 2] = raw_nbr[:, 2], raw_nbr[:, 0], raw_nbr[:, 1]
    on_lattice = (bt >= k) & (bt < k + nb)
    e1, e2 = bp[bt[:, 1]] - bp[bt[:, 0]], bp[bt[:, 2]] - bp[bt[:, 0]]
    if (0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]) > float(max_area) * (1 + 1e-9)).any():
        return None
    if min_angle is not None:
        bad = min_angles_deg(bp, bt) < float(min_angle) * (1 - 1e-9)
        # below the bound only at the tile's own points (the repair rounds' case), never at the lattice's
        if (bad & (on_lattice.any(axis=1) | ~(bt < k).any(axis=1))).any():
            return None
    # stitch: each outline edge (a, b) is one band triangle's boundary edge (b, a)
    br, bs = np.nonzero(bnbr < 0)
    ba, bb = bt[br, bs], bt[br, (bs + 1) % 3]
    edge = on_lattice[br, bs] & on_lattice[br, (bs + 1) % 3]  # (no tile segment joins two lattice points)
    br, bs, ba, bb = br[edge], bs[edge], ba[edge], bb[edge]
    n_out = len(bp)
    okey = outline[:, 0] * n_out + outline[:, 1]
    order = np.argsort(okey)
    sk = okey[order]
    pos = np.minimum(np.searchsorted(sk, bb * n_out + ba), max(len(sk) - 1, 0))
    if len(br) != len(sk) or not np.array_equal(sk[pos], bb * n_out + ba) or len(np.unique(pos)) != len(pos):
        return None
    mb = len(bt)
    pid[inner_ids] = n_out + np.arange(len(inner_ids))
    # (the whole tile's arrays filled in place: no temporary of their size)
    points = np.empty((n_out + len(inner_ids), 2))
    points[:n_out] = bp
    grid.coords_into(inner_ids // nx, inner_ids % nx, points[n_out:])
    tri = np.empty((mb + count, 3), np.int64)
    tri[:mb] = bt
    np.take(pid, corners, out=tri[mb:])
    nbr = np.empty((mb + count, 3), np.int64)
    nbr[:mb] = bnbr
    np.add(lnbr, mb, out=nbr[mb:])
    nbr[mb:][lnbr < 0] = -1
    lt, ls = out_t[order[pos]], out_s[order[pos]]
    nbr[br, bs] = lt + mb
    nbr[mb + lt, ls] = br
    segs = np.asarray(out.get("segments", np.zeros((0, 2))), dtype=np.int64).reshape(-1, 2)
    marks = np.asarray(out.get("segment_markers", np.zeros((0, 1))), dtype=np.int64).reshape(-1)
    user = ~(((segs >= k) & (segs < k + nb)).all(axis=1))  # the outline is no segment of the domain
    segs, marks = segs[user], marks[user]
    attrs = np.zeros((len(tri), 0))
    if len(tile.region_triangles) and len(np.unique(tile.region_attribute)) == 1:
        attrs = np.full((len(tri), 1), tile.region_attribute[0])  # (the tile lies in one region)
    elif len(tile.region_triangles):
        # each piece of the lattice lies in one region (no segment comes near it): one
        # location per piece; the band's own pieces (its neighbours stop at the
        # outline) by the flood fill, over the band only (not the whole tile's rows)
        inside = region_attributes(tile, bp, bt, bnbr, segs)
        label = np.empty(count, np.int64)
        seeds = np.empty(count, np.int64)
        pieces = label_pieces_into(corners, lnbr, np.zeros(0, np.int64), np.zeros(nx * ny, np.bool_), label, seeds)
        first = corners[seeds[:pieces]].ravel()
        where = locate_in_triangles(tile.region_points, tile.region_triangles,
                                    grid.coords(first // nx, first % nx).reshape(-1, 3, 2).mean(axis=1))
        if (where < 0).any():
            raise MeshingError(f"tile {tile.index}: a piece of the lattice lies outside the coarse mesh (regions)")
        attrs = np.concatenate([inside, tile.region_attribute[where][label]])[:, None]
    return Mesh(points=points, triangle_attributes=attrs, triangles=tri, segments=segs, segment_markers=marks,
                neighbors=nbr, info={"backend": "triangle", "switches": tile_switches(min_angle, max_area),
                                     "tile": tile.index, "lattice": "band",
                                     # (98 % lattice rows, strip by strip: sparse mode need
                                     # not renumber them, ``sparse.renumbers``)
                                     "rows_local": True})


def mesh_tile(tile: Tile, min_angle: float | None, max_area: float, lattice: bool = True) -> Mesh:
    """Triangle mesh of one tile, in its local numbering.

    The tile's vertices keep their order (points ``[:len(tile.vertex_ids)]``, their
    coordinates exactly the tile's); the interior lattice (:func:`lattice_points`,
    unless ``lattice=False``) and Triangle's Steiner points follow.

    Subnormal coordinates go to Triangle as 0 and come back as given
    (:func:`~hammesh.parallel.tiles.without_subnormals`: Triangle's predicates assume
    no underflow).
    """
    from dataclasses import replace

    from hammesh.parallel.tiles import without_subnormals

    given = np.asarray(tile.vertices, dtype=np.float64)
    safe = without_subnormals(given)
    if np.array_equal(safe, given):
        return _mesh_tile(tile, min_angle, max_area, lattice)
    m = _mesh_tile(replace(tile, vertices=safe), min_angle, max_area, lattice)
    m.points[: len(given)] = given
    return m


def _mesh_tile(tile: Tile, min_angle: float | None, max_area: float, lattice: bool) -> Mesh:
    grid = lattice_grid(tile, max_area) if lattice else None
    if grid is not None and LATTICE_BAND:
        band = mesh_band(tile, grid, min_angle, max_area)
        if band is not None:
            return band
    extra = np.zeros((0, 2)) if grid is None else grid.coords(*np.nonzero(grid.keep))
    data = {
        "vertices": np.ascontiguousarray(np.concatenate([tile.vertices, extra]), dtype=np.float64),
        "segments": np.ascontiguousarray(tile.segments, dtype=np.int32),
        "segment_markers": np.ascontiguousarray(tile.segment_markers, dtype=np.int32)[:, None],
    }
    holes = holes_in_hull(tile.vertices, tile.holes)  # (the lattice's points lie inside the tile)
    if len(holes):
        data["holes"] = np.ascontiguousarray(holes)
    out = triangulate_guarded(data, tile_switches(min_angle, max_area), f"tile {tile.index}")
    tri = np.asarray(out.get("triangles", np.zeros((0, 3))), dtype=np.int64).reshape(-1, 3)
    if len(tri) == 0:
        raise MeshingError(f"Triangle produced no triangles for tile {tile.index}")
    # ours: neighbors[:, s] across edge (s, s + 1); Triangle's column s is opposite corner s
    raw_nbr = np.asarray(out["neighbors"]).reshape(-1, 3)
    nbr = np.empty(raw_nbr.shape, np.int64)  # (one pass from Triangle's int32 rows, no stacked copy)
    nbr[:, 0], nbr[:, 1], nbr[:, 2] = raw_nbr[:, 2], raw_nbr[:, 0], raw_nbr[:, 1]
    pts = np.asarray(out["vertices"], dtype=np.float64)
    if len(pts) < len(tile.vertices) or not np.array_equal(pts[: len(tile.vertices)], tile.vertices):
        raise MeshingError(f"Triangle did not keep tile {tile.index}'s vertices in order")
    segs = np.asarray(out.get("segments", np.zeros((0, 2))), dtype=np.int64).reshape(-1, 2)
    attrs = np.zeros((len(tri), 0))
    if len(tile.region_triangles):
        attrs = region_attributes(tile, pts, tri, nbr, segs)[:, None]
    return Mesh(
        points=pts,
        triangle_attributes=attrs,
        triangles=tri,
        segments=segs,
        segment_markers=np.asarray(out.get("segment_markers", np.zeros((0, 1))), dtype=np.int64).reshape(-1),
        neighbors=nbr,
        info={"backend": "triangle", "switches": tile_switches(min_angle, max_area), "tile": tile.index},
    )


def load_tile_kernels() -> Mesh:
    """Load (or, with a stale numba cache, compile) the compiled kernels of a tile's
    mesh with its lattice into this process: :func:`mesh_tile` of a small square
    (~2k triangles, the band path); returns that mesh.

    Why: a local cluster's workers are forked after the driver has loaded the
    Hamiltonian mode's kernels (:func:`hammesh.parallel.cluster.start_method`), but
    the lattice's kernels were loaded by each worker in its first tile, inside the
    tile's measured mesh step, and compiled there by every worker at once after an
    edit or an install had made numba's cache stale. Loaded in the driver before the
    fork, the workers start with them.
    """
    from hammesh.domain import Domain
    from hammesh.parallel.tiles import decompose

    from hammesh.parallel._kernels import label_pieces_into

    area = 1e-3
    d = decompose(Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]]), min_angle=30, max_area=area, n_tiles=1)
    m = mesh_tile(d.tiles[0], 30, area)
    # (the regions' flood fill, which a tile of one region does not run)
    label = np.empty(m.n_triangles, np.int64)
    label_pieces_into(m.triangles, m.neighbors, np.zeros(0, np.int64), np.zeros(m.n_points, np.bool_), label,
                      np.empty(m.n_triangles, np.int64))
    return m
