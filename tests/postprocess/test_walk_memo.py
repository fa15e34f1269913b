"""The cover swap tests' walk memo (``_join_kernels.ring_outside_pairs_memo``).

Each link's outside walk is read from a memo of the walks made before on the same
cover, kept as it is walked; the lock-step budget counts the steps as the plain walk
does. So on any cover (real ones, and ``is_cov`` arrays with bits flipped, where walks
run off the cover) and any sequence of link sets and budgets, every answer must be the
plain walk's (``ring_outside_pairs``), whatever the memo's size: rows that fill up,
rows moved to the top as they outgrow their room, a memo too small to keep a walk.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.postprocess import _join_kernels as J
from tests.helpers import blob, bundled_cover, bundled_domain



def _link_sets(tw, is_cov, cyc, rng, n_groups: int, size: int) -> list:
    """Link sets as the swap tests make them: a breadth-first blob's border cover
    half-edges, grouped by the cycle outside (sets of three or more are walked)."""
    m = len(cyc)
    on = np.flatnonzero(cyc >= 0)
    sets = []
    for _ in range(n_groups):
        start = int(rng.choice(on)) if len(on) else int(rng.integers(m))
        group, seen = blob(tw, rng, start, size)
        links = [3 * x + k for x in group for k in range(3)
                 if is_cov[3 * x + k] and tw[3 * x + k] >= 0 and tw[3 * x + k] // 3 not in seen]
        by_cycle: dict = {}
        for h in links:
            by_cycle.setdefault(int(cyc[tw[h] // 3]), []).append(h)
        sets += [np.array(rng.permutation(hs), np.int64) for hs in by_cycle.values() if len(hs) >= 3]
        if len(links) >= 3:  # (also all of them at once: links of several cycles)
            sets.append(np.array(links, np.int64))
    # and cover half-edges anywhere on the longest cycle (long walks between them,
    # in both directions: rows outgrow their room and move)
    if len(on):
        big = np.flatnonzero(cyc == np.bincount(cyc[on]).argmax())
        for k in (3, 5, 8):
            x = rng.choice(big, size=k, replace=False)
            sets.append(np.array([3 * t + np.flatnonzero(is_cov[3 * t:3 * t + 3])[0] if is_cov[3 * t:3 * t + 3].any()
                                  else 3 * t for t in x.tolist()], np.int64))
    return sets


@settings(max_examples=40, deadline=None)
@given(
    name=st.sampled_from(["face", "la", "double_hex"]),
    area=st.sampled_from([0.5, 0.05]),
    seed=st.integers(0, 2**31 - 1),
    size=st.integers(2, 40),
    rows=st.sampled_from([2, 4, 64]),
    steps=st.sampled_from([1, 7, 300, 700, 3000, 1 << 16]),
    flip=st.sampled_from([0.0, 0.0, 0.01, 0.2]),
)
def test_memo_walks_answer_as_the_plain_walks(name, area, seed, size, rows, steps, flip) -> None:
    _check(name, area, seed, size, rows, steps, flip)


@pytest.mark.parametrize("steps", [3000, 1 << 16])
@pytest.mark.parametrize("seed", range(6))
def test_memo_keeps_long_walks_as_walked(seed, steps) -> None:
    # (long walks on the 64 k mesh's big cycle: rows fill, grow and move every time)
    _check("face", 0.5, seed, 20, 64, steps, 0.0)


def _check(name, area, seed, size, rows, steps, flip) -> None:
    tri, tw, cover = bundled_cover(name, area)
    rng = np.random.default_rng(seed)
    is_cov = cover.is_cov.copy()
    if flip:  # (not a cover any more: walks end off it, or loop without meeting a link)
        is_cov ^= rng.random(len(is_cov)) < flip
    sets = _link_sets(tw, is_cov, cover.cycle, rng, 4, size)
    if not sets:
        return
    memo = J.new_walk_memo(rows, steps)
    # each set asked several times in a random order, with budgets that cut the walks
    # off at any point, so later calls read, extend and outgrow what earlier ones kept
    for i in rng.integers(len(sets), size=12).tolist():
        links = sets[i]
        if (tw[links] < 0).any():
            continue  # (a link's walk starts outside: not a border cover edge after the flips)
        budget = int(rng.choice([1, 2, 3, 5, 17, 100, 1000, 10**4, 10**6]))
        want_pair, want_deduced = J.ring_outside_pairs(tw, is_cov, links, budget)
        got_pair, got_deduced = J.ring_outside_pairs_memo(tw, is_cov, links, budget, *memo)
        assert got_pair.tolist() == want_pair.tolist() and got_deduced == want_deduced
        assert memo.state[0] <= steps and 2 * memo.state[1] <= rows
        # what the memo keeps of each walk is its first steps, as walked
        for r in np.flatnonzero(memo.table[:, 0] >= 0).tolist():
            h, off, n, cap = memo.table[r].tolist()
            assert 0 <= n <= cap and off + cap <= steps
            cur = h
            for k in range(n):
                f = J.cover_exit(tw, is_cov, cur)
                assert memo.steps[off + k] == (tw[f] if f >= 0 else -1)
                if f < 0:
                    assert k == n - 1  # (a walk ends there)
                    break
                cur = f


def test_memo_cleared_forgets_every_walk() -> None:
    tri, tw, cover = bundled_cover("face", 0.5)
    rng = np.random.default_rng(1)
    sets = _link_sets(tw, cover.is_cov, cover.cycle, rng, 8, 30)
    memo = J.new_walk_memo()
    for links in sets:
        J.ring_outside_pairs_memo(tw, cover.is_cov, links, 10**6, *memo)
    assert memo.state[1] > 0 and memo.state[0] > 0
    J.clear_walk_memo(memo)
    assert memo.state.tolist() == [0, 0] and (memo.table[:, 0] < 0).all()
    # a changed cover after clearing: the plain walks' answers again
    is_cov = cover.is_cov ^ (rng.random(len(cover.is_cov)) < 0.05)
    for links in sets:
        assert (J.ring_outside_pairs_memo(tw, is_cov, links, 10**6, *memo)[0].tolist()
                == J.ring_outside_pairs(tw, is_cov, links, 10**6)[0].tolist())


@pytest.mark.parametrize("memo_steps", [0, 300])
@pytest.mark.parametrize("name", ["la", "square_circle_hole"])
def test_construction_with_walk_memos_is_the_plain_walks(name: str, memo_steps: int, monkeypatch) -> None:
    # the cover swaps' walks (``ALT_POSITIONS_BELOW`` = 0, as on big meshes) through
    # the two threads' memos, kept over the tasks and cleared at each swap taken, give
    # the same mesh and report as plain walks (memo_steps 0) and as a memo that fills
    # up (300 steps: walks no longer kept)
    import hammesh.postprocess.cycle_cover as cycle_cover_module
    from hammesh.postprocess import sparse

    monkeypatch.setattr(cycle_cover_module, "RECOLOUR_BELOW", 0)  # (else no swaps are left here)
    monkeypatch.setattr(sparse, "ALT_POSITIONS_BELOW", 0)
    dom = bundled_domain(name)
    area = 0.0005 * float(np.ptp(dom.vertices[:, 0]) * np.ptp(dom.vertices[:, 1]))
    m = hammesh.quality_mesh(dom, min_angle=25 if name == "la" else 30, max_area=area, isolate=False)
    memos = []
    real = J.new_walk_memo

    def kept(*a, **k):
        memos.append(real(*a, **k))
        return memos[-1]

    monkeypatch.setattr(J, "new_walk_memo", kept)
    with_memo = hammesh.hamiltonian(m)
    assert len(memos) == 2 and all(len(x.steps) == J.WALK_MEMO_STEPS for x in memos)
    assert with_memo.report["alternating_merges"] >= 2  # (memos cleared between tasks)
    monkeypatch.setattr(J, "WALK_MEMO_STEPS", memo_steps)
    other = hammesh.hamiltonian(m)
    assert all(len(x.steps) == memo_steps for x in memos[2:])
    times = ("seconds", "step_seconds", "step_cpu_seconds")
    assert {k: v for k, v in other.report.items() if k not in times} == {
        k: v for k, v in with_memo.report.items() if k not in times}
    for f in ("points", "triangles", "components", "position", "parent", "kind"):
        np.testing.assert_array_equal(getattr(other, f), getattr(with_memo, f), err_msg=f)
