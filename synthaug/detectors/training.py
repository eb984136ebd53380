"""Detector training: the one code path of the three families, with hard-negative mining rounds.

Everything that turns patches into a trained detector lives here, beside the
detectors (``synthaug train``, the experiments and any user script call the
same functions):

- :func:`train_detector` — one family (``"hog"``, ``"adaboost"``, ``"cnn"``) on
  positive / negative patches with the budgets of :class:`TrainOptions`; given a
  ``mining_source`` it runs the mining rounds below;
- :func:`train_with_mining` — train, then in rounds: mine
  (:func:`~synthaug.detectors.mining.mine_hard_negatives`), add, retrain, and
  measure the **validation false-positive count**
  (:func:`~synthaug.detectors.mining.validation_false_positives`);
  stop when it stops falling (or after ``mining_rounds``) and keep the detector
  with the fewest; every round's added negatives and count go into a log.
  ``TrainOptions.mining_select`` / ``mining_patience`` choose the round by the
  validation AP of the same detections instead, and allow rounds without a new
  best before stopping (defaults: the rule above).

Beside it: :mod:`synthaug.detectors.frames` (the memory-bounded frame streams mined
and validated on), :mod:`synthaug.detectors.mining` (the scan and the count),
:mod:`synthaug.detectors.training_sets` (positive and negative patch sets: real,
perturbed, synthetic, object-free crops) and :mod:`synthaug.detectors.video_training`
(a folder of labelled videos -> split -> training set -> :func:`train_with_mining`:
what ``synthaug train`` runs).

Import rule: these modules import ``synthaug.data`` and ``synthaug.detectors``
only (never ``synthaug.evaluate`` / ``synthaug.fit``); protocol settings come in
as plain values.

Example:
    >>> from synthaug.detectors.toy import toy_patches
    >>> pos, neg = toy_patches(40, 80, seed=0)
    >>> det = train_detector("hog", pos, neg, 0, options=TrainOptions(hog_components=1, hog_mining_rounds=0))
    >>> det.kind, det.window
    ('hog', 40)
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, replace
from typing import Any, Callable, ClassVar, Iterable, Literal, Sequence

import numpy as np
import torch
from torch import Tensor

from synthaug._checks import one_of
from synthaug.detectors.frames import _as_item
from synthaug.detectors.mining import mine_hard_negatives, validation_false_positives

__all__ = [
    "DETECTORS",
    "MINING_SELECT",
    "ADA_CASCADE",
    "FAMILY_DEFAULTS",
    "TrainOptions",
    "check_kind",
    "train_detector",
    "train_with_mining",
    "TrainResult",
]

DetectorKind = Literal["hog", "adaboost", "cnn"]
DETECTORS: tuple[str, ...] = ("hog", "adaboost", "cnn")
MINING_SELECT: tuple[str, ...] = ("fp", "ap")
"""What the mining rounds are chosen by (``TrainOptions.mining_select``)."""
BOX_MODELS: tuple[str, ...] = ("cnn", "ridge", "ensemble")
"""The box regression's models (``TrainOptions.box_model``)."""
ADA_CASCADE: tuple[str, ...] = ("all", "real")
"""Which training positives set AdaBoost's soft-cascade thresholds (``TrainOptions.ada_cascade``)."""
FAMILY_DEFAULTS: dict[str | None, dict[str, Any]] = {
    None: {"ada_rounds": 100, "mining_select": "fp", "mining_patience": 0, "box_calibration": 20},
    "adaboost": {"ada_rounds": 300, "mining_select": "ap", "mining_patience": 1, "box_calibration": 20},
}
"""What :class:`TrainOptions` fields left at None mean for each family (``None``: HOG, the CNN and any other
registered family).

AdaBoost's: its validation false-positive count jumps after the first mining round (184 -> 313, 222 -> 347 on the
halmstad drones) and the old rule kept round 0, unmined; with one round of patience the next rounds fall to 49 / 89.
Measured (halmstad drones, 100 seeds, 3 training seeds, ``results/learning_curve/adaboost_mining/README.md``): 300
rounds with ``"ap"`` / 1 against 100 rounds with ``"fp"`` / 0, test AP@0.5 0.175 -> 0.244 (paired +0.069 [+0.030,
+0.120]), patch AP 0.754 -> 0.802; validation 0.501 (seed 0: 0.359 -> 0.502). For HOG and the CNN the same rule
was neutral or worse on test (stop 28, ``results/synthetic/drone_v1/README.md``), so theirs stay. ``ada_rounds`` is
unused by HOG and the CNN; it is 100 there so that their cache keys stay those of before this table.
"""


# =========================================================================== options
CNN_FINETUNE_LR_SCALE: float = 0.1
"""The CNN's fine-tuning learning rate as a share of its training rate (``TrainOptions.cnn_finetune_epochs``)."""
FAMILY_ONLY_LATER_FIELDS: dict[str, str] = {"hog_kmeans_restarts": "hog", "cnn_finetune_epochs": "cnn",
                                             "ada_energy_floor": "adaboost", "ada_transfer": "adaboost",
                                             "ada_cascade": "adaboost"}
"""Later :class:`TrainOptions` fields that change only one family's training (field -> family): the other
families' cache keys leave them out whatever their value (:meth:`TrainOptions.key_fields`)."""


@dataclass(frozen=True)
class TrainOptions:
    """Training budgets of the three families and of the hard-negative mining (CPU-only, shared machine).

    Attributes:
        hog_components: root filters of the HOG mixture (the paper's DPM: 3-5).
        hog_mining_rounds: HOG's own cache-mining rounds (negative pool + HOG mining frames).
        hog_mining_frames: at most this many frames (object boxes ignored) for HOG's own mining.
        hog_kmeans_restarts: k-means runs of the components' initialisation, the lowest inertia kept
            (:func:`~synthaug.detectors.hog_dpm.kmeans`). With one run, 2 of 5 all-frames drone detectors
            (training seeds 1 and 3) started from a worse clustering and scored 0.50 instead of 0.59 on the test
            videos, and their next mining round fired on ground texture (validation AP 0.02);
            ``results/learning_curve/mining_collapse/README.md``.
        ada_rounds: boosting rounds T (None: the family's default, :data:`FAMILY_DEFAULTS`: 300 for
            AdaBoost).
        ada_candidates: random Levi-Weiss candidates (of the exhaustive grid).
        ada_energy_floor: AdaBoost's energy floor per pixel (:func:`~synthaug.detectors.weak_learners.edge_orientation_energy`)
            in units of its training negatives' gradient level (:func:`~synthaug.detectors.adaboost.gradient_level`,
            measured at each training): a rectangle whose gradients are at that level no longer shows its faint
            structure at full strength. 0: the paper's energy (the training before this option). Measured
            (halmstad drones, protocol v2 test split, 100 seeds, 3 training seeds, paired against 0 on the same
            seeds, ``results/learning_curve/adaboost_scale/README.md``; 1 was set before the runs): AP@0.5 0.385 ->
            0.501, +0.116 [+0.048, +0.171], 11/14 videos; on the x2 scale check 0.143 -> 0.344, +0.201 [+0.104,
            +0.307] (x2 keeps 0.69 of x1 instead of 0.37); x0.75 +0.054 [+0.013, +0.098]. Without it the stumps
            score faint, smooth structure (sky and cloud texture, most of all on upsampled frames) like a drone's
            edges: the ranked false positives at x2 were mostly windows of the finest levels.
        ada_transfer: train AdaBoost as Dynamic-TrAdaBoost with the added positives (synthetic, perturbed, ...) as
            the source distribution (``source_positives`` of :func:`~synthaug.detectors.adaboost.train_adaboost`):
            α is measured on the real positives and the negatives only, and an added positive the stumps keep
            getting wrong loses weight instead of gaining it. Used only when the caller says which positives are
            real (``real_positives`` of :func:`train_with_mining`) and some are not. False: plain AdaBoost.
        ada_cascade: which positives set AdaBoost's soft-cascade thresholds (``cascade_positives`` of
            :func:`~synthaug.detectors.adaboost.train_adaboost`): ``"all"`` every training positive (the training
            before this option), ``"real"`` the real ones only, when the caller says which (``real_positives`` of
            :func:`train_with_mining`) and some were added. The cascade decides which windows are scored to the
            end, at detection and in the mining. ``"real"`` is the default since stop 60 (halmstad drones,
            protocol v2 test split, 12 real seeds + 20x synthetic, 3 training seeds, trained with each cascade and
            paired, ``results/synthetic/adaboost_12/README.md``): with the transfer rule AP@0.5 0.321 -> 0.357,
            +0.036 [+0.005, +0.067], 10/14 videos; the stored detectors recalibrated ran 2.5x faster side by
            side (stop 59); at 100 seeds their AP moved by 0.001 or less
            (``results/synthetic/adaboost_baselines/``). A few added positives that score low otherwise loosen
            every stage (thresholds 2-60x looser at 12 seeds).
        cnn_epochs: passes over the training patches (each mirrored or not;
            ``PatchDetectorModule`` under ``lightning.Trainer``).
        cnn_batch_size: mini-batch size.
        cnn_max_steps: the number of epochs is reduced so that training takes
            at most about this many optimiser steps (large synthetic sets).
        cnn_finetune_epochs: after the CNN's training on every positive, this many further passes over the
            *real* positives and the same negatives at a tenth of the learning rate (the added positives --
            synthetic, perturbed, ... -- left out; :data:`CNN_FINETUNE_LR_SCALE`): pre-train on the mixed set,
            fine-tune on real data, the usual schedule for a small network and synthetic images. Used only when
            the caller says which positives are real (``real_positives`` of :func:`train_with_mining`; ``synthaug
            train`` and the runner do) and some are not; 0 = off (the training before this option). Measured
            (halmstad drones, 100 seeds + 20x synthetic from each seed set's d_HOG fit, ensemble box map; paired
            against the same training without it, ``results/synthetic/cnn_finetune/README.md``): 4 epochs,
            validation split (3 seeds) +0.040 [+0.013, +0.067], 15/20 videos; test split (5 seeds) +0.058
            [+0.033, +0.081], 9/14 videos, every seed up (0.534 -> 0.592). Costs a second, shorter training per
            mining round: 11 -> 12-14 s at round 0, 16-17 -> 24 s at round 1 (runs beside other jobs).
        cnn_shift: positives moved by random whole-pixel offsets up to this many pixels
            each step (the CNN scans every 8 pixels; ``PatchDetectorModule(shift=)``).
        mining_rounds: rounds of :func:`train_with_mining` (mine, add, retrain) at most;
            used only when a mining source is given; 0 = no mining.
        mining_stride: every k-th frame of every mining video is scanned. Measured at 30 on the 56 halmstad
            drone training videos + 32 bird videos (894 frames, 640x512, 1 torch thread, shared 2-core box):
            one round (scan + retrain + validation on 219 frames) HOG 71 s (scan 53 s), CNN 89 s (58 s),
            AdaBoost 238 s (171 s); 4 470 negatives added per round; peak memory 1.4-2.1 GB.
        mining_per_frame: false positives kept per frame (the best after NMS).
        mining_max_per_round: at most this many new negatives per round (the highest-scoring).
        mining_margin: labelled boxes grow by ``max(4 px, margin x longest side)`` on each side
            before masking.
        mining_nms_iou: NMS among a frame's windows before the per-frame top-k
            (one clutter object gives one negative per round, not ten shifted copies).
        scales: pyramid of mining and validation (None: ``sliding.DEFAULT_SCALES``).
        mining_frame_scale: ``(low, high)``: every mining frame is resized by a factor drawn log-uniformly in
            this range (per frame, from the training seed, the video and the frame index:
            :class:`~synthaug.detectors.frames.RescaledFrames`) before the pyramid scans it, so the mined
            negatives include clutter at magnifications the native frames never reach (an upsampled frame is
            smoother than any native level). ``(1, 1)``, the default: native frames (the mining before this
            option). Scale-jittered mining did not fix AdaBoost's x2 check and cost it x1 AP
            (``results/learning_curve/adaboost_scale/README.md``).
        val_stride: every k-th frame of the validation videos is scored.
        val_top_k: detections kept per validation frame.
        val_iou: matching IoU of the validation count.
        val_target_recall: the count is the false positives above the score reaching this recall.
        box_regression: fit a :class:`~synthaug.detectors.boxes.BoxRegressor` (detections ->
            the annotators' boxes) on the training videos' labelled frames, before the mining
            rounds (it does not depend on the detector; their validation counts use it).
            Measured on the halmstad drone test split (HOG, 100 seeds, seed 0): frame AP@0.5
            0.206 -> 0.333 on the same detections.
        box_stride: every k-th labelled frame of the training videos feeds the box regression.
        mining_select: what the validation frames choose the round by: ``"fp"`` (the fewest validation
            false positives at recall ``val_target_recall``; the earliest on ties) or ``"ap"`` (the highest
            validation AP of the same pooled detections, ``validation_false_positives(...)["ap"]``; the
            earliest on ties). A round is a *new best* when it is strictly better by this criterion.
            ``"ap"`` uses every kept detection instead of the one operating point (the count of the CNN
            moved 28 -> 52 between rounds of one training), and it is the quantity the protocol scores.
        mining_patience: rounds in a row without a new best that are still run before stopping; 0 stops
            at the first round that is not a new best (the rule before these options). Mining always
            continues from the latest round's detector and negatives; the chosen round is the best one,
            wherever the rounds stopped. Each extra round costs one scan + one training + one
            validation (about 90 s for the CNN on the halmstad drone videos).
            ``mining_select`` and ``mining_patience`` at None take the family's default
            (:data:`FAMILY_DEFAULTS`: ``"fp"`` / 0 for HOG and the CNN, ``"ap"`` / 1 for AdaBoost).

        box_model: the box regression's model: ``"ensemble"`` (the default,
            :class:`~synthaug.detectors.box_cnn.EnsembleBoxRegressor`: the mean of the two maps' deltas),
            ``"cnn"`` (:class:`~synthaug.detectors.box_cnn.CNNBoxRegressor`, a small CNN on the box's context
            pixels) or ``"ridge"`` (:class:`~synthaug.detectors.boxes.BoxRegressor`, ridge regression on HOG
            cells; the model before this option). Validation split of the halmstad drones (100 seeds, training
            seed 0, the same raw detections), frame AP@0.5 at x1 / x2 (frames resized, the scale check): HOG
            ridge 0.671 / 0.335, cnn 0.667 / 0.567, ensemble 0.686 / 0.456; CNN detector 0.638 / 0.490,
            0.666 / 0.616, 0.676 / 0.597: the ensemble is the best at x1 for both. On the test split (3
            training seeds, full pipeline) the CNN detector's x1: ridge 0.409, cnn 0.357, ensemble 0.392; x2
            0.312, 0.359, 0.353 (``results/learning_curve/drone_box_cnn/README.md``). The CNN map costs
            ~2 min to fit (ridge ~20 s).

        box_calibration: after training, correct the detector's boxes by its own errors on every k-th labelled
            frame of its training videos (:func:`~synthaug.detectors.box_calibration.calibrate_boxes`: a linear
            function of the box's log size, fitted by least squares on its detections matched at IoU >= 0.3);
            0: off. Too few matched detections to fit (fewer than 20) keeps the box map. Measured on the halmstad
            drones (HOG, 100 real seeds, 3 training seeds, paired with the same stored detectors; stop 73,
            ``results/synthetic/box_calibration/README.md``): every 20th frame (≈ 850 frames, 2-4 min) takes
            AP@0.5 0.698 -> 0.804 on the validation videos (+0.105 [+0.047, +0.165]) and 0.597 -> 0.704 on the test
            videos (+0.107 [+0.048, +0.167]): the mapped boxes were ≈ 7 % too small (median log-size delta
            +0.06 to +0.09). AdaBoost (stop 97, ``results/synthetic/adaboost_rounds/README.md``; its stored
            detectors, 100 real seeds, read back): test AP@0.5 0.535 -> 0.629 (+0.094 [+0.033, +0.159], 9 training
            seeds), validation 0.669 -> 0.753 (+0.085 [+0.027, +0.142], 3 seeds). None: the family's default
            (:data:`FAMILY_DEFAULTS`: 20 for every family).
        box_calibration_form: how that correction's size term is fitted
            (:data:`~synthaug.detectors.box_calibration.CALIBRATION_FORMS`): ``"regression"`` (least squares of the
            labelled size on the detected one) or ``"inverse"`` (the detected size on the labelled one, inverted;
            unbiased whatever the training videos' mix of sizes;
            :func:`~synthaug.detectors.box_calibration.fit_calibration`).
            Inverse − regression on the halmstad drone test videos (the CNN, 100 seeds, stop 76): −0.137 AP@0.5.

    The two ``mining_*`` selection fields, ``box_model`` and ``hog_kmeans_restarts`` were added after cells had
    been cached; at ``"fp"``, 0, ``"ridge"`` and 1 the training is the one before them, and
    :data:`LATER_FIELDS` lets a cache key leave them out (:meth:`key_fields`).
    """

    hog_components: int = 3
    hog_mining_rounds: int = 2
    hog_mining_frames: int = 40
    hog_kmeans_restarts: int = 10
    ada_rounds: int | None = None
    ada_candidates: int = 2000
    ada_energy_floor: float = 1.0
    ada_transfer: bool = False
    ada_cascade: str = "real"
    cnn_epochs: int = 12
    cnn_batch_size: int = 128
    cnn_max_steps: int = 1200
    cnn_shift: int = 0
    cnn_finetune_epochs: int = 4
    mining_rounds: int = 3
    mining_stride: int = 30
    mining_per_frame: int = 5
    mining_max_per_round: int = 10000
    mining_margin: float = 0.25
    mining_nms_iou: float = 0.3
    scales: tuple[float, ...] | None = None
    val_stride: int = 30
    val_top_k: int = 10
    val_iou: float = 0.5
    val_target_recall: float = 0.5
    box_regression: bool = True
    box_stride: int = 15
    mining_select: str | None = None
    mining_patience: int | None = None
    box_model: str = "ensemble"
    mining_frame_scale: tuple[float, float] = (1.0, 1.0)
    box_calibration: int | None = None
    box_calibration_form: str = "regression"

    LATER_FIELDS: ClassVar[tuple[tuple[str, Any], ...]] = (("mining_select", "fp"), ("mining_patience", 0),
                                                           ("box_model", "ridge"), ("hog_kmeans_restarts", 1),
                                                           ("cnn_finetune_epochs", 0), ("mining_frame_scale", (1.0, 1.0)),
                                                           ("ada_energy_floor", 0.0), ("ada_transfer", False),
                                                           ("ada_cascade", "all"), ("box_calibration", 0),
                                                           ("box_calibration_form", "regression"))
    """Fields added after cells were cached, with the value at which the training is the one before them
    (``box_model``'s default, ``"ensemble"``, is not that value: cells of the default options have new keys;
    nor are ``hog_kmeans_restarts``' default, 10, and ``cnn_finetune_epochs``' default, 4, which only HOG's and the
    CNN's keys carry: :data:`FAMILY_ONLY_LATER_FIELDS`; the runner also leaves the fine-tuning out of cells without
    added positives, where it does nothing)."""

    def for_family(self, kind: str | None) -> "TrainOptions":
        """These options with every field left at None set to ``kind``'s default (:data:`FAMILY_DEFAULTS`).

        Example:
            >>> o = TrainOptions()
            >>> (o.for_family("adaboost").ada_rounds, o.for_family("adaboost").mining_patience)
            (300, 1)
            >>> (o.for_family("hog").mining_select, TrainOptions(mining_patience=2).for_family("adaboost").mining_patience)
            ('fp', 2)
        """
        fam = FAMILY_DEFAULTS.get(kind, FAMILY_DEFAULTS[None])
        return replace(self, **{k: v for k, v in fam.items() if getattr(self, k) is None})

    def key_fields(self, kind: str | None = None) -> dict[str, Any]:
        """``dataclasses.asdict`` of :meth:`for_family` ``(kind)`` without the :data:`LATER_FIELDS` at their former values.

        A cache key built from it is unchanged for the options that existed before those fields
        (older cells stay valid) and differs whenever one of them is set. Keys of the same training are
        equal whether a family default was left at None or written out.

        Example:
            >>> TrainOptions().key_fields("hog") == {k: v for k, v in asdict(TrainOptions(ada_rounds=100,
            ...                                                                    box_calibration=20)).items()
            ...                                      if k not in ("mining_select", "mining_patience", "cnn_finetune_epochs",
            ...                                                   "mining_frame_scale", "ada_energy_floor",
            ...                                                   "ada_transfer", "ada_cascade",
            ...                                                   "box_calibration_form")}
            True
            >>> TrainOptions().key_fields("cnn")["cnn_finetune_epochs"]  # the CNN's fine-tuning is in its keys only
            4
            >>> TrainOptions(mining_patience=1).key_fields("hog")["mining_patience"]
            1
            >>> TrainOptions().key_fields("adaboost") == TrainOptions(ada_rounds=300, mining_select="ap",
            ...                                                          mining_patience=1).key_fields("adaboost")
            True
            >>> "box_model" in TrainOptions(box_model="ridge").key_fields("hog")  # the cells before box_model
            False
            >>> "hog_kmeans_restarts" in TrainOptions().key_fields("cnn")  # no k-means outside HOG: the CNN's keys stay
            False
        """
        d = asdict(self.for_family(kind))
        for name, default in self.LATER_FIELDS:
            family = FAMILY_ONLY_LATER_FIELDS.get(name)
            if d[name] == default or (family is not None and kind is not None and kind != family):
                d.pop(name)
        return d

    def __post_init__(self) -> None:
        for name in ("mining_stride", "mining_per_frame", "mining_max_per_round", "val_stride", "val_top_k", "box_stride"):
            if int(getattr(self, name)) < 1:
                raise ValueError(f"{name} must be >= 1, got {getattr(self, name)}")
        if self.mining_rounds < 0:
            raise ValueError(f"mining_rounds must be >= 0, got {self.mining_rounds}")
        if self.mining_margin < 0:
            raise ValueError(f"mining_margin must be >= 0, got {self.mining_margin}")
        if isinstance(self.ada_energy_floor, bool) or not (float(self.ada_energy_floor) >= 0
                                                           and math.isfinite(float(self.ada_energy_floor))):
            raise ValueError(f"ada_energy_floor must be a finite number >= 0, got {self.ada_energy_floor!r}")
        if not isinstance(self.ada_transfer, bool):
            raise ValueError(f"ada_transfer must be a bool, got {self.ada_transfer!r}")
        one_of(self.ada_cascade, ADA_CASCADE, "ada_cascade")
        if not 0 <= int(self.cnn_shift) < 20:
            raise ValueError(f"cnn_shift must be in [0, 20) pixels, got {self.cnn_shift}")
        if not 0 < self.val_target_recall <= 1 or not 0 < self.val_iou <= 1:
            raise ValueError(f"val_target_recall and val_iou must be in (0, 1], got {self.val_target_recall}, {self.val_iou}")
        if self.mining_select is not None:
            one_of(self.mining_select, MINING_SELECT, "mining_select", alternatives=" or None")
        # (name, lowest value, None allowed: the family's default)
        for name, low, optional in (("mining_patience", 0, True), ("ada_rounds", 1, True), ("hog_kmeans_restarts", 1, False),
                                     ("cnn_finetune_epochs", 0, False), ("box_calibration", 0, True)):
            v = getattr(self, name)
            if v is None and optional:
                continue
            if v is None or isinstance(v, bool) or int(v) != v or v < low:
                raise ValueError(f"{name} must be an integer >= {low}{' or None' if optional else ''}, got {v!r}")
        one_of(self.box_model, BOX_MODELS, "box_model")
        from synthaug.detectors.box_calibration import check_form

        check_form(self.box_calibration_form, "box_calibration_form")
        if self.scales is not None:
            object.__setattr__(self, "scales", tuple(float(s) for s in self.scales))
        from synthaug.detectors.frames import check_scale_range

        object.__setattr__(self, "mining_frame_scale", check_scale_range(self.mining_frame_scale))

    def pyramid(self) -> tuple[float, ...]:
        from synthaug.detectors.sliding import DEFAULT_SCALES

        return tuple(DEFAULT_SCALES if self.scales is None else self.scales)


def check_kind(kind: str) -> None:
    """Raise ``ValueError`` naming the known families unless ``kind`` is one of :data:`DETECTORS`."""
    if kind not in DETECTORS:
        raise ValueError(f"unknown detector kind {kind!r}; choose from {list(DETECTORS)}")


# =========================================================================== one fit
def _fit_once(
    kind: str,
    positives: Tensor,
    negatives: Tensor,
    seed: int,
    *,
    box_in_window: Sequence[float] | None,
    mining_frames: Sequence[Tensor],
    mining_boxes: Sequence[Tensor | None] | None,
    options: TrainOptions,
    positive_weights: Tensor | None = None,
    real_positives: int | None = None,
) -> Any:
    from synthaug.detectors.base import check_patches

    check_kind(kind)
    options = options.for_family(kind)
    if not isinstance(positives, Tensor) or positives.dim() != 4 or positives.shape[0] == 0:
        raise ValueError(f"positives must be a non-empty (P, 1, S, S) float tensor, got {getattr(positives, 'shape', positives)}")
    n_real = _real_count(real_positives, len(positives))
    if not isinstance(negatives, Tensor) or negatives.dim() != 4 or negatives.shape[0] == 0:
        raise ValueError(f"negatives must be a non-empty (N, 1, S, S) float tensor, got {getattr(negatives, 'shape', negatives)}")
    window = int(positives.shape[-1])
    positives = check_patches(positives, window)
    negatives = check_patches(negatives, window)
    if kind == "hog":
        from synthaug.detectors.hog_dpm import HOGDetector

        frames = list(mining_frames)[: options.hog_mining_frames]
        boxes = None if mining_boxes is None else list(mining_boxes)[: len(frames)]
        det = HOGDetector.fit(
            positives,
            negatives,
            background_images=frames,
            ignore_boxes=boxes,
            components=options.hog_components,
            mining_rounds=options.hog_mining_rounds,
            kmeans_restarts=options.hog_kmeans_restarts,
            window=window,
            generator=torch.Generator().manual_seed(seed),
            positive_weights=positive_weights,
        )
    elif kind == "adaboost":
        from synthaug.detectors.adaboost import train_adaboost

        floor = 0.0
        if options.ada_energy_floor:
            from synthaug.detectors.adaboost import gradient_level

            floor = options.ada_energy_floor * gradient_level(negatives)
        added = 0 < n_real < len(positives)
        source = len(positives) - n_real if options.ada_transfer and added else 0
        cascade = n_real if options.ada_cascade == "real" and added else None
        det = train_adaboost(positives, negatives, n_rounds=options.ada_rounds, candidates=options.ada_candidates, seed=seed,
                             positive_weights=positive_weights, energy_floor=floor, source_positives=source,
                             cascade_positives=cascade)
    else:
        # the one CNN training loop: PatchDetectorModule + PatchDataModule.from_tensors under a CPU lightning.Trainer
        from synthaug.detectors.lightning_module import fit_patch_detector

        def capped(epochs: int, n: int) -> int:
            return max(1, min(epochs, options.cnn_max_steps // max(1, math.ceil(n / options.cnn_batch_size))))

        module = fit_patch_detector(positives, negatives, epochs=capped(options.cnn_epochs, len(positives) + len(negatives)),
                                    batch_size=options.cnn_batch_size, seed=seed, shift=options.cnn_shift,
                                    positive_weights=positive_weights)
        if options.cnn_finetune_epochs and 0 < n_real < len(positives):  # fine-tune on the real positives only
            real = positives[:n_real]
            module = fit_patch_detector(real, negatives, epochs=capped(options.cnn_finetune_epochs, n_real + len(negatives)),
                                        batch_size=options.cnn_batch_size, seed=seed, shift=options.cnn_shift,
                                        lr=float(module.hparams["lr"]) * CNN_FINETUNE_LR_SCALE, module=module)
        det = module.to_detector()
    det.box_in_window = None if box_in_window is None else tuple(float(v) for v in box_in_window)
    return det


def _real_count(real_positives: int | None, n: int) -> int:
    """How many of ``n`` positives are real (the first ones): ``real_positives``, all of them when None."""
    if real_positives is None:
        return n
    if isinstance(real_positives, bool) or int(real_positives) != real_positives or not 0 <= real_positives <= n:
        raise ValueError(f"real_positives must be an integer in [0, {n}] (the number of positives), got {real_positives!r}")
    return int(real_positives)


def train_detector(
    kind: str,
    positives: Tensor,
    negatives: Tensor,
    seed: int = 0,
    *,
    box_in_window: Sequence[float] | None = None,
    mining_frames: Sequence[Tensor] = (),
    mining_boxes: Sequence[Tensor | None] | None = None,
    options: TrainOptions = TrainOptions(),
    mining_source: Iterable[Any] | None = None,
    val_frames: Iterable[Any] | None = None,
    log: Callable[[str], None] | None = None,
    real_positives: int | None = None,
) -> Any:
    """Train one detector family on positive and negative patches (with mining rounds when given a source).

    Args:
        kind: ``"hog"`` (HOG root-filter mixture with its own hard-negative cache mining),
            ``"adaboost"`` (Levi-Weiss stumps) or ``"cnn"`` (PatchCNN).
        positives: object patches, float in [0, 1].
        negatives: background patches, float in [0, 1].
        seed: seeds every random choice of the training.
        box_in_window: object box inside a window (``[x, y, w, h]``, window
            pixels) reported by sliding-window detection; None = whole window.
        mining_frames: HOG only: full grayscale frames ``(H, W)`` in [0, 1]
            scanned by HOG's own mining (at most ``options.hog_mining_frames``).
        mining_boxes: HOG only: per mining frame, ``(G, 4)`` object boxes never mined.
        options: training and mining budgets.
        mining_source: frames to mine hard negatives from, for every family
            (:class:`~synthaug.detectors.frames.VideoFrames` or an iterable of :class:`~synthaug.detectors.frames.MiningFrame`); None: no
            mining rounds (a single fit, as before).
        val_frames: validation frames for the stopping rule (see :func:`train_with_mining`).
        log: progress printer.
        real_positives: the first this many ``positives`` are real, the rest added (synthetic, perturbed, ...);
            None: all real. Read by the CNN's fine-tuning (``options.cnn_finetune_epochs``) only.

    Returns:
        A :class:`~synthaug.detectors.base.PatchDetector` (the round chosen by ``options.mining_select``:
        by default the lowest validation FP count; :func:`train_with_mining` also returns the per-round log).

    Shape:
        - positives: (P, 1, 40, 40), negatives: (N, 1, 40, 40)
    """
    if mining_source is None or options.mining_rounds == 0:
        return _fit_once(kind, positives, negatives, seed, box_in_window=box_in_window, mining_frames=mining_frames,
                         mining_boxes=mining_boxes, options=options, real_positives=real_positives)
    return train_with_mining(kind, positives, negatives, seed, box_in_window=box_in_window, mining_frames=mining_frames,
                             mining_boxes=mining_boxes, options=options, mining_source=mining_source,
                             val_frames=val_frames, log=log, real_positives=real_positives).detector


# =========================================================================== mining rounds
@dataclass
class TrainResult:
    """A detector trained with mining rounds, and what happened.

    Attributes:
        detector: the chosen detector (fewest validation false positives, or the highest validation AP
            with ``TrainOptions(mining_select="ap")``).
        log: ``{"rounds": [{"round", "added", "negatives", "val", "mine_s", "train_s", "val_s",
            "frames_scanned"}], "chosen_round", "stop_reason", "mining": {...}}``.
        negatives: the negatives the chosen detector was trained on.
    """

    detector: Any
    log: dict[str, Any]
    negatives: Tensor


def train_with_mining(
    kind: str,
    positives: Tensor,
    negatives: Tensor,
    seed: int = 0,
    *,
    box_in_window: Sequence[float] | None = None,
    mining_frames: Sequence[Tensor] = (),
    mining_boxes: Sequence[Tensor | None] | None = None,
    options: TrainOptions = TrainOptions(),
    mining_source: Iterable[Any] | None = None,
    val_frames: Iterable[Any] | None = None,
    log: Callable[[str], None] | None = None,
    fit: Callable[[Tensor, Tensor], Any] | None = None,
    box_regressor: Any = None,
    positive_weights: Tensor | None = None,
    real_positives: int | None = None,
    refresh_positives: Callable[[Any, int], Tensor] | None = None,
) -> TrainResult:
    """Train, then mine hard negatives and retrain in rounds until the validation false positives stop falling.

    Round 0 trains on ``negatives``; round ``r >= 1`` mines the current detector's
    false positives on ``mining_source`` (:func:`~synthaug.detectors.mining.mine_hard_negatives`, windows never
    mined before), adds them, retrains from scratch with the same seed and counts the
    validation false positives (:func:`~synthaug.detectors.mining.validation_false_positives` on ``val_frames``,
    decoded once and kept as uint8). It stops when that count does not fall below the
    best so far, when nothing new is mined, or after ``options.mining_rounds``; the
    detector with the fewest is returned (the earliest on ties). Without validation
    frames every round runs and the last detector is returned.

    ``options.mining_select = "ap"`` ranks the rounds by the validation AP of the same
    detections instead (highest wins, the earliest on ties), and ``options.mining_patience = p``
    runs up to ``p`` further rounds without a new best before stopping (mining goes on from the
    latest detector); the best round is returned either way. At ``"fp"`` and 0 (the defaults)
    this is exactly the rule above.

    Args:
        kind, positives, negatives, seed, box_in_window, mining_frames, mining_boxes, options:
            as :func:`train_detector`.
        mining_source: re-iterable frames (:class:`~synthaug.detectors.frames.VideoFrames`), streamed once per round.
        val_frames: validation frames (:class:`~synthaug.detectors.frames.MiningFrame` items, e.g. ``VideoFrames(...,
            null_frames=True)``); None: no stopping rule.
        log: progress printer.
        fit: ``(positives, negatives) -> detector`` replacing the family's training
            (tests, other families); ``box_in_window`` is still set on its result.
        box_regressor: set on every round's detector (a
            :class:`~synthaug.detectors.boxes.BoxRegressor`; it does not depend on the
            detector), so the validation count matches at the boxes detection reports.
        positive_weights: ``(P,)`` each positive's weight in the positive class, the same in every
            round (mined negatives weigh 1): HOG's per-sample SVM cost
            (:meth:`~synthaug.detectors.hog_dpm.HOGDetector.fit`) or the CNN's per-sample BCE weight
            (:func:`~synthaug.detectors.lightning_module.fit_patch_detector`) or AdaBoost's starting weights
            (:func:`~synthaug.detectors.adaboost.train_adaboost`). None: all equal.
        real_positives: the first this many ``positives`` are real (see :func:`train_detector`); every round's
            CNN fine-tunes on them when ``options.cnn_finetune_epochs`` > 0.
        refresh_positives: ``(detector, r) -> positives`` called with round ``r``'s detector once round ``r + 1``'s
            negatives are mined; round ``r + 1`` and later train on what it returns, which must have the shape of
            ``positives`` (the real ones first, unchanged). The d_CNN refit: the synthetic positives redrawn from
            capture parameters refitted against the network just trained (``AddedPositives.refit`` of
            :func:`~synthaug.detectors.video_training.train_from_videos`). None: the same positives every round.

    Returns:
        A :class:`TrainResult`.
    """
    say = log or (lambda m: None)
    options = options.for_family(kind)
    _real_count(real_positives, int(positives.shape[0]))  # a bad count fails before the first training

    def train(neg: Tensor) -> Any:
        if fit is None:
            det = _fit_once(kind, positives, neg, seed, box_in_window=box_in_window, mining_frames=mining_frames,
                            mining_boxes=mining_boxes, options=options, positive_weights=positive_weights,
                            real_positives=real_positives)
        else:
            det = fit(positives, neg)
            det.box_in_window = None if box_in_window is None else tuple(float(v) for v in box_in_window)
        if box_regressor is not None:  # validation counts false positives among the boxes detection reports
            det.box_regressor = box_regressor
        return det

    if fit is None:
        check_kind(kind)
    scales = options.pyramid()
    val = _decoded_validation(val_frames, say)

    def count(det: Any) -> tuple[dict[str, Any] | None, float]:
        if val is None:
            return None, 0.0
        t = time.perf_counter()
        r = validation_false_positives(det, val, scales=scales, top_k=options.val_top_k, iou=options.val_iou,
                                       target_recall=options.val_target_recall)
        return r, time.perf_counter() - t

    t0 = time.perf_counter()
    det = train(negatives)
    t_train = time.perf_counter() - t0
    v, t_val = count(det)
    rounds = [{"round": 0, "added": 0, "negatives": int(negatives.shape[0]), "frames_scanned": 0, "val": v,
               "mine_s": 0.0, "train_s": round(t_train, 1), "val_s": round(t_val, 1)}]
    say(f"round 0: {negatives.shape[0]} negatives, train {t_train:.0f}s" + _val_text(v))
    best = (det, v, 0, negatives)
    current_neg = negatives
    seen: set[tuple[str, int, int, int, int]] = set()
    stop = "mining_rounds reached" if options.mining_rounds else "no mining (mining_rounds = 0)"
    if mining_source is None:
        stop = "no mining source"
    if mining_source is not None and options.mining_frame_scale != (1.0, 1.0):
        from synthaug.detectors.frames import RescaledFrames

        mining_source = RescaledFrames(mining_source, options.mining_frame_scale, seed=seed)
    for r in range(1, options.mining_rounds + 1 if mining_source is not None else 1):
        mined = mine_hard_negatives(det, mining_source, scales=scales, per_frame=options.mining_per_frame,
                                    max_negatives=options.mining_max_per_round, margin=options.mining_margin,
                                    nms_iou=options.mining_nms_iou, exclude=seen)
        if len(mined) == 0:
            rounds.append({"round": r, "added": 0, "negatives": int(current_neg.shape[0]), "frames_scanned": mined.frames_scanned,
                           "val": None, "mine_s": round(mined.seconds, 1), "train_s": 0.0, "val_s": 0.0})
            stop = "no new negative mined"
            say(f"round {r}: nothing new mined on {mined.frames_scanned} frames ({mined.seconds:.0f}s); stop")
            break
        current_neg = torch.cat([current_neg, mined.patches.to(current_neg.dtype)])
        refresh: dict[str, Any] = {}
        if refresh_positives is not None:
            t0 = time.perf_counter()
            positives = _refreshed(refresh_positives(det, r - 1), positives, n_real=_real_count(real_positives,
                                                                                                   len(positives)))
            refresh = {"refresh_s": round(time.perf_counter() - t0, 1)}
            say(f"round {r}: positives redrawn after round {r - 1} ({refresh['refresh_s']:.0f}s)")
        t0 = time.perf_counter()
        det = train(current_neg)
        t_train = time.perf_counter() - t0
        v, t_val = count(det)
        rounds.append({"round": r, "added": len(mined), "negatives": int(current_neg.shape[0]),
                       "frames_scanned": mined.frames_scanned, "val": v, "mine_s": round(mined.seconds, 1),
                       "train_s": round(t_train, 1), "val_s": round(t_val, 1),
                       "videos": len({s for s, _ in mined.sources}), **refresh})
        say(f"round {r}: +{len(mined)} negatives from {mined.frames_scanned} frames (scan {mined.seconds:.0f}s), "
            f"{current_neg.shape[0]} in all, train {t_train:.0f}s" + _val_text(v))
        if v is None:
            best = (det, v, r, current_neg)
            continue
        if best[1] is None or _better(v, best[1], options.mining_select):
            best = (det, v, r, current_neg)
            continue
        if r - best[2] > options.mining_patience:
            stop = _stop_reason(options, best[1], v, r - best[2])
            say(f"stop: {stop}; keeping round {best[2]}")
            break
        say(f"no new best ({_criterion(options.mining_select, v)} vs {_criterion(options.mining_select, best[1])} at "
            f"round {best[2]}); {options.mining_patience - (r - best[2]) + 1} more round(s) of patience")
    if stop == "mining_rounds reached" and best[2] != rounds[-1]["round"]:
        say(f"keeping round {best[2]} ({_criterion(options.mining_select, best[1])})")
    out_log = {"rounds": rounds, "chosen_round": best[2], "stop_reason": stop,
               **_settings_log(options, scales, mining_source, val)}
    return TrainResult(best[0], out_log, best[3])


def _refreshed(new: Any, old: Tensor, *, n_real: int) -> Tensor:
    """``refresh_positives``' result, checked: the shape of the positives it replaces, the real ones unchanged."""
    if not isinstance(new, Tensor) or new.shape != old.shape:
        raise ValueError(f"refresh_positives must return a tensor of the positives' shape {tuple(old.shape)}, got "
                         f"{getattr(new, 'shape', type(new).__name__)}")
    if not torch.equal(new[:n_real], old[:n_real]):
        raise ValueError(f"refresh_positives changed the first {n_real} (real) positives: only the added ones may change")
    return new.to(old.dtype)


def _val_text(v: dict[str, Any] | None) -> str:
    """A round's validation result in the progress line (``", validation FP 28, AP 0.412"``)."""
    if not v:
        return ""
    return f", validation FP {v['fp']}" + ("" if v.get("ap") is None else f", AP {v['ap']:.3f}")


def _criterion(select: str, v: dict[str, Any]) -> str:
    """A validation result as the selection reads it (``"FP 28"``, ``"AP 0.4120"``)."""
    if select == "fp":
        return f"FP {v['fp']}"
    return "AP none" if v.get("ap") is None else f"AP {v['ap']:.4f}"


def _better(v: dict[str, Any], best: dict[str, Any], select: str) -> bool:
    """Whether validation result ``v`` is a new best over ``best`` (strictly: ties keep the earlier round).

    ``"fp"``: fewer false positives; ``"ap"``: a higher AP (a None AP, no labelled object, is never better).
    """
    if select == "fp":
        return v["fp"] < best["fp"]
    a, b = v.get("ap"), best.get("ap")
    return a is not None and (b is None or a > b)


def _stop_reason(options: TrainOptions, best: dict[str, Any], v: dict[str, Any], since: int) -> str:
    """The log's ``stop_reason`` when the rounds stop for want of a new best (the old wording at the defaults)."""
    if options.mining_select == "fp" and options.mining_patience == 0:
        return f"validation false positives stopped falling ({best['fp']} -> {v['fp']})"
    what = {"fp": "fewer validation false positives", "ap": "higher validation AP"}[options.mining_select]
    return (f"no {what} in {since} round(s) (patience {options.mining_patience}; "
            f"best {_criterion(options.mining_select, best)}, last {_criterion(options.mining_select, v)})")


def _decoded_validation(val_frames: Iterable[Any] | None, say: Callable[[str], None]) -> list[Any] | None:
    """The validation frames decoded once (images as uint8 arrays or tensors); None when there is none."""
    if val_frames is None:
        return None
    t0 = time.perf_counter()
    val = [it._replace(image=np.asarray(it.image) if not isinstance(it.image, Tensor) else it.image)
           for it in (_as_item(x) for x in val_frames)]
    say(f"validation: {len(val)} frames, {sum(0 if v.boxes is None else len(v.boxes) for v in val)} objects "
        f"(decoded in {time.perf_counter() - t0:.1f}s)")
    return val or None


def _settings_log(options: TrainOptions, scales: Sequence[float], mining_source: Any,
                  val: list[Any] | None) -> dict[str, Any]:
    """The ``"mining"`` and ``"validation"`` settings of :func:`train_with_mining`'s log."""
    return {"mining": {"stride": getattr(mining_source, "stride", None), "per_frame": options.mining_per_frame,
                       "max_per_round": options.mining_max_per_round, "margin": options.mining_margin,
                       "scales": list(scales), "max_rounds": options.mining_rounds,
                       "select": options.mining_select, "patience": options.mining_patience,
                       "frame_scale": list(options.mining_frame_scale)},
            "validation": None if val is None else {"frames": len(val), "top_k": options.val_top_k, "iou": options.val_iou,
                                                    "target_recall": options.val_target_recall}}
