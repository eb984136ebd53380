"""What the reference camera hides: the candidate effects' realistic settings and ranges, the paper's
per-seed ranges, and :func:`resolve_hidden` (a request filled in and checked) with the per-seed draw.
"""

from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

import numpy as np

import synthaug.effects.camera  # noqa: F401  (registers the candidate effects)
from synthaug.effects.camera import CAMERA_EFFECTS
from synthaug.effects.registry import get_effect


Strength = float | tuple[float, float]

# Typical settings of each candidate (a float is one value for the whole seed set,
# the camera's; a (low, high) pair is drawn per seed, for scene-dependent effects).
REALISTIC_STRENGTHS: dict[str, dict[str, Strength]] = {
    "vignetting": {"vignette_k": 0.3},
    "gamma": {"gamma_g": 0.75},
    "shot_noise": {"shot_sigma": 0.04},
    "defocus": {"defocus_sigma": 1.0},
    "compression": {"jpeg_quality": 40.0},
    "specular": {"specular_ks": (0.3, 0.6), "specular_shininess": 30.0},
    "haze": {"haze_extinction_px": 10.0, "haze_airlight": 0.85},
    "chromatic_aberration": {"ca_shift": 2.0},
    "white_balance": {"wb_gain": 0.9},
    "sharpening": {"sharpen_amount": 1.0, "sharpen_sigma": 1.0},
    "lens_distortion": {"distortion_k1": -0.15},
    "rolling_shutter": {"rs_magnitude": (0.06, 0.15)},
    "rotor_blur": {"rotor_opacity": (0.15, 0.4)},
    "exposure": {"exposure_auto": 0.5, "exposure_offset": 0.04},
    "interlacing": {"interlace_shift": (1.0, 2.0)},
    "column_pattern": {"column_gain_sd": 0.02},
}

# The realistic span of each setting (documentation, and for tests drawing strengths).
REALISTIC_RANGES: dict[str, dict[str, tuple[float, float]]] = {
    "vignetting": {"vignette_k": (0.2, 0.4)},
    "gamma": {"gamma_g": (0.7, 1.4)},
    "shot_noise": {"shot_sigma": (0.02, 0.06)},
    "defocus": {"defocus_sigma": (0.7, 1.5)},
    "compression": {"jpeg_quality": (30.0, 60.0)},
    "specular": {"specular_ks": (0.2, 0.6), "specular_shininess": (10.0, 60.0)},
    "haze": {"haze_amount": (0.1, 0.4), "haze_extinction_px": (5.0, 15.0), "haze_airlight": (0.7, 0.95)},
    "chromatic_aberration": {"ca_shift": (1.0, 3.0)},
    "white_balance": {"wb_gain": (0.8, 1.25)},
    "sharpening": {"sharpen_amount": (0.5, 1.5), "sharpen_sigma": (0.7, 1.5)},
    "lens_distortion": {"distortion_k1": (-0.2, 0.1)},
    "rolling_shutter": {"rs_magnitude": (0.05, 0.15)},
    "rotor_blur": {"rotor_opacity": (0.1, 0.5)},
    "exposure": {"exposure_gain": (0.8, 1.3), "exposure_auto": (0.3, 0.8), "exposure_offset": (-0.05, 0.05)},
    "interlacing": {"interlace_shift": (0.5, 2.5)},
    "column_pattern": {"column_gain_sd": (0.01, 0.04)},
}

# Effects the reference camera can hide that are NOT candidates of the model
# (for the "unexplained" case): interlaced fields of a moving object; a sensor's fixed column pattern (each
# frame column's gain 1 + column_gain_sd * N(0, 1), the same in every frame and background of the camera:
# column fixed-pattern noise of a CMOS read-out).
OUTSIDE_EFFECTS: tuple[str, ...] = ("interlacing", "column_pattern")

WHOLE_FRAME_EFFECTS: tuple[str, ...] = (
    "haze", "defocus", "chromatic_aberration", "lens_distortion", "vignetting", "exposure", "white_balance",
    "column_pattern", "shot_noise", "gamma", "sharpening", "compression",
)
OBJECT_ONLY_EFFECTS: tuple[str, ...] = ("specular", "rotor_blur", "rolling_shutter", "interlacing")

# Per-seed ranges of the paper's parameters, in patch pixels (σ) / intensity.
PAPER_RANGES: dict[str, tuple[float, float]] = {
    "w_d": (0.05, 0.7),
    "sigma_s": (0.3, 1.2),
    "sigma_u": (0.0, 2.0),
    "sigma_v": (0.0, 0.6),
    "alpha_m": (-math.pi / 2, math.pi / 2),
    "sigma_n": (0.0, 0.03),
}

# Settings the reference camera turns into the effect's own parameters per seed (the physics behind them);
# giving those parameters explicitly replaces the setting:
# rs_magnitude -> rs_skew/rs_stretch along the seed's motion direction; haze_extinction_px -> haze_amount
# = 1 - exp(-haze_extinction_px / object_px) (Koschmieder: a smaller object is farther, behind more air);
# exposure_auto -> exposure_gain = (AE_TARGET / mean scene brightness) ** exposure_auto (auto-exposure).
_DERIVED_PARAMS = {"rs_magnitude": ("rs_skew", "rs_stretch"), "haze_extinction_px": ("haze_amount",),
                   "exposure_auto": ("exposure_gain",)}
AE_TARGET = 0.5


def resolve_hidden(
    hidden: Mapping[str, Mapping[str, Strength]] | Sequence[str] | None,
) -> dict[str, dict[str, Strength]]:
    """Hidden effects with every setting filled in (defaults from :data:`REALISTIC_STRENGTHS`).

    Args:
        hidden: ``{effect: {param: value or (low, high)}}`` (missing params take
            their realistic default), or a list of effect names, or None.

    Returns:
        ``{effect: {param: value or (low, high)}}``, in :data:`CAMERA_EFFECTS` order.

    Example:
        >>> resolve_hidden(["defocus"])
        {'defocus': {'defocus_sigma': 1.0}}
    """
    if hidden is None:
        return {}
    if isinstance(hidden, str):
        raise ValueError(f"hidden must be a mapping or a list of effect names, got the string {hidden!r}")
    items = dict(hidden) if isinstance(hidden, Mapping) else {name: {} for name in hidden}
    known = set(CAMERA_EFFECTS) | set(OUTSIDE_EFFECTS)
    out: dict[str, dict[str, Strength]] = {}
    for name in list(CAMERA_EFFECTS) + list(OUTSIDE_EFFECTS):
        if name not in items:
            continue
        given = dict(items[name] or {})
        allowed = set(REALISTIC_STRENGTHS[name])
        if name in CAMERA_EFFECTS:
            allowed |= {s.name for s in get_effect(name).params}
        base = {k: v for k, v in REALISTIC_STRENGTHS[name].items()
                if not set(_DERIVED_PARAMS.get(k, ())) & set(given)}  # an explicit value replaces the physics
        bad = sorted(set(given) - allowed)
        if bad:
            raise ValueError(f"hidden[{name!r}]: unknown parameter(s) {bad}; known: {sorted(allowed)}")
        merged = {**base, **given}
        for k, v in merged.items():
            merged[k] = _check_strength(name, k, v)
        out[name] = merged
    unknown = sorted(set(items) - known)
    if unknown:
        raise ValueError(f"unknown hidden effect(s) {unknown}; candidates: {sorted(known)}")
    return out


def _check_strength(effect: str, name: str, v: Any) -> Strength:
    if isinstance(v, (tuple, list)):
        if len(v) != 2 or not all(math.isfinite(float(x)) for x in v) or float(v[0]) > float(v[1]):
            raise ValueError(f"hidden[{effect!r}][{name!r}] must be a number or (low, high), got {v!r}")
        lo, hi = float(v[0]), float(v[1])
        _check_in_spec(effect, name, lo)
        _check_in_spec(effect, name, hi)
        return (lo, hi)
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise ValueError(f"hidden[{effect!r}][{name!r}] must be a number or (low, high), got {v!r}") from None
    if not math.isfinite(x):
        raise ValueError(f"hidden[{effect!r}][{name!r}] must be finite, got {v!r}")
    _check_in_spec(effect, name, x)
    return x


_REFERENCE_SPECS = {"haze_extinction_px": (0.0, 100.0), "exposure_auto": (0.0, 1.5), "rs_magnitude": (-1.0, 1.0),
                    "column_gain_sd": (0.0, 0.2)}


def _check_in_spec(effect: str, name: str, x: float) -> None:
    if name in _REFERENCE_SPECS and not _REFERENCE_SPECS[name][0] <= x <= _REFERENCE_SPECS[name][1]:
        lo, hi = _REFERENCE_SPECS[name]
        raise ValueError(f"hidden[{effect!r}][{name!r}] must be in [{lo}, {hi}], got {x}")
    if effect not in CAMERA_EFFECTS:
        return
    for s in get_effect(effect).params:
        if s.name == name and not (s.low <= x <= s.high):
            raise ValueError(f"hidden[{effect!r}][{name!r}] must be in [{s.low}, {s.high}], got {x}")


def _draw_strengths(settings: dict[str, dict[str, Strength]], rng: np.random.Generator) -> dict[str, dict[str, float]]:
    out = {}
    for eff, params in settings.items():
        out[eff] = {k: (float(rng.uniform(v[0], v[1])) if isinstance(v, tuple) else float(v))
                    for k, v in sorted(params.items())}
    return out
