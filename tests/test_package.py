"""The package's top level: every public name resolves, and ``import hammesh`` is light."""

from __future__ import annotations

import subprocess
import sys
import types

import hammesh


def test_every_public_name_resolves() -> None:
    for name in hammesh.__all__:
        value = getattr(hammesh, name)
        assert value is not None, name
    assert set(hammesh.__all__) <= set(dir(hammesh))


def test_every_module_defines_what_its_all_lists() -> None:
    # a name in a module's __all__ that it does not define breaks `from module import *`
    import importlib
    import pkgutil

    missing = []
    for info in pkgutil.walk_packages(hammesh.__path__, "hammesh."):
        if info.name == "hammesh.__main__":  # (runs the command line)
            continue
        module = importlib.import_module(info.name)
        missing += [f"{info.name}.{name}" for name in getattr(module, "__all__", ()) if not hasattr(module, name)]
    assert missing == []


def test_unknown_name_is_an_attribute_error() -> None:
    try:
        hammesh.no_such_name  # noqa: B018
    except AttributeError as exc:
        assert "no_such_name" in str(exc)
    else:  # pragma: no cover - the assertion below reports it
        raise AssertionError("hammesh.no_such_name did not raise AttributeError")


def test_functions_named_like_their_subpackage_stay_functions() -> None:
    # importing the subpackages (again) must not rebind hammesh.verify / .partition
    import hammesh.partition  # noqa: F401
    import hammesh.verify.certificate  # noqa: F401

    assert callable(hammesh.verify) and not isinstance(hammesh.verify, types.ModuleType)
    assert callable(hammesh.partition) and not isinstance(hammesh.partition, types.ModuleType)
    assert hammesh.verify is sys.modules["hammesh.verify"].verify
    assert hammesh.partition is sys.modules["hammesh.partition"].partition


def test_import_loads_no_kernel_module() -> None:
    # a fresh interpreter: `import hammesh` must not import the meshing, certificate or
    # strips code (every CLI call and Dask worker paid for it); first use still works
    code = (
        "import sys, hammesh\n"
        "loaded = sorted(m for m in sys.modules if m.startswith('hammesh.'))\n"
        "print(','.join(loaded))\n"
        "hammesh.strips\n"
        "print('hammesh.strips' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split("\n")
    loaded = set(out[0].split(",")) - {""}
    assert loaded <= {"hammesh.errors", "hammesh.numba_cache"}, loaded
    assert out[1] == "True"


def test_import_does_not_import_numba_and_the_cache_guard_follows_it() -> None:
    # `import hammesh` used to import numba (~1 s of every CLI call, `--help` and exit-2
    # errors included) only to patch its cache classes; the patch now waits for numba's
    # own import (an import hook) and is in place before any kernel can load
    code = (
        "import sys, hammesh\n"
        "print('numba' in sys.modules)\n"
        "import numba\n"
        "from numba.core.caching import IndexDataCacheFile as F\n"
        "print(getattr(F._load_index, '_hammesh_guard', False), getattr(F.load, '_hammesh_guard', False))\n"
        "print(any(type(f).__name__ == '_GuardOnImport' for f in sys.meta_path))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split("\n")
    assert out[0] == "False"
    assert out[1] == "True True"
    assert out[2] == "False"  # the hook leaves once it has run


def test_cache_guard_is_in_place_when_numba_came_first() -> None:
    code = (
        "import numba, hammesh\n"
        "from numba.core.caching import IndexDataCacheFile as F\n"
        "print(getattr(F._load_index, '_hammesh_guard', False))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "True"

