"""``hammesh strip``: any triangle mesh file -> a verified triangle-strip index buffer."""

from __future__ import annotations

import argparse
from pathlib import Path

from hammesh.errors import FileFormatError, InvalidOptionError

HELP = "encode a triangle mesh (2D or 3D) as a verified GL triangle-strip index buffer"
EXAMPLES = """examples:
  hammesh strip bunny.ply -o bunny.json                  # greedy strips joined by restart
  hammesh strip plate.vtu -o plate.json --join stitch    # one strip, degenerate stitching
  hammesh strip plate.vtu -o plate.npz                   # binary (uint32 indices)
  hammesh strip small.obj -o small.json --method christofides   # Thm 5.3, <= 5000 triangles
  hammesh strip plate.vtu -o plate.json --generalized    # IRIS GL: one vertex + one bit each
methods: auto (a file stored in Hamiltonian-cycle order, as 'hammesh mesh' writes it, is sent
as one strip per cycle when that is shorter than the greedy cover), greedy, order, christofides.
Every buffer is decoded with OpenGL's rules and compared with the mesh before it is written."""


def add_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("mesh", type=Path, help="triangle mesh (.vtu .msh .obj .ply .stl .off .ele ...)")
    p.add_argument("-o", "--output", type=Path, required=True, help="strip buffer (.json or .npz)")
    p.add_argument("--join", choices=("restart", "stitch"), default="restart", help="how strips are joined")
    p.add_argument("--restart-index", type=int, default=0xFFFFFFFF, help="primitive restart index")
    p.add_argument("--generalized", action="store_true", help="write generalized strips (vertex + turn bit)")
    p.add_argument(
        "--method", choices=("auto", "greedy", "order", "christofides"), default="auto", help="how to find the strips"
    )


def run(args: argparse.Namespace) -> int:
    from hammesh.strips.christofides import christofides_strip
    from hammesh.strips.encode import encode, encode_generalized
    from hammesh.strips.files import STRIP_SUFFIXES, read_surface, write_strip

    if args.output.suffix.lower() not in STRIP_SUFFIXES:
        raise FileFormatError(f"{args.output}: output must be {' or '.join(STRIP_SUFFIXES)}")
    if not args.mesh.exists():
        raise FileFormatError(f"{args.mesh}: no such file")
    if args.generalized and args.method == "christofides":
        raise InvalidOptionError("--generalized is not available with --method christofides")
    mesh = read_surface(args.mesh)
    method = args.method
    extra: dict = {}
    if args.generalized:
        if method == "auto":
            candidates = [("greedy", encode_generalized(mesh, method="greedy"))]
            try:
                candidates.append(("order", encode_generalized(mesh, method="order")))
            except (InvalidOptionError, ValueError):
                pass
            method, strip = min(candidates, key=lambda c: len(c[1].vertices))
        else:
            strip = encode_generalized(mesh, method=method)
    elif method == "christofides":
        enc = christofides_strip(mesh, join=args.join, restart_index=args.restart_index)
        strip = enc.strip
        extra["christofides"] = enc.report()
        # the contract counts mesh triangles; redrawn ones are reported apart
        extra["drawn"] = strip.n_triangles
        extra["triangles"] = enc.n_triangles
        extra["indices_per_triangle"] = len(strip.indices) / enc.n_triangles
    elif method == "auto":
        kw = {"join": args.join, "restart_index": args.restart_index}
        candidates = [("greedy", encode(mesh, method="greedy", **kw))]
        try:
            candidates.append(("order", encode(mesh, method="order", **kw)))
        except (InvalidOptionError, ValueError):
            pass  # rows are not stored as dual paths: greedy only
        method, strip = min(candidates, key=lambda c: len(c[1].indices))
    else:
        strip = encode(mesh, method=method, join=args.join, restart_index=args.restart_index)
    extra["method"] = method
    write_strip(strip, args.output, extra)
    n_tri = extra.get("triangles", strip.n_triangles)
    ipt = extra.get("indices_per_triangle", strip.indices_per_triangle)
    print(
        f"{args.mesh}: {n_tri:,} triangles -> {strip.n_strips} strip(s), "
        f"{strip.n_swaps} swap(s), {ipt:.4f} indices per triangle ({method}); wrote {args.output}"
    )
    return 0
