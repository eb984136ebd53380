"""The capture step: the reference camera's whole-frame camera on a linear frame, in physical order
(:data:`~synthaug.diagnose.reference_camera.settings.WHOLE_FRAME_EFFECTS`), then 8-bit and JPEG.
"""

from __future__ import annotations

import math

import numpy as np
import torch

from synthaug.effects import camera_functional as Cx
from synthaug.effects.functional import gaussian_blur_fft


def _blur_pad(sigma: float) -> int:
    return int(math.ceil(3.0 * sigma)) + 2


def capture(img: torch.Tensor, cam: dict[str, dict[str, float]], noise: torch.Tensor, noise_factor: float,
            read_noise: float, tint: np.ndarray | None = None) -> torch.Tensor:
    """The whole-frame camera on a (1, C, H, W) float64 scene image, up to (not including) 8-bit/JPEG.
    ``tint``: the colour of the scene's air (RGB, unit luma), the haze airlight's colour in RGB."""
    one = lambda v: torch.tensor([float(v)], dtype=img.dtype)  # noqa: E731
    if "haze" in cam:
        air = one(cam["haze"]["haze_airlight"])
        if tint is not None and img.shape[1] == 3:
            air = (air * torch.as_tensor(tint, dtype=img.dtype)).clamp(0.0, 1.0)[None]
        img = Cx.haze(img, one(cam["haze"]["haze_amount"]), air)
    if "defocus" in cam:
        s = cam["defocus"]["defocus_sigma"]
        img = gaussian_blur_fft(img, one(s), pad=_blur_pad(s), border="replicate")
    if "chromatic_aberration" in cam:
        img = Cx.chromatic_aberration(img, one(cam["chromatic_aberration"]["ca_shift"]), border="border")
    if "lens_distortion" in cam:
        img = Cx.lens_distortion(img, one(cam["lens_distortion"]["distortion_k1"]), recentre=False, border="border")
    if "vignetting" in cam:
        img = Cx.vignetting(img, one(cam["vignetting"]["vignette_k"]))
    if "exposure" in cam:
        img = Cx.exposure(img, one(cam["exposure"]["exposure_gain"]), one(cam["exposure"]["exposure_offset"]))
    if "white_balance" in cam:
        img = Cx.white_balance(img, wb_gains(cam["white_balance"]["wb_gain"], img.shape[1], img.dtype))
    shot = cam.get("shot_noise", {}).get("shot_sigma", 0.0)
    std = torch.sqrt(read_noise ** 2 + shot ** 2 * img.clamp(0.0, 1.0))
    img = img + noise_factor * std * noise
    if "gamma" in cam:
        img = Cx.gamma_curve(img.clamp(0.0, 1.0), one(cam["gamma"]["gamma_g"]))
    if "sharpening" in cam:
        s = cam["sharpening"]["sharpen_sigma"]
        img = Cx.unsharp_mask(img, one(cam["sharpening"]["sharpen_amount"]), one(s), pad=_blur_pad(s),
                              border="replicate")
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
