"""The first call is what a user gets (issue 11, item 7): kernels loaded ahead.

``hammesh.postprocess.load_kernels`` loads the compiled kernels of ``hamiltonian()``;
``quality_mesh`` runs it while Triangle computes in its child process, so that the
CLI's pipeline (mesh, then hamiltonian) does not load them on the critical path.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
import threading

import numpy as np

import hammesh
from hammesh.meshing.isolate import run_isolated
from hammesh.postprocess import load_kernels


def _value() -> int:
    return 42


def _fail() -> None:
    raise RuntimeError("meanwhile failed")


def test_meanwhile_runs_beside_the_child_and_cannot_spoil_the_result() -> None:
    ran = threading.Event()
    assert run_isolated(_value, (), name="test", timeout=60, meanwhile=ran.set) == 42
    assert ran.wait(10)
    assert run_isolated(_value, (), name="test", timeout=60, meanwhile=_fail) == 42


# counts the compiled signatures of every numba kernel hammesh has imported
_SIGNATURES = textwrap.dedent(
    """
    import sys
    from numba.core.registry import CPUDispatcher

    def signatures():
        out = {}
        for name, mod in list(sys.modules.items()):
            if name.startswith("hammesh"):
                for attr, obj in list(vars(mod).items()):
                    if isinstance(obj, CPUDispatcher):
                        out[f"{name}.{attr}"] = len(obj.signatures)
        return out
    """
)


def test_load_kernels_loads_what_hamiltonian_runs() -> None:
    script = _SIGNATURES + textwrap.dedent(
        """
        import hammesh
        from hammesh.postprocess import load_kernels

        dom = hammesh.Domain.from_polygon([[0, 0], [3, 0], [3, 1], [0, 1]], holes=[[[1, 0.4], [2, 0.4], [1.5, 0.6]]])
        mesh = hammesh.quality_mesh(dom, min_angle=25, max_area=0.002, isolate=False)
        load_kernels()
        before = signatures()
        assert sum(before.values()) > 5, before
        h = hammesh.hamiltonian(mesh)
        assert h.report["verified"]
        after = signatures()
        new = {k: v for k, v in after.items() if v != before.get(k, 0)}
        assert not new, f"kernels loaded by the call itself: {new}"
        print("OK")
        """
    )
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=1800)  # may compile every kernel (minutes on a loaded machine)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "OK" in proc.stdout


def test_quality_mesh_loads_the_kernels_while_triangle_runs() -> None:
    script = _SIGNATURES + textwrap.dedent(
        """
        import threading
        import hammesh

        assert sum(signatures().values()) == 0
        dom = hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])
        mesh = hammesh.quality_mesh(dom, min_angle=30, max_area=1e-4)  # isolated (default)
        for t in threading.enumerate():
            if t.name == "hammesh-meanwhile":
                t.join(300)
        before = signatures()
        assert sum(before.values()) > 5, before
        h = hammesh.hamiltonian(mesh)
        new = {k: v for k, v in signatures().items() if v != before.get(k, 0)}
        assert not new, f"kernels loaded by the call itself: {new}"
        print("OK")
        """
    )
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=1800)  # may compile every kernel (minutes on a loaded machine)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "OK" in proc.stdout


def test_load_kernels_is_idempotent_and_harmless() -> None:
    load_kernels()
    load_kernels()
    dom = hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])
    h = hammesh.hamiltonian(hammesh.quality_mesh(dom, min_angle=20, max_area=0.05))
    assert h.report["verified"] and np.sum(h.components) == h.n_triangles


def test_expected_reserve_follows_the_area_bound() -> None:
    """The pages faulted in while Triangle runs: about what incircle ``hamiltonian()``
    takes through ``hammesh.pages.fresh`` for the expected triangle count; none for
    small meshes or without an area bound."""
    from hammesh.meshing import MeshOptions, expected_reserve

    from hammesh import meshing

    dom = hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]], holes=[[[0.4, 0.4], [0.6, 0.4], [0.6, 0.6]]])
    big = expected_reserve(dom, MeshOptions(min_angle=30, max_area=1e-6))
    assert big == 0 or 0.9 * 1.6e6 * meshing.RESERVE_BYTES_PER_TRIANGLE <= big <= 1.6e6 * meshing.RESERVE_BYTES_PER_TRIANGLE
    assert expected_reserve(dom, MeshOptions(min_angle=30, max_area=1e-3)) == 0
    assert expected_reserve(dom, MeshOptions(min_angle=30)) == 0


def test_quality_mesh_faults_a_reserve_that_hamiltonian_takes(monkeypatch) -> None:
    import threading

    from hammesh import meshing, pages

    monkeypatch.setattr(meshing, "RESERVE_MIN_BYTES", 1 << 20)
    pages.release()
    dom = hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])
    mesh = hammesh.quality_mesh(dom, min_angle=30, max_area=5e-5)  # isolated (default)
    for t in threading.enumerate():
        if t.name == "hammesh-meanwhile":
            t.join(300)
    if sys.platform.startswith("linux"):
        assert pages.reserved() > 0
    h = hammesh.hamiltonian(mesh, mode="incircle")
    assert h.report["verified"] and pages.reserved() == 0


def test_the_validations_hilbert_table_is_made_while_triangle_runs(monkeypatch) -> None:
    """For a mesh expected at ``TABLE_AHEAD_MIN_TRIANGLES`` or more, the table of the
    size the mesh turns out to need is made in the waiting thread; not for a small one."""
    import threading

    from hammesh import meshing
    from hammesh.halfedge import locality

    made = []
    real = locality.hilbert_table
    monkeypatch.setattr(locality, "hilbert_table", lambda bits: made.append((threading.current_thread().name, bits))
                        or real(bits))
    monkeypatch.setattr(meshing, "TABLE_AHEAD_MIN_TRIANGLES", 20_000)
    dom = hammesh.Domain.from_polygon([[0, 0], [1, 0], [1, 1], [0, 1]])
    ahead, sizes = {}, {}
    for max_area in (5e-5, 5e-3):
        made.clear()
        mesh = hammesh.quality_mesh(dom, min_angle=30, max_area=max_area)  # isolated (default)
        for t in threading.enumerate():
            if t.name == "hammesh-meanwhile":
                t.join(300)
        ahead[max_area] = [bits for name, bits in made if name == "hammesh-meanwhile"]
        sizes[max_area] = mesh.n_triangles
    # (the first call in a process loads the kernels there too, meshing tiny squares)
    assert sizes[5e-5] >= 20_000 > sizes[5e-3]
    bits = locality.cell_bits(sizes[5e-5])
    assert ahead[5e-5][-1:] == [bits] and bits not in ahead[5e-3]


def test_bench_core_child_leaves_no_file_behind(tmp_path) -> None:
    """The fresh child of ``benchmarks/bench_core.py`` with ``--path ""`` (no mesh to save)
    once wrote Triangle's time to ``.triangle`` in the working directory."""
    from pathlib import Path
    import json

    bench = Path(__file__).parent.parent.parent / "benchmarks" / "bench_core.py"
    proc = subprocess.run(
        [sys.executable, str(bench), "--child", "pipeline", "--max-area", "0.01", "--path", "", "--mode", "incircle"],
        capture_output=True, text=True, timeout=600, cwd=tmp_path,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert out["verified"] and out["triangle_inside"] > 0
    assert list(tmp_path.iterdir()) == []
