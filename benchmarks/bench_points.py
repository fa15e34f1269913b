"""Thm 3.1 Hamiltonian triangulation vs scipy.spatial.Delaunay (Qhull), same points, same run.

Usage::

    python benchmarks/bench_points.py            # 10k, 100k, 1M uniform and clustered
    python benchmarks/bench_points.py --sizes 10000 100000
    python benchmarks/bench_points.py --sequential   # §4: Lemma 4.2 and the exact search

For each set: seconds of ``hamiltonian_triangulation`` (including its verification,
which every call runs) and of its construction alone, seconds of Qhull, the ratio
ours / Qhull, and min-angle statistics of both (the quality price: the splitter
triangulation is far from Delaunay).  A warm-up call compiles the numba kernels
first (cached on disk afterwards).

``--sequential``: seconds of Lemma 4.2's construction (``few_interior_sequential``,
with its certificate) on 0, 1, 2 interior points at the given sizes, and of the exact
search on the Thm 4.1 family at n = 9..12 (no strip exists: the search is exhaustive).
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def _angles(pts: np.ndarray, tri: np.ndarray) -> np.ndarray:
    p = pts[tri]
    out = []
    for k in range(3):
        a, b, c = p[:, k], p[:, (k + 1) % 3], p[:, (k + 2) % 3]
        u, v = b - a, c - a
        cos = (u * v).sum(1) / np.sqrt((u * u).sum(1) * (v * v).sum(1))
        out.append(np.degrees(np.arccos(np.clip(cos, -1, 1))))
    return np.min(out, axis=0)


def make(kind: str, n: int, rng: np.random.Generator) -> np.ndarray:
    if kind == "uniform":
        return rng.random((n, 2))
    centers = rng.random((20, 2))
    pts = centers[rng.integers(0, 20, n)] + 0.02 * rng.standard_normal((n, 2))
    return np.unique(pts, axis=0)


def _ellipse_plus(n: int, inner: int, rng: np.random.Generator) -> np.ndarray:
    ang = np.sort(rng.random(n - inner)) * 2 * np.pi
    hull = np.c_[2.0 * np.cos(ang), np.sin(ang)]
    return np.vstack([hull, 0.5 * (rng.random((inner, 2)) - 0.5)])


def sequential(sizes: list[int], seed: int) -> None:
    from hammesh.pointset import few_interior_sequential, lemma42_plan, no_sequential_example
    from hammesh.pointset import search_sequential

    few_interior_sequential(_ellipse_plus(100, 2, np.random.default_rng(seed)))  # compile
    print(f"{'n':>9} {'inner':>5} {'case':>6} {'core':>9} | {'seconds':>7}")
    for n in sizes:
        for inner in (0, 1, 2):
            pts = _ellipse_plus(n, inner, np.random.default_rng(seed))
            plan = lemma42_plan(pts)
            t0 = time.perf_counter()
            few_interior_sequential(pts)
            print(f"{n:>9,} {inner:>5} {plan.case:>6} {plan.source:>9} | {time.perf_counter() - t0:7.3f}",
                  flush=True)
    for n in range(9, 13):
        pts = no_sequential_example(n)
        t0 = time.perf_counter()
        found = search_sequential(pts)
        print(f"exact search, Thm 4.1 set n = {n}: {'none' if found is None else 'FOUND'} "
              f"in {time.perf_counter() - t0:.2f} s", flush=True)


def main(argv: list[str] | None = None) -> None:
    from scipy.spatial import Delaunay

    from hammesh.pointset import hamiltonian_triangulation
    from hammesh.pointset import hamiltonian as thm31
    from hammesh.pointset.validate import as_points, convex_hull

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+",
                    help="default 10k 100k 1M (--sequential: 1k 10k 100k)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--sequential", action="store_true", help="§4 figures instead (see above)")
    args = ap.parse_args(argv)
    if args.sequential:
        sequential(args.sizes or [1_000, 10_000, 100_000], args.seed)
        return
    args.sizes = args.sizes or [10_000, 100_000, 1_000_000]
    hamiltonian_triangulation(np.random.default_rng(1).random((100, 2)), seed=0)  # compile
    head = (f"{'set':>9} {'n':>9} | {'ours s':>7} {'build s':>7} {'qhull s':>7} {'ratio':>6} | "
            f"{'min° ours':>9} {'p5° ours':>8} {'min° qh':>8} {'p5° qh':>7}")
    print(head)
    print("-" * len(head))
    for kind in ("uniform", "clustered"):
        for n in args.sizes:
            rng = np.random.default_rng(args.seed)
            pts = make(kind, n, rng)
            t0 = time.perf_counter()
            tri = hamiltonian_triangulation(pts, seed=args.seed)
            ours = time.perf_counter() - t0
            p = as_points(pts)
            hull = convex_hull(p)
            t0 = time.perf_counter()
            thm31._attempt(p, hull, np.random.default_rng(args.seed))
            build = time.perf_counter() - t0
            t0 = time.perf_counter()
            d = Delaunay(pts)
            qh = time.perf_counter() - t0
            a_ours, a_qh = _angles(pts, tri), _angles(pts, d.simplices)
            print(f"{kind:>9} {len(pts):>9,} | {ours:7.2f} {build:7.2f} {qh:7.2f} {ours / qh:6.2f} | "
                  f"{a_ours.min():9.2e} {np.percentile(a_ours, 5):8.2f} {a_qh.min():8.2e} "
                  f"{np.percentile(a_qh, 5):7.2f}", flush=True)


if __name__ == "__main__":
    main()
