"""Real-world surface defects built in numpy (no pyvista needed): issue 12's 3D surfaces.

Each builder returns ``(points (n, 3), triangles (m, 3), expected)`` where ``expected``
holds the defect counts the construction puts in by design (the tests compare
:class:`hammesh.strips.defects.MeshDefects` with them).  Stand-ins for pyvista's data:
``finned_torus(132)`` for the Stanford bunny's 132 non-manifold edges, ``pole_sphere``
for the globe's zero-area pole triangles, ``klein_bottle`` / ``mobius_strip`` for the
parametric non-orientable surfaces.
"""

from __future__ import annotations

import numpy as np

from hammesh.surface.shapes import torus


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


def mobius_strip(nu: int = 24, nv: int = 5):
    """A Möbius band: the seam glues row ``j`` to ``nv - 1 - j``: ``nv - 1`` flipped neighbours."""
    u = np.arange(nu) * 2 * np.pi / nu
    v = np.linspace(-1, 1, nv)
    uu, vv = np.meshgrid(u, v, indexing="ij")
    r = 1 + 0.4 * vv * np.cos(uu / 2)
    pts = np.stack([r * np.cos(uu), r * np.sin(uu), 0.4 * vv * np.sin(uu / 2)], -1).reshape(-1, 3)
    tri = _grid_band(nu, nv, lambda j: nv - 1 - j, wrap_v=False)
    return pts, tri, {"flipped_neighbours": nv - 1, "non_orientable_pieces": 1, "non_manifold_edges": 0}


def klein_bottle(nu: int = 24, nv: int = 12):
    """Figure-8 Klein bottle: ``(u + 2 pi, v) ~ (u, -v)``; closed, one piece, not orientable."""
    u = np.arange(nu) * 2 * np.pi / nu
    v = np.arange(nv) * 2 * np.pi / nv
    uu, vv = np.meshgrid(u, v, indexing="ij")
    r = 3 + np.cos(uu / 2) * np.sin(vv) - np.sin(uu / 2) * np.sin(2 * vv)
    z = np.sin(uu / 2) * np.sin(vv) + np.cos(uu / 2) * np.sin(2 * vv)
    pts = np.stack([r * np.cos(uu), r * np.sin(uu), z], -1).reshape(-1, 3)
    tri = _grid_band(nu, nv, lambda j: (-j) % nv, wrap_v=True)
    return pts, tri, {"flipped_neighbours": nv, "non_orientable_pieces": 1, "non_manifold_edges": 0}


def finned_torus(n_fins: int = 132, nu: int = 48, nv: int = 24, seed: int = 0):
    """A torus with ``n_fins`` extra triangles, each on its own torus edge: that many non-manifold edges."""
    pts, tri = torus(nu, nv)
    rng = np.random.default_rng(seed)
    e = np.sort(tri[:, [0, 1]], axis=1)
    e = np.unique(e, axis=0)
    pick = e[rng.choice(len(e), n_fins, replace=False)]
    apex = pts[pick].mean(axis=1) * 1.3 + rng.normal(0, 0.01, (n_fins, 3))
    fins = np.c_[pick, len(pts) + np.arange(n_fins)]
    return np.r_[pts, apex], np.r_[tri, fins].astype(np.int64), {"non_manifold_edges": n_fins, "flipped_neighbours": 0}


def pole_sphere(nu: int = 16, nv: int = 9):
    """A UV sphere whose poles are ``nu`` coincident points each (as pyvista's globe): ``2 nu`` zero-area triangles."""
    u = np.arange(nu) * 2 * np.pi / nu
    v = np.linspace(0, np.pi, nv)
    uu, vv = np.meshgrid(u, v, indexing="ij")
    pts = np.stack([np.sin(vv) * np.cos(uu), np.sin(vv) * np.sin(uu), np.cos(vv)], -1).reshape(-1, 3)
    pts[:, :2][np.abs(np.sin(vv.reshape(-1))) < 1e-12] = 0.0  # the poles exactly
    tri = _grid_band(nu, nv, lambda j: j, wrap_v=False)
    return pts, tri, {"zero_area": 2 * nu, "non_manifold_edges": 0, "flipped_neighbours": 0}


def flipped_triangle(seed: int = 3):
    """A torus with one interior triangle reversed: its three edges are flipped neighbours."""
    pts, tri = torus(16, 10)
    tri = tri.copy()
    tri[seed] = tri[seed, ::-1]
    return pts, tri, {"flipped_neighbours": 3, "non_orientable_pieces": 0, "non_manifold_edges": 0}


def double_sided(seed: int = 5):
    """A torus, one triangle doubled with the opposite winding, and a loose two-sided triangle (a pillow)."""
    pts, tri = torus(16, 10)
    extra = np.array([[0.0, 0.0, 2.0], [1.0, 0.0, 2.0], [0.0, 1.0, 2.5]])
    n = len(pts)
    tri = np.r_[tri, tri[seed : seed + 1, ::-1], [[n, n + 1, n + 2], [n, n + 2, n + 1]]].astype(np.int64)
    return np.r_[pts, extra], tri, {"double_sided": 2, "non_manifold_edges": 3, "flipped_neighbours": 0}


def duplicate_and_repeated():
    """A torus with one triangle listed twice (same winding) and one row repeating a vertex."""
    pts, tri = torus(16, 10)
    tri = np.r_[tri, tri[7:8], [[1, 1, 2]]].astype(np.int64)
    return pts, tri, {"duplicate": 1, "repeated_vertex": 1, "non_manifold_edges": 3}


ALL = {
    "mobius": mobius_strip,
    "klein": klein_bottle,
    "finned torus (bunny stand-in)": finned_torus,
    "pole sphere (globe stand-in)": pole_sphere,
    "one flipped triangle": flipped_triangle,
    "double-sided faces": double_sided,
    "duplicate + repeated vertex": duplicate_and_repeated,
}
