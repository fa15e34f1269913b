"""``hammesh.pages.fresh``: arrays faulted in ahead, in small pages (issue 11, first call)."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from hammesh import pages, threads
from hammesh.pages import fresh


@pytest.mark.parametrize("shape, dtype, fill", [((1000, 3), np.int64, 0), (5_000_000, np.int32, -2),
                                                ((7,), np.int8, None), (0, np.float64, 1.5)])
def test_fresh_has_the_shape_dtype_and_fill(shape, dtype, fill) -> None:
    a = fresh(shape, dtype, fill)
    assert a.shape == np.empty(shape).shape and a.dtype == dtype and a.flags.c_contiguous
    if fill is not None:
        assert (a == fill).all()


def _vma(addr: int) -> dict[str, str]:
    """The /proc/self/smaps entry of the mapping holding ``addr``."""
    entry: dict[str, str] = {}
    inside = False
    with open("/proc/self/smaps") as f:
        for line in f:
            head = line.split()[0]
            if "-" in head and not head.endswith(":"):
                lo, hi = (int(x, 16) for x in head.split("-"))
                if inside:
                    break
                inside = lo <= addr < hi
                continue
            if inside:
                key, _, value = line.partition(":")
                entry[key] = value.strip()
    return entry


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="madvise and /proc/self/smaps are Linux's")
def test_fresh_pages_are_small_and_resident_before_any_write() -> None:
    """64 MB without a fill: resident already (populated by the kernel), advised
    ``nohugepage`` (VmFlags ``nh``), no huge page in the range."""
    a = fresh(8 << 20, np.int64)
    vma = _vma(a.ctypes.data + a.nbytes // 2)
    assert "nh" in vma["VmFlags"].split()
    assert int(vma["AnonHugePages"].split()[0]) == 0
    assert int(vma["Rss"].split()[0]) * 1024 >= 0.99 * a.nbytes


@pytest.fixture
def no_reserve():
    pages.release()
    yield
    pages.release()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="mremap and /proc/self/smaps are Linux's")
def test_fresh_takes_its_pages_from_the_reserve(no_reserve) -> None:
    """Arrays taken from the reserve are its faulted pages moved out (resident, small
    pages, a mapping of their own), filled as asked; small arrays never take from it."""
    assert pages.reserve(32 << 20) == 32 << 20
    small = fresh(100, np.int64, 3)
    assert pages.reserved() == 32 << 20 and (small == 3).all()
    a = fresh((1 << 20, 3), np.int32, -2)  # 12 MiB
    b = fresh(1 << 20, np.float64)  # 8 MiB, unspecified contents
    assert pages.reserved() == (32 - 20) << 20
    assert a.shape == (1 << 20, 3) and a.dtype == np.int32 and (a == -2).all()
    assert b.shape == (1 << 20,) and b.dtype == np.float64 and a.flags.c_contiguous and b.flags.writeable
    vma = _vma(b.ctypes.data + b.nbytes // 2)
    assert int(vma["Rss"].split()[0]) * 1024 >= b.nbytes  # there before any write
    assert int(vma["AnonHugePages"].split()[0]) == 0
    b[:] = 1.5
    c = fresh(16 << 20, np.uint8)  # more than is left: an ordinary fresh array
    assert c.nbytes == 16 << 20 and pages.reserved() == 12 << 20
    pages.release()
    assert pages.reserved() == 0
    assert (a == -2).all() and (b == 1.5).all()  # arrays taken stay valid after the release
    assert fresh(4 << 20, np.int8, 1).sum() == 4 << 20


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="mremap is Linux's")
def test_an_array_from_the_reserve_frees_its_memory_when_it_dies(no_reserve) -> None:
    import gc

    pages.reserve(16 << 20)
    a = fresh(8 << 20, np.uint8, 7)
    addr = a.ctypes.data
    assert _vma(addr)
    del a
    gc.collect()
    threads.wait_later()  # (unmapped on the background thread: ``threads.later``)
    assert not _vma(addr)  # unmapped (nothing else was mapped there meanwhile)


def test_an_unused_reserve_is_dropped_after_a_while(no_reserve, monkeypatch) -> None:
    import time

    monkeypatch.setattr(pages, "RESERVE_SECONDS", 0.05)
    if not pages.reserve(4 << 20):
        pytest.skip("no mremap here")
    deadline = time.monotonic() + 10
    while pages.reserved() and time.monotonic() < deadline:
        time.sleep(0.01)
    assert pages.reserved() == 0


def test_hamiltonian_drops_the_reserve(no_reserve) -> None:
    import hammesh
    from tests.helpers import plate

    m = plate(0, 1, max_area=0.01)
    pages.reserve(8 << 20)
    hammesh.hamiltonian(m, mode="incircle")
    assert pages.reserved() == 0


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="mremap is Linux's")
def test_trim_gives_back_what_a_construction_will_not_take(no_reserve) -> None:
    """``pages.trim``: the reserve keeps only what a construction will take; arrays taken
    before stay valid, and what is trimmed is unmapped (not resident any more)."""
    assert pages.reserve(32 << 20) == 32 << 20
    a = fresh(4 << 20, np.uint8, 5)
    r = pages._reserve
    tail = r.addr + r.size - (1 << 20)  # inside the reserve's untaken rest
    assert _vma(tail)
    assert pages.trim(8 << 20) == 8 << 20
    assert pages.reserved() == 8 << 20 and (a == 5).all()
    assert not _vma(tail) or _vma(tail).get("Rss", "0 kB").split()[0] == "0"
    b = fresh(8 << 20, np.uint8, 1)  # exactly what is left: taken from the reserve
    assert pages.reserved() == 0 and b.sum() == 8 << 20
    assert pages.trim(1 << 20) == 0  # (nothing left: nothing to do)


def test_sparse_mode_keeps_only_its_share_of_the_reserve(no_reserve, monkeypatch) -> None:
    """``hamiltonian(mode="sparse")`` trims the reserve to its share
    (``postprocess.RESERVE_TAKEN``) before it validates: the rest is not held to its end."""
    import hammesh
    from hammesh import postprocess
    from tests.helpers import plate

    m = plate(0, 1, max_area=0.01)
    if not pages.reserve(16 << 20):
        pytest.skip("no mremap here")
    seen = []
    real = postprocess.prepare_mesh

    def spy(*args, **kw):
        seen.append(pages.reserved())
        return real(*args, **kw)

    monkeypatch.setattr(postprocess, "prepare_mesh", spy)
    hammesh.hamiltonian(m, mode="sparse")
    share = postprocess.RESERVE_TAKEN["sparse"] * m.n_triangles
    assert seen and seen[0] <= max(share + pages._PAGE, 0) < 16 << 20
    assert pages.reserved() == 0


def test_later_runs_in_order_off_the_caller_or_inline_on_one_core() -> None:
    # ``threads.later`` (where the reserve's arrays are unmapped): one background thread,
    # in submission order, errors dropped; inline where the process may use one thread
    import threading

    me = threading.get_ident()
    seen: list = []
    for i in range(50):
        threads.later(lambda i=i: seen.append((i, threading.get_ident())))
    threads.wait_later()
    assert [i for i, _ in seen] == list(range(50))
    if threads.cores() > 1:
        assert len({t for _, t in seen}) == 1 and seen[0][1] != me
    threads.later(lambda: 1 / 0)
    threads.later(lambda: seen.append(("after an error", threading.get_ident())))
    threads.wait_later()
    assert seen[-1][0] == "after an error"
    old = threads.limit(1)
    try:
        threads.later(lambda: seen.append(("inline", threading.get_ident())))
        assert seen[-1] == ("inline", me)
    finally:
        threads.limit(old)


def test_later_held_keeps_the_background_work_for_the_blocks_end() -> None:
    # session 21: ``threads.later_held`` (the certificate's row threads want both cores):
    # work handed to ``later`` inside the block waits, in order, and runs after it;
    # ``wait_later`` inside a block still returns (the queue runs while it waits)
    import time

    threads.wait_later()
    seen: list = []
    if threads.cores() < 2:  # (one thread: nothing in the background to hold)
        with threads.later_held():
            threads.later(seen.append, 1)
        assert seen == [1]
        return
    with threads.later_held():
        threads.later(seen.append, 1)
        with threads.later_held():  # (nested: the outer block still holds)
            threads.later(seen.append, 2)
        time.sleep(0.05)
        assert seen == []
        threads.wait_later()
        assert seen == [1, 2]
        threads.later(seen.append, 3)
        time.sleep(0.05)
        assert seen == [1, 2]
    threads.wait_later()
    assert seen == [1, 2, 3]


def test_later_held_waits_at_most_later_hold_max(monkeypatch) -> None:
    # blocks of several threads that overlap without end must not keep the background
    # work (a process's dead pages) forever: it runs ``LATER_HOLD_MAX`` after the first opened
    import time

    if threads.cores() < 2:
        pytest.skip("one thread: nothing in the background to hold")
    threads.wait_later()
    monkeypatch.setattr(threads, "LATER_HOLD_MAX", 0.2)
    seen: list = []
    with threads.later_held():
        t0 = time.monotonic()
        threads.later(lambda: seen.append(time.monotonic() - t0))
        while not seen and time.monotonic() - t0 < 10:
            time.sleep(0.01)
        assert seen and 0.15 <= seen[0] < 5.0


@pytest.mark.skipif(not hasattr(__import__("os"), "fork"), reason="fork is POSIX's")
def test_later_in_a_forked_child_runs_on_its_own_thread() -> None:
    # the parent's background thread is not in a forked child: the child starts its own
    import multiprocessing as mp

    threads.later(lambda: None)  # (the parent's thread exists)
    threads.wait_later()
    ctx = mp.get_context("fork")
    out = ctx.Queue()

    def child(q) -> None:
        seen = []
        threads.later(seen.append, 1)
        threads.wait_later()
        q.put(seen)

    p = ctx.Process(target=child, args=(out,))
    p.start()
    got = out.get(timeout=30)
    p.join(30)
    assert p.exitcode == 0 and got == [1]
