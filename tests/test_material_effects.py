"""object_texture (synthaug.effects.material) against independent references."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from synthaug.effects import PAPER_EFFECTS, sample_fields, simulate
from synthaug.effects.material import TEXTURE_PAD, texture_field
from synthaug.effects.registry import RenderState, get_effect, list_effects, ordered
from synthaug.params import CaptureParams


def _disc_layers(b=2, size=40, radius=11.0):
    """A disc facing the camera (hard edge) and a random background, float64."""
    yy, xx = np.mgrid[:size, :size]
    cov = ((yy - size / 2 + 0.5) ** 2 + (xx - size / 2 + 0.5) ** 2 <= radius ** 2).astype(np.float64)
    cov = np.broadcast_to(cov, (b, 1, size, size)).copy()
    nrm = np.zeros((b, 3, size, size))
    nrm[:, 2] = cov[:, 0]
    bg = np.random.default_rng(5).random((b, 1, size, size)) * 0.5 + 0.3
    return torch.tensor(cov), torch.tensor(nrm), torch.tensor(bg)


def _theta(b, amp, scale=1.5, effects=("material", "object_texture")):
    return CaptureParams({"w_d": torch.full((b,), 0.5), "texture_amp": torch.full((b,), float(amp)),
                          "texture_scale": torch.full((b,), float(scale))}, effects=effects)


def _flat_state(field, color=0.4, size=64):
    b = field.shape[0]
    ones = torch.ones((b, 1, size, size), dtype=torch.float64)
    normals = torch.zeros((b, 3, size, size), dtype=torch.float64)
    return RenderState(object_color=color * ones, coverage=ones, normals=normals, background=torch.zeros_like(ones),
                       fields={"texture": field})


def test_registered_with_stage_order_and_ranges():
    eff = get_effect("object_texture")
    assert "object_texture" in list_effects()
    assert eff.stage == "object" and eff.is_random
    names = [e.name for e in ordered(list(PAPER_EFFECTS) + ["object_texture"])]
    assert names.index("material") < names.index("object_texture") < names.index("motion_blur")
    spec = {s.name: (s.low, s.high) for s in eff.params}
    assert spec == {"texture_amp": (0.0, 1.0), "texture_scale": (0.3, 4.0)}


def test_zero_amplitude_is_the_identity():
    cov, nrm, bg = _disc_layers()
    g = lambda: torch.Generator().manual_seed(3)  # noqa: E731
    base = CaptureParams.sample(2, generator=g(), effects=PAPER_EFFECTS).replace(w_d=torch.tensor([0.3, 0.7]))
    ext = CaptureParams({**base.as_dict(), "texture_amp": torch.zeros(2), "texture_scale": torch.tensor([0.3, 4.0])},
                        effects=PAPER_EFFECTS + ("object_texture",))
    a = simulate(cov, nrm, bg, base, generator=g())
    b = simulate(cov, nrm, bg, ext, generator=g())
    torch.testing.assert_close(b, a, atol=0, rtol=0)


@pytest.mark.parametrize("ell", [1.0, 2.0, 3.0])
def test_applied_field_has_unit_variance_and_the_analytic_correlation(ell):
    # the applied relative albedo change, divided by a, against exp(-d²/(4ℓ²)) of blurred white noise
    amp, color, size = 0.1, 0.4, 96
    gen = torch.Generator().manual_seed(11)
    fields = get_effect("object_texture").sample_fields((24, 1, size, size), gen, torch.float64)
    out = get_effect("object_texture").apply(_flat_state(fields["texture"], color, size),
                                             texture_amp=torch.full((24, 1), amp, dtype=torch.float64),
                                             texture_scale=torch.full((24, 1), ell, dtype=torch.float64))
    f = ((out.object_color / color - 1.0) / amp)[:, 0].numpy()
    assert abs(f.var() - 1.0) < 0.1 and abs(f.mean()) < 0.05
    for d in range(1, 7):
        rho = np.mean([(f[:, :, :-d] * f[:, :, d:]).mean(), (f[:, :-d, :] * f[:, d:, :]).mean()]) / f.var()
        assert abs(rho - np.exp(-d * d / (4 * ell * ell))) < 0.03, (d, rho)


def test_correlation_length_is_distinguishable():
    # a wrong ℓ (0.7× or 1.4×) must fail the same comparison: the test above can fail
    gen = torch.Generator().manual_seed(2)
    w = get_effect("object_texture").sample_fields((24, 1, 96, 96), gen, torch.float64)["texture"]
    f = texture_field(w, torch.full((24,), 2.0, dtype=torch.float64), (96, 96))[:, 0].numpy()
    rho = (f[:, :, :-3] * f[:, :, 3:]).mean() / f.var()
    for wrong in (1.4, 2.8):
        assert abs(rho - np.exp(-9 / (4 * wrong ** 2))) > 0.1


def test_only_object_pixels_change_and_values_stay_in_range():
    cov, nrm, bg = _disc_layers()
    g = lambda: torch.Generator().manual_seed(8)  # noqa: E731
    plain = simulate(cov, nrm, bg, _theta(2, 0.0), generator=g(), clamp=False)
    tex = simulate(cov, nrm, bg, _theta(2, 0.8, 1.0), generator=g(), clamp=False)
    outside = (cov == 0).expand_as(tex)
    assert torch.equal(tex[outside], plain[outside])
    inside = (cov == 1).expand_as(tex)
    assert (tex[inside] - plain[inside]).abs().mean() > 0.05
    # clamp to [0, 1] on the object layer: a huge relative change saturates but never leaves the range
    state = RenderState(object_color=torch.full((2, 1, 40, 40), 0.9, dtype=torch.float64), coverage=cov, normals=nrm,
                        background=bg, fields=sample_fields(["object_texture"], (2, 1, 40, 40), g(), torch.float64))
    out = get_effect("object_texture").apply(state, texture_amp=torch.ones(2, 1, dtype=torch.float64),
                                             texture_scale=torch.full((2, 1), 0.3, dtype=torch.float64))
    assert out.object_color.min() >= 0.0 and out.object_color.max() <= 1.0
    assert (out.object_color == 1.0).any() and (out.object_color == 0.0).any()


def test_gradcheck_in_amplitude_float64():
    cov, nrm, bg = _disc_layers(b=1, size=24, radius=7.0)
    fields = sample_fields(["object_texture"], (1, 1, 24, 24), torch.Generator().manual_seed(4), torch.float64)
    eff = get_effect("object_texture")

    def f(a):
        st = RenderState(object_color=0.45 * cov, coverage=cov, normals=nrm, background=bg, fields=fields)
        return eff.apply(st, texture_amp=a, texture_scale=torch.full((1, 1), 1.2, dtype=torch.float64)).object_color

    a = torch.full((1, 1), 0.2, dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradcheck(f, (a,))


def test_deterministic_given_the_generator_and_leaves_other_fields_alone():
    shape = (3, 1, 40, 40)
    eff = PAPER_EFFECTS + ("object_texture",)
    a = sample_fields(eff, shape, torch.Generator().manual_seed(21))
    b = sample_fields(eff, shape, torch.Generator().manual_seed(21))
    c = sample_fields(eff, shape, torch.Generator().manual_seed(22))
    assert torch.equal(a["texture"], b["texture"]) and not torch.equal(a["texture"], c["texture"])
    assert a["texture"].shape == (3, 1, 40 + 2 * TEXTURE_PAD, 40 + 2 * TEXTURE_PAD)
    # the texture is drawn from a child of the generator: the object noise is the base model's
    base = sample_fields(PAPER_EFFECTS, shape, torch.Generator().manual_seed(21))
    assert torch.equal(a["noise"], base["noise"])
    assert not torch.allclose(a["texture"][..., :40, :40], a["noise"])
    cov, nrm, bg = _disc_layers()
    th = _theta(2, 0.5, 2.0)
    x = simulate(cov, nrm, bg, th, generator=torch.Generator().manual_seed(1))
    y = simulate(cov, nrm, bg, th, generator=torch.Generator().manual_seed(1))
    assert torch.equal(x, y)


def test_bad_input_raises():
    eff = get_effect("object_texture")
    st = _flat_state(torch.zeros((1, 1, 64, 64), dtype=torch.float64), size=64)  # not padded
    kw = dict(texture_amp=torch.full((1, 1), 0.1, dtype=torch.float64),
              texture_scale=torch.full((1, 1), 1.0, dtype=torch.float64))
    with pytest.raises(ValueError, match="too small"):
        eff.apply(st, **kw)
    with pytest.raises(ValueError, match="texture"):
        eff.apply(st.replace(fields={}), **kw)
    with pytest.raises(ValueError, match="generator"):
        eff.sample_fields((1, 1, 8, 8), 3)
