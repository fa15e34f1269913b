"""``hammesh points``: a point set -> Hamiltonian (Thm 3.1) or sequential (§4) triangulation."""

from __future__ import annotations

import argparse
from pathlib import Path

HELP = "triangulate a point set so that its triangles form one Hamiltonian cycle (Thm 3.1)"
EXAMPLES = """examples:
  hammesh points cloud.node -o cloud.vtu --png cloud.png      # Thm 3.1, O(n log n)
  hammesh points pts.txt -o strip.vtu --sequential            # one alternating strip (§4)
  hammesh points pts.npy -o pts.msh --seed 3
inputs: .node (Triangle), .npy ((n, 2) array), anything else: plain text, one "x y" per line
        (# comments, commas allowed).
outputs: any mesh format of hammesh.io; triangles are written in cycle (or strip) order.
exit codes: 0 ok, 2 bad input or no sequential triangulation (--sequential), 3 verification failed."""


def add_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("input", type=Path, help="points (.node, .npy or 'x y' text)")
    p.add_argument("-o", "--output", type=Path, help="output mesh (.vtu .msh .obj .ele ...)")
    p.add_argument("--png", type=Path, help="draw the triangulation and its cycle into this image")
    p.add_argument("--sequential", action="store_true",
                   help="require a sequential triangulation (alternating strip, §4): any size with "
                        "at most two interior points (Lemma 4.2), else at most 12 points")
    p.add_argument("--seed", type=int, help="seed of the random splitters (Lemma 3.2)")


def run(args: argparse.Namespace) -> int:
    from hammesh import pointset
    from hammesh.io.points_text import read_points
    from hammesh.errors import InvalidDomainError

    from hammesh import params
    from hammesh.io import check_outputs
    from hammesh.mesh import HamiltonianMesh

    if args.seed is not None:
        params.integer("--seed", args.seed, low=0, high=2**63 - 1)
    from hammesh.errors import FileFormatError
    from hammesh.io import supported_suffixes

    if args.output is not None and args.output.suffix.lower() not in supported_suffixes():
        raise FileFormatError(f"{args.output}: unknown output format; supported: {' '.join(supported_suffixes())}")
    if args.png is not None and args.png.suffix.lower() != ".png":
        raise FileFormatError(f"{args.png}: the picture is PNG; use a .png file name")
    check_outputs({"-o": args.output, "--png": args.png}, [args.input])
    pts = pointset.as_points(read_points(args.input))
    hull = pointset.convex_hull(pts)
    if args.sequential:
        tri = pointset.sequential_triangulation(pts)
        if tri is None:
            raise InvalidDomainError(
                f"{args.input.name}: these {len(pts)} points have no sequential triangulation "
                "(proved by the exact search, or by the zigzag test in convex position)"
            )
        shape = "sequential strip"
    else:
        tri = pointset.hamiltonian_triangulation(pts, seed=args.seed)
        shape = "Hamiltonian cycle" if hull.h < len(pts) else "Hamiltonian path (convex position)"
    mesh = HamiltonianMesh.from_order(pts, tri)
    print(f"{len(pts):,} points ({hull.h} on the hull) -> {len(tri):,} triangles, {shape}, verified")
    if args.output is not None:
        from hammesh.io import write
        from hammesh.io.paths import wrote_text

        write(mesh, args.output)
        print(f"wrote mesh: {wrote_text(args.output)}")
    if args.png is not None:
        from hammesh.plot import plot_cycle

        closed = shape == "Hamiltonian cycle"
        title = None if closed else f"{shape} (the closing segment is not part of it)"
        plot_cycle(mesh, args.png, title=title)
        print(f"wrote picture: {args.png}")
    return 0
