"""``hammesh check`` and the constrained edges stored in mesh files.

A domain with an internal constrained loop (marker 5) inside a boundary square
(marker 1) and two regions is meshed through the public API; every format that stores
constrained edges must give them back with their markers, ``check`` must accept the
file, and a file with a stored constrained edge that is not a mesh edge must fail with
exit 3 and one line on stderr.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import hammesh
from hammesh.cli import main

SEGMENT_SUFFIXES = [".vtu", ".vtk", ".msh", ".xdmf", ".ele"]


@pytest.fixture(scope="module")
def ham() -> hammesh.HamiltonianMesh:
    outer = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
    inner = [[0.3, 0.3], [0.7, 0.3], [0.7, 0.7], [0.3, 0.7]]
    square = [[0, 1], [1, 2], [2, 3], [3, 0]]
    dom = hammesh.Domain(
        vertices=np.array(outer + inner),
        segments=np.array(square + [[a + 4, b + 4] for a, b in square]),
        segment_markers=np.array([1, 1, 1, 1, 5, 5, 5, 5]),
        regions=np.array([[0.5, 0.5, 2.0, np.nan], [0.1, 0.1, 1.0, np.nan]]),
    )
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=0.01)
    return hammesh.hamiltonian(m)


def edges_with_markers(segments: np.ndarray, markers: np.ndarray) -> list[tuple[int, int, int]]:
    """Undirected constrained edges with their markers, as a sorted list (a multiset)."""
    seg = np.sort(np.asarray(segments, dtype=np.int64), axis=1)
    return sorted(zip(seg[:, 0].tolist(), seg[:, 1].tolist(), np.asarray(markers).tolist()))


def test_fixture_has_internal_and_boundary_segments(ham) -> None:
    assert set(ham.segment_markers.tolist()) == {1, 5}
    assert len(ham.segments) > 8  # the input segments were split by the mesher


@pytest.mark.parametrize("suffix", SEGMENT_SUFFIXES)
def test_segments_and_markers_round_trip_and_check_passes(tmp_path: Path, ham, suffix, capsys) -> None:
    path = tmp_path / f"m{suffix}"
    hammesh.write(ham, path)
    back = hammesh.read_mesh(path)
    assert back.segments.dtype == np.int64 and back.segment_markers.dtype == np.int64
    assert edges_with_markers(back.segments, back.segment_markers) == edges_with_markers(
        ham.segments, ham.segment_markers
    )
    np.testing.assert_array_equal(back.points, ham.points)
    np.testing.assert_array_equal(back.triangles, ham.triangles)  # still the cycle order
    capsys.readouterr()
    assert main(["check", str(path)]) == 0
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("suffix", SEGMENT_SUFFIXES)
def test_check_rejects_a_stored_segment_that_is_not_an_edge(tmp_path: Path, ham, suffix, capsys) -> None:
    # the mesh vertices closest to two opposite corners are never joined by an edge
    a = int(np.argmin(np.hypot(*(ham.points - [0.0, 0.0]).T)))
    b = int(np.argmin(np.hypot(*(ham.points - [1.0, 1.0]).T)))
    edges = {frozenset(e) for t in ham.triangles.tolist() for e in zip(t, t[1:] + t[:1])}
    assert frozenset((a, b)) not in edges
    bad = dataclasses.replace(
        ham,
        segments=np.vstack([ham.segments, [[a, b]]]),
        segment_markers=np.append(ham.segment_markers, 9),
    )
    path = tmp_path / f"bad{suffix}"
    hammesh.write(bad, path)
    assert [a, b] in hammesh.read_mesh(path).segments.tolist()
    capsys.readouterr()
    assert main(["check", str(path)]) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "verification failed" in err and f"[{a}, {b}]" in err and "not an edge" in err


def test_check_pairs_the_half_edges_once(ham, tmp_path: Path, monkeypatch) -> None:
    """``hammesh check`` finds the pairing once (the certificate's kernel) for the runs,
    the cycle checks and the overlap test; a damaged file still fails."""
    from hammesh.verify import _kernels as cert_kernels

    path = tmp_path / "ham.vtu"
    hammesh.write(ham, path)
    real = cert_kernels.half_edge_twins
    calls = []

    def counted(tri, n_points):
        calls.append(len(tri))
        return real(tri, n_points)

    monkeypatch.setattr(cert_kernels, "half_edge_twins", counted)
    assert main(["check", str(path)]) == 0
    assert calls == [ham.n_triangles]
    swapped = ham.triangles.copy()
    swapped[[0, len(swapped) // 2]] = swapped[[len(swapped) // 2, 0]]
    hammesh.write(dataclasses.replace(ham, triangles=swapped), tmp_path / "bad.vtu")
    assert main(["check", str(tmp_path / "bad.vtu")]) == 3
