"""A mesh spanning less than ``MIN_EXTENT`` is refused as input (exit 2, named), as a
domain is, not reported as a failed verification (exit 3) or as "every triangle has zero
area" where the areas only underflow (tester18 r05)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

import hammesh
from hammesh.cli import main
from hammesh.domain.validate import MIN_EXTENT
from tests.helpers import plate


@pytest.fixture(scope="module")
def h() -> hammesh.HamiltonianMesh:
    return hammesh.hamiltonian(plate(1, 1, max_area=0.05))


@pytest.mark.parametrize("scale", [1e-80, 1e-170, 1e-250])
def test_hamiltonian_refuses_a_tiny_mesh_by_name(h, scale: float) -> None:
    tiny = hammesh.Mesh(points=h.points * scale, triangles=h.triangles)
    with pytest.raises(hammesh.InvalidMeshError, match="spans only .*rescale it"):
        hammesh.hamiltonian(tiny)


@pytest.mark.parametrize("suffix", [".vtu", ".ele", ".ply"])
@pytest.mark.parametrize("scale", [1e-80, 1e-250])
def test_check_refuses_a_tiny_file_with_exit_2(tmp_path: Path, h, suffix: str, scale: float, capsys) -> None:
    out = tmp_path / f"tiny{suffix}"
    hammesh.write(replace(h, points=h.points * scale), out)
    assert main(["check", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "spans only" in err[0] and "zero area" not in err[0]


def test_just_above_the_limit_is_checked(tmp_path: Path, h) -> None:
    out = tmp_path / "small.vtu"
    hammesh.write(replace(h, points=h.points * (4 * MIN_EXTENT)), out)
    assert main(["check", str(out)]) == 0
