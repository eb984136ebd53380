"""The realism critic (synthaug.detectors.critic) and the synthetic positives it filters (``realism_keep``).

Known answers: synthetic sets mixing patches drawn like the real ones with speckled or striped ones (the critic must
keep the former); the cross-fitting checked by changing one seed's real patch (its own synthetic patches' scores must
not move); the logits checked against scipy's own minimiser of the same penalised logistic objective.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

from synthaug.detectors.critic import fit_logistic, hog_features, least_synthetic, realism_scores, seed_quotas
from test_gap import blobs


def _mixed(n_seeds: int, per_seed: int, seed: int, **odd: object) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Real blobs, and per seed ``per_seed`` synthetic ones: the even-numbered like the real, the odd with ``odd``."""
    real = blobs(n_seeds, seed)
    like = blobs(n_seeds * per_seed, seed + 1)
    unlike = blobs(n_seeds * per_seed, seed + 2, **odd)  # type: ignore[arg-type]
    syn = np.where((np.arange(n_seeds * per_seed) % 2 == 1)[:, None, None], unlike, like)
    groups = np.repeat(np.arange(n_seeds), per_seed)
    return real, syn, groups


@pytest.mark.parametrize("odd", [{"speckle": 0.03}, {"stripes": True}])
def test_the_critic_keeps_the_patches_drawn_like_the_real_ones(odd):
    real, syn, groups = _mixed(40, 4, 10, **odd)
    keep = least_synthetic(real, syn, groups, 80, seed=0)
    assert keep.shape == (80,) and keep.dtype == np.int64 and np.all(np.diff(keep) > 0)
    # the like-the-real half: chance 0.5 (sd 0.056 over 80); measured 0.84 (speckle) and 0.78 (stripes) here,
    # 0.78-0.89 over three draws of the data
    assert (keep % 2 == 0).mean() >= 0.7, (keep % 2 == 0).mean()
    scores = realism_scores(real, syn, groups, seed=0)
    assert scores[1::2].mean() > scores[0::2].mean()


def _hamilton(drawn: np.ndarray, count: int) -> np.ndarray:
    """Hamilton's (largest-remainder) apportionment in exact rational arithmetic, written independently."""
    from fractions import Fraction

    total = int(drawn.sum())
    exact = [Fraction(int(d) * count, total) for d in drawn]
    quota = [int(e) for e in exact]  # floor (non-negative)
    order = sorted(range(len(drawn)), key=lambda i: (-(exact[i] - quota[i]), i))
    for i in order[:count - sum(quota)]:
        quota[i] += 1
    return np.array(quota)


def test_seed_quotas_are_the_largest_remainder_shares():
    assert seed_quotas(np.array([0, 0, 0, 1, 1, 2, 2, 2, 2, 2]), 5).tolist() == [2, 1, 2]  # exact 1.5, 1, 2.5
    assert seed_quotas(np.array([1, 1, 3]), 3).tolist() == [0, 2, 0, 1]  # every draw kept; a seed that drew none
    assert seed_quotas(np.array([0, 1, 2, 3]), 2).tolist() == [1, 1, 0, 0]  # equal remainders: the lower seeds
    assert seed_quotas(np.zeros(0, np.int64), 0).tolist() == []
    rng = np.random.default_rng(0)
    for _ in range(200):
        groups = rng.integers(0, int(rng.integers(1, 30)), int(rng.integers(1, 400)))
        count = int(rng.integers(0, len(groups) + 1))
        q = seed_quotas(groups, count)
        drawn = np.bincount(groups)
        np.testing.assert_array_equal(q, _hamilton(drawn, count))
        assert q.sum() == count and np.all(q <= drawn) and np.all(np.abs(q - drawn * count / len(groups)) < 1)
    with pytest.raises(ValueError, match="count must be"):
        seed_quotas(np.array([0, 1]), 3)


def test_the_seed_selection_keeps_every_seeds_share_and_its_least_synthetic():
    """Seed 0's synthetic patches are all speckled: selecting over the whole set drops (nearly) all of them, selecting
    per seed keeps its share, and within every seed the kept patches are its lowest logits."""
    real, syn, groups = _mixed(12, 8, 60, speckle=0.03)
    syn[groups == 0] = blobs(8, 61, speckle=0.06)
    count = 24
    kwargs = dict(seed=2, folds=2)
    scores = realism_scores(real, syn, groups, **kwargs)
    by_set = least_synthetic(real, syn, groups, count, selection="set", **kwargs)
    by_seed = least_synthetic(real, syn, groups, count, **kwargs)  # the default
    np.testing.assert_array_equal(by_set, np.sort(np.argsort(scores, kind="stable")[:count]))
    assert by_seed.shape == (count,) and by_seed.dtype == np.int64 and np.all(np.diff(by_seed) > 0)
    kept = np.bincount(groups[by_seed], minlength=12)
    np.testing.assert_array_equal(kept, np.full(12, 2))  # 8 drawn a seed, a quarter kept: 2 each
    assert np.bincount(groups[by_set], minlength=12)[0] == 0  # the speckled seed: none kept over the whole set
    for g in range(12):
        mine = np.flatnonzero(groups == g)
        np.testing.assert_array_equal(by_seed[groups[by_seed] == g], np.sort(mine[np.argsort(scores[mine])[:2]]))
    # like-the-real patches still preferred within the seeds (the even half; chance 0.5)
    assert (by_seed % 2 == 0).mean() >= 0.7
    with pytest.raises(ValueError, match="selection must be one of"):
        least_synthetic(real, syn, groups, count, selection="seeds")


def test_a_patch_is_scored_by_a_critic_that_never_saw_its_seed():
    real, syn, groups = _mixed(12, 6, 20, speckle=0.03)
    s0 = realism_scores(real, syn, groups, folds=3, seed=5)
    changed = real.copy()
    changed[4] = blobs(1, 999, stripes=True)[0]  # (255 - x would not do: HOG's orientations are unsigned)
    s1 = realism_scores(changed, syn, groups, folds=3, seed=5)
    np.testing.assert_array_equal(s1[groups == 4], s0[groups == 4])  # seed 4's own critic saw none of it
    assert not np.allclose(s1, s0)  # the other parts' critics did train on it
    # the parts are a function of the seed only: another seed moves them
    assert not np.allclose(realism_scores(real, syn, groups, folds=3, seed=6), s0)


def test_scores_are_the_logits_of_scipys_optimum_on_each_part():
    """Two parts, given by the same generator as the critic's: each part's logits are x·w + b of the minimiser of
    sum log(1 + exp(-s (x·w + b))) + |w|² / (2C) on the other part, features standardised there (scipy L-BFGS)."""
    from scipy.optimize import minimize

    real, syn, groups = _mixed(10, 3, 30, speckle=0.03)
    n = len(real)
    scores = realism_scores(real, syn, groups, folds=2, synthetic_per_real=3, C=0.5, seed=7)
    rng = np.random.default_rng(7)
    part = np.empty(n, np.int64)
    for j, idx in enumerate(np.array_split(rng.permutation(n), 2)):
        part[idx] = j
    fr, fs = hog_features(real), hog_features(syn)
    for j in range(2):
        x = np.concatenate([fr[part != j], fs[part[groups] != j]])  # 3 per real seed: no subsample
        y = np.r_[np.zeros((part != j).sum()), np.ones((part[groups] != j).sum())]
        mu, sd = x.mean(0), x.std(0)
        sd = np.where(sd > 1e-12, sd, 1.0)
        z = (x - mu) / sd
        s = 2 * y - 1

        def objective(theta: np.ndarray) -> tuple[float, np.ndarray]:
            m = s * (z @ theta[:-1] + theta[-1])
            sig = 1 / (1 + np.exp(m))
            grad_m = -s * sig
            f = np.logaddexp(0, -m).sum() + theta[:-1] @ theta[:-1] / (2 * 0.5)
            return f, np.r_[z.T @ grad_m + theta[:-1] / 0.5, grad_m.sum()]

        res = minimize(objective, np.zeros(z.shape[1] + 1), jac=True, method="L-BFGS-B",
                       options={"maxiter": 5000, "gtol": 1e-10, "ftol": 1e-14})
        mine = part[groups] == j
        expected = ((fs[mine] - mu) / sd) @ res.x[:-1] + res.x[-1]
        np.testing.assert_allclose(scores[mine], expected, rtol=1e-4, atol=1e-4)


def test_the_critic_and_the_two_sample_test_share_classifier_and_features():
    import synthaug.diagnose.gap as gap

    assert gap.fit_logistic is fit_logistic
    x = blobs(5, 50)  # uint8 as a seed set stores them, and the same as float
    np.testing.assert_array_equal(hog_features(x), gap.feature_extractor("hog")(x))
    np.testing.assert_array_equal(hog_features(torch.from_numpy(x)[:, None].float() / 255), hog_features(x))


def test_bad_inputs_are_refused():
    real, syn, groups = _mixed(4, 2, 40)
    with pytest.raises(ValueError, match="folds"):
        realism_scores(real, syn, groups, folds=5)
    with pytest.raises(ValueError, match="folds"):
        realism_scores(real, syn, groups, folds=1)
    with pytest.raises(ValueError, match=r"groups must lie in \[0, 4\)"):
        realism_scores(real, syn, groups + 1)
    with pytest.raises(ValueError, match="groups must be"):
        realism_scores(real, syn, groups[:-1])
    with pytest.raises(ValueError, match="synthetic_per_real"):
        realism_scores(real, syn, groups, synthetic_per_real=0)
    with pytest.raises(ValueError, match="count must be"):
        least_synthetic(real, syn, groups, len(syn) + 1)
    with pytest.raises(ValueError, match=r"patches must be \(N, 1, 40, 40\)"):
        hog_features(np.zeros((2, 3, 40, 40), np.uint8))
    with pytest.raises(ValueError, match="patches must be a torch.Tensor"):
        hog_features([[0.0]])
    # every synthetic patch drawn with seeds of one part: the other part's critic has no synthetic example
    with pytest.raises(ValueError, match="no synthetic patch"):
        realism_scores(real, syn[:2], np.zeros(2, np.int64), folds=4)


@pytest.fixture(scope="module")
def seeds_and_fit(tmp_path_factory):
    from synthaug.data.procedural import sky_backgrounds
    from synthaug.data.seedset import SeedSet, write_seedset
    from synthaug.params import CaptureParams

    root = tmp_path_factory.mktemp("critic")
    n = 6
    bgs = sky_backgrounds(n, (40, 40), seed=0)
    write_seedset(root / "s", patches=bgs, backgrounds=bgs, boxes=[[0, 0, 16, 16]] * n, centres=[[20, 20]] * n,
                  crops=[[20, 20, 40]] * n, records=[{"video": "v"}] * n,
                  frames=list(sky_backgrounds(n, (64, 64), seed=1)),
                  background_frames=list(sky_backgrounds(n, (64, 64), seed=1)),
                  metadata={"patch_size": 40, "object_fraction": 0.7})
    fit = root / "fit.json"
    CaptureParams.sample(n, generator=torch.Generator().manual_seed(0)).save(fit)
    return SeedSet.load(root / "s"), fit


def test_synthetic_positives_keep_the_least_synthetic_of_a_larger_draw(seeds_and_fit):
    from synthaug.detectors.training_sets import synthetic_positives

    seeds, fit = seeds_and_fit
    plain, plain_idx = synthetic_positives(seeds, "quadcopter", fit, 12, seed=3, return_seed_index=True)
    pool, pool_idx = synthetic_positives(seeds, "quadcopter", fit, 30, seed=3, return_seed_index=True)
    torch.testing.assert_close(pool[:12], plain)  # the first draws are the unfiltered set's
    np.testing.assert_array_equal(pool_idx[:12], plain_idx)
    kept, kept_idx = synthetic_positives(seeds, "quadcopter", fit, 12, seed=3, realism_keep=0.4, batch=7,
                                         return_seed_index=True)
    keep = least_synthetic(np.asarray(seeds.patches), pool, pool_idx, 12, seed=3)
    torch.testing.assert_close(kept, pool[torch.from_numpy(keep)])
    np.testing.assert_array_equal(kept_idx, pool_idx[keep])
    assert not torch.equal(kept, plain)
    # 8 bits: the critic sees the rounded patches, as training does
    q = synthetic_positives(seeds, "quadcopter", fit, 12, seed=3, realism_keep=0.4, quantize=True)
    torch.testing.assert_close(q * 255, (q * 255).round(), rtol=0, atol=1e-4)
    torch.testing.assert_close(synthetic_positives(seeds, "quadcopter", fit, 12, seed=3, realism_keep=1.0), plain)
    for bad in (0.0, 1.5, -0.2):
        with pytest.raises(ValueError, match="realism_keep"):
            synthetic_positives(seeds, "quadcopter", fit, 4, realism_keep=bad)
    # the default keeps each seed's share of the draw (seed_quotas), its least synthetic; "set" the whole draw's
    np.testing.assert_array_equal(np.bincount(kept_idx, minlength=6), seed_quotas(pool_idx, 12))
    by_set = synthetic_positives(seeds, "quadcopter", fit, 12, seed=3, realism_keep=0.4, realism_selection="set")
    keep = least_synthetic(np.asarray(seeds.patches), pool, pool_idx, 12, seed=3, selection="set")
    torch.testing.assert_close(by_set, pool[torch.from_numpy(keep)])
    with pytest.raises(ValueError, match="realism_selection"):
        synthetic_positives(seeds, "quadcopter", fit, 4, realism_keep=0.5, realism_selection="video")


def test_a_one_seed_set_cannot_be_filtered(tmp_path):
    from synthaug.data.procedural import sky_backgrounds
    from synthaug.data.seedset import SeedSet, write_seedset
    from synthaug.detectors.training_sets import synthetic_positives
    from synthaug.params import CaptureParams

    bgs = sky_backgrounds(1, (40, 40), seed=0)
    write_seedset(tmp_path / "s", patches=bgs, backgrounds=bgs, boxes=[[0, 0, 16, 16]], centres=[[20, 20]],
                  crops=[[20, 20, 40]], records=[{"video": "v"}], frames=list(sky_backgrounds(1, (64, 64), seed=1)),
                  background_frames=list(sky_backgrounds(1, (64, 64), seed=1)),
                  metadata={"patch_size": 40, "object_fraction": 0.7})
    fit = tmp_path / "fit.json"
    CaptureParams.sample(1, generator=torch.Generator().manual_seed(0)).save(fit)
    with pytest.raises(ValueError, match=">= 2 seeds"):
        synthetic_positives(SeedSet.load(tmp_path / "s"), "quadcopter", fit, 4, realism_keep=0.5)
