"""Hamiltonian triangulations of point sets (paper §3, Thm 3.1 with Lemma 3.2).

Thm 3.1: a point set in convex position has a Hamiltonian *path* triangulation (a fan
from one point); any other set has a Hamiltonian *cycle* triangulation, built by
fanning around one interior point (the fan's dual is a cycle) and inserting the other
points one at a time: a point inside triangle ``T`` splits it into three and the
cycle, which enters ``T`` by one edge and leaves by another, runs entry piece ->
middle piece -> exit piece (Figure 12).  Lemma 3.2: choosing each splitter at random
among the points inside a triangle gives expected O(n log n) time (backward analysis);
here every triangle keeps its points in one contiguous slice that each split
partitions in place, like quicksort.

Degenerate input (the paper assumes general position) is handled exactly:

* points on hull edges are vertices; the start fan uses only strict corners, and a
  point on a hull edge splits its triangle into two (the cycle always passes);
* a point on an interior edge splits both triangles into four pieces forming a ring;
  the cycle passes unless it crosses that edge entering and leaving at opposite
  pieces; then the kernel first tries other splitters (a strictly interior point of
  either triangle turns the configuration around); when every remaining point is
  stuck, :mod:`hammesh.pointset._cycle_repair` inserts one by re-triangulating a few
  consecutive cycle triangles around it (exact search, the cycle is kept), or makes
  a cycle-preserving flip nearby, and the kernel resumes; the search work is bounded
  (:data:`CHAIN_BUDGET`, :data:`RETRY_BUDGET`, :data:`WASTED_STEPS_PER_ATTEMPT`): an
  attempt whose repairs keep failing restarts with other random choices, and
  :data:`MAX_ATTEMPTS` failed attempts are a :class:`MeshingError` (seen once, on
  101 points in two long collinear runs, with a smaller retry budget);
* duplicates, fewer than 3 points, all points on one line: :class:`InvalidDomainError`.

The output has ``2 n - h - 2`` triangles (``h`` points on the hull boundary) and is
verified (:func:`hammesh.pointset.verify.verify_point_triangulation`) before it is
returned.
"""

from __future__ import annotations

import numpy as np

from hammesh import params
from hammesh.errors import MeshingError
from hammesh.pointset._cycle_repair import insert_by_chain, repair
from hammesh.pointset._kernels import OK, STUCK, cycle_order, fan_locate, insert_points
from hammesh.pointset.validate import Hull, as_points, convex_hull
from hammesh.pointset.verify import verify_point_triangulation

__all__ = ["hamiltonian_triangulation", "MAX_ATTEMPTS"]

#: Restarts (with new random choices) before a degenerate configuration is given up.
MAX_ATTEMPTS = 12
#: Random interior apexes tried for the start fan (the first with no point on a spoke wins).
APEX_TRIES = 8
#: Repairs (:mod:`hammesh.pointset._cycle_repair`: region re-triangulations or flips)
#: per point before a restart.
MAX_REPAIRS_PER_POINT = 1
#: Search steps of one region re-triangulation call (successful calls: median ~150,
#: 99th percentile ~12,000 on grids and parallel collinear runs).
CHAIN_BUDGET = 20_000
#: Budget of the next call after a fruitless one (a flip came in between): most
#: successes are cheap, and a stalled neighbourhood rarely yields to more search.
RETRY_BUDGET = 5_000
#: Steps of *fruitless* calls attempt ``k`` (0-based) may spend before it restarts:
#: ``min(k + 1, 4) * WASTED_STEPS_PER_ATTEMPT``, so early attempts restart soon (a
#: restart is cheap and often succeeds at once) and later ones search longer.  With
#: :data:`MAX_ATTEMPTS` this bounds all fruitless search before ``MeshingError`` by
#: 42 * 60,000 + 12 * 20,000 steps (a few minutes of Python at worst).
WASTED_STEPS_PER_ATTEMPT = 3 * CHAIN_BUDGET


def hamiltonian_triangulation(points: np.ndarray, seed: int | None = None) -> np.ndarray:
    """A triangulation of ``points`` whose triangles, in row order, form a Hamiltonian cycle.

    Parameters
    ----------
    points : (n, 2) float64
        Distinct points, not all on one line.
    seed : int, optional
        Seed of the random splitters (Lemma 3.2); the same seed gives the same output.

    Returns
    -------
    (2 n - h - 2, 3) int64
        Counter-clockwise triangles; consecutive rows share an edge and so do the last
        and first (a cycle), unless every point is on the hull boundary: then there is
        no interior point and the rows form a Hamiltonian path (Thm 3.1).

    Raises
    ------
    InvalidDomainError
        Fewer than 3 points, non-finite or duplicate points, all points collinear.
    MeshingError
        A degenerate configuration (long collinear runs) defeated every repair and
        :data:`MAX_ATTEMPTS` restarts; the work before is bounded.  Rare: try another
        seed.
    VerificationError
        The output failed its certificate (a bug).

    Examples
    --------
    >>> import numpy as np
    >>> pts = np.array([[0., 0], [4, 0], [4, 4], [0, 4], [1, 1], [3, 2]])
    >>> tri = hamiltonian_triangulation(pts, seed=1)
    >>> tri.shape                         # 2 n - h - 2 = 12 - 4 - 2
    (6, 3)
    """
    pts = as_points(points)
    hull = convex_hull(pts)
    rng = np.random.default_rng(None if seed is None else params.integer("seed", seed, low=0))
    for attempt in range(MAX_ATTEMPTS):
        tri = _attempt(pts, hull, rng, attempt)
        if tri is not None:
            verify_point_triangulation(pts, tri, "cycle" if hull.h < len(pts) else "path")
            return tri
    raise MeshingError(
        f"no Hamiltonian triangulation found for these {len(pts)} points after "
        f"{MAX_ATTEMPTS} restarts (degenerate configuration); try another seed"
    )


def _locate(
    pts: np.ndarray, apex: int, spokes: np.ndarray, cyclic: bool, n: int
) -> tuple[np.ndarray, np.ndarray, int]:
    """Points other than the fan's, their fan triangle, and how many lie on a spoke."""
    used = np.zeros(n, dtype=bool)
    used[apex] = True
    used[spokes] = True
    rest = np.flatnonzero(~used).astype(np.int64)
    if len(rest) == 0:
        return rest, rest.copy(), 0
    ang = np.arctan2(pts[rest, 1] - pts[apex, 1], pts[rest, 0] - pts[apex, 0])
    sp = np.arctan2(pts[spokes, 1] - pts[apex, 1], pts[spokes, 0] - pts[apex, 0])
    rel_sp = np.mod(sp - sp[0], 2 * np.pi)
    rel_sp[0] = 0.0
    rel = np.mod(ang - sp[0], 2 * np.pi)
    guess = np.searchsorted(rel_sp, rel, side="right") - 1
    where, n_on = fan_locate(pts, apex, spokes, cyclic, guess.astype(np.int64), rest)
    if (where < 0).any():  # pragma: no cover - the fan covers the hull
        raise MeshingError("point location in the start fan failed")
    return rest, where, int(n_on)


def _attempt(
    pts: np.ndarray, hull: Hull, rng: np.random.Generator, attempt: int = 0
) -> np.ndarray | None:
    n = len(pts)
    m = 2 * n - hull.h - 2
    on_hull = np.zeros(n, dtype=bool)
    on_hull[hull.boundary] = True
    corners = hull.corners
    if hull.h < n:
        # a random interior apex; among a few, one with no point on a spoke (points on
        # interior edges are the only degenerate case that can stall the insertion)
        interior = np.flatnonzero(~on_hull)
        best = None
        for _ in range(APEX_TRIES):
            cand = int(interior[rng.integers(len(interior))])
            placed = _locate(pts, cand, corners, True, n)
            if best is None or placed[2] < best[1][2]:
                best = (cand, placed)
            if placed[2] == 0:
                break
        apex, (rest, where, _) = best
        spokes = corners
        cyclic = True
    else:
        shift = int(rng.integers(len(corners)))
        spokes = np.roll(corners, -shift)
        apex = int(spokes[0])
        spokes = spokes[1:]
        cyclic = False
        rest, where, _ = _locate(pts, apex, np.ascontiguousarray(spokes, dtype=np.int64), False, n)
    spokes = np.ascontiguousarray(spokes, dtype=np.int64)
    s = len(spokes)
    n0 = s if cyclic else s - 1

    tri = np.zeros((m, 3), dtype=np.int64)
    nbr = np.full((m, 3), -1, dtype=np.int64)
    nxt = np.full(m, -1, dtype=np.int64)
    prv = np.full(m, -1, dtype=np.int64)
    i = np.arange(n0)
    tri[:n0, 0] = apex
    tri[:n0, 1] = spokes[i]
    tri[:n0, 2] = spokes[(i + 1) % s]
    if cyclic:
        nbr[:n0, 0] = (i - 1) % n0
        nbr[:n0, 2] = (i + 1) % n0
        nxt[:n0] = (i + 1) % n0
        prv[:n0] = (i - 1) % n0
    else:
        nbr[1:n0, 0] = i[:-1]
        nbr[: n0 - 1, 2] = i[1:]
        nxt[: n0 - 1] = i[1:]
        prv[1:n0] = i[:-1]

    lo = np.zeros(m, dtype=np.int64)
    hi = np.zeros(m, dtype=np.int64)
    if len(rest):
        by = np.argsort(where, kind="stable")
        rest = rest[by]
        counts = np.bincount(where, minlength=m)[:n0]
        ends = np.cumsum(counts)
        hi[:n0] = ends
        lo[:n0] = ends - counts
    B = np.ascontiguousarray(rest, dtype=np.int64)
    seed = int(rng.integers(1, 2**62))
    n_tri, status = insert_points(pts, tri, nbr, nxt, prv, lo, hi, B, n0, seed)
    repairs = 0
    wasted = 0  # search steps of fruitless region re-triangulations in this attempt
    budget = CHAIN_BUDGET
    while status == STUCK and repairs < MAX_REPAIRS_PER_POINT * n + 8:
        if wasted >= WASTED_STEPS_PER_ATTEMPT * min(attempt + 1, 4):
            return None  # a restart (new apex, new splitters) is cheaper than more search
        added, B, steps = insert_by_chain(
            pts, tri, nbr, nxt, prv, lo, hi, B, n_tri, budget=budget
        )
        n_tri += added
        budget = CHAIN_BUDGET if added else RETRY_BUDGET
        if not added:
            wasted += steps
            done, B = repair(pts, tri, nbr, nxt, prv, lo, hi, B, n_tri, rng)
            if not done:
                break
        repairs += 1
        seed = int(rng.integers(1, 2**62))
        n_tri, status = insert_points(pts, tri, nbr, nxt, prv, lo, hi, B, n_tri, seed)
    if status == STUCK:
        return None
    if status != OK or n_tri != m:
        raise MeshingError(f"internal error in the insertion (status {status}, {n_tri} of {m} triangles)")
    order = cycle_order(nxt, prv, m)
    if len(order) != m:
        raise MeshingError("internal error: the cycle links do not visit every triangle once")
    return tri[order]
