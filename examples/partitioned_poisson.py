"""A partitioned two-material Poisson solve driven by hammesh's tags (scikit-fem).

``-div(kappa grad u) = 0`` on a plate with a hole: two materials (regions 1 and 2,
``kappa`` 1 and 20) meet along an interface segment (marker 5).  The boundary markers
choose the boundary conditions by name:

* ``marker_4`` (left side): Dirichlet ``u = 0``;  ``marker_2`` (right side): ``u = 1``;
* ``marker_1`` (bottom): Neumann, an inflow ``kappa du/dn = 0.5``;
* ``marker_3`` (top) and ``marker_6`` (the hole): Neumann, insulated.

``hammesh.to_skfem`` hands over the mesh with these names; the Hamiltonian cycle is cut
into ``k`` contiguous pieces by ``hammesh.partition`` (connected by construction, sizes equal to within one
triangle), each piece assembles its own elements (as a process of a distributed
solver would), and the sum is solved by conjugate gradients with a one-level additive
Schwarz preconditioner over the pieces.  It checks that the assembled pieces add up to
the whole matrix, that the partitioned solve matches a direct solve, that every piece
is connected, and that the interface (marker 5) has length 1; it writes
``OUTDIR/plate.vtu`` with ``u`` and ``part``.  Needs ``pip install hammesh[fem]``.

    python examples/partitioned_poisson.py [OUTDIR] [--parts K] [--max-area A]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import hammesh

#: outer ring (counter-clockwise) and one marker per side: bottom, bottom, right, top, top, left
OUTER = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0], [0.0, 1.0]]
SIDE_MARKERS = [1, 1, 2, 3, 3, 4]
HOLE = [[1.4, 0.3], [1.7, 0.3], [1.7, 0.7], [1.4, 0.7]]
KAPPA = {"region_1": 1.0, "region_2": 20.0}


def domain() -> hammesh.Domain:
    """The plate, its hole (marker 6), the interface x = 1 (marker 5) and two regions."""
    dom = hammesh.Domain.from_polygon(
        OUTER, holes=[HOLE], internal_segments=[[[1.0, 0.0], [1.0, 1.0]]],
        ring_markers=[SIDE_MARKERS, 6], internal_markers=[5],
    )
    regions = [[0.5, 0.5, 1.0, np.nan], [1.2, 0.5, 2.0, np.nan]]  # x, y, attribute, max area
    return hammesh.Domain(dom.vertices, dom.segments, dom.holes, regions,
                          segment_markers=dom.segment_markers, vertex_markers=dom.vertex_markers)


def main(out: Path, parts: int = 8, max_area: float = 1e-3) -> hammesh.HamiltonianMesh:
    import meshio
    from scipy.sparse import diags
    from scipy.sparse.csgraph import connected_components
    from scipy.sparse.linalg import LinearOperator, cg, splu, spsolve
    from skfem import Basis, BilinearForm, ElementTriP1, FacetBasis, LinearForm, asm
    from skfem.helpers import dot, grad

    out.mkdir(parents=True, exist_ok=True)
    h = hammesh.hamiltonian(hammesh.quality_mesh(domain(), min_angle=30, max_area=max_area))
    mesh = hammesh.to_skfem(h)  # boundaries "marker_<k>", subdomains "region_<a>"
    element = ElementTriP1()
    basis = Basis(mesh, element)

    @BilinearForm
    def stiffness(u, v, w):
        return w.kappa * dot(grad(u), grad(v))

    @LinearForm
    def inflow(v, w):
        return 0.5 * v

    # --- the pieces of the cycle: connected, balanced ---------------------------------
    pieces = hammesh.partition(h, parts)  # contiguous stretches of the cycle, checked connected
    part = pieces.part
    dual = hammesh.dual_graph(h)
    sizes = np.bincount(part, minlength=parts)
    for p in range(parts):  # connectivity again, here from scikit-fem's side of the hand-off
        rows = np.flatnonzero(part == p)
        n_pieces, _ = connected_components(dual[rows][:, rows], directed=False)
        assert n_pieces == 1, f"part {p} is not connected"
    assert pieces.connected
    rows, cols = dual.nonzero()
    cut = int(np.count_nonzero(part[rows] != part[cols]) // 2)
    assert cut == pieces.edge_cut

    # --- each piece assembles its own elements, material by region name ----------------
    A = None
    for p in range(parts):
        for region, kappa in KAPPA.items():
            elements = np.intersect1d(np.flatnonzero(part == p), mesh.subdomains[region])
            if len(elements):
                local = asm(stiffness, Basis(mesh, element, elements=elements), kappa=kappa)
                A = local if A is None else A + local
    whole = sum(asm(stiffness, Basis(mesh, element, elements=mesh.subdomains[r]), kappa=kappa)
                for r, kappa in KAPPA.items())
    assert abs(A - whole).max() < 1e-12 * abs(whole).max()
    b = asm(inflow, FacetBasis(mesh, element, facets=mesh.boundaries["marker_1"]))

    # --- Dirichlet sides by name, the rest of the boundary is Neumann -------------------
    u = np.zeros(basis.N)
    left = basis.get_dofs(mesh.boundaries["marker_4"]).all()
    right = basis.get_dofs(mesh.boundaries["marker_2"]).all()
    u[right] = 1.0
    fixed = np.union1d(left, right)
    free = np.setdiff1d(np.arange(basis.N), fixed)
    K = A[free][:, free].tocsc()
    rhs = b[free] - A[free][:, fixed] @ u[fixed]
    direct = spsolve(K, rhs)

    # one-level additive Schwarz: a local solve on the free dofs of each piece's triangles
    where = np.full(basis.N, -1)
    where[free] = np.arange(len(free))
    local = []
    for p in range(parts):
        dofs = np.unique(where[mesh.t[:, part == p]])
        dofs = dofs[dofs >= 0]
        local.append((dofs, splu(K[dofs][:, dofs].tocsc())))

    def schwarz(r: np.ndarray) -> np.ndarray:
        z = np.zeros_like(r)
        for dofs, lu in local:
            z[dofs] += lu.solve(r[dofs])
        return z

    counts = {}
    for name, M in (("Jacobi", diags(1.0 / K.diagonal())), ("additive Schwarz", LinearOperator(K.shape, schwarz, dtype=np.float64))):
        iterations = []
        x, info = cg(K, rhs, M=M, rtol=1e-10, maxiter=5000, callback=lambda xk: iterations.append(1))
        assert info == 0, f"CG ({name}) did not converge"
        assert np.abs(x - direct).max() < 1e-6, name
        counts[name] = len(iterations)
    u[free] = direct

    # the interface between the materials: an interior named boundary of length 1
    ends = mesh.p[:, mesh.facets[:, mesh.boundaries["marker_5"]]]
    interface = float(np.hypot(*(ends[:, 1] - ends[:, 0])).sum())
    assert abs(interface - 1.0) < 1e-12

    print(f"{h.n_triangles} triangles, {basis.N} dofs, {parts} parts of {sizes.min()}-{sizes.max()} "
          f"triangles, all connected, dual edge cut {cut}")
    print(f"Dirichlet dofs: {len(left)} (marker_4, u = 0) + {len(right)} (marker_2, u = 1); "
          f"interface (marker_5) length {interface:.6f}")
    print("CG iterations: " + ", ".join(f"{name} {n}" for name, n in counts.items()))
    print(f"u in [{u.min():.4f}, {u.max():.4f}]")

    data = hammesh.to_meshio(h)
    data.point_data["u"] = u
    data.cell_data["part"] = [part]
    meshio.write(out / "plate.vtu", data)
    return h


if __name__ == "__main__":
    args = sys.argv[1:]
    options = {"--parts": ("parts", int), "--max-area": ("max_area", float)}
    kwargs = {}
    for flag, (name, cast) in options.items():
        if flag in args:
            i = args.index(flag)
            kwargs[name] = cast(args[i + 1])
            del args[i : i + 2]
    main(Path(args[0]) if args else Path("partitioned-poisson"), **kwargs)
