"""SyntheticObjectDataset: determinism across workers, mixing, modes, bad inputs, fork safety."""

import json
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import torch
from torch.utils.data import DataLoader, Dataset

from synthaug.data.poses import FittedPose, SeedOffset, UniformPose
from synthaug.data.procedural import sky_backgrounds
from synthaug.data.synthetic import SyntheticObjectDataset, collate_detection
from synthaug.params import CaptureParams


class RealPatches(Dataset):
    def __init__(self, n=6, size=40):
        g = torch.Generator().manual_seed(123)
        self.x = torch.rand(n, 1, size, size, generator=g)

    def __len__(self):
        return len(self.x)

    def __getitem__(self, i):
        return self.x[i], 1


@pytest.fixture(scope="module")
def backgrounds():
    return sky_backgrounds(4, (64, 72), seed=1)


def make(backgrounds, small_cache, **kw):
    kw.setdefault("length", 40)
    return SyntheticObjectDataset("quadcopter", backgrounds, render=small_cache, **kw)


def _bytes(loader):
    out = []
    for images, targets in loader:
        out.append(images.numpy().tobytes())
        out.append(targets["theta"].numpy().tobytes())
        out.append(targets["labels"].numpy().tobytes())
    return out


@pytest.mark.slow
def test_identical_bytes_with_0_1_2_workers(backgrounds, small_cache):
    ds = make(backgrounds, small_cache, length=None, real=RealPatches(), synthetic_per_real=5)
    ds.set_epoch(3)
    runs = [_bytes(DataLoader(ds, batch_size=7, num_workers=w, shuffle=False)) for w in (0, 1, 2)]
    assert runs[0] == runs[1] == runs[2]


def test_item_is_a_pure_function_of_seed_epoch_index(backgrounds, small_cache):
    a = make(backgrounds, small_cache, seed=5)
    b = make(backgrounds, small_cache, seed=5)
    assert torch.equal(a[7][0], b[7][0])
    assert torch.equal(a[7][0], a.__getitems__([3, 7, 1])[1][0])  # batch composition doesn't matter
    c = make(backgrounds, small_cache, seed=6)
    assert not torch.equal(a[7][0], c[7][0])
    before = a[7][0].clone()
    a.set_epoch(1)
    assert not torch.equal(a[7][0], before)
    a.set_epoch(0)
    assert torch.equal(a[7][0], before)


def test_mixing_with_a_users_dataset(backgrounds, small_cache):
    real = RealPatches(n=6)
    ds = make(backgrounds, small_cache, length=None, real=real, synthetic_per_real=2.5)
    assert len(ds) == 6 + 15
    img, target = ds[2]
    assert torch.equal(img, real[2][0]) and target["synthetic"].item() is False and target["labels"].item() == 1
    assert target["seed_index"].item() == -1 and torch.isnan(target["theta"]).all()
    batch = next(iter(DataLoader(ds, batch_size=len(ds))))
    assert batch[0].shape == (21, 1, 40, 40)
    assert batch[1]["synthetic"].sum().item() == 15


def test_patch_items_targets_and_negatives(backgrounds, small_cache):
    ds = make(backgrounds, small_cache, negative_fraction=0.5, length=60)
    labels, seen_neg = [], 0
    for i in range(len(ds)):
        img, t = ds[i]
        assert img.shape == (1, 40, 40) and img.dtype == torch.float32
        assert 0.0 <= img.min() and img.max() <= 1.0
        labels.append(int(t["labels"]))
        # Θ metadata: the seed's capture parameters, the item's own pose
        row = ds.params[int(t["seed_index"])].to_vector()[0]
        torch.testing.assert_close(t["theta"][5:], row[5:])
        if t["labels"] == 0:  # a negative is an untouched crop of the seed's background
            bg = torch.from_numpy(backgrounds[int(t["seed_index"])]).float() / 255
            windows = bg.unfold(0, 40, 1).unfold(1, 40, 1)
            assert (windows - img[0]).abs().amax((-1, -2)).min() < 1e-6
            seen_neg += 1
    assert 15 < seen_neg < 45 and set(labels) == {0, 1}


def test_object_changes_the_patch_and_effects_can_be_ablated(backgrounds, small_cache):
    ds = make(backgrounds, small_cache, negative_fraction=0.0)
    ds_off = make(backgrounds, small_cache, negative_fraction=0.0, effects=["material"])
    img, t = ds[0]
    img_off, _ = ds_off[0]
    s = int(t["seed_index"])
    assert not torch.equal(img, img_off)
    bgs = torch.from_numpy(backgrounds[s]).float() / 255
    windows = bgs.unfold(0, 40, 1).unfold(1, 40, 1)
    assert (windows - img_off[0]).abs().amax((-1, -2)).min() > 0.05  # the object is there


def test_frame_mode_boxes(small_cache):
    frames = sky_backgrounds(2, (120, 160), seed=3)
    ds = SyntheticObjectDataset("quadcopter", frames, render=small_cache, mode="frame", length=12,
                                object_size=(16, 30), effects=["material"])
    loader = DataLoader(ds, batch_size=4, collate_fn=collate_detection)
    images, targets = next(iter(loader))
    for img, t in zip(images, targets):
        assert img.shape == (1, 120, 160)
        assert t["boxes"].dtype == torch.float32 and t["boxes"].shape == (1, 4)
        assert t["labels"].dtype == torch.int64 and t["labels"].tolist() == [1]
        x0, y0, x1, y1 = t["boxes"][0].tolist()
        assert 0 <= x0 < x1 <= 160 and 0 <= y0 < y1 <= 120
        assert 4 <= max(x1 - x0, y1 - y0) <= 31
        bg = torch.from_numpy(frames[int(t["seed_index"])]).float() / 255
        changed = (img[0] - bg).abs() > 0.02
        ys, xs = torch.nonzero(changed, as_tuple=True)
        inside = (xs >= x0 - 1) & (xs < x1 + 1) & (ys >= y0 - 1) & (ys < y1 + 1)
        assert inside.float().mean() > 0.95  # the object lives in its box


def test_rgb_mode(small_cache):
    frames = np.stack([np.dstack([b, b // 2, b // 3]) for b in sky_backgrounds(2, (50, 50), seed=0)])
    ds = SyntheticObjectDataset("quadcopter", frames, render=small_cache, length=4, channels=3)
    img, t = ds[0]
    assert img.shape == (3, 40, 40) and t["theta"].shape == (5 + 6 * 3,)


def test_reads_a_fitted_parameter_file(tmp_path, backgrounds, small_cache):
    theta = CaptureParams({"sigma_s": [0.5, 1.0, 1.5, 2.0], "w_d": [0.1, 0.2, 0.3, 0.4]})
    theta.save(tmp_path / "fit.json")
    ds = make(backgrounds, small_cache, params=tmp_path / "fit.json")
    _, t = ds[0]
    s = int(t["seed_index"])
    assert t["theta"][5].item() == pytest.approx([0.5, 1.0, 1.5, 2.0][s])


def test_bad_inputs(tmp_path, backgrounds, small_cache):
    with pytest.raises(ValueError, match=r"backgrounds\[1\] is 30x30, smaller than the 40x40 patch"):
        make([backgrounds[0], np.zeros((30, 30), np.uint8)], small_cache)
    with pytest.raises(ValueError, match="params has 2 rows but there are 4 backgrounds"):
        make(backgrounds, small_cache, params=CaptureParams.default(2))
    bad = tmp_path / "bad.json"
    CaptureParams.default(4).save(bad)
    doc = json.loads(bad.read_text())
    doc["rows"][1]["theta"]["sigma_s"] = [float("nan")]
    bad.write_text(json.dumps(doc))
    with pytest.raises(ValueError, match="sigma_s .* must be finite, got nan"):
        make(backgrounds, small_cache, params=bad)
    with pytest.raises(ValueError, match="mode must be"):
        make(backgrounds, small_cache, mode="video")
    with pytest.raises(ValueError, match="backgrounds is empty"):
        make([], small_cache)
    with pytest.raises(ValueError, match="length must be given"):
        make(backgrounds, small_cache, length=None)
    with pytest.raises(ValueError, match=r"expected an \(H, W\) or \(H, W, C\) image"):
        make([np.zeros((2, 50, 50, 2))], small_cache)
    with pytest.raises(ValueError, match="effects .* have no parameters"):
        make(backgrounds, small_cache, effects=["material", "vignetting_unknown"])
    with pytest.raises(IndexError, match="out of range"):
        make(backgrounds, small_cache)[40]
    with pytest.raises(FileNotFoundError, match="mesh file not found"):
        SyntheticObjectDataset("/nonexistent/mesh.obj", backgrounds, length=2)


FORK_SCRIPT = textwrap.dedent("""
    import os, sys
    os.environ["PYOPENGL_PLATFORM"] = "egl"
    import numpy as np, torch, trimesh, pyrender
    from torch.utils.data import DataLoader
    # 1. the user's own code renders with pyrender in the main process first
    scene = pyrender.Scene()
    scene.add(pyrender.Mesh.from_trimesh(trimesh.creation.box()))
    scene.add(pyrender.OrthographicCamera(1, 1), pose=np.array([[1,0,0,0],[0,1,0,0],[0,0,1,3],[0,0,0,1.]]))
    r = pyrender.OffscreenRenderer(32, 32)
    r.render(scene)
    from synthaug.data.synthetic import SyntheticObjectDataset
    bgs = np.full((2, 48, 48), 128, np.uint8)
    # 2. our exact renderer also renders in the main process before the fork
    ds = SyntheticObjectDataset("quadcopter", bgs, length=8, render="exact", negative_fraction=0.0)
    first = ds[0][0]
    # 3. forked DataLoader workers render exact samples
    loader = DataLoader(ds, batch_size=4, num_workers=2, multiprocessing_context="fork")
    images = torch.cat([b[0] for b in loader])
    assert torch.equal(images[0], first), "worker result differs from main-process result"
    print("OK", images.shape[0], flush=True)
""")


@pytest.mark.slow
def test_dataloader_workers_render_after_the_main_process_rendered(tmp_path):
    """Forked workers must not deadlock even though the parent holds a GL context."""
    script = tmp_path / "fork_after_render.py"
    script.write_text(FORK_SCRIPT)
    try:
        proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=240)
    except subprocess.TimeoutExpired:
        pytest.fail("DataLoader workers hung after the main process rendered (fork after GL context)")
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "OK 8" in proc.stdout


def test_per_seed_object_scale_from_a_fit_file(tmp_path, small_cache):
    bgs = np.full((2, 40, 40), 200, np.uint8)
    theta = CaptureParams({"w_d": [0.1, 0.1]})
    theta.save(tmp_path / "fit.json", extra=[{"object_scale": 0.25}, {"object_scale": 0.9}])
    ds = SyntheticObjectDataset("quadcopter", bgs, tmp_path / "fit.json", render=small_cache, length=40,
                                negative_fraction=0.0, effects=["material"], pose_sampling=UniformPose({"beta": (1.2, 1.5)}))
    area = {0: [], 1: []}
    for i in range(len(ds)):
        img, t = ds[i]
        area[int(t["seed_index"])].append(float((img < 0.6).float().sum()))
    # areas scale with the square of the object scale: (0.9 / 0.25)^2 ≈ 13
    assert np.median(area[1]) > 6 * np.median(area[0]) > 0
    fixed = SyntheticObjectDataset("quadcopter", bgs, tmp_path / "fit.json", render=small_cache, length=4,
                                   object_scale=0.5)
    assert fixed.seed_scales is None


CROSS_PROCESS_SCRIPT = textwrap.dedent("""
    import hashlib, sys
    import torch
    from torch.utils.data import DataLoader
    from synthaug.data.procedural import sky_backgrounds
    from synthaug.data.synthetic import EpochSampler, SyntheticObjectDataset
    from synthaug.render.cache import ViewCache

    cache = ViewCache.build("quadcopter", step_deg=30, sprite_size=48)
    ds = SyntheticObjectDataset("quadcopter", sky_backgrounds(4, (64, 72), seed=1), cache=cache, length=12, seed=3)
    workers = int(sys.argv[1])
    sampler = EpochSampler(ds)
    loader = DataLoader(ds, batch_size=5, sampler=sampler, num_workers=workers, persistent_workers=workers > 0)
    for epoch in (0, 1):
        sampler.set_epoch(epoch)
        h = hashlib.sha256()
        for images, targets in loader:
            h.update(images.numpy().tobytes()); h.update(targets["theta"].numpy().tobytes())
            h.update(targets["labels"].numpy().tobytes())
        print(epoch, h.hexdigest(), flush=True)
""")


@pytest.mark.slow
def test_identical_bytes_across_processes_and_persistent_workers(tmp_path):
    """Fresh interpreters (other hash seeds), 0 workers and 2 persistent workers over two epochs: same bytes."""
    import os

    script = tmp_path / "cross_process.py"
    script.write_text(CROSS_PROCESS_SCRIPT)
    outs = []
    for hash_seed, workers in (("1", "0"), ("2", "2"), ("3", "1")):
        env = {**os.environ, "PYTHONHASHSEED": hash_seed, "OMP_NUM_THREADS": "1", "PYTHONWARNINGS": "ignore"}
        proc = subprocess.run([sys.executable, str(script), workers], capture_output=True, text=True, timeout=240,
                              env=env)
        assert proc.returncode == 0, proc.stderr[-3000:]
        outs.append(proc.stdout.split())
    assert len(outs[0]) == 4 and outs[0][1] != outs[0][3]  # the epoch reaches the workers: new poses
    assert outs[0] == outs[1] == outs[2]


def test_jittered_pose_is_the_fitted_rotation_turned_in_the_objects_frame():
    """Euler angles of R(α, β, γ)·exp([v]x), against scipy (R = Rz(γ) Ry(β) Rx(α) is scipy's extrinsic 'xyz')."""
    from scipy.spatial.transform import Rotation

    from synthaug.data.poses import jittered_pose

    rng = np.random.default_rng(3)
    for _ in range(50):
        a, b, c = rng.uniform(-np.pi, np.pi), rng.uniform(-1.5, 1.5), rng.uniform(-np.pi, np.pi)
        v = rng.normal(size=3) * 0.4
        ref = Rotation.from_euler("xyz", [a, b, c]) * Rotation.from_rotvec(v)
        got = Rotation.from_euler("xyz", jittered_pose(a, b, c, v))
        assert (ref.inv() * got).magnitude() < 1e-9
        a2, b2, c2 = jittered_pose(a, b, c, v)
        assert -np.pi <= a2 <= np.pi and -np.pi / 2 <= b2 <= np.pi / 2 and -np.pi <= c2 <= np.pi
    assert jittered_pose(0.3, -0.2, 1.0, np.zeros(3)) == pytest.approx((0.3, -0.2, 1.0), abs=1e-12)


def test_at_seed_pose_sampling_places_each_object_at_its_seeds_fitted_offset(backgrounds, small_cache):
    """``"uniform_at_seed"`` / ``"fitted_at_seed"``: the rotations of ``"uniform"`` / ``"fitted"`` (the same draws),
    t_x, t_y each seed's fitted offset; the strings build :class:`SeedOffset` (same bytes); bad uses are refused."""
    fit = CaptureParams.sample(4, generator=torch.Generator().manual_seed(9))
    fit.t_x = torch.tensor([0.08, -0.06, 0.0, 0.12])  # offsets of their own, off the uniform ±0.1 draw's grid
    fit.t_y = torch.tensor([-0.04, 0.1, 0.07, -0.11])
    for rotation in ("uniform", "fitted"):
        plain = make(backgrounds, small_cache, params=fit, pose_sampling=rotation, length=30)
        at = make(backgrounds, small_cache, params=fit, pose_sampling=f"{rotation}_at_seed", length=30)
        inner = UniformPose() if rotation == "uniform" else FittedPose(fit)
        by_object = make(backgrounds, small_cache, params=fit, pose_sampling=SeedOffset(inner, fit), length=30)
        moved = 0
        for i in range(30):
            (img_p, tp), (img_a, ta), (img_o, to) = plain[i], at[i], by_object[i]
            assert int(ta["seed_index"]) == int(tp["seed_index"])
            if int(ta["labels"]) != 1:
                continue
            s = int(ta["seed_index"])
            np.testing.assert_allclose(ta["theta"][:3].numpy(), tp["theta"][:3].numpy(), atol=1e-6)  # rotation kept
            assert ta["theta"][3:5].tolist() == pytest.approx([float(fit.t_x[s]), float(fit.t_y[s])], abs=1e-6)
            assert torch.equal(img_a, img_o) and torch.equal(ta["theta"], to["theta"])
            moved += int(not torch.equal(img_a, img_p))
        assert moved > 10  # the offset moves the rendered object
    # the offsets as an (N, 2) array, and the sampler's draws are the wrapped one's
    g1, g2 = torch.Generator().manual_seed(4), torch.Generator().manual_seed(4)
    a = SeedOffset(FittedPose(fit, 10.0), np.stack([fit.t_x.numpy(), fit.t_y.numpy()], 1)).sample(g1, 3, [0.3] * 5)
    b = FittedPose(fit, 10.0).sample(g2, 3, [0.3] * 5)
    assert [a[n] for n in ("alpha", "beta", "gamma")] == pytest.approx([b[n] for n in ("alpha", "beta", "gamma")])
    assert (a["t_x"], a["t_y"]) == pytest.approx((0.12, -0.11))
    with pytest.raises(ValueError, match="give params"):
        make(backgrounds, small_cache, pose_sampling="uniform_at_seed")
    with pytest.raises(ValueError, match="object_box"):
        make(backgrounds, small_cache, params=fit, pose_sampling="fitted_at_seed", object_box=0.6)
    with pytest.raises(ValueError, match="3 offsets but there are 4 seeds"):
        make(backgrounds, small_cache, params=fit, pose_sampling=SeedOffset(UniformPose(), np.zeros((3, 2))))
    with pytest.raises(ValueError, match="4 offsets but the sampler holds 3 rotations"):
        SeedOffset(FittedPose(np.zeros((3, 3))), fit)
    with pytest.raises(ValueError, match=r"\(N, 2\) array"):
        SeedOffset(UniformPose(), np.zeros((4, 3)))
    with pytest.raises(ValueError, match="must be finite"):
        SeedOffset(UniformPose(), np.full((4, 2), np.nan))
    with pytest.raises(ValueError, match="pose sampler"):
        SeedOffset("uniform", fit)


def test_fitted_pose_sampling_draws_around_each_seeds_fitted_pose(backgrounds, small_cache):
    from scipy.spatial.transform import Rotation

    fit = CaptureParams.sample(4, generator=torch.Generator().manual_seed(9))
    exact = make(backgrounds, small_cache, params=fit, pose_sampling=FittedPose(fit, jitter_deg=0.0), length=40)
    for i in range(len(exact)):
        _, t = exact[i]
        s = int(t["seed_index"])
        # theta = (alpha, beta, gamma, t_x, t_y, capture...): the seed's fitted rotation, exactly
        want = Rotation.from_euler("xyz", [float(getattr(fit, n)[s]) for n in ("alpha", "beta", "gamma")])
        assert (want.inv() * Rotation.from_euler("xyz", t["theta"][:3].double().numpy())).magnitude() < 1e-5
    # with a jitter: the angle to the fitted rotation is |v|, v ~ N(0, s^2 I3): a chi(3) of mean 2 s sqrt(2/pi)
    sigma = 20.0
    ds = make(backgrounds, small_cache, params=fit, pose_sampling=FittedPose(fit, jitter_deg=sigma), length=400)
    angles = []
    for i in range(len(ds)):
        _, t = ds[i]
        if int(t["labels"]) == 1:
            s = int(t["seed_index"])
            want = Rotation.from_euler("xyz", [float(getattr(fit, n)[s]) for n in ("alpha", "beta", "gamma")])
            angles.append((want.inv() * Rotation.from_euler("xyz", t["theta"][:3].double().numpy())).magnitude())
    mean = np.degrees(np.mean(angles))
    assert len(angles) > 100 and mean == pytest.approx(2 * sigma * np.sqrt(2 / np.pi), rel=0.15)
    # the default stays the paper's draw: every item its own rotation, spread over the whole range, whatever the fit
    default = make(backgrounds, small_cache, params=fit, length=40)
    poses = np.array([default[i][1]["theta"][:3].numpy() for i in range(len(default))])
    assert len(np.unique(poses.round(6), axis=0)) == 40 and np.ptp(poses[:, 2]) > 4.0
    assert len(np.unique(np.array([exact[i][1]["theta"][:3].numpy() for i in range(40)]).round(5), axis=0)) <= 4
    with pytest.raises(ValueError, match="give params"):
        make(backgrounds, small_cache, pose_sampling="fitted")
    with pytest.raises(ValueError, match="pose_sampling"):
        make(backgrounds, small_cache, params=fit, pose_sampling="kde")
    with pytest.raises(ValueError, match="jitter_deg"):
        FittedPose(fit, jitter_deg=-1.0)
    with pytest.raises(ValueError, match="4 seeds"):  # one fitted rotation per seed
        make(backgrounds, small_cache, params=fit, pose_sampling=FittedPose(np.zeros((3, 3))))
