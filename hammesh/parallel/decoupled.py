"""Mesh a domain as decoupled tiles (issue 15 step 1), tile by tile, with repair rounds."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from hammesh.domain import Domain
from hammesh.mesh import Mesh
from hammesh.parallel.tile_mesh import mesh_tile
from hammesh.parallel.tiles import Decomposition, coupled_ends, decompose, split_segments
from hammesh.parallel.union import min_angles_deg

__all__ = ["DecoupledMesh", "mesh_decoupled", "bad_corner_vertices", "repair_rows", "small_angle_vertices",
           "coarse_min_angle", "MAX_ROUNDS"]

#: repair rounds: segments next to a triangle below the min angle are halved and the
#: tiles holding them meshed again
MAX_ROUNDS = 4

#: ``mapper(func, argument_tuples) -> results``, in order (a plain loop, or a cluster)
Mapper = Callable[[Callable, list[tuple]], list]


def _serial(func: Callable, args: list[tuple]) -> list:
    return [func(*a) for a in args]


def bad_corner_vertices(tile_vertex_ids: np.ndarray, n_input: int, mesh: Mesh, min_angle: float | None,
                        ignore: np.ndarray | None = None) -> np.ndarray:
    """Global ids of the tile's vertices (prescribed or the user's own) that are a
    corner of a triangle below ``min_angle``: Triangle could not fix that triangle
    without splitting a segment ``-Y`` protects.

    The user's own vertices count too (session 15): on the domain's boundary a
    triangle with a corner there and its circumcentre over a protected subsegment is
    left as bad as one at a prescribed point (seen on random domains: 21 degrees at
    an input vertex with no repair round). ``n_input`` is kept for the callers.
    ``ignore``: global ids of the small input angles (:func:`small_angle_vertices`):
    a triangle with a corner at one of them is not reported (no repair raises them).
    """
    if min_angle is None:
        return np.zeros(0, np.int64)
    k = len(tile_vertex_ids)
    near = mesh.triangles[(mesh.triangles < k).any(axis=1)]  # only these can have such a corner
    ang = min_angles_deg(mesh.points, near)
    bad = near[ang < float(min_angle) * (1 - 1e-9)]
    if ignore is not None and len(ignore) and len(bad):
        # a bad triangle touching a small input angle (or its shells) is the input's
        local = np.flatnonzero(np.isin(tile_vertex_ids, ignore))
        bad = bad[~np.isin(bad, local).any(axis=1)]
    corners = np.unique(bad.ravel())
    return np.asarray(tile_vertex_ids[corners[corners < k]], np.int64)


def coarse_min_angle(decomp: Decomposition) -> float:
    """Smallest angle of the decomposition's coarse quality mesh (Triangle ``pq`` of the
    whole domain, :func:`~hammesh.parallel.tiles.decompose`): below the min angle only
    at small input angles, where no run of Triangle meets the bound either."""
    t = decomp.coarse_triangles
    return float(min_angles_deg(decomp.coarse_points, t).min()) if len(t) else 180.0


def small_angle_vertices(decomp: Decomposition) -> np.ndarray:
    """The decomposition's vertices at a corner of a coarse triangle below the min
    angle: small input angles and Triangle's concentric shells around them (the coarse
    quality run of the whole domain could not meet the bound there; the shells'
    subsegments are the tiles' own, :func:`~hammesh.parallel.tiles.decompose`). A
    triangle below the bound there is the input's, not the tiles': no repair round
    halves the segments there (halving does not raise an input angle, and four rounds
    made the corner's triangles no better on a random domain with a 20-degree input
    angle, 18.0 degrees as Triangle's coarse run).
    """
    t, q = decomp.coarse_triangles, decomp.min_angle
    if q is None or not len(t):
        return np.zeros(0, np.int64)
    bad = t[min_angles_deg(decomp.coarse_points, t) < q * (1 - 1e-9)]
    if not len(bad):
        return np.zeros(0, np.int64)
    xy = decomp.coarse_points[np.unique(bad.ravel())]
    v = decomp.vertices
    key = np.ascontiguousarray(v).view(np.complex128).ravel()  # (exact coordinates as one key)
    return np.flatnonzero(np.isin(key, np.ascontiguousarray(xy).view(np.complex128).ravel()))


def repair_rows(decomp: Decomposition, ids: np.ndarray) -> np.ndarray:
    """Rows of ``decomp.segments`` to halve for the bad corner vertices ``ids``: every
    segment meeting one of them (not the small input angles, :func:`small_angle_vertices`), and, closed over corners, every segment meeting a
    halved one at a vertex at an angle below ``COUPLED_DEG`` (:func:`coupled_ends`).

    Why the closure: the pieces meeting at a corner start with equal subsegments
    (the tile's triangle there has both as sides, and ``-Y`` forbids the split that
    would fix a thin one). Halving the subsegments at one bad vertex also halves the
    end of each at its other vertex; where that is a corner, its legs were left
    unequal (1 : 2): on random domains the repair rounds made a 29-degree triangle a
    16-degree ear at the next corner and never converged. Halving every leg of such a
    corner keeps their ratio; along a straight chain nothing is tied, so the closure
    stops at the first vertex where the boundary goes straight on.
    """
    seg = decomp.segments
    ids = np.setdiff1d(np.asarray(ids, np.int64), small_angle_vertices(decomp))
    hit = np.isin(seg, ids).any(axis=1)
    if not hit.any():
        return np.zeros(0, np.int64)
    i, j = coupled_ends(decomp.vertices, seg)
    if len(i):
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components

        n = len(seg)
        graph = coo_matrix((np.ones(len(i), np.int8), (i // 2, j // 2)), shape=(n, n))
        _, label = connected_components(graph, directed=False)
        hit = np.isin(label, label[hit])
    return np.flatnonzero(hit)


def _mesh_and_check(tile, min_angle, max_area, n_input, lattice=True, ignore=None):
    m = mesh_tile(tile, min_angle, max_area, lattice=lattice)
    return m, bad_corner_vertices(tile.vertex_ids, n_input, m, min_angle, ignore)


@dataclass(frozen=True, eq=False)
class DecoupledMesh:
    """The tiles' meshes (local numbering) and the decomposition they conform to."""

    decomposition: Decomposition
    meshes: tuple[Mesh, ...]
    rounds: int
    split: int


def mesh_decoupled(domain: Domain, *, min_angle: float | None, max_area: float, n_tiles: int,
                   mapper: Mapper | None = None, lattice: bool = True) -> DecoupledMesh:
    """Decompose ``domain`` and mesh every tile alone (``mapper`` may run them anywhere).

    Where a tile has a triangle below ``min_angle`` at one of the prescribed vertices
    (the discretisation was too coarse for a nearby feature), the segments meeting
    that vertex are halved in the decomposition (both tiles of a separator get the same
    point) and the changed tiles are meshed again, at most ``MAX_ROUNDS`` times.
    ``lattice=False``: no interior lattice (:func:`~hammesh.parallel.tile_mesh.mesh_tile`).
    """
    run = mapper or _serial
    decomp = decompose(domain, min_angle=min_angle, max_area=max_area, n_tiles=n_tiles)
    ignore = small_angle_vertices(decomp)
    results = run(_mesh_and_check, [(t, min_angle, max_area, decomp.n_input, lattice, ignore) for t in decomp.tiles])
    meshes = [r[0] for r in results]
    bad = [r[1] for r in results]
    rounds = split = 0
    while rounds < MAX_ROUNDS:
        ids = np.unique(np.concatenate(bad)) if bad else np.zeros(0, np.int64)
        if len(ids) == 0:
            break
        rows = repair_rows(decomp, ids)
        if len(rows) == 0:  # (a bad corner at a lone vertex: no segment to halve)
            break
        decomp, changed = split_segments(decomp, rows)
        split += len(rows)
        rounds += 1
        again = run(_mesh_and_check, [(decomp.tiles[i], min_angle, max_area, decomp.n_input, lattice, ignore)
                                      for i in changed])
        bad = []
        for i, (m, b) in zip(changed.tolist(), again):
            meshes[i] = m
            bad.append(b)
    return DecoupledMesh(decomposition=decomp, meshes=tuple(meshes), rounds=rounds, split=split)
