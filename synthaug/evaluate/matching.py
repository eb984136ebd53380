"""The frame protocol: one video's detections matched to its labelled objects at every protocol IoU.

Per test video, :func:`match_video` matches the per-frame detections (``[x, y, w, h, score]``,
the format of :func:`synthaug.detectors.sliding.detect_multiscale` and the detection files)
to the per-frame labelled boxes with the VOC rule of :mod:`synthaug.evaluate.ap`
(:func:`~synthaug.evaluate.ap.rank_detections`, the ranking :func:`~synthaug.evaluate.ap.match_detections`
labels) at every protocol IoU and keeps a :class:`VideoMatches`: the sorted
scores, their TP flags, each detection's longest side, the longest side of the
object each TP matched, and the longest side of every labelled object. From
these, :mod:`synthaug.evaluate.stats` pools any multiset of videos into one AP
(``∫ p(r) dr``, :mod:`synthaug.evaluate.ap`), so the bootstrap over videos and
paired differences need no detection. Boxes are XYXY inside (torchvision's
``box_convert`` / ``box_iou``); XYWH only at the edges (inputs, label files).

**Size buckets** (COCO semantics, by the longest side of the *labelled* box):
in bucket ``[lo, hi)`` objects outside it are *ignored* — a detection matched
to one is neither TP nor FP — and an unmatched detection counts as FP only if
its own longest side is in the bucket (else it is ignored). The matching is the
one of the all-sizes AP (the TP/FP labels of :func:`match_detections`, the matched
object = the one it overlaps most), then relabelled; it equals COCOeval with
``areaRng`` = the squared edges on square boxes whenever no detection reaches
the IoU threshold with two objects (always true with one object per frame, the
shared label format), which the tests check.

Example:
    >>> dets = [np.array([[10, 10, 20, 20, 0.9], [100, 100, 30, 30, 0.8]]), np.zeros((0, 5))]
    >>> gts = [np.array([[10, 10, 20, 20]]), np.array([[50, 50, 60, 60]])]
    >>> vm = match_video(dets, gts, iou_thresholds=(0.5, 0.3), stem="V_1")
    >>> vm.tp[0].tolist(), vm.gt_size.tolist(), vm.n_objects
    ([True, False], [20.0, 60.0], 2)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np

from synthaug.evaluate.ap import rank_detections
from synthaug.evaluate.protocol import Protocol, SizeBucket

__all__ = ["VideoMatches", "match_video", "match_videos"]


def _longest_side(xyxy: np.ndarray) -> np.ndarray:
    b = np.asarray(xyxy, dtype=np.float64).reshape(-1, 4)
    return np.maximum(b[:, 2] - b[:, 0], b[:, 3] - b[:, 1])


def _iou_index(thresholds: Sequence[float], iou: float) -> int:
    for k, t in enumerate(thresholds):
        if math.isclose(t, iou, rel_tol=0, abs_tol=1e-9):
            return k
    raise ValueError(f"IoU {iou} was not matched; available: {list(thresholds)}")


@dataclass
class VideoMatches:
    """One video's detections matched to its objects at every protocol IoU.

    Attributes:
        stem: the video.
        n_frames: frames scored (processed; the objects of the others do not count).
        iou_thresholds: the matching IoUs, ``(K,)``.
        scores: ``(D,)`` detection scores, decreasing (:func:`synthaug.evaluate.ap.match_detections`'s order).
        tp: ``(K, D)`` bool, true positive at each IoU.
        det_size: ``(D,)`` longest side of each detection's box (pixels).
        match_size: ``(K, D)`` longest side of the labelled box each TP matched (NaN for a false positive).
        gt_size: ``(G,)`` longest side of every labelled object of the scored frames.
    """

    stem: str
    n_frames: int
    iou_thresholds: tuple[float, ...]
    scores: np.ndarray
    tp: np.ndarray
    det_size: np.ndarray
    match_size: np.ndarray
    gt_size: np.ndarray

    @property
    def n_objects(self) -> int:
        return int(self.gt_size.size)

    @property
    def n_detections(self) -> int:
        return int(self.scores.size)

    def ranking(self, iou: float | None = None, bucket: SizeBucket | Sequence[float | None] | None = None
                ) -> tuple[np.ndarray, np.ndarray, int]:
        """``(scores, is_tp, n_objects)`` at ``iou`` (default: the first), restricted to a size bucket.

        With a bucket (COCO semantics): a TP counts only if its object is in the bucket (else the
        detection is ignored); an FP counts only if its own longest side is in the bucket (else
        ignored); ``n_objects`` counts the objects in the bucket.
        """
        k = 0 if iou is None else _iou_index(self.iou_thresholds, iou)
        tp = self.tp[k]
        if bucket is None:
            return self.scores, tp, self.n_objects
        b = bucket if isinstance(bucket, SizeBucket) else SizeBucket(float(bucket[0]), None if bucket[1] is None else float(bucket[1]))
        keep = np.where(tp, b.contains(self.match_size[k]), b.contains(self.det_size))
        return self.scores[keep], tp[keep], int(b.contains(self.gt_size).sum())

    def to_json(self) -> dict[str, Any]:
        return {
            "stem": self.stem, "n_frames": self.n_frames, "iou_thresholds": list(self.iou_thresholds),
            "scores": self.scores.tolist(), "tp": self.tp.astype(int).tolist(), "det_size": self.det_size.tolist(),
            "match_size": [[None if math.isnan(v) else v for v in row] for row in self.match_size.tolist()],
            "gt_size": self.gt_size.tolist(),
        }

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "VideoMatches":
        k = len(d["iou_thresholds"])
        n = len(d["scores"])
        vm = cls(
            stem=str(d["stem"]), n_frames=int(d["n_frames"]), iou_thresholds=tuple(float(t) for t in d["iou_thresholds"]),
            scores=np.asarray(d["scores"], dtype=np.float64).reshape(n),
            tp=np.asarray(d["tp"], dtype=bool).reshape(k, n),
            det_size=np.asarray(d["det_size"], dtype=np.float64).reshape(n),
            match_size=np.array([[np.nan if v is None else v for v in row] for row in d["match_size"]], dtype=np.float64).reshape(k, n),
            gt_size=np.asarray(d["gt_size"], dtype=np.float64).reshape(-1),
        )
        return vm


def match_video(
    detections: Sequence[np.ndarray | None],
    ground_truth: Sequence[np.ndarray | None],
    *,
    iou_thresholds: Sequence[float] = (0.5, 0.3),
    stem: str = "",
) -> VideoMatches:
    """Match one video's per-frame detections to its labelled boxes at every IoU.

    Args:
        detections: per frame ``(K, 5)`` ``[x, y, w, h, score]`` or None (frame not processed:
            it and its objects are left out), as :func:`synthaug.evaluate.ap.match_detections`.
        ground_truth: per frame ``(G, 4)`` ``[x, y, w, h]`` or None (no object).
        iou_thresholds: the protocol's IoUs.
        stem: the video's name.

    Returns:
        The :class:`VideoMatches`. TP/FP labels are :func:`match_detections`' (VOC rule); the
        object a TP matched is the one it overlaps most (the rule's candidate).
    """
    ranked = rank_detections(detections, ground_truth)
    if not np.all(np.isfinite(ranked.scores)):
        raise ValueError(f"video {stem!r}: detection scores must be finite")
    ious = tuple(float(t) for t in iou_thresholds)
    tp = np.array([ranked.true_positives(t) for t in ious], dtype=bool).reshape(len(ious), ranked.scores.size)
    gt_size = _longest_side(ranked.objects)
    candidate_size = np.full(ranked.scores.size, np.nan)  # the object a TP matched is its candidate
    has = ranked.candidate >= 0
    candidate_size[has] = gt_size[ranked.candidate[has]]
    return VideoMatches(stem=stem, n_frames=ranked.n_frames, iou_thresholds=ious, scores=ranked.scores, tp=tp,
                        det_size=_longest_side(ranked.boxes), match_size=np.where(tp, candidate_size, np.nan),
                        gt_size=gt_size)


def match_videos(
    stems: Sequence[str],
    detections: Sequence[Sequence[np.ndarray | None]],
    ground_truth: Sequence[Sequence[np.ndarray | None]],
    protocol: Protocol,
) -> list[VideoMatches]:
    """:func:`match_video` for every video (e.g. an ``EvalSet``'s ``stems`` and ``boxes``) at the protocol's IoUs."""
    if not (len(stems) == len(detections) == len(ground_truth)):
        raise ValueError(f"{len(stems)} stems, {len(detections)} detection lists, {len(ground_truth)} ground-truth lists")
    return [match_video(d, g, iou_thresholds=protocol.iou_thresholds, stem=s) for s, d, g in zip(stems, detections, ground_truth)]
