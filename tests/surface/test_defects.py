"""``hammesh surface`` on real-world surfaces (issue 12): one verified cycle per piece, pieces cut at bad edges."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.surface import surface_hamiltonian
from tests.strips.defect_meshes import ALL


def _edge_users(tri: np.ndarray) -> dict:
    users: dict = {}
    for t, (a, b, c) in enumerate(tri.tolist()):
        for p, q in ((a, b), (b, c), (c, a)):
            users.setdefault((min(p, q), max(p, q)), []).append((t, p, q))
    return users


def _pieces_and_cuts(tri: np.ndarray) -> tuple[int, list]:
    """Pieces joined across proper edges, and the directed half-edges on cuts (a dictionary walk)."""
    g = nx.Graph()
    g.add_nodes_from(range(len(tri)))
    cuts = []
    for u in _edge_users(tri).values():
        if len(u) == 2 and (u[0][1], u[0][2]) == (u[1][2], u[1][1]):
            g.add_edge(u[0][0], u[1][0])
        else:
            cuts += [(p, q) for _, p, q in u]
    return nx.number_connected_components(g), sorted(cuts)


def _area(pts: np.ndarray, tri: np.ndarray) -> np.ndarray:
    p = pts[tri]
    return 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)


@pytest.mark.parametrize("name", list(ALL))
@pytest.mark.parametrize("mode", [{}, {"split_all": True}])
def test_defect_surfaces(name, mode):
    pts, tri, expected = ALL[name]()
    h = surface_hamiltonian(pts, tri, **mode)
    rep = h.report
    assert rep["verified"]
    dropped = np.array(rep["dropped_rows"], dtype=np.int64)
    kept = np.setdiff1d(np.arange(len(tri)), dropped)
    assert set(np.unique(h.parent)) == set(kept.tolist())  # every kept row is re-triangulated
    # checked here without the certificate: one cycle per piece, the same cuts, the same area
    n_pieces, cuts_in = _pieces_and_cuts(tri[kept])
    assert len(h.components) == n_pieces
    _, cuts_out = _pieces_and_cuts(h.triangles)
    assert cuts_out == cuts_in
    assert np.isclose(_area(h.points, h.triangles).sum(), _area(pts, tri[kept]).sum(), rtol=1e-12)
    starts = np.r_[0, np.cumsum(h.components)]
    for a, b in zip(starts[:-1], starts[1:]):
        run = h.triangles[a:b]
        for t0, t1 in zip(run, np.roll(run, -1, axis=0)):
            assert len(set(t0.tolist()) & set(t1.tolist())) >= 2
    from hammesh.strips import encode, verify_gl_strip

    strip = encode(h)  # one strip per cycle, cuts and all
    assert strip.n_strips == len(h.components)
    verify_gl_strip(h.triangles, strip.indices, strip.restart_index)
    for key, value in expected.items():
        if key == "non_manifold_edges" and "duplicate" in expected:
            continue  # the surface drops the copy first: the edges are clean again
        assert rep["defects"][key] == value, (key, rep["defects"])


def test_swaps_on_defect_surfaces():
    for name in ("klein", "one flipped triangle", "finned torus (bunny stand-in)"):
        pts, tri, _ = ALL[name]()
        h = surface_hamiltonian(pts, tri, swaps=True)
        assert h.report["verified"] and h.report["exact_surface"] is False


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 40), st.integers(3, 10))
def test_any_triangle_soup(seed, m, n):
    """Random triangles on few vertices: verified, or refused only when nothing has an area."""
    rng = np.random.default_rng(seed)
    tri = rng.integers(0, n, (m, 3))
    pts = rng.random((n, 3))
    try:
        h = surface_hamiltonian(pts, tri)
    except hammesh.InvalidMeshError as exc:
        assert "positive area" in str(exc)
        return
    n_pieces, cuts_in = _pieces_and_cuts(tri[np.unique(h.parent)])
    assert len(h.components) == n_pieces
    assert _pieces_and_cuts(h.triangles)[1] == cuts_in


def test_cli_surface_reports_defects(tmp_path):
    import json

    import meshio

    from hammesh.cli import main

    pts, tri, _ = ALL["klein"]()
    src = tmp_path / "klein.obj"
    meshio.write(src, meshio.Mesh(pts, [("triangle", tri)]))
    out = tmp_path / "k.vtu"
    rep = tmp_path / "r.json"
    code = main(["surface", str(src), "-o", str(out), "--report", str(rep)])
    assert code in (0, None)
    doc = json.loads(rep.read_text())
    found = doc.get("defects") or doc.get("report", {}).get("defects")
    assert found["non_orientable_pieces"] == 1 and found["flipped_neighbours"] == 12


@pytest.mark.parametrize("name", ["klein", "finned torus (bunny stand-in)", "one flipped triangle"])
def test_check_rereads_a_defect_surface(tmp_path, name):
    """`hammesh check` on what `hammesh surface` wrote: pieces across proper edges only.

    (Not the double-sided faces: ``read_surface`` welds exactly coincident points, and
    the two sides' incenters coincide, so the file reads back as another topology.)
    """
    from hammesh.cli import main
    from hammesh.surface import write_surface
    from hammesh.verify.surface import infer_surface_runs

    pts, tri, _ = ALL[name]()
    h = surface_hamiltonian(pts, tri)
    path = tmp_path / "out.vtu"
    write_surface(h, path)
    assert main(["check", str(path)]) in (0, None)
    assert infer_surface_runs(h.triangles, h.n_points).tolist() == h.components.tolist()
    if len(h.components) == 1:
        return
    # the first cycle's last triangle moved to the end of the file: its piece is split
    k = int(h.components[0])
    split = np.r_[h.triangles[: k - 1], h.triangles[k:], h.triangles[k - 1 : k]]
    with pytest.raises(hammesh.VerificationError, match="split over several runs"):
        infer_surface_runs(split, h.n_points)
