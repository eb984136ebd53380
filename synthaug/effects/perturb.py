"""The classic augmentation baseline of the paper's Table 1: patches perturbed by rotation, shift, mirror, blur, noise.

Example:
    >>> import torch
    >>> x = torch.rand(4, 1, 40, 40, generator=torch.Generator().manual_seed(0))
    >>> y = perturb_patches(x, 3, generator=torch.Generator().manual_seed(1))
    >>> tuple(y.shape), bool(((y >= 0) & (y <= 1)).all())
    ((12, 1, 40, 40), True)

The blur is a sampled, truncated (radius ⌈3σ_max⌉) and normalised spatial
Gaussian, not :func:`synthaug.effects.functional.gaussian_blur_fft`: that one
applies the *analytic* transfer function, which differs from the sampled kernel
by up to ~0.2 (pixel values in [0, 1]) at σ ≈ 0.3 px, so using it would change
every perturbed training set and the cached Table 1 cells.
"""

from __future__ import annotations

import math

import torch
import torch.nn.functional as F
from torch import Tensor

__all__ = ["perturb_patches", "with_perturbed_copies"]


def perturb_patches(
    patches: Tensor,
    copies: int,
    *,
    generator: torch.Generator,
    max_rotation_deg: float = 15.0,
    max_translation: float = 0.08,
    mirror: bool = True,
    max_blur_sigma: float = 1.5,
    max_noise_sigma: float = 0.03,
) -> Tensor:
    """The classic augmentation baseline: random rotation, translation, mirroring, blur and noise.

    Every output is one input patch warped by a random rotation (uniform in
    ±``max_rotation_deg``) and translation (uniform in ±``max_translation`` of
    the side, border pixels replicated), mirrored with probability 1/2,
    blurred by a Gaussian of σ uniform in [0, ``max_blur_sigma``] px and given
    Gaussian noise of σ uniform in [0, ``max_noise_sigma``], then clipped to [0, 1].
    The input is not modified.

    Args:
        patches: float patches in [0, 1].
        copies: perturbed copies per patch (>= 0).
        generator: the only source of randomness.
        max_rotation_deg, max_translation, mirror, max_blur_sigma, max_noise_sigma: ranges.

    Returns:
        ``copies * N`` perturbed patches; copy ``c`` of patch ``i`` is row ``c * N + i``.

    Shape:
        - patches: (N, 1, P, P)
        - output: (copies * N, 1, P, P)
    """
    if not isinstance(patches, Tensor) or patches.dim() != 4 or not patches.dtype.is_floating_point:
        raise ValueError(f"patches must be a float (N, C, P, P) tensor, got {getattr(patches, 'shape', patches)}")
    if copies < 0:
        raise ValueError(f"copies must be >= 0, got {copies}")
    n, c, h, w = patches.shape
    m = n * copies
    if m == 0:
        return patches.new_zeros(0, c, h, w)
    x = patches.repeat(copies, 1, 1, 1)
    angle = (torch.rand(m, generator=generator) * 2 - 1) * math.radians(max_rotation_deg)
    shift = (torch.rand(m, 2, generator=generator) * 2 - 1) * (2 * max_translation)  # normalised coords span 2
    flip = (torch.rand(m, generator=generator) < 0.5) if mirror else torch.zeros(m, dtype=torch.bool)
    sigma = torch.rand(m, generator=generator) * max_blur_sigma
    noise_sigma = torch.rand(m, generator=generator) * max_noise_sigma
    noise = torch.randn(m, c, h, w, generator=generator)
    cos, sin = torch.cos(angle), torch.sin(angle)
    sx = torch.where(flip, -1.0, 1.0)
    theta = torch.stack([torch.stack([cos * sx, -sin, shift[:, 0]], 1), torch.stack([sin * sx, cos, shift[:, 1]], 1)], 1)
    grid = F.affine_grid(theta.to(x.dtype), list(x.shape), align_corners=False)
    x = F.grid_sample(x, grid, mode="bilinear", padding_mode="border", align_corners=False)
    # per-sample separable Gaussian blur (σ = 0 -> identity kernel)
    radius = max(1, math.ceil(3 * max_blur_sigma))
    t = torch.arange(-radius, radius + 1, dtype=x.dtype)
    k = torch.exp(-0.5 * (t[None] / sigma.clamp_min(1e-3)[:, None].to(x.dtype)) ** 2)
    k = k / k.sum(1, keepdim=True)  # (m, 2r+1)
    xb = x.reshape(1, m * c, h, w)
    kc = k.repeat_interleave(c, 0)
    xb = F.conv2d(F.pad(xb, (radius, radius, 0, 0), mode="replicate"), kc[:, None, None, :], groups=m * c)
    xb = F.conv2d(F.pad(xb, (0, 0, radius, radius), mode="replicate"), kc[:, None, :, None], groups=m * c)
    x = xb.reshape(m, c, h, w) + noise * noise_sigma[:, None, None, None].to(x.dtype)
    return x.clamp(0.0, 1.0)


def with_perturbed_copies(patches: Tensor, copies: int, *, seed: int) -> Tensor:
    """``patches`` followed by ``copies`` perturbed versions of each (:func:`perturb_patches`, its
    generator seeded with ``seed``): the positives of the paper's perturbation baseline."""
    return torch.cat([patches, perturb_patches(patches, copies, generator=torch.Generator().manual_seed(seed))])
