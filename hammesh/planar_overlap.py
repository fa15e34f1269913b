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

**Fans: pairs sharing a vertex of many triangles** (a user's fan of 32k triangles round
one vertex: every box holds the centre, so every pair was a candidate, 15 s at 32k,
quadratic). Two counter-clockwise triangles sharing exactly one vertex ``v`` have
intersecting interiors iff their angular sectors at ``v`` do (each triangle lies in
its sector, and near ``v`` fills it). Round every vertex of more than
:data:`FAN_DEGREE` triangles the sectors are sorted by their first ray (an exact
angular order: the half-plane of a direction by comparisons of coordinates, then the
orientation predicate) and each sector's last ray must not pass the next one's first
(:func:`_fan_overlap_into`): ``O(d log d)`` exact predicates for ``d`` triangles.
Each triangle touching such a vertex is put in the *group* of one (the one of most
triangles); the grid keeps a cell's entries sorted by group, and a triangle skips its
own group's block in a cell by a binary search instead of visiting it: pairs sharing
that vertex are never enumerated (the fan now costs ``O(m log m)``). A pair sharing a
vertex of another group is tested as any other.

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

__all__ = ["find_overlap", "Grid", "build_grid", "boundary_triangles", "fan_groups", "FAN_DEGREE"]

#: cell numbers at level 0 fit this many bits (the finest cell is at least extent / 2**21)
_LEVEL_BITS = 21
_EMPTY = -1
#: a vertex of more triangles than this is a fan's centre: pairs sharing it are decided
#: by the angular order round it (quality meshes have at most ~12: nothing changes for them)
FAN_DEGREE = 16


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
    members: np.ndarray  # indices into ``targets``, grouped by cell, then by fan group
    member_group: np.ndarray  # (entries,) the member's fan group (-1: none); (0,) without fans


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
                         slot_end, members, group, member_group, t_lo, t_hi):
    """Lowest overlapping pair ``(i, j)``, ``i < j``, of a triangle ``t_lo <= t < t_hi`` and a
    target, or ``(-1, -1)``, but for pairs of one fan group (``group``: each triangle's,
    empty without fans; ``member_group``: the cell entries', sorted within a cell): those
    are skipped, a block at a time. ``top``: the coarsest target's level (no target of
    its own level is coarser)."""
    best_i = -1
    best_j = -1
    fans = group.shape[0] > 0
    for t in range(t_lo, t_hi):
        g = group[t] if fans else -1
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
                        s0 = slot_start[s]
                        s1 = slot_end[s]
                        g0 = s1  # (the block of t's own fan group, [g0, g1): skipped)
                        g1 = s1
                        if g >= 0:
                            g0 = s0 + np.searchsorted(member_group[s0:s1], g)
                            g1 = s0 + np.searchsorted(member_group[s0:s1], g, side="right")
                        q = s0
                        while q < s1:
                            if q == g0:
                                q = g1
                                if q >= s1:
                                    break
                            r = members[q]
                            q += 1
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


@njit(cache=True, inline="always")
def _half(pts, v, p):
    """0 if the direction from point ``v`` to point ``p`` is in [0, 180) degrees, else 1
    (exact: comparisons of coordinates, no subtraction)."""
    if pts[p, 1] > pts[v, 1] or (pts[p, 1] == pts[v, 1] and pts[p, 0] > pts[v, 0]):
        return 0
    return 1


@njit(cache=True, inline="always")
def _before(pts, v, p, q):
    """Direction ``v -> p`` strictly before ``v -> q`` counter-clockwise from the +x axis (exact)."""
    hp = _half(pts, v, p)
    hq = _half(pts, v, q)
    if hp != hq:
        return hp < hq
    return orient_points(pts, v, p, q) > 0


@njit(cache=True, nogil=True)
def _fan_overlap_into(pts, tri, start, rows, corner, order, buf, out):
    """For fan centre ``c`` (its triangles ``rows[start[c]:start[c + 1]]``, the centre at
    their corner ``corner[...]``): ``out[c]`` an overlapping pair of them, or ``(-1, -1)``.

    The sectors are sorted by first ray (bottom-up merge sort of ``order``, exact
    comparisons; ``buf`` its scratch); then, cyclically, each sector's last ray must
    not pass the next sector's first (two first rays alike: both sectors hold the
    directions just after it)."""
    for c in range(start.shape[0] - 1):
        lo = start[c]
        d = start[c + 1] - lo
        out[c, 0] = -1
        out[c, 1] = -1
        if d < 2:
            continue
        v = tri[rows[lo], corner[lo]]
        for i in range(d):
            order[lo + i] = lo + i
        width = 1
        while width < d:
            for a in range(0, d, 2 * width):
                m = min(a + width, d)
                b = min(a + 2 * width, d)
                i = a
                j = m
                k = a
                while i < m or j < b:
                    if j < b and i < m:  # (stable: the left run's first on ties)
                        p = tri[rows[order[lo + j]], (corner[order[lo + j]] + 1) % 3]
                        q = tri[rows[order[lo + i]], (corner[order[lo + i]] + 1) % 3]
                        take_left = not _before(pts, v, p, q)
                    else:
                        take_left = j >= b
                    if take_left:
                        buf[lo + k] = order[lo + i]
                        i += 1
                    else:
                        buf[lo + k] = order[lo + j]
                        j += 1
                    k += 1
            for i in range(d):
                order[lo + i] = buf[lo + i]
            width *= 2
        for i in range(d):
            e = order[lo + i]
            f = order[lo + (i + 1) % d]
            a = tri[rows[e], (corner[e] + 1) % 3]  # this sector: rays v->a .. v->b
            b = tri[rows[e], (corner[e] + 2) % 3]
            y = tri[rows[f], (corner[f] + 1) % 3]  # the next sector's first ray
            o = orient_points(pts, v, a, y)
            bad = False
            if o == 0 and _half(pts, v, a) == _half(pts, v, y):
                bad = True  # (the same first ray)
            elif o > 0 and orient_points(pts, v, b, y) < 0:
                bad = True  # (y within this sector's half-turn, before its last ray)
            if bad:
                out[c, 0] = min(rows[e], rows[f])
                out[c, 1] = max(rows[e], rows[f])
                break


def fan_groups(points: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, tuple[int, int] | None]:
    """``(group, pair)``: each triangle's fan group (the vertex of more than
    :data:`FAN_DEGREE` triangles it touches, the one of most; -1 for none; an empty
    array when no vertex is a fan's centre) and an overlapping pair of triangles
    sharing a fan centre (the lowest of those the angular check meets), or None.

    ``points`` (n, 2) float64 and ``triangles`` (m, 3) int64, contiguous."""
    deg = np.bincount(triangles.reshape(-1), minlength=len(points))
    if not len(deg) or deg.max() <= FAN_DEGREE:
        return np.zeros(0, np.int64), None
    dt = deg[triangles]
    high = dt > FAN_DEGREE
    best = np.argmax(np.where(high, dt, -1), axis=1)
    group = np.where(high.any(axis=1), triangles[np.arange(len(triangles)), best], -1).astype(np.int64)
    r, k = np.nonzero(high)
    by = np.argsort(triangles[r, k], kind="stable")
    r, k = r[by].astype(np.int64), k[by].astype(np.int64)
    _, first = np.unique(triangles[r, k], return_index=True)
    start = np.append(first, len(r)).astype(np.int64)
    out = np.empty((len(first), 2), np.int64)
    _fan_overlap_into(points, triangles, start, r, k, np.empty(len(r), np.int64), np.empty(len(r), np.int64), out)
    hits = out[out[:, 0] >= 0]
    pair = None if not len(hits) else tuple(int(x) for x in hits[np.lexsort((hits[:, 1], hits[:, 0]))[0]])
    return group, pair


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


def build_grid(points: np.ndarray, triangles: np.ndarray, targets: np.ndarray,
               group: np.ndarray | None = None) -> Grid:
    """The hierarchical grid of the ``targets``' bounding boxes (see the module docstring);
    ``group``: every triangle's fan group (:func:`fan_groups`), a cell's entries sorted by it."""
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
    if group is not None and len(group):
        order = np.lexsort((group[targets[members[:used]]], keys[:used]))
    else:
        order = np.argsort(keys[:used], kind="stable")
    keys, members = keys[:used][order], members[:used][order]
    member_group = group[targets[members]] if group is not None and len(group) else np.zeros(0, np.int64)
    n_cells = int(np.count_nonzero(np.diff(keys))) + 1 if used else 0
    slots = 1 << max(4, int(2 * n_cells).bit_length())
    slot_key = np.full(slots, _EMPTY, np.int64)
    slot_start = np.zeros(slots, np.int64)
    slot_end = np.zeros(slots, np.int64)
    _hash_cells(keys, slot_key, slot_start, slot_end)
    return Grid(targets, lo, hi, level, origin, c0, n_levels, slot_key, slot_start, slot_end, members, member_group)


def find_overlap(
    points: np.ndarray, triangles: np.ndarray, *, twin: np.ndarray | None = None
) -> tuple[int, int] | None:
    """A pair ``(i, j)``, ``i < j``, of triangles whose interiors intersect, or None.

    The pair returned is the lowest among those in which one triangle has a boundary
    edge (there is one whenever any two triangles overlap: see the module docstring),
    where the pairs sharing a fan's centre (a vertex of more than :data:`FAN_DEGREE`
    triangles) count by the one the angular check meets round it.

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
    group, fan_pair = fan_groups(pts, tri)
    g = build_grid(pts, tri, boundary_triangles(tri, len(pts), twin), group)
    found = run_all([
        (lambda lo=lo, hi=hi: _first_overlap_range(
            pts, tri, g.targets, g.lo, g.hi, g.level, g.origin, g.c0, g.n_levels, int(g.level.max()), g.slot_key,
            g.slot_start, g.slot_end, g.members, group, g.member_group, lo, hi))
        for lo, hi in row_ranges(len(tri), threads.THREAD_MIN_ROWS)
    ])
    hits = [(int(i), int(j)) for i, j in found if i >= 0] + ([fan_pair] if fan_pair is not None else [])
    return min(hits) if hits else None
