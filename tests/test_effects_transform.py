"""CaptureEffects: the capture effects as a transform for any images (issue 14, part 6)."""

from __future__ import annotations

import math

import pytest
import torch

from synthaug.effects import PAPER_EFFECTS, CaptureEffects, sample_fields, simulate
from synthaug.effects.transform import ParamsFileNotFoundError
from synthaug.params import CaptureParams

EXACT = dict(rtol=0.0, atol=0.0)
CAMERA_SET = PAPER_EFFECTS + ("object_texture", "vignetting", "defocus", "shot_noise", "gamma")


def _fitted(n: int = 5, channels: int = 1, effects=PAPER_EFFECTS, seed: int = 0) -> CaptureParams:
    """A stand-in for a fit file: n rows drawn from the default ranges."""
    return CaptureParams.sample(n, generator=torch.Generator().manual_seed(seed), channels=channels, effects=effects)


def _images(b: int = 4, c: int = 1, h: int = 24, w: int = 28, seed: int = 1) -> torch.Tensor:
    return torch.rand(b, c, h, w, generator=torch.Generator().manual_seed(seed)) * 0.8 + 0.1


def _dataset_layers(cache, b: int, size: int, seed: int):
    """Coverage / normals of b random poses, posed from the view cache as the dataset does."""
    g = torch.Generator().manual_seed(seed)
    u = torch.rand(5, b, generator=g)
    alpha = (u[0] * 2 - 1) * math.pi
    beta = (u[1] * 2 - 1) * math.pi / 2
    gamma = (u[2] * 2 - 1) * math.pi
    t_x, t_y = (u[3] - 0.5) * 0.2, (u[4] - 0.5) * 0.2
    cov, nrm = cache.layers(alpha, beta, gamma, t_x, t_y, size=size, object_scale=torch.full((b,), 0.7))
    return cov, nrm


# ------------------------------------------------------------ the dataset's own path
@pytest.mark.parametrize("channels,effects", [(1, PAPER_EFFECTS), (3, PAPER_EFFECTS), (1, CAMERA_SET)])
def test_equals_simulate_on_rendered_layers(small_cache, channels, effects):
    """Fed the dataset's layers (coverage + normals from the view cache over a real background), Θ and fields,
    forward is S(Θ, B) exactly: the same numbers simulate() gives the dataset."""
    b, size = 5, 40
    cov, nrm = _dataset_layers(small_cache, b, size, seed=2)
    assert float(cov.sum()) > 0
    bgs = _images(b, channels, size, size, seed=3)
    fitted = _fitted(4, channels, effects)
    theta = fitted[torch.tensor([0, 3, 1, 1, 2])]  # each item one seed's row, as sampling="seed" does
    fields = sample_fields(effects, (b, channels, size, size), torch.Generator().manual_seed(4))
    origin = torch.tensor([[0.0, 0.0], [100.0, 40.0], [8.0, 16.0], [300.0, 200.0], [3.0, 5.0]])
    frame_size = torch.tensor([[320.0, 240.0]]).expand(b, 2)
    ref = simulate(cov, nrm, bgs, theta, effects=effects, fields=fields, origin=origin, frame_size=frame_size)
    aug = CaptureEffects(fitted)
    out = aug(bgs, params={"theta": theta, "fields": fields}, coverage=cov, normals=nrm, origin=origin,
              frame_size=frame_size)
    torch.testing.assert_close(out, ref, **EXACT)
    assert not torch.equal(out, bgs)


def test_own_draw_replays_simulate_and_p_gate_keeps_the_rest(small_cache):
    """make_params' rows are fitted rows; with p < 1 the drawn samples equal simulate() on the whole batch and
    the others are returned bit for bit."""
    b, size = 12, 32
    cov, nrm = _dataset_layers(small_cache, b, size, seed=5)
    bgs = _images(b, 1, size, size, seed=6)
    fitted = _fitted(6)
    aug = CaptureEffects(fitted, p=0.5, generator=7)
    draw = aug.make_params(bgs.shape)
    assert draw["row"].min() >= 0 and draw["row"].max() < 6
    torch.testing.assert_close(draw["theta"].to_vector(), fitted[draw["row"]].to_vector(), **EXACT)
    on = draw["apply"]
    assert 0 < int(on.sum()) < b
    out = aug(bgs, params=draw, coverage=cov, normals=nrm)
    ref = simulate(cov, nrm, bgs, draw["theta"], fields=draw["fields"])
    torch.testing.assert_close(out[on], ref[on], **EXACT)
    torch.testing.assert_close(out[~on], bgs[~on], **EXACT)


# --------------------------------------------------------------- plain-image semantics
def test_plain_image_semantics_of_the_paper_effects():
    x = _images(3, 1, 32, 32)
    theta = CaptureParams({"sigma_s": 1.5, "sigma_u": 2.0, "sigma_v": 0.5, "alpha_m": 0.3, "sigma_n": 0.05,
                           "w_d": [[0.2], [0.5], [0.7]]}, channels=1)
    fields = sample_fields(PAPER_EFFECTS, tuple(x.shape), torch.Generator().manual_seed(0))
    draw = {"theta": theta, "fields": fields}
    # boundary blur: no object boundary without a mask -> the identity
    torch.testing.assert_close(CaptureEffects(theta, ["boundary_blur"])(x, params=draw), x, rtol=0, atol=1e-5)
    # material: the gain w_d / 0.5 (w_d = 0.5, simulate's default material, is the identity)
    gain = CaptureEffects(theta, ["material"])(x, params=draw)
    torch.testing.assert_close(gain, (x * theta.w_d[:, :, None, None] / 0.5).clamp(0, 1), **EXACT)
    torch.testing.assert_close(gain[1], x[1], **EXACT)
    # object noise: everywhere
    noisy = CaptureEffects(theta, ["object_noise"])(x, params=draw)
    torch.testing.assert_close(noisy, (x + 0.05 * fields["noise"]).clamp(0, 1), rtol=0, atol=1e-6)
    # motion blur: blurs the interior (a normalised blur), fades to the input at the border
    mb = CaptureEffects(theta, ["motion_blur"])(x, params=draw)
    assert (mb[..., 8:-8, 8:-8] - x[..., 8:-8, 8:-8]).abs().mean() > 0.05
    assert mb[..., 8:-8, 8:-8].std() < x[..., 8:-8, 8:-8].std()
    assert mb.min() >= 0 and mb.max() <= 1


def test_material_gain_is_the_ratio_to_simulates_default_material(small_cache):
    """Why the plain-image material is a gain: on a rendered object, material on / material off = w_d / 0.5."""
    cov, nrm = _dataset_layers(small_cache, 3, 32, seed=8)
    full = torch.ones_like(cov)
    bg = _images(3, 1, 32, 32, seed=9)
    theta = CaptureParams({"w_d": [0.1, 0.5, 0.9]})
    on = simulate(full, nrm, bg, theta, effects=["material"])
    off = simulate(full, nrm, bg, theta, effects=[])
    torch.testing.assert_close(on, off * theta.w_d[:, :, None, None] / 0.5, rtol=1e-6, atol=1e-7)
    # and with the normals given, CaptureEffects renders exactly that
    torch.testing.assert_close(CaptureEffects(theta, ["material"])(bg, params={"theta": theta}, normals=nrm),
                               on, **EXACT)


def test_mask_confines_object_effects():
    x = _images(2, 3, 48, 48)
    mask = torch.zeros(2, 1, 48, 48)
    mask[:, :, 12:36, 12:36] = 1.0
    aug = CaptureEffects(_fitted(3, channels=3), ["object_noise", "material"], generator=0)
    out = aug(x, coverage=mask)
    outside = (mask == 0).expand_as(x)
    torch.testing.assert_close(out[outside], x[outside], **EXACT)
    assert (out - x)[~outside].abs().mean() > 1e-2
    # boundary blur acts on the mask's edge only
    theta = CaptureParams({"sigma_s": 1.5}, channels=3)
    bb = CaptureEffects(theta, ["boundary_blur"])(x, params={"theta": theta[[0, 0]]}, coverage=mask.bool())
    assert (bb - x)[..., 20:28, 20:28].abs().max() < 1e-5  # inside
    assert (bb - x)[..., 0:4, 0:4].abs().max() < 1e-5  # outside
    assert (bb - x)[..., 11:13, 14:34].abs().mean() > 1e-2  # on the edge


# ------------------------------------------------------------------ draws
def test_same_generator_seed_same_output_and_global_rng():
    x = _images(4, 1)
    a = CaptureEffects(_fitted(), generator=11)(x)
    b = CaptureEffects(_fitted(), generator=11)(x)
    c = CaptureEffects(_fitted(), generator=12)(x)
    torch.testing.assert_close(a, b, **EXACT)
    assert not torch.equal(a, c)
    aug = CaptureEffects(_fitted(), generator=torch.Generator().manual_seed(5))
    d1 = aug.make_params(x.shape, generator=torch.Generator().manual_seed(3))
    d2 = aug.make_params(x.shape, generator=3)
    torch.testing.assert_close(aug(x, params=d1), aug(x, params=d2), **EXACT)
    torch.testing.assert_close(aug(x, d1), aug(x, params=d1), **EXACT)  # kornia's positional forward(input, params)
    glob = CaptureEffects(_fitted())  # generator=None: torch's global generator
    torch.manual_seed(0)
    g1 = glob(x)
    torch.manual_seed(0)
    torch.testing.assert_close(glob(x), g1, **EXACT)


def test_same_on_batch_shares_theta_and_fields():
    x = _images(1, 3).expand(6, -1, -1, -1).contiguous()
    shared = CaptureEffects(_fitted(8, channels=3), same_on_batch=True, generator=0)
    draw = shared.make_params(x.shape)
    assert len(set(draw["row"].tolist())) == 1 and len(set(draw["apply"].tolist())) == 1
    out = shared(x, params=draw)
    for k in range(1, 6):
        torch.testing.assert_close(out[k], out[0], **EXACT)
    assert not torch.equal(out[0], x[0])
    apart = CaptureEffects(_fitted(8, channels=3), generator=0)(x)
    assert not torch.equal(apart[0], apart[1])


def test_uniform_sampling_is_capture_density_uniform():
    density = pytest.importorskip("synthaug.data.density")
    fitted = _fitted(7, channels=3)
    aug = CaptureEffects(fitted, sampling="uniform", generator=21)
    draw = aug.make_params((5, 3, 8, 8))
    g = torch.Generator().manual_seed(21)
    torch.rand(5, generator=g, dtype=torch.float64)  # the p gate comes first
    dens = density.CaptureDensity(fitted, kind="uniform")
    ref = dens.to_params(dens.sample(5, generator=g))
    torch.testing.assert_close(draw["theta"].to_vector(), ref.to_vector(), **EXACT)
    assert (draw["row"] == -1).all()
    with pytest.raises(ValueError, match="synthaug.data"):
        CaptureEffects(fitted, sampling="kde")


def test_params_none_samples_default_ranges_for_any_channels():
    for c in (1, 3):
        aug = CaptureEffects(None, generator=0)
        draw = aug.make_params((64, c, 8, 8))
        s = draw["theta"].sigma_n
        assert s.shape == (64, c) and 0 <= float(s.min()) and float(s.max()) <= 0.08
        assert aug(_images(64, c, 8, 8), params=draw).shape == (64, c, 8, 8)


def test_p_zero_returns_the_input():
    x = _images(3, 1)
    out = CaptureEffects(_fitted(), p=0.0, generator=0)(x)
    torch.testing.assert_close(out, x, **EXACT)
    assert out is not x


# ------------------------------------------------------------------ inputs
def test_dtypes_and_tensor_types():
    tv_tensors = pytest.importorskip("torchvision.tv_tensors")
    x = _images(2, 3)
    aug = CaptureEffects(_fitted(channels=3), generator=0)
    draw = aug.make_params(x.shape)
    ref = aug(x, params=draw)
    u8 = (x * 255).round().to(torch.uint8)
    out8 = aug(u8, params=draw)
    assert out8.dtype == torch.uint8
    torch.testing.assert_close(out8, (aug(u8.float() / 255, params=draw) * 255).round().to(torch.uint8), **EXACT)
    out64 = aug(x.double(), params=draw)
    assert out64.dtype == torch.float64
    torch.testing.assert_close(out64.float(), ref, rtol=0, atol=1e-5)
    assert aug(x.half(), params=draw).dtype == torch.float16
    img = aug(tv_tensors.Image(x), params=draw)
    assert type(img) is tv_tensors.Image
    torch.testing.assert_close(img.as_subclass(torch.Tensor), ref, **EXACT)
    one = aug(tv_tensors.Image(x[0]), params={"theta": draw["theta"][0], "fields": {k: v[:1] for k, v in
                                                                                   draw["fields"].items()}})
    assert type(one) is tv_tensors.Image and one.shape == x[0].shape
    torch.testing.assert_close(one.as_subclass(torch.Tensor), ref[0], **EXACT)
    with pytest.raises(ValueError, match="dtype"):
        aug(torch.zeros(2, 3, 8, 8, dtype=torch.int32))
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        aug(x * 2 - 0.5)


def test_gradient_flows_to_the_images():
    x = _images(2, 1).requires_grad_(True)
    CaptureEffects(_fitted(), p=0.5, generator=1)(x).sum().backward()
    assert x.grad is not None and torch.isfinite(x.grad).all()


def test_fit_file_path(tmp_path):
    fitted = _fitted(4, channels=3)
    fitted.save(tmp_path / "fit.json")
    x = _images(3, 3)
    a = CaptureEffects(tmp_path / "fit.json", generator=2)(x)
    b = CaptureEffects(fitted, generator=2)(x)
    torch.testing.assert_close(a, b, **EXACT)


def test_clear_errors(tmp_path):
    gray = _fitted(3, channels=1)
    with pytest.raises(ValueError, match=r"images: .*3 channel\(s\) but params were fitted for 1"):
        CaptureEffects(gray)(_images(2, 3))
    with pytest.raises(ValueError, match="images.*1 or 3 channels"):
        CaptureEffects(None)(_images(2, 2))
    with pytest.raises(ValueError, match="params: capture-parameter file not found"):
        CaptureEffects(tmp_path / "missing.json")
    with pytest.raises(FileNotFoundError):
        CaptureEffects(str(tmp_path / "missing.json"))
    assert issubclass(ParamsFileNotFoundError, ValueError)
    (tmp_path / "bad.json").write_text("{}")
    with pytest.raises(ValueError, match="params: .*not a synthaug capture-parameter file"):
        CaptureEffects(tmp_path / "bad.json")
    with pytest.raises(ValueError, match="effects: unknown effect"):
        CaptureEffects(gray, ["motion_blur", "warp_drive"])
    with pytest.raises(ValueError, match="effects: params hold no parameters"):
        CaptureEffects(gray, ["defocus"])
    with pytest.raises(ValueError, match="^p must"):
        CaptureEffects(gray, p=1.5)
    with pytest.raises(ValueError, match="images must be"):
        CaptureEffects(gray)(torch.zeros(8, 8))
    with pytest.raises(ValueError, match="coverage must have shape"):
        CaptureEffects(gray)(_images(2, 1), coverage=torch.ones(3, 1, 24, 28))
    with pytest.raises(ValueError, match="rows but the batch"):
        CaptureEffects(gray)(_images(2, 1), params={"theta": gray})


# ---------------------------------------------------------------- pipelines
def test_inside_torchvision_v2_compose_boxes_pass_through():
    pytest.importorskip("torchvision")
    from torchvision import tv_tensors
    from torchvision.transforms import v2

    img = tv_tensors.Image(_images(1, 3, 32, 40)[0])
    boxes = tv_tensors.BoundingBoxes(torch.tensor([[2.0, 3.0, 12.0, 20.0], [20.0, 5.0, 38.0, 30.0]]),
                                     format="XYXY", canvas_size=(32, 40))
    target = {"boxes": boxes, "labels": torch.tensor([1, 2])}
    pipe = v2.Compose([v2.RandomHorizontalFlip(p=1), CaptureEffects(_fitted(channels=3), generator=4)])
    out_img, out_t = pipe(img, target)
    flip_img, flip_t = v2.RandomHorizontalFlip(p=1)(img, target)
    assert type(out_img) is tv_tensors.Image and type(out_t["boxes"]) is tv_tensors.BoundingBoxes
    torch.testing.assert_close(out_t["boxes"], flip_t["boxes"], **EXACT)
    assert out_t["boxes"].canvas_size == (32, 40) and out_t["boxes"].format == flip_t["boxes"].format
    torch.testing.assert_close(out_t["labels"], target["labels"], **EXACT)
    ref = CaptureEffects(_fitted(channels=3), generator=4)(flip_img)
    torch.testing.assert_close(out_img, ref, **EXACT)
    assert not torch.equal(out_img, flip_img)
    # the v2 face on its own, and PIL images
    v2_aug = CaptureEffects(_fitted(channels=3), generator=4).as_v2()
    assert isinstance(v2_aug, v2.Transform)
    torch.testing.assert_close(v2_aug(flip_img, flip_t)[0], ref, **EXACT)
    # a dataset item's target (its "theta" is a tensor, not a draw) passes through untouched
    item_t = {"labels": torch.tensor(1), "theta": torch.zeros(11)}
    out_pair = CaptureEffects(_fitted(channels=3), generator=4)(flip_img, item_t)
    assert out_pair[1].keys() == item_t.keys() and all(out_pair[1][k] is v for k, v in item_t.items())
    torch.testing.assert_close(out_pair[0], ref, **EXACT)
    pil = v2.functional.to_pil_image((flip_img * 255).round().to(torch.uint8))
    assert CaptureEffects(_fitted(channels=3), generator=4)(pil).size == pil.size


def test_inside_kornia_augmentation_sequential():
    K = pytest.importorskip("kornia.augmentation")
    x = _images(2, 3, 32, 40)
    boxes = torch.tensor([[[2.0, 3.0, 12.0, 20.0]], [[20.0, 5.0, 38.0, 30.0]]])
    mask = torch.zeros(2, 1, 32, 40)
    mask[:, :, 5:15, 8:30] = 1
    keys = ["input", "bbox_xyxy", "mask"]
    seq = K.AugmentationSequential(K.RandomHorizontalFlip(p=1.0), CaptureEffects(_fitted(channels=3), generator=9),
                                   data_keys=keys)
    out, out_boxes, out_mask = seq(x, boxes, mask)
    _, flip_boxes, flip_mask = K.AugmentationSequential(K.RandomHorizontalFlip(p=1.0), data_keys=keys)(x, boxes, mask)
    torch.testing.assert_close(out_boxes, flip_boxes, **EXACT)
    torch.testing.assert_close(out_mask, flip_mask, **EXACT)
    torch.testing.assert_close(out, CaptureEffects(_fitted(channels=3), generator=9)(x.flip(-1)), **EXACT)


@pytest.mark.skipif(not torch.cuda.is_available(), reason="needs a CUDA device")
def test_cuda_matches_cpu():
    x = _images(3, 3, 32, 32)
    aug = CaptureEffects(_fitted(channels=3), generator=0)
    draw = aug.make_params(x.shape)
    torch.testing.assert_close(aug(x.cuda(), params=draw).cpu(), aug(x, params=draw), rtol=1e-4, atol=1e-4)
