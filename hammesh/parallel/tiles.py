"""Decoupled tiles: a domain cut into tiles that Triangle can mesh one at a time (issue 15).

The Delaunay decoupling method (Linardakis & Chrisochoides, SIAM J. Sci. Comput.
30(4), 2008) with axis-parallel cuts:

1. a **coarse quality mesh** of the whole domain (Triangle ``pq`` with a large area
   bound, a few ten thousand triangles) gives the domain itself (its area, which side
   of a cut is inside), the local feature size (its edge lengths) and the estimated
   triangle count of any part (its area over ``AREA_FILL x max_area``);
2. a **kd split** cuts the bounding box into ``n_tiles`` boxes of about equal
   estimated count; each cut is moved (within a few percent of the balanced position)
   to where it crosses the user's segments at large angles and stays clear of their
   vertices, so that no small angle or tiny feature appears where none was;
3. the user's segments are **cut** where they cross a cut; the parts of each cut that
   lie inside the domain are the **separators**; every separator and every user
   segment piece is **discretised** with the spacing Triangle would give it
   (:mod:`hammesh.parallel.sizing`, graded near features);
4. each tile gets the pieces inside its box and the separators on its border; Triangle
   meshes it with ``-Y`` (no Steiner point on the tile's boundary), so both tiles
   along a separator end with exactly its subsegments: the union conforms.

Every point of the decomposition has one global index (the input's vertices first, at
their indices), shared by all tiles that use it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from hammesh.domain import Domain
from hammesh.errors import InvalidOptionError, MeshingError
from hammesh.meshing.options import MeshOptions, format_number
from hammesh.parallel.sizing import AREA_FILL, EDGE_PER_SQRT_AREA, graded_points_many

__all__ = ["Tile", "Decomposition", "decompose", "check_bounds", "split_segments", "coupled_ends", "without_subnormals",
           "COARSE_TRIANGLES",
           "COUPLED_DEG", "CUT_TOUCH"]

#: area bound of the coarse mesh: bounding box area / COARSE_TRIANGLES
COARSE_TRIANGLES = 20_000
#: the fewest estimated triangles a tile may hold (``decompose`` refuses more tiles): at
#: ~3 a tile (64 tiles of a 185-triangle domain) the separators made 128,052 triangles,
#: 2,000 tiles of the demo at ``-a 0.002`` gave a tile no triangle (an internal error,
#: session 17). Small on purpose: the coarse-size tests decompose small meshes into many
#: tiles; 16 tiles of that domain (12 a tile) still make 4.7x its triangles
MIN_TILE_TRIANGLES = 10
#: a cut may move this fraction of its box's estimated count off the balanced position
CUT_WINDOW = 0.04
#: cut positions tried in the window
CUT_CANDIDATES = 33
#: windows tried next (both axes) when no position in CUT_WINDOW is good
WIDER_WINDOWS = (0.1, 0.2)
#: a cut should cross user segments at least this many degrees above the min angle
CROSS_MARGIN_DEG = 10.0
#: and stay this many local edge lengths away from vertices
CLEARANCE = 1.0
#: a cut keeps clear of the vertices on the box sides it ends on, too (and may end at
#: another cut's end): :func:`_choose_cut`; False: only of those inside the box (before session 16)
SIDE_VERTICES = True
#: a cut position closer than this times the box's extent to a vertex (and not at it,
#: as at another cut's end) is never taken (session 17): the cut's crossings with the
#: segments ending there would lie that close to the vertex, and a separator would pass
#: it as close, input that crashes Triangle (SIGSEGV; ``tile_mesh.NEAR_RELATIVE``).
#: Before, only a cut exactly at a vertex was refused; any other was only ranked low
#: and taken when no candidate crossed the segments at a good angle.
CUT_TOUCH = 1e-9
#: a coarse edge lying on a cut counts as inside the domain (:func:`_line_cover`,
#: session 17); False: only triangles the cut crosses (before, kept for the A/B)
LINE_EDGES = True
#: a cut closer to a vertex than this fraction of CLEARANCE is looked for in the wider windows too
WIDEN_BELOW = 0.5
#: a separator's subsegment is at most this times its distance to a vertex off its line
OBSTACLE_FACTOR = 1.5
#: most samples of the size along one piece
MAX_SAMPLES_PER_PIECE = 200_000


@dataclass(frozen=True, eq=False)
class Tile:
    """One tile: the PSLG Triangle meshes alone.

    Attributes
    ----------
    index : int
    box : (4,) float64
        ``xmin, xmax, ymin, ymax`` (closed).
    vertex_ids : (k,) int64
        Global index of each of the tile's vertices (sorted).
    vertices : (k, 2) float64
    segments : (s, 2) int64
        Local indices.
    segment_markers : (s,) int64
        The user's markers; 0 on separators.
    separator : (s,) bool
        Which segments are separator subsegments (shared with one other tile).
    holes : (h, 2) float64
    estimate : float
        Estimated triangle count.
    """

    index: int
    box: np.ndarray
    vertex_ids: np.ndarray
    vertices: np.ndarray
    segments: np.ndarray
    segment_markers: np.ndarray
    separator: np.ndarray
    holes: np.ndarray
    estimate: float
    #: coarse triangles over the box and their regional attribute (empty: no regions)
    region_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)), repr=False)
    region_triangles: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), np.int64), repr=False)
    region_attribute: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    #: coarse triangles over the box (the domain there: where the tile's lattice goes)
    coarse_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)), repr=False)
    coarse_triangles: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), np.int64), repr=False)


@dataclass(frozen=True, eq=False)
class Decomposition:
    """A domain cut into tiles (:func:`decompose`).

    Attributes
    ----------
    vertices : (N, 2) float64
        Global points: the domain's vertices at their indices, then crossing points,
        junctions of cuts and the points of the discretisation.
    n_input : int
        ``len(domain.vertices)``.
    segments : (S, 2) int64
        Global segments: the user's segments cut and discretised, and the separators.
    separator : (S,) bool
    origin : (S,) int64
        The user segment each piece came from (-1 for separators).
    tiles : tuple of Tile
    area : float
        The domain's area (coarse mesh).
    cuts : (c, 4) float64
        ``axis (0: x = value), value, lo, hi`` of every cut.
    estimate : float
        Estimated triangle count of a single Triangle run.
    min_angle, max_area : float or None
        The options the tiles are meshed with.
    coarse_points, coarse_triangles, coarse_region : arrays
        The coarse mesh and the region row of each of its triangles (-1: none), used
        to give the tiles' triangles their regional attributes.
    """

    vertices: np.ndarray
    n_input: int
    segments: np.ndarray
    separator: np.ndarray
    origin: np.ndarray
    tiles: tuple[Tile, ...]
    area: float
    cuts: np.ndarray
    estimate: float
    min_angle: float | None
    max_area: float | None
    coarse_points: np.ndarray = field(repr=False)
    coarse_triangles: np.ndarray = field(repr=False)
    coarse_region: np.ndarray = field(repr=False)
    regions: np.ndarray = field(repr=False)
    holes: np.ndarray = field(repr=False, default_factory=lambda: np.zeros((0, 2)))
    segment_markers: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0, np.int64))

    @property
    def n_tiles(self) -> int:
        return len(self.tiles)


# ---------------------------------------------------------------------------- coarse mesh


def _tri_area(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    a, b, c = p[t[:, 0]], p[t[:, 1]], p[t[:, 2]]
    return 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))


def _hull_segments(vertices: np.ndarray) -> np.ndarray:
    from hammesh.parallel.guard import triangulate_guarded

    out = triangulate_guarded({"vertices": np.array(vertices)}, "pcQ", "the domain's hull")
    return np.asarray(out["segments"], dtype=np.int64).reshape(-1, 2)


def without_subnormals(xy: np.ndarray) -> np.ndarray:
    """``xy`` (float64) with every subnormal coordinate (``0 < |x| < 2.2e-308``) made 0:
    what Triangle gets, the caller putting the given coordinates back on its output.

    Triangle's exact predicates assume no underflow (Shewchuk, "Adaptive precision
    floating-point arithmetic and fast robust geometric predicates", 1997): random
    domains with a vertex at ``(0.6, 5e-324)`` made Triangle fail ("Unable to find a
    triangle leading from ...") on the coarse mesh and on a tile, though the whole
    domain's quality run happened to pass. Moving a point by less than 2.2e-308 turns
    no triangle that meets a min angle; the union's check tests the true coordinates.
    """
    xy = np.asarray(xy, dtype=np.float64)
    tiny = (np.abs(xy) < np.finfo(np.float64).tiny) & (xy != 0)
    return np.where(tiny, 0.0, xy) if tiny.any() else np.array(xy)


def _coarse_mesh(vertices, segments, holes, regions, min_angle, max_area):
    """Triangle's coarse quality mesh of the domain: points, triangles, region rows,
    and its subsegments with the user segment each lies on (Triangle's own grading of
    the segments near small angles and close features, kept by the tiles)."""
    from hammesh.parallel.guard import triangulate_guarded

    ext = np.ptp(vertices, axis=0)
    area_bound = max(float(ext[0] * ext[1]) / COARSE_TRIANGLES, 4.0 * max_area)
    q = 20.0 if min_angle is None else min(float(min_angle), 30.0)
    data = {"vertices": without_subnormals(vertices), "segments": segments.astype(np.int32),
            # the marker carries the segment's row, to find it again on each subsegment
            "segment_markers": (np.arange(len(segments), dtype=np.int32) + 1)[:, None]}
    if len(holes):
        data["holes"] = holes
    sw = "p" + "q" + format_number(q) + "a" + format_number(area_bound)
    if len(regions):
        reg = np.zeros((len(regions), 4))
        reg[:, :2] = regions[:, :2]
        reg[:, 2] = np.arange(len(regions))
        reg[:, 3] = -1.0
        data["regions"] = reg
        sw += "A"
    out = triangulate_guarded(data, sw + "Q", "the coarse mesh")
    pts = np.array(out["vertices"], dtype=np.float64)
    pts[: len(vertices)] = vertices  # (as given: see without_subnormals)
    tri = np.asarray(out.get("triangles", np.zeros((0, 3))), dtype=np.int64).reshape(-1, 3)
    if len(tri) == 0:  # (as the serial path says it; Triangle's box.poly: an IndexError before)
        raise MeshingError("Triangle produced no triangles (are all triangles inside holes?)")
    if len(regions):
        row = np.asarray(out["triangle_attributes"]).reshape(-1).round().astype(np.int64)
    else:
        row = np.full(len(tri), -1, np.int64)
    sub = np.asarray(out.get("segments", np.zeros((0, 2))), dtype=np.int64).reshape(-1, 2)
    origin = np.asarray(out.get("segment_markers", np.zeros((0, 1))), dtype=np.int64).reshape(-1) - 1
    return pts, tri, row, sub, origin


class _Sizer:
    """Wanted edge length at any point: min(area-implied, coarse mesh's local size)."""

    def __init__(self, pts: np.ndarray, tri: np.ndarray, tri_area_bound: np.ndarray, shortest: bool = False) -> None:
        from scipy.spatial import cKDTree

        edges = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
        length = np.linalg.norm(pts[edges[:, 0]] - pts[edges[:, 1]], axis=1)
        n = len(pts)
        total = np.bincount(edges.ravel(), weights=np.repeat(length, 2), minlength=n)
        count = np.bincount(edges.ravel(), minlength=n)
        local = np.where(count > 0, total / np.maximum(count, 1), np.inf)
        if shortest:  # the shortest edge at each vertex: the narrowest gap it sees
            local = np.full(n, np.inf)
            np.minimum.at(local, edges.ravel(), np.repeat(length, 2))
        bound = np.full(n, np.inf)
        np.minimum.at(bound, tri.ravel(), np.repeat(tri_area_bound, 3))
        h = np.minimum(EDGE_PER_SQRT_AREA * np.sqrt(bound), local)
        used = np.isfinite(h)
        self.tree = cKDTree(pts[used])
        self.h = h[used]

    def __call__(self, xy: np.ndarray) -> np.ndarray:
        _, i = self.tree.query(np.asarray(xy, dtype=np.float64).reshape(-1, 2))
        return self.h[i]


#: the separators' and pieces' sizes come from a second coarse mesh that has the
#: separators as segments (False: from the first coarse mesh, which knows no separator)
FEATURE_MESH = True
#: pieces meeting at a vertex at an angle below this start with equal subsegments
#: (:func:`_coupled_min`); straighter on, they are not tied
COUPLED_DEG = 160.0
#: pieces meeting nearly straight on start at most this many times longer than the
#: shortest of the others there (session 15): a subsegment 4x its neighbour's on a
#: 168-degree bend of the boundary was encroached by the small triangles its neighbour
#: needs, and ``-Y`` forbade the split (21 degrees on a random domain; halving both
#: in a repair round keeps the ratio, so the rounds never fixed it)
STRAIGHT_RATIO = 1.5
#: most plans made while the caps at the vertices settle (each lowers them)
CAP_PASSES = 12
#: the caps have settled when none drops by more than this fraction (a corner's legs
#: then differ by at most that much; exact settling took 11 plans at 6M triangles)
CAP_SETTLED = 0.05


def _feature_sizer(p: np.ndarray, segs: np.ndarray, lonely: np.ndarray, holes: np.ndarray,
                   min_angle: float | None, max_area: float) -> _Sizer:
    """The size function of the domain *with its separators*: a cut passing close to a
    vertex, or crossing a segment near one of its ends, makes a feature (a narrow gap,
    a short piece) that the first coarse mesh never saw; Triangle's quality mesh of the
    decomposed PSLG grades its edges to it (its local feature size, as Ruppert's
    refinement does), so the pieces and separators there are discretised finely enough
    that no tile needs a point on a segment ``-Y`` keeps unsplit."""
    used = np.unique(np.concatenate([segs.ravel(), lonely]))
    local = np.searchsorted(used, segs)
    pts, tri, _, _, _ = _coarse_mesh(p[used], local, holes, np.zeros((0, 4)), min_angle, max_area)
    return _Sizer(pts, tri, np.full(len(tri), max_area), shortest=True)


# ---------------------------------------------------------------------------- kd split


@dataclass
class _Cut:
    axis: int  # 0: the line x = value; 1: y = value
    value: float
    lo: float
    hi: float
    fixed: list = field(default_factory=list)  # (coordinate along the line, vertex id)


class _Builder:
    """Mutable state of the decomposition while it is built (vertices, pieces, cuts)."""

    def __init__(self, vertices: np.ndarray, segments: np.ndarray, markers: np.ndarray) -> None:
        self.points = [vertices]
        self.n_points = len(vertices)
        self.n_input = len(vertices)
        self.pieces = segments.copy()
        self.piece_origin = np.arange(len(segments), dtype=np.int64)
        self.piece_marker = markers.copy()
        self.cuts: list[_Cut] = []
        #: vertex ids where a cut ends on an earlier cut (a later cut may end there too)
        self.junctions: set[int] = set()

    def coords(self) -> np.ndarray:
        if len(self.points) > 1:
            self.points = [np.concatenate(self.points)]
        return self.points[0]

    def add_points(self, xy: np.ndarray) -> np.ndarray:
        xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        ids = self.n_points + np.arange(len(xy), dtype=np.int64)
        self.points.append(xy)
        self.n_points += len(xy)
        return ids


def _pieces_in_box(b: _Builder, box: np.ndarray) -> np.ndarray:
    p = b.coords()
    mid = 0.5 * (p[b.pieces[:, 0]] + p[b.pieces[:, 1]])
    return np.flatnonzero((mid[:, 0] > box[0]) & (mid[:, 0] < box[1]) & (mid[:, 1] > box[2]) & (mid[:, 1] < box[3]))


def _side_vertices(b: _Builder, box, axis: int, sides) -> tuple[np.ndarray, np.ndarray]:
    """The vertices already on the two box sides a cut along ``axis`` ends on (earlier
    cuts), inside the box's span: their coordinates ``(n, 2)`` and whether each is a
    junction (another cut's end, where this cut may end too)."""
    o = 1 - axis
    xy, junction = [], []
    for side, end in ((sides[2 * o], box[2 * o]), (sides[2 * o + 1], box[2 * o + 1])):
        if side < 0:
            continue
        for pos, vid in b.cuts[side].fixed:
            if vid >= 0 and box[2 * axis] < pos < box[2 * axis + 1]:
                q = np.empty(2)
                q[axis], q[o] = pos, end
                xy.append(q)
                junction.append(vid in b.junctions)
    return np.array(xy, np.float64).reshape(-1, 2), np.array(junction, bool)


def _choose_cut(b: _Builder, box, axis, c_lo, c_hi, c_mid, sizer, min_angle, sides=None) -> tuple[float, bool]:
    """The cut position in [c_lo, c_hi] crossing segments at the largest angles, clear of vertices.

    The vertices on the box's sides where the cut ends count too (session 16): the
    cuts of the two halves of a box were chosen each alone, and on a crack's domain
    they ended 0.001 apart on the cut between them (1.539 and 1.540 with a local size
    of 0.03): a separator piece that short made Triangle grade down to it, and the tiny
    triangles there made the worst of the tile's Hamiltonian output (19.5 deg). A cut
    may end exactly at another cut's end (a crossing of four tiles): those positions
    are candidates, and clear of that vertex."""
    p = b.coords()
    # the vertices a separator must keep clear of: segment ends (the coarse mesh's
    # interior points are no features) and the user's vertices
    feat = np.zeros(len(p), bool)
    feat[b.pieces.ravel()] = True
    feat[: b.n_input] = True
    inside = feat & (p[:, 0] > box[0]) & (p[:, 0] < box[1]) & (p[:, 1] > box[2]) & (p[:, 1] < box[3])
    v = p[inside]
    snap = np.zeros(len(v), bool)
    if sides is not None and SIDE_VERTICES:
        on_side, junction = _side_vertices(b, box, axis, sides)
        v, snap = np.concatenate([v, on_side]), np.concatenate([snap, junction])
    hv = sizer(v) if len(v) else np.zeros(0)
    ends = v[snap, axis]
    cand = np.unique(np.concatenate([np.linspace(c_lo, c_hi, CUT_CANDIDATES), [c_mid],
                                     ends[(ends >= c_lo) & (ends <= c_hi)]]))
    pieces = b.pieces[_pieces_in_box(b, box)]
    a, e = p[pieces[:, 0]], p[pieces[:, 1]]
    d = e - a
    sin_cross = np.abs(d[:, axis]) / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-300)
    need = math.radians(min(90.0, (min_angle or 20.0) + CROSS_MARGIN_DEG))
    best, best_key = c_mid, None
    touch = CUT_TOUCH * float(max(box[1] - box[0], box[3] - box[2]))
    for c in cand:
        gap = np.abs(v[:, axis] - c)
        at_end = snap & (v[:, axis] == c)  # (ending at another cut's end)
        if (gap[~at_end] <= touch).any():
            continue
        clear = np.where(at_end, np.inf, gap / hv) if len(v) else np.array([np.inf])
        clear_min = float(clear.min())
        crossing = (a[:, axis] - c) * (e[:, axis] - c) < 0
        ang = float(np.arcsin(np.clip(sin_cross[crossing].min(), 0, 1))) if crossing.any() else math.pi / 2
        # an angle the mesher cannot meet is fatal; closeness to vertices is repaired
        # by finer separator spacing (and repair rounds), so it only ranks
        key = (ang >= need, min(clear_min / CLEARANCE, 1.0) if ang >= need else ang / need, -abs(c - c_mid))
        if best_key is None or key > best_key:
            best, best_key = float(c), key
    return best, (best_key if best_key is not None else (False, 0.0, 0.0))


def _cut_pieces(b: _Builder, box, axis: int, c: float, cut_id: int) -> None:
    """Split the pieces inside ``box`` that cross the line at ``c``; record crossings."""
    p = b.coords()
    idx = _pieces_in_box(b, box)
    a, e = p[b.pieces[idx, 0]], p[b.pieces[idx, 1]]
    cross = (a[:, axis] - c) * (e[:, axis] - c) < 0
    idx, a, e = idx[cross], a[cross], e[cross]
    if len(idx) == 0:
        return
    o = 1 - axis
    t = (c - a[:, axis]) / (e[:, axis] - a[:, axis])
    xy = np.empty((len(idx), 2))
    xy[:, axis] = c
    xy[:, o] = a[:, o] + t * (e[:, o] - a[:, o])
    ids = b.add_points(xy)
    tail = np.stack([ids, b.pieces[idx, 1]], axis=1)
    b.pieces[idx, 1] = ids
    b.pieces = np.concatenate([b.pieces, tail])
    b.piece_origin = np.concatenate([b.piece_origin, b.piece_origin[idx]])
    b.piece_marker = np.concatenate([b.piece_marker, b.piece_marker[idx]])
    b.cuts[cut_id].fixed.extend(zip(xy[:, o].tolist(), ids.tolist()))


def _kd_split(b: _Builder, root, n_tiles, centroid, weight, sizer, min_angle):
    """Leaves ``(box, sides)``; ``sides[k]``: cut id the box side k lies on (-1: the root)."""
    leaves = []
    stack = [(root, np.array([-1, -1, -1, -1]), n_tiles)]
    while stack:
        box, sides, k = stack.pop()
        if k == 1:
            leaves.append((box, sides))
            continue
        inb = (centroid[:, 0] > box[0]) & (centroid[:, 0] < box[1]) & (centroid[:, 1] > box[2]) & (centroid[:, 1] < box[3])
        cx, w = centroid[inb], weight[inb]
        if len(cx):
            span = cx.max(axis=0) - cx.min(axis=0)
        else:
            span = np.array([box[1] - box[0], box[3] - box[2]])
        axis = 0 if span[0] >= span[1] else 1
        k1 = k // 2
        if len(cx) == 0 or w.sum() <= 0:
            c_lo = c_hi = c_mid = 0.5 * (box[2 * axis] + box[2 * axis + 1])
            c_lo, c_hi = box[2 * axis] + 0.4 * (box[2 * axis + 1] - box[2 * axis]), box[2 * axis] + 0.6 * (box[2 * axis + 1] - box[2 * axis])
        else:
            order = np.argsort(cx[:, axis], kind="stable")
            xs, cw = cx[order, axis], np.cumsum(w[order])
            total = cw[-1]

            def at(f):
                return float(np.interp(f * total, cw, xs))

            f = k1 / k
            c_mid = at(f)
            c_lo, c_hi = at(max(f - CUT_WINDOW, 0.02)), at(min(f + CUT_WINDOW, 0.98))
            # no good position near the balanced one: look further, then across the
            # other axis (balance costs less than an angle the mesher cannot meet)
            c, key = _choose_cut(b, box, axis, c_lo, c_hi, c_mid, sizer, min_angle, sides)
            for wider in WIDER_WINDOWS:
                if key[0] and key[1] >= WIDEN_BELOW:  # (a cut too close to a vertex makes a sliver tile)
                    break
                for ax in (axis, 1 - axis):
                    order = np.argsort(cx[:, ax], kind="stable")
                    xs, cw = cx[order, ax], np.cumsum(w[order])
                    mid = float(np.interp(f * total, cw, xs))
                    lo_, hi_ = (float(np.interp(max(f - wider, 0.02) * total, cw, xs)),
                                float(np.interp(min(f + wider, 0.98) * total, cw, xs)))
                    c2, key2 = _choose_cut(b, box, ax, lo_, hi_, mid, sizer, min_angle, sides)
                    if key2[:2] > key[:2]:
                        c, axis, key = c2, ax, key2
        if len(cx) == 0 or w.sum() <= 0:
            c, _ = _choose_cut(b, box, axis, c_lo, c_hi, c_mid, sizer, min_angle, sides)
        o = 1 - axis
        cut = _Cut(axis, c, float(box[2 * o]), float(box[2 * o + 1]))
        b.cuts.append(cut)
        cut_id = len(b.cuts) - 1
        # the cut's ends on earlier cuts are junctions: one vertex on both lines
        for end, side in ((cut.lo, sides[2 * o]), (cut.hi, sides[2 * o + 1])):
            if side >= 0:
                # (another cut's end at the same place: one vertex, four tiles around it)
                there = [vid for pos, vid in b.cuts[side].fixed if pos == c and vid in b.junctions]
                if there:
                    cut.fixed.append((end, there[0]))
                    continue
                xy = np.empty(2)
                xy[axis], xy[o] = c, end
                vid = int(b.add_points(xy)[0])
                b.junctions.add(vid)
                cut.fixed.append((end, vid))
                b.cuts[side].fixed.append((c, vid))
            else:
                cut.fixed.append((end, -1))
        _cut_pieces(b, box, axis, c, cut_id)
        low, high = box.copy(), box.copy()
        low[2 * axis + 1] = c
        high[2 * axis] = c
        s_low, s_high = sides.copy(), sides.copy()
        s_low[2 * axis + 1] = cut_id
        s_high[2 * axis] = cut_id
        stack.append((high, s_high, k - k1))
        stack.append((low, s_low, k1))
    return leaves


# ---------------------------------------------------------------------------- separators


def _line_cover(ptsc: np.ndarray, tric: np.ndarray, axis: int, c: float) -> np.ndarray:
    """Merged intervals (along the line) where the line ``axis = c`` is inside the coarse mesh.

    A coarse edge lying on the line counts too (session 17): the coarse mesh's
    Steiner points can sit exactly on a cut (a point at (0, 0) between an inner
    loop's vertices at (+-0.207, 0), the cut at y = 0), and the triangles on either
    side only touch the line there; before, that stretch was taken for outside the
    domain, no separator was made on it, and Triangle ate the loop's inside from one
    tile's hull (the union's check failed: a separator edge in one tile only)."""
    o = 1 - axis
    P_all = ptsc[tric]  # (t, 3, 2)
    lo_ax, hi_ax = P_all[:, :, axis].min(axis=1), P_all[:, :, axis].max(axis=1)
    hit = (lo_ax < c) & (hi_ax > c)
    on = P_all[:, :, axis] == c
    flat = (on.sum(axis=1) == 2) & LINE_EDGES  # (one edge on the line: its interval)
    E = P_all[flat][on[flat]].reshape(-1, 2, 2)[:, :, o]
    P = P_all[hit]
    if len(P) == 0 and len(E) == 0:
        return np.zeros((0, 2))
    lo = np.full(len(P), np.inf)
    hi = np.full(len(P), -np.inf)
    for k in range(3):
        p, q = P[:, k], P[:, (k + 1) % 3]
        s = (p[:, axis] - c) * (q[:, axis] - c) <= 0
        den = q[:, axis] - p[:, axis]
        s &= den != 0
        t = np.where(s, (c - p[:, axis]) / np.where(den == 0, 1.0, den), 0.0)
        val = p[:, o] + t * (q[:, o] - p[:, o])
        lo = np.where(s, np.minimum(lo, val), lo)
        hi = np.where(s, np.maximum(hi, val), hi)
    lo, hi = np.concatenate([lo, E.min(axis=1)]), np.concatenate([hi, E.max(axis=1)])
    order = np.argsort(lo)
    lo, hi = lo[order], hi[order]
    run_hi = np.maximum.accumulate(hi)
    tol = 1e-12 * max(1.0, float(np.abs(P_all[hit | flat]).max()))
    start = np.concatenate([[True], lo[1:] > run_hi[:-1] + tol])
    first = np.flatnonzero(start)
    last = np.concatenate([first[1:] - 1, [len(lo) - 1]])
    return np.stack([lo[first], run_hi[last]], axis=1)


def _covered(intervals: np.ndarray, x: np.ndarray) -> np.ndarray:
    if len(intervals) == 0:
        return np.zeros(len(x), bool)
    i = np.searchsorted(intervals[:, 0], x, side="right") - 1
    ok = i >= 0
    return ok & (x < intervals[np.maximum(i, 0), 1]) & (x > intervals[np.maximum(i, 0), 0])


#: :func:`_plan` keeps the sizes it sampled on each piece (``memo``) and samples again
#: only the pieces whose sample count changed (False: every pass samples every piece)
PLAN_MEMO = True


def _sample_sizes(xy: np.ndarray, seg: np.ndarray, axis: np.ndarray, a: np.ndarray, sizer, obstacles) -> np.ndarray:
    """The wanted size at sample points ``xy`` of pieces ``seg``: the sizer's, and on a
    separator at most ``OBSTACLE_FACTOR`` times the distance to the nearest vertex off
    its line."""
    h = sizer(xy)
    on_axis = axis[seg] >= 0
    if obstacles is not None and on_axis.any():
        q = np.flatnonzero(on_axis)
        dist, nb = obstacles.query(xy[q], k=4)
        nb = np.minimum(nb, len(obstacles.data) - 1)
        ax = axis[seg[q]]
        pts = obstacles.data[nb]  # (q, 4, 2)
        own = np.take_along_axis(pts, ax[:, None, None].repeat(4, 1), axis=2)[..., 0]
        line = a[seg[q], ax]
        dist = np.where((own != line[:, None]) & np.isfinite(dist), dist, np.inf).min(axis=1)
        h[q] = np.minimum(h[q], OBSTACLE_FACTOR * dist)
    return h


def vertex_end_pairs(p: np.ndarray, segs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every pair of segment ends meeting at a vertex: two arrays of indices into
    ``segs.ravel()`` (end ``2 r + side`` of row ``r``) and whether the two meet at an
    angle below ``COUPLED_DEG`` (a corner; else nearly straight on)."""
    v = segs.ravel()
    other = segs[:, ::-1].ravel()
    d = p[other] - p[v]
    d /= np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-300)[:, None]
    order = np.argsort(v, kind="stable")
    vs, ds = v[order], d[order]
    cos_lim = math.cos(math.radians(COUPLED_DEG))
    first, second, corner = [], [], []
    k = 1
    while k < len(vs) and (vs[k:] == vs[:-k]).any():
        i = np.flatnonzero(vs[k:] == vs[:-k])
        first.append(order[i])
        second.append(order[i + k])
        corner.append((ds[i + k] * ds[i]).sum(axis=1) > cos_lim)
        k += 1
    if not first:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, bool)
    return np.concatenate(first), np.concatenate(second), np.concatenate(corner)


def coupled_ends(p: np.ndarray, segs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pairs of segment ends meeting at a vertex at an angle below ``COUPLED_DEG``
    (:func:`vertex_end_pairs`).

    Where two pieces meet at a corner, the tile's triangle at that corner has both
    first subsegments as sides: legs more than ``tan(60 deg)`` apart at a right angle
    make it too thin, and ``-Y`` forbids the split that would repair it. Nearly
    straight on (a polygon's arc, a chain of the coarse mesh's subsegments) they are
    not coupled: a short end does not ripple along the whole chain (they are bounded
    by ``STRAIGHT_RATIO`` instead, :func:`_coupled_min`).
    """
    i, j, corner = vertex_end_pairs(p, segs)
    return i[corner], j[corner]


def _coupled_min(p: np.ndarray, segs: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """For every end of every piece, the shortest ``ends`` of the *other* pieces meeting
    it at that vertex at an angle below ``COUPLED_DEG`` (:func:`coupled_ends`), and
    ``STRAIGHT_RATIO`` times those meeting it nearly straight on (inf: none).

    ``ends`` (S, 2): a length at each end of each piece.
    """
    val = ends.ravel()
    out = np.full(len(val), np.inf)
    i, j, corner = vertex_end_pairs(p, segs)
    factor = np.where(corner, 1.0, STRAIGHT_RATIO)
    np.minimum.at(out, i, factor * val[j])
    np.minimum.at(out, j, factor * val[i])
    return out.reshape(-1, 2)


def _plan(p: np.ndarray, segs: np.ndarray, sizer, caps: np.ndarray, obstacles,
          memo: dict | None = None) -> list[np.ndarray]:
    """Stations of the new points on every segment ``(a, b)`` (graded, capped at the ends).

    On a separator (axis-parallel) the size is also at most ``OBSTACLE_FACTOR`` times
    the distance to the nearest vertex off its line: a longer subsegment would have
    that vertex in its diametral circle (encroached), and ``-Y`` forbids the split
    that Delaunay refinement would make. All pieces are sampled at once; a piece whose
    sizes turn out finer than its sampling is sampled again at their scale.

    ``memo`` (a dict, empty at first, then passed again with the same points, pieces,
    sizer and obstacles): the sizes sampled on each piece, by its sample count. A
    piece sampled again at the same count has the same sample points, hence the same
    sizes: they are taken from the memo (the size queries were ~60 % of the
    decomposition at 6M triangles, the three plans sampling mostly the same ~60k
    points; every result is the same, tested).
    """
    a, e = p[segs[:, 0]], p[segs[:, 1]]
    d = e - a
    length = np.hypot(d[:, 0], d[:, 1])
    axis = np.where(d[:, 0] == 0, 0, np.where(d[:, 1] == 0, 1, -1))
    h0 = np.minimum(np.minimum(sizer(a), sizer(e)), caps.min(axis=1))
    m = np.clip(np.ceil(4.0 * length / np.maximum(h0, 1e-300)), 2, MAX_SAMPLES_PER_PIECE).astype(np.int64)
    live = length > 0
    for _ in range(3):
        idx = np.flatnonzero(live)
        first = np.cumsum(m[idx] + 1) - (m[idx] + 1)  # each live piece's first sample
        seg = np.repeat(idx, m[idx] + 1)
        start = np.repeat(first, m[idx] + 1)
        frac = (np.arange(len(seg)) - start) / np.repeat(m[idx], m[idx] + 1)
        st = frac * length[seg]
        xy = a[seg] + frac[:, None] * d[seg]
        if memo is not None and "m" in memo:
            hit = np.repeat(memo["m"][idx] == m[idx], m[idx] + 1)
            h = np.empty(len(seg))
            h[hit] = memo["h"][memo["first"][seg[hit]] + (np.arange(len(seg)) - start)[hit]]
            miss = ~hit
            if miss.any():
                h[miss] = _sample_sizes(xy[miss], seg[miss], axis, a, sizer, obstacles)
        else:
            h = _sample_sizes(xy, seg, axis, a, sizer, obstacles)
        if memo is not None:
            memo["m"] = np.full(len(segs), -1, np.int64)
            memo["m"][idx] = m[idx]
            memo["first"] = np.zeros(len(segs), np.int64)
            memo["first"][idx] = first
            memo["h"] = h
        hmin = np.full(len(segs), np.inf)
        np.minimum.at(hmin, seg, h)
        spacing = length / np.maximum(m, 1)
        coarse = live & (spacing > 0.5 * hmin) & (m < MAX_SAMPLES_PER_PIECE)
        if not coarse.any():
            break
        m[coarse] = np.clip(np.ceil(4.0 * length[coarse] / np.maximum(hmin[coarse], 1e-300)), 2,
                            MAX_SAMPLES_PER_PIECE).astype(np.int64)
    out, owner = graded_points_many(length, st, seg, h, caps[:, 0], caps[:, 1])
    plans = [np.zeros(0)] * len(segs)
    if len(owner):
        cut = np.flatnonzero(np.diff(owner)) + 1
        for grp in np.split(np.arange(len(owner)), cut):
            plans[int(owner[grp[0]])] = out[grp]
    return plans


def _end_lengths(segs: np.ndarray, plans: list[np.ndarray], length: np.ndarray) -> np.ndarray:
    """(S, 2): the planned first and last subsegment of every piece."""
    first = np.array([st[0] if len(st) else L for st, L in zip(plans, length)]).reshape(-1)
    last = np.array([L - st[-1] if len(st) else L for st, L in zip(plans, length)]).reshape(-1)
    return np.stack([first, last], axis=1).reshape(-1, 2)


def _commit(b: _Builder, segs: np.ndarray, plans: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Add the planned points; the new segments and the row each came from."""
    p = b.coords()
    out, rows, new_xy = [], [], []
    next_id = b.n_points
    for r, ((u, v), st) in enumerate(zip(segs.tolist(), plans)):
        if len(st) == 0:
            out.append((u, v))
            rows.append(r)
            continue
        a, e = p[u], p[v]
        d = e - a
        length = float(math.hypot(d[0], d[1]))
        xy = a + np.outer(st / length, d)
        for k in (0, 1):  # a separator keeps its constant coordinate exactly
            if a[k] == e[k]:
                xy[:, k] = a[k]
        ids = next_id + np.arange(len(st))
        next_id += len(st)
        new_xy.append(xy)
        chain = np.concatenate([[u], ids, [v]])
        out.extend(zip(chain[:-1].tolist(), chain[1:].tolist()))
        rows.extend([r] * (len(chain) - 1))
    if new_xy:
        b.add_points(np.concatenate(new_xy))
    return np.asarray(out, np.int64).reshape(-1, 2), np.asarray(rows, np.int64)


# ---------------------------------------------------------------------------- decompose


def check_bounds(min_angle: float | None, max_area: float | None) -> None:
    """The quality bounds of parallel meshing checked as :func:`hammesh.quality_mesh`
    checks them (``MeshOptions``: finite numbers, ``0 <= min_angle <= MAX_MIN_ANGLE``,
    ``max_area > 0``), and ``max_area`` required: it sets the separators' spacing."""
    if max_area is None:
        raise InvalidOptionError("parallel meshing needs max_area (-a): it sets the separators' spacing")
    MeshOptions(min_angle=min_angle, max_area=max_area)


def decompose(domain: Domain, *, min_angle: float | None, max_area: float, n_tiles: int) -> Decomposition:
    """Cut ``domain`` into ``n_tiles`` tiles that Triangle meshes alone into a conforming union.

    Parameters
    ----------
    domain : Domain
    min_angle : float or None
        Degrees, as :func:`hammesh.quality_mesh`.
    max_area : float
        Global area bound (required: it sets the separators' spacing).
    n_tiles : int
        Number of tiles (>= 1).

    Returns
    -------
    Decomposition

    Raises
    ------
    InvalidOptionError
        No ``max_area``, or regional area bounds (not supported by the tiles yet).
    """
    check_bounds(min_angle, max_area)
    if not (isinstance(n_tiles, (int, np.integer)) and n_tiles >= 1):
        raise InvalidOptionError(f"tiles must be a positive integer, got {n_tiles!r}")
    regions = np.asarray(domain.regions, dtype=np.float64).reshape(-1, 4)
    if len(regions) and np.isfinite(regions[:, 3]).any():
        raise InvalidOptionError(
            "regional area bounds are not supported by parallel meshing yet; mesh without --workers"
        )
    verts = np.array(domain.vertices, dtype=np.float64)  # writable copies: Triangle's buffers
    segs = np.array(domain.segments, dtype=np.int64).reshape(-1, 2)
    markers = np.array(domain.segment_markers, dtype=np.int64).reshape(-1)
    if len(segs) == 0:  # Triangle's "pc": the convex hull is the domain's boundary
        segs = _hull_segments(verts)
        markers = np.ones(len(segs), np.int64)
    holes = np.array(domain.holes, dtype=np.float64).reshape(-1, 2)
    ptsc, tric, rowc, sub, sub_origin = _coarse_mesh(verts, segs, holes, regions, min_angle, float(max_area))
    if not np.array_equal(ptsc[: len(verts)], verts):
        raise InvalidOptionError("Triangle did not keep the domain's vertices in order")
    # user segments eaten by holes are not in the coarse mesh's output: segments of
    # the domain's own outline and interior are, as Triangle's graded subsegments
    segs, markers = sub, markers[np.clip(sub_origin, 0, len(markers) - 1)]
    area_c = _tri_area(ptsc, tric)
    bound_c = np.full(len(tric), float(max_area))
    sizer = _Sizer(ptsc, tric, bound_c)
    weight = area_c / (AREA_FILL * bound_c)
    most = max(1, int(weight.sum() // MIN_TILE_TRIANGLES))
    if n_tiles > most:  # (the separators of tiles this small outnumber their triangles: up to 692x)
        raise InvalidOptionError(
            f"tiles={int(n_tiles)} is too many for this domain: about {weight.sum():,.0f} triangles, at most "
            f"{most} tile(s) of {MIN_TILE_TRIANGLES} or more", option="tiles")
    centroid = ptsc[tric].mean(axis=1)

    b = _Builder(ptsc, segs, markers)
    b.n_input = len(verts)
    b.piece_origin = sub_origin.copy()
    lo, hi = verts.min(axis=0), verts.max(axis=0)
    pad = 0.01 * max(float((hi - lo).max()), 1e-300)
    root = np.array([lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad])
    leaves = _kd_split(b, root, int(n_tiles), centroid, weight, sizer, min_angle)

    # separators: the parts of each cut inside the domain, between consecutive fixed points
    p = b.coords()
    sep = []
    for cut in b.cuts:
        fixed = sorted(cut.fixed)
        cover = _line_cover(ptsc, tric, cut.axis, cut.value)
        coords = np.array([f[0] for f in fixed])
        mids = 0.5 * (coords[1:] + coords[:-1])
        inside = _covered(cover, mids)
        for j in np.flatnonzero(inside):
            u, v = fixed[j][1], fixed[j + 1][1]
            if u < 0 or v < 0:
                continue  # reaches the padded root box: cannot be inside
            sep.append((u, v))
    sep = np.asarray(sep, np.int64).reshape(-1, 2)

    # caps at every vertex: the shortest piece or separator part meeting it
    p = b.coords()
    allsegs = np.concatenate([b.pieces, sep])
    length = np.linalg.norm(p[allsegs[:, 0]] - p[allsegs[:, 1]], axis=1)
    caps = _coupled_min(p, allsegs, np.repeat(length[:, None], 2, axis=1))
    # plan, then plan again with every vertex's ends capped at the shortest subsegment
    # meeting it: where a separator crosses a segment both start equally short
    from scipy.spatial import cKDTree

    lonely_user = np.ones(len(p), bool)
    lonely_user[segs.ravel()] = False
    lonely_user = lonely_user[: len(verts)]
    if len(sep) and FEATURE_MESH:
        sizer = _feature_sizer(p, allsegs, np.flatnonzero(lonely_user), holes, min_angle, float(max_area))
    obstacles = cKDTree(np.concatenate([p[np.unique(b.pieces)], verts[lonely_user]]))
    memo = {} if PLAN_MEMO else None  # (the sizes sampled on each piece, for the next plans)
    # until the caps settle: a short piece split evenly may end shorter than its cap,
    # and the pinned ends of its neighbours (graded_points_many) must follow it
    for _ in range(CAP_PASSES):
        plans = _plan(p, allsegs, sizer, caps, obstacles, memo)
        settled = np.minimum(caps, _coupled_min(p, allsegs, _end_lengths(allsegs, plans, length)))
        if np.all(settled >= caps * (1 - CAP_SETTLED)):
            break
        caps = settled
    new, rows = _commit(b, allsegs, plans)
    is_user_row = rows < len(b.pieces)
    user_new, user_rows = new[is_user_row], rows[is_user_row]
    sep_new = new[~is_user_row]
    p = b.coords()
    segments = np.concatenate([user_new, sep_new])
    is_sep = np.concatenate([np.zeros(len(user_new), bool), np.ones(len(sep_new), bool)])
    origin = np.concatenate([b.piece_origin[user_rows], np.full(len(sep_new), -1, np.int64)])
    seg_marker = np.concatenate([b.piece_marker[user_rows], np.zeros(len(sep_new), np.int64)])

    boxes = [box for box, _ in leaves]
    tiles = _make_tiles(p, segments, is_sep, seg_marker, boxes, len(verts), holes, ptsc, tric, rowc, regions,
                        centroid, weight)
    cuts = np.array([[c.axis, c.value, c.lo, c.hi] for c in b.cuts]).reshape(-1, 4)
    return Decomposition(
        vertices=p, n_input=len(verts), segments=segments, separator=is_sep, origin=origin,
        tiles=tuple(tiles), area=float(area_c.sum()), cuts=cuts, estimate=float(weight.sum()),
        min_angle=None if min_angle is None else float(min_angle), max_area=float(max_area),
        coarse_points=ptsc, coarse_triangles=tric, coarse_region=rowc, regions=regions,
        holes=holes, segment_markers=seg_marker,
    )


def _make_tiles(p, segments, is_sep, seg_marker, boxes, n_input, holes, ptsc, tric, rowc, regions,
                centroid=None, weight=None) -> list[Tile]:
    """Each box's tile: the segments whose midpoint lies in the (closed) box."""
    if weight is None:
        centroid = ptsc[tric].mean(axis=1)
        weight = np.zeros(len(tric))
    mid = 0.5 * (p[segments[:, 0]] + p[segments[:, 1]])
    on_seg = np.zeros(len(p), bool)
    on_seg[segments.ravel()] = True
    lonely = np.flatnonzero(~on_seg[:n_input])  # the user's vertices on no segment
    P = ptsc[tric]
    tiles = []
    for i, box in enumerate(boxes):
        sel = (mid[:, 0] >= box[0]) & (mid[:, 0] <= box[1]) & (mid[:, 1] >= box[2]) & (mid[:, 1] <= box[3])
        lv = lonely[(p[lonely, 0] > box[0]) & (p[lonely, 0] < box[1]) & (p[lonely, 1] > box[2]) & (p[lonely, 1] < box[3])]
        ids = np.unique(np.concatenate([segments[sel].ravel(), lv]))
        local = np.searchsorted(ids, segments[sel])
        hsel = (holes[:, 0] >= box[0]) & (holes[:, 0] <= box[1]) & (holes[:, 1] >= box[2]) & (holes[:, 1] <= box[3])
        inb = (centroid[:, 0] > box[0]) & (centroid[:, 0] < box[1]) & (centroid[:, 1] > box[2]) & (centroid[:, 1] < box[3])
        over = ((P[:, :, 0].max(axis=1) >= box[0]) & (P[:, :, 0].min(axis=1) <= box[1])
                & (P[:, :, 1].max(axis=1) >= box[2]) & (P[:, :, 1].min(axis=1) <= box[3]))
        used, inv = np.unique(tric[over], return_inverse=True)
        extra = dict(coarse_points=ptsc[used], coarse_triangles=inv.reshape(-1, 3))
        if len(regions):
            attr = np.where(rowc[over] >= 0, regions[np.clip(rowc[over], 0, None), 2], 0.0)
            extra.update(region_points=extra["coarse_points"], region_triangles=extra["coarse_triangles"],
                         region_attribute=attr)
        tiles.append(Tile(
            index=i, box=box, vertex_ids=ids, vertices=p[ids], segments=local.astype(np.int64),
            segment_markers=seg_marker[sel], separator=is_sep[sel], holes=holes[hsel],
            estimate=float(weight[inb].sum()), **extra,
        ))
    return tiles


def split_segments(decomp: Decomposition, rows: np.ndarray) -> tuple[Decomposition, np.ndarray]:
    """Split the decomposition's segments ``rows`` at their midpoints.

    Used where a tile's Triangle run could not meet the min angle next to a segment
    it was not allowed to split (``-Y``): both tiles along a separator get the same
    new point. Returns the new decomposition and the indices of the tiles that changed.
    """
    rows = np.unique(np.asarray(rows, dtype=np.int64))
    p = decomp.vertices
    seg = decomp.segments
    a, e = p[seg[rows, 0]], p[seg[rows, 1]]
    mid = 0.5 * (a + e)
    for k in (0, 1):
        same = a[:, k] == e[:, k]
        mid[same, k] = a[same, k]
    ids = len(p) + np.arange(len(rows), dtype=np.int64)
    tail = np.stack([ids, seg[rows, 1]], axis=1)
    seg2 = seg.copy()
    seg2[rows, 1] = ids
    segments = np.concatenate([seg2, tail])
    is_sep = np.concatenate([decomp.separator, decomp.separator[rows]])
    origin = np.concatenate([decomp.origin, decomp.origin[rows]])
    marker = np.concatenate([decomp.segment_markers, decomp.segment_markers[rows]])
    points = np.concatenate([p, mid])
    boxes = [t.box for t in decomp.tiles]
    tiles = _make_tiles(points, segments, is_sep, marker, boxes, decomp.n_input, decomp.holes,
                        decomp.coarse_points, decomp.coarse_triangles, decomp.coarse_region, decomp.regions)
    changed = []
    for i, (old, new) in enumerate(zip(decomp.tiles, tiles)):
        if len(old.segments) != len(new.segments):
            changed.append(i)
        tiles[i] = replace(new, estimate=old.estimate)
    out = replace(decomp, vertices=points, segments=segments, separator=is_sep, origin=origin,
                  segment_markers=marker, tiles=tuple(tiles))
    return out, np.asarray(changed, dtype=np.int64)
