"""The plan's crossing half-edges (``_sparse_kernels.crossing_half_edges``).

``plan_merges`` needs every edge between two different nodes (cover cycles,
uncovered triangles), one half-edge each. They are read off the join candidates (and
the edges between two uncovered triangles) instead of a pass over all 3 m half-edges:
on any labelling of the triangles that must be exactly the edges the pass finds, and
the plan must not depend on their order or on which half of each is given.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.postprocess import _sparse_kernels as sk
from tests.helpers import bundled_cover



def _crossing_by_a_pass(tw, cyc) -> list:
    """The lower half-edge of every edge whose two triangles are different nodes (the reference)."""
    h = np.flatnonzero(tw > np.arange(len(tw)))
    ct, cu = cyc[h // 3], cyc[tw[h] // 3]
    return sorted(h[(ct < 0) | (cu < 0) | (ct != cu)].tolist())


@settings(max_examples=40, deadline=None)
@given(
    name=st.sampled_from(["face", "la", "double_hex", "A"]),
    seed=st.integers(0, 2**31 - 1),
    off=st.sampled_from([0.0, 0.001, 0.05, 0.5, 1.0]),
    relabel=st.booleans(),
)
def test_crossing_half_edges_are_the_passs(name, seed, off, relabel) -> None:
    tri, tw, cover = bundled_cover(name, 0.5)
    rng = np.random.default_rng(seed)
    cyc = cover.cycle.copy()
    if relabel:  # (any labelling: few cycles, so neighbours often share one)
        cyc = rng.integers(0, 4, len(cyc)).astype(np.int64)
    cyc[rng.random(len(cyc)) < off] = -1  # uncovered triangles, up to all of them
    unc = np.flatnonzero(cyc < 0)
    got = sk.crossing_half_edges(tw, cyc, unc, sk.join_candidates(tw, cyc))
    lower = np.minimum(got, tw[got]).tolist()
    assert len(set(lower)) == len(lower)  # each edge once
    assert sorted(lower) == _crossing_by_a_pass(tw, cyc)


@pytest.mark.parametrize("name", ["face", "la", "A"])
def test_plan_does_not_depend_on_the_crossing_order(name) -> None:
    # the plan from the crossing half-edges ascending (the pass's order) and shuffled:
    # the same statuses, slots, joins and counts (the bridges' stages take the edges
    # Kruskal left apart in ascending order either way)
    tri, tw, cover = bundled_cover(name, 0.5)
    rng = np.random.default_rng(7)
    bridges = 0
    for off in (0.0, 0.02, 0.3):
        cyc = cover.cycle.copy()
        cyc[rng.random(len(cyc)) < off] = -1
        n_cyc = int(cyc.max()) + 1
        unc = np.flatnonzero(cyc < 0)
        cand = sk.join_candidates(tw, cyc)
        order = rng.permutation(len(cand))[: len(cand) // 3]  # (a third: Kruskal leaves nodes apart)
        ckind = rng.integers(1, 3, len(cand)).astype(np.int8)
        cross = np.sort(sk.crossing_half_edges(tw, cyc, unc, cand))
        is_con = np.zeros(len(tw), np.bool_)
        is_con[rng.random(len(tw)) < 0.05] = True
        plans = []
        flipped = np.where(rng.random(len(cross)) < 0.5, cross, tw[cross])  # (either half of each)
        for c in (cross, rng.permutation(cross), rng.permutation(flipped)):
            m = len(tri)
            arrays = (np.empty(m, np.int8), np.empty(3 * m, np.int8), np.empty(m, np.int64), np.empty(m, np.int64))
            uf, pu = np.empty(n_cyc + len(unc), np.int64), np.empty(n_cyc + len(unc), np.int64)
            sk._plan_fill_range(cyc, *arrays, 0, m)
            counts, bad = sk._plan_merges_into(tri, tw, is_con, cyc, n_cyc, unc, cand[order], ckind[order],
                                               np.zeros(m, np.bool_), True, *arrays, uf, pu, c.copy())
            plans.append([a.tolist() for a in (*arrays, counts, bad)])
        assert plans[0] == plans[1] == plans[2]
        bridges += plans[0][4][2]
    assert bridges > 0


def _kruskal_by_python(tw, cyc, cand, ckind, no_absorb) -> tuple[list, list, list]:
    """Stage A of the plan in plain Python (the reference): each judged join taken in
    order where its triangles are in no join yet and it joins two nodes."""
    parent: dict = {}

    def find(x):
        while parent.get(x, x) != x:
            x = parent[x]
        return x

    swap_he = [-1] * len(cyc)
    join = [-1] * len(cyc)
    status = [1 if c < 0 else 0 for c in cyc.tolist()]
    for i, h in enumerate(cand.tolist()):
        g = int(tw[h])
        t, u = h // 3, g // 3
        if swap_he[t] >= 0 or swap_he[u] >= 0 or (cyc[u] < 0 and no_absorb[u]):
            continue
        # (nodes: a cycle id, or the uncovered triangle itself)
        rt, ru = find(("c", int(cyc[t]))), find(("c", int(cyc[u])) if cyc[u] >= 0 else ("u", u))
        if rt == ru:
            continue
        parent[rt] = ru
        swap_he[t], swap_he[u], join[t], join[u] = h, g, i, i
        status[t] = status[u] = sk.SWAP if ckind[i] == 1 else sk.EDGE
    return status, swap_he, join


@settings(max_examples=30, deadline=None)
@given(
    name=st.sampled_from(["face", "la", "A"]),
    seed=st.integers(0, 2**31 - 1),
    off=st.sampled_from([0.0, 0.02, 0.3]),
    share=st.sampled_from([1.0, 0.3]),
)
def test_plan_merges_threaded_is_the_serial_kernels(name, seed, off, share) -> None:
    # plan_merges on a big mesh finds the pieces on another core beside Kruskal's
    # joins (whose candidates' rows it asks for ahead): the same plan as the serial
    # kernel, and Kruskal's joins those of a plain Python pass
    tri, tw, cover = bundled_cover(name, 0.5)
    rng = np.random.default_rng(seed)
    cyc = cover.cycle.copy()
    cyc[rng.random(len(cyc)) < off] = -1
    n_cyc = int(cyc.max()) + 1
    m = len(tri)
    unc = np.flatnonzero(cyc < 0)
    joinable = sk.join_candidates(tw, cyc)
    order = rng.permutation(len(joinable))[: int(len(joinable) * share)]
    cand = joinable[order]
    ckind = rng.integers(1, 3, len(cand)).astype(np.int8)
    is_con = rng.random(len(tw)) < 0.05
    no_absorb = rng.random(m) < 0.3
    arrays = (np.empty(m, np.int8), np.empty(3 * m, np.int8), np.empty(m, np.int64), np.empty(m, np.int64))
    sk._plan_fill_range(cyc, *arrays, 0, m)
    uf, pu = np.empty(n_cyc + len(unc), np.int64), np.empty(n_cyc + len(unc), np.int64)
    cross = sk.crossing_half_edges(tw, cyc, unc, joinable)
    serial = sk._plan_merges_into(tri, tw, is_con, cyc, n_cyc, unc, cand, ckind, no_absorb, True, *arrays, uf, pu,
                                  cross)
    with pytest.MonkeyPatch.context() as mp:  # (the threaded path on a small mesh, on any machine)
        mp.setattr(sk, "PLAN_SIDE_MIN_ROWS", 0)
        mp.setattr(hammesh.threads, "cores", lambda: 2)
        plan = sk.plan_merges(tri, tw, is_con, cyc, n_cyc, cand, ckind, no_absorb, True, joinable)
    for a, b in zip((*arrays, *serial), (plan.status, plan.slot, plan.swap_he, plan.join, plan.counts, plan.bad)):
        assert a.tolist() == b.tolist()
    # Kruskal's joins alone against the reference (the bridges' stages only add splits)
    st_a = (np.empty(m, np.int8), np.empty(3 * m, np.int8), np.empty(m, np.int64), np.empty(m, np.int64))
    sk._plan_fill_range(cyc, *st_a, 0, m)
    counts = sk._kruskal_joins_into(tw, cyc, n_cyc, unc, cand, ckind, no_absorb, st_a[0], st_a[2], st_a[3], uf)
    status, swap_he, join = _kruskal_by_python(tw, cyc, cand, ckind, no_absorb)
    assert st_a[0].tolist() == status and st_a[2].tolist() == swap_he and st_a[3].tolist() == join
    absorbed = [s for t, s in enumerate(status) if s == sk.SWAP and cyc[t] < 0]
    assert counts[0] == len(absorbed) and counts[2] == 0
