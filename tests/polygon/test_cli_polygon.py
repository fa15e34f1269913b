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
        got = hammesh.io.read_polygon(f)
        assert got.shape == (4, 2)
        assert _run([f, "-o", tmp_path / (f.stem + f.suffix[1:] + ".json")]) == 0


@pytest.mark.parametrize("name, text, match", [
    ("b.txt", "0 0\n1 0 2\n", "expected two numbers 'x y'"),
    ("b.txt", "# nothing\n", "no points"),
    ("b.wkt", "POLYGON ((0 0, 1 0, 0 1), 0.1 0.1, 0.2 0.1)", "expected 'POLYGON"),
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


def _ring_square(s, x0=0.0, y0=0.0):
    return [[x0, y0], [x0 + s, y0], [x0 + s, y0 + s], [x0, y0 + s]]


@pytest.mark.parametrize("fmt", ["wkt", "geojson", "poly"])
def test_holes_steiner_reports_k_method_and_count(tmp_path, capsys, fmt):
    outer = _ring_square(10.0)
    hole = _ring_square(2.0, 4.0, 4.0)[::-1]
    f = tmp_path / f"h.{fmt}"
    if fmt == "wkt":
        ring = lambda r: "(" + ", ".join(f"{x} {y}" for x, y in r + r[:1]) + ")"
        f.write_text(f"POLYGON ({ring(outer)}, {ring(hole)})")
    elif fmt == "geojson":
        f.write_text(json.dumps({"type": "Polygon", "coordinates": [outer + outer[:1], hole + hole[:1]]}))
    else:
        pts = outer + hole
        lines = [f"{len(pts)} 2 0 0"] + [f"{i + 1} {x} {y}" for i, (x, y) in enumerate(pts)]
        segs = [(i, (i + 1) % 4) for i in range(4)] + [(4 + i, 4 + (i + 1) % 4) for i in range(4)]
        lines += [f"{len(segs)} 0"] + [f"{k + 1} {a + 1} {b + 1}" for k, (a, b) in enumerate(segs)]
        lines += ["1", "1 5 5"]
        f.write_text("\n".join(lines) + "\n")
    out = tmp_path / "o.json"
    assert _run([f, "--steiner", "cycle", "-o", out, "--png", tmp_path / "o.png"]) == 0
    doc = json.loads(out.read_text())
    T, Q = np.array(doc["triangles"]), np.array(doc["points"])
    checks.assert_triangulates_domain([np.array(outer), np.array(hole)], Q, T)
    checks.assert_dual_path(T, cycle=True)
    said = capsys.readouterr().out
    k = doc["k"]
    assert doc["n_steiner"] == k - 1 == len(Q) - 8
    assert f"with {k - 1} Steiner points (k = {k} convex pieces, method hertel-mehlhorn)" in said


def test_holes_without_steiner_and_refusals(tmp_path):
    f = tmp_path / "h.geojson"
    outer, hole = _ring_square(10.0), _ring_square(2.0, 4.0, 4.0)
    f.write_text(json.dumps({"type": "Polygon", "coordinates": [outer, hole]}))
    out = tmp_path / "o.json"
    assert _run([f, "-o", out]) == 0      # Thm 2.2, exact: the square annulus has one
    T = np.array(json.loads(out.read_text())["triangles"])
    checks.assert_dual_path(T)
    with pytest.raises(InvalidDomainError, match="--sequential is for polygons without holes"):
        _run([f, "--sequential"])
    with pytest.raises(hammesh.errors.InvalidOptionError, match="NP-hard"):
        _run([f, "--steiner", "path", "--decomposition", "optimal"])


def test_comb_reports_the_minimum(tmp_path, capsys):
    f = _text(tmp_path, shapes.comb(11))
    assert _run([f, "--steiner", "cycle"]) == 0
    assert "with 11 Steiner points (k = 12 convex pieces, method optimal)" in capsys.readouterr().out
    assert _run([f, "--steiner", "cycle", "--decomposition", "hertel-mehlhorn"]) == 0
    assert "method hertel-mehlhorn" in capsys.readouterr().out
