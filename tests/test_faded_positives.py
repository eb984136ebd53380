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


def test_faded_copies_scale_the_object_difference_inside_the_box_only() -> None:
    seeds = _Seeds(np.array([[60.0, 40.0, 28.0, 14.0], [50.0, 50.0, 20.0, 30.0]]))
    out, info = faded_positives(seeds, 3, contrast=(0.3, 0.9), seed=0)
    assert out.shape == (6, 1, 40, 40) and out.dtype == torch.float32
    assert info["count"] == 6 and info["contrast"] == [0.3, 0.9] and 0.3 <= info["contrast_median"] <= 0.9
    # the draws: log-uniform in the range, from the explicit generator
    rng = np.random.default_rng(0)
    cs = np.exp(rng.uniform(np.log(0.3), np.log(0.9), 6))
    for k in range(6):
        i = k // 3
        real = seeds.patches[i].astype(np.float64) / 255
        bg = BG / 255
        m = box_mask(seeds.boxes[i], seeds.crops[i], 40)
        got = out[k, 0].double().numpy()
        # numpy reference of I' = I - (1 - c) m (I - B)
        np.testing.assert_allclose(got, real - (1 - cs[k]) * m * (real - bg), atol=1e-6)
        # deep inside the box (mask 1) the object's depth below the sky is c times the real one's
        inner = m > 0.999
        assert inner.sum() > 20
        np.testing.assert_allclose((bg - got[inner]) / (bg - real[inner]), cs[k], rtol=1e-3)  # float32 out
        # outside the feathered box nothing changed
        far = m == 0
        assert far.sum() > 500 and np.array_equal(got[far], real[far].astype(np.float32))
    again, _ = faded_positives(seeds, 3, contrast=(0.3, 0.9), seed=0)
    assert torch.equal(out, again)
    other, _ = faded_positives(seeds, 3, contrast=(0.3, 0.9), seed=1)
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


def test_a_negative_range_inverts_the_object_against_its_background() -> None:
    """``contrast=INVERTED_CONTRAST``: the dark box becomes brighter than the sky, by |c| of its depth, c log-uniform."""
    from synthaug.detectors.training_sets import INVERTED_CONTRAST

    seeds = _Seeds(np.array([[60.0, 40.0, 28.0, 14.0], [50.0, 50.0, 20.0, 30.0]]))
    sky, ink = 120, 80  # a shallow object, so that the inverted one stays inside [0, 255]
    seeds.patches = np.stack([crop_patch(_frame(b, bg=sky, fg=ink), crop=c)[0] for b, c in zip(seeds.boxes, seeds.crops)])
    seeds.backgrounds = np.full_like(seeds.patches, sky)
    assert INVERTED_CONTRAST == (-1.0, -0.5)
    out, info = faded_positives(seeds, 2, contrast=INVERTED_CONTRAST, seed=3)
    assert info["contrast"] == [-1.0, -0.5] and -1.0 <= info["contrast_median"] <= -0.5
    rng = np.random.default_rng(3)
    cs = -np.exp(rng.uniform(np.log(0.5), np.log(1.0), 4))  # |c| log-uniform in [0.5, 1], sign negative
    for k in range(4):
        i = k // 2
        real = seeds.patches[i].astype(np.float64) / 255
        bg = sky / 255
        m = box_mask(seeds.boxes[i], seeds.crops[i], 40)
        got = out[k, 0].double().numpy()
        # numpy reference of I' = I - (1 - c) m (I - B), clipped to [0, 1]
        np.testing.assert_allclose(got, np.clip(real - (1 - cs[k]) * m * (real - bg), 0, 1), atol=1e-6)
        inner = m > 0.999
        # the object now stands *above* the sky, at |c| of the depth it had below it (120 + 40 |c| <= 160: no clipping)
        assert (got[inner] > bg).all()
        np.testing.assert_allclose((got[inner] - bg) / (bg - real[inner]), -cs[k], rtol=1e-3)
        far = m == 0
        assert np.array_equal(got[far], real[far].astype(np.float32))
    # a range across zero or beyond -1 is refused
    for bad in ((-1.0, 0.5), (-1.5, -0.5), (-0.5, -1.0), (-0.5, 0.0)):
        with pytest.raises(ValueError, match="contrast"):
            faded_positives(seeds, 1, contrast=bad)
    # a positive range draws exactly as before the sign was allowed
    before, _ = faded_positives(seeds, 2, contrast=(0.3, 0.9), seed=3)
    rng = np.random.default_rng(3)
    c0 = np.exp(rng.uniform(np.log(0.3), np.log(0.9)))
    real0 = seeds.patches[0].astype(np.float64) / 255
    m0 = box_mask(seeds.boxes[0], seeds.crops[0], 40)
    np.testing.assert_allclose(before[0, 0].double().numpy(), real0 - (1 - c0) * m0 * (real0 - sky / 255), atol=1e-6)
