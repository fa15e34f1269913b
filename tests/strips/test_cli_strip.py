"""``hammesh strip`` (module-level: registered by the lead in hammesh.cli.COMMANDS)."""

from __future__ import annotations

import argparse
import json

import meshio
import numpy as np
import pytest

import hammesh
from hammesh.cli import strip as strip_cli
from hammesh.errors import FileFormatError
from hammesh.io import read_mesh
from hammesh.strips import decode_generalized, decode_gl_strip
from hammesh.strips.generalized import GeneralizedStrips

from .conftest import oriented_set, square_hamiltonian, torus_mesh


def run(argv):
    p = argparse.ArgumentParser()
    strip_cli.add_args(p)
    return strip_cli.run(p.parse_args([str(a) for a in argv]))


@pytest.fixture(scope="module")
def ham_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("strip") / "h.vtu"
    hammesh.write(square_hamiltonian(), path)
    return path


@pytest.fixture(scope="module")
def torus_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("strip") / "torus.off"
    t = torus_mesh()
    meshio.write(path, meshio.Mesh(t.points, [("triangle", t.triangles)]))
    return path


@pytest.mark.parametrize("join", ["restart", "stitch"])
def test_json_contract_and_round_trip(ham_file, tmp_path, join, capsys):
    out = tmp_path / "s.json"
    assert run([ham_file, "-o", out, "--join", join]) == 0
    doc = json.loads(out.read_text())
    assert doc["primitive"] == "triangle_strip"
    h = square_hamiltonian()
    assert doc["triangles"] == h.n_triangles
    assert doc["restart_index"] == (0xFFFFFFFF if join == "restart" else None)
    assert doc["indices_per_triangle"] == pytest.approx(len(doc["indices"]) / h.n_triangles)
    assert doc["strips"] >= 1 and doc["method"] in ("greedy", "order", "rows", "zigzag")  # (auto's candidates)
    tri = decode_gl_strip(np.array(doc["indices"]), doc["restart_index"])
    assert oriented_set(tri) == oriented_set(h.triangles)
    assert "indices per triangle" in capsys.readouterr().out
    assert [p.name for p in tmp_path.iterdir()] == ["s.json"]  # atomic: no temporaries left


def test_order_method_gives_one_strip(ham_file, tmp_path):
    out = tmp_path / "s.json"
    run([ham_file, "-o", out, "--method", "order"])
    doc = json.loads(out.read_text())
    assert doc["strips"] == 1
    assert len(doc["indices"]) == doc["triangles"] + 2 + doc["swaps"]


def test_npz_and_3d_surface(torus_file, tmp_path):
    out = tmp_path / "t.npz"
    run([torus_file, "-o", out])
    z = np.load(out)
    assert z["indices"].dtype == np.uint32
    t = torus_mesh()
    tri = decode_gl_strip(z["indices"].astype(np.int64), int(z["restart_index"]))
    assert oriented_set(tri) == oriented_set(read_mesh(torus_file, dim=None).triangles)
    assert int(z["triangles"]) == t.n_triangles


def test_generalized(torus_file, tmp_path):
    out = tmp_path / "g.json"
    run([torus_file, "-o", out, "--generalized"])
    doc = json.loads(out.read_text())
    assert doc["primitive"] == "generalized_strip"
    g = GeneralizedStrips(
        np.array(doc["indices"]),
        np.array(doc["swap_bits"], bool),
        np.array(doc["strip_starts"]),
        np.r_[0, np.cumsum(np.diff(doc["strip_starts"]) - 2)],
    )
    assert oriented_set(decode_generalized(g)) == oriented_set(read_mesh(torus_file, dim=None).triangles)


def test_christofides_reports_bound(ham_file, tmp_path):
    out = tmp_path / "c.json"
    run([ham_file, "-o", out, "--method", "christofides", "--join", "stitch"])
    doc = json.loads(out.read_text())
    rep = doc["christofides"]
    assert rep["indices"] <= rep["bound_9_4"]
    assert doc["triangles"] == square_hamiltonian().n_triangles


def test_errors(tmp_path, ham_file):
    with pytest.raises(FileFormatError, match="no such file"):
        run([tmp_path / "missing.vtu", "-o", tmp_path / "x.json"])
    with pytest.raises(FileFormatError, match=".json or .npz"):
        run([ham_file, "-o", tmp_path / "x.txt"])
    bad = tmp_path / "nm.obj"
    pts = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]])
    meshio.write(bad, meshio.Mesh(pts, [("triangle", np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]]))]))
    run([bad, "-o", tmp_path / "x.json"])  # a non-manifold edge is cut, not refused
    doc = json.loads((tmp_path / "x.json").read_text())
    assert doc["defect_non_manifold_edges"] == 1 and doc["triangles"] == 3


def test_fast_is_the_greedy_cover_alone(torus_file, tmp_path):
    out = tmp_path / "f.json"
    run([torus_file, "-o", out, "--fast"])
    doc = json.loads(out.read_text())
    assert doc["method"] == "fast"
    assert oriented_set(decode_gl_strip(np.array(doc["indices"]), doc["restart_index"])) == oriented_set(
        read_mesh(torus_file, dim=None).triangles
    )
    run([torus_file, "-o", tmp_path / "d.json"])
    assert len(doc["indices"]) >= len(json.loads((tmp_path / "d.json").read_text())["indices"])
    from hammesh.errors import InvalidOptionError

    for bad in (["--cache", "16"], ["--generalized"], ["--method", "zigzag"]):
        with pytest.raises(InvalidOptionError, match="fast"):
            run([torus_file, "-o", tmp_path / "g.json", "--fast", *bad])
        assert not (tmp_path / "g.json").exists()
