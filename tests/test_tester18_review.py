"""Session 18 tester review: tampered outputs, mesh-file data and output siblings.

Each open finding of ``/tmp/tester18/FINDINGS.md`` is an ``xfail(strict=True)`` test
named by its id (rNN): it fails on main e295856 and turns into a pass when the
finding is fixed (then drop the mark). The passing tests pin what the review found
sound (``hammesh check`` rejects rows swapped, a triangle flipped or dropped).
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import meshio
import numpy as np
import pytest

import hammesh
from hammesh.cli import main

DEMO = Path(hammesh.__file__).parent / "data" / "demo.poly"


def _plate(tmp_path: Path) -> Path:
    """The demo plate meshed by hammesh (a verified one-cycle .vtu)."""
    out = tmp_path / "plate.vtu"
    assert main(["mesh", str(DEMO), "-q", "30", "-a", "0.05", "-o", str(out)]) == 0
    return out


def _rewrite(src: Path, dst: Path, edit) -> Path:
    """``src`` read by meshio, changed by ``edit(mesh)``, written to ``dst``."""
    m = meshio.read(src)
    edit(m)
    meshio.write(dst, m)
    return dst


def _permute(m: meshio.Mesh, order: np.ndarray) -> None:
    m.cells = [meshio.CellBlock("triangle", m.cells[0].data[order])]
    m.cell_data = {k: [v[0][order]] for k, v in m.cell_data.items()}


@pytest.fixture(scope="module")
def plate(tmp_path_factory) -> Path:
    return _plate(tmp_path_factory.mktemp("plate"))


def test_check_accepts_the_untampered_meshio_rewrite(plate, tmp_path):
    out = _rewrite(plate, tmp_path / "same.vtu", lambda m: None)
    assert main(["check", str(out)]) == 0


@pytest.mark.parametrize("tamper", ["swap", "flip", "drop", "duplicate"])
def test_check_rejects_tampered_rows(plate, tmp_path, tamper, capsys):
    def edit(m):
        n = len(m.cells[0].data)
        if tamper == "swap":
            o = np.arange(n)
            o[[5, n // 2]] = o[[n // 2, 5]]
            _permute(m, o)
        elif tamper == "flip":
            t = m.cells[0].data.copy()
            t[7] = t[7][::-1]
            m.cells = [meshio.CellBlock("triangle", t)]
        elif tamper == "drop":
            _permute(m, np.delete(np.arange(n), n // 2))
        else:
            _permute(m, np.r_[np.arange(n), 0])

    out = _rewrite(plate, tmp_path / f"{tamper}.vtu", edit)
    assert main(["check", str(out)]) == 3
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "verification failed" in err[0]


@pytest.mark.parametrize("field", ["cycle_position", "cycle_id"])
def test_check_rejects_corrupted_cycle_fields(plate, tmp_path, field):
    def edit(m):
        v = m.cell_data[field][0].copy()
        if field == "cycle_position":
            v[[3, 9]] = v[[9, 3]]
        else:
            v[4] = 7
        m.cell_data[field] = [v]

    out = _rewrite(plate, tmp_path / f"{field}.vtu", edit)
    assert main(["check", str(out)]) == 3


def test_pvtu_piece_unreadable_is_a_file_format_error(tmp_path):
    mesh = hammesh.read_mesh(_plate(tmp_path))
    index = tmp_path / "one.pvtu"
    hammesh.write(mesh, index)
    piece = tmp_path / "one.0.vtu"
    assert piece.is_file()
    piece.write_text("hello\n")
    try:
        hammesh.read_mesh(index)
    except hammesh.FileFormatError:
        return
    except SystemExit as exc:  # (what meshio does)
        pytest.fail(f"SystemExit({exc.code}) instead of FileFormatError")
    pytest.fail("an unreadable piece was accepted")


@pytest.mark.slow
def test_check_rejects_pvtu_without_its_last_piece(tmp_path):
    out = tmp_path / "part"
    rc = subprocess.run([sys.executable, "-m", "hammesh", "mesh", str(DEMO), "-q", "30", "-a", "0.01", "--tiles", "2",
                         "--partitioned", "-o", str(out)], capture_output=True, timeout=900).returncode
    assert rc == 0
    index = out / "mesh.pvtu"
    text = index.read_text()
    pieces = sorted(p.name for p in out.glob("piece_*.vtu"))
    assert len(pieces) >= 2
    index.write_text(re.sub(f'<Piece Source="{pieces[-1]}"[^>]*/>', "", text))
    assert main(["check", str(index)]) != 0


def _tiny(tmp_path: Path, scale: float) -> Path:
    m = meshio.read(_plate(tmp_path))
    out = tmp_path / "tiny.vtu"
    meshio.write(out, meshio.Mesh(m.points * scale, [("triangle", m.cells_dict["triangle"])]))
    return out


def test_tiny_mesh_file_is_bad_input_not_failed_verification(tmp_path):
    assert main(["mesh", str(_tiny(tmp_path, 1e-90)), "-o", str(tmp_path / "o.vtu")]) == 2


def test_ele_output_does_not_clobber_the_users_poly(tmp_path):
    domain = tmp_path / "plate.poly"
    domain.write_bytes(DEMO.read_bytes())
    vtu = tmp_path / "plate.vtu"
    assert main(["mesh", str(domain), "-q", "30", "-a", "0.05", "-o", str(vtu)]) == 0
    rc = main(["mesh", str(vtu), "-o", str(tmp_path / "plate.ele")])
    assert domain.read_bytes() == DEMO.read_bytes(), f"plate.poly overwritten (exit {rc})"


def _square_with_lines(path: Path, **cell_data) -> Path:
    pts = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5]], float)
    tri = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
    lines = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])
    kw = {"file_format": "gmsh22", "binary": False} if path.suffix == ".msh" else {}
    meshio.write(path, meshio.Mesh(pts, [("line", lines), ("triangle", tri)], cell_data=cell_data), **kw)
    return path


def test_line_cell_data_is_carried_or_reported(tmp_path):
    src = _square_with_lines(tmp_path / "lines.vtu", bc=[np.array([7, 8, 9, 10]), np.zeros(4, int)])
    out, rep = tmp_path / "o.vtu", tmp_path / "r.json"
    assert main(["mesh", str(src), "-o", str(out), "--report", str(rep)]) == 0
    markers = set(np.asarray(hammesh.read_mesh(out).segment_markers).tolist())
    noted = "bc" in json.dumps(json.loads(rep.read_text()).get("not_carried", []))
    assert {7, 8, 9, 10} <= markers or noted


def test_msh_output_keeps_physical_surfaces_of_a_small_mesh(tmp_path):
    """r06 (fixed in session 19): 5 points, 4 segment markers and two surface tags are
    more Gmsh entities than nodes; the segments' entities are merged (their markers
    stay in ``segment_marker``), not the triangles'."""
    src = _square_with_lines(tmp_path / "tags.msh",
                             **{"gmsh:physical": [np.array([11, 12, 13, 14]), np.array([100, 100, 200, 200])],
                                "gmsh:geometrical": [np.array([1, 2, 3, 4]), np.ones(4, int)]})
    out = tmp_path / "o.msh"
    assert main(["mesh", str(src), "-o", str(out)]) == 0
    m = meshio.read(out)
    for i, c in enumerate(m.cells):
        if c.type == "triangle":
            np.testing.assert_array_equal(m.cell_data["gmsh:physical"][i], m.cell_data["physical"][i])
    assert {100, 200} <= set(np.concatenate([m.cell_data["gmsh:physical"][i] for i, c in enumerate(m.cells)
                                             if c.type == "triangle"]).tolist())
    back = hammesh.read_mesh(out)
    assert sorted(back.segment_markers.tolist()) == [11, 12, 13, 14]


def test_pvtu_output_keeps_or_reports_the_segments(tmp_path, capsys):
    out, rep = tmp_path / "s.pvtu", tmp_path / "s.json"
    assert main(["mesh", str(DEMO), "-q", "30", "-a", "0.05", "-o", str(out), "--report", str(rep)]) == 0
    noted = "constrained edges" in capsys.readouterr().out
    assert len(hammesh.read_mesh(out).segments) > 0 or noted
