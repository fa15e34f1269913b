"""``hammesh mesh``'s choices are spelled in the CLI (parsing imports no registry) and
must stay the registries' names."""

from __future__ import annotations

import subprocess
import sys

from hammesh.cli import mesh


def test_backend_and_mode_names_are_the_registries():
    from hammesh.meshing import BACKENDS
    from hammesh.postprocess import MODES

    assert tuple(sorted(BACKENDS)) == mesh.BACKEND_NAMES
    assert tuple(sorted(MODES)) == mesh.MODE_NAMES


def test_parsing_every_mesh_option_imports_no_library_module():
    """The parallel path starts its local cluster right after parsing: parsing itself
    (``--mode``, ``--backend`` and the rest given) loads none of numba, the meshing or
    post-processing registries, nor the parallel package's modules."""
    code = ("import sys; from hammesh.cli import build_parser; "
            "a = build_parser('mesh').parse_args(['mesh', 'x.poly', '-q', '30', '-a', '1e-3', '--mode', 'incircle', "
            "'--backend', 'triangle', '--renumber', 'rcm', '--workers', '2', '--partitioned', '-o', 'd']); "
            "import hammesh.parallel.command, hammesh.parallel.cluster, hammesh.cli.inputs; "
            "print(a.mode, sorted(m for m in ('numba', 'scipy', 'hammesh.postprocess', 'hammesh.meshing', "
            "'hammesh.domain', 'hammesh.io', 'hammesh.parallel.run', 'hammesh.parallel.tiles', 'dask') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split(maxsplit=1) == ["incircle", "[]\n"]


def test_an_unknown_mode_exits_2_with_the_names():
    p = subprocess.run([sys.executable, "-m", "hammesh", "mesh", "x.poly", "--mode", "nope"], capture_output=True,
                       text=True)
    assert p.returncode == 2
    assert "incircle" in p.stderr and "sparse" in p.stderr and len(p.stderr.strip().splitlines()) == 1


def test_fast_exit_joins_threads_runs_exit_handlers_and_flushes():
    """``fast_exit`` skips only the interpreter's teardown: a non-daemon thread still
    working is joined, every ``atexit`` handler runs, buffered output (a pipe) is
    flushed, and the exit code is the one given."""
    code = ("import atexit, threading, time\n"
            "from hammesh.cli import fast_exit\n"
            "atexit.register(lambda: print('handler ran'))\n"
            "threading.Thread(target=lambda: (time.sleep(0.3), print('thread done'))).start()\n"
            "print('before')\n"
            "fast_exit(7)\n"
            "print('never')\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert p.returncode == 7
    assert p.stdout.splitlines() == ["before", "thread done", "handler ran"]


def test_a_program_calling_main_is_not_the_entry():
    out = subprocess.run([sys.executable, "-c", "from hammesh.cli import is_entry; print(is_entry())"],
                         capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
