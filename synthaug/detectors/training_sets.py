"""The positive and negative patch sets detectors are trained on.

Positives: a seed set's real patches (:func:`real_positives`), with perturbed
copies (:func:`perturbed_positives`, the paper's Table 1 baseline), copies shown
smaller, as a farther object (:func:`downscaled_positives`), copies with the
object's contrast against its own background lowered (:func:`faded_positives`), synthetic
patches generated from a capture-parameter fit (:func:`synthetic_positives`), or
every labelled frame of some videos (:func:`frames_training_set`). Negatives: the
seed set's plus object-free crops of its seed frames (:func:`negative_pool`),
rendered distractors (:func:`distractor_negatives`: blobs drawn as the synthetic
positives are, the object swapped for an ellipsoid), look-alike crops of
negative-class videos (:func:`bird_hard_negatives`), and the seed frames HOG
mines on its own (:func:`mining_frames`). All patches are float ``(N, 1, P, P)``
in [0, 1].
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
import torch
from torch import Tensor

from synthaug.data.video import find_video

__all__ = [
    "real_positives",
    "perturbed_positives",
    "downscaled_positives",
    "faded_positives",
    "check_realism_keep",
    "synthetic_positives",
    "DISTRACTOR_AXES",
    "distractor_meshes",
    "DISTRACTOR_STYLES",
    "SOFT_DISTRACTOR_CONTRAST",
    "SOFT_DISTRACTOR_BLUR_PX",
    "soften",
    "distractor_negatives",
    "negative_pool",
    "mining_frames",
    "frames_training_set",
    "bird_hard_negatives",
]


def _as_float_patches(x: Any) -> Tensor:
    t = torch.as_tensor(np.asarray(x)) if not isinstance(x, Tensor) else x
    if t.dtype == torch.uint8:
        t = t.float() / 255.0
    if t.dim() == 3:
        t = t[:, None]
    return t.float().contiguous()


def real_positives(seedset: Any) -> Tensor:
    """The seed set's real object patches as float ``(N, 1, P, P)`` in [0, 1]."""
    return _as_float_patches(seedset.patches)


def perturbed_positives(seedset: Any, copies: int, *, seed: int = 0) -> Tensor:
    """Real patches plus ``copies`` perturbed versions of each (the paper's Table 1 baseline,
    :func:`~synthaug.effects.perturb.perturb_patches`)."""
    from synthaug.effects.perturb import with_perturbed_copies

    return with_perturbed_copies(real_positives(seedset), copies, seed=seed)


DOWNSCALED_SIDES: tuple[float, float] = (16.0, 24.0)
"""Longest sides (px) the copies of :func:`downscaled_positives` are drawn between by default: the small drones of
the halmstad test split (28 % of its boxes are under 24 px, none under 14; the training split has 8 % under 24)."""


def downscaled_positives(
    seedset: Any,
    copies: int,
    *,
    sides: tuple[float, float] = DOWNSCALED_SIDES,
    max_scale: float | None = None,
    seed: int = 0,
) -> tuple[Tensor, dict[str, Any]]:
    """``copies`` copies of every real seed, each shown as a smaller (farther) object, cut the way the detector sees it.

    Each copy shrinks the seed's whole frame (``cv2.INTER_AREA``, the pixel-area average of a camera that sees the
    object from farther) by a factor that brings the box's longest side ``L`` to ``s``, drawn log-uniform in
    ``[sides[0], min(sides[1], L)]``, and cuts a window around the shrunk box's centre (moved by a random sub-pixel
    offset, so copies differ in sampling phase) of side ``max(s / object_fraction, P / max_scale)``: the seeds' scale
    normalisation down to the largest magnification of the detector's pyramid, below which the object fills less of
    the window, as it does when a detector scans such a frame. Seeds whose longest side is under ``sides[0]`` give no
    copy.

    Args:
        seedset: a :class:`~synthaug.data.seedset.SeedSet` (its frames, boxes, patch size and object fraction).
        copies: copies per eligible seed (0: none).
        sides: ``(low, high)`` longest sides in px, ``0 < low <= high``.
        max_scale: the detector pyramid's largest resize factor (None: no limit, every copy scale-normalised like
            the seeds).
        seed: seeds the draws (:class:`numpy.random.Generator`).

    Returns:
        ``(patches, info)``: float ``(N, 1, P, P)`` in [0, 1] and ``{"copies", "count", "sides", "max_scale",
        "seeds_used", "side_median"}``.

    Example:
        >>> from synthaug.data.seedset import SeedSet  # doctest: +SKIP
        >>> patches, info = downscaled_positives(SeedSet("seeds/"), 2, max_scale=1.25)  # doctest: +SKIP
    """
    import cv2

    from synthaug.data.seedset import crop_patch

    lo, hi = (float(v) for v in sides)
    if not (0 < lo <= hi and np.isfinite(hi)):
        raise ValueError(f"sides must satisfy 0 < low <= high, got {tuple(sides)}")
    if copies < 0:
        raise ValueError(f"copies must be >= 0, got {copies}")
    if max_scale is not None and not (np.isfinite(max_scale) and max_scale > 0):
        raise ValueError(f"max_scale must be positive, got {max_scale}")
    p, frac = int(seedset.patches.shape[-1]), float(seedset.object_fraction)
    rng = np.random.default_rng(seed)
    out, drawn, used = [], [], 0
    for i in range(len(seedset) if copies else 0):
        box = np.asarray(seedset.boxes[i], np.float64).reshape(-1, 4)[0]
        longest = float(max(box[2], box[3]))
        if longest < lo:
            continue
        used += 1
        frame = seedset.frame(i)
        h, w = frame.shape[:2]
        for _ in range(copies):
            s = float(np.exp(rng.uniform(np.log(lo), np.log(min(hi, longest)))))
            f = s / longest
            size = (max(1, int(round(w * f))), max(1, int(round(h * f))))
            small = cv2.resize(frame, size, interpolation=cv2.INTER_AREA)
            fx, fy = size[0] / w, size[1] / h
            cx = (box[0] + box[2] / 2) * fx + rng.uniform(-0.5, 0.5)
            cy = (box[1] + box[3] / 2) * fy + rng.uniform(-0.5, 0.5)
            side = s / frac if max_scale is None else max(s / frac, p / float(max_scale))
            patch, _ = crop_patch(small, crop=(cx, cy, side), patch_size=p)
            out.append(patch)
            drawn.append(s)
    info = {"copies": int(copies), "count": len(out), "sides": [lo, hi], "max_scale": max_scale, "seeds_used": used,
            "side_median": round(float(np.median(drawn)), 2) if drawn else None}
    if not out:
        return torch.zeros(0, 1, p, p), info
    return _as_float_patches(np.stack(out)), info


FADED_CONTRAST: tuple[float, float] = (0.3, 0.9)
"""Contrast factors :func:`faded_positives` draws between by default (log-uniform): on the halmstad drones, the test
split's objects stand 0.4x (under 24 px) and 0.33x (24-48 px) as deep below their surroundings as the training
split's (median darkest-decile depth 2.0 vs 5.0 and 1.0 vs 3.0 gray levels,
results/learning_curve/drone_downscaled/contrast.py). That measure reads only darkening: two thirds of the test
split's drones are *brighter* than the sky (results/learning_curve/label_convention/README.md), which it counts as
faint; :data:`INVERTED_CONTRAST` addresses those."""


INVERTED_CONTRAST: tuple[float, float] = (-1.0, -0.5)
"""A negative :func:`faded_positives` range: copies with the object's contrast against its background *inverted* (a
dark drone shown bright against the same sky). On the halmstad drones 17-19 % of the training seeds' objects are
brighter than their background, 67 % of the test split's (results/learning_curve/label_convention/README.md)."""


def _check_contrast(contrast: Sequence[float]) -> tuple[float, float]:
    """``(low, high)`` of one sign: ``0 < low <= high <= 1`` (fainter) or ``-1 <= low <= high < 0`` (inverted)."""
    lo, hi = (float(v) for v in contrast)
    if not (0 < lo <= hi <= 1 or -1 <= lo <= hi < 0):
        raise ValueError(f"contrast must satisfy 0 < low <= high <= 1 (fainter) or -1 <= low <= high < 0 (inverted), "
                         f"got {tuple(contrast)}")
    return lo, hi


def box_mask(box: Sequence[float], crop: Sequence[float], patch_size: int, *, feather: float = 1.0) -> np.ndarray:
    """The object box's footprint in a seed patch: float ``(P, P)`` in [0, 1].

    Each patch pixel holds the fraction of its area the box ``(x, y, w, h)`` covers once mapped into the patch the
    way :func:`~synthaug.data.seedset.crop_patch` cuts ``crop = [c_x, c_y, side]`` (frame x maps to
    ``(x - c_x) P / side + P / 2``); ``feather > 0`` then smooths it with a Gaussian of that sigma in patch px.

    Example:
        >>> box_mask((10, 10, 20, 20), (20, 20, 40), 4, feather=0).tolist()
        [[0.0, 0.0, 0.0, 0.0], [0.0, 1.0, 1.0, 0.0], [0.0, 1.0, 1.0, 0.0], [0.0, 0.0, 0.0, 0.0]]
    """
    x, y, w, h = (float(v) for v in np.asarray(box, np.float64).reshape(-1)[:4])
    cx, cy, side = (float(v) for v in crop)
    s = patch_size / side
    edges = np.arange(patch_size + 1, dtype=np.float64)

    def cover(start: float, length: float, centre: float) -> np.ndarray:
        """The share of each patch column (row) inside ``[start, start + length)`` of the frame."""
        lo, hi = s * (start - centre) + patch_size / 2, s * (start + length - centre) + patch_size / 2
        return np.clip(np.minimum(edges[1:], hi) - np.maximum(edges[:-1], lo), 0.0, 1.0)

    m = cover(y, h, cy)[:, None] * cover(x, w, cx)[None, :]
    if feather > 0:
        from scipy.ndimage import gaussian_filter

        m = gaussian_filter(m, feather, mode="constant")
    return m


def faded_positives(
    seedset: Any,
    copies: int,
    *,
    contrast: tuple[float, float] = FADED_CONTRAST,
    seed: int = 0,
) -> tuple[Tensor, dict[str, Any]]:
    """``copies`` copies of every real seed with the object fainter against its own background (or inverted).

    Inside the object's box (:func:`box_mask`, feathered by 1 px) each copy moves the patch toward the seed's
    background patch (the same crop of the object-free background frame): ``I' = I - (1 - c) m (I - B)``, so the
    object's difference from its background is scaled by ``c``, drawn log-uniform in ``contrast``; outside the box
    the patch is left as it was. The real-data counterpart of a lowered diffuse weight: the same object seen against
    a brighter sky, through haze, or by a camera with less contrast. A negative range (``|c|`` log-uniform, e.g.
    :data:`INVERTED_CONTRAST`) inverts the object's contrast: a dark object shown brighter than its background.

    Args:
        seedset: a :class:`~synthaug.data.seedset.SeedSet` (its patches, backgrounds, boxes and crops).
        copies: copies per seed (0: none).
        contrast: ``(low, high)`` contrast factors of one sign, ``0 < low <= high <= 1`` or ``-1 <= low <= high < 0``.
        seed: seeds the draws (:class:`numpy.random.Generator`).

    Returns:
        ``(patches, info)``: float ``(N, 1, P, P)`` in [0, 1] and ``{"copies", "count", "contrast",
        "contrast_median"}``.

    Example:
        >>> from synthaug.data.seedset import SeedSet  # doctest: +SKIP
        >>> patches, info = faded_positives(SeedSet("seeds/"), 1)  # doctest: +SKIP
    """
    lo, hi = _check_contrast(contrast)
    sign = 1.0 if lo > 0 else -1.0
    a, b = sorted((abs(lo), abs(hi)))
    if copies < 0:
        raise ValueError(f"copies must be >= 0, got {copies}")
    p = int(seedset.patches.shape[-1])
    rng = np.random.default_rng(seed)
    out, drawn = [], []
    for i in range(len(seedset) if copies else 0):
        img = np.asarray(seedset.patches[i], np.float64) / 255.0
        bg = np.asarray(seedset.backgrounds[i], np.float64) / 255.0
        m = box_mask(seedset.boxes[i], seedset.crops[i], p)
        for _ in range(copies):
            c = sign * float(np.exp(rng.uniform(np.log(a), np.log(b))))
            out.append(img - (1.0 - c) * m * (img - bg))
            drawn.append(c)
    info = {"copies": int(copies), "count": len(out), "contrast": [lo, hi],
            "contrast_median": round(float(np.median(drawn)), 3) if drawn else None}
    if not out:
        return torch.zeros(0, 1, p, p), info
    return _as_float_patches(np.clip(np.stack(out), 0.0, 1.0).astype(np.float32)), info


def check_realism_keep(realism_keep: Any) -> float:
    """``realism_keep`` (:func:`synthetic_positives`) as a float: a fraction in (0, 1], else ``ValueError``.

    >>> check_realism_keep(1), check_realism_keep(0.25)
    (1.0, 0.25)
    """
    if isinstance(realism_keep, bool) or not isinstance(realism_keep, (int, float)) or not 0 < realism_keep <= 1:
        raise ValueError(f"realism_keep must be a fraction in (0, 1], got {realism_keep!r}")
    return float(realism_keep)


QUANTIZE: tuple[bool | str, ...] = (False, True, "native_scale")
"""How :func:`synthetic_positives` rounds its draws to the 256 levels of 8 bits: False (the paper: the renderer's
continuous values), True (every draw, as a camera delivers its frames) or ``"native_scale"`` (the draws of the seeds
whose object the detector's pyramid sees at about its own size, :func:`native_scale_seeds`; the others in float)."""

NATIVE_SCALE_MAX: float = 1 / math.sqrt(0.8)
"""``quantize="native_scale"`` rounds the seeds whose crop side is at most this many patch sides: the geometric
midpoint of the pyramid levels 1.0 and 0.8 (the project's pyramids step by 0.8), so a seed is rounded where the level
nearest to its object's scale is 1.0 or above — where a detector sees its real object as it was stored, on the
8-bit lattice — and left in float where the pyramid shrinks it (a resized level is off the lattice)."""


def check_quantize(quantize: Any) -> bool | str:
    """``quantize`` (:func:`synthetic_positives`) checked: one of :data:`QUANTIZE`, else ``ValueError``.

    >>> check_quantize(True), check_quantize("native_scale")
    (True, 'native_scale')
    """
    if isinstance(quantize, (bool, np.bool_)):
        return bool(quantize)
    if isinstance(quantize, str) and quantize in QUANTIZE:
        return quantize
    raise ValueError(f"quantize must be one of {QUANTIZE}, got {quantize!r}")


def quantize_name(quantize: bool | str) -> str:
    """How ``quantize`` reads in a cell's or a training set's name (``""`` where nothing is rounded).

    >>> quantize_name(False), quantize_name(True), quantize_name("native_scale")
    ('', ', 8-bit', ', 8-bit at native scale')
    """
    quantize = check_quantize(quantize)
    return ", 8-bit at native scale" if quantize == "native_scale" else ", 8-bit" if quantize else ""


def native_scale_seeds(seedset: Any) -> np.ndarray:
    """A bool per seed of ``seedset``: True where its crop side (``frame_scale``,
    :func:`~synthaug.data.seedset.seed_geometry`) is at most :data:`NATIVE_SCALE_MAX` patch sides, the seeds
    ``quantize="native_scale"`` rounds."""
    from synthaug.data.seedset import seed_geometry as seed_places

    return seed_places(seedset)["frame_scale"].numpy() <= NATIVE_SCALE_MAX + 1e-9


def synthetic_positives(
    seedset: Any,
    mesh: Any,
    fit_file: str | Path,
    count: int,
    *,
    seed: int = 0,
    effects: Sequence[str] | None = None,
    capture_sampling: str = "seed",
    batch: int = 2048,
    seed_geometry: Mapping[str, Any] | str | None = "auto",
    pose_sampling: str = "uniform",
    object_box: float | str | None = None,
    object_box_share: float = 1.0,
    shape_variation: float = 0.0,
    quantize: bool | str = False,
    background_sampling: str = "seed",
    realism_keep: float = 1.0,
    realism_selection: str = "seed",
    realism_features: str = "hog",
    return_seed_index: bool = False,
) -> Tensor | tuple[Tensor, np.ndarray]:
    """``count`` synthetic object patches generated from a capture-parameter fit.

    Each patch keeps one seed's fitted capture parameters and background and
    draws a random pose (:class:`~synthaug.data.synthetic.SyntheticObjectDataset`).

    Args:
        seedset: the seed set the fit was made on (backgrounds).
        mesh: mesh path or built-in name.
        fit_file: ``synthaug fit`` output.
        count: number of patches.
        seed: the dataset's base seed.
        effects: effects applied (None: all fitted ones); leaving one out is the ablation.
        capture_sampling: ``"seed"`` (the paper), ``"uniform"`` (Fig. 10) or ``"kde"``.
        batch: items built per ``__getitems__`` call.
        seed_geometry: each seed's place in its frame, for position-aware camera effects
            (:class:`~synthaug.data.synthetic.SyntheticObjectDataset`; default ``"auto"``: the seed
            set's); None: the patch is the frame.
        pose_sampling: ``"uniform"`` (the paper), ``"fitted"`` (around each seed's fitted pose), or either with
            ``"_at_seed"``: the object at its seed's fitted offset (:data:`~synthaug.data.poses.POSE_SAMPLING`; see
            :class:`~synthaug.data.synthetic.SyntheticObjectDataset`).
        object_box: None (the paper) or each object framed as ingest frames a labelled seed: its coverage box
            centred, its longest side this fraction of the patch (``"seed"``: the seed set's ``object_fraction``;
            see :class:`~synthaug.data.synthetic.SyntheticObjectDataset`).
        object_box_share: the fraction of the objects ``object_box`` frames (1: every one); the others keep the
            paper's framing (:class:`~synthaug.data.synthetic.SyntheticObjectDataset`'s ``object_box_share``).
        shape_variation: 0 (the paper: the mesh alone) or > 0: each patch's object one of
            :class:`~synthaug.data.synthetic.SyntheticObjectDataset`'s shapes around the mesh (its
            ``shape_variation``: stretched axes, parts scaled, within ± this fraction).
        quantize: True: round every patch to the 256 levels of 8 bits, as a camera delivers its frames and as the
            real positives and negatives are stored. False (the paper): the renderer's continuous values, so no
            synthetic patch has the exactly flat areas that real ones have. ``"native_scale"``: round the patches
            of the seeds the detector sees at about their own size (:func:`native_scale_seeds`), leave the others
            in float (:data:`QUANTIZE`).
        background_sampling: ``"seed"`` (the paper: each object on its own seed's background) or ``"other"`` (on
            another seed's; :class:`~synthaug.data.synthetic.SyntheticObjectDataset`'s ``background_sampling``).
        realism_keep: 1 (the paper: every drawn patch) or the fraction of drawn patches kept: ``ceil(count /
            realism_keep)`` are drawn (the first ``count`` of them are the patches drawn without the filter) and the
            ``count`` that a critic in HOG features finds least synthetic against the seed set's real patches are
            kept, in their drawn order (:func:`~synthaug.detectors.critic.least_synthetic`, cross-fitted by seed,
            seeded by ``seed``; after ``quantize``, so the critic sees what training sees). Needs >= 2 seeds.
        realism_selection: with ``realism_keep`` under 1, ``"seed"`` (the default: each seed keeps the same share of
            its own draws, the least synthetic of them), ``"set"`` (the ``count`` least synthetic of the whole draw)
            or ``"item"`` (the dataset's lazy form: a :class:`~synthaug.detectors.critic.RealismCritic` fitted on
            the first ``2 · 5 · seeds`` unfiltered draws, then each of the ``count`` patches the least synthetic of
            its ``round(1 / realism_keep)`` candidates, which keep its seed; before ``quantize``;
            :data:`~synthaug.detectors.critic.REALISM_SELECTION`).
        realism_features: the critic's features with ``realism_keep`` under 1 (``"seed"`` and ``"set"``
            selections): ``"hog"`` (the default) or ``"weak_learners"`` (AdaBoost's,
            :data:`~synthaug.detectors.critic.REALISM_FEATURES`).
        return_seed_index: also return each patch's ``seed_index`` (the seed whose capture parameters it was
            drawn with), so that a seed's real and synthetic patches can be held out together
            (:func:`synthaug.diagnose.gap.training_samples`).

    Returns:
        Float patches ``(count, 1, P, P)`` in [0, 1] (with ``quantize``: multiples of 1/255, those of the rounded
        seeds with ``"native_scale"``); with
        ``return_seed_index``, ``(patches, seed_index (count,) int64)``.
    """
    from synthaug.data.synthetic import SyntheticObjectDataset
    from synthaug.effects.camera_functional import quantize_levels

    if count < 0:
        raise ValueError(f"count must be >= 0, got {count}")
    from synthaug.detectors.critic import check_realism_features, check_realism_selection

    realism_keep = check_realism_keep(realism_keep)
    quantize = check_quantize(quantize)
    check_realism_selection(realism_selection)
    check_realism_features(realism_features, selection=realism_selection if realism_keep < 1 else None)
    drawn = count if realism_keep == 1 else int(math.ceil(count / realism_keep - 1e-9))
    p = int(seedset.patches.shape[-1])
    if count == 0:
        empty = torch.zeros(0, 1, p, p)
        return (empty, np.zeros(0, np.int64)) if return_seed_index else empty
    if drawn > count and len(seedset) < 2:
        raise ValueError(f"realism_keep < 1 needs a seed set of >= 2 seeds (the critic is cross-fitted by seed), "
                         f"got {len(seedset)}")
    lazy = drawn > count and realism_selection == "item"  # the dataset's critic picks each item among candidates
    ds = SyntheticObjectDataset(
        mesh, seedset, params=str(fit_file), length=count if lazy else drawn, patch_size=p, negative_fraction=0.0,
        effects=None if effects is None else list(effects), capture_sampling=capture_sampling, seed=seed,  # type: ignore[arg-type]
        seed_geometry=seed_geometry, pose_sampling=pose_sampling, object_box=object_box,  # type: ignore[arg-type]
        object_box_share=object_box_share,
        shape_variation=shape_variation, background_sampling=background_sampling,  # type: ignore[arg-type]
        realism_candidates=max(2, round(1 / realism_keep)),
    )
    if lazy:
        from synthaug.detectors.critic import RealismCritic

        ds.realism_critic = RealismCritic.from_dataset(ds, np.asarray(seedset.patches), seed=seed)
        drawn = count
    out, seed_index = [], []
    for start in range(0, drawn, batch):
        items = ds.__getitems__(list(range(start, min(drawn, start + batch))))
        out.append(torch.stack([img for img, _ in items]))
        seed_index += [int(t["seed_index"]) for _, t in items]
    patches = torch.cat(out).float().clamp(0, 1)
    groups = np.array(seed_index, dtype=np.int64)
    if quantize is True:
        patches = quantize_levels(patches)
    elif quantize == "native_scale":
        rounded = torch.from_numpy(native_scale_seeds(seedset)[groups])
        patches = torch.where(rounded[:, None, None, None], quantize_levels(patches), patches)
    if drawn > count:  # "seed" and "set": the count least synthetic of the larger draw
        from synthaug.detectors.critic import least_synthetic

        keep = least_synthetic(np.asarray(seedset.patches), patches, groups, count, seed=seed,
                               selection=realism_selection, features=realism_features)
        patches, groups = patches[torch.from_numpy(keep)], groups[keep]
    return (patches, groups) if return_seed_index else patches


DISTRACTOR_AXES: tuple[tuple[float, float, float], ...] = (
    (1.0, 1.0, 1.0), (1.0, 0.5, 0.5), (1.0, 0.3, 0.3), (1.0, 1.0, 0.35), (1.0, 1.0, 0.6), (1.0, 0.55, 0.3),
    (1.0, 0.75, 0.45), (1.0, 0.4, 0.2))
"""The distractors' shapes: ellipsoids by their axes (x, y, z; a sphere, cigars, discs, flattened cigars), each
normalised to a unit longest side as every mesh is (results/synthetic/adaboost_distractors/, stop 98)."""


def distractor_meshes() -> list[Any]:
    """One :class:`trimesh.Trimesh` ellipsoid per :data:`DISTRACTOR_AXES` entry (an icosphere of 642 vertices,
    stretched)."""
    import trimesh

    out = []
    for axes in DISTRACTOR_AXES:
        blob = trimesh.creation.icosphere(subdivisions=3)
        blob.apply_scale(axes)
        out.append(blob)
    return out


DISTRACTOR_STYLES: tuple[str, ...] = ("drawn", "soft")
"""How :func:`distractor_negatives` draws its blobs: ``"drawn"`` as the object is (its seed's capture parameters),
``"soft"`` faint and blurred like the cloud puffs AdaBoost takes for drones (stop 97)."""
SOFT_DISTRACTOR_CONTRAST: tuple[float, float] = (0.15, 0.5)
"""``|c|`` of a soft distractor, log-uniform: its difference from the background scaled by ``±c``."""
SOFT_DISTRACTOR_BLUR_PX: tuple[float, float] = (1.0, 3.0)
"""σ (px of the patch) of the Gaussian a soft distractor's difference from its background is blurred by, uniform."""


def soften(patches: Tensor, backgrounds: Tensor, *, rng: np.random.Generator,
           contrast: tuple[float, float] = SOFT_DISTRACTOR_CONTRAST,
           blur_px: tuple[float, float] = SOFT_DISTRACTOR_BLUR_PX) -> tuple[Tensor, dict[str, np.ndarray]]:
    """Each patch made a faint, soft version of itself against its background: ``B + c · (G_σ * (I - B))``.

    ``|c|`` is drawn log-uniform in ``contrast``, its sign + or - with equal odds (a dark blob also shown brighter than
    its background, as a cloud is), σ uniform in ``blur_px`` (``kornia.filters.gaussian_blur2d``, replicated border:
    ``I - B`` is 0 away from the object); the result is clipped to [0, 1].

    Args:
        patches: float ``(N, C, P, P)`` in [0, 1].
        backgrounds: float ``(N, C, P, P)``: each patch's background without its object.
        rng: the draws' generator.

    Returns:
        ``(patches, {"contrast": (N,), "sigma": (N,)})``.
    """
    from kornia.filters import gaussian_blur2d

    a, b = (float(v) for v in contrast)
    lo, hi = (float(v) for v in blur_px)
    if not (0 < a <= b <= 1):
        raise ValueError(f"contrast must be 0 < low <= high <= 1, got {contrast}")
    if not (0 < lo <= hi):
        raise ValueError(f"blur_px must be 0 < low <= high, got {blur_px}")
    if patches.shape != backgrounds.shape:
        raise ValueError(f"patches {tuple(patches.shape)} and backgrounds {tuple(backgrounds.shape)} differ")
    n = int(patches.shape[0])
    c = np.exp(rng.uniform(np.log(a), np.log(b), n)) * rng.choice((-1.0, 1.0), n)
    sigma = rng.uniform(lo, hi, n)
    if n == 0:
        return patches.clone(), {"contrast": c, "sigma": sigma}
    k = 2 * math.ceil(3 * hi) + 1
    sig = torch.as_tensor(np.stack([sigma, sigma], 1), dtype=patches.dtype)
    blurred = gaussian_blur2d(patches - backgrounds, (k, k), sig, border_type="replicate")
    out = backgrounds + torch.as_tensor(c, dtype=patches.dtype)[:, None, None, None] * blurred
    return out.clamp(0.0, 1.0), {"contrast": c, "sigma": sigma}


def distractor_negatives(seedset: Any, fit_file: str | Path, count: int, *, seed: int = 0, style: str = "drawn",
                         **draw: Any) -> Tensor:
    """``count`` rendered distractors: negatives drawn as :func:`synthetic_positives` draws its patches (each
    seed's fitted capture parameters and background, its poses and placement, ``draw``'s options) with an
    ellipsoid of :func:`distractor_meshes` in place of the object, split evenly over the shapes (the first ones
    take the remainder), the shape ``k`` drawn with the dataset seed ``seed + k``.

    Domain randomisation's flying distractors: where a detector learns "looks rendered" as the class cue, a
    rendered blob that is not the object tells it to look at the shape instead. ``draw`` may not ask for a
    realism critic or shape variation (a distractor is no object: neither applies).

    ``style`` (:data:`DISTRACTOR_STYLES`): ``"drawn"`` (the default) keeps each blob as its seed's capture draws it;
    ``"soft"`` makes each one faint and soft against its seed's background (:func:`soften`, its draws from
    ``numpy.random.default_rng(seed + k)`` for the shape ``k``; before the 8-bit rounding when ``draw`` asks for
    it): the look of a low-contrast cloud puff rather than of the object. ``"soft"`` needs each blob on its own
    seed's background (``background_sampling="seed"``).

    The distractors are rounded to 8 bits wherever ``draw``'s ``quantize`` is not False: every one of them with
    ``"native_scale"`` too (a blob is no object seen at a size; so the measured cells drew them,
    ``results/synthetic/rounding_parts/``).

    Returns:
        Float patches ``(count, 1, P, P)`` in [0, 1], the shapes in :data:`DISTRACTOR_AXES` order.
    """
    if count < 0:
        raise ValueError(f"count must be >= 0, got {count}")
    if style not in DISTRACTOR_STYLES:
        raise ValueError(f"style must be one of {DISTRACTOR_STYLES}, got {style!r}")
    draw = {**draw, "quantize": bool(check_quantize(draw.get("quantize", False)))}
    for key, off in (("realism_keep", 1.0), ("shape_variation", 0.0)):
        if draw.get(key, off) != off:
            raise ValueError(f"distractors are drawn without {key} (got {draw[key]!r})")
    if style == "soft" and draw.get("background_sampling", "seed") != "seed":
        raise ValueError("soft distractors are faded against their own seed's background: background_sampling "
                         f"must be 'seed', got {draw['background_sampling']!r}")
    meshes = distractor_meshes()
    per, extra = divmod(count, len(meshes))
    counts = [per + (k < extra) for k in range(len(meshes))]
    if style == "drawn":
        parts = [synthetic_positives(seedset, m, fit_file, c, seed=seed + k, **draw)  # the first one even when empty
                 for k, (m, c) in enumerate(zip(meshes, counts)) if c or k == 0]
        return torch.cat(parts)
    from synthaug.effects.camera_functional import quantize_levels

    backgrounds = _as_float_patches(seedset.backgrounds)
    parts = []
    for k, (m, c) in enumerate(zip(meshes, counts)):
        if not c and k:
            continue
        blobs, idx = synthetic_positives(seedset, m, fit_file, c, seed=seed + k, return_seed_index=True,
                                         **{**draw, "quantize": False})
        faint, _ = soften(blobs, backgrounds[torch.from_numpy(idx)], rng=np.random.default_rng(seed + k))
        parts.append(quantize_levels(faint) if draw.get("quantize") else faint)
    return torch.cat(parts)


def negative_pool(seedset: Any, extra: int = 3000, *, seed: int = 0) -> Tensor:
    """The seed set's negatives plus ``extra`` object-free crops of its seed frames.

    Crops use the seeds' crop sides (the same scale normalisation as the
    positives) and never touch the labelled box (grown by a margin).
    """
    from synthaug.data.negatives import sample_negatives

    neg = [np.asarray(seedset.negatives, np.uint8)]
    if extra > 0:
        n = len(seedset)
        frames = np.stack([seedset.frame(i) for i in range(n)])
        boxes = [np.asarray(seedset.boxes[i], np.float64) for i in range(n)]
        more, _ = sample_negatives(frames, boxes, extra, sides=[float(s) for s in seedset.crops[:, 2]],
                                   rng=np.random.default_rng(seed), patch_size=int(seedset.patches.shape[-1]))
        neg.append(more)
    return _as_float_patches(np.concatenate(neg))


def mining_frames(seedset: Any, limit: int = 40) -> tuple[list[Tensor], list[Tensor]]:
    """Up to ``limit`` seed frames (float ``(H, W)``) and their boxes, for HOG hard-negative mining."""
    n = min(limit, len(seedset))
    pick = np.unique(np.linspace(0, len(seedset) - 1, n).round().astype(int))
    frames = [torch.from_numpy(seedset.frame(int(i))).float() / 255.0 for i in pick]
    boxes = [torch.as_tensor(seedset.boxes[int(i)], dtype=torch.float32).reshape(1, 4) for i in pick]
    return frames, boxes


def frames_training_set(
    videos: Sequence[str],
    videos_dir: str | Path,
    labels_dir: str | Path,
    *,
    frame_step: int = 1,
    negatives_per_video: int = 60,
    mining_frames_per_video: int = 1,
    patch_size: int = 40,
    object_fraction: float = 0.7,
    seed: int = 0,
) -> dict[str, Any]:
    """Positives from every ``frame_step``-th labelled frame of the training videos (the "plenty of real data" reference).

    Args:
        videos: training video stems.
        videos_dir, labels_dir: the shared-format folders.
        frame_step: 1 = every labelled frame.
        negatives_per_video: object-free crops drawn per video (seed crop sides).
        mining_frames_per_video: frames kept (with their boxes) for HOG mining.
        patch_size, object_fraction: the seed sets' patch geometry.
        seed: seeds the negative sampling.

    Returns:
        ``{"positives": (P,1,S,S), "negatives": (N,1,S,S), "boxes": (P,4) frame boxes,
        "mining_frames": [...], "mining_boxes": [...]}``.
    """
    from synthaug.data.negatives import sample_negatives
    from synthaug.data.seedset import crop_geometry, crop_patch
    from synthaug.data.video import read_video_with_labels

    rng = np.random.default_rng(seed)
    videos_dir, labels_dir = Path(videos_dir), Path(labels_dir)
    pos, neg, boxes_all, mf, mb = [], [], [], [], []
    for stem in videos:
        video_file = find_video(videos_dir, stem)
        if video_file is None:
            raise ValueError(f"no video file for {stem!r} in {videos_dir}")
        frames, labels, _ = read_video_with_labels(video_file, labels_dir / f"{stem}.json")
        labelled = [i for i, b in enumerate(labels.boxes) if b is not None]
        sides = []
        for i in labelled[::frame_step]:
            box = np.asarray(labels.boxes[i], np.float64).reshape(-1, 4)[0]
            patch, _ = crop_patch(frames[i], box=box, patch_size=patch_size, object_fraction=object_fraction)
            pos.append(patch)
            boxes_all.append(box)
            sides.append(float(crop_geometry(box, patch_size=patch_size, object_fraction=object_fraction)[2]))
        if sides and negatives_per_video > 0:
            n, _ = sample_negatives(frames, labels.boxes, negatives_per_video, sides=sides, rng=rng, patch_size=patch_size)
            neg.append(n)
        for i in labelled[:: max(1, len(labelled) // max(mining_frames_per_video, 1))][:mining_frames_per_video]:
            mf.append(torch.from_numpy(frames[i]).float() / 255.0)
            mb.append(torch.as_tensor(labels.boxes[i], dtype=torch.float32).reshape(-1, 4))
    if not pos:
        raise ValueError(f"no labelled frame in videos {list(videos)[:5]}...")
    return {
        "positives": _as_float_patches(np.stack(pos)),
        "negatives": _as_float_patches(np.concatenate(neg)) if neg else torch.zeros(0, 1, patch_size, patch_size),
        "boxes": torch.as_tensor(np.stack(boxes_all), dtype=torch.float32),
        "mining_frames": mf,
        "mining_boxes": mb,
    }


def bird_hard_negatives(videos: Sequence[str], videos_dir: str | Path, labels_dir: str | Path, *, per_video: int = 16,
                        patch_size: int = 40, object_fraction: float = 0.7) -> Tensor:
    """Look-alike crops (:func:`synthaug.data.negatives.hard_negatives`) of negative-class videos, one video in memory at a time."""
    from synthaug.data.negatives import hard_negatives
    from synthaug.data.video import read_video_with_labels

    out = []
    for stem in videos:
        path = find_video(videos_dir, stem)
        if path is None:
            raise ValueError(f"no video file for {stem!r} in {videos_dir}")
        frames, labels, _ = read_video_with_labels(path, Path(labels_dir) / f"{stem}.json")
        p, _ = hard_negatives(frames, labels.boxes, per_video, patch_size=patch_size, object_fraction=object_fraction)
        out.append(p)
    if not out:
        return torch.zeros(0, 1, patch_size, patch_size)
    return _as_float_patches(np.concatenate(out))
