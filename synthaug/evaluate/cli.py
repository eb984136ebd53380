"""``synthaug evaluate``: detections JSON + label files -> precision–recall PNG and AP.

Usage::

    synthaug evaluate --detections dets/*.json --labels /data/halmstad/labels --out eval/

Each detections file (written by ``synthaug detect``; a bare JSON list of
per-frame lists is accepted too) is paired with its label file: the label file
whose ``"video"`` field, or whose stem, equals the detections' video stem.
``--labels`` takes a folder of label files, or label files. With exactly one
detections file and one label file they are paired whatever their names, unless
both name a video and the videos differ (an error: another video's labels).
Label boxes must be finite (an error names the file and frame); a box of zero
or negative width or height is left out of the ground truth, with a warning.

Label format (shared halmstad)::

    {"video": "V_DRONE_001.mp4", "class": "drone", "box_format": "xywh_pixels",
     "boxes": [[x, y, w, h] | null, ...]}     # one entry per frame; null = no object

Only the first ``min(#detection frames, #label frames)`` frames of a video
count; frames whose detections are ``null`` (not processed) are left out. All
videos are pooled into one precision–recall curve (one AP); per-video APs are
reported beside it. Writes ``OUT/pr.png`` and ``OUT/metrics.json`` and prints
the metrics JSON on stdout.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--detections", type=Path, nargs="+", required=True, help="detections JSON file(s) from `synthaug detect`")
    parser.add_argument("--labels", type=Path, nargs="+", required=True, help="label folder, or label JSON file(s)")
    parser.add_argument("--out", type=Path, required=True, help="output folder for pr.png and metrics.json")
    parser.add_argument("--iou", type=float, default=0.5, help="IoU of a correct detection (default 0.5)")
    parser.add_argument("--title", default="", help="title of the PR plot")
    parser.add_argument("--unlabelled-frames", choices=["score", "skip"], default="score",
                        help="a frame whose label is null: a frame with no object, every detection on it a false "
                             "positive (score, protocol halmstad_v1), or not annotated, not scored (skip, halmstad_v2)")


def load_labels(path: Path) -> tuple[str, list[np.ndarray | None]]:
    """Read one label file: ``(video name, per-frame (G, 4) boxes or None)``.

    The file is read by :func:`synthaug.data.video.read_labels` (the one reader of the shared
    halmstad format: a JSON object with ``class`` and a non-empty ``boxes`` list) and its boxes taken
    by :meth:`~synthaug.data.video.VideoLabels.ground_truth` (entries None, one ``[x, y, w, h]`` box or a
    list of boxes; boxes of zero or negative width or height left out with a :class:`UserWarning`).

    Raises:
        ValueError: naming the file, for a malformed file, a non-finite box or an unsupported ``box_format``.
    """
    from synthaug.data.video import read_labels

    labels = read_labels(path)
    return labels.video or Path(path).stem, labels.ground_truth()


def load_detections(path: Path) -> tuple[str, list[np.ndarray | None]]:
    """Read one detections file: ``(video name, per-frame (K, 5) arrays or None)``."""
    try:
        data: Any = json.loads(Path(path).read_text())
    except (OSError, json.JSONDecodeError) as e:
        raise ValueError(f"cannot read detections file {path}: {e}") from e
    if isinstance(data, dict):
        if "detections" not in data:
            raise ValueError(f"{path} is not a detections file (no 'detections' key)")
        video, per_frame = str(data.get("video", Path(path).stem)), data["detections"]
    elif isinstance(data, list):
        video, per_frame = Path(path).stem, data
    else:
        raise ValueError(f"{path} is not a detections file (got JSON {type(data).__name__})")
    frames: list[np.ndarray | None] = []
    for i, entry in enumerate(per_frame):
        if entry is None:
            frames.append(None)
            continue
        try:
            arr = np.asarray(entry, dtype=np.float64).reshape(-1, 5) if len(entry) else np.zeros((0, 5))
        except (ValueError, TypeError) as e:
            raise ValueError(f"{path}: frame {i} must be a list of [x, y, w, h, score], got {entry!r}") from e
        if not np.isfinite(arr[:, :4]).all():
            raise ValueError(f"{path}: frame {i} has non-finite box coordinates: {entry!r}")
        if (arr[:, 2:4] < 0).any() or np.isnan(arr[:, 4]).any():
            raise ValueError(f"{path}: frame {i} has a box of negative size or a NaN score: {entry!r}")
        frames.append(arr)
    return video, frames


def _from_images(path: Path) -> bool:
    """Whether a detections file was made from a folder of frames (its 'video' is the folder's name)."""
    try:
        data = json.loads(Path(path).read_text())
    except (OSError, json.JSONDecodeError):
        return False
    if not isinstance(data, dict):
        return True  # a bare list names no video
    if "input" in data:
        return data["input"] == "images"
    return not Path(str(data.get("video", ""))).suffix  # older files: a folder name has no extension


def _label_files(paths: list[Path]) -> list[Path]:
    files: list[Path] = []
    for p in paths:
        if p.is_dir():
            files.extend(sorted(p.glob("*.json")))
        elif p.is_file():
            files.append(p)
        else:
            raise ValueError(f"--labels: no such file or folder {p}")
    if not files:
        raise ValueError(f"--labels: no label JSON file in {[str(p) for p in paths]}")
    return files


def pair_files(detection_files: list[Path], label_paths: list[Path]) -> list[tuple[Path, Path]]:
    """Pair each detections file with its label file by video stem (see module docstring)."""
    labels = _label_files(label_paths)
    explicit_files = all(p.is_file() for p in label_paths)
    if len(detection_files) == 1 and len(labels) == 1 and explicit_files:
        # paired whatever their names, unless both name a video and the videos differ
        det, lab = detection_files[0], labels[0]
        if not _from_images(det):
            video, _ = load_detections(det)
            try:
                label_video = json.loads(lab.read_text()).get("video")
            except (OSError, json.JSONDecodeError, AttributeError):
                label_video = None
            if isinstance(label_video, str) and Path(label_video).stem != Path(video).stem:
                raise ValueError(f"{det} holds detections of video {video!r} but the label file {lab} is for "
                                 f"{label_video!r}; give the label file of the same video")
        return [(det, lab)]
    by_stem: dict[str, Path] = {}
    for f in labels:
        by_stem.setdefault(f.stem, f)
        try:
            video = json.loads(f.read_text()).get("video")
        except (OSError, json.JSONDecodeError, AttributeError):
            video = None
        if isinstance(video, str):
            by_stem.setdefault(Path(video).stem, f)
    pairs = []
    for d in detection_files:
        video, _ = load_detections(d)
        stem = Path(video).stem
        if stem not in by_stem:
            raise ValueError(f"no label file for video {video!r} of {d} among {len(labels)} label files")
        pairs.append((d, by_stem[stem]))
    return pairs


def evaluate_files(detection_files: list[Path], label_paths: list[Path], *, iou: float = 0.5,
                   skip_unlabelled: bool = False) -> tuple[Any, dict[str, Any]]:
    """Pool all videos into one PR curve; returns ``(PRResult, metrics dict with per-video APs)``.

    ``skip_unlabelled``: frames without a labelled box are not scored (their detections are dropped, as for a frame
    not processed): protocol v2's ``unlabelled_frames="skip"``.
    """
    from synthaug.evaluate.ap import evaluate_detections, has_labelled_box

    all_dets: list[np.ndarray | None] = []
    all_gts: list[np.ndarray | None] = []
    per_video: dict[str, Any] = {}
    for det_file, label_file in pair_files(detection_files, label_paths):
        video, dets = load_detections(det_file)
        _, gts = load_labels(label_file)
        n = min(len(dets), len(gts))
        if skip_unlabelled:
            dets = [d if has_labelled_box(g) else None for d, g in zip(dets[:n], gts[:n])]
        res = evaluate_detections(dets[:n], gts[:n], iou)
        per_video[Path(video).stem] = {"ap": res.metrics()["ap"], "n_frames": res.n_frames, "n_ground_truth": res.n_ground_truth}
        all_dets.extend(dets[:n])
        all_gts.extend(gts[:n])
    result = evaluate_detections(all_dets, all_gts, iou)
    metrics = result.metrics()
    metrics["n_videos"] = len(per_video)
    metrics["per_video"] = per_video
    return result, metrics


def main(args: argparse.Namespace) -> int:
    try:
        return _run(args)
    except (ValueError, FileNotFoundError) as e:
        print(f"synthaug evaluate: error: {e}", file=sys.stderr)
        return 2


def _run(args: argparse.Namespace) -> int:
    from synthaug._checks import check_output_dir
    from synthaug.evaluate.ap import plot_pr
    from synthaug.params import atomic_write_text

    if not 0.0 < args.iou <= 1.0:
        raise ValueError(f"--iou must be in (0, 1], got {args.iou}")
    for d in args.detections:
        if not d.is_file():
            raise FileNotFoundError(f"detections file not found: {d}")
    check_output_dir(args.out)
    result, metrics = evaluate_files(list(args.detections), list(args.labels), iou=args.iou,
                                     skip_unlabelled=args.unlabelled_frames == "skip")
    metrics["unlabelled_frames"] = args.unlabelled_frames
    args.out.mkdir(parents=True, exist_ok=True)
    label = "detector"
    try:
        first = json.loads(args.detections[0].read_text())
        if isinstance(first, dict) and isinstance(first.get("detector"), str):
            label = first["detector"]
    except (OSError, json.JSONDecodeError):
        pass
    plot_pr({label: result}, args.out / "pr.png", title=args.title or f"{metrics['n_videos']} video(s), IoU >= {args.iou}")
    metrics["pr_png"] = str(args.out / "pr.png")
    text = json.dumps(metrics, indent=2)
    atomic_write_text(args.out / "metrics.json", text + "\n")
    print(text)
    return 0
