"""Input checks shared by the commands: argparse ``type=`` functions and output-path checks.

A bad option or an unusable output path is reported before the first expensive
step, in one line that names the option (issue 18: "validate before working").

* ``type=`` functions (:func:`positive_int`, :func:`finite_float`, ...) make
  argparse reject a bad number as it parses: ``synthaug demo --ratio -1`` exits
  2 with ``argument --ratio: must be a finite number >= 0, got '-1'``.
* :func:`check_output_file` / :func:`check_output_dir` raise :class:`ValueError`
  naming the option when ``--out`` can never be written (an existing folder
  where a file is expected, a file where a folder is expected, a file on the
  way to it), so a command fails before it works, not after.
"""

from __future__ import annotations

import argparse
import math
import os
import re
from pathlib import Path
from typing import Any, Callable, Collection, Sequence

__all__ = ["positive_int", "nonneg_int", "positive_float", "nonneg_float", "unit_float", "open_unit_float",
           "finite_float", "float_in", "int_at_least", "check_output_file", "check_output_dir",
           "check_seedset_dir", "first_line", "add_option", "dataclass_defaults", "one_of"]


def one_of(value: Any, choices: Collection[str], name: str, *, alternatives: str = "") -> str:
    """``value`` if it is one of the strings ``choices`` (a tuple, or a dict's keys); else ``ValueError`` naming
    ``name``, the choices and any ``alternatives`` the caller accepts besides them (e.g. ``" or None"``, checked by
    the caller).

    >>> one_of("ns", ("pushpull", "telea", "ns"), "inpaint method")
    'ns'
    >>> one_of("x", ("a", "b"), "mode", alternatives=" or None")
    Traceback (most recent call last):
    ...
    ValueError: mode must be one of ['a', 'b'] or None, got 'x'
    """
    if not isinstance(value, str) or value not in choices:
        raise ValueError(f"{name} must be one of {list(choices)}{alternatives}, got {value!r}")
    return value


def _number(text: str, kind: type) -> float | int:
    try:
        value = kind(text)
    except (TypeError, ValueError):
        raise argparse.ArgumentTypeError(f"must be {'an integer' if kind is int else 'a number'}, got {text!r}") \
            from None
    if kind is float and not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text!r}")
    return value


def int_at_least(low: int) -> Callable[[str], int]:
    """An argparse type: an integer >= ``low``."""

    def parse(text: str) -> int:
        value = int(_number(text, int))
        if value < low:
            raise argparse.ArgumentTypeError(f"must be an integer >= {low}, got {text!r}")
        return value

    parse.__name__ = f"integer >= {low}"  # argparse names the type in its "invalid ... value" message
    return parse


positive_int = int_at_least(1)
nonneg_int = int_at_least(0)


def finite_float(text: str) -> float:
    """An argparse type: a finite number (no nan / inf)."""
    return float(_number(text, float))


def positive_float(text: str) -> float:
    """An argparse type: a finite number > 0."""
    value = finite_float(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be a finite number > 0, got {text!r}")
    return value


def nonneg_float(text: str) -> float:
    """An argparse type: a finite number >= 0."""
    value = finite_float(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be a finite number >= 0, got {text!r}")
    return value


def unit_float(text: str) -> float:
    """An argparse type: a number in [0, 1]."""
    value = finite_float(text)
    if not 0.0 <= value <= 1.0:
        raise argparse.ArgumentTypeError(f"must be in [0, 1], got {text!r}")
    return value


def open_unit_float(text: str) -> float:
    """An argparse type: a number in (0, 1)."""
    value = finite_float(text)
    if not 0.0 < value < 1.0:
        raise argparse.ArgumentTypeError(f"must be in (0, 1), got {text!r}")
    return value


def float_in(low: float, high: float, *, low_open: bool = False) -> Callable[[str], float]:
    """An argparse type: a finite number in ``[low, high]`` (``(low, high]`` with ``low_open``)."""

    def parse(text: str) -> float:
        value = finite_float(text)
        if not ((low < value) if low_open else (low <= value)) or value > high:
            raise argparse.ArgumentTypeError(f"must be in {'(' if low_open else '['}{low:g}, {high:g}], got {text!r}")
        return value

    parse.__name__ = f"number in [{low:g}, {high:g}]"
    return parse


def _blocking_parent(path: Path) -> Path | None:
    """The first existing ancestor of ``path`` that is not a folder (so nothing can be made under it)."""
    for parent in path.parents:
        if parent.exists():
            return None if parent.is_dir() else parent
    return None


def check_output_file(path: str | os.PathLike, option: str = "--out") -> Path:
    """``path`` can be written as a file: it is not a folder and no file stands on its way.

    Raises:
        ValueError: naming ``option`` and the path.
    """
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"{option}: {path} is a directory; give the path of a file")
    blocker = _blocking_parent(path)
    if blocker is not None:
        raise ValueError(f"{option}: cannot write {path}: {blocker} is a file, not a folder")
    if path.exists() and not os.access(path, os.W_OK):
        raise ValueError(f"{option}: {path} is not writable")
    return path


def check_output_dir(path: str | os.PathLike, option: str = "--out") -> Path:
    """``path`` is, or can be made, a folder: it is not a file and no file stands on its way.

    Raises:
        ValueError: naming ``option`` and the path.
    """
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise ValueError(f"{option}: {path} is a file; give a directory")
    blocker = _blocking_parent(path)
    if blocker is not None:
        raise ValueError(f"{option}: cannot make the folder {path}: {blocker} is a file, not a folder")
    return path


def check_seedset_dir(path: str | os.PathLike, option: str = "--seed-set") -> Path:
    """``path`` is a seed-set folder (it holds ``seedset.json``); its contents are checked when it is loaded.

    Raises:
        FileNotFoundError: naming ``option`` and the path.
    """
    path = Path(path)
    if not (path / "seedset.json").is_file():
        why = "does not exist" if not path.exists() else "is not a folder" if not path.is_dir() else \
            "holds no seedset.json"
        raise FileNotFoundError(f"{option}: {path} is not a seed set: it {why} (`synthaug ingest` makes one)")
    return path


# ------------------------------------------------------------ one CLI vocabulary (issue 17)
# Every subcommand spells a concept the same way (--seed-set, --seed-counts, --params, --frame-stride,
# --patch-size, --no-progress, ...). An old spelling stays accepted for one release as a hidden alias: the
# same dest, type and choices, absent from --help, printing nothing extra.

def add_option(container: argparse._ActionsContainer, name: str, *, aliases: Sequence[str] = (),
               **kwargs: Any) -> argparse.Action:
    """``container.add_argument(name, **kwargs)``, with ``aliases`` (old spellings) accepted but hidden.

    An alias parses exactly as ``name`` (same ``dest``, ``type``, ``nargs``, ``choices``; a flag stays a flag)
    and is left out of ``--help`` and the usage line. A ``required`` option with aliases becomes a required
    group of itself and its aliases, so either spelling satisfies it (argparse names only ``name`` when
    neither is given); giving both is an error. ``container`` may itself be a mutually exclusive group.

    Example:
        >>> p = argparse.ArgumentParser()
        >>> _ = add_option(p, "--seed-set", aliases=["--seeds"], required=True, help="seed-set folder")
        >>> p.parse_args(["--seeds", "d"]) == p.parse_args(["--seed-set", "d"])
        True
        >>> "--seeds" in p.format_help()
        False
    """
    aliases = list(aliases)
    if aliases and kwargs.get("required"):
        if not isinstance(container, argparse._MutuallyExclusiveGroup):
            container = container.add_mutually_exclusive_group(required=True)
        kwargs["required"] = False
    action = container.add_argument(name, **kwargs)
    if not aliases:
        return action
    hidden: dict[str, Any] = {"dest": action.dest, "default": argparse.SUPPRESS, "help": argparse.SUPPRESS}
    if action.nargs == 0:  # a flag: store_true / store_false / store_const
        hidden.update(action="store_const", const=action.const)
    else:
        hidden.update(type=action.type, nargs=action.nargs, choices=action.choices, metavar=action.metavar)
    container.add_argument(*aliases, **hidden)
    return action


def dataclass_defaults(cls: type) -> dict[str, Any]:
    """``{field name: default}`` of a dataclass (``default_factory`` called), for a CLI that must not retype
    them: ``parser.add_argument("--budget", default=dataclass_defaults(FitConfig)["budget"])``."""
    import dataclasses

    out = {}
    for f in dataclasses.fields(cls):
        if f.default is not dataclasses.MISSING:
            out[f.name] = f.default
        elif f.default_factory is not dataclasses.MISSING:
            out[f.name] = f.default_factory()
    return out


def first_line(message: object, limit: int = 300) -> str:
    """The first non-empty line of an error message, at most ``limit`` characters (library errors such as
    torch's weights-only refusal span many lines)."""
    lines = [s.strip() for s in str(message).splitlines() if s.strip()]
    text = lines[0] if lines else ""
    return text if len(text) <= limit else text[: limit - 3] + "..."


def torch_load_error(e: BaseException, limit: int = 200) -> str:
    """One line for an exception from ``torch.load(..., weights_only=True)``: a refused pickle (code or objects
    other than tensors and plain values) says so and names the refused global; anything else is its first line."""
    text = str(e)
    if "Weights only load failed" in text:
        m = re.search(r"Unsupported global: GLOBAL (\S+)", text)
        if m:
            return f"it holds pickled code or objects ({m.group(1)}), which are never loaded (weights_only)"
        m = re.search(r"WeightsUnpickler error: ([^\n]+)", text)
        return "unreadable bytes, refused by the weights-only unpickler" + (f" ({m.group(1).strip()})" if m else "")
    return f"{type(e).__name__}: {first_line(text, limit)}"
