"""Thm 2.4 post-process: properties over a corpus of domains and random inputs."""

from __future__ import annotations

import numpy as np
import pytest
import triangle
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial import Delaunay

import hammesh
from hammesh.postprocess import incenters
from tests.helpers import (
    angles_deg,
    assert_certificate,
    bundled_domain,
    dual_pieces,
    hull_area,
    plate_with_loops,
    square,
    star_pslg,
)

# Triangle's bundled planar domains (box and greenland are tested on their own)
BUNDLED = ["A", "la", "face", "double_hex", "double_hex2", "double_hex3", "square_circle_hole", "spiral", "dots", "ell"]


@pytest.mark.parametrize("name", BUNDLED)
def test_bundled_domains(name: str) -> None:
    try:
        dom = bundled_domain(name)
    except hammesh.InvalidDomainError as exc:  # a bundled file our validator rejects
        pytest.skip(f"{name}: {exc}")
    m = hammesh.quality_mesh(dom, min_angle=25, max_area=hull_area(dom) / 2000)
    h = hammesh.hamiltonian(m, mode="incircle")
    assert h.report["verified"] is True
    assert_certificate(m, h)


def test_box_hole_eats_everything_is_a_clear_error() -> None:
    # box.poly has a hole point but no closed outer boundary: Triangle eats it all
    with pytest.raises(hammesh.MeshingError, match="no triangles"):
        hammesh.quality_mesh(bundled_domain("box"), min_angle=20)


def test_greenland_file_mesh() -> None:
    # Triangle's bundled greenland.node/.ele: 64k triangles of a real coastline
    d = triangle.get_data("greenland")
    m = hammesh.Mesh(points=d["vertices"], triangles=d["triangles"].astype(np.int64))
    h = hammesh.hamiltonian(m, mode="incircle")
    assert_certificate(m, h)


def test_incenter_is_equidistant_from_sides() -> None:
    rng = np.random.default_rng(1)
    pts = rng.random((3, 2))
    tri = np.array([[0, 1, 2]])
    c = incenters(pts, tri)[0]
    d = []
    for a, b in ((0, 1), (1, 2), (2, 0)):
        e = pts[b] - pts[a]
        w = c - pts[a]
        d.append(abs(e[0] * w[1] - e[1] * w[0]) / np.linalg.norm(e))
    assert np.allclose(d, d[0])


@pytest.mark.parametrize("n_loops", [0, 1, 3])
def test_midpoints_one_per_separated_region(n_loops: int) -> None:
    m = hammesh.quality_mesh(plate_with_loops(n_loops), min_angle=30, max_area=0.005)
    h = hammesh.hamiltonian(m, mode="incircle")
    regions = dual_pieces(m.triangles, m.segments)
    pieces = dual_pieces(m.triangles)
    assert regions == n_loops + 1
    assert h.report["midpoints"] == regions - pieces == n_loops
    assert (h.kind == 2).sum() == 4 * n_loops
    assert_certificate(m, h)
    # every input constrained edge survives: as an edge, or as two halves at its midpoint
    out_edges = {tuple(sorted(e)) for t in h.triangles.tolist() for e in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
    for a, b in m.segments.tolist():
        if tuple(sorted((a, b))) not in out_edges:
            mid = 0.5 * (m.points[a] + m.points[b])
            c = int(np.flatnonzero((h.points == mid).all(axis=1))[0])
            assert tuple(sorted((a, c))) in out_edges and tuple(sorted((c, b))) in out_edges


def test_constrained_edges_are_never_flipped() -> None:
    m = hammesh.quality_mesh(plate_with_loops(2), min_angle=30, max_area=0.01)
    h = hammesh.hamiltonian(m, mode="incircle")
    out_edges = {tuple(sorted(e)) for t in h.triangles.tolist() for e in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
    for a, b in h.segments.tolist():
        assert tuple(sorted((a, b))) in out_edges


def test_crack_needs_no_midpoint() -> None:
    # a dangling crack from the boundary into the interior: one region, no midpoint
    v = square(0, 0, 1) + [[0.5, 0.0], [0.5, 0.6]]
    segs = [[0, 4], [4, 1], [1, 2], [2, 3], [3, 0], [4, 5]]
    m = hammesh.quality_mesh(hammesh.Domain(vertices=v, segments=segs), min_angle=28, max_area=0.01)
    h = hammesh.hamiltonian(m, mode="incircle")
    assert h.report["midpoints"] == 0
    assert_certificate(m, h)


def test_disconnected_pieces_give_one_cycle_each() -> None:
    v = square(0, 0, 1) + square(2, 0, 1) + square(4, 0.5, 0.5)
    segs = []
    for b in (0, 4, 8):
        segs += [[b, b + 1], [b + 1, b + 2], [b + 2, b + 3], [b + 3, b]]
    dom = hammesh.Domain(vertices=v, segments=segs, holes=[[1.5, 0.5], [3.5, 0.5]])
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=0.02)
    h = hammesh.hamiltonian(m, mode="incircle")
    assert len(h.components) == 3
    assert h.report["components"] == h.components.tolist()
    assert (h.position[np.cumsum(h.components) - h.components] == 0).all()
    assert_certificate(m, h)


def test_sharp_input_angle_bound_still_holds() -> None:
    # a 5-degree wedge: Triangle cannot improve the tip, the bound is relative to it
    ang = np.radians(5)
    v = [[0, 0], [1, 0], [np.cos(ang), np.sin(ang)]]
    m = hammesh.quality_mesh(hammesh.Domain(vertices=v, segments=[[0, 1], [1, 2], [2, 0]]), min_angle=20, max_area=0.001)
    h = hammesh.hamiltonian(m, mode="incircle")
    assert angles_deg(m.points, m.triangles).min() < 6
    assert_certificate(m, h)


def test_attributes_follow_parent() -> None:
    v = square(0, 0, 2) + square(0.5, 0.5, 1)
    segs = [[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4]]
    dom = hammesh.Domain(vertices=v, segments=segs, regions=[[0.1, 0.1, 1, np.nan], [1, 1, 2, np.nan]])
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=0.02)
    h = hammesh.hamiltonian(m, mode="incircle")
    np.testing.assert_array_equal(h.triangle_attributes, m.triangle_attributes[h.parent])
    inside = (np.abs(h.points[h.triangles].mean(axis=1) - 1.0) < 0.5).all(axis=1)
    assert (h.triangle_attributes[inside, 0] == 2).all()
    assert (h.triangle_attributes[~inside, 0] == 1).all()


def test_works_on_any_file_mesh_either_orientation() -> None:
    rng = np.random.default_rng(7)
    pts = rng.random((300, 2))
    tri = Delaunay(pts).simplices.astype(np.int64)
    tri[::2] = tri[::2, ::-1]  # mixed orientation, as files may have
    m = hammesh.Mesh(points=pts, triangles=tri)
    h = hammesh.hamiltonian(m, mode="incircle")
    ccw = hammesh.Mesh(points=pts, triangles=np.where(np.isin(np.arange(len(tri)), np.arange(0, len(tri), 2))[:, None], tri[:, ::-1], tri))
    assert_certificate(ccw, h)


@given(dom=star_pslg(), min_angle=st.floats(0, 30), area=st.sampled_from([None, 0.05, 0.01]))
def test_random_pslg_certificate(dom: hammesh.Domain, min_angle: float, area: float | None) -> None:
    m = hammesh.quality_mesh(dom, min_angle=min_angle, max_area=area, isolate=False)
    h = hammesh.hamiltonian(m, mode="incircle")
    assert_certificate(m, h)


@pytest.mark.slow
def test_large_mesh_certificate() -> None:
    dom = plate_with_loops(2)
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=2e-5)
    h = hammesh.hamiltonian(m, mode="incircle")
    assert h.report["verified"] and h.n_triangles > 100_000
    assert h.report["midpoints"] == 2


@given(dom=star_pslg(), area=st.sampled_from([0.05, 0.01]))
def test_claimed_pairing_is_the_true_adjacency(dom: hammesh.Domain, area: float) -> None:
    """The construction's own half-edge pairing (which the certificate checks instead
    of recomputing) equals an independent bucket matching of the output."""
    from hammesh.halfedge import prepare_mesh
    from hammesh.postprocess.incircle import incircle_hamiltonian
    from hammesh.verify import _kernels

    m = hammesh.quality_mesh(dom, min_angle=25, max_area=area, isolate=False)
    clean, he, is_con = prepare_mesh(m)
    h, claim = incircle_hamiltonian(clean, he, is_con)
    twin, bad = _kernels.half_edge_twins(h.triangles, h.n_points)
    assert bad == -1
    np.testing.assert_array_equal(claim, twin)


def test_a_wrong_claim_is_not_believed() -> None:
    from dataclasses import replace

    from hammesh.verify.certificate import certify
    from hammesh.verify.reference import input_facts

    m = hammesh.quality_mesh(plate_with_loops(1), min_angle=30, max_area=0.02)
    h = hammesh.hamiltonian(m, mode="incircle")
    tri = h.triangles.copy()
    tri[[0, 1]] = tri[[1, 0]]  # a broken output ...
    bogus = np.full(3 * len(tri), -1, dtype=np.int64)  # ... with an "all boundary" claim
    with pytest.raises(hammesh.VerificationError):
        certify(replace(h, triangles=tri), input_facts(m), claim=bogus)
    # a valid output with a bogus claim still passes (the claim is checked, then ignored)
    certify(h, input_facts(m), claim=bogus)


@pytest.mark.parametrize("n_loops, pieces", [(0, 1), (3, 1), (2, 3)])
@pytest.mark.parametrize("cores", [2, 3])
def test_forest_searched_in_slabs(monkeypatch, n_loops: int, pieces: int, cores: int) -> None:
    """Searched in threads (one slab each), the forest still spans every piece with the
    fewest midpoints, and the output passes the certificate."""
    import hammesh.threads as row_threads
    from hammesh.postprocess import _thm24_kernels as _kernels
    from tests.helpers import plate

    m = plate(n_loops, pieces, max_area=0.002)
    monkeypatch.setattr(row_threads, "THREAD_MIN_ROWS", 50)
    monkeypatch.setattr(row_threads.os, "cpu_count", lambda: cores)
    from hammesh.halfedge import prepare_mesh

    clean, he, is_con = prepare_mesh(m)
    tri, code, order, firsts, split = _kernels.spanning_forest(clean.triangles, he.twin, is_con, clean.points)
    np.testing.assert_array_equal(split, np.flatnonzero((code & 3) == 3))  # the split slots
    assert sorted(order.tolist()) == list(range(m.n_triangles))
    tree = (code & 3) >= _kernels.TREE_BIT
    assert tree.sum() == 2 * (m.n_triangles - pieces)  # a spanning forest: m - pieces edges
    assert ((code & 3) == 3).sum() == 2 * n_loops  # crossings: regions - pieces
    h = hammesh.hamiltonian(m, mode="incircle")
    assert len(h.components) == pieces and h.report["midpoints"] == n_loops
    assert_certificate(m, h)


@pytest.mark.parametrize("loops", [0, 1])
def test_walk_reusing_the_input_pairing_arrays(loops: int) -> None:
    """``incircle_streaming(..., reuse=True)`` makes ``parent`` and ``kind`` of the dead
    pairing arrays when no constrained edge is split (``loops=0``), else allocates them;
    either way the output equals the plain construction's."""
    from hammesh.halfedge import prepare_mesh
    from hammesh.postprocess.incircle import incircle_streaming
    from tests.helpers import plate

    m = plate(loops, 1, max_area=0.01)
    clean, he, is_con = prepare_mesh(m)
    plain, claim, _ = incircle_streaming(clean, he, is_con, None)
    clean, he, is_con = prepare_mesh(m)
    twin = he.twin
    got, claim2, _ = incircle_streaming(clean, he, is_con, None, reuse=True)
    assert np.shares_memory(got.parent, twin) == (loops == 0)
    assert (plain.report["midpoints"] == 0) == (loops == 0)
    for k in ("triangles", "parent", "kind", "points", "components"):
        np.testing.assert_array_equal(getattr(got, k), getattr(plain, k), err_msg=k)
    np.testing.assert_array_equal(claim2, claim)
    assert hammesh.verify(got, m)["min_angle_output_deg"] > 0


@pytest.mark.parametrize("loops, pieces", [(0, 1), (0, 2), (1, 1)])
def test_walk_with_arrays_made_ahead_on_the_side_thread(loops: int, pieces: int) -> None:
    """``walk_arrays(..., n_points=n)`` made ahead (as ``hammesh.hamiltonian`` does on its
    side thread) gives the output's points where they fit (no midpoint) and is ignored
    where not; positions reuse the walk's dead ``code`` array for one cycle; the
    output equals the plain construction's."""
    from concurrent.futures import ThreadPoolExecutor

    from hammesh.halfedge import prepare_mesh
    from hammesh.postprocess.incircle import incircle_streaming, walk_arrays
    from tests.helpers import plate

    m = plate(loops, pieces, max_area=0.01)
    plain, claim, _ = incircle_streaming(*prepare_mesh(m), None)
    nh = 3 * m.n_triangles
    with ThreadPoolExecutor(1) as side:
        ready = side.submit(walk_arrays, nh, nh, False, m.n_points)
        arrays = ready.result()
        got, claim2, stream = incircle_streaming(*prepare_mesh(m), side, ready, reuse=True)
        stream.join()
    fits = loops == 0
    assert np.shares_memory(got.points, arrays["points"]) == fits
    assert not any(np.shares_memory(got.position, a) for a in arrays.values())
    np.testing.assert_array_equal(plain.position, np.arange(len(plain.triangles)) - np.repeat(
        np.cumsum(plain.components) - plain.components, plain.components))
    for k in ("triangles", "parent", "kind", "points", "components", "position"):
        np.testing.assert_array_equal(getattr(got, k), getattr(plain, k), err_msg=k)
    np.testing.assert_array_equal(claim2, claim)
    assert hammesh.verify(got, m)["min_angle_output_deg"] > 0
