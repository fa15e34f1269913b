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


@pytest.mark.parametrize("tiles, mode, parts", [(3, "sparse", None), (4, "incircle", 3)])
def test_typed_pieces_hold_the_same_values_in_fewer_bytes(tmp_path, tiles, mode, parts):
    """With ``piece_types`` (what ``write_partitioned`` passes) the integer arrays are
    32-bit (``kind`` one byte): the same values as the 64-bit piece, fewer bytes, and
    the index lists the types the pieces use."""
    import re
    import xml.etree.ElementTree as ET

    from hammesh.io import vtu
    from hammesh.io.pvtu import write_index
    from hammesh.parallel.partitioned import piece_types

    tiled = run_tiles(hammesh.read_domain(DEMO), min_angle=30, max_area=1e-3, tiles=tiles, mode=mode)
    comps = tiled.plan.components
    fargs = finish_args(tiled)
    types = piece_types(max(a[11] for a in fargs), int(comps.sum()), int(tiled.mesh_triangles.sum()))
    assert types["kind"] == "UInt8" and set(types.values()) == {"Int32", "UInt8"}
    for i, (h, a) in enumerate(zip(tiled.outcomes, fargs)):
        _finish_and_write(h.value, a, str(tmp_path / f"wide{i}.vtu"), comps, parts)
        _finish_and_write(h.value, a, str(tmp_path / f"narrow{i}.vtu"), comps, parts, types)
        wide, narrow = vtu.read_raw(tmp_path / f"wide{i}.vtu"), vtu.read_raw(tmp_path / f"narrow{i}.vtu")
        assert wide.keys() == narrow.keys()
        for key, w in wide.items():
            assert np.array_equal(narrow[key], w)  # the same values
            if key[0] != "Points" and key[1] not in ("types",) and not key[1].startswith("attribute_"):
                assert narrow[key].dtype.itemsize < w.dtype.itemsize, key
        assert (tmp_path / f"narrow{i}.vtu").stat().st_size < 0.8 * (tmp_path / f"wide{i}.vtu").stat().st_size
        head = (tmp_path / f"narrow{i}.vtu").read_bytes().split(b"<AppendedData")[0].decode()
        got = {n: t for t, n in re.findall(r'<DataArray type="(\w+)" Name="(\w+)"', head) if n in types}
        assert got and all(types[k] == v for k, v in got.items())
    write_index(tmp_path / "i.pvtu", ["narrow0.vtu"], cycles=len(comps) > 1, part=parts is not None, types=types)
    listed = {e.get("Name"): e.get("type") for e in ET.parse(tmp_path / "i.pvtu").getroot().iter("PDataArray")}
    assert all(listed[k] == types[k] for k in listed if k in types) and listed["global_id"] == types["global_id"]
