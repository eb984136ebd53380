"""The real-vs-synthetic gap in each detector family's features, all measures together
(:func:`measure_gap`: two-sample test, KID, separating features, figures) as one JSON-able dict.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
from torch import Tensor

from synthaug.diagnose.gap.features import FAMILIES, _float_patches, feature_extractor
from synthaug.diagnose.gap.figures import looks_synthetic_grid, render_cnn_separation, render_hog_glyphs
from synthaug.diagnose.gap.mmd import kid
from synthaug.diagnose.gap.separation import effect_sizes, separating_features
from synthaug.diagnose.gap.two_sample import classifier_two_sample_test


GAP_FORMAT = "synthaug.gap"


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
