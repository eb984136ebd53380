"""Detector training with hard-negative mining at scale (synthaug.detectors.training, .mining, .frames,
.video_training), on generated data only."""

from __future__ import annotations

import inspect
import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from synthaug.detectors.base import PatchDetector
from synthaug.detectors.frames import MiningFrame, VideoFrames
from synthaug.detectors.mining import mine_hard_negatives, validation_false_positives
from synthaug.detectors.training import TrainOptions, train_detector, train_with_mining
from synthaug.detectors.video_training import TrainingInputError, discover_videos, split_by_video

GREY = 200


class Darkness(PatchDetector):
    """Scores a window by its darkness (1 - mean); windows whose darkest pixel is at a forbidden level score 2 lower.

    ``fit(negatives)`` forbids the darkest-pixel level (tenths) of every dark negative: once the black
    distractors of the mining frames are negatives, every window touching a black square is suppressed.
    """

    kind = "darkness_training_test"

    def __init__(self, forbidden: set[int] | None = None) -> None:
        self.window, self.stride = 40, 4
        self.forbidden = set(forbidden or ())

    @staticmethod
    def level(patches: torch.Tensor) -> torch.Tensor:
        return (patches.amin((1, 2, 3)) * 10).floor().long()

    @classmethod
    def fit(cls, positives: torch.Tensor, negatives: torch.Tensor) -> "Darkness":
        dark = negatives[(1 - negatives.mean((1, 2, 3))) > 0.5]
        return cls({int(v) for v in cls.level(dark).tolist()})

    def score_patches(self, patches: torch.Tensor) -> torch.Tensor:
        s = 1 - patches.mean((1, 2, 3))
        if self.forbidden:
            bad = torch.tensor([int(v) in self.forbidden for v in self.level(patches).tolist()])
            s = s - 2.0 * bad.float()
        return s

    def state_dict(self) -> dict[str, Any]:
        return {"forbidden": sorted(self.forbidden)}

    @classmethod
    def from_state_dict(cls, state: dict[str, Any]) -> "Darkness":
        return cls(set(state["forbidden"]))


def _frame(squares: list[tuple[int, int, int]], h: int = 120, w: int = 160) -> np.ndarray:
    f = np.full((h, w), GREY, np.uint8)
    for x, y, v in squares:
        f[y:y + 40, x:x + 40] = v
    return f


# ----------------------------------------------------------------- mining: what is mined
def test_mined_negatives_are_true_background_and_exact_windows() -> None:
    """The object (the darkest thing in each frame) is never mined; each patch is the window the detector scored."""
    rng = np.random.default_rng(0)
    frames, boxes = [], []
    for i in range(6):
        ox, oy = int(rng.integers(0, 30)) * 4, int(rng.integers(0, 18)) * 4
        f = _frame([(ox, oy, 0)])  # the labelled object: black, the best window of the frame
        f = np.clip(f.astype(int) + rng.integers(-30, 30, f.shape), 0, 255).astype(np.uint8)
        f[oy:oy + 40, ox:ox + 40] = 0
        frames.append(MiningFrame(f, np.array([[ox + 6.0, oy + 6.0, 28.0, 28.0]]), "V_X_001", i))
        boxes.append(np.array([[ox + 6.0, oy + 6.0, 28.0, 28.0]]))
    frames.append(MiningFrame(_frame([(60, 40, 0)]), None, "V_BIRD_001", 0))  # a negative-class frame: nothing masked
    scales = (1.0, 0.8)
    mined = mine_hard_negatives(Darkness(), iter(frames), scales=scales, per_frame=4, margin=0.25)
    assert mined.frames_scanned == 7
    assert 0 < len(mined) <= 7 * 4
    assert mined.scores.tolist() == sorted(mined.scores.tolist(), reverse=True)
    from synthaug.data.backgrounds import grow_boxes

    for (video, index), box in zip(mined.sources, mined.boxes.tolist()):
        if video == "V_BIRD_001":
            continue
        for gx, gy, gw, gh in grow_boxes(boxes[index], margin_fraction=0.25, min_margin=4.0):
            assert not (box[0] < gx + gw and box[2] > gx and box[1] < gy + gh and box[3] > gy), (index, box)
    per_frame = {}
    for s in mined.sources:
        per_frame[s] = per_frame.get(s, 0) + 1
    assert max(per_frame.values()) <= 4
    # the negative-class frame gives its black square (nothing masked there), and it scores highest
    assert mined.sources[0] == ("V_BIRD_001", 0) and mined.boxes[0].tolist() == [60.0, 40.0, 100.0, 80.0]
    # every patch is the detector's window: rescoring gives the mined score
    np.testing.assert_allclose(Darkness().score_patches(mined.patches).numpy(), mined.scores.numpy(), atol=1e-5)
    # scale-1 windows equal the frame crop exactly
    for p, (video, index), box in zip(mined.patches, mined.sources, mined.boxes.tolist()):
        if abs(box[2] - box[0] - 40) < 1e-4:
            x, y = int(round(box[0])), int(round(box[1]))
            img = frames[-1].image if video == "V_BIRD_001" else frames[index].image
            np.testing.assert_allclose(p[0].numpy(), img[y:y + 40, x:x + 40] / 255.0, atol=1e-6)
    # mined windows are excluded next time; a global cap keeps the best
    again = mine_hard_negatives(Darkness(), frames, scales=scales, per_frame=4, exclude=set(mined.keys))
    assert not set(again.keys) & set(mined.keys)
    capped = mine_hard_negatives(Darkness(), frames, scales=scales, per_frame=4, max_negatives=5)
    assert len(capped) == 5 and torch.equal(capped.scores, mined.scores[:5])


def test_video_frames_stream_by_video_every_kth_labelled_frame(tmp_path: Path) -> None:
    from synthaug.data.synthvideo import make_panning_video

    make_panning_video(tmp_path, n_frames=9, size=(96, 80), seed=0, name="V_DRONE_004")
    make_panning_video(tmp_path, n_frames=5, size=(96, 80), seed=1, name="V_BIRD_009", class_name="bird")
    lab = tmp_path / "labels" / "V_DRONE_004.json"
    doc = json.loads(lab.read_text())
    doc["boxes"][3] = None  # not drawn in frame 3: not a mining frame (the object may be in view)
    lab.write_text(json.dumps(doc))
    src = VideoFrames(tmp_path / "videos", tmp_path / "labels", positive=["V_DRONE_004"], negative=["V_BIRD_009"], stride=3)
    assert inspect.isgenerator(iter(src))  # streamed, never a list of frames
    got = [(f.video, f.index, f.boxes is None) for f in src]
    assert got == [("V_DRONE_004", 0, False), ("V_DRONE_004", 6, False), ("V_BIRD_009", 0, True), ("V_BIRD_009", 3, True)]
    assert src.planned_frames() == 4
    val = VideoFrames(tmp_path / "videos", tmp_path / "labels", positive=["V_DRONE_004"], stride=3, null_frames=True)
    assert [(f.index, f.boxes is None) for f in val] == [(0, False), (3, True), (6, False)]
    first = next(iter(src))
    np.testing.assert_allclose(first.boxes[0], doc["boxes"][0])


# ----------------------------------------------------------------- validation count and the stopping rule
def test_validation_false_positives_hand_counted() -> None:
    # 2 frames: object (value 100) + black distractor; one object-free frame with a distractor
    frames = [MiningFrame(_frame([(0, 0, 100), (100, 60, 0)]), np.array([[0.0, 0.0, 40.0, 40.0]])),
              MiningFrame(_frame([(60, 0, 100), (0, 80, 0)]), np.array([[60.0, 0.0, 40.0, 40.0]])),
              MiningFrame(_frame([(40, 40, 0)]), None)]
    r = validation_false_positives(Darkness(), frames, scales=[1.0], top_k=1)
    # top-1 per frame is each frame's distractor: 3 FPs, no object found
    assert r == {"fp": 3, "recall_reached": False, "threshold": None, "max_recall": 0.0, "tp": 0, "detections": 3,
                 "frames": 3, "objects": 2, "ap": 0.0, "ap_envelope": 0.0}
    r = validation_false_positives(Darkness(), frames, scales=[1.0], top_k=2)
    # by score: the 3 distractors (1.0), then the objects: recall 1/2 is reached at the 4th detection with 3 FPs above
    assert r["fp"] == 3 and r["recall_reached"] and r["max_recall"] == 1.0 and r["tp"] == 2
    r = validation_false_positives(Darkness({0}), frames, scales=[1.0], top_k=2)  # distractors suppressed
    assert r["fp"] == 0 and r["threshold"] == pytest.approx(1 - 100 / 255, abs=1e-5)


def test_mining_rounds_stop_when_validation_fp_stops_falling() -> None:
    """Round 1 mines the black distractors -> validation FPs fall to 0; round 2 mines grey sky -> no fall -> stop, keep round 1."""
    mining = [MiningFrame(_frame([(4 * i, 8, 100), (80, 60, 0)]), np.array([[4.0 * i, 8.0, 40.0, 40.0]]), "V_M_001", i)
              for i in range(4)]
    val = [MiningFrame(_frame([(8, 72, 100), (100, 4, 0)]), np.array([[8.0, 72.0, 40.0, 40.0]]), "V_V_001", i) for i in range(3)]
    val.append(MiningFrame(_frame([(60, 40, 0)]), None, "V_V_001", 3))
    grey = torch.full((20, 1, 40, 40), GREY / 255.0)
    pos = torch.full((5, 1, 40, 40), 100 / 255.0)
    fits = []

    def fit(p: torch.Tensor, n: torch.Tensor) -> Darkness:
        fits.append(n.shape[0])
        return Darkness.fit(p, n)

    opts = TrainOptions(mining_rounds=6, mining_per_frame=3, scales=(1.0,), val_top_k=3)
    res = train_with_mining("toy", pos, grey, 0, box_in_window=(0, 0, 40, 40), options=opts, mining_source=mining,
                            val_frames=val, fit=fit)
    rounds = res.log["rounds"]
    assert [r["round"] for r in rounds] == [0, 1, 2]
    assert [r["val"]["fp"] for r in rounds] == [4, 0, 0]  # the 4 distractors outrank the objects, then none
    assert [r["added"] for r in rounds] == [0, 12, 12]  # 3 per frame, 4 frames; round 2 never repeats round 1
    assert [r["negatives"] for r in rounds] == [20, 32, 44] and fits == [20, 32, 44]
    assert res.log["chosen_round"] == 1 and "stopped falling" in res.log["stop_reason"]
    assert res.negatives.shape[0] == 32 and res.detector.forbidden == {0}
    assert res.detector.box_in_window == (0.0, 0.0, 40.0, 40.0)
    # without validation frames every round runs
    res = train_with_mining("toy", pos, grey, 0, options=TrainOptions(mining_rounds=2, mining_per_frame=3, scales=(1.0,)),
                            mining_source=mining, fit=fit)
    assert [r["round"] for r in res.log["rounds"]] == [0, 1, 2] and res.log["chosen_round"] == 2
    # a box regressor is set on every round's detector, and the validation count matches at its boxes:
    # one that moves every box by a whole box width turns each object hit into a miss (round 0: 4 FPs -> 6)
    from synthaug.detectors.boxes import BoxRegressor

    off = BoxRegressor.identity()
    off.mean_y = torch.tensor([1.0, 0.0, 0.0, 0.0], dtype=torch.float64)
    res = train_with_mining("toy", pos, grey, 0, box_in_window=(0, 0, 40, 40), options=opts, mining_source=mining,
                            val_frames=val, fit=fit, box_regressor=off)
    assert res.detector.box_regressor is off
    assert res.log["rounds"][0]["val"]["fp"] > 4 and not res.log["rounds"][0]["val"]["recall_reached"]


def test_validation_ap_matches_an_independent_computation() -> None:
    """The validation AP of the stopping rule = the protocol's AP (synthaug.evaluate.ap: its own matching and curve) and
    torchmetrics' binary average precision rescaled to recall over all objects, on the same detections."""
    from torchmetrics.functional.classification import binary_average_precision

    from synthaug.detectors.frames import _image_tensor
    from synthaug.detectors.mining import _pooled_ap
    from synthaug.detectors.sliding import detect_multiscale
    from synthaug.evaluate.ap import average_precision, evaluate_detections, match_detections, precision_recall

    # objects and distractors of interleaved darkness: the ranking mixes hits and misses; one object-free frame and
    # one object never detected (recall < 1)
    frames = [MiningFrame(_frame([(8, 8, o), (100, 64, d)]), np.array([[8.0, 8.0, 40.0, 40.0]]))
              for o, d in [(60, 80), (110, 20), (90, 120), (150, 170), (30, 100)]]
    frames += [MiningFrame(_frame([(60, 40, 50)]), None),
               MiningFrame(_frame([(60, 40, 250)]), np.array([[0.0, 70.0, 40.0, 40.0]]))]
    r = validation_false_positives(Darkness(), frames, scales=[1.0], top_k=2)
    dets = [detect_multiscale(Darkness(), _image_tensor(f.image), scales=[1.0], nms_iou=0.3, max_detections=2).numpy()
            for f in frames]
    gts = [f.boxes for f in frames]
    ref = evaluate_detections(dets, gts, 0.5)
    assert r["objects"] == ref.n_ground_truth == 6 and r["tp"] == ref.n_true_positives == 5
    assert 0.2 < r["ap"] < 0.9 and r["ap"] == pytest.approx(ref.ap, abs=1e-9)
    assert r["ap_envelope"] == pytest.approx(ref.ap_envelope, abs=1e-9)
    scores, is_tp, n_gt, _ = match_detections(dets, gts, 0.5)
    tm = float(binary_average_precision(torch.as_tensor(scores), torch.as_tensor(is_tp).long()))
    assert r["ap"] == pytest.approx(tm * is_tp.sum() / n_gt, abs=1e-6)  # torchmetrics' recall is over detected objects
    # ties enter together, and the envelope differs from the step curve: both as the protocol's functions
    sc, tp = np.array([0.9, 0.8, 0.8, 0.7, 0.6, 0.6]), np.array([False, True, False, True, True, False])
    p_, rc, _ = precision_recall(sc, tp, 5)
    ap, env = _pooled_ap(sc, tp, 5)
    assert ap == pytest.approx(average_precision(p_, rc)) and env == pytest.approx(average_precision(p_, rc, envelope=True))
    assert env > ap
    # by hand: recall 1/5 at precision 1/3 (0.8 ties), 2/5 at 1/2, 3/5 at 1/2 (0.6 ties)
    assert ap == pytest.approx(0.2 / 3 + 0.2 / 2 + 0.2 / 2)
    assert _pooled_ap(np.zeros(0), np.zeros(0, bool), 3) == (0.0, 0.0) and _pooled_ap(sc, tp, 0) == (None, None)


class _Scripted:
    """A detector whose validation result is scripted (``fp``, ``ap``): one per call of ``fit``."""

    window, stride = 40, 4

    def __init__(self, i: int, fp: int, ap: float | None) -> None:
        self.i, self.fp, self.ap = i, fp, ap


def _scripted_mining(monkeypatch: pytest.MonkeyPatch, fps: list[int], aps: list[float | None], options: TrainOptions):
    """``train_with_mining`` over a scripted sequence: round r's detector has validation FP ``fps[r]`` and AP ``aps[r]``;
    every scan mines one new window (no frame is scanned: mining and validation are stubbed)."""
    import synthaug.detectors.training as T
    from synthaug.detectors.mining import MinedNegatives

    made: list[_Scripted] = []

    def fit(p: torch.Tensor, n: torch.Tensor) -> _Scripted:
        made.append(_Scripted(len(made), fps[len(made)], aps[len(made)]))
        return made[-1]

    def mine(det: Any, source: Any, **k: Any) -> MinedNegatives:
        return MinedNegatives(torch.full((1, 1, 40, 40), det.i / 100), torch.zeros(1, 4), torch.ones(1), [("V", det.i)],
                              [("V", det.i, 0, 0, 0)], 1, 0.0)

    monkeypatch.setattr(T, "mine_hard_negatives", mine)
    monkeypatch.setattr(T, "validation_false_positives", lambda det, val, **k: {"fp": det.fp, "ap": det.ap})
    res = train_with_mining("toy", torch.ones(2, 1, 40, 40), torch.zeros(10, 1, 40, 40), 0, options=options,
                            mining_source=[object()], val_frames=[MiningFrame(np.zeros((8, 8), np.uint8), None)], fit=fit)
    assert res.detector is made[res.log["chosen_round"]]  # the chosen round's detector and its negatives
    assert res.negatives.shape[0] == 10 + res.log["chosen_round"]
    return res


def test_mining_patience_runs_rounds_without_a_new_best(monkeypatch: pytest.MonkeyPatch) -> None:
    fps = [36, 38, 20, 25, 30, 10]
    aps = [0.30, 0.35, 0.32, 0.50, 0.40, 0.45]

    def run(**kw: Any) -> dict[str, Any]:
        return _scripted_mining(monkeypatch, fps, aps, TrainOptions(mining_rounds=5, **kw)).log

    log = run()  # today's rule: the first round without fewer FPs stops; round 2's 20 is never seen
    assert [r["round"] for r in log["rounds"]] == [0, 1] and log["chosen_round"] == 0
    assert log["stop_reason"] == "validation false positives stopped falling (36 -> 38)"
    assert log["mining"]["select"] == "fp" and log["mining"]["patience"] == 0
    log = run(mining_patience=1)  # 38 is tolerated, 20 is a new best, 25 and 30 are two rounds without one: stop
    assert [r["round"] for r in log["rounds"]] == [0, 1, 2, 3, 4] and log["chosen_round"] == 2
    assert "patience 1" in log["stop_reason"] and "FP 20" in log["stop_reason"]
    log = run(mining_patience=2)  # ... one more round: 10 is found, the budget ends the rounds
    assert len(log["rounds"]) == 6 and log["chosen_round"] == 5 and log["stop_reason"] == "mining_rounds reached"
    log = run(mining_patience=9)  # patience beyond the budget: every round, the best kept
    assert len(log["rounds"]) == 6 and log["chosen_round"] == 5


def test_mining_select_ap_keeps_the_round_of_highest_validation_ap(monkeypatch: pytest.MonkeyPatch) -> None:
    fps = [36, 38, 20, 25, 30, 10]
    aps = [0.30, 0.35, 0.32, 0.50, 0.40, 0.45]

    def run(fps: list[int] = fps, aps: list[float | None] = aps, **kw: Any) -> dict[str, Any]:
        return _scripted_mining(monkeypatch, fps, aps, TrainOptions(mining_rounds=5, mining_select="ap", **kw)).log

    log = run()  # 0.35 is a new best, 0.32 is not: stop, keep round 1 (by FP the same rounds would keep round 0)
    assert [r["round"] for r in log["rounds"]] == [0, 1, 2] and log["chosen_round"] == 1
    assert "higher validation AP" in log["stop_reason"] and "AP 0.3500" in log["stop_reason"]
    log = run(mining_patience=1)  # 0.50 at round 3, then 0.40 and 0.45: stop at round 5, keep round 3 (FP would keep 5)
    assert len(log["rounds"]) == 6 and log["chosen_round"] == 3 and "patience 1" in log["stop_reason"]
    log = run(aps=[0.4, 0.4, 0.4, 0.4, 0.4, 0.4], mining_patience=1)  # ties are not a new best: the earliest round
    assert len(log["rounds"]) == 3 and log["chosen_round"] == 0
    log = run(aps=[None, 0.1, None, 0.2, 0.2, 0.2], mining_patience=1)  # no AP (no object) is never better
    assert log["chosen_round"] == 3 and len(log["rounds"]) == 6


@pytest.mark.parametrize("field, value", [("mining_select", "recall"), ("mining_patience", -1), ("mining_patience", 1.5)])
def test_train_options_refuse_a_bad_mining_rule(field: str, value: Any) -> None:
    with pytest.raises(ValueError, match=field):
        TrainOptions(**{field: value})


def test_train_options_key_fields_leave_the_later_fields_out_at_their_defaults() -> None:
    from dataclasses import asdict

    old = {k: v for k, v in asdict(TrainOptions(ada_rounds=100, box_calibration=20)).items()
           if k not in ("mining_select", "mining_patience", "mining_frame_scale", "ada_energy_floor", "ada_transfer",
                        "ada_cascade", "box_calibration_form")}
    not_hog = {k: v for k, v in old.items() if k != "hog_kmeans_restarts"}  # HOG's k-means is in HOG's keys only
    only_hog = {k: v for k, v in old.items() if k != "cnn_finetune_epochs"}  # the CNN's fine-tuning: the CNN's keys
    # the keys of before the family defaults; no kind keeps every family-only field (AdaBoost's floor and cascade at
    # their defaults)
    for kind, base in (("hog", only_hog), ("cnn", not_hog),
                       (None, {**old, "ada_energy_floor": 1.0, "ada_cascade": "real"})):
        assert TrainOptions().key_fields(kind) == base
        assert TrainOptions(mining_select="ap").key_fields(kind) == {**base, "mining_select": "ap"}
        assert TrainOptions(mining_patience=1).key_fields(kind) == {**base, "mining_patience": 1}
    ada = TrainOptions().key_fields("adaboost")
    assert (ada["ada_rounds"], ada["mining_select"], ada["mining_patience"]) == (300, "ap", 1)
    assert TrainOptions(mining_select="fp", mining_patience=0, ada_rounds=100, ada_energy_floor=0,
                        ada_cascade="all", box_calibration=0).key_fields("adaboost") \
        == {k: v for k, v in not_hog.items() if k not in ("cnn_finetune_epochs", "box_calibration")}
    # the box calibration: every family's default (HOG and the CNN since stop 73, AdaBoost since stop 97); at 0 the
    # keys of before it, so AdaBoost's default cells have new keys and its uncalibrated cells keep theirs
    assert "box_calibration" not in TrainOptions(box_calibration=0).key_fields("hog") and ada["box_calibration"] == 20
    assert "box_calibration" not in TrainOptions(box_calibration=0).key_fields("adaboost")
    # the floor and the real-positive cascade changed AdaBoost's training: its default cells have new keys
    assert (ada["ada_energy_floor"], ada["ada_cascade"]) == (1.0, "real")


def test_hog_kmeans_restarts_key_and_training(monkeypatch: pytest.MonkeyPatch) -> None:
    """One k-means run is the training of the cells before the option (their keys leave it out); the default, 10,
    and any other count are part of HOG's key and of no other family's; the count reaches HOG's fit."""
    from dataclasses import asdict

    import synthaug.detectors.hog_dpm as hd

    assert "hog_kmeans_restarts" not in TrainOptions(hog_kmeans_restarts=1).key_fields("hog")
    assert TrainOptions().key_fields("hog")["hog_kmeans_restarts"] == 10 == asdict(TrainOptions())["hog_kmeans_restarts"]
    assert TrainOptions(hog_kmeans_restarts=3).key_fields("hog")["hog_kmeans_restarts"] == 3
    for bad in (0, -1, 2.5, True, None):
        with pytest.raises(ValueError, match="hog_kmeans_restarts"):
            TrainOptions(hog_kmeans_restarts=bad)
    for kind in ("cnn", "adaboost"):  # no k-means there: their keys stay the ones before the option
        assert "hog_kmeans_restarts" not in TrainOptions(hog_kmeans_restarts=3).key_fields(kind)
        assert TrainOptions().key_fields(kind) == TrainOptions(hog_kmeans_restarts=1).key_fields(kind)
    seen = []
    fit = hd.HOGDetector.fit
    monkeypatch.setattr(hd.HOGDetector, "fit", classmethod(
        lambda cls, *a, **k: seen.append(k["kmeans_restarts"]) or fit.__func__(cls, *a, **k)))
    from synthaug.detectors.toy import toy_patches

    pos, neg = toy_patches(8, 16, seed=0)
    train_detector("hog", pos, neg, 0, options=TrainOptions(hog_components=2, hog_mining_rounds=0, hog_kmeans_restarts=4))
    assert seen == [4]


def test_cnn_finetune_epochs_key_and_checks() -> None:
    """No fine-tuning (0) is the training of the cells before the option; any other count is in the CNN's key and
    in no other family's; a bad count or a bad number of real positives is a clear error."""
    assert "cnn_finetune_epochs" not in TrainOptions(cnn_finetune_epochs=0).key_fields("cnn")
    assert TrainOptions().key_fields("cnn")["cnn_finetune_epochs"] == 4  # the default (measured) is a new training
    assert TrainOptions(cnn_finetune_epochs=3).key_fields("cnn")["cnn_finetune_epochs"] == 3
    for kind in ("hog", "adaboost"):
        assert TrainOptions(cnn_finetune_epochs=3).key_fields(kind) == TrainOptions().key_fields(kind)
    for bad in (-1, 1.5, True, None):
        with pytest.raises(ValueError, match="cnn_finetune_epochs"):
            TrainOptions(cnn_finetune_epochs=bad)
    from synthaug.detectors.toy import toy_patches

    pos, neg = toy_patches(6, 12, seed=0)
    for bad in (-1, 7, 2.5):
        with pytest.raises(ValueError, match="real_positives"):
            train_with_mining("cnn", pos, neg, 0, options=TrainOptions(cnn_epochs=1, mining_rounds=0), real_positives=bad)


def test_cnn_finetune_trains_on_the_real_positives_after_the_mixed_set(monkeypatch: pytest.MonkeyPatch) -> None:
    """With ``cnn_finetune_epochs`` the CNN is trained on every positive, then the same module continues on the first
    ``real_positives`` alone and the same negatives at a tenth of the rate; without added positives, or at 0, there is
    one training, the one before the option."""
    import synthaug.detectors.lightning_module as lm
    from synthaug.detectors.toy import toy_patches

    calls: list[dict[str, Any]] = []
    fit = lm.fit_patch_detector

    def spy(p, n, **kw):
        m = fit(p, n, **kw)
        calls.append({"pos": p.clone(), "neg": n.clone(), "lr": kw.get("lr", 3e-3), "given": kw.get("module"),
                      "module": m, "weights": {k: v.clone() for k, v in m.net.state_dict().items()}})
        return m

    monkeypatch.setattr(lm, "fit_patch_detector", spy)
    pos, neg = toy_patches(10, 30, seed=1)
    opts = TrainOptions(cnn_epochs=2, cnn_batch_size=16, mining_rounds=0, cnn_finetune_epochs=2)
    det = train_detector("cnn", pos, neg, 3, options=opts, real_positives=4)
    assert len(calls) == 2
    first, second = calls
    assert torch.equal(first["pos"], pos) and first["given"] is None
    assert torch.equal(second["pos"], pos[:4]) and torch.equal(second["neg"], neg)
    assert second["given"] is first["module"] and second["lr"] == pytest.approx(first["lr"] * 0.1)
    # the detector is the fine-tuned network, which moved away from the mixed-set training
    final = {k: v for k, v in det.net.state_dict().items()}
    assert all(torch.equal(final[k], second["weights"][k]) for k in final)
    assert any(not torch.equal(first["weights"][k], second["weights"][k]) for k in final if final[k].is_floating_point())
    # the first stage is exactly the training without the option (same seed, same data)
    calls.clear()
    base = train_detector("cnn", pos, neg, 3, options=TrainOptions(cnn_epochs=2, cnn_batch_size=16, mining_rounds=0,
                                                                   cnn_finetune_epochs=0), real_positives=4)
    assert len(calls) == 1 and all(torch.equal(calls[0]["weights"][k], first["weights"][k]) for k in final)
    assert all(torch.equal(v, calls[0]["weights"][k]) for k, v in base.net.state_dict().items())
    for real in (None, 10, 0):  # nothing added (or nothing real to fine-tune on): one training
        calls.clear()
        train_detector("cnn", pos, neg, 3, options=opts, real_positives=real)
        assert len(calls) == 1


def test_fit_patch_detector_continues_a_given_module() -> None:
    """``module=`` keeps the given network's weights as the starting point: at a negligible rate they stay put, while
    a new training from the same seed starts elsewhere; a window mismatch is refused."""
    from synthaug.detectors.lightning_module import fit_patch_detector
    from synthaug.detectors.toy import toy_patches

    pos, neg = toy_patches(8, 24, seed=2)
    m = fit_patch_detector(pos, neg, epochs=2, batch_size=16, seed=5)
    before = {k: v.clone() for k, v in m.net.state_dict().items()}
    m2 = fit_patch_detector(pos, neg, epochs=1, batch_size=16, seed=5, lr=1e-12, module=m)
    assert m2 is m
    for k, v in m.net.state_dict().items():
        if v.is_floating_point() and "running" not in k:
            torch.testing.assert_close(v, before[k], atol=1e-6, rtol=0)
    fresh = fit_patch_detector(pos, neg, epochs=1, batch_size=16, seed=5, lr=1e-12)
    assert any(not torch.allclose(fresh.net.state_dict()[k], before[k]) for k in before if before[k].is_floating_point())
    with pytest.raises(ValueError, match="window"):
        fit_patch_detector(pos[:, :, :32, :32], neg[:, :, :32, :32], epochs=1, module=m)


def test_family_defaults_reach_the_training(monkeypatch: pytest.MonkeyPatch) -> None:
    """Fields left at None take the family's default where a detector is trained: AdaBoost gets 300 rounds and
    one round of patience by validation AP, HOG and the CNN keep the fewest validation FPs without patience;
    a value given is kept."""
    import synthaug.detectors.adaboost as ab

    seen = []
    monkeypatch.setattr(ab, "train_adaboost",
                        lambda pos, neg, n_rounds, candidates, seed, positive_weights=None, energy_floor=0.0,
                               source_positives=0, cascade_positives=None:
                        seen.append(n_rounds) or 1 / 0)
    from synthaug.detectors.toy import toy_patches

    pos, neg = toy_patches(8, 8, seed=0)
    for opts, want in ((TrainOptions(), 300), (TrainOptions(ada_rounds=7), 7)):
        with pytest.raises(ZeroDivisionError):
            train_detector("adaboost", pos, neg, 0, options=opts)
        assert seen[-1] == want
    assert TrainOptions().for_family("cnn") == TrainOptions(ada_rounds=100, mining_select="fp", mining_patience=0,
                                                            box_calibration=20)
    assert TrainOptions().for_family("adaboost") == TrainOptions(ada_rounds=300, mining_select="ap", mining_patience=1,
                                                                 box_calibration=20)
    assert TrainOptions(box_calibration=5).for_family("adaboost").box_calibration == 5  # a value given is kept
    assert TrainOptions().for_family("some_plugin") == TrainOptions().for_family("hog")
    with pytest.raises(ValueError, match="ada_rounds"):
        TrainOptions(ada_rounds=0)


def test_cnn_positive_weights_reach_every_mining_round(monkeypatch: pytest.MonkeyPatch) -> None:
    """--synthetic-share for the CNN: every round's training (the mined negatives added, weight 1) gets the same
    per-positive weights, and so does AdaBoost's (its starting weights)."""
    import synthaug.detectors.lightning_module as lm
    from synthaug.detectors.video_training import share_weights

    mining = [MiningFrame(_frame([(4 * i, 8, 100), (80, 60, 0)]), np.array([[4.0 * i, 8.0, 40.0, 40.0]]), "V_M_001", i)
              for i in range(4)]
    grey = torch.full((20, 1, 40, 40), GREY / 255.0)
    pos = torch.full((5, 1, 40, 40), 100 / 255.0)
    w = share_weights(2, 5, 0.5)  # 2 real positives, 3 added: half the weight each
    seen = []

    class Trained:
        def __init__(self, negatives: torch.Tensor) -> None:
            self.negatives = negatives

        def to_detector(self) -> Darkness:
            return Darkness.fit(pos, self.negatives)

    def spy(positives: torch.Tensor, negatives: torch.Tensor, **kw: Any) -> Trained:
        seen.append((positives.shape[0], negatives.shape[0], kw.get("positive_weights")))
        return Trained(negatives)

    monkeypatch.setattr(lm, "fit_patch_detector", spy)
    opts = TrainOptions(mining_rounds=2, mining_per_frame=3, scales=(1.0,), cnn_epochs=1)
    res = train_with_mining("cnn", pos, grey, 0, box_in_window=(0, 0, 40, 40), options=opts, mining_source=mining,
                            positive_weights=w)
    assert [r["negatives"] for r in res.log["rounds"]] == [20, 32, 44]
    assert [(p, n) for p, n, _ in seen] == [(5, 20), (5, 32), (5, 44)]
    assert all(x is w for _, _, x in seen)
    seen.clear()
    train_with_mining("cnn", pos, grey, 0, options=opts, mining_source=mining)
    assert [x for _, _, x in seen] == [None, None, None]  # the default: no weights
    # AdaBoost's starting weights, the same vector in every round
    import synthaug.detectors.adaboost as ada

    ada_seen: list[Any] = []

    def ada_spy(positives: torch.Tensor, negatives: torch.Tensor, **kw: Any) -> Darkness:
        ada_seen.append(kw.get("positive_weights"))
        return Darkness.fit(pos, negatives)

    monkeypatch.setattr(ada, "train_adaboost", ada_spy)
    train_with_mining("adaboost", pos, grey, 0, options=opts, mining_source=mining, positive_weights=w)
    assert len(ada_seen) == 3 and all(x is w for x in ada_seen)


# ----------------------------------------------------------------- the three families on generated videos
@pytest.fixture(scope="module")
def videos(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from synthaug.data.synthvideo import make_panning_video

    root = tmp_path_factory.mktemp("train_videos")
    for i, stem in enumerate(["V_DRONE_003", "V_DRONE_010", "V_DRONE_027", "V_DRONE_031"]):
        make_panning_video(root, n_frames=10, size=(160, 128), seed=i, name=stem)
    make_panning_video(root, n_frames=10, size=(160, 128), seed=9, name="V_BIRD_002", class_name="bird")
    (root / "labels" / "notes.json").write_text(json.dumps({"not": "a label file"}))
    return root


@pytest.mark.parametrize("kind", ["hog", "adaboost", "cnn"])
def test_every_family_mines_and_logs(videos: Path, kind: str) -> None:
    from synthaug.detectors.training_sets import frames_training_set

    d = frames_training_set(["V_DRONE_003", "V_DRONE_010"], videos / "videos", videos / "labels", frame_step=2,
                            negatives_per_video=40)
    opts = TrainOptions(hog_components=1, hog_mining_rounds=0, ada_rounds=10, ada_candidates=200, cnn_epochs=2,
                        mining_rounds=1, mining_stride=3, mining_per_frame=4, scales=(1.0, 0.8), val_stride=3)
    src = VideoFrames(videos / "videos", videos / "labels", positive=["V_DRONE_003", "V_DRONE_010"], negative=["V_BIRD_002"], stride=3)
    val = VideoFrames(videos / "videos", videos / "labels", positive=["V_DRONE_027"], stride=3, null_frames=True)
    res = train_with_mining(kind, d["positives"], d["negatives"], 0, box_in_window=(6, 6, 28, 28), options=opts,
                            mining_source=src, val_frames=val)
    r0, r1 = res.log["rounds"]
    assert r1["added"] > 0 and r1["frames_scanned"] == 12 and r1["negatives"] == r0["negatives"] + r1["added"]
    assert r0["val"]["frames"] == 4 and r0["val"]["objects"] == 4 and isinstance(r1["val"]["fp"], int)
    assert res.detector.kind == kind and res.detector.box_in_window == (6.0, 6.0, 28.0, 28.0)
    assert res.log["chosen_round"] == (1 if r1["val"]["fp"] < r0["val"]["fp"] else 0)


def test_mining_frame_scale_mines_rescaled_frames_masking_their_boxes(videos: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """TrainOptions(mining_frame_scale=...): every mined frame reaches the scan resized by its own factor (the one
    frame_scale draws from the seed, video and index), its labelled boxes scaled with it; native frames otherwise."""
    import synthaug.detectors.training as training
    from synthaug.detectors.frames import frame_scale
    from synthaug.detectors.training_sets import frames_training_set

    d = frames_training_set(["V_DRONE_003"], videos / "videos", videos / "labels", frame_step=2, negatives_per_video=40)
    src = VideoFrames(videos / "videos", videos / "labels", positive=["V_DRONE_003"], negative=["V_BIRD_002"], stride=3)
    native = {(f.video, f.index): f for f in src}
    seen: list[tuple[str, int, tuple[int, int], np.ndarray | None]] = []
    real_mine = training.mine_hard_negatives

    def spy(det, frames, **kw):
        for f in frames:
            seen.append((f.video, f.index, tuple(f.image.shape[-2:]), f.boxes))
        return real_mine(det, frames, **kw)

    monkeypatch.setattr(training, "mine_hard_negatives", spy)
    opts = TrainOptions(ada_rounds=10, ada_candidates=200, mining_rounds=2, mining_per_frame=4, scales=(1.0, 0.8),
                        mining_frame_scale=(0.75, 2.0))
    res = train_with_mining("adaboost", d["positives"], d["negatives"], 3, options=opts, mining_source=src)
    assert len(seen) == 2 * len(native) and res.log["mining"]["frame_scale"] == [0.75, 2.0]
    factors = []
    for video, index, shape, boxes in seen:
        f = frame_scale((0.75, 2.0), 3, video, index)
        h, w = native[(video, index)].image.shape
        assert shape == (round(h * f), round(w * f))  # resize_image's rounding
        if native[(video, index)].boxes is None:
            assert boxes is None
        else:
            s = np.array([shape[1] / w, shape[0] / h] * 2)
            np.testing.assert_allclose(boxes, native[(video, index)].boxes * s)
        factors.append(f)
    assert [a[:3] for a in seen[: len(native)]] == [b[:3] for b in seen[len(native):]]  # same factors every round
    assert min(factors) < 1.0 < max(factors) and len(set(factors)) > 3
    assert [frame_scale((0.75, 2.0), 4, v, i) for v, i in native] != [frame_scale((0.75, 2.0), 3, v, i) for v, i in native]
    seen.clear()
    train_with_mining("adaboost", d["positives"], d["negatives"], 3, options=replace(opts, mining_frame_scale=(1, 1)),
                      mining_source=src)
    assert [s[2] for s in seen] == [native[(v, i)].image.shape for v, i, _, _ in seen]


def test_ada_energy_floor_is_in_units_of_the_negatives_gradient_level() -> None:
    from synthaug.detectors.adaboost import gradient_level
    from synthaug.detectors.toy import toy_patches

    pos, neg = toy_patches(30, 40, seed=2)
    det = train_detector("adaboost", pos, neg, 0, options=TrainOptions(ada_rounds=8, ada_candidates=100,
                                                                      ada_energy_floor=0.5))
    assert det.learners.floor == pytest.approx(0.5 * gradient_level(neg), rel=1e-12) and det.learners.floor > 0
    paper = train_detector("adaboost", pos, neg, 0, options=TrainOptions(ada_rounds=8, ada_candidates=100, ada_energy_floor=0))
    assert paper.learners.floor == 0
    default = train_detector("adaboost", pos, neg, 0, options=TrainOptions(ada_rounds=8, ada_candidates=100))
    assert default.learners.floor == pytest.approx(gradient_level(neg), rel=1e-12)  # the default: 1 x the level
    o = TrainOptions(ada_energy_floor=0.5)
    assert o.key_fields("adaboost")["ada_energy_floor"] == 0.5 and "ada_energy_floor" not in o.key_fields("hog")
    assert "ada_energy_floor" not in TrainOptions(ada_energy_floor=0).key_fields("adaboost")  # the cells before it
    for bad in (-0.1, float("inf"), True):
        with pytest.raises(ValueError, match="ada_energy_floor"):
            TrainOptions(ada_energy_floor=bad)


def test_frame_scale_is_log_uniform_and_refuses_bad_ranges() -> None:
    from scipy import stats

    from synthaug.detectors.frames import RescaledFrames, frame_scale

    f = np.array([frame_scale((0.5, 2.0), 0, f"V_{v:03d}", i) for v in range(40) for i in range(0, 300, 10)])
    assert f.min() >= 0.5 and f.max() <= 2.0
    assert stats.kstest(np.log(f), stats.uniform(np.log(0.5), np.log(4.0)).cdf).pvalue > 0.01
    for bad in [(2.0, 1.0), (0.0, 1.0), (1.0, float("inf")), (1.0,), "ab"]:
        with pytest.raises(ValueError, match="frame scale range"):
            TrainOptions(mining_frame_scale=bad)
        with pytest.raises(ValueError, match="frame scale range"):
            RescaledFrames([], bad)
    assert "mining_frame_scale" not in TrainOptions(mining_frame_scale=(1, 1)).key_fields("adaboost")  # native: the old key
    assert TrainOptions(mining_frame_scale=[0.75, 2]).key_fields("hog")["mining_frame_scale"] == (0.75, 2.0)


# ----------------------------------------------------------------- split by video
def test_split_by_video_deterministic_any_numbering(videos: Path, tmp_path: Path) -> None:
    vs = discover_videos(videos / "videos", videos / "labels")
    assert vs.classes == {"V_BIRD_002": "bird", "V_DRONE_003": "drone", "V_DRONE_010": "drone", "V_DRONE_027": "drone",
                          "V_DRONE_031": "drone"}
    a = split_by_video(vs, "drone", seed=3)
    assert a == split_by_video(vs, "drone", seed=3)
    assert a["source"] == "auto" and len(a["train"]) == 3 and len(a["val"]) == 1
    assert set(a["train"]) | set(a["val"]) == {s for s, c in vs.classes.items() if c == "drone"}
    assert not set(a["train"]) & set(a["val"]) and a["negative_train"] + a["negative_val"] == ["V_BIRD_002"]
    vals = {tuple(split_by_video(vs, "drone", seed=s)["val"]) for s in range(8)}
    assert len(vals) > 1  # the seed moves the split
    split = {"format": "synthaug.video_split", "version": 1, "classes": dict(vs.classes),
             "train": ["V_DRONE_003", "V_DRONE_031", "V_DRONE_099"], "val": ["V_DRONE_010"], "test": ["V_DRONE_027"],
             "hard_negatives": {"train": ["V_BIRD_002"], "val": [], "test": []}}
    (tmp_path / "split.json").write_text(json.dumps(split))
    b = split_by_video(vs, "drone", split=tmp_path / "split.json")
    assert (b["train"], b["val"], b["negative_train"]) == (["V_DRONE_003", "V_DRONE_031"], ["V_DRONE_010"], ["V_BIRD_002"])
    with pytest.raises(TrainingInputError, match="--class.*'cat'") as e:
        split_by_video(vs, "cat")
    assert e.value.option == "--class"
    with pytest.raises(TrainingInputError, match="--split"):
        split_by_video(vs, "drone", split=tmp_path / "missing.json")


@pytest.mark.parametrize("field, value", [("box_stride", 0), ("cnn_shift", -1), ("cnn_shift", 20), ("mining_stride", 0)])
def test_train_options_refuse_bad_values_naming_the_field(field: str, value: int) -> None:
    with pytest.raises(ValueError, match=field):
        TrainOptions(**{field: value})


def test_ada_transfer_makes_the_added_positives_adaboosts_source(monkeypatch: pytest.MonkeyPatch) -> None:
    """``TrainOptions.ada_transfer``: the positives after the real ones reach ``train_adaboost`` as its source
    positives; without a real count, with only real positives or when off, none do; AdaBoost's keys carry it when
    set, no other family's."""
    import synthaug.detectors.adaboost as ada
    from synthaug.detectors.toy import toy_patches

    seen: list[int] = []
    real_train = ada.train_adaboost

    def spy(*a, **k):
        seen.append(k.get("source_positives", 0))
        return real_train(*a, **k)

    monkeypatch.setattr(ada, "train_adaboost", spy)
    pos, neg = toy_patches(30, 40, seed=2)
    small = TrainOptions(ada_rounds=6, ada_candidates=60)
    on = replace(small, ada_transfer=True)
    train_detector("adaboost", pos, neg, 0, options=on, real_positives=20)
    train_detector("adaboost", pos, neg, 0, options=on)                      # no real count: all real
    train_detector("adaboost", pos, neg, 0, options=on, real_positives=30)   # nothing added
    train_detector("adaboost", pos, neg, 0, options=small, real_positives=20)  # off
    assert seen == [10, 0, 0, 0]
    assert TrainOptions(ada_transfer=True).key_fields("adaboost")["ada_transfer"] is True
    assert "ada_transfer" not in TrainOptions().key_fields("adaboost")  # the cells before it
    assert "ada_transfer" not in TrainOptions(ada_transfer=True).key_fields("hog")
    with pytest.raises(ValueError, match="ada_transfer"):
        TrainOptions(ada_transfer=1)


def test_ada_cascade_real_calibrates_adaboosts_cascade_on_the_real_positives(monkeypatch: pytest.MonkeyPatch) -> None:
    """``TrainOptions.ada_cascade = "real"``: ``train_adaboost`` gets the real count as its ``cascade_positives``
    when positives were added (none without a real count, with only real positives or at ``"all"``); AdaBoost's keys
    carry it when set, no other family's; an unknown value is refused."""
    import synthaug.detectors.adaboost as ada
    from synthaug.detectors.toy import toy_patches

    seen: list[int | None] = []
    real_train = ada.train_adaboost

    def spy(*a, **k):
        seen.append(k.get("cascade_positives"))
        return real_train(*a, **k)

    monkeypatch.setattr(ada, "train_adaboost", spy)
    pos, neg = toy_patches(30, 40, seed=2)
    small = TrainOptions(ada_rounds=6, ada_candidates=60, ada_cascade="all")
    on = replace(small, ada_cascade="real")
    det = train_detector("adaboost", pos, neg, 0, options=on, real_positives=20)
    train_detector("adaboost", pos, neg, 0, options=on)                      # no real count: all real
    train_detector("adaboost", pos, neg, 0, options=on, real_positives=30)   # nothing added
    train_detector("adaboost", pos, neg, 0, options=small, real_positives=20)  # every positive
    assert seen == [20, None, None, None]
    ends = torch.tensor(det._stage_ends()) - 1
    assert (det.partial_scores(pos[:20])[:, ends[:-1]] >= det.rejection[:-1]).all()  # no real positive rejected
    assert TrainOptions(ada_cascade="real").key_fields("adaboost")["ada_cascade"] == "real"
    assert "ada_cascade" not in TrainOptions(ada_cascade="all").key_fields("adaboost")  # the cells before it
    assert TrainOptions().ada_cascade == "real" and TrainOptions().key_fields("adaboost")["ada_cascade"] == "real"
    assert "ada_cascade" not in TrainOptions(ada_cascade="real").key_fields("cnn")
    with pytest.raises(ValueError, match="ada_cascade"):
        TrainOptions(ada_cascade="target")


def test_refresh_positives_redraws_the_added_positives_between_rounds() -> None:
    """``refresh_positives`` (the d_CNN refit's hook) is called with round r's detector once round r + 1's negatives
    are mined; round r + 1 trains on what it returns; a wrong shape or changed real positives are refused."""
    mining = [MiningFrame(_frame([(4 * i, 8, 100), (80, 60, 0)]), np.array([[4.0 * i, 8.0, 40.0, 40.0]]), "V_M_001", i)
              for i in range(4)]
    grey = torch.full((20, 1, 40, 40), GREY / 255.0)
    pos = torch.cat([torch.full((5, 1, 40, 40), 100 / 255.0), torch.full((3, 1, 40, 40), 90 / 255.0)])  # 5 real, 3 added
    seen, calls = [], []

    def fit(p: torch.Tensor, n: torch.Tensor) -> Darkness:
        seen.append(p.clone())
        return Darkness.fit(p, n)

    def refresh(det: Any, r: int) -> torch.Tensor:
        calls.append((det, r))
        new = pos.clone()
        new[5:] = (80 - r) / 255.0
        return new

    opts = TrainOptions(mining_rounds=2, mining_per_frame=3, scales=(1.0,))
    res = train_with_mining("toy", pos, grey, 0, options=opts, mining_source=mining, fit=fit, real_positives=5,
                            refresh_positives=refresh)
    assert [r["round"] for r in res.log["rounds"]] == [0, 1, 2]
    assert [r for _, r in calls] == [0, 1] and all(isinstance(d, Darkness) for d, _ in calls)
    assert calls[1][0] is not calls[0][0]  # round 1's detector, not round 0's
    assert torch.equal(seen[0], pos)  # round 0: the given positives
    for k, r in ((1, 0), (2, 1)):  # round k: what the refresh after round k - 1 returned
        assert torch.equal(seen[k][:5], pos[:5]) and torch.allclose(seen[k][5:], torch.full((3, 1, 40, 40), (80 - r) / 255.0))
    assert "refresh_s" in res.log["rounds"][1] and "refresh_s" not in res.log["rounds"][0]
    with pytest.raises(ValueError, match="shape"):
        train_with_mining("toy", pos, grey, 0, options=opts, mining_source=mining, fit=fit, real_positives=5,
                          refresh_positives=lambda d, r: pos[:7])
    with pytest.raises(ValueError, match="real"):
        train_with_mining("toy", pos, grey, 0, options=opts, mining_source=mining, fit=fit, real_positives=5,
                          refresh_positives=lambda d, r: torch.zeros_like(pos))
