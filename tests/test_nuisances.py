"""Nuisances of the reference camera (issue 20, item 1): variation that is not a camera effect."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import torch

from synthaug.diagnose.nuisances import (
    DRAW_RANGES,
    MODEL_AMBIENT,
    MODEL_LIGHT,
    Nuisances,
    SeedNuisance,
    drift_scene,
    shade_object,
    smooth_normals,
)

FAST = dict(n_seeds=6, frame_size=(96, 128), object_px=(16.0, 24.0), view_step_deg=30.0, sprite_size=48, seed=5,
            n_videos=3)


def _unit_normals(shape, seed):
    g = torch.Generator().manual_seed(seed)
    n = torch.randn(shape, generator=g, dtype=torch.float64)
    n[:, 2] = n[:, 2].abs() + 0.2  # facing the camera
    return n / n.norm(dim=1, keepdim=True)


def test_none_shades_exactly_like_the_fits_material():
    from synthaug.effects.functional import diffuse_material

    nrm = _unit_normals((2, 3, 9, 9), 0)
    cov = torch.ones(2, 1, 9, 9, dtype=torch.float64)
    cov[..., :2, :] = 0
    none = Nuisances.none()
    assert none.is_none() and none.shading_is_model and none.mesh_is_model
    seed_nz = none.draw_seed(seed=1, index=0, video=0)
    assert seed_nz.light_dir == pytest.approx(MODEL_LIGHT) and seed_nz.light_strength == 1.0
    assert seed_nz.drift == (0.0, 0.0) and seed_nz.flicker == 0.0
    w = torch.tensor([0.3, 0.6], dtype=torch.float64)
    torch.testing.assert_close(shade_object(nrm, cov, w, none, seed_nz), diffuse_material(nrm, cov, w[:, None]))


def test_shade_object_by_hand():
    """One pixel, numpy by hand: strength · [w_d · (1 + amp·F) · (a + (1 - a) max(0, n·l)) + ks (n·h)^s]."""
    nz = Nuisances(ambient=0.3, specular_ks=0.2, specular_shininess=12.0, albedo_texture_amp=0.1)
    light = np.array([0.3, 0.4, math.sqrt(1 - 0.25)])
    sn = SeedNuisance(light_dir=tuple(light), light_strength=0.9, drift=(0.0, 0.0), flicker=0.0, texture_seed=0)
    n = np.array([0.1, -0.2, 1.0])
    n /= np.linalg.norm(n)
    nrm = torch.from_numpy(n).reshape(1, 3, 1, 1)
    cov = torch.ones(1, 1, 1, 1, dtype=torch.float64)
    tex = torch.full((1, 1, 1, 1), -0.5, dtype=torch.float64)
    h = (light + [0, 0, 1]) / np.linalg.norm(light + [0, 0, 1])
    ref = 0.9 * (0.4 * (1 + 0.1 * -0.5) * (0.3 + 0.7 * max(0.0, n @ light)) + 0.2 * max(0.0, n @ h) ** 12.0)
    assert float(shade_object(nrm, cov, 0.4, nz, sn, texture=tex)) == pytest.approx(ref, rel=1e-9)


def test_smooth_normals_against_scipy_normalised_convolution():
    from scipy import ndimage

    nrm = _unit_normals((1, 3, 32, 32), 3)
    cov = torch.zeros(1, 1, 32, 32, dtype=torch.float64)
    cov[..., 6:26, 8:24] = 1.0
    nrm = nrm * cov
    out = smooth_normals(nrm, cov, 1.2)
    w = cov[0, 0].numpy()
    num = np.stack([ndimage.gaussian_filter(nrm[0, c].numpy() * w, 1.2, mode="constant", truncate=6) for c in range(3)])
    den = ndimage.gaussian_filter(w, 1.2, mode="constant", truncate=6)
    inside = w > 0
    ref = num[:, inside] / den[inside]
    ref /= np.linalg.norm(ref, axis=0, keepdims=True)
    np.testing.assert_allclose(out[0].numpy()[:, inside], ref, atol=2e-3)
    assert float(out[0].norm(dim=0)[torch.from_numpy(inside)].min()) == pytest.approx(1.0)
    assert (out[0][:, ~torch.from_numpy(inside)] == 0).all()
    # a plane's normals are left as they are
    flat = torch.zeros(1, 3, 16, 16, dtype=torch.float64)
    flat[:, 2] = 1.0
    torch.testing.assert_close(smooth_normals(flat, torch.ones(1, 1, 16, 16, dtype=torch.float64), 1.5), flat)


def test_drift_scene_moves_without_blurring():
    """A smooth pattern moves by exactly the drift (analytic, away from the edges); the power of white noise is
    kept (a moving scene is not a blurrier one: a bilinear shift by 0.5 px would lose ~40 % of it)."""
    yy, xx = np.mgrid[0:64, 0:96].astype(np.float64)
    pattern = lambda x, y: 0.5 + 0.2 * np.cos(2 * np.pi * x / 23.0) * np.sin(2 * np.pi * y / 17.0 + 0.4)  # noqa
    sn = SeedNuisance(light_dir=MODEL_LIGHT, light_strength=1.0, drift=(0.6, -0.3), flicker=0.01, texture_seed=0)
    out = drift_scene(pattern(xx, yy), sn)
    ref = pattern(xx - 0.6, yy + 0.3) * 1.01
    np.testing.assert_allclose(out[12:-12, 12:-12], ref[12:-12, 12:-12], atol=4e-3)  # edge ringing: 2 % of 0.2
    rgb = np.stack([pattern(xx, yy), 0.9 * pattern(xx, yy)])
    np.testing.assert_allclose(drift_scene(rgb, sn)[1], drift_scene(0.9 * pattern(xx, yy), sn))
    noise = 0.5 + 0.05 * np.random.default_rng(0).standard_normal((64, 96))
    half = SeedNuisance(light_dir=MODEL_LIGHT, light_strength=1.0, drift=(0.5, 0.5), flicker=0.0, texture_seed=0)
    inner = (slice(8, -8), slice(8, -8))
    assert drift_scene(noise, half)[inner].std() == pytest.approx(noise[inner].std(), rel=0.03)
    still = SeedNuisance(light_dir=MODEL_LIGHT, light_strength=1.0, drift=(0.0, 0.0), flicker=0.0, texture_seed=0)
    assert drift_scene(noise, still) is noise


def test_draw_is_explicitly_seeded_in_range_and_validated():
    a = Nuisances.draw(np.random.default_rng(7))
    assert a == Nuisances.draw(np.random.default_rng(7)) and a != Nuisances.draw(np.random.default_rng(8))
    many = [Nuisances.draw(np.random.default_rng(k)) for k in range(40)]
    for name, (lo, hi) in DRAW_RANGES.items():
        vals = [getattr(n, name) for n in many]
        assert lo <= min(vals) and max(vals) <= hi, name
    assert {n.normal_smoothing_px == 0 for n in many} == {True, False}  # flat and smooth both drawn
    assert Nuisances.from_dict(json.loads(json.dumps(a.as_dict()))) == a
    with pytest.raises(ValueError, match="specular_ks must be in"):
        Nuisances(specular_ks=-0.1)
    with pytest.raises(ValueError, match="mesh_sections"):
        Nuisances(mesh_sections=3)
    with pytest.raises(ValueError, match="unknown nuisance field"):
        Nuisances.from_dict({"glare": 1.0})
    with pytest.raises(ValueError, match="numpy.random.Generator"):
        Nuisances.draw(0)  # type: ignore[arg-type]


def test_draw_seed_light_is_per_video_and_tilted_within_the_spread():
    nz = Nuisances(light_spread_deg=30.0, light_strength_spread=0.2, background_drift_px=1.0)
    a, b, c = (nz.draw_seed(seed=2, index=i, video=v) for i, v in ((0, 0), (3, 0), (1, 1)))
    assert a.light_dir == b.light_dir and a.light_strength == b.light_strength  # the same video's light
    assert a.light_dir != c.light_dir and a.drift != b.drift  # another video; another frame
    for s in (a, c):
        ang = math.degrees(math.acos(np.clip(np.dot(s.light_dir, MODEL_LIGHT), -1, 1)))
        assert ang <= 30.0 + 1e-9 and 0.8 <= s.light_strength <= 1.2
        assert math.hypot(*s.drift) <= 1.0


@pytest.mark.slow
def test_reference_camera_with_nuisances(tmp_path):
    from synthaug.data.seedset import SeedSet
    from synthaug.diagnose.reference_camera import load_truth, make_measured_seedset

    base = SeedSet.load(make_measured_seedset(tmp_path / "base", **FAST))
    none = SeedSet.load(make_measured_seedset(tmp_path / "none", nuisances=Nuisances.none(), **FAST))
    np.testing.assert_array_equal(base.patches, none.patches)
    assert (tmp_path / "base" / "seedset.json").read_bytes() == (tmp_path / "none" / "seedset.json").read_bytes()
    assert "nuisances" not in base.metadata["reference_camera"]

    nz = Nuisances(ambient=0.3, specular_ks=0.15, normal_smoothing_px=1.0, albedo_texture_amp=0.1,
                   light_spread_deg=30.0, light_strength_spread=0.15, rotor_scale=1.15, mesh_sections=24,
                   mesh_perturbation=0.02, background_drift_px=1.0, background_flicker=0.01)
    s = SeedSet.load(make_measured_seedset(tmp_path / "nz", nuisances=nz, **FAST))
    rc = s.metadata["reference_camera"]
    assert Nuisances.from_dict(rc["nuisances"]) == nz and "rotors x1.15" in rc["mesh"]
    load_truth(s.path)  # still a valid truth file
    meta = json.loads((s.path / "truth.json").read_text())
    assert Nuisances.from_dict(meta["metadata"]["nuisances"]) == nz
    for i, rec in enumerate(s.records):
        want = nz.draw_seed(seed=FAST["seed"], index=i, video=i % FAST["n_videos"])
        assert rec["truth"]["nuisance"] == json.loads(json.dumps(want.as_dict()))
    # the scene's draws are the same (pose, place, Θ): the object is in the same crop, its look differs
    assert (np.abs(s.crops[:, :2] - base.crops[:, :2]) <= 0.1 * s.crops[:, 2:3]).all()
    assert np.abs(s.patches.astype(int) - base.patches.astype(int)).mean() > 1.0
    # the background estimate is the still scene through the same camera: unchanged by the nuisances
    for i in range(len(s)):
        np.testing.assert_array_equal(s.background_frame(i), base.background_frame(i))
    with pytest.raises(ValueError, match="mesh perturbation once"):
        make_measured_seedset(tmp_path / "x", nuisances=Nuisances(mesh_perturbation=0.02), mesh_perturbation=0.02,
                              **FAST)
    with pytest.raises(ValueError, match="Nuisances record"):
        make_measured_seedset(tmp_path / "x", nuisances={"ambient": 0.3}, **FAST)  # type: ignore[arg-type]


def test_a_hidden_highlight_is_the_real_materials_own_gloss(tmp_path):
    """Stop 112: with nuisances, a hidden ``specular`` is lit by its video's light (direction and strength) on the real
    material's (smooth) normals, so it is the same highlight as that material's own gloss of the same ks and exponent
    (the clean cases' nuisance): the two seed sets agree up to 8-bit rounding, and both differ from the material
    without gloss."""
    from synthaug.data.seedset import SeedSet
    from synthaug.diagnose.reference_camera import make_measured_seedset

    kw = dict(FAST, n_seeds=4)
    nz = Nuisances(ambient=0.3, normal_smoothing_px=1.2, light_spread_deg=35.0, light_strength_spread=0.15)
    spec = {"specular": {"specular_ks": 0.15, "specular_shininess": 20.0}}
    hidden = SeedSet.load(make_measured_seedset(tmp_path / "h", hidden=spec, nuisances=nz, **kw))
    glossy = SeedSet.load(make_measured_seedset(
        tmp_path / "g", nuisances=Nuisances(**{**nz.as_dict(), "specular_ks": 0.15, "specular_shininess": 20.0}), **kw))
    matte = SeedSet.load(make_measured_seedset(tmp_path / "m", nuisances=nz, **kw))
    # the videos' lights are tilted away from the model's (0, 0.5, 0.866)
    assert max(abs(r["truth"]["nuisance"]["light_dir"][0]) for r in hidden.records) > 0.05
    d_hg = np.abs(hidden.patches.astype(int) - glossy.patches.astype(int))
    d_hm = np.abs(hidden.patches.astype(int) - matte.patches.astype(int))
    assert d_hg.max() <= 1 and d_hm.max() >= 10, (d_hg.max(), d_hm.max())


def test_paint_tint_keeps_luma_and_has_its_saturation_and_hue():
    from synthaug.diagnose.nuisances import PAINT_SATURATION, paint_tint
    from synthaug.effects.camera_functional import LUMA_WEIGHTS

    lw = np.asarray(LUMA_WEIGHTS)
    hues = np.arange(0.0, 360.0, 15.0)
    tints = np.stack([paint_tint(0.08, h) for h in hues])
    np.testing.assert_allclose(tints @ lw, 1.0, atol=1e-12)  # gray data do not see the paint
    np.testing.assert_allclose(np.linalg.norm(tints - 1, axis=1), 0.08, atol=1e-12)
    # opposite hues are opposite offsets; 0 degrees is reddish (red up, blue down), 180 bluish
    np.testing.assert_allclose(paint_tint(0.08, 200.0) - 1, -(paint_tint(0.08, 20.0) - 1), atol=1e-12)
    red, blue = paint_tint(0.1, 0.0), paint_tint(0.1, 180.0)
    assert red[0] > 1 > red[2] and blue[2] > 1 > blue[0]
    # the chroma plane is spanned: offsets at 0 and 90 degrees are orthogonal, and both orthogonal to the luma
    a, b = paint_tint(1.0, 0.0) - 1, paint_tint(1.0, 90.0) - 1
    assert abs(a @ b) < 1e-12 and abs(a @ lw) < 1e-12 and abs(b @ lw) < 1e-12
    many = [Nuisances.draw(np.random.default_rng(k)) for k in range(40)]
    sat = [n.paint_saturation for n in many]
    assert PAINT_SATURATION[0] <= min(sat) and max(sat) <= PAINT_SATURATION[1]
    assert Nuisances().paint_rgb.tolist() == [1.0, 1.0, 1.0]
    with pytest.raises(ValueError, match="paint_saturation must be in"):
        Nuisances(paint_saturation=0.8)


@pytest.mark.slow
def test_reference_camera_paints_the_colour_object_and_gray_data_do_not_see_it(tmp_path):
    from synthaug.data.seedset import SeedSet
    from synthaug.diagnose.reference_camera import make_measured_seedset

    plain = Nuisances(ambient=0.3, light_spread_deg=20.0)
    painted = Nuisances(ambient=0.3, light_spread_deg=20.0, paint_saturation=0.3, paint_hue_deg=0.0)
    gray = [SeedSet.load(make_measured_seedset(tmp_path / f"g{k}", nuisances=n, **FAST))
            for k, n in enumerate((plain, painted))]
    np.testing.assert_array_equal(gray[0].patches, gray[1].patches)  # one channel: the paint has unit luma
    patches, backs = [], []
    for k, n in enumerate((plain, painted)):
        make_measured_seedset(tmp_path / f"c{k}", nuisances=n, colour=True, **FAST)
        with np.load(tmp_path / f"c{k}" / "colour.npz") as z:  # (N, P, P, 3) uint8
            patches.append(z["patches_rgb"].astype(np.float64))
            backs.append(z["backgrounds_rgb"].astype(np.float64))
    np.testing.assert_array_equal(backs[0], backs[1])  # the scene is not painted
    obj = np.abs(patches[0] - backs[0]).sum(-1) > 12  # the object's pixels
    red = [p[..., 0][obj].mean() for p in patches]
    blue = [p[..., 2][obj].mean() for p in patches]
    assert red[1] > red[0] + 3 and blue[1] < blue[0] - 3  # hue 0: redder, less blue, on the object only
