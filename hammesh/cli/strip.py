"""``hammesh strip``: any triangle mesh file -> a verified triangle-strip index buffer."""

from __future__ import annotations

import argparse
from pathlib import Path

from hammesh.errors import FileFormatError

HELP = "encode a triangle mesh (2D or 3D) as a verified GL triangle-strip index buffer"
EXAMPLES = """examples:
  hammesh strip bunny.ply -o bunny.json                  # greedy strips joined by restart
  hammesh strip plate.vtu -o plate.json --join stitch    # one strip, degenerate stitching
  hammesh strip plate.vtu -o plate.npz                   # binary (uint32 indices)
  hammesh strip small.obj -o small.json --method christofides   # Thm 5.3, <= 5000 triangles
  hammesh strip plate.vtu -o plate.json --generalized    # IRIS GL: one vertex + one bit each
  hammesh strip plate.vtu -o plate.json --cache --reorder-vertices   # for a 32-entry FIFO
  hammesh strip plate.vtu -o plate.json --cache 16       # for a 16-entry FIFO
  hammesh strip big.vtu -o big.npz --fast                # greedy cover alone (no end moves)
methods: auto (the shortest of rows (planar meshes), greedy, zigzag and, for a file stored in
Hamiltonian-cycle order as 'hammesh mesh' writes it, one strip per cycle), greedy, zigzag (from
swap-free chains), rows (from rows along the x or y axis), order, christofides.
Every buffer is decoded with OpenGL's rules and compared with the mesh before it is written.
The document reports the buffer's FIFO cache figures (acmr, atvr, overfetch; 16 entries
unless --cache says otherwise)."""


#: Options whose value may be left out, and the value then (``hammesh.cli.with_bare_values``:
#: ``--cache mesh.vtu`` must not read the mesh's name as the number).
BARE_VALUES = {"--cache": "32"}


def add_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("mesh", type=Path, help="triangle mesh (.vtu .msh .obj .ply .stl .off .ele ...)")
    p.add_argument("-o", "--output", type=Path, required=True, help="strip buffer (.json or .npz)")
    p.add_argument("--join", choices=("restart", "stitch"), default="restart", help="how strips are joined")
    p.add_argument("--restart-index", type=int, default=0xFFFFFFFF, help="primitive restart index (0..4294967295)")
    p.add_argument("--generalized", action="store_true", help="write generalized strips (vertex + turn bit)")
    p.add_argument(
        "--method", choices=("auto", "greedy", "order", "zigzag", "rows", "christofides"), default="auto", help="how to find the strips"
    )
    g = p.add_argument_group("GPU caches")
    # const: hammesh.strips.cache.CACHE_MODE_FIFO, written out to keep the CLI's imports lazy (a test compares)
    g.add_argument("--cache", type=int, nargs="?", const=int(BARE_VALUES["--cache"]), default=None, metavar="N",
                   help="lay strips for a FIFO vertex cache of N entries (typical 16-32; --cache alone: 32). "
                        "Planar meshes: rows (strips along the x or y axis) cut into columns of ~11N/16 triangles "
                        "a row and sent column by column, so each row finds the vertices of the row before "
                        "still cached (q30 meshes, FIFO 32: ~0.62-0.63 vertex loads per triangle at ~1.28-1.30 "
                        "indices, meshoptimizer's vertex-cache order + stripify ~0.64 at ~1.72; FIFO 16: ~0.68-0.70 "
                        "at ~1.36-1.38, meshoptimizer ~0.71; without --cache ~1.0 at ~1.23). Surfaces: the "
                        "swap-free (zigzag) chains cut into pieces of ~1.25 N triangles, "
                        "sent in an order that finds their vertices cached (~0.8 at ~1.36 at FIFO 16). With "
                        "--method greedy or zigzag: that cover in pieces of at most 3 N in that order")
    p.add_argument("--fast", action="store_true",
                   help="the greedy cover alone, no end moves: faster, ~0.03 more indices per triangle")
    g.add_argument("--reorder-vertices", action="store_true",
                   help="renumber vertices in order of first use; the document lists vertex_order")


def run(args: argparse.Namespace) -> int:
    from hammesh import params
    from hammesh.io import check_outputs, read_mesh
    from hammesh.io.paths import require_file
    from hammesh.strips.choose import MAX_RESTART_INDEX, choose_strip
    from hammesh.strips.files import STRIP_SUFFIXES, write_strip

    if args.output.suffix.lower() not in STRIP_SUFFIXES:
        raise FileFormatError(f"{args.output}: output must be {' or '.join(STRIP_SUFFIXES)}")
    params.integer("--restart-index", args.restart_index, low=0, high=MAX_RESTART_INDEX,
                   what="GL index buffers are uint32")
    check_outputs({"-o": args.output}, [args.mesh])
    require_file(args.mesh)  # (no such file / is a directory / not a regular file: as every reader says)
    if args.generalized and args.method == "christofides":
        raise params.invalid("--method", args.method, "not 'christofides' with --generalized")
    if args.cache is not None:
        params.integer("--cache", args.cache, low=3, high=1 << 16, what="FIFO entries")
    mesh = read_mesh(args.mesh, dim=None)
    choice = choose_strip(mesh, method=args.method, join=args.join, restart_index=args.restart_index,
                          generalized=args.generalized, cache=args.cache, reorder_vertices=args.reorder_vertices,
                          fast=args.fast)
    repairs = mesh.info.get("repairs", [])
    extra = {**choice.extra, "repairs": list(repairs)}
    write_strip(choice.strip, args.output, extra)
    cache = f"; ACMR {choice.extra['acmr']:.3f} at FIFO {choice.extra['cache_size']}" if "acmr" in choice.extra else ""
    print(
        f"{args.mesh}: {choice.n_triangles:,} triangles -> {choice.strip.n_strips} strip(s), "
        f"{choice.strip.n_swaps} swap(s), {choice.indices_per_triangle:.4f} indices per triangle "
        f"({choice.method}){cache}; wrote {args.output}"
        + (f"\nrepairs: {'; '.join(map(str, repairs))}" if repairs else "")
    )
    return 0
