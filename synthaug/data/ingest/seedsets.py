"""Stage 2 of ingest: seed sets drawn from the train shards, spread across videos (:func:`select_spread`,
:func:`assemble_seed_sets`), and the seed sets an earlier run left that are no longer current
(:func:`stale_seed_sets`).
"""

from __future__ import annotations

import json
import logging
import os
import zlib
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from synthaug._io import digest
from synthaug.data.ingest.shards import IngestConfig, _shard_is_current

log = logging.getLogger("synthaug.ingest")


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
