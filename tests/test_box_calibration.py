"""A detector's own box correction (synthaug.detectors.box_calibration): the least squares against numpy's, the
matching against a hand-worked case, the state through the detector file, and the behaviour it exists for — a
detector whose boxes are systematically too small gets the labelled boxes back on frames it was not fitted on."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from torchvision.ops import box_iou

from synthaug.detectors.base import load_detector, save_detector
from synthaug.detectors.box_calibration import (
    CalibratedBoxRegressor, calibrate_boxes, detection_pairs, fit_calibration, size_features,
)
from synthaug.detectors.box_cnn import regressor_from_state_dict
from synthaug.detectors.boxes import BoxRegressor, decode_deltas, encode_deltas
from synthaug.detectors.frames import MiningFrame


def _boxes(n: int, seed: int) -> torch.Tensor:
    g = np.random.default_rng(seed)
    side = np.exp(g.uniform(np.log(10), np.log(90), n))
    x, y = g.uniform(0, 500, n), g.uniform(0, 400, n)
    asp = g.uniform(0.8, 1.6, n)
    w, h = side * np.sqrt(asp), side / np.sqrt(asp)
    return torch.as_tensor(np.stack([x, y, x + w, y + h], 1))


def test_fit_recovers_a_size_dependent_bias_and_equals_numpy_least_squares():
    boxes = _boxes(300, 0)
    true = torch.tensor([[0.02, -0.01, 0.15, 0.12], [0.0, 0.03, -0.10, -0.08]], dtype=torch.float64)
    targets = decode_deltas(boxes.float(), size_features(boxes) @ true).double()
    torch.testing.assert_close(fit_calibration(boxes, targets), true, atol=1e-4, rtol=0)
    # with noise: numpy's least squares on [1, log(sqrt(wh) / 32)] against the encoded deltas
    g = np.random.default_rng(1)
    noisy = targets + torch.as_tensor(g.normal(0, 1.5, targets.shape))
    noisy[:, 2:] = torch.maximum(noisy[:, 2:], noisy[:, :2] + 1)
    b = boxes.numpy()
    x = np.c_[np.ones(300), 0.5 * np.log((b[:, 2] - b[:, 0]) * (b[:, 3] - b[:, 1])) - np.log(32)]
    y = encode_deltas(boxes, noisy).numpy()
    np.testing.assert_allclose(fit_calibration(boxes, noisy).numpy(), np.linalg.lstsq(x, y, rcond=None)[0], atol=1e-9)


def test_one_box_size_fits_the_intercept_alone_and_too_few_pairs_is_an_error():
    boxes = torch.tensor([[0.0, 0.0, 20.0, 20.0], [50.0, 40.0, 70.0, 60.0], [5.0, 9.0, 25.0, 29.0]], dtype=torch.float64)
    targets = boxes + torch.tensor([-2.0, -2.0, 2.0, 2.0], dtype=torch.float64)  # every side 20 -> 24
    coef = fit_calibration(boxes, targets)
    torch.testing.assert_close(coef[0], torch.tensor([0.0, 0.0, np.log(1.2), np.log(1.2)], dtype=torch.float64))
    assert torch.equal(coef[1], torch.zeros(4, dtype=torch.float64))
    with pytest.raises(ValueError, match="at least 2"):
        fit_calibration(boxes[:1], targets[:1])


def test_inverse_form_is_unbiased_for_every_object_size_where_regression_leans_to_the_training_sizes():
    """A detector whose sizes compress the true range (log side = a + 0.8 log true + noise): fitted on a mix of
    mostly mid-size objects, the regression form makes small objects' boxes too large on a mix with many small ones;
    the inverse form's slope is numpy's straight line of the detected size on the true one, inverted, and its boxes
    are a median of 0 off the true size in every size band."""
    g = np.random.default_rng(3)

    def pairs(sides: np.ndarray) -> tuple[torch.Tensor, torch.Tensor]:
        x, y = g.uniform(0, 500, sides.size), g.uniform(0, 400, sides.size)
        det = np.exp(0.4 + 0.8 * np.log(sides) + g.normal(0, 0.12, sides.size))
        lab = torch.as_tensor(np.stack([x, y, x + sides, y + sides], 1))
        return torch.as_tensor(np.stack([x, y, x + det, y + det], 1)), lab

    train = np.exp(np.r_[g.normal(np.log(36), 0.2, 900), g.uniform(np.log(12), np.log(90), 100)])
    det, lab = pairs(train)
    f_det = np.log(det[:, 2].numpy() - det[:, 0].numpy()) - np.log(32)
    f_lab = np.log(lab[:, 2].numpy() - lab[:, 0].numpy()) - np.log(32)
    slope_ref = 1.0 / np.polyfit(f_lab, f_det, 1)[0] - 1.0
    inv, reg = fit_calibration(det, lab, form="inverse"), fit_calibration(det, lab)
    np.testing.assert_allclose(inv[1, 2:].numpy(), [slope_ref, slope_ref], rtol=1e-9)
    torch.testing.assert_close(inv[:, :2], reg[:, :2])  # the positions: least squares either way
    test = np.exp(g.uniform(np.log(12), np.log(90), 3000))  # many small objects
    d2, l2 = pairs(test)
    true_side = l2[:, 2] - l2[:, 0]
    for coef, small_bias in ((inv, (-0.04, 0.04)), (reg, (0.08, 1.0))):
        out = decode_deltas(d2.float(), size_features(d2) @ coef).double()
        err = torch.log((out[:, 2] - out[:, 0]) / true_side)
        small, large = true_side < 20, true_side > 60
        assert small_bias[0] < float(err[small].median()) < small_bias[1]
        if coef is inv:
            assert abs(float(err[large].median())) < 0.04
        else:
            assert float(err[large].median()) < -0.08
    with pytest.raises(ValueError, match="form"):
        fit_calibration(det, lab, form="median")

    def never(*a, **k):
        raise AssertionError("a detection ran before the form was checked")

    with pytest.raises(ValueError, match="form must be one of"):  # refused before any frame is detected
        calibrate_boxes(object(), [object()], form="median", detect=never)


def test_pairs_follow_the_greedy_rule_by_score():
    labelled = np.array([[0, 0, 10, 10], [100, 100, 10, 10]], float)
    dets = np.array([
        [1, 1, 10, 10, 0.5],      # IoU 0.68 with the first box, but a better-scoring detection takes it first
        [0, 0, 10, 12, 0.9],      # IoU 0.83 with the first box: matched
        [104, 104, 10, 10, 0.7],  # IoU 0.22 with the second: under 0.3, unmatched
        [102, 101, 10, 10, 0.4],  # IoU 0.56 with the second: matched
    ])
    p, g = detection_pairs(dets, labelled)
    torch.testing.assert_close(p, torch.tensor([[0.0, 0, 10, 12], [102, 101, 112, 111]], dtype=torch.float64))
    torch.testing.assert_close(g, torch.tensor([[0.0, 0, 10, 10], [100, 100, 110, 110]], dtype=torch.float64))
    p, _ = detection_pairs(dets, labelled, min_iou=0.2)
    assert p.shape[0] == 2 and p[1].tolist() == [104, 104, 114, 114]  # the better-scoring 0.22 takes the box first
    assert detection_pairs(dets, None)[0].shape == (0, 4) and detection_pairs(np.zeros((0, 5)), labelled)[0].shape == (0, 4)


def test_refine_is_the_base_map_then_the_correction_and_the_state_round_trips(tmp_path):
    base = BoxRegressor.identity()
    coef = torch.tensor([[0.05, -0.02, 0.2, 0.1], [0.01, 0.0, -0.05, 0.03]], dtype=torch.float64)
    cal = CalibratedBoxRegressor(base, coef, {"pairs": 3})
    image = torch.rand(1, 1, 80, 96)
    boxes = torch.tensor([[10.0, 12.0, 40.0, 30.0], [50.0, 20.0, 90.0, 70.0]])
    mapped = base.refine(image, boxes)
    torch.testing.assert_close(cal.refine(image, boxes), decode_deltas(mapped, size_features(mapped) @ coef))
    assert cal.refine(image, boxes[:0]).shape == (0, 4)
    back = regressor_from_state_dict(cal.state_dict())
    assert isinstance(back, CalibratedBoxRegressor) and torch.equal(back.coef, coef) and back.meta == {"pairs": 3}
    torch.testing.assert_close(back.refine(image, boxes), cal.refine(image, boxes))
    no_base = CalibratedBoxRegressor(None, coef)
    torch.testing.assert_close(no_base.refine(image, boxes), decode_deltas(boxes, size_features(boxes) @ coef))
    with pytest.raises(ValueError, match="finite"):
        CalibratedBoxRegressor(None, torch.zeros(3, 4))
    with pytest.raises(ValueError, match="malformed"):
        regressor_from_state_dict({"model": "calibrated", "base": None})


def test_a_detector_whose_boxes_are_too_small_gets_the_labelled_boxes_back(tmp_path):
    from synthaug.detectors.sliding import detect_multiscale
    from synthaug.detectors.toy import toy_frame, toy_patches
    from synthaug.detectors.training import TrainOptions, train_detector

    pos, neg = toy_patches(40, 80, seed=0)
    det = train_detector("hog", pos, neg, seed=0, options=TrainOptions(hog_components=1, hog_mining_rounds=0))
    det.box_in_window = (8.0, 8.0, 24.0, 24.0)  # the 40-px objects reported as 24-px boxes

    def frames(seeds):
        out = []
        for s in seeds:
            image, boxes = toy_frame(seed=s)
            out.append(MiningFrame((image[0, 0] * 255).round().to(torch.uint8).numpy(), boxes.numpy(), "V_T_001", s))
        return out

    cal = calibrate_boxes(det, frames(range(8)), scales=(1.0,), min_pairs=10, detect=detect_multiscale)
    assert cal.base is None and cal.meta["frames"] == 8 and cal.meta["pairs"] >= 10
    assert abs(float(cal.coef[0, 2]) - np.log(40 / 24)) < 0.1 and abs(float(cal.coef[0, 3]) - np.log(40 / 24)) < 0.1

    def mean_iou(d):
        ious = []
        for f in frames(range(100, 106)):
            dd = detect_multiscale(d, torch.as_tensor(f.image).float() / 255, scales=(1.0,), max_detections=20)
            p, g = detection_pairs(dd.numpy(), f.boxes)
            ious += box_iou(p, g).diagonal().tolist()
        return float(np.mean(ious))

    before = mean_iou(det)
    det.box_regressor = cal
    after = mean_iou(det)
    assert before < 0.45 and after > 0.75, (before, after)
    back = load_detector(save_detector(det, tmp_path / "d.pt"))
    assert isinstance(back.box_regressor, CalibratedBoxRegressor) and torch.equal(back.box_regressor.coef, cal.coef)
    with pytest.raises(ValueError, match="at least 1000 needed"):
        calibrate_boxes(det, frames(range(2)), scales=(1.0,), min_pairs=1000, detect=detect_multiscale)
