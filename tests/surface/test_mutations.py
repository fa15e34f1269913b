"""Mutation tests of the surface certificate (issue 11, item 4, for ``hammesh.surface``).

Each test injects one construction bug (a monkeypatch of what ``surface_hamiltonian``
calls, or a damaged result) and asserts that ``surface_hamiltonian`` raises
:class:`~hammesh.errors.VerificationError` naming the fault: the certificate derives its
facts itself, so a bug in the construction's pairing, degenerate-row test, orientation,
angles or bookkeeping cannot make it agree.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from hammesh.errors import VerificationError
from hammesh.surface import hamiltonian as construction
from hammesh.surface import noisy_sphere, surface_hamiltonian, thick_plate
from hammesh.surface.shapes import torus
from tests.strips.defect_meshes import ALL


def _patch_result(monkeypatch, damage):
    """Let the sparse construction run, then ``damage`` its result (before welding back)."""
    real = construction.sparse_cycles

    def broken(*args, **kwargs):
        return damage(real(*args, **kwargs))

    monkeypatch.setattr(construction, "sparse_cycles", broken)


def test_dropped_pairings_split_a_piece(monkeypatch):
    """The construction's pairing loses triangle 0's three edges: two cycles for one piece."""
    real = construction.proper_pairing

    def lossy(tri, n):
        p = real(tri, n)
        tw = p.twin.copy()
        tw[tw[:3][tw[:3] >= 0]] = -1
        tw[:3] = -1
        return p._replace(twin=tw)

    monkeypatch.setattr(construction, "proper_pairing", lossy)
    with pytest.raises(VerificationError, match="share a proper edge but lie in different cycles"):
        surface_hamiltonian(*torus(12, 8))


def test_a_legitimate_triangle_treated_as_degenerate(monkeypatch):
    """The construction's zero-area test is wrong for row 5: it is left out."""
    real = construction.zero_area_rows

    def wrong(pts, tri):
        z = real(pts, tri)
        z[5] = True
        return z

    monkeypatch.setattr(construction, "zero_area_rows", wrong)
    with pytest.raises(VerificationError, match=r"input triangle 5 .* is left out"):
        surface_hamiltonian(*torus(12, 8))


def test_flipped_triangle_silently_reoriented(monkeypatch):
    """The construction 'repairs' a flipped input triangle: the cuts no longer match the input."""
    pts, tri, _ = ALL["one flipped triangle"]()
    real = construction.prepare_surface

    def repairing(points, triangles):
        t = np.array(triangles, copy=True)
        t[3] = t[3, ::-1]
        return real(points, t)

    monkeypatch.setattr(construction, "prepare_surface", repairing)
    with pytest.raises(VerificationError, match="cuts changed"):
        surface_hamiltonian(pts, tri)


def test_weld_back_forgotten(monkeypatch):
    """The copies of the unwelded vertices stay: the seam of the Klein bottle is lost."""
    monkeypatch.setattr(construction, "_weld_back", lambda r, n, copy_of: r)
    pts, tri, _ = ALL["klein"]()
    with pytest.raises(VerificationError, match="cuts changed"):
        surface_hamiltonian(pts, tri)


def test_steiner_point_off_the_plane(monkeypatch):
    pts, tri = torus(12, 8)  # needs Steiner points (100 points out for 96 in)

    def lift(r):
        assert len(r.points) > len(pts)
        p = r.points.copy()
        p[-1] *= 1.001  # a midpoint (or incenter) off its input triangle's plane
        return replace(r, points=p)

    _patch_result(monkeypatch, lift)
    with pytest.raises(VerificationError, match="leaves the plane"):
        surface_hamiltonian(pts, tri)


def test_two_rows_swapped(monkeypatch):
    def swap(r):
        t = r.triangles.copy()
        t[[1, 7]] = t[[7, 1]]
        return replace(r, triangles=t, parent=r.parent[[0, 7, 2, 3, 4, 5, 6, 1, *range(8, len(t))]])

    _patch_result(monkeypatch, swap)
    with pytest.raises(VerificationError, match="breaks at triangle"):
        surface_hamiltonian(*torus(12, 8))


def test_run_length_off_by_one(monkeypatch):
    pts, tri, _ = ALL["finned torus (bunny stand-in)"]()

    def shift(r):
        lengths = r.lengths.copy()
        lengths[0] += 1
        lengths[1] -= 1
        return replace(r, lengths=lengths)

    _patch_result(monkeypatch, shift)
    with pytest.raises(VerificationError, match="breaks at triangle|not a cycle|different cycles"):
        surface_hamiltonian(pts, tri)


def test_wrong_parent(monkeypatch):
    def mislabel(r):
        par = r.parent.copy()
        k = int(np.argmax(par != par[0]))
        par[[0, k]] = par[[k, 0]]  # both input triangles still covered, by each other's pieces
        return replace(r, parent=par)

    _patch_result(monkeypatch, mislabel)
    with pytest.raises(VerificationError, match="leaves the plane|cover area"):
        surface_hamiltonian(*noisy_sphere(2, noise=0.1))


def test_triangle_duplicated(monkeypatch):
    def dup(r):
        t = r.triangles.copy()
        t[2] = t[0]
        return replace(r, triangles=t)

    _patch_result(monkeypatch, dup)
    with pytest.raises(VerificationError, match="appears twice"):
        surface_hamiltonian(*torus(12, 8))


def test_output_triangle_flipped(monkeypatch):
    def flip(r):
        t = r.triangles.copy()
        t[4] = t[4, ::-1]
        return replace(r, triangles=t)

    _patch_result(monkeypatch, flip)
    with pytest.raises(VerificationError, match="breaks at triangle"):
        surface_hamiltonian(*torus(12, 8))


def test_input_vertex_moved(monkeypatch):
    def move(r):
        p = r.points.copy()
        p[0] += 1e-9
        return replace(r, points=p)

    _patch_result(monkeypatch, move)
    with pytest.raises(VerificationError, match="input points are not kept"):
        surface_hamiltonian(*torus(12, 8))


def test_wrong_angle_cache(monkeypatch):
    """The construction's input minimum angle is 10x too small.

    Before issue 13 its swaps then went below half the true minimum (and the
    certificate refused them). Sparse mode now judges every join by its parents' own
    angles (a usable join keeps >= 1/2 of them), so a wrong global minimum no longer
    reaches the output: verified, and the bound holds against the true minimum.
    """
    real = construction.surface_angles

    def small(points, triangles):
        amin, i, amax, area = real(points, triangles)
        return amin / 10, i, amax, area

    monkeypatch.setattr(construction, "surface_angles", small)
    pts, tri = thick_plate(0.01)
    h = surface_hamiltonian(pts, tri, swaps=True)
    true_min = real(pts, tri)[0]
    assert h.report["verified"] and h.report["swaps"] > 0
    assert np.radians(h.report["min_angle_output_deg"]) >= 0.5 * true_min * (1 - 1e-9)


def test_unpatched_runs_pass():
    """The same inputs without a bug are verified (the tests above fail for the bug only)."""
    for pts, tri in (torus(12, 8), noisy_sphere(2, noise=0.1), ALL["klein"]()[:2], ALL["one flipped triangle"]()[:2]):
        assert surface_hamiltonian(pts, tri).report["verified"]
    assert surface_hamiltonian(*thick_plate(0.01), swaps=True).report["verified"]
