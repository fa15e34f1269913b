"""Test and benchmark surfaces: closed, with boundary, of genus 0, 1 and 2, and real-world defects.

Plain arrays out: ``points (n, 3) float64``, ``triangles (m, 3) int64``; consistently
oriented (outward normals on closed surfaces) except the defect surfaces (issue 12),
stand-ins for pyvista's data built in numpy: :func:`mobius_strip` and
:func:`klein_bottle` (not orientable: flipped neighbours on their seam),
:func:`finned_torus` (``n_fins`` non-manifold edges: 132 as the Stanford bunny),
:func:`pole_sphere` (coincident pole points: zero-area triangles, as the globe),
:func:`flipped_triangle`, :func:`double_sided` and :func:`duplicate_and_repeated`.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "icosphere",
    "torus",
    "thick_plate",
    "noisy_sphere",
    "mobius_strip",
    "klein_bottle",
    "finned_torus",
    "pole_sphere",
    "flipped_triangle",
    "double_sided",
    "duplicate_and_repeated",
]


def icosphere(nsub: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Unit icosphere: the icosahedron, each face split in 4 ``nsub`` times (20 * 4**nsub faces)."""
    p = (1 + 5**0.5) / 2
    pts = np.array(
        [[-1, p, 0], [1, p, 0], [-1, -p, 0], [1, -p, 0], [0, -1, p], [0, 1, p],
         [0, -1, -p], [0, 1, -p], [p, 0, -1], [p, 0, 1], [-p, 0, -1], [-p, 0, 1]], float
    )
    tri = np.array(
        [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]], np.int64
    )
    pts /= np.linalg.norm(pts, axis=1)[:, None]
    for _ in range(int(nsub)):
        e = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
        key = np.sort(e, axis=1)
        uniq, inv = np.unique(key, axis=0, return_inverse=True)
        mid = pts[uniq].mean(axis=1)
        mid /= np.linalg.norm(mid, axis=1)[:, None]
        m = len(tri)
        ids = len(pts) + inv.reshape(-1)
        ab, bc, ca = ids[:m], ids[m : 2 * m], ids[2 * m :]
        a, b, c = tri.T
        tri = np.concatenate([np.c_[a, ab, ca], np.c_[ab, b, bc], np.c_[ca, bc, c], np.c_[ab, bc, ca]])
        pts = np.concatenate([pts, mid])
    return pts, tri


def torus(nu: int = 48, nv: int = 24, *, R: float = 1.0, r: float = 0.4, hole: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Torus of ``2 nu nv`` triangles; ``hole=True`` removes a 3 x 3 patch (one boundary loop)."""
    u = np.arange(nu) * 2 * np.pi / nu
    v = np.arange(nv) * 2 * np.pi / nv
    uu, vv = np.meshgrid(u, v, indexing="ij")
    pts = np.stack([(R + r * np.cos(vv)) * np.cos(uu), (R + r * np.cos(vv)) * np.sin(uu), r * np.sin(vv)], -1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    i, j = i.reshape(-1), j.reshape(-1)
    idx = lambda a, b: (a % nu) * nv + (b % nv)  # noqa: E731
    p00, p10, p01, p11 = idx(i, j), idx(i + 1, j), idx(i, j + 1), idx(i + 1, j + 1)
    alt = (i + j) % 2 == 0  # alternate the diagonals
    t1 = np.where(alt[:, None], np.c_[p00, p10, p11], np.c_[p00, p10, p01])
    t2 = np.where(alt[:, None], np.c_[p00, p11, p01], np.c_[p10, p11, p01])
    keep = np.ones(len(i), bool)
    if hole:
        keep &= ~((i >= 2) & (i < 5) & (j >= 2) & (j < 5))
    tri = np.concatenate([t1[keep], t2[keep]]).astype(np.int64)
    return pts, tri


def thick_plate(max_area: float = 0.004, thickness: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """Closed genus-2 surface: a quality-meshed plate with two holes, top, bottom and walls."""
    import hammesh

    sq = lambda x, y, s: [[x, y], [x + s, y], [x + s, y + s], [x, y + s]]  # noqa: E731
    dom = hammesh.Domain.from_polygon([[0, 0], [2, 0], [2, 1], [0, 1]], holes=[sq(0.3, 0.3, 0.4), sq(1.3, 0.3, 0.4)])
    m = hammesh.quality_mesh(dom, min_angle=30, max_area=max_area)
    p2, t = m.points, m.triangles
    n = len(p2)
    top = np.c_[p2, np.full(n, thickness / 2)]
    bot = np.c_[p2, np.full(n, -thickness / 2)]
    pts = np.concatenate([top, bot])
    # boundary half-edges a -> b (domain on the left): half-edges without twin
    e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    key = e[:, 0] * n + e[:, 1]
    rev = e[:, 1] * n + e[:, 0]
    bnd = e[~np.isin(key, rev)]
    a, b = bnd[:, 0], bnd[:, 1]
    walls = np.concatenate([np.c_[a + n, b + n, b], np.c_[a + n, b, a]])
    tri = np.concatenate([t, t[:, ::-1] + n, walls]).astype(np.int64)
    return pts, tri


def noisy_sphere(nsub: int = 5, noise: float = 0.25, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A "scanned" closed surface: an icosphere with bumps and per-vertex radial noise.

    ``noise`` is relative to the mean edge length; angles vary widely, as on scans.
    """
    pts, tri = icosphere(nsub)
    rng = np.random.default_rng(seed)
    h = np.linalg.norm(pts[tri[:, 0]] - pts[tri[:, 1]], axis=1).mean()
    bumps = 1 + 0.15 * np.sin(3 * pts[:, 0]) * np.cos(2 * pts[:, 1]) + 0.1 * np.sin(5 * pts[:, 2])
    radial = bumps + noise * h * rng.standard_normal(len(pts))
    tangent = noise * h * rng.standard_normal(pts.shape)
    tangent -= (tangent * pts).sum(axis=1)[:, None] * pts
    return pts * radial[:, None] + tangent, tri


def _grid_band(nu: int, nv: int, wrap_u, wrap_v: bool):
    """Quads of a ``nu x nv`` vertex grid, two triangles each, with the given wrap of ``u``.

    ``wrap_u(j)`` is the row that column 0 glues to (``None``: no wrap in ``u``).
    """
    tris = []
    for i in range(nu if wrap_u is not None else nu - 1):
        for j in range(nv if wrap_v else nv - 1):
            j1 = (j + 1) % nv
            if i == nu - 1:  # the seam: column 0 with its rows permuted
                p10, p11 = wrap_u(j), wrap_u(j1)
            else:
                p10, p11 = (i + 1) * nv + j, (i + 1) * nv + j1
            p00, p01 = i * nv + j, i * nv + j1
            tris += [[p00, p10, p11], [p00, p11, p01]]
    return np.array(tris, np.int64)


def mobius_strip(nu: int = 24, nv: int = 5) -> tuple[np.ndarray, np.ndarray]:
    """A Möbius band: the seam glues row ``j`` to ``nv - 1 - j``: ``nv - 1`` flipped neighbours."""
    u = np.arange(nu) * 2 * np.pi / nu
    v = np.linspace(-1, 1, nv)
    uu, vv = np.meshgrid(u, v, indexing="ij")
    r = 1 + 0.4 * vv * np.cos(uu / 2)
    pts = np.stack([r * np.cos(uu), r * np.sin(uu), 0.4 * vv * np.sin(uu / 2)], -1).reshape(-1, 3)
    tri = _grid_band(nu, nv, lambda j: nv - 1 - j, wrap_v=False)
    return pts, tri


def klein_bottle(nu: int = 24, nv: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """Figure-8 Klein bottle: ``(u + 2 pi, v) ~ (u, -v)``; closed, one piece, not orientable."""
    u = np.arange(nu) * 2 * np.pi / nu
    v = np.arange(nv) * 2 * np.pi / nv
    uu, vv = np.meshgrid(u, v, indexing="ij")
    r = 3 + np.cos(uu / 2) * np.sin(vv) - np.sin(uu / 2) * np.sin(2 * vv)
    z = np.sin(uu / 2) * np.sin(vv) + np.cos(uu / 2) * np.sin(2 * vv)
    pts = np.stack([r * np.cos(uu), r * np.sin(uu), z], -1).reshape(-1, 3)
    tri = _grid_band(nu, nv, lambda j: (-j) % nv, wrap_v=True)
    return pts, tri


def finned_torus(n_fins: int = 132, nu: int = 48, nv: int = 24, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A torus with ``n_fins`` extra triangles, each on its own torus edge: that many non-manifold edges."""
    pts, tri = torus(nu, nv)
    rng = np.random.default_rng(seed)
    e = np.sort(tri[:, [0, 1]], axis=1)
    e = np.unique(e, axis=0)
    pick = e[rng.choice(len(e), n_fins, replace=False)]
    apex = pts[pick].mean(axis=1) * 1.3 + rng.normal(0, 0.01, (n_fins, 3))
    fins = np.c_[pick, len(pts) + np.arange(n_fins)]
    return np.r_[pts, apex], np.r_[tri, fins].astype(np.int64)


def pole_sphere(nu: int = 16, nv: int = 9) -> tuple[np.ndarray, np.ndarray]:
    """A UV sphere whose poles are ``nu`` coincident points each (as pyvista's globe): ``2 nu`` zero-area triangles."""
    u = np.arange(nu) * 2 * np.pi / nu
    v = np.linspace(0, np.pi, nv)
    uu, vv = np.meshgrid(u, v, indexing="ij")
    pts = np.stack([np.sin(vv) * np.cos(uu), np.sin(vv) * np.sin(uu), np.cos(vv)], -1).reshape(-1, 3)
    pts[:, :2][np.abs(np.sin(vv.reshape(-1))) < 1e-12] = 0.0  # the poles exactly
    tri = _grid_band(nu, nv, lambda j: j, wrap_v=False)
    return pts, tri


def flipped_triangle(seed: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """A torus with one interior triangle reversed: its three edges are flipped neighbours."""
    pts, tri = torus(16, 10)
    tri = tri.copy()
    tri[seed] = tri[seed, ::-1]
    return pts, tri


def double_sided(seed: int = 5) -> tuple[np.ndarray, np.ndarray]:
    """A torus, one triangle doubled with the opposite winding, and a loose two-sided triangle (a pillow)."""
    pts, tri = torus(16, 10)
    extra = np.array([[0.0, 0.0, 2.0], [1.0, 0.0, 2.0], [0.0, 1.0, 2.5]])
    n = len(pts)
    tri = np.r_[tri, tri[seed : seed + 1, ::-1], [[n, n + 1, n + 2], [n, n + 2, n + 1]]].astype(np.int64)
    return np.r_[pts, extra], tri


def duplicate_and_repeated() -> tuple[np.ndarray, np.ndarray]:
    """A torus with one triangle listed twice (same winding) and one row repeating a vertex."""
    pts, tri = torus(16, 10)
    tri = np.r_[tri, tri[7:8], [[1, 1, 2]]].astype(np.int64)
    return pts, tri
