"""The pipeline shared by ``hammesh mesh`` and ``hammesh demo``: read, mesh, post-process,
verify, write — with a progress bar on a terminal and nothing written on failure."""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from hammesh.domain import Domain, read_domain
from hammesh.errors import FileFormatError
from hammesh.io import read_mesh, supported_suffixes, write, write_report
from hammesh.mesh import HamiltonianMesh, Mesh
from hammesh.meshing import quality_mesh
from hammesh.postprocess import hamiltonian

__all__ = ["Outputs", "DOMAIN_SUFFIXES", "load_input", "run_pipeline", "summary"]

#: inputs read as domains (meshed first); anything else is read as a finished mesh
DOMAIN_SUFFIXES = (".poly", ".node")


@dataclass(frozen=True)
class Outputs:
    mesh: Path | None = None
    report: Path | None = None
    png: Path | None = None
    strip: Path | None = None

    def check(self) -> None:
        """Fail before any work if an output cannot be written in the asked format."""
        if self.mesh is not None and self.mesh.suffix.lower() not in supported_suffixes():
            raise FileFormatError(
                f"{self.mesh}: unknown output format; supported: {' '.join(supported_suffixes())}"
            )
        if self.report is not None and self.report.suffix.lower() != ".json":
            raise FileFormatError(f"{self.report}: the report is JSON; use a .json file name")
        if self.png is not None and self.png.suffix.lower() != ".png":
            raise FileFormatError(f"{self.png}: the picture is PNG; use a .png file name")
        if self.strip is not None and self.strip.suffix.lower() not in (".json", ".npz"):
            raise FileFormatError(f"{self.strip}: the strip buffer is .json or .npz")


def load_input(path: Path) -> Domain | Mesh:
    """A domain (``.poly``/``.node``) or a mesh (any other registered suffix)."""
    if not path.exists():
        raise FileFormatError(f"{path}: no such file")
    if path.suffix.lower() in DOMAIN_SUFFIXES:
        return read_domain(path)
    return read_mesh(path)


class _Steps:
    """A step progress bar on stderr, shown only on a terminal."""

    def __init__(self, total: int) -> None:
        from tqdm import tqdm

        self.bar = tqdm(
            total=total, file=sys.stderr, disable=not sys.stderr.isatty(), leave=False, unit="step"
        )

    def step(self, what: str) -> None:
        self.bar.set_description(what)

    def done(self) -> None:
        self.bar.update(1)

    def close(self) -> None:
        self.bar.close()


def run_pipeline(
    source: Domain | Mesh, mesh_options: dict[str, Any], outputs: Outputs, *, mode: str = "sparse", keep: float = 0.9
) -> HamiltonianMesh:
    """Mesh (if ``source`` is a Domain), make Hamiltonian, verify, then write outputs."""
    outputs.check()
    steps = _Steps(
        2 + sum(x is not None for x in (outputs.mesh, outputs.report, outputs.png, outputs.strip))
    )
    try:
        if isinstance(source, Domain):
            steps.step("meshing")
            mesh = quality_mesh(source, **mesh_options)
        else:
            mesh = source
        steps.done()
        steps.step("hamiltonian + verify")
        h = hamiltonian(mesh, mode=mode, keep=keep)
        steps.done()
        t0 = time.perf_counter()
        if outputs.mesh is not None:
            steps.step(f"writing {outputs.mesh.name}")
            write(h, outputs.mesh)
            steps.done()
        if outputs.png is not None:
            from hammesh.plot import plot_cycle

            steps.step(f"drawing {outputs.png.name}")
            plot_cycle(h, outputs.png)
            steps.done()
        if outputs.strip is not None:
            from hammesh.strips import encode, write_strip

            steps.step(f"writing {outputs.strip.name}")
            # the cycle order itself: one strip per cycle (swaps where turns repeat)
            strip = encode(h, method="order")
            write_strip(strip, outputs.strip, extra={"method": "order"})
            h.report["strip"] = {
                "strips": int(strip.n_strips),
                "indices_per_triangle": float(strip.indices_per_triangle),
            }
            steps.done()
        h.report.setdefault("seconds", {})["write"] = time.perf_counter() - t0
        if outputs.report is not None:
            steps.step(f"writing {outputs.report.name}")
            write_report(h.report, outputs.report)
            steps.done()
    finally:
        steps.close()
    return h


def summary(h: HamiltonianMesh) -> str:
    """A few human lines about a verified Hamiltonian mesh."""
    r = h.report
    sec = r.get("seconds", {})
    mesh_s = sec.get("mesh")
    lines = [
        f"{r['input_triangles']:,} input triangles -> {r['triangles']:,} triangles in "
        f"{len(r['components'])} Hamiltonian cycle(s), verified",
        f"steiner points {r['steiner_points']:,} ({r['midpoints']} constrained-edge midpoints)"
        + (
            f", {r['cycles_before_merging']:,} cover cycles joined"
            if "cycles_before_merging" in r
            else ""
        ),
        f"min angle {r['min_angle_input_deg']:.2f} -> {r['min_angle_output_deg']:.2f} deg "
        f"(bound: half), max angle {r['max_angle_output_deg']:.2f} deg",
        "seconds: "
        + ", ".join(
            f"{k} {v:.3f}" for k, v in (("mesh", mesh_s), ("hamiltonian", sec.get("hamiltonian")), ("verify", sec.get("verify"))) if v is not None
        ),
    ]
    return "\n".join(lines)
