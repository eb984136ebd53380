"""`synthaug train` end to end on a folder of generated videos (non-contiguous numbering), then `synthaug detect`."""

from __future__ import annotations

import json
import os
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest
import torch

from synthaug.cli import main as cli_main
from synthaug.detectors.hog_dpm import HOGDetector

DRONES = ["V_DRONE_003", "V_DRONE_010", "V_DRONE_027"]
# small budgets: tiny frames, one pyramid level pair, every 3rd frame mined and validated
# --threads 1: every training at one thread, whatever ran before it in this process (synthaug detect sets torch's
# threads to 1 for the process; a training's floating point depends on the thread count)
FAST = ["--scales", "1.0", "0.8", "--mining-stride", "3", "--val-stride", "3", "--mining-rounds", "2", "--hog-components", "2",
        "--extra-negatives", "300", "--workers", "1", "--quiet", "--threads", "1"]


@pytest.fixture(scope="module")
def ws(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    from synthaug.data.synthvideo import make_panning_video

    root = tmp_path_factory.mktemp("train_cli")
    for i, stem in enumerate(DRONES):
        make_panning_video(root, n_frames=12, size=(160, 128), seed=i, name=stem)
    make_panning_video(root, n_frames=12, size=(160, 128), seed=7, name="V_BIRD_002", class_name="bird")
    return {"root": root, "videos": root / "videos", "labels": root / "labels"}


def _refused_by_train_parser(extra: list[str], message: str, capsys: pytest.CaptureFixture[str]) -> None:
    """``synthaug train``'s parser exits on ``extra`` (after the required options) with a usage error naming
    ``message``."""
    import argparse

    from synthaug.detectors.train_cli import add_arguments

    parser = argparse.ArgumentParser(prog="synthaug train")
    add_arguments(parser)
    with pytest.raises(SystemExit) as e:
        parser.parse_args(["--detector", "hog", "--class", "drone", "--videos", "v", "--labels", "l", "--out", "o",
                           *extra])
    assert e.value.code == 2 and message in capsys.readouterr().err


def _train(ws: dict[str, Path], out: Path, *extra: str) -> int:
    return cli_main(["train", "--class", "drone", "--videos", str(ws["videos"]), "--labels", str(ws["labels"]),
                     "--out", str(out), *FAST, *extra])


@pytest.fixture(scope="module")
def trained(ws: dict[str, Path]) -> dict[str, Any]:
    out = ws["root"] / "runs" / "hog.pt"
    rc = _train(ws, out, "--detector", "hog", "--seed-counts", "8", "--seed", "0")
    assert rc == 0
    return {"out": out, "meta": json.loads(out.with_suffix(".json").read_text())}


@pytest.mark.parametrize("model", ["ridge", "cnn"])
def test_box_model_option_fits_that_map(ws: dict[str, Path], tmp_path: Path, model: str) -> None:
    from synthaug.detectors.base import load_detector
    from synthaug.detectors.box_cnn import CNNBoxRegressor, EnsembleBoxRegressor
    from synthaug.detectors.boxes import BoxRegressor

    out = tmp_path / f"{model}.pt"
    assert _train(ws, out, "--detector", "hog", "--seed-counts", "8", "--seed", "0", "--mining-rounds", "0",
                  "--box-model", model) == 0
    box = json.loads(out.with_suffix(".json").read_text())["box_regression"]
    reg = load_detector(out).box_regressor
    assert box["model"] == model
    if model == "ridge":
        assert float(box["ridge"]) in [float(r) for r in box["cv_mse"]] and isinstance(reg, BoxRegressor)
    else:
        assert box["samples"] > 0 and isinstance(reg, CNNBoxRegressor) and not isinstance(reg, EnsembleBoxRegressor)


@pytest.mark.slow
def test_box_calibration_corrects_the_trained_detectors_own_boxes(ws: dict[str, Path], tmp_path: Path) -> None:
    """``--box-calibration 1``: the saved detector's box map is followed by the correction that
    :func:`calibrate_boxes` fits on its training videos' frames, recorded in the metadata."""
    from synthaug.detectors.base import load_detector
    from synthaug.detectors.box_calibration import CalibratedBoxRegressor, calibrate_boxes
    from synthaug.detectors.sliding import detect_multiscale
    from synthaug.detectors.boxes import BoxRegressor
    from synthaug.detectors.frames import VideoFrames

    out = tmp_path / "cal.pt"
    assert _train(ws, out, "--detector", "hog", "--seed-counts", "8", "--seed", "0", "--mining-rounds", "0",
                  "--box-model", "ridge", "--box-calibration", "1") == 0
    meta = json.loads(out.with_suffix(".json").read_text())
    det = load_detector(out)
    assert isinstance(det.box_regressor, CalibratedBoxRegressor) and isinstance(det.box_regressor.base, BoxRegressor)
    assert meta["options"]["box_calibration"] == 1 and meta["box_calibration"]["stride"] == 1
    assert meta["box_calibration"]["frames"] == 12 * len(meta["split"]["train"])  # every frame of the training videos
    assert meta["box_calibration"]["pairs"] >= 20
    # the same correction, fitted again on the uncorrected detector
    det.box_regressor = det.box_regressor.base
    again = calibrate_boxes(det, VideoFrames(ws["videos"], ws["labels"], positive=meta["split"]["train"], stride=1),
                            scales=(1.0, 0.8), detect=detect_multiscale)
    assert again.meta["coef"] == meta["box_calibration"]["coef"] and meta["box_calibration"]["form"] == "regression"
    # --box-calibration-form inverse: the size term fitted the other way round, on the same detections
    out = tmp_path / "inverse.pt"
    assert _train(ws, out, "--detector", "hog", "--seed-counts", "8", "--seed", "0", "--mining-rounds", "0",
                  "--box-model", "ridge", "--box-calibration", "1", "--box-calibration-form", "inverse") == 0
    inv = json.loads(out.with_suffix(".json").read_text())["box_calibration"]
    assert inv["form"] == "inverse" and inv["pairs"] == meta["box_calibration"]["pairs"]
    assert inv["coef"] == calibrate_boxes(det, VideoFrames(ws["videos"], ws["labels"], positive=meta["split"]["train"],
                                                           stride=1),
                                          scales=(1.0, 0.8), form="inverse", detect=detect_multiscale).meta["coef"]
    # too few labelled frames at the stride to fit a correction: the box map is kept, and the metadata says why
    out = tmp_path / "few.pt"
    assert _train(ws, out, "--detector", "hog", "--seed-counts", "8", "--seed", "0", "--mining-rounds", "0",
                  "--box-model", "ridge", "--box-calibration", "12") == 0
    few = json.loads(out.with_suffix(".json").read_text())["box_calibration"]
    assert few["stride"] == 12 and "at least 20 needed" in few["skipped"]
    assert isinstance(load_detector(out).box_regressor, BoxRegressor)


@pytest.mark.slow
def test_box_regressor_is_cached_in_the_work_folder_by_its_inputs(ws: dict[str, Path], tmp_path: Path) -> None:
    # the box map depends on the training videos' labels, the model, the stride, the aspect and the seed, not on
    # the detector: a second training into the same --work reads it back (the same state); another seed, a changed
    # label file or a damaged cache file fits it again
    import shutil

    from synthaug.detectors.base import load_detector
    from synthaug.detectors.training import TrainOptions
    from synthaug.detectors.video_training import box_regressor_key, discover_videos

    work = tmp_path / "work"

    def train(name: str, *extra: str) -> tuple[dict[str, Any], Any]:
        out = tmp_path / f"{name}.pt"
        assert _train(ws, out, "--seed-counts", "8", "--mining-rounds", "0", "--box-model", "ridge",
                      "--work", str(work), *extra) == 0
        return json.loads(out.with_suffix(".json").read_text())["box_regression"], load_detector(out).box_regressor

    first, reg1 = train("hog", "--detector", "hog", "--seed", "0")
    seed0_files = list((work / "box_regressors").glob("ridge_*.pt"))
    assert "cached" not in first and len(seed0_files) == 1
    again, reg2 = train("ada", "--detector", "adaboost", "--seed", "0", "--ada-rounds", "5")
    assert again["cached"].startswith(str(work / "box_regressors")) and again["fit_seconds"] == first["seconds"]

    def same(a: Any, b: Any) -> bool:
        if isinstance(a, torch.Tensor):
            return isinstance(b, torch.Tensor) and torch.equal(a, b)
        if isinstance(a, dict):
            return isinstance(b, dict) and a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
        if isinstance(a, (list, tuple)):
            return isinstance(b, (list, tuple)) and len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
        return a == b

    assert same(reg1.state_dict(), reg2.state_dict()) and type(reg1) is type(reg2)
    other, _ = train("hog1", "--detector", "hog", "--seed", "1")
    assert "cached" not in other and len(list((work / "box_regressors").glob("ridge_*.pt"))) == 2
    seed0_files[0].write_bytes(b"not a checkpoint")
    damaged, _ = train("hog0", "--detector", "hog", "--seed", "0")
    assert "cached" not in damaged
    assert torch.load(seed0_files[0], weights_only=False)["format"] == "synthaug.box_regressor_cache"  # replaced
    # the key: every input of the fit, and nothing else
    vs = discover_videos(ws["videos"], ws["labels"])
    stems = sorted(s for s, c in vs.classes.items() if c == "drone")
    base = box_regressor_key(vs, stems, TrainOptions(), 1.0, 0)
    assert base == box_regressor_key(vs, list(reversed(stems)), TrainOptions(mining_rounds=0, ada_rounds=7), 1.0, 0)
    changed = {box_regressor_key(vs, stems, TrainOptions(), 1.0, 1), box_regressor_key(vs, stems[:2], TrainOptions(), 1.0, 0),
               box_regressor_key(vs, stems, TrainOptions(box_model="cnn"), 1.0, 0),
               box_regressor_key(vs, stems, TrainOptions(box_stride=3), 1.0, 0),
               box_regressor_key(vs, stems, TrainOptions(), 1.2, 0)}
    assert base not in changed and len(changed) == 5
    video = next(ws["videos"].glob(f"{stems[0]}.*"))  # a new time stamp on the same bytes (a copied folder): same key
    st = video.stat()
    os.utime(video, ns=(st.st_atime_ns, st.st_mtime_ns + 10**12))
    assert box_regressor_key(vs, stems, TrainOptions(), 1.0, 0) == base
    os.utime(video, ns=(st.st_atime_ns, st.st_mtime_ns))
    copy = tmp_path / "labels_copy"
    shutil.copytree(ws["labels"], copy)
    doc = json.loads((copy / f"{stems[0]}.json").read_text())
    doc["boxes"][0] = [v + 1 for v in doc["boxes"][0]] if doc["boxes"][0] else doc["boxes"][0]
    (copy / f"{stems[0]}.json").write_text(json.dumps(doc))
    assert box_regressor_key(discover_videos(ws["videos"], copy), stems, TrainOptions(), 1.0, 0) != base


def test_two_trainings_needing_one_box_regressor_fit_it_once(ws: dict[str, Path], tmp_path: Path,
                                                             monkeypatch: pytest.MonkeyPatch) -> None:
    # two trainings started side by side (threads here; processes in the experiments) with the same inputs: the
    # first fits the box map under its lock, the second waits and reads the very same map back
    import threading
    import time

    from synthaug.detectors import video_training as VT
    from synthaug.detectors.training import TrainOptions

    vs = VT.discover_videos(ws["videos"], ws["labels"])
    sp = {"train": sorted(s for s, c in vs.classes.items() if c == "drone")}
    fits: list[int] = []
    real_fit = VT._fit_box_regressor

    def slow_fit(*a: Any, **k: Any) -> Any:
        fits.append(1)
        time.sleep(1.0)  # long enough for the other thread to reach the lock
        return real_fit(*a, **k)

    monkeypatch.setattr(VT, "_fit_box_regressor", slow_fit)
    out: dict[int, Any] = {}

    def run(i: int) -> None:
        out[i] = VT._box_regressor(vs, sp, TrainOptions(box_model="ridge"), (0, 0, 20, 20), seed=0,
                                   say=lambda m: None, cache_dir=tmp_path / "box")

    threads = [threading.Thread(target=run, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert fits == [1] and len(list((tmp_path / "box").glob("ridge_*.pt"))) == 1
    infos = sorted((out[0][1], out[1][1]), key=lambda d: "cached" in d)
    assert "cached" not in infos[0] and infos[1]["fit_seconds"] == infos[0]["seconds"]  # one fitted, one read back
    assert torch.equal(out[0][0].state_dict()["weights"], out[1][0].state_dict()["weights"])


def test_two_trainings_on_one_ingest_folder_take_turns(ws: dict[str, Path], tmp_path: Path,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    # the runner's jobs side by side on one ingest folder: the ingest rewrites the seed set even when every video is
    # reused, and a second process swapping the folder at the same time failed (stop 81). With the lock the two
    # ingests never overlap and both read the same seed set.
    import threading
    import time

    import numpy as np

    from synthaug.data import ingest as ingest_mod
    from synthaug.detectors import video_training as VT

    vs = VT.discover_videos(ws["videos"], ws["labels"])
    sp = {"class": "drone", "train": sorted(s for s, c in vs.classes.items() if c == "drone"),
          "negative_train": sorted(s for s, c in vs.classes.items() if c != "drone")}
    real_ingest = ingest_mod.ingest_videos
    active, overlap = [0], [0]
    guard = threading.Lock()

    def slow_ingest(*a: Any, **k: Any) -> Any:
        with guard:
            active[0] += 1
            overlap[0] = max(overlap[0], active[0])
        try:
            time.sleep(0.5)  # long enough for the other thread to arrive
            return real_ingest(*a, **k)
        finally:
            with guard:
                active[0] -= 1

    monkeypatch.setattr(ingest_mod, "ingest_videos", slow_ingest)
    out: dict[int, Any] = {}
    errors: list[BaseException] = []

    def run(i: int) -> None:
        try:
            out[i] = VT._seed_set_by_ingest(vs, sp, 6, tmp_path / "work", ingest_seed=0, workers=1,
                                            log=lambda m: None, negative_classes=("bird",))
        except BaseException as e:  # noqa: BLE001 - reported by the assertion below
            errors.append(e)

    threads = [threading.Thread(target=run, args=(i,)) for i in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == [] and overlap[0] == 1 and len(out) == 3
    assert all(np.array_equal(out[0].patches, out[i].patches) for i in (1, 2)) and len(out[0]) >= 6


@pytest.mark.slow
def test_mining_round_choice_options_reach_the_training(ws: dict[str, Path], tmp_path: Path) -> None:
    # --mining-select / --mining-patience (the runner's options) are synthaug train's too, and recorded
    out = tmp_path / "ap.pt"
    assert _train(ws, out, "--detector", "hog", "--seed-counts", "8", "--seed", "0", "--box-model", "ridge",
                  "--mining-select", "ap", "--mining-patience", "1") == 0
    meta = json.loads(out.with_suffix(".json").read_text())
    assert meta["options"]["mining_select"] == "ap" and meta["options"]["mining_patience"] == 1
    assert meta["mining"]["mining"]["frame_scale"] == [1.0, 1.0]  # the family's default: native frames
    assert meta["mining"]["mining"]["select"] == "ap" and meta["mining"]["mining"]["patience"] == 1
    rounds = meta["mining"]["rounds"]
    aps = [r["val"]["ap"] for r in rounds if r.get("val")]
    assert aps and rounds[meta["mining"]["chosen_round"]]["val"]["ap"] == max(aps)  # the round of the highest AP


@pytest.mark.slow
def test_train_then_detect_end_to_end(ws: dict[str, Path], trained: dict[str, Any], capsys: pytest.CaptureFixture[str]) -> None:
    from synthaug.detectors.base import load_detector

    det = load_detector(trained["out"])
    assert det.kind == "hog" and det.box_in_window is not None
    assert det.box_regressor is not None  # the annotators' box convention, learned from the training labels
    box = trained["meta"]["box_regression"]
    assert box["videos"] == len(trained["meta"]["split"]["train"])  # every drone training video (not the bird)
    assert box["model"] == "ensemble"  # TrainOptions.box_model's default: the ridge and the CNN maps' mean
    ridge, cnn = box["parts"]
    assert (ridge["model"], cnn["model"]) == ("ridge", "cnn") and ridge["samples"] > 0 and cnn["samples"] > 0
    assert float(ridge["ridge"]) in [float(r) for r in ridge["cv_mse"]]
    assert cnn["held_out_mse"] is None and cnn["epoch_kept"] == cnn["epochs"] - 1  # 2 training videos: none held out
    assert [type(p).__name__ for p in det.box_regressor.parts] == ["BoxRegressor", "CNNBoxRegressor"]
    val_video = trained["meta"]["split"]["val"][0]
    dets = ws["root"] / "dets.json"
    capsys.readouterr()
    rc = cli_main(["detect", "--checkpoint", str(trained["out"]), "--video", str(ws["videos"] / f"{val_video}.mp4"),
                   "--out", str(dets), "--frame-stride", "5", "--scales", "1.0", "0.8", "--quiet"])
    assert rc == 0
    payload = json.loads(dets.read_text())
    assert payload["detector"] == "hog" and len(payload["detections"]) == 12
    assert [d is None for d in payload["detections"]] == [i % 5 != 0 for i in range(12)]
    assert all(1 <= len(d) <= 10 for d in payload["detections"] if d is not None)
    # the object is found (8 seeds, tiny frames): one of the 3 best boxes of every processed frame overlaps it
    boxes = json.loads((ws["labels"] / f"{val_video}.json").read_text())["boxes"]
    for i in (0, 5, 10):
        gx, gy, gw, gh = boxes[i]
        assert any(min(x + w, gx + gw) > max(x, gx) and min(y + h, gy + gh) > max(y, gy)
                   for x, y, w, h, _ in payload["detections"][i][:3]), i


def test_metadata_split_by_video_deterministic(ws: dict[str, Path], trained: dict[str, Any]) -> None:
    import synthaug

    meta = trained["meta"]
    sp = meta["split"]
    assert meta["format"] == "synthaug.trained_detector" and meta["synthaug_version"] == synthaug.__version__
    assert meta["detector"] == "hog" and meta["class"] == "drone" and meta["seed"] == 0
    assert sp["source"] == "auto" and sp["seed"] == 0 and sp["fractions"] == {"train": 0.8, "val": 0.2}
    assert sorted(sp["train"] + sp["val"]) == DRONES and not set(sp["train"]) & set(sp["val"])
    assert len(sp["val"]) == 1 and sp["negative_train"] == ["V_BIRD_002"]
    assert meta["positives"]["mode"] == "seeds" and meta["positives"]["count"] == 8
    assert meta["options"]["mining_stride"] == 3 and meta["options"]["scales"] == [1.0, 0.8]
    rounds = meta["mining"]["rounds"]
    assert rounds[0]["added"] == 0 and all(r["added"] > 0 for r in rounds[1:]) and len(rounds) >= 2
    assert all(isinstance(r["val"]["fp"], int) for r in rounds if r["val"] is not None)
    assert meta["negatives"]["final"] == rounds[meta["mining"]["chosen_round"]]["negatives"]
    assert meta["command"]["detector"] == "hog" and meta["command"]["seed_counts"] == 8
    # the same command again: the same split and the same detector (ingest shards reused)
    again = ws["root"] / "runs" / "hog_again.pt"
    assert _train(ws, again, "--detector", "hog", "--seed-counts", "8", "--seed", "0", "--work", str(trained["out"]) + ".work") == 0
    meta2 = json.loads(again.with_suffix(".json").read_text())
    assert meta2["split"] == sp and meta2["mining"]["rounds"][0]["val"] == rounds[0]["val"]
    a, b = torch.load(trained["out"], weights_only=True), torch.load(again, weights_only=True)
    assert torch.equal(a["state"]["weights"], b["state"]["weights"])


@pytest.mark.slow
def test_all_frames_adaboost_and_cnn_from_a_seed_set(ws: dict[str, Path], trained: dict[str, Any],
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    out = ws["root"] / "runs" / "ada.pt"
    assert _train(ws, out, "--detector", "adaboost", "--all-frames", "--frame-step", "2", "--ada-rounds", "10",
                  "--ada-candidates", "200", "--mining-rounds", "1") == 0
    meta = json.loads(out.with_suffix(".json").read_text())
    assert meta["positives"] == {"mode": "all_frames", "frame_step": 2, "count": 12}  # 2 training videos x 12 frames / 2
    assert meta["mining"]["rounds"][1]["added"] > 0
    out = ws["root"] / "runs" / "cnn.pt"
    seedset = trained["meta"]["positives"]["seedset"]
    import synthaug.detectors.lightning_module as lm

    fitted, fit = [], lm.fit_patch_detector
    monkeypatch.setattr(lm, "fit_patch_detector", lambda p, n, **kw: fitted.append(len(p)) or fit(p, n, **kw))
    assert _train(ws, out, "--detector", "cnn", "--seedset", seedset, "--cnn-epochs", "2", "--mining-rounds", "0",
                  "--downscaled-copies", "2", "--faded-copies", "1", "--cnn-finetune-epochs", "1") == 0
    meta = json.loads(out.with_suffix(".json").read_text())
    # --cnn-finetune-epochs: trained on every positive, then fine-tuned on the seed set's real positives alone
    real = meta["positives"]["count"]
    assert meta["options"]["cnn_finetune_epochs"] == 1
    assert fitted == [real + meta["downscaled"]["count"] + meta["faded"]["count"], real]
    assert meta["positives"]["mode"] == "seedset" and [r["round"] for r in meta["mining"]["rounds"]] == [0]
    # --downscaled-copies: 2 copies of each seed of at least 16 px, windows down to the pyramid's largest scale (1.0)
    down = meta["downscaled"]
    assert down["copies"] == 2 and down["max_scale"] == 1.0 and down["count"] == 2 * down["seeds_used"] > 0
    # --faded-copies: one fainter copy of every seed, contrast drawn in the default range
    faded = meta["faded"]
    assert faded["copies"] == 1 and faded["count"] == meta["positives"]["count"] and faded["contrast"] == [0.3, 0.9]
    assert 0.3 <= faded["contrast_median"] <= 0.9
    from synthaug.detectors.base import load_detector

    assert load_detector(out).kind == "cnn"
    # --faded-contrast -1 -0.5: the copies are inverted (the object brighter than its background where it was darker)
    out = ws["root"] / "runs" / "hog_inverted.pt"
    assert _train(ws, out, "--detector", "hog", "--seedset", seedset, "--mining-rounds", "0", "--faded-copies", "1",
                  "--faded-contrast", "-1", "-0.5") == 0
    meta = json.loads(out.with_suffix(".json").read_text())
    inv = meta["faded"]
    assert inv["contrast"] == [-1.0, -0.5] and -1.0 <= inv["contrast_median"] <= -0.5
    assert inv["count"] == meta["positives"]["count"]


@pytest.mark.slow
def test_synthetic_positives_from_a_fit(ws: dict[str, Path], trained: dict[str, Any], monkeypatch: pytest.MonkeyPatch) -> None:
    """--params adds ratio x seeds synthetic patches made on the seed set (the generator itself is tested elsewhere)."""
    import synthaug.detectors.video_training as video_training
    from synthaug.params import CaptureParams

    calls = []

    def fake(seedset: Any, mesh: Any, fit_file: Any, count: int, *, seed: int = 0, pose_sampling: str = "uniform",
             object_box: Any = None, shape_variation: float = 0.0, object_box_share: float = 1.0,
             **_: Any) -> torch.Tensor:
        calls.append((len(seedset), str(mesh), count, seed, pose_sampling) + ((object_box,) if object_box else ())
                     + ((shape_variation,) if shape_variation else ())
                     + ((object_box_share,) if object_box_share != 1 else ()))
        return torch.rand(count, 1, 40, 40, generator=torch.Generator().manual_seed(seed))

    monkeypatch.setattr(video_training, "synthetic_positives", fake)
    fit = ws["root"] / "fit8.json"
    CaptureParams.sample(8, generator=torch.Generator().manual_seed(0)).save(fit)
    out = ws["root"] / "runs" / "hog_syn.pt"
    seedset = trained["meta"]["positives"]["seedset"]
    assert _train(ws, out, "--detector", "hog", "--seedset", seedset, "--params", str(fit), "--synthetic-ratio", "3",
                  "--mining-rounds", "0") == 0
    meta = json.loads(out.with_suffix(".json").read_text())
    assert calls == [(8, "quadcopter", 24, 2, "uniform")]
    # HOG's default: the critic keeps a quarter (FAMILY_REALISM_KEEP)
    assert meta["synthetic"] == {"params": str(fit), "mesh": "quadcopter", "ratio": 3.0, "count": 24,
                                 "pose_sampling": "uniform", "realism_keep": 0.25, "realism_selection": "seed"}
    # --pose-sampling reaches the synthetic positives and the metadata; --perturb-copies adds perturbed real ones
    out2 = ws["root"] / "runs" / "hog_syn_fitted.pt"
    assert _train(ws, out2, "--detector", "hog", "--seedset", seedset, "--params", str(fit), "--synthetic-ratio", "3",
                  "--pose-sampling", "fitted", "--perturb-copies", "2", "--copy-paste-ratio", "1.5",
                  "--mining-rounds", "0") == 0
    meta2 = json.loads(out2.with_suffix(".json").read_text())
    assert calls[-1] == (8, "quadcopter", 24, 2, "fitted") and meta2["synthetic"]["pose_sampling"] == "fitted"
    assert meta2["perturbed"] == {"copies": 2, "count": 16}
    assert meta2["synthetic"]["copy_paste"] == {"ratio": 1.5, "count": 12}  # the copy-paste baseline, cut with the fit
    # --object-box seed reaches the synthetic positives and the metadata (absent at its default, above)
    out_box = ws["root"] / "runs" / "hog_syn_box.pt"
    assert _train(ws, out_box, "--detector", "hog", "--seedset", seedset, "--params", str(fit), "--synthetic-ratio", "3",
                  "--object-box", "seed", "--mining-rounds", "0") == 0
    assert calls[-1] == (8, "quadcopter", 24, 2, "uniform", "seed")
    assert json.loads(out_box.with_suffix(".json").read_text())["synthetic"]["object_box"] == "seed"
    assert "object_box_share" not in json.loads(out_box.with_suffix(".json").read_text())["synthetic"]
    # --object-box-share: a mixture of the two framings, in the metadata; without --object-box, a clear error
    out_mix = ws["root"] / "runs" / "hog_syn_mix.pt"
    assert _train(ws, out_mix, "--detector", "hog", "--seedset", seedset, "--params", str(fit),
                  "--synthetic-ratio", "3", "--object-box", "seed", "--object-box-share", "0.5",
                  "--mining-rounds", "0") == 0
    assert calls[-1] == (8, "quadcopter", 24, 2, "uniform", "seed", 0.5)
    assert json.loads(out_mix.with_suffix(".json").read_text())["synthetic"]["object_box_share"] == 0.5
    n_calls = len(calls)
    assert _train(ws, out_mix, "--detector", "hog", "--seedset", seedset, "--params", str(fit),
                  "--synthetic-ratio", "3", "--object-box-share", "0.5", "--mining-rounds", "0") == 2
    assert len(calls) == n_calls
    # --shape-variation likewise (absent from the metadata at its default 0, above)
    out_shape = ws["root"] / "runs" / "hog_syn_shape.pt"
    assert _train(ws, out_shape, "--detector", "hog", "--seedset", seedset, "--params", str(fit), "--synthetic-ratio",
                  "3", "--shape-variation", "0.3", "--mining-rounds", "0") == 0
    assert calls[-1] == (8, "quadcopter", 24, 2, "uniform", 0.3)
    assert json.loads(out_shape.with_suffix(".json").read_text())["synthetic"]["shape_variation"] == 0.3
    assert "shape_variation" not in meta["synthetic"]
    from synthaug.data.seedset import SeedSet
    from synthaug.detectors.training_sets import synthetic_positives  # the real generator: "seed" reads the seed set

    ss = SeedSet.load(seedset)
    x = synthetic_positives(ss, "quadcopter", fit, 4, object_box="seed")
    assert x.shape == (4, 1, ss.patch_size, ss.patch_size) and ss.object_fraction > 0
    # --synthetic-share reaches the SVM as per-positive weights: the 8 real seeds hold 1 - share of the positive half
    seen = []
    real_fit = HOGDetector.fit

    def spy(positives, negatives, **kw):
        seen.append((positives.shape[0], kw.get("positive_weights")))
        return real_fit(positives, negatives, **kw)

    monkeypatch.setattr(HOGDetector, "fit", staticmethod(spy))
    out3 = ws["root"] / "runs" / "hog_syn_share.pt"
    assert _train(ws, out3, "--detector", "hog", "--seedset", seedset, "--params", str(fit), "--synthetic-ratio", "3",
                  "--synthetic-share", "0.25", "--mining-rounds", "0") == 0
    (n, w), = seen
    assert n == 32 and w.shape == (32,)
    assert float(w[:8].sum()) == pytest.approx(0.75 * 32) and float(w[8:].sum()) == pytest.approx(0.25 * 32)
    assert json.loads(out3.with_suffix(".json").read_text())["positives"]["synthetic_share"] == 0.25


@pytest.mark.parametrize("kind", ["cnn", "adaboost"])
def test_synthetic_share_reaches_the_cnn_loss_and_adaboost_start_weights(ws: dict[str, Path], trained: dict[str, Any],
                                                                        monkeypatch: pytest.MonkeyPatch,
                                                                        kind: str) -> None:
    """--synthetic-share for the CNN (its loss's sample weights) and AdaBoost (its positives' starting weights): the 8
    real seeds hold 1 - share of the positive class's weight. AdaBoost with --ada-transfer too: the 24 added
    positives are its source positives; the 8 real ones set its cascade (--ada-cascade real, the default; the CNN is
    given --ada-cascade all, which reaches its metadata and nothing else)."""
    import synthaug.detectors.adaboost as ada
    import synthaug.detectors.lightning_module as lm
    from synthaug.detectors.video_training import AddedPositives, _check_options

    _check_options(kind, AddedPositives(perturb_copies=1, synthetic_share=0.5), frame_step=1, all_frames=False,
                   seedset=None, seed_count=8)  # accepted
    seen, sources, cascades = [], [], []
    module, name, short = ((lm, "fit_patch_detector", {"epochs": 1}) if kind == "cnn" else
                           (ada, "train_adaboost", {"n_rounds": 3, "candidates": 50}))
    real_fit = getattr(module, name)

    def spy(positives, negatives, **kw):
        seen.append((positives.shape[0], kw.get("positive_weights")))
        sources.append(kw.get("source_positives"))
        cascades.append(kw.get("cascade_positives"))
        return real_fit(positives, negatives, **{**kw, **short})

    monkeypatch.setattr(module, name, spy)
    out = ws["root"] / "runs" / f"{kind}_share.pt"
    seedset = trained["meta"]["positives"]["seedset"]
    flags = ["--ada-transfer"] if kind == "adaboost" else ["--ada-cascade", "all"]
    assert _train(ws, out, "--detector", kind, "--seedset", seedset, "--perturb-copies", "3", "--synthetic-share", "0.25",
                  "--mining-rounds", "0", *flags) == 0
    (n, w), *finetune = seen
    assert sources[0] == (24 if kind == "adaboost" else None)
    assert cascades[0] == (8 if kind == "adaboost" else None)
    assert n == 32 and w.shape == (32,)
    # the CNN then fine-tunes on the 8 real positives alone, unweighted (TrainOptions.cnn_finetune_epochs)
    assert finetune == ([(8, None)] if kind == "cnn" else [])
    assert float(w[:8].sum()) == pytest.approx(0.75 * 32) and float(w[8:].sum()) == pytest.approx(0.25 * 32)
    meta = json.loads(out.with_suffix(".json").read_text())
    assert meta["positives"]["synthetic_share"] == 0.25 and meta["options"]["ada_transfer"] == (kind == "adaboost")
    assert meta["options"]["ada_cascade"] == ("real" if kind == "adaboost" else "all")


@pytest.mark.parametrize("kind, share, real_weight", [("adaboost", None, 0.75), ("adaboost", "count", None),
                                                      ("hog", None, None), ("hog", "count", None)])
def test_synthetic_share_default_is_the_familys(ws: dict[str, Path], trained: dict[str, Any],
                                                monkeypatch: pytest.MonkeyPatch, kind: str, share: str | None,
                                                real_weight: float | None) -> None:
    """Without --synthetic-share each family trains with its own share (FAMILY_SYNTHETIC_SHARE): AdaBoost's real
    positives hold 3/4 of the positive weight (the metadata says 0.25), HOG weighs every positive the same (no
    weights, no share in the metadata); --synthetic-share count weighs every positive the same in both."""
    import synthaug.detectors.adaboost as ada

    seen = []
    module, name, short = ((ada, "train_adaboost", {"n_rounds": 3, "candidates": 50}) if kind == "adaboost" else
                           (HOGDetector, "fit", {}))
    real_fit = getattr(module, name)

    def spy(positives, negatives, **kw):
        seen.append((positives.shape[0], kw.get("positive_weights")))
        return real_fit(positives, negatives, **{**kw, **short})

    monkeypatch.setattr(module, name, staticmethod(spy) if kind == "hog" else spy)
    out = ws["root"] / "runs" / f"{kind}_share_{share}.pt"
    seedset = trained["meta"]["positives"]["seedset"]
    flags = [] if share is None else ["--synthetic-share", share]
    assert _train(ws, out, "--detector", kind, "--seedset", seedset, "--perturb-copies", "3", "--mining-rounds", "0",
                  *flags) == 0
    (n, w), = seen
    assert n == 32
    positives = json.loads(out.with_suffix(".json").read_text())["positives"]
    if real_weight is None:
        assert w is None and "synthetic_share" not in positives
    else:
        assert float(w[:8].sum()) == pytest.approx(real_weight * 32) and float(w[8:].sum()) == pytest.approx(8.0)
        assert positives["synthetic_share"] == pytest.approx(1 - real_weight)


def test_synthetic_share_is_a_number_or_count(capsys: pytest.CaptureFixture[str]) -> None:
    from synthaug.detectors.train_cli import synthetic_share_arg

    assert synthetic_share_arg("count") == "count" and synthetic_share_arg("0.25") == 0.25
    with pytest.raises(SystemExit) as e:
        cli_main(["train", "--synthetic-share", "half", "--out", "x.pt"])
    assert e.value.code == 2 and "argument --synthetic-share: must be a number, got 'half'" in capsys.readouterr().err


@pytest.mark.parametrize(
    "case, option",
    [
        ("no_videos", "--videos"),
        ("no_labels", "--labels"),
        ("no_class", "--class"),
        ("bad_detector", "--detector"),
        ("too_many_seeds", "--seed-counts"),
        ("params_rows", "--params"),
        ("ratio_without_params", "--synthetic-ratio"),
        ("params_with_all_frames", "--params"),
        ("negative_perturb_copies", "--perturb-copies"),
        ("negative_copy_paste", "--copy-paste-ratio"),
        ("copy_paste_without_params", "--copy-paste-ratio"),
        ("share_out_of_range", "--synthetic-share"),
        ("share_without_added", "--synthetic-share"),
        ("share_count_without_added", "--synthetic-share"),
        ("quantize_without_synthetic", "--quantize"),
        ("at_seed_with_object_box", "--pose-sampling"),
        ("negative_patience", "--mining-patience"),
        ("frame_scale_reversed", "--mining-frame-scale"),
        ("negative_downscaled", "--downscaled-copies"),
        ("downscaled_with_all_frames", "--downscaled-copies"),
        ("negative_faded", "--faded-copies"),
        ("faded_with_all_frames", "--faded-copies"),
        ("contrast_without_faded", "--faded-contrast"),
        ("contrast_across_zero", "--faded-contrast"),
        ("no_positive_videos", "--positive-videos"),
        ("more_positive_videos_than_training_videos", "--positive-videos"),
        ("capture_sampling_without_synthetic", "--capture-sampling"),
        ("background_sampling_without_synthetic", "--background-sampling"),
        ("effects_off_without_synthetic", "--effects-off"),
        ("effect_off_not_in_the_fit", "--effects-off"),
        ("realism_keep_without_synthetic", "--realism-keep"),
    ],
)
def test_errors_exit_2_naming_the_option(ws: dict[str, Path], trained: dict[str, Any], tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str], case: str, option: str) -> None:
    from synthaug.params import CaptureParams

    fit3 = tmp_path / "fit3.json"
    CaptureParams.sample(3, generator=torch.Generator().manual_seed(0)).save(fit3)
    base = {"--detector": "hog", "--class": "drone", "--videos": str(ws["videos"]), "--labels": str(ws["labels"])}
    extra: list[str] = ["--seed-counts", "8", "--work", str(trained["out"]) + ".work"]
    if case == "no_videos":
        base["--videos"] = str(tmp_path / "nowhere")
    elif case == "no_labels":
        base["--labels"] = str(tmp_path / "nowhere")
    elif case == "no_class":
        base["--class"] = "cat"
    elif case == "bad_detector":
        base["--detector"] = "svm"
    elif case == "too_many_seeds":
        extra = ["--seed-counts", "1000"]
    elif case == "params_rows":
        extra += ["--params", str(fit3)]
    elif case == "ratio_without_params":
        extra += ["--synthetic-ratio", "5"]
    elif case == "params_with_all_frames":
        extra = ["--all-frames", "--params", str(fit3)]
    elif case == "negative_perturb_copies":
        extra += ["--perturb-copies", "-1"]
    elif case == "negative_copy_paste":
        extra += ["--copy-paste-ratio", "-1"]
    elif case == "copy_paste_without_params":
        extra += ["--copy-paste-ratio", "2"]
    elif case == "share_out_of_range":
        extra += ["--perturb-copies", "1", "--synthetic-share", "1.0"]
    elif case == "share_without_added":
        extra += ["--synthetic-share", "0.5"]
    elif case == "share_count_without_added":
        extra += ["--synthetic-share", "count"]
    elif case == "quantize_without_synthetic":
        extra += ["--quantize"]
    elif case == "at_seed_with_object_box":
        extra += ["--pose-sampling", "uniform_at_seed", "--object-box", "seed"]
    elif case == "negative_patience":
        extra += ["--mining-patience", "-1"]
    elif case == "frame_scale_reversed":
        extra += ["--mining-frame-scale", "2", "1"]
    elif case == "negative_downscaled":
        extra += ["--downscaled-copies", "-1"]
    elif case == "downscaled_with_all_frames":
        extra = ["--all-frames", "--downscaled-copies", "1"]
    elif case == "negative_faded":
        extra += ["--faded-copies", "-1"]
    elif case == "faded_with_all_frames":
        extra = ["--all-frames", "--faded-copies", "1"]
    elif case == "contrast_without_faded":
        extra += ["--faded-contrast", "-1", "-0.5"]
    elif case == "contrast_across_zero":
        extra += ["--faded-copies", "1", "--faded-contrast", "-0.5", "0.5"]
    elif case == "no_positive_videos":
        extra += ["--positive-videos", "0"]
    elif case == "more_positive_videos_than_training_videos":
        extra += ["--positive-videos", "999"]
    elif case == "capture_sampling_without_synthetic":
        extra += ["--capture-sampling", "uniform"]
    elif case == "background_sampling_without_synthetic":
        extra += ["--background-sampling", "other"]
    elif case == "effects_off_without_synthetic":
        extra += ["--effects-off", "motion_blur"]
    elif case == "realism_keep_without_synthetic":
        extra += ["--realism-keep", "0.5"]
    elif case == "effect_off_not_in_the_fit":  # rotor_blur is a registered effect, but not one the paper's fit holds
        fit8 = tmp_path / "fit8.json"
        CaptureParams.sample(8, generator=torch.Generator().manual_seed(0)).save(fit8)
        extra += ["--params", str(fit8), "--synthetic-ratio", "1", "--effects-off", "rotor_blur"]
    out = tmp_path / "det.pt"
    argv = ["train", *[x for kv in base.items() for x in kv], "--out", str(out), *FAST, *extra]
    capsys.readouterr()
    assert cli_main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("synthaug train: error: ") and option in err, err
    assert not out.exists()
    if case == "params_rows":
        assert "3 rows" in err and "8 seeds" in err
    if case == "too_many_seeds":
        assert "1000" in err and "24 labelled frames" in err
    if case == "no_class":
        assert "'cat'" in err and "drone" in err
    if case in ("negative_perturb_copies", "negative_copy_paste", "negative_downscaled", "negative_faded"):
        assert "must be >= 0, got -1" in err
    if case == "copy_paste_without_params":
        assert "--params" in err


@pytest.mark.slow
def test_capture_sampling_and_effects_off_reach_the_synthetic_positives(ws: dict[str, Path], trained: dict[str, Any],
                                                                        monkeypatch: pytest.MonkeyPatch,
                                                                        capsys: pytest.CaptureFixture[str]) -> None:
    """--capture-sampling (the paper's Fig. 10) and --effects-off (Fig. 9) reach the generator: the effects left
    out are removed from the fit's own list, in its order; both are in the metadata only when not at the default."""
    import synthaug.detectors.video_training as video_training
    from synthaug.params import CaptureParams

    calls = []

    def fake(seedset: Any, mesh: Any, fit_file: Any, count: int, *, seed: int = 0, capture_sampling: str = "seed",
             effects: Any = None, **_: Any) -> torch.Tensor:
        calls.append((count, capture_sampling, effects))
        return torch.rand(count, 1, 40, 40, generator=torch.Generator().manual_seed(seed))

    monkeypatch.setattr(video_training, "synthetic_positives", fake)
    fit = ws["root"] / "fit8_fig9.json"
    theta = CaptureParams.sample(8, generator=torch.Generator().manual_seed(0))
    theta.save(fit)
    seedset = trained["meta"]["positives"]["seedset"]
    out = ws["root"] / "runs" / "hog_fig9.pt"
    assert _train(ws, out, "--detector", "hog", "--seedset", seedset, "--params", str(fit), "--synthetic-ratio", "2",
                  "--capture-sampling", "uniform", "--effects-off", "motion_blur", "object_noise",
                  "--mining-rounds", "0") == 0
    kept = [e for e in theta.effects if e not in ("motion_blur", "object_noise")]
    assert calls == [(16, "uniform", kept)] and kept == ["boundary_blur", "material"]
    syn = json.loads(out.with_suffix(".json").read_text())["synthetic"]
    assert syn["capture_sampling"] == "uniform" and syn["effects_off"] == ["motion_blur", "object_noise"]
    out2 = ws["root"] / "runs" / "hog_fig9_default.pt"
    assert _train(ws, out2, "--detector", "hog", "--seedset", seedset, "--params", str(fit), "--synthetic-ratio", "2",
                  "--mining-rounds", "0") == 0
    assert calls[-1] == (16, "seed", None)
    syn2 = json.loads(out2.with_suffix(".json").read_text())["synthetic"]
    assert "capture_sampling" not in syn2 and "effects_off" not in syn2 and "quantize" not in syn2
    # --quantize reaches the generator and the metadata
    out3 = ws["root"] / "runs" / "hog_fig9_8bit.pt"
    quantized = []
    monkeypatch.setattr(video_training, "synthetic_positives",
                        lambda *a, quantize=False, **k: quantized.append(quantize) or fake(*a, **k))
    assert _train(ws, out3, "--detector", "hog", "--seedset", seedset, "--params", str(fit), "--synthetic-ratio", "2",
                  "--mining-rounds", "0", "--quantize") == 0
    assert quantized == [True] and json.loads(out3.with_suffix(".json").read_text())["synthetic"]["quantize"] is True
    out3n = ws["root"] / "runs" / "hog_fig9_native.pt"
    assert _train(ws, out3n, "--detector", "hog", "--seedset", seedset, "--params", str(fit), "--synthetic-ratio",
                  "2", "--mining-rounds", "0", "--quantize", "native_scale") == 0
    assert quantized == [True, "native_scale"]
    assert json.loads(out3n.with_suffix(".json").read_text())["synthetic"]["quantize"] == "native_scale"
    # --realism-keep likewise: HOG's default a quarter (above, syn2), a value given itself; 1 (the paper) is not in
    # the metadata
    assert syn2["realism_keep"] == 0.25
    kept_fractions = []
    monkeypatch.setattr(video_training, "synthetic_positives",
                        lambda *a, realism_keep=1.0, **k: kept_fractions.append(realism_keep) or fake(*a, **k))
    for i, (given, kind) in enumerate(((["--realism-keep", "0.5"], "hog"), (["--realism-keep", "1"], "hog"),
                                       ([], "adaboost"))):  # AdaBoost's quarter: its family's (FAMILY_SYNTHETIC)
        out4 = ws["root"] / "runs" / f"critic_{i}.pt"
        assert _train(ws, out4, "--detector", kind, "--seedset", seedset, "--params", str(fit), "--synthetic-ratio",
                      "2", "--mining-rounds", "0", *given) == 0
        assert json.loads(out4.with_suffix(".json").read_text())["synthetic"].get("realism_keep") == (
            0.5, None, 0.25)[i]
    assert kept_fractions == [0.5, 1.0, 0.25]
    # --realism-selection reaches the generator and the metadata (HOG's default above: seed)
    selections = []
    monkeypatch.setattr(video_training, "synthetic_positives",
                        lambda *a, realism_selection="?", **k: selections.append(realism_selection) or fake(*a, **k))
    out5 = ws["root"] / "runs" / "critic_per_set.pt"
    assert _train(ws, out5, "--detector", "hog", "--seedset", seedset, "--params", str(fit), "--synthetic-ratio", "2",
                  "--mining-rounds", "0", "--realism-selection", "set") == 0
    assert selections == ["set"]
    assert json.loads(out5.with_suffix(".json").read_text())["synthetic"]["realism_selection"] == "set"
    assert syn2["realism_selection"] == "seed"
    # --realism-features likewise (HOG's, the default, is not in the metadata)
    features = []
    monkeypatch.setattr(video_training, "synthetic_positives",
                        lambda *a, realism_features="?", **k: features.append(realism_features) or fake(*a, **k))
    out6 = ws["root"] / "runs" / "critic_weak_learners.pt"
    assert _train(ws, out6, "--detector", "adaboost", "--seedset", seedset, "--params", str(fit), "--synthetic-ratio",
                  "2", "--mining-rounds", "0", "--realism-keep", "0.5", "--realism-features", "weak_learners") == 0
    assert features == ["weak_learners"]
    assert json.loads(out6.with_suffix(".json").read_text())["synthetic"]["realism_features"] == "weak_learners"
    assert "realism_features" not in syn2
    monkeypatch.setattr(video_training, "synthetic_positives", fake)
    # the family's default (effects_off=None): the CNN's synthetic positives leave the fitted blurs out (only those
    # the fit has), HOG and AdaBoost keep every effect, () keeps every effect for the CNN too
    from synthaug.detectors.train_cli import _effects_off
    from synthaug.detectors.video_training import FAMILY_EFFECTS_OFF, AddedPositives, TrainingInputError, _add_from_fit

    assert FAMILY_EFFECTS_OFF == {"cnn": ("boundary_blur", "motion_blur")}
    no_mb = ws["root"] / "fit8_no_motion_blur.json"
    CaptureParams.sample(8, generator=torch.Generator().manual_seed(1),
                         effects=["boundary_blur", "object_noise", "material"]).save(no_mb)

    class _SeedSet(list):
        path = seedset

    for kind, off, fit_file, effects, recorded in (
            ("cnn", None, fit, ["object_noise", "material"], ["boundary_blur", "motion_blur"]),
            ("hog", None, fit, None, None), ("adaboost", None, fit, None, None), ("cnn", (), fit, None, None),
            ("cnn", None, no_mb, ["object_noise", "material"], ["boundary_blur"])):
        ts = SimpleNamespace(seedset=_SeedSet(range(8)), positives=torch.zeros(8, 1, 40, 40), info={})
        info = _add_from_fit(ts, AddedPositives(params=fit_file, synthetic_ratio=1.0, effects_off=off,
                                                distractor_ratio=0.0), kind, seed=0, say=lambda m: None)
        assert calls[-1] == (8, "seed", effects), (kind, off)
        assert info.get("effects_off") == recorded and ts.positives.shape[0] == 16
    ts = SimpleNamespace(seedset=_SeedSet(range(8)), positives=torch.zeros(8, 1, 40, 40), info={})  # no synthetic
    assert "effects_off" not in _add_from_fit(ts, AddedPositives(params=fit, copy_paste_ratio=0.0), "cnn", seed=0,
                                              say=lambda m: None)
    assert _effects_off(None) is None and _effects_off(["none"]) == () and _effects_off(["material"]) == ("material",)
    with pytest.raises(TrainingInputError, match="none"):
        _effects_off(["none", "material"])
    # the dataclass refuses what the command line cannot give

    with pytest.raises(ValueError, match="capture_sampling"):
        AddedPositives(capture_sampling="fitted")
    for bad_keep in (0.0, 1.5):
        with pytest.raises(ValueError, match="realism_keep"):
            AddedPositives(realism_keep=bad_keep)
    with pytest.raises(ValueError, match="realism_selection"):
        AddedPositives(realism_selection="video")
    with pytest.raises(ValueError, match="effects_off"):
        AddedPositives(effects_off="motion_blur")  # type: ignore[arg-type]
    assert AddedPositives(effects_off=["material"]).effects_off == ("material",)  # type: ignore[arg-type]
    # a name that is no registered effect is refused when the command line is parsed, before any ingest
    _refused_by_train_parser(["--effects-off", "speckle"], "unknown effect 'speckle'", capsys)
    _refused_by_train_parser(["--realism-keep", "0"], "--realism-keep: must be in (0, 1], got '0'", capsys)


def test_the_cnn_family_puts_its_synthetic_objects_on_other_seeds_backgrounds(ws: dict[str, Path],
                                                                              monkeypatch: pytest.MonkeyPatch) -> None:
    """``background_sampling=None`` is the family's: the CNN's synthetic objects sit on other seeds' backgrounds
    (recorded in the metadata), HOG's and AdaBoost's on their own seed's (no key, the former metadata); a value given
    wins for every family; a one-seed set falls back to its own background unless ``"other"`` is asked for, which is
    refused naming the option; without synthetic positives nothing is recorded."""
    import argparse

    import synthaug.detectors.video_training as video_training
    from synthaug.detectors.train_cli import add_arguments
    from synthaug.detectors.video_training import (
        FAMILY_BACKGROUND_SAMPLING,
        AddedPositives,
        TrainingInputError,
        _add_from_fit,
        resolve_background_sampling,
    )
    from synthaug.params import CaptureParams

    drawn: list[str] = []

    def fake(seedset: Any, mesh: Any, fit_file: Any, count: int, *, seed: int = 0, background_sampling: str = "seed",
             **_: Any) -> torch.Tensor:
        drawn.append(background_sampling)
        return torch.zeros(count, 1, 40, 40)

    monkeypatch.setattr(video_training, "synthetic_positives", fake)
    assert FAMILY_BACKGROUND_SAMPLING == {"cnn": "other"}
    fits = {}
    for n in (8, 1):
        fits[n] = ws["root"] / f"fit{n}_backgrounds.json"
        CaptureParams.sample(n, generator=torch.Generator().manual_seed(n)).save(fits[n])

    class _SeedSet(list):
        path = ws["root"]

    def add(kind: str, n: int, **added: Any) -> dict[str, Any]:
        ts = SimpleNamespace(seedset=_SeedSet(range(n)), positives=torch.zeros(n, 1, 40, 40), info={})
        added = {"distractor_ratio": 0.0, **added}  # AdaBoost's own distractors: their own test
        info = _add_from_fit(ts, AddedPositives(params=fits[n], **added), kind, seed=0, say=lambda m: None)
        assert info is not None
        return info

    for kind, given, n, expected in (("cnn", None, 8, "other"), ("hog", None, 8, "seed"), ("adaboost", None, 8, "seed"),
                                     ("cnn", "seed", 8, "seed"), ("hog", "other", 8, "other"), ("cnn", None, 1, "seed")):
        info = add(kind, n, synthetic_ratio=1.0, background_sampling=given)
        assert drawn[-1] == expected, (kind, given, n)
        assert info.get("background_sampling") == (None if expected == "seed" else expected), (kind, given, n)
        assert resolve_background_sampling(kind, given, n) == expected
    count = len(drawn)
    with pytest.raises(TrainingInputError, match="--background-sampling: other .* has 1 seed"):
        add("hog", 1, synthetic_ratio=1.0, background_sampling="other")
    assert "background_sampling" not in add("cnn", 8, copy_paste_ratio=0.0) and len(drawn) == count
    with pytest.raises(ValueError, match="background_sampling must be one of"):
        AddedPositives(background_sampling="random")
    parser = argparse.ArgumentParser(prog="synthaug train")
    add_arguments(parser)
    base = ["--detector", "cnn", "--class", "drone", "--videos", "v", "--labels", "l", "--out", "o"]
    assert parser.parse_args(base).background_sampling is None
    assert parser.parse_args([*base, "--background-sampling", "seed"]).background_sampling == "seed"


def test_added_positives_resolve_to_the_familys_recipe_only_where_synthetic_positives_are_drawn() -> None:
    """``AddedPositives.resolved``: each option ``FAMILY_SYNTHETIC`` may set, left at None, becomes the family's
    where there are synthetic positives (AdaBoost's recipe; HOG's and the CNN's the paper's) and the paper's where
    there are none; a value given is kept; a family's pose at the seeds' offsets yields to an object box; resolving
    twice changes nothing; the command line leaves each at None unless given."""
    import argparse

    from synthaug.detectors.train_cli import add_arguments
    from synthaug.detectors.video_training import FAMILY_SYNTHETIC, PAPER_SYNTHETIC, AddedPositives

    synthetic = AddedPositives(params="fit.json", synthetic_ratio=2.0)
    ada = synthetic.resolved("adaboost")
    assert {k: getattr(ada, k) for k in PAPER_SYNTHETIC} == {
        "pose_sampling": "fitted_at_seed", "shape_variation": 0.3, "quantize": "native_scale",
        "realism_features": "weak_learners", "distractor_ratio": 5.0, "distractor_style": "soft"} \
        == FAMILY_SYNTHETIC["adaboost"]
    assert ada.resolved("adaboost") == ada and ada.resolved("hog") == ada  # resolved values are given values
    for kind in ("hog", "cnn"):
        assert {k: getattr(synthetic.resolved(kind), k) for k in PAPER_SYNTHETIC} == PAPER_SYNTHETIC
    perturbed = AddedPositives(perturb_copies=2).resolved("adaboost")  # nothing drawn: the paper's
    assert {k: getattr(perturbed, k) for k in PAPER_SYNTHETIC} == PAPER_SYNTHETIC
    given = AddedPositives(params="fit.json", synthetic_ratio=2.0, quantize=False, distractor_ratio=0.0,
                           object_box="seed").resolved("adaboost")
    assert (given.quantize, given.distractor_ratio, given.distractor_style, given.pose_sampling,
            given.shape_variation) == (False, 0.0, "drawn", "fitted", 0.3)
    parser = argparse.ArgumentParser()
    add_arguments(parser)
    args = parser.parse_args(["--detector", "adaboost", "--class", "drone", "--videos", "v", "--labels", "l",
                              "--out", "o"])
    assert [getattr(args, k) for k in PAPER_SYNTHETIC] == [None] * 6
    assert parser.parse_args(["--detector", "adaboost", "--class", "drone", "--videos", "v", "--labels", "l",
                              "--out", "o", "--no-quantize"]).quantize is False
    for words, value in ((["--quantize"], True), (["--quantize", "on"], True), (["--quantize", "off"], False),
                         (["--quantize", "native_scale"], "native_scale")):
        assert parser.parse_args(["--detector", "adaboost", "--class", "drone", "--videos", "v", "--labels", "l",
                                  "--out", "o", *words]).quantize == value


def test_distractors_are_drawn_as_the_synthetic_positives_and_join_the_negatives(
        ws: dict[str, Path], trained: dict[str, Any], monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """``--distractor-ratio K``: K rendered distractors per real seed go to the negatives (not the positives), drawn
    with the synthetic positives' fit, poses, effects and 8 bits, at their own seed; recorded in the metadata; refused
    without synthetic positives and below 0."""
    import synthaug.detectors.video_training as video_training
    from synthaug.detectors.video_training import AddedPositives, TrainingInputError, _check_options
    from synthaug.params import CaptureParams

    drawn: list[tuple[str, int, int, dict[str, Any]]] = []
    styles: list[str | None] = []

    def record(what: str) -> Any:
        def draw(seedset: Any, *args: Any, seed: int = 0, **kw: Any) -> torch.Tensor:
            count = args[-1]
            drawn.append((what, count, seed, {k: kw.get(k) for k in ("pose_sampling", "effects", "quantize")}))
            styles.append(kw.get("style"))
            return torch.full((count, 1, 40, 40), 0.5)
        return draw

    monkeypatch.setattr(video_training, "synthetic_positives", record("positives"))
    monkeypatch.setattr(video_training, "distractor_negatives", record("distractors"))
    fit = ws["root"] / "fit8_distractors.json"
    theta = CaptureParams.sample(8, generator=torch.Generator().manual_seed(0))
    theta.save(fit)
    seedset = trained["meta"]["positives"]["seedset"]
    common = ["--detector", "adaboost", "--seedset", seedset, "--params", str(fit), "--synthetic-ratio", "2",
              "--pose-sampling", "fitted_at_seed", "--effects-off", "motion_blur", "--quantize", "--mining-rounds", "0"]
    out0, out1 = ws["root"] / "runs" / "ada_no_distractors.pt", ws["root"] / "runs" / "ada_distractors.pt"
    assert _train(ws, out0, *common, "--distractor-ratio", "0") == 0
    assert [d[0] for d in drawn] == ["positives"]
    assert _train(ws, out1, *common, "--distractor-ratio", "1.5", "--distractor-style", "drawn") == 0
    (_, n_pos, s_pos, how_pos), (_, n_dist, s_dist, how_dist) = drawn[1:]
    kept = [e for e in theta.effects if e != "motion_blur"]
    assert (n_pos, n_dist) == (16, 12) and s_dist != s_pos
    assert how_dist == how_pos == {"pose_sampling": "fitted_at_seed", "effects": kept, "quantize": True}
    m0, m1 = (json.loads(o.with_suffix(".json").read_text()) for o in (out0, out1))
    assert m1["negatives"]["initial"] == m0["negatives"]["initial"] + 12
    assert m1["synthetic"]["distractors"] == {"ratio": 1.5, "count": 12} and "distractors" not in m0["synthetic"]
    assert m1["synthetic"]["count"] == m0["synthetic"]["count"] == 16
    # refused: no synthetic positives to draw them as, a negative ratio (the command line and the dataclass)
    for added, match in ((AddedPositives(params=fit, distractor_ratio=1.0), "drawn as the synthetic positives"),
                         (AddedPositives(params=fit, synthetic_ratio=1.0, distractor_ratio=-1.0), ">= 0")):
        with pytest.raises(TrainingInputError, match=f"--distractor-ratio.*{match}"):
            _check_options("adaboost", added, frame_step=1, all_frames=False, seedset=None, seed_count=8)
    _refused_by_train_parser(["--distractor-ratio", "-2"], "--distractor-ratio", capsys)
    # --distractor-style soft: the same draw, passed the style, recorded in the metadata; refused without distractors
    out2 = ws["root"] / "runs" / "ada_soft_distractors.pt"
    assert _train(ws, out2, *common, "--distractor-ratio", "1.5", "--distractor-style", "soft") == 0
    assert styles[1:] == [None, "drawn", None, "soft"] and drawn[-1][:2] == ("distractors", 12)
    m2 = json.loads(out2.with_suffix(".json").read_text())
    assert m2["synthetic"]["distractors"] == {"ratio": 1.5, "count": 12, "style": "soft"}
    # unset: AdaBoost's own (FAMILY_SYNTHETIC: 5 soft distractors per seed); HOG's none
    out3 = ws["root"] / "runs" / "ada_family_distractors.pt"
    assert _train(ws, out3, *common) == 0
    assert styles[-1] == "soft" and drawn[-1][:2] == ("distractors", 40)
    assert json.loads(out3.with_suffix(".json").read_text())["synthetic"]["distractors"] == {
        "ratio": 5.0, "count": 40, "style": "soft"}
    with pytest.raises(TrainingInputError, match="--distractor-style.*--distractor-ratio"):
        _check_options("hog", AddedPositives(params=fit, synthetic_ratio=1.0, distractor_style="soft"),
                       frame_step=1, all_frames=False, seedset=None, seed_count=8)
    with pytest.raises(TrainingInputError, match="--distractor-style.*cloudy"):
        _check_options("adaboost", AddedPositives(params=fit, synthetic_ratio=1.0, distractor_ratio=1.0,
                                                  distractor_style="cloudy"),
                       frame_step=1, all_frames=False, seedset=None, seed_count=8)
    _refused_by_train_parser(["--distractor-style", "cloudy"], "--distractor-style", capsys)
