"""``synthaug preview``: a PNG grid of synthetic samples (real beside synthetic with ``--seed-set``).

Examples::

    synthaug preview --out preview.png                      # built-in quadcopter on generated skies
    synthaug preview --mesh plane.glb --seed-set seeds/drone --params fit.json --out preview.png
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np
import torch


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from synthaug._checks import add_option

    parser.add_argument("--out", default="preview.png", help="output PNG")
    parser.add_argument("--mesh", default="quadcopter", help="mesh file or built-in name (default: quadcopter)")
    add_option(parser, "--seed-set", aliases=["--seeds"], default=None,
               help="seed-set folder: show real seeds beside synthetic samples")
    parser.add_argument("--params", default=None, help="capture-parameter file (one row per seed)")
    parser.add_argument("--n", type=int, default=48, help="samples (without --seed-set) or seeds shown (with)")
    parser.add_argument("--per-seed", type=int, default=4, help="synthetic samples per real seed (with --seed-set)")
    parser.add_argument("--mode", choices=["patch", "frame"], default="patch",
                        help="patches (classifier input) or whole frames with the object composited")
    add_option(parser, "--patch-size", aliases=["--size"], type=int, default=40, help="patch side")
    parser.add_argument("--zoom", type=int, default=3, help="nearest-neighbour upscaling of each tile")
    parser.add_argument("--effects", nargs="*", default=None, help="effects to apply (default: all)")
    parser.add_argument("--step-deg", type=float, default=5.0, help="view-cache grid step (degrees)")
    parser.add_argument("--seed", type=int, default=0, help="dataset seed (poses, noise)")


def tile_grid(tiles: list[np.ndarray], cols: int, pad: int = 2, zoom: int = 1, *,
              col_labels: list[str] | None = None, row_labels: list[str] | None = None) -> np.ndarray:
    """uint8 (H, W) tiles of equal size -> one grid image, white separators, optional column/row headers.

    Example:
        >>> g = tile_grid([np.zeros((4, 4), np.uint8)] * 3, cols=2)
        >>> g.shape
        (14, 14)
    """
    h, w = tiles[0].shape
    rows = math.ceil(len(tiles) / cols)
    grid = np.full((rows * (h * zoom + pad) + pad, cols * (w * zoom + pad) + pad), 255, np.uint8)
    for k, t in enumerate(tiles):
        r, c = divmod(k, cols)
        t = np.kron(t, np.ones((zoom, zoom), np.uint8)) if zoom > 1 else t
        y, x = pad + r * (h * zoom + pad), pad + c * (w * zoom + pad)
        grid[y:y + h * zoom, x:x + w * zoom] = t
    if not col_labels and not row_labels:
        return grid
    from PIL import Image, ImageDraw, ImageFont

    font = ImageFont.load_default()
    top = 14 if col_labels else 0
    left = (6 * max(len(s) for s in row_labels) + 6) if row_labels else 0
    canvas = Image.new("L", (grid.shape[1] + left, grid.shape[0] + top), 255)
    canvas.paste(Image.fromarray(grid), (left, top))
    draw = ImageDraw.Draw(canvas)
    for c, text in enumerate(col_labels or []):
        x = left + pad + c * (w * zoom + pad) + (w * zoom) // 2
        draw.text((x, top // 2), text, fill=0, font=font, anchor="mm")
    for r, text in enumerate(row_labels or []):
        y = top + pad + r * (h * zoom + pad) + (h * zoom) // 2
        draw.text((2, y), text, fill=0, font=font, anchor="lm")
    return np.asarray(canvas)


def _u8(img: torch.Tensor) -> np.ndarray:
    a = img.detach().float().clamp(0, 1)
    a = a[0] if a.shape[0] == 1 else a.mean(0)
    return np.round(a.numpy() * 255).astype(np.uint8)


def main(args: argparse.Namespace) -> int:
    from PIL import Image

    from synthaug.data.procedural import sky_backgrounds
    from synthaug.data.synthetic import SyntheticObjectDataset
    from synthaug.params import CaptureParams, fitted_object_scales
    from synthaug.render.cache import ViewCache

    try:
        out, seeds, loaded = _validate(args)
    except (ValueError, FileNotFoundError) as e:
        print(f"synthaug preview: error: {e}", file=sys.stderr)
        return 2
    cache = ViewCache.build(args.mesh, step_deg=args.step_deg, sprite_size=96 if args.mode == "patch" else 128)
    if seeds is None:
        if args.mode == "patch":
            bgs = sky_backgrounds(8, (args.patch_size * 2, args.patch_size * 2), seed=args.seed)
        else:
            bgs = sky_backgrounds(4, (256, 320), seed=args.seed)
        params = loaded[0] if loaded else None
        ds = SyntheticObjectDataset(args.mesh, bgs, params, length=args.n, mode=args.mode, patch_size=args.patch_size,
                                    negative_fraction=0.0, effects=args.effects, seed=args.seed, render=cache)
        tiles = [_u8(img) for img, _ in ds.__getitems__(list(range(len(ds))))]
        cols = 8 if args.mode == "patch" else 2
        grid = tile_grid(tiles, cols, zoom=args.zoom if args.mode == "patch" else 1,
                         col_labels=["synthetic"] * cols)
        info = {"samples": len(tiles), "mode": args.mode}
    else:
        n = min(args.n, len(seeds))
        params, scales = None, None
        if loaded:
            params, extra, _ = loaded
            scales = fitted_object_scales(extra)
        if params is None:
            params = CaptureParams.sample(len(seeds), generator=torch.Generator().manual_seed(args.seed))
        tiles = []
        for k in range(n):
            scale = float(scales[k]) if scales is not None else seeds.object_fraction
            ds = SyntheticObjectDataset(args.mesh, [seeds.backgrounds[k]], params[k], length=args.per_seed,
                                        patch_size=seeds.patch_size, object_scale=scale,
                                        negative_fraction=0.0, effects=args.effects, seed=args.seed + k,
                                        render=cache)
            tiles.append(seeds.patches[k])
            tiles.append(seeds.backgrounds[k])
            tiles += [_u8(img) for img, _ in ds.__getitems__(list(range(args.per_seed)))]
        grid = tile_grid(tiles, 2 + args.per_seed, zoom=args.zoom,
                         col_labels=["real", "background"] + [f"synthetic {j + 1}" for j in range(args.per_seed)],
                         row_labels=[f"seed {k}" for k in range(n)])
        info = {"seeds": n, "columns": ["real", "background"] + ["synthetic"] * args.per_seed}
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.tmp{out.suffix}")  # atomic: a crash never leaves half a PNG under --out
    Image.fromarray(grid).save(tmp)
    tmp.replace(out)
    print(json.dumps({"preview": str(out), **info}))
    return 0


def _validate(args: argparse.Namespace) -> tuple[Path, Any, tuple | None]:
    """Every option and input file checked before the view cache is built: ``(out, seed set or None, the
    loaded ``--params`` (CaptureParams, extra, metadata) or None)``; raises ValueError / FileNotFoundError
    naming the option."""
    from PIL import Image

    from synthaug._checks import check_output_file, check_seedset_dir
    from synthaug.params import CaptureParams

    for name in ("n", "per_seed", "zoom"):
        if getattr(args, name) < 1:
            raise ValueError(f"--{name.replace('_', '-')} must be >= 1, got {getattr(args, name)}")
    if args.patch_size < 8:
        raise ValueError(f"--patch-size must be >= 8, got {args.patch_size}")
    if not (math.isfinite(args.step_deg) and 0.1 <= args.step_deg <= 45):
        raise ValueError(f"--step-deg must be in [0.1, 45], got {args.step_deg}")
    out = check_output_file(args.out)
    if out.suffix.lower() not in Image.registered_extensions():
        raise ValueError(f"--out: {out} has no image extension PIL can write (e.g. .png)")
    seeds = None
    if args.seed_set is not None:
        from synthaug.data.seedset import SeedSet

        seeds = SeedSet.load(check_seedset_dir(args.seed_set))
        if len(seeds) == 0:
            raise ValueError(f"--seed-set: {args.seed_set} holds no seeds")
    loaded = CaptureParams.load_with_extra(args.params) if args.params else None
    if loaded is not None and seeds is not None and loaded[0].batch_size != len(seeds):
        raise ValueError(f"--params: {args.params} has {loaded[0].batch_size} rows but {args.seed_set} has "
                         f"{len(seeds)} seeds")
    if args.effects:
        known = loaded[0].effects if loaded else CaptureParams.sample(1, generator=torch.Generator()).effects
        unknown = [e for e in args.effects if e not in known]
        if unknown:
            raise ValueError(f"--effects: {unknown} are not among the capture parameters' effects {list(known)}")
    return out, seeds, loaded
