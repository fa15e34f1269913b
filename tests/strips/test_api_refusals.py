"""The strips API refuses what is not a mesh or a valid index with a HammeshError
(a tuple, an array or a string gave an AttributeError; a float buffer was truncated)."""

from __future__ import annotations

import numpy as np
import pytest

import hammesh
from hammesh import strips
from hammesh.errors import InvalidOptionError


@pytest.fixture(scope="module")
def square():
    return hammesh.quality_mesh(hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]]), max_area=0.05)


@pytest.mark.parametrize("bad", ["x", None, "tuple", "array"])
def test_encode_and_the_dual_need_a_mesh(square, bad):
    value = {"tuple": (square.points, square.triangles), "array": square.triangles}.get(bad, bad)
    for call in (strips.encode, strips.sequential_order):
        with pytest.raises(InvalidOptionError, match="mesh=.* must be a hammesh.Mesh"):
            call(value)


@pytest.mark.parametrize("restart", [-1, 2**32, 1.5, "x"])
def test_restart_index_is_a_uint32(square, restart):
    with pytest.raises(InvalidOptionError, match="restart_index"):
        strips.encode(square, restart_index=restart)


def test_restart_index_at_the_top_of_uint32_works(square):
    s = strips.encode(square, restart_index=2**32 - 1)
    got = strips.decode_gl_strip(s.indices, s.restart_index)
    assert sorted(map(sorted, got.tolist())) == sorted(map(sorted, square.triangles.tolist()))


@pytest.mark.parametrize("indices, match", [(np.array([0.0, 1.0, 2.0]), "integers"), ([0, 1, -2, 3], ">= 0")])
def test_decode_refuses_floats_and_negative_indices(indices, match):
    with pytest.raises(InvalidOptionError, match=match):
        strips.decode_gl_strip(indices, restart_index=7)
