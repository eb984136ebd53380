"""The measured noise level (robust Immerkær) and ``FitConfig(object_noise="measured")``."""

import numpy as np
import pytest
import torch
from scipy.signal import convolve2d

from synthaug.fit.fitting import FitConfig, _cfg_json, build_distance, fit_one, patches_tensor
from synthaug.fit.noise_level import noise_sigma
from synthaug.params import CaptureParams


def _smooth(n: int = 96) -> torch.Tensor:
    y, x = torch.meshgrid(torch.linspace(0, 1, n, dtype=torch.float64), torch.linspace(0, 1, n, dtype=torch.float64),
                          indexing="ij")
    return 0.4 + 0.3 * torch.sin(3 * x) * torch.cos(2 * y)


def _immerkaer_mean(img: np.ndarray) -> float:
    """Immerkær's own estimator (CVIU 1996, eq. 3), with scipy: sqrt(π/2) / (6 (W-2)(H-2)) Σ |I * N|."""
    k = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], float)
    h, w = img.shape
    return float(np.sqrt(np.pi / 2) / (6 * (w - 2) * (h - 2)) * np.abs(convolve2d(img, k, mode="valid")).sum())


@pytest.mark.parametrize("sigma", [0.005, 0.02, 0.05])
def test_recovers_the_noise_of_a_smooth_image_and_agrees_with_immerkaer(sigma):
    g = torch.Generator().manual_seed(int(sigma * 1e4))
    img = _smooth() + sigma * torch.randn(96, 96, generator=g, dtype=torch.float64)
    est = float(noise_sigma(img[None, None])[0])
    assert est == pytest.approx(sigma, rel=0.08)
    assert est == pytest.approx(_immerkaer_mean(img.numpy()), rel=0.08)


def test_an_object_edge_is_not_counted_as_noise():
    """Thin dark diagonal arms (a drone seen from below) on the smooth image: Immerkær's mean counts
    their edges as noise (5x the truth), the median barely (straight axis-aligned edges cancel in N)."""
    g = torch.Generator().manual_seed(3)
    img = _smooth(64)
    yy, xx = torch.meshgrid(torch.arange(64.0), torch.arange(64.0), indexing="ij")
    img[((yy - xx).abs() < 3) | ((yy + xx - 63).abs() < 3)] = 0.05
    img = img + 0.01 * torch.randn(64, 64, generator=g, dtype=torch.float64)
    est = float(noise_sigma(img[None, None])[0])
    assert 0.009 < est < 0.015
    assert _immerkaer_mean(img.numpy()) > 3 * 0.01  # the reason for the median


def test_shapes_channels_and_errors():
    assert noise_sigma(torch.full((2, 1, 8, 8), 0.5)).tolist() == [0.0, 0.0]  # a flat image has no noise
    g = torch.Generator().manual_seed(0)
    x = torch.stack([_smooth(48) + s * torch.randn(48, 48, generator=g, dtype=torch.float64) for s in (0.01, 0.04)])
    one = noise_sigma(x[:, None])
    three = noise_sigma(x[:, None].expand(2, 3, 48, 48))  # channels pooled: the same level
    assert one.shape == (2,) and one[1] > 3 * one[0]
    torch.testing.assert_close(one, three)
    assert noise_sigma(torch.zeros(0, 1, 8, 8)).shape == (0,)
    with pytest.raises(ValueError, match="B, C, H, W"):
        noise_sigma(torch.zeros(8, 8))
    with pytest.raises(ValueError, match="3 x 3"):
        noise_sigma(torch.zeros(1, 1, 2, 8))


def test_fit_pins_sigma_n_at_the_measured_level():
    from synthaug.data.procedural import sky_backgrounds
    from synthaug.render.cache import ViewCache

    cache = ViewCache.build("quadcopter", step_deg=15, sprite_size=32)
    bg = patches_tensor(sky_backgrounds(1, (40, 40), seed=2))
    g = torch.Generator().manual_seed(5)
    x = (bg + 0.03 * torch.randn(bg.shape, generator=g)).clamp(0, 1)
    level = float(noise_sigma(x)[0])
    d = build_distance("hog")
    res = fit_one(x, bg, cache, d, FitConfig(budget=60, object_noise="measured"), seed=1, object_scale=0.7)
    sn = float(CaptureParams.from_vector(torch.tensor([res["theta"]]), validate=False).sigma_n)
    assert sn == pytest.approx(level, abs=1e-6) and 0.02 < level < 0.04
    # clipped to the σ_n bounds
    low = fit_one(x, bg, cache, d, FitConfig(budget=60, object_noise="measured", bounds={"sigma_n": (0.0, 0.01)}),
                  seed=1, object_scale=0.7)
    assert float(CaptureParams.from_vector(torch.tensor([low["theta"]]), validate=False).sigma_n) == pytest.approx(0.01)
    # the paper's setting searches it (one coordinate more)
    fitted = fit_one(x, bg, cache, d, FitConfig(budget=60), seed=1, object_scale=0.7)
    assert float(CaptureParams.from_vector(torch.tensor([fitted["theta"]]), validate=False).sigma_n) != pytest.approx(level)
    with pytest.raises(ValueError, match="object_noise"):
        FitConfig(object_noise="speckle")
    # the setting is part of a fit's fingerprint, but absent at the paper's (earlier fits stay current)
    assert "object_noise" not in _cfg_json(FitConfig()) and _cfg_json(FitConfig(object_noise="measured"))["object_noise"] == "measured"
