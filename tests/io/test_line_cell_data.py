"""Cell data on a VTK file's line cells is carried: a whole-numbered field becomes the
segment markers (the output's ``edge_marker``), any other is listed as not carried
(tester18 r04: boundary-condition ids on lines were dropped in silence)."""

from __future__ import annotations

from pathlib import Path

import meshio
import numpy as np
import pytest

import hammesh
from hammesh.cli import main

PTS = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5]], float)
TRI = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
LINES = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])


def write(path: Path, cell_data: dict) -> Path:
    meshio.write(path, meshio.Mesh(PTS, [("line", LINES), ("triangle", TRI)], cell_data=cell_data))
    return path


@pytest.mark.parametrize("suffix", [".vtu", ".vtk"])
def test_a_whole_numbered_line_field_becomes_the_segment_markers(tmp_path: Path, suffix: str) -> None:
    src = write(tmp_path / f"bc{suffix}", {"bc": [np.array([7, 8, 9, 10]), np.zeros(4, int)]})
    m = hammesh.read_mesh(src)
    got = {tuple(sorted(s)): k for s, k in zip(m.segments.tolist(), m.segment_markers.tolist())}
    assert got == {tuple(sorted(s)): k for s, k in zip(LINES.tolist(), [7, 8, 9, 10])}
    assert "not_carried" not in (m.info or {})
    out = tmp_path / "out.vtu"
    assert main(["mesh", str(src), "-o", str(out)]) == 0
    back = hammesh.read_mesh(out)
    assert sorted(set(back.segment_markers.tolist())) == [7, 8, 9, 10]


def test_other_line_fields_are_listed_as_not_carried(tmp_path: Path, capsys) -> None:
    src = write(tmp_path / "two.vtu", {"bc": [np.array([7, 8, 9, 10]), np.zeros(4, int)],
                                       "flux": [np.array([0.5, 0.0, 1.5, 2.0]), np.zeros(4)]})
    m = hammesh.read_mesh(src)
    assert sorted(set(m.segment_markers.tolist())) == [7, 8, 9, 10]
    notes = m.info["not_carried"]
    assert any("'flux' on 4 line cells" in n for n in notes)
    assert main(["mesh", str(src), "-o", str(tmp_path / "o.vtu")]) == 0
    assert "note: cell data 'flux' on 4 line cells" in capsys.readouterr().out


def test_zero_line_data_and_named_markers_take_precedence(tmp_path: Path) -> None:
    src = write(tmp_path / "z.vtu", {"segment_marker": [np.array([1, 2, 3, 4]), np.zeros(4, int)],
                                     "zero": [np.zeros(4, int), np.ones(4, int)]})
    m = hammesh.read_mesh(src)
    assert m.segment_markers.tolist() == [1, 2, 3, 4]
    assert "not_carried" not in (m.info or {})
