"""SyntheticObjectDataset's per-item parameters: ``make_params`` -> frozen :class:`ItemParams` -> ``render``.

The bytes of every mode are pinned to the values recorded before the draw became public (see
``RECORDED``); ``render(make_params(i))`` replays ``ds[i]``; pose samplers are pluggable objects.
"""

import dataclasses
import json
import math

import numpy as np
import pytest
import scipy.stats
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
        return SyntheticObjectDataset("quadcopter", patches, render=cache, seed=3, **kw)

    def frame(**kw):
        kw.setdefault("length", 8)
        return SyntheticObjectDataset("quadcopter", frames, render=cache, mode="frame", object_size=(18, 34),
                                      seed=4, **kw)

    geo = {"origin": torch.tensor([[10.0, 20.0], [0.0, 0.0], [50.0, 5.0], [7.0, 90.0]]),
           "frame_size": torch.tensor([[320.0, 240.0]] * 4), "frame_scale": torch.tensor([1.0, 0.5, 2.0, 1.0])}
    return {
        "patch": patch(),
        "patch_fit": patch(params=fit),
        "patch_kde": patch(params=fit, capture_sampling="kde"),
        "patch_uniform": patch(params=fit, capture_sampling="uniform"),
        "patch_fitted_pose": patch(params=fit, pose_sampling=FittedPose(fit, jitter_deg=15.0)),
        "patch_kde_fitted_pose": patch(params=fit, capture_sampling="kde", pose_sampling="fitted"),
        "patch_ranges": patch(pose_sampling=UniformPose({"beta": (-0.2, 0.3), "t_x": (-0.1, 0.1)}),
                              negative_fraction=0.25),
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


def _fingerprint(items):
    """The images' sum and sum of squares and the targets' sum (NaN as 0), float64: equal bytes give equal sums,
    and unlike a hash of the bytes they survive last-bit differences between CPUs (vectorised float kernels)."""
    img = sum(float(im.double().sum()) for im, _ in items)
    sq = sum(float((im.double() ** 2).sum()) for im, _ in items)
    tgt = sum(float(torch.nan_to_num(torch.as_tensor(t[k]).double()).sum()) for _, t in items for k in sorted(t))
    return [round(img, 6), round(sq, 6), round(tgt, 6)]


def _indices(ds):
    """Single items, a batch in a jumbled order and items of epoch 2."""
    n = len(ds)
    return [[0], [n - 1], [5, 1, 3, n - 2], [(2, 1), (2, 4)]]


def fingerprints(cache):
    """Name -> fingerprints of :func:`_indices` (what ``RECORDED`` holds)."""
    return {name: [_fingerprint(ds.__getitems__(ix)) for ix in _indices(ds)] for name, ds in _configs(cache).items()}


# Recorded from the code before make_params / render (commit 937bf8a, a worktree first on PYTHONPATH) with
#   OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl python -c "import json, sys; sys.path.insert(0, 'tests'); \
#     from test_dataset_params import fingerprints; from synthaug.render.cache import ViewCache; \
#     print(json.dumps(fingerprints(ViewCache.build('quadcopter', step_deg=30, sprite_size=48))))"
# (on this machine the items' bytes were also equal: their sha256 matched before and after the change)
RECORDED: dict[str, list[list[float]]] = {
    "patch": [[863.274533, 477.109523, 3.899896], [1075.216037, 737.007174, 10.930462], [4119.547612, 2790.729663, 31.149151], [1772.858109, 1036.030853, 6.924641]],
    "patch_fit": [[863.274533, 477.109523, 8.226909], [1095.830216, 761.194548, 12.949315], [4152.494144, 2830.182756, 44.011493], [1776.093784, 1042.673856, 12.815929]],
    "patch_kde": [[863.274533, 477.109523, 5.502067], [1082.618215, 745.352005, 12.852547], [4216.049965, 2885.917955, 44.709266], [1840.15428, 1098.401261, 16.064365]],
    "patch_uniform": [[863.274533, 477.109523, 7.207878], [1076.916452, 738.01253, 12.542332], [4101.693534, 2769.784287, 42.584366], [1818.228757, 1076.389222, 14.429932]],
    "patch_fitted_pose": [[863.274533, 477.109523, 4.804827], [1098.697646, 765.095604, 9.324187], [4211.751115, 2885.381136, 34.016296], [1800.886443, 1063.971188, 16.399821]],
    "patch_kde_fitted_pose": [[863.274533, 477.109523, 7.940024], [1015.824504, 670.994691, 10.675165], [4194.26002, 2857.765708, 43.837742], [1826.275699, 1084.368019, 26.375272]],
    "patch_ranges": [[856.07752, 469.529318, 5.93396], [1084.043765, 747.645119, 11.981459], [3979.891151, 2621.737977, 28.370304], [1768.688897, 1034.689143, 8.633773]],
    "patch_rgb": [[2589.8236, 1431.32857, 15.288666], [3241.32028, 2229.183911, 15.466594], [12429.269791, 8434.515204, 62.205258], [5354.485723, 3135.644543, 22.831404]],
    "patch_geometry_extended": [[863.274533, 477.109523, 5.320481], [1097.920053, 764.290272, 13.551038], [4152.66832, 2825.323726, 40.778532], [1777.710673, 1046.838733, 11.770588]],
    "patch_real_transforms": [[807.790964, 545.307851, 0.0], [785.141895, 393.491707, 6.400807], [3579.361669, 2327.982105, 17.298392], [1601.289627, 964.505593, -1.495797]],
    "frame": [[15997.593411, 13652.537404, 329.006324], [12120.473111, 7845.182809, 255.976409], [53258.79579, 38443.54615, 1345.495601], [32282.685644, 27720.097422, 503.649095]],
    "frame_negatives": [[16236.204098, 13978.019431, 6.006324], [12131.902326, 7857.065818, 6.976409], [53277.779785, 38487.209645, 579.495601], [32282.685644, 27720.097422, 503.649095]],
    "frame_fit_kde_fitted_pose": [[16044.264552, 13713.632784, 326.539341], [12052.066411, 7782.448721, 256.019686], [53099.112477, 38240.939713, 1324.118066], [32397.04166, 27849.557629, 494.181036]],
    "frame_uniform": [[16114.749991, 13788.281206, 328.922144], [12063.46377, 7789.784412, 255.145368], [53151.295745, 38320.879654, 1343.999989], [32393.014101, 27844.87174, 504.629759]],
    "frame_real_transforms": [[3423.412107, 2377.040679, 155.915657], [3277.514014, 2155.72924, 150.618788], [13994.982989, 9945.60803, 497.452], [7623.46951, 5916.946727, 93.560156]]
}


@pytest.fixture(scope="module")
def configs(small_cache):
    return _configs(small_cache)


def test_items_equal_the_ones_recorded_before_make_params(small_cache):
    """Every mode gives the items of the code before make_params / render (same draws, same order)."""
    got = fingerprints(small_cache)
    assert set(got) == set(RECORDED)
    for name, rows in RECORDED.items():
        for row, ref in zip(got[name], rows):
            assert row == pytest.approx(ref, rel=1e-6, abs=1e-4), name


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
    ds = SyntheticObjectDataset("quadcopter", bgs, render=small_cache, length=10, pose_sampling=sampler)
    assert ds.pose_sampler is sampler and isinstance(sampler, PoseSampler)
    for i in range(len(ds)):
        _, t = ds[i]
        s = int(t["seed_index"])
        assert t["theta"][:5].tolist() == pytest.approx([0.1 * s, 0.2, -0.3, 0.05, -0.05], abs=1e-6)
    assert len(sampler.calls) == 10 and all(n == 5 for _, n in sampler.calls)
    # the built-in samplers are such objects: passing them gives the strings' bytes
    fit = CaptureParams.sample(4, generator=torch.Generator().manual_seed(9))
    by_name = SyntheticObjectDataset("quadcopter", bgs, fit, render=small_cache, length=6, pose_sampling="fitted")
    by_object = SyntheticObjectDataset("quadcopter", bgs, fit, render=small_cache, length=6,
                                       pose_sampling=FittedPose(fit, jitter_deg=20.0))
    uniform = SyntheticObjectDataset("quadcopter", bgs, fit, render=small_cache, length=6)
    by_uniform = SyntheticObjectDataset("quadcopter", bgs, fit, render=small_cache, length=6,
                                        pose_sampling=UniformPose())
    for i in range(6):
        _same_item(by_name[i], by_object[i])
        _same_item(uniform[i], by_uniform[i])
    # FittedPose without jitter: the seed's fitted rotation itself
    p = FittedPose(fit, jitter_deg=0.0).sample(torch.Generator(), 2, [0.5] * 5)
    assert [p[n] for n in ("alpha", "beta", "gamma")] == pytest.approx(
        [float(getattr(fit, n)[2]) for n in ("alpha", "beta", "gamma")], abs=1e-6)


def test_bad_pose_sampling_is_refused_with_a_clear_message(small_cache):
    bgs = sky_backgrounds(2, (64, 72), seed=1)

    def make(**kw):
        return SyntheticObjectDataset("quadcopter", bgs, render=small_cache, length=4, **kw)

    with pytest.raises(ValueError, match=r"pose_sampling must be one of 'uniform', 'fitted', 'uniform_at_seed', "
                                         r"'fitted_at_seed' or a pose sampler.*'kde'"):
        make(pose_sampling="kde")
    with pytest.raises(ValueError, match=r"pose_sampling must be .* got int"):
        make(pose_sampling=3)
    with pytest.raises(ValueError, match=r"pose_sampling must be .* got object"):
        make(pose_sampling=object())
    with pytest.raises(ValueError, match="give params"):
        make(pose_sampling="fitted")
    with pytest.raises(ValueError, match="jitter_deg"):
        FittedPose(np.zeros((2, 3)), jitter_deg=math.nan)
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        FittedPose(np.zeros((2, 2)))


def test_former_constructor_arguments_still_work_for_one_release(small_cache, tmp_path):
    """``cache`` / ``cache_options`` (now ``render``) and ``pose_ranges`` / ``pose_jitter_deg`` (now a pose
    sampler object): each still accepted, with a FutureWarning naming the new spelling, and the same bytes."""
    bgs = sky_backgrounds(3, (64, 72), seed=1)
    fit = CaptureParams.sample(3, generator=torch.Generator().manual_seed(9))
    fit_file = tmp_path / "fit.json"
    fit.save(fit_file)

    def make(**kw):
        return SyntheticObjectDataset("quadcopter", bgs, length=6, seed=2, **kw)

    ranges = {"beta": (0.0, 0.1), "t_x": (-0.03, 0.05)}
    pairs = [
        ({"cache": small_cache}, {"render": small_cache}, "render=<the ViewCache>"),
        ({"params": fit, "render": small_cache, "pose_ranges": ranges},
         {"params": fit, "render": small_cache, "pose_sampling": UniformPose(ranges)}, "UniformPose"),
        ({"params": fit, "render": small_cache, "pose_sampling": "fitted", "pose_jitter_deg": 7.0},
         {"params": fit, "render": small_cache, "pose_sampling": FittedPose(fit, 7.0)}, "FittedPose"),
        # the fit as a file: FittedPose reads it as the dataset does
        ({"params": fit_file, "render": small_cache, "pose_sampling": "fitted", "pose_jitter_deg": 3.0,
          "pose_ranges": ranges},
         {"params": fit_file, "render": small_cache, "pose_sampling": FittedPose(fit_file, 3.0, ranges)}, "FittedPose"),
    ]
    for old, new, hint in pairs:
        with pytest.warns(FutureWarning, match=hint):
            before = make(**old)
        after = make(**new)
        for i in range(6):
            _same_item(before[i], after[i])
    # the ranges really changed the poses (the pair above is not vacuous)
    plain = make(params=fit, render=small_cache)
    assert not all(torch.equal(plain[i][1]["theta"], make(params=fit, render=small_cache,
                                                           pose_sampling=UniformPose(ranges))[i][1]["theta"])
                   for i in range(6))
    with pytest.warns(FutureWarning), pytest.raises(ValueError, match="leave render at 'cache'"):
        make(render="exact", cache_options={"step_deg": 30})
    with pytest.warns(FutureWarning), pytest.raises(ValueError, match="pose_ranges is for"):
        make(render=small_cache, pose_sampling=FixedPose(), pose_ranges={"beta": (0.0, 0.1)})
    with pytest.warns(FutureWarning), pytest.raises(ValueError, match="pose_jitter_deg"):
        make(params=fit, render=small_cache, pose_sampling="fitted", pose_jitter_deg=-1.0)
    with pytest.raises(TypeError, match="unexpected keyword.*'cache_size'"):
        make(render=small_cache, cache_size=3)
    with pytest.raises(ValueError, match="render must be 'cache', 'exact'"):
        make(render="gl")
    with pytest.raises(ValueError, match="render must be .* got int"):
        make(render=3)


def _object_boxes(ds, n):
    """Longest side and centre of each item's object, read off the image: with the material alone, a black object
    (w_d = 0) over a constant 0.8 background, the coverage is exactly ``1 - image / 0.8``; its box at 0.5 in numpy."""
    sides, centres = [], []
    for i in range(n):
        cov = 1.0 - ds[i][0][0].numpy() / 0.8
        ys, xs = np.nonzero(cov >= 0.5)
        sides.append(max(ys.max() - ys.min() + 1, xs.max() - xs.min() + 1))
        centres.append(((xs.max() + xs.min() + 1) / 2, (ys.max() + ys.min() + 1) / 2))
    return np.array(sides), np.array(centres)


def test_object_box_frames_every_object_as_ingest_frames_a_labelled_seed(small_cache):
    """object_box: whatever the drawn pose and translation, the object's box is centred in the patch and its longest
    side is the fraction of the patch (as ``crop_patch`` frames a labelled real object); the paper's framing varies."""
    n = 3
    fit = CaptureParams.default(n)
    fit = fit.replace(w_d=torch.zeros(fit.w_d.shape))
    bgs = [np.full((64, 72), 0.8, np.float32) for _ in range(n)]

    def make(box):
        return SyntheticObjectDataset("quadcopter", bgs, fit, render=small_cache, length=40, negative_fraction=0.0,
                                      effects=["material"], object_box=box, seed=1)

    sides, centres = _object_boxes(make(0.6), 40)
    assert np.all(np.abs(sides - 24) <= 1), sides  # 0.6 x 40 px, to the pixel the first look measures
    assert np.all(np.abs(centres - 20.0) <= 1.0), centres
    paper_sides, paper_centres = _object_boxes(make(None), 40)
    assert paper_sides.max() - paper_sides.min() >= 8 and np.abs(paper_centres - 20.0).max() > 2  # not framed
    # the item is still a pure function of (seed, epoch, index), and its theta records the framing translation
    ds = make(0.6)
    a, b = ds[5], ds[5]
    assert torch.equal(a[0], b[0]) and torch.equal(a[1]["theta"], b[1]["theta"])
    assert ds.make_params(5).pose["t_x"] != pytest.approx(float(a[1]["theta"][3]))


def test_object_box_share_frames_a_drawn_share_of_the_objects_and_leaves_the_rest_as_the_paper_draws_them(small_cache):
    """object_box_share: the items drawn as framed are exactly the object_box dataset's items, the others exactly the
    paper's (same seed, same draws: the share is drawn last), their count binomial around the share; at 1 nothing
    moves; a batch renders what the items render one by one."""
    n = 3
    fit = CaptureParams.default(n)
    fit = fit.replace(w_d=torch.zeros(fit.w_d.shape))
    bgs = [np.full((64, 72), 0.8, np.float32) for _ in range(n)]

    def make(box, **kw):
        return SyntheticObjectDataset("quadcopter", bgs, fit, render=small_cache, length=60, negative_fraction=0.0,
                                      effects=["material"], object_box=box, seed=4, **kw)

    mixed, framed, paper = make(0.6, object_box_share=0.3), make(0.6), make(None)
    flags = np.array([mixed.make_params(i).framed for i in range(60)])
    assert not any(not framed.make_params(i).framed for i in range(60))  # a share of 1 draws nothing
    assert scipy.stats.binomtest(int(flags.sum()), 60, 0.3).pvalue > 1e-3 and 0 < flags.sum() < 60
    for i in range(60):
        ref = framed if flags[i] else paper
        assert torch.equal(mixed[i][0], ref[i][0]), i
    batch = mixed.__getitems__(list(range(12)))
    assert all(torch.equal(img, mixed[i][0]) for i, (img, _) in enumerate(batch))
    with_one = make(0.6, object_box_share=1.0)
    assert all(torch.equal(with_one[i][0], framed[i][0]) for i in range(5))
    sides, _ = _object_boxes(mixed, 60)
    # framed: 0.6 x 40 px to a pixel or two (as the test above; a thin part can cross 0.5); the rest vary
    assert np.abs(sides[flags] - 24).max() <= 2 and np.abs(sides[~flags] - 24).max() > 3
    with pytest.raises(ValueError, match="give an object_box"):
        make(None, object_box_share=0.5)
    for bad in (0.0, 1.2, -0.1, True, "half"):
        with pytest.raises(ValueError, match="object_box_share must be a fraction in"):
            make(0.6, object_box_share=bad)


def test_bad_object_box_is_refused_with_a_clear_message(small_cache):
    bgs = sky_backgrounds(2, (64, 72), seed=1)

    def make(**kw):
        return SyntheticObjectDataset("quadcopter", bgs, render=small_cache, length=4, **kw)

    for bad in (0.0, 1.5, -0.2, math.nan, True, "tight"):
        with pytest.raises(ValueError, match="object_box must be a fraction in"):
            make(object_box=bad)
    with pytest.raises(ValueError, match="give a seed set as backgrounds"):
        make(object_box="seed")  # plain images carry no object_fraction
    with pytest.raises(ValueError, match="object_box frames patch-mode objects"):
        make(object_box=0.7, mode="frame")


def test_object_box_fit_frames_objects_at_the_size_of_the_fitted_renders(small_cache, tmp_path):
    """object_box="fit": the median over seeds of the fitted render's box (coverage >= 0.5 at the fitted pose and
    scale, measured here in numpy on the cache's own layers) as a fraction of the patch, and every item framed at it."""
    n = 3
    fit = CaptureParams.default(n)
    fit = fit.replace(w_d=torch.zeros(fit.w_d.shape), alpha=torch.tensor([0.3, 1.2, 2.5]),
                      beta=torch.tensor([0.6, 0.9, 1.3]), t_x=torch.tensor([0.05, -0.05, 0.0]))
    path = tmp_path / "fit.json"
    scales = [0.45, 0.55, 0.65]
    fit.save(path, extra=[{"object_scale": s} for s in scales])
    cov, _ = small_cache.layers(fit.alpha, fit.beta, fit.gamma, fit.t_x, fit.t_y, size=40,
                                object_scale=torch.tensor(scales))
    sides = []
    for c in cov[:, 0].numpy():
        ys, xs = np.nonzero(c >= 0.5)
        sides.append(max(ys.max() - ys.min() + 1, xs.max() - xs.min() + 1))
    bgs = [np.full((64, 72), 0.8, np.float32) for _ in range(n)]
    ds = SyntheticObjectDataset("quadcopter", bgs, str(path), render=small_cache, length=30, negative_fraction=0.0,
                                effects=["material"], object_box="fit", seed=2)
    assert ds.object_box == pytest.approx(np.median(sides) / 40)
    got, centres = _object_boxes(ds, 30)
    # to the pixel mostly; a thin part crossing the 0.5 level once rescaled moves a box by up to 3 px (48-px sprites)
    assert np.median(np.abs(got - np.median(sides))) <= 1 and np.abs(got - np.median(sides)).max() <= 3
    assert np.all(np.abs(centres - 20.0) <= 1.5)
    with pytest.raises(ValueError, match="give params from a fit with per-seed scales"):
        SyntheticObjectDataset("quadcopter", bgs, fit, render=small_cache, length=4, object_box="fit")


def test_background_sampling_other_puts_each_object_on_another_seeds_background(small_cache):
    """``background_sampling="other"``: each synthetic item's background is another seed's (never its own), drawn
    uniformly over the others (chi-square against scipy), and that background is the one rendered (negatives are
    the bare background patch, so the pixels say whose it is); every other draw is the paper's own ("seed")."""
    from scipy import stats

    n = 4
    bgs = [np.full((48, 48), 0.1 + 0.2 * i, np.float32) for i in range(n)]  # seed i's background: level 0.1 + 0.2 i
    fit = CaptureParams.sample(n, generator=torch.Generator().manual_seed(3))

    def make(**kw):
        return SyntheticObjectDataset("quadcopter", bgs, fit, render=small_cache, length=600, patch_size=40, seed=5,
                                      **kw)

    own, other = make(), make(background_sampling="other")
    pairs = np.array([(p.seed_index, p.background) for p in (other.make_params(i) for i in range(600))])
    assert np.all(pairs[:, 0] != pairs[:, 1]) and pairs[:, 1].min() >= 0 and pairs[:, 1].max() < n
    for s in range(n):  # given the seed, its background is uniform over the three others
        counts = np.bincount(pairs[pairs[:, 0] == s, 1], minlength=n)
        assert counts[s] == 0 and stats.chisquare(np.delete(counts, s)).pvalue > 1e-3, counts
    for i in range(40):  # the background is the only draw it adds: seed, pose, crop, capture and fields as "seed"
        a, b = own.make_params(i), other.make_params(i)
        assert a.background_index is None and a.background == a.seed_index
        assert dataclasses.replace(b, background_index=None) == a
    negatives = [i for i in range(60) if other.make_params(i).negative]
    assert len(negatives) >= 10
    for i in negatives:  # a negative is the background patch itself: the other seed's level, not its own
        p = other.make_params(i)
        np.testing.assert_allclose(other[i][0].numpy(), 0.1 + 0.2 * p.background, atol=1e-6)
        np.testing.assert_allclose(own[i][0].numpy(), 0.1 + 0.2 * p.seed_index, atol=1e-6)
    positives = [i for i in range(60) if not other.make_params(i).negative][:8]
    for i in positives:  # a positive keeps its seed's capture row (theta) over the other background
        img, target = other[i]
        p = other.make_params(i)
        assert int(target["seed_index"]) == p.seed_index
        torch.testing.assert_close(target["theta"], own[i][1]["theta"])
        corner = float(img[0, 0, 0])
        assert corner == pytest.approx(0.1 + 0.2 * p.background, abs=0.02)  # the patch's corner is background
    # a replayed item is the same bytes, and a changed background renders that change alone
    p = other.make_params(positives[0])
    assert torch.equal(other.render(p)[0], other[positives[0]][0])
    with pytest.raises(ValueError, match="background_index 9 out of range"):
        other.render(dataclasses.replace(p, background_index=9))


def test_bad_background_sampling_is_refused_with_a_clear_message(small_cache):
    bgs = sky_backgrounds(2, (64, 72), seed=1)
    with pytest.raises(ValueError, match="background_sampling must be one of"):
        SyntheticObjectDataset("quadcopter", bgs, render=small_cache, length=4, background_sampling="random")
    with pytest.raises(ValueError, match="at least 2 backgrounds"):
        SyntheticObjectDataset("quadcopter", bgs[:1], render=small_cache, length=4, background_sampling="other")
