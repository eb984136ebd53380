"""Read the inputs of a seed set: videos with per-frame boxes, or images with COCO boxes.

Two input formats are understood:

* a video plus a per-frame label JSON in the format of ``../shared/data/halmstad/labels``::

    {"video": "V_DRONE_001.mp4", "class": "drone", "box_format": "xywh_pixels",
     "boxes": [[x, y, w, h] | null, ...]}

  (``null``: the target is not visible in that frame);
* a folder of images plus a COCO JSON file (``images``, ``annotations`` with
  ``bbox`` = ``[x, y, w, h]`` in pixels, ``categories``).

Everything is read as 8-bit grayscale, the seed-set contract. Bad inputs raise
:class:`IngestInputError` (a ``ValueError``) whose message names the file and
the problem; frame/label count mismatches and out-of-frame boxes are repaired
and *counted* (see :class:`BoxCleanup`), never silently dropped.

Example:
    >>> import numpy as np
    >>> boxes = [np.array([-5.0, 10.0, 20.0, 10.0]), None, np.array([700.0, 0.0, 5.0, 5.0])]
    >>> clean, stats = clip_boxes(boxes, width=640, height=512)
    >>> clean[0].tolist(), clean[1], clean[2]
    ([0.0, 10.0, 15.0, 10.0], None, None)
    >>> stats.clipped, stats.dropped
    (1, 1)
"""

from __future__ import annotations

import json
import logging
import os
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator, Sequence

import numpy as np

__all__ = [
    "IngestInputError",
    "BoxCleanup",
    "VideoLabels",
    "CocoImage",
    "iter_frames",
    "video_frame_size",
    "read_labels",
    "read_video",
    "read_video_with_labels",
    "clip_boxes",
    "read_coco",
    "read_image_gray",
    "VIDEO_EXTENSIONS",
    "find_video",
]

VIDEO_EXTENSIONS: tuple[str, ...] = (".mp4", ".avi", ".mov", ".mkv", ".m4v")
LABEL_BOX_FORMAT = "xywh_pixels"

log = logging.getLogger("synthaug.data")

# a label file and its video whose lengths differ by more than this fraction (and 2 frames) get a warning
LENGTH_MISMATCH_WARN = 0.10


class IngestInputError(ValueError):
    """A user input (video, label or COCO file) that cannot be used, with the reason."""


@dataclass
class BoxCleanup:
    """What :func:`clip_boxes` / :func:`read_video_with_labels` repaired.

    Attributes:
        clipped: boxes partly outside the frame, clipped to it.
        dropped: boxes outside the frame (or degenerate after clipping), dropped.
        invalid: boxes with non-finite values or non-positive size, dropped.
        frames_decoded: frames decoded from the video (``-1`` when not a video).
        labels_read: entries in the label file.
        frames_used: ``min(frames_decoded, labels_read)``, the shorter of the two.
    """

    clipped: int = 0
    dropped: int = 0
    invalid: int = 0
    frames_decoded: int = -1
    labels_read: int = -1
    frames_used: int = -1

    def as_dict(self) -> dict[str, int]:
        return dict(self.__dict__)


@dataclass
class VideoLabels:
    """The per-frame boxes of one video.

    Attributes:
        path: the label file.
        video: video file name from the label file (may be empty).
        class_name: object class (``"drone"``).
        boxes: one entry per frame, ``None`` or a float64 ``[x, y, w, h]`` array (the shared
            format's one box per frame; anything else is kept as a NaN box for
            :func:`clip_boxes` to count and drop).
        entries: the file's per-frame entries as read, for :meth:`ground_truth`.
    """

    path: Path
    video: str
    class_name: str
    boxes: list[np.ndarray | None]
    entries: list[Any] = field(default_factory=list, repr=False)

    def ground_truth(self) -> list[np.ndarray | None]:
        """The boxes as evaluation's ground truth: per frame a float64 ``(G, 4)`` XYWH array or ``None``.

        An entry may be ``null`` / ``[]`` (no object), one ``[x, y, w, h]`` box, or a list of them (more
        than one object in a frame). Boxes of zero or negative width or height are left out (a
        :class:`UserWarning` names the file and frames): no detection could match them.

        Raises:
            IngestInputError: naming the file and frame, for a malformed entry or a non-finite box.
        """
        import warnings

        frames: list[np.ndarray | None] = []
        degenerate: list[int] = []
        for i, entry in enumerate(self.entries):
            if entry is None or (isinstance(entry, list) and len(entry) == 0):
                frames.append(None)
                continue
            try:
                arr = np.asarray(entry, dtype=np.float64)
            except (ValueError, TypeError):
                arr = np.zeros((0, 0))
            if arr.ndim == 1:
                arr = arr[None]
            if arr.ndim != 2 or arr.shape[1] != 4:
                raise IngestInputError(f"{self.path}: frame {i} box must be [x, y, w, h] or a list of them, got {entry!r}")
            if not np.isfinite(arr).all():
                raise IngestInputError(f"{self.path}: frame {i} has a non-finite box: {entry!r}")
            keep = (arr[:, 2:] > 0).all(axis=1)
            if not keep.all():
                degenerate.append(i)
                arr = arr[keep]
            frames.append(arr if len(arr) else None)
        if degenerate:
            warnings.warn(f"{self.path}: {len(degenerate)} frame(s) have boxes of zero or negative width/height, left "
                          f"out of the ground truth (frames {degenerate[:5]}{' ...' if len(degenerate) > 5 else ''})",
                          stacklevel=2)
        return frames

    @property
    def stem(self) -> str:
        return self.path.stem


@dataclass
class CocoImage:
    """One image of a COCO file with its boxes.

    Attributes:
        path: the image file.
        image_id: COCO image id.
        width: width from the COCO file (0 when absent).
        height: height from the COCO file (0 when absent).
        boxes: float64 ``(K, 4)`` xywh boxes in pixels.
        classes: the K class names.
    """

    path: Path
    image_id: int
    width: int
    height: int
    boxes: np.ndarray
    classes: list[str] = field(default_factory=list)


def _load_json(path: Path, what: str) -> Any:
    try:
        text = path.read_text()
    except FileNotFoundError:
        raise IngestInputError(f"{what} not found: {path}") from None
    except (OSError, UnicodeDecodeError) as e:
        raise IngestInputError(f"{what} {path} cannot be read ({e})") from None
    if not text.strip():
        raise IngestInputError(f"{what} {path} is empty")
    try:
        return json.loads(text)
    except json.JSONDecodeError as e:
        raise IngestInputError(f"{what} {path} is not valid JSON ({e})") from None


def _parse_box(raw: Any) -> np.ndarray | None:
    if raw is None:
        return None
    try:
        box = np.asarray(raw, dtype=np.float64)
    except (TypeError, ValueError):
        return np.full(4, np.nan)
    if box.shape != (4,):
        return np.full(4, np.nan)
    return box


def read_labels(path: str | os.PathLike, *, classes: Sequence[str] | None = None) -> VideoLabels:
    """Read one per-frame label file (the halmstad format).

    Args:
        path: the ``.json`` label file.
        classes: known class names; a file whose class is not among them is an
            error. ``None`` accepts any class.

    Returns:
        The labels; malformed boxes are kept as NaN arrays for :func:`clip_boxes`
        to count and drop.

    Raises:
        IngestInputError: missing/empty/non-JSON file, no boxes, unknown class,
            or a box format other than ``xywh_pixels``.
    """
    path = Path(path)
    doc = _load_json(path, "label file")
    if not isinstance(doc, dict):
        raise IngestInputError(f"label file {path} must hold a JSON object, got {type(doc).__name__}")
    boxes = doc.get("boxes")
    if not isinstance(boxes, list) or len(boxes) == 0:
        raise IngestInputError(f"label file {path} is empty: it holds no per-frame boxes")
    fmt = doc.get("box_format", LABEL_BOX_FORMAT)
    if fmt != LABEL_BOX_FORMAT:
        raise IngestInputError(f"label file {path}: box_format must be {LABEL_BOX_FORMAT!r}, got {fmt!r}")
    class_name = doc.get("class")
    if not isinstance(class_name, str) or not class_name:
        raise IngestInputError(f"label file {path}: missing 'class', got {class_name!r}")
    if classes is not None and class_name not in classes:
        raise IngestInputError(f"label file {path}: unknown class {class_name!r}; known: {sorted(classes)}")
    return VideoLabels(path=path, video=str(doc.get("video", "")), class_name=class_name,
                       boxes=[_parse_box(b) for b in boxes], entries=list(boxes))


def iter_frames(path: str | os.PathLike, *, wanted: Callable[[int], bool] | None = None, stop: int | None = None,
                colour: bool = False) -> Iterator[tuple[int, np.ndarray | None]]:
    """Decode a video with OpenCV frame by frame: the one frame loop of the package.

    Args:
        path: the video file.
        wanted: which frame indices to decode (``None``: all); the others are only grabbed
            (no decoding cost) and yielded as ``(index, None)``.
        stop: stop before this frame index (``None``: at the end of the video).
        colour: RGB frames ``(H, W, 3)`` (a gray video is replicated) instead of gray ``(H, W)``;
            both uint8.

    Yields:
        ``(index, frame)`` for every frame up to ``stop`` or the end of the video.

    Raises:
        IngestInputError: OpenCV cannot open the file.
    """
    import cv2

    with _capture(path) as cap:
        index = 0
        while stop is None or index < stop:
            if wanted is not None and not wanted(index):
                if not cap.grab():
                    break
                yield index, None
            else:
                ok, frame = cap.read()
                if not ok or frame is None:
                    break
                if colour:
                    frame = cv2.cvtColor(frame, cv2.COLOR_BGR2RGB if frame.ndim == 3 else cv2.COLOR_GRAY2RGB)
                elif frame.ndim == 3:
                    frame = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
                yield index, frame
            index += 1


def video_frame_size(path: str | os.PathLike) -> tuple[int, int]:
    """``(width, height)`` of a video as OpenCV reports it (``(0, 0)`` when unknown).

    Raises:
        IngestInputError: OpenCV cannot open the file.
    """
    import cv2

    with _capture(path) as cap:
        return int(cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT))


@contextmanager
def _capture(path: str | os.PathLike) -> Iterator[Any]:
    """An opened ``cv2.VideoCapture``, released on exit."""
    import cv2

    cap = cv2.VideoCapture(str(path))
    try:
        if not cap.isOpened():
            raise IngestInputError(f"video {path} cannot be opened (not a video OpenCV can decode?)")
        yield cap
    finally:
        cap.release()


def read_video(path: str | os.PathLike, *, max_frames: int | None = None, colour: bool = False) -> np.ndarray:
    """Decode a video with OpenCV into 8-bit grayscale (or RGB) frames.

    Args:
        path: the video file.
        max_frames: stop after this many frames (``None``: all).
        colour: RGB frames ``(T, H, W, 3)`` (a gray video is replicated); their gray is
            ``cv2.cvtColor(frame, COLOR_RGB2GRAY)``, identical to the default's.

    Returns:
        uint8 array of shape ``(T, H, W)`` (or ``(T, H, W, 3)``).

    Raises:
        IngestInputError: the file is missing or no frame can be decoded.
    """
    path = Path(path)
    if not path.is_file():
        raise IngestInputError(f"video not found: {path}")
    frames = [f for _, f in iter_frames(path, stop=max_frames, colour=colour)]
    if not frames:
        raise IngestInputError(f"video {path} is unreadable: no frame could be decoded")
    return np.stack(frames)


def clip_boxes(
    boxes: Sequence[np.ndarray | None], *, width: int, height: int, min_size: float = 2.0,
) -> tuple[list[np.ndarray | None], BoxCleanup]:
    """Clip xywh boxes to the frame; drop those outside it or degenerate.

    Args:
        boxes: per-frame ``[x, y, w, h]`` arrays or ``None``.
        width: frame width W.
        height: frame height H.
        min_size: a clipped box thinner than this (pixels) is dropped.

    Returns:
        The cleaned list (same length; dropped boxes become ``None``) and the counts.
    """
    if width <= 0 or height <= 0:
        raise ValueError(f"frame size must be positive, got {width}x{height}")
    stats = BoxCleanup()
    out: list[np.ndarray | None] = []
    for b in boxes:
        if b is None:
            out.append(None)
            continue
        if not np.all(np.isfinite(b)) or b[2] <= 0 or b[3] <= 0:
            stats.invalid += 1
            out.append(None)
            continue
        x0, y0, x1, y1 = b[0], b[1], b[0] + b[2], b[1] + b[3]
        cx0, cy0, cx1, cy1 = max(x0, 0.0), max(y0, 0.0), min(x1, float(width)), min(y1, float(height))
        if cx1 - cx0 < min_size or cy1 - cy0 < min_size:
            stats.dropped += 1
            out.append(None)
            continue
        if (cx0, cy0, cx1, cy1) != (x0, y0, x1, y1):
            stats.clipped += 1
        out.append(np.array([cx0, cy0, cx1 - cx0, cy1 - cy0], dtype=np.float64))
    return out, stats


def read_video_with_labels(
    video_path: str | os.PathLike, label_path: str | os.PathLike, *, classes: Sequence[str] | None = None,
    colour: bool = False,
) -> tuple[np.ndarray, VideoLabels, BoxCleanup]:
    """Decode a video and its labels, aligned to the shorter of the two, boxes clipped.

    A length difference of more than 10 % (and 2 frames) between the label file and the video is logged as a
    warning (``synthaug.data``): the label file may not be this video's.

    Returns:
        ``(frames, labels, cleanup)``: uint8 ``(T, H, W)`` frames (``(T, H, W, 3)`` RGB with
        ``colour``) and labels with exactly ``T`` boxes, ``T = min(frames decoded, labels read)``.

    Raises:
        IngestInputError: as :func:`read_labels` and :func:`read_video`; and when boxes were given but none is
            usable (every one invalid or outside the frame).
    """
    labels = read_labels(label_path, classes=classes)
    frames = read_video(video_path, colour=colour)
    n = min(len(frames), len(labels.boxes))
    diff = abs(len(frames) - len(labels.boxes))
    if diff > 2 and diff > LENGTH_MISMATCH_WARN * n:
        log.warning("synthaug: label file %s has %d entries for the %d frames of %s; using the first %d "
                    "(the shorter of the two) - is it this video's label file?", label_path, len(labels.boxes),
                    len(frames), video_path, n)
    boxes, stats = clip_boxes(labels.boxes[:n], width=frames.shape[2], height=frames.shape[1])
    stats.frames_decoded, stats.labels_read, stats.frames_used = len(frames), len(labels.boxes), n
    if stats.invalid + stats.dropped and all(b is None for b in boxes):
        raise IngestInputError(
            f"label file {label_path}: none of its boxes is usable ({stats.invalid} invalid: not 4 finite numbers "
            f"or a zero/negative size; {stats.dropped} outside the {frames.shape[2]}x{frames.shape[1]} frame)")
    labels.boxes = boxes
    return frames[:n], labels, stats


def read_image_gray(path: str | os.PathLike) -> np.ndarray:
    """Read an image file as uint8 grayscale ``(H, W)``; unreadable files raise IngestInputError."""
    import cv2

    path = Path(path)
    if not path.is_file():
        raise IngestInputError(f"image not found: {path}")
    img = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    if img is None:
        raise IngestInputError(f"image {path} is unreadable (not an image OpenCV can decode?)")
    return img


def read_coco(
    coco_path: str | os.PathLike, image_dir: str | os.PathLike, *, classes: Sequence[str] | None = None,
) -> list[CocoImage]:
    """Read a COCO detection file (``bbox`` annotations) for images under ``image_dir``.

    Images without annotations are skipped (nothing to seed from); crowd
    annotations (``iscrowd=1``) are ignored.

    Args:
        coco_path: the COCO JSON file.
        image_dir: folder the ``file_name`` entries are relative to.
        classes: known category names (``None``: any category of the file).

    Returns:
        One :class:`CocoImage` per annotated image, in the file's image order.

    Raises:
        IngestInputError: missing/empty/invalid file, no annotations, an
            annotation naming an unknown image or category, or a category
            outside ``classes``.
    """
    coco_path, image_dir = Path(coco_path), Path(image_dir)
    doc = _load_json(coco_path, "COCO file")
    if not isinstance(doc, dict) or not isinstance(doc.get("images"), list):
        raise IngestInputError(f"COCO file {coco_path} must hold an object with an 'images' list")
    anns = doc.get("annotations")
    if not isinstance(anns, list) or not anns:
        raise IngestInputError(f"COCO file {coco_path} is empty: it holds no annotations")
    cats = {int(c["id"]): str(c["name"]) for c in doc.get("categories", []) if "id" in c and "name" in c}
    images = {}
    for im in doc["images"]:
        if "id" not in im or "file_name" not in im:
            raise IngestInputError(f"COCO file {coco_path}: image entry without id/file_name: {im}")
        images[int(im["id"])] = im
    per_image: dict[int, list[tuple[list[float], str]]] = {}
    for ann in anns:
        if ann.get("iscrowd", 0):
            continue
        iid, cid = ann.get("image_id"), ann.get("category_id")
        if iid not in images:
            raise IngestInputError(f"COCO file {coco_path}: annotation {ann.get('id')} names unknown image_id {iid}")
        if cid not in cats:
            raise IngestInputError(
                f"COCO file {coco_path}: annotation {ann.get('id')} has unknown category_id {cid}; "
                f"known: {sorted(cats)}")
        name = cats[cid]
        if classes is not None and name not in classes:
            raise IngestInputError(f"COCO file {coco_path}: unknown class {name!r}; known: {sorted(classes)}")
        bbox = ann.get("bbox")
        if not isinstance(bbox, (list, tuple)) or len(bbox) != 4:
            raise IngestInputError(f"COCO file {coco_path}: annotation {ann.get('id')} has no [x, y, w, h] bbox, got {bbox!r}")
        per_image.setdefault(int(iid), []).append(([float(v) for v in bbox], name))
    out = []
    for iid, im in images.items():
        if iid not in per_image:
            continue
        boxes = np.array([b for b, _ in per_image[iid]], dtype=np.float64).reshape(-1, 4)
        out.append(CocoImage(path=image_dir / im["file_name"], image_id=iid, width=int(im.get("width", 0)),
                             height=int(im.get("height", 0)), boxes=boxes,
                             classes=[c for _, c in per_image[iid]]))
    return out


def find_video(video_dir: str | os.PathLike, stem: str) -> Path | None:
    """The video file ``video_dir/<stem><ext>`` for the first of :data:`VIDEO_EXTENSIONS` that exists, else None.

    Example:
        >>> import tempfile
        >>> with tempfile.TemporaryDirectory() as d:
        ...     _ = (Path(d) / "V_1.avi").write_bytes(b"")
        ...     find_video(d, "V_1").name, find_video(d, "V_2")
        ('V_1.avi', None)
    """
    video_dir = Path(video_dir)
    return next((video_dir / f"{stem}{ext}" for ext in VIDEO_EXTENSIONS if (video_dir / f"{stem}{ext}").is_file()), None)


def iter_video_label_pairs(video_dir: str | os.PathLike, label_dir: str | os.PathLike) -> Iterator[tuple[str, Path, Path]]:
    """``(stem, video_path, label_path)`` for every label file, matched to a video by stem.

    The video path is ``video_dir/<stem>.mp4`` (or another known extension);
    when none exists the ``.mp4`` path is returned and decoding reports it.
    """
    video_dir, label_dir = Path(video_dir), Path(label_dir)
    for label in sorted(label_dir.glob("*.json")):
        yield label.stem, find_video(video_dir, label.stem) or video_dir / f"{label.stem}.mp4", label
