"""``synthaug train``: videos + labels (+ a fit) -> a trained detector file for ``synthaug detect``.

Usage::

    synthaug train --detector hog --class drone --videos ../shared/data/halmstad/videos \\
        --labels ../shared/data/halmstad/labels --split configs/splits/halmstad.json \\
        --seed-counts 100 --out runs/hog_drone.pt
    synthaug detect --checkpoint runs/hog_drone.pt --video V_DRONE_042.mp4 --frame-stride 5 --out dets.json

Any folder in the shared label format works (``videos/<stem>.mp4`` + ``labels/<stem>.json``,
any stems, any numbering). Without ``--split`` the videos of the class are split *by video*
into train / validation (80 / 20, seeded by ``--seed``); the split, the options, the mining
log (negatives added and validation false positives per round) and the synthaug version are
written beside the checkpoint as ``<out>.json``. ``--seed-counts N`` draws N seed frames from
the training videos exactly as ``synthaug ingest`` does (into ``<out>.work/``, reused by a
rerun); ``--all-frames`` uses every labelled training frame. The training itself is
:func:`synthaug.detectors.video_training.train_from_videos`, the code path of the experiments.

Bad inputs exit with status 2 and a message naming the option.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

__all__ = ["add_arguments", "add_budget_options", "budget_options", "main"]

_DETECTORS = ("hog", "adaboost", "cnn")

# The detector families' training budgets, one spelling for `synthaug train` and `synthaug experiment`:
# TrainOptions field -> (flag, lowest value, help); the defaults are TrainOptions'.
_BUDGETS = {
    "hog_components": ("--hog-components", 1, "HOG mixture components (aspect clusters)"),
    "hog_mining_rounds": ("--hog-mining-rounds", 0, "HOG's own cache-mining rounds per training"),
    "hog_kmeans_restarts": ("--hog-kmeans-restarts", 1,
                            "k-means runs of the HOG components' initialisation, the lowest inertia kept (1: the "
                            "training before this option)"),
    "ada_rounds": ("--ada-rounds", 1, "AdaBoost boosting rounds (default 300)"),
    "ada_candidates": ("--ada-candidates", 1, "AdaBoost weak-learner candidates scored per round"),
    "cnn_epochs": ("--cnn-epochs", 1, "CNN passes over the training patches"),
    "cnn_max_steps": ("--cnn-max-steps", 1, "cap on CNN optimiser steps"),
    "cnn_finetune_epochs": ("--cnn-finetune-epochs", 0,
                            "CNN passes over the real positives alone after training on all of them, at a tenth of the "
                            "learning rate (default 4; 0: off, the training before this option; used when synthetic or other "
                            "added positives are mixed in)"),
}


def add_budget_options(parser: argparse._ActionsContainer) -> None:
    """Add the training-budget options of the three families (``--hog-components`` ... ``--cnn-max-steps``),
    defaults read from :class:`~synthaug.detectors.training.TrainOptions`; :func:`budget_options` reads them back."""
    from synthaug._checks import dataclass_defaults, int_at_least
    from synthaug.detectors.training import TrainOptions

    d = dataclass_defaults(TrainOptions)
    for name, (flag, low, help_) in _BUDGETS.items():
        parser.add_argument(flag, type=int_at_least(low), default=d[name], help=help_)


def budget_options(args: argparse.Namespace) -> dict[str, int]:
    """The :class:`~synthaug.detectors.training.TrainOptions` fields that :func:`add_budget_options` added."""
    return {name: getattr(args, name) for name in _BUDGETS}


def effect_name(name: str) -> str:
    """An argparse type: the name of a registered capture effect (``--effects-off``)."""
    from synthaug.effects.registry import list_effects

    if name not in list_effects():
        raise argparse.ArgumentTypeError(f"unknown effect {name!r}; choose from {', '.join(list_effects())}")
    return name


def synthetic_share_arg(text: str) -> float | str:
    """An argparse type: ``--synthetic-share``, a number (the added positives' share, checked when training) or
    ``count`` (every positive weighs the same; :data:`~synthaug.detectors.video_training.BY_COUNT`)."""
    from synthaug._checks import finite_float
    from synthaug.detectors.video_training import BY_COUNT

    return BY_COUNT if text == BY_COUNT else finite_float(text)


QUANTIZE_ARGS: dict[str, bool | str] = {"on": True, "off": False, "native_scale": "native_scale"}
"""``--quantize``'s words and the :data:`~synthaug.detectors.training_sets.QUANTIZE` value each stands for (``synthaug
train``'s and the runner's)."""


def quantize_arg(text: str) -> bool | str:
    """An argparse type: ``--quantize``'s word (:data:`QUANTIZE_ARGS`) as ``AddedPositives``' ``quantize``."""
    if text not in QUANTIZE_ARGS:
        raise argparse.ArgumentTypeError(f"invalid choice {text!r}; choose from {', '.join(QUANTIZE_ARGS)}")
    return QUANTIZE_ARGS[text]


def _effects_off(values: list[str] | None) -> tuple[str, ...] | None:
    """``--effects-off`` as :class:`~synthaug.detectors.video_training.AddedPositives` takes it (None: the family's)."""
    from synthaug.detectors.video_training import TrainingInputError

    if values is None:
        return None
    if "none" in values:
        if len(values) > 1:
            raise TrainingInputError("--effects-off", f"'none' (every fitted effect) cannot be given with effect names, "
                                                      f"got {' '.join(values)}")
        return ()
    return tuple(values)


def add_adaboost_options(parser: argparse.ArgumentParser, *, keyed: bool = False) -> None:
    """AdaBoost's training options, one declaration for ``synthaug train`` and the evaluation runner.

    ``keyed``: say in the help when an option becomes part of a runner cell's key.
    """
    from synthaug._checks import nonneg_float
    from synthaug.detectors.training import ADA_CASCADE, TrainOptions

    parser.add_argument("--ada-energy-floor", type=nonneg_float, default=TrainOptions.ada_energy_floor,
                        help="AdaBoost: energy floor of the stumps' normalisation, in units of the training negatives' "
                             "gradient level (0: the paper's energy" + ("; part of AdaBoost's cell keys otherwise)"
                                                                        if keyed else ")"))
    parser.add_argument("--ada-transfer", action="store_true",
                        help="AdaBoost: train as Dynamic-TrAdaBoost, the added positives (synthetic, perturbed, ...) as "
                             "the source distribution: their misses lose weight, alpha is measured on the real positives "
                             "and the negatives (used only with added positives" +
                             ("; part of AdaBoost's cell keys when set)" if keyed else ")"))
    parser.add_argument("--ada-cascade", choices=ADA_CASCADE, default=TrainOptions.ada_cascade,
                        help="AdaBoost: the positives whose partial scores set the soft cascade's thresholds: real "
                             "(the default: the real ones only, when positives are added; a few added positives that "
                             "score low otherwise loosen every stage) or all (every training positive, the training "
                             "before stop 60" + ("; part of AdaBoost's cell keys when real)" if keyed else ")"))


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from synthaug._checks import add_option, dataclass_defaults, float_in, int_at_least, nonneg_float, positive_float
    from synthaug.data.captures import CAPTURE_SAMPLERS
    from synthaug.data.items import BACKGROUND_SAMPLING
    from synthaug.data.poses import POSE_SAMPLING
    from synthaug.detectors.box_calibration import CALIBRATION_FORMS
    from synthaug.detectors.critic import REALISM_FEATURES, REALISM_SELECTION
    from synthaug.detectors.training import BOX_MODELS, MINING_SELECT, TrainOptions
    from synthaug.detectors.training_sets import DISTRACTOR_STYLES

    d = dataclass_defaults(TrainOptions)  # the training budgets' defaults are TrainOptions'
    parser.add_argument("--detector", required=True, help=f"detector family: {' | '.join(_DETECTORS)}")
    parser.add_argument("--class", dest="class_name", required=True, help="class to detect (the label files' 'class', e.g. drone)")
    parser.add_argument("--videos", type=Path, required=True, help="folder of videos <stem>.mp4 (any stems, any numbering)")
    parser.add_argument("--labels", type=Path, required=True, help="folder of per-video label JSON files (shared format)")
    parser.add_argument("--out", type=Path, required=True, help="detector file to write (.pt); metadata goes to the same name with .json")
    parser.add_argument("--split", type=Path, help="video split JSON (configs/splits/halmstad.json format); default: split by video "
                                                   "from --seed, see --val-fraction")
    pos = parser.add_mutually_exclusive_group()
    pos.add_argument("--seed-counts", type=int, default=None,
                     help="real seed frames drawn from the training videos the way `synthaug ingest` draws them (default 100)")
    pos.add_argument("--all-frames", action="store_true", help="every labelled frame of the training videos (see --frame-step)")
    add_option(pos, "--seed-set", aliases=["--seedset"], type=Path,
               help="use this seed set (`synthaug ingest` output) instead of drawing seeds")
    parser.add_argument("--frame-step", type=int, default=1, help="with --all-frames: every K-th labelled frame")
    parser.add_argument("--positive-videos", type=int, default=None, metavar="K",
                        help="positives (seeds or all frames) from only K of the training videos, drawn by --seed; the "
                             "box map, mining and validation still use every training video (default: all)")
    parser.add_argument("--params", type=Path, help="`synthaug fit` output made on the seed set: adds synthetic positives")
    parser.add_argument("--mesh", help="mesh of the synthetic object (default: the fit's mesh, else the built-in quadcopter)")
    parser.add_argument("--synthetic-ratio", type=float, default=None,
                        help="synthetic patches per real seed with --params (default 10 when --params is given, else 0)")
    parser.add_argument("--pose-sampling", choices=list(POSE_SAMPLING), default=None,
                        help="poses of the synthetic positives: uniform (the paper) or around each seed's fitted "
                             "pose (fitted); *_at_seed: the same rotations with the object at its seed's fitted "
                             "offset; default: the detector family's (fitted_at_seed for AdaBoost, fitted with "
                             "--object-box; uniform for HOG and the CNN)")
    parser.add_argument("--object-box", choices=["seed", "fit"], default=None,
                        help="frame each synthetic object as ingest frames a labelled seed, its box centred and its "
                             "longest side the seed set's object_fraction of the patch (seed) or the median size of the "
                             "fitted renders' boxes (fit); default: the paper's mesh-scale framing")
    parser.add_argument("--object-box-share", type=float_in(0.0, 1.0, low_open=True), default=1.0, metavar="SHARE",
                        help="with --object-box: the fraction of the synthetic objects it frames, the others framed as "
                             "the paper's (default 1: every one; e.g. 0.5, a mixture of the two framings)")
    parser.add_argument("--shape-variation", type=nonneg_float, default=None,
                        help="vary the synthetic objects' shape around the mesh (axes stretched, parts such as arms and "
                             "rotors scaled) within +- this fraction, e.g. 0.3; 0: the mesh alone (the paper); "
                             "default: the detector family's (0.3 for AdaBoost, 0 for HOG and the CNN)")
    parser.add_argument("--quantize", nargs="?", const=True, type=quantize_arg, default=None,
                        metavar="{on,off,native_scale}",
                        help="round the synthetic positives to 8-bit levels, as the real frames are stored (on, the "
                             "value when none is given); off: the renderer's continuous values (the paper's); "
                             "native_scale: round those of the seeds the pyramid sees at about their own size, the "
                             "others continuous; default: the detector family's (native_scale for AdaBoost, "
                             "continuous for HOG and the CNN)")
    parser.add_argument("--no-quantize", dest="quantize", action="store_const", const=False,
                        help="the same as --quantize off")
    parser.add_argument("--realism-keep", type=float_in(0.0, 1.0, low_open=True), default=None, metavar="FRACTION",
                        help="draw synthetic positives 1/FRACTION times over and keep the FRACTION that a critic in "
                             "HOG features, trained on the seed set's real patches, finds least synthetic (cross-fitted "
                             "by seed); 1: every drawn patch, the paper's; default: the detector family's (0.25 for "
                             "HOG and AdaBoost, 1 for the CNN)")
    parser.add_argument("--realism-selection", choices=list(REALISM_SELECTION), default="seed",
                        help="how the critic keeps its fraction: seed (each seed keeps the same share of its own "
                             "draws, the least synthetic of them; the default), set (the least synthetic of the "
                             "whole draw; a seed may keep none) or item (each patch the least synthetic of its own "
                             "1/keep candidates, as SyntheticObjectDataset's realism_critic draws)")
    parser.add_argument("--realism-features", choices=list(REALISM_FEATURES), default=None,
                        help="the critic's features (selections seed and set): hog or weak_learners (the "
                             "edge-orientation energies of random rectangles that AdaBoost's stumps threshold); "
                             "default: the detector family's (weak_learners for AdaBoost, hog for HOG and the CNN)")
    parser.add_argument("--distractor-ratio", type=nonneg_float, default=None, metavar="K",
                        help="add K rendered distractors per real seed to the negatives: drawn as the synthetic "
                             "positives are (their fit, poses, effects, 8 bits), an ellipsoid in place of the object "
                             "(domain randomisation's distractors); needs --synthetic-ratio; 0: none; default: the "
                             "detector family's with synthetic positives (5 for AdaBoost, 0 for HOG and the CNN)")
    parser.add_argument("--distractor-style", choices=list(DISTRACTOR_STYLES), default=None,
                        help="how the distractors look: drawn (as the object is drawn) or soft (each faint and blurred "
                             "against its background, like a cloud puff); needs distractors; default: the detector "
                             "family's (soft for AdaBoost, drawn for HOG and the CNN)")
    parser.add_argument("--background-sampling", choices=list(BACKGROUND_SAMPLING), default=None,
                        help="the synthetic objects' backgrounds: seed (the paper: each on its own seed's background) "
                             "or other (each on another seed's background, its capture parameters still its own); "
                             "default: the detector family's (other for the CNN, seed for HOG and AdaBoost)")
    parser.add_argument("--capture-sampling", choices=list(CAPTURE_SAMPLERS), default="seed",
                        help="how the synthetic positives' capture parameters are drawn: seed (the paper: one seed's "
                             "fitted row), uniform (each between its fitted extremes, the paper's Fig. 10) or kde")
    parser.add_argument("--effects-off", nargs="+", default=None, metavar="EFFECT",
                        type=lambda n: n if n == "none" else effect_name(n),
                        help="fitted effects left out of the synthetic positives (the paper's Fig. 9 ablation), e.g. "
                             "motion_blur; none: every fitted effect; default: the detector family's (the CNN leaves "
                             "boundary_blur and motion_blur out, measured on the drone videos; HOG and AdaBoost none)")
    parser.add_argument("--perturb-copies", type=int, default=0,
                        help="perturbed copies (rotation, shift, mirror, blur, noise) of every real positive: the paper's baseline")
    parser.add_argument("--downscaled-copies", type=int, default=0,
                        help="copies of every real seed shown as a smaller, farther object (its frame shrunk so the "
                             "object's longest side is 16-24 px), cut the way the detector's pyramid sees it")
    parser.add_argument("--faded-copies", type=int, default=0,
                        help="copies of every real seed with the object fainter against its own background (its "
                             "difference from the seed's background patch scaled by x0.3-0.9 inside the box)")
    parser.add_argument("--faded-contrast", type=float, nargs=2, metavar=("LOW", "HIGH"), default=None,
                        help="the faded copies' contrast range (default 0.3 0.9); a negative range, e.g. -1 -0.5, "
                             "inverts the object's contrast (a dark object shown brighter than its background)")
    parser.add_argument("--copy-paste-ratio", type=float, default=0.0,
                        help="copy-paste patches per real seed with --params: the seeds' objects cut out with their fitted "
                             "silhouettes, pasted on other seeds' backgrounds (a user's baseline)")
    parser.add_argument("--synthetic-share", type=synthetic_share_arg, default=None, metavar="SHARE",
                        help="the share of the positive class's training weight held by the added positives "
                             "(synthetic, copy-paste, perturbed, downscaled, faded), the rest by the real ones (HOG: the "
                             "SVM's sample cost; CNN: the loss's sample weight; AdaBoost: the positives' starting "
                             "weights), or 'count': every positive weighs the same; default: the family's (AdaBoost "
                             "0.25, HOG and the CNN by count)")
    parser.add_argument("--seed", type=int, default=0, help="training seed: initialisation, negative sampling, the automatic split")
    parser.add_argument("--ingest-seed", type=int, default=0, help="`synthaug ingest --seed` of the seed draw (shards are reused per value)")
    parser.add_argument("--val-fraction", type=float, default=0.2, help="share of the class's videos kept for validation without --split")
    parser.add_argument("--negative-classes", nargs="*", default=["bird"],
                        help="classes whose videos never show the class: mined whole for hard negatives")
    parser.add_argument("--mining-rounds", type=int, default=d["mining_rounds"], help="hard-negative mining rounds at most (0: none)")
    parser.add_argument("--mining-stride", type=int, default=d["mining_stride"], help="mine every K-th frame of every training video")
    parser.add_argument("--mining-per-frame", type=int, default=d["mining_per_frame"], help="false positives kept per mined frame")
    parser.add_argument("--mining-select", choices=list(MINING_SELECT), default=d["mining_select"],
                        help="the mining round kept: fewest validation false positives (fp) or highest validation AP of "
                             "the same detections (ap); default: the family's (fp for hog and cnn, ap for adaboost)")
    parser.add_argument("--mining-patience", type=int, default=d["mining_patience"],
                        help="mining rounds without a new best still run before stopping (0: stop at the first); "
                             "default: the family's (0 for hog and cnn, 1 for adaboost)")
    add_adaboost_options(parser)
    parser.add_argument("--mining-frame-scale", type=positive_float, nargs=2, metavar=("LOW", "HIGH"),
                        default=d["mining_frame_scale"],
                        help="resize every mined frame by a factor drawn log-uniformly in [LOW, HIGH] (per frame, from "
                             "--seed) before the pyramid scans it: negatives at magnifications the native frames never "
                             "reach; default 1 1: native frames")
    add_option(parser, "--val-frame-stride", aliases=["--val-stride"], type=int, default=d["val_stride"],
               help="validation false positives counted on every K-th validation frame")
    parser.add_argument("--scales", type=float, nargs="+", default=None,
                        help="pyramid of mining and validation (default: synthaug.detectors.sliding.DEFAULT_SCALES)")
    add_budget_options(parser)
    parser.add_argument("--box-model", choices=list(BOX_MODELS), default=d["box_model"],
                        help="box regression from the detection's context: a small CNN on its pixels, ridge on its HOG cells, or the "
                             "mean of both (ensemble)")
    parser.add_argument("--box-calibration", type=int_at_least(0), default=d["box_calibration"], metavar="STRIDE",
                        help="after training, correct the boxes by the detector's own errors on every STRIDE-th labelled "
                             "frame of its training videos (0: off; default: the family's, 20 for every family)")
    parser.add_argument("--box-calibration-form", choices=list(CALIBRATION_FORMS), default=d["box_calibration_form"],
                        help="how the calibration's size term is fitted: the labelled size on the detected one "
                             "(regression) or the detected size on the labelled one, inverted (inverse: −0.137 "
                             "AP@0.5 on the drone test videos, stop 76)")
    parser.add_argument("--cnn-shift", type=int, default=d["cnn_shift"],
                        help="CNN positives moved by random whole-pixel offsets up to this (0: off)")
    parser.add_argument("--extra-negatives", type=int, default=3000, help="object-free crops of the seed frames added to the seed set's negatives")
    parser.add_argument("--work", type=Path, help="ingest folder for --seed-counts (default: <out>.work)")
    parser.add_argument("--workers", type=int, default=2, help="ingest worker processes")
    parser.add_argument("--threads", type=int, default=None, help="torch intra-op threads (default: torch's)")
    add_option(parser, "--no-progress", aliases=["--quiet"], action="store_true", help="no progress lines on stderr")


def _err(message: str) -> int:
    print(f"synthaug train: error: {message}", file=sys.stderr)
    return 2


def main(args: argparse.Namespace) -> int:
    if args.detector not in _DETECTORS:
        return _err(f"--detector: unknown detector {args.detector!r}; choose from {list(_DETECTORS)}")
    for opt, value, low in (("--frame-step", args.frame_step, 1), ("--mining-stride", args.mining_stride, 1),
                            ("--mining-per-frame", args.mining_per_frame, 1), ("--val-frame-stride", args.val_frame_stride, 1),
                            ("--mining-rounds", args.mining_rounds, 0), ("--mining-patience", args.mining_patience, 0),
                            ("--workers", args.workers, 1)):
        if value is not None and value < low:  # None: the family's default
            return _err(f"{opt}: must be >= {low}, got {value}")
    if args.seed_counts is not None and args.seed_counts < 1:
        return _err(f"--seed-counts: must be >= 1, got {args.seed_counts}")
    if args.threads is not None and args.threads < 1:
        return _err(f"--threads: must be >= 1, got {args.threads}")
    if args.mining_frame_scale[0] > args.mining_frame_scale[1]:
        return _err(f"--mining-frame-scale: LOW must be <= HIGH, got {args.mining_frame_scale[0]:g} {args.mining_frame_scale[1]:g}")
    if args.synthetic_ratio is not None and args.params is None:
        return _err("--synthetic-ratio: synthetic positives need a fit: give --params FIT.json")
    from synthaug.detectors.video_training import check_placement

    try:
        check_placement([args.pose_sampling] if args.pose_sampling else [], [args.object_box])
    except ValueError as e:
        return _err(f"--pose-sampling: {e}")
    if args.object_box_share < 1 and args.object_box is None:
        return _err(f"--object-box-share {args.object_box_share:g} is the share of the objects --object-box frames: "
                    "give --object-box seed or fit")
    ratio = args.synthetic_ratio if args.synthetic_ratio is not None else (10.0 if args.params is not None else 0.0)

    import torch

    from synthaug.detectors.training import TrainOptions
    from synthaug.detectors.video_training import AddedPositives, TrainingInputError, train_from_videos

    if args.threads is not None:
        torch.set_num_threads(args.threads)
    try:
        options = TrainOptions(**budget_options(args), cnn_shift=args.cnn_shift, mining_rounds=args.mining_rounds,
                               mining_stride=args.mining_stride, mining_per_frame=args.mining_per_frame,
                               mining_select=args.mining_select, mining_patience=args.mining_patience,
                               val_stride=args.val_frame_stride, box_model=args.box_model,
                               box_calibration=args.box_calibration, box_calibration_form=args.box_calibration_form,
                               scales=None if args.scales is None else tuple(args.scales),
                               mining_frame_scale=tuple(args.mining_frame_scale),
                               ada_energy_floor=args.ada_energy_floor, ada_transfer=args.ada_transfer,
                               ada_cascade=args.ada_cascade)
    except ValueError as e:
        return _err(str(e))

    def log(msg: str) -> None:
        if not args.no_progress:
            print(f"[{time.strftime('%H:%M:%S')}] {msg}", file=sys.stderr, flush=True)

    try:
        det, meta = train_from_videos(
            args.detector, args.class_name, args.videos, args.labels, out=args.out, split=args.split, seed=args.seed,
            seed_count=100 if args.seed_counts is None else args.seed_counts, all_frames=args.all_frames,
            frame_step=args.frame_step, seedset=args.seed_set, positive_videos=args.positive_videos,
            added=AddedPositives(params=args.params, mesh=args.mesh, synthetic_ratio=ratio,
                                 perturb_copies=args.perturb_copies, pose_sampling=args.pose_sampling,
                                 object_box=args.object_box, object_box_share=args.object_box_share,
                                 shape_variation=args.shape_variation,
                                 capture_sampling=args.capture_sampling, effects_off=_effects_off(args.effects_off),
                                 copy_paste_ratio=args.copy_paste_ratio, synthetic_share=args.synthetic_share,
                                 downscaled_copies=args.downscaled_copies, faded_copies=args.faded_copies,
                                 faded_contrast=None if args.faded_contrast is None else tuple(args.faded_contrast),
                                 quantize=args.quantize, background_sampling=args.background_sampling,
                                 realism_keep=args.realism_keep, realism_selection=args.realism_selection,
                                 realism_features=args.realism_features,
                                 distractor_ratio=args.distractor_ratio,
                                 distractor_style=args.distractor_style),
            options=options, work_dir=args.work, ingest_seed=args.ingest_seed,
            ingest_workers=args.workers, negative_classes=tuple(args.negative_classes), val_fraction=args.val_fraction,
            extra_negatives=args.extra_negatives, log=log,
            command={k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items() if not k.startswith("_")},
        )
    except TrainingInputError as e:
        return _err(str(e))
    except (ValueError, FileNotFoundError) as e:
        return _err(str(e))
    rounds = meta["mining"]["rounds"]
    summary = {"out": str(args.out), "metadata": str(args.out.with_suffix(".json")), "detector": args.detector,
               "class": args.class_name, "train_videos": len(meta["split"]["train"]), "val_videos": len(meta["split"]["val"]),
               "positives": meta["positives"]["count"] + (meta["synthetic"]["count"] if meta["synthetic"] else 0),
               "negatives": meta["negatives"]["final"],
               "mining": [{"round": r["round"], "added": r["added"], "val_fp": None if r["val"] is None else r["val"]["fp"]}
                          for r in rounds],
               "chosen_round": meta["mining"]["chosen_round"], "seconds": meta["seconds"]["total"]}
    print(json.dumps(summary))
    return 0
