"""The noise level of a real image: what the object noise σ_n of a fit should be, measured rather than fitted.

Fitted with a feature distance (d_HOG, d_CNN), σ_n buys gradient energy the
coarse render lacks: on the 100 real drone seeds the fits put σ_n at a median
0.072 (d_HOG; a quarter at the 0.1 bound) and 0.042 (d_CNN) — 10 to 18 grey
levels of speckle on the object — while the seed patches themselves carry a
noise level of about 0.0013 (this estimator; results/synthetic/drone_v1). So
``FitConfig(object_noise="measured")`` pins σ_n of each seed at its patch's
measured level.

The estimator is Immerkær's (*Fast noise variance estimation*, CVIU 1996): the
image convolved with the difference of two Laplacians

    N = [[1, -2, 1], [-2, 4, -2], [1, -2, 1]]

which cancels planes and slow ramps; on white noise of std σ the response has
std ``6σ`` (ΣN² = 36). Immerkær averages ``|I * N|``; here the median of
``|I * N|`` is used instead (``σ = 1.4826 · median|I * N| / 6``), so that the
few pixels on an object's edges do not count as noise.

Example:
    >>> g = torch.Generator().manual_seed(0)
    >>> ramp = torch.linspace(0.2, 0.8, 128).repeat(128, 1)
    >>> x = (ramp + 0.02 * torch.randn(128, 128, generator=g))[None, None]
    >>> round(float(noise_sigma(x)[0]), 3)
    0.02
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

_KERNEL = torch.tensor([[1.0, -2.0, 1.0], [-2.0, 4.0, -2.0], [1.0, -2.0, 1.0]])
_MAD_TO_STD = 1.482602218505602  # 1 / Φ⁻¹(3/4)


def noise_sigma(images: torch.Tensor) -> torch.Tensor:
    """Per-image noise standard deviation (robust Immerkær), in the images' units.

    Args:
        images: (B, C, H, W) float, H and W >= 3. Channels are pooled (one level per image).

    Returns:
        (B,) float64.

    Raises:
        ValueError: wrong shape or an image smaller than 3 × 3.
    """
    if not isinstance(images, torch.Tensor) or images.ndim != 4:
        raise ValueError(f"images must be a (B, C, H, W) tensor, got {getattr(images, 'shape', type(images))}")
    b, c, h, w = images.shape
    if h < 3 or w < 3:
        raise ValueError(f"images must be at least 3 x 3 pixels, got {h} x {w}")
    if b == 0:
        return torch.zeros(0, dtype=torch.float64)
    x = images.detach().to(torch.float64).reshape(b * c, 1, h, w)
    r = F.conv2d(x, _KERNEL.to(torch.float64)[None, None]).reshape(b, -1)
    return _MAD_TO_STD * r.abs().median(dim=1).values / 6.0
