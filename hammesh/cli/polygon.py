"""``hammesh polygon``: a simple polygon -> Hamiltonian / sequential / Steiner triangulation."""

from __future__ import annotations

import argparse
from pathlib import Path


HELP = "triangulate a polygon (holes allowed) so that its triangles form one dual path (Thm 2.1-2.3, 4.4)"
EXAMPLES = """examples:
  hammesh polygon outline.poly -o outline.json --png outline.png     # Thm 2.1, or fail
  hammesh polygon outline.txt --sequential -o strip.json             # Thm 4.4 (one strip)
  hammesh polygon comb.poly --steiner path -o comb.vtu               # Thm 2.3, k-2 Steiner points
  hammesh polygon plate.wkt --steiner cycle                          # holes: Thm 2.3 on H-M pieces
inputs: .poly (closed chains of segments: the largest is the outline, the others holes),
        .geojson/.json (a Polygon, holes allowed), .wkt (POLYGON ((...), (hole), ...)),
        anything else: plain text, one "x y" per line (# comments).
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
    p.add_argument("--decomposition", choices=["auto", "optimal", "hertel-mehlhorn"], default="auto",
                   help="convex pieces for --steiner: the minimum (auto, optimal; Hertel-Mehlhorn "
                        "with holes) or Hertel-Mehlhorn")


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from hammesh import polygon
    from hammesh.errors import InvalidDomainError
    from hammesh.io import check_outputs
    from hammesh.io.polygon_files import read_polygon_rings, write_triangulation
    from hammesh.errors import FileFormatError
    from hammesh.io import supported_suffixes

    if args.output is not None and args.output.suffix.lower() not in (".json", *supported_suffixes()):
        raise FileFormatError(f"{args.output}: unknown output format; supported: .json {' '.join(supported_suffixes())}")
    if args.png is not None and args.png.suffix.lower() != ".png":
        raise FileFormatError(f"{args.png}: the picture is PNG; use a .png file name")
    check_outputs({"-o": args.output, "--png": args.png}, [args.input])
    pts, holes = read_polygon_rings(args.input)
    rings = [pts, *holes]
    n_steiner, k, closed = 0, None, False
    if args.steiner:
        res = polygon.steiner_hamiltonian_result(pts, args.steiner, holes=holes or None,
                                                 decomposition=args.decomposition)
        Q, T, n_steiner, k, closed = res.points, res.triangles, res.n_steiner, res.k, args.steiner == "cycle"
        what = (f"Hamiltonian {args.steiner} with {n_steiner} Steiner points "
                f"(k = {k} convex pieces, method {res.method})")
    elif holes:
        if args.sequential:
            raise InvalidDomainError(f"{args.input}: --sequential is for polygons without holes; "
                                     "try --steiner path")
        T, Q = polygon.hamiltonian_triangulation_holes(pts, holes), np.concatenate(rings)
        what = f"Hamiltonian triangulation with {len(holes)} hole{'' if len(holes) == 1 else 's'}"
        if T is None:
            raise InvalidDomainError(f"{args.input}: the polygon with holes has no Hamiltonian "
                                     "triangulation (Thm 2.2); --steiner path adds Steiner points (Thm 2.3)")
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
    n_in = sum(len(r) for r in rings)
    if args.output is not None:
        write_triangulation(args.output, Q, T, n=n_in, n_steiner=n_steiner, k=k,
                            kind=args.steiner or ("sequential" if args.sequential else "hamiltonian"))
    if args.png is not None:
        from hammesh.polygon.plot import plot_polygon_path

        plot_polygon_path(pts, Q, T, args.png, closed=closed, holes=holes,
                          title=f"{args.input.name}: {what}")
    print(f"{n_in} vertices: {what}, {len(T)} triangles")
    from hammesh.io.paths import wrote_text  # (a .ele output's .node/.poly named too)

    for label, path in (("triangulation", args.output), ("picture", args.png)):
        if path is not None:
            print(f"wrote {label}: {wrote_text(path) if label == 'triangulation' else path}")
    return 0
