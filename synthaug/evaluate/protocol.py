"""The evaluation protocol: one versioned definition of how every experiment measures a detector.

A protocol file (``configs/protocol/<name>.json``, :func:`load_protocol`) fixes
*what* is measured; the modules beside this one measure it and keep enough per
video to recompute every number later (other seeds, other subsets of videos,
bootstrap intervals) without running detection again.

Protocol file (``configs/protocol/halmstad_v1.json``)::

    {"name": "halmstad_v1", "version": 1, "description": "...",
     "split_file": "configs/splits/halmstad.json",          # optional (null: the caller names the videos)
     "test": {"split": "test", "frame_stride": 5},         # every 5th frame of every test video of the class
                                                           # (+ "unlabelled_frames": "skip": frames without a
                                                           #  labelled box are not scored; v2)
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

Where each step of the protocol lives:

- the protocol itself (this module): :class:`Protocol`, :func:`load_protocol`, :func:`split_videos`;
- the frame protocol (detection AP, size buckets): :mod:`synthaug.evaluate.matching`
  (:func:`~synthaug.evaluate.matching.match_video`, :class:`~synthaug.evaluate.matching.VideoMatches`);
- the scale check: :func:`synthaug.evaluate.videos.scale_frame` / :func:`~synthaug.evaluate.videos.scale_eval_set`;
- the paper's patch protocol: :mod:`synthaug.evaluate.patches`;
- one condition's results and their JSON: :mod:`synthaug.evaluate.results` (:class:`~synthaug.evaluate.results.ProtocolResult`);
- summaries and the markdown table: :mod:`synthaug.evaluate.summary`.

Wiring (what an experiment runner, ``synthaug train`` and ``synthaug evaluate`` do; one cell =
one detector trained with one seed, cached under a key holding ``proto.fingerprint()``)::

    from synthaug.evaluate.matching import match_videos
    from synthaug.evaluate.patches import patch_eval_set, score_patch_set
    from synthaug.evaluate.protocol import load_protocol, split_videos
    from synthaug.evaluate.results import ProtocolResult
    from synthaug.evaluate.summary import report_table
    from synthaug.evaluate.videos import load_eval_set, scale_eval_set

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
    >>> p = Protocol.from_dict(example_protocol_dict())
    >>> p.main_iou, [b.label for b in p.size_buckets]
    (0.5, ['<24 px', '24–48 px', '48–96 px', '≥96 px'])
    >>> p.test.frame_stride, p.split("val").split, len(p.fingerprint())
    (5, 'val', 16)
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

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
]

DEFAULT_PROTOCOL = Path(__file__).resolve().parents[2] / "configs" / "protocol" / "halmstad_v1.json"
"""The protocol every experiment of the repository uses (a checkout's ``configs/``)."""


UNLABELLED_FRAMES = ("score", "skip")
"""What a scored frame without any labelled box can be (:attr:`SplitSpec.unlabelled_frames`)."""


class ProtocolError(ValueError):
    """A protocol file or dict that cannot be used; the message names the field."""


@dataclass(frozen=True)
class SplitSpec:
    """Which videos and frames a split is scored on.

    Attributes:
        split: the split of the video-split file (``"test"``, ``"val"``, ``"train"``).
        frame_stride: frames ``0, k, 2k, ...`` of every video of the split (frame index = position
            in the label file's ``boxes`` list).
        unlabelled_frames: what a frame without any labelled box is: ``"score"`` (a frame with no object: every
            detection on it is a false positive; protocol v1) or ``"skip"`` (not annotated: not scored). The
            shared format reads a null entry as "target not visible", but on the halmstad drones two test videos
            are null throughout and a third in 217 of 305 frames while the drone is in view (protocol v2's
            description; results/learning_curve/unlabelled_drones/README.md).
    """

    split: str
    frame_stride: int
    unlabelled_frames: str = "score"

    def to_dict(self) -> dict[str, Any]:
        """The spec as JSON; ``unlabelled_frames`` only when not ``"score"`` (v1 protocols keep their fingerprint)."""
        d = asdict(self)
        if d["unlabelled_frames"] == "score":
            d.pop("unlabelled_frames")
        return d


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
            "test": self.test.to_dict(),
            "val": self.val.to_dict(),
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
        d = _obj(top[key], source, key, ["split", "frame_stride"], ["unlabelled_frames"])
        if d["split"] not in SPLITS:
            raise _err(source, f"{key}.split", f"must be one of {list(SPLITS)}", d["split"])
        unl = d.get("unlabelled_frames", "score")
        if unl not in UNLABELLED_FRAMES:
            raise _err(source, f"{key}.unlabelled_frames", f"must be one of {list(UNLABELLED_FRAMES)}", unl)
        return SplitSpec(str(d["split"]), _int(d["frame_stride"], source, f"{key}.frame_stride", 1), str(unl))

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
