"""`hammesh points` through the registered CLI entry point."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import hammesh
from hammesh.cli import main


def test_points_verb_writes_a_verified_cycle(tmp_path: Path) -> None:
    rng = np.random.default_rng(11)
    src = tmp_path / "cloud.npy"
    np.save(src, rng.random((300, 2)))
    out = tmp_path / "cloud.vtu"
    assert main(["points", str(src), "-o", str(out)]) == 0
    assert main(["check", str(out)]) == 0
    m = hammesh.read_mesh(out)
    assert m.n_points == 300


def test_points_verb_rejects_duplicates_with_exit_2(tmp_path: Path, capsys) -> None:
    src = tmp_path / "dup.txt"
    src.write_text("0 0\n1 0\n0 1\n1 0\n0.3 0.3\n")
    assert main(["points", str(src), "-o", str(tmp_path / "o.vtu")]) == 2
    err = capsys.readouterr().err
    assert "duplicate" in err and err.count("\n") == 1
    assert not (tmp_path / "o.vtu").exists()
