"""Compiled kernels of the parallel path (one job each)."""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["area_sum", "edges_within_into", "label_pieces_into", "lattice_mark_inside_into", "lattice_clear_near_segments_into",
           "lattice_clear_near_points_into", "lattice_triangles_into", "lattice_mesh_into", "near_feature"]


@njit(cache=True, nogil=True)
def area_sum(points: np.ndarray, triangles: np.ndarray) -> float:
    """Sum of the triangles' signed areas (counter-clockwise positive), in one pass:
    numpy's three corner gathers cost ~0.35 s per 2M triangles, this ~10 ms."""
    total = 0.0
    for r in range(triangles.shape[0]):
        a, b, c = triangles[r, 0], triangles[r, 1], triangles[r, 2]
        total += (points[b, 0] - points[a, 0]) * (points[c, 1] - points[a, 1]) \
            - (points[b, 1] - points[a, 1]) * (points[c, 0] - points[a, 0])
    return 0.5 * total


@njit(cache=True, nogil=True)
def edges_within_into(triangles: np.ndarray, k: int, rows: np.ndarray, slots: np.ndarray) -> int:
    """Every row and slot ``s`` whose edge ``(s, s + 1)`` joins two points below ``k``
    (a tile's own points: its separator edges are among these), row by row; returns
    their number, ``rows``/``slots`` filled up to their length (the points below
    ``k`` span a planar graph: at most ``6 k`` such rows and slots). One pass over the
    rows instead of numpy's column copies and masks (~0.2 s per 9M-row incircle tile)."""
    count = 0
    for r in range(triangles.shape[0]):
        for s in range(3):
            if triangles[r, s] < k and triangles[r, (s + 1) % 3] < k:
                if count < rows.shape[0]:
                    rows[count] = r
                    slots[count] = s
                count += 1
    return count


@njit(cache=True, nogil=True)
def label_pieces_into(triangles: np.ndarray, neighbors: np.ndarray, segment_keys: np.ndarray,
                      on_segment: np.ndarray, label: np.ndarray, seeds: np.ndarray) -> int:
    """Label the dual components of a mesh cut at its segments (flood fill); returns
    their number ``k``, ``seeds[:k]`` the lowest triangle of each (component ``i``
    grows from ``seeds[i]``). ``neighbors[:, s]`` is across edge ``(s, s + 1)`` (-1: none);
    ``segment_keys``: sorted ``min * n + max`` of the segments' end points, ``n`` the
    number of points (``len(on_segment)``); only edges with both ends on a segment
    are looked up."""
    n = on_segment.shape[0]
    m = triangles.shape[0]
    label[:] = -1
    stack = np.empty(m, np.int64)
    count = 0
    for seed in range(m):
        if label[seed] >= 0:
            continue
        label[seed] = count
        seeds[count] = seed
        stack[0] = seed
        top = 1
        while top > 0:
            top -= 1
            t = stack[top]
            for e in range(3):
                nb = neighbors[t, e]
                if nb < 0 or label[nb] >= 0:
                    continue
                a = triangles[t, e]
                b = triangles[t, (e + 1) % 3]
                if on_segment[a] and on_segment[b]:
                    key = min(a, b) * n + max(a, b)
                    j = np.searchsorted(segment_keys, key)
                    if j < segment_keys.shape[0] and segment_keys[j] == key:
                        continue
                label[nb] = count
                stack[top] = nb
                top += 1
        count += 1
    return count


# --- the triangular lattice of a tile's interior (tile_mesh.lattice_points) -----------
# Point (i, j) of the lattice is (x0 + (i + (j & 1) / 2) h, y0 + j dy): rows dy apart,
# every other row shifted by half a step (equilateral triangles when dy = h sqrt(3) / 2).


@njit(cache=True, nogil=True)
def _edge_span(px: float, py: float, qx: float, qy: float, y: float, xl: float, xr: float) -> tuple[float, float]:
    """``[xl, xr]`` widened by where edge ``pq`` meets the line at height ``y`` (if it does)."""
    if not ((py <= y <= qy) or (qy <= y <= py)):
        return xl, xr
    if py == qy:
        return min(xl, min(px, qx)), max(xr, max(px, qx))
    x = px + (y - py) * (qx - px) / (qy - py)
    return min(xl, x), max(xr, x)


@njit(cache=True, nogil=True)
def lattice_mark_inside_into(x0: float, y0: float, h: float, dy: float, points: np.ndarray, triangles: np.ndarray,
                             keep: np.ndarray) -> None:
    """Set ``keep[j, i]`` for every lattice point inside (or on) one of the triangles:
    each triangle's rows, the row's span inside the triangle by its three edges."""
    ny, nx = keep.shape
    for r in range(triangles.shape[0]):
        ax, ay = points[triangles[r, 0], 0], points[triangles[r, 0], 1]
        bx, by = points[triangles[r, 1], 0], points[triangles[r, 1], 1]
        cx, cy = points[triangles[r, 2], 0], points[triangles[r, 2], 1]
        lo_y = min(ay, min(by, cy))
        hi_y = max(ay, max(by, cy))
        j0 = max(0, int(np.ceil((lo_y - y0) / dy)))
        j1 = min(ny - 1, int(np.floor((hi_y - y0) / dy)))
        for j in range(j0, j1 + 1):
            y = y0 + j * dy
            xl, xr = _edge_span(ax, ay, bx, by, y, np.inf, -np.inf)
            xl, xr = _edge_span(bx, by, cx, cy, y, xl, xr)
            xl, xr = _edge_span(cx, cy, ax, ay, y, xl, xr)
            if xl > xr:
                continue
            shift = x0 + 0.5 * h * (j & 1)
            i0 = max(0, int(np.ceil((xl - shift) / h)))
            i1 = min(nx - 1, int(np.floor((xr - shift) / h)))
            for i in range(i0, i1 + 1):
                keep[j, i] = True


@njit(cache=True, nogil=True)
def lattice_clear_near_segments_into(x0: float, y0: float, h: float, dy: float, points: np.ndarray,
                                     segments: np.ndarray, radius: np.ndarray, keep: np.ndarray) -> None:
    """Clear ``keep[j, i]`` for every lattice point closer than ``radius[s]`` to segment ``s``."""
    ny, nx = keep.shape
    for s in range(segments.shape[0]):
        ax, ay = points[segments[s, 0], 0], points[segments[s, 0], 1]
        bx, by = points[segments[s, 1], 0], points[segments[s, 1], 1]
        r = radius[s]
        ex, ey = bx - ax, by - ay
        ll = ex * ex + ey * ey
        j0 = max(0, int(np.floor((min(ay, by) - r - y0) / dy)))
        j1 = min(ny - 1, int(np.ceil((max(ay, by) + r - y0) / dy)))
        for j in range(j0, j1 + 1):
            y = y0 + j * dy
            shift = x0 + 0.5 * h * (j & 1)
            i0 = max(0, int(np.floor((min(ax, bx) - r - shift) / h)))
            i1 = min(nx - 1, int(np.ceil((max(ax, bx) + r - shift) / h)))
            for i in range(i0, i1 + 1):
                if not keep[j, i]:
                    continue
                x = shift + i * h
                t = 0.0 if ll == 0.0 else min(1.0, max(0.0, ((x - ax) * ex + (y - ay) * ey) / ll))
                dx, dyy = x - ax - t * ex, y - ay - t * ey
                if dx * dx + dyy * dyy < r * r:
                    keep[j, i] = False


@njit(cache=True, nogil=True)
def lattice_clear_near_points_into(x0: float, y0: float, h: float, dy: float, points: np.ndarray, radius: float,
                                   keep: np.ndarray) -> None:
    """Clear ``keep[j, i]`` for every lattice point closer than ``radius`` to one of ``points``."""
    ny, nx = keep.shape
    for s in range(points.shape[0]):
        px, py = points[s, 0], points[s, 1]
        j0 = max(0, int(np.floor((py - radius - y0) / dy)))
        j1 = min(ny - 1, int(np.ceil((py + radius - y0) / dy)))
        for j in range(j0, j1 + 1):
            y = y0 + j * dy
            shift = x0 + 0.5 * h * (j & 1)
            i0 = max(0, int(np.floor((px - radius - shift) / h)))
            i1 = min(nx - 1, int(np.ceil((px + radius - shift) / h)))
            for i in range(i0, i1 + 1):
                x = shift + i * h
                if (x - px) ** 2 + (y - py) ** 2 < radius * radius:
                    keep[j, i] = False


# --- the lattice's own triangles (tile_mesh: Triangle meshes only the band) ------------
# Strip j lies between rows j and j + 1; with o = j & 1 its cell i holds an "up"
# triangle (i, j), (i + 1, j), (i + o, j + 1) and a "down" triangle (i + 1 - o, j),
# (i + 1, j + 1), (i, j + 1), both counter-clockwise, each equilateral.


@njit(cache=True, nogil=True)
def lattice_triangles_into(keep: np.ndarray, block: int, blocks: np.ndarray, index: np.ndarray) -> int:
    """Number the lattice triangles whose three corners are kept: ``index[j, 2 i]``
    (up) and ``index[j, 2 i + 1]`` (down) of strip ``j`` cell ``i``, -1 where a corner
    is not kept; returns their number.

    Numbered block by block, ``block`` strips by ``block`` cells each, the blocks in the
    order ``blocks`` gives (``(k, 2)``: block row, block column; a Hilbert order of
    them), strip by strip inside a block: rows close on the curve are close in the
    tile. Strip by strip over the whole tile (a triangle's neighbours in the next strip
    ~2 nx rows away) the sparse ``hamiltonian()`` of the 6M demo's 3M-triangle tiles
    took 5.8-7.1 / 4.6-5.2 s CPU, with 2 x 2 blocks 4.1-4.2 / 3.9-4.9 s (1.5M demo:
    2.2-2.3 / 1.7-2.0 s against 1.75 / 1.5-1.6 s; same process, alternating, load 8)."""
    ny, nx = keep.shape
    index[:] = -1
    count = 0
    for b in range(blocks.shape[0]):
        bj, bi = blocks[b, 0] * block, blocks[b, 1] * block
        for j in range(bj, min(bj + block, ny - 1)):
            o = j & 1
            for i in range(bi, min(bi + block, nx - 1)):
                if keep[j, i] and keep[j, i + 1] and keep[j + 1, i + o]:
                    index[j, 2 * i] = count
                    count += 1
                if keep[j, i + 1 - o] and keep[j + 1, i + 1] and keep[j + 1, i]:
                    index[j, 2 * i + 1] = count
                    count += 1
    return count


@njit(cache=True, nogil=True)
def _lattice_at(index: np.ndarray, j: int, c: int) -> int:
    if j < 0 or j >= index.shape[0] or c < 0 or c >= index.shape[1]:
        return -1
    return index[j, c]


@njit(cache=True, nogil=True)
def lattice_mesh_into(index: np.ndarray, nx: int, corners: np.ndarray, neighbors: np.ndarray,
                      incident: np.ndarray) -> None:
    """The numbered lattice triangles (:func:`lattice_triangles_into`): their corners as
    grid ids ``j nx + i``, their neighbours among themselves (``neighbors[t, s]`` across
    edge ``(s, s + 1)``, -1 on the lattice's outline) and, per grid point, the number
    of triangles meeting it (6: an interior point).

    Neighbours, by the strip layout above: up ``s0`` -> down of strip ``j - 1`` cell
    ``i``, ``s1`` -> down ``(j, i + o)``, ``s2`` -> down ``(j, i - 1 + o)``; down ``s0`` ->
    up ``(j, i + 1 - o)``, ``s1`` -> up ``(j + 1, i)``, ``s2`` -> up ``(j, i - o)``."""
    incident[:] = 0
    for j in range(index.shape[0]):
        o = j & 1
        for i in range(index.shape[1] // 2):
            t = index[j, 2 * i]
            if t >= 0:
                a, b, c = j * nx + i, j * nx + i + 1, (j + 1) * nx + i + o
                corners[t, 0], corners[t, 1], corners[t, 2] = a, b, c
                incident[a] += 1
                incident[b] += 1
                incident[c] += 1
                neighbors[t, 0] = _lattice_at(index, j - 1, 2 * i + 1)
                neighbors[t, 1] = _lattice_at(index, j, 2 * (i + o) + 1)
                neighbors[t, 2] = _lattice_at(index, j, 2 * (i - 1 + o) + 1)
            t = index[j, 2 * i + 1]
            if t >= 0:
                a, b, c = j * nx + i + 1 - o, (j + 1) * nx + i + 1, (j + 1) * nx + i
                corners[t, 0], corners[t, 1], corners[t, 2] = a, b, c
                incident[a] += 1
                incident[b] += 1
                incident[c] += 1
                neighbors[t, 0] = _lattice_at(index, j, 2 * (i + 1 - o))
                neighbors[t, 1] = _lattice_at(index, j + 1, 2 * i)
                neighbors[t, 2] = _lattice_at(index, j, 2 * (i - o))


@njit(cache=True, nogil=True)
def near_feature(points: np.ndarray, order: np.ndarray, segments: np.ndarray, tol: float) -> tuple[int, int, int]:
    """The first pair of features closer than ``tol`` (in x and in y for two points):
    ``(0, i, j)`` two points (exact duplicates included), ``(1, i, s)`` point ``i`` and
    the inside of segment ``s`` (not one of its ends), ``(-1, -1, -1)`` none.

    ``order``: the points sorted by x, then y (``np.lexsort((y, x))``). Both searches
    go over the runs of equal x within ``tol`` (a segment's: its x-extent) and search
    each run by y: a lattice's points share their column's x, and a sweep over x alone
    would visit a whole column per point."""
    n = order.shape[0]
    xs = np.empty(n)
    ys = np.empty(n)
    for a in range(n):
        xs[a] = points[order[a], 0]
        ys[a] = points[order[a], 1]
    run_end = np.empty(n, np.int64)  # (the end of the run of equal x holding a)
    e = n
    for a in range(n - 1, -1, -1):
        if a + 1 < n and xs[a + 1] != xs[a]:
            e = a + 1
        run_end[a] = e
    for a in range(n):
        if a + 1 < run_end[a] and ys[a + 1] - ys[a] <= tol:
            return 0, order[a], order[a + 1]
        b = run_end[a]
        while b < n and xs[b] - xs[a] <= tol:
            e = run_end[b]
            k = b + np.searchsorted(ys[b:e], ys[a] - tol)
            if k < e and ys[k] <= ys[a] + tol:
                return 0, order[a], order[k]
            b = e
    for s in range(segments.shape[0]):
        p, q = segments[s, 0], segments[s, 1]
        if p < 0 or q < 0 or p >= points.shape[0] or q >= points.shape[0]:
            continue
        px, py, qx, qy = points[p, 0], points[p, 1], points[q, 0], points[q, 1]
        dx, dy = qx - px, qy - py
        length2 = dx * dx + dy * dy
        if length2 == 0.0:
            continue
        ylo, yhi = min(py, qy) - tol, max(py, qy) + tol
        b = np.searchsorted(xs, min(px, qx) - tol)  # (a run's start)
        while b < n and xs[b] <= max(px, qx) + tol:
            e = run_end[b]
            k = b + np.searchsorted(ys[b:e], ylo)
            while k < e and ys[k] <= yhi:
                i = order[k]
                k += 1
                if i == p or i == q:
                    continue
                t = ((points[i, 0] - px) * dx + (points[i, 1] - py) * dy) / length2
                if t <= 0.0 or t >= 1.0:
                    continue
                cross = (points[i, 0] - px) * dy - (points[i, 1] - py) * dx
                if cross * cross <= tol * tol * length2:
                    return 1, i, s
            b = e
    return -1, -1, -1
