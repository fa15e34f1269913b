"""Atomic file output: write to a temporary sibling, then ``os.replace`` it onto the target.

A reader never sees a half-written file: the target is either the old file (or absent)
or the complete new one.  The temporary file lives in the target's directory (so
``os.replace`` is a rename on one file system) and keeps the target's suffix (so
libraries that pick a format from the extension, like meshio, still work), e.g.
``plate.vtu`` is written as ``.plate.vtu.tmp-4711-1a2b3c4d.vtu`` first (``4711``: the
writing process).

Temporary files never outlive their writer for long:

* any exception, ``KeyboardInterrupt`` or (in the ``hammesh`` command, which turns
  ``SIGTERM`` into :class:`~hammesh.errors.Terminated`) termination removes them;
* a ``SIGKILL`` cannot be caught: the next atomic write into the same directory removes
  every temporary file of this module whose writing process is gone
  (:func:`remove_stale_temps`).

Errors of the file system (missing directory, permission, full disk) are raised as
:class:`~hammesh.errors.OutputError` naming the *target*, never the temporary name.
A target name of up to 255 bytes works: the temporary name shortens the copied name to
stay within the file-system limit.

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
import re
import secrets
from collections.abc import Iterator, Sequence
from pathlib import Path

from hammesh.errors import OutputError

__all__ = [
    "atomic_path",
    "atomic_paths",
    "atomic_write_text",
    "temp_sibling",
    "remove_stale_temps",
    "is_temp_name",
]

_MAX_TRIES = 100
_NAME_MAX = 255  # bytes, ext4/xfs/btrfs/tmpfs
_SUFFIX_MAX = 16
#: ``.<name>.tmp-<pid>-<8 hex><suffix>``
_TEMP_RE = re.compile(r"^\..*\.tmp-(\d+)-[0-9a-f]{8}(\.[^./]{0,16})?$", re.DOTALL)


def is_temp_name(name: str) -> bool:
    """True if ``name`` is a temporary file name made by :func:`temp_sibling`."""
    return _TEMP_RE.match(name) is not None


def _pid_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):  # another user's live process / absurd pid
        return True
    return True


def remove_stale_temps(directory: str | os.PathLike[str]) -> list[Path]:
    """Remove the temporary files of :func:`temp_sibling` in ``directory`` whose writer is gone.

    A process killed by ``SIGKILL`` (or a power cut) cannot clean up after itself; its
    temporary files carry its pid, and a pid that no longer runs cannot finish them.
    Errors (unreadable directory, a file removed meanwhile) are ignored.

    Returns
    -------
    list of Path
        The files removed.
    """
    removed: list[Path] = []
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return removed
    for entry in entries:
        match = _TEMP_RE.match(entry.name)
        if match is None or _pid_alive(int(match.group(1))):
            continue
        with contextlib.suppress(OSError):
            if entry.is_file(follow_symlinks=False):
                os.remove(entry.path)
                removed.append(Path(entry.path))
    return removed


def _temp_name(target: Path) -> str:
    suffix = target.suffix if len(target.suffix) <= _SUFFIX_MAX else ""
    tail = f".tmp-{os.getpid()}-{secrets.token_hex(4)}{suffix}"
    budget = _NAME_MAX - 1 - len(tail.encode())
    stem = target.name.encode(errors="surrogateescape")[:budget].decode(errors="ignore")
    return f".{stem}{tail}"


def _output_error(target: Path, exc: OSError) -> OutputError:
    reason = exc.strerror or str(exc) or type(exc).__name__
    return OutputError(f"{target}: cannot write ({reason})")


def temp_sibling(path: str | os.PathLike[str]) -> Path:
    """Create (exclusively, empty) and return a temporary sibling of ``path``.

    The name is ``.<name>.tmp-<pid>-<8 hex digits><suffix>`` (``<name>`` shortened if
    the whole would exceed 255 bytes); permissions follow the umask as for any new file.

    Raises
    ------
    OutputError
        The directory does not exist or is not writable (the message names ``path``).
    """
    target = Path(path)
    parent = target.parent
    for _ in range(_MAX_TRIES):
        tmp = parent / _temp_name(target)
        try:
            fd = os.open(tmp, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666)
        except FileExistsError:
            continue
        except OSError as exc:
            raise _output_error(target, exc) from None
        os.close(fd)
        return tmp
    raise OutputError(f"{target}: could not create a temporary file next to it")


def _remove_quietly(path: Path) -> None:
    with contextlib.suppress(OSError):
        os.remove(path)


@contextlib.contextmanager
def atomic_paths(paths: Sequence[str | os.PathLike[str]]) -> Iterator[list[Path]]:
    """Yield one temporary path per target; replace all targets only if the block succeeds.

    Parameters
    ----------
    paths : sequence of path-like
        Targets, replaced in this order (put the file that readers open first last,
        e.g. ``.node`` before ``.ele``).

    On any exception (including ``KeyboardInterrupt`` and
    :class:`~hammesh.errors.Terminated`) every temporary file is removed, the targets
    are left untouched and the exception propagates; an ``OSError`` is re-raised as
    :class:`~hammesh.errors.OutputError` naming the target.
    """
    targets = [Path(p) for p in paths]
    for directory in dict.fromkeys(t.parent for t in targets):
        remove_stale_temps(directory)
    temps: list[Path] = []
    try:
        for target in targets:
            temps.append(temp_sibling(target))
        try:
            yield list(temps)
        except OSError as exc:
            if isinstance(exc, OutputError):
                raise
            # the writer names the temporary file: name the target instead
            named = next((t for t, tmp in zip(targets, temps) if str(tmp) == exc.filename), targets[-1])
            raise _output_error(named, exc) from None
        for tmp, target in zip(temps, targets):
            try:
                os.replace(tmp, target)
            except OSError as exc:
                raise _output_error(target, exc) from None
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
