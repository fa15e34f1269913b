"""Strips of real-world surfaces (issue 12): non-manifold, flipped, non-orientable, degenerate, doubled.

A strip needs none of a manifold's properties: every input row that has three distinct
vertices is drawn exactly once with its own winding, whatever the edges around it.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hammesh.mesh import Mesh
from hammesh.strips.defects import (
    orientation_pieces,
    proper_pairing,
    triangle_repeats,
    zero_area_rows,
)
from hammesh.strips.dual import dual_mesh
from hammesh.strips.encode import encode, encode_generalized
from hammesh.strips.generalized import decode_generalized
from hammesh.strips.gl import decode_gl_strip, verify_gl_strip

from .conftest import oriented_set
from .defect_meshes import ALL


def _drawable(tri: np.ndarray) -> np.ndarray:
    return tri[(tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 2] != tri[:, 0])]


def _crossed_edges_are_proper(tri: np.ndarray, indices: np.ndarray, restart: int | None) -> None:
    """Consecutive triangles of one strip share an edge used by exactly those two, oppositely.

    (Restart joins only: a stitched join may put two unrelated triangles side by side.)
    """
    users: dict[tuple[int, int], list[tuple[int, int]]] = {}
    for a, b, c in tri.tolist():
        for p, q in ((a, b), (b, c), (c, a)):
            users.setdefault((min(p, q), max(p, q)), []).append((p, q))
    seg = np.split(indices, np.flatnonzero(indices == restart)) if restart is not None else [indices]
    for s in seg:
        s = s[s != restart] if restart is not None else s
        drawn = decode_gl_strip(s)
        for t0, t1 in zip(drawn[:-1], drawn[1:]):
            common = sorted(set(t0.tolist()) & set(t1.tolist()))
            assert len(common) >= 2  # swaps in between keep an edge in common
            pairs = [(p, q) for i, p in enumerate(common) for q in common[i + 1 :]]  # 3 for a pillow
            ok = [len(users[e]) == 2 and users[e][0] == users[e][1][::-1] for e in pairs]
            assert any(ok), f"strip crosses the cut edge {pairs[0]}: {users[pairs[0]]}"


@pytest.mark.parametrize("name", list(ALL))
def test_defect_meshes_are_drawn_with_their_windings(name):
    pts, tri, expected = ALL[name]()
    mesh = Mesh(pts, tri)
    s = encode(mesh)
    want = _drawable(tri)
    verify_gl_strip(want, s.indices, s.restart_index)  # the full multiset comparison, windings
    assert oriented_set(decode_gl_strip(s.indices, s.restart_index)) == oriented_set(want)
    found = s.defects.to_dict()
    for key, value in expected.items():
        assert found[key] == value, (key, found)
    _crossed_edges_are_proper(want, s.indices, s.restart_index)
    repeated = (tri[:, 0] == tri[:, 1]) | (tri[:, 1] == tri[:, 2]) | (tri[:, 2] == tri[:, 0])
    assert s.to_dict()["dropped_rows"] == np.flatnonzero(repeated).tolist()
    assert dual_mesh(mesh).n_triangles == len(want)
    g = encode_generalized(mesh)
    assert oriented_set(decode_generalized(g)) == oriented_set(want)
    assert g.defects == s.defects


@pytest.mark.parametrize("join", ["restart", "stitch"])
def test_klein_and_mobius_joins(join):
    for build in (ALL["klein"], ALL["mobius"]):
        pts, tri, _ = build()
        s = encode(Mesh(pts, tri), join=join)
        verify_gl_strip(tri, s.indices, s.restart_index)


def test_pairing_cuts_exactly_the_bad_edges():
    """proper_pairing against a dictionary of edge users."""
    rng = np.random.default_rng(1)
    for _ in range(20):
        tri = rng.integers(0, 9, (30, 3))
        tri = _drawable(tri)
        p = proper_pairing(tri, 9)
        users: dict = {}
        for h, (a, b) in enumerate(zip(tri.reshape(-1), tri[:, [1, 2, 0]].reshape(-1))):
            users.setdefault((min(a, b), max(a, b)), []).append((h, a))
        n_nm = n_fl = 0
        for u in users.values():
            if len(u) == 2 and u[0][1] != u[1][1]:
                assert p.twin[u[0][0]] == u[1][0] and p.twin[u[1][0]] == u[0][0]
            else:
                assert all(p.twin[h] == -1 for h, _ in u)
            n_nm += len(u) >= 3
            n_fl += len(u) == 2 and u[0][1] == u[1][1]
        assert (p.non_manifold_edges, len(p.flipped)) == (n_nm, n_fl)


def test_orientability_by_hand():
    pts, tri, _ = ALL["mobius"]()
    p = proper_pairing(tri, len(pts))
    assert orientation_pieces(len(tri), p.twin, p.flipped) == (1, 1)
    # cut the seam: an orientable band
    keep = np.ones(len(tri), bool)
    keep[-2 * 4 :] = False
    p = proper_pairing(tri[keep], len(pts))
    assert orientation_pieces(int(keep.sum()), p.twin, p.flipped) == (1, 0)


def test_repeats_and_zero_area_rows():
    tri = np.array([[0, 1, 2], [1, 2, 0], [0, 2, 1], [3, 4, 5], [2, 1, 0]])
    double, dup, rows = triangle_repeats(tri)
    assert (double, dup) == (1, 2) and rows.sum() == 2
    pts = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 0], [1, 1, 1], [2, 2, 2]])
    assert zero_area_rows(pts, tri).tolist() == [False, False, False, True, False]
    # a sliver floating point cannot resolve: a 6e-8 base under a 1.4e9 height (the globe's poles)
    sliver = np.array([[7.8e8, -1.18e9, -6.2e9], [2.1e-7, -3.3e-7, -6.371e9], [2.7e-7, -2.8e-7, -6.371e9]])
    assert zero_area_rows(sliver, np.array([[0, 1, 2]])).tolist() == [True]


def test_only_repeated_vertices_is_refused():
    from hammesh.errors import InvalidMeshError

    with pytest.raises(InvalidMeshError, match="repeat a vertex"):
        encode(Mesh(np.zeros((3, 3)), np.array([[0, 0, 1], [2, 1, 1]])))


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 80), st.integers(3, 12), st.sampled_from(["restart", "stitch"]))
def test_any_triangle_soup_round_trips(seed, m, n, join):
    """Random triangles on few vertices: every kind of defect at once, every row kept as given."""
    rng = np.random.default_rng(seed)
    tri = rng.integers(0, n, (m, 3))
    pts = rng.random((n, 3))
    want = _drawable(tri)
    if len(want) == 0:
        return
    s = encode(Mesh(pts, tri), join=join)
    verify_gl_strip(want, s.indices, s.restart_index)
    if join == "restart":
        _crossed_edges_are_proper(want, s.indices, s.restart_index)
    assert s.defects.repeated_vertex == len(tri) - len(want)


@pytest.mark.parametrize("name", sorted(ALL) + ["clean torus", "repeated rows"])
def test_census_beside_the_pairing_gives_the_same_dual(name, monkeypatch):
    """Large meshes run the face census on a second thread beside the pairing (which assumes
    no repeated vertex and is redone when one shows up): the same DualMesh as in one thread."""
    import hammesh.strips.dual as dual_module
    from hammesh.surface import shapes

    if name == "clean torus":
        mesh = Mesh(*shapes.torus(12, 8))
    elif name == "repeated rows":  # a clean torus with rows repeating a vertex: the pairing is redone
        pts, tri = shapes.torus(12, 8)
        mesh = Mesh(pts, np.r_[tri[:5], [[0, 0, 1], [3, 4, 3]], tri[5:]])
    else:
        pts, tri, _ = ALL[name]()
        mesh = Mesh(pts, tri)
    one = dual_mesh(mesh)
    monkeypatch.setattr(dual_module, "CENSUS_BESIDE_PAIRING", 0)
    two = dual_mesh(mesh)
    assert np.array_equal(one.triangles, two.triangles) and np.array_equal(one.twin, two.twin)
    assert one.defects == two.defects
    assert (one.rows is None) == (two.rows is None) and (one.rows is None or np.array_equal(one.rows, two.rows))
    assert (one.records is None) == (two.records is None)
    if one.records is not None:
        assert np.array_equal(one.records, two.records)
    if name == "repeated rows":
        assert two.defects.repeated_vertex == 2 and len(two.rows) == len(tri)
    s = encode(mesh)
    verify_gl_strip(one.triangles, s.indices, s.restart_index)


def _zero_area_reference(p: np.ndarray, row) -> bool:
    """The zero-area rule without the filter: cross product at the vertex opposite the longest
    side (ties: the side with the least sum of vertex indices), twice the area <= rtol x side^2."""
    from hammesh.strips.defects import ZERO_AREA_RTOL

    a, b, c = row
    sides = [(a, b, c), (b, c, a), (c, a, b)]  # side p -> q, apex r
    length = [float(np.sum((p[q_] - p[p_]) ** 2)) for p_, q_, _ in sides]
    best = max(range(3), key=lambda k: (length[k], -(sides[k][0] + sides[k][1])))
    p_, q_, r_ = sides[best]
    u, v = p[r_] - p[q_], p[p_] - p[r_]
    u3, v3 = np.r_[u, [0.0] * (3 - len(u))], np.r_[v, [0.0] * (3 - len(v))]
    cx = u3[1] * v3[2] - u3[2] * v3[1]
    cy = u3[2] * v3[0] - u3[0] * v3[2]
    cz = u3[0] * v3[1] - u3[1] * v3[0]
    return length[best] == 0.0 or float(np.sqrt(cx * cx + cy * cy + cz * cz)) <= ZERO_AREA_RTOL * length[best]


@given(st.integers(0, 2**32 - 1), st.sampled_from([2, 3]), st.sampled_from([0.0, 1e-16, 1e-14, 1e-13, 1e-12, 1e-8, 1.0]))
@settings(max_examples=200, deadline=None)
def test_zero_area_rule_is_one_answer_for_every_rotation_and_the_reversed_row(seed, d, lift):
    """The face census's filter (one cross product) changes no answer of the plain rule, and the
    answer does not depend on where a row starts or which way it is listed (a strip draws a row
    in some rotation, odd windows reversed in the buffer)."""
    rng = np.random.default_rng(seed)
    scale = 10.0 ** rng.integers(-6, 9)
    base = rng.normal(size=(2, d)) * scale
    # a third point near the line through the first two (off it by `lift` of the side's
    # length), sometimes on a vertex, or isosceles so that two sides tie
    t = rng.choice([rng.uniform(-1, 2), 0.0, 0.5])
    normal = rng.normal(size=d)
    third = base[0] + t * (base[1] - base[0]) + lift * np.linalg.norm(base[1] - base[0]) * normal
    pts = np.vstack([base, third])
    ids = rng.permutation(10)[:3]
    p = np.zeros((10, d))
    p[ids] = pts
    rows = [ids[[0, 1, 2]], ids[[1, 2, 0]], ids[[2, 0, 1]], ids[[2, 1, 0]], ids[[1, 0, 2]], ids[[0, 2, 1]]]
    got = zero_area_rows(p, np.array(rows)).tolist()
    assert got == [_zero_area_reference(p, r) for r in rows]
    assert len(set(got)) == 1


# m up to 700: up to three blocks of CENSUS_BLOCK = 256 rows, the last one partial
@given(st.integers(0, 2**32 - 1), st.sampled_from([2, 3]), st.integers(1, 700))
@settings(max_examples=40, deadline=None)
def test_census_over_several_blocks_flags_each_row_as_the_plain_rule(seed, d, m):
    """face_flags reads planar rows CENSUS_BLOCK at a time (corners gathered into columns, the
    filter vectorized): every row's flag is still the plain rule's, slivers, repeated
    vertices and a last partial block included."""
    from hammesh.strips._dual_kernels import FACE_OK, FACE_REPEATED, FACE_ZERO_AREA, face_flags
    from hammesh.strips.defects import ZERO_AREA_RTOL

    rng = np.random.default_rng(seed)
    n = 60
    p = rng.normal(size=(n, d)) * 10.0 ** rng.integers(-3, 4)
    # some points on the line through points 0 and 1: rows over them are slivers or exact zeros
    for i in range(2, 12):
        p[i] = p[0] + rng.choice([0.0, 0.5, 2.0, rng.uniform(-1, 2)]) * (p[1] - p[0])
        p[i] += rng.choice([0.0, 1e-15, 1e-9]) * np.linalg.norm(p[1] - p[0]) * rng.normal(size=d)
    tri = rng.integers(0, n, size=(m, 3))
    line = rng.random(m) < 0.3
    tri[line] = np.c_[rng.integers(0, 12, (int(line.sum()), 3))]
    flags = np.full(m, -1, np.int8)
    n_rep, n_zero = face_flags(p, tri.astype(np.int64), ZERO_AREA_RTOL, flags)
    want = []
    for a, b, c in tri.tolist():
        if a == b or b == c or c == a:
            want.append(FACE_REPEATED)
        else:
            want.append(FACE_ZERO_AREA if _zero_area_reference(p, (a, b, c)) else FACE_OK)
    assert flags.tolist() == want
    assert (n_rep, n_zero) == (want.count(FACE_REPEATED), want.count(FACE_ZERO_AREA))
