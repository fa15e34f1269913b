"""Strip encodings: indices per triangle and time, ours vs VTK's vtkStripper and pyffi's NvTriStrip.

    python benchmarks/bench_strips.py            # all meshes
    python benchmarks/bench_strips.py --quick    # small meshes only

Ours: :func:`hammesh.strips.encode` (greedy dual paths, restart join; the time excludes
verification, which is reported apart).  VTK: ``pyvista.PolyData.strip()`` (vtkStripper),
counted as its strips joined with one restart index each.  pyffi: ``pyffi.utils.tristrip
.stripify`` + restart join.  Competitors missing from the environment are skipped.  The
first call of ours pays numba's one-off compile (cached afterwards); a warm-up run is made.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import hammesh
from hammesh.mesh import Mesh
from hammesh.strips import encode, verify_gl_strip


def planar(max_area: float, poly=((0, 0), (1, 0), (1, 1), (0, 1))) -> Mesh:
    return hammesh.quality_mesh(hammesh.Domain.from_polygon([list(p) for p in poly]), min_angle=30, max_area=max_area)


#: Triangle's bundled PSLGs (``triangle.get_data``) and the max area giving ~12k triangles
#: at min angle 30.
BUNDLED = {
    "A": 1.1e-5,
    "la": 0.064,
    "face": 2.7,
    "double_hex": 1.25e-4,
    "square_circle_hole": 5.9e-3,
    "spiral": 2.5e-3,
}


def bundled(name: str, max_area: float) -> Mesh | None:
    try:
        import triangle
    except ImportError:
        return None
    d = triangle.get_data(name)
    kw = {k: d[k] for k in ("segments", "holes") if k in d}
    dom = hammesh.Domain(vertices=d["vertices"], **kw)
    return hammesh.quality_mesh(dom, min_angle=30, max_area=max_area)


def torus(nu: int, nv: int) -> Mesh:
    u, v = np.meshgrid(np.arange(nu) * 2 * np.pi / nu, np.arange(nv) * 2 * np.pi / nv, indexing="ij")
    R, r = 2.0, 0.7
    pts = np.c_[((R + r * np.cos(v)) * np.cos(u)).ravel(), ((R + r * np.cos(v)) * np.sin(u)).ravel(), (r * np.sin(v)).ravel()]
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    i, j = i.ravel(), j.ravel()
    idx = lambda a, b: (a % nu) * nv + (b % nv)  # noqa: E731
    a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
    return Mesh(pts, np.r_[np.c_[a, b, c], np.c_[a, c, d]])


def icosphere(nsub: int) -> Mesh | None:
    try:
        import pyvista as pv
    except ImportError:
        return None
    s = pv.Icosphere(nsub=nsub)
    return Mesh(np.asarray(s.points, dtype=float), np.asarray(s.faces).reshape(-1, 4)[:, 1:].astype(np.int64))


def bumpy_sphere(n: int, seed: int = 0) -> Mesh:
    """A closed 'scanned-like' surface: convex hull of jittered sphere points, then bumps."""
    from scipy.spatial import ConvexHull

    rng = np.random.default_rng(seed)
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1)[:, None]
    hull = ConvexHull(p)
    tri = hull.simplices.astype(np.int64)
    c = p[tri].mean(axis=1)
    nrm = np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]])
    flip = (nrm * c).sum(axis=1) < 0
    tri[flip] = tri[flip][:, ::-1]
    p = p * (1 + 0.05 * np.sin(7 * p[:, :1]) * np.cos(5 * p[:, 1:2]))
    return Mesh(p, tri)


def ours(mesh: Mesh) -> tuple[float, float, float]:
    t = time.perf_counter()
    s = encode(mesh, verify=False)
    dt = time.perf_counter() - t
    t = time.perf_counter()
    verify_gl_strip(mesh.triangles, s.indices, s.restart_index)
    return s.indices_per_triangle, dt, time.perf_counter() - t


def vtk(mesh: Mesh) -> tuple[float, float] | None:
    try:
        import pyvista as pv
    except ImportError:
        return None
    pts = mesh.points if mesh.points.shape[1] == 3 else np.c_[mesh.points, np.zeros(len(mesh.points))]
    poly = pv.PolyData(pts, np.c_[np.full(len(mesh.triangles), 3), mesh.triangles].ravel())
    t = time.perf_counter()
    out = poly.strip()
    dt = time.perf_counter() - t
    strips = np.asarray(out.strips)
    n_idx, n_strips, i = 0, 0, 0
    while i < len(strips):
        k = int(strips[i])
        n_idx += k
        n_strips += 1
        i += k + 1
    # triangles vtkStripper left out of strips stay as polys (3 indices + a restart each)
    n_polys = len(np.asarray(out.faces)) // 4
    total = n_idx + max(n_strips - 1, 0) + 4 * n_polys
    return total / len(mesh.triangles), dt


def pyffi(mesh: Mesh) -> tuple[float, float] | None:
    try:
        from pyffi.utils import tristrip
    except ImportError:
        return None
    tris = [tuple(t) for t in mesh.triangles.tolist()]
    t = time.perf_counter()
    strips = tristrip.stripify(tris, stitchstrips=False)
    dt = time.perf_counter() - t
    total = sum(len(s) for s in strips) + max(len(strips) - 1, 0)
    return total / len(tris), dt


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    meshes: dict[str, Mesh | None] = {
        "square a=1e-3": planar(1e-3),
        "L-shape a=1e-3": planar(1e-3, ((0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2))),
        "torus 4k": torus(60, 40),
        "icosphere nsub=3": icosphere(3),
        "bumpy sphere 10k": bumpy_sphere(5000),
    }
    if not args.quick:
        meshes.update(
            {
                "square a=1e-4": planar(1e-4),
                **{name: bundled(name, a) for name, a in BUNDLED.items()},
                "icosphere nsub=5": icosphere(5),
                "torus 100k": torus(320, 160),
            }
        )
    encode(meshes["torus 4k"])  # warm-up (numba)
    rows = []
    for name, mesh in meshes.items():
        if mesh is None:
            continue
        o = ours(mesh)
        v = vtk(mesh)
        f = pyffi(mesh) if mesh.n_triangles <= 20000 else None
        rows.append((name, mesh.n_triangles, o, v, f))
    head = f"{'mesh':<20}{'triangles':>10} | {'ours ipt':>9}{'time s':>8}{'verify s':>9} | {'vtk ipt':>8}{'time s':>8} | {'pyffi ipt':>9}{'time s':>8}"
    print(head)
    print("-" * len(head))
    for name, m, o, v, f in rows:
        vs = f"{v[0]:>8.3f}{v[1]:>8.3f}" if v else f"{'-':>8}{'-':>8}"
        fs = f"{f[0]:>9.3f}{f[1]:>8.3f}" if f else f"{'-':>9}{'-':>8}"
        print(f"{name:<20}{m:>10,} | {o[0]:>9.3f}{o[1]:>8.3f}{o[2]:>9.3f} | {vs} | {fs}")


if __name__ == "__main__":
    main()
