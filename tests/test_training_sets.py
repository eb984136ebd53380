"""Rendered distractors (:func:`synthaug.detectors.training_sets.distractor_negatives`): the shapes, their split and
seeds, and what a render of one looks like against an independent measure of its silhouette."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

import synthaug.detectors.training_sets as training_sets
from synthaug.detectors.training_sets import DISTRACTOR_AXES, distractor_meshes, distractor_negatives


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
    assert not calls


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
