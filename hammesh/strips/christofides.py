"""Thm 5.3: an encoding sequence at most 9/4 times optimal, via Christofides.

The triangles are the cities, the distance of two triangles is their shortest-path
distance in the dual graph (a metric), and networkx's Christofides heuristic gives a
closed tour within 3/2 of the shortest walk visiting every triangle; expanded along
shortest dual paths it is a walk of ``m'`` triangle visits (``m <= m' <= 2 m``).

Ears (triangles with two boundary edges: one dual neighbour) are removed first and put
back next to their neighbour, as in the proof; the walk is cut open at its longest
tour edge, split wherever it turns back over the edge it came in by, and each piece is
sent as a GL strip with a swap wherever two turns go the same way; the pieces are
stitched (or restarted).  Redrawn triangles at the ends of pieces are dropped.

The result records ``m'`` and checks the theorem's bound against a lower bound of the
optimum: every encoding sequence of ``m`` triangles has at least ``m + 2`` indices, so
``length <= 9/4 (m + 2)`` implies ``length <= 9/4 |S_opt|``; it is asserted
(:class:`~hammesh.errors.VerificationError`).  Christofides' matching is O(k^3) in pure
Python (about 14 s for 500 triangles), so the default limit is 1000 triangles.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import shortest_path

from hammesh.errors import InvalidOptionError, VerificationError
from hammesh.strips.dual import DualMesh, MeshLike, dual_mesh
from hammesh.strips.gl import RESTART_INDEX, GLStrip, gl_strip, verify_gl_strip

__all__ = ["ChristofidesEncoding", "christofides_walk", "christofides_strip", "MAX_TRIANGLES"]

#: Default size limit of :func:`christofides_strip`.
MAX_TRIANGLES = 1000


@dataclass(frozen=True, eq=False)
class ChristofidesEncoding:
    """Thm 5.3's encoding of a mesh and its figures.

    Attributes
    ----------
    strip : GLStrip
    walk : (m',) int64
        Triangle visits of the expanded Christofides walk(s), ears inserted.
    walk_length : int
        ``m'``.
    n_triangles : int
        ``m``.
    n_ears : int
    lower_bound : int
        ``m + 2``: no encoding sequence is shorter.
    bound : float
        ``9/4 * lower_bound``; ``len(strip.indices) <= bound`` was checked.
    """

    strip: GLStrip
    walk: np.ndarray
    walk_length: int
    n_triangles: int
    n_ears: int
    lower_bound: int
    bound: float

    @property
    def ratio(self) -> float:
        """Encoding length over the lower bound (at most 9/4)."""
        return len(self.strip.indices) / self.lower_bound

    def report(self) -> dict:
        return {
            "triangles": self.n_triangles,
            "walk_length": self.walk_length,
            "ears": self.n_ears,
            "indices": int(len(self.strip.indices)),
            "lower_bound": self.lower_bound,
            "bound_9_4": self.bound,
            "ratio": self.ratio,
        }


def _component_walk(nb: np.ndarray, members: np.ndarray) -> list[int]:
    """Christofides walk of one dual component (``members``: its triangle ids)."""
    import networkx as nx
    from networkx.algorithms.approximation import christofides

    k = len(members)
    if k <= 2:
        return members.tolist()
    deg = (nb[members] >= 0).sum(axis=1)
    is_ear = deg == 1
    core = members[~is_ear]
    ears = members[is_ear]
    local = {int(t): i for i, t in enumerate(core.tolist())}
    rows, cols = [], []
    for i, t in enumerate(core.tolist()):
        for u in nb[t]:
            j = local.get(int(u))
            if j is not None:
                rows.append(i)
                cols.append(j)
    kc = len(core)
    if kc == 1:
        tour = [0]
        pred = None
    else:
        graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(kc, kc)).tocsr()
        dist, pred = shortest_path(graph, unweighted=True, directed=False, return_predecessors=True)
        g = nx.Graph()
        iu, ju = np.triu_indices(kc, 1)
        g.add_weighted_edges_from(zip(iu.tolist(), ju.tolist(), dist[iu, ju].tolist()))
        cycle = christofides(g, weight="weight")  # closed: cycle[0] == cycle[-1]
        tour = cycle[:-1]
        if len(tour) > 1:
            # open the tour at its longest leg
            legs = [dist[tour[i], tour[(i + 1) % len(tour)]] for i in range(len(tour))]
            c = int(np.argmax(legs))
            tour = tour[c + 1 :] + tour[: c + 1]
    walk = [tour[0]]
    for a, b in zip(tour[:-1], tour[1:]):
        seg = []
        x = b
        while x != a:
            seg.append(x)
            x = int(pred[a, x])
        walk.extend(reversed(seg))
    walk = [int(core[i]) for i in walk]
    # ears: at the ends of the walk when their neighbour is there, else visited and left
    for e in ears.tolist():
        u = int(nb[e][nb[e] >= 0][0])
        if walk[-1] == u:
            walk.append(e)
        elif walk[0] == u:
            walk.insert(0, e)
        else:
            i = walk.index(u)
            walk[i + 1 : i + 1] = [e, u]
    return walk


def christofides_walk(dual: DualMesh) -> tuple[np.ndarray, np.ndarray]:
    """Christofides walks of every dual component (Thm 5.3).

    Returns
    -------
    walk : (m',) int64
        Triangle visits, component after component; consecutive visits of a component
        share an edge and every triangle is visited at least once.
    starts : (c + 1,) int64
        Offsets of the components' walks.
    """
    nb = dual.neighbor_triangles
    walks = [_component_walk(nb, np.flatnonzero(dual.component == c)) for c in range(dual.n_components)]
    starts = np.r_[0, np.cumsum([len(w) for w in walks])].astype(np.int64)
    return np.fromiter((t for w in walks for t in w), dtype=np.int64, count=int(starts[-1])), starts


def _split_pieces(walk: np.ndarray, starts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cut walks where they turn back (t, u, t) and trim redraws at the pieces' ends."""
    pieces: list[list[int]] = []
    for a, b in zip(starts[:-1].tolist(), starts[1:].tolist()):
        w = walk[a:b].tolist()
        cur = [w[0]]
        for i in range(1, len(w)):
            if len(cur) >= 2 and w[i] == cur[-2]:
                pieces.append(cur)
                cur = [w[i]]
            else:
                cur.append(w[i])
        pieces.append(cur)
    # trim: a visit is needed only where its triangle is first drawn
    drawn: set[int] = set()
    first_visit: list[list[bool]] = []
    for p in pieces:
        flags = []
        for t in p:
            flags.append(t not in drawn)
            drawn.add(t)
        first_visit.append(flags)
    order: list[int] = []
    offs = [0]
    for p, flags in zip(pieces, first_visit):
        if not any(flags):
            continue
        lo = flags.index(True)
        hi = len(flags) - flags[::-1].index(True)
        order.extend(p[lo:hi])
        offs.append(len(order))
    return np.array(order, dtype=np.int64), np.array(offs, dtype=np.int64)


def christofides_strip(
    mesh: MeshLike,
    *,
    join: str = "stitch",
    restart_index: int | None = RESTART_INDEX,
    max_triangles: int = MAX_TRIANGLES,
) -> ChristofidesEncoding:
    """Thm 5.3's encoding of ``mesh`` as a GL strip buffer, with its bound checked.

    Parameters
    ----------
    mesh : Mesh or HamiltonianMesh
    join : {"stitch", "restart"}
        ``"stitch"`` gives one encoding sequence (the theorem's setting).
    restart_index : int
    max_triangles : int
        Refuse larger meshes (Christofides' matching is cubic).

    Returns
    -------
    ChristofidesEncoding

    Raises
    ------
    InvalidOptionError
        The mesh has more than ``max_triangles`` triangles.
    VerificationError
        The buffer does not decode to the mesh, or is longer than ``9/4 (m + 2)``.
    """
    dual = dual_mesh(mesh)
    m = dual.n_triangles
    if m > max_triangles:
        raise InvalidOptionError(
            f"the Christofides encoding is for meshes of up to {max_triangles} triangles; this one has {m} "
            "(use the greedy encoder, or raise max_triangles)"
        )
    walk, wstarts = christofides_walk(dual)
    order, starts = _split_pieces(walk, wstarts)
    strip = gl_strip(dual.triangles, dual.twin, order, starts, join=join, restart_index=restart_index)
    verify_gl_strip(dual.triangles, strip.indices, strip.restart_index, allow_redraw=True)
    deg = (dual.neighbor_triangles >= 0).sum(axis=1)
    lower = m + 2
    bound = 9 / 4 * lower
    if len(strip.indices) > bound:
        raise VerificationError(
            f"Christofides encoding has {len(strip.indices)} indices, above 9/4 of the lower bound {lower}"
        )
    return ChristofidesEncoding(
        strip=strip,
        walk=walk,
        walk_length=int(len(walk)),
        n_triangles=m,
        n_ears=int((deg == 1).sum()),
        lower_bound=lower,
        bound=bound,
    )
