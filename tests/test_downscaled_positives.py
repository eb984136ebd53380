"""`downscaled_positives`: real seeds shown as smaller, farther objects, cut the way the detector's pyramid sees them."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
import pytest
import torch

from synthaug.data.seedset import crop_patch
from synthaug.detectors.training_sets import downscaled_positives

BG, FG = 200, 40


@dataclass
class _Seeds:
    """The few fields of a SeedSet that downscaled_positives reads: one flat frame per seed with a dark box."""

    boxes: np.ndarray
    object_fraction: float = 0.7
    size: tuple[int, int] = (160, 128)

    def __post_init__(self) -> None:
        self.patches = np.zeros((len(self.boxes), 40, 40), np.uint8)

    def __len__(self) -> int:
        return len(self.boxes)

    def frame(self, i: int) -> np.ndarray:
        f = np.full(self.size[::-1], BG, np.uint8)
        x, y, w, h = (int(v) for v in self.boxes[i])
        f[y:y + h, x:x + w] = FG
        return f


def _ink(patch: torch.Tensor) -> float:
    """The dark object's area in patch pixels: the intensity it removes from the background, over its contrast."""
    return float(((BG / 255.0 - patch) / ((BG - FG) / 255.0)).sum())


def test_object_area_and_window_follow_the_drawn_side_and_the_largest_magnification() -> None:
    # a 40 x 40 square shrunk to a 16 px side: with windows down to x1.25 the crop is 40 / 1.25 = 32 px, so the object
    # spans 16 x 1.25 = 20 patch px (area 400); scale-normalised (no limit) it spans 0.7 x 40 = 28 px (area 784)
    seeds = _Seeds(np.array([[60.0, 40.0, 40.0, 40.0]]))
    limited, info = downscaled_positives(seeds, 3, sides=(16.0, 16.0), max_scale=1.25, seed=0)
    assert limited.shape == (3, 1, 40, 40) and limited.dtype == torch.float32
    assert info["count"] == 3 and info["seeds_used"] == 1 and info["side_median"] == 16.0
    for p in limited:
        assert _ink(p[0]) == pytest.approx(20.0 ** 2, rel=0.03)
    normalised, _ = downscaled_positives(seeds, 1, sides=(16.0, 16.0), max_scale=None, seed=0)
    assert _ink(normalised[0, 0]) == pytest.approx(28.0 ** 2, rel=0.03)
    # a side the pyramid reaches (24 px x 1.25 > 28) keeps the seeds' scale normalisation
    big, _ = downscaled_positives(seeds, 1, sides=(24.0, 24.0), max_scale=1.25, seed=0)
    assert _ink(big[0, 0]) == pytest.approx(28.0 ** 2, rel=0.03)


def test_shrinking_averages_pixel_areas_like_opencv() -> None:
    # independent reference: the frame shrunk by cv2.resize(INTER_AREA) to the drawn size, cut by crop_patch around the
    # shrunk box; the only other draw is the sub-pixel offset, bounded by half a pixel of the small frame
    seeds = _Seeds(np.array([[50.0, 30.0, 48.0, 32.0]]))
    got, _ = downscaled_positives(seeds, 1, sides=(20.0, 20.0), max_scale=1.25, seed=3)
    f = 20.0 / 48.0
    small = cv2.resize(seeds.frame(0), (round(160 * f), round(128 * f)), interpolation=cv2.INTER_AREA)
    fx, fy = small.shape[1] / 160, small.shape[0] / 128
    ref, _ = crop_patch(small, crop=((50 + 24) * fx, (30 + 16) * fy, 32.0), patch_size=40)
    diff = (got[0, 0] - torch.from_numpy(ref).float() / 255.0).abs()
    assert diff.mean() < 0.03  # a half-pixel shift of the small frame moves edges by <= 0.625 patch px
    assert _ink(got[0, 0]) == pytest.approx(_ink(torch.from_numpy(ref).float() / 255.0), rel=0.03)


def test_sides_are_drawn_in_range_and_small_seeds_are_skipped() -> None:
    boxes = np.array([[10.0, 10.0, 12.0, 8.0], [20.0, 20.0, 30.0, 18.0], [40.0, 30.0, 60.0, 50.0]])
    seeds = _Seeds(boxes)
    out, info = downscaled_positives(seeds, 4, sides=(16.0, 24.0), max_scale=1.25, seed=1)
    assert info["seeds_used"] == 2 and info["count"] == 8 and out.shape[0] == 8  # the 12 px seed is under 16 px
    assert 16.0 <= info["side_median"] <= 24.0
    # each copy's longest side s in [16, 24] px becomes s x 40 / max(s / 0.7, 32): 20 to 28 patch px; the other side
    # keeps the box's aspect (0.6 and 0.83), so sqrt(area) lies in [20 sqrt(0.6), 28 sqrt(0.83)]
    for p in out:
        assert 0.95 * 20 * np.sqrt(0.6) <= np.sqrt(_ink(p[0])) <= 1.05 * 28 * np.sqrt(50 / 60)


def test_reproducible_from_the_seed_and_errors() -> None:
    seeds = _Seeds(np.array([[60.0, 40.0, 40.0, 30.0], [20.0, 20.0, 36.0, 36.0]]))
    a, _ = downscaled_positives(seeds, 2, seed=7)
    b, _ = downscaled_positives(seeds, 2, seed=7)
    c, _ = downscaled_positives(seeds, 2, seed=8)
    assert torch.equal(a, b) and not torch.equal(a, c)
    empty, info = downscaled_positives(seeds, 0)
    assert empty.shape == (0, 1, 40, 40) and info["count"] == 0
    with pytest.raises(ValueError, match="copies must be >= 0"):
        downscaled_positives(seeds, -1)
    with pytest.raises(ValueError, match="0 < low <= high"):
        downscaled_positives(seeds, 1, sides=(24.0, 16.0))
    with pytest.raises(ValueError, match="max_scale must be positive"):
        downscaled_positives(seeds, 1, max_scale=0.0)
