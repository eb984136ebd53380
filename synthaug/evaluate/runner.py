"""Run training conditions under the evaluation protocol, one cached cell per (condition, seed).

A *condition* is a detector family and a training set (``real 100 seeds``,
``all training frames``, ``100 seeds + 20x synthetic``...). For each training
seed of the protocol (``min_training_seeds``; the seed drives the seed draw of
``synthaug ingest``, the negatives and the initialisation), the detector is
trained by :func:`synthaug.detectors.video_training.train_from_videos` — the code
path of ``synthaug train`` — and scored on the protocol's test frames (and,
optionally, the scale check and the patch protocol). Each (condition, seed) is
one cell of a :class:`~synthaug.evaluate.cells.CellCache`, keyed by the
protocol's fingerprint, the condition, the seed, the training budgets, the
pyramid scales and :data:`TRAINING_VERSION`; several processes may run the
same experiment at once (each cell is computed once). The trained detectors are
kept beside the cells (``<cache>/detectors/``): a cell that differs only in what
it scores (the validation split, the scale check, the patch protocol) reads its
detector back instead of training it again.

Results are :class:`~synthaug.evaluate.results.ProtocolResult`: bootstrap CIs
over test videos, paired differences between conditions (same seeds, same
resamples), AP by object size. The learning curve (issue 15, item 7) is
:func:`learning_curve`::

    python -m synthaug.evaluate.runner learning-curve --class drone --detectors hog cnn \\
        --seed-counts 12 100 --all-frames --out results/learning_curve/drone
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from synthaug._checks import add_option, float_in, int_at_least, nonneg_float, one_of, positive_float
from synthaug._io import exclusive_lock
from synthaug.data.captures import CAPTURE_SAMPLERS
from synthaug.data.items import BACKGROUND_SAMPLING
from synthaug.data.poses import POSE_SAMPLING
from synthaug.data.synthetic import check_object_box_share
from synthaug.detectors.train_cli import (
    QUANTIZE_ARGS,
    add_adaboost_options,
    add_budget_options,
    budget_options,
    effect_name,
    synthetic_share_arg,
)
from synthaug.detectors.box_calibration import CALIBRATION_FORMS, CALIBRATION_VERSION
from synthaug.detectors.critic import (REALISM_FEATURES, REALISM_SELECTION, check_realism_features,
                                       check_realism_selection, realism_variants)
from synthaug.detectors.training import BOX_MODELS, MINING_SELECT, TrainOptions
from synthaug.detectors.training_sets import check_quantize, DISTRACTOR_STYLES, quantize_name
from synthaug.detectors.video_training import (
    BY_COUNT,
    PAPER_SYNTHETIC,
    AddedPositives,
    calibrate_detector,
    check_placement,
    resolve_background_sampling,
    resolve_effects_off,
    resolve_realism_keep,
    resolve_synthetic_option,
    resolve_synthetic_share,
    train_from_videos,
)
from synthaug.evaluate.cells import CellCache
from synthaug.evaluate.matching import match_videos
from synthaug.evaluate.patches import patch_eval_set, score_patch_set
from synthaug.evaluate.protocol import Protocol, load_protocol, split_videos
from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.summary import report_table, summarize
from synthaug.evaluate.videos import detect_on_eval_set, load_eval_set, refine_detections, scale_eval_set

__all__ = ["TRAINING_VERSION", "OWN_DISTANCE", "Condition", "DataPaths", "ProtocolRunner", "learning_curve",
           "synthetic_comparison", "train_options", "main"]

OWN_DISTANCE = {"hog": "hog", "adaboost": "wl_learned", "cnn": "cnn"}
"""Each detector family's own distance of the paper's fits (d_HOG, d_WL^L, d_CNN)."""


TRAINING_VERSION = 6
"""Bumped whenever the training code changes what a cell would hold (2: the CNN trains through
``PatchDetectorModule``; 3: hard-negative mining over all training videos for every family; 4: a box
regressor in the annotators' convention, scored with and without it; 5: the box regressor is fitted
before the mining rounds, so their validation false-positive count matches at the reported boxes; 6: a second
NMS after the box regression)."""


# how a condition's name says its pose sampling (the former ", fitted poses" kept; "uniform": nothing)
_POSE_NAMES = {"uniform": "", "fitted": ", fitted poses", "uniform_at_seed": ", at the seeds' offsets",
               "fitted_at_seed": ", fitted poses at the seeds' offsets"}


@dataclass(frozen=True)
class Condition:
    """One training condition.

    Attributes:
        name: label in tables (``"hog / 100 seeds"``).
        kind: ``"hog"``, ``"adaboost"`` or ``"cnn"``.
        seed_count: real seeds drawn as ``synthaug ingest`` draws them (None with ``all_frames``).
        all_frames: every ``frame_step``-th labelled frame of the training videos.
        frame_step: see ``all_frames``.
        positive_videos: positives from only this many training videos, drawn by the training seed (None: all;
            :func:`~synthaug.detectors.video_training.positive_video_subset`); mining, box map and validation use all.
        params, synthetic_ratio, mesh: synthetic positives from a fit (``synthaug fit`` output) of the
            cell's seed set: ``params`` may hold ``{seed}`` (one fit per training seed, since each
            training seed draws its own seed set).
        fit_distance: fit the cell's seed set with this distance (``synthaug fit``'s defaults) when
            the ``params`` file is missing (default path: ``<work>/fits/<class>_<n>_seed<seed>_<distance>.json``,
            ``..._<distance>_<mesh stem>.json`` with a ``mesh``; a stored fit of another mesh is refused).
        fit_options: other :class:`~synthaug.fit.fitting.FitConfig` fields of that fit, as
            ``(name, value)`` pairs (default: ``synthaug fit``'s).
        perturb_copies: perturbed copies of every real positive (the paper's baseline).
        downscaled_copies: copies of every real seed shown smaller (farther), cut the way the pyramid sees them
            (:func:`~synthaug.detectors.training_sets.downscaled_positives`).
        faded_copies: copies of every real seed with the object fainter against its own background
            (:func:`~synthaug.detectors.training_sets.faded_positives`).
        faded_contrast: their contrast range (None: the default; a negative range inverts the object's contrast).
        pose_sampling: poses of the synthetic positives (``"uniform"``: the paper; ``"fitted"``: around
            each seed's fitted pose; either with ``"_at_seed"``: the object at its seed's fitted offset). None (the
            default), like ``shape_variation``, ``quantize``, ``realism_features``, ``distractor_ratio`` and
            ``distractor_style`` left at None: the family's
            (:data:`~synthaug.detectors.video_training.FAMILY_SYNTHETIC`, the paper's where nothing is drawn), resolved
            here, so a family's default cell has the key of the same options given.
        copy_paste_ratio: copy-paste patches per real seed (the real objects cut out with the fit's
            silhouettes, pasted on other seeds' backgrounds; a user's baseline).
        synthetic_share: the added positives' share of the positive class's training weight: a number,
            ``"count"`` (every positive weighs the same) or None (the default: the family's,
            :data:`~synthaug.detectors.video_training.FAMILY_SYNTHETIC_SHARE`), resolved here (None once resolved: by
            count, so cells by count keep their keys, and a family's default share has the key of that share given).
        object_box: None (the paper's framing) or ``"seed"``: synthetic objects framed as ingest frames a labelled
            seed (:class:`~synthaug.data.synthetic.SyntheticObjectDataset`'s ``object_box``).
        object_box_share: the fraction of the synthetic objects ``object_box`` frames (1: every one), the others
            framed as the paper's (:class:`~synthaug.data.synthetic.SyntheticObjectDataset`'s ``object_box_share``).
        shape_variation: 0 (the paper) or the synthetic objects' shape variation around the mesh
            (:class:`~synthaug.data.synthetic.SyntheticObjectDataset`'s ``shape_variation``).
        capture_sampling: ``"seed"`` (the paper) or how else the synthetic positives' capture parameters are drawn
            (``"uniform"``: between the fitted extremes, the paper's Fig. 10; ``"kde"``).
        effects_off: fitted effects left out of the synthetic positives (the paper's Fig. 9); ``()``: every effect;
            None (the default): the family's (:data:`~synthaug.detectors.video_training.FAMILY_EFFECTS_OFF`), resolved
            here so that a cell's key names what its training draws.
        dcnn_refit: the d_CNN refit (CNN only): after every mining round the fit is refitted with the network just
            trained as its distance (:func:`~synthaug.fit.refit.refit_with_network`, the fit's own options otherwise)
            and the next round's synthetic positives are redrawn from it (``AddedPositives.refit``). False: one fit.
        quantize: the synthetic positives rounded to 8-bit levels, as the real frames are (``AddedPositives``'
            ``quantize``; ``"native_scale"``: those of the seeds seen at about their own size). False: the renderer's
            continuous values.
        background_sampling: ``"seed"`` (the paper: each synthetic object on its own seed's background) or
            ``"other"`` (on another seed's; ``AddedPositives``' ``background_sampling``); None (the default): the
            family's (:data:`~synthaug.detectors.video_training.FAMILY_BACKGROUND_SAMPLING`), resolved here as the
            effects are.
        realism_keep: the fraction of drawn synthetic positives kept, those a critic in HOG features finds least
            synthetic (``AddedPositives``' ``realism_keep``; 1: every draw, the paper); None (the default): the
            family's (:data:`~synthaug.detectors.video_training.FAMILY_REALISM_KEEP`), resolved here as the effects
            are.
        realism_selection: ``AddedPositives``' ``realism_selection`` (``"seed"``, the default, ``"item"``, or ``"set"``,
            which is absent from the key: stop 82's cells keep theirs); ``"set"`` wherever every draw is kept.
        realism_features: the critic's features (``AddedPositives``' ``realism_features``: ``"hog"``, the default,
            absent from the key, or ``"weak_learners"``); ``"hog"`` wherever every draw is kept.
        distractor_ratio: rendered distractors per real seed added to the negatives (``AddedPositives``'
            ``distractor_ratio``; synthetic cells only; absent from the key at 0).
        distractor_style: how they look (``AddedPositives``' ``distractor_style``: ``"drawn"``, the default, absent
            from the key, or ``"soft"``); ``"drawn"`` wherever there are none.
    """

    name: str
    kind: str
    seed_count: int | None = 100
    all_frames: bool = False
    frame_step: int = 3
    params: str | None = None
    synthetic_ratio: float = 0.0
    mesh: str | None = None
    fit_distance: str | None = None
    fit_options: tuple[tuple[str, Any], ...] = ()
    perturb_copies: int = 0
    pose_sampling: str | None = None
    copy_paste_ratio: float = 0.0
    synthetic_share: float | str | None = None
    downscaled_copies: int = 0
    faded_copies: int = 0
    object_box: str | None = None
    faded_contrast: tuple[float, float] | None = None
    positive_videos: int | None = None
    shape_variation: float | None = None
    capture_sampling: str = "seed"
    effects_off: tuple[str, ...] | None = None
    dcnn_refit: bool = False
    quantize: bool | str | None = None
    background_sampling: str | None = None
    object_box_share: float = 1.0
    realism_keep: float | None = None
    realism_selection: str = "seed"
    realism_features: str | None = None
    distractor_ratio: float | None = None
    distractor_style: str | None = None

    def __post_init__(self) -> None:
        for name in PAPER_SYNTHETIC:  # the family's way of drawing its synthetic positives, resolved into the key
            object.__setattr__(self, name, resolve_synthetic_option(
                self.kind, name, getattr(self, name), synthetic=bool(self.synthetic_ratio), object_box=self.object_box,
                distractor_ratio=self.distractor_ratio, realism_selection=self.realism_selection))
        if self.distractor_ratio and not self.synthetic_ratio:
            raise ValueError("distractor_ratio: distractors are drawn as the synthetic positives are; this condition "
                             "has none")
        one_of(self.distractor_style, DISTRACTOR_STYLES, "distractor_style")
        if not self.distractor_ratio:  # no distractors: one cell, whatever their style
            object.__setattr__(self, "distractor_style", "drawn")
        off = self.effects_off
        object.__setattr__(self, "effects_off", () if off is None and not self.synthetic_ratio
                           else resolve_effects_off(self.kind, off))
        bs = self.background_sampling
        object.__setattr__(self, "background_sampling", "seed" if bs is None and not self.synthetic_ratio else
                           resolve_background_sampling(self.kind, bs, None if self.all_frames else self.seed_count))
        object.__setattr__(self, "synthetic_share", resolve_synthetic_share(self.kind, self.synthetic_share)
                           if self.adds_positives() else None)
        check_object_box_share(self.object_box_share, self.object_box)
        rk = self.realism_keep
        object.__setattr__(self, "realism_keep", 1.0 if rk is None and not self.synthetic_ratio else
                           resolve_realism_keep(self.kind, rk, None if self.all_frames else self.seed_count))
        check_realism_selection(self.realism_selection)
        # a keep of 1 selects nothing: one cell, whatever the selection
        (_, selection), = realism_variants([self.realism_keep], [self.realism_selection])
        object.__setattr__(self, "realism_selection", selection)
        check_realism_features(self.realism_features, selection=selection if self.realism_keep < 1 else None)
        if self.realism_keep == 1:  # no critic: one cell, whatever its features
            object.__setattr__(self, "realism_features", "hog")

    def identity(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d.pop("name")
        if self.all_frames:
            d["seed_count"] = None
        else:
            d["frame_step"] = None
        for k in ("fit_distance", "fit_options", "perturb_copies", "pose_sampling", "copy_paste_ratio",  # added later:
                  "synthetic_share", "downscaled_copies", "faded_copies", "object_box", "faded_contrast",
                  "positive_videos", "shape_variation"):
            if d[k] in (None, 0, (), "uniform"):                     # absent at their defaults (older cells keep their keys)
                d.pop(k)
        for k, default in (("capture_sampling", "seed"), ("effects_off", ()),  # added later still: the same, with
                           ("dcnn_refit", False), ("quantize", False), ("background_sampling", "seed"),
                           ("object_box_share", 1.0), ("realism_keep", 1.0), ("realism_selection", "set"),
                           ("realism_features", "hog"), ("distractor_ratio", 0.0), ("distractor_style", "drawn")):
            if d[k] == default:                                                  # their own defaults
                d.pop(k)
        return d

    def adds_positives(self) -> bool:
        """Whether the training set holds positives besides the real ones (synthetic, perturbed, copy-paste, ...)."""
        return bool(self.synthetic_ratio or self.perturb_copies or self.copy_paste_ratio or self.downscaled_copies
                    or self.faded_copies)


@dataclass(frozen=True)
class DataPaths:
    """The shared-format folders and the split (any folder of videos in that format)."""

    videos_dir: str = "../shared/data/halmstad/videos"
    labels_dir: str = "../shared/data/halmstad/labels"
    split_file: str | None = "configs/splits/halmstad.json"
    work_dir: str = "data/runs"


@dataclass
class ProtocolRunner:
    """Trains and scores conditions for one class under one protocol.

    Args:
        protocol: the protocol (:func:`~synthaug.evaluate.protocol.load_protocol`).
        class_name: the class to detect.
        paths: data folders and the split.
        cache: the cell cache.
        options: training budgets (part of every cell's key: :meth:`TrainOptions.key_fields`, which leaves out
            the fields added later while they are at their former values, so older cells stay valid).
        scales: pyramid factors of mining, validation and detection (None: the detectors' default; part of the
            key and of the trained detector's).
        detect_scales: pyramid factors of the scored detections only (None: ``scales``). Part of the cell's key
            when set, not of the trained detector's: a detector that is slow to train is scored with another
            pyramid without training it again.
        scale_check: also score the protocol's ``scale_check`` factors.
        patches: also score the paper's patch protocol.
        max_test_videos: use only the first this-many test videos (smoke runs; part of the key).
        eval_split: ``"test"`` (the protocol's test frames) or ``"val"`` (its validation frames:
            choosing a setting on them keeps the test split for the final number; part of the key).
        log: progress printer.
    """

    protocol: Protocol
    class_name: str = "drone"
    paths: DataPaths = field(default_factory=DataPaths)
    cache: CellCache | None = None
    options: TrainOptions = field(default_factory=TrainOptions)
    scales: tuple[float, ...] | None = None
    detect_scales: tuple[float, ...] | None = None
    scale_check: bool = True
    patches: bool = True
    max_test_videos: int | None = None
    eval_split: str = "test"
    log: Callable[[str], None] = print

    def __post_init__(self) -> None:
        if self.eval_split not in ("test", "val"):
            raise ValueError(f"eval_split must be 'test' or 'val', got {self.eval_split!r}")
        if self.cache is None:
            self.cache = CellCache(Path(self.paths.work_dir) / "cells")
        self._eval: dict[float, Any] = {}
        self._patches: Any = None

    # data ---------------------------------------------------------------------------------------
    def _frames(self) -> Any:
        return self.protocol.test if self.eval_split == "test" else self.protocol.val

    def test_videos(self) -> list[str]:
        stems = split_videos(self.protocol, self._frames().split, split_file=self.paths.split_file,
                             class_name=self.class_name)
        return stems[: self.max_test_videos] if self.max_test_videos else stems

    def scales_scored(self) -> tuple[float, ...]:
        return (1.0, *self.protocol.scale_check) if self.scale_check else (1.0,)

    def eval_set(self, scale: float = 1.0) -> Any:
        if 1.0 not in self._eval:
            t0 = time.perf_counter()
            self._eval[1.0] = load_eval_set(self.test_videos(), self.paths.videos_dir, self.paths.labels_dir,
                                            stride_k=self._frames().frame_stride,
                                            skip_unlabelled=self._frames().unlabelled_frames == "skip")
            es = self._eval[1.0]
            self.log(f"[test] {len(es.stems)} videos, {es.n_frames} frames (every {es.stride_k}th), "
                     f"{es.n_objects} objects, decoded in {time.perf_counter() - t0:.0f} s")
        if scale not in self._eval:
            self._eval[scale] = scale_eval_set(self._eval[1.0], scale)
        return self._eval[scale]

    def patch_set(self) -> Any:
        if self._patches is None:
            self._patches = patch_eval_set(self.paths.videos_dir, self.paths.labels_dir, self._frames().split,
                                           self.protocol, videos=self.test_videos(), split_file=self.paths.split_file,
                                           class_name=self.class_name)
        return self._patches

    # cells --------------------------------------------------------------------------------------
    def identity(self, condition: Condition, seed: int) -> dict[str, Any]:
        cond = condition.identity()
        if condition.params is not None and condition.fit_distance is None:  # a given fit: its bytes are part of the key
            import hashlib

            path = Path(condition.params.format(seed=seed))
            cond["params_sha256"] = hashlib.sha256(path.read_bytes()).hexdigest()[:16] if path.is_file() else None
        options = self.options.key_fields(condition.kind)
        if "box_calibration" in options:  # applied when scoring (:meth:`_calibrated`), versioned with its fit
            options["box_calibration"] = {"stride": options["box_calibration"], "version": CALIBRATION_VERSION}
        if not condition.adds_positives():  # the CNN's fine-tuning on the real positives, AdaBoost's transfer rule
            options.pop("cnn_finetune_epochs", None)  # and its real-positive cascade act on added positives only:
            options.pop("ada_transfer", None)  # without them, the same training and the same cell
            options.pop("ada_cascade", None)
        return {"what": "protocol_cell", "protocol": self.protocol.fingerprint(), "class": self.class_name,
                "condition": cond, "seed": int(seed), "options": options,
                "scales": None if self.scales is None else list(self.scales), "scored_scales": list(self.scales_scored()),
                "patches": self.patches, "max_test_videos": self.max_test_videos,
                **({} if self.eval_split == "test" else {"eval_split": self.eval_split}),
                **({} if self.detect_scales is None else {"detect_scales": list(self.detect_scales)}),

                "split_file": self.paths.split_file, "training_version": TRAINING_VERSION}

    def params_for(self, condition: Condition, seed: int) -> Any:
        """The fit of the cell's seed set: a path, a callable that makes it when missing, or None."""
        if condition.params is None and condition.fit_distance is None:
            return None
        n = condition.seed_count
        mesh_tag = "" if condition.mesh is None else f"_{Path(condition.mesh).stem}"  # one fit file per mesh
        path = Path(condition.params.format(seed=seed)) if condition.params is not None else \
            Path(self.paths.work_dir) / "fits" / f"{self.class_name}_{n}_seed{seed}_{condition.fit_distance}{mesh_tag}.json"
        if condition.fit_distance is None:
            return path

        def make(seedset_path: Path) -> Path:
            # cells of one seed set in two processes make its fit once: the second waits, then reads it
            with exclusive_lock(path.with_name(f".{path.name}.make.lock")):
                if path.is_file():
                    _check_fit_mesh(path, condition.mesh or "quadcopter")
                    return path
                from synthaug.fit.fitting import FitConfig, fit_seedset

                t0 = time.perf_counter()
                cfg = FitConfig(distance=condition.fit_distance, **dict(condition.fit_options))
                fit_seedset(seedset_path, condition.mesh or "quadcopter", path, cfg)
                self.log(f"    fit {path} ({condition.fit_distance}): {time.perf_counter() - t0:.0f} s")
            return path

        return make

    def training_identity(self, condition: Condition, seed: int) -> dict[str, Any]:
        """What the trained detector of a cell depends on: the cell's identity without what is only scored.

        Cells that differ only in the split they score, the scale check, the patch protocol, the pyramid of
        the scored detections, the box calibration or the number of test videos share one trained detector (the mining's validation
        frames are the protocol's either way).
        """
        ident = self.identity(condition, seed)
        for k in ("scored_scales", "patches", "max_test_videos", "eval_split", "detect_scales"):
            ident.pop(k, None)
        ident["options"] = {k: v for k, v in ident["options"].items()
                            if k not in ("box_calibration", "box_calibration_form")}
        return {**ident, "what": "trained_detector"}

    def _trained(self, condition: Condition, seed: int) -> tuple[Any, dict[str, Any], float, bool]:
        """The cell's detector, its training metadata, its training seconds and whether it was read back.

        Trained detectors are kept in ``<cache>/detectors/<key>.pt``, with a cell of the same key holding the
        training's metadata, so a cell that only scores differently reads the detector back instead of training
        it again. A second process asking for the same detector waits on the first one's lock; a stored file
        that is missing or unreadable is trained again and replaced.
        """
        from synthaug.detectors.base import load_detector, save_detector

        store = CellCache(self.cache.root / "detectors")  # type: ignore[union-attr]
        ident = self.training_identity(condition, seed)
        ckpt = store.path(ident).with_suffix(".pt")
        doc = store.get(ident)
        if doc is not None:
            try:
                det = load_detector(ckpt)
            except (FileNotFoundError, ValueError) as e:
                self.log(f"    stored detector unusable ({e}); training it again")
                store.path(ident).unlink(missing_ok=True)
            else:
                self.log(f"    detector read back from {ckpt} (trained in {doc['train_s']:.0f} s)")
                return det, doc["meta"], doc["train_s"], True
        trained: list[Any] = []

        def train() -> dict[str, Any]:
            det, meta, seconds = self._train(condition, seed)
            save_detector(det, ckpt)
            trained.append(det)
            # where it was trained: a detector read back later is scored elsewhere (machine_info)
            return {"meta": _json_safe({**meta, "machine": machine_info()}), "train_s": round(seconds, 1),
                    "file": ckpt.name}

        doc = store.get_or_compute(ident, train)
        if trained:
            return trained[0], doc["meta"], doc["train_s"], False
        self.log(f"    detector read back from {ckpt}, trained by another process while this one waited")
        return load_detector(ckpt), doc["meta"], doc["train_s"], True

    def _train(self, condition: Condition, seed: int) -> tuple[Any, dict[str, Any], float]:
        t0 = time.perf_counter()
        options = self.options if self.scales is None else dataclasses.replace(self.options, scales=tuple(self.scales))
        options = dataclasses.replace(options, box_calibration=0)  # the stored detector is uncorrected: _calibrated
        det, meta = train_from_videos(
            condition.kind, self.class_name, self.paths.videos_dir, self.paths.labels_dir,
            split=self.paths.split_file, seed=seed, seed_count=condition.seed_count, all_frames=condition.all_frames,
            frame_step=condition.frame_step, positive_videos=condition.positive_videos,
            added=AddedPositives(params=self.params_for(condition, seed), mesh=condition.mesh,
                                 synthetic_ratio=condition.synthetic_ratio, perturb_copies=condition.perturb_copies,
                                 pose_sampling=condition.pose_sampling, copy_paste_ratio=condition.copy_paste_ratio,
                                 synthetic_share=(condition.synthetic_share if condition.synthetic_share is not None
                                                  else BY_COUNT if condition.adds_positives() else None),
                                 downscaled_copies=condition.downscaled_copies,
                                 faded_copies=condition.faded_copies, object_box=condition.object_box,
                                 object_box_share=condition.object_box_share,
                                 faded_contrast=condition.faded_contrast, shape_variation=condition.shape_variation,
                                 capture_sampling=condition.capture_sampling,
                                 # the family's own set goes as None: training keeps those the fit has
                                 effects_off=None if condition.effects_off == resolve_effects_off(condition.kind, None)
                                 else condition.effects_off,
                                 refit=self._refit(condition, seed) if condition.dcnn_refit else None,
                                 quantize=condition.quantize, background_sampling=condition.background_sampling,
                                 realism_keep=condition.realism_keep,
                                 realism_selection=condition.realism_selection,
                                 realism_features=condition.realism_features,
                                 distractor_ratio=condition.distractor_ratio,
                                 distractor_style=condition.distractor_style),
            options=options,
            work_dir=Path(self.paths.work_dir) / f"ingest_{self.class_name}_seed{seed}", ingest_seed=seed,
            log=lambda m: self.log(f"    {m}"))
        return det, meta, time.perf_counter() - t0

    def _refit(self, condition: Condition, seed: int) -> Callable[[Path, Path, Any, int], Path]:
        """The d_CNN refit of a cell: the fit refitted against round r's network, the fit's own options otherwise
        (its seed moved by r + 1), into ``<cache>/refits/<detector key>_round<r>.json`` (kept for inspection)."""
        from synthaug.fit.config import config_from_json
        from synthaug.fit.refit import refit_with_network
        from synthaug.params import CaptureParams

        key = CellCache(self.cache.root / "detectors").path(self.training_identity(condition, seed)).stem  # type: ignore[union-attr]

        def refit(fit: Path, seedset: Path, det: Any, r: int) -> Path:
            _, _, meta = CaptureParams.load_with_extra(fit)
            cfg = config_from_json(meta["config"])
            cfg = dataclasses.replace(cfg, seed=cfg.seed + r + 1)
            out = self.cache.root / "refits" / f"{key}_round{r}.json"  # type: ignore[union-attr]
            return refit_with_network(det.net, seedset, condition.mesh or meta.get("mesh") or "quadcopter", out, cfg)

        return refit

    def _train_and_score(self, condition: Condition, seed: int) -> dict[str, Any]:
        t0 = time.perf_counter()
        det, meta, t_train, read_back = self._trained(condition, seed)
        machine = machine_info()
        out: dict[str, Any] = {"train_s": round(t_train, 1), "train": meta, "scales": {},  # meta: plain JSON already
                               "machine": machine, "detector_read_back": read_back}
        calibration = self.options.for_family(condition.kind).box_calibration
        if calibration:
            out["box_calibration"] = self._calibrated(det, meta, calibration)
        for s in self.scales_scored():
            es = self.eval_set(s)
            t1 = time.perf_counter()
            raw = detect_on_eval_set(det, es, scales=self.scales if self.detect_scales is None else self.detect_scales,
                                     nms_iou=self.protocol.detection.nms_iou,
                                     max_detections=self.protocol.detection.max_detections, refine_boxes=False)
            t_det = time.perf_counter() - t1
            dets = refine_detections(det, es, raw, nms_iou=self.protocol.detection.nms_iou)  # what detect_multiscale reports
            t_ref = time.perf_counter() - t1 - t_det
            res = ProtocolResult(condition.name, self.protocol, split=self.eval_split, scale=s)
            pats = score_patch_set(det, self.patch_set()) if (self.patches and s == 1.0) else ()
            res.add_seed(seed, videos=match_videos(es.stems, dets, es.boxes, self.protocol), patches=pats,
                         meta={"detect_s": round(t_det + t_ref, 1), "fps": round(es.n_frames / max(t_det + t_ref, 1e-9), 2),
                               "box_regression_s": round(t_ref, 1),
                               "positives": (meta.get("positives") or {}).get("count"),
                               # carried into the results' files, so a cell that does not reproduce can be traced to
                               # its machines (None: a detector stored before they were recorded)
                               "trained_on": meta.get("machine"), "scored_on": machine})
            out["scales"][repr(float(s))] = res.to_json()
            if getattr(det, "box_regressor", None) is not None:  # item 5: AP before the box mapping, same detections
                unref = ProtocolResult(f"{condition.name}, window boxes", self.protocol, split=self.eval_split, scale=s)
                unref.add_seed(seed, videos=match_videos(es.stems, raw, es.boxes, self.protocol), patches=pats, meta={})
                out.setdefault("window_boxes", {})[repr(float(s))] = unref.to_json()
            self.log(f"  {condition.name} seed {seed} x{s:g}: AP@{self.protocol.main_iou:g} {res.mean_ap():.3f} "
                     f"(detect {t_det + t_ref:.0f} s, {es.n_frames / max(t_det + t_ref, 1e-9):.1f} fps)")
        out["total_s"] = round(time.perf_counter() - t0, 1)
        return out

    def _calibrated(self, det: Any, meta: Mapping[str, Any], stride: int) -> dict[str, Any]:
        """Correct ``det``'s boxes by its own errors on every ``stride``-th labelled frame of its
        training videos (the split its metadata records), detected as the scored frames are
        (:func:`~synthaug.detectors.video_training.calibrate_detector`); the correction's metadata. The stored
        detector stays uncorrected, so cells that differ only in this option share it."""
        return _json_safe(calibrate_detector(
            det, self.paths.videos_dir, self.paths.labels_dir, meta["split"]["train"],
            stride=stride, scales=self.scales if self.detect_scales is None else self.detect_scales,
            nms_iou=self.protocol.detection.nms_iou, max_detections=self.protocol.detection.max_detections,
            form=self.options.box_calibration_form, say=lambda m: self.log(f"    {m}")))

    def run(self, condition: Condition, seeds: Sequence[int] | None = None, *,
            window_boxes: bool = False) -> dict[float, ProtocolResult]:
        """The condition's results per scored scale, all seeds combined (cells reused when cached).

        With ``window_boxes``, the same detections scored with the windows' boxes (before the
        detector's box regression; empty when the detectors have none).
        """
        seeds = list(range(self.protocol.min_training_seeds)) if seeds is None else [int(s) for s in seeds]
        per_scale: dict[float, list[ProtocolResult]] = {}
        for seed in seeds:
            t0 = time.perf_counter()
            cell = self.cache.get_or_compute(self.identity(condition, seed),  # type: ignore[union-attr]
                                             lambda: self._train_and_score(condition, seed))
            if cell is None:
                self.log(f"  {condition.name} seed {seed}: not in the cache (read-only)")
                continue
            if time.perf_counter() - t0 > 1.0:
                self.log(f"  {condition.name} seed {seed}: cell done in {cell.get('total_s', 0):.0f} s")
            for s, doc in (cell.get("window_boxes") or {} if window_boxes else cell["scales"]).items():
                per_scale.setdefault(float(s), []).append(ProtocolResult.from_json(doc))
        out = {}
        name = f"{condition.name}, window boxes" if window_boxes else condition.name
        for s, parts in per_scale.items():
            if window_boxes and len(parts) != len(seeds):  # cells without a box regressor lack them
                continue
            res = ProtocolResult.combine(parts, condition=name)
            res.meta.update({"kind": condition.kind, "condition": condition.identity()})
            if window_boxes:
                res.meta["window_boxes"] = True
            out[s] = res
        return out


def _check_fit_mesh(path: Path, mesh: str) -> None:
    """Refuse a stored fit made with another mesh than the cell's: its poses, scales and effects belong to that shape."""
    from synthaug.params import CaptureParams

    _, _, meta = CaptureParams.load_with_extra(path)
    made = meta.get("mesh")
    if made is None or str(made) == str(mesh):
        return
    if Path(str(made)).is_file() and Path(mesh).is_file() and Path(str(made)).resolve() == Path(mesh).resolve():
        return
    raise ValueError(f"{path} was fitted with mesh {made!r}, not {mesh!r}: remove it (it is made again) or pass the "
                     f"mesh it was fitted with")


def _json_safe(x: Any) -> Any:
    return json.loads(json.dumps(x, default=str))


# ------------------------------------------------------------------------------------------ learning curve
def learning_curve(runner: ProtocolRunner, *, detectors: Sequence[str], seed_counts: Sequence[int],
                   all_frames: bool, frame_step: int = 3, seeds: Sequence[int] | None = None,
                   positive_videos: Sequence[int] = (),
                   out: str | Path | None = None) -> dict[str, dict[str, ProtocolResult]]:
    """Real data only: each detector at each seed count (and all training frames), both protocols.

    ``positive_videos``: the same conditions again with the positives drawn from only K training videos, for
    each K (:attr:`Condition.positive_videos`: more frames of the same videos vs more videos), beside the
    conditions with all of them.

    Writes (when ``out``): ``<kind>_<condition>[_x<scale>].json`` (:class:`ProtocolResult`),
    ``learning_curve.md`` (a :func:`report_table` per detector and scale, the paired difference
    against the largest seed count) and ``learning_curve.png`` (AP@main IoU with its 95 % CI
    against the number of positives).
    """
    results: dict[str, dict[str, ProtocolResult]] = {}
    for kind in detectors:
        conds = []
        for k in (None, *map(int, positive_videos)):
            of = "" if k is None else f" of {k} videos"
            conds += [Condition(f"{kind} / {n} seeds{of}", kind, seed_count=int(n), positive_videos=k)
                      for n in seed_counts]
            if all_frames:
                conds.append(Condition(f"{kind} / all training frames{of}", kind, seed_count=None, all_frames=True,
                                       frame_step=frame_step, positive_videos=k))
        for c in conds:
            _run_into(results, runner, c, seeds)
            _run_into(results, runner, c, seeds, window_boxes=True)  # item 5: AP before the box mapping
    if out is not None:
        write_learning_curve(results, Path(out), baseline_count=max(seed_counts) if seed_counts else None)
    return results


def _run_into(results: dict[str, dict[str, ProtocolResult]], runner: ProtocolRunner, condition: Condition,
              seeds: Sequence[int] | None, *, window_boxes: bool = False) -> None:
    """``runner.run(condition)`` filed as ``results[<kind>[ x<scale>]][<row label>]``."""
    for s, res in runner.run(condition, seeds, window_boxes=window_boxes).items():
        group = condition.kind if s == 1.0 else f"{condition.kind} x{s:g}"
        results.setdefault(group, {})[res.condition] = res


def write_learning_curve(results: Mapping[str, Mapping[str, ProtocolResult]], out: Path, *,
                         baseline_count: int | None) -> None:
    _write_tables(results, out, "learning_curve.md", "# Learning curve (real data only)", baseline_count)
    _plot_learning_curve(results, out / "learning_curve.png")


def _write_tables(results: Mapping[str, Mapping[str, ProtocolResult]], out: Path, name: str, title: str,
                  baseline_count: int | None) -> None:
    """One JSON per result and ``out/name``: a :func:`report_table` per group, paired against the row
    ``... / <baseline_count> seeds`` (none when absent)."""
    from synthaug.params import atomic_write_text

    out.mkdir(parents=True, exist_ok=True)
    lines = [title, ""]
    for group, conds in results.items():
        for label, res in conds.items():
            res.save(out / f"{_slug(label)}{'' if res.scale == 1.0 else f'_x{res.scale:g}'}.json")
        base = next((n for n in conds if baseline_count is not None and n.endswith(f"/ {baseline_count} seeds")), None)
        lines += [f"## {group}", "", report_table(dict(conds), baseline=base), ""]
    atomic_write_text(out / name, "\n".join(lines) + "\n")


SLUG_MAX = 230
"""The longest file-name stem a cell's JSON gets (:func:`_slug`): with a scale suffix, ``.json`` and the atomic
write's temporary ``.NAME.XXXXXXXX.tmp`` it stays within the 255 bytes of a file name."""


def _slug(name: str) -> str:
    """A condition's name as a file-name stem: runs of other characters than letters, digits and dots as ``_``; a
    stem over :data:`SLUG_MAX` characters cut and ended by 16 hex digits of the full name's SHA-256 (shorter names
    keep the stems they always had).

    >>> _slug("hog / 12 seeds + 20x synthetic (hog, share 0.25)")
    'hog_12_seeds_20x_synthetic_hog_share_0.25'
    """
    import hashlib
    import re

    stem = re.sub(r"[^A-Za-z0-9.]+", "_", name).strip("_")
    if len(stem) <= SLUG_MAX:
        return stem
    return f"{stem[:SLUG_MAX - 17]}_{hashlib.sha256(name.encode()).hexdigest()[:16]}"


def _plot_learning_curve(results: Mapping[str, Mapping[str, ProtocolResult]], path: Path) -> None:
    """Two panels: frame AP at the main IoU and patch AP (the paper's protocol), each with its 95 % CI."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for label, pts in curve_points(results).items():
        for ax, panel in zip(axes, ("frame", "patch")):
            if pts[panel]:
                xs, ys, lo, hi = map(np.asarray, zip(*sorted(pts[panel])))
                ax.errorbar(xs, ys, yerr=[lo, hi], marker="o", capsize=3, label=label,
                            linestyle="--" if label.endswith("window boxes") else "-")
    titles = {"frame": "detection (frame AP@0.5)", "patch": "patch classification (paper's protocol)"}
    for ax, panel in zip(axes, ("frame", "patch")):
        ax.set_xscale("log")
        ax.set_xlabel("real training positives")
        ax.set_ylabel("AP, mean over seeds [95 % CI]")
        ax.set_title(titles[panel], fontsize=10)
        ax.set_ylim(0, 1)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8)
        else:  # e.g. the patch panel of a run with --no-patches
            ax.text(0.5, 0.5, "not scored in this run", ha="center", va="center", transform=ax.transAxes)
    fig.suptitle("Learning curve, real data only (CI: bootstrap over test videos)", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def curve_points(results: Mapping[str, Mapping[str, ProtocolResult]]
                 ) -> dict[str, dict[str, list[tuple[float, float, float, float]]]]:
    """The learning curve's lines: ``{line label: {"frame" | "patch": [(positives, AP, CI below, CI above)]}}``.

    One line per group, video subset (``positive_videos``) and box kind: the rows scored with the windows' boxes
    (``..., window boxes``) form their own line, at the positives of the row they re-score.
    """
    lines: dict[str, dict[str, list[tuple[float, float, float, float]]]] = {}
    for group, conds in results.items():
        xs = {name: _positives(res) for name, res in conds.items() if not res.meta.get("window_boxes")}
        for name, res in conds.items():
            windows = bool(res.meta.get("window_boxes"))
            k = res.meta.get("condition", {}).get("positive_videos")
            label = group + ("" if k is None else f", positives of {k} videos") + (", window boxes" if windows else "")
            pts = lines.setdefault(label, {"frame": [], "patch": []})
            x = xs.get(name.removesuffix(", window boxes"), _positives(res)) if windows else xs[name]
            sm = summarize(res)
            for panel, iv in (("frame", sm.ap[res.protocol.main_iou]), ("patch", sm.patch_ap)):
                if iv is not None and np.isfinite(iv.estimate):
                    lo = iv.estimate - iv.low if np.isfinite(iv.low) else 0.0
                    hi = iv.high - iv.estimate if np.isfinite(iv.high) else 0.0
                    pts[panel].append((x, iv.estimate, max(lo, 0.0), max(hi, 0.0)))
    return lines


def _positives(res: ProtocolResult) -> float:
    counts = [sr.meta.get("positives") for sr in res.seeds.values() if sr.meta.get("positives")]
    if counts:
        return float(np.mean(counts))
    cond = res.meta.get("condition", {})
    return float(cond.get("seed_count") or 1e4)


# ------------------------------------------------------------------------------------------ synthetic data
def _fit_label(distance: str | None, params: str | None, mesh: str | None) -> str:
    """How a condition's name says where its added positives come from: the fit's distance (or file), and the mesh
    when one is given (conditions of two meshes are otherwise named alike).

    >>> _fit_label("hog", None, None), _fit_label("hog", None, "../meshes/jet_airliner.ply")
    ('hog', 'hog, jet_airliner')
    >>> _fit_label(None, "fits/drone_100_seed{seed}_hog.json", None)
    'drone_100_seed{seed}_hog'
    """
    return f"{distance or Path(str(params)).stem}{'' if mesh is None else f', {Path(mesh).stem}'}"


def check_dcnn_refit(detectors: Sequence[str], dcnn_refit: Sequence[bool]) -> None:
    """Raise ``ValueError`` when a d_CNN refit is asked for a detector without a network (the refit follows a CNN
    being trained: HOG and AdaBoost have none)."""
    others = sorted(set(detectors) - {"cnn"})
    if any(dcnn_refit) and others:
        raise ValueError(f"the d_CNN refit follows a CNN being trained; detectors {others} have no network "
                         f"(run them without it)")


def _realism_name(keep: float, selection: str, features: str = "hog") -> str:
    """The part of a synthetic condition's name that says what the realism critic keeps."""
    if keep == 1:
        return ""
    if selection == "item":
        return f", the least synthetic of {max(2, round(1 / keep))} candidates per patch"
    return (f", the {keep:.0%} least synthetic of {1 / keep:.3g}x drawn{' of each seed' if selection == 'seed' else ''}"
            f"{' to a weak-learner critic' if features == 'weak_learners' else ''}")


def _distractor_name(ratio: float, style: str) -> str:
    """The part of a synthetic condition's name that says which distractors its negatives hold."""
    if not ratio:
        return ""
    return f" + {ratio:g}x{' soft' if style == 'soft' else ''} rendered distractors"


def synthetic_comparison(runner: ProtocolRunner, *, detectors: Sequence[str], seed_count: int = 100,
                         synthetic_ratios: Sequence[float] = (), fit_distance: str | Mapping[str, str] | None = None,
                         params: str | None = None, perturb_copies: Sequence[int] = (), mesh: str | None = None,
                         fit_options: Mapping[str, Any] | None = None,
                         pose_sampling: Sequence[str | None] = (None,),
                         copy_paste_ratios: Sequence[float] = (), seeds: Sequence[int] | None = None,
                         synthetic_share: float | str | None = None, downscaled_copies: Sequence[int] = (),
                         faded_copies: Sequence[int] = (), object_box: Sequence[str | None] = (None,),
                         object_box_share: float = 1.0,
                         faded_contrast: tuple[float, float] | None = None,
                         shape_variation: Sequence[float | None] = (None,),
                         capture_sampling: Sequence[str] = ("seed",),
                         effects_off: Sequence[str | Sequence[str] | None] = (None,),
                         dcnn_refit: Sequence[bool] = (False,),
                         quantize: Sequence[bool | str | None] = (None,),
                         background_sampling: Sequence[str | None] = (None,),
                         realism_keep: Sequence[float | None] = (None,),
                         realism_selection: Sequence[str] = ("seed",),
                         realism_features: str | None = None,
                         synthetic_downscaled: int = 0,
                         distractor_ratio: float | None = None,
                         distractor_style: str | None = None,
                         out: str | Path | None = None) -> dict[str, dict[str, ProtocolResult]]:
    """Issue 16 under the protocol: real seeds alone vs + synthetic positives vs + perturbed real ones.

    Every condition uses the same training seeds, so each one's paired difference against
    ``<kind> / <n> seeds`` (real only; the learning curve's cell, reused from the cache) is
    over the same seed sets, negatives and initialisations. Synthetic positives come from a fit
    of *each training seed's own* seed set: ``params`` (a path that may hold ``{seed}``) or, when
    it is missing, a fit made on the fly with ``fit_distance`` (a name, or detector -> name) and
    ``fit_options`` (other :class:`~synthaug.fit.fitting.FitConfig` fields); each ratio once per
    ``pose_sampling`` (``"uniform"``: the paper's poses; ``"fitted"``: around each seed's fitted pose; either with
    ``"_at_seed"``: the object at its seed's fitted offset, :data:`~synthaug.data.poses.POSE_SAMPLING`).
    ``copy_paste_ratios``: the copy-paste baseline (the seeds' objects cut out with the same fit's
    silhouettes, pasted on other seeds' backgrounds), one condition per ratio. ``downscaled_copies``: the real seeds
    shown smaller (:func:`~synthaug.detectors.training_sets.downscaled_positives`), one condition per count;
    ``faded_copies`` likewise, the objects made fainter against their own backgrounds
    (:func:`~synthaug.detectors.training_sets.faded_positives`; ``faded_contrast``: their contrast range, a negative
    one inverting the object's contrast). ``synthetic_share``: the added positives' share of
    the positive class's weight in every synthetic, perturbed, copy-paste, downscaled and faded condition (None: each
    family's own, named in the condition when it is a share; ``"count"``: every positive weighs the same).
    ``object_box``: each synthetic ratio once per framing (None: the paper's; ``"seed"``: as ingest frames a seed).
    ``object_box_share``: the fraction of the synthetic objects each framing other than None frames, the others
    framed as the paper's (1: every one; under 1, a mixture of the two framings).
    ``shape_variation``: each synthetic ratio once per value (0: the mesh alone; > 0: shapes varied around it).
    ``capture_sampling``: each synthetic ratio once per way of drawing the capture parameters (``"seed"``: the
    paper's, one seed's fitted row; ``"uniform"``: between the fitted extremes, Fig. 10). ``effects_off``: each
    synthetic ratio once per entry, as :func:`~synthaug.detectors.video_training.resolve_effects_off` reads it: None
    (the detector family's default), ``()`` (every fitted effect), an effect's name, or several names left out
    together (Fig. 9). ``dcnn_refit``: each synthetic ratio once per value (True: the fit refitted against the CNN
    after every mining round, :class:`Condition`'s ``dcnn_refit``; CNN only). ``quantize``: each synthetic ratio
    once per value (True: the synthetic positives rounded to 8-bit levels; ``"native_scale"``: those of the seeds
    seen at about their own size; :class:`Condition`'s ``quantize``).
    ``background_sampling``: each synthetic ratio once per value (``"seed"``: the paper, each object on its own
    seed's background; ``"other"``: on another seed's; None: the family's, :class:`Condition`'s
    ``background_sampling``). ``realism_keep``: each synthetic ratio once per value (1: every drawn positive; under
    1, that fraction of them, the least synthetic to a critic in HOG features; None: the family's,
    :class:`Condition`'s ``realism_keep``). ``realism_selection``: each ``realism_keep`` under 1 once per value
    (``"seed"``, ``"set"`` or ``"item"``, :class:`Condition`'s
    ``realism_selection``). ``realism_features``: the critic's features in every condition that keeps under 1
    (``"hog"`` or ``"weak_learners"``, :class:`Condition`'s ``realism_features``). ``synthetic_downscaled``: every
    synthetic
    condition also holds that many downscaled copies of each real seed (the two together, against each alone).
    ``distractor_ratio``: every synthetic condition also adds that many rendered distractors per real seed to its
    negatives (:class:`Condition`'s ``distractor_ratio``), drawn in ``distractor_style`` (``"drawn"`` or ``"soft"``).

    The real-only cells run after the added ones, so a real-only cell that another process is training meanwhile is
    read back when it is done rather than trained twice, and the added cells do not wait on it.

    Writes (when ``out``): one JSON per condition and ``comparison.md`` (a :func:`report_table` per
    detector and scale, paired against real only, its first row).
    """
    results: dict[str, dict[str, ProtocolResult]] = {}
    refits = list(dict.fromkeys(bool(v) for v in dcnn_refit))
    check_dcnn_refit(detectors, refits)
    check_placement([ps for ps in pose_sampling if ps is not None], object_box)
    for kind in detectors:
        def own(name: str, value: Any, **context: Any) -> Any:  # the family's where a value is None
            return resolve_synthetic_option(kind, name, value, **context)

        placements = list(dict.fromkeys((own("pose_sampling", ps, object_box=ob), ob)
                                        for ps in pose_sampling for ob in object_box))
        shapes = list(dict.fromkeys(float(own("shape_variation", sv)) for sv in shape_variation))
        rounding = list(dict.fromkeys(check_quantize(own("quantize", q)) for q in quantize))
        d_ratio = float(own("distractor_ratio", distractor_ratio))
        d_style = own("distractor_style", distractor_style, distractor_ratio=distractor_ratio)
        offs = list(dict.fromkeys(resolve_effects_off(kind, off) for off in effects_off))  # one per capture set
        grounds = list(dict.fromkeys(resolve_background_sampling(kind, bs, seed_count) for bs in background_sampling))
        keeps = realism_variants([resolve_realism_keep(kind, rk, seed_count) for rk in realism_keep],
                                 realism_selection)
        features = {sel: own("realism_features", realism_features, realism_selection=sel) for _, sel in keeps}
        dist = fit_distance.get(kind) if isinstance(fit_distance, Mapping) else fit_distance
        base = f"{kind} / {seed_count} seeds"
        fit_opts = tuple(sorted((fit_options or {}).items())) if dist else ()
        resolved = resolve_synthetic_share(kind, synthetic_share)
        share = "" if resolved is None else f", share {resolved:g}"
        conds = [Condition(base, kind, seed_count=seed_count)]
        fit = _fit_label(dist, params, mesh)
        conds += [Condition(f"{base} + {r:g}x synthetic ({fit}"
                            f"{_POSE_NAMES.get(ps, f', {ps} poses')}{share}"
                            f"{'' if ob is None else f', framed as the seeds ({ob})'}"
                            f"{'' if ob is None or object_box_share == 1 else f' for {object_box_share:.0%}'}"
                            f"{'' if not sv else f', shapes varied {sv:g}'}"
                            f"{'' if cs == 'seed' else f', capture {cs}'}"
                            f"{'' if not off else ', without ' + ' and '.join(off)}"
                            f"{', d_CNN refit every round' if rf else ''}"
                            f"{quantize_name(qz)}"
                            f"{'' if bs == 'seed' else ', backgrounds of other seeds'}"
                            f"{_realism_name(rk, sel, features[sel])})"
                            f"{f' + {synthetic_downscaled}x downscaled' if synthetic_downscaled else ''}"
                            f"{_distractor_name(d_ratio, d_style)}", kind,
                            seed_count=seed_count, downscaled_copies=int(synthetic_downscaled),
                            params=params, synthetic_ratio=float(r), mesh=mesh, fit_distance=dist,
                            fit_options=fit_opts, pose_sampling=ps, synthetic_share=synthetic_share, object_box=ob,
                            object_box_share=1.0 if ob is None else float(object_box_share),
                            shape_variation=float(sv), capture_sampling=cs, effects_off=off, dcnn_refit=rf,
                            quantize=qz, background_sampling=bs, realism_keep=rk, realism_selection=sel,
                            realism_features=features[sel], distractor_ratio=d_ratio, distractor_style=d_style)
                  for r in synthetic_ratios for ps, ob in placements for sv in shapes
                  for cs in capture_sampling for off in offs for rf in refits
                  for qz in rounding for bs in grounds for rk, sel in keeps]
        conds += [Condition(f"{base} + {c}x perturbed{share}", kind, seed_count=seed_count, perturb_copies=int(c),
                            synthetic_share=synthetic_share)
                  for c in perturb_copies]
        conds += [Condition(f"{base} + {r:g}x copy-paste ({fit} silhouettes{share})", kind,
                            seed_count=seed_count, params=params, mesh=mesh, fit_distance=dist, fit_options=fit_opts,
                            copy_paste_ratio=float(r), synthetic_share=synthetic_share)
                  for r in copy_paste_ratios]
        conds += [Condition(f"{base} + {c}x downscaled{share}", kind, seed_count=seed_count,
                            synthetic_share=synthetic_share, downscaled_copies=int(c)) for c in downscaled_copies]
        fc = None if faded_contrast is None else tuple(float(v) for v in faded_contrast)
        faded = "faded" if fc is None else (f"{'inverted' if fc[0] < 0 else 'faded'} (contrast x{fc[0]:g} to x{fc[1]:g})")
        conds += [Condition(f"{base} + {c}x {faded}{share}", kind, seed_count=seed_count,
                            synthetic_share=synthetic_share, faded_copies=int(c), faded_contrast=fc)
                  for c in faded_copies]
        # real only last: a second process training the same seeds' real-only cells (same cache) is then waited for
        # at the end instead of holding every added cell behind it; its row stays first in every table
        for c in conds[1:] + conds[:1]:
            _run_into(results, runner, c, seeds)
        for group, rows in results.items():
            if base in rows:
                results[group] = {base: rows[base], **{k: v for k, v in rows.items() if k != base}}
    if out is not None:
        _write_tables(results, Path(out), "comparison.md",
                      "# Real seeds vs + synthetic vs + perturbed (paired against real only)", seed_count)
    return results


# environment variables that move a library's kernels to another instruction set: oneDNN's (the box regressor's
# convolutions; stop 91 located the AdaBoost cells' machine shift there), torch's own, MKL's and numpy's
DISPATCH_ENV = ("ONEDNN_MAX_CPU_ISA", "DNNL_MAX_CPU_ISA", "ATEN_CPU_CAPABILITY", "MKL_ENABLE_INSTRUCTIONS", "MKL_CBWR",
                "NPY_DISABLE_CPU_FEATURES")


def machine_info() -> dict[str, Any]:
    """Where a cell was computed: the CPU, the instruction set torch dispatches to and the thread count.

    A float32 CNN trained twice in one process set-up gives the same bytes, but another instruction set (AVX2 vs
    AVX-512 kernels) or thread count changes the last bits, which hard-negative mining then amplifies (issue 15:
    the CNN's cells moved by up to 0.03 AP between sessions on fresh machines). Recorded with each cell so that a
    difference can be traced; not part of the key. The stored detector keeps the machine that trained it
    (``meta["machine"]``), and each result's per-seed metadata both (``trained_on``, ``scored_on``), so the results'
    files carry them (stop 78: HOG's 12-seed cells of stops 62/68 did not reproduce on stop 73's machine with the
    same code, the same ingest bytes and a bit-identical box map, and nothing recorded where they were made).
    ``dispatch_env`` records the environment caps of ``DISPATCH_ENV`` that are set: stop 91 traced AdaBoost's
    machine shift to oneDNN's kernels in the box regressor's CNN (``ATEN_CPU_CAPABILITY`` does not choose them), and
    ``ONEDNN_MAX_CPU_ISA=AVX2`` on an AVX-512 machine reproduced an AVX2 machine's cell exactly
    (results/synthetic/adaboost_where/README.md, section 4).
    """
    import platform

    import torch

    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            cpu = next((ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name")), cpu)
    except OSError:
        pass
    return {"cpu": cpu, "torch": torch.__version__, "cpu_capability": torch.backends.cpu.get_cpu_capability(),
            "torch_threads": torch.get_num_threads(),
            "dispatch_env": {k: os.environ[k] for k in DISPATCH_ENV if k in os.environ}}


# ------------------------------------------------------------------------------------------ command line
def _common_arguments(q: argparse.ArgumentParser) -> None:
    q.add_argument("--class", dest="class_name", default="drone", help="class to detect")
    q.add_argument("--detectors", nargs="+", default=["hog", "adaboost", "cnn"], choices=["hog", "adaboost", "cnn"],
                   help="detector families")
    add_option(q, "--training-seeds", aliases=["--seeds"], type=int, nargs="*", default=None,
               help="training seeds (default: the protocol's count)")
    q.add_argument("--protocol", default="configs/protocol/halmstad_v1.json", help="protocol file")
    q.add_argument("--videos", default=DataPaths.videos_dir, help="folder of videos (shared format)")
    q.add_argument("--labels", default=DataPaths.labels_dir, help="folder of label JSON files")
    q.add_argument("--split", default=DataPaths.split_file, help="split JSON (by video)")
    q.add_argument("--work", default=DataPaths.work_dir, help="ingest shards, fits and the cell cache live here")
    q.add_argument("--no-scale-check", action="store_true", help="skip the x2 / x0.75 test frames")
    q.add_argument("--scales", type=positive_float, nargs="+", default=None,
                   help="image pyramid resize factors of mining, validation and scoring (part of a cell's key; "
                        "default: synthaug.detectors.sliding.DEFAULT_SCALES)")
    q.add_argument("--detect-scales", type=positive_float, nargs="+", default=None,
                   help="image pyramid of the scored detections only (default: --scales); part of a cell's key but "
                        "not of its trained detector's, which is read back when stored")
    q.add_argument("--no-patches", action="store_true", help="skip the paper's patch protocol")
    q.add_argument("--max-test-videos", type=int, default=None, help="first N test videos only (smoke runs)")
    q.add_argument("--mining-rounds", type=int, default=TrainOptions.mining_rounds, help="hard-negative mining rounds")
    q.add_argument("--mining-stride", type=int_at_least(1), default=TrainOptions.mining_stride,
                   help="hard-negative mining scans every k-th frame of the mining videos (part of a cell's key)")
    q.add_argument("--cnn-shift", type=int, default=TrainOptions.cnn_shift, help="CNN positives' random shift (pixels)")
    q.add_argument("--mining-select", default=TrainOptions.mining_select, choices=list(MINING_SELECT),
                   help="the mining round kept: fewest validation false positives (fp) or highest validation AP of "
                        "the same detections (ap); default: the family's (fp for hog and cnn, ap for adaboost); part "
                        "of a cell's key only when not fp")
    q.add_argument("--mining-patience", type=int_at_least(0), default=TrainOptions.mining_patience,
                   help="mining rounds without a new best still run before stopping (0: stop at the first; default: "
                        "the family's, 0 for hog and cnn, 1 for adaboost); part of a cell's key only when not 0")
    add_adaboost_options(q, keyed=True)
    q.add_argument("--mining-frame-scale", type=positive_float, nargs=2, metavar=("LOW", "HIGH"),
                   default=TrainOptions.mining_frame_scale,
                   help="resize every mined frame by a factor drawn log-uniformly in [LOW, HIGH] before the pyramid scans "
                        "it (default 1 1: native frames; part of a cell's key otherwise)")
    q.add_argument("--box-model", default=TrainOptions.box_model, choices=list(BOX_MODELS),
                   help="the box regression: a small CNN on the detection's context pixels (cnn), ridge on its HOG "
                        "cells (ridge, the model before this option: its cells keep their keys) or the mean of both "
                        "(ensemble)")
    add_budget_options(q.add_argument_group("training budgets (part of a cell's key)"))
    q.add_argument("--eval-split", default="test", choices=["test", "val"],
                   help="score on the protocol's test frames, or its validation frames (to choose a setting)")
    q.add_argument("--threads", type=int, default=1, help="torch threads")
    q.add_argument("--box-calibration", type=int_at_least(0), default=TrainOptions.box_calibration, metavar="STRIDE",
                   help="correct each trained detector's boxes by its own errors on every STRIDE-th labelled frame of "
                        "its training videos before scoring (0: off; default: the family's, 20 for every family; part "
                        "of the cell's key, not the detector's)")
    q.add_argument("--box-calibration-form", choices=list(CALIBRATION_FORMS), default=TrainOptions.box_calibration_form,
                   help="how the calibration's size term is fitted: the labelled size on the detected one (regression) "
                        "or the detected size on the labelled one, inverted (inverse: unbiased whatever the training "
                        "videos' sizes; −0.137 AP@0.5 on the drone test videos, stop 76); part of the cell's key, "
                        "not the detector's")
    q.add_argument("--read-only", action="store_true", help="never train: tables from cached cells only")
    q.add_argument("--out", required=True, help="output folder")


def build_parser() -> argparse.ArgumentParser:
    """The parser of ``python -m synthaug.evaluate.runner`` (subcommands ``learning-curve`` and ``synthetic``)."""
    p = argparse.ArgumentParser(prog="python -m synthaug.evaluate.runner",
                                description="Experiments under the evaluation protocol (cached cells).",
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    sub = p.add_subparsers(dest="what", required=True)
    lc = sub.add_parser("learning-curve", help="real data only: detectors x seed counts (+ all frames)",
                        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    _common_arguments(lc)
    lc.add_argument("--seed-counts", type=int, nargs="*", default=[12, 25, 100], help="real seed counts")
    lc.add_argument("--all-frames", action="store_true", help="also train on every --frame-step-th labelled frame")
    lc.add_argument("--frame-step", type=int, default=3, help="stride over labelled frames with --all-frames")
    lc.add_argument("--positive-videos", type=int_at_least(1), nargs="*", default=[],
                    help="also every condition with its positives from only K training videos (drawn by the training "
                         "seed; mining, box map and validation still use all), one set of conditions per K")
    sy = sub.add_parser("synthetic", help="real seeds vs + synthetic (a fit per training seed) vs + perturbed, paired",
                        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    _common_arguments(sy)
    sy.add_argument("--seed-counts", type=int, default=100, help="real seeds per training set")
    sy.add_argument("--synthetic-ratios", type=float, nargs="*", default=[], help="synthetic patches per real seed")
    sy.add_argument("--params", default=None,
                    help="fit of each training seed's seed set; may hold {seed} (e.g. fits/drone_100_seed{seed}_hog.json)")
    sy.add_argument("--fit-distance", default=None,
                    help="fit missing --params files with this distance (default: each detector's own: hog, wl_learned, cnn)")
    sy.add_argument("--mesh", default=None, help="mesh of the synthetic object (default: the fit's)")
    sy.add_argument("--perturb-copies", type=int, nargs="*", default=[], help="perturbed copies per real positive")
    sy.add_argument("--pose-sampling", nargs="+", default=["default"], choices=["default", *POSE_SAMPLING],
                    help="poses of the synthetic positives, one condition per value: uniform (the paper), fitted "
                         "(around each seed's fitted pose); *_at_seed: the same rotations with the object at its "
                         "seed's fitted offset; default: the family's (fitted_at_seed for AdaBoost, uniform for the "
                         "others)")
    sy.add_argument("--copy-paste-ratios", type=float, nargs="*", default=[],
                    help="copy-paste baseline: patches per real seed, the seeds' objects cut out with the fit's "
                         "silhouettes and pasted on other seeds' backgrounds")
    sy.add_argument("--synthetic-downscaled-copies", type=int_at_least(0), default=0, metavar="K",
                    help="every synthetic condition also trains on K downscaled copies of each real seed (the two "
                         "together; compare with --downscaled-copies K, the copies alone)")
    sy.add_argument("--distractor-ratio", type=_or_default(nonneg_float), default="default", metavar="K",
                    help="every synthetic condition also adds K rendered distractors per real seed to its negatives: "
                         "drawn as its synthetic positives are, an ellipsoid in place of the object; default: the "
                         "family's (5 for AdaBoost, 0 for the others)")
    sy.add_argument("--distractor-style", choices=["default", *DISTRACTOR_STYLES], default="default",
                    help="how the distractors look: drawn (as the object is drawn) or soft (each faint and blurred "
                         "against its background, like a cloud puff); default: the family's (soft for AdaBoost, "
                         "drawn for the others)")
    sy.add_argument("--downscaled-copies", type=int_at_least(1), nargs="*", default=[],
                    help="copies of every real seed shown as a smaller, farther object (longest side 16-24 px), cut "
                         "the way the pyramid sees it; one condition per count")
    sy.add_argument("--faded-copies", type=int_at_least(1), nargs="*", default=[],
                    help="copies of every real seed with the object fainter against its own background (contrast "
                         "x0.3-0.9); one condition per count")
    sy.add_argument("--faded-contrast", type=float, nargs=2, metavar=("LOW", "HIGH"), default=None,
                    help="the faded copies' contrast range (default 0.3 0.9); a negative range, e.g. -1 -0.5, inverts "
                         "the object's contrast against its background (part of a cell's key)")
    sy.add_argument("--synthetic-share", type=synthetic_share_arg, default=None, metavar="SHARE",
                    help="the added positives' share of the positive class's training weight, or 'count' (every "
                         "positive weighs the same); default: the family's (AdaBoost 0.25, HOG and the CNN by count)")
    sy.add_argument("--object-box", nargs="+", choices=["none", "seed", "fit"], default=["none"],
                    help="framing of the synthetic objects, one condition per value: none (the paper's mesh scale), "
                         "seed (as ingest frames a labelled seed) or fit (at the fitted renders' median box size)")
    sy.add_argument("--object-box-share", type=float_in(0.0, 1.0, low_open=True), default=1.0, metavar="SHARE",
                    help="the fraction of the synthetic objects that a framing other than none frames, the others "
                         "framed as the paper's (default 1: every one; e.g. 0.5, a mixture of the two framings)")
    sy.add_argument("--shape-variation", type=_or_default(nonneg_float), nargs="+", default=["default"],
                    help="the synthetic objects' shape variation around the mesh (axes stretched, parts such as arms "
                         "and rotors scaled within +- this fraction), one condition per value; 0: the mesh alone; "
                         "default: the family's (0.3 for AdaBoost, 0 for the others)")
    sy.add_argument("--capture-sampling", nargs="+", choices=list(CAPTURE_SAMPLERS), default=["seed"],
                    help="how the synthetic positives' capture parameters are drawn, one condition per value: seed "
                         "(the paper: one seed's fitted row), uniform (each between its fitted extremes: Fig. 10), kde")
    sy.add_argument("--effects-off", nargs="+", default=["default"], metavar="EFFECT", type=_effect_or_none,
                    help="fitted effects left out of the synthetic positives, one condition per value (the paper's "
                         "Fig. 9: boundary_blur, motion_blur, object_noise, material); a+b: both left out in one "
                         "condition; none: every fitted effect; default: the detector family's (the CNN leaves "
                         "boundary_blur and motion_blur out, the others none)")
    sy.add_argument("--dcnn-refit", nargs="+", choices=["off", "on"], default=["off"],
                    help="the d_CNN refit, one condition per value: on refits each seed's fit with the CNN just trained "
                         "as the distance after every mining round and redraws the next round's synthetic positives "
                         "from it (CNN only); off keeps one fit")
    sy.add_argument("--quantize", nargs="+", choices=["default", *QUANTIZE_ARGS], default=["default"],
                    help="the synthetic positives rounded to 8-bit levels as the real frames are (on), left with "
                         "the renderer's continuous values (off, the paper) or rounded where the pyramid sees the "
                         "seed's object at about its own size (native_scale), one condition per value; default: the "
                         "family's (native_scale for AdaBoost, off for the others)")
    sy.add_argument("--background-sampling", nargs="+", choices=["default", *BACKGROUND_SAMPLING], default=["default"],
                    help="the synthetic objects' backgrounds, one condition per value: seed (the paper: each on its "
                         "own seed's background), other (each on another seed's, its capture parameters its own) or "
                         "default (the family's: other for the CNN, seed for the others)")
    sy.add_argument("--realism-keep", nargs="+", type=_or_default(float_in(0.0, 1.0, low_open=True)),
                    default=["default"], metavar="FRACTION",
                    help="the synthetic positives drawn 1/FRACTION times over, the FRACTION that a critic in HOG "
                         "features finds least synthetic against the seed set's real patches kept (cross-fitted by "
                         "seed), one condition per value; 1: every drawn positive (the paper); default: the family's "
                         "(0.25 for HOG and AdaBoost, 1 for the CNN)")
    sy.add_argument("--realism-selection", nargs="+", choices=list(REALISM_SELECTION), default=["seed"],
                    help="how the critic keeps its fraction, one condition per value (for --realism-keep under 1): "
                         "seed (each seed keeps the same share of its own draws, the least synthetic of them; the "
                         "default), set (the least synthetic of the whole draw; a seed may keep none) or item (each "
                         "patch the least synthetic of its own 1/keep candidates, as SyntheticObjectDataset's "
                         "realism_critic draws)")
    sy.add_argument("--realism-features", choices=["default", *REALISM_FEATURES], default="default",
                    help="the critic's features (for --realism-keep under 1; selections seed and set): hog or "
                         "weak_learners (the edge-orientation energies of random rectangles that AdaBoost's stumps "
                         "threshold); default: the family's (weak_learners for AdaBoost, hog for the others)")
    return p


def _or_default(kind: Callable[[str], Any]) -> Callable[[str], Any]:
    """An option's type that also takes ``default`` (the detector family's value, resolved per family)."""
    def parse(text: str) -> Any:
        return text if text == "default" else kind(text)
    parse.__name__ = getattr(kind, "__name__", "value")
    return parse


def _given(value: Any) -> Any:
    """An option's value, None for ``default`` (the detector family's)."""
    return None if value == "default" else value


def _effect_or_none(name: str) -> str:
    """``--effects-off`` values: ``none``, ``default``, a registered effect's name (:func:`effect_name`) or several
    joined by ``+``."""
    if name in ("none", "default"):
        return name
    names = [effect_name(n) for n in name.split("+")]
    if len(set(names)) != len(names):
        raise argparse.ArgumentTypeError(f"an effect named twice in {name!r}")
    return "+".join(sorted(names))  # one spelling, one cell key


def train_options(args: argparse.Namespace) -> TrainOptions:
    """The :class:`TrainOptions` of parsed runner arguments (budgets, mining, box model; the rest at defaults)."""
    return dataclasses.replace(TrainOptions(), **budget_options(args), mining_rounds=args.mining_rounds,
                               mining_stride=args.mining_stride,
                               cnn_shift=args.cnn_shift, mining_select=args.mining_select,
                               mining_patience=args.mining_patience, box_model=args.box_model,
                               mining_frame_scale=tuple(args.mining_frame_scale), ada_energy_floor=args.ada_energy_floor,
                               ada_transfer=args.ada_transfer, ada_cascade=args.ada_cascade,
                               box_calibration=args.box_calibration, box_calibration_form=args.box_calibration_form)


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.mining_frame_scale[0] > args.mining_frame_scale[1]:
        parser.error(f"--mining-frame-scale: LOW must be <= HIGH, got {args.mining_frame_scale[0]:g} "
                     f"{args.mining_frame_scale[1]:g}")
    options = train_options(args)
    if args.what == "synthetic":
        try:
            check_dcnn_refit(args.detectors, [v == "on" for v in args.dcnn_refit])
        except ValueError as e:
            parser.error(f"--dcnn-refit on: {e}")
        try:
            check_placement([p for p in args.pose_sampling if p != "default"],
                            [None if b == "none" else b for b in args.object_box])
        except ValueError as e:
            parser.error(f"--pose-sampling: {e}")
        if args.object_box_share < 1 and all(b == "none" for b in args.object_box):
            parser.error(f"--object-box-share {args.object_box_share:g} is the share of the objects a framing frames: "
                         "give --object-box seed or fit")
        ratio = _given(args.distractor_ratio)
        if args.distractor_style not in ("default", "drawn") and not all(
                resolve_synthetic_option(kind, "distractor_ratio", ratio) for kind in args.detectors):
            parser.error(f"--distractor-style {args.distractor_style}: there are no distractors to draw: give "
                         "--distractor-ratio above 0")
    import torch

    torch.set_num_threads(args.threads)
    proto = load_protocol(args.protocol)
    paths = DataPaths(args.videos, args.labels, args.split, args.work)
    runner = ProtocolRunner(proto, args.class_name, paths, CellCache(Path(args.work) / "cells", read_only=args.read_only),
                            options=options,
                            scales=None if args.scales is None else tuple(args.scales),
                            detect_scales=None if args.detect_scales is None else tuple(args.detect_scales),
                            scale_check=not args.no_scale_check, patches=not args.no_patches,
                            max_test_videos=args.max_test_videos, eval_split=args.eval_split)
    t0 = time.perf_counter()
    if args.what == "learning-curve":
        learning_curve(runner, detectors=args.detectors, seed_counts=args.seed_counts, all_frames=args.all_frames,
                       frame_step=args.frame_step, seeds=args.training_seeds,
                       positive_videos=args.positive_videos, out=args.out)
    else:
        dist = args.fit_distance or (None if args.params else OWN_DISTANCE)
        synthetic_comparison(runner, detectors=args.detectors, seed_count=args.seed_counts,
                             synthetic_ratios=args.synthetic_ratios, fit_distance=dist, params=args.params,
                             perturb_copies=args.perturb_copies, mesh=args.mesh,
                             pose_sampling=tuple(_given(p) for p in args.pose_sampling),
                             copy_paste_ratios=args.copy_paste_ratios, seeds=args.training_seeds,
                             synthetic_share=args.synthetic_share, downscaled_copies=args.downscaled_copies,
                             synthetic_downscaled=args.synthetic_downscaled_copies,
                             distractor_ratio=_given(args.distractor_ratio),
                             distractor_style=_given(args.distractor_style),
                             faded_copies=args.faded_copies,
                             faded_contrast=None if args.faded_contrast is None else tuple(args.faded_contrast),
                             object_box=tuple(None if b == "none" else b for b in args.object_box),
                             object_box_share=args.object_box_share,
                             shape_variation=tuple(_given(v) for v in args.shape_variation),
                             capture_sampling=tuple(args.capture_sampling),
                             effects_off=tuple(None if e == "default" else () if e == "none" else tuple(e.split("+"))
                                               for e in args.effects_off),
                             dcnn_refit=tuple(v == "on" for v in args.dcnn_refit),
                             quantize=tuple(None if v == "default" else QUANTIZE_ARGS[v] for v in args.quantize),
                             background_sampling=tuple(_given(b) for b in args.background_sampling),
                             realism_keep=tuple(_given(k) for k in args.realism_keep),
                             realism_selection=tuple(args.realism_selection),
                             realism_features=_given(args.realism_features),
                             out=args.out)
    print(json.dumps({"out": args.out, "seconds": round(time.perf_counter() - t0, 1)}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
