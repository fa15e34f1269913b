"""Point sets with no sequential triangulation (paper §4, Thm 4.1, Figure 13).

The nine points: a triangle ``A, B, C`` (counter-clockwise) inside a convex hexagon
``D, E, F, G, H, I`` such that ``D, E, F, I`` lie right of the oriented line ``(A, B)``,
``E, F, G, H`` right of ``(B, C)`` and ``G, H, I, D`` right of ``(C, A)``: the pairs
``E F``, ``G H``, ``I D`` sit in the wedges beyond ``B``, ``C`` and ``A``.  The exact
search (:mod:`hammesh.pointset.sequential_search`) confirms this set has no
sequential triangulation.

Only ``n = 9`` is produced.  The paper extends the set by ``n - 9`` hull points off
the arcs ``E-F``, ``G-H``, ``I-D``; with the coordinates used here every such
extension tried (one point at the middle of arc ``D-E``, ``F-G`` or ``H-I``, on the
circle or just outside the hexagon edge) *does* have a sequential triangulation
(found and certified by the search), so the extension needs conditions the text
does not state; :func:`no_sequential_example` refuses ``n > 9`` rather than return
an unverified set (see ``docs/pointset.md``).
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


def _certify(pts: np.ndarray) -> None:
    """Check the defining property of Figure 13 and the hull of the extension."""
    A, B, C, D, E, F, G, H, I = range(9)

    def right(p: int, q: int, r: int) -> bool:
        return orient(pts[p, 0], pts[p, 1], pts[q, 0], pts[q, 1], pts[r, 0], pts[r, 1]) < 0

    for (p, q), side in (((A, B), (D, E, F, I)), ((B, C), (E, F, G, H)), ((C, A), (G, H, I, D))):
        for r in side:
            if not right(p, q, r):
                raise VerificationError(f"point {LABELS[r]} is not right of line ({LABELS[p]}, {LABELS[q]})")
    hull = convex_hull(pts)
    if hull.h != len(pts) - 3 or not hull.corner.all():
        raise VerificationError("the hull must be every point but A, B, C, all strict corners")
    pos = {int(v): k for k, v in enumerate(hull.boundary)}
    h = hull.h
    for a, b in ((E, F), (G, H), (I, D)):
        if pos[b] != (pos[a] + 1) % h:
            raise VerificationError(f"hull arc {LABELS[a]}-{LABELS[b]} holds an extra point")


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
        ``n < 9`` (the theorem starts at 9) or ``n > 9`` (the extension is not
        reproduced, see the module docstring).

    Examples
    --------
    >>> no_sequential_example(9).shape
    (9, 2)
    """
    if int(n) != n or n < 9:
        raise InvalidOptionError(f"n must be an integer >= 9, got {n!r}")
    n = int(n)
    if n > 9:
        raise InvalidOptionError(
            f"n = {n}: only the 9-point set of Figure 13 is implemented; extending it by "
            "hull points as the paper describes gave sets that do have a sequential "
            "triangulation (docs/pointset.md)"
        )
    tri_ang = np.radians([210.0, 330.0, 90.0])  # A, B, C counter-clockwise
    inner = np.c_[np.cos(tri_ang), np.sin(tri_ang)]
    # D, E, F, G, H, I: pairs around the directions of A (I, D), B (E, F), C (G, H)
    a, b, c = tri_ang
    hex_ang = np.array([a + _DELTA, b - _DELTA, b + _DELTA, c + 2 * np.pi - _DELTA,
                        c + 2 * np.pi + _DELTA, a + 2 * np.pi - _DELTA])
    outer = _R * np.c_[np.cos(hex_ang), np.sin(hex_ang)]
    extra = n - 9
    # distribute the extras over the arcs D-E, F-G, H-I (open, evenly spaced)
    arcs = [(hex_ang[0], hex_ang[1]), (hex_ang[2], hex_ang[3]), (hex_ang[4], hex_ang[5])]
    more = []
    for k, (lo, hi) in enumerate(arcs):
        cnt = extra // 3 + (1 if k < extra % 3 else 0)
        if cnt:
            t = lo + (hi - lo) * np.arange(1, cnt + 1) / (cnt + 1)
            more.append(_R * np.c_[np.cos(t), np.sin(t)])
    pts = np.vstack([inner, outer, *more]) if more else np.vstack([inner, outer])
    pts = as_points(pts)
    _certify(pts)
    return pts
