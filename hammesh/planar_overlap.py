"""Do two triangles of a planar mesh overlap?  (What ``hammesh check`` needs without the input.)

The certificate of :mod:`hammesh.verify.certificate` proves that an output tiles its
*input* domain; a file checked on its own has no input to compare with, and two
counter-clockwise triangles that share no edge (two pieces, each a cycle) can lie on
top of each other.  :func:`find_overlap` settles it exactly, in compiled kernels.

**Only triangles with a boundary edge need partners.** For counter-clockwise
triangles, each directed edge used once (the certificate's items 2-3), the number of
triangles covering a point ``p`` is the winding number around ``p`` of the sum of the
triangles' edge chains, in which an edge and its reverse cancel: of the *boundary*
chain (the half-edges without twin). So the covering number changes only across
boundary edges, and if it is 2 or more somewhere, then at a boundary edge ``e`` on the
border of that region some side with covering number >= 2 is the side of a triangle
owning a boundary edge there (if the region lies on the other side of every boundary
edge through a point, the covering number there rises across them): that triangle's
interior meets another triangle's. Conversely such a pair is an overlap. So it is
enough to test the triangles owning a boundary half-edge (few: the mesh's border)
against all triangles.

* candidate pairs: a triangle against the boundary triangles whose bounding boxes
  overlap its own with positive area, found in a *hierarchical uniform grid* (a
  "loose" grid per level, as in collision detection: Ericson, *Real-Time Collision
  Detection*, 7.2) of the boundary triangles: one whose box is at most ``c0 2**L``
  wide and high is entered at every level ``>= L`` into the (at most 2 x 2) cells of
  side ``c0 2**L'`` its box meets. A triangle of level ``l`` looks in the cells its box
  meets at levels ``>= l``; a pair is tested at level ``max(l, L)`` only, in the one
  cell holding the lower-left corner of the boxes' intersection (once per pair,
  whatever the grading of the mesh);
* pairs sharing an edge are skipped (counter-clockwise triangles with a consistently
  oriented shared edge lie on its two sides: the certificate checks both facts);
* the test: two counter-clockwise triangles have disjoint interiors iff some edge line
  of one has the other's three vertices on its right or on it (the separating axis
  theorem for convex polygons: a separating line can be taken along an edge), decided
  by the exact predicate :func:`hammesh.predicates.orient_points`.

Triangles that share a vertex and lie side by side are separated by an edge line;
identical triangles stored twice (under other vertex numbers) are not. The boundary is
found with the certificate's own pairing (``hammesh.verify._kernels.half_edge_twins``);
a mesh using a directed edge twice (outside the precondition) has all its triangles
tested. The triangles are split among the machine's cores (the kernels release the
GIL); the answer does not depend on the split.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from hammesh import threads
from hammesh.threads import row_ranges, run_all
from hammesh.predicates import orient_points
from hammesh.verify import half_edge_twins

__all__ = ["find_overlap", "Grid", "build_grid", "boundary_triangles"]

#: cell numbers at level 0 fit this many bits (the finest cell is at least extent / 2**21)
_LEVEL_BITS = 21
_EMPTY = -1


class Grid(NamedTuple):
    """A hierarchical grid of some triangles' bounding boxes (:func:`build_grid`)."""

    targets: np.ndarray  # (k,) the triangles entered
    lo: np.ndarray  # (k, 2) their box corners
    hi: np.ndarray
    level: np.ndarray  # (k,) int64: their own level
    origin: np.ndarray  # (2,)
    c0: float  # cell side at level 0
    n_levels: int  # levels 0..n_levels-1 exist
    slot_key: np.ndarray  # hash table of cell keys (-1: empty) ...
    slot_start: np.ndarray  # ... and the cell's range in ``members``
    slot_end: np.ndarray
    members: np.ndarray  # indices into ``targets``, grouped by cell


@njit(cache=True, inline="always")
def _cell(x, origin, side):
    return np.int64(np.floor((x - origin) / side))


@njit(cache=True, inline="always")
def _key(level, cx, cy, inherited):
    """A cell's key; ``inherited``: the entries of finer targets (not the cell's own level)."""
    return (level << (2 * _LEVEL_BITS + 7)) | (cx << (_LEVEL_BITS + 4)) | (cy << 1) | inherited


@njit(cache=True, inline="always")
def _hash(key, mask):
    x = np.uint64(key) * np.uint64(0x9E3779B97F4A7C15)
    return np.int64((x >> np.uint64(32)) & np.uint64(mask))


@njit(cache=True, inline="always")
def _level_of(s, c0):
    """The least ``L >= 0`` with ``s <= c0 2**L``."""
    L = 0
    side = c0
    while s > side:
        side *= 2.0
        L += 1
    return L


@njit(cache=True, nogil=True)
def _box(pts, tri, t):
    a = tri[t, 0]
    b = tri[t, 1]
    c = tri[t, 2]
    x0 = min(pts[a, 0], min(pts[b, 0], pts[c, 0]))
    x1 = max(pts[a, 0], max(pts[b, 0], pts[c, 0]))
    y0 = min(pts[a, 1], min(pts[b, 1], pts[c, 1]))
    y1 = max(pts[a, 1], max(pts[b, 1], pts[c, 1]))
    return x0, y0, x1, y1


@njit(cache=True, nogil=True)
def _extent_range(pts, tri, lo_t, hi_t):
    """``(min x, min y, max x, max y, smallest positive box side)`` over rows ``lo_t..hi_t``."""
    x0 = np.inf
    y0 = np.inf
    x1 = -np.inf
    y1 = -np.inf
    smin = np.inf
    for t in range(lo_t, hi_t):
        a0, b0, a1, b1 = _box(pts, tri, t)
        x0 = min(x0, a0)
        y0 = min(y0, b0)
        x1 = max(x1, a1)
        y1 = max(y1, b1)
        s = max(a1 - a0, b1 - b0)
        if 0.0 < s < smin:
            smin = s
    return x0, y0, x1, y1, smin


@njit(cache=True, nogil=True)
def _target_entries(pts, tri, targets, origin, c0, n_levels, lo, hi, level, keys, members):
    """Enter each target at every level from its own up (at most 4 cells each)."""
    k = 0
    for i in range(targets.shape[0]):
        x0, y0, x1, y1 = _box(pts, tri, targets[i])
        lo[i, 0] = x0
        lo[i, 1] = y0
        hi[i, 0] = x1
        hi[i, 1] = y1
        level[i] = _level_of(max(x1 - x0, y1 - y0), c0)
        for L in range(level[i], n_levels):
            side = c0 * 2.0**L
            for cx in range(_cell(x0, origin[0], side), _cell(x1, origin[0], side) + 1):
                for cy in range(_cell(y0, origin[1], side), _cell(y1, origin[1], side) + 1):
                    keys[k] = _key(L, cx, cy, 1 if L > level[i] else 0)
                    members[k] = i
                    k += 1
    return k


@njit(cache=True, nogil=True)
def _hash_cells(keys, slot_key, slot_start, slot_end):
    """Open-addressing table of the cells of sorted ``keys``: a cell's range of entries."""
    mask = slot_key.shape[0] - 1
    i = 0
    n = keys.shape[0]
    while i < n:
        j = i + 1
        while j < n and keys[j] == keys[i]:
            j += 1
        s = _hash(keys[i], mask)
        while slot_key[s] != _EMPTY:
            s = (s + 1) & mask
        slot_key[s] = keys[i]
        slot_start[s] = i
        slot_end[s] = j
        i = j


@njit(cache=True, inline="always")
def _find(slot_key, key):
    mask = slot_key.shape[0] - 1
    s = _hash(key, mask)
    while slot_key[s] != _EMPTY:
        if slot_key[s] == key:
            return s
        s = (s + 1) & mask
    return -1


@njit(cache=True, inline="always")
def _shares_edge(tri, t, u):
    shared = 0
    for a in range(3):
        for b in range(3):
            if tri[t, a] == tri[u, b]:
                shared += 1
    return shared >= 2


@njit(cache=True)
def _separated(pts, tri, t, u):
    """Some edge line of ``t`` or ``u`` has the other's corners on its right or on it (exact)."""
    for side in range(2):
        own = t if side == 0 else u
        other = u if side == 0 else t
        for e in range(3):
            a = tri[own, e]
            b = tri[own, (e + 1) % 3]
            right = True
            for v in range(3):
                if orient_points(pts, a, b, tri[other, v]) > 0:
                    right = False
                    break
            if right:
                return True
    return False


@njit(cache=True, nogil=True)
def _first_overlap_range(pts, tri, targets, lo, hi, level, origin, c0, n_levels, top, slot_key, slot_start,
                         slot_end, members, t_lo, t_hi):
    """Lowest overlapping pair ``(i, j)``, ``i < j``, of a triangle ``t_lo <= t < t_hi`` and a
    target, or ``(-1, -1)``. ``top``: the coarsest target's level (no target of its own
    level is coarser)."""
    best_i = -1
    best_j = -1
    for t in range(t_lo, t_hi):
        x0, y0, x1, y1 = _box(pts, tri, t)
        lt = min(_level_of(max(x1 - x0, y1 - y0), c0), n_levels - 1)
        for L in range(lt, max(lt, top) + 1):
            side = c0 * 2.0**L
            for cx in range(_cell(x0, origin[0], side), _cell(x1, origin[0], side) + 1):
                for cy in range(_cell(y0, origin[1], side), _cell(y1, origin[1], side) + 1):
                    for inherited in range(2 if L == lt else 1):  # coarser: targets of that level only
                        s = _find(slot_key, _key(L, cx, cy, inherited))
                        if s < 0:
                            continue
                        for q in range(slot_start[s], slot_end[s]):
                            r = members[q]
                            u = targets[r]
                            if u == t:
                                continue
                            i = min(t, u)
                            j = max(t, u)
                            if best_i >= 0 and (i > best_i or (i == best_i and j >= best_j)):
                                continue
                            px = max(x0, lo[r, 0])
                            py = max(y0, lo[r, 1])
                            if not (min(x1, hi[r, 0]) > px and min(y1, hi[r, 1]) > py):
                                continue  # boxes disjoint or only touching: interiors disjoint
                            if _cell(px, origin[0], side) != cx or _cell(py, origin[1], side) != cy:
                                continue  # tested in the cell of the intersection's corner
                            if _shares_edge(tri, t, u) or _separated(pts, tri, t, u):
                                continue
                            best_i = i
                            best_j = j
    return best_i, best_j


def boundary_triangles(triangles: np.ndarray, n_points: int, twin: np.ndarray | None = None) -> np.ndarray:
    """Rows owning a half-edge without twin (all rows if a directed edge is used twice).

    ``twin``: the certificate's pairing of ``triangles`` if already found (``hammesh
    check`` finds it once for all its checks).
    """
    bad = -1
    if twin is None or np.shape(twin) != (3 * len(triangles),):
        twin, bad = half_edge_twins(triangles, n_points)
    if bad >= 0:
        return np.arange(len(triangles), dtype=np.int64)
    return np.unique(np.flatnonzero(twin < 0) // 3).astype(np.int64)


def build_grid(points: np.ndarray, triangles: np.ndarray, targets: np.ndarray) -> Grid:
    """The hierarchical grid of the ``targets``' bounding boxes (see the module docstring)."""
    spans = row_ranges(len(triangles), threads.THREAD_MIN_ROWS)
    ext = np.array(run_all([(lambda lo=lo, hi=hi: _extent_range(points, triangles, lo, hi)) for lo, hi in spans]))
    origin = np.array([ext[:, 0].min(), ext[:, 1].min()])
    extent = float(max(ext[:, 2].max() - origin[0], ext[:, 3].max() - origin[1]))
    smin = float(ext[:, 4].min())
    c0 = max(smin if np.isfinite(smin) else extent, extent / 2.0**_LEVEL_BITS, np.finfo(float).tiny)
    n_levels = int(np.ceil(np.log2(max(extent / c0, 1.0)))) + 2  # every box fits the top level
    k = len(targets)
    lo = np.empty((k, 2))
    hi = np.empty((k, 2))
    level = np.empty(k, np.int64)
    keys = np.empty(4 * k * n_levels, np.int64)
    members = np.empty(4 * k * n_levels, np.int64)
    used = _target_entries(points, triangles, targets, origin, c0, n_levels, lo, hi, level, keys, members)
    order = np.argsort(keys[:used], kind="stable")
    keys, members = keys[:used][order], members[:used][order]
    n_cells = int(np.count_nonzero(np.diff(keys))) + 1 if used else 0
    slots = 1 << max(4, int(2 * n_cells).bit_length())
    slot_key = np.full(slots, _EMPTY, np.int64)
    slot_start = np.zeros(slots, np.int64)
    slot_end = np.zeros(slots, np.int64)
    _hash_cells(keys, slot_key, slot_start, slot_end)
    return Grid(targets, lo, hi, level, origin, c0, n_levels, slot_key, slot_start, slot_end, members)


def find_overlap(
    points: np.ndarray, triangles: np.ndarray, *, twin: np.ndarray | None = None
) -> tuple[int, int] | None:
    """A pair ``(i, j)``, ``i < j``, of triangles whose interiors intersect, or None.

    The pair returned is the lowest among those in which one triangle has a boundary
    edge (there is one whenever any two triangles overlap: see the module docstring).

    Parameters
    ----------
    points : (n, 2) float64
    triangles : (m, 3) int64
        Counter-clockwise, each directed edge used once (the certificate's items 2-3).
    twin : (3 m,) int64, optional
        Their half-edge pairing as the certificate found it
        (``hammesh.verify.half_edge_twins``), if at hand: saves pairing them again.

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
    g = build_grid(pts, tri, boundary_triangles(tri, len(pts), twin))
    found = run_all([
        (lambda lo=lo, hi=hi: _first_overlap_range(
            pts, tri, g.targets, g.lo, g.hi, g.level, g.origin, g.c0, g.n_levels, int(g.level.max()), g.slot_key,
            g.slot_start, g.slot_end, g.members, lo, hi))
        for lo, hi in row_ranges(len(tri), threads.THREAD_MIN_ROWS)
    ])
    hits = [(int(i), int(j)) for i, j in found if i >= 0]
    return min(hits) if hits else None
