"""Polygon benchmark: Thm 2.1 decision (issue 4) and the minimum convex decomposition (issue 17).

Part 1 (issue 4): random simple polygons of 500, 1000, 2000 and 4000 vertices of two
kinds (star-shaped: random radii at sorted random angles; x-monotone: random upper and
lower chains).  For each, prints |E| (visibility edges), the visibility-graph time, the
Thm 2.1 decision time (visibility graph + dynamic program, as
``polygon.is_hamiltonian`` runs it), and the answer.  Target: 2000 vertices in <= 5 s.

Part 2 (issue 17): Figure 7 combs with 11, 50 and 200 teeth through
``steiner_hamiltonian_result`` (cycle): k, Steiner count (must be k - 1 with k = teeth
+ 1, the minimum) and time (target: 200 teeth <= 5 s); then "dented" polygons (a
convex n-gon with r vertices pushed in, n = 30..300, r <= 20): the minimum convex
decomposition (Keil's dynamic program) against the peer measured in the same run,
Hertel--Mehlhorn (pieces and time).  Target: <= 1 s at n = 300.  Times are the first
call in this process and the best of three.

    python benchmarks/bench_polygon.py [--sizes 500 1000 2000 4000] [--seed 0] [--part 1|2]
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


def comb(teeth: int) -> np.ndarray:
    """Figure 7: ``teeth`` unit teeth of height 4 on a base of height 1, gaps of 1."""
    pts = [(0.0, 0.0), (2.0 * teeth - 1.0, 0.0)]
    for i in range(teeth - 1, -1, -1):
        pts += [(2.0 * i + 1.0, 4.0), (2.0 * i, 4.0)]
        if i > 0:
            pts += [(2.0 * i, 1.0), (2.0 * i - 1.0, 1.0)]
    return np.array(pts)


def dented(n: int, r: int, rng) -> np.ndarray:
    """A convex n-gon on the unit circle with r non-adjacent vertices pushed in."""
    t = np.sort(rng.uniform(0, 2 * np.pi, n))
    rad = np.ones(n)
    rad[rng.choice(np.arange(0, n, 2), size=r, replace=False)] = rng.uniform(0.4, 0.85, r)
    return np.c_[rad * np.cos(t), rad * np.sin(t)]


def _timed(f, repeat=3):
    """(first call, best of ``repeat``) seconds and the first result."""
    times = []
    out = None
    for _ in range(repeat):
        t = time.perf_counter()
        res = f()
        times.append(time.perf_counter() - t)
        out = res if out is None else out
    return times[0], min(times), out


def decomposition(seed: int) -> None:
    from hammesh import polygon
    from hammesh.polygon.min_convex import minimum_convex_faces
    from hammesh.predicates import orient_rows

    print(f"{'comb teeth':>10s} {'n':>5s} {'k':>4s} {'Steiner':>8s} {'= k-1':>6s} "
          f"{'first s':>8s} {'best s':>7s}   method")
    for teeth in (11, 50, 200):
        p = comb(teeth)
        first, best, res = _timed(lambda: polygon.steiner_hamiltonian_result(p, "cycle"))
        ok = res.n_steiner == res.k - 1 and res.k == teeth + 1
        print(f"{teeth:10d} {len(p):5d} {res.k:4d} {res.n_steiner:8d} {str(ok):>6s} "
              f"{first:8.3f} {best:7.3f}   {res.method}")
    rng = np.random.default_rng(seed)
    print(f"\n{'dented n':>8s} {'r':>3s} {'k':>4s} {'first s':>8s} {'best s':>7s} "
          f"{'H-M k':>6s} {'H-M s':>7s} {'time / H-M':>10s}")
    for n in (30, 60, 100, 150, 200, 300):
        for r in (5, 10, 20):
            if 3 * r > n:
                continue
            p = dented(n, r, rng)
            cp = polygon.validate_polygon(p).points
            nr = int((orient_rows(np.roll(cp, 1, axis=0), cp, np.roll(cp, -1, axis=0)) < 0).sum())
            first, best, faces = _timed(lambda: minimum_convex_faces(cp))
            _, hm_best, hm = _timed(lambda: polygon.convex_decomposition(p, decomposition="hertel-mehlhorn"))
            print(f"{n:8d} {nr:3d} {len(faces):4d} {first:8.3f} {best:7.3f} {len(hm):6d} "
                  f"{hm_best:7.3f} {best / hm_best:10.1f}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[500, 1000, 2000, 4000])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--part", type=int, choices=[1, 2], help="only part 1 or 2")
    args = ap.parse_args(argv)

    from hammesh import polygon

    if args.part != 1:
        decomposition(args.seed)
        if args.part == 2:
            return 0
        print()

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
