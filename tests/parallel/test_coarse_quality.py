"""Decoupled tiles at coarse sizes: the union meets the requested min angle (issue 15).

A separator meeting a segment (or another separator, or the domain's boundary) at a
corner, or passing close to a vertex, used to leave a tile a triangle below the min
angle that ``-Y`` forbade Triangle to repair: ``hammesh mesh demo.poly -q 30 -a 0.01
--workers 2 --tiles 2`` failed its own union check (14.4 deg). The pieces meeting a
vertex now start with equal subsegments, sized by a coarse mesh that has the separators.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.parallel import assemble, check_union, mesh_decoupled
from hammesh.parallel.guard import input_fault
from tests.helpers import angles_deg, star_pslg


def _union_meets(dom, q, a, n_tiles):
    single = hammesh.quality_mesh(dom, min_angle=q, max_area=a, isolate=False)
    single_min = float(angles_deg(single.points, single.triangles).min())
    r = mesh_decoupled(dom, min_angle=q, max_area=a, n_tiles=n_tiles)
    # no tile gives Triangle points that close (it crashed on such input, session 17)
    assert all(input_fault(t.vertices, t.segments) is None for t in r.decomposition.tiles)
    u = assemble(r.decomposition, list(r.meshes))
    facts = check_union(r.decomposition, u, single_run_min_angle=single_min)
    # independent of the check: the test's own angles and areas
    p, t = u.points, u.triangles
    assert angles_deg(p, t).min() >= min(q, single_min) * (1 - 1e-9)
    sp = single.points[single.triangles]
    area = 0.5 * ((sp[:, 1, 0] - sp[:, 0, 0]) * (sp[:, 2, 1] - sp[:, 0, 1])
                  - (sp[:, 1, 1] - sp[:, 0, 1]) * (sp[:, 2, 0] - sp[:, 0, 0])).sum()
    assert facts.area == pytest.approx(area, rel=1e-9)
    assert facts.separator_edges > 0
    return r


@pytest.mark.parametrize("area, n_tiles", [(0.01, 2), (1e-4, 6)])
def test_the_reported_demo_cases_meet_30_degrees(area, n_tiles):
    """The two cases of the bug report (14.42 and 27.8 degrees before), with no repair round."""
    dom = hammesh.read_domain("hammesh/data/demo.poly")
    r = _union_meets(dom, 30.0, area, n_tiles)
    assert r.rounds == 0


def test_a_corner_starts_with_equal_subsegments():
    """Where a separator crosses the hexagon's edge at 90 degrees, the four subsegments
    meeting the crossing are equally long (a right corner with legs apart by more than
    tan 60 has an angle below 30 degrees that no tile may repair)."""
    from hammesh.parallel import decompose

    dom = hammesh.read_domain("hammesh/data/demo.poly")
    d = decompose(dom, min_angle=30, max_area=0.01, n_tiles=2)
    p, s = d.vertices, d.segments
    length = np.linalg.norm(p[s[:, 0]] - p[s[:, 1]], axis=1)
    shared = np.intersect1d(s[d.separator].ravel(), s[~d.separator].ravel())  # the crossings
    assert len(shared) > 0
    for v in shared:
        ends = length[(s == v).any(axis=1)]
        assert ends.max() <= 1.73 * ends.min(), (v, ends)


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(area=st.sampled_from([0.01, 0.005, 0.003, 1e-3]), n_tiles=st.integers(2, 9))
def test_demo_at_coarse_sizes_meets_30_degrees(area, n_tiles):
    _union_meets(hammesh.read_domain("hammesh/data/demo.poly"), 30.0, area, n_tiles)


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(dom=star_pslg(), area=st.sampled_from([5e-3, 2e-3, 1e-3, 5e-4]), n_tiles=st.integers(2, 8))
def test_random_domains_at_coarse_sizes_meet_the_min_angle(dom, area, n_tiles):
    """Star-shaped domains with a hole or an internal loop: the union conforms, has the
    domain's area and meets 30 degrees (or the single run's own minimum at a small input angle).

    (Randomized again in session 15: the rare misses had three causes, each with a
    reproducer below. Coarser still, ~100 triangles in all at area 0.02, a tile can
    miss by 2-3 degrees: docs/scale.md, Limits.)"""
    _union_meets(dom, 30.0, area, n_tiles)


@pytest.mark.slow
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(dom=star_pslg(), area=st.sampled_from([5e-3, 2e-3, 1e-3, 5e-4, 3e-4]), n_tiles=st.integers(2, 8))
def test_many_random_domains_meet_the_min_angle(dom, area, n_tiles):
    """The same over more examples and finer sizes (session 15, outside the suite: 0
    misses in 5,400 examples, against 14 in 2,100 before the causes were fixed)."""
    _union_meets(dom, 30.0, area, n_tiles)


#: a random domain whose 168-degree bend of the boundary met a separator's subsegments
#: 4x shorter than its own (21.1 degrees with no repair round; each round's halving of
#: both kept the ratio)
BEND = [[0.6594322309730846, 0.0], [0.5943344354825584, 0.2862163792117008], [0.5255840193932596, 0.6590615144284928],
        [0.2225187087469749, 0.9749181629027018], [-0.18733494130135203, 0.8207680057530561],
        [-0.4367751093547799, 0.5476986636091843], [-0.5620718027298678, 0.2706795141420966],
        [-0.7005328845037657, 8.579053547049991e-17], [-0.8376073561157945, -0.4033704432318455],
        [-0.5935401389104115, -0.7442757930044673], [-0.22251870874697505, -0.9749181629027018],
        [0.15588323172688875, -0.6829690625039669], [0.5935401389104111, -0.7442757930044676],
        [0.6658745080094333, -0.3206682623682937]]
#: a random pentagon where the repair rounds halved one leg of a corner and left an ear
#: of 16.2 degrees after four rounds
PENTAGON = [[0.9041801431142333, 0.0], [0.1946807064562169, 0.5991656052659468],
            [-0.5096807064562169, 0.37030470894425815], [-0.509680706456217, -0.370304708944258],
            [0.20692382162813064, -0.6368460392742867]]
#: a 20.2-degree input angle (Triangle's own runs: 20.2 degrees fine, 18.0 coarse)
SMALL_ANGLE = [[0.98, 0.0], [0.6784686091913338, 0.415251923561161], [0.5325071516813225, 0.5432311325942737],
               [-0.18048472431563584, 0.572210856493224], [-0.37733206159794036, 0.9260780287266553],
               [-0.33729061204748967, 0.6698768864684239], [-0.8549496210149045, 0.20550536728790722],
               [-0.8071431237118712, -0.03215238722023079], [0.2813536493701596, -0.6557527841750123],
               [0.5034193171609391, -0.6425203154226894], [0.9856402749186125, -0.1687994329325843],
               [0.7457670312283741, -0.07957094402366582]]


def _with_square_hole(outer, r):
    n = len(outer)
    v = [*outer, [r, 0.0], [0.0, r], [-r, 0.0], [0.0, -r]]
    s = [[i, (i + 1) % n] for i in range(n)] + [[n, n + 1], [n + 1, n + 2], [n + 2, n + 3], [n + 3, n]]
    return hammesh.Domain(vertices=v, segments=s, holes=[[0.0, 0.0]])


def test_a_bend_next_to_a_separator_meets_30_degrees_without_repair():
    """Pieces meeting nearly straight on start at most ``STRAIGHT_RATIO`` apart."""
    from hammesh.parallel.tiles import STRAIGHT_RATIO

    dom = _with_square_hole(BEND, 0.1259886837860367)
    r = _union_meets(dom, 30.0, 3e-4, 6)
    assert r.rounds == 0
    d = r.decomposition
    p, s = d.vertices, d.segments
    length = np.linalg.norm(p[s[:, 0]] - p[s[:, 1]], axis=1)
    ends = length[(s == 0).any(axis=1)]  # the bend (input vertex 0, 168 degrees)
    assert len(ends) == 2 and ends.max() <= STRAIGHT_RATIO * ends.min() * 1.06


def test_repair_rounds_keep_a_corner_s_legs_equal():
    """Halving the subsegments at a bad vertex halves every leg of the corners at their
    other ends too (:func:`~hammesh.parallel.decoupled.repair_rows`)."""
    dom = _with_square_hole(PENTAGON, 0.16210333322037423)
    r = _union_meets(dom, 30.0, 5e-4, 7)
    assert 1 <= r.rounds < 4


def test_repair_rows_close_over_corners_only():
    from hammesh.parallel import decompose
    from hammesh.parallel.decoupled import repair_rows
    from hammesh.parallel.tiles import coupled_ends

    d = decompose(hammesh.read_domain("hammesh/data/demo.poly"), min_angle=30, max_area=0.01, n_tiles=2)
    crossing = np.intersect1d(d.segments[d.separator].ravel(), d.segments[~d.separator].ravel())[0]
    rows = repair_rows(d, [crossing])
    at = np.flatnonzero((d.segments == crossing).any(axis=1))
    assert set(at.tolist()) <= set(rows.tolist())
    # every row taken is tied to another taken row at a corner (or meets the vertex)
    i, j = coupled_ends(d.vertices, d.segments)
    tied = set((i // 2)[np.isin(j // 2, rows)].tolist()) | set((j // 2)[np.isin(i // 2, rows)].tolist())
    assert set(rows.tolist()) <= tied | set(at.tolist())
    assert len(rows) < 0.1 * len(d.segments)  # (not the whole chain)


def test_a_small_input_angle_is_not_repaired_and_the_command_accepts_it(tmp_path, capsys):
    """The union meets what Triangle's own runs meet at a 20.2-degree input angle, with
    no repair round (four rounds made it 18.0 degrees), and the command exits 0."""
    from hammesh.cli import main
    from hammesh.domain.triangle_files import write_poly
    from hammesh.parallel.decoupled import small_angle_vertices

    dom = _with_square_hole(SMALL_ANGLE, 0.16457277353926913)
    r = _union_meets(dom, 30.0, 5e-3, 4)
    assert r.rounds == 0
    assert 4 in small_angle_vertices(r.decomposition).tolist()  # (the 20.2-degree vertex)
    path = tmp_path / "d.poly"
    write_poly(dom, path)
    out = tmp_path / "d.vtu"
    assert main(["mesh", str(path), "-q", "30", "-a", "5e-3", "--tiles", "4", "-o", str(out)]) == 0
    capsys.readouterr()
    assert main(["check", str(out)]) == 0


@pytest.mark.parametrize("area, n_tiles", [("0.01", "2"), ("1e-4", "6")])
def test_the_reported_commands_exit_0_and_check(tmp_path, capsys, area, n_tiles):
    """The bug report's commands (in process: the same tiles as ``--workers 2``) exit 0,
    not 3 (the command checks the union itself), and their output passes ``hammesh check``."""
    from hammesh.cli import main

    out = tmp_path / "t.vtu"
    assert main(["mesh", "hammesh/data/demo.poly", "-q", "30", "-a", area, "--tiles", n_tiles, "-o", str(out)]) == 0
    capsys.readouterr()
    assert main(["check", str(out)]) == 0


def test_a_subnormal_coordinate_is_meshed_and_kept():
    """A vertex at ``(0.6, 5e-324)`` (hypothesis found it) made Triangle fail on a tile
    and on the coarse mesh: its predicates assume no underflow. Triangle now gets 0
    there, the union the given coordinate."""
    from hammesh.parallel.tiles import without_subnormals

    v = [[0.6, 5e-324], [0.08221587816870324, 0.5943404322246207], [-0.4161468365471424, 0.9092974268256817],
         [-0.6536436208636119, -0.7568024953079282], [0.28366218546322625, -0.9589242746631385]]
    assert np.array_equal(without_subnormals(np.array(v))[0], [0.6, 0.0])
    assert np.array_equal(without_subnormals(np.array(v))[1:], np.array(v)[1:])
    dom = hammesh.Domain.from_polygon(v)
    r = _union_meets(dom, 30.0, 5e-3, 2)
    u = assemble(r.decomposition, list(r.meshes))
    assert u.points[0, 1] == 5e-324 and u.points[0, 0] == 0.6


#: a random domain (hypothesis, session 17) whose coarse mesh has a Steiner point at
#: (0, 0) between its inner loop's vertices at (+-0.207, 0): at 7 tiles a cut runs
#: along y = 0 on coarse edges, and that stretch was taken for outside the domain
LOOP_ON_CUT = [[0.75, 0.0], [0.66409202, 0.34854238], [0.42604856, 0.6172379], [0.09040251, 0.74453166],
               [-0.26595367, 0.70126218], [-0.74851075, 0.66312266], [-0.97094182, 0.23931566],
               [-0.97094182, -0.23931566], [-0.74851075, -0.66312266], [-0.22162805, -0.58438515],
               [0.1054696, -0.86862026], [0.56806475, -0.82298387], [0.66409202, -0.34854238],
               [0.20703125, 0.0], [0.0, 0.20703125], [-0.20703125, 0.0], [0.0, -0.20703125]]


def test_a_cut_along_coarse_edges_keeps_its_separator(monkeypatch):
    """The cut y = 0 lies on coarse edges inside the loop: it gets its separator, the
    union conforms (before: a separator edge in one tile only, the loop's inside
    eaten from the other tile's hull; the check catches it with the fix switched off)."""
    import hammesh.parallel.tiles as tiles
    from hammesh.errors import VerificationError

    segs = [[i, (i + 1) % 13] for i in range(13)] + [[13, 14], [14, 15], [15, 16], [16, 13]]
    dom = hammesh.Domain(vertices=LOOP_ON_CUT, segments=segs)
    _union_meets(dom, 30.0, 0.005, 7)
    monkeypatch.setattr(tiles, "LINE_EDGES", False)
    with pytest.raises(VerificationError, match="not shared by two tiles"):
        _union_meets(dom, 30.0, 0.005, 7)
