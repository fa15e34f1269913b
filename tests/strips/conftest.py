"""Shared meshes and independent helpers for the strip tests (pure numpy / Python)."""

from __future__ import annotations

import functools

import numpy as np
from scipy.spatial import Delaunay
import pytest

import hammesh
from hammesh.mesh import Mesh
from tests.helpers import grid_mesh

SQUARE = [[0, 0], [1, 0], [1, 1], [0, 1]]


@functools.lru_cache(maxsize=None)
def square_mesh(max_area: float = 0.01) -> Mesh:
    return hammesh.quality_mesh(hammesh.Domain.from_polygon(SQUARE), min_angle=30, max_area=max_area)


@functools.lru_cache(maxsize=None)
def square_hamiltonian(max_area: float = 0.01) -> hammesh.HamiltonianMesh:
    return hammesh.hamiltonian(square_mesh(max_area))


def delaunay_mesh(seed: int, n: int, lift: bool = False) -> Mesh:
    rng = np.random.default_rng(seed)
    pts = rng.random((n, 2))
    tri = Delaunay(pts).simplices.astype(np.int64)
    p = pts[tri]
    cr = (p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1]) - (p[:, 1, 1] - p[:, 0, 1]) * (p[:, 2, 0] - p[:, 0, 0])
    tri[cr < 0] = tri[cr < 0][:, ::-1]
    if lift:
        pts = np.c_[pts, pts[:, 0] ** 2 + pts[:, 1] ** 2]
    return Mesh(pts, tri)


def torus_mesh(nu: int = 12, nv: int = 8) -> Mesh:
    """Closed 3D surface (no boundary), outward winding."""
    u, v = np.meshgrid(np.arange(nu) * 2 * np.pi / nu, np.arange(nv) * 2 * np.pi / nv, indexing="ij")
    R, r = 2.0, 0.7
    pts = np.c_[((R + r * np.cos(v)) * np.cos(u)).ravel(), ((R + r * np.cos(v)) * np.sin(u)).ravel(), (r * np.sin(v)).ravel()]
    idx = lambda i, j: (i % nu) * nv + (j % nv)  # noqa: E731
    tri = []
    for i in range(nu):
        for j in range(nv):
            a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
            tri += [[a, b, c], [a, c, d]]
    return Mesh(pts, np.array(tri, dtype=np.int64))


def fan_mesh(k: int) -> Mesh:
    """``k`` counter-clockwise triangles around vertex 0 (open fan, k <= 7)."""
    ang = np.linspace(0, 1.5 * np.pi, k + 1)
    pts = np.r_[[[0.0, 0.0]], np.c_[np.cos(ang), np.sin(ang)]]
    tri = [[0, i, i + 1] for i in range(1, k + 1)]
    return Mesh(pts, np.array(tri, dtype=np.int64))


def zigzag_mesh(k: int) -> Mesh:
    """``k`` triangles of a zig-zag whose GL strip is 0, 1, ..., k + 1 (no swap)."""
    pts = np.array([[i // 2, 1 - i % 2] for i in range(k + 2)], dtype=float)
    tri = []
    for i in range(k):
        t = [i, i + 1, i + 2]
        if i % 2:
            t = [i + 1, i, i + 2]
        tri.append(t)
    return Mesh(pts, np.array(tri, dtype=np.int64))


#: Small meshes of every kind the round-trip tests draw from (planar quality, structured,
#: lifted to 3D, closed surface, fan), built on demand.
SMALL_MESHES = {
    "square": lambda: square_mesh(),
    "grid": lambda: grid_mesh(5, 4),
    "surface": lambda: grid_mesh(4, 4, z=True),
    "torus": lambda: torus_mesh(),
    "fan": lambda: fan_mesh(7),
}


def oriented_set(tri) -> list[tuple[int, int, int]]:
    """Sorted list of triangles, each rotated to start at its least vertex (independent of hammesh)."""
    out = []
    for a, b, c in np.asarray(tri).tolist():
        r = [a, b, c]
        i = r.index(min(r))
        out.append(tuple(r[i:] + r[:i]))
    return sorted(out)


def gl_decode_reference(indices, restart=None) -> list[tuple[int, int, int]]:
    """Plain-Python OpenGL GL_TRIANGLE_STRIP semantics (for cross-checking the decoder)."""
    out, strip = [], []
    for x in list(indices) + ([restart] if restart is not None else []):
        if restart is not None and x == restart:
            for i in range(len(strip) - 2):
                a, b, c = strip[i : i + 3]
                if len({a, b, c}) == 3:
                    out.append((b, a, c) if i % 2 else (a, b, c))
            strip = []
        else:
            strip.append(int(x))
    if restart is None:
        for i in range(len(strip) - 2):
            a, b, c = strip[i : i + 3]
            if len({a, b, c}) == 3:
                out.append((b, a, c) if i % 2 else (a, b, c))
    return out


def random_path_cover(nbr: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Random partition of the dual graph into paths (random walks on unvisited triangles)."""
    m = len(nbr)
    seen = np.zeros(m, bool)
    order, starts = [], [0]
    for s in rng.permutation(m):
        if seen[s]:
            continue
        t = int(s)
        seen[t] = True
        order.append(t)
        while True:
            cand = [int(u) for u in nbr[t] if u >= 0 and not seen[u]]
            if not cand:
                break
            t = cand[rng.integers(len(cand))]
            seen[t] = True
            order.append(t)
        starts.append(len(order))
    return np.array(order), np.array(starts)


@pytest.fixture(scope="session")
def square():
    return square_mesh()


@pytest.fixture(scope="session")
def square_ham():
    return square_hamiltonian()


def corrupt_claim(idx, claim, corrupt, rng, n_points, restart):
    """A strip buffer and draw claim with one fault (``corrupt``): 0 none, 1 a wrong index in
    the buffer, 2 a wrong claim (reversed), 3 a triangle missing from the end, 4 one row
    claimed twice and another never.  Returns new ``(idx, claim)``."""
    idx, claim = idx.copy(), np.array(claim).copy()
    if corrupt == 1:
        i = int(rng.integers(len(idx)))
        if idx[i] != restart:
            idx[i] = (idx[i] + 1) % n_points
    elif corrupt == 2:
        claim = claim[::-1].copy()
    elif corrupt == 3:
        idx = idx[:-1]
    elif corrupt == 4:
        claim[0] = claim[-1]
    return idx, claim
