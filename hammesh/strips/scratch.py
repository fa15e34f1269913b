"""Work arrays kept from one two-halves encoding to the next (:mod:`hammesh.strips.halves`).

Why: a half of a 1M-triangle mesh writes ~70 MB of work arrays (its rows copy, the
pairing's buckets and keys, the triangle records, the greedy strips' queue) that the
process has never touched: every page is faulted in and zeroed by the kernel on first
write.  On the development VM that was ~10 ms of each half's ~85 ms thread CPU at 1M
(`docs/strips.md`, "Session 12").  Here the work arrays of a call are kept for
:data:`KEEP_SECONDS` and handed to the next call that needs them (only their size
matters: a buffer at least as large is reused, a larger one replaces it), so a program
that encodes meshes one after another pays the faults once.  The first call in a
process pays them in full (the benchmarks report it beside the best of several).
:func:`release` frees the kept arrays now; :func:`kept_bytes` says how much is held.

Nothing returned to the caller lives in these arrays (the index buffer is always a new
array).  A call takes every kept array out under a lock (:func:`borrow`) and gives its
arrays back when done (:meth:`Scratch.give_back`), so two calls at once never share a
buffer: the second finds nothing kept and allocates its own.
"""

from __future__ import annotations

import threading
import time

import numpy as np

from hammesh.pages import MADV_NOHUGEPAGE, MADV_POPULATE_WRITE, advise

__all__ = ["KEEP_SECONDS", "Scratch", "borrow", "new_buffer", "release", "kept_bytes"]

#: Seconds the work arrays of the last call are kept for the next one.
KEEP_SECONDS = 60.0

_lock = threading.Lock()
_kept: dict[str, np.ndarray] = {}
_last_use = 0.0
_timer: threading.Timer | None = None


class Scratch:
    """The work arrays of one call, by role name (one flat byte buffer each).

    :meth:`take` returns a view of the role's buffer shaped as asked (its contents are
    whatever the last call left: like ``np.empty``); :meth:`give_back` returns the
    buffers to the pool.
    """

    def __init__(self, kept: dict[str, np.ndarray]) -> None:
        self._kept = kept
        self._used: dict[str, np.ndarray] = {}

    def take(self, role: str, shape: int | tuple[int, ...], dtype, written: float = 1.0,
             huge: bool = False) -> np.ndarray:
        """An uninitialised array for ``role`` (each role at most once per call).

        ``written``: about which fraction of it the call writes (from the front).  A new
        buffer gets small pages, that part of it faulted in by one system call
        (:func:`new_buffer`); with ``huge``, numpy's default (transparent huge pages from 4
        MiB, faulted in as written): for arrays read and written at random, where a small
        page's TLB miss costs more than a huge page's fault (at 1M triangles the two halves
        took 3-10% longer with the records, pairing keys and strip queue in small pages).
        """
        dt = np.dtype(dtype)
        nbytes = int(np.prod(shape, dtype=np.int64)) * dt.itemsize
        buf = self._kept.pop(role, None)
        if buf is None or buf.nbytes < nbytes:
            size = max(nbytes, dt.itemsize)
            buf = np.empty(size, np.uint8) if huge else new_buffer(size, written)
        self._used[role] = buf
        return buf[:nbytes].view(dt).reshape(shape)

    def give_back(self) -> None:
        """Keep this call's buffers (and any it did not take) for the next call."""
        global _last_use, _timer
        bufs = {**self._kept, **self._used}
        self._kept, self._used = {}, {}
        with _lock:
            for role, buf in bufs.items():
                old = _kept.get(role)
                if old is None or old.nbytes < buf.nbytes:  # two calls at once: keep the larger
                    _kept[role] = buf
            _last_use = time.monotonic()
            if _timer is None:
                _timer = threading.Timer(KEEP_SECONDS, _expire)
                _timer.daemon = True
                _timer.start()


def new_buffer(nbytes: int, written: float) -> np.ndarray:
    """``nbytes`` of new memory in small pages, its first ``written`` fraction faulted in now.

    Why (the first call in a process; ``docs/strips.md``, Speed): numpy asks for
    transparent huge pages on arrays of 4 MiB and more, and with this VM's
    ``defrag=madvise`` a huge-page fault may compact memory first: first encodings at
    1M triangles spent 82-288 ms of system time faulting their work arrays in huge pages,
    32-56 ms in small ones (four fresh processes each).  ``MADV_POPULATE_WRITE`` then faults the part the call
    writes in one system call instead of a trap per page (:mod:`hammesh.pages`); the
    rest is faulted in only if it is ever written.
    """
    buf = np.empty(nbytes, np.uint8)
    advise(buf, MADV_NOHUGEPAGE)
    if written > 0:
        advise(buf[: int(nbytes * min(written, 1.0))], MADV_POPULATE_WRITE)
    return buf


def borrow() -> Scratch:
    """Every kept array, taken out of the pool for one call (see the module docstring)."""
    with _lock:
        kept = dict(_kept)
        _kept.clear()
    return Scratch(kept)


def _expire() -> None:
    """The timer: release when nothing used the arrays for :data:`KEEP_SECONDS`, else wait on."""
    global _timer
    with _lock:
        _timer = None
        idle = time.monotonic() - _last_use
        if idle < KEEP_SECONDS:
            _timer = threading.Timer(KEEP_SECONDS - idle, _expire)
            _timer.daemon = True
            _timer.start()
            return
        _kept.clear()


def release() -> None:
    """Free the kept work arrays now (arrays a running call has taken are not affected)."""
    global _timer
    with _lock:
        _kept.clear()
        if _timer is not None:
            _timer.cancel()
        _timer = None


def kept_bytes() -> int:
    """Bytes of work arrays kept for the next call."""
    with _lock:
        return sum(b.nbytes for b in _kept.values())
