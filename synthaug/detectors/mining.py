"""Hard-negative mining and the validation false-positive count of the mining rounds.

:func:`mine_hard_negatives` scans full frames with the detector's own sliding
window scoring (:func:`~synthaug.detectors.sliding.candidate_boxes` + NMS, the
pyramid of :func:`~synthaug.detectors.sliding.detect_multiscale`), never taking a
window that touches a labelled box grown by a margin, and keeps the top-scoring
windows of every frame as new negatives (:class:`MinedNegatives`).

**Validation false-positive count** (the stopping rule of
:func:`~synthaug.detectors.training.train_with_mining`): detections
(:func:`~synthaug.detectors.sliding.detect_multiscale`, ``val_top_k`` per frame)
on every ``val_stride``-th frame of the validation videos are matched to the
labels (greedy by score, IoU >= ``val_iou``; null-label frames have no object);
the count is the number of false positives scoring at or above the detection at
which recall first reaches ``val_target_recall`` (50 %) — the clutter a user must
accept to find half of the drones. When that recall is never reached every
kept false positive counts (:func:`validation_false_positives`).

The same matched detections, pooled over the validation frames, also give a
**validation AP** (``"ap"``: ``∫ p(r) dr`` of the step precision-recall curve,
recall over all labelled objects, detections of equal score entering together:
the protocol's AP convention of :mod:`synthaug.evaluate.ap`; ``"ap_envelope"``:
the same integral of the monotone precision envelope, VOC's "all points"). It
costs nothing beyond the count and is what ``TrainOptions(mining_select="ap")``
selects the round on. Unlike the count it uses every kept detection, not the one
operating point. It is capped by ``val_top_k`` detections per frame, so it is a
selection score, not the protocol's test AP.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Iterable, Sequence

import numpy as np
import torch
from torch import Tensor

from synthaug.data.boxes import box_iou, xywh_to_xyxy
from synthaug.detectors.frames import _as_item, _image_tensor

__all__ = ["MinedNegatives", "mine_hard_negatives", "validation_false_positives"]


@dataclass
class MinedNegatives:
    """The false positives of one scan (:func:`mine_hard_negatives`).

    Attributes:
        patches: float ``(M, 1, W, W)`` windows exactly as the detector scored them
            (cut from the pyramid level).
        boxes: ``(M, 4)`` XYXY window in frame pixels.
        scores: ``(M,)`` detector scores.
        sources: ``(video, frame index)`` of each.
        keys: ``(video, frame index, level, y, x)`` of each (deduplication across rounds).
        frames_scanned: frames scanned.
        seconds: wall time of the scan.
    """

    patches: Tensor
    boxes: Tensor
    scores: Tensor
    sources: list[tuple[str, int]] = field(default_factory=list)
    keys: list[tuple[str, int, int, int, int]] = field(default_factory=list)
    frames_scanned: int = 0
    seconds: float = 0.0

    def __len__(self) -> int:
        return int(self.patches.shape[0])


def _grown_xyxy(boxes: Any, margin: float, min_margin: float = 4.0) -> Tensor:
    from synthaug.data.backgrounds import grow_boxes

    g = grow_boxes(np.asarray(boxes, np.float64).reshape(-1, 4), margin_fraction=margin, min_margin=min_margin)
    return torch.as_tensor(np.concatenate([g[:, :2], g[:, :2] + g[:, 2:]], 1), dtype=torch.float32)


def _touching(boxes_xyxy: Tensor, grown_xyxy: Tensor) -> Tensor:
    """Bool per box: it intersects (positive area) one of the grown boxes."""
    if grown_xyxy.numel() == 0 or boxes_xyxy.numel() == 0:
        return torch.zeros(boxes_xyxy.shape[0], dtype=torch.bool)
    b, g = boxes_xyxy[:, None, :], grown_xyxy[None, :, :]
    return ((b[..., 0] < g[..., 2]) & (b[..., 2] > g[..., 0]) & (b[..., 1] < g[..., 3]) & (b[..., 3] > g[..., 1])).any(1)


@torch.no_grad()
def mine_hard_negatives(
    detector: Any,
    frames_iter: Iterable[Any],
    ignore_boxes: Sequence[Any] | None = None,
    *,
    scales: Sequence[float] | None = None,
    per_frame: int = 5,
    max_negatives: int = 10000,
    margin: float = 0.25,
    nms_iou: float = 0.3,
    score_threshold: float = float("-inf"),
    pre_nms_top_k: int = 3000,
    exclude: set[tuple[str, int, int, int, int]] | None = None,
) -> MinedNegatives:
    """Scan full frames with the detector and keep the top-scoring windows of each as hard negatives.

    Every frame goes through :func:`~synthaug.detectors.sliding.candidate_boxes`
    (the pyramid and dense scoring of ``detect_multiscale``, with the whole window
    as box); windows touching a labelled box grown by ``max(4 px, margin x longest
    side)`` are dropped; NMS (``nms_iou``) and the ``per_frame`` best remain; over
    all frames the ``max_negatives`` best are kept (memory stays bounded: the pool
    is trimmed as it grows). Each kept window is cut from its pyramid level, so the
    patch is exactly what the detector scored.

    Args:
        detector: any :class:`~synthaug.detectors.base.PatchDetector`.
        frames_iter: :class:`~synthaug.detectors.frames.MiningFrame` items (or ``(image, boxes[, video, index])``
            tuples, or bare images with ``ignore_boxes``); streamed once.
        ignore_boxes: per frame, ``(G, 4)`` XYWH boxes, when the items are bare images.
        scales: pyramid (default ``sliding.DEFAULT_SCALES``).
        per_frame: windows kept per frame.
        max_negatives: windows kept over all frames (the highest-scoring).
        margin: growth of the masked boxes (fraction of their longest side).
        nms_iou: NMS threshold among a frame's windows.
        score_threshold: windows scoring below are never negatives (default: any).
        pre_nms_top_k: windows of a frame entering the masking and NMS (the best).
        exclude: window keys (:attr:`MinedNegatives.keys`) never returned (mined before).

    Returns:
        :class:`MinedNegatives`, best first.
    """
    from synthaug.detectors.base import check_image
    from synthaug.detectors.sliding import DEFAULT_SCALES

    if per_frame < 1 or max_negatives < 1:
        raise ValueError(f"per_frame and max_negatives must be >= 1, got {per_frame}, {max_negatives}")
    scales = [float(s) for s in (DEFAULT_SCALES if scales is None else scales)]
    window = int(detector.window)
    exclude = exclude if exclude is not None else set()
    t0 = time.perf_counter()
    pool = _MinedPool(max_negatives)
    n_frames = 0
    for j, raw in enumerate(frames_iter):
        item = _as_item(raw)
        if ignore_boxes is not None and item.boxes is None:
            item = item._replace(boxes=ignore_boxes[j])
        video = item.video or "_"
        index = item.index if item.index >= 0 else j
        image = check_image(_image_tensor(item.image))
        n_frames += 1
        cand, sc = _unmasked_windows(detector, image, item.boxes, scales=scales, score_threshold=score_threshold,
                                     pre_nms_top_k=pre_nms_top_k, margin=margin)
        if cand.shape[0] == 0:
            continue
        _take_best_windows(pool, detector, image, cand, sc, scales=scales, nms_iou=nms_iou, per_frame=per_frame,
                           source=(video, int(index)), exclude=exclude)
        if len(pool) > 2 * max_negatives:
            pool.trim()
    pool.trim()
    return pool.result(window, n_frames, t0)


class _MinedPool:
    """The windows mined so far (patch, XYXY box, score, source, key), trimmed to the best ``limit``."""

    def __init__(self, limit: int) -> None:
        self.limit = limit
        self.patches: list[Tensor] = []
        self.boxes: list[Tensor] = []
        self.scores: list[Tensor] = []
        self.sources: list[tuple[str, int]] = []
        self.keys: list[tuple[str, int, int, int, int]] = []

    def __len__(self) -> int:
        return len(self.keys)

    def add(self, patch: Tensor, box: Tensor, score: Tensor, source: tuple[str, int],
            key: tuple[str, int, int, int, int]) -> None:
        self.patches.append(patch)
        self.boxes.append(box)
        self.scores.append(score)
        self.sources.append(source)
        self.keys.append(key)

    def trim(self) -> None:
        """Keep the ``limit`` highest-scoring windows (ties: the earlier), as one tensor each."""
        if len(self.keys) <= self.limit:
            return
        s = torch.cat(self.scores)
        order = torch.sort(s, descending=True, stable=True).indices[:self.limit]
        p, b = torch.cat(self.patches)[order], torch.cat(self.boxes)[order]
        idx = order.tolist()
        src, ks = [self.sources[i] for i in idx], [self.keys[i] for i in idx]
        self.patches[:], self.boxes[:], self.scores[:] = [p], [b], [s[order]]
        self.sources[:], self.keys[:] = src, ks

    def result(self, window: int, n_frames: int, t0: float) -> MinedNegatives:
        """The pool best first, as :class:`MinedNegatives` (``t0``: the scan's start)."""
        if self.keys:
            s = torch.cat(self.scores)
            order = torch.sort(s, descending=True, stable=True).indices
            idx = order.tolist()
            return MinedNegatives(torch.cat(self.patches)[order], torch.cat(self.boxes)[order], s[order],
                                  [self.sources[i] for i in idx], [self.keys[i] for i in idx], n_frames,
                                  time.perf_counter() - t0)
        return MinedNegatives(torch.zeros(0, 1, window, window), torch.zeros(0, 4), torch.zeros(0), [], [], n_frames,
                              time.perf_counter() - t0)


def _unmasked_windows(detector: Any, image: Tensor, boxes: Any, *, scales: Sequence[float], score_threshold: float,
                      pre_nms_top_k: int, margin: float) -> tuple[Tensor, Tensor]:
    """A frame's scored windows (XYXY, frame pixels) with a finite score, none touching a grown labelled box."""
    from synthaug.detectors.sliding import candidate_boxes

    window = int(detector.window)
    whole = (0.0, 0.0, float(window), float(window))
    cand, sc = candidate_boxes(detector, image, scales=scales, score_threshold=score_threshold,
                               pre_nms_top_k=pre_nms_top_k, box_in_window=whole)
    finite = torch.isfinite(sc)
    cand, sc = cand[finite], sc[finite]
    if cand.shape[0] and boxes is not None and np.asarray(boxes).size:
        keep = ~_touching(cand, _grown_xyxy(boxes, margin))
        cand, sc = cand[keep], sc[keep]
    return cand, sc


def _take_best_windows(pool: _MinedPool, detector: Any, image: Tensor, cand: Tensor, sc: Tensor, *,
                       scales: Sequence[float], nms_iou: float, per_frame: int, source: tuple[str, int],
                       exclude: set[tuple[str, int, int, int, int]]) -> None:
    """Add the ``per_frame`` best windows of a frame left by NMS (and not in ``exclude``) to ``pool``,
    each cut from its pyramid level as the detector scored it."""
    from synthaug.detectors.sliding import nms, resize_image

    window, stride = int(detector.window), int(detector.stride)
    # the levels as candidate_boxes made them: (resized level, its true x/y scale)
    levels: dict[int, tuple[Tensor, float, float]] = {}
    sides = []
    for s in scales:  # a level's window side in frame pixels (resize_image's rounding of the level width)
        lw = max(1, round(image.shape[-1] * s))
        sides.append(window / (lw / image.shape[-1]))
    side_t = torch.tensor(sides)
    order = nms(cand, sc, nms_iou)
    kept = 0
    for k in order.tolist():
        if kept >= per_frame:
            break
        x0, y0, x1, _ = cand[k].tolist()
        li = int((side_t - (x1 - x0)).abs().argmin())
        if li not in levels:
            lvl = resize_image(image, scales[li])
            levels[li] = (lvl, lvl.shape[-2] / image.shape[-2], lvl.shape[-1] / image.shape[-1])
        lvl, sy, sx = levels[li]
        x, y = int(round(x0 * sx)), int(round(y0 * sy))
        if x % stride or y % stride or y + window > lvl.shape[-2] or x + window > lvl.shape[-1]:
            continue  # not a window of this level (cannot happen with consistent levels)
        key = (source[0], source[1], li, y, x)
        if key in exclude:
            continue
        exclude.add(key)
        pool.add(lvl[0, :, y:y + window, x:x + window].clone()[None], cand[k][None], sc[k:k + 1], source, key)
        kept += 1


@torch.no_grad()
def validation_false_positives(
    detector: Any,
    frames: Iterable[Any],
    *,
    scales: Sequence[float] | None = None,
    top_k: int = 10,
    iou: float = 0.5,
    target_recall: float = 0.5,
    nms_iou: float = 0.3,
) -> dict[str, Any]:
    """The validation false-positive count of the stopping rule (module docstring).

    Args:
        detector: any patch detector (its ``box_in_window`` gives the boxes).
        frames: :class:`~synthaug.detectors.frames.MiningFrame` items; ``boxes`` None = no object in the frame.
        scales: pyramid (default ``sliding.DEFAULT_SCALES``).
        top_k: detections kept per frame.
        iou: a detection is a true positive when its IoU with a not yet matched object is >= this
            (greedy by score within the frame, the VOC rule).
        target_recall: the operating point.
        nms_iou: NMS threshold of the detection.

    Returns:
        ``{"fp": count, "recall_reached": bool, "threshold": score at the operating point
        (None when not reached), "max_recall", "tp", "detections", "frames", "objects", "ap", "ap_envelope"}``;
        ``"ap"`` / ``"ap_envelope"``: the validation AP of the same pooled detections (module docstring; 0.0
        with objects but no detection, None without any labelled object).

    Example:
        >>> # the toy "darkness" scorer finds one of two dark squares above a darker distractor
        >>> import torch.nn.functional as F
        >>> from synthaug.detectors.base import PatchDetector
        >>> from synthaug.detectors.frames import MiningFrame
        >>> class Dark(PatchDetector):
        ...     kind = "dark_doc"
        ...     def score_patches(self, p): return 1 - p.mean((1, 2, 3))
        ...     def score_map(self, im): return 1 - F.avg_pool2d(im, 40, 4)[0, 0]
        ...     def state_dict(self): return {}
        ...     @classmethod
        ...     def from_state_dict(cls, s): return cls()
        >>> f = np.full((120, 160), 200, np.uint8); f[40:80, 40:80] = 50; f[0:40, 100:140] = 0
        >>> r = validation_false_positives(Dark(), [MiningFrame(f, np.array([[40., 40, 40, 40]]))], scales=[1.0], top_k=2)
        >>> r["fp"], r["recall_reached"], r["max_recall"], r["ap"]   # FP then TP: precision 1/2 at recall 1
        (1, True, 1.0, 0.5)
    """
    from synthaug.detectors.sliding import DEFAULT_SCALES, detect_multiscale

    scales = list(DEFAULT_SCALES if scales is None else scales)
    scores: list[float] = []
    tps: list[bool] = []
    n_obj = n_frames = 0
    for raw in frames:
        item = _as_item(raw)
        n_frames += 1
        dets = detect_multiscale(detector, _image_tensor(item.image), scales=scales, nms_iou=nms_iou,
                                 max_detections=top_k).numpy().astype(np.float64)
        gts = None if item.boxes is None else np.asarray(item.boxes, np.float64).reshape(-1, 4)
        g = 0 if gts is None else len(gts)
        n_obj += g
        used = np.zeros(g, bool)
        ious = box_iou(xywh_to_xyxy(dets[:, :4]), xywh_to_xyxy(gts)) if g and len(dets) else np.zeros((len(dets), g))
        for d in range(len(dets)):  # best first
            hit = False
            if g:
                cand = np.where(~used, ious[d], -1.0)
                m = int(cand.argmax())
                if cand[m] >= iou:
                    used[m] = True
                    hit = True
            scores.append(float(dets[d, 4]))
            tps.append(hit)
    order = np.argsort(-np.asarray(scores, np.float64), kind="stable")
    tp_sorted = np.asarray(tps, bool)[order]
    cum_tp = np.cumsum(tp_sorted)
    total_fp = int((~tp_sorted).sum())
    max_recall = float(cum_tp[-1] / n_obj) if n_obj and len(cum_tp) else 0.0
    reached = False
    fp, threshold = total_fp, None
    if n_obj and len(cum_tp):
        hit = np.nonzero(cum_tp >= target_recall * n_obj - 1e-9)[0]
        if hit.size:
            i = int(hit[0])
            reached = True
            fp = int(i + 1 - cum_tp[i])
            threshold = float(np.asarray(scores)[order][i])
    ap, ap_env = _pooled_ap(np.asarray(scores, np.float64)[order], tp_sorted, n_obj)
    return {"fp": fp, "recall_reached": reached, "threshold": threshold, "max_recall": round(max_recall, 4),
            "tp": int(cum_tp[-1]) if len(cum_tp) else 0, "detections": len(scores), "frames": n_frames, "objects": n_obj,
            "ap": ap, "ap_envelope": ap_env}


def _pooled_ap(scores: np.ndarray, is_tp: np.ndarray, n_objects: int) -> tuple[float | None, float | None]:
    """``(AP, envelope AP)`` of detections sorted by decreasing score (recall over ``n_objects``).

    Precision and recall are taken at the last detection of each run of equal scores (ties enter
    together), ``AP = Σ (r_k - r_{k-1}) p_k`` and the envelope variant replaces ``p_k`` by
    ``max_{j >= k} p_j``: :func:`synthaug.evaluate.ap.average_precision`'s two conventions, rewritten
    here because detector modules never import ``synthaug.evaluate``. Both None when there is no object
    (AP undefined; JSON has no NaN), 0.0 when there are objects but no detection.

    Example:
        >>> ap, env = _pooled_ap(np.array([0.9, 0.8, 0.7]), np.array([False, True, True]), 2)
        >>> round(ap, 4), round(env, 4)   # (1/2)(1/2) + (1/2)(2/3); the envelope lifts the first 1/2 to 2/3
        (0.5833, 0.6667)
    """
    if n_objects <= 0:
        return None, None
    if scores.size == 0:
        return 0.0, 0.0
    tp = np.cumsum(is_tp)
    last = np.r_[np.nonzero(np.diff(scores))[0], scores.size - 1]
    precision = tp[last] / (last + 1.0)
    recall = tp[last] / float(n_objects)
    steps = np.diff(np.r_[0.0, recall])
    envelope = np.maximum.accumulate(precision[::-1])[::-1]
    return float(np.sum(steps * precision)), float(np.sum(steps * envelope))
