"""How the strip kernels are compiled, and their work buffers.

* :data:`loop_helper`: the decorator of the small helpers called inside the encoder's
  loops.  They read and write the arrays they are given but never allocate, so they are
  compiled without numba's reference counting (NRT): with it, every call increfs and
  decrefs each array argument, ~70 ns a call on the development machine, which had made
  the path-cover moves ten times slower than their arithmetic.  ``_nrt`` is a private
  numba option, so a numba that rejects it (when decorating or when compiling a probe)
  gets plain ``njit(cache=True, nogil=True)``: same results, slower moves
  (:data:`HELPERS_WITHOUT_REFCOUNT` says which).
* :func:`carve`: one numpy buffer cut into the named work arrays of a kernel, the
  offsets computed once, here.  numpy asks for transparent huge pages on big arrays; a
  dozen numba-allocated arrays had cost ~5 ms of first-touch page faults at 100k
  triangles.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["kernel", "loop_helper", "HELPERS_WITHOUT_REFCOUNT", "carve", "NEXT_CORNER", "row", "CORNERS"]

#: The decorator of every strip kernel that may allocate.
kernel = njit(cache=True, nogil=True)

#: ``(k + 1) % 3`` as a table: an index select instead of a division or a branch.
NEXT_CORNER = np.array([1, 2, 0], np.int64)

#: An index the caller knows is ``>= 0``, as ``np.uint64``: numba indexes with it without
#: Python's negative-index wraparound (a compare and a select per access; ~10% of the
#: greedy cover's time at 1M triangles).  Arithmetic on it stays unsigned only with other
#: ``uint64`` operands (``row(h) // CORNERS``; with a literal, ``row(h) // 3``, numba
#: types the result ``int64`` again), so convert back (``np.int64``) for signed arithmetic.
row = np.uint64

#: Corners per triangle as ``np.uint64``: ``row(h) // CORNERS`` is the triangle of
#: half-edge ``h``, still unsigned.
CORNERS = np.uint64(3)


def _probe(a):
    a[0] += 1
    return a[0]


def _helper_decorator():
    """``njit(cache=True, nogil=True, _nrt=False)`` if this numba accepts and compiles it, else without ``_nrt``."""
    try:
        dec = njit(cache=True, nogil=True, _nrt=False)
        probe = dec(_probe)
        if probe(np.zeros(1, np.int64)) != 1:
            raise RuntimeError("probe gave a wrong result")
        return dec, True
    except Exception:  # noqa: BLE001 - any failure of the private option: plain njit
        return njit(cache=True, nogil=True), False


loop_helper, HELPERS_WITHOUT_REFCOUNT = _helper_decorator()


def carve(dtype, *shapes):
    """Views of one new numpy buffer, one per shape (an int or a tuple), in order.

    >>> a, b = carve(np.int64, (2, 3), 4)
    >>> a.shape, b.shape, a.base is b.base
    ((2, 3), (4,), True)
    """
    sizes = [int(np.prod(s)) for s in shapes]
    buf = np.empty(sum(sizes), dtype)
    out = []
    at = 0
    for s, n in zip(shapes, sizes):
        out.append(buf[at : at + n].reshape(s))
        at += n
    return out
