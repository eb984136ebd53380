"""Kernel Inception Distance (Bińkowski et al., ICLR 2018) in any feature space: the unbiased MMD² with
the cubic kernel ``k(x, y) = (x·y / d + 1)³``, mean ± std over random subsets.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from torch import Tensor

from synthaug.diagnose.gap.features import _features_pair


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
