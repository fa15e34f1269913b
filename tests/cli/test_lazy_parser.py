"""The CLI builds only the chosen subcommand's options, so help and usage errors stay light."""

from __future__ import annotations

import subprocess
import sys

import pytest

from hammesh.cli import COMMANDS, build_parser, chosen_command

HEAVY = ("numba", "hammesh.postprocess", "hammesh.domain", "hammesh.meshing", "hammesh.verify", "hammesh.io")


def _loaded_after(code: str) -> set[str]:
    """Heavy modules a fresh interpreter has loaded after running ``code``."""
    probe = (
        "import sys\n"
        f"{code}\n"
        f"print('LOADED:', *(m for m in {HEAVY!r} if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout
    (line,) = [x for x in out.splitlines() if x.startswith("LOADED:")]
    return set(line.split()[1:])


def test_top_level_help_imports_no_library_module() -> None:
    code = "from hammesh.cli import main\ntry:\n    main(['--help'])\nexcept SystemExit:\n    pass"
    assert _loaded_after(code) == set()


def test_a_usage_error_of_check_imports_no_library_module() -> None:
    code = "from hammesh.cli import main\ntry:\n    main(['check'])\nexcept SystemExit as e:\n    assert e.code == 2, e.code"
    assert _loaded_after(code) == set()


@pytest.mark.parametrize(
    ("argv", "expected"),
    [(["mesh", "a.poly"], "mesh"), (["--version"], None), (["-h", "check", "x"], "check"), (["nope"], None), ([], None)],
)
def test_chosen_command_is_the_first_word(argv: list[str], expected: str | None) -> None:
    assert chosen_command(argv) == expected


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_each_command_parses_its_own_options_when_chosen(name: str) -> None:
    """The options built for a chosen command are the same as in the full parser."""
    full = build_parser("all")._subparsers._group_actions[0].choices[name]  # type: ignore[union-attr]
    alone = build_parser(name)._subparsers._group_actions[0].choices[name]  # type: ignore[union-attr]
    assert [a.dest for a in alone._actions] == [a.dest for a in full._actions]
    assert len(full._actions) > 1  # at least -h and one option of its own
