"""Effect registry: every capture effect is a named plug-in of S(Θ, B).

An effect declares its parameters (:class:`~synthaug.params.ParamSpec`; the
built-in effects' are in :data:`synthaug.params.EFFECT_PARAM_SPECS`), the
stage where it acts, an order within the stage, and an ``apply`` that maps a
:class:`RenderState` to a new one without drawing random numbers (random fields
such as noise are drawn beforehand by :meth:`Effect.sample_fields`, so that a
sample can be replayed and a fit sees a deterministic objective).

Stages, in the order :func:`synthaug.effects.simulate` runs them:

``"object"``
    act on the rendered object layer before it is overlaid (material, motion
    blur of the object over the background...). The state's ``image`` is None.
``"image"``
    act on the composite, after the object has been overlaid on the real
    background (boundary blur, object noise, camera effects...).

New effects subclass :class:`Effect` and call :func:`register_effect`; nothing
else in the pipeline changes. The built-in effects (:mod:`~synthaug.effects.paper`,
:mod:`~synthaug.effects.camera`, :mod:`~synthaug.effects.material`) register
when the :mod:`synthaug.effects` package is imported, which any import of this
module does first; this module imports none of them.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable, ClassVar, Literal

import torch

from synthaug.params import PAPER_EFFECTS, ParamSpec, declare_effect_params

__all__ = ["PAPER_EFFECTS", "Effect", "EffectFn", "RenderState", "Stage", "get_effect", "list_effects", "ordered",
           "register_effect"]

Stage = Literal["object", "image"]


@dataclass(frozen=True)
class RenderState:
    """Everything an effect may read or change, batched.

    Shape:
        - object_color: (B, C, H, W), object radiance, *not* premultiplied.
        - coverage: (B, 1, H, W), fraction of each pixel covered by the object
          (the object's alpha), in [0, 1].
        - normals: (B, 3, H, W), camera-frame unit normals (x right, y up,
          z toward the camera); zero where the object is absent.
        - background: (B, C, H, W), the real background B_i.
        - image: (B, C, H, W) composite, or None before compositing.
        - origin: (B, 2) pixel (x, y) of the patch's top-left corner in its full
          frame, and frame_size (B, 2) the frame's (W, H): position-aware effects
          (vignetting, lens distortion...) read these.
        - fields: random fields drawn by the effects' ``sample_fields``.
        - extras: layers for later effects (e.g. ``part_ids``, ``depth``).
    """

    object_color: torch.Tensor
    coverage: torch.Tensor
    normals: torch.Tensor
    background: torch.Tensor
    image: torch.Tensor | None = None
    origin: torch.Tensor | None = None
    frame_size: torch.Tensor | None = None
    fields: dict[str, torch.Tensor] = field(default_factory=dict)
    extras: dict[str, torch.Tensor] = field(default_factory=dict)

    def replace(self, **changes: object) -> "RenderState":
        return replace(self, **changes)

    @property
    def batch_size(self) -> int:
        return int(self.coverage.shape[0])


class Effect:
    """Base class of a capture effect. Subclasses set the class attributes."""

    name: ClassVar[str]
    stage: ClassVar[Stage]
    order: ClassVar[float]
    params: ClassVar[tuple[ParamSpec, ...]] = ()
    doc: ClassVar[str] = ""
    # Gradients are exact w.r.t. the parameters and the image layers (object colour, background,
    # composite), so the effect can sit in a gradient-based fit; the shared test battery
    # (tests/effect_checks.py) gradchecks every effect that keeps this True. Coverage is geometry
    # and is not part of the promise.
    differentiable: ClassVar[bool] = True

    def sample_fields(self, shape: tuple[int, int, int, int], generator: torch.Generator,
                      dtype: torch.dtype = torch.float32) -> dict[str, torch.Tensor]:
        """Random fields this effect needs, for an image batch of ``shape`` (B, C, H, W)."""
        return {}

    @property
    def is_random(self) -> bool:
        """Whether the effect draws random fields (it overrides :meth:`sample_fields`)."""
        return type(self).sample_fields is not Effect.sample_fields

    def apply(self, state: RenderState, **params: torch.Tensor) -> RenderState:  # pragma: no cover - abstract
        raise NotImplementedError


_REGISTRY: dict[str, Effect] = {}


def register_effect(cls: type[Effect]) -> type[Effect]:
    """Class decorator: instantiate and register an effect under ``cls.name``."""
    name = getattr(cls, "name", None)
    if not isinstance(name, str) or not name:
        raise ValueError(f"{cls.__name__} must define a non-empty `name`")
    if cls.stage not in ("object", "image"):
        raise ValueError(f"{cls.__name__}.stage must be 'object' or 'image', got {cls.stage!r}")
    if name in _REGISTRY and type(_REGISTRY[name]) is not cls:
        raise ValueError(f"an effect named {name!r} is already registered ({type(_REGISTRY[name]).__name__})")
    declare_effect_params(name, cls.params)  # Θ learns the effect's parameters (built-ins: already declared)
    _REGISTRY[name] = cls()
    return cls


def get_effect(name: str) -> Effect:
    try:
        return _REGISTRY[name]
    except KeyError:
        raise ValueError(f"unknown effect {name!r}; registered: {sorted(_REGISTRY)}") from None


def list_effects() -> list[str]:
    return sorted(_REGISTRY)


def ordered(names: tuple[str, ...] | list[str]) -> list[Effect]:
    """Effects sorted by (stage, order): object-stage ones first."""
    effects = [get_effect(n) for n in names]
    rank = {"object": 0, "image": 1}
    return sorted(effects, key=lambda e: (rank[e.stage], e.order, e.name))


EffectFn = Callable[..., torch.Tensor]
