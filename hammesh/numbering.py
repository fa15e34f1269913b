"""Vertex numberings for FEM codes: along the cycle, reverse Cuthill-McKee, Hilbert (issue 14).

A finite element matrix couples the vertices of each edge; its bandwidth (largest
``|i - j|`` over the edges) and profile (sum over rows of the distance from the
diagonal to the row's first coupled column) depend only on the vertex numbering.
hammesh's output numbers the input points first and the Steiner points after, which
is neither; :func:`renumber` gives one of:

* ``"cycle"``: vertices in the order the cycle first reaches them (rows in cycle
  order, corners in row order): follows the compact cycle, stretch by stretch;
* ``"rcm"``: reverse Cuthill-McKee of the vertex graph
  (``scipy.sparse.csgraph.reverse_cuthill_mckee``), the classic small-profile order;
* ``"hilbert"``: vertices along a Hilbert curve through their coordinates (16 bits
  per axis), a cache-friendly order for assembly and matrix-free codes.

Triangles keep their rows (the cycle order); only vertex indices change.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any

import numpy as np

from hammesh import params
from hammesh.mesh import HamiltonianMesh, Mesh

__all__ = ["NUMBERINGS", "renumber", "vertex_order", "bandwidth_profile", "hilbert_keys"]

#: The numberings :func:`renumber` knows.
NUMBERINGS = ("cycle", "rcm", "hilbert")


def hilbert_keys(points: np.ndarray, bits: int = 16) -> np.ndarray:
    """Position of each point along a Hilbert curve through its bounding square.

    The classic bit-by-bit rotation (``xy2d``), vectorized over the points; ``bits``
    per axis, so keys are below ``4 ** bits``.
    """
    p = np.asarray(points, dtype=np.float64)[:, :2]
    if len(p) == 0:
        return np.zeros(0, np.int64)
    lo = p.min(axis=0)
    span = float((p.max(axis=0) - lo).max()) or 1.0
    side = 1 << bits
    q = np.minimum(((p - lo) / span * side).astype(np.int64), side - 1)
    x, y = q[:, 0].copy(), q[:, 1].copy()
    d = np.zeros(len(p), np.int64)
    s = side >> 1
    while s > 0:
        rx = (x & s) > 0
        ry = (y & s) > 0
        d += s * s * ((3 * rx.astype(np.int64)) ^ ry.astype(np.int64))
        # rotate the quadrant so the curve's sub-square is in standard position
        flip = ~ry & rx
        x = np.where(flip, side - 1 - x, x)
        y = np.where(flip, side - 1 - y, y)
        swap = ~ry
        x, y = np.where(swap, y, x), np.where(swap, x, y)
        s >>= 1
    return d


def _edges(triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    tri = np.asarray(triangles, dtype=np.int64)
    u = tri.reshape(-1)
    v = tri[:, [1, 2, 0]].reshape(-1)
    return u, v


def bandwidth_profile(triangles: np.ndarray, n_points: int) -> tuple[int, int]:
    """Bandwidth and profile of the vertex matrix of ``triangles``.

    Bandwidth: largest ``|i - j|`` over the edges. Profile (envelope size): the sum
    over vertices ``i`` of ``i - min(i, neighbours of i)``.
    """
    u, v = _edges(triangles)
    if len(u) == 0:
        return 0, 0
    bw = int(np.abs(u - v).max())
    first = np.arange(n_points, dtype=np.int64)
    a = np.concatenate([u, v])
    b = np.concatenate([v, u])
    np.minimum.at(first, a, b)
    return bw, int((np.arange(n_points) - first).sum())


def vertex_order(mesh: Mesh | HamiltonianMesh, method: str) -> np.ndarray:
    """The new order of the vertices: new vertex ``i`` is old vertex ``order[i]``.

    Vertices no triangle uses come last, in their old order.
    """
    params.choice("renumber", method, NUMBERINGS)
    n = len(mesh.points)
    tri = np.asarray(mesh.triangles, dtype=np.int64)
    if method == "cycle":
        flat = tri.reshape(-1)
        first = np.full(n, len(flat), np.int64)
        np.minimum.at(first, flat, np.arange(len(flat)))
        return np.argsort(first, kind="stable")
    if method == "hilbert":
        return np.argsort(hilbert_keys(mesh.points), kind="stable")
    # (imported here: ``hammesh mesh`` imports this module to build its options, and
    # scipy.sparse costs ~0.3-0.6 s of every command's start; only "rcm" needs it)
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import reverse_cuthill_mckee

    u, v = _edges(tri)
    graph = coo_matrix((np.ones(len(u), np.int8), (u, v)), shape=(n, n)).tocsr()
    graph = (graph + graph.T).tocsr()
    return np.asarray(reverse_cuthill_mckee(graph, symmetric_mode=True), dtype=np.int64)


def _renumbered(mesh: Any, order: np.ndarray) -> Any:
    """``mesh`` with vertex ``order[i]`` renamed ``i`` (every per-vertex field moved)."""
    n = len(mesh.points)
    new_of = np.empty(n, np.int64)
    new_of[order] = np.arange(n, dtype=np.int64)
    changes: dict[str, Any] = {
        "points": np.asarray(mesh.points)[order],
        "triangles": new_of[np.asarray(mesh.triangles, dtype=np.int64)],
        "segments": new_of[np.asarray(mesh.segments, dtype=np.int64)].reshape(-1, 2),
    }
    for f in dataclasses.fields(mesh):  # e.g. vertex markers: per-vertex arrays move too
        value = getattr(mesh, f.name)
        if f.name.startswith("vertex_") and isinstance(value, np.ndarray) and len(value) == n:
            changes[f.name] = value[order]
    if getattr(mesh, "point_data", None):  # the input's per-point values move with the points
        changes["point_data"] = {k: np.asarray(v)[order] for k, v in mesh.point_data.items()}
    if isinstance(mesh, Mesh):
        changes["neighbors"] = mesh.neighbors  # rows keep their order
    return dataclasses.replace(mesh, **changes)


def renumber(mesh: Mesh | HamiltonianMesh, method: str = "rcm") -> tuple[Mesh | HamiltonianMesh, dict[str, Any]]:
    """Renumber the vertices of ``mesh`` (``method`` one of :data:`NUMBERINGS`).

    Returns
    -------
    mesh : same type
        Points reordered, triangles and segments mapped, rows (the cycle) unchanged.
        A HamiltonianMesh's report gains ``"numbering"``.
    numbering : dict
        ``method``, ``bandwidth``/``profile`` before and after, ``order`` (new vertex
        ``i`` is old vertex ``order[i]``, an array) and seconds.

    Raises
    ------
    InvalidOptionError
        Unknown method.
    """
    params.instance("mesh", mesh, (Mesh, HamiltonianMesh), "a hammesh.Mesh or HamiltonianMesh")
    params.choice("renumber", method, NUMBERINGS)
    t0 = time.perf_counter()
    order = vertex_order(mesh, method)
    out = _renumbered(mesh, order)
    t1 = time.perf_counter()
    bw0, pf0 = bandwidth_profile(mesh.triangles, len(mesh.points))
    bw1, pf1 = bandwidth_profile(out.triangles, len(out.points))
    info = {
        "method": method,
        "bandwidth_before": bw0,
        "profile_before": pf0,
        "bandwidth": bw1,
        "profile": pf1,
        "seconds": t1 - t0,
    }
    if isinstance(out, HamiltonianMesh):
        out = dataclasses.replace(out, report={**out.report, "numbering": info})
    return out, {**info, "order": order}
