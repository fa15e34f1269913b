"""Thm 5.3: Christofides encoding round-trips, visits every triangle, stays within 9/4."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh.errors import InvalidOptionError
from hammesh.strips.christofides import christofides_strip, christofides_walk
from hammesh.strips.dual import dual_mesh
from hammesh.strips.gl import decode_gl_strip

from hammesh.mesh import Mesh

from tests.helpers import grid_mesh

from .conftest import delaunay_mesh, fan_mesh, oriented_set, square_mesh, torus_mesh


def check(mesh, enc):
    decoded = decode_gl_strip(enc.strip.indices, enc.strip.restart_index)
    assert set(oriented_set(decoded)) == set(oriented_set(mesh.triangles))
    m = mesh.n_triangles
    assert enc.n_triangles == m
    assert m <= enc.walk_length <= 2 * m + 2 * enc.n_ears
    assert enc.lower_bound == m + 2
    assert len(enc.strip.indices) <= 9 / 4 * enc.lower_bound
    assert enc.ratio <= 2.25
    # Lemma 5.2, counted independently from the buffer: empty (degenerate) windows
    drawn = len(decoded)
    assert drawn == enc.drawn >= m
    L, S = len(enc.strip.indices), enc.strip.n_strips
    windows = L - 2 if enc.strip.restart_index is None else L - (S - 1) - 2 * S
    assert windows - drawn == enc.empty
    assert enc.empty_bound == enc.walk_length / 2 + 2 * enc.n_ears
    assert enc.report()["within_5_2"] == (enc.empty <= enc.empty_bound)


@pytest.mark.parametrize(
    "mesh", [square_mesh(0.05), square_mesh(), grid_mesh(4, 3), torus_mesh(), fan_mesh(6)],
    ids=["square28", "square159", "grid", "torus", "fan"],
)
@pytest.mark.parametrize("join", ["stitch", "restart"])
def test_corpus(mesh, join):
    check(mesh, christofides_strip(mesh, join=join))


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(3, 60), st.booleans(), st.sampled_from(["stitch", "restart"]))
def test_random_delaunay(seed, n, lift, join):
    mesh = delaunay_mesh(seed, n, lift)
    check(mesh, christofides_strip(mesh, join=join))


def test_many_pieces_and_ears():
    """Several components (one of two triangles, fans full of ears) in one buffer."""
    f, g, z = fan_mesh(5), grid_mesh(1, 1), grid_mesh(4, 1)
    mesh = Mesh(
        np.r_[f.points, g.points + 10, z.points - 10],
        np.r_[f.triangles, g.triangles + len(f.points), z.triangles + len(f.points) + len(g.points)],
    )
    for join in ("stitch", "restart"):
        check(mesh, christofides_strip(mesh, join=join))


def test_walk_visits_every_triangle_with_adjacent_steps():
    d = dual_mesh(square_mesh())
    walk, starts = christofides_walk(d)
    assert set(walk.tolist()) == set(range(d.n_triangles))
    nb = d.neighbor_triangles
    assert all(walk[i + 1] in nb[walk[i]] for i in range(len(walk) - 1))


def test_size_limit():
    with pytest.raises(InvalidOptionError, match="up to 10 triangles"):
        christofides_strip(square_mesh(), max_triangles=10)


def test_larger_mesh_within_bound():
    mesh = square_mesh(0.003)  # ~500 triangles, well under a second
    check(mesh, christofides_strip(mesh))


@pytest.mark.slow
def test_a_few_thousand_triangles():
    mesh = square_mesh(5.5e-4)  # ~2,900 triangles, a few seconds (the matching)
    assert mesh.n_triangles > 2500
    enc = christofides_strip(mesh)
    check(mesh, enc)
    assert enc.walk_length < 1.25 * mesh.n_triangles
    assert enc.empty <= enc.empty_bound  # Lemma 5.2's figure, met with room on quality meshes
