"""Dual paths: the turn of every triangle along a triangle order.

A *dual path* is a sequence of triangles in which consecutive triangles share an edge.
Several paths are stored flat: ``order (L,)`` triangle ids and ``starts (S + 1,)``
offsets (path ``s`` is ``order[starts[s]:starts[s + 1]]``).  A triangle may occur more
than once (a walk that redraws triangles, as in Thm 5.3).

Along a path each triangle except the ends is entered through one edge and left
through another; the two share one vertex, the *pivot*.  In an encoding that sends
one new vertex per triangle the two registers after a triangle hold its exit edge:
the pivot (older) and the triangle's new vertex (newer).  The next triangle's natural
exit contains the newer register, so a *swap* (IRIS GL ``swaptmesh``, or one repeated
index in a GL strip) is needed exactly when two consecutive pivots coincide — when
three consecutively crossed edges share a vertex, the paper's definition of a
non-sequential step (§4).  The first triangle's older register is the tail of its exit
half-edge (forced by its winding).

One O(L) pass of a compiled kernel (:func:`hammesh.strips._path_kernels.path_turns`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hammesh.errors import InvalidMeshError
from hammesh.strips import _path_kernels

__all__ = ["PathTurns", "path_turns", "check_starts"]


@dataclass(frozen=True, eq=False)
class PathTurns:
    """Per-position data of flat dual paths (see the module docstring).

    Attributes
    ----------
    order : (L,) int64
    starts : (S + 1,) int64
    first, last : (L,) bool
        Position opens / closes its path.
    entry : (L,) int64
        Local edge ``k`` (0..2) of ``order[i]`` crossed to enter it, -1 at path starts.
    exit : (L,) int64
        Local edge crossed to leave, -1 at path ends.
    new_vertex : (L,) int64
        Vertex opposite the entry edge (the one index a strip sends), -1 at path starts.
    pivot : (L,) int64
        Older register after the triangle: shared vertex of entry and exit edges; at a
        path start, the tail of the exit half-edge; -1 at path ends.
    swap : (L,) bool
        A swap is needed before this triangle's new vertex.
    head : (L, 3) int64
        At path starts, the three vertices sent first (opposite vertex, then the exit
        half-edge's tail and head; a one-triangle path: its row); zero elsewhere.
    """

    order: np.ndarray
    starts: np.ndarray
    first: np.ndarray
    last: np.ndarray
    entry: np.ndarray
    exit: np.ndarray
    new_vertex: np.ndarray
    pivot: np.ndarray
    swap: np.ndarray
    head: np.ndarray

    @property
    def n_paths(self) -> int:
        return len(self.starts) - 1

    @property
    def n_swaps(self) -> int:
        return int(self.swap.sum())


def check_starts(order: np.ndarray, starts: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
    """Validate flat paths; return them as int64 arrays.

    Raises
    ------
    InvalidMeshError
        ``starts`` not from 0 to ``len(order)`` strictly increasing, or a triangle id
        out of range.
    """
    order = np.ascontiguousarray(order, dtype=np.int64).reshape(-1)
    starts = np.ascontiguousarray(starts, dtype=np.int64).reshape(-1)
    if len(order) == 0:
        raise InvalidMeshError("the triangle order is empty")
    if len(starts) < 2 or starts[0] != 0 or starts[-1] != len(order) or np.any(np.diff(starts) <= 0):
        raise InvalidMeshError(
            f"path offsets must rise strictly from 0 to {len(order)}, got {starts[:6].tolist()}..."
        )
    if order.min() < 0 or order.max() >= m:
        i = int(np.argmax((order < 0) | (order >= m)))
        raise InvalidMeshError(f"position {i} of the order names triangle {int(order[i])}; there are {m}")
    return order, starts


def path_turns(triangles: np.ndarray, twin: np.ndarray, order: np.ndarray, starts: np.ndarray) -> PathTurns:
    """Entry/exit edges, pivots and swaps of flat dual paths.

    Parameters
    ----------
    triangles : (m, 3) int64
    twin : (3 m,) int64
        Half-edge pairing (:attr:`hammesh.strips.dual.DualMesh.twin`).
    order : (L,) int
        Triangle ids, path after path.
    starts : (S + 1,) int
        Path offsets into ``order``.

    Returns
    -------
    PathTurns

    Raises
    ------
    InvalidMeshError
        Two consecutive triangles of a path do not share an edge, or a path leaves a
        triangle through the edge it entered by (a walk that turns back must be split).
    """
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    order, starts = check_starts(order, starts, len(tri))
    twin = np.ascontiguousarray(twin, dtype=np.int64)
    r = _path_kernels.path_turns(tri, twin, order, starts)
    err, j = r.err, r.pos
    if err == 1:
        raise InvalidMeshError(
            f"triangles {int(order[j])} and {int(order[j + 1])} (positions {j}, {j + 1} of the "
            "order) are consecutive in a path but share no edge"
        )
    if err == 2:
        raise InvalidMeshError(
            f"the path turns back at position {j} (triangle {int(order[j])} is left through the "
            "edge it was entered by); split the walk there"
        )
    return PathTurns(
        order=order,
        starts=starts,
        first=r.first,
        last=r.last,
        entry=r.entry,
        exit=r.exit,
        new_vertex=r.new_vertex,
        pivot=r.pivot,
        swap=r.swap,
        head=r.head,
    )
