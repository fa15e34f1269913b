"""GL_TRIANGLE_STRIP index buffers with exact OpenGL semantics (paper §1, §5).

OpenGL draws triangle ``i`` of a strip from indices ``i, i+1, i+2``; odd ``i`` have their
winding swapped, ``(i+1, i, i+2)``; a triangle with a repeated index is degenerate and
draws nothing.  With primitive restart enabled, the restart index ends one strip and the
next index starts a new one at ``i = 0``.

Encoding a dual path sends three indices for its first triangle and one per further
triangle, plus one repeated index (a *swap*) wherever two consecutive turns go the same
way (see :mod:`hammesh.strips.paths`).  Several paths are joined either with the
primitive-restart index or by *degenerate stitching* (repeat the last index and the next
strip's first; the next strip's start is re-ordered when it falls on an odd position, so
a join always costs two indices).

:func:`decode_gl_strip` applies the OpenGL rules literally; :func:`verify_gl_strip`
proves that a buffer draws exactly a mesh's oriented triangles.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hammesh.errors import InvalidOptionError, VerificationError
from hammesh.strips._decode_kernels import check_claimed_draws
from hammesh.strips._emit_kernels import emit_restart_joined, stitch_strips
from hammesh.strips.defects import MeshDefects, defect_fields
from hammesh.strips.dual import oriented_key
from hammesh.strips.paths import PathTurns, path_turns

__all__ = [
    "GLStrip",
    "RESTART_INDEX",
    "JOINS",
    "gl_strip",
    "gl_strip_from_turns",
    "decode_gl_strip",
    "verify_gl_strip",
]

#: Default primitive-restart index: ``GL_PRIMITIVE_RESTART_FIXED_INDEX`` for uint32 buffers.
RESTART_INDEX = 0xFFFFFFFF

#: How several strips are joined into one buffer.
JOINS = ("restart", "stitch")


@dataclass(frozen=True, eq=False)
class GLStrip:
    """One GL_TRIANGLE_STRIP index buffer.

    Attributes
    ----------
    indices : (L,) int64
    restart_index : int or None
        The primitive-restart index used in ``indices`` (``None``: stitched, no restart).
    n_triangles : int
        Non-degenerate triangles drawn (a walk that redraws counts them again).
    n_strips : int
        Dual paths encoded (strips before joining).
    n_swaps : int
        Repeated indices inserted for two turns the same way.
    defects : MeshDefects or None
        What the input mesh had (set by :func:`~hammesh.strips.encode.encode`).
    dropped : (k,) int64
        Input rows not drawn: they repeat a vertex index (OpenGL draws nothing for them).
    vertex_order : (n,) int64 or None
        Set when the vertices were renumbered in order of first use
        (``encode(..., reorder_vertices=True)``): ``indices`` refer to the vertex buffer
        ``points[vertex_order]``.
    """

    indices: np.ndarray
    restart_index: int | None
    n_triangles: int
    n_strips: int
    n_swaps: int
    defects: MeshDefects | None = None
    dropped: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64), repr=False)
    vertex_order: np.ndarray | None = field(default=None, repr=False)

    @property
    def indices_per_triangle(self) -> float:
        return len(self.indices) / max(self.n_triangles, 1)

    def to_dict(self) -> dict:
        """The JSON document of ``hammesh strip`` (see ``docs/strips.md``)."""
        return {
            "primitive": "triangle_strip",
            "indices": self.indices.tolist(),
            "restart_index": self.restart_index,
            "triangles": int(self.n_triangles),
            "strips": int(self.n_strips),
            "indices_per_triangle": float(self.indices_per_triangle),
            "swaps": int(self.n_swaps),
        } | defect_fields(self.defects, self.dropped) | (
            {} if self.vertex_order is None else {"vertex_order": self.vertex_order.tolist()}
        )


def _even_encoding(turns: PathTurns) -> tuple[np.ndarray, np.ndarray]:
    """Each path encoded to start at an even position, concatenated; with its offsets."""
    first, swap = turns.first, turns.swap
    counts = np.where(first, 3, 1 + swap.astype(np.int64))
    ends = np.cumsum(counts)
    pos = ends - counts
    out = np.empty(int(ends[-1]) if len(ends) else 0, dtype=np.int64)
    f = np.flatnonzero(first)
    out[pos[f]] = turns.head[f, 0]
    out[pos[f] + 1] = turns.head[f, 1]
    out[pos[f] + 2] = turns.head[f, 2]
    s = np.flatnonzero(swap)
    out[pos[s]] = turns.pivot[s - 1]
    nf = np.flatnonzero(~first)
    out[pos[nf] + swap[nf]] = turns.new_vertex[nf]
    enc_starts = np.r_[pos[turns.starts[:-1]], len(out)].astype(np.int64)
    return out, enc_starts


def gl_strip_from_turns(
    turns: PathTurns, *, join: str = "restart", restart_index: int | None = RESTART_INDEX
) -> GLStrip:
    """Encode analysed dual paths (:func:`~hammesh.strips.paths.path_turns`) as one buffer.

    See :func:`gl_strip` for the parameters.
    """
    if join not in JOINS:
        raise InvalidOptionError(f"join must be one of {', '.join(JOINS)}, got {join!r}")
    S = turns.n_paths
    n_swaps = turns.n_swaps
    if S == 1 and join == "stitch":
        enc, _ = _even_encoding(turns)
        return GLStrip(enc, None, len(turns.order), 1, n_swaps)
    if join == "restart":
        if restart_index is None:
            if S == 1:
                enc, _ = _even_encoding(turns)
                return GLStrip(enc, None, len(turns.order), 1, n_swaps)
            raise InvalidOptionError("join='restart' needs a restart_index")
        R = int(restart_index)
        out, top = emit_restart_joined(
            turns.first, turns.swap, turns.head, turns.pivot, turns.new_vertex, turns.starts, R
        )
        if 0 <= R <= top and np.count_nonzero(out == R) != S - 1:
            raise InvalidOptionError(f"restart index {R} is a vertex index of the mesh")
        return GLStrip(out, R, len(turns.order), S, n_swaps)
    enc, enc_starts = _even_encoding(turns)
    ntri = np.diff(turns.starts)
    swap1 = np.zeros(S, dtype=bool)
    long = ntri >= 3
    swap1[long] = turns.swap[turns.starts[:-1][long] + 1]
    out = stitch_strips(enc, enc_starts, ntri, swap1)
    # stitching at odd starts toggles each such strip's first swap; recount from the buffer
    w = np.lib.stride_tricks.sliding_window_view(out, 3) if len(out) >= 3 else np.zeros((0, 3), np.int64)
    degenerate = (w[:, 0] == w[:, 1]) | (w[:, 1] == w[:, 2]) | (w[:, 0] == w[:, 2])
    drawn = len(w) - int(degenerate.sum())
    n_swaps = len(out) - drawn - 2 - 2 * (S - 1) - 2 * (S - 1)
    return GLStrip(out, None, len(turns.order), S, int(n_swaps))


def gl_strip(
    triangles: np.ndarray,
    twin: np.ndarray,
    order: np.ndarray,
    starts: np.ndarray,
    *,
    join: str = "restart",
    restart_index: int | None = RESTART_INDEX,
) -> GLStrip:
    """GL_TRIANGLE_STRIP buffer drawing the triangles of dual paths, in path order.

    Parameters
    ----------
    triangles : (m, 3) int64
        Windings to reproduce.
    twin : (3 m,) int64
        Half-edge pairing of ``triangles`` (:func:`hammesh.strips.dual.dual_mesh`).
    order : (L,) int
        Triangle ids, path after path; consecutive ones in a path share an edge.
    starts : (S + 1,) int
        Path offsets into ``order``.
    join : {"restart", "stitch"}
        Join paths with ``restart_index`` or by degenerate stitching.
    restart_index : int
        Must not be a vertex index (default ``0xFFFFFFFF``).

    Returns
    -------
    GLStrip
        ``len(order) + 2 S + swaps`` indices plus ``S - 1`` restarts, or plus
        ``2 (S - 1)`` stitching indices.

    Examples
    --------
    A zig-zag of four triangles whose first one is counter-clockwise in strip order
    needs no swap: ``T + 2`` indices.

    >>> import numpy as np
    >>> from hammesh.mesh import Mesh
    >>> from hammesh.strips.dual import dual_mesh
    >>> pts = np.array([[0., 1], [0, 0], [1, 1], [1, 0], [2, 1], [2, 0]])
    >>> d = dual_mesh(Mesh(pts, np.array([[0, 1, 2], [2, 1, 3], [2, 3, 4], [4, 3, 5]])))
    >>> s = gl_strip(d.triangles, d.twin, [0, 1, 2, 3], [0, 4])
    >>> s.indices.tolist(), s.n_swaps
    ([0, 1, 2, 3, 4, 5], 0)
    >>> decode_gl_strip(s.indices).tolist()
    [[0, 1, 2], [2, 1, 3], [2, 3, 4], [4, 3, 5]]
    """
    turns = path_turns(triangles, twin, order, starts)
    return gl_strip_from_turns(turns, join=join, restart_index=restart_index)


def decode_gl_strip(indices: np.ndarray, restart_index: int | None = None) -> np.ndarray:
    """Triangles an OpenGL ``GL_TRIANGLE_STRIP`` draw of ``indices`` produces, in order.

    Parameters
    ----------
    indices : (L,) int
    restart_index : int, optional
        Primitive-restart index (``None``: restart disabled; the value is then an
        ordinary index).

    Returns
    -------
    (k, 3) int64
        Triangle ``i`` of each strip is ``(i, i+1, i+2)`` for even ``i`` and
        ``(i+1, i, i+2)`` for odd ``i``; triangles with a repeated index are dropped.

    Examples
    --------
    >>> decode_gl_strip([0, 1, 2, 2, 3, 7, 4, 5, 6], restart_index=7).tolist()
    [[0, 1, 2], [4, 5, 6]]
    """
    given = np.asarray(indices)
    if given.size and given.dtype.kind not in "iu":  # (a float buffer would be truncated in silence)
        raise InvalidOptionError(f"indices must be integers, got an array of {given.dtype}")
    if given.size and given.min() < 0:
        raise InvalidOptionError(f"indices must be >= 0, got {int(given.min())}")
    idx = given.astype(np.int64, copy=False).reshape(-1)
    L = len(idx)
    if L < 3:
        return np.zeros((0, 3), dtype=np.int64)
    i = np.arange(L, dtype=np.int64)
    if restart_index is None:
        is_r = np.zeros(L, dtype=bool)
    else:
        is_r = idx == int(restart_index)
    last_r = np.maximum.accumulate(np.where(is_r, i, -1))
    pos = i - last_r - 1  # position inside its strip (-1 at a restart)
    w = i[: L - 2]
    # a window is a triangle iff it holds no restart: its start is >= 0 and no restart
    # occurs in (start, start + 2], i.e. the last restart at start + 2 is before start
    valid = (pos[w] >= 0) & (last_r[w + 2] < w)
    a, b, c = idx[w], idx[w + 1], idx[w + 2]
    odd = (pos[w] % 2) == 1
    tri = np.stack([np.where(odd, b, a), np.where(odd, a, b), c], axis=1)
    keep = valid & (a != b) & (b != c) & (a != c)
    return tri[keep]


def _can_split(split, idx: np.ndarray, r: int, use_r: bool, n: int) -> bool:
    if split is None or not use_r:
        return False
    p, q = int(split[0]), int(split[1])
    return 0 < p < len(idx) and 0 <= q <= n and int(idx[p - 1]) == r


def _check_in_two_parts(tri: np.ndarray, idx: np.ndarray, r: int, claim: np.ndarray, split) -> bool:
    """The claimed-order proof of both halves of a buffer cut after a restart, one on a second thread."""
    from concurrent.futures import ThreadPoolExecutor

    from hammesh.strips._decode_kernels import check_claimed_part

    m = len(tri)
    if len(claim) != m:
        return False
    p, q = int(split[0]), int(split[1])
    seen = np.zeros(m, np.bool_)
    with ThreadPoolExecutor(1) as pool:
        second = pool.submit(check_claimed_part, tri, idx[p:], r, True, claim[q:], seen)
        first = check_claimed_part(tri, idx[: p - 1], r, True, claim[:q], seen)
        second = second.result()
    # each part drew exactly its claim (q and m - q rows, none twice within a part): a row
    # named in both parts would leave another unseen
    return first[0] == 0 and second[0] == 0 and bool(seen.all())


def verify_gl_strip(
    triangles: np.ndarray,
    indices: np.ndarray,
    restart_index: int | None = None,
    *,
    allow_redraw: bool = False,
    order: np.ndarray | None = None,
    split: tuple[int, int] | None = None,
) -> None:
    """Prove that a buffer draws exactly ``triangles`` with their windings.

    Parameters
    ----------
    triangles : (m, 3) int
    indices : (L,) int
    restart_index : int, optional
    allow_redraw : bool
        Accept triangles drawn more than once (walks of Thm 5.3): compare sets instead
        of multisets.
    order : (m,) int, optional
        The rows in the order the encoder meant them to be drawn.  Then the proof is
        two O(L) compiled passes (:func:`~hammesh.strips._decode_kernels.check_claimed_draws`): decode
        with OpenGL's rules, the ``k``-th triangle drawn is row ``order[k]`` with its
        winding, and ``order`` names every row once.  If that claim fails, the full
        O(m log m) comparison below decides (and names the problem).
    split : (p, q), optional
        With ``order``: check ``indices[:p - 1]`` against ``order[:q]`` and
        ``indices[p:]`` against ``order[q:]`` on two threads
        (:func:`~hammesh.strips._decode_kernels.check_claimed_part`).  Sound for any
        ``(p, q)``: the cut is used only where ``indices[p - 1]`` is the restart index
        (there OpenGL starts a new strip, so each part decodes as the whole does);
        anywhere else the buffer is checked in one piece.

    Raises
    ------
    VerificationError
        Naming a triangle that is missing, reversed, extra or drawn twice.
    """
    if order is not None and not allow_redraw:
        tri = np.ascontiguousarray(triangles, dtype=np.int64).reshape(-1, 3)
        idx = np.ascontiguousarray(indices, dtype=np.int64).reshape(-1)
        use_r = restart_index is not None
        r = int(restart_index) if use_r else -1
        claim = np.ascontiguousarray(order, dtype=np.int64)
        if _can_split(split, idx, r, use_r, len(claim)):
            if _check_in_two_parts(tri, idx, r, claim, split):
                return
        else:
            status, _ = check_claimed_draws(tri, idx, r, use_r, claim)
            if status == 0:
                return
    want = oriented_key(triangles)
    got = oriented_key(decode_gl_strip(indices, restart_index))
    if allow_redraw:
        got = np.unique(got, axis=0)
        want = np.unique(want, axis=0)
    if got.shape == want.shape and np.array_equal(got, want):
        return
    gs = {tuple(r) for r in got.tolist()}
    ws = {tuple(r) for r in want.tolist()}
    missing = sorted(ws - gs)
    extra = sorted(gs - ws)
    if missing:
        t = missing[0]
        rev = (t[0], t[2], t[1])
        how = "drawn reversed" if tuple(oriented_key(np.array([rev]))[0]) in gs else "not drawn"
        raise VerificationError(f"triangle {list(t)} of the mesh is {how} by the strip buffer")
    if extra:
        raise VerificationError(f"the strip buffer draws {list(extra[0])}, which is not a mesh triangle")
    raise VerificationError(
        f"the strip buffer draws {len(got)} triangles for a mesh of {len(want)} (some drawn twice)"
    )
