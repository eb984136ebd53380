"""The seed-set format: patch geometry against references, write/load round trip, errors."""

from __future__ import annotations

import errno
import json
import os
import threading

import cv2
import numpy as np
import pytest

from synthaug.data import seedset
from synthaug.data.seedset import SeedSet, crop_geometry, crop_patch, replace_dir, write_seedset


def _smooth(h=120, w=160, seed=0):
    rng = np.random.default_rng(seed)
    img = cv2.GaussianBlur(rng.random((h, w)).astype(np.float32), (0, 0), 6)
    return cv2.normalize(img, None, 0, 255, cv2.NORM_MINMAX).astype(np.uint8)


def test_crop_at_scale_one_is_a_slice():
    img = _smooth()
    # box 28x14 at (50, 40): side = 28 / 0.7 = 40 = P, centre (64, 47) -> patch = img[27:67, 44:84]
    patch, crop = crop_patch(img, box=(50, 40, 28, 14), patch_size=40, object_fraction=0.7)
    assert crop.tolist() == [64.0, 47.0, 40.0]
    assert np.array_equal(patch, img[27:67, 44:84])


def test_crop_downscale_matches_area_resize():
    img = _smooth()
    # side 80 around centre (80, 60), P = 40: half resolution of img[20:100, 40:120]
    patch, _ = crop_patch(img, crop=(80, 60, 80), patch_size=40)
    ref = cv2.resize(img[20:100, 40:120], (40, 40), interpolation=cv2.INTER_AREA)
    assert np.abs(patch.astype(int) - ref).mean() < 1.0


def test_crop_upscale_matches_skimage():
    from skimage.transform import resize

    img = _smooth()
    patch, _ = crop_patch(img, crop=(80, 60, 20), patch_size=40)
    ref = resize(img[50:70, 70:90].astype(float), (40, 40), order=1, mode="edge", anti_aliasing=False,
                 preserve_range=True)
    assert np.abs(patch.astype(float) - ref).mean() < 0.6 and np.abs(patch.astype(float) - ref).max() <= 3


def test_object_is_centred_and_scaled():
    img = np.zeros((200, 200), np.uint8)
    img[90:110, 60:140] = 255  # an 80 x 20 bar centred at (100, 100)
    patch, _ = crop_patch(img, box=(60, 90, 80, 20), patch_size=40, object_fraction=0.5)
    cols = np.nonzero(patch[20] > 127)[0]
    rows = np.nonzero(patch[:, 20] > 127)[0]
    assert cols.min() == 10 and cols.max() == 29  # longest side spans 0.5 * 40 = 20 px, centred
    assert abs(len(rows) - 5) <= 1  # 20 px * (40 / 160)
    w = patch.astype(float)
    yy, xx = np.mgrid[0:40, 0:40]
    # the object's centre of mass is the patch centre (19.5, 19.5 in pixel-centre coordinates)
    assert abs((w * xx).sum() / w.sum() - 19.5) < 0.05 and abs((w * yy).sum() / w.sum() - 19.5) < 0.05


@pytest.mark.parametrize("crop", [(20.3, 14.8, 11.0), (20.3, 14.8, 37.0)])  # up- and downscaling
def test_crop_of_an_rgb_frame_is_the_crop_of_each_channel(crop):
    rgb = np.random.default_rng(3).integers(0, 255, (30, 40, 3), dtype=np.uint8)
    patch, _ = crop_patch(rgb, crop=crop, patch_size=16)
    ref = np.stack([crop_patch(np.ascontiguousarray(rgb[..., c]), crop=crop, patch_size=16)[0] for c in range(3)], -1)
    assert patch.shape == (16, 16, 3) and np.array_equal(patch, ref)
    with pytest.raises(ValueError, match="RGB"):
        crop_patch(rgb[..., :2], crop=crop)


def test_crop_geometry_errors():
    with pytest.raises(ValueError, match="positive size"):
        crop_geometry((0, 0, 0, 5))
    with pytest.raises(ValueError, match="object_fraction"):
        crop_geometry((0, 0, 5, 5), object_fraction=1.5)
    with pytest.raises(ValueError, match="exactly one"):
        crop_patch(np.zeros((8, 8), np.uint8))


def _write(path, n=3, m=2, p=16):
    rng = np.random.default_rng(0)
    frames = [rng.integers(0, 255, (30, 40), dtype=np.uint8) for _ in range(n)]
    bgs = [rng.integers(0, 255, (30, 40), dtype=np.uint8) for _ in range(n)]
    write_seedset(path, patches=rng.integers(0, 255, (n, p, p), dtype=np.uint8),
                  backgrounds=rng.integers(0, 255, (n, p, p), dtype=np.uint8),
                  boxes=[[i, i, 5, 6] for i in range(n)], centres=[[i + 2.5, i + 3] for i in range(n)],
                  crops=[[i + 2.5, i + 3, 8.6] for i in range(n)],
                  records=[{"video": f"v{i % 2}", "frame": i, "class": "drone", "background_method": "median",
                            "background_quality": 0.5, "split": "train"} for i in range(n)],
                  frames=frames, background_frames=bgs,
                  negatives=rng.integers(0, 255, (m, p, p), dtype=np.uint8),
                  negative_records=[{"kind": "background"} for _ in range(m)],
                  metadata={"patch_size": p, "object_fraction": 0.7, "source": "test"})
    return frames, bgs


def test_round_trip_contract(tmp_path):
    frames, bgs = _write(tmp_path / "s")
    s = SeedSet.load(tmp_path / "s")
    assert len(s) == 3
    assert s.patches.dtype == np.uint8 and s.patches.shape == (3, 16, 16)
    assert s.backgrounds.dtype == np.uint8 and s.backgrounds.shape == (3, 16, 16)
    assert s.boxes.dtype == np.float32 and s.boxes.shape == (3, 4)
    assert s.centres.dtype == np.float32 and s.centres.shape == (3, 2)
    assert s.negatives.shape == (2, 16, 16)
    assert s.metadata["format"] == "synthaug.seedset" and s.metadata["version"] == 1
    assert s.metadata["patch_size"] == 16 and s.object_fraction == 0.7 and s.metadata["source"] == "test"
    for i in range(3):
        assert np.array_equal(s.frame(i), frames[i])
        assert np.array_equal(s.background_frame(i), bgs[i])
        for key in ("video", "frame", "class", "background_method", "background_quality", "split"):
            assert key in s.records[i]
    assert not [p for p in os.listdir(tmp_path) if p.startswith(".")]  # no temporary left


def test_subset_and_replace(tmp_path):
    _write(tmp_path / "s")
    s = SeedSet.load(tmp_path / "s")
    s.save_subset(tmp_path / "sub", [2, 0], negatives=[1])
    sub = SeedSet.load(tmp_path / "sub")
    assert len(sub) == 2 and np.array_equal(sub.patches, s.patches[[2, 0]])
    assert np.array_equal(sub.frame(0), s.frame(2)) and np.array_equal(sub.negatives, s.negatives[[1]])
    # writing over an existing seed set replaces it whole
    s.save_subset(tmp_path / "sub", [1], negatives=False)
    again = SeedSet.load(tmp_path / "sub")
    assert len(again) == 1 and len(again.negatives) == 0
    assert not [p for p in os.listdir(tmp_path) if p.startswith(".")]


def test_load_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="not a seed set"):
        SeedSet.load(tmp_path)
    _write(tmp_path / "s")
    head = tmp_path / "s" / "seedset.json"
    doc = json.loads(head.read_text())
    head.write_text(json.dumps({**doc, "version": 99}))
    with pytest.raises(ValueError, match="unsupported version 99"):
        SeedSet.load(tmp_path / "s")
    head.write_text(json.dumps({**doc, "format": "other"}))
    with pytest.raises(ValueError, match="not a synthaug seed set"):
        SeedSet.load(tmp_path / "s")


def test_write_errors(tmp_path):
    with pytest.raises(ValueError, match="one entry per record"):
        write_seedset(tmp_path / "x", patches=np.zeros((2, 8, 8), np.uint8), backgrounds=np.zeros((2, 8, 8), np.uint8),
                      boxes=np.zeros((2, 4)), centres=np.zeros((2, 2)), crops=np.zeros((2, 3)), records=[{}],
                      frames=[], background_frames=[], metadata={"patch_size": 8, "object_fraction": 0.7})
    with pytest.raises(ValueError, match="patch_size and object_fraction"):
        write_seedset(tmp_path / "x", patches=(), backgrounds=(), boxes=(), centres=(), crops=(), records=[],
                      frames=[], background_frames=[], metadata={})
    assert not (tmp_path / "x").exists()


def test_replace_dir_by_two_writers_keeps_one_whole_folder(tmp_path):
    # two writers replacing one folder at once (the runner's jobs re-ingesting one seed, stop 81)
    final = tmp_path / "set"
    final.mkdir()
    (final / "v").write_text("old")
    tmps = []
    for i in range(8):
        t = tmp_path / f".set.tmp-{i}"
        t.mkdir()
        (t / "v").write_text(str(i))
        tmps.append(t)
    errors = []

    def swap(t):
        try:
            replace_dir(t, final)
        except BaseException as e:  # noqa: BLE001 - reported by the assertion below
            errors.append(e)

    threads = [threading.Thread(target=swap, args=(t,)) for t in tmps]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == [] and (final / "v").read_text() in {str(i) for i in range(8)}
    assert [p.name for p in tmp_path.iterdir()] == ["set"]  # no temporary or old folder left
    # a move that fails for another reason puts the former folder back and raises
    keep = (final / "v").read_text()
    bad = tmp_path / ".set.tmp-bad"
    bad.mkdir()
    real_replace = os.replace

    def denied(a, b):
        if os.fspath(a) == os.fspath(bad):
            raise PermissionError(errno.EACCES, "denied")
        real_replace(a, b)

    with pytest.MonkeyPatch.context() as m:
        m.setattr(seedset.os, "replace", denied)
        with pytest.raises(PermissionError):
            replace_dir(bad, final)
    assert (final / "v").read_text() == keep and sorted(p.name for p in tmp_path.iterdir()) == [".set.tmp-bad", "set"]


def test_interrupted_write_leaves_nothing(tmp_path, monkeypatch):
    _write(tmp_path / "s")
    before = SeedSet.load(tmp_path / "s").patches.copy()

    def boom(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(np, "savez", boom)
    with pytest.raises(KeyboardInterrupt):
        _write(tmp_path / "s")
    # the old seed set is intact and no temporary folder is left
    assert np.array_equal(SeedSet.load(tmp_path / "s").patches, before)
    assert not [p for p in os.listdir(tmp_path) if p.startswith(".")]


@pytest.mark.parametrize("frame_scale", [0.6, 1.0, 1.6, 2.5])
def test_crop_resampling_sigma_matches_the_measured_blur_of_crop_patch(frame_scale):
    """A Gaussian blob of known σ, cut at random sub-pixel places: its second moment in the patch is
    (σ / frame_scale)² plus the predicted resampling variance (averaged over phases)."""
    from synthaug.data.seedset import crop_patch, crop_resampling_sigma

    rng = np.random.default_rng(0)
    sb, p = 2.0, 40
    yy, xx = np.mgrid[0:130, 0:130]
    var = []
    for _ in range(40):
        cx, cy = rng.uniform(60, 70, 2)
        img = np.exp(-((xx - cx) ** 2 + (yy - cy) ** 2) / (2 * sb ** 2)).astype(np.float32)
        patch, _ = crop_patch(img, crop=[cx + rng.uniform(-1, 1), cy + rng.uniform(-1, 1), p * frame_scale],
                              patch_size=p)
        w = patch.astype(np.float64).sum(0)
        x = np.arange(p)
        mu = (w * x).sum() / w.sum()
        var.append((w * (x - mu) ** 2).sum() / w.sum())
    blob = (sb / frame_scale) ** 2
    extra = float(crop_resampling_sigma(frame_scale)) ** 2
    assert np.mean(var) - blob == pytest.approx(extra, rel=0.1)
    with pytest.raises(ValueError, match="positive"):
        crop_resampling_sigma([1.0, 0.0])


def test_rgb_patches_bad_input(tmp_path):
    _write(tmp_path / "s")
    s = SeedSet.load(tmp_path / "s")
    assert s.colour() is None
    good = np.zeros((3, 16, 16, 3), np.uint8)
    args = dict(patches=s.patches, backgrounds=s.backgrounds, boxes=s.boxes, centres=s.centres, crops=s.crops,
                records=s.records, frames=[s.frame_path(i) for i in range(3)],
                background_frames=[s.background_frame_path(i) for i in range(3)],
                metadata={"patch_size": 16, "object_fraction": 0.7})
    with pytest.raises(ValueError, match="both patches_rgb and backgrounds_rgb"):
        write_seedset(tmp_path / "a", patches_rgb=good, **args)
    with pytest.raises(ValueError, match=r"patches_rgb must be uint8 \(3, 16, 16, 3\)"):
        write_seedset(tmp_path / "b", patches_rgb=good[:2], backgrounds_rgb=good, **args)
    write_seedset(tmp_path / "c", patches_rgb=good, backgrounds_rgb=good, **args)
    np.savez(tmp_path / "c" / "colour.npz", patches_rgb=good[:1], backgrounds_rgb=good[:1])  # a stale file
    with pytest.raises(ValueError, match="expected RGB patches"):
        SeedSet.load(tmp_path / "c").colour()
