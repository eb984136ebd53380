"""Generated object / background patches for tests, tiny configs and benchmarks.

Objects are dark blob-like shapes (an ellipse body with two crossing arms, a
crude drone silhouette) over smooth textured backgrounds; negatives are the
same kind of background, sometimes crossed by a straight edge so that "has
strong gradients" alone does not separate the classes. Every draw comes from
an explicit ``torch.Generator``; item ``i`` of ``toy_patches(..., seed=s)``
depends only on ``(s, i)`` so a dataset of them is worker-count independent.

Example:
    >>> pos, neg = toy_patches(4, 4, seed=0)
    >>> pos.shape, neg.shape, bool(pos.min() >= 0 and pos.max() <= 1)
    (torch.Size([4, 1, 40, 40]), torch.Size([4, 1, 40, 40]), True)
"""

from __future__ import annotations

import math

import torch
from torch import Tensor

__all__ = ["toy_patch", "toy_patches", "toy_frame"]


def _background(size: int, g: torch.Generator) -> Tensor:
    """Smooth random texture: a few random low-frequency cosines plus fine noise."""
    yy, xx = torch.meshgrid(torch.arange(size, dtype=torch.float32), torch.arange(size, dtype=torch.float32), indexing="ij")
    base = 0.45 + 0.3 * torch.rand((), generator=g)
    img = torch.full((size, size), float(base))
    for _ in range(3):
        f = 0.02 + 0.15 * torch.rand(2, generator=g)
        ph = 2 * math.pi * torch.rand((), generator=g)
        amp = 0.08 * torch.rand((), generator=g)
        img = img + amp * torch.cos(f[0] * xx + f[1] * yy + ph)
    img = img + 0.02 * torch.randn(size, size, generator=g)
    return img


def toy_patch(label: int, size: int = 40, *, generator: torch.Generator) -> Tensor:
    """One ``(1, size, size)`` patch: an object (label 1) or background (label 0)."""
    if label not in (0, 1):
        raise ValueError(f"label must be 0 or 1, got {label}")
    g = generator
    img = _background(size, g)
    yy, xx = torch.meshgrid(torch.arange(size, dtype=torch.float32), torch.arange(size, dtype=torch.float32), indexing="ij")
    if label == 1:
        c = size / 2 + (torch.rand(2, generator=g) - 0.5) * size * 0.15
        r = size * (0.12 + 0.08 * torch.rand(2, generator=g))
        ang = math.pi * torch.rand((), generator=g)
        dy, dx = yy - c[0], xx - c[1]
        u = dx * torch.cos(ang) + dy * torch.sin(ang)
        v = -dx * torch.sin(ang) + dy * torch.cos(ang)
        body = (u / r[0]) ** 2 + (v / r[1]) ** 2 <= 1
        arm_len = size * 0.32
        arm1 = (u.abs() - v.abs()).abs() < 1.6
        arms = arm1 & (u.abs() < arm_len * 0.72) & (v.abs() < arm_len * 0.72)
        mask = (body | arms).float()
        # soft edges: average with shifted copies
        soft = (mask + mask.roll(1, 0) + mask.roll(1, 1) + mask.roll(-1, 0) + mask.roll(-1, 1)) / 5
        dark = 0.05 + 0.2 * torch.rand((), generator=g)
        img = img * (1 - soft) + dark * soft
    elif torch.rand((), generator=g) < 0.5:
        # a straight edge across the background (a horizon, a roof line)
        ang = math.pi * torch.rand((), generator=g)
        off = (torch.rand((), generator=g) - 0.5) * size * 0.6
        side = (xx - size / 2) * torch.cos(ang) + (yy - size / 2) * torch.sin(ang) > off
        img = img + (0.25 * torch.rand((), generator=g) - 0.125) * side.float()
    return img.clamp(0, 1)[None]


def toy_patches(n_pos: int, n_neg: int, size: int = 40, *, seed: int = 0) -> tuple[Tensor, Tensor]:
    """``n_pos`` object patches and ``n_neg`` background patches, ``(N, 1, size, size)`` float32.

    Item ``i`` of each class is a pure function of ``(seed, label, i)``.
    """
    if n_pos < 0 or n_neg < 0:
        raise ValueError(f"n_pos and n_neg must be >= 0, got {n_pos}, {n_neg}")

    def make(label: int, n: int) -> Tensor:
        out = torch.empty(n, 1, size, size)
        for i in range(n):
            g = torch.Generator().manual_seed(hash((seed, label, i)) & 0x7FFFFFFF)
            out[i] = toy_patch(label, size, generator=g)
        return out

    return make(1, n_pos), make(0, n_neg)


def toy_frame(
    height: int = 240,
    width: int = 320,
    n_objects: int = 3,
    size: int = 40,
    *,
    seed: int = 0,
) -> tuple[Tensor, Tensor]:
    """A ``(1, 1, height, width)`` frame tiled with backgrounds and ``n_objects`` objects.

    Returns:
        ``(frame, boxes)``, boxes ``(n_objects, 4)`` as ``[x, y, w, h]`` in pixels
        on a grid of ``size`` cells (objects do not overlap).
    """
    g = torch.Generator().manual_seed(seed)
    rows, cols = height // size, width // size
    if n_objects > rows * cols:
        raise ValueError(f"n_objects must be <= {rows * cols} cells for a {height}x{width} frame, got {n_objects}")
    frame = torch.rand(height, width, generator=g) * 0.02 + 0.5
    cells = torch.randperm(rows * cols, generator=g)[:n_objects].tolist()
    boxes = []
    for cell in range(rows * cols):
        r, c = divmod(cell, cols)
        label = 1 if cell in cells else 0
        frame[r * size:(r + 1) * size, c * size:(c + 1) * size] = toy_patch(label, size, generator=g)[0]
        if label:
            boxes.append([c * size, r * size, size, size])
    return frame[None, None], torch.tensor(boxes, dtype=torch.float32).reshape(-1, 4)
