"""Certificate of a triangulation of a polygon (with holes, with Steiner points) and its order.

:func:`verify_polygon_triangulation` checks, raising :class:`VerificationError`
naming the triangle, edge or point at fault:

1. shapes, indices in range; the output points start with the rings' points,
   bit for bit (outer ring, then each hole); every output point is a vertex;
2. every triangle is counter-clockwise by the exact orientation predicate;
3. edge-manifold: no directed edge is used twice (the certificate's own pairing,
   ``hammesh.verify._kernels.half_edge_twins``);
4. the unpaired half-edges are exactly the ring edges, directed with the domain on
   their left (outer ring counter-clockwise, holes clockwise; each ring's orientation
   found exactly at its lowest-leftmost vertex), and the triangle areas sum to the
   domain's area (relative tolerance :data:`AREA_RTOL`);
5. the order: ``"cycle"``: consecutive rows share an edge and so do the last and
   first; ``"path"``: consecutive rows share an edge (one triangle is both).

Items 2-4 prove the triangles tile the domain without overlap (the argument of
:mod:`hammesh.verify.certificate`). The code shared with the polygon constructions is
``hammesh.predicates`` and numpy only.
"""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from hammesh.errors import VerificationError
from hammesh.predicates import orient
from hammesh.verify.tiling import triangulation_boundary_keys

__all__ = ["verify_polygon_triangulation", "AREA_RTOL", "ORDERS"]

AREA_RTOL = 1e-9
#: Accepted values of ``order``.
ORDERS = ("cycle", "path", None)


def _fail(msg: str) -> None:
    raise VerificationError(msg)


def _ccw_ring(ring: np.ndarray) -> bool:
    """Exact orientation of a simple ring: the turn at its lowest-leftmost vertex."""
    i = int(np.lexsort((ring[:, 1], ring[:, 0]))[0])
    p, q, r = ring[i - 1], ring[i], ring[(i + 1) % len(ring)]
    return orient(p[0], p[1], q[0], q[1], r[0], r[1]) > 0


def verify_polygon_triangulation(
    rings: Sequence[np.ndarray], points: np.ndarray, triangles: np.ndarray, order: str | None = None
) -> dict[str, Any]:
    """Check that ``triangles`` over ``points`` triangulate the polygon ``rings`` in ``order``.

    Parameters
    ----------
    rings : sequence of (n_i, 2) float64
        The outer ring first, then the holes; either orientation.
    points : (N, 2) float64
        The rings' points concatenated, then any Steiner points.
    triangles : (m, 3) int64
    order : {"cycle", "path", None}

    Returns
    -------
    dict
        ``n_triangles``, ``n_steiner`` and ``area``.

    Raises
    ------
    VerificationError
    """
    if order not in ORDERS:
        raise ValueError(f"order must be one of {ORDERS}, got {order!r}")
    rs = [np.asarray(r, dtype=np.float64) for r in rings]
    pts = np.ascontiguousarray(points, dtype=np.float64)
    tri = np.asarray(triangles)
    if pts.ndim != 2 or pts.shape[1] != 2 or tri.ndim != 2 or tri.shape[1] != 3 or len(tri) == 0:
        _fail(f"bad shapes: points {pts.shape}, triangles {tri.shape}")
    if not np.issubdtype(tri.dtype, np.integer):
        _fail(f"triangles must be integers, got {tri.dtype}")
    tri = np.ascontiguousarray(tri, dtype=np.int64)
    n, m = len(pts), len(tri)
    flat = np.concatenate(rs) if rs else np.zeros((0, 2))
    if n < len(flat) or not np.array_equal(pts[: len(flat)], flat):
        _fail("the output points do not start with the polygon's points, unchanged")
    if tri.min() < 0 or tri.max() >= n:
        t = int(np.argmax(((tri < 0) | (tri >= n)).any(axis=1)))
        _fail(f"triangle {t} {tri[t].tolist()} references a point outside 0..{n - 1}")
    got = triangulation_boundary_keys(pts, tri)  # all used, positive, edge-manifold
    want, area, off = [], 0.0, 0
    for j, r in enumerate(rs):
        idx = off + np.arange(len(r), dtype=np.int64)
        off += len(r)
        if _ccw_ring(r) != (j == 0):  # the domain on the left: outer CCW, holes CW
            idx = idx[::-1]
        want.append(idx * n + np.roll(idx, -1))
        x, y = pts[idx, 0], pts[idx, 1]
        area += 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))
    want = np.sort(np.concatenate(want)) if want else np.zeros(0, np.int64)
    if not np.array_equal(got, want):
        k = int(np.setxor1d(got, want)[0])
        _fail(f"edge ({k // n}, {k % n}) is on the boundary of only one of the triangulation and the polygon")
    a, b, c = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    total = 0.5 * math.fsum((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))
    if not math.isclose(total, area, rel_tol=AREA_RTOL, abs_tol=0.0):
        _fail(f"triangle areas sum to {total!r}, the polygon's area is {area!r}")
    if order is not None and m > 1:
        nxt = np.roll(tri, -1, axis=0) if order == "cycle" else tri[1:]
        common = (tri[: len(nxt), :, None] == nxt[:, None, :]).sum(axis=(1, 2))
        if (common != 2).any():
            t = int(np.argmax(common != 2))
            _fail(f"the {order} breaks at triangle {t}: it shares no edge with triangle {(t + 1) % m}")
    return {"n_triangles": m, "n_steiner": n - len(flat), "area": total}
