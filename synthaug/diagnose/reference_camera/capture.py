"""The capture step: the reference camera's whole-frame camera on a linear frame, in physical order
(:data:`~synthaug.diagnose.reference_camera.settings.WHOLE_FRAME_EFFECTS`), then 8-bit and JPEG.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np
import torch

from synthaug.diagnose.reference_camera.settings import WHOLE_FRAME_EFFECTS
from synthaug.effects import camera_functional as Cx
from synthaug.effects.functional import gaussian_blur_fft


def _blur_pad(sigma: float) -> int:
    return int(math.ceil(3.0 * sigma)) + 2


def _one(v: float, like: torch.Tensor) -> torch.Tensor:
    return torch.tensor([float(v)], dtype=like.dtype)


def _haze(img: torch.Tensor, p: dict[str, float], tint: np.ndarray | None) -> torch.Tensor:
    air = _one(p["haze_airlight"], img)
    if tint is not None and img.shape[1] == 3:  # the airlight has the colour of the scene's air
        air = (air * torch.as_tensor(tint, dtype=img.dtype)).clamp(0.0, 1.0)[None]
    return Cx.haze(img, _one(p["haze_amount"], img), air)


def _defocus(img: torch.Tensor, p: dict[str, float], tint: np.ndarray | None) -> torch.Tensor:
    s = p["defocus_sigma"]
    return gaussian_blur_fft(img, _one(s, img), pad=_blur_pad(s), border="replicate")


def _sharpening(img: torch.Tensor, p: dict[str, float], tint: np.ndarray | None) -> torch.Tensor:
    s = p["sharpen_sigma"]
    return Cx.unsharp_mask(img, _one(p["sharpen_amount"], img), _one(s, img), pad=_blur_pad(s), border="replicate")


def column_gains(width: int, sd: float, pattern_seed: int) -> np.ndarray:
    """A sensor's fixed column pattern: each frame column's gain ``1 + sd * N(0, 1)``, from the stream
    ``[pattern_seed, 5]`` (the camera's: the same in every frame and background it captures).

    Example:
        >>> g = column_gains(4000, 0.02, 7)
        >>> round(float(g.mean()), 3), round(float(g.std()), 3), bool((column_gains(4000, 0.02, 7) == g).all())
        (1.0, 0.02, True)
    """
    return 1.0 + float(sd) * np.random.default_rng([int(pattern_seed), 5]).standard_normal(int(width))


def _column_pattern(img: torch.Tensor, p: dict[str, float], tint: np.ndarray | None) -> torch.Tensor:
    g = column_gains(img.shape[-1], p["column_gain_sd"], int(p["pattern_seed"]))
    return img * torch.as_tensor(g, dtype=img.dtype)


def _lens_frame(img: torch.Tensor, k1: float) -> torch.Tensor:
    """A whole frame through a lens of division-model ``k1`` (the map of
    :func:`~synthaug.effects.camera_functional.lens_distortion`, the frame's border repeated beyond it), resampled
    by a quintic spline (scipy's ``map_coordinates``).

    A lens maps the scene onto the sensor before it is sampled and blurs nothing; resampling a sampled frame does:
    bilinearly, the frame's finest detail halves (measured, stop 41: the frames' high-frequency power 0.30-0.35x
    the undistorted frames', and the diagnosis named the blur defocus), Keys' bicubic (a = -0.75) boosts the
    middle frequencies (the edge ratio then read sharpening). The quintic spline keeps the band nearly flat."""
    from scipy import ndimage

    sx, sy = Cx.lens_distortion_source(img, _one(k1, img), recentre=False)
    out = np.stack([ndimage.map_coordinates(img[0, c].numpy(), [sy[0, c].numpy(), sx[0, c].numpy()], order=5,
                                            mode="nearest") for c in range(img.shape[1])])
    return torch.from_numpy(out)[None].to(img.dtype)


# each whole-frame effect on a (1, C, H, W) image, given its settings (shot noise and JPEG: see capture / to_u8)
_FRAME_STEPS: dict[str, Callable[[torch.Tensor, dict[str, float], np.ndarray | None], torch.Tensor]] = {
    "haze": _haze,
    "defocus": _defocus,
    "chromatic_aberration": lambda img, p, t: Cx.chromatic_aberration(img, _one(p["ca_shift"], img), border="border"),
    "lens_distortion": lambda img, p, t: _lens_frame(img, p["distortion_k1"]),
    "vignetting": lambda img, p, t: Cx.vignetting(img, _one(p["vignette_k"], img)),
    "exposure": lambda img, p, t: Cx.exposure(img, _one(p["exposure_gain"], img), _one(p["exposure_offset"], img)),
    "white_balance": lambda img, p, t: Cx.white_balance(img, wb_gains(p["wb_gain"], img.shape[1], img.dtype)),
    "gamma": lambda img, p, t: Cx.gamma_curve(img.clamp(0.0, 1.0), _one(p["gamma_g"], img)),
    "sharpening": _sharpening,
    "column_pattern": _column_pattern,
}


def capture(img: torch.Tensor, cam: dict[str, dict[str, float]], noise: torch.Tensor, noise_factor: float,
            read_noise: float, tint: np.ndarray | None = None) -> torch.Tensor:
    """The whole-frame camera on a (1, C, H, W) float64 scene image, up to (not including) 8-bit/JPEG.

    The hidden effects of ``cam`` act in the order of
    :data:`~synthaug.diagnose.reference_camera.settings.WHOLE_FRAME_EFFECTS`; the sensor's noise (read noise
    always, shot noise when hidden; ``noise`` its standard normal field, scaled by ``noise_factor``) sits at
    ``shot_noise``'s place. ``tint``: the colour of the scene's air (RGB, unit luma), the haze airlight's
    colour in RGB.
    """
    for name in WHOLE_FRAME_EFFECTS:
        if name == "shot_noise":
            shot = cam.get("shot_noise", {}).get("shot_sigma", 0.0)
            std = torch.sqrt(read_noise ** 2 + shot ** 2 * img.clamp(0.0, 1.0))
            img = img + noise_factor * std * noise
        elif name in cam and name in _FRAME_STEPS:
            img = _FRAME_STEPS[name](img, cam[name], tint)
    return img


def wb_gains(g: float, channels: int, dtype: torch.dtype = torch.float64) -> torch.Tensor:
    """White balance ``g`` as per-channel gains (1, C): gray ``g``; RGB ``(g, 1, 1/g)`` (a colour-temperature
    shift: red up, blue down, green fixed)."""
    if channels == 3:
        return torch.tensor([[g, 1.0, 1.0 / g]], dtype=dtype)
    return torch.tensor([float(g)], dtype=dtype)


def to_u8(img: torch.Tensor, cam: dict[str, dict[str, float]]) -> np.ndarray:
    """8-bit (and JPEG) of a (1, C, H, W) image: (H, W) gray or (H, W, 3) RGB."""
    import cv2

    u8 = np.clip(np.round(img[0].permute(1, 2, 0).numpy() * 255.0), 0, 255).astype(np.uint8)
    u8 = u8[..., 0] if u8.shape[-1] == 1 else np.ascontiguousarray(u8)
    if "compression" in cam:
        q = int(round(cam["compression"]["jpeg_quality"]))
        bgr = u8 if u8.ndim == 2 else cv2.cvtColor(u8, cv2.COLOR_RGB2BGR)
        ok, buf = cv2.imencode(".jpg", bgr, [cv2.IMWRITE_JPEG_QUALITY, q])
        if not ok:
            raise RuntimeError("JPEG encoding failed")
        u8 = cv2.imdecode(buf, cv2.IMREAD_GRAYSCALE if u8.ndim == 2 else cv2.IMREAD_COLOR)
        u8 = u8 if u8.ndim == 2 else cv2.cvtColor(u8, cv2.COLOR_BGR2RGB)
    return u8
