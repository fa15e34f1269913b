"""``--tree`` (incircle mode's spanning tree; sparse mode's opt-in fishbone) on the parallel path: every tile's cycle
is the one ``hammesh.hamiltonian`` makes with that tree."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import hammesh
from hammesh.cli import main
from hammesh.errors import InvalidOptionError
from hammesh.parallel.run import run_tiles

DEMO = str(Path(hammesh.__file__).parent / "data" / "demo.poly")


@pytest.mark.parametrize("tree", ["quadtree", "fishbone"])
def test_every_tile_cycle_is_hamiltonian_with_the_tree(tree):
    dom = hammesh.read_domain(DEMO)
    tiled = run_tiles(dom, min_angle=30, max_area=2e-3, tiles=2, mode="incircle", keep_meshes=True, tree=tree)
    orders = []
    for handle in tiled.outcomes:
        o = handle.result()
        ref = hammesh.hamiltonian(o.mesh, mode="incircle", tree=tree)
        assert np.array_equal(o.ham.triangles, ref.triangles)
        orders.append(o.ham.triangles)
    other = "quadtree" if tree == "fishbone" else "fishbone"
    o = tiled.outcomes[0].result()
    # (the check can fail: the two trees give different cycles on these tiles)
    assert not np.array_equal(orders[0], hammesh.hamiltonian(o.mesh, mode="incircle", tree=other).triangles)


def test_an_unknown_tree_is_refused_before_any_tile():
    dom = hammesh.read_domain(DEMO)
    with pytest.raises(InvalidOptionError, match="tree"):
        run_tiles(dom, min_angle=30, max_area=2e-3, tiles=2, mode="incircle", tree="oak")


def test_cli_passes_tree_to_the_tiles(tmp_path, capsys):
    rep = tmp_path / "r.json"
    assert main(["mesh", DEMO, "-q", "30", "-a", "2e-3", "--tiles", "2", "--mode", "incircle", "--tree",
                 "fishbone", "--partitioned", "-o", str(tmp_path / "d"), "--report", str(rep)]) == 0
    assert json.loads(rep.read_text())["parallel"]["tree"] == "fishbone"
    rep2 = tmp_path / "r2.json"
    # the serial path's default: fishbone with --parts
    assert main(["mesh", DEMO, "-q", "30", "-a", "2e-3", "--tiles", "2", "--mode", "incircle", "--parts", "3",
                 "-o", str(tmp_path / "m.vtu"), "--report", str(rep2)]) == 0
    assert json.loads(rep2.read_text())["parallel"]["tree"] == "fishbone"
    capsys.readouterr()


def test_cli_sparse_mode_takes_tree_fishbone_to_the_tiles(tmp_path, capsys):
    # sparse mode's fishbone (issue 14's opt-in compact cycle) reaches the tiles as it
    # reaches the serial call; --parts alone keeps sparse mode's free cover
    rep = tmp_path / "r.json"
    assert main(["mesh", DEMO, "-q", "30", "-a", "2e-3", "--tiles", "2", "--tree", "fishbone", "--partitioned",
                 "-o", str(tmp_path / "d"), "--report", str(rep)]) == 0
    assert json.loads(rep.read_text())["parallel"]["tree"] == "fishbone"
    rep2 = tmp_path / "r2.json"
    assert main(["mesh", DEMO, "-q", "30", "-a", "2e-3", "--tiles", "2", "--parts", "3",
                 "-o", str(tmp_path / "m.vtu"), "--report", str(rep2)]) == 0
    assert json.loads(rep2.read_text())["parallel"]["tree"] == "quadtree"
    capsys.readouterr()
