"""The interior lattice's off switch: ``lattice=False`` through ``run_tiles``, the Python
API (``parallel_hamiltonian``, ``write_partitioned``) and ``hammesh mesh --no-lattice``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import hammesh
from hammesh.cli import main
from hammesh.errors import InvalidOptionError
from hammesh.parallel import decompose, mesh_tile, parallel_hamiltonian, write_partitioned
from hammesh.parallel.run import run_tiles
from hammesh.parallel.tile_mesh import lattice_points
from tests.helpers import assert_cycles

DEMO = str(Path(hammesh.__file__).parent / "data" / "demo.poly")
AREA = 1e-3  # every tile of the demo then has lattice points (test_lattice)


def _tile_counts(lattice: bool) -> list[int]:
    """The tiles' own Triangle runs (mesh_tile), with or without the lattice."""
    d = decompose(hammesh.read_domain(DEMO), min_angle=30, max_area=AREA, n_tiles=2)
    return [mesh_tile(t, 30, AREA, lattice=lattice).n_triangles for t in d.tiles]


def _lattice_of_tiles() -> np.ndarray:
    d = decompose(hammesh.read_domain(DEMO), min_angle=30, max_area=AREA, n_tiles=2)
    return np.concatenate([lattice_points(t, AREA) for t in d.tiles])


def _held(points: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Which rows of ``q`` are exactly rows of ``points``."""
    c = lambda a: np.ascontiguousarray(a, dtype=np.float64).view(np.complex128).ravel()  # noqa: E731
    return np.isin(c(q), c(points))


@pytest.mark.parametrize("lattice", [True, False])
def test_run_tiles_meshes_each_tile_as_asked(lattice):
    tiled = run_tiles(hammesh.read_domain(DEMO), min_angle=30, max_area=AREA, tiles=2, lattice=lattice)
    assert tiled.rounds == 0
    assert tiled.mesh_triangles.tolist() == _tile_counts(lattice)


def test_the_switch_changes_the_tiles():
    """(so the two tests above cannot both pass by ignoring the switch)"""
    assert _tile_counts(True) != _tile_counts(False)


def test_python_api_without_lattice_has_no_lattice_point():
    dom = hammesh.read_domain(DEMO)
    q = _lattice_of_tiles()
    assert len(q) > 100
    h = parallel_hamiltonian(dom, min_angle=30, max_area=AREA, tiles=2, lattice=False)
    assert h.report["verified"] and h.report["parallel"]["lattice"] is False
    assert h.report["parallel"]["mesh_triangles"] == sum(_tile_counts(False))
    # Triangle's own Steiner points may hit a lattice point now and then, not most of them
    assert _held(h.points, q).mean() < 0.05
    assert_cycles(h)
    on = parallel_hamiltonian(dom, min_angle=30, max_area=AREA, tiles=2)
    assert on.report["parallel"]["lattice"] is True and _held(on.points, q).all()


def test_write_partitioned_without_lattice(tmp_path):
    rep = write_partitioned(hammesh.read_domain(DEMO), tmp_path / "parts", min_angle=30, max_area=AREA, tiles=2,
                            lattice=False)
    assert rep["parallel"]["lattice"] is False
    assert rep["parallel"]["mesh_triangles"] == sum(_tile_counts(False))
    m = hammesh.read_mesh(tmp_path / "parts" / "mesh.pvtu")
    assert _held(m.points, _lattice_of_tiles()).mean() < 0.05


@pytest.mark.parametrize("bad", [0, "no", None])
def test_lattice_must_be_a_bool(tmp_path, bad):
    with pytest.raises(InvalidOptionError, match="lattice"):
        parallel_hamiltonian(hammesh.read_domain(DEMO), min_angle=30, max_area=AREA, tiles=2, lattice=bad)
    with pytest.raises(InvalidOptionError, match="lattice"):
        write_partitioned(hammesh.read_domain(DEMO), tmp_path / "p", min_angle=30, max_area=AREA, lattice=bad)
    assert not any(tmp_path.iterdir())  # nothing written


def test_cli_no_lattice(tmp_path, capsys):
    out, rep = tmp_path / "parts", tmp_path / "r.json"
    assert main(["mesh", DEMO, "-q", "30", "-a", str(AREA), "--tiles", "2", "--no-lattice", "--partitioned",
                 "-o", str(out), "--report", str(rep)]) == 0
    r = json.loads(rep.read_text())
    assert r["parallel"]["lattice"] is False
    assert r["parallel"]["mesh_triangles"] == sum(_tile_counts(False))
    capsys.readouterr()
    assert main(["check", str(out / "mesh.pvtu")]) == 0


def test_cli_no_lattice_alone_exits_2(tmp_path, capsys):
    out = tmp_path / "o.vtu"
    assert main(["mesh", DEMO, "-q", "30", "-a", str(AREA), "--no-lattice", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "--no-lattice" in err and len(err.splitlines()) == 1
    assert not out.exists()
