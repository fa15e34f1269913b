"""Work arrays kept between two-halves encodings (:mod:`hammesh.strips.scratch`)."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from hammesh.halfedge import mesh_arrays
from hammesh.strips import halves, scratch
from hammesh.strips.gl import RESTART_INDEX, decode_gl_strip

from .conftest import delaunay_mesh, oriented_set


@pytest.fixture(autouse=True)
def _empty_pool():
    scratch.release()
    yield
    scratch.release()


def _halves(m, fast=True):
    pts, tri = mesh_arrays(m.points, m.triangles, dims=(2, 3))
    finish = None
    if not fast:
        from hammesh.strips.encode import half_encoder

        finish = half_encoder(RESTART_INDEX)
    return halves.encode_in_halves(pts, tri, RESTART_INDEX, True, 1, finish)


def test_take_reuses_a_large_enough_buffer_and_replaces_a_small_one():
    s = scratch.borrow()
    a = s.take("x", (10, 3), np.int32)
    s.give_back()
    assert scratch.kept_bytes() == a.nbytes
    s = scratch.borrow()
    assert scratch.kept_bytes() == 0  # taken out for this call
    b = s.take("x", 7, np.int64)  # 56 bytes fit in the kept 120
    assert b.shape == (7,) and b.dtype == np.int64 and np.shares_memory(a, b)
    s.give_back()
    s = scratch.borrow()
    c = s.take("x", 100, np.int64)  # too large: a new buffer, kept instead
    assert not np.shares_memory(a, c)
    s.give_back()
    assert scratch.kept_bytes() == c.nbytes
    scratch.release()
    assert scratch.kept_bytes() == 0


@pytest.mark.parametrize("fast", [True, False])
def test_a_second_call_reuses_the_arrays_and_leaves_the_first_result_alone(fast):
    a_mesh, b_mesh = delaunay_mesh(1, 3000, False), delaunay_mesh(2, 2500, True)
    a = _halves(a_mesh, fast)
    kept = scratch.kept_bytes()
    assert kept > 0
    a_copy = a.indices.copy()
    b = _halves(b_mesh, fast)  # writes into the kept arrays
    assert np.array_equal(a.indices, a_copy)  # the first buffer is no kept array
    assert oriented_set(decode_gl_strip(b.indices, b.restart_index)) == oriented_set(b_mesh.triangles)
    again = _halves(a_mesh, fast)  # the same buffer from reused arrays
    assert np.array_equal(again.indices, a.indices)


def test_calls_at_once_on_two_threads_never_share_arrays():
    meshes = [delaunay_mesh(s, 2000, s % 2 == 0) for s in range(6)]
    out: dict[int, object] = {}

    def work(i):
        out[i] = _halves(meshes[i])

    threads = [threading.Thread(target=work, args=(i,)) for i in range(len(meshes))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for i, m in enumerate(meshes):
        s = out[i]
        assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(m.triangles)


def _resident_pages(a: np.ndarray) -> np.ndarray:
    """``mincore`` of the whole pages inside ``a``: True where the page is in memory."""
    import ctypes
    import mmap

    libc = ctypes.CDLL(None, use_errno=True)
    page = mmap.PAGESIZE
    lo = -(-a.ctypes.data // page) * page
    n = (a.ctypes.data + a.nbytes - lo) // page
    vec = (ctypes.c_ubyte * n)()
    libc.mincore.argtypes = (ctypes.c_void_p, ctypes.c_size_t, ctypes.c_void_p)
    assert libc.mincore(ctypes.c_void_p(lo), ctypes.c_size_t(n * page), vec) == 0
    return np.frombuffer(vec, np.uint8) & 1 == 1


@pytest.mark.skipif(not __import__("sys").platform.startswith("linux"), reason="madvise/mincore are Linux's")
def test_new_buffers_fault_in_the_written_part_only():
    """A new work array has the part the call writes in memory already, and nothing beyond it
    (small pages: a huge page would bring 2 MiB at once)."""
    from hammesh import pages

    probe = np.empty(1 << 20, np.uint8)
    if not pages.advise(probe, pages.MADV_POPULATE_WRITE):
        pytest.skip("no MADV_POPULATE_WRITE here")
    # above glibc's largest dynamic mmap threshold (32 MiB): new pages, not the heap's
    buf = scratch.new_buffer(64 << 20, written=0.25)
    assert buf.dtype == np.uint8 and buf.nbytes == 64 << 20
    res = _resident_pages(buf)
    q = len(res) // 4
    assert res[: q - 1].all()  # the written quarter: faulted in by one call
    assert not res[q + 1 :].any()  # the rest: not touched, not a huge page
    buf[-1] = 7  # still ordinary memory
    assert buf[-1] == 7
