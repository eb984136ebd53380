"""`faded_positives`: real seeds with the object fainter against its own background; `box_mask`: the box's footprint."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
import torch

from synthaug.data.seedset import crop_geometry, crop_patch
from synthaug.detectors.training_sets import FADED_CONTRAST, box_mask, faded_positives

BG, FG = 200, 40


def _frame(box, size=(160, 128), bg=BG, fg=FG) -> np.ndarray:
    f = np.full(size[::-1], bg, np.uint8)
    x, y, w, h = (int(v) for v in box)
    f[y:y + h, x:x + w] = fg
    return f


@dataclass
class _Seeds:
    """The fields of a SeedSet that faded_positives reads, cut by crop_patch from flat frames with a dark box."""

    boxes: np.ndarray

    def __post_init__(self) -> None:
        self.crops = np.stack([crop_geometry(b) for b in self.boxes])
        self.patches = np.stack([crop_patch(_frame(b), crop=c)[0] for b, c in zip(self.boxes, self.crops)])
        self.backgrounds = np.full_like(self.patches, BG)  # the object-free frame is the flat sky

    def __len__(self) -> int:
        return len(self.boxes)


def _reference(seeds: _Seeds, i: int, c: float, sky: float) -> tuple[np.ndarray, float, np.ndarray, np.ndarray]:
    """Seed ``i``'s patch, sky level, box mask and the numpy reference of ``I' = I - (1 - c) m (I - B)`` in [0, 1]."""
    real = seeds.patches[i].astype(np.float64) / 255
    m = box_mask(seeds.boxes[i], seeds.crops[i], 40)
    return real, sky / 255, m, np.clip(real - (1 - c) * m * (real - sky / 255), 0, 1)


def test_box_mask_is_the_box_footprint_crop_patch_cuts() -> None:
    # hand-computed: a 20 x 20 box in a 40 px crop seen at 4 px covers the central 2 x 2 pixels exactly
    assert box_mask((10, 10, 20, 20), (20, 20, 40), 4, feather=0).tolist() == \
        [[0, 0, 0, 0], [0, 1, 1, 0], [0, 1, 1, 0], [0, 0, 0, 0]]
    # a box whose edges fall mid-pixel: partial coverage (x from 0.5 to 2.5 patch px, y from 1 to 3)
    m = box_mask((5, 10, 20, 20), (20, 20, 40), 4, feather=0)
    assert m[1].tolist() == [0.5, 1.0, 0.5, 0.0] and m[0].sum() == 0 and m[:, 3].sum() == 0
    # independent reference: the ink crop_patch's bilinear resampling shows for a dark box on a flat frame
    for box in ([60, 40, 28, 14], [70, 50, 9, 23], [33, 21, 40, 40]):
        patch, crop = crop_patch(_frame(box), box=box)
        ink = (BG - patch.astype(np.float64)) / (BG - FG)
        m = box_mask(box, crop, 40, feather=0)
        assert m.sum() == pytest.approx(ink.sum(), rel=0.02)
        assert np.abs(m - ink).max() < 0.55  # edges: bilinear vs area coverage differ by at most half a pixel's
        # feathering moves ink across edges but keeps its total (the box is well inside the window)
        assert box_mask(box, crop, 40).sum() == pytest.approx(m.sum(), rel=1e-3)


@pytest.mark.parametrize("contrast, sky, ink", [((0.3, 0.9), BG, FG), ((-1.0, -0.5), 120, 80)],
                         ids=["fainter", "inverted"])
def test_faded_copies_scale_the_object_difference_inside_the_box_only(contrast, sky, ink) -> None:
    """``I' = I - (1 - c) m (I - B)``, |c| log-uniform in the range (negative: the object brighter than its sky,
    a shallow object so that nothing clips), against numpy; nothing changes outside the feathered box."""
    seeds = _Seeds(np.array([[60.0, 40.0, 28.0, 14.0], [50.0, 50.0, 20.0, 30.0]]))
    seeds.patches = np.stack([crop_patch(_frame(b, bg=sky, fg=ink), crop=c)[0] for b, c in zip(seeds.boxes, seeds.crops)])
    seeds.backgrounds = np.full_like(seeds.patches, sky)
    out, info = faded_positives(seeds, 3, contrast=contrast, seed=0)
    assert out.shape == (6, 1, 40, 40) and out.dtype == torch.float32
    lo, hi = contrast
    assert info["count"] == 6 and info["contrast"] == [lo, hi] and lo <= info["contrast_median"] <= hi
    # the draws: |c| log-uniform in the range, from the explicit generator, with the range's sign
    a, b = sorted((abs(lo), abs(hi)))
    cs = np.sign(lo) * np.exp(np.random.default_rng(0).uniform(np.log(a), np.log(b), 6))
    for k in range(6):
        real, bg, m, want = _reference(seeds, k // 3, cs[k], sky)
        got = out[k, 0].double().numpy()
        np.testing.assert_allclose(got, want, atol=1e-6)
        # deep inside the box (mask 1) the object's difference from the sky is c times the real one's
        inner = m > 0.999
        assert inner.sum() > 20
        np.testing.assert_allclose((got[inner] - bg) / (real[inner] - bg), cs[k], rtol=1e-3)  # float32 out
        if lo < 0:
            assert (got[inner] > bg).all()  # the dark object now stands above the sky
        far = m == 0
        assert far.sum() > 500 and np.array_equal(got[far], real[far].astype(np.float32))
    again, _ = faded_positives(seeds, 3, contrast=contrast, seed=0)
    assert torch.equal(out, again)
    other, _ = faded_positives(seeds, 3, contrast=contrast, seed=1)
    assert not torch.equal(out, other)


def test_defaults_bad_inputs_and_none() -> None:
    seeds = _Seeds(np.array([[60.0, 40.0, 28.0, 14.0]]))
    assert FADED_CONTRAST == (0.3, 0.9)
    out, info = faded_positives(seeds, 0)
    assert out.shape == (0, 1, 40, 40) and info["count"] == 0 and info["contrast_median"] is None
    for bad in ((0.0, 0.5), (0.6, 0.5), (0.5, 1.2)):
        with pytest.raises(ValueError, match="contrast"):
            faded_positives(seeds, 1, contrast=bad)
    with pytest.raises(ValueError, match="copies"):
        faded_positives(seeds, -1)
    # contrast 1: the copy is the real patch
    same, _ = faded_positives(seeds, 1, contrast=(1.0, 1.0))
    np.testing.assert_allclose(same[0, 0].numpy(), seeds.patches[0] / 255.0, atol=1e-6)


def test_contrast_ranges_of_one_sign_only() -> None:
    from synthaug.detectors.training_sets import INVERTED_CONTRAST

    seeds = _Seeds(np.array([[60.0, 40.0, 28.0, 14.0]]))
    assert INVERTED_CONTRAST == (-1.0, -0.5)
    for bad in ((-1.0, 0.5), (-1.5, -0.5), (-0.5, -1.0), (-0.5, 0.0)):
        with pytest.raises(ValueError, match="contrast"):
            faded_positives(seeds, 1, contrast=bad)
