"""Polygon benchmark (issue 4): visibility-graph size and Thm 2.1 decision time.

Random simple polygons of 500, 1000, 2000 and 4000 vertices of two kinds (star-shaped:
random radii at sorted random angles; x-monotone: random upper and lower chains).  For
each, prints |E| (visibility edges), the visibility-graph time, the Thm 2.1 decision
time (visibility graph + dynamic program, as ``polygon.is_hamiltonian`` runs it), and
the answer.

    python benchmarks/bench_polygon.py [--sizes 500 1000 2000 4000] [--seed 0]

Target (issue 4): 2000 vertices decided in <= 5 s.
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def star(n: int, rng) -> np.ndarray:
    t = np.sort(rng.uniform(0, 2 * np.pi, n))
    r = rng.uniform(0.3, 1.0, n)
    return np.c_[r * np.cos(t), r * np.sin(t)]


def monotone(n: int, rng) -> np.ndarray:
    x = np.sort(rng.uniform(0, 1, n))
    up = rng.random(n) < 0.5
    up[0] = up[-1] = False
    y = rng.uniform(0.05, 1, n)
    y[0] = y[-1] = 0.0
    return np.vstack([np.c_[x[~up], -y[~up]], np.c_[x[up], y[up]][::-1]])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[500, 1000, 2000, 4000])
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)

    from hammesh import polygon

    rng = np.random.default_rng(args.seed)
    polygon.is_hamiltonian(star(50, rng))  # compile / load the numba cache
    print(f"{'kind':9s} {'n':>6s} {'|E|':>10s} {'vis s':>8s} {'decide s':>9s}  hamiltonian")
    for kind, make in (("star", star), ("monotone", monotone)):
        for n in args.sizes:
            p = make(n, rng)
            t = time.perf_counter()
            e = polygon.visibility_graph(p)
            t_vis = time.perf_counter() - t
            t = time.perf_counter()
            ok = polygon.is_hamiltonian(p)
            t_dec = time.perf_counter() - t
            print(f"{kind:9s} {n:6d} {len(e):10,d} {t_vis:8.3f} {t_dec:9.3f}  {ok}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
