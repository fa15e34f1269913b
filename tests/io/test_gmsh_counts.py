"""A ``.msh`` file whose counts lie is refused in bounded time and memory (meshio's Gmsh
reader trusts them: ``hammesh.io.meshio_format._guarded_gmsh_read`` runs it in a child
with a budget scaled to the file's size); a sound file reads as before."""

from __future__ import annotations

import subprocess
import sys
import time

import numpy as np
import pytest

from hammesh.errors import FileFormatError
from hammesh.io import meshio_format, read_mesh

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the guard needs Linux's fork + rlimit")

HEAD = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
COORDS = "0 0 0\n1 0 0\n0 1 0\n"


def _msh(tag: int, strings: int = 1) -> str:
    return (HEAD + f"$Nodes\n1 3 1 {tag}\n2 0 0 3\n1\n2\n{tag}\n" + COORDS + "$EndNodes\n"
            f"$Elements\n1 1 1 1\n2 0 2 1\n1 1 2 {tag}\n$EndElements\n"
            f"$ElementData\n{strings}\n\"v\"\n1\n0.0\n3\n0\n1\n1\n1 1.0\n$EndElementData\n")


def test_a_sound_file_reads(tmp_path):
    path = tmp_path / "ok.msh"
    path.write_text(_msh(3))
    m = read_mesh(path)
    assert m.triangles.tolist() == [[0, 1, 2]] and m.points.shape == (3, 2)


def test_a_huge_node_tag_is_refused_within_the_budget(tmp_path):
    path = tmp_path / "tag.msh"
    path.write_text(_msh(2**31 + 2))  # meshio: np.full(max tag + 1) = 16 GiB
    t = time.perf_counter()
    with pytest.raises(FileFormatError, match="tag.msh"):
        read_mesh(path)
    assert time.perf_counter() - t < 30


def test_a_string_count_past_the_end_is_stopped(tmp_path, monkeypatch):
    monkeypatch.setattr(meshio_format, "GMSH_SECONDS_BASE", 2.0)
    path = tmp_path / "strings.msh"
    path.write_text(_msh(3, strings=2**31))  # meshio: readline() 2^31 times past the end
    t = time.perf_counter()
    with pytest.raises(FileFormatError, match=r"strings\.msh: .*did not finish within 2 s"):
        read_mesh(path)
    assert time.perf_counter() - t < 30


def test_the_cli_says_it_in_one_line(tmp_path):
    path = tmp_path / "tag.msh"
    path.write_text(_msh(2**31 + 2))
    out = tmp_path / "o.vtu"
    p = subprocess.run([sys.executable, "-m", "hammesh", "mesh", str(path), "-o", str(out)], capture_output=True,
                       text=True, timeout=120)
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1 and "tag.msh" in p.stderr
    assert not out.exists()
    np.testing.assert_array_equal(sorted(p.name for p in tmp_path.iterdir()), ["tag.msh"])
