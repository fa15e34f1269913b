"""Mesh a plate with two holes and an interface loop, make it Hamiltonian, save it.

    python examples/plate_with_holes.py [OUTDIR]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import hammesh
from hammesh.plot import plot_cycle


def plate() -> hammesh.Domain:
    outer = [[0, 0], [4, 0], [4, 2], [0, 2]]
    t = np.linspace(0, 2 * np.pi, 32, endpoint=False)
    circle = np.c_[1.0 + 0.4 * np.cos(t), 1.0 + 0.4 * np.sin(t)]
    square_hole = [[2.6, 0.6], [3.2, 0.6], [3.2, 1.2], [2.6, 1.2]]
    return hammesh.Domain.from_polygon(outer, holes=[circle, square_hole])


def main(out: Path) -> hammesh.HamiltonianMesh:
    out.mkdir(parents=True, exist_ok=True)
    mesh = hammesh.quality_mesh(plate(), min_angle=30, max_area=0.005)
    h = hammesh.hamiltonian(mesh)
    hammesh.write(h, out / "plate.vtu")
    plot_cycle(h, out / "plate.png")
    r = h.report
    print(f"{r['input_triangles']} -> {r['triangles']} triangles, {len(r['components'])} cycle(s), "
          f"min angle {r['min_angle_input_deg']:.1f} -> {r['min_angle_output_deg']:.1f} deg")
    return h


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("example-out"))
