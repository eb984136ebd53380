"""Which features separate real from synthetic patches: effect sizes (Cohen's d) per feature, the
logistic weights beside, and HOG features averaged per cell and orientation.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
from torch import Tensor

from synthaug.diagnose.gap.features import _features_pair, hog_feature_layout


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
