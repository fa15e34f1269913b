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
    python benchmarks/bench_cover.py --steps [--target 1500000] [--repeat 5]
    python benchmarks/bench_cover.py --steps --local [--target 1500000] [--repeat 5]
    python benchmarks/bench_cover.py --fresh 3 [--target 1500000]
    python benchmarks/bench_cover.py --phases [--target 1500000] [--repeat 5]

``--fresh N``: the cover's first call in a fresh process, as sparse mode makes it: the
sparse ``hamiltonian()`` of the plate is run once with ``cycle_cover``'s arguments
captured (rows renumbered by ``renumber_local``, the rule its matching judges edges by) into a
temporary file; N children each time raw Triangle's first call on the plate (the
peer, in that process), load the cover's kernels on a small mesh (as ``quality_mesh``
does while Triangle runs), then time the first and a second ``cycle_cover`` on those
arguments: wall and process CPU (the side thread included), CPU per step, the
cover's shape, and first call / raw Triangle in wall and in CPU (median printed).

``--phases`` (session 16): the matching's phases one by one on the arguments sparse
mode gives the cover (captured as for ``--fresh``), each timed in thread CPU and wall
seconds on the calling thread, median of ``--repeat`` rounds: per half the
breadth-first order, the greedy with its online searches and the searches from what
it left; then ``search_frees``, the parity defects' drop phase serially and in two
parts side by side (``cycle_cover._drop_defects``: the main thread's CPU, and the
wall), and the chain phase; with the free triangles each phase leaves.

``--corpus``: the sparse ``hamiltonian()`` on the ~16k-triangle q30 meshes of
``bench_sparse.py`` (8 domains): the cover's uncovered triangles per mesh and in all,
and those with a boundary edge (``report["uncovered"]``, ``["uncovered_boundary"]``);
session 8 left 62 / 43. ``--compile``: a child process with a new, empty
``NUMBA_CACHE_DIR`` compiles what the quadtree needs first, then times its first
``cycle_cover`` call (the cover's kernels compiled) in wall and CPU seconds, and
the CPU seconds of each step (``cycle_cover(..., clock=)``: where the compile goes).

``--steps``: process CPU (and wall) seconds per step of ``cycle_cover``
(``cycle_cover(..., clock=)``) on the plate as Triangle numbers it and on the same
mesh with its triangles renumbered in Morton or Hilbert order of their centroids
(``local_order`` here; the vertices renumbered by first use too: "+v"), the
variants alternating in one process for ``--repeat`` rounds (median per step), with
each variant's cycles and uncovered triangles: what a local numbering buys the cover.
With ``--local`` the mesh is renumbered by ``hammesh.halfedge.renumber_local`` (as sparse
mode hands it to the cover from 100k triangles on) and the variants are the cover's
two halves: the count quadtree's top split (``points=``) against a quadrant border of the renumbering
(``local=True``), alternating in one process, with each variant's cycles and uncovered
triangles. ``HAMMESH_BENCH_MESH=plate.npz`` (arrays ``points``, ``triangles``) uses that mesh
instead of meshing the plate with Triangle.

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
clock = {}
cycle_cover(tri, tw, points=pts, online=256, good=np.zeros(3 * len(tri), bool), clock=clock)
print(f"COMPILE first cycle_cover {time.perf_counter() - t:.1f} s wall, {cpu() - c:.1f} s CPU")
for step, (w, cs) in clock.items():
    print(f"  {step:16s} {cs:6.1f} s CPU")
"""


_FRESH_CHILD = """
import resource, sys, time
import numpy as np
import triangle
from scipy.spatial import Delaunay
sys.path.insert(0, sys.argv[3])
from bench_cover import plate_domain
from hammesh.halfedge import half_edges
from hammesh.meshing import MeshOptions, triangle_switches
from hammesh.postprocess.cycle_cover import JoinRule, cycle_cover
def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime
dom, max_area = plate_domain(int(sys.argv[2]))
data = {"vertices": np.array(dom.vertices, np.float64), "segments": np.array(dom.segments, np.int32),
        "holes": np.array(dom.holes, np.float64)}
w, c = time.perf_counter(), cpu()
raw = triangle.triangulate(data, triangle_switches(dom, MeshOptions(min_angle=30, max_area=max_area)))
print(f"FRESH triangle {time.perf_counter() - w:.4f} {cpu() - c:.4f} {len(raw['triangles'])} triangles")
del raw
g = np.mgrid[0:60, 0:60].reshape(2, -1).T.astype(float)
p = g + 0.01 * np.random.default_rng(1).random(g.shape)
t = Delaunay(p).simplices.astype(np.int64)
small = JoinRule(np.full(len(t), 0.5), 0.9, 2.2, np.zeros(3 * len(t), bool))
cycle_cover(t, half_edges(t, len(p)).twin, points=p, online=256, rule=small, judge=True)  # kernels loaded
z = np.load(sys.argv[1])
tri, tw, pts = z["tri"], z["tw"], z["points"]
rule = JoinRule(z["amin"], float(z["keep"]), float(z["hi"]), z["pinned"], bool(z["swaps"]), bool(z["edge_splits"]),
                z["corners"] if len(z["corners"]) else None)
for call in ("first", "second"):
    clock = {}
    w, c = time.perf_counter(), cpu()
    cov = cycle_cover(tri, tw, rule=rule, judge=bool(z["judge"]), points=pts, local=bool(z["local"]), clock=clock)
    w, c = time.perf_counter() - w, cpu() - c
    steps = " ".join(f"{k}={v[1]:.3f}" for k, v in clock.items())
    print(f"FRESH {call} {w:.4f} {c:.4f} cycles {cov.n_cycles} uncovered {cov.n_uncovered}; CPU per step {steps}")
"""


def fresh_table(target: int, runs: int) -> None:
    """The cover's first call in fresh processes, on the arguments sparse mode gives it (``--fresh``)."""
    import os
    import subprocess
    import sys
    import tempfile
    from pathlib import Path

    import hammesh
    import hammesh.postprocess.sparse as sparse

    mesh, _ = plate_mesh(target)
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "cover_in.npz")
        real = sparse.cycle_cover

        def capture(tri, tw, **kw):
            r = kw["rule"]
            np.savez(path, tri=tri, tw=tw, points=kw["points"], local=kw["local"], judge=kw["judge"], amin=r.amin,
                     keep=r.keep, hi=r.hi, pinned=r.pinned, swaps=r.swaps, edge_splits=r.edge_splits,
                     corners=np.zeros((0, 3), np.float32) if r.corners is None else r.corners)
            return real(tri, tw, **kw)

        sparse.cycle_cover = capture
        try:
            hammesh.hamiltonian(mesh, mode="sparse")
        finally:
            sparse.cycle_cover = real
        print(f"m = {mesh.n_triangles:,}; each child: raw Triangle on the plate (first call, the peer), the cover's "
              f"kernels loaded on a small mesh, then cycle_cover twice on sparse mode's arguments")
        ratios = []
        for _ in range(runs):
            out = subprocess.run([sys.executable, "-c", _FRESH_CHILD, path, str(target), str(Path(__file__).parent)],
                                 capture_output=True, text=True, check=True).stdout
            got = {}
            for line in out.splitlines():
                if line.startswith("FRESH"):
                    _, call, w, c, rest = line.split(" ", 4)
                    got[call] = (float(w), float(c))
                    print(f"  {call:8s} {float(w):.3f} s wall, {float(c):.3f} s CPU; {rest}", flush=True)
            (tw_, tc), (fw, fc) = got["triangle"], got["first"]
            ratios.append((fw / tw_, fc / tc))
            print(f"  first call / raw Triangle: {fw / tw_:.3f} wall, {fc / tc:.3f} CPU", flush=True)
        w, c = np.median(np.array(ratios), axis=0)
        print(f"FRESH_RATIO first cycle_cover / raw Triangle, median of {runs}: {w:.3f} wall, {c:.3f} CPU")


def plate_domain(target: int):
    """The plate with two holes of ``plate_mesh`` and its max area for about ``target`` triangles."""
    import hammesh

    a = np.linspace(0, 2 * np.pi, 48, endpoint=False)
    circ = np.c_[np.cos(a), np.sin(a)]
    plate = hammesh.Domain.from_polygon(
        [[0, 0], [4, 0], [4, 2], [0, 2]], holes=[circ * 0.45 + [1, 1], circ * 0.3 + [3, 1]]
    )
    area = 8.0 - np.pi * (0.45**2 + 0.3**2)
    return plate, area / (0.63 * target)


def compile_time() -> None:
    """The cover's kernels compiled from nothing, in a child with an empty numba cache (``--compile``)."""
    import os
    import subprocess
    import sys
    import tempfile

    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        subprocess.run([sys.executable, "-c", _COMPILE_CHILD], env=env, check=True)


def plate_mesh(target: int):
    """The plate with two holes meshed by Triangle (min angle 30) at about ``target``
    triangles, and Triangle's first-call seconds."""
    import hammesh

    plate, max_area = plate_domain(target)
    t = time.perf_counter()
    mesh = hammesh.quality_mesh(plate, min_angle=30, max_area=max_area)
    return mesh, time.perf_counter() - t


def _hilbert_d(x: np.ndarray, y: np.ndarray, bits: int) -> np.ndarray:
    """Hilbert index of integer points in a ``2**bits`` square (the classic xy2d loop,
    vectorized over the points; Wikipedia, "Hilbert curve")."""
    x, y = x.astype(np.int64).copy(), y.astype(np.int64).copy()
    d = np.zeros(len(x), np.int64)
    n = 1 << bits
    s = n >> 1
    while s > 0:
        rx = ((x & s) > 0).astype(np.int64)
        ry = ((y & s) > 0).astype(np.int64)
        d += s * s * ((3 * rx) ^ ry)
        # rotate the quadrant
        flip = ry == 0
        swap_x = flip & (rx == 1)
        x[swap_x] = n - 1 - x[swap_x]
        y[swap_x] = n - 1 - y[swap_x]
        x[flip], y[flip] = y[flip], x[flip].copy()
        s >>= 1
    return d


def local_order(points: np.ndarray, tri: np.ndarray, curve: str = "morton", bits: int = 16) -> np.ndarray:
    """Rows of ``tri`` sorted by the Morton (Z) or Hilbert index of their centroids on a
    ``2**bits`` grid over the bounding box (a benchmark's stand-in for the renumbering
    the sparse pipeline is to do at its start)."""
    c = points[tri].mean(axis=1)
    lo, hi = c.min(axis=0), c.max(axis=0)
    q = ((c - lo) / max(float((hi - lo).max()), 1e-300) * ((1 << bits) - 1)).astype(np.int64)
    if curve == "hilbert":
        key = _hilbert_d(q[:, 0], q[:, 1], bits)
    else:
        key = np.zeros(len(q), np.int64)
        for b in range(bits):
            key |= ((q[:, 0] >> b) & 1) << (2 * b + 1) | ((q[:, 1] >> b) & 1) << (2 * b)
    return np.argsort(key, kind="stable")


def renumbered(points: np.ndarray, tri: np.ndarray, perm: np.ndarray, vertices: bool):
    """The mesh with triangle ``perm[i]`` as row i (and the vertices numbered by first
    use in the new rows if ``vertices``)."""
    t2 = tri[perm]
    if not vertices:
        return points, t2
    flat = t2.ravel()
    first = np.full(len(points), len(flat), np.int64)
    np.minimum.at(first, flat, np.arange(len(flat)))
    vorder = np.argsort(first, kind="stable")
    new_id = np.empty(len(points), np.int64)
    new_id[vorder] = np.arange(len(points))
    return points[vorder], new_id[t2]


def steps_table(target: int, repeat: int, local: bool = False) -> None:
    """Process CPU per cover step, Triangle's numbering vs local ones (``--steps``), or
    on the renumbered mesh the quadtree's halves vs the row halves (``--local``)."""
    import os

    from hammesh.halfedge import half_edges, renumber_local
    from hammesh.postprocess.cycle_cover import cycle_cover

    cache = os.environ.get("HAMMESH_BENCH_MESH")  # an .npz of points/triangles to skip Triangle
    if cache and os.path.exists(cache):
        z = np.load(cache)
        pts, tri = z["points"], z["triangles"].astype(np.int64)
    else:
        mesh, _ = plate_mesh(target)
        pts, tri = mesh.points, mesh.triangles.astype(np.int64)
    keywords: dict = {}
    if local:
        loc = renumber_local(pts, tri, half_edges(tri, len(pts)).twin)
        data = {"quadtree": (loc.points, loc.triangles, loc.twin), "quadrant": (loc.points, loc.triangles, loc.twin)}
        keywords = {"quadrant": {"local": True}}
    else:
        variants = {"triangle": (pts, tri)}
        for curve in ("morton", "hilbert"):
            perm = local_order(pts, tri, curve)
            variants[curve] = renumbered(pts, tri, perm, False)
            variants[curve + "+v"] = renumbered(pts, tri, perm, True)
        data = {k: (p, t, half_edges(t, len(p)).twin) for k, (p, t) in variants.items()}
    for k, (p, t, tw) in data.items():
        a, b = np.repeat(np.arange(len(t)), 3)[tw >= 0], tw[tw >= 0] // 3
        print(f"{k:10s} median |t - neighbour| {np.median(np.abs(a - b)):,.0f} rows", flush=True)
    cpu: dict = {k: {} for k in data}
    wall: dict = {k: [] for k in data}
    for r in range(repeat):
        for k, (p, t, tw) in data.items():
            clock: dict = {}
            t0 = time.perf_counter()
            c = cycle_cover(t, tw, points=p, good=np.zeros(3 * len(t), bool), clock=clock, **keywords.get(k, {}))
            wall[k].append(time.perf_counter() - t0)
            for step, (_, cs) in clock.items():
                cpu[k].setdefault(step, []).append(cs)
            if r == 0:
                print(f"{k:10s} m = {len(t):,}: cycles {c.n_cycles:,}, uncovered {c.n_uncovered}, dropped "
                      f"{c.n_dropped}, unmatched {c.n_unmatched}", flush=True)
    steps = list(cpu[next(iter(data))])
    print(f"median of {repeat} rounds, process CPU s per step:")
    print(f"{'step':16s}" + "".join(f"{k:>11s}" for k in data))
    for step in steps + ["total"]:
        row = [np.median(np.sum(list(cpu[k].values()), axis=0)) if step == "total" else np.median(cpu[k][step])
               for k in data]
        print(f"{step:16s}" + "".join(f"{v:11.3f}" for v in row))
    print(f"{'wall':16s}" + "".join(f"{np.median(wall[k]):11.3f}" for k in data))


def phases_table(target: int, repeat: int) -> None:
    """Thread CPU per phase of the cover's matching, on sparse mode's arguments (``--phases``)."""
    from unittest import mock

    import hammesh
    import hammesh.postprocess.cycle_cover as cc
    import hammesh.postprocess.sparse as sparse
    from hammesh.postprocess import _cover_kernels as ck
    from hammesh.postprocess import _join_kernels as J

    mesh, _ = plate_mesh(target)
    # sparse mode's arguments to the cover: the call a wrapping mock records
    with mock.patch.object(sparse, "cycle_cover", wraps=sparse.cycle_cover) as spy:
        hammesh.hamiltonian(mesh, mode="sparse")
    (tri, tw), kw = spy.call_args
    tri, pts = np.ascontiguousarray(tri, np.int64), kw["points"]
    m = len(tri)
    r = kw["rule"]  # (sparse mode judges the edges as the greedy asks: ``cycle_cover(..., judge=True)``)
    e_rule = J.edge_rule(pts, tri, tw, r.pinned, r.amin, r.keep, r.hi, r.swaps, r.edge_splits, r.corners)
    times: dict = {}
    frees_left: dict = {}

    def lap(name, t0, left=None):
        t1 = time.perf_counter(), time.thread_time()
        times.setdefault(name, []).append((t1[0] - t0[0], t1[1] - t0[1]))
        if left is not None:
            frees_left[name] = left
        return t1

    def n_free(active, mate):
        return int((active & (mate < 0)).sum())

    for _ in range(repeat):
        nb = np.empty((m, 3), np.int32)
        ck.neighbors_into(tw, nb, 0, m)
        alive, deg = ck.peel(nb, m)
        active = alive & (deg == 3)
        side = np.zeros(m, np.int8)
        side[cc._quadrant_cut(pts, tri, m):] = 1
        mate = np.full(m, -1, np.int32)
        work = (np.empty(m, np.int32), np.empty(m, np.int32), np.full(m, -1, np.int8), np.zeros(m, np.int64))
        memo = np.zeros(3 * m, np.int8)  # (no edge judged yet)
        s = 0
        for half in (0, 1):
            t0 = time.perf_counter(), time.thread_time()
            act = np.zeros(m, np.bool_)
            act[side == half] = active[side == half]
            order = ck._bfs_order(nb, side, half)
            t0 = lap(f"half {half}: order", t0)
            queue = np.empty(cc.ONLINE_BUDGET + 2016, np.int32)
            # (each half's stamps start at 0, as in match_half: the halves touch disjoint triangles)
            sh = ck._greedy_matching(nb, act, m, e_rule, memo, order, cc.ONLINE_BUDGET, *work, queue, mate)
            t0 = lap(f"half {half}: greedy+online", t0, n_free(act, mate))
            sh = ck._augment_every_free(nb, act, act, mate, *work, sh, queue, 2000)
            lap(f"half {half}: searches", t0, n_free(act, mate))
            s = max(s, sh)
        judged = int(np.count_nonzero(memo[tw >= 0])), int(np.count_nonzero(tw >= 0))
        t0 = time.perf_counter(), time.thread_time()
        frees, s = ck.search_frees(nb, active, alive, mate, *work, s, 2000)
        t0 = lap("search_frees", t0, n_free(active, mate))
        state = (mate.copy(), active.copy(), alive.copy())
        s1, _d = cc._drop_defects(nb, active, alive, mate, work, s, frees, False)
        t0 = lap("drop, serial", t0, n_free(active, mate))
        after = (mate.copy(), active.copy(), alive.copy())
        mate[:], active[:], alive[:] = state
        batches: list = []  # per run_all: each call's thread CPU (the first runs on this thread)

        def metered(calls, real_run=cc.run_all):
            def one(c):
                c0 = time.thread_time()
                out = c()
                return out, time.thread_time() - c0
            got_ = real_run([lambda c=c: one(c) for c in calls])
            batches.append([g_[1] for g_ in got_])
            return [g_[0] for g_ in got_]

        cc.run_all = metered
        try:
            t0 = time.perf_counter(), time.thread_time()
            s, _d = cc._drop_defects(nb, active, alive, mate, work, s1 + 1, frees, True)
            t1 = time.perf_counter(), time.thread_time()
        finally:
            cc.run_all = metered.__defaults__[0]
        # the critical path in CPU: this thread's work outside the side-by-side calls,
        # plus the slower call of each pass (what the wall is on two free cores)
        crit = t1[1] - t0[1] - sum(b[0] for b in batches) + sum(max(b) for b in batches)
        times.setdefault("drop, two parts: critical", []).append((t1[0] - t0[0], crit))
        times.setdefault("drop, parts A / B", []).append(tuple(batches[-1][:2]) if len(batches) > 1 else (0, 0))
        t0 = lap("drop, two parts", t0, n_free(active, mate))
        same = all(np.array_equal(a, b) for a, b in zip(after, (mate, active, alive)))
        frees_left["drop, two parts"] = f"{frees_left['drop, two parts']} (serial's state: {same})"
        ck.chain_frees(nb, active, alive, mate, *work, s, frees, tri, pts, cc.GUIDE_WEIGHT, cc.CHAIN_COST)
        lap("chain", t0, n_free(active, mate))
    print(f"m = {m:,}; median of {repeat} rounds, calling thread (drop, two parts: the main thread's part; "
          f"'critical': its work outside the two-thread passes plus each pass's slower thread, in CPU)")
    print(f"  inner half-edges the greedy judged: {judged[0]:,} of {judged[1]:,} "
          f"({100 * judged[0] / max(judged[1], 1):.1f} %)")
    for name, v in times.items():
        v = np.array(v)
        if name == "drop, parts A / B":  # (the two parts' thread CPU)
            print(f"  {name:26s} {np.median(v[:, 0]) * 1e3:7.1f} / {np.median(v[:, 1]) * 1e3:.1f} ms CPU")
            continue
        print(f"  {name:26s} {np.median(v[:, 1]) * 1e3:7.1f} ms CPU {np.median(v[:, 0]) * 1e3:7.1f} ms wall; "
              f"free after: {frees_left.get(name, '')}", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--target", type=int, default=None, help="triangles of the input mesh (1.5M; --cells: 100k)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--cells", default=None, help="comma-separated cell sizes: the cut table instead (0: unconfined)")
    ap.add_argument("--corpus", action="store_true", help="uncovered triangles on the 16k corpus instead")
    ap.add_argument("--compile", action="store_true", help="first cycle_cover with an empty numba cache instead")
    ap.add_argument("--steps", action="store_true", help="CPU per cover step, Triangle's vs local numberings")
    ap.add_argument("--local", action="store_true", help="--steps, renumber_local: quadtree vs quadrant halves")
    ap.add_argument("--fresh", type=int, default=0, help="first cycle_cover in N fresh processes, as sparse calls it")
    ap.add_argument("--phases", action="store_true", help="thread CPU per phase of the cover's matching")
    args = ap.parse_args()
    if args.phases:
        phases_table(args.target or 1_500_000, args.repeat)
        return
    if args.fresh > 0:
        fresh_table(args.target or 1_500_000, args.fresh)
        return
    if args.steps:
        steps_table(args.target or 1_500_000, args.repeat, args.local)
        return
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
    from hammesh.halfedge import half_edges
    from hammesh.postprocess.cycle_cover import cycle_cover

    mesh, t_tri = plate_mesh(args.target)
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
