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

from .conftest import fan_mesh, grid_mesh, oriented_set, square_mesh, torus_mesh
from .test_encode import delaunay_mesh


def check(mesh, enc):
    decoded = decode_gl_strip(enc.strip.indices, enc.strip.restart_index)
    assert set(oriented_set(decoded)) == set(oriented_set(mesh.triangles))
    m = mesh.n_triangles
    assert enc.n_triangles == m
    assert m <= enc.walk_length <= 2 * m + 2 * enc.n_ears
    assert enc.lower_bound == m + 2
    assert len(enc.strip.indices) <= 9 / 4 * enc.lower_bound
    assert enc.ratio <= 2.25


@pytest.mark.parametrize(
    "mesh", [square_mesh(0.05), square_mesh(), grid_mesh(4, 3), torus_mesh(), fan_mesh(6)],
    ids=["square28", "square159", "grid", "torus", "fan"],
)
@pytest.mark.parametrize("join", ["stitch", "restart"])
def test_corpus(mesh, join):
    check(mesh, christofides_strip(mesh, join=join))


@settings(max_examples=15)
@given(st.integers(0, 2**32 - 1), st.integers(3, 40), st.booleans())
def test_random_delaunay(seed, n, lift):
    mesh = delaunay_mesh(seed, n, lift)
    check(mesh, christofides_strip(mesh))


def test_walk_visits_every_triangle_with_adjacent_steps():
    d = dual_mesh(square_mesh())
    walk, starts = christofides_walk(d)
    assert set(walk.tolist()) == set(range(d.n_triangles))
    nb = d.neighbor_triangles
    assert all(walk[i + 1] in nb[walk[i]] for i in range(len(walk) - 1))


def test_size_limit():
    with pytest.raises(InvalidOptionError, match="up to 10 triangles"):
        christofides_strip(square_mesh(), max_triangles=10)


@pytest.mark.slow
def test_larger_mesh_within_bound():
    mesh = square_mesh(0.003)  # ~500 triangles, ~15 s (networkx matching)
    check(mesh, christofides_strip(mesh))
