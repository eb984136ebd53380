"""Levi–Weiss edge-orientation energies E(X, R, o) against a direct numpy computation."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from synthaug.detectors.weak_learners import (
    WeakLearners,
    edge_orientation_energy,
    exhaustive_candidates,
    interior_orientation_maps,
    orientation_integrals,
    orientation_maps,
    random_candidates,
    rect_sums,
    weak_learner_response,
)


def _np_maps(img: np.ndarray, n_bins: int) -> np.ndarray:
    """Reference: per-pixel loops over the definition (edge-replicated central differences)."""
    h, w = img.shape
    out = np.zeros((n_bins, h, w))
    for y in range(h):
        for x in range(w):
            gx = (img[y, min(x + 1, w - 1)] - img[y, max(x - 1, 0)]) / 2
            gy = (img[min(y + 1, h - 1), x] - img[max(y - 1, 0), x]) / 2
            mag = math.sqrt(gx * gx + gy * gy + 1e-12)
            theta = math.atan2(gy, gx) % math.pi
            b = int(round(theta * n_bins / math.pi)) % n_bins
            out[b, y, x] = mag
    return out


def _np_energy(img: np.ndarray, rects: np.ndarray, orients: np.ndarray, n_bins: int, eps: float) -> np.ndarray:
    maps = _np_maps(img, n_bins)
    e = []
    for (y0, x0, h, w), o in zip(rects, orients):
        region = maps[:, y0:y0 + h, x0:x0 + w]
        e.append(region[o].sum() / (region.sum() + eps))
    return np.array(e)


def _images(n: int, size: int = 40, seed: int = 0) -> torch.Tensor:
    from synthaug.detectors.toy import toy_patches

    pos, neg = toy_patches(n - n // 2, n // 2, size, seed=seed)
    return torch.cat([pos, neg])


@pytest.mark.parametrize("n_bins", [2, 4, 8])
def test_orientation_maps_match_numpy(n_bins: int) -> None:
    img = torch.rand(1, 1, 9, 11, generator=torch.Generator().manual_seed(n_bins), dtype=torch.float64)
    ours = orientation_maps(img, n_bins)[0].numpy()
    np.testing.assert_allclose(ours, _np_maps(img[0, 0].numpy(), n_bins), atol=1e-12)


def test_known_edges_land_in_expected_bins() -> None:
    x = torch.zeros(2, 1, 7, 7)
    x[0, :, :, 4:] = 1.0  # vertical edge: horizontal gradient -> bin 0
    x[1, :, 4:, :] = 1.0  # horizontal edge: vertical gradient -> bin K/2
    m = orientation_maps(x, 4)
    assert m[0, 0, 3, 3] == pytest.approx(0.5) and m[0, 1:, 3, 3].abs().max() < 1e-5
    assert m[1, 2, 3, 3] == pytest.approx(0.5) and m[1, [0, 1, 3], 3, 3].abs().max() < 1e-5


@pytest.mark.parametrize("n_bins", [4, 6])
def test_energies_match_numpy(n_bins: int) -> None:
    g = torch.Generator().manual_seed(1)
    x = _images(3).double()
    rects, orients = random_candidates(40, 40, n_bins, generator=g)
    # also rectangles touching the image border (allowed by the energy function)
    rects = torch.cat([rects, torch.tensor([[0, 0, 40, 40], [0, 30, 10, 10]])])
    orients = torch.cat([orients, torch.tensor([0, n_bins - 1])])
    ours = edge_orientation_energy(x, rects, orients, n_bins, eps=1e-3)
    for b in range(3):
        ref = _np_energy(x[b, 0].numpy(), rects.numpy(), orients.numpy(), n_bins, 1e-3)
        np.testing.assert_allclose(ours[b].numpy(), ref, rtol=1e-9, atol=1e-12)


def test_float32_energies_close_to_float64() -> None:
    x = _images(4)
    rects, orients = exhaustive_candidates(40, 4, step=8)
    e32 = edge_orientation_energy(x, rects, orients)
    e64 = edge_orientation_energy(x.double(), rects, orients)
    assert e32.dtype == torch.float32
    np.testing.assert_allclose(e32.numpy(), e64.numpy(), atol=1e-5)


def test_rect_sums_match_slicing() -> None:
    m = torch.rand(2, 3, 12, 10, generator=torch.Generator().manual_seed(2), dtype=torch.float64)
    ii = torch.nn.functional.pad(m.cumsum(-1).cumsum(-2), (1, 0, 1, 0))
    rects = torch.tensor([[0, 0, 12, 10], [3, 2, 4, 5], [11, 9, 1, 1]])
    ours = rect_sums(ii, rects)
    for r, (y0, x0, h, w) in enumerate(rects.tolist()):
        np.testing.assert_allclose(ours[:, :, r].numpy(), m[:, :, y0:y0 + h, x0:x0 + w].sum((-1, -2)).numpy())


def test_integrals_and_interior_maps_agree_with_maps() -> None:
    x = torch.rand(2, 1, 13, 17, generator=torch.Generator().manual_seed(3))
    m = orientation_maps(x, 4)
    ii = orientation_integrals(x, 4, dtype=torch.float64)
    assert ii.shape == (2, 4, 14, 18) and ii.dtype == torch.float64
    np.testing.assert_allclose(ii[..., -1, -1].numpy(), m.double().sum((-1, -2)).numpy(), rtol=1e-12)
    assert torch.equal(interior_orientation_maps(x, 4), m[..., 1:-1, 1:-1])


def test_batched_equals_unbatched_and_input_unchanged() -> None:
    x = _images(5)
    x0 = x.clone()
    rects, orients = random_candidates(30, 40, 4, generator=torch.Generator().manual_seed(4))
    batched = edge_orientation_energy(x, rects, orients)
    single = torch.cat([edge_orientation_energy(x[i:i + 1], rects, orients) for i in range(5)])
    torch.testing.assert_close(batched, single)
    assert torch.equal(x, x0)
    assert edge_orientation_energy(x[:0], rects, orients).shape == (0, 30)


def test_energy_gradcheck_float64() -> None:
    x = torch.rand(1, 1, 10, 10, generator=torch.Generator().manual_seed(5), dtype=torch.float64)
    x.requires_grad_(True)
    rects = torch.tensor([[1, 1, 8, 8], [2, 3, 4, 5]])
    orients = torch.tensor([1, 2])
    assert torch.autograd.gradcheck(lambda t: edge_orientation_energy(t, rects, orients, 4), (x,), eps=1e-7, atol=1e-5)


def test_random_candidates_inside_interior_and_reproducible() -> None:
    r1, o1 = random_candidates(500, 40, 4, generator=torch.Generator().manual_seed(6), min_size=6)
    r2, o2 = random_candidates(500, 40, 4, generator=torch.Generator().manual_seed(6), min_size=6)
    r3, _ = random_candidates(500, 40, 4, generator=torch.Generator().manual_seed(7), min_size=6)
    assert torch.equal(r1, r2) and torch.equal(o1, o2) and not torch.equal(r1, r3)
    assert (r1[:, :2] >= 1).all() and (r1[:, :2] + r1[:, 2:] <= 39).all() and (r1[:, 2:] >= 6).all()
    assert set(o1.tolist()) == {0, 1, 2, 3}
    # positions cover the whole interior range
    assert int(r1[:, 0].min()) == 1 and int((r1[:, 0] + r1[:, 2]).max()) == 39


def test_exhaustive_candidate_count_by_hand() -> None:
    # interior of 38 px, corners every 4 px from 0, sides 4, 8, ... fitting: Σ_{p=0,4,..,36} floor((38-p)/4)
    per_axis = sum((38 - p) // 4 for p in range(0, 38, 4))
    rects, orients = exhaustive_candidates(40, 4, step=4, min_size=4)
    assert len(rects) == per_axis ** 2 * 4 == len(orients)
    assert len(torch.unique(torch.cat([rects, orients[:, None]], 1), dim=0)) == len(rects)
    assert ((rects[:, :2] - 1) % 4 == 0).all() and (rects[:, 2:] % 4 == 0).all()


def test_weak_learner_response_step_sigmoid_polarity() -> None:
    e = torch.tensor([[0.1, 0.3, 0.5]])
    tau = torch.tensor([0.2, 0.2, 0.6])
    assert weak_learner_response(e, tau).tolist() == [[0.0, 1.0, 0.0]]
    assert weak_learner_response(e, tau, torch.tensor([-1.0, -1.0, 1.0])).tolist() == [[1.0, 0.0, 0.0]]
    soft = weak_learner_response(e, tau, temperature=1e-4)
    torch.testing.assert_close(soft, weak_learner_response(e, tau))
    mid = weak_learner_response(tau[None], tau, temperature=0.1)
    torch.testing.assert_close(mid, torch.full((1, 3), 0.5))
    with pytest.raises(ValueError, match="temperature"):
        weak_learner_response(e, tau, temperature=0.0)


def test_weak_learners_roundtrip_and_responses() -> None:
    x = _images(6)
    wl = WeakLearners.random(50, generator=torch.Generator().manual_seed(8), reference=x)
    h = wl.responses(x)
    assert h.shape == (6, 50) and set(h.unique().tolist()) <= {0.0, 1.0}
    # thresholds drawn from reference energies split them: not all learners are constant
    assert (h.std(0) > 0).float().mean() > 0.3
    e = wl.energies(x)
    torch.testing.assert_close(h, (e > wl.thresholds).float())
    import io

    buf = io.BytesIO()
    torch.save(wl.state_dict(), buf)
    buf.seek(0)
    back = WeakLearners.from_state_dict(torch.load(buf, weights_only=True))
    torch.testing.assert_close(back.responses(x), h)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: orientation_maps(torch.rand(2, 3, 8, 8)), r"\(B, 1, H, W\)"),
        (lambda: orientation_maps(torch.zeros(1, 1, 8, 8, dtype=torch.long)), "float"),
        (lambda: orientation_maps(torch.rand(1, 1, 8, 8), n_bins=1), "n_bins"),
        (lambda: random_candidates(5, 40, 4, generator=torch.Generator(), min_size=39), "min_size"),
        (lambda: exhaustive_candidates(40, 4, step=0), "step"),
        (lambda: rect_sums(torch.zeros(1, 1, 5, 5), torch.tensor([[0, 0, 5, 5]])), "exceeds"),
        (lambda: rect_sums(torch.zeros(1, 1, 5, 5), torch.tensor([[0, 0, 0, 2]])), "h, w >= 1"),
        (lambda: edge_orientation_energy(torch.rand(1, 1, 8, 8), torch.tensor([[1, 1, 2, 2]]), torch.tensor([4])), "orientations"),
        (lambda: WeakLearners(torch.tensor([[1, 1, 2, 2]]), torch.tensor([0]), torch.tensor([0.1]),
                              torch.tensor([0.5]), torch.tensor([1.0])), "polarity"),
        (lambda: WeakLearners(torch.tensor([[30, 30, 20, 2]]), torch.tensor([0]), torch.tensor([0.1]),
                              torch.tensor([1.0]), torch.tensor([1.0])), "fit"),
    ],
)
def test_bad_inputs(call, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        call()
