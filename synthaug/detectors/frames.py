"""Frames to mine hard negatives from and to validate on: one labelled frame at a time.

:class:`MiningFrame` is one grayscale frame with its labelled boxes (masked when
mining, matched when validating); :class:`VideoFrames` streams every k-th frame of
some labelled videos in the shared label format, video by video, so memory holds
one frame whatever the number of videos.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator, NamedTuple, Sequence

import numpy as np
import torch
from torch import Tensor

__all__ = ["MiningFrame", "VideoFrames", "RescaledFrames", "frame_scale"]


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
        from synthaug.data.video import clip_boxes, find_video, iter_frames, read_labels, video_frame_size

        path = find_video(self.videos_dir, stem)
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


def frame_scale(scale_range: Sequence[float], seed: int, video: str, index: int) -> float:
    """The resize factor of one mining frame: log-uniform in ``scale_range``, drawn from a generator seeded by
    ``(seed, video, index)`` only, so a frame gets the same factor in every mining round and in any order.

    Example:
        >>> f = frame_scale((0.75, 2.0), 0, "V_DRONE_001", 30)
        >>> 0.75 <= f <= 2.0 and f == frame_scale((0.75, 2.0), 0, "V_DRONE_001", 30)
        True
        >>> frame_scale((1.0, 1.0), 3, "V", 0)
        1.0
    """
    lo, hi = (float(v) for v in scale_range)
    if lo == hi:
        return lo
    key = zlib.crc32(f"{int(seed)}:{video}:{int(index)}".encode())
    u = float(torch.rand((), generator=torch.Generator().manual_seed(key), dtype=torch.float64))
    return float(lo * (hi / lo) ** u)


@dataclass
class RescaledFrames:
    """Mining frames resized by a per-frame factor (scale jitter of the hard-negative mining), boxes with them.

    Each frame of ``source`` is resized by :func:`frame_scale` ``(scale_range, seed, video, index)`` (bilinear,
    antialiased when shrinking: :func:`~synthaug.detectors.sliding.resize_image`, the pyramid's resize) and its
    labelled boxes are scaled by the true factors of the resized size. The detector's pyramid then sees the
    clutter of a frame at magnifications its native frames never reach: an upsampled frame holds smoother,
    blurrier structures than any native level (``TrainOptions.mining_frame_scale``).

    Args:
        source: re-iterable :class:`MiningFrame` items (e.g. :class:`VideoFrames`).
        scale_range: ``(low, high)`` factors, ``0 < low <= high``.
        seed: the training seed (the factors depend on it, on the video stem and on the frame index only).

    Example:
        >>> frames = [MiningFrame(np.zeros((40, 60), np.uint8), np.array([[10., 10., 8., 6.]]), "V", 0)]
        >>> out = list(RescaledFrames(frames, (2.0, 2.0)))
        >>> tuple(out[0].image.shape), out[0].boxes.tolist(), out[0].video, out[0].index
        ((80, 120), [[20.0, 20.0, 16.0, 12.0]], 'V', 0)
    """

    source: Any
    scale_range: tuple[float, float]
    seed: int = 0

    def __post_init__(self) -> None:
        self.scale_range = check_scale_range(self.scale_range)

    @property
    def stride(self) -> Any:  # the mining log reads the source's frame stride
        return getattr(self.source, "stride", None)

    def __iter__(self) -> Iterator[MiningFrame]:
        from synthaug.detectors.sliding import resize_image

        for j, raw in enumerate(self.source):
            item = _as_item(raw)
            index = item.index if item.index >= 0 else j
            f = frame_scale(self.scale_range, self.seed, item.video or "_", index)
            image = _image_tensor(item.image)
            if f == 1.0:
                yield item._replace(image=image)
                continue
            out = resize_image(image[None, None], f)[0, 0]
            boxes = item.boxes
            if boxes is not None:
                sx, sy = out.shape[-1] / image.shape[-1], out.shape[-2] / image.shape[-2]
                boxes = np.asarray(boxes, np.float64).reshape(-1, 4) * np.array([sx, sy, sx, sy])
            yield MiningFrame(out, boxes, item.video, item.index)


def check_scale_range(scale_range: Any) -> tuple[float, float]:
    """``(low, high)`` as floats, refusing anything but two finite factors with ``0 < low <= high``."""
    try:
        lo, hi = (float(v) for v in scale_range)
    except (TypeError, ValueError):
        raise ValueError(f"a frame scale range must be two numbers (low, high), got {scale_range!r}") from None
    if not (0 < lo <= hi and math.isfinite(hi)):
        raise ValueError(f"a frame scale range must have 0 < low <= high (finite), got {scale_range!r}")
    return lo, hi


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
