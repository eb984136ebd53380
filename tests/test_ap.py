"""Average precision and PR curves on hand-computed cases."""

from __future__ import annotations

import math

import numpy as np
import pytest

from synthaug.evaluate.ap import average_precision, evaluate_detections, iou_xywh, match_detections, plot_pr, precision_recall

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
    assert iou_xywh(np.array([shifted]), np.array([wide]))[0, 0] == 0.5
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
