"""SyntheticObjectDataset in the torchvision ecosystem: tv_tensors targets through transforms v2,
one item format for real and synthetic items, and epochs carried by the sampler."""

import numpy as np
import pytest
import torch
from torch.utils.data import DataLoader, Dataset, DistributedSampler
from torchvision import tv_tensors
from torchvision.transforms import v2

from synthaug.data.procedural import sky_backgrounds
from synthaug.data.synthetic import EpochSampler, SyntheticObjectDataset, collate_detection


@pytest.fixture(scope="module")
def frames():
    return sky_backgrounds(3, (120, 160), seed=3)


def frame_ds(frames, small_cache, **kw):
    kw.setdefault("length", 24)
    kw.setdefault("effects", ["material"])  # no blur: the object's changed pixels are the rendered ones
    return SyntheticObjectDataset("quadcopter", frames, render=small_cache, mode="frame", object_size=(18, 34),
                                  negative_fraction=0.0, **kw)


class WithObjectMask:
    """Test transform: marks the object's rendered pixels (frame != its background) as a
    ``tv_tensors.Mask`` *before* the user's v2 pipeline, which moves mask, image and boxes together."""

    def __init__(self, backgrounds, pipeline):
        self.backgrounds = backgrounds
        self.pipeline = pipeline

    def __call__(self, image, target):
        bg = torch.from_numpy(self.backgrounds[int(target["seed_index"])]).float() / 255
        mask = tv_tensors.Mask(((image[0] - bg).abs() > 0.06).to(torch.uint8)[None])
        # thin parts with coverage < 0.5 (1-px rotor arms) may lie outside the coverage >= 0.5 box already
        before = outside_fraction(mask, target["boxes"])
        return self.pipeline(image, dict(target, object_mask=mask, outside_before=before))


def outside_fraction(mask, boxes, margin=2.0):
    """Share of the mask's pixels (pixel centres) outside every box grown by ``margin`` px."""
    ys, xs = torch.nonzero(mask.reshape(mask.shape[-2:]) > 0, as_tuple=True)
    if len(xs) == 0:
        return float("nan")
    cx, cy = xs.float() + 0.5, ys.float() + 0.5
    inside = torch.zeros_like(cx, dtype=torch.bool)
    for x0, y0, x1, y1 in boxes.tolist():
        inside |= (cx >= x0 - margin) & (cx <= x1 + margin) & (cy >= y0 - margin) & (cy <= y1 + margin)
    return 1.0 - inside.float().mean().item()


def test_frame_items_are_tv_tensors(frames, small_cache):
    img, t = frame_ds(frames, small_cache)[0]
    assert isinstance(img, tv_tensors.Image) and img.shape == (1, 120, 160)
    assert isinstance(t["boxes"], tv_tensors.BoundingBoxes)
    assert t["boxes"].format == tv_tensors.BoundingBoxFormat.XYXY and tuple(t["boxes"].canvas_size) == (120, 160)
    assert t["boxes"].dtype == torch.float32 and t["labels"].dtype == torch.int64


@pytest.mark.parametrize("pipeline", [
    v2.Compose([v2.RandomHorizontalFlip(p=1.0)]),
    v2.Compose([v2.RandomHorizontalFlip(p=0.5), v2.RandomVerticalFlip(p=0.5),
                v2.RandomResizedCrop((96, 128), scale=(0.5, 1.0), antialias=True),
                v2.ColorJitter(brightness=0.3, contrast=0.3), v2.SanitizeBoundingBoxes()]),
    v2.Compose([v2.RandomIoUCrop(min_scale=0.5), v2.Resize((120, 160), antialias=True), v2.SanitizeBoundingBoxes()]),
    v2.Compose([v2.RandomZoomOut(fill=0.5, side_range=(1.0, 2.0)), v2.RandomAffine(degrees=0, translate=(0.2, 0.2)),
                v2.SanitizeBoundingBoxes()]),
], ids=["hflip", "flip-resizedcrop-jitter-sanitize", "ioucrop", "zoomout-affine"])
def test_v2_pipeline_keeps_the_object_in_its_box(frames, small_cache, pipeline):
    ds = frame_ds(frames, small_cache, transforms=WithObjectMask(frames, pipeline))
    kept = 0
    for i in range(len(ds)):
        img, t = ds[i]
        assert isinstance(t["boxes"], tv_tensors.BoundingBoxes)
        assert tuple(t["boxes"].canvas_size) == tuple(img.shape[-2:])
        assert len(t["labels"]) == len(t["boxes"])
        if len(t["boxes"]) == 0 or t["object_mask"].sum() < 30:
            continue  # cropped away (SanitizeBoundingBoxes dropped the box) or too little of it left
        kept += 1
        assert t["outside_before"] < 0.06, i
        assert outside_fraction(t["object_mask"], t["boxes"]) < t["outside_before"] + 0.03, i
    assert kept >= len(ds) // 2


def test_plain_tensor_boxes_would_not_follow_the_flip(frames, small_cache):
    """Control: the check above fails when boxes are plain tensors (what items were before)."""
    def strip(image, target):
        target = dict(target, boxes=target["boxes"].as_subclass(torch.Tensor))
        return image, target

    flip = WithObjectMask(frames, v2.RandomHorizontalFlip(p=1.0))
    ds = frame_ds(frames, small_cache, transforms=lambda im, t: flip(*strip(im, t)), length=12)
    outside = [outside_fraction(t["object_mask"], t["boxes"]) for _, t in (ds[i] for i in range(12))]
    assert np.median(outside) > 0.5  # objects near the vertical midline stay in place: the median, not all


def test_transforms_are_reproducible_per_item(frames, small_cache):
    pipe = v2.Compose([v2.RandomResizedCrop((64, 64), antialias=True), v2.SanitizeBoundingBoxes()])
    a = frame_ds(frames, small_cache, transforms=pipe, seed=2)
    b = frame_ds(frames, small_cache, transforms=pipe, seed=2)
    torch.manual_seed(123)  # the global generator's state does not matter
    x = a[5]
    torch.manual_seed(7)
    y = b.__getitems__([1, 5])[1]
    assert torch.equal(x[0], y[0]) and torch.equal(x[1]["boxes"], y[1]["boxes"])
    assert not torch.equal(a[5][0], a[6][0])


class UserFrames(Dataset):
    """A user's detection dataset: uint8 (H, W, 3) numpy frames and a target with a list of boxes."""

    def __init__(self, frames):
        self.frames = frames

    def __len__(self):
        return len(self.frames)

    def __getitem__(self, i):
        rgb = np.dstack([self.frames[i]] * 3)
        return rgb, {"boxes": [[10.0, 20.0, 40.0, 44.0]], "labels": [1]}


def test_real_and_synthetic_frames_have_one_format_and_both_get_transforms(frames, small_cache):
    ds = frame_ds(frames, small_cache, length=None, real=UserFrames(frames), synthetic_per_real=2,
                  transforms=v2.RandomHorizontalFlip(p=1.0))
    images, targets = next(iter(DataLoader(ds, batch_size=len(ds), collate_fn=collate_detection)))
    assert len(images) == 9 and sum(bool(t["synthetic"]) for t in targets) == 6
    for img, t in zip(images, targets):
        assert isinstance(img, tv_tensors.Image) and img.dtype == torch.float32 and img.shape == (1, 120, 160)
        assert isinstance(t["boxes"], tv_tensors.BoundingBoxes) and t["labels"].dtype == torch.int64
    real_img, real_t = images[0], targets[0]
    torch.testing.assert_close(real_t["boxes"], torch.tensor([[120.0, 20.0, 150.0, 44.0]]))  # flipped: 160 - x
    gray = torch.from_numpy(frames[0]).float() / 255  # (0.299 + 0.587 + 0.114) * v = v
    torch.testing.assert_close(real_img[0], gray.flip(-1), atol=1e-5, rtol=0)


def test_a_users_uint8_patches_collate_with_synthetic_ones(small_cache):
    """The obvious ``real=[(patch, 1) ...]`` with uint8 numpy patches: converted, not passed through."""
    bgs = sky_backgrounds(3, (48, 48), seed=0)
    patches = [np.asarray(b[:40, :40]) for b in bgs]
    ds = SyntheticObjectDataset("quadcopter", bgs, render=small_cache, real=[(p, 1) for p in patches],
                                synthetic_per_real=3)
    images, targets = next(iter(DataLoader(ds, batch_size=len(ds))))
    assert images.shape == (12, 1, 40, 40) and images.dtype == torch.float32
    torch.testing.assert_close(images[1, 0], torch.from_numpy(patches[1]).float() / 255)
    assert targets["labels"].dtype == torch.int64 and targets["labels"][:3].tolist() == [1, 1, 1]
    with pytest.raises(ValueError, match=r"real\[0\]: image is 30x30 but patch_size is 40"):
        SyntheticObjectDataset("quadcopter", bgs, render=small_cache, real=[(np.zeros((30, 30), np.uint8), 1)],
                               synthetic_per_real=1)[0]


def test_epoch_sampler_reaches_persistent_workers(small_cache):
    bgs = sky_backgrounds(2, (48, 48), seed=1)
    ds = SyntheticObjectDataset("quadcopter", bgs, render=small_cache, length=8, negative_fraction=0.0)
    reference = {e: torch.stack([ds.__getitems__([(e, i)])[0][0] for i in range(8)]) for e in (0, 1)}
    assert not torch.equal(reference[0], reference[1])
    with pytest.raises(IndexError, match=r"an \(epoch, index\) pair"):
        ds.__getitems__([(1, 2, 3)])

    sampler = EpochSampler(ds)
    loader = DataLoader(ds, batch_size=4, sampler=sampler, num_workers=2, persistent_workers=True)
    seen = {}
    for epoch in (0, 1):
        sampler.set_epoch(epoch)
        seen[epoch] = torch.cat([x for x, _ in loader])
    for e in (0, 1):
        assert torch.equal(seen[e], reference[e])

    # control: set_epoch on the dataset does not reach persistent workers (why the sampler exists)
    plain = DataLoader(ds, batch_size=4, num_workers=2, persistent_workers=True)
    first = torch.cat([x for x, _ in plain])
    ds.set_epoch(1)
    assert torch.equal(torch.cat([x for x, _ in plain]), first)


def test_epoch_sampler_wraps_a_distributed_sampler():
    inner = DistributedSampler(range(10), num_replicas=2, rank=1, shuffle=True, seed=3)
    s = EpochSampler(inner)
    s.set_epoch(4)
    ref = DistributedSampler(range(10), num_replicas=2, rank=1, shuffle=True, seed=3)
    ref.set_epoch(4)
    assert list(s) == [(4, i) for i in ref] and len(s) == len(ref) == 5
    own = EpochSampler(10, shuffle=True, seed=0)
    orders = []
    for e in (0, 1, 0):
        own.set_epoch(e)
        orders.append([i for _, i in own])
    assert sorted(orders[0]) == list(range(10)) and orders[0] == orders[2] != orders[1]
    with pytest.raises(ValueError, match="shuffle=True is for EpochSampler's own sampling"):
        EpochSampler(inner, shuffle=True)
