"""`synthaug export`: COCO / YOLO files checked against pycocotools, torchvision's box_convert and the dataset."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pytest
import torch
from PIL import Image

from synthaug.cli import build_parser, main
from synthaug.data.export import export_dataset, seedset_real_frames
from synthaug.data.procedural import sky_backgrounds
from synthaug.data.seedset import SeedSet, crop_patch, write_seedset
from synthaug.data.synthetic import SyntheticObjectDataset
from synthaug.params import CaptureParams

FRAME = (96, 128)  # (H, W) of the seed frames
OBJECT_SIZE = (10.0, 20.0)  # object crop 40 px: fits the frames
# the view cache conftest's small_cache builds (same disk entry, built once per session)
FAST = ["--object-size", "10", "20", "--step-deg", "30", "--sprite-size", "48"]


def _write_seeds(path: Path, n: int = 3) -> Path:
    """A tiny seed set: sky frames with a dark rectangle as the labelled object."""
    bg_frames = sky_backgrounds(n, FRAME, seed=5)
    frames, boxes, patches, bgs, crops = [], [], [], [], []
    for i in range(n):
        f = bg_frames[i].copy()
        x, y, w, h = 20 + 10 * i, 30 + 5 * i, 16, 10
        f[y:y + h, x:x + w] = 30
        p, c = crop_patch(f, box=(x, y, w, h), patch_size=40, object_fraction=0.7)
        b, _ = crop_patch(bg_frames[i], crop=c, patch_size=40)
        frames.append(f)
        boxes.append([x, y, w, h])
        patches.append(p)
        bgs.append(b)
        crops.append(c)
    return write_seedset(path, patches=np.stack(patches), backgrounds=np.stack(bgs), boxes=boxes,
                         centres=[[x + w / 2, y + h / 2] for x, y, w, h in boxes], crops=crops,
                         records=[{"video": f"v{i}", "frame": i} for i in range(n)], frames=frames,
                         background_frames=list(bg_frames), metadata={"patch_size": 40, "object_fraction": 0.7})


@pytest.fixture(scope="module")
def seeds_dir(tmp_path_factory) -> Path:
    return _write_seeds(tmp_path_factory.mktemp("export_seeds") / "seeds")


def _dataset(seeds_dir, cache, count, negative_fraction=0.0, seed=0):
    """The dataset `synthaug export` builds for FAST options (sampled Θ)."""
    return SyntheticObjectDataset("quadcopter", SeedSet.load(seeds_dir), None, length=count, mode="frame",
                                  negative_fraction=negative_fraction, object_size=OBJECT_SIZE, seed=seed,
                                  render=cache)


def _export(fmt, seeds_dir, out, count, *extra) -> int:
    return main(["export", "--format", fmt, "--seed-set", str(seeds_dir), "--count", str(count), "--out", str(out),
                 *FAST, *extra])


def _files(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def coco_run(seeds_dir, small_cache, tmp_path_factory):
    out = tmp_path_factory.mktemp("coco") / "ds"
    assert _export("coco", seeds_dir, out, 8, "--include-real", "--seed", "3") == 0
    return out, _dataset(seeds_dir, small_cache, 8, seed=3).__getitems__(list(range(8)))


@pytest.fixture(scope="module")
def yolo_run(seeds_dir, small_cache, tmp_path_factory):
    out = tmp_path_factory.mktemp("yolo") / "ds"
    assert _export("yolo", seeds_dir, out, 10, "--negative-fraction", "0.4", "--include-real",
                   "--class-name", "drone") == 0
    return out, _dataset(seeds_dir, small_cache, 10, negative_fraction=0.4).__getitems__(list(range(10)))


def test_coco_loads_with_pycocotools_and_matches_the_dataset(coco_run, seeds_dir):
    from pycocotools.coco import COCO
    from torchvision.ops import box_convert

    out, items = coco_run
    coco = COCO(str(out / "annotations.json"))
    seeds = SeedSet.load(seeds_dir)
    assert len(coco.getImgIds()) == 8 + len(seeds)
    assert len(coco.getAnnIds()) == 8 + len(seeds)  # negative fraction 0: one box per frame, one per real seed
    assert coco.loadCats(coco.getCatIds()) == [{"id": 1, "name": "object", "supercategory": "object"}]
    by_name = {im["file_name"]: im for im in coco.dataset["images"]}
    for i, (img, target) in enumerate(items):
        im = by_name[f"syn_{i:06d}.png"]
        assert im["synthetic"] is True and (im["height"], im["width"]) == FRAME
        anns = coco.loadAnns(coco.getAnnIds(imgIds=im["id"]))
        assert len(anns) == 1 and anns[0]["category_id"] == 1 and anns[0]["iscrowd"] == 0
        want = box_convert(target["boxes"], in_fmt="xyxy", out_fmt="xywh")[0].tolist()
        np.testing.assert_allclose(anns[0]["bbox"], want, atol=1e-6)
        assert anns[0]["area"] == pytest.approx(want[2] * want[3])
        # the PNG holds the dataset's frame (8-bit)
        png = np.asarray(Image.open(out / "images" / im["file_name"]))
        np.testing.assert_array_equal(png, np.round(img[0].clamp(0, 1).numpy() * 255).astype(np.uint8))
    for k in range(len(seeds)):
        im = by_name[f"real_{k:06d}.png"]
        assert im["synthetic"] is False
        (ann,) = coco.loadAnns(coco.getAnnIds(imgIds=im["id"]))
        np.testing.assert_allclose(ann["bbox"], seeds.boxes[k], atol=1e-6)
        np.testing.assert_array_equal(np.asarray(Image.open(out / "images" / im["file_name"])), seeds.frame(k))
    info = coco.dataset["info"]
    import synthaug

    assert info["synthaug_version"] == synthaug.__version__ and info["seed"] == 3
    assert info["options"]["count"] == 8 and info["options"]["format"] == "coco" and info["options"]["include_real"]


def test_object_pixels_lie_inside_the_exported_box(coco_run, seeds_dir):
    """Pixels that differ from the seed's background frame sit in the box.

    The dataset's box is the object's extent at coverage >= 0.5 before the effects, so
    thin parts below half coverage and the blur's spill reach a few pixels beyond it
    (measured over 120 frames of these settings: at most 4.5 px, 92 % of the changed
    pixels within 1 px): every changed pixel within 5 px, most within 1 px, and the
    difference's centre of mass inside.
    """
    out, items = coco_run
    doc = json.loads((out / "annotations.json").read_text())
    seeds = SeedSet.load(seeds_dir)
    boxes = {a["image_id"]: a["bbox"] for a in doc["annotations"]}
    fractions = []
    for im in doc["images"]:
        if not im["synthetic"]:
            continue
        png = np.asarray(Image.open(out / "images" / im["file_name"])).astype(float)
        diff = np.abs(png - seeds.background_frame(im["seed_index"]).astype(float))
        ys, xs = np.nonzero(diff > 5)  # 0.02 of the range
        assert len(xs) > 0, im["file_name"]  # the object is there
        x, y, w, h = boxes[im["id"]]
        cx, cy = xs + 0.5, ys + 0.5  # pixel centres
        dx = np.maximum(np.maximum(x - cx, cx - (x + w)), 0)
        dy = np.maximum(np.maximum(y - cy, cy - (y + h)), 0)
        assert np.hypot(dx, dy).max() <= 5, im["file_name"]
        fractions.append(float(((dx <= 1) & (dy <= 1)).mean()))
        gy, gx = np.mgrid[:diff.shape[0], :diff.shape[1]]
        mx, my = (gx * diff).sum() / diff.sum() + 0.5, (gy * diff).sum() / diff.sum() + 0.5
        assert x <= mx <= x + w and y <= my <= y + h, im["file_name"]
    assert len(fractions) == 8 and np.mean(fractions) > 0.85, fractions


def test_yolo_lines_denormalise_to_the_dataset_boxes(yolo_run, seeds_dir):
    yaml = pytest.importorskip("yaml")
    out, items = yolo_run
    seeds = SeedSet.load(seeds_dir)
    data = yaml.safe_load((out / "data.yaml").read_text())
    assert data["path"] == str(out.resolve()) and data["train"] == "images" and data["names"] == {0: "drone"}
    H, W = FRAME
    expected = {f"syn_{i:06d}": t["boxes"].numpy() for i, (_, t) in enumerate(items)}
    expected.update({f"real_{k:06d}": np.array([[x, y, x + w, y + h]]) for k, (x, y, w, h) in enumerate(seeds.boxes)})
    assert sorted(p.stem for p in (out / "images").glob("*.png")) == sorted(expected)
    assert sorted(p.stem for p in (out / "labels").glob("*.txt")) == sorted(expected)
    n_empty = 0
    for stem, want in expected.items():
        text = (out / "labels" / f"{stem}.txt").read_text()
        n_empty += text == ""
        rows = [line.split() for line in text.splitlines()]
        assert len(rows) == len(want)
        for row, (x0, y0, x1, y1) in zip(rows, want.tolist()):
            assert len(row) == 5 and row[0] == "0"
            xc, yc, bw, bh = (float(v) for v in row[1:])
            assert all(0 <= v <= 1 for v in (xc, yc, bw, bh))
            got = [(xc - bw / 2) * W, (yc - bh / 2) * H, (xc + bw / 2) * W, (yc + bh / 2) * H]
            np.testing.assert_allclose(got, [x0, y0, x1, y1], atol=1e-4, rtol=0)
    n_neg = sum(len(t["boxes"]) == 0 for _, t in items)
    assert 0 < n_neg < len(items) and n_empty == n_neg  # empty txt exactly for the frames without an object


def test_two_runs_give_byte_identical_files(seeds_dir, tmp_path):
    for fmt in ("coco", "yolo"):
        out = tmp_path / fmt
        args = (fmt, seeds_dir, out, 5, "--include-real", "--negative-fraction", "0.3", "--seed", "7")
        assert _export(*args) == 0
        first = _files(out)
        out.rename(tmp_path / f"{fmt}_first")
        assert _export(*args) == 0
        assert _files(out) == first
        # --overwrite and another --batch-size give the same files too
        assert _export(*args, "--overwrite", "--batch-size", "2") == 0
        assert _files(out) == first
        assert len(first) == (5 + 3 + 1 if fmt == "coco" else 2 * (5 + 3) + 1)


@pytest.mark.parametrize("case", ["format", "count", "seed-set", "params", "out"])
def test_errors_exit_2_name_the_option_and_write_nothing(case, seeds_dir, tmp_path, capsys):
    out = tmp_path / "out"
    fmt, count, seeds, extra = "coco", 3, seeds_dir, []
    if case == "format":
        fmt = "voc"
    elif case == "count":
        count = 0
    elif case == "seed-set":
        seeds = tmp_path / "no_such_seedset"
    elif case == "params":
        p = tmp_path / "fit.json"
        CaptureParams.sample(2, generator=torch.Generator().manual_seed(0)).save(p)  # the seed set has 3
        extra = ["--params", str(p)]
    elif case == "out":
        out.mkdir()
        (out / "keep.txt").write_text("mine")
    before = _files(tmp_path)
    listing = sorted(p.name for p in tmp_path.iterdir())
    assert _export(fmt, seeds, out, count, *extra) == 2
    err = capsys.readouterr().err
    assert f"--{case}" in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == listing  # no output, no temporary folder left
    assert _files(tmp_path) == before
    if case == "out":
        assert _files(out) == {"keep.txt": b"mine"}
        assert _export(fmt, seeds, out, count, "--overwrite") == 0  # replaced on request
        assert not (out / "keep.txt").exists() and (out / "annotations.json").exists()


def test_a_matching_fit_file_is_used(seeds_dir, small_cache, tmp_path):
    p = tmp_path / "fit.json"
    params = CaptureParams.sample(3, generator=torch.Generator().manual_seed(11))
    params.save(p)
    out = tmp_path / "ds"
    assert _export("coco", seeds_dir, out, 4, "--params", str(p)) == 0
    ds = SyntheticObjectDataset("quadcopter", SeedSet.load(seeds_dir), params, length=4, mode="frame",
                                negative_fraction=0.0, object_size=OBJECT_SIZE, render=small_cache)
    doc = json.loads((out / "annotations.json").read_text())
    for (img, t), im in zip(ds.__getitems__(list(range(4))), doc["images"]):
        png = np.asarray(Image.open(out / "images" / im["file_name"]))
        np.testing.assert_array_equal(png, np.round(img[0].clamp(0, 1).numpy() * 255).astype(np.uint8))


class _TvTensors(torch.utils.data.Dataset):
    """The dataset's items as torchvision tv_tensors (Image, BoundingBoxes in a chosen format)."""

    def __init__(self, ds, box_format="XYXY"):
        self.ds, self.mode, self.seed, self.epoch, self.box_format = ds, ds.mode, ds.seed, ds.epoch, box_format

    def __len__(self):
        return len(self.ds)

    def __getitem__(self, i):
        from torchvision import tv_tensors
        from torchvision.ops import box_convert

        img, t = self.ds[i]
        b = box_convert(t["boxes"], in_fmt="xyxy", out_fmt=self.box_format.lower())
        t = {**t, "boxes": tv_tensors.BoundingBoxes(b, format=self.box_format, canvas_size=tuple(img.shape[-2:]))}
        return tv_tensors.Image(img), t


@pytest.mark.parametrize("fmt", ["coco", "yolo"])
def test_api_works_with_tv_tensors(fmt, seeds_dir, small_cache, tmp_path):
    pytest.importorskip("torchvision.tv_tensors")
    ds = _dataset(seeds_dir, small_cache, 4, negative_fraction=0.25)
    real = seedset_real_frames(seeds_dir)
    export_dataset(ds, tmp_path / "plain", fmt, 4, real=real)
    plain = _files(tmp_path / "plain")
    for box_format in ("XYXY", "CXCYWH"):  # pixel-edge boxes convert exactly (integers and halves)
        export_dataset(_TvTensors(ds, box_format), tmp_path / box_format, fmt, 4, real=real)
        tv = _files(tmp_path / box_format)
        assert sorted(tv) == sorted(plain)
        for name in plain:
            if name != "data.yaml":  # names its own folder
                assert tv[name] == plain[name], (box_format, name)


def test_api_errors(seeds_dir, small_cache, tmp_path):
    ds = _dataset(seeds_dir, small_cache, 3)
    with pytest.raises(ValueError, match="format"):
        export_dataset(ds, tmp_path / "a", "voc", 2)
    with pytest.raises(ValueError, match="count"):
        export_dataset(ds, tmp_path / "a", "coco", 4)
    patch_ds = SyntheticObjectDataset("quadcopter", [np.full((48, 48), 128, np.uint8)], length=2, render=small_cache)
    with pytest.raises(ValueError, match="frame-mode"):
        export_dataset(patch_ds, tmp_path / "a", "coco", 2)
    assert list(tmp_path.iterdir()) == []


def test_every_option_has_a_help_text_with_its_default():
    sub = next(a for a in build_parser("export")._actions if a.dest == "command")
    parser = sub.choices["export"]
    opts = [a for a in parser._actions if a.option_strings and a.dest != "help" and a.help != argparse.SUPPRESS]
    assert {"--format", "--seed-set", "--params", "--mesh", "--count", "--out", "--include-real", "--seed",
            "--object-size", "--negative-fraction", "--class-name", "--overwrite"} <= {a.option_strings[0] for a in opts}
    for a in opts:
        assert a.help and ("(default:" in a.help or "(required)" in a.help), a.option_strings
