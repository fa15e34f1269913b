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
    python benchmarks/bench_cover.py --corpus      # uncovered triangles, the 16k corpus
    python benchmarks/bench_cover.py --compile     # first cycle_cover with an empty numba cache

``--corpus``: the sparse ``hamiltonian()`` on the ~16k-triangle q30 meshes of
``bench_sparse.py`` (8 domains): the cover's uncovered triangles per mesh and in all,
and those with a boundary edge (``report["uncovered"]``, ``["uncovered_boundary"]``);
session 8 left 62 / 43. ``--compile``: a child process with a new, empty
``NUMBA_CACHE_DIR`` compiles what the quadtree needs first, then times its first
``cycle_cover`` call (the cover's kernels compiled) in wall and CPU seconds.

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


def corpus_table() -> None:
    """Uncovered triangles of the sparse cover on bench_sparse.py's 16k corpus (``--corpus``)."""
    import sys
    import warnings
    from pathlib import Path

    import hammesh

    sys.path.insert(0, str(Path(__file__).parent))
    from bench_sparse import _domains, _mesh_at

    tot = [0, 0]
    for name, dom in _domains():
        m = _mesh_at(dom, 16_000)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = hammesh.hamiltonian(m, mode="sparse").report
        tot[0] += r["uncovered"]
        tot[1] += r["uncovered_boundary"]
        print(f"{name:<20}{m.n_triangles:>8,} triangles: uncovered {r['uncovered']:>3}, with a boundary edge "
              f"{r['uncovered_boundary']:>3}", flush=True)
    print(f"CORPUS_UNCOVERED {tot[0]} with a boundary edge {tot[1]}")


_COMPILE_CHILD = """
import resource, time
import numpy as np
from hammesh.halfedge import half_edges
from hammesh.postprocess._thm24_kernels import quadtree_coords
from hammesh.postprocess.cycle_cover import cycle_cover
g = np.mgrid[0:60, 0:60].reshape(2, -1).T.astype(float)
pts = g + 0.01 * np.random.default_rng(1).random(g.shape)
from scipy.spatial import Delaunay
tri = Delaunay(pts).simplices.astype(np.int64)
tw = half_edges(tri, len(pts)).twin
quadtree_coords(pts, tri)
def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime
t, c = time.perf_counter(), cpu()
cycle_cover(tri, tw, points=pts, online=256, good=np.zeros(3 * len(tri), bool))
print(f"COMPILE first cycle_cover {time.perf_counter() - t:.1f} s wall, {cpu() - c:.1f} s CPU")
"""


def compile_time() -> None:
    """The cover's kernels compiled from nothing, in a child with an empty numba cache (``--compile``)."""
    import os
    import subprocess
    import sys
    import tempfile

    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        subprocess.run([sys.executable, "-c", _COMPILE_CHILD], env=env, check=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--target", type=int, default=None, help="triangles of the input mesh (1.5M; --cells: 100k)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--cells", default=None, help="comma-separated cell sizes: the cut table instead (0: unconfined)")
    ap.add_argument("--corpus", action="store_true", help="uncovered triangles on the 16k corpus instead")
    ap.add_argument("--compile", action="store_true", help="first cycle_cover with an empty numba cache instead")
    args = ap.parse_args()
    if args.corpus:
        corpus_table()
        return
    if args.compile:
        compile_time()
        return
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
