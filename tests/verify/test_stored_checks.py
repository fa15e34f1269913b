"""``hammesh check`` of what hammesh writes (:mod:`hammesh.verify.stored`): ``--path``
(:mod:`hammesh.verify.path`): a path mesh written by the
polygon constructions passes; every mutation that breaks a promise of a path mesh
fails, naming the fault."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from hammesh.errors import InvalidDomainError, VerificationError
from hammesh.polygon import steiner_hamiltonian
from hammesh.verify.path import verify_stored_path_mesh
from tests.polygon.shapes import comb, dented

polygons = st.one_of(
    st.builds(lambda n, r, seed: dented(n, min(r, n // 4), seed), st.integers(6, 30), st.integers(0, 6),
              st.integers(0, 10_000)),
    st.builds(comb, st.integers(1, 6)),
)


def _path_mesh(points: np.ndarray, kind: str = "path") -> tuple[np.ndarray, np.ndarray]:
    try:
        q, t = steiner_hamiltonian(points, kind)
    except InvalidDomainError:  # (a dented polygon with few corners may cross itself)
        assume(False)
    return np.asarray(q, dtype=np.float64), np.asarray(t, dtype=np.int64)


@settings(max_examples=40, deadline=None)
@given(polygons, st.sampled_from(["path", "cycle"]))
def test_the_polygon_constructions_outputs_pass(points, kind):
    q, t = _path_mesh(points, kind)
    runs, stats, twin = verify_stored_path_mesh(q, t)
    assert runs.tolist() == [len(t)]
    assert 0 < stats["min_angle_output_deg"] <= stats["max_angle_output_deg"] < 180
    assert len(twin) == 3 * len(t)
    if kind == "cycle" and len(t) >= 3:
        assert stats["closed_runs"] == 1


@settings(max_examples=40, deadline=None)
@given(polygons, st.integers(0, 10**6))
def test_two_triangles_swapped_break_the_path(points, pick):
    q, t = _path_mesh(points)
    if len(t) < 3:
        return
    i = pick % (len(t) - 1)
    j = (i + 1 + pick // len(t) % (len(t) - 2)) % len(t)
    moved = t.copy()
    moved[[i, j]] = moved[[j, i]]
    # (a swap may leave a path: then the check must pass; else it names the break)
    nb = [set(map(tuple, np.sort(r[[0, 1, 1, 2, 2, 0]].reshape(3, 2), axis=1))) for r in moved]
    still = all(nb[k] & nb[k + 1] for k in range(len(moved) - 1))
    if still:
        verify_stored_path_mesh(q, moved)
    else:
        with pytest.raises(VerificationError, match="path breaks at triangle"):
            verify_stored_path_mesh(q, moved)


@settings(max_examples=25, deadline=None)
@given(polygons, st.integers(0, 10**6))
def test_a_clockwise_triangle_fails(points, pick):
    q, t = _path_mesh(points)
    bad = t.copy()
    k = pick % len(t)
    bad[k] = bad[k, ::-1]
    with pytest.raises(VerificationError):  # (the pairing sees a directed edge twice, or the orientation test)
        verify_stored_path_mesh(q, bad)


def test_a_missing_constrained_edge_and_a_split_piece_fail():
    q, t = _path_mesh(comb(3))
    with pytest.raises(VerificationError, match="constrained edge"):
        verify_stored_path_mesh(q, t, segments=np.array([[0, len(q) // 2]]))
    two = np.vstack([t, t + len(q)])
    pts = np.vstack([q, q + [10 * np.ptp(q[:, 0]) + 1, 0]])
    runs, _, _ = verify_stored_path_mesh(pts, two)
    assert runs.tolist() == [len(t), len(t)]
    mixed = np.vstack([two[:1], two[len(t):len(t) + 1], two[1:len(t)], two[len(t) + 1:]])
    with pytest.raises(VerificationError, match="not stored as one consecutive"):
        verify_stored_path_mesh(pts, mixed)


def test_cli_check_path(tmp_path):
    outline = tmp_path / "L.txt"
    outline.write_text("0 0\n4 0\n4 1\n1 1\n1 3\n0 3\n")
    out = tmp_path / "L.vtu"
    run = [sys.executable, "-m", "hammesh"]
    assert subprocess.run(run + ["polygon", str(outline), "--steiner", "path", "-o", str(out)],
                          capture_output=True).returncode == 0
    cycle = subprocess.run(run + ["check", str(out)], capture_output=True, text=True)
    assert cycle.returncode == 3 and "--path" in cycle.stderr
    path = subprocess.run(run + ["check", str(out), "--path"], capture_output=True, text=True)
    assert path.returncode == 0 and "Hamiltonian path(s)" in path.stdout


def test_cli_check_surface_of_a_folded_flat_surface(tmp_path):
    # a flat (z = 0) surface folded over itself along x = 1: `hammesh surface` verifies it;
    # plain check reads a constant-z file as planar (inverted rows) and says to use --surface
    import meshio

    p = np.array([[x, y, 0.0] for y in range(3) for x in range(3)], float)
    t = []
    for j in range(2):
        for i in range(2):
            a = j * 3 + i
            t += [[a, a + 1, a + 4], [a, a + 4, a + 3]]
    p[[2, 5, 8], 0] = 0.5
    src, out = tmp_path / "fold.obj", tmp_path / "fold_s.vtu"
    meshio.Mesh(p, [("triangle", np.array(t))]).write(src)
    run = [sys.executable, "-m", "hammesh"]
    assert subprocess.run(run + ["surface", str(src), "-o", str(out)], capture_output=True).returncode == 0
    plain = subprocess.run(run + ["check", str(out)], capture_output=True, text=True)
    assert plain.returncode == 3 and "--surface" in plain.stderr
    surface = subprocess.run(run + ["check", str(out), "--surface"], capture_output=True, text=True)
    assert surface.returncode == 0, surface.stderr
    both = subprocess.run(run + ["check", str(out), "--surface", "--path"], capture_output=True, text=True)
    assert both.returncode == 2 and len(both.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("suffix", [".vtu", ".ply", ".obj"])
def test_check_of_a_double_sided_surface_output(tmp_path, suffix):
    # (session 17's tester: a double-sided face keeps both sides, their Steiner points
    # lie at one place as two vertices; `check` welded them and refused the output)
    import meshio

    from hammesh.surface.shapes import double_sided

    pts, tri = double_sided()
    src, out = tmp_path / "ds.vtu", tmp_path / f"ds_s{suffix}"
    meshio.Mesh(pts, [("triangle", tri)]).write(src)
    run = [sys.executable, "-m", "hammesh"]
    made = subprocess.run(run + ["surface", str(src), "-o", str(out)], capture_output=True, text=True)
    assert made.returncode == 0, made.stderr
    checked = subprocess.run(run + ["check", str(out)], capture_output=True, text=True)
    assert checked.returncode == 0, checked.stderr
