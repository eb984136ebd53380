"""Statistics helpers of the diagnosis: a one-sample t-test and within-group permutation
correlation tests (Spearman, Pearson).

They read arrays only (no rendering, no seed sets), so every diagnosis module
can use them without reaching into :mod:`synthaug.diagnose.residuals`.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["t_test", "within_groups", "permutation_spearman", "permutation_correlation"]


def t_test(x: np.ndarray) -> tuple[float, float, float]:
    """One-sample two-sided t-test of mean 0 (normal approximation for the p-value).

    Returns:
        (mean, t, p). NaNs are ignored; fewer than 3 values give (mean, 0, 1).

    Example:
        >>> m, t, p = t_test(np.array([1.0, 1.1, 0.9, 1.05, 0.95]))
        >>> round(m, 2), p < 1e-3
        (1.0, True)
    """
    x = np.asarray(x, np.float64)
    x = x[np.isfinite(x)]
    if len(x) < 3:
        return (float(x.mean()) if len(x) else 0.0), 0.0, 1.0
    m = float(x.mean())
    s = float(x.std(ddof=1))
    if s == 0:
        return m, (0.0 if m == 0 else math.copysign(1e6, m)), (1.0 if m == 0 else 0.0)
    t = m / (s / math.sqrt(len(x)))
    # Student t with n-1 dof
    from scipy import stats

    p = float(2 * stats.t.sf(abs(t), len(x) - 1))
    return m, float(t), p


def _rank(x: np.ndarray) -> np.ndarray:
    from scipy.stats import rankdata

    return rankdata(x)


def within_groups(x: np.ndarray, groups: np.ndarray | None) -> np.ndarray:
    """``x`` minus its group's mean (groups of one seed give NaN); ``x`` itself when ``groups`` is None.

    Example:
        >>> within_groups(np.array([1.0, 3.0, 10.0, 14.0, 5.0]), np.array([0, 0, 1, 1, 2])).tolist()
        [-1.0, 1.0, -2.0, 2.0, nan]
    """
    x = np.asarray(x, np.float64)
    if groups is None:
        return x
    groups = np.asarray(groups)
    out = np.full_like(x, np.nan)
    for g in np.unique(groups):
        sel = groups == g
        if sel.sum() >= 2:
            out[sel] = x[sel] - x[sel].mean()
    return out


def permutation_spearman(x: np.ndarray, y: np.ndarray, rng: np.random.Generator, n_perm: int = 9999,
                         groups: np.ndarray | None = None) -> tuple[float, float]:
    """Spearman's ρ of (x, y) and its two-sided permutation p-value.

    With ``groups`` (e.g. the video of each seed) the dependence is measured
    *within* groups: both variables are centred per group and ``y`` is
    permuted only inside its group, so a per-group nuisance (the light of a
    video) neither creates nor hides a dependence.

    Example:
        >>> rng = np.random.default_rng(0)
        >>> x = np.arange(30.0)
        >>> rho, p = permutation_spearman(x, x + rng.normal(size=30), rng)
        >>> rho > 0.9, p < 0.01
        (True, True)
    """
    return permutation_correlation(x, y, rng, n_perm, groups, method="spearman")


def permutation_correlation(x: np.ndarray, y: np.ndarray, rng: np.random.Generator, n_perm: int = 9999,
                            groups: np.ndarray | None = None, *, method: str = "spearman") -> tuple[float, float]:
    """A correlation of (x, y) (``method`` ``"spearman"``: of ranks; ``"pearson"``: of the values, for a
    dependence known to be linear, where it has more power) and its two-sided permutation p-value, within
    ``groups`` as :func:`permutation_spearman`. The p-value is exact under exchangeability within groups for
    either statistic.

    Example:
        >>> rng = np.random.default_rng(0)
        >>> x = np.arange(30.0)
        >>> r, p = permutation_correlation(x, 2 * x + rng.normal(size=30), rng, method="pearson")
        >>> r > 0.9, p < 0.01
        (True, True)
    """
    if method not in ("spearman", "pearson"):
        raise ValueError(f"method must be 'spearman' or 'pearson', got {method!r}")
    x = within_groups(x, groups)
    y = within_groups(y, groups)
    g = np.zeros(len(x), np.int64) if groups is None else np.unique(np.asarray(groups), return_inverse=True)[1]
    ok = np.isfinite(x) & np.isfinite(y)
    x, y, g = x[ok], y[ok], g[ok]
    if len(x) < 5 or np.ptp(x) == 0 or np.ptp(y) == 0:
        return 0.0, 1.0
    if method == "spearman":
        rx = _rank(x) - (len(x) + 1) / 2
        ry = _rank(y) - (len(y) + 1) / 2
    else:
        rx, ry = x - x.mean(), y - y.mean()
    den = math.sqrt(float((rx * rx).sum() * (ry * ry).sum()))
    rho = float((rx * ry).sum() / den)
    perm = np.tile(np.arange(len(x)), (n_perm, 1))
    for gi in np.unique(g):  # permute inside each group only
        idx = np.nonzero(g == gi)[0]
        perm[:, idx] = idx[rng.permuted(np.tile(np.arange(len(idx)), (n_perm, 1)), axis=1)]
    null = (ry[perm] @ rx) / den
    p = (1 + int((np.abs(null) >= abs(rho) - 1e-12).sum())) / (n_perm + 1)
    return rho, float(p)
