"""Sparse Hamiltonian cycle meshes: Thm 2.4's guarantee with few Steiner points.

Arkin, Held, Mitchell, Skiena, Thm 2.4 splits *every* triangle at its incenter and
flips one edge per dual spanning-tree edge. Its proof is local: for two adjacent
triangles t, u split at their incenters ``I_t``, ``I_u``, the quadrilateral
``a I_u b I_t`` over their shared edge ``ab`` is convex (each incenter sees ``ab`` under
more than 90 degrees, Fig. 9) and flipping ``ab`` into ``I_t I_u`` creates no angle below
half an angle of t or u. Nothing in it needs the *other* triangles to be split. So
(after Gopi & Eppstein, who do the same with edge-midpoint splits and no angle bound):

1. **cover** the dual graph by vertex-disjoint cycles (``cycle_cover``: the complement
   of a matching, as Gopi & Eppstein; cycles merged for free by re-matching around
   vertices): a triangle on a cover cycle is kept whole and the cycle walks through it;
2. **join** the cycles (and the few triangles no cycle covers) into one cycle per
   connected piece, cheapest first (``_sparse_kernels.plan_merges``):

   * *swap* (0 Steiner points): two cover triangles of different cycles, ``t = abc``
     and ``u = bad``, are replaced by ``adc`` and ``dbc``; the two cycles, which passed
     ``p-t-q`` and ``r-u-s``, now pass ``p-dbc-s`` and ``r-adc-q``: one cycle. A cover
     triangle and an uncovered one swapped the same way take the uncovered one into
     the cycle (``p-dbc-adc-q``). Used only where both new triangles keep every angle
     at least half the input's minimum (checked, with margin; the certificate checks
     again);
   * *edge split* (1 Steiner point): split ``ab`` at its midpoint M; t, u become
     ``aMc, Mbc, bMd, Mad`` and the cycles run ``p-Mbc-bMd-s ... r-Mad-aMc-q`` (Gopi &
     Eppstein's merge); also on constrained edges (kept as two halves); used only
     where the four triangles keep the angle bound (checked);
   * *bridge* (Thm 2.4's step, 1 Steiner point per triangle split): split t and u at
     their incenters and flip ``ab``. In t's three sectors the cycle enters by one
     cover sector, crosses to the flipped triangle ``(I_t, a, I_u)``, runs around u (and
     u's whole cycle), returns by ``(I_u, b, I_t)`` and leaves by t's other cover sector.
     Both cycles become one. An uncovered triangle is split once and can bridge to
     all three neighbours (its three sectors form a ring, as every triangle's does in
     Thm 2.4);
   * *midpoint bridge* across a constrained edge (never flipped): the edge's midpoint
     and the four triangles of the conformal variant of Thm 2.4, as in incircle mode.

Every output angle is an input angle (whole triangles), half an input angle or more
(Thm 2.4: sectors, bridges, midpoint bridges), or a swap / edge-split angle checked
against the bound:
``min angle out >= 1/2 min angle in``, verified by the same certificate as incircle
mode. See ``docs/sparse.md`` for the argument and the measured Steiner counts.

The output is assembled as triangles plus, for each, the two edges the cycle crosses
("links"); the cycle order is read off by following links across the output's
half-edge twins (``_sparse_kernels.walk_links``), which are also handed to the
certificate as its pairing claim.
"""

from __future__ import annotations

import math
import threading
import time
import weakref
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace
from functools import partial
from typing import Callable, NamedTuple

import numpy as np

from hammesh.halfedge import (half_edge_twins, local_half_edges, match_half_edges, orient_ccw, renumber_local,
                              restore_vertices)
from hammesh.errors import InvalidOptionError, VerificationError
from hammesh.mesh import HamiltonianMesh, Mesh, cycle_positions
from hammesh.pages import fresh, reserved
from hammesh.postprocess.conform import split_segments
from hammesh.postprocess import _improve_kernels as _ik
from hammesh.postprocess import _join_kernels as _j
from hammesh.postprocess import _sparse_kernels as _k
from hammesh.postprocess.cycle_cover import (CycleCover, JoinRule, corner_angle, cycle_cover, cycle_ids_by_halves,
                                            join_classes, lone_join_bound)
from hammesh.postprocess.comb_cover import comb_cover
from hammesh.postprocess.sparse_cells import fishbone_cells, join_classes as fish_classes
from hammesh.halfedge import HalfEdges
from hammesh import threads
from hammesh.threads import row_ranges, run_all

__all__ = [
    "sparse_hamiltonian", "renumbers", "SparseResult", "sparse_cycles", "local_quality", "kept_radius_ratio", "triangle_angles", "triangle_facts", "KEEP",
    "corner_bound", "join_bounds", "PlanSteps", "SPARSE_TREES", "kept_ratio_start", "kept_ratio_finish",
]

#: swaps must keep the smallest angle above ``(1 + SWAP_MARGIN) x`` half the input's
SWAP_MARGIN = 1e-6
#: the local quality rule's default factor (issue 13): new angles >= KEEP x the parents' smallest
KEEP = 0.9
#: new angles may exceed the input's largest angle by this much (degrees)
MAX_ANGLE_SLACK_DEG = 5.0
#: step halvings of the compass search placing a split's Steiner point
PLACE_ITERS = 6
#: a split is placed only if its midpoint misses the rule by less than this (degrees)
PLACE_REACH_DEG = 10.0
#: joins the plan took below the rule are placed again without a reach (``_place_taken``)
PLACE_TAKEN = True
#: rounds of improvement flips and Steiner point moves
IMPROVE_ROUNDS = 3
#: with a page reserve, ``sparse_cycles``' ``beside_cover`` (the certificate's look at the
#: input, ~0.1 s on one thread at 1.5 M) starts as the plan starts: its Python leaves the
#: other core idle (~0.1 s at 1.5 M, session 17's ``--critical``); False: after the output
#: rows, beside the improvement, which since session 19 is too short to hide it
SIDE_BEFORE_PLAN = True
#: with ``SIDE_BEFORE_PLAN``, start it earlier still: as the splits are placed (their
#: Kruskal orders and open candidates leave the other core idle, ~0.04 s at 1.5 M), so
#: that most of it is done before the plan's cover swaps test on two threads
SIDE_BEFORE_PLACING = True
#: outputs of this many rows or more: the improvement works only on the new rows that
#: miss issue 13's absolute targets (angle below ``keep`` x the input's smallest or above
#: its largest + 5 degrees) and on the Steiner points at their corners; below, on every
#: new row (the local rule's misses too). Session 19: at 1.5 M the rows that meet the
#: targets and miss only their parents' rule were most of the step's work (``_improve``)
IMPROVE_ALL_BELOW = 100_000
#: candidate joins per thread below which scoring runs in one call (a placement is
#: ~100x the work of an angle row, so threads pay off far below THREAD_MIN_ROWS)
SCORE_MIN_ROWS = 20_000
#: candidates per thread below which *placing* splits (a compass search per row, ~10 us)
#: runs in one call: the placement passes are a few thousand rows at 1.5 M triangles,
#: serial on the main thread before (0.03-0.04 s) while the other core idled
PLACE_MIN_ROWS = 1_000
#: rows per thread below which ``triangle_facts`` runs in one call: its passes over the
#: new rows (~35 k at 1.5 M: the report, the target repair, the kept rows' sample) ran
#: serial, ~18 ms on the main thread; a pass on ``hammesh.threads``' kept pool starts
#: in ~20 us (the default ``THREAD_MIN_ROWS`` dates from a new pool per pass)
FACTS_MIN_ROWS = 8_192
#: rows (Steiner points) a thread from which the improvement step's tries (moves) are
#: worked out on both cores before its serial loops (``_improve_kernels.failing_flips``,
#: ``smooth_steiner``): ~1 us a try, ~4 us a point
IMPROVE_MIN_ROWS = 4_096
SMOOTH_MIN_POINTS = 512
#: most triangles one fan (one Steiner point) may replace
FAN_MAX = 12
#: a fan group may take in one covered neighbour across its non-cover edge and so join
#: that cycle without a join (``_join_kernels.fan_groups``)
FAN_ABSORB = True
#: rows between two of the sample whose worst ratio bounds ``kept_radius_ratio``'s search
KEPT_RATIO_STRIDE = 64
#: triangles from which ``sparse_hamiltonian`` renumbers its input along a Hilbert
#: curve first (``hammesh.halfedge.renumber_local``): every pass then reads a
#: triangle's neighbours and corners nearby in memory. Below it the mesh fits the
#: caches anyway and the output stays the one of the input's numbering.
LOCAL_MIN_TRIANGLES = 100_000


def renumbers(m: int, dim: int, info: dict) -> bool:
    """Whether sparse mode renumbers a mesh of ``m`` rows in ``dim`` dimensions for
    locality (``renumber_local``): planar, from ``LOCAL_MIN_TRIANGLES`` rows on, unless
    ``info["rows_local"]`` says the rows are local already. The lattice tiles of
    ``hammesh.parallel`` are (98 % lattice rows, numbered strip by strip in blocks):
    there the renumbering was 0.06-0.085 s of a 0.75 M tile's 0.55-0.61 s CPU, and the
    call without it took 0.86x the CPU (four tiles of the 6M demo, one thread, session
    20; uncovered 748 -> 708, Steiner points 864 -> 820, the smallest angle 24.8 -> 21.0
    deg: it moves with any change of the cover's order, 20.8-28.2 deg on one tile in
    session 12).
    """
    return m >= LOCAL_MIN_TRIANGLES and dim == 2 and not info.get("rows_local", False)


@dataclass(frozen=True, eq=False)
class SparseResult:
    """The sparse construction on plain arrays (2D or 3D points)."""

    points: np.ndarray  # (n_out, d) float64: input points, incenters, midpoints
    triangles: np.ndarray  # (m_out, 3) int64 in cycle order
    lengths: np.ndarray  # (c,) int64 cycle lengths
    parent: np.ndarray  # (m_out,) int64
    kind: np.ndarray  # (m_out,) int8
    claim: np.ndarray  # (3 m_out,) int64 half-edge twins of the output rows
    mid_a: np.ndarray  # (q,) int64 edges split at midpoints
    mid_b: np.ndarray
    counts: dict


class _Steps:
    """Wall and process CPU seconds per step of the construction (the report's
    ``step_seconds`` / ``step_cpu_seconds``): where a call's time goes, without a
    profiler. Process CPU counts every thread (the threaded passes' helpers too)."""

    def __init__(self) -> None:
        self.wall: dict[str, float] = {}
        self.cpu: dict[str, float] = {}
        self._t, self._c = time.perf_counter(), time.process_time()

    def done(self, step: str) -> None:
        """The time since the last mark belongs to ``step`` (added up if it recurs)."""
        t, c = time.perf_counter(), time.process_time()
        self.wall[step] = self.wall.get(step, 0.0) + t - self._t
        self.cpu[step] = self.cpu.get(step, 0.0) + c - self._c
        self._t, self._c = t, c


def _incenters(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    p = points[tri]
    la = np.linalg.norm(p[:, 2] - p[:, 1], axis=1)
    lb = np.linalg.norm(p[:, 0] - p[:, 2], axis=1)
    lc = np.linalg.norm(p[:, 1] - p[:, 0], axis=1)
    return (la[:, None] * p[:, 0] + lb[:, None] * p[:, 1] + lc[:, None] * p[:, 2]) / (la + lb + lc)[:, None]


def triangle_angles(points: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Smallest and largest angle (radians) of every triangle (2D or 3D points)."""
    lo, hi, _, _ = triangle_facts(points, triangles)
    return lo, hi


def triangle_facts(
    points: np.ndarray, triangles: np.ndarray, room: int = 0, corners: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, float, int]:
    """Smallest and largest angle of every triangle, the worst radius ratio and its row.

    One threaded pass (``_join_kernels.triangle_min_max_into``): the angles the local
    rule needs and the report's worst circumradius / (2 x inradius) (``row`` -1 if
    no triangle is worse than equilateral). ``room``: rows of memory left after the
    smallest angles (``_longer`` grows them in place). ``corners`` ((m, 3) float32,
    planar): filled with every corner's angle on the way (the cover's first test of
    an edge, ``cycle_cover.JoinRule.corners``).
    """
    pts = np.ascontiguousarray(points, dtype=np.float64)
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    lo = _with_room(fresh(len(tri) + room, np.float64), len(tri))  # (from quality_mesh's reserve, if any: no faults)
    hi = fresh(len(tri), np.float64)
    cn = np.zeros((0, 3), np.float32)
    parts = _row_pass(lambda a, b: (a, *_j.triangle_min_max_into(pts, tri[a:b], lo[a:b], hi[a:b],
                                                                 cn if corners is None else corners[a:b])),
                      len(tri), FACTS_MIN_ROWS)
    worst, row = 1.0, -1
    for a, w, r in parts:
        if r >= 0 and w > worst:
            worst, row = float(w), a + int(r)
    return lo, hi, worst, row


def _row_pass(fill, n: int, min_rows: int | None = None) -> list:
    """``fill(lo, hi)`` over one contiguous row range per core, side by side (``hammesh.threads``).

    The kernels are ``nogil`` and fill disjoint slices of their outputs; below
    ``min_rows`` rows per thread (default ``hammesh.threads.THREAD_MIN_ROWS``) one call.
    """
    spans = row_ranges(n, threads.THREAD_MIN_ROWS if min_rows is None else min_rows)
    return run_all([partial(fill, lo, hi) for lo, hi in spans])


#: tied places beyond which :func:`stable_argsort` sorts again stably instead of fixing the ties
STABLE_TIES_MAX = 16_384


def stable_argsort(key: np.ndarray) -> np.ndarray:
    """``np.argsort(key, kind="stable")`` of a float array, by numpy's faster unstable
    sort: equal keys lie together after it, and each run of them put back in index
    order is exactly the stable order (ties by index). ~0.6 x the time for ~120 k
    keys (``_join_order``'s sort, twice a call, session 20). The runs are put back
    together, by one small sort of the tied places (session 21: at 1.5 M triangles
    ~400 tied places among 67 k keys, over the 256 a loop of one sort per run took,
    so both calls paid the unstable sort and then the stable one: 9.5 ms each). NaN
    keys, or more than ``STABLE_TIES_MAX`` tied places: the stable sort itself."""
    o = np.argsort(key)
    if len(o) < 2:
        return o
    ks = key[o]
    if np.isnan(ks[-1]):  # (NaN sorts last; NaNs never compare equal)
        return np.argsort(key, kind="stable")
    tie = np.flatnonzero(ks[1:] == ks[:-1])
    if len(tie) > STABLE_TIES_MAX:
        return np.argsort(key, kind="stable")
    if len(tie):
        at = np.union1d(tie, tie + 1)  # the places in runs of equal keys, in order
        run = np.cumsum(np.concatenate([[0], ks[at[1:]] != ks[at[:-1]]]))  # (equal keys: one run)
        sub = o[at]
        o[at] = sub[np.lexsort((sub, run))]  # each run's indices in increasing order
    return o


def _join_order(
    kind: np.ndarray, slack: np.ndarray, newmin: np.ndarray, pmin: np.ndarray, whole: np.ndarray,
    cls: np.ndarray | None = None, first: bool = False,
) -> np.ndarray:
    """Candidates in the order Kruskal takes them: best joins first.

    Joins meeting the local rule (slack >= 0) come first, Steiner-free swaps before
    splits, each by decreasing slack; then those that miss it but keep the rule
    against the input's *global* minimum (``whole``: new angles >= keep x the
    input's smallest, <= its largest + 5 degrees), then the others that keep at
    least half their parents' smallest angle (no worse than a Thm 2.4 bridge), each
    by decreasing slack. Other candidates are dropped (a bridge does better).

    ``cls`` (``cycle_cover.join_classes``, when the cover's cycles are confined to
    quadtree cells) orders each tier and kind before the slack: the joins inside
    the finest cells first, near the cells' centres, then up the quadtree, so that
    the final cycle sweeps the domain cell by cell (issue 14). Measured, tiers first
    keep the Steiner points near the unconfined cover's; classes first cut a
    little less and cost 2-4x the points. ``first``: the class before the tiers
    (``sparse_cells``: the fishbone's classes, ``tree="fishbone"``).
    """
    meets = slack >= 0.0
    usable = (kind != _j.NO_JOIN) & (meets | (newmin >= 0.5 * pmin))
    idx = np.flatnonzero(usable)
    kk = np.where(meets[idx], kind[idx], 0)
    tier = np.where(meets[idx], 0, np.where(whole[idx], 1, 2))
    if cls is None:  # (one stable sort of one key: tier, kind, then the slack, which lies in
        # [-pi, pi], so 8 apart per class keeps the classes apart; slacks within ~1e-14 of
        # each other keep the index order, where lexsort's three passes compared them
        # exactly: 0.6 x the time, session 19)
        key = (3 * tier + kk) * 8.0 - slack[idx]
        return idx[stable_argsort(key)]
    if first:
        return idx[np.lexsort((-slack[idx], kk, tier, cls[idx]))]
    return idx[np.lexsort((-slack[idx], cls[idx], kk, tier))]


def _fans(pts, tri, tw, con, cover: CycleCover, amin_t, keep: float, hi: float, floor: float, amax_in: float,
          unc: np.ndarray):
    """Replace groups of uncovered triangles by fans (``_join_kernels.fan_groups``).

    Returns the modified ``(points, triangles, twin, pinned, cover, parent_min,
    orig_of, is_fan, n_fan)`` (no fan: the arguments, ``orig_of`` and ``is_fan``
    None): the fans' points follow the input points, fan
    triangles follow the kept ones; ``orig_of`` maps each triangle to the input
    triangle it lies in or over (a fan triangle: the one holding its outer edge),
    ``parent_min`` is the smallest angle of the triangles each one replaces. ``unc``:
    the uncovered triangles, ascending.
    """
    m = len(tri)
    hi_fan = max(hi, 0.5 * math.pi + 0.5 * amax_in)  # no worse than an incenter sector
    # fan triangles keep the input's minimum angle (2 x floor): a bridge may split
    # them at their incenters later, and Thm 2.4's bound then needs exactly that
    group, fpt, gmin, off, corners, hes, absorbed, apex = _j.fan_groups(
        pts, tri, tw, con, cover.cycle, amin_t, float(keep), hi, 2.0 * floor, hi_fan, FAN_MAX, PLACE_ITERS,
        cover.is_cov, FAN_ABSORB, unc, fresh(m, np.int64, -1),
    )
    n_fan = len(fpt)
    if n_fan == 0:  # (no new orig_of, is_fan: the caller's stand; an arange here faulted 12 MB at 1.5 M)
        return pts, tri, tw, con, cover, amin_t, None, None, 0
    n = len(pts)
    kept = np.flatnonzero(group < 0)
    sizes = np.diff(off)
    g_of = np.repeat(np.arange(n_fan), sizes)
    nxt = np.arange(len(corners)) + 1
    nxt[off[1:] - 1] = off[:-1]  # the last corner wraps to the group's first
    fan_tri = np.stack([n + g_of, corners, corners[nxt]], axis=1)
    tri2 = np.concatenate([tri[kept], fan_tri])
    pts2 = np.concatenate([pts, fpt])
    m2 = len(tri2)
    tw2, dup = half_edge_twins(tri2, len(pts2))
    if dup >= 0:
        raise VerificationError(f"internal error: fan edge of row {int(dup) // 3} used twice")
    con2 = np.concatenate([con.reshape(m, 3)[kept], np.zeros((len(fan_tri), 3), np.bool_)], axis=0)
    con2[len(kept):, 1] = con[hes]
    is_cov2 = np.concatenate(
        [cover.is_cov.reshape(m, 3)[kept], np.tile(np.array([True, False, True]), (len(fan_tri), 1))], axis=0
    )
    # a fan that took in a covered triangle is a path of that triangle's cycle, cut at
    # the spoke to its apex (``fan_groups``); the others are cycles of their own
    own = absorbed < 0
    gid = np.where(own, cover.n_cycles + np.cumsum(own) - 1, cover.cycle[np.maximum(absorbed, 0)])
    r_w = len(kept) + off[:-1][~own] + apex[~own]
    is_cov2[r_w - 1] = (True, True, False)
    is_cov2[r_w] = (False, True, True)
    cyc2 = np.concatenate([cover.cycle[kept], gid[g_of]])
    cover2 = CycleCover(
        is_cov=is_cov2.reshape(-1),
        cycle=cyc2,
        n_cycles=cover.n_cycles + int(own.sum()),
        n_uncovered=int((cyc2 < 0).sum()),
        n_unmatched=cover.n_unmatched,
        n_rotations=cover.n_rotations,
    )
    amin2 = np.concatenate([amin_t[kept], gmin[g_of]])
    orig_of = np.concatenate([kept, hes // 3])
    is_fan = np.zeros(m2, np.bool_)
    is_fan[len(kept):] = True
    return pts2, tri2, tw2, con2.reshape(-1), cover2, amin2, orig_of, is_fan, n_fan


#: most triangles one ring fan (an uncovered triangle and covered neighbours) may replace
RING_MAX = 4


def _union_polygon(tri: np.ndarray, tw: np.ndarray, con: np.ndarray, members: list[int]):
    """Counter-clockwise corners and outer half-edges of a group's union, or None.

    None unless the union is a disc whose every corner is on its boundary (a dual
    tree: ``len(members) + 2`` outer edges in one closed loop), so that a fan over it
    keeps every vertex, and no edge inside it is pinned (a constrained edge, or one
    between regions, must stay).
    """
    k = len(members) + 2
    poly, hes = np.empty(k, np.int64), np.empty(k, np.int64)
    n = _k.union_polygon_into(tri, tw, con, np.asarray(members, np.int64), poly, hes)  # (a kernel: called per
    return (poly.tolist(), hes.tolist()) if n else None  # group of every ring tried, ~600 at 1.5 M)


def _ring_links(tw: np.ndarray, is_cov: np.ndarray, hes: list[int]):
    """Which spokes of a ring fan over a group carry the cycles that crossed it, or None.

    The group's covered triangles were entered and left by cover edges across its
    outer edges (*links*, an even number). In the ring (one fan triangle per outer
    edge, in order) every link must end an *arc* of consecutive fan triangles, the
    arcs pairing the links in ring order and leaving no fan triangle between two
    arcs: then every fan triangle has two cover edges and every outside triangle
    keeps its own. Returns the boolean ``spoke[i]`` (spoke i at corner i, between fan
    triangles i - 1 and i, is a cover edge) of the first pairing that fits
    (``_ring_link_options`` gives both), or None if neither does.
    """
    options = _ring_link_options(tw, is_cov, hes)
    return np.asarray(options[0], np.bool_) if options else None


def _ring_link_options(tw: np.ndarray, is_cov: np.ndarray, hes: list[int]) -> list[tuple]:
    """Every pairing of a ring's links into arcs that fits (``_ring_links``): zero to two
    (each a tuple of bools, ``spoke[i]``; plain Python: a few entries, called per group)."""
    n = len(hes)
    links = [i for i, h in enumerate(hes) if tw[h] >= 0 and is_cov[h]]
    if not links:
        return [(True,) * n]  # the ring is a cycle of its own
    if len(links) % 2:
        return []
    out = []
    for shift in (0, 1):
        ends = [links[(shift + 2 * k + 1) % len(links)] for k in range(len(links) // 2)]
        starts = [links[(shift + 2 * k + 2) % len(links)] for k in range(len(links) // 2)]
        if all((b - a) % n == 1 for a, b in zip(ends, starts)):
            off = set(starts)
            spoke = tuple(i not in off for i in range(n))
            if spoke not in out:
                out.append(spoke)
    return out


def _missing_targets(pts, tri, tw, con, cycle, amin_t, lo: float, hi: float, floor: float) -> np.ndarray:
    """Isolated uncovered triangles no join can absorb within the absolute targets.

    ``join_bounds`` gives the isolated uncovered triangles (few); each inner edge's
    join is judged as the plan would (``_join_kernels.score_joins_into``, split
    placed without a reach) against the *global* targets: smallest new angle >= ``lo``,
    largest <= ``hi``. Returns the rows where no edge's join meets both (e.g. the
    join bound below ``lo``, or a swap whose largest angle is over ``hi``).
    """
    rows, bound, _ = join_bounds(pts, tri, tw, cycle)
    out = []
    one = [np.zeros(1, np.int8), np.empty(1), np.empty(1), np.empty(1), np.empty((1, 2))]
    for t, b in zip(rows.tolist(), bound.tolist()):
        ok = False
        if b >= lo:
            for k in range(3):
                g = tw[3 * t + k]
                if g < 0:
                    continue
                pm = min(amin_t[t], amin_t[g // 3])
                _j.score_joins_into(
                    pts, tri, tw, con, np.array([g]), amin_t, lo / pm, hi, floor, -2.0, True, True,
                    PLACE_ITERS, math.inf, *one,
                )
                if one[0][0] != _j.NO_JOIN and one[2][0] >= lo and one[3][0] <= hi:
                    ok = True
                    break
        if not ok:
            out.append(t)
    return np.asarray(out, np.int64)


def _best_ring(pts, tri, tw, con, is_cov, cycle, blocked, t, lo: float, hi: float, floor2: float,
               amin=None, keep: float = 0.0, accept=None):
    """The best ring fan over the uncovered triangle ``t`` and covered neighbours, or None.

    Every connected group of ``t`` (an int, or a list of triangles to start from) and
    up to ``RING_MAX`` triangles in all, the others covered (not ``blocked``, across
    free edges), whose union is a disc (``_union_polygon``) and whose links pair into
    arcs (``_ring_links``) gets its fan point placed (``_join_kernels.place_fan``); a
    group qualifies if every fan angle is ``>= max(lo, floor2)`` (with ``amin``: and
    ``>= keep`` x its members' smallest angle, the local rule) and ``<= hi``, and
    ``accept(members, hes, spoke)`` if given. Returns ``(slack, members, (polygon,
    half-edges), spoke, x, y)`` of the largest slack (then the smaller group).
    """
    best = None
    seen: set[frozenset] = set()
    stack = [[t] if isinstance(t, int) else list(t)]
    amin_k, keep_k = (np.zeros(0), 0.0) if amin is None else (amin, float(keep))
    while stack:
        members = stack.pop()
        key = frozenset(members)
        if key in seen:
            continue
        seen.add(key)
        if len(members) > 1:
            ms = np.asarray(members, np.int64)
            pp = _union_polygon(tri, tw, con, ms)
            options = [] if pp is None else _ring_link_options(tw, is_cov, pp[1])
            if options:
                poly = np.asarray(pp[0], np.int64)
                # (centroids as starts, the first step, the local rule's bound: in the kernel)
                x, y, sl, nmin, nmax, lo_g = _k.ring_fan_point(
                    pts, tri, ms, poly, len(poly), amin_k, keep_k, lo, hi, PLACE_ITERS + 2, float(floor2)
                )
                ok = sl > -math.inf and nmin >= max(lo_g, floor2) and nmax <= hi
                if ok and (best is None or (sl, -len(members)) > (best[0], -len(best[1]))):
                    if accept is not None:  # the costlier check last, only for a better fan
                        options = [o for o in options if accept(members, pp[1], o)]
                    if options:
                        best = (sl, members, pp, options[0], x, y)
        if len(members) >= RING_MAX:
            continue
        for x in members:
            for k in range(3):
                g = tw[3 * x + k]
                if g < 0 or con[3 * x + k]:
                    continue
                y = int(g // 3)
                if y in members or blocked[y] or cycle[y] < 0:
                    continue
                stack.append(members + [y])
    return best


#: removals along each alternating path a re-route may take (``_reroute``)
REROUTE_DEPTH = 4
#: ``tree=`` names sparse mode takes: its own free cover (``"quadtree"``), the fishbone's
#: cells (``"fishbone"``, ``sparse_cells``), the comb cover (``"comb"``, ``comb_cover``)
SPARSE_TREES = ("quadtree", "fishbone", "comb")


def _alternating_paths(tw, is_cov, cycle, start: int, avoid: set, depth: int, stop: int = -1):
    """Alternating paths of the cover from ``start``, which gained a cover edge.

    ``start`` gives up one of its cover edges (to ``y``), ``y`` then takes its
    non-cover edge (to a covered ``x``), ``x`` gives up one of its other cover edges,
    and so on (at most ``depth`` give-ups). Yields ``(y, nodes, flips)`` after each
    give-up: ``y`` is one cover edge short there, ``nodes`` the path, ``flips`` the
    half-edges whose cover state changes (one per edge). A path reaching ``stop``
    ends there.
    """
    todo = [(start, [start], [])]
    while todo:
        x, nodes, flips = todo.pop()
        for k in range(3):
            h = 3 * x + k
            g = tw[h]
            if g < 0 or not is_cov[h]:
                continue
            y = int(g // 3)
            if y in nodes or y in avoid:
                continue
            path = nodes + [y]
            yield y, path, flips + [h]
            if y == stop or (len(flips) + 1) // 2 + 1 > depth:
                continue
            for j in range(3):
                f = 3 * y + j
                e = tw[f]
                if e < 0 or is_cov[f]:
                    continue
                x2 = int(e // 3)
                if cycle[x2] >= 0 and x2 not in path and x2 not in avoid:
                    todo.append((x2, path + [x2], flips + [h, f]))


def _flip_cover(tw, is_cov, flips) -> None:
    for h in flips:
        is_cov[h] = not is_cov[h]
        is_cov[tw[h]] = is_cov[h]


def _reroute(pts, tri, tw, con, cover: CycleCover, is_fan, amin_t, lo: float, hi: float, floor2: float,
             depth: int | None = None):
    """Re-route the cover through uncovered triangles that neither a join nor a ring fan can keep.

    For such a triangle ``t`` (on the boundary, typically: its corners at the
    boundary edge are single input angles, so every join and every fan over it
    halves one) with covered neighbours ``u``, ``w``: give ``t`` the cover edges
    ``t-u``, ``t-w`` and restore the degrees by two alternating paths
    (``_alternating_paths``) from ``u`` and ``w`` that end at one triangle ``z``
    losing both its cover edges (``z`` is left off instead of ``t``), or by one path
    from ``u`` that ends at ``w`` (nothing left off). ``z`` is taken only if a ring
    fan over it meets the targets (``_best_ring``); the cover's cycles may merge or
    split (the joins take it from there). ``depth``: the removals along each path
    (None: ``REROUTE_DEPTH``). Returns the new cover and the number of triangles
    re-routed.
    """
    depth = REROUTE_DEPTH if depth is None else depth  # (``tree="comb"``: 0)
    m = len(tri)
    rows = _missing_targets(pts, tri, tw, con, cover.cycle, amin_t, lo, hi, 0.5 * floor2)
    if not len(rows):
        return cover, 0
    # the cover's own arrays until a re-route is taken (the tries below flip and set
    # them back), then copies with room after them: the ring fans and joins append rows
    # in place (``_longer``), and the cover must stay as it was (``_relabel_group``)
    is_cov, cycle = cover.is_cov, cover.cycle
    touched = np.zeros(m, np.bool_)
    fan_or_touched = is_fan.copy()  # is_fan | touched, and touched as a set: no O(m) pass per pair
    touched_set: set[int] = set()
    done = 0
    for t in rows.tolist():
        if _best_ring(pts, tri, tw, con, is_cov, cycle, is_fan, t, lo, hi, floor2) is not None:
            continue  # a ring fan takes it
        nbs = [int(tw[3 * t + k] // 3) for k in range(3) if tw[3 * t + k] >= 0]
        t_he = {int(tw[3 * t + k] // 3): 3 * t + k for k in range(3) if tw[3 * t + k] >= 0}
        best = None
        for i in range(len(nbs)):
            for j in range(len(nbs)):
                u, w = nbs[i], nbs[j]
                if i == j or cycle[u] < 0 or cycle[w] < 0 or touched[u] or touched[w]:
                    continue
                avoid = {t} | touched_set
                from_w: dict[int, list] = {}
                for y, nodes, flips in _alternating_paths(tw, is_cov, cycle, w, avoid | {u}, depth):
                    from_w.setdefault(y, []).append((nodes, flips))
                for y, nodes, flips in _alternating_paths(tw, is_cov, cycle, u, avoid, depth, w):
                    cands = []
                    if y == w:  # the path ends at w, which gave t its edge: nothing left off
                        if best is None or best[3] >= 0 or len(flips) < best[0]:
                            best = (len(flips), [t_he[u], t_he[w]] + flips, nodes, -1)
                        continue
                    if best is not None and best[3] < 0:
                        continue
                    if y in from_w and not is_fan[y]:
                        for nodes2, flips2 in from_w[y]:
                            if set(nodes).isdisjoint(nodes2[:-1]) and tw[flips[-1]] != tw[flips2[-1]]:
                                cands.append((nodes + nodes2, flips + flips2, y))
                    for nodes_all, flips_all, z in cands:
                        cost = len(flips_all)
                        if best is not None and cost >= best[0]:
                            continue
                        add = [t_he[u], t_he[w]]
                        _flip_cover(tw, is_cov, add + flips_all)
                        c_t, c_z = cycle[t], cycle[z]
                        cycle[t], cycle[z] = cycle[u], -1
                        ring = _best_ring(pts, tri, tw, con, is_cov, cycle, fan_or_touched, z, lo, hi, floor2)
                        _flip_cover(tw, is_cov, add + flips_all)
                        cycle[t], cycle[z] = c_t, c_z
                        if ring is not None:
                            best = (cost, add + flips_all, nodes_all, z)
        if best is None:
            continue
        if is_cov is cover.is_cov:  # (the first re-route taken)
            is_cov, cycle = _copy_with_room(cover.is_cov, 3 * ROOM_ROWS), _copy_with_room(cover.cycle, ROOM_ROWS)
        _, flips, nodes, z = best
        _flip_cover(tw, is_cov, flips)
        cycle[t] = cycle[nodes[0]]
        if z >= 0:
            cycle[z] = -1
        touched[nodes] = True
        touched[t] = True
        fan_or_touched[nodes] = True
        fan_or_touched[t] = True
        touched_set.update(int(x) for x in nodes)
        touched_set.add(int(t))
        done += 1
    if not done:
        return cover, 0
    local = _relabel_group(tw, cover.is_cov, is_cov, cover.cycle, cover.n_cycles, touched_set)
    cyc2, n_cyc2 = local if local is not None else cycle_ids_by_halves(tw, is_cov)
    return CycleCover(
        is_cov=is_cov, cycle=cyc2, n_cycles=int(n_cyc2), n_uncovered=int((cyc2 < 0).sum()),
        n_unmatched=cover.n_unmatched, n_rotations=cover.n_rotations,
    ), done


def _link_components(links, *partners: dict) -> dict:
    """Each link's component (a representative link) when every link is joined to its
    partner in each of ``partners`` (link -> link maps): which links one cycle passes
    after a ring or re-route rewired them. Union-find with path halving."""
    root = {h: h for h in links}

    def find(h):
        while root[h] != h:
            root[h] = root[root[h]]
            h = root[h]
        return h

    for h in links:
        for partner in partners:
            root[find(h)] = find(partner[h])
    return {h: find(h) for h in links}


def _border_links(tw: np.ndarray, cov: np.ndarray, group: set) -> list[int]:
    """The group's *links*: its half-edges on the cover ``cov`` whose twin lies outside
    it (member side), in row order."""
    return [3 * x + k for x in sorted(group) for k in range(3)
            if tw[3 * x + k] >= 0 and tw[3 * x + k] // 3 not in group and cov[3 * x + k]]


def _outside_pairs(tw: np.ndarray, cov: np.ndarray, by_id: dict):
    """The links paired *outside* a group by the cover ``cov`` (``by_id``: each cycle's
    links): a cycle crossing the group once pairs its two links, one crossing more
    often is walked outwards (``_join_kernels.ring_outside_pairs``, lock-step;
    ``_relabel_group``, ``_swap_outcome``).

    Returns ``(outside, unwalked)``: each link's partner and, per cycle, one link
    whose outside path was not walked; None where a walk is undecided within
    ``RING_WALK_BUDGET``.
    """
    outside: dict[int, int] = {}
    unwalked: set[int] = set()
    for hs in by_id.values():
        if len(hs) == 2:
            outside[hs[0]], outside[hs[1]] = hs[1], hs[0]
            unwalked.add(hs[0])
            continue
        pair, deduced = _j.ring_outside_pairs(tw, cov, np.asarray(hs, np.int64), RING_WALK_BUDGET)
        if (pair < 0).any():
            return None
        for h, j in zip(hs, pair.tolist()):
            outside[h] = hs[j]
        unwalked.add(hs[deduced] if deduced >= 0 else hs[0])
    return outside, unwalked


def _inside_pairs(tw: np.ndarray, on_cover: Callable[[int], bool], group: set, links: list):
    """The links paired *inside* ``group`` by a cover (``on_cover(h)``: is half-edge
    ``h`` on it), walked from each link through the group's triangles to the link it
    leaves by (``_relabel_group``, ``_swap_outcome``).

    Returns ``(inside, on_path)``: each link's partner (both ways) and, per triangle
    on a path, the link its path starts from; None where a triangle on a path has
    other than one cover edge onwards.
    """
    inside: dict[int, int] = {}
    on_path: dict[int, int] = {}
    for h in links:
        if h in inside:
            continue
        came = h
        while True:
            x = came // 3
            on_path[x] = h
            f = [3 * x + k for k in range(3) if 3 * x + k != came and on_cover(3 * x + k)]
            if len(f) != 1:
                return None
            f = f[0]
            if tw[f] // 3 not in group:
                break
            came = int(tw[f])
        inside[h], inside[f] = f, h
    return inside, on_path


def _relabel_group(tw, old_cov, new_cov, cycle, n_cycles: int, group: set):
    """The cover's cycle ids after its edges changed only *inside* ``group`` (``_reroute``), or None.

    Outside the group every cover edge is as it was, so each cycle crossing the group
    still joins its *links* (cover edges across the group's border) in pairs outside
    it (a cycle crossing once: its two links; more often: walked outwards,
    ``_join_kernels.ring_outside_pairs``, lock-step); inside, the new cover joins
    them in new pairs (walked here, through the group's few triangles). The new
    cycles are the components of both pairings, plus cycles now wholly inside the
    group. Old ids merge by a union-find (one O(m) gather); a cycle the group
    splits keeps its id on the piece holding the one outside path not walked, and
    the walked paths of its other pieces are labelled by walking them again
    (``label_outside_into``; within the walks' budget). None (the caller labels the
    cover anew) where a walk is undecided.
    """
    links = _border_links(tw, old_cov, group)
    old_id = {h: int(cycle[tw[h] // 3]) for h in links}
    by_id: dict[int, list] = {}
    for h in links:
        by_id.setdefault(old_id[h], []).append(h)
    pairs = _outside_pairs(tw, old_cov, by_id)
    if pairs is None:
        return None
    outside, unwalked = pairs
    paths = _inside_pairs(tw, lambda h: bool(new_cov[h]), group, links)  # (the new cover inside)
    if paths is None:
        return None
    inside, on_path = paths
    comp = _link_components(links, outside, inside)
    # each new cycle's id: the smallest old id whose far (unwalked) part it holds, else a new one
    holds: dict[int, int] = {}
    for h in links:
        if h in unwalked or outside[h] in unwalked:
            r = comp[h]
            holds[r] = min(holds.get(r, old_id[h]), old_id[h])
    comps = sorted(set(comp.values()))
    n_new = n_cycles
    rep = {}
    for r in comps:
        if r in holds:
            rep[r] = holds[r]
        else:
            rep[r] = n_new
            n_new += 1
    out = cycle.copy()
    lut = np.arange(n_cycles + len(group) + len(links), dtype=np.int64)
    alive = np.zeros(len(lut), np.bool_)
    alive[:n_cycles] = True
    for x in group:  # cycles wholly inside the group before: gone
        if cycle[x] >= 0 and cycle[x] not in by_id:
            alive[cycle[x]] = False
    links_arr = np.asarray(links, np.int64)
    for h in links:
        r = comp[h]
        if h in unwalked or outside[h] in unwalked:
            lut[old_id[h]] = rep[r]  # its far part stays where it is: relabelled by the gather
            if rep[r] != old_id[h]:
                alive[old_id[h]] = False
        elif h < outside[h]:  # a walked path of a split piece: label it now
            _j.label_outside_into(tw, old_cov, h, links_arr, out, rep[r])
    alive[n_cycles:n_new] = True
    for x in sorted(group):
        if x in on_path:
            out[x] = rep[comp[on_path[x]]]
        elif not any(new_cov[3 * x + k] for k in range(3)):
            out[x] = -1
        else:
            out[x] = -2  # on a cycle wholly inside the group (below)
    for x in sorted(group):  # cycles now wholly inside the group: new ids
        if out[x] != -2:
            continue
        stack = [x]
        while stack:
            y = stack.pop()
            if out[y] != -2:
                continue
            out[y] = n_new
            stack += [int(tw[3 * y + k] // 3) for k in range(3) if new_cov[3 * y + k]]
        alive[n_new] = True
        n_new += 1
    # labels written above are final ids already: the gather maps ids through lut,
    # which leaves every id in use as a final id (lut[id] = id) and merges the rest
    rank = np.cumsum(alive[:n_new]) - 1
    _relabel_cycles(out, rank[lut[:n_new]])
    return out, int(alive[:n_new].sum())


#: below-rule joins one call tries to replace by ring joins (``_ring_joins``), worst first
RING_JOIN_TRIES = 32
#: rounds of ring joins, each patching the plan (0: none)
RING_JOIN_PASSES = 1


def _ring_pairs(tw, is_cov, members, hes, spoke):
    """How a ring fan re-pairs the cycles crossing its group.

    Returns ``(links, old, new)``: the ring positions with a link, and for each the
    link it was joined to through the group (following cover edges inside it) and
    the one its arc joins it to now.
    """
    mset = set(members)
    n = len(hes)
    links = [i for i in range(n) if tw[hes[i]] >= 0 and is_cov[hes[i]]]
    pos = {hes[i]: i for i in links}
    old_link = set(links)
    old, new = {}, {}
    for i in links:
        came = hes[i]
        while True:
            x = came // 3
            f = next(3 * x + k for k in range(3) if 3 * x + k != came and is_cov[3 * x + k])
            g = tw[f]
            if g >= 0 and g // 3 in mset:
                came = g
                continue
            old[i] = pos[f]
            break
        d = 1 if spoke[(i + 1) % n] else -1  # row i's cover spoke leads along its arc
        j = (i + d) % n
        while j not in old_link:
            j = (j + d) % n
        new[i] = j
    return links, old, new


#: most steps the outside walks of one ring may take (``_ring_outcome``); undecided rings are not taken
RING_WALK_BUDGET = 20_000


@dataclass(frozen=True)
class RingOutcome:
    """What a ring fan does to the cycles crossing its group (``_ring_outcome``).

    ``links``: ring positions with a link; ``old_id[i]``: the cycle link ``i`` is on;
    ``comp[i]``: the new cycle link ``i`` is on (a representative link position);
    ``split``: some old cycle is spread over two new ones.
    """

    links: list
    old_id: dict
    comp: dict
    split: bool

    def merges(self, ca: int, cb: int) -> bool:
        """Do the old cycles ``ca`` and ``cb`` end on one new cycle, and none split?"""
        if self.split:
            return False
        at = {self.old_id[i]: self.comp[i] for i in self.links}
        return ca in at and cb in at and at[ca] == at[cb]

    def keeps_all(self) -> bool:
        """Every crossing cycle stays one cycle of its own (none merged, none split)."""
        if self.split:
            return False
        ids: dict[int, int] = {}
        for i in self.links:
            if ids.setdefault(self.comp[i], self.old_id[i]) != self.old_id[i]:
                return False
        return True

    def only_merges(self, ca: int, cb: int) -> bool:
        """``merges(ca, cb)``, and every other crossing cycle stays a cycle of its own."""
        if not self.merges(ca, cb):
            return False
        by_comp: dict[int, set] = {}
        for i in self.links:
            by_comp.setdefault(self.comp[i], set()).add(self.old_id[i])
        return all(len(ids) == 1 or ids == {ca, cb} for ids in by_comp.values())


def _ring_outcome(tw, is_cov, cycle, members, hes, spoke, find=None) -> RingOutcome | None:
    """The new cycles through a ring fan's group, decided locally (no relabelling).

    Inside the group the old cover joined the links in pairs (``_ring_pairs``' ``old``),
    the fan's arcs join them in new pairs (``new``); outside, each cycle joins its
    links in pairs too: a cycle crossing the group once joins its two links, one
    crossing it more often is walked outwards from its links
    (``_join_kernels.ring_outside_pairs``, lock-step, so the longest outside path is
    never walked). The new cycles are the components of outside and new pairs.
    None if the walks exceed ``RING_WALK_BUDGET`` (the ring is then not used as a
    join). ``find`` maps a cycle id to the one it was merged into (``_apply_rings``).
    """
    links, _, new = _ring_pairs(tw, is_cov, members, hes, spoke)
    old_id = {i: int(cycle[tw[hes[i]] // 3]) for i in links}
    if find is not None:
        old_id = {i: find(c) for i, c in old_id.items()}
    by_id: dict[int, list] = {}
    for i in links:
        by_id.setdefault(old_id[i], []).append(i)
    outside = {}
    for ids in by_id.values():
        if len(ids) == 2:
            outside[ids[0]], outside[ids[1]] = ids[1], ids[0]
            continue
        pair, _ = _j.ring_outside_pairs(tw, is_cov, np.asarray([hes[i] for i in ids], np.int64), RING_WALK_BUDGET)
        if (pair < 0).any():
            return None
        for i, j in zip(ids, pair.tolist()):
            outside[i] = ids[j]
    comp = _link_components(links, outside, new)
    split = any(len({comp[i] for i in ids}) > 1 for ids in by_id.values())
    return RingOutcome(links, old_id, comp, split)


def _ring_joins(pts, tri, tw, con, cover: CycleCover, amin_t, orig_of, is_fan, order, join, cand, slack, newmin,
                newmax, status, slot, swap_he, counts, keep: float, lo: float, hi: float, floor2: float,
                steps_at: PlanSteps):
    """Ring fans in place of the joins the plan took below the local rule or the targets (issue 13).

    A swap or split over ``ab`` of ``t = abc``, ``u = bad`` divides the corners ``c``
    and ``d``, each a single input angle; where those are small no such join meets
    ``keep`` x the pair's smallest angle. A fan around one point over ``t``, ``u`` and
    one or two covered neighbours (``_best_ring``, local rule against all its
    members) divides only its polygon's corners, which gather several input angles,
    and re-routes the cycles crossing it. Tried, up to ``RING_JOIN_TRIES``:
    the joins between two cycles below the rule, the Thm 2.4 bridges between two
    cycles (both triangles split at their incenters) and the uncovered triangles the
    plan split at their incenters and bridged once (a ring fan over them,
    ``_ring_fans``' test) — first those whose rows miss the absolute targets (``lo``:
    ``keep`` x the input's smallest angle; ``hi``), then by the local rule's slack.

    The plan is *patched*, not made again: a ring is taken only where it does
    exactly what the plan's step did (``_ring_outcome``: it joins ``t``'s and
    ``u``'s cycles and leaves every other cycle crossing it as it was; over an
    uncovered triangle, a leaf of the plan's tree, it merges and splits nothing),
    its other members take part in no join, and only the replaced step is undone
    (its statuses, slots and counts). So Kruskal's tree stays a tree and no re-plan
    (candidates, scores, placements, Kruskal: O(m)) is needed. Returns
    ``_apply_rings``' arrays, the patched ``(status, slot, swap_he, join)`` and the
    number of rings, or None; ``counts`` is updated in place. ``steps_at``: the plan's
    steps (:class:`PlanSteps`).
    """
    tasks = []  # (misses the targets, slack, t, u or -1)
    taken = order[steps_at.taken(join, len(order))]
    low = taken[slack[taken] < 0.0]
    t_of, u_of = cand[low] // 3, tw[cand[low]] // 3
    both = (cover.cycle[t_of] >= 0) & (cover.cycle[u_of] >= 0)
    for i, t, u in zip(low[both].tolist(), t_of[both].tolist(), u_of[both].tolist()):
        tasks.append((not (newmin[i] >= lo and newmax[i] <= hi), float(slack[i]), t, u))
    bridged = steps_at.slotted(slot)
    bridged = bridged[tw[bridged] > bridged]
    split_unc = np.flatnonzero(status == _k.SPLIT)
    split_unc = split_unc[cover.cycle[split_unc] < 0]
    rows = np.unique(np.concatenate([bridged // 3, tw[bridged] // 3, split_unc]))
    a_lo, a_hi = triangle_angles(pts, tri[rows]) if len(rows) else (np.zeros(0), np.zeros(0))
    # an incenter's sectors: half of each corner; 90 degrees + half a corner at the incenter
    miss = dict(zip(rows.tolist(), ((0.5 * a_lo < lo) | (0.5 * math.pi + 0.5 * a_hi > hi)).tolist()))
    half = dict(zip(rows.tolist(), (0.5 * a_lo - keep * amin_t[rows]).tolist()))
    for h in bridged.tolist():
        t, u = h // 3, int(tw[h] // 3)
        if cover.cycle[t] >= 0 and cover.cycle[u] >= 0:
            tasks.append((miss[t] or miss[u], min(half[t], half[u]), t, u))
    for t in split_unc.tolist():
        tasks.append((miss[t], half[t], t, -1))
    if not tasks:
        return None
    tasks.sort(key=lambda x: (not x[0], x[1]))

    def slots_of(x: int) -> list[int]:
        return [3 * x + k for k in range(3) if slot[3 * x + k] != _k.PLAIN]

    def free(x: int, allowed: tuple = ()) -> bool:
        """In no step of the plan (or only in the one being replaced)."""
        return (status[x] == _k.PASS or x in allowed) and all(tw[h] // 3 in allowed for h in slots_of(x))

    used = np.zeros(len(tri), np.bool_)
    blocked = is_fan.copy()  # is_fan | used, kept up to date (no O(m) pass per task)
    rings, steps = [], []  # steps: what each ring replaces, (t, u, bridge partner or -1)

    def fits(ms, hes, sp, t, u, x):
        if not all(free(y, (t, u, x)) for y in ms):
            return False
        out = _ring_outcome(tw, cover.is_cov, cover.cycle, ms, hes, sp)
        if out is None:
            return False
        if u < 0:
            return out.keeps_all()
        return out.only_merges(int(cover.cycle[t]), int(cover.cycle[u]))

    for missing, _, t, u in tasks[:RING_JOIN_TRIES]:
        if blocked[t] or (u >= 0 and blocked[u]):
            continue
        x = -1
        if u < 0:  # an uncovered triangle: a ring fan (no cycle of its own to join)
            br = slots_of(t)
            if len(br) != 1:  # bridged more than once: not a leaf of the plan's tree
                continue
            x = int(tw[br[0]] // 3)
            best = _best_ring(pts, tri, tw, con, cover.is_cov, cover.cycle, blocked, t, lo, hi, floor2,
                              accept=lambda ms, hes, sp: fits(ms, hes, sp, t, -1, x))
        else:  # a join missing the targets: any ring within them; else one meeting the rule
            if status[t] == _k.SPLIT and (len(slots_of(t)) != 1 or len(slots_of(u)) != 1):
                continue  # a bridge: only if it is the one step of both triangles
            best = _best_ring(
                pts, tri, tw, con, cover.is_cov, cover.cycle, blocked, [t, u], lo, hi, floor2,
                amin=None if missing else amin_t, keep=keep,
                accept=lambda ms, hes, sp: fits(ms, hes, sp, t, u, -1),
            )
        n_before = len(rings)
        _take_ring(best, tw, used, rings)
        if len(rings) > n_before:
            blocked[rings[-1][0]] = True
            h = slots_of(t)[0] if status[t] == _k.SPLIT else -1  # the bridge to undo (read now:
            steps.append((t, u, x, h, int(tw[h]) if h >= 0 else -1))  # the fans may reuse tw's rows)
    if not rings:
        return None

    def still_fits(j: int, outcome, find) -> bool:
        # on the cover as the rings before it left it (a cycle may cross two of them)
        t, u = steps[j][:2]
        if outcome is None:
            return False
        if u < 0:
            return outcome.keeps_all()
        return outcome.only_merges(find(int(cover.cycle[t])), find(int(cover.cycle[u])))

    arrays, applied = _apply_rings(pts, tri, tw, con, cover, amin_t, orig_of, is_fan, rings, accept=still_fits)
    if not applied:
        return None
    # undo the replaced steps, then the fans' rows take part in no step (one copy of
    # each array, which the fans' two rows each lengthen)
    extra = 2 * len(applied)
    status, slot = _longer(status, extra, _k.PASS), _longer(slot, 3 * extra, _k.PLAIN)
    swap_he, join = _longer(swap_he, extra, -1), _longer(join, extra, -1)
    for j in applied:
        t, u, x, h, g = steps[j]
        if h < 0:  # a swap or split between two cycles
            counts[1 if status[t] == _k.SWAP else 3] -= 1
        else:  # a bridge (t, u covered) or an uncovered t's one bridge (to x)
            slot[h] = slot[g] = _k.PLAIN
            counts[2] -= 1
            y = g // 3
            if y not in rings[j][0] and cover.cycle[y] >= 0 and not slots_of(y):
                status[y] = _k.PASS  # a cover triangle split only for that bridge
        for y in rings[j][0]:
            status[y] = _k.PASS
            swap_he[y] = join[y] = -1
            slot[3 * y: 3 * y + 3] = _k.PLAIN
    return arrays, (status, slot, swap_he, join), len(applied)


def _take_ring(best, tw: np.ndarray, used: np.ndarray, taken: list) -> None:
    """Append ``_best_ring``'s ring (``None``: nothing) to ``taken`` unless one of its
    members or a triangle beside it is already in a taken ring (no two rings adjacent);
    marks its members ``used``."""
    if best is None:
        return
    _, members, (poly, hes), spoke, x, y = best
    near = [tw[h] // 3 for h in hes if tw[h] >= 0]
    if used[members].any() or used[near].any():
        return
    used[members] = True
    taken.append((members, poly, hes, spoke, x, y))


def _ring_fans(pts, tri, tw, con, cover: CycleCover, amin_t, orig_of, is_fan, lo: float, hi: float, floor2: float):
    """Absorb isolated uncovered triangles that no join can keep at ``lo`` by *ring fans*.

    A join over an edge of an uncovered triangle ``t`` divides the two corners
    opposite it (``join_bounds``), so where those are small no join meets issue 13's
    target. A fan around one Steiner point ``P`` over ``t`` *and some covered
    neighbours* (at most ``RING_MAX`` triangles: a disc, so every vertex stays)
    divides only the group's polygon corners, which gather several input angles,
    and its ``k + 2`` triangles keep every cycle that crossed the group (``_ring_links``:
    the cycles are re-routed around ``P``; they may merge or split, the joins take
    it from there). ``P`` is placed by ``_join_kernels.place_fan`` (the best of the
    members' centroids, then compass search); a group is taken only if every fan
    angle is ``>= max(lo, floor2)`` and ``<= hi`` (``floor2``: the input's minimum, so
    a later Thm 2.4 bridge that splits a fan triangle still keeps the proven floor);
    the best slack wins, then the smaller group. One Steiner point, as the incenter
    it replaces. Uncovered triangles next to a fan are left alone.

    Returns the arrays of ``_fans`` (and ``orig_of``, ``is_fan`` composed) plus the
    number of ring fans.
    """
    m = len(tri)
    rows = _missing_targets(pts, tri, tw, con, cover.cycle, amin_t, lo, hi, 0.5 * floor2)
    if not len(rows) or pts.shape[1] != 2:
        return pts, tri, tw, con, cover, amin_t, orig_of, is_fan, 0
    taken: list[tuple[list[int], list[int], list[int], np.ndarray, float, float]] = []
    used = np.zeros(m, np.bool_)
    blocked = is_fan.copy()  # is_fan | used, kept up to date
    for t in rows.tolist():
        best = _best_ring(pts, tri, tw, con, cover.is_cov, cover.cycle, blocked, t, lo, hi, floor2)
        n_before = len(taken)
        _take_ring(best, tw, used, taken)
        if len(taken) > n_before:
            blocked[taken[-1][0]] = True
    if not taken:
        return pts, tri, tw, con, cover, amin_t, orig_of, is_fan, 0
    arrays, applied = _apply_rings(pts, tri, tw, con, cover, amin_t, orig_of, is_fan, taken,
                                   spare=2 * RING_JOIN_TRIES * RING_JOIN_PASSES)
    return (*arrays, len(applied))


#: buffers ``_longer`` made with rows to spare, by data address: (weak reference to
#: the object owning the memory, rows, dtype, row shape). A later ``_longer`` of a
#: prefix of one grows into its spare rows without a copy
_ROOMY: dict[int, tuple] = {}


def _memory_owner(a: np.ndarray):
    """The object that keeps ``a``'s memory alive (numpy collapses view chains to it:
    an ndarray that owns its data, or e.g. ``hammesh.pages``' mapping)."""
    return a if a.base is None else a.base


def _keep_room(a: np.ndarray, rows: int) -> None:
    """Note that ``a``, a prefix of its buffer, has ``rows`` rows of memory there: a later
    ``_longer`` of ``a`` grows into them without a copy (while the buffer lives)."""
    if not len(a) or rows <= len(a) or not a.flags.c_contiguous:
        return
    addr = a.ctypes.data

    def gone(r, addr=addr) -> None:  # (only its own entry: a longer view may have taken the address)
        if _ROOMY.get(addr, (None,))[0] is r:
            del _ROOMY[addr]

    try:
        ref = weakref.ref(_memory_owner(a), gone)
    except TypeError:  # an owner without weak references: no room kept
        return
    _ROOMY[addr] = (ref, int(rows), a.dtype, a.shape[1:])


def _with_room(buf: np.ndarray, n: int) -> np.ndarray:
    """The first ``n`` rows of ``buf``; the others are room for ``_longer`` (``_keep_room``)."""
    out = buf[:n]
    _keep_room(out, len(buf))
    return out


#: rows of room after the per-triangle arrays that sparse mode's ring fans and ring
#: joins lengthen (two rows each: ``_apply_rings``), where those arrays are made: so
#: that the rows are appended in place rather than every array copied (~130 MB at
#: 1.5 M triangles, for one ring fan and 15 ring joins, and the reserve's pages the
#: output then had to fault in: ``bench_sparse.py --breakdown``)
ROOM_ROWS = 512
#: ... and room for ``m // STEINER_ROOM_DIVISOR`` Steiner points after the points (at
#: 1.5 M q30 triangles sparse mode adds ~0.3 %; beyond the room they are copied)
STEINER_ROOM_DIVISOR = 64


def _longer(a: np.ndarray, extra: int, fill=None, spare: int = 0) -> np.ndarray:
    """``a`` with ``extra`` more rows (``fill`` or unspecified).

    Where ``a`` is a prefix of a buffer an earlier call made with ``spare`` rows, the
    result is a longer prefix of that buffer (no copy: ``a``'s rows are shared, so
    the caller must not need ``a`` unchanged, nor grow the same prefix twice). Else
    one copy into a ``hammesh.pages.fresh`` array (small pages faulted in one call,
    or the reserve's; not ``np.concatenate``'s ``np.empty``: at 1.5 M rows the page
    faults cost more than the copy) with ``spare`` rows of room after it.
    """
    n = len(a)
    entry = _ROOMY.get(a.ctypes.data) if n and a.flags.c_contiguous else None
    if entry is not None:
        ref, rows, dtype, tail = entry
        if ref() is _memory_owner(a) and dtype == a.dtype and tail == a.shape[1:] and rows >= n + extra:
            # the buffer's rows past ``a`` exist (its owner is alive): a view over them
            full = np.lib.stride_tricks.as_strided(a, shape=(rows,) + tail, strides=a.strides, writeable=True)
            out = full[: n + extra]
            if fill is not None:
                out[n:] = fill
            _keep_room(out, rows)  # (its owner is a new view object: a later call grows it too)
            return out
    out = _copy_with_room(a, spare, extra)
    if fill is not None:
        out[n:] = fill
    return out


def _copy_with_room(a: np.ndarray, spare: int, extra: int = 0) -> np.ndarray:
    """A copy of ``a`` with ``extra`` more rows (unspecified) in a ``hammesh.pages.fresh``
    buffer with ``spare`` rows of room after it (``_longer`` grows into them)."""
    n = len(a)
    buf = fresh((n + extra + spare,) + a.shape[1:], a.dtype)
    out = buf[: n + extra]

    def rows(lo: int, hi: int) -> None:  # (one range per core: numpy's copy frees the GIL)
        out[lo:hi] = a[lo:hi]

    _row_pass(rows, n)
    if spare and n:
        _keep_room(out, len(buf))
    return out


def _relabel_cycles(cycle: np.ndarray, lut: np.ndarray) -> None:
    """``cycle[t] = lut[cycle[t]]`` for the covered rows, in place, one row range per core
    (``_join_kernels.relabel_cycles_into``: 1.5 M rows, ~2 ms of one core a call)."""
    _row_pass(lambda lo, hi: _j.relabel_cycles_into(cycle[lo:hi], lut), len(cycle))


def _apply_rings(pts, tri, tw, con, cover: CycleCover, amin_t, orig_of, is_fan, taken, accept=None, spare: int = 0):
    """Replace each ring fan's members by its ``k + 2`` rows (``_ring_fans``, ``_ring_joins``).

    ``taken``: ``(members, polygon, outer half-edges, spoke, x, y)`` per fan, no two
    adjacent, applied in order. A fan's first rows take its members' rows, its last
    two are appended, so every other row and half-edge keeps its index: only the
    fans' own twins and the twins facing them are written (no O(m) renumbering).
    Each fan's effect on the cycles (``_ring_outcome``) is decided on the cover as
    the fans before it left it; with ``accept(index in taken, outcome, find)`` (``find``:
    a cycle id to the one it was merged into) a fan whose
    outcome it refuses is left out. The cycles are relabelled by those outcomes
    (old cycles merged by a union-find over cycle ids, O(m) only as one gather) and
    anew (``cycle_ids_by_halves``) only where a fan split a cycle or its outcome
    was not decided.

    Returns the new ``(points, triangles, twin, pinned, cover, parent_min, orig_of,
    is_fan)`` (``orig_of``: the input triangle holding a fan row's outer edge;
    ``parent_min``: the members' smallest angle; the fans' points follow the
    points) and the indices in ``taken`` of the fans applied.
    """
    m = len(tri)
    extra = 2 * len(taken)
    # (``spare`` rows of room: the ring joins' rows, later, without a copy)
    tri2, tw2, con2 = _longer(tri, extra, None, spare), _longer(tw, 3 * extra, None, 3 * spare), _longer(
        con, 3 * extra, None, 3 * spare)
    is_cov2, cyc2 = _longer(cover.is_cov, 3 * extra, None, 3 * spare), _longer(cover.cycle, extra, None, spare)
    amin2, orig2 = _longer(amin_t, extra, None, spare), _longer(orig_of, extra, None, spare)
    fan2 = _longer(is_fan, extra, True, spare)
    n_pts = len(pts)
    n_cyc = cover.n_cycles
    up: dict[int, int] = {}  # union-find over cycle ids: merged cycles point to a smaller id

    def find(c: int) -> int:
        while c in up:
            c = up[c]
        return c

    relabel_all = False
    applied, new_pts = [], []
    for j, (members, poly, hes, spoke, x, y) in enumerate(taken):
        k = len(poly)
        outcome = None
        if not relabel_all or accept is not None:
            outcome = _ring_outcome(tw2, is_cov2, cyc2, members, hes, spoke, find)
            if accept is not None and not accept(j, outcome, find):
                continue
            if outcome is None or outcome.split:
                relabel_all = True
        base = m + 2 * len(applied)
        rows = list(members) + [base, base + 1]
        v = n_pts + len(applied)
        applied.append(j)
        new_pts.append((x, y))
        # every value read from the arrays before any row of this fan is written
        outer = [int(tw2[h]) for h in hes]
        f_con = [bool(con2[h]) for h in hes]
        f_link = [outer[i] >= 0 and bool(is_cov2[hes[i]]) for i in range(k)]
        f_orig = [int(orig2[h // 3]) for h in hes]
        f_min = float(amin2[members].min())
        for i in range(k):
            r = rows[i]
            tri2[r] = (v, poly[i], poly[(i + 1) % k])
            tw2[3 * r] = 3 * rows[(i - 1) % k] + 2
            tw2[3 * r + 1] = outer[i]
            tw2[3 * r + 2] = 3 * rows[(i + 1) % k]
            if outer[i] >= 0:
                tw2[outer[i]] = 3 * r + 1
            con2[3 * r: 3 * r + 3] = (False, f_con[i], False)
            is_cov2[3 * r: 3 * r + 3] = (bool(spoke[i]), f_link[i], bool(spoke[(i + 1) % k]))
            amin2[r] = f_min
            orig2[r] = f_orig[i]
            fan2[r] = True
        if relabel_all:
            continue
        # the fan rows' cycles: each arc (rows between two consecutive links along
        # the cover spokes) is on its link's new cycle; a ring without links is one
        comp = outcome.comp
        if not outcome.links:
            cyc2[rows] = n_cyc
            n_cyc += 1
            continue
        rep: dict[int, int] = {}  # new cycle (a representative link) -> its id: the smallest old id in it
        for i in outcome.links:
            c = comp[i]
            rep[c] = min(rep.get(c, outcome.old_id[i]), outcome.old_id[i])
        for i in outcome.links:
            if rep[comp[i]] != outcome.old_id[i]:
                up[outcome.old_id[i]] = rep[comp[i]]
        for i in range(k):  # row i lies on the arc of the link its cover spokes lead to
            d = i
            while d not in comp:
                d = (d + 1) % k  # a row without a link has both spokes on the cover
            cyc2[rows[i]] = rep[comp[d]]
    used = m + 2 * len(applied)
    tri2, tw2, con2, is_cov2 = tri2[:used], tw2[: 3 * used], con2[: 3 * used], is_cov2[: 3 * used]
    cyc2, amin2, orig2, fan2 = cyc2[:used], amin2[:used], orig2[:used], fan2[:used]
    if relabel_all:
        cyc2, n_cyc2 = cycle_ids_by_halves(tw2, is_cov2)
    else:
        n_cyc2 = n_cyc
        if up:  # merged ids resolved, then made contiguous again (one gather)
            lut = np.arange(n_cyc, dtype=np.int64)
            for c in up:
                lut[c] = find(c)
            alive = np.zeros(n_cyc, np.bool_)
            alive[lut] = True
            rank = np.cumsum(alive) - 1
            n_cyc2 = int(alive.sum())
            _relabel_cycles(cyc2, rank[lut])
    cover2 = CycleCover(
        is_cov=is_cov2, cycle=cyc2, n_cycles=int(n_cyc2), n_uncovered=int((cyc2 < 0).sum()),
        n_unmatched=cover.n_unmatched, n_rotations=cover.n_rotations,
    )
    pts2 = _longer(pts, len(new_pts), None, spare // 2)  # (a ring join: one point, two rows)
    pts2[n_pts:] = np.asarray(new_pts, np.float64).reshape(-1, pts.shape[1])
    return (pts2, tri2, tw2, con2, cover2, amin2, orig2, fan2), applied


def corner_bound(points: np.ndarray, triangles: np.ndarray, twin: np.ndarray) -> float:
    """Half the smallest boundary corner: no Hamiltonian triangulation of the domain does better.

    A corner of the boundary with interior angle theta (a wedge at a boundary vertex)
    covered by a single triangle makes that triangle's two edges there boundary
    edges: a leaf of the dual graph, which no Hamiltonian cycle passes (unless the
    piece is that one triangle). So every corner holds two triangles or more and one
    of them has an angle <= theta / 2 there, whatever the construction, as long as
    the boundary is kept (the certificate checks that it is). Returns ``min theta / 2``
    (radians) over the wedges; ``pi`` for a mesh without boundary. Walks each wedge
    around its vertex from its incoming boundary edge (vectorised over the wedges,
    one step per triangle of the widest wedge).
    """
    pts = np.asarray(points, dtype=np.float64)
    tri = np.asarray(triangles, dtype=np.int64)
    h = np.flatnonzero(np.asarray(twin) < 0)
    if not len(h):
        return math.pi
    cur_t, cur_k = h // 3, (h % 3 + 1) % 3  # corner of the boundary edge's end b
    theta = np.zeros(len(h))
    idx = np.arange(len(h))
    for _ in range(len(tri) + 1):  # a wedge has at most every triangle
        if not len(idx):
            break
        t, k = cur_t[idx], cur_k[idx]
        theta[idx] += corner_angle(pts, tri, t, k)
        g = twin[3 * t + k]  # the edge leaving b in t, seen from the next triangle
        go = g >= 0
        idx, g = idx[go], g[go]
        cur_t[idx], cur_k[idx] = g // 3, (g % 3 + 1) % 3
    return 0.5 * float(theta.min())


def join_bounds(points: np.ndarray, triangles: np.ndarray, twin: np.ndarray, cycle: np.ndarray,
                uncovered: np.ndarray | None = None):
    """What joins can keep at the triangles a cover leaves off, at best (issue 13).

    An uncovered triangle ``t`` is absorbed by a join over one of its interior edges
    ``e`` (a swap, or a split with its point placed anywhere in the quadrilateral) or
    split at its incenter and bridged. A join over ``e`` divides the two corners
    opposite ``e`` (t's and the neighbour u's: the swap's diagonal ends there, the
    split's point is joined to them), so one of its angles is at most
    ``min(t_opp, u_opp) / 2``; the incenter halves every corner of t. So no join keeps
    more than ``max(max_e min(t_opp, u_opp) / 2, min angle of t / 2)`` there: on an
    uncovered triangle with a boundary edge ``ab`` opposite a wide corner (e.g.
    33/33/114 degrees) that is ~ half of t's corners at ``a`` and ``b``. Only a cover
    that passes t keeps it whole.

    ``uncovered``: ``np.flatnonzero(cycle < 0)`` if the caller has it (an O(m) pass).
    Returns ``(rows, bound, boundary)``: the *isolated* uncovered triangles (every
    neighbour covered; chains of uncovered triangles go to fans), each one's bound
    (radians) and whether it has a boundary edge.
    """
    pts = np.asarray(points, dtype=np.float64)
    tri = np.asarray(triangles, dtype=np.int64)
    unc = np.flatnonzero(cycle < 0) if uncovered is None else uncovered
    he = 3 * unc[:, None] + np.arange(3)
    g = twin[he]
    inner = g >= 0
    iso = np.where(inner, cycle[np.where(inner, g, 0) // 3] >= 0, True).all(axis=1)
    unc, he, g, inner = unc[iso], he[iso], g[iso], inner[iso]
    if not len(unc):
        return unc, np.zeros(0), np.zeros(0, np.bool_)
    ks = np.arange(3)
    t_corner = np.stack([corner_angle(pts, tri, unc, np.full(len(unc), k)) for k in ks], axis=1)
    gg = np.where(inner, g, 0)
    u_opp = corner_angle(pts, tri, (gg // 3).ravel(), ((gg % 3 + 2) % 3).ravel()).reshape(gg.shape)
    return unc, lone_join_bound(t_corner, u_opp, inner), ~inner.all(axis=1)


class PlanSteps(NamedTuple):
    """Where the plan (``_sparse_kernels.plan_merges``) put its steps, found once.

    ``rows``: the triangles in a join (``join >= 0``), ascending; ``slots``: the
    half-edges with a bridge (``slot != PLAIN``), ascending. The steps after the plan
    (``_place_taken``, ``_alternating_merges``, ``_ring_joins``, the report) only undo
    steps and append rows in none, so what is left of these lists is what a scan of
    every row and slot would find, at the cost of the few entries.
    """

    rows: np.ndarray
    slots: np.ndarray

    def joined(self, join: np.ndarray) -> np.ndarray:
        """The triangles still in a join, ascending (``np.flatnonzero(join >= 0)``)."""
        return self.rows[join[self.rows] >= 0]

    def slotted(self, slot: np.ndarray) -> np.ndarray:
        """The half-edges still with a bridge, ascending (``np.flatnonzero(slot != PLAIN)``)."""
        return self.slots[slot[self.slots] != _k.PLAIN]

    def taken(self, join: np.ndarray, n_cand: int) -> np.ndarray:
        """The places in Kruskal's order of the joins still taken, ascending
        (``np.unique(join[self.joined(join)])``, by a mask of the ``n_cand`` places
        instead of a sort: ~27 k entries at 1.5 M, 1.5-3 ms -> ~0.3 ms)."""
        is_taken = np.zeros(n_cand, np.bool_)
        is_taken[join[self.joined(join)]] = True
        return np.flatnonzero(is_taken)


def _place_taken(
    score, order, join, cand, ckind, slack, newmin, newmax, point, global_lo: float, hi: float, con, tw, cycle, status,
    counts, steps_at: PlanSteps, iters: int,
) -> int:
    """Place the Steiner points of the joins Kruskal took below the rule, with no reach.

    Before the plan a split is placed only if its midpoint misses the rule by less
    than ``PLACE_REACH_DEG``: placing further ones moves them ahead in Kruskal's
    order and changes which joins the plan takes (measured: more Steiner points and
    worse joins elsewhere). Once the plan is fixed, a join it took below the rule
    (a free edge) is judged again with its point placed wherever the compass search
    goes (``score``): the better of its swap and its placed split is kept, and the
    pair's ``status`` and the plan's ``counts`` follow a change of kind. Returns the
    number of joins improved. ``steps_at``: the plan's steps (:class:`PlanSteps`).
    """
    taken = order[steps_at.taken(join, len(order))]
    low = taken[(slack[taken] < 0.0) & ~con[cand[taken]]]
    if not len(low):
        return 0
    before = [x[low].copy() for x in (ckind, slack, newmin, newmax, point)]
    # (the compass search alone, as before the plan; measured with the exact optimum
    # (``_join_kernels.ridge_ascent``) here: rows below the rule on the 16 k corpus
    # 533 -> 538 (la 46 -> 45, face 59 -> 63, square_circle_hole 72 -> 75), ring
    # joins 69 -> 62: the joins it changes are not the ones the ring joins need)
    score(low, iters, math.inf, False)
    # better: a larger smallest angle, the largest no worse than allowed (the slack
    # alone would trade a max angle above the rule for a larger min)
    # and now meeting the rule, or newly reaching it against the input's minimum
    # (``global_lo``): a placed split that fixes neither would turn a swap's two rows
    # below the rule into four, or add a Steiner point for nothing the targets see
    # (a split placed anew in place of its midpoint costs nothing: taken if better)
    glob_now = (newmin[low] >= global_lo) & (newmax[low] <= hi)
    glob_before = (before[2] >= global_lo) & (before[3] <= hi)
    fixes = (slack[low] >= 0.0) | ((newmin[low] >= global_lo) & (before[2] < global_lo)) | (
        (before[0] == _j.SPLIT_JOIN) & (ckind[low] == _j.SPLIT_JOIN)
    )
    better = (
        (slack[low] > before[1]) & (newmin[low] > before[2]) & fixes & (newmax[low] <= np.maximum(hi, before[3]))
    )
    # or newly within both absolute targets (issue 13's min and max), e.g. a swap whose
    # largest angle is over the input's + 5 degrees replaced by a placed split
    better |= glob_now & ~glob_before
    for x, x0 in zip((ckind, slack, newmin, newmax, point), before):
        x[low[~better]] = x0[~better]
    k0 = before[0]
    changed = low[better & (ckind[low] != k0)]
    t, u = cand[changed] // 3, tw[cand[changed]] // 3
    swap = ckind[changed] == _j.SWAP_JOIN
    status[t] = np.where(swap, _k.SWAP, _k.EDGE)
    status[u] = status[t]
    absorb = cycle[u] < 0
    counts[0] += int((swap & absorb).sum()) - int((~swap & absorb).sum())
    counts[1] += int((swap & ~absorb).sum()) - int((~swap & ~absorb).sum())
    counts[3] += int((~swap).sum()) - int(swap.sum())
    return int(better.sum())


#: joins below the rule between two cycles that one call tries to replace by a cover
#: swap merging the two cycles (``_alternating_merges``), worst first
ALT_MERGE_TRIES = 32
#: give-ups of an alternating cycle (``_join_kernels.alternating_cycles_into``): its length is twice that
ALT_MERGE_DEPTH = 20
#: steps of the search for one join's alternating cycles (``_join_kernels.alternating_cycles_into``)
ALT_MERGE_BUDGET = 20_000
#: calls of ``_alternating_merges``, each on the cover the one before left (2: one more
#: swap on the 16 k corpus, 351 rows below the rule either way)
ALT_MERGE_PASSES = 1
#: alternating cycles judged per join (``_swap_outcome``), shorter first
ALT_MERGE_CHECKS = 24
#: alternating cycles per join also judged for merging more cycles than the join's two
#: (taken where the plan joins exactly those by a subtree of its steps, all undone)
ALT_MERGE_WIDER = 16
#: below this many triangles the swaps' outside pairings are read off cycle positions
#: (``_join_kernels.cycle_positions_into``, O(m) again after each swap taken), not walked
#: (CPU of the whole call against the walks, session 13: 15 k 0.054 / 0.060 s, 30 k
#: 0.098 / 0.103 s, 76 k 0.192 / 0.166 s: the renumbering grows with m)
ALT_POSITIONS_BELOW = 25_000
#: there, in place of ``ALT_MERGE_DEPTH``, ``ALT_MERGE_CHECKS``, ``ALT_MERGE_WIDER``: the checks
#: read positions, so more of them cost what the walks did (docs/sparse.md, session 13)
ALT_SMALL_DEPTH, ALT_SMALL_CHECKS, ALT_SMALL_WIDER = 28, 64, 64
#: most steps of one swap's outside walks (``_join_kernels.swap_merge_outcome``); undecided: not taken
ALT_MERGE_WALK = 20_000


def _swap_outcome(tw, is_cov, flipped: set, cycle, group: set, find) -> RingOutcome | None:
    """What a cover swap inside ``group`` does to the cycles crossing it, decided locally.

    ``flipped``: the half-edges (both of each edge) whose cover state the swap
    changes. As ``_relabel_group`` pairs the links (outside: the cover as it is,
    walked in lock-step where a cycle crosses more than once; inside: the swapped
    cover), without labelling. None if a walk is undecided, or if some triangle of
    the group is not on a path between two links afterwards (a cycle wholly inside
    the group: a split) or some cycle lay wholly inside it before (it would merge
    unseen).
    """
    links = _border_links(tw, is_cov, group)
    old_id = {h: find(int(cycle[tw[h] // 3])) for h in links}
    by_id: dict[int, list] = {}
    for h in links:
        by_id.setdefault(old_id[h], []).append(h)
    if any(find(int(cycle[x])) not in by_id for x in group):
        return None
    pairs = _outside_pairs(tw, is_cov, by_id)
    if pairs is None:
        return None
    outside = pairs[0]
    paths = _inside_pairs(tw, lambda h: bool(is_cov[h]) != (h in flipped), group, links)
    if paths is None or len(paths[1]) != len(group):
        return None
    inside = paths[0]
    comp = _link_components(links, outside, inside)
    split = any(len({comp[h] for h in hs}) > 1 for hs in by_id.values())
    return RingOutcome(links, old_id, comp, split)


def _label_paths(tw, is_cov, group: set, out: RingOutcome, find, cyc) -> None:
    """After a swap inside ``group``: each of its triangles takes the id of the cycle
    whose path through the group it is on now (``out.comp``; merged ids by ``find``)."""
    ids: dict = {}
    for h in out.links:
        ids.setdefault(out.comp[h], find(out.old_id[h]))
    for h in out.links:
        came = h
        while True:
            x = came // 3
            cyc[x] = ids[out.comp[h]]
            f = next(3 * x + k for k in range(3) if 3 * x + k != came and is_cov[3 * x + k])
            if tw[f] // 3 not in group:
                break
            came = int(tw[f])


#: cover swap tests the other thread may make beyond the one the caller reads
#: (``_SwapTests``): enough to keep both threads testing, few wasted when one is taken
SWAP_TESTS_AHEAD = 2


class _SwapTests:
    """One task's cover-swap tests (``_join_kernels.swap_merge_outcome``), shared by the
    caller and one pool thread in the order the caller reads them.

    Each thread claims the next untested alternating cycle; the caller reads the
    answers in order and, where one is not there yet, tests the next unclaimed cycle
    itself (or waits for the other thread's). A test only reads the cover, which
    changes only when a swap is taken, and then the task ends: :meth:`stop` lets the
    other thread finish its test first. So every answer is the one the serial loop
    gets; the tests made beyond the one taken are those the other thread
    claimed while the caller judged an answer (at most ``SWAP_TESTS_AHEAD`` beyond
    the one it reads: ~430 tests at 1.5 M became ~590 without that bound, +0.02 s
    CPU). Cycle ``c`` is asked the wide question
    (merges beyond the two cycles wanted) if ``c < wide`` — the caller asks it while
    its count of answers other than 1 lasts, so exactly there unless an answer 1 came
    before and was not taken; then :meth:`answer` asks again. The tests of one task
    cost from microseconds to ~5 ms each (walks on the big cycle that end undecided at
    ``ALT_MERGE_WALK``): at 1.5 M triangles ~430 of them, 0.06 s. Each thread walks
    through a walk memo of its own (``memos``: the caller's, the other thread's;
    ``_join_kernels.WalkMemo``), kept over the tasks until the cover changes.
    """

    def __init__(self, pool: ThreadPoolExecutor, cover_args: tuple, n: int, ca: int, cb: int, wide: int, pos, plen,
                 memos: tuple):
        self.args, self.n, self.wide, self.cb = cover_args, n, wide, (ca, cb, ALT_MERGE_WALK)
        self.pp, self.memos = (pos, plen), memos
        self.answers = np.full(n, -1, np.int64)
        self.next, self.read, self.ended = 0, 0, False
        self.lock = threading.Condition()
        self.other = pool.submit(self._run)

    def _claim(self, ahead: bool = False) -> int:
        """The next untested cycle, -1 if none; ``ahead``: the other thread's claim, at
        most ``SWAP_TESTS_AHEAD`` cycles past the one the caller reads (it waits)."""
        with self.lock:
            while ahead and self.read + SWAP_TESTS_AHEAD < self.next < self.n:
                self.lock.wait()
            c = self.next
            if c >= self.n:
                return -1
            self.next = c + 1
            return c

    def _test(self, c: int, wide: bool, mine: bool = True) -> int:
        return _k.swap_outcome_of(*self.args, c, *self.cb, wide, *self.pp, *self.memos[0 if mine else 1])

    def _run(self) -> None:
        try:
            while (c := self._claim(ahead=True)) >= 0:
                a = self._test(c, c < self.wide, mine=False)
                with self.lock:
                    self.answers[c] = a
                    self.lock.notify_all()
        finally:  # (also on an error: the caller stops waiting and raises it, ``answer``)
            with self.lock:
                self.next, self.ended = self.n, True
                self.lock.notify_all()

    def answer(self, c: int, wide: bool) -> int:
        """Cycle ``c``'s answer to the question the serial loop asks (``wide`` or not)."""
        with self.lock:
            self.read = c
            self.lock.notify_all()
        while self.answers[c] < 0:
            mine = self._claim()
            if mine >= 0:
                self.answers[mine] = self._test(mine, mine < self.wide)
                continue
            with self.lock:
                self.lock.wait_for(lambda: self.answers[c] >= 0 or self.ended)
            if self.answers[c] < 0:
                self.other.result()  # (the other thread's error, if it stopped on one)
                self.answers[c] = self._test(c, c < self.wide)  # (else the finally ran first)
        a = int(self.answers[c])
        if wide and c >= self.wide and a != 1:  # (asked narrow: the wide answer differs only here)
            a = self._test(c, True)
        return a

    def stop(self) -> None:
        """No more tests; returns once the other thread's test in progress is done."""
        with self.lock:
            self.next = self.n
            self.lock.notify_all()
        self.other.result()


def _flip_group(tw: np.ndarray, fl: np.ndarray) -> np.ndarray:
    """The triangles on either side of the half-edges ``fl`` of an alternating cycle, sorted."""
    return np.unique(np.concatenate([fl // 3, tw[fl] // 3]))


def _alternating_merges(tw, cover: CycleCover, is_fan, order, join, cand, slack, newmin, newmax, status, slot,
                        swap_he, counts, lo: float, hi: float, steps_at: PlanSteps):
    """Joins below the rule between two cycles replaced by merging the cycles in the cover (issue 13).

    A swap or split over ``ab`` of ``t = abc`` (cycle A), ``u = bad`` (cycle B)
    divides the corners ``c`` and ``d``; where no edge between A and B has both
    corners large enough, every join between them misses the local rule. But the
    cover itself can change for free: swapping cover and non-cover edges along an
    *alternating cycle* through ``t-u`` (``_join_kernels.alternating_cycles_into``; the cover's
    rotations around a vertex are the shortest) keeps every triangle on two cover
    edges, nothing in the mesh changes, and where it makes A and B one cycle and
    leaves every other cycle crossing it one cycle (``_swap_outcome``), the join is
    not needed. Tried, up to ``ALT_MERGE_TRIES``, on the joins between two cycles
    below the rule, those missing the absolute targets (``lo``, ``hi``) first, then by
    slack; the cycle's other triangles must take part in no step of the plan (nor
    in a fan, nor in an earlier swap), so the plan is patched as ``_ring_joins``
    patches it: the join's statuses and counts undone, Kruskal's tree minus the edge
    A-B with A and B one node. Returns the new cover and the number of merges
    (``counts`` and the plan's arrays are updated in place). ``steps_at``: the plan's
    steps (:class:`PlanSteps`).
    """
    is_taken = np.zeros(len(cand), np.bool_)  # (the joins taken, without np.unique's sort)
    is_taken[join[steps_at.joined(join)]] = True
    low = order[np.flatnonzero(is_taken)]
    low = low[slack[low] < 0.0]
    t_of, u_of = cand[low] // 3, tw[cand[low]] // 3
    low = low[(cover.cycle[t_of] >= 0) & (cover.cycle[u_of] >= 0)]
    miss = ~((newmin[low] >= lo) & (newmax[low] <= hi))
    # Thm 2.4 bridges between two cycles first (two incenters, sectors halving every
    # corner), each the one step of both its triangles; then the joins below the rule
    slotted = steps_at.slotted(slot)  # (few: the bridges' half-edges)
    bridged = slotted[tw[slotted] > slotted]
    bt, bu = bridged // 3, tw[bridged] // 3
    sole = (cover.cycle[bt] >= 0) & (cover.cycle[bu] >= 0)
    sole &= ((slot.reshape(-1, 3)[bt] != _k.PLAIN).sum(axis=1) == 1)
    sole &= ((slot.reshape(-1, 3)[bu] != _k.PLAIN).sum(axis=1) == 1)
    tasks = bridged[sole].tolist() + cand[low[np.lexsort((slack[low], ~miss))]].tolist()
    tasks = tasks[:ALT_MERGE_TRIES]
    if not tasks:
        return cover, 0
    # (copies in pages of the reserve: 15 MB at 1.5 M that would fault in here)
    is_cov = fresh(cover.is_cov.shape, np.bool_)
    cyc = fresh(cover.cycle.shape, cover.cycle.dtype)  # (the decisions read the ids as the swaps before left them)
    # triangles no alternating cycle may pass: in a step of the plan, a fan, uncovered,
    # or on a swap taken before (an O(m) pass, only where some join is tried)
    blocked = fresh(len(status), np.bool_)

    def rows(lo_: int, hi_: int) -> None:  # (the copies one range per core too: numpy's copy frees the GIL)
        cyc[lo_:hi_] = cover.cycle[lo_:hi_]
        is_cov[3 * lo_:3 * hi_] = cover.is_cov[3 * lo_:3 * hi_]
        _k.blocked_rows_into(status, is_fan, cyc, blocked, lo_, hi_)

    _row_pass(rows, len(status))
    blocked[slotted // 3] = True
    used: set[int] = set()
    root = np.arange(cover.n_cycles, dtype=np.int64)  # merged cycle ids: union-find

    def find(c: int) -> int:
        while root[c] != c:
            c = int(root[c])
        return c

    # the plan's steps between two cycles that a swap may make unneeded: its joins
    # (any slack) and the bridges above, as half-edge -> is a bridge
    every = order[np.flatnonzero(is_taken)]
    jt, ju = cand[every] // 3, tw[cand[every]] // 3
    steps = dict.fromkeys(cand[every[(cover.cycle[jt] >= 0) & (cover.cycle[ju] >= 0)]].tolist(), False)
    steps.update(dict.fromkeys(bridged[sole].tolist(), True))
    # cycle id (a root of ``root``) -> the steps at that cycle, a set made when first
    # asked for (``at_of``) from the steps sorted by cycle: a set per cycle made up
    # front (~12 k at 1.5 M) cost more in the garbage collector's passes than the rest
    hs_all = np.fromiter(steps, np.int64, len(steps))
    ends = np.concatenate([cyc[hs_all // 3], cyc[tw[hs_all] // 3]])
    by_end = np.argsort(ends, kind="stable")
    at_h = np.concatenate([hs_all, hs_all])[by_end]
    at_start = np.searchsorted(ends[by_end], np.arange(cover.n_cycles + 1))
    at: dict[int, set] = {}

    def at_of(c: int) -> set:
        s = at.get(c)
        if s is None:
            s = at[c] = set(at_h[at_start[c]:at_start[c + 1]].tolist())
        return s

    def undo(h: int) -> None:
        """The plan's step over ``h`` is not needed: undone (its triangles pass whole)."""
        t, u = h // 3, int(tw[h] // 3)
        if steps.pop(h):
            slot[h] = slot[tw[h]] = _k.PLAIN
            counts[2] -= 1
        else:
            counts[1 if status[t] == _k.SWAP else 3] -= 1
        for x in (t, u):
            status[x] = _k.PASS
            swap_he[x] = join[x] = -1

    def tree_inside(merged: set) -> list | None:
        """The plan's steps between the cycles ``merged``, if they span them (a subtree of
        Kruskal's tree: all of them can go), else None (the swap would close a loop)."""
        # every step inside has an end at a cycle other than the one with the most
        # steps (the big cycle holds most of the mesh's joins: not scanned)
        sets = sorted((at_of(c) for c in merged), key=len)
        near = set().union(*sets[:-1])
        inside = [h for h in near if find(int(cyc[h // 3])) in merged and find(int(cyc[tw[h] // 3])) in merged]
        if len(inside) != len(merged) - 1:
            return None
        parent = {c: c for c in merged}

        def top(c):
            while parent[c] != c:
                c = parent[c]
            return c

        for h in inside:
            parent[top(find(int(cyc[h // 3])))] = top(find(int(cyc[tw[h] // 3])))
        return inside if len({top(c) for c in merged}) == 1 else None

    # cycle positions (below ``ALT_POSITIONS_BELOW`` triangles): the checks' outside
    # pairings read off them, not walked; made again after each swap taken (O(m))
    small = len(status) < ALT_POSITIONS_BELOW
    pos = fresh(len(status), np.int64) if small else np.empty(0, np.int64)
    plen = fresh(len(pos), np.int64) if small else pos
    if small:
        _j.cycle_positions_into(tw, is_cov, pos, plen)
    # (with positions the checks are cheap: more of them, deeper)
    depth, checks, n_wider = (ALT_SMALL_DEPTH, ALT_SMALL_CHECKS, ALT_SMALL_WIDER) if small else (
        ALT_MERGE_DEPTH, ALT_MERGE_CHECKS, ALT_MERGE_WIDER)
    buf = np.empty(checks * (2 * depth + 2), np.int64)
    starts = np.empty(checks + 1, np.int64)
    # big meshes: a task's tests shared by two threads (``_SwapTests``)
    pool = ThreadPoolExecutor(1) if not small and threads.cores() > 1 else None
    # the walks each thread made on this cover (big meshes: the same links are walked
    # again and again, ``_join_kernels.ring_outside_pairs_memo``), cleared when it changes
    memos = tuple(_j.new_walk_memo(2, 0) if small else _j.new_walk_memo(steps=_j.WALK_MEMO_STEPS) for _ in range(2))
    done = 0
    for h0 in tasks:
        t, u = h0 // 3, int(tw[h0] // 3)
        if t in used or u in used or h0 not in steps:
            continue
        ca, cb = find(int(cyc[t])), find(int(cyc[u]))
        n = _j.alternating_cycles_into(tw, is_cov, blocked, h0, depth, ALT_MERGE_BUDGET, buf, starts, checks)
        wider = n_wider
        tests = None
        if pool is not None and n > 1:
            tests = _SwapTests(pool, (tw, is_cov, cyc, root, buf, starts), n, ca, cb, wider, pos, plen, memos)
        for c in range(n):
            fl = buf[starts[c]:starts[c + 1]]
            # (1: ca and cb merge alone; 2, asked while ``wider`` lasts: more cycles merge,
            # taken if the plan joins them by a subtree)
            if tests is not None:
                merges = tests.answer(c, wider > 0)
            else:
                merges = _j.swap_merge_outcome(tw, is_cov, cyc, root, fl, _flip_group(tw, fl), ca, cb,
                                               ALT_MERGE_WALK, wider > 0, pos, plen, *memos[0])
            if merges != 1:
                if wider <= 0:
                    continue
                wider -= 1
                if merges != 2:
                    continue
            flips = fl.tolist()
            group = set(_flip_group(tw, fl).tolist())  # (made only here: ~700 cycles tested at 1.5 M, few pass)
            flipped = set(flips) | {int(tw[h]) for h in flips}
            out = _swap_outcome(tw, is_cov, flipped, cyc, group, find)  # (the same decision, with the pairings)
            if out is None or out.split:
                continue
            by_comp: dict = {}
            for h in out.links:
                by_comp.setdefault(out.comp[h], set()).add(out.old_id[h])
            gone = []
            for merged in (ids for ids in by_comp.values() if len(ids) > 1):
                inside = tree_inside(merged)
                if inside is None:
                    gone = None
                    break
                gone.append((merged, inside))
            if not gone or h0 not in {h for _, inside in gone for h in inside}:
                continue
            if tests is not None:
                tests.stop()  # (before the cover changes under the other thread's test)
            _flip_cover(tw, is_cov, flips)
            for memo in memos:  # (both threads idle: the other one stopped above)
                _j.clear_walk_memo(memo)
            blocked[list(group)] = True
            used.update(group)
            for merged, inside in gone:
                keep_id = min(merged)
                sets = sorted((at_of(c) for c in merged), key=len)
                near = sets[-1]  # (the largest set updated in place, the others added)
                near.update(*sets[:-1])
                near.difference_update(inside)
                for c_id in merged:
                    root[c_id] = keep_id
                    at[c_id] = set()  # (merged into keep_id's)
                at[keep_id] = near
                for h in inside:
                    undo(h)
                    done += 1
            _label_paths(tw, is_cov, group, out, find, cyc)
            if small:
                _j.cycle_positions_into(tw, is_cov, pos, plen)
            break
        if tests is not None:
            tests.stop()
    if pool is not None:
        pool.shutdown()
    if not done:
        return cover, 0
    lut = np.array([find(c) for c in np.flatnonzero(root != np.arange(len(root))).tolist()], np.int64)
    lut_all = np.arange(cover.n_cycles, dtype=np.int64)
    lut_all[root != np.arange(len(root))] = lut
    lut = lut_all
    alive = lut == np.arange(cover.n_cycles)
    rank = np.cumsum(alive) - 1
    _relabel_cycles(cyc, rank[lut])
    return replace(cover, is_cov=is_cov, cycle=cyc, n_cycles=int(alive.sum())), done


def sparse_cycles(
    points: np.ndarray,
    triangles: np.ndarray,
    twin: np.ndarray,
    is_con: np.ndarray,
    min_angle: float,
    *,
    keep: float = KEEP,
    swaps: bool = True,
    edge_splits: bool = True,
    flip_bridges: bool = True,
    max_fold_deg: float = 180.0,
    use_cover: bool = True,
    place_iters: int = PLACE_ITERS,
    fans: bool = True,
    improve: bool = True,
    beside_cover: Callable[[], object] | None = None,
    local: bool = False,
    tree: str = "quadtree",
) -> SparseResult:
    """The sparse construction on arrays (unverified).

    Parameters
    ----------
    points : (n, d) float64, d = 2 (counter-clockwise triangles) or 3 (surface)
    triangles : (m, 3) int64, consistently oriented
    twin : (3 m,) int64
    is_con : (3 m,) bool
        Pinned half-edges: never flipped nor swapped, split only at their midpoint
        (constrained edges, edges between regions).
    min_angle : float
        The input's minimum angle in radians; every join keeps every new angle above
        half of it (the proven floor, Thm 2.4).
    keep : float
        The local quality rule (issue 13): a join *meets* it if every new angle is
        at least ``keep`` x the smallest angle of the two triangles it replaces and
        no new angle exceeds the input's largest angle + 5 degrees. Joins meeting it
        are taken first, best first; where none does, the best one available.
    swaps : bool
        Allow Steiner-free swaps (they change the surface in 3D).
    edge_splits : bool
        Allow joins by one Steiner point on (or, planar and free, near) the shared edge.
    flip_bridges : bool
        Bridge free edges by flipping between incenters (False: by their midpoint,
        which keeps a 3D surface exactly).
    max_fold_deg : float
        3D swaps only between triangles whose normals differ by at most this.
    use_cover : bool
        False: no cover, every triangle is split and bridged (Thm 2.4 itself, as a
        baseline for surfaces).
    place_iters : int
        Step halvings of the compass search placing a split's Steiner point (0: the
        midpoint).
    fans : bool
        Planar only: replace chains of uncovered triangles by fans around one
        Steiner point each (``_join_kernels.fan_groups``) instead of a point each.
    improve : bool
        Planar only: after the joins, flip edges the cycle crosses between two
        consecutive triangles where that keeps the cycle and raises the pair's
        smallest angle (``_improve_kernels``): the join's cavity re-triangulated.
        From ``IMPROVE_ALL_BELOW`` output rows on, only around the new rows that miss
        the absolute targets (``keep`` x the input's smallest angle, its largest + 5 degrees).
    beside_cover : callable, optional
        Called once, to hand work that needs nothing of the construction to another
        thread (``hammesh.hamiltonian`` starts the certificate's look at the input
        there, and without a page reserve faults one for the steps after the cover):
        as the cover starts, or, where ``hammesh.pages`` holds a reserve, as the
        splits are placed (``SIDE_BEFORE_PLACING``: their sorts and open candidates,
        then the plan's Python, run on one core, and it is mostly done before the
        cover swaps' tests take two threads; the cover's matching and the scores take
        both), or as the plan starts (``SIDE_BEFORE_PLAN`` alone), else after the
        output rows, beside the improvement.
    local : bool
        The rows are in ``renumber_local``'s order (``sparse_hamiltonian`` from
        ``LOCAL_MIN_TRIANGLES`` on): the cover splits them at a quadrant border of that
        order (``cycle_cover(..., local=True)``).
    tree : {"quadtree", "fishbone", "comb"}
        ``"fishbone"`` (planar): the cover confined to the fishbone's cells and bands,
        the joins in its class order (``sparse_cells``, issue 14: a compact cycle).
        ``"comb"`` (planar): ``comb_cover``'s compact cycle, the re-routes off.
    """
    if not 0.0 <= keep <= 1.0:
        raise InvalidOptionError(f"keep must be between 0 and 1, got {keep!r}")
    pts = np.ascontiguousarray(points, dtype=np.float64)
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    tw = np.ascontiguousarray(twin, dtype=np.int64)
    con = np.ascontiguousarray(is_con, dtype=np.bool_)
    n, m = len(pts), len(tri)
    steps = _Steps()
    room = ROOM_ROWS if fans and pts.shape[1] == 2 else 0  # (only planar ring fans grow arrays)
    # the corner angles too where the cover's matching judges edges (planar): its first
    # test reads them instead of the points (``_join_kernels.corners_rule_out``)
    corners = fresh((m, 3), np.float32) if use_cover and pts.shape[1] == 2 else None
    amin_t, amax_t, ratio_in, ratio_row = triangle_facts(pts, tri, room, corners)
    steps.done("input_angles")

    def lone_bounds(cycle: np.ndarray) -> tuple:  # (reads the signs of ``cycle`` only)
        unc = np.flatnonzero(cycle < 0)
        return unc, join_bounds(pts, tri, tw, cycle, unc)

    # what the joins can keep at best where the cover leaves triangles off, and what
    # no construction can beat at the boundary's corners (the report): made once the
    # cover knows the rows it leaves off (``cycle_cover(..., beside=)``) or after it
    bounds: list = []
    amax_in = float(amax_t.max()) if m else 0.0  # (the input's largest angle, once: an O(m) pass)
    hi = amax_in + math.radians(MAX_ANGLE_SLACK_DEG) if m else math.pi
    floor = 0.5 * min_angle * (1.0 + SWAP_MARGIN)
    cos_fold = math.cos(math.radians(max_fold_deg)) if max_fold_deg < 180 else -2.0
    fish = None  # (tree="fishbone": sparse_cells' cells and classes)
    combed = False  # (tree="comb": the comb's cover taken)
    if use_cover:
        # edges whose join (swap or midpoint split) keeps the rule: the cover's
        # matching prefers them as its non-cover edges, where cycles get joined.
        # Planar: judged inside the matching, only where it has to choose
        # (``cycle_cover(..., judge=True)``: a third of the edges at 1.5 M)
        good = None
        if pts.shape[1] != 2:
            inner = np.flatnonzero(tw > np.arange(3 * m))
            g_kind = np.zeros(len(inner), np.int8)
            g_slack = np.empty(len(inner))
            _j.score_joins_into(
                pts, tri, tw, con, inner, amin_t, float(keep), hi, floor, cos_fold, bool(swaps), bool(edge_splits),
                0, 0.0, g_kind, g_slack, np.empty(len(inner)), np.empty(len(inner)),
                np.empty((len(inner), pts.shape[1])),
            )
            good = np.zeros(3 * m, np.bool_)
            ok = inner[g_slack >= 0.0]
            good[ok] = True
            good[tw[ok]] = True
        steps.done("judge_edges")
        # the other core's work: at the cover's start where it has pages to fault for
        # the steps after the cover (no reserve left by quality_mesh); with a reserve
        # only the certificate's look at the input, which waits for the serial plan:
        # beside the cover it took a core from the matching's two threads (0.1 s CPU
        # at 1.5 M)
        late = beside_cover is not None and reserved() > 0
        if beside_cover is not None and not late:
            beside_cover()
        fish = fishbone_cells(pts, tri, tw) if tree == "fishbone" and pts.shape[1] == 2 else None  # (issue 14)
        # (the matching's and the re-colouring's judge)
        rule = JoinRule(amin_t, float(keep), hi, con, bool(swaps), bool(edge_splits),
                        corners) if pts.shape[1] == 2 else None
        cover = None
        if tree == "comb" and pts.shape[1] == 2:  # (issue 14: ``comb_cover``, docs/partition.md)
            cover = comb_cover(pts, tri, tw)
            if not cover.is_cov.any():  # no interior vertex, no vertex tree (a ring one
                cover = None  # triangle wide): the free cover, which may still find a cycle
        combed = cover is not None
        if cover is None:
            cover = cycle_cover(tri, tw, good=good, points=pts, local=local, rule=rule,
                                cells=None if fish is None else fish.cell, judge=rule is not None,
                                beside=lambda cycle: bounds.append((lone_bounds(cycle), corner_bound(pts, tri, tw))))
        rule = corners = None  # (the corner angles' pages given back: only the cover reads them)
    else:
        if beside_cover is not None:
            beside_cover()
        cover = CycleCover(np.zeros(3 * m, np.bool_), np.full(m, -1, np.int64), 0, m, 0)
    steps.done("cover")
    n_unc0 = cover.n_uncovered
    # (the bounds: two passes of numpy over the rows and half-edges, ~10 ms at 1.5 M: beside the
    # cover's rotations if it made them on two threads, else side by side here; both
    # read the arrays before the ring fans write rows of them in place)
    if not bounds:
        bounds.append(run_all([partial(lone_bounds, cover.cycle), partial(corner_bound, pts, tri, tw)]))
    (unc_all, (jb_rows, jb, jb_bnd)), c_bound = bounds[0]
    n_unc_bnd = int((tw[3 * unc_all[:, None] + np.arange(3)] < 0).any(axis=1).sum())
    steps.done("bounds")
    quad0 = cover.quad  # the cover's quadtree cells order the joins (``_join_order``)
    pts0, m0 = pts, m
    orig_of = fresh(m + room, np.int64)  # (the reserve's pages, numbered on both cores: no 12 MB arange)
    _row_pass(lambda lo, hi_: _k.iota_into(orig_of, lo, hi_), m + room)
    orig_of = _with_room(orig_of, m)
    is_fan = _with_room(fresh(m + room, np.bool_, 0), m)  # (pages faulted: read first in the report)
    n_fan, amin_p = 0, amin_t
    if use_cover and fans and pts.shape[1] == 2 and cover.n_uncovered > 1:
        pts, tri, tw, con, cover, amin_p, orig_f, fan_f, n_fan = _fans(
            pts, tri, tw, con, cover, amin_t, keep, hi, floor, amax_in, unc_all
        )
        if n_fan:  # (else the arrays with room made above stay)
            orig_of, is_fan = orig_f, fan_f
        n, m = len(pts), len(tri)
    n_ring = n_reroute = 0
    if use_cover and fans and pts.shape[1] == 2 and cover.n_uncovered:  # (every size: session 10)
        cover, n_reroute = _reroute(pts, tri, tw, con, cover, is_fan, amin_p, keep * min_angle, hi, 2.0 * floor,
                                    0 if combed else None)  # (they would splice the comb's cycle)
        pts, tri, tw, con, cover, amin_p, orig_of, is_fan, n_ring = _ring_fans(
            pts, tri, tw, con, cover, amin_p, orig_of, is_fan, keep * min_angle, hi, 2.0 * floor
        )
        n, m, n_fan = len(pts), len(tri), n_fan + n_ring
    steps.done("fans")
    n_ring_join = 0
    for ring_pass in range(1):  # (one plan: the ring joins patch it, ``_ring_joins``)
        cand = _k.join_candidates(tw, cover.cycle) if use_cover else np.zeros(0, np.int64)
        ckind = np.zeros(len(cand), np.int8)
        slack = np.empty(len(cand))
        newmin = np.empty(len(cand))
        newmax = np.empty(len(cand))
        point = np.empty((len(cand), pts.shape[1]))
        def score(rows: np.ndarray, iters: int, reach: float = math.radians(PLACE_REACH_DEG), exact: bool = True) -> None:
            c = cand[rows]
            parts = (ckind[rows], slack[rows], newmin[rows], newmax[rows], point[rows])
            _row_pass(
                lambda lo, hi_: _j.score_joins_into(
                    pts, tri, tw, con, c[lo:hi_], amin_p, float(keep), hi, floor, cos_fold, bool(swaps),
                    bool(edge_splits), iters, reach, *(x[lo:hi_] for x in parts), exact,
                ),
                len(c),
                SCORE_MIN_ROWS if iters == 0 else PLACE_MIN_ROWS,
            )
            ckind[rows], slack[rows], newmin[rows], newmax[rows], point[rows] = parts

        t_of, u_of = cand // 3, tw[cand] // 3
        pmin = np.minimum(amin_p[t_of], amin_p[u_of])
        cls = None if quad0 is None else join_classes(quad0, orig_of[t_of], orig_of[u_of])
        if fish is not None:
            cls = fish_classes(fish, orig_of[t_of], orig_of[u_of])
        every = np.arange(len(cand))
        # judge every candidate unplaced; place a split's point only where Kruskal can
        # still use the join after all joins meeting the rule unplaced (``open_candidates``)
        score(every, 0)
        steps.done("score_joins")
        if use_cover and late and SIDE_BEFORE_PLAN and SIDE_BEFORE_PLACING:
            beside_cover()
            late = False
        if place_iters > 0 and edge_splits and pts.shape[1] == 2:  # also when empty: load_kernels loads it
            whole = (newmin >= keep * min_angle) & (newmax <= hi)
            order = _join_order(ckind, slack, newmin, pmin, whole, cls, fish is not None)
            dropped = np.ones(len(cand), np.bool_)  # dropped: a bridge did better
            dropped[order] = False
            rest = np.flatnonzero(dropped)  # (as setdiff1d of every and order, without its sort)
            first = np.concatenate([order, rest])
            open_ = _k.open_candidates(tw, cover.cycle, cover.n_cycles, cand[first], slack[first] >= 0.0)
            redo = first[open_ & (slack[first] >= -math.radians(PLACE_REACH_DEG)) & ~con[cand[first]]]
            # (the compass search alone: its points order Kruskal's choices; with the
            # exact optimum here as well the rows below the rule on the 16 k corpus
            # went 533 -> 540 (face 59 -> 64, square_circle_hole 72 -> 75))
            score(np.sort(redo), int(place_iters), exact=False)
        whole = (newmin >= keep * min_angle) & (newmax <= hi)
        order = _join_order(ckind, slack, newmin, pmin, whole, cls, fish is not None)
        steps.done("place_splits")
        if use_cover and late and SIDE_BEFORE_PLAN:  # (the plan: Python on one core, bar the swap tests)
            beside_cover()
            late = False
        no_absorb = np.zeros(m, np.bool_)
        for attempt in range(4):
            if attempt == 3:
                no_absorb[:] = True
            status, slot, swap_he, join, counts, bad = _k.plan_merges(
                tri, tw, con, cover.cycle, cover.n_cycles, cand[order], ckind[order], no_absorb, flip_bridges, cand,
                room,
            )
            for a, rows in ((status, m + room), (slot, 3 * (m + room)), (swap_he, m + room), (join, m + room)):
                _keep_room(a, rows)  # (the ring joins append rows to the plan: ``_ring_joins``)
            if not bad.any():
                break
            no_absorb |= bad  # an absorbed triangle cut a cycle off: not there
        if bad.any():
            raise VerificationError("internal error: the sparse merge left a piece with two cycles")
        # the plan's steps, found once (the steps after it only undo some, and each
        # reads what is left of these instead of scanning the m rows and 3 m slots again)
        steps_at = PlanSteps(np.flatnonzero(join >= 0), np.flatnonzero(slot != _k.PLAIN))
        n_placed_late = 0
        if PLACE_TAKEN and place_iters > 0 and edge_splits and pts.shape[1] == 2:
            n_placed_late = _place_taken(
                score, order, join, cand, ckind, slack, newmin, newmax, point, keep * min_angle, hi, con, tw, cover.cycle,
                status, counts, steps_at,
                int(place_iters),
            )
        n_alt = 0
        for _ in range(ALT_MERGE_PASSES if use_cover and fans and pts.shape[1] == 2 and ALT_MERGE_TRIES > 0 else 0):
            cover, n_swapped = _alternating_merges(tw, cover, is_fan, order, join, cand, slack, newmin, newmax,
                                                   status, slot, swap_he, counts, keep * min_angle, hi, steps_at)
            n_alt += n_swapped
            if not n_swapped:
                break
        for _ in range(RING_JOIN_PASSES if use_cover and fans and pts.shape[1] == 2 else 0):
            rings = _ring_joins(pts, tri, tw, con, cover, amin_p, orig_of, is_fan, order, join, cand, slack, newmin,
                                newmax, status, slot, swap_he, counts, keep, keep * min_angle, hi, 2.0 * floor,
                                steps_at)
            if rings is None:
                break
            (pts, tri, tw, con, cover, amin_p, orig_of, is_fan), (status, slot, swap_he, join), n_rj = rings
            n_ring_join += n_rj
            n, m, n_fan = len(pts), len(tri), n_fan + n_rj
        break  # the ring joins patch the plan (``_ring_joins``): it is not made again
    steps.done("plan_joins")
    # the triangles a join changes (~2 % at 1.5 M: the output's passes go over these)
    changed = np.flatnonzero(status != _k.PASS)
    split_rows = changed[status[changed] == _k.SPLIT]  # (few: the incenters' triangles)
    # new rows only; a triangle kept whole stays the input's row until the gather
    out, link, parent, partner, kind, mid_a, mid_b, mid_t = _k.emit(
        tri, tw, cover.is_cov, status, slot, swap_he, split_rows, n, changed
    )
    n_split = len(split_rows)
    mids = 0.5 * (pts[mid_a] + pts[mid_b])
    placed = mid_t >= 0
    mids[placed] = point[order[join[mid_t[placed]]]]  # (the few rows: no gather of every candidate)
    inc = _incenters(pts, tri[split_rows])
    all_pts = _longer(pts, len(inc) + len(mids))  # (in place where the points have room)
    all_pts[len(pts):] = np.concatenate([inc, mids])
    tw_new, changed, face_tw, dup = _k.new_row_twins(out, tri, tw, status, len(all_pts), changed)
    if dup >= 0:
        raise VerificationError(f"internal error: output edge of virtual row {int(dup) // 3} used twice")
    # (the walk's table of links, then the gather's row places: one buffer)
    ends = fresh(2 * (len(tri) + len(out)), np.int64)
    order_rows, lengths, low, bad = _k.walk_links(status, cover.is_cov, link, parent, tw, tw_new, changed, face_tw,
                                                  ends)
    if bad >= 0:
        raise VerificationError(f"internal error: output row {int(bad)} is not linked into a cycle")
    # runs in the order of their lowest input triangle; rows, their parents' smallest
    # angle (pm) and the twins renumbered as the claim, in one gather
    run_order = np.argsort(low, kind="stable") if len(lengths) > 1 else np.zeros(len(lengths), np.int64)
    # (and the kept rows' pinned output edges, the improvement's: on the way)
    pinned_out = fresh(3 * len(order_rows), np.bool_) if improve and pts.shape[1] == 2 else None
    out, parent, partner, kind, pm, lengths, claim = _k.rows_in_cycle_order(
        order_rows, lengths, run_order, tri, tw, status, out, parent, partner, kind, tw_new, changed, face_tw, amin_p,
        ends, con=con, pinned=pinned_out,
    )
    if n_fan:  # a fan triangle kept whole: a side joined to a Steiner point; its row is where
        # the gather put it (its places left in ``ends``): the few fan rows, not a pass over all
        fan_t = np.flatnonzero(is_fan)
        kind[ends[fan_t[status[fan_t] == _k.PASS]]] = 0
    steps.done("output_rows")
    if use_cover and late:  # (the improvement, report and mapping back: one core, bar a few
        beside_cover()  # short passes; the swap tests and the output rows' passes take both)
    # the report's worst ratio of the kept rows, begun beside the improvement (which
    # leaves the other core mostly idle): the rows it keeps keep their points
    kept_start = None
    if improve and pts.shape[1] == 2 and len(out):
        kept_start = threads.run_beside(kept_ratio_start, all_pts, out, kind, parent, amin_p)
    n_improve = n_moved = 0
    new_facts = None  # (the new rows' facts, if the improvement's last look is of the final rows)
    n0_input = len(pts0)  # Steiner points follow the input's (fan points first)
    if improve and pts.shape[1] == 2 and len(out):
        out, claim, kind, pm, n_improve, n_moved, new_facts = _improve(
            all_pts, out, claim, kind, pm, lengths, tri, tw, con, parent, partner, mid_a, mid_b, n + n_split, hi,
            n0_input, keep, keep * min_angle, floor, pinned_out,
        )
    steps.done("improve")
    n_fan_rows = int(is_fan.sum())

    def kept_ratio_of() -> float:
        # the kept rows' worst radius ratio: the input's if its worst triangle is kept,
        # else measured on the few kept rows whose smallest angle allows worse
        if ratio_row >= 0:
            n_whole = len(orig_of) - n_fan_rows  # rows not in a fan, in input order
            r_now = np.searchsorted(orig_of[:n_whole], ratio_row)
            if r_now < n_whole and orig_of[r_now] == ratio_row and (kind[parent == r_now] == 3).any():
                return float(ratio_in)
        if kept_start is not None:
            return kept_ratio_finish(all_pts, out, kind, parent, amin_p, kept_start.result())
        return kept_radius_ratio(all_pts, out, kind, parent, amin_p)

    def counts_of() -> tuple[dict, int, int]:
        # (the new rows' counts, the kept ratio left out: 1 is no ratio's worst)
        q = local_quality(all_pts, out, pm, kind, keep, hi, 1.0, new_facts)
        return q, int((slot == _k.FLIP).sum() // 2), int((slack[order[join[steps_at.joined(join)]]] < 0).sum() // 2)

    # the kept rows' ratio (what ``kept_ratio_start`` left, or ~9 ms at 1.5 M) on the
    # other core beside the counts; both read ``parent`` before it is mapped through
    # the fans below
    (quality, n_flip_pairs, n_split_below), kept_ratio = run_all([counts_of, kept_ratio_of])
    quality["radius_ratio_output"] = float(max(quality["radius_ratio_output"], kept_ratio))
    quality["max_angle_input_deg"] = math.degrees(amax_in) if m0 else 0.0
    quality["radius_ratio_input"] = float(ratio_in)
    if n_fan:  # (in place: the rows' parents are this function's own array)
        _row_pass(lambda lo, hi_: _k.map_through_into(parent, orig_of, lo, hi_), len(parent))
    counts_d = {
        "cycles_before_merging": int(cover.n_cycles),
        "cover_rotations": int(cover.n_rotations),
        "uncovered": int(n_unc0),
        "fans": int(n_fan),
        "ring_fans": int(n_ring),
        "rerouted": int(n_reroute),
        "ring_joins": int(n_ring_join),
        "alternating_merges": int(n_alt),
        "fan_triangles_replaced": int(m0 - (m - n_fan_rows)),
        "unmatched": int(cover.n_unmatched),
        "incenters": n_split,
        "midpoints": int(len(mid_a)),
        "swaps": int(counts[0] + counts[1]),
        "swaps_absorbing": int(counts[0]),
        "edge_splits": int(counts[3]),
        "merges": int(counts.sum()),
        "bridges": int(counts[2]),
        "flips": n_flip_pairs,
        "retries": attempt,
        "joins_placed_after_plan": int(n_placed_late),
        "uncovered_boundary": n_unc_bnd,
        "join_bound_deg": math.degrees(float(jb.min())) if len(jb) else None,
        "uncovered_below_target": int((jb < keep * min_angle * (1.0 - 1e-9)).sum()),
        "corner_bound_deg": math.degrees(c_bound),
        "improvement_flips": int(n_improve),
        "steiner_moved": int(n_moved),
        "joins_below_rule": int(counts[2]) + n_split_below,
        **quality,
    }
    steps.done("report")
    counts_d["step_seconds"] = steps.wall
    counts_d["step_cpu_seconds"] = steps.cpu
    return SparseResult(
        points=all_pts,
        triangles=out,
        lengths=lengths.astype(np.int64),
        parent=parent,
        kind=kind,
        claim=claim,
        mid_a=mid_a,
        mid_b=mid_b,
        counts=counts_d,
    )


def kept_radius_ratio(
    points: np.ndarray, rows: np.ndarray, kind: np.ndarray, parent: np.ndarray, parent_min: np.ndarray
) -> float:
    """The worst circumradius / (2 x inradius) of the rows kept whole (``kind`` 3), 1 if none.

    ``parent_min[parent[i]]`` is row i's smallest angle if it is kept. A triangle of
    smallest angle a has ``R / 2r = 1 / (8 sin(a/2) sin(b/2) sin(c/2)) <= U(a) = 1 /
    (8 sin^2(a/2) cos a)`` (b = a, c = pi - 2a: the other two as far apart as they
    can be), and U falls on (0, 60 deg]. So with ``r0`` the worst ratio of a sample
    of the kept rows (every ``KEPT_RATIO_STRIDE``-th row), only kept rows with ``U(a)
    >= r0``, i.e. ``a <= arccos((1 + sqrt(1 - 1 / r0)) / 2)``, can be worse: measured
    exactly, they give the same maximum as measuring every kept row. At 1.5 M q30
    triangles: r0 ~2, a <= ~31.4 deg, 0.8 % of the rows (every kept row measured:
    0.17 s CPU when the input's worst triangle was joined).
    """
    _, r0, few = kept_ratio_start(points, rows, kind, parent, parent_min)
    return max(r0, triangle_facts(points, rows[few])[2]) if len(few) else r0


def kept_ratio_start(
    points: np.ndarray, rows: np.ndarray, kind: np.ndarray, parent: np.ndarray, parent_min: np.ndarray
) -> tuple[np.ndarray, float, np.ndarray]:
    """``kept_radius_ratio``'s sample and search, while the improvement may still change
    the rows (``kept_ratio_finish`` ends it on the final rows).

    The improvement only turns kept rows (kind 3) into swapped ones (kind 4), never
    back, and moves Steiner points only, which no kept row has: so the rows kept at
    the end are kept throughout, with the same points. Returns ``(sample, r0, few)``:
    the sampled rows read as kept, their worst ratio, and the rows read as kept whose
    parent's smallest angle allows worse than ``r0``.
    """
    sample = np.arange(0, len(rows), KEPT_RATIO_STRIDE)
    sample = sample[kind[sample] == 3]
    r0 = triangle_facts(points, rows[sample])[2] if len(sample) else 1.0
    bound = math.acos(0.5 * (1.0 + math.sqrt(1.0 - 1.0 / r0))) if r0 > 1.0 else math.pi
    few = np.empty(len(rows), np.int64)  # (pages beyond the few rows written are never touched)
    # (margin: the angles and the ratios are rounded apart)
    k = _k.kept_below(kind, parent, parent_min, bound * (1.0 + 1e-6), few)
    return sample, r0, few[:k]


def kept_ratio_finish(
    points: np.ndarray, rows: np.ndarray, kind: np.ndarray, parent: np.ndarray, parent_min: np.ndarray, start: tuple
) -> float:
    """``kept_radius_ratio`` of the final rows from ``kept_ratio_start``'s ``start``.

    If every sampled row is still kept, the sample is the one the final rows give (a
    row kept at the end was read as kept), so is ``r0`` and its bound, and the rows to
    measure are those of ``few`` still kept: the same value. Else measured anew.
    """
    sample, r0, few = start
    if not (kind[sample] == 3).all():  # (a sampled row was swapped meanwhile)
        return kept_radius_ratio(points, rows, kind, parent, parent_min)
    few = few[kind[few] == 3]
    return max(r0, triangle_facts(points, rows[few])[2]) if len(few) else r0


def local_quality(
    points: np.ndarray,
    triangles: np.ndarray,
    parents_min: np.ndarray,
    kind: np.ndarray,
    keep: float,
    max_allowed: float,
    kept_ratio: float | None = None,
    new_facts: tuple | None = None,
) -> dict:
    """The local quality rule's counts over the output (issue 13, item 1).

    A new triangle (every kind but 3, kept whole) is *below the parent rule* if its
    smallest angle is under ``keep`` x ``parents_min`` (the smallest angle of the
    input triangles it replaces), *above the max rule* if its largest angle exceeds
    ``max_allowed`` (radians); both up to a relative 1e-9. Only the new rows are
    measured (a kept row has its input triangle's angles); ``kept_ratio`` is the worst
    radius ratio of the kept rows if the caller knows it (else measured here);
    ``new_facts``: ``(new rows, their smallest and largest angles, worst radius
    ratio)`` if the caller measured them on these rows and points (else measured here).
    """
    if new_facts is None:
        new = np.flatnonzero(kind != 3)
        lo, hi, ratio, _ = triangle_facts(points, triangles[new])
    else:
        new, lo, hi, ratio = new_facts
    if kept_ratio is None:
        kept_ratio = triangle_facts(points, triangles[kind == 3])[2]
    pm = parents_min[new]
    below = lo < keep * pm * (1.0 - 1e-9)
    above = hi > max_allowed * (1.0 + 1e-9)
    return {
        "keep": float(keep),
        "below_parent_rule": int(below.sum()),
        "above_max_rule": int(above.sum()),
        # a parent of zero angle (a degenerate input, refused later) gives no ratio: inf
        "worst_parent_ratio": float(np.divide(lo, pm, out=np.full_like(lo, np.inf), where=pm > 0).min())
        if len(new) else 1.0,
        "min_angle_new_deg": math.degrees(float(lo.min())) if len(new) else None,
        "max_angle_new_deg": math.degrees(float(hi.max())) if len(new) else None,
        "radius_ratio_output": float(max(ratio, kept_ratio)),
    }


def _improve(pts, out, claim, kind, pm, lengths, tri, tw, con, parent, partner, mid_a, mid_b, first_mid, hi,
             first_steiner, keep, lo_global, floor, pinned=None):
    """Cycle-keeping improvement flips (``_improve_kernels.improve_flips``) on the final rows.

    An output edge is pinned if it is a pinned input edge (constrained, between
    regions; ``con`` over ``tri``) or a half of one split at its midpoint
    (``_improve_kernels.pinned_output_edges``, from each row's parents). ``pinned``:
    the kept rows' entries found already (the output rows' gather), the new rows'
    are found here.
    """
    new = np.flatnonzero(kind != 3)  # (the new rows: an O(m) pass, made once for both uses)
    if pinned is None:
        pinned = _ik.pinned_output_edges(out, parent, partner, tri, tw, con, int(first_mid), mid_a, mid_b)
    else:  # (the new rows only: the kept rows', ~99 % of them, came with the gather)
        pinned = _ik.pinned_output_edges(out, parent, partner, tri, tw, con, int(first_mid), mid_a, mid_b,
                                         rows=new, pinned=pinned)
    # the caller's rows, claim, kinds and parents' angles are its own fresh arrays:
    # changed in place, not copied (4 x 1.5 M rows of fresh bytes saved)
    out = np.ascontiguousarray(out, dtype=np.int64)
    twin = np.ascontiguousarray(claim, dtype=np.int64)
    pm = np.ascontiguousarray(pm, dtype=np.float64)
    lengths = np.ascontiguousarray(lengths, dtype=np.int64)
    starts = np.cumsum(lengths) - lengths
    n_flips = n_moved = 0
    # which rows changed when, and when each try last failed: a try is not made again
    # while its rows are as they were (``_improve_kernels.improve_flips``)
    touched = fresh(len(out), np.int64, 0)
    failed = fresh(len(out), np.int64, -1)
    clock = np.zeros(1, np.int64)
    judged = np.full(max(len(pts) - first_steiner, 0), -1, np.int64)  # (and each Steiner point's last look)
    only_missing = len(out) >= IMPROVE_ALL_BELOW
    missing_rows = _MissingRows(touched, clock)  # (the rows changed since the last ask measured again)
    for _ in range(IMPROVE_ROUNDS):
        tries = missing_rows(pts, out, new, lo_global, hi) if only_missing else new
        if only_missing and not len(tries):
            break
        # (the tries that fail as the rows are now, found on both cores; the loop skips them)
        _ik.failing_flips(pts, out, twin, pinned, starts, lengths, float(hi), tries, touched, failed, clock,
                          IMPROVE_MIN_ROWS)
        flips = _ik.improve_flips(
            pts, out, twin, pinned, starts, lengths, pm, kind, float(hi), 4 * len(out) + 16, tries, touched, failed,
            clock,
        )
        n_flips += flips
        if flips:  # flips make kept rows new: taken again
            new = np.flatnonzero(kind != 3)
        if first_steiner >= len(pts):
            break
        if only_missing:  # the points on no row missing the targets: as if judged now and left
            # (judged again once a row around them changes, as any point left alone)
            # (the rows as the flips left them; none: the ones the flips were tried on)
            _leave_points_off(out, missing_rows(pts, out, new, lo_global, hi) if flips else tries, first_steiner,
                              judged, int(clock[0]))
        moved = _ik.smooth_steiner(
            pts, out, twin, pinned, pm, first_steiner, float(keep), float(hi), PLACE_ITERS, new, touched, clock,
            judged, SMOOTH_MIN_POINTS,
        )
        n_moved += moved
        if moved == 0:
            break
    # (the loop's ask, its measurements up to date, gives the repair's first round: only_missing)
    repaired, facts = _repair_targets(pts, out, twin, pinned, kind, first_steiner, lo_global, hi, floor,
                                      missing_rows if only_missing else None)
    n_moved += repaired
    return out, twin, kind, pm, int(n_flips), int(n_moved), facts


def _missing_rows(pts: np.ndarray, out: np.ndarray, rows: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """``rows`` whose smallest angle is below ``lo`` or whose largest is above ``hi``."""
    a_lo, a_hi, _, _ = triangle_facts(pts, out[rows])
    return rows[(a_lo < lo) | (a_hi > hi)]


class _MissingRows:
    """:func:`_missing_rows` asked again and again as the rows change (``_improve``'s
    rounds), measuring only the rows changed since it last measured.

    ``touched`` and ``clock`` are the improvement step's (``_improve_kernels``): every
    change to a row's corners (a flip) or to a corner's place (``smooth_steiner``
    moving a point) stamps the row with the advanced clock, so the rows stamped after
    the clock read at the last measurement are the only ones whose angles may differ;
    the others' are kept (an angle is a function of the row's three points alone, so
    the answer is the full pass's). At 1.5 M triangles the step asked three times of
    ~37 k rows, ~5 ms wall each on both cores; the two later asks change a few
    hundred rows.
    """

    def __init__(self, touched: np.ndarray, clock: np.ndarray):
        self.touched, self.clock = touched, clock
        self.rows = np.empty(0, np.int64)
        self.lo = self.hi = np.empty(0)
        self.at = -1  # (the clock when last measured; -1: never)

    def __call__(self, pts: np.ndarray, out: np.ndarray, rows: np.ndarray, lo: float, hi: float) -> np.ndarray:
        """``rows`` (sorted, unique) whose smallest angle is below ``lo`` or largest above ``hi``."""
        a_lo, a_hi = np.empty(len(rows)), np.empty(len(rows))
        if self.at < 0 or not len(self.rows):
            stale = np.arange(len(rows))
        else:  # (rows measured before and unchanged since: kept)
            at = np.minimum(np.searchsorted(self.rows, rows), len(self.rows) - 1)
            known = self.rows[at] == rows
            a_lo[known], a_hi[known] = self.lo[at[known]], self.hi[at[known]]
            stale = np.flatnonzero(~known | (self.touched[rows] > self.at))
        self.at = int(self.clock[0])
        if len(stale) == len(rows):
            a_lo, a_hi, _, _ = triangle_facts(pts, out[rows])
        elif len(stale):
            a_lo[stale], a_hi[stale], _, _ = triangle_facts(pts, out[rows[stale]])
        self.rows, self.lo, self.hi = rows, a_lo, a_hi
        return rows[(a_lo < lo) | (a_hi > hi)]


def _leave_points_off(out: np.ndarray, rows: np.ndarray, first: int, judged: np.ndarray, now: int) -> None:
    """Mark every Steiner point (``>= first``) that is no corner of ``rows`` judged at clock
    ``now`` (``_improve_kernels.smooth_steiner`` then leaves it while its star is unchanged)."""
    on = np.zeros(len(judged), np.bool_)
    v = out[rows].ravel()
    on[v[v >= first] - first] = True
    judged[~on] = now


def _repair_targets(pts, out, twin, pinned, kind, first_steiner: int, lo: float, hi: float, floor: float,
                    missing_rows: _MissingRows | None = None):
    """Move the Steiner points of rows that miss issue 13's absolute targets (in place).

    After the improvement step, the new rows with an angle below ``lo`` (``keep`` x
    the input's smallest) or above ``hi`` (its largest + 5 degrees) are few (none on
    most meshes); each free Steiner point among their corners is moved for the
    global targets (``_join_kernels.move_to_targets``), up to ``IMPROVE_ROUNDS``
    rounds. Returns the number of moves and the new rows' facts ``(new, smallest,
    largest angle, worst radius ratio)`` if the last ones measured are the final rows'
    (no move after them; else None): the report's (``local_quality``), not measured again.
    ``missing_rows``: the improvement step's ask (:class:`_MissingRows`, with the
    same ``lo`` and ``hi``), which gives the first round's rows from the rows changed
    since it last measured; the full pass is then made only where no point moves
    (the report's facts), not where the next round measures again anyway.
    """
    new = np.flatnonzero(kind != 3)
    if not len(new) or first_steiner >= len(pts):
        return 0, None
    moved = 0
    final = None
    for r in range(IMPROVE_ROUNDS):
        if r == 0 and missing_rows is not None:
            miss = missing_rows(pts, out, new, lo, hi)
        else:
            a_lo, a_hi, ratio, _ = triangle_facts(pts, out[new])
            final = (new, a_lo, a_hi, ratio)
            miss = new[(a_lo < lo) | (a_hi > hi)]
        rc = np.argwhere(out[miss] >= first_steiner)
        if not len(rc):
            break
        hs = 3 * miss[rc[:, 0]] + rc[:, 1]
        _, first_h = np.unique(out[miss[rc[:, 0]], rc[:, 1]], return_index=True)
        n = _j.move_to_targets(pts, out, twin, pinned, hs[first_h], float(lo), float(hi), float(floor), PLACE_ITERS)
        moved += n
        if n:
            final = None  # (points moved since)
        else:
            break
    if final is None and moved == 0:  # (the first round's ask, no point moved: the report's facts)
        a_lo, a_hi, ratio, _ = triangle_facts(pts, out[new])
        final = (new, a_lo, a_hi, ratio)
    return moved, final


def count_report(r: SparseResult, n: int, m: int) -> dict:
    """The report's counts of a sparse construction from ``n`` points, ``m`` triangles."""
    steiner = r.counts["incenters"] + r.counts["midpoints"] + r.counts.get("fans", 0)
    return {
        "triangles": int(len(r.triangles)),
        "vertices": int(len(r.points)),
        "input_triangles": int(m),
        "input_vertices": int(n),
        "steiner_points": int(steiner),
        "steiner_per_input_triangle": steiner / m,
        "triangles_added": int(len(r.triangles) - m),
        **r.counts,
        "components": [int(x) for x in r.lengths],
    }


def _numbered_back(r: SparseResult, loc, points: np.ndarray, started: tuple[float, float]) -> SparseResult:
    """``r``, made on the renumbered mesh ``loc`` (``renumber_local``), in the input's numbers.

    The rows' input vertices, the split edges' ends and the parents go back through
    ``loc``'s orders (in place where ``r`` owns the array); the input points are the
    caller's again. The time of the renumbering and of this is the report's ``locality``
    step (``started``: wall and CPU clocks before the renumbering, minus the steps)."""
    t0, c0 = time.perf_counter(), time.process_time()
    n = len(points)
    restore_vertices(r.triangles, loc.vertex_order)
    r.points[:n] = points
    vo = loc.vertex_order
    mid_a = np.where(r.mid_a < n, vo[np.minimum(r.mid_a, n - 1)], r.mid_a)
    mid_b = np.where(r.mid_b < n, vo[np.minimum(r.mid_b, n - 1)], r.mid_b)
    counts = dict(r.counts)
    wall, cpu = dict(counts["step_seconds"]), dict(counts["step_cpu_seconds"])
    wall["locality"] = time.perf_counter() - t0 + (t0 - started[0] - sum(wall.values()))
    cpu["locality"] = time.process_time() - c0 + (c0 - started[1] - sum(cpu.values()))
    counts["step_seconds"], counts["step_cpu_seconds"] = wall, cpu
    parent = r.parent  # (sparse_cycles' own array: mapped in place, one threaded pass)
    run_all([
        (lambda lo=lo, hi=hi: _k.map_through_into(parent, loc.triangle_order, lo, hi))
        for lo, hi in row_ranges(len(parent), threads.THREAD_MIN_ROWS)
    ])
    return replace(r, parent=parent, mid_a=mid_a, mid_b=mid_b, counts=counts)


def _region_edges(twin: np.ndarray, attrs: np.ndarray) -> np.ndarray:
    """Half-edges whose row's attributes (``attrs``, a row per triangle) differ from
    their twin's."""
    inner = twin >= 0
    differ = np.zeros(len(twin), np.bool_)
    differ[inner] = (attrs[np.flatnonzero(inner) // 3] != attrs[twin[inner] // 3]).any(axis=1)
    return differ


def sparse_hamiltonian(
    mesh: Mesh, he: HalfEdges | None, is_con: np.ndarray | None, *, keep: float = KEEP,
    beside_cover: Callable[[], object] | None = None, tree: str = "quadtree",
) -> tuple[HamiltonianMesh, np.ndarray]:
    """Build the sparse Hamiltonian cycle mesh (unverified; see ``hammesh.hamiltonian``).

    Parameters
    ----------
    mesh : Mesh
        Counter-clockwise, validated (``hammesh.halfedge.prepare_mesh``).
    he : HalfEdges or None
    is_con : (3 m,) bool or None
        None both (``prepare_mesh(..., cells=True, match=False)``): matched here, on a
        big mesh once in the renumbered order (``hammesh.halfedge.local_half_edges``).
    keep : float
        The local quality rule's factor (``sparse_cycles``).
    beside_cover : callable, optional
        Called once beside the construction (``sparse_cycles``).
    tree : {"quadtree", "fishbone", "comb"}
        ``sparse_cycles``' (``"fishbone"``, ``"comb"``: compact cycles).

    Returns
    -------
    HamiltonianMesh
        ``kind`` 0 incenter sector, 1 flip, 2 midpoint, 3 input triangle kept whole,
        4 swapped pair; ``report`` holds the construction counts.
    claim : (3 m_out,) int64
        The output's half-edge twins (checked by the certificate).
    """
    pts, tri = mesh.points, mesh.triangles
    n, m = mesh.n_points, mesh.n_triangles
    seen = mesh.info.get("validated")  # found by prepare_mesh's orientation pass
    amin = float(seen["min_angle"] if seen else orient_ccw(pts, tri).min_angle)
    local = renumbers(m, pts.shape[1], mesh.info)
    if he is None and not local:
        he, is_con = match_half_edges(mesh)
    pinned = is_con
    attr = np.asarray(mesh.triangle_attributes)
    # an edge between two regions is kept where it is (split only at its midpoint): a
    # moved edge would carry one region's attribute into the other
    regions = bool(attr.size and m and (attr != attr[:1]).any())
    if regions and he is not None:
        pinned = is_con | _region_edges(he.twin, attr.reshape(m, -1))
    if local:
        t0, c0 = time.perf_counter(), time.process_time()
        # room after the rows and points: the ring fans and joins and the Steiner points
        # are appended in place (``_longer``), not by copying every array
        rt, rp = ROOM_ROWS, ROOM_ROWS + m // STEINER_ROOM_DIVISOR
        if he is None:  # (matched once, in the new order: ``prepare_mesh(match=False)``)
            loc = local_half_edges(mesh, room=(rt, rp))
            if regions:
                loc.marks[:] |= _region_edges(loc.twin, attr.reshape(m, -1)[loc.triangle_order])
        else:
            # (the cell keys the validation found, if asked: ``prepare_mesh(cells=True)``; used once)
            keys = seen.pop("cells", None) if seen else None
            loc = renumber_local(pts, tri, he.twin, pinned, keys, room=(rt, rp))
        for a, rows in ((loc.triangles, m + rt), (loc.twin, 3 * (m + rt)), (loc.marks, 3 * (m + rt)),
                        (loc.points, n + rp)):
            _keep_room(a, rows)
        r = sparse_cycles(
            loc.points, loc.triangles, loc.twin, loc.marks, amin, keep=keep, beside_cover=beside_cover, local=True,
            tree=tree,
        )
        # (the arrays the construction dropped as it returned, ~290 MB at 1.5 M, are given
        # back after these two-thread passes, not beside them: ``threads.later_held``)
        with threads.later_held():
            r = _numbered_back(r, loc, pts, (t0, c0))
    else:
        r = sparse_cycles(pts, tri, he.twin, pinned, amin, keep=keep, beside_cover=beside_cover, tree=tree)
    with threads.later_held():
        return _as_output(mesh, r, n, m)


def _as_output(mesh: Mesh, r: SparseResult, n: int, m: int) -> tuple[HamiltonianMesh, np.ndarray]:
    """``sparse_hamiltonian``'s result from the construction's (in the input's numbering)."""
    n_inc = r.counts["incenters"]
    segs, markers = split_segments(
        mesh.segments, mesh.segment_markers, r.mid_a, r.mid_b, n + r.counts["fans"] + n_inc, len(r.points)
    )
    lengths = r.lengths
    if len(lengths) == 1:  # (one cycle: 0, 1, ... numbered on both cores in the page reserve, no fresh
        position = fresh(int(lengths[0]), np.int64)  # 12 MB faulted at 1.5 M as ``np.arange`` does)
        _row_pass(lambda lo, hi_: _k.iota_into(position, lo, hi_), len(position))
    else:
        position = cycle_positions(lengths)
    report = count_report(r, n, m)
    h = HamiltonianMesh(
        points=r.points,
        triangles=r.triangles,
        segments=segs,
        segment_markers=markers,
        components=lengths,
        position=position,
        parent=r.parent,
        kind=r.kind,
        # (no attribute columns: no gather of 1.5 M empty rows)
        triangle_attributes=mesh.triangle_attributes[r.parent] if np.shape(mesh.triangle_attributes)[1:] != (0,)
        else np.zeros((len(r.parent), 0)),
        report=report,
    )
    return h, r.claim
