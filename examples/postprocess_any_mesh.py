"""Turn a mesh made elsewhere (here: scipy's Delaunay of random points) into a
Hamiltonian cycle mesh and walk it as one strip of triangles.

    python examples/postprocess_any_mesh.py [OUTDIR]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy.spatial import Delaunay

import hammesh


def main(out: Path) -> hammesh.HamiltonianMesh:
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(42)
    pts = rng.random((500, 2))
    mesh = hammesh.Mesh(points=pts, triangles=Delaunay(pts).simplices.astype(np.int64))
    hammesh.write(mesh, out / "delaunay.vtu")
    h = hammesh.hamiltonian(hammesh.read_mesh(out / "delaunay.vtu"))
    hammesh.write(h, out / "hamiltonian.obj")
    # consecutive triangles share an edge: each step adds exactly one new vertex
    new = [len(set(h.triangles[i + 1]) - set(h.triangles[i])) for i in range(h.n_triangles - 1)]
    print(f"{h.n_triangles} triangles; new vertices per step: {sorted(set(new))}")
    return h


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("example-out"))
