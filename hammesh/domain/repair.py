"""Repairs of a planar straight-line graph that Triangle would make itself, reported.

Triangle (``-p``) accepts a graph whose segments cross, overlap or pass through
vertices, and whose vertices repeat: it splits and merges as it inserts segments.
hammesh does the same *before* Triangle runs, with exact predicates, so that the
:class:`~hammesh.domain.Domain` it meshes is exactly the graph Triangle meshes, and
records every repair as a :class:`Repair` (what, how many, where) for the report.
With ``strict=True`` the first defect is refused instead, with an
:class:`~hammesh.errors.InvalidDomainError` naming it.

Repairs, in the order they are made:

``duplicate_vertex``
    Vertices at identical coordinates are merged into the lowest index; segments are
    re-pointed to it and the others are dropped (later vertices move down; Triangle
    ignores such a vertex too). Unused copies are simply dropped.
``zero_length_segment``, ``duplicate_segment``
    Dropped (Triangle ignores them), the first copy kept.
``vertex_on_segment``
    A vertex strictly inside a segment (a T-junction): the segment is split there.
``collinear_overlap``
    Collinear segments sharing more than a point: split at each other's endpoints,
    the common pieces kept once (marker of the lower-numbered segment).
``crossing``
    Two segments crossing at an interior point: the point (rounded to float64,
    clamped into both segments' boxes) is appended as a new vertex and both are split
    there, as Triangle does. Rounding can leave the new vertex a few ulps off either
    segment; the result is checked again (up to four rounds).

Every original vertex that is kept stays at its index (minus the dropped duplicates
before it); new vertices are appended.  Sub-segments inherit their segment's marker;
a crossing vertex takes the marker of the lower-numbered segment.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from hammesh.domain import intersections as ix
from hammesh.domain.validate import holes_inside_hull
from hammesh.errors import InvalidDomainError
from hammesh.predicates import orient_rows

__all__ = ["Repair", "RepairedGraph", "repair_graph", "drop_outside_holes", "refuse_points_on_segments", "REPAIR_KINDS",
           "MAX_ROUNDS"]

#: Every repair kind, in the order repairs are made.
REPAIR_KINDS = ("duplicate_vertex", "zero_length_segment", "duplicate_segment",
                "vertex_on_segment", "collinear_overlap", "crossing", "hole_outside")
#: Noding rounds before a graph whose crossing points keep creating defects is refused.
MAX_ROUNDS = 4
#: Candidate tests above which the grid is not used to find all defects at once...
GRID_TESTS = 2e7
#: ... and the sweep repairs one defect at a time, up to this many (then the grid).
MAX_SINGLE_REPAIRS = 200
_WHERE = 5  # example locations kept per repair


@dataclass(frozen=True)
class Repair:
    """One kind of repair made to a domain.

    Attributes
    ----------
    kind : str
        One of :data:`REPAIR_KINDS`.
    count : int
        How many times (vertices dropped, segments dropped, junctions split, overlaps
        merged, crossings inserted).
    where : tuple of (float, float)
        Up to five example locations.
    defect : str
        The first instance, as a strict refusal would name it.
    action : str
        What was done about it (and the others of its kind).
    """

    kind: str
    count: int
    where: tuple
    defect: str
    action: str

    @property
    def message(self) -> str:
        """One line: the first defect and what was done."""
        return f"{self.defect}: {self.action}"

    def to_dict(self) -> dict:
        """JSON-ready: ``{"kind", "count", "where": [[x, y], ...], "message"}``."""
        return {"kind": self.kind, "count": int(self.count),
                "where": [[float(x), float(y)] for x, y in self.where], "message": self.message}


class RepairedGraph(NamedTuple):
    vertices: np.ndarray
    segments: np.ndarray
    segment_markers: np.ndarray
    vertex_markers: np.ndarray
    repairs: tuple


def _fmt(x) -> str:
    return repr(float(x))


def _pt(p) -> str:
    return f"({_fmt(p[0])}, {_fmt(p[1])})"


def _where(points) -> tuple:
    return tuple((float(p[0]), float(p[1])) for p in np.asarray(points)[:_WHERE])


# ----------------------------------------------------------------------------- holes

def drop_outside_holes(vertices: np.ndarray, holes: np.ndarray, strict: bool) -> tuple[np.ndarray, tuple]:
    """The hole points inside the convex hull of ``vertices`` and the repair that dropped
    the others (``()`` if none): a point outside is in no triangle, and Triangle's
    ``carveholes`` may crash locating one that lies inside the bounding box
    (:func:`hammesh.domain.validate.holes_in_hull`).

    Raises
    ------
    InvalidDomainError
        With ``strict``, naming the first such hole point.
    """
    if len(holes) == 0:
        return holes, ()
    keep = holes_inside_hull(vertices, holes)
    if keep.all():
        return holes, ()
    out = holes[~keep]
    defect = f"hole point {int(np.argmin(keep))} at {_pt(out[0])} lies outside the convex hull of the vertices"
    if strict:
        raise InvalidDomainError(defect)
    return holes[keep], (Repair("hole_outside", len(out), _where(out), defect,
                                "dropped: it is in no triangle (Triangle could crash locating it)"),)


def _first_on_segment(xy: np.ndarray, segs: np.ndarray, pts: np.ndarray) -> tuple[int, str, int] | None:
    """``(point, "vertex" | "segment", index)`` of the lowest-numbered point of ``pts``
    lying exactly on a segment's end or on a segment of the graph (exact: coordinate comparisons
    and the orientation predicate), or None.

    The segments each point may lie on are found by a sweep in x (a segment's x range
    against the points sorted by x), then its y range, then ``orient == 0``."""
    if not len(pts):
        return None
    hits = []
    ends = np.unique(segs)  # (a vertex on no segment is inside one region: any of its triangles will do)
    on_vertex = np.isin(pts[:, 0] + 1j * pts[:, 1], xy[ends, 0] + 1j * xy[ends, 1])
    if on_vertex.any():
        i = int(np.argmax(on_vertex))
        hits.append((i, "vertex", int(ends[np.flatnonzero((xy[ends] == pts[i]).all(axis=1))[0]])))
    if len(segs):
        a, b = xy[segs[:, 0]], xy[segs[:, 1]]
        order = np.argsort(pts[:, 0], kind="stable")
        px = pts[order, 0]
        lo = np.searchsorted(px, np.minimum(a[:, 0], b[:, 0]), "left")
        hi = np.searchsorted(px, np.maximum(a[:, 0], b[:, 0]), "right")
        count = hi - lo
        if count.sum():
            seg = np.repeat(np.arange(len(segs)), count)
            ramp = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
            pt = order[np.repeat(lo, count) + ramp]
            y = pts[pt, 1]
            inside = (y >= np.minimum(a[seg, 1], b[seg, 1])) & (y <= np.maximum(a[seg, 1], b[seg, 1]))
            seg, pt = seg[inside], pt[inside]
            if len(seg):
                on = orient_rows(np.ascontiguousarray(a[seg]), np.ascontiguousarray(b[seg]),
                                 np.ascontiguousarray(pts[pt])) == 0
                if on.any():
                    k = np.flatnonzero(on)
                    j = k[np.lexsort((seg[k], pt[k]))[0]]
                    hits.append((int(pt[j]), "segment", int(seg[j])))
    return min(hits, key=lambda h: (h[0], h[1] == "segment")) if hits else None


def refuse_points_on_segments(vertices: np.ndarray, segments: np.ndarray, holes: np.ndarray,
                              regions: np.ndarray) -> None:
    """Refuse a hole or region point that lies exactly on a segment or a vertex.

    Why: Triangle (``carveholes``, ``regionplague``) starts from the triangle its point
    location returns for the point, and for a point on an edge that is either side's:
    a square hole whose hole point lies on its bottom side removed the ring around it
    instead (8 of 32 triangles kept), the same point on its top side the square; a
    region point on a corner gave its attribute to one side or the other. Triangle
    accepts such input but what it makes of it is chance, not the user's domain
    (hammesh gave either silently before session 19); a point off the segment, on
    the side meant, says it.

    Raises
    ------
    InvalidDomainError
        Naming the point, where it is and the segment or vertex it lies on.
    """
    xy = np.asarray(vertices, dtype=np.float64).reshape(-1, 2)
    segs = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    for what, pts, meaning in (("hole", np.asarray(holes, np.float64).reshape(-1, 2),
                                "which side is the hole"),
                               ("region", np.asarray(regions, np.float64).reshape(-1, 4)[:, :2],
                                "which side the region is")):
        hit = _first_on_segment(xy, segs, np.ascontiguousarray(pts))
        if hit is None:
            continue
        i, kind, j = hit
        on = (f"vertex {j} of the domain" if kind == "vertex" else
              f"segment {j} ({_pt(xy[segs[j, 0]])} to {_pt(xy[segs[j, 1]])})")
        raise InvalidDomainError(f"{what} point {i} at {_pt(pts[i])} lies exactly on {on}: Triangle would pick "
                                 f"{meaning} by chance; move it off, into the side meant")


# ----------------------------------------------------------------------------- vertices

def _merge_duplicate_vertices(xy, segs, vmark, strict, repairs):
    n = len(xy)
    order = np.lexsort((np.arange(n), xy[:, 1], xy[:, 0]))
    v = xy[order]
    same = np.zeros(n, bool)
    same[1:] = (v[1:] == v[:-1]).all(axis=1)
    if not same.any():
        return xy, segs, vmark
    group = np.cumsum(~same) - 1
    first = order[np.flatnonzero(~same)]          # lowest index of each group (stable sort)
    keep_of = np.empty(n, np.int64)
    keep_of[order] = first[group]
    dropped = np.flatnonzero(keep_of != np.arange(n))
    j = int(dropped[0])
    i = int(keep_of[j])
    if strict:
        raise InvalidDomainError(f"vertices {i} and {j} are duplicates: both at {_pt(xy[i])}")
    kept = keep_of == np.arange(n)
    new_index = np.cumsum(kept) - 1
    remap = new_index[keep_of]
    used = np.zeros(n, bool)
    used[segs.ravel()] = True
    how = ("segments re-pointed to it" if used[dropped].any() else "unused")
    repairs.append(Repair(
        "duplicate_vertex", len(dropped), _where(xy[dropped]),
        f"vertices {i} and {j} are duplicates: both at {_pt(xy[i])}",
        f"merged into vertex {i} ({how}); {len(dropped)} duplicate(s) dropped, later "
        "vertices renumbered"))
    return xy[kept], remap[segs], vmark[kept]


# ----------------------------------------------------------------------------- segments

def _drop_degenerate_segments(xy, segs, smark, strict, repairs):
    zero = segs[:, 0] == segs[:, 1]
    if zero.any():
        i = int(np.flatnonzero(zero)[0])
        if strict:
            raise InvalidDomainError(
                f"segment {i} has zero length: both ends are vertex {segs[i, 0]}")
        repairs.append(Repair("zero_length_segment", int(zero.sum()), _where(xy[segs[zero, 0]]),
                              f"segment {i} has zero length: both ends are vertex {segs[i, 0]}",
                              f"{int(zero.sum())} zero-length segment(s) dropped"))
        segs, smark = segs[~zero], smark[~zero]
    key = np.sort(segs, axis=1)
    order = np.lexsort((np.arange(len(key)), key[:, 1], key[:, 0]))
    k = key[order]
    same = np.zeros(len(k), bool)
    same[1:] = (k[1:] == k[:-1]).all(axis=1)
    if same.any():
        firsts = np.maximum.accumulate(np.where(~same, np.arange(len(k)), 0))
        dup = order[same]
        orig = order[firsts[same]]
        t = int(np.argmin(dup))
        i, j = sorted((int(orig[t]), int(dup[t])))
        a, b = segs[i]
        if strict:
            raise InvalidDomainError(
                f"segments {i} and {j} are duplicates: both connect vertices {a} and {b}")
        mid = 0.5 * (xy[segs[dup, 0]] + xy[segs[dup, 1]])
        repairs.append(Repair("duplicate_segment", len(dup), _where(mid),
                              f"segments {i} and {j} are duplicates: both connect vertices "
                              f"{a} and {b}", f"{len(dup)} duplicate(s) dropped"))
        keep = np.ones(len(segs), bool)
        keep[dup] = False
        segs, smark = segs[keep], smark[keep]
    return segs, smark


def check_not_collinear(xy) -> None:
    """Refuse a vertex set whose convex hull has zero area (exact test)."""
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    axis = int(np.argmax(hi - lo))
    a = xy[np.argmin(xy[:, axis])]
    b = xy[np.argmax(xy[:, axis])]
    n = len(xy)
    sign = orient_rows(np.broadcast_to(a, (n, 2)).copy(), np.broadcast_to(b, (n, 2)).copy(),
                       np.ascontiguousarray(xy))
    if not sign.any():
        raise InvalidDomainError(
            f"all {n} vertices are collinear (the convex hull has zero area)")


def _describe(xy, segs, d: ix.Defect) -> str:
    """The one-line refusal of defect ``d`` (strict mode)."""
    if d.kind == ix.KIND_VERTEX:
        # the vertex may be the end of a segment lying along this one: say "overlap"
        lo, hi = ix.ordered_ends(xy, segs)
        for t in np.flatnonzero((segs == d.b).any(axis=1)):
            if ix.pair_kind(xy, lo, hi, d.a, t) == ix.KIND_OVERLAP:
                return _describe(xy, segs, ix.Defect(ix.KIND_OVERLAP, min(d.a, t), max(d.a, t)))
        return (f"segment {d.a} passes through vertex {d.b} at {_pt(xy[d.b])}, "
                "which is not one of its endpoints")
    i, j = d.a, d.b
    if d.kind == ix.KIND_CROSSING:
        return f"segments {i} and {j} cross at {_pt(_crossing_point(xy, segs[i], segs[j]))}"
    lo, hi = ix.ordered_ends(xy, segs[[i, j]])
    if d.kind == ix.KIND_OVERLAP:
        ends = sorted((int(v) for v in (lo[0], hi[0], lo[1], hi[1])),
                      key=lambda v: (xy[v, 0], xy[v, 1]))
        p, q = ends[1], ends[2]  # the common part: between the middle two ends
        return (f"segments {i} and {j} overlap collinearly between "
                f"{_pt(xy[p])} and {_pt(xy[q])}")
    # touch: an endpoint of one lies inside the other
    for seg, other in ((i, j), (j, i)):
        for v in segs[other]:
            a, b = segs[seg]
            if v in (a, b):
                continue
            if orient_rows(xy[[a]], xy[[b]], xy[[v]])[0] == 0:
                return (f"segment {seg} passes through vertex {int(v)} at {_pt(xy[v])}, "
                        "which is not one of its endpoints")
    return f"segments {i} and {j} touch"  # pragma: no cover - kinds are exhaustive


def _crossing_point(xy, s, t):
    """Where segments ``s`` and ``t`` (rows of vertex pairs, or ``(k, 2)`` arrays of
    them) cross, rounded, clamped into both segments' boxes."""
    s, t = np.atleast_2d(s), np.atleast_2d(t)
    p0, p1 = xy[s[:, 0]], xy[s[:, 1]]
    q0, q1 = xy[t[:, 0]], xy[t[:, 1]]
    r, d = p1 - p0, q1 - q0
    w = q0 - p0
    den = r[:, 0] * d[:, 1] - r[:, 1] * d[:, 0]
    u = (w[:, 0] * d[:, 1] - w[:, 1] * d[:, 0]) / den
    x = p0 + u[:, None] * r
    lo = np.maximum(np.minimum(p0, p1), np.minimum(q0, q1))
    hi = np.minimum(np.maximum(p0, p1), np.maximum(q0, q1))
    out = np.clip(x, lo, hi)
    return out[0] if out.shape[0] == 1 else out


def _one_defect(xy, segs, d: ix.Defect):
    """``(pairs, inside)`` as :func:`~hammesh.domain.intersections.all_defects` gives
    them, for the single defect ``d``."""
    pairs = np.zeros((0, 3), np.int64)
    if d.kind == ix.KIND_VERTEX:
        return pairs, np.array([[d.a, d.b]], np.int64)
    if d.kind == ix.KIND_CROSSING:
        return np.array([[d.kind, d.a, d.b]], np.int64), np.zeros((0, 2), np.int64)
    rows = []
    for s, t in ((d.a, d.b), (d.b, d.a)):
        a, b = segs[s]
        for v in segs[t]:
            if v in (a, b):
                continue
            lo, hi = np.minimum(xy[a], xy[b]), np.maximum(xy[a], xy[b])
            if (orient_rows(xy[[a]], xy[[b]], xy[[v]])[0] == 0
                    and (lo <= xy[v]).all() and (xy[v] <= hi).all()):
                rows.append((s, v))
    return pairs, np.array(rows, np.int64).reshape(-1, 2)


def _node(xy, segs, smark, vmark, found, counts):
    """Split every segment at the vertices inside it and at its crossings
    (``found = (pairs, inside)`` as ``all_defects`` returns them)."""
    pairs, inside = found
    n = len(xy)
    cross = pairs[pairs[:, 0] == ix.KIND_CROSSING]
    # crossing points: new vertices, coincident ones merged, existing coordinates reused
    split_seg = [inside[:, 0]]
    split_vtx = [inside[:, 1]]
    if len(cross):
        pts = _crossing_point(xy, segs[cross[:, 1]], segs[cross[:, 2]]).reshape(-1, 2)
        uniq, inv = np.unique(pts, axis=0, return_inverse=True)
        inv = inv.reshape(-1)
        allpts = np.concatenate([xy, uniq])
        order = np.lexsort((np.arange(len(allpts)), allpts[:, 1], allpts[:, 0]))
        srt = allpts[order]
        same = np.zeros(len(srt), bool)
        same[1:] = (srt[1:] == srt[:-1]).all(axis=1)
        head = np.maximum.accumulate(np.where(~same, np.arange(len(srt)), 0))
        rep = np.empty(len(allpts), np.int64)
        rep[order] = order[head]  # an existing vertex precedes a new copy (stable)
        new_rows = rep[n:] >= n
        ids = np.full(len(uniq), -1, np.int64)
        ids[~new_rows] = rep[n:][~new_rows]
        ids[new_rows] = n + np.arange(int(new_rows.sum()))
        first_seg = np.full(len(uniq), np.iinfo(np.int64).max)
        np.minimum.at(first_seg, inv, np.minimum(cross[:, 1], cross[:, 2]))
        xy = np.concatenate([xy, uniq[new_rows]])
        vmark = np.concatenate([vmark, smark[first_seg[new_rows]]])
        vid = ids[inv]
        split_seg += [cross[:, 1], cross[:, 2]]
        split_vtx += [vid, vid]
        counts["crossing"].append((len(cross), pts,
                                   f"segments {cross[0, 1]} and {cross[0, 2]} cross at "
                                   f"{_pt(pts[0])}", "a vertex inserted at each crossing, "
                                   "both segments split there (as Triangle does)"))
    # a vertex inside a segment is a T-junction, or the end of an overlapping segment
    if len(inside):
        partner = ix.overlap_ends(xy[:n], segs, inside)
        along = partner >= 0
        tj = ~along
        if tj.any():
            s0, v0 = inside[np.flatnonzero(tj)[0]]
            counts["vertex_on_segment"].append((int(tj.sum()), xy[inside[tj, 1]],
                                                f"segment {s0} passes through vertex {v0} at "
                                                f"{_pt(xy[v0])}, which is not one of its endpoints",
                                                "segments split at the vertices inside them"))
        if along.any():
            # each overlapping pair puts an end of one inside the other: count pairs
            pairs = np.unique(np.sort(np.c_[inside[along, 0], partner[along]], axis=1), axis=0)
            i, j = pairs[0]
            counts["collinear_overlap"].append((len(pairs), xy[inside[along, 1]],
                                                _describe(xy, segs, ix.Defect(ix.KIND_OVERLAP,
                                                                              int(i), int(j))),
                                                "merged: split at each other's ends, common "
                                                "pieces kept once"))
    seg_idx = np.concatenate(split_seg).astype(np.int64)
    vtx_idx = np.concatenate(split_vtx).astype(np.int64)
    # order the split points along their segment, chain them
    a, b = xy[segs[seg_idx, 0]], xy[segs[seg_idx, 1]]
    t = ((xy[vtx_idx] - a) * (b - a)).sum(axis=1)
    order = np.lexsort((t, seg_idx))
    seg_idx, vtx_idx = seg_idx[order], vtx_idx[order]
    s = len(segs)
    nsplit = np.bincount(seg_idx, minlength=s)
    pieces = nsplit + 1
    total = int(pieces.sum())
    parent = np.repeat(np.arange(s), pieces)
    start = np.cumsum(pieces) - pieces
    chain = np.empty(total + s, np.int64)  # per segment: a, splits..., b
    cstart = start + np.arange(s)
    chain[cstart] = segs[:, 0]
    chain[cstart + pieces] = segs[:, 1]
    within = np.arange(len(seg_idx)) - np.repeat(np.cumsum(nsplit) - nsplit, nsplit)
    chain[np.repeat(cstart, nsplit) + 1 + within] = vtx_idx
    first = np.repeat(cstart, pieces) + (np.arange(total) - np.repeat(start, pieces))
    new_segs = np.stack([chain[first], chain[first + 1]], axis=1)
    new_mark = smark[parent]
    # overlapping pieces now coincide: keep the first, drop zero-length pieces
    ok = new_segs[:, 0] != new_segs[:, 1]
    new_segs, new_mark = new_segs[ok], new_mark[ok]
    key = np.sort(new_segs, axis=1)
    _, first_row = np.unique(key, axis=0, return_index=True)
    keep = np.sort(first_row)
    return xy, new_segs[keep], new_mark[keep], vmark


def repair_graph(vertices, segments, segment_markers, vertex_markers, *,
                 strict: bool = False) -> RepairedGraph:
    """Repair (or, ``strict``, refuse) a graph's duplicates, junctions, overlaps, crossings.

    Parameters
    ----------
    vertices : (n, 2) float64, finite
    segments : (s, 2) int64, indices in range
    segment_markers : (s,) int64
    vertex_markers : (n,) int64
    strict : bool
        Refuse the first defect with :class:`~hammesh.errors.InvalidDomainError`
        instead of repairing it.

    Returns
    -------
    RepairedGraph
        The arrays of the repaired graph (the inputs themselves when nothing was
        repaired) and ``repairs``, a tuple of :class:`Repair` (empty if none).

    Raises
    ------
    InvalidDomainError
        ``strict`` and a defect; all vertices collinear; crossing points that keep
        creating defects after :data:`MAX_ROUNDS` rounds.

    Examples
    --------
    >>> import numpy as np
    >>> v = np.array([[0., 0], [2, 0], [2, 2], [0, 2], [1, 0]])   # 4 lies on segment 0
    >>> s = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])
    >>> g = repair_graph(v, s, np.ones(4, np.int64), np.zeros(5, np.int64))
    >>> g.segments.tolist(), g.repairs[0].kind
    ([[0, 4], [4, 1], [1, 2], [2, 3], [3, 0]], 'vertex_on_segment')
    """
    repairs: list[Repair] = []
    xy, segs, smark, vmark = vertices, segments, segment_markers, vertex_markers
    xy, segs, vmark = _merge_duplicate_vertices(xy, segs, vmark, strict, repairs)
    check_not_collinear(xy)
    if len(segs):
        segs, smark = _drop_degenerate_segments(xy, segs, smark, strict, repairs)
    counts = {k: [] for k in ("vertex_on_segment", "collinear_overlap", "crossing")}
    rounds = singles = 0
    while True:
        d = ix.first_defect(xy, segs)
        if d.kind == ix.KIND_NONE:
            break
        if strict:
            raise InvalidDomainError(_describe(xy, segs, d))
        if rounds == MAX_ROUNDS:
            raise InvalidDomainError(
                f"cannot repair the segments robustly: after {MAX_ROUNDS} rounds of inserting "
                f"crossing points, {_describe(xy, segs, d)}")
        # all defects at once where the grid is cheap; else (a vertex of huge degree,
        # long segments packed together) the sweep's one defect at a time, which
        # costs a sweep per defect: fine for the few a real file has
        found = ix.all_defects(xy, segs, max_tests=GRID_TESTS if singles < MAX_SINGLE_REPAIRS
                               else np.inf)
        if found is None:
            found = _one_defect(xy, segs, d)
            singles += 1
        else:
            rounds += 1
        xy, segs, smark, vmark = _node(xy, segs, smark, vmark, found, counts)
    for kind in ("vertex_on_segment", "collinear_overlap", "crossing"):
        if counts[kind]:
            total = sum(c for c, _, _, _ in counts[kind])
            where = np.concatenate([w for _, w, _, _ in counts[kind]])
            repairs.append(Repair(kind, total, _where(where), *counts[kind][0][2:]))
    return RepairedGraph(xy, segs, smark, vmark, tuple(repairs))
