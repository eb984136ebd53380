"""Patterns fixed in the frame (synthaug.diagnose.frame_pattern) against hand-made frames and known nulls."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from synthaug.diagnose.frame_pattern import (
    block_grid,
    falloff_k,
    fixed_line_pattern,
    frame_summary,
    line_profiles,
    radial_falloff,
    scene_clusters,
)


def test_line_profiles_against_a_hand_computed_frame():
    f = np.full((30, 50), 100, np.uint8)
    f[:, 20] = 120  # one brighter column
    f[5:15, 30:40] = 250  # the object's square, left out
    p = line_profiles(f, exclude=(30, 5, 10), high_pass=5)
    m = np.log(np.full(50, 100 / 255.0))
    m[20] = np.log(120 / 255.0)
    # the local quadratic over 5 px (Savitzky-Golay's hand-tabled weights); the ends are flat, so exact there too
    quad = m.copy()
    quad[2:-2] = np.convolve(m, np.array([-3, 12, 17, 12, -3]) / 35.0, mode="valid")
    np.testing.assert_allclose(p["x"], m - quad, atol=1e-12)
    # every row has the same mean once the object's square is left out: the row profile is flat
    assert np.abs(p["y"]).max() < 1e-3
    # colour: the mean of the channels
    np.testing.assert_allclose(line_profiles(np.dstack([f, f, f]), exclude=(30, 5, 10), high_pass=5)["x"], p["x"])
    with pytest.raises(ValueError, match="shape"):
        line_profiles(np.zeros((2, 3, 4, 5)))


def test_identical_profiles_agree_fully_and_opposite_ones_disagree():
    rng = np.random.default_rng(0)
    g = rng.standard_normal(64)
    out = fixed_line_pattern([g, g, g], ["a", "b", "c"], np.random.default_rng(1), n_perm=199)
    assert out["rho"] == pytest.approx(1.0)
    np.testing.assert_allclose(out["pattern"], g)
    assert out["amplitude"] == pytest.approx(g.std())
    # two videos, one the negative of the other: agreement -1
    assert fixed_line_pattern([g, -g], ["a", "b"], np.random.default_rng(1), n_perm=99)["rho"] == pytest.approx(-1.0)


def test_seeds_of_one_video_are_averaged_and_other_sizes_left_out():
    rng = np.random.default_rng(2)
    a, b = rng.standard_normal(40), rng.standard_normal(40)
    out = fixed_line_pattern([a, a + 0.0, b, rng.standard_normal(30)], ["v1", "v1", "v2", "v3"],
                             np.random.default_rng(0), n_perm=99)
    # v3's frames have another size: only v1 (mean a) and v2 (b) are compared, by hand
    expect = float(a @ b / (0.5 * (a @ a + b @ b)))
    assert out["groups"] == 2 and out["seeds"] == 3 and out["length"] == 40
    assert out["rho"] == pytest.approx(expect)
    # fewer than two videos: nothing to compare
    assert fixed_line_pattern([a, b], ["v1", "v1"], np.random.default_rng(0)) is None
    assert fixed_line_pattern([], [], np.random.default_rng(0)) is None


def test_null_p_values_are_uniform():
    # videos whose profiles share nothing: the permutation p-value is uniform (a calibrated test)
    rng = np.random.default_rng(3)
    ps = []
    for _ in range(300):
        prof = [rng.standard_normal(96) for _ in range(8)]
        ps.append(fixed_line_pattern(prof, [i % 4 for i in range(8)], rng, n_perm=199)["p"])
    ps = np.array(ps)
    assert stats.kstest(ps, "uniform").pvalue > 0.01
    assert 0.03 <= float(np.mean(ps < 0.1)) <= 0.17  # binomial(300, 0.1): 0.1 +- 4 sd


def test_a_shared_pattern_is_found_among_strong_scene_structure():
    # each video's own scene structure (twice the pattern's amplitude, fixed within the video) hides a 1 % gain
    # pattern in any one frame; the agreement across videos finds it, and its estimate follows the truth
    rng = np.random.default_rng(4)
    gain = 0.01 * rng.standard_normal(256)
    scenes = [0.02 * rng.standard_normal(256) for _ in range(6)]
    prof = [scenes[i % 6] + gain + 0.002 * rng.standard_normal(256) for i in range(36)]
    out = fixed_line_pattern(prof, [i % 6 for i in range(36)], np.random.default_rng(5), n_perm=999)
    assert out["p"] < 0.01 and 0.05 < out["rho"] < 0.5  # about 1 / (1 + 2^2)
    assert np.corrcoef(out["pattern"], gain)[0, 1] > 0.4
    # without the pattern: no finding
    prof0 = [scenes[i % 6] + 0.002 * rng.standard_normal(256) for i in range(36)]
    assert fixed_line_pattern(prof0, [i % 6 for i in range(36)], np.random.default_rng(5), n_perm=999)["p"] > 0.01


def test_a_periodic_pattern_gets_its_period():
    rng = np.random.default_rng(6)
    x = np.arange(256)
    gain = 0.01 * (x % 8 == 0)  # a jump every 8 columns (a block grid)
    prof = [gain - gain.mean() + 0.003 * rng.standard_normal(256) for _ in range(10)]
    out = fixed_line_pattern(prof, list(range(10)), np.random.default_rng(0), n_perm=199)
    assert out["period_px"] == pytest.approx(8.0) and out["peak_ratio"] > 20
    white = fixed_line_pattern([0.01 * rng.standard_normal(256)] * 4, list(range(4)), np.random.default_rng(0),
                               n_perm=99)
    assert white["peak_ratio"] < 20


# ------------------------------------------------------------------ radial fall-off (vignetting)
def _frame_grid(h: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    radius = 0.5 * np.hypot(w, h)  # r = 1 at the corners, as the camera's vignetting
    return (xx - (w - 1) / 2) / radius, (yy - (h - 1) / 2) / radius


def test_frame_summary_recovers_an_exact_log_quadratic_frame():
    # log I = a + b dx + c dy - s r² exactly: the row-wise block fit (block means over the usable pixels) recovers s to
    # rounding; the crop and clipped pixels are left out, blocks cut by them included
    h, w = 96, 128
    dx, dy = _frame_grid(h, w)
    f = np.exp(np.log(0.4) + 0.1 * dx - 0.2 * dy - 0.25 * (dx ** 2 + dy ** 2))
    assert frame_summary(f)["log_slope"] == pytest.approx(0.25, abs=1e-9)
    g = f.copy()
    g[30:50, 60:80] = 0.9  # the object, in its crop
    g[:10, :20] = 1.0  # a clipped sky corner
    out = frame_summary(g, exclude=(60, 30, 20))
    assert out["log_slope"] == pytest.approx(0.25, abs=1e-9)
    assert out["texture"].shape == (h // 4, w // 4) and np.isnan(out["repeat"]) and out["shape"] == (h, w)
    # colour: the channels' mean; uint8 frames are read as such
    assert frame_summary(np.dstack([f, f, f]))["log_slope"] == pytest.approx(0.25, abs=1e-9)
    assert frame_summary(np.round(255 * f).astype(np.uint8))["log_slope"] == pytest.approx(0.25, abs=0.01)
    with pytest.raises(ValueError, match="shape"):
        frame_summary(np.zeros((2, 3, 4, 5)))


@pytest.mark.parametrize("k", [-0.2, 0.1, 0.3, 0.6])
def test_falloff_k_inverts_the_fit_of_a_vignetted_frame(k):
    h, w = 120, 160
    dx, dy = _frame_grid(h, w)
    f = 0.5 * (1.0 - k * (dx ** 2 + dy ** 2))  # the camera's vignetting: 1 - k r²
    assert falloff_k(frame_summary(f)["log_slope"], (h, w)) == pytest.approx(k, abs=1e-4)


def test_scene_clusters_join_chains_of_one_scene_and_place_textureless_frames_by_video():
    rng = np.random.default_rng(0)
    a, b, c = rng.standard_normal((3, 24, 32))
    ab = (a + b) / np.sqrt(2)  # a panning camera: a ~ ab ~ b, but a and b themselves do not correlate
    f = [{"texture": t + 0.05 * rng.standard_normal(t.shape), "repeat": 0.9} for t in (a, ab, b, c)]
    f.append({"texture": rng.standard_normal((24, 32)), "repeat": 0.1})  # video v0, cannot be placed
    f.append({"texture": rng.standard_normal((24, 32)), "repeat": float("nan")})  # v0 too: one scene with it
    f.append({"texture": rng.standard_normal((24, 32)), "repeat": 0.1})  # v1's: its own
    f.append({"texture": a[:12], "repeat": 0.9})  # another frame size: never the same scene by texture
    lab = scene_clusters(f, ["v0", "v1", "v2", "v0", "v0", "v0", "v1", "v0"])
    assert lab.tolist() == [0, 0, 0, 1, 2, 2, 3, 4]


@pytest.mark.slow
def test_radial_falloff_p_values_are_uniform_over_scenes_not_frames():
    # 8 scenes of 6 frames each (a static camera: one texture and one scene slope per video, the frames' own
    # noise small), no vignetting: the test over scenes keeps its level; over frames it would not
    rng = np.random.default_rng(3)
    ps, naive = [], []
    for _ in range(300):
        frames, groups = [], []
        for v in range(8):
            tex, slope = rng.standard_normal((12, 16)), 0.15 * rng.standard_normal()
            for _ in range(6):
                frames.append({"log_slope": slope + 0.02 * rng.standard_normal(), "repeat": 0.9, "shape": (48, 64),
                               "texture": tex + 0.1 * rng.standard_normal(tex.shape)})
                groups.append(f"v{v}")
        out = radial_falloff(frames, groups)
        assert out["scenes"] == 8 and out["frames"] == 48
        ps.append(out["p"])
        naive.append(stats.ttest_1samp([f["log_slope"] for f in frames], 0.0, alternative="greater").pvalue)
    assert stats.kstest(ps, "uniform").pvalue > 0.01
    assert np.mean(np.array(naive) < 0.01) > 0.1  # frames as if independent: many false alarms at 1 %
    # a camera's fall-off shared by every scene is found, at its strength
    frames = [{**f, "log_slope": f["log_slope"] + 0.357} for f in frames]  # log(1 - 0.3) at the corners ~ -0.357
    out = radial_falloff(frames, groups)
    assert out["p"] < 1e-3 and 0.1 < out["k"] < 0.5
    assert radial_falloff(frames[:12], groups[:12]) is None  # two scenes: nothing to test over


def test_blockiness_by_hand_and_on_an_opencv_jpeg():
    # the frame rises by 1 level per pixel and by 3 more across every 8th line (between 8m - 1 and 8m), down the
    # columns and the rows: steps on the lines 4, elsewhere 1 -> log 4 in both directions, the smaller of the two
    x, y = np.arange(96), np.arange(64)[:, None]
    f = (10 + x + 3 * (x // 8) + y + 3 * (y // 8)).astype(np.uint8)
    assert frame_summary(f)["blockiness"] == pytest.approx(np.log(4.0), abs=1e-9)
    g = f.copy()
    g[8:40, 40:72] = np.where(np.arange(32) % 8 == 0, 250, 10)[None, :]  # the object's square: left out
    assert frame_summary(g, exclude=(42, 10, 28))["blockiness"] == pytest.approx(np.log(4.0), abs=1e-9)
    # the grid in the columns alone (log 4 there, rows flat: 0) is not a codec's square blocks -> 0
    c = np.tile(20 + x + 3 * (x // 8), (64, 1)).astype(np.uint8)
    assert frame_summary(c)["blockiness"] == pytest.approx(0.0, abs=1e-9)
    # one scene edge on a grid line (x = 64) is not a grid: the median over the lines stays 0
    x = np.arange(128)
    e = np.tile(20 + x, (64, 1)).astype(np.uint8)
    e[:, 64:] += 10
    assert frame_summary(e)["blockiness"] == pytest.approx(0.0, abs=1e-9)
    # OpenCV's JPEG codec on a textured frame: its 8x8 grid shows; the frame itself has none
    import cv2

    rng = np.random.default_rng(0)
    scene = cv2.GaussianBlur(rng.uniform(40, 200, (192, 256)), (0, 0), 3).astype(np.uint8)
    jpeg = cv2.imdecode(cv2.imencode(".jpg", scene, [cv2.IMWRITE_JPEG_QUALITY, 30])[1], cv2.IMREAD_GRAYSCALE)
    assert -0.1 < frame_summary(scene)["blockiness"] < 0.05  # the smaller of two noisy ~0 values: a little below
    assert frame_summary(jpeg)["blockiness"] > 0.3
    # over scenes: ten JPEG frames of ten scenes against their originals
    scenes = [cv2.GaussianBlur(rng.uniform(40, 200, (96, 128)), (0, 0), 3).astype(np.uint8) for _ in range(10)]
    enc = [cv2.imdecode(cv2.imencode(".jpg", s_, [cv2.IMWRITE_JPEG_QUALITY, 30])[1], cv2.IMREAD_GRAYSCALE)
           for s_ in scenes]
    found = block_grid([frame_summary(e, background=e) for e in enc], [None] * 10)
    assert found["scenes"] == 10 and found["p"] < 1e-6 and found["log_ratio"] > 0.3
    assert block_grid([frame_summary(s_, background=s_) for s_ in scenes], [None] * 10)["log_ratio"] < 0.05
    # a sensor's fixed column pattern (gain 1 + 0.04 N(0, 1) per column) whose grid columns happen to step more
    # (+-0.04 more on every 8th column) in every frame of the camera: a grid in one direction, not a codec's
    gain = 1 + 0.04 * rng.standard_normal(128) + 0.04 * np.where(np.arange(128) % 8 == 0, 1.0, 0.0) * (
        (-1.0) ** (np.arange(128) // 8))
    fixed = [np.clip(s_ * gain[None, :], 0, 255).astype(np.uint8) for s_ in scenes]
    cols = [frame_summary(f_, background=f_) for f_ in fixed]
    assert block_grid(cols, [None] * 10)["p"] > 0.05
    # transposed (a row pattern), the same
    rows = [frame_summary(np.ascontiguousarray(f_.T), background=np.ascontiguousarray(f_.T)) for f_ in fixed]
    assert block_grid(rows, [None] * 10)["p"] > 0.05


@pytest.mark.parametrize("quality", [20, 30, 45, 65, 80, 90])
def test_jpeg_quality_reads_libjpeg_and_the_model_coding(quality):
    # OpenCV's libjpeg and the model's own JPEG coding (jpeg_quantize, rounded to 8 bits) at a known quality:
    # the DCT steps read back give that quality within 3 (neighbouring qualities share most steps); the object's
    # crop does not disturb it; a frame never coded has no table
    import cv2
    import torch

    from synthaug.diagnose.frame_pattern import jpeg_quality
    from synthaug.effects.camera_functional import jpeg_quantize

    rng = np.random.default_rng(quality)
    scene = cv2.GaussianBlur(rng.uniform(30, 220, (192, 256)), (0, 0), 1.5)
    lib = cv2.imdecode(cv2.imencode(".jpg", scene.astype(np.uint8), [cv2.IMWRITE_JPEG_QUALITY, quality])[1], 0)
    model = jpeg_quantize(torch.tensor(scene / 255.0)[None, None], float(quality))[0, 0].numpy()
    model = np.clip(np.round(model * 255.0), 0, 255).astype(np.uint8)
    for frame in (lib, model):
        out = jpeg_quality([frame_summary(frame, exclude=(100, 60, 40))])
        assert out is not None and abs(out["quality"] - quality) <= 3, out
    assert jpeg_quality([frame_summary(scene.astype(np.uint8))]) is None
    assert jpeg_quality([]) is None
    # flat 8x8 blocks never coded (a clear sky): every DC on a multiple of 8, no AC step: not a JPEG table
    flat = np.kron(rng.integers(40, 200, (24, 32)), np.ones((8, 8))).astype(np.uint8)
    assert jpeg_quality([frame_summary(flat)]) is None


def test_compression_frame_setting_is_the_read_quality_within_the_grid():
    from synthaug.diagnose.screening import CANDIDATE_GRIDS, frame_setting

    top = max(g["jpeg_quality"] for g in CANDIDATE_GRIDS["compression"])
    assert frame_setting("compression", {"jpeg_quality": 37.5, "gain": 0.3}) == {"jpeg_quality": 37.5}
    assert frame_setting("compression", {"jpeg_quality": 97.0, "gain": 0.3}) == {"jpeg_quality": top}
    assert frame_setting("compression", {"jpeg_quality": None, "gain": 0.3}) is None  # the distance setting stands
    assert frame_setting("vignetting", {"gain": 0.25}) == {"vignette_k": 0.25}
    assert frame_setting("vignetting", None) is None


# ------------------------------------------------------------------ in-camera sharpening: the frames' edge ratio
def _step_frame(sigma: float, *, lo: float = 0.3, c: float = 0.4) -> tuple[np.ndarray, np.ndarray]:
    """Vertical step edges (a bright band, rising then falling), each a Gaussian-blurred step ``lo + c Φ((x - x0) /
    σ)`` along its rows, at other columns in each of three 40-row blocks (so no column or row holds an edge in most
    of its length: a line gain, :func:`destripe`, reads none); and where edges may lie: away from the blocks'
    seams. A scene whose edge profile is known in closed form."""
    x = np.arange(220, dtype=np.float64)
    rows = [lo + c * (stats.norm.cdf((x - a) / sigma) - stats.norm.cdf((x - b) / sigma))
            for a, b in ((40, 120), (70, 150), (100, 180))]
    frame = np.concatenate([np.tile(r, (40, 1)) for r in rows])
    outside = np.ones(frame.shape, bool)
    outside[38:42] = outside[78:82] = False
    return frame, outside


@pytest.mark.parametrize("sigma", [0.8, 1.2, 2.0])
def test_edge_ratio_of_blurred_steps_against_the_normal_cdf(sigma):
    # D(o) = I(x0 + o) - I(x0 - o) = c (2 Φ(o / σ) - 1) at every edge (the falling ones oriented by their gradient),
    # read at whole pixels: A(2) / A(4) = (2 Φ(2 / σ) - 1) / (2 Φ(4 / σ) - 1); the background frame (where the
    # edges are found) is another look, 1/1000 brighter (no pixel equal), so the edges' normals are exactly ±x
    from synthaug.diagnose.frame_pattern import edge_ratio

    f, out = _step_frame(sigma)
    b = f + 1e-3
    want = (2 * stats.norm.cdf(2 / sigma) - 1) / (2 * stats.norm.cdf(4 / sigma) - 1)
    assert edge_ratio(f, b, outside=out) == pytest.approx(want, abs=1e-5)
    # colour frames: the mean of the channels; uint8: /255 (both leave the ratio as it is, up to rounding)
    assert edge_ratio(np.dstack([f] * 3), b, outside=out) == pytest.approx(edge_ratio(f, b, outside=out), abs=1e-12)
    assert edge_ratio(np.round(f * 255).astype(np.uint8), b, outside=out) == pytest.approx(want, abs=0.025)
    # a sensor's fixed column gains (2 %, in both looks) are divided out first; without that they would read as
    # much sharper edges (a column's gain step chosen as an edge's centre adds to every step across it)
    gain = 1 + 0.02 * np.random.default_rng(5).standard_normal(f.shape[1])
    assert edge_ratio(f * gain, b * gain, outside=out) == pytest.approx(want, abs=0.01)


@pytest.mark.parametrize("sigma", [0.8, 1.2, 2.0])
def test_edge_ratio_under_a_column_pattern_with_a_saturated_sky(sigma):
    # a 4 % column pattern before the 8-bit clip, over a sky that rises through white: where a column's gain lifts it
    # past 1 the pixel holds the clip, not the gain. The gains are read on the unclipped pixels only and the edges
    # kept off the clipped ones, so the steps below the sky read their closed form as without the pattern; read on
    # every pixel (the code before stop 99) the sky's clipped columns set the gains and stripe the rest of the frame
    from synthaug.diagnose.frame_pattern import destripe, edge_ratio

    f, out = _step_frame(sigma)
    x = np.arange(f.shape[1])
    frame = np.concatenate([f, np.tile(0.97 + 0.06 * x / x[-1], (60, 1))])
    out = np.concatenate([out, np.ones((60, f.shape[1]), bool)])
    out[110:130] = False  # the seam between the steps and the sky is no camera edge
    gain = 1 + 0.04 * np.random.default_rng(5).standard_normal(f.shape[1])
    fg, bg = np.clip(frame * gain, 0, 1), np.clip((frame + 1e-3) * gain, 0, 1)
    assert 0.1 < float((bg >= 1).mean()) < 0.2
    want = (2 * stats.norm.cdf(2 / sigma) - 1) / (2 * stats.norm.cdf(4 / sigma) - 1)
    assert edge_ratio(fg, bg, outside=out) == pytest.approx(want, abs=0.003)
    # what the mask is for: with every pixel read, the steps' rows keep column steps of about 1 % (masked: 0.2 %)
    rows = slice(0, 100)
    for valid, lo, hi in ((None, 0.0, 0.003), (np.ones(fg.shape, bool), 0.006, 1.0)):
        _, b = destripe(fg, bg, valid=valid)
        left = np.log(b[rows] / (frame[rows] + 1e-3))
        assert lo <= float(np.diff(np.median(left, 0)).std()) < hi


def test_destripe_line_median_is_numpys_nanmedian_to_the_bit():
    # destripe's line gains are medians over each line's unclipped pixels: one sort with the NaNs last, not numpy's
    # masked-array path for short lines; the same values to the bit, odd and even counts, one or all pixels valid
    from synthaug.diagnose.frame_pattern import _column_nanmedian

    rng = np.random.default_rng(3)
    for shape, p_nan in (((192, 256), 0.1), ((256, 192), 0.6), ((7, 40), 0.5), ((1, 5), 0.0)):
        x = rng.standard_normal(shape)
        x[rng.random(shape) < p_nan] = np.nan
        x[0, :] = rng.standard_normal(shape[1])  # every column keeps a value
        x[1:, 0] = np.nan  # a column of one value
        np.testing.assert_array_equal(_column_nanmedian(x), np.nanmedian(x, axis=0))


def test_edge_ratio_is_not_applicable_without_an_independent_look_or_edges():
    from synthaug.diagnose.frame_pattern import edge_ratio

    f, _ = _step_frame(1.0)
    assert np.isnan(edge_ratio(f, f))  # the background frame is the frame itself: no second look
    assert np.isnan(edge_ratio(f, f[:, :-1]))  # another size
    flat = np.full((96, 160), 0.5) + 0.01 * np.random.default_rng(1).standard_normal((96, 160))
    assert np.isnan(edge_ratio(flat, np.full((96, 160), 0.5)))  # no edge reaches the contrast
    # the object's crop is left out with the profile's reach: edges only inside it are not the scene's
    out = np.ones(f.shape, bool)
    out[:, 20:200] = False
    assert np.isnan(edge_ratio(f, f + 1e-3, outside=out))


def test_edge_ratio_rises_with_sharpening_falls_with_blur_and_ignores_the_noise_of_the_frame():
    # a random blocky scene (edges of every orientation, steps up to 0.2), the camera's optics a 1.5-px blur; an
    # unsharp mask (scipy: I + a (I - G_s * I)) of amount a raises the ratio step by step, a defocus lowers it; the
    # frame's own noise (sd 0.03, ~8 grey levels, as the reference camera's shot noise) leaves it where it is,
    # because the edges are chosen on the independent background look, while choosing them on the noisy frame
    # itself inflates it (noise read as sharpness)
    from scipy import ndimage

    from synthaug.diagnose.frame_pattern import edge_ratio

    rng = np.random.default_rng(2)
    scenes = [ndimage.gaussian_filter(ndimage.zoom(0.4 + 0.2 * rng.random((12, 20)), 8, order=0), 1.5)
              for _ in range(6)]

    def ratio(op, noise=0.0, same_look=False):
        v = []
        for s in scenes:
            img = op(s)
            f = img + noise * rng.standard_normal(img.shape)
            b = f + 1e-3 if same_look else img + 0.005 * rng.standard_normal(img.shape)
            v.append(edge_ratio(f, b))
        return float(np.mean(v))

    usm = lambda a: (lambda s: s + a * (s - ndimage.gaussian_filter(s, 1.0)))  # noqa: E731
    r = [ratio(usm(a)) for a in (0.0, 0.5, 1.0, 1.5)]
    assert all(b > a + 0.02 for a, b in zip(r, r[1:])), r
    assert ratio(lambda s: ndimage.gaussian_filter(s, 1.0)) < r[0] - 0.05
    assert ratio(usm(0.0), noise=0.03) == pytest.approx(r[0], abs=0.02)
    assert ratio(usm(0.0), noise=0.03, same_look=True) > r[0] + 0.05


@pytest.mark.parametrize("g", [0.75, 1.4])
def test_a_known_tone_curve_is_undone_before_the_edges_are_read(g):
    # the closed-form edges of _step_frame through a camera's tone curve x^g (both looks): the ratio moves off
    # (2 Φ(2/σ) - 1) / (2 Φ(4/σ) - 1); read through the inverse curve it is back; a summary without looks reads NaN
    from synthaug.diagnose.frame_pattern import edge_ratio, tone_undone

    sigma = 1.2
    f, out = _step_frame(sigma, lo=0.1, c=0.8)  # contrasty edges: a curve bends them most
    want = (2 * stats.norm.cdf(2 / sigma) - 1) / (2 * stats.norm.cdf(4 / sigma) - 1)
    bent, bent_b = f ** g, (f + 1e-3) ** g
    assert abs(edge_ratio(bent, bent_b, outside=out) - want) > 0.005
    s = {"edge_ratio": edge_ratio(bent, bent_b, outside=out), "looks": (bent, bent_b, out)}  # frame_summary's keys
    (u,) = tone_undone([s], g)
    assert u["edge_ratio"] == pytest.approx(want, abs=1e-5)
    assert np.isnan(tone_undone([{**s, "looks": None}], g)[0]["edge_ratio"])
    with pytest.raises(ValueError, match="exponent"):
        tone_undone([s], 0.0)


def test_sharpening_is_read_through_an_accepted_tone_curve():
    # six blocky scenes of three videos through the optics (1.5-px blur), a camera's gamma 1.4 on both looks:
    # the frames' edge ratio over scenes rises above the unbent frames'; given the accepted gamma, the frame
    # evidence reads it back where the unbent frames are
    from scipy import ndimage

    from synthaug.diagnose.frame_pattern import frame_summary
    from synthaug.diagnose.screening import frame_evidence

    rng = np.random.default_rng(7)
    scenes = [ndimage.gaussian_filter(ndimage.zoom(0.1 + 0.8 * rng.random((12, 20)), 8, order=0), 1.5)
              for _ in range(6)]

    class Frames:  # what frame_evidence reads of the diagnosis data
        def __init__(self, g):
            self.frame_summaries = [frame_summary(s ** g, background=(s + 0.004 * rng.standard_normal(s.shape)) ** g,
                                                  keep_looks=True) for s in scenes]
            self.records = [{"video": i // 2} for i in range(len(scenes))]

        def __len__(self):
            return len(self.records)

    plain, bent = Frames(1.0), Frames(1.4)
    r0 = frame_evidence(plain)["sharpening"]["ratio"]
    r1 = frame_evidence(bent)["sharpening"]["ratio"]
    ev = frame_evidence(bent, {"gamma": {"gamma_g": 1.4}})["sharpening"]
    assert r1 > r0 + 0.01
    assert ev["ratio"] == pytest.approx(r0, abs=0.003) and ev["tone_undone"] == 1.4
    assert "tone_undone" not in frame_evidence(bent, {"defocus": {"defocus_sigma": 1.0}})["sharpening"]


def test_sharp_edges_tests_scenes_against_the_clean_centre():
    from synthaug.diagnose.frame_pattern import sharp_edges

    # 8 scenes of 6 frames, each scene its own edge level around the clean mean 0.63: p uniform over scenes
    rng = np.random.default_rng(4)
    ps = []
    for _ in range(300):
        frames, groups = [], []
        for v in range(8):
            tex, level = rng.standard_normal((12, 16)), 0.63 + 0.02 * rng.standard_normal()
            for _ in range(6):
                frames.append({"edge_ratio": level + 0.01 * rng.standard_normal(), "repeat": 0.9, "shape": (48, 64),
                               "texture": tex + 0.1 * rng.standard_normal(tex.shape)})
                groups.append(f"v{v}")
        out = sharp_edges(frames, groups, centre=0.63)
        assert out["scenes"] == 8 and out["frames"] == 48 and out["centre"] == 0.63
        ps.append(out["p"])
    assert stats.kstest(ps, "uniform").pvalue > 0.01
    # scipy's one-sample t-test of the scenes' means against the centre, on the last draw
    lab = scene_clusters(frames, groups)
    means = [np.mean([f["edge_ratio"] for f, l in zip(frames, lab) if l == c]) for c in range(lab.max() + 1)]
    assert out["p"] == pytest.approx(stats.ttest_1samp(means, 0.63, alternative="greater").pvalue)
    assert out["ratio"] == pytest.approx(np.mean(means))
    # sharper frames are found; without a calibrated centre there is nothing to test against
    sharp = [{**f, "edge_ratio": f["edge_ratio"] + 0.08} for f in frames]
    assert sharp_edges(sharp, groups, centre=0.63)["p"] < 1e-4
    assert sharp_edges(sharp, groups, centre=None)["p"] == 1.0
    # NaN ratios (no independent look) are left out; under 3 scenes: None
    assert sharp_edges([{**f, "edge_ratio": float("nan")} for f in frames], groups, centre=0.63) is None
    assert sharp_edges(frames[:12], groups[:12], centre=0.63) is None


def test_sharpening_frame_channel_needs_the_test_against_the_centre_and_the_clean_floor(monkeypatch):
    # the screening's frame channel of sharpening: the edge ratio is its statistic, significant when the test over
    # scenes (against the clean mean) rejects at alpha after Bonferroni AND the ratio exceeds the calibrated floor;
    # it sets no camera setting of its own (the distance screen's setting stands)
    from synthaug.diagnose import screening

    monkeypatch.setattr(screening, "gain_floor", lambda effect, channel: 0.66 if (effect, channel) == (
        "sharpening", "frame") else None)
    ev = {"sharpening": {"ratio": 0.70, "t": 9.0, "p": 1e-5, "centre": 0.63, "scenes": 40, "frames": 60}}
    ch = screening.frame_channel("sharpening", ev, 40, 0.01)
    assert ch["significant"] and ch["gain"] == 0.70 and ch["floor"] == 0.66 and ch["centre"] == 0.63
    assert ch["p_adjusted"] == pytest.approx(4e-4)
    assert not screening.frame_channel("sharpening", ev, 2000, 0.01)["significant"]  # p_adj 0.02
    low = {"sharpening": {**ev["sharpening"], "ratio": 0.65}}  # significant test, inside the clean range
    assert not screening.frame_channel("sharpening", low, 40, 0.01)["significant"]
    assert screening.frame_channel("sharpening", {"sharpening": None}, 40, 0.01) is None
    assert screening.frame_setting("sharpening", ch) is None
    assert "sharpening" in screening.FRAME_CANDIDATES


def _radial_blend(scene: np.ndarray, sharp_sigma: float, soft_sigma: float) -> np.ndarray:
    """``scene`` blurred by ``soft_sigma`` at the frame's centre and by ``sharp_sigma`` at its corners, blended by
    r² (1 at the corners, as :func:`edge_radial` measures it): edges that steepen toward the corners."""
    from scipy import ndimage

    h, w = scene.shape
    yy, xx = np.mgrid[0:h, 0:w]
    r2 = ((xx - (w - 1) / 2) ** 2 + (yy - (h - 1) / 2) ** 2) / (0.25 * (w * w + h * h))
    return r2 * ndimage.gaussian_filter(scene, sharp_sigma) + (1 - r2) * ndimage.gaussian_filter(scene, soft_sigma)


def test_edge_radial_is_the_least_squares_trend_of_the_edges_steps_with_r2():
    # the same edges edge_ratio reads; the fit A(2) = (a + b r²) A(4) checked against scipy's least squares, and the
    # frame summary carries it beside the ratio of the same edges
    from scipy import linalg, ndimage

    from synthaug.diagnose.frame_pattern import edge_radial, edge_ratio, edge_steps, frame_summary

    rng = np.random.default_rng(11)
    scene = ndimage.zoom(0.4 + 0.2 * rng.random((24, 32)), 8, order=0)
    f = _radial_blend(scene, 0.8, 2.0) + 0.003 * rng.standard_normal(scene.shape)
    b = _radial_blend(scene, 0.8, 2.0) + 0.003 * rng.standard_normal(scene.shape)
    st = edge_steps(f, b)
    (h, w), y, x = st["shape"], st["y"], st["x"]
    r2 = ((x - (w - 1) / 2) ** 2 + (y - (h - 1) / 2) ** 2) / (0.25 * (w * w + h * h))
    coef, *_ = linalg.lstsq(np.stack([st["a2"], st["a2"] * r2], 1), st["a1"])
    assert edge_radial(st) == pytest.approx(coef[1], rel=1e-9) and coef[1] > 0.05
    out = frame_summary(f, background=b)
    assert out["edge_radial"] == pytest.approx(coef[1], rel=1e-9)
    assert out["edge_ratio"] == pytest.approx(edge_ratio(f, b), rel=1e-12)
    assert np.isnan(frame_summary(f)["edge_radial"]) and np.isnan(edge_radial(None))  # no second look: no reading


def test_edge_radial_sees_a_trend_toward_the_corners_not_a_sharpening_of_every_edge():
    # an unsharp mask (amount 1 and 1.5) steepens every edge alike and leaves the trend where a plain frame has it;
    # a frame whose edges steepen toward the corners reads far above both
    from scipy import ndimage

    from synthaug.diagnose.frame_pattern import edge_radial, edge_steps

    rng = np.random.default_rng(2)

    def trend(op):
        v = []
        for _ in range(6):
            img = op(ndimage.gaussian_filter(ndimage.zoom(0.4 + 0.2 * rng.random((24, 32)), 8, order=0), 1.5))
            v.append(edge_radial(edge_steps(img + 0.005 * rng.standard_normal(img.shape),
                                            img + 0.005 * rng.standard_normal(img.shape))))
        return float(np.mean(v))

    usm = lambda a: (lambda s: s + a * (s - ndimage.gaussian_filter(s, 1.0)))  # noqa: E731
    plain, sharp1, sharp15 = trend(lambda s: s), trend(usm(1.0)), trend(usm(1.5))
    radial = trend(lambda s: _radial_blend(s, 0.3, 1.5))
    assert abs(plain) < 0.02 and abs(sharp1 - plain) < 0.03 and abs(sharp15 - plain) < 0.03, (plain, sharp1, sharp15)
    assert radial > plain + 0.08, (radial, plain)


def test_sharp_edges_carries_the_scenes_mean_radial_trend():
    from synthaug.diagnose.frame_pattern import scene_clusters, sharp_edges

    rng = np.random.default_rng(6)
    frames, groups = [], []
    for v in range(6):
        tex = rng.standard_normal((12, 16))
        for j in range(3 + v % 2):
            frames.append({"edge_ratio": 0.65 + 0.01 * rng.standard_normal(), "edge_radial": 0.01 * v + 0.002 * j,
                           "repeat": 0.9, "shape": (48, 64),
                           "texture": tex + 0.1 * rng.standard_normal(tex.shape)})
            groups.append(f"v{v}")
    out = sharp_edges(frames, groups, centre=0.63)
    lab = scene_clusters(frames, groups)
    means = [np.mean([f["edge_radial"] for f, c in zip(frames, lab) if c == k]) for k in range(lab.max() + 1)]
    assert out["radial"] == pytest.approx(np.mean(means))
    # frames without a reading (summaries of before the trend was read) leave it NaN, the ratio's test as it was
    old = [{k: v for k, v in f.items() if k != "edge_radial"} for f in frames]
    assert np.isnan(sharp_edges(old, groups, centre=0.63)["radial"])
    assert sharp_edges(old, groups, centre=0.63)["p"] == out["p"]


# a report with nothing but its screened rows, for write_markdown's sentences on a channel
_BARE_REPORT = {"inputs": {"seeds": "s", "n_seeds": 60, "mesh": "m", "fit": "f", "distance": "hog", "k_folds": 5,
                           "alpha": 0.01}, "findings": [], "residuals": {}, "parameter_dependence": [],
                "realism": {"accuracy_base": 0.5}, "seconds": 1.0}


def test_sharpening_frame_channel_is_not_named_when_the_edges_steepen_toward_the_corners(monkeypatch):
    # lens k1 +0.1 on the reference camera raises the frames' edge ratio past sharpening's floor where its scene did
    # not move (power table, lens +0.1 case 4); its edges steepen toward the corners, which no clean frame and no
    # sharpening does: above the clean floor of that trend the frame channel does not name sharpening, and says why
    from synthaug.diagnose import screening
    from synthaug.diagnose.frame_pattern import EDGE_RADIAL_FLOOR
    from synthaug.diagnose.report import write_markdown

    monkeypatch.setattr(screening, "gain_floor", lambda effect, channel: 0.66 if (effect, channel) == (
        "sharpening", "frame") else None)
    ev = {"sharpening": {"ratio": 0.70, "t": 9.0, "p": 1e-5, "centre": 0.63, "scenes": 40, "frames": 60,
                         "radial": EDGE_RADIAL_FLOOR - 0.01}}
    ch = screening.frame_channel("sharpening", ev, 40, 0.01)
    assert ch["significant"] and not ch["radial_veto"] and ch["radial_floor"] == EDGE_RADIAL_FLOOR
    steep = {"sharpening": {**ev["sharpening"], "radial": EDGE_RADIAL_FLOOR + 0.01}}
    vetoed = screening.frame_channel("sharpening", steep, 40, 0.01)
    assert not vetoed["significant"] and vetoed["radial_veto"] and vetoed["gain"] == 0.70
    # edges blurrier toward the corners lower the ratio rather than raise it: no veto that way; no reading: none
    for r in (-0.2, float("nan")):
        assert screening.frame_channel("sharpening", {"sharpening": {**ev["sharpening"], "radial": r}}, 40,
                                       0.01)["significant"]
    assert screening.frame_channel("sharpening", {"sharpening": {**ev["sharpening"], "radial": float("nan")}}, 40,
                                   0.01)["radial"] is None  # the report's JSON holds no NaN
    assert screening.frame_channel("sharpening", {"sharpening": {k: v for k, v in ev["sharpening"].items()
                                                                 if k != "radial"}}, 40, 0.01)["significant"]
    row = {"effect": "sharpening", "significant": False, "channel": "frame", "score": 4.0, "gain_feature": 0.0,
           "gain_pixel": 0.0}
    md = write_markdown({**_BARE_REPORT, "screened": [{**row, "channels": [vetoed]}]})
    assert f"Sharpening is not named from the frames: their edges steepen toward the corners (edge sharpness " \
           f"trend {EDGE_RADIAL_FLOOR + 0.01:+.3f}" in md
    assert "not named from the frames" not in write_markdown({**_BARE_REPORT, "screened": [{**row, "channels": [ch]}]})


def test_defocus_is_withheld_where_the_frames_edges_are_not_blurrier_than_clean_frames():
    # a defocus blurs the whole frame: its finding needs the frames' edges blurrier than the clean mean, the t-test
    # over scenes of sharp_edges read the other way (scipy's one-sided test "less" on the scenes' ratios); gamma 1.4
    # (the facets bent) reads 0.656 on the 13000 set's case 2, whose objects' pixel gain named defocus before stop 114
    from synthaug.diagnose.frame_pattern import sharp_edges
    from synthaug.diagnose.report import write_markdown
    from synthaug.diagnose.screening import BLUR_ALPHA, frames_blurred

    rng = np.random.default_rng(3)

    def frames(mean: float) -> list[dict]:
        return [{"edge_ratio": mean + 0.03 * rng.standard_normal(), "repeat": 0.0, "shape": (48, 64),
                 "texture": rng.standard_normal((12, 16))} for _ in range(40)]

    for mean in (0.62, 0.628, 0.635, 0.656):
        f = frames(mean)
        groups = [f"v{i}" for i in range(len(f))]  # textureless frames, one video each: every frame its own scene
        ev = {"sharpening": sharp_edges(f, groups, centre=0.635)}
        fb = frames_blurred("defocus", ev)
        want = stats.ttest_1samp([x["edge_ratio"] for x in f], 0.635, alternative="less").pvalue
        assert fb["p_blurrier"] == pytest.approx(want, rel=1e-6, abs=1e-12) and fb["scenes"] == 40
        assert fb["blurred"] == (want < BLUR_ALPHA) and fb["centre"] == 0.635
    assert frames_blurred("defocus", {"sharpening": sharp_edges(frames(0.60), groups, centre=0.635)})["blurred"]
    assert not frames_blurred("defocus", {"sharpening": sharp_edges(frames(0.656), groups, centre=0.635)})["blurred"]
    # not a blur of the frame, or nothing to read (no calibrated centre: no test)
    ev = {"sharpening": sharp_edges(frames(0.60), groups, centre=0.635)}
    for effect, e in (("haze", ev), ("sharpening", ev), ("defocus", {"sharpening": None}), ("defocus", None),
                      ("defocus", {"sharpening": sharp_edges(frames(0.60), groups, centre=None)})):
        assert frames_blurred(effect, e) is None
    veto = frames_blurred("defocus", {"sharpening": {**sharp_edges(frames(0.656), groups, centre=0.635),
                                                     "tone_undone": 1.4}})
    ch = {"channel": "distance:pixel", "gain": 0.0457, "significant": False, "frames_veto": veto}
    row = {"effect": "defocus", "significant": False, "channel": "distance:pixel", "score": 5.0, "gain_feature": 0.0,
           "gain_pixel": 0.0457}
    md = write_markdown({**_BARE_REPORT, "screened": [{**row, "channels": [ch]}]})
    assert ("Defocus is not named: rendering it fits the objects better (distance:pixel +4.6 %), but the whole frames' "
            f"edges are not blurrier than clean frames' (edge sharpness {veto['ratio']:.3f} over 40 scenes, read "
            f"through the tone curve γ 1.40 undone, clean mean 0.635: t {veto['t']:+.1f}") in md
    assert "Defocus is not named" not in write_markdown({**_BARE_REPORT, "screened": [{**row, "channels": [
        {k: v for k, v in ch.items() if k != "frames_veto"}]}]})


def test_unsharp_inverse_undoes_the_models_unsharp_mask():
    # the model's own unsharp mask (synthaug.effects.camera_functional, reflect border) undone by the division by
    # its transfer function, in the interior (the two borders differ within a few sigma of the edge)
    import torch

    from synthaug.diagnose.frame_pattern import unsharp_inverse
    from synthaug.effects import camera_functional as Cx

    img = np.random.default_rng(6).random((48, 64))
    for a, s in ((0.6, 0.7), (1.0, 1.0), (1.5, 1.5)):
        sharp = Cx.unsharp_mask(torch.from_numpy(img)[None, None], a, s, pad=8, border="reflect")[0, 0].numpy()
        back = unsharp_inverse(sharp, a, s)
        assert np.abs(back - img)[10:-10, 10:-10].max() < 5e-3, (a, s)
        assert np.abs(sharp - img)[10:-10, 10:-10].max() > 0.3  # it did sharpen


def test_sharpening_setting_reads_the_unsharp_mask_off_the_frames():
    # frames of blocky scenes (optics a 1.5-px blur), two independent looks each; the clean mean of their edge
    # ratio is the centre; sharpened by the camera at (1, 1) and at (1.5, 1.5) frame px, the grid setting whose
    # inverse brings them back to the centre is the camera's
    from scipy import ndimage

    from synthaug.diagnose.frame_pattern import edge_ratio, frame_summary, sharpening_setting
    from synthaug.diagnose.screening import CANDIDATE_GRIDS

    rng = np.random.default_rng(7)
    scenes = [ndimage.gaussian_filter(ndimage.zoom(0.3 + 0.4 * rng.random((12, 16)), 8, order=0), 1.5)
              for _ in range(8)]
    look = lambda img: np.clip(img + 0.005 * rng.standard_normal(img.shape), 0, 1)  # noqa: E731
    centre = float(np.mean([edge_ratio(look(s), look(s)) for s in scenes]))
    grid = CANDIDATE_GRIDS["sharpening"]
    for a, sg in ((1.0, 1.0), (1.5, 1.5)):
        usm = lambda s: s + a * (s - ndimage.gaussian_filter(s, sg, mode="reflect"))  # noqa: E731
        summ = [frame_summary(look(usm(s)), background=look(usm(s)), keep_looks=True) for s in scenes]
        assert all(f["looks"] is not None for f in summ)
        out = sharpening_setting(summ, grid, centre)
        assert out["setting"] == {"sharpen_amount": a, "sharpen_sigma": sg}, out
        assert len(out["ratios"]) == len(grid)
    # no frame kept its looks: nothing to read
    assert sharpening_setting([{**f, "looks": None} for f in summ], grid, centre) is None
    assert frame_summary(scenes[0], background=scenes[0] + 1e-3)["looks"] is None  # not asked for


def test_a_significant_frame_channel_gives_the_setting_whatever_channel_ranks_first():
    # report._setting: a row named from its distance channel takes the frames' read of the camera when its frame
    # channel is significant too; not when the frame channel is not (then the distance screen's grid point)
    from synthaug.diagnose.report import _setting

    frames = {"sharpen_amount": 1.5, "sharpen_sigma": 1.5}
    grid = {"sharpen_amount": 0.6, "sharpen_sigma": 1.5}
    row = {"effect": "sharpening", "channel": "distance:feature", "frame_setting": frames,
           "screen": {"feature": {"setting": grid}, "pixel": {"setting": grid}},
           "channels": [{"channel": "distance:feature", "significant": True},
                        {"channel": "frame", "significant": True}]}
    assert _setting(row) == frames
    row["channels"][1]["significant"] = False
    assert _setting(row) == grid
    assert _setting({**row, "channel": "frame"}) == frames


def _lens_look(scene: np.ndarray, k1: float) -> np.ndarray:
    """A scene through the library's whole-frame lens (division model, the reference camera's call)."""
    import torch

    from synthaug.effects.camera_functional import lens_distortion

    return lens_distortion(torch.from_numpy(scene)[None, None], k1, recentre=False, border="border")[0, 0].numpy()


def _textured_scene(rng: np.random.Generator, shape=(144, 192)) -> np.ndarray:
    from scipy import ndimage

    return 0.2 + 0.6 * ndimage.gaussian_filter(rng.random(shape), 2.0) / 0.15 * 0.1


@pytest.mark.parametrize("k1", [-0.2, -0.15, -0.05, 0.0, 0.1])
def test_radial_flow_reads_the_lens_k_off_a_moved_scene(k1):
    # a scene moved by a known shift between two looks (scipy's cubic-spline shift), both through the library's
    # whole-frame division-model lens: the fit of the frame as the background seen through the map reads k1 and
    # the shift; without distortion the motion is one shift and k reads 0
    from scipy import ndimage

    from synthaug.diagnose.frame_pattern import radial_flow

    rng = np.random.default_rng(11)
    scene = _textured_scene(rng)
    shift = (0.6, -0.8)  # (rows, columns): the scene moves 0.8 px left, 0.6 px down
    moved = ndimage.shift(scene, shift, order=3, mode="reflect")
    out = radial_flow(_lens_look(moved, k1), _lens_look(scene, k1))
    assert out["drift"] == pytest.approx(1.0, abs=0.03)
    assert out["k"] == pytest.approx(k1, abs=0.006)
    assert out["pixels"] > 20000


def test_radial_flow_is_unbiased_under_frame_noise_and_ignores_the_objects_crop():
    # each look its own noise (an independent look); an object pasted into the frame's crop only, the crop left out
    # (outside): over draws the reading's mean is the lens's k (0 and -0.15) within 3 standard errors
    from scipy import ndimage

    from synthaug.diagnose.frame_pattern import radial_flow

    rng = np.random.default_rng(12)
    outside = np.ones((144, 192), bool)
    outside[58:92, 78:112] = False
    for k1 in (0.0, -0.15):
        ks = []
        while len(ks) < 10:
            scene = _textured_scene(rng)
            t = rng.uniform(-1.0, 1.0, 2)
            if np.hypot(*t) < 0.4:
                continue
            moved = ndimage.shift(scene, t, order=3, mode="reflect")
            f = np.clip(_lens_look(moved, k1) + 0.01 * rng.standard_normal(scene.shape), 0, 1)
            b = np.clip(_lens_look(scene, k1) + 0.01 * rng.standard_normal(scene.shape), 0, 1)
            f[60:90, 80:110] = 0.95  # the object, in the frame only
            ks.append(radial_flow(f, b, outside=outside)["k"])
        ks = np.asarray(ks)
        assert np.isfinite(ks).all()
        assert abs(ks.mean() - k1) < 3 * ks.std(ddof=1) / np.sqrt(len(ks)) + 0.003, (k1, ks)


def test_radial_flow_has_no_reading_without_a_second_look_or_a_motion():
    from scipy import ndimage

    from synthaug.diagnose.frame_pattern import MIN_DRIFT_PX, radial_flow

    rng = np.random.default_rng(13)
    scene = _textured_scene(rng)
    f = _lens_look(ndimage.shift(scene, (0.5, 0.5), order=3, mode="reflect"), -0.15)
    assert np.isnan(radial_flow(f, f)["k"])  # the background is the frame itself: no independent look
    assert np.isnan(radial_flow(f, f[:, :-1])["k"])  # other shapes
    still = _lens_look(ndimage.shift(scene, (0.1, 0.0), order=3, mode="reflect"), -0.15)
    out = radial_flow(still, _lens_look(scene, -0.15))  # a shift under MIN_DRIFT_PX cannot tell k
    assert out["drift"] < MIN_DRIFT_PX and np.isnan(out["k"])
    flat = np.full_like(scene, 0.5)  # no texture: nothing to follow
    assert np.isnan(radial_flow(flat + 0.001 * rng.standard_normal(flat.shape), flat)["k"])


def test_lens_flow_tests_scenes_two_sided():
    from synthaug.diagnose.frame_pattern import lens_flow

    rng = np.random.default_rng(14)
    ps = []
    for _ in range(300):
        frames, groups = [], []
        for v in range(8):
            tex, level = rng.standard_normal((12, 16)), 0.005 * rng.standard_normal()
            for _ in range(6):
                frames.append({"flow_k": level + 0.02 * rng.standard_normal(), "repeat": 0.9, "shape": (48, 64),
                               "texture": tex + 0.1 * rng.standard_normal(tex.shape)})
                groups.append(f"v{v}")
        out = lens_flow(frames, groups)
        ps.append(out["p"])
    assert stats.kstest(ps, "uniform").pvalue > 0.01
    lab = scene_clusters(frames, groups)
    means = [np.mean([f["flow_k"] for f, l in zip(frames, lab) if l == c]) for c in range(lab.max() + 1)]
    assert out["p"] == pytest.approx(stats.ttest_1samp(means, 0.0).pvalue)
    assert out["k"] == pytest.approx(np.mean(means)) and out["scenes"] == 8 and out["frames"] == 48
    for k1 in (-0.15, 0.1):  # barrel and pincushion alike
        moved = lens_flow([{**f, "flow_k": f["flow_k"] + k1} for f in frames], groups)
        assert moved["p"] < 1e-4 and moved["k"] == pytest.approx(k1, abs=0.02)
    # frames without a reading (no motion, no second look) are left out; under 3 scenes: None
    assert lens_flow([{**f, "flow_k": float("nan")} for f in frames], groups) is None
    assert lens_flow(frames[:12], groups[:12]) is None


def test_lens_flow_weighs_frames_by_their_precision():
    """Frames whose scene moved little read k with a large error (the distortion's share of the motion is k times
    the shift): lens_flow's weights keep them from setting the estimate. Its estimate is the random-effects mean
    (DerSimonian-Laird's excess spread added to each stated error) and its test the Hartung-Knapp t, both checked
    against the textbook formulas and the weighted regression; its p is uniform under no lens when the stated errors
    are right (conservative when they are too small by a common factor), and frames whose errors are understated (a
    block codec's fixed grid) do not take the estimate over."""
    from synthaug.diagnose.frame_pattern import lens_flow

    rng = np.random.default_rng(15)

    def case(k1: float, scale: float = 1.0, bad: int = 0):
        frames, groups = [], []
        for v in range(20):
            tex, se = rng.standard_normal((12, 16)), rng.choice([0.004, 0.01, 0.1])  # shifts of ~1, 0.4, 0.04 px
            err = scale * se
            if v < bad:  # a frame whose stated error is ten times too small
                se, err = 0.01, 0.1
            frames.append({"flow_k": k1 + err * rng.standard_normal(), "flow_k_se": se, "repeat": 0.9,
                           "shape": (48, 64), "texture": tex})
            groups.append(f"v{v}")
        return frames, groups

    ps, weighted, plain = [], [], []
    for _ in range(300):
        frames, groups = case(0.0)
        out = lens_flow(frames, groups)
        ps.append(out["p"])
        weighted.append(out["k"])
        plain.append(np.mean([f["flow_k"] for f in frames]))
    assert stats.kstest(ps, "uniform").pvalue > 0.01
    assert np.std(weighted) < 0.3 * np.std(plain)
    # the errors 2.5x the stated ones (a lower bound, as radial_flow's): the test errs on the safe side
    understated = [lens_flow(*case(0.0, scale=2.5))["p"] for _ in range(300)]
    assert np.mean(np.array(understated) < 0.05) <= 0.05
    # DerSimonian-Laird's tau^2, then the weighted regression of a constant on sqrt(w)-scaled rows
    k, w = np.array([f["flow_k"] for f in frames]), np.array([f["flow_k_se"] ** -2.0 for f in frames])
    q = np.sum(w * (k - np.sum(w * k) / w.sum()) ** 2)
    tau2 = max(0.0, (q - (len(k) - 1)) / (w.sum() - np.sum(w ** 2) / w.sum()))
    w = 1.0 / (1.0 / w + tau2)
    x, y = np.sqrt(w)[:, None], np.sqrt(w) * k
    (coef,), res, *_ = np.linalg.lstsq(x, y, rcond=None)
    se_coef = np.sqrt(res[0] / (len(k) - 1) / float((x.T @ x)[0, 0]))
    assert out["tau"] == pytest.approx(np.sqrt(tau2), rel=1e-9, abs=1e-12)
    assert out["k"] == pytest.approx(coef, rel=1e-9)
    assert out["t"] == pytest.approx(coef / se_coef, rel=1e-9)
    assert out["p"] == pytest.approx(2 * stats.t.sf(abs(coef / se_coef), len(k) - 1), rel=1e-9)
    frames, groups = case(-0.15)
    out = lens_flow(frames, groups)
    assert out["p"] < 1e-6 and out["k"] == pytest.approx(-0.15, abs=0.01)
    # six frames of twenty with errors ten times their stated ones: the excess spread flattens the weights
    ks, alarms = [], 0
    for _ in range(200):
        out = lens_flow(*case(0.0, bad=6))
        ks.append(out["k"])
        alarms += out["p"] < 0.01
    assert np.sqrt(np.mean(np.square(ks))) < 0.02 and alarms <= 6
    # a frame without a usable error is left out, as one without a reading
    bad = [{**frames[0], "flow_k_se": float("nan")}] + frames[1:]
    assert lens_flow(bad, groups)["frames"] == len(frames) - 1


def test_lens_frame_channel_uses_the_size_of_k_and_sets_the_signed_k(monkeypatch):
    from synthaug.diagnose import screening

    monkeypatch.setattr(screening, "gain_floor", lambda effect, channel: 0.03 if (effect, channel) == (
        "lens_distortion", "frame") else None)
    ev = {"lens_distortion": {"k": -0.14, "t": -20.0, "p": 1e-8, "scenes": 30, "frames": 50}}
    ch = screening.frame_channel("lens_distortion", ev, 40, 0.01)
    assert ch["significant"] and ch["gain"] == pytest.approx(0.14) and ch["k1"] == -0.14 and ch["floor"] == 0.03
    assert screening.frame_setting("lens_distortion", ch) == {"distortion_k1": -0.14}
    small = {"lens_distortion": {**ev["lens_distortion"], "k": 0.02}}  # significant test, inside the clean range
    assert not screening.frame_channel("lens_distortion", small, 40, 0.01)["significant"]
    weak = {"lens_distortion": {**ev["lens_distortion"], "p": 1e-3}}  # p_adj 0.04
    assert not screening.frame_channel("lens_distortion", weak, 40, 0.01)["significant"]
    far = {"lens_distortion": {**ev["lens_distortion"], "k": -0.6}}  # the setting stays in the parameter's range
    assert screening.frame_setting("lens_distortion", screening.frame_channel("lens_distortion", far, 40, 0.01)) == {
        "distortion_k1": -0.3}
    assert "lens_distortion" in screening.FRAME_CANDIDATES


def test_radial_flow_is_not_fooled_by_a_vignetting_in_both_looks():
    # a radial gain fixed in the frame (1 - 0.4 r², in both looks) is no motion: the static gain terms of the fit
    # take it (without them the reference camera's vignetting of 0.3 read k 0.10-0.17); a lens under it still reads
    from scipy import ndimage

    from synthaug.diagnose.frame_pattern import radial_flow

    rng = np.random.default_rng(15)
    scene = _textured_scene(rng)
    h, w = scene.shape
    yy, xx = np.mgrid[:h, :w]
    vig = 1.0 - 0.4 * ((xx - (w - 1) / 2) ** 2 + (yy - (h - 1) / 2) ** 2) / (0.25 * (h * h + w * w))
    moved = ndimage.shift(scene, (0.7, 0.9), order=3, mode="reflect")
    for k1 in (0.0, -0.15):
        out = radial_flow(vig * _lens_look(moved, k1), vig * _lens_look(scene, k1))
        assert out["k"] == pytest.approx(k1, abs=0.006), k1


def test_a_lens_gain_under_the_utility_rule_is_named_when_the_frames_edges_steepen_toward_the_corners():
    # lens k1 +0.1, power table case 4 (its scene did not move: no reading of the lens from the motion): the lens's
    # pixel-distance gain passes its test and its calibrated floor but is 1.7 % of the distance, under the 2 % an
    # extension is asked to give; the frames' edges steepen toward the corners beyond every clean frame's (0.057
    # against 0.046). That reading names the lens; it rescues nothing that fails the test, the floor or the other
    # space, and it is not used when the lens's own frame test has a reading (which then decides)
    from scipy import stats

    from synthaug.diagnose import screening
    from synthaug.diagnose.calibration import HAND_MIN_GAIN
    from synthaug.diagnose.frame_pattern import EDGE_RADIAL_FLOOR
    from synthaug.diagnose.report import write_markdown

    steep = {"sharpening": {"ratio": 0.650, "radial": EDGE_RADIAL_FLOOR + 0.011}, "lens_distortion": None}
    cb = screening.frame_corroboration("lens_distortion", steep)
    assert cb == {"statistic": "edge_radial", "value": EDGE_RADIAL_FLOOR + 0.011, "floor": EDGE_RADIAL_FLOOR}
    for ev in ({**steep, "sharpening": {"radial": EDGE_RADIAL_FLOOR - 0.001}},  # within the clean range
               {**steep, "sharpening": {"radial": -0.2}},  # one-sided, as calibrated
               {**steep, "sharpening": {"radial": float("nan")}}, {**steep, "sharpening": {}},
               {**steep, "sharpening": None}, None,
               {**steep, "lens_distortion": {"k": 0.001, "p": 0.5, "scenes": 40, "frames": 60}}):  # motion read
        assert screening.frame_corroboration("lens_distortion", ev) is None, ev
    assert all(screening.frame_corroboration(e, steep) is None for e in screening.CANDIDATE_GRIDS
               if e != "lens_distortion")

    case4 = {"n_params": 1, "pixel": {"p": 2.6e-5, "gain": 0.01233, "raw_gain_all": 0.01733},
             "feature": {"p": 0.44, "gain": 0.0004, "raw_gain_all": 0.0054}}
    opts = {"n_tests": 41, "alpha": 0.01, "penalty": 0.005, "floor": 0.01081}
    plain = screening.distance_channel(case4, "pixel", "feature", **opts)
    assert not plain["significant"] and plain["corroborated_by"] is None
    assert plain["p_adjusted"] == pytest.approx(41 * 2.6e-5) and plain["z"] == pytest.approx(stats.norm.isf(2.6e-5))
    named = screening.distance_channel(case4, "pixel", "feature", corroboration=cb, **opts)
    assert named["significant"] and named["corroborated_by"] == cb
    assert {k: v for k, v in named.items() if k not in ("significant", "corroborated_by")} == \
           {k: v for k, v in plain.items() if k not in ("significant", "corroborated_by")}
    assert not screening.distance_channel(case4, "feature", "pixel", corroboration=cb, **opts)["significant"]
    for bad in ({"pixel": {**case4["pixel"], "p": 1e-3}},  # p_adj 0.041: the test fails
                {"pixel": {**case4["pixel"], "gain": 0.010}},  # under the calibrated floor
                {"feature": {**case4["feature"], "gain": -0.02}}):  # the detector's space gets worse
        ch = screening.distance_channel({**case4, **bad}, "pixel", "feature", corroboration=cb, **opts)
        assert not ch["significant"] and ch["corroborated_by"] is None, bad
    # a gain that is worth having on its own needs no corroboration, and none is recorded
    big = {**case4, "pixel": {**case4["pixel"], "raw_gain_all": HAND_MIN_GAIN}}
    ch = screening.distance_channel(big, "pixel", "feature", corroboration=cb, **opts)
    assert ch["significant"] and ch["corroborated_by"] is None

    row = {"effect": "lens_distortion", "significant": True, "channel": "distance:pixel", "score": 4.0,
           "gain_feature": 0.0004, "gain_pixel": 0.0123}
    md = write_markdown({**_BARE_REPORT, "screened": [{**row, "channels": [named]}]})
    assert (f"The lens (`lens_distortion`) is named from its distance:pixel gain of 1.7 %, under the "
            f"{100 * HAND_MIN_GAIN:.0f} % an extension is otherwise asked to give, because the whole frames show it: "
            f"their edges steepen toward the corners (edge sharpness trend {EDGE_RADIAL_FLOOR + 0.011:+.3f}") in md
    assert "The lens (" not in write_markdown({**_BARE_REPORT, "screened": [{**row, "channels": [ch]}]})
