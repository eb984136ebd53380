"""Pure, batched functions of the candidate camera effects (issue 6).

Same conventions as :mod:`synthaug.effects.functional`: ``(B, C, H, W)``
tensors, per-sample parameters of shape ``(B,)`` or ``(B, C)``, no random
draws (noise comes in as a field), no in-place change of inputs.

Most functions come in a *frame* form, the physics applied to a whole camera
frame (what :mod:`synthaug.diagnose.reference_camera` does), and the registered
effects in :mod:`synthaug.effects.camera` use them on the rendered *object*
only, because the real background B_i already went through the camera.

Position-aware functions (vignetting, chromatic aberration, lens distortion,
JPEG block grid) place a patch in its frame with:

- ``origin`` (B, 2): frame coordinates (x, y) of the patch's top-left pixel
  *edge* (for a seed: crop centre - side / 2),
- ``frame_size`` (B, 2): the frame's (W, H),
- ``frame_scale`` (B,): frame pixels per patch pixel (a seed: side / P).

Patch pixel (u, v) then sits at frame pixel ``origin + (u + 0.5) * scale - 0.5``
(the :func:`synthaug.data.seedset.crop_patch` convention). Without them the
patch is taken as the whole frame.

Example:
    >>> import torch
    >>> x = torch.full((1, 1, 5, 5), 0.5)
    >>> y = vignetting(x, torch.tensor([0.4]))
    >>> round(float(y[0, 0, 2, 2]), 4), round(float(y[0, 0, 0, 0]), 3)  # centre, corner
    (0.5, 0.372)
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
import torch
import torch.nn.functional as F

from synthaug.effects.functional import _per_channel, gaussian_blur_fft

__all__ = [
    "frame_coordinates",
    "vignetting",
    "exposure",
    "white_balance",
    "haze",
    "gamma_curve",
    "gamma_composite",
    "specular_highlight",
    "rotor_weight",
    "rotor_blur",
    "rolling_shutter",
    "defocus",
    "unsharp_mask",
    "chromatic_aberration",
    "lens_distortion",
    "shot_noise",
    "dct_matrix",
    "quantize_levels",
    "jpeg_table",
    "jpeg_difference_on_frame_grid",
    "jpeg_quantize",
    "LUMA_WEIGHTS",
]

# Rec. 601 luma: how the three colour planes of a lateral-CA fringe mix into gray.
LUMA_WEIGHTS = (0.299, 0.587, 0.114)

# JPEG (ITU T.81 Annex K) luminance quantisation table.
_JPEG_LUMA = np.array([
    [16, 11, 10, 16, 24, 40, 51, 61],
    [12, 12, 14, 19, 26, 58, 60, 55],
    [14, 13, 16, 24, 40, 57, 69, 56],
    [14, 17, 22, 29, 51, 87, 80, 62],
    [18, 22, 37, 56, 68, 109, 103, 77],
    [24, 35, 55, 64, 81, 104, 113, 92],
    [49, 64, 78, 87, 103, 121, 120, 101],
    [72, 92, 95, 98, 112, 100, 103, 99],
], dtype=np.float64)


def _pc(p: torch.Tensor | float, image: torch.Tensor, name: str) -> torch.Tensor:
    """Per-sample, per-channel parameter as (B, C, 1, 1)."""
    b, c = image.shape[:2]
    return _per_channel(p, b, c, image, name)[..., None, None]


def _check_image(image: torch.Tensor, name: str = "image") -> None:
    if image.ndim != 4:
        raise ValueError(f"{name} must be (B, C, H, W), got shape {tuple(image.shape)}")


# --------------------------------------------------------------- geometry
def frame_coordinates(
    batch: int,
    height: int,
    width: int,
    *,
    origin: torch.Tensor | None = None,
    frame_size: torch.Tensor | None = None,
    frame_scale: torch.Tensor | None = None,
    dtype: torch.dtype = torch.float32,
    device: torch.device | str | None = None,
) -> dict[str, torch.Tensor]:
    """Frame position of every patch pixel, relative to the frame centre.

    Args:
        batch, height, width: patch batch size and side.
        origin: (B, 2) patch top-left edge in frame pixels, or None (the patch is the frame).
        frame_size: (B, 2) frame (W, H); required with ``origin``.
        frame_scale: (B,) frame px per patch px (default 1).

    Returns:
        dict with ``x``, ``y`` (B, 1, H, W) frame pixel coordinates; ``dx``,
        ``dy`` the same relative to the frame centre divided by the half
        diagonal ``radius`` (so the corners have ``dx² + dy² = 1``);
        ``radius`` and ``scale`` (B, 1, 1, 1); ``centre`` and ``origin``
        (B, 2, 1, 1) frame pixels; ``patch_dx``, ``patch_dy`` (B, 1, 1, 1) the
        normalised position of the patch centre.
    """
    if (origin is None) != (frame_size is None):
        raise ValueError("give both origin and frame_size, or neither "
                         f"(got origin={'set' if origin is not None else None}, "
                         f"frame_size={'set' if frame_size is not None else None})")
    kw = {"dtype": dtype, "device": device}
    if origin is None:
        origin = torch.zeros(batch, 2, **kw)
        frame_size = torch.tensor([[float(width), float(height)]], **kw).expand(batch, 2)
    origin = torch.as_tensor(origin, **kw).reshape(-1, 2).expand(batch, 2)
    frame_size = torch.as_tensor(frame_size, **kw).reshape(-1, 2).expand(batch, 2)
    if (frame_size <= 0).any():
        raise ValueError(f"frame_size must be positive, got {frame_size.tolist()}")
    if frame_scale is None:
        scale = torch.ones(batch, **kw)
    else:
        scale = torch.as_tensor(frame_scale, **kw).reshape(-1).expand(batch)
        if (scale <= 0).any():
            raise ValueError(f"frame_scale must be > 0, got {scale.tolist()}")
    s = scale[:, None, None, None]
    u = torch.arange(width, **kw)[None, None, None, :]
    v = torch.arange(height, **kw)[None, None, :, None]
    x = origin[:, 0, None, None, None] + (u + 0.5) * s - 0.5
    y = origin[:, 1, None, None, None] + (v + 0.5) * s - 0.5
    x = x.expand(batch, 1, height, width)
    y = y.expand(batch, 1, height, width)
    cx = ((frame_size[:, 0] - 1) / 2)[:, None, None, None]
    cy = ((frame_size[:, 1] - 1) / 2)[:, None, None, None]
    radius = (0.5 * torch.sqrt(frame_size[:, 0] ** 2 + frame_size[:, 1] ** 2))[:, None, None, None]
    # the patch's centre (between pixels for even sides) in the same normalised frame
    x0 = origin[:, 0, None, None, None] + (width / 2.0) * s - 0.5
    y0 = origin[:, 1, None, None, None] + (height / 2.0) * s - 0.5
    return {"x": x, "y": y, "dx": (x - cx) / radius, "dy": (y - cy) / radius, "radius": radius, "scale": s,
            "centre": torch.cat([cx, cy], 1), "origin": origin[:, :, None, None],
            "patch_dx": (x0 - cx) / radius, "patch_dy": (y0 - cy) / radius}


def _sample(image: torch.Tensor, src_x: torch.Tensor, src_y: torch.Tensor, padding: str) -> torch.Tensor:
    """Bilinear ``image`` (B, C, H, W) at pixel coordinates (src_x, src_y), per channel.

    The coordinates broadcast to (B, C or 1, H', W'); the output is (B, C, H', W') (H', W' = H, W for a warp
    of the image onto itself).
    """
    b, c, h, w = image.shape
    ho, wo = torch.broadcast_shapes(src_x.shape, src_y.shape)[-2:]
    src_x = src_x.expand(b, c, ho, wo)
    src_y = src_y.expand(b, c, ho, wo)
    gx = (src_x + 0.5) * (2.0 / w) - 1.0
    gy = (src_y + 0.5) * (2.0 / h) - 1.0
    grid = torch.stack([gx, gy], -1).reshape(b * c, ho, wo, 2)
    out = F.grid_sample(image.reshape(b * c, 1, h, w), grid, mode="bilinear", padding_mode=padding,
                        align_corners=False)
    return out.reshape(b, c, ho, wo)


def _padding(border: str) -> str:
    if border not in ("zeros", "border"):
        raise ValueError(f"border must be 'zeros' or 'border', got {border!r}")
    return border


# -------------------------------------------------------------- pointwise
def vignetting(
    image: torch.Tensor,
    strength: torch.Tensor | float,
    *,
    origin: torch.Tensor | None = None,
    frame_size: torch.Tensor | None = None,
    frame_scale: torch.Tensor | None = None,
) -> torch.Tensor:
    """Radial light fall-off ``I · max(0, 1 - k r²)``, r = 1 at the frame corners.

    ``k`` (``vignette_k``) is the fraction of light lost at the corners (0.3 = 30 %).

    Shape:
        image (B, C, H, W), strength (B,) or (B, C) -> (B, C, H, W)
    """
    _check_image(image)
    k = _pc(strength, image, "vignette_k")
    b, _, h, w = image.shape
    g = frame_coordinates(b, h, w, origin=origin, frame_size=frame_size, frame_scale=frame_scale,
                          dtype=image.dtype, device=image.device)
    r2 = g["dx"] ** 2 + g["dy"] ** 2
    return image * (1.0 - k * r2).clamp_min(0.0)


def exposure(image: torch.Tensor, gain: torch.Tensor | float, offset: torch.Tensor | float) -> torch.Tensor:
    """Sensor gain and black-level offset: ``gain · I + offset``."""
    _check_image(image)
    return image * _pc(gain, image, "exposure_gain") + _pc(offset, image, "exposure_offset")


def white_balance(image: torch.Tensor, gain: torch.Tensor | float) -> torch.Tensor:
    """Per-channel white-balance gain ``g_c · I_c`` (in grayscale a plain gain)."""
    _check_image(image)
    return image * _pc(gain, image, "wb_gain")


def haze(image: torch.Tensor, amount: torch.Tensor | float, airlight: torch.Tensor | float) -> torch.Tensor:
    """Atmospheric scattering (Koschmieder): ``I · t + A · (1 - t)``, ``t = 1 - amount``.

    ``amount`` is 1 - transmission (0 = clear air), ``airlight`` A the horizon
    sky's intensity the contrast is lost toward.
    """
    _check_image(image)
    h = _pc(amount, image, "haze_amount")
    return image * (1.0 - h) + _pc(airlight, image, "haze_airlight") * h


_GAMMA_EPS = 1e-4


def gamma_curve(image: torch.Tensor, exponent: torch.Tensor | float) -> torch.Tensor:
    """Camera response ``max(I, ε)^g`` (g = 1: identity up to ε = 1e-4)."""
    _check_image(image)
    g = _pc(exponent, image, "gamma_g")
    return torch.where(image > _GAMMA_EPS, image, torch.full_like(image, _GAMMA_EPS)).pow(g)


def gamma_composite(image: torch.Tensor, coverage: torch.Tensor, background: torch.Tensor,
                    exponent: torch.Tensor | float) -> torch.Tensor:
    """A tone curve f(x) = x^g of the whole frame, seen through its real background.

    The camera records ``f(α·o + (1-α)·b)`` while the real background is
    ``B = f(b)``; so ``b = f⁻¹(B)`` and, for the current composite
    ``I = (object part) + (1-α)·B``,

        out = f(I + (1 - α) · (f⁻¹(B) - B)).

    Exact for the plain composite; wherever the object adds nothing (I = B)
    it returns B (up to the ε = 1e-4 floor of the curve), and g = 1 is the
    identity.

    Args:
        image: (B, C, H, W) composite. coverage: (B, 1 or C, H, W) α.
        background: (B, C, H, W) the real background B.
        exponent: (B,) or (B, C) ``gamma_g``.
    """
    _check_image(image)
    g = _pc(exponent, image, "gamma_g")
    b_lin = torch.where(background > _GAMMA_EPS, background, torch.full_like(background, _GAMMA_EPS)).pow(1.0 / g)
    x = image + (1.0 - coverage) * (b_lin - background)
    return torch.where(x > _GAMMA_EPS, x, torch.full_like(x, _GAMMA_EPS)).pow(g)


# ---------------------------------------------------------------- object layer
def specular_highlight(
    normals: torch.Tensor,
    coverage: torch.Tensor,
    ks: torch.Tensor | float,
    shininess: torch.Tensor | float,
    *,
    light_dir: torch.Tensor | tuple[float, float, float] = (0.0, 0.5, 0.8660254),
) -> torch.Tensor:
    """Blinn-Phong highlight ``k_s · max(0, n·h)^p`` on covered pixels.

    ``h`` is the half vector between the light and the view direction (0, 0, 1)
    (orthographic camera). Add it to the object's diffuse colour.

    Args:
        normals: (B, 3, H, W) camera-frame unit normals. coverage: (B, 1, H, W).
        ks: (B,) or (B, C) ``specular_ks``; C of the output follows ks.
        shininess: (B,) or (B, C) exponent p (``specular_shininess``).
        light_dir: (3,) or (B, 3) toward the light.

    Returns:
        (B, C, H, W) highlight radiance.
    """
    if normals.ndim != 4 or normals.shape[1] != 3:
        raise ValueError(f"normals must be (B, 3, H, W), got {tuple(normals.shape)}")
    b = normals.shape[0]
    k = torch.as_tensor(ks, dtype=normals.dtype, device=normals.device)
    k = k.expand(b) if k.ndim == 0 else k
    c = 1 if k.ndim == 1 else k.shape[1]
    ref = normals[:, :c]
    k = _pc(k, ref, "specular_ks")
    p = _pc(shininess, ref, "specular_shininess")
    l = torch.as_tensor(light_dir, dtype=normals.dtype, device=normals.device)
    if l.ndim == 1:
        l = l[None].expand(b, 3)
    l = l / l.norm(dim=1, keepdim=True).clamp_min(1e-12)
    view = torch.tensor([0.0, 0.0, 1.0], dtype=normals.dtype, device=normals.device)
    half = l + view
    half = half / half.norm(dim=1, keepdim=True).clamp_min(1e-12)
    nh = (normals * half[:, :, None, None]).sum(1, keepdim=True)
    pos = nh > 1e-6
    lobe = torch.where(pos, torch.exp(p * torch.log(torch.where(pos, nh, torch.ones_like(nh)))),
                       torch.zeros_like(nh + p))
    return k * lobe * (coverage > 0).to(normals.dtype)


def rotor_weight(coverage: torch.Tensor, *, inner: float = 0.55, width: float = 0.25) -> torch.Tensor:
    """Approximate rotor region when the renderer gives no ``part_rotor`` layer.

    A quadcopter's rotors are its extremities: the weight rises smoothly
    (smoothstep) from 0 at ``inner`` to 1 at ``inner + width`` of the object's
    radius, measured from the coverage centroid (radius = farthest pixel with
    coverage > 0.5). A geometric guess, not a part segmentation: it also
    catches arm tips and, on other shapes, any extremity. No gradient flows
    through it (geometry only).

    Shape:
        coverage (B, 1 or C, H, W) -> (B, 1, H, W) in [0, 1]
    """
    _check_image(coverage, "coverage")
    with torch.no_grad():
        cov = coverage[:, :1]
        b, _, h, w = cov.shape
        yy = torch.arange(h, dtype=cov.dtype, device=cov.device)[None, None, :, None]
        xx = torch.arange(w, dtype=cov.dtype, device=cov.device)[None, None, None, :]
        mass = cov.sum((2, 3), keepdim=True).clamp_min(1e-6)
        cx = (cov * xx).sum((2, 3), keepdim=True) / mass
        cy = (cov * yy).sum((2, 3), keepdim=True) / mass
        dist = torch.sqrt((xx - cx) ** 2 + (yy - cy) ** 2)
        solid = cov > 0.5
        rmax = torch.where(solid, dist, torch.zeros_like(dist)).amax((2, 3), keepdim=True).clamp_min(1e-6)
        t = ((dist / rmax - inner) / width).clamp(0.0, 1.0)
        return t * t * (3.0 - 2.0 * t)


def rotor_blur(coverage: torch.Tensor, opacity: torch.Tensor | float,
               part_rotor: torch.Tensor | None = None) -> torch.Tensor:
    """Spinning propellers: the rotor discs become semi-transparent.

    A blade spinning during the exposure covers each pixel of its disc only a
    fraction ``ρ`` (``rotor_opacity``) of the time, so the disc's coverage is
    scaled by ρ: ``α' = α - (1 - ρ) · α_rotor`` with ``α_rotor`` the
    rotor parts' coverage (``part_rotor``), or ``α · rotor_weight(α)`` when
    the renderer gives none. ρ = 1 is the identity (the coarse mesh's solid discs).

    Shape:
        coverage (B, 1 or C, H, W), opacity (B,) or (B, C) -> (B, C', H, W)
    """
    _check_image(coverage, "coverage")
    b = coverage.shape[0]
    rho = torch.as_tensor(opacity, dtype=coverage.dtype, device=coverage.device)
    c = 1 if rho.ndim <= 1 else rho.shape[1]
    rho = _per_channel(rho, b, c, coverage, "rotor_opacity")[..., None, None]
    rotor = coverage * rotor_weight(coverage) if part_rotor is None else torch.minimum(part_rotor, coverage)
    return (coverage - (1.0 - rho) * rotor).clamp(0.0, 1.0)


def rolling_shutter(object_color: torch.Tensor, coverage: torch.Tensor, skew: torch.Tensor | float,
                    stretch: torch.Tensor | float) -> tuple[torch.Tensor, torch.Tensor]:
    """Rolling-shutter distortion of a moving object: rows exposed at successive times.

    Row y is read at time ``τ·y``; an object moving at (v_x, v_y) px per unit
    time is displaced by ``v·τ·(y - y_c)``: a horizontal shear ``skew = v_x τ``
    (px per row) and a vertical stretch ``1 + stretch``, ``stretch = v_y τ``,
    about the patch's centre row (a global shift is the pose's t). Premultiplied
    colour and coverage are resampled (bilinear, zeros outside), like motion blur.

    Returns:
        (object_color, coverage), both (B, C, H, W).
    """
    _check_image(object_color, "object_color")
    b, c, h, w = object_color.shape
    sk = _pc(skew, object_color, "rs_skew")
    st = _pc(stretch, object_color, "rs_stretch")
    if ((1.0 + st) <= 0.05).any():
        raise ValueError(f"rs_stretch must be > -0.95, got {st.min().item()}")
    cov = coverage.expand(b, c, h, w)
    yy = torch.arange(h, dtype=object_color.dtype, device=object_color.device)[None, None, :, None]
    xx = torch.arange(w, dtype=object_color.dtype, device=object_color.device)[None, None, None, :]
    yc = (h - 1) / 2.0
    src_x = xx - sk * (yy - yc)
    src_y = yc + (yy - yc) / (1.0 + st)
    if b == 0:
        return object_color.clone(), cov.clone()
    stack = torch.cat([object_color * cov, cov], 1)
    out = _sample(stack, torch.cat([src_x.expand(b, c, h, w)] * 2, 1), torch.cat([src_y.expand(b, c, h, w)] * 2, 1),
                  "zeros")
    premul, cov_o = out[:, :c], out[:, c:].clamp(0.0, 1.0)
    color = torch.where(cov_o > 1e-6, premul / cov_o.clamp_min(1e-6), torch.zeros_like(premul))
    return color, cov_o


# ------------------------------------------------------------ linear spatial
def defocus(image: torch.Tensor, sigma: torch.Tensor | float, *, pad: int, border: str = "constant") -> torch.Tensor:
    """Defocus: an isotropic Gaussian PSF of std σ (``defocus_sigma``) on the whole image.

    A real defocus PSF is closer to a disc; a Gaussian of the same second moment
    (disc radius ≈ 2σ) is the usual smooth, differentiable stand-in.
    """
    _check_image(image)
    return gaussian_blur_fft(image, sigma, pad=pad, border=border)


def unsharp_mask(image: torch.Tensor, amount: torch.Tensor | float, sigma: torch.Tensor | float, *, pad: int,
                 border: str = "constant") -> torch.Tensor:
    """Camera sharpening (unsharp mask): ``I + a · (I - G_σ * I)``.

    Linear, so the halos it leaves around edges add up; ``a = 0`` is the identity.
    """
    _check_image(image)
    a = _pc(amount, image, "sharpen_amount")
    blurred = gaussian_blur_fft(image, sigma, pad=pad, border=border)
    return image + a * (image - blurred)


def chromatic_aberration(
    image: torch.Tensor,
    shift: torch.Tensor | float,
    *,
    origin: torch.Tensor | None = None,
    frame_size: torch.Tensor | None = None,
    frame_scale: torch.Tensor | None = None,
    border: str = "zeros",
) -> torch.Tensor:
    """Lateral chromatic aberration: red magnified, blue shrunk, about the frame centre.

    A colour plane's image point at normalised radius vector ``r`` moves by
    ``s · shift · r`` frame pixels (``shift`` = ``ca_shift``, the displacement
    at the corners; ``s`` = +1 red, 0 green, -1 blue). With C = 3 each channel
    is its plane (its own ``shift``); with C = 1 the gray image is the Rec. 601
    mix of the three displaced copies, i.e. a radial 3-tap blur growing toward
    the corners.

    Shape:
        image (B, C, H, W) with C in (1, 3) -> (B, C, H, W)
    """
    _check_image(image)
    b, c, h, w = image.shape
    if c not in (1, 3):
        raise ValueError(f"chromatic_aberration needs 1 or 3 channels, got {c}")
    sh = _pc(shift, image, "ca_shift")
    g = frame_coordinates(b, h, w, origin=origin, frame_size=frame_size, frame_scale=frame_scale,
                          dtype=image.dtype, device=image.device)
    xx = torch.arange(w, dtype=image.dtype, device=image.device)[None, None, None, :]
    yy = torch.arange(h, dtype=image.dtype, device=image.device)[None, None, :, None]
    # displacement in patch px per unit sign
    ux, uy = sh * g["dx"] / g["scale"], sh * g["dy"] / g["scale"]
    pad = _padding(border)
    signs = torch.tensor([1.0, 0.0, -1.0], dtype=image.dtype, device=image.device)[None, :, None, None]
    if c == 3:
        return _sample(image, xx - signs * ux, yy - signs * uy, pad)
    planes = _sample(image.expand(b, 3, h, w), xx - signs * ux, yy - signs * uy, pad)
    wts = torch.tensor(LUMA_WEIGHTS, dtype=image.dtype, device=image.device)[None, :, None, None]
    return (planes * wts).sum(1, keepdim=True)


def _undistort(qx: torch.Tensor, qy: torch.Tensor, k: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Division model: the scene (undistorted) position of image point q is ``q / (1 + k |q|²)``."""
    f = 1.0 / (1.0 + k * (qx * qx + qy * qy))
    return qx * f, qy * f


def lens_distortion(
    image: torch.Tensor,
    k1: torch.Tensor | float,
    *,
    origin: torch.Tensor | None = None,
    frame_size: torch.Tensor | None = None,
    frame_scale: torch.Tensor | None = None,
    recentre: bool = True,
    border: str = "zeros",
) -> torch.Tensor:
    """Radial lens distortion, one-parameter division model (Fitzgibbon 2001).

    The image point ``p_d`` (normalised by the half diagonal, so the corners
    are at radius 1) shows the scene point ``p_u = p_d / (1 + k₁ |p_d|²)``:
    k₁ < 0 is barrel (the border shows a wider field, straight lines bow
    outward), k₁ > 0 pincushion (``distortion_k1``). Each output pixel samples
    the input at its scene position (bilinear); no inverse is needed, and the
    map is defined everywhere for |k₁| < 1.

    With ``recentre`` (the object patch form) the distortion acts about the
    patch centre: the centre stays put and the local isotropic magnification
    (``det J`` of the map) is divided out, as the seed crop, centred on the box
    and scaled by its size, removes both; what is left is the object's
    anisotropic stretch (radial vs. tangential) and bending. ``recentre=False``
    distorts a whole frame (or a crop of one, at its place).

    Shape:
        image (B, C, H, W), k1 (B,) or (B, C) -> (B, C, H, W)
    """
    src_x, src_y = lens_distortion_source(image, k1, origin=origin, frame_size=frame_size,  # checks the image
                                          frame_scale=frame_scale, recentre=recentre)
    return _sample(image, src_x, src_y, _padding(border))


def lens_distortion_source(
    image: torch.Tensor,
    k1: torch.Tensor | float,
    *,
    origin: torch.Tensor | None = None,
    frame_size: torch.Tensor | None = None,
    frame_scale: torch.Tensor | None = None,
    recentre: bool = True,
) -> tuple[torch.Tensor, torch.Tensor]:
    """The pixel coordinates (src_x, src_y) each output pixel of :func:`lens_distortion` samples ``image`` at
    (the map alone, for a sampler of one's own: a whole frame's resampling with a higher-order kernel).

    Shape:
        image (B, C, H, W), k1 (B,) or (B, C) -> two (B, C, H, W)
    """
    _check_image(image)
    b, c, h, w = image.shape
    k = _pc(k1, image, "distortion_k1")
    if (k.abs() >= 1).any():
        raise ValueError(f"distortion_k1 must be in (-1, 1), got {k.flatten()[k.flatten().abs().argmax()].item()}")
    g = frame_coordinates(b, h, w, origin=origin, frame_size=frame_size, frame_scale=frame_scale,
                          dtype=image.dtype, device=image.device)
    radius, scale = g["radius"], g["scale"]
    qx, qy = g["dx"].expand(b, c, h, w), g["dy"].expand(b, c, h, w)
    if recentre:
        p0x, p0y = g["patch_dx"], g["patch_dy"]
        r0 = p0x * p0x + p0y * p0y
        det = (1.0 - k * r0) / (1.0 + k * r0) ** 3  # Jacobian determinant of the division map at p0
        f = det.clamp_min(1e-6).rsqrt()
        u0x, u0y = _undistort(p0x, p0y, k)
        ux, uy = _undistort(p0x + (qx - p0x) * f, p0y + (qy - p0y) * f, k)
        src_x = (w - 1) / 2.0 + (ux - u0x) * radius / scale
        src_y = (h - 1) / 2.0 + (uy - u0y) * radius / scale
    else:
        ux, uy = _undistort(qx, qy, k)
        src_x = (g["centre"][:, 0:1] + ux * radius - g["origin"][:, 0:1] + 0.5) / scale - 0.5
        src_y = (g["centre"][:, 1:2] + uy * radius - g["origin"][:, 1:2] + 0.5) / scale - 0.5
    return src_x, src_y


# ------------------------------------------------------------------ noise
def shot_noise(image: torch.Tensor, coverage: torch.Tensor, shot_sigma: torch.Tensor | float,
               noise: torch.Tensor) -> torch.Tensor:
    """Signal-dependent (photon) noise on the object: variance ``σ_shot² · I``.

    ``out = I + σ_shot · sqrt(max(I, 0)) · ε · α`` with ε a standard-normal field
    drawn beforehand; the constant (read-noise) part is the paper's σ_n.
    """
    _check_image(image)
    if noise.shape != image.shape:
        raise ValueError(f"noise must have the image's shape {tuple(image.shape)}, got {tuple(noise.shape)}")
    s = _pc(shot_sigma, image, "shot_sigma")
    return image + s * torch.sqrt(image.clamp_min(0.0) + 1e-8) * noise * coverage


# ------------------------------------------------------------------- JPEG
@lru_cache(maxsize=8)
def dct_matrix(dtype: torch.dtype = torch.float32, device: str = "cpu") -> torch.Tensor:
    """The orthonormal 8-point DCT-II matrix ``D`` of JPEG's block transform: coefficients ``D @ block @ D.T``."""
    n = np.arange(8)
    d = np.cos((2 * n[None, :] + 1) * n[:, None] * np.pi / 16) * np.sqrt(2 / 8)
    d[0] /= np.sqrt(2)
    return torch.tensor(d, dtype=dtype, device=device)


def jpeg_table(quality: torch.Tensor | float) -> torch.Tensor:
    """libjpeg's luminance quantisation steps for ``quality`` (any shape) -> (..., 8, 8).

    ``S = 5000 / q`` below 50, ``200 - 2q`` above; step ``floor((T·S + 50) / 100)``
    clipped to [1, 255] (``jpeg_set_quality`` with baseline tables).

    Example:
        >>> jpeg_table(50.0)[0, :4].tolist()
        [16.0, 11.0, 10.0, 16.0]
    """
    q = torch.as_tensor(quality, dtype=torch.float64).clamp(1.0, 100.0)
    s = torch.where(q < 50, 5000.0 / q, 200.0 - 2.0 * q)
    base = torch.as_tensor(_JPEG_LUMA)
    return torch.floor((base * s[..., None, None] + 50.0) / 100.0).clamp(1.0, 255.0)


def quantize_levels(image: torch.Tensor, bits: int = 8) -> torch.Tensor:
    """The image on the ``2**bits`` levels a camera stores it with: ``round(x · L) / L``, ``L = 2**bits - 1``.

    Real frames (and every patch cut from them) are 8-bit: flat areas are exactly flat. A render is not, so a
    detector can learn "no gradient at all here" as a mark of real data. Values are in [0, 1]; the rounding is exact
    (no gradient passes).

    Example:
        >>> quantize_levels(torch.tensor([0.0, 0.1, 0.5, 1.0])).mul(255).tolist()
        [0.0, 26.0, 128.0, 255.0]
        >>> quantize_levels(torch.tensor([0.3]), bits=1).tolist()
        [0.0]
    """
    if not isinstance(bits, int) or not 1 <= bits <= 16:
        raise ValueError(f"bits must be an int in [1, 16], got {bits!r}")
    levels = float(2 ** bits - 1)
    return image.mul(levels).round().div(levels)


def jpeg_quantize(image: torch.Tensor, quality: torch.Tensor | float, *,
                  phase: tuple[int, int] | torch.Tensor = (0, 0)) -> torch.Tensor:
    """Baseline-JPEG luminance coding of each channel: 8×8 DCT, quantise, inverse DCT.

    Values are in [0, 1] (×255 inside, level-shifted by 128 as JPEG does). The
    rounding is exact in the forward pass and passes gradients straight
    through (w.r.t. the image; ``quality`` is piecewise constant). Quality
    ≥ 100 is the identity ("off"; libjpeg's 100 is near-lossless anyway).
    There is no 8-bit rounding of the decoded pixels and no chroma
    subsampling (colour channels use the luminance table).

    Args:
        image: (B, C, H, W) in [0, 1].
        quality: (B,) or (B, C) in [1, 100].
        phase: (y, x) pixels of the first block that lie *before* the image
            (the frame's block grid seen from a crop: ``origin mod 8``), the
            same for the batch, or a (B, 2) integer tensor.

    Shape:
        image (B, C, H, W) -> (B, C, H, W)
    """
    _check_image(image)
    b, c, h, w = image.shape
    qual = _per_channel(quality, b, c, image, "jpeg_quality")
    if b == 0:
        return image.clone()
    ph = torch.as_tensor(phase, dtype=torch.int64).reshape(-1, 2).expand(b, 2)
    out = torch.empty_like(image)
    for key in torch.unique(ph, dim=0):
        idx = (ph == key).all(1).nonzero().flatten()
        out[idx] = _jpeg_blocks(image[idx], qual[idx], int(key[0]) % 8, int(key[1]) % 8)
    return out


def jpeg_difference_on_frame_grid(image: torch.Tensor, background: torch.Tensor, quality: torch.Tensor | float, *,
                                  origin: torch.Tensor, frame_scale: torch.Tensor | float) -> torch.Tensor:
    """JPEG coding of a composite seen through a resampled crop: the coding error on the FRAME's 8×8 grid.

    A seed patch is a resampled crop of a coded frame, so its blocks are the
    frame's, not the patch's. Both images are resampled (bilinear) onto a
    block-aligned canvas at frame resolution, coded there
    (:func:`jpeg_quantize`), and the *difference of the coding errors*
    ``(Q(W·I) - W·I) - (Q(W·B) - W·B)`` is resampled back and added to
    ``image``: the background's own coding is already in B, and the object
    keeps its resolution (only the error term is resampled).

    Args:
        image: (B, C, P, P) composite in [0, 1].
        background: (B, C, P, P) its background.
        quality: (B,) or (B, C) JPEG quality.
        origin: (B, 2) frame (x, y) of each patch's top-left pixel edge.
        frame_scale: (B,) frame pixels per patch pixel.

    Shape:
        (B, C, P, P) -> (B, C, P, P)

    Example:
        >>> b = torch.full((1, 1, 16, 16), 0.5); i = b.clone(); i[..., 4:12, 4:12] = 0.2
        >>> out = jpeg_difference_on_frame_grid(i, b, 100.0, origin=torch.tensor([[3.0, 5.0]]),
        ...                                     frame_scale=torch.tensor([1.3]))
        >>> torch.equal(out, i)  # quality 100: off
        True
    """
    _check_image(image)
    if background.shape != image.shape:
        raise ValueError(f"background must have the image's shape {tuple(image.shape)}, got {tuple(background.shape)}")
    b, c, h, w = image.shape
    if b == 0:
        return image.clone()
    org = torch.as_tensor(origin, dtype=torch.float64).reshape(-1, 2).expand(b, 2)
    fs = torch.as_tensor(frame_scale, dtype=torch.float64).reshape(-1).expand(b)
    if not bool((fs > 0).all()):
        raise ValueError("frame_scale must be > 0")
    start = torch.floor(torch.floor(org) / 8.0) * 8.0  # (B, 2) block-aligned canvas corner (frame px)
    extent = org + torch.stack([w * fs, h * fs], 1) - start
    # each seed's own canvas, the blocks its crop covers and one more: a seed is coded alone, whatever the batch (a
    # canvas as large as the batch's largest crop cost a 100-seed real set 25x the blocks, stop 113)
    sides = (torch.ceil(extent.max(1).values / 8.0 + 1.0) * 8.0).long()
    q = _per_channel(quality, b, c, image, "jpeg_quality")
    back = torch.empty_like(image)
    for side in torch.unique(sides).tolist():
        idx = (sides == side).nonzero().flatten()
        back[idx] = _frame_grid_error(image[idx], background[idx], q[idx], org[idx], fs[idx], start[idx], side)
    return image + back


def _frame_grid_error(image: torch.Tensor, background: torch.Tensor, q: torch.Tensor, org: torch.Tensor,
                      fs: torch.Tensor, start: torch.Tensor, side: int) -> torch.Tensor:
    """:func:`jpeg_difference_on_frame_grid`'s coding error on a ``side``-px canvas, resampled back to the patches."""
    b, c, h, w = image.shape
    dt = image.dtype
    j = torch.arange(side, dtype=torch.float64)
    # canvas pixel j = frame pixel start + j = patch pixel (start + j + 0.5 - origin) / fs - 0.5
    u = ((start[:, 0, None] + j[None] + 0.5 - org[:, 0, None]) / fs[:, None] - 0.5).to(dt)
    v = ((start[:, 1, None] + j[None] + 0.5 - org[:, 1, None]) / fs[:, None] - 0.5).to(dt)
    wi = _sample(image, u[:, None, None, :], v[:, None, :, None], "border")  # (B, C, side, side)
    wb = _sample(background, u[:, None, None, :], v[:, None, :, None], "border")
    err = (jpeg_quantize(wi, q) - wi) - (jpeg_quantize(wb, q) - wb)
    # back: patch pixel u sits at canvas pixel origin + (u + 0.5) * fs - 0.5 - start
    pu = torch.arange(w, dtype=torch.float64)
    pv = torch.arange(h, dtype=torch.float64)
    bx = (org[:, 0, None] + (pu[None] + 0.5) * fs[:, None] - 0.5 - start[:, 0, None]).to(dt)
    by = (org[:, 1, None] + (pv[None] + 0.5) * fs[:, None] - 0.5 - start[:, 1, None]).to(dt)
    return _sample(err, bx[:, None, None, :], by[:, None, :, None], "zeros")


def _jpeg_blocks(image: torch.Tensor, quality: torch.Tensor, py: int, px: int) -> torch.Tensor:
    b, c, h, w = image.shape
    hp = int(math.ceil((h + py) / 8)) * 8
    wp = int(math.ceil((w + px) / 8)) * 8
    x = F.pad(image * 255.0 - 128.0, (px, wp - w - px, py, hp - h - py), mode="replicate")
    d = dct_matrix(image.dtype, str(image.device))
    blocks = x.reshape(b, c, hp // 8, 8, wp // 8, 8).permute(0, 1, 2, 4, 3, 5)
    coef = d @ blocks @ d.T
    step = jpeg_table(quality.detach()).to(image.dtype)[:, :, None, None]  # (B, C, 1, 1, 8, 8)
    scaled = coef / step
    quant = (scaled + (torch.round(scaled) - scaled).detach()) * step
    rec = (d.T @ quant @ d).permute(0, 1, 2, 4, 3, 5).reshape(b, c, hp, wp)
    rec = (rec + 128.0)[..., py:py + h, px:px + w] / 255.0
    off = (quality >= 100.0 - 1e-6)[..., None, None]
    return torch.where(off, image, rec)
