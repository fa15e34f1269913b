"""Post-processes that turn any planar triangle mesh into a Hamiltonian cycle mesh."""

from __future__ import annotations

import numbers
import threading
import time
from dataclasses import replace

import numpy as np

from hammesh import idle, pages, params, threads
from hammesh.domain.resolution import check_resolution, check_rounding, snap_steiner_points
from hammesh.errors import InvalidDomainError, InvalidMeshError, InvalidOptionError, VerificationError
from hammesh.mesh import HamiltonianMesh, Mesh, output_vertex_markers
from hammesh.planar_overlap import find_overlap
from hammesh.point_data import carry_point_data
from hammesh.postprocess.incircle import TREES, incenters, incircle_hamiltonian, incircle_streaming, walk_arrays
from hammesh.postprocess import sparse as sparse_module
from hammesh.postprocess.kept_cycle import kept_cycle, kept_runs
from hammesh.postprocess.sparse import KEEP, SPARSE_TREES, sparse_hamiltonian
from hammesh.verify.certificate import certify, claim_structure
from hammesh.verify.reference import input_facts
from hammesh.halfedge import HalfEdges, match_half_edges, prepare_mesh

__all__ = ["hamiltonian", "incircle_hamiltonian", "sparse_hamiltonian", "incenters", "MODES", "load_kernels",
           "RESERVE_TAKEN", "RESERVE_AFTER_COVER"]

#: Available constructions, by name (``hamiltonian(mesh, mode=...)``).
MODES = {"incircle": incircle_hamiltonian, "sparse": sparse_hamiltonian}

#: Bytes per input triangle each mode takes from ``hammesh.pages``' reserve (through
#: ``pages.fresh``); the rest of a reserve is given back as the call starts
#: (``pages.trim``). incircle: 288 (``hammesh.meshing.RESERVE_BYTES_PER_TRIANGLE``'s list of
#: 256 and what it did not list: trimmed to 256 it faulted 22 k pages at 1.5 M, at 288
#: 4.1 k, when it held all of a 256 B reserve 6.0 k);
#: sparse: its arrays of one entry per input triangle, half-edge or output row (a
#: few more rows than triangles): the validation's half-edge twins (24), the
#: triangles' smallest and largest angles (16), the judged edges (3), the open
#: candidates' union-find and marks (9), the plan's status, slots, joins and
#: union-finds (36), the walk's order (8), the gather's rows and its positions,
#: parents, partners, kinds, angles and claim (81), the pinned edges (3), the
#: improvement's stamps (16) and the certificate's narrowed claim (12): 208; from
#: ``sparse.LOCAL_MIN_TRIANGLES`` the renumbering's too (cell keys 8, order 8, rows
#: 24, twins 24, pinned marks 3, points ~8: 75), 283 in all: so all of the 256 that
#: ``quality_mesh`` faults (the rest are made inside kernels, or small: a kernel
#: handed ``pages.fresh`` arrays raises this). Session 11: the walk's table of links
#: (16, its buffer then the gather's positions) and room after the per-row arrays
#: (``sparse.ROOM_ROWS``: the ring rows appended in place, not ~90 B per triangle of
#: copies), and the certificate's input facts (~26): measured at 1.5 M the reserve ran
#: out in the output rows at 256; 352. Session 12: the cover's neighbours, matching,
#: search arrays and cycle arrays (48: ~4 k pages fewer faulted in the cover at 1.5 M); 400.
#: Session 23: the drop phase's search arrays, the renumbering's vertex arrays and the
#: certificate's narrowed claim (18 MB at 1.5 M, which missed at 400); 416.
RESERVE_TAKEN = {"incircle": 288, "sparse": 416}

#: Bytes per input triangle sparse mode takes from ``hammesh.pages`` after its cover
#: (the open candidates 9, the plan 36, the walk 8 and its table of links 16 (then the
#: gather's row places), the gather 73, the pinned edges 3,
#: the stamps 16, the certificate's claim 12): without a reserve (a mesh read from a
#: file, or made by ``quality_mesh(isolate=False)``) the second thread faults in a
#: reserve of this size while the cover runs, mostly on one core.
RESERVE_AFTER_COVER = 173
#: triangles below which sparse mode makes no reserve of its own (few pages to fault)
SIDE_RESERVE_MIN_TRIANGLES = 200_000
#: whether the certificate looks at the input on a thread of the lowest priority
#: (:mod:`hammesh.idle`, Linux): it takes only what the construction leaves of the
#: cores, instead of a third of two of them where the construction runs two threads;
#: else on the side executor's thread. Quiet fresh 1.5 M first calls (session 23):
#: sparse 0.718 -> 0.704 s (medians of 6), incircle 0.441 -> 0.411 s (of 5)
LOOK_ON_IDLE_CORE = True
#: the certificate's look at the input, seconds per input triangle on one core (0.08 s
#: at 1.5 M, session 23): the longest a caller waits for the idle core's look before
#: it looks itself (``hammesh.idle``; where it may not raise the thread back)
LOOK_SECONDS_PER_TRIANGLE = 5.5e-8


_loaded = threading.Lock()
_loaded_modes: set[str] = set()


def load_kernels(mode: str = "sparse") -> None:
    """Load the compiled kernels of ``hamiltonian(mesh, mode=mode)`` into this process.

    A compiled kernel's first call in a process loads its machine code from numba's
    cache (about 10 ms per kernel, 0.1-0.2 s for one ``hamiltonian()``); this runs
    ``hamiltonian`` once on a small Triangle mesh so that the next call does not pay
    it. ``quality_mesh`` calls it while Triangle runs in its child process. Cheap
    after the first call in a process.
    """
    with _loaded:
        if mode in _loaded_modes:
            return
        from hammesh.domain import Domain
        from hammesh.meshing import quality_mesh

        square = Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])
        hamiltonian(quality_mesh(square, min_angle=30, max_area=0.01, isolate=False), mode=mode)
        if mode == "sparse":  # (and the paths only big outputs take)
            from hammesh.halfedge import half_edge_twins, renumber_local, restore_vertices
            from hammesh.postprocess._sparse_kernels import load_output_kernels

            load_output_kernels()
            from hammesh.postprocess._join_kernels import load_ring_kernels

            load_ring_kernels()
            m = quality_mesh(square, min_angle=30, max_area=0.05, isolate=False)  # (the renumbering, from
            tw = half_edge_twins(m.triangles, m.n_points)[0]  # sparse.LOCAL_MIN_TRIANGLES triangles)
            restore_vertices(renumber_local(m.points, m.triangles, tw, tw < 0).triangles, np.arange(m.n_points))
            # (and the twins matched once from Triangle's neighbours in the new order,
            # ``prepare_mesh(match=False)``: 4 kernels, ~13 ms of a first call's main thread)
            from hammesh.halfedge import local_half_edges

            local_half_edges(prepare_mesh(m, measure=True, cells=True, match=False)[0])
            from hammesh.postprocess.sparse import kept_radius_ratio  # (when the worst input triangle is joined)

            kept_radius_ratio(m.points, m.triangles, np.full(m.n_triangles, 3, np.int8), np.arange(m.n_triangles),
                              np.zeros(m.n_triangles))
        _loaded_modes.add(mode)


def refuse_overlap(clean: Mesh, he: HalfEdges | None) -> None:
    """Refuse a planar input mesh two of whose triangles overlap without sharing an edge.

    The validation sees overlaps across a shared edge (a triangle turned over); two
    triangles that meet at a vertex only, or not at all, can still lie on each other,
    and then the output would "tile" an input that covers some area twice (``hammesh
    check`` of it, which has no input to compare with, finds them). Only triangles
    with a boundary edge need testing (``hammesh.planar_overlap``): cheap next to the
    construction. Triangle's own meshes (``quality_mesh``) are planar by construction.
    """
    pair = find_overlap(clean.points, clean.triangles, twin=None if he is None else he.twin)
    if pair is not None:
        i, j = pair
        raise InvalidMeshError(f"triangles {i} and {j} overlap (a planar mesh covers each point once): "
                               "not a planar triangulation")


def _snapped(out: HamiltonianMesh, clean: Mesh, facts, claim) -> tuple[HamiltonianMesh, int, dict | None]:
    """``out`` with Steiner points moved to nearby float64 values that keep the angle bound
    (``snap_steiner_points``), fully certified again; stats None if that fails too."""
    segs = clean.segments
    keep = np.zeros(out.n_points, dtype=bool)
    if len(segs):  # midpoints of constrained edges must stay exact midpoints
        mid = np.ascontiguousarray(0.5 * (clean.points[segs[:, 0]] + clean.points[segs[:, 1]]))
        pc = np.ascontiguousarray(out.points).view(np.complex128).ravel()
        keep = np.isin(pc, mid.view(np.complex128).ravel())
    pts, k = snap_steiner_points(out.points, out.triangles, clean.n_points, 0.5 * facts.min_angle, keep=keep)
    if k == 0:
        return out, 0, None
    moved = replace(out, points=pts)
    try:
        return moved, k, certify(moved, facts, claim=claim)
    except VerificationError:
        return out, k, None


def hamiltonian(mesh: Mesh, *, mode: str = "sparse", keep: float = KEEP, tree: str = "quadtree") -> HamiltonianMesh:
    """Turn a planar triangle mesh into a verified Hamiltonian cycle mesh.

    ``mode="sparse"`` (the default): keeps the input mesh's quality. A cycle cover of
    the dual keeps almost every triangle whole; the cycles are joined by
    Steiner-free swaps and one-point splits judged against the triangles they
    replace (``keep``), Thm 2.4's incenter-flip bridges only where nothing else
    joins (``hammesh.postprocess.sparse``, docs/sparse.md). About 0.5 % Steiner
    points on quality meshes; FEM errors within 1-3 % of the input mesh's.

    ``mode="incircle"``: the paper's construction (Thm 2.4), a Steiner point at every
    triangle's incenter and one flip per dual spanning-tree edge; constrained edges
    are split at their midpoint where the tree must cross them. Its price: three
    times the triangles, angles down to half the input's and up to 150 degrees.
    Both modes guarantee (and certify) min angle >= 1/2 x the input's.

    Parameters
    ----------
    mesh : Mesh
        Any valid planar triangulation (ours or read from a file); triangles may be
        given in either orientation.
    mode : {"sparse", "incircle"}
    keep : float
        Sparse mode's local quality rule (issue 13): every triangle a join creates
        keeps its angles >= ``keep`` x the smallest angle of the triangles it
        replaces and <= the input's largest angle + 5 degrees where any join can
        (the report counts where none could); the proven floor (>= 1/2 the input's
        minimum) holds regardless. Ignored by ``"incircle"``.
    tree : {"quadtree", "fishbone", "comb"}
        Incircle mode's dual spanning tree (``hammesh.postprocess.incircle.TREES``):
        ``"fishbone"`` makes the cycle sweep the domain so that ``hammesh.partition``'s
        stretches cut close to METIS (docs/partition.md), at about +20 % of this call's
        time; ``"quadtree"`` (the default) is the fastest. Sparse mode: ``"fishbone"``
        confines the cover to the fishbone's cells and joins them in its class order
        (``hammesh.postprocess.sparse_cells``; an opt-in: it costs Steiner points and
        angles), ``"comb"`` takes ``hammesh.postprocess.comb_cover``'s (issue 14: cut
        1.2-1.4 x METIS at 300 k triangles, ~0.5 % Steiner points, smallest angle
        ~16-17 degrees where the default keeps ~27, ~3 x the CPU; docs/partition.md),
        ``"quadtree"`` (the default) leaves the cover free.

    Returns
    -------
    HamiltonianMesh
        Triangles in cycle order, one cycle per connected piece; ``report`` holds the
        counts, angles, timings and ``verified: True``.

    Raises
    ------
    InvalidMeshError
        The input is not a valid planar triangulation (message names the item).
    InvalidDomainError
        The certificate failed where two input vertices are fewer than
        ``hammesh.domain.resolution.MIN_FEATURE_ULPS`` ulps apart: no float64 Steiner
        point there keeps the bound (try ``mode="sparse"``, which places few; or move
        the domain nearer the origin).
    VerificationError
        The output failed its certificate (never returned then).
    """
    try:
        return _hamiltonian(mesh, mode, keep, tree)
    finally:  # what quality_mesh faulted in ahead and this call did not take
        pages.release()


def _hamiltonian(mesh: Mesh, mode: str, keep: float, tree: str = "quadtree") -> HamiltonianMesh:
    params.instance("mesh", mesh, (Mesh, HamiltonianMesh), "a hammesh.Mesh")  # issue 12 #11
    if isinstance(mesh, HamiltonianMesh):  # (its cycle is the input's order: kept_cycle)
        mesh = mesh.as_mesh()
    if mode not in MODES:
        raise InvalidOptionError(f"mode must be one of {sorted(MODES)}, got {mode!r}")
    if isinstance(keep, (bool, np.bool_)) or not (isinstance(keep, numbers.Real) and 0.0 <= keep <= 1.0):
        raise InvalidOptionError(f"keep must be a number between 0 and 1, got {keep!r}")
    keep = float(keep)  # (a numpy scalar is welcome; the kernels take a float)
    trees = SPARSE_TREES if mode == "sparse" else tuple(TREES)  # (each mode names its own)
    if tree not in trees:
        raise InvalidOptionError(f"tree must be one of {list(trees)} in {mode} mode, got {tree!r}")
    t0 = time.perf_counter()
    taken, shape = RESERVE_TAKEN.get(mode), np.shape(mesh.triangles)
    if taken is not None and len(shape) == 2 and pages.reserved():  # pages it will not take: back now
        pages.trim(taken * shape[0])
    # a second thread works beside the construction: the walk's arrays (while the
    # input is checked), the input's side of the certificate, and (incircle) the row
    # checks of the rows the walk has finished
    with threads.side_executor() as side:  # (inline when this process may use one thread)
        ready = None
        shape = np.shape(mesh.triangles)
        if mode == "incircle" and len(shape) == 2 and shape[1] == 3:
            # (parent and kind: made of the input's pairing arrays once the forest is done)
            ready = side.submit(walk_arrays, 3 * shape[0], 3 * shape[0], False, np.shape(mesh.points)[0])
        # the certificate's own look at the caller's input (never at the construction's
        # validated copy), on a thread of the lowest priority (``hammesh.idle``: it fills
        # what the construction leaves of the cores), from the start (incircle) or from
        # the placing of the splits on (sparse: its cover and the passes before keep
        # both cores busy)
        facts = []
        on_idle = LOOK_ON_IDLE_CORE and idle.available() and not isinstance(
            side, threads.InlineExecutor)
        grace = LOOK_SECONDS_PER_TRIANGLE * (shape[0] if len(shape) == 2 else 0)

        def start_facts() -> None:
            if not facts:
                facts.append(idle.on_idle_core(input_facts, mesh, grace=grace) if on_idle
                             else side.submit(input_facts, mesh))

        def beside_cover() -> None:  # (sparse: the other core is mostly idle during the cover)
            start_facts()
            m = shape[0] if len(shape) == 2 else 0
            if m >= SIDE_RESERVE_MIN_TRIANGLES and not pages.reserved() and not isinstance(
                side, threads.InlineExecutor
            ):
                side.submit(pages.reserve, RESERVE_AFTER_COVER * m)

        if mode == "incircle":
            start_facts()
        # (Thm 2.4 needs no angle; sparse mode renumbers big meshes by the cells the
        # orientation pass finds: sparse.LOCAL_MIN_TRIANGLES)
        local = mode == "sparse" and len(shape) == 2 and sparse_module.renumbers(
            shape[0], np.shape(mesh.points)[1] if np.ndim(mesh.points) == 2 else 0, mesh.info)
        # (sparse mode matches a big mesh's half-edges once, in its renumbered order)
        clean, he, is_con = prepare_mesh(mesh, measure=mode != "incircle", cells=local, match=not local)
        if not mesh.info.get("backend"):  # (not Triangle's own mesh: see refuse_overlap)
            refuse_overlap(clean, he)
        rows = prepared = vmarks = None
        if mode == "incircle":
            serial = isinstance(side, threads.InlineExecutor)  # (no row stream then: its checker waits for rows)
            out, claim, stream = incircle_streaming(clean, he, is_con, None if serial else side, ready, reuse=True,
                                                    tree=tree)
            del he, is_con  # (their memory is the output's parent and kind now)
            t1 = time.perf_counter()
            # the certificate's last steps, ahead, while the other thread checks rows
            prepared = claim_structure(out.triangles, claim)
            # (serial, so done while the other thread checks rows, not after them)
            vmarks = output_vertex_markers(mesh.vertex_markers, out.n_points, out.segments, out.segment_markers)
            if stream is not None:
                stream.join()  # then help with the row checks still to do
                rows = (stream.result(out.components), stream.used)
        else:
            # rows that already walk a cycle per piece (hammesh's own output read back) are
            # kept: a construction would only add triangles (kept_cycle)
            runs = kept_runs(clean.triangles) if tree == "quadtree" else None
            if runs is not None and he is None:
                he, is_con = match_half_edges(clean)  # (kept_cycle reads the input's pairing)
            out = None if runs is None else kept_cycle(clean, he, runs)
            claim = None if out is None else he.twin  # (the same rows: the input's pairing)
            if out is None:
                out, claim = sparse_hamiltonian(clean, he, is_con, keep=keep, beside_cover=beside_cover, tree=tree)
            t1 = time.perf_counter()
        start_facts()  # (if the construction did not)
        ref_facts = facts[0].result()
    snapped = 0
    try:
        # (its row threads take both cores: the pages the construction dropped, ~290 MB
        # at 1.5 M in sparse mode, are given back after it, not beside it)
        with threads.later_held():
            stats = certify(out, ref_facts, claim=claim, rows=rows, prepared=prepared)
    except VerificationError as exc:
        # detail finer than float64 can place Steiner points around (issue 12: a 1e-6
        # square at offset 1e9) is the input's limit, not a construction bug: move the
        # Steiner points to other float64 values nearby where that keeps the bound (and
        # certify again, in full), else say so (exit 2) instead of "verification
        # failed"; nothing unverified is returned
        try:
            check_resolution(mesh.points)
        except InvalidDomainError as limit:
            out, snapped, stats = _snapped(out, clean, ref_facts, claim)
            if stats is None:
                raise InvalidDomainError(f"{limit} (the certificate found: {exc})") from exc
        else:
            # (the input's vertices are far apart in ulps, the refinement's triangles may
            # not be: say so where rounding explains every row below the bound)
            if exc.check == "angle":  # (only the angle bound failed: no other fault)
                check_rounding(out.points, out.triangles, 0.5 * ref_facts.min_angle, mode)
            raise
    t2 = time.perf_counter()
    report = dict(out.report)
    report.update(
        {
            "mode": mode,
            # what the domain needed before meshing (hammesh.domain.repair), if meshed here
            "repairs": list(mesh.info.get("repairs", [])),
            "min_angle_input_deg": stats["min_angle_input_deg"],
            "min_angle_output_deg": stats["min_angle_output_deg"],
            "max_angle_output_deg": stats["max_angle_output_deg"],
            # rows within float64 rounding of the bound (verify.certificate.ROUNDING_RTOL_MAX)
            "angle_rounding_rows": stats.get("angle_rounding_rows", 0),
            # Steiner points moved off their rounded place (hammesh.domain.resolution)
            "steiner_points_snapped": snapped,
            "verified": True,
            "seconds": {
                "mesh": mesh.info.get("seconds"),
                "hamiltonian": t1 - t0,
                "verify": t2 - t1,
            },
        }
    )
    if vmarks is None:  # (snapping moves points only: the markers stand)
        vmarks = output_vertex_markers(mesh.vertex_markers, out.n_points, out.segments, out.segment_markers)
    # never lose data: the input's names and per-point values go with it (parent carries
    # the per-triangle values; Steiner points get interpolated point values)
    point_data = carry_point_data(mesh.point_data, mesh.points, mesh.triangles, out.points, out.triangles,
                                  out.parent, out.kind)
    return replace(out, report=report, vertex_markers=vmarks, attribute_names=mesh.attribute_names,
                   point_data=point_data)
