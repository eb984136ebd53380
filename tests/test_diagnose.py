"""Diagnosis (issue 6): statistics against scipy, and hidden effects that the diagnosis must find.

The measured data come from the reference camera (:mod:`synthaug.diagnose.reference_camera`) at the
realistic strengths of ``REALISTIC_STRENGTHS``, 64 seeds over 5 videos, one object material (w_d in
[0.3, 0.45], one value per video: the same paint under each scene's light). The fit is a real per-seed
CMA-ES fit with the HOG distance, started at the true pose (:func:`converged_fit`): a converged fit, which
absorbs what it can of the hidden effect, without the small-budget convergence failures that would
otherwise dominate the residuals.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch

from synthaug.diagnose.residuals import permutation_spearman, region_masks, t_test
from synthaug.diagnose.screening import CANDIDATE_GRIDS, _logistic_cv_accuracy, kfold

MEASURED = dict(n_seeds=64, frame_size=(192, 256), object_px=(20.0, 32.0), view_step_deg=20, sprite_size=48,
                paper_ranges={"w_d": (0.3, 0.45)})


def converged_fit(seeds_dir, out, *, budget: int = 250, step: float = 20.0, sprite: int = 48,
                  distance: str = "hog") -> Path:
    """Per-seed CMA-ES fit of the paper's Θ with ``distance``, started at the true pose and parameters."""
    from synthaug.data.seedset import SeedSet
    from synthaug.diagnose.reference_camera import load_truth
    from synthaug.fit.fitting import FitConfig, build_distance, fit_one, patches_tensor, seed_seed
    from synthaug.fit.objective import FitSpace
    from synthaug.params import CaptureParams
    from synthaug.render.cache import ViewCache

    seeds = SeedSet.load(seeds_dir)
    truth, textra, _ = load_truth(seeds_dir)
    td = truth.as_dict()
    start = CaptureParams({k: td[k] for k in CaptureParams.vector_names()}, validate=False)
    cfg = FitConfig(distance=distance, budget=budget, step_deg=step, sprite_size=sprite)
    cache = ViewCache.build("quadcopter", step_deg=step, sprite_size=sprite)
    dist = build_distance(distance, seeds)
    rows, extra = [], []
    for i in range(len(seeds)):
        sc = float(textra[i]["object_scale"])
        space = FitSpace.default(bounds={"sigma_n": (0.0, 0.1)}, scale_range=(0.85 * sc, 1.15 * sc))
        s = seed_seed(0, i)
        res = fit_one(patches_tensor(seeds.patches[i:i + 1]), patches_tensor(seeds.backgrounds[i:i + 1]), cache,
                      dist, cfg, seed=s, object_scale=sc, x0=space.from_theta(start[i])[0], space=space)
        rows.append(res["theta"])
        extra.append({"distance": res["distance"], "generator_seed": s, "object_scale": res["object_scale"]})
    out = Path(out)
    CaptureParams.from_vector(torch.tensor(rows, dtype=torch.float64)).save(
        out, extra=extra, metadata={"config": {"step_deg": step, "sprite_size": sprite, "distance": distance}})
    return out


def _diagnose(tmp: Path, hidden, seed: int = 1, n_seeds: int | None = None, colour: bool = False,
              nuisances=None) -> dict:
    from synthaug.diagnose.reference_camera import make_measured_seedset
    from synthaug.diagnose.report import diagnose

    seeds = make_measured_seedset(tmp / "seeds", hidden=hidden, seed=seed, colour=colour, nuisances=nuisances,
                                  **{**MEASURED, **({"n_seeds": n_seeds} if n_seeds else {})})
    fit = converged_fit(seeds, tmp / "fit.json")
    return diagnose(seeds, "quadcopter", fit, out_dir=tmp / "out")


# ----------------------------------------------------------------- statistics against references
def test_t_test_matches_scipy():
    from scipy import stats

    x = np.random.default_rng(0).normal(0.3, 1.0, 25)
    m, t, p = t_test(x)
    ref = stats.ttest_1samp(x, 0.0)
    assert m == pytest.approx(x.mean())
    assert t == pytest.approx(ref.statistic)
    assert p == pytest.approx(ref.pvalue)


def test_permutation_spearman_matches_scipy_and_is_calibrated():
    from scipy import stats

    rng = np.random.default_rng(1)
    x, y = rng.normal(size=40), rng.normal(size=40)
    rho, p = permutation_spearman(x, y + 0.5 * x, rng)
    ref = stats.spearmanr(x, y + 0.5 * x)
    assert rho == pytest.approx(ref.statistic)
    assert abs(p - ref.pvalue) < 0.02 + 0.3 * ref.pvalue
    # under the null the p-values are uniform: few below 0.05
    ps = [permutation_spearman(rng.normal(size=30), rng.normal(size=30), rng, n_perm=499)[1] for _ in range(60)]
    assert np.mean(np.array(ps) < 0.05) < 0.15


def test_within_video_spearman_removes_a_per_video_nuisance():
    from scipy import stats

    from synthaug.diagnose.residuals import within_groups

    rng = np.random.default_rng(3)
    g = np.repeat(np.arange(6), 6)
    x = rng.normal(size=36) + 2.0 * g  # the metadata's video means rise...
    y = 0.3 * (x - 2.0 * g) - 1.5 * g + 0.1 * rng.normal(size=36)  # ...the video's light falls, dependence within
    assert permutation_spearman(x, y, rng)[0] < 0  # pooled: the nuisance wins
    rho, p = permutation_spearman(x, y, rng, groups=g)
    ref = stats.spearmanr(within_groups(x, g), within_groups(y, g)).statistic
    assert rho == pytest.approx(ref) and rho > 0.8 and p < 1e-3
    # under the null (no within-video dependence, strong per-video offsets) the p-values stay uniform
    ps = [permutation_spearman(rng.normal(size=30) + np.repeat(np.arange(5.0), 6),
                               rng.normal(size=30) - np.repeat(np.arange(5.0), 6), rng, n_perm=499,
                               groups=np.repeat(np.arange(5), 6))[1] for _ in range(60)]
    assert np.mean(np.array(ps) < 0.05) < 0.15


def test_permutation_pearson_matches_scipy_and_is_calibrated_within_videos():
    from scipy import stats

    from synthaug.diagnose.residuals import within_groups
    from synthaug.diagnose.stats import permutation_correlation

    rng = np.random.default_rng(5)
    g = np.repeat(np.arange(5), 8)
    x = rng.normal(size=40) + np.repeat(rng.normal(size=5) * 3, 8)
    y = 0.4 * x + rng.normal(size=40) + np.repeat(rng.normal(size=5) * 3, 8)
    r, p = permutation_correlation(x, y, rng, 19_999, g, method="pearson")
    xc, yc = within_groups(x, g), within_groups(y, g)
    assert r == pytest.approx(stats.pearsonr(xc, yc).statistic)
    # the p-value of within-video shuffles, by a plain loop (not scipy's: it shuffles across videos, p 0.047 here,
    # where restricting the shuffles to each video gives 0.09)
    ref_rng, hits, n_ref = np.random.default_rng(2), 0, 4000
    for _ in range(n_ref):
        yp = yc.copy()
        for k in range(5):
            idx = np.nonzero(g == k)[0]
            yp[idx] = yc[ref_rng.permutation(idx)]
        hits += abs(np.corrcoef(xc, yp)[0, 1]) >= abs(r) - 1e-12
    assert abs(p - (hits + 1) / (n_ref + 1)) < 0.015
    ps = [permutation_correlation(rng.normal(size=30) + np.repeat(np.arange(5.0), 6),
                                  rng.lognormal(size=30) - np.repeat(np.arange(5.0), 6), rng, 499,
                                  np.repeat(np.arange(5), 6), method="pearson")[1] for _ in range(60)]
    assert np.mean(np.array(ps) < 0.05) < 0.15
    with pytest.raises(ValueError, match="method"):
        permutation_correlation(x, y, rng, method="kendall")


def test_exposure_absorption_is_tested_linearly_and_has_the_power_ranks_lack(monkeypatch):
    """Auto-exposure makes w_d follow the metered brightness B within a video: the Pearson correlation within videos
    (the dependence whose held-out R2 is the gain) finds it where the rank correlation is weaker (one video's
    brightness spans far more than the others', as in the power table's case whose rank test missed it)."""
    from types import SimpleNamespace

    from scipy import stats

    import synthaug.diagnose.residuals as residuals_mod
    import synthaug.diagnose.screening as screening_mod
    from synthaug.diagnose.stats import within_groups

    g = np.repeat(np.arange(5), 12)
    data = SimpleNamespace(records=[{"video": f"v{int(k)}"} for k in g])
    monkeypatch.setattr(residuals_mod, "seed_groups", lambda d: g)
    folds = screening_mod.kfold(60, 5, np.random.default_rng(0))
    ratios = []
    for seed in range(6):
        rng = np.random.default_rng(seed)
        spread = np.repeat([0.05, 0.08, 0.06, 0.05, 0.4], 12)  # within-video sd of log brightness
        b = np.exp(np.repeat(rng.normal(-0.7, 0.05, 5), 12) + spread * rng.normal(size=60))
        albedo = np.repeat(rng.uniform(0.3, 0.45, 5), 12)
        w = albedo * (0.5 / b) ** 0.5 + 0.05 * rng.normal(size=60)  # the gain (target / B)^a, a = 0.5
        monkeypatch.setattr(screening_mod, "seed_metadata", lambda d, b=b: {"frame_brightness": b})
        ab = screening_mod.absorption_gain(data, "exposure", w, folds, np.random.default_rng(1))
        assert ab["statistic"] == "pearson" and ab["sign_ok"] and ab["within"] == "video"
        assert ab["rho"] == pytest.approx(stats.pearsonr(within_groups(b, g), within_groups(w, g)).statistic)
        rho_s, p_s = permutation_spearman(b, w, np.random.default_rng(1), 99_999, groups=g)
        ratios.append(p_s / ab["p"])
        # the held-out gain is the linear R2 of the values within videos
        assert ab["gain"] == pytest.approx(screening_mod._cv_r2(within_groups(b, g), within_groups(w, g), folds))
    assert min(ratios) >= 0.5 and np.median(ratios) >= 5.0  # never much weaker, mostly far stronger
    # the other absorbed effects keep the rank test
    monkeypatch.setattr(screening_mod, "seed_metadata", lambda d: {"radial_r2": np.linspace(0.0, 0.3, 60)})
    assert screening_mod.absorption_gain(data, "vignetting", w, folds, np.random.default_rng(1))["statistic"] == "spearman"


def test_feature_residual_map_matches_the_flat_hog_descriptor():
    """The per-block HOG residual equals the norm over each block's slice of the flat descriptor (its documented
    order: block row, block col, cells, orientations)."""
    from types import SimpleNamespace

    from synthaug.detectors.hog import hog
    from synthaug.diagnose.residuals import feature_residual_map
    from synthaug.distances import get_distance

    g = torch.Generator().manual_seed(0)
    real, syn = torch.rand(3, 1, 40, 40, generator=g), torch.rand(3, 1, 40, 40, generator=g)
    dist = get_distance("hog")
    data = SimpleNamespace(real=real, distance=dist, distance_name="hog")
    out = feature_residual_map(data, syn)
    hb = out["per_seed"].shape[-1]
    flat = (hog(real, dist.config) - hog(syn, dist.config)).reshape(3, hb, hb, -1)
    np.testing.assert_allclose(out["per_seed"], flat.norm(dim=-1).double().numpy(), rtol=1e-4, atol=1e-6)
    assert out["cell_px"] == 8 and 0 <= out["share_centre"] <= 1
    assert feature_residual_map(data, real)["mean"].max() == 0
    assert feature_residual_map(SimpleNamespace(real=real, distance=dist, distance_name="eucl"), syn) is None


def test_region_masks_match_scipy_morphology():
    from scipy import ndimage

    cov = torch.zeros(1, 1, 24, 24)
    cov[..., 6:18, 4:15] = 1.0
    cov[..., 10:12, 15:20] = 0.8
    m = region_masks(cov, band=2)
    obj = cov[0, 0].numpy() > 0.5
    st = np.ones((5, 5), bool)
    ero = ndimage.binary_erosion(obj, st, border_value=1)
    dil = ndimage.binary_dilation(obj, st)
    np.testing.assert_array_equal(m["interior"][0, 0].numpy(), ero)
    np.testing.assert_array_equal(m["boundary"][0, 0].numpy(), dil & ~ero)
    np.testing.assert_array_equal(m["background"][0, 0].numpy(), ~dil)


def test_kfold_and_classifier_accuracy():
    rng = np.random.default_rng(2)
    folds = kfold(20, 4, rng)
    assert sorted(np.concatenate(folds).tolist()) == list(range(20))
    n = 40
    groups = np.concatenate([np.arange(n), np.arange(n)])
    y = np.concatenate([np.ones(n), np.zeros(n)])
    f = kfold(n, 5, rng)
    separable = rng.normal(size=(2 * n, 5)) + 3.0 * y[:, None]
    same = rng.normal(size=(2 * n, 5))
    assert _logistic_cv_accuracy(separable, y, groups, f) > 0.95
    assert 0.25 < _logistic_cv_accuracy(same, y, groups, f) < 0.75  # indistinguishable: about 50 %
    with pytest.raises(ValueError, match="at least 2 seeds"):
        kfold(1, 2, rng)


def test_bad_inputs(tmp_path):
    from synthaug.diagnose.report import diagnose
    from synthaug.diagnose.screening import screen_candidates

    with pytest.raises(ValueError, match="unknown candidate"):
        diagnose(tmp_path, "quadcopter", tmp_path / "f.json", candidates=["vignetting", "lens_flare"])
    with pytest.raises(ValueError, match="k must be"):
        diagnose(tmp_path, "quadcopter", tmp_path / "f.json", k=1)
    with pytest.raises(ValueError, match="unknown candidate"):
        screen_candidates(None, ["nope"])  # type: ignore[arg-type]


def test_every_candidate_has_a_grid():
    from synthaug.effects.camera import CAMERA_EFFECTS

    assert set(CANDIDATE_GRIDS) == set(CAMERA_EFFECTS)


# ----------------------------------------------------------------- hidden effects
# Effects that need more seeds than MEASURED's 64 (measured): haze's held-out gain is heavy-tailed (w_d absorbs
# its gain; the airlight offset shows only on seeds whose shading spans dark and bright): at 64 seeds it is
# under-powered (2.9 % HOG / 3.5 % pixel gain, the true extinction chosen, p_adj 0.03, and 'defocus' is named);
# at 128 seeds it is named first on data seeds 1 and 2 (5.2 % / 6.7 % pixel gain) and the clean set stays quiet.
N_SEEDS = {"haze": 128}
# Effects that exist only in colour, measured on RGB seed sets (colour.npz beside the gray patches): in gray,
# lateral chromatic aberration is a ~1 px radial blur (measured: named 'defocus', 3.1 % pixel gain, its own
# gain not significant even at 128 seeds) and white balance a plain gain that w_d absorbs.
COLOUR = ("chromatic_aberration", "white_balance")
# Effects read off the scene's motion between each frame and its background frame: a lens's radial distortion
# (frame_pattern.radial_flow). The project's own camera keeps the scene still; on the object alone (r² < 0.4) the
# lens is a stretch of a few percent, measured at 64 seeds in stop 41 (the camera's lens no longer blurring the frame,
# one more screening test): 3.3 % pixel gain, p_adj 0.011, not significant. So its case lets the scene drift up to
# 1 px, nothing else.
MOVING_SCENE = {"lens_distortion": {"background_drift_px": 1.0}}


@pytest.mark.slow
@pytest.mark.parametrize("effect", list(CANDIDATE_GRIDS))
def test_a_hidden_effect_is_named_first_and_significant(tmp_path, effect):
    from synthaug.diagnose.nuisances import Nuisances

    moving = Nuisances(**MOVING_SCENE[effect]) if effect in MOVING_SCENE else None
    report = _diagnose(tmp_path, [effect], n_seeds=N_SEEDS.get(effect), colour=effect in COLOUR, nuisances=moving)
    assert report["findings"], f"nothing significant; screened: {report['screened'][:3]}"
    first = report["findings"][0]
    assert first["effect"] == effect, [f["effect"] for f in report["findings"]]
    assert first["significant"]
    g = first["gains"]
    # the extended model's held-out gain: distance, absorbed-parameter R², noise-model likelihood, chroma, or the
    # frames' fall-off
    assert max(g["heldout_feature"], g["heldout_pixel"], g["absorbed_parameter_r2"] or -1,
               g["noise_loglik_per_px"] or -1, g["heldout_colour"] or -1, g["frame_statistic"] or -1) > 0
    if effect == "shot_noise":
        # its strength read from the frames' affine noise level function: the truth, plus the few per cent that
        # the background's own noise (0.35 of the frame's std, unknown to the diagnosis) adds
        from synthaug.diagnose.reference_camera import REALISTIC_STRENGTHS

        assert first["channel"] == "noise_level"
        assert first["setting"]["shot_sigma"] == pytest.approx(REALISTIC_STRENGTHS["shot_noise"]["shot_sigma"],
                                                               rel=0.15)
    # the files: report.json (same content) and the human report with its plots
    assert json.loads((tmp_path / "out" / "report.json").read_text())["findings"][0]["effect"] == effect
    md = (tmp_path / "out" / "report.md").read_text()
    assert effect in md and (tmp_path / "out" / "residuals.png").exists()


@pytest.mark.slow
def test_no_hidden_effect_reports_nothing_significant(tmp_path):
    report = _diagnose(tmp_path, None)
    assert report["findings"] == [], [(f["effect"], f.get("channel")) for f in report["findings"]]
    assert not report["significant"]
    assert "Nothing significant" in (tmp_path / "out" / "report.md").read_text()


@pytest.mark.slow
def test_haze_in_colour_is_found_at_64_seeds(tmp_path):
    # in colour the airlight has the sky's colour: a hazed object takes on the sky's colour (aerial perspective),
    # which the chroma residual sees at 64 seeds (measured: 32 % held-out chroma gain), where gray needs 128
    report = _diagnose(tmp_path, ["haze"], colour=True)
    assert [f["effect"] for f in report["findings"]][:1] == ["haze"], report["findings"]
    assert report["findings"][0]["channel"] == "distance:colour" and report["findings"][0]["gains"]["heldout_colour"] > 0


@pytest.mark.slow
def test_no_hidden_effect_in_colour_reports_nothing_significant(tmp_path):
    # the colour channel's control: a neutral object over tinted skies, nothing hidden
    report = _diagnose(tmp_path, None, colour=True)
    assert report["findings"] == [], [(f["effect"], f.get("channel")) for f in report["findings"]]


@pytest.mark.slow
def test_two_hidden_effects_are_both_found(tmp_path):
    # one whole-frame effect (in B too) and one object-only effect; forward selection screens the second on
    # top of the first
    pair = ["defocus", "rotor_blur"]
    report = _diagnose(tmp_path, pair)
    found = [f["effect"] for f in report["findings"]]
    assert set(pair) <= set(found), found
    assert report["findings"][1]["given"] == [found[0]]  # screened on top of the first


@pytest.mark.slow
def test_an_effect_outside_the_list_is_unexplained_with_its_structure(tmp_path):
    # interlacing (the reference camera's out-of-list effect): odd rows from the second field, the moving
    # object displaced by 1.5-2.5 px: an alternating-row comb on the object. A blur candidate may explain part
    # of it; the comb itself must be reported as unexplained, with its period.
    report = _diagnose(tmp_path, {"interlacing": {"interlace_shift": (1.5, 2.5)}})
    effects = [f["effect"] for f in report["findings"]]
    assert "unexplained" in effects, report["findings"]
    assert not set(effects) & {"compression", "rolling_shutter", "rotor_blur", "specular"}, effects
    structure = report["findings"][effects.index("unexplained")]["structure"]
    assert "periodic_rows" in structure, structure
    assert structure["periodic_rows"]["period_px"] == pytest.approx(2.0, abs=0.3)


def _diagnosed_nuisance_case(tmp_path, hidden, k):
    """A nuisance-varied reference-camera seed set (nuisances of the power table's case k, base seed 8000) with
    ``hidden`` at its realistic strength, the tests' converged fit, and its diagnosis (report in tmp_path/out)."""
    from synthaug.diagnose.nuisances import Nuisances
    from synthaug.diagnose.reference_camera import make_measured_seedset
    from synthaug.diagnose.report import diagnose

    seeds = make_measured_seedset(tmp_path / "seeds", hidden=hidden, seed=k,
                                  nuisances=Nuisances.draw(np.random.default_rng([8000, k])), **MEASURED)
    fit = converged_fit(seeds, tmp_path / "fit.json")
    return seeds, diagnose(seeds, "quadcopter", fit, out_dir=tmp_path / "out")


@pytest.mark.slow
def test_vignetting_on_a_nuisance_varied_camera_is_named_from_the_frames_at_its_strength(tmp_path):
    # vignetting at its realistic strength (1 - 0.3 r²) under another material, light per video, mesh and a
    # moving scene: on the objects (r² <= 0.3) it is a gain of 0.91-1 that w_d absorbs seed by seed (the absorbed
    # channel's R² stays below its clean floor), but the whole frames fall off toward the corners: named first,
    # from the frames, with the fall-off they imply within 0.1 of the truth; the frames' column / row patterns
    # stay quiet (a vignetting is smooth: the line profiles' local quadratic removes it, the frame's edges too)
    from synthaug.diagnose.reference_camera import REALISTIC_STRENGTHS

    k = REALISTIC_STRENGTHS["vignetting"]["vignette_k"]
    _, report = _diagnosed_nuisance_case(tmp_path, ["vignetting"], 12)
    first = report["findings"][0]
    assert (first["effect"], first["channel"]) == ("vignetting", "frame"), report["findings"]
    assert first["setting"]["vignette_k"] == pytest.approx(k, abs=0.1)
    assert first["gains"]["frame_statistic"] == first["setting"]["vignette_k"]
    assert not report["residuals"]["column_pattern"]["significant"] and not report["residuals"]["row_pattern"]["significant"]
    assert "fall off toward the corners" in (tmp_path / "out" / "report.md").read_text()


@pytest.mark.slow
@pytest.mark.xfail(strict=True, raises=(AssertionError, IndexError),
                   reason="issue 20, stop 112: since the reference camera lights a hidden highlight by its video's "
                          "light (tilted up to 40 degrees; it was the model's), the highlight channel's template at "
                          "the model's light misses this case: specular at its default strength 9 of 15 over the "
                          "three power sets (results/diagnose/README.md, stop 112)")
def test_specular_on_a_nuisance_varied_camera_is_named_from_the_objects_highlight(tmp_path):
    # a Blinn-Phong highlight at its realistic strength (ks 0.3-0.6 per seed, exponent 30) on a nuisance-varied
    # camera whose own material is glossy too (ks up to 0.2 at each video's light): on 20-30 px objects its distance
    # gain stays under the clean floor (stop 110: even the exact highlight added to the model reaches t <= 2.5), but
    # the lobe's amplitude fitted with the albedo seed by seed reads above every clean material's: named first, from
    # the highlight channel, its ks within 0.15 of the truth's mean. Expected to fail (strict) until the channel
    # follows each video's light: the hidden highlight is now on the real material, lit as its own gloss is.
    _, report = _diagnosed_nuisance_case(tmp_path, ["specular"], 1)
    first = report["findings"][0]
    assert (first["effect"], first["channel"]) == ("specular", "highlight"), report["findings"]
    assert first["setting"]["specular_ks"] == pytest.approx(0.45, abs=0.15)
    row = next(r for r in report["screened"] if r["effect"] == "specular")
    ch = next(c for c in row["channels"] if c["channel"] == "highlight")
    assert ch["gain"] > ch["floor"] > ch["centre"] and ch["p_adjusted"] < 0.01
    assert "carry a highlight" in (tmp_path / "out" / "report.md").read_text()


@pytest.mark.slow
def test_compression_on_a_nuisance_varied_camera_is_named_from_the_frames_at_its_quality(tmp_path):
    # libjpeg (OpenCV) at the realistic quality 40 on the whole frames of a nuisance-varied camera: named first,
    # from the frames' 8x8 block grid tested over scenes, its setting the quality the blocks' DCT steps read
    from synthaug.diagnose.reference_camera import REALISTIC_STRENGTHS

    q = REALISTIC_STRENGTHS["compression"]["jpeg_quality"]
    _, report = _diagnosed_nuisance_case(tmp_path, ["compression"], 13)
    first = report["findings"][0]
    assert (first["effect"], first["channel"]) == ("compression", "frame"), report["findings"]
    assert first["setting"]["jpeg_quality"] == pytest.approx(q, abs=3)
    assert "JPEG quality" in (tmp_path / "out" / "report.md").read_text()


@pytest.mark.slow
def test_sharpening_on_a_nuisance_varied_camera_is_named_from_the_frames_edges(tmp_path):
    # an unsharp mask at its realistic strength (amount 1, sigma 1 frame px) after the sensor, on a nuisance-varied
    # camera: on a 20-30 px object a 1-px halo that the fit's blur, noise and shading mismatch drown (its distance
    # gain stays under the clean floor), but every edge of the whole frames is steeper than clean frames' (read on
    # the frame at edges found on the independent background frame): named first, from the frames, at its setting
    from synthaug.diagnose.reference_camera import REALISTIC_STRENGTHS

    _, report = _diagnosed_nuisance_case(tmp_path, ["sharpening"], 14)
    first = report["findings"][0]
    assert (first["effect"], first["channel"]) == ("sharpening", "frame"), report["findings"]
    # its setting read off the frames: the unsharp mask whose inverse brings their edges back to clean frames'; one
    # statistic for two parameters, so amount and sigma trade off: within one step of the screening grid in each
    # (the power table's 10 cases: 8 exact, 2 one step off in both)
    from synthaug.diagnose.screening import CANDIDATE_GRIDS

    truth = REALISTIC_STRENGTHS["sharpening"]
    for name in ("sharpen_amount", "sharpen_sigma"):
        steps = sorted({g[name] for g in CANDIDATE_GRIDS["sharpening"]})
        assert abs(steps.index(first["setting"][name]) - steps.index(truth[name])) <= 1, first["setting"]
    row = next(r for r in report["screened"] if r["effect"] == "sharpening")
    ch = next(c for c in row["channels"] if c["channel"] == "frame")
    assert ch["gain"] > ch["floor"] > ch["centre"] and ch["p_adjusted"] < 0.01
    assert "edges are steeper than clean frames'" in (tmp_path / "out" / "report.md").read_text()


@pytest.mark.slow
def test_lens_distortion_on_a_nuisance_varied_camera_is_named_from_the_scenes_motion(tmp_path):
    # barrel distortion at its realistic strength (k1 -0.15 over the whole frame), on a nuisance-varied camera
    # whose scene drifts up to 1.2 px between each frame and its background frame (the power table's case 15): on
    # the objects (r² < 0.4) a stretch of a few percent the fitted pose absorbs, but the scene's motion between the
    # two looks is bent by the lens: named first, from the frames, with k1 read within 0.02 of the truth
    from synthaug.diagnose.reference_camera import REALISTIC_STRENGTHS

    k1 = REALISTIC_STRENGTHS["lens_distortion"]["distortion_k1"]
    _, report = _diagnosed_nuisance_case(tmp_path, ["lens_distortion"], 15)
    first = report["findings"][0]
    assert (first["effect"], first["channel"]) == ("lens_distortion", "frame"), report["findings"]
    assert first["setting"]["distortion_k1"] == pytest.approx(k1, abs=0.02)
    row = next(r for r in report["screened"] if r["effect"] == "lens_distortion")
    ch = next(c for c in row["channels"] if c["channel"] == "frame")
    assert ch["gain"] > ch["floor"] and ch["p_adjusted"] < 0.01 and ch["k1"] < 0
    assert "barrel" in (tmp_path / "out" / "report.md").read_text()


def _diagnosed_bench_case(tmp_path, bench_null, base: int, k: int, hidden: str, strength: str) -> dict:
    """Case ``k`` of the power table's seed base ``base`` (``bench_diagnose_null.py``'s seeds, nuisances and hidden
    setting), fitted as the bench's converged fit and diagnosed: the report."""
    from synthaug.diagnose.nuisances import Nuisances
    from synthaug.diagnose.report import diagnose

    seeds = tmp_path / "seeds"
    bench_null.case_seedset(seeds, k, base_seed=base, n_seeds=60,
                            nuisances=Nuisances.draw(np.random.default_rng([base, k])), hidden=hidden,
                            strength=strength)
    return diagnose(seeds, "quadcopter", converged_fit(seeds, tmp_path / "fit.json"), out_dir=None, plots=False,
                    seed=0)


@pytest.mark.slow
def test_a_pincushion_lens_on_a_still_scene_is_named_from_the_objects_with_the_frames_edge_trend(tmp_path, bench_null):
    # lens k1 +0.1 (its second realistic strength) on the power table's case 4 (bench_diagnose_null.py's seeds and
    # nuisances): its scene moved at most 0.15 px between each frame and its background frame, so the lens's motion
    # channel has no reading; on the objects the lens gains 1.7 % of the pixel distance (its test and its clean
    # floor passed, the 2 % utility rule not), and the frames' edges steepen toward the corners beyond every clean
    # frame's: named first from the objects, at its setting, with the report saying why, and not as sharpening
    from synthaug.diagnose.frame_pattern import EDGE_RADIAL_FLOOR
    from synthaug.diagnose.report import write_markdown

    k1 = bench_null.hidden_settings("lens_distortion", "alt")["lens_distortion"]["distortion_k1"]
    assert k1 == pytest.approx(0.1)
    report = _diagnosed_bench_case(tmp_path, bench_null, 8000, 4, "lens_distortion", "alt")
    first = report["findings"][0]
    assert (first["effect"], first["channel"]) == ("lens_distortion", "distance:pixel"), report["findings"]
    assert first["setting"]["distortion_k1"] == pytest.approx(k1, abs=0.02)
    assert "sharpening" not in [f["effect"] for f in report["findings"]]
    row = next(r for r in report["screened"] if r["effect"] == "lens_distortion")
    assert "frame" not in [c["channel"] for c in row["channels"]]  # no motion to read the lens from
    ch = next(c for c in row["channels"] if c["channel"] == "distance:pixel")
    assert ch["raw_gain_all"] < 0.02 and ch["gain"] > ch["floor"] and ch["p_adjusted"] < 0.01
    assert ch["corroborated_by"]["statistic"] == "edge_radial" and ch["corroborated_by"]["value"] > EDGE_RADIAL_FLOOR
    assert "The lens (`lens_distortion`) is named from its distance:pixel gain" in write_markdown(report)


@pytest.mark.slow
def test_a_pincushion_lens_whose_scene_does_not_move_is_not_named_sharpening(tmp_path, bench_null):
    # lens k1 +0.1 on the 11000 set's case 0 (bench_diagnose_null.py's seeds and nuisances): its scene moves at most
    # 0.07 px between the looks, so neither the lens's motion channel nor (at this set's edges) the edge trend reads
    # it, and the frames' edges are steeper than clean frames' (the lens changes the image's scale). Stop 99 named
    # it sharpening from the frames. A camera's sharpening filters the objects too; here rendering it fits them no
    # better than it fits clean ones, in either space: the frames' finding is withheld, and the report says why
    from synthaug.diagnose.calibration import gain_upper
    from synthaug.diagnose.report import write_markdown

    report = _diagnosed_bench_case(tmp_path, bench_null, 11000, 0, "lens_distortion", "alt")
    assert "sharpening" not in [f["effect"] for f in report["findings"]], report["findings"]
    row = next(r for r in report["screened"] if r["effect"] == "sharpening")
    frame = next(c for c in row["channels"] if c["channel"] == "frame")
    assert frame["gain"] > frame["floor"] and frame["p_adjusted"] < 0.01 and not frame["radial_veto"]
    assert not frame["significant"] and not frame["objects"]["agree"] and frame["objects_veto"]
    for c in row["channels"]:
        if c["channel"] in ("distance:feature", "distance:pixel"):  # the objects as clean ones
            assert c["gain"] <= gain_upper("sharpening", c["channel"]) == frame["objects"]["spaces"][c["channel"]][
                "clean_upper"]
    assert "rendering it does not fit the objects better than it fits clean ones" in write_markdown(report)


@pytest.mark.slow
def test_a_tone_curve_whose_objects_read_blurrier_is_not_named_defocus(tmp_path, bench_null):
    # gamma 1.4 (its second realistic strength) on the 13000 set's case 2: the real material's normals smoothed by
    # 1.94 px sit at defocus's pixel floor and the tone curve lifts them over it (stop 113), so rendering a defocus
    # fits the objects better, past its test and its floor. But a defocus blurs the whole frame, and these frames'
    # edges are sharper than clean frames': the finding is withheld, the tone curve named first, the report says why
    from synthaug.diagnose.report import write_markdown

    report = _diagnosed_bench_case(tmp_path, bench_null, 13000, 2, "gamma", "alt")
    assert (report["findings"][0]["effect"], report["findings"][0]["channel"]) == ("gamma", "noise_level"), \
        report["findings"]
    assert "defocus" not in [f["effect"] for f in report["findings"]]
    row = next(r for r in report["screened"] if r["effect"] == "defocus")
    ch = next(c for c in row["channels"] if c["channel"] == "distance:pixel")
    assert ch["gain"] > ch["floor"] and ch["p_adjusted"] < 0.01 and not ch["significant"]  # withheld, not failed
    veto = ch["frames_veto"]
    assert not veto["blurred"] and veto["t"] > 2 and veto["ratio"] > veto["centre"]  # sharper than clean frames
    assert "Defocus is not named: rendering it fits the objects better" in write_markdown(report)


@pytest.mark.slow
def test_a_defocus_at_the_low_end_of_its_range_blurs_the_frames_enough_to_be_named(tmp_path, bench_null, monkeypatch):
    # defocus σ 0.7 frame px (the low end of its realistic range) on the 13000 set's case 0, the faintest frames of
    # that row: their edges read 0.626 against the clean mean 0.635, under clean frames' own range (a bound there,
    # tried at stop 114, withheld 2 of these 5 cases), yet blurrier by the test over 60 scenes. Named first
    from synthaug.diagnose.calibration import gain_upper
    from synthaug.diagnose.diagnosis_data import load_diagnosis_data
    from synthaug.diagnose.reference_camera import settings
    from synthaug.diagnose.screening import frame_evidence, frames_blurred

    monkeypatch.setitem(settings.REALISTIC_STRENGTHS, "defocus", {"defocus_sigma": 0.7})
    report = _diagnosed_bench_case(tmp_path, bench_null, 13000, 0, "defocus", "default")
    assert (report["findings"][0]["effect"], report["findings"][0]["channel"]) == ("defocus", "distance:pixel"), \
        report["findings"]
    # its setting: the truth or above it by up to 0.3 px, as in all 65 defocus cases of stop 114's rows (σ 0.7 and
    # 1.0 on five sets, 1.5 on three; the real object's own softness adds to the blur: the error's Spearman ρ with
    # the normals' smoothing +0.32, the rotors' size +0.35)
    assert 0.7 <= report["findings"][0]["setting"]["defocus_sigma"] <= 1.0
    row = next(r for r in report["screened"] if r["effect"] == "defocus")
    assert not any(c.get("frames_veto") for c in row["channels"])
    data = load_diagnosis_data(tmp_path / "seeds", tmp_path / "fit.json", "quadcopter")
    fb = frames_blurred("defocus", frame_evidence(data))
    assert fb["blurred"] and fb["t"] < -2 and fb["scenes"] >= 50
    assert fb["ratio"] > 2 * fb["centre"] - gain_upper("sharpening", "frame")  # inside clean frames' own range


@pytest.mark.slow
def test_a_fixed_column_pattern_is_unexplained_with_its_structure(tmp_path):
    # a sensor's fixed column pattern at its realistic strength (each frame column's gain 1 + 0.02 N(0, 1)), on a
    # nuisance-varied camera: not a candidate, so "unexplained", described as gains fixed in the frame's columns
    # (not periodic), the row measure quiet; the pattern measured on the frames follows the camera's own gains
    from scipy.signal import savgol_filter

    from synthaug.diagnose.frame_pattern import HIGH_PASS, fixed_line_pattern
    from synthaug.diagnose.reference_camera import REALISTIC_STRENGTHS, column_gains
    from synthaug.diagnose.residuals import load_diagnosis_data

    sd = REALISTIC_STRENGTHS["column_pattern"]["column_gain_sd"]
    seeds, report = _diagnosed_nuisance_case(tmp_path, ["column_pattern"], 11)
    fit = tmp_path / "fit.json"
    effects = [f["effect"] for f in report["findings"]]
    # unexplained, and not sharpening: the frames' edge ratio divides the line gains out first
    assert "unexplained" in effects and "sharpening" not in effects, report["findings"]
    structure = report["findings"][effects.index("unexplained")]["structure"]
    assert "column_pattern" in structure, structure
    assert structure["column_pattern"]["periodic"] is False
    assert 0.5 * sd < structure["column_pattern"]["amplitude"] < 1.5 * sd
    assert not report["residuals"]["row_pattern"]["significant"]
    data = load_diagnosis_data(seeds, fit, "quadcopter")
    fp = fixed_line_pattern([fl["x"] for fl in data.frame_lines], [r["video"] for r in data.records],
                            np.random.default_rng(0), n_perm=99)
    log_g = np.log(column_gains(MEASURED["frame_size"][1], sd, 11))
    truth = log_g - savgol_filter(log_g, HIGH_PASS, 2, mode="interp")
    assert np.corrcoef(fp["pattern"], truth)[0, 1] > 0.9


# ----------------------------------------------------------------- colour (RGB seed sets)
def test_colour_seed_set_and_rgb_render_against_gray_references(tmp_path):
    """The reference camera's RGB capture: luma of the RGB patches = the gray patches (OpenCV's Rec. 601, to the
    crop's rounding); render_rgb of a neutral object = the gray render over each channel's background; the chroma
    distance = numpy's."""
    import cv2

    from synthaug.data.seedset import SeedSet
    from synthaug.diagnose.reference_camera import make_measured_seedset, wb_gains
    from synthaug.diagnose.residuals import chroma_distance, load_diagnosis_data, render_rgb, render_with

    p = make_measured_seedset(tmp_path / "m", n_seeds=6, colour=True, hidden={"white_balance": {"wb_gain": 0.8}},
                              frame_size=(96, 128), object_px=(16, 20), view_step_deg=30, sprite_size=48)
    s = SeedSet.load(p)
    with np.load(p / "colour.npz") as z:
        rgb, bg = z["patches_rgb"], z["backgrounds_rgb"]
    assert rgb.shape == (6, 40, 40, 3) and bg.shape == rgb.shape
    luma = np.stack([cv2.cvtColor(x, cv2.COLOR_RGB2GRAY) for x in rgb]).astype(int)
    assert np.abs(luma - s.patches.astype(int)).max() <= 2
    assert bg[..., 2].mean() > bg[..., 0].mean()  # a bluish sky, made redder-less by wb 0.8 on red
    torch.testing.assert_close(wb_gains(0.8, 3), torch.tensor([[0.8, 1.0, 1.25]], dtype=torch.float64))

    from synthaug.params import CaptureParams

    theta, extra, _ = CaptureParams.load_with_extra(p / "truth.json")
    theta.save(tmp_path / "fit.json", extra=extra, metadata={"config": {"step_deg": 30, "sprite_size": 48}})
    data = load_diagnosis_data(p, tmp_path / "fit.json", "quadcopter")
    assert data.real_rgb is not None and data.real_rgb.shape == (6, 3, 40, 40)
    ext = {"sharpening": {"sharpen_amount": 0.8, "sharpen_sigma": 1.0}}
    y = render_rgb(data, ext, w_d=torch.full((6,), 0.3))
    for c in range(3):
        d_c = data.subset(np.arange(6))
        d_c.background = data.background_rgb[:, c:c + 1]
        torch.testing.assert_close(y[:, c:c + 1], render_with(d_c, ext, w_d=torch.full((6,), 0.3)),
                                   atol=1e-5, rtol=1e-5)
    real = data.real_rgb.numpy()
    ref = np.sqrt((((real[:, 0] - real[:, 1]) - (y[:, 0] - y[:, 1]).numpy()) ** 2
                   + ((real[:, 2] - real[:, 1]) - (y[:, 2] - y[:, 1]).numpy()) ** 2).reshape(6, -1).sum(1))
    np.testing.assert_allclose(chroma_distance(data.real_rgb, y), ref, rtol=1e-5)
    # white balance in colour: the candidate's gains act per channel on the object only
    g = render_rgb(data, {"white_balance": {"wb_gain": torch.tensor([[0.8, 1.0, 1.25]])}}, w_d=torch.full((6,), 0.3))
    base = render_rgb(data, {"white_balance": {"wb_gain": 1.0}}, w_d=torch.full((6,), 0.3))
    torch.testing.assert_close(g[:, 1], base[:, 1])
    obj = data.coverage[:, 0] > 0.99
    assert (g[:, 0][obj] < base[:, 0][obj]).all() and (g[:, 2][obj] > base[:, 2][obj]).all()
    # an accepted white balance is applied per channel when later candidates are screened in colour, and as its
    # luma gain in gray
    from synthaug.diagnose.screening import given_values

    wb = {"white_balance": {"wb_gain": 0.8}}
    torch.testing.assert_close(given_values(data, wb, rgb=True)["white_balance"]["wb_gain"],
                               torch.tensor([[0.8, 1.0, 1.25]]))
    assert given_values(data, wb)["white_balance"]["wb_gain"] == pytest.approx(0.299 * 0.8 + 0.587 + 0.114 / 0.8)


# ----------------------------------------------------------------- single-channel data (issue 20, item 5)
def test_is_single_channel_by_hand():
    from synthaug.diagnose.residuals import is_single_channel

    g = np.full((3, 5, 5, 3), 100, np.uint8)
    assert is_single_channel(g)
    g[1, 2, 2, 0] += 2  # codec rounding: 2 levels of chroma is still gray
    assert is_single_channel(g)
    g[1, 2, 2, 2] -= 3  # |B - G| = 3: colour
    assert not is_single_channel(g)
    with pytest.raises(ValueError, match="RGB"):
        is_single_channel(np.zeros((4, 4)))


def test_gray_rgb_data_skips_colour_statistics_without_runtime_warnings(tmp_path):
    """A seed set whose RGB patches are gray (R = G = B, e.g. gray videos decoded to RGB): the colour channel of
    haze / white_balance / chromatic_aberration is skipped and said so, never screened on an all-zero chroma
    (which divided by zero and reported z 37 with a null gain), and no RuntimeWarning is raised anywhere."""
    import warnings

    from synthaug.data.seedset import SeedSet
    from synthaug.diagnose.reference_camera import load_truth, make_measured_seedset
    from synthaug.diagnose.report import diagnose
    from synthaug.diagnose.screening import COLOUR_CANDIDATES, COLOUR_ONLY
    from synthaug.effects.registry import PAPER_EFFECTS
    from synthaug.params import CaptureParams

    p = make_measured_seedset(tmp_path / "m", n_seeds=12, colour=True, frame_size=(96, 128), object_px=(16, 20),
                              view_step_deg=30, sprite_size=48, seed=4)
    s = SeedSet.load(p)
    gray3 = lambda a: np.repeat(np.asarray(a)[..., None], 3, -1)  # noqa: E731
    np.savez(p / "colour.npz", patches_rgb=gray3(s.patches), backgrounds_rgb=gray3(s.backgrounds))
    truth, textra, _ = load_truth(p)
    theta = CaptureParams({k: v for k, v in truth.as_dict().items()}, effects=PAPER_EFFECTS)
    extra = [{"distance": 1.0, "generator_seed": 7 + i, "object_scale": float(e["object_scale"])}
             for i, e in enumerate(textra)]
    theta.save(tmp_path / "fit.json", extra=extra, metadata={"config": {"step_deg": 30, "sprite_size": 48}})
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        report = diagnose(p, "quadcopter", tmp_path / "fit.json", k=3, out_dir=tmp_path / "out", plots=False)
    assert report["colour"]["screened"] is False and "single-channel" in report["colour"]["note"]
    rows = {r["effect"]: r for r in report["screened"]}
    # the colour-only candidates are not offered on single-channel data (issue 20: lens distortion k1 +0.1 was
    # named chromatic_aberration on gray data in 4 of 5 cases); haze keeps its gray channels
    assert report["colour"]["not_offered"] == list(COLOUR_ONLY)
    assert not set(COLOUR_ONLY) & set(rows) and not set(COLOUR_ONLY) & {f["effect"] for f in report["findings"]}
    for name in set(COLOUR_CANDIDATES) - set(COLOUR_ONLY):
        assert rows[name]["colour_skipped"] and rows[name]["gain_colour"] is None, rows[name]
        assert rows[name]["channel"] != "distance:colour" and rows[name]["score"] is not None
        assert rows[name]["gain"] is not None
    assert report["residuals"]["colour"]["skipped"]
    md = (tmp_path / "out" / "report.md").read_text()
    assert "Colour statistics skipped (single-channel data" in md
    assert "chromatic_aberration, white_balance not screened (colour-only" in md
    with pytest.raises(ValueError, match="an object colour needs RGB seed patches"):  # nothing to compare it with
        diagnose(p, "quadcopter", tmp_path / "fit.json", k=3, plots=False, object_colour=[1.0, 0.9, 0.8])
    # a true colour seed set keeps its colour channel (the same scenes, tinted skies)
    q = make_measured_seedset(tmp_path / "c", n_seeds=12, colour=True, frame_size=(96, 128), object_px=(16, 20),
                              view_step_deg=30, sprite_size=48, seed=4)
    from synthaug.diagnose.residuals import load_diagnosis_data

    theta.save(tmp_path / "fit_c.json", extra=extra, metadata={"config": {"step_deg": 30, "sprite_size": 48}})
    data = load_diagnosis_data(q, tmp_path / "fit_c.json", "quadcopter")
    assert data.real_rgb is not None and data.colour_note is None


def test_gray_data_never_offers_the_colour_only_candidates():
    """Without colour patches (gray, or RGB with equal channels: real_rgb None) chromatic aberration and white
    balance are not candidates: screen_candidates drops them even when asked, and they are never named; colour
    data keep every candidate."""
    from types import SimpleNamespace

    from synthaug.diagnose.screening import COLOUR_ONLY, offered_candidates

    names = list(CANDIDATE_GRIDS)
    gray, colour = SimpleNamespace(real_rgb=None), SimpleNamespace(real_rgb=torch.zeros(2, 3, 4, 4))
    kept, gone = offered_candidates(gray, names)
    assert gone == list(COLOUR_ONLY) == ["chromatic_aberration", "white_balance"]
    assert kept == [c for c in names if c not in COLOUR_ONLY] and "haze" in kept
    assert offered_candidates(colour, names) == (names, [])


def _gray_case_fitted_at_truth(tmp_path, effect: str, setting: dict, n_seeds: int):
    """A small gray measured seed set (seed 4) with ``effect`` hidden at ``setting``, and its fit: the truth without
    the hidden effect's parameters (the converged fit, no fitting run); its :class:`DiagnosisData`."""
    from synthaug.diagnose.reference_camera import load_truth, make_measured_seedset
    from synthaug.diagnose.residuals import load_diagnosis_data
    from synthaug.effects.registry import PAPER_EFFECTS
    from synthaug.params import CaptureParams

    p = make_measured_seedset(tmp_path / "m", n_seeds=n_seeds, hidden={effect: setting}, frame_size=(96, 128),
                              object_px=(16, 20), view_step_deg=30, sprite_size=48, seed=4)
    truth, textra, _ = load_truth(p)
    theta = CaptureParams({k: v for k, v in truth.as_dict().items() if k not in setting}, effects=PAPER_EFFECTS)
    extra = [{"distance": 1.0, "generator_seed": 7 + i, "object_scale": float(e["object_scale"])}
             for i, e in enumerate(textra)]
    theta.save(tmp_path / "fit.json", extra=extra, metadata={"config": {"step_deg": 30, "sprite_size": 48}})
    return load_diagnosis_data(p, tmp_path / "fit.json", "quadcopter")


def test_gray_screening_drops_colour_only_candidates_asked_for(tmp_path):
    from synthaug.diagnose.screening import n_screening_tests, screen_candidates

    data = _gray_case_fitted_at_truth(tmp_path, "lens_distortion", {"distortion_k1": 0.1}, n_seeds=8)
    assert data.real_rgb is None
    asked = ["chromatic_aberration", "lens_distortion", "white_balance"]
    rows = screen_candidates(data, asked, k=2)
    assert [r["effect"] for r in rows] == ["lens_distortion"]
    # the Bonferroni count stays that of the candidates asked for: leaving them out loosens no other test
    pix = next(c for c in rows[0]["channels"] if c["channel"] == "distance:pixel")
    assert pix["p_adjusted"] == pytest.approx(min(1.0, rows[0]["screen"]["pixel"]["p"] * n_screening_tests(asked)))


def _seed_set_fitted_at_truth(tmp_path, w_d_range):
    """A small gray reference-camera seed set (16 seeds, data seed 3, albedos drawn in ``w_d_range``, nothing hidden)
    fitted at its truth (no fitting run): its :class:`DiagnosisData` and the true per-seed w_d."""
    from synthaug.diagnose.reference_camera import load_truth, make_measured_seedset
    from synthaug.diagnose.residuals import load_diagnosis_data
    from synthaug.effects.registry import PAPER_EFFECTS
    from synthaug.params import CaptureParams

    p = make_measured_seedset(tmp_path / "m", n_seeds=16, frame_size=(96, 128), object_px=(16, 20),
                              view_step_deg=30, sprite_size=48, seed=3, paper_ranges={"w_d": w_d_range})
    truth, textra, _ = load_truth(p)
    theta = CaptureParams(truth.as_dict(), effects=PAPER_EFFECTS)
    extra = [{"distance": 1.0, "generator_seed": 7 + i, "object_scale": float(e["object_scale"])}
             for i, e in enumerate(textra)]
    theta.save(tmp_path / "fit.json", extra=extra, metadata={"config": {"step_deg": 30, "sprite_size": 48}})
    return load_diagnosis_data(p, tmp_path / "fit.json", "quadcopter"), truth.as_dict()["w_d"][:, 0]


def test_tone_evidence_sees_a_tone_curve_and_not_added_noise(tmp_path):
    """Issue 20: a rising noise level function is shot noise or an expansive tone curve; only the tone curve
    changes the signal. Hand-built patches over a reference-camera seed set's layers: the fitted model's render
    through a tone curve x^1.4 (and a little noise), and the same render with shot noise added instead
    (sd 0.04·sqrt(I)); the tone curve the NLF implies (slope +0.57 -> g = 1.4) must lower the pixel distance of
    the first and raise that of the second, and name each one's noise-level channel accordingly."""
    from synthaug.diagnose.diagnosis_data import pixel_distance, render_with
    from synthaug.diagnose.screening import base_render, noise_level_channel, tone_evidence

    data, w = _seed_set_fitted_at_truth(tmp_path, (0.3, 0.45))
    gen = torch.Generator().manual_seed(0)
    clean = render_with(data, None, w_d=w)
    noise = lambda sd: sd * torch.randn(clean.shape, generator=gen)  # noqa: E731
    nc = {"slope": 2 * 0.4 / 1.4, "t": 40.0, "p": 1e-30, "n_seeds": 16, "gain": 0.004, "fitted_slope": 2 * 0.4 / 1.4}
    named = {}
    for kind, real in (("gamma", render_with(data, {"gamma": {"gamma_g": 1.4}}, w_d=w) + noise(0.01)),
                       ("shot_noise", clean + noise(0.04 * clean.clamp_min(0).sqrt()))):
        data.real = real.clamp(0, 1)
        tone = tone_evidence(data, nc, pixel_distance(data.real, base_render(data)[0]))
        assert tone["implied_gamma_g"] == pytest.approx(1.4)
        assert (tone["gain"] > 0) == (kind == "gamma"), (kind, tone)
        named[kind] = [e for e in ("gamma", "shot_noise") if noise_level_channel(e, nc, 30, 0.01, tone)["significant"]]
    assert named == {"gamma": ["gamma"], "shot_noise": ["shot_noise"]}


# ----------------------------------------------------------------- residual hints
@pytest.mark.parametrize("period, periodic, hinted", [
    (8.0, True, True), (4.0, True, True), (8 / 3, True, True), (2.0, True, True),  # the 8-px grid's harmonics k/8
    (1 / (0.125 + 0.0125), True, True),  # one step of the periodic measures' frequency grid off 1/8
    (4.9, True, False), (1 / 0.1875, True, False), (3.3, True, False), (10.0, True, False),  # off the grid
    (8.0, False, False), (None, True, False), (float("nan"), True, False),  # no period: not a codec's grid
])
def test_line_structures_point_at_compression_only_on_the_8px_block_grid(period, periodic, hinted):
    from synthaug.diagnose.report import HINTS, structure_hints

    for name in ("periodic_rows", "periodic_columns", "column_pattern", "row_pattern"):
        m = {"p": 1e-6, "significant": True, "period_px": period}
        if name.endswith("_pattern"):
            m["periodic"] = periodic
        elif not periodic:
            continue  # the periodic_* measures always report a peak
        assert structure_hints(name, m) == (("compression",) if hinted else ()), (name, period)
    for name in ("tone_curve", "high_frequency", "block_8x8", "radial"):  # other structures: the table as it is
        assert structure_hints(name, {"p": 1e-6, "period_px": 4.9}) == HINTS[name]


def test_a_column_pattern_off_the_block_grid_is_neither_a_compression_hint_nor_explained_by_it():
    # the real drones' case (stop 32): compression accepted from the frames, and a fixed column pattern with a
    # 4.9-px period left in the residual; it must stay in the "unexplained" list, and not put compression first
    from synthaug.diagnose.report import _order, left_unexplained

    off = {"p": 1e-5, "significant": True, "period_px": 4.9, "periodic": True, "value": 0.4}
    on = dict(off, period_px=8.0)
    tone = {"p": 1e-4, "significant": True, "value": -0.6}
    cands = ["defocus", "compression", "gamma", "exposure", "haze"]
    order, hinted = _order({"column_pattern": off, "tone_curve": tone}, cands)
    assert hinted == ["gamma", "exposure", "haze"] and order == ["gamma", "exposure", "haze", "defocus", "compression"]
    order, hinted = _order({"column_pattern": on, "tone_curve": tone}, cands)
    assert hinted == ["compression", "gamma", "exposure", "haze"]
    left = left_unexplained({"column_pattern": off, "tone_curve": tone, "block_8x8": {"p": 1e-7}}, ["compression"])
    assert sorted(left) == ["column_pattern", "tone_curve"]
    left = left_unexplained({"column_pattern": on, "tone_curve": tone, "block_8x8": {"p": 1e-7}}, ["compression"])
    assert sorted(left) == ["tone_curve"]
    assert sorted(left_unexplained({"column_pattern": off, "tone_curve": tone}, ["gamma"])) == ["column_pattern"]


@pytest.mark.parametrize("explained", [True, False])
def test_a_distance_gain_that_frame_evidence_explains_is_not_accepted_first(monkeypatch, explained):
    """Forward selection: haze's held-out HOG gain comes first by rank; when shot noise (evidenced by the frames' noise
    level function, at the setting the frames read) explains it — haze re-screened on top of it is no longer
    significant — shot noise is accepted first and haze drops out; when it does not, the order stays."""
    import synthaug.diagnose.screening as scr
    from synthaug.diagnose.report import _forward_selection

    def row(effect, channel, significant=True):
        return {"effect": effect, "channel": channel, "significant": significant, "score": 3.0, "gain": 0.02,
                "p_adjusted": 1e-3, "noise_setting": {"shot_sigma": 0.04} if channel == "noise_level" else None,
                "frame_setting": None, "screen": {"feature": {"setting": {"haze_extinction_px": 15.0}},
                                                  "pixel": {"setting": {}}}}

    calls = []

    def fake_screen(data, names, *, given=None, **kw):
        calls.append((list(names), dict(given or {})))
        given = given or {}
        return [row(n, "distance:feature", significant=not (explained and "shot_noise" in given)) if n == "haze"
                else row(n, "noise_level") for n in names]

    monkeypatch.setattr(scr, "screen_candidates", fake_screen)
    first, picked = _forward_selection(None, ["haze", "shot_noise"], k=5, seed=0, alpha=0.01, max_effects=3,
                                       say=lambda s: None)
    order = [(r["effect"], list(given)) for r, given in picked]
    if explained:
        assert order == [("shot_noise", [])]
        assert (["haze"], {"shot_noise": {"shot_sigma": 0.04}}) in calls  # screened on top of the frames' setting
    else:
        assert order == [("haze", []), ("shot_noise", ["haze"])]


def test_a_distance_gain_another_candidate_explains_better_does_not_name_its_effect():
    """Stop 94: haze at airlight 0.85 was named defocus from a significant 4.9 % held-out pixel gain while haze, not
    significant itself, explained the same pixel distance by 6.5 %. In the detector's features and in pixels a
    significant gain names its effect only where no valid candidate explains that distance better; the chroma channel
    keeps its own rival (the object's paint)."""
    from synthaug.diagnose.report import write_markdown
    from synthaug.diagnose.screening import RIVAL_SPACES, explained_better

    def ch(space, gain, significant, other_ok=True):
        return {"channel": space, "gain": gain, "significant": significant, "other_ok": other_ok, "z": 3.0,
                "p_adjusted": 1e-4}

    pix, feat, col = "distance:pixel", "distance:feature", "distance:colour"
    assert RIVAL_SPACES == (feat, pix)
    channels = [[ch(pix, 0.049, True), ch(feat, 0.001, False)],  # defocus
                [ch(pix, 0.065, False), ch(feat, 0.036, False), ch(col, 0.14, False)],  # haze
                [ch(pix, 0.030, True), ch(feat, 0.020, True)],  # gamma: its feature gain is beaten by haze's too
                [ch(pix, 0.090, False, other_ok=False), ch(col, 0.30, True)]]  # buys pixels by losing features
    explained_better(["defocus", "haze", "gamma", "sharpening"], channels)
    (d_pix, _), (h_pix, _, h_col), (g_pix, g_feat), (s_pix, s_col) = channels
    assert not d_pix["significant"] and d_pix["explained_better_by"] == {"effect": "haze", "gain": 0.065}
    assert not g_pix["significant"] and g_pix["explained_better_by"]["effect"] == "haze"
    assert not g_feat["significant"] and g_feat["explained_better_by"] == {"effect": "haze", "gain": 0.036}
    assert s_col["significant"] and "explained_better_by" not in s_col  # chroma: not compared here
    assert not any("explained_better_by" in c for c in (h_pix, h_col, s_pix))  # none beaten that was not named
    # the best explanation keeps its name, a smaller significant one beside it does not; equal gains keep both
    top = [[ch(pix, 0.05, True)], [ch(pix, 0.04, True)], [ch(pix, 0.05, True)]]
    explained_better(["a", "b", "c"], top)
    assert [c[0]["significant"] for c in top] == [True, False, True]
    alone = [[ch(pix, 0.01, True)], [ch(feat, 0.5, True)]]  # a rival in the other space is no rival
    explained_better(["a", "b"], alone)
    assert alone[0][0]["significant"] and alone[1][0]["significant"]
    # a gain the whole frames corroborate (a lens whose frames' edges steepen toward the corners) keeps its name
    lens = [[{**ch(pix, 0.012, True), "corroborated_by": {"statistic": "edge_radial"}}], [ch(pix, 0.0375, False)]]
    explained_better(["lens_distortion", "defocus"], lens)
    assert lens[0][0]["significant"] and "explained_better_by" not in lens[0][0]
    # the report says why the significant gain names nothing
    base = {"inputs": {"seeds": "s", "n_seeds": 60, "mesh": "m", "fit": "f", "distance": "hog", "k_folds": 5,
                       "alpha": 0.01}, "findings": [], "residuals": {}, "parameter_dependence": [],
            "realism": {"accuracy_base": 0.5}, "seconds": 1.0}
    row = {"effect": "defocus", "significant": False, "channel": pix, "score": 4.1, "gain_feature": 0.0,
           "gain_pixel": 0.049, "channels": channels[0]}
    md = write_markdown({**base, "screened": [row]})
    assert ("Defocus's distance:pixel gain (4.9 % held out) passed its test but does not name it: `haze` explains "
            "the same distance better (6.5 %)") in md
    assert "names nothing: see below" in md and "names nothing" not in write_markdown(
        {**base, "screened": [{**row, "channels": [channels[1][0]]}]})


def test_screened_rows_name_no_effect_another_candidate_out_explains(tmp_path):
    """On a screening of measured seeds (defocus hidden, gray): every significant distance channel has the largest
    valid gain of its space, every row's significance is that of its channels, and the rule is in the report."""
    from synthaug.diagnose.report import _residual_sections
    from synthaug.diagnose.screening import (BLUR_RULE, OBJECTS_RULE, RIVAL_RULE, RIVAL_SPACES, frame_evidence,
                                             frames_blurred, screen_candidates)

    data = _gray_case_fitted_at_truth(tmp_path, "defocus", {"defocus_sigma": 1.5}, n_seeds=24)
    rows = screen_candidates(data, ["defocus", "haze", "gamma", "rotor_blur"], k=4)
    assert len(rows) == 4 and rows[0]["significant"]  # something to out-explain
    # the defocus blurs the scene's edges as well: the frames read blurrier than clean frames, nothing withheld
    assert frames_blurred("defocus", frame_evidence(data))["blurred"]
    assert not any(c.get("frames_veto") for r in rows for c in r["channels"])
    for space in RIVAL_SPACES:
        valid = {r["effect"]: c["gain"] for r in rows for c in r["channels"] if c["channel"] == space and c["other_ok"]}
        for r in rows:
            c = next(c for c in r["channels"] if c["channel"] == space)
            if c["significant"]:
                assert c["gain"] >= max(valid.values())
            if "explained_better_by" in c:
                eb = c["explained_better_by"]
                assert eb["gain"] == valid[eb["effect"]] > c["gain"] and not c["significant"]
    for r in rows:
        assert r["significant"] == any(c["significant"] for c in r["channels"])
    sections = _residual_sections(data, {"structure": {}, "fmap": None, "dependence": []}, [])
    assert sections["significance"]["rule"].endswith(RIVAL_RULE)
    assert OBJECTS_RULE in sections["significance"]["rule"]  # one rule, written where it applies
    assert BLUR_RULE in sections["significance"]["rule"]


def test_a_gain_explained_better_is_screened_again_on_top_of_the_better_explanation(monkeypatch):
    """Two hidden effects (defocus and rotor blur, test_two_hidden_effects_are_both_found): in the first round rotor
    blur's pixel gain is larger, so defocus's significant gain names nothing (explained_better); once rotor blur is
    accepted, defocus is screened again on top of it and named if it stands. A candidate neither significant nor
    out-explained is not screened again."""
    import synthaug.diagnose.screening as scr
    from synthaug.diagnose.report import _forward_selection

    def row(effect, significant, beaten_by=None):
        ch = {"channel": "distance:pixel", "significant": significant, "gain": 0.03}
        if beaten_by:
            ch["explained_better_by"] = {"effect": beaten_by, "gain": 0.05}
        return {"effect": effect, "channel": "distance:pixel", "significant": significant, "score": 3.0,
                "gain": 0.03, "p_adjusted": 1e-3, "noise_setting": None, "frame_setting": None, "channels": [ch],
                "screen": {"feature": {"setting": {}}, "pixel": {"setting": {"x": 1.0}}}}

    calls = []

    def fake_screen(data, names, *, given=None, **kw):
        calls.append((list(names), sorted(given or {})))
        if not given:
            return [row("rotor_blur", True), row("defocus", False, beaten_by="rotor_blur"), row("gamma", False)]
        return [row(n, True) for n in names]

    monkeypatch.setattr(scr, "screen_candidates", fake_screen)
    _, picked = _forward_selection(None, ["rotor_blur", "defocus", "gamma"], k=5, seed=0, alpha=0.01,
                                   max_effects=3, say=lambda s: None)
    assert [(r["effect"], list(given)) for r, given in picked] == [("rotor_blur", []), ("defocus", ["rotor_blur"])]
    assert calls[1] == (["defocus"], ["rotor_blur"])  # gamma, never significant, is not screened again


def test_object_paint_renders_through_the_renderer_and_is_recovered(tmp_path):
    """The object's colour read beside the colour channel (issue 20, stop 93): every paint's chroma distance from
    two renders equals the renderer's own image with the painted albedo (w_d per channel, w solved by numpy's least
    squares), and the paint the reference camera put on the object is the one read."""
    from synthaug.diagnose.diagnosis_data import paint_chroma_distances
    from synthaug.diagnose.nuisances import Nuisances, paint_tint
    from synthaug.diagnose.reference_camera import make_measured_seedset
    from synthaug.diagnose.residuals import chroma_distance, load_diagnosis_data, render_rgb
    from synthaug.diagnose.screening import kfold, object_colour
    from synthaug.params import CaptureParams

    p = make_measured_seedset(tmp_path / "m", n_seeds=12, colour=True, frame_size=(96, 128), object_px=(18, 22),
                              view_step_deg=30, sprite_size=48,
                              nuisances=Nuisances(paint_saturation=0.1, paint_hue_deg=120.0))
    theta, extra, _ = CaptureParams.load_with_extra(p / "truth.json")
    theta.save(tmp_path / "fit.json", extra=extra, metadata={"config": {"step_deg": 30, "sprite_size": 48}})
    data = load_diagnosis_data(p, tmp_path / "fit.json", "quadcopter")
    tints = np.stack([paint_tint(0.0, 0.0), paint_tint(0.05, 300.0), paint_tint(0.1, 120.0)])
    fast = paint_chroma_distances(data, None, torch.tensor(tints))
    n = len(data)
    real = data.real_rgb.double().numpy().reshape(n, -1)
    for k, t in enumerate(tints):
        tw = torch.tensor(t, dtype=torch.float32)
        i0 = render_rgb(data, None, w_d=torch.zeros(n, 3), clamp=False).double().numpy().reshape(n, -1)
        i1 = render_rgb(data, None, w_d=tw.expand(n, 3), clamp=False).double().numpy().reshape(n, -1)
        w = np.array([np.linalg.lstsq((i1 - i0)[i][:, None], (real - i0)[i], rcond=None)[0][0] for i in range(n)])
        w = np.clip(w, 0.0, 1.0)
        img = render_rgb(data, None, w_d=torch.tensor(w, dtype=torch.float32)[:, None] * tw)  # clamped
        np.testing.assert_allclose(fast[k], chroma_distance(data.real_rgb, img), rtol=2e-4, atol=1e-4)
    assert fast[2].mean() < fast[0].mean() and fast[2].mean() < fast[1].mean()  # the true paint fits best
    oc = object_colour(data, kfold(n, 3, np.random.default_rng(0)))
    assert abs((oc["setting"]["paint_hue_deg"] - 120.0 + 180.0) % 360.0 - 180.0) <= 15.0, oc
    assert 0.05 <= oc["setting"]["paint_saturation"] <= 0.15 and oc["gain"] > 0 and oc["p"] < 0.01


def test_haze_is_credited_only_beyond_the_objects_own_colour(tmp_path):
    """Stop 93: a slightly bluish object (a paint, an appearance) is most of haze's sky-coloured airlight in chroma.
    Haze on a painted object must beat the best case-wide paint alone on held-out seeds; white balance, which a
    paint reproduces exactly, is not asked to. On a painted clean case haze does not beat the paint; on a hazed
    neutral object, and on a hazed painted one, it does."""
    from synthaug.diagnose.nuisances import Nuisances
    from synthaug.diagnose.reference_camera import make_measured_seedset
    from synthaug.diagnose.residuals import load_diagnosis_data
    from synthaug.diagnose.screening import PAINT_MIMICS, screen_candidates
    from synthaug.params import CaptureParams

    def colour_channels(name, **kw):
        p = make_measured_seedset(tmp_path / name, n_seeds=24, colour=True, frame_size=(96, 128), object_px=(18, 22),
                                  view_step_deg=30, sprite_size=48, seed=11, **kw)
        theta, extra, _ = CaptureParams.load_with_extra(p / "truth.json")
        theta.save(tmp_path / f"{name}.json", extra=extra, metadata={"config": {"step_deg": 30, "sprite_size": 48}})
        data = load_diagnosis_data(p, tmp_path / f"{name}.json", "quadcopter")
        rows = screen_candidates(data, ["haze", "white_balance"], k=4, seed=0)
        return {r["effect"]: next(c for c in r["channels"] if c["channel"] == "distance:colour") for r in rows}

    assert PAINT_MIMICS == ("white_balance",)
    painted = colour_channels("painted", nuisances=Nuisances(paint_saturation=0.1, paint_hue_deg=150.0))
    assert painted["haze"]["gain"] > 0  # a bluish paint reads as airlight in chroma ...
    assert painted["haze"]["over_paint"]["gain"] < 0 and not painted["haze"]["significant"]  # ... but a paint is better
    assert painted["white_balance"]["over_paint"] is None
    hazed = colour_channels("hazed", hidden={"haze": {"haze_extinction_px": 15.0, "haze_airlight": 0.85}})
    assert hazed["haze"]["over_paint"]["gain"] > 0  # the airlight follows each seed's sky and distance
    # stop 94: haze on a painted object is tested as haze on a painted object (setting and paint chosen together)
    # against the paint alone, not haze on a grey object against the paint (where a bluish paint took haze's
    # name from it: a fresh power case named defocus)
    # (the realistic default strength on that case's paint: against grey haze the paint's p was 0.036 before
    # Bonferroni, against painted haze 1e-4)
    both = colour_channels("both", hidden={"haze": {"haze_extinction_px": 10.0, "haze_airlight": 0.85}},
                           nuisances=Nuisances(paint_saturation=0.075, paint_hue_deg=287.0))
    assert both["haze"]["over_paint"]["gain"] > 0 and both["haze"]["over_paint"]["p_adjusted"] < 0.01


def test_a_known_object_colour_tells_a_white_balance_from_the_paint(tmp_path):
    """On the object alone a white balance is a paint along the colour-temperature axis (stop 93). Given the
    object's colour (``diagnose(object_colour=)``, ``--object-colour``), the colour channel compares against it:
    a bluish paint is no longer a white balance, and a white balance on that painted object still is."""
    from synthaug.diagnose.diagnosis_data import object_colour_factors
    from synthaug.diagnose.nuisances import Nuisances, paint_tint
    from synthaug.diagnose.reference_camera import make_measured_seedset
    from synthaug.diagnose.residuals import load_diagnosis_data
    from synthaug.diagnose.screening import screen_candidates
    from synthaug.params import CaptureParams

    paint = Nuisances(paint_saturation=0.1, paint_hue_deg=180.0)  # bluish, on the white balance's axis

    def white_balance(name, known, **kw):
        p = make_measured_seedset(tmp_path / name, n_seeds=24, colour=True, frame_size=(96, 128), object_px=(18, 22),
                                  view_step_deg=30, sprite_size=48, seed=12, nuisances=paint, **kw)
        theta, extra, _ = CaptureParams.load_with_extra(p / "truth.json")
        theta.save(tmp_path / f"{name}.json", extra=extra, metadata={"config": {"step_deg": 30, "sprite_size": 48}})
        data = load_diagnosis_data(p, tmp_path / f"{name}.json", "quadcopter")
        data.object_rgb = object_colour_factors(paint.paint_rgb) if known else None
        row = screen_candidates(data, ["white_balance"], k=4, seed=0)[0]
        return next(c for c in row["channels"] if c["channel"] == "distance:colour")

    assert white_balance("clean", known=False)["significant"]  # the paint reads as a white balance ...
    assert not white_balance("clean", known=True)["significant"]  # ... not once the object's colour is known
    assert white_balance("wb", known=True, hidden={"white_balance": {"wb_gain": 0.8}})["significant"]
    np.testing.assert_allclose(object_colour_factors(2.0 * paint_tint(0.1, 180.0)), paint_tint(0.1, 180.0))
    with pytest.raises(ValueError, match="three positive"):
        object_colour_factors([1.0, 0.0, 1.0])


def test_the_periodic_peak_is_sought_in_frame_frequencies_above_the_shape_band():
    # per-seed row/column spectra of a 64-px patch: every seed carries a comb at 0.45 cycles per frame px (log
    # ratio 1), and the large-scale seeds (4 px of frame per 3 patch px) a stronger anisotropy at 0.2 cycles per
    # frame px, below PERIODIC_MIN_FREQUENCY (an object's shape): the peak is the comb; the log ratios are numpy's
    # interpolation of each seed's patch spectrum at the frame frequency, by hand
    from synthaug.diagnose.residuals import PERIODIC_MIN_FREQUENCY, periodic_peak

    n, p = 40, 64
    f = np.fft.rfftfreq(p)
    fs = np.where(np.arange(n) < 12, 4 / 3, 1.0)  # 12 of 40 seeds reach 0.2 / (4/3) = 0.15 frame cycles
    a, b = np.ones((n, f.size)), np.ones((n, f.size))
    for i in range(n):
        a[i] *= np.exp(np.interp(f / fs[i], [0.43, 0.45, 0.47], [0.0, 1.0, 0.0], left=0.0, right=0.0))
        if fs[i] > 1:
            a[i] *= np.exp(3.0 * np.exp(-0.5 * ((f / fs[i] - 0.2) / 0.01) ** 2))
    freq, lr, m = periodic_peak(a, b, fs)
    assert freq == pytest.approx(0.45)
    assert np.isfinite(lr).tolist() == (fs == 1).tolist()  # the large-scale seeds' patches end at 0.375 frame cycles
    want = [np.interp(0.45, f[f >= 0.2] / fs[i], np.log(a[i, f >= 0.2]), right=np.nan) for i in range(n)]
    np.testing.assert_allclose(lr, want, rtol=1e-12)
    grid = np.round(np.arange(PERIODIC_MIN_FREQUENCY, 0.5 + 1e-9, 0.0125), 4)
    reach = [int(((0.2 / fs <= g) & (g <= 0.5 / fs)).sum()) for g in grid]  # the seeds whose patch band holds g
    assert m == sum(c >= max(5, n // 4) for c in reach)  # the Bonferroni count: the frequencies enough seeds reach
    # searched from 0.15, the shape band's anisotropy (exp(3) on 12 seeds) would have been the peak
    low, _, _ = periodic_peak(a, b, fs, min_frequency=0.1)
    assert low == pytest.approx(0.2, abs=0.0125)


def test_highlight_strength_reads_an_added_highlight_whatever_the_albedo(tmp_path):
    """Issue 20, specular (stop 110): the highlight channel's amplitude. Hand-built patches over a reference-camera
    seed set's layers (fit at the truth): the model's render with a Blinn-Phong highlight (ks 0.4 at the template's
    exponent) added on objects of albedo 0.1-0.5 reads k 0.4, seed by seed as numpy's least squares of the same
    renders; the model's render with every albedo 30 % brighter (a shading mismatch that scales with the albedo)
    reads k near 0; a channel without a calibrated floor names nothing."""
    from synthaug.diagnose.diagnosis_data import render_with
    from synthaug.diagnose.screening import HIGHLIGHT_SHININESS, highlight_channel, highlight_strength

    data, w = _seed_set_fitted_at_truth(tmp_path, (0.1, 0.5))
    gen = torch.Generator().manual_seed(0)
    spec = {"specular": {"specular_ks": 0.4, "specular_shininess": HIGHLIGHT_SHININESS}}
    data.real = (render_with(data, spec, w_d=w, clamp=False) + 0.003 * torch.randn(data.real.shape, generator=gen))
    hl = highlight_strength(data)
    assert hl["k"] == pytest.approx(0.4, abs=0.02) and hl["n"] >= 12 and hl["t"] > 10

    # seed by seed: numpy's least squares of real - A(0.2) on [dA/dw, the template] over the same renders
    n = len(data)
    a0 = render_with(data, None, w_d=torch.full((n,), 0.2), clamp=False).double().flatten(1).numpy()
    a1 = render_with(data, None, w_d=torch.full((n,), 0.6), clamp=False).double().flatten(1).numpy()
    one = {"specular": {"specular_ks": 1.0, "specular_shininess": HIGHLIGHT_SHININESS}}
    h = render_with(data, one, w_d=torch.full((n,), 0.2), clamp=False).double().flatten(1).numpy() - a0
    y = data.real.double().flatten(1).numpy() - a0
    ref = [np.linalg.lstsq(np.stack([(a1[i] - a0[i]) / 0.4, h[i]], 1), y[i], rcond=None)[0][1] for i in range(n)
           if (h[i] ** 2).sum() > 1e-8]
    np.testing.assert_allclose(hl["per_seed_k"], ref, rtol=1e-6, atol=1e-8)

    data.real = (render_with(data, None, w_d=1.3 * w) + 0.003 * torch.randn(data.real.shape, generator=gen)).clamp(0, 1)
    assert abs(highlight_strength(data)["k"]) < 0.02
    uncalibrated = dict(hl, p=1e-12)
    ch = highlight_channel("specular", uncalibrated, 49, 0.01)
    assert ch["setting"] == {"specular_ks": round(hl["k"], 3), "specular_shininess": HIGHLIGHT_SHININESS}
    if ch["floor"] is None:
        assert not ch["significant"]
    else:  # calibrated: 0.4 lies above every clean material's amplitude
        assert ch["significant"] and ch["floor"] < 0.4
