"""SyntheticObjectDataset's per-item parameters: ``make_params`` -> frozen :class:`ItemParams` -> ``render``.

The bytes of every mode are pinned to the values recorded before the draw became public (see
``RECORDED``); ``render(make_params(i))`` replays ``ds[i]``; pose samplers are pluggable objects.
"""

import dataclasses
import hashlib
import json
import math

import numpy as np
import pytest
import torch
from torch.utils.data import Dataset
from torchvision.transforms import v2

from synthaug.data.procedural import sky_backgrounds
from synthaug.data.poses import FittedPose, PoseSampler, UniformPose
from synthaug.data.synthetic import ItemParams, SyntheticObjectDataset
from synthaug.effects.registry import PAPER_EFFECTS
from synthaug.params import POSE_NAMES, CaptureParams


class RealPatches(Dataset):
    def __init__(self, n=4, size=40):
        self.x = torch.rand(n, 1, size, size, generator=torch.Generator().manual_seed(123))

    def __len__(self):
        return len(self.x)

    def __getitem__(self, i):
        return self.x[i], 1


class RealFrames(Dataset):
    def __init__(self, frames):
        self.frames = frames

    def __len__(self):
        return len(self.frames)

    def __getitem__(self, i):
        return self.frames[i], {"boxes": [[10.0, 20.0, 40.0, 44.0]], "labels": [1]}


def _noise(image, target):
    """A transform with torch draws (the dataset seeds them per item)."""
    return (image + 0.01 * torch.rand(image.shape)).clamp(0, 1), target


def _configs(cache):
    """Name -> dataset: every mode the dataset has (patch/frame, capture and pose sampling, real, transforms)."""
    patches = sky_backgrounds(4, (64, 72), seed=1)
    frames = sky_backgrounds(3, (120, 160), seed=3)
    fit = CaptureParams.sample(4, generator=torch.Generator().manual_seed(9))
    fit3 = CaptureParams.sample(3, generator=torch.Generator().manual_seed(4))
    rgb = CaptureParams.sample(4, generator=torch.Generator().manual_seed(2), channels=3)
    extended = CaptureParams.sample(4, generator=torch.Generator().manual_seed(5),
                                    effects=[*PAPER_EFFECTS, "vignetting", "shot_noise"])

    def patch(**kw):
        kw.setdefault("length", 12)
        return SyntheticObjectDataset("quadcopter", patches, cache=cache, seed=3, **kw)

    def frame(**kw):
        kw.setdefault("length", 8)
        return SyntheticObjectDataset("quadcopter", frames, cache=cache, mode="frame", object_size=(18, 34),
                                      seed=4, **kw)

    geo = {"origin": torch.tensor([[10.0, 20.0], [0.0, 0.0], [50.0, 5.0], [7.0, 90.0]]),
           "frame_size": torch.tensor([[320.0, 240.0]] * 4), "frame_scale": torch.tensor([1.0, 0.5, 2.0, 1.0])}
    return {
        "patch": patch(),
        "patch_fit": patch(params=fit),
        "patch_kde": patch(params=fit, capture_sampling="kde"),
        "patch_uniform": patch(params=fit, capture_sampling="uniform"),
        "patch_fitted_pose": patch(params=fit, pose_sampling="fitted", pose_jitter_deg=15.0),
        "patch_kde_fitted_pose": patch(params=fit, capture_sampling="kde", pose_sampling="fitted"),
        "patch_ranges": patch(pose_ranges={"beta": (-0.2, 0.3), "t_x": (-0.1, 0.1)}, negative_fraction=0.25),
        "patch_rgb": patch(params=rgb, channels=3),
        "patch_geometry_extended": patch(params=extended, seed_geometry=geo),
        "patch_real_transforms": patch(length=None, real=RealPatches(), synthetic_per_real=2.5, transforms=_noise),
        "frame": frame(),
        "frame_negatives": frame(negative_fraction=0.4),
        "frame_fit_kde_fitted_pose": frame(params=fit3, capture_sampling="kde", pose_sampling="fitted"),
        "frame_uniform": frame(params=fit3, capture_sampling="uniform"),
        "frame_real_transforms": frame(length=None, real=RealFrames(frames), synthetic_per_real=2,
                                       transforms=v2.Compose([v2.RandomHorizontalFlip(), v2.RandomIoUCrop(),
                                                              v2.Resize((64, 80)), v2.SanitizeBoundingBoxes()])),
    }


def _digest(items):
    """sha256 over every item's image and target tensors (and the boxes' canvas sizes)."""
    h = hashlib.sha256()
    for image, target in items:
        h.update(image.numpy().tobytes())
        for k in sorted(target):
            v = target[k]
            h.update(k.encode())
            h.update(torch.as_tensor(v).numpy().tobytes())
            if hasattr(v, "canvas_size"):
                h.update(repr(tuple(v.canvas_size)).encode())
    return h.hexdigest()[:16]


def _indices(ds):
    """Single items, a batch in a jumbled order and items of epoch 2."""
    n = len(ds)
    return [[0], [n - 1], [5, 1, 3, n - 2], [(2, 1), (2, 4)]]


def digests(cache):
    """Name -> digests of :func:`_indices` (what ``RECORDED`` holds)."""
    return {name: [_digest(ds.__getitems__(ix)) for ix in _indices(ds)] for name, ds in _configs(cache).items()}


# Recorded from the code before make_params / render (commit 937bf8a) with
#   OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl python -c "import json, sys; sys.path.insert(0, 'tests'); \
#     from test_dataset_params import digests; from synthaug.render.cache import ViewCache; \
#     print(json.dumps(digests(ViewCache.build('quadcopter', step_deg=30, sprite_size=48)), indent=1))"
RECORDED: dict[str, list[str]] = {
    "patch": ["96026e4fa482605e", "ab60daa1b896c8da", "49a83fce67cbd7ce", "9fa42a45b923a856"],
    "patch_fit": ["b4c58baae28f8e22", "a8a54445bc36ce89", "2aa0bf9af0013b1d", "a362d7badb0f3183"],
    "patch_kde": ["269947f7099f40cb", "0a37198767f69b2e", "170991758e720d00", "2f72c2013d9c43f1"],
    "patch_uniform": ["8781d93ceab3d43c", "65ce96afd4e5a351", "a836cfaefbd76a1f", "e11283dccf649ceb"],
    "patch_fitted_pose": ["7d38682e5dc2abe4", "3c51065adcdca3ae", "d6de2db53a51003a", "e473cdeb7d3565ff"],
    "patch_kde_fitted_pose": ["22b90669c2c7f7b4", "f72454c649739d0a", "619b48ea09c791d4", "481d19c6b2c79a2d"],
    "patch_ranges": ["e42a54cd0f91ab6c", "5b38bf8bd647cf3f", "3251fa18ad62c650", "947e6b0893cb2492"],
    "patch_rgb": ["60aa733befe365df", "d044eee0b897dfa6", "40ba75a56c29d784", "52b53174967c2a88"],
    "patch_geometry_extended": ["5221134cb6ae532e", "955f56172bd20dc2", "e7d7d71d45cd597d", "c69a51d32fec61b1"],
    "patch_real_transforms": ["91a5d252068e21b0", "40134679d8d5b988", "ecb99f194d5a32c8", "8124ec34537e586d"],
    "frame": ["363ce66e0480e834", "02c8186bb4aa6d85", "afeb2f83c37864f7", "71174c3ae89dad38"],
    "frame_negatives": ["d63fd9402bf5ffc7", "d122681d50a75fa0", "5d3d484f0a340e3c", "71174c3ae89dad38"],
    "frame_fit_kde_fitted_pose": ["d98c5c9c637c3f03", "b7fdf468bda86734", "ab0ada032744430c", "412661319e292ef0"],
    "frame_uniform": ["299e32b4af09684d", "70462a2b2f08565f", "f82027ef23b82ddf", "41d44a506a20d5b3"],
    "frame_real_transforms": ["1a5a7b5cab7c3455", "de9235cd806914a9", "27a40daa89a27446", "b32a7b4f460a4743"],
}


@pytest.fixture(scope="module")
def configs(small_cache):
    return _configs(small_cache)


def test_bytes_equal_the_ones_recorded_before_make_params(small_cache):
    """Every mode gives the bytes of the code before make_params / render (same draws, same order)."""
    assert digests(small_cache) == RECORDED


def _same_item(a, b):
    assert type(a[0]) is type(b[0]) and torch.equal(a[0], b[0])
    assert sorted(a[1]) == sorted(b[1])
    for k in a[1]:
        x, y = torch.as_tensor(a[1][k]), torch.as_tensor(b[1][k])
        assert x.shape == y.shape and x.numpy().tobytes() == y.numpy().tobytes(), k  # bytes: NaN == NaN


@pytest.mark.parametrize("name", ["patch_real_transforms", "patch_kde_fitted_pose", "frame_real_transforms",
                                  "frame_fit_kde_fitted_pose"])
def test_render_of_make_params_replays_the_item(configs, name):
    ds = configs[name]
    n = len(ds)
    for i in (0, 1, n - 1):
        p = ds.make_params(i)
        assert p == ds.make_params(i) and p != ds.make_params(i, epoch=1)  # deterministic, new per epoch
        _same_item(ds.render(p), ds[i])
        _same_item(ds.render(ds.make_params(i, epoch=2)), ds.__getitems__([(2, i)])[0])
    assert ds.make_params(-1) == ds.make_params(n - 1)
    batch = [ds.make_params(i) for i in (3, 0, n - 2)]
    for got, want in zip(ds.render(batch), ds.__getitems__([3, 0, n - 2])):
        _same_item(got, want)
    with pytest.raises(IndexError, match="out of range"):
        ds.make_params(n)


def test_params_are_frozen_serialisable_and_render_what_they_say(configs):
    ds = configs["patch_kde_fitted_pose"]
    p = next(q for q in map(ds.make_params, range(len(ds))) if not q.negative)
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.seed_index = 0
    assert p.real is False and 0 <= p.seed_index < 4 and p.object_px is None and len(p.capture) > 0
    assert sorted(p.pose) == ["alpha", "beta", "gamma", "t_x", "t_y"]
    assert set(p.fields) == {"noise"} and p.fields["noise"].shape == (1, 1, 40, 40)
    plain = {k: v for k, v in dataclasses.asdict(p).items() if k != "fields"}
    back = json.loads(json.dumps(plain))
    assert back["pose"] == p.pose and tuple(back["crop_xy"]) == p.crop_xy and tuple(back["capture"]) == p.capture
    assert ItemParams(**{**back, "crop_xy": tuple(back["crop_xy"]), "capture": tuple(back["capture"]),
                         "fields": p.fields}) == p
    # the target's theta starts with the params' pose; another pose renders another item, the same background
    image, target = ds.render(p)
    assert target["seed_index"].item() == p.seed_index
    assert target["theta"][:5].tolist() == pytest.approx([p.pose[n] for n in POSE_NAMES], abs=1e-6)
    turned = dataclasses.replace(p, pose={**p.pose, "gamma": p.pose["gamma"] + 1.0})
    assert not torch.equal(ds.render(turned)[0], image)
    bare = ds.render(dataclasses.replace(p, negative=True))[0]
    x, y = p.crop_xy
    assert torch.equal(bare, ds.backgrounds[p.seed_index][:, y:y + 40, x:x + 40])
    real = configs["patch_real_transforms"].make_params(1)
    assert real.real and real.seed_index == -1 and real.pose == {} and real.fields == {}
    json.dumps(dataclasses.asdict(real))
    with pytest.raises(TypeError, match="ItemParams"):
        ds.render([{"index": 0}])
    with pytest.raises(ValueError, match="seed_index"):
        ds.render(dataclasses.replace(p, seed_index=9))


class FixedPose:
    """A user's pose sampler: one pose per seed, turned by the seed index; records its calls."""

    def __init__(self):
        self.calls = []

    def sample(self, generator, seed_index, u):
        self.calls.append((seed_index, len(u)))
        return {"alpha": 0.1 * seed_index, "beta": 0.2, "gamma": -0.3, "t_x": 0.05, "t_y": -0.05}


def test_a_pose_sampler_object_is_honoured(small_cache):
    bgs = sky_backgrounds(4, (64, 72), seed=1)
    sampler = FixedPose()
    ds = SyntheticObjectDataset("quadcopter", bgs, cache=small_cache, length=10, pose_sampling=sampler)
    assert ds.pose_sampler is sampler and isinstance(sampler, PoseSampler)
    for i in range(len(ds)):
        _, t = ds[i]
        s = int(t["seed_index"])
        assert t["theta"][:5].tolist() == pytest.approx([0.1 * s, 0.2, -0.3, 0.05, -0.05], abs=1e-6)
    assert len(sampler.calls) == 10 and all(n == 5 for _, n in sampler.calls)
    # the built-in samplers are such objects: passing them gives the strings' bytes
    fit = CaptureParams.sample(4, generator=torch.Generator().manual_seed(9))
    by_name = SyntheticObjectDataset("quadcopter", bgs, fit, cache=small_cache, length=6, pose_sampling="fitted",
                                     pose_jitter_deg=7.0)
    by_object = SyntheticObjectDataset("quadcopter", bgs, fit, cache=small_cache, length=6,
                                       pose_sampling=FittedPose(fit, jitter_deg=7.0))
    by_uniform = SyntheticObjectDataset("quadcopter", bgs, fit, cache=small_cache, length=6,
                                        pose_sampling=UniformPose({"beta": (0.0, 0.1)}))
    ranged = SyntheticObjectDataset("quadcopter", bgs, fit, cache=small_cache, length=6,
                                    pose_ranges={"beta": (0.0, 0.1)})
    for i in range(6):
        _same_item(by_name[i], by_object[i])
        _same_item(by_uniform[i], ranged[i])
    # FittedPose without jitter: the seed's fitted rotation itself
    p = FittedPose(fit, jitter_deg=0.0).sample(torch.Generator(), 2, [0.5] * 5)
    assert [p[n] for n in ("alpha", "beta", "gamma")] == pytest.approx(
        [float(getattr(fit, n)[2]) for n in ("alpha", "beta", "gamma")], abs=1e-6)


def test_bad_pose_sampling_is_refused_with_a_clear_message(small_cache):
    bgs = sky_backgrounds(2, (64, 72), seed=1)

    def make(**kw):
        return SyntheticObjectDataset("quadcopter", bgs, cache=small_cache, length=4, **kw)

    with pytest.raises(ValueError, match=r"pose_sampling must be 'uniform', 'fitted' or a pose sampler.*'kde'"):
        make(pose_sampling="kde")
    with pytest.raises(ValueError, match=r"pose_sampling must be .* got int"):
        make(pose_sampling=3)
    with pytest.raises(ValueError, match=r"pose_sampling must be .* got object"):
        make(pose_sampling=object())
    with pytest.raises(ValueError, match="give params"):
        make(pose_sampling="fitted")
    with pytest.raises(ValueError, match="pose_ranges is for"):
        make(pose_sampling=FixedPose(), pose_ranges={"beta": (0.0, 0.1)})
    with pytest.raises(ValueError, match="pose_jitter_deg"):
        FittedPose(np.zeros((2, 3)), jitter_deg=math.nan)
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        FittedPose(np.zeros((2, 2)))
