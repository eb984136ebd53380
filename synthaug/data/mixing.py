"""Real items beside synthetic ones: a user's dataset in the synthetic items' format, and the mixing counts.

:class:`~synthaug.data.synthetic.SyntheticObjectDataset` with ``real=`` holds ``len(real)`` real items first
(indices ``0 .. len(real) - 1``) and ``round(synthetic_per_real · len(real))`` synthetic ones after them, so a
shuffling sampler mixes them at that ratio (:func:`mixed_counts`). A real item comes out in the synthetic
items' format whatever the user's dataset returns (:class:`RealItems`): uint8 or float arrays, (H, W),
(H, W, C) or (C, H, W) (:func:`to_float_image`), an int label or a target dict.

The layout stays inside the dataset (not a wrapper around a synthetic-only one) because a synthetic item is
seeded by its index in the mixed dataset and ``transforms`` by the same index for real and synthetic items
alike: a wrapper would shift every synthetic item's draws (other bytes for the same seed).

Example:
    >>> import torch
    >>> real = RealItems([(torch.zeros(1, 8, 8), 1)], mode="patch", channels=1, patch_size=8, label=1, theta_size=3)
    >>> image, target = real[0]
    >>> tuple(image.shape), target["labels"].item(), target["synthetic"].item(), target["seed_index"].item()
    ((1, 8, 8), 1, False, -1)
    >>> mixed_counts([0] * 4, 2.5, None)
    (4, 10)
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import torch
from torchvision import tv_tensors

__all__ = ["RealItems", "mixed_counts", "to_float_image"]


def to_float_image(img: Any, channels: int, where: str) -> torch.Tensor:
    """(H, W) or (H, W, C) array / (C, H, W) tensor -> (C, H, W) float32 in [0, 1]."""
    if isinstance(img, (str, os.PathLike)):
        from PIL import Image

        try:
            img = np.asarray(Image.open(img))
        except Exception as e:
            raise ValueError(f"{where}: cannot read image {img}: {e}") from None
    if isinstance(img, torch.Tensor):
        t = img.detach().cpu()
        if t.ndim == 3 and t.shape[0] in (1, 3):
            chw = t
        elif t.ndim == 2:
            chw = t[None]
        else:
            raise ValueError(f"{where}: expected (H, W) or (C, H, W) tensor, got shape {tuple(t.shape)}")
    else:
        a = np.asarray(img)
        if a.ndim == 2:
            chw = torch.from_numpy(np.ascontiguousarray(a))[None]
        elif a.ndim == 3 and a.shape[2] in (1, 3, 4):
            chw = torch.from_numpy(np.ascontiguousarray(a[..., :3])).permute(2, 0, 1)
        else:
            raise ValueError(f"{where}: expected an (H, W) or (H, W, C) image, got shape {a.shape}")
    if chw.dtype == torch.uint8:
        chw = chw.float() / 255.0
    elif chw.is_floating_point():
        chw = chw.float()
        if chw.numel() and (not torch.isfinite(chw).all() or chw.min() < -1e-3 or chw.max() > 1 + 1e-3):
            raise ValueError(f"{where}: float images must be finite and in [0, 1]")
    else:
        raise ValueError(f"{where}: unsupported dtype {chw.dtype} (use uint8 or float in [0, 1])")
    if chw.shape[0] == channels:
        return chw.contiguous()
    if channels == 1 and chw.shape[0] == 3:  # ITU-R BT.601 luma, as OpenCV's RGB2GRAY
        w = torch.tensor([0.299, 0.587, 0.114])[:, None, None]
        return (chw * w).sum(0, keepdim=True)
    if channels == 3 and chw.shape[0] == 1:
        return chw.expand(3, -1, -1).contiguous()
    raise ValueError(f"{where}: cannot convert {chw.shape[0]} channels to {channels}")


def mixed_counts(real: Any, synthetic_per_real: float, length: int | None) -> tuple[int, int]:
    """``(n_real, n_synthetic)``: ``len(real)`` and ``round(synthetic_per_real · len(real))`` with ``real``,
    else ``(0, length)``."""
    if real is not None:
        if synthetic_per_real < 0 or not math.isfinite(synthetic_per_real):
            raise ValueError(f"synthetic_per_real must be finite and >= 0, got {synthetic_per_real}")
        n_real = len(real)
        return n_real, int(round(synthetic_per_real * n_real))
    if length is None or length < 0:
        raise ValueError(f"length must be given (>= 0) when real is None, got {length}")
    return 0, int(length)


@dataclass(frozen=True)
class RealItems:
    """A user's map-style dataset of ``(image, label_or_target)`` with items in the synthetic items' format.

    Patch mode: image (C, P, P) float32 in [0, 1], target ``labels`` int64 () (the given label, or ``label``
    when the target is a dict without one). Frame mode: ``tv_tensors.Image`` and a target with ``boxes``
    (``tv_tensors.BoundingBoxes`` XYXY) and ``labels`` (N,). Both: ``synthetic`` False, ``seed_index`` -1 and a
    NaN ``theta`` of ``theta_size`` (unless the target has them), so that mixed batches collate.

    Args:
        real: the user's dataset (``len`` and ``[i]``).
        mode: ``"patch"`` or ``"frame"``; channels: 1 or 3; patch_size: the patches' side (patch mode);
        label: the object's class id; theta_size: length of the synthetic items' ``theta``.
    """

    real: Any
    mode: Literal["patch", "frame"]
    channels: int
    patch_size: int
    label: int
    theta_size: int

    def __len__(self) -> int:
        return len(self.real)


    def __getitem__(self, i: int) -> tuple[torch.Tensor, dict[str, Any]]:
        """Item ``i`` of the user's dataset in the synthetic items' format (image dtype, shape, target keys)."""
        item = self.real[i]
        if not isinstance(item, (tuple, list)) or len(item) != 2:
            raise ValueError(f"real dataset items must be (image, target) pairs; item {i} is {type(item).__name__}")
        image, target = item
        where = f"real[{i}]"
        img = to_float_image(image, self.channels, where)
        h, w = img.shape[-2:]
        if isinstance(target, Mapping):
            t = dict(target)
        else:
            t = {"labels": target}
        if self.mode == "patch":
            if (h, w) != (self.patch_size, self.patch_size):
                raise ValueError(f"{where}: image is {h}x{w} but patch_size is {self.patch_size} (real and synthetic "
                                 f"patches must have one size to be batched together)")
            label = torch.as_tensor(t.get("labels", self.label))
            if label.numel() != 1:
                raise ValueError(f"{where}: a patch's label must be one class id, got shape {tuple(label.shape)}")
            t["labels"] = label.reshape(()).to(torch.int64)
        else:
            if "boxes" not in t:
                raise ValueError(f"{where}: frame mode needs a target dict with 'boxes' (N, 4) XYXY pixels")
            boxes = torch.as_tensor(t["boxes"], dtype=torch.float32).reshape(-1, 4)
            t["boxes"] = tv_tensors.BoundingBoxes(boxes, format="XYXY", canvas_size=(h, w))
            labels = t.get("labels")
            t["labels"] = (torch.full((len(boxes),), self.label, dtype=torch.int64) if labels is None
                           else torch.as_tensor(labels, dtype=torch.int64).reshape(-1))
            if len(t["labels"]) != len(boxes):
                raise ValueError(f"{where}: {len(boxes)} boxes but {len(t['labels'])} labels")
            img = tv_tensors.Image(img)
        t.setdefault("synthetic", torch.tensor(False))
        t.setdefault("seed_index", torch.tensor(-1, dtype=torch.int64))
        t.setdefault("theta", torch.full((self.theta_size,), float("nan")))
        return img, t
