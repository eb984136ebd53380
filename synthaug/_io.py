"""Atomic file writes: readers never see a half-written file (one home for the whole package)."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary sibling, fsync, then ``os.replace``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def atomic_write_text(path: str | os.PathLike, text: str) -> None:
    """:func:`atomic_write_bytes` of UTF-8 text."""
    atomic_write_bytes(path, text.encode("utf-8"))


# ------------------------------------------------------------ fingerprints
# What a result depends on is recorded beside it as a hash; a rerun compares the hashes and redoes what changed.

def sha256_file(path: str | os.PathLike, *, chunk: int = 1 << 20) -> str:
    """SHA-256 (hex) of a whole file, read in chunks."""
    import hashlib

    h = hashlib.sha256()
    with open(path, "rb") as f:
        while True:
            block = f.read(chunk)
            if not block:
                break
            h.update(block)
    return h.hexdigest()


def quick_file_fingerprint(path: str | os.PathLike, *, edge: int = 1 << 20) -> dict[str, object]:
    """A cheap fingerprint of a large file (a video): size, mtime and the SHA-256 of its first and last ``edge``
    bytes. Any edit that changes the size, the time stamp, the header or the tail shows."""
    import hashlib

    st = os.stat(path)
    h = hashlib.sha256()
    with open(path, "rb") as f:
        h.update(f.read(edge))
        if st.st_size > edge:
            f.seek(max(edge, st.st_size - edge))
            h.update(f.read(edge))
    return {"size": int(st.st_size), "mtime_ns": int(st.st_mtime_ns), "head_tail_sha256": h.hexdigest()}


def digest(obj: object, *, length: int = 20) -> str:
    """A short SHA-256 (hex) of a JSON-able object (keys sorted)."""
    import hashlib
    import json

    return hashlib.sha256(json.dumps(obj, sort_keys=True, default=str).encode()).hexdigest()[:length]
