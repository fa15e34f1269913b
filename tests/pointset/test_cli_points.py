"""``hammesh points`` (tested through its module: the lead registers it in COMMANDS)."""

from __future__ import annotations

import argparse

import numpy as np
import pytest

from hammesh.cli import points
from hammesh.errors import FileFormatError, InvalidDomainError
from hammesh.io import read_mesh
from hammesh.io.points_text import read_points
from hammesh.pointset import no_sequential_example, verify_point_triangulation


def _run(argv):
    p = argparse.ArgumentParser()
    points.add_args(p)
    return points.run(p.parse_args([str(a) for a in argv]))


@pytest.fixture
def cloud(tmp_path):
    pts = np.random.default_rng(0).random((60, 2))
    txt = tmp_path / "cloud.txt"
    txt.write_text("# x y\n" + "\n".join(f"{x} {y}" for x, y in pts))
    np.save(tmp_path / "cloud.npy", pts)
    node = tmp_path / "cloud.node"
    node.write_text(f"{len(pts)} 2 0 0\n" + "\n".join(f"{i + 1} {x} {y}" for i, (x, y) in enumerate(pts)))
    return pts, tmp_path


@pytest.mark.parametrize("name", ["cloud.txt", "cloud.npy", "cloud.node"])
def test_inputs_and_cycle_order_is_kept(cloud, name, capsys):
    pts, d = cloud
    out = d / "out.vtu"
    assert _run([d / name, "-o", out, "--png", d / "p.png", "--seed", "1"]) == 0
    assert "Hamiltonian cycle, verified" in capsys.readouterr().out
    back = read_mesh(out)
    assert np.allclose(back.points[:, :2], pts)
    verify_point_triangulation(back.points[:, :2], back.triangles, "cycle")
    assert (d / "p.png").stat().st_size > 0


def test_sequential_and_none(tmp_path, capsys):
    sq = tmp_path / "sq.txt"
    sq.write_text("0 0\n2 0\n2 2\n0 2\n0.7 0.9\n")
    assert _run([sq, "-o", tmp_path / "s.vtu", "--sequential"]) == 0
    assert "sequential strip" in capsys.readouterr().out
    bad = tmp_path / "thm41.npy"
    np.save(bad, no_sequential_example(9))
    with pytest.raises(InvalidDomainError, match="no sequential triangulation"):
        _run([bad, "--sequential"])


def test_bad_files(tmp_path):
    with pytest.raises(FileFormatError, match="no such file"):
        read_points(tmp_path / "missing.txt")
    f = tmp_path / "bad.txt"
    f.write_text("0 0\n1 2 3\n")
    with pytest.raises(FileFormatError, match="bad.txt:2"):
        read_points(f)
    np.save(tmp_path / "bad.npy", np.zeros((3, 3)))
    with pytest.raises(FileFormatError, match="shape"):
        read_points(tmp_path / "bad.npy")
    dup = tmp_path / "dup.txt"
    dup.write_text("0 0\n1 0\n0 1\n1 0\n")
    with pytest.raises(InvalidDomainError, match="points 1 and 3"):
        _run([dup])
