"""The experiments' cell cache: one trained-and-scored configuration per file, keyed by everything that changes it.

A *cell* is one detector trained on one training set with one seed and scored
under one evaluation protocol. Its identity is a plain mapping (protocol
fingerprint, class, detector kind, training-set description, seed, pyramid
scales, training budgets, the training code's version, ...); the cache key is
the SHA-256 of its canonical JSON, so a change to *any* of these is a new
cell, never a stale hit. (The old ``cells.json`` key held neither the scales
nor the budgets nor the training code's version.)

Storage is one JSON file per cell under the cache folder, written atomically
(temporary file + rename). Two processes asking for the same missing cell do
not both train it: the first takes an exclusive ``flock`` on the cell's lock
file and computes, the second blocks on the lock and then reads the result.
Different cells never contend.

Example:
    >>> import tempfile
    >>> cache = CellCache(tempfile.mkdtemp())
    >>> calls = []
    >>> def train():
    ...     calls.append(1)
    ...     return {"ap": 0.5}
    >>> cache.get_or_compute({"kind": "hog", "seed": 0}, train)
    {'ap': 0.5}
    >>> cache.get_or_compute({"seed": 0, "kind": "hog"}, train), len(calls)   # key order does not matter
    ({'ap': 0.5}, 1)
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from synthaug._io import exclusive_lock, read_versioned_json

__all__ = ["CellCache", "cell_key", "canonical_json"]

CELL_FORMAT = 1


def canonical_json(identity: Mapping[str, Any]) -> str:
    """Key-sorted, compact JSON of a cell identity (tuples become lists; other values must be JSON types)."""
    try:
        return json.dumps(identity, sort_keys=True, separators=(",", ":"), allow_nan=False)
    except (TypeError, ValueError) as e:
        raise ValueError(f"a cell identity must be plain JSON (str, int, float, bool, None, lists, dicts): {e}") from None


def cell_key(identity: Mapping[str, Any]) -> str:
    """24 hex digits of the SHA-256 of :func:`canonical_json`."""
    return hashlib.sha256(canonical_json(identity).encode()).hexdigest()[:24]


class CellCache:
    """Cells on disk, one file each: ``<root>/<key>.json`` = ``{"format", "identity", "result", "seconds"}``.

    Args:
        root: the cache folder (created on first write).
        read_only: never compute: :meth:`get_or_compute` returns None for a missing cell
            (regenerate every table from the cache alone).
    """

    def __init__(self, root: str | os.PathLike, *, read_only: bool = False) -> None:
        self.root = Path(root)
        self.read_only = bool(read_only)
        if self.root.exists() and not self.root.is_dir():
            raise ValueError(f"cell cache {self.root} exists and is not a folder")

    def path(self, identity: Mapping[str, Any]) -> Path:
        return self.root / f"{cell_key(identity)}.json"

    def get(self, identity: Mapping[str, Any]) -> Any | None:
        """The cached result of ``identity``, or None."""
        p = self.path(identity)
        if not p.is_file():
            return None
        doc = read_versioned_json(p, format=None, version=CELL_FORMAT, version_key="format", what="experiment cell")
        if canonical_json(doc["identity"]) != canonical_json(identity):  # a hash collision or a hand-edited file
            raise ValueError(f"{p}: stored identity differs from the requested one")
        return doc["result"]

    def put(self, identity: Mapping[str, Any], result: Any, *, seconds: float | None = None) -> Path:
        """Write one cell atomically (temporary file in the same folder, then rename)."""
        self.root.mkdir(parents=True, exist_ok=True)
        p = self.path(identity)
        doc = {"format": CELL_FORMAT, "identity": json.loads(canonical_json(identity)), "result": result,
               "seconds": None if seconds is None else round(float(seconds), 2)}
        fd, tmp = tempfile.mkstemp(dir=self.root, prefix=f".{p.stem}.", suffix=".tmp")
        try:
            with os.fdopen(fd, "w") as f:
                json.dump(doc, f, indent=1, sort_keys=True, allow_nan=False)
                f.write("\n")
            os.replace(tmp, p)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        return p

    def get_or_compute(self, identity: Mapping[str, Any], compute: Callable[[], Any]) -> Any | None:
        """The cell's result, computing (once across processes) and storing it when missing.

        ``compute()`` must return plain JSON. While one process computes a cell,
        others asking for it wait on its lock and then read it.
        """
        hit = self.get(identity)
        if hit is not None or self.read_only:
            return hit
        with exclusive_lock(self.root / f".{cell_key(identity)}.lock"):
            hit = self.get(identity)  # computed by another process while we waited
            if hit is not None:
                return hit
            t0 = time.perf_counter()
            result = compute()
            self.put(identity, result, seconds=time.perf_counter() - t0)
            return result

    def __len__(self) -> int:
        return sum(1 for _ in self.root.glob("*.json")) if self.root.is_dir() else 0

    def identities(self) -> list[dict[str, Any]]:
        """Every stored cell's identity (for listing and for regenerating reports)."""
        if not self.root.is_dir():
            return []
        return [json.loads(p.read_text())["identity"] for p in sorted(self.root.glob("*.json"))]
