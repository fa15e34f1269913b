"""Decoupled tiles on domains with internal segments that end inside the domain (issue 15, session 16).

``hammesh mesh crack.poly -q 30 -a 0.002 --workers 2`` (a 4 x 3 rectangle, a crack
from (1, 1.5) to (3, 1.5), a lone vertex) printed a min angle of 22.07 deg where the
serial run printed 28.59. The union of the tiles' Triangle meshes met 30 deg (30.26):
what fell below was the tile's sparse ``hamiltonian()`` output (within its proven
bound, half the input's minimum), at the corner where the separator meets the outline
(docs/scale.md, Session 16). These tests hold the properties that are guaranteed on
such domains: the union meets the requested angle, the output is verified and keeps
the proven bound, and (the defect found on the way) two cuts ending on the same cut
from its two sides end at one vertex or clear of each other.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hammesh
import hammesh.parallel.tiles as tiles_module
from hammesh.errors import HammeshError
from hammesh.parallel import assemble, mesh_decoupled, parallel_hamiltonian
from hammesh.parallel.tiles import decompose
from tests.helpers import angles_deg, bundled_domain

#: the reported input (the tester's crack.poly): an outline, a crack ending inside at
#: both ends, a lone vertex
CRACK = hammesh.Domain(
    vertices=[[0, 0], [4, 0], [4, 3], [0, 3], [1, 1.5], [3, 1.5], [2, 2.5]],
    segments=[[0, 1], [1, 2], [2, 3], [3, 0], [4, 5]],
)


def _union_and_output(dom, q, a, n_tiles):
    """The union of the tiles' meshes (checked here, not by the code under test) and the
    parallel output."""
    r = mesh_decoupled(dom, min_angle=q, max_area=a, n_tiles=n_tiles)
    u = assemble(r.decomposition, list(r.meshes))
    union_min = float(angles_deg(u.points, u.triangles).min())
    h = parallel_hamiltonian(dom, min_angle=q, max_area=a, tiles=n_tiles)
    out = angles_deg(h.points, h.triangles)
    return union_min, float(out.min()), h


def _keeps_the_bounds(dom, q, a, n_tiles):
    union_min, out_min, h = _union_and_output(dom, q, a, n_tiles)
    assert union_min >= q * (1 - 1e-9)
    assert h.report["verified"] is True
    # sparse mode's proven bound: at least half the input's smallest angle
    assert out_min >= 0.5 * union_min * (1 - 1e-9)
    # the union's triangles all reach the output (its area; its input vertices)
    assert h.report["union"]["triangles"] <= len(h.triangles)
    return union_min, out_min


@pytest.mark.parametrize("area, n_tiles", [(0.002, 2), (0.001, 4), (0.005, 7)])
def test_the_reported_crack_keeps_the_bounds(area, n_tiles):
    union_min, out_min = _keeps_the_bounds(CRACK, 30.0, area, n_tiles)
    assert union_min >= 30.0


@pytest.mark.parametrize("name", ["face", "double_hex", "double_hex2", "double_hex3", "square_circle_hole"])
@pytest.mark.parametrize("n_tiles", [2, 7])
def test_triangle_examples_keep_the_bounds(name, n_tiles):
    dom = bundled_domain(name)
    span = np.ptp(np.asarray(dom.vertices, float), axis=0).prod()
    _keeps_the_bounds(dom, 30.0, span / 2000, n_tiles)


def _junction_gaps(dom, area, n_tiles):
    """For every cut, the distances between the ends of the later cuts on it (0 where two
    meet at one vertex), over the local length sqrt(area)."""
    d = decompose(dom, min_angle=30, max_area=area, n_tiles=n_tiles)
    cuts = d.cuts  # axis, value, lo, hi
    gaps = []
    for i, (axis, value, lo, hi) in enumerate(cuts):
        ends = [c[1] for c in cuts[i + 1:] if c[0] != axis and (c[2] == value or c[3] == value)]
        ends = np.sort(ends)
        gaps += list(np.diff(ends) / np.sqrt(area))
    return np.array(gaps)


def test_cuts_ending_on_one_cut_from_both_sides_meet_or_keep_clear(monkeypatch):
    """The crack at 4 tiles: the two halves' cuts ended 0.001 apart on the middle cut
    (a local size of ~0.03), a separator piece Triangle had to grade down to."""
    gaps = _junction_gaps(CRACK, 0.001, 4)
    assert len(gaps) and ((gaps == 0) | (gaps >= 0.5)).all(), gaps
    monkeypatch.setattr(tiles_module, "SIDE_VERTICES", False)
    before = _junction_gaps(CRACK, 0.001, 4)
    assert ((before > 0) & (before < 0.5)).any(), before  # (what the check catches)


def test_the_crossing_of_four_tiles_is_one_vertex():
    d = decompose(CRACK, min_angle=30, max_area=0.001, n_tiles=4)
    corners = {}
    for t in d.tiles:
        for x in t.box[:2]:
            for y in t.box[2:]:
                corners.setdefault((x, y), 0)
                corners[(x, y)] += 1
    assert max(corners.values()) == 4
    (x, y), = [k for k, v in corners.items() if v == 4]
    assert ((d.vertices == [x, y]).all(axis=1)).sum() == 1
    u = assemble(d, list(mesh_decoupled(CRACK, min_angle=30, max_area=0.001, n_tiles=4).meshes))
    assert angles_deg(u.points, u.triangles).min() >= 30.0 * (1 - 1e-9)


def test_a_domain_all_in_holes_is_a_meshing_error(capsys):
    dom = bundled_domain("box")  # Triangle's box.poly: one outline side, the rest eaten
    with pytest.raises(HammeshError, match="no triangles"):
        parallel_hamiltonian(dom, min_angle=30, max_area=0.01, tiles=2)


@st.composite
def cracked_star(draw):
    """A random star-shaped polygon with one or two internal segments that end inside
    the domain (a crack with both ends inside, or a segment from an outline vertex
    inwards; each on a ray of its own) and maybe a lone vertex near the centre.

    No input angle below 60 degrees: at a smaller one the union is held to Triangle's
    coarse run there, which a tile does not always reach (a 45-degree angle: 27.86
    against 28.73 degrees, docs/scale.md, Session 16, left open)."""
    n = draw(st.integers(5, 12))
    angles = np.linspace(0, 2 * np.pi, n, endpoint=False) + draw(st.floats(0, 0.5))
    radii = np.array(draw(st.lists(st.floats(0.7, 1.0), min_size=n, max_size=n)))
    v = np.c_[radii * np.cos(angles), radii * np.sin(angles)].tolist()
    segs = [[i, (i + 1) % n] for i in range(n)]
    rays = draw(st.lists(st.integers(0, n - 1), min_size=1, max_size=2, unique=True))
    for i in rays:
        k = len(v)
        if draw(st.booleans()):  # a crack with both ends inside, between two outline vertices' rays
            phi = angles[i] + np.pi / n
            r0, r1 = draw(st.floats(0.1, 0.3)), draw(st.floats(0.4, 0.6))
            v += [[r0 * np.cos(phi), r0 * np.sin(phi)], [r1 * np.cos(phi), r1 * np.sin(phi)]]
            segs.append([k, k + 1])
        else:  # from an outline vertex inwards, halving its angle (no input angle below 60 degrees)
            p, a, b = (np.asarray(v[j], float) for j in (i, (i - 1) % n, (i + 1) % n))
            ua, ub = (a - p) / np.hypot(*(a - p)), (b - p) / np.hypot(*(b - p))
            if np.degrees(np.arccos(np.clip(ua @ ub, -1, 1))) < 120:
                continue
            w = (ua + ub) / np.hypot(*(ua + ub))
            v.append((p + draw(st.floats(0.2, 0.4)) * w).tolist())
            segs.append([i, k])
    if draw(st.booleans()):
        v.append([draw(st.floats(-0.03, 0.03)), draw(st.floats(-0.03, 0.03))])
    return hammesh.Domain(vertices=v, segments=segs)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(dom=cracked_star(), area=st.sampled_from([5e-3, 2e-3, 1e-3]), n_tiles=st.integers(2, 7))
def test_random_domains_with_dangling_segments_keep_the_bounds(dom, area, n_tiles):
    single = hammesh.quality_mesh(dom, min_angle=30, max_area=area, isolate=False)
    single_min = float(angles_deg(single.points, single.triangles).min())
    union_min, out_min, h = _union_and_output(dom, 30.0, area, n_tiles)
    assert union_min >= min(30.0, single_min) * (1 - 1e-9)
    assert h.report["verified"] is True
    assert out_min >= 0.5 * union_min * (1 - 1e-9)
