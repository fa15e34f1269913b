"""Generalized triangle strips (IRIS GL ``tmesh`` style): one vertex per triangle plus a turn bit.

The paper's §1 encoding of a Hamiltonian ordering: after the first two vertices, every
triangle sends one new vertex and one bit saying whether the two registers are swapped
(``swaptmesh``) before the vertex is used.  Any triangle order in which consecutive
triangles share an edge (a dual path) has such an encoding; the swap bits are exactly the
places where two consecutive turns go the same way (:mod:`hammesh.strips.paths`).

Decoding keeps two registers ``r0, r1`` (the first two vertices).  For each further vertex
``v`` with bit ``b``: if ``b``, swap ``r0, r1``; emit ``(r0, r1, v)`` on even parity or
``(r1, r0, v)`` on odd parity (parity flips once per triangle and once per swap); then
``r0, r1 = r1, v``.  This equals a GL strip in which every set bit is a repeated index.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hammesh.errors import InvalidMeshError
from hammesh.strips._decode_kernels import decode_generalized_strips
from hammesh.strips.defects import MeshDefects, defect_fields
from hammesh.strips.paths import PathTurns, path_turns

__all__ = ["GeneralizedStrips", "generalized_strips", "generalized_from_turns", "decode_generalized"]


@dataclass(frozen=True, eq=False)
class GeneralizedStrips:
    """Several generalized strips, stored flat.

    Attributes
    ----------
    vertices : (T + 2 S,) int64
        Strip after strip; strip ``s`` is ``vertices[vertex_starts[s]:vertex_starts[s + 1]]``.
    swaps : (T,) bool
        One turn bit per triangle (always ``False`` for a strip's first triangle).
    vertex_starts : (S + 1,) int64
    triangle_starts : (S + 1,) int64
        Offsets of each strip's triangles (and bits).
    defects : MeshDefects or None
        What the input mesh had (set by :func:`~hammesh.strips.encode.encode_generalized`).
    dropped : (k,) int64
        Input rows not encoded: they repeat a vertex index.
    """

    vertices: np.ndarray
    swaps: np.ndarray
    vertex_starts: np.ndarray
    triangle_starts: np.ndarray
    defects: MeshDefects | None = None
    dropped: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64), repr=False)

    @property
    def n_triangles(self) -> int:
        return int(len(self.swaps))

    @property
    def n_strips(self) -> int:
        return int(len(self.triangle_starts) - 1)

    @property
    def n_swaps(self) -> int:
        return int(self.swaps.sum())

    @property
    def indices_per_triangle(self) -> float:
        return len(self.vertices) / max(self.n_triangles, 1)

    def to_dict(self) -> dict:
        """JSON document of ``hammesh strip --generalized`` (see ``docs/strips.md``)."""
        return {
            "primitive": "generalized_strip",
            "indices": self.vertices.tolist(),
            "swap_bits": self.swaps.astype(np.int64).tolist(),
            "strip_starts": self.vertex_starts.tolist(),
            "restart_index": None,
            "triangles": self.n_triangles,
            "strips": self.n_strips,
            "swaps": self.n_swaps,
            "indices_per_triangle": float(self.indices_per_triangle),
        } | defect_fields(self.defects, self.dropped)


def generalized_from_turns(turns: PathTurns) -> GeneralizedStrips:
    """Generalized strips of analysed dual paths (:func:`~hammesh.strips.paths.path_turns`)."""
    first = turns.first
    counts = np.where(first, 3, 1)
    ends = np.cumsum(counts)
    pos = ends - counts
    out = np.empty(int(ends[-1]), dtype=np.int64)
    f = np.flatnonzero(first)
    for j in range(3):
        out[pos[f] + j] = turns.head[f, j]
    nf = np.flatnonzero(~first)
    out[pos[nf]] = turns.new_vertex[nf]
    vstarts = np.r_[pos[turns.starts[:-1]], len(out)].astype(np.int64)
    return GeneralizedStrips(out, turns.swap.copy(), vstarts, turns.starts.copy())


def generalized_strips(
    triangles: np.ndarray, twin: np.ndarray, order: np.ndarray, starts: np.ndarray
) -> GeneralizedStrips:
    """Generalized strips drawing dual paths' triangles in path order.

    Parameters
    ----------
    triangles : (m, 3) int64
    twin : (3 m,) int64
        Half-edge pairing (:func:`hammesh.strips.dual.dual_mesh`).
    order : (L,) int
        Triangle ids, path after path; consecutive triangles of a path share an edge.
    starts : (S + 1,) int
        Path offsets into ``order``.

    Returns
    -------
    GeneralizedStrips
        ``L + 2 S`` vertices and ``L`` bits.

    Examples
    --------
    A fan of four triangles around vertex 0 crosses three edges at vertex 0 in a row:
    one swap.

    >>> import numpy as np
    >>> from hammesh.mesh import Mesh
    >>> from hammesh.strips.dual import dual_mesh
    >>> pts = np.array([[0., 0], [1, 0], [1, 1], [0, 1], [-1, 1], [-1, 0]])
    >>> d = dual_mesh(Mesh(pts, np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]])))
    >>> g = generalized_strips(d.triangles, d.twin, [0, 1, 2, 3], [0, 4])
    >>> g.vertices.tolist(), g.swaps.tolist()
    ([1, 2, 0, 3, 4, 5], [False, False, True, False])
    >>> decode_generalized(g).tolist()
    [[1, 2, 0], [0, 2, 3], [0, 3, 4], [0, 4, 5]]
    """
    return generalized_from_turns(path_turns(triangles, twin, order, starts))


def decode_generalized(strips: GeneralizedStrips) -> np.ndarray:
    """Oriented triangles drawn by generalized strips, in order.

    Returns
    -------
    (T, 3) int64

    Raises
    ------
    InvalidMeshError
        Inconsistent offsets (a strip's vertex count is not its triangle count plus two)
        or a bit set on a strip's first triangle.
    """
    v = np.ascontiguousarray(strips.vertices, dtype=np.int64)
    b = np.ascontiguousarray(strips.swaps, dtype=np.bool_)
    vs = np.ascontiguousarray(strips.vertex_starts, dtype=np.int64)
    ts = np.ascontiguousarray(strips.triangle_starts, dtype=np.int64)
    if len(vs) != len(ts) or vs[0] != 0 or ts[0] != 0 or vs[-1] != len(v) or ts[-1] != len(b):
        raise InvalidMeshError("generalized strip offsets do not match the vertex and bit arrays")
    nt = np.diff(ts)
    if np.any(nt < 1) or np.any(np.diff(vs) != nt + 2):
        s = int(np.argmax((nt < 1) | (np.diff(vs) != nt + 2)))
        raise InvalidMeshError(f"generalized strip {s} does not have two more vertices than triangles")
    if np.any(b[ts[:-1]]):
        s = int(np.argmax(b[ts[:-1]]))
        raise InvalidMeshError(f"generalized strip {s} has a swap bit on its first triangle")
    return decode_generalized_strips(v, vs, b, ts)
