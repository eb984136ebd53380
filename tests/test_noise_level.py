"""The camera's noise level function (synthaug.diagnose.noise) against known noise models and scipy."""

from __future__ import annotations

import math

import numpy as np
import pytest

from synthaug.diagnose.noise import (
    _heldout_loglik,
    frame_noise_levels,
    nlf_slope,
    noise_channel,
    shot_noise_sigma,
)


def _scene(rng: np.random.Generator, h: int = 300, w: int = 400) -> np.ndarray:
    """A smooth sky-like scene spanning 0.3-0.85."""
    return np.tile(np.linspace(0.3, 0.85, w), (h, 1)) + 0.02 * np.sin(np.arange(h) / 15.0)[:, None]


def test_binned_variance_recovers_a_known_noise_level_function():
    rng = np.random.default_rng(0)
    b = _scene(rng)
    a_, b_ = 4e-5, 1.6e-3  # read + shot: var = a + b I
    f = b + rng.normal(size=b.shape) * np.sqrt(a_ + b_ * b)
    nlf = frame_noise_levels(f, b)
    assert len(nlf["signal"]) >= 10
    true = a_ + b_ * nlf["signal"]
    # the high-pass (5x5 local mean removed) keeps 24/25 of white noise's variance
    np.testing.assert_allclose(nlf["var"], true * 24 / 25, rtol=0.08)
    # the log-log slope equals numpy's weighted line fit through the bins, and the model's local slope
    x, y = np.log(nlf["signal"]), np.log(nlf["var"])
    ref = np.polyfit(x, y, 1, w=np.sqrt(nlf["count"]))[0]
    assert nlf_slope(nlf) == pytest.approx(ref, abs=0.02)
    i_mid = float(np.exp(x.mean()))
    assert nlf_slope(nlf) == pytest.approx(b_ * i_mid / (a_ + b_ * i_mid), abs=0.1)


def test_a_tone_curve_after_read_noise_makes_the_nlf_fall_as_predicted():
    rng = np.random.default_rng(1)
    x = _scene(rng) ** (1 / 0.75)  # linear radiance
    g, sd = 0.75, 0.004
    f = np.clip(x + sd * rng.normal(size=x.shape), 1e-4, 1) ** g
    b = x ** g
    nlf = frame_noise_levels(f, b)
    assert nlf_slope(nlf) == pytest.approx(2 * (g - 1) / g, abs=0.08)  # var ∝ f'(x)² = I^(2(g-1)/g)


def test_textured_pixels_and_the_object_are_left_out():
    rng = np.random.default_rng(2)
    b = _scene(rng)
    f = b + 0.01 * rng.normal(size=b.shape)
    ex = np.zeros_like(b, bool)
    ex[40:80, 50:90] = True
    f[ex] = 0.0  # an "object" that is nothing like noise
    b_tex = b.copy()
    b_tex[150:190, 220:260] += 0.2 * (np.indices((40, 40)).sum(0) % 2)  # a checkerboard, misregistered in f
    f[150:190, 221:261] += 0.2 * (np.indices((40, 40)).sum(0) % 2)
    nlf = frame_noise_levels(f, b_tex, exclude=ex)
    np.testing.assert_allclose(nlf["var"], 1e-4 * 24 / 25, rtol=0.12)
    with pytest.raises(ValueError, match="same shape"):
        frame_noise_levels(f, b[:10])


def test_heldout_loglik_matches_scipy_on_the_samples():
    from scipy import stats

    rng = np.random.default_rng(3)
    sig = np.array([0.3, 0.5, 0.7])
    sd_true = np.sqrt(1e-3 * sig)
    samples = [rng.normal(0, s, 4000) for s in sd_true]
    nlf = {"signal": sig, "var": np.array([np.mean(x ** 2) for x in samples]), "count": np.array([4000] * 3)}
    for slope in (0.0, 1.0):
        shape = sig ** slope
        level = float(np.mean(nlf["var"] / shape))
        ref = np.mean(np.concatenate([stats.norm.logpdf(x, 0, math.sqrt(level * s)) for x, s in zip(samples, shape)]))
        assert _heldout_loglik(nlf, slope) == pytest.approx(ref, rel=1e-9)
    assert _heldout_loglik(nlf, 1.0) > _heldout_loglik(nlf, 0.0)  # the true model wins


def test_noise_channel_reads_flat_noise_as_nothing():
    from synthaug.diagnose.screening import kfold, noise_level_channel

    rng = np.random.default_rng(4)
    nlfs_flat, nlfs_shot = [], []
    for i in range(16):
        b = _scene(rng, 96, 128) * rng.uniform(0.8, 1.1)
        nlfs_flat.append(frame_noise_levels(b + 0.006 * rng.normal(size=b.shape), b))
        nlfs_shot.append(frame_noise_levels(b + rng.normal(size=b.shape) * np.sqrt(1e-3 * b), b))
    folds = kfold(16, 4, rng)
    flat, shot = noise_channel(nlfs_flat, folds), noise_channel(nlfs_shot, folds)
    assert abs(flat["slope"]) < 0.1 and shot["slope"] > 0.8 and shot["gain"] > 0
    assert not noise_level_channel("shot_noise", flat, 30, 0.01)["significant"]
    assert noise_level_channel("shot_noise", shot, 30, 0.01)["significant"]
    assert not noise_level_channel("gamma", shot, 30, 0.01)["significant"]  # wrong direction for a tone curve
    assert noise_level_channel("vignetting", shot, 30, 0.01) is None


def test_a_background_that_is_the_frame_off_the_object_gives_no_levels():
    # an ingested background replaces only the object region: frame - background is 0 elsewhere, no noise to see
    rng = np.random.default_rng(5)
    f = _scene(rng) + 0.01 * rng.normal(size=(300, 400))
    b = f.copy()
    ex = np.zeros_like(f, bool)
    ex[100:140, 100:150] = True
    b[ex] = 0.5
    assert len(frame_noise_levels(f, b, exclude=ex)["signal"]) == 0


def test_an_aligned_neighbour_frame_gives_the_nlf_of_both_frames():
    """Ingested video: the second look is the next frame, aligned by a homography (here a 3-px pan): the
    difference holds both frames' noise, var = 2 (a + b I); its object (box) and the warp's border are left out."""
    from synthaug.diagnose.noise import aligned_neighbour

    rng = np.random.default_rng(6)
    h, w = 300, 400
    wide = np.tile(np.linspace(0.3, 0.85, w + 3), (h, 1))
    sd = lambda x: np.sqrt(4e-5 + 1.6e-3 * x)  # noqa: E731
    f = wide[:, :w] + rng.normal(size=(h, w)) * sd(wide[:, :w])
    nb = wide[:, 3:] + rng.normal(size=(h, w)) * sd(wide[:, 3:])  # nb[y, x] = scene[y, x + 3]
    nb[100:130, 200:240] = 0.05  # the neighbour's object
    H = [[1.0, 0.0, 3.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]  # nb pixel (x, y) -> f pixel (x + 3, y)
    warped, out = aligned_neighbour(f, nb, H, box=(200, 100, 40, 30), margin=0.0)
    assert out[:, :3].all() and not out[:, 3:].all()
    assert out[100:130, 203:243].all() and not out[100:130, 250:].any()
    np.testing.assert_allclose(warped[~out], wide[:, :w][~out], atol=0.2)
    nlf = frame_noise_levels(f, warped, exclude=out)
    np.testing.assert_allclose(nlf["var"], 2 * (4e-5 + 1.6e-3 * nlf["signal"]) * 24 / 25, rtol=0.08)


def test_a_codec_copy_is_not_noise():
    # two looks that differ only by sparse +-1 grey levels (a codec copied the block): no noise to measure
    rng = np.random.default_rng(7)
    b = np.round(_scene(rng) * 255) / 255
    f = b + (rng.random(b.shape) < 0.02) * rng.choice([-1, 1], size=b.shape) / 255
    assert len(frame_noise_levels(f, b)["signal"]) == 0
    g = b + rng.normal(size=b.shape) * 1.0 / 255  # one grey level of real noise: measured
    assert len(frame_noise_levels(np.round(g * 255) / 255, b)["signal"]) >= 10


def test_a_rising_noise_level_goes_to_gamma_or_shot_noise_by_the_signals_tone():
    """Issue 20: an expansive tone curve (g > 1) makes the noise rise with brightness as shot noise does (slope
    2(g - 1)/g = +0.57 at g = 1.4); the NLF was given to shot noise alone, so gamma 1.4 was named shot_noise in 5
    of 5 cases. The patches' tone decides now: the implied tone curve lowering the pixel distance is gamma's, else
    shot noise's; never both, and gamma's setting is the one the slope implies."""
    from synthaug.diagnose.screening import noise_level_channel, noise_setting

    rising = {"slope": 0.55, "t": 40.0, "p": 1e-30, "n_seeds": 60, "gain": 0.004, "fitted_slope": 0.55}
    tone_curve = {"implied_gamma_g": 1.38, "gain": 0.014, "t": 2.7, "explains": "gamma"}
    added_noise = {"implied_gamma_g": 1.38, "gain": -0.006, "t": -1.6, "explains": "shot_noise"}
    sig = lambda e, tone: noise_level_channel(e, rising, 30, 0.01, tone)["significant"]  # noqa: E731
    assert sig("gamma", tone_curve) and not sig("shot_noise", tone_curve)
    assert sig("shot_noise", added_noise) and not sig("gamma", added_noise)
    assert not sig("gamma", None) and sig("shot_noise", None)  # no tone evidence: shot noise, as before
    assert noise_level_channel("gamma", rising, 30, 0.01, tone_curve)["tone"]["explains"] == "gamma"
    assert noise_setting("gamma", rising)["gamma_g"] == pytest.approx(2.0 / (2.0 - 0.55))
    # a falling NLF is a compressive tone curve whatever the tone says (shot noise cannot make it fall)
    falling = {**rising, "slope": -0.64, "fitted_slope": -0.64}
    assert noise_level_channel("gamma", falling, 30, 0.01, None)["significant"]
    assert not noise_level_channel("shot_noise", falling, 30, 0.01, None)["significant"]
    assert "tone" not in noise_level_channel("gamma", falling, 30, 0.01, None)


def _tone_frames(rng: np.random.Generator, g: float, *, n: int = 12, hw: tuple[int, int] = (120, 160)
                 ) -> list[dict[str, np.ndarray]]:
    """NLFs of ``n`` frames with read noise changing from frame to frame, then a tone curve x^g after the sensor."""
    out = []
    for _ in range(n):
        b = _scene(rng, *hw) * rng.uniform(0.7, 1.1)
        lin = b ** (1.0 / g)  # the linear scene whose tone-mapped look is b
        out.append(frame_noise_levels(np.clip(lin + rng.uniform(0.003, 0.008) * rng.normal(size=b.shape), 0, 1) ** g,
                                      b))
    return out


def test_a_rising_noise_levels_shape_tells_a_tone_curve_from_shot_noise():
    """Stop 95: on fresh cases the patches' tone gave gamma 1.4 to shot noise in 2 of 5. The NLF's shape tells
    them apart: read noise through x^1.4 gives a power law var ∝ I^0.57 (straight in log-log), shot noise over
    read noise var = a + b·I (flat, then rising). Held-out seeds pick the generating shape; a shape gaining under
    5 % of the NLF's own gain (weak shot noise here: 2 %) or shot noise far above the read noise (a ≈ 0, the two
    shapes coincide) leaves the verdict to the patches' tone."""
    from synthaug.diagnose.noise import nlf_shape
    from synthaug.diagnose.screening import shape_verdict

    rng = np.random.default_rng(3)
    folds = [np.arange(i, 24, 4) for i in range(4)]
    for g in (1.25, 1.4):
        tone = _tone_frames(rng, g, n=24)
        sh, nc = nlf_shape(tone, folds), noise_channel(tone, folds)
        assert nc["slope"] > 0 and sh["gain"] > 0 and shape_verdict(sh, nc["gain"], 0.01) == "gamma"
    weak = _shot_frames(rng, 0.012, n=24)  # shot noise comparable to the read noise: curved
    sh, nc = nlf_shape(weak, folds), noise_channel(weak, folds)
    assert nc["slope"] > 0 and sh["gain"] < 0 and shape_verdict(sh, nc["gain"], 0.01) != "gamma"
    strong = _shot_frames(rng, 0.08, n=24)  # far above the read noise: var ≈ b·I, a power law of slope 1 too
    sh, nc = nlf_shape(strong, folds), noise_channel(strong, folds)
    assert shape_verdict(sh, nc["gain"], 0.01) != "gamma"
    # the channel follows a conclusive shape over the patches' tone, and the tone where the shape is not conclusive
    from synthaug.diagnose.screening import noise_level_channel

    rising = {"slope": 0.55, "t": 40.0, "p": 1e-30, "n_seeds": 60, "gain": 0.004, "fitted_slope": 0.55}
    added_noise = {"implied_gamma_g": 1.38, "gain": -0.006, "t": -1.6, "explains": "shot_noise"}
    power = {**rising, "shape": {"gain": 0.001, "p": 1e-7, "positive": 55, "n": 60, "per_seed": []}}
    sig = lambda e, nc, tone: noise_level_channel(e, nc, 30, 0.01, tone)["significant"]  # noqa: E731
    assert sig("gamma", power, added_noise) and not sig("shot_noise", power, added_noise)
    assert noise_level_channel("gamma", power, 30, 0.01, added_noise)["shape"]["explains"] == "gamma"
    tiny = {**rising, "shape": {"gain": 1e-5, "p": 0.009, "positive": 38, "n": 60, "per_seed": []}}  # 0.25 % of the NLF's gain
    assert sig("shot_noise", tiny, added_noise) and not sig("gamma", tiny, added_noise)


def _shot_frames(rng: np.random.Generator, sigma: float, *, n: int = 8, background_sd: float = 0.0,
                 hw: tuple[int, int] = (120, 160)) -> list[dict[str, np.ndarray]]:
    """NLFs of ``n`` frames with read noise changing from frame to frame (the gain) and shot noise ``sigma``;
    the background a second look whose noise has ``background_sd`` times the frame's std."""
    out = []
    for i in range(n):
        b = _scene(rng, *hw) * rng.uniform(0.7, 1.1)
        sd = np.sqrt(rng.uniform(0.003, 0.008) ** 2 + sigma ** 2 * b)
        out.append(frame_noise_levels(b + sd * rng.normal(size=b.shape), b + background_sd * sd * rng.normal(size=b.shape)))
    return out


@pytest.mark.parametrize("sigma", [0.02, 0.04, 0.08])
def test_shot_noise_sigma_recovers_the_cameras_shot_noise(sigma):
    rng = np.random.default_rng(int(sigma * 1000))
    assert shot_noise_sigma(_shot_frames(rng, sigma)) == pytest.approx(sigma, rel=0.08)


def test_shot_noise_sigma_counts_the_looks_and_reads_read_noise_as_none():
    rng = np.random.default_rng(11)
    # a frame minus its neighbour: two equal looks, said so by the NLFs' "looks"
    two = [{**n, "looks": 2.0} for n in _shot_frames(rng, 0.04, background_sd=1.0)]
    assert shot_noise_sigma(two) == pytest.approx(0.04, rel=0.08)
    # a background with noise of its own, not said: sigma reads sqrt(1 + kappa²) high (the reference camera's 0.35)
    kappa = 0.35
    assert shot_noise_sigma(_shot_frames(rng, 0.04, background_sd=kappa)) == pytest.approx(
        0.04 * math.sqrt(1 + kappa ** 2), rel=0.08)
    # read noise only (a different level per frame): no shot noise
    assert shot_noise_sigma(_shot_frames(rng, 0.0)) < 0.006
    # too few frames, or no spread of brightness: no reading
    assert shot_noise_sigma(_shot_frames(rng, 0.04, n=2)) is None
    flat = {"signal": np.array([0.5, 0.5]), "var": np.array([1e-4, 1.1e-4]), "count": np.array([500, 500])}
    assert shot_noise_sigma([flat] * 4) is None


def test_shot_noise_sigma_is_the_weighted_fit_by_hand():
    # exact variances on the affine model with one constant per frame: the fit returns the slope exactly
    sig = np.array([0.2, 0.4, 0.6, 0.8])
    nlfs = [{"signal": sig, "var": (a + 0.03 ** 2 * sig) * 24 / 25, "count": np.array([400, 300, 200, 100])}
            for a in (1e-5, 4e-5, 9e-5)]
    assert shot_noise_sigma(nlfs) == pytest.approx(0.03, rel=1e-9)


def test_the_nlf_sets_shot_noise_and_gamma_and_nothing_else():
    from synthaug.diagnose.screening import noise_setting

    nc = {"fitted_slope": 0.5, "shot_sigma": 0.041}
    assert noise_setting("shot_noise", nc) == {"shot_sigma": 0.041}
    assert noise_setting("shot_noise", {**nc, "shot_sigma": 0.5}) == {"shot_sigma": 0.2}  # the parameter's range
    assert noise_setting("shot_noise", {**nc, "shot_sigma": None}) is None
    assert noise_setting("gamma", nc) == {"gamma_g": pytest.approx(2 / 1.5)}
    assert noise_setting("defocus", nc) is None
