"""Cover swaps along alternating cycles in place of joins below the rule (issue 13, item 1).

The local decision (``_join_kernels.swap_merge_outcome``: links, outside walks, inside
pairs) is checked against labelling the whole swapped cover again
(``_cover_kernels.cycle_ids``), and the construction against itself with the swaps off.
"""

from __future__ import annotations

import importlib
from pathlib import Path

import numpy as np
import pytest

import hammesh
import hammesh.postprocess.cycle_cover as cycle_cover_module
from hammesh.halfedge import half_edge_twins
from hammesh.postprocess import _cover_kernels as ck
from hammesh.postprocess import _join_kernels as J
from hammesh.postprocess import sparse
from hammesh.postprocess.cycle_cover import cycle_cover
from tests.helpers import bundled_domain, hull_area
from tests.postprocess.test_sparse import assert_sparse_certificate


def _ids_before_and_after(tw, is_cov, flips, m):
    """Every cycle labelled again before and after the swap along ``flips``: the two
    labellings, their counts and the (old, new) id pairs of the triangles outside the
    swapped ones (whose cycles may trade triangles among them)."""
    old, n_old = ck.cycle_ids(tw, is_cov, m)
    new_cov = is_cov.copy()
    for h in flips:
        new_cov[h] = not new_cov[h]
        new_cov[tw[h]] = new_cov[h]
    new, n_new = ck.cycle_ids(tw, new_cov, m)
    cov = old >= 0
    cov[[h // 3 for h in flips] + [tw[h] // 3 for h in flips]] = False
    return old, n_old, new, n_new, set(zip(old[cov].tolist(), new[cov].tolist()))


def _only_merges_by_relabelling(tw, is_cov, flips, a, b, m) -> bool:
    """Swap, label every cycle again: outside the swapped triangles, is the new
    partition the old one with a and b joined?"""
    old, n_old, new, n_new, pairs = _ids_before_and_after(tw, is_cov, flips, m)
    if not np.array_equal(old < 0, new < 0) or n_new != n_old - 1:
        return False  # (one cycle fewer: none new inside the swapped triangles, none lost there)
    old_to_new: dict = {}
    new_to_old: dict = {}
    for o, n in pairs:
        old_to_new.setdefault(o, set()).add(n)
        new_to_old.setdefault(n, set()).add(o)
    if any(len(v) > 1 for v in old_to_new.values()):
        return False  # a split
    merged = [v for v in new_to_old.values() if len(v) > 1]
    return merged == [{a, b}]


def _no_split_by_relabelling(tw, is_cov, flips, m) -> bool:
    """Swap, label every cycle again: outside the swapped triangles no cycle split, no
    cycle lies wholly inside them before or after, and some merged."""
    _, n_old, _, n_new, pairs = _ids_before_and_after(tw, is_cov, flips, m)
    olds = {o for o, _ in pairs}
    news = {n for _, n in pairs}
    return len(olds) == n_old and len(news) == n_new and len(pairs) == len(olds) and n_new < n_old


@pytest.mark.parametrize("name", ["face", "la"])
def test_local_swap_decision_equals_relabelling_the_cover(name: str) -> None:
    dom = bundled_domain(name)
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=hull_area(dom) / 1500)
    pts, tri = np.asarray(m.points, np.float64), np.asarray(m.triangles, np.int64)
    tw, _ = half_edge_twins(tri, len(pts))
    cover = cycle_cover(tri, tw)
    is_cov, cyc = cover.is_cov, cover.cycle
    root = np.arange(cover.n_cycles, dtype=np.int64)
    blocked = cyc < 0
    between = [h for h in range(3 * len(tri)) if tw[h] > h and not is_cov[h] and cyc[h // 3] >= 0
               and cyc[tw[h] // 3] >= 0 and cyc[h // 3] != cyc[tw[h] // 3]]
    assert len(between) >= 10
    buf, starts = np.empty(24 * 42, np.int64), np.empty(25, np.int64)
    none = np.empty(0, np.int64)
    # the outside pairings read off cycle positions (``sparse`` below
    # ``ALT_POSITIONS_BELOW`` triangles) instead of walked: the same answers
    pos, plen = np.empty(len(tri), np.int64), np.empty(len(tri), np.int64)
    J.cycle_positions_into(tw, is_cov, pos, plen)
    plain = J.new_walk_memo(2, 0)  # (no memo: plain walks)
    memo = J.new_walk_memo()  # the walks kept over all the checks on this cover: the same answers
    yes = no = wider = 0
    for h0 in between[:40]:
        t, u = h0 // 3, tw[h0] // 3
        n = J.alternating_cycles_into(tw, is_cov, blocked, h0, 20, 20_000, buf, starts, 24)
        for c in range(n):
            fl = buf[starts[c]:starts[c + 1]]
            # an alternating cycle through h0: non-cover and cover edges alternate, closed
            assert fl[0] == h0 and len(fl) % 2 == 0
            assert [bool(is_cov[h]) for h in fl] == [False, True] * (len(fl) // 2)
            for x, y in zip(fl, np.roll(fl, -1)):
                assert {x // 3, tw[x] // 3} & {y // 3, tw[y] // 3}
            group = np.unique(np.concatenate([fl // 3, tw[fl] // 3]))
            local = J.swap_only_merges(tw, is_cov, cyc, root, fl, group, cyc[t], cyc[u], 10**9, False)
            assert local == _only_merges_by_relabelling(tw, is_cov, fl.tolist(), cyc[t], cyc[u], len(tri))
            yes += local
            no += not local
            wide = J.swap_only_merges(tw, is_cov, cyc, root, fl, group, cyc[t], cyc[u], 10**9, True)
            assert wide == _no_split_by_relabelling(tw, is_cov, fl.tolist(), len(tri))
            assert wide or not local
            wider += wide and not local
            # both answers from one walk, as ``sparse._alternating_merges`` asks them
            both = J.swap_merge_outcome(tw, is_cov, cyc, root, fl, group, cyc[t], cyc[u], 10**9, True, none, none,
                                        *plain)
            assert both == (1 if local else 2 if wide else 0)
            assert J.swap_merge_outcome(tw, is_cov, cyc, root, fl, group, cyc[t], cyc[u], 10**9, False, none,
                                        none, *plain) == int(local)
            assert J.swap_merge_outcome(tw, is_cov, cyc, root, fl, group, cyc[t], cyc[u], 0, True, pos, plen,
                                        *plain) == both
            for budget in (10**9, 40):  # (40: walks cut off by the budget, undecided)
                assert J.swap_merge_outcome(tw, is_cov, cyc, root, fl, group, cyc[t], cyc[u], budget, True, none,
                                            none, *memo) == J.swap_merge_outcome(
                    tw, is_cov, cyc, root, fl, group, cyc[t], cyc[u], budget, True, none, none, *plain)
    assert yes >= 1 and no >= 1 and wider >= 1  # every answer exercised


@pytest.mark.parametrize("name", ["la", "double_hex"])
def test_cover_swaps_take_joins_below_the_rule_away(name: str, monkeypatch) -> None:
    """The same mesh with the swaps off and on: each swap takes one join (a swap, split
    or bridge below the rule) out of the plan and changes nothing else, so fewer rows
    below the rule and no more Steiner points; the certificate's independent re-check
    passes."""
    monkeypatch.syspath_prepend(str(Path(__file__).parents[2] / "benchmarks"))
    monkeypatch.setattr(cycle_cover_module, "RECOLOUR_BELOW", 0)  # (no session-14 re-colouring: it leaves nothing here)
    bench_sparse = importlib.import_module("bench_sparse")
    m = bench_sparse._mesh_at(dict(bench_sparse._domains())[name], 4000)
    on = hammesh.hamiltonian(m)
    monkeypatch.setattr(sparse, "RING_JOIN_PASSES", 0)  # (the ring joins try other joins after them)
    alone = hammesh.hamiltonian(m)
    monkeypatch.setattr(sparse, "ALT_MERGE_TRIES", 0)
    off = hammesh.hamiltonian(m)
    r_on, r_alone, r_off = on.report, alone.report, off.report
    assert r_off["alternating_merges"] == 0 and r_alone["alternating_merges"] >= 1
    assert_sparse_certificate(m, on)
    assert_sparse_certificate(m, alone)
    assert r_alone["merges"] + r_alone["alternating_merges"] == r_off["merges"]
    assert r_alone["uncovered"] == r_off["uncovered"] and r_alone["retries"] == r_off["retries"]
    assert r_alone["steiner_points"] <= r_off["steiner_points"]
    assert r_alone["below_parent_rule"] < r_off["below_parent_rule"]
    # (a swap merging more than two cycles also takes the plan's other steps between
    # them, some of them within the rule)
    assert r_off["joins_below_rule"] - r_alone["alternating_merges"] <= r_alone["joins_below_rule"]
    assert r_alone["joins_below_rule"] < r_off["joins_below_rule"]
    # with the ring joins after them (the default), still fewer than without the swaps
    monkeypatch.setattr(sparse, "RING_JOIN_PASSES", 1)
    both_off = hammesh.hamiltonian(m)
    assert r_on["below_parent_rule"] < both_off.report["below_parent_rule"]
    assert r_on["steiner_points"] <= both_off.report["steiner_points"]


def test_a_second_pass_of_swaps_starts_from_the_first(monkeypatch) -> None:
    """``ALT_MERGE_PASSES = 2``: the second call works on the cover and plan the first
    left (no join swapped twice, the points and rows as the certificate checks them)."""
    monkeypatch.syspath_prepend(str(Path(__file__).parents[2] / "benchmarks"))
    bench_sparse = importlib.import_module("bench_sparse")
    m = bench_sparse._mesh_at(dict(bench_sparse._domains())["double_hex"], 4000)
    monkeypatch.setattr(cycle_cover_module, "RECOLOUR_BELOW", 0)  # (no session-14 re-colouring: it leaves nothing here)
    one = hammesh.hamiltonian(m)
    monkeypatch.setattr(sparse, "ALT_MERGE_PASSES", 2)
    two = hammesh.hamiltonian(m)
    assert_sparse_certificate(m, two)
    assert two.report["alternating_merges"] >= one.report["alternating_merges"] >= 1
    assert two.n_points == m.n_points + two.report["steiner_points"]
