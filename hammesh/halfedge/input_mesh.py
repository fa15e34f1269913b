"""Validation of a triangle mesh handed to an algorithm (ours or read from a file)."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from hammesh.halfedge import _kernels, locality
from hammesh.domain.validate import MAX_ABS_COORDINATE, check_extent
from hammesh.errors import InvalidMeshError
from hammesh.mesh import Mesh

__all__ = ["HalfEdges", "half_edges", "mesh_arrays", "prepare_mesh", "match_half_edges", "local_half_edges"]


@dataclass(frozen=True, eq=False)
class HalfEdges:
    """Half-edge adjacency of a triangle array.

    ``h = 3 t + k`` runs from ``triangles[t, k]`` to ``triangles[t, (k + 1) % 3]``.
    ``twin[h]`` is the opposite half-edge (-1 on the boundary); ``vertex_he[v]`` is
    one half-edge leaving ``v`` (the start of a rotation around ``v``).
    """

    triangles: np.ndarray
    twin: np.ndarray
    vertex_he: np.ndarray

    def mark(self, segments: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(is_con (3m,) bool, found (s,) bool)`` for constrained edges ``segments``."""
        segs = np.ascontiguousarray(segments, dtype=np.int64).reshape(-1, 2)
        return _kernels.mark_segments(self.triangles, self.twin, self.vertex_he, segs)

    def neighbors_of(self, v: int) -> np.ndarray:
        """Vertices sharing an edge with ``v`` (may repeat)."""
        return _kernels.vertex_neighbors(self.triangles, self.twin, self.vertex_he, int(v))


def _raise_non_manifold(tri: np.ndarray, bad: int) -> None:
    t, k = divmod(int(bad), 3)
    a, b = int(tri[t, k]), int(tri[t, (k + 1) % 3])
    raise InvalidMeshError(
        f"edge ({a}, {b}) of triangle {t} is shared by more than two triangles or by "
        "two triangles in the same direction (non-manifold edge or overlap)"
    )


def half_edges(triangles: np.ndarray, n_points: int, neighbors: np.ndarray | None = None) -> HalfEdges:
    """Match the half-edges of ``triangles``; raise if an edge is non-manifold.

    Parameters
    ----------
    triangles : (m, 3) int64, consistently oriented
    n_points : int
    neighbors : (m, 3) int64, optional
        A neighbour array to take the matching from (e.g. Triangle's); it is checked
        (each claimed neighbour holds the edge reversed and names us back) and ignored
        if wrong. A trusted neighbour array skips the O(m) bucket matching.

    Raises
    ------
    InvalidMeshError
        An edge is used twice in the same direction: three or more triangles share
        it, or two neighbours are oriented inconsistently (overlap).
    """
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    twin = None
    if neighbors is not None and np.shape(neighbors) == tri.shape:
        twin, bad = _kernels.twins_from_neighbors(tri, np.ascontiguousarray(neighbors, dtype=np.int64))
        if bad >= 0:
            twin = None
    if twin is None:
        twin, bad = _kernels.half_edge_twins(tri, int(n_points))
        if bad >= 0:
            _raise_non_manifold(tri, bad)
    return HalfEdges(triangles=tri, twin=twin, vertex_he=_kernels.vertex_half_edges(tri, int(n_points)))


def mesh_arrays(
    points: np.ndarray, triangles: np.ndarray, dims: tuple[int, ...] = (2,)
) -> tuple[np.ndarray, np.ndarray]:
    """Contiguous ``float64`` points and ``int64`` triangles, checked before any kernel.

    Parameters
    ----------
    points : (n, d) array_like, d in ``dims``
    triangles : (m, 3) array_like of int

    Raises
    ------
    InvalidMeshError
        Wrong shapes or dtype, no triangles, a non-finite point or one beyond
        ``MAX_ABS_COORDINATE`` (squared lengths overflow), points spanning less than
        ``MIN_EXTENT`` (areas underflow), an index out of range
        (the message names the point or triangle).
    """
    return _checked_arrays(points, triangles, dims)[:2]


def _checked_arrays(
    points: np.ndarray, triangles: np.ndarray, dims: tuple[int, ...], indices: bool = True
) -> tuple[np.ndarray, np.ndarray, tuple[list[float], list[float]]]:
    """:func:`mesh_arrays` and the points' column ranges it found (``(lo, hi)``, as
    ``hammesh.domain.validate.column_ranges``: for the cells' grid). ``indices=False``:
    the vertex indices not checked (signed ones: the caller's orientation pass checks
    them as it reads the rows, then :func:`_refuse_bad_index`)."""
    pts = np.asarray(points)
    tri = np.asarray(triangles)
    if pts.ndim != 2 or pts.shape[1] not in dims:
        shapes = " or ".join(f"(n, {d})" for d in dims)
        raise InvalidMeshError(f"points must have shape {shapes}, got {pts.shape}")
    if tri.ndim != 2 or tri.shape[1] != 3:
        raise InvalidMeshError(f"triangles must have shape (m, 3), got {tri.shape}")
    if len(tri) == 0:
        raise InvalidMeshError("the mesh has no triangles")
    if not np.issubdtype(tri.dtype, np.integer):
        raise InvalidMeshError(f"triangles must be integers, got dtype {tri.dtype}")
    pts = np.ascontiguousarray(pts, dtype=np.float64)
    if tri.dtype.kind == "u" and tri.max() >= len(pts):  # before the cast wraps 2**64-1 to -1
        t, k = np.argwhere(tri >= len(pts))[0]
        raise InvalidMeshError(
            f"triangle {t} references vertex {int(tri[t, k])} but there are only {len(pts)} points"
        )
    tri = np.ascontiguousarray(tri, dtype=np.int64)
    # (one compiled pass per row range, both cores, for every check below; the
    # row-wise searches for the messages only on failure)
    finite, lo, hi, least, most = _kernels.input_ranges(pts, tri, indices)
    if not finite:
        i = int(np.argmin(np.isfinite(pts).all(axis=1)))
        raise InvalidMeshError(f"point {i} has a non-finite coordinate {pts[i].tolist()}")
    if len(pts) and max(-min(lo), max(hi)) > MAX_ABS_COORDINATE:  # planar and 3D alike
        i = int(np.argmax(np.abs(pts).max(axis=1) > MAX_ABS_COORDINATE))
        raise InvalidMeshError(
            f"point {i} {pts[i].tolist()} is beyond |x| <= {MAX_ABS_COORDINATE:g} "
            "(squared lengths would overflow)"
        )
    check_extent(pts, InvalidMeshError, ranges=(lo, hi))
    if least < 0 or most >= len(pts) or not len(pts):  # (no points: every index is out of range)
        _refuse_bad_index(tri, len(pts))
    return pts, tri, (lo, hi)


def _refuse_bad_index(tri: np.ndarray, n: int) -> None:
    """Raise naming the first triangle with a vertex index out of range, if any."""
    out = (tri < 0) | (tri >= n)
    if out.any():
        t = int(np.argmax(out.any(axis=1)))
        raise InvalidMeshError(
            f"triangle {t} references vertex {int(tri[t][out[t]][0])} but there are only {n} points"
        )


def prepare_mesh(
    mesh: Mesh, *, measure: bool = True, cells: bool = False, match: bool = True
) -> tuple[Mesh, HalfEdges | None, np.ndarray | None]:
    """Check a planar mesh and return it counter-clockwise with its half-edges.

    ``measure=False``: no ``info["validated"]`` (for a construction that needs none of
    it: Thm 2.4's; the orientation pass then only orients and checks).
    ``cells=True`` (with ``measure``): the orientation pass also finds every
    triangle's cell key for ``hammesh.halfedge.renumber_local`` (``info["validated"]
    ["cells"]``, a ``locality.CellKeys``, consumed by the renumbering).
    ``match=False`` (with ``cells``): the half-edges are not matched here, ``he`` and
    ``is_con`` are None: :func:`local_half_edges` matches them once, in the renumbered
    order (sparse mode), or :func:`match_half_edges` in this one.

    Returns
    -------
    mesh : Mesh
        Same mesh with int64/float64 arrays and every triangle counter-clockwise.
    he : HalfEdges or None
    is_con : (3 m,) bool or None
        Half-edges that lie on a constrained edge (``mesh.segments``). None both
        with ``match=False`` and ``cells``.

    The returned mesh's ``info["validated"]`` holds what the orientation pass found on
    the way: ``min_angle`` (radians), ``total`` (area) and ``used`` (bool per point),
    for a construction's own use (sparse mode's bound), and ``ranges``, the points'
    column ranges ``(lo, hi)`` (a renumbering keeps them: ``locality.grid_frame``'s
    ``ranges``); the certificate never reads it.

    Raises
    ------
    InvalidMeshError
        Naming the bad item: shapes, non-finite points, out-of-range indices, a
        triangle with a repeated vertex or zero area, a non-manifold edge, a segment
        that is not an edge of the mesh.
    """
    # (the indices are checked by the orientation pass, which reads the rows anyway)
    pts, tri, ranges = _checked_arrays(mesh.points, mesh.triangles, (2,), indices=False)
    n = len(pts)
    used = np.zeros(n, dtype=np.bool_) if measure else None
    keys = None
    if cells and measure:  # (the bounding box only of finite points, checked above)
        grid = locality.cell_grid(pts, len(tri), ranges=ranges)
        keys = locality.empty_cell_keys(grid, len(tri))
    rows = tri
    tri, n_flipped, bad_t, min_angle, area = _kernels.orient_ccw(
        pts, rows, used, measure=measure, cells=None if keys is None else (grid, keys)
    )
    if bad_t >= 0:
        _refuse_bad_index(rows, n)  # (first, as mesh_arrays would have)
        t = int(bad_t)
        row = np.asarray(mesh.triangles)[t].tolist()
        what = "repeats a vertex" if len(set(row)) < 3 else "has zero area"
        raise InvalidMeshError(f"triangle {t} {row} {what}")
    segs = np.asarray(mesh.segments)
    if segs.size == 0:
        segs = np.zeros((0, 2), dtype=np.int64)
    if segs.ndim != 2 or segs.shape[1] != 2:
        raise InvalidMeshError(f"segments must have shape (s, 2), got {segs.shape}")
    segs = np.ascontiguousarray(segs, dtype=np.int64)
    sout = (segs < 0) | (segs >= n)
    if sout.any():
        s = int(np.argmax(sout.any(axis=1)))
        raise InvalidMeshError(
            f"segment {s} references vertex {segs[s][sout[s]][0]} but there are only {n} points"
        )
    # neighbours (Triangle's) are only valid for the rows as given
    nbr = mesh.neighbors if n_flipped == 0 else None
    he = is_con = None
    if match or not (cells and measure):
        he, is_con = _matched(tri, n, nbr, segs)
    attrs = np.asarray(mesh.triangle_attributes, dtype=np.float64)
    if attrs.ndim != 2 or attrs.shape[0] != len(tri):
        attrs = np.zeros((len(tri), 0))
    clean = replace(
        mesh,
        points=pts,
        triangles=tri,
        segments=segs,
        segment_markers=np.asarray(mesh.segment_markers, dtype=np.int64).reshape(-1),
        triangle_attributes=attrs,
        # found on the way, for a construction's bound (sparse mode's local rule)
        info={**mesh.info, "validated": {"min_angle": min_angle, "total": area, "used": used, "cells": keys,
                                         "neighbors": nbr if he is None else None, "ranges": ranges}}
        if measure
        else dict(mesh.info),
    )
    return clean, he, is_con


def _matched(tri: np.ndarray, n: int, nbr: np.ndarray | None, segs: np.ndarray) -> tuple[HalfEdges, np.ndarray]:
    """:func:`half_edges` of checked rows and the half-edges on ``segs``; raise if one is missing."""
    he = half_edges(tri, n, neighbors=nbr)
    is_con, found = he.mark(segs)
    _refuse_missing(segs, found)
    return he, is_con


def _refuse_missing(segs: np.ndarray, found: np.ndarray) -> None:
    if not found.all():
        missing = int(np.argmin(found))
        raise InvalidMeshError(
            f"segment {missing} {segs[missing].tolist()} is not an edge of the mesh"
        )


def match_half_edges(clean: Mesh) -> tuple[HalfEdges, np.ndarray]:
    """``(he, is_con)`` of a mesh ``prepare_mesh(..., match=False)`` returned, in its order.

    Raises
    ------
    InvalidMeshError
        As ``prepare_mesh``: a non-manifold edge, a segment that is not an edge.
    """
    nbr = (clean.info.get("validated") or {}).get("neighbors")
    return _matched(clean.triangles, clean.n_points, nbr, clean.segments)


def local_half_edges(clean: Mesh, room: tuple[int, int] = (0, 0)) -> locality.Renumbered:
    """A mesh ``prepare_mesh(..., cells=True, match=False)`` returned, renumbered for
    locality (``locality.renumber_local``) with its half-edges matched once.

    With a neighbour array to try (Triangle's, rows not reversed) the twins are
    matched in the new order (``locality.renumber_from_neighbors``: at 1.5 M triangles
    ~0.035 s CPU and ~0.02 s of the serial path fewer than matching them in the
    input's order and renumbering them, docs/sparse.md, session 16); otherwise, or if
    the neighbours are not to be trusted, as ``prepare_mesh`` matches them, then
    renumbered. ``marks``: the half-edges on a segment. ``room``: as
    ``renumber_local``'s. The cell keys are consumed.

    Raises
    ------
    InvalidMeshError
        As ``prepare_mesh`` would have (the messages name the input's rows and vertices).
    """
    seen = clean.info.get("validated") or {}
    keys = seen.pop("cells", None)
    nbr = seen.pop("neighbors", None)
    if nbr is not None and np.shape(nbr) == clean.triangles.shape:
        got = locality.renumber_from_neighbors(clean.points, clean.triangles, nbr, clean.segments, keys, room)
        if got is not None:
            loc, found = got
            _refuse_missing(clean.segments, found)
            return loc
        keys = None  # (consumed by the try)
    he, is_con = _matched(clean.triangles, clean.n_points, nbr, clean.segments)
    return locality.renumber_local(clean.points, clean.triangles, he.twin, is_con, keys, room)
