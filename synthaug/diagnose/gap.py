"""How far synthetic patches are from real seed patches *in a detector's own features* (issue 16, item 1).

A detector never sees pixels: the HOG detector sees HOG blocks, AdaBoost sees
the responses of its Levi–Weiss weak learners, the CNN sees its activations.
Synthetic data can look fine to a person and still be trivially separable in
those features (speckle that buys HOG gradient energy, edge-on poses, a coarse
silhouette). This module measures that gap per detector family:

1. :func:`feature_extractor` — the family's features of a batch of patches,
   reusing the feature maps of :mod:`synthaug.distances` (``hog``,
   ``wl_random`` / ``wl_learned``, ``cnn``);
2. :func:`classifier_two_sample_test` — a classifier two-sample test
   (Lopez-Paz & Oquab, "Revisiting classifier two-sample tests", ICLR 2017):
   held-out accuracy of an L2 logistic regression real vs synthetic, with a
   binomial CI and the one-sided p-value against 0.5 (0.5 = indistinguishable);
3. :func:`kid` — the Kernel Inception Distance (Bińkowski et al., "Demystifying
   MMD GANs", ICLR 2018) in the same features: the unbiased MMD² with the cubic
   kernel ``k(x, y) = (x·y / d + 1)³``, mean ± std over random subsets;
4. :func:`separating_features` — which features separate them most, and the
   pictures: :func:`render_hog_glyphs` (mean HOG glyphs real / synthetic /
   difference), :func:`render_cnn_separation` (the CNN channels that differ
   most), :func:`looks_synthetic_grid` (samples sorted by the classifier's
   held-out "looks synthetic" probability);
5. :func:`measure_gap` — all of it for several families, as a JSON-able dict; :func:`gap_section` and
   :func:`gap_markdown` make it the ``gap`` section of the ``synthaug diagnose`` report (``--gap``).

Example:
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> real = rng.normal(size=(60, 5)); syn = rng.normal(size=(60, 5)) + [2, 0, 0, 0, 0]
    >>> t = classifier_two_sample_test(real, syn, folds=5, seed=0)
    >>> t.accuracy > 0.8, t.p_value < 0.01
    (True, True)
    >>> separating_features(real, syn, top=1)[0]["index"]
    0
    >>> same = kid(real, rng.normal(size=(60, 5)), subsets=20, subset_size=50)
    >>> shifted = kid(real, syn, subsets=20, subset_size=50)
    >>> abs(same.mean) < 0.05 < shifted.mean
    True
"""

from __future__ import annotations

import copy
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np
import torch
from torch import Tensor

__all__ = [
    "FAMILIES",
    "GAP_FORMAT",
    "FeatureExtractor",
    "feature_extractor",
    "fit_logistic",
    "TwoSampleTest",
    "classifier_two_sample_test",
    "binomial_ci",
    "mmd2_polynomial",
    "KIDResult",
    "kid",
    "separating_features",
    "effect_sizes",
    "hog_feature_layout",
    "hog_cell_means",
    "render_hog_glyphs",
    "render_cnn_separation",
    "looks_synthetic_grid",
    "measure_gap",
    "gap_section",
    "gap_markdown",
    "training_samples",
]

FAMILIES = ("hog", "adaboost", "cnn")
"""The detector families whose feature spaces :func:`feature_extractor` knows."""

GAP_FORMAT = "synthaug.gap"

_CHUNK = 1024  # patches per feature-extraction batch


# --------------------------------------------------------------------------------------------------------------
# 1. features


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


# --------------------------------------------------------------------------------------------------------------
# 2. classifier two-sample test


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


def fit_logistic(x: np.ndarray, y: np.ndarray, *, C: float = 1.0, max_iter: int = 100,
                 tol: float = 1e-9) -> tuple[np.ndarray, float]:
    """L2-penalised logistic regression, ``min Σ_i log(1 + exp(-s_i (x_i·w + b))) + ||w||² / (2C)``.

    The objective of scikit-learn's ``LogisticRegression(C=C)`` (intercept not penalised); scikit-learn is
    not a dependency of synthaug. Minimised by Newton's method with a backtracking line search, from zero —
    deterministic, and quadratic convergence also when the classes are (nearly) separable, where first-order
    methods crawl. With more features than samples (HOG, CNN activations of a seed set), the problem is
    solved exactly in the span of the samples: the optimum satisfies ``w = -C Xᵀ(σ(z) - y)``, so with
    ``Xᵀ = Q R`` (thin QR) ``w = Q β`` and ``x_i·w = (Rᵀ β)_i``, an n-dimensional problem with the same
    penalty ``||β||²``.

    Args:
        x: features ``(N, D)`` (standardise them first: the penalty is isotropic).
        y: labels in {0, 1}, ``(N,)``.
        C: inverse penalty strength.
        max_iter: Newton iterations.
        tol: stop when the gradient's largest entry is below ``tol`` times ``N``.

    Returns:
        ``(w, b)``: weights ``(D,)`` and intercept; P(y = 1 | x) = σ(x·w + b).

    Example:
        >>> w, b = fit_logistic(np.array([[-1.0], [1.0]]), np.array([0, 1]))
        >>> round(float(w[0]), 3), abs(round(b, 6))  # the optimum solves w = 2 σ(-w)
        (0.675, 0.0)
    """
    from scipy.special import expit

    if not C > 0:
        raise ValueError(f"C must be > 0, got {C}")
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    n, d = x.shape
    if x.shape[0] != y.shape[0]:
        raise ValueError(f"x and y must have the same number of rows, got {x.shape[0]} and {y.shape[0]}")
    q = None
    if d > n:
        q, r = np.linalg.qr(x.T)  # (D, N), (N, N)
        z_feats = r.T
    else:
        z_feats = x
    k = z_feats.shape[1]
    design = np.concatenate([z_feats, np.ones((n, 1))], axis=1)
    penalty = np.full(k + 1, 1.0 / C)
    penalty[k] = 0.0

    def objective(theta: np.ndarray) -> float:
        z = design @ theta
        return float(np.sum(np.logaddexp(0.0, z) - y * z) + 0.5 * np.sum(penalty * theta * theta))

    theta = np.zeros(k + 1)
    f = objective(theta)
    for _ in range(max_iter):
        p = expit(design @ theta)
        grad = design.T @ (p - y) + penalty * theta
        if np.abs(grad).max() < tol * n:
            break
        hess = (design * (p * (1 - p))[:, None]).T @ design
        hess[np.diag_indices_from(hess)] += penalty + 1e-12
        step = np.linalg.solve(hess, grad)
        t, slope = 1.0, float(grad @ step)
        while True:  # Armijo backtracking: a full Newton step can overshoot far from the optimum
            candidate = theta - t * step
            f_new = objective(candidate)
            if f_new <= f - 1e-4 * t * slope or t < 1e-10:
                break
            t *= 0.5
        theta, f = candidate, f_new
    w = theta[:k] if q is None else q @ theta[:k]
    return w.copy(), float(theta[k])


def _standardiser(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    mu = x.mean(0)
    sd = x.std(0)
    return mu, np.where(sd > 1e-12, sd, 1.0)  # constant features stay constant (0), not NaN


def binomial_ci(successes: int, trials: int, *, confidence: float = 0.95, method: str = "wilson") -> tuple[float, float]:
    """Confidence interval of a binomial proportion (scipy's ``BinomTestResult.proportion_ci``).

    Args:
        successes: k.
        trials: n > 0.
        confidence: coverage.
        method: ``"wilson"`` (score interval) or ``"exact"`` (Clopper–Pearson).

    Example:
        >>> [round(v, 4) for v in binomial_ci(80, 100)]
        [0.7112, 0.8666]
    """
    from scipy.stats import binomtest

    if method not in ("wilson", "exact"):
        raise ValueError(f"method must be 'wilson' or 'exact', got {method!r}")
    if not 0 < confidence < 1:
        raise ValueError(f"confidence must be in (0, 1), got {confidence}")
    ci = binomtest(int(successes), int(trials)).proportion_ci(confidence_level=confidence, method=method)
    return float(ci.low), float(ci.high)


@dataclass(frozen=True)
class TwoSampleTest:
    """Result of :func:`classifier_two_sample_test` (label 1 = synthetic).

    Attributes:
        accuracy: held-out accuracy over all folds (0.5 = indistinguishable).
        ci: its confidence interval ``(low, high)``.
        p_value: one-sided binomial p-value of ``accuracy > 0.5``.
        n_correct: held-out predictions that were right.
        n_test: held-out predictions (2 × samples per class).
        folds: k.
        weights: ``(D,)`` logistic weights fitted on all (balanced) samples, standardised features;
            > 0 pushes towards "synthetic".
        bias: its intercept.
        probabilities: ``(n_test,)`` held-out P(synthetic) of each sample, real ones first.
        real_index: which rows of the real features were used (the balanced subsample), ``(m,)``.
        syn_index: same for the synthetic features.
        ci_method: ``"wilson"`` or ``"exact"``.
        p_permutation: permutation p-value of ``accuracy > 0.5`` (None when not computed).
        permutations: label shuffles behind ``p_permutation``.
    """

    accuracy: float
    ci: tuple[float, float]
    p_value: float
    n_correct: int
    n_test: int
    folds: int
    weights: np.ndarray
    bias: float
    probabilities: np.ndarray
    real_index: np.ndarray
    syn_index: np.ndarray
    ci_method: str = "wilson"
    p_permutation: float | None = None
    permutations: int = 0

    def as_dict(self, arrays: bool = False) -> dict[str, Any]:
        """JSON-able summary; ``arrays=True`` adds the weights, probabilities and indices."""
        out: dict[str, Any] = {"accuracy": self.accuracy, "ci": list(self.ci), "ci_method": self.ci_method,
                               "p_value": self.p_value, "n_correct": self.n_correct, "n_test": self.n_test,
                               "per_class": self.n_test // 2, "folds": self.folds,
                               "p_permutation": self.p_permutation, "permutations": self.permutations}
        if arrays:
            out.update(weights=self.weights.tolist(), bias=self.bias, probabilities=self.probabilities.tolist(),
                       real_index=self.real_index.tolist(), syn_index=self.syn_index.tolist())
        return out


def _stratified_folds(y: np.ndarray, folds: int, rng: np.random.Generator) -> np.ndarray:
    """Fold number of every sample: each class split into ``folds`` near-equal random parts on its own."""
    fold_of = np.empty(len(y), dtype=np.int64)
    for cls in (0.0, 1.0):
        idx = np.flatnonzero(y == cls)
        for j, part in enumerate(np.array_split(rng.permutation(len(idx)), folds)):
            fold_of[idx[part]] = j
    return fold_of


def _heldout_probabilities(x: np.ndarray, y: np.ndarray, fold_of: np.ndarray, folds: int, C: float) -> np.ndarray:
    from scipy.special import expit

    prob = np.empty(len(y))
    for j in range(folds):
        te = fold_of == j
        mu, sd = _standardiser(x[~te])
        w, b = fit_logistic((x[~te] - mu) / sd, y[~te], C=C)
        prob[te] = expit(((x[te] - mu) / sd) @ w + b)
    return prob


def _n_correct(prob: np.ndarray, y: np.ndarray) -> int:
    return int(((prob > 0.5) == (y > 0.5)).sum())


def classifier_two_sample_test(
    real_feats: np.ndarray | Tensor,
    syn_feats: np.ndarray | Tensor,
    *,
    folds: int = 5,
    seed: int = 0,
    C: float = 1.0,
    confidence: float = 0.95,
    ci_method: str = "wilson",
    permutations: int = 0,
    groups_real: np.ndarray | Sequence[int] | None = None,
    groups_syn: np.ndarray | Sequence[int] | None = None,
) -> TwoSampleTest:
    """Classifier two-sample test (Lopez-Paz & Oquab 2017): can a linear classifier tell real from synthetic?

    Classes are balanced first (the larger set is subsampled without replacement, ``numpy`` generator seeded
    by ``seed``), then each class is split into ``folds`` parts (stratified k-fold, same generator). For every
    fold an L2 logistic regression (:func:`fit_logistic`, features standardised with the training part's mean
    and std) is trained on the other folds and predicts the held-out one. The number of right held-out
    predictions is compared with Binomial(n, 1/2): a CI of the accuracy (``scipy.stats.binomtest``,
    Wilson or Clopper–Pearson) and the one-sided p-value of ``accuracy > 0.5``.

    The binomial treats the n held-out predictions as independent. Within a fold they are; across folds the
    classifiers share training data, and the pooled k-fold accuracy varies more than a binomial under H0
    (measured on two draws of one distribution of 100 patches each, 30 replicates per family: sd 0.047-0.049
    against the binomial's 0.035; 4-20 % of one-sided p < 0.05). The binomial ``ci`` and ``p_value`` are
    therefore somewhat optimistic; ``permutations > 0`` adds ``p_permutation``, which is exact: the labels
    are shuffled (keeping m per class), the same stratified k-fold is re-run, and
    ``p = (1 + #{shuffled accuracy >= accuracy}) / (1 + permutations)``.

    With ``groups_real`` / ``groups_syn`` (e.g. the seed each patch comes from), folds are drawn by group:
    all samples of a group, real or synthetic, are held out together. Use them whenever a real patch and
    synthetic patches share something (a seed's background, its best-fit render): split apart, the
    classifier learns the shared part with the synthetic label and calls the held-out real patch synthetic,
    pulling the accuracy *below* 0.5 (measured: 0.19 for 16 seeds against their best-fit renders).
    The folds are then stratified only approximately; permutations shuffle labels within the same folds.

    Args:
        real_feats: ``(N_r, D)`` features of the real patches.
        syn_feats: ``(N_s, D)`` features of the synthetic patches.
        folds: k >= 2; each class needs at least k samples after balancing.
        seed: seeds the subsample, the folds and the permutations.
        C: inverse L2 penalty of the logistic regression (scikit-learn's ``C``).
        confidence: CI coverage.
        ci_method: ``"wilson"`` or ``"exact"`` (Clopper–Pearson).
        permutations: label shuffles for ``p_permutation`` (0: not computed; costs ``folds`` fits each).
        groups_real: ``(N_r,)`` group label of every real row (needs ``groups_syn`` too).
        groups_syn: ``(N_s,)`` group label of every synthetic row.

    Returns:
        A :class:`TwoSampleTest`.
    """
    from scipy.stats import binomtest

    real, syn = _features_pair(real_feats, syn_feats)
    if not isinstance(folds, int) or folds < 2:
        raise ValueError(f"folds must be an int >= 2, got {folds!r}")
    if not isinstance(seed, int):
        raise ValueError(f"seed must be an int, got {seed!r}")
    if ci_method not in ("wilson", "exact"):
        raise ValueError(f"ci_method must be 'wilson' or 'exact', got {ci_method!r}")
    if not isinstance(permutations, int) or permutations < 0:
        raise ValueError(f"permutations must be an int >= 0, got {permutations!r}")
    if (groups_real is None) != (groups_syn is None):
        raise ValueError("give both groups_real and groups_syn, or neither")
    if groups_real is not None:
        groups_real, groups_syn = np.asarray(groups_real), np.asarray(groups_syn)
        if groups_real.shape != (len(real),) or groups_syn.shape != (len(syn),):
            raise ValueError(f"groups_real / groups_syn must have shapes ({len(real)},) / ({len(syn)},), got "
                             f"{groups_real.shape} / {groups_syn.shape}")
    m = min(len(real), len(syn))
    if m < folds:
        raise ValueError(f"need at least folds={folds} samples per class, got {len(real)} real and {len(syn)} synthetic")
    rng = np.random.default_rng(seed)
    real_index = np.sort(rng.choice(len(real), m, replace=False)) if len(real) > m else np.arange(m)
    syn_index = np.sort(rng.choice(len(syn), m, replace=False)) if len(syn) > m else np.arange(m)
    x = np.concatenate([real[real_index], syn[syn_index]])
    y = np.concatenate([np.zeros(m), np.ones(m)])
    grouped = groups_real is not None
    if grouped:
        groups = np.concatenate([groups_real[real_index], groups_syn[syn_index]])
        unique, inverse = np.unique(groups, return_inverse=True)
        if len(unique) < folds:
            raise ValueError(f"need at least folds={folds} groups, got {len(unique)}")
        group_fold = np.empty(len(unique), dtype=np.int64)
        for j, part in enumerate(np.array_split(rng.permutation(len(unique)), folds)):
            group_fold[part] = j
        fold_of = group_fold[inverse]
    else:
        fold_of = _stratified_folds(y, folds, rng)
    prob = _heldout_probabilities(x, y, fold_of, folds, C)
    correct = _n_correct(prob, y)
    n = 2 * m
    p_perm = None
    if permutations:
        as_extreme = 0
        for _ in range(permutations):
            y_b = rng.permutation(y)
            fold_b = fold_of if grouped else _stratified_folds(y_b, folds, rng)
            as_extreme += _n_correct(_heldout_probabilities(x, y_b, fold_b, folds, C), y_b) >= correct
        p_perm = (1 + as_extreme) / (1 + permutations)
    mu, sd = _standardiser(x)
    w_all, b_all = fit_logistic((x - mu) / sd, y, C=C)
    return TwoSampleTest(
        accuracy=correct / n, ci=binomial_ci(correct, n, confidence=confidence, method=ci_method),
        p_value=float(binomtest(correct, n, 0.5, alternative="greater").pvalue), n_correct=correct, n_test=n,
        folds=folds, weights=w_all, bias=b_all, probabilities=prob, real_index=real_index, syn_index=syn_index,
        ci_method=ci_method, p_permutation=p_perm, permutations=permutations)


# --------------------------------------------------------------------------------------------------------------
# 3. KID


def _poly_kernel(a: np.ndarray, b: np.ndarray, degree: int, gamma: float, coef: float) -> np.ndarray:
    return (a @ b.T * gamma + coef) ** degree


def mmd2_polynomial(x: np.ndarray | Tensor, y: np.ndarray | Tensor, *, degree: int = 3, gamma: float | None = None,
                    coef: float = 1.0) -> float:
    """Unbiased MMD² with the polynomial kernel ``k(a, b) = (γ a·b + coef)^degree`` (γ = 1/d by default).

    ``MMD²_u = Σ_{i≠j} k(x_i, x_j) / (m(m-1)) + Σ_{i≠j} k(y_i, y_j) / (n(n-1)) - 2 Σ_{i,j} k(x_i, y_j) / (mn)``
    (Gretton et al. 2012, eq. 3); the sets may differ in size.

    Example:
        >>> rng = np.random.default_rng(0)
        >>> round(mmd2_polynomial(rng.normal(size=(50, 4)), rng.normal(size=(40, 4)) + 1), 2)
        7.15
    """
    x, y = _features_pair(x, y)
    m, n = len(x), len(y)
    if m < 2 or n < 2:
        raise ValueError(f"the unbiased MMD needs at least 2 samples per set, got {m} and {n}")
    gamma = 1.0 / x.shape[1] if gamma is None else float(gamma)
    kxx = _poly_kernel(x, x, degree, gamma, coef)
    kyy = _poly_kernel(y, y, degree, gamma, coef)
    kxy = _poly_kernel(x, y, degree, gamma, coef)
    return float((kxx.sum() - np.trace(kxx)) / (m * (m - 1)) + (kyy.sum() - np.trace(kyy)) / (n * (n - 1))
                 - 2.0 * kxy.mean())


@dataclass(frozen=True)
class KIDResult:
    """Result of :func:`kid`: mean and (population) std of MMD² over the subsets, and the values."""

    mean: float
    std: float
    subset_size: int
    values: np.ndarray

    def as_dict(self) -> dict[str, Any]:
        return {"mean": self.mean, "std": self.std, "subsets": int(len(self.values)), "subset_size": self.subset_size}


_GRAM_LIMIT = 3000  # samples up to which the whole kernel matrix is computed once (72 MB of float64)


def kid(
    real_feats: np.ndarray | Tensor,
    syn_feats: np.ndarray | Tensor,
    *,
    subsets: int = 100,
    subset_size: int = 1000,
    seed: int = 0,
    degree: int = 3,
    gamma: float | None = None,
    coef: float = 1.0,
) -> KIDResult:
    """Kernel Inception Distance (Bińkowski et al. 2018) in any feature space.

    For each of ``subsets`` draws, ``subset_size`` real and ``subset_size`` synthetic rows are picked without
    replacement (``numpy`` generator seeded by ``seed``) and the unbiased MMD² with the cubic kernel
    ``k(x, y) = (x·y / d + 1)³`` is computed (:func:`mmd2_polynomial`); KID is their mean, reported with their
    std (population std, as torchmetrics). 0 = same distribution (the estimator is unbiased, so it can be
    slightly negative). ``subset_size`` is capped at the smaller set (the KID paper's 1000 is more than a
    seed set holds); equal to both set sizes, every subset is the whole data.

    Args:
        real_feats: ``(N_r, D)``.
        syn_feats: ``(N_s, D)``.
        subsets: number of subsets.
        subset_size: rows per set per subset (>= 2 after capping).
        seed: seeds the subsets.
        degree: kernel degree (3).
        gamma: kernel scale (None: 1/d).
        coef: kernel offset (1).

    Returns:
        A :class:`KIDResult`.
    """
    real, syn = _features_pair(real_feats, syn_feats)
    if not isinstance(subsets, int) or subsets < 1:
        raise ValueError(f"subsets must be an int >= 1, got {subsets!r}")
    if not isinstance(subset_size, int) or subset_size < 2:
        raise ValueError(f"subset_size must be an int >= 2, got {subset_size!r}")
    m = min(subset_size, len(real), len(syn))
    if m < 2:
        raise ValueError(f"KID needs at least 2 samples per set, got {len(real)} real and {len(syn)} synthetic")
    gamma = 1.0 / real.shape[1] if gamma is None else float(gamma)
    rng = np.random.default_rng(seed)
    nr = len(real)
    gram = None
    if nr + len(syn) <= _GRAM_LIMIT:
        both = np.concatenate([real, syn])
        gram = _poly_kernel(both, both, degree, gamma, coef)
    values = np.empty(subsets)
    for s in range(subsets):
        ir = rng.permutation(nr)[:m]
        js = rng.permutation(len(syn))[:m]
        if gram is not None:
            kxx, kyy, kxy = gram[np.ix_(ir, ir)], gram[np.ix_(nr + js, nr + js)], gram[np.ix_(ir, nr + js)]
        else:
            x, y = real[ir], syn[js]
            kxx, kyy = _poly_kernel(x, x, degree, gamma, coef), _poly_kernel(y, y, degree, gamma, coef)
            kxy = _poly_kernel(x, y, degree, gamma, coef)
        values[s] = ((kxx.sum() - np.trace(kxx)) + (kyy.sum() - np.trace(kyy))) / (m * (m - 1)) - 2.0 * kxy.mean()
    return KIDResult(float(values.mean()), float(values.std()), m, values)


# --------------------------------------------------------------------------------------------------------------
# 4. which features separate them, as numbers and images


def separating_features(
    real_feats: np.ndarray | Tensor,
    syn_feats: np.ndarray | Tensor,
    *,
    names: Sequence[str] | None = None,
    weights: np.ndarray | None = None,
    top: int = 10,
    rank_by: str = "effect_size",
) -> list[dict[str, Any]]:
    """Features ranked by how much they separate synthetic from real.

    The effect size of feature i is the standardised mean difference (Cohen's d)
    ``d_i = (mean_syn - mean_real) / pooled_sd`` (> 0: larger in synthetic); a feature constant in both
    sets but with different values gets ``±1e12`` (perfectly separating).

    Args:
        real_feats: ``(N_r, D)``.
        syn_feats: ``(N_s, D)``.
        names: one name per feature (e.g. :attr:`FeatureExtractor.names`).
        weights: the two-sample test's logistic weights ``(D,)`` (reported, and used by ``rank_by="weight"``).
        top: how many to return.
        rank_by: ``"effect_size"`` (|d|) or ``"weight"`` (|w|, needs ``weights``).

    Returns:
        ``top`` dicts, most separating first: ``index``, ``name``, ``effect_size``, ``mean_real``,
        ``mean_synthetic`` and ``weight`` (None without ``weights``).
    """
    real, syn = _features_pair(real_feats, syn_feats)
    d = real.shape[1]
    if len(real) < 2 or len(syn) < 2:
        raise ValueError(f"need at least 2 samples per set, got {len(real)} and {len(syn)}")
    if names is not None and len(names) != d:
        raise ValueError(f"names must have one entry per feature ({d}), got {len(names)}")
    if weights is not None:
        weights = np.asarray(weights, dtype=np.float64)
        if weights.shape != (d,):
            raise ValueError(f"weights must have shape ({d},), got {weights.shape}")
    if rank_by not in ("effect_size", "weight"):
        raise ValueError(f"rank_by must be 'effect_size' or 'weight', got {rank_by!r}")
    if rank_by == "weight" and weights is None:
        raise ValueError("rank_by='weight' needs weights=")
    effect = effect_sizes(real, syn)
    key = np.abs(effect) if rank_by == "effect_size" else np.abs(weights)
    order = np.argsort(-key, kind="stable")[:max(0, int(top))]
    mr, ms = real.mean(0), syn.mean(0)
    return [{"index": int(i), "name": None if names is None else names[i], "effect_size": float(effect[i]),
             "mean_real": float(mr[i]), "mean_synthetic": float(ms[i]),
             "weight": None if weights is None else float(weights[i])} for i in order]


def effect_sizes(real: np.ndarray, syn: np.ndarray) -> np.ndarray:
    """Cohen's d of every feature, ``(D,)``: ``(mean_syn - mean_real) / pooled_sd`` (see :func:`separating_features`)."""
    nr, ns = len(real), len(syn)
    diff = syn.mean(0) - real.mean(0)
    pooled = np.sqrt(((nr - 1) * real.var(0, ddof=1) + (ns - 1) * syn.var(0, ddof=1)) / (nr + ns - 2))
    tiny = 1e-12 * np.maximum(1.0, np.abs(np.concatenate([real, syn])).max(0))
    return np.where(pooled > tiny, diff / np.where(pooled > tiny, pooled, 1.0),
                    np.where(np.abs(diff) > tiny, np.sign(diff) * 1e12, 0.0))


def hog_cell_means(feats: np.ndarray | Tensor, config: Any, window: int) -> np.ndarray:
    """Mean HOG value per (cell, orientation), averaged over the samples and the blocks holding the cell.

    Args:
        feats: HOG descriptors ``(N, D)`` or one ``(D,)`` (:func:`~synthaug.detectors.hog.hog` order).
        config: the HOG settings.
        window: patch side.

    Returns:
        ``(cells, cells, orientations)``.

    Example:
        >>> from synthaug.detectors.hog import DEFAULT_HOG
        >>> hog_cell_means(np.ones(576), DEFAULT_HOG, 40).shape
        (5, 5, 9)
    """
    f = feats.detach().cpu().double().numpy() if isinstance(feats, Tensor) else np.asarray(feats, np.float64)
    f = f.reshape(-1, f.shape[-1]).mean(0)
    lay = hog_feature_layout(config, window)
    if f.shape[0] != len(lay):
        raise ValueError(f"a {window}-px HOG descriptor has {len(lay)} values, got {f.shape[0]}")
    cells = window // config.cell_size
    total = np.zeros((cells, cells, config.orientations))
    count = np.zeros_like(total)
    rows, cols, ori = lay[:, 0] + lay[:, 2], lay[:, 1] + lay[:, 3], lay[:, 4]
    np.add.at(total, (rows, cols, ori), f)
    np.add.at(count, (rows, cols, ori), 1.0)
    return total / np.maximum(count, 1.0)


def _figure_array(fig: Any, path: str | os.PathLike | None) -> np.ndarray:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)  # no global backend switch: pyplot is never imported
    canvas.draw()
    rgb = np.asarray(canvas.buffer_rgba())[..., :3].copy()
    if path is not None:
        _save_png(rgb, path)
    return rgb


def _save_png(image: np.ndarray, path: str | os.PathLike) -> Path:
    from PIL import Image

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp.png")  # atomic: never half a PNG under its final name
    Image.fromarray(image).save(tmp)
    tmp.replace(path)
    return path


def _draw_glyphs(ax: Any, cells: np.ndarray, scale: float, signed: bool = False) -> None:
    n_rows, n_cols, n_ori = cells.shape
    for r in range(n_rows):
        for c in range(n_cols):
            for o in range(n_ori):
                v = cells[r, c, o]
                if v == 0:
                    continue
                theta = (o + 0.5) * math.pi / n_ori  # gradient angle, rows pointing down
                # the glyph draws the edge, perpendicular to the gradient
                dx, dy = -math.sin(theta) * 0.45, math.cos(theta) * 0.45
                colour = ("tab:red" if v > 0 else "tab:blue") if signed else "white"
                ax.plot([c + 0.5 - dx, c + 0.5 + dx], [r + 0.5 - dy, r + 0.5 + dy], color=colour,
                        lw=0.3 + 4.0 * abs(v) / scale, solid_capstyle="round")
    ax.set_xlim(0, n_cols)
    ax.set_ylim(n_rows, 0)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


def render_hog_glyphs(real_feats: np.ndarray | Tensor, syn_feats: np.ndarray | Tensor, config: Any, window: int,
                      path: str | os.PathLike | None = None) -> np.ndarray:
    """Mean HOG glyphs — real, synthetic, and synthetic − real — as one RGB image.

    Each cell shows one line per orientation bin along the *edge* direction (perpendicular to the gradient
    bin), its width the mean block-normalised value (averaged over the blocks holding the cell). In the
    difference panel, red = more in synthetic, blue = more in real.

    Args:
        real_feats: real HOG descriptors ``(N_r, D)``.
        syn_feats: synthetic HOG descriptors ``(N_s, D)``.
        config: the HOG settings.
        window: patch side.
        path: also written there as PNG (atomically).

    Returns:
        uint8 ``(H, W, 3)``.
    """
    from matplotlib.figure import Figure

    real = hog_cell_means(real_feats, config, window)
    syn = hog_cell_means(syn_feats, config, window)
    fig = Figure(figsize=(9, 3.3), dpi=90)
    axes = fig.subplots(1, 3)
    scale = max(float(real.max()), float(syn.max()), 1e-9)
    diff = syn - real
    for ax, cells, title, signed, s in ((axes[0], real, "real (mean HOG)", False, scale),
                                        (axes[1], syn, "synthetic (mean HOG)", False, scale),
                                        (axes[2], diff, "synthetic - real", True,
                                         max(float(np.abs(diff).max()), 1e-9))):
        if not signed:
            ax.set_facecolor("black")
        _draw_glyphs(ax, cells, s, signed)
        ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return _figure_array(fig, path)


def render_cnn_separation(effect: np.ndarray, extractor: FeatureExtractor, *, channels: int = 8,
                          path: str | os.PathLike | None = None) -> np.ndarray:
    """The CNN's most separating activations: per-position effect size maps of the top channels of layers 2, 3.

    Args:
        effect: Cohen's d per feature ``(D,)`` (:func:`effect_sizes`), in the extractor's order.
        extractor: the ``cnn`` :class:`FeatureExtractor` the features came from.
        channels: channels shown per layer (those with the largest mean |d|).
        path: also written there as PNG.

    Returns:
        uint8 ``(H, W, 3)``; red = activation larger in synthetic.
    """
    from matplotlib.figure import Figure

    if extractor.family != "cnn":
        raise ValueError(f"render_cnn_separation needs a cnn extractor, got {extractor.family!r}")
    effect = np.asarray(effect, np.float64)
    if effect.shape != (extractor.n_features,):
        raise ValueError(f"effect must have shape ({extractor.n_features},), got {effect.shape}")
    effect = np.clip(effect, -10, 10)
    maps, start = [], 0
    for layer, shape in zip(extractor.layout["layers"], extractor.layout["shapes"]):
        size = int(np.prod(shape))
        maps.append((layer, effect[start:start + size].reshape(shape)))
        start += size
    shown = [(layer, m) for layer, m in maps if m.shape[-1] > 1]  # spatial layers (2 and 3 for 40 px)
    v = max(max(float(np.abs(m).max()) for _, m in shown), 1e-9)
    fig = Figure(figsize=(1.3 * channels, 1.5 * len(shown) + 0.4), dpi=90)
    axes = np.atleast_2d(fig.subplots(len(shown), channels, squeeze=False))
    for row, (layer, m) in enumerate(shown):
        order = np.argsort(-np.abs(m).mean(axis=(1, 2)), kind="stable")
        for col in range(channels):
            ax = axes[row, col]
            ax.set_xticks([])
            ax.set_yticks([])
            if col >= len(order):
                ax.set_axis_off()
                continue
            c = order[col]
            ax.imshow(m[c], cmap="RdBu_r", vmin=-v, vmax=v)
            ax.set_title(f"L{layer} ch{c}", fontsize=7)
    fig.suptitle("Cohen's d per activation (red: larger in synthetic)", fontsize=8)
    fig.tight_layout()
    return _figure_array(fig, path)


def _u8_tiles(patches: Tensor | np.ndarray, index: np.ndarray) -> list[np.ndarray]:
    x = _float_patches(patches, None)[torch.as_tensor(np.ascontiguousarray(index), dtype=torch.long)]
    return [np.round(t[0].clamp(0, 1).numpy() * 255).astype(np.uint8) for t in x]


def looks_synthetic_grid(real_patches: Tensor | np.ndarray, syn_patches: Tensor | np.ndarray, test: TwoSampleTest,
                         *, n: int = 8, zoom: int = 2, path: str | os.PathLike | None = None) -> np.ndarray:
    """Samples sorted by the two-sample test's held-out P(synthetic), as one labelled grid.

    Rows: the synthetic patches that look most synthetic (what gives them away) and most real, then the real
    patches that look most synthetic and most real. Tiling is :func:`synthaug.data.preview.tile_grid`.

    Args:
        real_patches: the real patches the test's features came from (rows match ``test.real_index``).
        syn_patches: the synthetic patches, likewise.
        test: a :class:`TwoSampleTest` of their features.
        n: patches per row.
        zoom: nearest-neighbour upscaling.
        path: also written there as PNG.

    Returns:
        uint8 ``(H, W)`` grid.
    """
    from synthaug.data.preview import tile_grid

    m = len(test.real_index)
    p_real, p_syn = test.probabilities[:m], test.probabilities[m:]
    n = max(1, min(int(n), m))
    syn_order = test.syn_index[np.argsort(-p_syn, kind="stable")]
    real_order = test.real_index[np.argsort(-p_real, kind="stable")]
    p_syn_sorted, p_real_sorted = np.sort(p_syn)[::-1], np.sort(p_real)[::-1]
    rows = [(_u8_tiles(syn_patches, syn_order[:n]), f"syn, most synthetic (p>={p_syn_sorted[n - 1]:.2f})"),
            (_u8_tiles(syn_patches, syn_order[::-1][:n]), f"syn, most real (p<={p_syn_sorted[::-1][n - 1]:.2f})"),
            (_u8_tiles(real_patches, real_order[:n]), f"real, most synthetic (p>={p_real_sorted[n - 1]:.2f})"),
            (_u8_tiles(real_patches, real_order[::-1][:n]), f"real, most real (p<={p_real_sorted[::-1][n - 1]:.2f})")]
    tiles = [t for r, _ in rows for t in r]
    grid = tile_grid(tiles, n, zoom=zoom, row_labels=[label for _, label in rows])
    if path is not None:
        _save_png(grid, path)
    return grid


# --------------------------------------------------------------------------------------------------------------
# 5. all together


def measure_gap(
    real_patches: Tensor | np.ndarray,
    synthetic_patches: Tensor | np.ndarray,
    families: Sequence[str] = FAMILIES,
    *,
    detectors: Mapping[str, Any] | None = None,
    folds: int = 5,
    seed: int = 0,
    C: float = 1.0,
    permutations: int = 200,
    kid_subsets: int = 100,
    kid_subset_size: int = 1000,
    top: int = 10,
    out_dir: str | os.PathLike | None = None,
    n_learners: int = 1000,
    groups_real: np.ndarray | Sequence[int] | None = None,
    groups_syn: np.ndarray | Sequence[int] | None = None,
) -> dict[str, Any]:
    """The real-vs-synthetic gap in each detector family's features: two-sample test, KID, top features.

    Args:
        real_patches: real seed patches, uint8 ``(N, P, P)`` (``SeedSet.patches``) or float ``(N, 1, P, P)``.
        synthetic_patches: synthetic patches, same conventions and size.
        families: subset of :data:`FAMILIES`.
        detectors: ``{family: detector or checkpoint path}`` (see :func:`feature_extractor`); a family
            left out uses the extractor's detector-free default (HOG settings, random weak learners
            thresholded on the real patches, an untrained seeded CNN).
        folds: folds of the two-sample test.
        seed: seeds everything random (subsample, folds, KID subsets, random learners / network).
        C: inverse L2 penalty of the two-sample classifier.
        permutations: label shuffles of the two-sample test's exact p-value (``p_permutation``; 0: none).
        kid_subsets: KID subsets.
        kid_subset_size: KID subset size (capped at the smaller set).
        top: separating features reported per family.
        out_dir: when given, the figures are written there (``gap_<family>_samples.png``, and
            ``gap_hog_glyphs.png`` / ``gap_cnn_activations.png``) and named in the result.
        n_learners: random weak learners when no AdaBoost detector is given.
        groups_real: group (e.g. seed) of every real patch; with ``groups_syn``, the two-sample test holds
            groups out together (see :func:`classifier_two_sample_test`).
        groups_syn: group of every synthetic patch.

    Returns:
        JSON-able dict: ``format``, ``n_real``, ``n_synthetic``, ``seed``, and ``families`` — per family
        ``features`` (what they are), ``n_features``, ``two_sample`` (:meth:`TwoSampleTest.as_dict`), ``kid``
        (:meth:`KIDResult.as_dict`), ``top_features`` (:func:`separating_features`, with the logistic
        weights) and ``figures`` (file names in ``out_dir``).
    """
    families = list(families)
    bad = [f for f in families if f not in FAMILIES]
    if bad or not families:
        raise ValueError(f"families must be a non-empty subset of {list(FAMILIES)}, got {families}")
    detectors = dict(detectors or {})
    extra = [k for k in detectors if k not in families]
    if extra:
        raise ValueError(f"detectors given for families not measured: {extra} (families: {families})")
    real = _float_patches(real_patches, None)
    syn = _float_patches(synthetic_patches, None)
    if real.shape[-2:] != syn.shape[-2:]:
        raise ValueError(f"real and synthetic patches must have the same size, got {tuple(real.shape[-2:])} and "
                         f"{tuple(syn.shape[-2:])}")
    window = int(real.shape[-1])
    out = None if out_dir is None else Path(out_dir)
    result: dict[str, Any] = {"format": GAP_FORMAT, "version": 1, "n_real": int(len(real)),
                              "n_synthetic": int(len(syn)), "seed": seed, "grouped_folds": groups_real is not None,
                              "families": {},
                              "note": "two_sample: held-out accuracy of an L2 logistic regression real vs synthetic "
                                      "(0.5 = indistinguishable), binomial CI and one-sided p against 0.5 (somewhat "
                                      "optimistic for pooled k-fold predictions), p_permutation exact; kid: "
                                      "unbiased MMD^2, cubic kernel (x.y/d + 1)^3, mean and std over subsets; "
                                      "top_features: Cohen's d (> 0 = larger in synthetic)"}
    for fam in families:
        fx = feature_extractor(fam, detectors.get(fam), window=window, reference=real, seed=seed,
                               n_learners=n_learners)
        fr, fs = fx(real), fx(syn)
        test = classifier_two_sample_test(fr, fs, folds=folds, seed=seed, C=C, permutations=permutations,
                                          groups_real=groups_real, groups_syn=groups_syn)
        k = kid(fr, fs, subsets=kid_subsets, subset_size=kid_subset_size, seed=seed)
        effect = effect_sizes(fr, fs)
        figures: dict[str, str] = {}
        if out is not None:
            name = f"gap_{fam}_samples.png"
            looks_synthetic_grid(real, syn, test, path=out / name)
            figures["samples"] = name
            if fam == "hog":
                name = "gap_hog_glyphs.png"
                render_hog_glyphs(fr, fs, fx.layout["config"], fx.window, path=out / name)
                figures["glyphs"] = name
            elif fam == "cnn":
                name = "gap_cnn_activations.png"
                render_cnn_separation(effect, fx, path=out / name)
                figures["activations"] = name
        result["families"][fam] = {
            "features": fx.description, "n_features": fx.n_features,
            "two_sample": test.as_dict(), "kid": k.as_dict(),
            "top_features": separating_features(fr, fs, names=fx.names, weights=test.weights, top=top),
            "figures": figures,
        }
    return result


# --------------------------------------------------------------------------------------------------------------
# the section of the ``synthaug diagnose`` report


def gap_section(
    real_patches: Tensor | np.ndarray,
    synthetic: Mapping[str, Any],
    *,
    real_groups: np.ndarray | Sequence[int] | None = None,
    families: Sequence[str] = FAMILIES,
    detectors: Mapping[str, Any] | None = None,
    seed: int = 0,
    out_dir: str | os.PathLike | None = None,
    **kwargs: Any,
) -> dict[str, Any]:
    """:func:`measure_gap` of the real patches against several synthetic sets — the diagnosis report's ``gap``.

    Args:
        real_patches: the real seed patches.
        synthetic: ``{name: patches}`` or ``{name: (patches, groups)}``, e.g. ``{"training": <random-pose
            samples of the fit>, "fitted": <each seed's best-fit render>}``; names must be plain words (they
            name figure folders); groups (the seed of each patch) need ``real_groups``.
        real_groups: the group (seed) of every real patch: folds then hold groups out together.
        families: detector families measured.
        detectors: ``{family: detector or checkpoint}`` (see :func:`feature_extractor`).
        seed: seeds everything random.
        out_dir: figures go to ``out_dir/gap_<name>/``; their paths in the result are relative to ``out_dir``.
        **kwargs: passed to :func:`measure_gap` (``folds``, ``permutations``, ``kid_subsets``...).

    Returns:
        ``{"comparisons": {name: measure_gap result}, "note": ...}``, JSON-able.
    """
    bad = [n for n in synthetic if not (isinstance(n, str) and n.isidentifier())]
    if bad or not synthetic:
        raise ValueError(f"synthetic must map plain names to patches, got names {list(synthetic)}")
    out: dict[str, Any] = {"comparisons": {}, "note": (
        "real seed patches vs synthetic patches in each detector family's own features: held-out accuracy of a "
        "logistic regression (0.5 = the detector's features cannot tell them apart), binomial 95 % CI and "
        "one-sided p (somewhat optimistic for pooled k-fold predictions; p_permutation is exact), KID (unbiased "
        "MMD^2, cubic kernel) and the most separating features (Cohen's d > 0: larger in synthetic)")}
    for name, patches in synthetic.items():
        groups = None
        if isinstance(patches, tuple):
            patches, groups = patches
            if real_groups is None:
                raise ValueError(f"synthetic set {name!r} has groups: give real_groups too")
        sub = None if out_dir is None else Path(out_dir) / f"gap_{name}"
        res = measure_gap(real_patches, patches, families, detectors=detectors, seed=seed, out_dir=sub,
                          groups_real=None if groups is None else real_groups, groups_syn=groups, **kwargs)
        for fam in res["families"].values():
            fam["figures"] = {k: f"gap_{name}/{v}" for k, v in fam["figures"].items()}
        out["comparisons"][name] = res
    return out


def training_samples(seedset: Any, mesh: Any, fit_file: str | os.PathLike, count: int, *,
                     seed: int = 0, pose_sampling: str = "uniform") -> tuple[Tensor, np.ndarray]:
    """``count`` synthetic training patches of a fit, and the seed each one comes from.

    The dataset of :func:`synthaug.detectors.training_sets.synthetic_positives` (same arguments, same patches:
    one seed's fitted parameters and background, a random pose — ``pose_sampling="fitted"``: around the seed's
    fitted pose), keeping each item's ``seed_index`` so the two-sample test can hold a seed's real and synthetic
    patches out together.

    Returns:
        ``(patches (count, 1, P, P) float in [0, 1], seed_index (count,) int64)``.
    """
    from synthaug.data.synthetic import SyntheticObjectDataset

    if not isinstance(count, int) or count < 1:
        raise ValueError(f"count must be an int >= 1, got {count!r}")
    p = int(seedset.patches.shape[-1])
    ds = SyntheticObjectDataset(mesh, seedset, params=str(fit_file), length=count, patch_size=p,
                                negative_fraction=0.0, seed=seed, seed_geometry="auto", pose_sampling=pose_sampling)
    items = ds.__getitems__(list(range(count)))
    patches = torch.stack([img for img, _ in items]).float().clamp(0, 1)
    return patches, np.array([int(t["seed_index"]) for _, t in items], dtype=np.int64)


def gap_markdown(section: Mapping[str, Any]) -> list[str]:
    """Markdown lines of a :func:`gap_section` result: one table row per comparison and family, then figures.

    Example:
        >>> rng = np.random.default_rng(0)
        >>> real = rng.integers(0, 255, (20, 40, 40), dtype=np.uint8)
        >>> sec = gap_section(real, {"noisy": real // 2 + 60}, families=("hog",), folds=2, permutations=0,
        ...                   kid_subsets=2)
        >>> [line for line in gap_markdown(sec) if line.startswith("| noisy")][0][:40]
        '| noisy | hog | HOG descriptor (the dete'
    """
    lines = ["## Gap in the detectors' features", "", section.get("note", ""), "",
             "| synthetic | family | features | n real / syn | accuracy [95 % CI] | p (binomial) | p (permutation) "
             "| KID ± std | most separating feature (Cohen's d) |",
             "|---|---|---|---|---|---|---|---|---|"]
    figures: list[tuple[str, str, str]] = []
    for name, res in section["comparisons"].items():
        for fam, r in res["families"].items():
            t, k = r["two_sample"], r["kid"]
            top = r["top_features"][0] if r["top_features"] else None
            pp = "" if t.get("p_permutation") is None else f"{t['p_permutation']:.2g} ({t['permutations']})"
            feats = r["features"].split(":")[0]
            lines.append(
                f"| {name} | {fam} | {feats} | {res['n_real']} / {res['n_synthetic']} | {t['accuracy']:.3f} "
                f"[{t['ci'][0]:.3f}, {t['ci'][1]:.3f}] | {t['p_value']:.2g} | {pp} | {k['mean']:.4g} ± {k['std']:.2g} | "
                + ("" if top is None else f"{top['name']} ({top['effect_size']:+.2f})") + " |")
            figures += [(name, fam, path) for path in r["figures"].values()]
    lines.append("")
    for name, fam, path in figures:
        lines += [f"![{name} {fam}]({path})", ""]
    return lines
