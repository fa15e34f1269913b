"""``hammesh mesh``: domain or mesh file -> verified Hamiltonian cycle mesh."""

from __future__ import annotations

import argparse
from functools import partial
from pathlib import Path

from hammesh import params
from hammesh.errors import InvalidOptionError

HELP = "mesh a domain (or take a mesh file) and make it a verified Hamiltonian cycle mesh"
EXAMPLES = """examples:
  hammesh mesh plate.poly --min-angle 30 --max-area 0.01 -o plate.vtu --report plate.json --png plate.png
  hammesh mesh A.poly --min-angle 25 -o A.msh
  hammesh mesh existing.vtu -o hamiltonian.vtu        # post-process a mesh made elsewhere
  hammesh mesh plate.poly -q 30 --strip plate.json    # the cycle as one GL triangle strip
inputs: .poly/.node are domains (meshed first); .vtu .msh .xdmf .obj .ply .ele ... are meshes."""


#: the names of ``hammesh.meshing.BACKENDS`` and ``hammesh.postprocess.MODES``, spelled
#: here so that parsing the options imports neither registry: their modules load numba,
#: scipy and every kernel module (0.3-0.7 s measured), and the parallel path starts its
#: local cluster before it imports them (docs/scale.md "The driver's start");
#: tests/cli/test_cli_choices.py holds them equal to the registries
BACKEND_NAMES = ("meshpy", "triangle")
MODE_NAMES = ("incircle", "sparse")
#: ``hammesh.postprocess.sparse.KEEP``, spelled here for the same reason (the same test)
KEEP = 0.9


def add_args(p: argparse.ArgumentParser) -> None:
    from hammesh.numbering import NUMBERINGS  # (a light module: numpy and hammesh.mesh)

    p.add_argument("input", type=Path, help="domain (.poly, .node) or triangle mesh file")
    p.add_argument("-o", "--output", type=Path, help="output mesh (.vtu .msh .xdmf .obj .ply .ele ...)")
    p.add_argument("--report", type=Path, help="write the report JSON here")
    p.add_argument("--png", type=Path, help="draw the mesh and its cycle into this PNG")
    p.add_argument("--strip", type=Path, help="write the cycle as a GL triangle-strip buffer (.json/.npz)")
    g = p.add_argument_group("quality meshing (domain inputs)")
    g.add_argument("-q", "--min-angle", type=float, help="minimum angle in degrees (0..34)")
    g.add_argument("-a", "--max-area", type=float, help="maximum triangle area (> 0)")
    g.add_argument("--backend", choices=BACKEND_NAMES, default="triangle")
    g.add_argument("--conforming-delaunay", action="store_true", help="every triangle Delaunay (-D)")
    g.add_argument("--max-steiner", type=int, help="limit on Steiner points added by the mesher")
    g.add_argument("--timeout", type=float, help="stop the mesher after this many seconds")
    p.add_argument(
        "--mode", choices=MODE_NAMES, default="sparse",
        help="Hamiltonian construction: sparse (default, keeps the input's quality) or incircle (Thm 2.4)",
    )
    p.add_argument(
        "--keep", type=float,
        help="sparse mode: new angles >= KEEP x the replaced triangles' smallest where a join can (0..1, "
             "default 0.9)",
    )
    g = p.add_argument_group("partition and numbering (issue 14; docs/partition.md)")
    g.add_argument("--parts", type=int, metavar="K",
                   help="cut the cycle into K connected, balanced parts: a 'part' cell array in the output")
    g.add_argument("--tree", choices=("quadtree", "fishbone", "comb"),
                   help="incircle mode's spanning tree: fishbone (the default with --parts) sweeps the domain so "
                        "that parts cut close to METIS, ~20%% slower; quadtree (the default otherwise) is the fastest. "
                        "Sparse mode: fishbone confines the cover to the fishbone's cells (an opt-in: more Steiner "
                        "points, lower angles; docs/partition.md); comb (sparse mode only) a compact cover from "
                        "an induced vertex tree (round the hole of a ring-shaped domain): cuts ~1.2-1.4x METIS, "
                        "~0.5%% Steiner points, angles down to ~16 deg (the default keeps ~27 at q30)")
    g.add_argument("--renumber", choices=NUMBERINGS,
                   help="renumber the vertices (bandwidth/profile in the report)")
    g = p.add_argument_group("parallel (decoupled tiles, docs/scale.md; domain inputs with -a)")
    g.add_argument("--workers", type=int, help="mesh the tiles on a local Dask cluster of N processes "
                   "(pip install hammesh[dask])")
    g.add_argument("--scheduler", help="use the running Dask scheduler at this address instead")
    g.add_argument("--tiles", type=int, help="number of tiles (default: one per worker, more past 3M triangles)")
    g.add_argument("--partitioned", action="store_true",
                   help="-o is a directory: one .vtu per tile written by its worker + mesh.pvtu (cycle order)")
    g.add_argument("--force", action="store_true",
                   help="--partitioned: replace the content of an existing non-empty -o directory")
    g.add_argument("--no-lattice", action="store_true",
                   help="mesh each tile by Triangle alone, without the interior lattice of points")
    p.add_argument("--strict", action="store_true",
                   help="refuse an input that needs repairs (quads, T-junctions, crossing segments...) "
                        "instead of repairing it; the report's 'repairs' lists what was repaired")


def spanning_tree(args: argparse.Namespace) -> str:
    """The ``tree`` these options ask for, the same on the serial and the parallel path:
    ``--tree`` if given (sparse mode too: ``fishbone`` is its opt-in compact cycle);
    else incircle mode's fishbone with ``--parts``, and quadtree otherwise (sparse mode
    keeps its free cover with ``--parts`` alone)."""
    return args.tree or ("fishbone" if args.parts is not None and args.mode == "incircle" else "quadtree")


def run(args: argparse.Namespace) -> int:
    # options hamiltonian() would refuse, refused before minutes of meshing
    if args.keep is not None and args.mode == "incircle":  # (it would be ignored: say so, not silently)
        raise InvalidOptionError("--keep applies to --mode sparse (incircle mode has no local quality rule)")
    args.keep = KEEP if args.keep is None else args.keep
    params.number("--keep", args.keep, low=0, high=1, what="the local quality rule's factor")
    if args.workers is not None or args.scheduler is not None or args.partitioned or args.tiles is not None \
            or args.force or args.no_lattice:
        from hammesh.parallel.command import run_parallel

        return run_parallel(args)
    from hammesh.cli.pipeline import Outputs, load_input, run_pipeline, summary
    from hammesh.domain import Domain
    from hammesh.partition import partitioned

    outputs = Outputs(mesh=args.output, report=args.report, png=args.png, strip=args.strip, inputs=(args.input,))
    outputs.check()  # before reading: a bad output path costs nothing
    if args.timeout is not None:
        params.number("--timeout", args.timeout, low=0, low_open=True, high=params.MAX_SECONDS, what="seconds")
    source = load_input(args.input, strict=args.strict)
    options = {
        "min_angle": args.min_angle,
        "max_area": args.max_area,
        "backend": args.backend,
        "conforming_delaunay": args.conforming_delaunay,
        "max_steiner": args.max_steiner,
        "timeout": args.timeout,
    }
    if not isinstance(source, Domain):
        given = ["--" + k.replace("_", "-") for k, v in options.items() if v not in (None, False, "triangle")]
        if given:
            raise InvalidOptionError(
                f"{args.input} is already a mesh; meshing options ({', '.join(given)}) apply to .poly/.node domains"
            )
    finish = None
    if args.parts is not None or args.renumber is not None:
        if args.parts is not None:
            params.integer("--parts", args.parts, low=1, what="number of parts")
        finish = partial(partitioned, k=args.parts, renumber=args.renumber)
    tree = spanning_tree(args)
    h = run_pipeline(source, options, outputs, mode=args.mode, keep=args.keep, tree=tree, strict=args.strict,
                     finish=finish)
    print(summary(h))
    from hammesh.io.paths import wrote_text  # (a .ele output's .node/.poly named too)

    for label, path in (
        ("mesh", args.output),
        ("report", args.report),
        ("picture", args.png),
        ("strip", args.strip),
    ):
        if path is not None:
            print(f"wrote {label}: {wrote_text(path) if label == 'mesh' else path}")
    return 0
