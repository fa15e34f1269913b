"""``hammesh check``: re-verify a Hamiltonian mesh file."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from hammesh import params
from hammesh.errors import FileFormatError, InvalidMeshError, InvalidOptionError, VerificationError

if TYPE_CHECKING:
    import numpy as np

HELP = "re-verify that a mesh file's triangles, in file order, form Hamiltonian cycles (or paths: --path)"
EXAMPLES = """examples:
  hammesh check plate.vtu
  hammesh check plate.obj --min-angle 14.9     # also require a minimum angle
  hammesh check bunny-cycle.ply                # a 3D surface from `hammesh surface`
  hammesh check outline.vtu --path             # a path from `hammesh polygon`
  hammesh check folded.vtu --surface           # a flat surface (all z equal) from `hammesh surface`
Each connected piece must be stored as one run of triangles that closes into a cycle
(with --path: each triangle of the run shares an edge with the next),
and every constrained edge stored in the file (line cells, or the .poly next to a .ele)
must be an edge of the triangles; no two triangles of a planar mesh may overlap (exact
test); exit 0 if verified, 3 if not, 2 if the file cannot
be read."""


def add_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("mesh", type=Path, help="mesh file written by hammesh (any supported format)")
    p.add_argument("--min-angle", type=float, help="also require every angle >= this (degrees)")
    p.add_argument("--report", type=Path, help="write the check's figures as JSON")
    p.add_argument("--surface", action="store_true",
                   help="check as a 3D surface (the surface certificate) even where every point has the same z: "
                        "a flat surface from `hammesh surface` may fold over itself")
    p.add_argument("--path", action="store_true",
                   help="require a Hamiltonian path per piece instead of a cycle (what `hammesh polygon` and, for "
                        "some inputs, `hammesh points` write)")


def run(args: argparse.Namespace) -> int:
    # imported here, not with the CLI: ``hammesh --help`` and a refused option import
    # neither the readers nor the certificate's kernels (numba)
    from hammesh.domain.validate import check_extent
    from hammesh.io import check_outputs, read_mesh, write_report
    from hammesh.io.paths import require_file
    from hammesh.io.report import collect_repairs, format_angle
    from hammesh.verify.stored import verify_stored_mesh

    if args.min_angle is not None:
        params.number("--min-angle", args.min_angle, low=0, high=60, what="degrees")
    if args.report is not None and args.report.suffix.lower() != ".json":
        raise FileFormatError(f"{args.report}: the report is JSON; use a .json file name")
    check_outputs({"--report": args.report}, [args.mesh])
    require_file(args.mesh)  # (no such file / is a directory / not a regular file: as every reader says)
    if args.surface and args.path:
        raise InvalidOptionError("--surface and --path exclude each other (`hammesh surface` writes cycles)")
    mesh = read_mesh(args.mesh, dim=3 if args.surface else None)
    check_extent(mesh.points, InvalidMeshError, str(args.mesh))  # (unverifiable input: exit 2, not a failed check)
    try:  # (a readable file that is no valid mesh fails the check: exit 3, not 2)
        runs, stats, triangles = verify_stored_mesh(mesh, path=args.path)
    except InvalidMeshError as exc:
        raise VerificationError(str(exc)) from None
    except VerificationError as exc:
        if mesh.points.shape[1] == 2 and exc.check in ("orientation", "overlap"):
            raise VerificationError(f"{exc} (a flat surface from `hammesh surface` may fold over itself: check it "
                                    "with --surface)") from None
        if not args.path and _is_path(mesh.triangles):  # say what it is: `hammesh points`/`polygon` make paths
            raise VerificationError(
                f"{exc}; the triangles form a Hamiltonian path, not a cycle (it does not close), "
                "as `hammesh points`/`polygon` make for some inputs: check it with --path") from None
        raise
    if args.min_angle is not None and stats["min_angle_output_deg"] < args.min_angle:
        raise VerificationError(
            f"min angle {stats['min_angle_output_deg']:.6f} deg is below the required {args.min_angle} deg"
        )
    stats.update({"file": str(args.mesh), "triangles": len(triangles), "components": runs.tolist(), "verified": True,
                  "repairs": collect_repairs(mesh)})
    if args.report is not None:
        write_report(stats, args.report)
    kind = "path(s)" if args.path else "cycle(s)"
    print(
        f"OK {args.mesh}: {len(triangles):,} triangles in {len(runs)} Hamiltonian {kind}; "
        f"angles {format_angle(stats['min_angle_output_deg'])}..{format_angle(stats['max_angle_output_deg'])} deg"
    )
    return 0


def _is_path(triangles: np.ndarray) -> bool:
    """Whether every two consecutive triangles share an edge (two corners) but the last
    and the first do not: a Hamiltonian path in file order."""
    import numpy as np

    t = np.sort(np.asarray(triangles, dtype=np.int64), axis=1)
    if len(t) < 2:
        return len(t) == 1
    shared = (t[:-1, :, None] == t[1:, None, :]).any(axis=2).sum(axis=1)
    wrap = np.isin(t[-1], t[0]).sum()  # (two triangles: the wrap would cross their one edge again)
    return bool((shared >= 2).all() and (wrap < 2 or len(t) == 2))
