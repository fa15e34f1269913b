"""Output paths checked before any work: never overwrite an input, never a half-done run.

A command that reads some files and writes others calls :func:`check_outputs` first.
It refuses (:class:`~hammesh.errors.OutputError`, naming the path and the option):

* an output whose directory does not exist, is not a directory or is not writable;
* an output that is an existing directory, or whose name is longer than 255 bytes;
* an output that *is* an input, including the siblings a writer adds (``-o m.ele``
  also writes ``m.node`` and ``m.poly``) and those a reader opens (``m.ele`` reads
  ``m.node`` and ``m.poly``): compared by resolved path and, for existing files, by
  device and inode (hard links, ``..``, symlinks);
* two outputs that are one file (``--report x.json --strip x.json``).
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from pathlib import Path

from hammesh.errors import OutputError

__all__ = ["check_outputs", "written_files", "wrote_text", "read_files", "require_file", "wrote_it", "refuse_foreign_companions",
           "TRIANGLE_SIBLINGS"]

#: Triangle's file family: writing or reading one member may touch the others.
TRIANGLE_SIBLINGS = (".node", ".poly", ".ele")

_NAME_MAX = 255


def require_file(path: str | os.PathLike[str], needed_by: str | None = None) -> None:
    """Refuse an input that is not a regular file, in one wording for every reader:
    ``no such file``, ``is a directory``, or ``not a regular file`` (a device or a pipe:
    ``/dev/zero`` behind a ``.poly`` name was read until the memory cap)."""
    from hammesh.errors import FileFormatError

    p = Path(path)
    if p.is_file():
        return
    why = "is a directory" if p.is_dir() else "not a regular file" if p.exists() else "no such file"
    raise FileFormatError(f"{p}: {why}" + (f" (needed by {needed_by})" if needed_by else ""))


def written_files(path: str | os.PathLike[str]) -> list[Path]:
    """The files a mesh write to ``path`` creates.

    ``.ele``/``.node``: the Triangle triple; ``NAME.pvtu``: the index and its one piece
    ``NAME.0.vtu`` (:func:`hammesh.io.pvtu.write`), so both are checked before and removed
    after a failed run.
    """
    path = Path(path)
    if path.suffix.lower() in (".ele", ".node"):
        return [path.with_suffix(s) for s in TRIANGLE_SIBLINGS]
    if path.suffix.lower() == ".pvtu":
        return [path, path.with_name(path.stem + ".0.vtu")]
    return [path]


def wrote_text(path: str | os.PathLike[str]) -> str:
    """``path`` as a "wrote" line names it, with the files its writer adds beside it
    (:func:`written_files`: ``plate.ele (and plate.node, plate.poly)``), so that nothing
    written goes unsaid.

    >>> wrote_text("out/plate.ele"), wrote_text("m.vtu")
    ('out/plate.ele (and out/plate.node, out/plate.poly)', 'm.vtu')
    """
    path = Path(path)
    others = ", ".join(str(f) for f in written_files(path) if f != path)
    return f"{path} (and {others})" if others else str(path)


def wrote_it(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` starts as hammesh's Triangle-format writer starts every file
    (``# hammesh ...``): such a companion of a ``.ele``/``.node`` output is replaced, any
    other file (the user's domain ``NAME.poly``) is not."""
    try:
        with open(path, "rb") as f:
            return f.read(10) == b"# hammesh "
    except OSError:
        return False


def refuse_foreign_companions(path: str | os.PathLike[str], label: str | None = None) -> None:
    """Refuse a mesh output whose writer would also replace a file hammesh did not write:
    ``-o plate.ele`` writes ``plate.node`` and ``plate.poly`` too, and ``plate.poly`` may be
    the user's domain (Triangle itself writes ``plate.1.*`` for that reason).

    Raises
    ------
    OutputError
        Naming the file that would be replaced (and ``label``, the option, if given).
    """
    path = Path(path)
    for f in written_files(path):
        if f != path and f.suffix.lower() in TRIANGLE_SIBLINGS and f.is_file() and not wrote_it(f):
            raise OutputError(f"{f}: exists and is not a file hammesh wrote; writing {path.name} would replace it "
                              "(a Triangle mesh is the .node/.ele/.poly triple); move it or choose another output "
                              f"name{f' ({label})' if label else ''}")


def read_files(path: str | os.PathLike[str]) -> list[Path]:
    """The files reading ``path`` may open: itself, and for a Triangle file its siblings."""
    path = Path(path)
    if path.suffix.lower() in TRIANGLE_SIBLINGS:
        return [path, *(path.with_suffix(s) for s in TRIANGLE_SIBLINGS if s != path.suffix.lower())]
    return [path]


def _identity(path: Path) -> tuple[str, tuple[int, int] | None]:
    resolved = os.path.realpath(path)
    try:
        st = os.stat(path)
    except OSError:
        return resolved, None
    return resolved, (st.st_dev, st.st_ino)


def _same(a: tuple[str, tuple[int, int] | None], b: tuple[str, tuple[int, int] | None]) -> bool:
    return a[0] == b[0] or (a[1] is not None and a[1] == b[1])


def _check_writable(path: Path, label: str) -> None:
    if not path.name:
        raise OutputError(f"{path}: not a file name ({label})")
    if len(os.fsencode(path.name)) > _NAME_MAX:
        raise OutputError(f"{path}: file name longer than {_NAME_MAX} bytes ({label})")
    if path.is_dir():
        raise OutputError(f"{path}: is a directory ({label})")
    parent = path.parent
    if not parent.exists():
        raise OutputError(f"{path}: directory {parent} does not exist ({label})")
    if not parent.is_dir():
        raise OutputError(f"{path}: {parent} is not a directory ({label})")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise OutputError(f"{path}: directory {parent} is not writable ({label})")


def check_outputs(
    outputs: Mapping[str, str | os.PathLike[str] | None],
    inputs: Iterable[str | os.PathLike[str]] = (),
    *,
    make_dirs: Iterable[str | os.PathLike[str]] = (),
) -> None:
    """Refuse, before any work, outputs that cannot be written or would destroy an input.

    Parameters
    ----------
    outputs : mapping
        Option label (``"-o"``, ``"--report"``...) -> path, or None (not asked for).
        Mesh paths are expanded to every file the writer creates (:func:`written_files`).
    inputs : iterable of path-like
        Files the command reads, expanded to the files their readers open
        (:func:`read_files`).
    make_dirs : iterable of path-like
        Directories the command will create itself (``hammesh demo --out``): an output
        inside one is checked against its first existing ancestor.

    Raises
    ------
    OutputError
        The first problem found; the message names the path and the option.
    """
    pending = {Path(d) for d in make_dirs if not Path(d).exists()}
    inputs_seen = [(Path(f), _identity(Path(f))) for p in inputs for f in read_files(p)]
    outputs_seen: list[tuple[str, Path, tuple[str, tuple[int, int] | None]]] = []
    for label, given in outputs.items():
        if given is None:
            continue
        for f in written_files(given):
            if f.parent in pending:
                parent = f.parent
                while not parent.exists() and parent != parent.parent:
                    parent = parent.parent
                if not parent.is_dir() or not os.access(parent, os.W_OK | os.X_OK):
                    raise OutputError(f"{f}: cannot create directory {f.parent} ({label})")
            else:
                _check_writable(f, label)
            ident = _identity(f)
            for src, src_ident in inputs_seen:
                if _same(ident, src_ident):
                    extra = "" if f == Path(given) else f" (written with {Path(given).name})"
                    raise OutputError(f"{f}: is an input file{extra}; choose another output name ({label})")
            for other_label, other, other_ident in outputs_seen:
                if _same(ident, other_ident):
                    raise OutputError(f"{f}: given twice as output ({other_label} and {label})")
            outputs_seen.append((label, f, ident))
        refuse_foreign_companions(given, label)  # (after the input checks: theirs is the better message)
