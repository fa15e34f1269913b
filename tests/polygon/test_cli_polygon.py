"""``hammesh polygon`` (module-level: the lead registers it in hammesh.cli.COMMANDS)."""

import argparse
import json

import numpy as np
import pytest

import hammesh
from hammesh.cli import polygon as cmd
from hammesh.errors import FileFormatError, InvalidDomainError
from tests.polygon import checks, shapes


def _run(argv):
    p = argparse.ArgumentParser()
    cmd.add_args(p)
    return cmd.run(p.parse_args([str(a) for a in argv]))


def _text(tmp_path, pts, name="p.txt"):
    f = tmp_path / name
    f.write_text("# polygon\n" + "\n".join(f"{x!r} {y!r}" for x, y in np.asarray(pts).tolist()) + "\n")
    return f


def test_hamiltonian_json_and_png(tmp_path, capsys):
    f = _text(tmp_path, shapes.regular(7))
    out, png = tmp_path / "o.json", tmp_path / "o.png"
    assert _run([f, "-o", out, "--png", png]) == 0
    doc = json.loads(out.read_text())
    T = np.array(doc["triangles"])
    checks.assert_triangulates(shapes.regular(7), np.array(doc["points"]), T)
    checks.assert_dual_path(T)
    assert png.stat().st_size > 1000
    assert "Hamiltonian triangulation, 5 triangles" in capsys.readouterr().out


def test_sequential_and_steiner_mesh_output(tmp_path):
    f = _text(tmp_path, shapes.comb(3))
    with pytest.raises(InvalidDomainError, match="no sequential triangulation"):
        _run([f, "--sequential", "-o", tmp_path / "s.json"])
    assert not (tmp_path / "s.json").exists()
    with pytest.raises(InvalidDomainError, match="--steiner path"):
        _run([f])
    out = tmp_path / "c.vtu"
    assert _run([f, "--steiner", "cycle", "-o", out, "--png", tmp_path / "c.png"]) == 0
    m = hammesh.read_mesh(out)
    checks.assert_dual_path(m.triangles, cycle=True)


def test_poly_geojson_wkt_inputs(tmp_path):
    sq = [[0, 0], [1, 0], [1, 1], [0, 1]]
    poly = tmp_path / "a.poly"
    poly.write_text("4 2 0 0\n1 0 0\n2 1 0\n3 1 1\n4 0 1\n4 0\n1 2 1\n2 3 2\n3 4 3\n4 1 4\n0\n")
    gj = tmp_path / "a.geojson"
    gj.write_text(json.dumps({"type": "Polygon", "coordinates": [sq + [sq[0]]]}))
    wkt = tmp_path / "a.wkt"
    wkt.write_text("POLYGON ((0 0, 1 0, 1 1, 0 1, 0 0))")
    for f in (poly, gj, wkt):
        got = cmd.read_polygon(f)
        assert got.shape == (4, 2)
        assert _run([f, "-o", tmp_path / (f.stem + f.suffix[1:] + ".json")]) == 0


@pytest.mark.parametrize("name, text, match", [
    ("b.txt", "0 0\n1 0 2\n", "expected two numbers 'x y'"),
    ("b.txt", "# nothing\n", "no points"),
    ("b.wkt", "POLYGON ((0 0, 1 0, 0 1), (0.1 0.1, 0.2 0.1, 0.1 0.2))", "without holes"),
    ("b.geojson", '{"type": "Point", "coordinates": [0, 0]}', "expected a GeoJSON Polygon"),
    ("b.wkt", "POLYGON ((0 0, 1 x, 0 1))", "b.wkt: coordinates cannot be converted"),
    ("b.wkt", "POLYGON ((0 0 0, 1 0 0, 0 1 0))", r"b.wkt: coordinates must have shape \(k, 2\)"),
])
def test_bad_files(tmp_path, name, text, match):
    f = tmp_path / name
    f.write_text(text)
    with pytest.raises(FileFormatError, match=match):
        _run([f, "-o", tmp_path / "x.json"])


def test_invalid_polygon_is_one_line(tmp_path):
    f = _text(tmp_path, [[0, 0], [1, 1], [1, 0], [0, 1]])
    with pytest.raises(InvalidDomainError, match="edges 0 and 2 cross"):
        _run([f])
