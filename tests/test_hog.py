"""HOG in torch against skimage.feature.hog and direct numpy computations."""

from __future__ import annotations

import numpy as np
import pytest
import torch
import torch.nn.functional as F

from synthaug.detectors.hog import (
    DEFAULT_HOG,
    SKIMAGE_HOG,
    HOGConfig,
    block_features,
    cell_histograms,
    dense_block_map,
    descriptor_to_filter,
    hog,
    image_gradients,
    orientation_votes,
)

skimage_feature = pytest.importorskip("skimage.feature")


def _fixed_images() -> list[np.ndarray]:
    rng = np.random.default_rng(1234)
    yy, xx = np.mgrid[0:40, 0:40]
    disk = ((yy - 20) ** 2 + (xx - 17) ** 2 < 90).astype(np.float64) * 0.8 + 0.1
    ramp = (xx + 2 * yy) / 120.0
    bars = ((xx // 5) % 2).astype(np.float64)
    return [
        rng.random((40, 40)),  # noise: every orientation
        rng.integers(0, 256, (40, 40)) / 255.0,  # 8-bit quantised values: exact 0/90/180° angles occur
        disk,  # a blob: the detector's case
        ramp,  # constant gradient
        bars,  # vertical edges only
        np.zeros((40, 40)),  # no gradient at all
        rng.random((43, 37)),  # not a multiple of the cell: partial cells dropped
        rng.random((64, 48)),
    ]


@pytest.mark.parametrize("index", range(8))
def test_hog_matches_skimage_in_reference_mode(index: int) -> None:
    image = _fixed_images()[index]
    ref = skimage_feature.hog(image, orientations=9, pixels_per_cell=(8, 8), cells_per_block=(2, 2), block_norm="L2-Hys")
    ours = hog(torch.from_numpy(image)[None, None], SKIMAGE_HOG)[0].numpy()
    assert ours.shape == ref.shape
    # skimage accumulates cell sums in float32
    np.testing.assert_allclose(ours, ref, atol=1e-6)


@pytest.mark.parametrize("config", [HOGConfig(binning="hard", orientations=6, cell_size=6, block_size=3), HOGConfig(binning="hard", block_norm="L2")])
def test_hog_matches_skimage_other_settings(config: HOGConfig) -> None:
    image = np.random.default_rng(5).random((48, 42))
    ref = skimage_feature.hog(
        image,
        orientations=config.orientations,
        pixels_per_cell=(config.cell_size,) * 2,
        cells_per_block=(config.block_size,) * 2,
        block_norm=config.block_norm,
    )
    ours = hog(torch.from_numpy(image)[None, None], config)[0].numpy()
    np.testing.assert_allclose(ours, ref, atol=1e-6)


def test_hog_float32_close_to_float64() -> None:
    image = torch.rand(3, 1, 40, 40, generator=torch.Generator().manual_seed(0), dtype=torch.float64)
    for config in (SKIMAGE_HOG, DEFAULT_HOG):
        h64 = hog(image, config)
        h32 = hog(image.float(), config)
        assert h32.dtype == torch.float32
        # hard bins can flip on float32 rounding for a handful of pixels; most values agree
        assert (h32.double() - h64).abs().median() < 1e-6


def test_gradients_match_numpy() -> None:
    image = np.random.default_rng(2).random((9, 11))
    g_row, g_col = image_gradients(torch.from_numpy(image)[None, None])
    ref_row = np.zeros_like(image)
    ref_row[1:-1] = image[2:] - image[:-2]
    ref_col = np.zeros_like(image)
    ref_col[:, 1:-1] = image[:, 2:] - image[:, :-2]
    np.testing.assert_allclose(g_row[0, 0].numpy(), ref_row)
    np.testing.assert_allclose(g_col[0, 0].numpy(), ref_col)


def _soft_votes_numpy(image: np.ndarray, n: int = 9) -> np.ndarray:
    """Linear interpolation between the two nearest bin centres, pixel by pixel."""
    g_row = np.zeros_like(image)
    g_row[1:-1] = image[2:] - image[:-2]
    g_col = np.zeros_like(image)
    g_col[:, 1:-1] = image[:, 2:] - image[:, :-2]
    out = np.zeros((n,) + image.shape)
    width = 180.0 / n
    for y in range(image.shape[0]):
        for x in range(image.shape[1]):
            mag = np.hypot(g_row[y, x], g_col[y, x])
            if mag == 0:
                continue
            angle = np.degrees(np.arctan2(g_row[y, x], g_col[y, x])) % 180.0
            centre_pos = angle / width - 0.5
            lo = int(np.floor(centre_pos))
            frac = centre_pos - lo
            out[lo % n, y, x] += mag * (1 - frac)
            out[(lo + 1) % n, y, x] += mag * frac
    return out


def test_soft_votes_match_numpy_interpolation() -> None:
    image = np.random.default_rng(3).random((12, 14))
    ours = orientation_votes(torch.from_numpy(image)[None, None], DEFAULT_HOG)[0].numpy()
    np.testing.assert_allclose(ours, _soft_votes_numpy(image), atol=1e-12)


@pytest.mark.parametrize("config", [SKIMAGE_HOG, DEFAULT_HOG])
def test_votes_sum_to_gradient_magnitude(config: HOGConfig) -> None:
    image = np.random.default_rng(4).random((20, 20))
    votes = orientation_votes(torch.from_numpy(image)[None, None], config)[0].numpy()
    g_row = np.zeros_like(image)
    g_row[1:-1] = image[2:] - image[:-2]
    g_col = np.zeros_like(image)
    g_col[:, 1:-1] = image[:, 2:] - image[:, :-2]
    np.testing.assert_allclose(votes.sum(0), np.hypot(g_row, g_col), atol=1e-12)


@pytest.mark.parametrize("config", [SKIMAGE_HOG, DEFAULT_HOG])
@pytest.mark.parametrize("stride", [1, 2, 3, 4, 8])
def test_cell_histograms_equal_pooled_votes(config: HOGConfig, stride: int) -> None:
    image = torch.rand(2, 1, 37, 45, generator=torch.Generator().manual_seed(stride), dtype=torch.float64)
    ref = F.avg_pool2d(orientation_votes(image, config), kernel_size=8, stride=stride)
    ours = cell_histograms(image, config, stride=stride)
    assert ours.shape == ref.shape
    torch.testing.assert_close(ours, ref)


@pytest.mark.parametrize("stride", [2, 4, 8])
def test_dense_block_map_equals_per_window_blocks(stride: int) -> None:
    """A window's blocks in the dense map = blocks of the window computed with 1 px of context."""
    gen = torch.Generator().manual_seed(7)
    image = torch.rand(1, 1, 70, 90, generator=gen, dtype=torch.float64)
    dense = dense_block_map(image, DEFAULT_HOG, stride)
    d = 8 // stride
    for y_px, x_px in [(8, 16), (24, 48), (16, 40)]:
        crop = image[..., y_px - 1 : y_px + 41, x_px - 1 : x_px + 41]  # 1-px margin: true gradients at the border
        votes = orientation_votes(crop, DEFAULT_HOG)[..., 1:41, 1:41]
        blocks = block_features(F.avg_pool2d(votes, 8, 8), DEFAULT_HOG)  # (1, 36, 4, 4)
        y, x = y_px // stride, x_px // stride
        from_dense = dense[..., y : y + 4 * d : d, x : x + 4 * d : d]
        torch.testing.assert_close(from_dense, blocks)


def test_descriptor_to_filter_dot_equals_convolution() -> None:
    gen = torch.Generator().manual_seed(8)
    patches = torch.rand(5, 1, 40, 40, generator=gen)
    weights = torch.randn(3, 576, generator=gen)
    dots = hog(patches, DEFAULT_HOG) @ weights.T
    blocks = block_features(cell_histograms(patches, DEFAULT_HOG), DEFAULT_HOG)
    conv = F.conv2d(blocks, descriptor_to_filter(weights, DEFAULT_HOG, 40))[:, :, 0, 0]
    torch.testing.assert_close(conv, dots, rtol=1e-5, atol=1e-5)


def test_batched_equals_unbatched_and_input_unchanged() -> None:
    images = torch.rand(4, 1, 40, 40, generator=torch.Generator().manual_seed(9))
    before = images.clone()
    batched = hog(images)
    single = torch.cat([hog(images[i : i + 1]) for i in range(4)])
    torch.testing.assert_close(batched, single)
    assert torch.equal(images, before)
    assert hog(images[:0]).shape == (0, 576)


def test_multichannel_is_per_channel() -> None:
    images = torch.rand(2, 3, 40, 40, generator=torch.Generator().manual_seed(10))
    out = hog(images)
    assert out.shape == (2, 3 * 576)
    torch.testing.assert_close(out[:, 576:1152], hog(images[:, 1:2]))


def test_soft_hog_gradcheck() -> None:
    # away from zero-gradient pixels and block clipping kinks the descriptor is smooth
    gen = torch.Generator().manual_seed(11)
    image = torch.rand(1, 1, 16, 16, generator=gen, dtype=torch.float64).requires_grad_(True)
    config = HOGConfig(block_norm="L2")
    assert torch.autograd.gradcheck(lambda x: hog(x, config), (image,), eps=1e-6, atol=1e-4)


def test_hog_gradient_finite_on_flat_image() -> None:
    image = torch.full((1, 1, 40, 40), 0.5, requires_grad=True)
    hog(image).sum().backward()
    assert torch.isfinite(image.grad).all()


def test_bad_inputs() -> None:
    with pytest.raises(ValueError, match="smaller than one block"):
        hog(torch.rand(1, 1, 12, 40))
    with pytest.raises(ValueError, match=r"\(B, C, H, W\)"):
        hog(torch.rand(40, 40))
    with pytest.raises(ValueError, match="float"):
        hog(torch.zeros(1, 1, 40, 40, dtype=torch.uint8))
    with pytest.raises(ValueError, match="binning"):
        HOGConfig(binning="bilinear")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="orientations"):
        HOGConfig(orientations=0)
    with pytest.raises(ValueError, match="stride must divide"):
        dense_block_map(torch.rand(1, 1, 40, 40), DEFAULT_HOG, 3)
    with pytest.raises(ValueError, match=r"weights must be \(K, 576\)"):
        descriptor_to_filter(torch.zeros(2, 100), DEFAULT_HOG, 40)
