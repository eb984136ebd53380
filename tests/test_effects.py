"""Capture effects against independent numpy/scipy references."""

import math

import numpy as np
import pytest
import torch
from scipy import ndimage, signal

from synthaug.effects import functional as Fx
from synthaug.effects import simulate, sample_fields
from synthaug.effects.registry import Effect, RenderState, get_effect, list_effects, register_effect
from synthaug.params import CaptureParams, ParamSpec

RNG = np.random.default_rng(0)


def dense_gaussian_kernel(su, sv, angle, radius=25):
    """Sampled anisotropic Gaussian, covariance R diag(su², sv²) Rᵀ, u at `angle` from +x toward +y."""
    y, x = np.mgrid[-radius:radius + 1, -radius:radius + 1].astype(np.float64)
    c, s = math.cos(angle), math.sin(angle)
    u = x * c + y * s
    v = -x * s + y * c
    k = np.exp(-0.5 * (u ** 2 / su ** 2 + v ** 2 / sv ** 2))
    return k / k.sum()


def _t(a):
    return torch.tensor(a, dtype=torch.float64)


@pytest.mark.parametrize("sigma", [1.0, 2.0, 3.5])
def test_isotropic_blur_matches_scipy(sigma):
    x = RNG.random((2, 1, 40, 36))
    y = Fx.gaussian_blur_fft(_t(x), _t([sigma, sigma]), pad=20).numpy()
    for b in range(2):
        ref = ndimage.gaussian_filter(x[b, 0], sigma, mode="constant", truncate=10)
        np.testing.assert_allclose(y[b, 0], ref, atol=2e-3 if sigma < 1.5 else 1e-6)


def test_anisotropic_blur_matches_dense_kernel():
    x = np.zeros((1, 1, 64, 64))
    x[0, 0, 20:44, 28:36] = RNG.random((24, 8))
    su, sv, ang = 4.0, 1.5, 0.6
    y = Fx.gaussian_blur_fft(_t(x), _t([su]), _t([sv]), _t([ang]), pad=20).numpy()[0, 0]
    ref = signal.convolve2d(x[0, 0], dense_gaussian_kernel(su, sv, ang), mode="same")
    np.testing.assert_allclose(y, ref, atol=1e-5)


def test_blur_direction_convention():
    x = torch.zeros(2, 1, 41, 41, dtype=torch.float64)
    x[:, :, 20, 20] = 1
    y = Fx.gaussian_blur_fft(x, _t([4.0, 4.0]), _t([0.0, 0.0]), _t([0.0, math.pi / 2]), pad=15)
    # angle 0 smears along x (one row), angle π/2 along y (one column)
    assert y[0, 0, 20].sum() > 0.999 and y[0, 0, :, 20].sum() < 0.2
    assert y[1, 0, :, 20].sum() > 0.999 and y[1, 0, 20].sum() < 0.2


def test_small_sigma_is_band_limited_gaussian():
    """Below 1 px the transfer function is exp(-2π² fᵀΣf) on the DFT grid: check against numpy's FFT."""
    x = RNG.random((1, 1, 27, 27))  # odd: no Nyquist bin, where a rotated kernel is ambiguous
    su, sv, ang = 0.6, 0.3, 1.1
    y = Fx.gaussian_blur_fft(_t(x), _t([su]), _t([sv]), _t([ang]), pad=0).numpy()[0, 0]
    fy = np.fft.fftfreq(27)[:, None]
    fx = np.fft.fftfreq(27)[None, :]
    c, s = math.cos(ang), math.sin(ang)
    cov = np.array([[c, -s], [s, c]]) @ np.diag([su ** 2, sv ** 2]) @ np.array([[c, s], [-s, c]])
    quad = cov[0, 0] * fx ** 2 + 2 * cov[0, 1] * fx * fy + cov[1, 1] * fy ** 2
    ref = np.real(np.fft.ifft2(np.fft.fft2(x[0, 0]) * np.exp(-2 * math.pi ** 2 * quad)))
    np.testing.assert_allclose(y, ref, atol=1e-12)


def test_zero_sigma_is_identity():
    x = torch.rand(3, 2, 20, 24)
    y = Fx.gaussian_blur_fft(x, torch.zeros(3, 2), pad=6, border="replicate")
    torch.testing.assert_close(y, x, atol=1e-6, rtol=0)


def _layers(b=2, h=32, w=32, c=1):
    rng = np.random.default_rng(42)  # same layers at every call
    cov = np.zeros((b, 1, h, w))
    cov[:, :, 10:22, 8:24] = 1.0
    cov[:, :, 9, 8:24] = 0.5
    nrm = np.zeros((b, 3, h, w))
    nrm[:, 2] = 1.0
    nrm = nrm * (cov > 0)
    color = np.where(cov > 0, 0.2 + 0.3 * rng.random((b, c, h, w)), 0.0)
    bg = rng.random((b, c, h, w)) * 0.5 + 0.4
    return cov, nrm, color, bg


def test_motion_blur_and_composite_match_numpy():
    cov, _, color, bg = _layers()
    su, sv, ang = np.array([3.0, 2.0]), np.array([1.0, 1.5]), np.array([0.3, -1.0])
    col_b, cov_b = Fx.motion_blur(_t(color), _t(cov), _t(su), _t(sv), _t(ang), pad=20)
    img = Fx.composite(col_b, cov_b, _t(bg)).numpy()
    for b in range(2):
        k = dense_gaussian_kernel(su[b], sv[b], ang[b])
        premul = signal.convolve2d(color[b, 0] * cov[b, 0], k, mode="same")
        alpha = signal.convolve2d(cov[b, 0], k, mode="same")
        ref = premul + (1 - alpha) * bg[b, 0]  # the object smears over the background
        np.testing.assert_allclose(img[b, 0], ref, atol=1e-4)


def test_boundary_blur_matches_scipy_reference():
    cov, _, color, bg = _layers()
    img = color * cov + bg * (1 - cov)
    sig = np.array([1.5, 2.5])
    out = Fx.boundary_blur(_t(img), _t(cov), _t(sig), pad=12).numpy()
    for b in range(2):
        m = ndimage.gaussian_filter(cov[b, 0], sig[b], mode="nearest", truncate=8)
        blurred = ndimage.gaussian_filter(img[b, 0], sig[b], mode="nearest", truncate=8)
        band = np.clip(4 * m * (1 - m), 0, 1)
        ref = img[b, 0] + band * (blurred - img[b, 0])
        np.testing.assert_allclose(out[b, 0], ref, atol=2e-4)
        # far from the object nothing changes
        assert np.abs(out[b, 0, :2] - img[b, 0, :2]).max() < 1e-3  # far from the object: ~unchanged


def test_object_noise_only_on_object_pixels():
    cov, _, color, bg = _layers()
    img = _t(color * cov + bg * (1 - cov))
    noise = torch.randn(img.shape, generator=torch.Generator().manual_seed(0), dtype=torch.float64)
    out = Fx.object_noise(img, _t(cov), _t([0.05, 0.1]), noise)
    expected = img.numpy() + np.array([0.05, 0.1])[:, None, None, None] * noise.numpy() * cov
    np.testing.assert_allclose(out.numpy(), expected, atol=1e-12)
    outside = cov == 0
    assert np.array_equal(out.numpy()[np.broadcast_to(outside, out.shape)], img.numpy()[np.broadcast_to(outside, out.shape)])


def test_diffuse_material_is_lambert():
    n = RNG.normal(size=(2, 3, 6, 7))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    cov = np.ones((2, 1, 6, 7))
    cov[:, :, 0] = 0
    light = np.array([0.3, 0.5, 0.8])
    out = Fx.diffuse_material(_t(n), _t(cov), _t([[0.2], [0.9]]), light_dir=tuple(light), ambient=0.25).numpy()
    l = light / np.linalg.norm(light)
    lam = np.clip(np.einsum("bchw,c->bhw", n, l), 0, None)
    ref = np.array([0.2, 0.9])[:, None, None] * (0.25 + 0.75 * lam) * (cov[:, 0] > 0)
    np.testing.assert_allclose(out[:, 0], ref, atol=1e-12)


def test_gradcheck_every_continuous_parameter():
    cov, nrm, color, bg = _layers(b=1, h=14, w=14)
    cov = ndimage.gaussian_filter(cov, (0, 0, 1, 1))  # smooth alpha: no clamp kinks
    color_t, cov_t, bg_t = _t(color), _t(cov), _t(bg)
    s3 = lambda *v: _t([list(v)]).requires_grad_(True)  # noqa: E731

    assert torch.autograd.gradcheck(
        lambda su, sv, a: Fx.gaussian_blur_fft(bg_t, su, sv, a, pad=5), (s3(1.3), s3(0.8), s3(0.4)))
    assert torch.autograd.gradcheck(
        lambda su, sv, a: Fx.composite(*Fx.motion_blur(color_t, cov_t, su, sv, a, pad=6), bg_t),
        (s3(1.2), s3(0.7), s3(0.3)))
    img = Fx.composite(color_t, cov_t, bg_t)
    assert torch.autograd.gradcheck(lambda s: Fx.boundary_blur(img, cov_t, s, pad=5), (s3(1.1),))
    noise = torch.randn(img.shape, dtype=torch.float64, generator=torch.Generator().manual_seed(1))
    assert torch.autograd.gradcheck(lambda s: Fx.object_noise(img, cov_t, s, noise), (s3(0.05),))
    assert torch.autograd.gradcheck(lambda w: Fx.diffuse_material(_t(nrm), cov_t, w), (s3(0.5),))


def test_gradients_reach_every_capture_parameter_through_simulate():
    cov, nrm, _, bg = _layers(b=2, h=24, w=24)
    theta0 = CaptureParams.sample(2, generator=torch.Generator().manual_seed(0))
    v = theta0.to_vector().double().requires_grad_(True)
    theta = CaptureParams.from_vector(v)
    img = simulate(_t(cov), _t(nrm), _t(bg), theta, generator=torch.Generator().manual_seed(0), clamp=False)
    img.sum().backward()
    names = CaptureParams.vector_names()
    for j, name in enumerate(names[5:], start=5):
        assert v.grad[:, j].abs().sum() > 0, f"no gradient reaches {name}"


def test_functions_do_not_modify_inputs_and_batch_equals_single():
    cov, nrm, color, bg = (torch.tensor(a, dtype=torch.float32) for a in _layers(b=3))
    copies = [t.clone() for t in (cov, nrm, color, bg)]
    su, sv, an = torch.tensor([1.0, 2.0, 0.5]), torch.tensor([0.5, 1.0, 0.2]), torch.tensor([0.1, 0.2, 0.3])
    col_b, cov_b = Fx.motion_blur(color, cov, su, sv, an, pad=15)
    img = Fx.boundary_blur(Fx.composite(col_b, cov_b, bg), cov_b, su, pad=9)
    for t, c in zip((cov, nrm, color, bg), copies):
        assert torch.equal(t, c)
    for k in range(3):
        c1, v1 = Fx.motion_blur(color[k:k + 1], cov[k:k + 1], su[k:k + 1], sv[k:k + 1], an[k:k + 1], pad=15)
        i1 = Fx.boundary_blur(Fx.composite(c1, v1, bg[k:k + 1]), v1, su[k:k + 1], pad=9)
        torch.testing.assert_close(i1[0], img[k], atol=1e-6, rtol=0)


def test_empty_batch():
    e = torch.zeros(0, 1, 10, 10)
    assert Fx.gaussian_blur_fft(e, torch.zeros(0), pad=3).shape == (0, 1, 10, 10)
    c, v = Fx.motion_blur(e, e, torch.zeros(0), torch.zeros(0), torch.zeros(0), pad=3)
    assert c.shape == (0, 1, 10, 10) and v.shape == (0, 1, 10, 10)
    assert Fx.boundary_blur(e, e, torch.zeros(0), pad=3).shape == (0, 1, 10, 10)


def test_bad_inputs():
    with pytest.raises(ValueError, match=r"image must be \(B, C, H, W\)"):
        Fx.gaussian_blur_fft(torch.zeros(3, 3), 1.0, pad=1)
    with pytest.raises(ValueError, match="sigma_u: expected shape"):
        Fx.gaussian_blur_fft(torch.zeros(2, 1, 4, 4), torch.zeros(3), pad=1)
    with pytest.raises(ValueError, match="border must be"):
        Fx.gaussian_blur_fft(torch.zeros(1, 1, 4, 4), torch.zeros(1), pad=1, border="wrap")
    with pytest.raises(ValueError, match="noise must have the image's shape"):
        Fx.object_noise(torch.zeros(1, 1, 4, 4), torch.zeros(1, 1, 4, 4), torch.zeros(1), torch.zeros(1, 1, 3, 3))


def _sim(theta, effects=None, seed=0, bg=None):
    cov, nrm, _, bg0 = _layers(b=theta.batch_size, c=theta.channels)
    bg = bg0 if bg is None else bg
    return simulate(_t(cov), _t(nrm), _t(bg), theta, effects=effects, generator=torch.Generator().manual_seed(seed))


def test_switching_an_effect_off_equals_its_neutral_value():
    theta = CaptureParams.sample(2, generator=torch.Generator().manual_seed(5))
    neutral = {"boundary_blur": {"sigma_s": 0.0}, "motion_blur": {"sigma_u": 0.0, "sigma_v": 0.0},
               "object_noise": {"sigma_n": 0.0}, "material": {"w_d": 0.5}}
    for off in ("boundary_blur", "motion_blur", "object_noise", "material"):
        kept = [e for e in theta.effects if e != off]
        a = _sim(theta, effects=kept)
        b = _sim(theta.replace(**neutral[off]))
        torch.testing.assert_close(a, b, atol=1e-6, rtol=0)


def test_rgb_is_three_grayscale_channels_with_their_own_parameters():
    """The paper's RGB extension: each channel rendered with its own Θ, then combined."""
    g = torch.Generator().manual_seed(2)
    theta = CaptureParams.sample(2, generator=g, channels=3)
    cov, nrm, _, bg = _layers(b=2, c=3)
    noise = torch.randn(2, 3, 32, 32, generator=g, dtype=torch.float64)
    rgb = simulate(_t(cov), _t(nrm), _t(bg), theta, fields={"noise": noise})
    for c in range(3):
        values = {n: (v[:, c] if v.ndim == 2 else v) for n, v in theta.as_dict().items()}
        gray = CaptureParams(values, channels=1)
        one = simulate(_t(cov), _t(nrm), _t(bg[:, c:c + 1]), gray, fields={"noise": noise[:, c:c + 1]})
        torch.testing.assert_close(rgb[:, c:c + 1], one, atol=1e-9, rtol=0)


def test_simulate_replays_with_the_same_fields():
    theta = CaptureParams.sample(2, generator=torch.Generator().manual_seed(1))
    fields = sample_fields(theta.effects, (2, 1, 32, 32), torch.Generator().manual_seed(9))
    cov, nrm, _, bg = _layers()
    a = simulate(_t(cov), _t(nrm), _t(bg), theta, fields=fields)
    b = simulate(_t(cov), _t(nrm), _t(bg), theta, fields=fields)
    assert torch.equal(a, b)
    with pytest.raises(ValueError, match="pass `fields` or a `generator`"):
        simulate(_t(cov), _t(nrm), _t(bg), theta)
    with pytest.raises(ValueError, match="channels"):
        simulate(_t(cov), _t(nrm), _t(np.repeat(bg, 3, 1)), theta, fields=fields)


def test_new_effect_plugs_in_without_touching_the_others(effect_registry):
    @register_effect
    class _TestGain(Effect):
        name = "_test_gain"
        stage = "image"
        order = 50.0
        params = (ParamSpec("gain_test", "g", "x", 0.0, 4.0, 1.0, "test gain"),)

        def apply(self, state: RenderState, *, gain_test):
            return state.replace(image=state.image * gain_test[..., None, None])

    assert "_test_gain" in list_effects()
    effects = ["boundary_blur", "motion_blur", "object_noise", "material", "_test_gain"]
    theta = CaptureParams({"sigma_s": [1.0], "gain_test": [0.5]}, effects=effects)
    assert CaptureParams.vector_names(effects=effects)[-1] == "gain_test"
    with_gain = _sim(theta)
    base = _sim(CaptureParams({"sigma_s": [1.0]}))
    torch.testing.assert_close(with_gain, (base * 0.5).clamp(0, 1), atol=1e-6, rtol=0)
    with pytest.raises(ValueError, match="already registered"):
        @register_effect
        class _Other(Effect):  # noqa: F811
            name = "_test_gain"
            stage = "image"
            order = 1.0
    with pytest.raises(ValueError, match="unknown effect"):
        get_effect("nope")


def test_a_test_effect_does_not_outlive_its_test():
    from synthaug.params import EFFECT_PARAM_SPECS

    assert "_test_gain" not in list_effects()  # registered above inside the effect_registry fixture
    assert "_test_gain" not in EFFECT_PARAM_SPECS  # and its parameters left Θ's table with it
    with pytest.raises(ValueError, match="unknown effect"):
        CaptureParams({"gain_test": [0.5]}, effects=["material", "_test_gain"])
