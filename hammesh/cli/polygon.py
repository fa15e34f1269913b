"""``hammesh polygon``: a simple polygon -> Hamiltonian / sequential / Steiner triangulation."""

from __future__ import annotations

import argparse
from pathlib import Path


from hammesh.errors import InvalidDomainError
from hammesh.io import check_outputs, read_polygon
from hammesh.io.polygon_files import write_triangulation

HELP = "triangulate a simple polygon so that its triangles form one dual path (Thm 2.1, 2.3, 4.4)"
EXAMPLES = """examples:
  hammesh polygon outline.poly -o outline.json --png outline.png     # Thm 2.1, or fail
  hammesh polygon outline.txt --sequential -o strip.json             # Thm 4.4 (one strip)
  hammesh polygon comb.poly --steiner path -o comb.vtu               # Thm 2.3, k-2 Steiner points
inputs: .poly (one closed chain of segments), .geojson/.json (a Polygon without holes),
        .wkt (POLYGON ((...))), anything else: plain text, one "x y" per line (# comments).
outputs: .json (points, triangles in path order, counts) or any mesh format of hammesh.io."""


def add_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("input", type=Path, help="polygon file (.poly, .geojson, .wkt or 'x y' text)")
    p.add_argument("-o", "--output", type=Path, help="output (.json or a mesh format: .vtu .msh .obj ...)")
    p.add_argument("--png", type=Path, help="draw polygon, triangles and dual path into this image")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--sequential", action="store_true",
                   help="require alternating turns (one triangle strip, Thm 4.4)")
    g.add_argument("--steiner", choices=["cycle", "path"],
                   help="add Steiner points: k-1 for a cycle, k-2 for a path (Thm 2.3)")


def run(args: argparse.Namespace) -> int:
    from hammesh import polygon

    from hammesh.errors import FileFormatError
    from hammesh.io import supported_suffixes

    if args.output is not None and args.output.suffix.lower() not in (".json", *supported_suffixes()):
        raise FileFormatError(f"{args.output}: unknown output format; supported: .json {' '.join(supported_suffixes())}")
    if args.png is not None and args.png.suffix.lower() != ".png":
        raise FileFormatError(f"{args.png}: the picture is PNG; use a .png file name")
    check_outputs({"-o": args.output, "--png": args.png}, [args.input])
    pts = read_polygon(args.input)
    n_steiner, k, closed = 0, None, False
    if args.steiner:
        res = polygon.steiner_hamiltonian_result(pts, args.steiner)
        Q, T, n_steiner, k, closed = res.points, res.triangles, res.n_steiner, res.k, args.steiner == "cycle"
        what = f"Hamiltonian {args.steiner} with {n_steiner} Steiner points ({k} convex pieces, {res.method})"
    elif args.sequential:
        T, Q = polygon.sequential_triangulation(pts), pts
        what = "sequential triangulation (one strip)"
        if T is None:
            raise InvalidDomainError(f"{args.input}: the polygon has no sequential triangulation "
                                     "(Thm 4.4); try without --sequential or with --steiner path")
    else:
        T, Q = polygon.hamiltonian_triangulation(pts), pts
        what = "Hamiltonian triangulation"
        if T is None:
            raise InvalidDomainError(f"{args.input}: the polygon has no Hamiltonian triangulation "
                                     "(Thm 2.1); --steiner path adds k-2 Steiner points (Thm 2.3)")
    if args.output is not None:
        write_triangulation(args.output, Q, T, n=len(pts), n_steiner=n_steiner, k=k,
                            kind=args.steiner or ("sequential" if args.sequential else "hamiltonian"))
    if args.png is not None:
        from hammesh.polygon.plot import plot_polygon_path

        plot_polygon_path(pts, Q, T, args.png, closed=closed, title=f"{args.input.name}: {what}")
    print(f"{len(pts)} vertices: {what}, {len(T)} triangles")
    for label, path in (("triangulation", args.output), ("picture", args.png)):
        if path is not None:
            print(f"wrote {label}: {path}")
    return 0
