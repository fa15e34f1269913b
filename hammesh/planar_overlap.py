"""Do two triangles of a planar mesh overlap?  (What ``hammesh check`` needs without the input.)

The certificate of :mod:`hammesh.verify.certificate` proves that an output tiles its
*input* domain; a file checked on its own has no input to compare with, and two
counter-clockwise triangles that share no edge (two pieces, each a cycle) can lie on
top of each other.  :func:`find_overlap` settles it exactly:

* candidate pairs: triangles whose bounding boxes overlap with positive area, found in
  a uniform grid of about one triangle per cell (pairs sharing a cell, deduplicated);
  pairs sharing an edge are skipped (counter-clockwise triangles with a consistently
  oriented shared edge lie on its two sides: the certificate checks both facts);
* the test: two counter-clockwise triangles have disjoint interiors iff some edge line
  of one has the other's three vertices on its right or on it (the separating axis
  theorem for convex polygons: a separating line can be taken along an edge), decided
  exactly: floating point where Shewchuk's error bound decides the sign, else the exact
  predicate :func:`hammesh.predicates.orient_many`.

Triangles that share a vertex and lie side by side are separated by an edge line;
identical triangles stored twice (under other vertex numbers) are not.
"""

from __future__ import annotations

import numpy as np

from hammesh.predicates import orient_many

__all__ = ["find_overlap"]

#: pairs tested per batch
_BATCH = 200_000
#: grid cells per triangle at most, so a long sliver cannot blow up the grid
_MAX_CELLS = 64
#: Shewchuk's ccwerrboundA: a float orientation beyond it has the exact sign
_ERRBOUND = (3.0 + 16.0 * np.finfo(float).eps) * np.finfo(float).eps / 2


def _cells(lo: np.ndarray, hi: np.ndarray, origin: np.ndarray, cell: float):
    i0 = np.floor((lo - origin) / cell).astype(np.int64)
    i1 = np.floor((hi - origin) / cell).astype(np.int64)
    span = i1 - i0 + 1
    return i0, i1, span, span[:, 0] * span[:, 1]


def _candidate_pairs(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    m = len(lo)
    origin = lo.min(axis=0)
    extent = hi.max(axis=0) - origin
    area = float(extent[0] * extent[1])
    cell = max(np.sqrt(area / m) * 2.0 if area > 0 else float(extent.max()), np.finfo(float).tiny)
    i0, i1, span, count = _cells(lo, hi, origin, cell)
    while count.max() > _MAX_CELLS:  # coarser grid: a few huge triangles
        cell *= 2.0
        i0, i1, span, count = _cells(lo, hi, origin, cell)
    tri = np.repeat(np.arange(m, dtype=np.int64), count)
    k = np.arange(len(tri)) - np.repeat(np.cumsum(count) - count, count)
    w = np.repeat(span[:, 0], count)
    cx = np.repeat(i0[:, 0], count) + k % w
    cy = np.repeat(i0[:, 1], count) + k // w
    key = cx * (int(i1[:, 1].max()) + 2) + cy
    order = np.argsort(key, kind="stable")
    key, tri = key[order], tri[order]
    pairs = []
    idx = np.arange(len(key))
    d = 1
    while len(idx):  # entries d apart in one cell; cells empty out as d grows
        j = idx + d
        ok = j < len(key)
        idx, j = idx[ok], j[ok]
        same = key[idx] == key[j]
        idx, j = idx[same], j[same]
        if len(idx):
            pairs.append(np.stack([tri[idx], tri[j]], axis=1))
        d += 1
    if not pairs:
        return np.zeros((0, 2), np.int64)
    p = np.sort(np.concatenate(pairs), axis=1)
    p = p[p[:, 0] != p[:, 1]]
    flat = np.sort(p[:, 0] * m + p[:, 1])  # sort + neighbour test: numpy's hashing unique is slow here
    flat = flat[np.concatenate([[True], flat[1:] != flat[:-1]])]
    p = np.stack([flat // m, flat % m], axis=1)
    a, b = p[:, 0], p[:, 1]  # bounding boxes that only touch: interiors disjoint
    keep = (np.minimum(hi[a], hi[b]) > np.maximum(lo[a], lo[b])).all(axis=1)
    return p[keep]


def _signs(pts: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Exact orientation signs of rows ``(a, b, c)``: floating point where its error bound
    decides (Shewchuk's filter), the exact predicate for the rest."""
    pa, pb, pc = pts[a], pts[b], pts[c]
    left = (pa[:, 0] - pc[:, 0]) * (pb[:, 1] - pc[:, 1])
    right = (pa[:, 1] - pc[:, 1]) * (pb[:, 0] - pc[:, 0])
    det = left - right
    sign = np.sign(det).astype(np.int8)
    unsure = np.abs(det) <= _ERRBOUND * (np.abs(left) + np.abs(right))
    unsure &= (a != c) & (b != c)  # a repeated vertex: exactly zero already
    if unsure.any():
        rows = np.stack([a[unsure], b[unsure], c[unsure]], axis=1)
        sign[unsure] = orient_many(pts, rows)
    return sign


def find_overlap(points: np.ndarray, triangles: np.ndarray) -> tuple[int, int] | None:
    """The first pair of triangles whose interiors intersect, or None.

    Parameters
    ----------
    points : (n, 2) float64
    triangles : (m, 3) int64
        Counter-clockwise, each directed edge used once (the certificate's items 2-3).

    Examples
    --------
    >>> pts = np.array([[0., 0.], [2., 0.], [0., 2.], [0.5, 0.5], [3., 0.5], [0.5, 3.]])
    >>> find_overlap(pts, np.array([[0, 1, 2], [3, 4, 5]]))
    (0, 1)
    >>> find_overlap(pts, np.array([[0, 1, 2], [1, 4, 5]])) is None
    True
    """
    pts = np.ascontiguousarray(points, dtype=np.float64)
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    if len(tri) < 2:
        return None
    corners = pts[tri]
    pairs = _candidate_pairs(corners.min(axis=1), corners.max(axis=1))
    if len(pairs):
        shared = (tri[pairs[:, 0]][:, :, None] == tri[pairs[:, 1]][:, None, :]).sum(axis=(1, 2))
        pairs = pairs[shared < 2]
    for start in range(0, len(pairs), _BATCH):
        p = pairs[start:start + _BATCH]
        ta, tb = tri[p[:, 0]], tri[p[:, 1]]
        separated = np.zeros(len(p), dtype=bool)
        for own, other in ((ta, tb), (tb, ta)):
            for e in range(3):
                a, b = own[:, e], own[:, (e + 1) % 3]
                right = np.ones(len(p), dtype=bool)
                for v in range(3):
                    right &= _signs(pts, a, b, other[:, v]) <= 0
                separated |= right
        bad = np.flatnonzero(~separated)
        if len(bad):
            i, j = (int(x) for x in p[bad[0]])
            return (i, j)
    return None
