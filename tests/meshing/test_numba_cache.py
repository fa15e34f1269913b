"""numba's kernel cache (hammesh.numba_cache): a stale cache is a miss, never an error."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import hammesh.numba_cache as numba_cache

GUARD = Path(numba_cache.__file__)


def _run(pkg_root: Path, code: str, cache: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(pkg_root), "NUMBA_CACHE_DIR": str(cache)}
    return subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=300)


def test_an_index_naming_a_moved_module_is_a_cache_miss(tmp_path) -> None:
    """Regression: a kernel cached while its argument type lived in a module that has
    since moved. numba unpickles the stale index before it checks the source stamp and
    raised ``ModuleNotFoundError`` on the first call; with the guard the kernel is
    compiled again."""
    pkg = tmp_path / "stalepkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "shapes.py").write_text("from typing import NamedTuple\n\n\nclass Pair(NamedTuple):\n    a: int\n    b: int\n")
    (pkg / "mod.py").write_text(textwrap.dedent("""\
        from numba import njit

        from stalepkg.shapes import Pair  # noqa: F401


        @njit(cache=True)
        def f(p):
            return p.a + p.b
        """))
    cache = tmp_path / "cache"
    first = _run(tmp_path, "from stalepkg.mod import f; from stalepkg.shapes import Pair; print(f(Pair(1, 2)))", cache)
    assert first.returncode == 0 and first.stdout.strip() == "3", first.stderr
    # the module moves away; f's file changes (same name and line: same index file)
    (pkg / "shapes.py").unlink()
    (pkg / "mod.py").write_text(textwrap.dedent("""\
        from numba import njit

        PAIR = None  # (the shapes module is gone)


        @njit(cache=True)
        def f(p):
            return p + 1
        """))
    call = "from stalepkg.mod import f; print(f(1))"
    unguarded = _run(tmp_path, call, cache)
    assert unguarded.returncode != 0 and "No module named 'stalepkg.shapes'" in unguarded.stderr
    guard = (
        "import importlib.util as u; s = u.spec_from_file_location('nc', %r); m = u.module_from_spec(s); "
        "s.loader.exec_module(m); assert m.guard_stale_indexes(); " % str(GUARD)
    )
    guarded = _run(tmp_path, guard + call, cache)
    assert guarded.returncode == 0 and guarded.stdout.strip() == "2", guarded.stderr
    # the index was rewritten: the next process loads f without the guard
    again = _run(tmp_path, call, cache)
    assert again.returncode == 0 and again.stdout.strip() == "2", again.stderr


def test_guard_is_installed_on_import_and_idempotent() -> None:
    from numba.core.caching import IndexDataCacheFile

    assert getattr(IndexDataCacheFile._load_index, "_hammesh_guard", False)
    before = IndexDataCacheFile._load_index
    assert numba_cache.guard_stale_indexes()
    assert IndexDataCacheFile._load_index is before  # not wrapped twice


def test_an_entry_holding_another_signatures_code_is_a_cache_miss(tmp_path) -> None:
    """numba's unlocked save: two processes compiling one kernel for two signatures at once
    both write entry ``.1.nbc``, and the index can map ``int64`` to ``float64``'s machine
    code (the kernel then returned 4619567317775286272 for 7). Built here from two caches:
    the int64 index with the float64 entry. With the guard the entry is a miss."""
    pkg = tmp_path / "racepkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "mod.py").write_text("from numba import njit\n\n\n@njit(cache=True)\ndef f(x):\n    return x\n")
    ints, floats, mixed = (tmp_path / name for name in ("ints", "floats", "mixed"))
    assert _run(tmp_path, "from racepkg.mod import f; print(f(7))", ints).stdout.strip() == "7"
    assert _run(tmp_path, "from racepkg.mod import f; print(f(7.5))", floats).stdout.strip() == "7.5"
    index = [p for p in ints.rglob("*.nbi")]
    entry = [p for p in floats.rglob("*.nbc")]
    assert len(index) == 1 and len(entry) == 1
    target = mixed / index[0].relative_to(ints).parent
    target.mkdir(parents=True)
    (target / index[0].name).write_bytes(index[0].read_bytes())
    (target / entry[0].name).write_bytes(entry[0].read_bytes())
    guard = (
        "import importlib.util as u; s = u.spec_from_file_location('nc', %r); m = u.module_from_spec(s); "
        "s.loader.exec_module(m); assert m.guard_stale_indexes(); " % str(GUARD)
    )
    guarded = _run(tmp_path, guard + "from racepkg.mod import f; print(f(7))", mixed)
    assert guarded.returncode == 0 and guarded.stdout.strip() == "7", guarded.stdout + guarded.stderr
