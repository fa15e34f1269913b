"""Cycle-cover benchmark (issue 13's speed, the cover's share): the sparse mode's cover vs Triangle.

Meshes the plate with two holes of ``bench_partition.py`` with Triangle (min angle
30) at about ``--target`` triangles (default 1.5 M), timing Triangle (the peer, first
call in this process), then times ``cycle_cover`` on it: the first call (kernels
loaded from numba's cache), then ``--repeat`` rounds of three settings under the same
load: the current cover (the two halves of the quadtree's top split on two threads,
parity defects fixed by dropped interior triangles), the same on one thread (no
points: no split), and without drops (``drop=False``: chains of boundary triangles).
Prints wall and process CPU seconds, the ratios to Triangle, and the cover's shape:
cycles, uncovered triangles (those with a boundary edge, those dropped), and the
largest cycle's share (a winding cover: issue 14).

    python benchmarks/bench_cover.py [--target 1500000] [--repeat 3]
    python benchmarks/bench_cover.py --cells 0,1024,256 [--target 100000]

``--cells``: the cover's cycles confined to quadtree cells of about S triangles
(``cycle_cover.CELL_SIZE``; 0: unconfined, the default) on ``bench_partition.py``'s
two domains: each mesh is made once, then for each S the sparse ``hamiltonian()``
and the cycle cut of k = 8 and 64 pieces against one METIS call on the same output
graph (issue 14's ratio), with the Steiner points and the uncovered triangles.
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def cells_table(target: int, sizes: list[int]) -> None:
    """Sparse cycle cut / METIS's with the cover confined to cells of each size (``--cells``)."""
    import sys
    import warnings
    from pathlib import Path

    import pymetis
    from scipy.sparse import coo_matrix

    import hammesh
    import hammesh.postprocess.cycle_cover as cc
    from hammesh.partition import dual_edges, edge_cut, partition

    sys.path.insert(0, str(Path(__file__).parent))
    from bench_partition import _domains

    keep = cc.CELL_SIZE
    try:
        for name, dom, area in _domains():
            mesh = hammesh.quality_mesh(dom, min_angle=30, max_area=area / (0.63 * target))
            for size in sizes:
                cc.CELL_SIZE = size
                t = time.perf_counter()
                h = hammesh.hamiltonian(mesh, mode="sparse")
                dt = time.perf_counter() - t
                r = h.report
                a, b = dual_edges(h.triangles)
                m = h.n_triangles
                g = coo_matrix((np.ones(len(a), np.int8), (a, b)), shape=(m, m))
                g = (g + g.T).tocsr()
                cuts = []
                for k in (8, 64):
                    p = partition(h, k)
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        mp = np.asarray(pymetis.part_graph(k, xadj=g.indptr, adjncy=g.indices)[1])
                    mc = edge_cut(mp, a, b)
                    cuts.append(f"k={k} {p.edge_cut:,} / METIS {mc:,} = {p.edge_cut / mc:.2f}")
                print(f"{name} ({mesh.n_triangles:,} input) cell_size {size}: {'; '.join(cuts)}; Steiner "
                      f"{r['steiner_points']} ({100 * r['steiner_per_input_triangle']:.2f} %); cycles "
                      f"{r['cycles_before_merging']:,}; uncovered {r['uncovered']:,}; hamiltonian {dt:.2f} s; "
                      f"verified {r['verified']}", flush=True)
    finally:
        cc.CELL_SIZE = keep


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--target", type=int, default=None, help="triangles of the input mesh (1.5M; --cells: 100k)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--cells", default=None, help="comma-separated cell sizes: the cut table instead (0: unconfined)")
    args = ap.parse_args()
    if args.cells is not None:
        cells_table(args.target or 100_000, [int(x) for x in args.cells.split(",")])
        return
    args.target = args.target or 1_500_000
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

    pts = mesh.points
    boundary = (twin.reshape(-1, 3) < 0).any(axis=1)
    variants = {  # name: cycle_cover's keywords
        "current": dict(points=pts),  # two halves on two threads, parity defects fixed by drops
        "one thread": dict(),  # no points: no split, the whole mesh in one call
        "no drops": dict(points=pts, drop=False),  # parity defects through chains of boundary triangles
    }

    def run(kw: dict):
        t, c0 = time.perf_counter(), time.process_time()
        c = cycle_cover(tri, twin, online=256, **kw)
        dt, cpu = time.perf_counter() - t, time.process_time() - c0
        big = np.bincount(c.cycle[c.cycle >= 0]).max() if c.n_cycles else 0
        return dt, cpu, c, big / len(tri)

    def shape(c, share) -> str:
        return (f"cycles {c.n_cycles:,}, uncovered {c.n_uncovered} ({int((boundary & (c.cycle < 0)).sum())} with a "
                f"boundary edge, {c.n_dropped} dropped), largest cycle {share:.1%}")

    dt, cpu, c, share = run(variants["current"])
    print(f"m = {len(tri):,}; Triangle (quality_mesh, first call) {t_tri:.3f} s")
    print(f"cover, first call: {dt:.3f} s ({cpu:.3f} s CPU) = {dt / t_tri:.3f} x Triangle; {shape(c, share)}")
    best = {k: (np.inf, np.inf) for k in variants}
    for _ in range(args.repeat):
        for name, kw in variants.items():
            dt, cpu, c, share = run(kw)
            best[name] = (min(best[name][0], dt), min(best[name][1], cpu))
            print(f"  {name:10s} {dt:.3f} s, {cpu:.3f} s CPU: {shape(c, share)}", flush=True)
    for name, (dt, cpu) in best.items():
        print(f"best of {args.repeat}, {name:10s}: {dt:.3f} s = {dt / t_tri:.3f} x Triangle ({cpu:.3f} s CPU)")


if __name__ == "__main__":
    main()
