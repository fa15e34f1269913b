"""The pipeline shared by ``hammesh mesh`` and ``hammesh demo``: read, mesh, post-process,
verify, write — with a progress bar on a terminal and nothing written on failure.

Every output path is checked before any work (:func:`hammesh.io.check_outputs`: the
directory exists and is writable, no output is an input or a sibling of one, no two
outputs are one file); an output written before a later one fails is removed again
(or, if it existed before the run, left replaced: each file is written atomically)."""

from __future__ import annotations

import contextlib
import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hammesh.cli.inputs import DOMAIN_SUFFIXES
from hammesh.domain import Domain, read_domain
from hammesh.errors import FileFormatError, InvalidDomainError
from hammesh.io import check_outputs, read_mesh, supported_suffixes, unwritten_data, write, write_report
from hammesh.io.paths import require_file
from hammesh.io.guard import reading
from hammesh.io.paths import written_files
from hammesh.io.report import collect_repairs, format_angle
from hammesh.mesh import HamiltonianMesh, Mesh
from hammesh.meshing import quality_mesh
from hammesh.postprocess import hamiltonian

__all__ = ["Outputs", "DOMAIN_SUFFIXES", "load_input", "run_pipeline", "summary"]


@dataclass(frozen=True)
class Outputs:
    mesh: Path | None = None
    report: Path | None = None
    png: Path | None = None
    strip: Path | None = None
    #: files read by the run: no output may be one of them (or a sibling)
    inputs: tuple[Path, ...] = ()
    #: directories the run creates (``hammesh demo --out``), after the work succeeded
    make_dirs: tuple[Path, ...] = field(default=())

    def labelled(self) -> dict[str, Path | None]:
        return {"-o": self.mesh, "--report": self.report, "--png": self.png, "--strip": self.strip}

    def check(self) -> None:
        """Fail before any work if an output cannot be written in the asked format, or
        would overwrite an input, or names the same file as another output."""
        if self.mesh is not None and self.mesh.suffix.lower() not in supported_suffixes():
            if self.mesh.suffix.lower() == ".poly":  # (a domain, not a mesh: hammesh.domain.write_poly)
                raise FileFormatError(
                    f"{self.mesh}: .poly is a domain (input) format; write the mesh as one of "
                    f"{' '.join(supported_suffixes())} (.ele writes .node/.poly/.ele)"
                )
            raise FileFormatError(
                f"{self.mesh}: unknown output format; supported: {' '.join(supported_suffixes())}"
            )
        if self.report is not None and self.report.suffix.lower() != ".json":
            raise FileFormatError(f"{self.report}: the report is JSON; use a .json file name")
        if self.png is not None and self.png.suffix.lower() != ".png":
            raise FileFormatError(f"{self.png}: the picture is PNG; use a .png file name")
        if self.strip is not None and self.strip.suffix.lower() not in (".json", ".npz"):
            raise FileFormatError(f"{self.strip}: the strip buffer is .json or .npz")
        check_outputs(self.labelled(), self.inputs, make_dirs=self.make_dirs)


def accepts(func: Any, name: str) -> bool:
    """True if ``func`` takes a keyword argument ``name`` (options other modules add)."""
    import inspect

    try:
        return name in inspect.signature(func).parameters
    except (TypeError, ValueError):
        return False


def load_input(path: Path, *, strict: bool = False) -> Domain | Mesh:
    """A domain (``.poly``/``.node``) or a mesh (any other registered suffix).

    ``strict``: refuse an input that would need repairs instead of repairing it.
    """
    require_file(path)  # (no such file / is a directory / not a regular file: as every reader says)
    if path.suffix.lower() in DOMAIN_SUFFIXES:
        with reading(path):
            if strict and accepts(read_domain, "strict"):
                return read_domain(path, strict=True)
            return read_domain(path)
    return read_mesh(path, strict=strict)


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
    source: Domain | Mesh,
    mesh_options: dict[str, Any],
    outputs: Outputs,
    *,
    mode: str = "sparse",
    keep: float = 0.9,
    tree: str = "quadtree",
    strict: bool = False,
    finish: Callable[[HamiltonianMesh], HamiltonianMesh] | None = None,
) -> HamiltonianMesh:
    """Mesh (if ``source`` is a Domain), make Hamiltonian, verify, then write outputs.

    ``finish``: applied to the verified mesh before anything is written (e.g. the
    partition and vertex numbering of ``hammesh mesh --parts/--renumber``).

    ``strict``: the mesher gets ``strict=True`` (where it takes it) and any repair
    recorded on the way is refused (:class:`~hammesh.errors.InvalidDomainError`) before
    anything is written.
    """
    outputs.check()
    if strict and accepts(quality_mesh, "strict"):
        mesh_options = {**mesh_options, "strict": True}
    written: list[Path] = []
    created_dirs: list[Path] = []
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
        h = hamiltonian(mesh, mode=mode, keep=keep, tree=tree)
        steps.done()
        h.report["repairs"] = collect_repairs(source, mesh, h)
        if strict and h.report["repairs"]:
            first = h.report["repairs"][0]
            more = len(h.report["repairs"]) - 1
            raise InvalidDomainError(
                f"--strict: the input needs repairs ({first}{f' and {more} more' if more else ''})"
            )
        if finish is not None:
            h = finish(h)
        # never in silence: what the input brought, or --parts made, that the output will not hold
        not_carried = list(mesh.info.get("not_carried", []))
        if outputs.mesh is not None:
            not_carried += [f"not written: {x}" for x in unwritten_data(h, outputs.mesh)]
        if not_carried:
            h.report["not_carried"] = not_carried
        t0 = time.perf_counter()
        for directory in outputs.make_dirs:
            created_dirs += _make_dir(directory)
        # files that did not exist before the run: removed again if a later output fails
        written = [f for p in outputs.labelled().values() if p is not None for f in written_files(p)
                   if not os.path.lexists(f)]
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
    except BaseException:
        for f in written:
            with contextlib.suppress(OSError):
                os.remove(f)
        for directory in reversed(created_dirs):
            with contextlib.suppress(OSError):
                directory.rmdir()  # only if empty
        raise
    finally:
        steps.close()
    return h


def _make_dir(directory: Path) -> list[Path]:
    """Create ``directory`` and missing parents; return the ones created (outermost first)."""
    missing: list[Path] = []
    d = directory
    while not d.exists():
        missing.append(d)
        d = d.parent
    directory.mkdir(parents=True, exist_ok=True)
    return list(reversed(missing))


def _repair_lines(repairs: list) -> list[str]:
    """One line saying what the input needed (the report lists every repair)."""
    if not repairs:
        return []
    said = [r if isinstance(r, str) else str(r.get("defect", r)) if isinstance(r, dict) else str(r) for r in repairs]
    more = f" and {len(said) - 1} more (the report's 'repairs')" if len(said) > 1 else ""
    return [f"repaired: {said[0]}{more}"]


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
            else ", the input's cycle order kept" if r.get("kept_input_cycle") else ""
        ),
        f"min angle {format_angle(r['min_angle_input_deg'])} -> {format_angle(r['min_angle_output_deg'])} deg "
        f"(bound: half), max angle {format_angle(r['max_angle_output_deg'])} deg"
        + (  # sparse mode's local rule (issue 13): said where a join could not keep it
            f"; {r['below_parent_rule']:,} new triangle(s) below {r['keep']:g} x their parents' "
            f"smallest angle (worst {r['worst_parent_ratio']:.2f} x)"
            if r.get("below_parent_rule")
            else ""
        ),
        *_repair_lines(r.get("repairs") or []),
        "seconds: "
        + ", ".join(
            f"{k} {v:.3f}" for k, v in (("mesh", mesh_s), ("hamiltonian", sec.get("hamiltonian")), ("verify", sec.get("verify"))) if v is not None
        ),
    ]
    lines += [f"note: {x}" for x in r.get("not_carried", [])]
    return "\n".join(lines)
