"""Ingest: videos + boxes (or images + COCO) -> per-video shards -> seed sets.

Two stages, both restartable:

1. **Shards.** Every video (or chunk of COCO images) is processed on its own,
   in parallel worker processes, into ``OUT/pool/<stem>/``, itself a seed set
   (:mod:`synthaug.data.seedset`) holding that video's seed candidates
   (evenly spaced labelled frames, with backgrounds from
   :mod:`synthaug.data.backgrounds`), its background negatives and, for
   hard-negative classes (birds), its hard negatives. A shard is written to a
   temporary folder and renamed into place, so an interrupted run leaves no
   half-written shard. Each shard records the fingerprint of its inputs (the
   options, the video file's size, mtime and the SHA-256 of its first and last
   MiB, the label file's SHA-256, the split, the synthaug version); a rerun
   skips shards whose fingerprint is current and redoes the rest, with a
   warning naming what changed (so editing one label file re-ingests exactly
   that video). A video that fails writes ``OUT/pool/<stem>.error.json``
   with the reason and never stops the others. Worker processes die with the
   command (:mod:`synthaug._procs`): a ``kill -9`` leaves nothing running.
2. **Seed sets.** For every positive class and every requested count (12, 25,
   50, 100...), seeds are drawn from the *train* shards only, spread across
   videos (round-robin over the videos in a seeded order, so the 12-seed set is
   contained in the 25-seed set, and so on), into
   ``OUT/seedsets/<class>_<count>/`` with a ``contact_sheet.png``. Negatives of
   a seed set are all background negatives of that class's train videos plus
   the hard negatives of the train hard-negative videos. Seed sets are drawn
   from this run's shards only (not from shards of other videos an earlier run
   left in the pool), and record the run's fingerprint; a seed set under
   ``OUT/seedsets`` left by an earlier run with other inputs is reported as
   stale (``stale_seed_sets``), never as current.

``OUT/ingest_report.json`` sums up what was done, skipped, failed, repaired.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import shutil
import sys
import time
import zlib
from collections import Counter
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from synthaug._io import digest, quick_file_fingerprint, sha256_file

log = logging.getLogger("synthaug.ingest")

__all__ = ["IngestConfig", "VideoJob", "process_video", "process_images", "ingest_videos", "ingest_coco",
           "assemble_seed_sets", "select_spread"]


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
    """What a video's shard depends on: the options, the video file (size, mtime, SHA-256 of its first and last
    MiB), the label file's SHA-256, the split and the synthaug version."""
    from synthaug import __version__

    return {"options": cfg.fingerprint(), "synthaug_version": __version__, "split": job.split,
            "video": _or_none(quick_file_fingerprint, job.video_path),
            "labels_sha256": _or_none(sha256_file, job.label_path)}


def images_inputs(images: Sequence[Any], split_of: dict[str, str], cfg: IngestConfig) -> dict[str, Any]:
    """What a COCO chunk's shard depends on: the options, each image's file (as a video's), boxes, classes and
    split, and the synthaug version."""
    from synthaug import __version__

    rows = [[str(im.path), int(im.image_id), np.asarray(im.boxes, np.float64).round(6).tolist(), list(im.classes),
             split_of.get(im.path.name, split_of.get(im.path.stem, "train")),
             _or_none(quick_file_fingerprint, im.path)] for im in images]
    return {"options": cfg.fingerprint(), "synthaug_version": __version__, "images": digest(rows, length=64)}


_INPUT_NAMES = {"options": "the ingest options", "synthaug_version": "the synthaug version",
                "video": "the video file", "labels_sha256": "the label file", "images": "the images or their boxes"}


def _what_changed(old: dict[str, Any], new: dict[str, Any]) -> str:
    out = []
    for k in sorted(set(old) | set(new)):
        if old.get(k) != new.get(k):
            out.append(f"the split {old.get(k)} -> {new.get(k)}" if k == "split" else _INPUT_NAMES.get(k, k))
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


def _worker_init() -> None:
    import cv2

    cv2.setNumThreads(1)


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


def _run(tasks: list[tuple[str, Callable[..., dict[str, Any]], tuple[Any, ...]]], workers: int, progress: bool,
         pool: Path) -> tuple[list[dict[str, Any]], dict[str, str]]:
    from synthaug.params import atomic_write_text

    done: list[dict[str, Any]] = []
    failed: dict[str, str] = {}

    def finish(stem: str, result: dict[str, Any] | None, err: BaseException | None) -> None:
        err_file = pool / f"{stem}.error.json"
        if err is None:
            done.append(result or {})
            err_file.unlink(missing_ok=True)
        else:
            msg = f"{type(err).__name__}: {err}"
            failed[stem] = msg
            atomic_write_text(err_file, json.dumps({"stem": stem, "error": msg}))

    try:
        from tqdm.auto import tqdm
    except ImportError:  # pragma: no cover
        tqdm = None
    bar = tqdm(total=len(tasks), desc="ingest", unit="video", disable=not progress or tqdm is None, file=sys.stderr)
    try:
        if workers <= 1:
            for stem, fn, args in tasks:
                try:
                    finish(stem, fn(*args), None)
                except Exception as e:  # one bad input never loses the others
                    finish(stem, None, e)
                bar.update(1)
        else:
            import multiprocessing as mp

            from synthaug._procs import pool_kwargs

            # workers die with this process: a kill -9 of the command leaves nothing running
            with ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn"),
                                     **pool_kwargs(_worker_init)) as ex:
                futs = {ex.submit(fn, *args): stem for stem, fn, args in tasks}
                try:
                    for fut in as_completed(futs):
                        try:
                            finish(futs[fut], fut.result(), None)
                        except Exception as e:
                            finish(futs[fut], None, e)
                        bar.update(1)
                except BaseException:
                    for f in futs:
                        f.cancel()
                    raise
    finally:
        bar.close()
    return done, failed


def select_spread(candidates: Sequence[tuple[str, int]], n: int, rng: np.random.Generator,
                  good: Sequence[bool] | None = None) -> list[int]:
    """Pick ``n`` candidates spread across groups: round-robin over groups in a random order.

    Args:
        candidates: ``(group, key)`` pairs, e.g. ``(video, frame)``.
        n: how many to pick (all when fewer exist).
        rng: numpy Generator for the group and within-group orders.
        good: optional flags; every good candidate is picked (spread across
            groups) before any other.

    Returns:
        Indices into ``candidates``; a prefix of the order for a larger ``n``.

    Example:
        >>> c = [("a", 0), ("a", 1), ("a", 2), ("b", 0), ("c", 0)]
        >>> sorted(c[i][0] for i in select_spread(c, 3, np.random.default_rng(0)))
        ['a', 'b', 'c']
    """
    groups: dict[str, list[int]] = {}
    for i, (g, _) in enumerate(candidates):
        groups.setdefault(g, []).append(i)
    names = sorted(groups)
    order = [names[i] for i in rng.permutation(len(names))]
    queues = {g: [groups[g][i] for i in rng.permutation(len(groups[g]))] for g in order}
    out: list[int] = []
    for tier in ((True, False) if good is not None else (None,)):
        tq = {g: [i for i in q if tier is None or bool(good[i]) == tier] for g, q in queues.items()}
        while len(out) < n and any(tq.values()):
            for g in order:
                if tq[g] and len(out) < n:
                    out.append(tq[g].pop(0))
    return out


def _run_fingerprint(shards: Sequence[Any], cfg: IngestConfig) -> str:
    """The fingerprint of a draw: the options and every shard's fingerprint."""
    return digest({"options": cfg.fingerprint(),
                   "shards": {Path(s.path).name: s.metadata.get("ingest_fingerprint") for s in shards}})


def assemble_seed_sets(out_dir: str | os.PathLike, *, seed_counts: Sequence[int], cfg: IngestConfig,
                       classes: Sequence[str] | None = None, split: str = "train",
                       contact_sheets: bool = True, shards: Sequence[str] | None = None) -> list[dict[str, Any]]:
    """Draw the seed sets ``OUT/seedsets/<class>_<n>`` from the shards in ``OUT/pool``.

    Args:
        shards: the names of the shards to draw from (a run's videos / chunks); default: every shard of the pool
            made with these options.

    Returns:
        One dict per written seed set (path, class, requested and actual counts). Each seed set records the
        fingerprint of the draw (``ingest_fingerprint``: the options and every shard's fingerprint).
    """
    from synthaug.data.contact_sheet import contact_sheet_image, _caption
    from synthaug.data.seedset import SeedSet

    out_dir = Path(out_dir)
    pool = out_dir / "pool"
    if shards is None:
        dirs = [d for d in (sorted(pool.iterdir()) if pool.is_dir() else [])
                if d.is_dir() and not d.name.startswith(".") and _shard_is_current(d, cfg)]
    else:
        dirs = [pool / name for name in sorted(set(shards)) if (pool / name / "seedset.json").is_file()]
    shards = [SeedSet.load(d) for d in dirs]
    run_fp = _run_fingerprint(shards, cfg)
    run_inputs = {"options": cfg.fingerprint(),
                  "shards": {Path(s.path).name: s.metadata.get("ingest_fingerprint") for s in shards}}
    written = []
    pos_classes = sorted({r["class"] for s in shards for r in s.records if r.get("split") == split})
    if classes is not None:
        pos_classes = [c for c in pos_classes if c in classes]
    hard_shards = [s for s in shards if s.metadata.get("shard", {}).get("hard_negative")
                   and s.metadata["shard"].get("split") == split]
    import cv2

    for cls in pos_classes:
        cands: list[tuple[str, int]] = []
        where: list[tuple[int, int]] = []
        for si, s in enumerate(shards):
            for ri, r in enumerate(s.records):
                if r.get("class") == cls and r.get("split") == split:
                    cands.append((r["video"], int(r["frame"])))
                    where.append((si, ri))
        neg_shards = [si for si, s in enumerate(shards)
                      if any(nr.get("class") == cls and nr.get("split") == split and nr.get("kind") == "background"
                             for nr in s.negative_records)]
        rng = np.random.default_rng([cfg.seed, zlib.crc32(cls.encode())])
        good = [shards[si].records[ri].get("background_quality", 0.0) <= cfg.max_background_error
                for si, ri in where]
        order = select_spread(cands, len(cands), rng, good)
        for n in seed_counts:
            pick = [where[k] for k in order[:n]]
            by_shard: dict[int, list[int]] = {}
            for si, ri in pick:
                by_shard.setdefault(si, []).append(ri)
            parts = [(shards[si], by_shard.get(si, []), si in neg_shards) for si in sorted(set(by_shard) | set(neg_shards))]
            parts += [(s, [], True) for s in hard_shards]
            extra = {}
            if contact_sheets and pick:
                pp = np.stack([shards[si].patches[ri] for si, ri in pick])
                bb = np.stack([shards[si].backgrounds[ri] for si, ri in pick])
                sheet = contact_sheet_image(pp, bb, captions=[_caption(shards[si].records[ri]) for si, ri in pick])
                ok, buf = cv2.imencode(".png", sheet)
                extra["contact_sheet.png"] = buf.tobytes()
            path = out_dir / "seedsets" / f"{cls}_{n}"
            meta = {"source": {"pool": str(pool), "class": cls, "split": split, "requested_seeds": n,
                               "videos": sorted({shards[si].records[ri]["video"] for si, ri in pick})},
                    "shard": None, "ingest_fingerprint": run_fp, "ingest_inputs": run_inputs}
            SeedSet.concat_to(path, parts, metadata=meta, extra_files=extra)
            written.append({"path": str(path), "class": cls, "requested": n, "seeds": len(pick),
                            "videos": len(meta["source"]["videos"]), "ingest_fingerprint": run_fp})
    return written


def stale_seed_sets(out_dir: str | os.PathLike, written: Sequence[dict[str, Any]], cfg: IngestConfig,
                    shards: Sequence[str]) -> list[str]:
    """Seed sets under ``OUT/seedsets`` this run did not draw and that an earlier run drew from other inputs
    (another fingerprint than this run's shards would give); each gets a warning."""
    from synthaug.data.seedset import SeedSet

    out_dir = Path(out_dir)
    root = out_dir / "seedsets"
    if not root.is_dir():
        return []
    pool = out_dir / "pool"
    run_fp = _run_fingerprint([SeedSet.load(pool / s) for s in sorted(set(shards))
                               if (pool / s / "seedset.json").is_file()], cfg)
    done = {Path(w["path"]).resolve() for w in written}
    stale = []
    for d in sorted(root.iterdir()):
        head = d / "seedset.json"
        if d.resolve() in done or not head.is_file():
            continue
        try:
            fp = json.loads(head.read_text()).get("ingest_fingerprint")
        except (OSError, ValueError):
            fp = None
        if fp != run_fp:
            stale.append(str(d))
            log.warning("synthaug ingest: %s was drawn by an earlier run from other videos, labels or options and "
                        "is not current (this run did not redraw it); delete it, or rerun with its class and count",
                        d)
    return stale


def _write_report(out_dir: Path, report: dict[str, Any]) -> None:
    from synthaug.params import atomic_write_text

    atomic_write_text(out_dir / "ingest_report.json", json.dumps(report, indent=1, default=str))


def _summarise(done: list[dict[str, Any]], skipped: list[str], failed: dict[str, str], seconds: float) -> dict[str, Any]:
    methods: Counter[str] = Counter()
    cleanup: Counter[str] = Counter()
    for d in done:
        methods.update(d.get("background_methods", {}))
        for k in ("clipped", "dropped", "invalid"):
            cleanup[k] += int(d.get("cleanup", {}).get(k, 0))
        c = d.get("cleanup", {})
        if c.get("frames_decoded", -1) >= 0 and c.get("frames_decoded") != c.get("labels_read"):
            cleanup["length_mismatch_videos"] += 1
    return {"processed": len(done), "skipped_current": len(skipped), "failed": failed,
            "background_methods": dict(methods), "box_cleanup": dict(cleanup), "seconds": round(seconds, 2),
            "videos": {d["stem"]: d for d in done}}


def _check_out(out_dir: str | os.PathLike) -> Path:
    from synthaug._checks import check_output_dir

    out_dir = check_output_dir(out_dir)  # not a file, and no file on the way to it
    for p in (out_dir / "pool", out_dir / "seedsets"):
        if p.exists() and not p.is_dir():
            raise ValueError(f"{p} is a file; the output folder must hold a folder there (--out)")
    return out_dir


def _finish(out_dir: Path, cfg: IngestConfig, seed_counts: Sequence[int], done: list[dict[str, Any]],
            skipped: list[str], failed: dict[str, str], redone: dict[str, str], t0: float) -> dict[str, Any]:
    """The report and the seed sets, drawn from this run's shards only (the reused and the made ones)."""
    report = _summarise(done, skipped, failed, time.perf_counter() - t0)
    report["redone"] = redone
    shards = list(skipped) + [d["stem"] for d in done]
    report["seed_sets"] = assemble_seed_sets(out_dir, seed_counts=seed_counts, cfg=cfg, shards=shards) \
        if seed_counts else []
    report["stale_seed_sets"] = stale_seed_sets(out_dir, report["seed_sets"], cfg, shards) if seed_counts else []
    return report


def ingest_videos(
    video_dir: str | os.PathLike,
    label_dir: str | os.PathLike,
    out_dir: str | os.PathLike,
    *,
    split: str | os.PathLike | Any | None = None,
    splits: Sequence[str] = ("train",),
    cfg: IngestConfig = IngestConfig(),
    seed_counts: Sequence[int] = (12, 25, 50, 100),
    workers: int = 2,
    progress: bool = True,
    redo: bool = False,
    limit: int | None = None,
) -> dict[str, Any]:
    """Ingest every video of ``label_dir`` that belongs to ``splits``, then draw the seed sets.

    Args:
        video_dir: folder of videos, matched to label files by stem.
        label_dir: folder of label JSON files (halmstad format).
        out_dir: output folder (``pool/``, ``seedsets/``, ``ingest_report.json``).
        split: a split file / :class:`~synthaug.data.splits.VideoSplit`; None
            puts every video in ``train`` (hard-negative classes included).
        splits: which splits to ingest (seed sets always come from ``train``).
        cfg: the options.
        seed_counts: seed-set sizes to draw per positive class (empty: none).
        workers: worker processes (1: in this process).
        progress: show a progress bar on stderr.
        redo: reprocess shards even when they are current.
        limit: ingest at most this many videos (quick looks, tests).

    Returns:
        The report (also written to ``OUT/ingest_report.json``).
    """
    from synthaug.data.splits import VideoSplit, load_split
    from synthaug.data.video import iter_video_label_pairs

    t0 = time.perf_counter()
    out_dir = _check_out(out_dir)
    # inputs are checked before the output folder is made: a bad one leaves nothing behind
    vs = split if isinstance(split, VideoSplit) or split is None else load_split(split)
    for s in splits:
        if s not in ("train", "val", "test"):
            raise ValueError(f"splits must be among train/val/test, got {s!r}")
    label_dir = Path(label_dir)
    if not label_dir.is_dir():
        raise FileNotFoundError(f"label folder not found: {label_dir}")
    if not Path(video_dir).is_dir():
        raise FileNotFoundError(f"video folder not found: {video_dir}")
    jobs = []
    pairs = list(iter_video_label_pairs(video_dir, label_dir))
    if not pairs:
        raise ValueError(f"no label file (*.json) in {label_dir}")
    for stem, vpath, lpath in pairs:
        which = "train" if vs is None else vs.split_of(stem)
        if which in splits:
            jobs.append(VideoJob(stem, vpath, lpath, which))
    if limit is not None:
        jobs = jobs[:limit]
    if not jobs:
        raise ValueError(f"no video of {label_dir} belongs to the splits {list(splits)}")
    pool = out_dir / "pool"
    pool.mkdir(parents=True, exist_ok=True)
    _clean_stale(pool)
    todo, skipped, redone = [], [], {}
    for job in jobs:
        current, why = _shard_status(pool / job.stem, cfg, video_inputs(job, cfg), (job.video_path, job.label_path))
        if not redo and current:
            skipped.append(job.stem)
            continue
        if why and not redo:
            redone[job.stem] = why
            log.warning("synthaug ingest: %s: %s changed since its shard was made; ingesting it again", job.stem, why)
        todo.append((job.stem, process_video, (job, cfg, str(pool))))
    done, failed = _run(todo, workers, progress, pool)
    report = _finish(out_dir, cfg, seed_counts, done, skipped, failed, redone, t0)
    report["seconds_total"] = round(time.perf_counter() - t0, 2)
    report["config"] = asdict(cfg)
    _write_report(out_dir, report)
    return report


def ingest_coco(
    coco_path: str | os.PathLike,
    image_dir: str | os.PathLike,
    out_dir: str | os.PathLike,
    *,
    split: str | os.PathLike | None = None,
    cfg: IngestConfig = IngestConfig(),
    seed_counts: Sequence[int] = (12, 25, 50, 100),
    workers: int = 2,
    progress: bool = True,
    redo: bool = False,
    chunk: int = 64,
) -> dict[str, Any]:
    """Ingest an image folder with COCO boxes (backgrounds by inpainting), then draw the seed sets.

    Args:
        coco_path: the COCO JSON file.
        image_dir: folder the COCO ``file_name`` entries are relative to.
        out_dir: output folder, as :func:`ingest_videos`.
        split: optional JSON ``{"train": [...], "val": [...], "test": [...]}``
            of image file names or stems; default: every image in ``train``.
        cfg: the options (``seeds_per_video`` is not used: every box is a seed).
        seed_counts: seed-set sizes per class.
        workers: worker processes.
        progress: progress bar.
        redo: reprocess current shards.
        chunk: images per shard (the unit of resumption).

    Returns:
        The report (also written to ``OUT/ingest_report.json``).
    """
    from synthaug.data.video import read_coco

    t0 = time.perf_counter()
    if chunk < 1:
        raise ValueError(f"chunk must be >= 1, got {chunk}")
    out_dir = _check_out(out_dir)
    # inputs are checked before the output folder is made: a bad one leaves nothing behind
    images = read_coco(coco_path, image_dir, classes=cfg.classes)
    split_of: dict[str, str] = {}
    if split is not None:
        doc = json.loads(Path(split).read_text())
        for s in ("train", "val", "test"):
            for name in doc.get(s, []):
                split_of[str(name)] = s
    pool = out_dir / "pool"
    pool.mkdir(parents=True, exist_ok=True)
    _clean_stale(pool)
    todo, skipped, redone = [], [], {}
    for k in range(0, len(images), chunk):
        name = f"coco_{k // chunk:05d}"
        part = images[k:k + chunk]
        current, why = _shard_status(pool / name, cfg, images_inputs(part, split_of, cfg),
                                     [Path(coco_path)] + [im.path for im in part])
        if not redo and current:
            skipped.append(name)
            continue
        if why and not redo:
            redone[name] = why
            log.warning("synthaug ingest: %s: %s changed since its shard was made; ingesting it again", name, why)
        todo.append((name, process_images, (name, part, split_of, cfg, str(pool), str(coco_path))))
    done, failed = _run(todo, workers, progress, pool)
    report = _finish(out_dir, cfg, seed_counts, done, skipped, failed, redone, t0)
    report["unreadable_images"] = [e for d in done for e in d.get("unreadable", [])]
    report["seconds_total"] = round(time.perf_counter() - t0, 2)
    report["config"] = asdict(cfg)
    _write_report(out_dir, report)
    return report
