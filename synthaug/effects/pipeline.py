"""S(Θ, B): compose the registered effects into one synthetic image."""

from __future__ import annotations

from typing import Sequence

import torch

from synthaug.effects import functional as Fx
from synthaug.effects.registry import RenderState, get_effect, ordered
from synthaug.params import CaptureParams

__all__ = ["sample_fields", "apply_effects", "simulate"]


def sample_fields(effects: Sequence[str], shape: tuple[int, int, int, int], generator: torch.Generator,
                  dtype: torch.dtype = torch.float32) -> dict[str, torch.Tensor]:
    """Draw every random field the ``effects`` need, for an image batch of ``shape``."""
    fields: dict[str, torch.Tensor] = {}
    for eff in ordered(list(effects)):
        for k, v in eff.sample_fields(shape, generator, dtype).items():
            if k in fields:
                raise ValueError(f"random field {k!r} is drawn by two effects")
            fields[k] = v
    return fields


def apply_effects(state: RenderState, theta: CaptureParams, effects: Sequence[str] | None = None,
                  *, clamp: bool = True) -> RenderState:
    """Run the object-stage effects, overlay on the background, run the image-stage effects.

    Args:
        state: layers from the renderer; ``object_color`` holds the object under
            the default material (used as is when ``material`` is off).
        theta: Θ; must hold the parameters of every effect in ``effects``.
        effects: names to apply (default: all effects of ``theta``). Leaving one
            out is the paper's ablation: the effect is skipped, not zeroed.
        clamp: clip the final image to [0, 1] (a camera saturates).

    Returns:
        the final state; ``state.image`` is the synthetic image S(Θ, B).
    """
    names = list(theta.effects if effects is None else effects)
    missing = [n for n in names if n not in theta.effects]
    if missing:
        raise ValueError(f"theta holds no parameters for effect(s) {missing}; it has {list(theta.effects)}")
    if theta.batch_size != state.batch_size:
        raise ValueError(f"theta has batch {theta.batch_size} but the layers have {state.batch_size}")
    values = theta.as_dict()
    composited = False
    for eff in ordered(names):
        if eff.stage == "image" and not composited:
            state = state.replace(image=Fx.composite(state.object_color, state.coverage, state.background))
            composited = True
        params = {s.name: values[s.name].to(state.background.dtype) for s in eff.params}
        state = eff.apply(state, **params)
    if not composited:
        state = state.replace(image=Fx.composite(state.object_color, state.coverage, state.background))
    if clamp:
        state = state.replace(image=state.image.clamp(0.0, 1.0))
    return state


def simulate(
    coverage: torch.Tensor,
    normals: torch.Tensor,
    background: torch.Tensor,
    theta: CaptureParams,
    *,
    effects: Sequence[str] | None = None,
    fields: dict[str, torch.Tensor] | None = None,
    generator: torch.Generator | None = None,
    origin: torch.Tensor | None = None,
    frame_size: torch.Tensor | None = None,
    extras: dict[str, torch.Tensor] | None = None,
    clamp: bool = True,
) -> torch.Tensor:
    """S(Θ, B) from rendered layers: the composite image after all effects.

    Args:
        coverage: (B, 1, H, W) object coverage for Θ's pose (from a renderer).
        normals: (B, 3, H, W) camera-frame normals for Θ's pose.
        background: (B, C, H, W) real background in [0, 1]; C = theta.channels.
        theta: Θ (pose already used by the renderer; capture parameters here).
        effects: subset of theta's effects to apply (ablation).
        fields: random fields (e.g. ``noise``); drawn from ``generator`` if None.
        generator: needed when ``fields`` is None and an effect is random.

    Returns:
        (B, C, H, W) synthetic image.
    """
    if background.ndim != 4:
        raise ValueError(f"background must be (B, C, H, W), got {tuple(background.shape)}")
    if background.shape[1] != theta.channels:
        raise ValueError(f"background has {background.shape[1]} channels but theta has {theta.channels}")
    if coverage.shape[-2:] != background.shape[-2:]:
        raise ValueError(f"layers {tuple(coverage.shape[-2:])} and background {tuple(background.shape[-2:])} differ in size")
    names = list(theta.effects if effects is None else effects)
    if fields is None:
        needs = any(get_effect(n).is_random for n in names)
        if needs and generator is None:
            raise ValueError("these effects draw random fields: pass `fields` or a `generator`")
        fields = sample_fields(names, tuple(background.shape), generator) if needs else {}
    if ordered(names)[:1] == [get_effect("material")]:
        # the material effect runs first and replaces the object colour: skip the default one
        color = torch.zeros((), dtype=background.dtype).expand_as(background)
    else:
        default_w = torch.full((background.shape[0], theta.channels), 0.5, dtype=background.dtype)
        color = Fx.diffuse_material(normals, coverage, default_w)
    state = RenderState(object_color=color, coverage=coverage, normals=normals, background=background,
                        origin=origin, frame_size=frame_size, fields=fields, extras=dict(extras or {}))
    return apply_effects(state, theta, names, clamp=clamp).image
