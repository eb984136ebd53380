"""Issue 18, "a clear error for every bad input, validate before working": a table of bad inputs across the
commands. Each one exits 2 (or raises ValueError) during argument validation, with a message that names the
offending option, and writes nothing: no output file or folder, no half-made work folder.

Inputs are tiny and generated in ``tmp_path``; no case gets as far as loading a checkpoint, reading a video,
building a view cache or fitting, so the whole table runs in seconds.
"""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest

from synthaug.cli import main


def _seedset(root):
    from synthaug.data.procedural import sky_backgrounds
    from synthaug.data.seedset import write_seedset

    bgs = sky_backgrounds(2, (40, 40), seed=0)
    patches = bgs.copy()
    patches[:, 15:25, 10:30] = 30
    frames = sky_backgrounds(2, (64, 64), seed=1)
    write_seedset(root / "seeds", patches=patches, backgrounds=bgs, boxes=[[0, 0, 10, 10]] * 2,
                  centres=[[5, 5]] * 2, crops=[[5, 5, 14]] * 2, records=[{"video": "v"}] * 2,
                  frames=list(frames), background_frames=list(frames),
                  metadata={"patch_size": 40, "object_fraction": 0.7})
    return root / "seeds"


def _labels(video, boxes):
    return {"video": video, "class": "drone", "box_format": "xywh_pixels", "boxes": boxes}


@pytest.fixture
def inputs(tmp_path):
    """Paths the table's argument lists are formatted with: tiny valid inputs, a file and a folder in the way."""
    seeds = _seedset(tmp_path)
    (tmp_path / "dets.json").write_text(json.dumps(
        {"format": "synthaug.detections", "version": 1, "video": "V_DRONE_001.mp4", "input": "video",
         "detections": [[[10, 10, 8, 8, 0.9]], None, []]}))
    (tmp_path / "labels").mkdir()
    (tmp_path / "labels" / "V_DRONE_001.json").write_text(json.dumps(_labels("V_DRONE_001.mp4",
                                                                              [[10, 10, 8, 8], None, None])))
    (tmp_path / "V_DRONE_002.json").write_text(json.dumps(_labels("V_DRONE_002.mp4", [[10, 10, 8, 8], None, None])))
    (tmp_path / "nan_labels.json").write_text(
        json.dumps(_labels("V_DRONE_001.mp4", [[10, 10, 8, 8], None, None])).replace("8, 8]", "NaN, 8]", 1))
    (tmp_path / "v.mp4").write_bytes(b"")  # never opened: every case fails before the video is read
    (tmp_path / "ckpt.pt").write_bytes(b"")  # never loaded, likewise
    (tmp_path / "fit.json").write_text("{}")
    (tmp_path / "a_file.txt").write_text("in the way\n")
    (tmp_path / "a_dir").mkdir()
    (tmp_path / "videos").mkdir()
    return {"tmp": tmp_path, "seeds": seeds, "dets": tmp_path / "dets.json", "labels": tmp_path / "labels",
            "label": tmp_path / "labels" / "V_DRONE_001.json", "other_label": tmp_path / "V_DRONE_002.json",
            "nan_label": tmp_path / "nan_labels.json", "video": tmp_path / "v.mp4", "ckpt": tmp_path / "ckpt.pt",
            "fit": tmp_path / "fit.json", "file": tmp_path / "a_file.txt", "dir": tmp_path / "a_dir",
            "videos": tmp_path / "videos", "new": tmp_path / "new_out", "under_file": tmp_path / "a_file.txt" / "x"}


DEMO = ["demo", "--out", "{new}"]
EXPERIMENT = ["experiment", "fig11_ratio", "--out", "{new}"]
INGEST = ["ingest", "--videos", "{videos}", "--labels", "{labels}", "--no-progress"]
FIT = ["fit", "--seed-set", "{seeds}", "--no-progress"]
DETECT = ["detect", "--video", "{video}", "--checkpoint", "{ckpt}"]
EVALUATE = ["evaluate", "--detections", "{dets}", "--labels", "{labels}"]
DIAGNOSE = ["diagnose", "--seed-set", "{seeds}", "--params", "{fit}", "--no-progress"]
PREVIEW = ["preview"]

# (id, argv, text the error must hold: the option it names)
CASES = [
    # synthaug demo: numbers are refused as they are parsed, --hidden and --out before the first video is made
    ("demo-ratio-negative", DEMO + ["--ratio", "-1"], "--ratio"),
    ("demo-ratio-nan", DEMO + ["--ratio", "nan"], "--ratio"),
    ("demo-ratio-inf", DEMO + ["--ratio", "inf"], "--ratio"),
    ("demo-ratio-text", DEMO + ["--ratio", "lots"], "--ratio"),
    ("demo-hidden-unknown", DEMO + ["--hidden", "rainbow"], "--hidden"),
    ("demo-videos-1", DEMO + ["--videos", "1"], "--videos"),
    ("demo-frames-0", DEMO + ["--frames", "0"], "--frames"),
    ("demo-seed-counts-0", DEMO + ["--seed-counts", "0"], "--seed-counts"),
    ("demo-budget-5", DEMO + ["--budget", "5"], "--budget"),
    ("demo-frame-stride-0", DEMO + ["--frame-stride", "0"], "--frame-stride"),
    ("demo-diagnosis-seeds-2", DEMO + ["--diagnosis-seeds", "2"], "--diagnosis-seeds"),
    ("demo-out-is-a-file", ["demo", "--out", "{file}"], "--out"),
    ("demo-out-under-a-file", ["demo", "--out", "{under_file}"], "--out"),
    # synthaug experiment
    ("experiment-ratios-negative", EXPERIMENT + ["--ratios", "1", "-1"], "--ratios"),
    ("experiment-ratios-nan", EXPERIMENT + ["--ratios", "nan"], "--ratios"),
    ("experiment-seed-counts-0", EXPERIMENT + ["--seed-counts", "0"], "--seed-counts"),
    ("experiment-frame-stride-0", EXPERIMENT + ["--frame-stride", "0"], "--frame-stride"),
    ("experiment-scales-0", EXPERIMENT + ["--scales", "0"], "--scales"),
    ("experiment-fit-budget-3", EXPERIMENT + ["--fit-budget", "3"], "--fit-budget"),
    ("experiment-threads-0", EXPERIMENT + ["--threads", "0"], "--threads"),
    ("experiment-distances-unknown", EXPERIMENT + ["--distances", "hog", "bogus"], "--distances"),
    ("experiment-out-is-a-file", ["experiment", "fig11_ratio", "--out", "{file}"], "--out"),
    # synthaug ingest: --out must be a folder
    ("ingest-out-is-a-file", INGEST + ["--out", "{file}"], "--out"),
    ("ingest-out-under-a-file", INGEST + ["--out", "{under_file}"], "--out"),
    ("ingest-patch-size-4", INGEST + ["--out", "{new}", "--patch-size", "4"], "--patch-size"),
    ("ingest-object-fraction-0", INGEST + ["--out", "{new}", "--object-fraction", "0"], "--object-fraction"),
    ("ingest-object-fraction-1.5", INGEST + ["--out", "{new}", "--object-fraction", "1.5"], "--object-fraction"),
    ("ingest-seed-counts-0", INGEST + ["--out", "{new}", "--seed-counts", "12", "0"], "--seed-counts"),
    ("ingest-per-video-0", INGEST + ["--out", "{new}", "--per-video", "0"], "--per-video"),
    ("ingest-workers-0", INGEST + ["--out", "{new}", "--workers", "0"], "--workers"),
    ("ingest-limit-negative", INGEST + ["--out", "{new}", "--limit", "-1"], "--limit"),
    # synthaug fit: --out must be a file
    ("fit-out-is-a-dir", FIT + ["--out", "{dir}"], "--out"),
    ("fit-out-under-a-file", FIT + ["--out", "{under_file}"], "--out"),
    ("fit-budget-5", FIT + ["--out", "{new}", "--budget", "5"], "--budget"),
    ("fit-step-deg-0", FIT + ["--out", "{new}", "--step-deg", "0"], "--step-deg"),
    ("fit-sprite-size-4", FIT + ["--out", "{new}", "--sprite-size", "4"], "--sprite-size"),
    ("fit-object-scale-2", FIT + ["--out", "{new}", "--object-scale", "2"], "--object-scale"),
    ("fit-workers-0", FIT + ["--out", "{new}", "--workers", "0"], "--workers"),
    ("fit-distance-unknown", FIT + ["--out", "{new}", "--distance", "bogus"], "--distance"),
    ("fit-effects-unknown", FIT + ["--out", "{new}", "--effects", "rainbow"], "--effects"),
    ("fit-seed-set-not-a-seed-set", ["fit", "--seed-set", "{dir}", "--out", "{new}"], "--seed-set"),
    ("fit-dask-nobody-listens", FIT + ["--out", "{new}", "--dask", "tcp://127.0.0.1:1"], "--dask"),
    ("fit-dask-not-an-address", FIT + ["--out", "{new}", "--dask", "scheduler"], "--dask"),
    # synthaug detect: --out must be a file; checked before the checkpoint is loaded
    ("detect-out-is-a-dir", DETECT + ["--out", "{dir}"], "--out"),
    ("detect-out-under-a-file", DETECT + ["--out", "{under_file}"], "--out"),
    ("detect-frame-stride-0", DETECT + ["--out", "{new}", "--frame-stride", "0"], "--frame-stride"),
    ("detect-nms-iou-2", DETECT + ["--out", "{new}", "--nms-iou", "2"], "--nms-iou"),
    ("detect-scales-0", DETECT + ["--out", "{new}", "--scales", "1", "0"], "--scales"),
    ("detect-max-detections-0", DETECT + ["--out", "{new}", "--max-detections", "0"], "--max-detections"),
    ("detect-score-threshold-nan", DETECT + ["--out", "{new}", "--score-threshold", "nan"], "--score-threshold"),
    ("detect-video-is-a-dir", ["detect", "--video", "{dir}", "--checkpoint", "{ckpt}", "--out", "{new}"],
     "--video"),
    ("detect-images-missing", ["detect", "--images", "{new}", "--checkpoint", "{ckpt}", "--out", "{tmp}/d.json"],
     "--images"),
    # synthaug evaluate: --out must be a folder
    ("evaluate-out-is-a-file", EVALUATE + ["--out", "{file}"], "--out"),
    ("evaluate-out-under-a-file", EVALUATE + ["--out", "{under_file}"], "--out"),
    ("evaluate-iou-0", EVALUATE + ["--out", "{new}", "--iou", "0"], "--iou"),
    ("evaluate-iou-nan", EVALUATE + ["--out", "{new}", "--iou", "nan"], "--iou"),
    # another video's labels: an error naming both files
    ("evaluate-labels-of-another-video", ["evaluate", "--detections", "{dets}", "--labels", "{other_label}",
                                          "--out", "{new}"], "V_DRONE_002"),
    ("evaluate-label-box-nan", ["evaluate", "--detections", "{dets}", "--labels", "{nan_label}", "--out", "{new}"],
     "non-finite box"),
    # synthaug diagnose
    ("diagnose-alpha-1.5", DIAGNOSE + ["--out", "{new}", "--alpha", "1.5"], "--alpha"),
    ("diagnose-folds-1", DIAGNOSE + ["--out", "{new}", "--folds", "1"], "--folds"),
    ("diagnose-out-is-a-file", DIAGNOSE + ["--out", "{file}"], "--out"),
    ("diagnose-distance-unknown", DIAGNOSE + ["--out", "{new}", "--distance", "bogus"], "--distance"),
    ("diagnose-extended-fit-is-a-dir", DIAGNOSE + ["--out", "{new}", "--extended-fit", "{dir}"], "--extended-fit"),
    # synthaug preview: checked before the view cache is built
    ("preview-n-0", PREVIEW + ["--out", "{tmp}/p.png", "--n", "0"], "--n"),
    ("preview-patch-size-4", PREVIEW + ["--out", "{tmp}/p.png", "--patch-size", "4"], "--patch-size"),
    ("preview-step-deg-90", PREVIEW + ["--out", "{tmp}/p.png", "--step-deg", "90"], "--step-deg"),
    ("preview-out-is-a-dir", PREVIEW + ["--out", "{dir}"], "--out"),
    ("preview-out-not-an-image", PREVIEW + ["--out", "{tmp}/p.txt"], "--out"),
    ("preview-effects-unknown", PREVIEW + ["--out", "{tmp}/p.png", "--effects", "rainbow"], "--effects"),
    ("preview-seed-set-not-a-seed-set", PREVIEW + ["--out", "{tmp}/p.png", "--seed-set", "{dir}"], "--seed-set"),
    # synthaug bench render
    ("bench-batch-size-0", ["bench", "render", "--batch-size", "0"], "--batch-size"),
    ("bench-patch-size-4", ["bench", "render", "--patch-size", "4"], "--patch-size"),
    ("bench-step-deg-negative", ["bench", "render", "--step-deg", "-5"], "--step-deg"),
]


def _snapshot(root):
    return sorted((str(p.relative_to(root)), p.is_dir(), None if p.is_dir() else p.stat().st_size)
                  for p in root.rglob("*"))


def _run(argv):
    try:
        return main(argv)
    except SystemExit as e:  # argparse refuses a bad value as it parses: exit 2, its message on stderr
        return e.code


@pytest.mark.parametrize("argv, needle", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_input_exits_2_naming_the_option_and_writes_nothing(argv, needle, inputs, capsys, monkeypatch):
    root = inputs["tmp"]
    monkeypatch.chdir(root)  # a default output path (demo's outputs/demo, preview.png) would land here
    argv = [a.format(**inputs) for a in argv]
    before = _snapshot(root)
    rc = _run(argv)
    err = capsys.readouterr().err
    assert rc == 2, err
    message = err.strip().splitlines()[-1]  # the error line (argparse prints its usage, naming every option, above)
    assert needle in message, err
    print(message)
    assert "Traceback" not in err
    assert _snapshot(root) == before, "a rejected command wrote something"


def test_the_table_covers_every_command_with_an_output():
    commands = {c[1][0] for c in CASES}
    assert {"demo", "experiment", "ingest", "fit", "detect", "evaluate", "diagnose", "preview", "bench"} <= commands
    assert len(CASES) >= 30


# SyntheticObjectDataset: every argument is checked whether or not it is used (real=None or not)
DATASET_CASES = [
    ("synthetic-per-real-negative-without-real", {"synthetic_per_real": -1, "length": 4}, "synthetic_per_real"),
    ("synthetic-per-real-nan", {"synthetic_per_real": math.nan, "length": 4}, "synthetic_per_real"),
    ("synthetic-per-real-bool", {"synthetic_per_real": True, "length": 4}, "synthetic_per_real"),
    ("patch-size-fraction", {"patch_size": 40.7, "length": 4}, "patch_size"),
    ("patch-size-small", {"patch_size": 4, "length": 4}, "patch_size"),
    ("length-negative", {"length": -1}, "length"),
    ("length-fraction", {"length": 2.5}, "length"),
    ("length-and-real", {"length": 4, "real": [(np.zeros((40, 40), np.uint8), 1)]}, "length"),
    ("length-missing", {}, "length"),
]


@pytest.mark.parametrize("kwargs, name", [c[1:] for c in DATASET_CASES], ids=[c[0] for c in DATASET_CASES])
def test_dataset_rejects_bad_arguments_naming_them(kwargs, name):
    from synthaug.data.synthetic import SyntheticObjectDataset

    bgs = [np.full((48, 48), 128, np.uint8)]
    with pytest.raises(ValueError, match=name):
        SyntheticObjectDataset("quadcopter", bgs, **kwargs)


def test_dataset_takes_an_integral_float_patch_size(small_cache):
    from synthaug.data.synthetic import SyntheticObjectDataset

    ds = SyntheticObjectDataset("quadcopter", [np.full((48, 48), 128, np.uint8)], length=1, patch_size=np.float64(24),
                                render=small_cache)
    assert ds.patch_size == 24 and isinstance(ds.patch_size, int)


def test_a_live_dask_scheduler_is_connected_to(tmp_path):
    """The --dask probe refuses a dead address (the table above) but lets a live one through."""
    distributed = pytest.importorskip("distributed")
    from synthaug.fit.fitting import _dask_client

    with distributed.LocalCluster(n_workers=0, processes=False, protocol="tcp", host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        client = _dask_client(cluster.scheduler_address)
        try:
            assert client.scheduler_info()["address"] == cluster.scheduler_address
        finally:
            client.close()


def test_boxes_of_no_size_are_no_ground_truth(tmp_path):
    """A label box of zero or negative width/height counts as nothing to find (with a warning naming the file),
    so it neither lowers recall nor hides a frame's real box."""
    from synthaug.evaluate.cli import evaluate_files, load_labels

    label = tmp_path / "V_DRONE_001.json"
    label.write_text(json.dumps(_labels("V_DRONE_001.mp4",
                                        [[[10, 10, 8, 8], [30, 30, 0, 8]], [5, 5, -3, 4], [1, 1, 4, 4]])))
    with pytest.warns(UserWarning, match=r"V_DRONE_001\.json.*2 frame\(s\).*zero or negative"):
        _, frames = load_labels(label)
    assert frames[0].tolist() == [[10, 10, 8, 8]] and frames[1] is None and frames[2].tolist() == [[1, 1, 4, 4]]
    dets = tmp_path / "dets.json"
    dets.write_text(json.dumps({"video": "V_DRONE_001.mp4", "input": "video",
                                "detections": [[[10, 10, 8, 8, 0.9]], [], [[1, 1, 4, 4, 0.8]]]}))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result, metrics = evaluate_files([dets], [label])
    assert metrics["n_ground_truth"] == 2 and metrics["ap"] == pytest.approx(1.0)


def test_labels_of_another_video_are_an_error_naming_both(tmp_path):
    from synthaug.evaluate.cli import pair_files

    dets = tmp_path / "dets.json"
    dets.write_text(json.dumps({"video": "V_DRONE_001.mp4", "input": "video", "detections": [[]]}))
    label = tmp_path / "l.json"
    label.write_text(json.dumps(_labels("V_DRONE_002.mp4", [None])))
    with pytest.raises(ValueError, match="V_DRONE_001.*V_DRONE_002"):
        pair_files([dets], [label])
    # the same video under another file name is paired; frames from a folder (no video name) too
    label.write_text(json.dumps(_labels("V_DRONE_001.mp4", [None])))
    assert pair_files([dets], [label]) == [(dets, label)]
    dets.write_text(json.dumps({"video": "frames", "input": "images", "detections": [[]]}))
    label.write_text(json.dumps(_labels("V_DRONE_002.mp4", [None])))
    assert pair_files([dets], [label]) == [(dets, label)]


def test_evaluate_reads_label_files_with_the_ingest_reader_rules(tmp_path):
    """Issue 17: `synthaug evaluate` and ingestion read a label file with one reader
    (synthaug.data.video.read_labels). The evaluation's own copy accepted two files the shared
    halmstad format does not allow, which ingestion refused: one without a ``class`` and one whose
    ``boxes`` list is empty (it labels no frame, so it silently evaluated nothing). Both are errors now."""
    from synthaug.data.video import read_labels
    from synthaug.evaluate.cli import load_labels

    no_class = tmp_path / "V_DRONE_001.json"
    no_class.write_text(json.dumps({"video": "V_DRONE_001.mp4", "box_format": "xywh_pixels", "boxes": [[1, 1, 4, 4]]}))
    empty = tmp_path / "V_DRONE_002.json"
    empty.write_text(json.dumps(_labels("V_DRONE_002.mp4", [])))
    for bad, match in ((no_class, "missing 'class'"), (empty, "holds no per-frame boxes")):
        with pytest.raises(ValueError, match=match):
            read_labels(bad)
        with pytest.raises(ValueError, match=match):
            load_labels(bad)
    # the evaluation's extensions stay: several boxes in a frame, [] for none; a file without "video" is its stem
    ok = tmp_path / "V_DRONE_003.json"
    ok.write_text(json.dumps({"class": "drone", "box_format": "xywh_pixels", "boxes": [[[1, 1, 4, 4], [9, 9, 2, 2]], [], None]}))
    video, frames = load_labels(ok)
    assert video == "V_DRONE_003" and frames[0].shape == (2, 4) and frames[1] is None and frames[2] is None
    # ingestion keeps one box per frame (the shared format): a two-box entry is a NaN box for clip_boxes to drop
    assert np.isnan(read_labels(ok).boxes[0]).all()
