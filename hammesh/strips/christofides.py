"""Thm 5.3: an encoding sequence at most 9/4 times optimal, via Christofides.

The triangles are the cities, the distance of two triangles is their shortest-path
distance in the dual graph (a metric).  Christofides' heuristic gives a closed tour
within 3/2 of the shortest walk visiting every triangle; expanded along shortest dual
paths it is a walk of ``m'`` triangle visits (``m <= m' <= 2 m``).  Its parts:

* minimum spanning tree: every dual edge has length 1 and every distance is at least
  1, so any spanning tree of the dual graph is one; we take the one through the greedy
  strip cover (:func:`hammesh.strips.encode.greedy_paths`) so that few nodes have odd
  degree (typically 7% of the triangles, against ~40% for a BFS tree);
* minimum-weight perfect matching of the odd nodes: networkx's ``min_weight_matching``
  (exact with integer weights, O(k^3) in pure Python in the number ``k`` of odd nodes)
  on the complete graph of their dual distances;
* Euler circuit (networkx) and shortcutting, as in networkx's ``christofides`` (which
  needs the complete graph of all ``m`` triangles: 4.5 million edges at 3,000).

Ears (triangles with two boundary edges: one dual neighbour) are removed first and put
back next to their neighbour, as in the proof; the walk is cut open at its longest
tour edge, split wherever it turns back over the edge it came in by, and each piece is
sent as a GL strip (in its better direction) with a swap wherever two turns go the same
way; the pieces are stitched (or restarted).  Redrawn triangles at the ends of pieces
are dropped.

Reported with every result: Lemma 5.2's bound.  For a walk of ``m'`` non-empty
triangles some encoding sequence has at most ``m'/2`` empty (degenerate) triangles,
plus two per ear (``e`` ears; the proof's accounting), so it is at most
``3 m'/2 + 2 e + 2`` long.  The lemma is an existence result (its construction is not
in the paper); our buffer's ``empty`` count (swaps, plus four per stitched join) is
reported against ``m'/2 + 2 e`` and is usually far below it (0.3 m' on quality
meshes), but it is not guaranteed: a walk cut into many pieces, stitched, can exceed
it (e.g. 21 > 20 on a 38-triangle Delaunay mesh, three pieces; even one unstitched
walk of a 7-triangle mesh needs 4 swaps > 3.5: docs/strips.md, "Lemma 5.2").

Checked on every result (:class:`~hammesh.errors.VerificationError` otherwise): the
round trip, and Thm 5.3's ``length <= 9/4 (m + 2)``: every encoding sequence of ``m``
triangles has at least ``m + 2`` indices, so this implies ``length <= 9/4 |S_opt|``.

Time: ~1 s at 1,000 triangles and ~3 s at 3,000 on planar quality meshes (the
matching dominates); the default limit is 5,000 triangles.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import shortest_path

from hammesh.errors import InvalidOptionError, VerificationError
from hammesh.strips.dual import DualMesh, MeshLike, dual_mesh
from hammesh.strips.gl import RESTART_INDEX, GLStrip, decode_gl_strip, gl_strip_from_turns, verify_gl_strip

__all__ = ["ChristofidesEncoding", "christofides_walk", "christofides_strip", "MAX_TRIANGLES"]

#: Default size limit of :func:`christofides_strip`.
MAX_TRIANGLES = 5000


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
    drawn : int
        Non-empty triangles the buffer draws (``m`` plus redraws).
    empty : int
        Empty (degenerate) triangles in the buffer: swaps, and stitching.
    empty_bound : float
        Lemma 5.2's ``m'/2 + 2 * n_ears`` (reported, not enforced: see the module).
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
    drawn: int
    empty: int
    empty_bound: float
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
            "drawn": self.drawn,
            "empty": self.empty,
            "empty_bound_5_2": self.empty_bound,
            "within_5_2": self.empty <= self.empty_bound,
            "lower_bound": self.lower_bound,
            "bound_9_4": self.bound,
            "ratio": self.ratio,
        }


def _spanning_tree(nb: np.ndarray, core: np.ndarray, cover: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """A spanning tree of the core's dual graph with few odd-degree nodes, as ``(k - 1, 2)`` local pairs.

    Every dual edge has length 1 and every distance is at least 1, so *any* spanning
    tree of the dual graph is a minimum spanning tree of the metric (Christofides only
    needs an MST).  We take the one through the encoder's path cover: its path edges
    first, then the fewest-odd connectors (end to end, then end to interior), so that
    few nodes have odd degree and the matching is small.
    """
    from scipy.sparse.csgraph import minimum_spanning_tree

    k = len(core)
    local = np.full(len(nb), -1, np.int64)
    local[core] = np.arange(k)
    order, starts = cover
    pos = np.full(len(nb), -1, np.int64)
    pos[order] = np.arange(len(order))
    pid = np.repeat(np.arange(len(starts) - 1), np.diff(starts))
    t = np.repeat(core, 3)
    u = nb[core].reshape(-1)
    keep = (u >= 0) & (t < u)
    t, u = t[keep], u[keep]
    keep = local[u] >= 0
    t, u = t[keep], u[keep]
    on_path = (np.abs(pos[t] - pos[u]) == 1) & (pid[pos[t]] == pid[pos[u]])
    # a path end of the core cover: a core neighbour on its path on at most one side
    path_deg = np.zeros(len(nb), np.int64)
    np.add.at(path_deg, t[on_path], 1)
    np.add.at(path_deg, u[on_path], 1)
    end = path_deg <= 1
    w = np.where(on_path, 1.0, 5.0 - end[t] - end[u])  # 1 path, 3 end-end, 4 end-interior, 5
    tree = minimum_spanning_tree(coo_matrix((w, (local[t], local[u])), shape=(k, k))).tocoo()
    return np.c_[tree.row, tree.col].astype(np.int64)


def _component_walk(nb: np.ndarray, members: np.ndarray, cover: tuple[np.ndarray, np.ndarray]) -> list[int]:
    """Christofides walk of one dual component (``members``: its triangle ids).

    MST (:func:`_spanning_tree`) + networkx's exact minimum-weight perfect matching of
    its odd-degree nodes under the dual shortest-path distance (integer weights, so
    exact) + Euler circuit + shortcutting, as in Christofides' heuristic; each leg of
    the tour is then expanded along a shortest dual path.
    """
    import networkx as nx

    k = len(members)
    if k <= 2:
        return members.tolist()
    deg = (nb[members] >= 0).sum(axis=1)
    is_ear = deg == 1
    core = members[~is_ear]
    ears = members[is_ear]
    kc = len(core)
    if kc == 1:
        walk = [int(core[0])]
    else:
        local = {int(t): i for i, t in enumerate(core.tolist())}
        rows = [local[int(t)] for t in np.repeat(core, 3)]
        cols = [local.get(int(u), -1) for u in nb[core].reshape(-1)]
        rc = np.array([(r, c) for r, c in zip(rows, cols) if c >= 0], dtype=np.int64)
        graph = coo_matrix((np.ones(len(rc)), (rc[:, 0], rc[:, 1])), shape=(kc, kc)).tocsr()
        tree = _spanning_tree(nb, core, cover)
        tdeg = np.bincount(tree.reshape(-1), minlength=kc)
        odd = np.flatnonzero(tdeg % 2 == 1)
        multi = nx.MultiGraph()
        multi.add_nodes_from(range(kc))
        multi.add_edges_from(tree.tolist())
        if len(odd):
            dist = shortest_path(graph, unweighted=True, directed=False, indices=odd).astype(np.int64)
            g = nx.Graph()
            iu, ju = np.triu_indices(len(odd), 1)
            g.add_weighted_edges_from(zip(odd[iu].tolist(), odd[ju].tolist(), dist[iu, odd[ju]].tolist()))
            multi.add_edges_from(nx.min_weight_matching(g, weight="weight"))
        # shortcutting: the Euler circuit's first visits (Christofides' tour)
        seen = np.zeros(kc, bool)
        tour = []
        for a, _ in nx.eulerian_circuit(multi, source=0):
            if not seen[a]:
                seen[a] = True
                tour.append(a)
        tour = np.array(tour, dtype=np.int64)
        nxt = np.roll(tour, -1)
        adjacent = np.asarray(graph[tour, nxt]).reshape(-1) > 0
        far = np.flatnonzero(~adjacent)
        legs_from = np.unique(tour[far])
        pred = None
        row = {}
        if len(legs_from):
            dist2, pred = shortest_path(
                graph, unweighted=True, directed=False, indices=legs_from, return_predecessors=True
            )
            row = {int(a): i for i, a in enumerate(legs_from.tolist())}
            legs = np.ones(len(tour), np.int64)
            legs[far] = dist2[[row[int(a)] for a in tour[far]], nxt[far]].astype(np.int64)
        else:
            legs = np.ones(len(tour), np.int64)
        # open the closed tour at its longest leg
        c = int(np.argmax(legs))
        tour = np.r_[tour[c + 1 :], tour[: c + 1]]
        walk_local = [int(tour[0])]
        for a, b in zip(tour[:-1].tolist(), tour[1:].tolist()):
            if graph[a, b]:
                walk_local.append(b)
                continue
            seg = []
            x = b
            r = row[a]
            while x != a:
                seg.append(x)
                x = int(pred[r, x])
            walk_local.extend(reversed(seg))
        walk = [int(core[i]) for i in walk_local]
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
    from hammesh.strips.encode import greedy_paths

    nb = dual.neighbor_triangles
    cover = greedy_paths(dual)
    walks = [_component_walk(nb, np.flatnonzero(dual.component == c), cover) for c in range(dual.n_components)]
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
        Refuse larger meshes (the matching is cubic in the odd nodes of the tree).

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
    from hammesh.strips.encode import orient_path_turns

    walk, wstarts = christofides_walk(dual)
    order, starts = _split_pieces(walk, wstarts)
    strip = gl_strip_from_turns(orient_path_turns(dual, order, starts), join=join, restart_index=restart_index)
    verify_gl_strip(dual.triangles, strip.indices, strip.restart_index, allow_redraw=True)
    deg = (dual.neighbor_triangles >= 0).sum(axis=1)
    size = np.bincount(dual.component)
    n_ears = int(((deg == 1) & (size[dual.component] > 2)).sum())  # removed and re-inserted
    drawn = len(decode_gl_strip(strip.indices, strip.restart_index))
    S = strip.n_strips
    L = len(strip.indices)
    windows = L - 2 if strip.restart_index is None else L - (S - 1) - 2 * S
    empty = windows - drawn
    empty_bound = len(walk) / 2 + 2 * n_ears
    lower = m + 2
    bound = 9 / 4 * lower
    if L > bound:
        raise VerificationError(f"Christofides encoding has {L} indices, above 9/4 of the lower bound {lower}")
    return ChristofidesEncoding(
        strip=strip,
        walk=walk,
        walk_length=int(len(walk)),
        n_triangles=m,
        n_ears=n_ears,
        drawn=int(drawn),
        empty=int(empty),
        empty_bound=float(empty_bound),
        lower_bound=lower,
        bound=bound,
    )
