"""Rendered distractors (:func:`synthaug.detectors.training_sets.distractor_negatives`): the shapes, their split and
seeds, what a render of one looks like against an independent measure of its silhouette, and the soft style
(:func:`~synthaug.detectors.training_sets.soften`) against scipy's Gaussian filter."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

import synthaug.detectors.training_sets as training_sets
from synthaug.detectors.training_sets import (DISTRACTOR_AXES, SOFT_DISTRACTOR_BLUR_PX, SOFT_DISTRACTOR_CONTRAST,
                                              distractor_meshes, distractor_negatives, soften)


def test_distractor_meshes_are_the_listed_ellipsoids() -> None:
    meshes = distractor_meshes()
    assert len(meshes) == len(DISTRACTOR_AXES) == 8
    for m, axes in zip(meshes, DISTRACTOR_AXES):
        np.testing.assert_allclose(m.extents, 2 * np.asarray(axes), rtol=1e-6)  # a unit sphere stretched
        assert m.is_watertight and m.is_convex


def test_distractors_split_evenly_over_the_shapes_each_at_its_own_seed(monkeypatch: pytest.MonkeyPatch) -> None:
    calls: list[tuple[tuple[float, ...], int, int, dict[str, Any]]] = []

    def fake(seedset: Any, mesh: Any, fit: Any, count: int, *, seed: int = 0, **kw: Any) -> torch.Tensor:
        calls.append((tuple(np.round(mesh.extents / 2, 6)), count, seed, kw))
        return torch.full((count, 1, 8, 8), float(len(calls)))

    monkeypatch.setattr(training_sets, "synthetic_positives", fake)
    out = distractor_negatives(None, "fit.json", 19, seed=100, quantize=True, pose_sampling="fitted_at_seed")
    assert [c[1] for c in calls] == [3, 3, 3, 2, 2, 2, 2, 2]  # 19 = 8 x 2 + 3: the first three take one more
    assert [c[2] for c in calls] == list(range(100, 108))
    assert [c[0] for c in calls] == [tuple(a) for a in DISTRACTOR_AXES]
    assert all(c[3] == {"quantize": True, "pose_sampling": "fitted_at_seed"} for c in calls)
    assert out.shape == (19, 1, 8, 8)
    assert out[:, 0, 0, 0].tolist() == [float(k + 1) for k, c in enumerate([3, 3, 3, 2, 2, 2, 2, 2]) for _ in range(c)]
    calls.clear()
    assert distractor_negatives(None, "fit.json", 0).shape == (0, 1, 8, 8)  # the patch size of an empty draw
    assert distractor_negatives(None, "fit.json", 3).shape[0] == 3
    assert [c[1] for c in calls] == [0, 1, 1, 1]  # shapes that get none are not drawn
    calls.clear()
    for bad, match in (({"realism_keep": 0.25}, "realism_keep"), ({"shape_variation": 0.3}, "shape_variation")):
        with pytest.raises(ValueError, match=match):
            distractor_negatives(None, "fit.json", 8, **bad)
    with pytest.raises(ValueError, match="count"):
        distractor_negatives(None, "fit.json", -1)
    with pytest.raises(ValueError, match="quantize must be one of"):
        distractor_negatives(None, "fit.json", 8, quantize="sometimes")
    assert not calls
    # rounded wherever quantize is not False: every distractor with "native_scale" (a blob is seen at no object size)
    distractor_negatives(None, "fit.json", 8, quantize="native_scale")
    assert [c[3]["quantize"] for c in calls] == [True] * 8


def _eigen_ratio(diff: np.ndarray) -> float:
    """The silhouette's elongation: sqrt of the ratio of its second moments' eigenvalues (numpy), weighted by
    how far each pixel is from the flat background."""
    w = diff / diff.sum()
    yy, xx = np.mgrid[: diff.shape[0], : diff.shape[1]].astype(float)
    my, mx = (w * yy).sum(), (w * xx).sum()
    cov = np.array([[(w * (yy - my) ** 2).sum(), (w * (yy - my) * (xx - mx)).sum()],
                    [(w * (yy - my) * (xx - mx)).sum(), (w * (xx - mx) ** 2).sum()]])
    lo, hi = np.linalg.eigvalsh(cov)
    return float(np.sqrt(hi / lo))


@pytest.mark.slow
def test_a_rendered_sphere_is_round_and_a_cigar_long(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Rendered with no capture effect on a flat background, a sphere distractor's silhouette has equal second
    moments whatever its pose; a cigar's (axes 1 : 0.3 : 0.3) is elongated in most poses."""
    from synthaug.data.seedset import SeedSet, write_seedset
    from synthaug.params import CaptureParams

    n, p, level = 4, 40, 0.6
    flat = np.full((n, p, p), round(level * 255), np.uint8)
    frames = [np.full((64, 64), round(level * 255), np.uint8)] * n
    write_seedset(tmp_path / "s", patches=flat, backgrounds=flat, boxes=[[12, 12, 28, 28]] * n,
                  centres=[[20, 20]] * n, crops=[[20, 20, 40]] * n, records=[{"video": "v"}] * n, frames=frames,
                  background_frames=frames, metadata={"patch_size": p, "object_fraction": 0.7})
    fit = tmp_path / "fit.json"
    CaptureParams.sample(n, generator=torch.Generator().manual_seed(0), effects=[]).save(fit)
    ss = SeedSet.load(tmp_path / "s")
    monkeypatch.setattr(training_sets, "DISTRACTOR_AXES", ((1.0, 1.0, 1.0), (1.0, 0.3, 0.3)))
    out = distractor_negatives(ss, fit, 24, seed=3).numpy()[:, 0]
    assert out.shape == (24, p, p) and 0 <= out.min() and out.max() <= 1
    diff = np.abs(out - flat[0] / 255.0)
    assert (diff.reshape(24, -1).max(1) > 0.05).all()  # every patch shows its object
    ratios = np.array([_eigen_ratio(d) for d in diff])
    sphere, cigar = ratios[:12], ratios[12:]
    assert sphere.max() < 1.25, sphere
    assert np.median(cigar) > 1.8 and np.median(cigar) > 1.5 * np.median(sphere), cigar


def test_soften_is_the_background_plus_a_blurred_scaled_difference_as_scipy_computes_it() -> None:
    """``B + c (G_sigma * (I - B))`` against ``scipy.ndimage.gaussian_filter`` (the same radius, replicated border)
    with the draws it reports; far from the object nothing moves; the draws lie in their ranges, both signs occur,
    and the same generator seed gives the same patches."""
    from scipy.ndimage import gaussian_filter

    rng = np.random.default_rng(0)
    n, p = 64, 40
    bg = rng.uniform(0.2, 0.8, (n, 1, p, p))
    img = bg.copy()
    img[:, :, 14:26, 12:28] = rng.uniform(0, 1, (n, 1, 12, 16))  # the object, away from the border
    out, drawn = soften(torch.from_numpy(img), torch.from_numpy(bg), rng=np.random.default_rng(5))
    radius = math.ceil(3 * SOFT_DISTRACTOR_BLUR_PX[1])
    for i in range(n):
        blurred = gaussian_filter(img[i, 0] - bg[i, 0], drawn["sigma"][i], mode="nearest", radius=radius)
        ref = np.clip(bg[i, 0] + drawn["contrast"][i] * blurred, 0, 1)
        np.testing.assert_allclose(out[i, 0].numpy(), ref, atol=1e-6)
    far = np.ones((p, p), bool)
    far[14 - radius:26 + radius, 12 - radius:28 + radius] = False
    np.testing.assert_array_equal(out.numpy()[:, 0][:, far], bg[:, 0][:, far])
    a, b = SOFT_DISTRACTOR_CONTRAST
    assert (a <= np.abs(drawn["contrast"])).all() and (np.abs(drawn["contrast"]) <= b).all()
    assert 10 < (drawn["contrast"] < 0).sum() < n - 10  # both signs, about half each
    lo, hi = SOFT_DISTRACTOR_BLUR_PX
    assert (lo <= drawn["sigma"]).all() and (drawn["sigma"] <= hi).all()
    again, _ = soften(torch.from_numpy(img), torch.from_numpy(bg), rng=np.random.default_rng(5))
    assert torch.equal(out, again)
    # fainter: the object's largest difference from its background shrinks at least by the largest contrast
    assert ((out - torch.from_numpy(bg)).abs().amax((1, 2, 3)).numpy()
            <= b * np.abs(img - bg).max((1, 2, 3)) + 1e-9).all()
    for bad in ({"contrast": (0.0, 0.5)}, {"contrast": (0.6, 0.5)}, {"blur_px": (0.0, 1.0)}):
        with pytest.raises(ValueError):
            soften(torch.from_numpy(img), torch.from_numpy(bg), rng=np.random.default_rng(0), **bad)
    with pytest.raises(ValueError, match="differ"):
        soften(torch.from_numpy(img), torch.from_numpy(bg[:2]), rng=np.random.default_rng(0))


def test_soft_distractors_fade_each_blob_against_its_own_seeds_background(monkeypatch: pytest.MonkeyPatch) -> None:
    """Soft distractors: each shape drawn unrounded with its seed index, faded against that seed's background with
    ``default_rng(seed + k)``, then rounded to 8 bits when the draw asks; the other style's checks still hold."""
    n, p = 3, 40
    backgrounds = np.stack([np.full((p, p), 40 * (i + 1), np.uint8) for i in range(n)])
    seedset = type("S", (), {"backgrounds": backgrounds})()
    calls: list[dict[str, Any]] = []

    def fake(ss: Any, mesh: Any, fit: Any, count: int, *, seed: int = 0, **kw: Any):
        calls.append({"count": count, "seed": seed, **kw})
        idx = np.arange(count) % n
        blobs = torch.from_numpy(backgrounds[idx].astype(np.float32) / 255)[:, None].clone()
        blobs[:, :, 18:22, 18:22] = 1.0  # a white object in the middle, farther than the blur from the corners
        return blobs, idx

    monkeypatch.setattr(training_sets, "synthetic_positives", fake)
    out = distractor_negatives(seedset, "fit.json", 10, seed=100, style="soft", quantize=True,
                               pose_sampling="fitted_at_seed")
    assert [c["count"] for c in calls] == [2, 2, 1, 1, 1, 1, 1, 1]
    assert [c["seed"] for c in calls] == list(range(100, 108))
    assert all(c["quantize"] is False and c["return_seed_index"] and c["pose_sampling"] == "fitted_at_seed"
               for c in calls)
    assert out.shape == (10, 1, p, p)
    np.testing.assert_array_equal((out * 255).round() / 255, out)  # rounded to 8 bits after the fade
    drawn = list(calls)
    idx = np.concatenate([np.arange(c["count"]) % n for c in drawn])
    expect = []
    for k, c in enumerate(drawn):
        blobs, i = fake(None, None, None, c["count"])
        bg = torch.from_numpy(backgrounds[i].astype(np.float32) / 255)[:, None]
        faint, _ = soften(blobs, bg, rng=np.random.default_rng(100 + k))
        expect.append((faint * 255).round() / 255)
    torch.testing.assert_close(out, torch.cat(expect), atol=1e-6, rtol=0)
    corners = out[:, 0, 0, 0].numpy() * 255
    np.testing.assert_allclose(corners, backgrounds[idx, 0, 0], atol=0.5)  # the seed's own background around it
    with pytest.raises(ValueError, match="background_sampling"):
        distractor_negatives(seedset, "fit.json", 4, style="soft", background_sampling="other")
    with pytest.raises(ValueError, match="style"):
        distractor_negatives(seedset, "fit.json", 4, style="cloudy")
