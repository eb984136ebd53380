"""Every registered distance: metric-like properties, plus references for eucl and hog.

The generic tests are parametrised over ``list_distances()``, so distances
added by other modules (weak learners, CNN) are covered as soon as they register.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

from synthaug.distances import (
    Distance,
    example_distance,
    get_distance,
    get_entry,
    list_distances,
    register_distance,
    unregister_distance,
)

NAMES = list_distances()


def _blob_images(n: int, seed: int) -> torch.Tensor:
    """Dark ellipse-like blobs at random positions on smooth bright backgrounds, (n, 1, 40, 40)."""
    g = torch.Generator().manual_seed(seed)
    yy, xx = torch.meshgrid(torch.arange(40.0), torch.arange(40.0), indexing="ij")
    out = []
    for _ in range(n):
        cy, cx = (10 + 20 * torch.rand(2, generator=g)).tolist()
        ry, rx = (4 + 6 * torch.rand(2, generator=g)).tolist()
        background = 0.6 + 0.2 * torch.rand((), generator=g) + 0.1 * torch.sin(xx / (3 + 5 * torch.rand((), generator=g)))
        blob = (((yy - cy) / ry) ** 2 + ((xx - cx) / rx) ** 2 < 1).float()
        out.append(background * (1 - blob) + 0.15 * blob)
    return torch.stack(out)[:, None].clamp(0, 1)


@pytest.fixture(scope="module", params=NAMES)
def distance(request: pytest.FixtureRequest) -> Distance:
    return example_distance(request.param, torch.Generator().manual_seed(0))


def test_builtin_distances_registered() -> None:
    assert {"eucl", "hog"} <= set(NAMES)


def test_zero_on_identical_images(distance: Distance) -> None:
    x = _blob_images(6, 1)
    d = distance(x, x.clone())
    assert d.shape == (6,)
    torch.testing.assert_close(d, torch.zeros(6), atol=1e-5, rtol=0)


def test_symmetric(distance: Distance) -> None:
    a, b = _blob_images(5, 2), _blob_images(5, 3)
    torch.testing.assert_close(distance(a, b), distance(b, a), rtol=1e-4, atol=1e-5)


def test_nonnegative_and_slightly_perturbed_is_closer(distance: Distance) -> None:
    x = _blob_images(8, 4)
    g = torch.Generator().manual_seed(5)
    perturbed = (x + 0.01 * torch.randn(x.shape, generator=g)).clamp(0, 1)
    different = _blob_images(8, 6)
    d_near = distance(x, perturbed)
    d_far = distance(x, different)
    assert (d_near >= 0).all() and (d_far >= 0).all()
    message = f"{distance.name}: near {d_near.tolist()} far {d_far.tolist()}"
    if distance.differentiable:
        assert (d_near < d_far).all(), message
    else:
        # piecewise-constant distances (hard weak learners) jump when noise pushes a
        # response over a threshold: require the ranking on average and for most pairs
        assert d_near.mean() < d_far.mean(), message
        assert (d_near < d_far).float().mean() >= 0.75, message


def test_real_broadcasts_over_batch(distance: Distance) -> None:
    real = _blob_images(1, 7)
    syn = _blob_images(4, 8)
    broadcast = distance(real, syn)
    expanded = distance(real.expand(4, -1, -1, -1).contiguous(), syn)
    torch.testing.assert_close(broadcast, expanded)
    single = torch.cat([distance(real, syn[i : i + 1]) for i in range(4)])
    torch.testing.assert_close(broadcast, single, rtol=1e-4, atol=1e-5)


def test_inputs_unchanged_and_bad_shapes(distance: Distance) -> None:
    real, syn = _blob_images(1, 9), _blob_images(3, 10)
    r0, s0 = real.clone(), syn.clone()
    distance(real, syn)
    assert torch.equal(real, r0) and torch.equal(syn, s0)
    with pytest.raises(ValueError, match="batch"):
        distance(_blob_images(2, 1), syn)
    with pytest.raises(ValueError, match=r"\(B, C, H, W\)"):
        distance(real[0], syn)


def test_gradients_finite_where_differentiable(distance: Distance) -> None:
    if not distance.differentiable:
        pytest.skip(f"{distance.name} is piecewise constant")
    real = _blob_images(1, 11)
    syn = torch.cat([real, _blob_images(2, 12)]).requires_grad_(True)  # includes d = 0
    distance(real, syn).sum().backward()
    assert torch.isfinite(syn.grad).all()
    assert syn.grad[1:].abs().sum() > 0


def test_eucl_matches_numpy() -> None:
    a, b = _blob_images(3, 13), _blob_images(3, 14)
    ref = np.sqrt(((a.numpy().astype(np.float64) - b.numpy()) ** 2).reshape(3, -1).sum(1))
    np.testing.assert_allclose(get_distance("eucl")(a, b).numpy(), ref, rtol=1e-5)


def test_hog_matches_skimage_l2() -> None:
    skimage_feature = pytest.importorskip("skimage.feature")
    from synthaug.detectors.hog import SKIMAGE_HOG

    a, b = _blob_images(3, 15).double(), _blob_images(3, 16).double()

    def sk(x: torch.Tensor) -> np.ndarray:
        return skimage_feature.hog(x[0].numpy(), 9, (8, 8), (2, 2), block_norm="L2-Hys")

    ref = [np.linalg.norm(sk(a[i]) - sk(b[i])) for i in range(3)]
    ours = get_distance("hog", config=SKIMAGE_HOG)(a, b)
    np.testing.assert_allclose(ours.numpy(), ref, atol=1e-6)


def test_registry_errors_and_plugins() -> None:
    with pytest.raises(ValueError, match="unknown distance 'nope'.*eucl"):
        get_distance("nope")
    with pytest.raises(ValueError, match="example"):
        register_distance("needs_data", needs_fit=True)

    @register_distance("test_l1")
    class L1(Distance):
        """L1 between pixels."""

        def forward(self, x_real: torch.Tensor, x_syn: torch.Tensor) -> torch.Tensor:
            return (x_real - x_syn).abs().flatten(1).sum(1)

    try:
        assert "test_l1" in list_distances()
        assert get_entry("test_l1").doc == "L1 between pixels."
        with pytest.raises(ValueError, match="already registered"):

            @register_distance("test_l1")
            class Other(Distance):  # noqa: F841
                pass
    finally:
        unregister_distance("test_l1")
    assert "test_l1" not in list_distances()
