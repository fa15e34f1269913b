"""A tile gives Triangle no hole point outside the convex hull of its points.

Session 18: the interpreter crash in ``mesh_band``'s in-process Triangle call. A tile
takes every domain hole whose point lies in its box; where the tile's piece of the
domain does not surround the point, it lies outside the hull of the tile's input.
Triangle's ``carveholes`` skips only points outside the bounding box, and ``locate``
may then step from a hull triangle into Triangle's outer "dummy" triangle and read its
NULL corners (SIGSEGV in ``preciselocate``, every run, any heap).
``band_hole_outside_hull.json`` is the band input that crashed (found by a Triangle
build that fills every pool item with a pattern, in-process over 3,900 examples of the
random-domain tests' generator; the stock wheel dies on it too). Calls that may crash
run in a child (``run_isolated``), so a regression fails a test instead of pytest.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from hammesh.errors import MeshingError
from hammesh.meshing.isolate import run_isolated
from hammesh.parallel import decompose
from hammesh.parallel import tile_mesh
from hammesh.domain.validate import holes_in_hull
from hammesh.parallel.tile_mesh import mesh_tile
from tests.parallel.test_coarse_quality import BEND, _with_square_hole

CRASH = Path(__file__).with_name("band_hole_outside_hull.json")


def _crash_input() -> tuple[dict, str]:
    d = json.loads(CRASH.read_text())
    data = {"vertices": np.array(d["vertices"]), "segments": np.array(d["segments"], np.int32),
            "holes": np.array(d["holes"])}
    return data, d["switches"]


def _triangulate(data: dict, switches: str) -> int:
    import triangle

    return len(triangle.triangulate(data, switches)["triangles"])


def test_triangle_dies_on_the_band_input_with_its_hole_point():
    """The reason for the filter: the domain's hole point (0, 0) lies in the band's
    bounding box, outside its hull; Triangle reads NULL corners and dies."""
    data, switches = _crash_input()
    with pytest.raises(MeshingError, match="crashed"):
        run_isolated(_triangulate, (data, switches), name="Triangle (the band input)", timeout=60)


def test_holes_in_hull_drops_that_point_and_triangle_meshes_the_band():
    data, switches = _crash_input()
    kept = holes_in_hull(data["vertices"], data["holes"])
    assert kept.tolist() == [data["holes"][1].tolist()]  # (the lattice's hole point stays)
    data["holes"] = kept
    assert run_isolated(_triangulate, (data, switches), name="Triangle (filtered)", timeout=60) > 100


def test_holes_in_hull_keeps_points_inside_and_on_the_hull():
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.2]])
    holes = np.array([[0.5, 0.5], [1.0, 0.5], [0.0, 0.0], [1.0 + 1e-9, 0.5], [-0.5, 0.5], [0.5, 1.5]])
    assert holes_in_hull(square, holes).tolist() == [[0.5, 0.5], [1.0, 0.5], [0.0, 0.0]]
    assert holes_in_hull(square, np.zeros((0, 2))).shape == (0, 2)


def _given_holes(tile, lattice: bool) -> list[np.ndarray]:
    """The hole points ``mesh_tile`` gives Triangle (every call of the tile)."""
    seen = []
    real = tile_mesh.triangulate_guarded

    def spy(data, switches, what, seconds=None, isolate=False):
        seen.append((np.asarray(data["vertices"]), np.asarray(data.get("holes", np.zeros((0, 2))))))
        return real(data, switches, what, seconds=seconds, isolate=True)  # (a child: a crash is an error)

    tile_mesh.triangulate_guarded = spy
    try:
        mesh_tile(tile, 30.0, 1e-3, lattice=lattice)
    finally:
        tile_mesh.triangulate_guarded = real
    return seen


@pytest.mark.parametrize("lattice", [True, False])
def test_a_tile_gives_triangle_only_hole_points_inside_its_hull(lattice):
    """BEND with a square hole, 4 tiles: tile 2's box holds the hole point (0, 0), its
    piece of the domain does not surround it (before: given to Triangle)."""
    d = decompose(_with_square_hole(BEND, 0.12), min_angle=30, max_area=1e-3, n_tiles=4)
    tile = d.tiles[2]
    assert len(tile.holes) == 1 and len(holes_in_hull(tile.vertices, tile.holes)) == 0
    calls = _given_holes(tile, lattice)
    assert calls
    for vertices, holes in calls:
        assert not any(np.array_equal(h, tile.holes[0]) for h in holes)
        assert len(holes_in_hull(vertices, holes)) == len(holes)
