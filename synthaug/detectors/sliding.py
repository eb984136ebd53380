"""Multi-scale sliding-window detection and non-maximum suppression.

Any :class:`~synthaug.detectors.base.PatchDetector` detects objects in a full
frame: the frame is resized by each factor of an image pyramid, the detector's
dense :meth:`~synthaug.detectors.base.PatchDetector.score_map` is computed per
level, windows above a threshold become boxes in input-image pixels, and greedy
non-maximum suppression keeps the best of overlapping boxes.

A scale factor ``s`` resizes the image by ``s``, so a window of ``window`` pixels
covers ``window / s`` input pixels: ``s > 1`` finds objects *smaller* than the
window, ``s < 1`` larger ones. The detector's ``box_in_window`` (the object's
box inside a training patch, default the whole window) maps a window to the
reported box.

Example:
    >>> import torch
    >>> boxes = torch.tensor([[0., 0., 10., 10.], [1., 1., 11., 11.], [20., 20., 30., 30.]])
    >>> nms(boxes, torch.tensor([0.9, 0.8, 0.7]), iou_threshold=0.5).tolist()
    [0, 2]
"""

from __future__ import annotations

import math
from typing import Sequence

import torch
import torch.nn.functional as F
from torch import Tensor

from synthaug.detectors.base import PatchDetector, check_image

DEFAULT_SCALES: tuple[float, ...] = (1.25, 1.0, 0.8, 0.64, 0.51, 0.41)
"""Pyramid factors (ratio 1.25). With seed patches whose object spans 0.7 of the
40-px window (28 px), they find objects of about 22 to 68 px — the drones of the
halmstad videos (23–55 px); add 0.33 and 0.26 for airplanes (up to ~115 px)."""


def geometric_scales(largest: float = 1.25, smallest: float = 0.41, count: int = 6) -> tuple[float, ...]:
    """``count`` scale factors spaced geometrically from ``largest`` down to ``smallest``.

    Example:
        >>> [round(s, 3) for s in geometric_scales(2.0, 0.5, 3)]
        [2.0, 1.0, 0.5]
    """
    if count < 1:
        raise ValueError(f"count must be >= 1, got {count}")
    if not (0 < smallest <= largest and math.isfinite(largest)):
        raise ValueError(f"need 0 < smallest <= largest, got smallest={smallest}, largest={largest}")
    if count == 1:
        return (float(largest),)
    ratio = (smallest / largest) ** (1.0 / (count - 1))
    return tuple(float(largest * ratio**i) for i in range(count))


def xywh_to_xyxy(boxes: Tensor) -> Tensor:
    """``[x, y, w, h]`` -> ``[x1, y1, x2, y2]``, shape ``(K, 4)``."""
    return torch.cat([boxes[:, :2], boxes[:, :2] + boxes[:, 2:4]], dim=1)


def box_iou(a: Tensor, b: Tensor) -> Tensor:
    """Pairwise intersection-over-union of ``[x1, y1, x2, y2]`` boxes (continuous coordinates).

    Shape:
        - a: (K, 4), b: (M, 4)
        - output: (K, M)

    Example:
        >>> box_iou(torch.tensor([[0., 0., 2., 2.]]), torch.tensor([[1., 0., 3., 2.]]))
        tensor([[0.3333]])
    """
    area_a = (a[:, 2] - a[:, 0]).clamp_min(0) * (a[:, 3] - a[:, 1]).clamp_min(0)
    area_b = (b[:, 2] - b[:, 0]).clamp_min(0) * (b[:, 3] - b[:, 1]).clamp_min(0)
    top_left = torch.maximum(a[:, None, :2], b[None, :, :2])
    bottom_right = torch.minimum(a[:, None, 2:], b[None, :, 2:])
    wh = (bottom_right - top_left).clamp_min(0)
    inter = wh[..., 0] * wh[..., 1]
    union = area_a[:, None] + area_b[None, :] - inter
    return torch.where(union > 0, inter / union.clamp_min(1e-12), torch.zeros_like(inter))


def nms(boxes_xyxy: Tensor, scores: Tensor, iou_threshold: float, max_keep: int | None = None) -> Tensor:
    """Greedy non-maximum suppression.

    Repeatedly keeps the highest-scoring remaining box and drops every remaining
    box whose IoU with it is *greater than* ``iou_threshold``. Ties in score are
    broken by the lower index (stable sort).

    Args:
        boxes_xyxy: boxes ``[x1, y1, x2, y2]``.
        scores: one score per box.
        iou_threshold: overlap above which the weaker box is suppressed, in [0, 1].
        max_keep: stop after this many kept boxes (the result is then the
            first ``max_keep`` of the full answer); None = no limit.

    Returns:
        Indices of the kept boxes, by decreasing score (int64).

    Shape:
        - boxes_xyxy: (K, 4), scores: (K,)
        - output: (K',)
    """
    if boxes_xyxy.dim() != 2 or boxes_xyxy.shape[1] != 4:
        raise ValueError(f"boxes_xyxy must be (K, 4), got shape {tuple(boxes_xyxy.shape)}")
    if scores.shape != boxes_xyxy.shape[:1]:
        raise ValueError(f"scores must be ({boxes_xyxy.shape[0]},), got shape {tuple(scores.shape)}")
    if not 0.0 <= float(iou_threshold) <= 1.0:
        raise ValueError(f"iou_threshold must be in [0, 1], got {iou_threshold}")
    limit = boxes_xyxy.shape[0] if max_keep is None else int(max_keep)
    if limit < 0:
        raise ValueError(f"max_keep must be >= 0, got {max_keep}")
    if boxes_xyxy.shape[0] == 0 or limit == 0:
        return torch.zeros(0, dtype=torch.long)
    order = torch.sort(scores, descending=True, stable=True).indices
    boxes = boxes_xyxy[order]
    alive = torch.ones(boxes.shape[0], dtype=torch.bool)
    keep: list[int] = []
    # one IoU row per *kept* box: O(kept x K) instead of the full K x K matrix
    while len(keep) < limit:
        remaining = torch.nonzero(alive)
        if remaining.numel() == 0:
            break
        i = int(remaining[0])
        keep.append(i)
        alive &= box_iou(boxes[i : i + 1], boxes)[0] <= iou_threshold
        alive[i] = False
    return order[torch.tensor(keep, dtype=torch.long)]


def resize_image(image: Tensor, scale: float) -> Tensor:
    """Bilinear resize by ``scale`` (antialiased when shrinking), ``(1, 1, H, W)`` in and out."""
    if scale == 1.0:
        return image
    h, w = image.shape[-2:]
    size = (max(1, round(h * scale)), max(1, round(w * scale)))
    return F.interpolate(image, size=size, mode="bilinear", align_corners=False, antialias=scale < 1.0)


@torch.no_grad()
def detect_multiscale(
    detector: PatchDetector,
    image: Tensor,
    *,
    scales: Sequence[float] = DEFAULT_SCALES,
    nms_iou: float = 0.3,
    score_threshold: float = float("-inf"),
    max_detections: int = 100,
    pre_nms_top_k: int = 3000,
    box_in_window: Sequence[float] | None = None,
) -> Tensor:
    """Detect objects in one grayscale frame with an image pyramid.

    Args:
        detector: any patch detector.
        image: grayscale float image in [0, 1].
        scales: pyramid resize factors (at least one; the paper-like default
            has 7). Levels smaller than the window are skipped.
        nms_iou: IoU above which a weaker overlapping box is suppressed.
        score_threshold: windows scoring below are discarded before NMS (default:
            none — the ``pre_nms_top_k`` best windows compete, which is what an
            AP evaluation wants; use the detector's decision threshold, 0 for the
            SVM and AdaBoost, for a yes/no output).
        max_detections: at most this many boxes are returned (best first).
        pre_nms_top_k: only the best this-many windows over all levels enter NMS
            (bounds NMS's quadratic cost when the threshold is low).
        box_in_window: ``[x, y, w, h]`` of the object inside a window, in window
            pixels; default ``detector.box_in_window`` if set, else the whole window.

    Returns:
        Detections ``[x, y, w, h, score]`` in input-image pixels, by decreasing score.

    Shape:
        - image: (H, W) or (1, 1, H, W)
        - output: (K, 5), K <= max_detections
    """
    image = check_image(image)
    scales = [float(s) for s in scales]
    if not scales or any(not (s > 0 and math.isfinite(s)) for s in scales):
        raise ValueError(f"scales must be a non-empty list of positive numbers, got {scales}")
    if max_detections < 0:
        raise ValueError(f"max_detections must be >= 0, got {max_detections}")
    window, stride = int(detector.window), int(detector.stride)
    if box_in_window is None:
        box_in_window = getattr(detector, "box_in_window", None) or (0.0, 0.0, float(window), float(window))
    bx, by, bw, bh = (float(v) for v in box_in_window)
    if not (bw > 0 and bh > 0):
        raise ValueError(f"box_in_window must have positive width and height, got {list(box_in_window)}")

    all_boxes: list[Tensor] = []
    all_scores: list[Tensor] = []
    for scale in scales:
        level = resize_image(image, scale)
        if level.shape[-2] < window or level.shape[-1] < window:
            continue
        scores = detector.score_map(level)
        # true scale of this level (rounding of the resized size)
        sy = level.shape[-2] / image.shape[-2]
        sx = level.shape[-1] / image.shape[-1]
        ys, xs = torch.nonzero(scores >= score_threshold, as_tuple=True)
        if ys.numel() == 0:
            continue
        values = scores[ys, xs]
        x0 = (xs.float() * stride + bx) / sx
        y0 = (ys.float() * stride + by) / sy
        boxes = torch.stack([x0, y0, x0 + bw / sx, y0 + bh / sy], dim=1)
        all_boxes.append(boxes)
        all_scores.append(values.float())
    if not all_boxes:
        return torch.zeros(0, 5)
    boxes = torch.cat(all_boxes)
    scores = torch.cat(all_scores)
    if scores.numel() > pre_nms_top_k:
        top = torch.topk(scores, pre_nms_top_k).indices
        boxes, scores = boxes[top], scores[top]
    keep = nms(boxes, scores, nms_iou, max_keep=max_detections)
    kept = boxes[keep]
    return torch.cat([kept[:, :2], kept[:, 2:] - kept[:, :2], scores[keep, None]], dim=1)
