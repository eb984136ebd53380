"""One condition measured with a protocol: per training seed, every video's matches and patch scores.

A :class:`ProtocolResult` is one condition (detector x training set x scale) on one
split: per training seed, the :class:`~synthaug.evaluate.matching.VideoMatches` of every
test video and the :class:`~synthaug.evaluate.patches.PatchVideoScores` of every video's
patches; ``to_json`` / ``from_json`` / ``save`` / ``load`` round-trip it exactly,
:meth:`ProtocolResult.combine` merges cells run one seed at a time. The numbers
(pooled AP per seed, video-bootstrap intervals, paired differences) come from
:mod:`synthaug.evaluate.stats`; :mod:`synthaug.evaluate.summary` turns results into a table.

Example:
    >>> import numpy as np
    >>> from synthaug.evaluate.matching import match_video
    >>> from synthaug.evaluate.protocol import Protocol, example_protocol_dict
    >>> p = Protocol.from_dict(example_protocol_dict())
    >>> dets = [np.array([[10, 10, 20, 20, 0.9], [100, 100, 30, 30, 0.8]]), np.zeros((0, 5))]
    >>> gts = [np.array([[10, 10, 20, 20]]), np.array([[50, 50, 60, 60]])]
    >>> vm = match_video(dets, gts, iou_thresholds=p.iou_thresholds, stem="V_1")
    >>> r = ProtocolResult(condition="demo", protocol=p)
    >>> r.add_seed(0, videos=[vm])
    >>> round(r.mean_ap(), 3), round(r.mean_ap(bucket=p.size_buckets[0]), 3)   # the 60-px object is missed
    (0.5, 1.0)
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import numpy as np

from synthaug._io import atomic_write_text, check_header, read_versioned_json
from synthaug.evaluate.matching import VideoMatches
from synthaug.evaluate.patches import PatchVideoScores
from synthaug.evaluate.protocol import Protocol, SizeBucket
from synthaug.evaluate.stats import PooledRanking

__all__ = ["RESULT_FORMAT", "RESULT_VERSION", "SeedResult", "ProtocolResult"]

RESULT_FORMAT = "synthaug.protocol_result"
RESULT_VERSION = 1


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

    def trained_elsewhere(self, other: "ProtocolResult") -> dict[int, tuple[dict[str, Any], dict[str, Any]]]:
        """The seeds both results have whose detectors were trained on different machines: seed ->
        ``(this seed's trained_on, other's)``, from each seed's ``meta["trained_on"]``
        (:func:`~synthaug.evaluate.runner.machine_info`), compared on the fields both record (seeds without it on
        either side are not counted).

        A paired difference pairs seeds by id, which pairs the training randomness only when both were trained on
        one machine: another instruction set (AVX2 vs AVX-512 kernels) changes a float32 fit's last bits, which
        validation-chosen rounds and hard-negative mining can amplify (AdaBoost at 100 seeds: the same code, seeds
        and data on another machine moved real-only test AP@0.5 by -0.023 [-0.033, -0.010],
        results/synthetic/adaboost_where/README.md).

        >>> from synthaug.evaluate.protocol import Protocol, example_protocol_dict
        >>> p = Protocol.from_dict(example_protocol_dict())
        >>> a, b = ProtocolResult("a", p), ProtocolResult("b", p)
        >>> a.add_seed(0, meta={"trained_on": {"cpu_capability": "AVX512"}})
        >>> b.add_seed(0, meta={"trained_on": {"cpu_capability": "AVX2"}})
        >>> a.trained_elsewhere(b)
        {0: ({'cpu_capability': 'AVX512'}, {'cpu_capability': 'AVX2'})}
        """
        out = {}
        for s in self.seed_ids:
            if s not in other.seeds:
                continue
            mine, theirs = self.seeds[s].meta.get("trained_on"), other.seeds[s].meta.get("trained_on")
            if mine and theirs and any(mine[k] != theirs[k] for k in mine.keys() & theirs.keys()):
                out[s] = (mine, theirs)
        return out

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
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(path, json.dumps(self.to_json(), separators=(",", ":")) + "\n")
        return path

    @classmethod
    def load(cls, path: str | Path) -> "ProtocolResult":
        return cls.from_json(read_versioned_json(path, format=RESULT_FORMAT, version=RESULT_VERSION,
                                                 what="protocol result"), source=path)
