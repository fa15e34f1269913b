"""The ``hammesh`` command line: one module per subcommand.

Each subcommand module has ``add_args(parser)`` and ``run(args) -> int``. ``main``
turns every hammesh error into one line on stderr and an exit code:

====  =====================================================
0     success
2     bad input, bad option or usage (nothing is written)
3     verification failed (nothing is written)
1     unexpected internal error (set HAMMESH_DEBUG=1 for the traceback)
130   interrupted (Ctrl-C)
143   terminated (SIGTERM, e.g. by ``timeout``; 129 for SIGHUP)
====  =====================================================

Only the chosen subcommand's options are built (:func:`build_parser`): its module
imports the registries its choices come from, and the library is imported by ``run``,
so ``hammesh --help`` or a usage error costs no kernel module (nor numba).

Messages are one line: a newline or other control character in a file name is shown
escaped.  ``SIGTERM`` and ``SIGHUP`` raise :class:`~hammesh.errors.Terminated` in the
main thread, so every temporary file is removed and no target is half-written.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import signal
import sys
import warnings
from typing import Any
from collections.abc import Sequence

from hammesh.cli import check, demo, mesh, partition, points, polygon, strip, surface
from hammesh.errors import HammeshError, InvalidOptionError, Terminated, VerificationError

__all__ = ["main", "build_parser", "option_message", "LIBRARY_NAMES", "chosen_command", "with_bare_values", "one_line", "exit_fast", "fast_exit", "is_entry", "COMMANDS", "EXIT_OK", "EXIT_BAD_INPUT", "EXIT_VERIFICATION", "EXIT_INTERNAL"]

EXIT_OK, EXIT_INTERNAL, EXIT_BAD_INPUT, EXIT_VERIFICATION = 0, 1, 2, 3
#: stdout closed by its reader (128 + SIGPIPE, as the shell reports a program killed by it)
EXIT_BROKEN_PIPE = 141

#: subcommand name -> module with add_args / run (and a one-line HELP)
COMMANDS = {"mesh": mesh, "check": check, "strip": strip, "polygon": polygon, "points": points, "surface": surface, "demo": demo,
            "partition": partition}


#: Library parameter names whose command-line option has another name (``hammesh mesh
#: --parts K`` calls ``partition(h, k=K)``).
LIBRARY_NAMES = {"k": "parts"}


class _Parser(argparse.ArgumentParser):
    """One-line errors; knows its subcommands' parsers (``commands``)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.commands: dict[str, _Parser] = {}

    def option_flag(self, dest: str) -> str | None:
        """The longest flag of the option stored in ``dest`` (``--min-angle``), if any."""
        # (argparse keeps every action, also those of argument groups, in ``_actions``)
        for action in self._actions:
            if action.dest == dest and action.option_strings:
                return max(action.option_strings, key=len)
        return None

    def error(self, message: str) -> None:  # one line, exit 2, as for any bad input
        self.exit(EXIT_BAD_INPUT, one_line(f"{self.prog}: error: {message}") + "\n")


def option_message(exc: HammeshError, parser: _Parser, command: str | None) -> str:
    """``exc``'s message with the library's parameter name (``min_angle=50 is not
    valid``) replaced by the command's option (``--min-angle=50 is not valid``)."""
    text = str(exc)
    name = getattr(exc, "option", None)
    sub = parser.commands.get(command or "")
    if not isinstance(exc, InvalidOptionError) or not name or sub is None or not text.startswith(f"{name}="):
        return text
    flag = sub.option_flag(name) or sub.option_flag(LIBRARY_NAMES.get(name, ""))
    return flag + text[len(name):] if flag else text


def chosen_command(argv: Sequence[str] | None) -> str | None:
    """The subcommand ``argv`` names (its first word not starting with ``-``), if any."""
    words = sys.argv[1:] if argv is None else list(argv)
    first = next((w for w in words if not w.startswith("-")), None)
    return first if first in COMMANDS else None


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The ``hammesh`` parser; only ``command``'s options are added (all if "all").

    Every subcommand is listed with its help line; building the options of the one
    that runs is enough to parse, and keeps the others' imports away from it.
    """
    from hammesh import __version__

    parser = _Parser(
        prog="hammesh",
        description="Guaranteed-quality triangle meshes whose triangles form one "
        "Hamiltonian cycle of the dual graph, verified (Arkin, Held, Mitchell, Skiena: "
        "Hamiltonian triangulations; sparse mode by default, Thm 2.4 as --mode incircle).",
        epilog="Exit codes: 0 ok, 2 bad input or usage, 3 verification failed, 1 internal error, "
        "141 stdout closed (outputs written).",
    )
    parser.add_argument("--version", action="version", version=f"hammesh {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for name, module in COMMANDS.items():
        p = sub.add_parser(
            name,
            help=module.HELP,
            description=module.HELP,
            epilog=module.EXAMPLES,
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        parser.commands[name] = p
        if command in (name, "all"):
            module.add_args(p)
        p.set_defaults(_run=module.run)
    return parser


def one_line(text: object) -> str:
    """``text`` on one line: control characters (a newline in a file name) escaped."""
    s = str(text)
    if s.isprintable():
        return s
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in s)


def _say(message: str) -> None:
    print(one_line(message), file=sys.stderr)


def _terminate(signum: int, frame: object) -> None:
    raise Terminated(signum)


def _interruption(exc: BaseException) -> BaseException | None:
    """The Terminated/KeyboardInterrupt behind ``exc``, if any.

    A signal handler that raises while a numba kernel is returning makes the
    dispatcher report ``SystemError: CPUDispatcher(...) returned a result with an
    exception set`` with the handler's exception as its context (seen under SIGTERM in
    ``test_defect8_real_sigterm_to_the_command``): still a termination, not a bug.
    """
    seen = 0
    e: BaseException | None = exc
    while e is not None and seen < 20:
        if isinstance(e, (Terminated, KeyboardInterrupt)):
            return e
        e = e.__cause__ or e.__context__
        seen += 1
    return None


def _install_signal_handlers() -> dict[int, object]:
    """SIGTERM/SIGHUP -> :class:`Terminated` (main thread only); returns the old handlers."""
    old: dict[int, object] = {}
    for name in ("SIGTERM", "SIGHUP"):
        signum = getattr(signal, name, None)
        if signum is None:
            continue
        try:
            old[signum] = signal.signal(signum, _terminate)
        except ValueError:  # not the main thread (an embedding application)
            break
    return old


_fast_exit = False


def exit_fast() -> None:
    """Ask :func:`main`, when it runs as the process's entry (the ``hammesh`` script or
    ``python -m hammesh``), to end the process with :func:`fast_exit` once the command
    returns (the parallel path asks: ``hammesh.parallel.command``)."""
    global _fast_exit
    _fast_exit = True


def is_entry() -> bool:
    """Whether this process runs the ``hammesh`` command itself (``__main__`` is the
    console script or ``hammesh.__main__``), not a program that calls :func:`main`."""
    m = sys.modules.get("__main__")
    spec = getattr(m, "__spec__", None)
    if spec is not None and spec.name == "hammesh.__main__":
        return True
    name = os.path.basename(getattr(m, "__file__", None) or "")
    return name in ("hammesh", "hammesh.exe", "hammesh-script.py")


def fast_exit(code: int) -> None:
    """End this process now with ``code``, after everything an exit must do, without
    the interpreter's teardown.

    The non-daemon threads are joined and every ``atexit`` handler runs (Dask's,
    ``tempfile``'s and ``weakref.finalize``'s clean-ups, logging's flush), then stdout
    and stderr are flushed and ``os._exit`` ends the process: what is skipped is
    Python's destruction of every module and object it made, which after a local Dask
    cluster and numba took 0.15-0.18 s of the command's wall time (measured at 0.3M
    triangles, 6 alternating runs, load 7: the output's end to the process's end
    0.28 s median against 0.11 s); the system frees the memory at once. Every output
    file is closed (and renamed into place) before the command returns.
    Falls back to ``sys.exit`` where the interpreter has no such hooks.
    """
    import atexit
    import threading

    shutdown = getattr(threading, "_shutdown", None)
    run_exit = getattr(atexit, "_run_exitfuncs", None)
    if shutdown is None or run_exit is None:  # pragma: no cover - not CPython
        sys.exit(code)
    try:
        shutdown()  # (the non-daemon threads joined, as at a normal exit, first)
        run_exit()
    finally:
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError, AttributeError):
                pass
        os._exit(code)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``hammesh`` console script; returns the exit code (as the
    entry of a command that asked for it, :func:`exit_fast`, ends the process instead)."""
    old = _install_signal_handlers()
    try:
        code = _main(argv)
    finally:
        for signum, handler in old.items():
            signal.signal(signum, handler)  # type: ignore[arg-type]
    if _fast_exit and argv is None and is_entry():
        fast_exit(code)
    return code


def with_bare_values(argv: Sequence[str], bare: dict[str, str]) -> list[str]:
    """``argv`` with the value written out after each option of ``bare`` given without
    its (optional, integer) value: ``--cache mesh.vtu`` becomes ``--cache 32 mesh.vtu``.

    argparse lets an ``nargs="?"`` option take the next word whatever it is, so the
    input file after a bare ``--cache`` was read as its number ("invalid int value").
    """
    words = list(argv)
    out: list[str] = []
    for i, word in enumerate(words):
        out.append(word)
        nxt = words[i + 1] if i + 1 < len(words) else None
        if word in bare and nxt is not None and not nxt.startswith("-"):
            try:
                int(nxt)
            except ValueError:
                out.append(bare[word])
    return out


def _main(argv: Sequence[str] | None) -> int:
    command = chosen_command(argv)
    bare = getattr(COMMANDS.get(command), "BARE_VALUES", None)
    if bare:
        argv = with_bare_values(sys.argv[1:] if argv is None else argv, bare)
    parser = build_parser(command)
    try:
        args = parser.parse_args(argv)
    except Terminated as exc:
        return 128 + exc.signum
    try:
        with warnings.catch_warnings():
            # numpy's overflow/divide notes from hammesh's own arithmetic on extreme input
            # are not the user's to act on, and the CLI promises one line on bad input
            warnings.filterwarnings("ignore", category=RuntimeWarning, module=r"hammesh\.")
            # (and numpy's own, raised inside its reductions on such input: a .npy of NaNs)
            warnings.filterwarnings("ignore", category=RuntimeWarning, module=r"numpy\.")
            return int(args._run(args))
    except VerificationError as exc:
        _say(f"hammesh: verification failed: {exc}")
        return EXIT_VERIFICATION
    except HammeshError as exc:
        _say(f"hammesh: error: {option_message(exc, parser, command)}")
        return EXIT_BAD_INPUT
    except BrokenPipeError as exc:
        if getattr(exc, "filename", None):  # an output file that is a pipe: a write error
            _say(f"hammesh: error: {exc.filename}: {exc.strerror or exc}")
            return EXIT_BAD_INPUT
        # stdout's reader quit (``hammesh mesh ... | head -1``): the work and its files are
        # done; end quietly as a program killed by SIGPIPE does, with no second error
        # when Python flushes stdout at exit
        with contextlib.suppress(OSError, ValueError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_BROKEN_PIPE
    except OSError as exc:  # unreadable input, unwritable output directory, ...
        where = f"{exc.filename}: " if getattr(exc, "filename", None) else ""
        _say(f"hammesh: error: {where}{exc.strerror or exc}")
        return EXIT_BAD_INPUT
    except MemoryError:  # a declared count or a size beyond this machine
        _say("hammesh: error: out of memory (input too large for this machine, or a corrupt size field)")
        return EXIT_BAD_INPUT
    except RecursionError:  # e.g. JSON nested 100,000 deep
        _say("hammesh: error: input nested too deeply")
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        _say("hammesh: interrupted")
        return 130
    except Terminated as exc:
        _say(f"hammesh: terminated by signal {exc.signum}")
        return 128 + exc.signum
    except Exception as exc:  # noqa: BLE001 - the CLI promises no traceback
        stop = _interruption(exc)
        if stop is not None:  # a signal that landed as a compiled kernel returned
            if isinstance(stop, Terminated):
                _say(f"hammesh: terminated by signal {stop.signum}")
                return 128 + stop.signum
            _say("hammesh: interrupted")
            return 130
        if os.environ.get("HAMMESH_DEBUG"):
            raise
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        _say(f"hammesh: internal error: {type(exc).__name__}: {first} (HAMMESH_DEBUG=1 shows the traceback)")
        return EXIT_INTERNAL


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
