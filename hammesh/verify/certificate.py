"""The certificate every Hamiltonian mesh passes before hammesh returns or writes it.

What is checked (each failure raises :class:`~hammesh.errors.VerificationError`
naming the triangle, edge or vertex at fault):

1. ``components`` are positive run lengths summing to the number of triangles;
   inside each run consecutive triangles share an edge (exactly two vertices) and
   the last shares one with the first: every run is a closed cycle.
2. Every triangle is strictly counter-clockwise by the exact orientation predicate
   (``hammesh.predicates.orient``): no inverted or degenerate triangle, even where a
   floating-point area would round to the wrong sign.
3. Edge-manifold and consistently oriented: no directed edge is used twice, which
   also rules out a triangle appearing twice.
4. Runs are exactly the connected pieces: no edge joins two runs.
5. With the input mesh (``reference``): its points are kept unchanged at the same
   indices, every vertex it used is still used, the total area is unchanged
   (relative tolerance ``AREA_RTOL``, plus what float64 rounding of the two sums can
   explain: :func:`area_rounding_bound`), the boundary edges are the same, every input
   constrained edge is an output edge or the union of two output edges meeting at
   its exact midpoint, and the minimum angle is at least ``angle_ratio`` times the
   input's minimum angle, up to a relative tolerance ``ANGLE_RTOL`` (the bound of
   Thm 2.4 is tight: an incenter triangle has exactly half an input angle, which
   floating point can round either way by a few ulps).

Every fact about the input is derived here (``hammesh.verify.reference``), from the
mesh the caller gave, with the certificate's own kernels (``hammesh.verify._kernels``)
and the exact predicates: nothing is read from the construction's validation
(``hammesh.halfedge``) or from a cache in ``Mesh.info``. The code shared with the
constructions is ``hammesh.predicates`` and numpy.

Items 2-3 with the unchanged area and boundary mean the output triangles tile the
input domain without overlap: glue the triangles along a pairing of their half-edges
(each pair the same edge, opposite directions); the result is a surface whose
boundary is the unpaired half-edges. Mapped to the plane with every triangle positive
it covers each point of a domain piece the same number of times (the degree is
constant away from the image of the boundary); if the unpaired half-edges are exactly
the input's boundary edges, that number is at least one in every piece (triangles sit
on the inner side of its boundary), and equal total area makes it exactly one. So
with a reference, *any* valid pairing proves the tiling, which lets a construction
hand its own pairing in as a claim (:func:`certify`): checking a claim is one read
per half-edge, where finding the pairing needs a bucket sort. Without a reference,
or with a claim that fails its checks, the pairing is computed here.
"""

from __future__ import annotations

import math
import threading
from typing import Any, Callable, NoReturn

import numpy as np

from hammesh import params, threads
from hammesh.pages import fresh
from hammesh.threads import row_ranges, run_all
from hammesh.errors import VerificationError
from hammesh.mesh import HamiltonianMesh, Mesh
from hammesh.predicates import orient_points
from hammesh.verify import _kernels
from hammesh.verify._kernels import RowChecks
from hammesh.verify.reference import (
    KEY_BASE,
    InputFacts,
    boundary_keys,
    edge_keys,
    input_facts,
    undirected_keys,
)
from hammesh.verify.runs import infer_runs_and_pairing

__all__ = [
    "verify",
    "verify_cycle_mesh",
    "verify_stored_cycle_mesh",
    "certify",
    "claim_structure",
    "combine_rows",
    "pair_dtype",
    "ANGLE_RTOL",
    "AREA_RTOL",
    "area_rounding_bound",
    "has_edges",
    "ROUNDING_RTOL_MAX",
    "row_angles",
]

ANGLE_RTOL = 1e-9
AREA_RTOL = 1e-9
#: the most a row's smallest angle may fall short of the bound (relative) when the
#: float64 rounding of its Steiner points explains the shortfall (see _rounding_explains)
ROUNDING_RTOL_MAX = 1e-6
#: a rounded Steiner point moves by at most one ulp per coordinate; an angle at a
#: vertex moves by at most that distance over the adjacent edge length, twice for the
#: angle at the moved point itself; 4 leaves room for the angle's own evaluation
ROUNDING_FACTOR = 4.0


def _fail(msg: str, check: str) -> NoReturn:
    raise VerificationError(msg, check=check)


def _certify_rows(
    pts: np.ndarray,
    tri: np.ndarray,
    runs: np.ndarray,
    claim: np.ndarray,
    used: np.ndarray,
    side: Callable[[], Any] | None = None,
) -> tuple[RowChecks, Any]:
    """``_kernels.certify_row_range`` over all rows, split across the machine's cores.

    The kernels release the GIL, so plain threads share the pass; the chunks' results
    combine exactly (first failures by row, extremes, sums), the same as one call.
    ``side`` (e.g. the input's facts) runs alongside; its result is returned second.
    """
    no_marks = np.empty(0, dtype=np.bool_)
    spans = row_ranges(len(tri), threads.THREAD_MIN_ROWS)
    calls = [
        (lambda lo=lo, hi=hi: _kernels.certify_row_range(pts, tri, runs, claim, lo, hi, used, no_marks))
        for lo, hi in spans
    ]
    if side is not None and len(spans) >= threads.cores():
        # a task beyond the cores (``run_all`` would start a pool of its own for the
        # three and leave the caller idle: 30-45 ms of a 1.5 M sparse call's wall for
        # ~30 ms of work a thread): the range that ends first runs it after its rows
        claimed, box = threading.Lock(), []

        def then_side(call: Callable[[], RowChecks]) -> Callable[[], RowChecks]:
            def run() -> RowChecks:
                out = call()
                if claimed.acquire(blocking=False):
                    box.append(side())
                return out
            return run

        return combine_rows(run_all([then_side(c) for c in calls])), box[0]
    results = run_all(calls + ([side] if side is not None else []))
    k = len(spans)
    return combine_rows(results[:k]), (results[k] if side is not None else None)


def combine_rows(parts: list[RowChecks]) -> RowChecks:
    """Combine ``certify_row_range`` results of disjoint row ranges into one."""

    def first(name: str) -> int:
        hits = [getattr(p, name) for p in parts if getattr(p, name) >= 0]
        return min(hits) if hits else -1

    lo = min(parts, key=lambda p: p.min_angle)
    hi = max(parts, key=lambda p: p.max_angle)
    small = min(parts, key=lambda p: p.min_area)
    return RowChecks(
        bad_index=first("bad_index"),
        bad_consecutive=first("bad_consecutive"),
        bad_pair=first("bad_pair"),
        cross_run=first("cross_run"),
        min_angle=lo.min_angle,
        argmin=lo.argmin,
        max_angle=hi.max_angle,
        argmax=hi.argmax,
        min_area=small.min_area,
        argmin_area=small.argmin_area,
        total_area=math.fsum(p.total_area for p in parts),
        bad_orientation=first("bad_orientation"),
        links=sum(p.links for p in parts),
        unpaired=sum(p.unpaired for p in parts),
        row_digest=_wrap(sum(p.row_digest for p in parts)),
        pair_digest=_wrap(sum(p.pair_digest for p in parts)),
        points_digest=0,
    )


def pair_dtype(m: int) -> type:
    """The dtype the certificate checks a pairing of ``m`` rows in: int32 when ``3 m``
    half-edge numbers fit (half the reads), else int64.

    One dtype for every pairing (a construction's claim, incircle's int32 or sparse's
    int64, and the certificate's own) means one compiled signature of each row
    kernel: each compiles in 15-20 s on a fresh checkout. Narrowing a claim cannot
    make a wrong one pass: the certificate checks the pairing it is given, whatever
    the construction meant by it.
    """
    return np.int32 if 3 * m < 2**31 - 1 else np.int64


def area_rounding_bound(points: np.ndarray, triangles: np.ndarray) -> float:
    """A bound on the rounding error of the certificate's float64 total area of these rows.

    Each row's doubled area is a cross product of two coordinate differences; its
    rounding error is at most ``3 u (|a_x b_y| + |a_y b_x|)`` (two differences, two
    products, a subtraction; ``u`` the unit roundoff), and ``|a_x b_y| + |a_y b_x| <=
    (|a|^2 + |b|^2) / 2``, below the sum ``S`` of the row's squared sides whichever two
    sides a kernel takes: the area's error is below ``1.5 u S``; summing ``m`` terms adds
    at most ``m u`` times the sum of their magnitudes. Both are doubled here for margin.
    Only read where the float totals disagree (a vertex at 1e8 beside unit triangles:
    the exact areas equal, the float ones 2e-9 apart).
    """
    pts = np.asarray(points, dtype=np.float64)
    tri = np.asarray(triangles, dtype=np.int64)
    u = np.finfo(np.float64).eps / 2
    a, b, c = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    sides = (((b - a) ** 2).sum(axis=1) + ((c - b) ** 2).sum(axis=1) + ((a - c) ** 2).sum(axis=1))
    e1, e2 = b - a, c - b
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    return float(3.0 * u * sides.sum() + 2.0 * len(tri) * u * area.sum())


def _wrap(x: int) -> int:
    """``x`` modulo 2**64 (digests are sums with wrapping arithmetic)."""
    return x % (1 << 64)


def _final_digests(tri: np.ndarray, pair: np.ndarray) -> tuple[int, int]:
    """:func:`_kernels.digest_range` over all rows, split across the cores."""
    spans = row_ranges(len(tri), threads.THREAD_MIN_ROWS)
    parts = run_all([(lambda lo=lo, hi=hi: _kernels.digest_range(tri, pair, lo, hi)) for lo, hi in spans])
    return _wrap(sum(p[0] for p in parts)), _wrap(sum(p[1] for p in parts))


def points_digest(points: np.ndarray) -> int:
    """Digest of a point array's bit patterns (see :func:`_kernels.points_digest`)."""
    return _wrap(int(_kernels.points_digest(np.ascontiguousarray(points, dtype=np.float64).view(np.int64).ravel())))


def claim_structure(triangles: np.ndarray, claim: np.ndarray) -> dict[str, Any]:
    """The output's boundary keys if ``claim`` is its pairing, computed ahead.

    :func:`certify` uses them only if the claim passes its checks; a construction
    computes this while its rows are checked.
    """
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    return {"boundary": boundary_keys(tri, np.ascontiguousarray(claim, dtype=pair_dtype(len(tri))))}


def verify_cycle_mesh(
    points: np.ndarray,
    triangles: np.ndarray,
    components: np.ndarray,
    *,
    segments: np.ndarray | None = None,
    reference: Mesh | None = None,
    angle_ratio: float = 0.5,
) -> dict[str, Any]:
    """Check that ``triangles`` in row order form closed Hamiltonian cycles.

    Parameters
    ----------
    points : (n, 2) float64
    triangles : (m, 3) int64
        In cycle order.
    components : (c,) int64
        Run lengths of the cycles.
    segments : (s, 2) int64, optional
        The output's constrained edges; each must be an edge of ``triangles``.
    reference : Mesh, optional
        The input mesh; enables the checks of item 5 of the module docstring. Every
        fact about it is derived here.
    angle_ratio : float
        Required ``min angle out / min angle in`` (Thm 2.4: 0.5).

    Returns
    -------
    dict
        ``min_angle_output_deg``, ``max_angle_output_deg``, ``area`` and, with a
        reference, ``min_angle_input_deg``.

    Raises
    ------
    VerificationError
    """
    facts = None if reference is None else input_facts(reference)
    return _certify(points, triangles, components, segments, facts, None, None, None, angle_ratio)


def verify_stored_cycle_mesh(
    points: np.ndarray, triangles: np.ndarray, segments: np.ndarray | None = None
) -> tuple[np.ndarray, dict[str, Any], np.ndarray]:
    """Items 1-4 for a mesh read from a file (``hammesh check``), one pairing for all.

    The runs are inferred from the stored order (:func:`hammesh.verify.infer_runs`);
    the half-edge pairing found there (the certificate's own kernel) serves the cycle
    checks too, and is returned for the caller's overlap test
    (``hammesh.planar_overlap.find_overlap(..., twin=)``).

    Returns
    -------
    runs : (c,) int64
    stats : dict
        As :func:`verify_cycle_mesh`.
    twin : (3 m,) int64
        The half-edge pairing (-1 on the boundary).
    """
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    runs, twin = infer_runs_and_pairing(tri, len(points))
    stats = _certify(points, tri, runs, segments, None, None, None, None, 0.5, own_twin=twin)
    return runs, stats, twin


def verify(mesh: HamiltonianMesh, reference: Mesh | None = None, *, angle_ratio: float = 0.5) -> dict[str, Any]:
    """Certificate of a :class:`~hammesh.mesh.HamiltonianMesh` against its input mesh.

    ``hammesh.verify(output, input)``: takes the two meshes and nothing else; every
    fact is derived from them (see module docstring). Without ``reference`` only
    items 1-4 are checked (what ``hammesh check FILE`` can know).

    Raises
    ------
    VerificationError
        Naming the fault.
    """
    params.instance("mesh", mesh, HamiltonianMesh, "a hammesh.HamiltonianMesh (a Mesh has no cycles)")
    return verify_cycle_mesh(
        mesh.points, mesh.triangles, mesh.components, segments=mesh.segments, reference=reference,
        angle_ratio=angle_ratio,
    )


def certify(
    mesh: HamiltonianMesh,
    facts: InputFacts | None,
    *,
    claim: np.ndarray | None = None,
    rows: tuple[RowChecks, np.ndarray] | None = None,
    prepared: dict[str, Any] | None = None,
    angle_ratio: float = 0.5,
) -> dict[str, Any]:
    """The certificate with a construction's fast paths (internal; see :func:`verify`).

    ``facts`` must come from :func:`hammesh.verify.reference.input_facts` of the
    caller's input (the certificate's own code), or be None (no input to compare). ``claim``: the construction's
    pairing of the output's half-edges, *checked* (a reversed-edge involution with as
    many unpaired half-edges as the input has boundary edges) before it replaces the
    bucket matching; a claim that fails is ignored. ``rows``: ``(results, used)`` of a
    :class:`~hammesh.verify.stream.RowStream` (the certificate's row checks, run on
    the rows while the construction wrote them). ``prepared``:
    :func:`claim_structure` of the claim, used only if the claim passes.
    """
    return _certify(mesh.points, mesh.triangles, mesh.components, mesh.segments, facts, claim, rows,
                    prepared, angle_ratio)


def _certify(
    points: np.ndarray,
    triangles: np.ndarray,
    components: np.ndarray,
    segments: np.ndarray | None,
    facts: InputFacts | None,
    twin_claim: np.ndarray | None,
    rows: tuple[RowChecks, np.ndarray] | None,
    prepared: dict[str, Any] | None,
    angle_ratio: float,
    own_twin: np.ndarray | None = None,
) -> dict[str, Any]:
    """The certificate; ``own_twin``: the output's pairing as this package's
    ``_kernels.half_edge_twins`` found it (never a construction's claim)."""
    pts = np.asarray(points, dtype=np.float64)
    tri = np.asarray(triangles)
    runs = np.asarray(components).reshape(-1)
    if pts.ndim != 2 or pts.shape[1] != 2 or tri.ndim != 2 or tri.shape[1] != 3:
        _fail(f"bad shapes: points {pts.shape}, triangles {tri.shape}", check="input")
    if not np.issubdtype(tri.dtype, np.integer) or not np.issubdtype(runs.dtype, np.integer):
        _fail(f"triangles and components must be integers, got {tri.dtype} and {runs.dtype}", check="input")
    tri = np.ascontiguousarray(tri, dtype=np.int64)
    runs = runs.astype(np.int64)
    n, m = len(pts), len(tri)
    if m == 0:
        _fail("the mesh has no triangles", check="input")
    if not np.isfinite(pts).all():
        _fail(f"point {int(np.argmax(~np.isfinite(pts).all(axis=1)))} is not finite", check="input")
    if (runs <= 0).any() or runs.sum() != m:
        _fail(f"components {runs.tolist()[:10]} are not positive run lengths summing to {m}", check="input")

    # a claimed pairing is only of use with the input's boundary (the tiling argument)
    pdt = pair_dtype(m)
    claim = np.empty(0, dtype=pdt)
    if twin_claim is not None and facts is not None and np.shape(twin_claim) == (3 * m,):
        claim = np.asarray(twin_claim)
        if claim.dtype != pdt or not claim.flags.c_contiguous:  # (incircle's int32 claim: no copy)
            claim = fresh(claim.shape, pdt)  # (sparse's int64 claim, narrowed: a reserve's pages if any)
            wide = np.asarray(twin_claim)
            run_all([  # (one range per core: numpy's cast releases the GIL)
                (lambda lo=lo, hi=hi: np.copyto(claim[lo:hi], wide[lo:hi], casting="unsafe"))
                for lo, hi in row_ranges(len(claim), threads.THREAD_MIN_ROWS)
            ])
    streamed = rows is not None
    if rows is None:
        used = np.zeros(n, dtype=np.bool_)
        # the claim's boundary keys beside the row checks (a third thread: the two
        # row ranges leave a core idle at their ends), used below only if the claim
        # passes, as ``prepared``'s are (sparse mode hands in no ``prepared``); a
        # process capped at one thread starts none (then found below, if needed)
        side = prepared is None and len(claim) > 0 and threads.cores() > 1
        ahead = (lambda: claim_structure(tri, claim)) if side else None
        rows, ahead_out = _certify_rows(pts, tri, runs, claim, used, side=ahead)
        if ahead_out is not None:
            prepared = ahead_out
    else:  # checked while the construction ran (``hammesh.verify.stream``)
        rows, used = rows
    # the claim is a pairing of all half-edges with as many unpaired ones as the input
    # has boundary edges, or it is not used
    claim_ok = (
        len(claim) > 0
        and rows.bad_pair < 0
        and 2 * rows.links + rows.unpaired == 3 * m
        and rows.unpaired == len(facts.boundary)
    )
    if streamed:  # what was checked is what is returned: nothing rewritten since
        d_rows, d_pairs = _final_digests(tri, claim if claim_ok else np.empty(0, dtype=pdt))
        if d_rows != _wrap(rows.row_digest):
            _fail("the output rows changed after they were checked", check="input")
        if rows.points_digest != points_digest(pts):
            _fail("the output points changed after the rows using them were checked", check="input")
        if claim_ok and d_pairs != _wrap(rows.pair_digest):
            # a claim entry was rewritten after its check (the digests agree on every
            # claim that was not: the int32 mismatch seen before was signed overflow
            # in the hash, see _kernels._mix): check the final claim again, whole, in
            # one pass over the rows (0.2 s at 4.5 M rows; finding the pairing: 0.9 s)
            used = np.zeros(n, dtype=np.bool_)
            rows, _ = _certify_rows(pts, tri, runs, claim, used)
            claim_ok = (
                rows.bad_pair < 0
                and 2 * rows.links + rows.unpaired == 3 * m
                and rows.unpaired == len(facts.boundary)
            )
    if rows.bad_index >= 0:
        i = rows.bad_index
        _fail(f"triangle {i} {tri[i].tolist()} references a vertex outside 0..{n - 1}", check="input")
    if rows.bad_consecutive >= 0:
        bad = rows.bad_consecutive
        run = int(np.searchsorted(np.cumsum(runs), bad, side="right"))
        _fail(
            f"cycle {run} breaks at triangle {bad}: it shares no edge with the next "
            "triangle of its cycle", check="cycle"
        )
    if rows.argmin < 0 or not (math.isfinite(rows.min_angle) and math.isfinite(rows.total_area)):
        _fail("angles and areas are not finite (coordinates too large or too small)", check="input")
    if rows.bad_orientation >= 0:  # exact: a float area may round either way on a flat triangle
        t = rows.bad_orientation
        sign = int(orient_points(pts, *(int(v) for v in tri[t])))
        what = "degenerate (collinear corners)" if sign == 0 else "inverted"
        _fail(f"triangle {t} {tri[t].tolist()} is {what} (exact orientation test)", check="orientation")

    dup = -1
    if claim_ok:
        twin = claim
        cross = rows.cross_run
    else:  # no (valid) claim: find the pairing, then check the runs with it
        prepared = None
        if own_twin is not None and np.shape(own_twin) == (3 * m,):
            twin, dup = own_twin, -1
        else:
            twin, dup = _kernels.half_edge_twins(tri, n)
        twin = twin.astype(pdt, copy=False)  # (one compiled signature of the kernels below)
        cross = -1 if dup >= 0 else int(_kernels.first_cross_run_edge(twin, runs))
    if dup >= 0:
        t, k = divmod(int(dup), 3)
        same = np.flatnonzero((np.sort(tri, axis=1) == np.sort(tri[t])).all(axis=1))
        if len(same) > 1:
            _fail(f"triangle {tri[t].tolist()} appears twice (rows {same[:2].tolist()})", check="overlap")
        _fail(
            f"edge ({tri[t, k]}, {tri[t, (k + 1) % 3]}) of triangle {t} is used twice in the "
            "same direction (overlap or non-manifold edge)", check="overlap"
        )
    if cross >= 0:
        _fail(
            f"triangles {cross // 3} and {int(twin[cross]) // 3} share an edge but lie in different "
            "cycles (a connected piece must be one cycle)", check="cycle"
        )

    has_segs = segments is not None and np.size(segments) > 0
    b_out = None  # the output's boundary edge keys, if needed
    if has_segs or facts is not None:
        b_out = prepared["boundary"] if prepared is not None else boundary_keys(tri, twin)
    if has_segs:
        segs = np.asarray(segments)
        if segs.ndim != 2 or segs.shape[1] != 2 or not np.issubdtype(segs.dtype, np.integer):
            _fail(f"constrained edges must be (s, 2) integers, got shape {segs.shape}", check="input")
        segs = segs.astype(np.int64)
        if segs.min() < 0 or segs.max() >= n:
            _fail(f"constrained edges reference vertices outside 0..{n - 1}", check="input")
        inner = np.flatnonzero(~_on_boundary(segs, b_out))  # boundary edges are edges
        if len(inner):
            found = has_edges(tri, n, segs[inner])
            if not found.all():
                s = int(inner[np.argmin(found)])
                _fail(f"constrained edge {s} {segs[s].tolist()} is not an edge of the mesh", check="domain")

    stats: dict[str, Any] = {
        "min_angle_output_deg": math.degrees(rows.min_angle),
        "max_angle_output_deg": math.degrees(rows.max_angle),
        "area": float(rows.total_area),
    }
    if facts is not None:
        stats.update(_compare_with_input(pts, tri, facts, used, rows, angle_ratio, b_out))
    return stats


def _compare_with_input(
    pts: np.ndarray,
    tri: np.ndarray,
    facts: InputFacts,
    used_out: np.ndarray,
    rows: RowChecks,
    angle_ratio: float,
    b_out: np.ndarray,
) -> dict[str, Any]:
    n = len(pts)
    n_in = len(facts.points)
    if n < n_in:
        _fail(f"the output has {n} points, fewer than the input's {n_in}", check="domain")
    # (one equality pass, SIMD, no temporaries; the row-wise search only on failure:
    # 2 ms against 17-23 ms at 0.77 M points)
    moved = [] if np.array_equal(pts[:n_in], facts.points) else np.flatnonzero(
        (pts[:n_in] != facts.points).any(axis=1)
    )
    if len(moved):
        i = int(moved[0])
        _fail(f"input point {i} {facts.points[i].tolist()} is not kept unchanged (output has {pts[i].tolist()})", check="domain")
    lost = facts.used & ~used_out[:n_in]
    if lost.any():
        _fail(f"input vertex {int(np.argmax(lost))} is no longer a vertex of the mesh", check="domain")

    total = rows.total_area
    if not math.isclose(total, facts.area, rel_tol=AREA_RTOL, abs_tol=0.0):
        # (float areas of triangles far from the origin or of very different sizes can
        # differ by more than AREA_RTOL: allow what rounding can explain, no more)
        slack = AREA_RTOL * abs(facts.area) + area_rounding_bound(pts, tri)
        slack += math.inf if facts.triangles is None else area_rounding_bound(facts.points, facts.triangles)
        if not abs(total - facts.area) <= slack or facts.triangles is None:
            _fail(f"total area changed from {facts.area!r} to {total!r}", check="domain")

    b_in = facts.boundary
    if not np.array_equal(b_out, b_in):
        diff = np.setxor1d(b_out, b_in)
        k = int(diff[0])
        _fail(
            f"boundary changed: edge ({k // KEY_BASE}, {k % KEY_BASE}) is on the boundary of only one of "
            "input and output", check="domain"
        )

    _check_segments_kept(pts, tri, facts.segments, b_out)

    r_min = facts.min_angle
    floor = angle_ratio * r_min * (1.0 - ANGLE_RTOL)
    rounded = 0
    if rows.min_angle < floor:
        rounded = _rounding_explains(pts, tri, n_in, angle_ratio * r_min, floor)
        if rounded < 0:
            t = rows.argmin
            _fail(
                f"triangle {t} {tri[t].tolist()} has angle {math.degrees(rows.min_angle):.6f} deg, "
                f"below {angle_ratio} x the input minimum {math.degrees(r_min):.6f} deg", check="angle"
            )
    return {"min_angle_input_deg": math.degrees(r_min), "angle_rounding_rows": int(rounded)}


def row_angles(pts: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """``(m, 3)`` angles (radians) at each row's corners, by ``atan2(|cross|, dot)``.

    The certificate's own numpy evaluation (accurate for slivers, where ``acos`` of a
    cosine near 1 is not).
    """
    a, b, c = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    out = np.empty(tri.shape, dtype=np.float64)
    for k, (p, q, r) in enumerate(((a, b, c), (b, c, a), (c, a, b))):
        u, v = q - p, r - p
        cross = np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
        dot = u[:, 0] * v[:, 0] + u[:, 1] * v[:, 1]
        out[:, k] = np.arctan2(cross, dot)
    return out


def _rounding_explains(pts: np.ndarray, tri: np.ndarray, n_in: int, bound: float, floor: float) -> int:
    """Rows below ``floor`` whose shortfall the float64 rounding of Steiner points explains.

    Thm 2.4's bound is tight (an incenter triangle has exactly half an input angle), and
    a Steiner point is stored rounded to float64 in the input's coordinates: it moves
    by up to one ulp per coordinate, which moves an angle at a corner by up to that
    distance over the adjacent edge length. On a sliver far from the origin (the
    20,000-vertex circle meshed without a quality bound: 0.009 deg angles) that is a
    relative 1e-8, more than ``ANGLE_RTOL``. A row below ``floor`` is accepted only if
    it has a Steiner point (a vertex beyond the input's ``n_in``), its shortfall is
    within ``ROUNDING_FACTOR * ulp / shortest edge`` and at most ``ROUNDING_RTOL_MAX``
    of the bound. Returns how many rows were accepted so, or -1 if any row is not.
    Rare path (only when the plain check fails), so plain numpy over all rows.
    """
    ang = row_angles(pts, tri).min(axis=1)
    low = np.flatnonzero(ang < floor)
    if len(low) == 0:  # the kernels' and numpy's evaluations differ in the last bits
        return 0
    rows = tri[low]
    if not (rows >= n_in).any(axis=1).all():
        return -1
    p = pts[rows]  # (k, 3, 2)
    edges = np.linalg.norm(p - np.roll(p, -1, axis=1), axis=2).min(axis=1)
    ulp = np.spacing(np.abs(p).max(axis=(1, 2)))
    allowance = ROUNDING_FACTOR * ulp / edges
    shortfall = bound - ang[low]
    ok = (shortfall <= allowance) & (shortfall <= ROUNDING_RTOL_MAX * bound)
    return int(len(low)) if ok.all() else -1


def _on_boundary(segs: np.ndarray, keys: np.ndarray) -> np.ndarray:
    """Which edges ``segs`` (either direction) are among the sorted boundary ``keys``."""
    out = np.zeros(len(segs), dtype=bool)
    if len(keys):
        for k in (edge_keys(segs[:, 0], segs[:, 1]), edge_keys(segs[:, 1], segs[:, 0])):
            i = np.searchsorted(keys, k).clip(max=len(keys) - 1)
            out |= keys[i] == k
    return out


def has_edges(tri: np.ndarray, n: int, edges: np.ndarray) -> np.ndarray:
    """Which undirected ``edges`` (k, 2) are edges of ``tri`` (one pass over its half-edges)."""
    keys = undirected_keys(edges, n)
    want = np.unique(keys)
    return _kernels.find_edges(tri, n, want)[np.searchsorted(want, keys)]


def _check_segments_kept(pts: np.ndarray, tri: np.ndarray, segs: np.ndarray, b_out: np.ndarray) -> None:
    """Every input constrained edge is an output edge, or split at its exact midpoint.

    Boundary edges are output edges (the boundaries were found equal); the others
    are looked up among the output's edges, and a segment ``ab`` that is none must be
    the output edges ``aM`` and ``Mb`` for an output vertex ``M`` at exactly its
    midpoint (there are few such segments: one per region a construction joins).
    """
    inner = np.flatnonzero(~_on_boundary(segs, b_out))
    if len(inner) == 0:
        return
    n = len(pts)
    missing = inner[~has_edges(tri, n, segs[inner])]
    if len(missing) == 0:
        return
    a, b = segs[missing, 0], segs[missing, 1]
    mid = 0.5 * (pts[a] + pts[b])
    # output vertices at exactly a midpoint: compare coordinates as one complex value
    pc = np.ascontiguousarray(pts).view(np.complex128).ravel()
    mc = np.ascontiguousarray(mid).view(np.complex128).ravel()
    cand = np.flatnonzero(np.isin(pc, mc))
    cand = cand[np.argsort(pc[cand], kind="stable")]
    lo = np.searchsorted(pc[cand], mc, side="left")
    hi = np.searchsorted(pc[cand], mc, side="right")
    seg_of = np.repeat(np.arange(len(missing)), hi - lo)
    c = cand[np.concatenate([np.arange(i, j) for i, j in zip(lo, hi)]) if len(seg_of) else np.zeros(0, int)]
    halves = has_edges(tri, n, np.c_[a[seg_of], c]) & has_edges(tri, n, np.c_[c, b[seg_of]])
    ok = np.zeros(len(missing), dtype=bool)
    ok[seg_of[halves]] = True
    if not ok.all():
        s = int(missing[np.argmin(ok)])
        _fail(
            f"input constrained edge {s} ({segs[s, 0]}, {segs[s, 1]}) is neither an output edge nor "
            "split at its midpoint", check="domain"
        )
