"""The row cover (:mod:`hammesh.strips.rows`) and ``encode(method="rows")``."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh.strips import choose_strip, dual_mesh, encode
from hammesh.strips.gl import RESTART_INDEX, decode_gl_strip
from hammesh.strips.rows import ROW_AXES, parallel_edges, row_links, row_path_cover

from .conftest import delaunay_mesh, oriented_set, square_mesh, torus_mesh


def _edge_sines(points, tri, angle):
    """|sin| of each edge's angle to the axis, in plain Python (the oracle of parallel_edges)."""
    out = np.zeros(tri.shape)
    for t, row in enumerate(tri):
        for k in range(3):
            (x0, y0), (x1, y1) = points[row[k]][:2], points[row[(k + 1) % 3]][:2]
            dx, dy = x1 - x0, y1 - y0
            length = (dx * dx + dy * dy) ** 0.5
            out[t, k] = 0.0 if length == 0 else abs(dy * np.cos(angle) - dx * np.sin(angle)) / length
    return out


@given(st.integers(0, 2**32 - 1), st.integers(4, 120), st.sampled_from(ROW_AXES + (0.3,)))
@settings(max_examples=40, deadline=None)
def test_rows_are_paths_that_never_cross_a_refused_edge(seed, n, angle):
    m = delaunay_mesh(seed, n)
    dual = dual_mesh(m)
    refused = parallel_edges(dual.points, dual.triangles, angle)
    sines = _edge_sines(dual.points, dual.triangles, angle)
    assert np.allclose(sines[np.arange(len(refused)), refused], sines.min(axis=1))
    link = row_links(dual.twin, refused)
    assert ((link >= 0).sum(axis=1) <= 2).all()
    order, starts = row_path_cover(dual.points, dual.triangles, dual.twin, angle)
    assert sorted(order.tolist()) == list(range(dual.n_triangles))  # every triangle once
    path = np.empty(dual.n_triangles, np.int64)
    for i, (a, b) in enumerate(zip(starts[:-1], starts[1:])):
        path[order[a:b]] = i
        for t, u in zip(order[a : b - 1], order[a + 1 : b]):
            assert u in link[t]  # consecutive triangles are linked: neither refuses their edge
    # each path is a whole component of the link graph (a cycle is opened, never split)
    t, k = np.nonzero(link >= 0)
    assert (path[t] == path[link[t, k]]).all()


@given(st.integers(0, 2**32 - 1), st.integers(10, 200), st.booleans(), st.sampled_from(["rows", "auto"]))
@settings(max_examples=30, deadline=None)
def test_rows_method_draws_every_triangle_once_with_its_winding(seed, n, lift, method):
    m = delaunay_mesh(seed, n, lift)
    s = encode(m, method=method)
    assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(m.triangles)
    c = encode(m, method="rows", cache=16)
    assert oriented_set(decode_gl_strip(c.indices, c.restart_index)) == oriented_set(m.triangles)


def test_auto_keeps_the_shortest_and_rows_beat_the_greedy_cover_on_a_quality_mesh():
    """On a q30 square the rows (with the end moves) need fewer indices than the greedy cover
    (measured 1.294 -> 1.239 at 1.6k triangles); auto keeps the shortest buffer it tried."""
    m = square_mesh(1e-3)
    rows = encode(m, method="rows")
    auto = encode(m)
    dual = dual_mesh(m)
    from hammesh.strips.encode import greedy_paths, restart_strip

    order, starts = greedy_paths(dual)
    greedy = restart_strip(dual.triangles, dual.twin, order, starts, RESTART_INDEX)
    assert len(auto.indices) <= min(len(rows.indices), len(greedy.indices))
    assert rows.indices_per_triangle < greedy.indices_per_triangle - 0.02


def test_rows_on_a_surface_use_the_xy_projection_and_the_cli_offers_them_on_planar_meshes():
    t = torus_mesh(30, 20)
    s = encode(t, method="rows")
    assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(t.triangles)
    assert choose_strip(square_mesh(1e-2)).method in ("rows", "greedy", "zigzag")
    assert choose_strip(square_mesh(1e-2), method="rows", cache=16).method == "rows+cache"


@given(st.integers(0, 2**32 - 1), st.integers(4, 150), st.floats(0, 3.2))
@settings(max_examples=30, deadline=None)
def test_the_compiled_links_match_the_numpy_rule(seed, n, angle):
    from hammesh.strips._row_kernels import row_links_into

    dual = dual_mesh(delaunay_mesh(seed, n))
    m = dual.n_triangles
    refused, link = np.empty(m, np.int64), np.empty((m, 3), np.int64)
    row_links_into(dual.points, dual.triangles, dual.twin, np.cos(angle), np.sin(angle), refused, link)
    sines = _edge_sines(dual.points, dual.triangles, angle)
    assert np.allclose(sines[np.arange(m), refused], sines.min(axis=1))
    assert np.array_equal(link, row_links(dual.twin, refused))


@given(st.integers(0, 2**32 - 1), st.integers(30, 300), st.sampled_from([6, 16, 32]), st.sampled_from(ROW_AXES),
       st.integers(0, 4))
@settings(max_examples=25, deadline=None)
def test_band_layout_sends_whole_pieces_column_by_column(seed, n, N, angle, merge):
    """Without drift cuts or moved cuts: every piece inside one column, columns in order,
    serpentine heights, each piece a consecutive run of one path."""
    from hammesh.strips.rows import band_frame, band_layout, path_columns

    dual = dual_mesh(delaunay_mesh(seed, n))
    order, starts = row_path_cover(dual.points, dual.triangles, dual.twin, angle)
    frame = band_frame(dual.points, dual.triangles, N, angle)
    new, ns = band_layout(frame, dual.triangles, dual.twin, order, starts, merge)
    assert sorted(new.tolist()) == list(range(dual.n_triangles))
    # a triangle changes column only inside a run of fewer than `merge` of its path's
    # triangles in one column, and then takes the column of its neighbouring run
    pc = path_columns(frame.column, order, starts, merge)
    raw = frame.column[order]
    for a, b in zip(starts[:-1], starts[1:]):
        runs = np.split(np.arange(a, b), np.flatnonzero(np.diff(raw[a:b])) + 1)
        for i, r in enumerate(runs):
            if len(r) >= merge:
                assert np.array_equal(pc[r], raw[r])
            elif i > 0:  # a short run stays with the run before it
                assert (pc[r] == raw[runs[i - 1][0]]).all()
            elif len(runs) > 1:  # the path's first run: with the run after it
                assert (pc[r] == raw[runs[1][0]]).all()
    column = np.empty(dual.n_triangles, np.int64)
    column[order] = pc
    pieces = [new[a:b] for a, b in zip(ns[:-1], ns[1:])]
    cols = [set(column[p].tolist()) for p in pieces]
    assert all(len(c) == 1 for c in cols)  # a piece never crosses a column border
    col = [c.pop() for c in cols]
    assert col == sorted(col)  # column after column
    _assert_runs_of_paths(order, starts, pieces)
    for c in set(col):  # serpentine: mean heights up in even columns, down in odd ones
        h = [frame.height[p].mean() for p, k in zip(pieces, col) if k == c]
        assert h == sorted(h, reverse=c % 2 == 1)


def _assert_runs_of_paths(order, starts, pieces):
    """Each piece a consecutive run of one path of ``order`` (either direction)."""
    where = np.empty(len(order), np.int64)
    where[order] = np.arange(len(order))
    path = np.searchsorted(starts, where, side="right") - 1
    for p in pieces:
        pos = np.sort(where[p])
        assert len(set(path[p].tolist())) == 1
        assert np.array_equal(pos, np.arange(pos[0], pos[0] + len(p)))
        assert np.array_equal(where[p], pos) or np.array_equal(where[p], pos[::-1])


def _plain_piece_cost(dual, piece):
    """Indices of one piece in its better direction, by the writer itself (no restart)."""
    from hammesh.strips.encode import restart_strip

    best = None
    for p in (piece, piece[::-1]):
        s = restart_strip(dual.triangles, dual.twin, np.asarray(p, np.int64), np.array([0, len(p)], np.int64), RESTART_INDEX)
        best = len(s.indices) if best is None else min(best, len(s.indices))
    return best


@given(st.integers(0, 2**32 - 1), st.integers(30, 300), st.sampled_from([8, 16, 32]), st.sampled_from(ROW_AXES),
       st.integers(1, 4), st.sampled_from([0.0, 1.0, 3.0]))
@settings(max_examples=25, deadline=None)
def test_band_layout_moves_cuts_to_the_cheapest_place(seed, n, N, angle, reach, drift):
    """With moved cuts and drift cuts: whole runs of paths, each piece in a direction with
    no more indices than the other (the writer's own count), the compiled piece cost equal
    to the writer's, and (no drift cuts) every cut inside a path within ``reach`` of a
    column border."""
    from hammesh.strips._band_kernels import equal_pivots_into, piece_cost
    from hammesh.strips.rows import band_frame, band_layout, path_columns

    dual = dual_mesh(delaunay_mesh(seed, n))
    order, starts = row_path_cover(dual.points, dual.triangles, dual.twin, angle)
    frame = band_frame(dual.points, dual.triangles, N, angle)
    new, ns = band_layout(frame, dual.triangles, dual.twin, order, starts, 2, reach, drift)
    assert sorted(new.tolist()) == list(range(dual.n_triangles))
    pieces = [new[a:b] for a, b in zip(ns[:-1], ns[1:])]
    _assert_runs_of_paths(order, starts, pieces)
    twin3 = dual.twin.reshape(-1, 3)
    cum = np.empty(len(order) + 1, np.int64)
    equal_pivots_into(dual.triangles, twin3, order, starts, cum)
    where = np.empty(len(order), np.int64)
    where[order] = np.arange(len(order))
    for p in pieces:
        lo = int(where[p].min())
        plain = _plain_piece_cost(dual, p)
        assert piece_cost(dual.triangles, twin3, order, cum, lo, lo + len(p)) == plain
        assert _sent_cost(dual, p) == plain  # sent in a cheapest direction
    column = np.empty(dual.n_triangles, np.int64)
    column[order] = path_columns(frame.column, order, starts, 2)
    pc = column[order]
    raw_cuts = set()
    for a, b in zip(starts[:-1], starts[1:]):
        raw_cuts.update(int(i) for i in range(a + 1, b) if pc[i] != pc[i - 1])
    cuts = {int(where[p].min()) for p in pieces} - set(starts.tolist())
    if drift == 0:
        assert all(min((abs(c - r) for r in raw_cuts), default=reach + 1) <= reach for c in cuts)


@given(st.integers(0, 2**32 - 1), st.integers(30, 400), st.sampled_from([8, 16, 32]), st.sampled_from(ROW_AXES))
@settings(max_examples=25, deadline=None)
def test_band_layout_joins_pieces_only_where_that_saves_indices(seed, n, N, angle):
    """Joined pieces: every piece a dual path (consecutive triangles share an edge), every
    triangle once, each piece sent in a cheapest direction, the compiled chain cost equal to
    the writer's, and the whole buffer no longer than without the joins."""
    from hammesh.strips._band_kernels import chain_cost
    from hammesh.strips.encode import restart_strip
    from hammesh.strips.rows import band_frame, band_layout

    dual = dual_mesh(delaunay_mesh(seed, n))
    tri, twin = dual.triangles, dual.twin
    order, starts = row_path_cover(dual.points, tri, twin, angle)
    frame = band_frame(dual.points, tri, N, angle)
    plain = band_layout(frame, tri, twin, order, starts, 2, 2, 3.0)
    new, ns = band_layout(frame, tri, twin, order, starts, 2, 2, 3.0, join=True)
    assert sorted(new.tolist()) == list(range(dual.n_triangles))
    neighbours = {t: set((twin.reshape(-1, 3)[t][twin.reshape(-1, 3)[t] >= 0] // 3).tolist()) for t in range(len(tri))}
    link = np.full((len(tri), 2), -1, np.int64)
    for a, b in zip(ns[:-1], ns[1:]):
        p = new[a:b]
        assert all(int(v) in neighbours[int(u)] for u, v in zip(p[:-1], p[1:]))
        assert _sent_cost(dual, p) == _plain_piece_cost(dual, p)
        for u, v in zip(p[:-1], p[1:]):
            link[u, 1], link[v, 0] = v, u
        assert chain_cost(tri, twin.reshape(-1, 3), link, p[0]) == _plain_piece_cost(dual, p)
    ours = restart_strip(tri, twin, new, ns, RESTART_INDEX)
    assert len(ours.indices) <= len(restart_strip(tri, twin, *plain, RESTART_INDEX).indices)
    assert oriented_set(decode_gl_strip(ours.indices, ours.restart_index)) == oriented_set(tri)


def _sent_cost(dual, p):
    """Indices of piece ``p`` written in the direction it is given (no restart)."""
    from hammesh.strips.encode import restart_strip

    s = restart_strip(dual.triangles, dual.twin, np.asarray(p, np.int64), np.array([0, len(p)], np.int64), RESTART_INDEX)
    return len(s.indices)


def test_cache_mode_lays_rows_in_bands_on_planar_meshes():
    """q30 square, FIFO 16: the rows in bands load fewer vertices per triangle than
    meshoptimizer's vcache + stripify does on such meshes (0.706-0.714, measured in
    docs/strips.md) at far fewer indices (1.72 there); surfaces keep the chains."""
    from hammesh.strips import vertex_cache_stats

    m = square_mesh(1e-4)
    s = encode(m, cache=16)
    assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(m.triangles)
    acmr = vertex_cache_stats(s.indices, s.restart_index, m.n_triangles, 16).acmr
    plain = vertex_cache_stats(*(lambda g: (g.indices, g.restart_index))(encode(m)), m.n_triangles, 16).acmr
    assert acmr < 0.70 < plain and s.indices_per_triangle < 1.45
    t = torus_mesh(30, 20)
    c = encode(t, cache=16)
    assert oriented_set(decode_gl_strip(c.indices, c.restart_index)) == oriented_set(t.triangles)


def test_cache_mode_at_fifo_64_loads_fewer_vertices_within_1_30_indices():
    """q30 square, FIFO 64: rows of at most 11/16 of the FIFO (rows.band_slack) keep
    under 1.30 indices per triangle with fewer loads than meshoptimizer vcache + stripify's
    0.608-0.618 at FIFO 64 on such meshes (measured in docs/strips.md, session 13); rows of
    FIFO - 3 triangles (the slack at 16) load more at 64 than at 16."""
    from hammesh.strips import rows, vertex_cache_stats

    assert [rows.band_slack(n) for n in (3, 16, 32, 64)] == [3, 5, 10, 20]
    m = square_mesh(1e-4)
    s = encode(m, cache=64)
    assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(m.triangles)
    assert vertex_cache_stats(s.indices, s.restart_index, m.n_triangles, 64).acmr < 0.61
    assert s.indices_per_triangle < 1.30


def test_cache_mode_at_fifo_32_loads_fewer_vertices_within_1_30_indices():
    """q30 square of ~16k triangles, FIFO 32: cuts moved onto swaps and drift cuts (session 14)
    keep it at most 1.30 indices per triangle with fewer loads than meshoptimizer vcache +
    stripify's 0.636-0.643 at FIFO 32 on q30 meshes (docs/strips.md); without the moved cuts
    the same layout took 1.31-1.33."""
    from hammesh.strips import vertex_cache_stats

    m = square_mesh(1e-4)
    s = encode(m, cache=32)
    assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(m.triangles)
    assert vertex_cache_stats(s.indices, s.restart_index, m.n_triangles, 32).acmr < 0.636
    assert s.indices_per_triangle <= 1.30
