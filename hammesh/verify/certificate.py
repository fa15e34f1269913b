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
   (relative tolerance ``AREA_RTOL``), the boundary edges are the same, every input
   constrained edge is an output edge or the union of two collinear output edges
   meeting at its midpoint, and the minimum angle is at least ``angle_ratio`` times
   the input's minimum angle, up to a relative tolerance ``ANGLE_RTOL`` (the bound of
   Thm 2.4 is tight: an incenter triangle has exactly half an input angle, which
   floating point can round either way by a few ulps).

Items 2-3 with the unchanged area and boundary mean the output triangles tile the
input domain without overlap: glue the triangles along a pairing of their half-edges
(each pair the same edge, opposite directions); the result is a surface whose
boundary is the unpaired half-edges. Mapped to the plane with every triangle positive
it covers each point of a domain piece the same number of times (the degree is
constant away from the image of the boundary); if the unpaired half-edges are exactly
the input's boundary edges, that number is at least one in every piece (triangles sit
on the inner side of its boundary), and equal total area makes it exactly one. So
with a reference, *any* valid pairing proves the tiling, which lets the construction
hand its own pairing in (``twin_claim``): checking a claim is one read per
half-edge, where finding the pairing needs a bucket sort. Without a reference the
pairing is always computed, and a non-manifold edge fails item 3 directly.
"""

from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np

from hammesh import _threads, params
from hammesh._threads import row_ranges, run_all
from hammesh.halfedge import HalfEdges
from hammesh.halfedge._kernels import vertex_half_edges
from hammesh.errors import VerificationError
from hammesh.mesh import HamiltonianMesh, Mesh
from hammesh.predicates import orient_points
from hammesh.verify import _kernels
from hammesh.verify._kernels import RowChecks

__all__ = ["verify", "verify_cycle_mesh", "input_facts", "claim_structure", "ANGLE_RTOL", "AREA_RTOL"]

ANGLE_RTOL = 1e-9
AREA_RTOL = 1e-9


def _fail(msg: str) -> None:
    raise VerificationError(msg)


#: Edge keys ``a * KEY_BASE + b``: one base for input and output (any vertex < 2**31).
KEY_BASE = 1 << 32


def _edge_keys(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a.astype(np.int64) * KEY_BASE + b.astype(np.int64)


def _certify_rows(
    pts: np.ndarray,
    tri: np.ndarray,
    runs: np.ndarray,
    claim: np.ndarray,
    used: np.ndarray,
    side: Callable[[], Any] | None = None,
) -> tuple[tuple, Any]:
    """``_kernels.certify_row_range`` over all rows, split across the machine's cores.

    The kernels release the GIL, so plain threads share the pass; the chunks' results
    combine exactly (first failures by row, extremes, sums), the same as one call.
    ``side`` (the input-side facts) runs alongside; its result is returned second.
    """
    no_marks = np.empty(0, dtype=np.bool_)
    spans = row_ranges(len(tri), _threads.THREAD_MIN_ROWS)
    calls = [
        (lambda lo=lo, hi=hi: _kernels.certify_row_range(pts, tri, runs, claim, lo, hi, used, no_marks))
        for lo, hi in spans
    ]
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
    )


def _input_facts(ref: Mesh, r_twin: np.ndarray) -> dict[str, Any]:
    """What the comparison with the input needs from it (runs beside other work).

    The smallest angle, the area and the used vertices are taken from
    ``ref.info["validated"]`` when ``prepare_mesh`` found them already.
    """
    rp = np.asarray(ref.points, dtype=np.float64)
    rt = np.ascontiguousarray(ref.triangles, dtype=np.int64)
    seen = ref.info.get("validated") if isinstance(ref.info, dict) else None
    if seen is not None:
        r_min, r_total, used = seen["min_angle"], seen["total"], seen["used"]
    else:
        stats = _kernels.angle_area_stats(rp, rt)
        r_min, r_total = stats.min_angle, stats.total_area
        used = np.zeros(len(rp), dtype=np.bool_)
        _kernels.mark_used(rt, used)
    return {
        "min_angle": r_min,
        "total": r_total,
        "used": used,
        "boundary": _boundary_keys(rt, r_twin),
        "n_boundary": int(np.count_nonzero(r_twin < 0)),
    }


input_facts = _input_facts


def claim_structure(triangles: np.ndarray, n_points: int, claim: np.ndarray) -> dict[str, Any]:
    """What the certificate's last steps need from the output, computed ahead.

    The sorted boundary edge keys if ``claim`` is the pairing;
    ``verify_cycle_mesh(prepared=...)`` uses them only if the claim passes its checks.
    A construction computes this while its rows are checked. (The vertex rotations
    that interior constrained edges need are built only when there are such edges.)
    """
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    return {"boundary": _boundary_keys(tri, claim)}


def _boundary_keys(tri: np.ndarray, twin: np.ndarray) -> np.ndarray:
    e = _kernels.boundary_half_edges(tri, twin)
    return np.sort(_edge_keys(e[:, 0], e[:, 1]))


def verify_cycle_mesh(
    points: np.ndarray,
    triangles: np.ndarray,
    components: np.ndarray,
    *,
    segments: np.ndarray | None = None,
    reference: Mesh | None = None,
    reference_twin: np.ndarray | None = None,
    twin_claim: np.ndarray | None = None,
    angle_ratio: float = 0.5,
    rows: tuple | None = None,
    input_facts: dict[str, Any] | None = None,
    prepared: dict[str, Any] | None = None,
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
        The input mesh; enables the checks of item 5 of the module docstring.
    reference_twin : (3 m_in,) int64, optional
        The reference's half-edge twins if already computed (saves one pass).
    twin_claim : (3 m,) int64, optional
        A claimed pairing of the output's half-edges (from the construction). With a
        reference it replaces the bucket matching: the claim is checked to be a
        reversed-edge involution, and the boundary/area checks then prove it is the
        true adjacency (see the module docstring). A claim that is not a valid
        pairing, or leaves a different number of boundary edges than the input has,
        is ignored (the pairing is then computed).
    angle_ratio : float
        Required ``min angle out / min angle in`` (Thm 2.4: 0.5).
    rows : tuple, optional
        ``(row results, used)`` already computed by a
        :class:`~hammesh.verify.stream.RowStream` that checked the rows while they
        were written; the same checks are then not run again.
    input_facts : dict, optional
        ``input_facts(reference, reference_twin)`` if already computed.
    prepared : dict, optional
        ``claim_structure(triangles, n, twin_claim)`` if already computed (used only
        if the claim is valid).

    Returns
    -------
    dict
        ``min_angle_output_deg``, ``max_angle_output_deg``, ``area`` and, with a
        reference, ``min_angle_input_deg``.

    Raises
    ------
    VerificationError
    """
    pts = np.asarray(points, dtype=np.float64)
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    runs = np.asarray(components, dtype=np.int64).reshape(-1)
    n, m = len(pts), len(tri)
    if pts.ndim != 2 or pts.shape[1] != 2 or tri.ndim != 2 or tri.shape[1] != 3:
        _fail(f"bad shapes: points {pts.shape}, triangles {tri.shape}")
    if m == 0:
        _fail("the mesh has no triangles")
    if not np.isfinite(pts).all():
        _fail(f"point {int(np.argmax(~np.isfinite(pts).all(axis=1)))} is not finite")
    if (runs <= 0).any() or runs.sum() != m:
        _fail(f"components {runs.tolist()[:10]} are not positive run lengths summing to {m}")

    if reference is not None and reference_twin is None:
        r_tri = np.asarray(reference.triangles)
        if r_tri.size and (r_tri.min() < 0 or r_tri.max() >= len(reference.points)):
            _fail("the reference mesh references vertices outside its points")
        reference_twin, r_dup = _kernels.half_edge_twins(
            np.ascontiguousarray(reference.triangles, dtype=np.int64), len(reference.points)
        )
        if r_dup >= 0:
            _fail("the input mesh is not edge-manifold; it cannot serve as a reference")
    # a claimed pairing is only of use with a reference (the tiling argument needs the
    # input's boundary)
    claim = None
    if twin_claim is not None:  # int32 claims are checked as they are (no copy)
        claim = np.asarray(twin_claim)
        claim = np.ascontiguousarray(claim, dtype=claim.dtype if claim.dtype == np.int32 else np.int64)
    if not (claim is not None and reference_twin is not None and claim.shape == (3 * m,)):
        claim = np.empty(0, dtype=np.int64)
    ref_facts = input_facts
    if rows is None:
        used = np.zeros(n, dtype=np.bool_)
        side = None
        if reference is not None and ref_facts is None:
            side = lambda: _input_facts(reference, reference_twin)  # noqa: E731
        rows, side_facts = _certify_rows(pts, tri, runs, claim, used, side)
        ref_facts = ref_facts if side is None else side_facts
    else:  # checked while the construction ran (``hammesh.verify.stream``)
        rows, used = rows
        if reference is not None and ref_facts is None:
            ref_facts = _input_facts(reference, reference_twin)
    (bad_index, bad, bad_pair, cross, amin, tmin, amax, _, area_min, tarea, total, bad_orient,
     links, unpaired) = rows
    # the claim is a pairing of all half-edges with as many unpaired ones as the input
    # has boundary edges, or it is not used
    if len(claim) and not (
        bad_pair < 0
        and 2 * links + unpaired == 3 * m
        and (unpaired == ref_facts["n_boundary"] if ref_facts else False)
    ):
        bad_pair = 0
    if bad_index >= 0:
        _fail(f"triangle {bad_index} {tri[bad_index].tolist()} references a vertex outside 0..{n - 1}")
    if bad >= 0:
        run = int(np.searchsorted(np.cumsum(runs), bad, side="right"))
        _fail(
            f"cycle {run} breaks at triangle {bad}: it shares no edge with the next "
            "triangle of its cycle"
        )
    if tmin < 0 or not (math.isfinite(amin) and math.isfinite(total)):
        _fail("angles and areas are not finite (coordinates too large or too small)")
    if bad_orient >= 0:  # exact: a float area may round either way on a flat triangle
        t = bad_orient
        sign = int(orient_points(pts, *(int(v) for v in tri[t])))
        what = "degenerate (collinear corners)" if sign == 0 else "inverted"
        _fail(f"triangle {t} {tri[t].tolist()} is {what} (exact orientation test)")

    dup = -1
    if not (len(claim) and bad_pair < 0):
        prepared = None
    if prepared is not None:
        twin = claim
    elif len(claim) and bad_pair < 0:
        twin = claim
    else:  # no (valid) claim: find the pairing, then check the runs with it
        twin, dup = _kernels.half_edge_twins(tri, n)
        cross = -1 if dup >= 0 else int(_kernels.first_cross_run_edge(twin, runs))
    if dup >= 0:
        t, k = divmod(int(dup), 3)
        same = np.flatnonzero((np.sort(tri, axis=1) == np.sort(tri[t])).all(axis=1))
        if len(same) > 1:
            _fail(f"triangle {tri[t].tolist()} appears twice (rows {same[:2].tolist()})")
        _fail(
            f"edge ({tri[t, k]}, {tri[t, (k + 1) % 3]}) of triangle {t} is used twice in the "
            "same direction (overlap or non-manifold edge)"
        )
    h = int(cross)
    if h >= 0:
        _fail(
            f"triangles {h // 3} and {int(twin[h]) // 3} share an edge but lie in different "
            "cycles (a connected piece must be one cycle)"
        )

    has_segs = segments is not None and len(segments) > 0
    b_out = None  # the output's boundary edge keys, if needed
    if has_segs or reference is not None:
        b_out = prepared["boundary"] if prepared is not None else _boundary_keys(tri, twin)
    he_box: list[HalfEdges] = []

    def out_he() -> HalfEdges:  # vertex rotations: built once, only if a segment needs it
        if not he_box:
            he_box.append(HalfEdges(tri, twin, vertex_half_edges(tri, n)))
        return he_box[0]

    if has_segs:
        segs = np.ascontiguousarray(segments, dtype=np.int64).reshape(-1, 2)
        if segs.min() < 0 or segs.max() >= n:
            _fail(f"constrained edges reference vertices outside 0..{n - 1}")
        inner = np.flatnonzero(~_on_boundary(segs, b_out))  # boundary edges are edges
        if len(inner):
            found = out_he().mark(segs[inner])[1]
            if not found.all():
                s = int(inner[np.argmin(found)])
                _fail(f"constrained edge {s} {segs[s].tolist()} is not an edge of the mesh")

    stats: dict[str, Any] = {
        "min_angle_output_deg": math.degrees(amin),
        "max_angle_output_deg": math.degrees(amax),
        "area": float(total),
    }
    if reference is not None:
        stats.update(
            _compare_with_input(
                pts, tri, out_he, reference, ref_facts, used, amin, tmin, total, angle_ratio, b_out
            )
        )
    return stats


def _compare_with_input(
    pts: np.ndarray,
    tri: np.ndarray,
    out_he: Callable[[], HalfEdges],
    ref: Mesh,
    facts: dict[str, Any],
    used_out: np.ndarray,
    amin: float,
    tmin: int,
    total: float,
    angle_ratio: float,
    b_out: np.ndarray,
) -> dict[str, Any]:
    n = len(pts)
    rp = np.asarray(ref.points, dtype=np.float64)
    n_in = len(rp)
    if n < n_in or not np.array_equal(pts[:n_in], rp):
        _fail("the input points are not kept unchanged as the first output points")
    lost = facts["used"] & ~used_out[:n_in]
    if lost.any():
        _fail(f"input vertex {int(np.argmax(lost))} is no longer a vertex of the mesh")

    r_min, r_total = facts["min_angle"], facts["total"]
    if not math.isclose(total, r_total, rel_tol=AREA_RTOL, abs_tol=0.0):
        _fail(f"total area changed from {r_total!r} to {total!r}")

    b_in = facts["boundary"]
    if not np.array_equal(b_out, b_in):
        diff = np.setxor1d(b_out, b_in)
        k = int(diff[0])
        _fail(
            f"boundary changed: edge ({k // KEY_BASE}, {k % KEY_BASE}) is on the boundary of only one of "
            "input and output"
        )

    _check_segments_kept(pts, out_he, ref, b_out)

    floor = angle_ratio * r_min * (1.0 - ANGLE_RTOL)
    if amin < floor:
        _fail(
            f"triangle {tmin} {tri[tmin].tolist()} has angle {math.degrees(amin):.6f} deg, "
            f"below {angle_ratio} x the input minimum {math.degrees(r_min):.6f} deg"
        )
    return {"min_angle_input_deg": math.degrees(r_min)}


def _on_boundary(segs: np.ndarray, keys: np.ndarray) -> np.ndarray:
    """Which edges ``segs`` (either direction) are among the sorted boundary ``keys``."""
    out = np.zeros(len(segs), dtype=bool)
    if len(keys):
        for k in (_edge_keys(segs[:, 0], segs[:, 1]), _edge_keys(segs[:, 1], segs[:, 0])):
            i = np.searchsorted(keys, k).clip(max=len(keys) - 1)
            out |= keys[i] == k
    return out


def _check_segments_kept(pts: np.ndarray, out_he: Callable[[], HalfEdges], ref: Mesh, b_out: np.ndarray) -> None:
    """Every input constrained edge is an output edge, or split at its exact midpoint.

    Boundary edges are output edges (the boundaries were found equal); only the
    others need a look at the vertex rotations.
    """
    segs = np.ascontiguousarray(ref.segments, dtype=np.int64).reshape(-1, 2)
    inner = np.flatnonzero(~_on_boundary(segs, b_out))
    if len(inner) == 0:
        return
    he = out_he()
    # a segment that is no output edge must be split at its midpoint M into the
    # output edges (a, M) and (M, b); there are few such segments (one per region)
    for s in inner[~he.mark(segs[inner])[1]].tolist():
        a, b = int(segs[s, 0]), int(segs[s, 1])
        mid = 0.5 * (pts[a] + pts[b])
        cands = he.neighbors_of(a)
        cands = np.unique(cands[(pts[cands] == mid).all(axis=1)])
        if not any(he.mark(np.array([[a, c], [c, b]], dtype=np.int64))[1].all() for c in cands):
            _fail(
                f"input constrained edge {s} ({a}, {b}) is neither an output edge nor "
                "split at its midpoint"
            )


def verify(
    mesh: HamiltonianMesh,
    reference: Mesh | None = None,
    *,
    reference_twin: np.ndarray | None = None,
    twin_claim: np.ndarray | None = None,
    angle_ratio: float = 0.5,
    rows: tuple | None = None,
    input_facts: dict[str, Any] | None = None,
    prepared: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Certificate of a :class:`~hammesh.mesh.HamiltonianMesh` (see module docstring).

    ``reference`` is the input mesh it was made from (counter-clockwise); without it
    only items 1-4 are checked (what ``hammesh check FILE`` can know).
    """
    params.instance("mesh", mesh, HamiltonianMesh, "a hammesh.HamiltonianMesh (a Mesh has no cycles)")
    return verify_cycle_mesh(
        mesh.points,
        mesh.triangles,
        mesh.components,
        segments=mesh.segments,
        reference=reference,
        reference_twin=reference_twin,
        twin_claim=twin_claim,
        angle_ratio=angle_ratio,
        rows=rows,
        input_facts=input_facts,
        prepared=prepared,
    )
