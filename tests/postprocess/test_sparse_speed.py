"""Sparse mode's threaded and fused passes give the output of the one-thread passes, array for array.

Speed work must not change what sparse mode makes (issue 13: quality decides the
output, speed only how fast it is made). Each test runs the same input through the
one-thread path (``hammesh.threads.limit(1)``) and through the threaded one with its
row thresholds lowered so that a small mesh takes it, and compares every array.
"""

from __future__ import annotations

import numpy as np
import pytest

import hammesh
import hammesh.postprocess.cycle_cover as cycle_cover_module
from hammesh import threads
from hammesh.halfedge import half_edge_twins
from hammesh.halfedge import locality
from hammesh.postprocess import _sparse_kernels as sk
from hammesh.postprocess import sparse as sparse_module
from tests.helpers import bundled_domain, plate_with_loops, square

#: output arrays that must agree
FIELDS = ("points", "triangles", "components", "position", "parent", "kind", "segments", "segment_markers",
          "vertex_markers", "triangle_attributes")


def _domain(name: str) -> hammesh.Domain:
    if name == "loops":
        return plate_with_loops(3)
    if name == "regions":  # two regions: their shared edges are pinned
        v = square(0, 0, 2) + square(0.5, 0.5, 1)
        segs = [[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4]]
        return hammesh.Domain(vertices=v, segments=segs, regions=[[0.1, 0.1, 1, np.nan], [1, 1, 2, np.nan]])
    return bundled_domain(name)


def _small_mesh(name: str) -> hammesh.Mesh:
    dom = _domain(name)
    area = 0.0005 * float(np.ptp(dom.vertices[:, 0]) * np.ptp(dom.vertices[:, 1]))
    return hammesh.quality_mesh(dom, min_angle=25 if name == "la" else 30, max_area=area, isolate=False)


def _one_thread(m: hammesh.Mesh) -> hammesh.HamiltonianMesh:
    old = threads.limit(1)
    try:
        return hammesh.hamiltonian(m)
    finally:
        threads.limit(old)


def _report(h: hammesh.HamiltonianMesh) -> dict:
    return {k: v for k, v in h.report.items() if k not in ("seconds", "step_seconds", "step_cpu_seconds")}


@pytest.mark.parametrize("name", ["A", "la", "loops", "regions"])
def test_threaded_passes_give_the_one_thread_output(name: str, monkeypatch) -> None:
    m = _small_mesh(name)
    one = _one_thread(m)
    if threads.cores() < 2:
        pytest.skip("one core: the threaded passes cannot run")
    monkeypatch.setattr(threads, "THREAD_MIN_ROWS", 37)
    monkeypatch.setattr(sk, "WALK_TWO_ENDS_MIN_ROWS", 10)
    monkeypatch.setattr(sparse_module, "PLACE_MIN_ROWS", 3)  # (placing splits on both cores)
    monkeypatch.setattr(locality, "TABLE_MIN_CELLS", 4)  # (the Hilbert table on both cores)
    monkeypatch.setattr(sparse_module, "FACTS_MIN_ROWS", 5)  # (the new rows' angles on both cores)
    two = hammesh.hamiltonian(m)
    assert one.n_triangles > 500
    for f in FIELDS:
        np.testing.assert_array_equal(getattr(two, f), getattr(one, f), err_msg=f)
    assert _report(two) == _report(one)


def _linked_rows(h: hammesh.HamiltonianMesh, seed: int):
    """``h``'s rows shuffled, each with the bits of the edges its cycle crosses, and their twins."""
    tri = np.asarray(h.triangles, np.int64)
    k = len(tri)
    tw, _ = half_edge_twins(tri, h.n_points)
    ends = np.cumsum(h.components)
    nxt = np.arange(1, k + 1)
    nxt[ends - 1] = ends - h.components  # each run closes on itself
    g = tw.reshape(k, 3)
    rows = np.arange(k)[:, None]
    crossed = (g >= 0) & ((g // 3 == nxt[rows]) | (nxt[np.maximum(g, 0) // 3] == rows))
    link = (crossed * (1 << np.arange(3))).sum(axis=1).astype(np.uint8)
    perm = np.random.default_rng(seed).permutation(k)
    shuffled = tri[perm]
    return shuffled, link[perm], half_edge_twins(shuffled, h.n_points)[0]


def test_walk_from_both_ends_gives_the_one_thread_order_and_names_the_same_bad_row(monkeypatch) -> None:
    """Several cycles (two pieces, each its own cycle; the walk's first cycle is walked from both ends)."""
    if threads.cores() < 2:
        pytest.skip("one core: the walk from both ends does not run")
    dom = hammesh.Domain(vertices=square(0, 0, 1) + square(2, 0, 1),
                         segments=[[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4]])
    h = hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=30, max_area=0.002, isolate=False))
    assert len(h.components) == 2
    rows, link, tw = _linked_rows(h, 3)
    k = len(rows)
    none = np.zeros(0, np.int64)
    parent = np.arange(k)

    def walk(link):
        return sk.walk_links(np.zeros(0, np.int8), np.zeros(0, np.bool_), link, parent, none, tw, none, none)

    one = walk(link)
    monkeypatch.setattr(sk, "WALK_TWO_ENDS_MIN_ROWS", 10)
    two = walk(link)
    assert one.bad == two.bad == -1
    np.testing.assert_array_equal(two.order, one.order)
    np.testing.assert_array_equal(two.lengths, one.lengths)
    np.testing.assert_array_equal(two.low, one.low)
    assert sorted(two.lengths) == sorted(h.components)
    for r in (int(one.order[0]), int(one.order[k // 3]), int(one.order[-1])):
        broken = link.copy()
        broken[r] &= broken[r] - 1  # drop the row's lowest link bit
        monkeypatch.setattr(sk, "WALK_TWO_ENDS_MIN_ROWS", 10**9)
        want = walk(broken).bad
        monkeypatch.setattr(sk, "WALK_TWO_ENDS_MIN_ROWS", 10)
        assert want >= 0 and walk(broken).bad == want


def test_sparse_takes_its_big_arrays_from_the_reserve(monkeypatch) -> None:
    """A first call after ``quality_mesh`` finds the pages of its big arrays faulted already:
    it takes them from the reserve (``hammesh.pages``), within its share
    (``postprocess.RESERVE_TAKEN``), and the output is the one made without a reserve."""
    from hammesh import pages, postprocess

    m = hammesh.quality_mesh(hammesh.Domain.from_polygon(square(0, 0, 1)), min_angle=30, max_area=2e-4, isolate=False)
    plain = hammesh.hamiltonian(m)
    monkeypatch.setattr(pages, "RESERVE_MIN_ARRAY", 4096)  # (every array of a row each: a small mesh)
    assert m.n_triangles > 4096
    share = postprocess.RESERVE_TAKEN["sparse"] * m.n_triangles
    if not pages.reserve(2 * share):
        pytest.skip("no mremap here")
    taken = []
    real = pages._from_reserve

    def spy(nbytes):
        got = real(nbytes)
        if got is not None:
            taken.append(nbytes)
        return got

    monkeypatch.setattr(pages, "_from_reserve", spy)
    h = hammesh.hamiltonian(m)
    assert pages.reserved() == 0  # (the rest given back)
    # validation twins, angles, plan, walk, gather, pinned edges, stamps, claim: most of the share
    # (on this small mesh 73 %: arrays sized by the cycles, not the rows, stay below
    # RESERVE_MIN_ARRAY since session 13; at 2.4M triangles 93 % of the share is taken)
    assert 0.7 * share <= sum(taken) <= share
    for f in FIELDS:
        np.testing.assert_array_equal(getattr(h, f), getattr(plain, f), err_msg=f)


def test_without_a_reserve_the_second_thread_faults_one_beside_the_cover(monkeypatch) -> None:
    """A mesh not made by an isolated ``quality_mesh`` (read from a file): the pages of the
    arrays after the cover are faulted on the other thread while the cover runs
    (``postprocess.RESERVE_AFTER_COVER``); the output is the same."""
    import time

    from hammesh import pages, postprocess
    from hammesh.postprocess import sparse

    if threads.cores() < 2:
        pytest.skip("one core: no second thread")
    m = hammesh.quality_mesh(hammesh.Domain.from_polygon(square(0, 0, 1)), min_angle=30, max_area=2e-4, isolate=False)
    pages.release()
    plain = hammesh.hamiltonian(m)
    monkeypatch.setattr(pages, "RESERVE_MIN_ARRAY", 4096)
    monkeypatch.setattr(postprocess, "SIDE_RESERVE_MIN_TRIANGLES", 1000)
    real_cover, real_take = sparse.cycle_cover, pages._from_reserve
    taken = []

    def cover(*args, **kw):  # (the reserve is ready before the cover ends: no race in the test)
        t0 = time.monotonic()
        while not pages.reserved() and time.monotonic() < t0 + 10:
            time.sleep(0.001)
        return real_cover(*args, **kw)

    def take(nbytes):
        got = real_take(nbytes)
        if got is not None:
            taken.append(nbytes)
        return got

    monkeypatch.setattr(sparse, "cycle_cover", cover)
    monkeypatch.setattr(pages, "_from_reserve", take)
    h = hammesh.hamiltonian(m)
    assert pages.reserved() == 0
    assert 0.5 * postprocess.RESERVE_AFTER_COVER * m.n_triangles <= sum(taken)
    assert sum(taken) <= postprocess.RESERVE_AFTER_COVER * m.n_triangles + 16 * pages._PAGE
    for f in FIELDS:
        np.testing.assert_array_equal(getattr(h, f), getattr(plain, f), err_msg=f)


@pytest.mark.parametrize("name", ["loops", "regions", "la"])
def test_renumbered_input_maps_back(name: str, monkeypatch) -> None:
    """From ``sparse.LOCAL_MIN_TRIANGLES`` the input is renumbered along a Hilbert curve
    (``hammesh.halfedge.renumber_local``); the output (certified) must speak of the
    caller's mesh: its points first and unmoved, kept rows equal to their parents,
    every row inside its parent's region (attributes), split segments on the input's."""
    from hammesh.postprocess import sparse

    dom = _domain(name)
    area = 0.0005 * float(np.ptp(dom.vertices[:, 0]) * np.ptp(dom.vertices[:, 1]))
    m = hammesh.quality_mesh(dom, min_angle=25 if name == "la" else 30, max_area=area, isolate=False)
    monkeypatch.setattr(sparse, "LOCAL_MIN_TRIANGLES", 10**12)
    plain = hammesh.hamiltonian(m)
    monkeypatch.setattr(sparse, "LOCAL_MIN_TRIANGLES", 100)
    h = hammesh.hamiltonian(m)  # (certified, or it raises)
    assert "locality" in h.report["step_seconds"] and "locality" not in plain.report["step_seconds"]
    n = m.n_points
    np.testing.assert_array_equal(h.points[:n], m.points)
    kept = h.kind == 3
    np.testing.assert_array_equal(np.sort(h.triangles[kept], axis=1), np.sort(m.triangles[h.parent[kept]], axis=1))
    np.testing.assert_array_equal(h.triangle_attributes, m.triangle_attributes[h.parent])
    if name == "regions":  # every row in its parent's region: the inner square is region 2
        c = h.points[h.triangles].mean(axis=1)
        inner = ((c > 0.5) & (c < 1.5)).all(axis=1)
        np.testing.assert_array_equal(h.triangle_attributes[:, 0] == 2, inner)
        assert inner.any() and not inner.all()
    # constrained edges: every output segment lies on an input segment with its marker
    seg_in = {tuple(sorted(s)): k for s, k in zip(m.segments.tolist(), m.segment_markers.tolist())}
    p = h.points
    for (a, b), k in zip(h.segments.tolist(), h.segment_markers.tolist()):
        hit = [s for s in seg_in if _on_segment(p, a, b, s)]
        assert hit and seg_in[hit[0]] == k
    np.testing.assert_array_equal(h.vertex_markers[:n], plain.vertex_markers[:n])
    # the same construction, other numbering: counts of the same order
    assert abs(h.report["steiner_points"] - plain.report["steiner_points"]) <= 0.5 * plain.report["steiner_points"] + 5


def _on_segment(p: np.ndarray, a: int, b: int, s: tuple[int, int]) -> bool:
    """Output edge ``a b`` lies on input segment ``s`` (both ends on it, within rounding)."""
    u, v = p[s[0]], p[s[1]]
    d = v - u
    L2 = float(d @ d)
    for q in (p[a], p[b]):
        t = float((q - u) @ d) / L2
        if not (-1e-9 <= t <= 1 + 1e-9) or abs(d[0] * (q - u)[1] - d[1] * (q - u)[0]) > 1e-9 * L2:
            return False
    return True


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_kept_radius_ratio_is_the_worst_of_every_kept_row(seed: int, monkeypatch) -> None:
    """``sparse.kept_radius_ratio`` measures only the kept rows whose smallest angle allows a
    ratio above its sample's worst: the same maximum as measuring them all, whichever rows
    are kept (the worst ones too, or not)."""
    from hammesh.postprocess import sparse

    dom = bundled_domain("A") if seed == 2 else hammesh.Domain.from_polygon(square(0, 0, 1))
    m = hammesh.quality_mesh(dom, min_angle=(25, 30, 20)[seed], max_area=0.001 if seed < 2 else 0.5, isolate=False)
    lo, _, worst, row = sparse.triangle_facts(m.points, m.triangles)
    rng = np.random.default_rng(seed)
    monkeypatch.setattr(sparse, "KEPT_RATIO_STRIDE", 7)
    for trial in range(40):
        kind = np.where(rng.random(m.n_triangles) < rng.uniform(0.05, 1.0), 3, 0).astype(np.int8)
        if trial % 3 == 0:
            kind[row] = 0  # the input's worst joined: the case that measures
        kept = kind == 3
        want = sparse.triangle_facts(m.points, m.triangles[kept])[2] if kept.any() else 1.0
        assert sparse.kept_radius_ratio(m.points, m.triangles, kind, np.arange(m.n_triangles), lo) == want


@pytest.mark.parametrize("name", ["la", "regions"])
def test_ring_rows_appended_in_place_give_the_copied_output(name: str, monkeypatch) -> None:
    """With room after the per-row arrays (``sparse.ROOM_ROWS``, renumbered input) the
    ring fans, ring joins and Steiner points are appended in place; with none
    (``ROOM_ROWS = 0``, ``STEINER_ROOM_DIVISOR`` huge) every growth copies, as before
    session 11. Same output, array for array, and the room is really used."""
    from hammesh.postprocess import sparse

    dom = _domain(name)
    area = 0.0005 * float(np.ptp(dom.vertices[:, 0]) * np.ptp(dom.vertices[:, 1]))
    m = hammesh.quality_mesh(dom, min_angle=25 if name == "la" else 30, max_area=area, isolate=False)
    monkeypatch.setattr(sparse, "LOCAL_MIN_TRIANGLES", 100)
    monkeypatch.setattr(cycle_cover_module, "RECOLOUR_BELOW", 0)  # (no session-14 re-colouring: it leaves nothing here)
    grown = []
    real = sparse._longer

    def spy(a, extra, fill=None, spare=0):
        out = real(a, extra, fill, spare)
        grown.append(bool(len(a)) and np.shares_memory(out, a))
        return out

    monkeypatch.setattr(sparse, "_longer", spy)
    h = hammesh.hamiltonian(m)
    in_place = sum(grown)
    assert h.report["ring_joins"] + h.report["ring_fans"] > 0 or name == "regions"
    assert in_place >= 1  # (the Steiner points at least; every ring row's arrays where rings are)
    monkeypatch.setattr(sparse, "ROOM_ROWS", 0)
    monkeypatch.setattr(sparse, "STEINER_ROOM_DIVISOR", 10**12)
    grown.clear()
    copied = hammesh.hamiltonian(m)
    assert sum(grown) < in_place
    for f in FIELDS:
        np.testing.assert_array_equal(getattr(h, f), getattr(copied, f), err_msg=f)
    assert _report(h) == _report(copied)


def test_room_outlives_the_views_that_grew_into_it() -> None:
    """``sparse._keep_room``: a view ``_longer`` grew in place is grown again in place
    (its owner is a new view object), and the death of an older view does not drop the
    newer one's entry (the weak reference's callback removes only its own)."""
    import gc

    from hammesh.postprocess import sparse

    buf = np.arange(100, dtype=np.int64)
    a = sparse._with_room(buf, 10)
    b = sparse._longer(a, 5, -1)
    assert np.shares_memory(a, b) and b.tolist() == list(range(10)) + [-1] * 5
    c = sparse._longer(b, 5, -2)
    assert np.shares_memory(c, buf) and c[10:].tolist() == [-1] * 5 + [-2] * 5
    del b
    gc.collect()
    d = sparse._longer(c, 80, 0)  # (c's entry survived b's death; 100 rows: still in place)
    assert np.shares_memory(d, buf) and len(d) == 100
    e = sparse._longer(d, 1)  # no room left: a copy
    assert not np.shares_memory(e, buf) and np.array_equal(e[:100], d)


def test_link_table_flags_rows_not_linked_back() -> None:
    """``_sparse_kernels._link_ends_into``: each row's two links (``4 g + j``), -1 for a row
    with other than two links or one whose other side does not link back."""
    # a fan of four new rows around a centre, each crossing its two spokes (as
    # ``load_output_kernels``): one cycle
    k = 4
    r = np.arange(k)
    tw = np.stack([np.full(k, -1), 3 * ((r + 1) % k) + 2, 3 * ((r - 1) % k) + 1], axis=1).reshape(-1)
    none = np.zeros(0, np.int64)
    link = np.full(k, 6, np.uint8)
    ends = np.empty(2 * k, np.int64)
    sk._link_ends_into(np.zeros(0, np.int8), np.zeros(0, np.bool_), link, none, tw, none, none, 0, k, ends)
    for x in range(k):
        assert sorted(ends[2 * x: 2 * x + 2] >> 2) == sorted([tw[3 * x + 1], tw[3 * x + 2]])
        assert (ends[2 * x: 2 * x + 2] & 3).tolist() == [1, 2]
    link[2] = 2  # row 2 crosses one spoke only: it and row 1 (whose link to 2 is not returned) are bad
    sk._link_ends_into(np.zeros(0, np.int8), np.zeros(0, np.bool_), link, none, tw, none, none, 0, k, ends)
    bad = [x for x in range(k) if ends[2 * x] < 0]
    assert 2 in bad and len(bad) == 2
    walk = sk.walk_links(np.zeros(0, np.int8), np.zeros(0, np.bool_), link, r.copy(), none, tw, none, none)
    assert walk.bad in bad


@pytest.mark.parametrize("name", ["A", "face"])
def test_every_midpoint_bridge_shares_one_midpoint(name: str) -> None:
    """``emit``: a midpoint bridge's two split triangles use one midpoint (found for the
    second by binary search over the bridges' midpoint slots): every midpoint vertex lies
    in exactly four rows, two on each side, and no edge is split twice."""
    from hammesh.halfedge import prepare_mesh
    from hammesh.postprocess import sparse

    m = hammesh.quality_mesh(_domain(name), min_angle=30, max_area=None)
    clean, he, con = prepare_mesh(m)
    for kw in ({"use_cover": False, "flip_bridges": False}, {"flip_bridges": False}):
        kw["improve"] = False  # (improvement flips may give a midpoint a fifth row)
        r = sparse.sparse_cycles(clean.points, clean.triangles, he.twin, con, clean.info["validated"]["min_angle"],
                                 **kw)
        assert len(r.mid_a) > 0
        first_mid = len(r.points) - len(r.mid_a)
        used = np.bincount(r.triangles.ravel(), minlength=len(r.points))[first_mid:]
        assert (used == 4).all()
        edges = np.sort(np.stack([r.mid_a, r.mid_b], axis=1), axis=1)
        assert len(np.unique(edges, axis=0)) == len(edges)


def _union_polygon_by_dict(tri, tw, con, members):
    """The ring group's union polygon as ``sparse._union_polygon`` walked it before its
    kernel (session 12): a dictionary from each outer edge's start to its end."""
    ms = set(members)
    nxt: dict = {}
    for x in members:
        for k in range(3):
            h = 3 * x + k
            g = tw[h]
            if g >= 0 and g // 3 in ms:
                if con[h]:
                    return None
                continue
            a = int(tri[x, k])
            if a in nxt:
                return None
            nxt[a] = (int(tri[x, (k + 1) % 3]), h)
    if len(nxt) != len(members) + 2:
        return None
    start = next(iter(nxt))
    poly, hes, v = [], [], start
    for _ in range(len(nxt)):
        if v not in nxt:
            return None
        poly.append(v)
        v, h = nxt[v]
        hes.append(h)
    return (poly, hes) if v == start else None


@pytest.mark.parametrize("name", ["A", "loops", "regions"])
def test_union_polygon_kernel_walks_as_the_dictionary_did(name: str) -> None:
    from hammesh.halfedge import prepare_mesh
    from hammesh.postprocess import sparse

    dom = _domain(name)
    area = 0.0005 * float(np.ptp(dom.vertices[:, 0]) * np.ptp(dom.vertices[:, 1]))
    clean, he, con = prepare_mesh(hammesh.quality_mesh(dom, min_angle=30, max_area=area, isolate=False))
    tri, tw = clean.triangles, he.twin
    rng = np.random.default_rng(7)
    # groups grown across edges (pinned ones too: those must give None), 2 to 5 triangles,
    # and some that are not connected or hold a triangle twice
    groups = []
    for t in rng.choice(len(tri), min(300, len(tri)), replace=False).tolist():
        g = [t]
        for _ in range(int(rng.integers(1, 5))):
            x = g[int(rng.integers(len(g)))]
            nb = [int(h // 3) for h in tw[3 * x: 3 * x + 3] if h >= 0 and h // 3 not in g]
            if nb:
                g.append(nb[int(rng.integers(len(nb)))])
        groups.append(g)
    groups += [[0, len(tri) - 1], [5, 5], [1, 2, 3]]
    n_some = 0
    for g in groups:
        want = _union_polygon_by_dict(tri, tw, con, g)
        got = sparse._union_polygon(tri, tw, con, np.asarray(g, np.int64))
        assert got == want, g
        n_some += want is not None
    assert 50 < n_some < len(groups)  # (both answers seen)


def test_ring_fan_point_places_as_the_numpy_starts_did() -> None:
    from hammesh.halfedge import prepare_mesh
    from hammesh.postprocess import _join_kernels, sparse

    dom = _domain("A")
    clean, he, con = prepare_mesh(hammesh.quality_mesh(dom, min_angle=30, max_area=0.5, isolate=False))
    pts, tri, tw = clean.points, clean.triangles, he.twin
    amin = sparse.triangle_angles(pts, tri)[0]
    n = refused = 0
    for h in np.flatnonzero(tw > np.arange(len(tw)))[:200].tolist():
        members = [h // 3, int(tw[h] // 3)]
        pp = sparse._union_polygon(tri, tw, con, np.asarray(members))
        if pp is None:
            continue
        poly = np.asarray(pp[0], np.int64)
        for keep in (0.0, 0.9):
            lo = 0.2
            lo_g = lo if keep == 0.0 else max(lo, keep * float(amin[members].min()))
            starts = pts[tri[members]].sum(axis=1) / 3.0
            step = 0.25 * np.sqrt(float(((pts[poly] - starts[0]) ** 2).sum(axis=1).min()))
            want = _join_kernels.place_fan(pts, poly, len(poly), starts, len(starts), lo_g, 2.5, step, 8)
            got = sk.ring_fan_point(pts, tri, np.asarray(members), poly, len(poly), amin, keep, lo, 2.5, 8)
            assert got[5] == lo_g
            if got[2] == -np.inf and want[2] > -np.inf:
                # refused without a search (session 16): no fan point keeps lo_g there,
                # so the search's point is one the caller refuses too
                assert want[3] < lo_g
                refused += 1
            else:
                np.testing.assert_allclose(np.asarray(got[:5], float), np.asarray(want, float), rtol=0, atol=1e-12)  # corner_atan2 vs atan2: last bits
            # the caller's floor: above half the smallest corner, never a fan (no search)
            half = _join_kernels.half_smallest_corner(pts, poly, len(poly))
            over = sk.ring_fan_point(pts, tri, np.asarray(members), poly, len(poly), amin, keep, lo, 2.5, 8,
                                     1.01 * half)
            assert over[2] == -np.inf
            if want[2] > -np.inf:
                assert want[3] <= half + 1e-12
            n += 1
    assert n > 20 and refused < n


@pytest.mark.parametrize("name", ["A", "regions"])
def test_new_row_twins_packed_sort_matches_its_argsort_fallback(name: str, monkeypatch) -> None:
    from hammesh.postprocess import sparse

    seen = []
    real = sk.new_row_twins

    def spy(out, tri, tw, status, n_points, changed):
        got = real(out, tri, tw, status, n_points, changed)
        # n_points this large needs more than 62 bits with the index: the argsort path
        big = real(out, tri, tw, status, 1 << 31, changed)
        seen.append(len(out))
        for a, b in zip(got[:3], big[:3]):
            np.testing.assert_array_equal(a, b)
        assert got[3] == big[3] == -1
        return got

    monkeypatch.setattr(sparse._k, "new_row_twins", spy)
    dom = _domain(name)
    area = 0.001 * float(np.ptp(dom.vertices[:, 0]) * np.ptp(dom.vertices[:, 1]))
    hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=30, max_area=area, isolate=False))
    assert seen and seen[0] > 10


@pytest.mark.parametrize("name", ["la", "regions"])
def test_plan_steps_are_what_a_scan_finds(name: str, monkeypatch) -> None:
    """``PlanSteps`` left after the steps that undo joins and bridges = a fresh scan."""
    from hammesh.postprocess import sparse

    checked = []
    # (positions of join, slot (None: not an argument) and steps_at in each step's arguments)
    where = {"_place_taken": (2, None, -2), "_alternating_merges": (4, 10, -1), "_ring_joins": (9, 15, -1)}
    for fn, (i_join, i_slot, i_steps) in where.items():
        def spy(*a, _real=getattr(sparse, fn), _at=(i_join, i_slot, i_steps), **k):
            join, steps_at = a[_at[0]], a[_at[2]]
            np.testing.assert_array_equal(steps_at.joined(join), np.flatnonzero(join >= 0))
            if _at[1] is not None:
                slot = a[_at[1]]
                np.testing.assert_array_equal(steps_at.slotted(slot), np.flatnonzero(slot != sparse._k.PLAIN))
            checked.append(_real.__name__)
            return _real(*a, **k)

        monkeypatch.setattr(sparse, fn, spy)
    dom = _domain(name)
    area = 0.0005 * float(np.ptp(dom.vertices[:, 0]) * np.ptp(dom.vertices[:, 1]))
    h = hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=25 if name == "la" else 30, max_area=area,
                                                 isolate=False))
    assert set(checked) == {"_alternating_merges", "_ring_joins", "_place_taken"}
    assert h.report["alternating_merges"] + h.report["ring_joins"] > 0  # (steps were undone)


@pytest.mark.parametrize("name", ["la", "square_circle_hole"])
def test_cover_swap_tests_on_two_threads_take_the_one_thread_swaps(name: str, monkeypatch) -> None:
    # (the walks' path, ``ALT_POSITIONS_BELOW`` = 0, as on big meshes; two threads share
    # each task's tests there: ``sparse._SwapTests``)
    monkeypatch.setattr(cycle_cover_module, "RECOLOUR_BELOW", 0)  # (no session-14 re-colouring: it leaves no swaps here)
    monkeypatch.setattr(sparse_module, "ALT_POSITIONS_BELOW", 0)
    m = _small_mesh(name)
    one = _one_thread(m)
    if threads.cores() < 2:
        pytest.skip("one core: the tests run in the caller's thread")
    shared, real = [], sparse_module._SwapTests.__init__

    def counted(self, *a, **k):
        shared.append(self)
        real(self, *a, **k)

    monkeypatch.setattr(sparse_module._SwapTests, "__init__", counted)
    two = hammesh.hamiltonian(m)
    assert one.report["alternating_merges"] >= 3 and shared  # (swaps taken, the shared tests ran)
    assert _report(two) == _report(one)
    for f in FIELDS:
        np.testing.assert_array_equal(getattr(two, f), getattr(one, f), err_msg=f)


def test_an_error_in_the_other_threads_swap_test_reaches_the_caller(monkeypatch) -> None:
    import threading

    if threads.cores() < 2:
        pytest.skip("one core: the tests run in the caller's thread")
    monkeypatch.setattr(cycle_cover_module, "RECOLOUR_BELOW", 0)  # (no session-14 re-colouring: it leaves no swaps here)
    monkeypatch.setattr(sparse_module, "ALT_POSITIONS_BELOW", 0)
    m = _small_mesh("la")
    caller, real = threading.get_ident(), sk.swap_outcome_of

    def fails_off_the_caller(*a):
        if threading.get_ident() != caller:
            raise RuntimeError("test failed on the other thread")
        return real(*a)

    monkeypatch.setattr(sk, "swap_outcome_of", fails_off_the_caller)
    got: list = []

    def run() -> None:
        nonlocal caller
        caller = threading.get_ident()
        try:
            hammesh.hamiltonian(m)
        except RuntimeError as exc:
            got.append(exc)

    t = threading.Thread(target=run, daemon=True)
    t.start()
    t.join(120)
    assert not t.is_alive(), "the caller waits for ever on the other thread's answer"
    assert got and "other thread" in str(got[0])


def test_renumbered_input_refuses_bad_segments_and_keeps_own_cycles_alike(monkeypatch) -> None:
    """With the half-edges matched in the renumbered order (``sparse.LOCAL_MIN_TRIANGLES``
    reached): a segment off the mesh is named as without renumbering, and hammesh's own
    output read back is kept as it is (its pairing taken in the input's order)."""
    from dataclasses import replace

    from hammesh.postprocess import sparse

    dom = _domain("loops")
    area = 0.0005 * float(np.ptp(dom.vertices[:, 0]) * np.ptp(dom.vertices[:, 1]))
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=area, isolate=False)
    a, b = int(m.triangles[0, 0]), int(m.triangles[-1, 1])
    assert not ((m.triangles == a).any(axis=1) & (m.triangles == b).any(axis=1)).any()
    bad = replace(m, segments=np.concatenate([m.segments, [[a, b]]]),
                  segment_markers=np.concatenate([m.segment_markers, [1]]))
    said = []
    for least in (10**12, 100):
        monkeypatch.setattr(sparse, "LOCAL_MIN_TRIANGLES", least)
        with pytest.raises(hammesh.InvalidMeshError) as err:
            hammesh.hamiltonian(bad)
        said.append(str(err.value))
    assert said[0] == said[1] and f"[{a}, {b}] is not an edge" in said[0]
    h = hammesh.hamiltonian(m)
    own = hammesh.Mesh(h.points, h.triangles, segments=h.segments, segment_markers=h.segment_markers)
    again = hammesh.hamiltonian(own)
    assert again.report["kept_input_cycle"] and again.report["steiner_points"] == 0
    np.testing.assert_array_equal(again.triangles, own.triangles)


@pytest.mark.parametrize("before_plan, before_placing", [(True, True), (True, False), (False, False)])
def test_side_work_starts_once_as_the_plan_starts_when_pages_are_reserved(before_plan: bool, before_placing: bool,
                                                                          monkeypatch) -> None:
    """With a page reserve, ``sparse_cycles``' ``beside_cover`` (the certificate's look at
    the input) is called exactly once: as the splits are placed (``SIDE_BEFORE_PLACING``,
    session 21: their sorts and open candidates leave the other core idle, and it is
    then mostly done before the plan's swap tests take two threads), else as the plan
    starts (``SIDE_BEFORE_PLAN``, session 19: the plan's Python leaves the other core
    idle), else after the output rows (the improvement's start); without a reserve, as
    the cover starts."""
    from hammesh.halfedge import prepare_mesh
    from hammesh.postprocess import sparse

    m = hammesh.quality_mesh(bundled_domain("face"), min_angle=30, max_area=None)
    clean, he, is_con = prepare_mesh(m)
    amin = float(clean.info["validated"]["min_angle"])
    log: list[str] = []
    for name, tag in (("open_candidates", "place"), ("plan_merges", "plan"), ("emit", "rows")):
        real = getattr(sparse._k, name)
        monkeypatch.setattr(sparse._k, name, lambda *a, _r=real, _t=tag, **k: (log.append(_t), _r(*a, **k))[1])
    real_cover = sparse.cycle_cover
    monkeypatch.setattr(sparse, "cycle_cover", lambda *a, **k: (log.append("cover"), real_cover(*a, **k))[1])
    monkeypatch.setattr(sparse, "SIDE_BEFORE_PLAN", before_plan)
    monkeypatch.setattr(sparse, "SIDE_BEFORE_PLACING", before_placing)
    late = (["cover", "side", "place", "plan", "rows"] if before_placing else
            ["cover", "place", "side", "plan", "rows"] if before_plan else ["cover", "place", "plan", "rows", "side"])
    for reserve, want in ((1, late), (0, ["side", "cover", "place", "plan", "rows"])):
        log.clear()
        monkeypatch.setattr(sparse, "reserved", lambda r=reserve: r)
        sparse.sparse_cycles(clean.points, clean.triangles, he.twin, is_con, amin,
                             beside_cover=lambda: log.append("side"))
        assert [x for i, x in enumerate(log) if x not in log[:i]] == want, log
        assert log.count("side") == 1


def test_rows_local_hint_skips_the_renumbering(monkeypatch) -> None:
    """``info["rows_local"]`` (``hammesh.parallel``'s lattice tiles set it): sparse mode
    does not renumber the rows however many they are, and the output is the one of a
    mesh below ``LOCAL_MIN_TRIANGLES`` (same rows, same cycle), certified; without the
    hint the same mesh is renumbered."""
    from dataclasses import replace

    from hammesh.postprocess import sparse

    dom = _domain("loops")
    area = 0.0005 * float(np.ptp(dom.vertices[:, 0]) * np.ptp(dom.vertices[:, 1]))
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=area, isolate=False)
    monkeypatch.setattr(sparse, "LOCAL_MIN_TRIANGLES", 10**12)
    plain = hammesh.hamiltonian(m)
    monkeypatch.setattr(sparse, "LOCAL_MIN_TRIANGLES", 100)
    renumbered = hammesh.hamiltonian(m)
    hinted = hammesh.hamiltonian(replace(m, info={**m.info, "rows_local": True}))
    assert "locality" in renumbered.report["step_seconds"]
    assert "locality" not in hinted.report["step_seconds"] and hinted.report["verified"]
    np.testing.assert_array_equal(hinted.triangles, plain.triangles)
    np.testing.assert_array_equal(hinted.points, plain.points)
    assert sparse.renumbers(10**6, 2, {}) and not sparse.renumbers(10**6, 2, {"rows_local": True})
    assert not sparse.renumbers(10**6, 3, {}) and not sparse.renumbers(10, 2, {})


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_kept_ratio_begun_before_the_swaps_is_the_final_rows_ratio(seed: int, monkeypatch) -> None:
    """``kept_ratio_start`` read while rows are still swapped away (kind 3 -> 4, rows
    rewritten) and ``kept_ratio_finish`` on the final rows give ``kept_radius_ratio`` of
    the final rows: by the rows read then if no sampled row was swapped, else anew."""
    from hammesh.postprocess import sparse

    dom = bundled_domain("A") if seed == 2 else hammesh.Domain.from_polygon(square(0, 0, 1))
    m = hammesh.quality_mesh(dom, min_angle=(25, 30, 20)[seed], max_area=0.001 if seed < 2 else 0.5, isolate=False)
    lo, _, _, _ = sparse.triangle_facts(m.points, m.triangles)
    rng = np.random.default_rng(seed)
    monkeypatch.setattr(sparse, "KEPT_RATIO_STRIDE", 7)
    parent = np.arange(m.n_triangles)
    ways = set()
    for trial in range(40):
        kind = np.where(rng.random(m.n_triangles) < rng.uniform(0.05, 1.0), 3, 0).astype(np.int8)
        rows = m.triangles.copy()
        start = sparse.kept_ratio_start(m.points, rows, kind, parent, lo)
        # the improvement: some kept rows swapped (other points, kind 4); half the
        # trials spare the sampled rows
        kept = np.flatnonzero(kind == 3)
        gone = kept[rng.random(len(kept)) < 0.2]
        if trial % 2:
            gone = gone[gone % 7 != 0]
        kind[gone] = 4
        rows[gone] = np.roll(rows[gone], 1, axis=0)
        sampled_swapped = bool((gone % 7 == 0).any())
        ways.add(sampled_swapped)
        want = sparse.kept_radius_ratio(m.points, rows, kind, parent, lo)
        assert sparse.kept_ratio_finish(m.points, rows, kind, parent, lo, start) == want
    assert ways == {True, False}
