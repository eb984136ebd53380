"""Fast dense scoring (issue 19) == the former implementation kept as ``_score_map_reference``.

AdaBoost scores every stump over whole response maps and the CNN runs channels-last;
both must give the detections of the former code: same score maps (up to float
rounding) and, through ``detect_multiscale``, the same boxes and scores. No timings here:
speed is measured by ``benchmarks/bench_detect.py --reference``.
"""

from __future__ import annotations

import copy
import math

import pytest
import torch

from synthaug.detectors.adaboost import AdaBoostDetector, train_adaboost
from synthaug.detectors.cnn import CNNDetector, PatchCNN
from synthaug.detectors.sliding import detect_multiscale
from synthaug.detectors.toy import toy_frame, toy_patches
from synthaug.detectors.weak_learners import (
    WeakLearners,
    interior_block_integrals,
    interior_orientation_maps,
)

SCALES = (1.25, 1.0, 0.8, 0.64)


def _reference(det):
    """A copy of ``det`` whose ``score_map`` is the former implementation."""
    ref = copy.copy(det)
    ref.score_map = det._score_map_reference
    return ref


def _assert_same_detections(det, frame: torch.Tensor, **kwargs) -> None:
    new = detect_multiscale(det, frame, scales=SCALES, **kwargs)
    old = detect_multiscale(_reference(det), frame, scales=SCALES, **kwargs)
    assert new.shape == old.shape and new.shape[0] > 0
    torch.testing.assert_close(new[:, :4], old[:, :4], rtol=1e-5, atol=1e-4)  # boxes, pixels
    torch.testing.assert_close(new[:, 4], old[:, 4], rtol=1e-4, atol=1e-5)  # scores


@pytest.fixture(scope="module")
def adaboost() -> AdaBoostDetector:
    pos, neg = toy_patches(60, 120, seed=0)
    return train_adaboost(pos, neg, n_rounds=30, candidates=400, seed=0, stage_size=7)


def _frames() -> list[torch.Tensor]:
    g = torch.Generator().manual_seed(4)
    return [toy_frame(163, 201, n_objects=3, seed=5)[0], toy_frame(200, 240, n_objects=2, seed=11)[0],
            torch.rand(1, 1, 97, 131, generator=g), torch.full((1, 1, 60, 70), 0.5)]


@pytest.mark.parametrize("cascade", ["off", "calibrated", "aggressive", "rejects_all"])
def test_adaboost_score_map_equals_reference(adaboost: AdaBoostDetector, cascade: str) -> None:
    det = copy.deepcopy(adaboost)
    if cascade == "off":
        det.cascade = False
    elif cascade == "aggressive":  # most windows dropped early: the survivors-only phase runs
        det.calibrate_cascade(toy_patches(60, 0, seed=0)[0], quantile=0.6, margin=0.0)
    elif cascade == "rejects_all":
        det.rejection = torch.full_like(det.rejection, 1e9)
        det.rejection[-1] = -math.inf
    for frame in _frames():
        torch.testing.assert_close(det.score_map(frame), det._score_map_reference(frame), rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("stride", [3, 4, 8])
def test_adaboost_grids_and_strides_equal_reference(stride: int) -> None:
    # stride 3: off-grid rectangles (g = 1); 4: 4-px blocks, one block per step; 8: two blocks per step
    g = torch.Generator().manual_seed(3)
    if stride == 3:
        wl = WeakLearners.random(25, generator=g, reference=toy_patches(20, 20, seed=1)[0])
        wl.weights = torch.rand(25, generator=g) + 0.1
        det = AdaBoostDetector(wl, stride=stride, cascade=False)
        assert det._grid() == 1
    else:
        pos, neg = toy_patches(40, 80, seed=1)
        det = train_adaboost(pos, neg, n_rounds=20, candidates=300, seed=1, stride=stride)
        assert det._grid() == 4
    for frame in _frames():
        torch.testing.assert_close(det.score_map(frame), det._score_map_reference(frame), rtol=1e-6, atol=1e-6)


def test_adaboost_detections_equal_reference(adaboost: AdaBoostDetector) -> None:
    frame, _ = toy_frame(200, 260, n_objects=3, seed=7)
    _assert_same_detections(adaboost, frame, max_detections=10)
    _assert_same_detections(adaboost, frame, max_detections=100, score_threshold=0.0)


@pytest.mark.parametrize("block", [1, 2, 4])
def test_block_integrals_equal_summed_orientation_maps(block: int) -> None:
    # the former score_map's integral images: one-hot maps, float64, block sums, cumulative sums
    x = torch.rand(1, 1, 45, 58, generator=torch.Generator().manual_seed(0))
    x[..., 10:20, 10:30] = 0.25  # flat areas: zero gradients, bin 0
    maps = interior_orientation_maps(x, 4)[0]
    nbh, nbw = maps.shape[1] // block, maps.shape[2] // block
    maps = maps[:, : nbh * block, : nbw * block].double().reshape(4, nbh, block, nbw, block).sum((2, 4))
    ii = torch.nn.functional.pad(maps.cumsum(-1).cumsum(-2), (1, 0, 1, 0))
    expected = torch.cat([ii, ii.sum(0, keepdim=True)])
    assert torch.equal(interior_block_integrals(x, 4, block), expected)


def test_orientation_bins_match_the_remainder_formula() -> None:
    # bins come from selects instead of float remainders: the same bins, also at angles ±0, ±π, ±π/4
    g = torch.Generator().manual_seed(0)
    ramp = torch.linspace(1, 0, 64).expand(64, 64)  # gx < 0, gy = 0: atan2 = π
    diagonal = (torch.arange(64)[:, None] + torch.arange(64)[None, :]).float() / 128  # 45°, 135° edges
    images = [torch.rand(64, 64, generator=g), torch.rand(64, 64, generator=g) ** 8, ramp, ramp.T, -ramp,
              diagonal, diagonal.flip(1), torch.full((64, 64), 0.5), (torch.rand(64, 64, generator=g) > 0.5).float()]
    x = torch.cat(images, dim=1)[None, None]
    from synthaug.detectors.weak_learners import _magnitude_and_bin

    gx = (x[..., 1:-1, 2:] - x[..., 1:-1, :-2]) * 0.5
    gy = (x[..., 2:, 1:-1] - x[..., :-2, 1:-1]) * 0.5
    theta = torch.atan2(gy, gx).remainder(math.pi)
    assert (torch.atan2(gy, gx) == torch.tensor(math.pi)).any() and (torch.atan2(gy, gx) < 0).any()
    for n_bins in (2, 3, 4, 6, 9):
        _, bins = _magnitude_and_bin(x, n_bins)
        expected = torch.round(theta * (n_bins / math.pi)).remainder(n_bins)
        assert torch.equal(bins, expected)


def _cnn(seed: int = 1) -> CNNDetector:
    return CNNDetector(PatchCNN(generator=torch.Generator().manual_seed(seed)))


@pytest.mark.parametrize("size", [(40, 40), (47, 55), (121, 163), (200, 240)])
def test_cnn_score_map_equals_reference(size: tuple[int, int]) -> None:
    det = _cnn()
    img = torch.rand(1, 1, *size, generator=torch.Generator().manual_seed(2))
    fast, ref = det.score_map(img), det._score_map_reference(img)
    assert fast.shape == ref.shape
    torch.testing.assert_close(fast, ref, rtol=1e-4, atol=1e-5)


def test_cnn_detections_equal_reference() -> None:
    frame, _ = toy_frame(200, 260, n_objects=3, seed=7)
    _assert_same_detections(_cnn(), frame, max_detections=10)


def test_cnn_fast_path_follows_weight_updates_and_keeps_gradients() -> None:
    det = _cnn()
    img = torch.rand(1, 1, 64, 80, generator=torch.Generator().manual_seed(0))
    before = det.score_map(img)
    with torch.no_grad():
        det.net.fc.weight.mul_(2.0)
    torch.testing.assert_close(det.score_map(img), det._score_map_reference(img), rtol=1e-4, atol=1e-5)
    assert not torch.allclose(det.score_map(img), before)
    net = det.net
    w = net.conv2.weight
    net.score_map(img).sum().backward()
    assert w.grad is not None and torch.isfinite(w.grad).all() and w.grad.abs().sum() > 0


@pytest.mark.parametrize("binning", ["soft", "hard"])
def test_hog_dense_block_map_without_autograd_equals_block_features(binning: str) -> None:
    # the detector's path (in-place normalisation, per-cell sums of squares) vs the autograd path
    from synthaug.detectors.hog import HOGConfig, block_features, cell_histograms, dense_block_map

    config = HOGConfig(binning=binning)
    g = torch.Generator().manual_seed(0)
    for image in (torch.rand(1, 1, 83, 117, generator=g), toy_frame(120, 160, 2, seed=3)[0], torch.full((1, 1, 48, 48), 0.3)):
        with torch.no_grad():
            fast = dense_block_map(image, config, stride=4)
        reference = block_features(cell_histograms(image, config, stride=4), config, dilation=2)
        torch.testing.assert_close(fast, reference, rtol=1e-5, atol=1e-6)
        x = image.clone().requires_grad_(True)  # with autograd: block_features itself, differentiable
        dense_block_map(x, config, stride=4).sum().backward()
        assert x.grad is not None and torch.isfinite(x.grad).all()
