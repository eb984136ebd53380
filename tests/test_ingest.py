"""Ingest end to end: generated videos with known backgrounds, resumption, bad inputs, COCO round trip."""

from __future__ import annotations

import json
import shutil

import cv2
import numpy as np
import pytest

from synthaug.data.backgrounds import grow_boxes, object_mask
from synthaug.data.ingest import IngestConfig, ingest_coco, ingest_videos
from synthaug.data.seedset import SeedSet, crop_patch
from synthaug.data.synthvideo import make_panning_video
from synthaug.data.video import IngestInputError, clip_boxes, read_coco, read_labels, read_video_with_labels

CFG = IngestConfig(seeds_per_video=4, negatives_per_video=6, hard_negatives_per_video=5, patch_size=32)


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    root = tmp_path_factory.mktemp("data")
    truth = {}
    for k in range(3):
        v = make_panning_video(root, n_frames=45, size=(320, 256), seed=10 + k, name=f"V_DRONE_{k + 1:03d}")
        truth[v.video_path.stem] = v
    make_panning_video(root, n_frames=30, size=(320, 256), seed=20, name="V_BIRD_001", class_name="bird")
    return root, truth


@pytest.fixture()
def data_copy(dataset, tmp_path):
    root, truth = dataset
    shutil.copytree(root, tmp_path / "data")
    return tmp_path / "data", truth


def _ingest(root, out, **kw):
    kw.setdefault("cfg", CFG)
    kw.setdefault("workers", 1)
    kw.setdefault("progress", False)
    return ingest_videos(root / "videos", root / "labels", out, **kw)


def test_ingest_generated_videos(dataset, tmp_path):
    root, truth = dataset
    report = _ingest(root, tmp_path / "out", seed_counts=(3, 6))
    assert report["failed"] == {} and report["processed"] == 4
    small, big = SeedSet.load(tmp_path / "out/seedsets/drone_3"), SeedSet.load(tmp_path / "out/seedsets/drone_6")
    assert len(small) == 3 and len(big) == 6
    assert len({r["video"] for r in small.records}) == 3  # spread across videos
    keys = lambda s: {(r["video"], r["frame"]) for r in s.records}  # noqa: E731
    assert keys(small) <= keys(big)  # nested seed sets
    assert (tmp_path / "out/seedsets/drone_6/contact_sheet.png").is_file()
    assert big.patches.shape == (6, 32, 32) and big.metadata["patch_size"] == 32
    for i, rec in enumerate(big.records):
        v = truth[rec["video"]]
        t = rec["frame"]
        assert rec["split"] == "train" and rec["class"] == "drone"
        assert rec["background_method"] in ("median", "median+inpaint", "inpaint")
        # the full frame is the decoded frame; the box is the label; the centre is the box centre
        frame = big.frame(i)
        assert np.abs(frame.astype(int) - v.frames[t]).mean() < 2
        np.testing.assert_allclose(big.boxes[i], v.boxes[t], atol=0.01)
        np.testing.assert_allclose(big.centres[i], v.boxes[t][:2] + v.boxes[t][2:] / 2, atol=0.01)
        # the background frame is the true background where the object was
        m = object_mask(frame.shape, big.boxes[i], margin_fraction=0, min_margin=0)
        bgf = big.background_frame(i)
        err = np.abs(bgf[m].astype(int) - v.backgrounds[t][m]).mean()
        assert err < (4 if rec["background_method"] != "inpaint" else 2 * rec["background_quality"] + 3), rec
        assert np.abs(v.frames[t][m].astype(int) - v.backgrounds[t][m]).mean() > 3 * err  # the object is gone
        # patches are the frame / background-frame crops
        ref, _ = crop_patch(bgf, crop=big.crops[i], patch_size=32)
        assert np.array_equal(big.backgrounds[i], ref)
        ref_obj, _ = crop_patch(frame, box=big.boxes[i], patch_size=32, object_fraction=0.7)
        assert np.array_equal(big.patches[i], ref_obj)
    # negatives: background crops away from every box, plus the bird's hard negatives
    kinds = [r["kind"] for r in big.negative_records]
    assert kinds.count("hard") == 5 and kinds.count("background") == 18
    for r in big.negative_records:
        if r["kind"] != "background":
            assert r["class"] == "bird"
            continue
        cx, cy, side = r["crop"]
        x, y, w, h = grow_boxes(truth[r["video"]].boxes[r["frame"]])[0]
        assert cx + side / 2 <= x or cx - side / 2 >= x + w or cy + side / 2 <= y or cy - side / 2 >= y + h
    assert len(big.negatives) == len(big.negative_records)


def test_rerun_skips_finished_videos_and_redoes_missing(data_copy, tmp_path):
    root, _ = data_copy
    out = tmp_path / "out"
    _ingest(root, out, seed_counts=())
    before = SeedSet.load(out / "pool/V_DRONE_002").patches.copy()
    shutil.rmtree(out / "pool/V_DRONE_001")
    (out / "pool/.V_DRONE_003.tmp-abc").mkdir()  # what a killed worker leaves behind
    report = _ingest(root, out, seed_counts=(2,))
    assert report["processed"] == 1 and report["skipped_current"] == 3
    assert list(report["videos"]) == ["V_DRONE_001"]
    assert not (out / "pool/.V_DRONE_003.tmp-abc").exists()
    assert np.array_equal(SeedSet.load(out / "pool/V_DRONE_002").patches, before)
    # other options -> shards are stale and redone
    report = _ingest(root, out, seed_counts=(), cfg=IngestConfig(seeds_per_video=2, patch_size=32))
    assert report["processed"] == 4


def test_one_bad_video_never_loses_the_others(data_copy, tmp_path):
    root, _ = data_copy
    (root / "videos/V_DRONE_002.mp4").write_bytes(b"\x00not a video" * 100)
    (root / "labels/V_DRONE_004.json").write_text("")  # empty label file (and no video)
    lab = json.loads((root / "labels/V_DRONE_003.json").read_text())
    (root / "labels/V_CAT_001.json").write_text(json.dumps({**lab, "class": "cat"}))
    shutil.copy(root / "videos/V_DRONE_003.mp4", root / "videos/V_CAT_001.mp4")
    report = _ingest(root, tmp_path / "out", seed_counts=(2,), cfg=IngestConfig(
        seeds_per_video=2, negatives_per_video=2, patch_size=32, classes=("drone",)))
    failed = report["failed"]
    assert set(failed) == {"V_DRONE_002", "V_DRONE_004", "V_CAT_001"}
    assert "unreadable" in failed["V_DRONE_002"] or "cannot be opened" in failed["V_DRONE_002"]
    assert "is empty" in failed["V_DRONE_004"]
    assert "unknown class 'cat'" in failed["V_CAT_001"]
    assert (tmp_path / "out/pool/V_DRONE_002.error.json").is_file()
    assert report["processed"] == 3  # drone 1, drone 3, bird
    assert len(SeedSet.load(tmp_path / "out/seedsets/drone_2")) == 2


def test_length_mismatch_and_boxes_outside(data_copy):
    root, truth = data_copy
    path = root / "labels/V_DRONE_001.json"
    lab = json.loads(path.read_text())
    boxes = lab["boxes"] + [[1.0, 1.0, 5.0, 5.0]] * 3  # 3 labels more than frames
    boxes[0] = [-10.0, 5.0, 30.0, 20.0]  # partly outside: clipped
    boxes[1] = [400.0, 5.0, 30.0, 20.0]  # fully outside: dropped
    boxes[2] = [10.0, 5.0, -3.0, 20.0]  # invalid
    path.write_text(json.dumps({**lab, "boxes": boxes}))
    frames, labels, stats = read_video_with_labels(root / "videos/V_DRONE_001.mp4", path)
    assert len(frames) == len(labels.boxes) == 45
    assert (stats.frames_decoded, stats.labels_read, stats.frames_used) == (45, 48, 45)
    assert (stats.clipped, stats.dropped, stats.invalid) == (1, 1, 1)
    assert labels.boxes[0].tolist() == [0.0, 5.0, 20.0, 20.0] and labels.boxes[1] is None
    # fewer labels than frames: the shorter wins
    path.write_text(json.dumps({**lab, "boxes": lab["boxes"][:20]}))
    frames, labels, stats = read_video_with_labels(root / "videos/V_DRONE_001.mp4", path)
    assert len(frames) == len(labels.boxes) == 20


@pytest.mark.parametrize("content, match", [
    ("", "is empty"),
    ("{not json", "not valid JSON"),
    ('{"class": "drone", "boxes": []}', "is empty"),
    ('{"class": "drone", "box_format": "xyxy", "boxes": [null]}', "box_format"),
    ('{"boxes": [null]}', "missing 'class'"),
    ('[1, 2]', "JSON object"),
])
def test_bad_label_files(tmp_path, content, match):
    p = tmp_path / "V_X.json"
    p.write_text(content)
    with pytest.raises(IngestInputError, match=match):
        read_labels(p)


def test_unknown_class_and_missing_files(tmp_path):
    p = tmp_path / "V_X.json"
    p.write_text('{"class": "cat", "boxes": [null]}')
    with pytest.raises(IngestInputError, match="unknown class 'cat'"):
        read_labels(p, classes=("drone", "airplane"))
    with pytest.raises(IngestInputError, match="not found"):
        read_labels(tmp_path / "missing.json")
    from synthaug.data.video import read_video

    with pytest.raises(IngestInputError, match="video not found"):
        read_video(tmp_path / "missing.mp4")


def test_clip_boxes_errors():
    with pytest.raises(ValueError, match="frame size must be positive"):
        clip_boxes([], width=0, height=10)


def _export_coco(seeds: SeedSet, out_dir):
    """Seed frames -> PNG images + COCO JSON (the inverse of COCO ingest)."""
    (out_dir / "images").mkdir(parents=True)
    images, anns = [], []
    for i in range(len(seeds)):
        name = f"img_{i:03d}.png"
        cv2.imwrite(str(out_dir / "images" / name), seeds.frame(i))
        h, w = seeds.frame(i).shape
        images.append({"id": i + 1, "file_name": name, "width": w, "height": h})
        anns.append({"id": i + 1, "image_id": i + 1, "category_id": 7, "bbox": seeds.boxes[i].tolist(), "iscrowd": 0})
    doc = {"images": images, "annotations": anns, "categories": [{"id": 7, "name": "drone"}]}
    (out_dir / "coco.json").write_text(json.dumps(doc))
    return doc


def test_coco_round_trip(dataset, tmp_path):
    root, _ = dataset
    _ingest(root, tmp_path / "vid", seed_counts=(6,))
    seeds = SeedSet.load(tmp_path / "vid/seedsets/drone_6")
    doc = _export_coco(seeds, tmp_path / "coco")
    report = ingest_coco(tmp_path / "coco/coco.json", tmp_path / "coco/images", tmp_path / "cout", cfg=CFG,
                         seed_counts=(6,), workers=1, progress=False, chunk=4)
    assert report["failed"] == {} and report["processed"] == 2
    back = SeedSet.load(tmp_path / "cout/seedsets/drone_6")
    assert len(back) == 6
    by_name = {r["video"]: i for i, r in enumerate(back.records)}
    for i in range(len(seeds)):
        j = by_name[f"img_{i:03d}.png"]
        np.testing.assert_allclose(back.boxes[j], seeds.boxes[i], atol=1e-4)
        assert np.array_equal(back.patches[j], seeds.patches[i])  # same frame, same box -> same patch
        assert np.array_equal(back.frame(j), seeds.frame(i))
        assert back.records[j]["background_method"] == "inpaint" and back.records[j]["class"] == "drone"
        # the inpainted background no longer holds the object: far from the frame inside the box
        m = object_mask(back.frame(j).shape, back.boxes[j], margin_fraction=0, min_margin=0)
        assert np.abs(back.background_frame(j)[m].astype(int) - back.frame(j)[m]).mean() > 10
    assert read_coco(tmp_path / "coco/coco.json", tmp_path / "coco/images")[0].classes == ["drone"]
    assert len(doc["images"]) == 6


def test_coco_bad_inputs(tmp_path):
    img_dir = tmp_path / "images"
    img_dir.mkdir()
    cv2.imwrite(str(img_dir / "a.png"), np.full((64, 64), 120, np.uint8))
    (img_dir / "b.png").write_bytes(b"garbage")
    good = {"images": [{"id": 1, "file_name": "a.png"}, {"id": 2, "file_name": "b.png"}],
            "annotations": [{"id": 1, "image_id": 1, "category_id": 1, "bbox": [20, 20, 16, 16]},
                            {"id": 2, "image_id": 2, "category_id": 1, "bbox": [20, 20, 16, 16]}],
            "categories": [{"id": 1, "name": "drone"}]}
    coco = tmp_path / "c.json"
    for doc, match in [({**good, "annotations": []}, "no annotations"),
                       ({**good, "categories": [{"id": 2, "name": "drone"}]}, "unknown category_id 1"),
                       ({**good, "annotations": [{**good["annotations"][0], "image_id": 9}]}, "unknown image_id 9")]:
        coco.write_text(json.dumps(doc))
        with pytest.raises(IngestInputError, match=match):
            read_coco(coco, img_dir)
    coco.write_text(json.dumps(good))
    with pytest.raises(IngestInputError, match="unknown class 'drone'"):
        read_coco(coco, img_dir, classes=("bird",))
    # an unreadable image is reported, the readable one still becomes a seed
    report = ingest_coco(coco, img_dir, tmp_path / "out", cfg=CFG, seed_counts=(1,), workers=1, progress=False)
    assert len(report["unreadable_images"]) == 1 and "b.png" in report["unreadable_images"][0]
    assert len(SeedSet.load(tmp_path / "out/seedsets/drone_1")) == 1


@pytest.mark.slow
def test_parallel_equals_serial(dataset, tmp_path):
    root, _ = dataset
    _ingest(root, tmp_path / "a", seed_counts=(4,), workers=1)
    _ingest(root, tmp_path / "b", seed_counts=(4,), workers=2)
    a, b = SeedSet.load(tmp_path / "a/seedsets/drone_4"), SeedSet.load(tmp_path / "b/seedsets/drone_4")
    assert [r["frame"] for r in a.records] == [r["frame"] for r in b.records]
    assert np.array_equal(a.patches, b.patches) and np.array_equal(a.backgrounds, b.backgrounds)
    assert np.array_equal(a.negatives, b.negatives)


def test_cli(dataset, tmp_path, capsys):
    from synthaug.cli import main

    root, _ = dataset
    rc = main(["ingest", "--videos", str(root / "videos"), "--labels", str(root / "labels"), "--out",
               str(tmp_path / "out"), "--seeds", "2", "--per-video", "2", "--patch-size", "24", "--workers", "1",
               "--no-progress"])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    assert out["failed"] == {} and out["processed"] == 4
    assert SeedSet.load(tmp_path / "out/seedsets/drone_2").patches.shape == (2, 24, 24)
    assert main(["ingest", "--videos", str(root), "--out", str(tmp_path / "x")]) == 2  # --labels missing
    assert main(["ingest", "--videos", "a", "--labels", "b", "--coco", "c", "--images", "d", "--out", "x"]) == 2
    assert main(["ingest", "--videos", str(root / "videos"), "--labels", str(tmp_path / "nope"),
                 "--out", str(tmp_path / "y"), "--no-progress"]) == 2
    assert "label folder not found" in capsys.readouterr().err


def test_colour_ingest_keeps_rgb_patches_with_the_colour_background(dataset, tmp_path):
    """A colour video (the generated scene tinted per channel): the seed set carries RGB patches whose luma is the
    gray patch (OpenCV's Rec. 601, to the crop's rounding) and whose background, filled by the same aligned median,
    is the true tinted background where the object was; a gray ingest writes none."""
    import cv2

    root, truth = dataset
    stem = "V_DRONE_001"
    v = truth[stem]
    tint = np.array([1.1, 1.0, 0.8])  # B, G, R as OpenCV writes
    data = tmp_path / "data"
    (data / "videos").mkdir(parents=True)
    (data / "labels").mkdir()
    shutil.copy(root / "labels" / f"{stem}.json", data / "labels" / f"{stem}.json")
    h, w = v.frames.shape[1:]
    writer = cv2.VideoWriter(str(data / "videos" / f"{stem}.mp4"), cv2.VideoWriter_fourcc(*"mp4v"), 30.0, (w, h), True)
    for f in v.frames:
        writer.write(np.clip(f[..., None] * tint, 0, 255).astype(np.uint8))
    writer.release()
    report = _ingest(data, tmp_path / "out", seed_counts=(4,))
    assert report["failed"] == {}
    s = SeedSet.load(tmp_path / "out/seedsets/drone_4")
    rgb, bg = s.colour()
    assert rgb.shape == bg.shape == (4, 32, 32, 3)
    luma = np.stack([cv2.cvtColor(x, cv2.COLOR_RGB2GRAY) for x in rgb]).astype(int)
    assert np.abs(luma - s.patches.astype(int)).max() <= 2
    for i, rec in enumerate(s.records):
        t = rec["frame"]
        true_bg = np.clip(v.backgrounds[t][..., None] * tint[::-1], 0, 255)  # RGB
        ref = np.stack([crop_patch(np.ascontiguousarray(true_bg[..., c]).astype(np.uint8), crop=s.crops[i],
                                   patch_size=32)[0] for c in range(3)], -1).astype(int)
        err = np.abs(bg[i].astype(int) - ref).reshape(-1, 3).mean(0)
        assert (err < (6 if rec["background_method"] != "inpaint" else 2 * rec["background_quality"] + 6)).all(), err
        assert bg[i][..., 0].mean() < bg[i][..., 2].mean()  # blue above red: the tint survived
    # subsets keep their colour; a gray ingest has none
    s.save_subset(tmp_path / "sub", [2, 0])
    sub = SeedSet.load(tmp_path / "sub")
    assert np.array_equal(sub.colour()[0], rgb[[2, 0]]) and np.array_equal(sub.colour()[1], bg[[2, 0]])
    from dataclasses import replace

    _ingest(data, tmp_path / "gray", seed_counts=(4,), cfg=replace(CFG, colour=False))
    assert SeedSet.load(tmp_path / "gray/seedsets/drone_4").colour() is None


def test_each_seed_keeps_an_aligned_neighbour_frame_for_the_noise_level_function(dataset, tmp_path):
    """The seed's second look at the scene: a neighbouring frame and the homography onto the seed's frame; warped,
    it matches the seed's frame off both objects to the codec's error (the truth: the generated pan)."""
    from synthaug.diagnose.noise import aligned_neighbour, seed_noise_levels

    root, truth = dataset
    _ingest(root, tmp_path / "out", seed_counts=(6,))
    s = SeedSet.load(tmp_path / "out/seedsets/drone_6")
    for i, rec in enumerate(s.records):
        nb = rec["neighbour"]
        assert 1 <= abs(nb["offset"]) <= 2
        v = truth[rec["video"]]
        assert np.abs(s.neighbour_frame(i).astype(int) - v.frames[rec["frame"] + nb["offset"]]).mean() < 2
        warped, out = aligned_neighbour(s.frame(i), s.neighbour_frame(i), nb["homography"], nb["box"])
        out |= object_mask(out.shape, s.boxes[i], margin_fraction=0.5, min_margin=0)
        err = np.abs(warped[~out] * 255 - s.frame(i)[~out])
        assert np.median(err) < 2.0, np.median(err)
    assert seed_noise_levels(s) is not None  # measurable through the neighbours (the backgrounds are not)
    s.save_subset(tmp_path / "sub", [1])
    assert SeedSet.load(tmp_path / "sub").records[0]["neighbour"] == s.records[1]["neighbour"]
    assert np.array_equal(SeedSet.load(tmp_path / "sub").neighbour_frame(0), s.neighbour_frame(1))


@pytest.mark.parametrize("bad", [[0, 0, 0, 0], [5, 5, -3, 4], [float("nan"), 1, 2, 3], [900, 900, 10, 10], [1, 2]])
def test_a_video_whose_every_box_is_unusable_fails_naming_its_label_file(data_copy, tmp_path, capsys, bad):
    from synthaug.cli import main

    root, _ = data_copy
    path = root / "labels/V_DRONE_002.json"
    lab = json.loads(path.read_text())
    path.write_text(json.dumps({**lab, "boxes": [bad] * len(lab["boxes"])}))
    rc = main(["ingest", "--videos", str(root / "videos"), "--labels", str(root / "labels"), "--out",
               str(tmp_path / "out"), "--seeds", "2", "--per-video", "2", "--patch-size", "24", "--workers", "1",
               "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 1 and "V_DRONE_002 failed" in err and "none of its boxes is usable" in err and str(path) in err


def test_a_label_file_much_longer_than_its_video_warns(data_copy, caplog):
    import logging

    root, _ = data_copy
    path = root / "labels/V_DRONE_001.json"
    lab = json.loads(path.read_text())
    path.write_text(json.dumps({**lab, "boxes": lab["boxes"] * 4}))  # 180 labels for 45 frames
    caplog.set_level(logging.WARNING, logger="synthaug.data")
    frames, labels, stats = read_video_with_labels(root / "videos/V_DRONE_001.mp4", path)
    assert len(frames) == len(labels.boxes) == 45
    assert any("180 entries for the 45 frames" in r.getMessage() for r in caplog.records)
    caplog.clear()
    path.write_text(json.dumps({**lab, "boxes": lab["boxes"] + [None]}))  # one more: the shorter rule, silently
    read_video_with_labels(root / "videos/V_DRONE_001.mp4", path)
    assert not caplog.records


def test_ingest_into_a_file_is_one_clear_error(data_copy, tmp_path, capsys):
    from synthaug.cli import main

    root, _ = data_copy
    (tmp_path / "taken").write_text("x")
    rc = main(["ingest", "--videos", str(root / "videos"), "--labels", str(root / "labels"), "--out",
               str(tmp_path / "taken"), "--no-progress", "--workers", "1"])
    err = capsys.readouterr().err
    assert rc == 2 and f"{tmp_path / 'taken'} is a file" in err and "Traceback" not in err
