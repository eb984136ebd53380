"""Pure, batched capture-effect functions (kornia's functional layer).

Every function takes ``(B, C, H, W)`` tensors and per-sample parameters of
shape ``(B,)`` or ``(B, C)`` (per channel), never draws random numbers and
never modifies its inputs. All are differentiable in their continuous
parameters: the Gaussian blurs are applied in the Fourier domain with the
*analytic* transfer function of an anisotropic Gaussian,
``Ĝ(f) = exp(-2π² fᵀ Σ f)``, which is smooth in (σ_u, σ_v, α_m), exactly the
identity at σ = 0, and costs the same for every σ (the project brief measured a
15×15 per-sample kernel by grouped convolution at ~500 patches/s against
~3,200 by FFT, 64×64, one thread).

Example:
    >>> import torch
    >>> x = torch.zeros(1, 1, 32, 32); x[..., 16, 16] = 1.0
    >>> y = gaussian_blur_fft(x, torch.tensor([2.0]), pad=8)
    >>> round(float(y.sum()), 4)
    1.0
"""

from __future__ import annotations

import math
from functools import lru_cache

import torch
import torch.nn.functional as F

__all__ = [
    "next_fast_len",
    "gaussian_transfer",
    "gaussian_blur_fft",
    "diffuse_material",
    "motion_blur",
    "composite",
    "boundary_blur",
    "object_noise",
]


def next_fast_len(n: int) -> int:
    """Smallest m >= n whose only prime factors are 2, 3 and 5 (fast FFT size)."""
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n}")
    m = n
    while True:
        k = m
        for p in (2, 3, 5):
            while k % p == 0:
                k //= p
        if k == 1:
            return m
        m += 1


def _per_channel(p: torch.Tensor | float, batch: int, channels: int, ref: torch.Tensor, name: str) -> torch.Tensor:
    p = torch.as_tensor(p, dtype=ref.dtype, device=ref.device)
    if p.ndim == 0:
        p = p.expand(batch)
    if p.ndim == 1:
        if p.shape[0] != batch:
            raise ValueError(f"{name}: expected shape ({batch},) or ({batch}, {channels}), got {tuple(p.shape)}")
        p = p[:, None]
    if p.ndim != 2 or p.shape[0] != batch or p.shape[1] not in (1, channels):
        raise ValueError(f"{name}: expected shape ({batch},) or ({batch}, {channels}), got {tuple(p.shape)}")
    return p.expand(batch, channels)


@lru_cache(maxsize=32)
def _freqs(h: int, w: int, dtype: torch.dtype, device: str) -> tuple[torch.Tensor, torch.Tensor]:
    fy = torch.fft.fftfreq(h, dtype=dtype, device=device)[:, None]
    fx = torch.fft.rfftfreq(w, dtype=dtype, device=device)[None, :]
    return fy, fx


def gaussian_transfer(
    h: int, w: int, sigma_u: torch.Tensor, sigma_v: torch.Tensor, angle: torch.Tensor
) -> torch.Tensor:
    """Transfer function of an anisotropic Gaussian on an ``h × w`` rfft2 grid.

    Args:
        h, w: spatial size of the (padded) signal.
        sigma_u: (B, C) standard deviation along the direction ``angle`` (px).
        sigma_v: (B, C) standard deviation across it (px).
        angle: (B, C) direction of u, radians from +x toward +y (image rows go down).

    Returns:
        (B, C, h, w // 2 + 1) real tensor.
    """
    fy, fx = _freqs(h, w, sigma_u.dtype, str(sigma_u.device))
    c = torch.cos(angle)[..., None, None]
    s = torch.sin(angle)[..., None, None]
    fu = fx * c + fy * s
    fv = -fx * s + fy * c
    su2 = (sigma_u * sigma_u)[..., None, None]
    sv2 = (sigma_v * sigma_v)[..., None, None]
    return torch.exp(-2.0 * math.pi ** 2 * (su2 * fu * fu + sv2 * fv * fv))


def gaussian_blur_fft(
    image: torch.Tensor,
    sigma_u: torch.Tensor | float,
    sigma_v: torch.Tensor | float | None = None,
    angle: torch.Tensor | float | None = None,
    *,
    pad: int,
    border: str = "constant",
) -> torch.Tensor:
    """Per-sample (anisotropic) Gaussian blur by FFT.

    Args:
        image: (B, C, H, W).
        sigma_u: (B,) or (B, C) σ along ``angle`` in pixels (isotropic if
            ``sigma_v`` is None).
        sigma_v: (B,) or (B, C) σ across ``angle``; defaults to ``sigma_u``.
        angle: (B,) or (B, C) radians; defaults to 0.
        pad: pixels of padding on each side before the circular convolution;
            choose about 3σ_max so no energy wraps around. A fixed flag, so the
            FFT size (and the floating-point result) does not depend on the batch.
        border: ``"constant"`` (zeros: object layers), ``"replicate"`` or
            ``"reflect"`` (images).

    Returns:
        (B, C, H, W) blurred image.

    Shape:
        image (B, C, H, W) -> (B, C, H, W)
    """
    if image.ndim != 4:
        raise ValueError(f"image must be (B, C, H, W), got shape {tuple(image.shape)}")
    if pad < 0:
        raise ValueError(f"pad must be >= 0, got {pad}")
    b, c, h, w = image.shape
    su = _per_channel(sigma_u, b, c, image, "sigma_u")
    sv = su if sigma_v is None else _per_channel(sigma_v, b, c, image, "sigma_v")
    ang = torch.zeros_like(su) if angle is None else _per_channel(angle, b, c, image, "angle")
    if b == 0:
        return image.clone()
    hp, wp = next_fast_len(h + 2 * pad), next_fast_len(w + 2 * pad)
    pads = (pad, wp - w - pad, pad, hp - h - pad)
    if border == "constant":
        x = F.pad(image, pads)
    elif border in ("replicate", "reflect"):
        x = F.pad(image, pads, mode=border) if (pad > 0 or hp > h or wp > w) else image
    else:
        raise ValueError(f"border must be 'constant', 'replicate' or 'reflect', got {border!r}")
    spec = torch.fft.rfft2(x)
    spec = spec * gaussian_transfer(hp, wp, su, sv, ang)
    out = torch.fft.irfft2(spec, s=(hp, wp))
    return out[..., pad:pad + h, pad:pad + w]


def _blur_groups(stack: torch.Tensor, groups: int, sigma_u: torch.Tensor, sigma_v: torch.Tensor | None,
                 angle: torch.Tensor | None, *, pad: int, border: str) -> torch.Tensor:
    """Blur ``groups`` stacked (B, C, H, W) blocks of ``stack`` with the same per-(B, C) kernels.

    Same result as :func:`gaussian_blur_fft` on the σ's repeated ``groups`` times,
    but the transfer function (the costly ``exp``) is computed once.
    """
    b, gc, h, w = stack.shape
    c = gc // groups
    hp, wp = next_fast_len(h + 2 * pad), next_fast_len(w + 2 * pad)
    pads = (pad, wp - w - pad, pad, hp - h - pad)
    x = F.pad(stack, pads) if border == "constant" else F.pad(stack, pads, mode=border)
    spec = torch.fft.rfft2(x).view(b, groups, c, hp, wp // 2 + 1)
    sv = sigma_u if sigma_v is None else sigma_v
    ang = torch.zeros_like(sigma_u) if angle is None else angle
    spec = spec * gaussian_transfer(hp, wp, sigma_u, sv, ang)[:, None]
    out = torch.fft.irfft2(spec.view(b, gc, hp, wp // 2 + 1), s=(hp, wp))
    return out[..., pad:pad + h, pad:pad + w]


def diffuse_material(
    normals: torch.Tensor,
    coverage: torch.Tensor,
    w_d: torch.Tensor,
    *,
    light_dir: torch.Tensor | tuple[float, float, float] = (0.0, 0.5, 0.8660254),
    ambient: float = 0.4,
) -> torch.Tensor:
    """MP — object radiance from the diffuse reflection weight w_d (Lambert).

    ``object = w_d · (ambient + (1 - ambient) · max(0, n·l))`` on covered pixels,
    0 elsewhere: w_d sets the object's intensity (its colour, per channel) and
    the Lambert term adds diffuse shading.

    Args:
        normals: (B, 3, H, W) camera-frame unit normals (x right, y up, z to camera).
        coverage: (B, 1, H, W) object coverage in [0, 1].
        w_d: (B,) or (B, C) diffuse weight; C of the output follows w_d.
        light_dir: (3,) or (B, 3) direction *toward* the light, camera frame.
        ambient: fraction of light that is direction-independent (flag).

    Returns:
        (B, C, H, W) object colour (straight, not premultiplied).
    """
    if normals.ndim != 4 or normals.shape[1] != 3:
        raise ValueError(f"normals must be (B, 3, H, W), got {tuple(normals.shape)}")
    b = normals.shape[0]
    w = torch.as_tensor(w_d, dtype=normals.dtype, device=normals.device)
    if w.ndim == 1:
        w = w[:, None]
    if w.ndim != 2 or w.shape[0] != b:
        raise ValueError(f"w_d: expected shape ({b},) or ({b}, C), got {tuple(w.shape)}")
    l = torch.as_tensor(light_dir, dtype=normals.dtype, device=normals.device)
    if l.ndim == 1:
        l = l[None].expand(b, 3)
    l = l / l.norm(dim=1, keepdim=True).clamp_min(1e-12)
    lambert = (normals * l[:, :, None, None]).sum(1, keepdim=True).clamp_min(0.0)
    shade = (ambient + (1.0 - ambient) * lambert) * (coverage > 0).to(normals.dtype)
    return shade * w[:, :, None, None]


def motion_blur(
    object_color: torch.Tensor,
    coverage: torch.Tensor,
    sigma_u: torch.Tensor,
    sigma_v: torch.Tensor,
    angle: torch.Tensor,
    *,
    pad: int,
) -> tuple[torch.Tensor, torch.Tensor]:
    """MB — anisotropic Gaussian (σ_u, σ_v, α_m) on the object layer.

    The premultiplied colour and the coverage are blurred together, so after
    compositing the object smears over the background (its alpha spreads).
    With per-channel σ the coverage of channel c is blurred with channel c's σ.

    Returns:
        (object_color, coverage): straight colour (B, C, H, W) and coverage
        (B, C, H, W) or (B, 1, H, W) when C == 1.
    """
    b, c = object_color.shape[:2]
    premul = object_color * coverage
    stack = torch.cat([premul, coverage.expand(b, c, *coverage.shape[2:])], dim=1)
    su = _per_channel(sigma_u, b, c, object_color, "sigma_u")
    sv = _per_channel(sigma_v, b, c, object_color, "sigma_v")
    an = _per_channel(angle, b, c, object_color, "angle")
    if b == 0:
        return object_color.clone(), coverage.expand(b, c, *coverage.shape[2:]).clone()
    out = _blur_groups(stack, 2, su, sv, an, pad=pad, border="constant")
    premul_b, cov_b = out[:, :c], out[:, c:].clamp(0.0, 1.0)
    color = premul_b / cov_b.clamp_min(1e-6)
    color = torch.where(cov_b > 1e-6, color, torch.zeros_like(color))
    return color, cov_b


def composite(object_color: torch.Tensor, coverage: torch.Tensor, background: torch.Tensor) -> torch.Tensor:
    """Overlay the object on the background: ``c·α + B·(1 - α)``."""
    return object_color * coverage + background * (1.0 - coverage)


def boundary_blur(image: torch.Tensor, coverage: torch.Tensor, sigma_s: torch.Tensor, *, pad: int) -> torch.Tensor:
    """BB — Gaussian σ_s along the object boundary of the composite.

    ``out = I + w · (G_σs * I - I)`` with the band weight
    ``w = 4 · m (1 - m)``, ``m = G_σs * coverage``: 1 on the boundary, falling
    to 0 inside and outside the object within about 2σ_s, so only the
    object/background transition is mixed. σ_s = 0 is the identity.

    Args:
        image: (B, C, H, W) composite.
        coverage: (B, 1 or C, H, W) object coverage.
        sigma_s: (B,) or (B, C) px.
    """
    b, c = image.shape[:2]
    s = _per_channel(sigma_s, b, c, image, "sigma_s")
    cov = coverage.expand(b, c, *coverage.shape[2:])
    if b == 0:
        return image.clone()
    out = _blur_groups(torch.cat([image, cov], 1), 2, s, None, None, pad=pad, border="replicate")
    blurred, m = out[:, :c], out[:, c:].clamp(0.0, 1.0)
    band = (4.0 * m * (1.0 - m)).clamp(0.0, 1.0)
    return image + band * (blurred - image)


def object_noise(image: torch.Tensor, coverage: torch.Tensor, sigma_n: torch.Tensor, noise: torch.Tensor) -> torch.Tensor:
    """RN — Gaussian noise of std σ_n on the object's pixels only.

    ``out = I + σ_n · ε · α`` where ε is a standard-normal field drawn
    beforehand (so the function is deterministic) and α the coverage: the
    background is real and already carries the camera's noise.
    """
    b, c = image.shape[:2]
    if noise.shape != image.shape:
        raise ValueError(f"noise must have the image's shape {tuple(image.shape)}, got {tuple(noise.shape)}")
    s = _per_channel(sigma_n, b, c, image, "sigma_n")[..., None, None]
    return image + s * noise * coverage
