"""Box regression in the annotators' convention (synthaug.detectors.boxes): deltas against torchvision's
BoxCoder, ridge against numpy least squares, and the behaviour it exists for — on frames where the
annotators' box is known, jittered detector boxes come closer to it."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from torchvision.models.detection._utils import BoxCoder
from torchvision.ops import box_convert, box_iou

from synthaug.detectors.base import load_detector, save_detector
from synthaug.detectors.boxes import BoxRegressor, _ridge, decode_deltas, encode_deltas, jitter_boxes
from synthaug.detectors.sliding import nms
from synthaug.detectors.frames import MiningFrame
from synthaug.evaluate.videos import EvalSet, detect_on_eval_set, refine_detections


def test_deltas_match_torchvision_boxcoder_and_round_trip():
    g = torch.Generator().manual_seed(0)
    xy = torch.rand(50, 2, generator=g) * 100
    p = torch.cat([xy, xy + 5 + torch.rand(50, 2, generator=g) * 40], 1)
    xy2 = torch.rand(50, 2, generator=g) * 100
    t = torch.cat([xy2, xy2 + 5 + torch.rand(50, 2, generator=g) * 40], 1)
    ref = BoxCoder(weights=(1.0, 1.0, 1.0, 1.0)).encode_single(t, p)
    torch.testing.assert_close(encode_deltas(p, t), ref, rtol=1e-5, atol=1e-5)
    size = p[:, 2:] - p[:, :2]
    start = p[:, :2] + 0.3 * size  # within the decode clamp (shift <= 1 box, size factor <= 4)
    small = torch.cat([start, start + 1.3 * size], 1)
    torch.testing.assert_close(decode_deltas(p, encode_deltas(p, small)), small, rtol=1e-4, atol=1e-3)
    torch.testing.assert_close(decode_deltas(p, encode_deltas(p, small)),
                               BoxCoder(weights=(1.0, 1.0, 1.0, 1.0)).decode_single(encode_deltas(p, small), p), rtol=1e-4, atol=1e-3)


def test_ridge_equals_numpy_least_squares_on_the_augmented_system():
    rng = np.random.default_rng(1)
    x, y, lam = rng.normal(size=(40, 6)), rng.normal(size=(40, 4)), 3.0
    ref = np.linalg.lstsq(np.vstack([x, np.sqrt(lam) * np.eye(6)]), np.vstack([y, np.zeros((6, 4))]), rcond=None)[0]
    np.testing.assert_allclose(_ridge(torch.as_tensor(x), torch.as_tensor(y), lam).numpy(), ref, atol=1e-10)


def test_jitter_is_reproducible_overlapping_and_of_the_requested_aspect():
    boxes = torch.tensor([[10.0, 20.0, 40.0, 40.0], [100.0, 50.0, 160.0, 110.0]])
    a, ia = jitter_boxes(boxes, 30, aspect=1.5, generator=torch.Generator().manual_seed(3))
    b, ib = jitter_boxes(boxes, 30, aspect=1.5, generator=torch.Generator().manual_seed(3))
    assert torch.equal(a, b) and torch.equal(ia, ib) and 0 < a.shape[0] <= 60
    torch.testing.assert_close((a[:, 2] - a[:, 0]) / (a[:, 3] - a[:, 1]), torch.full((a.shape[0],), 1.5))
    iou = box_iou(a, boxes)[torch.arange(a.shape[0]), ia]
    assert bool((iou >= 0.2).all())


def _frames(n: int, seed: int) -> list[MiningFrame]:
    """Dark rectangles of random size and aspect on a bright textured sky: the annotators' box is the rectangle."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        img = np.clip(170 + 25 * rng.standard_normal((120, 160)).cumsum(1) / 30, 0, 255)
        w, h = rng.uniform(14, 40), rng.uniform(10, 28)
        x, y = rng.uniform(20, 160 - w - 20), rng.uniform(20, 120 - h - 20)
        img[int(round(y)):int(round(y + h)), int(round(x)):int(round(x + w))] = 40
        box = np.array([[round(x), round(y), round(x + w) - round(x), round(y + h) - round(y)]], float)
        out.append(MiningFrame(img.astype(np.uint8), box, f"V_{i % 6}", i))
    return out


def test_regressor_moves_jittered_boxes_towards_the_labelled_box():
    reg = BoxRegressor.fit(_frames(60, 0), aspect=1.3, jitters=12, seed=0)
    assert reg.meta["samples"] > 400 and reg.meta["videos"] == 6
    assert reg.ridge in (100.0, 300.0, 1000.0, 3000.0, 10000.0)
    before, after = [], []
    gen = torch.Generator().manual_seed(7)
    for f in _frames(20, 1):  # held-out frames
        g = box_convert(torch.as_tensor(f.boxes, dtype=torch.float32), "xywh", "xyxy")
        p, _ = jitter_boxes(g, 10, aspect=1.3, generator=gen)
        image = torch.as_tensor(f.image).float() / 255
        before.append(box_iou(p, g)[:, 0])
        after.append(box_iou(reg.refine(image, p), g)[:, 0])
    before, after = torch.cat(before), torch.cat(after)
    assert float(after.mean()) > float(before.mean()) + 0.1, (float(before.mean()), float(after.mean()))
    assert float((after >= 0.5).float().mean()) > float((before >= 0.5).float().mean())


def test_identity_and_state_round_trip_through_the_detector_file(tmp_path):
    from synthaug.detectors.sliding import detect_multiscale
    from synthaug.detectors.toy import toy_frame, toy_patches
    from synthaug.detectors.training import TrainOptions, train_detector

    pos, neg = toy_patches(40, 80, seed=0)
    det = train_detector("hog", pos, neg, seed=0, options=TrainOptions(hog_components=1, hog_mining_rounds=0))
    det.box_regressor = BoxRegressor.fit(_frames(30, 2), aspect=1.0, jitters=6, seed=0)
    path = save_detector(det, tmp_path / "d.pt")
    back = load_detector(path)
    for a, b in zip(det.box_regressor.state_dict().values(), back.box_regressor.state_dict().values()):
        assert (torch.equal(a, b) if isinstance(a, torch.Tensor) else a == b)
    image = toy_frame(seed=0)[0]
    raw = detect_multiscale(back, image, scales=(1.0,), refine_boxes=False)
    ref = detect_multiscale(back, image, scales=(1.0,))
    # the kept boxes refined, then a second NMS at the same threshold over the refined boxes
    moved = back.box_regressor.refine(image, box_convert(raw[:, :4], "xywh", "xyxy"))
    keep = nms(moved, raw[:, 4], 0.3)
    torch.testing.assert_close(ref[:, :4], box_convert(moved[keep], "xyxy", "xywh"))
    assert torch.equal(ref[:, 4], raw[keep, 4])
    # the evaluation path gives the same without scanning twice
    es = EvalSet(["V_T_001"], [(image[0, 0] * 255).round().to(torch.uint8).numpy()[None]], [[0]], [[None]], 1)
    image_u8 = torch.as_tensor(es.frames[0][0]).float() / 255
    a = detect_on_eval_set(back, es, scales=(1.0,), max_detections=10)
    b = refine_detections(back, es, detect_on_eval_set(back, es, scales=(1.0,), max_detections=10, refine_boxes=False))
    np.testing.assert_allclose(a[0][0], b[0][0], atol=1e-4)
    assert a[0][0].shape[0] <= detect_multiscale(back, image_u8, scales=(1.0,), refine_boxes=False, max_detections=10).shape[0]
    det.box_regressor = BoxRegressor.identity()
    torch.testing.assert_close(detect_multiscale(det, image, scales=(1.0,))[:, :4], raw[:, :4])


def test_refine_and_suppress_keeps_the_best_of_boxes_that_now_coincide():
    from synthaug.detectors.sliding import refine_and_suppress

    boxes = torch.tensor([[10.0, 10.0, 30.0, 30.0], [10.0, 10.0, 30.0, 30.0], [60.0, 60.0, 80.0, 80.0], [11.0, 10.0, 31.0, 30.0]])
    scores = torch.tensor([0.9, 0.8, 0.7, 0.6])
    b, s = refine_and_suppress(BoxRegressor.identity(), torch.rand(1, 1, 100, 100), boxes, scores, 0.3)
    assert s.tolist() == pytest.approx([0.9, 0.7]) and torch.equal(b, boxes[[0, 2]])


def test_malformed_state_is_a_clear_error():
    state = BoxRegressor.identity().state_dict()
    with pytest.raises(ValueError, match="shapes"):
        BoxRegressor.from_state_dict({**state, "weights": torch.zeros(3, 4)})
    with pytest.raises(ValueError, match="missing"):
        BoxRegressor.from_state_dict({k: v for k, v in state.items() if k != "mean_y"})
    with pytest.raises(ValueError, match="no labelled box"):
        BoxRegressor.fit([MiningFrame(np.zeros((50, 50), np.uint8), None, "v", 0)], aspect=1.0)


def test_data_boxes_is_torchvision_in_float64_and_empty_pairs_do_not_match() -> None:
    """synthaug.data.boxes: the one home of box conversion and IoU (XYXY inside, XYWH at file edges)."""
    import numpy as np
    from torchvision.ops import box_iou as tv_box_iou

    from synthaug.data.boxes import box_iou, xywh_to_xyxy, xyxy_to_xywh

    xywh = np.array([[1.5, 2.0, 3.0, 4.0], [0.0, 0.0, 0.0, 0.0]])
    xyxy = xywh_to_xyxy(xywh)
    assert xyxy.dtype == np.float64 and xyxy.tolist() == [[1.5, 2.0, 4.5, 6.0], [0.0, 0.0, 0.0, 0.0]]
    assert np.array_equal(xyxy_to_xywh(xyxy), xywh)
    iou = box_iou(xyxy, xyxy)
    assert np.allclose(iou[0], tv_box_iou(torch.as_tensor(xyxy), torch.as_tensor(xyxy)).numpy()[0])
    assert iou[1, 1] == 0.0  # torchvision's 0/0 (NaN) is no match
    assert box_iou(np.zeros((0, 4)), xyxy).shape == (0, 2)
