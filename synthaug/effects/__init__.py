"""Capture effects: pure functions, a registry, and the composed S(Θ, B)."""

from synthaug.effects.functional import (
    boundary_blur,
    composite,
    diffuse_material,
    gaussian_blur_fft,
    motion_blur,
    object_noise,
)
from synthaug.effects.pipeline import apply_effects, sample_fields, simulate
from synthaug.effects.registry import (
    PAPER_EFFECTS,
    Effect,
    RenderState,
    get_effect,
    list_effects,
    register_effect,
)
from synthaug.effects.transform import CaptureEffects

# the built-in effects register themselves when imported: the paper's four, the
# camera candidates of the diagnosis, the material extensions
from synthaug.effects import camera, material, paper  # noqa: E402,F401  (registration)

__all__ = [
    "PAPER_EFFECTS", "Effect", "RenderState", "get_effect", "list_effects", "register_effect",
    "apply_effects", "sample_fields", "simulate", "CaptureEffects",
    "boundary_blur", "composite", "diffuse_material", "gaussian_blur_fft", "motion_blur", "object_noise",
]
