"""``hammesh surface``: 3D triangle surface file -> verified Hamiltonian cycle surface."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from hammesh import params
from hammesh.errors import FileFormatError

HELP = "make a 3D triangle surface (.obj .ply .stl .off .vtu .vtk .vtp) one strip per piece, few Steiner points"
EXAMPLES = """examples:
  hammesh surface bunny.ply -o bunny.vtu --report bunny.json
  hammesh surface part.stl -o part.obj --swaps          # Steiner-free flips too (surface moves slightly)
Every new triangle lies inside an input triangle (same surface, same area); the minimum
3D angle is at least half the input's. Exit 0 ok, 2 bad input, 3 verification failed."""


def add_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("input", type=Path, help="surface mesh (.obj .ply .stl .off .vtu .vtk .vtp .msh .xdmf)")
    p.add_argument("-o", "--output", type=Path, help="output surface (.vtu .vtk .vtp .obj .ply .stl .off .msh .xdmf)")
    p.add_argument("--report", type=Path, help="write the report JSON here")
    p.add_argument("--swaps", action="store_true", help="also flip edges without Steiner points (not exact)")
    p.add_argument("--max-fold", type=float, default=10.0, help="with --swaps: largest normal change in degrees (0..180)")


def run(args: argparse.Namespace) -> int:
    from hammesh.io import check_outputs, read_mesh, unwritten_data, write_report
    from hammesh.io.report import collect_repairs
    from hammesh.surface import SURFACE_SUFFIXES, surface_hamiltonian, write_surface
    from hammesh.surface.files import weld_surface

    if args.output is not None and args.output.suffix.lower() not in SURFACE_SUFFIXES:
        raise FileFormatError(f"{args.output}: unknown surface format; supported: {' '.join(SURFACE_SUFFIXES)}")
    if args.report is not None and args.report.suffix.lower() != ".json":
        raise FileFormatError(f"{args.report}: the report is JSON; use a .json file name")
    params.number("--max-fold", args.max_fold, low=0, high=180, what="degrees")
    check_outputs({"-o": args.output, "--report": args.report}, [args.input])
    mesh = read_mesh(args.input, dim=3)
    welded = weld_surface(mesh.points, mesh.triangles, mesh.point_data)
    h = surface_hamiltonian(
        welded.points, welded.triangles, swaps=args.swaps, max_fold_deg=args.max_fold,
        triangle_attributes=mesh.triangle_attributes, attribute_names=mesh.attribute_names,
        point_data={name: np.asarray(v)[welded.source] for name, v in mesh.point_data.items()},
    )
    h.report["repairs"] = collect_repairs(mesh, h)
    # never in silence (as `hammesh mesh`): what the input brought that the output will not hold
    not_carried = list(mesh.info.get("not_carried", []))
    if args.output is not None:
        not_carried += [f"not written: {x}" for x in unwritten_data(h, args.output)]
    if not_carried:
        h.report["not_carried"] = not_carried
    if args.output is not None:
        write_surface(h, args.output)
    if args.report is not None:
        write_report(h.report, args.report)
    r = h.report
    print(
        f"{r['input_triangles']:,} input triangles -> {r['triangles']:,} triangles in "
        f"{len(r['components'])} Hamiltonian cycle(s), verified\n"
        f"steiner points {r['steiner_points']:,} ({100 * r['steiner_per_input_triangle']:.2f}% of input triangles), "
        f"cycles before merging {r['cycles_before_merging']:,}\n"
        f"min angle {r['min_angle_input_deg']:.2f} -> {r['min_angle_output_deg']:.2f} deg (3D, bound: half), "
        f"area change {r['area_change_rel']:.2e}"
    )
    for note in r.get("not_carried", []):
        print(f"note: {note}")
    from hammesh.io.paths import wrote_text  # (a .ele output's .node/.poly named too)

    for label, path in (("surface", args.output), ("report", args.report)):
        if path is not None:
            print(f"wrote {label}: {wrote_text(path) if label == 'surface' else path}")
    return 0
