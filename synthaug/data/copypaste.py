"""Copy-paste positives: the real seed objects cut out and pasted on other backgrounds (a user's baseline).

What a practitioner would try before rendering anything (Dwibedi et al., *Cut,
Paste and Learn*, ICCV 2017; Ghiasi et al., *Simple Copy-Paste*, CVPR 2021):
each real seed object is cut out of its patch with its **fitted silhouette**
(the mesh's coverage at the seed's fitted pose, translation and scale from a
``synthaug fit`` file, dilated by ``dilate`` px so that the real object's own
outline is inside, edges feathered by a Gaussian of σ ``feather``) and pasted
on the background of *another* seed, with a random scale (log-uniform in
``scale``), horizontal flip, brightness factor (``brightness``, on the
object) and Gaussian blur (σ uniform in ``blur``, on the object and its matte
together, as a defocused object). The background keeps its own pixels.

Every draw comes from one ``torch.Generator`` seeded with ``seed``; item ``k``
uses seed ``k mod N``'s object (cycling, as the synthetic positives do).

Example:
    >>> import numpy as np
    >>> patches = np.full((2, 16, 16), 200, np.uint8); patches[:, 6:10, 6:10] = 40
    >>> masks = np.zeros((2, 16, 16), np.float32); masks[:, 6:10, 6:10] = 1
    >>> out = paste_objects(patches, np.full((2, 16, 16), 200, np.uint8), masks, 4, seed=0, blur=(0.0, 0.0))
    >>> tuple(out.shape), bool(out.min() < 0.3), bool(out.max() <= 1.0)
    ((4, 1, 16, 16), True, True)
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F
from torch import Tensor


def fitted_silhouettes(seedset: Any, fit_file: str | Path, mesh: Any = None, *, cache: Any = None) -> np.ndarray:
    """Each seed's object coverage (N, P, P) in [0, 1] at its fitted pose, translation and scale.

    Raises:
        ValueError: the fit does not hold one row per seed of ``seedset``.
    """
    from synthaug.data.fitted import fitted_layers

    *_, cov, _ = fitted_layers(fit_file, len(seedset), int(np.asarray(seedset.patches).shape[-1]), mesh=mesh,
                               cache=cache, default_scale=float(seedset.object_fraction))
    return cov[:, 0].numpy()


def paste_objects(patches: np.ndarray, backgrounds: np.ndarray, masks: np.ndarray, count: int, *, seed: int,
                  scale: tuple[float, float] = (0.8, 1.25), brightness: tuple[float, float] = (0.8, 1.2),
                  blur: tuple[float, float] = (0.0, 1.0), flip: float = 0.5, dilate: int = 1,
                  feather: float = 0.7) -> Tensor:
    """``count`` patches: object ``k mod N`` (``patches`` × ``masks``) pasted on another seed's background.

    Args:
        patches, backgrounds: (N, P, P) uint8 real seed patches and their backgrounds.
        masks: (N, P, P) object silhouettes in [0, 1] (e.g. :func:`fitted_silhouettes`).
        count: patches made.
        seed: seeds every draw.
        scale: log-uniform range of the object's scale about the patch centre.
        brightness: uniform range of the factor on the object's pixels.
        blur: uniform range of the Gaussian σ (px) on the pasted object and its matte.
        flip: probability of a horizontal flip.
        dilate: px the silhouette is grown by (the fit is approximate) before feathering.
        feather: σ (px) of the matte's soft edge (0: hard).

    Returns:
        (count, 1, P, P) float in [0, 1].
    """
    import kornia

    patches = np.asarray(patches)
    backgrounds = np.asarray(backgrounds)
    masks = np.asarray(masks, np.float32)
    if patches.ndim != 3 or backgrounds.shape != patches.shape or masks.shape != patches.shape:
        raise ValueError(f"patches, backgrounds and masks must share one (N, P, P) shape, got {patches.shape}, "
                         f"{backgrounds.shape}, {masks.shape}")
    if count < 0:
        raise ValueError(f"count must be >= 0, got {count}")
    for name, (lo, hi), floor in (("scale", scale, 1e-6), ("brightness", brightness, 0.0), ("blur", blur, 0.0)):
        if not floor <= lo <= hi:
            raise ValueError(f"{name} must be a range ({floor} <=) low <= high, got {(lo, hi)}")
    if not 0.0 <= flip <= 1.0:
        raise ValueError(f"flip must be a probability, got {flip}")
    n, p = patches.shape[0], patches.shape[-1]
    if count == 0 or n == 0:
        return torch.zeros(count, 1, p, p)
    g = torch.Generator().manual_seed(int(seed))
    obj = torch.from_numpy(patches.astype(np.float32) / 255.0)[:, None]
    bgs = torch.from_numpy(backgrounds.astype(np.float32) / 255.0)[:, None]
    matte = (torch.from_numpy(masks)[:, None] > 0.5).float()
    if dilate > 0:
        matte = F.max_pool2d(matte, 2 * dilate + 1, stride=1, padding=dilate)
    if feather > 0:
        k = 2 * math.ceil(3 * feather) + 1
        matte = kornia.filters.gaussian_blur2d(matte, (k, k), (feather, feather), border_type="constant")
    src = torch.arange(count) % n
    other = torch.randint(0, max(n - 1, 1), (count,), generator=g)
    dst = torch.where(other >= src, other + 1, other) if n > 1 else src  # another seed's background
    lo, hi = math.log(scale[0]), math.log(scale[1])
    s = torch.exp(lo + (hi - lo) * torch.rand(count, generator=g))
    mirror = torch.rand(count, generator=g) < flip
    bright = brightness[0] + (brightness[1] - brightness[0]) * torch.rand(count, generator=g)
    sigma = blur[0] + (blur[1] - blur[0]) * torch.rand(count, generator=g)
    # scale about the centre (and mirror): the output samples the source at x / s
    theta = torch.zeros(count, 2, 3)
    theta[:, 0, 0] = torch.where(mirror, -1.0, 1.0) / s
    theta[:, 1, 1] = 1.0 / s
    grid = F.affine_grid(theta, [count, 1, p, p], align_corners=False)
    layers = torch.cat([obj[src] * matte[src], matte[src]], 1)  # premultiplied colour and matte
    layers = F.grid_sample(layers, grid, mode="bilinear", padding_mode="zeros", align_corners=False)
    blurred = sigma > 0.05
    if bool(blurred.any()):
        out = layers.clone()
        for i in torch.nonzero(blurred).flatten().tolist():  # per-item σ: kornia takes one kernel size per call
            sg = float(sigma[i])
            k = 2 * math.ceil(3 * sg) + 1
            out[i:i + 1] = kornia.filters.gaussian_blur2d(layers[i:i + 1], (k, k), (sg, sg), border_type="constant")
        layers = out
    premul, alpha = layers[:, :1], layers[:, 1:].clamp(0.0, 1.0)
    return (premul * bright[:, None, None, None] + bgs[dst] * (1.0 - alpha)).clamp(0.0, 1.0)


def copy_paste_positives(seedset: Any, fit_file: str | Path, count: int, *, seed: int = 0, mesh: Any = None,
                         **kwargs: Any) -> Tensor:
    """``count`` copy-paste patches of a seed set: :func:`paste_objects` with :func:`fitted_silhouettes`."""
    masks = fitted_silhouettes(seedset, fit_file, mesh)
    return paste_objects(np.asarray(seedset.patches), np.asarray(seedset.backgrounds), masks, count, seed=seed, **kwargs)
