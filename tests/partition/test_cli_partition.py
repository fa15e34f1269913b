"""``hammesh mesh --parts/--renumber`` and ``hammesh partition``."""

from __future__ import annotations

import json
from pathlib import Path

import meshio
import numpy as np
import pytest

import hammesh
from hammesh.cli import main
from hammesh.partition import cycle_runs, dual_edges, part_components

DEMO = Path(hammesh.__file__).parent / "data" / "demo.poly"


def _parts_of(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    m = meshio.read(path)
    blocks = [i for i, c in enumerate(m.cells) if c.type == "triangle"]
    tri = np.concatenate([m.cells[i].data for i in blocks])
    part = np.concatenate([np.asarray(m.cell_data["part"][i]) for i in blocks]).astype(np.int64)
    return m.points[:, :2], tri, part


@pytest.mark.parametrize("mode", ["sparse", "incircle"])
def test_mesh_with_parts_writes_connected_balanced_parts(tmp_path, mode: str, capsys) -> None:
    out, rep = tmp_path / "d.vtu", tmp_path / "d.json"
    code = main(["mesh", str(DEMO), "-q", "30", "-a", "0.01", "--mode", mode, "-o", str(out),
                 "--report", str(rep), "--parts", "5", "--renumber", "rcm"])
    assert code == 0
    pts, tri, part = _parts_of(out)
    sizes = np.bincount(part)
    assert len(sizes) == 5 and sizes.max() - sizes.min() <= 1
    a, b = dual_edges(tri)
    assert part_components(part, 5, a, b).tolist() == [1] * 5
    report = json.loads(rep.read_text())
    assert report["partition"]["edge_cut"] == int((part[a] != part[b]).sum())
    assert report["numbering"]["method"] == "rcm" and report["numbering"]["bandwidth"] > 0
    assert main(["check", str(out)]) == 0  # still a verified cycle mesh


def test_partition_command_round_trip(tmp_path, capsys) -> None:
    src, out, rep = tmp_path / "d.vtu", tmp_path / "d8.vtu", tmp_path / "p.json"
    assert main(["mesh", str(DEMO), "-q", "30", "-a", "0.01", "-o", str(src)]) == 0
    assert main(["partition", str(src), "-k", "8", "-o", str(out), "--report", str(rep)]) == 0
    assert "all parts connected" in capsys.readouterr().out
    _, tri, part = _parts_of(out)
    back = hammesh.read_mesh(src)
    np.testing.assert_array_equal(tri, back.triangles)  # rows and vertices kept
    runs = cycle_runs(tri)
    assert len(runs) == 1
    assert int((part != np.roll(part, 1)).sum()) == 8  # 8 stretches of the cycle
    assert json.loads(rep.read_text())["partition"]["k"] == 8


@pytest.mark.parametrize("argv, message", [(["-k", "0"], "--parts=0"), (["-k", "-3"], "--parts=-3")])
def test_partition_command_refuses_bad_options(tmp_path, argv, message, capsys) -> None:
    src = tmp_path / "d.vtu"
    assert main(["mesh", str(DEMO), "-q", "25", "-a", "0.05", "-o", str(src)]) == 0
    capsys.readouterr()
    out = tmp_path / "x.vtu"
    assert main(["partition", str(src), "-o", str(out), *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_partition_command_refuses_a_file_out_of_cycle_order(tmp_path, capsys) -> None:
    """A mesh not written in cycle order: one line, exit 2, nothing written."""
    g = meshio.Mesh(np.array([[0, 0], [1, 0], [1, 1], [0, 1], [2, 0], [2, 1]], float),
                    [("triangle", np.array([[0, 1, 2], [4, 5, 2], [0, 2, 3], [1, 4, 2]]))])
    src = tmp_path / "g.vtu"
    g.write(src)
    out = tmp_path / "x.vtu"
    assert main(["partition", str(src), "-k", "2", "-o", str(out)]) == 2
    assert "cycle order" in capsys.readouterr().err and not out.exists()


def test_partition_command_never_overwrites_its_input(tmp_path, capsys) -> None:
    src = tmp_path / "d.vtu"
    assert main(["mesh", str(DEMO), "-q", "25", "-a", "0.05", "-o", str(src)]) == 0
    before = src.read_bytes()
    assert main(["partition", str(src), "-k", "2", "-o", str(src)]) == 2
    assert src.read_bytes() == before


def test_mesh_refuses_zero_parts(tmp_path, capsys) -> None:
    out = tmp_path / "d.vtu"
    assert main(["mesh", str(DEMO), "-q", "25", "-a", "0.05", "-o", str(out), "--parts", "0"]) == 2
    assert not out.exists()


@pytest.mark.parametrize("fault", ["moved vertex", "swapped rows"])
def test_partition_refuses_a_file_that_is_no_cycle_mesh(tmp_path, fault: str, capsys) -> None:
    # (session 17's tester: a vertex moved far in hammesh's own output was cut into
    # "all parts connected" parts, and `hammesh check` refused the written file)
    src = tmp_path / "d.vtu"
    assert main(["mesh", str(DEMO), "-q", "30", "-a", "0.05", "-o", str(src)]) == 0
    m = meshio.read(src)
    if fault == "moved vertex":
        m.points[m.cells[0].data[10, 0], 0] += 3.0
    else:
        block = m.cells[0].data
        block[[3, len(block) // 2]] = block[[len(block) // 2, 3]]
    bad, out = tmp_path / "bad.vtu", tmp_path / "p.vtu"
    meshio.write(bad, m)
    capsys.readouterr()
    assert main(["partition", str(bad), "-k", "3", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not a verified Hamiltonian cycle mesh" in err[0]
    assert not out.exists()
    assert main(["partition", str(src), "-k", "3", "-o", str(out)]) == 0  # (the file as written is cut)
