"""Candidate camera effects (issue 6): registered extensions of S(Θ, B).

A real camera does more than the paper's four effects. Each candidate here is
a registered :class:`~synthaug.effects.registry.Effect` with its own
parameters, neutral at their default (the identity), so
``CaptureParams(effects=PAPER_EFFECTS + ("vignetting",))`` extends Θ and
:func:`synthaug.effects.simulate` runs it. The pure functions live in
:mod:`synthaug.effects.camera_functional`.

The real background B_i was captured through the camera, so a whole-frame
effect is already inside it; what the model misses is the effect's action on
the rendered *object*. Hence:

- affine pointwise effects (haze, vignetting, exposure, white balance) act on
  the object's colour (object stage): ``α·T(o) + (1-α)·T(b)`` is exactly
  ``T(α·o + (1-α)·b)`` for affine T;
- linear spatial effects L (defocus, chromatic aberration, lens distortion,
  sharpening) act on the object's difference layer: the camera records
  ``L(α·o + (1-α)·b) = L(b) + L(α·(o - b))`` and B = L(b), so
  ``out = B + L(I - B)`` (b ≈ B under the object);
- the tone curve (gamma) relinearises the background, see
  :func:`~synthaug.effects.camera_functional.gamma_composite`;
- compression: ``out = B + Q(I) - Q(B)``, Q the JPEG coder, so blocks without
  the object are untouched;
- object-only physics (specular highlights, spinning rotors, rolling shutter
  of the moving object, photon noise on its pixels) act on the object alone.

=====================  ======  =====================================  =========
name                   stage   parameters (neutral)                   order
=====================  ======  =====================================  =========
specular               object  specular_ks (0), specular_shininess    1
haze                   object  haze_amount (0), haze_airlight         2
vignetting             object  vignette_k (0)                         3
exposure               object  exposure_gain (1), exposure_offset (0) 4
white_balance          object  wb_gain (1)                            5
rotor_blur             object  rotor_opacity (1)                      7
rolling_shutter        object  rs_skew (0), rs_stretch (0)            15
defocus                image   defocus_sigma (0)                      5
chromatic_aberration   image   ca_shift (0)                           6
lens_distortion        image   distortion_k1 (0)                      7
shot_noise             image   shot_sigma (0)                         25
gamma                  image   gamma_g (1)                            30
sharpening             image   sharpen_amount (0), sharpen_sigma      35
compression            image   jpeg_quality (100 = off)               40
=====================  ======  =====================================  =========

(The paper's effects: material 0, motion_blur 10 (object); boundary_blur 10,
object_noise 20 (image).) The orders follow the physics: atmosphere, optics,
sensor, then the camera's processing (tone curve, sharpening, codec).

Position-aware effects (vignetting, chromatic aberration, lens distortion, the
JPEG block grid) read ``state.origin`` (B, 2), ``state.frame_size`` (B, 2) and
``state.extras["frame_scale"]`` (B,) (frame px per patch px, a seed's
``side / P``; default 1); without them the patch is taken as the frame.
``rotor_blur`` uses ``state.extras["part_rotor"]`` (B, 1, H, W) when the
renderer provides it. Importing this module registers the effects.

Example:
    >>> import torch
    >>> from synthaug.params import CaptureParams
    >>> from synthaug.effects import PAPER_EFFECTS, simulate
    >>> theta = CaptureParams({"vignette_k": [0.3]}, effects=PAPER_EFFECTS + ("vignetting",))
    >>> cov = torch.zeros(1, 1, 8, 8); cov[..., 2:6, 2:6] = 1
    >>> nrm = torch.zeros(1, 3, 8, 8); nrm[:, 2] = cov[:, 0]
    >>> img = simulate(cov, nrm, torch.full((1, 1, 8, 8), 0.8), theta, generator=torch.Generator().manual_seed(0))
    >>> img.shape, round(float(img[0, 0, 0, 0]), 2)  # the real background is untouched
    (torch.Size([1, 1, 8, 8]), 0.8)
"""

from __future__ import annotations

import math

import torch

from synthaug.effects import camera_functional as Cx
from synthaug.effects.paper import DEFAULT_LIGHT
from synthaug.effects.registry import Effect, RenderState, register_effect
from synthaug.params import DEFOCUS_SIGMA_MAX, EFFECT_PARAM_SPECS, SHARPEN_SIGMA_MAX  # noqa: F401  (re-exported)

__all__ = ["CAMERA_EFFECTS", "DEFOCUS_SIGMA_MAX", "SHARPEN_SIGMA_MAX", "frame_geometry"]


# the candidate effects, in the order
CAMERA_EFFECTS: tuple[str, ...] = (
    "vignetting", "gamma", "shot_noise", "defocus", "compression", "specular", "haze",
    "chromatic_aberration", "white_balance", "sharpening", "lens_distortion", "rolling_shutter",
    "rotor_blur", "exposure",
)


def _pad(sigma_max: float) -> int:
    return int(math.ceil(3.0 * sigma_max))


def frame_geometry(state: RenderState) -> dict[str, torch.Tensor | None]:
    """``origin``, ``frame_size``, ``frame_scale`` of a state (None where unknown)."""
    return {"origin": state.origin, "frame_size": state.frame_size,
            "frame_scale": state.extras.get("frame_scale")}


def _image(state: RenderState, name: str) -> torch.Tensor:
    if state.image is None:
        raise ValueError(f"{name} is an image-stage effect: it needs the composite (state.image is None)")
    return state.image


def _on_difference(state: RenderState, name: str, fn) -> RenderState:
    """``B + L(I - B)``: a linear spatial camera effect seen through the real background."""
    img = _image(state, name)
    bg = state.background
    return state.replace(image=bg + fn(img - bg))


# ------------------------------------------------------------- object stage
@register_effect
class Specular(Effect):
    """Specular highlights (Blinn-Phong), the paper's own suggested extension of MP."""

    name = "specular"
    stage = "object"
    order = 1.0
    params = EFFECT_PARAM_SPECS["specular"]  # declared in synthaug.params

    def apply(self, state: RenderState, *, specular_ks: torch.Tensor,
              specular_shininess: torch.Tensor) -> RenderState:
        light = state.extras.get("light_dir", torch.tensor(DEFAULT_LIGHT))
        hl = Cx.specular_highlight(state.normals, state.coverage, specular_ks, specular_shininess, light_dir=light)
        return state.replace(object_color=state.object_color + hl)


@register_effect
class Haze(Effect):
    """Atmospheric haze: the object's contrast fades toward the airlight."""

    name = "haze"
    stage = "object"
    order = 2.0
    params = EFFECT_PARAM_SPECS["haze"]  # declared in synthaug.params

    def apply(self, state: RenderState, *, haze_amount: torch.Tensor, haze_airlight: torch.Tensor) -> RenderState:
        return state.replace(object_color=Cx.haze(state.object_color, haze_amount, haze_airlight))


@register_effect
class Vignetting(Effect):
    """Vignetting: light fall-off toward the frame corners, ``1 - k r²`` (position-aware)."""

    name = "vignetting"
    stage = "object"
    order = 3.0
    params = EFFECT_PARAM_SPECS["vignetting"]  # declared in synthaug.params

    def apply(self, state: RenderState, *, vignette_k: torch.Tensor) -> RenderState:
        return state.replace(object_color=Cx.vignetting(state.object_color, vignette_k, **frame_geometry(state)))


@register_effect
class Exposure(Effect):
    """Exposure: sensor gain and black-level offset on the object (the background has them)."""

    name = "exposure"
    stage = "object"
    order = 4.0
    params = EFFECT_PARAM_SPECS["exposure"]  # declared in synthaug.params

    def apply(self, state: RenderState, *, exposure_gain: torch.Tensor, exposure_offset: torch.Tensor) -> RenderState:
        return state.replace(object_color=Cx.exposure(state.object_color, exposure_gain, exposure_offset))


@register_effect
class WhiteBalance(Effect):
    """White balance: per-channel gain (grayscale: a plain gain, indistinguishable from w_d)."""

    name = "white_balance"
    stage = "object"
    order = 5.0
    params = EFFECT_PARAM_SPECS["white_balance"]  # declared in synthaug.params

    def apply(self, state: RenderState, *, wb_gain: torch.Tensor) -> RenderState:
        return state.replace(object_color=Cx.white_balance(state.object_color, wb_gain))


@register_effect
class RotorBlur(Effect):
    """Spinning propellers: the rotor discs are seen semi-transparent (opacity ρ)."""

    name = "rotor_blur"
    stage = "object"
    order = 7.0
    params = EFFECT_PARAM_SPECS["rotor_blur"]  # declared in synthaug.params

    def apply(self, state: RenderState, *, rotor_opacity: torch.Tensor) -> RenderState:
        cov = Cx.rotor_blur(state.coverage, rotor_opacity, state.extras.get("part_rotor"))
        return state.replace(coverage=cov)


@register_effect
class RollingShutter(Effect):
    """Rolling shutter: rows read at successive times shear and stretch the moving object."""

    name = "rolling_shutter"
    stage = "object"
    order = 15.0
    params = EFFECT_PARAM_SPECS["rolling_shutter"]  # declared in synthaug.params

    def apply(self, state: RenderState, *, rs_skew: torch.Tensor, rs_stretch: torch.Tensor) -> RenderState:
        color, cov = Cx.rolling_shutter(state.object_color, state.coverage, rs_skew, rs_stretch)
        return state.replace(object_color=color, coverage=cov)


# -------------------------------------------------------------- image stage
@register_effect
class Defocus(Effect):
    """Defocus: whole-image Gaussian blur σ (the object's sharp detail and edges alike)."""

    name = "defocus"
    stage = "image"
    order = 5.0
    params = EFFECT_PARAM_SPECS["defocus"]  # declared in synthaug.params

    def apply(self, state: RenderState, *, defocus_sigma: torch.Tensor) -> RenderState:
        return _on_difference(state, self.name,
                              lambda d: Cx.defocus(d, defocus_sigma, pad=_pad(DEFOCUS_SIGMA_MAX)))


@register_effect
class ChromaticAberration(Effect):
    """Lateral chromatic aberration: colour planes scaled about the frame centre (gray: radial blur)."""

    name = "chromatic_aberration"
    stage = "image"
    order = 6.0
    params = EFFECT_PARAM_SPECS["chromatic_aberration"]  # declared in synthaug.params

    def apply(self, state: RenderState, *, ca_shift: torch.Tensor) -> RenderState:
        geo = frame_geometry(state)
        return _on_difference(state, self.name, lambda d: Cx.chromatic_aberration(d, ca_shift, **geo))


@register_effect
class LensDistortion(Effect):
    """Radial lens distortion k₁ (barrel < 0 < pincushion), about the patch centre."""

    name = "lens_distortion"
    stage = "image"
    order = 7.0
    params = EFFECT_PARAM_SPECS["lens_distortion"]  # declared in synthaug.params

    def apply(self, state: RenderState, *, distortion_k1: torch.Tensor) -> RenderState:
        geo = frame_geometry(state)
        return _on_difference(state, self.name, lambda d: Cx.lens_distortion(d, distortion_k1, recentre=True, **geo))


@register_effect
class ShotNoise(Effect):
    """Photon (shot) noise on the object: variance σ_shot² · I, grows with brightness."""

    name = "shot_noise"
    stage = "image"
    order = 25.0
    params = EFFECT_PARAM_SPECS["shot_noise"]  # declared in synthaug.params

    def sample_fields(self, shape, generator, dtype=torch.float32):
        return {"shot_noise": torch.randn(shape, generator=generator, dtype=dtype)}

    def apply(self, state: RenderState, *, shot_sigma: torch.Tensor) -> RenderState:
        img = _image(state, self.name)
        noise = state.fields.get("shot_noise")
        if noise is None:
            raise ValueError("shot_noise needs a 'shot_noise' field: draw it with sample_fields(...)")
        return state.replace(image=Cx.shot_noise(img, state.coverage, shot_sigma, noise.to(img.dtype)))


@register_effect
class Gamma(Effect):
    """Camera response (tone) curve x^g of the whole frame, relinearising the real background."""

    name = "gamma"
    stage = "image"
    order = 30.0
    params = EFFECT_PARAM_SPECS["gamma"]  # declared in synthaug.params

    def apply(self, state: RenderState, *, gamma_g: torch.Tensor) -> RenderState:
        img = _image(state, self.name)
        return state.replace(image=Cx.gamma_composite(img, state.coverage, state.background, gamma_g))


@register_effect
class Sharpening(Effect):
    """In-camera sharpening (unsharp mask): halos along the object's edges."""

    name = "sharpening"
    stage = "image"
    order = 35.0
    params = EFFECT_PARAM_SPECS["sharpening"]  # declared in synthaug.params

    def apply(self, state: RenderState, *, sharpen_amount: torch.Tensor, sharpen_sigma: torch.Tensor) -> RenderState:
        return _on_difference(state, self.name, lambda d: Cx.unsharp_mask(d, sharpen_amount, sharpen_sigma,
                                                                          pad=_pad(SHARPEN_SIGMA_MAX)))


@register_effect
class Compression(Effect):
    """Block-based (JPEG) compression artefacts where the object is: ``B + Q(I) - Q(B)``.

    With the patch's place in its frame (``origin`` and the ``frame_scale``
    extra) the coding happens on the frame's 8×8 grid
    (:func:`~synthaug.effects.camera_functional.jpeg_difference_on_frame_grid`:
    the object resampled to frame resolution, coded, the error resampled
    back); with an origin alone, at frame scale 1 (phase = origin mod 8);
    else on the patch's own grid.
    Deterministic; not differentiable in the quality (quantisation steps are
    piecewise constant), gradients w.r.t. the image pass straight through.
    """

    name = "compression"
    stage = "image"
    order = 40.0
    differentiable = False  # the straight-through gradient w.r.t. the image is by design, not exact
    params = EFFECT_PARAM_SPECS["compression"]  # declared in synthaug.params

    def apply(self, state: RenderState, *, jpeg_quality: torch.Tensor) -> RenderState:
        img = _image(state, self.name)
        bg = state.background
        scale = state.extras.get("frame_scale")
        if state.origin is not None and scale is not None:  # a resampled crop: code on the frame's grid
            fs = torch.as_tensor(scale, dtype=torch.float64).reshape(-1).expand(state.batch_size)
            org = torch.as_tensor(state.origin, dtype=torch.float64).reshape(-1, 2).expand(state.batch_size, 2)
            return state.replace(image=Cx.jpeg_difference_on_frame_grid(img, bg, jpeg_quality, origin=org,
                                                                        frame_scale=fs))
        phase = block_phase(state)
        q_img = Cx.jpeg_quantize(img, jpeg_quality, phase=phase)
        q_bg = Cx.jpeg_quantize(bg, jpeg_quality, phase=phase)
        return state.replace(image=bg + (q_img - q_bg))


def block_phase(state: RenderState) -> torch.Tensor:
    """(B, 2) JPEG block phase (y, x) of each patch: ``round(origin) mod 8`` at scale 1, else 0."""
    b = state.batch_size
    phase = torch.zeros(b, 2, dtype=torch.int64)
    if state.origin is None:
        return phase
    scale = state.extras.get("frame_scale")
    scale = torch.ones(b) if scale is None else torch.as_tensor(scale, dtype=torch.float64).reshape(-1).expand(b)
    org = torch.as_tensor(state.origin, dtype=torch.float64).reshape(-1, 2).expand(b, 2)
    aligned = ((scale - 1.0).abs() < 1e-3) & ((org - org.round()).abs() < 1e-3).all(1)
    ph = torch.remainder(org.round().long(), 8).flip(1)  # (x, y) -> (y, x)
    return torch.where(aligned[:, None], ph, phase)
