"""Point sets with no sequential triangulation (paper §4, Thm 4.1, Figure 13).

The nine points: a triangle ``A, B, C`` (counter-clockwise) inside a convex hexagon
``D, E, F, G, H, I`` such that ``D, E, F, I`` lie right of the oriented line ``(A, B)``,
``E, F, G, H`` right of ``(B, C)`` and ``G, H, I, D`` right of ``(C, A)``: the pairs
``E F``, ``G H``, ``I D`` sit in the *wedges* beyond ``B``, ``C`` and ``A`` (the regions
right of both lines through that corner).  This makes every edge of ``A B C``
uncrossable, so every triangulation contains the triangle ``A B C``, which is where
the proof starts.

**Extension to n > 9.**  The paper adds ``n - 9`` points on the hull, none on the
hull arcs ``E-F``, ``G-H``, ``I-D``.  Taken literally that is not enough: a hull
point in the middle of arc ``D-E`` (right of ``(A, B)`` only) sees ``G`` and ``H``
across the edge ``A B``, ``A B C`` is no longer forced, and such sets *do* have
sequential triangulations (found by the exact search and certified by Thm 4.3; see
``docs/pointset.md``).  What the proof needs is the defining property for the new
points too: each extra point lies in one of the three wedges, i.e. on arc ``D-E``
or ``H-I`` but still right of both lines through ``A`` (and the rotated
statements for ``B``, ``C``).  Then no segment between two points crosses an edge
of ``A B C`` (a segment between two points right of ``(C, A)`` stays right of it,
and all of ``A B`` but ``A`` is left of it), and the paper's case analysis goes
through unchanged.  :func:`no_sequential_example` places the extra points that
way, round-robin over the six wedge slots beside the pairs; the exact search
confirms there is no sequential triangulation for every ``n`` from 9 to 12.

"""

from __future__ import annotations

import numpy as np

from hammesh.errors import InvalidOptionError, VerificationError
from hammesh.predicates import orient
from hammesh.pointset.validate import as_points, convex_hull

__all__ = ["no_sequential_example", "LABELS"]

#: Names of the first nine points, in output order.
LABELS = ("A", "B", "C", "D", "E", "F", "G", "H", "I")

_R = 3.0  # hull radius; the inner triangle has circumradius 1
_DELTA = np.radians(10.0)  # half-width of a wedge pair, well inside the 60-degree wedge


def _wedge_of(pts: np.ndarray, r: int) -> int | None:
    """Index 0, 1, 2 of the corner ``A, B, C`` whose wedge holds point ``r``, or ``None``."""
    A, B, C = 0, 1, 2

    def right(p: int, q: int) -> bool:
        return orient(pts[p, 0], pts[p, 1], pts[q, 0], pts[q, 1], pts[r, 0], pts[r, 1]) < 0

    for k, (l1, l2) in enumerate((((C, A), (A, B)), ((A, B), (B, C)), ((B, C), (C, A)))):
        if right(*l1) and right(*l2):
            return k
    return None


def _general_position(pts: np.ndarray) -> None:
    """No three points collinear.

    Hull triples are excluded by the hull check (all strict corners); for triples
    through ``A``, ``B`` or ``C`` the other points are sorted by direction modulo pi
    and neighbours are tested exactly.
    """
    for p in range(3):
        d = np.delete(np.arange(len(pts)), p)
        ang = np.mod(np.arctan2(pts[d, 1] - pts[p, 1], pts[d, 0] - pts[p, 0]), np.pi)
        srt = d[np.argsort(ang)]
        for u, v in zip(srt, np.roll(srt, -1)):
            if orient(pts[p, 0], pts[p, 1], pts[u, 0], pts[u, 1], pts[v, 0], pts[v, 1]) == 0:
                raise VerificationError(f"points {p}, {u}, {v} are collinear")


def _certify(pts: np.ndarray) -> None:
    """Check the defining property of Figure 13, for the extra points too, and the hull."""
    A, B, C, D, E, F, G, H, I = range(9)

    def right(p: int, q: int, r: int) -> bool:
        return orient(pts[p, 0], pts[p, 1], pts[q, 0], pts[q, 1], pts[r, 0], pts[r, 1]) < 0

    for (p, q), side in (((A, B), (D, E, F, I)), ((B, C), (E, F, G, H)), ((C, A), (G, H, I, D))):
        for r in side:
            if not right(p, q, r):
                raise VerificationError(f"point {LABELS[r]} is not right of line ({LABELS[p]}, {LABELS[q]})")
    for r in range(9, len(pts)):
        if _wedge_of(pts, r) is None:
            raise VerificationError(f"extra point {r} is in no wedge beyond A, B or C")
    hull = convex_hull(pts)
    if hull.h != len(pts) - 3 or not hull.corner.all():
        raise VerificationError("the hull must be every point but A, B, C, all strict corners")
    pos = {int(v): k for k, v in enumerate(hull.boundary)}
    h = hull.h
    for a, b in ((E, F), (G, H), (I, D)):
        if pos[b] != (pos[a] + 1) % h:
            raise VerificationError(f"hull arc {LABELS[a]}-{LABELS[b]} holds an extra point")
    _general_position(pts)


def _wedge_arc(corner: np.ndarray, other1: np.ndarray, other2: np.ndarray) -> tuple[float, float]:
    """Angles (on the hull circle) where the lines from ``other1``/``other2`` through
    ``corner`` leave the circle beyond ``corner``: the wedge's arc, increasing."""
    out = []
    for o in (other1, other2):
        d = corner - o
        d = d / np.hypot(*d)
        # corner + s d on the circle of radius _R, s > 0
        bq = float(corner @ d)
        s = -bq + np.sqrt(bq * bq - (float(corner @ corner) - _R * _R))
        x = corner + s * d
        out.append(float(np.arctan2(x[1], x[0])))
    lo, hi = sorted(out)
    if hi - lo > np.pi:  # the arc wraps through angle pi
        lo, hi = hi, lo + 2 * np.pi
    return lo, hi


def no_sequential_example(n: int) -> np.ndarray:
    """``n`` points in general position with no sequential triangulation (Thm 4.1).

    Parameters
    ----------
    n : int
        At least 9.

    Returns
    -------
    (n, 2) float64
        Rows ``A, B, C, D, ..., I`` (:data:`LABELS`) then the extra hull points; the
        defining property of Figure 13 is checked before returning.

    Raises
    ------
    InvalidOptionError
        ``n`` is not an integer ``>= 9`` (the theorem starts at 9).

    Examples
    --------
    >>> no_sequential_example(9).shape
    (9, 2)
    >>> no_sequential_example(40).shape
    (40, 2)
    """
    if int(n) != n or n < 9:
        raise InvalidOptionError(f"n must be an integer >= 9, got {n!r}")
    n = int(n)
    tri_ang = np.radians([210.0, 330.0, 90.0])  # A, B, C counter-clockwise
    inner = np.c_[np.cos(tri_ang), np.sin(tri_ang)]
    # D, E, F, G, H, I: pairs around the directions of A (I, D), B (E, F), C (G, H)
    a, b, c = tri_ang
    hex_ang = np.array([a + _DELTA, b - _DELTA, b + _DELTA, c + 2 * np.pi - _DELTA,
                        c + 2 * np.pi + _DELTA, a + 2 * np.pi - _DELTA])
    outer = _R * np.c_[np.cos(hex_ang), np.sin(hex_ang)]
    extra = n - 9
    # six slots, two per wedge, beside the pairs and away from the hull arcs between
    # them: after D and before I (A's wedge), after F and before E (B's), after H and
    # before G (C's); each slot is the part of the wedge's arc outside its pair,
    # shrunk by a margin so the points stay strictly inside the wedge
    slots = []
    for k in range(3):  # A (pair I, D), B (E, F), C (G, H)
        lo, hi = _wedge_arc(inner[k], inner[(k + 1) % 3], inner[(k + 2) % 3])
        mid = tri_ang[k]
        turn = 2 * np.pi * np.round((mid - (lo + hi) / 2) / (2 * np.pi))
        lo, hi = lo + turn, hi + turn
        if not lo < mid - _DELTA < mid + _DELTA < hi:
            raise VerificationError("the pairs must lie inside their wedges")
        slots.append((mid + _DELTA, hi - 0.1 * (hi - mid - _DELTA)))  # after D, F, H
        slots.append((lo + 0.1 * (mid - _DELTA - lo), mid - _DELTA))  # before I, E, G
    counts = [extra // 6 + (1 if s < extra % 6 else 0) for s in range(6)]
    more = []
    for (lo, hi), cnt in zip(slots, counts):
        if cnt:
            t = lo + (hi - lo) * np.arange(1, cnt + 1) / (cnt + 1)
            more.append(_R * np.c_[np.cos(t), np.sin(t)])
    pts = np.vstack([inner, outer, *more])
    pts = as_points(pts)
    _certify(pts)
    return pts
