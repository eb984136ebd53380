"""Negative patches: background crops away from every box, and hard negatives around other objects.

Background negatives are cut from *labelled* frames only (where the object's
position is known), at the scales of the video's seed crops, from squares that
do not touch any grown box. Hard negatives are crops centred on the boxes of
look-alike objects (birds for a drone detector), scale-normalised exactly like
seeds, so a detector sees them at the size it sees drones.

Example:
    >>> import numpy as np
    >>> frames = np.zeros((3, 100, 120), np.uint8)
    >>> boxes = [np.array([10.0, 10.0, 20.0, 20.0])] * 3
    >>> patches, recs = sample_negatives(frames, boxes, 5, sides=[30.0], rng=np.random.default_rng(0),
    ...                                  patch_size=16)
    >>> patches.shape, all(_overlaps(r["crop"], boxes[0]) is False for r in recs)
    ((5, 16, 16), True)
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from synthaug.data.backgrounds import grow_boxes
from synthaug.data.seedset import crop_patch

__all__ = ["sample_negatives", "hard_negatives"]


def _overlaps(crop: Sequence[float], box: Any, *, margin_fraction: float = 0.25, min_margin: float = 4.0) -> bool:
    cx, cy, side = (float(v) for v in crop)
    half = side / 2
    for x, y, w, h in grow_boxes(box, margin_fraction=margin_fraction, min_margin=min_margin):
        if cx - half < x + w and cx + half > x and cy - half < y + h and cy + half > y:
            return True
    return False


def sample_negatives(
    frames: np.ndarray,
    boxes: Sequence[Any],
    n: int,
    *,
    sides: Sequence[float],
    rng: np.random.Generator,
    patch_size: int = 40,
    max_tries: int = 50,
    meta: dict[str, Any] | None = None,
) -> tuple[np.ndarray, list[dict[str, Any]]]:
    """Draw up to ``n`` object-free square crops from the labelled frames.

    Args:
        frames: uint8 ``(T, H, W)``.
        boxes: per frame ``None`` or xywh box(es); frames without a box are not used.
        n: number of negatives wanted.
        sides: crop sides (frame pixels) to draw from, e.g. the seeds' crop sides.
        rng: numpy Generator for every draw.
        patch_size: P of the output patches.
        max_tries: placement attempts per negative before giving up on it.
        meta: fields copied into every record (video, class, split...).

    Returns:
        uint8 ``(M, P, P)`` patches (``M <= n``) and M records with ``kind``,
        ``frame`` and ``crop``.
    """
    if n < 0:
        raise ValueError(f"n must be >= 0, got {n}")
    labelled = [i for i, b in enumerate(boxes) if b is not None]
    sides = [float(s) for s in sides if s > 0]
    out, recs = [], []
    if not labelled or not sides or n == 0:
        return np.zeros((0, patch_size, patch_size), np.uint8), []
    h, w = frames.shape[1:]
    for _ in range(n):
        for _try in range(max_tries):
            i = int(labelled[rng.integers(len(labelled))])
            side = float(sides[rng.integers(len(sides))])
            if side >= min(w, h):
                continue
            cx = float(rng.uniform(side / 2, w - side / 2))
            cy = float(rng.uniform(side / 2, h - side / 2))
            crop = [cx, cy, side]
            if _overlaps(crop, boxes[i]):
                continue
            patch, _ = crop_patch(frames[i], crop=crop, patch_size=patch_size)
            out.append(patch)
            recs.append({**(meta or {}), "kind": "background", "frame": i, "crop": [round(v, 3) for v in crop]})
            break
    return (np.stack(out) if out else np.zeros((0, patch_size, patch_size), np.uint8)), recs


def hard_negatives(
    frames: np.ndarray,
    boxes: Sequence[Any],
    n: int,
    *,
    patch_size: int = 40,
    object_fraction: float = 0.7,
    meta: dict[str, Any] | None = None,
) -> tuple[np.ndarray, list[dict[str, Any]]]:
    """Crops centred on the boxes of up to ``n`` evenly spaced labelled frames (look-alike objects).

    Returns:
        uint8 ``(M, P, P)`` patches and M records (``kind="hard"``, ``frame``, ``box``, ``crop``).
    """
    if n < 0:
        raise ValueError(f"n must be >= 0, got {n}")
    labelled = [i for i, b in enumerate(boxes) if b is not None]
    if not labelled or n == 0:
        return np.zeros((0, patch_size, patch_size), np.uint8), []
    pick = sorted({labelled[int(k)] for k in np.linspace(0, len(labelled) - 1, min(n, len(labelled))).round()})
    out, recs = [], []
    for i in pick:
        box = np.asarray(boxes[i], np.float64).reshape(-1, 4)[0]
        patch, crop = crop_patch(frames[i], box=box, patch_size=patch_size, object_fraction=object_fraction)
        out.append(patch)
        recs.append({**(meta or {}), "kind": "hard", "frame": i, "box": [round(float(v), 2) for v in box],
                     "crop": [round(float(v), 3) for v in crop]})
    return np.stack(out), recs
