"""hammesh.fem: scikit-fem, meshio and pyvista get the named boundaries and regions.

The expected sets are derived here from the mesh's own arrays (segments, markers,
attributes) and compared with what the converters and the FEM codes' own readers
(``skfem.MeshTri.load``, ``pyvista.read``, ``meshio.read``) find.
"""

from __future__ import annotations

import sys

import meshio
import numpy as np
import pytest

import hammesh
from hammesh.errors import InvalidMeshError, MissingDependencyError
from tests.fem.conftest import HOLE_MARKER, INTERFACE_MARKER, OUTER_MARKERS

FILES = [".vtu", ".vtk", ".xdmf", ".msh"]


def edge_set(pairs) -> set[tuple[int, int]]:
    pairs = np.sort(np.asarray(pairs, dtype=np.int64).reshape(-1, 2), axis=1)
    return set(map(tuple, pairs.tolist()))


def expected_boundaries(h) -> dict[str, set[tuple[int, int]]]:
    return {f"marker_{k}": edge_set(h.segments[h.segment_markers == k])
            for k in np.unique(h.segment_markers).tolist()}


def expected_subdomains(h) -> dict[str, list[int]]:
    a = h.triangle_attributes[:, 0]
    return {f"region_{int(v)}": np.flatnonzero(a == v).tolist() for v in np.unique(a)}


def skfem_sets(m) -> tuple[dict[str, set[tuple[int, int]]], dict[str, list[int]]]:
    """A skfem mesh's named sets as vertex pairs / element lists."""
    bnd = {k: edge_set(m.facets[:, np.asarray(v)].T) for k, v in (m.boundaries or {}).items()}
    sub = {k: sorted(np.asarray(v).tolist()) for k, v in (m.subdomains or {}).items()}
    return bnd, sub


def test_fixture_has_every_tag(plate):
    assert set(plate.segment_markers.tolist()) == {*OUTER_MARKERS, HOLE_MARKER, INTERFACE_MARKER}
    assert set(np.unique(plate.triangle_attributes[:, 0]).tolist()) == {1.0, 2.0}


def test_to_skfem_names_every_marker_and_region(plate):
    skfem = pytest.importorskip("skfem")
    m = hammesh.to_skfem(plate)
    assert isinstance(m, skfem.MeshTri)
    np.testing.assert_array_equal(m.p.T, plate.points)
    np.testing.assert_array_equal(m.t.T, np.sort(plate.triangles, axis=1))  # element i = triangle i
    bnd, sub = skfem_sets(m)
    assert bnd == expected_boundaries(plate)
    assert sub == expected_subdomains(plate)
    # each facet of a set exactly once; the interface is interior, the rest boundary
    for name, facets in m.boundaries.items():
        assert len(np.unique(facets)) == len(facets) == len(bnd[name])
    interior = set(np.flatnonzero(m.f2t[1] >= 0).tolist())
    assert set(np.asarray(m.boundaries[f"marker_{INTERFACE_MARKER}"]).tolist()) <= interior
    assert not set(np.asarray(m.boundaries["marker_4"]).tolist()) & interior


@pytest.mark.parametrize("suffix", FILES)
def test_meshtri_load_finds_boundaries_and_subdomains(tmp_path, plate, suffix):
    skfem = pytest.importorskip("skfem")
    path = tmp_path / f"plate{suffix}"
    hammesh.write(plate, path)
    m = skfem.MeshTri.load(str(path))
    np.testing.assert_array_equal(m.p.T[:, :2], plate.points)  # the numbering is kept
    np.testing.assert_array_equal(m.t.T, np.sort(plate.triangles, axis=1))
    bnd, sub = skfem_sets(m)
    assert bnd == expected_boundaries(plate)
    assert sub == expected_subdomains(plate)


def test_msh_round_trip_keeps_the_node_order(tmp_path, plate):
    path = tmp_path / "plate.msh"
    hammesh.write(plate, path)
    raw = meshio.read(path, file_format="gmsh")  # what any Gmsh reader sees
    np.testing.assert_array_equal(raw.points[:, :2], plate.points)
    tri = np.concatenate([b.data for b in raw.cells if b.type == "triangle"])
    np.testing.assert_array_equal(tri, plate.triangles)
    assert {k: v.tolist() for k, v in raw.field_data.items()} == {
        **{f"marker_{k}": [k, 1] for k in np.unique(plate.segment_markers).tolist()},
        "region_1": [1, 2], "region_2": [2, 2],
    }
    back = hammesh.read_mesh(path)
    np.testing.assert_array_equal(back.points, plate.points)
    np.testing.assert_array_equal(back.triangles, plate.triangles)
    np.testing.assert_array_equal(back.vertex_markers, plate.vertex_markers)


def test_pyvista_reads_triangles_only(tmp_path, plate):
    pv = pytest.importorskip("pyvista")
    hammesh.write(plate, tmp_path / "plate.vtu")
    grid = pv.read(tmp_path / "plate.vtu")
    assert grid.n_cells == plate.n_triangles
    assert set(np.asarray(grid.celltypes).tolist()) == {int(pv.CellType.TRIANGLE)}
    np.testing.assert_array_equal(grid.cell_data["cycle_position"], plate.position)
    np.testing.assert_array_equal(grid.point_data["vertex_marker"], plate.vertex_markers)


def test_to_pyvista(plate):
    pv = pytest.importorskip("pyvista")
    grid = hammesh.to_pyvista(plate)
    assert isinstance(grid, pv.UnstructuredGrid)
    assert set(np.asarray(grid.celltypes).tolist()) == {int(pv.CellType.TRIANGLE)}
    np.testing.assert_array_equal(grid.points[:, :2], plate.points)
    cells = np.asarray(grid.cells).reshape(-1, 4)
    assert (cells[:, 0] == 3).all()
    np.testing.assert_array_equal(cells[:, 1:], plate.triangles)
    np.testing.assert_array_equal(grid.cell_data["kind"], plate.kind)
    np.testing.assert_array_equal(grid.cell_data["attribute_0"], plate.triangle_attributes[:, 0])
    assert not [k for k in grid.cell_data.keys() if k.startswith("skfem:")]
    # the constrained edges, from the per-triangle fields
    flags, marks = grid.cell_data["segment_edges"], grid.cell_data["edge_marker"]
    t, k = np.nonzero((flags[:, None] >> np.arange(3)) & 1)
    tri = plate.triangles
    stored = {(int(tri[a, b]), int(tri[a, (b + 1) % 3])): int(marks[a, b]) for a, b in zip(t, k)}
    assert edge_set(list(stored)) == edge_set(plate.segments) and len(stored) == len(plate.segments)


def test_to_meshio_is_what_skfem_reads(plate):
    skfem_meshio = pytest.importorskip("skfem.io.meshio")
    out = hammesh.to_meshio(plate)
    assert [b.type for b in out.cells] == ["triangle"]
    bnd, sub = skfem_sets(skfem_meshio.from_meshio(out))
    assert bnd == expected_boundaries(plate) and sub == expected_subdomains(plate)
    msh = hammesh.to_meshio(plate, layout=".msh")
    assert {b.type for b in msh.cells} == {"triangle", "line"}


def test_missing_extra_is_one_line_naming_the_extra(monkeypatch, plate):
    monkeypatch.setitem(sys.modules, "skfem", None)  # import skfem -> ImportError
    monkeypatch.setitem(sys.modules, "pyvista", None)
    with pytest.raises(MissingDependencyError, match=r"^skfem is not installed: pip install hammesh\[fem\]$"):
        hammesh.to_skfem(plate)
    with pytest.raises(MissingDependencyError, match=r"pip install hammesh\[vtk\]$"):
        hammesh.to_pyvista(plate)
    assert isinstance(MissingDependencyError("x"), (hammesh.HammeshError, ImportError))


def test_to_skfem_refuses_a_segment_that_is_not_an_edge(plate):
    pytest.importorskip("skfem")
    import dataclasses

    a, b = 0, int(np.argmax(np.hypot(*(plate.points - plate.points[0]).T)))  # far apart
    bad = dataclasses.replace(plate, segments=np.vstack([plate.segments, [[a, b]]]),
                              segment_markers=np.append(plate.segment_markers, 8))
    with pytest.raises(InvalidMeshError, match=rf"segments\[{len(plate.segments)}\] = \({a}, {b}\) is not an edge"):
        hammesh.to_skfem(bad)


def test_converters_refuse_what_is_not_a_mesh():
    with pytest.raises(InvalidMeshError, match="expected a hammesh.Mesh"):
        hammesh.to_meshio("plate.vtu")


# --- neighbours and the dual graph ------------------------------------------------------


def test_neighbors_are_the_shared_edges(plate):
    nbr = plate.neighbors
    assert nbr is plate.neighbors  # computed once
    tri = plate.triangles
    m = len(tri)
    t, k = np.nonzero(nbr >= 0)
    u = nbr[t, k]
    a, b = tri[t, k], tri[t, (k + 1) % 3]
    # the neighbour holds the edge reversed
    has = ((tri[u] == b[:, None]) & (np.roll(tri[u], -1, axis=1) == a[:, None])).any(axis=1)
    assert has.all()
    # boundary edges: used by one triangle only
    edges = np.sort(np.stack([tri, np.roll(tri, -1, axis=1)], axis=2).reshape(-1, 2), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert int((nbr < 0).sum()) == int((counts == 1).sum())
    # consecutive rows of the cycle are neighbours
    nxt = np.arange(1, m + 1) % m
    assert (nbr == nxt[:, None]).any(axis=1).all()


def test_dual_graph(plate):
    g = hammesh.dual_graph(plate)
    m = plate.n_triangles
    assert g.shape == (m, m) and (g != g.T).nnz == 0 and g.diagonal().sum() == 0
    assert g.nnz == int((plate.neighbors >= 0).sum())
    rows = np.repeat(np.arange(m), np.diff(g.indptr))
    assert (plate.neighbors[rows] == g.indices[:, None]).any(axis=1).all()


def test_plain_mesh_neighbors(plate_mesh):
    from hammesh.fem import neighbors
    from hammesh.mesh import triangle_neighbors

    np.testing.assert_array_equal(neighbors(plate_mesh), triangle_neighbors(plate_mesh.triangles))


def test_surfaces_go_to_pyvista_not_to_skfem():
    pv = pytest.importorskip("pyvista")
    pytest.importorskip("skfem")
    from tests.helpers import grid_mesh

    surface = grid_mesh(3, 2, z=True)
    grid = hammesh.to_pyvista(surface)
    np.testing.assert_array_equal(grid.points, surface.points)
    assert set(np.asarray(grid.celltypes).tolist()) == {int(pv.CellType.TRIANGLE)}
    with pytest.raises(InvalidMeshError, match=r"expected a planar mesh \(points \(n, 2\)\), got points \(12, 3\)"):
        hammesh.to_skfem(surface)
