"""Ceilings for sparse mode's compact cycle (issue 14, session 15): what would a sparse
cycle cut if it followed a sweep already known to be compact?

Sparse mode's output is Triangle's mesh with a few Steiner points (0.3 %), so what a
sparse cycle can cut is bounded by how compact an order of Triangle's triangles can
be. Each function here makes one such order (or partition) on the *input* mesh, from
which the cut of its ``k`` stretches is measured against METIS's on the same graph
(``bench_partition.py --ceilings``):

* :func:`walk_positions`: the incircle cycle on the same mesh (which meets the target
  on its own, three times finer, mesh) projected onto the input triangles: each input
  triangle at the first or the median position of its rows in the walk;
* :func:`projected_parts`: incircle's ``k`` parts themselves projected, each input
  triangle to the part holding most of its rows, then smoothed (a triangle with two
  neighbours in another part moves there): what a cycle following incircle's
  *regions* (not its order) could cut; neither balanced exactly nor always connected;
* :func:`kd_order`: recursive median bisection of the centroids across the longer
  side (the stretches at ``k = 2^j`` are its cells; a control, with no cycle at all);
* :func:`vertex_tree_cover`: a different construction of one cycle, no joins at all:
  the walk around an *induced tree* of interior vertices (the cycle passes through
  every triangle with vertices on both sides: Thm 2.4's walk around a tree, one level
  down, on the vertices). Grown by Prim's search in the count quadtree's classes
  (``_thm24_kernels.edge_class`` on the vertices), a vertex joins when exactly one of
  its neighbours is in the tree; triangles with no tree vertex stay uncovered.

Session 16 ("a ring of compact blocks"): the final cycle as a *ring* of compact
blocks, each walked as a Hamiltonian path from a triangle next to the previous block
to one next to the next block (no join tree, so no block in two runs):

* :func:`curve_order`: the triangles along a generalized Hilbert curve through the
  domain's bounding box (a closed space-filling order of compact cells);
* :func:`sweep_blocks`: each block walked as a sweep, breadth-first from its triangles
  next to the previous block (the ideal path: what a block's path could cut at best);
* :func:`block_cycles` / :func:`ring_order`: each block walked by *its own sparse
  cycle* (sparse mode on the block alone), opened where it enters from the previous
  block; and how many blocks could be spliced into the ring with no Steiner point (an
  entry triangle next to the previous block adjacent, along the block's cycle, to an
  exit triangle next to the next one);
* :func:`cover_cycle_order`: one cycle of a cycle cover walked (the default cover's
  largest cycle holds 87-88 % of the triangles: its stretches are what the sparse
  cycle cuts).

These are measurements, not constructions sparse mode uses (docs/partition.md,
"Session 15: ceilings", "Session 16: a ring of compact blocks").
"""

from __future__ import annotations

import heapq
from typing import NamedTuple

import numpy as np
from numba import njit

from hammesh.partition import edge_cut, part_components
from hammesh.postprocess._thm24_kernels import edge_class, quadtree_coords

__all__ = ["walk_positions", "order_cut", "stretch_parts", "projected_parts", "smooth_parts", "kd_order", "VertexTree",
           "vertex_tree_cover", "dual_neighbours", "gilbert_path", "curve_order", "curve_blocks", "sweep_blocks",
           "BlockCycles", "block_cycles", "ring_order", "cover_cycle_order"]


def dual_neighbours(twin: np.ndarray) -> np.ndarray:
    """(m, 3) int64: the triangle across each side (-1 on the boundary)."""
    return np.where(twin >= 0, twin // 3, -1).reshape(-1, 3)


def walk_positions(parent: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
    """``(first, median)``: for each of ``m`` input triangles the first and the median
    row of the cycle (rows in cycle order, ``parent`` their input triangle) in it."""
    pos = np.arange(len(parent))
    srt = np.lexsort((pos, parent))
    par = parent[srt]
    starts = np.r_[0, np.flatnonzero(np.diff(par)) + 1]
    counts = np.diff(np.r_[starts, len(par)])
    if len(starts) != m:
        raise ValueError("every input triangle must have a row")
    return pos[srt][starts], pos[srt][starts + counts // 2]


def order_cut(order: np.ndarray, k: int, a: np.ndarray, b: np.ndarray, shift: bool = True) -> tuple[int, int]:
    """``(edge cut, parts not connected)`` of :func:`stretch_parts`."""
    part = stretch_parts(order, k, a, b, shift)
    return edge_cut(part, a, b), int((part_components(part, k, a, b) > 1).sum())


def stretch_parts(order: np.ndarray, k: int, a: np.ndarray, b: np.ndarray, shift: bool = True) -> np.ndarray:
    """Part of each triangle when ``order`` (a permutation of the triangles, read as a
    cycle) is cut into ``k`` stretches of ``floor(j m / k)`` ... rows, dual edges
    ``a``-``b``; with ``shift`` the stretches start at the best shift, as
    ``hammesh.partition`` cuts a cycle (same difference-array count: a start in
    ``(x, y]`` cuts an edge whose rows ``x < y`` are at most ``m // k`` apart the
    short way round)."""
    m = len(order)
    pos = np.empty(m, np.int64)
    pos[order] = np.arange(m)
    best = 0
    starts = (np.arange(k) * m) // k
    if shift and k > 1:
        x, y = np.minimum(pos[a], pos[b]), np.maximum(pos[a], pos[b])
        d = y - x
        q = m // k
        diff = np.zeros(m + 1, np.int64)
        near = (d <= q) & (2 * d <= m)  # rows x+1 .. y
        np.add.at(diff, x[near] + 1, 1)
        np.add.at(diff, y[near] + 1, -1)
        wrap = (m - d <= q) & (2 * d > m)  # rows y+1 .. m-1 and 0 .. x
        np.add.at(diff, y[wrap] + 1, 1)
        diff[m] -= int(wrap.sum())
        diff[0] += int(wrap.sum())
        np.add.at(diff, x[wrap] + 1, -1)
        depth = np.cumsum(diff[:m])
        best = int(np.argmin(depth[np.arange(q)[:, None] + starts[None, :]].sum(axis=1)))
    part = np.empty(m, np.int64)
    part[order] = np.searchsorted(starts, (np.arange(m) - best) % m, side="right") - 1
    return part


@njit(cache=True, nogil=True)
def _smooth_into(part, nb, passes):
    """In place: ``passes`` sweeps in which each triangle with two neighbours in one
    other part moves there, one at a time (each move cuts at least one edge less)."""
    for _ in range(passes):
        moved = 0
        for t in range(part.shape[0]):
            for k in range(3):
                u = nb[t, k]
                if u < 0 or part[u] == part[t]:
                    continue
                same = 0
                for j in range(3):
                    if nb[t, j] >= 0 and part[nb[t, j]] == part[u]:
                        same += 1
                if same >= 2:
                    part[t] = part[u]
                    moved += 1
                    break
        if moved == 0:
            break


def smooth_parts(part: np.ndarray, nb: np.ndarray, passes: int = 6) -> np.ndarray:
    """A copy of ``part`` in which, ``passes`` times, every triangle with two
    neighbours (``nb``, -1 none) in one other part moves there (one at a time, so
    that the cut only falls)."""
    out = np.ascontiguousarray(part, dtype=np.int64).copy()
    _smooth_into(out, np.ascontiguousarray(nb, dtype=np.int64), int(passes))
    return out


def projected_parts(parent: np.ndarray, row_part: np.ndarray, m: int, k: int, nb: np.ndarray,
                    passes: int = 6) -> np.ndarray:
    """Each of ``m`` input triangles in the part (of ``k``) holding most of its rows
    (``row_part`` of the rows, ``parent`` their input triangle), then
    :func:`smooth_parts`."""
    votes = np.zeros((m, k), np.int64)
    np.add.at(votes, (parent, row_part), 1)
    return smooth_parts(votes.argmax(axis=1), nb, passes)


def kd_order(centroids: np.ndarray, leaf: int = 64) -> np.ndarray:
    """Order of the points by recursive median bisection across the longer side of
    each cell's bounding box (cells of ``leaf`` points or fewer kept in input order):
    ``k = 2^j`` equal stretches are its cells."""
    out = np.empty(len(centroids), np.int64)
    stack = [(np.arange(len(centroids)), 0)]
    while stack:
        idx, lo = stack.pop()
        if len(idx) <= leaf:
            out[lo:lo + len(idx)] = idx
            continue
        c = centroids[idx]
        axis = int(np.ptp(c[:, 1]) > np.ptp(c[:, 0]))
        half = len(idx) // 2
        s = idx[np.argpartition(c[:, axis], half)]
        stack.append((s[half:], lo + half))
        stack.append((s[:half], lo))
    return out


class VertexTree(NamedTuple):
    """Result of :func:`vertex_tree_cover`.

    Attributes
    ----------
    inside : (n,) bool
        The tree's vertices.
    order : (c,) int64
        The covered triangles in cycle order (consecutive ones share an edge, the
        last and the first too).
    uncovered : (u,) int64
        Triangles with no tree vertex (all three outside).
    """

    inside: np.ndarray
    order: np.ndarray
    uncovered: np.ndarray


@njit(cache=True, nogil=True)
def _grow_tree_into(vv_ptr, vv_idx, boundary, q, seed, inside):
    """Prim's search over the vertices from ``seed``, lowest ``edge_class`` first;
    a vertex joins when it is interior and exactly one neighbour is inside (so the
    inside vertices induce a tree). Fills ``inside``; returns its size."""
    n = len(boundary)
    count = np.zeros(n, np.int64)
    heap = [(np.int64(0), np.int64(0), np.int64(seed))]
    seq = 1
    size = 0
    while len(heap):
        _, _, v = heapq.heappop(heap)
        if inside[v] or boundary[v] or (size > 0 and count[v] != 1):
            continue
        inside[v] = True
        size += 1
        for j in range(vv_ptr[v], vv_ptr[v + 1]):
            w = vv_idx[j]
            count[w] += 1
            if not inside[w] and not boundary[w] and count[w] == 1:
                heapq.heappush(heap, (np.int64(edge_class(q[v], q[w])), np.int64(seq), np.int64(w)))
                seq += 1
    return size


@njit(cache=True, nogil=True)
def _adjacent(ptr, idx, a, b):
    """Whether vertices ``a`` and ``b`` share an edge (``ptr``/``idx``: neighbour lists)."""
    for j in range(ptr[a], ptr[a + 1]):
        if idx[j] == b:
            return True
    return False


@njit(cache=True, nogil=True)
def _repair_into(ptr, idx, vt_ptr, vt_idx, tri, inside, boundary, max_visit, passes):
    """Cover uncovered triangles (no inside vertex) and keep the inside an induced tree:
    for each, the best of its vertices ``v`` (most triangles covered, net) that either
    has one inside neighbour (taken in) or two non-adjacent ones ``a``, ``b``: then
    ``v`` closes a loop with the tree path from ``a`` to ``b`` (breadth-first, at most
    ``max_visit`` vertices), and one vertex ``w`` of that loop with no other tree
    neighbour leaves (the tree stays connected, one edge fewer than vertices), the one
    that uncovers fewest. Only moves that cover more than they uncover; ``passes``
    sweeps. In place; returns ``(swaps, additions)``."""
    n = len(inside)
    m = tri.shape[0]
    count = np.zeros(n, np.int64)
    for v in range(n):
        if inside[v]:
            for j in range(ptr[v], ptr[v + 1]):
                count[idx[j]] += 1
    s = np.zeros(m, np.int64)
    for t in range(m):
        for k in range(3):
            if inside[tri[t, k]]:
                s[t] += 1
    par = np.full(n, -1, np.int64)
    seen = np.full(n, -1, np.int64)
    queue = np.empty(n, np.int64)
    stamp = 0
    swaps = 0
    adds = 0
    for _ in range(passes):
        changed = 0
        for t in range(m):
            if s[t] != 0:
                continue
            best_net = 0
            best_v = -1
            best_w = -1
            for kk in range(3):
                v = tri[t, kk]
                if boundary[v] or inside[v]:
                    continue
                gain = 0
                for j in range(vt_ptr[v], vt_ptr[v + 1]):
                    if s[vt_idx[j]] == 0:
                        gain += 1
                if count[v] == 1:
                    if gain > best_net:
                        best_net = gain
                        best_v = v
                        best_w = -1
                    continue
                if count[v] != 2:
                    continue
                a = -1; b = -1
                for j in range(ptr[v], ptr[v + 1]):
                    x = idx[j]
                    if inside[x]:
                        if a < 0:
                            a = x
                        else:
                            b = x
                if _adjacent(ptr, idx, a, b):
                    continue
                # BFS in the tree from a to b
                stamp += 1
                head = 0
                tail = 1
                queue[0] = a
                seen[a] = stamp
                par[a] = -1
                found = False
                while head < tail and tail < max_visit:
                    x = queue[head]
                    head += 1
                    if x == b:
                        found = True
                        break
                    for j in range(ptr[x], ptr[x + 1]):
                        y = idx[j]
                        if inside[y] and seen[y] != stamp:
                            seen[y] = stamp
                            par[y] = x
                            queue[tail] = y
                            tail += 1
                if not found:
                    continue
                w = b
                while w >= 0:
                    # tree degree after adding v
                    deg = 0
                    for j in range(ptr[w], ptr[w + 1]):
                        if inside[idx[j]]:
                            deg += 1
                    if w == a or w == b:
                        deg += 1
                    if deg == 2:
                        loss = 0
                        for j in range(vt_ptr[w], vt_ptr[w + 1]):
                            u = vt_idx[j]
                            has_v = tri[u, 0] == v or tri[u, 1] == v or tri[u, 2] == v
                            if s[u] - 1 + (1 if has_v else 0) == 0:
                                loss += 1
                        if gain - loss > best_net:
                            best_net = gain - loss
                            best_v = v
                            best_w = w
                    w = par[w]
            if best_v < 0:
                continue
            changed += 1
            inside[best_v] = True
            for j in range(ptr[best_v], ptr[best_v + 1]):
                count[idx[j]] += 1
            for j in range(vt_ptr[best_v], vt_ptr[best_v + 1]):
                s[vt_idx[j]] += 1
            if best_w >= 0:
                swaps += 1
                inside[best_w] = False
                for j in range(ptr[best_w], ptr[best_w + 1]):
                    count[idx[j]] -= 1
                for j in range(vt_ptr[best_w], vt_ptr[best_w + 1]):
                    s[vt_idx[j]] -= 1
            else:
                adds += 1
        if changed == 0:
            break
    return swaps, adds


def vertex_tree_cover(points: np.ndarray, triangles: np.ndarray, twin: np.ndarray, repair: int = 0,
                      max_visit: int = 400) -> VertexTree:
    """The cycle around an induced tree of interior vertices (module docstring).

    Parameters
    ----------
    points : (n, 2) float64
    triangles : (m, 3) int64
    twin : (3 m,) int64, -1 on the boundary
    repair : int
        Sweeps of :func:`_repair_into` over the uncovered triangles after the growth
        (0: none).
    max_visit : int
        The repair's tree-path search visits at most this many vertices.
    """
    tri = np.ascontiguousarray(triangles, dtype=np.int64)
    n = len(points)
    bh = np.flatnonzero(twin < 0)
    boundary = np.zeros(n, np.bool_)
    boundary[tri[bh // 3, bh % 3]] = True
    boundary[tri[bh // 3, (bh % 3 + 1) % 3]] = True
    e = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    e = np.unique(np.sort(np.concatenate([e, e[:, ::-1]]), axis=1), axis=0)
    both = np.concatenate([e, e[:, ::-1]])
    both = both[np.lexsort((both[:, 1], both[:, 0]))]
    ptr = np.searchsorted(both[:, 0], np.arange(n + 1))
    # the quadtree coordinates of the vertices: each a triangle (v, v, v)
    q = quadtree_coords(points, np.repeat(np.arange(n, dtype=np.int64), 3).reshape(n, 3))[:, 0].astype(np.int64)
    inside = np.zeros(n, np.bool_)
    interior = np.flatnonzero(~boundary)
    if len(interior):
        seed = interior[np.argmin(((points[interior] - points.mean(axis=0)) ** 2).sum(axis=1))]
        ptr = ptr.astype(np.int64)
        idx = np.ascontiguousarray(both[:, 1])
        _grow_tree_into(ptr, idx, boundary, q, int(seed), inside)
        if repair:
            flat = tri.ravel()
            tv = np.argsort(flat, kind="stable")
            vt_ptr = np.searchsorted(flat[tv], np.arange(n + 1)).astype(np.int64)
            _repair_into(ptr, idx, vt_ptr, (tv // 3).astype(np.int64), tri, inside, boundary, int(max_visit),
                         int(repair))
    s = inside[tri].sum(axis=1)
    covered = np.flatnonzero((s > 0) & (s < 3))
    # the cycle crosses the edges with one end inside (never a boundary edge: no
    # boundary vertex is inside)
    across = (inside[tri] != inside[np.roll(tri, -1, axis=1)]).ravel()
    order = np.empty(len(covered), np.int64)
    length = _cover_walk_into(np.ascontiguousarray(twin, dtype=np.int64), across, int(covered[0]), order) \
        if len(covered) else 0
    return VertexTree(inside, order[:length], np.flatnonzero(s == 0))


def gilbert_path(width: int, height: int) -> np.ndarray:
    """(width * height, 2) int64: the cells of a ``width`` x ``height`` grid along a
    generalized Hilbert curve, consecutive cells side by side (one diagonal step at
    most where both sides are odd).

    Jakub Cervený's ``gilbert2d`` (github.com/jakubcerveny/gilbert, BSD-2-Clause),
    with an explicit stack instead of recursion.
    """
    out = np.empty((width * height, 2), np.int64)
    n = 0
    stack = [(0, 0, width, 0, 0, height) if width >= height else (0, 0, 0, height, width, 0)]
    while stack:
        x, y, ax, ay, bx, by = stack.pop()
        w, h = abs(ax + ay), abs(bx + by)
        dax, day, dbx, dby = np.sign(ax), np.sign(ay), np.sign(bx), np.sign(by)
        if h == 1 or w == 1:  # one row (or column) straight through
            dx, dy, steps = (dax, day, w) if h == 1 else (dbx, dby, h)
            for i in range(steps):
                out[n] = (x + i * dx, y + i * dy)
                n += 1
            continue
        ax2, ay2, bx2, by2 = ax // 2, ay // 2, bx // 2, by // 2
        if 2 * w > 3 * h:  # long: two halves along the major axis
            if abs(ax2 + ay2) % 2 and w > 2:  # even steps
                ax2, ay2 = ax2 + dax, ay2 + day
            stack.append((x + ax2, y + ay2, ax - ax2, ay - ay2, bx, by))
            stack.append((x, y, ax2, ay2, bx, by))
        else:  # up, along, back down
            if abs(bx2 + by2) % 2 and h > 2:
                bx2, by2 = bx2 + dbx, by2 + dby
            stack.append((x + (ax - dax) + (bx2 - dbx), y + (ay - day) + (by2 - dby), -bx2, -by2, -(ax - ax2),
                          -(ay - ay2)))
            stack.append((x + bx2, y + by2, ax, ay, bx - bx2, by - by2))
            stack.append((x, y, bx2, by2, ax2, ay2))
    return out


def curve_order(centroids: np.ndarray, cells: int) -> np.ndarray:
    """Order of the points along :func:`gilbert_path` on a grid of about ``cells``
    cells over their bounding box (cells as square as the box allows); points of
    one cell by x, then y."""
    c = np.asarray(centroids, dtype=np.float64)[:, :2]
    lo = c.min(axis=0)
    span = np.maximum(c.max(axis=0) - lo, 1e-300)
    aspect = span[0] / span[1]
    h = max(1, int(round(np.sqrt(cells / aspect))))
    w = max(1, int(round(h * aspect)))
    path = gilbert_path(w, h)
    rank = np.empty((w, h), np.int64)
    rank[path[:, 0], path[:, 1]] = np.arange(len(path))
    ix = np.minimum(((c[:, 0] - lo[0]) / span[0] * w).astype(np.int64), w - 1)
    iy = np.minimum(((c[:, 1] - lo[1]) / span[1] * h).astype(np.int64), h - 1)
    return np.lexsort((c[:, 1], c[:, 0], rank[ix, iy]))


def curve_blocks(order: np.ndarray, size: int, nb: np.ndarray, passes: int = 6) -> np.ndarray:
    """(m,) int64: blocks of ``size`` consecutive triangles of ``order``, their borders
    smoothed (:func:`smooth_parts`; numbers in the order's sense)."""
    block = np.empty(len(order), np.int64)
    block[order] = np.arange(len(order)) // max(int(size), 1)
    return smooth_parts(block, nb, passes)


@njit(cache=True, nogil=True)
def _sweep_into(block, nb, members, starts, out):
    """Each block (``members[starts[i]:starts[i + 1]]``) breadth-first from its
    triangles next to block ``i - 1`` (its first member if none), what the search
    cannot reach after it, in place of the block's rows in ``out``."""
    m = block.shape[0]
    seen = np.zeros(m, np.bool_)
    for i in range(starts.shape[0] - 1):
        lo, hi = starts[i], starts[i + 1]
        n = lo
        for j in range(lo, hi):
            t = members[j]
            for k in range(3):
                u = nb[t, k]
                if u >= 0 and block[u] == block[t] - 1 and not seen[t]:
                    seen[t] = True
                    out[n] = t
                    n += 1
        if n == lo and hi > lo:
            seen[members[lo]] = True
            out[n] = members[lo]
            n += 1
        head = lo
        while True:
            while head < n:
                t = out[head]
                head += 1
                for k in range(3):
                    u = nb[t, k]
                    if u >= 0 and block[u] == block[t] and not seen[u]:
                        seen[u] = True
                        out[n] = u
                        n += 1
            if n == hi:
                break
            for j in range(lo, hi):  # another piece of the block
                if not seen[members[j]]:
                    seen[members[j]] = True
                    out[n] = members[j]
                    n += 1
                    break


def _members(block: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    members = np.argsort(block, kind="stable")
    return members, np.searchsorted(block[members], np.arange(int(block.max()) + 2))


def sweep_blocks(block: np.ndarray, nb: np.ndarray) -> np.ndarray:
    """The triangles block by block (``block`` numbers, 0.. in ring order), each block
    breadth-first from its triangles next to the previous block: the ideal path
    through a block (a sweep), the bound of a ring of these blocks."""
    block = np.ascontiguousarray(block, dtype=np.int64)
    members, starts = _members(block)
    out = np.empty(len(block), np.int64)
    _sweep_into(block, np.ascontiguousarray(nb, dtype=np.int64), members, starts, out)
    return out


class BlockCycles(NamedTuple):
    """Result of :func:`block_cycles`.

    Attributes
    ----------
    orders : list of (b,) int64
        Each block's input triangles in the order of its own sparse cycle(s) (first
        row of each; a block in several pieces: one cycle after the other).
    steiner : int
        Steiner points of all the blocks' cycles.
    triangles : int
        Rows of all the blocks' cycles.
    min_angle : float
        Smallest output angle over the blocks, degrees.
    """

    orders: list
    steiner: int
    triangles: int
    min_angle: float


def block_cycles(points: np.ndarray, triangles: np.ndarray, block: np.ndarray) -> BlockCycles:
    """Sparse mode (``hammesh.hamiltonian(..., mode="sparse")``) on each block alone,
    as a mesh of its own: what a block's own Hamiltonian cycle looks like, and what
    cutting the mesh into blocks costs in Steiner points and angles."""
    import hammesh

    members, starts = _members(np.asarray(block, dtype=np.int64))
    orders, steiner, rows, amin = [], 0, 0, 180.0
    for i in range(len(starts) - 1):
        mem = members[starts[i]:starts[i + 1]]
        if len(mem) == 0:
            orders.append(mem)
            continue
        used, local = np.unique(triangles[mem].ravel(), return_inverse=True)
        h = hammesh.hamiltonian(hammesh.Mesh(points=points[used], triangles=local.reshape(-1, 3)), mode="sparse")
        steiner += int(h.report["steiner_points"])
        rows += h.n_triangles
        amin = min(amin, float(h.report["min_angle_output_deg"]))
        par = h.parent[h.parent >= 0]
        first = np.unique(par, return_index=True)[1]  # a flipped pair's rows may name one parent only
        seq = par[np.sort(first)]
        rest = np.setdiff1d(np.arange(len(mem)), seq)
        orders.append(mem[np.r_[seq, rest]])
    return BlockCycles(orders, steiner, rows, amin)


def ring_order(orders: list, block: np.ndarray, nb: np.ndarray) -> tuple[np.ndarray, int]:
    """``(order, spliced)``: the blocks in number order, each walked along its own
    cycle (``orders``, :func:`block_cycles`) from where it can be spliced into the
    ring: at a cycle edge whose two triangles touch the previous and the next block
    (counted in ``spliced``: no Steiner point needed there), else from its first
    triangle next to the previous block."""
    out, spliced = [], 0
    live = [i for i, o in enumerate(orders) if len(o)]
    for j, i in enumerate(live):
        o = orders[i]
        around = np.where(nb[o] >= 0, block[np.maximum(nb[o], 0)], -1)
        prev = (around == live[j - 1]).any(axis=1)
        nxt = (around == live[(j + 1) % len(live)]).any(axis=1)
        fwd = np.flatnonzero(prev & np.roll(nxt, 1))  # path o[s] .. o[s - 1]
        back = np.flatnonzero(np.roll(prev, 1) & nxt)  # path o[s - 1] .. o[s] backwards
        if len(fwd):
            out.append(np.roll(o, -fwd[0]))
        elif len(back):
            out.append(np.roll(o, -back[0])[::-1])
        else:
            out.append(np.roll(o, -int(np.argmax(prev))))
        spliced += bool(len(fwd) or len(back))
    return np.concatenate(out), spliced


@njit(cache=True, nogil=True)
def _cover_walk_into(twin, is_cov, start, order):
    """The cover cycle through ``start`` (``is_cov`` half-edges); fills ``order``,
    returns its length."""
    prev, cur, n = -1, start, 0
    while True:
        order[n] = cur
        n += 1
        nxt = -1
        for k in range(3):
            h = 3 * cur + k
            if is_cov[h] and twin[h] >= 0 and twin[h] // 3 != prev:
                nxt = twin[h] // 3
                break
        if nxt < 0 or nxt == start or n == order.shape[0]:
            return n
        prev, cur = cur, nxt


def cover_cycle_order(twin: np.ndarray, is_cov: np.ndarray, cycle: np.ndarray, which: int) -> np.ndarray:
    """The triangles of cover cycle ``which`` (``cycle`` ids of a ``CycleCover``) in
    cycle order."""
    members = np.flatnonzero(cycle == which)
    order = np.empty(len(members), np.int64)
    n = _cover_walk_into(np.ascontiguousarray(twin, dtype=np.int64), np.ascontiguousarray(is_cov, dtype=np.bool_),
                         int(members[0]), order)
    return order[:n]
