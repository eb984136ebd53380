"""Stage 1 of ingest: shards. The options of a run (:class:`IngestConfig`), what a shard depends on and whether
one is current (its inputs' fingerprint), and making one: a video's (:func:`process_video`) or a chunk of
COCO images' (:func:`process_images`) seed candidates, backgrounds and negatives, as a seed set.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import time
import zlib
from collections import Counter
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from synthaug._io import digest, file_fingerprint, sha256_file


# What a shard holds: 1 gray patches and frames; 2 + RGB patches (colour.npz) and each seed's aligned neighbour frame.
SHARD_VERSION = 2


@dataclass(frozen=True)
class IngestConfig:
    """Options of an ingest run (their fingerprint decides whether a shard is reused).

    Args:
        patch_size: P, side of the seed patches (the paper: 40).
        object_fraction: the box's longest side spans this fraction of P.
        seeds_per_video: seed candidates per video (evenly spaced labelled frames).
        negatives_per_video: background negatives per video (per image for COCO: a quarter, at least 1).
        hard_negatives_per_video: hard negatives per hard-negative video.
        min_box_side: seeds need a box whose longest side is at least this (pixels).
        seed: base seed of every numpy Generator (per video: ``[seed, crc32(stem)]``).
        classes: known classes (None: any); others are errors.
        hard_negative_classes: classes whose videos only give hard negatives.
        margin_fraction: background object region = box grown by this fraction.
        max_residual: alignment check threshold, gray levels.
        inpaint_method: ``"pushpull"``, ``"telea"`` or ``"ns"``.
        max_background_error: seeds whose background quality figure (estimated
            fill error, gray levels) exceeds this are drawn into seed sets only
            after all better ones (of every video).
        colour: also keep RGB seed patches and backgrounds (``colour.npz``, the same
            crops; the background's colour fill uses the gray estimate's neighbours and
            homographies), for the diagnosis' colour channel. Videos only.
    """

    patch_size: int = 40
    object_fraction: float = 0.7
    seeds_per_video: int = 8
    negatives_per_video: int = 16
    hard_negatives_per_video: int = 16
    min_box_side: float = 8.0
    seed: int = 0
    classes: tuple[str, ...] | None = None
    hard_negative_classes: tuple[str, ...] = ("bird",)
    margin_fraction: float = 0.25
    max_residual: float = 8.0
    inpaint_method: str = "pushpull"
    max_background_error: float = 12.0
    colour: bool = True

    def __post_init__(self) -> None:
        if self.patch_size < 8:
            raise ValueError(f"patch_size must be >= 8, got {self.patch_size}")
        if not 0 < self.object_fraction <= 1:
            raise ValueError(f"object_fraction must be in (0, 1], got {self.object_fraction}")
        for name in ("seeds_per_video", "negatives_per_video", "hard_negatives_per_video"):
            if getattr(self, name) < 0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)}")
        if self.inpaint_method not in ("pushpull", "telea", "ns"):
            raise ValueError(f"inpaint_method must be pushpull, telea or ns, got {self.inpaint_method!r}")

    def fingerprint(self) -> str:
        # the shard layout's version too: shards written by older code lack what newer code reads
        key = {**asdict(self), "shard_version": SHARD_VERSION}
        return hashlib.sha1(json.dumps(key, sort_keys=True).encode()).hexdigest()[:16]


@dataclass
class VideoJob:
    """One video to ingest."""

    stem: str
    video_path: Path
    label_path: Path
    split: str = "train"


def _rng(cfg: IngestConfig, stem: str) -> np.random.Generator:
    return np.random.default_rng([cfg.seed, zlib.crc32(stem.encode())])


def _metadata(cfg: IngestConfig, inputs: dict[str, Any] | None = None, **more: Any) -> dict[str, Any]:
    return {"patch_size": cfg.patch_size, "object_fraction": cfg.object_fraction,
            "ingest_fingerprint": digest(inputs) if inputs is not None else cfg.fingerprint(),
            "ingest_options_fingerprint": cfg.fingerprint(), "ingest_inputs": inputs,
            "ingest_config": asdict(cfg), **more}


def _or_none(fn: Callable[[Any], Any], path: Any) -> Any:
    try:
        return fn(path)
    except OSError:  # missing / unreadable: processing reports it
        return None


def video_inputs(job: VideoJob, cfg: IngestConfig) -> dict[str, Any]:
    """What a video's shard depends on: the options, the video file's size and SHA-256 (not its time stamp: a
    copied folder keeps its shards), the label file's SHA-256, the split and the synthaug version."""
    from synthaug import __version__

    return {"options": cfg.fingerprint(), "synthaug_version": __version__, "split": job.split,
            "video": _or_none(file_fingerprint, job.video_path),
            "labels_sha256": _or_none(sha256_file, job.label_path)}


def images_inputs(images: Sequence[Any], split_of: dict[str, str], cfg: IngestConfig) -> dict[str, Any]:
    """What a COCO chunk's shard depends on: the options, each image's file (as a video's), boxes, classes and
    split, and the synthaug version."""
    from synthaug import __version__

    rows = [[str(im.path), int(im.image_id), np.asarray(im.boxes, np.float64).round(6).tolist(), list(im.classes),
             split_of.get(im.path.name, split_of.get(im.path.stem, "train")),
             _or_none(file_fingerprint, im.path)] for im in images]
    return {"options": cfg.fingerprint(), "synthaug_version": __version__, "images": digest(rows, length=64)}


_INPUT_NAMES = {"options": "the ingest options", "synthaug_version": "the synthaug version",
                "video": "the video file", "labels_sha256": "the label file", "images": "the images or their boxes"}


def _what_changed(old: dict[str, Any], new: dict[str, Any]) -> str:
    """The inputs that differ, named for a user; a file recorded in another form of fingerprint (an older synthaug's,
    e.g. size + time stamp + partial hash before the full SHA-256) is said to be that, not to have changed."""
    out = []
    for k in sorted(set(old) | set(new)):
        a, b = old.get(k), new.get(k)
        if a == b:
            continue
        name = _INPUT_NAMES.get(k, k)
        if k == "split":
            out.append(f"the split {a} -> {b}")
        elif isinstance(a, dict) and isinstance(b, dict) and set(a) != set(b):
            out.append(f"the form of {name}'s fingerprint (recorded by an older synthaug: {', '.join(sorted(a))})")
        else:
            out.append(name)
    return ", ".join(out) or "another fingerprint"


def _mtime_ns(path: Path) -> int | None:
    try:
        return path.stat().st_mtime_ns
    except OSError:
        return None


def _shard_status(shard: Path, cfg: IngestConfig, inputs: dict[str, Any] | None = None,
                  sources: Sequence[Path] = ()) -> tuple[bool, str]:
    """``(current, why not)`` of a shard against the inputs it would be made from now (``""`` for no shard).

    Without ``inputs`` only the options are compared. A shard of an older synthaug (no recorded inputs) is kept
    when its options and split match and its ``sources`` (video, label file) are not newer than it.
    """
    head = shard / "seedset.json"
    if not head.is_file():
        return False, ""
    try:
        meta = json.loads(head.read_text())
    except (OSError, ValueError):
        return False, "its header is unreadable"
    if not isinstance(meta, dict):
        return False, "its header is unreadable"
    options = meta.get("ingest_options_fingerprint", meta.get("ingest_fingerprint"))
    if inputs is None:
        return options == cfg.fingerprint(), "the ingest options"
    old = meta.get("ingest_inputs")
    if isinstance(old, dict):
        ok = meta.get("ingest_fingerprint") == digest(inputs)
        return ok, "" if ok else _what_changed(old, inputs)
    if options != cfg.fingerprint():
        return False, "the ingest options"
    if "split" in inputs and (meta.get("shard") or {}).get("split") != inputs["split"]:
        return False, f"the split {(meta.get('shard') or {}).get('split')} -> {inputs['split']}"
    made = head.stat().st_mtime_ns
    newer = [p.name for p in sources if (_mtime_ns(p) or 0) > made]
    return (not newer), (f"{', '.join(newer)} newer than its shard (made by an older synthaug)" if newer else "")


def _fully_inside(box: np.ndarray, w: int, h: int) -> bool:
    return box[0] >= 0.5 and box[1] >= 0.5 and box[0] + box[2] <= w - 0.5 and box[1] + box[3] <= h - 0.5


def _seed_entries(frame: np.ndarray, background: np.ndarray, box: np.ndarray, cfg: IngestConfig
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    from synthaug.data.seedset import crop_patch

    patch, crop = crop_patch(frame, box=box, patch_size=cfg.patch_size, object_fraction=cfg.object_fraction)
    bg, _ = crop_patch(background, crop=crop, patch_size=cfg.patch_size)
    return patch, bg, crop


def _noise_neighbour(aligner: Any, boxes: Sequence[Any], index: int, offsets: Sequence[int]) -> dict[str, Any] | None:
    """The nearest frame aligned onto ``frames[index]`` (±1, ±2, then the background's neighbours): a second
    look at the scene, for the camera's noise level function. ``{"frame", "offset", "homography", "box"}``."""
    n = len(boxes)
    for off in [1, -1, 2, -2] + sorted(set(int(o) for o in offsets), key=lambda o: (abs(o), o)):
        j = index + off
        if off == 0 or not 0 <= j < n:
            continue
        H = aligner.homography(j, index)
        if H is not None:
            b = boxes[j]
            return {"frame": j, "offset": off, "homography": np.asarray(H, np.float64).round(8).tolist(),
                    "box": None if b is None else [round(float(v), 2) for v in np.asarray(b).reshape(-1)[:4]]}
    return None


def process_video(job: VideoJob, cfg: IngestConfig, pool_dir: str | os.PathLike) -> dict[str, Any]:
    """Ingest one video into the shard ``pool_dir/<stem>`` (see the module docstring).

    Returns:
        A summary dict (stem, class, counts, background methods, cleanup counts, seconds).

    Raises:
        IngestInputError: unreadable video, empty label file, unknown class...
    """
    from synthaug.data.backgrounds import FrameAligner, estimate_background
    from synthaug.data.negatives import hard_negatives, sample_negatives
    from synthaug.data.seedset import crop_patch, write_seedset
    from synthaug.data.video import read_video_with_labels

    t0 = time.perf_counter()
    inputs = video_inputs(job, cfg)  # before reading: an edit made meanwhile shows at the next run
    known = None if cfg.classes is None else tuple(cfg.classes) + tuple(cfg.hard_negative_classes)
    frames, labels, cleanup = read_video_with_labels(job.video_path, job.label_path, classes=known, colour=cfg.colour)
    frames_rgb = None
    if cfg.colour:  # the gray frames are the RGB frames' luma, exactly as a gray decode gives them
        import cv2

        frames_rgb = frames
        frames = np.stack([cv2.cvtColor(f, cv2.COLOR_RGB2GRAY) for f in frames_rgb])
    cls = labels.class_name
    h, w = frames.shape[1:]
    boxes = labels.boxes
    rng = _rng(cfg, job.stem)
    meta = {"video": job.stem, "class": cls, "split": job.split}
    hard = cls in cfg.hard_negative_classes
    patches, bgs, crops, recs, full, full_bg, sel_boxes = [], [], [], [], [], [], []
    patches_rgb, bgs_rgb, neighbours = [], [], []
    methods: Counter[str] = Counter()
    if not hard and cfg.seeds_per_video > 0:
        eligible = [i for i, b in enumerate(boxes)
                    if b is not None and _fully_inside(b, w, h) and max(b[2], b[3]) >= cfg.min_box_side]
        if eligible:
            k = min(cfg.seeds_per_video, len(eligible))
            pick = sorted({eligible[int(j)] for j in np.linspace(0, len(eligible) - 1, k).round()})
            aligner = FrameAligner(frames, boxes)
            for i in pick:
                res = estimate_background(frames, boxes, i, aligner=aligner, margin_fraction=cfg.margin_fraction,
                                          max_residual=cfg.max_residual, inpaint_method=cfg.inpaint_method,
                                          colour_frames=frames_rgb)
                patch, bg, crop = _seed_entries(frames[i], res.background, boxes[i], cfg)
                if frames_rgb is not None:
                    patches_rgb.append(crop_patch(frames_rgb[i], crop=crop, patch_size=cfg.patch_size)[0])
                    bgs_rgb.append(crop_patch(res.background_rgb, crop=crop, patch_size=cfg.patch_size)[0])
                patches.append(patch), bgs.append(bg), crops.append(crop), sel_boxes.append(boxes[i])
                full.append(frames[i]), full_bg.append(res.background)
                methods[res.method] += 1
                nb = _noise_neighbour(aligner, boxes, i, res.details.get("offsets_used", []))
                neighbours.append(None if nb is None else frames[nb["frame"]])
                recs.append({**meta, "frame": i, "background_method": res.method,
                             **({} if nb is None else {"neighbour": nb}),
                             "background_quality": round(float(res.quality), 3), "n_aligned": res.n_aligned,
                             "inpainted_fraction": round(res.inpainted_fraction, 3),
                             "object_contrast": res.details.get("object_contrast"),
                             "box": [round(float(v), 2) for v in boxes[i]],
                             "crop": [round(float(v), 3) for v in crop], "source_path": str(job.video_path)})
    if hard:
        negs, neg_recs = hard_negatives(frames, boxes, cfg.hard_negatives_per_video, patch_size=cfg.patch_size,
                                        object_fraction=cfg.object_fraction, meta=meta)
    else:
        sides = [c[2] for c in crops] or [max(b[2], b[3]) / cfg.object_fraction for b in boxes if b is not None]
        negs, neg_recs = sample_negatives(frames, boxes, cfg.negatives_per_video, sides=sides, rng=rng,
                                          patch_size=cfg.patch_size, meta=meta)
    p = cfg.patch_size
    summary = {"stem": job.stem, "class": cls, "split": job.split, "hard_negative": hard, "n_seeds": len(recs),
               "n_negatives": len(negs), "background_methods": dict(methods), "cleanup": cleanup.as_dict(),
               "frame_size": [w, h]}
    write_seedset(Path(pool_dir) / job.stem, patches=np.array(patches, np.uint8).reshape(-1, p, p),
                  backgrounds=np.array(bgs, np.uint8).reshape(-1, p, p),
                  boxes=np.array(sel_boxes, np.float32).reshape(-1, 4),
                  centres=np.array([[b[0] + b[2] / 2, b[1] + b[3] / 2] for b in sel_boxes], np.float32).reshape(-1, 2),
                  crops=np.array(crops, np.float32).reshape(-1, 3), records=recs, frames=full, background_frames=full_bg,
                  negatives=negs, negative_records=neg_recs,
                  metadata=_metadata(cfg, inputs, source={"video": str(job.video_path),
                                                          "labels": str(job.label_path)}, shard=summary),
                  patches_rgb=np.array(patches_rgb, np.uint8).reshape(-1, p, p, 3) if cfg.colour else None,
                  backgrounds_rgb=np.array(bgs_rgb, np.uint8).reshape(-1, p, p, 3) if cfg.colour else None,
                  neighbour_frames=neighbours)
    summary["seconds"] = round(time.perf_counter() - t0, 3)
    return summary


def process_images(name: str, images: Sequence[Any], split_of: dict[str, str], cfg: IngestConfig,
                   pool_dir: str | os.PathLike, coco_path: str = "") -> dict[str, Any]:
    """Ingest a chunk of COCO images (:class:`~synthaug.data.video.CocoImage`) into ``pool_dir/<name>``.

    Each annotated box is a seed; its background is inpainted (one image: no
    neighbours), with all boxes of the image removed. Unreadable images are
    counted and skipped.
    """
    from synthaug.data.backgrounds import estimate_background_single
    from synthaug.data.negatives import sample_negatives
    from synthaug.data.seedset import write_seedset
    from synthaug.data.video import IngestInputError, clip_boxes, read_image_gray

    t0 = time.perf_counter()
    inputs = images_inputs(images, split_of, cfg)
    rng = _rng(cfg, name)
    patches, bgs, crops, recs, full, full_bg, sel_boxes = [], [], [], [], [], [], []
    negs, neg_recs, errors = [], [], []
    methods: Counter[str] = Counter()
    totals: Counter[str] = Counter()
    n_neg = max(1, cfg.negatives_per_video // 4) if cfg.negatives_per_video else 0
    for im in images:
        try:
            img = read_image_gray(im.path)
        except IngestInputError as e:
            errors.append(str(e))
            continue
        h, w = img.shape
        clean, stats = clip_boxes(list(im.boxes), width=w, height=h)
        for k, v in stats.as_dict().items():
            if v > 0:
                totals[k] += v
        keep = [(b, c) for b, c in zip(clean, im.classes) if b is not None]
        if not keep:
            continue
        all_boxes = np.array([b for b, _ in keep])
        res = estimate_background_single(img, all_boxes, margin_fraction=cfg.margin_fraction,
                                         inpaint_method=cfg.inpaint_method)
        split = split_of.get(im.path.name, split_of.get(im.path.stem, "train"))
        meta = {"video": im.path.name, "split": split}
        for b, c in keep:
            if not (_fully_inside(b, w, h) and max(b[2], b[3]) >= cfg.min_box_side):
                continue
            patch, bg, crop = _seed_entries(img, res.background, b, cfg)
            patches.append(patch), bgs.append(bg), crops.append(crop), sel_boxes.append(b)
            full.append(img), full_bg.append(res.background)
            methods[res.method] += 1
            recs.append({**meta, "class": c, "frame": 0, "image_id": im.image_id, "background_method": res.method,
                         "background_quality": round(float(res.quality), 3), "n_aligned": 0,
                         "inpainted_fraction": 1.0, "object_contrast": res.details.get("object_contrast"),
                         "box": [round(float(v), 2) for v in b], "crop": [round(float(v), 3) for v in crop],
                         "source_path": str(im.path)})
        sides = [max(b[2], b[3]) / cfg.object_fraction for b, _ in keep]
        ng, nr = sample_negatives(img[None], [all_boxes], n_neg, sides=sides, rng=rng, patch_size=cfg.patch_size,
                                  meta={**meta, "class": keep[0][1]})
        negs += list(ng)
        neg_recs += nr
    p = cfg.patch_size
    summary = {"stem": name, "n_images": len(images), "n_seeds": len(recs), "n_negatives": len(negs),
               "background_methods": dict(methods), "cleanup": dict(totals), "unreadable": errors}
    write_seedset(Path(pool_dir) / name, patches=np.array(patches, np.uint8).reshape(-1, p, p),
                  backgrounds=np.array(bgs, np.uint8).reshape(-1, p, p),
                  boxes=np.array(sel_boxes, np.float32).reshape(-1, 4),
                  centres=np.array([[b[0] + b[2] / 2, b[1] + b[3] / 2] for b in sel_boxes], np.float32).reshape(-1, 2),
                  crops=np.array(crops, np.float32).reshape(-1, 3), records=recs, frames=full, background_frames=full_bg,
                  negatives=np.array(negs, np.uint8).reshape(-1, p, p), negative_records=neg_recs,
                  metadata=_metadata(cfg, inputs, source={"coco": coco_path}, shard=summary))
    summary["seconds"] = round(time.perf_counter() - t0, 3)
    return summary


def _shard_is_current(shard: Path, cfg: IngestConfig) -> bool:
    """Whether a shard was made with these options (its inputs are checked by :func:`_shard_status`)."""
    return _shard_status(shard, cfg)[0]


def _clean_stale(pool: Path) -> None:
    """Remove temporary folders/files an interrupted run of ours left (names we create only)."""
    if not pool.is_dir():
        return
    for p in pool.iterdir():
        if p.name.startswith(".") and (".tmp-" in p.name or ".old-" in p.name or p.name.endswith(".tmp")):
            shutil.rmtree(p, ignore_errors=True) if p.is_dir() else p.unlink(missing_ok=True)
