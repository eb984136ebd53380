"""The ``gap`` section of the ``synthaug diagnose`` report: :func:`measure_gap` against several
synthetic sets (:func:`gap_section`), the fit's training samples it compares (:func:`training_samples`)
and its markdown (:func:`gap_markdown`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
from torch import Tensor

from synthaug.diagnose.gap.features import FAMILIES
from synthaug.diagnose.gap.measure import measure_gap


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


def training_samples(seedset: Any, mesh: Any, fit_file: str | os.PathLike, count: int, *, seed: int = 0,
                     **options: Any) -> tuple[Tensor, np.ndarray]:
    """``count`` synthetic training patches of a fit, and the seed each one comes from.

    :func:`synthaug.detectors.training_sets.synthetic_positives` itself (same arguments, same patches: one seed's
    fitted parameters and background, a random pose), keeping each item's ``seed_index`` (the seed of its capture
    parameters) so the two-sample test can hold a seed's real and synthetic patches out together. ``options`` are
    its keywords (``pose_sampling``, ``object_box``, ``shape_variation``, ``effects``, ``capture_sampling``,
    ``quantize``, ``background_sampling``...), so every way of drawing the training positives is measured here
    too without being listed twice.

    Returns:
        ``(patches (count, 1, P, P) float in [0, 1], seed_index (count,) int64)``.
    """
    from synthaug.detectors.training_sets import synthetic_positives

    if not isinstance(count, int) or count < 1:
        raise ValueError(f"count must be an int >= 1, got {count!r}")
    # passing return_seed_index too is Python's own TypeError ("multiple values for keyword argument")
    return synthetic_positives(seedset, mesh, fit_file, count, seed=seed, return_seed_index=True, **options)


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
