"""NMS and box IoU against brute-force Python references."""

from __future__ import annotations

import itertools

import pytest
import torch

from synthaug.detectors.sliding import box_iou, nms


def _iou_python(a: list[float], b: list[float]) -> float:
    ix = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
    iy = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
    inter = ix * iy
    union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter
    return inter / union if union > 0 else 0.0


def _nms_python(boxes: list[list[float]], scores: list[float], threshold: float) -> list[int]:
    """Textbook greedy NMS: pick the best remaining, drop everything overlapping it more than the threshold."""
    remaining = sorted(range(len(boxes)), key=lambda i: (-scores[i], i))
    keep = []
    while remaining:
        best = remaining.pop(0)
        keep.append(best)
        remaining = [i for i in remaining if _iou_python(boxes[best], boxes[i]) <= threshold]
    return keep


def _random_boxes(n: int, seed: int) -> tuple[torch.Tensor, torch.Tensor]:
    g = torch.Generator().manual_seed(seed)
    xy = torch.rand(n, 2, generator=g) * 100
    wh = 5 + torch.rand(n, 2, generator=g) * 40
    scores = torch.rand(n, generator=g)
    return torch.cat([xy, xy + wh], 1).double(), scores.double()


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("threshold", [0.0, 0.3, 0.5, 0.9])
def test_nms_matches_bruteforce(seed: int, threshold: float) -> None:
    boxes, scores = _random_boxes(60, seed)
    expected = _nms_python(boxes.tolist(), scores.tolist(), threshold)
    assert nms(boxes, scores, threshold).tolist() == expected


def test_nms_ties_and_quantised_scores() -> None:
    boxes, _ = _random_boxes(80, 99)
    scores = torch.randint(0, 4, (80,), generator=torch.Generator().manual_seed(1)).double()
    assert nms(boxes, scores, 0.3).tolist() == _nms_python(boxes.tolist(), scores.tolist(), 0.3)


def test_nms_max_keep_is_prefix() -> None:
    boxes, scores = _random_boxes(100, 3)
    full = nms(boxes, scores, 0.3)
    for k in (0, 1, 5, len(full) + 3):
        assert nms(boxes, scores, 0.3, max_keep=k).tolist() == full[:k].tolist()


def test_nms_identical_boxes_and_threshold_one() -> None:
    boxes = torch.tensor([[0.0, 0.0, 10.0, 10.0]] * 3)
    scores = torch.tensor([0.1, 0.5, 0.3])
    assert nms(boxes, scores, 0.5).tolist() == [1]
    assert nms(boxes, scores, 1.0).tolist() == [1, 2, 0]  # IoU 1 is not > 1: nothing suppressed


def test_nms_empty_and_bad_input() -> None:
    assert nms(torch.zeros(0, 4), torch.zeros(0), 0.5).tolist() == []
    with pytest.raises(ValueError, match=r"boxes_xyxy must be \(K, 4\)"):
        nms(torch.zeros(3, 5), torch.zeros(3), 0.5)
    with pytest.raises(ValueError, match="scores must be"):
        nms(torch.zeros(3, 4), torch.zeros(2), 0.5)
    with pytest.raises(ValueError, match="iou_threshold must be in"):
        nms(torch.zeros(3, 4), torch.zeros(3), 1.5)


def test_box_iou_matches_bruteforce() -> None:
    a, _ = _random_boxes(15, 5)
    b, _ = _random_boxes(12, 6)
    ours = box_iou(a, b)
    for i, j in itertools.product(range(15), range(12)):
        assert ours[i, j].item() == pytest.approx(_iou_python(a[i].tolist(), b[j].tolist()), abs=1e-12)
