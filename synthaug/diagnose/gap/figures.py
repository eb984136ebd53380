"""The gap's pictures: mean HOG glyphs (real / synthetic / difference), the CNN channels that differ
most, and samples sorted by the two-sample classifier's held-out "looks synthetic" probability.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import Tensor

from synthaug.diagnose.gap.features import FeatureExtractor, _float_patches
from synthaug.diagnose.gap.separation import hog_cell_means
from synthaug.diagnose.gap.two_sample import TwoSampleTest


def _figure_array(fig: Any, path: str | os.PathLike | None) -> np.ndarray:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)  # no global backend switch: pyplot is never imported
    canvas.draw()
    rgb = np.asarray(canvas.buffer_rgba())[..., :3].copy()
    if path is not None:
        _save_png(rgb, path)
    return rgb


def _save_png(image: np.ndarray, path: str | os.PathLike) -> Path:
    from PIL import Image

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp.png")  # atomic: never half a PNG under its final name
    Image.fromarray(image).save(tmp)
    tmp.replace(path)
    return path


def _draw_glyphs(ax: Any, cells: np.ndarray, scale: float, signed: bool = False) -> None:
    n_rows, n_cols, n_ori = cells.shape
    for r in range(n_rows):
        for c in range(n_cols):
            for o in range(n_ori):
                v = cells[r, c, o]
                if v == 0:
                    continue
                theta = (o + 0.5) * math.pi / n_ori  # gradient angle, rows pointing down
                # the glyph draws the edge, perpendicular to the gradient
                dx, dy = -math.sin(theta) * 0.45, math.cos(theta) * 0.45
                colour = ("tab:red" if v > 0 else "tab:blue") if signed else "white"
                ax.plot([c + 0.5 - dx, c + 0.5 + dx], [r + 0.5 - dy, r + 0.5 + dy], color=colour,
                        lw=0.3 + 4.0 * abs(v) / scale, solid_capstyle="round")
    ax.set_xlim(0, n_cols)
    ax.set_ylim(n_rows, 0)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


def render_hog_glyphs(real_feats: np.ndarray | Tensor, syn_feats: np.ndarray | Tensor, config: Any, window: int,
                      path: str | os.PathLike | None = None) -> np.ndarray:
    """Mean HOG glyphs — real, synthetic, and synthetic − real — as one RGB image.

    Each cell shows one line per orientation bin along the *edge* direction (perpendicular to the gradient
    bin), its width the mean block-normalised value (averaged over the blocks holding the cell). In the
    difference panel, red = more in synthetic, blue = more in real.

    Args:
        real_feats: real HOG descriptors ``(N_r, D)``.
        syn_feats: synthetic HOG descriptors ``(N_s, D)``.
        config: the HOG settings.
        window: patch side.
        path: also written there as PNG (atomically).

    Returns:
        uint8 ``(H, W, 3)``.
    """
    from matplotlib.figure import Figure

    real = hog_cell_means(real_feats, config, window)
    syn = hog_cell_means(syn_feats, config, window)
    fig = Figure(figsize=(9, 3.3), dpi=90)
    axes = fig.subplots(1, 3)
    scale = max(float(real.max()), float(syn.max()), 1e-9)
    diff = syn - real
    for ax, cells, title, signed, s in ((axes[0], real, "real (mean HOG)", False, scale),
                                        (axes[1], syn, "synthetic (mean HOG)", False, scale),
                                        (axes[2], diff, "synthetic - real", True,
                                         max(float(np.abs(diff).max()), 1e-9))):
        if not signed:
            ax.set_facecolor("black")
        _draw_glyphs(ax, cells, s, signed)
        ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return _figure_array(fig, path)


def render_cnn_separation(effect: np.ndarray, extractor: FeatureExtractor, *, channels: int = 8,
                          path: str | os.PathLike | None = None) -> np.ndarray:
    """The CNN's most separating activations: per-position effect size maps of the top channels of layers 2, 3.

    Args:
        effect: Cohen's d per feature ``(D,)`` (:func:`effect_sizes`), in the extractor's order.
        extractor: the ``cnn`` :class:`FeatureExtractor` the features came from.
        channels: channels shown per layer (those with the largest mean |d|).
        path: also written there as PNG.

    Returns:
        uint8 ``(H, W, 3)``; red = activation larger in synthetic.
    """
    from matplotlib.figure import Figure

    if extractor.family != "cnn":
        raise ValueError(f"render_cnn_separation needs a cnn extractor, got {extractor.family!r}")
    effect = np.asarray(effect, np.float64)
    if effect.shape != (extractor.n_features,):
        raise ValueError(f"effect must have shape ({extractor.n_features},), got {effect.shape}")
    effect = np.clip(effect, -10, 10)
    maps, start = [], 0
    for layer, shape in zip(extractor.layout["layers"], extractor.layout["shapes"]):
        size = int(np.prod(shape))
        maps.append((layer, effect[start:start + size].reshape(shape)))
        start += size
    shown = [(layer, m) for layer, m in maps if m.shape[-1] > 1]  # spatial layers (2 and 3 for 40 px)
    v = max(max(float(np.abs(m).max()) for _, m in shown), 1e-9)
    fig = Figure(figsize=(1.3 * channels, 1.5 * len(shown) + 0.4), dpi=90)
    axes = np.atleast_2d(fig.subplots(len(shown), channels, squeeze=False))
    for row, (layer, m) in enumerate(shown):
        order = np.argsort(-np.abs(m).mean(axis=(1, 2)), kind="stable")
        for col in range(channels):
            ax = axes[row, col]
            ax.set_xticks([])
            ax.set_yticks([])
            if col >= len(order):
                ax.set_axis_off()
                continue
            c = order[col]
            ax.imshow(m[c], cmap="RdBu_r", vmin=-v, vmax=v)
            ax.set_title(f"L{layer} ch{c}", fontsize=7)
    fig.suptitle("Cohen's d per activation (red: larger in synthetic)", fontsize=8)
    fig.tight_layout()
    return _figure_array(fig, path)


def _u8_tiles(patches: Tensor | np.ndarray, index: np.ndarray) -> list[np.ndarray]:
    x = _float_patches(patches, None)[torch.as_tensor(np.ascontiguousarray(index), dtype=torch.long)]
    return [np.round(t[0].clamp(0, 1).numpy() * 255).astype(np.uint8) for t in x]


def looks_synthetic_grid(real_patches: Tensor | np.ndarray, syn_patches: Tensor | np.ndarray, test: TwoSampleTest,
                         *, n: int = 8, zoom: int = 2, path: str | os.PathLike | None = None) -> np.ndarray:
    """Samples sorted by the two-sample test's held-out P(synthetic), as one labelled grid.

    Rows: the synthetic patches that look most synthetic (what gives them away) and most real, then the real
    patches that look most synthetic and most real. Tiling is :func:`synthaug.data.preview.tile_grid`.

    Args:
        real_patches: the real patches the test's features came from (rows match ``test.real_index``).
        syn_patches: the synthetic patches, likewise.
        test: a :class:`TwoSampleTest` of their features.
        n: patches per row.
        zoom: nearest-neighbour upscaling.
        path: also written there as PNG.

    Returns:
        uint8 ``(H, W)`` grid.
    """
    from synthaug.data.preview import tile_grid

    m = len(test.real_index)
    p_real, p_syn = test.probabilities[:m], test.probabilities[m:]
    n = max(1, min(int(n), m))
    syn_order = test.syn_index[np.argsort(-p_syn, kind="stable")]
    real_order = test.real_index[np.argsort(-p_real, kind="stable")]
    p_syn_sorted, p_real_sorted = np.sort(p_syn)[::-1], np.sort(p_real)[::-1]
    rows = [(_u8_tiles(syn_patches, syn_order[:n]), f"syn, most synthetic (p>={p_syn_sorted[n - 1]:.2f})"),
            (_u8_tiles(syn_patches, syn_order[::-1][:n]), f"syn, most real (p<={p_syn_sorted[::-1][n - 1]:.2f})"),
            (_u8_tiles(real_patches, real_order[:n]), f"real, most synthetic (p>={p_real_sorted[n - 1]:.2f})"),
            (_u8_tiles(real_patches, real_order[::-1][:n]), f"real, most real (p<={p_real_sorted[::-1][n - 1]:.2f})")]
    tiles = [t for r, _ in rows for t in r]
    grid = tile_grid(tiles, n, zoom=zoom, row_labels=[label for _, label in rows])
    if path is not None:
        _save_png(grid, path)
    return grid
