"""Contact sheet: every seed patch beside its background patch, with provenance, as one PNG.

Example:
    >>> import numpy as np
    >>> p = np.full((3, 40, 40), 90, np.uint8)
    >>> sheet = contact_sheet_image(p, p, captions=["a", "b", "c"], columns=2, zoom=2)
    >>> sheet.shape
    (204, 340)
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Sequence

import numpy as np

__all__ = ["contact_sheet_image", "write_contact_sheet", "seedset_contact_sheet"]


def contact_sheet_image(patches: np.ndarray, backgrounds: np.ndarray, *, captions: Sequence[str] | None = None,
                        columns: int = 8, zoom: int = 2, gap: int = 8, caption_height: int = 14) -> np.ndarray:
    """Grid of ``[patch | background]`` pairs, each pair captioned.

    Args:
        patches: uint8 ``(N, P, P)``.
        backgrounds: uint8 ``(N, P, P)``.
        captions: N short strings written under each pair.
        columns: pairs per row.
        zoom: integer nearest-neighbour upscaling of the patches.
        gap: pixels between pairs.
        caption_height: pixels reserved for the caption.

    Returns:
        uint8 grayscale image.
    """
    import cv2

    if patches.shape != backgrounds.shape or patches.ndim != 3:
        raise ValueError(f"patches and backgrounds must both be (N, P, P), got {patches.shape} and {backgrounds.shape}")
    if columns < 1 or zoom < 1:
        raise ValueError(f"columns and zoom must be >= 1, got {columns}, {zoom}")
    n, p = patches.shape[0], patches.shape[1] * zoom
    rows = max(1, -(-n // columns))
    cell_w, cell_h = 2 * p + 2 + gap, p + caption_height + gap
    sheet = np.full((rows * cell_h, min(n, columns) * cell_w if n else cell_w), 255, np.uint8)
    for k in range(n):
        r, c = divmod(k, columns)
        y, x = r * cell_h, c * cell_w
        a = np.kron(patches[k], np.ones((zoom, zoom), np.uint8))
        b = np.kron(backgrounds[k], np.ones((zoom, zoom), np.uint8))
        sheet[y:y + p, x:x + p] = a
        sheet[y:y + p, x + p + 2:x + 2 * p + 2] = b
        if captions is not None:
            cv2.putText(sheet, str(captions[k])[:28], (x, y + p + caption_height - 4), cv2.FONT_HERSHEY_PLAIN,
                        0.7, 0, 1, cv2.LINE_AA)
    return sheet


def write_contact_sheet(path: str | os.PathLike, image: np.ndarray) -> Path:
    """Encode ``image`` as PNG and write it atomically."""
    import cv2

    from synthaug.data.seedset import atomic_write_bytes

    ok, buf = cv2.imencode(".png", image)
    if not ok:
        raise RuntimeError(f"cannot encode the contact sheet {path}")
    atomic_write_bytes(path, buf.tobytes())
    return Path(path)


def _caption(rec: dict) -> str:
    video = str(rec.get("video", "?")).replace("V_", "").replace("AIRPLANE", "AIR")
    method = {"median": "med", "median+inpaint": "med+inp", "inpaint": "inp"}.get(rec.get("background_method"), "?")
    return f"{video}#{rec.get('frame', '?')} {method}"


def seedset_contact_sheet(seeds: "object", path: str | os.PathLike | None = None, *, max_seeds: int = 200,
                          columns: int = 8, zoom: int = 2) -> np.ndarray:
    """Contact sheet of a :class:`~synthaug.data.seedset.SeedSet` (or its folder); written to ``path`` if given."""
    from synthaug.data.seedset import SeedSet

    s = seeds if isinstance(seeds, SeedSet) else SeedSet.load(seeds)  # type: ignore[arg-type]
    k = min(len(s), max_seeds)
    img = contact_sheet_image(s.patches[:k], s.backgrounds[:k], captions=[_caption(r) for r in s.records[:k]],
                              columns=columns, zoom=zoom)
    if path is not None:
        write_contact_sheet(path, img)
    return img
