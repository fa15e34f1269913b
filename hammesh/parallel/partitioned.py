"""Partitioned output: every worker writes its tile's piece; the driver writes the index.

The driver never holds the mesh: it gets the decomposition, the tiles' small border
summaries and, per piece, a file name and a few counts. What is certified, and by whom:

* each tile's Hamiltonian mesh passes the independent certificate against the tile's
  mesh (:func:`hammesh.hamiltonian`, on the worker): cycles closed, same domain and
  boundary, constrained edges kept, angles >= half the tile's input minimum;
* the tiles conform: every separator edge is held by exactly two tiles' triangles, in
  opposite directions (:func:`~hammesh.parallel.joins.plan_joins`), and the tiles'
  areas add up to the domain's (the coarse constrained triangulation's);
* the joins form a spanning forest of the tiles' cycles (one cycle per piece) and
  every triangle a join makes is checked on its worker (exact orientation, angle floor);

so the union is an edge-manifold triangulation of the domain (tiles glued along their
common boundary edges) whose rows, by ``global_position``, are one closed cycle per
piece. ``hammesh check DIR/mesh.pvtu`` re-verifies the stitched mesh independently
(it needs the whole mesh in memory).
"""

from __future__ import annotations

import heapq
import os
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from hammesh import params
from hammesh.domain import Domain
from hammesh.errors import InvalidOptionError, OutputError, VerificationError
from hammesh.io.tags import EDGE_MARKER, SEGMENT_EDGES, VERTEX_MARKER
from hammesh.partition import spread_parts
from hammesh.parallel.markers import given_at, point_markers
from hammesh.parallel.run import (decompose_estimate, default_tiles, domain_marks, finish_args, not_carried, on_holder,
                                  outcome_hamiltonian, progress_bar, run_tiles, since_start, task_clock)

__all__ = ["write_partitioned", "INDEX_NAME", "piece_name", "stretch_parts", "parts_per_cycle", "check_target", "is_output_file",
           "piece_types", "int_type", "marker_type", "lent_swaps", "spill_wanted", "HELD_BYTES_PER_TRIANGLE",
           "SPILL_SHARE"]

INDEX_NAME = "mesh.pvtu"

#: bytes a worker holds per triangle of a tile between its task and its piece: an
#: upper bound (the Hamiltonian mesh, incircle's three rows per triangle with parents,
#: kinds and attributes, and its points, is less than a tile task's peak, measured at
#: 350-400 B per triangle at 1.5M-triangle tiles, docs/scale.md "On a cluster")
HELD_BYTES_PER_TRIANGLE = 400
#: share of a worker's memory its held tiles may take before they go to spill files
SPILL_SHARE = 0.5


def spill_wanted(runner, n_workers: int, tiles: int, estimate: float) -> bool:
    """Whether each tile's Hamiltonian mesh waits for the join plan in a file instead
    of its worker's memory: when a worker would hold more tiles than fit in
    ``SPILL_SHARE`` of its memory (``HELD_BYTES_PER_TRIANGLE`` per triangle).

    Why not whenever a worker runs several tiles (before session 12): at 6M triangles
    the four balance tiles (:func:`~hammesh.parallel.run.default_tiles`) on two
    workers hold at most ~1.2 GB each, and pickling them to files and back is work on
    every tile's path that memory does not call for; at 100M (64 tiles, 32 per
    worker) they would hold ~20 GB each, and spill.
    Memory per worker: a running cluster's ``memory_limit`` (the smallest), else
    this machine's memory over the workers (a local cluster's default limit).
    """
    if tiles <= n_workers:
        return False
    held = -(-tiles // n_workers) * (float(estimate) / tiles) * HELD_BYTES_PER_TRIANGLE
    from hammesh.parallel.cluster import Starting

    limit = 0.0
    info = None if isinstance(runner, Starting) else getattr(runner, "scheduler_info", None)
    if info is not None:  # (a cluster of its own: what each worker may use)
        limits = [w.get("memory_limit") or 0 for w in info().get("workers", {}).values()]
        limit = float(min(limits)) if limits and min(limits) > 0 else 0.0
    if limit <= 0:
        try:
            import psutil

            limit = psutil.virtual_memory().total / max(1, n_workers)
        except ImportError:  # pragma: no cover - psutil comes with Dask
            return True
    return held > SPILL_SHARE * limit


def piece_name(tile: int) -> str:
    return f"piece_{tile:04d}.vtu"


def int_type(bound: int) -> str:
    """``Int32`` when every value is in ``[-1, bound)`` and ``bound`` fits, else ``Int64``."""
    return "Int32" if int(bound) < 2**31 else "Int64"


def piece_types(n_points: int, n_rows: int, n_parents: int, markers: np.ndarray | None = None) -> dict[str, str]:
    """VTK type of the pieces' integer point and cell data, the same in every piece
    (the index lists one type per array): 32-bit while the whole output's point ids,
    rows and parent rows fit, ``kind`` one byte (an index into ``KIND_NAMES``).
    ``markers`` (the segment markers, when the pieces hold the constrained edges):
    ``segment_edges`` one byte (six bits), ``edge_marker`` the narrowest type that
    holds them (:func:`marker_type`).

    Why: the pieces are our own format (``hammesh.read_mesh``/``hammesh check`` read
    any integer type) and their bytes are the write step's cost: with every integer
    array 64-bit an incircle row took ~81 bytes, with these ~52."""
    rows = int_type(n_rows)
    out = {"global_id": int_type(n_points), "global_position": rows, "cycle_id": rows, "cycle_position": rows,
           "part": rows, "parent": int_type(n_parents), "kind": "UInt8"}
    if markers is not None:
        out.update({SEGMENT_EDGES: "UInt8", EDGE_MARKER: marker_type(markers)})
    return out


def parts_per_cycle(components: np.ndarray, k: int) -> np.ndarray:
    """Parts given to each cycle: at least one each, the largest part as small as
    possible (the rule of :func:`hammesh.partition.partition`); 0 for cycles that go
    whole into a part when ``k`` is below the number of cycles (see :func:`stretch_parts`)."""
    lengths = np.asarray(components, np.int64)
    if k < len(lengths):
        return np.zeros(len(lengths), np.int64)
    return spread_parts(lengths, k)


def stretch_parts(position: np.ndarray, components: np.ndarray, k: int) -> np.ndarray:
    """Part of each row from its global cycle position alone: ``k`` balanced stretches
    of the cycles (``--parts`` with ``--partitioned``; every worker labels its own rows).

    A stretch of a Hamiltonian cycle is edge-connected, so every part is one connected
    piece, sizes within one triangle of each other per cycle. The stretches start at
    ``floor(j n / k)`` (what :func:`hammesh.partition.partition` does with shift 0: its
    search for the shift cutting fewest edges needs the whole mesh). With fewer parts
    than cycles, whole cycles go, largest first, to the lightest part.
    """
    lengths = np.asarray(components, np.int64)
    ends = np.cumsum(lengths)
    cyc = np.searchsorted(ends, position, side="right")
    cpos = position - (ends - lengths)[cyc]
    per = parts_per_cycle(lengths, k)
    if k >= len(lengths):
        base = np.concatenate([[0], np.cumsum(per)[:-1]])
        return base[cyc] + ((cpos + 1) * per[cyc] - 1) // lengths[cyc]
    owner = np.zeros(len(lengths), np.int64)
    load = [(0, j) for j in range(k)]
    for r in np.argsort(-lengths, kind="stable").tolist():
        w, j = heapq.heappop(load)
        owner[r] = j
        heapq.heappush(load, (w + int(lengths[r]), j))
    return owner[cyc]


def marker_type(markers: np.ndarray) -> str:
    """The narrowest signed VTK integer type holding every value of ``markers`` (the
    pieces' ``edge_marker``: almost all zeros, three per row, so its width is most of
    what the constrained edges add to a piece's bytes)."""
    mk = np.asarray(markers, dtype=np.int64).reshape(-1)
    lo, hi = (int(mk.min()), int(mk.max())) if len(mk) else (0, 0)
    for name, bits in (("Int8", 8), ("Int16", 16), ("Int32", 32)):
        if -(1 << (bits - 1)) <= lo and hi < (1 << (bits - 1)):
            return name
    return "Int64"


def _removed_rows(args: tuple) -> np.ndarray:
    """The tile's rows its joins replace (sorted)."""
    tile, joins = args[1], args[4]
    return np.array(sorted({j.t_row for j in joins if j.t_tile == tile} | {j.u_row for j in joins if j.u_tile == tile}),
                    np.int64)


def _lent_rows(args: tuple) -> np.ndarray:
    """The tile's rows that are the far side ``u`` of a swap whose triangles another
    tile's piece holds (its edges ``a d`` and ``d b`` go there: ``A1 = a d c``, ``A2 = d b c``)."""
    tile = args[1]
    return np.array(sorted({j.u_row for j in args[4] if j.swap and j.u_tile == tile and j.t_tile != tile}), np.int64)


def _global_ids(args: tuple, local: np.ndarray) -> np.ndarray:
    """Global ids of a tile's local points (as :func:`~hammesh.parallel.joins.piece_layout` numbers them)."""
    tile, mesh_offset, n_mesh, ham_offset = args[0], args[5], args[6], args[7]
    z = np.asarray(local, np.int64)
    k = len(tile.vertex_ids)
    return np.where(z < k, tile.vertex_ids[np.minimum(z, max(k - 1, 0))] if k else 0,
                    np.where(z < n_mesh, mesh_offset + z - k, ham_offset + z - n_mesh))


def _lent_edges(outcome, args: tuple) -> dict:
    """On the worker of a tile ``U``: the constrained edges of its swap rows ``u`` that
    no row of its own piece will hold (``u``'s edges ``a d``, ``d b`` go to the other
    tile's rows ``A1``, ``A2``; another of ``U``'s rows, or its join rows, may hold
    them too, and then ``U``'s piece flags them). ``{join index: [(first, second,
    marker), ...]}``, global ids in the segment's direction; an edge two such swaps
    share goes to the one of lower index. The segments are few: the scan of the
    rows is made only for those that are constrained edges."""
    h = outcome_hamiltonian(outcome, drop_spill=False)
    tile = args[1]
    lent = _lent_rows(args)
    out: dict[int, list] = {}
    if not len(lent):
        return out
    tri = np.asarray(h.triangles, dtype=np.int64)
    seg = np.asarray(h.segments, dtype=np.int64).reshape(-1, 2)
    mk = np.asarray(h.segment_markers, dtype=np.int64).reshape(-1)
    g = _global_ids(args, seg)
    sep = np.isin(np.sort(g, axis=1) @ np.array([args[11], 1]), args[10])
    seg, mk, g = seg[~sep], mk[~sep], g[~sep]
    row_join = {j.u_row: j.index for j in args[4] if j.swap and j.u_tile == tile and j.t_tile != tile}
    for r in lent.tolist():
        for k in range(3):
            p, q = int(tri[r, k]), int(tri[r, (k + 1) % 3])
            hit = np.flatnonzero(((seg[:, 0] == p) & (seg[:, 1] == q)) | ((seg[:, 0] == q) & (seg[:, 1] == p)))
            if not len(hit):
                continue
            holders = np.flatnonzero((tri == p).any(axis=1) & (tri == q).any(axis=1))
            if not np.isin(holders, lent).all():
                continue  # (another row of U: U's piece holds it)
            if row_join[r] != min(row_join[int(x)] for x in holders):
                continue
            s = int(hit[0])
            out.setdefault(row_join[r], []).append((int(g[s, 0]), int(g[s, 1]), int(mk[s])))
    return out


def _edge_entries(h, lay, args: tuple, lent_joins, lent: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The piece's constrained edges as sparse per-row fields: ``(keys, flags,
    markers (k, 3))`` for the rows holding one (key: a tile row ``r``, or ``m + k`` for
    join row ``k``), in :func:`hammesh.io.tags.edge_fields`' encoding: each edge once in
    the whole output, with its direction.

    Each of the tile's constrained edges (its separators left out: interior edges of
    the union) goes to the row :func:`~hammesh.io.tags.segment_slots` picks (the one
    in which it runs forwards), else to the other row holding it when a join replaced
    the first, else to the join row that now holds it (a join's new rows keep the
    replaced triangles' other edges), else it is the far side of a swap the other
    tile's piece holds (``lent_joins``: the swaps the driver asked about; anything else
    is an internal error, never a silent loss). ``lent``: the edges other tiles lend
    to this piece's swap rows (:func:`_lent_edges`).
    """
    from hammesh.io.tags import segment_slots

    tri = np.asarray(h.triangles, dtype=np.int64)
    m = len(tri)
    seg = np.asarray(lay.local_segments, dtype=np.int64).reshape(-1, 2)
    gseg = np.asarray(lay.segments, dtype=np.int64).reshape(-1, 2)
    mk = np.asarray(lay.segment_markers, dtype=np.int64).reshape(-1)
    slots = segment_slots(tri, seg)
    if slots is None:
        raise VerificationError(f"tile {args[1]}: its constrained edges are not edges of its triangles once each")
    removed = np.zeros(m + 1, bool)
    removed[_removed_rows(args)] = True
    slot, other = slots.slot.copy(), slots.other
    moved = removed[slot // 3]
    use_other = moved & (other >= 0) & ~removed[np.where(other >= 0, other // 3, m)]
    slot[use_other] = other[use_other]
    keys = slot // 3
    corner = tri.reshape(-1)[slot]
    backwards = corner != seg[:, 0]
    at = slot % 3
    placed = ~(moved & ~use_other)
    keys, at = keys.astype(np.int64), at.astype(np.int64)
    extra_k, extra_at, extra_back, extra_mk = [], [], [], []
    gj = lay.point_ids[lay.join_triangles] if len(lay.join_triangles) else np.zeros((0, 3), np.int64)

    def find_in_joins(first: int, second: int):
        for c in range(3):
            fwd = np.flatnonzero((gj[:, c] == first) & (gj[:, (c + 1) % 3] == second))
            if len(fwd):
                return int(fwd[0]), c, False
            bwd = np.flatnonzero((gj[:, c] == second) & (gj[:, (c + 1) % 3] == first))
            if len(bwd):
                return int(bwd[0]), c, True
        return None

    lent_rows = {j.u_row for j in args[4] if j.index in lent_joins and j.u_tile == args[1]}
    for i in np.flatnonzero(~placed).tolist():
        got = find_in_joins(int(gseg[i, 0]), int(gseg[i, 1]))
        if got is None:
            rows = {int(slots.slot[i] // 3)} | ({int(other[i] // 3)} if other[i] >= 0 else set())
            if not rows <= lent_rows:
                raise VerificationError(f"tile {args[1]}: constrained edge {gseg[i].tolist()} is held by no row "
                                        "of its piece")
            continue  # (the other tile's piece flags it: _lent_edges)
        extra_k.append(m + got[0])
        extra_at.append(got[1])
        extra_back.append(got[2])
        extra_mk.append(mk[i])
    mine = {j.index for j in args[4] if j.t_tile == args[1]}
    for edges in lent:
        for ji, items in edges.items():
            if ji not in mine:
                continue  # (its own, lent away: passed to order the spill file's reads)
            for first, second, marker in items:
                got = find_in_joins(first, second)
                if got is None:
                    raise VerificationError(f"tile {args[1]}: the swap of join {ji} holds no edge "
                                            f"{[first, second]}")
                extra_k.append(m + got[0])
                extra_at.append(got[1])
                extra_back.append(got[2])
                extra_mk.append(marker)
    keys = np.concatenate([keys[placed], np.asarray(extra_k, np.int64)])
    at = np.concatenate([at[placed], np.asarray(extra_at, np.int64)])
    backwards = np.concatenate([backwards[placed], np.asarray(extra_back, bool)])
    marker = np.concatenate([mk[placed], np.asarray(extra_mk, np.int64)])
    uk, inv = np.unique(keys, return_inverse=True)
    flags = np.zeros(len(uk), np.int64)
    np.add.at(flags, inv, (1 << at) + (backwards.astype(np.int64) << (at + 3)))  # (distinct slots: + is |)
    marks = np.zeros((len(uk), 3), np.int64)
    marks[inv, at] = marker
    return uk, flags, marks


def _finish_and_write(outcome, args: tuple, path: str, components: np.ndarray, parts: int | None,
                      types: dict[str, str] | None = None, marks: tuple | None = None, edges=None, *lent: dict):
    """On the tile's worker: number its rows globally (its side of the joins), write its
    piece. Returns ``(file name, rows, first global position, attribute width, part sizes)``.

    The piece is written chunk by chunk straight from the tile's Hamiltonian mesh in
    the order :func:`~hammesh.parallel.joins.piece_layout` plans (runs of its cycle,
    forward or backward, and the join rows): no gathered copy of the rows is made
    (at millions of rows such copies, fresh memory each, were most of the finish and
    write steps). The bytes are :func:`~hammesh.io.pvtu.write_piece`'s.
    ``marks``: the input vertices' nonzero markers (:func:`~hammesh.parallel.run.domain_marks`):
    the piece's points get a ``vertex_marker`` array as the serial path's output
    (:func:`~hammesh.parallel.markers.point_markers`); None: none written.
    ``edges``: None, no constrained edges written; else the joins whose far swap side
    this tile lends (:func:`_lent_edges`, asked by the driver) and ``lent`` the edges
    other tiles lend to it: the piece gets ``segment_edges`` and ``edge_marker`` as the
    serial ``.vtu`` (:func:`hammesh.io.tags.edge_fields`), from :func:`_edge_entries`'
    few rows (every other row zeros: one reused buffer, no per-row array made).
    """
    from hammesh.io.pvtu import VTK_TRIANGLE, write_raw_chunks
    from hammesh.parallel.joins import CHUNK_ROWS, piece_layout

    e0, t0, c0 = time.time(), time.perf_counter(), time.process_time()
    h = outcome_hamiltonian(outcome)
    lay = piece_layout(h, *args)
    t1, c1 = time.perf_counter(), time.process_time()
    m, n, w = len(h.triangles), len(h.points), lay.join_attributes.shape[1]
    tri = np.asarray(h.triangles, dtype=np.int64)
    attrs = np.asarray(h.triangle_attributes, dtype=np.float64).reshape(m, w)
    parent, kind, off = np.asarray(h.parent, dtype=np.int64), np.asarray(h.kind), lay.triangle_offset
    renum = None if lay.keep is None else np.cumsum(lay.keep) - 1
    spans = [(g, r, len(range(*r.indices(m))) if isinstance(r, slice) else 1) for g, r in lay.chunks()]
    ends = np.cumsum(components)
    sizes = None if parts is None else np.zeros(parts, np.int64)

    def rows(values, joins, own=None, both=None):
        """Chunks of a per-row array in piece order (``own`` applied to the tile's
        rows, ``both`` to every chunk)."""
        def gen():
            for _, r, _ in spans:
                c = (values[r] if own is None else own(values[r])) if isinstance(r, slice) else joins[r:r + 1]
                yield c if both is None else both(c)
        return gen

    def by_position(fn):
        def gen():
            for g, _, c in spans:
                yield fn(g + np.arange(c, dtype=np.int64))
        return gen

    def global_parent(p):
        p = p + off
        p[p < off] = -1  # -1 (no parent) stays -1
        return p

    def cycle_id(pos):
        return np.searchsorted(ends, pos, side="right")

    def cycle_position(pos):
        return pos - (ends - components)[cycle_id(pos)]

    def part_of(pos):
        part = stretch_parts(pos, components, parts)
        sizes[:] += np.bincount(part, minlength=parts)
        return part

    keep = lay.keep
    n_points = len(lay.point_ids) if keep is None else int(keep.sum())

    def points(ids: bool):
        def gen():
            for src, base in ((h.points, 0), (lay.join_points, n)):
                for a in range(0, len(src), CHUNK_ROWS):
                    b = min(a + CHUNK_ROWS, len(src))
                    if ids:
                        c = lay.point_ids[base + a:base + b]
                    else:
                        c = np.zeros((b - a, 3))
                        c[:, :2] = src[a:b]
                    yield c if keep is None else c[keep[base + a:base + b]]
        return gen

    def cells(fn):
        def gen():
            for a in range(0, lay.n_rows, CHUNK_ROWS):
                yield fn(a, min(a + CHUNK_ROWS, lay.n_rows))
        return gen

    mr = lay.n_rows
    ty = types or {}
    # (the piece's own point indices and offsets; without ``types`` all Int64, write_piece's bytes)
    local = int_type(max(n_points, 3 * mr + 1)) if types else "Int64"
    arrays = [("PointData", "global_id", ty.get("global_id", "Int64"), 1, n_points, points(True)),
              ("CellData", "global_position", ty.get("global_position", "Int64"), 1, mr, by_position(lambda pos: pos)),
              ("CellData", "parent", ty.get("parent", "Int64"), 1, mr, rows(parent, lay.join_parent, own=global_parent)),
              ("CellData", "kind", ty.get("kind", "Int64"), 1, mr, rows(kind, lay.join_kind))]
    if marks is not None:
        vm = point_markers(len(lay.point_ids), lay.local_segments, lay.segment_markers,
                           given_at(lay.point_ids, len(args[0].vertex_ids), marks))
        vm = vm if keep is None else vm[keep]
        arrays.insert(1, ("PointData", VERTEX_MARKER, "Int32", 1, n_points, lambda: iter([vm.astype(np.int32)])))
    if len(components) > 1:  # (one cycle: all zeros and global_position again, not written)
        arrays[2:2] = [("CellData", "cycle_id", ty.get("cycle_id", "Int64"), 1, mr, by_position(cycle_id)),
                       ("CellData", "cycle_position", ty.get("cycle_position", "Int64"), 1, mr,
                        by_position(cycle_position))]
    if parts is not None:
        arrays.append(("CellData", "part", ty.get("part", "Int64"), 1, mr, by_position(part_of)))
    if edges is not None:
        ekey, eflag, emark = _edge_entries(h, lay, args, edges, lent)
        widest = max((c for _, _, c in spans), default=1)

        def sparse_rows(values: np.ndarray, width: int):
            """A per-row field that is zero but on the rows ``ekey`` (``values``), in piece order."""
            def gen():
                zero = np.zeros((widest, width), values.dtype)
                for _, r, c in spans:
                    if isinstance(r, slice):
                        start, _, step = r.indices(m)
                        lo, hi = (start, start + c) if step == 1 else (start - c + 1, start + 1)
                    else:
                        lo = hi = m + r
                        hi += 1
                    i0, i1 = np.searchsorted(ekey, (lo, hi))
                    if i0 == i1:
                        yield zero[:c]
                        continue
                    out = np.zeros((c, width), values.dtype)
                    forward = not isinstance(r, slice) or step == 1
                    out[(ekey[i0:i1] - lo) if forward else (start - ekey[i0:i1])] = values[i0:i1]
                    yield out
            return gen

        arrays += [("CellData", SEGMENT_EDGES, ty.get(SEGMENT_EDGES, "Int64"), 1, mr, sparse_rows(eflag[:, None], 1)),
                   ("CellData", EDGE_MARKER, ty.get(EDGE_MARKER, "Int64"), 3, 3 * mr, sparse_rows(emark, 3))]
    arrays += [("CellData", f"attribute_{i}", "Float64", 1, mr, rows(attrs[:, i], lay.join_attributes[:, i]))
               for i in range(w)]
    arrays += [("Points", "", "Float64", 3, 3 * n_points, points(False)),
               ("Cells", "connectivity", local, 1, 3 * mr,
                rows(tri, lay.join_triangles, both=None if renum is None else renum.__getitem__)),
               ("Cells", "offsets", local, 1, mr, cells(lambda a, b: 3 * np.arange(a + 1, b + 1, dtype=np.int64))),
               ("Cells", "types", "UInt8", 1, mr, cells(lambda a, b: np.full(b - a, VTK_TRIANGLE, np.uint8)))]
    write_raw_chunks(path, arrays, n_points, mr)
    first = int(lay.items[0][0]) if lay.items else -1
    return (Path(path).name, mr, first, w, sizes,
            {"finish": t1 - t0, "write": time.perf_counter() - t1, "cpu_finish": c1 - c0,
             "cpu_write": time.process_time() - c1, "clock": (e0, time.time(), os.getpid())})


def lent_swaps(tiled) -> dict[int, tuple[int, int]]:
    """The swaps whose far side ``u`` may lend a constrained edge to the other tile's
    piece (:func:`_lent_edges`): ``{join index: (u tile, t tile)}``.

    Asked only where it can happen: a constrained edge ``a d`` or ``d b`` of ``u = b a
    d`` (``ab`` on a separator, ``d`` off its line) is a piece of a user segment
    through ``a`` or ``b``, and a separator's end on a user segment is where the cut
    crossed it, an end of the segment's pieces (:func:`~hammesh.parallel.tiles.decompose`
    cuts them there). Few: most joins' ends are on no user segment, and then no task
    is made. A piece that nevertheless finds such an edge not asked about stops with
    an internal error (:func:`_edge_entries`), never drops it."""
    d = tiled.decomposition
    ends = np.unique(np.asarray(d.segments, np.int64)[~np.asarray(d.separator, bool)])
    out = {}
    for j in tiled.plan.joins:
        if j.swap and j.u_tile != j.t_tile and np.isin([j.a, j.b], ends).any():
            out[j.index] = (j.u_tile, j.t_tile)
    return out


def apex_marks(tiled, args: tuple, marks: tuple | None) -> tuple | None:
    """``marks`` (the input's nonzero vertex markers) plus the markers of the swap
    apexes this tile's piece takes from the other tile (``args``: its
    :func:`~hammesh.parallel.run.finish_args`): such a point is on none of this piece's
    constrained edges, so its marker comes from the tile that holds them (the border
    rows' ``z_mark``), and both pieces give it the same."""
    if marks is None:
        return None
    ids, values = [marks[0]], [marks[1]]
    for ji, (gid, _) in (args[12] or {}).items():
        j = tiled.plan.joins[ji]
        bu = tiled.borders[j.u_tile]
        mark = int(bu.z_mark[int(np.flatnonzero(bu.row == j.u_row)[0])]) if bu.z_mark is not None else 0
        if mark and gid not in set(marks[0].tolist()):
            ids.append(np.array([gid], np.int64))
            values.append(np.array([mark], np.int64))
    return np.concatenate(ids), np.concatenate(values)


def check_target(out: Path, *, force: bool = False, inputs: tuple = ()) -> None:
    """Refuse an output directory that is a file, holds an input, or is not empty
    (unless ``force`` and it holds an earlier partitioned output and nothing else: then
    that is replaced once the new one is complete). The current directory or one above
    it is never replaced (it cannot be renamed away; the run would fail at its end)."""
    if out.exists() and not out.is_dir():
        raise OutputError(f"{out}: --partitioned writes a directory; this is a file")
    target = out.resolve()
    for p in inputs:
        q = Path(p).resolve()
        if q == target or target in q.parents:
            raise OutputError(f"{out}: holds the input {p}; choose another output directory")
    if not (out.is_dir() and any(out.iterdir())):
        return
    if not force:
        raise OutputError(f"{out}: directory exists and is not empty (--force replaces an earlier "
                          "partitioned output)")
    cwd = Path.cwd().resolve()
    if target == cwd or target in cwd.parents:
        raise OutputError(f"{out}: is the current directory or holds it; --force cannot replace it")
    foreign = sorted(p.name for p in out.iterdir() if not is_output_file(p))
    if foreign:
        raise OutputError(f"{out}: holds {foreign[0]!r}{f' and {len(foreign) - 1} more' if len(foreign) > 1 else ''}, "
                          "not an earlier partitioned output; --force replaces only mesh.pvtu and piece_*.vtu")


def is_output_file(path: Path) -> bool:
    """A file a partitioned output holds: the index or a piece (what ``--force`` may replace)."""
    import re

    return path.is_file() and not path.is_symlink() and (
        path.name == INDEX_NAME or re.fullmatch(r"piece_\d{4,}\.vtu", path.name) is not None)


def write_partitioned(domain: Domain, directory: str | os.PathLike[str], *, min_angle: float | None = None,
                      max_area: float, tiles: int | None = None, workers: int | None = None, client=None,
                      scheduler: str | None = None, mode: str = "sparse", keep: float = 0.9,
                      parts: int | None = None, force: bool = False, inputs: tuple = (),
                      progress: bool = False, lattice: bool = True, tree: str = "quadtree") -> dict:
    """Mesh ``domain`` on the tiles and write ``DIRECTORY/mesh.pvtu`` + one ``.vtu`` per tile.

    Everything is written into a fresh directory beside ``DIRECTORY`` and renamed onto it
    when complete: a failed or interrupted run leaves nothing behind, and no stale piece
    of an earlier run survives. An existing non-empty ``DIRECTORY`` is refused unless
    ``force`` (then replaced); one holding an ``inputs`` path always.

    ``parts``: a ``part`` cell array of ``parts`` balanced stretches of the cycle
    (:func:`stretch_parts`); the report gains ``"partition"`` (sizes, imbalance).
    ``lattice``: as :func:`~hammesh.parallel.run.parallel_hamiltonian` (``False``: no
    interior lattice, each tile Triangle's own run). ``tree``: incircle mode's spanning
    tree in every tile (:func:`hammesh.hamiltonian`).

    Returns the report (counts, seconds, ``index`` path). Pieces are written by the
    worker that made them; the index lists them in the order the cycle enters them.
    """
    from hammesh.io.pvtu import write_index
    from hammesh.parallel.cluster import runner_for

    out = Path(directory)
    check_target(out, force=force, inputs=inputs)
    if parts is not None and (isinstance(parts, bool) or not isinstance(parts, (int, np.integer)) or parts < 1):
        raise InvalidOptionError(f"parts must be a positive integer, got {parts!r}")
    lattice = params.flag("lattice", lattice)
    t0 = time.perf_counter()
    parent = out.absolute().parent
    made = [d for d in [parent, *parent.parents] if not d.exists()]
    parent.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".partial", dir=parent))
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(work, 0o777 & ~umask)  # mkdtemp's 0700 would become the output's mode
    spill = work / ".spill"
    try:
        with runner_for(workers=workers, client=client, scheduler=scheduler, mode=mode,
                        background=True) as (runner, n_workers):
            estimate = decompose_estimate(domain, min_angle, max_area)
            if tiles is None:
                tiles = default_tiles(estimate, n_workers)
            # workers whose tiles would not fit in memory keep none until the plan
            spill_dir = None
            if spill_wanted(runner, n_workers, tiles, estimate):
                spill.mkdir()
                spill_dir = spill
            tiled = run_tiles(domain, min_angle=min_angle, max_area=max_area, tiles=tiles, runner=runner,
                              mode=mode, keep=keep, progress=progress_bar(progress, 2), spill_dir=spill_dir,
                              lattice=lattice, tree=tree)
            comps = tiled.plan.components
            if parts is not None and parts > int(comps.sum()):
                raise InvalidOptionError(f"--parts {parts}: more parts than the {int(comps.sum()):,} triangles")
            t1 = time.perf_counter()
            fargs = finish_args(tiled)
            d = tiled.decomposition
            # the constrained edges (the serial path writes them when the domain has segments)
            edges = bool(len(domain.segments))
            types = piece_types(max((a[11] for a in fargs), default=0), int(comps.sum()),
                                int(tiled.mesh_triangles.sum()), d.segment_markers[~d.separator] if edges else None)
            marks = domain_marks(domain)
            # (the serial path writes the markers when any is nonzero: any input vertex's or segment's)
            if not (len(marks[0]) or np.any(tiled.decomposition.segment_markers != 0)):
                marks = None
            asked = lent_swaps(tiled) if edges else {}
            # (a swap's far side lends its constrained edges: a small task on its tile's
            # worker, whose result goes to the other tile's task, not through the driver)
            lenders = sorted({u for u, _ in asked.values()})
            lent = {u: runner.submit(_lent_edges, tiled.outcomes[u], fargs[u], pure=False, priority=1,
                                     **on_holder(runner, tiled.outcomes[u])) for u in lenders}

            def lending(i: int) -> tuple:
                """Tile ``i``'s swaps asked about (None: no edges written) and the lending
                tasks it waits for (the ones lending to it, and its own: its spill file is
                read by both)."""
                own = None if not edges else frozenset(ji for ji, (u, _) in asked.items() if u == i)
                return own, *[lent[u] for u in sorted({u for u, t in asked.values() if i in (t, u)})]

            done = runner.gather([runner.submit(_finish_and_write, h, a, str(work / piece_name(i)), comps, parts,
                                                types, apex_marks(tiled, a, marks), *lending(i),
                                                pure=False, **on_holder(runner, h))
                                  for i, (h, a) in enumerate(zip(tiled.outcomes, fargs))])
            t2 = time.perf_counter()
            worker_rss = peak_rss_workers(runner)
        order = sorted(range(len(done)), key=lambda i: done[i][2])
        width = max(x[3] for x in done)
        write_index(work / INDEX_NAME, [done[i][0] for i in order if done[i][1] > 0], width,
                    cycles=len(comps) > 1, part=parts is not None, types=types,
                    cell_arrays=None if not edges else {SEGMENT_EDGES: (types[SEGMENT_EDGES], 1),
                                                        EDGE_MARKER: (types[EDGE_MARKER], 3),
                                                        **{f"attribute_{i}": ("Float64", 1) for i in range(width)}},
                    point_arrays=None if marks is None else {VERTEX_MARKER: ("Int32", 1)})
        for i, d in enumerate(done):
            if d[1] == 0:
                (work / d[0]).unlink()
        if spill.exists():
            shutil.rmtree(spill)
        _replace_dir(work, out)
    except BaseException:
        shutil.rmtree(work, ignore_errors=True)
        for d in made:  # parents this call created, innermost first
            try:
                d.rmdir()
            except OSError:
                break
        raise
    t3 = time.perf_counter()
    d = tiled.decomposition
    report = {
        "index": str(out / INDEX_NAME), "pieces": sum(x[1] > 0 for x in done), "triangles": int(sum(x[1] for x in done)),
        "components": comps.tolist(), "verified": True,
        "parallel": {"tiles": d.n_tiles, "workers": n_workers, "repair_rounds": tiled.rounds,
                     "lattice": lattice, "tree": tree,
                     "joins": len(tiled.plan.joins),
                     "join_swaps": sum(j.swap for j in tiled.plan.joins),
                     "joins_not_whole": tiled.plan.fallback_joins, "tile_cycles": tiled.plan.nodes,
                     "pieces": tiled.plan.pieces, "estimate": d.estimate,
                     "mesh_triangles": int(tiled.mesh_triangles.sum()), "spilled": spill_dir is not None,
                     "seconds": {**tiled.seconds, "pieces": t2 - t1, "index": t3 - t2, "total": t3 - t0},
                     "tile_seconds": {**tiled.tile_seconds,
                                      **{k: sum(x[5][k] for x in done)
                                         for k in ("finish", "write", "cpu_finish", "cpu_write")}},
                     "tile_steps": [{**st, **{k: v for k, v in x[5].items() if k != "clock"},
                                     "piece_at": task_clock(x[5]["clock"], "piece_at")["piece_at"]}
                                    for st, x in zip(tiled.tile_steps, done)],
                     "since_start": {**tiled.since_start, "end": since_start()},
                     "tail_threads": tiled.tail_threads,
                     "driver_cpu": {**tiled.driver_cpu, "end": time.process_time()},
                     "peak_rss_mb": {"driver": peak_rss_mb(), "workers": worker_rss}},
    }
    if not_carried(domain):
        report["not_carried"] = not_carried(domain)
    if parts is not None:
        sizes = np.sum([x[4] for x in done], axis=0)
        report["partition"] = {"k": int(parts), "scheme": "cycle stretches (shift 0)",
                               "size_min": int(sizes.min()), "size_max": int(sizes.max()),
                               "imbalance": float(sizes.max() * parts / sizes.sum())}
    return report


def _replace_dir(work: Path, out: Path) -> None:
    """Rename the finished ``work`` onto ``out``; an existing ``out`` (empty, or
    ``--force``) is moved aside first and removed after."""
    if not out.exists():
        os.rename(work, out)
        return
    old = Path(tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".old", dir=work.parent))
    old.rmdir()
    os.rename(out, old)
    try:
        os.rename(work, out)
    except BaseException:
        os.rename(old, out)  # put the old content back
        raise
    shutil.rmtree(old, ignore_errors=True)


def peak_rss_mb() -> float:
    """This process's peak resident set size (MB; Linux reports kB)."""
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def peak_rss_workers(runner) -> list[float]:
    """Every Dask worker's peak RSS (MB); [] when the tiles ran in this process."""
    run = getattr(runner, "run", None)
    if run is None:
        return []
    return sorted(float(v) for v in run(peak_rss_mb).values())
