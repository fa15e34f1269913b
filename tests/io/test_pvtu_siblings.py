"""A ``.pvtu`` write creates two files: both are output paths (checked, cleaned up)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import hammesh
from hammesh.io import check_outputs
from hammesh.io.paths import written_files


def test_pvtu_write_names_its_piece(tmp_path: Path) -> None:
    target = tmp_path / "out.pvtu"
    dom = hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])
    hammesh.write(hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=25, max_area=0.05)), target)
    made = sorted(p.name for p in tmp_path.iterdir())
    assert made == sorted(p.name for p in written_files(target))


def test_pvtu_piece_never_overwrites_the_input(tmp_path: Path) -> None:
    dom = hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])
    source = tmp_path / "out.0.vtu"  # the name the piece of out.pvtu would take
    hammesh.write(hammesh.quality_mesh(dom, min_angle=25, max_area=0.05), source)
    before = source.read_bytes()
    try:
        check_outputs({"mesh": tmp_path / "out.pvtu"}, inputs=(source,))
    except hammesh.HammeshError as e:
        assert "out.0.vtu" in str(e)
    else:
        raise AssertionError("a .pvtu whose piece is the input was accepted")
    r = subprocess.run([sys.executable, "-m", "hammesh", "mesh", str(source), "-o", str(tmp_path / "out.pvtu")],
                       capture_output=True, text=True)
    assert r.returncode == 2, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
    assert source.read_bytes() == before
    assert not (tmp_path / "out.pvtu").exists()
