"""The ``hammesh`` command line: one module per subcommand.

Each subcommand module has ``add_args(parser)`` and ``run(args) -> int``. ``main``
turns every hammesh error into one line on stderr and an exit code:

====  =====================================================
0     success
2     bad input, bad option or usage (nothing is written)
3     verification failed (nothing is written)
1     unexpected internal error (set HAMMESH_DEBUG=1 for the traceback)
====  =====================================================
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence

from hammesh.cli import check, demo, mesh, points, polygon, strip, surface
from hammesh.errors import HammeshError, VerificationError

__all__ = ["main", "COMMANDS", "EXIT_OK", "EXIT_BAD_INPUT", "EXIT_VERIFICATION", "EXIT_INTERNAL"]

EXIT_OK, EXIT_INTERNAL, EXIT_BAD_INPUT, EXIT_VERIFICATION = 0, 1, 2, 3

#: subcommand name -> module with add_args / run (and a one-line HELP)
COMMANDS = {"mesh": mesh, "check": check, "strip": strip, "polygon": polygon, "points": points, "surface": surface, "demo": demo}


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, exit 2, as for any bad input
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    from hammesh import __version__

    parser = _Parser(
        prog="hammesh",
        description="Guaranteed-quality triangle meshes whose triangles form one "
        "Hamiltonian cycle (Arkin, Held, Mitchell, Skiena, Thm 2.4).",
        epilog="Exit codes: 0 ok, 2 bad input or usage, 3 verification failed, 1 internal error.",
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
        module.add_args(p)
        p.set_defaults(_run=module.run)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``hammesh`` console script; returns the exit code."""
    args = build_parser().parse_args(argv)
    try:
        return int(args._run(args))
    except VerificationError as exc:
        print(f"hammesh: verification failed: {exc}", file=sys.stderr)
        return EXIT_VERIFICATION
    except HammeshError as exc:
        print(f"hammesh: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as exc:  # unreadable input, unwritable output directory, ...
        where = f" {exc.filename}" if getattr(exc, "filename", None) else ""
        print(f"hammesh: error:{where}: {exc.strerror or exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("hammesh: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # noqa: BLE001 - the CLI promises no traceback
        if os.environ.get("HAMMESH_DEBUG"):
            raise
        print(
            f"hammesh: internal error: {type(exc).__name__}: {exc} (HAMMESH_DEBUG=1 shows the traceback)",
            file=sys.stderr,
        )
        return EXIT_INTERNAL


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
