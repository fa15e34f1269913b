"""A ``.pvtu`` index knows its pieces: a piece left out, replaced, moved or unreadable is
named (exit 2), never read as a smaller or different mesh (tester18 r01, r02)."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import hammesh
from hammesh.io import pvtu, vtu


@pytest.fixture(scope="module")
def two_pieces(tmp_path_factory) -> Path:
    """One Hamiltonian cycle written as two pieces (the first and second half of its rows),
    as the partitioned output writes them: global point ids and global positions."""
    dom = hammesh.Domain.from_polygon([[0, 0], [2, 0], [2, 1], [0, 1]], holes=[[[0.8, 0.4], [1.2, 0.4], [1, 0.6]]])
    h = hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=28, max_area=0.01))
    d = tmp_path_factory.mktemp("pieces")
    m = h.n_triangles
    names = []
    for i, rows in enumerate((np.arange(m // 2), np.arange(m // 2, m))):
        ids = np.unique(h.triangles[rows])
        name = f"piece_{i:04d}.vtu"
        pvtu.write_piece(d / name, ids, h.points[ids], h.triangles[rows], rows, None, None, h.parent[rows],
                         h.kind[rows], np.zeros((len(rows), 0)))
        names.append(name)
    pvtu.write_index(d / "mesh.pvtu", names, cycles=False)
    return d


def check(index: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "hammesh", "check", str(index)], capture_output=True, text=True)


def test_the_index_records_its_pieces_and_passes(two_pieces: Path) -> None:
    total, n_pieces, listed = pvtu.index_counts(two_pieces / "mesh.pvtu")
    assert n_pieces == 2 and total == sum(listed)
    assert listed == [pvtu.piece_cells(two_pieces / f"piece_{i:04d}.vtu") for i in range(2)]
    r = check(two_pieces / "mesh.pvtu")
    assert r.returncode == 0, r.stderr
    assert f"{total:,} triangles in 1 Hamiltonian cycle" in r.stdout


def tampered(src: Path, tmp_path: Path, how: str) -> Path:
    d = tmp_path / "t"
    shutil.copytree(src, d)
    index = d / "mesh.pvtu"
    if how == "last piece left out":
        text = index.read_text()
        start = text.index('<Piece Source="piece_0001.vtu"')
        index.write_text(text[:start] + text[text.index("/>", start) + 2:])
    elif how == "piece replaced by the other":
        shutil.copy(d / "piece_0000.vtu", d / "piece_0001.vtu")
    elif how == "piece unreadable":
        (d / "piece_0001.vtu").write_text("hello\n")
    elif how == "piece empty":
        (d / "piece_0001.vtu").write_bytes(b"")
    elif how == "counts left out, last piece left out":  # an index of another writer: positions
        text = index.read_text()
        for name in ("NumberOfCells", "NumberOfPieces"):
            while f' {name}="' in text:
                a = text.index(f' {name}="')
                text = text[:a] + text[text.index('"', a + len(name) + 3) + 1:]
        start = text.index('<Piece Source="piece_0000.vtu"')
        index.write_text(text[:start] + text[text.index("/>", start) + 2:])
    else:
        raise AssertionError(how)
    return index


@pytest.mark.parametrize("how", ["last piece left out", "piece replaced by the other", "piece unreadable",
                                 "piece empty", "counts left out, last piece left out"])
def test_a_tampered_index_is_refused_by_name(two_pieces: Path, tmp_path: Path, how: str) -> None:
    r = check(tampered(two_pieces, tmp_path, how))
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("hammesh: error:"), r.stderr
    assert "Traceback" not in r.stderr and r.stdout == ""


def test_a_moved_shared_point_is_refused(two_pieces: Path, tmp_path: Path) -> None:
    """Both pieces hold the points where the halves meet: one moved in one piece is named."""
    d = tmp_path / "t"
    shutil.copytree(two_pieces, d)
    gid0, gid1 = (vtu.read_raw(d / f"piece_{i:04d}.vtu")[("PointData", "global_id")] for i in range(2))
    shared = np.intersect1d(gid0, gid1)
    assert len(shared)
    piece = vtu.read_raw(d / "piece_0001.vtu")
    pts = np.asarray(piece[("Points", "points")])[:, :2].copy()
    pts[np.flatnonzero(np.isin(gid1, shared))[0]] += [1e-3, 0.0]
    t = piece[("Cells", "connectivity")].astype(np.int64).reshape(-1, 3)
    zeros = np.zeros(len(t), np.int64)
    pvtu.write_piece(d / "piece_0001.vtu", gid1, pts, t, piece[("CellData", "global_position")], None, None,
                     zeros, zeros, np.zeros((len(t), 0)), local=True)
    assert pvtu.piece_cells(d / "piece_0001.vtu") == len(t)
    r = check(d / "mesh.pvtu")
    assert r.returncode == 2 and "different places" in r.stderr, r.stderr


def test_a_pvtu_keeps_the_constrained_edges_and_markers(tmp_path: Path) -> None:
    """tester18 r08: the serial .pvtu dropped the segments (the boundary conditions) in silence."""
    from tests.helpers import plate

    h = hammesh.hamiltonian(plate(2, 1, max_area=0.01))
    assert len(h.segments) and h.segment_markers.any()
    hammesh.write(h, tmp_path / "h.pvtu")
    back = hammesh.read_mesh(tmp_path / "h.pvtu")

    def edges(m) -> set:
        return {(min(a, b), max(a, b), k) for (a, b), k in zip(m.segments.tolist(), m.segment_markers.tolist())}

    assert edges(back) == edges(h)
    assert hammesh.io.unwritten_data(h, tmp_path / "h.pvtu") == []
    r = check(tmp_path / "h.pvtu")
    assert r.returncode == 0, r.stderr
