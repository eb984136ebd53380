"""Procedural backgrounds: the default data that ships with the project (made by code).

Sky-like grayscale images: a vertical gradient, soft clouds (smoothed noise at
several scales) and sensor noise, from an explicit seed.

Example:
    >>> bgs = sky_backgrounds(2, (48, 64), seed=0)
    >>> bgs.shape, bgs.dtype
    ((2, 48, 64), dtype('uint8'))
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage


def sky_backgrounds(n: int, size: tuple[int, int] = (512, 640), *, seed: int = 0) -> np.ndarray:
    """``n`` sky-like uint8 images of ``size`` (H, W)."""
    if n < 0:
        raise ValueError(f"n must be >= 0, got {n}")
    h, w = size
    if h < 1 or w < 1:
        raise ValueError(f"size must be positive, got {size}")
    rng = np.random.default_rng(seed)
    out = np.empty((n, h, w), np.uint8)
    yy = np.linspace(0.0, 1.0, h)[:, None]
    for i in range(n):
        top, bottom = rng.uniform(0.45, 0.8), rng.uniform(0.6, 0.95)
        img = top + (bottom - top) * yy + np.zeros((1, w))
        for scale, amp in ((max(h, w) / 6, 0.12), (max(h, w) / 20, 0.05)):
            noise = ndimage.gaussian_filter(rng.standard_normal((h, w)), sigma=scale, mode="wrap")
            noise /= noise.std() + 1e-12
            img += amp * rng.uniform(0.3, 1.0) * noise
        img += rng.normal(0.0, 0.01, (h, w))
        out[i] = np.clip(img * 255.0, 0, 255).astype(np.uint8)
    return out
