"""The paper's four capture effects (Rozantsev et al. 2015, Sec. 3), registered.

=============  =====  ======================================  ======================
name           stage  parameters                              paper
=============  =====  ======================================  ======================
material       object w_d (diffuse weight)                    MP
motion_blur    object σ_u, σ_v (px), α_m (rad)                MB
boundary_blur  image  σ_s (px)                                BB
object_noise   image  σ_n (intensity, image in [0, 1])        RN
=============  =====  ======================================  ======================
"""

from __future__ import annotations

import math

import torch

from synthaug.effects import functional as Fx
from synthaug.effects.registry import Effect, RenderState, register_effect
from synthaug.params import EFFECT_PARAM_SPECS, SIGMA_M_MAX, SIGMA_N_MAX, SIGMA_S_MAX  # noqa: F401  (re-exported)

# the σ ranges (SIGMA_*_MAX, px) are declared with the parameters in synthaug.params; the blur padding follows them
DEFAULT_LIGHT = (0.0, 0.5, 0.8660254)  # toward the light: from above, in front


def _pad(sigma_max: float) -> int:
    return int(math.ceil(3.0 * sigma_max))


@register_effect
class Material(Effect):
    """MP — diffuse reflection weight w_d: object intensity (colour per channel) and Lambert shading."""

    name = "material"
    stage = "object"
    order = 0.0
    ambient = 0.4
    params = EFFECT_PARAM_SPECS["material"]  # declared in synthaug.params

    def apply(self, state: RenderState, *, w_d: torch.Tensor) -> RenderState:
        light = state.extras.get("light_dir", torch.tensor(DEFAULT_LIGHT))
        color = Fx.diffuse_material(state.normals, state.coverage, w_d, light_dir=light, ambient=self.ambient)
        return state.replace(object_color=color)


@register_effect
class MotionBlur(Effect):
    """MB — anisotropic Gaussian (σ_u, σ_v) at angle α_m on the object, smearing it over the background."""

    name = "motion_blur"
    stage = "object"
    order = 10.0
    params = EFFECT_PARAM_SPECS["motion_blur"]  # declared in synthaug.params

    def apply(self, state: RenderState, *, sigma_u: torch.Tensor, sigma_v: torch.Tensor,
              alpha_m: torch.Tensor) -> RenderState:
        color, cov = Fx.motion_blur(state.object_color, state.coverage, sigma_u, sigma_v, alpha_m,
                                    pad=_pad(SIGMA_M_MAX))
        return state.replace(object_color=color, coverage=cov)


@register_effect
class BoundaryBlur(Effect):
    """BB — Gaussian σ_s along the object boundary, after the overlay on the background."""

    name = "boundary_blur"
    stage = "image"
    order = 10.0
    params = EFFECT_PARAM_SPECS["boundary_blur"]  # declared in synthaug.params

    def apply(self, state: RenderState, *, sigma_s: torch.Tensor) -> RenderState:
        assert state.image is not None
        return state.replace(image=Fx.boundary_blur(state.image, state.coverage, sigma_s, pad=_pad(SIGMA_S_MAX)))


@register_effect
class ObjectNoise(Effect):
    """RN — Gaussian noise σ_n on the object's pixels only (the background is real)."""

    name = "object_noise"
    stage = "image"
    order = 20.0
    params = EFFECT_PARAM_SPECS["object_noise"]  # declared in synthaug.params

    def sample_fields(self, shape, generator, dtype=torch.float32):
        return {"noise": torch.randn(shape, generator=generator, dtype=dtype)}

    def apply(self, state: RenderState, *, sigma_n: torch.Tensor) -> RenderState:
        assert state.image is not None
        noise = state.fields.get("noise")
        if noise is None:
            raise ValueError("object_noise needs a 'noise' field: draw it with sample_fields(...)")
        return state.replace(image=Fx.object_noise(state.image, state.coverage, sigma_n, noise))
