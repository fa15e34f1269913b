"""Real-world surface defects (issue 12) with the counts each builder puts in by design.

The builders live in :mod:`hammesh.surface.shapes` (numpy; no pyvista needed).  Each
entry returns ``(points, triangles, expected)``; the tests compare
:class:`hammesh.strips.defects.MeshDefects` with ``expected``.
"""

from __future__ import annotations

from hammesh.surface import shapes


def _with(build, expected, **kw):
    def make():
        pts, tri = build(**kw)
        return pts, tri, expected

    return make


ALL = {
    "mobius": _with(shapes.mobius_strip, {"flipped_neighbours": 4, "non_orientable_pieces": 1, "non_manifold_edges": 0}),
    "klein": _with(shapes.klein_bottle, {"flipped_neighbours": 12, "non_orientable_pieces": 1, "non_manifold_edges": 0}),
    "finned torus (bunny stand-in)": _with(shapes.finned_torus, {"non_manifold_edges": 132, "flipped_neighbours": 0}),
    "pole sphere (globe stand-in)": _with(
        shapes.pole_sphere, {"zero_area": 32, "non_manifold_edges": 0, "flipped_neighbours": 0}
    ),
    "one flipped triangle": _with(
        shapes.flipped_triangle, {"flipped_neighbours": 3, "non_orientable_pieces": 0, "non_manifold_edges": 0}
    ),
    "double-sided faces": _with(
        shapes.double_sided, {"double_sided": 2, "non_manifold_edges": 3, "flipped_neighbours": 0}
    ),
    "duplicate + repeated vertex": _with(
        shapes.duplicate_and_repeated, {"duplicate": 1, "repeated_vertex": 1, "non_manifold_edges": 3}
    ),
}
