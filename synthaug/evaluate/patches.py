"""The paper's patch protocol: object crops and background windows of the test frames, scored and measured.

:func:`patch_eval_set` crops every labelled object of the test frames (every
``frame_stride``-th) exactly as seeds are cropped (:func:`synthaug.data.seedset.crop_patch`,
the seed-set geometry, boxes read and clipped by :func:`synthaug.data.video.read_video_with_labels`
as ingest does) and ``negatives_per_positive`` random background windows of the
same frame at the same crop side, each overlapping no labelled box (IoU 0), from a
Generator seeded by ``[patch.seed, crc32(stem)]`` (a video's patches do not
depend on the other videos). :func:`score_patch_set` scores them with a detector
(one :class:`PatchVideoScores` per video, what a
:class:`~synthaug.evaluate.results.ProtocolResult` keeps), :func:`patch_metrics` gives
AP and tie-aware ROC-AUC with video-bootstrap intervals.

Example:
    >>> m = patch_metrics(np.array([0.9, 0.2, 0.8, 0.1]), np.array([1, 0, 0, 1]))
    >>> round(m.ap.estimate, 3), round(m.roc_auc.estimate, 3), m.n_positive, m.n_negative
    (0.75, 0.5, 2, 2)
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from synthaug.data.boxes import xywh_to_xyxy
from synthaug.data.video import VIDEO_EXTENSIONS, find_video
from synthaug.evaluate.protocol import BootstrapSpec, Protocol, split_videos
from synthaug.evaluate.stats import Interval, PooledRanking, bootstrap_seed_mean

__all__ = ["PatchSet", "PatchVideoScores", "patch_eval_set", "score_patch_set", "PatchMetrics", "patch_metrics"]


@dataclass
class PatchSet:
    """The patch-classification test set.

    Attributes:
        patches: uint8 ``(N, P, P)``.
        labels: int8 ``(N,)``, 1 object / 0 background.
        video: ``(N,)`` index into ``stems``.
        stems: the videos.
        frame: ``(N,)`` frame index in its video (position in the label file).
        crop: float32 ``(N, 3)`` ``[c_x, c_y, side]`` in frame pixels.
        info: counts (positives, negatives, negatives not placed, boxes cleaned) and the protocol used.
    """

    patches: np.ndarray
    labels: np.ndarray
    video: np.ndarray
    stems: list[str]
    frame: np.ndarray
    crop: np.ndarray
    info: dict[str, Any] = field(default_factory=dict)

    def __len__(self) -> int:
        return int(self.labels.size)

    def as_float(self) -> Any:
        """Float tensor ``(N, 1, P, P)`` in [0, 1] (what ``PatchDetector.score_patches`` takes)."""
        import torch

        return torch.from_numpy(self.patches).float().div_(255.0)[:, None]


def _find_video(videos_dir: Path, stem: str) -> Path:
    path = find_video(videos_dir, stem)
    if path is None:
        raise ValueError(f"no video file for {stem!r} in {videos_dir} (tried {list(VIDEO_EXTENSIONS)})")
    return path


def _disjoint(cx: float, cy: float, side: float, boxes_xyxy: np.ndarray) -> bool:
    """The square window overlaps no box (IoU 0; touching edges is not overlapping)."""
    h = side / 2
    x0, y0, x1, y1 = cx - h, cy - h, cx + h, cy + h
    b = boxes_xyxy
    inter = (np.minimum(x1, b[:, 2]) > np.maximum(x0, b[:, 0])) & (np.minimum(y1, b[:, 3]) > np.maximum(y0, b[:, 1]))
    return not bool(inter.any())


def patch_eval_set(
    videos_dir: str | Path,
    labels_dir: str | Path,
    split: str,
    protocol: Protocol,
    *,
    videos: Sequence[str] | None = None,
    split_file: str | Path | None = None,
    class_name: str | None = None,
) -> PatchSet:
    """The paper's patch-classification test set of a split's videos.

    Positives: every labelled object of every ``frame_stride``-th frame (the split's), cropped like
    seeds: :func:`synthaug.data.seedset.crop_patch` with ``box=`` and the protocol's
    ``patch_size`` / ``object_fraction`` (the object centred, its longest side spanning
    ``object_fraction * P``), boxes decoded and clipped by
    :func:`synthaug.data.video.read_video_with_labels` as ingest does. Negatives: per positive,
    ``negatives_per_positive`` square windows of the same frame with the positive's crop side,
    uniformly placed inside the frame, overlapping no labelled box of that frame (IoU 0), cropped
    with ``crop_patch(crop=...)``; a window not placed after ``max_tries`` draws is dropped and
    counted (``info["negatives_missing"]``). Randomness: per video
    ``np.random.default_rng([patch.seed, crc32(stem)])``.

    Args:
        videos_dir, labels_dir: the shared-format folders (``<stem>.<ext>``, ``<stem>.json``).
        split: ``"test"`` or ``"val"`` (the protocol's split and frame stride).
        protocol: the protocol.
        videos: the videos (stems); default: the split's, from ``split_file`` or the protocol's.
        split_file: video-split file (when ``videos`` is None).
        class_name: keep only videos of this class (when ``videos`` is None).

    Returns:
        The :class:`PatchSet`, videos in the given order (frame numbers are positions in each
        video's label file; videos are identified by stem, never by number).
    """
    from synthaug.data.seedset import crop_patch
    from synthaug.data.video import read_video_with_labels

    spec = protocol.split(split)
    ps = protocol.patch
    stems = list(videos) if videos is not None else split_videos(protocol, split, split_file=split_file, class_name=class_name)
    if not stems:
        raise ValueError("no video to build patches from")
    if len(set(stems)) != len(stems):
        raise ValueError("a video is listed twice")
    videos_dir, labels_dir = Path(videos_dir), Path(labels_dir)
    patches, labels, vid, frames_idx, crops = [], [], [], [], []
    info: dict[str, Any] = {"protocol": protocol.name, "fingerprint": protocol.fingerprint(), "split": spec.split,
                            "frame_stride": spec.frame_stride, "positives": 0, "negatives": 0, "negatives_missing": 0,
                            "boxes_clipped": 0, "boxes_dropped": 0, "per_video": {}}
    for v, stem in enumerate(stems):
        frames, labs, cleanup = read_video_with_labels(_find_video(videos_dir, stem), labels_dir / f"{stem}.json")
        info["boxes_clipped"] += cleanup.clipped
        info["boxes_dropped"] += cleanup.dropped + cleanup.invalid
        rng = np.random.default_rng([ps.seed, zlib.crc32(stem.encode("utf-8"))])
        h, w = frames.shape[1:3]
        n_pos = n_neg = n_miss = 0
        for f in range(0, len(labs.boxes), spec.frame_stride):
            if labs.boxes[f] is None:
                continue
            boxes = np.asarray(labs.boxes[f], dtype=np.float64).reshape(-1, 4)
            boxes_xyxy = xywh_to_xyxy(boxes)
            for box in boxes:
                patch, crop = crop_patch(frames[f], box=box, patch_size=ps.patch_size, object_fraction=ps.object_fraction)
                patches.append(patch)
                labels.append(1)
                vid.append(v)
                frames_idx.append(f)
                crops.append(crop)
                n_pos += 1
                side = float(crop[2])
                for _ in range(ps.negatives_per_positive):
                    placed = False
                    if side < min(w, h):
                        for _try in range(ps.max_tries):
                            cx = float(rng.uniform(side / 2, w - side / 2))
                            cy = float(rng.uniform(side / 2, h - side / 2))
                            if _disjoint(cx, cy, side, boxes_xyxy):
                                placed = True
                                break
                    if not placed:
                        n_miss += 1
                        continue
                    neg, ncrop = crop_patch(frames[f], crop=[cx, cy, side], patch_size=ps.patch_size)
                    patches.append(neg)
                    labels.append(0)
                    vid.append(v)
                    frames_idx.append(f)
                    crops.append(ncrop)
                    n_neg += 1
        info["per_video"][stem] = {"frames": len(labs.boxes), "positives": n_pos, "negatives": n_neg}
        info["positives"] += n_pos
        info["negatives"] += n_neg
        info["negatives_missing"] += n_miss
        del frames
    p = ps.patch_size
    return PatchSet(
        patches=np.stack(patches).astype(np.uint8) if patches else np.zeros((0, p, p), np.uint8),
        labels=np.asarray(labels, dtype=np.int8), video=np.asarray(vid, dtype=np.int64), stems=stems,
        frame=np.asarray(frames_idx, dtype=np.int64),
        crop=np.stack(crops).astype(np.float32) if crops else np.zeros((0, 3), np.float32), info=info,
    )


@dataclass
class PatchVideoScores:
    """One video's patches scored by a detector: ``scores (N,)`` and ``labels (N,)`` (1 object, 0 background)."""

    stem: str
    scores: np.ndarray
    labels: np.ndarray

    def ranking(self) -> tuple[np.ndarray, np.ndarray, int]:
        lab = self.labels.astype(bool)
        return self.scores, lab, int(lab.sum())

    def to_json(self) -> dict[str, Any]:
        return {"stem": self.stem, "scores": self.scores.tolist(), "labels": self.labels.astype(int).tolist()}

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "PatchVideoScores":
        s = np.asarray(d["scores"], dtype=np.float64).reshape(-1)
        lab = np.asarray(d["labels"], dtype=np.int8).reshape(-1)
        if s.shape != lab.shape:
            raise ValueError(f"patch scores of {d.get('stem')!r}: {s.size} scores but {lab.size} labels")
        return cls(str(d["stem"]), s, lab)


def score_patch_set(detector: Any, patch_set: PatchSet, *, batch_size: int = 4096) -> list[PatchVideoScores]:
    """Score every patch with ``detector.score_patches`` and split the scores by video.

    Raises:
        ValueError: the detector's window differs from the patches' size.
    """
    import torch

    p = int(patch_set.patches.shape[-1]) if len(patch_set) else int(getattr(detector, "window", 40))
    window = int(getattr(detector, "window", p))
    if window != p:
        raise ValueError(f"the detector's window is {window} px, the patches are {p} px")
    scores = np.zeros(len(patch_set), dtype=np.float64)
    with torch.no_grad():
        for start in range(0, len(patch_set), batch_size):
            x = torch.from_numpy(patch_set.patches[start:start + batch_size]).float().div_(255.0)[:, None]
            scores[start:start + x.shape[0]] = detector.score_patches(x).double().cpu().numpy().reshape(-1)
    return [PatchVideoScores(stem, scores[patch_set.video == v], patch_set.labels[patch_set.video == v].copy())
            for v, stem in enumerate(patch_set.stems)]


@dataclass
class PatchMetrics:
    """Patch-classification AP and ROC-AUC (mean over seeds), with video-bootstrap intervals."""

    ap: Interval
    roc_auc: Interval
    n_positive: int
    n_negative: int
    n_videos: int
    seeds: list[Any]

    def to_json(self) -> dict[str, Any]:
        return {"ap": self.ap.to_json(), "roc_auc": self.roc_auc.to_json(), "n_positive": self.n_positive,
                "n_negative": self.n_negative, "n_videos": self.n_videos, "seeds": [str(s) for s in self.seeds]}


def patch_metrics(
    scores: np.ndarray | Mapping[Any, np.ndarray],
    labels: np.ndarray,
    videos: np.ndarray | Sequence[Any] | None = None,
    *,
    bootstrap: BootstrapSpec | None = None,
) -> PatchMetrics:
    """AP (``∫ p(r) dr`` of the ranking, :mod:`synthaug.evaluate.ap`) and tie-aware ROC-AUC of patch scores.

    Args:
        scores: ``(N,)`` scores, or seed id -> ``(N,)`` scores of that seed's detector (the same patches).
        labels: ``(N,)`` 1 object / 0 background.
        videos: ``(N,)`` video of each patch (any hashable ids) — the bootstrap's units; None: no interval.
        bootstrap: resamples, seed, ci (default :class:`BootstrapSpec`: 2000, 0, 0.95).

    Returns:
        :class:`PatchMetrics` (means over seeds; each seed scored on the same video resamples).
    """
    labels = np.asarray(labels).reshape(-1)
    if not np.isin(labels, (0, 1)).all():
        raise ValueError("labels must be 0 or 1")
    per_seed = dict(scores) if isinstance(scores, Mapping) else {0: scores}
    for s, x in per_seed.items():
        if np.asarray(x).reshape(-1).shape != labels.shape:
            raise ValueError(f"seed {s}: {np.asarray(x).size} scores for {labels.size} labels")
    if videos is None:
        vidx, n_vid = np.zeros(labels.size, dtype=np.int64), 1
    else:
        vids = np.asarray(videos).reshape(-1)
        if vids.shape != labels.shape:
            raise ValueError(f"{vids.size} video ids for {labels.size} labels")
        _, vidx = np.unique(vids, return_inverse=True)
        n_vid = int(vidx.max()) + 1 if vidx.size else 0
    lab = labels.astype(bool)
    pools = {}
    for s, x in per_seed.items():
        x = np.asarray(x, dtype=np.float64).reshape(-1)
        pools[s] = PooledRanking([(x[vidx == v], lab[vidx == v], int(lab[vidx == v].sum())) for v in range(n_vid)])
    bs = bootstrap or BootstrapSpec()
    if videos is None:
        est_ap = float(np.mean([p.ap() for p in pools.values()]))
        est_auc = float(np.mean([p.roc_auc() for p in pools.values()]))
        nan = float("nan")
        ap_iv, auc_iv = Interval(est_ap, nan, nan, bs.ci, 0, 0), Interval(est_auc, nan, nan, bs.ci, 0, 0)
    else:
        kw = dict(resamples=bs.resamples, seed=bs.seed, ci=bs.ci)
        ap_iv = bootstrap_seed_mean(pools, metric="ap", **kw)
        auc_iv = bootstrap_seed_mean(pools, metric="roc_auc", **kw)
    return PatchMetrics(ap_iv, auc_iv, int(lab.sum()), int((~lab).sum()), n_vid, list(per_seed))
