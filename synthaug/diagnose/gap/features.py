"""The features a detector family sees (HOG blocks, weak-learner responses, CNN activations), as
numpy arrays: :func:`feature_extractor` reuses the feature maps of :mod:`synthaug.distances`.
"""

from __future__ import annotations

import copy
import os
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
import torch
from torch import Tensor


FAMILIES = ("hog", "adaboost", "cnn")
"""The detector families whose feature spaces :func:`feature_extractor` knows."""

_CHUNK = 1024  # patches per feature-extraction batch


@dataclass
class FeatureExtractor:
    """A detector family's features of ``window x window`` grayscale patches.

    Call it on uint8 ``(N, P, P)`` patches (as :class:`~synthaug.data.seedset.SeedSet` stores them) or float
    ``(N, 1, P, P)`` in [0, 1]; it returns float64 ``(N, D)`` numpy features.

    Attributes:
        family: ``"hog"``, ``"adaboost"`` or ``"cnn"``.
        description: where the features come from (e.g. "random PatchCNN, seed 0").
        window: the patch side the features need.
        features: ``(B, 1, window, window)`` float tensor -> ``(B, D)`` tensor.
        names: one short name per feature (``D`` of them).
        layout: family-specific description of the feature order (HOG: the config; CNN: the layer shapes).
    """

    family: str
    description: str
    window: int
    features: Callable[[Tensor], Tensor]
    names: list[str]
    layout: dict[str, Any] = field(default_factory=dict)

    @property
    def n_features(self) -> int:
        return len(self.names)

    @torch.no_grad()
    def __call__(self, patches: Tensor | np.ndarray) -> np.ndarray:
        x = _float_patches(patches, self.window)
        if x.shape[0] == 0:
            return np.zeros((0, self.n_features))
        out = torch.cat([self.features(c) for c in x.split(_CHUNK)])
        return out.double().numpy()


def _float_patches(patches: Tensor | np.ndarray, window: int | None) -> Tensor:
    """uint8 (N, P, P) / (N, 1, P, P) or float in [0, 1] -> float32 (N, 1, P, P); the size is checked."""
    if isinstance(patches, np.ndarray):
        patches = torch.from_numpy(np.ascontiguousarray(patches))
    if not isinstance(patches, Tensor):
        raise ValueError(f"patches must be a torch.Tensor or numpy array, got {type(patches).__name__}")
    if patches.dim() == 3:
        patches = patches[:, None]
    if patches.dim() != 4 or patches.shape[1] != 1:
        raise ValueError(f"patches must be grayscale (N, P, P) or (N, 1, P, P), got shape {tuple(patches.shape)}")
    if window is not None and patches.shape[-2:] != (window, window):
        raise ValueError(f"these features need {window}x{window} patches, got {tuple(patches.shape[-2:])}")
    if patches.dtype == torch.uint8:
        return patches.float() / 255.0
    if not patches.dtype.is_floating_point:
        raise ValueError(f"patches must be uint8 or float in [0, 1], got dtype {patches.dtype}")
    return patches.float()


def hog_feature_layout(config: Any, window: int) -> np.ndarray:
    """Where each value of :func:`~synthaug.detectors.hog.hog` of a ``window``-px patch sits.

    Returns:
        int array ``(D, 5)``: ``(block_row, block_col, cell_row, cell_col, orientation)`` per feature, the
        descriptor's own order; the absolute cell is ``(block_row + cell_row, block_col + cell_col)``.

    Example:
        >>> from synthaug.detectors.hog import DEFAULT_HOG
        >>> lay = hog_feature_layout(DEFAULT_HOG, 40)
        >>> lay.shape, lay[9].tolist()
        ((576, 5), [0, 0, 0, 1, 0])
    """
    blocks = window // config.cell_size - config.block_size + 1
    config.descriptor_length(window, window)  # validates the size
    b, o = config.block_size, config.orientations
    grid = np.indices((blocks, blocks, b, b, o)).reshape(5, -1).T
    return grid.astype(np.int64)


def _hog_extractor(detector: Any, window: int) -> FeatureExtractor:
    from synthaug.detectors.hog import DEFAULT_HOG, HOGConfig
    from synthaug.detectors.hog_dpm import HOGDetector
    from synthaug.distances.basic import HOGDistance

    if detector is None:
        config, source = DEFAULT_HOG, "HOG descriptor (the detector's default settings)"
    elif isinstance(detector, HOGConfig):
        config, source = detector, "HOG descriptor (given settings)"
    elif isinstance(detector, HOGDetector):
        config, window, source = detector.config, detector.window, "HOG descriptor of the given HOG detector"
    else:
        raise ValueError(f"the hog family takes a HOGDetector, a HOGConfig or None, got {type(detector).__name__}")
    lay = hog_feature_layout(config, window)
    step = 180.0 / config.orientations
    names = [f"cell({br + cr},{bc + cc}) of block({br},{bc}) bin {o} ({(o + 0.5) * step:.0f} deg gradient)"
             for br, bc, cr, cc, o in lay]
    return FeatureExtractor("hog", source + f": {config}", window, HOGDistance(config).features, names,
                            {"config": config, "hog_layout": lay})


def _adaboost_extractor(detector: Any, window: int, reference: Tensor | None, seed: int,
                        n_learners: int) -> FeatureExtractor:
    from synthaug.distances.weak_learners import wl_learned, wl_random

    if detector is None:
        ref = None if reference is None else _float_patches(reference, window)
        dist = wl_random(n_learners=n_learners, window=window, seed=seed, reference=ref)
        source = (f"{n_learners} random Levi-Weiss weak learners (d_WL^R, seed {seed}"
                  + (", thresholds at real-patch energies)" if ref is not None else ")"))
    else:
        dist = wl_learned(detector=detector)  # AdaBoostDetector or WeakLearners; names a wrong type
        source = f"the {len(dist.learners)} weak learners of the given AdaBoost detector, response h_i * sqrt(alpha_i)"
    wl = dist.learners
    names = [f"wl{i} rect(y={r[0]},x={r[1]},h={r[2]},w={r[3]}) bin {int(o)}"
             for i, (r, o) in enumerate(zip(wl.rects.tolist(), wl.orientations))]
    return FeatureExtractor("adaboost", source, int(wl.window), dist.features, names,
                            {"rects": wl.rects.numpy(), "orientations": wl.orientations.numpy()})


def _cnn_extractor(detector: Any, seed: int) -> FeatureExtractor:
    from synthaug.detectors.cnn import CNNDetector, PatchCNN
    from synthaug.distances.cnn import CNNDistance

    if detector is None:
        net = PatchCNN(generator=torch.Generator().manual_seed(seed))
        source = (f"activations of layers 2..5 of an UNTRAINED PatchCNN (random weights, seed {seed}): a fixed "
                  "random feature map, not a detector's; pass a trained CNN for the detector's own view")
    elif isinstance(detector, (PatchCNN, CNNDetector)):
        net = detector.net if isinstance(detector, CNNDetector) else detector
        source = "activations of layers 2..5 of the given CNN (the d_CNN features, eq. 6)"
    else:
        raise ValueError(f"the cnn family takes a PatchCNN, a CNNDetector or None, got {type(detector).__name__}")
    # CNNDistance freezes the network it holds: give it a copy, the caller's network is left as it was
    dist = CNNDistance(copy.deepcopy(net).cpu(), first_layer=2)
    with torch.no_grad():
        acts = dist.net.layer_activations(torch.zeros(1, 1, net.window, net.window))[1:]
    shapes = [tuple(a.shape[1:]) for a in acts]
    names = [f"layer{n} ch{c} ({y},{x})" for n, s in zip(range(2, 6), shapes)
             for c, y, x in np.ndindex(*s)]
    return FeatureExtractor("cnn", source, net.window, dist.features, names,
                            {"layers": list(range(2, 6)), "shapes": shapes})


def feature_extractor(
    family: str,
    detector: Any = None,
    *,
    window: int = 40,
    reference: Tensor | np.ndarray | None = None,
    seed: int = 0,
    n_learners: int = 1000,
) -> FeatureExtractor:
    """The features a detector family sees, reusing the feature maps of :mod:`synthaug.distances`.

    Args:
        family: ``"hog"`` (the HOG descriptor, :class:`~synthaug.distances.basic.HOGDistance`),
            ``"adaboost"`` (weak-learner responses, :mod:`synthaug.distances.weak_learners`) or ``"cnn"``
            (activations of layers 2..5, :class:`~synthaug.distances.cnn.CNNDistance`).
        detector: the trained detector whose features to use, or a path to its checkpoint
            (``save_detector`` file; for ``cnn`` also a Lightning ``.ckpt``). ``hog``: a ``HOGDetector`` or a
            ``HOGConfig``; ``adaboost``: an ``AdaBoostDetector`` (its learners, weighted sqrt(α) as in d_WL^L)
            or ``WeakLearners``; ``cnn``: a ``PatchCNN`` or ``CNNDetector``. None: ``hog`` uses the default
            HOG settings; ``adaboost`` ``n_learners`` random learners (d_WL^R, drawn with ``seed``);
            ``cnn`` an *untrained* PatchCNN with weights drawn from ``seed`` — a fixed random feature map,
            said so in the extractor's ``description``.
        window: patch side (HOG; the other families take it from the detector).
        reference: real patches; with ``adaboost`` and no detector, each random learner's threshold is
            the energy of one of them (learners that split real data).
        seed: seeds the random learners / random network when no detector is given.
        n_learners: number of random weak learners.

    Returns:
        A :class:`FeatureExtractor`.

    Example:
        >>> fx = feature_extractor("hog")
        >>> fx(np.zeros((3, 40, 40), np.uint8)).shape, fx.names[0]
        ((3, 576), 'cell(0,0) of block(0,0) bin 0 (10 deg gradient)')
        >>> feature_extractor("cnn").n_features  # 16x8x8 + 32x3x3 + 64 + 1
        1377
    """
    if family not in FAMILIES:
        raise ValueError(f"unknown detector family {family!r}; families: {list(FAMILIES)}")
    if not isinstance(seed, int):
        raise ValueError(f"seed must be an int, got {seed!r}")
    if isinstance(detector, (str, os.PathLike)):
        if family == "cnn":
            from synthaug.detectors.cnn import load_patch_cnn

            detector = load_patch_cnn(detector)
        else:
            from synthaug.detectors.base import load_detector

            detector = load_detector(detector)
    if family == "hog":
        return _hog_extractor(detector, window)
    if family == "adaboost":
        if not isinstance(n_learners, int) or n_learners < 1:
            raise ValueError(f"n_learners must be an int >= 1, got {n_learners!r}")
        return _adaboost_extractor(detector, window, None if reference is None else _as_tensor(reference), seed,
                                   n_learners)
    return _cnn_extractor(detector, seed)


def _as_tensor(x: Tensor | np.ndarray) -> Tensor:
    return torch.from_numpy(np.ascontiguousarray(x)) if isinstance(x, np.ndarray) else x


def _features_pair(real: Any, syn: Any) -> tuple[np.ndarray, np.ndarray]:
    out = []
    for name, f in (("real_feats", real), ("syn_feats", syn)):
        a = f.detach().cpu().double().numpy() if isinstance(f, Tensor) else np.asarray(f, dtype=np.float64)
        if a.ndim != 2:
            raise ValueError(f"{name} must be a 2-D (N, D) array, got shape {a.shape}")
        if not np.isfinite(a).all():
            raise ValueError(f"{name} holds non-finite values")
        out.append(a)
    if out[0].shape[1] != out[1].shape[1]:
        raise ValueError(f"real_feats and syn_feats must have the same number of features, got {out[0].shape[1]} "
                         f"and {out[1].shape[1]}")
    return out[0], out[1]

