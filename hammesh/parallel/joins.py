"""Per-tile Hamiltonian cycles joined across separators into one cycle per piece (issue 15).

Each tile's cycles are built alone (:func:`hammesh.hamiltonian` on the tile's mesh,
certified against it). Two cycles of adjacent tiles are then joined across one
separator edge ``ab`` by Thm 2.4's bridge (Arkin, Held, Mitchell, Skiena, proof of
Thm 2.4, Fig. 9): the two triangles ``t = abc`` and ``u = bad`` on either side are split
at their incenters ``I_t, I_u`` and ``ab`` is flipped into ``I_t I_u``; the cycle that
passed ``... - t - ...`` now runs

    [ca side] - I_t c a - I_t a I_u - I_u a d - [u's whole cycle] - I_u d b - I_u b I_t - I_t b c - [bc side]

The proof is local (each incenter sees ``ab`` under more than 90 degrees, so the flip is
legal, and no new angle is below half an angle of ``t`` or ``u``), so it holds in the
union of two tiles as in one mesh. Bridges are used only between triangles both tiles
kept whole (``kind`` 3: input triangles of their tile), so every new angle is at least
half the union's input minimum, as the certificate requires. One bridge per edge of a
spanning forest of the graph whose nodes are the tiles' cycles (Kruskal, best pair of
triangles first) leaves one cycle per connected piece of the domain.

The global cycle order is planned by the driver from small per-tile summaries
(:func:`border_rows`): a list of blocks (runs of a tile's cycle, walked forward or
backward, and single join triangles) whose lengths give every block its place; each
tile then numbers its own rows (:func:`finish_tile`) without the others' triangles.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hammesh.errors import VerificationError
from hammesh.mesh import HamiltonianMesh
from hammesh.parallel._kernels import area_sum, edges_within_into
from hammesh.parallel.markers import point_markers
from hammesh.parallel.tiles import Tile

__all__ = ["BorderRows", "Join", "Plan", "border_rows", "plan_joins", "finish_tile", "TilePiece", "KIND_INPUT",
           "PieceLayout", "piece_layout", "piece_parent", "CHUNK_ROWS"]

#: ``HamiltonianMesh.kind`` of a triangle kept whole
KIND_INPUT = 3
#: a swap's new angles must exceed half the input's minimum by this factor
SWAP_MARGIN = 1e-6
#: join triangle names, in forward cycle order (t side, u side, t side)
T_NAMES = ("S_ca", "F_a", "F_b", "S_bc", "A1", "A2")
U_NAMES = ("S_ad", "S_db")


@dataclass(frozen=True, eq=False)
class BorderRows:
    """A tile's output triangles on its separator edges (small: one row per edge).

    For each: the directed separator edge ``x -> y`` as the triangle has it
    (counter-clockwise), global ids; the apex ``z`` (local id in the tile's output);
    the row, its run, position and run length; the positions of the run neighbours
    sharing edge ``y-z`` (*after*) and ``z-x`` (*before*) (-1: none); the kind; the
    three corners' coordinates ``x, y, z``; the smallest angle (degrees).
    """

    tile: int
    x: np.ndarray
    y: np.ndarray
    z_local: np.ndarray
    row: np.ndarray
    run: np.ndarray
    pos: np.ndarray
    run_length: np.ndarray
    after: np.ndarray
    before: np.ndarray
    kind: np.ndarray
    xyz: np.ndarray
    min_angle: np.ndarray
    run_starts: np.ndarray
    n_points: int
    n_triangles: int
    input_min_angle: float = 0.0
    area: float = 0.0
    #: the apex's vertex marker from the tile's constrained edges (largest nonzero marker
    #: of one ending there, else 0): a swap's apex is the other piece's point too
    z_mark: np.ndarray | None = None


def _min_angle_deg(p: np.ndarray) -> np.ndarray:
    """Smallest angle of triangles given as corners ``(m, 3, 2)``."""
    e = [p[:, (k + 1) % 3] - p[:, k] for k in range(3)]
    out = np.full(len(p), np.inf)
    for k in range(3):
        u, v = e[k], -e[(k + 2) % 3]
        cos = (u * v).sum(1) / np.maximum(np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1), 1e-300)
        out = np.minimum(out, np.degrees(np.arccos(np.clip(cos, -1, 1))))
    return out


def border_rows(h: HamiltonianMesh, tile: Tile, tile_index: int) -> BorderRows:
    """The rows of a tile's Hamiltonian output that hold its separator edges."""
    k = len(tile.vertex_ids)
    sep = tile.segments[tile.separator]
    n = len(h.points)
    key_sep = np.sort(sep, axis=1) @ np.array([n, 1])
    tri = np.ascontiguousarray(h.triangles, dtype=np.int64)
    # separator ends are the tile's own points: the edges between two of them, then
    # those that are separator edges
    cap = 6 * k + 6  # (a planar graph's edges, each in two rows at most)
    rows, slot = np.empty(cap, np.int64), np.empty(cap, np.int64)
    near = edges_within_into(tri, k, rows, slot)
    if near > cap:  # (not planar: then count first)
        rows, slot = np.empty(near, np.int64), np.empty(near, np.int64)
        edges_within_into(tri, k, rows, slot)
    by_slot = np.argsort(slot[:near], kind="stable")  # slot by slot, rows ascending
    rows, slot = rows[by_slot], slot[by_slot]
    a, b = tri[rows, slot], tri[rows, (slot + 1) % 3]
    hit = np.isin(np.minimum(a, b) * n + np.maximum(a, b), key_sep)
    rows, slot = rows[hit], slot[hit]
    x = tri[rows, slot]
    y = tri[rows, (slot + 1) % 3]
    z = tri[rows, (slot + 2) % 3]
    if (x >= k).any() or (y >= k).any():
        raise VerificationError(f"tile {tile_index}: a separator edge was split by the Hamiltonian construction")
    ends = np.cumsum(h.components)
    starts = ends - h.components
    run = np.searchsorted(ends, rows, side="right")
    pos = rows - starts[run]
    L = h.components[run]
    prev = starts[run] + (pos - 1) % L
    nxt = starts[run] + (pos + 1) % L

    def has(rr, u, v):
        t = tri[rr]
        return (t == u[:, None]).any(1) & (t == v[:, None]).any(1)

    after = np.where(has(nxt, y, z) & (L > 1), (pos + 1) % L, np.where(has(prev, y, z) & (L > 1), (pos - 1) % L, -1))
    before = np.where(has(nxt, z, x) & (L > 1), (pos + 1) % L, np.where(has(prev, z, x) & (L > 1), (pos - 1) % L, -1))
    xyz = np.stack([h.points[x], h.points[y], h.points[z]], axis=1)
    return BorderRows(
        tile=tile_index, x=tile.vertex_ids[x], y=tile.vertex_ids[y], z_local=z, row=rows, run=run, pos=pos,
        run_length=L, after=after, before=before, kind=np.asarray(h.kind)[rows], xyz=xyz,
        min_angle=_min_angle_deg(xyz), run_starts=starts, n_points=n, n_triangles=len(tri),
        input_min_angle=float(h.report.get("min_angle_input_deg", 0.0)),
        z_mark=point_markers(n, h.segments, h.segment_markers, (np.zeros(0, np.int64), np.zeros(0, np.int64)))[z],
        area=float(area_sum(np.ascontiguousarray(h.points, dtype=np.float64),
                            np.ascontiguousarray(h.triangles, dtype=np.int64))),
    )


@dataclass(frozen=True)
class Join:
    """One bridge: tile ``t_tile`` row ``t_row`` (``a b c``) and ``u_tile`` row ``u_row`` (``b a d``)."""

    index: int
    t_tile: int
    t_row: int
    u_tile: int
    u_row: int
    a: int  # global ids of the separator edge, a -> b counter-clockwise in t
    b: int
    I_t: tuple[float, float]
    I_u: tuple[float, float]
    swap: bool = False  # flip ab into cd (no Steiner point) instead of a bridge
    slot: int = -1  # a bridge's incenters are join points 2 slot and 2 slot + 1


@dataclass(frozen=True, eq=False)
class Plan:
    """The joins and the global cycle order, as blocks.

    ``blocks``: ``(tile, "run", run, start, step, count)`` or ``(tile, "tri", join, name)``
    in cycle order; ``start`` (global position of each block); ``components``: the
    number of triangles of each cycle (one per piece); ``join_point_base``: global id of
    the first join point (join ``j`` adds ``base + 2 j`` = ``I_t`` and ``base + 2 j + 1``).
    """

    joins: tuple[Join, ...]
    blocks: list
    start: np.ndarray
    components: np.ndarray
    join_point_base: int
    nodes: int
    pieces: int
    fallback_joins: int = 0


def _incenter(p: np.ndarray) -> tuple[float, float]:
    la = np.linalg.norm(p[2] - p[1])
    lb = np.linalg.norm(p[0] - p[2])
    lc = np.linalg.norm(p[1] - p[0])
    c = (la * p[0] + lb * p[1] + lc * p[2]) / (la + lb + lc)
    return float(c[0]), float(c[1])


class _UF:
    def __init__(self, n: int) -> None:
        self.p = list(range(n))

    def find(self, a: int) -> int:
        while self.p[a] != a:
            self.p[a] = self.p[self.p[a]]
            a = self.p[a]
        return a

    def union(self, a: int, b: int) -> bool:
        a, b = self.find(a), self.find(b)
        if a == b:
            return False
        self.p[a] = b
        return True


def _swap_min_angles(t_xyz: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Smallest angle of ``adc, dbc`` after flipping ``ab`` of each ``t = abc``,
    ``u = bad`` (``t_xyz (p, 3, 2)``, ``d (p, 2)``); 0 where ``acbd`` is not strictly
    convex (the flip is not legal)."""
    a, b, c = t_xyz[:, 0], t_xyz[:, 1], t_xyz[:, 2]

    def cross(o, p, q):
        return (p[:, 0] - o[:, 0]) * (q[:, 1] - o[:, 1]) - (p[:, 1] - o[:, 1]) * (q[:, 0] - o[:, 0])

    ca, cb = cross(c, d, a), cross(c, d, b)
    legal = ((ca < 0) & (0 < cb)) | ((cb < 0) & (0 < ca))
    if len(a) == 0:
        return np.zeros(0)
    tris = np.stack([np.stack([a, d, c], 1), np.stack([d, b, c], 1)], 1).reshape(-1, 3, 2)
    low = _min_angle_deg(tris).reshape(-1, 2).min(axis=1)
    return np.where(legal, low, 0.0)


def _incenters(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Incenters of the triangles ``abc`` (each corner weighted by its opposite side)."""
    la = np.hypot(*(c - b).T)[:, None]
    lb = np.hypot(*(a - c).T)[:, None]
    lc = np.hypot(*(b - a).T)[:, None]
    return (la * a + lb * b + lc * c) / (la + lb + lc)


def _bridge_min_angles(t_xyz: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Smallest angle of the six triangles Thm 2.4's bridge makes over ``ab`` of each
    ``t = abc``, ``u = bad`` (``t_xyz (p, 3, 2)``, ``d (p, 2)``; the module notes name
    them): at least half of ``t``'s and ``u``'s smallest (the proof), often more, so the
    bridges are ranked by what they make, not by their parents."""
    if len(t_xyz) == 0:
        return np.zeros(0)
    a, b, c = t_xyz[:, 0], t_xyz[:, 1], t_xyz[:, 2]
    it, iu = _incenters(a, b, c), _incenters(b, a, d)
    tris = np.stack([np.stack(corners, 1) for corners in
                     ((it, c, a), (it, a, iu), (iu, a, d), (iu, d, b), (iu, b, it), (it, b, c))], 1)
    return _min_angle_deg(tris.reshape(-1, 3, 2)).reshape(-1, 6).min(axis=1)


def plan_joins(borders: list[BorderRows], n_decomposition_points: int, keep: float = 0.9,
               n_separators: int | None = None) -> Plan:
    """Choose the joins (Kruskal over the tiles' cycles) and the global cycle order.

    Best first: a *swap* (flip ``ab`` into ``cd``, no Steiner point, the sparse mode's
    join) whose new angles meet the local quality rule (>= ``keep`` x the two
    triangles' smallest); then, by the smallest angle they make, Thm 2.4's bridges
    between triangles kept whole (proven: >= half their angles) and swaps keeping half
    the input's minimum (before session 13 every such bridge went first, ranked by its
    parents: the demo's two tiles were joined by a bridge making 20.4 deg); last a
    bridge of other triangles (only the certificate vouches for those; counted in the
    report).
    """
    floor = 0.5 * min((b.input_min_angle for b in borders), default=0.0)
    # nodes: (tile, run)
    node_base = np.concatenate([[0], np.cumsum([len(b.run_starts) for b in borders])]).astype(np.int64)
    n_nodes = int(node_base[-1])
    run_len = np.concatenate([np.diff(np.concatenate([b.run_starts, [b.n_triangles]])) for b in borders])
    # match the two sides of every separator edge by its directed key
    ent = []
    for b in borders:
        ent.append(np.stack([np.full(len(b.row), b.tile), np.arange(len(b.row)), b.x, b.y], axis=1))
    ent = np.concatenate(ent) if ent else np.zeros((0, 4), np.int64)
    big = int(max(n_decomposition_points, 1))
    fwd = ent[:, 2] * big + ent[:, 3]
    back = ent[:, 3] * big + ent[:, 2]
    order = np.argsort(fwd)
    where = np.searchsorted(fwd[order], back)
    where = np.minimum(where, len(order) - 1)
    mate = order[where]
    ok = fwd[mate] == back
    if not ok.all() or np.unique(fwd).size != len(fwd):
        i = int(np.flatnonzero(~ok)[0]) if not ok.all() else 0
        raise VerificationError(
            f"separator edge ({int(ent[i, 2])}, {int(ent[i, 3])}) of tile {int(ent[i, 0])} is not the edge of "
            "exactly one triangle of one other tile, opposite: the tiles do not conform")
    if n_separators is not None and len(ent) != 2 * n_separators:
        raise VerificationError(f"{len(ent)} tile triangles hold the {n_separators} separator edges, not two each")
    # every separator edge's two sides, as flat arrays in ``ent`` order
    flat = {f: np.concatenate([getattr(b, f) for b in borders]) if borders else np.zeros(0)
            for f in ("run", "run_length", "after", "before", "kind", "min_angle")}
    xyz = np.concatenate([b.xyz for b in borders]) if borders else np.zeros((0, 3, 2))
    i = np.flatnonzero(ok & (np.arange(len(ent)) < mate))
    j = mate[i]
    ni = node_base[ent[i, 0]] + flat["run"][i].astype(np.int64)
    nj = node_base[ent[j, 0]] + flat["run"][j].astype(np.int64)
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    pieces, _ = connected_components(coo_matrix((np.ones(len(ni)), (ni, nj)), shape=(n_nodes, n_nodes)),
                                     directed=False)
    usable = ((flat["run_length"][i] >= 3) & (flat["run_length"][j] >= 3) & (flat["after"][i] >= 0)
              & (flat["before"][i] >= 0) & (flat["after"][j] >= 0) & (flat["before"][j] >= 0))
    i, j, ni, nj = i[usable], j[usable], ni[usable], nj[usable]
    whole = (flat["kind"][i] == KIND_INPUT) & (flat["kind"][j] == KIND_INPUT)
    parents = np.minimum(flat["min_angle"][i], flat["min_angle"][j])
    new = _swap_min_angles(xyz[i], xyz[j][:, 2])
    bound = floor * (1 + SWAP_MARGIN)
    # 0: a swap meeting the local quality rule (no Steiner point); 1: Thm 2.4's bridge
    # (proven bound); 2: a swap keeping the certificate's bound; 3: a bridge of triangles
    # not kept whole (checked by the certificate only)
    bridged = _bridge_min_angles(xyz[i], xyz[j][:, 2])
    swap_ok = new >= bound
    # 0: a swap meeting the local quality rule (no Steiner point); 1: the better of a swap
    # keeping the certificate's bound and Thm 2.4's bridge of triangles kept whole (its
    # bound proven), by the smallest angle each makes; 3: a bridge of triangles not kept
    # whole (checked by the certificate only)
    rank = np.where(new >= np.maximum(keep * parents, bound), 0, np.where(whole | swap_ok, 1, 3))
    use_swap = (rank == 0) | (swap_ok & (~whole | (new >= bridged)))
    made = np.where(use_swap, new, bridged)
    score = -np.where(rank == 3, parents, made)
    ti, ri, tj, rj = ent[i, 0], ent[i, 1], ent[j, 0], ent[j, 1]
    order = np.lexsort((rj, tj, ri, ti, score, rank))  # best first, ties by tile and row
    uf = _UF(n_nodes)
    used: set[tuple[int, int]] = set()
    chosen = []
    fallback = 0
    swaps = {}
    need = n_nodes - pieces
    for q in order.tolist():
        if len(chosen) == need:
            break
        a_, b_ = (int(ti[q]), int(ri[q])), (int(tj[q]), int(rj[q]))
        if a_ in used or b_ in used:
            continue
        if uf.union(int(ni[q]), int(nj[q])):
            used.add(a_)
            used.add(b_)
            chosen.append((a_[0], a_[1], b_[0], b_[1], int(ni[q]), int(nj[q])))
            swaps[a_] = swaps[b_] = bool(use_swap[q])
            fallback += int(rank[q] == 3)
    if n_nodes - len(chosen) != pieces:
        raise VerificationError(
            f"could not join the tiles' {n_nodes} cycles into {pieces} (one per piece): "
            f"{len(chosen)} joins found")
    # orient the forest: root each tree, the parent side of a join is its t side
    adj: dict[int, list] = {i: [] for i in range(n_nodes)}
    for c in chosen:
        ti, ri, tj, rj, ni, nj = c
        adj[ni].append((nj, (ti, ri, tj, rj)))
        adj[nj].append((ni, (tj, rj, ti, ri)))
    seen = np.zeros(n_nodes, bool)
    joins: list[Join] = []
    children: dict[int, list] = {i: [] for i in range(n_nodes)}  # node -> [(pos, join index, child)]
    roots = []
    for r in range(n_nodes):
        if seen[r]:
            continue
        roots.append(r)
        seen[r] = True
        stack = [r]
        while stack:
            v = stack.pop()
            for w, (tt, rt, tu, ru) in adj[v]:
                if seen[w]:
                    continue
                seen[w] = True
                bt, bu = borders[tt], borders[tu]
                a, b = int(bt.x[rt]), int(bt.y[rt])
                j = Join(index=len(joins), t_tile=tt, t_row=int(bt.row[rt]), u_tile=tu, u_row=int(bu.row[ru]),
                         a=a, b=b, I_t=_incenter(bt.xyz[rt]), I_u=_incenter(bu.xyz[ru]), swap=swaps[(tt, rt)],
                         slot=-1 if swaps[(tt, rt)] else sum(not x.swap for x in joins))
                joins.append(j)
                children[v].append((int(bt.pos[rt]), j.index, w, (tt, rt), (tu, ru)))
                stack.append(w)
    # the global order: walk every tree
    node_tile = np.repeat(np.arange(len(borders)), np.diff(node_base))
    node_run = np.arange(n_nodes) - node_base[node_tile]
    blocks: list = []
    components = []

    def walk(node: int, start: int, step: int, count: int) -> None:
        L = int(run_len[node])
        tile = int(node_tile[node])
        here = []
        for pos, ji, child, (tt, rt), (tu, ru) in children[node]:
            k = ((pos - start) * step) % L
            if k < count:
                here.append((k, pos, ji, child, (tt, rt), (tu, ru)))
        here.sort()
        done = 0
        for k, pos, ji, child, (tt, rt), (tu, ru) in here:
            if k > done:
                blocks.append((tile, "run", int(node_run[node]), (start + step * done) % L, step, k - done))
            bt, bu = borders[tt], borders[tu]
            arrival = (pos - step) % L
            forward = arrival == int(bt.before[rt])
            upos = int(bu.pos[ru])
            Lc = int(run_len[child])
            ua, ub = int(bu.after[ru]), int(bu.before[ru])
            if joins[ji].swap:  # [ca] - adc - [u's cycle from ad to db] - dbc - [bc]
                seq_a, seq_b = (("A1",), ("A2",)) if forward else (("A2",), ("A1",))
                u_first = u_last = None
            elif forward:
                seq_a, seq_b = ("S_ca", "F_a"), ("F_b", "S_bc")
                u_first, u_last = "S_ad", "S_db"
            else:
                seq_a, seq_b = ("S_bc", "F_b"), ("F_a", "S_ca")
                u_first, u_last = "S_db", "S_ad"
            enter = ua if forward else ub
            for name in seq_a:
                blocks.append((tt, "tri", ji, name))
            if u_first:
                blocks.append((tu, "tri", ji, u_first))
            cstep = 1 if enter == (upos + 1) % Lc else -1
            walk(child, enter, cstep, Lc - 1)
            if u_last:
                blocks.append((tu, "tri", ji, u_last))
            for name in seq_b:
                blocks.append((tt, "tri", ji, name))
            done = k + 1
        if count > done:
            blocks.append((tile, "run", int(node_run[node]), (start + step * done) % L, step, count - done))

    import sys

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 4 * n_nodes + 100))
    for r in roots:
        first = len(blocks)
        walk(r, 0, 1, int(run_len[r]))
        sizes = [_block_size(bk) for bk in blocks[first:]]
        components.append(int(sum(sizes)))
    sizes = np.array([_block_size(bk) for bk in blocks], dtype=np.int64)
    start = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
    return Plan(joins=tuple(joins), blocks=blocks, start=start, components=np.array(components, np.int64),
                join_point_base=0, nodes=n_nodes, pieces=pieces, fallback_joins=fallback)


def _block_size(bk) -> int:
    return int(bk[5]) if bk[1] == "run" else 1


def _check_join_triangles(tri, gid, points, joins, base, apex, floor, tile_index) -> None:
    """Every triangle a join made: counter-clockwise by the exact predicate, every angle
    at least ``floor`` degrees (half the input's minimum) up to rounding."""
    from hammesh.predicates import orient_many

    need = set(np.unique(tri).tolist())
    pos = np.flatnonzero(np.isin(gid, np.fromiter(need, np.int64, len(need))))
    coords = {int(gid[i]): points[i] for i in pos.tolist()}
    for j in joins:
        if j.slot >= 0:
            coords[base + 2 * j.slot] = np.array(j.I_t)
            coords[base + 2 * j.slot + 1] = np.array(j.I_u)
    for ji, (g, xy) in (apex or {}).items():
        coords[int(g)] = np.asarray(xy, dtype=np.float64)
    ids = np.unique(tri)
    pts = np.array([coords[int(i)] for i in ids.tolist()])
    local = np.searchsorted(ids, tri)
    if (orient_many(np.ascontiguousarray(pts), np.ascontiguousarray(local)) <= 0).any():
        raise VerificationError(f"tile {tile_index}: a join triangle is not counter-clockwise")
    low = _min_angle_deg(pts[local]).min()
    if low < floor * (1 - 1e-6):  # Thm 2.4 is tight: half an angle, up to rounding
        raise VerificationError(f"tile {tile_index}: a join triangle has an angle {low:.6f} < {floor:.6f} deg")


@dataclass(frozen=True, eq=False)
class TilePiece:
    """One tile's share of the output, rows in cycle order.

    ``point_ids`` / ``points``: the global id and coordinates of the points its
    triangles use; ``triangles``: rows of indices into them (``point_ids[triangles]`` in
    global numbering); ``position``: the global cycle position of each row.
    """

    tile: int
    point_ids: np.ndarray
    points: np.ndarray
    triangles: np.ndarray
    position: np.ndarray
    kind: np.ndarray
    parent: np.ndarray
    triangle_attributes: np.ndarray
    segments: np.ndarray
    segment_markers: np.ndarray


#: rows per chunk when a piece is copied or written chunk by chunk (a few MB: the
#: allocator reuses the buffer, so no fresh page is faulted per chunk)
CHUNK_ROWS = 1 << 18


@dataclass(frozen=True, eq=False)
class PieceLayout:
    """One tile's share of the output as a plan over its Hamiltonian mesh's rows: which
    rows, in which order, and the joins' few new rows, with no row copied yet.

    ``items``: in cycle order, ``(position, lo, count, step)``: the tile's rows ``lo,
    lo + step, ...`` (``count`` of them, ``step`` +1 or -1) at global positions
    ``position ...``; a join row ``k`` is ``(position, -1 - k, 1, 0)``. Point ``i`` of the
    piece's point list (``point_ids``) is the tile's point ``i`` for ``i < n_own``, then
    the join points (``join_points``); ``keep`` (None: all) marks the points some row
    uses, when not all are. ``join_*``: the join rows' corners (indices into the point
    list, before dropping the unused), kind, parent (global), attributes;
    ``triangle_offset``: the tile's first triangle in the global parent numbering.
    :meth:`chunks` walks the rows in order, :meth:`take` gathers an array by them.
    """

    tile: int
    items: tuple
    n_rows: int
    n_own: int
    point_ids: np.ndarray
    join_points: np.ndarray
    keep: np.ndarray | None
    triangle_offset: int
    join_triangles: np.ndarray
    join_kind: np.ndarray
    join_parent: np.ndarray
    join_attributes: np.ndarray
    segments: np.ndarray
    segment_markers: np.ndarray
    #: ``segments`` as indices into the piece's point list (before dropping the unused)
    local_segments: np.ndarray | None = None

    def chunks(self, chunk: int = CHUNK_ROWS):
        """``(position, rows)`` in cycle order: ``rows`` a slice of the tile's rows (at
        most ``chunk``, step +-1) or an int ``k`` (join row ``k``, one row)."""
        for g, lo, count, step in self.items:
            if lo < 0:
                yield g, -1 - lo
                continue
            for a in range(0, count, chunk):
                c = min(chunk, count - a)
                s = lo + step * a
                yield g + a, (slice(s, s + c) if step == 1 else slice(s, s - c if s >= c else None, -1))

    def take(self, values: np.ndarray, joins: np.ndarray) -> np.ndarray:
        """``values`` (one row per tile row) in the piece's row order, ``joins[k]`` for join row ``k``."""
        parts = [values[r] if isinstance(r, slice) else joins[r:r + 1] for _, r in self.chunks(1 << 62)]
        if not parts:
            return np.zeros((0, *values.shape[1:]), values.dtype)
        return np.concatenate(parts).astype(values.dtype, copy=False)

    def positions(self) -> np.ndarray:
        """The global position of each row of the piece."""
        return np.concatenate([g + np.arange(c, dtype=np.int64) for g, _, c, _ in self.items]) \
            if self.items else np.zeros(0, np.int64)


def piece_layout(h: HamiltonianMesh, tile: Tile, tile_index: int, plan_blocks: list, plan_start: np.ndarray,
                 joins: list[Join], mesh_offset: int, n_mesh_points: int, ham_offset: int, join_point_base: int,
                 triangle_offset: int, separator_keys: np.ndarray, n_global: int,
                 swap_apex: dict | None = None, floor: float = 0.0) -> PieceLayout:
    """Where a tile's rows go in the global cycle and what its side of the joins adds
    (:class:`PieceLayout`), checked: the plan's runs and the joins cover every row of
    the tile exactly once but the ones its joins replace, and every join triangle is
    counter-clockwise with angles >= ``floor``. Arguments as :func:`finish_tile`.
    """
    k = len(tile.vertex_ids)
    n = len(h.points)
    gid = np.concatenate([tile.vertex_ids, mesh_offset + np.arange(n_mesh_points - k, dtype=np.int64),
                          ham_offset + np.arange(n - n_mesh_points, dtype=np.int64)])
    m = len(h.triangles)
    ends = np.cumsum(h.components)
    starts = ends - h.components
    new_tri, new_kind, new_parent, new_attr = [], [], [], []
    jmap = {j.index: j for j in joins}
    # a swap's far apex d: (global id, coordinates), from the other tile via the driver
    h_other_apex = {ji: int(v[0]) for ji, v in (swap_apex or {}).items()}
    attrs = np.asarray(h.triangle_attributes)
    # the rows in cycle order, block by block (the blocks' positions are consecutive
    # stretches): a run of a cycle (at most two stretches of rows, forward or
    # backward: no index array, no sort), or a join triangle
    mine = sorted((g, i) for i, (bk, g) in enumerate(zip(plan_blocks, plan_start.tolist())) if bk[0] == tile_index)
    items, spans = [], []
    for g, i in mine:
        bk = plan_blocks[i]
        if bk[1] == "run":
            _, _, run, start, step, count = bk
            L, s0 = int(h.components[run]), int(starts[run])
            if step not in (1, -1) or not (0 <= start < L) or not (0 <= count <= L):
                raise VerificationError(f"tile {tile_index}: a block of the cycle plan is not a run of its cycle")
            first = min(count, L - start) if step == 1 else min(count, start + 1)
            for at, lo, c in ((0, s0 + start, first), (first, s0 + (0 if step == 1 else L - 1), count - first)):
                if c > 0:
                    items.append((g + at, lo, c, step))
                    spans.append((lo, lo + c) if step == 1 else (lo - c + 1, lo + 1))
            continue
        _, _, ji, name = bk
        j = jmap[ji]
        It, Iu = join_point_base + 2 * j.slot, join_point_base + 2 * j.slot + 1
        if name in T_NAMES:
            row = j.t_row
            t = h.triangles[row]
            c = int(gid[[v for v in t if int(gid[v]) not in (j.a, j.b)][0]])
            if name in ("A1", "A2"):
                u = h_other_apex[j.index]
                tri = (j.a, u, c) if name == "A1" else (u, j.b, c)
            else:
                tri = {"S_ca": (It, c, j.a), "F_a": (It, j.a, Iu), "F_b": (Iu, j.b, It), "S_bc": (It, j.b, c)}[name]
        else:
            row = j.u_row
            t = h.triangles[row]
            d = int(gid[[v for v in t if int(gid[v]) not in (j.a, j.b)][0]])
            tri = {"S_ad": (Iu, j.a, d), "S_db": (Iu, d, j.b)}[name]
        items.append((g, -1 - len(new_tri), 1, 0))
        new_tri.append(tri)
        new_kind.append(4 if name in ("A1", "A2") else (1 if name in ("F_a", "F_b") else 0))
        new_parent.append(triangle_offset + int(h.parent[row]) if h.parent[row] >= 0 else -1)
        new_attr.append(attrs[row] if attrs.shape[1] else np.zeros(0))
    if new_tri:
        _check_join_triangles(np.asarray(new_tri, np.int64), gid, h.points, joins, join_point_base, swap_apex,
                              floor, tile_index)
    # every row of the tile exactly once, but the ones its joins replace: the runs'
    # stretches and those rows tile 0..m-1 without gap or overlap
    removed = set()
    for j in joins:
        if j.t_tile == tile_index:
            removed.add(j.t_row)
        if j.u_tile == tile_index:
            removed.add(j.u_row)
    cover = sorted(spans + [(r, r + 1) for r in removed])
    at = 0
    for lo, hi in cover:
        if lo != at:
            raise VerificationError(f"tile {tile_index}: the cycle plan does not cover its rows")
        at = hi
    if at != m:
        raise VerificationError(f"tile {tile_index}: the cycle plan does not cover its rows")
    # the points this piece uses: its own and the join points (a swap's apex d is the
    # other tile's point: added unless this tile holds it too)
    jp_ids, jp_xy = [], []
    for j in joins:
        if j.swap:
            if j.t_tile == tile_index:
                gid_d, xy_d = swap_apex[j.index]
                jp_ids.append(int(gid_d))
                jp_xy.append(tuple(xy_d))
            continue
        jp_ids += [join_point_base + 2 * j.slot, join_point_base + 2 * j.slot + 1]
        jp_xy += [j.I_t, j.I_u]
    jp_ids_a = np.asarray(jp_ids, np.int64)
    # a swap's apex may be a prescribed point this tile holds too (its sorted vertex_ids)
    at_v = np.minimum(np.searchsorted(tile.vertex_ids, jp_ids_a), max(k - 1, 0))
    fresh = ~((tile.vertex_ids[at_v] == jp_ids_a) if k else np.zeros(len(jp_ids_a), bool))
    ids = np.concatenate([gid, jp_ids_a[fresh]])
    jxy = np.asarray(jp_xy, np.float64).reshape(-1, 2)[fresh]
    nt = np.asarray(new_tri, np.int64).reshape(-1, 3)
    if len(nt):
        want = np.unique(nt)
        # few: the join triangles' corners (a search in those few, not np.isin's pass
        # sorting the piece's ~1.5M ids: ~25 ms of an incircle piece's finish)
        at_w = np.minimum(np.searchsorted(want, ids), len(want) - 1)
        hold = np.flatnonzero(want[at_w] == ids)
        order_at = np.argsort(ids[hold])
        nt = hold[order_at][np.searchsorted(ids[hold][order_at], nt)]
    # which points the rows use: the tile's (counted over its rows, less the replaced
    # ones) and the join rows' corners
    uses = np.bincount(np.asarray(h.triangles).ravel(), minlength=n) if m else np.zeros(n, np.int64)
    if removed:
        np.subtract.at(uses, np.asarray(h.triangles)[sorted(removed)].ravel(), 1)
    used = np.zeros(len(ids), bool)
    used[:n] = uses > 0
    used[nt.ravel()] = True
    # constrained edges: the tile's, minus its separators (interior edges of the union)
    segs = gid[h.segments]
    keys = np.sort(segs, axis=1) @ np.array([n_global, 1])
    keep_s = ~np.isin(keys, separator_keys)
    width = attrs.shape[1] if attrs.ndim == 2 else 0
    return PieceLayout(tile=tile_index, items=tuple(items), n_rows=m - len(removed) + len(nt), n_own=n,
                       point_ids=ids, join_points=jxy, keep=None if used.all() else used,
                       triangle_offset=int(triangle_offset), join_triangles=nt,
                       join_kind=np.asarray(new_kind, np.int8), join_parent=np.asarray(new_parent, np.int64),
                       join_attributes=np.asarray(new_attr, np.float64).reshape(len(nt), width),
                       segments=segs[keep_s], segment_markers=np.asarray(h.segment_markers)[keep_s],
                       local_segments=np.asarray(h.segments, np.int64)[keep_s])


def piece_parent(parent: np.ndarray, triangle_offset: int) -> np.ndarray:
    """A tile's ``parent`` rows in global numbering (-1, no parent, stays -1)."""
    out = np.asarray(parent, dtype=np.int64) + triangle_offset
    out[out < triangle_offset] = -1
    return out


def finish_tile(h: HamiltonianMesh, tile: Tile, tile_index: int, plan_blocks: list, plan_start: np.ndarray,
                joins: list[Join], mesh_offset: int, n_mesh_points: int, ham_offset: int, join_point_base: int,
                triangle_offset: int, separator_keys: np.ndarray, n_global: int,
                swap_apex: dict | None = None, floor: float = 0.0) -> TilePiece:
    """Number a tile's rows and points globally and apply its side of the joins.

    Global points: the decomposition's, then every tile's mesh Steiner points (tile
    ``i``'s from ``mesh_offset``), then every tile's Hamiltonian Steiner points (from
    ``ham_offset``), then the join points (``join_point_base``): so the union of the
    tile meshes is a prefix of the output, as the certificate wants its input.
    (:func:`piece_layout`, gathered; the partitioned output writes the layout chunk
    by chunk instead.)
    """
    lay = piece_layout(h, tile, tile_index, plan_blocks, plan_start, joins, mesh_offset, n_mesh_points, ham_offset,
                       join_point_base, triangle_offset, separator_keys, n_global, swap_apex, floor)
    local = lay.take(np.asarray(h.triangles, dtype=np.int64), lay.join_triangles)
    ids = lay.point_ids
    xy = np.concatenate([np.asarray(h.points, dtype=np.float64), lay.join_points])
    if lay.keep is not None:  # (a join's corner points are new; the tile's own all used, as a rule)
        local = (np.cumsum(lay.keep) - 1)[local]
        ids, xy = ids[lay.keep], xy[lay.keep]
    attrs = np.asarray(h.triangle_attributes)
    attrs = attrs.reshape(len(attrs), lay.join_attributes.shape[1])
    return TilePiece(tile=tile_index, point_ids=ids, points=xy, triangles=local, position=lay.positions(),
                     kind=lay.take(np.asarray(h.kind).astype(np.int8, copy=False), lay.join_kind),
                     parent=lay.take(piece_parent(h.parent, triangle_offset), lay.join_parent),
                     triangle_attributes=lay.take(attrs, lay.join_attributes),
                     segments=lay.segments, segment_markers=lay.segment_markers)
