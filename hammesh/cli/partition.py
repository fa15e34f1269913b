"""``hammesh partition``: a mesh file in cycle order -> the same mesh with a ``part`` array."""

from __future__ import annotations

import argparse
from pathlib import Path

from hammesh import params
from hammesh.errors import FileFormatError, InvalidMeshError, VerificationError

HELP = "cut the Hamiltonian cycle(s) of a mesh file into K connected, balanced parts"
EXAMPLES = """examples:
  hammesh partition plate.vtu -k 64 -o plate-64.vtu              # 'part' cell array
  hammesh partition plate.vtu -k 8 -o plate-8.msh --renumber rcm --report parts.json
The file's triangles must be in Hamiltonian cycle order (any mesh 'hammesh mesh' wrote);
the file is certified first, as 'hammesh check' does (exit 2 if it fails).
Each cycle (connected piece) is cut into consecutive stretches of (almost) equal size;
the edge cut, balance and a connectivity check are printed and written to --report."""


def add_args(p: argparse.ArgumentParser) -> None:
    from hammesh.numbering import NUMBERINGS

    p.add_argument("mesh", type=Path, help="mesh file in cycle order (.vtu .msh .xdmf .ele ...)")
    p.add_argument("-k", "--parts", type=int, required=True, help="number of parts (>= 1)")
    p.add_argument("-o", "--output", type=Path, required=True, help="output mesh with the 'part' cell array")
    p.add_argument("--renumber", choices=NUMBERINGS, help="also renumber the vertices")
    p.add_argument("--report", type=Path, help="write the partition's figures as JSON")


def run(args: argparse.Namespace) -> int:
    from hammesh.io import check_outputs, read_mesh, write, write_report
    from hammesh.io.paths import require_file
    from hammesh.partition import partitioned
    from hammesh.verify.stored import verify_stored_mesh

    params.integer("--parts", args.parts, low=1, what="number of parts")
    if args.report is not None and args.report.suffix.lower() != ".json":
        raise FileFormatError(f"{args.report}: the report is JSON; use a .json file name")
    check_outputs({"-o": args.output, "--report": args.report}, [args.mesh])
    require_file(args.mesh)  # (no such file / is a directory / not a regular file: as every reader says)
    mesh = read_mesh(args.mesh)
    # the file's rows are cut as the cycle they claim to be: certified first, as
    # `hammesh check` would (a moved vertex made overlapping "parts" before, session 17)
    try:
        verify_stored_mesh(mesh)
    except (VerificationError, InvalidMeshError) as exc:
        raise InvalidMeshError(f"{args.mesh}: not a verified Hamiltonian cycle mesh in cycle order ({exc}); "
                               "`hammesh mesh` makes one") from None
    out = partitioned(mesh, args.parts, renumber=args.renumber)
    r = out.report["partition"]
    write(out, args.output)
    summary = {"file": str(args.mesh), "output": str(args.output), "partition": r}
    if "numbering" in out.report:
        summary["numbering"] = out.report["numbering"]
    if args.report is not None:
        try:
            write_report(summary, args.report)
        except BaseException:
            args.output.unlink(missing_ok=True)  # no half-finished set of outputs
            raise
    from hammesh.io.paths import wrote_text

    print(
        f"{args.mesh}: {out.n_triangles:,} triangles -> {r['k']} parts of {r['size_min']:,}..{r['size_max']:,} "
        f"(imbalance {r['imbalance']:.4f}), edge cut {r['edge_cut']:,}, "
        f"{'all parts connected' if r['connected'] else 'NOT all parts connected'}; wrote {wrote_text(args.output)}"
    )
    if "numbering" in out.report:
        nb = out.report["numbering"]
        print(f"renumbered ({nb['method']}): bandwidth {nb['bandwidth_before']:,} -> {nb['bandwidth']:,}, "
              f"profile {nb['profile_before']:,} -> {nb['profile']:,}")
    return 0
