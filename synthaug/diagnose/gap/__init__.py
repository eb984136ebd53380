"""How far synthetic patches are from real seed patches *in a detector's own features* (issue 16, item 1).

A detector never sees pixels: the HOG detector sees HOG blocks, AdaBoost sees
the responses of its Levi–Weiss weak learners, the CNN sees its activations.
Synthetic data can look fine to a person and still be trivially separable in
those features (speckle that buys HOG gradient energy, edge-on poses, a coarse
silhouette). This package measures that gap per detector family, one module a concept:

1. ``features`` — :func:`feature_extractor`: the family's features of a batch of patches,
   reusing the feature maps of :mod:`synthaug.distances` (``hog``,
   ``wl_random`` / ``wl_learned``, ``cnn``);
2. ``two_sample`` — :func:`classifier_two_sample_test`: a classifier two-sample test
   (Lopez-Paz & Oquab, "Revisiting classifier two-sample tests", ICLR 2017):
   held-out accuracy of an L2 logistic regression real vs synthetic, with a
   binomial CI and the one-sided p-value against 0.5 (0.5 = indistinguishable);
3. ``mmd`` — :func:`kid`: the Kernel Inception Distance (Bińkowski et al., "Demystifying
   MMD GANs", ICLR 2018) in the same features: the unbiased MMD² with the cubic
   kernel ``k(x, y) = (x·y / d + 1)³``, mean ± std over random subsets;
4. ``separation`` — :func:`separating_features`: which features separate them most; ``figures`` — the
   pictures: :func:`render_hog_glyphs` (mean HOG glyphs real / synthetic /
   difference), :func:`render_cnn_separation` (the CNN channels that differ
   most), :func:`looks_synthetic_grid` (samples sorted by the classifier's
   held-out "looks synthetic" probability);
5. ``measure`` — :func:`measure_gap`: all of it for several families, as a JSON-able dict;
   ``section`` — :func:`gap_section` and :func:`gap_markdown` make it the ``gap`` section of the
   ``synthaug diagnose`` report (``--gap``).

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

from synthaug.diagnose.gap.features import FAMILIES, FeatureExtractor, feature_extractor, hog_feature_layout
from synthaug.diagnose.gap.figures import looks_synthetic_grid, render_cnn_separation, render_hog_glyphs
from synthaug.diagnose.gap.measure import GAP_FORMAT, measure_gap
from synthaug.diagnose.gap.mmd import KIDResult, kid, mmd2_polynomial
from synthaug.diagnose.gap.section import gap_markdown, gap_section, training_samples
from synthaug.diagnose.gap.separation import effect_sizes, hog_cell_means, separating_features
from synthaug.diagnose.gap.two_sample import TwoSampleTest, binomial_ci, classifier_two_sample_test, fit_logistic

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
