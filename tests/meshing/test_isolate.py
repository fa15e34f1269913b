"""The meshing child process: results through shared memory, nothing left behind.

``hammesh.meshing.isolate.run_isolated`` hands the child's arrays over in an anonymous
memory file; these tests check that the arrays arrive intact and writable, that no
descriptor, mapping or ``/dev/shm`` entry survives any way the child can end (answer,
crash, timeout, error), and that the child dies with its parent (issue 12, item 8).
"""

from __future__ import annotations

import gc
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import hammesh
from hammesh.meshing import isolate
from hammesh.meshing.isolate import ARENA_MIN_BYTES, SHARED_MEMORY, run_isolated

LINUX = sys.platform.startswith("linux")
MEMFD_NAME = "memfd:hammesh-result"


def _arrays(*, alloc=np.empty) -> dict:
    big = alloc((300_000, 3), np.int64)
    big[...] = np.arange(900_000).reshape(-1, 3)
    pts = alloc((100_000, 2), np.float64)
    pts[...] = np.linspace(0.0, 1.0, 200_000).reshape(-1, 2)
    return {
        "big": big,
        "view": big[100:],  # a view into an allocated block
        "pts": pts,
        "copied": np.arange(60_000, dtype=np.float64) * 0.25,  # big, not from alloc
        "small": np.arange(5, dtype=np.int8),
        "empty": np.zeros((0, 3), dtype=np.int64),
        "strided": np.arange(20).reshape(4, 5)[:, ::2],
        "mesh": hammesh.Mesh(points=pts[:3].copy(), triangles=np.array([[0, 1, 2]])),
        "text": "kept",
    }


def _expected() -> dict:
    return _arrays()


def _crash() -> None:
    os.kill(os.getpid(), signal.SIGSEGV)


def _crash_after_alloc(*, alloc) -> None:
    a = alloc((1_000_000,), np.float64)
    a.fill(1.0)
    os.kill(os.getpid(), signal.SIGKILL)


def _hang(*, alloc) -> None:
    a = alloc((1_000_000,), np.float64)
    a.fill(1.0)
    time.sleep(60)


def _hammesh_error(*, alloc) -> None:
    alloc((1_000_000,), np.float64).fill(2.0)
    raise hammesh.InvalidOptionError("bad option from the child")


def _other_error(*, alloc) -> None:
    alloc((1_000_000,), np.float64).fill(2.0)
    raise KeyError("inner")


def _fds() -> set[str]:
    return set(os.listdir("/proc/self/fd")) if LINUX else set()


def _memfd_mappings() -> int:
    if not LINUX:
        return 0
    with open("/proc/self/maps") as f:
        return sum(MEMFD_NAME in line for line in f)


def _dev_shm() -> set[str]:
    return set(os.listdir("/dev/shm")) if os.path.isdir("/dev/shm") else set()


def _wait_for_reapers() -> None:
    """A child that answered is reaped by a daemon thread (not to delay the caller)."""
    for t in threading.enumerate():
        if t.name == "hammesh-reap":
            t.join(30)


def _mapped_file(a: np.ndarray) -> object:
    """What ``a``'s memory finally belongs to (following bases and memoryviews)."""
    obj: object = a
    while True:
        if isinstance(obj, np.ndarray) and obj.base is not None:
            obj = obj.base
        elif isinstance(obj, memoryview):
            obj = obj.obj
        else:
            return obj


def test_result_arrays_arrive_intact_and_writable() -> None:
    got = run_isolated(_arrays, (), name="test", timeout=60, alloc=True)
    want = _expected()
    for key in ("big", "view", "pts", "copied", "small", "empty", "strided"):
        np.testing.assert_array_equal(got[key], want[key])
        assert got[key].dtype == want[key].dtype and got[key].shape == want[key].shape
        assert got[key].flags.writeable
    np.testing.assert_array_equal(got["mesh"].points, want["mesh"].points)
    assert got["text"] == "kept"
    got["big"][5, 1] = -7  # writable, and private to this process now
    assert got["big"][5, 1] == -7


@pytest.mark.skipif(not SHARED_MEMORY, reason="no memfd_create/fork: results are pickled")
def test_big_arrays_are_mapped_not_copied() -> None:
    got = run_isolated(_arrays, (), name="test", timeout=60, alloc=True)
    for key in ("big", "view", "pts", "copied"):
        assert type(_mapped_file(got[key])).__name__ == "SharedResult", key
    # a view stays a view of the same memory, as it would be in-process
    got["big"][100, 0] = -1
    assert got["view"][0, 0] == -1
    # small arrays travel in the pickle: holding one must not hold the whole mapping
    for small in (got["small"], got["mesh"].points, got["strided"]):
        assert small.nbytes < ARENA_MIN_BYTES
        assert type(_mapped_file(small)).__name__ != "SharedResult"


@pytest.mark.skipif(not LINUX, reason="/proc is Linux")
def test_mapping_is_released_with_the_arrays() -> None:
    before = _memfd_mappings()
    got = run_isolated(_arrays, (), name="test", timeout=60, alloc=True)
    assert _memfd_mappings() == before + (1 if SHARED_MEMORY else 0)
    del got
    gc.collect()
    assert _memfd_mappings() == before


@pytest.mark.skipif(not LINUX, reason="/proc is Linux")
@pytest.mark.parametrize(
    "func, timeout, error",
    [
        (_crash_after_alloc, 60, "crashed \\(SIGKILL\\)"),
        (_hang, 0.5, "did not finish within 0.5 s"),
        (_hammesh_error, 60, "bad option from the child"),
        (_other_error, 60, "KeyError"),
    ],
)
def test_nothing_is_left_behind_on_failure(func, timeout: float, error: str) -> None:
    fds, shm, maps = _fds(), _dev_shm(), _memfd_mappings()
    with pytest.raises(hammesh.HammeshError, match=error) as info:
        run_isolated(func, (), name="Triangle", timeout=timeout, alloc=True)
    assert "\n" not in str(info.value)
    gc.collect()
    # no new descriptor (one another thread of this process closed meanwhile, e.g. a
    # kernel-cache file a previous test's loading thread had open, is not a leak)
    assert _fds() <= fds
    assert _dev_shm() == shm
    assert _memfd_mappings() == maps


def _result_file_sizes() -> list[tuple[int, int]]:
    """``(size, allocated bytes)`` of each result file this process maps."""
    out = []
    with open("/proc/self/maps") as f:
        for line in f:
            if MEMFD_NAME in line:
                st = os.stat(f"/proc/self/map_files/{line.split()[0]}")
                out.append((st.st_size, st.st_blocks * 512))
    return out


@pytest.mark.skipif(not (LINUX and SHARED_MEMORY), reason="/proc is Linux; no memfd: nothing shared")
def test_pages_allocated_ahead_beyond_the_result_are_given_back() -> None:
    """``prefault``: the parent allocates the result file ahead while the child computes;
    what the child did not use is cut off before the file is mapped (a mapping keeps
    the whole file alive, as long as the mesh lives)."""
    before = _result_file_sizes()
    got = run_isolated(_arrays, (), name="test", timeout=60, alloc=True, prefault=64 << 20)
    want = _expected()
    for key in ("big", "view", "pts", "copied"):
        np.testing.assert_array_equal(got[key], want[key])
    after = _result_file_sizes()
    assert len(after) == len(before) + 1
    size, allocated = max(after)  # (the arrays above are larger than any other test's)
    used = 300_000 * 3 * 8 + 100_000 * 2 * 8 + 60_000 * 8  # the three blocks, page-rounded below
    assert used <= size < used + 3 * os.sysconf("SC_PAGE_SIZE")
    assert allocated <= size  # nothing of the 64 MiB ahead is kept beyond it
    del got
    gc.collect()


@pytest.mark.skipif(not LINUX, reason="/proc is Linux")
@pytest.mark.parametrize("func, timeout, error", [(_crash_after_alloc, 60, "SIGKILL"), (_hang, 0.5, "within")])
def test_nothing_is_left_behind_on_failure_with_pages_ahead(func, timeout: float, error: str) -> None:
    fds, maps = _fds(), _memfd_mappings()
    with pytest.raises(hammesh.HammeshError, match=error):
        run_isolated(func, (), name="Triangle", timeout=timeout, alloc=True, prefault=32 << 20)
    gc.collect()
    assert _fds() <= fds
    assert _memfd_mappings() == maps
    assert not [t for t in threading.enumerate() if t.name == "hammesh-prefault"]


@pytest.mark.skipif(not LINUX, reason="/proc is Linux")
def test_nothing_is_left_behind_on_success() -> None:
    fds, shm = _fds(), _dev_shm()
    dom = hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=1e-4)
    assert m.n_triangles > 10_000
    _wait_for_reapers()
    assert _fds() == fds  # the file's descriptor is closed: only the mapping holds it
    assert _dev_shm() == shm


def test_pipe_fallback_gives_the_same_result(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(isolate, "SHARED_MEMORY", False)
    got = run_isolated(_arrays, (), name="test", timeout=60, alloc=True)
    np.testing.assert_array_equal(got["big"], _expected()["big"])
    assert type(_mapped_file(got["big"])).__name__ != "SharedResult"


def test_isolated_mesh_equals_in_process_mesh() -> None:
    dom = hammesh.Domain.from_polygon(
        [[0, 0], [1, 0], [1, 1], [0, 1]], holes=[[[0.4, 0.4], [0.6, 0.4], [0.6, 0.6], [0.4, 0.6]]]
    )
    a = hammesh.quality_mesh(dom, min_angle=30, max_area=2e-4, isolate=False)
    b = hammesh.quality_mesh(dom, min_angle=30, max_area=2e-4, isolate=True)
    for field in ("points", "triangles", "neighbors", "segments", "segment_markers", "triangle_attributes"):
        x, y = getattr(a, field), getattr(b, field)
        assert x.dtype == y.dtype and x.flags.c_contiguous and y.flags.c_contiguous, field
        np.testing.assert_array_equal(x, y)


_ORPHAN = textwrap.dedent(
    """
    import ctypes, os, sys
    from hammesh.meshing.isolate import run_isolated

    def c_sleep(path):
        with open(path + ".tmp", "w") as f:
            f.write(str(os.getpid()))
        os.replace(path + ".tmp", path)
        ctypes.PyDLL(None).sleep(120)  # C code that holds the GIL, like Triangle

    run_isolated(c_sleep, (sys.argv[1],), name="Triangle", timeout=None)
    """
)


def _running(pid: int) -> bool:
    """Whether ``pid`` exists and is not a zombie."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except (FileNotFoundError, ProcessLookupError):
        return False


@pytest.mark.skipif(not LINUX, reason="PR_SET_PDEATHSIG is Linux")
def test_child_dies_with_its_killed_parent(tmp_path: Path) -> None:
    script = tmp_path / "orphan.py"
    script.write_text(_ORPHAN)
    pid_file = tmp_path / "child.pid"
    parent = subprocess.Popen([sys.executable, str(script), str(pid_file)])
    try:
        deadline = time.monotonic() + 60
        while not pid_file.exists():
            assert parent.poll() is None, "the parent ended before its child started"
            assert time.monotonic() < deadline, "the child never started"
            time.sleep(0.05)
        child = int(pid_file.read_text())
        assert _running(child)
        parent.send_signal(signal.SIGKILL)  # no handler, no cleanup can run
        parent.wait(30)
        deadline = time.monotonic() + 10
        while _running(child) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not _running(child), "the meshing child outlived its SIGKILLed parent"
    finally:
        if parent.poll() is None:
            parent.kill()
            parent.wait()
        if pid_file.exists() and _running(int(pid_file.read_text())):
            os.kill(int(pid_file.read_text()), signal.SIGKILL)  # (only if the test failed)


def _allocate_200_mb() -> int:
    a = np.ones(200 * 2**20 // 8)  # (touched: a real allocation)
    return int(a.size)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="RLIMIT_AS and /proc: Linux")
def test_the_child_s_memory_is_capped_and_running_out_is_said(monkeypatch):
    """The child may use what it has plus a share of the available memory: a runaway
    refinement fails there ("ran out of memory") instead of taking the machine down."""
    assert run_isolated(_allocate_200_mb, (), name="test", timeout=60) == 200 * 2**20 // 8
    monkeypatch.setattr(isolate, "MEMORY_FRACTION", 1e-4)  # (a few MB more than the child has)
    with pytest.raises(hammesh.MeshingError, match="test ran out of memory"):
        run_isolated(_allocate_200_mb, (), name="test", timeout=60)
    # Triangle's own allocation failure (its triexit) is said the same way
    square = hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])
    with pytest.raises(hammesh.MeshingError, match="Triangle ran out of memory"):
        hammesh.quality_mesh(square, min_angle=30, max_area=1e-6)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="RLIMIT_AS and /proc: Linux")
def test_limit_memory_sets_size_plus_a_share_of_the_available_memory():
    code = ("import resource\nfrom hammesh.meshing.isolate import limit_memory\n"
            "got = limit_memory(0.5)\nprint(got, resource.getrlimit(resource.RLIMIT_AS)[0], limit_memory(0.9))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    got, soft, looser = int(out[0]), int(out[1]), out[2]
    assert got == soft > 0
    assert looser == "None"  # (a looser cap is never set over a tighter one)
