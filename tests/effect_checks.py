"""``check_effect``: the checks every registered capture effect must pass (issue 17).

An effect's ``apply`` maps a :class:`~synthaug.effects.registry.RenderState` to a
new one; the battery builds a small random state for the effect's stage (an
``image`` for image-stage effects, none for object-stage ones), draws the
effect's random fields and parameters in their sampling ranges, and checks:

- no input is modified in place (state tensors, fields, extras, parameters);
- a batch gives what its items give one by one;
- an empty batch gives an empty batch;
- the dtype (float32 and float64) is kept;
- gradients are right (``torch.autograd.gradcheck`` w.r.t. the parameters and
  the image layers: object colour, background, composite) where the effect
  declares ``differentiable = True`` (:class:`~synthaug.effects.registry.Effect`'s
  default). Coverage is geometry and is left out: measured, ``material``,
  ``motion_blur``, ``rolling_shutter`` and ``rotor_blur`` are not exactly
  differentiable in it (thresholds, a ``no_grad`` rotor weight).

``tests/test_effect_checks.py`` runs it over every registered effect; a new
effect is checked by being registered.
"""

from __future__ import annotations

import torch

from synthaug.effects.registry import Effect, RenderState, get_effect

OUTPUTS = ("object_color", "coverage", "image")


def make_state(effect: Effect, batch: int, channels: int, size: int, dtype: torch.dtype,
               seed: int = 0) -> tuple[RenderState, dict[str, torch.Tensor]]:
    """A random state for ``effect``'s stage and parameters drawn in their sampling ranges."""
    g = torch.Generator().manual_seed(seed)
    shape = (batch, channels, size, size)
    yy, xx = torch.meshgrid(torch.linspace(-1, 1, size, dtype=torch.float64),
                            torch.linspace(-1, 1, size, dtype=torch.float64), indexing="ij")
    blob = (1.0 - (xx ** 2 + yy ** 2) / 0.5).clamp(0, 1)  # a soft disc, the same for every item
    jitter = 0.9 + 0.1 * torch.rand((batch, 1, 1, 1), generator=g, dtype=torch.float64)
    coverage = (blob[None, None] * jitter).to(dtype)
    z = torch.sqrt((1 - xx ** 2 - yy ** 2).clamp_min(0))
    normals = (torch.stack([xx, yy, z])[None] * (blob > 0)).expand(batch, 3, size, size).to(dtype).contiguous()
    background = (0.2 + 0.6 * torch.rand(shape, generator=g, dtype=torch.float64)).to(dtype)
    color = (0.1 + 0.8 * torch.rand(shape, generator=g, dtype=torch.float64)).to(dtype)
    image = None
    if effect.stage == "image":
        image = (color * coverage + background * (1 - coverage)).to(dtype)
    origin = torch.tensor([[3.0 * i, 5.0] for i in range(batch)], dtype=dtype).reshape(batch, 2)
    frame_size = torch.tensor([[4.0 * size, 3.0 * size]] * batch, dtype=dtype).reshape(batch, 2)
    extras = {"frame_scale": torch.full((batch,), 1.5, dtype=dtype)}
    fields = effect.sample_fields(shape, g, dtype)
    params = {}
    for spec in effect.params:
        lo, hi = spec.sampling_range
        lo, hi = lo + 0.1 * (hi - lo), hi - 0.1 * (hi - lo)  # inside the range: no kink at a bound
        n = channels if spec.per_channel else 1
        params[spec.name] = (lo + (hi - lo) * torch.rand((batch, n), generator=g, dtype=torch.float64)).to(dtype)
        if not spec.per_channel:
            params[spec.name] = params[spec.name][:, 0]
    state = RenderState(object_color=color, coverage=coverage, normals=normals, background=background, image=image,
                        origin=origin, frame_size=frame_size, fields=fields, extras=extras)
    return state, params


def _tensors(state: RenderState, params: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
    out = {k: getattr(state, k) for k in ("object_color", "coverage", "normals", "background", "image", "origin",
                                          "frame_size")}
    out.update({f"fields.{k}": v for k, v in state.fields.items()})
    out.update({f"extras.{k}": v for k, v in state.extras.items()})
    out.update({f"params.{k}": v for k, v in params.items()})
    return {k: v for k, v in out.items() if isinstance(v, torch.Tensor)}


def _outputs(state: RenderState) -> dict[str, torch.Tensor]:
    return {k: getattr(state, k) for k in OUTPUTS if getattr(state, k) is not None}


def _item(state: RenderState, params: dict[str, torch.Tensor], i: int) -> tuple[RenderState, dict[str, torch.Tensor]]:
    take = lambda t: None if t is None else t[i:i + 1]  # noqa: E731
    item = state.replace(object_color=take(state.object_color), coverage=take(state.coverage),
                         normals=take(state.normals), background=take(state.background), image=take(state.image),
                         origin=take(state.origin), frame_size=take(state.frame_size),
                         fields={k: take(v) for k, v in state.fields.items()},
                         extras={k: take(v) for k, v in state.extras.items()})
    return item, {k: v[i:i + 1] for k, v in params.items()}


def check_no_in_place(effect: Effect, channels: int = 1) -> None:
    state, params = make_state(effect, 3, channels, 16, torch.float64)
    before = {k: v.clone() for k, v in _tensors(state, params).items()}
    effect.apply(state, **params)
    for k, v in _tensors(state, params).items():
        assert torch.equal(v, before[k]), f"{effect.name}: apply modified its input {k} in place"


def check_batched_equals_items(effect: Effect, channels: int = 1) -> None:
    state, params = make_state(effect, 3, channels, 16, torch.float64)
    whole = _outputs(effect.apply(state, **params))
    for i in range(3):
        item_state, item_params = _item(state, params, i)
        for k, v in _outputs(effect.apply(item_state, **item_params)).items():
            torch.testing.assert_close(whole[k][i:i + 1], v, atol=1e-10, rtol=1e-8,
                                       msg=lambda m, k=k, i=i: f"{effect.name}: item {i} of {k} in a batch: {m}")


def check_empty_batch(effect: Effect, channels: int = 1) -> None:
    state, params = make_state(effect, 0, channels, 16, torch.float32)
    out = _outputs(effect.apply(state, **params))
    for k, v in out.items():
        assert v.shape[0] == 0, f"{effect.name}: an empty batch gave {k} of shape {tuple(v.shape)}"


def check_dtype(effect: Effect, dtype: torch.dtype, channels: int = 1) -> None:
    state, params = make_state(effect, 2, channels, 16, dtype)
    out = _outputs(effect.apply(state, **params))
    for k, v in out.items():
        assert v.dtype == dtype, f"{effect.name}: {dtype} in, {k} is {v.dtype}"
        assert torch.isfinite(v).all(), f"{effect.name}: {k} is not finite"


def check_gradients(effect: Effect, channels: int = 1) -> None:
    """gradcheck of the outputs w.r.t. the parameters and the colour/background/composite layers (float64)."""
    state, params = make_state(effect, 2, channels, 8, torch.float64)
    layers = {k: getattr(state, k) for k in ("object_color", "background", "image")
              if getattr(state, k) is not None}
    names = list(params) + list(layers)
    inputs = tuple((params[n] if n in params else layers[n]).detach().clone().requires_grad_(True) for n in names)

    def fn(*xs: torch.Tensor) -> tuple[torch.Tensor, ...]:
        vals = dict(zip(names, xs))
        s = state.replace(**{k: vals[k] for k in layers})
        out = _outputs(effect.apply(s, **{k: vals[k] for k in params}))
        return tuple(out[k] for k in sorted(out))

    assert torch.autograd.gradcheck(fn, inputs, eps=1e-6, atol=1e-5, rtol=1e-3), effect.name


def check_effect(name: str, channels: int = 1) -> None:
    """Every check on the registered effect ``name``."""
    effect = get_effect(name)
    check_no_in_place(effect, channels)
    check_batched_equals_items(effect, channels)
    check_empty_batch(effect, channels)
    for dtype in (torch.float32, torch.float64):
        check_dtype(effect, dtype, channels)
    if effect.differentiable:
        check_gradients(effect, channels)

