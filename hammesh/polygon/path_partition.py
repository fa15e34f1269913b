"""Minimum path partition of a polygon triangulation (Arkin et al., Lemma 5.1).

The dual graph of a triangulation of a simple polygon is a tree, so the fewest triangle
strips (dual paths, each triangle in exactly one) is a minimum vertex-disjoint path
cover of a tree.  It is found greedily from the leaves up, in ``O(n)``: a node joins
the paths of up to two children that still end at them; with two it closes, with
fewer it stays open to its parent.  (Lemma 5.1's odd-degree bound is the count for
the edge-disjoint variant; triangle strips need the vertex-disjoint one.)
"""

from __future__ import annotations

import numpy as np

from hammesh.errors import InvalidMeshError
from hammesh.polygon._triangulate import triangle_neighbors

__all__ = ["path_partition", "forest_path_partition"]


def path_partition(points, triangles) -> list[np.ndarray]:
    """Partition the triangles into the fewest dual paths (Lemma 5.1).

    Parameters
    ----------
    points : (n, 2) array_like of float
        The vertices the triangles index (a polygon, possibly with Steiner points).
    triangles : (m, 3) array_like of int
        A triangulation whose dual graph is a forest (e.g. of a simple polygon).

    Returns
    -------
    list of (k_i,) int64
        Row indices into ``triangles``; along each path consecutive triangles share an
        edge; every row appears in exactly one path.  Paths are ordered by their
        smallest row index; the number of paths is the minimum possible.

    Raises
    ------
    InvalidMeshError
        Bad shapes, an index out of range, a degenerate triangle, an edge shared by
        three triangles, or a dual graph with a cycle (then the problem is NP-hard,
        Section 5).

    Examples
    --------
    >>> path_partition([[0, 0], [2, 0], [1, 2], [1, -2], [3, 1], [-1, 1]],
    ...                [[0, 1, 2], [0, 3, 1], [1, 4, 2], [0, 2, 5]])
    [array([1, 0, 2]), array([3])]
    """
    pts = np.asarray(points, dtype=np.float64)
    tri = np.asarray(triangles)
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise InvalidMeshError(f"points must have shape (n, 2), got {pts.shape}")
    if tri.ndim != 2 or tri.shape[1] != 3:
        raise InvalidMeshError(f"triangles must have shape (m, 3), got {tri.shape}")
    if tri.size and not np.issubdtype(tri.dtype, np.integer):
        raise InvalidMeshError(f"triangles must be integers, got dtype {tri.dtype}")
    tri = tri.astype(np.int64)
    m = len(tri)
    if m == 0:
        return []
    bad = (tri < 0) | (tri >= len(pts))
    if bad.any():
        t, k = np.argwhere(bad)[0]
        raise InvalidMeshError(f"triangle {t} references vertex {tri[t, k]} but there are {len(pts)} points")
    p = pts[tri]
    area2 = ((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
             - (p[:, 1, 1] - p[:, 0, 1]) * (p[:, 2, 0] - p[:, 0, 0]))
    if np.any(area2 == 0):
        raise InvalidMeshError(f"triangle {int(np.flatnonzero(area2 == 0)[0])} is degenerate (zero area)")
    try:
        nb = triangle_neighbors(tri)
    except ValueError as exc:
        raise InvalidMeshError(str(exc)) from None
    n_dual_edges = int((nb >= 0).sum()) // 2
    # forest check: edges = nodes - components
    comp = _components(nb)
    if n_dual_edges != m - int(comp.max()) - 1:
        raise InvalidMeshError(
            "the dual graph of the triangles has a cycle; Lemma 5.1 needs a triangulation of "
            "a simple polygon (a tree), minimum path partition is NP-hard in general")
    return _greedy(nb)


def forest_path_partition(neighbors) -> list[np.ndarray]:
    """Lemma 5.1 on a dual forest given as its neighbour array (no geometry checks).

    Parameters
    ----------
    neighbors : (m, 3) array_like of int
        ``neighbors[t, k]``: the triangle across edge ``k`` of ``t``, or -1; symmetric,
        and the graph must be a forest (the caller checks; e.g. the strip encoders).

    Returns
    -------
    list of (k_i,) int64
        As :func:`path_partition`: the fewest dual paths, each row in exactly one.

    Examples
    --------
    >>> [p.tolist() for p in forest_path_partition([[1, -1, -1], [0, 2, 3], [1, -1, -1], [1, -1, -1]])]
    [[0], [2, 1, 3]]
    """
    nb = np.asarray(neighbors, dtype=np.int64).reshape(-1, 3)
    return _greedy(nb) if len(nb) else []


def _components(nb: np.ndarray) -> np.ndarray:
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    m = len(nb)
    t, k = np.nonzero(nb >= 0)
    g = coo_matrix((np.ones(len(t)), (t, nb[t, k])), shape=(m, m))
    return connected_components(g, directed=False)[1]


def _greedy(nb: np.ndarray) -> list[np.ndarray]:
    m = len(nb)
    visited = np.zeros(m, bool)
    parent = np.full(m, -1, np.int64)
    post: list[int] = []
    for root in range(m):
        if visited[root]:
            continue
        visited[root] = True
        stack = [root]
        order = []
        while stack:  # preorder; reversed it is a valid post-order for the greedy
            v = stack.pop()
            order.append(v)
            for u in nb[v]:
                if u >= 0 and not visited[u]:
                    visited[u] = True
                    parent[u] = v
                    stack.append(u)
        post.extend(reversed(order))
    open_end = np.ones(m, bool)   # v's path still ends at v (fewer than 2 children joined)
    joined = np.zeros(m, np.int64)
    links: list[tuple[int, int]] = []
    for v in post:
        p = parent[v]
        if p >= 0 and open_end[v] and joined[p] < 2:
            links.append((v, int(p)))
            joined[p] += 1
            if joined[p] == 2:
                open_end[p] = False
    adj = [[] for _ in range(m)]
    for a, b in links:
        adj[a].append(b)
        adj[b].append(a)
    seen = np.zeros(m, bool)
    paths = []
    for s in range(m):
        if seen[s] or len(adj[s]) == 2:
            continue
        path, prev, v = [s], -1, s
        seen[s] = True
        while True:
            nxt = [u for u in adj[v] if u != prev]
            if not nxt:
                break
            prev, v = v, nxt[0]
            seen[v] = True
            path.append(v)
        paths.append(np.array(path, dtype=np.int64))
    paths.sort(key=lambda q: int(q.min()))
    return paths
