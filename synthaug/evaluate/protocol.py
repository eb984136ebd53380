"""The evaluation protocol: one versioned definition of how every experiment measures a detector.

A protocol file (``configs/protocol/<name>.json``, :func:`load_protocol`) fixes
*what* is measured; this module measures it and keeps enough per video to
recompute every number later (other seeds, other subsets of videos, bootstrap
intervals) without running detection again.

Protocol file (``configs/protocol/halmstad_v1.json``)::

    {"name": "halmstad_v1", "version": 1, "description": "...",
     "split_file": "configs/splits/halmstad.json",          # optional (null: the caller names the videos)
     "test": {"split": "test", "frame_stride": 5},         # every 5th frame of every test video of the class
     "val":  {"split": "val",  "frame_stride": 5},
     "min_training_seeds": 3,                              # seeds (data sampling + initialisation) per cell
     "iou_thresholds": [0.5, 0.3],                         # the first is the main one
     "size_buckets_px": [[0, 24], [24, 48], [48, 96], [96, null]],   # [low, high) of the box's longest side
     "scale_check": [2.0, 0.75],                           # test frames resized by these factors, boxes with them
     "bootstrap": {"resamples": 2000, "seed": 0, "ci": 0.95},
     "patch": {"negatives_per_positive": 20, "seed": 0, "patch_size": 40, "object_fraction": 0.7, "max_tries": 100},
     "detection": {"max_detections": 10, "nms_iou": 0.3}}  # optional: how detections are produced for scoring

Every field is validated (unknown fields are errors: a typo must not silently
fall back to a default); :meth:`Protocol.fingerprint` hashes the canonical JSON
of everything but ``description`` — put it in every cache key.

**Frame protocol** (detection AP). Per test video, :func:`match_video` matches the
per-frame detections (``[x, y, w, h, score]``, the format of
:func:`synthaug.detectors.sliding.detect_multiscale` and the detection files)
to the per-frame labelled boxes with :func:`synthaug.evaluate.ap.match_detections`
(VOC rule) at every protocol IoU and keeps a :class:`VideoMatches`: the sorted
scores, their TP flags, each detection's longest side, the longest side of the
object each TP matched, and the longest side of every labelled object. From
these, :mod:`synthaug.evaluate.stats` pools any multiset of videos into one AP
(``∫ p(r) dr``, :mod:`synthaug.evaluate.ap`), so the bootstrap over videos and
paired differences need no detection. Boxes are XYXY inside (torchvision's
``box_convert`` / ``box_iou``); XYWH only at the edges (inputs, label files).

**Size buckets** (COCO semantics, by the longest side of the *labelled* box):
in bucket ``[lo, hi)`` objects outside it are *ignored* — a detection matched
to one is neither TP nor FP — and an unmatched detection counts as FP only if
its own longest side is in the bucket (else it is ignored). The matching is the
one of the all-sizes AP (the TP/FP labels of :func:`match_detections`, the matched
object = the one it overlaps most), then relabelled; it equals COCOeval with
``areaRng`` = the squared edges on square boxes whenever no detection reaches
the IoU threshold with two objects (always true with one object per frame, the
shared label format), which the tests check.

**Scale check**: :func:`scale_frame` / :func:`scale_eval_set` resize test frames
by ``s`` (``cv2.INTER_AREA`` down, ``INTER_LINEAR`` up) and their boxes with them.

**Patch protocol** (the paper's numbers): :func:`patch_eval_set` crops every
labelled object of the test frames (every ``frame_stride``-th) exactly as
seeds are cropped (:func:`synthaug.data.seedset.crop_patch`, the seed-set
geometry, boxes read and clipped by :func:`synthaug.data.video.read_video_with_labels`
as ingest does) and ``negatives_per_positive`` random background windows of the
same frame at the same crop side, each overlapping no labelled box (IoU 0), from a
Generator seeded by ``[patch.seed, crc32(stem)]`` (a video's patches do not
depend on the other videos). :func:`score_patch_set` scores them with a detector,
:func:`patch_metrics` gives AP and tie-aware ROC-AUC with video-bootstrap intervals.

**Results**: a :class:`ProtocolResult` is one condition (detector x training set x
scale) on one split: per training seed, the :class:`VideoMatches` of every test
video and the :class:`PatchVideoScores` of every video's patches; ``to_json`` /
``from_json`` / ``save`` / ``load`` round-trip it exactly, :meth:`ProtocolResult.combine`
merges cells run one seed at a time. :func:`summarize` / :func:`report_table`
render ``condition | seeds | AP@0.5 [95 % CI] | AP@0.3 [CI] | Δ vs baseline [CI]
| videos improved | AP per size bucket | patch AP / ROC-AUC``.

Wiring (what an experiment runner, ``synthaug train`` and ``synthaug evaluate`` do; one cell =
one detector trained with one seed, cached under a key holding ``proto.fingerprint()``)::

    proto = load_protocol()                                 # configs/protocol/halmstad_v1.json
    stems = split_videos(proto, "test", class_name="drone")  # or any folder's videos
    es = load_eval_set(stems, videos_dir, labels_dir, stride_k=proto.test.frame_stride)
    patches = patch_eval_set(videos_dir, labels_dir, "test", proto, videos=stems)   # once per split
    results = {s: ProtocolResult("cnn / real 100", proto, scale=s) for s in (1.0, *proto.scale_check)}
    for seed in range(proto.min_training_seeds):
        det = train_detector(..., seed=seed)
        for s, res in results.items():
            es_s = es if s == 1.0 else scale_eval_set(es, s)
            dets = [[detect_multiscale(det, torch.from_numpy(f).float() / 255, scales=...,
                                       max_detections=proto.detection.max_detections,
                                       nms_iou=proto.detection.nms_iou).numpy() for f in frames]
                    for frames in es_s.frames]
            res.add_seed(seed, videos=match_videos(es_s.stems, dets, es_s.boxes, proto),
                         patches=score_patch_set(det, patches) if s == 1.0 else ())
    results[1.0].save(out / "cnn_real100.json")             # ProtocolResult.load / .combine later
    table = report_table({"real 100": base, "ours": results[1.0], "ours x2": results[2.0]}, baseline="real 100")

Example:
    >>> import numpy as np
    >>> p = Protocol.from_dict(example_protocol_dict())
    >>> p.main_iou, [b.label for b in p.size_buckets]
    (0.5, ['<24 px', '24–48 px', '48–96 px', '≥96 px'])
    >>> dets = [np.array([[10, 10, 20, 20, 0.9], [100, 100, 30, 30, 0.8]]), np.zeros((0, 5))]
    >>> gts = [np.array([[10, 10, 20, 20]]), np.array([[50, 50, 60, 60]])]
    >>> vm = match_video(dets, gts, iou_thresholds=p.iou_thresholds, stem="V_1")
    >>> vm.tp[0].tolist(), vm.gt_size.tolist(), vm.n_objects
    ([True, False], [20.0, 60.0], 2)
    >>> r = ProtocolResult(condition="demo", protocol=p)
    >>> r.add_seed(0, videos=[vm])
    >>> round(r.mean_ap(), 3), round(r.mean_ap(bucket=p.size_buckets[0]), 3)   # the 60-px object is missed
    (0.5, 1.0)
"""

from __future__ import annotations

import hashlib
import json
import math
import zlib
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import numpy as np

from synthaug._io import check_header, read_versioned_json
from synthaug.data.boxes import box_iou, xywh_to_xyxy, xyxy_to_xywh
from synthaug.evaluate.stats import (
    Interval,
    PairedDifference,
    PooledRanking,
    bootstrap_seed_mean,
    paired_difference,
)

__all__ = [
    "DEFAULT_PROTOCOL",
    "ProtocolError",
    "SplitSpec",
    "BootstrapSpec",
    "PatchSpec",
    "DetectionSpec",
    "SizeBucket",
    "Protocol",
    "load_protocol",
    "example_protocol_dict",
    "split_videos",
    "VideoMatches",
    "match_video",
    "match_videos",
    "PatchVideoScores",
    "SeedResult",
    "ProtocolResult",
    "ConditionSummary",
    "summarize",
    "summarize_conditions",
    "report_table",
    "scale_frame",
    "scale_eval_set",
    "PatchSet",
    "patch_eval_set",
    "score_patch_set",
    "PatchMetrics",
    "patch_metrics",
]

DEFAULT_PROTOCOL = Path(__file__).resolve().parents[2] / "configs" / "protocol" / "halmstad_v1.json"
"""The protocol every experiment of the repository uses (a checkout's ``configs/``)."""

RESULT_FORMAT = "synthaug.protocol_result"
RESULT_VERSION = 1


# =========================================================================== protocol file
class ProtocolError(ValueError):
    """A protocol file or dict that cannot be used; the message names the field."""


@dataclass(frozen=True)
class SplitSpec:
    """Which videos and frames a split is scored on.

    Attributes:
        split: the split of the video-split file (``"test"``, ``"val"``, ``"train"``).
        frame_stride: frames ``0, k, 2k, ...`` of every video of the split (frame index = position
            in the label file's ``boxes`` list).
    """

    split: str
    frame_stride: int


@dataclass(frozen=True)
class BootstrapSpec:
    """Bootstrap over test videos: resamples, the seed of its Generator, the confidence level."""

    resamples: int = 2000
    seed: int = 0
    ci: float = 0.95


@dataclass(frozen=True)
class PatchSpec:
    """The patch-classification protocol.

    Attributes:
        negatives_per_positive: background windows drawn per object patch.
        seed: base seed of the negatives' Generator (per video ``[seed, crc32(stem)]``).
        patch_size: P of the patches (the seed sets': 40).
        object_fraction: the labelled box's longest side spans this fraction of P (seed sets: 0.7).
        max_tries: placements tried per negative before giving it up (counted in the patch set's info).
    """

    negatives_per_positive: int = 20
    seed: int = 0
    patch_size: int = 40
    object_fraction: float = 0.7
    max_tries: int = 100


@dataclass(frozen=True)
class DetectionSpec:
    """How detections are produced for scoring: boxes kept per frame and the NMS overlap."""

    max_detections: int = 10
    nms_iou: float = 0.3


@dataclass(frozen=True)
class SizeBucket:
    """Objects whose labelled box's longest side is in ``[low, high)`` pixels (``high=None``: no bound)."""

    low: float
    high: float | None

    @property
    def label(self) -> str:
        """``"<24 px"``, ``"24–48 px"``, ``"≥96 px"``."""
        if self.high is None:
            return f"≥{self.low:g} px"
        if self.low <= 0:
            return f"<{self.high:g} px"
        return f"{self.low:g}–{self.high:g} px"

    def contains(self, sizes: np.ndarray) -> np.ndarray:
        """Boolean mask of ``sizes`` in ``[low, high)`` (NaN: never)."""
        s = np.asarray(sizes, dtype=np.float64)
        with np.errstate(invalid="ignore"):
            m = s >= self.low
            if self.high is not None:
                m &= s < self.high
        return m

    def to_list(self) -> list[float | None]:
        return [self.low, self.high]


@dataclass(frozen=True)
class Protocol:
    """A validated protocol (:func:`load_protocol`). Field meanings: module docstring."""

    name: str
    version: int
    test: SplitSpec
    val: SplitSpec
    min_training_seeds: int
    iou_thresholds: tuple[float, ...]
    size_buckets: tuple[SizeBucket, ...]
    scale_check: tuple[float, ...]
    bootstrap: BootstrapSpec
    patch: PatchSpec
    detection: DetectionSpec = DetectionSpec()
    split_file: str | None = None
    description: str = ""

    @property
    def main_iou(self) -> float:
        """The first IoU threshold (0.5): the headline AP."""
        return self.iou_thresholds[0]

    def split(self, which: str) -> SplitSpec:
        """``"test"`` or ``"val"``."""
        if which not in ("test", "val"):
            raise ValueError(f"which must be 'test' or 'val', got {which!r}")
        return self.test if which == "test" else self.val

    def to_dict(self) -> dict[str, Any]:
        """The protocol as a JSON-ready dict (defaults filled in; :meth:`from_dict` reads it back)."""
        return {
            "name": self.name,
            "version": self.version,
            "description": self.description,
            "split_file": self.split_file,
            "test": asdict(self.test),
            "val": asdict(self.val),
            "min_training_seeds": self.min_training_seeds,
            "iou_thresholds": list(self.iou_thresholds),
            "size_buckets_px": [b.to_list() for b in self.size_buckets],
            "scale_check": list(self.scale_check),
            "bootstrap": asdict(self.bootstrap),
            "patch": asdict(self.patch),
            "detection": asdict(self.detection),
        }

    def fingerprint(self) -> str:
        """16 hex digits of the SHA-256 of the canonical JSON (sorted keys, no spaces, without
        ``description``): equal for protocols that measure the same thing, whatever their file layout."""
        d = self.to_dict()
        d.pop("description")
        text = json.dumps(d, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
        return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]

    @classmethod
    def from_dict(cls, doc: Mapping[str, Any], *, source: str = "protocol") -> "Protocol":
        """Validate a protocol dict; :class:`ProtocolError` names ``source`` and the faulty field."""
        return _parse_protocol(doc, source)


def _err(source: str, field_: str, msg: str, got: Any = ...) -> ProtocolError:
    tail = "" if got is ... else f", got {got!r}"
    return ProtocolError(f"{source}: field '{field_}' {msg}{tail}")


def _obj(doc: Any, source: str, path: str, required: Sequence[str], optional: Sequence[str] = ()) -> Mapping[str, Any]:
    if not isinstance(doc, Mapping):
        raise _err(source, path or "<root>", "must be a JSON object", doc)
    prefix = f"{path}." if path else ""
    for k in required:
        if k not in doc:
            raise _err(source, prefix + k, "is missing")
    unknown = sorted(set(doc) - set(required) - set(optional))
    if unknown:
        raise _err(source, prefix + unknown[0], f"is not a protocol field (known here: {sorted([*required, *optional])})")
    return doc


def _int(v: Any, source: str, path: str, minimum: int) -> int:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or isinstance(v, float) and not v.is_integer():
        raise _err(source, path, f"must be an integer >= {minimum}", v)
    if v < minimum:
        raise _err(source, path, f"must be an integer >= {minimum}", v)
    return int(v)


def _num(v: Any, source: str, path: str, *, low: float, high: float | None = None, low_open: bool = False,
         high_open: bool = False) -> float:
    lo_b = "(" if low_open else "["
    hi_b = ")" if high_open or high is None else "]"
    rng = f"{lo_b}{low:g}, {'∞' if high is None else f'{high:g}'}{hi_b}"
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(float(v)):
        raise _err(source, path, f"must be a number in {rng}", v)
    x = float(v)
    if x < low or (low_open and x == low) or (high is not None and (x > high or (high_open and x == high))):
        raise _err(source, path, f"must be a number in {rng}", v)
    return x


def _parse_protocol(doc: Mapping[str, Any], source: str) -> Protocol:
    from synthaug.data.splits import SPLITS

    top = _obj(doc, source, "", ["name", "version", "test", "val", "min_training_seeds", "iou_thresholds",
                                 "size_buckets_px", "scale_check", "bootstrap", "patch"],
               ["description", "split_file", "detection"])
    name = top["name"]
    if not isinstance(name, str) or not name.strip():
        raise _err(source, "name", "must be a non-empty string", name)
    version = _int(top["version"], source, "version", 1)
    desc = top.get("description", "")
    if not isinstance(desc, str):
        raise _err(source, "description", "must be a string", desc)
    split_file = top.get("split_file")
    if split_file is not None and (not isinstance(split_file, str) or not split_file):
        raise _err(source, "split_file", "must be a path string or null", split_file)

    def split_spec(key: str) -> SplitSpec:
        d = _obj(top[key], source, key, ["split", "frame_stride"])
        if d["split"] not in SPLITS:
            raise _err(source, f"{key}.split", f"must be one of {list(SPLITS)}", d["split"])
        return SplitSpec(str(d["split"]), _int(d["frame_stride"], source, f"{key}.frame_stride", 1))

    test, val = split_spec("test"), split_spec("val")
    min_seeds = _int(top["min_training_seeds"], source, "min_training_seeds", 1)

    ious = top["iou_thresholds"]
    if not isinstance(ious, list) or not ious:
        raise _err(source, "iou_thresholds", "must be a non-empty list of numbers in (0, 1]", ious)
    iou_t = tuple(_num(v, source, f"iou_thresholds[{i}]", low=0.0, high=1.0, low_open=True) for i, v in enumerate(ious))
    if len(set(iou_t)) != len(iou_t):
        raise _err(source, "iou_thresholds", "must not repeat a value", ious)

    raw_b = top["size_buckets_px"]
    if not isinstance(raw_b, list) or not raw_b:
        raise _err(source, "size_buckets_px", "must be a non-empty list of [low, high] pairs (high may be null)", raw_b)
    buckets = []
    for i, b in enumerate(raw_b):
        p = f"size_buckets_px[{i}]"
        if not isinstance(b, list) or len(b) != 2:
            raise _err(source, p, "must be a [low, high] pair (high may be null)", b)
        lo = _num(b[0], source, f"{p}[0]", low=0.0)
        hi = None if b[1] is None else _num(b[1], source, f"{p}[1]", low=lo, low_open=True)
        if hi is None and i != len(raw_b) - 1:
            raise _err(source, f"{p}[1]", "may be null (no upper bound) only in the last bucket", b)
        if buckets and lo < buckets[-1].high:  # type: ignore[operator]
            raise _err(source, p, f"must start at or after the previous bucket's end {buckets[-1].high:g} "
                                  "(buckets sorted, not overlapping)", b)
        buckets.append(SizeBucket(lo, hi))

    sc = top["scale_check"]
    if not isinstance(sc, list):
        raise _err(source, "scale_check", "must be a list of positive numbers (may be empty)", sc)
    scales = tuple(_num(v, source, f"scale_check[{i}]", low=0.0, low_open=True) for i, v in enumerate(sc))
    if len(set(scales)) != len(scales):
        raise _err(source, "scale_check", "must not repeat a value", sc)

    bd = _obj(top["bootstrap"], source, "bootstrap", ["resamples", "seed", "ci"])
    boot = BootstrapSpec(_int(bd["resamples"], source, "bootstrap.resamples", 1), _int(bd["seed"], source, "bootstrap.seed", 0),
                         _num(bd["ci"], source, "bootstrap.ci", low=0.0, high=1.0, low_open=True, high_open=True))

    pd = _obj(top["patch"], source, "patch", ["negatives_per_positive", "seed"], ["patch_size", "object_fraction", "max_tries"])
    dflt = PatchSpec()
    patch = PatchSpec(
        negatives_per_positive=_int(pd["negatives_per_positive"], source, "patch.negatives_per_positive", 1),
        seed=_int(pd["seed"], source, "patch.seed", 0),
        patch_size=_int(pd.get("patch_size", dflt.patch_size), source, "patch.patch_size", 8),
        object_fraction=_num(pd.get("object_fraction", dflt.object_fraction), source, "patch.object_fraction",
                             low=0.0, high=1.0, low_open=True),
        max_tries=_int(pd.get("max_tries", dflt.max_tries), source, "patch.max_tries", 1),
    )
    dd = _obj(top.get("detection", {}), source, "detection", [], ["max_detections", "nms_iou"])
    ddf = DetectionSpec()
    det = DetectionSpec(_int(dd.get("max_detections", ddf.max_detections), source, "detection.max_detections", 1),
                        _num(dd.get("nms_iou", ddf.nms_iou), source, "detection.nms_iou", low=0.0, high=1.0, low_open=True))
    return Protocol(name=name, version=version, test=test, val=val, min_training_seeds=min_seeds, iou_thresholds=iou_t,
                    size_buckets=tuple(buckets), scale_check=scales, bootstrap=boot, patch=patch, detection=det,
                    split_file=split_file, description=desc)


def load_protocol(path: str | Path = DEFAULT_PROTOCOL) -> Protocol:
    """Read and validate a protocol file.

    Raises:
        ProtocolError: missing/unreadable/non-JSON file, or a bad field (named in the message).
    """
    path = Path(path)
    try:
        doc = json.loads(path.read_text())
    except FileNotFoundError:
        raise ProtocolError(f"protocol file not found: {path}") from None
    except (OSError, UnicodeDecodeError) as e:
        raise ProtocolError(f"protocol file {path} cannot be read ({e})") from None
    except json.JSONDecodeError as e:
        raise ProtocolError(f"protocol file {path} is not valid JSON ({e})") from None
    return _parse_protocol(doc, f"protocol {path}")


def example_protocol_dict(**overrides: Any) -> dict[str, Any]:
    """The ``halmstad_v1`` fields as a dict (tests, docs), top-level fields replaced by ``overrides``."""
    d: dict[str, Any] = {
        "name": "halmstad_v1", "version": 1, "split_file": "configs/splits/halmstad.json",
        "test": {"split": "test", "frame_stride": 5}, "val": {"split": "val", "frame_stride": 5},
        "min_training_seeds": 3, "iou_thresholds": [0.5, 0.3],
        "size_buckets_px": [[0, 24], [24, 48], [48, 96], [96, None]], "scale_check": [2.0, 0.75],
        "bootstrap": {"resamples": 2000, "seed": 0, "ci": 0.95},
        "patch": {"negatives_per_positive": 20, "seed": 0, "patch_size": 40, "object_fraction": 0.7, "max_tries": 100},
        "detection": {"max_detections": 10, "nms_iou": 0.3},
    }
    d.update(overrides)
    return d


def split_videos(protocol: Protocol, which: str = "test", *, split_file: str | Path | None = None,
                 class_name: str | None = None) -> list[str]:
    """The positive videos of the protocol's ``which`` split (``"test"``/``"val"``), optionally of one class.

    Args:
        protocol: the protocol (its ``split_file`` unless ``split_file`` is given; a relative
            path is taken from the current folder).
        which: ``"test"`` or ``"val"``.
        split_file: the video-split file to use instead.
        class_name: keep videos of this class only (the split file's ``classes``).

    Raises:
        ValueError: no split file, or no video left.
    """
    from synthaug.data.splits import load_split

    path = split_file if split_file is not None else protocol.split_file
    if path is None:
        raise ValueError(f"protocol {protocol.name} names no split_file: pass split_file= or the videos themselves")
    vs = load_split(path)
    name = protocol.split(which).split
    stems = [v for v in vs.videos[name] if class_name is None or vs.classes.get(v) == class_name]
    if not stems:
        raise ValueError(f"no {name} video{'' if class_name is None else f' of class {class_name!r}'} in {path}")
    return stems


# =========================================================================== per-video matching
def _longest_side(xyxy: np.ndarray) -> np.ndarray:
    b = np.asarray(xyxy, dtype=np.float64).reshape(-1, 4)
    return np.maximum(b[:, 2] - b[:, 0], b[:, 3] - b[:, 1])


def _iou_index(thresholds: Sequence[float], iou: float) -> int:
    for k, t in enumerate(thresholds):
        if math.isclose(t, iou, rel_tol=0, abs_tol=1e-9):
            return k
    raise ValueError(f"IoU {iou} was not matched; available: {list(thresholds)}")


@dataclass
class VideoMatches:
    """One video's detections matched to its objects at every protocol IoU.

    Attributes:
        stem: the video.
        n_frames: frames scored (processed; the objects of the others do not count).
        iou_thresholds: the matching IoUs, ``(K,)``.
        scores: ``(D,)`` detection scores, decreasing (:func:`synthaug.evaluate.ap.match_detections`'s order).
        tp: ``(K, D)`` bool, true positive at each IoU.
        det_size: ``(D,)`` longest side of each detection's box (pixels).
        match_size: ``(K, D)`` longest side of the labelled box each TP matched (NaN for a false positive).
        gt_size: ``(G,)`` longest side of every labelled object of the scored frames.
    """

    stem: str
    n_frames: int
    iou_thresholds: tuple[float, ...]
    scores: np.ndarray
    tp: np.ndarray
    det_size: np.ndarray
    match_size: np.ndarray
    gt_size: np.ndarray

    @property
    def n_objects(self) -> int:
        return int(self.gt_size.size)

    @property
    def n_detections(self) -> int:
        return int(self.scores.size)

    def ranking(self, iou: float | None = None, bucket: SizeBucket | Sequence[float | None] | None = None
                ) -> tuple[np.ndarray, np.ndarray, int]:
        """``(scores, is_tp, n_objects)`` at ``iou`` (default: the first), restricted to a size bucket.

        With a bucket (COCO semantics): a TP counts only if its object is in the bucket (else the
        detection is ignored); an FP counts only if its own longest side is in the bucket (else
        ignored); ``n_objects`` counts the objects in the bucket.
        """
        k = 0 if iou is None else _iou_index(self.iou_thresholds, iou)
        tp = self.tp[k]
        if bucket is None:
            return self.scores, tp, self.n_objects
        b = bucket if isinstance(bucket, SizeBucket) else SizeBucket(float(bucket[0]), None if bucket[1] is None else float(bucket[1]))
        keep = np.where(tp, b.contains(self.match_size[k]), b.contains(self.det_size))
        return self.scores[keep], tp[keep], int(b.contains(self.gt_size).sum())

    def to_json(self) -> dict[str, Any]:
        return {
            "stem": self.stem, "n_frames": self.n_frames, "iou_thresholds": list(self.iou_thresholds),
            "scores": self.scores.tolist(), "tp": self.tp.astype(int).tolist(), "det_size": self.det_size.tolist(),
            "match_size": [[None if math.isnan(v) else v for v in row] for row in self.match_size.tolist()],
            "gt_size": self.gt_size.tolist(),
        }

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> "VideoMatches":
        k = len(d["iou_thresholds"])
        n = len(d["scores"])
        vm = cls(
            stem=str(d["stem"]), n_frames=int(d["n_frames"]), iou_thresholds=tuple(float(t) for t in d["iou_thresholds"]),
            scores=np.asarray(d["scores"], dtype=np.float64).reshape(n),
            tp=np.asarray(d["tp"], dtype=bool).reshape(k, n),
            det_size=np.asarray(d["det_size"], dtype=np.float64).reshape(n),
            match_size=np.array([[np.nan if v is None else v for v in row] for row in d["match_size"]], dtype=np.float64).reshape(k, n),
            gt_size=np.asarray(d["gt_size"], dtype=np.float64).reshape(-1),
        )
        return vm


def match_video(
    detections: Sequence[np.ndarray | None],
    ground_truth: Sequence[np.ndarray | None],
    *,
    iou_thresholds: Sequence[float] = (0.5, 0.3),
    stem: str = "",
) -> VideoMatches:
    """Match one video's per-frame detections to its labelled boxes at every IoU.

    Args:
        detections: per frame ``(K, 5)`` ``[x, y, w, h, score]`` or None (frame not processed:
            it and its objects are left out), as :func:`synthaug.evaluate.ap.match_detections`.
        ground_truth: per frame ``(G, 4)`` ``[x, y, w, h]`` or None (no object).
        iou_thresholds: the protocol's IoUs.
        stem: the video's name.

    Returns:
        The :class:`VideoMatches`. TP/FP labels are :func:`match_detections`' (VOC rule); the
        object a TP matched is the one it overlaps most (the rule's candidate).
    """
    from synthaug.evaluate.ap import match_detections

    frames = min(len(detections), len(ground_truth))
    raw_scores, det_size, best_iou, best_size, gt_size = [], [], [], [], []
    n_frames = 0
    for f in range(frames):
        if detections[f] is None:
            continue
        n_frames += 1
        d = np.asarray(detections[f], dtype=np.float64).reshape(-1, 5)
        g = np.zeros((0, 4)) if ground_truth[f] is None else np.asarray(ground_truth[f], dtype=np.float64).reshape(-1, 4)
        d_xyxy, g_xyxy = xywh_to_xyxy(d[:, :4]), xywh_to_xyxy(g)
        gs = _longest_side(g_xyxy)
        gt_size.append(gs)
        raw_scores.append(d[:, 4])
        det_size.append(_longest_side(d_xyxy))
        if g.shape[0] and d.shape[0]:
            iou = box_iou(d_xyxy, g_xyxy)
            j = np.argmax(iou, axis=1)
            best_iou.append(iou[np.arange(d.shape[0]), j])
            best_size.append(gs[j])
        else:
            best_iou.append(np.zeros(d.shape[0]))
            best_size.append(np.full(d.shape[0], np.nan))
    cat = lambda xs: np.concatenate(xs) if xs else np.zeros(0)  # noqa: E731
    raw, dsz, biou, bsz, gsz = cat(raw_scores), cat(det_size), cat(best_iou), cat(best_size), cat(gt_size)
    if not np.all(np.isfinite(raw)):
        raise ValueError(f"video {stem!r}: detection scores must be finite")
    order = np.argsort(-raw, kind="stable")  # match_detections' order: by score, frame order on ties
    ious = tuple(float(t) for t in iou_thresholds)
    tps, msz = [], []
    for t in ious:
        scores, is_tp, n_gt, n_fr = match_detections(detections, ground_truth, t)
        if not np.array_equal(scores, raw[order]) or n_gt != gsz.size or n_fr != n_frames:
            raise AssertionError(f"video {stem!r}: detection order disagrees with match_detections")
        if np.any(biou[order][is_tp] < t):
            raise AssertionError(f"video {stem!r}: a true positive below IoU {t}")
        tps.append(is_tp)
        msz.append(np.where(is_tp, bsz[order], np.nan))
    return VideoMatches(stem=stem, n_frames=n_frames, iou_thresholds=ious, scores=raw[order],
                        tp=np.array(tps, dtype=bool).reshape(len(ious), raw.size), det_size=dsz[order],
                        match_size=np.array(msz, dtype=np.float64).reshape(len(ious), raw.size), gt_size=gsz)


def match_videos(
    stems: Sequence[str],
    detections: Sequence[Sequence[np.ndarray | None]],
    ground_truth: Sequence[Sequence[np.ndarray | None]],
    protocol: Protocol,
) -> list[VideoMatches]:
    """:func:`match_video` for every video (e.g. an ``EvalSet``'s ``stems`` and ``boxes``) at the protocol's IoUs."""
    if not (len(stems) == len(detections) == len(ground_truth)):
        raise ValueError(f"{len(stems)} stems, {len(detections)} detection lists, {len(ground_truth)} ground-truth lists")
    return [match_video(d, g, iou_thresholds=protocol.iou_thresholds, stem=s) for s, d, g in zip(stems, detections, ground_truth)]


# =========================================================================== results
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


@dataclass
class SeedResult:
    """What one training seed's detector gave: frame matches and patch scores per video, and metadata."""

    videos: list[VideoMatches] = field(default_factory=list)
    patches: list[PatchVideoScores] = field(default_factory=list)
    meta: dict[str, Any] = field(default_factory=dict)


def _sorted_by_stem(items: Iterable[Any], what: str) -> list[Any]:
    items = list(items)
    stems = [x.stem for x in items]
    if len(set(stems)) != len(stems):
        dup = sorted({s for s in stems if stems.count(s) > 1})
        raise ValueError(f"{what}: video(s) listed twice: {dup}")
    return sorted(items, key=lambda x: x.stem)


@dataclass
class ProtocolResult:
    """One condition (detector x training set x scale) measured with a protocol on one split.

    Attributes:
        condition: a label (``"cnn / real 100 seeds"``).
        protocol: the protocol it was measured with (stored whole in the JSON).
        split: ``"test"`` or ``"val"``.
        scale: the scale-check factor of the test frames (1.0: as recorded).
        seeds: training seed id -> :class:`SeedResult` (videos sorted by stem).
        meta: free-form (detector kind, training set, budgets, timings...).
    """

    condition: str
    protocol: Protocol
    split: str = "test"
    scale: float = 1.0
    seeds: dict[int, SeedResult] = field(default_factory=dict)
    meta: dict[str, Any] = field(default_factory=dict)
    _pools: dict[Any, dict[int, PooledRanking]] = field(default_factory=dict, init=False, repr=False, compare=False)

    # building ---------------------------------------------------------------
    def add_seed(self, seed: int, *, videos: Sequence[VideoMatches] = (), patches: Sequence[PatchVideoScores] = (),
                 meta: Mapping[str, Any] | None = None, overwrite: bool = False) -> None:
        """Record what the detector trained with ``seed`` gave.

        Raises:
            ValueError: seed already present (unless ``overwrite``), a video twice, IoUs other than
                the protocol's, or videos different from the other seeds'.
        """
        seed = int(seed)
        if seed in self.seeds and not overwrite:
            raise ValueError(f"{self.condition}: seed {seed} is already recorded")
        vids = _sorted_by_stem(videos, f"{self.condition} seed {seed}")
        pats = _sorted_by_stem(patches, f"{self.condition} seed {seed} patches")
        for v in vids:
            if tuple(v.iou_thresholds) != tuple(self.protocol.iou_thresholds):
                raise ValueError(f"{self.condition} seed {seed}, video {v.stem}: matched at IoUs {list(v.iou_thresholds)}, "
                                 f"the protocol's are {list(self.protocol.iou_thresholds)}")
        for other_seed, other in self.seeds.items():
            if other_seed == seed:
                continue
            if vids and other.videos and [v.stem for v in vids] != [v.stem for v in other.videos]:
                raise ValueError(f"{self.condition}: seed {seed} was scored on other videos than seed {other_seed}")
            if pats and other.patches and [p.stem for p in pats] != [p.stem for p in other.patches]:
                raise ValueError(f"{self.condition}: seed {seed}'s patches come from other videos than seed {other_seed}'s")
        self.seeds[seed] = SeedResult(vids, pats, dict(meta or {}))
        self._pools.clear()

    @classmethod
    def combine(cls, results: Sequence["ProtocolResult"], condition: str | None = None) -> "ProtocolResult":
        """Merge results of the same condition run one seed (or a few) at a time.

        Raises:
            ValueError: different protocols (fingerprints), splits or scales, or a seed twice.
        """
        if not results:
            raise ValueError("nothing to combine")
        first = results[0]
        out = cls(condition or first.condition, first.protocol, first.split, first.scale, {}, dict(first.meta))
        for r in results:
            if r.protocol.fingerprint() != first.protocol.fingerprint():
                raise ValueError(f"cannot combine results of protocols {first.protocol.name} ({first.protocol.fingerprint()}) "
                                 f"and {r.protocol.name} ({r.protocol.fingerprint()})")
            if r.split != first.split or r.scale != first.scale:
                raise ValueError(f"cannot combine split/scale {first.split}/{first.scale:g} with {r.split}/{r.scale:g}")
            for s, sr in r.seeds.items():
                out.add_seed(s, videos=sr.videos, patches=sr.patches, meta=sr.meta)
        return out

    # reading ----------------------------------------------------------------
    @property
    def seed_ids(self) -> list[int]:
        return sorted(self.seeds)

    @property
    def meets_min_seeds(self) -> bool:
        """At least the protocol's ``min_training_seeds`` seeds with results (frames or patches)."""
        return len([s for s in self.seeds.values() if s.videos or s.patches]) >= self.protocol.min_training_seeds

    @property
    def stems(self) -> list[str]:
        """The scored videos (sorted): the bootstrap's resampling units."""
        for s in self.seed_ids:
            if self.seeds[s].videos:
                return [v.stem for v in self.seeds[s].videos]
        return []

    @property
    def patch_stems(self) -> list[str]:
        for s in self.seed_ids:
            if self.seeds[s].patches:
                return [p.stem for p in self.seeds[s].patches]
        return []

    def _bucket(self, bucket: SizeBucket | int | None) -> SizeBucket | None:
        if bucket is None or isinstance(bucket, SizeBucket):
            return bucket
        return self.protocol.size_buckets[int(bucket)]

    def pools(self, iou: float | None = None, bucket: SizeBucket | int | None = None) -> dict[int, PooledRanking]:
        """Seed -> :class:`~synthaug.evaluate.stats.PooledRanking` of its videos (sorted by stem) at
        ``iou`` (default: the main one), in a size bucket (a :class:`SizeBucket` or its index)."""
        b = self._bucket(bucket)
        key = ("frames", self.protocol.main_iou if iou is None else float(iou), None if b is None else (b.low, b.high))
        if key not in self._pools:  # kept: their memoised bootstrap values are reused by paired differences
            self._pools[key] = {s: PooledRanking([v.ranking(iou, b) for v in self.seeds[s].videos])
                                for s in self.seed_ids if self.seeds[s].videos}
        return dict(self._pools[key])

    def patch_pools(self) -> dict[int, PooledRanking]:
        """Seed -> the pooled patch rankings (per video)."""
        if "patches" not in self._pools:
            self._pools["patches"] = {s: PooledRanking([p.ranking() for p in self.seeds[s].patches])
                                      for s in self.seed_ids if self.seeds[s].patches}
        return dict(self._pools["patches"])

    def per_seed_ap(self, iou: float | None = None, bucket: SizeBucket | int | None = None) -> dict[int, float]:
        """Seed -> AP of all its videos pooled (NaN without objects)."""
        return {s: p.ap() for s, p in self.pools(iou, bucket).items()}

    def mean_ap(self, iou: float | None = None, bucket: SizeBucket | int | None = None) -> float:
        """Mean over seeds of the pooled AP (NaN when there is no seed or no object)."""
        v = list(self.per_seed_ap(iou, bucket).values())
        return float(np.mean(v)) if v else float("nan")

    def n_objects(self, bucket: SizeBucket | int | None = None) -> int:
        """Labelled objects in the scored frames (in the bucket)."""
        b = self._bucket(bucket)
        for s in self.seed_ids:
            if self.seeds[s].videos:
                return int(sum(v.ranking(None, b)[2] for v in self.seeds[s].videos))
        return 0

    # serialisation ------------------------------------------------------------
    def to_json(self) -> dict[str, Any]:
        return {
            "format": RESULT_FORMAT, "version": RESULT_VERSION, "condition": self.condition, "split": self.split,
            "scale": self.scale, "protocol": self.protocol.to_dict(), "fingerprint": self.protocol.fingerprint(),
            "meta": self.meta,
            "seeds": {str(s): {"meta": sr.meta, "videos": [v.to_json() for v in sr.videos],
                               "patches": [p.to_json() for p in sr.patches]} for s, sr in sorted(self.seeds.items())},
        }

    @classmethod
    def from_json(cls, d: Mapping[str, Any], *, source: str | Path | None = None) -> "ProtocolResult":
        """Rebuild a result from :meth:`to_json`'s document; ``source`` (a file) is named in errors."""
        d = check_header(d, format=RESULT_FORMAT, version=RESULT_VERSION, what="protocol result", source=source)
        proto = Protocol.from_dict(d["protocol"], source="result's protocol")
        if d.get("fingerprint") not in (None, proto.fingerprint()):
            raise ValueError(f"result's protocol fingerprint {d.get('fingerprint')} != its protocol's {proto.fingerprint()}")
        r = cls(str(d["condition"]), proto, str(d.get("split", "test")), float(d.get("scale", 1.0)), {}, dict(d.get("meta", {})))
        for s, sd in d.get("seeds", {}).items():
            r.add_seed(int(s), videos=[VideoMatches.from_json(v) for v in sd.get("videos", [])],
                       patches=[PatchVideoScores.from_json(p) for p in sd.get("patches", [])], meta=sd.get("meta", {}))
        return r

    def save(self, path: str | Path) -> Path:
        """Write the JSON atomically (parent folders created)."""
        from synthaug._io import atomic_write_text

        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(path, json.dumps(self.to_json(), separators=(",", ":")) + "\n")
        return path

    @classmethod
    def load(cls, path: str | Path) -> "ProtocolResult":
        return cls.from_json(read_versioned_json(path, format=RESULT_FORMAT, version=RESULT_VERSION,
                                                 what="protocol result"), source=path)


# =========================================================================== summaries and the table
@dataclass
class ConditionSummary:
    """The numbers of one row of :func:`report_table`.

    Attributes:
        condition, split, scale: as the result.
        seeds: seed ids with frame results (else with patch results); ``meets_min_seeds``: at least the protocol's minimum.
        n_videos: test videos (bootstrap units).
        ap: IoU -> mean-over-seeds pooled AP with its video-bootstrap interval.
        buckets: size-bucket label -> mean-over-seeds AP at the main IoU (NaN: no object in it).
        bucket_objects: size-bucket label -> labelled objects in it.
        paired: difference to the baseline at the main IoU (None for the baseline or incomparable results).
        paired_note: why there is no paired difference, when there is none.
        patch_ap, patch_auc: patch-classification AP and ROC-AUC with intervals (None without patches).
        n_patches: ``{"positive": n, "negative": n}``.
    """

    condition: str
    split: str
    scale: float
    seeds: list[int]
    meets_min_seeds: bool
    n_videos: int
    ap: dict[float, Interval]
    buckets: dict[str, float]
    bucket_objects: dict[str, int]
    paired: PairedDifference | None = None
    paired_note: str = ""
    patch_ap: Interval | None = None
    patch_auc: Interval | None = None
    n_patches: dict[str, int] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        return {
            "condition": self.condition, "split": self.split, "scale": self.scale, "seeds": self.seeds,
            "meets_min_seeds": self.meets_min_seeds, "n_videos": self.n_videos,
            "ap": {f"{k:g}": v.to_json() for k, v in self.ap.items()},
            "buckets": {k: (None if math.isnan(v) else v) for k, v in self.buckets.items()},
            "bucket_objects": self.bucket_objects,
            "paired": None if self.paired is None else self.paired.to_json(), "paired_note": self.paired_note,
            "patch_ap": None if self.patch_ap is None else self.patch_ap.to_json(),
            "patch_auc": None if self.patch_auc is None else self.patch_auc.to_json(),
            "n_patches": self.n_patches,
        }


def summarize(result: ProtocolResult, baseline: ProtocolResult | None = None) -> ConditionSummary:
    """Every number of a condition: APs with CIs, per-bucket AP, patch metrics, and the paired
    difference to ``baseline`` (same protocol; same videos; seeds paired by id)."""
    p = result.protocol
    bs = p.bootstrap
    kw = dict(resamples=bs.resamples, seed=bs.seed, ci=bs.ci)
    ap: dict[float, Interval] = {}
    pools_main = result.pools(p.main_iou)
    if pools_main:
        for t in p.iou_thresholds:
            ap[t] = bootstrap_seed_mean(result.pools(t), **kw)
    buckets = {b.label: result.mean_ap(p.main_iou, b) for b in p.size_buckets}
    bucket_objects = {b.label: result.n_objects(b) for b in p.size_buckets}
    paired, note = None, ""
    if baseline is not None and baseline is not result:
        if baseline.protocol.fingerprint() != p.fingerprint():
            note = "other protocol"
        elif baseline.stems != result.stems or not pools_main:
            note = "other videos"
        else:
            base_pools = baseline.pools(p.main_iou)
            if not set(base_pools) & set(pools_main):
                note = "no common seed"
            else:
                paired = paired_difference(base_pools, pools_main, stems=result.stems, **kw)
    patch_ap = patch_auc = None
    n_patches: dict[str, int] = {}
    pp = result.patch_pools()
    if pp:
        patch_ap = bootstrap_seed_mean(pp, metric="ap", **kw)
        patch_auc = bootstrap_seed_mean(pp, metric="roc_auc", **kw)
        first = result.seeds[next(iter(pp))].patches
        npos = int(sum(x.labels.sum() for x in first))
        n_patches = {"positive": npos, "negative": int(sum(x.labels.size for x in first)) - npos}
    return ConditionSummary(result.condition, result.split, result.scale, list(pools_main or pp), result.meets_min_seeds,
                            len(result.stems or result.patch_stems), ap, buckets, bucket_objects, paired, note, patch_ap, patch_auc, n_patches)


def summarize_conditions(results: Mapping[str, ProtocolResult], baseline: str | None = None) -> dict[str, ConditionSummary]:
    """:func:`summarize` for every condition (keys are the row labels), paired with ``results[baseline]``.

    Raises:
        ValueError: results measured with different protocols, or an unknown baseline.
    """
    if not results:
        raise ValueError("no result to summarize")
    fps = {r.protocol.fingerprint() for r in results.values()}
    if len(fps) != 1:
        raise ValueError(f"results were measured with different protocols ({sorted(fps)}): they cannot share a table")
    if baseline is not None and baseline not in results:
        raise ValueError(f"baseline {baseline!r} is not one of the conditions {list(results)}")
    base = results[baseline] if baseline is not None else None
    out = {}
    for name, r in results.items():
        s = summarize(r, None if name == baseline else base)
        s.condition = name
        out[name] = s
    return out


def _f(x: float | None, digits: int = 3) -> str:
    return "–" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.{digits}f}"


def report_table(results: Mapping[str, ProtocolResult], baseline: str | None = None, *, digits: int = 3,
                 summaries: Mapping[str, ConditionSummary] | None = None) -> str:
    """A markdown table of conditions measured with one protocol.

    Columns: condition | seeds | AP@<main IoU> [CI] | AP at the other IoUs [CI] | Δ AP vs
    ``baseline`` [CI] | videos improved | AP per size bucket | patch AP [CI] | patch ROC-AUC [CI]
    (patch columns only when some result has patches). A seed count below the protocol's
    minimum is marked ``⚠``. Below the table: the protocol, bootstrap settings, objects per bucket
    and how "videos improved" is counted.

    Args:
        results: row label -> result (all of one protocol).
        baseline: the row the paired differences are taken against (None: no Δ columns).
        digits: decimals.
        summaries: precomputed :func:`summarize_conditions` output (saves the bootstrap).
    """
    sums = dict(summaries) if summaries is not None else summarize_conditions(results, baseline)
    first = next(iter(results.values()))
    p = first.protocol
    others = [t for t in p.iou_thresholds[1:]]
    has_patch = any(s.patch_ap is not None for s in sums.values())
    ci_pct = f"{100 * p.bootstrap.ci:g} %"
    header = ["condition", "seeds", f"AP@{p.main_iou:g} [{ci_pct} CI]"] + [f"AP@{t:g} [CI]" for t in others]
    if baseline is not None:
        header += [f"Δ AP@{p.main_iou:g} vs {baseline} [CI]", "videos improved"]
    header += [f"AP@{p.main_iou:g} {b.label}" for b in p.size_buckets]
    if has_patch:
        header += ["patch AP [CI]", "patch ROC-AUC [CI]"]
    rows = []
    for name, s in sums.items():
        label = name if results[name].scale == 1.0 else f"{name} (×{results[name].scale:g})"
        seeds = f"{len(s.seeds)}" + ("" if s.meets_min_seeds else " ⚠")
        row = [label, seeds] + [s.ap[t].format(digits) if t in s.ap else "–" for t in p.iou_thresholds]
        if baseline is not None:
            if name == baseline:
                row += ["(baseline)", ""]
            elif s.paired is None:
                row += [f"n/a ({s.paired_note})" if s.paired_note else "–", "–"]
            else:
                d = s.paired.difference.format(digits, signed=True)
                if len(s.paired.seeds) != len(sums[baseline].seeds) or len(s.paired.seeds) != len(s.seeds):
                    d += f" (on {len(s.paired.seeds)} common seeds)"
                row += [d, s.paired.wins.format()]
        row += [_f(s.buckets[b.label], digits) for b in p.size_buckets]
        if has_patch:
            row += ["–" if s.patch_ap is None else s.patch_ap.format(digits),
                    "–" if s.patch_auc is None else s.patch_auc.format(digits)]
        rows.append(row)
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    n_vid = max((s.n_videos for s in sums.values()), default=0)
    objs = next((s.bucket_objects for s in sums.values() if s.ap), {})
    n_frame_vid = any(s.ap for s in sums.values())
    lines += [
        "",
        f"Protocol `{p.name}` v{p.version} (fingerprint `{p.fingerprint()}`), split `{first.split}`: "
        f"every {p.split(first.split if first.split in ('test', 'val') else 'test').frame_stride}-th frame of {n_vid} videos. "
        f"AP = ∫ p(r) dr of all videos pooled, mean over training seeds; {ci_pct} percentile intervals from "
        f"{p.bootstrap.resamples} bootstrap resamples of the videos (seed {p.bootstrap.seed}, the same resamples for "
        f"every condition and seed). Δ: paired by seed id and resample.",
    ]
    if n_frame_vid:
        lines.append("Objects per size bucket (longest side of the labelled box): "
                     + ", ".join(f"{k}: {v}" for k, v in objs.items()) + ". In a bucket, objects of other sizes and "
                     "unmatched detections of other sizes are ignored (COCO).")
    if has_patch:
        npat = next((s.n_patches for s in sums.values() if s.n_patches), {})
        lines.append(f"Patches: {npat.get('positive', 0)} object crops (cropped like the seeds) and {npat.get('negative', 0)} "
                     f"background windows of the same frames and sizes; ROC-AUC counts ties as ½.")
    if baseline is not None:
        lines.append("Videos improved: videos whose own AP (mean over seeds) rose, out of the videos with a labelled "
                     "object (videos without one have no AP and are left out).")
    if any(not s.meets_min_seeds for s in sums.values()):
        lines.append(f"⚠ fewer than the protocol's {p.min_training_seeds} training seeds.")
    return "\n".join(lines) + "\n"


# =========================================================================== scale check
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


def scale_eval_set(eval_set: Any, scale: float) -> Any:
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


# =========================================================================== patch protocol
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
    from synthaug.data.video import VIDEO_EXTENSIONS

    for ext in VIDEO_EXTENSIONS:
        if (videos_dir / f"{stem}{ext}").is_file():
            return videos_dir / f"{stem}{ext}"
    raise ValueError(f"no video file for {stem!r} in {videos_dir} (tried {list(VIDEO_EXTENSIONS)})")


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
