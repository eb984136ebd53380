"""Material extensions of the paper's Lambertian material (issue 6: the model side of the diagnosis).

=================  ======  ==========================================  =========================================
name               stage   parameters                                  meaning
=================  ======  ==========================================  =========================================
object_texture     object  a (texture_amp), ℓ (texture_scale, px)      spatially correlated albedo variation
=================  ======  ==========================================  =========================================

``object_texture`` multiplies the object's colour by ``1 + a · F_ℓ``, where
``F_ℓ`` is a unit-variance Gaussian random field: white noise smoothed with a
Gaussian of standard deviation ℓ px and divided by its exact (discrete)
standard deviation, so its autocorrelation is exp(-d² / (4ℓ²)). The field is
fixed on the object layer (it acts before motion blur, which then smears it
with the object) and the result is clamped to [0, 1]. It is the small-scale
structure and contrast that the diagnosis found the coarse meshes lack (the
HOG fits fill it with i.i.d. object noise at its bound).

The white noise is drawn by :meth:`ObjectTexture.sample_fields` from a child
generator *derived* from the given one (a hash of its state): the caller's
generator is not advanced, so adding ``object_texture`` to a set of effects
leaves every other effect's random fields unchanged (a base fit and its
extension see the same object noise; a synthetic set with and without the
texture has the same poses, backgrounds and noise).
"""

from __future__ import annotations

import hashlib
import math

import torch

from synthaug.effects import functional as Fx
from synthaug.effects.registry import Effect, RenderState, register_effect
from synthaug.params import EFFECT_PARAM_SPECS, TEXTURE_SCALE_MAX, TEXTURE_SCALE_MIN  # noqa: F401  (re-exported)

__all__ = ["ObjectTexture", "texture_field", "TEXTURE_SCALE_MAX", "TEXTURE_PAD"]

# white-noise margin on each side of the patch: the smoothed field at a patch pixel sees all the noise
# within 4ℓ_max of it (kernel weight beyond is < exp(-8))
TEXTURE_PAD = int(math.ceil(4.0 * TEXTURE_SCALE_MAX))


def _child_generator(generator: torch.Generator) -> torch.Generator:
    """A generator seeded by a hash of ``generator``'s state (which is left as it is)."""
    if not isinstance(generator, torch.Generator):
        raise ValueError(f"generator must be a torch.Generator, got {type(generator).__name__}")
    state = generator.get_state().numpy().tobytes()
    seed = int.from_bytes(hashlib.sha256(b"object_texture" + state).digest()[:8], "little") & (2 ** 63 - 1)
    return torch.Generator().manual_seed(seed)


def texture_field(white: torch.Tensor, scale: torch.Tensor, size: tuple[int, int]) -> torch.Tensor:
    """Unit-variance Gaussian random field of correlation std ``scale`` from padded white noise.

    Args:
        white: (B, 1, H + 2P, W + 2P) i.i.d. N(0, 1) noise, P = :data:`TEXTURE_PAD`.
        scale: (B, C) or (B,) smoothing std ℓ in px, in [TEXTURE_SCALE_MIN, TEXTURE_SCALE_MAX].
        size: (H, W) of the field to return.

    Returns:
        (B, C, H, W) field F = (white * G_ℓ) / std, whose autocorrelation is exp(-d² / (4ℓ²)) (exactly
        that of the discrete blur; differentiable in ``scale``).
    """
    h, w = int(size[0]), int(size[1])
    if white.ndim != 4 or white.shape[1] != 1:
        raise ValueError(f"texture field must be (B, 1, H, W), got {tuple(white.shape)}")
    if white.shape[-2] < h + 2 * TEXTURE_PAD or white.shape[-1] < w + 2 * TEXTURE_PAD:
        raise ValueError(f"texture field {tuple(white.shape[-2:])} is too small for a {h}×{w} patch "
                         f"(needs {h + 2 * TEXTURE_PAD}×{w + 2 * TEXTURE_PAD}): draw it with sample_fields "
                         "for this image size")
    b = white.shape[0]
    scale = torch.as_tensor(scale, dtype=white.dtype)
    if scale.ndim == 1:
        scale = scale[:, None]
    if scale.ndim != 2 or scale.shape[0] != b:
        raise ValueError(f"texture_scale must be (B,) or (B, C) with B = {b}, got {tuple(scale.shape)}")
    c = scale.shape[1]
    if b == 0:  # nothing to smooth (an FFT of an empty batch is an error)
        return white.new_zeros((0, c, h, w))
    # the centre crop of the padded field: every pixel has ≥ P px of noise on each side
    oy = (white.shape[-2] - h) // 2
    ox = (white.shape[-1] - w) // 2
    src = white[:, :, oy - TEXTURE_PAD:oy + h + TEXTURE_PAD, ox - TEXTURE_PAD:ox + w + TEXTURE_PAD]
    src = src.expand(b, c, *src.shape[-2:])
    blurred = Fx.gaussian_blur_fft(src, scale, pad=0)[..., TEXTURE_PAD:TEXTURE_PAD + h, TEXTURE_PAD:TEXTURE_PAD + w]
    # exact variance of the blurred unit white noise: Σ k² of the (circular) kernel on the FFT grid
    hp, wp = Fx.next_fast_len(src.shape[-2]), Fx.next_fast_len(src.shape[-1])
    kernel = torch.fft.irfft2(Fx.gaussian_transfer(hp, wp, scale, scale, torch.zeros_like(scale)), s=(hp, wp))
    std = kernel.square().sum(dim=(-2, -1)).sqrt()
    return blurred / std[..., None, None]


@register_effect
class ObjectTexture(Effect):
    """Spatially correlated albedo variation fixed on the object: colour *= 1 + a · F_ℓ, clamped to [0, 1]."""

    name = "object_texture"
    stage = "object"
    order = 5.0  # after the material (0), before motion blur (10)
    params = EFFECT_PARAM_SPECS["object_texture"]  # declared in synthaug.params

    def sample_fields(self, shape, generator, dtype=torch.float32):
        b, _, h, w = shape
        g = _child_generator(generator)
        return {"texture": torch.randn((b, 1, h + 2 * TEXTURE_PAD, w + 2 * TEXTURE_PAD), generator=g, dtype=dtype)}

    def apply(self, state: RenderState, *, texture_amp: torch.Tensor, texture_scale: torch.Tensor) -> RenderState:
        white = state.fields.get("texture")
        if white is None:
            raise ValueError("object_texture needs a 'texture' field: draw it with sample_fields(...)")
        color = state.object_color
        field = texture_field(white.to(color.dtype), texture_scale.to(color.dtype), tuple(color.shape[-2:]))
        amp = texture_amp.to(color.dtype)
        amp = amp[:, None] if amp.ndim == 1 else amp
        color = (color * (1.0 + amp[..., None, None] * field)).clamp(0.0, 1.0)
        return state.replace(object_color=color)
