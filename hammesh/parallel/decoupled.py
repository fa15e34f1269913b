"""Mesh a domain as decoupled tiles (issue 15 step 1), tile by tile, with repair rounds."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from hammesh.domain import Domain
from hammesh.mesh import Mesh
from hammesh.parallel.tile_mesh import mesh_tile
from hammesh.parallel.tiles import Decomposition, decompose, split_segments
from hammesh.parallel.union import min_angles_deg

__all__ = ["DecoupledMesh", "mesh_decoupled", "bad_corner_vertices", "MAX_ROUNDS"]

#: repair rounds: segments next to a triangle below the min angle are halved and the
#: tiles holding them meshed again
MAX_ROUNDS = 4

#: ``mapper(func, argument_tuples) -> results``, in order (a plain loop, or a cluster)
Mapper = Callable[[Callable, list[tuple]], list]


def _serial(func: Callable, args: list[tuple]) -> list:
    return [func(*a) for a in args]


def bad_corner_vertices(tile_vertex_ids: np.ndarray, n_input: int, mesh: Mesh, min_angle: float | None) -> np.ndarray:
    """Global ids of the tile's prescribed vertices (not the user's own) that are a
    corner of a triangle below ``min_angle``: Triangle could not fix that triangle
    without splitting a segment ``-Y`` protects."""
    if min_angle is None:
        return np.zeros(0, np.int64)
    k = len(tile_vertex_ids)
    near = mesh.triangles[(mesh.triangles < k).any(axis=1)]  # only these can have such a corner
    ang = min_angles_deg(mesh.points, near)
    bad = near[ang < float(min_angle) * (1 - 1e-9)]
    corners = np.unique(bad.ravel())
    corners = corners[corners < len(tile_vertex_ids)]
    ids = tile_vertex_ids[corners]
    return ids[ids >= n_input]


def _mesh_and_check(tile, min_angle, max_area, n_input, lattice=True):
    m = mesh_tile(tile, min_angle, max_area, lattice=lattice)
    return m, bad_corner_vertices(tile.vertex_ids, n_input, m, min_angle)


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
    results = run(_mesh_and_check, [(t, min_angle, max_area, decomp.n_input, lattice) for t in decomp.tiles])
    meshes = [r[0] for r in results]
    bad = [r[1] for r in results]
    rounds = split = 0
    while rounds < MAX_ROUNDS:
        ids = np.unique(np.concatenate(bad)) if bad else np.zeros(0, np.int64)
        if len(ids) == 0:
            break
        rows = np.flatnonzero(np.isin(decomp.segments, ids).any(axis=1))
        decomp, changed = split_segments(decomp, rows)
        split += len(rows)
        rounds += 1
        again = run(_mesh_and_check, [(decomp.tiles[i], min_angle, max_area, decomp.n_input, lattice)
                                      for i in changed])
        bad = []
        for i, (m, b) in zip(changed.tolist(), again):
            meshes[i] = m
            bad.append(b)
    return DecoupledMesh(decomposition=decomp, meshes=tuple(meshes), rounds=rounds, split=split)
