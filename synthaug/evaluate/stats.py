"""Uncertainty of a detector's score on test *videos*: bootstrap CIs, paired differences, per-video wins.

The unit of resampling is the **test video**, never the frame: frames of one
video are near duplicates, so a frame bootstrap would claim far too much
certainty. One bootstrap resample draws ``V`` videos with replacement out of
the ``V`` test videos; a video drawn twice counts twice (its detections and its
objects enter the pool twice). The statistic of a resample is

- **AP of the pool** (:meth:`PooledRanking.ap`): the per-video ranked lists
  ``(score, is_tp)`` of the drawn videos are pooled into one ranking and scored
  with the project's one AP (:func:`synthaug.evaluate.ap.precision_recall` +
  :func:`~synthaug.evaluate.ap.average_precision`: ``∫ p(r) dr`` of the step
  curve, ties entering together); nothing is re-matched, so AP can be recomputed
  for any multiset of videos without running detection again;
- with several **training seeds**, the *mean over seeds* of the pooled AP, every
  seed scored on the **same** video resample (seeds inside the resample);
- the **percentile** interval: the ``(1 - ci) / 2`` and ``(1 + ci) / 2``
  quantiles (linear interpolation, ``np.quantile``'s default, as
  ``scipy.stats.bootstrap(method="percentile")``) of the resample statistics.

Every draw comes from :func:`resample_indices`: ``np.random.default_rng(seed)
.integers(0, V, size=(B, V))``, one explicit Generator seeded from the
protocol, so the same ``(V, B, seed)`` gives the same resamples for every
condition — that is what makes a **paired difference** paired: two conditions
(same seeds, matched by seed id; same videos) are scored on the same resamples
and the interval is the one of the per-resample difference of their seed means.
(These are also the indices scipy.stats.bootstrap draws from a Generator with the
same seed, which the tests use.)

Resamples whose pool holds no ground-truth object (possible when few test videos
have objects) have no AP: they are dropped from the percentile (``n_valid``
says how many were kept).

**Training randomness** (``resample_seeds=True``): the video bootstrap holds
every training seed's detector fixed, so its interval says how much the test
videos move a score, not how much another training run would (another seed
set, fit or synthetic draw: issue 16 measured single HOG cells moving 0.06 AP
with a refit). Resampling the seeds as well is the **pigeonhole bootstrap** of a
crossed seeds x videos design (Owen 2007, *Ann. Appl. Stat.* 1(1)): in resample
``b`` the ``V`` videos are drawn as above and, independently, ``S`` seed ids
with replacement from the ``S`` seeds (:func:`resample_seed_counts`); the
statistic is the mean over the drawn seeds (with multiplicity) of each seed's
pooled metric on the drawn videos. The video draws are the protocol's own, so
the per-seed APs are the memoised ones: the second interval costs nothing more.
For the mean of a seeds x videos table ``Y`` its bootstrap variance is exactly
``sum(A * (Y @ B @ Y.T)) / (S V)**2 - mean(Y)**2`` with ``A = J + I - J/S`` and
``B = J + I - J/V`` (``J`` all ones; the multinomial moments, checked in the
tests): the seeds' and the videos' variances plus their interaction, which it
counts more than once (mildly conservative, Owen's result). With few seeds
the seed part is coarse: ``S`` seeds give only ``C(2S-1, S)`` distinct seed
multisets (10 for 3 seeds) and the bootstrap's seed variance is ``(S-1)/S`` of
the sample's; read it with ≥ 5 seeds.

**Share of videos improved** (:func:`video_wins`): for each test video its own
AP (mean over the seeds) under both conditions; a video *improved* when the AP
rose by more than ``tol`` (1e-9), got *worse* when it fell by more, else *tied*.
Videos with no labelled object have no AP (every detection there is a false
positive, and false positives only matter relative to the objects of other
videos) and are **excluded** from the share, reported as ``excluded``.

Cost: one pooled AP is one :func:`~synthaug.evaluate.ap.precision_recall` on the
repeated rows, ≈ 0.5 ms for 10 k detections (16 videos x 60 frames x 10 boxes),
so 2000 resamples x 3 seeds x 2 IoUs take ≈ 6 s per condition on one core; the
results are memoised per multiset, so a paired difference against a condition
already summarised costs nothing more.

ROC-AUC (:meth:`PooledRanking.roc_auc`) is tie-aware: ``P(s⁺ > s⁻) + ½ P(s⁺ = s⁻)``
over (positive, negative) pairs of the pool, the Mann–Whitney ``U / (n⁺ n⁻)``.

Example:
    >>> import numpy as np
    >>> v1 = (np.array([0.9, 0.4]), np.array([True, False]), 1)   # (scores, is_tp, n_objects)
    >>> v2 = (np.array([0.8, 0.7]), np.array([False, True]), 2)
    >>> pool = PooledRanking([v1, v2])
    >>> round(pool.ap(), 4)                          # p = 1, 1/2, 2/3, 2/4 at r = 1/3, 1/3, 2/3, 2/3
    0.5556
    >>> round(pool.ap(np.array([2, 0])), 4)          # video 1 drawn twice: 2 objects, AP 1 * 2/2 (r = 1 at p = 1)
    1.0
    >>> ci = bootstrap_seed_mean({0: pool}, resamples=200, seed=0, ci=0.95)
    >>> ci.low <= ci.estimate <= ci.high
    True
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, Hashable, Mapping, Sequence

import numpy as np

from synthaug.evaluate.ap import average_precision, precision_recall

__all__ = [
    "Ranking",
    "PooledRanking",
    "Interval",
    "PairedDifference",
    "VideoWins",
    "resample_indices",
    "resample_counts",
    "resample_seed_counts",
    "percentile_interval",
    "bootstrap_statistic",
    "seed_mean_samples",
    "bootstrap_seed_mean",
    "paired_difference",
    "video_wins",
]

Ranking = tuple
"""One video's ranked list ``(scores (D,), is_positive (D,), n_positive)``; the scores in any order."""
Metric = str
"""``"ap"`` or ``"roc_auc"``."""


class PooledRanking:
    """The ranked lists of several videos, poolable for any multiset of them.

    Args:
        videos: per video ``(scores, is_positive, n_positive)``: the scores of its
            detections (or patches), whether each is a true positive (an object
            patch), and its number of ground-truth objects (positives), which may
            exceed ``is_positive.sum()`` (missed objects). Order of scores is free.

    The detections of all videos are sorted once by decreasing score (stable:
    video order, then the given order, on ties — the order
    :func:`synthaug.evaluate.ap.match_detections` gives pooled frames); a multiset
    of videos is a vector of ``counts`` (times each video is drawn), applied by
    repeating rows, so the pooled list is exactly the concatenation of the drawn
    videos' lists. Results are memoised per ``counts`` (a bootstrap evaluated
    twice on the same resamples costs once).
    """

    def __init__(self, videos: Sequence[Ranking]) -> None:
        scores, pos, vid, n_pos = [], [], [], []
        for i, v in enumerate(videos):
            if len(v) != 3:
                raise ValueError(f"video {i}: expected (scores, is_positive, n_positive), got {len(v)} items")
            s = np.asarray(v[0], dtype=np.float64).reshape(-1)
            p = np.asarray(v[1], dtype=bool).reshape(-1)
            if s.shape != p.shape:
                raise ValueError(f"video {i}: {s.size} scores but {p.size} is_positive flags")
            if not np.all(np.isfinite(s)):
                raise ValueError(f"video {i}: scores must be finite")
            n = int(v[2])
            if n < 0:
                raise ValueError(f"video {i}: n_positive must be >= 0, got {n}")
            scores.append(s)
            pos.append(p)
            vid.append(np.full(s.size, i, dtype=np.int64))
            n_pos.append(n)
        self.n_videos = len(n_pos)
        s = np.concatenate(scores) if scores else np.zeros(0)
        order = np.argsort(-s, kind="stable")
        self.scores = s[order]
        self.is_positive = (np.concatenate(pos) if pos else np.zeros(0, bool))[order]
        self.video = (np.concatenate(vid) if vid else np.zeros(0, np.int64))[order]
        self.n_positive = np.asarray(n_pos, dtype=np.int64)
        # tie groups of the pooled ranking (for the AUC)
        self._group_start = np.r_[0, np.nonzero(np.diff(self.scores))[0] + 1] if self.scores.size else np.zeros(0, np.int64)
        self._cache: dict[tuple[str, bytes], float] = {}

    def _counts(self, counts: np.ndarray | None) -> np.ndarray:
        if counts is None:
            return np.ones(self.n_videos, dtype=np.int64)
        c = np.asarray(counts)
        if c.shape != (self.n_videos,):
            raise ValueError(f"counts must have shape ({self.n_videos},), got {c.shape}")
        if np.any(c < 0):
            raise ValueError("counts must be >= 0")
        return c.astype(np.int64, copy=False)

    def pooled(self, counts: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, int]:
        """``(scores, is_positive, n_positive)`` of the pool of ``counts`` (default: every video once), sorted."""
        c = self._counts(counts)
        w = c[self.video]
        return np.repeat(self.scores, w), np.repeat(self.is_positive, w), int(c @ self.n_positive)

    def ap(self, counts: np.ndarray | None = None) -> float:
        """AP (``∫ p(r) dr``, :mod:`synthaug.evaluate.ap`) of the pool; NaN when it holds no object."""
        c = self._counts(counts)
        key = ("ap", c.tobytes())
        if key not in self._cache:
            s, t, n = self.pooled(c)
            if n == 0:
                self._cache[key] = float("nan")
            else:
                p, r, _ = precision_recall(s, t, n)
                self._cache[key] = average_precision(p, r)
        return self._cache[key]

    def roc_auc(self, counts: np.ndarray | None = None) -> float:
        """Tie-aware ROC-AUC of the pool (``is_positive`` vs not); NaN without positives or negatives.

        Only meaningful when every positive is in the ranking (patch classification,
        ``n_positive == is_positive.sum()``), not for detections.
        """
        c = self._counts(counts)
        key = ("auc", c.tobytes())
        if key not in self._cache:
            w = c[self.video].astype(np.float64)
            if w.size == 0:
                self._cache[key] = float("nan")
                return self._cache[key]
            pos_g = np.add.reduceat(w * self.is_positive, self._group_start)
            neg_g = np.add.reduceat(w * ~self.is_positive, self._group_start)
            n_pos, n_neg = pos_g.sum(), neg_g.sum()
            if n_pos == 0 or n_neg == 0:
                self._cache[key] = float("nan")
            else:
                above = np.cumsum(pos_g) - pos_g  # positives ranked strictly above each group
                self._cache[key] = float(np.sum(neg_g * (above + 0.5 * pos_g)) / (n_pos * n_neg))
        return self._cache[key]

    def metric(self, name: Metric, counts: np.ndarray | None = None) -> float:
        if name == "ap":
            return self.ap(counts)
        if name == "roc_auc":
            return self.roc_auc(counts)
        raise ValueError(f"unknown metric {name!r}; choose 'ap' or 'roc_auc'")

    def per_video(self, name: Metric = "ap") -> np.ndarray:
        """The metric of each video alone, ``(V,)`` (NaN for a video without objects)."""
        out = np.empty(self.n_videos)
        for v in range(self.n_videos):
            one = np.zeros(self.n_videos, dtype=np.int64)
            one[v] = 1
            out[v] = self.metric(name, one)
        return out


@dataclass
class Interval:
    """A point estimate with its percentile bootstrap interval.

    Attributes:
        estimate: the statistic on the test videos as they are (each once).
        low, high: the interval's ends (NaN when no resample was valid).
        ci: its confidence level (0.95).
        resamples: resamples drawn.
        n_valid: resamples with a defined statistic (a pool with objects).
        samples: the statistic of every resample (NaN where undefined), not serialised.
    """

    estimate: float
    low: float
    high: float
    ci: float
    resamples: int
    n_valid: int
    samples: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)

    def excludes_zero(self) -> bool:
        """The interval lies strictly on one side of 0 (a difference "significant" at level ci)."""
        return bool((self.low > 0 and self.high > 0) or (self.low < 0 and self.high < 0))

    def to_json(self) -> dict[str, Any]:
        return {"estimate": _jf(self.estimate), "low": _jf(self.low), "high": _jf(self.high), "ci": self.ci,
                "resamples": self.resamples, "n_valid": self.n_valid}

    def format(self, digits: int = 3, *, signed: bool = False) -> str:
        """``"0.412 [0.351, 0.470]"`` (``"–"`` for an undefined estimate)."""
        if _nan(self.estimate):
            return "–"
        f = f"{{:+.{digits}f}}" if signed else f"{{:.{digits}f}}"
        if _nan(self.low) or _nan(self.high):
            return f.format(self.estimate)
        return f"{f.format(self.estimate)} [{f.format(self.low)}, {f.format(self.high)}]"


def _nan(x: float) -> bool:
    return x is None or (isinstance(x, float) and math.isnan(x))


def _jf(x: float) -> float | None:
    return None if _nan(x) else float(x)


def resample_indices(n_videos: int, resamples: int, seed: int) -> np.ndarray:
    """The bootstrap's video draws: ``(B, V)`` indices, row ``b`` = the videos of resample ``b``.

    ``np.random.default_rng(seed).integers(0, V, size=(B, V))`` — the only random
    draw of the bootstrap; the same arguments give the same resamples for every
    condition (the pairing of paired differences).

    Example:
        >>> resample_indices(3, 2, seed=0).tolist()
        [[2, 1, 1], [0, 0, 0]]
    """
    if n_videos < 1:
        raise ValueError(f"n_videos must be >= 1, got {n_videos}")
    if resamples < 1:
        raise ValueError(f"resamples must be >= 1, got {resamples}")
    rng = np.random.default_rng(seed)
    return rng.integers(0, n_videos, size=(resamples, n_videos))


def resample_counts(indices: np.ndarray, n_videos: int) -> np.ndarray:
    """``(B, V)`` times each video is drawn in each resample, from :func:`resample_indices`."""
    indices = np.asarray(indices)
    counts = np.zeros((indices.shape[0], n_videos), dtype=np.int64)
    np.add.at(counts, (np.arange(indices.shape[0])[:, None], indices), 1)
    return counts


def resample_seed_counts(n_seeds: int, resamples: int, seed: int) -> np.ndarray:
    """``(B, S)`` times each training seed is drawn in each resample (the seed part of ``resample_seeds``).

    ``np.random.default_rng([seed, 1]).integers(0, S, size=(B, S))``, counted: a stream of its own, so the
    video draws (:func:`resample_indices` with ``seed``) stay the protocol's.

    Example:
        >>> resample_seed_counts(3, 2, seed=0).sum(1).tolist()
        [3, 3]
    """
    if n_seeds < 1:
        raise ValueError(f"n_seeds must be >= 1, got {n_seeds}")
    if resamples < 1:
        raise ValueError(f"resamples must be >= 1, got {resamples}")
    idx = np.random.default_rng([seed, 1]).integers(0, n_seeds, size=(resamples, n_seeds))
    return resample_counts(idx, n_seeds)


def percentile_interval(samples: np.ndarray, ci: float) -> tuple[float, float]:
    """``(low, high)`` = the ``(1-ci)/2`` and ``(1+ci)/2`` quantiles of the defined samples (NaN if none)."""
    if not 0.0 < ci < 1.0:
        raise ValueError(f"ci must be in (0, 1), got {ci}")
    x = np.asarray(samples, dtype=np.float64)
    x = x[~np.isnan(x)]
    if x.size == 0:
        return float("nan"), float("nan")
    lo, hi = np.quantile(x, [(1.0 - ci) / 2.0, (1.0 + ci) / 2.0])
    return float(lo), float(hi)


def bootstrap_statistic(
    statistic: Callable[[np.ndarray], float],
    n_videos: int,
    *,
    resamples: int = 2000,
    seed: int = 0,
    ci: float = 0.95,
) -> Interval:
    """Percentile bootstrap over videos of any statistic of a multiset of videos.

    Args:
        statistic: ``counts (V,) -> float`` (NaN = undefined), ``counts[v]`` = times video ``v``
            is in the multiset; the estimate is ``statistic(ones)``.
        n_videos: V.
        resamples, seed, ci: the protocol's bootstrap settings.

    Returns:
        The :class:`Interval` (with every resample's statistic in ``samples``).

    Example:
        >>> x = np.array([1.0, 2.0, 3.0, 10.0])
        >>> iv = bootstrap_statistic(lambda c: float(c @ x / c.sum()), 4, resamples=500, seed=1)
        >>> iv.estimate, iv.low < 4.0 < iv.high
        (4.0, True)
    """
    counts = resample_counts(resample_indices(n_videos, resamples, seed), n_videos)
    samples = np.array([statistic(c) for c in counts], dtype=np.float64)
    lo, hi = percentile_interval(samples, ci)
    est = float(statistic(np.ones(n_videos, dtype=np.int64)))
    return Interval(est, lo, hi, float(ci), int(resamples), int(np.sum(~np.isnan(samples))), samples)


def _seed_mean(pools: Mapping[Hashable, PooledRanking], metric: Metric, counts: np.ndarray | None) -> float:
    vals = [p.metric(metric, counts) for p in pools.values()]
    if not vals or any(_nan(v) for v in vals):
        return float("nan")
    return float(np.mean(vals))


def _check_pools(pools: Mapping[Hashable, PooledRanking]) -> int:
    if not pools:
        raise ValueError("no training seed: pools is empty")
    ns = {p.n_videos for p in pools.values()}
    if len(ns) != 1:
        raise ValueError(f"every seed must be scored on the same videos, got video counts {sorted(ns)}")
    return ns.pop()


def seed_mean_samples(pools: Mapping[Hashable, PooledRanking], counts: np.ndarray, metric: Metric = "ap",
                      seed_counts: np.ndarray | None = None) -> np.ndarray:
    """``(B,)``: for each resample (row of ``counts``) the mean over seeds of the pooled metric.

    With ``seed_counts`` (``(B, S)``, :func:`resample_seed_counts`; columns in the order of ``pools``) the
    mean of resample ``b`` weighs seed ``s`` by ``seed_counts[b, s]``; NaN when a drawn seed's metric is.
    """
    _check_pools(pools)
    counts = np.asarray(counts)
    if seed_counts is None:
        return np.array([_seed_mean(pools, metric, c) for c in counts], dtype=np.float64)
    w = np.asarray(seed_counts)
    if w.shape != (counts.shape[0], len(pools)):
        raise ValueError(f"seed_counts must have shape ({counts.shape[0]}, {len(pools)}), got {w.shape}")
    m = np.array([[p.metric(metric, c) for p in pools.values()] for c in counts], dtype=np.float64).reshape(w.shape)
    drawn = w > 0
    out = np.sum(np.where(drawn, m, 0.0) * w, axis=1) / np.sum(w, axis=1)
    out[np.any(drawn & np.isnan(m), axis=1)] = np.nan
    return out


def _samples(pools: Mapping[Hashable, PooledRanking], metric: Metric, resamples: int, seed: int,
             resample_seeds: bool) -> np.ndarray:
    """The bootstrap statistic of every resample: videos (the protocol's draws), and seeds when asked."""
    v = _check_pools(pools)
    counts = resample_counts(resample_indices(v, resamples, seed), v)
    w = resample_seed_counts(len(pools), resamples, seed) if resample_seeds else None
    return seed_mean_samples(pools, counts, metric, w)


def bootstrap_seed_mean(
    pools: Mapping[Hashable, PooledRanking],
    *,
    metric: Metric = "ap",
    resamples: int = 2000,
    seed: int = 0,
    ci: float = 0.95,
    resample_seeds: bool = False,
) -> Interval:
    """Mean over training seeds of the pooled metric, with its bootstrap-over-videos interval.

    Args:
        pools: seed id -> the per-video ranked lists of that seed's detector
            (the same videos, in the same order, for every seed).
        metric: ``"ap"`` or ``"roc_auc"``.
        resamples, seed, ci: the protocol's bootstrap settings.
        resample_seeds: also resample the training seeds (the pigeonhole bootstrap of the module's
            docstring): the interval then counts training randomness too.

    Returns:
        The :class:`Interval`; every seed is scored on the same video resample.
    """
    samples = _samples(pools, metric, resamples, seed, resample_seeds)
    lo, hi = percentile_interval(samples, ci)
    return Interval(_seed_mean(pools, metric, None), lo, hi, float(ci), int(resamples),
                    int(np.sum(~np.isnan(samples))), samples)


@dataclass
class VideoWins:
    """How many test videos a condition improved over a baseline (per-video metric, mean over seeds).

    Attributes:
        improved, worse, tied: videos whose metric rose, fell, stayed (within ``tol``).
        excluded: videos without a labelled object (no AP): not in the share.
        share_improved: ``improved / (improved + worse + tied)`` (NaN when no video counts).
        per_video: stem (or index) -> ``[baseline, condition]`` metric (None where undefined).
    """

    improved: int
    worse: int
    tied: int
    excluded: int
    share_improved: float
    per_video: dict[str, list[float | None]] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        return {"improved": self.improved, "worse": self.worse, "tied": self.tied, "excluded": self.excluded,
                "share_improved": _jf(self.share_improved), "per_video": self.per_video}

    def format(self) -> str:
        """``"9/14 (64 %)"`` (+ excluded videos)."""
        n = self.improved + self.worse + self.tied
        if n == 0:
            return "–"
        s = f"{self.improved}/{n} ({100 * self.share_improved:.0f} %)"
        return s


def video_wins(
    baseline: Mapping[Hashable, PooledRanking],
    condition: Mapping[Hashable, PooledRanking],
    *,
    metric: Metric = "ap",
    stems: Sequence[str] | None = None,
    tol: float = 1e-9,
) -> VideoWins:
    """Share of test videos whose own metric (mean over each condition's seeds) improved.

    Videos without a labelled object (metric undefined) are excluded and counted.
    """
    v = _check_pools(baseline)
    if _check_pools(condition) != v:
        raise ValueError("baseline and condition must be scored on the same videos")
    a = np.mean([p.per_video(metric) for p in baseline.values()], axis=0)
    b = np.mean([p.per_video(metric) for p in condition.values()], axis=0)
    names = list(stems) if stems is not None else [str(i) for i in range(v)]
    if len(names) != v:
        raise ValueError(f"{len(names)} stems for {v} videos")
    defined = ~(np.isnan(a) | np.isnan(b))
    d = b - a
    improved = int(np.sum(defined & (d > tol)))
    worse = int(np.sum(defined & (d < -tol)))
    tied = int(np.sum(defined)) - improved - worse
    n = improved + worse + tied
    per_video = {names[i]: [_jf(float(a[i])), _jf(float(b[i]))] for i in range(v)}
    return VideoWins(improved, worse, tied, int(np.sum(~defined)), improved / n if n else float("nan"), per_video)


@dataclass
class PairedDifference:
    """Condition minus baseline on the same seeds and the same video resamples.

    Attributes:
        difference: the mean-over-seeds metric of the condition minus the baseline's,
            with the percentile interval of the per-resample difference.
        seeds: the seed ids used (those both conditions have).
        wins: per-video improvement counts (:func:`video_wins`, on the same seeds).
        resampled: ``"videos"`` (the protocol's bootstrap) or ``"seeds and videos"`` (``resample_seeds``).
    """

    difference: Interval
    seeds: list[Hashable]
    wins: VideoWins
    resampled: str = "videos"

    def to_json(self) -> dict[str, Any]:
        return {"difference": self.difference.to_json(), "seeds": [str(s) for s in self.seeds],
                "wins": self.wins.to_json(), "resampled": self.resampled}


def paired_difference(
    baseline: Mapping[Hashable, PooledRanking],
    condition: Mapping[Hashable, PooledRanking],
    *,
    metric: Metric = "ap",
    resamples: int = 2000,
    seed: int = 0,
    ci: float = 0.95,
    stems: Sequence[str] | None = None,
    require_same_seeds: bool = False,
    resample_seeds: bool = False,
) -> PairedDifference:
    """Paired difference ``condition - baseline`` of the mean-over-seeds metric, bootstrap over videos.

    Seeds are paired by id: only the seeds both conditions have are used (with
    ``require_same_seeds`` any difference in the seed sets is an error). Both
    are scored on the same resamples (:func:`resample_indices` with ``seed``).
    With ``resample_seeds`` the seed ids are resampled too, the same draw for
    both conditions (a drawn id brings its pair): the interval counts training
    randomness (module docstring).

    Raises:
        ValueError: no common seed, or different numbers of videos.
    """
    common = [s for s in baseline if s in condition]
    if not common:
        raise ValueError(f"no common training seed: baseline {sorted(map(str, baseline))}, condition {sorted(map(str, condition))}")
    if require_same_seeds and set(baseline) != set(condition):
        raise ValueError(f"the conditions were trained with different seeds: {sorted(map(str, baseline))} vs {sorted(map(str, condition))}")
    a = {s: baseline[s] for s in common}
    b = {s: condition[s] for s in common}
    v = _check_pools(a)
    if _check_pools(b) != v:
        raise ValueError("baseline and condition must be scored on the same videos")
    diff = _samples(b, metric, resamples, seed, resample_seeds) - _samples(a, metric, resamples, seed, resample_seeds)
    lo, hi = percentile_interval(diff, ci)
    est = _seed_mean(b, metric, None) - _seed_mean(a, metric, None)
    iv = Interval(est, lo, hi, float(ci), int(resamples), int(np.sum(~np.isnan(diff))), diff)
    return PairedDifference(iv, common, video_wins(a, b, metric=metric, stems=stems),
                            "seeds and videos" if resample_seeds else "videos")
