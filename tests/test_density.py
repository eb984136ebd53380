"""Capture-parameter densities: KDE kernel equals scipy's, samples stay in range, the dataset uses them."""

import numpy as np
import pytest
import scipy.stats
import torch

from synthaug.data.density import CaptureDensity
from synthaug.params import CaptureParams


@pytest.fixture()
def seeds():
    g = torch.Generator().manual_seed(0)
    return CaptureParams.sample(40, generator=g)


def test_kde_kernel_matches_scipy(seeds):
    dens = CaptureDensity(seeds, kind="kde")
    data = seeds.to_vector().double().numpy()[:, 5:]
    ref = scipy.stats.gaussian_kde(data.T)
    np.testing.assert_allclose(dens.kernel_cov.numpy(), ref.covariance, rtol=1e-10, atol=1e-12)
    assert dens.factor == pytest.approx(ref.factor)


def test_kde_samples_follow_the_kernel_and_stay_in_range(seeds):
    dens = CaptureDensity(seeds, kind="kde")
    x = dens.sample(20000, generator=torch.Generator().manual_seed(1))
    assert bool(((x >= dens.low - 1e-9) & (x <= dens.high + 1e-9)).all())
    # mean of a KDE = data mean (folding at the bounds moves it a little; angles wrap, so skip them)
    lin = ~dens.periodic
    np.testing.assert_allclose(x.mean(0)[lin].numpy(), dens.data.mean(0)[lin].numpy(), atol=0.08)
    # reproducible with the same generator
    a = dens.sample(5, generator=torch.Generator().manual_seed(7))
    b = dens.sample(5, generator=torch.Generator().manual_seed(7))
    assert torch.equal(a, b)


def test_uniform_between_seed_min_and_max(seeds):
    dens = CaptureDensity(seeds, kind="uniform")
    x = dens.sample(5000, generator=torch.Generator().manual_seed(2))
    assert bool((x >= dens.data_min).all() and (x <= dens.data_max).all())
    np.testing.assert_allclose(x.min(0).values.numpy(), dens.data_min.numpy(), atol=0.05 * (dens.data_max - dens.data_min).max().item())


def test_bad_inputs(seeds):
    with pytest.raises(ValueError, match="kind must be"):
        CaptureDensity(seeds, kind="gmm")
    with pytest.raises(ValueError, match="at least 2 seeds"):
        CaptureDensity(seeds[0], kind="kde")


def test_dataset_draws_capture_parameters_from_the_density(small_cache):
    from synthaug.data.synthetic import SyntheticObjectDataset

    bgs = np.full((3, 40, 40), 150, np.uint8)
    params = CaptureParams({"sigma_s": [0.2, 0.5, 1.0], "w_d": [0.2, 0.4, 0.6]})
    ds = SyntheticObjectDataset("quadcopter", bgs, params, render=small_cache, length=30, capture_sampling="uniform")
    w = torch.stack([ds[i][1]["theta"][-1] for i in range(30)])
    assert bool(((w >= 0.2 - 1e-6) & (w <= 0.6 + 1e-6)).all())
    assert len(set(np.round(w.numpy(), 4))) > 10  # not just the three seed values
    seed_ds = SyntheticObjectDataset("quadcopter", bgs, params, render=small_cache, length=30)
    assert set(np.round([seed_ds[i][1]["theta"][-1].item() for i in range(30)], 4)) <= {0.2, 0.4, 0.6}


@pytest.mark.parametrize("name", ["seed", "kde", "uniform"])
def test_capture_sampler_object_is_its_name(small_cache, name):
    from synthaug.data.captures import CAPTURE_SAMPLERS, CaptureSampler
    from synthaug.data.synthetic import SyntheticObjectDataset

    bgs = np.full((3, 40, 40), 150, np.uint8)
    params = CaptureParams({"sigma_s": [0.2, 0.5, 1.0], "w_d": [0.2, 0.4, 0.6]})
    sampler = CAPTURE_SAMPLERS[name](params)
    a = SyntheticObjectDataset("quadcopter", bgs, params, render=small_cache, length=6, capture_sampling=name)
    b = SyntheticObjectDataset("quadcopter", bgs, params, render=small_cache, length=6, capture_sampling=sampler)
    assert b.capture_sampler is sampler and isinstance(sampler, CaptureSampler)
    for i in range(6):
        assert a.make_params(i) == b.make_params(i)
        assert torch.equal(a[i][0], b[i][0]) and torch.equal(a[i][1]["theta"], b[i][1]["theta"])


def test_own_capture_sampler_and_bad_ones(small_cache):
    from synthaug.data.synthetic import SyntheticObjectDataset

    bgs = np.full((3, 40, 40), 150, np.uint8)
    params = CaptureParams({"sigma_s": [0.2, 0.5, 1.0], "w_d": [0.2, 0.4, 0.6]})

    class Fixed:
        """Every item with the last seed's Θ, whatever its background."""

        def sample(self, generator, seed_index):
            return None

        def rows(self, seed_indices, captures):
            return params[torch.full_like(seed_indices, 2)]

    ds = SyntheticObjectDataset("quadcopter", bgs, params, render=small_cache, length=8, capture_sampling=Fixed())
    assert all(ds[i][1]["theta"][-1].item() == pytest.approx(0.6) for i in range(8))
    for bad in ("gmm", 3):
        with pytest.raises(ValueError, match="capture_sampling must be"):
            SyntheticObjectDataset("quadcopter", bgs, params, render=small_cache, length=4, capture_sampling=bad)
