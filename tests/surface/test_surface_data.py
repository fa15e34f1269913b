"""A surface's point and cell data reach the Hamiltonian surface (never lost)."""

from __future__ import annotations

import subprocess
import sys

import meshio
import numpy as np
import pytest

import hammesh.postprocess.cycle_cover as cycle_cover_module
from hammesh.surface import icosphere, surface_hamiltonian
from hammesh.surface.files import weld_surface


@pytest.mark.parametrize(("level", "split_all"), [(1, False), (2, True)])
def test_linear_point_data_is_exact_and_cells_follow_parents(level, split_all, monkeypatch):
    # (without session 14's re-colouring: with it the level-1 sphere needs no Steiner point)
    monkeypatch.setattr(cycle_cover_module, "RECOLOUR_BELOW", 0)
    points, triangles = icosphere(level)
    # a linear field: every Steiner point lies in its parent's plane, so interpolation is exact
    field = points @ np.array([1.0, -2.0, 0.5]) + 3.0
    label = np.arange(len(points), dtype=np.int64) % 5
    cell = np.column_stack([np.arange(len(triangles)), -np.arange(len(triangles))]).astype(float)
    h = surface_hamiltonian(points, triangles, triangle_attributes=cell, attribute_names=("id", "neg"),
                            point_data={"f": field, "label": label}, split_all=split_all)
    assert len(h.points) > len(points)  # Steiner points were made
    np.testing.assert_allclose(h.point_data["f"], h.points @ np.array([1.0, -2.0, 0.5]) + 3.0, atol=1e-12)
    assert h.point_data["label"].dtype == np.int64
    assert set(np.unique(h.point_data["label"])) <= set(range(5))
    np.testing.assert_array_equal(h.point_data["label"][: len(points)], label)
    np.testing.assert_array_equal(h.triangle_attributes, cell[h.parent])
    assert h.attribute_names == ("id", "neg")


def test_weld_keeps_points_whose_data_differ():
    # two squares' triangles, the seam's corners stored twice: equal data welds, a UV seam stays
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [1, 0, 0], [2, 0, 0], [1, 1, 0]], float)
    tri = np.array([[0, 1, 2], [3, 4, 5]])
    same = weld_surface(pts, tri, {"t": np.array([0.0, 1, 2, 1, 4, 2])})
    assert len(same.points) == 4 and same.triangles[1].tolist() == [1, 3, 2]
    seam = weld_surface(pts, tri, {"uv": np.array([[0, 0], [1, 0], [1, 1], [0, 0], [1, 0], [0, 1.0]])})
    assert len(seam.points) == 6
    np.testing.assert_array_equal(seam.points, pts[seam.source])


def test_cli_surface_carries_file_data(tmp_path):
    points, triangles = icosphere(1)
    src = tmp_path / "sphere.vtu"
    meshio.Mesh(points, [("triangle", triangles)], point_data={"Texture Coordinates": points[:, :2] * 0.5 + 0.5},
                cell_data={"material": [np.arange(len(triangles)) % 3]}).write(src)
    out = tmp_path / "out.vtu"
    run = subprocess.run([sys.executable, "-m", "hammesh", "surface", str(src), "-o", str(out)],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    back = meshio.read(out)
    uv = back.point_data["Texture Coordinates"]
    np.testing.assert_allclose(uv, back.points[:, :2] * 0.5 + 0.5, atol=1e-12)
    parent = back.cell_data["parent"][0]
    np.testing.assert_array_equal(back.cell_data["material"][0], (np.arange(len(triangles)) % 3)[parent])
