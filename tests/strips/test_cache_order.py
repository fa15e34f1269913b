"""A cover's strips sent in an order laid for a FIFO vertex cache (``encode(cache=N, method=greedy|zigzag)``)."""

from __future__ import annotations

import json
from collections import deque

import meshio
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh.errors import InvalidOptionError
from hammesh.mesh import Mesh
from hammesh.strips import decode_gl_strip, dual_mesh, encode, vertex_cache_stats
from hammesh.strips import _cache_order_kernels as K
from hammesh.strips._emit_kernels import restart_buffer
from hammesh.strips.cache import REVERSAL_WEIGHT, fifo_strip_order
from hammesh.strips.choose import choose_strip
from hammesh.strips.encode import _oriented_local

from .conftest import delaunay_mesh, oriented_set, square_mesh, torus_mesh
from .defect_meshes import ALL

R = 0xFFFFFFFF


def strips_of(indices, restart=R):
    """Each strip of a restart-joined buffer as the set of oriented triangles it draws."""
    idx = np.asarray(indices, np.int64)
    cuts = np.flatnonzero(idx == restart)
    parts = np.split(idx, cuts)
    out = []
    for k, p in enumerate(parts):
        p = p[1:] if k > 0 else p
        out.append(frozenset(oriented_set(decode_gl_strip(p, None))))
    return out


def oracle_check(fw, bw, n_tri, C, pick, flip):
    """Replay the greedy with a deque FIFO; at each step the kernel's choice must score the minimum.

    Candidates: unsent strips through a cached vertex; score: (misses + w * extra) / triangles
    in the better direction; with no candidate, the first unsent strip.  Ties may go either way.
    """
    S = len(fw)
    fifo: deque = deque()
    used = [False] * S

    def misses(seq):
        q = deque(fifo)
        miss = 0
        for v in seq:
            if v not in q:
                q.append(v)
                miss += 1
                if len(q) > C:
                    q.popleft()
        return miss

    for k in range(S):
        cached = set(fifo)
        cands = [s for s in range(S) if not used[s] and cached & set(fw[s])]
        s_k, f_k = int(pick[k]), bool(flip[k])
        if not cands:
            assert s_k == used.index(False) and not f_k
        else:
            assert s_k in cands
            short = lambda s: min(len(fw[s]), len(bw[s]))  # noqa: E731
            score = lambda s, seq: (misses(seq) + REVERSAL_WEIGHT * (len(seq) - short(s))) / n_tri[s]  # noqa: E731
            best = min(min(score(s, fw[s]), score(s, bw[s])) for s in cands)
            got = score(s_k, bw[s_k] if f_k else fw[s_k])
            assert got <= best + 1e-12
        used[s_k] = True
        for v in bw[s_k] if f_k else fw[s_k]:
            if v not in fifo:
                fifo.append(v)
                if len(fifo) > C:
                    fifo.popleft()


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 10_000), st.integers(30, 160), st.sampled_from([3, 4, 8, 16]))
def test_fifo_order_is_the_greedy_of_the_rule(seed, n, C):
    mesh = delaunay_mesh(seed, n)
    dual, tri, twin, order, starts, ids = _oriented_local(mesh, "greedy", None, dual_mesh(mesh))
    S = len(starts) - 1
    rev, _ = K.paths_in_order(order, starts, np.arange(S, dtype=np.int64), np.ones(S, np.bool_))
    fwb = restart_buffer(tri, twin, order, starts, -1).indices
    bwb = restart_buffer(tri, twin, rev, starts, -1).indices
    cf, cb = np.flatnonzero(fwb == -1), np.flatnonzero(bwb == -1)
    flo, fhi = np.r_[0, cf + 1], np.r_[cf, len(fwb)]
    blo, bhi = np.r_[0, cb + 1], np.r_[cb, len(bwb)]
    off, vt = K.strips_at_vertices(fwb, flo, fhi, len(dual.points))
    pick, flip = K.fifo_strip_order(fwb, flo, fhi, bwb, blo, bhi, np.diff(starts).astype(float), off, vt,
                                    len(dual.points), C, REVERSAL_WEIGHT)
    assert sorted(pick.tolist()) == list(range(S))
    fw = [fwb[a:b].tolist() for a, b in zip(flo, fhi)]
    bw = [bwb[a:b].tolist() for a, b in zip(blo, bhi)]
    oracle_check(fw, bw, np.diff(starts), C, pick, flip)
    # the paths come back whole, reversed where flipped
    o2, s2 = fifo_strip_order(tri, twin, order, starts, len(dual.points), C)
    assert len(s2) == len(starts)
    for k in range(S):
        p = order[starts[pick[k]] : starts[pick[k] + 1]]
        assert np.array_equal(o2[s2[k] : s2[k + 1]], p[::-1] if flip[k] else p)


@pytest.mark.parametrize("method", ["greedy", "zigzag"])
@pytest.mark.parametrize("mesh", [square_mesh(0.001), delaunay_mesh(4, 800), delaunay_mesh(5, 800, True)],
                         ids=["square", "delaunay", "lifted-delaunay"])
def test_cache_order_draws_the_mesh_with_fewer_loads(mesh, method):
    """Every triangle once with its winding, fewer FIFO loads than the cover in its own order."""
    plain = encode(mesh, method=method)
    s = encode(mesh, method=method, cache=16)
    assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(mesh.triangles)
    a = vertex_cache_stats(s.indices, R, mesh.n_triangles, 16).acmr
    b = vertex_cache_stats(plain.indices, R, mesh.n_triangles, 16).acmr
    assert a < b


@pytest.mark.parametrize("mesh", [square_mesh(0.0001), delaunay_mesh(6, 6000)], ids=["square-15k", "delaunay-12k"])
def test_cache_order_keeps_the_cover(mesh):
    """Above 5,000 triangles with many swaps the greedy cover is the only one tried: the same strips
    (as sets of oriented triangles), at most one more swap per strip (a reversed one)."""
    plain = encode(mesh, method="greedy")
    s = encode(mesh, method="greedy", cache=16)
    assert sorted(strips_of(s.indices), key=sorted) == sorted(strips_of(plain.indices), key=sorted)
    assert len(plain.indices) <= len(s.indices) <= len(plain.indices) + s.n_strips
    assert strips_of(s.indices) != strips_of(plain.indices)  # re-ordered


def test_one_strip_is_left_alone():
    t = torus_mesh(30, 20)
    plain = encode(t, method="greedy")
    assert plain.n_strips == 1
    assert np.array_equal(encode(t, method="greedy", cache=16).indices, plain.indices)


def test_stitched_and_reordered_vertices():
    m = square_mesh(0.002)
    s = encode(m, method="greedy", cache=16, join="stitch", reorder_vertices=True)
    tri = s.vertex_order[decode_gl_strip(s.indices, s.restart_index)]
    assert oriented_set(tri) == oriented_set(m.triangles)


def test_choose_strip_and_cli(tmp_path):
    from hammesh.cli import main

    m = square_mesh(0.002)
    c = choose_strip(m, method="zigzag", cache=16)
    assert c.method == "zigzag+cache" and c.extra["cache_size"] == 16
    with pytest.raises(InvalidOptionError, match="cache"):
        choose_strip(m, method="order", cache=16)
    src = tmp_path / "sq.vtu"
    meshio.write(src, meshio.Mesh(np.c_[m.points, np.zeros(len(m.points))], [("triangle", m.triangles)]))
    out = tmp_path / "s.json"
    assert main(["strip", str(src), "-o", str(out), "--cache", "16", "--method", "greedy"]) == 0
    doc = json.loads(out.read_text())
    assert doc["method"] == "greedy+cache"
    tri = decode_gl_strip(np.array(doc["indices"]), doc["restart_index"])
    assert oriented_set(tri) == oriented_set(m.triangles)


@pytest.mark.parametrize("name", sorted(ALL))
@pytest.mark.parametrize("method", ["greedy", "zigzag", "auto"])
def test_defect_meshes_in_fifo_order(name, method):
    """Surfaces with bad edges and dropped rows: every drawable row once with its winding (the proof
    inside encode, and decoded here), the same defects and dropped rows as without ``cache``."""
    pts, tri, _ = ALL[name]()
    mesh = Mesh(pts, tri)
    plain = encode(mesh, method="greedy" if method == "auto" else method)
    s = encode(mesh, method=method, cache=16)
    keep = np.setdiff1d(np.arange(len(tri)), s.dropped)
    assert np.array_equal(s.dropped, plain.dropped) and s.defects == plain.defects
    assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(tri[keep])


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10_000), st.integers(4, 300), st.booleans(), st.sampled_from(["greedy", "zigzag", "auto"]),
       st.sampled_from([3, 7, 16, 32]))
def test_random_meshes_round_trip_in_fifo_order(seed, n, lift, method, C):
    mesh = delaunay_mesh(seed, n, lift)
    s = encode(mesh, method=method, cache=C)  # proved inside encode
    assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(mesh.triangles)
    assert s.n_triangles == mesh.n_triangles
