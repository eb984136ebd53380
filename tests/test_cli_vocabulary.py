"""One CLI vocabulary (issue 17, item 6): every command spells a concept the same way, old spellings are hidden
aliases for one release, and defaults are read from the dataclasses that hold them."""

from __future__ import annotations

import argparse
import dataclasses
import re

import pytest

from synthaug._checks import add_option, dataclass_defaults
from synthaug.cli import build_parser

CANONICAL = ("--seed-set", "--seed-counts", "--params", "--frame-stride", "--patch-size", "--no-progress")


def _sub(command: str) -> argparse.ArgumentParser:
    top = build_parser(command)
    return next(a for a in top._actions if isinstance(a, argparse._SubParsersAction)).choices[command]


def _runner(what: str) -> argparse.ArgumentParser:
    from synthaug.evaluate.runner import build_parser as runner_parser

    top = runner_parser()
    return next(a for a in top._actions if isinstance(a, argparse._SubParsersAction)).choices[what]


def _gain() -> argparse.ArgumentParser:
    from synthaug.diagnose.gain import build_parser as gain_parser

    return gain_parser()


# (id, parser factory, options every parse needs, old spellings, the same with the canonical spellings)
CASES = [
    ("fit", lambda: _sub("fit"), ["--out", "f.json"], ["--seeds", "S"], ["--seed-set", "S"]),
    ("diagnose", lambda: _sub("diagnose"), ["--out", "d"],
     ["--seeds", "S", "--fit", "F", "--quiet"], ["--seed-set", "S", "--params", "F", "--no-progress"]),
    ("ingest", lambda: _sub("ingest"), ["--out", "o", "--videos", "v", "--labels", "l"],
     ["--seeds", "12", "25"], ["--seed-counts", "12", "25"]),
    ("train", lambda: _sub("train"),
     ["--detector", "hog", "--class", "drone", "--videos", "v", "--labels", "l", "--out", "o.pt"],
     ["--seedset", "S", "--val-stride", "5", "--quiet"], ["--seed-set", "S", "--val-frame-stride", "5", "--no-progress"]),
    ("detect", lambda: _sub("detect"), ["--video", "v.mp4", "--checkpoint", "c.pt", "--out", "d.json"],
     ["--stride", "5", "--quiet"], ["--frame-stride", "5", "--no-progress"]),
    ("experiment", lambda: _sub("experiment"), ["fig11_ratio", "--out", "o"],
     ["--seedsets", "S", "--fits", "F", "--stride-k", "7", "--val-stride-k", "9"],
     ["--seed-sets", "S", "--params-dir", "F", "--frame-stride", "7", "--val-frame-stride", "9"]),
    ("preview", lambda: _sub("preview"), [], ["--seeds", "S", "--size", "32"], ["--seed-set", "S", "--patch-size", "32"]),
    ("export", lambda: _sub("export"), ["--format", "coco", "--count", "3", "--out", "o"],
     ["--seeds", "S"], ["--seed-set", "S"]),
    ("demo", lambda: _sub("demo"), [], ["--seeds", "12", "--stride", "4"], ["--seed-counts", "12", "--frame-stride", "4"]),
    ("bench", lambda: _sub("bench"), ["render"], ["--size", "32"], ["--patch-size", "32"]),
    ("runner learning-curve", lambda: _runner("learning-curve"), ["--out", "o"],
     ["--seeds", "0", "1"], ["--training-seeds", "0", "1"]),
    ("runner synthetic", lambda: _runner("synthetic"), ["--out", "o"], ["--seeds", "3"], ["--training-seeds", "3"]),
    ("gain", _gain, ["--class", "drone", "--out", "o"],
     ["--fit", "F", "--n-seeds", "25", "--seedsets", "S", "--stride-k", "7"],
     ["--params", "F", "--seed-counts", "25", "--seed-sets", "S", "--frame-stride", "7"]),
]
IDS = [c[0] for c in CASES]


def _options(argv: list[str]) -> list[str]:
    return [a for a in argv if a.startswith("--")]


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_old_and_new_spelling_parse_to_the_same_namespace(case):
    _, make, base, old, new = case
    parser = make()
    # a subcommand's options follow its name ("bench render ..."); the rest go in front or behind alike
    got_old, got_new = parser.parse_args(base + old), parser.parse_args(base + new)
    assert got_old == got_new
    if base and base[0] == "render":
        parser = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices["render"]
    for opt in _options(new):  # each option arrived (else the test would pass vacuously)
        action = parser._option_string_actions[opt]
        assert getattr(got_new, action.dest) not in (None, action.default), opt


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_help_lists_the_canonical_spelling_and_hides_the_alias(case):
    _, make, base, old, new = case
    parser = make()
    if base and base[0] == "render":  # bench: the options live on its `render` subparser
        parser = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices["render"]
    text = parser.format_help()
    for opt in _options(new):
        assert re.search(rf"(?<![\w-]){re.escape(opt)}(?![\w-])", text), f"{opt} not in --help"
    for opt in set(_options(old)) - set(_options(new)):
        assert not re.search(rf"(?<![\w-]){re.escape(opt)}(?![\w-])", text), f"hidden alias {opt} shows in --help"


def test_every_subcommand_speaks_the_canonical_words_only():
    """No visible option of any subcommand uses an old spelling of a canonical concept."""
    from synthaug.cli import SUBCOMMANDS

    old = {"--seeds", "--seedset", "--seedsets", "--fit", "--fits", "--quiet", "--stride", "--stride-k",
           "--val-stride", "--val-stride-k", "--size", "--n-seeds"}
    parsers = [_sub(c) for c in SUBCOMMANDS] + [_runner("learning-curve"), _runner("synthetic"), _gain()]
    parsers += [next(a for a in _sub("bench")._actions if isinstance(a, argparse._SubParsersAction)).choices["render"]]
    for parser in parsers:
        visible = {s for a in parser._actions if a.help != argparse.SUPPRESS for s in a.option_strings}
        assert not visible & old, (parser.prog, visible & old)


def test_required_option_is_satisfied_by_either_spelling_and_names_the_canonical_one(capsys):
    p = argparse.ArgumentParser(prog="x")
    add_option(p, "--seed-set", aliases=["--seeds"], required=True, help="seed-set folder")
    assert p.parse_args(["--seeds", "a"]).seed_set == p.parse_args(["--seed-set", "a"]).seed_set == "a"
    with pytest.raises(SystemExit) as e:
        p.parse_args([])
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert "--seed-set" in err and "--seeds" not in err
    with pytest.raises(SystemExit) as e:  # both spellings at once: refused, not silently one of them
        p.parse_args(["--seeds", "a", "--seed-set", "b"])
    assert e.value.code == 2
    capsys.readouterr()


def test_alias_keeps_type_choices_and_flag_kind(capsys):
    p = argparse.ArgumentParser(prog="x")
    add_option(p, "--frame-stride", aliases=["--stride"], type=int, choices=[1, 2, 3], default=1, help="k")
    add_option(p, "--no-progress", aliases=["--quiet"], action="store_true", help="quiet")
    assert p.parse_args(["--stride", "2", "--quiet"]) == argparse.Namespace(frame_stride=2, no_progress=True)
    assert p.parse_args([]) == argparse.Namespace(frame_stride=1, no_progress=False)
    with pytest.raises(SystemExit):
        p.parse_args(["--stride", "5"])
    assert "--stride" in capsys.readouterr().err  # the error names the spelling the user typed
    with pytest.raises(SystemExit):
        p.parse_args(["--quiet", "yes"])  # still a flag
    capsys.readouterr()


# ------------------------------------------------------------ defaults read from the dataclasses
def _defaults(parser: argparse.ArgumentParser) -> dict:
    return {a.dest: a.default for a in parser._actions if a.default is not argparse.SUPPRESS}


def test_fit_reaches_every_fitconfig_field_with_its_default():
    from synthaug.fit.cli import config_from_args
    from synthaug.fit.fitting import FitConfig

    parser = _sub("fit")
    cli = _defaults(parser)
    fields = {f.name for f in dataclasses.fields(FitConfig)}
    assert fields <= set(cli), f"FitConfig fields without an option: {sorted(fields - set(cli))}"
    for name, value in dataclass_defaults(FitConfig).items():
        assert cli[name] == value, name
    args = parser.parse_args(["--seed-set", "S", "--out", "f.json"])
    assert config_from_args(args) == FitConfig()
    # and each newly reachable field arrives in the config
    args = parser.parse_args(["--seed-set", "S", "--out", "f.json", "--translation", "0.2", "--init-fraction", "0.5",
                              "--init-starts", "2", "--scale-range", "0.5", "1.5", "--bounds", "sigma_n=0,0.05",
                              "blur=0.1,1", "--distance-kwargs", '{"cell": 4}', "--no-fit-scale", "--init", "uniform",
                              "--object-noise", "measured"])
    cfg = config_from_args(args)
    assert (cfg.translation, cfg.init_fraction, cfg.init_starts, cfg.scale_range, cfg.fit_scale, cfg.init, cfg.object_noise) == \
        (0.2, 0.5, 2, (0.5, 1.5), False, "uniform", "measured")
    assert cfg.bounds == {"sigma_n": (0.0, 0.05), "blur": (0.1, 1.0)} and cfg.distance_kwargs == {"cell": 4}
    assert config_from_args(parser.parse_args(["--seed-set", "S", "--out", "f", "--bounds"])).bounds == {}


@pytest.mark.parametrize("argv, option", [
    (["--bounds", "sigma_n=0.1"], "--bounds"), (["--bounds", "sigma_n=0.2,0.1"], "--bounds"),
    (["--distance-kwargs", "[1]"], "--distance-kwargs"), (["--init-fraction", "1"], "--init-fraction"),
    (["--init-starts", "0"], "--init-starts"), (["--translation", "-1"], "--translation"),
])
def test_fit_new_options_refuse_bad_values_naming_the_option(argv, option, capsys):
    with pytest.raises(SystemExit) as e:
        _sub("fit").parse_args(["--seed-set", "S", "--out", "f.json", *argv])
    assert e.value.code == 2 and option in capsys.readouterr().err


def test_experiment_defaults_are_the_dataclasses():
    from synthaug.detectors.training import TrainOptions
    from synthaug.evaluate.context import ExperimentContext

    cli = _defaults(_sub("experiment"))
    ctx = dataclass_defaults(ExperimentContext)
    for dest, field in [("frame_stride", "stride_k"), ("val_frame_stride", "val_stride_k"), ("seed_sets", "seedsets_dir"),
                        ("params_dir", "fits_dir"), ("class_name", "class_name"), ("videos", "videos_dir"),
                        ("labels", "labels_dir"), ("split", "split_file"), ("seed", "seed"),
                        ("fit_workers", "fit_workers"), ("fit_budget", "fit_budget")]:
        assert cli[dest] == ctx[field], dest
    opts = dataclass_defaults(TrainOptions)
    for name in ("cnn_epochs", "cnn_max_steps", "ada_rounds", "ada_candidates", "hog_components", "hog_mining_rounds"):
        assert cli[name] == opts[name], name
    assert cli["frame_stride"] == 15 and cli["val_frame_stride"] == 30  # what every recorded experiment ran with


def test_train_defaults_are_trainoptions():
    from synthaug.detectors.training import TrainOptions

    cli = _defaults(_sub("train"))
    opts = dataclass_defaults(TrainOptions)
    assert cli["val_frame_stride"] == opts["val_stride"]
    for name in ("mining_rounds", "mining_stride", "mining_per_frame", "hog_components", "hog_mining_rounds",
                 "ada_rounds", "ada_candidates", "cnn_epochs", "cnn_max_steps", "cnn_shift"):
        assert cli[name] == opts[name], name


def test_ingest_defaults_are_ingestconfig():
    from synthaug.data.ingest import IngestConfig

    cli = _defaults(_sub("ingest"))
    cfg = dataclass_defaults(IngestConfig)
    for dest, field in [("patch_size", "patch_size"), ("object_fraction", "object_fraction"),
                        ("per_video", "seeds_per_video"), ("negatives_per_video", "negatives_per_video"),
                        ("hard_negatives_per_video", "hard_negatives_per_video"), ("inpaint", "inpaint_method"),
                        ("seed", "seed")]:
        assert cli[dest] == cfg[field], dest
    assert tuple(cli["hard_negative_classes"]) == cfg["hard_negative_classes"]


@pytest.mark.parametrize("value", ["x", None, 3, ["fp"]])
def test_one_of_refuses_anything_but_a_listed_string(value):
    from synthaug._checks import one_of

    assert one_of("ap", ("fp", "ap"), "mining_select") == "ap"
    with pytest.raises(ValueError) as err:
        one_of(value, ("fp", "ap"), "mining_select", alternatives=" or None")
    assert str(err.value) == f"mining_select must be one of ['fp', 'ap'] or None, got {value!r}"


@pytest.mark.parametrize("field, choices, alternatives", [("ada_cascade", "['all', 'real']", ""),
                                                          ("mining_select", "['fp', 'ap']", " or None"),
                                                          ("box_model", "['cnn', 'ridge', 'ensemble']", "")])
def test_train_options_name_the_field_and_its_choices(field, choices, alternatives):
    from synthaug.detectors.training import TrainOptions

    with pytest.raises(ValueError) as err:
        TrainOptions(**{field: "nope"})
    assert str(err.value) == f"{field} must be one of {choices}{alternatives}, got 'nope'"
