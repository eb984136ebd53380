"""Labelled videos -> a trained detector: what ``synthaug train`` and the experiments run.

:func:`train_from_videos` takes a folder of videos + labels (any numbering, any
classes) -> :func:`discover_videos` -> :func:`split_by_video` -> positives (seed
frames drawn the way ``synthaug ingest`` draws them, or every labelled frame, plus
synthetic ones from a fit; :mod:`synthaug.detectors.training_sets`) -> negatives ->
:func:`~synthaug.detectors.training.train_with_mining` -> a detector and its metadata.

**Negatives at scale.** The mining frames are every ``mining_stride``-th frame
of *every* training video of the class (labelled frames only: a null label does
not say the object is absent from view, only that it was not drawn, as
:func:`synthaug.data.negatives.sample_negatives` assumes too; the labelled box,
grown by ``max(4 px, mining_margin x longest side)`` on every side, is masked:
a window touching it is never a negative) and of every training video of the
negative classes (``"bird"``: every frame is free of the class, nothing is
masked — birds are the look-alikes to learn). HOG keeps its own DPM-style cache
mining over the negative pool (which now holds the mined windows) and the seed
frames; AdaBoost and the CNN learn from the mined windows only through this loop.
"""

from __future__ import annotations

import json
import math
import time
import dataclasses
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np
import torch
from torch import Tensor

from synthaug._checks import one_of
from synthaug._io import atomic_write_bytes, check_header, digest, exclusive_lock, file_fingerprint, sha256_file
from synthaug.data.video import find_video
from synthaug.detectors.frames import VideoFrames
from synthaug.detectors.training import DETECTORS, TrainOptions, train_with_mining
from synthaug.detectors.training_sets import (
    bird_hard_negatives,
    check_quantize,
    check_realism_keep,
    DISTRACTOR_STYLES,
    distractor_negatives,
    frames_training_set,
    mining_frames,
    negative_pool,
    quantize_name,
    real_positives,
    synthetic_positives,
)

__all__ = ["AddedPositives", "FAMILY_EFFECTS_OFF", "resolve_effects_off", "FAMILY_BACKGROUND_SAMPLING",
           "resolve_background_sampling", "FAMILY_REALISM_KEEP", "resolve_realism_keep", "FAMILY_SYNTHETIC_SHARE",
           "FAMILY_SYNTHETIC", "PAPER_SYNTHETIC", "resolve_synthetic_option", "BY_COUNT", "resolve_synthetic_share",
           "check_placement", "TrainingInputError", "VideoSet", "discover_videos", "split_by_video",
           "train_from_videos", "calibrate_detector", "METADATA_FORMAT"]

METADATA_FORMAT = "synthaug.trained_detector"
METADATA_VERSION = 1

FAMILY_EFFECTS_OFF: dict[str, tuple[str, ...]] = {"cnn": ("boundary_blur", "motion_blur")}
"""The fitted effects each detector family's synthetic positives leave out by default (:class:`AddedPositives`'s
``effects_off=None``); a family not listed keeps every effect. The CNN: the d_HOG fit's boundary and motion blur make
the synthetic drones softer than the CNN learns from best; chosen on the validation videos (drones, 100 seeds, 20x,
5 training seeds: +0.047 [+0.013, +0.081] AP@0.5 over every effect; ``results/synthetic/cnn_figs/README.md``)."""


def resolve_effects_off(kind: str, effects_off: str | Sequence[str] | None,
                        available: Sequence[str] | None = None) -> tuple[str, ...]:
    """The effects left out of a detector family's synthetic positives, as a tuple: None is the family's own set
    (:data:`FAMILY_EFFECTS_OFF`), a name is that effect alone, a sequence is those effects together. Given the
    effects a fit carries (``available``), the family's set keeps those among them and an effect asked for that is
    not among them is a ``ValueError``.

    >>> resolve_effects_off("cnn", None), resolve_effects_off("hog", None), resolve_effects_off("hog", "motion_blur")
    (('boundary_blur', 'motion_blur'), (), ('motion_blur',))
    >>> resolve_effects_off("cnn", None, available=("motion_blur", "object_noise"))
    ('motion_blur',)
    """
    if effects_off is None:
        family = FAMILY_EFFECTS_OFF.get(kind, ())
        return family if available is None else tuple(e for e in family if e in available)
    off = (effects_off,) if isinstance(effects_off, str) else tuple(effects_off)
    unknown = [] if available is None else sorted(set(off) - set(available))
    if unknown:
        raise ValueError(f"{unknown} not among the effects ({list(available or ())})")
    return off


FAMILY_BACKGROUND_SAMPLING: dict[str, str] = {"cnn": "other"}
"""Where each detector family's synthetic objects sit by default (:class:`AddedPositives`'s
``background_sampling=None``); a family not listed keeps the paper's, each object on its own seed's background
(``"seed"``). The CNN: on another seed's background (``"other"``), its capture parameters still its own seed's. Chosen
on the validation videos as the CNN's effects were (drones, 100 seeds, 20x, the CNN's own effects, built-in fits,
paired against own backgrounds; ``results/synthetic/background/README.md``): +0.031 [+0.011, +0.051] AP@0.5 on
training seeds 5-9, confirmed on seeds 0-4 (+0.014 [-0.013, +0.045]): +0.022 [+0.001, +0.045] over the 10. HOG keeps
its own: other backgrounds moved it +0.019 on test and -0.003 on validation (10 seeds each)."""


def resolve_background_sampling(kind: str, background_sampling: str | None, seed_count: int | None = None) -> str:
    """Where a detector family's synthetic objects sit: None is the family's own (:data:`FAMILY_BACKGROUND_SAMPLING`),
    a value of :data:`~synthaug.data.items.BACKGROUND_SAMPLING` is itself. A family's ``"other"`` falls back to
    ``"seed"`` for a seed set of ``seed_count < 2`` seeds (there is no other background); a ``"other"`` asked for is
    kept (and refused where the seeds are drawn).

    >>> resolve_background_sampling("cnn", None), resolve_background_sampling("hog", None)
    ('other', 'seed')
    >>> resolve_background_sampling("cnn", None, seed_count=1), resolve_background_sampling("hog", "other")
    ('seed', 'other')
    """
    from synthaug.data.items import BACKGROUND_SAMPLING

    if background_sampling is None:
        chosen = FAMILY_BACKGROUND_SAMPLING.get(kind, "seed")
        return "seed" if chosen == "other" and seed_count is not None and seed_count < 2 else chosen
    return one_of(background_sampling, BACKGROUND_SAMPLING, "background_sampling", alternatives=" or None")


FAMILY_REALISM_KEEP: dict[str, float] = {"hog": 0.25, "adaboost": 0.25}
"""The fraction of drawn synthetic positives each detector family keeps by default (:class:`AddedPositives`'s
``realism_keep=None``): those a critic in HOG features finds least synthetic against the seed set's real patches
(:func:`~synthaug.detectors.training_sets.synthetic_positives`' ``realism_keep``); a family not listed keeps every
draw (1, the paper). HOG keeps a quarter of 4x drawn: chosen on the validation videos (drones, 100 seeds, + 20x,
calibrated, ten training seeds, paired against every draw; ``results/synthetic/realism_critic/README.md``), +0.026
[+0.009, +0.051] AP@0.5 there and +0.008 [-0.006, +0.022] on the test videos. Since stop 83 the quarter is taken of
each seed's own draws (:class:`AddedPositives`' ``realism_selection="seed"``): at 12 seeds +0.017 [+0.003, +0.033] on
validation over the whole draw's quarter, at 100 seeds level (+0.001). AdaBoost keeps a quarter too since stop 104,
scored by a critic in its own features, as one part of its recipe (:data:`FAMILY_SYNTHETIC`). Alone, with the critic's
quarter (100 seeds, two training seeds, stop 86; ``results/synthetic/adaboost_critic/``) it was level with real only
on the validation videos (+0.001 [-0.033, +0.029]) and below it on the test videos (-0.041 [-0.068, -0.013]); with a
critic in its own features (``realism_features="weak_learners"``, stop 87, ``results/synthetic/adaboost_wl_critic/``)
+0.018 [-0.015, +0.044] on validation and -0.054 [-0.081, -0.032] on test; that with 8-bit positives
(``quantize=True``) +0.020 [-0.005, +0.043] and -0.007 [-0.027, +0.016]. The CNN was not measured with it."""


def resolve_realism_keep(kind: str, realism_keep: float | None, seed_count: int | None = None) -> float:
    """The fraction of drawn synthetic positives a detector family keeps: None is the family's own
    (:data:`FAMILY_REALISM_KEEP`), a fraction in (0, 1] is itself. A family's fraction falls back to 1 for a seed set
    of ``seed_count < 2`` seeds (the critic is cross-fitted by seed); a fraction asked for is kept (and refused where
    the positives are drawn).

    >>> resolve_realism_keep("hog", None), resolve_realism_keep("cnn", None), resolve_realism_keep("hog", 1)
    (0.25, 1.0, 1.0)
    >>> resolve_realism_keep("hog", None, seed_count=1)
    1.0
    """
    if realism_keep is None:
        chosen = FAMILY_REALISM_KEEP.get(kind, 1.0)
        return 1.0 if seed_count is not None and seed_count < 2 else chosen
    return check_realism_keep(realism_keep)


FAMILY_SYNTHETIC: dict[str, dict[str, Any]] = {
    "adaboost": {"pose_sampling": "fitted_at_seed", "shape_variation": 0.3, "quantize": "native_scale",
                 "realism_features": "weak_learners", "distractor_ratio": 5.0, "distractor_style": "soft"}}
"""How each detector family draws its synthetic positives by default, where it differs from the paper
(:data:`PAPER_SYNTHETIC`; :class:`AddedPositives`' fields of these names left at None, resolved by
:func:`resolve_synthetic_option`); a family not listed draws them as the paper does. AdaBoost (stop 104): each seed's
fitted rotation within 20 deg at its fitted offset, shapes varied +-30 % around the mesh, 8-bit levels, the quarter of
4x drawn its own weak-learner critic finds least synthetic (with :data:`FAMILY_REALISM_KEEP`), and 5 soft rendered
distractors per seed in the negatives (each blob faint and blurred against its background, like the cloud puffs it
took for drones). Measured as one configuration against real only on the drone test videos, calibrated, one machine
kind (``results/synthetic/adaboost_distractors/README.md``): 100 seeds, five training seeds, +0.024 [+0.003, +0.043]
AP@0.5, every seed up (the paper's draws with AdaBoost's share, its defaults before: -0.006 [-0.037, +0.017] at stop
61, uncalibrated), above + 20x copy-paste by +0.033 [+0.009, +0.059] and + 20x perturbed by +0.086 [+0.017,
+0.152]; without the distractors (the same draws) +0.029 [+0.011, +0.049] lower, and each part alone had been level
(``results/synthetic/factors/ranking.md``); 12 seeds, four training seeds, +0.093 [+0.061, +0.122] over 12 real, every
test video up, 0.62 [0.44, 0.84] of the 12 -> 100 real-seed gap. Airplanes, 12 seeds (stop 105,
``results/synthetic/airplane_v2/adaboost_recipe/``): +0.229 [+0.092, +0.420] over 12 real, 0.56 of the gap, but -0.038
[-0.075, -0.008] against the paper's draws, lost on the 48-96 px airplanes; float renders took it back there (+0.042
[+0.004, +0.076]) but not on the drones at 100 seeds (-0.019 [-0.053, +0.008], stop 106). Since stop 108 the rounding
is ``"native_scale"`` (:data:`~synthaug.detectors.training_sets.QUANTIZE`): 8-bit only the seeds the pyramid sees at
about their own size, float where it shrinks them (the distractors 8-bit), ``results/synthetic/rounding_parts/``,
paired against the 8-bit recipe: airplanes, 12 seeds, five training seeds, +0.037 [+0.003, +0.072] (every seed up;
seeds resampled too [-0.019, +0.095]; 0.83 [0.66, 1.06] of the 12 -> 100 gap); drones, 100 seeds, three training
seeds, +0.000 [-0.019, +0.016]; drones, 12 seeds, four training seeds, -0.001 [-0.019, +0.018]. The decision rule
(airplanes' paired CI above 0, the drones at 100 seeds losing nothing) was written before airplane seeds 3-4 ran."""

PAPER_SYNTHETIC: dict[str, Any] = {"pose_sampling": "uniform", "shape_variation": 0.0, "quantize": False,
                                   "realism_features": "hog", "distractor_ratio": 0.0, "distractor_style": "drawn"}
"""The paper's way of drawing the synthetic positives, for the options :data:`FAMILY_SYNTHETIC` may set."""


def resolve_synthetic_option(kind: str, name: str, value: Any = None, *, synthetic: bool = True,
                             object_box: Any = None, distractor_ratio: float | None = None,
                             realism_selection: str | None = None) -> Any:
    """One option of how a detector family draws its synthetic positives: ``value`` itself when given, else the
    family's (:data:`FAMILY_SYNTHETIC`) where there are synthetic positives (``synthetic``), else the paper's
    (:data:`PAPER_SYNTHETIC`). A family's pose at the seeds' offsets keeps its rotations and leaves the placement to a
    given ``object_box``; a family's distractor style is the paper's where the (resolved) ``distractor_ratio`` is 0;
    a family's critic features are HOG's for the ``"item"`` selection (which scores in HOG features).

    >>> resolve_synthetic_option("adaboost", "pose_sampling"), resolve_synthetic_option("hog", "pose_sampling")
    ('fitted_at_seed', 'uniform')
    >>> resolve_synthetic_option("adaboost", "pose_sampling", object_box="seed")
    'fitted'
    >>> resolve_synthetic_option("adaboost", "quantize", synthetic=False)
    False
    >>> resolve_synthetic_option("cnn", "quantize", True), resolve_synthetic_option("adaboost", "distractor_ratio")
    (True, 5.0)
    >>> resolve_synthetic_option("adaboost", "distractor_style", distractor_ratio=0)
    'drawn'
    """
    if name not in PAPER_SYNTHETIC:
        raise ValueError(f"{name!r} is not one of {sorted(PAPER_SYNTHETIC)}")
    if value is not None:
        return value
    chosen = FAMILY_SYNTHETIC.get(kind, {}).get(name, PAPER_SYNTHETIC[name]) if synthetic else PAPER_SYNTHETIC[name]
    if name == "pose_sampling" and object_box is not None:
        chosen = chosen.removesuffix("_at_seed")
    if name == "distractor_style" and not resolve_synthetic_option(kind, "distractor_ratio", distractor_ratio,
                                                                   synthetic=synthetic):
        chosen = PAPER_SYNTHETIC[name]
    if name == "realism_features" and realism_selection == "item":
        chosen = "hog"
    return chosen


BY_COUNT = "count"
"""``synthetic_share`` value that weighs every positive the same (the added ones hold ``added / (real + added)``)."""

FAMILY_SYNTHETIC_SHARE: dict[str, float] = {"adaboost": 0.25}
"""The added positives' share of the positive class's training weight by default, per detector family
(:class:`AddedPositives`'s ``synthetic_share=None``); a family not listed weighs every positive the same. AdaBoost: the
real positives hold 3/4 of the starting weight. Measured with 20x synthetic, 3 training seeds, test AP@0.5 paired
against the same cells by count: drones, 100 seeds +0.046 [+0.015, +0.070]
(``results/synthetic/drone_v2_adaboost_share/``); drones, 12 seeds +0.044 [+0.007, +0.083]
(``results/synthetic/adaboost_12/``; validation +0.038 [+0.009, +0.066]); airplanes, 12 seeds +0.057 [+0.004, +0.119]
(``results/synthetic/airplane_v2/``; validation −0.018 [−0.050, +0.012]: not confirmed there). Chosen for the
synthetic positives; the other added kinds (perturbed, copy-paste, ...) get it too, unmeasured."""


def resolve_synthetic_share(kind: str, share: float | str | None) -> float | None:
    """The added positives' share of the positive weight a detector family trains with: None is the family's
    (:data:`FAMILY_SYNTHETIC_SHARE`), :data:`BY_COUNT` weighs every positive the same (returned as None, as
    :func:`share_weights` reads it), a number is that share.

    >>> resolve_synthetic_share("adaboost", None), resolve_synthetic_share("hog", None)
    (0.25, None)
    >>> resolve_synthetic_share("adaboost", "count"), resolve_synthetic_share("hog", 0.5)
    (None, 0.5)
    """
    if share is None:
        return FAMILY_SYNTHETIC_SHARE.get(kind)
    if isinstance(share, str):
        if share != BY_COUNT:
            raise ValueError(f"synthetic_share must be a number in [0, 1), {BY_COUNT!r} or None, got {share!r}")
        return None
    return float(share)


class TrainingInputError(ValueError):
    """An input of :func:`train_from_videos` that cannot be used; ``option`` names the CLI option."""

    def __init__(self, option: str, message: str) -> None:
        super().__init__(f"{option}: {message}")
        self.option = option


@dataclass
class VideoSet:
    """The labelled videos of a folder pair: stem -> class, and the files.

    Attributes:
        videos_dir, labels_dir: the folders.
        classes: stem -> class name (from the label files), for stems with a video file.
        missing_video: label files without a video file (not used).
    """

    videos_dir: Path
    labels_dir: Path
    classes: dict[str, str]
    missing_video: list[str] = field(default_factory=list)


def check_placement(pose_sampling: Sequence[str], object_box: Sequence[Any]) -> None:
    """Raise ``ValueError`` when a pose sampling that places each object at its seed's offset (``"*_at_seed"``) is
    asked together with an object box, which centres the object itself (every pair of them would be trained)."""
    at_seed = [ps for ps in pose_sampling if ps.endswith("_at_seed")]
    boxes = [ob for ob in object_box if ob is not None]
    if at_seed and boxes:
        raise ValueError(f"pose sampling {at_seed} places each object at its seed's offset and object box {boxes} "
                         f"centres it: choose one")


@dataclass(frozen=True)
class AddedPositives:
    """What :func:`train_from_videos` adds to the real positives of a seed set, and how much weight it gets.

    Attributes:
        params: ``synthaug fit`` output made on the seed set (one row per seed), or a callable given the seed
            set's folder once it exists that returns that file (e.g. fits it); needed by the synthetic and
            copy-paste positives.
        mesh: mesh of the synthetic object (default: the fit's, else the built-in quadcopter).
        synthetic_ratio: synthetic patches per real seed (the paper's generator,
            :func:`~synthaug.detectors.training_sets.synthetic_positives`).
        pose_sampling: poses of the synthetic positives: ``"uniform"`` (the paper), ``"fitted"`` (around each
            seed's fitted pose), or either with ``"_at_seed"``: the object at its seed's fitted offset
            (:data:`~synthaug.data.poses.POSE_SAMPLING`). None (the default): the detector family's
            (:data:`FAMILY_SYNTHETIC`: AdaBoost ``"fitted_at_seed"``, ``"fitted"`` with an ``object_box``; the others
            ``"uniform"``).
        object_box: None (the paper) or ``"seed"`` / a fraction: each synthetic object framed as ingest frames a
            labelled seed (:class:`~synthaug.data.synthetic.SyntheticObjectDataset`'s ``object_box``).
        object_box_share: the fraction of the synthetic objects ``object_box`` frames (1: every one), the others
            framed as the paper's (:class:`~synthaug.data.synthetic.SyntheticObjectDataset`'s ``object_box_share``).
        shape_variation: 0 (the paper) or > 0: the synthetic objects' shapes vary around the mesh within ± this
            fraction (:class:`~synthaug.data.synthetic.SyntheticObjectDataset`'s ``shape_variation``). None (the
            default): the detector family's (:data:`FAMILY_SYNTHETIC`: AdaBoost 0.3, the others 0).
        capture_sampling: how each synthetic patch's capture parameters are drawn: ``"seed"`` (the paper: one seed's
            fitted row), ``"uniform"`` (each parameter uniform between its fitted extremes: the paper's Fig. 10
            baseline) or ``"kde"`` (:class:`~synthaug.data.synthetic.SyntheticObjectDataset`'s ``capture_sampling``).
        effects_off: fitted effects left out of the synthetic patches (the paper's Fig. 9 ablation), by name
            (e.g. ``("motion_blur",)``); each must be one of the fit's effects. ``()``: every fitted effect. None (the
            default): the detector family's (:data:`FAMILY_EFFECTS_OFF`, those among the fit's effects).
        copy_paste_ratio: copy-paste patches per real seed: the seeds' objects cut out with their fitted
            silhouettes and pasted on other seeds' backgrounds (:func:`~synthaug.data.copypaste.copy_paste_positives`;
            a user's baseline).
        perturb_copies: perturbed copies of every real positive (the paper's Table 1 baseline,
            :func:`~synthaug.effects.perturb.perturb_patches`).
        downscaled_copies: copies of every real seed shown as a smaller, farther object, cut the way the pyramid's
            largest magnification sees it (:func:`~synthaug.detectors.training_sets.downscaled_positives`; seed sets
            only).
        faded_copies: copies of every real seed with the object's contrast against its own background lowered
            (:func:`~synthaug.detectors.training_sets.faded_positives`; seed sets only).
        faded_contrast: the range the faded copies' contrast factor is drawn from (None:
            :data:`~synthaug.detectors.training_sets.FADED_CONTRAST`); a negative range (e.g.
            :data:`~synthaug.detectors.training_sets.INVERTED_CONTRAST`) inverts the object's contrast.
        refit: the d_CNN refit (CNN only): a callable ``(fit, seed_set_folder, detector, r) -> fit file`` that
            refits the fit ``fit`` of the seed set against round ``r``'s detector (e.g. its network as the ``cnn``
            distance, :func:`synthaug.fit.refit.refit_with_network`); the synthetic positives of rounds ``r + 1``
            and later are redrawn from the file it returns (the same poses and draws, the same effects left out;
            the copy-paste positives keep ``params``' silhouettes). None: one fit for every round (the paper's
            default). Needs synthetic positives and mining rounds.
        quantize: round the synthetic positives to 8-bit levels, as the real frames are stored
            (:func:`~synthaug.detectors.training_sets.synthetic_positives`' ``quantize``); ``"native_scale"``: only
            those of the seeds the pyramid sees at about their own size
            (:data:`~synthaug.detectors.training_sets.QUANTIZE`). False: the renderer's continuous values. None (the
            default): the detector family's (:data:`FAMILY_SYNTHETIC`: AdaBoost ``"native_scale"``, the others
            False).
        background_sampling: ``"seed"`` (the paper: each synthetic object on its own seed's background) or
            ``"other"`` (on another seed's, the capture parameters still its own seed's;
            :class:`~synthaug.data.synthetic.SyntheticObjectDataset`'s ``background_sampling``). None (the default):
            the detector family's (:data:`FAMILY_BACKGROUND_SAMPLING`: the CNN ``"other"``, the others ``"seed"``; a
            one-seed set ``"seed"``).
        realism_keep: the fraction of drawn synthetic positives kept, the ones a critic in HOG features finds least
            synthetic against the seed set's real patches
            (:func:`~synthaug.detectors.training_sets.synthetic_positives`' ``realism_keep``); 1: every draw (the
            paper). None (the default): the detector family's (:data:`FAMILY_REALISM_KEEP`: HOG and AdaBoost 0.25, the
            CNN 1; a one-seed set 1).
        realism_selection: with ``realism_keep`` under 1, ``"seed"`` (the default: each seed keeps the same share of
            its own draws), ``"set"`` (the least synthetic of the whole draw) or ``"item"`` (each patch the least
            synthetic of its own candidates;
            :func:`~synthaug.detectors.training_sets.synthetic_positives`' ``realism_selection``).
        realism_features: the critic's features, ``"hog"`` or ``"weak_learners"`` (the edge-orientation energies
            AdaBoost's stumps threshold; ``"seed"`` and ``"set"`` selections;
            :data:`~synthaug.detectors.critic.REALISM_FEATURES`). None (the default): the detector family's
            (:data:`FAMILY_SYNTHETIC`: AdaBoost ``"weak_learners"``, the others ``"hog"``).
        synthetic_share: the share of the positive class's training weight held by the added positives, the rest
            shared by the real ones; :data:`BY_COUNT` (``"count"``): every positive weighs the same, so the added ones
            hold ``added / (real + added)``; None (the default): the detector family's (:data:`FAMILY_SYNTHETIC_SHARE`:
            AdaBoost 0.25, the others by count). HOG: the SVM's per-sample cost; CNN: the BCE loss's per-sample
            weight (kept through the flip doubling, the split and the mining rounds); AdaBoost: the positives' starting
            weights (every mining round).
        distractor_ratio: rendered distractors per real seed added to the negatives: drawn as the synthetic
            positives are (their fit, poses, placement, effects and 8 bits), an ellipsoid in place of the object
            (:func:`~synthaug.detectors.training_sets.distractor_negatives`; domain randomisation's distractors).
            Needs synthetic positives. 0: none. None (the default): the detector family's (:data:`FAMILY_SYNTHETIC`:
            AdaBoost 5 where there are synthetic positives, the others 0).
        distractor_style: how the distractors look (:data:`~synthaug.detectors.training_sets.DISTRACTOR_STYLES`):
            ``"drawn"`` (as the object is drawn) or ``"soft"`` (each faint and blurred against its background, like a
            cloud puff). None (the default): the detector family's (:data:`FAMILY_SYNTHETIC`: AdaBoost ``"soft"``,
            the others ``"drawn"``; ``"drawn"`` where there are no distractors).
    """

    params: str | Path | Callable[[Path], str | Path] | None = None
    mesh: str | None = None
    synthetic_ratio: float = 0.0
    pose_sampling: str | None = None
    object_box: float | str | None = None
    shape_variation: float | None = None
    capture_sampling: str = "seed"
    effects_off: tuple[str, ...] | None = None
    copy_paste_ratio: float = 0.0
    perturb_copies: int = 0
    synthetic_share: float | str | None = None
    downscaled_copies: int = 0
    faded_copies: int = 0
    faded_contrast: tuple[float, float] | None = None
    refit: Callable[[Path, Path, Any, int], str | Path] | None = None
    quantize: bool | str | None = None
    background_sampling: str | None = None
    object_box_share: float = 1.0
    realism_keep: float | None = None
    realism_selection: str = "seed"
    realism_features: str | None = None
    distractor_ratio: float | None = None
    distractor_style: str | None = None

    def __post_init__(self) -> None:
        from synthaug.data.captures import CAPTURE_SAMPLERS
        from synthaug.data.poses import POSE_SAMPLING
        from synthaug.data.synthetic import check_object_box_share
        from synthaug.detectors.critic import check_realism_features, check_realism_selection

        resolve_background_sampling("", self.background_sampling)  # raises on a value that is not one
        one_of(self.capture_sampling, CAPTURE_SAMPLERS, "capture_sampling")
        if self.pose_sampling is not None:
            one_of(self.pose_sampling, POSE_SAMPLING, "pose_sampling")
            check_placement([self.pose_sampling], [self.object_box])
        check_object_box_share(self.object_box_share, self.object_box)
        if self.effects_off is not None:
            if isinstance(self.effects_off, str) or not all(isinstance(e, str) for e in self.effects_off):
                raise ValueError(f"effects_off must be None or a sequence of effect names, got {self.effects_off!r}")
            object.__setattr__(self, "effects_off", tuple(self.effects_off))
        if isinstance(self.synthetic_share, str):
            resolve_synthetic_share("", self.synthetic_share)  # raises on any string but BY_COUNT
        resolve_realism_keep("", self.realism_keep)  # raises on a value that is not a fraction in (0, 1]
        if self.quantize is not None:
            check_quantize(self.quantize)
        check_realism_selection(self.realism_selection)
        if self.realism_features is not None:
            check_realism_features(self.realism_features, selection=self.realism_selection)

    def resolved(self, kind: str) -> AddedPositives:
        """These positives with every option left at None that :data:`FAMILY_SYNTHETIC` may set resolved for the
        detector family ``kind`` (:func:`resolve_synthetic_option`: the family's where there are synthetic
        positives, else the paper's)."""
        synthetic = self.synthetic_ratio > 0
        values = {name: resolve_synthetic_option(kind, name, getattr(self, name), synthetic=synthetic,
                                                 object_box=self.object_box, distractor_ratio=self.distractor_ratio,
                                                 realism_selection=self.realism_selection)
                  for name in PAPER_SYNTHETIC}
        return dataclasses.replace(self, **values)


def discover_videos(videos_dir: str | Path, labels_dir: str | Path) -> VideoSet:
    """Every ``labels/<stem>.json`` with a ``videos/<stem>.<ext>`` (any numbering), and its class.

    Raises:
        TrainingInputError: a folder is missing (``--videos`` / ``--labels``) or holds no label file.
    """
    videos_dir, labels_dir = Path(videos_dir), Path(labels_dir)
    if not videos_dir.is_dir():
        raise TrainingInputError("--videos", f"folder not found: {videos_dir}")
    if not labels_dir.is_dir():
        raise TrainingInputError("--labels", f"folder not found: {labels_dir}")
    classes: dict[str, str] = {}
    missing: list[str] = []
    for f in sorted(labels_dir.glob("*.json")):
        try:
            doc = json.loads(f.read_text())
        except (OSError, json.JSONDecodeError) as e:
            raise TrainingInputError("--labels", f"label file {f} is not readable JSON ({e})") from None
        cls = doc.get("class") if isinstance(doc, dict) else None
        if not isinstance(cls, str) or not isinstance(doc.get("boxes"), list):
            continue  # not a label file of the shared format (e.g. a split or report file)
        if find_video(videos_dir, f.stem) is None:
            missing.append(f.stem)
            continue
        classes[f.stem] = cls
    if not classes:
        raise TrainingInputError("--labels", f"no label file of the shared format with a video in --videos {videos_dir} "
                                             f"(label files: {labels_dir})")
    return VideoSet(videos_dir, labels_dir, classes, missing)


def split_by_video(
    vs: VideoSet,
    class_name: str,
    *,
    split: str | Path | None = None,
    seed: int = 0,
    val_fraction: float = 0.2,
    block: int = 1,
    negative_classes: Sequence[str] = ("bird",),
) -> dict[str, Any]:
    """Training / validation videos of a class and the training videos of the negative classes.

    With ``split`` (a ``synthaug.video_split`` file) its ``train`` / ``val`` lists (and
    ``hard_negatives.train``) are used, restricted to the videos present; without it the
    videos are split by video with :func:`synthaug.data.splits.make_video_split`
    (fractions ``1 - val_fraction`` / ``val_fraction`` / 0, per class, blocks of ``block``
    consecutive numbers, shuffled by ``seed``): deterministic given the folder and ``seed``.

    Returns:
        ``{"source": "file" | "auto", "train", "val", "negative_train", "negative_val", ...}`` (sorted stems).

    Raises:
        TrainingInputError: no video of the class (``--class``), a bad split file (``--split``),
            no training video of the class.
    """
    from synthaug.data.splits import load_split, make_video_split

    present = {s for s, c in vs.classes.items() if c == class_name}
    if not present:
        found = sorted(set(vs.classes.values()))
        raise TrainingInputError("--class", f"no video of class {class_name!r} in --labels {vs.labels_dir} (classes found: {found})")
    neg_present = {s for s, c in vs.classes.items() if c in negative_classes and c != class_name}
    if split is not None:
        try:
            sp = load_split(split)
        except (ValueError, FileNotFoundError) as e:
            raise TrainingInputError("--split", str(e)) from None
        listed = set(sp.classes) | {v for s in sp.videos.values() for v in s} | {v for s in sp.hard_negatives.values() for v in s}
        out = {"source": "file", "file": str(split),
               "train": sorted(v for v in sp.videos.get("train", []) if v in present),
               "val": sorted(v for v in sp.videos.get("val", []) if v in present),
               "negative_train": sorted(v for v in sp.hard_negatives.get("train", []) + sp.videos.get("train", []) if v in neg_present),
               "negative_val": sorted(v for v in sp.hard_negatives.get("val", []) + sp.videos.get("val", []) if v in neg_present),
               "unlisted": sorted((present | neg_present) - listed),
               "listed_not_in_folder": len({v for v, c in sp.classes.items() if c == class_name} - present)}
    else:
        if not 0 <= val_fraction < 1:
            raise TrainingInputError("--val-fraction", f"must be in [0, 1), got {val_fraction}")
        classes = {s: vs.classes[s] for s in sorted(present | neg_present)}
        sp = make_video_split(classes, fractions={"train": 1 - val_fraction, "val": val_fraction, "test": 0.0}, seed=seed,
                              block=block, hard_negative_classes=tuple(c for c in negative_classes if c != class_name))
        out = {"source": "auto", "seed": seed, "fractions": {"train": 1 - val_fraction, "val": val_fraction}, "block": block,
               "rule": "synthaug.data.splits.make_video_split per class (by video, seeded shuffle of blocks of consecutive numbers)",
               "train": sorted(v for v in sp.videos["train"] if v in present),
               "val": sorted(v for v in sp.videos["val"] if v in present),
               "negative_train": sorted(sp.hard_negatives["train"]), "negative_val": sorted(sp.hard_negatives["val"])}
    if not out["train"]:
        raise TrainingInputError("--split" if split is not None else "--class",
                                 f"no training video of class {class_name!r}" + (f" in the split file {split}" if split else ""))
    out["class"] = class_name
    out["negative_classes"] = list(negative_classes)
    return out


def _labelled_frames(labels_dir: Path, stems: Sequence[str]) -> int:
    from synthaug.data.video import read_labels

    return sum(sum(1 for b in read_labels(labels_dir / f"{s}.json").boxes if b is not None) for s in stems)


def _seed_set_by_ingest(vs: VideoSet, split: Mapping[str, Any], n: int, work: Path, *, ingest_seed: int, workers: int,
                        log: Callable[[str], None], negative_classes: Sequence[str]) -> Any:
    """Seed set of ``n`` seeds drawn from the training videos exactly as ``synthaug ingest`` draws them."""
    from synthaug.data.ingest import IngestConfig, ingest_videos
    from synthaug.data.seedset import SeedSet
    from synthaug.data.splits import VideoSplit

    cls = split["class"]
    train = list(split["train"])
    per_video = max(IngestConfig().seeds_per_video, math.ceil(n / len(train)))
    cfg = IngestConfig(seeds_per_video=per_video, seed=ingest_seed, hard_negative_classes=tuple(negative_classes))
    only_train = VideoSplit({"train": train, "val": [], "test": []},
                            {"train": list(split["negative_train"]), "val": [], "test": []},
                            {s: vs.classes[s] for s in train + list(split["negative_train"])})
    t0 = time.perf_counter()
    # Two trainings on one ingest folder (the runner's jobs side by side): the ingest rewrites the seed sets even when
    # every video is reused, so one ingests and reads its seed set while the other waits (a swap of the seed set's
    # folder by one under the other's feet failed, stop 81).
    with exclusive_lock(work / ".ingest.lock"):
        report = ingest_videos(vs.videos_dir, vs.labels_dir, work, split=only_train, splits=("train",), cfg=cfg,
                               seed_counts=[n], workers=workers, progress=False)
        path = work / "seedsets" / f"{cls}_{n}"
        if not (path / "seedset.json").is_file():
            raise TrainingInputError("--seed-counts", f"ingest drew no seed of class {cls!r} from the training videos "
                                                      f"({report['failed']})")
        ss = SeedSet.load(path)
    if report["failed"]:
        log(f"ingest: {len(report['failed'])} video(s) failed: {report['failed']}")
    log(f"ingest: {report['processed']} videos processed, {report['skipped_current']} reused ({time.perf_counter() - t0:.0f}s)")
    if len(ss) < n:
        raise TrainingInputError("--seed-counts", f"{n} seeds asked but the training videos give only {len(ss)} usable seed frames "
                                                  f"(box fully inside the frame, longest side >= {cfg.min_box_side:g} px, "
                                                  f"{per_video} candidates per video); ask for at most {len(ss)} or use --all-frames")
    return ss


def train_from_videos(
    kind: str,
    class_name: str,
    videos_dir: str | Path,
    labels_dir: str | Path,
    *,
    out: str | Path | None = None,
    split: str | Path | None = None,
    seed: int = 0,
    seed_count: int | None = 100,
    all_frames: bool = False,
    frame_step: int = 1,
    seedset: str | Path | None = None,
    positive_videos: int | None = None,
    added: AddedPositives = AddedPositives(),
    options: TrainOptions = TrainOptions(),
    work_dir: str | Path | None = None,
    ingest_seed: int = 0,
    ingest_workers: int = 2,
    negative_classes: Sequence[str] = ("bird",),
    val_fraction: float = 0.2,
    split_block: int = 1,
    extra_negatives: int = 3000,
    log: Callable[[str], None] | None = None,
    command: Any = None,
) -> tuple[Any, dict[str, Any]]:
    """Videos + labels (+ a fit) -> a trained detector: what ``synthaug train`` runs.

    Steps: :func:`discover_videos` -> :func:`split_by_video` -> positives (``seed_count``
    seeds drawn by ``synthaug ingest``'s code into ``work_dir`` — its shards are reused by
    a rerun —, an existing ``seedset``, or with ``all_frames`` every ``frame_step``-th
    labelled frame of the training videos) + the ``added`` positives (synthetic, copy-paste,
    perturbed: :class:`AddedPositives`) -> negatives (the seed set's + ``extra_negatives`` object-free crops
    of the seed frames, or, with ``all_frames``, 60 crops per training video + look-alike
    crops of the negative-class videos) -> :func:`~synthaug.detectors.training.train_with_mining` over every
    ``options.mining_stride``-th frame of all training videos (+ negative-class videos),
    stopped on the validation videos -> ``out`` (:func:`~synthaug.detectors.base.save_detector`)
    and ``out`` with suffix ``.json`` (the metadata returned here).

    Args:
        kind: ``"hog"``, ``"adaboost"`` or ``"cnn"``.
        class_name: the class to detect (the label files' ``class``).
        videos_dir, labels_dir: the shared-format folders (any stems, any numbering).
        out: checkpoint to write (None: nothing written).
        split: a ``synthaug.video_split`` file; None: split by video from ``seed``.
        seed: training seed (initialisation, negatives, the automatic split).
        seed_count: real seeds (ignored with ``all_frames`` or ``seedset``).
        all_frames: every labelled frame of the training videos (every ``frame_step``-th).
        frame_step: see ``all_frames``.
        seedset: use this seed set (``synthaug ingest`` output) instead of ingesting.
        positive_videos: draw the positives (seeds or all frames) from only this many of the training videos
            (:func:`positive_video_subset`, drawn by ``seed``); the box map, the mining and the validation still use
            every training video. The subset's seed draw is ingested into ``<work_dir>/positive_videos_<K>_seed<seed>``, apart
            from the full set's. None: every training video.
        added: positives added to the real ones and their weight (:class:`AddedPositives`; default: none).
        options: budgets (:class:`~synthaug.detectors.training.TrainOptions`).
        work_dir: ingest output folder (default: ``<out>.work``; a temporary folder when ``out`` is None).
        ingest_seed: ``synthaug ingest --seed`` of the seed draw (0: the same seed set as a
            default ``synthaug ingest`` of the training videos).
        ingest_workers: ingest worker processes.
        negative_classes: classes whose videos are free of ``class_name`` (mined whole).
        val_fraction, split_block: the automatic split.
        extra_negatives: object-free crops of the seed frames added to the seed set's negatives.
        log: progress printer.
        command: the command line (or its parsed options), recorded in the metadata.

    Returns:
        ``(detector, metadata)``.

    Raises:
        TrainingInputError: an input that cannot be used; ``.option`` names the option.
    """
    say = log or (lambda m: None)
    _check_options(kind, added, frame_step=frame_step, all_frames=all_frames, seedset=seedset, seed_count=seed_count)
    if added.refit is not None and not options.mining_rounds:
        raise TrainingInputError("--dcnn-refit", "the refit runs between mining rounds, and there are none (mining_rounds = 0)")
    t_start = time.perf_counter()
    vs = discover_videos(videos_dir, labels_dir)
    sp = split_by_video(vs, class_name, split=split, seed=seed, val_fraction=val_fraction, block=split_block,
                        negative_classes=negative_classes)
    say(f"{class_name}: {len(sp['train'])} training videos, {len(sp['val'])} validation videos, "
        f"{len(sp['negative_train'])} negative-class training videos ({sp['source']} split)")
    pos_sp = _positive_split(sp, positive_videos, seed=seed, seedset=seedset)
    ingest_dir = work_dir
    if pos_sp is not sp:
        say(f"positives from {len(pos_sp['train'])} of the {len(sp['train'])} training videos: {pos_sp['train']}")
        given = _given_work_dir(work_dir, out)  # the subset's seed draw never touches the full set's seed sets
        ingest_dir = None if given is None else given / f"positive_videos_{len(pos_sp['train'])}_seed{seed}"
    _check_against_split(vs, pos_sp, class_name, params=added.params, all_frames=all_frames, seedset=seedset,
                         seed_count=seed_count)

    # ---------------------------------------------------------------- positives and negatives
    t0 = time.perf_counter()
    if seedset is not None or not all_frames:
        ss = _seed_set(vs, pos_sp, seedset=seedset, seed_count=seed_count, work_dir=ingest_dir, out=out,
                       ingest_seed=ingest_seed, ingest_workers=ingest_workers, negative_classes=negative_classes, say=say)
        ts = _seed_set_training_set(ss, seedset, extra_negatives=extra_negatives, seed=seed, options=options,
                                    ingest_seed=ingest_seed)
    else:
        ts = _all_frames_training_set(vs, pos_sp, frame_step=frame_step, seed=seed)
    if pos_sp is not sp:
        ts.info["positive_videos"] = list(pos_sp["train"])
    n_real = int(ts.positives.shape[0])
    perturb_info = _add_perturbed(ts, added.perturb_copies, seed=seed, say=say)
    downscaled_info = _add_downscaled(ts, added.downscaled_copies, options, seed=seed, say=say)
    faded_info = _add_faded(ts, added.faded_copies, seed=seed, say=say, contrast=added.faded_contrast)
    synthetic_info = _add_from_fit(ts, added, kind, seed=seed, say=say)
    t_data = time.perf_counter() - t0
    say(f"training set: {ts.positives.shape[0]} positives, {ts.negatives.shape[0]} negatives ({t_data:.0f}s)")

    # ---------------------------------------------------------------- training with mining
    box_cache = _box_cache_dir(work_dir, out)
    regressor, box_info = _box_regressor(vs, sp, options, ts.box_in_window, seed=seed, say=say, cache_dir=box_cache)
    t0 = time.perf_counter()
    share = resolve_synthetic_share(kind, added.synthetic_share)
    weights = share_weights(n_real, int(ts.positives.shape[0]), share)
    if weights is not None:
        ts.info["synthetic_share"] = share
    refresh = _refit_refresh(ts, added, synthetic_info, say) if added.refit is not None else None
    res = _mine_and_train(kind, ts, vs, sp, options, seed=seed, regressor=regressor, say=say, positive_weights=weights,
                          real_positives=n_real, refresh_positives=refresh)
    t_train = time.perf_counter() - t0
    meta = _metadata(kind, class_name, seed, videos_dir, labels_dir, sp, ts, res, options=options,
                     synthetic_info=synthetic_info, perturb_info=perturb_info, downscaled_info=downscaled_info,
                     faded_info=faded_info, box_info=box_info,
                     seconds={"data": round(t_data, 1), "training": round(t_train, 1),
                              "total": round(time.perf_counter() - t_start, 1)},
                     command=command, out=out)
    calibration = options.for_family(kind).box_calibration
    if calibration and sp["train"]:
        meta["box_calibration"] = calibrate_detector(res.detector, vs.videos_dir, vs.labels_dir, sp["train"],
                                                     stride=calibration, scales=options.scales,
                                                     nms_iou=options.mining_nms_iou,
                                                     form=options.box_calibration_form, say=say)
    if out is not None:
        _write_outputs(res.detector, meta, Path(out), say)
    return res.detector, meta


def calibrate_detector(detector: Any, videos_dir: str | Path, labels_dir: str | Path, videos: Sequence[str], *,
                       stride: int, scales: Sequence[float] | None = None, nms_iou: float = 0.3,
                       max_detections: int = 100, form: str = "regression",
                       say: Callable[[str], None] = lambda m: None) -> dict[str, Any]:
    """Set ``detector.box_regressor`` to its box map followed by the detector's own correction, fitted on every
    ``stride``-th labelled frame of ``videos`` (its training videos;
    :func:`~synthaug.detectors.box_calibration.calibrate_boxes`), detected with ``scales`` and ``nms_iou`` as
    scored, its size term fitted as ``form`` says (:func:`~synthaug.detectors.box_calibration.fit_calibration`).
    Returns the correction's metadata. With too few matched detections to fit (a few short videos), the
    detector keeps its box map, and the metadata and the log say so (``skipped``)."""
    from synthaug.detectors.box_calibration import calibrate_boxes

    frames = VideoFrames(videos_dir, labels_dir, positive=list(videos), stride=stride)
    try:
        from synthaug.detectors.sliding import detect_multiscale

        calibrated = calibrate_boxes(detector, frames, scales=scales, nms_iou=nms_iou, max_detections=max_detections,
                                     form=form, detect=detect_multiscale)
    except ValueError as e:
        say(f"box calibration skipped, the box map kept: {e}")
        return {"stride": int(stride), "skipped": str(e)}
    detector.box_regressor = calibrated
    info = dict(calibrated.meta, stride=int(stride))
    say(f"box calibration: {info['pairs']} detections of {info['frames']} training frames, median deltas "
        f"{info['median_deltas_before']} -> {info['median_deltas_after']} ({info['seconds']:.0f} s)")
    return info


def positive_video_subset(videos: Sequence[str], k: int, seed: int) -> list[str]:
    """``k`` of ``videos`` drawn by ``seed`` (sorted): the first ``k`` of one seeded permutation of the sorted stems,
    so for one seed the subsets are nested (``k`` videos are among those of ``k + 1``)."""
    stems = sorted(videos)
    if not 1 <= k <= len(stems):
        raise TrainingInputError("--positive-videos", f"must be in [1, {len(stems)}] (the training videos), got {k}")
    order = np.random.default_rng(seed).permutation(len(stems))
    return sorted(stems[i] for i in order[:k])


def _positive_split(sp: dict[str, Any], k: int | None, *, seed: int, seedset: str | Path | None) -> dict[str, Any]:
    """The split the positives are drawn from: ``sp`` itself, or with ``k`` of its training videos."""
    if k is None:
        return sp
    if seedset is not None:
        raise TrainingInputError("--positive-videos", "a given seed set already fixes its videos: drop --seed-set")
    return {**sp, "train": positive_video_subset(sp["train"], int(k), seed)}


def _check_options(kind: str, added: AddedPositives, *, frame_step: int, all_frames: bool,
                   seedset: str | Path | None, seed_count: int | None) -> None:
    """:func:`train_from_videos`' arguments on their own, ``added`` as ``kind`` resolves it
    (:meth:`AddedPositives.resolved`); :class:`TrainingInputError` names the option."""
    added = added.resolved(kind)
    params, synthetic_ratio, copy_paste_ratio = added.params, added.synthetic_ratio, added.copy_paste_ratio
    perturb_copies, synthetic_share = added.perturb_copies, added.synthetic_share
    if synthetic_share is not None:
        if synthetic_share != BY_COUNT and not 0.0 <= synthetic_share < 1.0:
            raise TrainingInputError("--synthetic-share", f"must be in [0, 1), got {synthetic_share}")
        if (synthetic_ratio <= 0 and copy_paste_ratio <= 0 and perturb_copies <= 0 and added.downscaled_copies <= 0
                and added.faded_copies <= 0):
            raise TrainingInputError("--synthetic-share", "there are no added positives to weigh: give --synthetic-ratio, "
                                     "--copy-paste-ratio, --perturb-copies, --downscaled-copies or --faded-copies")
    if added.realism_keep is not None and added.realism_keep < 1 and synthetic_ratio <= 0:
        raise TrainingInputError("--realism-keep", "there are no synthetic positives to filter: give --params (and a "
                                                   "--synthetic-ratio above 0)")
    if added.distractor_ratio < 0:
        raise TrainingInputError("--distractor-ratio", f"must be >= 0, got {added.distractor_ratio}")
    if added.distractor_style not in DISTRACTOR_STYLES:
        raise TrainingInputError("--distractor-style", f"must be one of {', '.join(DISTRACTOR_STYLES)}, "
                                                       f"got {added.distractor_style!r}")
    if added.distractor_style != "drawn" and added.distractor_ratio <= 0:
        raise TrainingInputError("--distractor-style", "there are no distractors to draw: give --distractor-ratio "
                                                       "above 0")
    if added.distractor_ratio > 0 and synthetic_ratio <= 0:
        raise TrainingInputError("--distractor-ratio", "distractors are drawn as the synthetic positives are, "
                                                       "and there are none: give --params and a --synthetic-ratio "
                                                       "above 0")
    if added.quantize and synthetic_ratio <= 0:
        raise TrainingInputError("--quantize", "there are no synthetic positives to round: give --params (and a "
                                               "--synthetic-ratio above 0)")
    if kind not in DETECTORS:
        raise TrainingInputError("--detector", f"unknown detector {kind!r}; choose from {list(DETECTORS)}")
    if frame_step < 1:
        raise TrainingInputError("--frame-step", f"must be >= 1, got {frame_step}")
    if synthetic_ratio < 0:
        raise TrainingInputError("--synthetic-ratio", f"must be >= 0, got {synthetic_ratio}")
    if synthetic_ratio > 0 and params is None:
        raise TrainingInputError("--synthetic-ratio", "synthetic positives need a fit: give --params FIT.json")
    for option, changed in (("--capture-sampling", added.capture_sampling != "seed"),
                            ("--background-sampling", added.background_sampling not in (None, "seed")),
                            ("--effects-off", bool(added.effects_off)), ("--dcnn-refit", added.refit is not None)):
        if changed and synthetic_ratio <= 0:
            raise TrainingInputError(option, "it changes the synthetic positives, and there are none: give "
                                             "--params FIT.json and a --synthetic-ratio above 0")
    if added.refit is not None and kind != "cnn":
        raise TrainingInputError("--dcnn-refit", f"the d_CNN refit follows the CNN being trained; {kind!r} has no network")
    if not all_frames and seedset is None and (seed_count is None or seed_count < 1):
        raise TrainingInputError("--seed-counts", f"must be >= 1, got {seed_count}")
    if perturb_copies < 0:
        raise TrainingInputError("--perturb-copies", f"must be >= 0, got {perturb_copies}")
    for option, copies, what in (("--downscaled-copies", added.downscaled_copies, "shrinks the seeds' frames"),
                                 ("--faded-copies", added.faded_copies, "fades the seeds toward their backgrounds")):
        if copies < 0:
            raise TrainingInputError(option, f"must be >= 0, got {copies}")
        if copies and all_frames and seedset is None:
            raise TrainingInputError(option, f"{what}: give --seed-counts or --seed-set, not --all-frames")
    if added.faded_contrast is not None:
        from synthaug.detectors.training_sets import _check_contrast

        if added.faded_copies <= 0:
            raise TrainingInputError("--faded-contrast", "there are no faded copies to draw it for: give --faded-copies")
        try:
            _check_contrast(added.faded_contrast)
        except (ValueError, TypeError) as e:
            raise TrainingInputError("--faded-contrast", str(e)) from None
    if copy_paste_ratio < 0:
        raise TrainingInputError("--copy-paste-ratio", f"must be >= 0, got {copy_paste_ratio}")
    if copy_paste_ratio > 0 and params is None:
        raise TrainingInputError("--copy-paste-ratio", "copy-paste cuts objects with their fitted silhouettes: give "
                                                       "--params FIT.json")
    if params is not None and not callable(params) and not Path(params).is_file():
        raise TrainingInputError("--params", f"file not found: {params}")
    if seedset is not None and not (Path(seedset) / "seedset.json").is_file():
        raise TrainingInputError("--seed-set", f"not a seed set folder (no seedset.json): {seedset}")


def _check_against_split(vs: VideoSet, sp: Mapping[str, Any], class_name: str, *, params: Any, all_frames: bool,
                         seedset: str | Path | None, seed_count: int | None) -> None:
    """The arguments against the videos found: a fit needs a seed set, the seeds asked must exist."""
    if params is not None and all_frames and seedset is None:
        raise TrainingInputError("--params", "synthetic positives need the seed set the fit was made on: use --seed-counts N "
                                             "(or --seed-set DIR), not --all-frames")
    if not all_frames and seedset is None:
        available = _labelled_frames(vs.labels_dir, sp["train"])
        if seed_count > available:  # type: ignore[operator]
            raise TrainingInputError("--seed-counts", f"{seed_count} seeds asked but the {len(sp['train'])} training videos of "
                                                      f"{class_name!r} have only {available} labelled frames")


@dataclass
class _TrainingSet:
    """What :func:`train_from_videos` trains on, and how the positives were made (``info``: the metadata's)."""

    positives: Tensor
    negatives: Tensor
    hog_frames: list[Tensor]
    hog_boxes: list[Tensor]
    box_in_window: Any
    info: dict[str, Any]
    seedset: Any = None
    redraw_synthetic: Callable[[str | Path], Tensor] | None = None  # the synthetic positives again, from another fit
    synthetic_slice: tuple[int, int] = (0, 0)  # where they sit in ``positives``


def _given_work_dir(work_dir: str | Path | None, out: str | Path | None) -> Path | None:
    """The ingest folder of :func:`train_from_videos`: ``work_dir``, else ``<out>.work``; None without either."""
    if work_dir is not None:
        return Path(work_dir)
    return None if out is None else Path(str(out) + ".work")


def _seed_set(vs: VideoSet, sp: Mapping[str, Any], *, seedset: str | Path | None, seed_count: int | None,
              work_dir: str | Path | None, out: str | Path | None, ingest_seed: int, ingest_workers: int,
              negative_classes: Sequence[str], say: Callable[[str], None]) -> Any:
    """The given seed set, or ``seed_count`` seeds ingested from the training videos into ``work_dir``
    (default ``<out>.work``, a temporary folder without ``out``)."""
    from synthaug.data.seedset import SeedSet

    if seedset is not None:
        return SeedSet.load(seedset)
    work = _given_work_dir(work_dir, out)
    if work is None:
        import tempfile

        work = Path(tempfile.mkdtemp(prefix="synthaug_train_"))
    return _seed_set_by_ingest(vs, sp, int(seed_count), work, ingest_seed=ingest_seed,  # type: ignore[arg-type]
                               workers=ingest_workers, log=say, negative_classes=negative_classes)


def _seed_set_training_set(ss: Any, seedset: str | Path | None, *, extra_negatives: int, seed: int,
                           options: TrainOptions, ingest_seed: int) -> _TrainingSet:
    """A seed set's real patches, its negatives + object-free crops of its frames, HOG's mining frames."""
    from synthaug.detectors.base import box_in_window_from_boxes

    if seedset is not None:
        info = {"mode": "seedset", "seedset": str(seedset), "count": len(ss)}
    else:
        info = {"mode": "seeds", "count": len(ss), "seedset": str(ss.path), "ingest_seed": ingest_seed,
                "drawn_as": "synthaug ingest (select_spread over the training videos' candidates)"}
    pos = real_positives(ss)
    neg = negative_pool(ss, extra_negatives, seed=seed)
    hog_frames, hog_boxes = mining_frames(ss, options.hog_mining_frames)
    box_in_window = box_in_window_from_boxes(torch.as_tensor(np.asarray(ss.boxes), dtype=torch.float32),
                                             window=int(ss.patch_size), object_fraction=float(ss.object_fraction))
    return _TrainingSet(pos, neg, hog_frames, hog_boxes, box_in_window, info, ss)


def _all_frames_training_set(vs: VideoSet, sp: Mapping[str, Any], *, frame_step: int, seed: int) -> _TrainingSet:
    """Every ``frame_step``-th labelled frame of the training videos; crops of them + of the negative-class videos."""
    from synthaug.detectors.base import box_in_window_from_boxes

    d = frames_training_set(sp["train"], vs.videos_dir, vs.labels_dir, frame_step=frame_step, seed=seed)
    birds = bird_hard_negatives(sp["negative_train"], vs.videos_dir, vs.labels_dir)
    pos, neg = d["positives"], torch.cat([d["negatives"], birds])
    info = {"mode": "all_frames", "frame_step": frame_step, "count": int(pos.shape[0])}
    return _TrainingSet(pos, neg, d["mining_frames"], d["mining_boxes"], box_in_window_from_boxes(d["boxes"]), info)


def _add_perturbed(ts: _TrainingSet, copies: int, *, seed: int, say: Callable[[str], None]) -> dict[str, Any] | None:
    """``copies`` perturbed copies of every real positive added to ``ts`` (the paper's Table 1 baseline)."""
    if not copies:
        return None
    from synthaug.effects.perturb import with_perturbed_copies

    n_real = ts.positives.shape[0]
    ts.positives = with_perturbed_copies(ts.positives, copies, seed=seed + 3)
    info = {"copies": copies, "count": int(ts.positives.shape[0] - n_real)}
    say(f"perturbed: {info['count']} copies of the {n_real} real positives")
    return info


def _add_downscaled(ts: _TrainingSet, copies: int, options: TrainOptions, *, seed: int,
                    say: Callable[[str], None]) -> dict[str, Any] | None:
    """``copies`` smaller copies of every real seed (:func:`~synthaug.detectors.training_sets.downscaled_positives`),
    cut down to the largest magnification of the pyramid the detector is mined and scored with."""
    if not copies:
        return None
    from synthaug.detectors.training_sets import downscaled_positives

    max_scale = max(options.pyramid())
    patches, info = downscaled_positives(ts.seedset, copies, max_scale=max_scale, seed=seed + 5)
    ts.positives = torch.cat([ts.positives, patches])
    say(f"downscaled: {info['count']} copies of {info['seeds_used']} seeds, longest side {info['sides'][0]:g}-"
        f"{info['sides'][1]:g} px (median {info['side_median']}), windows down to x{max_scale:g}")
    return info


def _add_faded(ts: _TrainingSet, copies: int, *, seed: int, say: Callable[[str], None],
               contrast: tuple[float, float] | None = None) -> dict[str, Any] | None:
    """``copies`` fainter (or, with a negative ``contrast`` range, inverted) copies of every real seed
    (:func:`~synthaug.detectors.training_sets.faded_positives`)."""
    if not copies:
        return None
    from synthaug.detectors.training_sets import FADED_CONTRAST, faded_positives

    patches, info = faded_positives(ts.seedset, copies, seed=seed + 6,
                                    contrast=FADED_CONTRAST if contrast is None else tuple(contrast))
    ts.positives = torch.cat([ts.positives, patches])
    say(f"faded: {info['count']} copies, contrast x{info['contrast'][0]:g} to x{info['contrast'][1]:g} "
        f"(median {info['contrast_median']})")
    return info


def _add_from_fit(ts: _TrainingSet, added: AddedPositives, kind: str, *, seed: int,
                  say: Callable[[str], None]) -> dict[str, Any] | None:
    """Synthetic (and copy-paste) positives made from the fit ``added.params`` of the seed set, added to ``ts``
    (the effects ``kind``'s family leaves out when ``added.effects_off`` is None, and its way of drawing them where
    ``added`` leaves it at None: :meth:`AddedPositives.resolved`)."""
    added = added.resolved(kind)
    ss, params, pose_sampling = ts.seedset, added.params, added.pose_sampling
    synthetic_ratio, copy_paste_ratio = added.synthetic_ratio, added.copy_paste_ratio
    if callable(params):  # ss exists: a fit without a seed set was refused before
        params = params(Path(ss.path))
    if params is None:
        return None
    from synthaug.params import CaptureParams

    try:
        theta, _, fit_meta = CaptureParams.load_with_extra(params)
    except (ValueError, FileNotFoundError) as e:
        raise TrainingInputError("--params", str(e)) from None
    if theta.batch_size != len(ss):
        raise TrainingInputError("--params", f"{params} has {theta.batch_size} rows but the seed set has {len(ss)} seeds "
                                             f"({ts.info.get('seedset')}): a fit holds one row per seed of the seed set "
                                             f"it was made on")
    mesh = added.mesh or fit_meta.get("mesh") or "quadcopter"
    # the family's effects off for the synthetic positives only (copy-paste draws no effect)
    effects_off = () if added.effects_off is None and synthetic_ratio <= 0 else added.effects_off
    try:
        effects_off = resolve_effects_off(kind, effects_off, available=theta.effects)
    except ValueError as e:
        raise TrainingInputError("--effects-off", f"{params}: {e}") from None
    effects = [e for e in theta.effects if e not in effects_off] if effects_off else None
    n_syn = int(round(synthetic_ratio * len(ss)))
    background_sampling = resolve_background_sampling(kind, added.background_sampling, len(ss)) \
        if synthetic_ratio > 0 else "seed"  # the family's, for the synthetic positives only
    if background_sampling == "other" and len(ss) < 2:
        raise TrainingInputError("--background-sampling", f"other puts each synthetic object on another seed's "
                                                          f"background, and the seed set has {len(ss)} seed")
    where = ", on other seeds' backgrounds" if background_sampling == "other" else ""
    # the family's, for the synthetic positives only
    realism_keep = resolve_realism_keep(kind, added.realism_keep, len(ss)) if synthetic_ratio > 0 else 1.0
    # how the synthetic patches are drawn, shared by the positives and the distractors
    how = dict(pose_sampling=pose_sampling, object_box=added.object_box, object_box_share=added.object_box_share,
               capture_sampling=added.capture_sampling, effects=effects, quantize=added.quantize,
               background_sampling=background_sampling)
    if n_syn:
        def draw(fit: str | Path) -> Tensor:
            return synthetic_positives(ss, mesh, fit, n_syn, seed=seed + 2, shape_variation=added.shape_variation,
                                       realism_keep=realism_keep, realism_selection=added.realism_selection,
                                       realism_features=added.realism_features, **how)

        t0 = time.perf_counter()
        syn = draw(params)
        ts.synthetic_slice = (int(ts.positives.shape[0]), int(ts.positives.shape[0]) + n_syn)
        ts.redraw_synthetic = draw
        ts.positives = torch.cat([ts.positives, syn])
        say(f"synthetic: {n_syn} patches from {params}"
            f"{', without ' + ' and '.join(effects_off) if effects_off else ''}{quantize_name(added.quantize)}"
            f"{where}{f', the {realism_keep:.0%} least synthetic kept' if realism_keep < 1 else ''}"
            f"{' of each seed' if realism_keep < 1 and added.realism_selection == 'seed' else ''}"
            f"{' (critic in weak-learner features)' if realism_keep < 1 and added.realism_features != 'hog' else ''}"
            f" ({time.perf_counter() - t0:.0f}s)")
    info: dict[str, Any] = {"params": str(params), "mesh": str(mesh), "ratio": synthetic_ratio, "count": n_syn,
                            "pose_sampling": pose_sampling,
                            **({"object_box": added.object_box} if added.object_box is not None else {}),
                            **({"object_box_share": added.object_box_share} if added.object_box_share < 1 else {}),
                            **({"shape_variation": added.shape_variation} if added.shape_variation else {}),
                            **({"capture_sampling": added.capture_sampling} if added.capture_sampling != "seed" else {}),
                            **({"effects_off": list(effects_off)} if effects_off else {}),
                            **({"quantize": added.quantize} if added.quantize else {}),
                            **({"background_sampling": background_sampling} if background_sampling != "seed" else {}),
                            **({"realism_keep": realism_keep} if realism_keep < 1 else {}),
                            **({"realism_selection": added.realism_selection} if realism_keep < 1 else {}),
                            **({"realism_features": added.realism_features}
                               if realism_keep < 1 and added.realism_features != "hog" else {})}
    n_dist = int(round(added.distractor_ratio * len(ss))) if n_syn else 0
    if n_dist:
        t0 = time.perf_counter()
        ts.negatives = torch.cat([ts.negatives, distractor_negatives(ss, params, n_dist, seed=seed + 100,
                                                                     style=added.distractor_style, **how)])
        soft = " soft" if added.distractor_style == "soft" else ""
        say(f"distractors: {n_dist}{soft} rendered ellipsoids added to the negatives ({time.perf_counter() - t0:.0f}s)")
        info["distractors"] = {"ratio": added.distractor_ratio, "count": n_dist,
                               **({"style": added.distractor_style} if added.distractor_style != "drawn" else {})}
    n_cp = int(round(copy_paste_ratio * len(ss)))
    if n_cp:
        from synthaug.data.copypaste import copy_paste_positives

        t0 = time.perf_counter()
        ts.positives = torch.cat([ts.positives, copy_paste_positives(ss, params, n_cp, seed=seed + 4, mesh=mesh)])
        say(f"copy-paste: {n_cp} patches cut with the silhouettes of {params} ({time.perf_counter() - t0:.0f}s)")
        info["copy_paste"] = {"ratio": copy_paste_ratio, "count": n_cp}
    return info


BOX_CACHE_FORMAT = "synthaug.box_regressor_cache"
BOX_CACHE_VERSION = 1
"""Part of every cached box regressor's key: bump it when the box maps' fitting changes."""


def _box_cache_dir(work_dir: str | Path | None, out: str | Path | None) -> Path | None:
    """Where fitted box regressors are kept between trainings: ``<work>/box_regressors`` of the ingest folder
    (:func:`_given_work_dir`); None when neither ``work_dir`` nor ``out`` is given."""
    work = _given_work_dir(work_dir, out)
    return None if work is None else work / "box_regressors"


def box_regressor_key(vs: VideoSet, videos: Sequence[str], options: TrainOptions, aspect: float, seed: int) -> str:
    """The cache key of a box regressor: everything its fit reads — the training videos (name, size and SHA-256 of
    each video file, not its time stamp, so a copied data folder keeps the cache; the bytes of its label file), the
    box model, the frame stride, the window's aspect, the seed (its jitter and initialisation) and :data:`BOX_CACHE_VERSION`. The detector, its
    positives and the mining do not enter: the box map is fitted on the labelled boxes alone, before them."""
    files = []
    for stem in sorted(videos):
        video = find_video(vs.videos_dir, stem)
        label = Path(vs.labels_dir) / f"{stem}.json"
        files.append([stem, None if video is None else [video.name, file_fingerprint(video)],
                      sha256_file(label) if label.is_file() else None])
    ident = {"what": "box_regressor", "version": BOX_CACHE_VERSION, "model": options.box_model,
             "stride": int(options.box_stride), "aspect": round(float(aspect), 9), "seed": int(seed), "videos": files}
    return digest(ident, length=24)


def _box_regressor(vs: VideoSet, sp: Mapping[str, Any], options: TrainOptions, box_in_window: Any, *, seed: int,
                   say: Callable[[str], None], cache_dir: Path | None = None) -> tuple[Any, dict[str, Any] | None]:
    """The box regressor fitted on the training videos (``options.box_regression``), and its metadata.

    With ``cache_dir``, a regressor fitted earlier from the same inputs (:func:`box_regressor_key`) is read back
    instead of fitted again (the ensemble's CNN map costs minutes); a new fit is written there atomically. Two
    trainings needing the same regressor at once share its lock: one fits it, the other waits and reads it back."""
    if not (options.box_regression and sp["train"]):
        return None, None
    aspect = float(box_in_window[2]) / float(box_in_window[3])
    if cache_dir is None:
        return _fit_box_regressor(vs, sp, options, aspect, seed=seed, say=say)
    path = cache_dir / f"{options.box_model}_{box_regressor_key(vs, sp['train'], options, aspect, seed)}.pt"
    with exclusive_lock(path.with_name(f".{path.name}.lock")):  # two trainings needing it: one fits, one waits
        cached = _cached_box_regressor(path, options, say) if path.is_file() else None
        if cached is not None:
            return cached
        regressor, box_info = _fit_box_regressor(vs, sp, options, aspect, seed=seed, say=say)
        import io

        buf = io.BytesIO()
        torch.save({"format": BOX_CACHE_FORMAT, "version": BOX_CACHE_VERSION, "state": regressor.state_dict(),
                    "info": box_info}, buf)
        atomic_write_bytes(path, buf.getvalue())
    return regressor, box_info


def _cached_box_regressor(path: Path, options: TrainOptions,
                          say: Callable[[str], None]) -> tuple[Any, dict[str, Any]] | None:
    """The regressor stored at ``path`` and its metadata, or None when the file is damaged (then fitted again)."""
    from synthaug.detectors.box_cnn import regressor_from_state_dict

    t0 = time.perf_counter()
    try:
        saved = check_header(torch.load(path, map_location="cpu", weights_only=False), format=BOX_CACHE_FORMAT,
                             version=BOX_CACHE_VERSION, what="cached box regressor", source=path)
        regressor = regressor_from_state_dict(saved["state"])
    except Exception as e:  # a damaged file is fitted again and replaced
        say(f"box regression: cached {path} unreadable ({type(e).__name__}: {e}); fitting again")
        return None
    box_info = dict(saved["info"], cached=str(path), fit_seconds=saved["info"].get("seconds"),
                    seconds=round(time.perf_counter() - t0, 1))
    say(f"box regression ({options.box_model}): reused {path} (fitted in {box_info['fit_seconds']} s)")
    return regressor, box_info


def _fit_box_regressor(vs: VideoSet, sp: Mapping[str, Any], options: TrainOptions, aspect: float, *, seed: int,
                       say: Callable[[str], None]) -> tuple[Any, dict[str, Any]]:
    t0 = time.perf_counter()
    reg_src = VideoFrames(vs.videos_dir, vs.labels_dir, positive=sp["train"], stride=options.box_stride)
    if options.box_model == "ensemble":
        from synthaug.detectors.box_cnn import EnsembleBoxRegressor

        (ridge, ridge_info), (cnn, cnn_info) = (_fit_box_map(m, reg_src, aspect, seed) for m in ("ridge", "cnn"))
        regressor: Any = EnsembleBoxRegressor([ridge, cnn])
        box_info = {"model": "ensemble", "videos": ridge_info.get("videos"), "parts": [ridge_info, cnn_info],
                    "seconds": round(time.perf_counter() - t0, 1)}
        say(f"box regression (ensemble of ridge {ridge.ridge:g} and cnn): {ridge_info['samples']} + "
            f"{cnn_info['samples']} jittered boxes ({box_info['seconds']:.0f}s)")
        return regressor, box_info
    regressor, box_info = _fit_box_map(options.box_model, reg_src, aspect, seed)
    box_info["seconds"] = round(time.perf_counter() - t0, 1)
    if options.box_model == "cnn":
        say(f"box regression (cnn): {box_info['samples']} jittered boxes of {box_info['videos']} training videos, "
            + (f"held-out MSE {min(box_info['held_out_mse']):.4f} " if box_info["held_out_mse"] else "no held-out video ")
            + f"(epoch {box_info['epoch_kept']}) ({box_info['seconds']:.0f}s)")
    else:
        say(f"box regression: {box_info['samples']} jittered boxes of {box_info['videos']} training videos, ridge "
            f"{regressor.ridge:g} by grouped CV ({box_info['seconds']:.0f}s)")
    return regressor, box_info


def _fit_box_map(model: str, frames: Any, aspect: float, seed: int) -> tuple[Any, dict[str, Any]]:
    """One box map (``"ridge"`` or ``"cnn"``) fitted on ``frames``, and its metadata (``model`` added; the ridge's
    strength too)."""
    if model == "cnn":
        from synthaug.detectors.box_cnn import CNNBoxRegressor

        reg: Any = CNNBoxRegressor.fit(frames, aspect=aspect, seed=seed)
        return reg, dict(reg.meta or {}, model="cnn")
    from synthaug.detectors.boxes import BoxRegressor

    reg = BoxRegressor.fit(frames, aspect=aspect, seed=seed)
    return reg, dict(reg.meta or {}, model="ridge", ridge=reg.ridge)


def share_weights(n_real: int, n_all: int, share: float | None) -> Tensor | None:
    """Per-positive weights giving the ``n_all - n_real`` added positives (after the real ones) ``share`` of the
    total weight and the real ones the rest (each group shared equally); None when ``share`` is None or nothing
    was added.

    Example:
        >>> share_weights(2, 6, 0.5).tolist()  # 2 real, 4 added: half the weight each
        [1.5, 1.5, 0.75, 0.75, 0.75, 0.75]
    """
    if share is None or n_all <= n_real:
        return None
    added = n_all - n_real
    w = torch.full((n_all,), (1.0 - share) * n_all / n_real, dtype=torch.float64)
    w[n_real:] = share * n_all / added
    return w


def _refit_refresh(ts: _TrainingSet, added: AddedPositives, synthetic_info: dict[str, Any] | None,
                   say: Callable[[str], None]) -> Callable[[Any, int], Tensor]:
    """The mining rounds' ``refresh_positives`` of the d_CNN refit: ``added.refit`` on round r's detector, then the
    synthetic positives redrawn from its fit into their slice of the positives (recorded in ``synthetic_info``)."""
    if ts.redraw_synthetic is None or synthetic_info is None:
        raise TrainingInputError("--dcnn-refit", "it refits the synthetic positives, and there are none: give --params "
                                                 "FIT.json and a --synthetic-ratio above 0")
    refits = synthetic_info.setdefault("refits", [])
    lo, hi = ts.synthetic_slice

    def refresh(det: Any, r: int) -> Tensor:
        t0 = time.perf_counter()
        fit = Path(added.refit(Path(synthetic_info["params"]), Path(ts.seedset.path), det, r))  # type: ignore[misc]
        t_fit = time.perf_counter() - t0
        positives = ts.positives.clone()
        positives[lo:hi] = ts.redraw_synthetic(fit).to(positives.dtype)  # type: ignore[misc]
        ts.positives = positives
        refits.append({"after_round": r, "params": str(fit), "fit_s": round(t_fit, 1)})
        say(f"d_CNN refit after round {r}: {fit} ({t_fit:.0f}s fit, {time.perf_counter() - t0 - t_fit:.0f}s draw)")
        return positives

    return refresh


def _mine_and_train(kind: str, ts: _TrainingSet, vs: VideoSet, sp: Mapping[str, Any], options: TrainOptions, *,
                    seed: int, regressor: Any, say: Callable[[str], None], positive_weights: Tensor | None = None,
                    real_positives: int | None = None, refresh_positives: Callable[[Any, int], Tensor] | None = None) -> Any:
    """:func:`~synthaug.detectors.training.train_with_mining` on ``ts``, mining every ``options.mining_stride``-th
    frame of the training videos (+ negative-class videos), stopped on the validation videos."""
    mine_src = VideoFrames(vs.videos_dir, vs.labels_dir, positive=sp["train"], negative=sp["negative_train"],
                           stride=options.mining_stride)
    val_src = VideoFrames(vs.videos_dir, vs.labels_dir, positive=sp["val"], stride=options.val_stride, null_frames=True) \
        if sp["val"] else None
    return train_with_mining(kind, ts.positives, ts.negatives, seed, box_in_window=ts.box_in_window,
                             mining_frames=ts.hog_frames, mining_boxes=ts.hog_boxes, options=options,
                             mining_source=mine_src if options.mining_rounds else None, val_frames=val_src, log=say,
                             box_regressor=regressor, positive_weights=positive_weights, real_positives=real_positives,
                             refresh_positives=refresh_positives)


def _metadata(kind: str, class_name: str, seed: int, videos_dir: str | Path, labels_dir: str | Path,
              sp: Mapping[str, Any], ts: _TrainingSet, res: Any, *, options: TrainOptions,
              synthetic_info: dict[str, Any] | None, perturb_info: dict[str, Any] | None,
              downscaled_info: dict[str, Any] | None, faded_info: dict[str, Any] | None, box_info: dict[str, Any] | None, seconds: dict[str, float],
              command: Any, out: str | Path | None) -> dict[str, Any]:
    """The metadata :func:`train_from_videos` returns and writes beside the checkpoint."""
    import synthaug

    meta = {
        "format": METADATA_FORMAT, "version": METADATA_VERSION, "synthaug_version": synthaug.__version__,
        "detector": kind, "class": class_name, "seed": seed,
        "videos_dir": str(Path(videos_dir).resolve()), "labels_dir": str(Path(labels_dir).resolve()),
        "split": sp, "positives": ts.info, "synthetic": synthetic_info, "perturbed": perturb_info,
        "downscaled": downscaled_info, "faded": faded_info,
        "negatives": {"initial": int(ts.negatives.shape[0]), "final": int(res.negatives.shape[0]),
                      "initial_source": ("seed set negatives + object-free crops of the seed frames"
                                         if ts.seedset is not None
                                         else "object-free crops of the training videos + look-alike crops of "
                                              "negative-class videos")},
        "box_in_window": [float(v) for v in ts.box_in_window],
        "box_regression": box_info,
        "options": asdict(options.for_family(kind)), "mining": res.log,
        "seconds": seconds,
        "command": command,
        "checkpoint": None if out is None else str(out),
    }
    if not sp["val"]:
        meta["warnings"] = ["no validation video: the mining ran every round without the stopping rule"]
    return meta


def _write_outputs(detector: Any, meta: Mapping[str, Any], out: Path, say: Callable[[str], None]) -> None:
    """The checkpoint at ``out`` and the metadata at ``out`` with suffix ``.json``."""
    from synthaug.detectors.base import save_detector
    from synthaug.params import atomic_write_text

    save_detector(detector, out)
    atomic_write_text(out.with_suffix(".json"), json.dumps(meta, indent=1, default=str) + "\n")
    say(f"wrote {out} and {out.with_suffix('.json')}")
