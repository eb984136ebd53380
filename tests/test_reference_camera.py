"""The measured-data simulator (reference camera): format, stored truth, whole-frame vs object-only physics."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from synthaug.data.seedset import SeedSet
from synthaug.diagnose.reference_camera import (
    REALISTIC_STRENGTHS,
    load_truth,
    make_measured_seedset,
    perturb_mesh,
    quadcopter_parts,
    resolve_hidden,
    seed_geometry,
)
from synthaug.effects import PAPER_EFFECTS, simulate
from synthaug.params import CaptureParams

# small and fast: 96 x 128 frames, a coarse view cache
FAST = dict(n_seeds=6, frame_size=(96, 128), object_px=(16.0, 24.0), view_step_deg=30.0, sprite_size=48, seed=5)


@pytest.fixture(scope="module")
def sets(tmp_path_factory):
    root = tmp_path_factory.mktemp("refcam")
    made = {}
    for name, hidden in (("clean", {}), ("vignetting", {"vignetting": {"vignette_k": 0.3}}),
                         ("rotor", ["rotor_blur"]), ("jpeg", {"compression": {"jpeg_quality": 35}}),
                         ("interlacing", {"interlacing": {"interlace_shift": 2.5}}),
                         ("columns", {"column_pattern": {"column_gain_sd": 0.03}})):
        made[name] = SeedSet.load(make_measured_seedset(root / name, hidden=hidden, **FAST))
    return made


def test_the_seed_set_loads_and_stores_the_truth(sets):
    s = sets["vignetting"]
    assert len(s) == 6 and s.patches.shape == (6, 40, 40) and s.backgrounds.shape == (6, 40, 40)
    assert s.frame(0).shape == (96, 128) and s.background_frame(0).shape == (96, 128)
    rc = s.metadata["reference_camera"]
    assert rc["hidden"] == {"vignetting": {"vignette_k": 0.3}} and rc["whole_frame"] == ["vignetting"]
    theta, extra, header = load_truth(s.path)
    assert theta.effects == PAPER_EFFECTS + ("vignetting",) and theta.batch_size == 6
    np.testing.assert_allclose(theta.vignette_k.numpy(), 0.3)
    for i, rec in enumerate(s.records):
        t = rec["truth"]
        assert t["hidden"] == {"vignetting": {"vignette_k": 0.3}}
        assert abs(t["theta"]["w_d"] - float(theta.w_d[i, 0])) < 1e-6
        assert extra[i]["object_scale"] == pytest.approx(t["object_scale"])
        # the crop stored in the arrays is the one the truth refers to
        side = float(s.crops[i, 2])
        np.testing.assert_allclose(t["origin"], s.crops[i, :2] - side / 2, atol=1e-3)
        assert t["frame_scale"] == pytest.approx(side / 40, rel=1e-5)
    geo = seed_geometry(s)
    np.testing.assert_allclose(geo["origin"].numpy(), [e["origin"] for e in extra], atol=1e-3)
    np.testing.assert_allclose(geo["frame_size"].numpy(), [[128, 96]] * 6)
    assert set(s.records[0]) >= {"video", "frame", "class", "background_method", "split"}


def _patch_gain(s, i, k):
    """1 - k r² at the patch pixels of seed i, computed from its crop (numpy, crop_patch geometry)."""
    cx, cy, side = (float(v) for v in s.crops[i])
    p = s.patch_size
    u = np.arange(p)
    x = cx + (u + 0.5 - p / 2) * side / p - 0.5
    y = cy + (u + 0.5 - p / 2) * side / p - 0.5
    w, h = 128, 96
    rad = 0.5 * math.hypot(w, h)
    r2 = ((x[None, :] - (w - 1) / 2) ** 2 + (y[:, None] - (h - 1) / 2) ** 2) / rad ** 2
    return 1 - k * r2


def test_whole_frame_vignetting_is_in_the_frame_the_background_and_the_object(sets):
    clean, vig = sets["clean"], sets["vignetting"]
    yy, xx = np.mgrid[:96, :128]
    gain = 1 - 0.3 * ((xx - 63.5) ** 2 + (yy - 47.5) ** 2) / (0.5 * math.hypot(128, 96)) ** 2
    for i in range(len(clean)):
        # same seed: the same scene, pose and box; only the camera differs
        np.testing.assert_array_equal(vig.crops[i], clean.crops[i])
        for a, b in ((vig.frame(i), clean.frame(i)), (vig.background_frame(i), clean.background_frame(i))):
            ok = b < 250  # the clean camera saturates there
            np.testing.assert_allclose(a[ok].astype(float), (gain * b)[ok], atol=2.0)
        g = _patch_gain(clean, i, 0.3)
        for a, b in ((vig.backgrounds[i], clean.backgrounds[i]), (vig.patches[i], clean.patches[i])):
            ok = b < 250
            np.testing.assert_allclose(a[ok].astype(float), (g * b)[ok], atol=2.0)
    corners = np.concatenate([vig.background_frame(i)[:6, :6].ravel() / clean.background_frame(i)[:6, :6].ravel()
                              for i in range(len(vig))])
    assert 0.68 < corners.mean() < 0.76  # 30 % fall-off in the corners


def test_object_only_effects_leave_the_background_untouched(sets):
    clean, rotor = sets["clean"], sets["rotor"]
    np.testing.assert_array_equal(rotor.backgrounds, clean.backgrounds)
    for i in range(len(clean)):
        np.testing.assert_array_equal(rotor.background_frame(i), clean.background_frame(i))
    # spinning rotors are see-through: the object stands out less from its background
    contrast = lambda s: np.abs(s.patches.astype(float) - s.backgrounds).sum((1, 2))  # noqa: E731
    assert (contrast(rotor) < contrast(clean)).all()
    opac = [r["truth"]["hidden"]["rotor_blur"]["rotor_opacity"] for r in rotor.records]
    assert min(opac) >= 0.15 and max(opac) <= 0.4 and len(set(opac)) == len(opac)  # drawn per seed


def _blockiness(img):
    """Mean |horizontal step| across 8-px block boundaries over that inside blocks."""
    d = np.abs(np.diff(img.astype(float), axis=1))
    cols = np.arange(d.shape[1])
    return d[:, cols % 8 == 7].mean() / d[:, cols % 8 != 7].mean()


def test_compression_shows_8x8_blocks_in_frames_and_backgrounds(sets):
    clean, jpeg = sets["clean"], sets["jpeg"]
    for i in range(len(clean)):
        assert _blockiness(jpeg.background_frame(i)) > 1.3 > 1.1 > _blockiness(clean.background_frame(i))
        assert _blockiness(jpeg.frame(i)) > 1.3


def test_the_fixed_column_pattern_is_the_cameras_in_every_frame_and_background(sets):
    from synthaug.diagnose.reference_camera import column_gains

    clean, cols = sets["clean"], sets["columns"]
    rc = cols.metadata["reference_camera"]
    assert "column_pattern" in rc["whole_frame"] and "column_pattern" not in rc["object_only"]
    gains = column_gains(128, 0.03, FAST["seed"])  # the camera's stream: the case's seed
    for i in range(len(clean)):
        for frame in ("frame", "background_frame"):
            a = getattr(cols, frame)(i).astype(float)
            b = getattr(clean, frame)(i).astype(float)
            ok = (b > 20) & (b < 235) & (a < 250)  # away from 8-bit clipping
            cols_ok = ok.sum(0) >= 10
            assert cols_ok.mean() > 0.5, (i, frame)
            # per column: the median ratio over rows is the column's gain, to the 8-bit rounding
            ratio = np.array([np.median(a[ok[:, c], c] / b[ok[:, c], c]) if cols_ok[c] else np.nan
                              for c in range(128)])
            np.testing.assert_allclose(ratio[cols_ok], gains[cols_ok], atol=0.008)
    theta, _, _ = load_truth(cols.path)
    assert theta.effects == PAPER_EFFECTS  # not a candidate
    assert cols.records[0]["truth"]["hidden"]["column_pattern"] == {"column_gain_sd": 0.03,
                                                                     "pattern_seed": float(FAST["seed"])}


def test_the_outside_effect_combs_the_moving_object(sets):
    clean, inter = sets["clean"], sets["interlacing"]
    assert "interlacing" in inter.metadata["reference_camera"]["object_only"]

    def comb(s, i):  # row-to-row zigzag of the object (second difference across rows, in its box)
        x, y, w, h = (int(round(v)) for v in s.boxes[i])
        f = s.frame(i).astype(float)[max(y - 2, 0):y + h + 2, max(x - 2, 0):x + w + 2]
        return np.abs(f[1:-1] - 0.5 * (f[:-2] + f[2:])).sum()

    ratios = [comb(inter, i) / comb(clean, i) for i in range(len(clean))]
    assert np.median(ratios) > 1.2
    theta, _, _ = load_truth(inter.path)
    assert theta.effects == PAPER_EFFECTS  # not a candidate: nothing in the model's Θ


def test_the_stored_truth_re_renders_the_patches(tmp_path):
    """Independent paths agree: the frame-level camera vs. the patch model at the stored true Θ."""
    from synthaug.render.cache import ViewCache

    path = make_measured_seedset(tmp_path / "d", hidden={"defocus": {"defocus_sigma": 1.3}}, read_noise=0.0,
                                 paper_ranges={"sigma_n": (0.0, 0.0)}, **FAST)
    s = SeedSet.load(path)
    theta, extra, _ = load_truth(path)
    geo = seed_geometry(s)
    cache = ViewCache.build("quadcopter", step_deg=30, sprite_size=48)
    cov, nrm = cache.layers(theta.alpha.float(), theta.beta.float(), theta.gamma.float(), theta.t_x.float(),
                            theta.t_y.float(), size=40, object_scale=torch.tensor([e["object_scale"] for e in extra]))
    real = torch.tensor(s.patches / 255.0, dtype=torch.float32)[:, None]
    bg = torch.tensor(s.backgrounds / 255.0, dtype=torch.float32)[:, None]
    kw = dict(generator=torch.Generator().manual_seed(0), origin=geo["origin"], frame_size=geo["frame_size"],
              extras={"frame_scale": geo["frame_scale"]})
    # the patch is a resampled crop of the frame: its known resampling blur joins the defocus (Gaussians add)
    from synthaug.data.seedset import crop_resampling_sigma

    res = torch.from_numpy(crop_resampling_sigma(geo["frame_scale"].double().numpy())).float()
    t32 = theta.to(torch.float32)
    d = t32.as_dict()
    d["defocus_sigma"] = torch.sqrt(d["defocus_sigma"] ** 2 + res[:, None] ** 2)
    full = simulate(cov, nrm, bg, type(theta)(d, effects=theta.effects, validate=False), **kw)
    paper_only = simulate(cov, nrm, bg, theta.to(torch.float32), effects=PAPER_EFFECTS, **kw)
    err = lambda x: (x - real).abs().mean((1, 2, 3))  # noqa: E731
    assert (err(full) < 0.35 * err(bg) + 0.5 / 255).all()  # the truth explains the object (up to 8-bit rounding)
    assert err(full).mean() < 0.8 * err(paper_only).mean()  # and the hidden defocus is part of it
    # σ in patch px (clipped to the spec's range in the file; the records keep the raw value)
    np.testing.assert_allclose(theta.defocus_sigma[:, 0].numpy(), np.minimum(1.3 / geo["frame_scale"].numpy(), 3.0),
                               rtol=1e-5)
    raw = [r["truth"]["hidden_model"]["defocus"]["defocus_sigma"] for r in s.records]
    np.testing.assert_allclose(raw, 1.3 / geo["frame_scale"].numpy(), rtol=1e-5)


def test_deterministic_for_a_seed(tmp_path):
    kw = dict(FAST, n_seeds=3)
    a = SeedSet.load(make_measured_seedset(tmp_path / "a", hidden=["specular", "shot_noise"], **kw))
    b = SeedSet.load(make_measured_seedset(tmp_path / "b", hidden=["specular", "shot_noise"], **kw))
    c = SeedSet.load(make_measured_seedset(tmp_path / "c", hidden=["specular", "shot_noise"], **dict(kw, seed=6)))
    np.testing.assert_array_equal(a.patches, b.patches)
    np.testing.assert_array_equal(a.backgrounds, b.backgrounds)
    assert a.records == b.records
    assert (a.path / "truth.json").read_text() == (b.path / "truth.json").read_text()
    assert not np.array_equal(a.patches, c.patches)


def test_rolling_shutter_follows_the_motion_direction(tmp_path):
    s = SeedSet.load(make_measured_seedset(tmp_path / "rs", hidden=["rolling_shutter"], **dict(FAST, n_seeds=3)))
    for rec in s.records:
        t = rec["truth"]
        rs, a = t["hidden"]["rolling_shutter"], t["theta"]["alpha_m"]
        assert 0.06 <= rs["rs_magnitude"] <= 0.15
        assert rs["rs_skew"] == pytest.approx(rs["rs_magnitude"] * math.cos(a))
        assert rs["rs_stretch"] == pytest.approx(rs["rs_magnitude"] * math.sin(a))
        assert set(t["hidden_model"]["rolling_shutter"]) == {"rs_skew", "rs_stretch"}


def test_quadcopter_parts_and_mesh_perturbation():
    import trimesh

    mesh, rotor = quadcopter_parts()
    disc = trimesh.creation.cylinder(radius=0.17, height=0.008, sections=32)
    assert rotor.sum() == 4 * len(disc.faces)
    z = mesh.vertices[mesh.faces[rotor]].reshape(-1, 3)[:, 2]
    assert z.min() > mesh.vertices[mesh.faces[~rotor]].reshape(-1, 3)[:, 2].max() - 1e-9  # rotors on top
    p = perturb_mesh(mesh, 0.05, seed=2)
    d = p.vertices - mesh.vertices
    assert np.array_equal(p.faces, mesh.faces)
    assert 0.01 < np.linalg.norm(d, axis=1).max() <= 0.05 * 3 / math.sqrt(3) + 1e-9
    # smooth: Lipschitz along every edge (3 sinusoids of <= 3 cycles per unit, weight 1/sqrt(3))
    e = mesh.edges_unique
    lip = 0.05 * 3 * (2 * math.pi * 3) / math.sqrt(3)
    dv = np.linalg.norm(mesh.vertices[e[:, 0]] - mesh.vertices[e[:, 1]], axis=1)
    assert (np.linalg.norm(d[e[:, 0]] - d[e[:, 1]], axis=1) <= lip * dv + 1e-12).all()


@pytest.mark.slow
def test_a_perturbed_mesh_changes_the_object_not_the_scene(tmp_path, sets):
    pert = SeedSet.load(make_measured_seedset(tmp_path / "p", hidden={}, mesh_perturbation=0.08, **FAST))
    clean = sets["clean"]
    assert pert.metadata["reference_camera"]["mesh"].startswith("quadcopter perturbed 0.08")
    assert not np.array_equal(pert.patches, clean.patches)
    # same scene: the background frames are identical
    for i in range(len(clean)):
        np.testing.assert_array_equal(pert.background_frame(i), clean.background_frame(i))


def test_resolve_hidden_and_bad_inputs(tmp_path):
    assert resolve_hidden(["gamma"]) == {"gamma": REALISTIC_STRENGTHS["gamma"]}
    assert resolve_hidden({"haze": {"haze_amount": 0.2}}) == {"haze": {"haze_amount": 0.2, "haze_airlight": 0.85}}
    assert resolve_hidden(None) == {}
    # a setting the reference camera derives (auto-exposure) is replaced by the effect's own explicit value
    assert resolve_hidden({"exposure": {"exposure_gain": 0.9}}) == {"exposure": {"exposure_gain": 0.9,
                                                                                  "exposure_offset": 0.04}}
    assert resolve_hidden(["exposure"])["exposure"]["exposure_auto"] == 0.5
    with pytest.raises(ValueError, match="exposure_auto"):
        resolve_hidden({"exposure": {"exposure_auto": 3.0}})
    # the sensor's column pattern: a gain spread beyond 20 % is no camera's
    with pytest.raises(ValueError, match=r"hidden\['column_pattern'\]\['column_gain_sd'\] must be in \[0.0, 0.2\], got 0.5"):
        resolve_hidden({"column_pattern": {"column_gain_sd": 0.5}})
    with pytest.raises(ValueError, match=r"hidden\['column_pattern'\]: unknown parameter\(s\) \['pattern_seed'\]"):
        resolve_hidden({"column_pattern": {"pattern_seed": 3}})  # the camera's own stream, not a setting
    with pytest.raises(ValueError, match=r"unknown hidden effect\(s\) \['fog'\]"):
        resolve_hidden(["fog"])
    with pytest.raises(ValueError, match=r"hidden\['gamma'\]: unknown parameter\(s\) \['gamma'\]"):
        resolve_hidden({"gamma": {"gamma": 2.0}})
    with pytest.raises(ValueError, match=r"hidden\['vignetting'\]\['vignette_k'\] must be in \[0.0, 0.9\], got 1.5"):
        resolve_hidden({"vignetting": {"vignette_k": 1.5}})
    with pytest.raises(ValueError, match=r"must be a number or \(low, high\), got \(0.5, 0.1\)"):
        resolve_hidden({"rotor_blur": {"rotor_opacity": (0.5, 0.1)}})
    with pytest.raises(ValueError, match="got the string 'gamma'"):
        resolve_hidden("gamma")
    with pytest.raises(ValueError, match=r"frame_size \(40, 40\) is too small"):
        make_measured_seedset(tmp_path / "x", n_seeds=1, frame_size=(40, 40))
    with pytest.raises(ValueError, match="n_seeds must be >= 1, got 0"):
        make_measured_seedset(tmp_path / "x", n_seeds=0)
    with pytest.raises(ValueError, match="mesh_perturbation must be in"):
        make_measured_seedset(tmp_path / "x", n_seeds=1, mesh_perturbation=0.9, **{k: v for k, v in FAST.items()
                                                                                     if k != "n_seeds"})
    with pytest.raises(ValueError, match=r"paper_ranges: unknown parameter\(s\) \['sigma_x'\]"):
        make_measured_seedset(tmp_path / "x", n_seeds=1, paper_ranges={"sigma_x": (0, 1)})


def test_every_candidate_can_be_hidden(tmp_path):
    """Each candidate runs through the whole-frame camera and lands in the truth file."""
    from synthaug.effects.camera import CAMERA_EFFECTS

    hidden = {name: {} for name in CAMERA_EFFECTS}
    hidden.update(exposure={"exposure_gain": 0.8}, white_balance={"wb_gain": 0.9})  # all at once: no saturation
    path = make_measured_seedset(tmp_path / "all", hidden=hidden, **dict(FAST, n_seeds=2))
    theta, _, rc = load_truth(path)
    assert set(theta.effects) == set(PAPER_EFFECTS) | set(CAMERA_EFFECTS)
    assert set(rc["whole_frame"]) | set(rc["object_only"]) == set(CAMERA_EFFECTS)
    s = SeedSet.load(path)
    assert s.patches.std() > 5  # an image, not a blank
    CaptureParams.load(path / "truth.json")  # in range: loads with validation


def test_the_cameras_whole_frame_lens_keeps_the_frames_detail():
    # a lens maps the scene before the sensor samples it and blurs nothing: the camera's whole-frame distortion takes
    # the library's division map (lens_distortion_source) and resamples with a quintic spline. Checked: a smooth
    # frame lands where the library's bilinear warp puts it; a fine sinusoid (0.35 cycles/px) keeps its amplitude
    # within 3 % where the bilinear warp loses far more of it
    from synthaug.diagnose.reference_camera.capture import _lens_frame
    from synthaug.effects import camera_functional as Cx

    h, w, k = 96, 128, 0.1
    yy, xx = np.mgrid[:h, :w].astype(np.float64)
    smooth = torch.tensor(0.5 + 0.3 * np.sin(xx / 9.0) * np.cos(yy / 11.0))[None, None]
    ref = Cx.lens_distortion(smooth, k, recentre=False, border="border")
    assert (_lens_frame(smooth, k) - ref)[..., 8:-8, 8:-8].abs().max() < 2e-3
    fine = torch.tensor(0.5 + 0.2 * np.sin(2 * np.pi * 0.35 * xx))[None, None]
    # the map moves the columns by up to 5.7 px and changes their spacing by a few percent, not the amplitude
    amp = lambda img: float(img[0, 0, 40:56, 16:-16].std() * math.sqrt(2))  # noqa: E731
    spline = amp(_lens_frame(fine, k))
    bilinear = amp(Cx.lens_distortion(fine, k, recentre=False, border="border"))
    assert spline == pytest.approx(0.2, rel=0.03)
    assert bilinear < 0.9 * spline
