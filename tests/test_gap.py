"""Gap measurement in the detectors' feature spaces (issue 16, item 1): synthaug.diagnose.gap.

Every check is against an independent reference (scipy's binomial intervals and a closed-form Wilson
interval, torchmetrics' KernelInceptionDistance, a double-loop MMD², the logistic regression's optimality
conditions) or a case with a known answer: two draws of one distribution, smooth blobs vs the same blobs
with speckle noise, and blobs with fine vertical stripes added in the top-left 16x16 pixels.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import torch

from synthaug.diagnose.gap import (
    FAMILIES,
    binomial_ci,
    classifier_two_sample_test,
    effect_sizes,
    feature_extractor,
    fit_logistic,
    hog_cell_means,
    kid,
    looks_synthetic_grid,
    measure_gap,
    mmd2_polynomial,
    render_cnn_separation,
    render_hog_glyphs,
    separating_features,
)


def blobs(n: int, seed: int, *, speckle: float = 0.0, stripes: bool = False) -> np.ndarray:
    """uint8 (n, 40, 40): a smooth Gaussian blob (random centre, size, contrast) on a gently sloped background.

    ``speckle``: i.i.d. Gaussian noise of that std added; ``stripes``: vertical stripes of period 4 px and
    amplitude 0.05 in the top-left 16x16 pixels (HOG cells (0..1, 0..1); a period of 2 px would be invisible
    to HOG's centred differences).
    """
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:40, 0:40].astype(float)
    out = np.empty((n, 40, 40))
    for i in range(n):
        cy, cx = 20 + rng.uniform(-3, 3, 2)
        s = rng.uniform(5, 8)
        a = rng.uniform(0.2, 0.4) * rng.choice([-1, 1])
        g = rng.uniform(-0.004, 0.004, 2)
        img = 0.5 + g[0] * (yy - 20) + g[1] * (xx - 20) + a * np.exp(-((yy - cy) ** 2 + (xx - cx) ** 2) / (2 * s * s))
        if speckle:
            img = img + rng.normal(0, speckle, img.shape)
        if stripes:
            img[:16, :16] += 0.05 * (((np.arange(16) // 2) % 2) * 2 - 1)[None, :]
        out[i] = img
    return np.round(np.clip(out, 0, 1) * 255).astype(np.uint8)


@pytest.fixture(scope="module")
def patches() -> dict[str, np.ndarray]:
    return {"real": blobs(100, 1), "same": blobs(100, 2), "speckle": blobs(100, 3, speckle=0.03),
            "stripes": blobs(100, 4, stripes=True)}


# ---------------------------------------------------------------- the two known cases, in every family


@pytest.mark.parametrize("family", FAMILIES)
def test_identical_distributions_are_indistinguishable(patches, family):
    fx = feature_extractor(family, reference=patches["real"])
    fr, fs = fx(patches["real"]), fx(patches["same"])
    t = classifier_two_sample_test(fr, fs, folds=5, seed=0, permutations=19)
    assert abs(t.accuracy - 0.5) < 0.1 and t.p_permutation > 0.05, (t.accuracy, t.p_permutation)
    k = kid(fr, fs, subsets=50, subset_size=50, seed=0)
    assert abs(k.mean) < 2.5 * k.std  # within the spread of the subset estimates: no evidence of a gap


def test_ci_covers_one_half_under_the_null():
    """Twenty independent draws of one distribution (HOG, 40 patches a side): the 95 % Wilson CI covers 0.5
    in most of them and the mean accuracy is 0.5. (Pooled k-fold predictions vary more than a binomial,
    so the coverage is somewhat below 95 %, see classifier_two_sample_test.)"""
    fx = feature_extractor("hog")
    accs, covered = [], 0
    for r in range(20):
        t = classifier_two_sample_test(fx(blobs(40, 1000 + 2 * r)), fx(blobs(40, 1001 + 2 * r)), seed=r)
        accs.append(t.accuracy)
        covered += t.ci[0] <= 0.5 <= t.ci[1]
    assert covered >= 16 and abs(np.mean(accs) - 0.5) < 0.04, (covered, np.mean(accs))


@pytest.mark.parametrize("family", FAMILIES)
def test_speckle_is_detected(patches, family):
    fx = feature_extractor(family, reference=patches["real"])
    fr, fs, f_same = fx(patches["real"]), fx(patches["speckle"]), fx(patches["same"])
    t = classifier_two_sample_test(fr, fs, folds=5, seed=0, permutations=99 if family == "hog" else 0)
    assert t.accuracy > 0.8 and t.p_value < 0.01 and t.ci[0] > 0.5, (t.accuracy, t.p_value)
    if family == "hog":
        assert t.p_permutation == 0.01  # no shuffle of the labels comes close: the smallest p of 99 shuffles
    if family != "cnn":  # KID in an untrained random CNN's features is too noisy for 100 samples
        k = kid(fr, fs, subsets=50, subset_size=50, seed=0)
        k0 = kid(fr, f_same, subsets=50, subset_size=50, seed=0)
        assert k.mean > 5 * k.std and k.mean > 20 * abs(k0.mean), (k, k0)


def test_top_hog_features_are_the_striped_cells(patches):
    """Known answer: the stripes put vertical edges (horizontal gradient: bins 0 and 8 of 9, centred at 10° and
    170°) into cells (0..1, 0..1); the most separating HOG features must all lie there, and those larger in
    synthetic must be those orientation bins."""
    fx = feature_extractor("hog")
    fr, fs = fx(patches["real"]), fx(patches["stripes"])
    t = classifier_two_sample_test(fr, fs, seed=0)
    assert t.accuracy > 0.9
    lay = fx.layout["hog_layout"]
    top = separating_features(fr, fs, names=fx.names, weights=t.weights, top=10)
    for f in top:
        br, bc, cr, cc, o = lay[f["index"]]
        assert br + cr <= 1 and bc + cc <= 1, f["name"]
        if f["effect_size"] > 0:
            assert o in (0, 8), f["name"]
    assert top[0]["effect_size"] > 0 and lay[top[0]["index"]][4] in (0, 8)
    assert top[0]["name"].startswith("cell(")
    # the mean-glyph view says the same: the striped cells gain horizontal-gradient energy
    diff = hog_cell_means(fs, fx.layout["config"], 40) - hog_cell_means(fr, fx.layout["config"], 40)
    gain = diff[..., 0] + diff[..., 8]
    assert np.unravel_index(np.argmax(gain), gain.shape) in {(0, 0), (0, 1), (1, 0), (1, 1)}


# ---------------------------------------------------------------- statistics against independent references


def test_ci_and_p_value_equal_scipy_and_closed_form():
    from scipy.stats import beta, binom, binomtest

    rng = np.random.default_rng(0)
    real, syn = rng.normal(size=(40, 3)), rng.normal(size=(40, 3)) + [0.6, 0, 0]
    t = classifier_two_sample_test(real, syn, folds=4, seed=0)
    k, n = t.n_correct, t.n_test
    assert n == 80 and t.accuracy == k / n
    ref = binomtest(k, n).proportion_ci(0.95, method="wilson")
    assert t.ci == pytest.approx((ref.low, ref.high), abs=1e-12)
    # Wilson score interval, closed form
    z = 1.959963984540054
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z / (1 + z * z / n) * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    assert t.ci == pytest.approx((centre - half, centre + half), abs=1e-9)
    assert t.p_value == pytest.approx(binom.sf(k - 1, n, 0.5), rel=1e-9)
    exact = classifier_two_sample_test(real, syn, folds=4, seed=0, ci_method="exact")
    assert exact.ci == pytest.approx((beta.ppf(0.025, k, n - k + 1), beta.ppf(0.975, k + 1, n - k)), abs=1e-9)
    assert binomial_ci(0, 10)[0] == 0.0 and binomial_ci(10, 10, method="exact")[1] == 1.0


def test_logistic_regression_satisfies_its_optimality_conditions():
    """∇ of Σ log-loss + ||w||²/(2C) vanishes at the returned (w, b): X^T(σ(z) - y) + w/C = 0, Σ(σ(z) - y) = 0."""
    from scipy.special import expit

    rng = np.random.default_rng(1)
    x = rng.normal(size=(60, 7))
    y = (x[:, 0] + 0.5 * rng.normal(size=60) > 0).astype(float)
    for c in (0.1, 1.0, 10.0):
        w, b = fit_logistic(x, y, C=c)
        r = expit(x @ w + b) - y
        assert np.abs(x.T @ r + w / c).max() < 1e-5 and abs(r.sum()) < 1e-5


@pytest.mark.filterwarnings("ignore:Metric `Kernel Inception Distance` will save all extracted features")
def test_kid_equals_torchmetrics_kernel_inception_distance():
    """torchmetrics' KID with a custom feature module (identity: the inputs are the features); with
    subset_size = both set sizes every subset is the whole data, so the random subsets do not matter."""
    from torchmetrics.image.kid import KernelInceptionDistance

    rng = np.random.default_rng(2)
    real, syn = rng.normal(size=(60, 12)), rng.normal(size=(60, 12)) * 1.2 + 0.3
    ref = KernelInceptionDistance(feature=torch.nn.Identity(), subsets=3, subset_size=60)
    ref.update(torch.from_numpy(real), real=True)
    ref.update(torch.from_numpy(syn), real=False)
    ref_mean, ref_std = ref.compute()
    k = kid(real, syn, subsets=3, subset_size=60, seed=0)
    assert k.subset_size == 60
    assert k.mean == pytest.approx(float(ref_mean), abs=1e-6)
    assert k.std == pytest.approx(float(ref_std), abs=1e-6)
    assert mmd2_polynomial(real, syn) == pytest.approx(float(ref_mean), abs=1e-9)


def _mmd2_double_loop(x: np.ndarray, y: np.ndarray) -> float:
    d = x.shape[1]

    def k(a, b):
        return (float(np.dot(a, b)) / d + 1.0) ** 3

    m, n = len(x), len(y)
    sxx = sum(k(x[i], x[j]) for i in range(m) for j in range(m) if i != j)
    syy = sum(k(y[i], y[j]) for i in range(n) for j in range(n) if i != j)
    sxy = sum(k(x[i], y[j]) for i in range(m) for j in range(n))
    return sxx / (m * (m - 1)) + syy / (n * (n - 1)) - 2 * sxy / (m * n)


def test_kid_subsets_equal_a_double_loop_mmd():
    """Unequal set sizes, subsets smaller than both: each subset's MMD² (subsets drawn in the documented order,
    real then synthetic permutation per subset) equals a plain double loop; mean and std are theirs."""
    rng = np.random.default_rng(3)
    real, syn = rng.normal(size=(25, 6)), rng.normal(size=(31, 6)) + 0.5
    assert mmd2_polynomial(real, syn) == pytest.approx(_mmd2_double_loop(real, syn), abs=1e-9)
    k = kid(real, syn, subsets=4, subset_size=12, seed=7)
    draw = np.random.default_rng(7)
    expected = []
    for _ in range(4):
        ir = draw.permutation(25)[:12]
        js = draw.permutation(31)[:12]
        expected.append(_mmd2_double_loop(real[ir], syn[js]))
    np.testing.assert_allclose(k.values, expected, atol=1e-9)
    assert k.mean == pytest.approx(np.mean(expected)) and k.std == pytest.approx(np.std(expected))
    assert kid(real, syn, subsets=2, subset_size=1000).subset_size == 25  # capped at the smaller set


def test_effect_sizes_are_cohens_d():
    rng = np.random.default_rng(4)
    real, syn = rng.normal(size=(30, 3)), rng.normal(size=(20, 3)) * [1, 2, 1] + [0, 0, 1]
    pooled = np.sqrt((29 * real.var(0, ddof=1) + 19 * syn.var(0, ddof=1)) / 48)
    np.testing.assert_allclose(effect_sizes(real, syn), (syn.mean(0) - real.mean(0)) / pooled)
    const = effect_sizes(np.zeros((5, 2)), np.ones((5, 2)) * [0, 1])
    assert const.tolist() == [0.0, 1e12]  # constant in both sets: equal -> 0, different -> perfectly separating
    top = separating_features(real, syn, top=2)
    assert [f["index"] for f in top][0] == 2 and top[0]["weight"] is None


# ---------------------------------------------------------------- determinism, balancing, bad input


def test_same_seed_same_result_and_balanced_subsample():
    rng = np.random.default_rng(5)
    real, syn = rng.normal(size=(30, 4)), rng.normal(size=(70, 4)) + 0.4
    a = classifier_two_sample_test(real, syn, seed=3)
    b = classifier_two_sample_test(real, syn, seed=3)
    c = classifier_two_sample_test(real, syn, seed=4)
    assert a.n_test == 60 and len(a.syn_index) == 30 and len(set(a.syn_index.tolist())) == 30
    assert a.real_index.tolist() == list(range(30))
    for field in ("probabilities", "weights", "syn_index"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
    assert a.as_dict(arrays=True) == b.as_dict(arrays=True)
    assert a.syn_index.tolist() != c.syn_index.tolist()
    np.testing.assert_array_equal(kid(real, syn, subsets=5, subset_size=20, seed=1).values,
                                  kid(real, syn, subsets=5, subset_size=20, seed=1).values)


def test_bad_input_is_named():
    from synthaug.detectors.hog import HOGConfig

    x = np.zeros((10, 3))
    with pytest.raises(ValueError, match="folds must be an int >= 2, got 1"):
        classifier_two_sample_test(x, x, folds=1)
    with pytest.raises(ValueError, match="at least folds=5 samples per class"):
        classifier_two_sample_test(x, x[:4])
    with pytest.raises(ValueError, match="same number of features, got 3 and 2"):
        kid(x, np.zeros((10, 2)))
    with pytest.raises(ValueError, match="syn_feats holds non-finite"):
        classifier_two_sample_test(x, np.full((10, 3), np.nan))
    with pytest.raises(ValueError, match="unknown detector family 'svm'"):
        feature_extractor("svm")
    with pytest.raises(ValueError, match="the cnn family takes a PatchCNN, a CNNDetector or None, got int"):
        feature_extractor("cnn", 3)
    with pytest.raises(ValueError, match="AdaBoostDetector or WeakLearners, got HOGConfig"):
        feature_extractor("adaboost", HOGConfig())
    with pytest.raises(ValueError, match="need 40x40 patches, got \\(32, 32\\)"):
        feature_extractor("cnn")(np.zeros((2, 32, 32), np.uint8))
    with pytest.raises(ValueError, match="families must be a non-empty subset"):
        measure_gap(np.zeros((10, 40, 40), np.uint8), np.zeros((10, 40, 40), np.uint8), families=("hog", "sift"))


# ---------------------------------------------------------------- extractors reuse the distances' features


def test_extractors_reuse_the_distance_features(patches):
    from synthaug.detectors.adaboost import AdaBoostDetector
    from synthaug.detectors.cnn import CNNDetector, PatchCNN
    from synthaug.detectors.hog import hog
    from synthaug.detectors.weak_learners import WeakLearners
    from synthaug.distances.cnn import CNNDistance

    x = torch.from_numpy(patches["real"][:6]).float()[:, None] / 255
    fx = feature_extractor("hog")
    np.testing.assert_allclose(fx(patches["real"][:6]), hog(x).double().numpy())
    np.testing.assert_array_equal(fx(patches["real"][:6]), fx(x))  # uint8 (N, P, P) == float (N, 1, P, P)

    wl = WeakLearners.random(20, generator=torch.Generator().manual_seed(0))
    wl.weights = torch.linspace(0.25, 1.0, 20)
    fa = feature_extractor("adaboost", AdaBoostDetector(wl))
    assert fa.n_features == 20 and "given AdaBoost" in fa.description
    np.testing.assert_allclose(fa(x), (wl.responses(x) * wl.weights.sqrt()).double().numpy(), rtol=1e-6)
    assert feature_extractor("adaboost", n_learners=30, reference=patches["real"]).n_features == 30

    net = PatchCNN(generator=torch.Generator().manual_seed(3))
    fc = feature_extractor("cnn", CNNDetector(net))
    with torch.no_grad():
        np.testing.assert_allclose(fc(x), CNNDistance(PatchCNN(generator=torch.Generator().manual_seed(3)))
                                   .features(x).double().numpy(), rtol=1e-5, atol=1e-6)
    assert all(p.requires_grad for p in net.parameters())  # the caller's network is not frozen
    assert fc.n_features == len(fc.names) == 1377 and fc.names[0] == "layer2 ch0 (0,0)"
    random_cnn = feature_extractor("cnn", seed=5)
    assert "UNTRAINED" in random_cnn.description
    np.testing.assert_array_equal(random_cnn(x), feature_extractor("cnn", seed=5)(x))


def test_measure_gap_is_json_and_writes_figures(tmp_path, patches):
    from PIL import Image

    real, syn = patches["real"][:40], patches["speckle"][:50]
    kw = dict(folds=4, seed=1, kid_subsets=5, kid_subset_size=30, top=3, n_learners=200, permutations=3)
    res = measure_gap(real, syn, out_dir=tmp_path, **kw)
    text = json.dumps(res, allow_nan=False)
    assert json.dumps(measure_gap(real, syn, **kw) | {"families": None}) == json.dumps(res | {"families": None})
    assert res["n_real"] == 40 and res["n_synthetic"] == 50 and set(res["families"]) == set(FAMILIES)
    for fam, r in res["families"].items():
        assert r["two_sample"]["n_test"] == 80 and r["two_sample"]["accuracy"] > 0.8
        assert len(r["top_features"]) == 3 and r["top_features"][0]["weight"] is not None
        for name in r["figures"].values():
            assert Image.open(tmp_path / name).size[0] > 100
    assert set(res["families"]["hog"]["figures"]) == {"samples", "glyphs"}
    assert set(res["families"]["cnn"]["figures"]) == {"samples", "activations"}
    again = measure_gap(real, syn, **kw)
    for fam in FAMILIES:  # same seed, same numbers (figures aside)
        assert again["families"][fam] | {"figures": {}} == res["families"][fam] | {"figures": {}}
    assert "Infinity" not in text and "NaN" not in text


def test_figures_show_the_difference(patches):
    fx = feature_extractor("hog")
    fr, fs = fx(patches["real"][:30]), fx(patches["stripes"][:30])
    img = render_hog_glyphs(fr, fs, fx.layout["config"], 40)
    assert img.ndim == 3 and img.shape[2] == 3 and img.dtype == np.uint8
    red = (img[..., 0] > 150) & (img[..., 1] < 100) & (img[..., 2] < 100)
    assert red.any()  # the difference panel draws glyphs larger in synthetic in red
    t = classifier_two_sample_test(fr, fs, folds=3, seed=0)
    grid = looks_synthetic_grid(patches["real"][:30], patches["stripes"][:30], t, n=4, zoom=1)
    assert grid.dtype == np.uint8 and grid.ndim == 2 and grid.shape[0] > 4 * 40
    fc = feature_extractor("cnn")
    e = effect_sizes(fc(patches["real"][:30]), fc(patches["stripes"][:30]))
    assert render_cnn_separation(e, fc, channels=4).shape[2] == 3
    with pytest.raises(ValueError, match="needs a cnn extractor"):
        render_cnn_separation(e, fx)


def paired_blobs(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Two uint8 (n, 40, 40) sets of one distribution, pair i sharing its blob and background (like a seed and
    its synthetic images): only the blob's centre is drawn anew."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:40, 0:40].astype(float)
    out = np.empty((2, n, 40, 40))
    for i in range(n):
        s, a = rng.uniform(5, 8), rng.uniform(0.2, 0.4) * rng.choice([-1, 1])
        g = rng.uniform(-0.004, 0.004, 2)
        for k in range(2):
            cy, cx = 20 + rng.uniform(-3, 3, 2)
            out[k, i] = (0.5 + g[0] * (yy - 20) + g[1] * (xx - 20)
                         + a * np.exp(-((yy - cy) ** 2 + (xx - cx) ** 2) / (2 * s * s)))
    out = np.round(np.clip(out, 0, 1) * 255).astype(np.uint8)
    return out[0], out[1]


def test_grouped_folds_remove_the_pairing_bias():
    """Known answer: paired draws of one distribution. Folds that split a pair teach the classifier the pair's
    shared background under the other label, and the held-out accuracy falls clearly below 0.5; folds that
    hold each pair out together give an accuracy whose CI covers 0.5."""
    fx = feature_extractor("hog")
    real, syn = paired_blobs(60, 0)
    fr, fs = fx(real), fx(syn)
    split = classifier_two_sample_test(fr, fs, seed=0)
    pairs = np.arange(60)
    grouped = classifier_two_sample_test(fr, fs, seed=0, permutations=19, groups_real=pairs, groups_syn=pairs)
    assert split.ci[1] < 0.5, split.ci
    assert grouped.ci[0] <= 0.5 <= grouped.ci[1] and grouped.p_permutation > 0.05, (grouped.ci, grouped.p_permutation)
    with pytest.raises(ValueError, match="give both groups_real and groups_syn"):
        classifier_two_sample_test(fr, fs, groups_real=pairs)
    with pytest.raises(ValueError, match="at least folds=5 groups, got 3"):
        classifier_two_sample_test(fr, fs, groups_real=pairs % 3, groups_syn=pairs % 3)


def test_gap_section_in_the_diagnosis_markdown(tmp_path, patches):
    """The diagnosis report's gap section (synthaug diagnose --gap): one table row per comparison and family,
    figure links that exist, and a report without the section unchanged."""
    from synthaug.diagnose.gap import gap_section
    from synthaug.diagnose.report import write_markdown

    real, syn = patches["real"][:30], patches["speckle"][:45]
    seed_of = np.arange(30)
    section = gap_section(real, {"training": (syn, np.arange(45) % 30), "fitted": patches["same"][:30]},
                          real_groups=seed_of, families=("hog", "cnn"), folds=3, permutations=2, kid_subsets=3,
                          out_dir=tmp_path)
    assert section["comparisons"]["training"]["grouped_folds"] and not section["comparisons"]["fitted"]["grouped_folds"]
    base = {"inputs": {"seeds": "s", "n_seeds": 30, "mesh": "m", "fit": "f", "distance": "hog", "k_folds": 5,
                       "alpha": 0.01},
            "findings": [], "residuals": {}, "parameter_dependence": [], "screened": [],
            "realism": {"accuracy_base": 0.5}, "seconds": 1.0}
    md = write_markdown({**base, "gap": json.loads(json.dumps(section))})
    assert "## Gap in the detectors' features" not in write_markdown(base)
    rows = [line for line in md.splitlines() if line.startswith(("| training |", "| fitted |"))]
    assert len(rows) == 4 and rows[0].startswith("| training | hog | HOG descriptor")
    links = [line[line.index("(") + 1:-1] for line in md.splitlines() if line.startswith("![")]
    assert "gap_training/gap_hog_glyphs.png" in links and all((tmp_path / p).is_file() for p in links)


def test_diagnose_cli_checks_the_gap_options_first(tmp_path, capsys):
    import argparse

    from synthaug.diagnose import cli

    parser = argparse.ArgumentParser()
    cli.add_arguments(parser)
    base = ["--seeds", str(tmp_path / "none"), "--fit", str(tmp_path / "f.json"), "--out", str(tmp_path / "o")]
    for extra, message in ((["--gap", "2", "--gap-detector", "svm=x.pt"], "--gap-detector must be FAMILY=CHECKPOINT"),
                           (["--gap", "2", "--gap-detector", f"cnn={tmp_path / 'no.pt'}"], "is not a file"),
                           (["--gap-detector", f"hog={tmp_path}"], "--gap-detector needs --gap N"),
                           (["--gap", "-1"], "--gap must be >= 0, got -1")):
        assert cli.main(parser.parse_args(base + extra)) == 2
        assert message in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("pose_sampling, object_box", [("uniform", None), ("fitted", None), ("uniform", "seed")])
def test_training_samples_are_the_detectors_synthetic_positives(tmp_path, pose_sampling, object_box):
    """The gap is measured on the very patches training uses (same fit, seed and pose sampling)."""
    from synthaug.data.procedural import sky_backgrounds
    from synthaug.data.seedset import SeedSet, write_seedset
    from synthaug.detectors.training_sets import synthetic_positives
    from synthaug.diagnose.gap import training_samples
    from synthaug.params import CaptureParams

    n = 4
    bgs = sky_backgrounds(n, (40, 40), seed=0)
    write_seedset(tmp_path / "s", patches=bgs, backgrounds=bgs, boxes=[[0, 0, 16, 16]] * n, centres=[[20, 20]] * n,
                  crops=[[20, 20, 40]] * n, records=[{"video": "v"}] * n, frames=list(sky_backgrounds(n, (64, 64), seed=1)),
                  background_frames=list(sky_backgrounds(n, (64, 64), seed=1)),
                  metadata={"patch_size": 40, "object_fraction": 0.7})
    seeds = SeedSet.load(tmp_path / "s")
    fit = tmp_path / "fit.json"
    CaptureParams.sample(n, generator=torch.Generator().manual_seed(0)).save(fit)
    x, idx = training_samples(seeds, "quadcopter", fit, 6, seed=3, pose_sampling=pose_sampling, object_box=object_box)
    ref = synthetic_positives(seeds, "quadcopter", fit, 6, seed=3, pose_sampling=pose_sampling, object_box=object_box)
    torch.testing.assert_close(x, ref)
    assert idx.shape == (6,) and idx.dtype == np.int64 and set(idx.tolist()) <= set(range(n))
    # the seed indices are the dataset's own items', whatever the batching
    from synthaug.data.synthetic import SyntheticObjectDataset

    ds = SyntheticObjectDataset("quadcopter", seeds, params=str(fit), length=6, patch_size=40, negative_fraction=0.0,
                                seed=3, pose_sampling=pose_sampling, object_box=object_box)
    assert idx.tolist() == [int(ds[i][1]["seed_index"]) for i in range(6)]
    xb, ib = synthetic_positives(seeds, "quadcopter", fit, 6, seed=3, pose_sampling=pose_sampling,
                                 object_box=object_box, batch=4, return_seed_index=True)
    torch.testing.assert_close(xb, x)
    np.testing.assert_array_equal(ib, idx)
    empty, ie = synthetic_positives(seeds, "quadcopter", fit, 0, return_seed_index=True)
    assert empty.shape == (0, 1, 40, 40) and ie.shape == (0,)
    with pytest.raises(TypeError, match="return_seed_index"):
        training_samples(seeds, "quadcopter", fit, 6, return_seed_index=False)
    if pose_sampling == "fitted" or object_box is not None:  # not the paper's uniform draw at the mesh's scale
        other, _ = training_samples(seeds, "quadcopter", fit, 6, seed=3)
        assert not torch.equal(x, other)
    else:  # the effects left out (the CNN's default) and the capture sampling: the training's patches too
        kept = ["object_noise", "material"]
        y, _ = training_samples(seeds, "quadcopter", fit, 6, seed=3, effects=kept, capture_sampling="uniform")
        torch.testing.assert_close(y, synthetic_positives(seeds, "quadcopter", fit, 6, seed=3, effects=kept,
                                                          capture_sampling="uniform"))
        assert not torch.equal(y, x)
        # quantize: the same patches on the 256 levels of 8 bits (the renderer's values are not on them)
        q = synthetic_positives(seeds, "quadcopter", fit, 6, seed=3, quantize=True)
        torch.testing.assert_close(training_samples(seeds, "quadcopter", fit, 6, seed=3, quantize=True)[0], q)
        assert not torch.equal(x * 255, (x * 255).round())
        torch.testing.assert_close(q * 255, (q * 255).round(), rtol=0, atol=1e-4)
        assert float((q - x).abs().max()) <= 0.5 / 255 + 1e-6
