"""Which row of which piece holds each constrained edge (``partitioned._edge_entries``,
``_lent_edges``; tester18 r08), on a hand-made pair of tiles where two swaps share
an edge of a user segment: the one join-made row of the other tile's piece that
holds it must flag it, once."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from hammesh.errors import VerificationError
from hammesh.parallel import partitioned as P
from hammesh.parallel.joins import Join

# global points: a separator x = 0 through e (0,-1), a (0,0), b (0,1); tile U right of
# it (d = (1,0)), tile T left (c1, c2); a user segment a -> d (marker 7) crosses the cut at a
A, B, E, D, C1, C2 = 0, 1, 2, 3, 4, 5
N_GLOBAL = 6
SEP_KEYS = np.array([A * N_GLOBAL + B, A * N_GLOBAL + E])
# J0: t1 = a b c1 with u1 = b a d; J1: t2 = e a c2 with u2 = a e d; both swaps. Their
# rows in T's piece: J0 A1 = a d c1, A2 = d b c1; J1 A1 = e d c2, A2 = d a c2:
# a d is in two of them
J0 = Join(index=0, t_tile=0, t_row=0, u_tile=1, u_row=0, a=A, b=B, I_t=(0, 0), I_u=(0, 0), swap=True)
J1 = Join(index=1, t_tile=0, t_row=1, u_tile=1, u_row=1, a=E, b=A, I_t=(0, 0), I_u=(0, 0), swap=True)


def _args(tile: int, vertex_ids: list[int]) -> tuple:
    k = len(vertex_ids)
    return (SimpleNamespace(vertex_ids=np.array(vertex_ids)), tile, [], np.zeros(0), [J0, J1], 100, k, 200, 300, 0,
            SEP_KEYS, N_GLOBAL, {}, 0.0)


def _u_tile():
    # local = global ids 0..3: u1 = b a d, u2 = a e d; segments: a -> d (7), the
    # separators b a, a e, the boundary b d, d e (1)
    h = SimpleNamespace(triangles=np.array([[B, A, D], [A, E, D]]),
                        segments=np.array([[A, D], [B, A], [A, E], [B, D], [D, E]]),
                        segment_markers=np.array([7, 0, 0, 1, 1]), spill=None)
    h.ham = h
    args = _args(1, [A, B, E, D])
    keep = np.array([True, False, False, True, True])
    lay = SimpleNamespace(local_segments=h.segments[keep], segments=h.segments[keep],
                          segment_markers=h.segment_markers[keep], point_ids=np.array([A, B, E, D]),
                          join_triangles=np.zeros((0, 3), np.int64))
    return h, args, lay


def _t_tile():
    # local a 0, b 1, e 2, c1 3, c2 4, then the swaps' apex d as a join point (5)
    ids = [A, B, E, C1, C2]
    h = SimpleNamespace(triangles=np.array([[0, 1, 3], [2, 0, 4]]), segments=np.array([[0, 1], [0, 2], [1, 3], [4, 2]]),
                        segment_markers=np.array([0, 0, 2, 2]))
    keep = np.array([False, False, True, True])
    lay = SimpleNamespace(local_segments=h.segments[keep], segments=np.array(ids)[h.segments[keep]],
                          segment_markers=h.segment_markers[keep], point_ids=np.array(ids + [D]),
                          join_triangles=np.array([[0, 5, 3], [5, 1, 3], [2, 5, 4], [5, 0, 4]]))
    return h, _args(0, ids), lay


def test_an_edge_two_swaps_share_is_lent_once_to_the_lower_join():
    """U's constrained edges no row of its piece holds go to T's swap rows: a d (both
    swaps hold it: J0, the lower) and the boundary edges b d (J0) and d e (J1), each
    with its direction and marker; T's own b c1 and c2 e go to the swap rows too."""
    from hammesh.io.tags import segments_from_edge_fields

    hu, au, lu = _u_tile()
    lent = P._lent_edges(hu, au)
    assert lent == {0: [(A, D, 7), (B, D, 1)], 1: [(D, E, 1)]}
    keys, _, _ = P._edge_entries(hu, lu, au, frozenset({0, 1}), ())
    assert len(keys) == 0  # (U's piece: both its rows replaced by T's swap rows)
    ht, at, lt = _t_tile()
    keys, flags, marks = P._edge_entries(ht, lt, at, frozenset(), (lent,))
    m = len(ht.triangles)
    assert keys.tolist() == [m + 0, m + 1, m + 2]  # J0 A1, J0 A2, J1 A1; not J1 A2 = d a c2
    assert flags.tolist() == [1, 1 | 8 | 2, 1 | 8 | 4] and marks.tolist() == [[7, 0, 0], [1, 2, 0], [1, 0, 2]]
    rows = lt.point_ids[lt.join_triangles[keys - m]]
    seg, mk = segments_from_edge_fields(rows, flags, marks)
    assert sorted(zip(map(tuple, seg.tolist()), mk.tolist())) == sorted(
        [((A, D), 7), ((B, D), 1), ((D, E), 1), ((B, C1), 2), ((C2, E), 2)])


def test_an_edge_no_row_holds_and_nobody_asked_about_stops():
    hu, au, lu = _u_tile()
    with pytest.raises(VerificationError, match="held by no row"):
        P._edge_entries(hu, lu, au, frozenset(), ())


@pytest.mark.parametrize("mode", ["sparse", "incircle"])
def test_asking_every_swap_changes_nothing(tmp_path, monkeypatch, mode):
    """The lending tasks asked about every swap (not only those with an end on a user
    segment, :func:`partitioned.lent_swaps`): on the demo's tiles they lend nothing (a
    join's triangles have cycle neighbours across both other edges, in their own tile)
    and the stitched segments are still the one-file run's."""
    import hammesh
    from hammesh.parallel.run import parallel_hamiltonian

    asked = []

    def every_swap(tiled):
        out = {j.index: (j.u_tile, j.t_tile) for j in tiled.plan.joins if j.swap and j.u_tile != j.t_tile}
        asked.append(len(out))
        return out

    lent = []
    real = P._lent_edges
    monkeypatch.setattr(P, "lent_swaps", every_swap)
    monkeypatch.setattr(P, "_lent_edges", lambda o, a: lent.append(real(o, a)) or lent[-1])
    dom = hammesh.read_domain("hammesh/data/demo.poly")
    P.write_partitioned(dom, tmp_path / "o", min_angle=30, max_area=2e-3, tiles=6, mode=mode)
    assert asked and asked[0] > 0 and len(lent) > 0 and all(x == {} for x in lent)
    back = hammesh.read_mesh(tmp_path / "o" / "mesh.pvtu")
    whole = parallel_hamiltonian(dom, min_angle=30, max_area=2e-3, tiles=6, mode=mode)
    key = sorted(zip(back.segments[:, 0].tolist(), back.segments[:, 1].tolist(), back.segment_markers.tolist()))
    assert key == sorted(zip(whole.segments[:, 0].tolist(), whole.segments[:, 1].tolist(),
                             whole.segment_markers.tolist()))
