"""Certificate of a triangulation of a point set and of its triangle order.

:func:`verify_point_triangulation` checks, raising :class:`VerificationError` that
names the triangle, edge or point at fault:

1. shapes, indices in range, ``2 n - h - 2`` triangles (``h`` points on the hull
   boundary, collinear ones included);
2. every point is a vertex;
3. every triangle is counter-clockwise with positive area (exact orientation test);
4. edge-manifold: no directed edge is used twice;
5. the unpaired edges are exactly the hull boundary edges, counter-clockwise, and the
   triangle areas sum to the hull area (relative tolerance :data:`AREA_RTOL`);
6. the order: ``"cycle"``: consecutive rows share an edge and so do the last and
   first; ``"path"``: consecutive rows share an edge.  (Not via
   :func:`hammesh.verify.certificate.verify_cycle_mesh`: its floating-point area test
   rejects nearly-flat triangles of nearly-collinear points that items 3-5 accept
   exactly.)

Items 3-5 prove the triangles tile the convex hull without overlap (positive
triangles glued along a pairing of their half-edges whose free boundary is the hull
boundary cover each point of the hull exactly once, see
:mod:`hammesh.verify.certificate`), and with 1-2 the triangulation of the point set.

Shared with the point-set constructions: ``hammesh.predicates`` and numpy only. The
hull is the certificate's own (``hammesh.verify._kernels.hull_chain``, a monotone
chain with the exact predicate), not the constructions' ``pointset.convex_hull``;
the pairing is the certificate's own bucket matching.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from hammesh.errors import VerificationError
from hammesh.verify import hull_chain
from hammesh.verify.tiling import triangulation_boundary_keys

__all__ = ["verify_point_triangulation", "AREA_RTOL", "ORDERS"]

AREA_RTOL = 1e-9
#: Accepted values of ``order``.
ORDERS = ("cycle", "path", None)


def _fail(msg: str) -> None:
    raise VerificationError(msg)


def verify_point_triangulation(
    points: np.ndarray, triangles: np.ndarray, order: str | None = "cycle"
) -> dict[str, Any]:
    """Check that ``triangles`` triangulate ``points`` and, in row order, form ``order``.

    Parameters
    ----------
    points : (n, 2) float64
        Distinct points (as checked by :func:`hammesh.pointset.validate.as_points`).
    triangles : (m, 3) int64
    order : {"cycle", "path", None}
        What consecutive rows must form; ``None`` checks the triangulation only.

    Returns
    -------
    dict
        ``n_points``, ``n_triangles``, ``hull_points`` and ``area``.

    Raises
    ------
    VerificationError
    """
    if order not in ORDERS:
        raise ValueError(f"order must be one of {ORDERS}, got {order!r}")
    pts = np.ascontiguousarray(points, dtype=np.float64)
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    if pts.ndim != 2 or pts.shape[1] != 2 or tri.ndim != 2 or tri.shape[1] != 3:
        _fail(f"bad shapes: points {pts.shape}, triangles {tri.shape}")
    n, m = len(pts), len(tri)
    if m == 0:
        _fail("there are no triangles")
    if tri.min() < 0 or tri.max() >= n:
        t = int(np.argmax(((tri < 0) | (tri >= n)).any(axis=1)))
        _fail(f"triangle {t} {tri[t].tolist()} references a point outside 0..{n - 1}")
    if not np.isfinite(pts).all():
        _fail(f"point {int(np.argmin(np.isfinite(pts).all(axis=1)))} is not finite")
    if len(np.unique(pts, axis=0)) < n:
        _fail("the points are not distinct")
    hull_b = hull_chain(pts, np.lexsort((pts[:, 1], pts[:, 0])).astype(np.int64))
    h = len(hull_b)
    if len(np.unique(hull_b)) != h:  # the chain runs back over itself
        _fail("the points are all collinear: there is no triangulation")
    if m != 2 * n - h - 2:
        _fail(f"{m} triangles, but a triangulation of {n} points with {h} on the hull has {2 * n - h - 2}")
    got = triangulation_boundary_keys(pts, tri)  # all used, positive, edge-manifold
    b = hull_b
    want = np.sort(b.astype(np.int64) * n + np.roll(b, -1))
    if not np.array_equal(got, want):
        k = int(np.setxor1d(got, want)[0])
        _fail(f"edge ({k // n}, {k % n}) is on the boundary of only one of the triangulation and the hull")
    # (about the first hull point: the shoelace of absolute coordinates cancels to
    # rounding noise when the hull is tiny against its distance from the origin)
    origin = pts[b[0]]
    x, y = pts[b, 0] - origin[0], pts[b, 1] - origin[1]
    hull_area = 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))
    extent = float(np.max(np.abs(pts - origin))) if len(pts) else 0.0
    rounding = 16.0 * np.finfo(float).eps * extent * extent * (len(b) + len(tri))
    a, bb, c = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    area = 0.5 * float(np.sum((bb[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (bb[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])))
    if not math.isclose(area, hull_area, rel_tol=AREA_RTOL, abs_tol=rounding):
        _fail(f"triangle areas sum to {area!r}, the hull's area is {hull_area!r}")
    if order is not None:
        if order == "cycle" and m < 3:
            _fail(f"{m} triangles cannot form a cycle")
        # every row is a distinct positive triangle of an edge-manifold triangulation
        # (checked exactly above), so two rows sharing two vertices share an edge; the
        # floating-point area test of verify_cycle_mesh is not used: it rejects
        # nearly-flat triangles of nearly-collinear points that are positive exactly
        nxt = np.roll(tri, -1, axis=0) if order == "cycle" else tri[1:]
        common = (tri[: len(nxt), :, None] == nxt[:, None, :]).sum(axis=(1, 2))
        if (common != 2).any():
            t = int(np.argmax(common != 2))
            what = "cycle" if order == "cycle" else "path"
            _fail(f"the {what} breaks at triangle {t}: it shares no edge with triangle {(t + 1) % m}")
    return {"n_points": n, "n_triangles": m, "hull_points": h, "area": area}
