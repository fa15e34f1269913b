"""Scalable encoder: round trips on planar and 3D meshes, Hamiltonian meshes as one strip, bad input."""

from __future__ import annotations

import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.errors import InvalidMeshError, InvalidOptionError
from hammesh.mesh import Mesh
from hammesh.strips.dual import dual_mesh
from hammesh.strips.encode import encode, encode_generalized, greedy_paths
from hammesh.strips.generalized import decode_generalized
from hammesh.strips.gl import decode_gl_strip, verify_gl_strip

from tests.helpers import grid_mesh

from .conftest import delaunay_mesh, oriented_set, square_hamiltonian, square_mesh, torus_mesh


def assert_round_trip(mesh, strip):
    decoded = decode_gl_strip(strip.indices, strip.restart_index)
    assert oriented_set(decoded) == oriented_set(mesh.triangles)
    S = strip.n_strips
    joins = (S - 1) if strip.restart_index is not None else 2 * (S - 1)
    assert len(strip.indices) == mesh.n_triangles + 2 * S + strip.n_swaps + joins


@given(
    st.integers(0, 2**32 - 1),
    st.integers(3, 60),
    st.booleans(),
    st.sampled_from(["restart", "stitch"]),
)
def test_greedy_round_trip_random_delaunay(seed, n, lift, join):
    mesh = delaunay_mesh(seed, n, lift)
    assert_round_trip(mesh, encode(mesh, join=join))
    g = encode_generalized(mesh)
    assert oriented_set(decode_generalized(g)) == oriented_set(mesh.triangles)


@pytest.mark.parametrize(
    "mesh",
    [square_mesh(), grid_mesh(7, 5), grid_mesh(6, 6, z=True), torus_mesh(), square_hamiltonian().as_mesh()],
    ids=["square", "grid", "surface", "torus", "hamiltonian-as-mesh"],
)
@pytest.mark.parametrize("join", ["restart", "stitch"])
def test_round_trip_corpus(mesh, join):
    s = encode(mesh, join=join)
    assert_round_trip(mesh, s)
    assert s.n_triangles == mesh.n_triangles


def test_greedy_paths_partition_the_dual():
    d = dual_mesh(square_mesh())
    order, starts = greedy_paths(d)
    assert sorted(order.tolist()) == list(range(d.n_triangles))
    nb = d.neighbor_triangles
    for a, b in zip(starts[:-1], starts[1:]):
        for i in range(a, b - 1):
            assert order[i + 1] in nb[order[i]]


def test_hamiltonian_mesh_is_one_strip_per_cycle():
    h = square_hamiltonian()
    s = encode(h)
    assert s.n_strips == len(h.components) == 1
    assert len(s.indices) == h.n_triangles + 2 + s.n_swaps
    assert_round_trip(h, s)
    # two cycles: two strips
    h2 = hammesh.hamiltonian(
        hammesh.quality_mesh(
            hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]]), min_angle=30, max_area=0.05
        )
    )
    pts = np.r_[h2.points, h2.points + 5]
    tri = np.r_[h2.triangles, h2.triangles + len(h2.points)]
    n = len(tri) // 2
    two = hammesh.HamiltonianMesh(
        points=pts,
        triangles=tri,
        segments=np.zeros((0, 2), np.int64),
        segment_markers=np.zeros(0, np.int64),
        components=np.array([n, n]),
        position=np.r_[np.arange(n), np.arange(n)],
        parent=np.zeros(2 * n, np.int64),
        kind=np.zeros(2 * n, np.int8),
        triangle_attributes=np.zeros((2 * n, 0)),
    )
    for join in ("restart", "stitch"):
        s = encode(two, join=join)
        assert s.n_strips == 2
        assert_round_trip(two, s)


def test_order_method_on_a_plain_mesh_in_cycle_order():
    h = square_hamiltonian()
    s = encode(h.as_mesh(), method="order")
    assert s.n_strips == 1


def test_several_components_are_several_strips():
    m = grid_mesh(3, 2)
    two = Mesh(np.r_[m.points, m.points + 10], np.r_[m.triangles, m.triangles + len(m.points)])
    s = encode(two)
    assert s.n_strips >= 2
    assert dual_mesh(two).n_components == 2
    assert_round_trip(two, s)


# --- bad input: clear errors naming the item ---------------------------------------------


def test_non_manifold_edge_is_cut_and_counted():
    """Three triangles on edge (0, 1): no strip crosses it, all three drawn with their windings."""
    pts = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]])
    tri = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    s = encode(Mesh(pts, tri))
    assert s.defects.non_manifold_edges == 1 and s.n_strips == 3
    assert_round_trip(Mesh(pts, tri), s)


def test_inconsistent_winding_is_kept():
    """A flipped neighbour: both windings drawn as given, the edge between them cut."""
    pts = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]])
    m = Mesh(pts, np.array([[0, 1, 2], [0, 2, 3][::-1]]))
    s = encode(m)
    assert s.defects.flipped_neighbours == 1 and s.n_strips == 2
    assert_round_trip(m, s)


@pytest.mark.parametrize(
    "tri,pts,match",
    [
        ([[0, 1, 1]], [[0, 0], [1, 0], [0, 1]], "all 1 triangles repeat a vertex"),
        ([[0, 1, 5]], [[0, 0], [1, 0], [0, 1]], "references vertex 5"),
        ([[0, 1, 2]], [[0, 0, 0, 0]], "shape"),
        ([[0, 1, 2]], [[0, 0], [1, np.nan], [0, 1]], "point 1"),
    ],
)
def test_bad_meshes(tri, pts, match):
    with pytest.raises(InvalidMeshError, match=match):
        encode(Mesh(np.array(pts, dtype=float), np.array(tri)))


def test_zero_area_faces_are_drawn_and_counted():
    """Collinear points (2D and 3D) make a drawable triangle; a repeated index does not."""
    pts = np.array([[0.0, 0, 0], [1, 1, 1], [2, 2, 2], [0, 1, 0]])
    m = Mesh(pts, np.array([[0, 1, 2], [0, 3, 1], [3, 3, 1]]))
    s = encode(m)
    assert (s.defects.zero_area, s.defects.repeated_vertex) == (1, 1)
    assert s.dropped.tolist() == [2] and s.n_triangles == 2
    verify_gl_strip(m.triangles[:2], s.indices, s.restart_index)
    pts2 = np.array([[0.0, 0], [1, 0], [0, 1], [2, -1]])
    s2 = encode(Mesh(pts2, np.array([[0, 1, 2], [1, 3, 2]])))
    assert s2.defects.zero_area == 1 and s2.n_triangles == 2


def test_bad_method():
    with pytest.raises(InvalidOptionError):
        encode(square_mesh(), method="magic")


@given(st.integers(0, 2**32 - 1), st.integers(3, 80), st.booleans())
def test_improved_cover_is_a_partition_and_never_longer(seed, n, lift):
    from hammesh.strips.encode import orient_path_turns
    from hammesh.strips.gl import gl_strip_from_turns

    d = dual_mesh(delaunay_mesh(seed, n, lift))
    lengths = []
    for improve in (False, True):
        order, starts = greedy_paths(d, improve=improve)
        assert sorted(order.tolist()) == list(range(d.n_triangles))
        nb = d.neighbor_triangles
        for a, b in zip(starts[:-1], starts[1:]):
            for i in range(a, b - 1):
                assert order[i + 1] in nb[order[i]]
        lengths.append(len(gl_strip_from_turns(orient_path_turns(d, order, starts)).indices))
    assert lengths[1] <= lengths[0]


# --- Lemma 5.1: tree duals (triangulated polygons) get the fewest strips ---------------


def _polygon_mesh(rng, n):
    from tests.polygon import brute

    p = brute.random_simple_polygon(rng, n, grid=40, tries=20)
    if p is None:
        return None, None
    tris = brute.all_triangulations(p)
    tri = np.array(tris[int(rng.integers(len(tris)))], dtype=np.int64)
    return Mesh(np.array(p, dtype=float), tri), brute.min_path_partition_size(len(tri), brute.dual_edges(tri.tolist()))


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(3, 11), st.sampled_from(["restart", "stitch"]))
def test_tree_dual_gets_the_minimum_number_of_strips(seed, n, join):
    from hammesh.strips.encode import is_forest

    mesh, fewest = _polygon_mesh(np.random.default_rng(seed), n)
    if mesh is None:
        return
    assert is_forest(dual_mesh(mesh))
    s = encode(mesh, join=join)
    assert s.n_strips == fewest
    assert_round_trip(mesh, s)
    g = encode_generalized(mesh)
    assert g.n_strips == fewest
    assert oriented_set(decode_generalized(g)) == oriented_set(mesh.triangles)


def test_tree_duals_on_many_random_polygons():
    rng = np.random.default_rng(11)
    done = 0
    for _ in range(80):
        mesh, fewest = _polygon_mesh(rng, int(rng.integers(4, 11)))
        if mesh is None:
            continue
        assert encode(mesh).n_strips == fewest
        done += 1
    assert done > 50


def test_large_polygon_triangulation_in_2d_and_3d():
    """A 400-gon's triangulation (dual tree), flat and lifted to 3D: Lemma 5.1's count."""
    from hammesh.polygon._triangulate import triangulate_polygon
    from hammesh.polygon.path_partition import path_partition
    from tests.polygon import shapes

    p = shapes.star(400, seed=2)
    T = triangulate_polygon(p)
    fewest = len(path_partition(p, T))
    for pts in (np.asarray(p, float), np.c_[np.asarray(p, float), np.zeros(len(p))]):
        s = encode(Mesh(pts, T))
        assert s.n_strips == fewest
        assert_round_trip(Mesh(pts, T), s)


@pytest.mark.parametrize("area", [0.05, 0.01])
def test_cycle_cut_is_the_best_of_every_cut_and_direction(area):
    """One strip for a fixed cyclic order: no other cut point or direction is shorter."""
    from hammesh.strips.gl import gl_strip

    h = square_hamiltonian(area)
    d = dual_mesh(h)
    k = h.n_triangles
    best = min(
        len(gl_strip(d.triangles, d.twin, np.roll(np.arange(k)[::step], -c), [0, k]).indices)
        for c in range(k)
        for step in (1, -1)
    )
    s = encode(h)
    assert s.n_strips == 1
    assert len(s.indices) == best


@given(st.integers(0, 2**32 - 1), st.integers(3, 60), st.booleans())
def test_dual_components_match_scipy(seed, n, lift):
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    mesh = delaunay_mesh(seed, n, lift)
    keep = np.random.default_rng(seed).random(mesh.n_triangles) < 0.6  # break it into pieces
    if not keep.any():
        return
    d = dual_mesh(Mesh(mesh.points, mesh.triangles[keep]))
    h = np.flatnonzero(d.twin >= 0)
    g = coo_matrix((np.ones(len(h)), (h // 3, d.twin[h] // 3)), shape=(d.n_triangles,) * 2)
    nc, label = connected_components(g, directed=False)
    assert d.n_components == nc
    assert d.component.tolist() == label.tolist()
    s = encode(Mesh(mesh.points, mesh.triangles[keep]))
    assert s.n_strips >= nc


def test_structured_grid_rows_are_swap_free():
    """A structured quad grid split into triangles: its rows are swap-free strips (issue 16:
    pyvista's load_random_hills took 97 swaps in L-shaped paths where the peers use none)."""
    from hammesh.strips._cover_kernels import zigzag_path_cover

    nx, ny = 30, 12
    x, y = np.meshgrid(np.arange(nx + 1.0), np.arange(ny + 1.0))
    pts = np.c_[x.ravel(), y.ravel(), np.sin(x.ravel()) * 0.1]
    v = lambda i, j: j * (nx + 1) + i  # noqa: E731
    tri = [[v(i, j), v(i + 1, j), v(i + 1, j + 1)] for j in range(ny) for i in range(nx)]
    tri += [[v(i, j), v(i + 1, j + 1), v(i, j + 1)] for j in range(ny) for i in range(nx)]
    m = Mesh(pts, np.array(tri, np.int64))
    s = encode(m)
    assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(m.triangles)
    assert s.n_swaps == 0 and s.n_strips <= ny
    assert len(s.indices) <= m.n_triangles + 3 * ny - 1  # rows: T + 2 S + (S - 1) restarts
    # the chains themselves (either rule): every consecutive pair of a chain shares an edge,
    # every triangle once, no swap inside a chain
    from hammesh.strips._cover_kernels import LONGEST_CHAIN, SHORTEST_CHAIN
    from hammesh.strips.paths import path_turns

    d = dual_mesh(m)
    nb = d.neighbor_triangles
    for rule in (LONGEST_CHAIN, SHORTEST_CHAIN):
        order, starts = zigzag_path_cover(d.records.copy(), np.arange(d.n_triangles - 1, -1, -1), rule)
        assert sorted(order.tolist()) == list(range(d.n_triangles))
        for a, b in zip(starts[:-1], starts[1:]):
            for i in range(a, b - 1):
                assert order[i + 1] in nb[order[i]]
        turns = path_turns(d.triangles, d.twin, order.astype(np.int64), starts)
        pos = np.arange(len(order)) - np.repeat(starts[:-1], np.diff(starts))  # position inside its chain
        assert not turns.swap[pos >= 2].any()  # alternating: only the first turn depends on the direction


def lat_long_sphere(n_theta: int, n_phi: int) -> Mesh:
    """A UV sphere as pyvista builds it: two poles and ``n_phi - 2`` rings of ``n_theta`` vertices, outward."""
    th = np.arange(n_theta) * 2 * np.pi / n_theta
    ph = np.linspace(0, np.pi, n_phi)[1:-1]
    ring = np.c_[(np.sin(ph)[:, None] * np.cos(th)).ravel(), (np.sin(ph)[:, None] * np.sin(th)).ravel(),
                 np.repeat(np.cos(ph), n_theta)]
    pts = np.r_[[[0, 0, 1.0]], ring, [[0, 0, -1.0]]]
    v = lambda r, j: 1 + r * n_theta + j % n_theta  # noqa: E731
    south = len(pts) - 1
    tri = [[0, v(0, j), v(0, j + 1)] for j in range(n_theta)]
    tri += [[south, v(n_phi - 3, j + 1), v(n_phi - 3, j)] for j in range(n_theta)]
    for r in range(n_phi - 3):
        for j in range(n_theta):
            tri += [[v(r, j), v(r + 1, j), v(r + 1, j + 1)], [v(r, j), v(r + 1, j + 1), v(r, j + 1)]]
    return Mesh(pts, np.array(tri, np.int64))


def _candidate_lengths(m: Mesh) -> list[int]:
    """Buffer lengths of the covers encode chooses from: greedy alone, swap-free chains (both rules)."""
    from hammesh.strips._cover_kernels import LONGEST_CHAIN, SHORTEST_CHAIN

    E = sys.modules["hammesh.strips.encode"]
    out = []
    for method, rule in (("greedy", LONGEST_CHAIN), ("zigzag", LONGEST_CHAIN), ("zigzag", SHORTEST_CHAIN)):
        d, tri, twin, loc, st_, ids = E._oriented_local(m, method, None, None, rule)
        out.append(len(E._buffer(d, tri, twin, loc, st_, ids, "restart", 0xFFFFFFFF)[0].indices))
    return out


@given(st.integers(6, 40), st.integers(4, 24))
@settings(max_examples=25, deadline=None)
def test_uv_spheres_keep_the_shortest_cover(n_theta, n_phi):
    """Latitude-longitude spheres (few swaps per strip) try the swap-free chains both ways
    (each seed's longest chain, and its shortest) and keep the shortest of the three buffers."""
    m = lat_long_sphere(n_theta, n_phi)
    s = encode(m)
    assert_round_trip(m, s)
    lengths = _candidate_lengths(m)
    assert len(s.indices) == min(lengths)
    assert encode(m, method="zigzag").indices.size == min(lengths[1:])


def test_uv_sphere_of_sphere_ply_no_longer_than_meridian_strips():
    """Issue 16: pyvista's sphere.ply (30 meridians, 16 rings with the poles; ours was 1.162
    against NvTriStrip's 1.120) -- the same layout is never longer than one swap-free strip per
    meridian column, pole to pole: ``T + 2 S + (S - 1)`` indices with ``S = 30`` (1.106)."""
    m = lat_long_sphere(30, 16)
    s = encode(m)
    assert_round_trip(m, s)
    assert len(s.indices) <= m.n_triangles + 3 * 30 - 1


@pytest.mark.parametrize("nu,nv", [(60, 40), (24, 10)])
def test_encoder_keeps_the_shorter_of_greedy_and_swap_free_chains(nu, nv):
    """On a smooth closed surface (few swaps) encode also tries the swap-free chains and keeps
    the shorter buffer; method 'zigzag' is that cover alone (issue 16: NvTriStrip's 1.012 on
    a 60 x 40 torus against our greedy 1.025)."""
    from hammesh.strips.gl import gl_strip

    m = torus_mesh(nu, nv)
    d = dual_mesh(m)
    order, starts = greedy_paths(d)
    greedy_only = gl_strip(d.triangles, d.twin, order, starts)
    z = encode(m, method="zigzag")
    assert_round_trip(m, z)
    s = encode(m)
    assert_round_trip(m, s)
    E = sys.modules["hammesh.strips.encode"]
    few = greedy_only.n_swaps <= max(E._ZIGZAG_TRIGGER * (greedy_only.n_strips - 1), E._ZIGZAG_SWAP_RATE * m.n_triangles)
    few = few or m.n_triangles <= E._ZIGZAG_ALWAYS
    want = min(len(z.indices), len(greedy_only.indices)) if few else len(greedy_only.indices)
    assert len(s.indices) == want
    if (nu, nv) == (60, 40):
        assert few
        assert s.indices_per_triangle < 1.012


@given(st.integers(0, 2**32 - 1), st.integers(12, 120), st.booleans())
@settings(max_examples=30, deadline=None)
def test_fast_is_the_greedy_cover_alone(seed, n, lift):
    """``fast=True``: the greedy cover without end moves or swap-free trials -- exactly the
    buffer of :func:`greedy_paths` with ``improve=False``, never shorter than the default."""
    from hammesh.strips.encode import orient_path_turns
    from hammesh.strips.gl import RESTART_INDEX, gl_strip_from_turns

    m = delaunay_mesh(seed, n, lift)
    f = encode(m, fast=True)
    assert_round_trip(m, f)
    d = dual_mesh(m)
    order, starts = greedy_paths(d, improve=False)
    want = gl_strip_from_turns(orient_path_turns(d, order, starts), join="restart", restart_index=RESTART_INDEX)
    assert len(f.indices) == len(want.indices)
    assert len(encode(m).indices) <= len(f.indices)
