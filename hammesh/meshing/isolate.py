"""Run a C mesher in a child process, so that no input can take the caller down.

Triangle and meshpy can crash the interpreter (SIGSEGV) or loop forever on inputs
that slip past validation. ``run_isolated`` forks a child (on platforms with
``fork``; else spawns one), lets it compute, and receives the result through a
pipe. A crash becomes :class:`~hammesh.errors.MeshingError` naming the signal, an
overrun of ``timeout`` kills the child.
"""

from __future__ import annotations

import faulthandler
import multiprocessing as mp
import os
import signal
import tempfile
import warnings
from typing import Any, Callable

from hammesh.errors import HammeshError, MeshingError

__all__ = ["run_isolated"]


def _c_output(log: Any) -> str:
    """The last line the C code printed (Triangle explains failures on stdout)."""
    try:
        log.flush()
        log.seek(0)
        lines = [ln.strip() for ln in log.read().decode(errors="replace").splitlines()]
        lines = [ln for ln in lines if ln]
        return " | ".join(lines[-3:])
    except OSError:
        return ""


def _child(conn: Any, func: Callable[..., Any], args: tuple[Any, ...]) -> None:
    # the C library prints to file descriptors 1/2 directly: keep that out of the
    # caller's terminal and use it to explain a failure instead
    faulthandler.disable()  # a crash is reported by the parent (signal name), not dumped
    log = tempfile.TemporaryFile()
    os.dup2(log.fileno(), 1)
    os.dup2(log.fileno(), 2)
    try:
        conn.send(("ok", func(*args)))
    except HammeshError as exc:  # keep hammesh's own errors as they are
        conn.send(("hammesh", exc))
    except BaseException as exc:  # noqa: BLE001 - reported to the parent, one line
        said = _c_output(log)
        conn.send(("error", f"{type(exc).__name__}: {exc}" + (f" ({said})" if said else "")))
    finally:
        conn.close()


def run_isolated(func: Callable[..., Any], args: tuple[Any, ...], *, name: str, timeout: float | None) -> Any:
    """Call ``func(*args)`` in a child process and return its result.

    Parameters
    ----------
    func : picklable callable (module-level function)
    args : tuple
    name : str
        What runs, for messages ("Triangle").
    timeout : float or None
        Seconds before the child is killed; None waits forever.

    Raises
    ------
    MeshingError
        The child crashed, was killed, timed out or raised a non-hammesh error.
    HammeshError
        Re-raised as the child raised it.
    """
    method = "fork" if "fork" in mp.get_all_start_methods() else "spawn"
    ctx = mp.get_context(method)
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(send, func, args), daemon=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)  # fork with threads (3.12+)
        proc.start()
    send.close()
    try:
        if not recv.poll(timeout):
            proc.kill()
            proc.join()
            raise MeshingError(f"{name} did not finish within {timeout:g} s and was stopped")
        try:
            msg = recv.recv()
        except (EOFError, OSError):
            proc.join()
            code = proc.exitcode
            if code is not None and code < 0:
                try:
                    sig = signal.Signals(-code).name
                except ValueError:
                    sig = f"signal {-code}"
                raise MeshingError(f"{name} crashed ({sig}) on this input") from None
            raise MeshingError(f"{name} exited (code {code}) without a result") from None
    finally:
        recv.close()
        if proc.is_alive():
            proc.join(5)
            if proc.is_alive():
                proc.kill()
    proc.join()
    if msg[0] == "ok":
        return msg[1]
    if msg[0] == "hammesh":
        raise msg[1]
    raise MeshingError(f"{name} failed: {msg[1]}")
