"""Candidate camera effects (issue 6) against independent numpy / scipy / OpenCV references."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
import torch
from scipy import ndimage

import synthaug.effects.camera  # noqa: F401  (registers the candidates)
from synthaug.effects import camera_functional as Cx
from synthaug.effects import functional as Fx
from synthaug.effects import PAPER_EFFECTS, simulate, sample_fields
from synthaug.effects.camera import CAMERA_EFFECTS
from synthaug.effects.registry import RenderState, get_effect, list_effects
from synthaug.params import CaptureParams


def _t(a):
    return torch.tensor(np.asarray(a, dtype=np.float64))


def _layers(b=2, h=32, w=32, c=1, seed=42):
    """A square object with a soft top edge, random colour and a random background."""
    rng = np.random.default_rng(seed)
    cov = np.zeros((b, 1, h, w))
    cov[:, :, 10:22, 8:24] = 1.0
    cov[:, :, 9, 8:24] = 0.5
    nrm = np.zeros((b, 3, h, w))
    nrm[:, 2] = 1.0
    nrm[:, 0, 10:22, 8:16] = 0.6  # two facets
    nrm[:, 2, 10:22, 8:16] = 0.8
    nrm = nrm * (cov > 0)
    color = np.where(cov > 0, 0.2 + 0.3 * rng.random((b, c, h, w)), 0.0)
    bg = rng.random((b, c, h, w)) * 0.5 + 0.4
    return cov, nrm, color, bg


def _frame_xy(b, h, w, origin, frame_size, scale):
    """Independent frame coordinates of patch pixels (numpy), normalised radius vector."""
    u = np.arange(w)[None, None, :]
    v = np.arange(h)[None, :, None]
    o = np.asarray(origin, float).reshape(b, 2)
    fs = np.asarray(frame_size, float).reshape(b, 2)
    s = np.asarray(scale, float).reshape(b)[:, None, None]
    x = o[:, 0, None, None] + (u + 0.5) * s - 0.5
    y = o[:, 1, None, None] + (v + 0.5) * s - 0.5
    cx, cy = (fs[:, 0] - 1) / 2, (fs[:, 1] - 1) / 2
    rad = 0.5 * np.hypot(fs[:, 0], fs[:, 1])
    dx = (x - cx[:, None, None]) / rad[:, None, None]
    dy = (y - cy[:, None, None]) / rad[:, None, None]
    return np.broadcast_to(dx, (b, h, w)), np.broadcast_to(dy, (b, h, w))


# ------------------------------------------------------------ registry / Θ
def test_all_candidates_register_with_unique_parameter_names():
    assert set(CAMERA_EFFECTS) <= set(list_effects())
    assert len(CAMERA_EFFECTS) == 14
    theta = CaptureParams.default(2, effects=PAPER_EFFECTS + CAMERA_EFFECTS)  # raises on a name clash
    names = theta.names
    assert len(names) == len(set(names))
    for name in CAMERA_EFFECTS:
        eff = get_effect(name)
        assert eff.params, name
        for spec in eff.params:
            assert spec.low <= spec.default <= spec.high, spec.name
            lo, hi = spec.sampling_range
            assert spec.low <= lo <= hi <= spec.high, spec.name


def _sim(theta, effects=None, seed=0, extras=None, origin=None, frame_size=None, c=1):
    cov, nrm, _, bg = _layers(b=theta.batch_size, c=c)
    return simulate(_t(cov), _t(nrm), _t(bg), theta, effects=effects, generator=torch.Generator().manual_seed(seed),
                    extras=extras, origin=origin, frame_size=frame_size, clamp=False)


@pytest.mark.parametrize("name", CAMERA_EFFECTS)
def test_neutral_parameters_are_the_identity_in_simulate(name):
    base = CaptureParams.sample(2, generator=torch.Generator().manual_seed(3))
    ext = CaptureParams(base.as_dict(), effects=PAPER_EFFECTS + (name,))  # the effect at its defaults
    origin = torch.tensor([[100.0, 60.0], [10.0, 200.0]])
    fsize = torch.tensor([[320.0, 256.0]] * 2)
    a = _sim(base, origin=origin, frame_size=fsize)
    b = _sim(ext, origin=origin, frame_size=fsize)
    tol = 2e-4 if name == "gamma" else 1e-6  # gamma: the ε = 1e-4 floor of the curve
    torch.testing.assert_close(b, a, atol=tol, rtol=0)


@pytest.mark.parametrize("name", CAMERA_EFFECTS)
def test_each_effect_changes_the_object_and_plugs_into_simulate(name):
    eff = get_effect(name)
    g = torch.Generator().manual_seed(7)
    theta = CaptureParams.sample(2, generator=g, effects=PAPER_EFFECTS + (name,))
    strong = {s.name: s.sampling_range[1] if s.default <= s.sampling_range[0] else s.sampling_range[0]
              for s in eff.params}
    if name == "compression":
        strong = {"jpeg_quality": 20.0}
    theta = theta.replace(**strong)
    origin = torch.tensor([[250.0, 190.0], [0.0, 0.0]])
    fsize = torch.tensor([[320.0, 256.0]] * 2)
    with_fx = _sim(theta, origin=origin, frame_size=fsize)
    without = _sim(theta, effects=PAPER_EFFECTS, origin=origin, frame_size=fsize)
    assert (with_fx - without).abs().amax() > 1e-3, f"{name} has no visible action at {strong}"
    assert torch.isfinite(with_fx).all()


# ------------------------------------------------------------ pointwise
def test_vignetting_matches_numpy_and_is_position_aware():
    b, h, w = 2, 20, 24
    x = _rand(b, 1, h, w)
    origin = np.array([[0.0, 0.0], [290.0, 230.0]])
    fsize = np.array([[320.0, 256.0]] * 2)
    scale = np.array([1.0, 1.25])
    k = np.array([0.3, 0.45])
    out = Cx.vignetting(_t(x), _t(k), origin=_t(origin), frame_size=_t(fsize), frame_scale=_t(scale)).numpy()
    dx, dy = _frame_xy(b, h, w, origin, fsize, scale)
    ref = x * np.clip(1 - k[:, None, None, None] * (dx ** 2 + dy ** 2)[:, None], 0, None)
    np.testing.assert_allclose(out, ref, atol=1e-12)
    # a patch cut from a vignetted frame = vignetting of the patch at its place in the frame
    frame = _rand(1, 1, 64, 80)
    vf = Cx.vignetting(_t(frame), _t([0.4])).numpy()
    patch = Cx.vignetting(_t(frame[..., 40:56, 60:76]), _t([0.4]), origin=_t([[60.0, 40.0]]),
                          frame_size=_t([[80.0, 64.0]])).numpy()
    np.testing.assert_allclose(patch, vf[..., 40:56, 60:76], atol=1e-12)
    # corners lose k of the light (pixel centres at the far corner of a large frame: r ≈ 1)
    big = Cx.vignetting(torch.ones(1, 1, 2, 2), _t([0.3]), origin=_t([[0.0, 0.0]]), frame_size=_t([[2000.0, 1600.0]]))
    assert abs(float(big[0, 0, 0, 0]) - 0.7) < 2e-3


def _rand(*shape, seed=0):
    return np.random.default_rng(seed).random(shape)


def test_exposure_white_balance_haze_match_numpy():
    x = _rand(2, 3, 5, 6)
    g, o = np.array([[1.2, 0.9, 1.0], [0.7, 1.1, 1.3]]), np.array([0.02, -0.04])
    np.testing.assert_allclose(Cx.exposure(_t(x), _t(g), _t(o)).numpy(),
                               x * g[..., None, None] + o[:, None, None, None], atol=1e-12)
    np.testing.assert_allclose(Cx.white_balance(_t(x), _t(g)).numpy(), x * g[..., None, None], atol=1e-12)
    h, a = np.array([0.3, 0.6]), np.array([0.9, 0.7])
    ref = x * (1 - h[:, None, None, None]) + (a * h)[:, None, None, None]
    np.testing.assert_allclose(Cx.haze(_t(x), _t(h), _t(a)).numpy(), ref, atol=1e-12)


@pytest.mark.parametrize("name,params,fn", [
    ("haze", {"haze_amount": 0.4, "haze_airlight": 0.9}, lambda v: 0.6 * v + 0.36),
    ("exposure", {"exposure_gain": 1.3, "exposure_offset": 0.05}, lambda v: 1.3 * v + 0.05),
])
def test_affine_object_effects_equal_the_whole_frame_camera(name, params, fn):
    """Affine T on the whole frame, background B = T(b): the object-stage effect is exact."""
    cov, nrm, color, b = _layers(b=1)
    cov = ndimage.gaussian_filter(cov, (0, 0, 1.2, 1.2))  # partial coverage everywhere on the edge
    theta = CaptureParams({"w_d": 0.6, **params}, effects=("material", name))
    out = simulate(_t(cov), _t(nrm), _t(fn(b)), theta, clamp=False).numpy()
    obj = Fx.diffuse_material(_t(nrm), _t(cov), _t([0.6])).numpy()
    camera = fn(obj * cov + b * (1 - cov))
    np.testing.assert_allclose(out, camera, atol=1e-12)


def test_gamma_composite_is_exact_through_the_real_background():
    cov, _, color, b = _layers(b=2)
    cov = ndimage.gaussian_filter(cov, (0, 0, 1.0, 1.0))
    g = np.array([0.7, 1.4])
    big_b = b ** g[:, None, None, None]  # the real background went through the tone curve
    comp = color * cov + big_b * (1 - cov)
    out = Cx.gamma_composite(_t(comp), _t(cov), _t(big_b), _t(g)).numpy()
    ref = (color * cov + b * (1 - cov)) ** g[:, None, None, None]  # camera of the linear scene
    np.testing.assert_allclose(out, ref, atol=1e-9)
    # where the object adds nothing, the background comes back unchanged
    np.testing.assert_allclose(out[cov == 0], big_b[cov == 0], atol=1e-9)


# ------------------------------------------------------------ object layer
def test_specular_matches_blinn_phong_in_numpy():
    rng = np.random.default_rng(1)
    n = rng.normal(size=(2, 3, 6, 7))
    n[:, 2] = np.abs(n[:, 2])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    cov = np.ones((2, 1, 6, 7))
    cov[:, :, 0] = 0
    ks, p = np.array([0.4, 0.8]), np.array([10.0, 50.0])
    light = np.array([0.2, 0.5, 0.8])
    out = Cx.specular_highlight(_t(n), _t(cov), _t(ks), _t(p), light_dir=tuple(light)).numpy()
    l = light / np.linalg.norm(light)
    hv = l + np.array([0, 0, 1.0])
    hv /= np.linalg.norm(hv)
    nh = np.clip(np.einsum("bchw,c->bhw", n, hv), 0, None)
    ref = ks[:, None, None] * nh ** p[:, None, None] * (cov[:, 0] > 0)
    np.testing.assert_allclose(out[:, 0], ref, atol=1e-12)


def test_rotor_blur_with_a_part_layer_and_the_extremity_approximation():
    cov = np.zeros((1, 1, 41, 41))
    cov[0, 0, 18:23, 4:37] = 1  # a cross: body and arms ...
    cov[0, 0, 4:37, 18:23] = 1
    rotor = np.zeros_like(cov)
    for cy, cx in ((6, 20), (34, 20), (20, 6), (20, 34)):  # ... with rotor discs at the tips
        yy, xx = np.mgrid[:41, :41]
        rotor[0, 0][(yy - cy) ** 2 + (xx - cx) ** 2 <= 9] = 1
    cov = np.maximum(cov, rotor)
    out = Cx.rotor_blur(_t(cov), _t([0.3]), _t(rotor)).numpy()
    np.testing.assert_allclose(out, cov - 0.7 * rotor, atol=1e-12)
    approx = Cx.rotor_blur(_t(cov), _t([0.3])).numpy()
    assert approx[0, 0, 20, 20] == 1.0  # body untouched
    assert approx[0, 0, 5, 20] < 0.35 and approx[0, 0, 20, 35] < 0.35  # tips nearly at ρ
    w = Cx.rotor_weight(_t(cov)).numpy()[0, 0]
    assert (w[rotor[0, 0] > 0] > 0.5).mean() > 0.6  # the extremities weigh ...
    assert w[16:25, 16:25].max() == 0.0 and 0.0 <= w.min() and w.max() <= 1.0  # ... the body centre does not
    np.testing.assert_allclose(Cx.rotor_blur(_t(cov), _t([1.0])).numpy(), cov, atol=0)


def test_rolling_shutter_matches_scipy_affine_transform():
    cov, _, color, _ = _layers(b=2, h=40, w=40)
    sk, st = np.array([0.3, -0.2]), np.array([0.1, -0.15])
    col_o, cov_o = Cx.rolling_shutter(_t(color), _t(cov), _t(sk), _t(st))
    yc = 39 / 2
    for b in range(2):
        mat = np.array([[1 / (1 + st[b]), 0.0], [-sk[b], 1.0]])  # output (row, col) -> input
        off = np.array([yc - yc / (1 + st[b]), sk[b] * yc])
        kw = dict(order=1, mode="grid-constant", cval=0.0)
        ref_cov = ndimage.affine_transform(cov[b, 0], mat, offset=off, **kw)
        ref_pre = ndimage.affine_transform(color[b, 0] * cov[b, 0], mat, offset=off, **kw)
        np.testing.assert_allclose(cov_o[b, 0].numpy(), ref_cov, atol=1e-9)
        np.testing.assert_allclose((col_o * cov_o)[b, 0].numpy(), ref_pre, atol=1e-9)


# ------------------------------------------------------------ linear spatial
def test_defocus_and_sharpening_act_on_the_object_difference_layer():
    cov, nrm, color, _ = _layers(b=1, h=40, w=40)
    b_const = np.full((1, 1, 40, 40), 0.7)  # constant background: b = L(b), so the effect is exact
    scene = color * cov + b_const * (1 - cov)
    for name, params, ref_fn in (
        ("defocus", {"defocus_sigma": 1.3},
         lambda x: ndimage.gaussian_filter(x, 1.3, mode="nearest", truncate=8)),
        ("sharpening", {"sharpen_amount": 1.2, "sharpen_sigma": 1.1},
         lambda x: x + 1.2 * (x - ndimage.gaussian_filter(x, 1.1, mode="nearest", truncate=8))),
    ):
        state = RenderState(object_color=_t(color), coverage=_t(cov), normals=_t(nrm), background=_t(b_const),
                            image=_t(scene))
        eff = get_effect(name)
        out = eff.apply(state, **{k: _t([[v]]) for k, v in params.items()}).image.numpy()
        np.testing.assert_allclose(out[0, 0], ref_fn(scene[0, 0]), atol=2e-4)  # FFT (band-limited) vs sampled kernel
    # with a textured background: out = B + L(I - B), background far from the object untouched
    _, _, _, bg = _layers(b=1, h=40, w=40)
    img = color * cov + bg * (1 - cov)
    state = RenderState(object_color=_t(color), coverage=_t(cov), normals=_t(nrm), background=_t(bg), image=_t(img))
    out = get_effect("defocus").apply(state, defocus_sigma=_t([[1.0]])).image.numpy()
    ref = bg + ndimage.gaussian_filter((img - bg)[0, 0], 1.0, mode="constant", truncate=8)
    np.testing.assert_allclose(out, ref, atol=1e-3)  # band-limited FFT Gaussian vs sampled kernel
    assert np.abs(out - bg)[..., :3, :].max() < 1e-4  # far from the object: ~unchanged


def _map_coords(img, src_x, src_y):
    return ndimage.map_coordinates(img, [src_y, src_x], order=1, mode="grid-constant", cval=0.0)


def test_chromatic_aberration_matches_scipy_resampling():
    h, w = 24, 28
    img = np.zeros((1, 3, h, w))
    img[0, :, 8:16, 10:18] = _rand(3, 8, 8)
    origin, fsize, scale = np.array([[280.0, 220.0]]), np.array([[320.0, 256.0]]), np.array([1.5])
    shift = np.array([[2.0, 2.0, 2.5]])
    out = Cx.chromatic_aberration(_t(img), _t(shift), origin=_t(origin), frame_size=_t(fsize),
                                  frame_scale=_t(scale)).numpy()
    dx, dy = _frame_xy(1, h, w, origin, fsize, scale)
    uu, vv = np.meshgrid(np.arange(w), np.arange(h))
    for c, s in enumerate((1.0, 0.0, -1.0)):
        d = s * shift[0, c] / scale[0]
        ref = _map_coords(img[0, c], uu - d * dx[0], vv - d * dy[0])
        np.testing.assert_allclose(out[0, c], ref, atol=1e-9)
    # grayscale: the luma mix of the displaced planes, a radial blur
    gray = Cx.chromatic_aberration(_t(img[:, 1:2]), _t([2.0]), origin=_t(origin), frame_size=_t(fsize),
                                   frame_scale=_t(scale)).numpy()
    ref = sum(wt * _map_coords(img[0, 1], uu - s * 2.0 / 1.5 * dx[0], vv - s * 2.0 / 1.5 * dy[0])
              for wt, s in zip(Cx.LUMA_WEIGHTS, (1.0, 0.0, -1.0)))
    np.testing.assert_allclose(gray[0, 0], ref, atol=1e-9)


def _blob_centroids(img, centres, r=5):
    out = []
    for cx, cy in centres:
        x0, y0 = int(round(cx)), int(round(cy))
        win = img[y0 - r:y0 + r + 1, x0 - r:x0 + r + 1]
        yy, xx = np.mgrid[y0 - r:y0 + r + 1, x0 - r:x0 + r + 1]
        out.append(((win * xx).sum() / win.sum(), (win * yy).sum() / win.sum()))
    return np.array(out)


def _distort(u, k):
    """Image position of scene points u (N, 2) under the division model, by root finding (scipy)."""
    from scipy.optimize import brentq

    out = []
    for pt in u:
        ru = float(np.hypot(*pt))
        if ru == 0:
            out.append(pt)
            continue
        rd = brentq(lambda r: r / (1 + k * r * r) - ru, 0.0, 1.5)
        out.append(pt * rd / ru)
    return np.array(out)


def test_lens_distortion_moves_points_by_the_division_model():
    h, w, k = 128, 160, -0.2
    pts = np.array([[20.0, 20.0], [140.0, 30.0], [80.0, 64.0], [40.0, 100.0], [120.0, 110.0], [60.0, 40.0]])
    yy, xx = np.mgrid[:h, :w]
    img = sum(np.exp(-((xx - px) ** 2 + (yy - py) ** 2) / (2 * 1.2 ** 2)) for px, py in pts)
    out = Cx.lens_distortion(_t(img[None, None]), _t([k]), recentre=False, border="zeros").numpy()[0, 0]
    c = np.array([(w - 1) / 2, (h - 1) / 2])
    rad = 0.5 * math.hypot(w, h)
    expected = c + rad * _distort((pts - c) / rad, k)
    got = _blob_centroids(out, expected)
    np.testing.assert_allclose(got, expected, atol=0.1)
    assert np.abs(expected - pts).max() > 2  # barrel: points moved toward the centre
    assert (np.hypot(*(expected - c).T) < np.hypot(*(pts - c).T) + 1e-9).all()


def test_lens_distortion_patch_form_follows_the_model_about_the_patch_centre():
    """Blobs in a patch move as the division model predicts, about the patch centre, with the
    local isotropic magnification divided out (reference: scipy root finding + numerical Jacobian)."""
    p, k, scale = 41, -0.25, 1.5
    fsize = np.array([640.0, 480.0])
    origin = np.array([560.0, 30.0])  # top-right region of the frame
    yy, xx = np.mgrid[:p, :p]
    offs = np.array([(0.0, 0.0), (9.0, 0.0), (0.0, 9.0), (-7.0, 7.0), (8.0, -8.0)])
    img = sum(np.exp(-((xx - 20 - ox) ** 2 + (yy - 20 - oy) ** 2) / (2 * 1.0 ** 2)) for ox, oy in offs)
    out = Cx.lens_distortion(_t(img[None, None]), _t([k]), origin=_t(origin[None]), frame_size=_t(fsize[None]),
                             frame_scale=_t([scale])).numpy()[0, 0]
    c = (fsize - 1) / 2
    rad = 0.5 * np.hypot(*fsize)
    p0 = (origin + (p / 2) * scale - 0.5 - c) / rad  # patch centre (image), normalised
    und = lambda q: q / (1 + k * (q ** 2).sum(-1, keepdims=True))  # noqa: E731
    eps = 1e-6
    jac = np.stack([(und(p0 + eps * e) - und(p0 - eps * e)) / (2 * eps) for e in np.eye(2)], 1)
    f = 1 / math.sqrt(np.linalg.det(jac))
    u = und(p0) + offs * scale / rad  # scene positions of the blobs
    expected = 20 + (_distort(u, k) - p0) * rad / scale / f
    got = _blob_centroids(out, expected, r=4)
    np.testing.assert_allclose(got, expected, atol=0.1)
    assert np.abs(got[0] - 20).max() < 0.02  # the centre stays put
    assert np.abs(expected[1:] - 20 - offs[1:]).max() > 0.5  # and the shape really changed


# ------------------------------------------------------------ noise / codec
def test_shot_noise_variance_grows_with_intensity():
    img = np.concatenate([np.full((1, 1, 100, 100), 0.1), np.full((1, 1, 100, 100), 0.8)], 0)
    cov = np.ones_like(img)
    cov[..., :10] = 0
    noise = torch.randn(img.shape, generator=torch.Generator().manual_seed(0), dtype=torch.float64)
    out = Cx.shot_noise(_t(img), _t(cov), _t([0.05, 0.05]), noise).numpy()
    ref = img + 0.05 * np.sqrt(img + 1e-8) * noise.numpy() * cov
    np.testing.assert_allclose(out, ref, atol=1e-12)
    assert np.array_equal(out[..., :10], img[..., :10])
    var = (out - img)[..., 10:].reshape(2, -1).var(1)
    np.testing.assert_allclose(var / np.array([0.1, 0.8]), 0.05 ** 2, rtol=0.1)


@pytest.mark.parametrize("quality", [25, 50, 85])
def test_jpeg_quantize_matches_opencv(quality):
    rng = np.random.default_rng(quality)
    img = ndimage.gaussian_filter(rng.random((64, 80)), 1.5)
    img = (img - img.min()) / (img.max() - img.min())
    u8 = np.round(img * 255).astype(np.uint8)
    ok, buf = cv2.imencode(".jpg", u8, [cv2.IMWRITE_JPEG_QUALITY, quality])
    ref = cv2.imdecode(buf, cv2.IMREAD_GRAYSCALE).astype(float)
    mine = Cx.jpeg_quantize(_t(u8[None, None] / 255.0), _t([float(quality)])).numpy()[0, 0] * 255
    artefact = np.abs(ref - u8).mean()
    assert artefact > 0.5
    assert np.abs(mine - ref).mean() < 0.25 * artefact + 0.2
    assert np.corrcoef((mine - u8).ravel(), (ref - u8).ravel())[0, 1] > 0.9


def test_dct_matrix_is_scipys_orthonormal_dct_ii():
    from scipy.fft import dctn

    block = np.random.default_rng(3).normal(size=(8, 8))
    d = Cx.dct_matrix(torch.float64).numpy()
    np.testing.assert_allclose(d @ block @ d.T, dctn(block, type=2, norm="ortho"), atol=1e-12)
    np.testing.assert_allclose(d @ d.T, np.eye(8), atol=1e-12)


def test_jpeg_block_phase_aligns_a_crop_with_the_frame_grid():
    frame = _rand(1, 1, 48, 56)
    full = Cx.jpeg_quantize(_t(frame), _t([40.0])).numpy()
    oy, ox = 11, 21  # crop origin; the crop's first full block starts at (16, 24) in the frame
    crop = frame[..., oy:oy + 30, ox:ox + 30]
    q = Cx.jpeg_quantize(_t(crop), _t([40.0]), phase=(oy % 8, ox % 8)).numpy()
    np.testing.assert_allclose(q[..., 16 - oy:40 - oy, 24 - ox:48 - ox], full[..., 16:40, 24:48], atol=1e-9)
    assert np.array_equal(Cx.jpeg_quantize(_t(crop), _t([100.0])).numpy(), crop)


def test_compression_effect_leaves_object_free_blocks_untouched():
    cov, nrm, color, bg = _layers(b=1, h=40, w=40)
    img = color * cov + bg * (1 - cov)  # object in rows 9..21, cols 8..23
    state = RenderState(object_color=_t(color), coverage=_t(cov), normals=_t(nrm), background=_t(bg), image=_t(img))
    out = get_effect("compression").apply(state, jpeg_quality=_t([[30.0]])).image.numpy()
    np.testing.assert_allclose(out[..., 24:, :], bg[..., 24:, :], atol=1e-12)
    np.testing.assert_allclose(out[..., :, 24:], bg[..., :, 24:], atol=1e-12)
    assert np.abs(out - img)[..., 8:24, 8:24].max() > 0.01


# ------------------------------------------------------------ generic properties
def _functional_calls(b, seed=0):
    """(name, fn(params...), params) for every pure function, on a batch of b."""
    cov, nrm, color, bg = _layers(b=b, h=24, w=24, seed=seed)
    cov = ndimage.gaussian_filter(cov, (0, 0, 1, 1))  # smooth alpha: no kinks
    img = color * cov + bg * (1 - cov)
    cov_t, nrm_t, color_t, bg_t, img_t = (_t(a) for a in (cov, nrm, color, bg, img))
    noise = torch.randn(img_t.shape, generator=torch.Generator().manual_seed(1), dtype=torch.float64)
    origin = _t([[200.0 + 10 * i, 150.0 - 7 * i] for i in range(b)])
    fsize = _t([[320.0, 256.0]] * b)
    scale = _t([1.2 + 0.1 * i for i in range(b)])
    geo = dict(origin=origin, frame_size=fsize, frame_scale=scale)
    v = lambda *x: _t([list(x)] * b)  # noqa: E731
    return [
        ("vignetting", lambda k: Cx.vignetting(img_t, k, **geo), (v(0.3),)),
        ("exposure", lambda g, o: Cx.exposure(color_t, g, o), (v(1.2), v(0.03))),
        ("white_balance", lambda g: Cx.white_balance(color_t, g), (v(1.1),)),
        ("haze", lambda h, a: Cx.haze(color_t, h, a), (v(0.3), v(0.8))),
        ("gamma", lambda g: Cx.gamma_composite(img_t, cov_t, bg_t, g), (v(0.8),)),
        ("specular", lambda k, p: Cx.specular_highlight(nrm_t, cov_t, k, p), (v(0.5), v(20.0))),
        ("rotor_blur", lambda r: Cx.rotor_blur(cov_t, r), (v(0.4),)),
        ("rolling_shutter", lambda s, t: torch.cat(Cx.rolling_shutter(color_t, cov_t, s, t), 1), (v(0.2), v(0.05))),
        ("defocus", lambda s: Cx.defocus(img_t - bg_t, s, pad=6), (v(1.1),)),
        ("sharpening", lambda a, s: Cx.unsharp_mask(img_t - bg_t, a, s, pad=6), (v(0.8), v(1.0))),
        ("chromatic_aberration", lambda s: Cx.chromatic_aberration(img_t - bg_t, s, **geo), (v(1.5),)),
        ("lens_distortion", lambda k: Cx.lens_distortion(img_t - bg_t, k, **geo), (v(-0.15),)),
        ("shot_noise", lambda s: Cx.shot_noise(img_t, cov_t, s, noise), (v(0.05),)),
        ("compression", lambda q: Cx.jpeg_quantize(img_t, q), (v(40.0),)),
    ]


def test_gradcheck_every_continuous_parameter():
    for name, fn, params in _functional_calls(1):
        if name == "compression":
            continue  # quality is piecewise constant (quantisation steps)
        params = tuple(p.clone().requires_grad_(True) for p in params)
        assert torch.autograd.gradcheck(fn, params, atol=1e-5), name


def test_compression_passes_image_gradients_straight_through():
    x = _t(_rand(1, 1, 16, 16)).requires_grad_(True)
    Cx.jpeg_quantize(x, _t([50.0])).sum().backward()
    torch.testing.assert_close(x.grad, torch.ones_like(x))


def test_batched_equals_single_and_inputs_untouched():
    for name, fn, params in _functional_calls(3):  # pure functions never write into their inputs
        before = [p.clone() for p in params]
        fn(*params)
        for p, q in zip(params, before):
            assert torch.equal(p, q), name
    # every effect at once, batch of 3 vs one sample at a time (different positions and scales)
    g = torch.Generator().manual_seed(11)
    effects = PAPER_EFFECTS + CAMERA_EFFECTS
    theta = CaptureParams.sample(3, generator=g, effects=effects)
    cov, nrm, _, bg = _layers(b=3)
    cov_t, nrm_t, bg_t = _t(cov), _t(nrm), _t(bg)
    copies = [t.clone() for t in (cov_t, nrm_t, bg_t)]
    fields = sample_fields(effects, tuple(bg_t.shape), torch.Generator().manual_seed(2), dtype=torch.float64)
    origin = _t([[10.0, 20.0], [200.0, 100.0], [40.0, 180.0]])
    fsize = _t([[320.0, 256.0]] * 3)
    extras = {"frame_scale": _t([1.0, 1.3, 0.8])}
    out = simulate(cov_t, nrm_t, bg_t, theta, fields=fields, origin=origin, frame_size=fsize, extras=extras)
    for t, c in zip((cov_t, nrm_t, bg_t), copies):
        assert torch.equal(t, c)
    for k in range(3):
        one = simulate(cov_t[k:k + 1], nrm_t[k:k + 1], bg_t[k:k + 1], theta[k],
                       fields={n: f[k:k + 1] for n, f in fields.items()}, origin=origin[k:k + 1],
                       frame_size=fsize[k:k + 1], extras={"frame_scale": extras["frame_scale"][k:k + 1]})
        torch.testing.assert_close(one[0], out[k], atol=1e-9, rtol=0)


def test_empty_batch():
    e = torch.zeros(0, 1, 10, 10)
    z = torch.zeros(0)
    assert Cx.vignetting(e, z).shape == e.shape
    assert Cx.gamma_composite(e, e, e, z).shape == e.shape
    assert Cx.jpeg_quantize(e, z).shape == e.shape
    assert Cx.rolling_shutter(e, e, z, z)[0].shape == e.shape
    assert Cx.defocus(e, z, pad=3).shape == e.shape


def test_bad_inputs_name_the_value():
    x = torch.zeros(1, 1, 8, 8)
    with pytest.raises(ValueError, match="give both origin and frame_size"):
        Cx.vignetting(x, torch.zeros(1), origin=torch.zeros(1, 2))
    with pytest.raises(ValueError, match=r"frame_scale must be > 0, got \[-1.0\]"):
        Cx.vignetting(x, torch.zeros(1), origin=torch.zeros(1, 2), frame_size=torch.ones(1, 2),
                      frame_scale=-torch.ones(1))
    with pytest.raises(ValueError, match="chromatic_aberration needs 1 or 3 channels, got 2"):
        Cx.chromatic_aberration(torch.zeros(1, 2, 8, 8), torch.zeros(1))
    with pytest.raises(ValueError, match="noise must have the image's shape"):
        Cx.shot_noise(x, x, torch.zeros(1), torch.zeros(1, 1, 4, 4))
    with pytest.raises(ValueError, match=r"image must be \(B, C, H, W\)"):
        Cx.exposure(torch.zeros(8, 8), 1.0, 0.0)
    with pytest.raises(ValueError, match="jpeg_quality: expected shape"):
        Cx.jpeg_quantize(x, torch.zeros(3))
    with pytest.raises(ValueError, match="border must be 'zeros' or 'border', got 'wrap'"):
        Cx.lens_distortion(x, torch.zeros(1), border="wrap")
    with pytest.raises(ValueError, match=r"gamma_g \(g\) must be in \[0.4, 2.5\]"):
        CaptureParams({"gamma_g": 3.0}, effects=PAPER_EFFECTS + ("gamma",))
    state = RenderState(object_color=x, coverage=x, normals=torch.zeros(1, 3, 8, 8), background=x)
    with pytest.raises(ValueError, match="image-stage effect"):
        get_effect("defocus").apply(state, defocus_sigma=torch.ones(1, 1))
    with pytest.raises(ValueError, match="needs a 'shot_noise' field"):
        get_effect("shot_noise").apply(state.replace(image=x), shot_sigma=torch.ones(1, 1))


def test_rgb_effects_are_per_channel():
    """With C = 3 each channel has its own parameter (the paper's RGB extension)."""
    g = torch.Generator().manual_seed(4)
    effects = PAPER_EFFECTS + ("white_balance", "vignetting", "defocus")
    theta = CaptureParams.sample(1, generator=g, channels=3, effects=effects)
    cov, nrm, _, bg = _layers(b=1, c=3)
    fields = sample_fields(effects, (1, 3, 32, 32), g, dtype=torch.float64)
    rgb = simulate(_t(cov), _t(nrm), _t(bg), theta, fields=fields)
    for c in range(3):
        gray = CaptureParams({n: (v[:, c] if v.ndim == 2 else v) for n, v in theta.as_dict().items()}, effects=effects)
        one = simulate(_t(cov), _t(nrm), _t(bg[:, c:c + 1]), gray, fields={k: f[:, c:c + 1] for k, f in fields.items()})
        torch.testing.assert_close(rgb[:, c:c + 1], one, atol=1e-9, rtol=0)


def test_jpeg_on_the_frame_grid_matches_opencv_through_a_crop():
    """A crop at an offset that is not a multiple of 8: the coding error of OpenCV's JPEG of the whole frame is
    reproduced on the frame's grid, not on the patch's."""
    import cv2

    from synthaug.effects.camera_functional import jpeg_difference_on_frame_grid, jpeg_quantize

    yy, xx = np.mgrid[0:96, 0:128]
    bg = 0.5 + 0.1 * np.sin(xx / 9.0) + 0.05 * np.cos(yy / 7.0)
    fr = bg.copy()
    fr[40:66, 50:83] = 0.15

    def coded(a):
        u8 = np.round(a * 255).astype(np.uint8)
        return cv2.imdecode(cv2.imencode(".jpg", u8, [cv2.IMWRITE_JPEG_QUALITY, 40])[1], 0) / 255.0, u8 / 255.0

    (jf, f), (jb, b) = coded(fr), coded(bg)
    x0, y0, p = 37, 29, 48
    cut = lambda a: torch.tensor(a[y0:y0 + p, x0:x0 + p])[None, None]  # noqa: E731
    target = cut(jf) - cut(f) - (cut(jb) - cut(b))  # the object's coding error, as the patch sees it
    img = cut(f) - cut(b) + cut(jb)
    bgp = cut(jb)
    model = jpeg_difference_on_frame_grid(img, bgp, 40.0, origin=torch.tensor([[float(x0), float(y0)]]),
                                          frame_scale=torch.tensor([1.0])) - img
    patch_grid = jpeg_quantize(img, 40.0) - jpeg_quantize(bgp, 40.0) + bgp - img
    corr = lambda a, c: float(np.corrcoef(a.flatten().numpy(), c.flatten().numpy())[0, 1])  # noqa: E731
    assert corr(model, target) > 0.8
    assert corr(patch_grid, target) < 0.6
    # quality 100 is off; a batch of mixed scales keeps its shape
    two = torch.rand(2, 1, 20, 20, dtype=torch.float64)
    out = jpeg_difference_on_frame_grid(two, two.flip(0), torch.tensor([100.0, 40.0]),
                                        origin=torch.tensor([[3.5, 7.0], [10.0, 1.0]]),
                                        frame_scale=torch.tensor([1.4, 0.7]))
    assert out.shape == two.shape and torch.equal(out[0], two[0])
    with pytest.raises(ValueError, match="frame_scale"):
        jpeg_difference_on_frame_grid(two, two, 40.0, origin=torch.zeros(2, 2), frame_scale=torch.tensor([1.0, 0.0]))


def test_jpeg_on_the_frame_grid_codes_each_seed_alone_whatever_its_batch():
    # a seed's coding on the frame's grid is its own: the same to the bit alone and beside crops 1x to 12x its
    # size (the canvas was the batch's largest crop's before stop 113: a 100-seed real set coded 25x the blocks, and
    # a seed's pixels moved with its neighbours' sizes)
    from synthaug.effects.camera_functional import jpeg_difference_on_frame_grid

    g = torch.Generator().manual_seed(0)
    img = torch.rand(4, 1, 24, 24, generator=g)
    bg = torch.rand(4, 1, 24, 24, generator=g)
    origin = torch.tensor([[13.0, 5.5], [200.2, 90.0], [3.0, 300.7], [57.5, 41.0]])
    scale = torch.tensor([0.8, 12.0, 2.5, 1.1])
    q = torch.tensor([30.0, 50.0, 70.0, 40.0])
    batch = jpeg_difference_on_frame_grid(img, bg, q, origin=origin, frame_scale=scale)
    for i in range(4):
        alone = jpeg_difference_on_frame_grid(img[i:i + 1], bg[i:i + 1], q[i:i + 1], origin=origin[i:i + 1],
                                              frame_scale=scale[i:i + 1])
        assert torch.equal(batch[i:i + 1], alone)
    assert not torch.equal(batch, img)  # the coding did something
