"""The realism critic (synthaug.detectors.critic) and the synthetic positives it filters (``realism_keep``).

Known answers: synthetic sets mixing patches drawn like the real ones with speckled or striped ones (the critic must
keep the former); the cross-fitting checked by changing one seed's real patch (its own synthetic patches' scores must
not move); the logits checked against scipy's own minimiser of the same penalised logistic objective.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

from synthaug.detectors.critic import (fit_logistic, hog_features, least_synthetic, realism_scores, seed_quotas,
                                       weak_learner_features)
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


@pytest.mark.parametrize("odd", [{"speckle": 0.03}, {"stripes": True}])
def test_the_weak_learner_critic_keeps_the_patches_drawn_like_the_real_ones(odd):
    real, syn, groups = _mixed(40, 4, 10, **odd)
    keep = least_synthetic(real, syn, groups, 80, seed=0, features="weak_learners")
    assert keep.shape == (80,) and keep.dtype == np.int64 and np.all(np.diff(keep) > 0)
    # the like-the-real half: chance 0.5 (sd 0.056 over 80)
    assert (keep % 2 == 0).mean() >= 0.7, (keep % 2 == 0).mean()
    scores = realism_scores(real, syn, groups, seed=0, features="weak_learners")
    assert scores[1::2].mean() > scores[0::2].mean()
    assert not np.allclose(scores, realism_scores(real, syn, groups, seed=0))  # HOG's critic is another one
    with pytest.raises(ValueError, match="features must be one of"):
        realism_scores(real, syn, groups, features="cnn")
    # the lazy selection scores in HOG: refused with another critic's features, wherever it is asked for
    from synthaug.detectors.critic import check_realism_features
    from synthaug.detectors.video_training import AddedPositives

    assert check_realism_features("weak_learners", selection="set") == "weak_learners"
    assert check_realism_features("hog", selection="item") == "hog"
    with pytest.raises(ValueError, match="'item' scores candidates in HOG features"):
        check_realism_features("weak_learners", selection="item")
    with pytest.raises(ValueError, match="'item' scores candidates in HOG features"):
        AddedPositives(realism_selection="item", realism_features="weak_learners")
    with pytest.raises(ValueError, match="realism_features must be one of"):
        AddedPositives(realism_features="cnn")


def test_weak_learner_features_are_adaboosts_energies_of_random_rectangles():
    """Hand-computed: a step edge between columns 19 and 20 puts all of a straddling rectangle's gradient in one
    orientation bin (E = 1 there, 0 in the others, up to eps) and none in a flat one (E = 0 outside bin 0). The
    rectangles are d_WL^R's (``WeakLearners.random`` with the same generator), and the floor is AdaBoost's:
    E = G_o / (G + eps + floor · gradient_level(reference) · |R|)."""
    from synthaug.detectors.adaboost import gradient_level
    from synthaug.detectors.weak_learners import DEFAULT_EPS, WeakLearners, orientation_integrals

    step = np.zeros((1, 40, 40), np.uint8)
    step[:, :, 20:] = 200
    e = weak_learner_features(step, step, n=500, seed=3, floor=0)
    wl = WeakLearners.random(500, 40, generator=torch.Generator().manual_seed(3))
    r = wl.rects.numpy()
    straddles = (r[:, 1] <= 18) & (r[:, 1] + r[:, 3] >= 22)
    flat = (r[:, 1] + r[:, 3] <= 18) | (r[:, 1] >= 22)
    assert straddles.sum() > 50 and flat.sum() > 50
    on = e[0, straddles]
    assert np.all((on < 1e-6) | (on > 0.999)) and 0 < (on > 0.5).mean() < 1  # one bin of four holds it all (eps)
    assert len(set(wl.orientations.numpy()[straddles][on > 0.5])) == 1
    # flat: no gradient but the magnitude's own 1e-6, which the gradient code files under bin 0
    np.testing.assert_array_equal(e[0, flat & (wl.orientations.numpy() != 0)], 0)
    tiny = flat & (wl.orientations.numpy() == 0)
    area = r[tiny, 2] * r[tiny, 3] * 1e-6
    np.testing.assert_allclose(e[0, tiny], area / (area + DEFAULT_EPS), rtol=1e-9)
    # the same rectangles as d_WL^R's learners, and their energies at floor 0
    x = (torch.from_numpy(blobs(6, 70))[:, None] / 255).double()  # float32 values, as detectors read patches
    np.testing.assert_allclose(weak_learner_features(x, x, n=300, seed=9, floor=0),
                               wl_energies := WeakLearners.random(300, 40, generator=torch.Generator().manual_seed(9),
                                                                  ).energies(x).numpy(), rtol=1e-12)
    # the floor: G and G_o from the orientation integrals, the floor's unit the reference's gradient level
    ref = (torch.from_numpy(blobs(8, 71))[:, None] / 255).double()
    floored = weak_learner_features(x, ref, n=300, seed=9, floor=2.0)
    level = 2.0 * gradient_level(ref)
    lw = WeakLearners.random(300, 40, generator=torch.Generator().manual_seed(9))
    ii = orientation_integrals(x, 4).numpy()
    y0, x0, h, w = (lw.rects.numpy()[:, k] for k in range(4))

    def box(a: np.ndarray) -> np.ndarray:
        return a[..., y0 + h, x0 + w] - a[..., y0, x0 + w] - a[..., y0 + h, x0] + a[..., y0, x0]

    g_o = box(ii)[:, lw.orientations.numpy(), np.arange(300)]
    g = box(ii.sum(1))
    np.testing.assert_allclose(floored, g_o / (g + DEFAULT_EPS + level * h * w), rtol=1e-10, atol=1e-12)
    assert np.all(floored <= wl_energies + 1e-12) and floored.shape == (6, 300)
    with pytest.raises(ValueError, match="same size"):
        weak_learner_features(x, ref[..., :32, :32])
    with pytest.raises(ValueError, match="n must be"):
        weak_learner_features(x, ref, n=0)


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


@pytest.mark.slow
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
    # a critic in AdaBoost's features keeps its own least synthetic of the same draw
    wl, wl_idx = synthetic_positives(seeds, "quadcopter", fit, 12, seed=3, realism_keep=0.4,
                                     realism_features="weak_learners", return_seed_index=True)
    keep = least_synthetic(np.asarray(seeds.patches), pool, pool_idx, 12, seed=3, features="weak_learners")
    torch.testing.assert_close(wl, pool[torch.from_numpy(keep)])
    np.testing.assert_array_equal(wl_idx, pool_idx[keep])
    with pytest.raises(ValueError, match="'item' scores candidates"):
        synthetic_positives(seeds, "quadcopter", fit, 4, realism_keep=0.5, realism_selection="item",
                            realism_features="weak_learners")


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


@pytest.mark.slow
def test_native_scale_rounds_the_seeds_seen_at_their_own_size_before_the_critic(tmp_path, monkeypatch):
    """``quantize="native_scale"``: the draws of the seeds whose crop side is at most 1/sqrt(0.8) patch sides are
    rounded to 8 bits, the others stay float, then the critic keeps its least synthetic (what training sees), the
    same items as the plain draw; every seed rounded is ``quantize=True``'s draw, none the float draw."""
    import synthaug.detectors.training_sets as training_sets
    from synthaug.data.procedural import sky_backgrounds
    from synthaug.data.seedset import SeedSet, write_seedset
    from synthaug.detectors.training_sets import native_scale_seeds, synthetic_positives
    from synthaug.params import CaptureParams

    sides = [40, 60, 44, 45, 30, 56]  # / 40: 1.0, 1.5, 1.1, 1.125, 0.75, 1.4; the threshold 1.118
    n, p = len(sides), 40
    bgs = sky_backgrounds(n, (p, p), seed=0)
    write_seedset(tmp_path / "s", patches=bgs, backgrounds=bgs, boxes=[[0, 0, 16, 16]] * n, centres=[[32, 32]] * n,
                  crops=[[32, 32, s] for s in sides], records=[{"video": "v"}] * n,
                  frames=list(sky_backgrounds(n, (64, 64), seed=1)),
                  background_frames=list(sky_backgrounds(n, (64, 64), seed=1)),
                  metadata={"patch_size": p, "object_fraction": 0.7})
    seeds = SeedSet.load(tmp_path / "s")
    fit = tmp_path / "fit.json"
    CaptureParams.sample(n, generator=torch.Generator().manual_seed(0)).save(fit)
    rounded = np.array([s / p <= 1 / np.sqrt(0.8) for s in sides])
    np.testing.assert_array_equal(native_scale_seeds(seeds), rounded)
    np.testing.assert_array_equal(rounded, [True, False, True, False, True, False])
    # the reference: every candidate drawn in float, the rounded seeds' rows rounded (numpy), the critic's quarter
    pool, idx = synthetic_positives(seeds, "quadcopter", fit, 48, seed=3, return_seed_index=True)
    ref = pool.numpy().copy()
    ref[rounded[idx]] = np.round(ref[rounded[idx]] * 255) / 255
    keep = least_synthetic(np.asarray(seeds.patches), torch.from_numpy(ref), idx, 12, seed=3,
                           features="weak_learners")
    out, out_idx = synthetic_positives(seeds, "quadcopter", fit, 12, seed=3, realism_keep=0.25,
                                       realism_features="weak_learners", quantize="native_scale",
                                       return_seed_index=True)
    np.testing.assert_array_equal(out_idx, idx[keep])
    np.testing.assert_allclose(out.numpy(), ref[keep], atol=1e-6, rtol=0)
    on_lattice = np.abs(out.numpy() * 255 - np.round(out.numpy() * 255)).max(axis=(1, 2, 3)) < 1e-4
    np.testing.assert_array_equal(on_lattice, rounded[out_idx])  # rendered values are off the lattice
    plain = synthetic_positives(seeds, "quadcopter", fit, 12, seed=3, quantize="native_scale")
    torch.testing.assert_close(plain[torch.from_numpy(rounded[idx[:12]])],
                               torch.from_numpy(ref[:12][rounded[idx[:12]]]), atol=1e-6, rtol=0)
    # the two ends: every seed rounded is quantize=True's draw, none the float draw
    for limit, quantize in ((np.inf, True), (0.0, False)):
        monkeypatch.setattr(training_sets, "NATIVE_SCALE_MAX", limit)
        torch.testing.assert_close(
            synthetic_positives(seeds, "quadcopter", fit, 12, seed=3, realism_keep=0.25, quantize="native_scale"),
            synthetic_positives(seeds, "quadcopter", fit, 12, seed=3, realism_keep=0.25, quantize=quantize))
    for bad in ("on", 1, None):
        with pytest.raises(ValueError, match="quantize must be one of"):
            synthetic_positives(seeds, "quadcopter", fit, 4, quantize=bad)


# ------------------------------------------------------------------ the critic in SyntheticObjectDataset (lazy form)
class _Brightness:
    """A toy critic (picklable, module level): a patch looks the more synthetic the brighter it is."""

    def __call__(self, patches, seed_index):
        return patches.float().mean(dim=(1, 2, 3)).double().numpy()


class _Constant:
    def __call__(self, patches, seed_index):
        return np.zeros(len(patches))


class _WrongShape:
    def __call__(self, patches, seed_index):
        return np.zeros(len(patches) + 1)


def _critic_dataset(cache, **kw):
    from synthaug.data.procedural import sky_backgrounds
    from synthaug.data.synthetic import SyntheticObjectDataset

    return SyntheticObjectDataset("quadcopter", list(sky_backgrounds(5, (40, 40), seed=2)), length=40, render=cache,
                                  seed=7, **kw)


def test_a_critic_keeps_each_item_the_least_synthetic_of_its_candidates(small_cache):
    plain = _critic_dataset(small_cache)
    ds = _critic_dataset(small_cache, realism_critic=_Brightness(), realism_candidates=4)
    items, base = ds.__getitems__(list(range(40))), plain.__getitems__(list(range(40)))
    score = _Brightness()
    lower = 0
    for i, ((img, t), (img0, t0)) in enumerate(zip(items, base)):
        p, p0 = ds.make_params(i), plain.make_params(i)
        assert int(t["seed_index"]) == int(t0["seed_index"]) == p.seed_index  # the candidates keep the item's seed
        assert p.negative == p0.negative and int(t["labels"]) == int(t0["labels"])
        torch.testing.assert_close(ds.render(p)[0], img, rtol=0, atol=0)  # render(make_params(i)) is ds[i]
        torch.testing.assert_close(ds[i][0], img, rtol=0, atol=0)  # alone or in a batch: the same item
        if p.negative:  # not scored: the plain draw
            assert p == p0
            continue
        s, s0 = score(img[None], None)[0], score(img0[None], None)[0]
        assert s <= s0  # the first candidate is the plain draw: the kept one is never more synthetic
        lower += s < s0
    # with 4 candidates the plain draw is the least bright in 1 of 4 (ties aside): the others move
    n_obj = sum(not ds.make_params(i).negative for i in range(40))
    assert lower >= 0.5 * n_obj, (lower, n_obj)
    # a critic indifferent to every candidate keeps the first of equal scores: the plain draw
    flat = _critic_dataset(small_cache, realism_critic=_Constant())
    for (img, _), (img0, _) in zip(flat.__getitems__(list(range(40))), base):
        torch.testing.assert_close(img, img0, rtol=0, atol=0)
    # epochs draw new candidates; the same (epoch, index) the same item
    e1 = ds.__getitems__([(1, i) for i in range(10)])
    assert any(not torch.equal(a[0], b[0]) for a, b in zip(e1, items[:10]))
    for a, b in zip(e1, ds.__getitems__([(1, i) for i in range(10)])):
        torch.testing.assert_close(a[0], b[0], rtol=0, atol=0)


def test_a_fitted_critic_travels_to_dataloader_workers(small_cache):
    import pickle

    from torch.utils.data import DataLoader

    from synthaug.data.procedural import sky_backgrounds
    from synthaug.detectors.critic import RealismCritic

    ds = _critic_dataset(small_cache)
    real = sky_backgrounds(5, (40, 40), seed=11)
    critic = RealismCritic.from_dataset(ds, real, folds=2)
    assert critic.n_seeds == 5 and critic.weight.shape[0] == 2
    # from_dataset is fit on the dataset's object draws in index order, before transforms
    # (the default count: 2 * 5 * 5 seeds = 50 objects; the next epochs' draws after the first's 40 items)
    drawn = [p for p in (ds.make_params(i, e) for e in range(3) for i in range(40)) if not p.negative][:50]
    syn = torch.stack([img for img, _ in ds.render(drawn, transformed=False)]).clamp(0, 1)
    groups = np.array([p.seed_index for p in drawn])
    ref = RealismCritic.fit(real, syn, groups, folds=2)
    np.testing.assert_array_equal(critic.weight, ref.weight)
    # the critic scores a patch with the part that never saw its seed: realism_scores' logits
    np.testing.assert_allclose(critic(syn, groups), realism_scores(real, syn, groups, folds=2), rtol=0, atol=1e-12)
    # a colour patch is scored in BT.601 luma (OpenCV's RGB2GRAY weights)
    rgb = torch.stack([syn[:, 0], syn[:, 0].flip(-1), syn[:, 0].flip(-2)], 1)
    luma = (rgb * torch.tensor([0.299, 0.587, 0.114])[None, :, None, None]).sum(1, keepdim=True)
    np.testing.assert_allclose(critic(rgb, groups), critic(luma, groups), rtol=0, atol=1e-4)
    back = pickle.loads(pickle.dumps(critic))
    np.testing.assert_array_equal(back(syn, groups), critic(syn, groups))
    ds.realism_critic = critic
    ref_bytes = [img for img, _ in ds.__getitems__(list(range(12)))]
    for workers in (0, 2):
        loader = DataLoader(ds, batch_size=4, num_workers=workers, multiprocessing_context="fork" if workers else None)
        got = torch.cat([b[0] for b in loader])[:12]
        torch.testing.assert_close(got, torch.stack(ref_bytes), rtol=0, atol=0)


def test_a_bad_critic_is_refused_with_a_clear_message(small_cache):
    from synthaug.data.procedural import sky_backgrounds
    from synthaug.data.synthetic import SyntheticObjectDataset
    from synthaug.detectors.critic import RealismCritic

    with pytest.raises(ValueError, match="realism_candidates"):
        _critic_dataset(small_cache, realism_candidates=1)
    with pytest.raises(ValueError, match="realism_candidates"):
        _critic_dataset(small_cache, realism_critic=_Brightness(), realism_candidates=2.5)
    with pytest.raises(ValueError, match="callable"):
        _critic_dataset(small_cache, realism_critic="hog")
    with pytest.raises(ValueError, match="patch mode"):
        SyntheticObjectDataset("quadcopter", list(sky_backgrounds(2, (160, 160), seed=2)), length=4, mode="frame",
                               render=small_cache, realism_critic=_Brightness())
    ds = _critic_dataset(small_cache, realism_critic=_WrongShape())
    with pytest.raises(ValueError, match="one score per patch"):
        ds.__getitems__(list(range(8)))
    with pytest.raises(ValueError, match="already has a realism_critic"):
        RealismCritic.from_dataset(_critic_dataset(small_cache, realism_critic=_Brightness()),
                                   sky_backgrounds(5, (40, 40), seed=1))
    other = RealismCritic.fit(sky_backgrounds(3, (40, 40), seed=1), sky_backgrounds(9, (40, 40), seed=3),
                              np.repeat(np.arange(3), 3))
    with pytest.raises(ValueError, match="fitted on 3 seeds but this dataset has 5"):
        _critic_dataset(small_cache).realism_critic = other
    with pytest.raises(ValueError, match="no synthetic object"):
        RealismCritic.from_dataset(_critic_dataset(small_cache, negative_fraction=1.0),
                                   sky_backgrounds(5, (40, 40), seed=1))


def test_synthetic_positives_item_selection_keeps_each_draws_seed_and_its_least_synthetic_candidate(seeds_and_fit):
    from synthaug.data.synthetic import SyntheticObjectDataset
    from synthaug.detectors.critic import RealismCritic
    from synthaug.detectors.training_sets import synthetic_positives

    seeds, fit = seeds_and_fit
    plain, plain_idx = synthetic_positives(seeds, "quadcopter", fit, 12, seed=3, return_seed_index=True)
    kept, kept_idx = synthetic_positives(seeds, "quadcopter", fit, 12, seed=3, realism_keep=0.25, batch=5,
                                         realism_selection="item", return_seed_index=True)
    np.testing.assert_array_equal(kept_idx, plain_idx)  # each patch keeps its draw's seed: the shares exactly
    assert kept.shape == plain.shape and not torch.equal(kept, plain)
    # the same dataset, its critic fitted on its own draws: each kept patch scores at most its plain draw
    ds = SyntheticObjectDataset("quadcopter", seeds, params=str(fit), length=12, patch_size=40, negative_fraction=0.0,
                                seed=3)
    critic = RealismCritic.from_dataset(ds, np.asarray(seeds.patches), seed=3)
    s, s0 = critic(kept, kept_idx), critic(plain, plain_idx)
    assert np.all(s <= s0 + 1e-9) and np.sum(s < s0 - 1e-9) >= 6, (s, s0)
    with pytest.raises(ValueError, match="'item' picks among"):
        least_synthetic(np.asarray(seeds.patches), plain, plain_idx, 6, selection="item")
