"""Shared test support: meshes and domains built by hand, and independent re-checks.

The one module test files share (no test module imports another): hand-built
Hamiltonian meshes (``fan``, ``hand_hamiltonian``; the ``hexagon``/``two_cycles``
fixtures in ``tests/conftest.py``), grids, Triangle's bundled domains, random PSLGs
(hypothesis), meshes with a bad edge, and re-checks of outputs in pure numpy /
networkx, which deliberately do not call hammesh's numba kernels, so that a bug
there cannot hide itself in a test.
"""

from __future__ import annotations

import numpy as np
import triangle
from hypothesis import strategies as st

import hammesh
from hammesh.mesh import HamiltonianMesh, Mesh

#: Meshes with a bad edge: used twice in one direction, or by three triangles.
BAD_EDGES = [
    [[0, 1, 2], [0, 1, 3]],
    [[0, 1, 2], [1, 0, 3], [0, 1, 4]],
    [[0, 1, 2], [1, 0, 3], [1, 0, 4]],
]


def fan(center: tuple[float, float], k: int, radius: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Centre point + regular ``k``-gon; triangles ``(0, i, i+1)`` CCW, in cycle order."""
    angles = 2 * np.pi * np.arange(k) / k
    ring = np.column_stack([np.cos(angles), np.sin(angles)]) * radius + center
    points = np.vstack([center, ring])
    i = np.arange(1, k + 1)
    triangles = np.column_stack([np.zeros(k, np.int64), i, i % k + 1])
    return points, triangles


def hand_hamiltonian(points, triangles, components, segments=None, n_attributes: int = 1) -> HamiltonianMesh:
    """A HamiltonianMesh from rows already in cycle order (runs ``components``)."""
    m = len(triangles)
    components = np.asarray(components, dtype=np.int64)
    starts = np.repeat(np.cumsum(components) - components, components)
    segments = np.zeros((0, 2), np.int64) if segments is None else np.asarray(segments, np.int64).reshape(-1, 2)
    return HamiltonianMesh(
        points=np.asarray(points, dtype=np.float64),
        triangles=np.asarray(triangles, dtype=np.int64),
        segments=segments,
        segment_markers=np.arange(1, len(segments) + 1, dtype=np.int64),
        components=components,
        position=np.arange(m, dtype=np.int64) - starts,
        parent=np.arange(m, dtype=np.int64) // 2,
        kind=(np.arange(m) % 3).astype(np.int8),
        triangle_attributes=np.linspace(0.1, 0.9, m)[:, None] * np.arange(1, n_attributes + 1),
        report={"n_triangles": m},
    )


def hexagon_mesh() -> HamiltonianMesh:
    """6 triangles around the centre of a regular hexagon: one cycle, boundary segments."""
    points, triangles = fan((0.0, 0.0), 6)
    boundary = np.column_stack([np.arange(1, 7), np.arange(1, 7) % 6 + 1])
    return hand_hamiltonian(points, triangles, [6], segments=boundary)


def two_cycles_mesh() -> HamiltonianMesh:
    """A hexagon fan (6 triangles) and a square fan (4 triangles): two cycles."""
    p1, t1 = fan((0.0, 0.0), 6)
    p2, t2 = fan((3.0, 0.5), 4, radius=0.7)
    return hand_hamiltonian(np.vstack([p1, p2]), np.vstack([t1, t2 + len(p1)]), [6, 4], n_attributes=2)


def grid_mesh(nx: int, ny: int, z: bool = False) -> Mesh:
    """Structured grid split into triangles (counter-clockwise), optionally lifted to 3D."""
    xs, ys = np.meshgrid(np.arange(nx + 1.0), np.arange(ny + 1.0))
    pts = np.c_[xs.ravel(), ys.ravel()]
    v = lambda i, j: j * (nx + 1) + i  # noqa: E731
    tri = []
    for j in range(ny):
        for i in range(nx):
            a, b, c, d = v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)
            tri += [[a, b, c], [a, c, d]]
    if z:
        pts = np.c_[pts, np.sin(pts[:, 0]) * np.cos(pts[:, 1])]
    return Mesh(pts, np.array(tri, dtype=np.int64))


def bundled_domain(name: str) -> hammesh.Domain:
    """One of Triangle's bundled example domains."""
    d = triangle.get_data(name)
    return hammesh.Domain(
        vertices=d["vertices"],
        segments=d.get("segments", np.zeros((0, 2), int)),
        holes=d.get("holes", np.zeros((0, 2))),
    )


def hull_area(dom: hammesh.Domain) -> float:
    """Area of the convex hull of a domain's vertices (a scale for ``max_area``)."""
    from scipy.spatial import ConvexHull

    return ConvexHull(dom.vertices).volume


def plate_with_loops(n_loops: int) -> hammesh.Domain:
    """Unit square with ``n_loops`` closed internal constrained squares (interfaces)."""
    v = square(0, 0, 1)
    segs = [[0, 1], [1, 2], [2, 3], [3, 0]]
    for i in range(n_loops):
        x = 0.1 + 0.28 * i
        base = len(v)
        v += square(x, 0.4, 0.2)
        segs += [[base, base + 1], [base + 1, base + 2], [base + 2, base + 3], [base + 3, base]]
    return hammesh.Domain(vertices=v, segments=segs)


@st.composite
def star_pslg(draw):
    """A random star-shaped polygon, optionally with a hole or an internal loop."""
    n = draw(st.integers(5, 14))
    angles = np.sort(np.array(draw(st.lists(st.floats(0, 2 * np.pi, exclude_max=True), min_size=n, max_size=n, unique=True))))
    gaps = np.diff(np.r_[angles, angles[0] + 2 * np.pi])
    if gaps.min() < 0.05 or gaps.max() > 2 * np.pi / 3:  # keep edges >= 0.3 from the centre
        angles = np.linspace(0, 2 * np.pi, n, endpoint=False)
    radii = np.array(draw(st.lists(st.floats(0.6, 1.0), min_size=n, max_size=n)))
    outer = np.c_[radii * np.cos(angles), radii * np.sin(angles)]
    inner_kind = draw(st.sampled_from(["none", "hole", "loop"]))
    v = outer.tolist()
    segs = [[i, (i + 1) % n] for i in range(n)]
    holes = []
    if inner_kind != "none":
        r = draw(st.floats(0.1, 0.25))
        k = len(v)
        v += (r * np.array([[1, 0], [0, 1], [-1, 0], [0, -1]])).tolist()
        segs += [[k, k + 1], [k + 1, k + 2], [k + 2, k + 3], [k + 3, k]]
        if inner_kind == "hole":
            holes = [[0.0, 0.0]]
    return hammesh.Domain(vertices=v, segments=segs, holes=holes)


def square(x0: float = 0.0, y0: float = 0.0, s: float = 1.0) -> list[list[float]]:
    return [[x0, y0], [x0 + s, y0], [x0 + s, y0 + s], [x0, y0 + s]]


def angles_deg(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    p = points[tri]
    out = np.empty(tri.shape)
    for k in range(3):
        u = p[:, (k + 1) % 3] - p[:, k]
        v = p[:, (k + 2) % 3] - p[:, k]
        if p.shape[2] == 3:  # surfaces: angles in 3D
            cr = np.linalg.norm(np.cross(u, v), axis=1)
        else:
            cr = np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
        out[:, k] = np.degrees(np.arctan2(cr, (u * v).sum(axis=1)))
    return out


def signed_areas(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    p = points[tri]
    a, b, c = p[:, 0], p[:, 1], p[:, 2]
    return 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))


def assert_cycles(h: hammesh.HamiltonianMesh) -> None:
    """Each run closes: consecutive triangles (and last->first) share exactly 2 vertices."""
    tri = h.triangles
    assert int(np.sum(h.components)) == len(tri)
    start = 0
    for length in np.asarray(h.components).tolist():
        run = tri[start : start + length]
        nxt = np.roll(run, -1, axis=0)
        shared = (run[:, :, None] == nxt[:, None, :]).sum(axis=(1, 2))
        assert (shared == 2).all(), f"run starting at {start} breaks at {np.argmin(shared == 2)}"
        assert len({tuple(sorted(t)) for t in run.tolist()}) == length
        start += length


def dual_pieces(tri: np.ndarray, cut_edges: np.ndarray | None = None) -> int:
    """Number of connected pieces of the dual graph, optionally not crossing ``cut_edges``."""
    import networkx as nx

    cut = set()
    if cut_edges is not None:
        cut = {tuple(sorted(e)) for e in np.asarray(cut_edges).tolist()}
    owner: dict[tuple[int, int], list[int]] = {}
    for t, (a, b, c) in enumerate(np.asarray(tri).tolist()):
        for e in ((a, b), (b, c), (c, a)):
            owner.setdefault(tuple(sorted(e)), []).append(t)
    g = nx.Graph()
    g.add_nodes_from(range(len(tri)))
    for e, ts in owner.items():
        if len(ts) == 2 and e not in cut:
            g.add_edge(*ts)
    return nx.number_connected_components(g)


def assert_tiling_and_bound(m: hammesh.Mesh, h: hammesh.HamiltonianMesh) -> None:
    """Independent re-check of the certificate's promises shared by every mode."""
    assert_cycles(h)
    assert (signed_areas(h.points, h.triangles) > 0).all()
    np.testing.assert_array_equal(h.points[: m.n_points], m.points)
    in_area = np.abs(signed_areas(m.points, m.triangles)).sum()
    assert np.isclose(signed_areas(h.points, h.triangles).sum(), in_area, rtol=1e-9)
    a_in = angles_deg(m.points, m.triangles).min()
    a_out = angles_deg(h.points, h.triangles).min()
    assert a_out >= 0.5 * a_in * (1 - 1e-9), (a_in, a_out)


def assert_one_cycle_in_balanced_parts(m: hammesh.Mesh, h: hammesh.HamiltonianMesh, ks: tuple[int, ...]) -> None:
    """A certified output of one cycle, re-checked here (:func:`assert_tiling_and_bound`),
    whose partitions into each ``k`` of ``ks`` parts are connected and balanced."""
    from hammesh.partition import partition

    assert h.report["verified"] and len(h.components) == 1
    assert_tiling_and_bound(m, h)
    for k in ks:
        p = partition(h, k)
        assert p.connected and p.sizes.max() - p.sizes.min() <= 1


def assert_certificate(m: hammesh.Mesh, h: hammesh.HamiltonianMesh) -> None:
    """Independent re-check of what the certificate promises, with Thm 2.4's counts."""
    assert_tiling_and_bound(m, h)
    # counts of Thm 2.4 + midpoints
    q = h.report["midpoints"]
    assert h.n_triangles == 3 * m.n_triangles + 2 * q
    assert h.n_points == m.n_points + m.n_triangles + q
    assert len(h.components) == dual_pieces(m.triangles)


def plate(n_loops: int, pieces: int, max_area: float = 0.004) -> hammesh.Mesh:
    """Unit squares side by side (``pieces`` pieces), the first with ``n_loops`` closed
    internal constrained squares (interfaces: one midpoint each), meshed."""
    v: list[list[float]] = []
    segs: list[list[int]] = []
    for p in range(pieces):
        b = len(v)
        v += square(2.0 * p, 0, 1)
        segs += [[b, b + 1], [b + 1, b + 2], [b + 2, b + 3], [b + 3, b]]
    for i in range(n_loops):
        b = len(v)
        v += square(0.1 + 0.28 * i, 0.4, 0.2)
        segs += [[b, b + 1], [b + 1, b + 2], [b + 2, b + 3], [b + 3, b]]
    holes = [[2.0 * p - 0.5, 0.5] for p in range(1, pieces)]
    dom = hammesh.Domain(vertices=v, segments=segs, holes=holes or None)
    return hammesh.quality_mesh(dom, min_angle=30, max_area=max_area)


_BUNDLED_COVERS: dict = {}


def bundled_cover(name: str, area: float):
    """``(triangles, twin, cycle_cover(...))`` of a q30 mesh of Triangle's bundled domain
    ``name`` with ``max_area=area`` (made once per process: the walk and plan tests share it)."""
    if (name, area) not in _BUNDLED_COVERS:
        from hammesh.halfedge import prepare_mesh
        from hammesh.postprocess.cycle_cover import cycle_cover

        m = hammesh.quality_mesh(bundled_domain(name), min_angle=30, max_area=area)
        clean, he, _ = prepare_mesh(m)
        _BUNDLED_COVERS[name, area] = clean.triangles, he.twin, cycle_cover(clean.triangles, he.twin)
    return _BUNDLED_COVERS[name, area]


def blob(tw: np.ndarray, rng: np.random.Generator, start: int, size: int) -> tuple[list, set]:
    """A breadth-first blob of at most ``size`` triangles from ``start`` over the
    half-edge twins ``tw``, neighbours in ``rng``'s order (what the swap tests group):
    its triangles in the order reached, and them as a set."""
    group, seen = [start], {start}
    for x in group:
        for k in rng.permutation(3).tolist():
            g = tw[3 * x + k]
            if g >= 0 and g // 3 not in seen and len(group) < size:
                seen.add(g // 3)
                group.append(g // 3)
    return group, seen
