"""Labelled test/validation frames decoded once, detection on them, and frame-level AP.

An :class:`EvalSet` is every k-th frame of some labelled videos (uint8 grayscale,
decoded by :func:`synthaug.data.video.read_video`) with their boxes;
:func:`detect_on_eval_set` runs multi-scale sliding-window detection on every
frame (the detections a protocol runner feeds to
:func:`synthaug.evaluate.matching.match_videos`), and :func:`evaluate_on_videos`
pools them into one PR curve (:class:`EvalResult`).

**Scale check** (the protocol's ``scale_check``): :func:`scale_frame` /
:func:`scale_eval_set` resize test frames by ``s`` (``cv2.INTER_AREA`` down,
``INTER_LINEAR`` up) and their boxes with them.

Example:
    >>> es = EvalSet(["v"], [np.zeros((2, 8, 8), np.uint8)], [[0, 5]], [[None, np.array([[1.0, 1, 4, 4]])]], 5)
    >>> es.n_frames, es.n_objects
    (2, 1)
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import torch

from synthaug.data.boxes import xywh_to_xyxy, xyxy_to_xywh
from synthaug.data.video import find_video, read_video
from synthaug.evaluate.cli import load_labels

# synthaug.detectors.sliding and synthaug.evaluate.ap are imported where used: both import torchvision
# (~1.4 s on top of torch), which would double the cost of importing this module and experiments.py.

__all__ = ["EvalSet", "EvalResult", "load_eval_set", "scale_frame", "scale_eval_set", "detect_on_eval_set",
           "evaluate_on_videos"]


@dataclass
class EvalSet:
    """Every k-th frame of some labelled videos, decoded once (uint8 grayscale).

    Attributes:
        stems: video stems.
        frames: per video, uint8 ``(T_k, H, W)`` frames.
        frame_indices: per video, the source index of each kept frame.
        boxes: per video, per kept frame, ``(G, 4)`` ``[x, y, w, h]`` or None.
        stride_k: frame stride.
    """

    stems: list[str]
    frames: list[np.ndarray]
    frame_indices: list[list[int]]
    boxes: list[list[np.ndarray | None]]
    stride_k: int

    @property
    def n_frames(self) -> int:
        return sum(len(f) for f in self.frames)

    @property
    def n_objects(self) -> int:
        return sum(sum(0 if b is None else len(b) for b in bs) for bs in self.boxes)


def load_eval_set(
    videos: Sequence[str],
    videos_dir: str | Path,
    labels_dir: str | Path,
    *,
    stride_k: int = 10,
    max_videos: int | None = None,
    skip_unlabelled: bool = False,
) -> EvalSet:
    """Decode every ``stride_k``-th frame of labelled videos and their boxes.

    Frames are decoded by :func:`synthaug.data.video.read_video` (up to the
    number of label entries) and every ``stride_k``-th one is kept.

    Args:
        videos: video stems (e.g. a split's test list), in the order to use.
        videos_dir: folder of ``<stem>.mp4`` (or another of
            :data:`synthaug.data.video.VIDEO_EXTENSIONS`).
        labels_dir: folder of ``<stem>.json`` label files (shared format).
        stride_k: keep frames ``0, k, 2k, ...`` (only frames with a label entry).
        max_videos: use only the first this-many videos (evenly spaced over the list).
        skip_unlabelled: leave out the kept frames that hold no labelled box (a protocol's
            ``unlabelled_frames="skip"``: not annotated rather than empty); a video left with no frame is
            left out, with a :class:`UserWarning` naming it.

    Returns:
        The :class:`EvalSet`.

    Raises:
        ValueError: bad stride, no video, a missing video or label file, an
            undecodable video.
    """
    from synthaug.evaluate.ap import has_labelled_box

    if stride_k < 1:
        raise ValueError(f"stride_k must be >= 1, got {stride_k}")
    videos = list(videos)
    if not videos:
        raise ValueError("videos is empty")
    if max_videos is not None:
        if max_videos < 1:
            raise ValueError(f"max_videos must be >= 1, got {max_videos}")
        if max_videos < len(videos):
            pick = np.linspace(0, len(videos) - 1, max_videos).round().astype(int)
            videos = [videos[i] for i in sorted(set(pick.tolist()))]
    videos_dir, labels_dir = Path(videos_dir), Path(labels_dir)
    out = EvalSet([], [], [], [], stride_k)
    for stem in videos:
        label_file = labels_dir / f"{stem}.json"
        if not label_file.is_file():
            raise ValueError(f"no label file {label_file} for video {stem!r}")
        video_file = find_video(videos_dir, stem)
        if video_file is None:
            raise ValueError(f"no video file for {stem!r} in {videos_dir}")
        _, gts = load_labels(label_file)
        if not gts:
            raise ValueError(f"no frame decoded from {video_file}: {label_file} has no entry")
        decoded = read_video(video_file, max_frames=len(gts))
        idx = list(range(0, len(decoded), stride_k))
        if skip_unlabelled:
            idx = [j for j in idx if has_labelled_box(gts[j])]
            if not idx:
                warnings.warn(f"video {stem!r}: no labelled box in its scored frames; left out "
                              "(unlabelled frames are skipped)", UserWarning, stacklevel=2)
                continue
        out.stems.append(stem)
        out.frames.append(np.ascontiguousarray(decoded[idx]))
        out.frame_indices.append(idx)
        out.boxes.append([gts[j] for j in idx])
    return out


def scale_frame(frame: np.ndarray, boxes: np.ndarray | None, scale: float) -> tuple[np.ndarray, np.ndarray | None]:
    """Resize a frame by ``scale`` and its XYXY boxes with it.

    ``cv2.INTER_AREA`` when shrinking, ``cv2.INTER_LINEAR`` when enlarging; the new size is
    ``round(W * scale) x round(H * scale)`` and boxes are multiplied by the actual per-axis
    factors ``W'/W``, ``H'/H`` (pixel edges at integers: an edge at ``x`` moves to ``x W'/W``).

    Args:
        frame: ``(H, W)`` or ``(H, W, C)`` image.
        boxes: ``(G, 4)`` ``[x1, y1, x2, y2]`` or None.
        scale: the factor (> 0).

    Returns:
        ``(frame, boxes)`` resized (copies; ``scale == 1`` returns copies unchanged).

    Example:
        >>> f, b = scale_frame(np.zeros((10, 20), np.uint8), np.array([[2.0, 2.0, 6.0, 4.0]]), 2.0)
        >>> f.shape, b.tolist()
        ((20, 40), [[4.0, 4.0, 12.0, 8.0]])
    """
    import cv2

    if not (isinstance(scale, (int, float)) and math.isfinite(scale) and scale > 0):
        raise ValueError(f"scale must be a positive number, got {scale!r}")
    h, w = frame.shape[:2]
    out_boxes = None if boxes is None else np.asarray(boxes, dtype=np.float64).reshape(-1, 4).copy()
    if scale == 1.0:
        return frame.copy(), out_boxes
    nw, nh = max(1, int(round(w * scale))), max(1, int(round(h * scale)))
    interp = cv2.INTER_AREA if scale < 1 else cv2.INTER_LINEAR
    out = cv2.resize(frame, (nw, nh), interpolation=interp)
    if out_boxes is not None:
        out_boxes *= np.array([nw / w, nh / h, nw / w, nh / h])
    return out, out_boxes


def scale_eval_set(eval_set: EvalSet, scale: float) -> EvalSet:
    """The scale check's test set: every frame of an ``EvalSet`` resized by ``scale``, boxes with it.

    ``eval_set`` is an :class:`synthaug.evaluate.videos.EvalSet` (``frames``: per video
    ``(T, H, W)`` uint8; ``boxes``: per video, per frame ``(G, 4)`` XYWH or None); a copy of the
    same type is returned (the frames take ``scale²`` times the memory).
    """
    frames, boxes = [], []
    for vf, vb in zip(eval_set.frames, eval_set.boxes):
        out_f, out_b = [], []
        for f, b in zip(vf, vb):
            bx = None if b is None else xywh_to_xyxy(b)
            sf, sb = scale_frame(f, bx, scale)
            out_f.append(sf)
            out_b.append(None if sb is None else xyxy_to_xywh(sb))
        frames.append(np.stack(out_f) if out_f else np.asarray(vf))
        boxes.append(out_b)
    return replace(eval_set, frames=frames, boxes=boxes)


@dataclass
class EvalResult:
    """AP of a detector on an :class:`EvalSet`.

    Attributes:
        ap: AP at IoU >= 0.5 (``∫ p(r) dr``, the paper's measure).
        ap_iou03: AP at IoU >= 0.3 (looser localisation; diagnostic).
        ap_envelope: VOC "all points" AP at IoU 0.5.
        max_recall: recall at the lowest score kept.
        n_frames, n_objects: evaluated frames and labelled objects.
        frames_per_second: detection speed (the detection's wall clock).
        per_video: stem -> AP at IoU 0.5.
        precision, recall: the IoU-0.5 curve, subsampled to at most 200 points.
    """

    ap: float
    ap_iou03: float
    ap_envelope: float
    max_recall: float
    n_frames: int
    n_objects: int
    frames_per_second: float
    per_video: dict[str, float | None] = field(default_factory=dict)
    precision: list[float] = field(default_factory=list)
    recall: list[float] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        return asdict(self)


def _nan_to_none(x: float) -> float | None:
    return None if x is None or (isinstance(x, float) and math.isnan(x)) else float(x)


@torch.no_grad()
def detect_on_eval_set(
    detector: Any,
    eval_set: EvalSet,
    *,
    scales: Sequence[float] | None = None,
    box_in_window: Sequence[float] | None = None,
    nms_iou: float = 0.3,
    max_detections: int = 10,
    refine_boxes: bool = True,
) -> list[list[np.ndarray]]:
    """Multi-scale sliding-window detection on every frame of ``eval_set``.

    Args:
        detector: a :class:`~synthaug.detectors.base.PatchDetector`.
        eval_set: frames and boxes (:func:`load_eval_set`).
        scales: pyramid factors (default :data:`synthaug.detectors.sliding.DEFAULT_SCALES`).
        box_in_window: object box inside a window (default: the detector's).
        nms_iou: NMS overlap threshold.
        max_detections: boxes kept per frame.
        refine_boxes: apply the detector's box regressor (if any); see
            :func:`~synthaug.detectors.sliding.detect_multiscale` and :func:`refine_detections`.

    Returns:
        Per video, per kept frame, float64 ``(K, 5)`` detections ``[x, y, w, h, score]``.
    """
    from synthaug.detectors.sliding import DEFAULT_SCALES, detect_multiscale

    scales = list(DEFAULT_SCALES if scales is None else scales)
    out: list[list[np.ndarray]] = []
    for frames in eval_set.frames:
        dets_v = []
        for frame in frames:
            image = torch.from_numpy(frame).float().div_(255.0)
            d = detect_multiscale(detector, image, scales=scales, nms_iou=nms_iou, max_detections=max_detections,
                                  box_in_window=box_in_window, refine_boxes=refine_boxes)
            dets_v.append(d.numpy().astype(np.float64))
        out.append(dets_v)
    return out


@torch.no_grad()
def refine_detections(detector: Any, eval_set: EvalSet, detections: Sequence[Sequence[np.ndarray]], *,
                      nms_iou: float = 0.3) -> list[list[np.ndarray]]:
    """``detect_on_eval_set(..., refine_boxes=False)`` output -> what ``refine_boxes=True`` reports.

    The detector's box regressor acts on the kept boxes only, followed by the second NMS of
    :func:`~synthaug.detectors.sliding.refine_and_suppress` (``nms_iou``: the detection's),
    so this equals ``detect_on_eval_set(..., refine_boxes=True)`` without scanning the frames
    twice. Returns copies of ``detections`` when the detector has no box regressor.
    """
    from torchvision.ops import box_convert

    from synthaug.detectors.sliding import refine_and_suppress

    reg = getattr(detector, "box_regressor", None)
    out: list[list[np.ndarray]] = []
    for frames, dets_v in zip(eval_set.frames, detections):
        refined = []
        for frame, d in zip(frames, dets_v):
            d = np.array(d, dtype=np.float64, copy=True).reshape(-1, 5)
            if reg is not None and d.shape[0]:
                image = torch.from_numpy(frame).float().div_(255.0)[None, None]
                boxes = box_convert(torch.as_tensor(d[:, :4], dtype=torch.float32), "xywh", "xyxy")
                b, sc = refine_and_suppress(reg, image, boxes, torch.as_tensor(d[:, 4], dtype=torch.float32), nms_iou)
                d = np.concatenate([box_convert(b, "xyxy", "xywh").numpy(), sc.numpy()[:, None]], 1).astype(np.float64)
            refined.append(d)
        out.append(refined)
    return out


def evaluate_on_videos(
    detector: Any,
    eval_set: EvalSet,
    *,
    scales: Sequence[float] | None = None,
    box_in_window: Sequence[float] | None = None,
    nms_iou: float = 0.3,
    max_detections: int = 10,
    iou: float = 0.5,
) -> EvalResult:
    """Run multi-scale sliding-window detection on every frame of ``eval_set`` and compute AP.

    Args:
        detector: a :class:`~synthaug.detectors.base.PatchDetector`.
        eval_set: frames and boxes (:func:`load_eval_set`).
        scales, box_in_window, nms_iou, max_detections: as :func:`detect_on_eval_set`.
        iou: matching IoU of the main AP (0.5, the paper's).

    Returns:
        An :class:`EvalResult` (all videos pooled into one PR curve).
    """
    from synthaug.evaluate.ap import evaluate_detections

    t0 = time.perf_counter()
    dets = detect_on_eval_set(detector, eval_set, scales=scales, box_in_window=box_in_window, nms_iou=nms_iou,
                              max_detections=max_detections)
    seconds = time.perf_counter() - t0
    dets_all: list[np.ndarray] = []
    gts_all: list[np.ndarray | None] = []
    per_video: dict[str, float | None] = {}
    for stem, dets_v, boxes in zip(eval_set.stems, dets, eval_set.boxes):
        per_video[stem] = _nan_to_none(evaluate_detections(dets_v, boxes, iou).ap)
        dets_all.extend(dets_v)
        gts_all.extend(boxes)
    res = evaluate_detections(dets_all, gts_all, iou)
    res03 = evaluate_detections(dets_all, gts_all, 0.3)
    keep = np.unique(np.linspace(0, max(res.recall.size - 1, 0), min(200, res.recall.size)).round().astype(int)) if res.recall.size else np.zeros(0, int)
    return EvalResult(
        ap=float(np.nan_to_num(res.ap)),
        ap_iou03=float(np.nan_to_num(res03.ap)),
        ap_envelope=float(np.nan_to_num(res.ap_envelope)),
        max_recall=float(res.recall.max()) if res.recall.size else 0.0,
        n_frames=res.n_frames,
        n_objects=res.n_ground_truth,
        frames_per_second=len(dets_all) / seconds if seconds > 0 else 0.0,
        per_video=per_video,
        precision=[round(float(v), 4) for v in res.precision[keep]],
        recall=[round(float(v), 4) for v in res.recall[keep]],
    )
