"""3D surfaces (issue 6, part 2): one verified cycle per piece, surface kept exactly."""

from __future__ import annotations

import meshio
import networkx as nx
import numpy as np
import pytest

import hammesh
from hammesh.surface import (
    icosphere,
    noisy_sphere,
    read_surface,
    surface_hamiltonian,
    thick_plate,
    torus,
    write_surface,
)
from hammesh.verify.surface import verify_surface
from tests.helpers import angles_deg


def pieces(tri: np.ndarray) -> int:
    g = nx.Graph()
    g.add_nodes_from(range(len(tri)))
    owner: dict = {}
    for t, (a, b, c) in enumerate(tri.tolist()):
        for e in ((a, b), (b, c), (c, a)):
            owner.setdefault(tuple(sorted(e)), []).append(t)
    g.add_edges_from(ts for ts in owner.values() if len(ts) == 2)
    return nx.number_connected_components(g)


def boundary(tri: np.ndarray) -> set:
    e = {(a, b) for a, b, c in tri.tolist() for (a, b) in ((a, b), (b, c), (c, a))}
    return {x for x in e if (x[1], x[0]) not in e}


def check(pts: np.ndarray, tri: np.ndarray, h: hammesh.HamiltonianMesh, exact: bool = True) -> None:
    """Independent (numpy/networkx) re-check of the surface certificate."""
    assert h.report["verified"] is True
    out = h.triangles
    start = 0
    for length in h.components.tolist():
        run = out[start : start + length]
        shared = (run[:, :, None] == np.roll(run, -1, axis=0)[:, None, :]).sum(axis=(1, 2))
        assert (shared == 2).all()
        start += length
    assert len({tuple(sorted(t)) for t in out.tolist()}) == len(out)
    assert len(h.components) == pieces(tri)
    np.testing.assert_array_equal(h.points[: len(pts)], pts)
    assert boundary(out) == boundary(tri)
    a_in, a_out = angles_deg(pts, tri).min(), angles_deg(h.points, out).min()
    assert a_out >= 0.5 * a_in * (1 - 1e-9)
    area = lambda p, t: 0.5 * np.linalg.norm(np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]]), axis=1)  # noqa: E731
    if exact:
        assert np.isclose(area(h.points, out).sum(), area(pts, tri).sum(), rtol=1e-9)
    r = h.report
    assert r["triangles_added"] == 2 * r["steiner_points"] == len(out) - len(tri)


SURFACES = {
    "icosphere": lambda: icosphere(3),
    "torus": lambda: torus(40, 20),
    "torus_with_hole": lambda: torus(40, 20, hole=True),
    "genus2": lambda: thick_plate(0.01),
    "noisy_sphere": lambda: noisy_sphere(3, noise=0.1),
}


@pytest.mark.parametrize("name", sorted(SURFACES))
def test_surfaces_verified_and_sparse(name: str) -> None:
    pts, tri = SURFACES[name]()
    h = surface_hamiltonian(pts, tri)
    check(pts, tri, h)
    assert h.report["exact_surface"] is True and h.report["area_change_rel"] == pytest.approx(0, abs=1e-12)
    assert h.report["steiner_points"] <= 0.05 * len(tri)
    assert (h.kind != 1).all() and (h.kind != 4).all()  # no flips: the surface is kept


def test_two_spheres_two_cycles() -> None:
    p, t = icosphere(2)
    pts = np.concatenate([p, p + [3.0, 0, 0]])
    tri = np.concatenate([t, t + len(p)])
    h = surface_hamiltonian(pts, tri)
    assert len(h.components) == 2
    check(pts, tri, h)


def test_planar_input_is_a_flat_surface() -> None:
    m = hammesh.quality_mesh(hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]]), min_angle=30, max_area=0.01)
    h = surface_hamiltonian(m.points, m.triangles)
    check(np.c_[m.points, np.zeros(m.n_points)], m.triangles, h)


def test_swaps_report_how_far_the_surface_moves() -> None:
    pts, tri = noisy_sphere(3, noise=0.1)
    h = surface_hamiltonian(pts, tri, swaps=True, max_fold_deg=15)
    check(pts, tri, h, exact=False)
    r = h.report
    assert r["exact_surface"] is False and r["swaps"] > 0
    assert r["steiner_points"] < surface_hamiltonian(pts, tri).report["steiner_points"]
    assert r["max_swap_height"] > 0 and abs(r["area_change_rel"]) < 0.01


@pytest.mark.parametrize("suffix", [".obj", ".ply", ".stl", ".off", ".vtu"])
def test_file_round_trip(tmp_path, suffix: str) -> None:
    pts, tri = torus(24, 12, hole=True)
    src = tmp_path / f"in{suffix}"
    meshio.write(src, meshio.Mesh(pts, [("triangle", tri)]))
    p, t = read_surface(src)
    assert len(t) == len(tri) and len(p) in (len(pts), len(np.unique(tri)))  # STL: welded, unused dropped
    h = surface_hamiltonian(p, t)
    dst = tmp_path / f"out{suffix}"
    write_surface(h, dst)
    p2, t2 = read_surface(dst)
    # the order survives: the file's rows are the cycle
    verify_surface(p2, t2, np.array([len(t2)]))
    assert len(t2) == h.n_triangles


def test_bad_inputs() -> None:
    with pytest.raises(hammesh.InvalidMeshError, match="positive area"):
        surface_hamiltonian(np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]], float), np.array([[0, 1, 2], [0, 0, 1]]))
    with pytest.raises(hammesh.InvalidMeshError, match="shape"):
        surface_hamiltonian(np.zeros((3, 4)), np.array([[0, 1, 2]]))
    with pytest.raises(hammesh.FileFormatError, match="unknown surface format"):
        read_surface("x.xyz")


def test_small_defective_inputs_are_accepted() -> None:
    """What used to be refused (issue 12): cut at the bad edges, degenerate rows dropped."""
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], float)
    cases = {
        "non_manifold_edges": np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]]),
        "flipped_neighbours": np.array([[0, 1, 2], [0, 1, 3]]),
        "repeated_vertex": np.array([[0, 1, 2], [1, 1, 3]]),
        "double_sided": np.array([[0, 1, 2], [1, 0, 2]]),  # a flat "pillow": one cycle of two
    }
    for key, tri in cases.items():
        h = surface_hamiltonian(pts, tri)
        assert h.report["verified"] and h.report["defects"][key] == 1, (key, h.report["defects"])
        assert set(np.unique(h.parent)) | set(h.report["dropped_rows"]) == set(range(len(tri)))


def test_quad_faces_are_triangulated_in_place(tmp_path) -> None:
    """Issue 12: a quad is split (keeping its winding), never dropped or refused."""
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0]], float)
    src = tmp_path / "q.vtu"
    meshio.write(src, meshio.Mesh(pts, [("quad", np.array([[0, 1, 2, 3]])), ("triangle", np.array([[1, 4, 2]]))]))
    _, tri = read_surface(src)
    assert tri.tolist() == [[0, 1, 2], [0, 2, 3], [1, 4, 2]]


def test_verifier_catches_broken_outputs() -> None:
    pts, tri = noisy_sphere(3, noise=0.1)
    h = surface_hamiltonian(pts, tri)
    assert h.n_points > len(pts)
    kw = dict(reference_points=pts, reference_triangles=tri, parent=h.parent)
    verify_surface(h.points, h.triangles, h.components, **kw)
    rng = np.random.default_rng(0)
    with pytest.raises(hammesh.VerificationError, match="breaks"):
        verify_surface(h.points, h.triangles[rng.permutation(h.n_triangles)], h.components)
    moved = h.points.copy()
    moved[len(pts)] *= 1.01  # a Steiner point off its input triangle's plane
    with pytest.raises(hammesh.VerificationError, match="plane|area|angle"):
        verify_surface(moved, h.triangles, h.components, **kw)
    flipped = h.triangles.copy()
    flipped[0] = flipped[0, ::-1]  # one triangle against its neighbours
    with pytest.raises(hammesh.VerificationError, match="breaks"):
        verify_surface(h.points, flipped, h.components)


def test_cli_surface(tmp_path) -> None:
    from hammesh.cli import main

    pts, tri = thick_plate(0.02)
    src = tmp_path / "plate.ply"
    meshio.write(src, meshio.Mesh(pts, [("triangle", tri)]))
    out, rep = tmp_path / "plate.vtu", tmp_path / "plate.json"
    assert main(["surface", str(src), "-o", str(out), "--report", str(rep)]) == 0
    m = meshio.read(out)
    assert "cycle_id" in m.cell_data and len(m.cells[0].data) > len(tri)
    assert main(["surface", str(tmp_path / "missing.obj")]) == 2
    assert main(["surface", str(src), "-o", str(tmp_path / "x.xyz")]) == 2
