"""Average precision AP = ∫₀¹ p(r) dr and precision–recall curves of a detector on frames.

Matching rule (PASCAL VOC's): all detections of all frames are sorted by
decreasing score; each, in turn, is compared with the ground-truth boxes of
its own frame; it is a true positive if the box it overlaps most has
IoU ≥ ``iou_threshold`` (0.5) and has not been claimed by a higher-scoring
detection, otherwise a false positive (a duplicate of a found object is a
false positive). Boxes arrive ``[x, y, w, h]`` (the format of the detection
and label files) and are converted once to ``[x1, y1, x2, y2]``; the IoU is
:func:`torchvision.ops.box_iou`, the one detection's NMS uses. Precision and
recall are evaluated at every distinct score (detections with equal scores
enter together), and

- ``ap`` — the paper's AveP, ``∫ p(r) dr`` of the raw step curve:
  ``Σ_k (r_k - r_{k-1}) p_k`` over distinct scores (scikit-learn's
  ``average_precision_score`` convention);
- ``ap_envelope`` — the same integral of the monotone envelope
  ``p̂(r) = max_{r' ≥ r} p(r')`` (VOC 2010+ "all points"), reported beside it.

Frames: a ``None`` entry in the detections means the frame was not processed
(e.g. skipped by a frame stride): that frame and its objects are left out.
A ``None`` ground truth (object not visible) is a frame with no object: its
detections are all false positives.

Example:
    >>> import numpy as np
    >>> dets = [np.array([[0, 0, 10, 10, 0.9]]), np.array([[50, 50, 10, 10, 0.8]])]
    >>> gts = [np.array([[0, 0, 10, 10]]), np.array([[0, 0, 10, 10]])]
    >>> round(evaluate_detections(dets, gts).ap, 3)   # p = 1 up to r = 0.5, then nothing
    0.5
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import torch

from synthaug.data.boxes import box_iou, xywh_to_xyxy


@dataclass
class PRResult:
    """Precision–recall curve and AP of one evaluation.

    Attributes:
        precision: precision at each distinct score threshold, high to low score.
        recall: recall at the same thresholds.
        thresholds: the distinct scores.
        ap: ``∫ p(r) dr`` of the step curve (NaN when there is no ground truth).
        ap_envelope: the same with the monotone precision envelope.
        n_ground_truth: objects in the evaluated frames.
        n_detections: detections in the evaluated frames.
        n_true_positives: detections matched to an object.
        n_frames: frames evaluated (processed and labelled).
        iou_threshold: the matching IoU.
    """

    precision: np.ndarray
    recall: np.ndarray
    thresholds: np.ndarray
    ap: float
    ap_envelope: float
    n_ground_truth: int
    n_detections: int
    n_true_positives: int
    n_frames: int
    iou_threshold: float
    extra: dict[str, Any] = field(default_factory=dict)

    def metrics(self) -> dict[str, Any]:
        """JSON-ready summary (no curves)."""
        best_f1 = 0.0
        if self.precision.size:
            f1 = 2 * self.precision * self.recall / np.maximum(self.precision + self.recall, 1e-12)
            best_f1 = float(f1.max())
        return {
            "ap": _json_float(self.ap),
            "ap_envelope": _json_float(self.ap_envelope),
            "iou_threshold": self.iou_threshold,
            "n_frames": self.n_frames,
            "n_ground_truth": self.n_ground_truth,
            "n_detections": self.n_detections,
            "n_true_positives": self.n_true_positives,
            "max_recall": float(self.recall.max()) if self.recall.size else 0.0,
            "best_f1": best_f1,
            **self.extra,
        }


def _json_float(x: float) -> float | None:
    return None if math.isnan(x) else float(x)


@dataclass(frozen=True)
class RankedDetections:
    """Every detection of a list of frames by decreasing score, with the object of its frame it overlaps most.

    The one home of the VOC matching rule (module docstring): :meth:`true_positives` labels the
    ranking at an IoU; :func:`match_detections` (the AP) and
    :func:`synthaug.evaluate.matching.match_video` (the protocol's per-video matches) both read it.

    Attributes:
        scores: ``(D,)`` detection scores, decreasing (stable: earlier frame first on ties).
        boxes: ``(D, 4)`` the detections' boxes, XYXY, in that order.
        candidate: ``(D,)`` index into ``objects`` of the object of its frame each detection
            overlaps most (the first on ties), -1 when its frame has no object.
        candidate_iou: ``(D,)`` its IoU with that object (0 when there is none).
        objects: ``(G, 4)`` every labelled box of the counted frames, XYXY, in frame order.
        n_frames: frames counted (processed).
    """

    scores: np.ndarray
    boxes: np.ndarray
    candidate: np.ndarray
    candidate_iou: np.ndarray
    objects: np.ndarray
    n_frames: int

    @property
    def n_ground_truth(self) -> int:
        return int(self.objects.shape[0])

    def true_positives(self, iou_threshold: float = 0.5) -> np.ndarray:
        """``(D,)`` bool: in score order, a detection is a TP if its candidate reaches ``iou_threshold``
        (inclusive) and no higher-scoring detection claimed it."""
        if not 0.0 < iou_threshold <= 1.0:
            raise ValueError(f"iou_threshold must be in (0, 1], got {iou_threshold}")
        claimed = np.zeros(self.n_ground_truth, dtype=bool)
        is_tp = np.zeros(self.scores.size, dtype=bool)
        for i, j in enumerate(self.candidate.tolist()):
            if j >= 0 and self.candidate_iou[i] >= iou_threshold and not claimed[j]:
                claimed[j] = True
                is_tp[i] = True
        return is_tp


def rank_detections(
    detections: Sequence[np.ndarray | None],
    ground_truth: Sequence[np.ndarray | None],
) -> RankedDetections:
    """Rank all detections of all frames by score and find each one's candidate object.

    Args:
        detections: per frame, ``(K, 5)`` ``[x, y, w, h, score]`` or None (not processed: the
            frame and its objects are left out).
        ground_truth: per frame, ``(G, 4)`` ``[x, y, w, h]`` or None (no object).
            Only the first ``min(len(detections), len(ground_truth))`` frames count.

    Returns:
        The :class:`RankedDetections`.
    """
    frames = min(len(detections), len(ground_truth))
    scores, boxes, candidate, candidate_iou, objects = [], [], [], [], []
    n_gt = 0
    n_frames = 0
    for f in range(frames):
        if detections[f] is None:
            continue
        n_frames += 1
        d = np.asarray(detections[f], dtype=np.float64).reshape(-1, 5)
        g = np.zeros((0, 4)) if ground_truth[f] is None else np.asarray(ground_truth[f], dtype=np.float64).reshape(-1, 4)
        d_xyxy, g_xyxy = xywh_to_xyxy(d[:, :4]), xywh_to_xyxy(g)  # XYWH at the file edge, XYXY inside
        if g.shape[0]:
            iou = box_iou(d_xyxy, g_xyxy)  # (K, G)
            j = np.argmax(iou, axis=1)
            candidate.append(n_gt + j)
            candidate_iou.append(iou[np.arange(d.shape[0]), j])
        else:
            candidate.append(np.full(d.shape[0], -1))
            candidate_iou.append(np.zeros(d.shape[0]))
        n_gt += g.shape[0]
        scores.append(d[:, 4])
        boxes.append(d_xyxy)
        objects.append(g_xyxy)
    cat = lambda xs, shape: np.concatenate(xs) if xs else np.zeros(shape)  # noqa: E731
    raw = cat(scores, (0,))
    order = np.array(sorted(range(raw.size), key=lambda i: -raw[i]), dtype=np.intp)  # stable: frame order on ties
    return RankedDetections(
        scores=raw[order], boxes=cat(boxes, (0, 4))[order], candidate=cat(candidate, (0,)).astype(np.intp)[order],
        candidate_iou=cat(candidate_iou, (0,))[order], objects=cat(objects, (0, 4)), n_frames=n_frames,
    )


def match_detections(
    detections: Sequence[np.ndarray | None],
    ground_truth: Sequence[np.ndarray | None],
    iou_threshold: float = 0.5,
) -> tuple[np.ndarray, np.ndarray, int, int]:
    """Label every detection true/false positive with the VOC rule (module docstring).

    Args:
        detections: per frame, ``(K, 5)`` ``[x, y, w, h, score]`` or None (not processed).
        ground_truth: per frame, ``(G, 4)`` ``[x, y, w, h]`` or None (no object).
            Only the first ``min(len(detections), len(ground_truth))`` frames count.
        iou_threshold: minimum IoU of a match (inclusive).

    Returns:
        ``(scores, is_true_positive, n_ground_truth, n_frames)``, the first two
        sorted by decreasing score (stable: earlier frame first on ties).
    """
    if not 0.0 < iou_threshold <= 1.0:
        raise ValueError(f"iou_threshold must be in (0, 1], got {iou_threshold}")
    ranked = rank_detections(detections, ground_truth)
    return ranked.scores, ranked.true_positives(iou_threshold), ranked.n_ground_truth, ranked.n_frames


def precision_recall(scores: np.ndarray, is_tp: np.ndarray, n_ground_truth: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Precision and recall at each distinct score (scores sorted decreasingly).

    Example:
        >>> p, r, t = precision_recall(np.array([0.9, 0.8, 0.8]), np.array([True, False, True]), 4)
        >>> p.tolist(), r.tolist(), t.tolist()
        ([1.0, 0.6666666666666666], [0.25, 0.5], [0.9, 0.8])
    """
    scores = np.asarray(scores, dtype=np.float64)
    is_tp = np.asarray(is_tp, dtype=bool)
    if scores.size == 0:
        return np.zeros(0), np.zeros(0), np.zeros(0)
    if np.any(np.diff(scores) > 0):
        raise ValueError("scores must be sorted by decreasing value")
    tp = np.cumsum(is_tp)
    fp = np.cumsum(~is_tp)
    # last index of each run of equal scores: ties enter the curve together
    last = np.r_[np.nonzero(np.diff(scores))[0], scores.size - 1]
    precision = tp[last] / (tp[last] + fp[last])
    recall = tp[last] / n_ground_truth if n_ground_truth > 0 else np.full(last.size, np.nan)
    return precision, recall, scores[last]


def average_precision(precision: np.ndarray, recall: np.ndarray, *, envelope: bool = False) -> float:
    """``∫ p(r) dr`` of a step precision–recall curve (recall non-decreasing).

    Args:
        precision: precision at each threshold.
        recall: recall at the same thresholds, starting implicitly from 0.
        envelope: integrate ``max_{r' >= r} p(r')`` instead of ``p`` (VOC 2010+).

    Returns:
        AP in [0, 1]; 0 for an empty curve, NaN if the recall is NaN (no ground truth).

    Example:
        >>> average_precision(np.array([1.0, 0.5, 2 / 3]), np.array([0.5, 0.5, 1.0]))
        0.8333333333333333
        >>> average_precision(np.array([1.0, 0.5, 2 / 3]), np.array([0.5, 0.5, 1.0]), envelope=True)
        0.8333333333333333
    """
    precision = np.asarray(precision, dtype=np.float64)
    recall = np.asarray(recall, dtype=np.float64)
    if precision.shape != recall.shape:
        raise ValueError(f"precision and recall must have the same shape, got {precision.shape} and {recall.shape}")
    if recall.size == 0:
        return 0.0
    if np.isnan(recall).any():
        return float("nan")
    if envelope:
        precision = np.maximum.accumulate(precision[::-1])[::-1]
    steps = np.diff(np.r_[0.0, recall])
    if np.any(steps < -1e-12):
        raise ValueError("recall must be non-decreasing")
    return float(np.sum(steps * precision))


def has_labelled_box(ground_truth: np.ndarray | None) -> bool:
    """Whether a frame's ground-truth entry (:func:`evaluate_detections`' convention) holds at least one box; frames
    without one are left out of the frame protocol under ``unlabelled_frames="skip"`` (protocol v2).

    Example:
        >>> has_labelled_box(None), has_labelled_box(np.zeros((0, 4))), has_labelled_box(np.ones((1, 4)))
        (False, False, True)
    """
    return ground_truth is not None and len(ground_truth) > 0


def evaluate_detections(
    detections: Sequence[np.ndarray | None],
    ground_truth: Sequence[np.ndarray | None],
    iou_threshold: float = 0.5,
) -> PRResult:
    """Precision–recall curve and AP of per-frame detections against per-frame boxes.

    Args:
        detections: per frame ``(K, 5)`` ``[x, y, w, h, score]``, or None for a frame not processed.
        ground_truth: per frame ``(G, 4)`` ``[x, y, w, h]``, or None for "no object".
        iou_threshold: IoU of a match (0.5 in the paper).

    Returns:
        A :class:`PRResult`.
    """
    scores, is_tp, n_gt, n_frames = match_detections(detections, ground_truth, iou_threshold)
    precision, recall, thresholds = precision_recall(scores, is_tp, n_gt)
    if n_gt == 0:
        ap = ap_env = float("nan")
    else:
        ap = average_precision(precision, recall)
        ap_env = average_precision(precision, recall, envelope=True)
    return PRResult(
        precision=precision,
        recall=recall if n_gt > 0 else np.zeros_like(recall),
        thresholds=thresholds,
        ap=ap,
        ap_envelope=ap_env,
        n_ground_truth=n_gt,
        n_detections=int(scores.size),
        n_true_positives=int(is_tp.sum()),
        n_frames=n_frames,
        iou_threshold=float(iou_threshold),
    )


def plot_pr(results: dict[str, PRResult], path: str | Path, *, title: str = "") -> Path:
    """Write a precision–recall plot (PNG, matplotlib Agg) with one curve per result.

    Args:
        results: ``{label: PRResult}``; the AP is appended to each label.
        path: PNG file to write (parent folders created).
        title: figure title.

    Returns:
        The path written.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(5, 4.5), dpi=120)
    try:
        for label, res in results.items():
            # step curve from (r=0, p=first precision) as integrated by `ap`
            r = np.r_[0.0, res.recall]
            p = np.r_[res.precision[:1] if res.precision.size else [1.0], res.precision]
            ap = "n/a" if math.isnan(res.ap) else f"{res.ap:.3f}"
            ax.step(r, p, where="pre", label=f"{label} (AP {ap})")
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 1.02)
        ax.set_xlabel("recall")
        ax.set_ylabel("precision")
        ax.grid(alpha=0.3)
        if title:
            ax.set_title(title)
        if results:
            ax.legend(loc="lower left", fontsize=8)
        fig.tight_layout()
        fig.savefig(path)
    finally:
        plt.close(fig)
    return path
