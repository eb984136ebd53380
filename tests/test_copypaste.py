"""Copy-paste positives (issue 16's user baseline): cut with the fitted silhouette, pasted on other backgrounds."""

import types

import numpy as np
import pytest
import torch

from synthaug.data.copypaste import copy_paste_positives, fitted_silhouettes, paste_objects
from synthaug.params import CaptureParams


def _toy(n=3, p=24, seed=0):
    rng = np.random.default_rng(seed)
    patches = rng.integers(150, 250, (n, p, p)).astype(np.uint8)
    masks = np.zeros((n, p, p), np.float32)
    for i in range(n):
        masks[i, 8:16, 6 + i:14 + i] = 1  # off-centre, so a flip moves it
        patches[i][masks[i] > 0] = 20 + 10 * i
    backgrounds = rng.integers(100, 200, (n, p, p)).astype(np.uint8)
    return patches, backgrounds, masks


PLAIN = dict(scale=(1.0, 1.0), brightness=(1.0, 1.0), blur=(0.0, 0.0), flip=0.0, dilate=0, feather=0.0)


def _backgrounds_used(out, backgrounds, masks, n):
    """Which seed's background each output shows outside its object (by exact match of those pixels)."""
    used = []
    for k in range(out.shape[0]):
        keep = masks[k % n] == 0
        hits = [j for j in range(n) if np.allclose(out[k, 0].numpy()[keep], backgrounds[j][keep] / 255.0, atol=1e-6)]
        used.append(hits)
    return used


def test_plain_paste_is_the_object_on_another_seeds_background():
    patches, backgrounds, masks = _toy()
    out = paste_objects(patches, backgrounds, masks, 9, seed=0, **PLAIN)
    for k in range(9):
        i = k % 3
        obj = masks[i] > 0
        np.testing.assert_allclose(out[k, 0].numpy()[obj], patches[i][obj] / 255.0, atol=1e-6)
    used = _backgrounds_used(out, backgrounds, masks, 3)
    assert all(len(u) == 1 and u[0] != k % 3 for k, u in enumerate(used))  # never the object's own background
    assert len({u[0] for u in used}) > 1


def test_flip_brightness_scale_and_blur_against_references():
    patches, backgrounds, masks = _toy(n=2)
    flipped = paste_objects(patches, backgrounds, masks, 2, seed=1, **{**PLAIN, "flip": 1.0})
    for k in range(2):
        m = np.fliplr(masks[k]) > 0
        np.testing.assert_allclose(flipped[k, 0].numpy()[m], np.fliplr(patches[k])[m] / 255.0, atol=1e-6)
    dark = paste_objects(patches, backgrounds, masks, 2, seed=1, **{**PLAIN, "brightness": (0.5, 0.5)})
    for k in range(2):
        m = masks[k] > 0
        np.testing.assert_allclose(dark[k, 0].numpy()[m], 0.5 * patches[k][m] / 255.0, atol=1e-6)
    # twice the size about the centre: the object's area (pixels far below the backgrounds) about x4
    big = paste_objects(patches, backgrounds, masks, 2, seed=1, **{**PLAIN, "scale": (2.0, 2.0)})
    for k in range(2):
        assert (big[k, 0] < 0.3).sum().item() == pytest.approx(4 * masks[k].sum(), rel=0.15)
    # blur spreads the object: fewer pixels at the object's own dark level, a soft edge
    soft = paste_objects(patches, backgrounds, masks, 2, seed=1, **{**PLAIN, "blur": (1.5, 1.5)})
    for k in range(2):
        assert (soft[k, 0] < 0.15).sum() < (masks[k] > 0).sum()
        assert ((soft[k, 0] > 0.2) & (soft[k, 0] < 0.35)).sum() > 0


def test_reproducible_and_seeded():
    patches, backgrounds, masks = _toy()
    a = paste_objects(patches, backgrounds, masks, 12, seed=5)
    b = paste_objects(patches, backgrounds, masks, 12, seed=5)
    c = paste_objects(patches, backgrounds, masks, 12, seed=6)
    assert torch.equal(a, b) and not torch.equal(a, c)
    assert a.shape == (12, 1, 24, 24) and 0.0 <= a.min() and a.max() <= 1.0
    assert paste_objects(patches, backgrounds, masks, 0, seed=0).shape == (0, 1, 24, 24)


@pytest.mark.parametrize("kwargs, match", [
    ({"scale": (1.2, 0.8)}, "scale"), ({"brightness": (-1.0, 1.0)}, "brightness"), ({"blur": (0.0, -1.0)}, "blur"),
    ({"flip": 1.5}, "flip"),
])
def test_bad_ranges_are_refused(kwargs, match):
    patches, backgrounds, masks = _toy()
    with pytest.raises(ValueError, match=match):
        paste_objects(patches, backgrounds, masks, 4, seed=0, **kwargs)
    with pytest.raises(ValueError, match="shape"):
        paste_objects(patches, backgrounds[:2], masks, 4, seed=0)
    with pytest.raises(ValueError, match="count"):
        paste_objects(patches, backgrounds, masks, -1, seed=0)


def test_fitted_silhouettes_are_the_mesh_coverage_at_the_fitted_parameters(tmp_path):
    from synthaug.render.cache import ViewCache

    cache = ViewCache.build("quadcopter", step_deg=15, sprite_size=32)
    theta = CaptureParams.sample(2, generator=torch.Generator().manual_seed(0))
    path = tmp_path / "fit.json"
    theta.save(path, extra=[{"object_scale": 0.5}, {"object_scale": 0.8}],
               metadata={"config": {"step_deg": 15, "sprite_size": 32}})
    seeds = _Seeds(types.SimpleNamespace(patches=np.zeros((2, 32, 32), np.uint8),
                                         backgrounds=np.zeros((2, 32, 32), np.uint8), object_fraction=0.7))
    masks = fitted_silhouettes(seeds, path, cache=cache)
    f = lambda t: t.float().reshape(-1)  # noqa: E731
    ref, _ = cache.layers(f(theta.alpha), f(theta.beta), f(theta.gamma), f(theta.t_x), f(theta.t_y), size=32,
                          object_scale=torch.tensor([0.5, 0.8]))
    np.testing.assert_array_equal(masks, ref[:, 0].numpy())
    assert masks[1].sum() > masks[0].sum() > 0  # the larger fitted scale covers more
    out = copy_paste_positives(seeds, path, 5, seed=0, mesh="quadcopter")
    assert out.shape == (5, 1, 32, 32)
    with pytest.raises(ValueError, match="rows"):
        fitted_silhouettes(_Seeds(types.SimpleNamespace(patches=np.zeros((3, 32, 32), np.uint8),
                                                        backgrounds=np.zeros((3, 32, 32), np.uint8),
                                                        object_fraction=0.7)), path, cache=cache)


class _Seeds:
    """The few seed-set fields the copy-paste reads."""

    def __init__(self, ns):
        self.patches, self.backgrounds, self.object_fraction = ns.patches, ns.backgrounds, ns.object_fraction

    def __len__(self):
        return len(self.patches)
