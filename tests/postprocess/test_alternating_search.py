"""The alternating-cycle search's pruning (``_join_kernels.alternating_cycles_into``).

A pair of steps ending at ``z`` with ``r`` pairs left is expanded only if ``z`` lies
within ``2 r + 1`` dual steps of ``t`` (``_back_distances``). A pruned branch holds no
cycle that closes within the depth, so with a budget that does not bind the search
must give exactly the cycles, in the same order, of the plain depth-first search it
was (re-implemented here in Python, without the pruning), on meshes and cover edges
drawn by hypothesis; and every cycle must alternate and close at ``t``.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.halfedge import prepare_mesh
from hammesh.postprocess import _join_kernels as J
from hammesh.postprocess.cycle_cover import cycle_cover
from tests.helpers import blob, bundled_domain


def _plain_search(twin, is_cov, blocked, h0, depth, max_cycles, budget=10**9):
    """The iterative-deepening depth-first search without pruning (the reference),
    counting its steps as the kernel does (one per cover edge looked across)."""
    t, u = h0 // 3, twin[h0] // 3
    out = []
    steps = [0]

    class Stop(Exception):
        pass

    def dfs(x, level, nodes, flips, limit):
        for j in range(3):
            f = 3 * x + j
            if not is_cov[f] or twin[f] < 0:
                continue
            steps[0] += 1
            if steps[0] > budget:
                raise Stop
            y = twin[f] // 3
            if y == t:
                if level > limit - 4 or limit == 4:
                    out.append(flips + [f])
                    if len(out) == max_cycles:
                        raise Stop
                continue
            if level >= limit or blocked[y] or y in nodes:
                continue
            g = [3 * y + i for i in range(3) if not is_cov[3 * y + i]]
            if not g or twin[g[0]] < 0:
                continue
            z = twin[g[0]] // 3
            if blocked[z] or z in nodes:
                continue
            dfs(z, level + 1, nodes + [y, z], flips + [f, g[0]], limit)

    try:
        for limit in range(4, depth + 1, 4):
            dfs(u, 0, [t, u], [h0], limit)
    except Stop:
        pass
    return out


def _mesh(name: str, area: float):
    m = hammesh.quality_mesh(bundled_domain(name), min_angle=30, max_area=area)
    clean, he, _ = prepare_mesh(m)
    tri, tw = clean.triangles, he.twin
    cover = cycle_cover(tri, tw)
    return tri, tw, cover


_MESHES: dict = {}


def _cached(name: str, area: float):
    if (name, area) not in _MESHES:
        _MESHES[name, area] = _mesh(name, area)
    return _MESHES[name, area]


@settings(max_examples=30, deadline=None)
@given(
    name=st.sampled_from(["face", "la", "double_hex"]),
    area=st.sampled_from([0.5, 0.05]),
    pick=st.integers(0, 10**6),
    depth=st.sampled_from([4, 8]),
    block=st.floats(0.0, 0.3),
    seed=st.integers(0, 2**31 - 1),
    budget=st.integers(1, 3000),
)
def test_pruned_search_finds_the_plain_searchs_cycles(name, area, pick, depth, block, seed, budget) -> None:
    tri, tw, cover = _cached(name, area)
    is_cov, cyc = cover.is_cov, cover.cycle
    m = len(tri)
    # a non-cover half-edge between two covered triangles
    h = np.flatnonzero((~is_cov) & (tw >= 0) & (cyc[np.arange(3 * m) // 3] >= 0) & (cyc[np.maximum(tw, 0) // 3] >= 0))
    if not len(h):
        return
    h0 = int(h[pick % len(h)])
    rng = np.random.default_rng(seed)
    blocked = rng.random(m) < block
    blocked[[h0 // 3, tw[h0] // 3]] = False
    max_cycles = 64
    out = np.empty(max_cycles * (2 * depth + 2), np.int64)
    starts = np.empty(max_cycles + 1, np.int64)
    n = J.alternating_cycles_into(tw, is_cov, blocked, h0, depth, 10**9, out, starts, max_cycles)
    got = [out[starts[i]:starts[i + 1]].tolist() for i in range(n)]
    want = _plain_search(tw, is_cov, blocked, h0, depth, max_cycles)
    assert got == want
    # with a budget that binds, the pruned search skips only steps in branches that
    # cannot close: what the plain search finds is a prefix of what it finds
    n = J.alternating_cycles_into(tw, is_cov, blocked, h0, depth, budget, out, starts, max_cycles)
    got_b = [out[starts[i]:starts[i + 1]].tolist() for i in range(n)]
    want_b = _plain_search(tw, is_cov, blocked, h0, depth, max_cycles, budget)
    assert got_b[: len(want_b)] == want_b
    t = h0 // 3
    for flips in got:
        # alternating: non-cover, cover, non-cover, ..., cover back into t; a closed walk
        assert [bool(is_cov[f]) for f in flips] == [i % 2 == 1 for i in range(len(flips))]
        assert flips[0] == h0 and tw[flips[-1]] // 3 == t
        for a, b in zip(flips, flips[1:]):
            assert tw[a] // 3 == b // 3
        visited = [f // 3 for f in flips]
        assert len(set(visited)) == len(visited)


@settings(max_examples=30, deadline=None)
@given(
    name=st.sampled_from(["face", "la", "double_hex"]),
    area=st.sampled_from([0.5, 0.05]),
    seed=st.integers(0, 2**31 - 1),
    size=st.integers(1, 60),
)
def test_positions_pair_links_as_the_walks_do(name, area, seed, size) -> None:
    # cycle positions: each cycle numbered 0..L-1 along its cover edges; and the
    # outside pairing of a random group's links on one cycle, read off them, is the
    # one ``ring_outside_pairs`` walks
    tri, tw, cover = _cached(name, area)
    is_cov, cyc = cover.is_cov, cover.cycle
    m = len(tri)
    pos, plen = np.empty(m, np.int64), np.empty(m, np.int64)
    J.cycle_positions_into(tw, is_cov, pos, plen)
    on = cyc >= 0
    assert ((pos >= 0) == on).all() and ((plen > 0) == on).all()
    for c in np.unique(cyc[on]).tolist():
        members = np.flatnonzero(cyc == c)
        assert sorted(pos[members].tolist()) == list(range(len(members)))
        assert (plen[members] == len(members)).all()
    h = np.flatnonzero(is_cov)
    d = (pos[tw[h] // 3] - pos[h // 3]) % plen[h // 3]
    assert ((d == 1) | (d == plen[h // 3] - 1)).all()  # neighbours on the cycle, either way
    # a random group: a breadth-first blob of ``size`` triangles
    rng = np.random.default_rng(seed)
    start = int(rng.choice(np.flatnonzero(on)))
    group, seen = blob(tw, rng, start, size)
    links = [3 * x + k for x in group for k in range(3)
             if is_cov[3 * x + k] and tw[3 * x + k] >= 0 and tw[3 * x + k] // 3 not in seen]
    by_cycle: dict = {}
    for l in links:
        by_cycle.setdefault(int(cyc[l // 3]), []).append(l)
    for hs in by_cycle.values():
        hs = np.array(hs, np.int64)
        walked, _ = J.ring_outside_pairs(tw, is_cov, hs, 10**9)
        assert J.pairs_by_position(tw, pos, plen, hs).tolist() == walked.tolist()
