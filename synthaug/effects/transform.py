"""The capture effects as an augmentation for *any* image batch (issue 14, part 6).

:class:`CaptureEffects` applies the fitted capture effects of a fit file (or
effects sampled from their default ranges) to a user's own images, inside a
kornia or torchvision-v2 pipeline::

    aug = CaptureEffects("fits/drone_100_hog.json", p=0.8, generator=0)
    out = aug(images)                         # (B, C, H, W) float in [0, 1]
    draw = aug.make_params(images.shape)      # kornia's split: draw ...
    out = aug(images, params=draw)            # ... then apply (replayable)

What the effects act on
-----------------------
The paper's effects act on a *rendered object*: its coverage α and camera-frame
normals n, composited over a real background B (:func:`~synthaug.effects.simulate`:
object-stage effects on the object layer, the overlay ``o·α + B·(1 - α)``, then
the image-stage effects). A user's image has no separate object layer, so here

- ``images`` is the real image B the effects see (the background);
- ``coverage`` (optional, ``(B, 1, H, W)`` in [0, 1]: an object mask) is α.
  Without it α = 1: the whole image is the object;
- ``normals`` (optional, ``(B, 3, H, W)``) are the object's normals. Given, the
  object's colour is the default material's shading of them, exactly as in
  :func:`~synthaug.effects.simulate`, so ``forward(B, coverage=α, normals=n)``
  **is** the dataset's own S(Θ, B) (tested bit for bit against ``simulate``).
  Without them the object's colour is the image itself ("the image is the
  object layer"), and ``material`` becomes the gain ``w_d / 0.5`` of the
  object's colour: its ratio to the default material (w_d = 0.5) that
  ``simulate`` renders when ``material`` is off, so w_d = 0.5 is the identity.

On a plain image (no mask, no normals) object and background are the same
image, so: ``material`` scales the brightness (per channel); ``motion_blur``
smears the whole image (normalised blur, fading to the input within 3σ of the
border where the blur's coverage drops below 1); ``object_noise`` adds noise
everywhere; ``boundary_blur`` does nothing (there is no object boundary: give a
``coverage`` mask for it). With a mask, the object-stage effects act on the
masked object over the image, boundary blur on the mask's edge, noise on the
mask. The candidate camera effects keep their model rules: the affine ones
(haze, exposure, white balance, vignetting) and gamma act on the object's
colour / the composite, hence on the whole image without a mask; the linear
spatial ones (defocus, chromatic aberration, lens distortion, sharpening) and
compression act on ``I - B``, the change the object stage made, because the
real image already went through the camera. Effects that read the object's
shape (specular) see no normals and add nothing.

Draws
-----
:meth:`CaptureEffects.make_params` draws, per sample: whether it is augmented
(``p``), Θ (``sampling="seed"``: one fitted row at random, the paper's rule
and the dataset's default; ``"uniform"``: each capture column uniform between
its min and max over the rows, bit-identical to
``CaptureDensity(params, kind="uniform")``; ``params=None``: every parameter
uniform in its default sampling range, ``CaptureParams.sample``), and the random
fields of the random effects (``Effect.sample_fields``: ``object_noise``'s
noise, ...). ``same_on_batch=True`` makes one draw for the whole batch, random
fields included (as kornia's ``RandomGaussianNoise`` shares its noise map): a
batch of identical images gives identical outputs. All numbers come from one
CPU ``torch.Generator`` (``generator=``; None = torch's global generator), so
the same seed gives the same output. ``"kde"`` is not offered: the kernel
density (:class:`synthaug.data.density.CaptureDensity`) lives in
``synthaug.data``, which this layer must not import (render → params → effects
→ data → ...). Its draws can be passed as rows:
``CaptureEffects(dens.to_params(dens.sample(10_000, generator=g)))``.

Why not a subclass of kornia's ``AugmentationBase2D``
-----------------------------------------------------
It is a plain ``nn.Module`` with kornia's interface (``make_params`` /
``forward(images, params=None)``, ``p``, ``same_on_batch``), because the base
does not fit without overriding everything it provides:

1. the object-aware effects need per-call *layers* (``coverage``, ``normals``,
   and ``origin``/``frame_size`` for the position-aware camera effects) beside
   the image; the base's ``forward(input, params, **kwargs)`` would take them as
   overrides of the *parameters* (and record them in ``_params``), and
   ``AugmentationSequential`` gives a child only its image, routing masks
   through the geometric mask path instead;
2. the base draws its ``p`` gate and parameters from torch's global RNG on the
   module's device; here every draw comes from an explicit ``torch.Generator``
   (reproducible, the dataset's rule), so ``forward_parameters`` would be
   replaced too;
3. a draw holds a :class:`~synthaug.params.CaptureParams` and a dict of random
   fields, which the base's containers slice and deep-copy as flat per-sample
   tensors; and ``forward`` must itself handle tv_tensors, uint8 and
   torchvision-v2 ``(image, target)`` samples.

Inside ``kornia.augmentation.AugmentationSequential`` it runs as any plain
module does (the container calls it on the image and passes masks, boxes and
keypoints through); a replay with the container's ``params=`` draws anew.

Inputs
------
``(B, C, H, W)`` or ``(C, H, W)`` tensors, C = 1 or 3 (Θ is per channel, so C
must equal the fit's channel count), float in [0, 1] (float16/bfloat16 are
computed in float32; float32/float64 in their own dtype) or uint8 (divided by
255, and the result rounded back to uint8). A ``tv_tensors.Image`` (or any
tensor subclass) comes back as the same type. Anything else — a
torchvision-v2 sample such as ``(image, {"boxes": ..., "labels": ...})``, a PIL
image — goes through :class:`CaptureEffectsV2` (a thin
``torchvision.transforms.v2.Transform``): images get the effects, boxes, masks,
labels pass through unchanged, so ``v2.Compose([..., CaptureEffects(...)])``
works. Apply it before ``Normalize`` (it checks the [0, 1] range).
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Literal

import torch
from torch import nn

from synthaug.effects.pipeline import apply_effects, sample_fields, simulate
from synthaug.effects.registry import PAPER_EFFECTS, RenderState, list_effects, ordered
from synthaug.params import POSE_NAMES, CaptureParams

__all__ = ["CaptureEffects", "CaptureEffectsV2", "ParamsFileNotFoundError"]

Sampling = Literal["seed", "uniform"]

# simulate() renders the object under this diffuse weight when "material" is off
# (its default_w): the plain-image material gain is w_d relative to it.
DEFAULT_W_D = 0.5
_RANGE_TOL = 1e-3  # float images may stray this far outside [0, 1] (the dataset's tolerance)


class ParamsFileNotFoundError(FileNotFoundError, ValueError):
    """The ``params`` file does not exist (both a ``FileNotFoundError`` and a ``ValueError``)."""


def _resolve_generator(generator: torch.Generator | int | None, name: str = "generator") -> torch.Generator:
    if generator is None:
        return torch.default_generator  # torch's global CPU generator (torch.manual_seed)
    if isinstance(generator, bool) or not isinstance(generator, (int, torch.Generator)):
        raise ValueError(f"{name} must be a torch.Generator, an int seed or None, got {type(generator).__name__}")
    if isinstance(generator, int):
        return torch.Generator().manual_seed(generator)
    if generator.device.type != "cpu":
        raise ValueError(f"{name} must be a CPU torch.Generator (draws are made on the CPU and moved to the "
                         f"images' device), got one on {generator.device}")
    return generator


def _is_tv_non_image(x: Any) -> bool:
    """A torchvision tv_tensor that is not an Image (boxes, masks, keypoints, video): never augmented here."""
    tvt = sys.modules.get("torchvision.tv_tensors")
    return tvt is not None and isinstance(x, tvt.TVTensor) and not isinstance(x, tvt.Image)


class CaptureEffects(nn.Module):
    """The fitted (or sampled) capture effects S(Θ, ·) as a transform for any image batch.

    See the module docstring for what the effects act on and how Θ is drawn.

    Args:
        params: a :class:`~synthaug.params.CaptureParams` (one row per seed), the
            path of a file written by ``synthaug fit`` / ``CaptureParams.save``,
            or None: every sample draws Θ from the effects' default sampling ranges.
        effects: the effects to apply (default: all of ``params``', or the paper's
            four when ``params`` is None); leaving one out is the paper's ablation.
        p: probability that a sample is augmented (the rest pass through unchanged).
        same_on_batch: one draw (Θ, random fields, the ``p`` gate) for the whole batch.
        sampling: ``"seed"`` (each sample takes one fitted row at random) or
            ``"uniform"`` (each capture column uniform between its fitted min and max).
        generator: a CPU ``torch.Generator`` or an int seed for all draws; None
            (default) uses torch's global generator: reproducible with
            ``torch.manual_seed``, seeded per DataLoader worker by torch and per
            item by ``SyntheticObjectDataset(transforms=...)``. A fixed generator
            is copied into every worker process, which then all draw the same.
        clamp: clip the result to [0, 1], as :func:`~synthaug.effects.simulate` does.

    Example:
        >>> import torch
        >>> aug = CaptureEffects(None, generator=0)  # Θ sampled from the default ranges; or a fit file
        >>> images = torch.full((2, 1, 32, 32), 0.5)
        >>> draw = aug.make_params(images.shape)
        >>> draw["theta"].sigma_n.shape, draw["fields"]["noise"].shape
        (torch.Size([2, 1]), torch.Size([2, 1, 32, 32]))
        >>> out = aug(images, params=draw)
        >>> out.shape, out.dtype, torch.equal(out, aug(images, params=draw))
        (torch.Size([2, 1, 32, 32]), torch.float32, True)
    """

    def __init__(
        self,
        params: CaptureParams | str | os.PathLike | None = None,
        effects: Sequence[str] | str | None = None,
        *,
        p: float = 1.0,
        same_on_batch: bool = False,
        sampling: Sampling = "seed",
        generator: torch.Generator | int | None = None,
        clamp: bool = True,
    ) -> None:
        super().__init__()
        self.params: CaptureParams | None = self._load_params(params)
        self.effects: tuple[str, ...] = self._check_effects(effects, self.params)
        if isinstance(p, bool) or not isinstance(p, (int, float)) or not 0.0 <= float(p) <= 1.0:
            raise ValueError(f"p must be a probability in [0, 1], got {p!r}")
        self.p = float(p)
        self.same_on_batch = bool(same_on_batch)
        if sampling == "kde":
            raise ValueError(
                "sampling='kde' is not offered here: the kernel density (synthaug.data.density.CaptureDensity) "
                "lives in synthaug.data, which the effects layer must not import. Draw rows from it and pass "
                "them as params (CaptureEffects(dens.to_params(dens.sample(n, generator=g)))), or use "
                "sampling='seed' or 'uniform'")
        if sampling not in ("seed", "uniform"):
            raise ValueError(f"sampling must be 'seed' or 'uniform', got {sampling!r}")
        self.sampling: Sampling = sampling
        self.generator = _resolve_generator(generator)
        self.clamp = bool(clamp)
        self.channels: int | None = None if self.params is None else self.params.channels
        if self.params is not None:
            data = self.params.to_vector().double()[:, len(POSE_NAMES):]
            # the "uniform" box: CaptureDensity(kind="uniform")'s data_min / data_max
            self._capture_min, self._capture_max = data.min(0).values, data.max(0).values

    # ------------------------------------------------------------ set-up
    @staticmethod
    def _load_params(params: Any) -> CaptureParams | None:
        if params is None or isinstance(params, CaptureParams):
            return params
        if isinstance(params, (str, os.PathLike)):
            path = Path(params)
            if not path.is_file():
                raise ParamsFileNotFoundError(
                    f"params: capture-parameter file not found: {path} (write one with `synthaug fit` or "
                    f"CaptureParams.save)")
            try:
                return CaptureParams.load(path)
            except ValueError as e:
                raise ValueError(f"params: {e}") from None
        raise ValueError(f"params must be a CaptureParams, the path of a fit file or None, "
                         f"got {type(params).__name__}")

    @staticmethod
    def _check_effects(effects: Sequence[str] | str | None, params: CaptureParams | None) -> tuple[str, ...]:
        if effects is None:
            return tuple(PAPER_EFFECTS if params is None else params.effects)
        names = (effects,) if isinstance(effects, str) else tuple(effects)
        if not all(isinstance(n, str) for n in names):
            raise ValueError(f"effects must be effect names (strings), got {list(names)!r}")
        registered = list_effects()
        unknown = [n for n in names if n not in registered]
        if unknown:
            raise ValueError(f"effects: unknown effect(s) {unknown}; registered: {registered}")
        if len(set(names)) != len(names):
            raise ValueError(f"effects: each effect may be named once, got {list(names)}")
        if params is not None:
            missing = [n for n in names if n not in params.effects]
            if missing:
                raise ValueError(f"effects: params hold no parameters for {missing} (they have {list(params.effects)})")
        return names

    def _check_channels(self, c: int, where: str) -> None:
        if self.params is not None and c != self.params.channels:
            raise ValueError(f"{where}: the images have {c} channel(s) but params were fitted for "
                             f"{self.params.channels} (capture parameters are per channel: use "
                             f"{self.params.channels}-channel images or params fitted for {c})")
        if c not in (1, 3):
            raise ValueError(f"{where}: images must have 1 or 3 channels (capture parameters are per channel), "
                             f"got {c}")

    def extra_repr(self) -> str:
        src = "sampled" if self.params is None else f"{self.params.batch_size} fitted rows, {self.sampling}"
        return f"effects={list(self.effects)}, params={src}, p={self.p}, same_on_batch={self.same_on_batch}"

    # -------------------------------------------------------------- draws
    def make_params(self, batch_shape: Sequence[int] | torch.Size,
                    generator: torch.Generator | int | None = None) -> dict[str, Any]:
        """Draw the per-sample parameters for an image batch of ``batch_shape`` (B, C, H, W).

        Args:
            batch_shape: (B, C, H, W) of the batch (C must match the params' channels).
            generator: overrides the module's generator for this draw.

        Returns:
            ``{"batch_shape": torch.Size, "apply": (B,) bool (the p gate), "row": (B,)
            int64 (the fitted row each sample took; -1 when Θ was not a row),
            "theta": CaptureParams with B rows, "fields": {name: tensor} random
            fields, (B, ...)}``. Pass it to :meth:`forward` as ``params=`` to apply
            (or replay) exactly this draw. Draw order from the generator: the p
            gate, then Θ, then the fields in the effects' order.
        """
        shape = tuple(int(s) for s in batch_shape)
        if len(shape) != 4 or min(shape) < 1:
            raise ValueError(f"batch_shape must be (B, C, H, W) with every size >= 1, got {tuple(batch_shape)}")
        b, c, h, w = shape
        self._check_channels(c, "batch_shape")
        g = self.generator if generator is None else _resolve_generator(generator)
        n = 1 if self.same_on_batch else b
        apply = torch.rand(n, generator=g, dtype=torch.float64) < self.p
        row = torch.full((n,), -1, dtype=torch.int64)
        if self.params is None:
            theta = CaptureParams.sample(n, generator=g, channels=c, effects=self.effects)
        elif self.sampling == "seed":
            row = torch.randint(self.params.batch_size, (n,), generator=g)
            theta = self.params[row]
        else:  # uniform in the fitted box, as CaptureDensity(kind="uniform").sample + to_params
            lo, hi = self._capture_min, self._capture_max
            u = torch.rand(n, lo.shape[0], generator=g, dtype=torch.float64)
            capture = lo + (hi - lo) * u
            theta = CaptureParams.from_vector(torch.cat([torch.zeros(n, len(POSE_NAMES), dtype=torch.float64),
                                                         capture], 1),
                                              channels=self.params.channels, effects=self.params.effects,
                                              validate=False)
        fields = sample_fields(self.effects, (n, c, h, w), g)
        if n != b:  # same_on_batch: one draw shared by every sample
            apply = apply.expand(b)
            row = row.expand(b)
            theta = theta[torch.zeros(b, dtype=torch.int64)]
            fields = {k: v.expand(b, *v.shape[1:]) for k, v in fields.items()}
        return {"batch_shape": torch.Size(shape), "apply": apply, "row": row, "theta": theta, "fields": fields}

    # ------------------------------------------------------------ forward
    def forward(
        self,
        *inputs: Any,
        params: Mapping[str, Any] | None = None,
        coverage: torch.Tensor | None = None,
        normals: torch.Tensor | None = None,
        origin: torch.Tensor | None = None,
        frame_size: torch.Tensor | None = None,
        extras: Mapping[str, torch.Tensor] | None = None,
    ) -> Any:
        """Apply the effects to an image batch (or pass a torchvision-v2 sample through :class:`CaptureEffectsV2`).

        Args:
            inputs: one ``(B, C, H, W)`` / ``(C, H, W)`` image tensor (or
                ``tv_tensors.Image``); anything else (an ``(image, target)`` sample,
                a dict, a PIL image) is handled as a torchvision-v2 transform.
            params: a draw from :meth:`make_params` (drawn here if None; also
                accepted positionally, kornia's ``forward(input, params)``). Only
                ``"theta"`` (a CaptureParams with B rows) and, for random effects,
                ``"fields"`` are required; ``"apply"`` defaults to all samples.
            coverage: (B, 1, H, W) object coverage / mask in [0, 1] (bool allowed);
                None: the whole image is the object.
            normals: (B, 3, H, W) camera-frame object normals: the object's colour
                is then the default material's shading, as in ``simulate``.
            origin, frame_size: (B, 2) the image's place in its frame, for the
                position-aware camera effects (see ``RenderState``).
            extras: further per-sample layers for effects (``RenderState.extras``).

        Returns:
            the augmented images, same shape, dtype and tensor type as the input.
        """
        if (len(inputs) == 2 and params is None and isinstance(inputs[1], Mapping)
                and isinstance(inputs[1].get("theta"), CaptureParams)):  # kornia's positional forward(input, params)
            inputs, params = inputs[:1], inputs[1]
        if len(inputs) == 1 and isinstance(inputs[0], torch.Tensor) and not _is_tv_non_image(inputs[0]):
            return self._forward_tensor(inputs[0], params, coverage=coverage, normals=normals, origin=origin,
                                        frame_size=frame_size, extras=extras)
        if not inputs:
            raise ValueError("CaptureEffects needs images: call it as aug(images)")
        given = [k for k, v in dict(params=params, coverage=coverage, normals=normals, origin=origin,
                                    frame_size=frame_size, extras=extras).items() if v is not None]
        if given:
            raise ValueError(f"{', '.join(given)} apply to one image tensor (aug(images, {given[0]}=...)), not to a "
                             f"structured torchvision-v2 sample")
        return self.as_v2()(*inputs)

    def as_v2(self) -> nn.Module:
        """This module as a ``torchvision.transforms.v2.Transform`` (shares its settings and generator)."""
        v2 = self.__dict__.get("_v2")
        if v2 is None:
            v2 = _v2_class()(self)
            self.__dict__["_v2"] = v2  # not a registered child: the wrapper holds this module, not the reverse
        return v2

    def _forward_tensor(self, images: torch.Tensor, params: Mapping[str, Any] | None, *,
                        coverage: torch.Tensor | None = None, normals: torch.Tensor | None = None,
                        origin: torch.Tensor | None = None, frame_size: torch.Tensor | None = None,
                        extras: Mapping[str, torch.Tensor] | None = None) -> torch.Tensor:
        out_type = type(images)
        x = images.as_subclass(torch.Tensor) if out_type is not torch.Tensor else images
        if x.ndim not in (3, 4):
            raise ValueError(f"images must be (B, C, H, W) or (C, H, W), got shape {tuple(x.shape)}")
        unbatched = x.ndim == 3
        xb = x[None] if unbatched else x
        xf = _to_float(xb)
        b, c, h, w = xf.shape
        self._check_channels(c, "images")
        if b == 0:
            out = xb.clone()
            return (out[0] if unbatched else out).as_subclass(out_type)
        if params is None:
            params = self.make_params(xf.shape)
        theta, fields, apply = self._check_draw(params, (b, c, h, w))
        cov = _layer(coverage, "coverage", (b, 1, h, w), unbatched, xf)
        nrm = _layer(normals, "normals", (b, 3, h, w), unbatched, xf)
        geo = {"origin": _per_sample(origin, "origin", b, unbatched, 2),
               "frame_size": _per_sample(frame_size, "frame_size", b, unbatched, 2)}
        ext = {k: (v[None] if unbatched and isinstance(v, torch.Tensor) else v) for k, v in dict(extras or {}).items()}
        if not bool(apply.any()):
            out = xb.clone()
        elif bool(apply.all()):
            out = _from_float(self._apply(xf, theta, fields, cov, nrm, geo, ext), xb.dtype)
        else:
            idx = torch.nonzero(apply).flatten()
            sel = lambda t: None if t is None else t[idx.to(t.device)]  # noqa: E731
            res = self._apply(sel(xf), theta[idx], {k: v[idx] for k, v in fields.items()}, sel(cov), sel(nrm),
                              {k: sel(v) for k, v in geo.items()},
                              {k: (sel(v) if isinstance(v, torch.Tensor) and v.ndim and v.shape[0] == b else v)
                               for k, v in ext.items()})
            out = xb.clone()
            out[idx.to(out.device)] = _from_float(res, xb.dtype)
        if unbatched:
            out = out[0]
        return out.as_subclass(out_type) if out_type is not torch.Tensor else out

    def _check_draw(self, params: Mapping[str, Any], shape: tuple[int, int, int, int]
                    ) -> tuple[CaptureParams, dict[str, torch.Tensor], torch.Tensor]:
        b = shape[0]
        if not isinstance(params, Mapping) or "theta" not in params:
            raise ValueError("params must be a draw of make_params (a dict with 'theta', 'fields', 'apply')")
        drawn = params.get("batch_shape")
        if drawn is not None and tuple(drawn) != tuple(shape):
            raise ValueError(f"params were drawn for a batch of shape {tuple(drawn)}, the images are {shape}")
        theta = params["theta"]
        if not isinstance(theta, CaptureParams):
            raise ValueError(f"params['theta'] must be a CaptureParams, got {type(theta).__name__}")
        if theta.batch_size != b:
            raise ValueError(f"params['theta'] has {theta.batch_size} rows but the batch has {b} images")
        if theta.channels != shape[1]:
            raise ValueError(f"params['theta'] has {theta.channels} channel(s) but the images have {shape[1]}")
        missing = [n for n in self.effects if n not in theta.effects]
        if missing:
            raise ValueError(f"params['theta'] holds no parameters for effect(s) {missing}")
        fields = dict(params.get("fields") or {})  # a missing field: the effect itself names it
        apply = params.get("apply")
        apply = torch.ones(b, dtype=torch.bool) if apply is None else torch.as_tensor(apply).to("cpu", torch.bool)
        if tuple(apply.shape) != (b,):
            raise ValueError(f"params['apply'] must have shape ({b},), got {tuple(apply.shape)}")
        return theta, fields, apply

    def _apply(self, x: torch.Tensor, theta: CaptureParams, fields: dict[str, torch.Tensor],
               coverage: torch.Tensor | None, normals: torch.Tensor | None,
               geo: dict[str, torch.Tensor | None], extras: dict[str, Any]) -> torch.Tensor:
        """S(Θ, x) on float images of the samples to augment."""
        b, c, h, w = x.shape
        theta = theta.to(x.device)
        fields = {k: v.to(device=x.device, dtype=x.dtype) for k, v in fields.items()}
        cov = torch.ones(b, 1, h, w, dtype=x.dtype, device=x.device) if coverage is None else coverage
        if normals is not None:  # a rendered object over the image: exactly the dataset's S(Θ, B)
            return simulate(cov, normals, x, theta, effects=self.effects, fields=fields, extras=extras,
                            clamp=self.clamp, **geo)
        names = list(self.effects)
        color = x  # the image is the object's colour (and the background behind it)
        if "material" in names:
            first = ordered(names)[0]
            if first.name != "material":  # the gain stands in for an effect that replaces the colour first
                raise RuntimeError(f"effect {first.name!r} runs before 'material'; the plain-image material gain "
                                   f"assumes material is the first effect")
            w_d = theta.w_d.to(device=x.device, dtype=x.dtype)
            color = x * (w_d / DEFAULT_W_D)[..., None, None]
            names.remove("material")
        state = RenderState(object_color=color, coverage=cov, normals=torch.zeros(b, 3, h, w, dtype=x.dtype,
                                                                                  device=x.device),
                            background=x, fields=fields, extras=dict(extras), **geo)
        return apply_effects(state, theta, names, clamp=self.clamp).image


# ------------------------------------------------------------------ helpers
def _to_float(x: torch.Tensor) -> torch.Tensor:
    if x.dtype == torch.uint8:
        return x.float() / 255.0
    if x.dtype in (torch.float16, torch.bfloat16):
        x = x.float()
    elif x.dtype not in (torch.float32, torch.float64):
        raise ValueError(f"images: unsupported dtype {x.dtype} (use float in [0, 1] or uint8)")
    if x.numel():
        lo, hi = torch.aminmax(x.detach())
        if not (math.isfinite(float(lo)) and math.isfinite(float(hi))) or lo < -_RANGE_TOL or hi > 1 + _RANGE_TOL:
            raise ValueError(f"images: float images must be finite and in [0, 1], got values in "
                             f"[{float(lo):.4g}, {float(hi):.4g}] (apply CaptureEffects before Normalize)")
    return x


def _from_float(x: torch.Tensor, dtype: torch.dtype) -> torch.Tensor:
    if dtype == torch.uint8:
        return (x * 255.0).round_().clamp_(0, 255).to(torch.uint8)
    return x.to(dtype)


def _layer(t: torch.Tensor | None, name: str, shape: tuple[int, int, int, int], unbatched: bool,
           ref: torch.Tensor) -> torch.Tensor | None:
    if t is None:
        return None
    if not isinstance(t, torch.Tensor):
        raise ValueError(f"{name} must be a tensor of shape {shape}, got {type(t).__name__}")
    t = t.as_subclass(torch.Tensor) if type(t) is not torch.Tensor else t
    if unbatched:
        t = t[None]
    if name == "coverage" and t.ndim == 3:  # (B, H, W) mask
        t = t[:, None]
    if tuple(t.shape) != shape:
        raise ValueError(f"{name} must have shape {shape} (batched like the images), got {tuple(t.shape)}")
    if t.dtype == torch.bool:
        t = t.to(ref.dtype)
    elif not t.is_floating_point():
        raise ValueError(f"{name} must be float (or a bool mask), got {t.dtype}")
    if name == "coverage" and t.numel():
        lo, hi = torch.aminmax(t.detach())
        if lo < 0 or hi > 1 or not math.isfinite(float(lo + hi)):
            raise ValueError(f"coverage must be in [0, 1], got values in [{float(lo):.4g}, {float(hi):.4g}]")
    return t.to(device=ref.device, dtype=ref.dtype)


def _per_sample(t: Any, name: str, b: int, unbatched: bool, width: int) -> torch.Tensor | None:
    if t is None:
        return None
    t = torch.as_tensor(t, dtype=torch.float32)
    if unbatched or t.ndim == 1:
        t = t.reshape(1, -1).expand(b, -1)
    if tuple(t.shape) != (b, width):
        raise ValueError(f"{name} must have shape ({b}, {width}), got {tuple(t.shape)}")
    return t


# ------------------------------------------------------- torchvision v2
_V2_CLASS: type | None = None


def _v2_class() -> type:
    """Build :class:`CaptureEffectsV2` on first use (importing torchvision only then)."""
    global _V2_CLASS
    if _V2_CLASS is not None:
        return _V2_CLASS
    import PIL.Image
    from torchvision import tv_tensors
    from torchvision.transforms import v2
    from torchvision.transforms.v2 import functional as TF

    def _pure_tensor(x: Any) -> bool:
        return type(x) is torch.Tensor  # noqa: E721  (v2's rule: a plain tensor is an image if no Image is present)

    class CaptureEffectsV2(v2.Transform):
        """Torchvision-v2 face of :class:`CaptureEffects`: images get the capture effects, the rest passes through.

        Transformed: ``tv_tensors.Image`` (kept as Image), a plain tensor when the
        sample holds no Image (v2's rule), PIL images (mode ``L`` or ``RGB``,
        converted to uint8 and back). Bounding boxes, masks, keypoints, labels
        and any other entry (videos included) are returned unchanged. Build it from a
        :class:`CaptureEffects` or from CaptureEffects' arguments.
        """

        _transformed_types = (tv_tensors.Image, _pure_tensor, PIL.Image.Image)

        def __init__(self, *args: Any, **kwargs: Any) -> None:
            super().__init__()
            if len(args) == 1 and not kwargs and isinstance(args[0], CaptureEffects):
                self.capture = args[0]
            else:
                self.capture = CaptureEffects(*args, **kwargs)

        def make_params(self, flat_inputs: list[Any]) -> dict[str, Any]:
            draws = []
            for inpt in flat_inputs:
                if isinstance(inpt, PIL.Image.Image):
                    shape = (1, len(inpt.getbands()), inpt.height, inpt.width)
                else:
                    shape = tuple(inpt.shape) if inpt.ndim == 4 else (1, *inpt.shape)
                draws.append((inpt, self.capture.make_params(shape)))
            return {"draws": draws}

        def transform(self, inpt: Any, params: dict[str, Any]) -> Any:
            draw = next(d for obj, d in params["draws"] if obj is inpt)
            if isinstance(inpt, PIL.Image.Image):
                if inpt.mode not in ("L", "RGB"):
                    raise ValueError(f"images: PIL images must be mode 'L' or 'RGB', got {inpt.mode!r}")
                return TF.to_pil_image(self.capture._forward_tensor(TF.pil_to_tensor(inpt), draw))
            return self.capture._forward_tensor(inpt, draw)  # keeps (C, H, W) / (B, C, H, W) and the type

        # the names torchvision < 0.21 calls
        _get_params = make_params
        _transform = transform

    CaptureEffectsV2.__module__ = __name__
    _V2_CLASS = CaptureEffectsV2
    return CaptureEffectsV2


def __getattr__(name: str) -> Any:
    if name == "CaptureEffectsV2":
        return _v2_class()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
