"""Detail at float64's resolution (issue 12): Steiner points moved to float64 values that
keep the bound, certified in full; refused with the resolution named where none does."""

from __future__ import annotations

import re

import numpy as np
import pytest

import hammesh
from hammesh.domain import Domain
from hammesh.domain.resolution import _min_angles, snap_steiner_points
from hammesh.errors import InvalidDomainError

RING = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])


def _square(side: float, offset: float) -> np.ndarray:
    return np.array([[0, 0], [side, 0], [side, side], [0, side]]) + offset


@pytest.mark.parametrize("mode", ["sparse", "incircle"])
def test_a_1e6_square_at_1e9_is_meshed_and_verified(mode: str) -> None:
    """8 ulps wide: the rounded incenters give 18.4 deg (< 22.5); nearby float64 points
    give 28.07 deg, and the independent certificate passes."""
    m = hammesh.quality_mesh(Domain(_square(1e-6, 1e9), RING))
    h = hammesh.hamiltonian(m, mode=mode)
    assert h.report["verified"] and h.report["steiner_points_snapped"] >= 1
    assert h.report["min_angle_output_deg"] >= 0.5 * h.report["min_angle_input_deg"]
    stats = hammesh.verify(h, m)  # the public certificate, from the two meshes only
    assert stats["min_angle_output_deg"] == pytest.approx(h.report["min_angle_output_deg"])
    np.testing.assert_array_equal(h.points[: m.n_points], m.points)  # input points kept


def test_no_float64_point_keeps_the_bound_is_refused_with_the_resolution() -> None:
    """A 2-ulp square: no float64 point lies strictly inside its half triangles'
    incircles' neighbourhoods with the bound: refused (exit 2), never unverified."""
    side = 2 * np.spacing(1e9)
    m = hammesh.quality_mesh(Domain(_square(side, 1e9), RING))
    with pytest.raises(InvalidDomainError, match=r"only \d+ float64 steps \(ulps\).*the certificate found"):
        hammesh.hamiltonian(m, mode="incircle")


def test_snap_moves_only_steiner_points_and_never_turns_a_row_over() -> None:
    u = np.spacing(1e9)
    pts = np.array([[0, 0], [8, 0], [8, 8], [0, 8], [5.66, 2.34], [2.34, 5.66]]) * u + 1e9
    pts[4:] = np.round((pts[4:] - 1e9) / u) * u + 1e9  # the rounded incenters (6, 2), (2, 6)
    tri = np.array([[4, 0, 1], [4, 1, 2], [4, 2, 5], [5, 2, 3], [5, 3, 0], [5, 0, 4]])
    bound = np.radians(22.5)
    assert _min_angles(pts, tri).min() < bound
    out, moved = snap_steiner_points(pts, tri, 4, bound)
    assert moved >= 1 and _min_angles(out, tri).min() > _min_angles(pts, tri).min()  # better, maybe not enough
    np.testing.assert_array_equal(out[:4], pts[:4])
    keep = np.zeros(6, bool)
    keep[4] = True
    out2, _ = snap_steiner_points(pts, tri, 4, bound, keep=keep)
    assert np.array_equal(out2[4], pts[4]) and np.array_equal(out2[:4], pts[:4])
    a, b, c = (out[tri[:, i]] for i in range(3))
    area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    assert (area > 0).all()


def test_cli_meshes_the_far_square(tmp_path) -> None:
    import subprocess
    import sys

    poly = tmp_path / "far.poly"
    s = "1000000000.000001"
    poly.write_text(f"4 2 0 1\n1 1000000000 1000000000 1\n2 {s} 1000000000 1\n3 {s} {s} 1\n4 1000000000 {s} 1\n"
                    "4 1\n1 1 2 1\n2 2 3 1\n3 3 4 1\n4 4 1 1\n0\n")
    out = tmp_path / "far.vtu"
    run = subprocess.run([sys.executable, "-m", "hammesh", "mesh", str(poly), "-o", str(out)],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert re.search(r"verified", run.stdout) and out.exists()
    check = subprocess.run([sys.executable, "-m", "hammesh", "check", str(out)], capture_output=True, text=True,
                           timeout=600)
    assert check.returncode == 0, check.stderr
