"""``--tiles`` against the domain's size: more tiles than ``tiles.MIN_TILE_TRIANGLES``
estimated triangles each allow is refused naming the most it allows (2,000 tiles of
the demo ended in an internal error, 64 tiles of a small domain made 692x its
triangles, session 17)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import hammesh
from hammesh.errors import InvalidOptionError
from hammesh.parallel.tiles import MIN_TILE_TRIANGLES, decompose

DEMO = Path(hammesh.__file__).parent / "data" / "demo.poly"


def test_decompose_refuses_tiles_below_the_floor_and_takes_the_most_it_names():
    dom = hammesh.read_domain(DEMO)
    with pytest.raises(InvalidOptionError, match=r"tiles=2000 is too many .* at most (\d+) tile") as info:
        decompose(dom, min_angle=30, max_area=0.002, n_tiles=2000)
    most = int(str(info.value).split("at most ")[1].split()[0])
    assert 1 <= most < 2000 and info.value.option == "tiles"
    d = decompose(dom, min_angle=30, max_area=0.002, n_tiles=most)  # (the most it names is taken)
    assert d.n_tiles == most
    assert d.estimate / most >= MIN_TILE_TRIANGLES


def test_the_cli_says_it_in_one_line(tmp_path):
    out = tmp_path / "t.vtu"
    p = subprocess.run([sys.executable, "-m", "hammesh", "mesh", str(DEMO), "-q", "30", "-a", "0.002", "--tiles",
                        "2000", "-o", str(out)], capture_output=True, text=True, timeout=300)
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1 and "--tiles=2000" in p.stderr
    assert not out.exists()


@settings(max_examples=25, deadline=None)
@given(area_exp=st.floats(-3.5, 1.0), workers=st.integers(2, 64))
def test_the_default_tile_count_is_one_the_domain_holds(area_exp: float, workers: int):
    # ``--workers N`` without ``--tiles`` on a small domain: the default count is one
    # ``decompose`` takes (it was refused, exit 2, session 20: Triangle's A at -a 0.02)
    from hammesh.parallel.run import decompose_estimate, default_tiles

    dom = hammesh.read_domain(DEMO)
    area = 10.0 ** area_exp
    est = decompose_estimate(dom, 30, area)
    n = default_tiles(est, workers)
    assert 1 <= n and (n == 1 or est / n >= MIN_TILE_TRIANGLES)
    if n < 64:  # (the big counts are the balance tiles' business, tested elsewhere)
        assert decompose(dom, min_angle=30, max_area=area, n_tiles=n).n_tiles == n
