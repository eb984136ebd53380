"""Nuisances of measured data: variation that is NOT a camera effect, for the reference camera (issue 20).

Real measured data differ from the fit's renderer in ways no capture effect
describes: the object's material and shading, the light of each video, the
real object's shape, a scene that moves between the frame and the background
estimate. A diagnosis that only ever sees data shaded exactly like its own
renderer cannot be trusted to stay quiet on real data; its null distributions
(:mod:`synthaug.diagnose.calibration`) are therefore measured on measured data
with these nuisances drawn at random.

Two records, drawn in one step and applied in another (as kornia's
``generate_parameters`` / ``apply_transform``):

- :class:`Nuisances` — the case's object, material, light and scene model
  (one frozen record per seed set: what the real object and its scenes are
  like). :meth:`Nuisances.none` is the fit's own model (Lambert shading with
  ambient 0.4 under the default light, flat normals, uniform albedo, the
  fit's mesh, a background that is exactly the frame's scene): the reference
  camera then makes the same bytes as without nuisances.
  :meth:`Nuisances.draw` draws a realistic case from a ``numpy.random.Generator``.
- :class:`SeedNuisance` — the values one seed sees (its video's light
  direction and strength, the scene's drift and brightness change between the
  frame and its background), drawn by :meth:`Nuisances.draw_seed` from
  ``(seed, seed index, video)`` alone, so that a seed set with and without a
  hidden camera effect has the same nuisances.

Applied by :func:`shade_object` (material and light on the object layers) and
:func:`drift_scene` (the frame's scene against the background's). The fit never
sees these values; the reference camera writes them into the seed set's header
and each record's truth.

Example:
    >>> import numpy as np
    >>> n = Nuisances.draw(np.random.default_rng(0))
    >>> n.is_none(), Nuisances.none().is_none(), Nuisances.from_dict(n.as_dict()) == n
    (False, True, True)
    >>> s = n.draw_seed(seed=3, index=0, video=0)
    >>> len(s.light_dir), abs(float(np.linalg.norm(s.light_dir)) - 1.0) < 1e-9
    (3, True)
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields
from typing import Any, Mapping

import numpy as np
import torch

__all__ = ["Nuisances", "SeedNuisance", "shade_object", "smooth_normals", "drift_scene", "paint_tint", "MODEL_LIGHT",
           "MODEL_AMBIENT"]

# The fit's material (synthaug.effects.paper.Material): Lambert, ambient 0.4, light from above and in front.
MODEL_LIGHT = (0.0, 0.5, 0.8660254)
MODEL_AMBIENT = 0.4

# (low, high) of each field that Nuisances.draw draws uniformly; the rest are discrete choices.
DRAW_RANGES: dict[str, tuple[float, float]] = {
    "ambient": (0.25, 0.55),
    "specular_ks": (0.0, 0.2),
    "specular_shininess": (10.0, 60.0),
    "albedo_texture_amp": (0.0, 0.12),
    "albedo_texture_px": (1.0, 3.0),
    "light_spread_deg": (10.0, 40.0),
    "light_strength_spread": (0.0, 0.2),
    "rotor_scale": (0.85, 1.2),
    "mesh_perturbation": (0.0, 0.04),
    "background_drift_px": (0.0, 1.5),
    "background_flicker": (0.0, 0.02),
}
SMOOTH_NORMALS_PX = (0.7, 2.0)  # smooth shading: the normal map blurred by this (frame px), drawn half the time
# The object's paint in colour (a chroma offset of its albedo, Rec. 601 luma kept): near-neutral bodies (white, grey,
# black plastics with a slight cast), drawn after every other field so that the draws before it are unchanged.
PAINT_SATURATION = (0.0, 0.1)
MESH_SECTIONS = (16, 24, 32)  # cylinders of the real quadcopter: the model's (16) or finer


@dataclass(frozen=True)
class SeedNuisance:
    """The nuisance values one seed sees (drawn by :meth:`Nuisances.draw_seed`).

    Attributes:
        light_dir: unit vector toward the light (camera frame: x right, y up, z to the camera), its video's.
        light_strength: its video's light strength relative to the model's (a factor on the object's radiance).
        drift: (dx, dy) frame px the frame's scene is moved by relative to the background frame's.
        flicker: relative brightness change of the frame's scene against the background frame's.
        texture_seed: seed of the albedo texture's white noise.
    """

    light_dir: tuple[float, float, float]
    light_strength: float
    drift: tuple[float, float]
    flicker: float
    texture_seed: int

    def as_dict(self) -> dict[str, Any]:
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self).items()}


@dataclass(frozen=True)
class Nuisances:
    """A case's object, material, light and scene model (frozen; see the module docstring).

    Attributes:
        ambient: fraction of direction-independent light (the model's: 0.4).
        specular_ks, specular_shininess: Blinn-Phong highlight, ks · max(0, n·h)^shininess, added to the object
            (the model's: none). A glossy paint, a plastic housing.
        normal_smoothing_px: smooth shading: the normal map blurred by this (frame px) inside the object and
            renormalised (0: the model's flat faces).
        albedo_texture_amp, albedo_texture_px: albedo × (1 + amp · F), F a unit-variance Gaussian field of
            correlation length ``albedo_texture_px`` frame px (paint, decals, dirt; the model's is uniform).
        light_spread_deg: each video's light is tilted from the model's by up to this angle (random azimuth).
        light_strength_spread: each video's light strength is a factor in [1 - s, 1 + s].
        rotor_scale: radius of the real propellers relative to the model's (built-in quadcopter only).
        mesh_sections: sections of the real quadcopter's cylinders (the model's 16; finer is smoother).
        mesh_perturbation: smooth deformation of the real mesh
            (:func:`~synthaug.diagnose.reference_camera.perturb_mesh`).
        background_drift_px: each seed's scene moves by up to this (frame px, random direction) between the
            frame and its background estimate (clouds, a panning camera).
        background_flicker: each seed's scene brightness changes by a factor in [1 - f, 1 + f] between them.
        paint_saturation, paint_hue_deg: the object's paint in colour: its albedo times :func:`paint_tint` per RGB
            channel (a chroma offset of this length at this hue; 0 the model's neutral grey; hue 0 toward red and
            away from blue, 180 a bluish cast). The Rec. 601 luma is unchanged, so gray data do not see it; a
            highlight stays white (a dielectric paint).
    """

    ambient: float = MODEL_AMBIENT
    specular_ks: float = 0.0
    specular_shininess: float = 30.0
    normal_smoothing_px: float = 0.0
    albedo_texture_amp: float = 0.0
    albedo_texture_px: float = 2.0
    light_spread_deg: float = 0.0
    light_strength_spread: float = 0.0
    rotor_scale: float = 1.0
    mesh_sections: int = 16
    mesh_perturbation: float = 0.0
    background_drift_px: float = 0.0
    background_flicker: float = 0.0
    paint_saturation: float = 0.0
    paint_hue_deg: float = 0.0

    def __post_init__(self) -> None:
        from synthaug.params import TEXTURE_SCALE_MAX, TEXTURE_SCALE_MIN

        checks = {
            "ambient": (0.0, 1.0), "specular_ks": (0.0, 1.0), "specular_shininess": (1.0, 500.0),
            "normal_smoothing_px": (0.0, 5.0), "albedo_texture_amp": (0.0, 0.5),
            "albedo_texture_px": (TEXTURE_SCALE_MIN, TEXTURE_SCALE_MAX), "light_spread_deg": (0.0, 80.0),
            "light_strength_spread": (0.0, 0.5), "rotor_scale": (0.5, 1.5), "mesh_perturbation": (0.0, 0.5),
            "background_drift_px": (0.0, 5.0), "background_flicker": (0.0, 0.2), "paint_saturation": (0.0, 0.5),
            "paint_hue_deg": (0.0, 360.0),
        }
        for name, (lo, hi) in checks.items():
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and lo <= v <= hi):
                raise ValueError(f"Nuisances.{name} must be in [{lo}, {hi}], got {v!r}")
        if int(self.mesh_sections) != self.mesh_sections or not 8 <= self.mesh_sections <= 64:
            raise ValueError(f"Nuisances.mesh_sections must be an integer in [8, 64], got {self.mesh_sections!r}")

    # ------------------------------------------------------------ construction
    @classmethod
    def none(cls) -> "Nuisances":
        """The fit's own model: no nuisance (the reference camera's output is unchanged)."""
        return cls()

    @classmethod
    def draw(cls, rng: np.random.Generator) -> "Nuisances":
        """A realistic random case: every nuisance on, each value uniform in :data:`DRAW_RANGES`, smooth
        normals half the time, the cylinders' sections from :data:`MESH_SECTIONS`, the paint's saturation from
        :data:`PAINT_SATURATION` at a uniform hue (drawn last: the fields before it are those drawn without it)."""
        if not isinstance(rng, np.random.Generator):
            raise ValueError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
        v = {k: float(rng.uniform(lo, hi)) for k, (lo, hi) in DRAW_RANGES.items()}
        smooth = bool(rng.random() < 0.5)
        v["normal_smoothing_px"] = float(rng.uniform(*SMOOTH_NORMALS_PX)) if smooth else 0.0
        v["mesh_sections"] = int(rng.choice(MESH_SECTIONS))
        v["paint_saturation"] = float(rng.uniform(*PAINT_SATURATION))
        v["paint_hue_deg"] = float(rng.uniform(0.0, 360.0))
        return cls(**v)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any] | None) -> "Nuisances":
        """The record of :meth:`as_dict` (None or {} : :meth:`none`)."""
        d = dict(d or {})
        known = {f.name for f in fields(cls)}
        bad = sorted(set(d) - known)
        if bad:
            raise ValueError(f"unknown nuisance field(s) {bad}; known: {sorted(known)}")
        return cls(**d)

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)

    def is_none(self) -> bool:
        return self == Nuisances()

    @property
    def shading_is_model(self) -> bool:
        """Whether the object is shaded exactly as the fit's material shades it."""
        return (self.ambient == MODEL_AMBIENT and self.specular_ks == 0 and self.normal_smoothing_px == 0
                and self.albedo_texture_amp == 0 and self.light_spread_deg == 0 and self.light_strength_spread == 0)

    @property
    def paint_rgb(self) -> np.ndarray:
        """The paint's per-channel factor on the albedo (RGB, unit luma): :func:`paint_tint`."""
        return paint_tint(self.paint_saturation, self.paint_hue_deg)

    @property
    def mesh_is_model(self) -> bool:
        return self.rotor_scale == 1.0 and self.mesh_sections == 16 and self.mesh_perturbation == 0

    # ------------------------------------------------------------ per seed
    def draw_seed(self, *, seed: int, index: int, video: int) -> SeedNuisance:
        """The values seed ``index`` of video ``video`` sees, a pure function of ``(seed, index, video)``.

        The light is its video's (streams ``[seed, video, 6]``); the scene's drift, flicker and the texture's
        noise are its own (``[seed, index, 5]``). No stream the reference camera uses otherwise is touched.
        """
        vr = np.random.default_rng([seed, video, 6])
        tilt = math.radians(float(vr.uniform(0.0, self.light_spread_deg)))
        azimuth = float(vr.uniform(0.0, 2 * math.pi))
        strength = 1.0 + float(vr.uniform(-self.light_strength_spread, self.light_strength_spread))
        light = _tilt(np.asarray(MODEL_LIGHT, np.float64), tilt, azimuth)
        sr = np.random.default_rng([seed, index, 5])
        a = float(sr.uniform(0.0, 2 * math.pi))
        r = float(sr.uniform(0.0, self.background_drift_px))
        flick = float(sr.uniform(-self.background_flicker, self.background_flicker))
        return SeedNuisance(light_dir=tuple(float(x) for x in light), light_strength=strength,
                            drift=(r * math.cos(a), r * math.sin(a)), flicker=flick,
                            texture_seed=int(sr.integers(2 ** 62)))


def paint_tint(saturation: float, hue_deg: float) -> np.ndarray:
    """Per-channel RGB factors ``1 + s (cos h · u + sin h · v)``: u, v an orthonormal basis of the chroma plane (the
    vectors orthogonal to the Rec. 601 luma weights L; u toward red and away from blue), so ``L · tint = 1`` and the
    offset's length is ``s``.

    Example:
        >>> from synthaug.effects.camera_functional import LUMA_WEIGHTS
        >>> t = paint_tint(0.1, 30.0)
        >>> round(float(np.dot(t, LUMA_WEIGHTS)), 12), round(float(np.linalg.norm(t - 1)), 12)
        (1.0, 0.1)
        >>> bool(paint_tint(0.1, 0.0)[0] > 1 > paint_tint(0.1, 0.0)[2]), paint_tint(0.0, 90.0).tolist()
        (True, [1.0, 1.0, 1.0])
    """
    from synthaug.effects.camera_functional import LUMA_WEIGHTS

    lw = np.asarray(LUMA_WEIGHTS, np.float64)
    x = np.array([1.0, 0.0, -1.0])
    u = x - (x @ lw) / (lw @ lw) * lw
    u /= np.linalg.norm(u)
    v = np.cross(lw, u)
    v /= np.linalg.norm(v)
    h = math.radians(hue_deg)
    return 1.0 + saturation * (math.cos(h) * u + math.sin(h) * v)


def _tilt(v: np.ndarray, angle: float, azimuth: float) -> np.ndarray:
    """``v`` (unit) tilted by ``angle`` toward the direction ``azimuth`` around it (Rodrigues)."""
    v = v / np.linalg.norm(v)
    helper = np.array([1.0, 0.0, 0.0]) if abs(v[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(v, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(v, e1)
    axis = math.cos(azimuth) * e1 + math.sin(azimuth) * e2  # perpendicular to v: the tilt's direction
    out = math.cos(angle) * v + math.sin(angle) * axis
    return out / np.linalg.norm(out)


# ------------------------------------------------------------------ apply (no random numbers drawn here)
def smooth_normals(normals: torch.Tensor, coverage: torch.Tensor, sigma: float) -> torch.Tensor:
    """Smooth shading from flat faces: normals blurred by ``sigma`` px inside the object, renormalised.

    The blur is normalised by the blurred coverage, so the object's edge does not pull normals toward zero.

    Shape:
        normals (B, 3, H, W), coverage (B, 1, H, W) -> (B, 3, H, W), unit where covered, 0 elsewhere.
    """
    if sigma <= 0:
        return normals
    from synthaug.effects.functional import gaussian_blur_fft

    s = torch.full((normals.shape[0],), float(sigma), dtype=normals.dtype)
    pad = int(math.ceil(3 * sigma)) + 2
    w = (coverage > 0).to(normals.dtype)
    num = gaussian_blur_fft(normals * w, s, pad=pad, border="constant")
    den = gaussian_blur_fft(w, s, pad=pad, border="constant").clamp_min(1e-6)
    n = num / den
    n = n / n.norm(dim=1, keepdim=True).clamp_min(1e-6)
    return torch.where(w > 0, n, torch.zeros_like(n))


def shade_object(normals: torch.Tensor, coverage: torch.Tensor, w_d: torch.Tensor | float, nuisances: Nuisances,
                 seed_nuisance: SeedNuisance, *, texture: torch.Tensor | None = None) -> torch.Tensor:
    """The real object's radiance: the case's material under its video's light (straight, not premultiplied).

    ``strength · [w_d · T · (ambient + (1 - ambient) · max(0, n·l)) + ks · max(0, n·h)^shininess]`` on
    covered pixels, with n the (optionally smoothed) normals, l the video's light, h the half vector between
    l and the view direction (0, 0, 1), T = 1 + amp · F the albedo texture (``texture`` = F, unit variance).
    With :meth:`Nuisances.none` it equals the fit's Lambert material
    (:func:`synthaug.effects.functional.diffuse_material`).

    Shape:
        normals (B, 3, H, W), coverage (B, 1, H, W), texture (B, 1, H, W) or None -> (B, 1, H, W).
    """
    from synthaug.effects.functional import diffuse_material

    n = smooth_normals(normals, coverage, nuisances.normal_smoothing_px)
    light = torch.tensor(seed_nuisance.light_dir, dtype=normals.dtype)
    w = torch.as_tensor(w_d, dtype=normals.dtype).reshape(-1, 1)
    col = diffuse_material(n, coverage, w, light_dir=light, ambient=nuisances.ambient)
    if texture is not None and nuisances.albedo_texture_amp > 0:
        col = col * (1.0 + nuisances.albedo_texture_amp * texture).clamp_min(0.0)
    if nuisances.specular_ks > 0:
        h = light + torch.tensor([0.0, 0.0, 1.0], dtype=normals.dtype)
        h = h / h.norm()
        ndh = (n * h.reshape(1, 3, 1, 1)).sum(1, keepdim=True).clamp_min(0.0)
        col = col + nuisances.specular_ks * ndh ** nuisances.specular_shininess * (coverage > 0).to(col.dtype)
    return (col * seed_nuisance.light_strength).clamp(0.0, 1.0)


def drift_scene(scene: np.ndarray, seed_nuisance: SeedNuisance) -> np.ndarray:
    """The frame's scene as it was when the frame was taken: the background's scene moved by ``drift`` px
    and its brightness changed by ``flicker``. Identity without drift or flicker.

    The move is a Fourier (sinc) shift of the scene, reflect-padded so the frame's edges do not wrap:
    a moving scene is not a blurrier one, and a bilinear shift would low-pass the frame's scene against
    the background's (a false "defocus").

    Shape:
        (H, W) or (C, H, W) float in [0, 1] -> the same.
    """
    dx, dy = seed_nuisance.drift
    if dx == 0 and dy == 0 and seed_nuisance.flicker == 0:
        return scene
    out = np.asarray(scene, np.float64)
    if dx or dy:
        pad = 16 + int(math.ceil(max(abs(dx), abs(dy))))
        planes = out[None] if out.ndim == 2 else out
        moved = []
        for plane in planes:
            a = np.pad(plane, pad, mode="reflect")
            fy = np.fft.fftfreq(a.shape[0])[:, None]
            fx = np.fft.fftfreq(a.shape[1])[None, :]
            f = np.fft.fft2(a) * np.exp(-2j * np.pi * (fx * dx + fy * dy))
            moved.append(np.real(np.fft.ifft2(f))[pad:-pad, pad:-pad])
        out = moved[0] if out.ndim == 2 else np.stack(moved)
    return np.clip(out * (1.0 + seed_nuisance.flicker), 0.0, 1.0)
