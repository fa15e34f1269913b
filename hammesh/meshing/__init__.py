"""Quality meshing of planar straight-line graphs, over interchangeable C backends.

``BACKENDS`` is the one registry: backend name -> function ``(Domain, MeshOptions)
-> Mesh``. Validation happens here, before any backend (C code) runs.
"""

from __future__ import annotations

import os
import threading
import time
from dataclasses import replace
from functools import partial

import numpy as np

from hammesh import pages, params
from hammesh.domain import Domain
from hammesh.errors import InvalidDomainError, InvalidOptionError, MeshingError
from hammesh.mesh import Mesh
from hammesh.meshing.isolate import run_isolated
from hammesh.meshing.meshpy_backend import mesh_with_meshpy
from hammesh.meshing.options import MAX_MIN_ANGLE, MeshOptions, check_sizes, format_number
from hammesh.meshing.triangle_backend import mesh_with_triangle, triangle_switches

__all__ = [
    "quality_mesh",
    "MeshOptions",
    "BACKENDS",
    "MAX_MIN_ANGLE",
    "format_number",
    "triangle_switches",
    "expected_reserve",
    "expected_result",
    "expected_triangles",
    "TABLE_AHEAD_MIN_TRIANGLES",
]

BACKENDS = {"triangle": mesh_with_triangle, "meshpy": mesh_with_meshpy}
_NAMES = {"triangle": "Triangle", "meshpy": "meshpy"}


#: Bytes of pages faulted in per expected triangle while Triangle runs, for the next
#: ``hamiltonian()`` to take through ``hammesh.pages.fresh``: the larger of the two
#: modes' shares (``hammesh.postprocess.RESERVE_TAKEN``). incircle takes ~288 (256 listed: the input
#: pairing 24, output rows 72, the claimed pairing 36, the walk's slots 12, output
#: points about 24, and the spanning forest's arrays 88 (its order 8, rows 24, codes
#: 24, queue 24, quadtree coordinates 8)); sparse from 1.5 M triangles on takes ~352
#: (session 11: at 256 its reserve ran out in the output rows, 18k pages faulted there);
#: session 12: ~400, the cover's matching and cycle arrays (48) taken from it too.
RESERVE_BYTES_PER_TRIANGLE = 400
#: Triangle's triangle count per ``area / max_area`` at a quality bound (1.59 on the
#: square with a hole at q30, 1e-6: 1.52 M triangles for an area of 0.96).
TRIANGLES_PER_AREA = 1.6
#: No reserve below this (small meshes fault their few pages quickly).
RESERVE_MIN_BYTES = 64 << 20
#: Bytes of Triangle's result per triangle as the isolated child hands it back (shared
#: memory): triangles 24, neighbours 24, about 0.51 points per triangle at 16 bytes and
#: their markers at 8, page rounding: 64.
RESULT_BYTES_PER_TRIANGLE = 64
#: No result file is allocated ahead below this.
RESULT_MIN_BYTES = 8 << 20


def _expected_bytes(domain: Domain, opts: MeshOptions, per_triangle: int, at_least: int) -> int:
    """``per_triangle`` x the triangles Triangle is expected to make, or 0 below ``at_least``.

    From the bounding box's area over the global area bound (an upper estimate of
    the domain's area), at most an eighth of the free memory.
    """
    if opts.max_area is None:
        return 0
    v = np.asarray(domain.vertices, dtype=np.float64)
    ext = np.ptp(v, axis=0) if len(v) else np.zeros(2)
    count = TRIANGLES_PER_AREA * float(ext[0] * ext[1]) / opts.max_area
    try:
        free = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):  # not POSIX: nothing ahead
        return 0
    nbytes = min(count * per_triangle, free / 8)
    return int(nbytes) if nbytes >= at_least else 0


def expected_reserve(domain: Domain, opts: MeshOptions) -> int:
    """Bytes of pages to fault in while Triangle meshes ``domain`` (0: none)."""
    return _expected_bytes(domain, opts, RESERVE_BYTES_PER_TRIANGLE, RESERVE_MIN_BYTES)


def expected_result(domain: Domain, opts: MeshOptions) -> int:
    """Bytes of the isolated mesher's result file to allocate ahead (0: none;
    ``hammesh.meshing.isolate.run_isolated(prefault=)``)."""
    return _expected_bytes(domain, opts, RESULT_BYTES_PER_TRIANGLE, RESULT_MIN_BYTES)


def expected_triangles(domain: Domain, opts: MeshOptions) -> int:
    """About how many triangles Triangle will make (an upper estimate; 0 without an area bound)."""
    return _expected_bytes(domain, opts, 1, 0)


#: from this many expected triangles on, the validation's Hilbert table is made while
#: Triangle runs (sparse mode renumbers such meshes by their cells)
TABLE_AHEAD_MIN_TRIANGLES = 100_000


def _meanwhile(reserve_bytes: int = 0, loaded: threading.Event | None = None, triangles: int = 0) -> None:
    """While the mesher runs in its child, prepare what ``hamiltonian()`` needs next.

    The parent process only waits meanwhile. The first call of each compiled kernel
    in a process loads its machine code from numba's cache (0.1-0.2 s in all), which
    a ``quality_mesh`` -> ``hamiltonian`` pipeline (the CLI's) then no longer pays;
    both modes: the default (sparse) and Thm 2.4's incircle construction. Then
    ``reserve_bytes`` of memory are faulted in (``hammesh.pages.reserve``): on this
    project's VM a fresh page costs a host fault besides its zeroing, a third of the
    first big ``hamiltonian()``'s system time (docs/benchmarks.md). For an expected
    mesh of ``triangles`` (from ``TABLE_AHEAD_MIN_TRIANGLES`` on) the validation's
    Hilbert table of that size is made (``hammesh.halfedge.locality.hilbert_table``:
    ~3 ms of the first call's critical path at 1.5 M, session 23).
    """
    try:
        from hammesh.postprocess import load_kernels

        load_kernels("sparse")
        load_kernels("incircle")
    finally:  # (the imports are done: the caller may import again, see quality_mesh)
        if loaded is not None:
            loaded.set()
    if triangles >= TABLE_AHEAD_MIN_TRIANGLES:
        from hammesh.halfedge import locality

        locality.hilbert_table(locality.cell_bits(triangles))
    if reserve_bytes:
        pages.reserve(reserve_bytes)


def quality_mesh(
    domain: Domain,
    *,
    min_angle: float | None = None,
    max_area: float | None = None,
    backend: str = "triangle",
    conforming_delaunay: bool = False,
    max_steiner: int | None = None,
    isolate: bool = True,
    timeout: float | None = None,
    strict: bool = False,
) -> Mesh:
    """Constrained (or conforming) Delaunay quality mesh of a planar domain.

    Parameters
    ----------
    domain : Domain
        Vertices, segments (boundary, internal, dangling), holes and regions.
        Regions' attributes are returned per triangle, their max areas are applied.
    min_angle : float, optional
        Minimum angle in degrees (0..34).
    max_area : float, optional
        Global maximum triangle area (> 0).
    backend : {"triangle", "meshpy"}
    conforming_delaunay : bool
        Triangle's ``-D`` (triangle backend only).
    max_steiner : int, optional
        Limit on added Steiner points (triangle backend only).
    isolate : bool
        Run the C mesher in a child process (default), so that a crash or hang of
        the C code raises :class:`~hammesh.errors.MeshingError` instead of killing
        the interpreter; the arrays come back through shared memory, without a copy
        (``hammesh.meshing.isolate``). ``False`` runs in-process.
    timeout : float, optional
        With ``isolate``, seconds after which the mesher is stopped.
    strict : bool
        Refuse a domain that needed repairs (``domain.repairs`` not empty: duplicate
        vertices, T-junctions, overlapping or crossing segments) instead of meshing
        the repaired graph; without it the repairs are listed in ``info["repairs"]``.

    Returns
    -------
    Mesh
        Counter-clockwise triangles with constrained edges (subdivided segments and
        their markers), neighbours and the regional attribute of every triangle.

    Raises
    ------
    InvalidOptionError, InvalidDomainError, MeshingError
        Detail below float64 resolution (a 1e-6 square at offset 1e9) is meshed, as
        Triangle does; ``hamiltonian`` explains it if its certificate then fails.
        InvalidOptionError also for a global or regional area bound implying more than
        ``MAX_TRIANGLES`` triangles (``hammesh.meshing.options.check_sizes``).

    Examples
    --------
    >>> import hammesh
    >>> dom = hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])
    >>> m = hammesh.quality_mesh(dom, min_angle=30, max_area=0.1)
    >>> m.triangles.shape[1]
    3
    """
    if backend not in BACKENDS:
        raise InvalidOptionError(f"backend must be one of {sorted(BACKENDS)}, got {backend!r}")
    if not isinstance(domain, Domain):
        raise InvalidOptionError(f"domain must be a hammesh.Domain, got {type(domain).__name__}")
    if timeout is not None:  # finite and bounded: inf or 1e300 overflow the wait (issue 12)
        timeout = params.number("timeout", timeout, low=0, low_open=True, high=params.MAX_SECONDS, what="seconds")
    opts = MeshOptions(
        min_angle=min_angle,
        max_area=max_area,
        conforming_delaunay=conforming_delaunay,
        max_steiner=max_steiner,
    )
    if strict and domain.repairs:
        raise InvalidDomainError(f"{domain.repairs[0].defect} (strict: not repaired)")
    check_sizes(domain, opts)
    func = BACKENDS[backend]
    t0 = time.perf_counter()
    loaded = threading.Event()
    if isolate:
        # the child allocates its output arrays where this process maps them (no copy)
        mesh = run_isolated(
            func, (domain, opts), name=_NAMES[backend], timeout=timeout, alloc=True,
            meanwhile=partial(_meanwhile, expected_reserve(domain, opts), loaded, expected_triangles(domain, opts)),
            prefault=expected_result(domain, opts) if backend == "triangle" else 0,
        )
    else:
        mesh = func(domain, opts)
        loaded.set()
    seconds = time.perf_counter() - t0
    # The side thread imports hammesh.postprocess and what its kernels' first calls import:
    # the caller's next import of the same modules (hamiltonian(), a test module) must
    # not run beside it, or Python hands one of the two threads a partially initialized
    # module ("cannot import name 'KEEP' from partially initialized module
    # 'hammesh.postprocess.sparse'", seen under pytest-xdist). On a big mesh it is done
    # long before Triangle; a small one waits for it (the next hamiltonian() would load
    # the kernels anyway).
    loaded.wait()
    if mesh.n_triangles == 0:
        raise MeshingError(
            f"{_NAMES[backend]} produced no triangles (are all triangles inside holes?)"
        )
    info = {"backend": backend, "seconds": seconds, "isolated": bool(isolate),
            "repairs": [r.to_dict() for r in domain.repairs]}
    if backend == "triangle":
        info["switches"] = triangle_switches(domain, opts)
    k = np.shape(getattr(domain, "vertex_attributes", np.zeros((0, 0))))[-1]
    if k and not mesh.point_data:  # (meshpy's build takes no vertex attributes)
        info["not_carried"] = [f"vertex attributes ({k} per vertex): the {backend} backend does not "
                               "interpolate them (backend='triangle' does)"]
    return replace(mesh, info=info)
