"""Vertex-cache figures, first-use numbering and the cache-aware mode (issue 16)."""

from __future__ import annotations

import json
from collections import deque

import meshio
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh.errors import InvalidOptionError
from hammesh.strips import decode_gl_strip, encode, reorder_vertices, vertex_cache_stats

from .conftest import delaunay_mesh, oriented_set, square_mesh, torus_mesh

R = 0xFFFFFFFF


def fifo_oracle(indices, restart, cache_size):
    """A FIFO cache as a deque: (loads, distinct)."""
    q: deque = deque()
    loads = 0
    for v in indices:
        if v == restart:
            continue
        if v not in q:
            loads += 1
            q.append(v)
            if len(q) > cache_size:
                q.popleft()
    return loads, len({v for v in indices if v != restart})


@settings(max_examples=60, deadline=None)
@given(st.lists(st.integers(0, 40), min_size=0, max_size=300), st.integers(3, 20), st.booleans())
def test_fifo_figures_match_a_deque(stream, cache_size, with_restart):
    idx = np.array([R if with_restart and v == 40 else v for v in stream], np.int64)
    s = vertex_cache_stats(idx, R if with_restart else None, 7, cache_size)
    loads, distinct = fifo_oracle(idx.tolist(), R if with_restart else -1, cache_size)
    assert s.vertices_transformed == loads
    assert s.acmr == pytest.approx(loads / 7)
    assert s.atvr == pytest.approx(loads / max(distinct, 1))
    assert (s.overfetch >= 1.0) or distinct == 0


def test_cache_size_below_three_is_refused():
    with pytest.raises(InvalidOptionError, match="cache"):
        vertex_cache_stats(np.arange(6), None, 4, 2)
    with pytest.raises(InvalidOptionError, match="cache"):
        encode(square_mesh(0.01), cache=2)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(0, 30), min_size=1, max_size=200), st.booleans())
def test_first_use_numbering(stream, with_restart):
    idx = np.array([R if with_restart and v == 30 else v for v in stream], np.int64)
    r = R if with_restart else None
    new, order = reorder_vertices(idx, r, 31)
    assert sorted(order.tolist()) == list(range(31))
    keep = idx != R
    assert np.array_equal(order[new[keep]], idx[keep]) and np.all(new[~keep] == R)
    seen = new[keep]
    firsts = [v for i, v in enumerate(seen.tolist()) if v not in seen[:i].tolist()]
    assert firsts == list(range(len(firsts)))  # first uses are 0, 1, 2, ...


@pytest.mark.parametrize("mesh", [square_mesh(0.001), torus_mesh(30, 20), delaunay_mesh(4, 800, True)],
                         ids=["square", "torus", "lifted-delaunay"])
@pytest.mark.parametrize("cache", [16, 32])
def test_cache_mode_round_trip_and_fewer_misses(mesh, cache):
    """Cache mode draws the mesh (proved by encode and checked here) with fewer FIFO misses than the default."""
    plain = encode(mesh)
    s = encode(mesh, cache=cache)
    assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(mesh.triangles)
    a = vertex_cache_stats(s.indices, s.restart_index, mesh.n_triangles, cache).acmr
    b = vertex_cache_stats(plain.indices, plain.restart_index, mesh.n_triangles, cache).acmr
    assert a < b


def test_reordered_vertices_draw_the_same_mesh():
    m = square_mesh(0.001)
    s = encode(m, cache=16, reorder_vertices=True)
    pts = m.points[s.vertex_order]
    tri = decode_gl_strip(s.indices, s.restart_index)
    back = s.vertex_order[tri]  # old numbering
    assert oriented_set(back) == oriented_set(m.triangles)
    assert np.allclose(pts[tri[0]], m.points[back[0]])
    plain = vertex_cache_stats(encode(m, cache=16).indices, R, m.n_triangles)
    assert vertex_cache_stats(s.indices, R, m.n_triangles).overfetch <= plain.overfetch


def test_cli_cache_and_reorder(tmp_path, capsys):
    from hammesh.cli import main

    def run(argv):
        return main(["strip", *map(str, argv)])

    t = square_mesh(0.002)
    src = tmp_path / "sq.vtu"
    meshio.write(src, meshio.Mesh(np.c_[t.points, np.zeros(len(t.points))], [("triangle", t.triangles)]))
    out = tmp_path / "s.json"
    assert run([src, "-o", out, "--cache", "32", "--reorder-vertices"]) == 0
    doc = json.loads(out.read_text())
    assert doc["method"] == "cache" and doc["cache_size"] == 32
    assert {"acmr", "atvr", "overfetch", "vertex_order"} <= set(doc)
    tri = decode_gl_strip(np.array(doc["indices"]), doc["restart_index"])
    assert oriented_set(np.array(doc["vertex_order"])[tri]) == oriented_set(t.triangles)
    assert "ACMR" in capsys.readouterr().out
    plain = tmp_path / "p.json"
    assert run([src, "-o", plain]) == 0
    assert json.loads(plain.read_text())["cache_size"] == 16
    alone = tmp_path / "a.json"  # --cache without N: hammesh.strips.cache.CACHE_MODE_FIFO
    assert run([src, "-o", alone, "--cache"]) == 0
    from hammesh.strips.cache import CACHE_MODE_FIFO

    doc = json.loads(alone.read_text())
    assert doc["method"] == "cache" and doc["cache_size"] == CACHE_MODE_FIFO == 32
    # a bare --cache before the mesh: the mesh is not read as its number
    first = tmp_path / "f.json"
    assert run(["--cache", src, "-o", first]) == 0
    assert json.loads(first.read_text())["cache_size"] == CACHE_MODE_FIFO


def test_cli_rejects_a_tiny_cache(tmp_path):
    from hammesh.cli import main

    t = square_mesh(0.01)
    src = tmp_path / "sq.vtu"
    meshio.write(src, meshio.Mesh(np.c_[t.points, np.zeros(len(t.points))], [("triangle", t.triangles)]))
    assert main(["strip", str(src), "-o", str(tmp_path / "x.json"), "--cache", "2"]) == 2
    assert not (tmp_path / "x.json").exists()
