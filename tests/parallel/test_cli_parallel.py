"""``hammesh mesh --tiles/--workers/--partitioned`` and ``hammesh check`` of a .pvtu (issue 15)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import hammesh
from hammesh.cli import main
from hammesh.io import pvtu
from tests.helpers import assert_cycles, dual_pieces

DEMO = str(Path(hammesh.__file__).parent / "data" / "demo.poly")


def test_tiles_in_process_write_a_checked_mesh(tmp_path, capsys):
    out = tmp_path / "out.vtu"
    assert main(["mesh", DEMO, "-q", "30", "-a", "2e-3", "--tiles", "3", "-o", str(out)]) == 0
    assert "3 tiles" in capsys.readouterr().out
    assert main(["check", str(out)]) == 0
    m = hammesh.read_mesh(out)
    assert dual_pieces(m.triangles) == 1


def test_partitioned_pieces_and_index_in_cycle_order(tmp_path, capsys):
    out = tmp_path / "parts"
    assert main(["mesh", DEMO, "-q", "30", "-a", "2e-3", "--tiles", "3", "--partitioned", "-o", str(out)]) == 0
    capsys.readouterr()
    index = out / "mesh.pvtu"
    pieces = pvtu.read_pieces(index)
    assert sorted(p.name for p in pieces) == ["piece_0000.vtu", "piece_0001.vtu", "piece_0002.vtu"]
    # each piece's rows are in increasing global position; pieces listed by first position
    import meshio

    firsts = []
    total = 0
    for p in pieces:
        gp = np.asarray(meshio.read(p).cell_data["global_position"][0])
        assert (np.diff(gp) > 0).all()
        firsts.append(gp[0])
        total += len(gp)
    assert firsts == sorted(firsts) and firsts[0] == 0
    # stitched: one closed cycle, checked by the command and by the tests' own walk
    assert main(["check", str(index)]) == 0
    m = hammesh.read_mesh(index)
    assert len(m.triangles) == total
    h = hammesh.HamiltonianMesh.from_order(m.points, m.triangles)
    assert_cycles(h)


def test_workers_without_dask_says_how_to_install(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    out = tmp_path / "out.vtu"
    assert main(["mesh", DEMO, "-q", "30", "-a", "2e-3", "--workers", "2", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "pip install hammesh[dask]" in err and len(err.splitlines()) == 1
    assert not out.exists()


@pytest.mark.parametrize("argv, what", [
    (["--tiles", "2"], "max-area"),
    (["-a", "1e-3", "--tiles", "2", "--png", "x.png"], "--png"),
    (["-a", "1e-3", "--tiles", "0"], "tiles"),
    (["-a", "1e-3", "--workers", "2", "--scheduler", "tcp://127.0.0.1:1"], "give one"),
    (["-a", "-1", "--tiles", "2"], "--max-area=-1.0 is not valid"),
    (["-a", "nan", "--tiles", "2", "--partitioned"], "--max-area=nan is not valid"),
    (["-a", "1e-3", "-q", "40", "--tiles", "2"], "--min-angle=40.0 is not valid"),
])
def test_bad_parallel_options_exit_2(tmp_path, capsys, argv, what):
    assert main(["mesh", DEMO, "-q", "30", *argv, "-o", str(tmp_path / "o.vtu")]) == 2
    assert what in capsys.readouterr().err
    assert not (tmp_path / "o.vtu").exists()


@pytest.mark.slow
def test_local_dask_cluster_of_two_workers(tmp_path, capsys, run_cli):
    pytest.importorskip("distributed")
    out = tmp_path / "parts"
    # (the suite's first local cluster may compile every kernel of a fresh numba cache:
    # 2.4 min at load ~1, past 600 s at load ~10; conftest's WATCHDOG_S, 900, less a minute)
    rc, _, err, left = run_cli(["mesh", DEMO, "-q", "30", "-a", "2e-3", "--workers", "2", "--partitioned", "-o", str(out)],
                               timeout=840)
    assert rc == 0 and left == []
    assert err == ""  # no Dask chatter (port warnings, nanny logs) for the user
    assert main(["check", str(out / "mesh.pvtu")]) == 0
