"""Detector training: the one code path of the three families, with hard-negative mining at scale.

Everything that turns *labelled videos* into a trained detector lives here, beside
the detectors (``synthaug train``, the experiments and any user script call the
same functions):

- :func:`train_detector` — one family (``"hog"``, ``"adaboost"``, ``"cnn"``) on
  positive / negative patches with the budgets of :class:`TrainOptions`; given a
  ``mining_source`` it runs the mining rounds below;
- :func:`mine_hard_negatives` — scan full frames with the detector's own sliding
  window scoring (:func:`~synthaug.detectors.sliding.candidate_boxes` + NMS, the
  pyramid of :func:`~synthaug.detectors.sliding.detect_multiscale`), never
  taking a window that touches a labelled box grown by a margin, and keep the
  top-scoring windows of every frame as new negatives;
- :func:`train_with_mining` — train, then in rounds: mine, add, retrain, and
  measure the **validation false-positive count** (:func:`validation_false_positives`);
  stop when it stops falling (or after ``mining_rounds``) and keep the detector
  with the fewest; every round's added negatives and count go into a log;
- :class:`VideoFrames` — a memory-bounded frame stream (video by video, every
  k-th frame) in the shared label format, the mining and validation source;
- :func:`train_from_videos` — a folder of videos + labels (any numbering, any
  classes) -> split by video -> positives (seed frames drawn the way
  ``synthaug ingest`` draws them, or every labelled frame, plus synthetic ones
  from a fit) -> negatives -> mining -> a detector and its metadata.

**Negatives at scale.** The mining frames are every ``mining_stride``-th frame
of *every* training video of the class (labelled frames only: a null label does
not say the object is absent from view, only that it was not drawn, as
:func:`synthaug.data.negatives.sample_negatives` assumes too; the labelled box,
grown by ``max(4 px, mining_margin x longest side)`` on every side, is masked:
a window touching it is never a negative) and of every training video of the
negative classes (``"bird"``: every frame is free of the class, nothing is
masked — birds are the look-alikes to learn). HOG keeps its own DPM-style cache
mining over the negative pool (which now holds the mined windows) and the seed
frames; AdaBoost and the CNN learn from the mined windows only through this loop.

**Validation false-positive count** (the stopping rule): detections
(:func:`~synthaug.detectors.sliding.detect_multiscale`, ``val_top_k`` per frame)
on every ``val_stride``-th frame of the validation videos are matched to the
labels (greedy by score, IoU >= ``val_iou``; null-label frames have no object);
the count is the number of false positives scoring at or above the detection at
which recall first reaches ``val_target_recall`` (50 %) — the clutter a user must
accept to find half of the drones. When that recall is never reached every
kept false positive counts.

Import rule: this module imports ``synthaug.data`` and ``synthaug.detectors``
only (never ``synthaug.evaluate`` / ``synthaug.fit``); protocol settings come in
as plain values.

Example:
    >>> from synthaug.detectors.toy import toy_patches
    >>> pos, neg = toy_patches(40, 80, seed=0)
    >>> det = train_detector("hog", pos, neg, 0, options=TrainOptions(hog_components=1, hog_mining_rounds=0))
    >>> det.kind, det.window
    ('hog', 40)
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator, Literal, Mapping, NamedTuple, Sequence

import numpy as np
import torch
from torch import Tensor

from synthaug.data.boxes import box_iou, xywh_to_xyxy

__all__ = [
    "DETECTORS",
    "TrainOptions",
    "TrainingInputError",
    "check_kind",
    "train_detector",
    "train_with_mining",
    "TrainResult",
    "MiningFrame",
    "VideoFrames",
    "MinedNegatives",
    "mine_hard_negatives",
    "validation_false_positives",
    "real_positives",
    "perturbed_positives",
    "synthetic_positives",
    "negative_pool",
    "mining_frames",
    "frames_training_set",
    "bird_hard_negatives",
    "VideoSet",
    "discover_videos",
    "split_by_video",
    "train_from_videos",
    "METADATA_FORMAT",
]

DetectorKind = Literal["hog", "adaboost", "cnn"]
DETECTORS: tuple[str, ...] = ("hog", "adaboost", "cnn")
METADATA_FORMAT = "synthaug.trained_detector"
METADATA_VERSION = 1


# =========================================================================== options
@dataclass(frozen=True)
class TrainOptions:
    """Training budgets of the three families and of the hard-negative mining (CPU-only, shared machine).

    Attributes:
        hog_components: root filters of the HOG mixture (the paper's DPM: 3-5).
        hog_mining_rounds: HOG's own cache-mining rounds (negative pool + HOG mining frames).
        hog_mining_frames: at most this many frames (object boxes ignored) for HOG's own mining.
        ada_rounds: boosting rounds T.
        ada_candidates: random Levi-Weiss candidates (of the exhaustive grid).
        cnn_epochs: passes over the training patches (each mirrored or not;
            ``PatchDetectorModule`` under ``lightning.Trainer``).
        cnn_batch_size: mini-batch size.
        cnn_max_steps: the number of epochs is reduced so that training takes
            at most about this many optimiser steps (large synthetic sets).
        cnn_shift: positives moved by random whole-pixel offsets up to this many pixels
            each step (the CNN scans every 8 pixels; ``PatchDetectorModule(shift=)``).
        mining_rounds: rounds of :func:`train_with_mining` (mine, add, retrain) at most;
            used only when a mining source is given; 0 = no mining.
        mining_stride: every k-th frame of every mining video is scanned. Measured at 30 on the 56 halmstad
            drone training videos + 32 bird videos (894 frames, 640x512, 1 torch thread, shared 2-core box):
            one round (scan + retrain + validation on 219 frames) HOG 71 s (scan 53 s), CNN 89 s (58 s),
            AdaBoost 238 s (171 s); 4 470 negatives added per round; peak memory 1.4-2.1 GB.
        mining_per_frame: false positives kept per frame (the best after NMS).
        mining_max_per_round: at most this many new negatives per round (the highest-scoring).
        mining_margin: labelled boxes grow by ``max(4 px, margin x longest side)`` on each side
            before masking.
        mining_nms_iou: NMS among a frame's windows before the per-frame top-k
            (one clutter object gives one negative per round, not ten shifted copies).
        scales: pyramid of mining and validation (None: ``sliding.DEFAULT_SCALES``).
        val_stride: every k-th frame of the validation videos is scored.
        val_top_k: detections kept per validation frame.
        val_iou: matching IoU of the validation count.
        val_target_recall: the count is the false positives above the score reaching this recall.
        box_regression: fit a :class:`~synthaug.detectors.boxes.BoxRegressor` (detections ->
            the annotators' boxes) on the training videos' labelled frames, before the mining
            rounds (it does not depend on the detector; their validation counts use it).
            Measured on the halmstad drone test split (HOG, 100 seeds, seed 0): frame AP@0.5
            0.206 -> 0.333 on the same detections.
        box_stride: every k-th labelled frame of the training videos feeds the box regression.
    """

    hog_components: int = 3
    hog_mining_rounds: int = 2
    hog_mining_frames: int = 40
    ada_rounds: int = 100
    ada_candidates: int = 2000
    cnn_epochs: int = 12
    cnn_batch_size: int = 128
    cnn_max_steps: int = 1200
    cnn_shift: int = 0
    mining_rounds: int = 3
    mining_stride: int = 30
    mining_per_frame: int = 5
    mining_max_per_round: int = 10000
    mining_margin: float = 0.25
    mining_nms_iou: float = 0.3
    scales: tuple[float, ...] | None = None
    val_stride: int = 30
    val_top_k: int = 10
    val_iou: float = 0.5
    val_target_recall: float = 0.5
    box_regression: bool = True
    box_stride: int = 15

    def __post_init__(self) -> None:
        for name in ("mining_stride", "mining_per_frame", "mining_max_per_round", "val_stride", "val_top_k", "box_stride"):
            if int(getattr(self, name)) < 1:
                raise ValueError(f"{name} must be >= 1, got {getattr(self, name)}")
        if self.mining_rounds < 0:
            raise ValueError(f"mining_rounds must be >= 0, got {self.mining_rounds}")
        if self.mining_margin < 0:
            raise ValueError(f"mining_margin must be >= 0, got {self.mining_margin}")
        if not 0 <= int(self.cnn_shift) < 20:
            raise ValueError(f"cnn_shift must be in [0, 20) pixels, got {self.cnn_shift}")
        if not 0 < self.val_target_recall <= 1 or not 0 < self.val_iou <= 1:
            raise ValueError(f"val_target_recall and val_iou must be in (0, 1], got {self.val_target_recall}, {self.val_iou}")
        if self.scales is not None:
            object.__setattr__(self, "scales", tuple(float(s) for s in self.scales))

    def pyramid(self) -> tuple[float, ...]:
        from synthaug.detectors.sliding import DEFAULT_SCALES

        return tuple(DEFAULT_SCALES if self.scales is None else self.scales)


class TrainingInputError(ValueError):
    """An input of :func:`train_from_videos` that cannot be used; ``option`` names the CLI option."""

    def __init__(self, option: str, message: str) -> None:
        super().__init__(f"{option}: {message}")
        self.option = option


def check_kind(kind: str) -> None:
    """Raise ``ValueError`` naming the known families unless ``kind`` is one of :data:`DETECTORS`."""
    if kind not in DETECTORS:
        raise ValueError(f"unknown detector kind {kind!r}; choose from {list(DETECTORS)}")


# =========================================================================== one fit
def _fit_once(
    kind: str,
    positives: Tensor,
    negatives: Tensor,
    seed: int,
    *,
    box_in_window: Sequence[float] | None,
    mining_frames: Sequence[Tensor],
    mining_boxes: Sequence[Tensor | None] | None,
    options: TrainOptions,
) -> Any:
    from synthaug.detectors.base import check_patches

    check_kind(kind)
    if not isinstance(positives, Tensor) or positives.dim() != 4 or positives.shape[0] == 0:
        raise ValueError(f"positives must be a non-empty (P, 1, S, S) float tensor, got {getattr(positives, 'shape', positives)}")
    if not isinstance(negatives, Tensor) or negatives.dim() != 4 or negatives.shape[0] == 0:
        raise ValueError(f"negatives must be a non-empty (N, 1, S, S) float tensor, got {getattr(negatives, 'shape', negatives)}")
    window = int(positives.shape[-1])
    positives = check_patches(positives, window)
    negatives = check_patches(negatives, window)
    if kind == "hog":
        from synthaug.detectors.hog_dpm import HOGDetector

        frames = list(mining_frames)[: options.hog_mining_frames]
        boxes = None if mining_boxes is None else list(mining_boxes)[: len(frames)]
        det = HOGDetector.fit(
            positives,
            negatives,
            background_images=frames,
            ignore_boxes=boxes,
            components=options.hog_components,
            mining_rounds=options.hog_mining_rounds,
            window=window,
            generator=torch.Generator().manual_seed(seed),
        )
    elif kind == "adaboost":
        from synthaug.detectors.adaboost import train_adaboost

        det = train_adaboost(positives, negatives, n_rounds=options.ada_rounds, candidates=options.ada_candidates, seed=seed)
    else:
        # the one CNN training loop: PatchDetectorModule + PatchDataModule.from_tensors under a CPU lightning.Trainer
        from synthaug.detectors.lightning_module import fit_patch_detector

        n = positives.shape[0] + negatives.shape[0]
        steps_per_epoch = max(1, math.ceil(n / options.cnn_batch_size))
        epochs = max(1, min(options.cnn_epochs, options.cnn_max_steps // steps_per_epoch))
        module = fit_patch_detector(positives, negatives, epochs=epochs, batch_size=options.cnn_batch_size, seed=seed,
                                    shift=options.cnn_shift)
        det = module.to_detector()
    det.box_in_window = None if box_in_window is None else tuple(float(v) for v in box_in_window)
    return det


def train_detector(
    kind: str,
    positives: Tensor,
    negatives: Tensor,
    seed: int = 0,
    *,
    box_in_window: Sequence[float] | None = None,
    mining_frames: Sequence[Tensor] = (),
    mining_boxes: Sequence[Tensor | None] | None = None,
    options: TrainOptions = TrainOptions(),
    mining_source: Iterable[Any] | None = None,
    val_frames: Iterable[Any] | None = None,
    log: Callable[[str], None] | None = None,
) -> Any:
    """Train one detector family on positive and negative patches (with mining rounds when given a source).

    Args:
        kind: ``"hog"`` (HOG root-filter mixture with its own hard-negative cache mining),
            ``"adaboost"`` (Levi-Weiss stumps) or ``"cnn"`` (PatchCNN).
        positives: object patches, float in [0, 1].
        negatives: background patches, float in [0, 1].
        seed: seeds every random choice of the training.
        box_in_window: object box inside a window (``[x, y, w, h]``, window
            pixels) reported by sliding-window detection; None = whole window.
        mining_frames: HOG only: full grayscale frames ``(H, W)`` in [0, 1]
            scanned by HOG's own mining (at most ``options.hog_mining_frames``).
        mining_boxes: HOG only: per mining frame, ``(G, 4)`` object boxes never mined.
        options: training and mining budgets.
        mining_source: frames to mine hard negatives from, for every family
            (:class:`VideoFrames` or an iterable of :class:`MiningFrame`); None: no
            mining rounds (a single fit, as before).
        val_frames: validation frames for the stopping rule (see :func:`train_with_mining`).
        log: progress printer.

    Returns:
        A :class:`~synthaug.detectors.base.PatchDetector` (the lowest validation FP count
        of the rounds; :func:`train_with_mining` also returns the per-round log).

    Shape:
        - positives: (P, 1, 40, 40), negatives: (N, 1, 40, 40)
    """
    if mining_source is None or options.mining_rounds == 0:
        return _fit_once(kind, positives, negatives, seed, box_in_window=box_in_window, mining_frames=mining_frames,
                         mining_boxes=mining_boxes, options=options)
    return train_with_mining(kind, positives, negatives, seed, box_in_window=box_in_window, mining_frames=mining_frames,
                             mining_boxes=mining_boxes, options=options, mining_source=mining_source,
                             val_frames=val_frames, log=log).detector


# =========================================================================== frame streams
class MiningFrame(NamedTuple):
    """One frame to mine or validate on.

    Attributes:
        image: uint8 ``(H, W)`` (or float in [0, 1]) grayscale frame.
        boxes: ``(G, 4)`` ``[x, y, w, h]`` labelled objects (masked when mining, matched when
            validating), or None (nothing there).
        video: source video stem.
        index: frame index in the video.
    """

    image: Any
    boxes: np.ndarray | None
    video: str = ""
    index: int = -1


def _find_video(videos_dir: Path, stem: str) -> Path | None:
    from synthaug.data.video import VIDEO_EXTENSIONS

    return next((videos_dir / f"{stem}{s}" for s in VIDEO_EXTENSIONS if (videos_dir / f"{stem}{s}").is_file()), None)


@dataclass
class VideoFrames:
    """A re-iterable, memory-bounded stream of every ``stride``-th frame of some labelled videos.

    Videos are decoded one at a time (skipped frames only grabbed) and every frame is
    yielded as soon as it is read, so memory holds one frame, whatever the number of
    videos. Boxes are read and clipped as ingest reads them
    (:func:`~synthaug.data.video.read_labels`, :func:`~synthaug.data.video.clip_boxes`;
    frames beyond the shorter of video and label file are not used).

    Args:
        videos_dir, labels_dir: the shared-format folders.
        positive: stems whose labelled boxes are objects of the class: only their
            frames *with* a box are yielded (with the box to mask / match), unless
            ``null_frames`` is True (validation: a null frame has no object).
        negative: stems whose every frame is free of the class (birds for drones):
            every ``stride``-th frame, ``boxes=None``.
        stride: frame step (frames ``0, k, 2k, ...`` of each video).
        null_frames: yield positive videos' null-label frames too (``boxes=None``).

    Example:
        >>> import tempfile
        >>> from synthaug.data.synthvideo import make_panning_video
        >>> with tempfile.TemporaryDirectory() as d:
        ...     _ = make_panning_video(d, n_frames=7, size=(96, 80), seed=0, name="V_A_001")
        ...     src = VideoFrames(f"{d}/videos", f"{d}/labels", positive=["V_A_001"], stride=3)
        ...     [(f.video, f.index, f.image.shape, f.boxes.shape) for f in src]
        [('V_A_001', 0, (80, 96), (1, 4)), ('V_A_001', 3, (80, 96), (1, 4)), ('V_A_001', 6, (80, 96), (1, 4))]
    """

    videos_dir: Path
    labels_dir: Path
    positive: Sequence[str] = ()
    negative: Sequence[str] = ()
    stride: int = 30
    null_frames: bool = False

    def __post_init__(self) -> None:
        self.videos_dir, self.labels_dir = Path(self.videos_dir), Path(self.labels_dir)
        self.positive, self.negative = list(self.positive), list(self.negative)
        if self.stride < 1:
            raise ValueError(f"stride must be >= 1, got {self.stride}")

    @property
    def stems(self) -> list[str]:
        return self.positive + self.negative

    def planned_frames(self) -> int:
        """Frames the stream will yield, counted from the label files (no decoding)."""
        from synthaug.data.video import read_labels

        n = 0
        for stem in self.stems:
            boxes = read_labels(self.labels_dir / f"{stem}.json").boxes
            pos = stem in self.positive and not self.null_frames
            n += sum(1 for i in range(0, len(boxes), self.stride) if not pos or boxes[i] is not None)
        return n

    def __iter__(self) -> Iterator[MiningFrame]:
        for stem in self.stems:
            yield from self._video(stem, stem in self.positive)

    def _video(self, stem: str, positive: bool) -> Iterator[MiningFrame]:
        from synthaug.data.video import clip_boxes, iter_frames, read_labels, video_frame_size

        path = _find_video(self.videos_dir, stem)
        if path is None:
            raise ValueError(f"no video file for {stem!r} in {self.videos_dir}")
        labels = read_labels(self.labels_dir / f"{stem}.json")
        w, h = video_frame_size(path)
        boxes = labels.boxes
        if w > 0 and h > 0:
            boxes, _ = clip_boxes(boxes, width=w, height=h)
        need = [i for i in range(0, len(boxes), self.stride)
                if not positive or self.null_frames or boxes[i] is not None]
        wanted = set(need)
        for i, frame in iter_frames(path, wanted=wanted.__contains__, stop=max(need) + 1 if need else 0):
            if frame is not None:
                b = boxes[i] if positive else None
                yield MiningFrame(frame, None if b is None else np.asarray(b, np.float64).reshape(-1, 4), stem, i)


def _as_item(item: Any) -> MiningFrame:
    if isinstance(item, MiningFrame):
        return item
    if isinstance(item, tuple):
        return MiningFrame(*item)
    return MiningFrame(item, None)


def _image_tensor(image: Any) -> Tensor:
    if isinstance(image, Tensor):
        t = image
    else:
        t = torch.from_numpy(np.ascontiguousarray(image))
    if t.dtype == torch.uint8:
        t = t.float().div_(255.0)
    t = t.float()
    while t.dim() > 2:
        t = t[0]
    return t


# =========================================================================== mining
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
        frames_iter: :class:`MiningFrame` items (or ``(image, boxes[, video, index])``
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
    from synthaug.detectors.sliding import DEFAULT_SCALES, candidate_boxes, nms, resize_image

    if per_frame < 1 or max_negatives < 1:
        raise ValueError(f"per_frame and max_negatives must be >= 1, got {per_frame}, {max_negatives}")
    scales = [float(s) for s in (DEFAULT_SCALES if scales is None else scales)]
    window, stride = int(detector.window), int(detector.stride)
    whole = (0.0, 0.0, float(window), float(window))
    exclude = exclude if exclude is not None else set()
    t0 = time.perf_counter()
    patches: list[Tensor] = []
    boxes_out: list[Tensor] = []
    scores_out: list[Tensor] = []
    sources: list[tuple[str, int]] = []
    keys: list[tuple[str, int, int, int, int]] = []
    n_frames = 0

    def trim() -> None:
        if len(keys) <= max_negatives:
            return
        s = torch.cat(scores_out)
        order = torch.sort(s, descending=True, stable=True).indices[:max_negatives]
        p, b = torch.cat(patches)[order], torch.cat(boxes_out)[order]
        idx = order.tolist()
        src, ks = [sources[i] for i in idx], [keys[i] for i in idx]
        patches[:], boxes_out[:], scores_out[:] = [p], [b], [s[order]]
        sources[:], keys[:] = src, ks

    for j, raw in enumerate(frames_iter):
        item = _as_item(raw)
        if ignore_boxes is not None and item.boxes is None:
            item = item._replace(boxes=ignore_boxes[j])
        video = item.video or "_"
        index = item.index if item.index >= 0 else j
        image = check_image(_image_tensor(item.image))
        n_frames += 1
        cand, sc = candidate_boxes(detector, image, scales=scales, score_threshold=score_threshold,
                                   pre_nms_top_k=pre_nms_top_k, box_in_window=whole)
        finite = torch.isfinite(sc)
        cand, sc = cand[finite], sc[finite]
        if cand.shape[0] == 0:
            continue
        if item.boxes is not None and np.asarray(item.boxes).size:
            keep = ~_touching(cand, _grown_xyxy(item.boxes, margin))
            cand, sc = cand[keep], sc[keep]
        if cand.shape[0] == 0:
            continue
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
            key = (video, int(index), li, y, x)
            if key in exclude:
                continue
            exclude.add(key)
            patches.append(lvl[0, :, y:y + window, x:x + window].clone()[None])
            boxes_out.append(cand[k][None])
            scores_out.append(sc[k:k + 1])
            sources.append((video, int(index)))
            keys.append(key)
            kept += 1
        if len(keys) > 2 * max_negatives:
            trim()
    trim()
    if keys:
        s = torch.cat(scores_out)
        order = torch.sort(s, descending=True, stable=True).indices
        idx = order.tolist()
        return MinedNegatives(torch.cat(patches)[order], torch.cat(boxes_out)[order], s[order],
                              [sources[i] for i in idx], [keys[i] for i in idx], n_frames, time.perf_counter() - t0)
    return MinedNegatives(torch.zeros(0, 1, window, window), torch.zeros(0, 4), torch.zeros(0), [], [], n_frames,
                          time.perf_counter() - t0)


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
        frames: :class:`MiningFrame` items; ``boxes`` None = no object in the frame.
        scales: pyramid (default ``sliding.DEFAULT_SCALES``).
        top_k: detections kept per frame.
        iou: a detection is a true positive when its IoU with a not yet matched object is >= this
            (greedy by score within the frame, the VOC rule).
        target_recall: the operating point.
        nms_iou: NMS threshold of the detection.

    Returns:
        ``{"fp": count, "recall_reached": bool, "threshold": score at the operating point
        (None when not reached), "max_recall", "tp", "detections", "frames", "objects"}``.

    Example:
        >>> # the toy "darkness" scorer finds one of two dark squares above a darker distractor
        >>> import torch.nn.functional as F
        >>> from synthaug.detectors.base import PatchDetector
        >>> class Dark(PatchDetector):
        ...     kind = "dark_doc"
        ...     def score_patches(self, p): return 1 - p.mean((1, 2, 3))
        ...     def score_map(self, im): return 1 - F.avg_pool2d(im, 40, 4)[0, 0]
        ...     def state_dict(self): return {}
        ...     @classmethod
        ...     def from_state_dict(cls, s): return cls()
        >>> f = np.full((120, 160), 200, np.uint8); f[40:80, 40:80] = 50; f[0:40, 100:140] = 0
        >>> r = validation_false_positives(Dark(), [MiningFrame(f, np.array([[40., 40, 40, 40]]))], scales=[1.0], top_k=2)
        >>> r["fp"], r["recall_reached"], r["max_recall"]
        (1, True, 1.0)
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
    return {"fp": fp, "recall_reached": reached, "threshold": threshold, "max_recall": round(max_recall, 4),
            "tp": int(cum_tp[-1]) if len(cum_tp) else 0, "detections": len(scores), "frames": n_frames, "objects": n_obj}


@dataclass
class TrainResult:
    """A detector trained with mining rounds, and what happened.

    Attributes:
        detector: the chosen detector (fewest validation false positives).
        log: ``{"rounds": [{"round", "added", "negatives", "val", "mine_s", "train_s", "val_s",
            "frames_scanned"}], "chosen_round", "stop_reason", "mining": {...}}``.
        negatives: the negatives the chosen detector was trained on.
    """

    detector: Any
    log: dict[str, Any]
    negatives: Tensor


def train_with_mining(
    kind: str,
    positives: Tensor,
    negatives: Tensor,
    seed: int = 0,
    *,
    box_in_window: Sequence[float] | None = None,
    mining_frames: Sequence[Tensor] = (),
    mining_boxes: Sequence[Tensor | None] | None = None,
    options: TrainOptions = TrainOptions(),
    mining_source: Iterable[Any] | None = None,
    val_frames: Iterable[Any] | None = None,
    log: Callable[[str], None] | None = None,
    fit: Callable[[Tensor, Tensor], Any] | None = None,
    box_regressor: Any = None,
) -> TrainResult:
    """Train, then mine hard negatives and retrain in rounds until the validation false positives stop falling.

    Round 0 trains on ``negatives``; round ``r >= 1`` mines the current detector's
    false positives on ``mining_source`` (:func:`mine_hard_negatives`, windows never
    mined before), adds them, retrains from scratch with the same seed and counts the
    validation false positives (:func:`validation_false_positives` on ``val_frames``,
    decoded once and kept as uint8). It stops when that count does not fall below the
    best so far, when nothing new is mined, or after ``options.mining_rounds``; the
    detector with the fewest is returned (the earliest on ties). Without validation
    frames every round runs and the last detector is returned.

    Args:
        kind, positives, negatives, seed, box_in_window, mining_frames, mining_boxes, options:
            as :func:`train_detector`.
        mining_source: re-iterable frames (:class:`VideoFrames`), streamed once per round.
        val_frames: validation frames (:class:`MiningFrame` items, e.g. ``VideoFrames(...,
            null_frames=True)``); None: no stopping rule.
        log: progress printer.
        fit: ``(positives, negatives) -> detector`` replacing the family's training
            (tests, other families); ``box_in_window`` is still set on its result.
        box_regressor: set on every round's detector (a
            :class:`~synthaug.detectors.boxes.BoxRegressor`; it does not depend on the
            detector), so the validation count matches at the boxes detection reports.

    Returns:
        A :class:`TrainResult`.
    """
    say = log or (lambda m: None)

    def train(neg: Tensor) -> Any:
        if fit is None:
            det = _fit_once(kind, positives, neg, seed, box_in_window=box_in_window, mining_frames=mining_frames,
                            mining_boxes=mining_boxes, options=options)
        else:
            det = fit(positives, neg)
            det.box_in_window = None if box_in_window is None else tuple(float(v) for v in box_in_window)
        if box_regressor is not None:  # validation counts false positives among the boxes detection reports
            det.box_regressor = box_regressor
        return det

    if fit is None:
        check_kind(kind)
    scales = options.pyramid()
    val = None
    if val_frames is not None:
        t0 = time.perf_counter()
        val = [it._replace(image=np.asarray(it.image) if not isinstance(it.image, Tensor) else it.image)
               for it in (_as_item(x) for x in val_frames)]
        say(f"validation: {len(val)} frames, {sum(0 if v.boxes is None else len(v.boxes) for v in val)} objects "
            f"(decoded in {time.perf_counter() - t0:.1f}s)")
        if not val:
            val = None

    def count(det: Any) -> tuple[dict[str, Any] | None, float]:
        if val is None:
            return None, 0.0
        t = time.perf_counter()
        r = validation_false_positives(det, val, scales=scales, top_k=options.val_top_k, iou=options.val_iou,
                                       target_recall=options.val_target_recall)
        return r, time.perf_counter() - t

    t0 = time.perf_counter()
    det = train(negatives)
    t_train = time.perf_counter() - t0
    v, t_val = count(det)
    rounds = [{"round": 0, "added": 0, "negatives": int(negatives.shape[0]), "frames_scanned": 0, "val": v,
               "mine_s": 0.0, "train_s": round(t_train, 1), "val_s": round(t_val, 1)}]
    say(f"round 0: {negatives.shape[0]} negatives, train {t_train:.0f}s" + (f", validation FP {v['fp']}" if v else ""))
    best = (det, v, 0, negatives)
    current_neg = negatives
    seen: set[tuple[str, int, int, int, int]] = set()
    stop = "mining_rounds reached" if options.mining_rounds else "no mining (mining_rounds = 0)"
    if mining_source is None:
        stop = "no mining source"
    for r in range(1, options.mining_rounds + 1 if mining_source is not None else 1):
        mined = mine_hard_negatives(det, mining_source, scales=scales, per_frame=options.mining_per_frame,
                                    max_negatives=options.mining_max_per_round, margin=options.mining_margin,
                                    nms_iou=options.mining_nms_iou, exclude=seen)
        if len(mined) == 0:
            rounds.append({"round": r, "added": 0, "negatives": int(current_neg.shape[0]), "frames_scanned": mined.frames_scanned,
                           "val": None, "mine_s": round(mined.seconds, 1), "train_s": 0.0, "val_s": 0.0})
            stop = "no new negative mined"
            say(f"round {r}: nothing new mined on {mined.frames_scanned} frames ({mined.seconds:.0f}s); stop")
            break
        current_neg = torch.cat([current_neg, mined.patches.to(current_neg.dtype)])
        t0 = time.perf_counter()
        det = train(current_neg)
        t_train = time.perf_counter() - t0
        v, t_val = count(det)
        rounds.append({"round": r, "added": len(mined), "negatives": int(current_neg.shape[0]),
                       "frames_scanned": mined.frames_scanned, "val": v, "mine_s": round(mined.seconds, 1),
                       "train_s": round(t_train, 1), "val_s": round(t_val, 1),
                       "videos": len({s for s, _ in mined.sources})})
        say(f"round {r}: +{len(mined)} negatives from {mined.frames_scanned} frames (scan {mined.seconds:.0f}s), "
            f"{current_neg.shape[0]} in all, train {t_train:.0f}s" + (f", validation FP {v['fp']}" if v else ""))
        if v is None:
            best = (det, v, r, current_neg)
            continue
        if best[1] is not None and v["fp"] >= best[1]["fp"]:
            stop = f"validation false positives stopped falling ({best[1]['fp']} -> {v['fp']})"
            say(f"stop: {stop}; keeping round {best[2]}")
            break
        best = (det, v, r, current_neg)
    out_log = {"rounds": rounds, "chosen_round": best[2], "stop_reason": stop,
               "mining": {"stride": getattr(mining_source, "stride", None), "per_frame": options.mining_per_frame,
                          "max_per_round": options.mining_max_per_round, "margin": options.mining_margin,
                          "scales": list(scales), "max_rounds": options.mining_rounds},
               "validation": None if val is None else {"frames": len(val), "top_k": options.val_top_k, "iou": options.val_iou,
                                                       "target_recall": options.val_target_recall}}
    return TrainResult(best[0], out_log, best[3])


# =========================================================================== positive and negative sets
def _as_float_patches(x: Any) -> Tensor:
    t = torch.as_tensor(np.asarray(x)) if not isinstance(x, Tensor) else x
    if t.dtype == torch.uint8:
        t = t.float() / 255.0
    if t.dim() == 3:
        t = t[:, None]
    return t.float().contiguous()


def real_positives(seedset: Any) -> Tensor:
    """The seed set's real object patches as float ``(N, 1, P, P)`` in [0, 1]."""
    return _as_float_patches(seedset.patches)


def perturbed_positives(seedset: Any, copies: int, *, seed: int = 0) -> Tensor:
    """Real patches plus ``copies`` perturbed versions of each (the paper's Table 1 baseline,
    :func:`~synthaug.effects.perturb.perturb_patches`)."""
    from synthaug.effects.perturb import with_perturbed_copies

    return with_perturbed_copies(real_positives(seedset), copies, seed=seed)


def synthetic_positives(
    seedset: Any,
    mesh: Any,
    fit_file: str | Path,
    count: int,
    *,
    seed: int = 0,
    effects: Sequence[str] | None = None,
    capture_sampling: str = "seed",
    batch: int = 2048,
    seed_geometry: Mapping[str, Any] | str | None = "auto",
    pose_sampling: str = "uniform",
) -> Tensor:
    """``count`` synthetic object patches generated from a capture-parameter fit.

    Each patch keeps one seed's fitted capture parameters and background and
    draws a random pose (:class:`~synthaug.data.synthetic.SyntheticObjectDataset`).

    Args:
        seedset: the seed set the fit was made on (backgrounds).
        mesh: mesh path or built-in name.
        fit_file: ``synthaug fit`` output.
        count: number of patches.
        seed: the dataset's base seed.
        effects: effects applied (None: all fitted ones); leaving one out is the ablation.
        capture_sampling: ``"seed"`` (the paper), ``"uniform"`` (Fig. 10) or ``"kde"``.
        batch: items built per ``__getitems__`` call.
        seed_geometry: each seed's place in its frame, for position-aware camera effects
            (:class:`~synthaug.data.synthetic.SyntheticObjectDataset`; default ``"auto"``: the seed
            set's); None: the patch is the frame.
        pose_sampling: ``"uniform"`` (the paper) or ``"fitted"`` (around each seed's fitted pose; see
            :class:`~synthaug.data.synthetic.SyntheticObjectDataset`).

    Returns:
        Float patches ``(count, 1, P, P)`` in [0, 1].
    """
    from synthaug.data.synthetic import SyntheticObjectDataset

    if count < 0:
        raise ValueError(f"count must be >= 0, got {count}")
    p = int(seedset.patches.shape[-1])
    if count == 0:
        return torch.zeros(0, 1, p, p)
    ds = SyntheticObjectDataset(
        mesh, seedset, params=str(fit_file), length=count, patch_size=p, negative_fraction=0.0,
        effects=None if effects is None else list(effects), capture_sampling=capture_sampling, seed=seed,  # type: ignore[arg-type]
        seed_geometry=seed_geometry, pose_sampling=pose_sampling,  # type: ignore[arg-type]
    )
    out = []
    for start in range(0, count, batch):
        items = ds.__getitems__(list(range(start, min(count, start + batch))))
        out.append(torch.stack([img for img, _ in items]))
    return torch.cat(out).float().clamp(0, 1)


def negative_pool(seedset: Any, extra: int = 3000, *, seed: int = 0) -> Tensor:
    """The seed set's negatives plus ``extra`` object-free crops of its seed frames.

    Crops use the seeds' crop sides (the same scale normalisation as the
    positives) and never touch the labelled box (grown by a margin).
    """
    from synthaug.data.negatives import sample_negatives

    neg = [np.asarray(seedset.negatives, np.uint8)]
    if extra > 0:
        n = len(seedset)
        frames = np.stack([seedset.frame(i) for i in range(n)])
        boxes = [np.asarray(seedset.boxes[i], np.float64) for i in range(n)]
        more, _ = sample_negatives(frames, boxes, extra, sides=[float(s) for s in seedset.crops[:, 2]],
                                   rng=np.random.default_rng(seed), patch_size=int(seedset.patches.shape[-1]))
        neg.append(more)
    return _as_float_patches(np.concatenate(neg))


def mining_frames(seedset: Any, limit: int = 40) -> tuple[list[Tensor], list[Tensor]]:
    """Up to ``limit`` seed frames (float ``(H, W)``) and their boxes, for HOG hard-negative mining."""
    n = min(limit, len(seedset))
    pick = np.unique(np.linspace(0, len(seedset) - 1, n).round().astype(int))
    frames = [torch.from_numpy(seedset.frame(int(i))).float() / 255.0 for i in pick]
    boxes = [torch.as_tensor(seedset.boxes[int(i)], dtype=torch.float32).reshape(1, 4) for i in pick]
    return frames, boxes


def frames_training_set(
    videos: Sequence[str],
    videos_dir: str | Path,
    labels_dir: str | Path,
    *,
    frame_step: int = 1,
    negatives_per_video: int = 60,
    mining_frames_per_video: int = 1,
    patch_size: int = 40,
    object_fraction: float = 0.7,
    seed: int = 0,
) -> dict[str, Any]:
    """Positives from every ``frame_step``-th labelled frame of the training videos (the "plenty of real data" reference).

    Args:
        videos: training video stems.
        videos_dir, labels_dir: the shared-format folders.
        frame_step: 1 = every labelled frame.
        negatives_per_video: object-free crops drawn per video (seed crop sides).
        mining_frames_per_video: frames kept (with their boxes) for HOG mining.
        patch_size, object_fraction: the seed sets' patch geometry.
        seed: seeds the negative sampling.

    Returns:
        ``{"positives": (P,1,S,S), "negatives": (N,1,S,S), "boxes": (P,4) frame boxes,
        "mining_frames": [...], "mining_boxes": [...]}``.
    """
    from synthaug.data.negatives import sample_negatives
    from synthaug.data.seedset import crop_geometry, crop_patch
    from synthaug.data.video import read_video_with_labels

    rng = np.random.default_rng(seed)
    videos_dir, labels_dir = Path(videos_dir), Path(labels_dir)
    pos, neg, boxes_all, mf, mb = [], [], [], [], []
    for stem in videos:
        video_file = next((videos_dir / f"{stem}{s}" for s in (".mp4", ".avi", ".mov", ".mkv") if (videos_dir / f"{stem}{s}").is_file()), None)
        if video_file is None:
            raise ValueError(f"no video file for {stem!r} in {videos_dir}")
        frames, labels, _ = read_video_with_labels(video_file, labels_dir / f"{stem}.json")
        labelled = [i for i, b in enumerate(labels.boxes) if b is not None]
        sides = []
        for i in labelled[::frame_step]:
            box = np.asarray(labels.boxes[i], np.float64).reshape(-1, 4)[0]
            patch, _ = crop_patch(frames[i], box=box, patch_size=patch_size, object_fraction=object_fraction)
            pos.append(patch)
            boxes_all.append(box)
            sides.append(float(crop_geometry(box, patch_size=patch_size, object_fraction=object_fraction)[2]))
        if sides and negatives_per_video > 0:
            n, _ = sample_negatives(frames, labels.boxes, negatives_per_video, sides=sides, rng=rng, patch_size=patch_size)
            neg.append(n)
        for i in labelled[:: max(1, len(labelled) // max(mining_frames_per_video, 1))][:mining_frames_per_video]:
            mf.append(torch.from_numpy(frames[i]).float() / 255.0)
            mb.append(torch.as_tensor(labels.boxes[i], dtype=torch.float32).reshape(-1, 4))
    if not pos:
        raise ValueError(f"no labelled frame in videos {list(videos)[:5]}...")
    return {
        "positives": _as_float_patches(np.stack(pos)),
        "negatives": _as_float_patches(np.concatenate(neg)) if neg else torch.zeros(0, 1, patch_size, patch_size),
        "boxes": torch.as_tensor(np.stack(boxes_all), dtype=torch.float32),
        "mining_frames": mf,
        "mining_boxes": mb,
    }


def bird_hard_negatives(videos: Sequence[str], videos_dir: str | Path, labels_dir: str | Path, *, per_video: int = 16,
                        patch_size: int = 40, object_fraction: float = 0.7) -> Tensor:
    """Look-alike crops (:func:`synthaug.data.negatives.hard_negatives`) of negative-class videos, one video in memory at a time."""
    from synthaug.data.negatives import hard_negatives
    from synthaug.data.video import read_video_with_labels

    out = []
    for stem in videos:
        path = _find_video(Path(videos_dir), stem)
        if path is None:
            raise ValueError(f"no video file for {stem!r} in {videos_dir}")
        frames, labels, _ = read_video_with_labels(path, Path(labels_dir) / f"{stem}.json")
        p, _ = hard_negatives(frames, labels.boxes, per_video, patch_size=patch_size, object_fraction=object_fraction)
        out.append(p)
    if not out:
        return torch.zeros(0, 1, patch_size, patch_size)
    return _as_float_patches(np.concatenate(out))


# =========================================================================== videos -> detector
@dataclass
class VideoSet:
    """The labelled videos of a folder pair: stem -> class, and the files.

    Attributes:
        videos_dir, labels_dir: the folders.
        classes: stem -> class name (from the label files), for stems with a video file.
        missing_video: label files without a video file (not used).
    """

    videos_dir: Path
    labels_dir: Path
    classes: dict[str, str]
    missing_video: list[str] = field(default_factory=list)


def discover_videos(videos_dir: str | Path, labels_dir: str | Path) -> VideoSet:
    """Every ``labels/<stem>.json`` with a ``videos/<stem>.<ext>`` (any numbering), and its class.

    Raises:
        TrainingInputError: a folder is missing (``--videos`` / ``--labels``) or holds no label file.
    """
    videos_dir, labels_dir = Path(videos_dir), Path(labels_dir)
    if not videos_dir.is_dir():
        raise TrainingInputError("--videos", f"folder not found: {videos_dir}")
    if not labels_dir.is_dir():
        raise TrainingInputError("--labels", f"folder not found: {labels_dir}")
    classes: dict[str, str] = {}
    missing: list[str] = []
    for f in sorted(labels_dir.glob("*.json")):
        try:
            doc = json.loads(f.read_text())
        except (OSError, json.JSONDecodeError) as e:
            raise TrainingInputError("--labels", f"label file {f} is not readable JSON ({e})") from None
        cls = doc.get("class") if isinstance(doc, dict) else None
        if not isinstance(cls, str) or not isinstance(doc.get("boxes"), list):
            continue  # not a label file of the shared format (e.g. a split or report file)
        if _find_video(videos_dir, f.stem) is None:
            missing.append(f.stem)
            continue
        classes[f.stem] = cls
    if not classes:
        raise TrainingInputError("--labels", f"no label file of the shared format with a video in --videos {videos_dir} "
                                             f"(label files: {labels_dir})")
    return VideoSet(videos_dir, labels_dir, classes, missing)


def split_by_video(
    vs: VideoSet,
    class_name: str,
    *,
    split: str | Path | None = None,
    seed: int = 0,
    val_fraction: float = 0.2,
    block: int = 1,
    negative_classes: Sequence[str] = ("bird",),
) -> dict[str, Any]:
    """Training / validation videos of a class and the training videos of the negative classes.

    With ``split`` (a ``synthaug.video_split`` file) its ``train`` / ``val`` lists (and
    ``hard_negatives.train``) are used, restricted to the videos present; without it the
    videos are split by video with :func:`synthaug.data.splits.make_video_split`
    (fractions ``1 - val_fraction`` / ``val_fraction`` / 0, per class, blocks of ``block``
    consecutive numbers, shuffled by ``seed``): deterministic given the folder and ``seed``.

    Returns:
        ``{"source": "file" | "auto", "train", "val", "negative_train", "negative_val", ...}`` (sorted stems).

    Raises:
        TrainingInputError: no video of the class (``--class``), a bad split file (``--split``),
            no training video of the class.
    """
    from synthaug.data.splits import load_split, make_video_split

    present = {s for s, c in vs.classes.items() if c == class_name}
    if not present:
        found = sorted(set(vs.classes.values()))
        raise TrainingInputError("--class", f"no video of class {class_name!r} in --labels {vs.labels_dir} (classes found: {found})")
    neg_present = {s for s, c in vs.classes.items() if c in negative_classes and c != class_name}
    if split is not None:
        try:
            sp = load_split(split)
        except (ValueError, FileNotFoundError) as e:
            raise TrainingInputError("--split", str(e)) from None
        listed = set(sp.classes) | {v for s in sp.videos.values() for v in s} | {v for s in sp.hard_negatives.values() for v in s}
        out = {"source": "file", "file": str(split),
               "train": sorted(v for v in sp.videos.get("train", []) if v in present),
               "val": sorted(v for v in sp.videos.get("val", []) if v in present),
               "negative_train": sorted(v for v in sp.hard_negatives.get("train", []) + sp.videos.get("train", []) if v in neg_present),
               "negative_val": sorted(v for v in sp.hard_negatives.get("val", []) + sp.videos.get("val", []) if v in neg_present),
               "unlisted": sorted((present | neg_present) - listed),
               "listed_not_in_folder": len({v for v, c in sp.classes.items() if c == class_name} - present)}
    else:
        if not 0 <= val_fraction < 1:
            raise TrainingInputError("--val-fraction", f"must be in [0, 1), got {val_fraction}")
        classes = {s: vs.classes[s] for s in sorted(present | neg_present)}
        sp = make_video_split(classes, fractions={"train": 1 - val_fraction, "val": val_fraction, "test": 0.0}, seed=seed,
                              block=block, hard_negative_classes=tuple(c for c in negative_classes if c != class_name))
        out = {"source": "auto", "seed": seed, "fractions": {"train": 1 - val_fraction, "val": val_fraction}, "block": block,
               "rule": "synthaug.data.splits.make_video_split per class (by video, seeded shuffle of blocks of consecutive numbers)",
               "train": sorted(v for v in sp.videos["train"] if v in present),
               "val": sorted(v for v in sp.videos["val"] if v in present),
               "negative_train": sorted(sp.hard_negatives["train"]), "negative_val": sorted(sp.hard_negatives["val"])}
    if not out["train"]:
        raise TrainingInputError("--split" if split is not None else "--class",
                                 f"no training video of class {class_name!r}" + (f" in the split file {split}" if split else ""))
    out["class"] = class_name
    out["negative_classes"] = list(negative_classes)
    return out


def _labelled_frames(labels_dir: Path, stems: Sequence[str]) -> int:
    from synthaug.data.video import read_labels

    return sum(sum(1 for b in read_labels(labels_dir / f"{s}.json").boxes if b is not None) for s in stems)


def _seed_set_by_ingest(vs: VideoSet, split: Mapping[str, Any], n: int, work: Path, *, ingest_seed: int, workers: int,
                        log: Callable[[str], None], negative_classes: Sequence[str]) -> Any:
    """Seed set of ``n`` seeds drawn from the training videos exactly as ``synthaug ingest`` draws them."""
    from synthaug.data.ingest import IngestConfig, ingest_videos
    from synthaug.data.seedset import SeedSet
    from synthaug.data.splits import VideoSplit

    cls = split["class"]
    train = list(split["train"])
    per_video = max(IngestConfig().seeds_per_video, math.ceil(n / len(train)))
    cfg = IngestConfig(seeds_per_video=per_video, seed=ingest_seed, hard_negative_classes=tuple(negative_classes))
    only_train = VideoSplit({"train": train, "val": [], "test": []},
                            {"train": list(split["negative_train"]), "val": [], "test": []},
                            {s: vs.classes[s] for s in train + list(split["negative_train"])})
    t0 = time.perf_counter()
    report = ingest_videos(vs.videos_dir, vs.labels_dir, work, split=only_train, splits=("train",), cfg=cfg, seed_counts=[n],
                           workers=workers, progress=False)
    if report["failed"]:
        log(f"ingest: {len(report['failed'])} video(s) failed: {report['failed']}")
    log(f"ingest: {report['processed']} videos processed, {report['skipped_current']} reused ({time.perf_counter() - t0:.0f}s)")
    path = work / "seedsets" / f"{cls}_{n}"
    if not (path / "seedset.json").is_file():
        raise TrainingInputError("--seed-counts", f"ingest drew no seed of class {cls!r} from the training videos ({report['failed']})")
    ss = SeedSet.load(path)
    if len(ss) < n:
        raise TrainingInputError("--seed-counts", f"{n} seeds asked but the training videos give only {len(ss)} usable seed frames "
                                                  f"(box fully inside the frame, longest side >= {cfg.min_box_side:g} px, "
                                                  f"{per_video} candidates per video); ask for at most {len(ss)} or use --all-frames")
    return ss


def train_from_videos(
    kind: str,
    class_name: str,
    videos_dir: str | Path,
    labels_dir: str | Path,
    *,
    out: str | Path | None = None,
    split: str | Path | None = None,
    seed: int = 0,
    seed_count: int | None = 100,
    all_frames: bool = False,
    frame_step: int = 1,
    seedset: str | Path | None = None,
    params: str | Path | Callable[[Path], str | Path] | None = None,
    mesh: str | None = None,
    synthetic_ratio: float = 0.0,
    perturb_copies: int = 0,
    pose_sampling: str = "uniform",
    copy_paste_ratio: float = 0.0,
    options: TrainOptions = TrainOptions(),
    work_dir: str | Path | None = None,
    ingest_seed: int = 0,
    ingest_workers: int = 2,
    negative_classes: Sequence[str] = ("bird",),
    val_fraction: float = 0.2,
    split_block: int = 1,
    extra_negatives: int = 3000,
    log: Callable[[str], None] | None = None,
    command: Any = None,
) -> tuple[Any, dict[str, Any]]:
    """Videos + labels (+ a fit) -> a trained detector: what ``synthaug train`` runs.

    Steps: :func:`discover_videos` -> :func:`split_by_video` -> positives (``seed_count``
    seeds drawn by ``synthaug ingest``'s code into ``work_dir`` — its shards are reused by
    a rerun —, an existing ``seedset``, or with ``all_frames`` every ``frame_step``-th
    labelled frame of the training videos) + ``synthetic_ratio`` synthetic patches per real
    seed from ``params`` -> negatives (the seed set's + ``extra_negatives`` object-free crops
    of the seed frames, or, with ``all_frames``, 60 crops per training video + look-alike
    crops of the negative-class videos) -> :func:`train_with_mining` over every
    ``options.mining_stride``-th frame of all training videos (+ negative-class videos),
    stopped on the validation videos -> ``out`` (:func:`~synthaug.detectors.base.save_detector`)
    and ``out`` with suffix ``.json`` (the metadata returned here).

    Args:
        kind: ``"hog"``, ``"adaboost"`` or ``"cnn"``.
        class_name: the class to detect (the label files' ``class``).
        videos_dir, labels_dir: the shared-format folders (any stems, any numbering).
        out: checkpoint to write (None: nothing written).
        split: a ``synthaug.video_split`` file; None: split by video from ``seed``.
        seed: training seed (initialisation, negatives, the automatic split).
        seed_count: real seeds (ignored with ``all_frames`` or ``seedset``).
        all_frames: every labelled frame of the training videos (every ``frame_step``-th).
        frame_step: see ``all_frames``.
        seedset: use this seed set (``synthaug ingest`` output) instead of ingesting.
        params: ``synthaug fit`` output made on the seed set (one row per seed), or a callable
            given the seed set's folder once it exists that returns that file (e.g. fits it).
        mesh: mesh of the synthetic object (default: the fit's, else the built-in quadcopter).
        synthetic_ratio: synthetic patches per real seed (needs ``params``).
        pose_sampling: poses of the synthetic positives: ``"uniform"`` (the paper) or ``"fitted"``
            (around each seed's fitted pose).
        perturb_copies: perturbed copies of every real positive added to the positives (the
            paper's Table 1 baseline, :func:`~synthaug.effects.perturb.perturb_patches`).
        copy_paste_ratio: copy-paste patches per real seed (needs ``params``: the seeds' objects cut
            out with their fitted silhouettes and pasted on other seeds' backgrounds,
            :func:`~synthaug.data.copypaste.copy_paste_positives`; a user's baseline).
        options: budgets (:class:`TrainOptions`).
        work_dir: ingest output folder (default: ``<out>.work``; a temporary folder when ``out`` is None).
        ingest_seed: ``synthaug ingest --seed`` of the seed draw (0: the same seed set as a
            default ``synthaug ingest`` of the training videos).
        ingest_workers: ingest worker processes.
        negative_classes: classes whose videos are free of ``class_name`` (mined whole).
        val_fraction, split_block: the automatic split.
        extra_negatives: object-free crops of the seed frames added to the seed set's negatives.
        log: progress printer.
        command: the command line (or its parsed options), recorded in the metadata.

    Returns:
        ``(detector, metadata)``.

    Raises:
        TrainingInputError: an input that cannot be used; ``.option`` names the option.
    """
    import synthaug
    from synthaug.detectors.base import box_in_window_from_boxes, save_detector

    say = log or (lambda m: None)
    if kind not in DETECTORS:
        raise TrainingInputError("--detector", f"unknown detector {kind!r}; choose from {list(DETECTORS)}")
    if frame_step < 1:
        raise TrainingInputError("--frame-step", f"must be >= 1, got {frame_step}")
    if synthetic_ratio < 0:
        raise TrainingInputError("--synthetic-ratio", f"must be >= 0, got {synthetic_ratio}")
    if synthetic_ratio > 0 and params is None:
        raise TrainingInputError("--synthetic-ratio", "synthetic positives need a fit: give --params FIT.json")
    if not all_frames and seedset is None and (seed_count is None or seed_count < 1):
        raise TrainingInputError("--seed-counts", f"must be >= 1, got {seed_count}")
    if perturb_copies < 0:
        raise TrainingInputError("--perturb-copies", f"must be >= 0, got {perturb_copies}")
    if copy_paste_ratio < 0:
        raise TrainingInputError("--copy-paste-ratio", f"must be >= 0, got {copy_paste_ratio}")
    if copy_paste_ratio > 0 and params is None:
        raise TrainingInputError("--copy-paste-ratio", "copy-paste cuts objects with their fitted silhouettes: give "
                                                       "--params FIT.json")
    if params is not None and not callable(params) and not Path(params).is_file():
        raise TrainingInputError("--params", f"file not found: {params}")
    if seedset is not None and not (Path(seedset) / "seedset.json").is_file():
        raise TrainingInputError("--seed-set", f"not a seed set folder (no seedset.json): {seedset}")
    t_start = time.perf_counter()
    vs = discover_videos(videos_dir, labels_dir)
    sp = split_by_video(vs, class_name, split=split, seed=seed, val_fraction=val_fraction, block=split_block,
                        negative_classes=negative_classes)
    say(f"{class_name}: {len(sp['train'])} training videos, {len(sp['val'])} validation videos, "
        f"{len(sp['negative_train'])} negative-class training videos ({sp['source']} split)")
    if params is not None and all_frames and seedset is None:
        raise TrainingInputError("--params", "synthetic positives need the seed set the fit was made on: use --seed-counts N "
                                             "(or --seed-set DIR), not --all-frames")
    if not all_frames and seedset is None:
        available = _labelled_frames(vs.labels_dir, sp["train"])
        if seed_count > available:  # type: ignore[operator]
            raise TrainingInputError("--seed-counts", f"{seed_count} seeds asked but the {len(sp['train'])} training videos of "
                                                      f"{class_name!r} have only {available} labelled frames")

    # ---------------------------------------------------------------- positives and negatives
    t0 = time.perf_counter()
    ss = None
    positives_info: dict[str, Any]
    hog_frames: list[Tensor] = []
    hog_boxes: list[Tensor] = []
    if seedset is not None or not all_frames:
        from synthaug.data.seedset import SeedSet

        if seedset is not None:
            ss = SeedSet.load(seedset)
            positives_info = {"mode": "seedset", "seedset": str(seedset), "count": len(ss)}
        else:
            if work_dir is None:
                if out is None:
                    import tempfile

                    work_dir = Path(tempfile.mkdtemp(prefix="synthaug_train_"))
                else:
                    work_dir = Path(str(out) + ".work")
            ss = _seed_set_by_ingest(vs, sp, int(seed_count), Path(work_dir), ingest_seed=ingest_seed,  # type: ignore[arg-type]
                                     workers=ingest_workers, log=say, negative_classes=negative_classes)
            positives_info = {"mode": "seeds", "count": len(ss), "seedset": str(ss.path), "ingest_seed": ingest_seed,
                              "drawn_as": "synthaug ingest (select_spread over the training videos' candidates)"}
        pos = real_positives(ss)
        neg = negative_pool(ss, extra_negatives, seed=seed)
        hog_frames, hog_boxes = mining_frames(ss, options.hog_mining_frames)
        box_in_window = box_in_window_from_boxes(torch.as_tensor(np.asarray(ss.boxes), dtype=torch.float32),
                                                 window=int(ss.patch_size), object_fraction=float(ss.object_fraction))
    else:
        d = frames_training_set(sp["train"], vs.videos_dir, vs.labels_dir, frame_step=frame_step, seed=seed)
        birds = bird_hard_negatives(sp["negative_train"], vs.videos_dir, vs.labels_dir)
        pos, neg = d["positives"], torch.cat([d["negatives"], birds])
        hog_frames, hog_boxes = d["mining_frames"], d["mining_boxes"]
        box_in_window = box_in_window_from_boxes(d["boxes"])
        positives_info = {"mode": "all_frames", "frame_step": frame_step, "count": int(pos.shape[0])}
    perturb_info = None
    if perturb_copies:
        from synthaug.effects.perturb import with_perturbed_copies

        n_real = pos.shape[0]
        pos = with_perturbed_copies(pos, perturb_copies, seed=seed + 3)
        perturb_info = {"copies": perturb_copies, "count": int(pos.shape[0] - n_real)}
        say(f"perturbed: {perturb_info['count']} copies of the {n_real} real positives")
    synthetic_info = None
    if callable(params):  # ss exists: a fit without a seed set was refused above
        params = params(Path(ss.path))  # type: ignore[union-attr]
    if params is not None:
        from synthaug.params import CaptureParams

        try:
            theta, _, fit_meta = CaptureParams.load_with_extra(params)
        except (ValueError, FileNotFoundError) as e:
            raise TrainingInputError("--params", str(e)) from None
        if theta.batch_size != len(ss):  # type: ignore[arg-type]
            raise TrainingInputError("--params", f"{params} has {theta.batch_size} rows but the seed set has {len(ss)} seeds "  # type: ignore[arg-type]
                                                 f"({positives_info.get('seedset')}): a fit holds one row per seed of the seed set "
                                                 f"it was made on")
        mesh = mesh or fit_meta.get("mesh") or "quadcopter"
        n_syn = int(round(synthetic_ratio * len(ss)))  # type: ignore[arg-type]
        if n_syn:
            ts = time.perf_counter()
            syn = synthetic_positives(ss, mesh, params, n_syn, seed=seed + 2, pose_sampling=pose_sampling)
            pos = torch.cat([pos, syn])
            say(f"synthetic: {n_syn} patches from {params} ({time.perf_counter() - ts:.0f}s)")
        synthetic_info = {"params": str(params), "mesh": str(mesh), "ratio": synthetic_ratio, "count": n_syn,
                          "pose_sampling": pose_sampling}
        n_cp = int(round(copy_paste_ratio * len(ss)))  # type: ignore[arg-type]
        if n_cp:
            from synthaug.data.copypaste import copy_paste_positives

            ts = time.perf_counter()
            pos = torch.cat([pos, copy_paste_positives(ss, params, n_cp, seed=seed + 4, mesh=mesh)])
            say(f"copy-paste: {n_cp} patches cut with the silhouettes of {params} ({time.perf_counter() - ts:.0f}s)")
            synthetic_info["copy_paste"] = {"ratio": copy_paste_ratio, "count": n_cp}
    t_data = time.perf_counter() - t0
    say(f"training set: {pos.shape[0]} positives, {neg.shape[0]} negatives ({t_data:.0f}s)")

    # ---------------------------------------------------------------- training with mining
    mine_src = VideoFrames(vs.videos_dir, vs.labels_dir, positive=sp["train"], negative=sp["negative_train"],
                           stride=options.mining_stride)
    val_src = VideoFrames(vs.videos_dir, vs.labels_dir, positive=sp["val"], stride=options.val_stride, null_frames=True) \
        if sp["val"] else None
    box_info = None
    regressor = None
    if options.box_regression and sp["train"]:
        from synthaug.detectors.boxes import BoxRegressor

        t0 = time.perf_counter()
        reg_src = VideoFrames(vs.videos_dir, vs.labels_dir, positive=sp["train"], stride=options.box_stride)
        regressor = BoxRegressor.fit(reg_src, aspect=float(box_in_window[2]) / float(box_in_window[3]), seed=seed)
        box_info = dict(regressor.meta or {}, ridge=regressor.ridge, seconds=round(time.perf_counter() - t0, 1))
        say(f"box regression: {box_info['samples']} jittered boxes of {box_info['videos']} training videos, ridge "
            f"{regressor.ridge:g} by grouped CV ({box_info['seconds']:.0f}s)")
    t0 = time.perf_counter()
    res = train_with_mining(kind, pos, neg, seed, box_in_window=box_in_window, mining_frames=hog_frames, mining_boxes=hog_boxes,
                            options=options, mining_source=mine_src if options.mining_rounds else None,
                            val_frames=val_src, log=say, box_regressor=regressor)
    t_train = time.perf_counter() - t0
    meta = {
        "format": METADATA_FORMAT, "version": METADATA_VERSION, "synthaug_version": synthaug.__version__,
        "detector": kind, "class": class_name, "seed": seed,
        "videos_dir": str(Path(videos_dir).resolve()), "labels_dir": str(Path(labels_dir).resolve()),
        "split": sp, "positives": positives_info, "synthetic": synthetic_info, "perturbed": perturb_info,
        "negatives": {"initial": int(neg.shape[0]), "final": int(res.negatives.shape[0]),
                      "initial_source": ("seed set negatives + object-free crops of the seed frames" if ss is not None
                                         else "object-free crops of the training videos + look-alike crops of negative-class videos")},
        "box_in_window": [float(v) for v in box_in_window],
        "box_regression": box_info,
        "options": asdict(options), "mining": res.log,
        "seconds": {"data": round(t_data, 1), "training": round(t_train, 1), "total": round(time.perf_counter() - t_start, 1)},
        "command": command,
        "checkpoint": None if out is None else str(out),
    }
    if not sp["val"]:
        meta["warnings"] = ["no validation video: the mining ran every round without the stopping rule"]
    if out is not None:
        from synthaug.params import atomic_write_text

        out = Path(out)
        save_detector(res.detector, out)
        atomic_write_text(out.with_suffix(".json"), json.dumps(meta, indent=1, default=str) + "\n")
        say(f"wrote {out} and {out.with_suffix('.json')}")
    return res.detector, meta
