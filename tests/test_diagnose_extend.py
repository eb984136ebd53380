"""Extending a fit with an accepted candidate effect (synthaug.diagnose.extend) and its use by the generator.

A tiny reference-camera seed set (4 seeds) and a base fit written from its truth stand in for a real fit.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from synthaug.diagnose.extend import extend_fit, select_extension
from synthaug.effects.registry import PAPER_EFFECTS
from synthaug.params import CaptureParams

STEP, SPRITE = 30.0, 48


@pytest.fixture(scope="module")
def seeds_and_fit(tmp_path_factory):
    """(seed-set folder, base fit file): Θ from the reference camera's truth, extras as ``synthaug fit`` writes."""
    from synthaug.diagnose.reference_camera import load_truth, make_measured_seedset

    d = tmp_path_factory.mktemp("extend")
    seeds = make_measured_seedset(d / "seeds", n_seeds=4, frame_size=(96, 128), object_px=(16.0, 20.0),
                                  view_step_deg=STEP, sprite_size=SPRITE, seed=3)
    truth, textra, _ = load_truth(seeds)
    theta = CaptureParams({k: v for k, v in truth.as_dict().items()}, effects=PAPER_EFFECTS)
    extra = [{"distance": 1.0 + i, "generator_seed": 100 + i, "object_scale": float(e["object_scale"])}
             for i, e in enumerate(textra)]
    fit = d / "fit.json"
    theta.save(fit, extra=extra, metadata={"config": {"step_deg": STEP, "sprite_size": SPRITE, "distance": "hog"}})
    return seeds, fit


def _finding(effect: str, setting: dict, **more) -> dict:
    return {"effect": effect, "significant": True, "channel": "distance:feature", "setting": setting, **more}


def _frame_scale(seeds) -> np.ndarray:
    """Frame px per patch px, by hand: crop side / patch side."""
    from synthaug.data.seedset import SeedSet

    s = SeedSet.load(seeds)
    return np.asarray(s.crops, np.float64)[:, 2] / s.patch_size


def test_defocus_values_are_frame_px_over_frame_scale_and_the_rest_is_kept(seeds_and_fit, tmp_path):
    seeds, fit = seeds_and_fit
    report = {"findings": [_finding("defocus", {"defocus_sigma": 1.0})], "screened": []}
    out = extend_fit(fit, seeds, report, tmp_path / "ext.json")
    base, bextra, bmeta = CaptureParams.load_with_extra(fit)
    ext, extra, meta = CaptureParams.load_with_extra(out)
    assert ext.effects == tuple(PAPER_EFFECTS) + ("defocus",)
    fs = _frame_scale(seeds)
    assert np.all(1.0 / fs < 3.0)  # inside the spec range: no clipping in this check
    np.testing.assert_allclose(ext.defocus_sigma[:, 0].numpy(), 1.0 / fs, rtol=1e-6)
    for name, v in base.as_dict().items():
        assert torch.equal(ext.as_dict()[name], v), name
    assert extra == bextra  # object_scale, generator_seed, distance per seed
    assert meta["config"] == bmeta["config"]
    assert meta["extension"]["effect"] == "defocus" and meta["extension"]["setting"] == {"defocus_sigma": 1.0}
    assert meta["extension"]["clipped_values"] == 0


def test_written_file_round_trips(seeds_and_fit, tmp_path):
    seeds, fit = seeds_and_fit
    out = extend_fit(fit, seeds, _finding("sharpening", {"sharpen_amount": 0.6, "sharpen_sigma": 1.0}),
                     tmp_path / "ext.json")
    a, ea, ma = CaptureParams.load_with_extra(out)
    a.save(tmp_path / "again.json", extra=ea, metadata=ma)
    b, eb, mb = CaptureParams.load_with_extra(tmp_path / "again.json")
    assert a.effects == b.effects and ea == eb and ma == mb
    for name, v in a.as_dict().items():
        assert torch.equal(b.as_dict()[name], v), name
    np.testing.assert_allclose(a.sharpen_amount[:, 0].numpy(), 0.6, rtol=1e-6)
    np.testing.assert_allclose(a.sharpen_sigma[:, 0].numpy(), np.clip(1.0 / _frame_scale(seeds), 0.3, 3.0), rtol=1e-6)


def test_rolling_shutter_follows_each_seeds_fitted_motion_direction(seeds_and_fit, tmp_path):
    seeds, fit = seeds_and_fit
    base = CaptureParams.load(fit)
    row = {"effect": "rolling_shutter", "significant": False, "channel": "distance:pixel",
           "setting_feature": {"rs_magnitude": -0.05}, "setting_pixel": {"rs_magnitude": 0.1}}
    assert select_extension(row)["setting"] == {"rs_magnitude": 0.1}  # the channel's space
    ext = CaptureParams.load(extend_fit(fit, seeds, row, tmp_path / "ext.json"))
    a = base.alpha_m[:, 0].double().numpy()
    np.testing.assert_allclose(ext.rs_skew[:, 0].numpy(), 0.1 * np.cos(a), atol=1e-6)
    np.testing.assert_allclose(ext.rs_stretch[:, 0].numpy(), 0.1 * np.sin(a), atol=1e-6)


def test_top_screened_is_used_only_when_asked(seeds_and_fit, tmp_path):
    seeds, fit = seeds_and_fit
    report = {"findings": [{"effect": "unexplained", "significant": True}],
              "screened": [{"effect": "compression", "significant": False, "channel": "distance:pixel",
                            "setting_feature": {"jpeg_quality": 80.0}, "setting_pixel": {"jpeg_quality": 30.0}}]}
    path = tmp_path / "report.json"
    path.write_text(json.dumps(report))
    with pytest.raises(ValueError, match="no candidate-effect finding"):
        extend_fit(fit, seeds, path, tmp_path / "ext.json")
    assert not (tmp_path / "ext.json").exists()
    sel = select_extension(path, use_top_screened=True)
    assert sel == {"effect": "compression", "setting": {"jpeg_quality": 30.0}, "space": "pixel",
                   "significant": False, "source": "top_screened"}
    ext = CaptureParams.load(extend_fit(fit, seeds, path, tmp_path / "ext.json", use_top_screened=True))
    assert torch.all(ext.jpeg_quality == 30.0)


def test_bad_inputs(seeds_and_fit, tmp_path):
    seeds, fit = seeds_and_fit
    out = tmp_path / "ext.json"
    with pytest.raises(ValueError, match="no candidate-effect finding"):
        extend_fit(fit, seeds, {"findings": [], "screened": []}, out)
    with pytest.raises(ValueError, match="unknown effect 'tilt_shift'"):
        extend_fit(fit, seeds, _finding("tilt_shift", {"x": 1.0}), out)
    with pytest.raises(ValueError, match="unexplained"):
        extend_fit(fit, seeds, {"effect": "unexplained"}, out)
    with pytest.raises(ValueError, match="does not match the parameters"):
        extend_fit(fit, seeds, _finding("defocus", {"sigma": 1.0}), out)
    with pytest.raises(ValueError, match="no setting"):
        extend_fit(fit, seeds, {"effect": "defocus", "channel": "distance:feature"}, out)
    with pytest.raises(FileNotFoundError, match="diagnosis report not found"):
        extend_fit(fit, seeds, tmp_path / "missing.json", out)
    ext = extend_fit(fit, seeds, _finding("defocus", {"defocus_sigma": 1.0}), out)
    with pytest.raises(ValueError, match="already has the effect 'defocus'"):
        extend_fit(ext, seeds, _finding("defocus", {"defocus_sigma": 1.0}), tmp_path / "twice.json")
    theta, extra, meta = CaptureParams.load_with_extra(fit)
    theta[[0, 1]].save(tmp_path / "short.json", extra=extra[:2], metadata=meta)
    with pytest.raises(ValueError, match="has 2 rows but the seed set has 4 seeds"):
        extend_fit(tmp_path / "short.json", seeds, _finding("defocus", {"defocus_sigma": 1.0}), out)


def _dataset(seeds, params, cache, **kw):
    from synthaug.data.seedset import SeedSet
    from synthaug.data.synthetic import SyntheticObjectDataset

    return SyntheticObjectDataset("quadcopter", SeedSet.load(seeds), params=str(params), length=6, patch_size=40,
                                  negative_fraction=0.0, seed=5, render=cache, **kw)


def _item_draw(ds, k: int):
    """Item ``k``'s draws by hand (dataset seed 5, epoch 0, 4 seeds): its generator after the uniform draws,
    the seed it uses and its pose."""
    from synthaug.data.synthetic import item_generator
    from synthaug.params import POSE_NAMES

    g = item_generator(5, 0, k)
    u = torch.rand(10, generator=g, dtype=torch.float64).tolist()
    pose = {n: torch.tensor([lo + (hi - lo) * u[2 + j]]) for j, n in enumerate(POSE_NAMES)
            for lo, hi in [ds.pose_sampler.ranges[n]]}
    return g, min(int(u[0] * 4), 3), pose


@pytest.mark.parametrize("effect, setting", [("defocus", {"defocus_sigma": 1.0}),
                                             ("shot_noise", {"shot_sigma": 0.05})])
def test_generator_applies_exactly_the_added_effect(seeds_and_fit, tmp_path, effect, setting):
    """Items of the extended fit = simulate(same layers, base Θ + the effect); ablating it gives the base items."""
    from synthaug.effects import simulate
    from synthaug.render.cache import ViewCache

    seeds, fit = seeds_and_fit
    cache = ViewCache.build("quadcopter", step_deg=STEP, sprite_size=SPRITE)
    ext_path = extend_fit(fit, seeds, _finding(effect, setting), tmp_path / "ext.json")
    base_ds, ext_ds = _dataset(seeds, fit, cache), _dataset(seeds, ext_path, cache)
    idx = list(range(len(base_ds)))
    base = torch.stack([im for im, _ in base_ds.__getitems__(idx)])
    ext = torch.stack([im for im, _ in ext_ds.__getitems__(idx)])
    assert (ext - base).abs().max() > 1e-3  # the effect is applied
    ablated = _dataset(seeds, ext_path, cache, effects=PAPER_EFFECTS)
    assert torch.equal(torch.stack([im for im, _ in ablated.__getitems__(idx)]), base)

    # the same items by hand: each item's pose, seed and random fields, base Θ_seed + the effect's per-seed values
    theta_ext = CaptureParams.load(ext_path)
    seed_scales = torch.tensor([float(e["object_scale"]) for e in CaptureParams.load_with_extra(fit)[1]])
    for k in idx:
        g, s, pose = _item_draw(ext_ds, k)
        fields = {}
        for name in ("object_noise", effect):  # the random effects in registry order
            from synthaug.effects.registry import get_effect

            fields.update(get_effect(name).sample_fields((1, 1, 40, 40), g))
        cov, nrm = cache.layers(pose["alpha"], pose["beta"], pose["gamma"], pose["t_x"], pose["t_y"], size=40,
                                object_scale=seed_scales[[s]])
        th = theta_ext[[s]].replace(**pose)
        bg = ext_ds.backgrounds[s][None]
        want = simulate(cov, nrm, bg, th, fields=fields)
        torch.testing.assert_close(ext[k:k + 1], want, atol=1e-5, rtol=0)


def test_cli_writes_the_extended_fit_from_the_first_finding(seeds_and_fit, tmp_path, monkeypatch, capsys):
    import argparse

    import synthaug.diagnose.report as report_mod
    from synthaug.diagnose import cli

    seeds, fit = seeds_and_fit
    fake = {"significant": True, "seconds": 1.0,
            "findings": [_finding("defocus", {"defocus_sigma": 1.0}), _finding("gamma", {"gamma_g": 0.8})]}
    monkeypatch.setattr(report_mod, "diagnose", lambda *a, **k: fake)
    p = argparse.ArgumentParser()
    cli.add_arguments(p)
    out = tmp_path / "ext.json"
    args = p.parse_args(["--seeds", str(seeds), "--fit", str(fit), "--out", str(tmp_path / "d"), "--quiet",
                         "--extended-fit", str(out)])
    assert cli.main(args) == 0
    assert json.loads(capsys.readouterr().out)["extended_fit"] == str(out)
    assert CaptureParams.load(out).effects[-1] == "defocus"

    fake["findings"] = [{"effect": "unexplained", "significant": True}]
    out2 = tmp_path / "none.json"
    args = p.parse_args(["--seeds", str(seeds), "--fit", str(fit), "--out", str(tmp_path / "d"), "--quiet",
                         "--extended-fit", str(out2)])
    assert cli.main(args) == 0
    got = capsys.readouterr()
    assert "--extended-fit not written" in got.err and json.loads(got.out)["extended_fit"] is None
    assert not out2.exists()


def test_seed_geometry_reaches_position_aware_effects_and_leaves_the_paper_effects_alone(seeds_and_fit, tmp_path):
    """With ``seed_geometry`` a vignetted item is darkened by its SEED's place in the frame (by hand: 1 - k r²)."""
    from synthaug.diagnose.reference_camera import seed_geometry
    from synthaug.effects import functional as Fx
    from synthaug.effects.pipeline import apply_effects
    from synthaug.effects.registry import RenderState, get_effect
    from synthaug.render.cache import ViewCache

    seeds, fit = seeds_and_fit
    cache = ViewCache.build("quadcopter", step_deg=STEP, sprite_size=SPRITE)
    geo = seed_geometry(seeds)
    idx = list(range(6))
    items = lambda ds: torch.stack([im for im, _ in ds.__getitems__(idx)])  # noqa: E731
    # the paper's effects ignore the geometry: Table 1's synthetic sets are unchanged by it
    assert torch.equal(items(_dataset(seeds, fit, cache, seed_geometry=None)),
                       items(_dataset(seeds, fit, cache, seed_geometry=geo)))

    ext_path = extend_fit(fit, seeds, _finding("vignetting", {"vignette_k": 0.5}), tmp_path / "ext.json")
    with_geo = items(_dataset(seeds, ext_path, cache, seed_geometry=geo))
    without = items(_dataset(seeds, ext_path, cache, seed_geometry=None))
    assert (with_geo - without).abs().max() > 1e-3  # the patch is no longer taken as the frame
    assert torch.equal(items(_dataset(seeds, ext_path, cache)), with_geo)  # default "auto": a seed set's own
    theta_ext = CaptureParams.load(ext_path)
    seed_scales = torch.tensor([float(e["object_scale"]) for e in CaptureParams.load_with_extra(fit)[1]])
    ds = _dataset(seeds, ext_path, cache, seed_geometry=geo)
    for k in idx:
        g, s, pose = _item_draw(ds, k)
        fields = get_effect("object_noise").sample_fields((1, 1, 40, 40), g)
        cov, nrm = cache.layers(pose["alpha"], pose["beta"], pose["gamma"], pose["t_x"], pose["t_y"], size=40,
                                object_scale=seed_scales[[s]])
        th = theta_ext[[s]].replace(**pose)
        bg = ds.backgrounds[s][None]
        # the object's colour darkened by 1 - k r², r² from this seed's patch pixels in its frame (by hand)
        ox, oy = (float(v) for v in geo["origin"][s])
        fw, fh = (float(v) for v in geo["frame_size"][s])
        fs = float(geo["frame_scale"][s])
        xs = ox + (torch.arange(40, dtype=torch.float64) + 0.5) * fs - 0.5
        ys = oy + (torch.arange(40, dtype=torch.float64) + 0.5) * fs - 0.5
        half = 0.5 * (fw ** 2 + fh ** 2) ** 0.5
        r2 = ((xs[None, :] - (fw - 1) / 2) ** 2 + (ys[:, None] - (fh - 1) / 2) ** 2) / half ** 2
        # the material, then the vignetting by hand, then the rest of the paper's pipeline
        color = Fx.diffuse_material(nrm, cov, torch.full((1, 1), 0.5))
        state = RenderState(object_color=color, coverage=cov, normals=nrm, background=bg, fields=fields)
        state = get_effect("material").apply(state, w_d=th.w_d)
        state = state.replace(object_color=state.object_color * (1 - 0.5 * r2).clamp_min(0).float()[None, None])
        want = apply_effects(state, th, [e for e in PAPER_EFFECTS if e != "material"]).image
        torch.testing.assert_close(with_geo[k:k + 1], want, atol=2e-4, rtol=0)
        assert not torch.allclose(without[k:k + 1], want, atol=2e-4)


def test_seed_geometry_bad_input(seeds_and_fit):
    from synthaug.diagnose.reference_camera import seed_geometry
    from synthaug.render.cache import ViewCache

    seeds, fit = seeds_and_fit
    cache = ViewCache.build("quadcopter", step_deg=STEP, sprite_size=SPRITE)
    geo = seed_geometry(seeds)
    with pytest.raises(ValueError, match=r"seed_geometry\['origin'\] must be finite with shape \(4, 2\)"):
        _dataset(seeds, fit, cache, seed_geometry={**geo, "origin": geo["origin"][:2]})
    with pytest.raises(ValueError, match="lacks \\['frame_scale'\\]"):
        _dataset(seeds, fit, cache, seed_geometry={k: v for k, v in geo.items() if k != "frame_scale"})
    with pytest.raises(ValueError, match="must be > 0"):
        _dataset(seeds, fit, cache, seed_geometry={**geo, "frame_scale": -geo["frame_scale"]})
    with pytest.raises(ValueError, match="'auto' or None"):
        _dataset(seeds, fit, cache, seed_geometry="frame")
    with pytest.raises(ValueError, match="seed_geometry is for patch mode"):
        _dataset(seeds, fit, cache, seed_geometry=geo, mode="frame", object_size=(10.0, 20.0))


def test_haze_and_white_balance_rows_follow_their_physics():
    import math

    from synthaug.diagnose.extend import extension_rows
    from synthaug.params import CaptureParams

    th = CaptureParams.default(2)
    fs = torch.tensor([2.0, 4.0])
    rows = extension_rows(th, fs, "haze", {"haze_extinction_px": 10.0, "haze_airlight": 0.8},
                          object_px=torch.tensor([20.0, 40.0]))
    assert rows["haze_amount"].tolist() == pytest.approx([1 - math.exp(-0.5), 1 - math.exp(-0.25)])
    assert rows["haze_airlight"].tolist() == pytest.approx([0.8, 0.8])
    with pytest.raises(ValueError, match="object_px"):
        extension_rows(th, fs, "haze", {"haze_extinction_px": 10.0, "haze_airlight": 0.8})
    # white balance (g, 1, 1/g) on a neutral object, in gray: its Rec. 601 luma gain
    wb = extension_rows(th, fs, "white_balance", {"wb_gain": 0.9})["wb_gain"]
    assert wb.tolist() == pytest.approx([0.299 * 0.9 + 0.587 + 0.114 / 0.9] * 2)


def test_with_the_mesh_w_d_is_re_solved_with_the_effect_as_screened(seeds_and_fit, tmp_path):
    """Haze brightens the object toward the airlight: with the mesh, the extended fit's w_d is the fitted w_d times
    the ratio of the least-squares w_d with and without haze (the screening's), found here by brute force."""
    from synthaug.diagnose.residuals import load_diagnosis_data, pixel_distance, render_with

    seeds, fit = seeds_and_fit
    report = {"findings": [_finding("haze", {"haze_extinction_px": 3.0, "haze_airlight": 0.6})], "screened": []}
    kept = CaptureParams.load_with_extra(extend_fit(fit, seeds, report, tmp_path / "kept.json"))[0]
    out, _, meta = CaptureParams.load_with_extra(extend_fit(fit, seeds, report, tmp_path / "ext.json",
                                                            mesh="quadcopter"))
    assert meta["extension"]["w_d"].startswith("scaled")
    torch.testing.assert_close(kept.w_d, CaptureParams.load_with_extra(fit)[0].w_d)
    data = load_diagnosis_data(seeds, fit, "quadcopter")
    ext = {"haze": {"haze_amount": out.haze_amount[:, 0], "haze_airlight": out.haze_airlight[:, 0]}}
    grid = torch.linspace(0.0, 1.0, 401)

    def best(e):
        d = np.stack([pixel_distance(data.real, render_with(data, e, w_d=torch.full((4,), float(g)), clamp=False))
                      for g in grid])
        return grid[d.argmin(0)].numpy()

    expected = kept.w_d[:, 0].numpy() * best(ext) / best(None)
    assert (expected > 0.05).all()  # inside the range: no clamping in this check
    np.testing.assert_allclose(out.w_d[:, 0].numpy(), expected, rtol=0.03)
    assert (out.w_d[:, 0] < kept.w_d[:, 0]).all()  # the airlight's brightness no longer needs the paint's


def test_cli_passes_a_known_object_colour_and_refuses_a_bad_one(seeds_and_fit, tmp_path, monkeypatch, capsys):
    import argparse

    import synthaug.diagnose.report as report_mod
    from synthaug.diagnose import cli

    seeds, fit = seeds_and_fit
    seen = {}

    def fake(*a, **k):
        seen.update(k)
        return {"significant": False, "seconds": 1.0, "findings": []}

    monkeypatch.setattr(report_mod, "diagnose", fake)
    p = argparse.ArgumentParser()
    cli.add_arguments(p)
    base = ["--seeds", str(seeds), "--fit", str(fit), "--out", str(tmp_path / "d"), "--quiet"]
    assert cli.main(p.parse_args(base + ["--object-colour", "200", "180", "150"])) == 0
    assert seen["object_colour"] == [200.0, 180.0, 150.0]
    capsys.readouterr()
    assert cli.main(p.parse_args(base + ["--object-colour", "1", "0", "1"])) == 2
    assert "--object-colour: an object colour is three positive" in capsys.readouterr().err
