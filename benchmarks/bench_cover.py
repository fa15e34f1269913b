"""Cycle-cover benchmark (issue 13's speed, the cover's share): the sparse mode's cover vs Triangle.

Meshes the plate with two holes of ``bench_partition.py`` with Triangle (min angle
30) at about ``--target`` triangles (default 1.5 M), timing Triangle (the peer, first
call in this process), then times ``cycle_cover`` on it: the first call (kernels
loaded from numba's cache), then ``--repeat`` rounds alternating the current cover
with ``online=0`` (the matching before session 6: Triangle's numbering, augmenting
searches afterwards), so both are measured under the same load. Prints each time,
the ratios cover / Triangle, and the cover's shape: cycles, uncovered triangles,
triangles left free by the matching, and the largest cycle's share (a winding
cover: issue 14).

    python benchmarks/bench_cover.py [--target 1500000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--target", type=int, default=1_500_000, help="triangles of the input mesh")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    import hammesh
    from hammesh.halfedge import half_edges
    from hammesh.postprocess.cycle_cover import cycle_cover

    a = np.linspace(0, 2 * np.pi, 48, endpoint=False)
    circ = np.c_[np.cos(a), np.sin(a)]
    plate = hammesh.Domain.from_polygon(
        [[0, 0], [4, 0], [4, 2], [0, 2]], holes=[circ * 0.45 + [1, 1], circ * 0.3 + [3, 1]]
    )
    area = 8.0 - np.pi * (0.45**2 + 0.3**2)
    t = time.perf_counter()
    mesh = hammesh.quality_mesh(plate, min_angle=30, max_area=area / (0.63 * args.target))
    t_tri = time.perf_counter() - t
    tri = mesh.triangles
    twin = half_edges(tri, mesh.n_points).twin

    def run(online: int):
        t = time.perf_counter()
        c = cycle_cover(tri, twin, online=online)
        dt = time.perf_counter() - t
        big = np.bincount(c.cycle[c.cycle >= 0]).max() if c.n_cycles else 0
        return dt, c, big / len(tri)

    dt, c, share = run(256)
    print(f"m = {len(tri):,}; Triangle (quality_mesh, first call) {t_tri:.3f} s")
    print(f"cover, first call: {dt:.3f} s = {dt / t_tri:.3f} x Triangle; cycles {c.n_cycles:,}, "
          f"uncovered {c.n_uncovered}, unmatched {c.n_unmatched}, largest cycle {share:.1%} of the triangles")
    best = {256: np.inf, 0: np.inf}
    for _ in range(args.repeat):
        for online in (0, 256):
            dt, c, share = run(online)
            best[online] = min(best[online], dt)
            name = "current" if online else "online=0"
            print(f"  {name:8s} {dt:.3f} s: cycles {c.n_cycles:,}, uncovered {c.n_uncovered}, "
                  f"largest cycle {share:.1%}", flush=True)
    print(f"best of {args.repeat}: current {best[256]:.3f} s = {best[256] / t_tri:.3f} x Triangle; "
          f"online=0 {best[0]:.3f} s = {best[0] / t_tri:.3f} x Triangle; speed-up {best[0] / best[256]:.2f}x")


if __name__ == "__main__":
    main()
