"""``hammesh.partition``: contiguous cycle pieces, exact balance, connected parts, cut."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.partition import cycle_runs, dual_edges, partition
from tests.helpers import dual_pieces, hand_hamiltonian, plate, square, star_pslg


def _cut_by_hand(tri: np.ndarray, part: np.ndarray) -> tuple[int, list[int]]:
    """Edge cut and pieces per part, from vertex pairs (networkx, no hammesh code)."""
    owner: dict[tuple[int, int], list[int]] = {}
    for t, (a, b, c) in enumerate(tri.tolist()):
        for e in ((a, b), (b, c), (c, a)):
            owner.setdefault((min(e), max(e)), []).append(t)
    cut = sum(1 for ts in owner.values() if len(ts) == 2 and part[ts[0]] != part[ts[1]])
    pieces = []
    for j in range(int(part.max()) + 1):
        rows = np.flatnonzero(part == j)
        pieces.append(dual_pieces(tri[rows]) if len(rows) else 0)
    return cut, pieces


def _runs_of(part: np.ndarray, lengths: np.ndarray) -> int:
    """Stretches of equal labels along the cycles (a part wrapping the end counts once)."""
    n = 0
    start = 0
    for length in lengths.tolist():
        p = part[start : start + length]
        changes = int((p != np.roll(p, 1)).sum())
        n += max(changes, 1)
        start += length
    return n


@pytest.fixture(scope="module")
def disc_incircle() -> hammesh.HamiltonianMesh:
    dom = hammesh.Domain.from_polygon(square(0, 0, 1), holes=[square(0.4, 0.4, 0.2)])
    return hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=30, max_area=0.0005), mode="incircle")


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(dom=star_pslg(), k=st.integers(1, 12), mode=st.sampled_from(["sparse", "incircle"]))
def test_parts_are_balanced_connected_stretches(dom, k: int, mode: str) -> None:
    """Every part is one stretch of its cycle, sizes within one of each other (one
    piece), one connected piece each; the reported cut and pieces match a
    recount from vertex pairs."""
    h = hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=25, max_area=0.02), mode=mode)
    k = min(k, h.n_triangles)
    p = partition(h, k)
    assert p.part.shape == (h.n_triangles,) and set(np.unique(p.part).tolist()) == set(range(k))
    assert int(p.sizes.sum()) == h.n_triangles
    assert int(p.sizes.max() - p.sizes.min()) <= 1
    assert p.report["imbalance"] == pytest.approx(p.sizes.max() * k / h.n_triangles)
    assert _runs_of(p.part, h.components) == k  # contiguous along the cycle
    cut, pieces = _cut_by_hand(h.triangles, p.part)
    assert p.edge_cut == cut == p.report["edge_cut"]
    assert pieces == [1] * k and p.connected and p.components.tolist() == pieces


def test_pieces_of_the_domain_are_cut_separately() -> None:
    """Three pieces, k = 7: each part lies in one piece, parts spread by size."""
    m = plate(0, 3, max_area=0.01)
    h = hammesh.hamiltonian(m, mode="sparse")
    p = partition(h, 7)
    run = np.repeat(np.arange(len(h.components)), h.components)
    for j in range(7):
        assert len(np.unique(run[p.part == j])) == 1
    assert sum(p.report["parts_per_piece"]) == 7 and min(p.report["parts_per_piece"]) >= 1
    assert p.connected
    cut, pieces = _cut_by_hand(h.triangles, p.part)
    assert cut == p.edge_cut and pieces == [1] * 7


def test_fewer_parts_than_pieces_reports_disconnected_parts() -> None:
    h = hammesh.hamiltonian(plate(0, 3, max_area=0.01), mode="sparse")
    p = partition(h, 2)
    assert not p.connected and p.report["connected"] is False
    assert int(p.sizes.sum()) == h.n_triangles


def test_compact_cycle_cuts_few_edges(disc_incircle) -> None:
    """The quadtree-ordered tree makes stretches compact: the 8-part cut stays within
    a small factor of a part's perimeter bound (a depth-first tree cut ~30x more)."""
    h = disc_incircle
    p = partition(h, 8)
    a, b = dual_edges(h.triangles)
    # 8 compact parts of a domain of ~m triangles cut about 2 * sqrt(8 m) edges;
    # finger-like stretches cut far more (their cut grows like m, not sqrt(m))
    assert p.edge_cut < 4.0 * np.sqrt(8 * h.n_triangles), (p.edge_cut, h.n_triangles, len(a))


@pytest.fixture(scope="module")
def square_incircle() -> hammesh.HamiltonianMesh:
    dom = hammesh.Domain.from_polygon(square(0, 0, 1))
    return hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=30, max_area=3e-4), mode="incircle")


@pytest.mark.parametrize("k", [4, 16])
def test_parts_of_a_square_are_its_quadtree_cells(square_incircle, k: int) -> None:
    """On a hole-free square the count quadtree's cells hold equal counts and the walk
    visits each whole (its children hang at its centre), so for k a power of 4 the
    stretches are the cells of a level: the cut is at most a straight grid's (the
    grid cut is counted on the same mesh; a tree whose stretches are strips or miss
    the cells cuts 1.3-1.7x more)."""
    h = square_incircle
    p = partition(h, k)
    a, b = dual_edges(h.triangles)
    c = h.points[h.triangles].mean(axis=1)
    g = int(round(np.sqrt(k)))
    cell = np.minimum((c * g).astype(np.int64), g - 1)
    grid = cell[:, 0] + g * cell[:, 1]
    grid_cut = int((grid[a] != grid[b]).sum())
    assert p.connected and int(p.sizes.max() - p.sizes.min()) <= 1
    assert p.edge_cut <= 1.1 * grid_cut, (p.edge_cut, grid_cut)


def _every_shift_cut(n: int, k: int, a: np.ndarray, b: np.ndarray) -> list[int]:
    """Cut of the stretches starting at ``s + floor(j n / k)``, for every ``s < n // k``."""
    cuts = []
    for s in range(n // k):
        starts = [s + (j * n) // k for j in range(k)]
        label = np.empty(n, np.int64)
        for j, lo in enumerate(starts):
            hi = starts[j + 1] if j + 1 < k else n + s
            label[np.arange(lo, hi) % n] = j
        cuts.append(int((label[a] != label[b]).sum()))
    return cuts


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(dom=star_pslg(), k=st.integers(2, 9), mode=st.sampled_from(["sparse", "incircle"]))
def test_best_shift_is_the_best_of_all_shifts(dom, k: int, mode: str) -> None:
    """The difference-array count is exact: the shift taken cuts as few edges as the
    best of every shift relabelled and recounted by brute force, and the cut it
    reports without the check is the recount."""
    h = hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=25, max_area=0.05), mode=mode)
    if len(h.components) != 1 or h.n_triangles < 2 * k:
        return
    a, b = dual_edges(h.triangles)
    every = _every_shift_cut(h.n_triangles, k, a, b)
    p = partition(h, k, edges=(a, b), check=False)
    assert p.edge_cut == min(every) == every[p.report["shifts"][0]]
    assert p.edge_cut == int((p.part[a] != p.part[b]).sum())
    assert p.report["connected"] is None


def test_best_shift_never_worse_than_plain_starts(disc_incircle) -> None:
    h = disc_incircle
    m = h.n_triangles
    a, b = dual_edges(h.triangles)
    for k in (3, 8, 20):
        plain = (np.arange(m) * k) // m
        assert partition(h, k).edge_cut <= int((plain[a] != plain[b]).sum())
        assert partition(h, k, check=False).edge_cut == partition(h, k).edge_cut


def test_mesh_read_back_from_a_file_is_partitioned(tmp_path, disc_incircle) -> None:
    path = tmp_path / "h.vtu"
    hammesh.write(disc_incircle, path)
    back = hammesh.read_mesh(path)
    np.testing.assert_array_equal(cycle_runs(back.triangles), disc_incircle.components)
    p = partition(back, 5)
    q = partition(disc_incircle, 5)
    np.testing.assert_array_equal(p.part, q.part)


def test_two_cycles_found_in_row_order(two_cycles) -> None:
    np.testing.assert_array_equal(cycle_runs(two_cycles.triangles), two_cycles.components)


def test_rows_out_of_cycle_order_are_refused(disc_incircle) -> None:
    tri = disc_incircle.triangles.copy()
    tri[[3, 40]] = tri[[40, 3]]
    with pytest.raises(hammesh.InvalidMeshError, match="cycle order"):
        partition(hammesh.Mesh(disc_incircle.points, tri), 4)


@pytest.mark.parametrize("k", [0, -1, 2.5, True, "4", 10**9])
def test_bad_k_is_refused(hexagon, k) -> None:
    with pytest.raises(hammesh.InvalidOptionError, match="k="):
        partition(hexagon, k)


def test_not_a_mesh_is_refused() -> None:
    with pytest.raises(hammesh.InvalidOptionError, match="h="):
        partition(np.zeros((3, 3)), 2)


def test_one_part_per_triangle(hexagon) -> None:
    p = partition(hexagon, 6)
    assert sorted(p.part.tolist()) == list(range(6)) and p.edge_cut == 6 and p.connected
