"""Validation and triangulation of a polygon with polygonal holes.

Used by :mod:`~hammesh.polygon.steiner` (``holes=``) and
:mod:`~hammesh.polygon.hamiltonian_holes`.  Internally the vertices are the outer ring
counter-clockwise followed by every hole clockwise (so the domain is on the left of
every directed boundary edge); ``order`` maps them to the caller's numbering, which is
the outer ring's points followed by each hole's points, in the order given.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from hammesh.domain.validate import validate_domain
from hammesh.errors import InvalidDomainError, MeshingError
from hammesh.polygon._polygon import edge_wording, as_polygon
from hammesh.polygon._triangulate import triangulate_polygon
from hammesh.predicates import orient_rows

__all__ = ["Domain", "as_domain", "triangulate_domain", "point_in_ring"]


@dataclass(frozen=True, eq=False)
class Domain:
    """A validated polygon with holes.

    Attributes
    ----------
    points : (N, 2) float64
        Outer ring counter-clockwise, then each hole clockwise.
    order : (N,) int64
        ``points[k]`` is the caller's vertex ``order[k]`` (outer points, then holes).
    nxt : (N,) int64
        The next vertex along the boundary (domain on the left).
    hole_points : (h, 2) float64
        One point strictly inside each hole.
    area : float
        Outer area minus the holes' areas.
    """

    points: np.ndarray
    order: np.ndarray
    nxt: np.ndarray
    hole_points: np.ndarray
    area: float

    @property
    def n(self) -> int:
        return int(self.points.shape[0])

    def boundary_edges(self) -> np.ndarray:
        """``(N, 2) int64`` directed boundary edges ``(v, nxt[v])``."""
        return np.stack([np.arange(self.n), self.nxt], axis=1)


def point_in_ring(p, ring: np.ndarray) -> bool:
    """Even-odd test of a point strictly off the ring's edges."""
    x, y = p
    xs, ys = ring[:, 0], ring[:, 1]
    xn, yn = np.roll(xs, -1), np.roll(ys, -1)
    crosses = (ys > y) != (yn > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xi = xs + (y - ys) * (xn - xs) / (yn - ys)
    return bool(np.count_nonzero(crosses & (x < xi)) % 2)


def as_domain(points, holes) -> Domain:
    """Validate a polygon with holes.

    Parameters
    ----------
    points : (n, 2) array_like of float
        The outer ring, either orientation.
    holes : sequence of (n_i, 2) array_like of float
        The hole rings, either orientation.

    Raises
    ------
    InvalidDomainError
        A ring is not a simple polygon, rings cross or touch, a hole is not inside the
        outer ring or is inside another hole.
    """
    outer = as_polygon(points)
    rings = [outer]
    for h, ring in enumerate(holes):
        try:
            rings.append(as_polygon(ring))
        except InvalidDomainError as exc:
            raise InvalidDomainError(f"hole {h}: {exc}") from None
    sizes = [r.n for r in rings]
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    pts, order, nxt = [], [], []
    for r, ring in enumerate(rings):
        o = np.arange(ring.n) if r == 0 else np.arange(ring.n)[::-1]  # holes clockwise
        pts.append(ring.points[o])
        order.append(offsets[r] + ring.order[o])
        nxt.append(offsets[r] + (np.arange(ring.n) + 1) % ring.n)
    P = np.ascontiguousarray(np.vstack(pts))
    segs = np.stack([np.arange(len(P)), np.concatenate(nxt)], axis=1)
    dom = SimpleNamespace(
        vertices=P, segments=segs, holes=np.zeros((0, 2)), regions=np.zeros((0, 4)),
        segment_markers=np.zeros(len(segs), np.int64), vertex_markers=np.zeros(len(P), np.int64))
    try:
        validate_domain(dom)
    except InvalidDomainError as exc:
        raise InvalidDomainError(f"rings of the polygon with holes cross or touch: "
                                 f"{edge_wording(str(exc))}") from None
    hole_points = []
    for h, ring in enumerate(rings[1:]):
        if not point_in_ring(ring.points[0], outer.points):
            raise InvalidDomainError(f"hole {h} is not inside the outer ring")
        for g, other in enumerate(rings[1:]):
            if g != h and point_in_ring(ring.points[0], other.points):
                raise InvalidDomainError(f"hole {h} is inside hole {g}")
        t = triangulate_polygon(ring.points)[0]
        hole_points.append(ring.points[t].mean(axis=0))
    area = outer.area - sum(r.area for r in rings[1:])
    return Domain(points=P, order=np.concatenate(order).astype(np.int64),
                  nxt=np.concatenate(nxt).astype(np.int64),
                  hole_points=np.array(hole_points).reshape(-1, 2), area=area)


def triangulate_domain(dom: Domain) -> np.ndarray:
    """Triangulate the domain without Steiner points: ``(N + 2h - 2, 3) int64``, CCW."""
    import triangle

    N = dom.n
    h = len(dom.hole_points)
    args = {"vertices": dom.points, "segments": dom.boundary_edges()}
    if h:
        args["holes"] = dom.hole_points
    out = triangle.triangulate(args, "pQ")
    tri = np.asarray(out.get("triangles", np.zeros((0, 3))), dtype=np.int64)
    if len(out["vertices"]) != N or len(tri) != N + 2 * h - 2:
        raise MeshingError(f"Triangle returned {len(out['vertices'])} vertices and {len(tri)} "
                           f"triangles for {N} vertices and {h} holes")
    P = dom.points
    s = orient_rows(P[tri[:, 0]], P[tri[:, 1]], P[tri[:, 2]])
    tri[s < 0] = tri[s < 0][:, ::-1]
    if np.any(s == 0):
        raise MeshingError("Triangle returned a degenerate triangle")
    return tri
