"""The fast rendering paths (issue 19) against the straightforward ones they replaced.

The references below are the implementations before issue 19, kept verbatim
(rfft2/irfft2 blurs with the transfer function of every row; the view warp
sampling the full, pre-scaled sprites). The new paths are the same operators
computed differently, so they must agree to float rounding: per effect, for
every subset of the paper's four effects through ``simulate``, and for whole
dataset items (patch and frame mode, grey and RGB).

Where a quantity is ill-conditioned by construction, the comparison is on the
quantity the image uses: the straight object colour after motion blur divides
by a coverage that may be ~1e-6 (compared: colour × coverage), and a normal is
normalised from a vector that may be ~1e-3 long at the object's fringe
(compared: normal × coverage).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import torch
import torch.nn.functional as F

from synthaug.data.procedural import sky_backgrounds
from synthaug.data.synthetic import SyntheticObjectDataset
from synthaug.effects import functional as Fx
from synthaug.effects import simulate
from synthaug.effects.registry import PAPER_EFFECTS
from synthaug.params import CaptureParams
from synthaug.render.cache import ViewCache


# ------------------------------------------------------------------ references (the path before issue 19)
def _ref_blur_groups(stack, groups, sigma_u, sigma_v, angle, *, pad, border):
    b, gc, h, w = stack.shape
    c = gc // groups
    hp, wp = Fx.next_fast_len(h + 2 * pad), Fx.next_fast_len(w + 2 * pad)
    pads = (pad, wp - w - pad, pad, hp - h - pad)
    x = F.pad(stack, pads) if border == "constant" else F.pad(stack, pads, mode=border)
    spec = torch.fft.rfft2(x).view(b, groups, c, hp, wp // 2 + 1)
    sv = sigma_u if sigma_v is None else sigma_v
    ang = torch.zeros_like(sigma_u) if angle is None else angle
    spec = spec * Fx.gaussian_transfer(hp, wp, sigma_u, sv, ang)[:, None]
    out = torch.fft.irfft2(spec.view(b, gc, hp, wp // 2 + 1), s=(hp, wp))
    return out[..., pad:pad + h, pad:pad + w]


def ref_motion_blur(object_color, coverage, sigma_u, sigma_v, angle, *, pad):
    b, c = object_color.shape[:2]
    premul = object_color * coverage
    stack = torch.cat([premul, coverage.expand(b, c, *coverage.shape[2:])], dim=1)
    su = Fx._per_channel(sigma_u, b, c, object_color, "sigma_u")
    sv = Fx._per_channel(sigma_v, b, c, object_color, "sigma_v")
    an = Fx._per_channel(angle, b, c, object_color, "angle")
    if b == 0:
        return object_color.clone(), coverage.expand(b, c, *coverage.shape[2:]).clone()
    out = _ref_blur_groups(stack, 2, su, sv, an, pad=pad, border="constant")
    premul_b, cov_b = out[:, :c], out[:, c:].clamp(0.0, 1.0)
    color = premul_b / cov_b.clamp_min(1e-6)
    color = torch.where(cov_b > 1e-6, color, torch.zeros_like(color))
    return color, cov_b


def ref_boundary_blur(image, coverage, sigma_s, *, pad):
    b, c = image.shape[:2]
    s = Fx._per_channel(sigma_s, b, c, image, "sigma_s")
    cov = coverage.expand(b, c, *coverage.shape[2:])
    if b == 0:
        return image.clone()
    out = _ref_blur_groups(torch.cat([image, cov], 1), 2, s, None, None, pad=pad, border="replicate")
    blurred, m = out[:, :c], out[:, c:].clamp(0.0, 1.0)
    band = (4.0 * m * (1.0 - m)).clamp(0.0, 1.0)
    return image + band * (blurred - image)


def ref_layers(self, alpha, beta, gamma, t_x, t_y, *, size, object_scale=0.7, dtype=torch.float32):
    if not hasattr(self, "_ref_full_sprites"):
        cov7 = torch.round(self.coverage.to(torch.float32) * (127.0 / 255.0)).to(torch.int8)
        self._ref_full_sprites = torch.cat([cov7[:, None], self.normals], dim=1).contiguous()
    h, w = (size, size) if isinstance(size, int) else size
    gamma = torch.as_tensor(gamma, dtype=dtype)
    b = gamma.shape[0]
    if b == 0:
        return torch.zeros(0, 1, h, w, dtype=dtype), torch.zeros(0, 3, h, w, dtype=dtype)
    idx = self.view_index(alpha, beta)
    sprites = self._ref_full_sprites[idx].to(dtype).mul_(1.0 / 127.0)
    tx = torch.as_tensor(t_x, dtype=dtype)
    ty = torch.as_tensor(t_y, dtype=dtype)
    osc = torch.as_tensor(object_scale, dtype=dtype).expand(b)
    k = self.sprite_scale / osc
    c, s = torch.cos(gamma), torch.sin(gamma)
    aspect = h / w
    px_x, px_y = 2 * tx, 2 * ty
    theta = torch.stack([
        torch.stack([k * c, -k * s * aspect, -k * (c * px_x - s * px_y)], 1),
        torch.stack([k * s, k * c * aspect, -k * (s * px_x + c * px_y)], 1),
    ], 1)
    grid = F.affine_grid(theta, [b, 4, h, w], align_corners=False)
    out = F.grid_sample(sprites, grid, mode="bilinear", padding_mode="zeros", align_corners=False)
    cov = out[:, :1].clamp(0.0, 1.0)
    nx, ny, nz = out[:, 1], out[:, 2], out[:, 3]
    cg, sg = c[:, None, None], s[:, None, None]
    nrm = torch.stack([cg * nx - sg * ny, sg * nx + cg * ny, nz], 1)
    norm = (nrm * nrm).sum(1, keepdim=True).sqrt_()
    nrm = nrm * torch.where(norm > 1e-3, 1.0 / norm.clamp_min(1e-3), 0.0)
    return cov, nrm


@pytest.fixture
def reference_path(monkeypatch):
    """Switch the effects and the view warp back to the reference implementations."""
    def use():
        monkeypatch.setattr(Fx, "motion_blur", ref_motion_blur)
        monkeypatch.setattr(Fx, "boundary_blur", ref_boundary_blur)
        monkeypatch.setattr(ViewCache, "layers", ref_layers)
    return use


# ------------------------------------------------------------------ data
def _layers(b, c, h, w, dtype, seed, distinct):
    """Object layers with soft edges, real-looking backgrounds, σ's with repeats (dataset-like) or all distinct."""
    g = torch.Generator().manual_seed(seed)
    yy, xx = torch.meshgrid(torch.arange(h, dtype=dtype), torch.arange(w, dtype=dtype), indexing="ij")
    cy = h * (0.3 + 0.4 * torch.rand(b, 1, 1, generator=g, dtype=dtype))
    cx = w * (0.3 + 0.4 * torch.rand(b, 1, 1, generator=g, dtype=dtype))
    r = min(h, w) * (0.1 + 0.2 * torch.rand(b, 1, 1, generator=g, dtype=dtype))
    cov = ((r - ((yy - cy) ** 2 + (xx - cx) ** 2).sqrt()).clamp(0, 1.5) / 1.5)[:, None]
    color = torch.rand(b, c, h, w, generator=g, dtype=dtype) * (cov > 0)
    bg = torch.rand(b, c, h, w, generator=g, dtype=dtype)
    rows = b if distinct else max(1, b // 4)
    pick = torch.arange(b) % rows

    def draw(high):
        return (torch.rand(rows, c, generator=g, dtype=dtype) * high)[pick]
    su, sv, sn = draw(5.0), draw(5.0), draw(3.0)
    an = ((torch.rand(rows, c, generator=g, dtype=dtype) - 0.5) * math.pi)[pick]
    su[0], sv[0], sn[0] = 0.0, 0.3, 0.0  # the identity and a sub-pixel blur are in every batch
    return cov, color, bg, su, sv, an, sn


CASES = [(16, 1, 64, 64), (9, 1, 40, 52), (5, 3, 33, 47), (4, 1, 120, 120)]


@pytest.mark.parametrize("dtype", [torch.float32, torch.float64])
@pytest.mark.parametrize("b,c,h,w", CASES)
@pytest.mark.parametrize("distinct", [False, True])
def test_motion_blur_equals_reference(b, c, h, w, dtype, distinct):
    cov, color, _, su, sv, an, _ = _layers(b, c, h, w, dtype, seed=h + w, distinct=distinct)
    col_n, cov_n = Fx.motion_blur(color, cov, su, sv, an, pad=15)
    col_r, cov_r = ref_motion_blur(color, cov, su, sv, an, pad=15)
    tol = 2e-6 if dtype == torch.float32 else 1e-12
    torch.testing.assert_close(cov_n, cov_r, atol=tol, rtol=0)
    # the colour is zeroed where the coverage is <= 1e-6 (a cut-off of the reference): a pixel that rounding
    # puts on the other side jumps by its premultiplied value (ringing of a sub-pixel blur, up to ~1e-3)
    flipped = (cov_n > 1e-6) != (cov_r > 1e-6)
    assert flipped.float().mean() < 1e-3 and bool(((cov_r - 1e-6).abs() < 10 * tol)[flipped].all())
    torch.testing.assert_close((col_n * cov_n)[~flipped], (col_r * cov_r)[~flipped], atol=tol, rtol=0)


@pytest.mark.parametrize("dtype", [torch.float32, torch.float64])
@pytest.mark.parametrize("b,c,h,w", CASES)
@pytest.mark.parametrize("distinct", [False, True])
def test_boundary_blur_equals_reference(b, c, h, w, dtype, distinct):
    cov, color, bg, _, _, _, sn = _layers(b, c, h, w, dtype, seed=h * w, distinct=distinct)
    img = Fx.composite(color, cov, bg)
    tol = 2e-6 if dtype == torch.float32 else 1e-12
    torch.testing.assert_close(Fx.boundary_blur(img, cov, sn, pad=9), ref_boundary_blur(img, cov, sn, pad=9),
                               atol=tol, rtol=0)


def test_fast_blurs_keep_their_gradients():
    cov, color, bg, su, sv, an, sn = _layers(4, 1, 20, 22, torch.float64, seed=3, distinct=False)
    params = [p.clone().requires_grad_(True) for p in (su + 0.5, sv + 0.5, an, sn + 0.5)]

    def run(mb, bb):
        col, cv = mb(color, cov, *params[:3], pad=6)
        return bb(Fx.composite(col, cv, bg), cv, params[3], pad=5).square().sum()
    g_new = torch.autograd.grad(run(Fx.motion_blur, Fx.boundary_blur), params)
    g_ref = torch.autograd.grad(run(ref_motion_blur, ref_boundary_blur), params)
    for a, r in zip(g_new, g_ref):
        torch.testing.assert_close(a, r, atol=1e-9, rtol=1e-7)


@pytest.fixture(scope="module")
def cache():
    return ViewCache.build("quadcopter", step_deg=30, sprite_size=48)


@pytest.mark.parametrize("size,dtype", [(64, torch.float32), ((40, 52), torch.float32), (64, torch.float64)])
def test_view_warp_equals_reference(cache, size, dtype):
    g = torch.Generator().manual_seed(0)
    b = 64
    pose = [(torch.rand(b, generator=g) * 2 - 1) * math.pi, (torch.rand(b, generator=g) - 0.5) * math.pi,
            (torch.rand(b, generator=g) * 2 - 1) * math.pi, (torch.rand(b, generator=g) - 0.5) * 0.4,
            (torch.rand(b, generator=g) - 0.5) * 0.4]
    scale = 0.3 + 0.6 * torch.rand(b, generator=g)
    cov_n, nrm_n = cache.layers(*pose, size=size, object_scale=scale, dtype=dtype)
    cov_r, nrm_r = ref_layers(cache, *pose, size=size, object_scale=scale, dtype=dtype)
    assert cov_r.sum() > 100  # the object is in view
    tol = 5e-5 if dtype == torch.float32 else 1e-10
    torch.testing.assert_close(cov_n, cov_r, atol=tol, rtol=0)
    torch.testing.assert_close(nrm_n * cov_r, nrm_r * cov_r, atol=tol, rtol=0)
    well = (cov_r > 0.05).expand_as(nrm_r)
    torch.testing.assert_close(nrm_n[well], nrm_r[well], atol=100 * tol, rtol=0)


SUBSETS = [s for k in range(len(PAPER_EFFECTS) + 1) for s in itertools.combinations(PAPER_EFFECTS, k)]


@pytest.mark.parametrize("channels", [1, 3])
def test_simulate_equals_reference_for_every_subset_of_effects(cache, reference_path, channels):
    g = torch.Generator().manual_seed(channels)
    b, size = 12, 48
    theta = CaptureParams.sample(b, generator=g, channels=channels)
    cov, nrm = cache.layers(theta.alpha, theta.beta, theta.gamma, theta.t_x, theta.t_y, size=size)
    bg = torch.rand(b, channels, size, size, generator=g)
    new = {s: simulate(cov, nrm, bg, theta, effects=s, generator=torch.Generator().manual_seed(1)) for s in SUBSETS}
    reference_path()
    for s in SUBSETS:
        ref = simulate(cov, nrm, bg, theta, effects=s, generator=torch.Generator().manual_seed(1))
        _assert_images_close(new[s], ref, f"effects {s}")


def _assert_images_close(new, ref, what):
    """Equal to float rounding, but for the rare pixel at the motion blur's 1e-6 coverage cut-off (see above)."""
    diff = (new - ref).abs()
    assert diff.max() < 5e-3, f"{what}: max |new - reference| {float(diff.max()):.3g}"
    assert (diff > 1e-5).float().mean() < 1e-3, f"{what}: {int((diff > 1e-5).sum())} pixels differ by > 1e-5"
    assert diff.mean() < 1e-6, f"{what}: mean |new - reference| {float(diff.mean()):.3g}"


def _items(ds, idx):
    return torch.stack([img.as_subclass(torch.Tensor) for img, _ in ds.__getitems__(idx)])


@pytest.mark.parametrize("mode,channels", [("patch", 1), ("patch", 3), ("frame", 1)])
def test_dataset_items_equal_reference(cache, reference_path, mode, channels):
    bgs = sky_backgrounds(4, (96, 96) if mode == "patch" else (160, 200), seed=2)
    ds = SyntheticObjectDataset("quadcopter", bgs, render=cache, length=64, mode=mode, patch_size=48,
                                channels=channels, negative_fraction=0.0, seed=7,
                                object_size=(20.0, 40.0))
    idx = list(range(24 if mode == "patch" else 8))
    new = _items(ds, idx)
    reference_path()
    ref = _items(ds, idx)
    _assert_images_close(new, ref, f"{mode}, {channels} channel(s)")


def test_frame_batches_from_workers_equal_the_main_process(cache):
    """Frames built in one shared block per batch (in workers) and per-item views of batch tensors."""
    from torch.utils.data import DataLoader

    from synthaug.data.synthetic import collate_detection

    bgs = sky_backgrounds(3, (120, 150), seed=4)
    ds = SyntheticObjectDataset("quadcopter", bgs, render=cache, length=12, mode="frame", negative_fraction=0.3,
                                seed=9, object_size=(20.0, 40.0))
    runs = []
    for workers in (0, 2):
        items = []
        for images, targets in DataLoader(ds, batch_size=5, num_workers=workers, collate_fn=collate_detection):
            items += [(img.as_subclass(torch.Tensor).clone(), {k: v.as_subclass(torch.Tensor).clone()
                                                               for k, v in t.items()}) for img, t in zip(images, targets)]
        runs.append(items)
    assert len(runs[0]) == len(runs[1]) == 12
    assert any(len(t["boxes"]) == 0 for _, t in runs[0]) and any(len(t["boxes"]) == 1 for _, t in runs[0])
    for (img0, t0), (img1, t1) in zip(*runs):
        assert torch.equal(img0, img1)
        assert t0.keys() == t1.keys() and all(torch.equal(t0[k], t1[k]) for k in t0)
    single = ds[7]
    assert torch.equal(single[0].as_subclass(torch.Tensor), runs[0][7][0])
    assert torch.equal(single[1]["boxes"].as_subclass(torch.Tensor), runs[0][7][1]["boxes"])


def test_items_do_not_depend_on_the_batch_they_are_rendered_in(cache):
    """A large batch is rendered in chunks and shares per-σ operators: its items equal the items alone."""
    bgs = sky_backgrounds(4, (96, 96), seed=5)
    ds = SyntheticObjectDataset("quadcopter", bgs, render=cache, length=300, patch_size=32, negative_fraction=0.1,
                                seed=11)
    idx = list(range(3, 3 + 150))  # more than one chunk of 32x32 patches
    batch = _items(ds, idx)
    alone = torch.stack([ds[i][0] for i in idx[::7]])
    small = _items(ds, idx[::7])
    torch.testing.assert_close(batch[::7], alone, atol=1e-6, rtol=0)
    torch.testing.assert_close(small, alone, atol=1e-6, rtol=0)


def _ref_box_from_coverage(cov, x0, y0, threshold=0.5):
    mask = cov >= threshold
    if not mask.any():
        mask = cov > 0
    if not mask.any():
        return torch.zeros((0, 4), dtype=torch.float32)
    ys = torch.nonzero(mask.any(1)).flatten()
    xs = torch.nonzero(mask.any(0)).flatten()
    return torch.tensor([[x0 + xs[0].item(), y0 + ys[0].item(), x0 + xs[-1].item() + 1, y0 + ys[-1].item() + 1]],
                        dtype=torch.float32)


def test_batched_boxes_equal_the_per_item_boxes():
    from synthaug.data.synthetic import _boxes_from_coverage

    g = torch.Generator().manual_seed(0)
    cov = torch.zeros(6, 20, 24)
    cov[0, 3:9, 5:7] = 1.0
    cov[1, 2, 3] = 0.3  # nothing >= 0.5: the box of what is > 0
    cov[1, 10, 20] = 0.2
    cov[3] = torch.rand(20, 24, generator=g) * (torch.rand(20, 24, generator=g) > 0.9)  # cov[2]: empty
    cov[4, 0, 0] = cov[4, 19, 23] = 0.9
    cov[5, 7:8, :] = 0.6
    x0, y0 = torch.tensor([0, 5, 7, 11, 2, 100]), torch.tensor([1, 0, 3, 8, 4, 50])
    boxes, counts = _boxes_from_coverage(cov, x0, y0)
    for k in range(6):
        ref = _ref_box_from_coverage(cov[k], int(x0[k]), int(y0[k]))
        assert counts[k] == len(ref)
        assert torch.equal(boxes[k, None][:counts[k]], ref)
