"""Load the compiled kernels of the large-mesh encoder ahead of the first call.

numba keeps each kernel's machine code in its disk cache, but a new process still loads
it on the first call of each kernel (the library unpickled, its object code linked, behind
one compiler lock): ~20-35 ms for the two-halves encoder's seven kernels at 1M triangles,
paid by the first ``encode`` (docs/strips.md, session 13).  :func:`prepare` encodes a small
grid through the same two-halves path (both modes), so a caller that starts it before
reading its mesh finds the kernels loaded.  Explicit, not an import side effect: a thread
started by ``import`` would run numba's lazy imports beside the caller's own.  ``encode``
itself starts it at its first two-halves call of each mode in a process (the kernels then
load while the halves copy and pair the mesh; ``hammesh.strips.encode._load_ahead``).
"""

from __future__ import annotations

import threading

import numpy as np

from hammesh.strips.encode import half_encoder
from hammesh.strips.gl import RESTART_INDEX
from hammesh.strips.halves import encode_in_halves

__all__ = ["prepare", "PREPARE_GRID", "quad_grid"]

#: Quads a side of the grid :func:`prepare` encodes (two triangles each: 1,152 triangles).
PREPARE_GRID = 24


def quad_grid(n: int) -> tuple[np.ndarray, np.ndarray]:
    """``n`` x ``n`` unit quads: ``points (n + 1)^2 x 2 float64``, ``triangles 2 n^2 x 3 int64`` (CCW)."""
    j, i = np.divmod(np.arange((n + 1) ** 2), n + 1)
    points = np.c_[i, j].astype(np.float64)
    v = (np.arange(n)[None, :] + (n + 1) * np.arange(n)[:, None]).ravel()
    triangles = np.r_[np.c_[v, v + 1, v + n + 2], np.c_[v, v + n + 2, v + n + 1]].astype(np.int64)
    return points, triangles


def _load(fast: bool) -> None:
    points, triangles = quad_grid(PREPARE_GRID)
    R = RESTART_INDEX
    # swap weight 1: any int will do, numba compiles (and loads) one machine code per type.
    # Not from the work arrays' pool: encode() starts this beside a large call, which would
    # then find the pool emptied by the grid and fault in ~140 MB of new arrays at 1M
    encode_in_halves(points, triangles, R, True, 1, None if fast else half_encoder(R), pooled=False)


def prepare(background: bool = True, fast: bool = False) -> threading.Thread | None:
    """Load the compiled kernels ``encode(mesh, fast=fast)`` runs on a large mesh (its two
    halves; ``float64`` points, ``int64`` rows).

    Parameters
    ----------
    background : bool
        Load them on a daemon thread (returned; ``join`` it to wait) while the caller
        reads its mesh; ``False``: load them now and return ``None``.
    fast : bool
        The kernels of ``encode(fast=True)`` (seven), else those of the default mode (its
        greedy cover, end moves and writer: a dozen more, which a thread still loading
        them would take from a fast encoding's second core).

    A first ``encode`` that starts while the thread is still loading waits for numba's
    compiler lock and then finds the kernels loaded: nothing is loaded twice.
    """
    if not background:
        _load(fast)
        return None
    t = threading.Thread(target=_load, args=(fast,), name="hammesh.strips.prepare", daemon=True)
    t.start()
    return t
