"""hammesh.io.tags: the per-triangle encodings of segments and named sets.

The scikit-fem encoding is checked against scikit-fem's own decoder on random
Delaunay meshes with random constrained edges (boundary and interior) and regions.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from hammesh.io import meshio_format, tags
from hammesh.mesh import Mesh
from tests.io.test_meshio_format import delaunay_meshes, undirected


def edges(triangles):
    t = np.asarray(triangles)
    return np.unique(np.sort(np.vstack([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1), axis=0)


@st.composite
def tagged_meshes(draw):
    mesh = draw(delaunay_meshes())
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    all_edges = edges(mesh.triangles)
    chosen = all_edges[rng.random(len(all_edges)) < draw(st.floats(0.05, 1.0))]
    if len(chosen) == 0:
        chosen = all_edges[:1]
    flip = rng.random(len(chosen)) < 0.5  # either direction
    chosen[flip] = chosen[flip][:, ::-1]
    chosen = chosen[rng.permutation(len(chosen))]
    markers = rng.integers(-3, draw(st.integers(1, 9)), size=len(chosen))
    regions = rng.integers(1, 4, len(mesh.triangles)).astype(float)
    return Mesh(mesh.points, mesh.triangles, segments=chosen, segment_markers=markers,
                triangle_attributes=regions[:, None])


@settings(max_examples=40, deadline=None)
@given(mesh=tagged_meshes())
def test_edge_fields_round_trip(mesh):
    flags, marks = tags.edge_fields(mesh)
    seg, mk = tags.segments_from_edge_fields(mesh.triangles, flags, marks)
    # every segment once, in its own direction, with its marker
    assert sorted(zip(map(tuple, seg.tolist()), mk.tolist())) == sorted(
        zip(map(tuple, mesh.segments.tolist()), mesh.segment_markers.tolist()))


@settings(max_examples=40, deadline=None)
@given(mesh=tagged_meshes())
def test_skfem_fields_decode_to_the_named_sets(mesh):
    skfem = pytest.importorskip("skfem")
    m = skfem.MeshTri(mesh.points.T.copy(), mesh.triangles.T.copy())
    boundaries, subdomains = m._decode_cell_data({k: [v] for k, v in tags.skfem_cell_data(mesh).items()})
    got = {k[len("marker_"):]: undirected(m.facets[:, np.asarray(v)].T, [0] * len(v)) for k, v in boundaries.items()}
    want = {str(k): undirected(mesh.segments[mesh.segment_markers == k], [0] * int((mesh.segment_markers == k).sum()))
            for k in np.unique(mesh.segment_markers).tolist()}
    assert got == want
    a = mesh.triangle_attributes[:, 0]
    assert {k: np.asarray(v).tolist() for k, v in subdomains.items()} == {
        f"region_{int(v)}": np.flatnonzero(a == v).tolist() for v in np.unique(a)}


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(mesh=tagged_meshes(), suffix=st.sampled_from([".vtu", ".xdmf", ".msh"]))
def test_meshtri_load_property(tmp_path, mesh, suffix):
    skfem = pytest.importorskip("skfem")
    if suffix == ".msh":  # a Gmsh entity per marker and per run of region, each needs a node
        runs = 1 + int(np.count_nonzero(np.diff(mesh.triangle_attributes[:, 0])))
        assume(runs + len(np.unique(mesh.segment_markers)) <= mesh.n_points)
    path = tmp_path / f"m{suffix}"
    meshio_format.write(mesh, path)
    m = skfem.MeshTri.load(str(path))
    np.testing.assert_array_equal(m.p.T[:, :2], mesh.points)
    for k in np.unique(mesh.segment_markers).tolist():
        facets = m.facets[:, np.asarray(m.boundaries[f"marker_{k}"])].T
        sel = mesh.segment_markers == k
        assert undirected(facets, [0] * len(facets)) == undirected(mesh.segments[sel], [0] * int(sel.sum()))


def test_segment_slots_refuses_what_a_triangle_field_cannot_hold():
    points = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]])
    tri = np.array([[0, 1, 2], [0, 2, 3]])
    assert tags.segment_slots(tri, np.array([[1, 3]])) is None  # not an edge
    assert tags.segment_slots(tri, np.array([[0, 2], [2, 0]])) is None  # twice
    slots = tags.segment_slots(tri, np.array([[2, 0], [0, 1]]))
    # (2, 0) runs forwards in triangle 0 (edge 2: 2 -> 0); the other side is triangle 1's edge 0
    assert slots.slot.tolist() == [2, 0] and slots.other.tolist() == [3, -1]
    assert Mesh(points, tri).n_triangles == 2


def _slots_by_brute_force(triangles, segments):
    """Every segment's slots ``3 t + k`` by a dictionary of all edges (the oracle)."""
    where = {}
    for t, row in enumerate(np.asarray(triangles).tolist()):
        for k in range(3):
            where.setdefault(frozenset((row[k], row[(k + 1) % 3])), []).append(3 * t + k)
    return [where.get(frozenset(e), []) for e in np.asarray(segments).tolist()]


@given(tagged_meshes(), st.integers(0, 2**32 - 1))
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_segment_slots_agree_with_a_dictionary_of_edges(mesh, seed):
    rng = np.random.default_rng(seed)
    segments = np.asarray(mesh.segments).reshape(-1, 2)
    if len(segments) and rng.random() < 0.3:  # a segment that is no edge, or one given twice
        extra = rng.integers(0, len(mesh.points), 2) if rng.random() < 0.5 else segments[0, ::-1]
        segments = np.vstack([segments, extra])
    found = tags.segment_slots(mesh.triangles, segments)
    expected = _slots_by_brute_force(mesh.triangles, segments)
    keys = [frozenset(e) for e in segments.tolist()]
    if len(set(keys)) < len(keys) or any(not 1 <= len(x) <= 2 for x in expected):
        assert found is None
        return
    tri = np.asarray(mesh.triangles).reshape(-1)
    for j, slots in enumerate(expected):
        forwards = [x for x in slots if tri[x] == segments[j, 0]]
        assert found.slot[j] == (forwards[0] if forwards else slots[0])
        assert found.other[j] == ([x for x in slots if x != found.slot[j]] or [-1])[0]


def test_names():
    assert tags.boundary_name(np.int64(-2)) == "marker_-2"
    assert tags.region_name(np.float64(3.0)) == "region_3"
    assert tags.region_name(1e-7) == "region_1e-07"


def test_too_many_sets_get_no_skfem_fields():
    points = np.array([[float(i), float(j)] for j in range(12) for i in range(12)])
    from scipy.spatial import Delaunay

    tri = Delaunay(points).simplices
    a, b, c = (points[tri[:, i]] for i in range(3))
    cw = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0] < 0
    tri[cw] = tri[cw][:, [0, 2, 1]]
    seg = edges(tri)
    mesh = Mesh(points, tri, segments=seg, segment_markers=np.arange(len(seg)),
                triangle_attributes=np.arange(len(tri), dtype=float)[:, None])
    assert len(seg) > tags.MAX_NAMED_SETS and len(tri) > tags.MAX_NAMED_SETS
    assert tags.skfem_cell_data(mesh) == {}
    flags, marks = tags.edge_fields(mesh)  # the hammesh fields hold them all
    assert int(sum(bin(f & 7).count("1") for f in flags.tolist())) == len(seg)
