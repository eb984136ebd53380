"""``synthaug export``: synthetic whole frames (+ the real seed frames) as a COCO or YOLO dataset.

For trainers that read a dataset from disk rather than a PyTorch ``Dataset``
(detectron2, mmdetection, ultralytics, ...). The frames come from a
:class:`~synthaug.data.synthetic.SyntheticObjectDataset` in ``mode="frame"``:
the object composited into the seed set's background frames with the fitted
capture parameters and a random pose, box = the object's rendered extent.

Layouts (``DIR`` = ``--out``)::

    coco:  DIR/images/syn_000000.png ...  DIR/annotations.json
    yolo:  DIR/images/syn_000000.png ...  DIR/labels/syn_000000.txt ...  DIR/data.yaml

Synthetic frames are ``syn_<dataset index>.png``, the real seed frames
(``--include-real``) ``real_<seed index>.png``; COCO images carry
``"synthetic": true/false``. COCO boxes are ``[x, y, w, h]`` in pixels (pixel
edges: a box covering pixel columns 3..5 is ``x = 3, w = 3``), category 1;
YOLO lines are ``0 x_center y_center width height`` divided by the image width
/ height, an empty file for a frame without an object. Boxes are clipped to
the frame. Every file is a pure function of the command (item = f(seed,
index); fixed PNG compression; sorted JSON keys), so the same command gives
byte-identical files. The output is written into a temporary folder beside
``DIR`` and renamed into place at the end: an interrupted export leaves nothing.

Examples::

    synthaug export --format coco --seed-set data/halmstad/seedsets/drone_100 \\
        --params fits/drone_100_hog.json --mesh ../shared/data/meshes/quadcopter.glb \\
        --count 5000 --include-real --out exports/drone_coco

    synthaug export --format yolo --seed-set data/halmstad/seedsets/drone_100 --count 5000 \\
        --object-size 12 48 --negative-fraction 0.1 --class-name drone --out exports/drone_yolo

Python::

    from synthaug.data.export import export_dataset, seedset_real_frames
    ds = SyntheticObjectDataset(mesh, seeds, "fit.json", mode="frame", length=1000)
    export_dataset(ds, "exports/coco", "coco", 1000, real=seedset_real_frames(seeds))
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import sys
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from synthaug._checks import one_of

__all__ = ["FORMATS", "export_dataset", "seedset_real_frames", "add_arguments", "main"]

FORMATS = ("coco", "yolo")
PNG_COMPRESSION = 6  # fixed zlib level: same pixels -> same bytes
YOLO_DECIMALS = 8  # 1e-8 of a 10,000 px frame is 1e-4 px


# ------------------------------------------------------------------ conversions
def _plain(x: Any) -> Any:
    """A torch Tensor subclass (tv_tensors.Image / BoundingBoxes) as a plain Tensor; anything else as is."""
    import torch

    if isinstance(x, torch.Tensor):
        return x.detach().cpu().as_subclass(torch.Tensor)
    return x


def _image_u8(img: Any, where: str) -> np.ndarray:
    """(C, H, W) tensor (float in [0, 1] or uint8) or (H, W) / (H, W, C) array -> uint8 (H, W) or (H, W, 3)."""
    import torch

    img = _plain(img)
    if isinstance(img, torch.Tensor):
        t = img
        if t.ndim == 2:
            t = t[None]
        if t.ndim != 3 or t.shape[0] not in (1, 3):
            raise ValueError(f"{where}: expected a (1|3, H, W) image tensor, got shape {tuple(t.shape)}")
        if t.dtype == torch.uint8:
            a = t.numpy()
        elif t.is_floating_point():
            a = np.round(t.float().clamp(0, 1).numpy() * 255.0).astype(np.uint8)
        else:
            raise ValueError(f"{where}: unsupported image dtype {t.dtype} (float in [0, 1] or uint8)")
        a = np.moveaxis(a, 0, -1)
    else:
        a = np.asarray(img)
        if a.ndim == 2:
            a = a[..., None]
        if a.ndim != 3 or a.shape[2] not in (1, 3):
            raise ValueError(f"{where}: expected an (H, W) or (H, W, 3) image, got shape {a.shape}")
        if a.dtype != np.uint8:
            if not np.issubdtype(a.dtype, np.floating):
                raise ValueError(f"{where}: unsupported image dtype {a.dtype} (float in [0, 1] or uint8)")
            a = np.round(np.clip(a, 0, 1) * 255.0).astype(np.uint8)
    return np.ascontiguousarray(a[..., 0] if a.shape[2] == 1 else a)


def _boxes_xyxy(target: Any, where: str) -> np.ndarray:
    """float64 (N, 4) XYXY boxes of a target (plain tensor/array boxes are XYXY; a
    ``tv_tensors.BoundingBoxes`` is converted from its own format)."""
    if not isinstance(target, Mapping) or "boxes" not in target:
        raise ValueError(f"{where}: the target must be a mapping with 'boxes' (a frame-mode dataset), "
                         f"got {type(target).__name__}")
    boxes = target["boxes"]
    fmt = getattr(boxes, "format", None)
    fmt_name = str(getattr(fmt, "name", fmt or "XYXY")).upper()
    b = _plain(boxes)
    if fmt_name != "XYXY":
        if fmt_name not in ("XYWH", "CXCYWH"):
            raise ValueError(f"{where}: boxes in format {fmt_name} are not supported (XYXY, XYWH or CXCYWH)")
        import torch
        from torchvision.ops import box_convert

        b = box_convert(torch.as_tensor(b).reshape(-1, 4), in_fmt=fmt_name.lower(), out_fmt="xyxy")
    if hasattr(b, "numpy"):
        b = b.numpy()
    a = np.asarray(b, dtype=np.float64).reshape(-1, 4)
    if not np.isfinite(a).all():
        raise ValueError(f"{where}: boxes must be finite")
    return a


def _clip(boxes: np.ndarray, w: int, h: int) -> np.ndarray:
    """Clip XYXY boxes to the frame; drop those left without area."""
    b = boxes.copy()
    b[:, 0::2] = b[:, 0::2].clip(0, w)
    b[:, 1::2] = b[:, 1::2].clip(0, h)
    return b[(b[:, 2] > b[:, 0]) & (b[:, 3] > b[:, 1])]


def _png_bytes(a: np.ndarray) -> bytes:
    import io

    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(a, mode="L" if a.ndim == 2 else "RGB").save(buf, format="PNG", compress_level=PNG_COMPRESSION)
    return buf.getvalue()


def _is_synthetic(target: Any) -> bool:
    v = target.get("synthetic", True) if isinstance(target, Mapping) else True
    return bool(_plain(v).item() if hasattr(v, "item") else v)


# ------------------------------------------------------------------ real frames
class _SeedFrames(Sequence):
    """The real seed frames of a seed set with their labelled box, as (image, target) pairs, read lazily."""

    def __init__(self, seeds: Any) -> None:
        self.seeds = seeds

    def __len__(self) -> int:
        return len(self.seeds)

    def __getitem__(self, i: int) -> tuple[np.ndarray, dict[str, Any]]:  # type: ignore[override]
        if not 0 <= i < len(self):
            raise IndexError(i)
        x, y, w, h = (float(v) for v in np.asarray(self.seeds.boxes[i], dtype=np.float64))
        return self.seeds.frame(i), {"boxes": np.array([[x, y, x + w, y + h]]), "synthetic": False,
                                     "seed_index": i}


def seedset_real_frames(seeds: Any) -> Sequence[tuple[np.ndarray, dict[str, Any]]]:
    """A seed set's real frames (``frames/NNNNN_frame.png``) with their labelled box (XYXY), for ``real=``.

    Args:
        seeds: a :class:`~synthaug.data.seedset.SeedSet` or the path of one.
    """
    if isinstance(seeds, (str, os.PathLike)):
        from synthaug.data.seedset import SeedSet

        seeds = SeedSet.load(seeds)
    return _SeedFrames(seeds)


# ------------------------------------------------------------------ writers
def _json_bytes(doc: Any) -> bytes:
    return (json.dumps(doc, sort_keys=True, separators=(",", ":"), allow_nan=False) + "\n").encode("utf-8")


def _yaml_str(s: str) -> str:
    return json.dumps(s)  # a JSON string is a valid YAML double-quoted scalar


def _check_out(out: Path, overwrite: bool) -> None:
    if out.exists() and not out.is_dir():
        raise FileExistsError(f"output {out} exists and is not a folder")
    if out.is_dir() and any(out.iterdir()) and not overwrite:
        raise FileExistsError(f"output folder {out} exists and is not empty (use overwrite to replace it)")


def export_dataset(
    dataset: Any,
    out: str | os.PathLike,
    fmt: str,
    count: int | None = None,
    *,
    real: Sequence[tuple[Any, Any]] | None = None,
    class_name: str = "object",
    overwrite: bool = False,
    info: Mapping[str, Any] | None = None,
    batch_size: int = 16,
) -> dict[str, Any]:
    """Write items ``0 .. count-1`` of a frame-mode dataset (and ``real`` frames) as a COCO or YOLO dataset.

    Args:
        dataset: a :class:`~synthaug.data.synthetic.SyntheticObjectDataset` in
            ``mode="frame"``, or any map-style dataset of ``(image, target)``
            with ``target["boxes"]`` XYXY pixels (plain tensors or torchvision
            ``tv_tensors``; images (C, H, W) float in [0, 1] or uint8). Items
            whose ``target["synthetic"]`` is False are written as ``real_item_*``.
        out: output folder; written into a temporary sibling, renamed at the end.
        fmt: ``"coco"`` or ``"yolo"``.
        count: number of items (default: ``len(dataset)``); at most ``len(dataset)``.
        real: extra real ``(image, target)`` frames, e.g.
            :func:`seedset_real_frames`; written as ``real_<k>.png``.
        class_name: the one category's name.
        overwrite: replace an existing non-empty ``out`` (else FileExistsError).
        info: more fields for the COCO ``info`` block (and the YOLO header comment).
        batch_size: items rendered per call (memory only; the files do not depend on it).

    Returns:
        A summary: ``out``, ``format``, ``images``, ``synthetic``, ``real``, ``boxes``, ``negatives``.

    Raises:
        ValueError: bad ``fmt`` / ``count`` / dataset mode / items.
        FileExistsError: ``out`` exists and is not empty (without ``overwrite``).
    """
    import synthaug

    one_of(fmt, FORMATS, "format")
    if getattr(dataset, "mode", "frame") != "frame":
        raise ValueError(f"export needs a frame-mode dataset (mode='frame'), got mode={dataset.mode!r}")
    n_items = len(dataset)
    count = n_items if count is None else int(count)
    if count < 1:
        raise ValueError(f"count must be >= 1, got {count}")
    if count > n_items:
        raise ValueError(f"count ({count}) exceeds the dataset's length ({n_items})")
    if batch_size < 1:
        raise ValueError(f"batch_size must be >= 1, got {batch_size}")
    out = Path(out)
    _check_out(out, overwrite)

    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(dir=out.parent, prefix=f".{out.name}.tmp-"))
    try:
        (tmp / "images").mkdir()
        if fmt == "yolo":
            (tmp / "labels").mkdir()
        writer = _ExportWriter(tmp, fmt)
        for start in range(0, count, batch_size):
            idx = list(range(start, min(start + batch_size, count)))
            items = dataset.__getitems__(idx) if hasattr(dataset, "__getitems__") else [dataset[i] for i in idx]
            for i, (image, target) in zip(idx, items):
                syn = _is_synthetic(target)
                writer.write(f"{'syn' if syn else 'real_item'}_{i:06d}", image, target, syn)
        images = writer.images
        n_syn = sum(im["synthetic"] for im in images)
        for k in range(len(real) if real is not None else 0):
            image, target = real[k]
            writer.write(f"real_{k:06d}", image, target, False)

        meta = {
            "description": f"synthaug export: {count} dataset frames"
                           + (f" + {len(real)} real frames" if real is not None else ""),
            "version": synthaug.__version__,
            "synthaug_version": synthaug.__version__,
            "seed": getattr(dataset, "seed", None),
            "epoch": getattr(dataset, "epoch", None),
            **dict(info or {}),
        }
        writer.write_index(meta, class_name, out)
        os.chmod(tmp, 0o755)
        from synthaug.data.seedset import replace_dir

        _check_out(out, overwrite)  # still free (nothing appeared while rendering)?
        replace_dir(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return {"out": str(out), "format": fmt, "images": len(images), "synthetic": n_syn,
            "real": len(images) - n_syn, "boxes": writer.n_boxes, "negatives": writer.n_negative}


class _ExportWriter:
    """Writes one image at a time into ``tmp`` (``images/<stem>.png``, YOLO ``labels/<stem>.txt``) and
    collects the COCO records; :meth:`write_index` writes ``annotations.json`` / ``data.yaml`` at the end."""

    def __init__(self, tmp: Path, fmt: str) -> None:
        self.tmp, self.fmt = tmp, fmt
        self.images: list[dict[str, Any]] = []
        self.annotations: list[dict[str, Any]] = []
        self.n_negative = self.n_boxes = 0

    def write(self, stem: str, image: Any, target: Any, synthetic: bool) -> None:
        a = _image_u8(image, stem)
        h, w = a.shape[:2]
        boxes = _clip(_boxes_xyxy(target, stem), w, h)
        self.n_negative += len(boxes) == 0
        self.n_boxes += len(boxes)
        extra = {}
        seed_index = target.get("seed_index") if isinstance(target, Mapping) else None
        if seed_index is not None and int(_plain(seed_index)) >= 0:
            extra["seed_index"] = int(_plain(seed_index))  # which seed's background / frame
        (self.tmp / "images" / f"{stem}.png").write_bytes(_png_bytes(a))
        image_id = len(self.images) + 1
        self.images.append({"id": image_id, "file_name": f"{stem}.png", "width": int(w), "height": int(h),
                            "synthetic": synthetic, **extra})
        if self.fmt == "coco":
            for x0, y0, x1, y1 in boxes.tolist():
                bw, bh = x1 - x0, y1 - y0
                self.annotations.append({"id": len(self.annotations) + 1, "image_id": image_id, "category_id": 1,
                                         "bbox": [x0, y0, bw, bh], "area": bw * bh, "iscrowd": 0})
        else:
            d = YOLO_DECIMALS
            lines = [f"0 {(x0 + x1) / 2 / w:.{d}f} {(y0 + y1) / 2 / h:.{d}f} {(x1 - x0) / w:.{d}f} "
                     f"{(y1 - y0) / h:.{d}f}\n" for x0, y0, x1, y1 in boxes.tolist()]
            (self.tmp / "labels" / f"{stem}.txt").write_text("".join(lines))

    def write_index(self, meta: Mapping[str, Any], class_name: str, out: Path) -> None:
        """COCO ``annotations.json`` (``meta`` as its ``info``) or YOLO ``data.yaml`` (``meta`` in its header)."""
        import synthaug

        if self.fmt == "coco":
            doc = {"info": meta, "images": self.images, "annotations": self.annotations,
                   "categories": [{"id": 1, "name": class_name, "supercategory": class_name}]}
            (self.tmp / "annotations.json").write_bytes(_json_bytes(doc))
        else:
            yaml = (f"# written by synthaug {synthaug.__version__}: "
                    f"{json.dumps(meta, sort_keys=True, allow_nan=False)}\n"
                    f"# val: the same images (replace with a real validation set)\n"
                    f"path: {_yaml_str(str(out.resolve()))}\n"
                    f"train: images\n"
                    f"val: images\n"
                    f"names:\n"
                    f"  0: {_yaml_str(class_name)}\n")
            (self.tmp / "data.yaml").write_text(yaml)


# ------------------------------------------------------------------ command line
def add_arguments(parser: argparse.ArgumentParser) -> None:
    from synthaug._checks import add_option

    parser.add_argument("--format", required=True, metavar="{coco,yolo}",
                        help="output layout: coco (images/ + annotations.json) or yolo (images/ + labels/ + "
                             "data.yaml, the ultralytics layout) (required)")
    add_option(parser, "--seed-set", aliases=["--seeds"], required=True,
               help="seed-set folder (synthaug ingest): its background frames are the backgrounds, "
                    "one per seed (required)")
    parser.add_argument("--params", default=None,
                        help="capture-parameter file, one row per seed (synthaug fit's output) "
                             "(default: none, one row per seed sampled from the default ranges with --seed)")
    parser.add_argument("--mesh", default="quadcopter",
                        help="mesh file (OBJ, PLY, STL, GLB/GLTF) or built-in name (default: quadcopter)")
    parser.add_argument("--count", type=int, required=True, help="number of synthetic frames, >= 1 (required)")
    parser.add_argument("--out", required=True,
                        help="output folder; must not exist or be empty unless --overwrite (required)")
    parser.add_argument("--include-real", action="store_true",
                        help="also write the seed set's real frames with their labelled box, as real_*.png "
                             "(COCO: \"synthetic\": false) (default: off)")
    parser.add_argument("--seed", type=int, default=0,
                        help="base random seed; frame i is a pure function of (seed, i) (default: 0)")
    parser.add_argument("--object-size", type=float, nargs=2, default=[20.0, 60.0], metavar=("MIN", "MAX"),
                        help="object size range in pixels (the mesh's longest side) (default: 20 60)")
    parser.add_argument("--negative-fraction", type=float, default=0.0,
                        help="fraction of frames without an object, in [0, 1] (default: 0.0)")
    parser.add_argument("--class-name", default="object", help="the category's name (default: object)")
    parser.add_argument("--overwrite", action="store_true",
                        help="replace a non-empty --out folder (default: off)")
    parser.add_argument("--step-deg", type=float, default=5.0,
                        help="view-cache grid step in degrees (default: 5.0)")
    parser.add_argument("--sprite-size", type=int, default=None,
                        help="view-cache sprite side in pixels (default: max(128, 2 x the largest object size))")
    parser.add_argument("--batch-size", type=int, default=16,
                        help="frames rendered per call (memory only; the files do not depend on it) (default: 16)")


def _fail(msg: str) -> int:
    print(f"synthaug export: {msg}", file=sys.stderr)
    return 2


def main(args: argparse.Namespace) -> int:
    if args.format not in FORMATS:
        return _fail(f"--format must be coco or yolo, got {args.format!r}")
    if args.count < 1:
        return _fail(f"--count must be >= 1, got {args.count}")
    if not (math.isfinite(args.negative_fraction) and 0.0 <= args.negative_fraction <= 1.0):
        return _fail(f"--negative-fraction must be in [0, 1], got {args.negative_fraction}")
    lo, hi = args.object_size
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo <= hi):
        return _fail(f"--object-size must be MIN MAX with 0 < MIN <= MAX, got {lo:g} {hi:g}")
    if args.sprite_size is not None and args.sprite_size < 8:
        return _fail(f"--sprite-size must be >= 8, got {args.sprite_size}")
    if not 0.1 <= args.step_deg <= 45:
        return _fail(f"--step-deg must be in [0.1, 45], got {args.step_deg:g}")
    if args.batch_size < 1:
        return _fail(f"--batch-size must be >= 1, got {args.batch_size}")
    out = Path(args.out)
    try:
        _check_out(out, args.overwrite)
    except FileExistsError as e:
        return _fail(f"--out: {e}".replace("(use overwrite", "(use --overwrite"))

    from synthaug.data.seedset import SeedSet
    from synthaug.params import CaptureParams

    seeds_dir = Path(args.seed_set)
    if not seeds_dir.is_dir():
        return _fail(f"--seed-set: seed-set folder not found: {seeds_dir}" if not seeds_dir.exists()
                     else f"--seed-set: not a folder: {seeds_dir}")
    try:
        seeds = SeedSet.load(seeds_dir)
    except (FileNotFoundError, ValueError, OSError) as e:
        return _fail(f"--seed-set: {e}")
    if len(seeds) == 0:
        return _fail(f"--seed-set: {seeds_dir} holds no seeds")
    params = None
    if args.params is not None:
        try:
            params = CaptureParams.load(args.params)
        except (FileNotFoundError, ValueError, OSError) as e:
            return _fail(f"--params: {e}")
        if params.batch_size != len(seeds):
            return _fail(f"--params: {args.params} has {params.batch_size} rows but the seed set {args.seed_set} "
                         f"has {len(seeds)} seeds (one row per seed)")
    if args.mesh not in _builtin_meshes() and not Path(args.mesh).is_file():
        return _fail(f"--mesh: mesh file not found: {args.mesh} (built-in names: {sorted(_builtin_meshes())})")

    from synthaug.data.synthetic import SyntheticObjectDataset
    from synthaug.render.cache import ViewCache

    sprite = args.sprite_size if args.sprite_size is not None else max(128, 2 * int(math.ceil(hi)))
    try:
        cache = ViewCache.build(args.mesh, step_deg=args.step_deg, sprite_size=sprite)
    except (FileNotFoundError, ValueError) as e:
        return _fail(f"--mesh: {e}")
    try:
        ds = SyntheticObjectDataset(args.mesh, seeds, params, length=args.count, mode="frame",
                                    negative_fraction=args.negative_fraction, object_size=(lo, hi),
                                    channels=params.channels if params is not None else 1, seed=args.seed,
                                    render=cache)
    except ValueError as e:
        msg = str(e)
        if "smaller than" in msg:
            msg = f"--object-size {lo:g} {hi:g}: {msg} (an object of MAX px needs frames of at least 2 x MAX px)"
        return _fail(msg)
    options = {k: v for k, v in sorted(vars(args).items())
               if not k.startswith("_") and k not in ("command", "overwrite", "batch_size")}
    try:
        summary = export_dataset(ds, out, args.format, args.count,
                                 real=seedset_real_frames(seeds) if args.include_real else None,
                                 class_name=args.class_name, overwrite=args.overwrite,
                                 info={"options": options}, batch_size=args.batch_size)
    except FileExistsError as e:
        return _fail(f"--out: {e}")
    except ValueError as e:
        return _fail(str(e))
    print(json.dumps(summary))
    return 0


def _builtin_meshes() -> Any:
    from synthaug.render.mesh import BUILTIN_MESHES

    return BUILTIN_MESHES
