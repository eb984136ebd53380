"""The ``synthaug`` command line: one subcommand per module, imported lazily.

Each subcommand module exposes ``add_arguments(parser)`` and ``main(args) -> int``.
``synthaug --help`` imports none of them; ``synthaug COMMAND ...`` imports only
that command's module. Every option's help ends with its default.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

# name -> (module, one-line help)
SUBCOMMANDS: dict[str, tuple[str, str]] = {
    "demo": ("synthaug.demo", "the whole method on generated data: ingest, fit, generate, train, evaluate"),
    "preview": ("synthaug.data.preview", "PNG grid of synthetic samples (real beside synthetic with --seed-set)"),
    "bench": ("synthaug.data.bench", "benchmarks: `synthaug bench render` prints JSON samples/s"),
    "ingest": ("synthaug.data.ingest_cli", "videos + boxes (or images + COCO) -> seed set with backgrounds"),
    "fit": ("synthaug.fit.cli", "seed set + mesh + distance -> fitted capture parameters per seed"),
    "diagnose": ("synthaug.diagnose.cli", "seed set + mesh + fit -> what the simulation gets wrong, ranked findings"),
    "experiment": ("synthaug.evaluate.experiments_cli", "the paper's experiments and the baselines on real videos"),
    "train": ("synthaug.detectors.train_cli", "videos + labels (+ a fit) -> a trained detector file for `synthaug detect`"),
    "detect": ("synthaug.detectors.cli", "checkpoint + video/images -> per-frame detections JSON"),
    "evaluate": ("synthaug.evaluate.cli", "detections + labels -> precision-recall PNG and AP"),
    "export": ("synthaug.data.export", "synthetic frames (+ real seeds) as a COCO or YOLO dataset for other trainers"),
}


class _HelpFormatter(argparse.ArgumentDefaultsHelpFormatter, argparse.RawDescriptionHelpFormatter):
    """Every option's default appended to its help (``(default: X)``), except flags and options whose default
    is "not given" (None); descriptions kept as written."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        if action.default is None or action.default is False or action.nargs == 0:
            return action.help
        return super()._get_help_string(action)


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser; with ``command``, that subcommand's options are added (its module imported), the others
    are listed by name and one-line help only."""
    parser = argparse.ArgumentParser(prog="synthaug", formatter_class=_HelpFormatter,
                                     description="synthaug: synthetic training images for object detectors, "
                                                 "realistic in the detector's eyes (Rozantsev et al., CVIU 2015)",
                                     epilog="`synthaug COMMAND --help` lists a command's options with their defaults.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (module, help_) in SUBCOMMANDS.items():
        p = sub.add_parser(name, help=help_, description=help_, formatter_class=_HelpFormatter)
        p.set_defaults(_module=module)
        if name != command:
            continue
        try:
            mod = importlib.import_module(module)
        except ModuleNotFoundError as e:
            if e.name and (e.name == module or module.startswith(e.name + ".")):
                p.set_defaults(_unavailable=f"`synthaug {name}` is not available in this version")
                continue
            raise
        mod.add_arguments(p)
    return parser


def _command(argv: list[str]) -> str | None:
    """The subcommand named in ``argv`` (the first argument that is one), if any."""
    for a in argv:
        if a in SUBCOMMANDS:
            return a
        if not a.startswith("-"):
            return None
    return None


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(_command(argv))
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 2
    if getattr(args, "_unavailable", None):
        print(args._unavailable, file=sys.stderr)
        return 2
    mod = importlib.import_module(args._module)
    try:
        return int(mod.main(args) or 0)
    except (ValueError, OSError) as e:
        # the last guard of "bad input -> one clear line" (issue 18): a bad value or an unusable file that a
        # command did not catch itself is still one line naming it, not a traceback. SYNTHAUG_DEBUG=1 re-raises.
        if os.environ.get("SYNTHAUG_DEBUG"):
            raise
        from synthaug._checks import first_line

        print(f"synthaug {args.command}: error: {first_line(e)} (SYNTHAUG_DEBUG=1 shows the traceback)",
              file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
