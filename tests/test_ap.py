"""Average precision and PR curves on hand-computed cases, and cross-checked against pycocotools and torchmetrics."""

from __future__ import annotations

import contextlib
import io
import math

import numpy as np
import pytest
import torch
from torchvision.ops import box_convert, box_iou

from synthaug.evaluate.ap import average_precision, evaluate_detections, match_detections, plot_pr, precision_recall

BOX = [10.0, 10.0, 20.0, 20.0]


def det(*rows: list[float]) -> np.ndarray:
    return np.array(rows, dtype=float).reshape(-1, 5)


def gt(*rows: list[float]) -> np.ndarray:
    return np.array(rows, dtype=float).reshape(-1, 4)


def test_perfect_detector_ap_one() -> None:
    dets = [det(BOX + [0.9]), det(BOX + [0.8]), det(BOX + [0.7])]
    gts = [gt(BOX)] * 3
    res = evaluate_detections(dets, gts)
    assert res.ap == pytest.approx(1.0)
    assert res.ap_envelope == pytest.approx(1.0)
    assert res.n_true_positives == 3 and res.n_ground_truth == 3


def test_hand_computed_ranking() -> None:
    # 3 objects, 4 detections ranked: TP, FP, TP, FP (the last object is never found)
    # p = 1, 1/2, 2/3, 2/4 at r = 1/3, 1/3, 2/3, 2/3
    # AP = 1/3 * 1 + 0 * 1/2 + 1/3 * 2/3 + 0 = 5/9
    far = [200.0, 200.0, 20.0, 20.0]
    dets = [det(BOX + [0.9], far + [0.8]), det(BOX + [0.7], far + [0.6]), det()]
    gts = [gt(BOX), gt(BOX), gt(BOX)]
    res = evaluate_detections(dets, gts)
    assert res.ap == pytest.approx(5 / 9)
    # envelope: p = max(1, ...) = 1 on (0, 1/3], max(2/3, 1/2) = 2/3 on (1/3, 2/3]: same 5/9
    assert res.ap_envelope == pytest.approx(5 / 9)
    np.testing.assert_allclose(res.precision, [1, 1 / 2, 2 / 3, 2 / 4])
    np.testing.assert_allclose(res.recall, [1 / 3, 1 / 3, 2 / 3, 2 / 3])


def test_envelope_differs_from_raw() -> None:
    # ranks: FP, TP, TP with 2 objects -> p = 0, 1/2, 2/3 at r = 0, 1/2, 1
    # raw AP = 0 * 0 + 1/2 * 1/2 + 1/2 * 2/3 = 7/12 ; envelope p = 2/3 everywhere -> 2/3
    far = [300.0, 300.0, 20.0, 20.0]
    dets = [det(far + [0.9], BOX + [0.8]), det(BOX + [0.7])]
    gts = [gt(BOX), gt(BOX)]
    res = evaluate_detections(dets, gts)
    assert res.ap == pytest.approx(7 / 12)
    assert res.ap_envelope == pytest.approx(2 / 3)


def test_duplicates_are_false_positives_and_iou_threshold_inclusive() -> None:
    # wide boxes shifted by a third of their width: IoU = 200 / 400 = 0.5 exactly -> a match
    wide = [0.0, 0.0, 30.0, 10.0]
    shifted = [10.0, 0.0, 30.0, 10.0]
    assert box_iou(box_convert(torch.tensor([shifted]), "xywh", "xyxy"), box_convert(torch.tensor([wide]), "xywh", "xyxy")).item() == 0.5
    scores, tp, n_gt, n_frames = match_detections([det(shifted + [0.9], wide + [0.8])], [gt(wide)], 0.5)
    assert tp.tolist() == [True, False] and n_gt == 1 and n_frames == 1  # the exact box came second: duplicate
    # with a stricter threshold the first misses and the second (exact) box matches
    _, tp, _, _ = match_detections([det(shifted + [0.9], wide + [0.8])], [gt(wide)], 0.6)
    assert tp.tolist() == [False, True]


def test_greedy_by_score_across_frames_and_multiple_objects() -> None:
    other = [60.0, 60.0, 20.0, 20.0]
    dets = [det(BOX + [0.5], other + [0.95]), det(BOX + [0.7])]
    gts = [gt(BOX, other), gt()]  # second frame: no object -> its detection is a FP
    scores, tp, n_gt, _ = match_detections(dets, gts)
    assert scores.tolist() == [0.95, 0.7, 0.5]
    assert tp.tolist() == [True, False, True]
    assert n_gt == 2


def test_unprocessed_frames_and_missing_labels() -> None:
    dets = [det(BOX + [0.9]), None, det(BOX + [0.5]), det(BOX + [0.4])]
    gts = [gt(BOX), gt(BOX), None]  # one label fewer than frames: the 4th frame is ignored
    res = evaluate_detections(dets, gts)
    assert res.n_frames == 2  # frame 1 unprocessed, frame 3 unlabelled
    assert res.n_ground_truth == 1  # the object of the skipped frame does not count
    # TP (0.9) then FP (0.5 on a frame without object): AP = 1 * 1 = 1
    assert res.ap == pytest.approx(1.0)
    assert res.precision.tolist() == [1.0, 0.5]


def test_ties_enter_together() -> None:
    far = [300.0, 300.0, 20.0, 20.0]
    p, r, t = precision_recall(np.array([0.5, 0.5]), np.array([False, True]), 1)
    assert p.tolist() == [0.5] and r.tolist() == [1.0] and t.tolist() == [0.5]
    # order inside a tie does not change AP
    a = evaluate_detections([det(far + [0.5]), det(BOX + [0.5])], [gt(BOX), gt(BOX)]).ap
    b = evaluate_detections([det(BOX + [0.5]), det(far + [0.5])], [gt(BOX), gt(BOX)]).ap
    assert a == pytest.approx(b) == pytest.approx(0.25)


def test_no_detections_and_no_ground_truth() -> None:
    res = evaluate_detections([det(), det()], [gt(BOX), gt(BOX)])
    assert res.ap == 0.0 and res.n_detections == 0
    res = evaluate_detections([det(BOX + [0.9])], [None])
    assert math.isnan(res.ap) and res.metrics()["ap"] is None


def test_average_precision_validation() -> None:
    with pytest.raises(ValueError, match="same shape"):
        average_precision(np.zeros(2), np.zeros(3))
    with pytest.raises(ValueError, match="non-decreasing"):
        average_precision(np.ones(2), np.array([0.5, 0.2]))
    with pytest.raises(ValueError, match="iou_threshold"):
        match_detections([], [], 0.0)


def test_plot_pr_writes_png(tmp_path) -> None:
    res = evaluate_detections([det(BOX + [0.9])], [gt(BOX)])
    out = plot_pr({"hog": res}, tmp_path / "sub" / "pr.png", title="t")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_all_point_interpolation_hand_computed() -> None:
    # 3 objects; ranked FP, TP, FP, TP, TP (scores 0.9 .. 0.5):
    #   p = 0, 1/2, 1/3, 2/4, 3/5   at   r = 0, 1/3, 1/3, 2/3, 1
    # raw step curve: 1/3 * 1/2 + 0 + 1/3 * 2/4 + 1/3 * 3/5 = 8/15
    # all-point envelope: p^ = 3/5 at every rank (the last point dominates) -> 3/5
    far = [300.0, 300.0, 20.0, 20.0]
    dets = [det(far + [0.9], BOX + [0.8]), det(far + [0.7], BOX + [0.6]), det(BOX + [0.5])]
    res = evaluate_detections(dets, [gt(BOX)] * 3)
    np.testing.assert_allclose(res.precision, [0, 1 / 2, 1 / 3, 2 / 4, 3 / 5])
    np.testing.assert_allclose(res.recall, [0, 1 / 3, 1 / 3, 2 / 3, 1])
    assert res.ap == pytest.approx(8 / 15)
    assert res.ap_envelope == pytest.approx(3 / 5)
    assert average_precision(res.precision, res.recall, envelope=True) == pytest.approx(_voc_all_point(res.precision, res.recall))


def test_all_point_and_101_point_differ_by_hand() -> None:
    # the curve of test_hand_computed_ranking: envelope 1 on (0, 1/3], 2/3 on (1/3, 2/3], nothing after
    # all points: 1/3 + 2/9 = 5/9; COCO's 101 points: 34 recalls (0 .. 0.33) at 1, 33 (0.34 .. 0.66) at 2/3, 34 at 0
    far = [200.0, 200.0, 20.0, 20.0]
    res = evaluate_detections([det(BOX + [0.9], far + [0.8]), det(BOX + [0.7], far + [0.6]), det()], [gt(BOX)] * 3)
    assert res.ap_envelope == pytest.approx(5 / 9)
    grid = _interpolated_precision(res.precision, res.recall, np.linspace(0, 1, 101))
    assert grid.mean() == pytest.approx(56 / 101)


def _voc_all_point(precision: np.ndarray, recall: np.ndarray) -> float:
    """VOC 2010+ devkit's ``voc_ap``: sentinels, monotone envelope, sum where recall changes."""
    mrec = np.r_[0.0, recall, 1.0]
    mpre = np.r_[0.0, precision, 0.0]
    for i in range(mpre.size - 1, 0, -1):
        mpre[i - 1] = max(mpre[i - 1], mpre[i])
    i = np.nonzero(mrec[1:] != mrec[:-1])[0]
    return float(np.sum((mrec[i + 1] - mrec[i]) * mpre[i + 1]))


def _interpolated_precision(precision: np.ndarray, recall: np.ndarray, recall_thresholds: np.ndarray) -> np.ndarray:
    """COCO's interpolation of our PR curve: at each recall threshold r the best precision at recall >= r (0 past the end)."""
    envelope = np.maximum.accumulate(precision[::-1])[::-1]
    idx = np.searchsorted(recall, recall_thresholds, side="left")
    out = np.zeros(len(recall_thresholds))
    valid = idx < recall.size
    out[valid] = envelope[idx[valid]]
    return out


def _random_frames(seed: int, n_frames: int = 40) -> tuple[list[np.ndarray], list[np.ndarray | None]]:
    """Frames of 640x480 with 0-3 disjoint objects (one per 160x160 cell, so that no detection can reach
    IoU 0.5 with two objects: the VOC and COCO matching rules then agree), jittered detections of them
    (IoUs on both sides of 0.5), false alarms, all scores distinct. Frames 0 and 7 have no object
    (0 as None, 7 as an empty array), frames 1 and 8 no detection, frame 2 neither."""
    rng = np.random.default_rng(seed)
    cells = [(cx * 160.0, cy * 160.0) for cx in range(4) for cy in range(3)]
    dets: list[np.ndarray] = []
    gts: list[np.ndarray | None] = []
    for f in range(n_frames):
        n_obj = 0 if f in (0, 2, 7) else int(rng.integers(1, 4))
        chosen = rng.choice(len(cells), size=n_obj, replace=False)
        objs = []
        for c in chosen:
            w, h = rng.uniform(20, 80, size=2)
            x = cells[c][0] + rng.uniform(0, 160 - w)
            y = cells[c][1] + rng.uniform(0, 160 - h)
            objs.append([x, y, w, h])
        g = np.array(objs, dtype=float).reshape(-1, 4)
        rows = []
        if f not in (1, 2, 8):
            for x, y, w, h in g:
                for _ in range(int(rng.integers(0, 3))):  # missed, found, or found twice (a duplicate)
                    s = rng.uniform(0.6, 1.4, size=2)
                    rows.append([x + rng.normal(0, 0.2) * w, y + rng.normal(0, 0.2) * h, w * s[0], h * s[1]])
            for _ in range(int(rng.integers(0 if f else 1, 4))):  # false alarms (frame 0 gets at least one)
                w, h = rng.uniform(20, 80, size=2)
                rows.append([rng.uniform(0, 560), rng.uniform(0, 400), w, h])
        d = np.array(rows, dtype=float).reshape(-1, 4)
        dets.append(np.c_[d, rng.uniform(0, 1, size=len(d))])
        gts.append(None if f == 0 else g)
    return dets, gts


def _coco_precision(dets: list[np.ndarray], gts: list[np.ndarray | None], iou: float) -> tuple[np.ndarray, np.ndarray]:
    """pycocotools' interpolated precision at its 101 recall thresholds (one category, all areas, up to 1000 detections)."""
    from pycocotools.coco import COCO
    from pycocotools.cocoeval import COCOeval

    images, annotations, results = [], [], []
    for f, (d, g) in enumerate(zip(dets, gts)):
        images.append({"id": f, "width": 640, "height": 480})
        for box in [] if g is None else g:
            annotations.append({"id": len(annotations) + 1, "image_id": f, "category_id": 1, "bbox": [float(v) for v in box],
                                "area": float(box[2] * box[3]), "iscrowd": 0})
        results.extend({"image_id": f, "category_id": 1, "bbox": [float(v) for v in row[:4]], "score": float(row[4])} for row in d)
    with contextlib.redirect_stdout(io.StringIO()):
        coco_gt = COCO()
        coco_gt.dataset = {"images": images, "annotations": annotations, "categories": [{"id": 1, "name": "object"}]}
        coco_gt.createIndex()
        coco_dt = coco_gt.loadRes(results)
        ev = COCOeval(coco_gt, coco_dt, "bbox")
        ev.params.iouThrs = np.array([iou])
        ev.params.maxDets = [1000]
        ev.params.areaRng = [[0.0, 1e10]]
        ev.params.areaRngLbl = ["all"]
        ev.evaluate()
        ev.accumulate()
    return ev.eval["precision"][0, :, 0, 0, 0], ev.params.recThrs


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("iou", [0.5, 0.3])
def test_ap_matches_pycocotools(seed: int, iou: float) -> None:
    pytest.importorskip("pycocotools")
    dets, gts = _random_frames(seed)
    scores = np.concatenate([d[:, 4] for d in dets])
    assert np.unique(scores).size == scores.size  # ties would be ordered differently by the two
    assert any(g is None or len(g) == 0 for g in gts) and any(len(d) == 0 for d in dets)
    res = evaluate_detections(dets, gts, iou)
    coco, rec_thrs = _coco_precision(dets, gts, iou)
    ours = _interpolated_precision(res.precision, res.recall, rec_thrs)
    assert res.n_true_positives > 5 and res.n_detections - res.n_true_positives > 5  # a non-trivial curve
    np.testing.assert_allclose(ours, coco, rtol=0, atol=1e-12)
    # the all-point envelope integral and its 101-point sampling differ by at most ~2/100 (a monotone p^)
    assert abs(res.ap_envelope - ours.mean()) <= 0.02 + 1e-12


def test_hand_case_matches_pycocotools() -> None:
    pytest.importorskip("pycocotools")
    far = [200.0, 200.0, 20.0, 20.0]
    dets = [det(BOX + [0.9], far + [0.8]), det(BOX + [0.7], far + [0.6]), det()]
    coco, _ = _coco_precision(dets, [gt(BOX)] * 3, 0.5)
    assert coco.mean() == pytest.approx(56 / 101)


def test_ap_matches_torchmetrics() -> None:
    pytest.importorskip("pycocotools")  # torchmetrics' default backend
    detection = pytest.importorskip("torchmetrics.detection")
    dets, gts = _random_frames(11, n_frames=30)
    assert max(len(d) for d in dets) <= 100  # the default max_detection_thresholds (1, 10, 100) keep them all
    metric = detection.MeanAveragePrecision(box_format="xywh", iou_thresholds=[0.5])
    preds, target = [], []
    for d, g in zip(dets, gts):
        g = np.zeros((0, 4)) if g is None else g
        preds.append({"boxes": torch.from_numpy(d[:, :4]).reshape(-1, 4), "scores": torch.from_numpy(d[:, 4]), "labels": torch.zeros(len(d), dtype=torch.long)})
        target.append({"boxes": torch.from_numpy(g).reshape(-1, 4), "labels": torch.zeros(len(g), dtype=torch.long)})
    metric.update(preds, target)
    out = metric.compute()
    res = evaluate_detections(dets, gts, 0.5)
    ours = _interpolated_precision(res.precision, res.recall, np.linspace(0, 1, 101)).mean()
    assert 0.05 < ours < 0.95
    assert float(out["map"]) == pytest.approx(ours, abs=1e-6)
    assert float(out["map_50"]) == pytest.approx(ours, abs=1e-6)


def _iou_xywh_numpy(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The former numpy XYWH IoU of the evaluation (areas as w * h)."""
    x1 = np.maximum(a[:, None, 0], b[None, :, 0])
    y1 = np.maximum(a[:, None, 1], b[None, :, 1])
    x2 = np.minimum(a[:, None, 0] + a[:, None, 2], b[None, :, 0] + b[None, :, 2])
    y2 = np.minimum(a[:, None, 1] + a[:, None, 3], b[None, :, 1] + b[None, :, 3])
    inter = np.clip(x2 - x1, 0, None) * np.clip(y2 - y1, 0, None)
    union = (a[:, 2] * a[:, 3])[:, None] + (b[:, 2] * b[:, 3])[None, :] - inter
    return np.where(union > 0, inter / np.where(union > 0, union, 1.0), 0.0)


@pytest.mark.parametrize("seed", range(3))
def test_matching_unchanged_by_xyxy_iou(seed: int) -> None:
    """The torchvision XYXY IoU labels every detection as the former numpy XYWH one did (same AP),
    on float32 detections (what detect_multiscale returns) and float64 labels."""
    dets, gts = _random_frames(100 + seed)
    dets = [d.astype(np.float32).astype(np.float64) for d in dets]
    _, tp, _, _ = match_detections(dets, gts, 0.5)
    # the former rule, written out: global score order, argmax IoU, unclaimed and >= threshold
    entries = sorted(((d[k, 4], f, k) for f, d in enumerate(dets) for k in range(len(d))), key=lambda e: -e[0])
    claimed = {f: np.zeros(0 if g is None else len(g), dtype=bool) for f, g in enumerate(gts)}
    expected = []
    for _, f, k in entries:
        g = np.zeros((0, 4)) if gts[f] is None else gts[f]
        if len(g) == 0:
            expected.append(False)
            continue
        ious = _iou_xywh_numpy(dets[f][k : k + 1, :4], g)[0]
        j = int(np.argmax(ious))
        expected.append(bool(ious[j] >= 0.5 and not claimed[f][j]))
        claimed[f][j] |= expected[-1]
    assert tp.tolist() == expected
