"""Where numba keeps hammesh's compiled kernels, and a fallback when nowhere is writable.

The kernels are compiled with ``cache=True``.  numba stores the cache in the package's
``__pycache__`` if it can write there, else in the user's cache directory
(``$XDG_CACHE_HOME/numba`` or ``~/.cache/numba``); a non-root user of a read-only
installation with an unwritable or missing ``HOME`` has neither, and numba then fails at
import time ("cannot cache function ...: no locator available").  :func:`ensure_cache`
runs before any kernel module is imported: if neither place is writable (and the user
did not set ``NUMBA_CACHE_DIR``), kernels are cached in a private temporary directory
for this process only, with one warning — the same as no caching.

Stale caches are harmless (:func:`guard_stale_indexes`): numba unpickles a cache
index *before* it compares the index's source stamp with the source file, and an
index written before a module moved names classes by their old module
(``hammesh._kernels``): the unpickling raised ``ModuleNotFoundError`` on import
although the index was stale anyway. An index (or cache entry) that cannot be read is
now a cache miss: the kernel is compiled again and the index rewritten.

Nothing here imports numba (~1 s): ``import hammesh`` runs :func:`ensure_cache`, and
the guard is installed when numba's caching module is first imported (an import hook,
:func:`guard_on_import`), so ``hammesh --help`` and a refused input pay no numba.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import os
import sys
import tempfile
import threading
import warnings
from pathlib import Path
from typing import Any

__all__ = ["ensure_cache", "writable_dir", "guard_stale_indexes", "guard_on_import", "CACHING_MODULE"]

#: numba's module whose cache classes :func:`guard_stale_indexes` patches (imported by
#: ``import numba`` itself)
CACHING_MODULE = "numba.core.caching"


def writable_dir(path: str | os.PathLike[str]) -> bool:
    """True if ``path`` is (or can be made) a directory this process can write to."""
    try:
        os.makedirs(path, exist_ok=True)
        with tempfile.TemporaryFile(dir=path):
            pass
    except OSError:
        return False
    return True


def _user_cache() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "numba"


def guard_stale_indexes() -> bool:
    """Make an unreadable numba cache index or entry a cache miss instead of an error.

    Wraps ``numba.core.caching.IndexDataCacheFile._load_index`` (an index that does not
    unpickle reads as empty, as numba already treats an index of another numba
    version) and ``.load`` (an entry that does not unpickle, or holds another
    signature's code after numba's unlocked save raced, is not found). Any numba
    cache in this process benefits; a fresh cache is read exactly as before. Returns
    False if this numba has no such methods (nothing patched). Idempotent.
    """
    try:
        from numba.core.caching import IndexDataCacheFile
    except ImportError:  # pragma: no cover - numba is a dependency
        return False
    load_index = getattr(IndexDataCacheFile, "_load_index", None)
    load = getattr(IndexDataCacheFile, "load", None)
    if load_index is None or load is None:
        return False
    if getattr(load_index, "_hammesh_guard", False):
        return True

    def _load_index(self):  # type: ignore[no-untyped-def]
        try:
            return load_index(self)
        except Exception:  # noqa: BLE001 - any unreadable index: stale, start afresh
            return {}

    def _load(self, key):  # type: ignore[no-untyped-def]
        try:
            data = load(self, key)
        except Exception:  # noqa: BLE001 - an entry naming a moved module: a miss
            return None
        try:
            # numba's save is not locked: two processes compiling one kernel for two
            # signatures at once both name their entry "<prefix>.<k>.nbc" and one
            # overwrites the other, so the index can map a signature to the other
            # signature's machine code (numba issues #4807, #10128; session 18 made a
            # toy kernel return 4619567317775286272 for 7 that way). An entry whose
            # stored signature is not the key's is a miss: numba compiles and saves
            # it again.
            stored = tuple(data[3].args)
            wanted = tuple(getattr(key[0], "args", key[0]))
            if stored != wanted:
                return None
        except Exception:  # noqa: BLE001 - another layout: trust numba's own lookup
            pass
        return data

    _load_index._hammesh_guard = True  # type: ignore[attr-defined]
    _load._hammesh_guard = True  # type: ignore[attr-defined]
    IndexDataCacheFile._load_index = _load_index
    IndexDataCacheFile.load = _load
    return True


class _GuardOnImport(importlib.abc.MetaPathFinder):
    """Finds nothing itself: hands numba's caching module to the usual finders and
    patches it (:func:`guard_stale_indexes`) right after it has run, before any
    kernel can be compiled or loaded; then leaves ``sys.meta_path``."""

    def __init__(self) -> None:
        self._busy = threading.local()

    def find_spec(self, fullname: str, path: Any, target: Any = None) -> Any:
        if fullname != CACHING_MODULE or getattr(self._busy, "on", False):
            return None
        self._busy.on = True
        try:  # the spec the other finders give (this one skips itself meanwhile)
            spec = importlib.machinery.PathFinder.find_spec(fullname, path, target)
        finally:
            self._busy.on = False
        loader = getattr(spec, "loader", None)
        if spec is None or not hasattr(loader, "exec_module"):
            return spec  # (a loader of another kind: patched by a later ensure_cache)
        spec.loader = _PatchAfter(loader)
        return spec


class _PatchAfter(importlib.abc.Loader):
    """A module's own loader, then :func:`guard_stale_indexes`."""

    def __init__(self, loader: Any) -> None:
        self._loader = loader

    def create_module(self, spec: Any) -> Any:
        return self._loader.create_module(spec)

    def exec_module(self, module: Any) -> None:
        self._loader.exec_module(module)
        _remove_hook()
        guard_stale_indexes()

    def __getattr__(self, name: str) -> Any:  # get_source, get_filename, ... as the loader's
        return getattr(self._loader, name)


_hook: _GuardOnImport | None = None


def _remove_hook() -> None:
    global _hook
    if _hook is not None and _hook in sys.meta_path:
        sys.meta_path.remove(_hook)
    _hook = None


def guard_on_import() -> bool:
    """:func:`guard_stale_indexes` now if numba's caching module is imported already,
    else as soon as it is (an import hook, removed once it has run). Never imports
    numba. Returns True if the guard is in place now."""
    global _hook
    if CACHING_MODULE in sys.modules:
        _remove_hook()
        return guard_stale_indexes()
    if _hook is None:
        _hook = _GuardOnImport()
        sys.meta_path.insert(0, _hook)
    return False


def ensure_cache(candidates: list[Path] | None = None) -> str | None:
    """Make numba's kernel cache usable; return the fallback directory if one was needed.

    Parameters
    ----------
    candidates : list of Path, optional
        The directories numba would try (default: this package's ``__pycache__`` and
        the user cache directory).
    """
    guard_on_import()
    if os.environ.get("NUMBA_CACHE_DIR"):
        return None  # the user chose; numba reports problems with it itself
    if candidates is None:
        candidates = [Path(__file__).parent / "__pycache__", _user_cache()]
    if any(writable_dir(c) for c in candidates):
        return None
    fallback = tempfile.mkdtemp(prefix="hammesh-numba-")
    os.environ["NUMBA_CACHE_DIR"] = fallback
    config = sys.modules.get("numba.core.config")
    if config is not None:  # numba imported by the caller already: its config is read once
        config.CACHE_DIR = fallback
    warnings.warn(
        f"hammesh: no writable numba cache directory ({', '.join(map(str, candidates))}); "
        "compiled kernels are not kept after this process (set NUMBA_CACHE_DIR to keep them)",
        RuntimeWarning,
        stacklevel=2,
    )
    return fallback
