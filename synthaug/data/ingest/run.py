"""The ingest commands: :func:`ingest_videos` and :func:`ingest_coco` decide which shards to (re)make, make them
in worker processes (:func:`_run`: one bad input never stops the others), draw the seed sets and write
``OUT/ingest_report.json``.
"""

from __future__ import annotations

import json
import logging
import os
import sys
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict
from pathlib import Path
from typing import Any, Callable, Sequence

from synthaug.data.ingest.seedsets import assemble_seed_sets, stale_seed_sets
from synthaug.data.ingest.shards import (
    IngestConfig,
    VideoJob,
    _clean_stale,
    _shard_status,
    images_inputs,
    process_images,
    process_video,
    video_inputs,
)

log = logging.getLogger("synthaug.ingest")


def _worker_init() -> None:
    import cv2

    cv2.setNumThreads(1)


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
