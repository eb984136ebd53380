"""Bootstrap over videos, paired differences, per-video wins and ROC-AUC against independent references."""

from __future__ import annotations

import numpy as np
import pytest

from synthaug.evaluate.ap import average_precision, evaluate_detections, precision_recall
from synthaug.evaluate.stats import (
    PooledRanking,
    bootstrap_seed_mean,
    bootstrap_statistic,
    paired_difference,
    percentile_interval,
    resample_counts,
    resample_indices,
    resample_seed_counts,
    seed_mean_samples,
    video_wins,
)


def _video(rng: np.random.Generator, n_det: int, n_obj: int, p_tp: float) -> tuple[np.ndarray, np.ndarray, int]:
    tp = rng.random(n_det) < p_tp
    tp[np.cumsum(tp) > n_obj] = False  # never more TPs than objects
    return rng.random(n_det), tp, n_obj


def _pool(seed: int, n_videos: int = 6, p_tp: float = 0.4) -> PooledRanking:
    rng = np.random.default_rng(seed)
    return PooledRanking([_video(rng, int(rng.integers(0, 12)), int(rng.integers(0, 5)), p_tp) for _ in range(n_videos)])


def _ap_of(scores: np.ndarray, tp: np.ndarray, n: int) -> float:
    order = np.argsort(-scores, kind="stable")
    p, r, _ = precision_recall(scores[order], tp[order], n)
    return average_precision(p, r)


# --------------------------------------------------------------------------- pooled AP
def test_pooled_ap_is_the_ap_of_the_concatenated_videos() -> None:
    rng = np.random.default_rng(3)
    vids = [_video(rng, 8, 3, 0.5), _video(rng, 0, 2, 0.5), _video(rng, 5, 0, 0.0), _video(rng, 10, 4, 0.3)]
    pool = PooledRanking(vids)
    cat = lambda idx: [np.concatenate([vids[i][k] for i in idx]) for k in (0, 1)]  # noqa: E731
    s, t = cat([0, 1, 2, 3])
    assert pool.ap() == pytest.approx(_ap_of(s, t, 9), abs=1e-12)
    # a multiset: video 3 twice, video 0 once, the others not drawn
    s, t = cat([3, 0, 3])
    assert pool.ap(np.array([1, 0, 0, 2])) == pytest.approx(_ap_of(s, t, 4 + 3 + 4), abs=1e-12)
    # no object in the pool: undefined
    assert np.isnan(pool.ap(np.array([0, 0, 3, 0])))
    # per-video metric = each video alone
    per = pool.per_video()
    assert per[0] == pytest.approx(_ap_of(vids[0][0], vids[0][1], 3)) and np.isnan(per[2]) and per[1] == 0.0


def test_pooled_ap_equals_evaluate_detections_on_frames() -> None:
    """Video lists made by matching frames, pooled: the AP of all frames evaluated at once."""
    from synthaug.evaluate.ap import match_detections

    rng = np.random.default_rng(0)
    videos = []
    for _ in range(5):
        dets, gts = [], []
        for _f in range(6):
            g = rng.uniform(0, 200, (int(rng.integers(0, 3)), 2))
            gts.append(np.c_[g, np.full((len(g), 2), 20.0)] if len(g) else None)
            d = [[x + rng.normal(0, 4), y + rng.normal(0, 4), 20, 20, rng.random()] for x, y in g if rng.random() < 0.7]
            d += [[*rng.uniform(0, 200, 2), 20, 20, rng.random()] for _ in range(int(rng.integers(0, 3)))]
            dets.append(np.array(d, float).reshape(-1, 5))
        videos.append((dets, gts))
    pool = PooledRanking([match_detections(d, g)[:3] for d, g in videos])
    ref = evaluate_detections([f for d, _ in videos for f in d], [f for _, g in videos for f in g])
    assert pool.ap() == pytest.approx(ref.ap, abs=1e-12)


# --------------------------------------------------------------------------- bootstrap vs scipy
def test_bootstrap_of_a_mean_matches_scipy_percentile() -> None:
    """Same Generator seed -> the same resample indices as scipy.stats.bootstrap, so the same interval."""
    from scipy.stats import bootstrap

    x = np.random.default_rng(5).gamma(2.0, 1.0, size=17)
    ours = bootstrap_statistic(lambda c: float(c @ x / c.sum()), x.size, resamples=999, seed=42, ci=0.95)
    ref = bootstrap((x,), np.mean, n_resamples=999, method="percentile", confidence_level=0.95,
                    rng=np.random.default_rng(42), vectorized=True)
    np.testing.assert_allclose(ours.samples, ref.bootstrap_distribution, rtol=0, atol=1e-12)
    assert ours.low == pytest.approx(ref.confidence_interval.low, abs=1e-12)
    assert ours.high == pytest.approx(ref.confidence_interval.high, abs=1e-12)
    assert ours.estimate == pytest.approx(x.mean()) and ours.n_valid == 999


def test_bootstrap_of_a_mean_within_monte_carlo_tolerance_of_scipy() -> None:
    """Different draws (seeds): the intervals agree within Monte Carlo error."""
    from scipy.stats import bootstrap

    x = np.random.default_rng(6).normal(3.0, 1.0, size=30)
    ours = bootstrap_statistic(lambda c: float(c @ x / c.sum()), x.size, resamples=4000, seed=1)
    ref = bootstrap((x,), np.mean, n_resamples=4000, method="percentile", rng=np.random.default_rng(2))
    se = x.std(ddof=1) / np.sqrt(x.size)
    assert abs(ours.low - ref.confidence_interval.low) < 0.1 * se * 4
    assert abs(ours.high - ref.confidence_interval.high) < 0.1 * se * 4


def test_resamples_are_deterministic_and_seeded() -> None:
    a, b, c = resample_indices(7, 50, 3), resample_indices(7, 50, 3), resample_indices(7, 50, 4)
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    counts = resample_counts(a, 7)
    assert counts.shape == (50, 7) and np.all(counts.sum(1) == 7)
    assert np.array_equal(counts[0], np.bincount(a[0], minlength=7))
    pools = {0: _pool(1), 1: _pool(2)}
    r1 = bootstrap_seed_mean(pools, resamples=300, seed=9)
    r2 = bootstrap_seed_mean({0: _pool(1), 1: _pool(2)}, resamples=300, seed=9)
    assert np.array_equal(r1.samples, r2.samples, equal_nan=True) and (r1.low, r1.high) == (r2.low, r2.high)
    r3 = bootstrap_seed_mean(pools, resamples=300, seed=10)
    assert not np.array_equal(r1.samples, r3.samples, equal_nan=True)


def test_seeds_share_each_video_resample() -> None:
    pools = {"a": _pool(1), "b": _pool(2), "c": _pool(3)}
    iv = bootstrap_seed_mean(pools, resamples=200, seed=0, ci=0.9)
    counts = resample_counts(resample_indices(6, 200, 0), 6)
    want = np.array([np.mean([p.ap(c) for p in pools.values()]) for c in counts])
    np.testing.assert_allclose(iv.samples, want, equal_nan=True)
    assert iv.estimate == pytest.approx(np.mean([p.ap() for p in pools.values()]))
    lo, hi = np.quantile(want[~np.isnan(want)], [0.05, 0.95])
    assert (iv.low, iv.high) == (pytest.approx(lo), pytest.approx(hi))
    assert iv.n_valid == int(np.sum(~np.isnan(want)))


def test_percentile_interval_skips_undefined_resamples() -> None:
    s = np.array([np.nan, 1.0, 2.0, 3.0, np.nan, 4.0])
    assert percentile_interval(s, 0.5) == pytest.approx(tuple(np.quantile([1, 2, 3, 4], [0.25, 0.75])))
    assert all(np.isnan(percentile_interval(np.full(3, np.nan), 0.95)))
    with pytest.raises(ValueError, match="ci"):
        percentile_interval(s, 1.0)


# --------------------------------------------------------------------------- seeds resampled too (pigeonhole)
class _TablePool:
    """A duck-typed pool whose metric is the count-weighted mean of one value per video (a linear statistic)."""

    def __init__(self, values: np.ndarray) -> None:
        self.values = np.asarray(values, dtype=np.float64)
        self.n_videos = self.values.size

    def metric(self, name: str, counts: np.ndarray | None = None) -> float:
        c = np.ones(self.n_videos) if counts is None else np.asarray(counts, dtype=np.float64)
        return float(c @ self.values / c.sum())

    def per_video(self, name: str = "ap") -> np.ndarray:
        return self.values.copy()


def _table(y: np.ndarray) -> dict[int, _TablePool]:
    return {i: _TablePool(row) for i, row in enumerate(y)}


def test_seed_resampling_has_the_exact_pigeonhole_variance() -> None:
    """Mean of an S x V table, rows and columns resampled independently: the bootstrap variance is
    E[T^2] - T^2 with T = w' Y z / (S V), E[w w'] = J + I - J/S and E[z z'] = J + I - J/V (multinomial)."""
    rng = np.random.default_rng(0)
    s_, v_ = 5, 9
    y = rng.normal(0, 1, (s_, 1)) + rng.normal(0, 0.5, (1, v_)) + rng.normal(0, 0.3, (s_, v_))
    a = np.ones((s_, s_)) + np.eye(s_) - 1.0 / s_
    b = np.ones((v_, v_)) + np.eye(v_) - 1.0 / v_
    exact = np.sum(a * (y @ b @ y.T)) / (s_ * v_) ** 2 - y.mean() ** 2
    crossed = bootstrap_seed_mean(_table(y), resamples=20000, seed=3, resample_seeds=True)
    videos = bootstrap_seed_mean(_table(y), resamples=20000, seed=3)
    exact_videos = np.sum(np.ones((s_, s_)) * (y @ b @ y.T)) / (s_ * v_) ** 2 - y.mean() ** 2
    assert crossed.estimate == pytest.approx(y.mean()) and np.mean(crossed.samples) == pytest.approx(y.mean(), abs=0.03)
    assert np.var(crossed.samples) == pytest.approx(exact, rel=0.05)
    assert np.var(videos.samples) == pytest.approx(exact_videos, rel=0.05)
    assert exact > 2 * exact_videos  # here the seeds carry most of the spread, which the video bootstrap misses


def test_seed_resampling_matches_scipy_when_only_seeds_differ() -> None:
    """Values constant over videos: the statistic is the mean of the drawn seeds' values, scipy's own bootstrap
    of the seed values with the same Generator (default_rng([seed, 1]))."""
    from scipy.stats import bootstrap

    vals = np.random.default_rng(4).gamma(2.0, 1.0, size=7)
    iv = bootstrap_seed_mean(_table(np.repeat(vals[:, None], 6, axis=1)), resamples=999, seed=11, resample_seeds=True)
    ref = bootstrap((vals,), np.mean, n_resamples=999, method="percentile", rng=np.random.default_rng([11, 1]),
                    vectorized=True)
    np.testing.assert_allclose(iv.samples, ref.bootstrap_distribution, rtol=0, atol=1e-12)
    assert iv.low == pytest.approx(ref.confidence_interval.low)
    assert iv.high == pytest.approx(ref.confidence_interval.high)
    counts = resample_seed_counts(7, 999, 11)
    assert counts.shape == (999, 7) and np.all(counts.sum(1) == 7)
    assert np.array_equal(counts, resample_seed_counts(7, 999, 11))
    assert not np.array_equal(counts, resample_seed_counts(7, 999, 12))


def test_seed_resampling_changes_nothing_when_the_seeds_agree() -> None:
    """Identical detectors under every seed id: the crossed bootstrap is the protocol's video bootstrap."""
    pools = {s: _pool(1) for s in range(4)}
    a = bootstrap_seed_mean(pools, resamples=300, seed=2)
    b = bootstrap_seed_mean(pools, resamples=300, seed=2, resample_seeds=True)
    np.testing.assert_allclose(b.samples, a.samples, rtol=0, atol=1e-12, equal_nan=True)
    assert (a.low, a.high, a.n_valid) == (pytest.approx(b.low), pytest.approx(b.high), b.n_valid)


def test_paired_seed_resampling_keeps_pairs_and_counts_training_randomness() -> None:
    """Condition = baseline + a per-seed shift on every video: over videos the difference is a constant (zero
    width); with the seeds resampled it is the bootstrap of the shifts (a drawn seed brings its pair)."""
    from scipy.stats import bootstrap

    rng = np.random.default_rng(8)
    y = rng.normal(0.5, 0.1, (6, 10))
    shift = rng.normal(0.02, 0.03, 6)
    base, cond = _table(y), _table(y + shift[:, None])
    over_videos = paired_difference(base, cond, resamples=999, seed=5)
    crossed = paired_difference(base, cond, resamples=999, seed=5, resample_seeds=True)
    assert over_videos.difference.high - over_videos.difference.low == pytest.approx(0.0, abs=1e-12)
    assert crossed.difference.estimate == pytest.approx(shift.mean())
    ref = bootstrap((shift,), np.mean, n_resamples=999, method="percentile", rng=np.random.default_rng([5, 1]),
                    vectorized=True)
    np.testing.assert_allclose(crossed.difference.samples, ref.bootstrap_distribution, rtol=0, atol=1e-12)
    assert (over_videos.resampled, crossed.resampled) == ("videos", "seeds and videos")
    assert crossed.to_json()["resampled"] == "seeds and videos"


def test_seed_resampling_is_undefined_only_where_an_undefined_seed_is_drawn() -> None:
    y = np.random.default_rng(1).random((4, 5))
    y[2] = np.nan
    iv = bootstrap_seed_mean(_table(y), resamples=200, seed=0, resample_seeds=True)
    drawn = resample_seed_counts(4, 200, 0)[:, 2] > 0
    assert np.array_equal(np.isnan(iv.samples), drawn) and iv.n_valid == int(np.sum(~drawn)) > 0
    with pytest.raises(ValueError, match="n_seeds"):
        resample_seed_counts(0, 10, 0)
    with pytest.raises(ValueError, match="seed_counts"):
        seed_mean_samples(_table(y), np.ones((3, 5), np.int64), seed_counts=np.ones((3, 2), np.int64))


# --------------------------------------------------------------------------- paired difference
def _hand_pools() -> tuple[dict[int, PooledRanking], dict[int, PooledRanking]]:
    # video 0: 2 objects; video 1: 1 object; video 2: no object (its detections are false positives)
    base = {
        0: PooledRanking([(np.array([0.9, 0.5]), np.array([True, False]), 2), (np.array([0.8]), np.array([False]), 1),
                          (np.array([0.7]), np.array([False]), 0)]),
        1: PooledRanking([(np.array([0.6]), np.array([True]), 2), (np.array([0.95]), np.array([True]), 1),
                          (np.zeros(0), np.zeros(0, bool), 0)]),
    }
    cond = {
        0: PooledRanking([(np.array([0.9, 0.8]), np.array([True, True]), 2), (np.array([0.7]), np.array([True]), 1),
                          (np.array([0.95]), np.array([False]), 0)]),
        1: PooledRanking([(np.array([0.6]), np.array([True]), 2), (np.array([0.5]), np.array([False]), 1),
                          (np.zeros(0), np.zeros(0, bool), 0)]),
        7: PooledRanking([(np.zeros(0), np.zeros(0, bool), 2), (np.zeros(0), np.zeros(0, bool), 1),
                          (np.zeros(0), np.zeros(0, bool), 0)]),  # a seed the baseline lacks: not paired
    }
    return base, cond


def test_paired_difference_hand_computed() -> None:
    base, cond = _hand_pools()
    # pooled, 3 objects:
    # base seed 0: 0.9 T, 0.8 F, 0.7 F, 0.5 F -> AP = 1/3 * 1 = 1/3
    # base seed 1: 0.95 T, 0.6 T -> AP = 1/3 * 1 + 1/3 * 1 = 2/3
    # cond seed 0: 0.95 F, 0.9 T, 0.8 T, 0.7 T -> AP = 1/3 (1/2 + 2/3 + 3/4) = 23/36
    # cond seed 1: 0.6 T, 0.5 F -> AP = 1/3
    assert base[0].ap() == pytest.approx(1 / 3) and base[1].ap() == pytest.approx(2 / 3)
    assert cond[0].ap() == pytest.approx(23 / 36) and cond[1].ap() == pytest.approx(1 / 3)
    pd = paired_difference(base, cond, resamples=64, seed=0, stems=["v0", "v1", "v2"])
    assert pd.seeds == [0, 1]
    assert pd.difference.estimate == pytest.approx((23 / 36 + 1 / 3) / 2 - (1 / 3 + 2 / 3) / 2)
    # one resample by hand: video 1 twice + video 2 (2 objects)
    c = np.array([0, 2, 1])
    # base s0: 0.8 F, 0.8 F, 0.7 F -> 0; base s1: 0.95 T, 0.95 T -> 1
    # cond s0: 0.95 F, 0.7 T, 0.7 T -> p = 2/3 at r = 1 -> 2/3; cond s1: 0.5 F x2 -> 0
    assert base[0].ap(c) == 0.0 and base[1].ap(c) == pytest.approx(1.0)
    assert cond[0].ap(c) == pytest.approx(2 / 3) and cond[1].ap(c) == 0.0
    counts = resample_counts(resample_indices(3, 64, 0), 3)
    want = np.array([np.mean([cond[s].ap(k) for s in (0, 1)]) - np.mean([base[s].ap(k) for s in (0, 1)]) for k in counts])
    np.testing.assert_allclose(pd.difference.samples, want, equal_nan=True)
    # per video (mean over seeds 0 and 1): v0 base (1/2*1 + 1/2*1/2 [0.6 T of 2]) ... computed from the lists:
    # base v0: s0 0.9 T 0.5 F / 2 obj -> 1/2; s1 0.6 T / 2 -> 1/2        -> 1/2
    # cond v0: s0 0.9 T 0.8 T -> 1;           s1 0.6 T -> 1/2            -> 3/4  (improved)
    # base v1: s0 0.8 F -> 0; s1 0.95 T -> 1 -> 1/2;  cond v1: s0 0.7 T -> 1; s1 0.5 F -> 0 -> 1/2 (tied)
    # v2: no object -> excluded
    w = pd.wins
    assert (w.improved, w.worse, w.tied, w.excluded) == (1, 0, 1, 1)
    assert w.share_improved == pytest.approx(0.5)
    assert w.per_video["v0"] == [pytest.approx(0.5), pytest.approx(0.75)] and w.per_video["v2"] == [None, None]
    with pytest.raises(ValueError, match="different seeds"):
        paired_difference(base, cond, resamples=8, require_same_seeds=True)
    with pytest.raises(ValueError, match="no common"):
        paired_difference({5: base[0]}, {6: cond[0]}, resamples=8)


def test_paired_difference_of_a_condition_with_itself_is_zero() -> None:
    pools = {0: _pool(11), 1: _pool(12), 2: _pool(13)}
    pd = paired_difference(pools, {k: _pool(11 + k) for k in range(3)}, resamples=200, seed=0)
    assert pd.difference.estimate == 0.0 and pd.difference.low == 0.0 and pd.difference.high == 0.0
    assert pd.wins.improved == 0 and pd.wins.worse == 0 and not pd.difference.excludes_zero()


def test_paired_interval_is_narrower_than_unpaired_for_correlated_conditions() -> None:
    """The point of pairing: a constant improvement on very different videos is certain."""
    rng = np.random.default_rng(0)
    vids = [_video(rng, 20, 4, float(q)) for q in rng.uniform(0.05, 0.8, 12)]
    better = [(s, t | (rng.random(t.size) < 0.15), n) for s, t, n in vids]
    better = [(s, t & (np.cumsum(t) <= n), n) for s, t, n in better]
    a, b = {0: PooledRanking(vids)}, {0: PooledRanking(better)}
    pd = paired_difference(a, b, resamples=500, seed=0)
    ia, ib = bootstrap_seed_mean(a, resamples=500), bootstrap_seed_mean(b, resamples=500)
    assert pd.difference.estimate > 0
    assert pd.difference.high - pd.difference.low < (ia.high - ia.low) + (ib.high - ib.low)


def test_video_wins_requires_same_videos() -> None:
    with pytest.raises(ValueError, match="same videos"):
        video_wins({0: _pool(1, n_videos=4)}, {0: _pool(1, n_videos=5)})


# --------------------------------------------------------------------------- ROC-AUC
@pytest.mark.parametrize("seed", range(3))
def test_roc_auc_is_mann_whitney_u(seed: int) -> None:
    from scipy.stats import mannwhitneyu

    rng = np.random.default_rng(seed)
    scores = np.round(rng.normal(size=300), 1)  # many ties
    labels = rng.random(300) < 0.2
    scores[labels] += 0.5
    pool = PooledRanking([(scores[:150], labels[:150], int(labels[:150].sum())),
                          (scores[150:], labels[150:], int(labels[150:].sum()))])
    u = mannwhitneyu(scores[labels], scores[~labels], alternative="two-sided").statistic
    assert pool.roc_auc() == pytest.approx(u / (labels.sum() * (~labels).sum()), abs=1e-12)
    # a multiset: the second video twice
    s2 = np.r_[scores[:150], scores[150:], scores[150:]]
    l2 = np.r_[labels[:150], labels[150:], labels[150:]]
    u2 = mannwhitneyu(s2[l2], s2[~l2]).statistic
    assert pool.roc_auc(np.array([1, 2])) == pytest.approx(u2 / (l2.sum() * (~l2).sum()), abs=1e-12)


def test_roc_auc_edge_cases() -> None:
    assert PooledRanking([(np.array([0.5, 0.5]), np.array([True, False]), 1)]).roc_auc() == 0.5
    assert PooledRanking([(np.array([0.9, 0.1]), np.array([True, False]), 1)]).roc_auc() == 1.0
    assert np.isnan(PooledRanking([(np.array([0.9]), np.array([True]), 1)]).roc_auc())
    assert np.isnan(PooledRanking([(np.zeros(0), np.zeros(0, bool), 0)]).roc_auc())
