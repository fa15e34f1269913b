"""Solve a PDE on a Hamiltonian mesh: P1 Poisson with scikit-fem, against Triangle's mesh.

``-Δu = f`` on the unit square with a circular hole, ``u = g`` on the boundary, with
the exact solution ``u = sin(πx) sin(πy)``. The same Triangle mesh (min angle 30) is
solved as it is and after ``hammesh.hamiltonian`` in sparse mode (the default) and in
incircle mode (Thm 2.4's construction); the L2 and H1 errors are printed side by
side. Needs the optional extra ``pip install hammesh[fem]`` (scikit-fem).

    python examples/poisson_skfem.py [OUTDIR] [--max-area A]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import hammesh


def exact(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.sin(np.pi * x) * np.sin(np.pi * y)


def poisson_errors(points: np.ndarray, triangles: np.ndarray) -> tuple[float, float]:
    """(L2 error, H1-seminorm error) of P1 Poisson on one mesh (scikit-fem)."""
    from skfem import Basis, ElementTriP1, Functional, LinearForm, MeshTri, asm, condense, solve
    from skfem.models.poisson import laplace

    mesh = MeshTri(np.ascontiguousarray(points.T), np.ascontiguousarray(triangles.T))
    basis = Basis(mesh, ElementTriP1(), intorder=4)

    @LinearForm
    def load(v, w):
        x, y = w.x
        return 2 * np.pi**2 * exact(x, y) * v

    A = asm(laplace, basis)
    b = asm(load, basis)
    u = np.zeros(basis.N)
    boundary = basis.get_dofs().all()
    u[boundary] = exact(*mesh.p[:, boundary])  # P1 nodal values on the boundary
    u = solve(*condense(A, b, x=u, D=boundary))

    @Functional
    def l2(w):
        x, y = w.x
        return (w["uh"] - exact(x, y)) ** 2

    @Functional
    def h1(w):
        x, y = w.x
        gx = np.pi * np.cos(np.pi * x) * np.sin(np.pi * y)
        gy = np.pi * np.sin(np.pi * x) * np.cos(np.pi * y)
        return (w["uh"].grad[0] - gx) ** 2 + (w["uh"].grad[1] - gy) ** 2

    uh = basis.interpolate(u)
    return float(np.sqrt(l2.assemble(basis, uh=uh))), float(np.sqrt(h1.assemble(basis, uh=uh)))


def domain() -> hammesh.Domain:
    """The unit square with a hole of radius 0.2 at (0.55, 0.45) (64-gon)."""
    a = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    hole = np.c_[0.55 + 0.2 * np.cos(a), 0.45 + 0.2 * np.sin(a)]
    return hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]], holes=[hole])


def main(out: Path, max_area: float = 2e-4) -> hammesh.HamiltonianMesh:
    out.mkdir(parents=True, exist_ok=True)
    mesh = hammesh.quality_mesh(domain(), min_angle=30, max_area=max_area)
    sparse = hammesh.hamiltonian(mesh, mode="sparse")
    incircle = hammesh.hamiltonian(mesh, mode="incircle")
    # incircle triples the triangles: compare it with a Triangle mesh of that size too
    fine = hammesh.quality_mesh(domain(), min_angle=30, max_area=max_area * mesh.n_triangles / incircle.n_triangles)
    errors = {}
    print(f"{'mesh':<24}{'triangles':>10}{'L2 error':>12}{'H1 error':>12}{'L2 ratio':>10}{'H1 ratio':>10}")
    for name, m, ref in (
        ("Triangle q30", mesh, None),
        ("hamiltonian sparse", sparse, "Triangle q30"),
        ("Triangle q30 finer", fine, None),
        ("hamiltonian incircle", incircle, "Triangle q30 finer"),
    ):
        errors[name] = poisson_errors(m.points, m.triangles)
        e2, e1 = errors[name]
        r2, r1 = (e2 / errors[ref][0], e1 / errors[ref][1]) if ref else (1.0, 1.0)
        print(f"{name:<24}{m.n_triangles:>10,}{e2:>12.4e}{e1:>12.4e}{r2:>10.3f}{r1:>10.3f}")
    print("ratios: against the Triangle mesh of about the same size (sparse: its own input)")
    hammesh.write(sparse, out / "poisson_hamiltonian.vtu")
    return sparse


if __name__ == "__main__":
    args = sys.argv[1:]
    area = 2e-4
    if "--max-area" in args:
        i = args.index("--max-area")
        area = float(args[i + 1])
        del args[i : i + 2]
    main(Path(args[0]) if args else Path("example-out"), area)
