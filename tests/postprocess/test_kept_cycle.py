"""A mesh whose rows already walk a Hamiltonian cycle per piece is kept as it is."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.mesh import KIND_NAMES
from hammesh.postprocess.kept_cycle import kept_runs
from tests.helpers import assert_cycles, assert_tiling_and_bound, dual_pieces, plate, star_pslg


def as_input(h: hammesh.HamiltonianMesh) -> hammesh.Mesh:
    """``h`` as a plain mesh (what reading hammesh's own output back gives)."""
    return hammesh.Mesh(h.points, h.triangles, segments=h.segments, segment_markers=h.segment_markers,
                        triangle_attributes=h.triangle_attributes)


def assert_kept(m: hammesh.Mesh, again: hammesh.HamiltonianMesh) -> None:
    np.testing.assert_array_equal(again.points, m.points)
    np.testing.assert_array_equal(again.triangles, m.triangles)
    assert again.report["kept_input_cycle"] and again.report["verified"]
    assert again.report["steiner_points"] == 0
    assert (again.kind == KIND_NAMES.index("input")).all()
    np.testing.assert_array_equal(again.parent, np.arange(m.n_triangles))
    assert_cycles(again)
    assert_tiling_and_bound(m, again)


def test_second_run_on_own_output_adds_nothing():
    m = plate(n_loops=2, pieces=2)
    h = hammesh.hamiltonian(m)
    assert h.report.get("kept_input_cycle") is None  # (Triangle's order is no cycle)
    again = hammesh.hamiltonian(as_input(h))
    assert_kept(as_input(h), again)
    assert len(again.components) == 2 == dual_pieces(h.triangles)
    starts = np.cumsum(again.components) - again.components
    assert (again.position[starts] == 0).all() and again.position.max() == max(again.components) - 1


def test_written_and_read_back(tmp_path):
    h = hammesh.hamiltonian(plate(n_loops=1, pieces=1))
    hammesh.write(h, tmp_path / "h.vtu")
    back = hammesh.read_mesh(tmp_path / "h.vtu")
    assert_kept(back, hammesh.hamiltonian(back))


def test_two_cycles_in_one_piece_are_joined_not_kept():
    h = hammesh.hamiltonian(plate(n_loops=0, pieces=1))
    m = as_input(h)
    # cut the one cycle into two closed runs of the same piece: a 2-factor, not a cycle
    tri = m.triangles
    n = len(tri)
    for cut in range(3, n - 3):
        a, b = tri[:cut], tri[cut:]
        runs = kept_runs(np.vstack([a, b]))
        if runs is not None and len(runs) == 2:
            break
    else:  # no such split of this cycle: reverse half of it instead (still not one cycle)
        a, b = tri[: n // 2], tri[n // 2:][::-1]
    two = replace(m, triangles=np.vstack([a, b]))
    out = hammesh.hamiltonian(two)
    assert not out.report.get("kept_input_cycle")
    assert len(out.components) == 1
    assert_cycles(out)


def test_incircle_and_fishbone_still_construct():
    h = hammesh.hamiltonian(plate(n_loops=0, pieces=1))
    m = as_input(h)
    inc = hammesh.hamiltonian(m, mode="incircle")
    assert inc.n_triangles == 3 * m.n_triangles + 2 * inc.report["midpoints"]
    fish = hammesh.hamiltonian(m, tree="fishbone")
    assert not fish.report.get("kept_input_cycle")


def test_kept_runs_refuses_other_orders():
    h = hammesh.hamiltonian(plate(n_loops=0, pieces=1))
    tri = h.triangles
    assert kept_runs(tri).tolist() == [len(tri)]
    rng = np.random.default_rng(0)
    assert kept_runs(tri[rng.permutation(len(tri))]) is None
    swapped = tri.copy()
    swapped[[5, len(tri) // 2]] = swapped[[len(tri) // 2, 5]]
    assert kept_runs(swapped) is None
    assert kept_runs(np.zeros((0, 3), dtype=np.int64)) is None
    assert kept_runs(np.array([[3, 0, 1], [1, 2, 3]])) is None  # (two rows: one edge, no cycle)
    assert kept_runs(np.array([[0, 1, 2]])) is None


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(star_pslg(), st.integers(0, 10**6))
def test_any_rotation_of_own_cycles_is_kept(dom, shift):
    h = hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=25, max_area=0.02))
    starts = np.cumsum(h.components) - h.components
    rows = np.concatenate([s + np.roll(np.arange(c), shift % c) for s, c in zip(starts, h.components)])
    m = replace(as_input(h), triangles=h.triangles[rows], triangle_attributes=h.triangle_attributes[rows])
    assert_kept(m, hammesh.hamiltonian(m))


def test_small_pieces_among_the_first_rows_are_kept():
    # pieces of a few rows each: their runs end within the rows looked at first
    h = hammesh.hamiltonian(plate(n_loops=0, pieces=3, max_area=0.3))
    assert len(h.components) == 3 and h.n_triangles < 64
    m = as_input(h)
    assert kept_runs(m.triangles).tolist() == h.components.tolist()
    assert_kept(m, hammesh.hamiltonian(m))
    back = replace(m, triangles=m.triangles[::-1].copy(), triangle_attributes=m.triangle_attributes[::-1].copy())
    assert kept_runs(back.triangles).tolist() == h.components[::-1].tolist()
    assert_kept(back, hammesh.hamiltonian(back))
