"""A cycle cover of the dual graph: vertex-disjoint cycles through most triangles.

Gopi & Eppstein (*Single-strip triangulation of manifolds with arbitrary topology*,
2004): in a cubic graph the edges outside a perfect matching form a 2-factor (disjoint
cycles through every vertex). The dual graph of a mesh with boundary has degrees 1-3;
here ears (and what peeling them leaves) stay uncovered, the degree-3 triangles are
matched among themselves, the rest of the dual edges are the cover, and the few
defects a maximum matching leaves are repaired locally (see
``_cover_kernels.finish_matching``, ``settle_cover``). Everything is O(m) in numba; the augmenting searches
are bounded by ``budget`` labelled triangles each. Finally cycles are merged for free
where the matching can be rotated around a vertex (``rotate``), and, on small meshes
with sparse mode's ``good`` edges, where re-colouring a few vertices inside / outside
the cycles merges or moves a node that has no good join (``_recolour_kernels``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from functools import partial
from typing import Callable, NamedTuple

import numpy as np

from hammesh import threads
from hammesh.pages import fresh, reserved
from hammesh.halfedge.locality import grid_frame
from hammesh.postprocess import _cover_kernels as _k
from hammesh.postprocess.sparse_cells import confine
from hammesh.postprocess import _join_kernels as _j
from hammesh.postprocess import _recolour_kernels as _rk
from hammesh.postprocess._thm24_kernels import CELL_BITS, quadtree_coords
from hammesh.threads import row_ranges, run_all

__all__ = [
    "CycleCover", "cycle_cover", "join_classes", "ONLINE_BUDGET", "ONLINE_MIN_TRIANGLES", "CELL_SIZE",
    "DEFECT_SEARCH_BUDGET", "DROP_BUDGET", "DROP_ROUNDS", "cycle_ids_by_halves", "CHAIN_COST", "GUIDE_WEIGHT",
    "GUIDE_MIN_TRIANGLES", "JoinRule", "defect_cut", "RECOLOUR_BELOW", "RECOLOUR_SET", "RECOLOUR_NODE", "RECOLOUR_CANDIDATES",
    "corner_angle", "lone_join_bound",
]

#: Triangles per quadtree cell that the cover's cycles are confined to by default
#: (``cycle_cover(..., points=)``); 0: not confined. Off by default: measured at
#: 100k triangles (docs/sparse.md) confinement cut the sparse cycle's k = 64 edge cut
#: from 2.1-2.2x METIS's to 1.8-2.0x only, for 1.1-1.6x the Steiner points.
CELL_SIZE = 0

#: Triangles the searches from a parity defect may label (``_cover_kernels._drop_matching``):
#: a longer augmenting search first, then one that may drop an interior triangle; and
#: how many times a defect a drop moves may be searched from again. Measured at 1.5 M
#: triangles (32 defects; loaded): searches of 20 k / 20 k / 100 k triangles then drop
#: searches of 20 k / 100 k / 100 k leave 122 / 34 / 12 triangles uncovered, the rest
#: going to chains of boundary triangles. One round fixes what two did (the 16k corpus
#: and 1.5 M: the same cover; round 0 alone leaves 82 uncovered on the corpus, not 62).
#: Session 20: the first (plain) search of 10 k, not 100 k. On the lattice tiles of
#: ``hammesh.parallel`` (98 % equilateral triangles: a bipartite dual, where a defect's
#: partner is often beyond any search) the failed 100 k searches were a third of
#: sparse ``hamiltonian()``'s CPU: four 0.75 M tiles of the 6M demo, one thread, the cover
#: 1.40-1.99 -> 0.70-0.78 s, the call 3.04-3.95 -> 2.22-2.47 s, uncovered 697 -> 748,
#: Steiner points 819 -> 864, min angle 24.83 deg both; the DROP search finds what the
#: plain one gave up on nearby. 1.5 M (bench_core's mesh): uncovered 11 -> 15, Steiner
#: points 4,596 -> 4,598, angles the same; the 16k corpus (``bench_sparse.py --angles``)
#: unchanged, line for line. 5 k: the same on the tiles, two corpus meshes moved.
DEFECT_SEARCH_BUDGET = 10_000
DROP_BUDGET = 100_000
DROP_ROUNDS = 1

#: The chain searches between the last parity defects (``_cover_kernels._chain_matching``)
#: are A* searches towards the nearest other free triangle when the points are known:
#: a step of the alternating tree costs 1, each triangle of a chain it steps through
#: (left uncovered if the path is taken) ``CHAIN_COST``, and the distance to the goal
#: counts ``GUIDE_WEIGHT`` steps per mean edge length of the start triangle.
#: Breadth-first, a chain was one step whatever its length, and a search from a
#: corner explored a disc reaching the nearest other defect (150-630 k triangles at
#: 1.5 M); counting only the distance (no chain cost), the paths ran along the
#: chains of thin strokes (Triangle's ``A`` at 16 k: 26 -> 76 uncovered).
CHAIN_COST = 20.0
GUIDE_WEIGHT = 1.25
#: Meshes from this size on guide the chain searches; below it a breadth-first search
#: costs little, and its chains are kept: guided at 16 k, Triangle's ``A`` lost its
#: angle target (24.1 deg out, 27.0 wanted; 13 uncovered instead of 26, but chains
#: whose joins cost more).
GUIDE_MIN_TRIANGLES = 100_000

#: Triangles an augmenting search started by the greedy matching may label (``online``).
ONLINE_BUDGET = 256
#: Meshes from this size on use the breadth-first greedy with online searches by
#: default; below it the searches cost little either way and the matching of
#: Triangle's numbering is kept (the small meshes' figures stay as they were).
ONLINE_MIN_TRIANGLES = 100_000

#: Below this many triangles (and with ``good`` edges), nodes of the cover that have no
#: non-cover edge whose join keeps the local rule (cycles of at most ``RECOLOUR_NODE``
#: triangles, uncovered triangles) are merged into others, or moved (``RECOLOUR_SHIFT``
#: 2: leaving at most one node more, each with a join that keeps the rule once placed),
#: where re-colouring a connected set of up to ``RECOLOUR_SET`` of the
#: ``RECOLOUR_CANDIDATES`` vertices nearest them allows (``_recolour_kernels``: the cover
#: swapped along the dual cycle around those vertices, the mesh unchanged), in at most
#: ``RECOLOUR_ROUNDS`` passes; a moved node's new cycles longer than
#: ``RECOLOUR_LONG_WALK`` triangles are taken to have a good join (not walked). Measured
#: (docs/sparse.md, session 14): the 16 k corpus of ``bench_sparse.py`` at the same CPU,
#: rows below the parents' rule 209 -> 65, Steiner points 358 -> 115; the plate at 90 k
#: 318 -> 58 points but 0.21 -> 0.83 s CPU (each move taken re-walks the big cycle), so
#: the gate is where the cover's other small-mesh extras stop (``sparse.ALT_POSITIONS_BELOW``);
#: the 1.5 M path is unchanged.
RECOLOUR_BELOW = 25_000
RECOLOUR_SET = 3
RECOLOUR_NODE = 64
RECOLOUR_CANDIDATES = 64
RECOLOUR_ROUNDS = 3
RECOLOUR_SHIFT = 2
RECOLOUR_LONG_WALK = 25_000


def corner_angle(pts: np.ndarray, tri: np.ndarray, t: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Angle (radians) at corner ``k`` of triangles ``t`` (2D or 3D points)."""
    p, q, r = pts[tri[t, k]], pts[tri[t, (k + 1) % 3]], pts[tri[t, (k + 2) % 3]]
    u, v = q - p, r - p
    if pts.shape[1] == 2:
        cross = np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
    else:
        cross = np.linalg.norm(np.cross(u, v), axis=1)
    return np.arctan2(cross, (u * v).sum(axis=1))


def lone_join_bound(t_corner: np.ndarray, u_opp: np.ndarray, inner: np.ndarray) -> np.ndarray:
    """What any join can keep at best at a triangle the cover leaves off alone (every
    neighbour covered), radians, per row: a join over edge ``k`` (a swap, or a split
    with its point anywhere in the quadrilateral) divides the two corners opposite it,
    the triangle's (``t_corner[:, k + 2]``) and the neighbour's (``u_opp[:, k]``), so one
    of its angles is at most half the smaller; a bridge splits the triangle at its
    incenter, halving every corner. ``t_corner`` (r, 3): the triangle's corners;
    ``u_opp`` (r, 3): the neighbour's corner opposite each edge (any value where
    ``inner`` (r, 3) is False: a boundary edge, no join over it). Shared by sparse
    mode's report (``sparse.join_bounds``) and the comb cover's choice of where to
    grow (``comb_cover.lone_join_bounds``)."""
    t_opp = t_corner[:, [2, 0, 1]]  # the corner opposite edge k (from corner k to k + 1) is k + 2
    per_edge = np.where(inner, 0.5 * np.minimum(t_opp, u_opp), 0.0)
    return np.maximum(per_edge.max(axis=1), 0.5 * t_corner.min(axis=1))


class JoinRule(NamedTuple):
    """Sparse mode's local quality rule, for the cover's re-colouring step (planar):
    with it, an edge whose split meets the rule once its point is placed counts as
    a good join there too (``_join_kernels.placed_good_into``), as Kruskal will see it."""

    amin: np.ndarray  # (m,) float64: each triangle's smallest angle, radians
    keep: float  # the rule's factor
    hi: float  # the largest angle allowed, radians
    pinned: np.ndarray  # (3 m,) bool: constrained half-edges (split only at their midpoint)
    swaps: bool = True  # joins by swaps allowed (``judge``: what a good edge may be)
    edge_splits: bool = True  # joins by edge splits allowed
    corners: np.ndarray | None = None  # (m, 3) float32: the corner angles, if known (``judge``'s first test)


@dataclass(frozen=True, eq=False)
class CycleCover:
    """Cycles of the dual graph.

    Attributes
    ----------
    is_cov : (3 m,) bool
        Half-edges whose dual edge is on a cover cycle (symmetric under ``twin``);
        every covered triangle has exactly two.
    cycle : (m,) int64
        Cycle id of each triangle, -1 for an uncovered one.
    n_cycles : int
    n_uncovered : int
    n_unmatched : int
        Degree-3 triangles the matching left free (before the local repair).
    n_rotations : int
        Cycles merged away by re-matching around vertices.
    n_recoloured : int
        Nodes (cycles, uncovered triangles) merged away by re-colouring vertices
        (``_recolour_kernels.recolour_merges``); counted in ``n_rotations`` too.
    n_recolour_shifts : int
        Nodes moved by re-colouring instead (each leaves at most one node more).
    n_dropped : int
        Interior (degree-3) triangles left uncovered to fix the matching's parity
        defects, instead of chains of boundary triangles (``drop``).
    quad : (m,) int64 or None
        Packed quadtree coordinates of each triangle (``_thm24_kernels.quadtree_coords``)
        when the cycles were confined to cells: ``join_classes`` orders the joins by them.
    """

    is_cov: np.ndarray
    cycle: np.ndarray
    n_cycles: int
    n_uncovered: int
    n_unmatched: int
    n_rotations: int = 0
    quad: np.ndarray | None = None
    n_dropped: int = 0
    n_recoloured: int = 0
    n_recolour_shifts: int = 0


def cycle_cover(
    triangles: np.ndarray,
    twin: np.ndarray,
    *,
    budget: int = 2000,
    online: int | None = None,
    arc_limit: int | None = None,
    rotate: bool = True,
    good: np.ndarray | None = None,
    points: np.ndarray | None = None,
    cell_size: int | None = None,
    drop: bool = True,
    local: bool = False,
    clock: dict | None = None,
    cells: np.ndarray | None = None,
    rule: JoinRule | None = None,
    judge: bool = False,
    beside: Callable[[np.ndarray], object] | None = None,
) -> CycleCover:
    """Cover the dual graph of a triangle mesh with vertex-disjoint cycles.

    Parameters
    ----------
    triangles : (m, 3) int64
    twin : (3 m,) int64
        Half-edge twins (``-1`` on the boundary), ``h = 3 t + k``.
    budget : int
        Triangles one augmenting search may label before it gives up.
    online : int, optional
        The greedy matching sweeps the dual graph breadth-first and starts an
        augmenting search of at most this many triangles from each triangle it
        strands, at once (``_cover_kernels._greedy_matching``); 0: Triangle's
        numbering and the searches afterwards (the matching before session 6).
        Default: ``ONLINE_BUDGET`` from ``ONLINE_MIN_TRIANGLES`` triangles on, else 0.
    arc_limit : int, optional
        Longest cover arc the repair may drop to fix a triangle left unmatched (default:
        any; the alternative, peeling, would drop whole cycles).
    rotate : bool
        Merge cycles by re-matching around vertices (``_cover_kernels.rotate_stars``):
        fewer cycles, same geometry.
    good : (3 m,) bool, optional
        Half-edges preferred as matching (non-cover) edges where the greedy matching
        has a choice: the non-cover edges are where cycles get joined, so sparse mode
        marks the edges whose join would keep its quality rule.
    points : (n, 2) float64, optional
        With points (planar) and ``cell_size > 0``, the cycles are confined to the
        cells of a count-balanced quadtree of about ``cell_size`` triangles each: every
        dual edge across a cell border is matched first, so no cover cycle crosses one
        (up to the few the matching must unpin), and the joins can then go finest cell
        first (``join_classes``) so that the final cycle sweeps the quadtree cell by
        cell, as the incircle mode's compact tree does. With points (2D or 3D) and
        from ``GUIDE_MIN_TRIANGLES`` triangles on, the last parity defects' chain
        searches are A* searches towards the nearest other free triangle
        (``CHAIN_COST``, ``GUIDE_WEIGHT``).
    cell_size : int, optional
        Default ``CELL_SIZE`` (read at call time).
    drop : bool
        Fix the degree-3 triangles no augmenting path can match by dropping interior
        triangles (each leaves the cover, its three neighbours then need no matching
        edge: ``_cover_kernels._drop_matching``) before chains of degree-2 triangles
        are used: those are boundary triangles, whose incenter sectors cost the sparse
        mode its worst angles. False: chains only (the cover before session 8).
    local : bool
        The rows are in a space-filling-curve order (``hammesh.halfedge.renumber_local``,
        as sparse mode hands them over from ``LOCAL_MIN_TRIANGLES`` on): the two halves
        matched side by side are then the two row halves (each a compact region), not
        the count quadtree's top split (``_quadrant_cut``: a quadrant border of that
        order found by binary search, not a pass over every row).
    clock : dict, optional
        Filled with ``step: (wall, process CPU)`` seconds per step of the cover
        (``benchmarks/bench_cover.py --steps``); process CPU counts every thread.
    cells : (m,) int64, optional
        The cells to confine the cycles to, given (``sparse_cells.fishbone_cells``:
        issue 14's hook; ``cell_size`` is then not used).
    rule : JoinRule, optional
        Below ``RECOLOUR_BELOW`` triangles (with ``good``), nodes of the cover with no
        good join are merged into others by re-colouring a few vertices
        (``_recolour_kernels``); with ``rule`` and planar ``points`` that step also
        counts the splits that meet the rule once placed as good joins.
    judge : bool
        With ``rule`` and planar ``points``, instead of ``good``: an edge is good if
        its swap or midpoint split meets ``rule`` (``_join_kernels.edge_meets_rule``, the
        test sparse mode's ``good`` was made by), judged when the greedy matching first
        has to choose across it; only those edges are judged (re-colouring, on small
        meshes, judges the rest). The same cover as with ``good`` made ahead.
    beside : callable, optional
        Called once with the cycle ids ((m,) int64) as soon as it is known which
        triangles the cover leaves off (-1; the other ids may still change, so it must
        read their signs only, and write nothing): on the other core beside the
        rotations' serial merging where they run on two threads (one core idle there:
        sparse mode's bounds for its report), else once the cover is done.

    Returns
    -------
    CycleCover

    Examples
    --------
    >>> import numpy as np
    >>> from hammesh.halfedge import half_edges
    >>> tri = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]])  # a fan around 0
    >>> c = cycle_cover(tri, half_edges(tri, 5).twin)
    >>> c.n_cycles, c.n_uncovered
    (1, 0)
    """
    mark = _Clock(clock)
    tw = np.ascontiguousarray(twin, dtype=np.int64)
    m = len(tw) // 3
    limit = m if arc_limit is None else int(arc_limit)
    if online is None:
        online = ONLINE_BUDGET if m >= ONLINE_MIN_TRIANGLES else 0
    # the good edges as the matching's memo (int8 per half-edge, ``_join_kernels.EDGE_*``):
    # judged as the matching asks (``judge``), or all known ahead
    lazy = judge and rule is not None and points is not None and np.shape(points)[1] == 2
    if lazy:
        e_rule = _j.edge_rule(points, triangles, tw, rule.pinned, rule.amin, rule.keep, rule.hi, rule.swaps,
                              rule.edge_splits, rule.corners)
        g = fresh(3 * m, np.int8, _j.EDGE_UNKNOWN)
    else:
        e_rule = _j.no_edge_rule()
        g = np.full(3 * m, _j.EDGE_NOT_GOOD, np.int8)
        if good is not None:
            g[np.ascontiguousarray(good, dtype=np.bool_).reshape(-1)] = _j.EDGE_GOOD
    quad = cell = None
    if cell_size is None:
        cell_size = CELL_SIZE
    if points is not None and cell_size > 0 and m > 0 and np.shape(points)[1] == 2:
        quad, cell = _cells(np.ascontiguousarray(points, dtype=np.float64), triangles, tw, m, int(cell_size))
    if cells is not None:  # (issue 14: sparse_cells' fishbone cells and bands)
        cell = np.ascontiguousarray(cells, dtype=np.int64)
    no_cell = np.zeros(0, np.int64)
    spans = row_ranges(m, threads.THREAD_MIN_ROWS)
    # the big arrays from ``hammesh.pages``' reserve where there is one (a first call
    # faulted ~9 k pages here: 0.03 s of the neighbours' 0.04 s CPU at 1.5 M)
    nb = fresh((m, 3), np.int32)
    if cell is None:  # (the dual degrees on the neighbours' threads: ~3 ms less of the peel's one core at 1.5 M)
        deg = fresh(m, np.int8)
        run_all([partial(_k.neighbors_degrees_into, tw, nb, deg, lo, hi) for lo, hi in spans])
        mark("neighbors")
        alive, active = _k.peel_active(nb, deg)
    else:
        run_all([partial(_k.neighbors_into, tw, nb, lo, hi) for lo, hi in spans])
        mark("neighbors")
        if cells is not None:  # (issue 14: ``sparse_cells`` may keep every cycle off the borders)
            confine(nb, cell)
        _k.cut_cell_borders(nb, cell)
        alive, deg = _k.peel(nb, m)
        active = alive & (deg == 3)
    mark("peel")
    mate = fresh(m, np.int32, -1)
    # the searches' parent, union-find, label (-1: none) and lca stamps: each search
    # sets what it touches, so only label is written ahead (int8; stamp's zeros: the
    # reserve's zeroed pages, else lazy ones). Triangle ids are int32 in the matching's
    # arrays (mate, parent, union-find, orders, stacks, queues): half the pages a first
    # call faults in
    stamp = fresh(m, np.int64, 0) if reserved() >= 8 * m else np.zeros(m, np.int64)
    work = (fresh(m, np.int32), fresh(m, np.int32), fresh(m, np.int8, -1), stamp)
    if cell is not None:
        s = _k.match_cells(nb, active, alive, deg, cell, e_rule, g, int(online), int(budget), mate, *work)
    else:
        # from ONLINE_MIN_TRIANGLES on (planar) the two halves of the count quadtree's
        # top split (in a local row order: the row halves) are matched side by side,
        # then joined across the split
        split = online > 0 and points is not None and np.shape(points)[1] == 2
        side = np.zeros(m, np.int8)
        if split and local:
            side[_quadrant_cut(np.asarray(points, dtype=np.float64), np.asarray(triangles), m):] = 1
        elif split:
            side = _halves(np.ascontiguousarray(points, dtype=np.float64), triangles, spans)
        mark("halves")
        calls = [partial(_k.match_half, nb, active, side, half, e_rule, g, int(online), int(budget), mate, *work)
                 for half in ((0, 1) if split else (0,))]
        s = max(run_all(calls) if len(spans) > 1 else [c() for c in calls])
    mark("match_halves")
    # the chain searches go best-first towards the nearest free triangle (points needed)
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    guide = points is not None and m >= GUIDE_MIN_TRIANGLES
    pts = np.ascontiguousarray(points, dtype=np.float64) if guide else np.zeros((0, 2))
    frees, s = _k.search_frees(nb, active, alive, mate, *work, s, int(budget))
    n_drop = 0
    if drop:
        s, n_drop = _drop_defects(nb, active, alive, mate, work, s, frees, len(spans) > 1)
    chain = partial(_k.chain_frees, nb, active, alive, mate, *work, s, frees, tri, pts, float(GUIDE_WEIGHT),
                    float(CHAIN_COST))
    if len(spans) > 1:  # the chain searches are serial: the other core faults in the arrays used next
        n_free, later = run_all([chain, partial(_Later, m, triangles, rotate)])
    else:
        n_free, later = chain(), _Later(m, triangles, rotate)
    mark("finish_matching")
    # one path for every size (one thread below THREAD_MIN_ROWS rows), so a small
    # mesh compiles the kernels a big one uses
    is_cov, cdeg = later.is_cov, later.cdeg
    run_all([partial(_k.cover_edges_into, nb, alive, mate, is_cov, cdeg, lo, hi) for lo, hi in spans])
    mark("cover_edges")
    n_unc = _k.settle_cover(nb, tw, is_cov, cdeg, alive, limit)
    mark("settle_cover")
    if cell is not None:
        side = np.zeros(m, np.int8)  # one half (as without the split): runs are whole cycles
    # (the walks read nb where it is the twins' own: cells cut it at their borders)
    cyc, n_cyc = cycle_ids_by_halves(tw, is_cov, side, spans, later.cyc, nb if cell is None else None)
    mark("cycle_ids")
    n_rot = 0
    recolours = rotate and (good is not None or lazy) and 0 < m < RECOLOUR_BELOW and cell is None
    if rotate and n_cyc > 1:
        cl = no_cell if cell is None else cell
        # the prefilter and the candidates on two threads, the rotations on one
        n_pts, vh, skip, cand = later.n_pts, later.vh, later.skip, later.cand
        run_all([partial(_k.star_prefilter_into, tri, is_cov, vh, skip, lo, hi) for lo, hi in spans])
        run_all([partial(_k.star_candidates_into, tw, is_cov, cyc, vh, skip, cl, cand, lo, hi)
                 for lo, hi in row_ranges(n_pts, threads.THREAD_MIN_ROWS)])
        table = np.empty(max(n_cyc, 1), np.int64)
        rot = partial(_k.rotate_candidates_table, tw, is_cov, cyc, n_cyc, vh, cand, cl, table)
        # (the rotations keep every triangle's cover degree: the rows left off are known;
        # re-colouring, on small meshes, may change them)
        early = beside is not None and len(spans) > 1 and not recolours
        n_rot = int(run_all([rot, partial(beside, cyc)])[0] if early else rot())
        if early:
            beside = None
        # the new ids: rows on two threads (none: the kernel loaded all the same, see _drop_defects)
        run_all([partial(_k.renumber_cycles_into, cyc, table, lo, hi if n_rot else lo) for lo, hi in spans])
        n_cyc -= n_rot
    mark("rotate")
    n_rec = n_shift = 0
    if recolours:
        tri_c = np.ascontiguousarray(triangles, dtype=np.int64)
        if lazy:  # (every edge judged: re-colouring reads them all; the same answers)
            g = np.zeros(3 * m, np.bool_)
            _j.good_half_edges_into(np.ascontiguousarray(points, dtype=np.float64), tri_c, tw, e_rule.pinned,
                                    e_rule.amin, e_rule.keep, float(rule.hi), e_rule.swaps, e_rule.edge_splits, 0,
                                    3 * m, g)
        else:
            g = g == _j.EDGE_GOOD
        g_rec = g
        if rule is not None and points is not None and np.shape(points)[1] == 2:
            g_rec = g_rec.copy()  # (the joins as Kruskal sees them: placed splits too)
            _j.placed_good_into(np.ascontiguousarray(points, dtype=np.float64), tri_c, tw,
                                np.ascontiguousarray(rule.pinned, dtype=np.bool_),
                                np.ascontiguousarray(rule.amin, dtype=np.float64), float(rule.keep), float(rule.hi),
                                g_rec)
        n_rec, n_shift = _rk.recolour_merges(
            tri_c, tw, is_cov, cyc, int(n_cyc), g, g_rec, int(tri_c.max()) + 1, RECOLOUR_NODE, RECOLOUR_SET,
            RECOLOUR_CANDIDATES, RECOLOUR_ROUNDS, RECOLOUR_SHIFT, RECOLOUR_LONG_WALK,
        )
        n_rec, n_shift = int(n_rec), int(n_shift)
        if n_rec or n_shift:  # (new cycles took fresh ids: number them as the cover does)
            cyc, n_cyc = cycle_ids_by_halves(tw, is_cov)
            n_unc = int((cyc < 0).sum())
    mark("recolour")
    if beside is not None:
        beside(cyc)
    return CycleCover(
        is_cov=is_cov,
        cycle=cyc,
        n_cycles=int(n_cyc),
        n_uncovered=int(n_unc),
        n_unmatched=int(n_free),
        n_rotations=n_rot + n_rec,
        quad=quad,
        n_dropped=int(n_drop),
        n_recoloured=n_rec,
        n_recolour_shifts=n_shift,
    )


class _Clock:
    """``clock[step] = (wall, process CPU)`` seconds since the last mark (nothing
    without a dict): the cover's steps for ``bench_cover.py --steps``."""

    def __init__(self, clock: dict | None) -> None:
        self.clock = clock
        self.t, self.c = time.perf_counter(), time.process_time()

    def __call__(self, step: str) -> None:
        if self.clock is None:
            return
        t, c = time.perf_counter(), time.process_time()
        w0, c0 = self.clock.get(step, (0.0, 0.0))
        self.clock[step] = (w0 + t - self.t, c0 + c - self.c)
        self.t, self.c = t, c


class _Later:
    """The big arrays the cover's last steps write, their pages faulted in on the
    second core while the first runs the (serial) searches from the defects: the
    cover (``is_cov``, ``cdeg``), the cycle ids (``cyc``: -1) and the rotations'
    vertex arrays (``vh``: -1, ``skip``: False, ``cand``), over the vertex count
    ``n_pts``."""

    def __init__(self, m: int, triangles: np.ndarray, rotate: bool) -> None:
        self.is_cov = fresh(3 * m, np.bool_, 0)
        self.cdeg = fresh(m, np.int8, 0)
        self.cyc = fresh(m, np.int64, -1)
        self.n_pts = int(np.max(triangles)) + 1 if rotate and m else 0
        # half-edge ids: int32 below 2**31 (715 M triangles), as nb is for triangle ids
        self.vh = fresh(self.n_pts, np.int32 if 3 * m < 2**31 else np.int64, -1)
        self.skip = fresh(self.n_pts, np.bool_, 0)
        self.cand = fresh(self.n_pts, np.bool_, 0)


def _drop_defects(nb: np.ndarray, active: np.ndarray, alive: np.ndarray, mate: np.ndarray, work: tuple, s: int,
                  frees: np.ndarray, two: bool) -> tuple[int, int]:
    """The parity defects' drop phase (``_cover_kernels.drop_defects``) from ``frees``,
    in place; returns ``(next lca stamp, triangles dropped)``, as the serial phase.

    With ``two`` threads and at least two defects, the free list is cut in two
    (``defect_cut``) and the parts run side by side, speculatively: the first on
    the arrays, the second on a copy of ``mate``, ``active``, ``alive`` (its own
    search arrays) marking every triangle it reads. If the first part wrote none of
    them (``writes_meet``: the searches' regions did not meet, or only where
    nothing was kept) the second's writes are copied over, which is the serial
    run's state; else the second part runs again after the first (as serially).
    Each defect's searches label up to ``DEFECT_SEARCH_BUDGET`` triangles, most of
    them failing: measured at 1.5 M (docs/partition.md, session 16) 9 searches of
    100 k triangles, 50 ms of one core.
    """
    m = len(mate)
    nomark = np.zeros(0, np.bool_)
    rounds = DROP_ROUNDS
    cut = defect_cut(frees, active, mate) if two else 0
    if cut <= 0:
        s, n_drop, w, _n = _k.drop_defects(nb, active, alive, mate, *work, s, DEFECT_SEARCH_BUDGET, DROP_BUDGET,
                                           rounds, frees, nomark)
        # the side-by-side path's kernels called on nothing: a small mesh's cover (as
        # ``load_kernels`` makes one) loads them, not a big mesh's first call (~10 ms each)
        _k.copy_state_into(mate, active, alive, mate, active, alive, 0, 0)
        _k.writes_meet(nomark, w, 0, w, 0)
        _k.copy_writes(w, 0, mate, active, alive, mate, active, alive)
        return int(s), int(n_drop)
    mate2, active2, alive2 = np.empty_like(mate), np.empty_like(active), np.empty_like(alive)
    run_all([partial(_k.copy_state_into, mate, active, alive, mate2, active2, alive2, lo, hi)
             for lo, hi in row_ranges(m, threads.THREAD_MIN_ROWS)])
    # the second part's search arrays: label -1, stamps zero, the rest set as touched;
    # pages faulted ahead (``fresh``; the reserve's where there is one): faulted as the
    # searches touched them, the second part took ~1.8 x the first's CPU at 1.5 M
    work2 = (fresh(m, np.int32), fresh(m, np.int32), fresh(m, np.int8, -1), fresh(m, np.int64, 0))
    seen = np.zeros(m, np.bool_)
    first, second = run_all([
        partial(_k.drop_defects, nb, active, alive, mate, *work, s, DEFECT_SEARCH_BUDGET, DROP_BUDGET, rounds,
                frees[:cut], nomark),
        partial(_k.drop_defects, nb, active2, alive2, mate2, *work2, 0, DEFECT_SEARCH_BUDGET, DROP_BUDGET, rounds,
                frees[cut:], seen),
    ])
    s, n_drop, w1, n1 = first
    _s2, n_drop2, w2, n2 = second
    if _k.writes_meet(seen, w1, n1, w2, n2):  # (rare: the regions met) serially, as without threads
        s, n_drop2, _w, _n = _k.drop_defects(nb, active, alive, mate, *work, s, DEFECT_SEARCH_BUDGET, DROP_BUDGET,
                                             rounds, frees[cut:], nomark)
    else:
        _k.copy_writes(w2, n2, mate2, active2, alive2, mate, active, alive)
    return int(s), int(n_drop) + int(n_drop2)


def defect_cut(frees: np.ndarray, active: np.ndarray, mate: np.ndarray) -> int:
    """Where ``_drop_defects`` cuts the free list (its position; 0: not cut): before
    the middle one of the triangles still free, so that each part has about half the
    defects (each costs about the same: mostly failed searches of the full budget),
    or before its neighbour if the middle gap of row numbers is under a quarter of the
    mean gap (rows in a local order are near where they are numbered: two defects that
    close may well pair up, and the parts' searches would meet)."""
    still = np.flatnonzero(active[frees] & (mate[frees] < 0))
    n = len(still)
    if n < 2:
        return 0
    rows = frees[still]
    gap = np.diff(rows)  # gap[i - 1]: before the i-th still free
    i = n // 2
    if 4 * gap[i - 1] * (n - 1) < rows[-1] - rows[0]:
        near = [j for j in (i - 1, i + 1) if 1 <= j <= n - 1]
        i = max(near, key=lambda j: gap[j - 1]) if near else i
    return int(still[i])


def cycle_ids_by_halves(twin: np.ndarray, is_cov: np.ndarray, side: np.ndarray | None = None,
                        spans: list | None = None, cyc: np.ndarray | None = None, nb: np.ndarray | None = None):
    """Cycle id of each covered triangle (-1: uncovered) and the number of cycles, as
    ``_cover_kernels.cycle_ids`` numbers them, on two threads: each half's runs of the
    cycles (``cycle_segments_into``), joined where they cross the split, then
    relabelled (into ``cyc``, all -1, if given). ``side`` (int8, 0 or 1 per triangle;
    default: one half) and ``spans`` (row ranges; default ``row_ranges``) choose the
    split and the threads. ``nb``: the neighbour rows of ``twin``
    (``_cover_kernels.neighbors_into``, int32), if the caller has them; made here if not
    (the walks read them: half the bytes of the twins)."""
    tw = np.ascontiguousarray(twin, dtype=np.int64)
    m = len(tw) // 3
    side = np.zeros(m, np.int8) if side is None else side
    spans = row_ranges(m, threads.THREAD_MIN_ROWS) if spans is None else spans
    cyc = np.full(m, -1, np.int64) if cyc is None else cyc
    if nb is None:
        nb = np.empty((m, 3), np.int32)
        run_all([partial(_k.neighbors_into, tw, nb, lo, hi) for lo, hi in spans])
    runs = [(np.empty(m, np.int64), np.empty((m, 2), np.int64)) for _ in range(2)]  # pages touched as used
    calls = [partial(_k.cycle_segments_into, nb, is_cov, side, h, cyc, *runs[h]) for h in (0, 1)]
    n0, n1 = run_all(calls) if len(spans) > 1 else [c() for c in calls]
    ids, n = _k.link_segments(cyc, side, n0, *runs[0], n1, *runs[1])
    run_all([partial(_k.relabel_segments_into, cyc, side, n0, ids, lo, hi) for lo, hi in spans])
    return cyc, n


def _halves(points: np.ndarray, triangles: np.ndarray, spans: list) -> np.ndarray:
    """Side (0 or 1, int8) of each triangle in the top split of the count quadtree
    (``_thm24_kernels.quadtree_coords``): the axis whose top bit halves the triangles
    more evenly, as the compact forest splits them."""
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    q = quadtree_coords(points, tri, spans=spans)[:, 0]
    m = len(q)
    bx, by = 2 * CELL_BITS - 1, CELL_BITS - 1
    nx = int(np.count_nonzero(q & (1 << bx)))
    ny = int(np.count_nonzero(q & (1 << by)))
    bit = bx if abs(2 * nx - m) <= abs(2 * ny - m) else by
    return ((q >> bit) & 1).astype(np.int8)


def _quadrant_cut(points: np.ndarray, triangles: np.ndarray, m: int) -> int:
    """First row of the second half when the rows are in ``renumber_local``'s order (a
    Hilbert curve over a grid of cells; any quadtree order of the same grid does):
    the start or end of the block of rows in the middle row's quadrant, at the
    coarsest quadtree level where one lies within ``m / 8`` rows of the middle, the
    one nearer to it. A quadrant's border is a short cut (at level 1 a straight line
    through the grid's middle or an L of two half lines), as the count quadtree's top
    split is; it is found by binary searches over the rows (a few dozen centroids)
    instead of the quadtree's pass over every row. Any cut is a valid split (the
    halves only share out the matching): rows in another order merely cut longer."""
    if m < 2:
        return m
    # the cells of hammesh.halfedge.locality's grid (the Hilbert table is not needed:
    # the curve keeps every quadrant's rows together)
    x0, y0, scale, bits = grid_frame(points, m)
    top = (1 << bits) - 1

    def cell(t: int) -> tuple[int, int]:  # the cell of row t's centroid (cell_key's arithmetic)
        a, b, c = triangles[t]
        ix = min(max(int(((points[a, 0] + points[b, 0] + points[c, 0]) / 3.0 - x0) * scale), 0), top)
        iy = min(max(int(((points[a, 1] + points[b, 1] + points[c, 1]) / 3.0 - y0) * scale), 0), top)
        return ix, iy

    def first(lo: int, hi: int, inside, q, sh: int) -> int:  # first row in lo..hi where inside flips
        while lo < hi:
            mid = (lo + hi) // 2
            cx, cy = cell(mid)
            if ((cx >> sh, cy >> sh) == q) == inside:
                hi = mid
            else:
                lo = mid + 1
        return lo

    middle = m // 2
    mx, my = cell(middle)
    best = middle
    for level in range(1, bits + 1):
        sh = bits - level
        q = (mx >> sh, my >> sh)
        rows = [r for r in (first(0, middle, True, q, sh), first(middle, m, False, q, sh)) if 0 < r < m]
        if rows:
            best = min(rows, key=lambda r: abs(r - middle))
            if 8 * abs(best - middle) <= m:
                return best
    return best


def _cells(points: np.ndarray, triangles: np.ndarray, twin: np.ndarray, m: int, size: int):
    """Packed quadtree coordinates and cell ids of about ``size`` triangles per cell."""
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    quad = quadtree_coords(points, tri)[:, 0].astype(np.int64)
    low = (1 << CELL_BITS) - 1
    qx, qy = quad >> CELL_BITS, quad & low
    area = float(qx.max() + 1) * float(qy.max() + 1)  # in finest cells
    level = int(round(0.5 * np.log2(max(size * area / m, 1.0))))
    cell = ((qx >> level) << 32) | (qy >> level)
    _k.smooth_cells(_k.neighbors(twin, m), cell, quad, 4)
    return quad, cell


def join_classes(quad: np.ndarray, t: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Class of a join between triangles ``t`` and ``u`` (arrays): the level of the
    smallest quadtree cell holding both, refined by how near the join lies to that
    cell's centre (``_thm24_kernels.edge_class``). Joins taken in increasing class
    join each cell's cycles before the cell is joined to its siblings, near its
    centre: the final cycle sweeps the cells like the incircle tour."""
    out = np.empty(len(t), np.int64)
    _k.edge_classes(quad[t], quad[u], out)
    return out
