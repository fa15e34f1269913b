"""Atomic file output: write to a temporary sibling, then ``os.replace`` it onto the target.

A reader never sees a half-written file: the target is either the old file (or absent)
or the complete new one.  The temporary file lives in the target's directory (so
``os.replace`` is a rename on one file system) and keeps the target's suffix (so
libraries that pick a format from the extension, like meshio, still work), e.g.
``plate.vtu`` is written as ``.plate.vtu.tmp-1a2b3c4d.vtu`` first.

Examples
--------
>>> import os, tempfile
>>> d = tempfile.mkdtemp()
>>> target = os.path.join(d, "a.txt")
>>> with atomic_path(target) as tmp:
...     with open(tmp, "w") as f:
...         _ = f.write("hello")
>>> open(target).read()
'hello'
>>> os.listdir(d)
['a.txt']
"""

from __future__ import annotations

import contextlib
import os
import secrets
from collections.abc import Iterator, Sequence
from pathlib import Path

__all__ = ["atomic_path", "atomic_paths", "atomic_write_text", "temp_sibling"]

_MAX_TRIES = 100


def temp_sibling(path: str | os.PathLike[str]) -> Path:
    """Create (exclusively, empty) and return a temporary sibling of ``path``.

    The name is ``.<name>.tmp-<8 hex digits><suffix>``; permissions follow the umask
    as for any new file.
    """
    target = Path(path)
    parent = target.parent
    for _ in range(_MAX_TRIES):
        tmp = parent / f".{target.name}.tmp-{secrets.token_hex(4)}{target.suffix}"
        try:
            fd = os.open(tmp, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666)
        except FileExistsError:
            continue
        os.close(fd)
        return tmp
    raise FileExistsError(f"{target}: could not create a temporary file next to it")


def _remove_quietly(path: Path) -> None:
    with contextlib.suppress(FileNotFoundError):
        os.remove(path)


@contextlib.contextmanager
def atomic_paths(paths: Sequence[str | os.PathLike[str]]) -> Iterator[list[Path]]:
    """Yield one temporary path per target; replace all targets only if the block succeeds.

    Parameters
    ----------
    paths : sequence of path-like
        Targets, replaced in this order (put the file that readers open first last,
        e.g. ``.node`` before ``.ele``).

    On any exception (including ``KeyboardInterrupt``) every temporary file is removed,
    the targets are left untouched and the exception propagates.
    """
    targets = [Path(p) for p in paths]
    temps: list[Path] = []
    try:
        for target in targets:
            temps.append(temp_sibling(target))
        yield list(temps)
        for tmp, target in zip(temps, targets):
            os.replace(tmp, target)
    except BaseException:
        for tmp in temps:
            _remove_quietly(tmp)
        raise


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary sibling path of ``path``; ``os.replace`` it onto ``path`` on success.

    Parameters
    ----------
    path : path-like
        The target file.  Its directory must exist.

    On any exception the temporary file is removed, ``path`` is left as it was, and the
    exception propagates.  The temporary file already exists (empty) when yielded;
    writers simply overwrite it.
    """
    with atomic_paths([path]) as (tmp,):
        yield tmp


def atomic_write_text(path: str | os.PathLike[str], text: str, encoding: str = "utf-8") -> None:
    """Write ``text`` to ``path`` atomically (see :func:`atomic_path`)."""
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding=encoding, newline="\n") as f:
            f.write(text)
