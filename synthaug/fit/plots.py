"""Plots of a fit: joint histograms of fitted capture parameters (paper Fig. 4) and
real seeds beside their fitted synthetic images for several distances (Fig. 8)."""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from synthaug.params import CaptureParams

PAPER_PAIRS = (("sigma_n", "sigma_v"), ("sigma_n", "sigma_s"), ("sigma_u", "sigma_v"))


def plot_joint_histograms(params: CaptureParams | str | Path, out: str | Path, *,
                          pairs: Sequence[tuple[str, str]] | None = None, bins: int = 10) -> Path:
    """2-D histograms of pairs of fitted capture parameters (default: the paper's three pairs;
    ``pairs="all"`` for every pair)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if not isinstance(params, CaptureParams):
        params = CaptureParams.load(params)
    values = {k: v.reshape(v.shape[0], -1)[:, 0].double().numpy() for k, v in params.as_dict().items()}
    spec = {s.name: s for s in params.specs}
    if pairs == "all":
        capture = [s.name for s in params.specs[5:]]
        pairs = list(itertools.combinations(capture, 2))
    pairs = list(pairs or PAPER_PAIRS)
    for a, b in pairs:
        if a not in values or b not in values:
            raise ValueError(f"unknown parameter pair ({a!r}, {b!r}); fields: {sorted(values)}")
    cols = min(3, len(pairs))
    rows = int(np.ceil(len(pairs) / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(3.6 * cols, 3.2 * rows), squeeze=False)
    for ax, (a, b) in zip(axes.flat, pairs):
        sa, sb = spec[a], spec[b]
        *_, mesh = ax.hist2d(values[b], values[a], bins=bins, range=[[sb.low, sb.high], [sa.low, sa.high]],
                             cmap="viridis")
        fig.colorbar(mesh, ax=ax, label="seeds")
        ax.set_title(f"{sa.symbol} vs {sb.symbol}", fontsize=9)
        ax.set_xlabel(f"{sb.symbol} ({sb.unit})")
        ax.set_ylabel(f"{sa.symbol} ({sa.unit})")
    for ax in list(axes.flat)[len(pairs):]:
        ax.axis("off")
    fig.suptitle(f"fitted capture parameters, {params.batch_size} seeds")
    fig.tight_layout()
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def plot_fitted_pairs(seeds: Any, fits: Mapping[str, str | Path], out: str | Path, *, mesh: Any = "quadcopter",
                      n: int = 8, zoom: int = 3) -> Path:
    """Grid: one row per seed; the real patch, then the fitted synthetic image for each distance."""
    from PIL import Image, ImageDraw

    from synthaug.fit.render_fit import render_fitted

    idx = list(range(min(n, len(seeds))))
    columns: list[np.ndarray] = []
    real = None
    for name, path in fits.items():
        r, s = render_fitted(seeds, path, mesh, indices=idx)
        real = r if real is None else real
        columns.append(s[:, 0].clamp(0, 1).numpy())
    if real is None:
        raise ValueError("no fit files given")
    tiles = [real[:, 0].numpy()] + columns
    p = tiles[0].shape[-1]
    pad = 2
    head = 14
    grid = np.full((head + len(idx) * (p * zoom + pad), len(tiles) * (p * zoom + pad)), 255, np.uint8)
    for c, col in enumerate(tiles):
        for r_, img in enumerate(col):
            t = np.kron(np.round(img * 255).astype(np.uint8), np.ones((zoom, zoom), np.uint8))
            y, x = head + r_ * (p * zoom + pad), c * (p * zoom + pad)
            grid[y:y + p * zoom, x:x + p * zoom] = t
    im = Image.fromarray(grid)
    draw = ImageDraw.Draw(im)
    for c, label in enumerate(["real"] + list(fits)):
        draw.text((c * (p * zoom + pad) + 2, 1), label, fill=0)
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    im.save(out)
    return out
