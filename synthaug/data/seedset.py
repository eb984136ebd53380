"""The on-disk seed set: real object patches, their backgrounds, boxes, frames, provenance.

Format ``synthaug.seedset`` version 1, a folder::

    seedset.json            header + one record per seed + one per negative
    arrays.npz              patches (N, P, P) uint8      object patches, grayscale
                            backgrounds (N, P, P) uint8  same crops of the background frame
                            boxes (N, 4) float32         xywh in full-frame pixels
                            centres (N, 2) float32       object centre (x, y), full-frame pixels
                            crops (N, 3) float32         crop centre x, y and side in frame pixels
                            negatives (M, P, P) uint8    object-free patches (may be M = 0)
    frames/NNNNN_frame.png        full original frame of seed NNNNN (grayscale)
    frames/NNNNN_background.png   full-frame background, object removed

Header fields: ``format``, ``version``, ``patch_size`` (P), ``object_fraction``
(the box's longest side spans this fraction of the patch side), ``source``
(free-form: input folders, split file, ingest options), ``n_seeds``,
``n_negatives``. A seed record holds ``video``, ``frame`` (index in the video),
``class``, ``background_method``, ``background_quality``, ``split`` and more
(``source_path``, ``n_aligned``, ``inpainted_fraction``, ...). A negative record
holds ``kind`` (``"background"`` or ``"hard"``), ``video``, ``frame``, ``class``
and ``crop``.

A seed set is written into a temporary sibling folder and renamed into place,
so readers never see a half-written one.

Patch geometry: pixel ``(u, v)`` of a patch (OpenCV convention, pixel centres
at integers) samples the frame at ``(c_x + (u + 0.5 - P/2) / s - 0.5, ...)``
with ``s = P * object_fraction / max(w, h)``: the object centre lands on the
patch centre and the box's longest side spans ``object_fraction * P`` pixels.

Example:
    >>> import numpy as np, tempfile, os
    >>> frame = np.zeros((60, 80), np.uint8); frame[20:40, 30:50] = 200
    >>> patch, crop = crop_patch(frame, box=(30, 20, 20, 20), patch_size=40, object_fraction=0.5)
    >>> patch.shape, crop.tolist(), int(patch[20, 20]), int(patch[2, 2])
    ((40, 40), [40.0, 30.0, 40.0], 200, 0)
    >>> with tempfile.TemporaryDirectory() as d:
    ...     _ = write_seedset(os.path.join(d, "s"), patches=patch[None], backgrounds=np.zeros_like(patch)[None],
    ...                       boxes=[[30, 20, 20, 20]], centres=[[40, 30]], crops=[crop], records=[{"video": "v"}],
    ...                       frames=[frame], background_frames=[np.zeros_like(frame)],
    ...                       metadata={"patch_size": 40, "object_fraction": 0.5})
    ...     s = SeedSet.load(os.path.join(d, "s"))
    ...     len(s), s.patches.shape, s.frame(0).shape, s.negatives.shape
    (1, (1, 40, 40), (60, 80), (0, 40, 40))
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import shutil
import tempfile
import uuid
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from synthaug._io import atomic_write_bytes, read_versioned_json

__all__ = [
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "SeedSet",
    "write_seedset",
    "crop_patch",
    "crop_geometry",
    "crop_resampling_sigma",
    "seed_geometry",
    "atomic_write_bytes",
    "replace_dir",
    "load_npz",
]

FORMAT_NAME = "synthaug.seedset"
FORMAT_VERSION = 1
HEADER = "seedset.json"
ARRAYS = "arrays.npz"
COLOUR = "colour.npz"  # optional RGB patches (patches_rgb, backgrounds_rgb)
ARRAY_KEYS = ("patches", "backgrounds", "boxes", "centres", "crops", "negatives")


def load_npz(path: str | os.PathLike, keys: Sequence[str] = ()) -> dict[str, np.ndarray]:
    """All arrays of an ``.npz`` file, never unpickling (``allow_pickle=False``); errors name the file.

    Raises:
        FileNotFoundError: if the file is missing.
        ValueError: naming the file, if it is truncated, not an npz archive, holds pickled (object) arrays
            or lacks one of ``keys``.
    """
    import zipfile

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path} is missing")
    try:
        z = np.load(path, allow_pickle=False)
    except (zipfile.BadZipFile, OSError, ValueError, EOFError) as e:
        # bytes that are neither .npz nor .npy are taken for a pickle, which allow_pickle=False refuses
        why = "unrecognised bytes" if "pickle" in str(e) else f"{type(e).__name__}: {e}"
        raise ValueError(f"{path} is not a readable npz archive (truncated or corrupt?): {why}") from None
    if not hasattr(z, "files"):
        raise ValueError(f"{path} is a single .npy array, not an .npz archive")
    try:
        with z:
            arrays = {k: z[k] for k in z.files}
    except (zipfile.BadZipFile, EOFError, OSError, ValueError, KeyError) as e:
        why = ("it holds pickled (object) arrays, which are never loaded" if "allow_pickle" in str(e)
               else f"{type(e).__name__}: {e}")
        raise ValueError(f"{path} is not a readable npz archive (truncated or corrupt?): {why}") from None
    missing = [k for k in keys if k not in arrays]
    if missing:
        raise ValueError(f"{path}: arrays {missing} are missing (it has {sorted(arrays)})")
    return arrays


def replace_dir(tmp: Path, final: Path) -> None:
    """Move the finished folder ``tmp`` to ``final``, replacing an older ``final``.

    Safe against another writer replacing the same folder at the same time (one of the two folders stays, whole):
    a ``final`` moved away between the check and the move, or put back before ours lands, is looked at again.
    """
    final = Path(final)
    while True:
        old = None
        if final.exists():
            old = final.with_name(f".{final.name}.old-{os.getpid()}-{uuid.uuid4().hex[:8]}")
            try:
                os.replace(final, old)
            except FileNotFoundError:  # another writer moved it first
                continue
        try:
            os.replace(tmp, final)
        except OSError as e:
            if e.errno in (errno.ENOTEMPTY, errno.EEXIST):  # another writer's folder landed in between: replace it
                if old is not None:
                    shutil.rmtree(old, ignore_errors=True)
                continue
            if old is not None:  # put the former folder back: nothing lost
                with contextlib.suppress(OSError):
                    os.replace(old, final)
            raise
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        return


def crop_geometry(box: Sequence[float], *, patch_size: int = 40, object_fraction: float = 0.7) -> np.ndarray:
    """``[c_x, c_y, side]``: the square frame region a seed patch shows.

    Example:
        >>> crop_geometry((10, 20, 28, 14), patch_size=40, object_fraction=0.7).tolist()
        [24.0, 27.0, 40.0]
    """
    x, y, w, h = (float(v) for v in box)
    if not (w > 0 and h > 0):
        raise ValueError(f"box must have positive size, got {list(box)}")
    if not 0 < object_fraction <= 1:
        raise ValueError(f"object_fraction must be in (0, 1], got {object_fraction}")
    return np.array([x + w / 2, y + h / 2, max(w, h) / object_fraction], dtype=np.float32)


def crop_patch(
    image: np.ndarray,
    *,
    box: Sequence[float] | None = None,
    crop: Sequence[float] | None = None,
    patch_size: int = 40,
    object_fraction: float = 0.7,
) -> tuple[np.ndarray, np.ndarray]:
    """Cut a ``P x P`` patch, object centred and scale-normalised, out of a frame.

    Pixels outside the frame replicate the border. Downscaling is
    anti-aliased (Gaussian pre-blur of sigma ``0.4 / s`` for a scale ``s < 1``).

    Args:
        image: uint8 ``(H, W)`` frame, or ``(H, W, 3)`` (every channel cut the same way).
        box: xywh object box (gives the crop through :func:`crop_geometry`), or
        crop: ``[c_x, c_y, side]`` directly (e.g. the crop of a seed, to cut
            the same region out of its background frame).
        patch_size: P.
        object_fraction: see :func:`crop_geometry`.

    Returns:
        ``(patch, crop)``: uint8 ``(P, P)`` (``(P, P, 3)``) and float32 ``[c_x, c_y, side]``.
    """
    import cv2

    if (box is None) == (crop is None):
        raise ValueError("give exactly one of box= and crop=")
    if patch_size < 2:
        raise ValueError(f"patch_size must be >= 2, got {patch_size}")
    if not (image.ndim == 2 or image.ndim == 3 and image.shape[2] == 3):
        raise ValueError(f"image must be grayscale (H, W) or RGB (H, W, 3), got shape {image.shape}")
    c = crop_geometry(box, patch_size=patch_size, object_fraction=object_fraction) if box is not None \
        else np.asarray(crop, dtype=np.float32)
    cx, cy, side = (float(v) for v in c)
    if not side > 0:
        raise ValueError(f"crop side must be > 0, got {side}")
    s = patch_size / side
    src = image
    ox = oy = 0
    if s < 1:
        # blur only the window the patch reads from
        sigma = 0.4 / s
        pad = int(np.ceil(side / 2 + 3 * sigma + 2))
        x0, y0 = max(int(cx) - pad, 0), max(int(cy) - pad, 0)
        x1, y1 = min(int(cx) + pad + 1, image.shape[1]), min(int(cy) + pad + 1, image.shape[0])
        if x1 > x0 and y1 > y0:
            src = cv2.GaussianBlur(image[y0:y1, x0:x1], (0, 0), sigma, borderType=cv2.BORDER_REPLICATE)
            ox, oy = x0, y0
    M = np.array([[s, 0, s * (0.5 - cx + ox) + patch_size / 2 - 0.5],
                  [0, s, s * (0.5 - cy + oy) + patch_size / 2 - 0.5]], dtype=np.float64)
    patch = cv2.warpAffine(src, M, (patch_size, patch_size), flags=cv2.INTER_LINEAR,
                           borderMode=cv2.BORDER_REPLICATE)
    return patch, c


def crop_resampling_sigma(frame_scale: Any) -> np.ndarray:
    """Std (patch px) of the blur :func:`crop_patch` puts on a seed patch, per axis.

    A seed patch is a resampled crop: for ``frame_scale = side / P > 1``
    (downscaling) the Gaussian pre-blur of σ = 0.4 patch px, then bilinear
    interpolation, whose tent kernel has variance 1/6 frame px² on average
    over the sub-pixel phase, i.e. ``1 / (6 frame_scale²)`` patch px².
    The background patch B_i went through the same resampling; a rendered
    object layer did not, so a model that composites a render over B_i
    needs this blur on the object to match the seed patch.

    Example:
        >>> [round(float(v), 3) for v in crop_resampling_sigma([0.5, 1.0, 2.0])]
        [0.816, 0.408, 0.449]
    """
    fs = np.asarray(frame_scale, dtype=np.float64)
    if np.any(~np.isfinite(fs)) or np.any(fs <= 0):
        raise ValueError(f"frame_scale must be positive and finite, got {frame_scale}")
    return np.sqrt(np.where(fs > 1.0, 0.16, 0.0) + 1.0 / (6.0 * fs * fs))


def seed_geometry(seeds: Any) -> dict[str, torch.Tensor]:
    """Where each seed patch sits in its frame, for the position-aware effects.

    Args:
        seeds: a :class:`~synthaug.data.seedset.SeedSet` (or a path to one).

    Returns:
        ``origin`` (N, 2), ``frame_size`` (N, 2) (W, H), ``frame_scale`` (N,)
        float32, as :func:`synthaug.effects.simulate` takes them
        (``origin=``, ``frame_size=``, ``extras={"frame_scale": ...}``).
    """
    import torch

    if isinstance(seeds, (str, os.PathLike)):
        seeds = SeedSet.load(seeds)
    crops = torch.as_tensor(np.asarray(seeds.crops, np.float64))
    side = crops[:, 2]
    origin = crops[:, :2] - side[:, None] / 2
    fs = seeds.metadata.get("frame_size")
    if fs is not None:
        frame_size = torch.tensor([[float(fs[0]), float(fs[1])]], dtype=torch.float64).expand(len(seeds), 2)
    else:
        frame_size = torch.tensor([[float(s) for s in seeds.frame(i).shape[::-1]] for i in range(len(seeds))],
                                  dtype=torch.float64).reshape(-1, 2)
    return {"origin": origin.float(), "frame_size": frame_size.float().contiguous(),
            "frame_scale": (side / seeds.patch_size).float()}


def _u8_stack(arrs: Any, p: int, name: str) -> np.ndarray:
    a = np.asarray(arrs, dtype=np.uint8) if len(arrs) else np.zeros((0, p, p), np.uint8)
    if a.ndim != 3 or a.shape[1:] != (p, p):
        raise ValueError(f"{name} must have shape (N, {p}, {p}), got {a.shape}")
    return a


def write_seedset(
    path: str | os.PathLike,
    *,
    patches: Any,
    backgrounds: Any,
    boxes: Any,
    centres: Any,
    crops: Any,
    records: Sequence[Mapping[str, Any]],
    frames: Sequence[np.ndarray | os.PathLike | str],
    background_frames: Sequence[np.ndarray | os.PathLike | str],
    negatives: Any = (),
    negative_records: Sequence[Mapping[str, Any]] | None = None,
    metadata: Mapping[str, Any] | None = None,
    extra_files: Mapping[str, bytes] | None = None,
    patches_rgb: Any = None,
    backgrounds_rgb: Any = None,
    neighbour_frames: Sequence[np.ndarray | os.PathLike | str | None] | None = None,
) -> Path:
    """Write a seed set folder atomically (temporary sibling, then rename).

    Args:
        path: the seed-set folder (replaced if it exists).
        patches: uint8 ``(N, P, P)`` object patches.
        backgrounds: uint8 ``(N, P, P)`` background patches.
        boxes: ``(N, 4)`` xywh boxes.
        centres: ``(N, 2)`` object centres.
        crops: ``(N, 3)`` crop centre and side.
        records: N provenance dicts.
        frames: N full frames, each a uint8 ``(H, W)`` array or the path of a
            PNG to copy (hard-linked when possible).
        background_frames: N full-frame backgrounds, same forms.
        negatives: uint8 ``(M, P, P)``.
        negative_records: M dicts (default: empty dicts).
        metadata: header fields; must hold ``patch_size`` and ``object_fraction``.
        extra_files: more files to place in the folder (e.g. a contact sheet PNG).
        patches_rgb, backgrounds_rgb: optional uint8 ``(N, P, P, 3)`` RGB versions of
            ``patches`` / ``backgrounds`` (same crops), written to ``colour.npz``
            (:meth:`SeedSet.colour`); the gray arrays stay the seed set's images.
        neighbour_frames: optional, per seed, a second frame of the same scene (e.g. the
            next frame of the video; None where there is none), written as
            ``frames/NNNNN_neighbour.png`` (:meth:`SeedSet.neighbour_frame`); the record
            says how it maps onto the seed's frame (``neighbour``: ``homography``, ``box``).

    Returns:
        The final folder path.
    """
    path = Path(path)
    meta = dict(metadata or {})
    if "patch_size" not in meta or "object_fraction" not in meta:
        raise ValueError(f"metadata must hold patch_size and object_fraction, got keys {sorted(meta)}")
    p = int(meta["patch_size"])
    n = len(records)
    patches = _u8_stack(patches, p, "patches")
    backgrounds = _u8_stack(backgrounds, p, "backgrounds")
    negatives = _u8_stack(negatives, p, "negatives")
    boxes = np.asarray(boxes, np.float32).reshape(-1, 4)
    centres = np.asarray(centres, np.float32).reshape(-1, 2)
    crops = np.asarray(crops, np.float32).reshape(-1, 3)
    neighbours = list(neighbour_frames) if neighbour_frames is not None else [None] * n
    for name, arr in (("patches", patches), ("backgrounds", backgrounds), ("boxes", boxes), ("centres", centres),
                      ("crops", crops), ("frames", frames), ("background_frames", background_frames),
                      ("neighbour_frames", neighbours)):
        if len(arr) != n:
            raise ValueError(f"{name} must have one entry per record ({n}), got {len(arr)}")
    if (patches_rgb is None) != (backgrounds_rgb is None):
        raise ValueError("give both patches_rgb and backgrounds_rgb, or neither")
    if patches_rgb is not None:
        patches_rgb, backgrounds_rgb = np.asarray(patches_rgb), np.asarray(backgrounds_rgb)
        for name, arr in (("patches_rgb", patches_rgb), ("backgrounds_rgb", backgrounds_rgb)):
            if arr.dtype != np.uint8 or arr.shape != (n, p, p, 3):
                raise ValueError(f"{name} must be uint8 {(n, p, p, 3)}, got {arr.dtype} {arr.shape}")
    neg_records = list(negative_records) if negative_records is not None else [{} for _ in range(len(negatives))]
    if len(neg_records) != len(negatives):
        raise ValueError(f"negative_records must have one entry per negative ({len(negatives)}), got {len(neg_records)}")

    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(dir=path.parent, prefix=f".{path.name}.tmp-"))
    try:
        (tmp / "frames").mkdir()
        recs = _write_frames(tmp, records, frames, background_frames, neighbours)
        with open(tmp / ARRAYS, "wb") as f:
            np.savez(f, patches=patches, backgrounds=backgrounds, boxes=boxes, centres=centres, crops=crops,
                     negatives=negatives)
        if patches_rgb is not None:
            with open(tmp / COLOUR, "wb") as f:
                np.savez_compressed(f, patches_rgb=patches_rgb, backgrounds_rgb=backgrounds_rgb)
        for name, data in (extra_files or {}).items():
            (tmp / name).write_bytes(data)
        header = {"format": FORMAT_NAME, "version": FORMAT_VERSION, **meta, "patch_size": p,
                  "object_fraction": float(meta["object_fraction"]), "n_seeds": n, "n_negatives": len(negatives),
                  "records": recs, "negative_records": [dict(r) for r in neg_records]}
        (tmp / HEADER).write_text(json.dumps(_jsonable(header), indent=1))
        os.chmod(tmp, 0o755)
        replace_dir(tmp, path)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return path


def _write_frames(tmp: Path, records: Sequence[Mapping[str, Any]], frames: Sequence[Any],
                  background_frames: Sequence[Any], neighbours: Sequence[Any]) -> list[dict[str, Any]]:
    """Each seed's frame, background frame and neighbour frame (if any) as ``frames/NNNNN_<kind>.png`` in
    ``tmp`` (arrays encoded, paths hard-linked or copied); the records with their file names."""
    import cv2

    recs = []
    for i, rec in enumerate(records):
        rec = dict(rec)
        for key, src, suffix in (("frame_file", frames[i], "frame"),
                                 ("background_file", background_frames[i], "background"),
                                 ("neighbour_file", neighbours[i], "neighbour")):
            if src is None and key == "neighbour_file":
                rec.pop(key, None)
                continue
            name = f"frames/{i:05d}_{suffix}.png"
            dst = tmp / name
            if isinstance(src, np.ndarray):
                if src.dtype != np.uint8 or src.ndim != 2:
                    raise ValueError(f"{key} {i} must be uint8 (H, W), got {src.dtype} {src.shape}")
                ok, buf = cv2.imencode(".png", src, [cv2.IMWRITE_PNG_COMPRESSION, 1])
                if not ok:
                    raise RuntimeError(f"cannot encode {key} {i} as PNG")
                dst.write_bytes(buf.tobytes())
            else:
                try:
                    os.link(src, dst)
                except OSError:
                    shutil.copyfile(src, dst)
            rec[key] = name
        recs.append(rec)
    return recs


def _jsonable(x: Any) -> Any:
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, Path):
        return str(x)
    return x


class SeedSet:
    """A seed set read from disk (see the module docstring for the format).

    Attributes:
        path: the folder.
        patches: uint8 ``(N, P, P)`` grayscale object patches, object centred,
            box's longest side spanning ``object_fraction * P``.
        backgrounds: uint8 ``(N, P, P)`` the same crops of the background frames.
        boxes: float32 ``(N, 4)`` xywh in full-frame pixels.
        centres: float32 ``(N, 2)`` object centres.
        crops: float32 ``(N, 3)`` crop centre and side in frame pixels.
        records: N provenance dicts (``video``, ``frame``, ``class``,
            ``background_method``, ``background_quality``, ``split``, ...).
        negatives: uint8 ``(M, P, P)`` object-free patches (``M`` may be 0).
        negative_records: M dicts (``kind``: ``"background"`` or ``"hard"``, ...).
        metadata: the header without the record lists.
    """

    def __init__(self, path: Path, header: dict[str, Any], arrays: Mapping[str, np.ndarray]) -> None:
        self.path = Path(path)
        self.records: list[dict[str, Any]] = list(header.pop("records"))
        self.negative_records: list[dict[str, Any]] = list(header.pop("negative_records", []))
        self.metadata: dict[str, Any] = header
        self.patches = arrays["patches"]
        self.backgrounds = arrays["backgrounds"]
        self.boxes = arrays["boxes"]
        self.centres = arrays["centres"]
        self.crops = arrays["crops"]
        self.negatives = arrays["negatives"]

    @classmethod
    def load(cls, path: str | os.PathLike) -> "SeedSet":
        """Read a seed-set folder; errors name the folder and the problem."""
        path = Path(path)
        head = path / HEADER
        if not head.is_file():
            raise FileNotFoundError(f"not a seed set (no {HEADER}): {path}")
        header = read_versioned_json(head, format=FORMAT_NAME, version=FORMAT_VERSION, what="seed set")
        if not isinstance(header.get("records"), list):
            raise ValueError(f"{head}: the header has no 'records' list")
        arrays = load_npz(path / ARRAYS, ARRAY_KEYS)
        n = len(header["records"])
        if len(arrays["patches"]) != n:
            raise ValueError(f"{path / ARRAYS}: {len(arrays['patches'])} patches for {n} records in {head}")
        return cls(path, header, arrays)

    def __len__(self) -> int:
        return len(self.records)

    @property
    def patch_size(self) -> int:
        return int(self.metadata["patch_size"])

    @property
    def object_fraction(self) -> float:
        return float(self.metadata["object_fraction"])

    def _png(self, i: int, key: str) -> np.ndarray:
        import cv2

        if not -len(self) <= i < len(self):
            raise IndexError(f"seed index must be in [0, {len(self)}), got {i}")
        f = self.path / self.records[i][key]
        img = cv2.imread(str(f), cv2.IMREAD_GRAYSCALE)
        if img is None:
            raise FileNotFoundError(f"seed {i}: cannot read {f}")
        return img

    def frame(self, i: int) -> np.ndarray:
        """Full original frame of seed ``i``, uint8 ``(H, W)``."""
        return self._png(i, "frame_file")

    def background_frame(self, i: int) -> np.ndarray:
        """Full-frame background of seed ``i`` (object removed), uint8 ``(H, W)``."""
        return self._png(i, "background_file")

    def neighbour_frame(self, i: int) -> np.ndarray | None:
        """A second frame of seed ``i``'s scene, uint8 ``(H, W)`` (record ``neighbour``: its homography onto
        the seed's frame and its object box), or None when the seed set has none."""
        return self._png(i, "neighbour_file") if "neighbour_file" in self.records[i] else None

    def neighbour_frame_path(self, i: int) -> Path | None:
        f = self.records[i].get("neighbour_file")
        return None if f is None else self.path / f

    def frame_path(self, i: int) -> Path:
        return self.path / self.records[i]["frame_file"]

    def background_frame_path(self, i: int) -> Path:
        return self.path / self.records[i]["background_file"]

    def colour(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The RGB seed patches and backgrounds, uint8 ``(N, P, P, 3)`` each, or None (a gray seed set)."""
        f = self.path / COLOUR
        if not f.exists():
            return None
        z = load_npz(f, ("patches_rgb", "backgrounds_rgb"))
        rgb, bg = z["patches_rgb"], z["backgrounds_rgb"]
        want = (len(self), self.patch_size, self.patch_size, 3)
        if rgb.shape != want or bg.shape != want:
            raise ValueError(f"{f}: expected RGB patches {want}, got {rgb.shape} and {bg.shape}")
        return rgb, bg

    def save_subset(self, path: str | os.PathLike, indices: Sequence[int], *,
                    negatives: bool | Sequence[int] = True, metadata: Mapping[str, Any] | None = None,
                    extra_files: Mapping[str, bytes] | None = None) -> Path:
        """Write the seeds ``indices`` (and all, none or some negatives) as a new seed set."""
        return SeedSet.concat_to(path, [(self, list(indices), negatives)], metadata=metadata, extra_files=extra_files)

    @staticmethod
    def concat_to(path: str | os.PathLike, parts: Sequence[tuple["SeedSet", Sequence[int], bool | Sequence[int]]],
                  *, metadata: Mapping[str, Any] | None = None,
                  extra_files: Mapping[str, bytes] | None = None) -> Path:
        """Write seeds and negatives picked from several seed sets (same P and object_fraction) as one.

        Args:
            path: output folder.
            parts: ``(seed_set, seed_indices, negatives)``; ``negatives`` is
                True (all), False (none) or indices.
            metadata: header fields overriding those of the first part.
            extra_files: see :func:`write_seedset`.
        """
        if not parts:
            raise ValueError("concat_to needs at least one part")
        first = parts[0][0]
        for s, _, _ in parts:
            if s.patch_size != first.patch_size or s.object_fraction != first.object_fraction:
                raise ValueError(f"cannot concatenate seed sets with P/object_fraction "
                                 f"{s.patch_size}/{s.object_fraction} and {first.patch_size}/{first.object_fraction}")
        cols: dict[str, list[Any]] = {k: [] for k in ("patches", "backgrounds", "boxes", "centres", "crops")}
        contributing = [(s, list(idx)) for s, idx, _ in parts if len(idx)]
        colours = [s.colour() for s, _ in contributing]
        rgb = None  # RGB patches travel along when every part that gives seeds has them
        if colours and all(c is not None for c in colours):
            rgb = tuple(np.concatenate([c[k][idx] for (_, idx), c in zip(contributing, colours)]) for k in (0, 1))
        records, frames, bgs, nbs, negs, neg_recs = [], [], [], [], [], []
        for s, idx, neg in parts:
            idx = list(idx)
            for k in cols:
                cols[k].append(getattr(s, k)[idx])
            records += [s.records[i] for i in idx]
            frames += [s.frame_path(i) for i in idx]
            bgs += [s.background_frame_path(i) for i in idx]
            nbs += [s.neighbour_frame_path(i) for i in idx]
            nidx = list(range(len(s.negatives))) if neg is True else ([] if neg is False else list(neg))
            negs.append(s.negatives[nidx])
            neg_recs += [s.negative_records[i] for i in nidx]
        meta = {k: v for k, v in first.metadata.items() if k not in ("format", "version", "n_seeds", "n_negatives")}
        meta.update(metadata or {})
        p = first.patch_size
        cat = {k: np.concatenate(v) if v else np.zeros((0,)) for k, v in cols.items()}
        return write_seedset(path, patches=cat["patches"].reshape(-1, p, p), backgrounds=cat["backgrounds"].reshape(-1, p, p),
                             boxes=cat["boxes"], centres=cat["centres"], crops=cat["crops"], records=records,
                             frames=frames, background_frames=bgs,
                             negatives=np.concatenate(negs).reshape(-1, p, p) if negs else (),
                             negative_records=neg_recs, metadata=meta, extra_files=extra_files,
                             patches_rgb=None if rgb is None else rgb[0], backgrounds_rgb=None if rgb is None else rgb[1],
                             neighbour_frames=nbs if any(x is not None for x in nbs) else None)

    def __repr__(self) -> str:
        return (f"SeedSet({str(self.path)!r}, n={len(self)}, negatives={len(self.negatives)}, "
                f"patch_size={self.patch_size}, object_fraction={self.object_fraction})")
