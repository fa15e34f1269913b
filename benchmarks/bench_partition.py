"""Partition benchmark (issue 14): cycle pieces vs METIS (pymetis), and vertex numberings.

Two of our domains (a plate with two round holes, a 12-tooth gear with a hole), each
meshed by Triangle (min angle 30) so that the Hamiltonian mesh has about ``--target``
triangles (default 300 000) in each mode (``incircle``: Thm 2.4, three triangles per
input triangle; ``sparse``). For k = 8 and 64, on the output's dual graph (triangles,
adjacent across an edge):

* ``hammesh.partition(h, k)``: contiguous stretches of the cycle (edge cut, largest
  part / mean, parts connected: counted by its check), its time: first call in this
  process and best of ``--repeat`` from the triangles alone (both with the
  connectivity check), and best of ``--repeat`` handed the dual graph (``edges=``)
  as METIS is, without the check (the ratio's figure: what METIS does, too);
* ``pymetis.part_graph(k)`` on the same graph (CSR built beforehand, not timed): edge
  cut, balance, connected parts (counted by the same check), time (best of ``--repeat``);
* the Hilbert-order baseline (issue 14): the triangles sorted along a Hilbert curve
  through their centroids, cut into k equal runs: edge cut, disconnected parts.

Targets: cycle cut / METIS cut <= 1.5 (goal 1.1), every part connected, exact
balance, partition time <= 1/20 of pymetis's.

Forest table (issue 14's cost): ``_thm24_kernels.spanning_forest`` (the compact tree)
against a plain breadth-first spanning forest with the same output (renumbered
triangles, packed half-edge codes; defined here, single-threaded), both on the input
mesh of each incircle row, alternating, best of ``--repeat`` (at least 9), plus the
first call of each in this process; wall time and CPU time (process; the compact forest
searches the two halves of its quadtree on two threads); target: compact / plain <= 1.2.

Numbering table: bandwidth and profile of the output's vertex matrix as hammesh
writes it, renumbered along the cycle, by RCM (scipy) and along a Hilbert curve.

    python benchmarks/bench_partition.py [--target 300000] [--repeat 3] [--quick]
    python benchmarks/bench_partition.py --forest-only --forest-size 1500000   # the forest table alone
    python benchmarks/bench_partition.py --domains square,rect_2x1 --modes incircle --ks 4,8,16,64   # controls
    python benchmarks/bench_partition.py --quick --modes incircle --plot parts/   # pictures of the parts
    python benchmarks/bench_partition.py --trees --target 100000   # other spanning trees (partition_trees.py)
    python benchmarks/bench_partition.py --sparse-cells 0,1024,4096 --target 100000   # sparse: cell-confined covers
    python benchmarks/bench_partition.py --modes sparse,sparse-fishbone --repeat 3   # sparse's fishbone option
    python benchmarks/bench_partition.py --modes sparse,sparse-comb --target 300000   # sparse's comb option
    python benchmarks/bench_partition.py --ceilings --target 100000   # what following a compact sweep could cut
    python benchmarks/bench_partition.py --blocks 4096,1024,256 --target 300000   # a ring of compact blocks
    python benchmarks/bench_partition.py --blocks 4096,1024 --along walk   # blocks of the incircle walk
    python benchmarks/bench_partition.py --colourings --target 100000   # sparse cycles as vertex colourings

``--ceilings`` (session 15) measures, on Triangle's mesh itself (sparse mode's output is
that mesh plus 0.3 % Steiner points), the cut of orders and partitions a sparse cycle
could follow (``benchmarks/partition_ceilings.py``) against METIS's (median of three
seeds), beside the cycles' own ratios.

``--blocks`` (session 16) measures, on Triangle's mesh, a cycle made as a ring of compact
blocks (a generalized Hilbert curve's runs of ``B`` triangles, smoothed), each block
walked once: as an ideal sweep, or along its own sparse cycle (sparse mode on the block
alone: its Steiner points, smallest angle, and the blocks that could be spliced into the
ring with none); beside the sparse cycle's own ratio and its cover's largest cycle alone.

``--colourings`` (session 21) measures sparse cycles as vertex colourings
(``benchmarks/partition_colourings.py``): repairs of a compact induced vertex tree's
uncovered triangles, each colouring's largest cycle cut against METIS's on Triangle's
mesh; then sparse mode with its cover replaced by the compact tree's (its price and cut).

``--modes sparse-fishbone`` is ``hamiltonian(mesh, mode="sparse", tree="fishbone")``
(``hammesh.postprocess.sparse_cells``); with it a table of its price against sparse
mode's default on the same input (Steiner points, angles, rows below the parent rule,
the call's process CPU). ``--modes sparse-comb`` (session 21) is ``tree="comb"``
(``hammesh.postprocess.comb_cover``), with the same table.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np


def _domains():
    import hammesh

    a = np.linspace(0, 2 * np.pi, 48, endpoint=False)
    circ = np.c_[np.cos(a), np.sin(a)]
    plate = hammesh.Domain.from_polygon(
        [[0, 0], [4, 0], [4, 2], [0, 2]], holes=[circ * 0.45 + [1, 1], circ * 0.3 + [3, 1]]
    )
    k = np.arange(96)
    r = np.where((k // 4) % 2 == 0, 1.0, 0.8)  # 12 teeth
    ang = 2 * np.pi * k / 96
    gear = hammesh.Domain.from_polygon(np.c_[r * np.cos(ang), r * np.sin(ang)], holes=[circ * 0.3])
    # hole-free controls (``--domains``): where the quadtree's hubs never fall in a hole
    square = hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])
    rect = hammesh.Domain.from_polygon([[0, 0], [2, 0], [2, 1], [0, 1]])
    return [("plate_2_holes", plate, 8.0 - np.pi * (0.45**2 + 0.3**2)), ("gear", gear, 2.62 - np.pi * 0.09),
            ("square", square, 1.0), ("rect_2x1", rect, 2.0)]


#: ``--modes``: the ``hamiltonian`` call of each (``sparse-fishbone``: sparse mode's
#: opt-in compact cycle, ``hammesh.postprocess.sparse_cells``; plain ``sparse`` is
#: sparse mode's default, the cover left free).
MODES = {"incircle": ("incircle", "fishbone"), "sparse": ("sparse", "quadtree"),
         "sparse-fishbone": ("sparse", "fishbone"), "sparse-comb": ("sparse", "comb")}


def _metis_median(k: int, a: np.ndarray, b: np.ndarray, m: int, seeds: int = 3) -> float:
    """METIS's edge cut on the dual graph ``a``-``b`` of ``m`` triangles: the median
    over ``seeds`` seeds (its cut moves by up to 20 % between seeds at k = 8)."""
    import pymetis
    from scipy.sparse import coo_matrix

    from hammesh.partition import edge_cut

    g = coo_matrix((np.ones(2 * len(a), np.int8), (np.r_[a, b], np.r_[b, a])), shape=(m, m)).tocsr()
    cuts = []
    for seed in range(seeds):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = pymetis.part_graph(k, xadj=g.indptr, adjncy=g.indices, options=pymetis.Options(seed=seed))
        cuts.append(edge_cut(np.asarray(res[1], dtype=np.int64), a, b))
    return float(np.median(cuts))


def _fill_parts(part: np.ndarray, nb: np.ndarray) -> np.ndarray:
    """``part`` with every -1 triangle given a neighbour's part, repeatedly."""
    part = part.copy()
    while (part < 0).any():
        miss = np.flatnonzero(part < 0)
        got = np.where(nb[miss] >= 0, part[np.maximum(nb[miss], 0)], -1).max(axis=1)
        if not (got >= 0).any():
            break
        part[miss] = got
    return part


def _input_mesh(dom, area: float, target: int):
    """Triangle's mesh of about ``target`` triangles (min angle 30), its dual edges
    ``a``-``b``, half-edge twins and dual neighbours (``--ceilings``, ``--blocks``)."""
    import hammesh
    from hammesh.halfedge import half_edges
    from hammesh.partition import dual_edges
    from partition_ceilings import dual_neighbours

    mesh = hammesh.quality_mesh(dom, min_angle=30, max_area=area / (0.63 * target))
    a, b = dual_edges(mesh.triangles, mesh.n_points)
    twin = half_edges(mesh.triangles, mesh.n_points).twin
    return mesh, a, b, twin, dual_neighbours(twin)


def _print_ceilings(domains, target: int, ks: list[int]) -> None:
    """``--ceilings``: the cut of orders a sparse cycle could follow, on Triangle's
    mesh (``partition_ceilings``), and the cycles' own, each / METIS's (median of 3 seeds)."""
    import os
    import sys

    import hammesh
    from hammesh.partition import dual_edges, edge_cut, part_components, partition

    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from partition_ceilings import (kd_order, order_cut, projected_parts, stretch_parts,
                                    vertex_tree_cover, walk_positions)

    print("| domain | triangles | k | incircle (own mesh) | sparse | sparse, fishbone | walk order, first / median "
          "| incircle's parts projected (disconnected, imbalance) | kd order (disconnected) "
          "| vertex tree (uncovered) | vertex tree, repaired (uncovered) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name, dom, area in domains:
        mesh, a, b, twin, nb = _input_mesh(dom, area, target)
        m = mesh.n_triangles
        hi = hammesh.hamiltonian(mesh, mode="incircle", tree="fishbone")
        hs = hammesh.hamiltonian(mesh, mode="sparse")
        hf = hammesh.hamiltonian(mesh, mode="sparse", tree="fishbone")
        first, median = walk_positions(hi.parent, m)
        kd = kd_order(mesh.points[mesh.triangles].mean(axis=1))
        trees = [vertex_tree_cover(mesh.points, mesh.triangles, twin, repair=r) for r in (0, 6)]
        for k in ks:
            mc = _metis_median(k, a, b, m)

            def own(h):
                ha, hb = dual_edges(h.triangles, h.n_points)
                return partition(h, k).edge_cut / _metis_median(k, ha, hb, h.n_triangles)

            pf, pm = (order_cut(np.argsort(x, kind="stable"), k, a, b) for x in (first, median))
            pp = projected_parts(hi.parent, partition(hi, k).part, m, k, nb)
            kc, kdis = order_cut(kd, k, a, b)
            cells = []
            for vt in trees:
                # the cycle's stretches (best shift on the edges between its triangles), the
                # uncovered triangles then given a neighbour's part
                local = np.full(m, -1, np.int64)
                local[vt.order] = np.arange(len(vt.order))
                on = (local[a] >= 0) & (local[b] >= 0)
                vpart = np.full(m, -1, np.int64)
                vpart[vt.order] = stretch_parts(np.arange(len(vt.order)), k, local[a[on]], local[b[on]])
                vpart = _fill_parts(vpart, nb)
                cells.append(f"{edge_cut(vpart, a, b) / mc:.2f} ({len(vt.uncovered) / m:.2%})")
            print(f"| {name} | {m:,} | {k} | {own(hi):.2f} | {own(hs):.2f} | {own(hf):.2f} "
                  f"| {pf[0] / mc:.2f} / {pm[0] / mc:.2f} "
                  f"| {edge_cut(pp, a, b) / mc:.2f} ({int((part_components(pp, k, a, b) > 1).sum())}, "
                  f"{np.bincount(pp, minlength=k).max() * k / m:.3f}) "
                  f"| {kc / mc:.2f} ({kdis}) "
                  f"| {' | '.join(cells)} |", flush=True)


def _largest_cycle_cut(tri, twin, colour, a, b, nb, ks: list[int], mcs: list[float]) -> tuple:
    """``(cycles, largest share, uncovered share, [cut / METIS per k])`` of a colouring's
    cover: its largest cycle's stretches (best shift), the other triangles given a
    neighbour's part (``--colourings``)."""
    from hammesh.partition import edge_cut
    from hammesh.postprocess.cycle_cover import cycle_ids_by_halves
    from partition_ceilings import cover_cycle_order, stretch_parts
    from partition_colourings import cover_of, cycle_sizes

    is_cov = cover_of(tri, twin, colour)
    cyc, n_cyc = cycle_ids_by_halves(twin, is_cov)
    m = len(tri)
    sizes = cycle_sizes(cyc, n_cyc)
    big = int(np.argmax(sizes))
    order = cover_cycle_order(twin, is_cov, cyc, big)
    local = np.full(m, -1, np.int64)
    local[order] = np.arange(len(order))
    on = (local[a] >= 0) & (local[b] >= 0)
    cuts = []
    for k, mc in zip(ks, mcs):
        part = np.full(m, -1, np.int64)
        part[order] = stretch_parts(np.arange(len(order)), k, local[a[on]], local[b[on]])
        cuts.append(edge_cut(_fill_parts(part, nb), a, b) / mc)
    return int(n_cyc), sizes[big] / m, float((cyc < 0).mean()), cuts


def _print_colourings(domains, target: int, ks: list[int]) -> None:
    """``--colourings``: sparse cycles as vertex colourings (``partition_colourings``).
    First on Triangle's mesh, the largest cycle of each colouring's cover cut as a cycle
    (the rest given a neighbour's part) / METIS's (median of 3 seeds); then through
    sparse mode itself, its cover replaced by ``compact_cover``: the price and the cut."""
    import os
    import sys

    import hammesh
    from hammesh.partition import dual_edges, partition
    from hammesh.postprocess import sparse as sp

    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import partition_colourings as pc
    from partition_ceilings import vertex_tree_cover

    print("| domain | triangles | colouring | uncovered | cycles | largest | " + " | ".join(f"k = {k}" for k in ks) + " |")
    print("|---|---|---|---|---|---|" + "---|" * len(ks))
    for name, dom, area in domains:
        mesh, a, b, twin, nb = _input_mesh(dom, area, target)
        tri = np.ascontiguousarray(mesh.triangles, dtype=np.int64)
        m, pts = len(tri), mesh.points
        bnd = pc.boundary_vertices(tri, twin, mesh.n_points)
        mcs = [_metis_median(k, a, b, m) for k in ks]
        tree = vertex_tree_cover(pts, tri, twin).inside.astype(np.int8)
        defer = pc.deferring_tree(pts, tri, twin)[0].astype(np.int8)
        rows = [("vertex tree (quadtree classes)", tree), ("the same, deferring doomed triangles", defer)]
        seeded = pc.colour_of_cover(tri, twin, pc.seeded_cover(pts, tri, twin, tree).is_cov, bnd)[0]
        rows.append(("cover seeded from the tree, no rotations", seeded))
        for levels, label in ((0, "in index order"), (10, "by scale, 10 levels")):
            c = seeded.copy()
            pc.scale_rotations(pts, tri, twin, c, levels)
            rows.append((f"the same, rotations {label}", c))
        for lmax in (4, 16, 64):
            c = defer.copy()
            pc.small_loop_adds(tri, twin, c, lmax)
            pc.capped_rotations(tri, twin, c, 2000)
            rows.append((f"deferring tree, loops <= {lmax + 2} added, capped rotations", c))
        axis, angle = pc.FISH_FRAMES[name]
        fish = pc.vertex_fishbone_tree(pc.turned(pts, angle), tri, twin, axis, levels=2).astype(np.int8)
        rows.append((f"vertex fishbone, 2 levels (axis {axis}, turned {angle:g})", fish))
        fish = pc.vertex_fishbone_tree(pc.turned(pts, angle), tri, twin, axis, penalty=5.0, max_defer=8,
                                       levels=2).astype(np.int8)
        rows.append(("the same, deferring doomed triangles", fish))
        c = fish.copy()
        pc.small_loop_adds(tri, twin, c, 4)
        pc.capped_rotations(tri, twin, c, 2000)
        rows.append(("the same, loops <= 6 added, capped rotations", c))
        comb = pc.vertex_fishbone_tree(pc.turned(pts, angle), tri, twin, axis, penalty=5.0, max_defer=8, levels=2,
                                       fill="comb").astype(np.int8)
        rows.append(("vertex fishbone, deferring, deepest cells as combs", comb))
        for label, c in rows:
            n_cyc, big, unc, cuts = _largest_cycle_cut(tri, twin, c, a, b, nb, ks, mcs)
            print(f"| {name} | {m:,} | {label} | {unc:.2%} | {n_cyc:,} | {big:.1%} | "
                  + " | ".join(f"{x:.2f}" for x in cuts) + " |", flush=True)
    print("\nThrough sparse mode (its cover replaced by partition_colourings.compact_cover; the output certified):\n")
    print("| domain | cover | triangles | Steiner points | min / max angle | rows below the parent rule | "
          + " | ".join(f"k = {k}" for k in ks) + " | CPU s | cover's cycles / uncovered |")
    print("|---|---|---|---|---|---|" + "---|" * len(ks) + "---|---|")
    for name, dom, area in domains:
        mesh = hammesh.quality_mesh(dom, min_angle=30, max_area=area / (0.63 * target))
        pc.FISH_AXIS, pc.FISH_ANGLE = pc.FISH_FRAMES[name]
        # (``reroute`` False: sparse's re-routes through uncovered boundary triangles off,
        # ``REROUTE_DEPTH = 0``: they split the cover's cycle into long arcs that the
        # joins splice back in another order)
        for label, tree, lmax, reroute, fill in (
                ("sparse's own (default)", None, None, True, "grow"),
                ("quadtree vertex tree, deferring", "quadtree", 0, True, "grow"),
                ("the same, loops <= 18, capped rotations", "quadtree", 16, True, "grow"),
                ("vertex fishbone, 2 levels, deferring", "fishbone", 0, True, "grow"),
                ("the same, loops <= 6, capped rotations", "fishbone", 4, True, "grow"),
                ("vertex fishbone, deferring; sparse's re-routes off", "fishbone", 0, False, "grow"),
                ("vertex fishbone, deferring, combs; re-routes off", "fishbone", 0, False, "comb")):
            orig, depth = sp.cycle_cover, sp.REROUTE_DEPTH
            pc.FISH_FILL = fill
            if lmax is not None:
                pc.TREE, pc.LMAX = tree, lmax
                sp.cycle_cover = pc.compact_cover
            if not reroute:
                sp.REROUTE_DEPTH = 0
            try:
                c0 = time.process_time()
                h = hammesh.hamiltonian(mesh, mode="sparse")
                cpu = time.process_time() - c0
            finally:
                sp.cycle_cover, sp.REROUTE_DEPTH = orig, depth
            r, m = h.report, h.n_triangles
            ha, hb = dual_edges(h.triangles, h.n_points)
            cuts = []
            for k in ks:
                p = partition(h, k)
                cuts.append(f"{p.edge_cut / _metis_median(k, ha, hb, m):.2f}" + ("" if p.connected else " (NOT connected)"))
            info = f"{pc.LAST['cycles']:,} / {pc.LAST['uncovered']:,}" if lmax is not None else ""
            print(f"| {name} | {label} | {m:,} | {r['steiner_points']:,} ({r['steiner_points'] / m:.2%}) "
                  f"| {r['min_angle_output_deg']:.1f} / {r['max_angle_output_deg']:.1f} | {r['below_parent_rule']:,} "
                  f"| {' | '.join(cuts)} | {cpu:.2f} | {info} |", flush=True)


def _print_blocks(domains, target: int, ks: list[int], sizes: list[int], along: str = "curve") -> None:
    """``--blocks``: a ring of compact blocks on Triangle's mesh (``partition_ceilings``),
    each / METIS's (median of 3 seeds), beside the sparse cycle's own ratio and what its
    cover's largest cycle alone cuts. ``along``: the blocks are runs of the generalized
    Hilbert curve (``curve``) or of the incircle walk on the same mesh (``walk``: each
    triangle at its median row)."""
    import os
    import sys

    import hammesh
    from hammesh.partition import dual_edges, edge_cut, partition
    from hammesh.postprocess.cycle_cover import cycle_cover

    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from partition_ceilings import (block_cycles, cover_cycle_order, curve_blocks, curve_order,
                                    order_cut, ring_order, stretch_parts, sweep_blocks, walk_positions)

    print("| domain | triangles | k | sparse (own) | its cover's largest cycle (share) | curve order (disconnected) | "
          + " | ".join(f"blocks of {b}: sweep / own cycles (disconnected)" for b in sizes) + " |")
    print("|---|---|---|---|---|---|" + "---|" * len(sizes))
    notes = []
    for name, dom, area in domains:
        mesh, a, b, twin, nb = _input_mesh(dom, area, target)
        m = mesh.n_triangles
        hs = hammesh.hamiltonian(mesh, mode="sparse")
        cover = cycle_cover(mesh.triangles, twin, points=mesh.points)
        big = int(np.argmax(np.bincount(cover.cycle[cover.cycle >= 0])))
        giant = cover_cycle_order(twin, cover.is_cov, cover.cycle, big)
        curve = curve_order(mesh.points[mesh.triangles].mean(axis=1), m // 2)
        runs = curve
        if along == "walk":
            hi = hammesh.hamiltonian(mesh, mode="incircle", tree="fishbone")
            runs = np.argsort(walk_positions(hi.parent, m)[1], kind="stable")
        rings = []
        for size in sizes:
            block = curve_blocks(runs, size, nb)
            t = time.process_time()
            bc = block_cycles(mesh.points, mesh.triangles, block)
            cpu = time.process_time() - t
            own, spliced = ring_order(bc.orders, block, nb)
            rings.append((sweep_blocks(block, nb), own))
            live = sum(1 for o in bc.orders if len(o))
            notes.append(f"{name}, blocks of {size} along the {along}: {live} blocks, {spliced} spliceable with no "
                         f"Steiner point; their own cycles {bc.steiner:,} Steiner points ({bc.steiner / m:.2%}), min angle "
                         f"{bc.min_angle:.1f}, {cpu:.1f} s CPU")
        for k in ks:
            mc = _metis_median(k, a, b, m)
            ha, hb = dual_edges(hs.triangles, hs.n_points)
            local = np.full(m, -1, np.int64)
            local[giant] = np.arange(len(giant))
            on = (local[a] >= 0) & (local[b] >= 0)
            gpart = np.full(m, -1, np.int64)
            gpart[giant] = stretch_parts(np.arange(len(giant)), k, local[a[on]], local[b[on]])
            gpart = _fill_parts(gpart, nb)
            cc, cdis = order_cut(curve, k, a, b)
            cells = []
            for sweep, own in rings:
                (sc, sdis), (oc, odis) = order_cut(sweep, k, a, b), order_cut(own, k, a, b)
                cells.append(f"{sc / mc:.2f} / {oc / mc:.2f} ({sdis}, {odis})")
            print(f"| {name} | {m:,} | {k} | {partition(hs, k).edge_cut / _metis_median(k, ha, hb, hs.n_triangles):.2f} "
                  f"| {edge_cut(gpart, a, b) / mc:.2f} ({len(giant) / m:.0%}) | {cc / mc:.2f} ({cdis}) "
                  f"| {' | '.join(cells)} |", flush=True)
    print()
    print("\n".join(notes))


def _mesh(dom, area: float, target: int, mode: str):
    import hammesh

    per_input = 3.0 if mode == "incircle" else 1.0
    m_in = target / per_input
    # Triangle's triangles at min angle 30 average about 0.63 x max_area
    mesh = hammesh.quality_mesh(dom, min_angle=30, max_area=area / (0.63 * m_in))
    how, tree = MODES[mode]
    return hammesh.hamiltonian(mesh, mode=how, tree=tree), mesh


def _sparse_price(name: str, mesh, repeat: int, option: str = "sparse-fishbone") -> list[str]:
    """Sparse mode's default against ``option`` (``tree="fishbone"`` or ``"comb"``) on the same input: Steiner
    points, min / max angle, rows below the parent rule, and the ``hamiltonian``
    call's process CPU (first call of each in this process, then ``repeat`` more
    alternating: median and range) and their ratio."""
    import hammesh

    cpu: dict = {"sparse": [], option: []}
    out: dict = {}
    for _ in range(1 + max(repeat, 0)):
        for mode in cpu:
            how, tree = MODES[mode]
            c = time.process_time()
            out[mode] = hammesh.hamiltonian(mesh, mode=how, tree=tree)
            cpu[mode].append(time.process_time() - c)
    base = float(np.median(cpu["sparse"]))
    rows = []
    for mode, h in out.items():
        r, m, c = h.report, h.n_triangles, cpu[mode]
        rows.append(f"| {name} | {mode} | {m:,} | {r['steiner_points']:,} ({r['steiner_points'] / m:.2%}) "
                    f"| {r['min_angle_output_deg']:.1f} / {r['max_angle_output_deg']:.1f} | {r['below_parent_rule']:,} "
                    f"| {c[0]:.2f} | {np.median(c):.2f} ({min(c):.2f}-{max(c):.2f}) | {np.median(c) / base:.2f} |")
    return rows


def _plain_forest_kernel():
    from numba import njit

    @njit(cache=True, nogil=True)
    def bfs_forest(tri, twin, is_con, order, rank, via, tri_r, code):
        """Breadth-first search over free edges from each unreached triangle (input
        order), numbering triangles as reached, then the packed codes (tree bit on the
        search's edges). Constrained edges are left out (the compact forest's extra
        union-find over them is not charged to the peer)."""
        m = tri.shape[0]
        rank[:] = -1
        n_seen = 0
        head = 0
        for s in range(m):
            if rank[s] >= 0:
                continue
            rank[s] = n_seen
            order[n_seen] = s
            via[n_seen] = -1
            n_seen += 1
            while head < n_seen:
                t = order[head]
                head += 1
                for kk in range(3):
                    g = twin[3 * t + kk]
                    if g < 0 or is_con[3 * t + kk]:
                        continue
                    u = g // 3
                    if rank[u] < 0:
                        rank[u] = n_seen
                        order[n_seen] = u
                        via[n_seen] = g
                        n_seen += 1
        for i in range(m):
            t = order[i]
            for kk in range(3):
                h = 3 * t + kk
                g = twin[h]
                bits = 1 if is_con[h] else 0
                tri_r[i, kk] = tri[t, kk]
                if g < 0:
                    code[3 * i + kk] = bits
                    continue
                u = g // 3
                if via[i] == h or via[rank[u]] == g:
                    bits |= 2
                code[3 * i + kk] = ((3 * rank[u] + g - 3 * u + 1) << 2) | bits
        return n_seen

    def plain_forest(tri, twin, is_con):
        m = len(tri)
        order, rank, via = (np.empty(m, np.int64) for _ in range(3))
        tri_r = np.empty_like(tri)
        code = np.empty(3 * m, np.int64)
        bfs_forest(tri, twin, is_con, order, rank, via, tri_r, code)
        return tri_r, code, order

    return plain_forest


def _forest_row(name: str, mesh, repeat: int) -> dict:
    from hammesh.halfedge import prepare_mesh
    from hammesh.postprocess._thm24_kernels import TREE_BIT, spanning_forest

    clean, he, is_con = prepare_mesh(mesh)
    tri, twin, pts = clean.triangles, he.twin, clean.points
    plain = _plain_forest_kernel()
    first, cpu = {}, {}

    def timed(which: str, f, *args):
        t, c = time.perf_counter(), time.process_time()
        r = f(*args)
        return r, time.perf_counter() - t, time.process_time() - c

    f, first["compact"], _ = timed("compact", spanning_forest, tri, twin, is_con, pts)
    (_, pcode, _), first["plain"], _ = timed("plain", plain, tri, twin, is_con)
    m = len(tri)
    pieces = len(f.firsts)
    assert int(((f.code & TREE_BIT) != 0).sum()) == 2 * (m - pieces)  # both are spanning forests
    best = {"compact": np.inf, "plain": np.inf}
    cpu = {"compact": np.inf, "plain": np.inf}
    for _ in range(max(repeat, 9)):  # cheap: enough repeats for a steady best on a loaded machine
        for which, fn, args in (("compact", spanning_forest, (tri, twin, is_con, pts)),
                                ("plain", plain, (tri, twin, is_con))):
            _, w, c = timed(which, fn, *args)
            best[which] = min(best[which], w)
            cpu[which] = min(cpu[which], c)
    return {"domain": name, "triangles": m, "first": first, "best": best, "cpu": cpu}


def _print_frames(size: int, repeat: int) -> None:
    """Process CPU of ``spanning_forest`` in its three frames on bench_core's square
    round a square hole (which wraps round its hole: the fishbone takes the ring frame),
    alternating: the fishbone in the ring frame, the same with the ring frame refused
    (``RING_ASPECT = 0``: the turned kd frame), and the count quadtree (``levels=0``,
    ``hamiltonian()``'s default tree)."""
    import os
    import sys

    import hammesh
    from hammesh.halfedge import prepare_mesh
    from hammesh.postprocess import _fishbone_kernels as fk
    from hammesh.postprocess._thm24_kernels import spanning_forest

    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from bench_core import _domain

    clean, he, is_con = prepare_mesh(hammesh.quality_mesh(_domain(), min_angle=30, max_area=0.96 / (0.63 * size)))
    tri, twin, pts = clean.triangles, he.twin, clean.points
    spanning_forest(tri, twin, is_con, pts)  # the kernels compiled or loaded
    old = fk.RING_ASPECT
    cpu: dict = {"ring frame": [], "kd frame": [], "count quadtree": []}
    try:
        for _ in range(max(repeat, 5)):
            for name in cpu:
                fk.RING_ASPECT = old if name == "ring frame" else 0.0
                c = time.process_time()
                spanning_forest(tri, twin, is_con, pts, levels=0 if name == "count quadtree" else fk.FISH_LEVELS)
                cpu[name].append(time.process_time() - c)
    finally:
        fk.RING_ASPECT = old
    base = np.median(cpu["count quadtree"])
    print("| tree | input triangles | forest CPU s, median (range) | / count quadtree |")
    print("|---|---|---|---|")
    for name, v in cpu.items():
        print(f"| {name} | {len(tri):,} | {np.median(v):.3f} ({min(v):.3f}-{max(v):.3f}) | {np.median(v) / base:.2f} |")


def _metis(k: int, xadj: np.ndarray, adjncy: np.ndarray, repeat: int) -> tuple[np.ndarray, float]:
    import pymetis

    best = np.inf
    parts = None
    for _ in range(repeat):
        t = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = pymetis.part_graph(k, xadj=xadj, adjncy=adjncy)
        best = min(best, time.perf_counter() - t)
        parts = np.asarray(res[1], dtype=np.int64)
    return parts, best


def _hilbert_parts(h, k: int) -> np.ndarray:
    from hammesh.numbering import hilbert_keys

    centroids = h.points[h.triangles].mean(axis=1)
    order = np.argsort(hilbert_keys(centroids), kind="stable")
    part = np.empty(h.n_triangles, np.int64)
    part[order] = (np.arange(h.n_triangles) * k) // h.n_triangles
    return part


def _wall_share(h, part: np.ndarray, a: np.ndarray, b: np.ndarray, n_in: int) -> float:
    """Share of the cut edges that are input edges (both ends input points: the walls of
    incircle mode); the rest are flipped edges and spokes (the spine)."""
    cut = part[a] != part[b]
    ta, tb = h.triangles[a[cut]], h.triangles[b[cut]]
    shared = (ta[:, :, None] == tb[:, None, :]).any(axis=2)
    ends = ta[shared].reshape(-1, 2)
    return float((ends < n_in).all(axis=1).mean()) if len(ends) else 0.0


def _row(name, mode, h, k, repeat, a, b, xadj, adjncy, n_in=None) -> dict:
    from hammesh.partition import edge_cut, part_components, partition

    m = h.n_triangles
    t = time.perf_counter()
    p = partition(h, k)  # from the triangles alone (finds the dual graph itself)
    first = time.perf_counter() - t
    best = best_nocheck = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        partition(h, k)
        best = min(best, time.perf_counter() - t)
        t = time.perf_counter()
        partition(h, k, edges=(a, b), check=False)  # handed the graph, as METIS is
        best_nocheck = min(best_nocheck, time.perf_counter() - t)
    mparts, mt = _metis(k, xadj, adjncy, repeat)
    mcut = edge_cut(mparts, a, b)
    mcomp = part_components(mparts, k, a, b)
    hpart = _hilbert_parts(h, k)
    hcut = edge_cut(hpart, a, b)
    hcomp = part_components(hpart, k, a, b)
    return {
        "domain": name,
        "mode": mode,
        "triangles": m,
        "k": k,
        "cut": p.edge_cut,
        "metis_cut": mcut,
        "cut_ratio": p.edge_cut / mcut,
        "connected": p.connected,
        "imbalance": p.imbalance,
        "metis_imbalance": float(np.bincount(mparts, minlength=k).max() * k / m),
        "metis_disconnected": int((mcomp > 1).sum()),
        "hilbert_cut_ratio": hcut / mcut,
        "hilbert_disconnected": int((hcomp > 1).sum()),
        "t_first": first,
        "t_best": best,
        "t_nocheck": best_nocheck,
        "t_metis": mt,
        # incircle: the share of each cut made of input edges (walls); the rest is spine
        "walls": (_wall_share(h, p.part, a, b, n_in), _wall_share(h, mparts, a, b, n_in)) if n_in else None,
    }


def _plot(h, k: int, path: str) -> None:
    """The k parts, coloured, as a PNG (where the stretches go: bands and wedges show)."""
    import os

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from hammesh.partition import partition

    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    part = partition(h, k).part
    fig, ax = plt.subplots(figsize=(10, 10))
    ax.tripcolor(h.points[:, 0], h.points[:, 1], h.triangles, facecolors=part % 20, cmap="tab20")
    ax.set_aspect("equal")
    ax.set_title(f"{h.n_triangles:,} triangles, k = {k}")
    fig.savefig(path, dpi=80)
    plt.close(fig)


def _numbering_rows(name, mode, h) -> list[str]:
    from hammesh.numbering import bandwidth_profile, renumber

    bw, pf = bandwidth_profile(h.triangles, h.n_points)
    rows = [f"| {name} | {mode} | as written | {bw:,} | {pf:,} | |"]
    for method in ("cycle", "rcm", "hilbert"):
        t = time.perf_counter()
        _, info = renumber(h, method)
        dt = time.perf_counter() - t
        rows.append(f"| {name} | {mode} | {method} | {info['bandwidth']:,} | {info['profile']:,} | {dt:.3f} |")
    return rows


def _print_forests(forests: list[dict]) -> None:
    print("| input mesh | input triangles | compact forest s (first, best) | plain BFS forest s (first, best) "
          "| compact / plain (best wall) | CPU s, compact / plain (best) |")
    print("|---|---|---|---|---|---|")
    for r in forests:
        f, b, c = r["first"], r["best"], r["cpu"]
        print(f"| {r['domain']} | {r['triangles']:,} | {f['compact']:.4f}, {b['compact']:.4f} "
              f"| {f['plain']:.4f}, {b['plain']:.4f} | {b['compact'] / b['plain']:.2f} "
              f"| {c['compact']:.3f} / {c['plain']:.3f} = {c['compact'] / c['plain']:.2f} |")
    if forests:
        worst = max(r["best"]["compact"] / r["best"]["plain"] for r in forests)
        print(f"\nworst compact / plain forest time {worst:.2f} (target <= 1.2; the compact forest runs its "
              "two halves on two threads, the plain one on one: CPU is the last column)")


def cut_ratio_cells(h, ks: list[int]) -> list[str]:
    """Cycle cut / METIS cut of ``h`` for each ``k`` in ``ks``, as table cells (METIS
    run once on ``h``'s own dual graph; "(disconnected)" marks a part in pieces)."""
    from scipy.sparse import coo_matrix

    from hammesh.partition import dual_edges, edge_cut, partition

    a, b = dual_edges(h.triangles)
    m = h.n_triangles
    g = coo_matrix((np.ones(len(a), np.int8), (a, b)), shape=(m, m))
    g = (g + g.T).tocsr()
    xadj, adjncy = g.indptr.astype(np.int64), g.indices.astype(np.int64)
    cells = []
    for k in ks:
        p = partition(h, k)
        mparts, _ = _metis(k, xadj, adjncy, 1)
        cells.append(f"{p.edge_cut / edge_cut(mparts, a, b):.2f}" + ("" if p.connected else " (disconnected)"))
    return cells


def _print_trees(domains, targets: list[int], ks: list[int], schemes: list[str] | None = None) -> None:
    """Incircle cycle cut / METIS cut of each tree scheme of ``partition_trees.SCHEMES``
    (METIS run on each scheme's own output: the outputs differ by their flips), on one
    mesh per entry of ``targets``; with several, the mean and the largest ratio of each
    scheme follow (one mesh's figure moves by about 0.1 with the mesh size alone).
    Fishbone schemes also get their cells' own cut at ``k = 4^j`` (``cells j``: the
    cycle cut where each level-``j`` cell is first reached, :func:`runs_of_cells`)."""
    import os
    import sys

    import hammesh

    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from partition_trees import SCHEMES, fishbone_of, runs_of_cells, tree

    from hammesh.halfedge import prepare_mesh
    from hammesh.partition import dual_edges, edge_cut, partition

    print("| domain | tree | triangles | " + " | ".join(f"k = {k}" for k in ks) + " | tree s |")
    print("|---|---|---|" + "---|" * len(ks) + "---|")
    ratios: dict = {}
    for name, dom, area in domains:
        for target in targets:
            mesh = hammesh.quality_mesh(dom, min_angle=30, max_area=area / (0.63 * target / 3.0))
            for scheme, weights in SCHEMES.items():
                if schemes and scheme not in schemes:
                    continue
                t = time.perf_counter()
                with tree(weights):
                    h = hammesh.hamiltonian(mesh, mode="incircle", tree="fishbone")
                dt = time.perf_counter() - t
                m = h.n_triangles
                cells = cut_ratio_cells(h, ks)
                ratios.setdefault((name, scheme), []).append([float(x.split()[0]) for x in cells])
                extra = ""
                if scheme.startswith("fishbone"):
                    twin = prepare_mesh(mesh)[1].twin
                    fb = fishbone_of(mesh.points, mesh.triangles, twin, **getattr(weights, "keywords", {}))
                    a, b = dual_edges(h.triangles)
                    mine = []
                    for k in ks:
                        j = int(round(np.log(k) / np.log(4)))
                        if 4**j == k and 0 < j < len(fb.labels):
                            run = runs_of_cells(h.parent, fb.labels[j])
                            sizes = np.bincount(run)
                            share = edge_cut(run, a, b) / partition(h, k).edge_cut
                            mine.append(f"k = {k}: cells' cut / cycle cut {share:.2f}, cells of {sizes.min():,}-{sizes.max():,}")
                    extra = " (" + "; ".join(mine) + ")" if mine else ""
                print(f"| {name} | {scheme} | {m:,} | " + " | ".join(cells) + f" | {dt:.1f} |{extra}", flush=True)
    if len(targets) > 1:
        print()
        print("| domain | tree | meshes | " + " | ".join(f"k = {k} mean / max" for k in ks) + " |")
        print("|---|---|---|" + "---|" * len(ks))
        for (name, scheme), v in ratios.items():
            v = np.array(v)
            print(f"| {name} | {scheme} | {len(v)} | "
                  + " | ".join(f"{v[:, i].mean():.3f} / {v[:, i].max():.2f}" for i in range(len(ks))) + " |")


#: ``--sparse-cells`` join orders (benchmark only: ``sparse._join_order`` is replaced inside the run).
#: ``tiers``: the shipped order (tier, kind, class, slack); ``levels``: first the quadtree
#: level *above the cover's cells* (joins inside a cell all in level 0), then the shipped
#: order, so that cells are joined to their siblings only once each is one cycle, while a
#: cell's own joins keep the best-slack order; ``classes``: the class first (every level);
#: ``hilbert``: joins inside a cell first, then between cells consecutive along a Hilbert
#: curve through the cells (a chain of cells), then the rest by class, each in the
#: shipped order (tier, kind, slack).
SPARSE_ORDERS = ("tiers", "levels", "classes", "hilbert")


def _sparse_order(order: str, cell_level: list):
    """A ``_join_order`` for ``--sparse-cells`` (see ``SPARSE_ORDERS``)."""
    from hammesh.postprocess import sparse
    from hammesh.postprocess._thm24_kernels import CENTRE_BINS

    shipped = sparse._join_order

    def join_order(kind, slack, newmin, pmin, whole, cls=None):
        if cls is None or order == "tiers":
            return shipped(kind, slack, newmin, pmin, whole, cls)
        meets = slack >= 0.0
        usable = (kind != sparse._j.NO_JOIN) & (meets | (newmin >= 0.5 * pmin))
        idx = np.flatnonzero(usable)
        kk = np.where(meets[idx], kind[idx], 0)
        tier = np.where(meets[idx], 0, np.where(whole[idx], 1, 2))
        c = cls[idx]
        if order == "classes":
            return idx[np.lexsort((-slack[idx], kk, tier, c))]
        if order == "hilbert":  # ``cls`` is ``_hilbert_classes``'
            return idx[np.lexsort((-slack[idx], kk, tier, c))]
        above = np.maximum(c // CENTRE_BINS - cell_level[0], 0)  # 0: inside one cell
        return idx[np.lexsort((-slack[idx], np.where(above > 0, c, 0), kk, tier, above))]

    return join_order


def _hilbert_classes(cell_level: list):
    """A ``join_classes`` for the ``hilbert`` order: 0 inside a cell (the quadtree's
    cell of the cover's level), 1 between cells consecutive along a Hilbert curve
    through the cells, else 2 + the shipped class."""
    from hammesh.numbering import hilbert_keys
    from hammesh.postprocess import cycle_cover

    def classes(quad, t, u):
        low = (1 << cycle_cover.CELL_BITS) - 1
        lv = cell_level[0]
        side = 1 << (cycle_cover.CELL_BITS - lv)
        cells = np.c_[(quad >> cycle_cover.CELL_BITS) >> lv, (quad & low) >> lv] + 0.5
        key = hilbert_keys(np.r_[cells, [[0.0, 0.0], [side, side]]], cycle_cover.CELL_BITS - lv)[:-2]
        gap = np.abs(key[t] - key[u])
        return np.where(gap == 0, 0, np.where(gap == 1, 1, 2 + cycle_cover.join_classes(quad, t, u)))

    return classes


def _print_sparse_cells(domains, target: int, ks: list[int], sizes: list[int], orders: list[str]) -> None:
    """Sparse cycle cut / METIS cut with the cover confined to quadtree cells of about
    ``size`` triangles (``cycle_cover.CELL_SIZE``; 0: not confined, the shipped cover)
    and the joins in each order of ``SPARSE_ORDERS``; Steiner points per output
    triangle and the ``hamiltonian`` call's wall and process CPU time (METIS run on each
    output)."""
    from unittest import mock

    import hammesh
    from hammesh.postprocess import cycle_cover, sparse

    cell_level = [0]
    cells = cycle_cover._cells

    def recording_cells(points, triangles, twin, m, size):  # the level ``_cells`` picks, kept
        quad, cell = cells(points, triangles, twin, m, size)
        low = (1 << cycle_cover.CELL_BITS) - 1
        area = float((quad >> cycle_cover.CELL_BITS).max() + 1) * float((quad & low).max() + 1)
        cell_level[0] = int(round(0.5 * np.log2(max(size * area / m, 1.0))))
        return quad, cell

    print("| domain | cells of | join order | triangles | Steiner points | " + " | ".join(f"k = {k}" for k in ks)
          + " | min / max angle | rows below the parent rule | hamiltonian s (wall, CPU) |")
    print("|---|---|---|---|---|" + "---|" * len(ks) + "---|---|---|")
    for name, dom, area in domains:
        mesh = hammesh.quality_mesh(dom, min_angle=30, max_area=area / (0.63 * target))
        for size in sizes:
            for order in (orders if size else ["tiers"]):
                with mock.patch.object(cycle_cover, "CELL_SIZE", size), \
                        mock.patch.object(cycle_cover, "_cells", recording_cells), \
                        mock.patch.object(sparse, "_join_order", _sparse_order(order, cell_level)), \
                        mock.patch.object(sparse, "join_classes",
                                          _hilbert_classes(cell_level) if order == "hilbert" else sparse.join_classes):
                    t, c = time.perf_counter(), time.process_time()
                    h = hammesh.hamiltonian(mesh, mode="sparse")
                    dt, dc = time.perf_counter() - t, time.process_time() - c
                m = h.n_triangles
                out = cut_ratio_cells(h, ks)
                r = h.report
                st = r["steiner_points"]
                print(f"| {name} | {size or 'not confined'} | {order if size else '-'} | {m:,} | {st:,} ({st / m:.2%}) | "
                      + " | ".join(out) + f" | {r['min_angle_output_deg']:.1f} / {r['max_angle_output_deg']:.1f} "
                      f"| {r['below_parent_rule']:,} | {dt:.2f}, {dc:.2f} |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--target", type=int, default=300_000, help="triangles of each Hamiltonian mesh")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="30 000 triangles, one repeat (a smoke run)")
    ap.add_argument("--forest-size", type=int, default=0,
                    help="also time the forests on a unit square of about this many input triangles")
    ap.add_argument("--forest-only", action="store_true", help="only the forest table")
    ap.add_argument("--domains", default="plate_2_holes,gear",
                    help="comma-separated: plate_2_holes, gear (the issue's), square, rect_2x1 (hole-free controls)")
    ap.add_argument("--modes", default="incircle,sparse,sparse-fishbone",
                    help="comma-separated: incircle, sparse, sparse-fishbone, sparse-comb (sparse mode's "
                         "tree=\"fishbone\", \"comb\")")
    ap.add_argument("--ks", default="8,64", help="comma-separated part counts")
    ap.add_argument("--trees", action="store_true",
                    help="only the incircle cut of other spanning trees (benchmarks/partition_trees.py) vs METIS")
    ap.add_argument("--targets", default="",
                    help="--trees: comma-separated mesh sizes (triangles), one mesh each; mean and max ratio follow")
    ap.add_argument("--schemes", default="", help="--trees' schemes (comma-separated; default: all)")
    ap.add_argument("--sparse-cells", metavar="SIZES", default="",
                    help="only the sparse cut with the cover confined to cells of these sizes (0: not), "
                         "comma-separated, each join order of SPARSE_ORDERS (--orders)")
    ap.add_argument("--orders", default=",".join(SPARSE_ORDERS), help="--sparse-cells' join orders")
    ap.add_argument("--frames", metavar="SIZE", type=int, default=0,
                    help="only the forest's CPU in the ring frame, the kd frame and as the count quadtree, on "
                         "bench_core's square round a square hole of about SIZE input triangles")
    ap.add_argument("--ceilings", action="store_true",
                    help="only the cut of orders a sparse cycle could follow, on Triangle's mesh (partition_ceilings.py)")
    ap.add_argument("--blocks", metavar="SIZES", default="",
                    help="only the cut of a ring of compact blocks of these sizes (comma-separated), on Triangle's "
                         "mesh (partition_ceilings.py)")
    ap.add_argument("--along", choices=("curve", "walk"), default="curve",
                    help="--blocks: runs of a generalized Hilbert curve, or of the incircle walk on the same mesh")
    ap.add_argument("--colourings", action="store_true",
                    help="only sparse cycles as vertex colourings (partition_colourings.py): repairs of a compact "
                         "vertex tree, on Triangle's mesh and through sparse mode")
    ap.add_argument("--plot", metavar="DIR", default="",
                    help="also draw each partition (parts coloured) to DIR/<domain>_<mode>_<k>.png")
    args = ap.parse_args()
    if args.quick:
        args.target, args.repeat = 30_000, 1
    import hammesh

    if args.frames:
        _print_frames(args.frames, args.repeat)
        return
    forests = []
    if args.forest_size:
        sq = hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])
        forests.append(_forest_row("unit square", hammesh.quality_mesh(sq, min_angle=30, max_area=1 / (0.63 * args.forest_size)), args.repeat))
    if args.forest_only:
        _print_forests(forests)
        return
    from scipy.sparse import coo_matrix

    from hammesh.partition import dual_edges

    rows, numbering, price = [], [], []
    chosen = args.domains.split(",")
    known = [d[0] for d in _domains()]
    if set(chosen) - set(known):
        ap.error(f"--domains: unknown {sorted(set(chosen) - set(known))}; known: {known}")
    if set(args.modes.split(",")) - set(MODES):
        ap.error(f"--modes: some of {sorted(MODES)}")
    ks = [int(k) for k in args.ks.split(",")]
    if args.sparse_cells:
        _print_sparse_cells([d for d in _domains() if d[0] in chosen], args.target, ks,
                            [int(x) for x in args.sparse_cells.split(",")], args.orders.split(","))
        return
    if args.ceilings:
        _print_ceilings([d for d in _domains() if d[0] in chosen], args.target, ks)
        return
    if args.colourings:
        _print_colourings([d for d in _domains() if d[0] in chosen], args.target, ks)
        return
    if args.blocks:
        _print_blocks([d for d in _domains() if d[0] in chosen], args.target, ks,
                      [int(x) for x in args.blocks.split(",")], args.along)
        return
    if args.trees:
        targets = [int(float(x)) for x in args.targets.split(",")] if args.targets else [args.target]
        _print_trees([d for d in _domains() if d[0] in chosen], targets, ks,
                     args.schemes.split(",") if args.schemes else None)
        return
    for name, dom, area in (d for d in _domains() if d[0] in chosen):
        for mode in args.modes.split(","):
            h, mesh = _mesh(dom, area, args.target, mode)
            if mode == "incircle":
                forests.append(_forest_row(name, mesh, args.repeat))
            if mode in ("sparse-fishbone", "sparse-comb"):
                price += _sparse_price(name, mesh, args.repeat, mode)
            a, b = dual_edges(h.triangles)
            m = h.n_triangles
            g = coo_matrix((np.ones(len(a), np.int8), (a, b)), shape=(m, m))
            g = (g + g.T).tocsr()
            xadj, adjncy = g.indptr.astype(np.int64), g.indices.astype(np.int64)
            for k in ks:
                r = _row(name, mode, h, k, args.repeat, a, b, xadj, adjncy,
                         n_in=mesh.n_points if mode == "incircle" else None)
                rows.append(r)
                if args.plot:
                    _plot(h, k, f"{args.plot}/{name}_{mode}_{k}.png")
                print(
                    f"{name:14s} {mode:8s} m={m:,} k={k:2d}: cut {r['cut']:,} / METIS {r['metis_cut']:,} = "
                    f"{r['cut_ratio']:.2f}; connected {r['connected']}; imbalance {r['imbalance']:.5f}; "
                    f"time {r['t_nocheck']:.4f} s / METIS {r['t_metis']:.3f} s = 1/{r['t_metis'] / r['t_nocheck']:.0f} "
                    f"(from triangles alone {r['t_best']:.4f} s)"
                    + (f"; walls {r['walls'][0]:.0%} of our cut, {r['walls'][1]:.0%} of METIS's" if r["walls"] else ""),
                    flush=True,
                )
            numbering += _numbering_rows(name, mode, h)
    print()
    print("| domain | mode | triangles | k | cycle cut | METIS cut | ratio | parts connected | imbalance "
          "| METIS imbalance / disconnected | Hilbert ratio / disconnected | partition s (first, best; given graph, no check) "
          "| METIS s | METIS / partition |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(
            f"| {r['domain']} | {r['mode']} | {r['triangles']:,} | {r['k']} | {r['cut']:,} | {r['metis_cut']:,} "
            f"| {r['cut_ratio']:.2f} | {'all' if r['connected'] else 'NO'} | {r['imbalance']:.5f} "
            f"| {r['metis_imbalance']:.3f} / {r['metis_disconnected']} "
            f"| {r['hilbert_cut_ratio']:.2f} / {r['hilbert_disconnected']} "
            f"| {r['t_first']:.4f}, {r['t_best']:.4f}, {r['t_nocheck']:.4f} | {r['t_metis']:.3f} "
            f"| {r['t_metis'] / r['t_nocheck']:.1f} |"
        )
    worst = max(r["cut_ratio"] for r in rows)
    slow = min(r["t_metis"] / r["t_nocheck"] for r in rows)
    ok = all(r["connected"] for r in rows) and all(r["imbalance"] <= 1 + 1.0 * r["k"] / r["triangles"] for r in rows)
    print(f"\nworst cut ratio {worst:.2f} (target <= 1.5, goal 1.1); all connected and balanced: {ok}; "
          f"smallest METIS / partition time {slow:.1f} (target >= 20)")
    if price:
        print("\nSparse mode's price of its tree options (same input; hamiltonian process CPU: first call, then "
              "median (range) of --repeat more, alternating):\n")
        print("| domain | mode | triangles | Steiner points | min / max angle | rows below the parent rule "
              "| CPU s first | CPU s median (range) | / sparse |")
        print("|---|---|---|---|---|---|---|---|---|")
        print("\n".join(price))
    print()
    _print_forests(forests)
    print()
    print("| domain | mode | numbering | bandwidth | profile | seconds |")
    print("|---|---|---|---|---|---|")
    print("\n".join(numbering))


if __name__ == "__main__":
    main()
