"""A cover's strips sent in an order laid for a FIFO vertex cache (``encode(cache=N, method=greedy|zigzag)``)."""

from __future__ import annotations

import json
import sys
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
from hammesh.strips.cache import PIECE_LENGTH, REVERSAL_WEIGHT, fifo_strip_order, split_paths
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


def deque_loads(seq, C, fifo=()):
    """Loads of ``seq`` read after the FIFO ``fifo`` (oldest first), and the FIFO after it: a deque model."""
    q = deque(fifo)
    loads = 0
    for v in seq:
        if v not in q:
            q.append(v)
            loads += 1
            if len(q) > C:
                q.popleft()
    return loads, list(q)


def buffers(mesh, method="greedy"):
    """A cover's strips as index buffers (as the cover oriented them, and reversed) with their bounds."""
    dual, tri, twin, order, starts, ids = _oriented_local(mesh, method, None, dual_mesh(mesh))
    S = len(starts) - 1
    rev, _ = K.paths_in_order(order, starts, np.arange(S, dtype=np.int64), np.ones(S, np.bool_))
    out = []
    for o in (order, rev):
        b = restart_buffer(tri, twin, o, starts, -1).indices
        c = np.flatnonzero(b == -1)
        out += [b, np.r_[0, c + 1].astype(np.int64), np.r_[c, len(b)].astype(np.int64)]
    return dual, tri, twin, order, starts, out


def replay_greedy_edge(gain, ab, extra_f, extra_b, w):
    """The greedy edge in plain Python: pairs best first (stable), ends free, directions agree,
    no cycle, gain beats ``w`` per newly fixed extra index; chains head by head in strip order."""
    S = len(extra_f)
    dirn, succ, pred = [-1] * S, [-1] * S, [-1] * S
    comp = list(range(S))
    for p in sorted(range(len(gain)), key=lambda p: -gain[p]):
        a, da, b, db = map(int, ab[p])
        if succ[a] >= 0 or pred[b] >= 0 or dirn[a] not in (-1, da) or dirn[b] not in (-1, db):
            continue
        extra = (extra_b[a] if da else extra_f[a]) * (dirn[a] < 0) + (extra_b[b] if db else extra_f[b]) * (dirn[b] < 0)
        if gain[p] - w * extra <= 0 or comp[a] == comp[b]:
            continue
        old = comp[a]
        comp = [comp[b] if c == old else c for c in comp]
        succ[a], pred[b], dirn[a], dirn[b] = b, a, da, db
    pick, flip = [], []
    for s in range(S):
        if pred[s] < 0:
            x = s
            while x >= 0:
                pick.append(x)
                flip.append(bool(dirn[x] == 1) if dirn[x] >= 0 else bool(extra_f[x] > extra_b[x]))
                x = succ[x]
    return pick, flip


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 10_000), st.integers(30, 160), st.sampled_from([3, 4, 8, 16]))
def test_fifo_states_pair_gains_and_greedy_edge_match_plain_python(seed, n, C):
    mesh = delaunay_mesh(seed, n)
    dual, tri, twin, order, starts, (fw, flo, fhi, bw, blo, bhi) = buffers(mesh)
    S = len(starts) - 1
    n_pts = len(dual.points)
    seqs = {(s, d): (bw[blo[s]:bhi[s]] if d else fw[flo[s]:fhi[s]]).tolist() for s in range(S) for d in (0, 1)}
    for d, (buf, lo, hi) in enumerate(((fw, flo, fhi), (bw, blo, bhi))):
        states = K.fifo_states(buf, lo, hi, C, n_pts)
        for s in range(S):
            _, q = deque_loads(seqs[(s, d)], C)
            assert states[s].tolist() == [-1] * (C - len(q)) + q
    off, vt = K.strips_at_vertices(fw, flo, fhi, n_pts)
    gain, ab = K.pair_gains(fw, flo, fhi, bw, blo, bhi, off, vt, n_pts, C)
    got = {tuple(map(int, r)): int(g) for g, r in zip(gain, ab)}
    assert len(got) == len(gain)  # each pair once
    want = {}
    for a in range(S):
        for b in range(S):
            if a == b or not set(seqs[(a, 0)]) & set(seqs[(b, 0)]):
                continue
            for da in (0, 1):
                for db in (0, 1):
                    alone, _ = deque_loads(seqs[(b, db)], C)
                    after, _ = deque_loads(seqs[(b, db)], C, deque_loads(seqs[(a, da)], C)[1])
                    if alone - after > 0:
                        want[(a, da, b, db)] = alone - after
    assert got == want
    nf, nb = fhi - flo, bhi - blo
    ef, eb = (nf - np.minimum(nf, nb)).astype(float), (nb - np.minimum(nf, nb)).astype(float)
    pick, flip = K.greedy_edge_order(gain, ab, ef, eb, REVERSAL_WEIGHT)
    assert sorted(pick.tolist()) == list(range(S))
    assert (pick.tolist(), flip.tolist()) == replay_greedy_edge(gain, ab, ef, eb, REVERSAL_WEIGHT)
    # the paths come back whole, reversed where flipped
    o2, s2 = fifo_strip_order(tri, twin, order, starts, n_pts, C)
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
def test_cache_order_keeps_the_cover_in_pieces(mesh, monkeypatch):
    """Above 5,000 triangles with many swaps the greedy cover is the only one tried: every strip is
    a piece of one of its strips (at most PIECE_LENGTH * N triangles, the pieces of a strip of equal
    length), each piece costing at most a restart, two start indices and a reversal's swap more."""
    # without cache, planar meshes also try the rows (encode._ROWS_UP_TO): the greedy cover alone here
    monkeypatch.setattr(sys.modules["hammesh.strips.encode"], "_ROWS_UP_TO", 0)
    plain = encode(mesh, method="greedy")
    monkeypatch.undo()
    s = encode(mesh, method="greedy", cache=16)
    whole = strips_of(plain.indices)
    pieces = strips_of(s.indices)
    owner = {t: k for k, st_ in enumerate(whole) for t in st_}
    longest = PIECE_LENGTH * 16
    for p in pieces:
        assert len({owner[t] for t in p}) == 1 and len(p) <= longest
    counts = np.bincount([owner[next(iter(p))] for p in pieces], minlength=len(whole))
    assert counts.tolist() == [-(-len(w) // longest) for w in whole]
    assert len(s.indices) <= len(plain.indices) + 3 * (s.n_strips - plain.n_strips) + s.n_strips
    assert pieces != sorted(pieces, key=lambda p: min(owner[t] for t in p))  # re-ordered


def test_split_paths():
    st_ = np.array([0, 1, 49, 97, 200])
    out = split_paths(st_, 48)
    assert out.tolist() == [0, 1, 49, 97, 131, 165, 200]
    assert split_paths(np.array([0, 5]), 5).tolist() == [0, 5]


def test_one_long_strip_is_cut_into_pieces():
    """A closed torus is one greedy strip; in cache mode it is cut into strips of at most
    PIECE_LENGTH * N triangles (a longer strip cannot hand its vertices to the next one)."""
    t = torus_mesh(30, 20)
    plain = encode(t, method="greedy")
    assert plain.n_strips == 1
    s = encode(t, method="greedy", cache=16)
    assert s.n_strips == -(-t.n_triangles // (PIECE_LENGTH * 16))
    assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(t.triangles)
    assert vertex_cache_stats(s.indices, R, t.n_triangles, 16).acmr < vertex_cache_stats(plain.indices, R, t.n_triangles, 16).acmr


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
