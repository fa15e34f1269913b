"""Strip encoders for any triangle mesh (paper §5): long dual paths, one index buffer.

Without Steiner points a mesh is rarely Hamiltonian (deciding it is NP-complete, §5), so
the scalable encoder covers the dual graph with few long paths, turn-aware so that few
swaps are needed, and joins them into one buffer:

* a :class:`~hammesh.mesh.HamiltonianMesh` (rows in cycle order, ``components`` run
  lengths) is sent as exactly one strip per cycle, cut and directed where that gives
  the fewest swaps (exact for the fixed order);
* a mesh whose dual graph is a forest (a triangulated polygon) starts from its minimum
  path partition (Lemma 5.1, :func:`forest_paths`);
* any other mesh is covered greedily (:func:`greedy_paths`, O(m) numba), seeds with the
  fewest free neighbours first, each path grown both ways, preferring neighbours with
  few free neighbours and then the alternating turn;
* then two sweeps of local moves at the path ends (join two ends, Posa rotation,
  tunnelling into a neighbouring path), each costed in O(1), keep every change that
  shortens the buffer (never adding a path), on the mesh renumbered in path order
  (memory locality), path ends visited from the last path back to the first;
* each path is sent in the direction that needs fewer swaps at its ends; with restarts
  the buffer is written in one compiled pass;
* from 50,000 triangles, on two cores, a plain mesh joined by restarts is encoded in two
  halves on two threads, each proving its own part (:mod:`hammesh.strips.halves`).

Cost of a buffer: ``T + 2 S + swaps`` plus ``S - 1`` restarts or ``2 (S - 1)`` stitches.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import numpy as np

from hammesh import params, threads
from hammesh.errors import InvalidOptionError
from hammesh.mesh import HamiltonianMesh, Mesh
from hammesh.strips._cover_kernels import (
    LONGEST_CHAIN,
    SHORTEST_CHAIN,
    greedy_path_cover,
    renumber_in_path_order,
    zigzag_path_cover,
)
from hammesh.strips._emit_kernels import restart_buffer
from hammesh.strips._dual_kernels import records_dtype
from hammesh.strips._greedy_strip_kernels import NO_SEED_ORDER, greedy_strip_buffer, strip_work
from hammesh.strips._moves_kernels import improve_cover
from hammesh.strips._path_kernels import orient_paths
from hammesh.strips.dual import DualMesh, MeshLike, dual_mesh
from hammesh.strips.cache import PIECE_LENGTH, SHORT_PIECE_LENGTH, fifo_strip_order, split_paths
from hammesh.strips.cache import reorder_vertices as _first_use_numbering
from hammesh.strips.halves import HALVES_FROM, encode_in_halves
from hammesh.strips.generalized import GeneralizedStrips, generalized_from_turns
from hammesh.strips.gl import JOINS, RESTART_INDEX, GLStrip, gl_strip_from_turns, verify_gl_strip
from hammesh.strips.paths import PathTurns, check_starts, path_turns
from hammesh.strips.rows import BAND_DRIFT, BAND_MERGE, ROW_AXES, band_frame, band_layout, band_reach, row_path_cover

__all__ = [
    "METHODS",
    "is_forest",
    "forest_paths",
    "greedy_paths",
    "cycle_paths",
    "mesh_paths",
    "encode",
    "encode_generalized",
    "restart_strip",
    "orient_path_turns",
    "PROOF_IN_TWO_PARTS",
    "half_encoder",
]

#: How the dual paths are found: ``"auto"`` is ``"order"`` for a HamiltonianMesh and
#: ``"greedy"`` otherwise (which also tries ``"zigzag"`` on meshes with few swaps, and
#: ``"rows"`` on planar meshes up to :data:`_ROWS_UP_TO` triangles); ``"zigzag"`` starts
#: from the swap-free chains, ``"rows"`` from the row cover (:mod:`hammesh.strips.rows`;
#: planar meshes) (a dual forest keeps Lemma 5.1's cover).
METHODS = ("auto", "greedy", "order", "zigzag", "rows")

#: Weight of a swap against a neighbour's remaining degree in the greedy choice.
_SWAP_WEIGHT = 1

#: Sweeps of :func:`~hammesh.strips._moves_kernels.improve_cover` over the path ends.  On the
#: benchmark's planar meshes (indices per triangle) the greedy cover gives 1.293-1.318,
#: one sweep 1.268-1.295, two 1.266-1.294, three 1.266-1.294 (ends visited from the last
#: path back; in the input's order it was 1.272-1.301 / 1.268-1.297 / 1.267-1.294).
#: Two keep every planar mesh <= 1.30 and within 0.0006 of (on 6 of 10, better than)
#: two sweeps in the input's order; one sweep would lose 0.001-0.002.
_IMPROVE_PASSES = 2


def is_forest(dual: DualMesh) -> bool:
    """Is the dual graph a forest (e.g. a triangulated polygon: no interior vertex)?"""
    edges = int(np.count_nonzero(dual.twin >= 0)) // 2
    if edges >= dual.n_triangles:  # a forest has at most m - 1 edges: skip the components
        return False
    return edges == dual.n_triangles - dual.n_components


def forest_paths(dual: DualMesh) -> tuple[np.ndarray, np.ndarray]:
    """Lemma 5.1: the fewest dual paths of a dual forest, in O(m).

    Uses :func:`hammesh.polygon.path_partition.forest_path_partition` (greedy from the
    leaves up); the caller checks :func:`is_forest`.
    """
    from hammesh.polygon.path_partition import forest_path_partition

    paths = forest_path_partition(dual.neighbor_triangles)
    order = np.concatenate(paths).astype(np.int64)
    starts = np.r_[0, np.cumsum([len(p) for p in paths])].astype(np.int64)
    return order, starts


def greedy_paths(dual: DualMesh, improve: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Cover the dual graph with paths, greedily, then improve the cover locally.

    A dual forest (a triangulated polygon) starts from its minimum path partition
    (Lemma 5.1, :func:`forest_paths`) instead; the local moves never add a path, so
    the strip count stays the minimum.

    Parameters
    ----------
    dual : DualMesh
    improve : bool
        After the greedy pass, join paths whose ends are neighbours, rotate path ends
        and tunnel into neighbouring paths wherever the buffer gets shorter
        (:func:`~hammesh.strips._moves_kernels.improve_cover`: a few sweeps over the path
        ends, each move costed in O(1)).  A single path is left as it is.

    Returns
    -------
    order : (m,) int64
        Every triangle once, path after path.
    starts : (S + 1,) int64
        Path offsets.  Paths never cross dual components.
    """
    _, _, order, starts, ids = _greedy_cover(dual, improve)
    return (order if ids is None else ids[order]).astype(np.int64, copy=False), starts


def _greedy_cover(dual: DualMesh, improve: bool = True, zigzag: int | None = None, rows: int | None = None):
    """:func:`greedy_paths` in the numbering of the first cover (what the fast path uses).

    The greedy pass reads the mesh's records (:attr:`DualMesh.records`, one half
    cache line per triangle).  After
    it (or Lemma 5.1's partition) the mesh is renumbered in path order
    (:func:`~hammesh.strips._cover_kernels.renumber_in_path_order`): the moves and the emission then
    walk mostly adjacent rows instead of Triangle's scattered numbering.  The moves
    visit the path ends from the last path back to the first, which is the same cover
    as visiting them in that order without renumbering.

    A cover of one path is returned as the greedy pass left it.

    Returns ``(tri, twin, order, starts, ids)``: the arrays the paths ``order`` refer
    to, and ``ids[i]`` the input triangle of row ``i`` (``None``: the input's own).
    ``zigzag``: start from the swap-free chains, taking each seed's longest
    (``LONGEST_CHAIN``) or shortest (``SHORTEST_CHAIN``) chain; ``rows``: start from the
    row cover along ``rows.ROW_AXES[rows]``; both ``None``: the greedy cover.
    """
    m = dual.n_triangles
    rec = dual.cover_records()
    if is_forest(dual):
        order, starts = forest_paths(dual)
    elif zigzag is not None:
        order, starts = zigzag_path_cover(rec, np.arange(m - 1, -1, -1), zigzag)
    elif rows is not None:
        order, starts = row_path_cover(dual.points, dual.triangles, dual.twin, ROW_AXES[rows])
    else:
        order, starts = greedy_path_cover(rec, _SWAP_WEIGHT, NO_SEED_ORDER)  # seeds m - 1, ..., 0
    if not improve or len(starts) == 2:
        # one path (a closed surface often is one): no join or tunnel exists, and the
        # rotations could only move a swap or two at its ends; not worth O(m) set-up
        return dual.triangles, dual.twin, order, starts, None
    tri, twin, _ = renumber_in_path_order(rec, order)
    # ends visited from the last path back to the first: neighbouring memory (the
    # input's numbering had scattered them), and on the benchmark's meshes as good a
    # cover (-0.0026 to +0.0006 indices per triangle against the input's order)
    visit = np.arange(m - 1, -1, -1, dtype=np.int64)
    local, starts = improve_cover(tri, twin, np.arange(m, dtype=np.int64), starts, _IMPROVE_PASSES, visit)
    return tri, twin, local, starts, order


def _cut_cycle(tri: np.ndarray, twin: np.ndarray, run: np.ndarray) -> np.ndarray:
    """Rotate one cycle so that opening it gives the shortest strip (exact, O(k)).

    For a fixed cyclic order the only choices are where to open it and in which
    direction to send it.  Interior pivots do not depend on either, so with
    ``f[j] = 1`` when the pivots at ``j - 1`` and ``j`` coincide (a swap in the
    cycle), opening before ``c`` costs ``k + 2 + sum(f) - f[c - 1] - f[c] - f[c + 1]``
    plus the first swap of the better direction: forwards it is needed when the tail
    of ``run[c]``'s exit half-edge is the pivot at ``c + 1``, backwards when the tail
    of ``run[c - 1]``'s half-edge towards ``run[c - 2]`` is the pivot at ``c - 2``.
    :func:`orient_path_turns` then sends the path in its better direction.
    """
    k = len(run)
    if k < 4:
        return run
    nb = twin[3 * run[-1] : 3 * run[-1] + 3]
    if not np.any((nb >= 0) & (nb // 3 == run[0])):
        return run  # an open path: nothing to choose
    ext = np.r_[run[-1], run, run[0]]
    turns = path_turns(tri, twin, ext, [0, k + 2])
    piv = turns.pivot[1 : k + 1]  # cyclic pivots of run[0..k-1]
    f = (piv == np.roll(piv, 1)).astype(np.int64)  # f[j]: swap at j in the cycle
    interior = f.sum() - f - np.roll(f, -1) - np.roll(f, 1)
    tail_fwd = tri[run, turns.exit[1 : k + 1]]  # run[c] leaving towards run[c + 1]
    first_fwd = tail_fwd == np.roll(piv, -1)
    tail_in = tri[run, turns.entry[1 : k + 1]]  # run[j] leaving back towards run[j - 1]
    first_bwd = np.roll(tail_in, 1) == np.roll(piv, 2)  # path run[c - 1], run[c - 2], ...
    cost = interior + np.minimum(first_fwd, first_bwd)
    c = int(np.argmin(cost))
    return np.roll(run, -c)


def cycle_paths(dual: DualMesh, components: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One path per cycle of a mesh stored in Hamiltonian-cycle order.

    Parameters
    ----------
    dual : DualMesh
        Of the cycle-ordered triangles.
    components : (c,) int
        Run lengths of the cycles (:attr:`HamiltonianMesh.components`).
    """
    comp = np.asarray(components, dtype=np.int64)
    starts = np.r_[0, np.cumsum(comp)].astype(np.int64)
    if starts[-1] != dual.n_triangles or np.any(comp <= 0):
        raise InvalidOptionError(
            f"cycle run lengths {comp.tolist()[:6]} do not add up to {dual.n_triangles} triangles"
        )
    order = np.concatenate(
        [_cut_cycle(dual.triangles, dual.twin, np.arange(a, b)) for a, b in zip(starts[:-1], starts[1:])]
    )
    return order, starts


def orient_path_turns(dual: DualMesh, order: np.ndarray, starts: np.ndarray) -> PathTurns:
    """Turns of the paths, each path reversed where that needs fewer swaps.

    Interior pivots (and so interior swaps) do not depend on the direction; only the
    swap after the first triangle does, so the reversed count comes from the forward
    turns at the path's last two triangles.
    """
    order, starts = check_starts(order, starts, dual.n_triangles)
    new, _ = orient_paths(dual.triangles, dual.twin, order, starts)
    return path_turns(dual.triangles, dual.twin, new, starts)


def _stored_runs(dual: DualMesh) -> np.ndarray:
    """Run lengths of a plain mesh stored piece after piece (as hammesh writes cycles)."""
    label = dual.component
    starts = np.r_[0, np.flatnonzero(np.diff(label) != 0) + 1]
    if len(starts) != dual.n_components:
        raise InvalidOptionError(
            "method 'order' needs each connected piece stored as one consecutive run of rows"
        )
    return np.diff(np.r_[starts, dual.n_triangles])


def _oriented_paths(mesh: MeshLike, method: str) -> tuple[DualMesh, np.ndarray, np.ndarray]:
    """Validated mesh, its dual paths (``order``, ``starts``), each in its better direction."""
    dual, _, _, order, starts, ids = _oriented_local(mesh, method)
    return dual, (order if ids is None else ids[order]), starts


def _oriented_local(
    mesh: MeshLike,
    method: str,
    cache: int | None = None,
    dual: DualMesh | None = None,
    rule: int = LONGEST_CHAIN,
    improve: bool = True,
    piece: float = PIECE_LENGTH,
):
    """:func:`_oriented_paths` in the numbering the paths were improved in (``rule``: which
    swap-free chain ``method="zigzag"`` takes from each seed; ``improve``: the end moves;
    with ``cache``, paths longer than ``piece * cache`` triangles are cut into equal pieces
    and all are sent in FIFO order).

    Returns ``(dual, tri, twin, order, starts, ids)``: ``order`` refers to the rows of
    ``tri`` (``twin`` its pairing), ``ids[i]`` is the input triangle of row ``i``
    (``None``: ``tri`` is the input's own array).
    """
    if method not in METHODS:
        raise InvalidOptionError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    zigzag = rule if method == "zigzag" else None
    rows = rule if method == "rows" else None
    dual = dual_mesh(mesh) if dual is None else dual
    if cache is not None and method == "order":
        raise InvalidOptionError("a cache-aware encoding makes its own paths: method 'order' does not apply")
    if method == "auto":
        method = "order" if isinstance(mesh, HamiltonianMesh) else "greedy"
    if method == "order":
        if isinstance(mesh, HamiltonianMesh):
            comps = np.asarray(mesh.components)
        else:
            comps = _stored_runs(dual)
        order, starts = cycle_paths(dual, comps)
        tri, twin, ids = dual.triangles, dual.twin, None
    else:
        tri, twin, order, starts, ids = _greedy_cover(dual, improve, zigzag, rows)
    order, starts = check_starts(order, starts, dual.n_triangles)
    bands = cache is not None and rows is not None
    if bands:
        # the rows (joined by the end moves over the whole mesh) cut into columns of ~cache -
        # rows.band_slack(cache) triangles a row, sent column by column (rows.band_layout).  A cover made
        # inside the columns (the dual cut at their borders) had fewer pieces but its end
        # moves join rows into U-turns and blobs: q30 10k 1.3615 ipt at ACMR16 0.804,
        # against 1.413 / 0.647 this way (docs/strips.md, sessions 12-13)
        # (session 14: cuts moved to save swaps, cut again where a piece drifts across rows,
        # pieces heading the same way joined, each turned along the rows on a tie; band_layout
        # turns the pieces itself)
        frame = band_frame(dual.points, tri, cache, ROW_AXES[rows])
        order, starts = band_layout(frame, tri, twin, order, starts, BAND_MERGE, band_reach(cache), BAND_DRIFT, join=True)
    else:
        if cache is not None:
            # strips a FIFO of ``cache`` entries can carry into the next one (cache.PIECE_LENGTH)
            starts = split_paths(starts, max(1, int(piece * cache)))
        order, _ = orient_paths(tri, twin, order, starts)
    if cache is not None and not bands:
        order, starts = fifo_strip_order(tri, twin, order, starts, len(dual.points), cache)
    return dual, tri, twin, order, starts, ids


def restart_strip(tri: np.ndarray, twin: np.ndarray, order: np.ndarray, starts: np.ndarray, restart_index: int) -> GLStrip:
    """:func:`~hammesh.strips.gl.gl_strip` with restarts, in one compiled pass (no turn arrays)."""
    R = int(restart_index)
    out, n_swaps, top, err = restart_buffer(tri, twin, order, starts, R)
    S = len(starts) - 1
    if err:
        turns = path_turns(tri, twin, order, starts)  # raises, naming the step
        return gl_strip_from_turns(turns, join="restart", restart_index=R)
    if 0 <= R <= top and np.count_nonzero(out == R) != S - 1:
        raise InvalidOptionError(f"restart index {R} is a vertex index of the mesh")
    return GLStrip(out, R, len(order), S, int(n_swaps))


def mesh_paths(mesh: MeshLike, method: str = "auto") -> tuple[DualMesh, PathTurns]:
    """Validate ``mesh``, cover its dual with paths and analyse their turns.

    Parameters
    ----------
    mesh : Mesh or HamiltonianMesh
    method : {"auto", "greedy", "order", "zigzag", "rows"}
        ``"order"`` takes the rows as given: a HamiltonianMesh's cycles, or a plain mesh
        whose pieces are stored as consecutive runs of rows, each a dual path or cycle
        (a Hamiltonian mesh read back from a file).

    Returns
    -------
    dual : DualMesh
    turns : PathTurns
    """
    dual, order, starts = _oriented_paths(mesh, method)
    return dual, path_turns(dual.triangles, dual.twin, order, starts)


def encode(
    mesh: MeshLike,
    *,
    join: str = "restart",
    restart_index: int | None = RESTART_INDEX,
    method: str = "auto",
    verify: bool = True,
    cache: int | None = None,
    reorder_vertices: bool = False,
    fast: bool = False,
) -> GLStrip:
    """One GL_TRIANGLE_STRIP index buffer drawing every triangle of ``mesh`` once.

    Parameters
    ----------
    mesh : Mesh or HamiltonianMesh
        Planar ``(n, 2)`` or surface ``(n, 3)`` points; windings are kept.
    join : {"restart", "stitch"}
    restart_index : int
        Used with ``join="restart"`` (default ``0xFFFFFFFF``).
    method : {"auto", "greedy", "order", "zigzag", "rows"}
        See :data:`METHODS` and :func:`mesh_paths`.  A HamiltonianMesh gives exactly one
        strip per cycle.
    verify : bool
        Decode the buffer with OpenGL's rules and compare with the mesh
        (:func:`~hammesh.strips.gl.verify_gl_strip`, two O(L) compiled passes against
        the order the paths were meant to draw; in two halves on two threads, from
        ``halves.HALVES_FROM`` triangles, the multiset fingerprints of
        :mod:`~hammesh.strips._fingerprint_kernels`, which read no claim: a wrong buffer
        passes only by a 64-bit hash coincidence, and a failed one gets the full
        comparison).  Costs ~3-10% of the encoding; leave on.
    cache : int, optional
        Lay the strips for a FIFO vertex cache of this many entries (at least 3): the
        cover's strips longer than ``cache.PIECE_LENGTH * cache`` triangles cut into equal
        pieces (:func:`~hammesh.strips.cache.split_paths`) and all sent in an order laid
        for the FIFO (:func:`~hammesh.strips.cache.fifo_strip_order`), with ``"greedy"`` or
        ``"zigzag"`` (``"zigzag"`` stays under 1.30 indices per triangle on q30 planar
        meshes, ACMR16 ~0.87).  With ``method="auto"`` on a planar mesh, or ``"rows"``: the
        row cover laid in bands (:func:`~hammesh.strips.rows.band_layout`, rows of at most
        ``cache - rows.band_slack(cache)`` triangles; q30 meshes ACMR32 0.618-0.631 at
        1.28-1.30 indices per triangle, ACMR16 0.68-0.70 at 1.36-1.38, ACMR64 0.57-0.59 at
        1.25-1.27; meshoptimizer's vertex-cache order + stripify 0.635-0.643, 0.71 and
        0.61 at 1.72-1.74); ``"auto"`` on a surface: the
        swap-free chains cut at ``cache.SHORT_PIECE_LENGTH * cache``.  Fewer vertex-shader
        runs for more indices.
    reorder_vertices : bool
        Renumber the vertices in order of first use (as meshoptimizer's
        ``optimizeVertexFetch``); the result's ``vertex_order`` says which old vertex
        each new one is (write ``points[vertex_order]``).
    fast : bool
        The greedy cover alone: no end moves, no second cover from the swap-free chains
        (about half the time; on q30 planar meshes ~0.02-0.03 more indices per triangle,
        ~1.30 instead of ~1.27, still fewer than vtkStripper's, NvTriStrip's or
        meshoptimizer's).

    From :data:`~hammesh.strips.halves.HALVES_FROM` triangles, when
    ``hammesh.threads.cores()`` allows two, a plain mesh joined by restarts (no
    ``cache``, no ``reorder_vertices``) is encoded in two halves on two threads
    (:func:`~hammesh.strips.halves.encode_in_halves`): ~0.002-0.004 more indices per
    triangle for about half the wall time; defects and dual forests take the one-thread
    path, as do default-mode results with few swaps (it tries the swap-free chains).

    Returns
    -------
    GLStrip
        ``n_strips`` counts the dual paths (at least one per connected piece).

    Raises
    ------
    InvalidMeshError
        Bad input mesh (see :func:`~hammesh.strips.dual.dual_mesh`).
    VerificationError
        The buffer does not decode to the mesh (a bug; never returned silently).

    Examples
    --------
    >>> import hammesh
    >>> m = hammesh.quality_mesh(hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]]), max_area=0.05)
    >>> s = encode(m)
    >>> s.n_triangles == m.n_triangles, s.indices_per_triangle < 2
    (True, True)
    """
    params.instance("mesh", mesh, (Mesh, HamiltonianMesh), "a hammesh.Mesh (e.g. hammesh.Mesh(points, triangles))")
    if join not in JOINS:
        raise InvalidOptionError(f"join must be one of {', '.join(JOINS)}, got {join!r}")
    if restart_index is not None:  # (an index buffer of uint32: the restart index is one too)
        restart_index = params.integer("restart_index", restart_index, low=0, high=2**32 - 1)
    if cache is not None:
        cache = params.integer("cache", cache, low=3, high=1 << 16, what="FIFO entries")
    reorder_vertices = params.flag("reorder_vertices", reorder_vertices)
    fast = params.flag("fast", fast)
    dual = None
    if cache is None and join == "restart" and restart_index is not None and method in ("auto", "greedy"):
        if not isinstance(mesh, HamiltonianMesh) and not reorder_vertices:
            if len(mesh.triangles) >= HALVES_FROM and threads.cores() >= 2:
                _load_ahead(fast)
                # the arrays as given: the halves' kernels check them as they first read them
                finish = None if fast else half_encoder(int(restart_index))
                halves = encode_in_halves(mesh.points, mesh.triangles, int(restart_index), verify, _SWAP_WEIGHT, finish)
                # few swaps (a structured grid, a smooth surface): the one-thread path
                # also tries the swap-free chains over the whole mesh (a 100k torus:
                # 1.0031 in one strip against the halves' 1.0063)
                if halves is not None and (fast or not _few_swaps(halves)):
                    return halves
    if fast and cache is None and join == "restart" and restart_index is not None and method in ("auto", "greedy"):
        if not isinstance(mesh, HamiltonianMesh):
            one_pass, dual = _greedy_in_one_pass(mesh, int(restart_index), verify, reorder_vertices)
            if one_pass is not None:
                return one_pass
    dual = dual_mesh(mesh) if dual is None else dual
    piece = PIECE_LENGTH
    if cache is not None and method == "auto":
        if dual.points.shape[1] == 2:
            # planar: the rows laid in bands (rows.band_layout): q30 meshes at FIFO 32 ACMR
            # 0.618-0.631 at 1.28-1.30 indices per triangle (meshoptimizer vcache + stripify 0.64 at 1.72)
            method = "rows"
        else:
            # surfaces: the swap-free chains in short pieces (cache.SHORT_PIECE_LENGTH)
            method, piece = "zigzag", SHORT_PIECE_LENGTH
    strip, order, starts = _cover_and_write(mesh, dual, method, cache, join, restart_index, fast, piece)
    rows = dual.triangles
    if reorder_vertices:
        strip, rows = _renumbered(strip, dual)
    if verify:
        verify_gl_strip(rows, strip.indices, strip.restart_index, order=order, split=_middle_restart(strip, order, starts))
    return replace(strip, defects=dual.defects, dropped=_dropped_rows(mesh, dual))


#: Modes (``fast``) whose two-halves kernels this process has started loading (:func:`_load_ahead`).
_LOADING: set = set()


def _load_ahead(fast: bool) -> None:
    """The first two-halves encoding of a mode in a process: its later kernels loaded on a
    thread (:func:`hammesh.strips.warm.prepare`) while the halves run their first steps.

    Why: numba loads each kernel from its disk cache on the kernel's first call, behind one
    lock; without this the halves wait for each load in turn as they reach it (~20-35 ms
    of a 1M-triangle first call in the fast mode, more in the default mode, which has more
    kernels).  The thread runs ahead on a small grid and loads them while the halves copy
    and pair the mesh.  Nothing happens after the first call of a mode (or after
    ``prepare``'s own thread was started by the caller: loading twice is waiting once).
    """
    if fast in _LOADING:
        return
    _LOADING.add(fast)
    from hammesh.strips.warm import prepare  # warm imports this module

    prepare(background=True, fast=fast)


def _cover_and_write(mesh, dual: DualMesh, method: str, cache, join: str, restart_index, fast: bool, piece=PIECE_LENGTH):
    """:func:`encode`'s paths and buffer for a checked mesh: ``(strip, order, starts)``, ``order``
    the input rows of ``dual`` in draw order (no proof, no renumbering)."""
    dual, tri, twin, local, starts, ids = _oriented_local(mesh, method, cache, dual=dual, improve=not fast, piece=piece)
    strip, order = _buffer(dual, tri, twin, local, starts, ids, join, restart_index)
    greedy = method == "greedy" or (cache is None and method == "auto" and not isinstance(mesh, HamiltonianMesh))
    few_swaps = _few_swaps(strip)
    rules: tuple = ()
    planar = dual.points.shape[1] == 2
    if fast:
        pass
    elif method == "zigzag":
        rules = (("zigzag", SHORTEST_CHAIN),)
    elif method == "rows":
        rules = (("rows", 1),)  # the other axis
    elif greedy and not is_forest(dual):
        # (a forest keeps Lemma 5.1's fewest strips) few swaps: a structured grid or a
        # smooth surface, whose swap-free rows the degree-first cover bends into L shapes
        # (one swap each); or a small mesh, where the two extra covers take ~1 ms: try the
        # swap-free chains both ways, keep the shortest buffer
        if few_swaps or strip.n_triangles <= _ZIGZAG_ALWAYS:
            rules = (("zigzag", LONGEST_CHAIN), ("zigzag", SHORTEST_CHAIN))
        if planar and cache is None and strip.n_triangles <= _ROWS_UP_TO:
            # planar meshes: the row cover along both axes (rows.py: 0.03-0.06 fewer
            # indices per triangle than the greedy cover on q30 meshes; two more covers
            # and end moves, ~2.5x the default's time).  Not with ``cache``: there the rows
            # are laid in bands (auto or method "rows"), a layout of their own
            rules += tuple(("rows", a) for a in range(len(ROW_AXES)))
    for alt_method, rule in rules:
        alt_paths = _oriented_local(mesh, alt_method, cache, dual, rule, piece=piece)
        alt, alt_order = _buffer(*alt_paths, join, restart_index)
        if len(alt.indices) < len(strip.indices):
            strip, order, starts = alt, alt_order, alt_paths[4]
    return strip, order, starts


def _few_swaps(strip: GLStrip) -> bool:
    """At most :data:`_ZIGZAG_TRIGGER` swaps per join or :data:`_ZIGZAG_SWAP_RATE` per triangle."""
    return strip.n_swaps <= max(_ZIGZAG_TRIGGER * (strip.n_strips - 1), _ZIGZAG_SWAP_RATE * strip.n_triangles)


def half_encoder(restart_index: int):
    """The default encoder for one half of :func:`~hammesh.strips.halves.encode_in_halves`:
    ``(points, rows, records, twin) -> (indices, order, n_strips, n_swaps)``."""

    def finish(pts, part, rec, twin):
        half = DualMesh(pts, part, twin, rec)
        strip, order, _ = _cover_and_write(half, half, "greedy", None, "restart", restart_index, False)
        return strip.indices, order, strip.n_strips, strip.n_swaps

    return finish


#: Swaps per path at or below which :func:`encode` also tries the swap-free chains
#: (:func:`~hammesh.strips._cover_kernels.zigzag_path_cover`).  Structured grids and
#: latitude-longitude spheres have ~1-3 (one per L-shaped path, some more at the poles:
#: pyvista's ``sphere.ply`` 2.8); quality meshes ~10.
_ZIGZAG_TRIGGER = 3

#: Meshes of at most this many triangles always try the swap-free chains too (two more
#: covers, ~1 ms): pyvista's ant 1.261 -> 1.243, nut 1.229 -> 1.222, globe 1.379 -> 1.358.
_ZIGZAG_ALWAYS = 5000

#: Covers of at most this many triangles (a half of the two-halves path counts its own:
#: meshes up to ~2 ``HALVES_FROM`` there) also try the row cover along each of
#: :data:`~hammesh.strips.rows.ROW_AXES` on planar meshes: 0.03-0.06 fewer indices per
#: triangle on q30 meshes for ~2.5x the default's time; above it the default keeps its
#: time (1M: 1.274 against 1.216 with the rows, for ~4.7x the time; ``method="rows"`` and
#: the CLI's ``auto`` try them at any size).
_ROWS_UP_TO = HALVES_FROM

#: ... or at most this many swaps per triangle (smooth surfaces: a torus 0.025 and 0.006,
#: where the chains joined by the end moves give 1.0083 and 1.0031 against the greedy
#: cover's 1.0250 and 1.0063; q30 planar meshes ~0.2, where they are not tried, to keep
#: the time: they would give 1.2649 instead of 1.2733 at 100k for ~1.7x the time, see
#: ``--method zigzag`` and the CLI's ``auto``).
_ZIGZAG_SWAP_RATE = 0.03


def _greedy_in_one_pass(mesh: MeshLike, R: int, verify: bool, reorder: bool) -> tuple[GLStrip | None, DualMesh]:
    """``encode(fast=True)`` with restarts: the greedy cover written as it is grown
    (:func:`~hammesh.strips._greedy_strip_kernels.greedy_strip_buffer`), its work arrays
    faulted in on a second thread while this one pairs the edges, the proof in two halves
    on two threads.  The same buffer as the three-pass path (a test compares).  A dual
    forest keeps Lemma 5.1's cover (``None``: take the three-pass path with ``dual``).
    """
    m = len(mesh.triangles)
    with ThreadPoolExecutor(1) as pool:
        work = pool.submit(strip_work, m, records_dtype(m, len(mesh.points))) if m >= _WORK_BESIDE_PAIRING else None
        dual = dual_mesh(mesh)
        work = None if work is None else work.result()
    if is_forest(dual):
        return None, dual
    rec = dual.cover_records()
    if work is None or len(work.order) != dual.n_triangles or work.bucket.dtype != rec.dtype:
        work = None  # rows repeating a vertex were dropped: sizes differ
    g = greedy_strip_buffer(rec, _SWAP_WEIGHT, R, work)
    S = len(g.starts) - 1
    if 0 <= R <= g.max_index and np.count_nonzero(g.indices == R) != S - 1:
        raise InvalidOptionError(f"restart index {R} is a vertex index of the mesh")
    strip = GLStrip(g.indices, R, dual.n_triangles, S, g.n_swaps)
    rows = dual.triangles
    if reorder:
        strip, rows = _renumbered(strip, dual)
    if verify:
        half = S // 2
        split = (int(g.index_starts[half]), int(g.starts[half])) if half > 0 and m >= PROOF_IN_TWO_PARTS else None
        verify_gl_strip(rows, strip.indices, R, order=g.order, split=split)
    return replace(strip, defects=dual.defects, dropped=_dropped_rows(mesh, dual)), dual


#: Triangles from which the round-trip proof runs in two halves on two threads
#: (:func:`~hammesh.strips.gl.verify_gl_strip`'s ``split``); below, a thread costs more
#: than half the proof (~0.4 ms at 10k triangles).
PROOF_IN_TWO_PARTS = 20_000


def _middle_restart(strip: GLStrip, order: np.ndarray, starts: np.ndarray) -> tuple[int, int] | None:
    """``(p, q)``: the buffer cut just after its middle restart index, and the rows drawn before it.

    ``None`` (one piece) for small or stitched buffers.  Every occurrence of the restart
    index is a restart for OpenGL, so the proof needs nothing else to decode the parts.
    """
    S = strip.n_strips
    if strip.restart_index is None or strip.n_triangles < PROOF_IN_TWO_PARTS or S < 2 or len(starts) != S + 1:
        return None
    cuts = np.flatnonzero(strip.indices == strip.restart_index)
    if len(cuts) != S - 1:
        return None
    half = S // 2
    return int(cuts[half - 1]) + 1, int(starts[half])


#: Triangles from which ``encode(fast=True)`` faults its work arrays in on a second thread.
_WORK_BESIDE_PAIRING = 50_000


def _renumbered(strip: GLStrip, dual: DualMesh) -> tuple[GLStrip, np.ndarray]:
    """``strip`` on vertices renumbered in order of first use, and the rows renumbered alike."""
    indices, vertex_order = _first_use_numbering(strip.indices, strip.restart_index, len(dual.points))
    new_id = np.empty_like(vertex_order)
    new_id[vertex_order] = np.arange(len(vertex_order))
    return replace(strip, indices=indices, vertex_order=vertex_order), new_id[dual.triangles]


def _buffer(dual, tri, twin, local, starts, ids, join, restart_index) -> tuple[GLStrip, np.ndarray]:
    """The GL buffer of paths ``local`` (rows of ``tri``) and the input rows in draw order."""
    order = local if ids is None else ids[local]
    if join == "restart" and restart_index is not None:
        return restart_strip(tri, twin, local, starts, restart_index), order
    turns = path_turns(dual.triangles, dual.twin, order, starts)
    return gl_strip_from_turns(turns, join=join, restart_index=restart_index), order


def _dropped_rows(mesh: MeshLike, dual: DualMesh) -> np.ndarray:
    """Input rows the strips leave out (those repeating a vertex)."""
    if dual.rows is None:
        return np.zeros(0, np.int64)
    keep = np.zeros(len(mesh.triangles), dtype=bool)
    keep[dual.rows] = True
    return np.flatnonzero(~keep)


def encode_generalized(mesh: MeshLike, *, method: str = "auto") -> GeneralizedStrips:
    """Generalized (IRIS GL) strips of ``mesh``: one vertex and one turn bit per triangle.

    Same paths as :func:`encode`; see :mod:`hammesh.strips.generalized`.
    """
    dual, turns = mesh_paths(mesh, method)
    return replace(generalized_from_turns(turns), defects=dual.defects, dropped=_dropped_rows(mesh, dual))
