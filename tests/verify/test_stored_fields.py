"""``hammesh check`` compares the cycle fields a file stores (``cycle_position``,
``cycle_id``, ``kind``, ``parent``) with what its rows are (tester18 r03): a viewer that
sorts by ``cycle_position`` must get the cycle the certificate verified."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import hammesh
from hammesh.cli import main
from hammesh.verify.stored import check_stored_fields
from tests.helpers import plate

SUFFIXES = [".vtu", ".vtk", ".msh", ".xdmf", ".ply", ".ele", ".pvtu"]


@pytest.fixture(scope="module")
def two_cycles() -> hammesh.HamiltonianMesh:
    h = hammesh.hamiltonian(plate(1, 2, max_area=0.02))
    assert len(h.components) == 2
    return h


def damaged(h: hammesh.HamiltonianMesh, field: str) -> hammesh.HamiltonianMesh:
    if field == "cycle_position":
        pos = h.position.copy()
        pos[[2, 5]] = pos[[5, 2]]
        return replace(h, position=pos)
    if field == "kind":
        kind = h.kind.copy()
        kind[7] = len(hammesh.KIND_NAMES) + 4
        return replace(h, kind=kind)
    if field == "parent":
        parent = h.parent.copy()
        parent[3] = -5
        return replace(h, parent=parent)
    raise AssertionError(field)


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_untampered_fields_pass(tmp_path: Path, two_cycles, suffix: str) -> None:
    out = tmp_path / f"h{suffix}"
    hammesh.write(two_cycles, out)
    fields = hammesh.read_mesh(out).info.get("cycle_fields", {})
    assert {"kind", "parent"} <= set(fields)  # (.pvtu: global_position stands for the positions)
    assert main(["check", str(out)]) == 0


#: (a .pvtu's positions are its global_position, checked by its reader: test_pvtu_integrity)
DAMAGES = [(s, f) for s in SUFFIXES for f in ("cycle_position", "kind", "parent")
           if not (s == ".pvtu" and f == "cycle_position")]


@pytest.mark.parametrize("suffix, field", DAMAGES)
def test_tampered_fields_fail_the_check(tmp_path: Path, two_cycles, suffix: str, field: str, capsys) -> None:
    out = tmp_path / f"h{suffix}"
    hammesh.write(damaged(two_cycles, field), out)
    assert main(["check", str(out)]) == 3
    err = capsys.readouterr().err
    assert f"stored {field} of triangle" in err


def test_cycle_ids_and_positions_are_derived_from_the_runs() -> None:
    runs = np.array([3, 2])
    good = {"cycle_position": np.array([0, 1, 2, 0, 1]), "cycle_id": np.array([0, 0, 0, 1, 1.0])}
    check_stored_fields(good, runs, 5)
    for name, i, value in [("cycle_id", 3, 0), ("cycle_position", 4, 2), ("cycle_id", 0, 0.5)]:
        bad = {k: v.astype(float) for k, v in good.items()}
        bad[name][i] = value
        with pytest.raises(hammesh.VerificationError, match=f"stored {name} of triangle {i}") as caught:
            check_stored_fields(bad, runs, 5)
        assert caught.value.check == "cycle"
    with pytest.raises(hammesh.VerificationError, match="has 4 values for 5 triangles"):
        check_stored_fields({"kind": np.zeros(4)}, runs, 5)
