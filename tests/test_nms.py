"""NMS (torchvision behind a thin wrapper) and box IoU against brute-force numpy references."""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
import pytest
import torch
from torchvision.ops import box_convert, box_iou

from synthaug.detectors.base import PatchDetector
from synthaug.detectors.sliding import candidate_boxes, detect_multiscale, nms


def _iou_numpy(box: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """IoU of one XYXY box with many, in the boxes' dtype (the operation order of torchvision's kernel)."""
    w = np.maximum(np.minimum(box[2], boxes[:, 2]) - np.maximum(box[0], boxes[:, 0]), 0)
    h = np.maximum(np.minimum(box[3], boxes[:, 3]) - np.maximum(box[1], boxes[:, 1]), 0)
    inter = w * h
    area = (boxes[:, 2] - boxes[:, 0]) * (boxes[:, 3] - boxes[:, 1])
    box_area = (box[2] - box[0]) * (box[3] - box[1])
    with np.errstate(invalid="ignore", divide="ignore"):
        return inter / (box_area + area - inter)


def _nms_numpy(boxes: np.ndarray, scores: np.ndarray, threshold: float, groups: np.ndarray | None = None) -> list[int]:
    """Textbook greedy NMS: take the best remaining box (lowest index on ties), drop the others of its
    group overlapping it by more than the threshold (compared in the boxes' dtype)."""
    groups = np.zeros(len(boxes), dtype=np.int64) if groups is None else groups
    thr = boxes.dtype.type(threshold)
    order = np.argsort(-scores, kind="stable")
    alive = np.ones(len(boxes), dtype=bool)
    keep = []
    for i in order:
        if not alive[i]:
            continue
        keep.append(int(i))
        alive[i] = False
        alive &= ~((_iou_numpy(boxes[i], boxes) > thr) & (groups == groups[i]))
    return keep


def _random_boxes(n: int, seed: int, dtype: torch.dtype = torch.float64, offset: float = 0.0) -> tuple[torch.Tensor, torch.Tensor]:
    g = torch.Generator().manual_seed(seed)
    xy = torch.rand(n, 2, generator=g, dtype=torch.float64) * 100 + offset
    wh = 5 + torch.rand(n, 2, generator=g, dtype=torch.float64) * 40
    scores = torch.rand(n, generator=g, dtype=torch.float64)
    return torch.cat([xy, xy + wh], 1).to(dtype), scores.to(dtype)


@pytest.mark.parametrize("dtype", [torch.float64, torch.float32])
@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("threshold", [0.0, 0.1, 0.3, 0.5, 0.7, 0.9, 1.0])
def test_nms_matches_numpy_reference(dtype: torch.dtype, seed: int, threshold: float) -> None:
    boxes, scores = _random_boxes(80, seed, dtype)
    expected = _nms_numpy(boxes.numpy(), scores.numpy(), threshold)
    got = nms(boxes, scores, threshold)
    assert got.dtype == torch.long
    assert got.tolist() == expected


def test_nms_ties_and_quantised_scores() -> None:
    boxes, _ = _random_boxes(300, 99)
    scores = torch.randint(0, 4, (300,), generator=torch.Generator().manual_seed(1)).double()
    for threshold in (0.0, 0.3, 0.8):
        assert nms(boxes, scores, threshold).tolist() == _nms_numpy(boxes.numpy(), scores.numpy(), threshold)


def test_nms_max_keep_is_prefix() -> None:
    boxes, scores = _random_boxes(100, 3)
    full = nms(boxes, scores, 0.3)
    for k in (0, 1, 5, len(full) + 3):
        assert nms(boxes, scores, 0.3, max_keep=k).tolist() == full[:k].tolist()


@pytest.mark.parametrize("grouped", [False, True])
def test_nms_max_keep_on_crowded_boxes(grouped: bool) -> None:
    """Few survivors among many boxes: the best-m prefix must grow (64, 128, ...) to reach max_keep."""
    g = torch.Generator().manual_seed(8)
    xy = torch.cat([torch.rand(1900, 2, generator=g, dtype=torch.float64) * 4, torch.rand(100, 2, generator=g, dtype=torch.float64) * 400])
    boxes = torch.cat([xy, xy + 30], 1)
    scores = torch.cat([torch.rand(1900, generator=g, dtype=torch.float64) + 1, torch.rand(100, generator=g, dtype=torch.float64)])
    groups = torch.randint(0, 2, (2000,), generator=g) if grouped else None
    expected = _nms_numpy(boxes.numpy(), scores.numpy(), 0.3, None if groups is None else groups.numpy())
    assert len(expected) > 20
    for k in (1, 3, 10, 20, len(expected), len(expected) + 1):
        assert nms(boxes, scores, 0.3, max_keep=k, groups=groups).tolist() == expected[:k]


def test_nms_identical_boxes_and_threshold_one() -> None:
    boxes = torch.tensor([[0.0, 0.0, 10.0, 10.0]] * 3)
    scores = torch.tensor([0.1, 0.5, 0.3])
    assert nms(boxes, scores, 0.5).tolist() == [1]
    assert nms(boxes, scores, 1.0).tolist() == [1, 2, 0]  # IoU 1 is not > 1: nothing suppressed


@pytest.mark.parametrize("dtype", [torch.float32, torch.float64])
def test_iou_equal_to_threshold_is_not_suppressed(dtype: torch.dtype) -> None:
    # inter 60, union 200: IoU 0.3 exactly in the boxes' dtype (float32(0.3) > 0.3 in double)
    boxes = torch.tensor([[0.0, 0.0, 13.0, 10.0], [7.0, 0.0, 20.0, 10.0]], dtype=dtype)
    scores = torch.tensor([0.9, 0.8], dtype=dtype)
    assert box_iou(boxes[:1], boxes[1:]).item() == float(torch.tensor(0.3, dtype=dtype))
    assert nms(boxes, scores, 0.3).tolist() == [0, 1]
    assert nms(boxes, scores, 0.29).tolist() == [0]


@pytest.mark.parametrize("n", [60, 1500])  # 1500 boxes: torchvision's per-group path (> 4000 numbers on CPU)
@pytest.mark.parametrize("threshold", [0.0, 0.3, 0.6])
def test_batched_nms_matches_numpy_reference(n: int, threshold: float) -> None:
    boxes, scores = _random_boxes(n, 7, offset=-50.0)  # negative coordinates: translated before batched_nms
    groups = torch.randint(0, 4, (n,), generator=torch.Generator().manual_seed(2))
    expected = _nms_numpy(boxes.numpy(), scores.numpy(), threshold, groups.numpy())
    got = nms(boxes, scores, threshold, groups=groups)
    assert got.tolist() == expected
    # = NMS per group, merged by decreasing score
    per_group = torch.cat([torch.nonzero(groups == c)[:, 0][nms(boxes[groups == c], scores[groups == c], threshold)] for c in range(4)])
    assert sorted(got.tolist()) == sorted(per_group.tolist())
    assert torch.all(scores[got][:-1] >= scores[got][1:])
    assert nms(boxes, scores, threshold, max_keep=7, groups=groups).tolist() == expected[:7]


def test_batched_nms_groups_do_not_suppress_each_other_and_ties() -> None:
    boxes = torch.tensor([[0.0, 0.0, 10.0, 10.0]] * 4 + [[1.0, 1.0, 11.0, 11.0]] * 2)
    scores = torch.tensor([0.5, 0.5, 0.5, 0.9, 0.5, 0.5])
    groups = torch.tensor([0, 1, 0, 2, 1, 2])
    # group 0: 0 beats 2 (tie, lower index); group 1: 1 beats 4; group 2: 3 beats 5
    assert nms(boxes, scores, 0.5, groups=groups).tolist() == [3, 0, 1]
    assert nms(boxes, scores, 0.5).tolist() == [3]  # one group: the best suppresses all
    # groups with many tied scores: order by decreasing score, then index
    many, _ = _random_boxes(1200, 11)
    tied = torch.randint(0, 3, (1200,), generator=torch.Generator().manual_seed(4)).double()
    g = torch.randint(0, 5, (1200,), generator=torch.Generator().manual_seed(5))
    assert nms(many, tied, 0.4, groups=g).tolist() == _nms_numpy(many.numpy(), tied.numpy(), 0.4, g.numpy())


def test_nms_empty_and_bad_input() -> None:
    assert nms(torch.zeros(0, 4), torch.zeros(0), 0.5).tolist() == []
    assert nms(torch.zeros(0, 4), torch.zeros(0), 0.5, groups=torch.zeros(0, dtype=torch.long)).tolist() == []
    with pytest.raises(ValueError, match=r"boxes_xyxy must be \(K, 4\)"):
        nms(torch.zeros(3, 5), torch.zeros(3), 0.5)
    with pytest.raises(ValueError, match="scores must be"):
        nms(torch.zeros(3, 4), torch.zeros(2), 0.5)
    with pytest.raises(ValueError, match="groups must be"):
        nms(torch.zeros(3, 4), torch.zeros(3), 0.5, groups=torch.zeros(2, dtype=torch.long))
    with pytest.raises(ValueError, match="iou_threshold must be in"):
        nms(torch.zeros(3, 4), torch.zeros(3), 1.5)
    with pytest.raises(ValueError, match="max_keep must be"):
        nms(torch.zeros(3, 4), torch.zeros(3), 0.5, max_keep=-1)


def test_box_iou_convention_is_continuous_xyxy() -> None:
    """torchvision's box_iou (no +1 pixel) against a brute-force reference, and XYWH <-> XYXY."""
    a, _ = _random_boxes(15, 5)
    b, _ = _random_boxes(12, 6)
    ours = box_iou(a, b)
    for i in range(15):
        np.testing.assert_allclose(ours[i].numpy(), _iou_numpy(a[i].numpy(), b.numpy()), rtol=0, atol=1e-12)
    assert box_iou(torch.tensor([[0.0, 0.0, 2.0, 2.0]]), torch.tensor([[1.0, 0.0, 3.0, 2.0]])).item() == pytest.approx(1 / 3)
    xywh = torch.tensor([[1.0, 2.0, 3.0, 4.0]])
    assert box_convert(xywh, "xywh", "xyxy").tolist() == [[1.0, 2.0, 4.0, 6.0]]
    torch.testing.assert_close(box_convert(box_convert(a, "xyxy", "xywh"), "xywh", "xyxy"), a, rtol=0, atol=1e-12)


class _MeanDetector(PatchDetector):
    """Scores a window by the mean of its centre: cheap, deterministic, many near-ties across levels."""

    kind = "test-mean"
    window = 16
    stride = 4

    def score_patches(self, patches: torch.Tensor) -> torch.Tensor:
        return patches[:, 0, 4:12, 4:12].mean(dim=(1, 2))

    def state_dict(self) -> dict[str, Any]:
        return {}

    @classmethod
    def from_state_dict(cls, state: dict[str, Any]) -> "_MeanDetector":
        return cls()


def test_detect_multiscale_is_candidates_then_reference_nms() -> None:
    det = _MeanDetector()
    image = torch.rand(90, 120, generator=torch.Generator().manual_seed(0))
    scales = (1.25, 1.0, 0.8)
    boxes, scores = candidate_boxes(det, image, scales=scales, pre_nms_top_k=400)
    assert boxes.dtype == torch.float32 and boxes.shape == (400, 4) and scores.shape == (400,)
    for nms_iou, max_det in itertools.product((0.0, 0.3, 0.6), (5, 100)):
        out = detect_multiscale(det, image, scales=scales, nms_iou=nms_iou, max_detections=max_det, pre_nms_top_k=400)
        keep = _nms_numpy(boxes.numpy(), scores.numpy(), nms_iou)[:max_det]
        assert out.shape == (len(keep), 5)
        torch.testing.assert_close(out[:, :4], box_convert(boxes[keep], "xyxy", "xywh"), rtol=0, atol=0)
        torch.testing.assert_close(out[:, 4], scores[keep], rtol=0, atol=0)
    assert detect_multiscale(det, image, scales=scales, max_detections=0).shape == (0, 5)
    assert detect_multiscale(det, torch.rand(10, 10), scales=scales).shape == (0, 5)
