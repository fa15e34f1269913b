"""Hamiltonian triangulations with Steiner points (Arkin et al., Theorem 2.3).

Given a decomposition of a simple polygon into ``k > 1`` convex pieces, a Hamiltonian
*cycle* triangulation needs ``k - 1`` Steiner points and a Hamiltonian *path*
triangulation ``k - 2``, and the rectilinear comb (Figure 7) shows this is tight.

Construction (the proof of Thm 2.3): the pieces and the diagonals between them form a
tree.  One Steiner point goes at the midpoint of every diagonal.  Two *root* pieces
sharing a diagonal are fanned from its Steiner point (the triangles around it form a
cycle); every other piece is fanned from the Steiner point on the diagonal to its
parent, and its fan is spliced into the parent's fan between the two triangles on
that diagonal.  For a *path*, one Steiner point is saved: the paper slides the root
point onto a vertex; here, equivalently, a leaf piece is fanned from an endpoint of
its diagonal instead, which cuts the cycle open there (this works whatever other
diagonals meet at that endpoint).  A convex polygon (``k = 1``) needs no Steiner point
for a path and one (its centroid) for a cycle.

Decomposition: an exact minimum convex decomposition by diagonals at any size
(:mod:`~hammesh.polygon.min_convex`, Keil's dynamic program), whose pieces may have
straight angles at diagonal ends; the piece tree is then rooted so that every piece is
fanned from a diagonal where it is strictly convex (:func:`_fan_tree`), else the
minimum strictly convex decomposition is used (it always has such a rooting).
Hertel--Mehlhorn on request, and with holes (a minimum is NP-hard there): drop every
diagonal of a triangulation whose removal keeps the two merged angles strictly convex,
at most 4 times the minimum number of pieces; a few removal orders are tried and the
fewest pieces kept (with holes: where the construction from the first order fails its
certificate, e.g. a vertex one ulp off a line whose rounded midpoints make a fan
degenerate, up to ``HOLE_ORDERS`` other orders are tried).  Vertices with a straight angle are left out of the
Hertel--Mehlhorn decomposition (they lie on piece sides).

Complexity: ``O(n)`` after the decomposition; the minimum one costs ``O(n^2)`` for the
visibility graph and ``O(n r^2)`` splits for ``r`` reflex vertices, Hertel--Mehlhorn
``O(n log n)`` (Triangle).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hammesh.errors import InvalidOptionError, VerificationError
from hammesh.polygon._polygon import Polygon, as_polygon
from hammesh.polygon.min_convex import minimum_convex_faces
from hammesh.polygon.verify import verify_polygon_triangulation
from hammesh.predicates import orient
from hammesh.polygon._triangulate import triangle_neighbors, triangulate_polygon

__all__ = ["steiner_hamiltonian", "steiner_hamiltonian_result", "convex_decomposition",
           "SteinerResult", "KINDS", "DECOMPOSITIONS"]

#: Accepted values of ``kind``.
KINDS = ("cycle", "path")
#: Accepted values of ``decomposition``.
DECOMPOSITIONS = ("auto", "optimal", "hertel-mehlhorn")


@dataclass(frozen=True, eq=False)
class SteinerResult:
    """Output of :func:`steiner_hamiltonian_result`.

    Attributes
    ----------
    points : (n + s, 2) float64
        The input vertices (input order) followed by the ``s`` Steiner points.
    triangles : (m, 3) int64
        Counter-clockwise, in order along the Hamiltonian cycle or path.
    pieces : list of (k_i,) int64
        The convex decomposition used (input vertex indices, counter-clockwise).
    kind : str
        ``"cycle"`` or ``"path"``.
    n_steiner : int
        ``s``: ``k - 1`` for a cycle, ``k - 2`` for a path (``k > 1``).
    method : str
        The decomposition used: ``"optimal"`` (a minimum convex decomposition, Keil's
        dynamic program, so ``k`` is the minimum over decompositions by diagonals),
        ``"optimal-strict"`` (minimum among decompositions whose pieces are strictly
        convex at diagonal ends, used when the minimum one admits no degenerate-free
        fan tree) or ``"hertel-mehlhorn"`` (at most 4 times the minimum).
    """

    points: np.ndarray
    triangles: np.ndarray
    pieces: list
    kind: str
    n_steiner: int
    method: str = "hertel-mehlhorn"

    @property
    def k(self) -> int:
        """Number of convex pieces."""
        return len(self.pieces)


def steiner_hamiltonian(points, kind: str = "cycle", *, holes=None,
                        decomposition: str = "auto") -> tuple[np.ndarray, np.ndarray]:
    """A Hamiltonian cycle or path triangulation of a simple polygon with Steiner points.

    Parameters
    ----------
    points : (n, 2) array_like of float
        Simple polygon, clockwise or counter-clockwise.
    kind : {"cycle", "path"}
        ``"cycle"``: the dual contains a Hamiltonian cycle, ``k - 1`` Steiner points
        (1 for a convex polygon); ``"path"``: a Hamiltonian path, ``max(k - 2, 0)``.
    holes : sequence of (n_i, 2) array_like of float, optional
        Polygonal holes (either orientation), strictly inside ``points`` and disjoint.
        The same construction applies (the paper, after Thm 2.3) with a spanning tree
        of the pieces; the decomposition is Hertel--Mehlhorn (a minimum one is NP-hard
        to find with holes), so ``k`` is not the minimum.
    decomposition : {"auto", "optimal", "hertel-mehlhorn"}
        ``"auto"`` and ``"optimal"``: the exact minimum convex decomposition (any size;
        with holes ``"auto"`` is Hertel--Mehlhorn).  ``"hertel-mehlhorn"``: the
        ``O(n log n)`` heuristic, at most 4 times the minimum.

    Returns
    -------
    Q : (n + s, 2) float64
        The input points (then the holes' points, in order) followed by the ``s``
        Steiner points (interior, at midpoints of decomposition diagonals).
    T : (m, 3) int64
        Counter-clockwise triangles indexing ``Q``, in cycle / path order (for a cycle
        the last row also shares an edge with the first).

    Raises
    ------
    InvalidDomainError
        ``points`` is not a simple polygon, or the holes are invalid.
    InvalidOptionError
        Unknown ``kind`` or ``decomposition``; ``"optimal"`` with holes.

    Examples
    --------
    >>> points = [[0, 0], [2, -1], [4, 0], [4, 4], [2, 1], [0, 4]]   # two convex pieces
    >>> Q, T = steiner_hamiltonian(points, kind="cycle")
    >>> len(Q), len(T)      # one Steiner point, the triangles around it form a cycle
    (7, 6)
    >>> Q, T = steiner_hamiltonian(points, kind="path")
    >>> len(Q), len(T)
    (6, 4)
    """
    res = steiner_hamiltonian_result(points, kind, holes=holes, decomposition=decomposition)
    return res.points, res.triangles


def steiner_hamiltonian_result(points, kind: str = "cycle", *, holes=None,
                               decomposition: str = "auto") -> SteinerResult:
    """:func:`steiner_hamiltonian` with the decomposition used (``k``, pieces, method)."""
    if kind not in KINDS:
        raise InvalidOptionError(f"kind must be one of {', '.join(map(repr, KINDS))}, got {kind!r}")
    if holes is not None and len(holes):
        rings = [np.asarray(points, dtype=np.float64)] + [np.asarray(h, dtype=np.float64) for h in holes]
        for attempt in range(HOLE_ORDERS):
            res = _with_holes(points, holes, kind, decomposition, attempt)
            try:
                verify_polygon_triangulation(rings, res.points, res.triangles, kind)
                return res
            except VerificationError:
                # a vertex one ulp off a line (an outline vertex under a hole's side) can
                # leave a fan of rounded midpoints degenerate; another removal order of
                # the diagonals gives other pieces (nothing unverified is returned)
                if attempt == HOLE_ORDERS - 1:
                    raise
    poly = as_polygon(points)
    pieces, diagonals, method = _decompose(poly, _check_decomposition(poly, decomposition))
    pts, tri = _construct(poly, pieces, diagonals, kind)
    # internal -> input indices for polygon vertices, Steiner points keep theirs
    n = poly.n
    remap = np.concatenate([poly.order, np.arange(n, len(pts))])
    Q = np.concatenate([np.asarray(points, dtype=np.float64).reshape(n, 2), pts[n:]])
    verify_polygon_triangulation([Q[:n]], Q, remap[tri], kind)
    return SteinerResult(points=Q, triangles=remap[tri], kind=kind, n_steiner=len(pts) - n,
                         method=method, pieces=[poly.order[np.asarray(p, dtype=np.int64)] for p in pieces])


#: Removal orders of Hertel--Mehlhorn's diagonals tried with holes before a failed
#: certificate stands: the triangulation's order, reversed, then seeded shuffles.
HOLE_ORDERS = 6


def _with_holes(points, holes, kind, decomposition, attempt: int = 0) -> SteinerResult:
    from hammesh.polygon._holes import as_domain, triangulate_domain

    if decomposition not in DECOMPOSITIONS:
        _check_decomposition(None, decomposition)
    if decomposition == "optimal":
        raise InvalidOptionError("decomposition='optimal' is not available with holes (a minimum "
                                 "convex decomposition is NP-hard there); use 'auto'")
    dom = as_domain(points, holes)
    P = dom.points
    tri = triangulate_domain(dom)
    nb = triangle_neighbors(tri)
    t_idx, k_idx = np.nonzero(nb >= 0)
    keep = t_idx < nb[t_idx, k_idx]
    t_idx, k_idx = t_idx[keep], k_idx[keep]
    if attempt:  # (see HOLE_ORDERS)
        order = (np.arange(len(t_idx))[::-1] if attempt == 1
                 else np.random.default_rng(attempt).permutation(len(t_idx)))
        t_idx, k_idx = t_idx[order], k_idx[order]
    faces = _hertel_mehlhorn(P, tri, nb, t_idx, k_idx)
    boundary = set(zip(range(dom.n), dom.nxt.tolist()))
    diagonals = {}
    for f, face in enumerate(faces):
        for s in range(len(face)):
            e = (face[s], face[(s + 1) % len(face)])
            if e not in boundary:
                diagonals[e] = f
    poly = Polygon(points=P, order=dom.order, area=dom.area)
    pts, T = _construct(poly, faces, diagonals, kind)
    N = dom.n
    remap = np.concatenate([dom.order, np.arange(N, len(pts))])
    Q = np.empty_like(pts)
    Q[remap] = pts
    return SteinerResult(points=Q, triangles=remap[T], kind=kind, n_steiner=len(pts) - N,
                         method="hertel-mehlhorn",
                         pieces=[dom.order[np.asarray(p, dtype=np.int64)] for p in faces])


def convex_decomposition(points, *, decomposition: str = "auto") -> list[np.ndarray]:
    """Convex decomposition of a simple polygon, as used by :func:`steiner_hamiltonian`.

    ``decomposition`` as there (the minimum by default, or Hertel--Mehlhorn).

    Returns
    -------
    list of (k_i,) int64
        The pieces as counter-clockwise cycles of input vertex indices; vertices with a
        straight angle appear on the piece sides they lie on.
    """
    poly = as_polygon(points)
    pieces, _, _ = _decompose(poly, _check_decomposition(poly, decomposition))
    return [poly.order[np.asarray(p, dtype=np.int64)] for p in pieces]


# ----------------------------------------------------------------------------- decomposition

def _check_decomposition(poly: Polygon, decomposition: str) -> str:
    if decomposition not in DECOMPOSITIONS:
        raise InvalidOptionError(f"decomposition must be one of "
                                 f"{', '.join(map(repr, DECOMPOSITIONS))}, got {decomposition!r}")
    return decomposition


def _corners(poly: Polygon) -> np.ndarray:
    p = poly.points
    n = poly.n
    keep = [k for k in range(n)
            if orient(p[k - 1, 0], p[k - 1, 1], p[k, 0], p[k, 1],
                      p[(k + 1) % n, 0], p[(k + 1) % n, 1]) != 0]
    return np.array(keep, dtype=np.int64)


def _decompose(poly: Polygon, method: str = "auto"):
    """Pieces (lists of internal vertex indices, CCW), their diagonals and the method.

    Returns ``(pieces, diagonals, method)`` with ``diagonals`` a dict ``(u, v) -> piece``
    for every directed piece side ``u -> v`` that is a diagonal (``u``, ``v`` internal).
    The first decomposition that admits a fan tree (:func:`_fan_tree`) is used: the
    minimum one (straight angles allowed, then not) when ``method`` allows it, else
    Hertel--Mehlhorn, whose pieces are strictly convex.
    """
    corners = _corners(poly)
    cp = np.ascontiguousarray(poly.points[corners])
    tries = []
    if method in ("optimal", "auto"):
        tries = [("optimal", True), ("optimal", False)]
    k_min = None
    everything = np.arange(poly.n)
    for name, straight in tries:
        # all vertices: a diagonal from a reflex vertex may end at a straight one
        faces = minimum_convex_faces(poly.points, straight=straight)
        k_min = len(faces) if k_min is None else k_min
        pieces, diagonals = _expand(poly, everything, faces)
        if _fan_tree(poly.points, pieces, diagonals) is not None:
            return pieces, diagonals, name if len(faces) == k_min else "optimal-strict"
    if method != "hertel-mehlhorn":  # pragma: no cover - strictly convex pieces always fan
        raise AssertionError("a strictly convex decomposition always has a fan tree")
    pieces, diagonals = _expand(poly, corners, _hm_faces(cp))
    return pieces, diagonals, "hertel-mehlhorn"


def _hm_faces(cp: np.ndarray):
    """Hertel--Mehlhorn faces (corner indices) over a few removal orders, fewest kept."""
    tri = triangulate_polygon(cp)
    nb = triangle_neighbors(tri)
    best = None
    t_idx, k_idx = np.nonzero(nb >= 0)
    keep = t_idx < nb[t_idx, k_idx]
    t_idx, k_idx = t_idx[keep], k_idx[keep]
    a = tri[t_idx, k_idx]
    b = tri[t_idx, (k_idx + 1) % 3]
    length = np.hypot(*(cp[a] - cp[b]).T)
    orders = [np.arange(len(a)), np.arange(len(a))[::-1], np.argsort(-length, kind="stable"),
              np.argsort(length, kind="stable")]
    for order in orders:
        faces = _hertel_mehlhorn(cp, tri, nb, t_idx[order], k_idx[order])
        if best is None or len(faces) < len(best):
            best = faces
    return best


def _expand(poly: Polygon, corners: np.ndarray, faces):
    """Corner-index faces -> internal vertex indices, with straight-angle vertices."""
    m = len(corners)
    n = poly.n
    pieces = []
    diagonals = {}
    for f, face in enumerate(faces):
        verts = []
        for s in range(len(face)):
            u, v = face[s], face[(s + 1) % len(face)]
            cu, cv = int(corners[u]), int(corners[v])
            verts.append(cu)
            if (v - u) % m == 1:  # polygon side: include the straight vertices on it
                w = (cu + 1) % n
                while w != cv:
                    verts.append(w)
                    w = (w + 1) % n
            else:
                diagonals[(cu, cv)] = f
        pieces.append(verts)
    return pieces, diagonals


def _good(P, piece, u, v) -> bool:
    """Whether ``piece`` is strictly convex at both ends of its side ``u -> v``.

    Only then is the fan from a point inside that side free of flat triangles.
    """
    L = len(piece)
    s = piece.index(u)
    w, x = piece[s - 1], piece[(s + 2) % L]
    return (orient(P[w, 0], P[w, 1], P[u, 0], P[u, 1], P[v, 0], P[v, 1]) != 0
            and orient(P[u, 0], P[u, 1], P[v, 0], P[v, 1], P[x, 0], P[x, 1]) != 0)


def _fan_tree(P, pieces, diagonals):
    """Root pieces, root diagonal and parents such that every fan is non-degenerate.

    Every piece but the roots is fanned from the Steiner point on the diagonal to its
    parent, the roots from the one on the root diagonal; each such diagonal must be
    :func:`_good` for the piece fanned from it.  Tries the root diagonals from the
    piece of highest degree first.  With holes the piece graph has cycles; the tree
    is a spanning tree of it, ``tree`` its diagonals (as vertex-pair frozensets).
    Returns ``(root_a, root_b, (u0, v0), parent, tree)`` or ``None``.
    """
    k = len(pieces)
    if k == 1:
        return 0, -1, None, {}, set()
    adj = [[] for _ in range(k)]
    for (u, v), f in diagonals.items():
        adj[f].append(diagonals[(v, u)])
    good = {(u, v): _good(P, pieces[f], u, v) for (u, v), f in diagonals.items()}
    sides = [[] for _ in range(k)]
    for (u, v), f in sorted(diagonals.items()):
        sides[f].append((u, v))
    by_degree = sorted(range(k), key=lambda f: (-len(adj[f]), f))
    for root_a in by_degree:
        for u0, v0 in sides[root_a]:
            if not (good[(u0, v0)] and good[(v0, u0)]):
                continue
            root_b = diagonals[(v0, u0)]
            parent = {root_a: -1, root_b: -1}
            tree = {frozenset((u0, v0))}
            stack = [root_a, root_b]
            ok = True
            while stack and ok:
                f = stack.pop()
                for u, v in sides[f]:
                    if diagonals[(v, u)] not in parent:
                        if not good[(v, u)]:
                            ok = False
                            break
                        parent[diagonals[(v, u)]] = f
                        tree.add(frozenset((u, v)))
                        stack.append(diagonals[(v, u)])
            if ok:
                return root_a, root_b, (u0, v0), parent, tree
    return None


def _hertel_mehlhorn(cp, tri, nb, t_idx, k_idx):
    """Faces (lists of corner indices, CCW) after dropping inessential diagonals."""
    m = len(tri)
    he_org = tri.reshape(-1)                      # half-edge 3t+k: tri[t,k] -> tri[t,k+1]
    nxt = (np.arange(3 * m) // 3) * 3 + (np.arange(3 * m) % 3 + 1) % 3
    prv = (np.arange(3 * m) // 3) * 3 + (np.arange(3 * m) % 3 + 2) % 3
    nxt, prv = nxt.tolist(), prv.tolist()
    org = he_org.tolist()
    twin = [-1] * (3 * m)
    for t in range(m):
        for k in range(3):
            u = nb[t, k]
            if u >= 0:
                a = tri[t, k]
                kk = int(np.flatnonzero(tri[u] == tri[t, (k + 1) % 3])[0])
                assert tri[u, (kk + 1) % 3] == a
                twin[3 * t + k] = 3 * int(u) + kk
    alive = [True] * (3 * m)

    def convex(w, a, y):
        return orient(cp[w, 0], cp[w, 1], cp[a, 0], cp[a, 1], cp[y, 0], cp[y, 1]) > 0

    for t, k in zip(t_idx.tolist(), k_idx.tolist()):
        h = 3 * t + k
        g = twin[h]
        a, b = org[h], org[g]
        w = org[prv[h]]            # w -> a on h's face
        y = org[nxt[nxt[g]]]       # a -> y on g's face: next(g) is a -> y
        z = org[prv[g]]            # z -> b on g's face
        c = org[nxt[nxt[h]]]       # b -> c on h's face
        if convex(w, a, y) and convex(z, b, c):
            ph, nh, pg, ng = prv[h], nxt[h], prv[g], nxt[g]
            nxt[ph], prv[ng] = ng, ph
            nxt[pg], prv[nh] = nh, pg
            alive[h] = alive[g] = False
    faces = []
    seen = [False] * (3 * m)
    for h in range(3 * m):
        if not alive[h] or seen[h]:
            continue
        face, e = [], h
        while not seen[e]:
            seen[e] = True
            face.append(org[e])
            e = nxt[e]
        faces.append(face)
    return faces


# ----------------------------------------------------------------------------- construction

def _construct(poly: Polygon, pieces, diagonals, kind):
    """Steiner points and ordered triangles, internal indices (Steiner points from n).

    For a path, the Steiner-saving step needs a Hamiltonian path of one piece starting
    on a given side; if a piece with straight-angle vertices has none, the next leaf is
    tried, and as a last resort the cycle (k - 1 Steiner points) is returned as path.
    """
    P = poly.points
    n = poly.n
    k = len(pieces)
    if k == 1:
        verts = pieces[0]
        if kind == "path":
            for apex in verts:   # a straight-angle vertex may not start a path
                tri = _fan(P, verts, apex)
                if tri is not None:
                    return P, np.array(tri, dtype=np.int64)
        corners = _corners(poly)
        centroid = P[corners].mean(axis=0)
        tri = [(n, verts[s], verts[(s + 1) % len(verts)]) for s in range(len(verts))]
        return np.vstack([P, centroid]), np.array(tri, dtype=np.int64)

    root_a, root_b, (u0, v0), parent, tree = _fan_tree(P, pieces, diagonals)
    children = [0] * k
    for g, f in parent.items():
        if f >= 0:
            children[f] += 1
    if kind == "path" and k == 2:  # no Steiner point: a path through both pieces
        fa = _fan(P, pieces[root_a], u0, order_from=v0)   # starts on (u0, v0)
        fb = _fan(P, pieces[root_b], u0, order_from=v0)   # starts on (v0, u0)
        if fa is not None and fb is not None:
            return P, np.array(fb[::-1] + fa, dtype=np.int64)
    leaves = [g for g in range(k) if children[g] == 0 and g not in (root_a, root_b)]
    candidates = leaves if kind == "path" else []
    for saved in candidates + [None]:
        out = _spliced_cycle(P, pieces, diagonals, tree, parent, root_a, root_b, (u0, v0), saved)
        if out is not None:
            return out
    raise AssertionError("unreachable: the cycle construction always succeeds")  # pragma: no cover


def _spliced_cycle(P, pieces, diagonals, tree, parent, root_a, root_b, e0, saved):
    """The cycle construction; with ``saved`` (a leaf piece) cut open into a path there.

    Only the ``tree`` diagonals get Steiner points; the others are plain sides.
    """
    n = len(P)
    steiner = {}
    extra = []
    for (u, v), f in sorted(diagonals.items()):
        if frozenset((u, v)) not in tree:
            continue
        if (v, u) in steiner:
            steiner[(u, v)] = steiner[(v, u)]
            continue
        g = diagonals[(v, u)]
        if saved is not None and {f, g} == {saved, parent[saved]}:
            continue
        steiner[(u, v)] = n + len(extra)
        extra.append((P[u] + P[v]) / 2.0)
    Q = np.vstack([P] + ([np.array(extra)] if extra else []))

    def sides(f, apex):
        """Sides of piece f in CCW order, starting just after the apex's position."""
        verts = pieces[f]
        L = len(verts)
        s0 = next(t for t in range(L) if steiner.get((verts[t], verts[(t + 1) % L])) == apex) + 1
        return [(verts[(s0 + t) % L], verts[(s0 + t + 1) % L]) for t in range(L)]

    seq = []
    leaf_fan = None

    def emit(root, apex, parent_f):
        """Fan of piece ``root`` around Steiner point ``apex``, children spliced in."""
        nonlocal leaf_fan
        stack = [["piece", root, apex, parent_f, sides(root, apex), 0]]
        while stack:
            fr = stack[-1]
            if fr[0] == "close":
                stack.pop()
                seq.append(fr[1])
                continue
            _, f, ap, par, sd, i = fr
            if i == len(sd):
                stack.pop()
                continue
            fr[5] = i + 1
            u, v = sd[i]
            if frozenset((u, v)) in tree:
                g = diagonals[(v, u)]
                if g == par:
                    continue
                mid = steiner.get((u, v))
                if mid is None:  # the saved leaf: a path starting on its side (v, u)
                    seq.append((ap, u, v))
                    leaf_fan = (len(seq) - 1, _fan(Q, pieces[g], u, order_from=v))
                    continue
                seq.append((ap, u, mid))
                stack.append(["close", (ap, mid, v)])
                stack.append(["piece", g, mid, f, sides(g, mid), 0])
                continue
            if not _collinear(Q, ap, u, v):
                seq.append((ap, u, v))

    s0 = steiner[e0]
    emit(root_a, s0, root_b)
    emit(root_b, s0, root_a)
    if saved is None:
        return Q, np.array(seq, dtype=np.int64)
    T, fan = leaf_fan
    if fan is None:
        return None
    ordered = seq[T + 1:] + seq[:T] + [seq[T]] + fan
    return Q, np.array(ordered, dtype=np.int64)


def _collinear(Q, a, u, v) -> bool:
    return orient(Q[a, 0], Q[a, 1], Q[u, 0], Q[u, 1], Q[v, 0], Q[v, 1]) == 0


def _fan(Q, verts, apex, order_from=None):
    """Triangles of the convex cycle ``verts`` in a dual path starting on a side at ``apex``.

    ``(apex, order_from)`` (or ``(order_from, apex)``) must be a side of the cycle; the
    returned triangles (vertex ids of ``Q``) start at the one on that side.  Without
    straight-angle vertices this is the fan from ``apex``; otherwise the Thm 2.1
    dynamic program on the piece is used.  Returns None if no such path exists.
    """
    from hammesh.polygon._polygon import Polygon
    from hammesh.polygon.hamiltonian import chords_by_gap, path_from_table, path_table
    from hammesh.polygon.visibility import visibility_matrix

    L = len(verts)
    s = verts.index(apex)
    # local CCW order w with the start side (w[L-1], w[0])
    w = [verts[(s + t) % L] for t in range(L)]
    if order_from is not None and order_from == w[1]:
        w = w[1:] + w[:1]          # side (apex, w1) becomes (w[L-1], w[0])
    if L == 3:
        return [tuple(w)]
    straight = any(_collinear(Q, w[t - 1], w[t], w[(t + 1) % L]) for t in range(L))
    if not straight:
        a = w[0]
        tri = [(a, w[t], w[t + 1]) for t in range(1, L - 1)]
        return tri[::-1]  # start on the side (w[L-1], w[0])
    pts = np.ascontiguousarray(Q[w])
    poly = Polygon(points=pts, order=np.arange(L), area=0.0)
    ci, cj = chords_by_gap(visibility_matrix(poly))
    D = path_table(ci, cj, L)
    # D[0, L-1]: chain 0..L-1 closed by its own side (L-1, 0)
    if L >= 4 and D[0, L - 2]:
        first, rest = (0, L - 2, L - 1), path_from_table(D, 0, L - 2, L)
    elif L >= 4 and D[1, L - 1]:
        first, rest = (0, 1, L - 1), path_from_table(D, 1, L - 1, L)
    else:
        return None
    local = [first] + [tuple(r) for r in rest]
    return [tuple(w[i] for i in sorted(t)) for t in local]
