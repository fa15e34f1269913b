"""``hammesh demo``: the whole pipeline on the bundled plate domain."""

from __future__ import annotations

import argparse
from importlib import resources
from pathlib import Path

HELP = "mesh the bundled demo plate; writes mesh.vtu, report.json and cycle.png"
EXAMPLES = """examples:
  hammesh demo                      # writes hammesh-demo/{mesh.vtu,report.json,cycle.png}
  hammesh demo --out /tmp/d --max-area 0.002"""


def demo_domain_path() -> Path:
    """Path of the bundled demo domain (``hammesh/data/demo.poly``)."""
    return Path(str(resources.files("hammesh") / "data" / "demo.poly"))


def add_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", type=Path, default=Path("hammesh-demo"), help="output folder (default: hammesh-demo)")
    p.add_argument("--min-angle", type=float, default=30.0)
    p.add_argument("--max-area", type=float, default=0.01)
    p.add_argument("--mode", choices=["sparse", "incircle"], default="sparse", help="Hamiltonian construction")


def run(args: argparse.Namespace) -> int:
    from hammesh.cli.pipeline import Outputs, run_pipeline, summary
    from hammesh.domain import read_domain

    domain = read_domain(demo_domain_path())
    outputs = Outputs(  # the folder is made only once the mesh is verified
        mesh=args.out / "mesh.vtu",
        report=args.out / "report.json",
        png=args.out / "cycle.png",
        make_dirs=() if args.out.exists() else (args.out,),
    )
    h = run_pipeline(domain, {"min_angle": args.min_angle, "max_area": args.max_area}, outputs, mode=args.mode)
    print(f"demo domain: {demo_domain_path()}")
    print(summary(h))
    print(f"wrote {outputs.mesh}, {outputs.report}, {outputs.png}")
    return 0
