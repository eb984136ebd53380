"""The command line a newcomer meets: lazy `synthaug --help`, help text and default for every option."""

import argparse
import subprocess
import sys

import pytest

from synthaug.cli import SUBCOMMANDS, build_parser


def _parsers(parser, prefix):
    """(name, parser) for a parser and its nested subcommands."""
    yield prefix, parser
    for a in parser._actions:
        if isinstance(a, argparse._SubParsersAction):
            for name, sub in a.choices.items():
                yield from _parsers(sub, f"{prefix} {name}")


@pytest.mark.parametrize("command", sorted(SUBCOMMANDS))
def test_every_option_has_help_and_its_default(command):
    top = build_parser(command)
    sub = next(a for a in top._actions if isinstance(a, argparse._SubParsersAction)).choices[command]
    for name, parser in _parsers(sub, command):
        text = " ".join(parser.format_help().split())
        for a in parser._actions:
            if isinstance(a, (argparse._HelpAction, argparse._SubParsersAction)):
                continue
            opt = (a.option_strings or [a.dest])[0]
            assert a.help and a.help.strip(), f"synthaug {name} {opt}: no help text"
            if a.default not in (None, False, argparse.SUPPRESS) and a.nargs != 0:
                shown = a.default if not isinstance(a.default, (list, tuple)) else type(a.default)(a.default)
                assert f"(default: {shown})" in text, f"synthaug {name} {opt}: default {a.default!r} not in --help"


def test_top_level_help_imports_no_subcommand():
    code = ("import sys; from synthaug.cli import main\n"
            "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
            "mods = [m for m, _ in __import__('synthaug.cli').cli.SUBCOMMANDS.values() if m in sys.modules]\n"
            "print('IMPORTED', mods, 'torch' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120).stdout
    assert "IMPORTED [] False" in out, out


def test_a_subcommand_imports_only_its_module():
    code = ("import sys; from synthaug.cli import build_parser\n"
            "build_parser('evaluate')\n"
            "print('IMPORTED', [m for m, _ in __import__('synthaug.cli').cli.SUBCOMMANDS.values() if m in sys.modules])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120).stdout
    assert "IMPORTED ['synthaug.evaluate.cli']" in out, out
