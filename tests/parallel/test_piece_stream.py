"""The partitioned output's pieces, written chunk by chunk from the tile's rows
(``partitioned._finish_and_write``), are byte for byte the pieces ``write_piece``
writes from the gathered rows of ``finish_tile``."""

from __future__ import annotations

import numpy as np
import pytest

import hammesh
from hammesh.io.pvtu import write_piece
from hammesh.parallel import joins
from hammesh.parallel.partitioned import _finish_and_write, stretch_parts
from hammesh.parallel.run import finish_args, run_tiles

DEMO = "hammesh/data/demo.poly"


def _gathered_piece(outcome, args, path, components, parts):
    piece = joins.finish_tile(outcome.ham, *args)
    ends = np.cumsum(components)
    cid = np.searchsorted(ends, piece.position, side="right")
    cpos = piece.position - (ends - components)[cid]
    if len(components) == 1:  # (one cycle: no cycle_id / cycle_position columns)
        cid = cpos = None
    part = None if parts is None else stretch_parts(piece.position, components, parts)
    write_piece(path, piece.point_ids, piece.points, piece.triangles, piece.position, cid, cpos, piece.parent,
                piece.kind, piece.triangle_attributes, part=part, local=True)
    return piece


@pytest.mark.parametrize("tiles, mode, parts, chunk", [(3, "sparse", None, 1 << 18), (4, "incircle", 5, 7),
                                                       (5, "sparse", 2, 1000)])
def test_streamed_piece_equals_the_gathered_one(tmp_path, monkeypatch, tiles, mode, parts, chunk):
    monkeypatch.setattr(joins, "CHUNK_ROWS", chunk)  # many chunks, runs split across them
    tiled = run_tiles(hammesh.read_domain(DEMO), min_angle=30, max_area=1e-3, tiles=tiles, mode=mode)
    comps = tiled.plan.components
    steps = {bk[4] for bk in tiled.plan.blocks if bk[1] == "run"}
    assert steps <= {1, -1} and (tiles != 5 or -1 in steps)  # (5 sparse tiles: runs walked backward too)
    total = 0
    for i, (h, a) in enumerate(zip(tiled.outcomes, finish_args(tiled))):
        piece = _gathered_piece(h.value, a, tmp_path / f"g{i}.vtu", comps, parts)
        name, rows, first, width, sizes, _ = _finish_and_write(h.value, a, str(tmp_path / f"s{i}.vtu"), comps, parts)
        assert (tmp_path / f"s{i}.vtu").read_bytes() == (tmp_path / f"g{i}.vtu").read_bytes()
        assert rows == len(piece.triangles) and first == int(piece.position[0])
        if parts is not None:
            assert sizes.tolist() == np.bincount(stretch_parts(piece.position, comps, parts), minlength=parts).tolist()
        total += rows
    assert total == int(comps.sum())
    assert not list(tmp_path.glob("*.part"))


def test_layout_refuses_a_plan_that_misses_rows():
    tiled = run_tiles(hammesh.read_domain(DEMO), min_angle=30, max_area=1e-3, tiles=2)
    h, a = tiled.outcomes[0], list(finish_args(tiled)[0])
    blocks = [bk for bk in a[2]]
    i = next(k for k, bk in enumerate(blocks) if bk[1] == "run" and bk[5] > 2)
    bk = blocks[i]
    blocks[i] = (*bk[:5], bk[5] - 1)  # one row short
    a[2] = blocks
    with pytest.raises(hammesh.VerificationError, match="does not cover"):
        joins.piece_layout(h.value.ham, *a)
