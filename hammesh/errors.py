"""Exception hierarchy of hammesh.

Every error hammesh raises derives from :class:`HammeshError`; each subclass also
inherits the builtin it refines, so ``except ValueError`` keeps working for callers
who do not know hammesh.  Messages are one line and name the offending item
(field, index, file, option).
"""

from __future__ import annotations

__all__ = [
    "HammeshError",
    "InvalidDomainError",
    "InvalidMeshError",
    "InvalidOptionError",
    "FileFormatError",
    "NotPlanarError",
    "MeshingError",
    "VerificationError",
    "OutputError",
    "MissingDependencyError",
    "Terminated",
]


class HammeshError(Exception):
    """Base class of every error raised by hammesh."""


class InvalidDomainError(HammeshError, ValueError):
    """A planar straight-line graph (vertices, segments, holes, regions) is invalid."""


class InvalidMeshError(HammeshError, ValueError):
    """A triangle mesh given to an algorithm is not a valid planar triangulation."""


class InvalidOptionError(HammeshError, ValueError):
    """An option value is out of range or impossible (e.g. a min angle Triangle cannot reach).

    ``option`` names the parameter (``"min_angle"``) when the message starts with
    ``"<option>="`` (:func:`hammesh.params.invalid`): the command line then shows its
    own option name there (``--min-angle=50 is not valid: ...``).
    """

    def __init__(self, message: str = "", *, option: str | None = None) -> None:
        super().__init__(message)
        self.option = option

    def __reduce__(self):  # (keeps ``option`` across processes: Dask workers raise it)
        return (type(self), self.args, {"option": self.option})


class FileFormatError(HammeshError, ValueError):
    """A file is missing, empty, truncated, of an unknown format or malformed."""


class NotPlanarError(FileFormatError):
    """A mesh file holds a 3D surface where a planar mesh is needed (z varies)."""


class MeshingError(HammeshError, RuntimeError):
    """The meshing backend failed, crashed or timed out."""


class VerificationError(HammeshError, AssertionError):
    """An output failed its certificate (cycle, orientation, angles, area, conformity).

    ``check`` names the failed check for callers that react to one kind of failure
    (never parse the message): ``"input"`` (shapes, indices, non-finite values),
    ``"cycle"`` (a run breaks or crosses), ``"orientation"`` (an inverted or degenerate
    triangle), ``"overlap"`` (an edge used twice in one direction, a duplicate triangle,
    triangles that overlap in the plane), ``"domain"`` (area, boundary, points or
    constrained edges not kept), ``"angle"`` (a triangle below the angle bound) or
    ``None`` where a check does not say.
    """

    CHECKS = ("input", "cycle", "orientation", "overlap", "domain", "angle")

    def __init__(self, message: str = "", *, check: str | None = None) -> None:
        super().__init__(message)
        self.check = check

    def __reduce__(self):  # (keeps ``check`` across processes: Dask workers raise it)
        return (type(self), self.args, {"check": self.check})


class OutputError(HammeshError, OSError):
    """An output file cannot be written: missing or unwritable directory, full disk, an
    output that is also an input, two outputs naming one file.  The message names the
    target (never a temporary file)."""


class MissingDependencyError(HammeshError, ImportError):
    """An optional dependency (an extra such as ``hammesh[fem]``) is not installed; the
    message names the ``pip install`` that provides it."""


class Terminated(BaseException):
    """The process received ``SIGTERM`` (or ``SIGHUP``); raised by the ``hammesh`` command's
    signal handler so that ``finally`` blocks and temporary-file cleanup run.  Like
    ``KeyboardInterrupt`` it is not an ``Exception``: ``except Exception`` does not stop it."""

    def __init__(self, signum: int = 15) -> None:
        super().__init__(f"terminated by signal {signum}")
        self.signum = signum
