"""``hammesh check`` on 3D surfaces, and 3D surfaces through the shared writer."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import hammesh
from hammesh.cli import main
from hammesh.surface import read_surface, surface_hamiltonian
from hammesh.surface.shapes import torus


@pytest.fixture(scope="module")
def cycle_surface() -> hammesh.HamiltonianMesh:
    p, t = torus(24, 12, hole=True)
    return surface_hamiltonian(p, t)


@pytest.mark.parametrize("suffix", [".vtu", ".vtk", ".obj", ".ply", ".stl", ".off"])
def test_surface_written_by_hammesh_write_is_rechecked(tmp_path: Path, suffix: str, cycle_surface, capsys) -> None:
    h = cycle_surface
    out = tmp_path / f"cycle{suffix}"
    hammesh.write(h, out)
    points, triangles = read_surface(out)
    # same triangles in the same (cycle) order, same 3D coordinates
    assert np.allclose(points[triangles], h.points[h.triangles])
    assert main(["check", str(out), "--report", str(tmp_path / "r.json")]) == 0
    assert f"{h.n_triangles:,} triangles in 1 Hamiltonian cycle" in capsys.readouterr().out


def test_check_rejects_a_broken_surface_cycle(tmp_path: Path, cycle_surface, capsys) -> None:
    h = cycle_surface
    tri = h.triangles.copy()
    tri[[3, 40]] = tri[[40, 3]]
    out = tmp_path / "bad.ply"
    hammesh.write(replace(h, triangles=tri), out)
    assert main(["check", str(out)]) == 3
    assert "breaks at triangle" in capsys.readouterr().err


def test_check_surface_min_angle(tmp_path: Path, cycle_surface) -> None:
    out = tmp_path / "c.vtu"
    hammesh.write(cycle_surface, out)
    amin = cycle_surface.report["min_angle_output_deg"]
    assert main(["check", str(out), "--min-angle", f"{amin - 0.01}"]) == 0
    assert main(["check", str(out), "--min-angle", f"{amin + 0.5}"]) == 3


def test_triangle_files_refuse_a_surface(tmp_path: Path, cycle_surface) -> None:
    with pytest.raises(hammesh.InvalidMeshError, match="planar"):
        hammesh.write(cycle_surface, tmp_path / "s.ele")
    assert not list(tmp_path.iterdir())


def test_check_welds_only_points_whose_data_agree(tmp_path: Path, capsys) -> None:
    """A cylinder's caps and side meet at the rim with other normals: `hammesh surface`
    keeps those points apart, and so must `hammesh check` (it merged them by coordinate
    and called the verified output broken)."""
    pv = pytest.importorskip("pyvista")
    pv.Cylinder(resolution=24).triangulate().save(tmp_path / "cyl.vtp")
    out = tmp_path / "cyl.vtu"
    assert main(["surface", str(tmp_path / "cyl.vtp"), "-o", str(out)]) == 0
    assert "Normals" in hammesh.read_mesh(out, dim=None).point_data
    capsys.readouterr()
    assert main(["check", str(out)]) == 0
    assert "in 3 Hamiltonian cycle(s)" in capsys.readouterr().out


def test_surface_notes_the_point_data_a_format_cannot_hold(tmp_path: Path, capsys) -> None:
    """`hammesh surface x.vtu -o y.obj` said nothing while dropping the point data."""
    p, t = torus(12, 6, hole=True)
    src = tmp_path / "t.vtu"
    hammesh.write(hammesh.Mesh(p, t, point_data={"temperature": p[:, 0].copy()}), src)
    assert main(["surface", str(src), "-o", str(tmp_path / "t.obj")]) == 0
    assert "note: not written: point data 'temperature' (.obj holds geometry only)" in capsys.readouterr().out
    assert main(["surface", str(src), "-o", str(tmp_path / "t.ply")]) == 0  # (.ply holds it)
    assert "note:" not in capsys.readouterr().out


@pytest.mark.parametrize("damage, hint", [("flip", True), ("swap", False)])
def test_check_hints_at_surface_only_for_orientation_faults(tmp_path: Path, damage: str, hint: bool, capsys) -> None:
    """A flat file with an inverted triangle may be a folded surface (say --surface); a broken
    cycle is not (no hint). The hint follows ``VerificationError.check``, not the message."""
    from tests.helpers import plate

    h = hammesh.hamiltonian(plate(1, 1, max_area=0.02))
    tri = h.triangles.copy()
    if damage == "flip":
        tri[5] = tri[5, ::-1]
    else:
        tri[[3, 40]] = tri[[40, 3]]
    out = tmp_path / "bad.vtu"
    hammesh.write(replace(h, triangles=tri), out)
    assert main(["check", str(out)]) == 3
    err = capsys.readouterr().err
    assert ("check it with --surface" in err) == hint
    assert ("overlap" in err) == (damage == "flip")  # (a flipped row uses its edges in the neighbours' direction)
