"""Train / validation / test splits *by video*, never by frame.

Frames of one video are near duplicates, and videos with neighbouring numbers
are often takes of the same session, so videos are grouped into blocks of
``block`` consecutive numbers per class and whole blocks are assigned to the
splits (stratified by class, seeded shuffle). Hard-negative videos (birds) are
split the same way: train birds give hard negatives for training, test birds
test false alarms.

File format (``synthaug.video_split`` version 1, JSON)::

    {"format": "synthaug.video_split", "version": 1, "dataset": "halmstad",
     "seed": 0, "block": 4, "fractions": {"train": 0.6, "val": 0.2, "test": 0.2},
     "classes": {"V_DRONE_001": "drone", ...},
     "train": [...], "val": [...], "test": [...],              # positive videos
     "hard_negatives": {"train": [...], "val": [...], "test": [...]}}

Regenerate the committed halmstad split with
``python -m synthaug.data.splits --labels ../shared/data/halmstad/labels --out configs/splits/halmstad.json``.

Example:
    >>> classes = {f"V_DRONE_{i:03d}": "drone" for i in range(1, 21)}
    >>> split = make_video_split(classes, seed=0)
    >>> [len(split.videos[s]) for s in SPLITS]
    [12, 4, 4]
    >>> split.split_of("V_DRONE_001") in SPLITS
    True
"""

from __future__ import annotations

import argparse
import json
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from synthaug._io import atomic_write_text, read_versioned_json

__all__ = ["SPLITS", "VideoSplit", "make_video_split", "load_split", "save_split"]

SPLITS: tuple[str, ...] = ("train", "val", "test")
FORMAT_NAME = "synthaug.video_split"
FORMAT_VERSION = 1


@dataclass
class VideoSplit:
    """Which video belongs to which split.

    Attributes:
        videos: split name -> positive video stems.
        hard_negatives: split name -> hard-negative video stems.
        classes: stem -> class name.
        info: the other header fields (dataset, seed, block, fractions).
    """

    videos: dict[str, list[str]]
    hard_negatives: dict[str, list[str]] = field(default_factory=lambda: {s: [] for s in SPLITS})
    classes: dict[str, str] = field(default_factory=dict)
    info: dict[str, object] = field(default_factory=dict)

    def split_of(self, stem: str) -> str | None:
        """The split of a video (positive or hard negative), None when unlisted."""
        for s in SPLITS:
            if stem in self.videos.get(s, ()) or stem in self.hard_negatives.get(s, ()):
                return s
        return None

    def is_hard_negative(self, stem: str) -> bool:
        return any(stem in v for v in self.hard_negatives.values())

    def to_json(self) -> dict[str, object]:
        return {"format": FORMAT_NAME, "version": FORMAT_VERSION, **self.info, "classes": self.classes,
                **{s: sorted(self.videos.get(s, [])) for s in SPLITS},
                "hard_negatives": {s: sorted(self.hard_negatives.get(s, [])) for s in SPLITS}}


def _number(stem: str) -> int:
    m = re.search(r"(\d+)(?!.*\d)", stem)
    return int(m.group(1)) if m else 0


def _assign(stems: list[str], fractions: Mapping[str, float], block: int, rng: np.random.Generator) -> dict[str, list[str]]:
    stems = sorted(stems, key=lambda s: (_number(s), s))
    blocks = [stems[i:i + block] for i in range(0, len(stems), block)]
    order = rng.permutation(len(blocks))
    total = len(stems)
    out: dict[str, list[str]] = {s: [] for s in SPLITS}
    for b in order:
        # give the block to the split furthest below its target share
        deficit = {s: fractions[s] * total - len(out[s]) for s in SPLITS}
        best = max(SPLITS, key=lambda s: (deficit[s], -SPLITS.index(s)))
        out[best] += blocks[b]
    return out


def make_video_split(
    classes: Mapping[str, str],
    *,
    fractions: Mapping[str, float] | None = None,
    seed: int = 0,
    block: int = 4,
    hard_negative_classes: Sequence[str] = ("bird",),
    dataset: str = "",
) -> VideoSplit:
    """Split videos by video, stratified by class, in blocks of consecutive numbers.

    Args:
        classes: video stem -> class name.
        fractions: share of videos per split (default 0.6 / 0.2 / 0.2).
        seed: seed of the numpy Generator that shuffles the blocks.
        block: consecutive video numbers kept together (same recording session).
        hard_negative_classes: classes listed under ``hard_negatives``.
        dataset: name written in the header.

    Returns:
        The :class:`VideoSplit`.
    """
    fractions = dict(fractions or {"train": 0.6, "val": 0.2, "test": 0.2})
    if set(fractions) != set(SPLITS) or any(v < 0 for v in fractions.values()) or abs(sum(fractions.values()) - 1) > 1e-6:
        raise ValueError(f"fractions must give train/val/test shares >= 0 summing to 1, got {fractions}")
    if block < 1:
        raise ValueError(f"block must be >= 1, got {block}")
    rng = np.random.default_rng(seed)
    videos: dict[str, list[str]] = {s: [] for s in SPLITS}
    hard: dict[str, list[str]] = {s: [] for s in SPLITS}
    for cls in sorted(set(classes.values())):
        part = _assign([k for k, v in classes.items() if v == cls], fractions, block, rng)
        target = hard if cls in hard_negative_classes else videos
        for s in SPLITS:
            target[s] += part[s]
    info = {"dataset": dataset, "seed": seed, "block": block, "fractions": fractions}
    return VideoSplit({s: sorted(v) for s, v in videos.items()}, {s: sorted(v) for s, v in hard.items()},
                      dict(sorted(classes.items())), info)


def save_split(split: VideoSplit, path: str | os.PathLike) -> None:
    """Write a split file (atomically)."""
    atomic_write_text(path, json.dumps(split.to_json(), indent=1) + "\n")


def load_split(path: str | os.PathLike) -> VideoSplit:
    """Read a split file written by :func:`save_split`.

    A video listed in two splits is an error (it would leak between them).
    """
    path = Path(path)
    doc = read_versioned_json(path, format=FORMAT_NAME, version=FORMAT_VERSION, what="split file")
    videos = {s: list(doc.get(s, [])) for s in SPLITS}
    hard = {s: list(doc.get("hard_negatives", {}).get(s, [])) for s in SPLITS}
    seen: dict[str, str] = {}
    for kind, table in (("videos", videos), ("hard_negatives", hard)):
        for s in SPLITS:
            for stem in table[s]:
                if stem in seen:
                    raise ValueError(f"{path}: video {stem!r} is listed twice ({seen[stem]} and {kind}/{s})")
                seen[stem] = f"{kind}/{s}"
    info = {k: v for k, v in doc.items() if k not in (*SPLITS, "hard_negatives", "classes", "format", "version")}
    return VideoSplit(videos, hard, dict(doc.get("classes", {})), info)


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description="write a by-video train/val/test split of a label folder")
    p.add_argument("--labels", required=True, help="folder of per-video label JSON files")
    p.add_argument("--out", required=True, help="output split JSON")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--block", type=int, default=4)
    p.add_argument("--dataset", default="halmstad")
    args = p.parse_args(argv)
    classes = {}
    for f in sorted(Path(args.labels).glob("*.json")):
        classes[f.stem] = json.loads(f.read_text())["class"]
    split = make_video_split(classes, seed=args.seed, block=args.block, dataset=args.dataset)
    save_split(split, args.out)
    print(json.dumps({s: len(split.videos[s]) for s in SPLITS} | {"hard_negatives": {s: len(split.hard_negatives[s]) for s in SPLITS}}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
