"""``synthaug detect``: a detector checkpoint + a video (or a folder of images) -> detections JSON.

Usage::

    synthaug detect --checkpoint runs/hog.pt --video V_DRONE_001.mp4 --out dets.json --frame-stride 5

The output file::

    {"format": "synthaug.detections", "version": 1,
     "video": "V_DRONE_001.mp4", "input": "video", "source": "/path/to/V_DRONE_001.mp4",
     "detector": "hog", "checkpoint": "runs/hog.pt",
     "frame_stride": 5, "n_frames": 300, "box_format": "xywh_score_pixels",
     "scales": [...], "nms_iou": 0.3, "score_threshold": null, "max_detections": 10,
     "detections": [[[x, y, w, h, score], ...], null, null, null, null, [...], ...]}

``detections`` holds one entry per frame of the source: a list (possibly
empty) of ``[x, y, w, h, score]`` boxes in pixels of the original frame, best
first, for every processed frame, and ``null`` for frames skipped by the frame
stride or after ``--max-frames`` — ``synthaug evaluate`` leaves those out.
Frames are converted to grayscale float in [0, 1] (OpenCV's BGR -> gray).
``input`` is ``"video"`` (``video`` names the video file) or ``"images"``
(``video`` names the folder of frames); ``synthaug evaluate`` refuses to score
a video's detections against another video's labels.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path
from typing import Iterator

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # torch is imported when a command runs, not by `synthaug --help`
    from synthaug.detectors.base import PatchDetector

FORMAT_NAME = "synthaug.detections"
FORMAT_VERSION = 1
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from synthaug._checks import add_option

    src = parser.add_mutually_exclusive_group(required=True)
    src.add_argument("--video", type=Path, help="video file readable by OpenCV")
    src.add_argument("--images", type=Path, help="folder of frames (png/jpg/...), processed in sorted name order")
    parser.add_argument("--checkpoint", type=Path, required=True, help="detector file written by save_detector")
    parser.add_argument("--out", type=Path, required=True, help="detections JSON to write")
    add_option(parser, "--frame-stride", aliases=["--stride"], type=int, default=1,
               help="process every K-th frame (others are null)")
    parser.add_argument("--max-frames", type=int, default=None, help="stop after this many source frames")
    parser.add_argument(
        "--scales", type=float, nargs="+", default=None, help="image pyramid resize factors (default: synthaug.detectors.sliding.DEFAULT_SCALES)"
    )
    parser.add_argument("--score-threshold", type=float, default=None, help="drop windows scoring below (default: keep the best)")
    parser.add_argument("--nms-iou", type=float, default=0.3, help="NMS IoU threshold")
    parser.add_argument("--max-detections", type=int, default=10, help="boxes kept per frame")
    parser.add_argument(
        "--threads",
        type=int,
        default=1,
        help="torch intra-op threads (default 1: per-frame ops are small, and extra threads slow down badly on a busy CPU; run one process per video to use more cores)",
    )
    add_option(parser, "--no-progress", aliases=["--quiet"], action="store_true", help="no progress line on stderr")


def iter_video_frames(path: Path, *, frame_stride: int = 1, max_frames: int | None = None) -> Iterator[tuple[int, np.ndarray | None]]:
    """Yield ``(index, gray float32 frame in [0, 1])`` for processed frames, ``(index, None)`` for skipped ones.

    The frames are :func:`synthaug.data.video.iter_frames`' (skipped frames are only grabbed).

    Raises:
        ValueError: if OpenCV cannot open the file.
    """
    from synthaug.data.video import iter_frames

    for index, frame in iter_frames(path, wanted=lambda i: i % frame_stride == 0, stop=max_frames):
        yield index, None if frame is None else _to_gray_float(frame)


def iter_image_frames(folder: Path, *, frame_stride: int = 1, max_frames: int | None = None) -> Iterator[tuple[int, np.ndarray | None]]:
    """Like :func:`iter_video_frames` over the images of a folder in sorted name order."""
    import cv2

    if not folder.is_dir():
        raise ValueError(f"--images must be a folder, got {folder}")
    files = sorted(p for p in folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
    if not files:
        raise ValueError(f"no image ({', '.join(IMAGE_SUFFIXES)}) in {folder}")
    for index, file in enumerate(files[:max_frames]):
        if index % frame_stride:
            yield index, None
            continue
        frame = cv2.imread(str(file), cv2.IMREAD_UNCHANGED)
        if frame is None:
            raise ValueError(f"cannot read image {file}")
        yield index, _to_gray_float(frame)


def _to_gray_float(frame: np.ndarray) -> np.ndarray:
    import cv2

    if frame.ndim == 3 and frame.shape[2] == 4:
        frame = cv2.cvtColor(frame, cv2.COLOR_BGRA2GRAY)
    elif frame.ndim == 3:
        frame = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    scale = 65535.0 if frame.dtype == np.uint16 else 255.0 if frame.dtype == np.uint8 else 1.0
    return frame.astype(np.float32) / scale


def detect_frames(
    detector: "PatchDetector",
    frames: Iterator[tuple[int, np.ndarray | None]],
    *,
    scales: list[float],
    score_threshold: float | None,
    nms_iou: float,
    max_detections: int,
    progress: bool = False,
) -> tuple[list[list[list[float]] | None], dict[str, float]]:
    """Run :func:`detect_multiscale` over frames; returns (per-frame detections or None, timing)."""
    import torch

    from synthaug.detectors.sliding import detect_multiscale

    out: list[list[list[float]] | None] = []
    processed = 0
    busy = 0.0
    for index, frame in frames:
        if frame is None:
            out.append(None)
            continue
        t0 = time.perf_counter()
        dets = detect_multiscale(
            detector,
            torch.from_numpy(frame),
            scales=scales,
            nms_iou=nms_iou,
            score_threshold=-math.inf if score_threshold is None else score_threshold,
            max_detections=max_detections,
        )
        busy += time.perf_counter() - t0
        processed += 1
        out.append([[round(float(v), 3) for v in row[:4]] + [float(row[4])] for row in dets])
        if progress and processed % 10 == 0:
            print(f"\rframe {index + 1}: {processed / busy:.1f} frames/s", end="", file=sys.stderr, flush=True)
    if progress and processed:
        print(file=sys.stderr)
    return out, {"processed_frames": processed, "seconds": busy, "frames_per_second": processed / busy if busy else 0.0}


def main(args: argparse.Namespace) -> int:
    try:
        return _run(args)
    except (ValueError, FileNotFoundError) as e:
        print(f"synthaug detect: error: {e}", file=sys.stderr)
        return 2


def _run(args: argparse.Namespace) -> int:
    import torch

    from synthaug._checks import check_output_file
    from synthaug.detectors.base import load_detector
    from synthaug.detectors.sliding import DEFAULT_SCALES

    if args.scales is None:
        args.scales = list(DEFAULT_SCALES)

    if args.frame_stride < 1:
        raise ValueError(f"--frame-stride must be >= 1, got {args.frame_stride}")
    if args.max_frames is not None and args.max_frames < 0:
        raise ValueError(f"--max-frames must be >= 0, got {args.max_frames}")
    if args.threads < 1:
        raise ValueError(f"--threads must be >= 1, got {args.threads}")
    if not (math.isfinite(args.nms_iou) and 0.0 <= args.nms_iou <= 1.0):
        raise ValueError(f"--nms-iou must be in [0, 1], got {args.nms_iou}")
    if not args.scales or not all(math.isfinite(s) and s > 0 for s in args.scales):
        raise ValueError(f"--scales must be positive numbers, got {args.scales}")
    if args.max_detections < 1:
        raise ValueError(f"--max-detections must be >= 1, got {args.max_detections}")
    if args.score_threshold is not None and not math.isfinite(args.score_threshold):
        raise ValueError(f"--score-threshold must be a finite number, got {args.score_threshold}")
    if args.video is not None and not args.video.is_file():
        raise FileNotFoundError(f"--video: video not found: {args.video}" if not args.video.is_dir()
                                else f"--video: {args.video} is a directory (use --images for a folder of frames)")
    if args.images is not None and not args.images.is_dir():
        raise FileNotFoundError(f"--images: folder not found: {args.images}" if not args.images.exists()
                                else f"--images: {args.images} is a file (use --video for a video file)")
    check_output_file(args.out)
    torch.set_num_threads(args.threads)
    detector = load_detector(args.checkpoint)
    if args.video is not None:
        source = args.video
        frames = iter_video_frames(args.video, frame_stride=args.frame_stride, max_frames=args.max_frames)
    else:
        source = args.images
        frames = iter_image_frames(args.images, frame_stride=args.frame_stride, max_frames=args.max_frames)
    detections, timing = detect_frames(
        detector,
        frames,
        scales=list(args.scales),
        score_threshold=args.score_threshold,
        nms_iou=args.nms_iou,
        max_detections=args.max_detections,
        progress=not args.no_progress,
    )
    payload = {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "video": source.name,
        "input": "video" if args.video is not None else "images",
        "source": str(source.resolve()),
        "detector": detector.kind,
        "checkpoint": str(args.checkpoint),
        "frame_stride": args.frame_stride,
        "n_frames": len(detections),
        "box_format": "xywh_score_pixels",
        "scales": list(args.scales),
        "nms_iou": args.nms_iou,
        "score_threshold": args.score_threshold,
        "max_detections": args.max_detections,
        "detections": detections,
    }
    from synthaug.params import atomic_write_text

    args.out.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(args.out, json.dumps(payload, separators=(",", ":")))
    summary = {"out": str(args.out), "video": source.name, "n_frames": len(detections), **timing}
    print(json.dumps(summary))
    return 0
