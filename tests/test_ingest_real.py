"""Ingest on a few short real halmstad videos, and the committed by-video split."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from synthaug.data.backgrounds import estimate_background, object_mask
from synthaug.data.ingest import IngestConfig, ingest_videos
from synthaug.data.seedset import SeedSet
from synthaug.data.splits import SPLITS, load_split, make_video_split, save_split
from synthaug.data.video import read_video_with_labels

REPO = Path(__file__).resolve().parents[1]
SPLIT_FILE = REPO / "configs/splits/halmstad.json"


def _link_subset(shared_data, tmp_path, stems):
    """A videos/ + labels/ pair holding only ``stems`` (symlinks, nothing copied)."""
    for sub, ext in (("videos", ".mp4"), ("labels", ".json")):
        (tmp_path / sub).mkdir()
        for s in stems:
            (tmp_path / sub / f"{s}{ext}").symlink_to(shared_data / "halmstad" / sub / f"{s}{ext}")
    return tmp_path / "videos", tmp_path / "labels"


@pytest.mark.real_data
def test_ingest_real_videos(shared_data, tmp_path):
    split = load_split(SPLIT_FILE)
    stems = [split.videos["train"][0], split.videos["train"][-1], split.hard_negatives["train"][0]]
    videos, labels = _link_subset(shared_data, tmp_path, stems)
    cfg = IngestConfig(seeds_per_video=3, negatives_per_video=4, hard_negatives_per_video=3)
    report = ingest_videos(videos, labels, tmp_path / "out", split=SPLIT_FILE, cfg=cfg, seed_counts=(2,),
                           workers=1, progress=False)
    assert report["failed"] == {} and report["processed"] == 3
    for s in report["seed_sets"]:
        seeds = SeedSet.load(s["path"])
        assert len(seeds) == 2 and seeds.patches.shape == (2, 40, 40)
        assert {r["split"] for r in seeds.records} == {"train"}
        assert any(r["kind"] == "hard" for r in seeds.negative_records)
        for i, rec in enumerate(seeds.records):
            assert rec["background_method"] in ("median", "median+inpaint", "inpaint")
            assert np.isfinite(rec["background_quality"])
            frame, bg = seeds.frame(i), seeds.background_frame(i)
            assert frame.shape == bg.shape == (512, 640)
            m = object_mask(frame.shape, seeds.boxes[i], margin_fraction=0, min_margin=0)
            # the object was removed: the background differs from the frame inside the box ...
            assert np.abs(bg[m].astype(int) - frame[m]).max() > 20
            # ... and only around it
            region = object_mask(frame.shape, seeds.boxes[i], margin_fraction=0.25, min_margin=4)
            assert np.array_equal(bg[~region], frame[~region])


@pytest.mark.real_data
def test_real_background_never_shows_the_object(shared_data):
    """The dark drone is gone: the fill inside its box is as bright as the sky ring around it."""
    split = load_split(SPLIT_FILE)
    stem = next(s for s in split.videos["train"] if "DRONE" in s)
    frames, labels, _ = read_video_with_labels(shared_data / f"halmstad/videos/{stem}.mp4",
                                               shared_data / f"halmstad/labels/{stem}.json")
    idx = [i for i, b in enumerate(labels.boxes) if b is not None][::75][:3]
    for i in idx:
        res = estimate_background(frames, labels.boxes, i)
        box = object_mask(frames[i].shape, labels.boxes[i], margin_fraction=0, min_margin=0)
        ring = object_mask(frames[i].shape, labels.boxes[i], margin_fraction=0.6, min_margin=8) & ~res.region
        frame_dev = np.abs(np.percentile(frames[i][box], 2) - np.median(frames[i][ring]))
        bg_dev = np.abs(np.percentile(res.background[box], 2) - np.median(frames[i][ring]))
        assert bg_dev < 0.5 * frame_dev or frame_dev < 10, (stem, i, res.method, frame_dev, bg_dev)


@pytest.mark.real_data
def test_committed_split_covers_the_shared_videos(shared_data):
    split = load_split(SPLIT_FILE)  # also checks that no video is listed twice
    classes = {p.stem: json.loads(p.read_text())["class"] for p in (shared_data / "halmstad/labels").glob("*.json")}
    positives = {s for s, c in classes.items() if c in ("drone", "airplane")}
    birds = {s for s, c in classes.items() if c == "bird"}
    listed = {s for k in SPLITS for s in split.videos[k]}
    hard = {s for k in SPLITS for s in split.hard_negatives[k]}
    assert listed == positives and hard == birds
    for cls in ("drone", "airplane"):
        n = [sum(classes[s] == cls for s in split.videos[k]) for k in SPLITS]
        assert n[0] > n[1] > 0 and n[2] > 0, (cls, n)
    # the committed file is what the generator gives
    assert make_video_split(classes, seed=split.info["seed"], block=split.info["block"],
                            dataset="halmstad").to_json() == json.loads(SPLIT_FILE.read_text())


def test_split_is_by_video_in_blocks(tmp_path):
    classes = {f"V_DRONE_{i:03d}": "drone" for i in range(1, 41)}
    classes |= {f"V_BIRD_{i:03d}": "bird" for i in range(1, 11)}
    split = make_video_split(classes, seed=1, block=4)
    all_pos = [s for k in SPLITS for s in split.videos[k]]
    assert sorted(all_pos) == sorted(s for s in classes if "DRONE" in s) and len(set(all_pos)) == 40
    assert [len(split.videos[k]) for k in SPLITS] == [24, 8, 8]
    assert sum(len(v) for v in split.hard_negatives.values()) == 10
    for b in range(10):  # blocks of 4 consecutive numbers stay together
        assert len({split.split_of(f"V_DRONE_{4 * b + j:03d}") for j in range(1, 5)}) == 1
    save_split(split, tmp_path / "s.json")
    again = load_split(tmp_path / "s.json")
    assert again.videos == split.videos and again.split_of("V_BIRD_001") in SPLITS
    doc = json.loads((tmp_path / "s.json").read_text())
    doc["val"].append(doc["train"][0])
    (tmp_path / "s.json").write_text(json.dumps(doc))
    with pytest.raises(ValueError, match="listed twice"):
        load_split(tmp_path / "s.json")
    with pytest.raises(ValueError, match="fractions"):
        make_video_split(classes, fractions={"train": 0.5, "val": 0.1, "test": 0.1})
