"""Injected construction bugs: every one must be caught by the certificate, by name.

Two kinds of mutation: a monkeypatch of construction code (the input's half-edge
pairing, orientation and constrained edges in ``hammesh.halfedge``; Thm 2.4's
incenters and spanning forest in ``hammesh.postprocess._thm24_kernels``), after
which ``hammesh.hamiltonian`` must raise; and an output damaged by hand, which the
public ``hammesh.verify(output, input)`` must reject. Each case names the message
the certificate must give. Both constructions (``mode="incircle"``, ``"sparse"``)
run through the construction-side patches and the hand damage.
"""

from __future__ import annotations

import functools
from dataclasses import replace

import numpy as np
import pytest

import hammesh
from hammesh.halfedge import _kernels as he_kernels
from hammesh.postprocess import _thm24_kernels as thm24
from tests.helpers import plate

MODES = ("incircle", "sparse")


def grid(nx: int = 12, ny: int = 6) -> hammesh.Mesh:
    """``nx`` x ``ny`` unit squares, each cut into two triangles; no neighbour array."""
    xs, ys = np.meshgrid(np.arange(nx + 1.0), np.arange(ny + 1.0))
    pts = np.c_[xs.ravel(), ys.ravel()]
    v = lambda i, j: j * (nx + 1) + i  # noqa: E731
    tri = []
    for j in range(ny):
        for i in range(nx):
            tri += [[v(i, j), v(i + 1, j), v(i + 1, j + 1)], [v(i, j), v(i + 1, j + 1), v(i, j + 1)]]
    return hammesh.Mesh(points=pts, triangles=np.array(tri, dtype=np.int64))


def on_line_x1(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Half-edges (``3 t + k``) lying on the line x = 1."""
    a = points[tri[:, [0, 1, 2]], 0]
    b = points[tri[:, [1, 2, 0]], 0]
    return np.flatnonzero(((a == 1.0) & (b == 1.0)).ravel())


def drop_pairs_on_x1(monkeypatch, points: np.ndarray) -> None:
    """The construction's pairing forgets every edge on x = 1 (both halves boundary)."""
    real = he_kernels.half_edge_twins

    def broken(tri, n_points):
        twin, bad = real(tri, n_points)
        if n_points != len(points):  # (sparse pairs its output with it too: left intact)
            return twin, bad
        twin = twin.copy()
        twin[on_line_x1(points, tri)] = -1
        return twin, bad

    monkeypatch.setattr(he_kernels, "half_edge_twins", broken)


# ---------------------------------------------------------------- the grid


@pytest.mark.parametrize("mode", MODES)
def test_grid_with_six_pairings_dropped_is_rejected(monkeypatch, mode: str) -> None:
    """Issue 11: the construction-side pairing drops the 6 interior edges on x = 1 of a
    12 x 6 grid of unit squares (144 triangles): two cycles for one piece."""
    m = grid()
    assert m.n_triangles == 144 and m.neighbors is None
    h = hammesh.hamiltonian(m, mode=mode)  # intact: one cycle
    assert len(h.components) == 1
    assert len(on_line_x1(m.points, m.triangles)) == 12  # 6 edges, both halves
    drop_pairs_on_x1(monkeypatch, m.points)
    with pytest.raises(hammesh.VerificationError, match="different cycles|boundary changed"):
        hammesh.hamiltonian(m, mode=mode)


# ---------------------------------------------------------------- construction patches


@pytest.mark.parametrize("mode", MODES)
def test_extra_pairing_is_rejected(monkeypatch, mode: str) -> None:
    """The pairing joins the left and right boundary edges of the grid (a cylinder)."""
    m = grid(4, 3)
    real = he_kernels.half_edge_twins
    pts = m.points

    def broken(tri, n_points):
        twin, bad = real(tri, n_points)
        if n_points != len(pts):  # the input's pairing only
            return twin, bad
        twin = twin.copy()
        a = pts[tri[:, [0, 1, 2]]].reshape(-1, 2)
        b = pts[tri[:, [1, 2, 0]]].reshape(-1, 2)
        left = np.flatnonzero((a[:, 0] == 0) & (b[:, 0] == 0) & (twin < 0))
        right = np.flatnonzero((a[:, 0] == 4) & (b[:, 0] == 4) & (twin < 0))
        ly = np.minimum(a[left, 1], b[left, 1])
        ry = np.minimum(a[right, 1], b[right, 1])
        left, right = left[np.argsort(ly)], right[np.argsort(ry)]
        twin[left] = right
        twin[right] = left
        return twin, bad

    monkeypatch.setattr(he_kernels, "half_edge_twins", broken)
    with pytest.raises(hammesh.VerificationError, match="breaks at triangle|inverted|boundary changed|not linked into a cycle"):
        hammesh.hamiltonian(m, mode=mode)


@pytest.mark.parametrize("mode", MODES)
def test_wrong_orientation_pass_is_rejected(monkeypatch, mode: str) -> None:
    """The construction's orientation pass turns every row clockwise."""
    real = he_kernels.orient_ccw

    def broken(points, tri, used=None, measure=True, **kw):
        r = real(points, tri, used, measure=measure, **kw)
        return r._replace(triangles=r.triangles[:, ::-1].copy())

    monkeypatch.setattr(he_kernels, "orient_ccw", broken)
    with pytest.raises(hammesh.VerificationError, match="inverted"):
        hammesh.hamiltonian(grid(3, 2), mode=mode)


def edges_changed(m: hammesh.Mesh, h: hammesh.HamiltonianMesh) -> np.ndarray:
    """Interior input edges ``(k, 2)`` that are not output edges (flipped or swapped away)."""
    tri, out = m.triangles, h.triangles
    ends = lambda t: np.sort(np.c_[t[:, [0, 1, 2]].reshape(-1, 1), t[:, [1, 2, 0]].reshape(-1, 1)], axis=1)  # noqa: E731
    e_in, e_out = ends(tri), ends(out)
    key = lambda e: e[:, 0] * len(h.points) + e[:, 1]  # noqa: E731
    k_in, counts = np.unique(key(e_in), return_counts=True)
    inner = k_in[counts == 2]  # shared by two input triangles
    gone = np.setdiff1d(inner, key(e_out))
    return np.c_[gone // len(h.points), gone % len(h.points)]


@pytest.mark.parametrize("mode, max_area", [("incircle", 0.01), ("sparse", 0.004)])
def test_forgotten_constrained_edges_are_rejected(monkeypatch, mode: str, max_area: float) -> None:
    """The construction does not see the constrained edges (``mark_segments`` reports
    none), on an input whose constrained edges include interior edges it changes.

    Forced, not hoped for: a construction that sees no constrained edge does on this
    input exactly what it does on the same mesh without segments (same triangles,
    same pairing, every edge free), so the edges that run flips or swaps away are
    found first and then declared constrained (any edge of a mesh may be one)."""
    m = plate(2, 1, max_area=max_area)
    free = hammesh.hamiltonian(replace(m, segments=np.zeros((0, 2), np.int64), segment_markers=np.zeros(0, np.int64)),
                               mode=mode)
    gone = edges_changed(m, free)
    assert len(gone) > 0  # (incircle flips every tree edge; sparse joins its cover's cycles)
    pinned = replace(m, segments=np.r_[m.segments, gone], segment_markers=np.r_[m.segment_markers, np.ones(len(gone), np.int64)])
    hammesh.hamiltonian(pinned, mode=mode)  # seen, they are kept (or split at their midpoints)
    real = he_kernels.mark_segments

    def broken(tri, twin, vh, segments):
        is_con, found = real(tri, twin, vh, segments)
        return np.zeros_like(is_con), found

    monkeypatch.setattr(he_kernels, "mark_segments", broken)
    with pytest.raises(
        hammesh.VerificationError,
        match="constrained edge .* (is not an edge of the mesh|is neither an output edge nor split at its midpoint)",
    ):
        hammesh.hamiltonian(pinned, mode=mode)


def test_incenter_outside_its_triangle_is_rejected(monkeypatch) -> None:
    """Thm 2.4's incenters: one lands outside its triangle (mirrored over an edge)."""
    real = thm24.incenters

    def broken(points, tri, out=None):
        out = real(points, tri, out)
        a, b = points[tri[0, 0]], points[tri[0, 1]]
        out[0] = a + b - out[0]  # point reflection through the edge's midpoint
        return out

    monkeypatch.setattr(thm24, "incenters", broken)
    with pytest.raises(hammesh.VerificationError, match="inverted|breaks"):
        hammesh.hamiltonian(grid(3, 2), mode="incircle")


def test_tree_edge_dropped_splits_the_cycle(monkeypatch) -> None:
    """The spanning forest loses a tree edge: the walk makes two cycles for one piece."""
    real = thm24.spanning_forest

    def broken(tri, twin, is_con, points=None, **options):
        f = real(tri, twin, is_con, points, **options)
        code = f.code.copy()
        h = int(np.flatnonzero(((code & thm24.TREE_BIT) != 0) & ((code & thm24.CON_BIT) == 0))[-1])
        g = int((code[h] >> 2) - 1)
        code[[h, g]] &= ~thm24.TREE_BIT
        return f._replace(code=code)

    monkeypatch.setattr(thm24, "spanning_forest", broken)
    with pytest.raises(hammesh.VerificationError, match="tree walk|different cycles"):
        hammesh.hamiltonian(grid(3, 2), mode="incircle")


def test_rows_rewritten_after_their_check_are_caught(monkeypatch) -> None:
    """The walk swaps two rows it already published (the side thread may have checked
    them): the certificate compares what it checked with what is returned."""
    real = thm24.emit_cycles_into

    def broken(*args):
        status = real(*args)
        if status == 1:
            out = args[7]
            out[[1, 4]] = out[[4, 1]]
        return status

    monkeypatch.setattr(thm24, "emit_cycles_into", broken)
    with pytest.raises(hammesh.VerificationError, match="rows changed after they were checked|breaks at triangle"):
        hammesh.hamiltonian(grid(6, 4), mode="incircle")


def test_points_rewritten_after_the_check_began_are_caught(monkeypatch) -> None:
    """The construction moves an input point when it assembles its result (the row
    checks may have started on the points: then their digest differs, else the point
    is not the input's)."""
    from hammesh.postprocess import incircle

    real = incircle.HamiltonianMesh

    def moving(**kw):
        pts = kw["points"]
        pts[0] += 1e-9
        return real(**kw)

    monkeypatch.setattr(incircle, "HamiltonianMesh", moving)
    with pytest.raises(hammesh.VerificationError, match="points changed after|input point 0 .* not kept unchanged"):
        hammesh.hamiltonian(grid(6, 4), mode="incircle")


def lie_about_the_angle(monkeypatch) -> None:
    """The construction's validation reports a tiny input minimum angle."""
    import hammesh.postprocess as post

    real = post.prepare_mesh

    def lying(mesh, **kw):
        clean, he, is_con = real(mesh, **kw)
        # (incircle measures nothing in its validation: the lie is put where sparse's is)
        seen = clean.info.get("validated") or {"total": 1.0, "used": np.ones(clean.n_points, bool)}
        info = {**clean.info, "validated": {**seen, "min_angle": 1e-3}}
        return replace(clean, info=info), he, is_con

    monkeypatch.setattr(post, "prepare_mesh", lying)


@pytest.mark.parametrize("mode", MODES)
def test_wrong_angle_cache_does_not_reach_the_certificate(monkeypatch, mode: str) -> None:
    """The construction's validation reports a tiny input angle: the certificate still
    measures the input itself (the reported input angle is the true one) and the
    output holds the true bound."""
    from tests.helpers import angles_deg

    m = plate(1, 1, max_area=0.01)
    lie_about_the_angle(monkeypatch)
    h = hammesh.hamiltonian(m, mode=mode)
    true_min = angles_deg(m.points, m.triangles).min()
    assert np.isclose(h.report["min_angle_input_deg"], true_min, rtol=1e-9)
    assert angles_deg(h.points, h.triangles).min() >= 0.5 * true_min * (1 - 1e-9)


@pytest.mark.parametrize("mode", MODES)
def test_angle_cache_in_the_input_is_not_trusted(monkeypatch, mode: str) -> None:
    """Issue 11: a cache in ``info["validated"]`` claiming a tiny input angle does not
    let an output below the true bound through ``hammesh.verify``."""
    m = plate(1, 1, max_area=0.01)
    h = made_in(mode, m)
    lied = replace(m, info={"validated": {"min_angle": 1e-3, "total": 1.0, "used": np.ones(m.n_points, bool)}})
    hammesh.verify(h, lied)  # the valid output passes
    with pytest.raises(hammesh.VerificationError, match="below 0.5 x the input minimum"):
        hammesh.verify(squeezed(m, h), lied)


# ---------------------------------------------------------------- hand-damaged outputs


def made_in(mode: str, m: hammesh.Mesh) -> hammesh.HamiltonianMesh:
    """``hamiltonian(m, mode)``; sparse without swaps, edge splits and cover swaps, so
    that its merges are Thm 2.4 bridges (incenters to damage)."""
    from hammesh.postprocess import sparse

    with pytest.MonkeyPatch.context() as mp:
        if mode == "sparse":
            mp.setattr(sparse.sparse_cycles, "__kwdefaults__",
                       {**sparse.sparse_cycles.__kwdefaults__, "swaps": False, "edge_splits": False})
            mp.setattr(sparse, "ALT_MERGE_TRIES", 0)  # (they would take the bridges away)
        h = hammesh.hamiltonian(m, mode=mode)
    assert h.report["incenters"] >= 1
    return h


@functools.lru_cache(maxsize=None)
def made(mode: str) -> tuple[hammesh.Mesh, hammesh.HamiltonianMesh]:
    """The loops plate and its output (built once per mode)."""
    m = plate(2, 1, max_area=0.01)
    return m, made_in(mode, m)


def squeezed(m: hammesh.Mesh, h: hammesh.HamiltonianMesh) -> hammesh.HamiltonianMesh:
    """Move one Steiner point (inside the fan of triangles around it) toward a corner:
    still a valid tiling, but with a small angle."""
    star = np.flatnonzero((h.triangles >= m.n_points).any(axis=1))
    v = int(h.triangles[star[0]][h.triangles[star[0]] >= m.n_points][0])
    fan = np.flatnonzero((h.triangles == v).any(axis=1))
    corner = int(next(u for u in h.triangles[fan[0]] if u != v))
    pts = h.points.copy()
    pts[v] = pts[v] + 0.9 * (pts[corner] - pts[v])
    return replace(h, points=pts)


def damaged(h: hammesh.HamiltonianMesh, what: str, m: hammesh.Mesh) -> hammesh.HamiltonianMesh:
    tri, pts, runs = h.triangles.copy(), h.points.copy(), h.components.copy()
    n_in = m.n_points
    if what == "missing triangle":
        return replace(h, triangles=np.delete(tri, 5, axis=0), components=runs - np.eye(len(runs), dtype=int)[0])
    if what == "duplicated triangle":
        tri[7] = tri[3]
        return replace(h, triangles=tri)
    if what == "rows swapped":
        tri[[4, 9]] = tri[[9, 4]]
        return replace(h, triangles=tri)
    if what == "run length off by one":
        runs[0] += 1
        return replace(h, components=runs)
    if what == "cycle split in two":
        k = int(runs[0]) // 2
        return replace(h, components=np.r_[k, runs[0] - k, runs[1:]].astype(np.int64))
    if what == "flipped orientation":
        tri[11] = tri[11, ::-1]
        return replace(h, triangles=tri)
    if what == "moved input vertex":
        pts[3] += [1e-12, 0.0]
        return replace(h, points=pts)
    if what == "incenter outside its triangle":
        v = int(np.max(tri[h.kind == 0]))  # a Steiner point at an incenter
        t = int(np.flatnonzero((tri == v).any(axis=1))[0])
        a, b = (u for u in tri[t] if u != v)
        pts[v] = pts[a] + pts[b] - pts[v]
        return replace(h, points=pts)
    if what == "midpoint off the segment":  # slid along its segment: no longer the midpoint
        halves = h.segments[(h.segments >= n_in).any(axis=1)]
        mid = int(halves[0].max())
        a, b = (int(e.min()) for e in halves if e.max() == mid)
        pts[mid] += 0.01 * (pts[b] - pts[a])
        return replace(h, points=pts)
    if what == "vertex out of range":
        tri[2, 1] = len(pts) + 3
        return replace(h, triangles=tri)
    if what == "point not finite":
        pts[-1, 0] = np.nan
        return replace(h, points=pts)
    if what == "output segment not an edge":
        segs = np.r_[h.segments, [[0, len(pts) - 1]]]
        return replace(h, segments=segs.astype(np.int64), segment_markers=np.r_[h.segment_markers, 1])
    if what == "small angle":
        return squeezed(m, h)
    raise AssertionError(what)


CASES = {
    "missing triangle": "breaks at triangle|boundary changed|area",
    "duplicated triangle": "breaks at triangle|appears twice",
    "rows swapped": "breaks at triangle",
    "run length off by one": "not positive run lengths summing",
    "cycle split in two": "breaks at triangle",
    "flipped orientation": "inverted",
    "moved input vertex": "input point 3 .* not kept unchanged",
    "incenter outside its triangle": "inverted",
    "vertex out of range": "references a vertex outside",
    "point not finite": "not finite",
    "midpoint off the segment": "constrained edge .* neither an output edge nor split at its midpoint",
    "output segment not an edge": "constrained edge .* not an edge of the mesh",
    "small angle": "below 0.5 x the input minimum",
}


#: the ``check`` each damage must be reported under (callers react to it, never to the text)
CHECKS = {
    "missing triangle": {"cycle", "domain"},
    "duplicated triangle": {"cycle", "overlap"},
    "rows swapped": {"cycle"},
    "run length off by one": {"input"},
    "cycle split in two": {"cycle"},
    "flipped orientation": {"orientation"},
    "moved input vertex": {"domain"},
    "incenter outside its triangle": {"orientation"},
    "vertex out of range": {"input"},
    "point not finite": {"input"},
    "midpoint off the segment": {"domain"},
    "output segment not an edge": {"domain"},
    "small angle": {"angle"},
}


#: Sparse mode splits no constrained edge on the loops plate: its midpoint case is incircle's.
DAMAGES = [(mode, what) for mode in MODES for what in sorted(CASES)
           if not (mode == "sparse" and what == "midpoint off the segment")]


@pytest.mark.parametrize("mode, what", DAMAGES)
def test_damaged_output_is_rejected(mode: str, what: str) -> None:
    m, h = made(mode)
    hammesh.verify(h, m)  # the intact output passes
    with pytest.raises(hammesh.VerificationError, match=CASES[what]) as caught:
        hammesh.verify(damaged(h, what, m), m)
    assert caught.value.check in CHECKS[what]
    assert caught.value.check in hammesh.VerificationError.CHECKS


# ---------------------------------------------------------------- point sets and polygons


@pytest.fixture(scope="module")
def point_set() -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(3)
    pts = np.r_[rng.random((40, 2)), [[0.0, 0.0], [0.5, 0.0], [1.0, 0.0]]]  # collinear hull points
    return pts, hammesh.pointset.hamiltonian_triangulation(pts, seed=1)


def test_point_set_certificate_does_not_use_the_constructions_hull(monkeypatch, point_set) -> None:
    from hammesh.pointset import validate

    pts, tri = point_set

    def no_hull(*a, **k):
        raise AssertionError("the certificate called the constructions' hull")

    monkeypatch.setattr(validate, "convex_hull", no_hull)
    order = "cycle" if len(tri) and (np.isin(tri[0], tri[-1]).sum() == 2) else "path"
    hammesh.pointset.verify_point_triangulation(pts, tri, order)


POINT_DAMAGES = {
    "rows swapped": (lambda p, t: (p, t[[3, 0, 1, 2, *range(4, len(t))]]), "breaks at triangle"),
    "flipped orientation": (lambda p, t: (p, np.r_[t[:5], t[5:6, ::-1], t[6:]]), "triangle 5 .* clockwise"),
    "missing triangle": (lambda p, t: (p, t[1:]), "triangles, but a triangulation of"),
    "duplicated triangle": (lambda p, t: (p, np.r_[t[:-1], t[:1]]), "used twice|boundary"),
    "moved point": (lambda p, t: (p + np.where(np.arange(len(p))[:, None] == 0, 0.3, 0.0), t), "clockwise|boundary|area|degenerate"),
    "vertex out of range": (lambda p, t: (p, np.where(t == t[0, 0], len(p), t)), "outside"),
}


@pytest.mark.parametrize("what", sorted(POINT_DAMAGES))
def test_damaged_point_set_triangulation_is_rejected(point_set, what: str) -> None:
    pts, tri = point_set
    damage, needle = POINT_DAMAGES[what]
    p, t = damage(pts.copy(), tri.copy())
    with pytest.raises(hammesh.VerificationError, match=needle):
        hammesh.pointset.verify_point_triangulation(p, t, "path")


SPIRAL = np.array([[0, 0], [6, 0], [6, 6], [1, 6], [1, 2], [4, 2], [4, 4], [3, 4], [3, 3], [2, 3], [2, 5], [5, 5],
                   [5, 1], [0, 1]], float)


def test_polygon_construction_bug_is_caught(monkeypatch) -> None:
    """Thm 2.1's solver returns its triangles with one row reversed: the public call raises."""
    from hammesh.polygon import hamiltonian

    sq = [[0, 0], [2, 0], [3, 1], [2, 2], [0, 2], [-1, 1]]
    assert hamiltonian.hamiltonian_triangulation(sq) is not None
    real = hamiltonian._solve

    def broken(poly):
        tri = real(poly)
        tri[1] = tri[1, ::-1]
        return tri

    monkeypatch.setattr(hamiltonian, "_solve", broken)
    with pytest.raises(hammesh.VerificationError, match="triangle 1 .* clockwise"):
        hamiltonian.hamiltonian_triangulation(sq)


def test_steiner_construction_bug_is_caught(monkeypatch) -> None:
    """Thm 2.3's construction moves a Steiner point outside the polygon."""
    from hammesh.polygon import steiner

    real = steiner._construct

    def broken(poly, pieces, diagonals, kind):
        pts, tri = real(poly, pieces, diagonals, kind)
        pts = pts.copy()
        pts[-1] += 100.0
        return pts, tri

    monkeypatch.setattr(steiner, "_construct", broken)
    with pytest.raises(hammesh.VerificationError, match="clockwise|boundary|area"):
        hammesh.polygon.steiner_hamiltonian(SPIRAL, "cycle")


POLYGON_DAMAGES = {
    "rows swapped": (lambda q, t: (q, t[[2, 0, 1, *range(3, len(t))]]), "breaks at triangle"),
    "flipped orientation": (lambda q, t: (q, np.r_[t[:1], t[1:2, ::-1], t[2:]]), "triangle 1 .* clockwise"),
    "missing triangle": (lambda q, t: (q, t[:-1]), "boundary of only one|not a vertex"),
    "duplicated triangle": (lambda q, t: (q, np.r_[t, t[:1]]), "used twice"),
    "moved polygon vertex": (lambda q, t: (q + np.where(np.arange(len(q))[:, None] == 2, 1e-9, 0.0), t), "do not start with the polygon"),
    "Steiner point moved": (lambda q, t: (q + np.where(np.arange(len(q))[:, None] == len(q) - 1, 100.0, 0.0), t), "clockwise|area|degenerate"),
}


@pytest.mark.parametrize("what", sorted(POLYGON_DAMAGES))
def test_damaged_polygon_triangulation_is_rejected(what: str) -> None:
    from hammesh.polygon.verify import verify_polygon_triangulation

    res = hammesh.polygon.steiner_hamiltonian_result(SPIRAL, "cycle")
    assert res.n_steiner >= 1
    verify_polygon_triangulation([SPIRAL], res.points, res.triangles, "cycle")  # intact: passes
    damage, needle = POLYGON_DAMAGES[what]
    q, t = damage(res.points.copy(), res.triangles.copy())
    with pytest.raises(hammesh.VerificationError, match=needle):
        verify_polygon_triangulation([SPIRAL], q, t, "cycle")
