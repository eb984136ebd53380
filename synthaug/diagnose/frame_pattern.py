"""Patterns fixed in the frame: a sensor's column (row) gains, the same in every frame the camera makes.

A CMOS read-out gives each column its own amplifier, so real frames carry a fixed column pattern: each
frame column's gain differs by a percent or two, the same in every frame. The renderer draws the object
without it, so the object's pixels miss what the background around it has. On an object of 20-30 px the
residual is far too weak to see it (0.02 x the object's intensity), but the whole frames show it well: the
profile of a frame's mean log intensity across its columns, high-passed (a scene's slow changes removed),
is the pattern plus the scene's own column structure (trees, poles, the horizon). The scene's structure is
not fixed in the frame from one video to the next; the camera's pattern is.

So the statistic is the **cross-video agreement of the high-passed profiles at the same frame column**:
each video's mean profile ``D_v`` (its seeds' frames, the object's crop left out), and

    ρ = Σ_{v<u} <D_v, D_u> / ((V - 1) / 2 · Σ_v |D_v|²)

(the mean cross-video inner product over the mean squared norm: 1 when every video shows the same pattern,
about 0 when they do not). Its null keeps every video's own profile and destroys only the alignment
between videos: each video's profile is shifted circularly by its own random offset
(:func:`fixed_line_pattern`, one-sided permutation test, ``n_perm`` shifts drawn from the given generator).
A pattern fixed in frame rows is the same statistic on the rows' profiles.

Frames of other sizes than the most common one are left out (their columns are other columns); with fewer
than two videos (or two seeds) there is nothing to compare and the measure is not applicable.

**A radial fall-off (vignetting)** is the other gain fixed in the frame: ``1 - k r²`` (r = 1 at the corners),
the same in every frame. On the object it is a gain of 0.9-1 that the fitted albedo w_d absorbs, but the whole
frames carry it: each frame's least-squares fit ``log I = a_j + b_j dx - s dx²`` over 4-px blocks, each row of
blocks ``j`` with its own level and tilt (the seed's crop and saturated pixels left out), gives its log fall-off
``s`` (:func:`frame_summary`). Read along the rows, a camera's ``1 - k r²`` gives the same ``s`` in every row,
while whatever changes with height — the sky's gradient with elevation, a horizon with the ground below it, as
in nearly every real outdoor frame — goes into the rows' levels (a fit of ``r²`` over the whole frame read the
real drone videos' horizons as a fall-off: its ``dy²`` coefficient was 6x its ``dx²`` one, positive in 56 of 56
videos). A scene has radial
structure of its own (a bright cloud in the middle, a dark corner), so ``s`` of one frame is the camera's plus
its scene's, and frames of the same scene are not independent: the test runs over **scenes**, not frames
(:func:`scene_clusters`: frames whose band-passed textures correlate ≥ :data:`SAME_SCENE` are one scene; a
frame whose texture does not repeat in its own background frame — a bare sky, noise — cannot be placed by its
texture and joins the other such frames of its video). :func:`radial_falloff` is the one-sided t-test of the
scenes' mean ``s`` against 0 (one value per scene, ≥ 3 scenes) and the fall-off ``k`` it implies
(:func:`falloff_k`).

**A codec's block grid** is fixed in the frame too: JPEG (and a video codec's transform) quantises 8x8 blocks
counted from the frame's top-left, so the intensity jumps across the grid's lines more than between the other
columns (rows). Each frame's ``blockiness`` is the median over the grid's lines of the log ratio of the mean
absolute step across a line to the mean step inside the blocks beside it, the smaller of the columns' and the
rows' (the crop left out; 0 without a grid): a codec's blocks are square, so its grid shows in both directions,
while a sensor's fixed column (row) pattern, whose random steps may fall larger on the grid's columns in every
frame of the camera, shows in one;
:func:`block_grid` tests it over scenes as the fall-off is. A JPEG's quality is read from the same grid
(:func:`jpeg_quality`): the decoded blocks' DCT coefficients sit on multiples of the quantisation steps, the
steps of libjpeg's table at that quality.
**In-camera sharpening** (an unsharp mask after the sensor) is in the whole frames too: it steepens every edge and
puts a halo beside it. Each frame's ``edge_ratio`` (:func:`edge_ratio`) is read off its strong edges (gradient
maxima of the top :data:`EDGE_QUANTILE` of the gradient, contrast ≥ :data:`EDGE_MIN_CONTRAST`): the mean
antisymmetric profile ``D(o) = I(x + o·n) - I(x - o·n)`` across them at 2 and 4 px, ``A(2) / A(4)``, the share of an
edge's full step already made 2 px from its centre — larger for sharper edges (a blur lowers it, a sharpening
halo raises it). The edges are found, oriented and kept on the seed's **background frame** (an independent look at
the same scene) and the profile is read on the frame: the frame's noise then does not choose the edges it is
measured on, so noise adds no sharpness (selected and read on one noisy look, the reference camera's shot noise
read as sharper edges than a sharpening of amount 1). A pattern fixed in the frame is in both looks, though: a
sensor's column gains make every column step a little, a step chosen as an edge's centre on the background frame
adds to every step across it on the frame, and the reference camera's 2 % column pattern read 0.85-1.5 where clean
frames read 0.62-0.64. So the line gains are divided out of both looks first (:func:`destripe`: each column's
gain the median over the rows of the log background's high-pass across the columns, each row's likewise, repeated
:data:`DESTRIPE_PASSES` times), which leaves clean frames within 0.002 and brings those cases to 0.63-0.65
(``results/diagnose/null/edge_ratio_cases.py``). The gains are read on the unclipped pixels only, and no edge is
read within its profile's reach of a clipped pixel: a saturated sky holds the 8-bit end in the columns whose gain
lifts it past white and not in the others, so read as gains it striped the rest of the frame, and divided by them it
became a shared fine pattern of its own (a 4 % pattern read up to 0.009 above its clean case; stop 99,
``results/diagnose/null/column_edges.py``). The setting is read the same way (:func:`sharpening_setting`):
the unsharp mask whose exact inverse (:func:`unsharp_inverse`) brings the frames' edge ratio back to the clean mean.
Without an independent look (an ingested video whose
background frame is the frame itself off the object) the ratio is not measured. A scene's own edges (poles,
clouds) set its level, so it is tested over scenes as the fall-off is (:func:`sharp_edges`), against the mean
that clean frames give it (the calibrated centre): unlike a fall-off or a block grid, edge sharpness has no
physical zero. A sharpening steepens every edge alike, wherever it lies in the frame; a lens changes the image's
local scale with the distance from the centre, and with it the edges' sharpness (the reference camera's pincushion
raised the mean ratio past sharpening's floor). So each frame also reads the ratio's trend toward the corners
(:func:`edge_radial`), and edges that steepen toward the corners beyond :data:`EDGE_RADIAL_FLOOR` do not name
sharpening.

**A lens's radial distortion** is fixed in the frame as well, but it moves nothing a single frame shows: it bends the
scene's motion. Between a frame and its background frame the scene moves a little (the camera drifts, the scene
sways); through an undistorted lens that motion is one shift over the whole frame, through a lens of division-model
``k`` a shift ``t`` shows at frame point ``p`` as about ``t + k (|p|² t + 2 p (p·t))`` — more at the corners
(pincushion) or less (barrel). Fitting the frame as its background seen through that map
(:func:`radial_flow`, Gauss-Newton on the two looks, the crop left out) reads ``k`` — the two-view estimate of radial
distortion (Fitzgibbon 2001). On the object (20-30 px, within r² < 0.4 of the centre) the same lens is a
stretch of a few percent that the fitted pose absorbs. The reading needs a shift of at least :data:`MIN_DRIFT_PX`
and an independent look (an ingested video's background frame is the frame itself); :func:`lens_flow` tests it
over scenes, two-sided, each frame weighed by the precision of its reading (a small shift reads k noisily), the
scenes' spread beyond their stated errors added to every error (a random-effects mean).
"""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

__all__ = ["line_profiles", "fixed_line_pattern", "HIGH_PASS", "frame_summary", "scene_clusters", "radial_falloff",
           "block_grid", "jpeg_quality", "falloff_k", "SAME_SCENE", "FALLOFF_BLOCK", "CODEC_BLOCK",
           "edge_ratio", "edge_steps", "edge_radial", "EDGE_RADIAL_FLOOR", "sharp_edges", "destripe", "unsharp_inverse",
           "sharpening_setting", "EDGE_OFFSETS",
           "EDGE_QUANTILE", "EDGE_MIN_CONTRAST", "SETTING_FRAMES",
           "radial_flow", "lens_flow", "MIN_DRIFT_PX"]

HIGH_PASS = 7  # frame px: the window of the local quadratic removed from a profile (the scene's slow changes)
FALLOFF_BLOCK = 4  # frame px: the side of the blocks a frame's fall-off is fitted on
CODEC_BLOCK = 8  # frame px: the block grid of JPEG and of video codecs' transforms, from the frame's top-left
DCT_POSITIONS = ((0, 0), (0, 1), (1, 0), (1, 1), (0, 2), (2, 0))  # the 8x8 DCT coefficients a quality is read from
SCENE_BAND = (3, 15)  # blocks: a scene's texture is its block image's running mean over 3 minus over 15 blocks
SAME_SCENE = 0.6  # textures correlating at least this much show the same scene (measured: a frame and its own
# background frame 0.88-0.94 median, two independent sky scenes at most 0.57, on the reference camera's cases)
EDGE_OFFSETS = (2, 4)  # frame px: edge_ratio is the mean step across an edge at the first over that at the second
EDGE_QUANTILE = 0.97  # the edges: gradient maxima among the frame's strongest 3 % gradients ...
EDGE_MIN_CONTRAST = 8.0 / 255.0  # ... whose step between 4 px either side reaches this on the background frame
MIN_EDGES = 20  # fewer edges in a frame: no ratio
EDGE_RADIAL_FLOOR = 0.046092
"""The frames' edge-sharpness trend toward the corners (:func:`edge_radial`, mean over scenes) above which edges
that are sharper than clean frames' are not a sharpening (which steepens every edge alike) but something that
changes with the distance from the centre, as a lens does (:func:`~synthaug.diagnose.screening.frame_channel`). It is
the calibration's floor rule (:mod:`synthaug.diagnose.calibration`: ``max(max(μ, 0) + zσ, max)``, z one-sided) on the
44 clean calibration cases (μ 0.0057, σ 0.0131, max 0.0321; z 3.0781; the full-fit set's seed sets made at that
fit's view step and sprite size, as the calibration made them, since stop 67), measured by
``results/diagnose/null/edge_radial_scenes.py`` (``clip_s99/edge_radial_scenes.json``, its ``clean`` block; stop 99's
edges kept off clipped pixels moved it from 0.045629). It only
withholds a finding, so it is not one of the calibrated tests the family-wise z counts."""
SAME_LOOK = 0.9  # share of equal pixels above which a background frame is the frame itself (no second look)
DESTRIPE_PASSES = 6  # the 7-px high-pass keeps 6/7 of a line's gain per pass: 6 passes leave (1/7)^6 of it
DESTRIPE_MIN_PIXELS = 16  # unclipped pixels a line needs for destripe to read its gain
# at most this many frames keep their two looks, to read a sharpening's setting (sharpening_setting; its 1-parameter
# read of a 2-parameter mask needs them: 12 frames picked a neighbouring grid point in 3 of 5 cases)
SETTING_FRAMES = 100
FLOW_SIGMA = 1.0  # frame px: both looks are smoothed by this before the scene's motion between them is fitted
FLOW_ITERS = 10  # at most this many damped Gauss-Newton steps a stage (radial_flow: coarse, then fine)
FLOW_MARGIN = 6  # frame px left out at the frame's edges (a shifted look's border has no partner)
FLOW_MAX_K = 0.3  # |k| beyond the parameter's range: the motion fit has diverged (no reading)
FLOW_MAX_DRIFT_PX = 8.0  # a larger motion between the looks is not a drift the fit can follow (no reading)
MIN_DRIFT_PX = 0.15
"""A shift smaller than this (frame px) cannot tell a lens's k (:func:`radial_flow` gives none). The distortion's
share of the motion is ``k`` times the shift, so a small shift's reading is noisy but not wrong: :func:`lens_flow`
weighs each frame by its precision. Measured on the 44 clean calibration cases (stop 100,
``results/diagnose/null/centre_s100/flow_small_drift.py``): with those weights the clean cases' ``|k|`` stays at
most 0.033 down to 0.15 px (0.016 at 0.2, 0.025 at 0.3), where the lens's realistic strengths read 0.09-0.16, and
falls apart below it (0.14 at 0.1 px: a case with three frames that moved more)."""


def line_profiles(frame: np.ndarray, *, exclude: Sequence[float] | None = None,
                  high_pass: int = HIGH_PASS) -> dict[str, np.ndarray]:
    """A frame's high-passed profiles of mean log intensity: ``"x"`` across its columns (W,), ``"y"`` across
    its rows (H,).

    Args:
        frame: (H, W) or (H, W, C) uint8 or float in [0, 1] (colour: the mean of the channels).
        exclude: ``(x0, y0, side)`` frame px: a square left out of the means (the object's crop).
        high_pass: window (px, odd) of the local quadratic (Savitzky-Golay) subtracted from each profile: a
            smooth trend — a scene's slow change, a vignetting's parabola — leaves nothing, at the frame's edges
            too (a running mean there leaves a vignetting's edge in every video alike: a false column pattern).

    Example:
        >>> f = np.full((40, 60), 100, np.uint8); f[:, 30] = 110  # one brighter column
        >>> p = line_profiles(f)
        >>> int(np.argmax(p["x"])), bool(abs(p["y"]).max() < 1e-12)
        (30, True)
    """
    from scipy.signal import savgol_filter

    f = np.asarray(frame, np.float64)
    if f.ndim == 3:
        f = f.mean(-1)
    if f.ndim != 2:
        raise ValueError(f"frame must be (H, W) or (H, W, C), got shape {np.shape(frame)}")
    if np.asarray(frame).dtype == np.uint8:
        f = f / 255.0
    log = np.log(np.clip(f, 1.0 / 255.0, None))
    w = np.ones_like(log)
    if exclude is not None:
        x0, y0, side = (float(v) for v in exclude)
        h, wd = log.shape
        xa, xb = int(np.clip(np.floor(x0), 0, wd)), int(np.clip(np.ceil(x0 + side), 0, wd))
        ya, yb = int(np.clip(np.floor(y0), 0, h)), int(np.clip(np.ceil(y0 + side), 0, h))
        w[ya:yb, xa:xb] = 0.0
    out = {}
    for name, axis in (("x", 0), ("y", 1)):
        m = (log * w).sum(axis) / np.maximum(w.sum(axis), 1.0)
        out[name] = m - savgol_filter(m, int(high_pass), 2, mode="interp")
    return out


def fixed_line_pattern(profiles: Sequence[np.ndarray], groups: Sequence[Any], rng: np.random.Generator, *,
                       n_perm: int = 4999) -> dict[str, Any] | None:
    """The cross-video agreement of line profiles at the same frame line, with its permutation test.

    Args:
        profiles: one high-passed profile per seed (:func:`line_profiles`' ``"x"`` or ``"y"``).
        groups: each seed's video (seeds of one video are averaged; a seed without one is its own group).
        rng: generator of the circular shifts.
        n_perm: number of random shift sets of the null.

    Returns:
        None when fewer than two groups share the most common profile length; else ``rho`` (the statistic),
        ``p`` (one-sided: the pattern agrees more than chance alignment), ``pattern`` (the mean profile over
        the groups: the estimated log-gain pattern, high-passed), ``amplitude`` (its standard deviation),
        ``period_px`` / ``peak_ratio`` (the pattern spectrum's strongest period and its power over the
        spectrum's median: a periodic pattern has a high ratio), ``groups``, ``seeds`` and ``length``.

    Example:
        >>> rng = np.random.default_rng(0)
        >>> gain = 0.02 * rng.standard_normal(200)  # a fixed pattern, in every video
        >>> prof = [gain + 0.01 * rng.standard_normal(200) for _ in range(12)]
        >>> out = fixed_line_pattern(prof, [i % 4 for i in range(12)], np.random.default_rng(1), n_perm=999)
        >>> out["rho"] > 0.8, out["p"] < 0.01, out["groups"]
        (True, True, 4)
    """
    lengths = [len(p) for p in profiles]
    if not lengths:
        return None
    size = max(set(lengths), key=lengths.count)
    keep = [i for i, n in enumerate(lengths) if n == size]
    names = [str(groups[i]) if groups[i] is not None else f"seed{i}" for i in keep]
    vids = sorted(set(names))
    if len(vids) < 2:
        return None
    prof = np.stack([np.asarray(profiles[i], np.float64) for i in keep])
    lab = np.asarray(names)
    d = np.stack([prof[lab == v].mean(0) for v in vids])  # (V, L)
    n_v = d.shape[0]
    sq = float((d ** 2).sum())  # a circular shift keeps every profile's norm: only the sum over videos changes
    rho = _agreement(d.sum(0)[None], sq, n_v)[0]
    off = rng.integers(0, size, (int(n_perm), n_v))
    off[:, 0] = 0  # only the videos' relative shifts matter
    null = np.empty(int(n_perm))
    cols = np.arange(size)
    for a in range(0, int(n_perm), 512):  # chunks: memory (chunk, length), not (n_perm, videos, length)
        o = off[a:a + 512]
        total = np.zeros((o.shape[0], size))
        for v in range(n_v):
            total += d[v][(cols[None, :] - o[:, v:v + 1]) % size]
        null[a:a + 512] = _agreement(total, sq, n_v)
    pattern = d.mean(0)
    power = np.abs(np.fft.rfft(pattern - pattern.mean())) ** 2
    freqs = np.fft.rfftfreq(size)
    band = freqs >= 2.0 / size  # periods up to half the frame
    in_band = np.where(band, power, -np.inf)
    # the fundamental: the lowest frequency within half the strongest peak (a comb's harmonics are as strong)
    j = int(np.flatnonzero(in_band >= 0.5 * in_band.max())[0])
    return {"rho": float(rho), "p": float((1 + np.sum(null >= rho)) / (int(n_perm) + 1)), "pattern": pattern,
            "amplitude": float(pattern.std()), "period_px": float(1.0 / freqs[j]),
            "peak_ratio": float(power[j] / max(float(np.median(power[band])), 1e-30)),
            "groups": int(n_v), "seeds": len(keep), "length": int(size)}


def _agreement(total: np.ndarray, sq: float, n_v: int) -> np.ndarray:
    """ρ from the (K, L) sums over the groups' profiles, the groups' summed squared norms ``sq`` and their
    number: the mean cross-group inner product over the mean squared norm."""
    return 0.5 * ((total ** 2).sum(-1) - sq) / max(0.5 * (n_v - 1) * sq, 1e-30)


# ------------------------------------------------------------------ radial fall-off (vignetting)
def _gray(frame: np.ndarray) -> np.ndarray:
    """A frame as float (H, W) in [0, 1] (colour: the mean of the channels)."""
    a = np.asarray(frame)
    f = a.astype(np.float64)
    if f.ndim == 3:
        f = f.mean(-1)
    if f.ndim != 2:
        raise ValueError(f"frame must be (H, W) or (H, W, C), got shape {np.shape(frame)}")
    return f / 255.0 if a.dtype == np.uint8 else f


def _unclipped(f: np.ndarray) -> np.ndarray:
    """The pixels of a float [0, 1] frame off its 8-bit ends (a clipped pixel says nothing of gain or motion)."""
    return (f > 2.5 / 255.0) & (f < 252.5 / 255.0)


def _gray_log(frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A frame's log intensity (colour: the mean of the channels) and its unsaturated pixels."""
    f = _gray(frame)
    return np.log(np.clip(f, 1.0 / 255.0, None)), _unclipped(f)


def _two_looks(frame: np.ndarray, background: np.ndarray, outside: np.ndarray | None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Both looks as float gray and where they may be compared (``outside``, else everywhere), or None when they
    are not two looks at one scene: other shapes, or a background that is the frame itself (≥ :data:`SAME_LOOK`
    of those pixels equal)."""
    f, b = _gray(frame), _gray(background)
    if f.shape != b.shape:
        return None
    ok = np.ones(f.shape, bool) if outside is None else np.asarray(outside, bool)
    if np.mean(f[ok] == b[ok]) >= SAME_LOOK:
        return None
    return f, b, ok


def _blocks(log: np.ndarray, ok: np.ndarray, step: int) -> tuple[np.ndarray, np.ndarray]:
    """Block means of ``log`` over ``ok`` pixels (step x step blocks), and whether a block has ≥ half its pixels."""
    h, w = log.shape[0] // step * step, log.shape[1] // step * step
    sm = (log * ok)[:h, :w].reshape(h // step, step, w // step, step).sum((1, 3))
    n = ok[:h, :w].reshape(h // step, step, w // step, step).sum((1, 3))
    return sm / np.maximum(n, 1), n >= step * step / 2


def _pixel_radius(shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Normalised frame position (dx, dy) of every pixel of a frame ``shape`` = (H, W): relative to the frame
    centre over the half diagonal, as :func:`synthaug.effects.camera_functional.frame_coordinates`."""
    h, w = shape
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float64)
    radius = 0.5 * math.hypot(w, h)
    return (xs - (w - 1) / 2.0) / radius, (ys - (h - 1) / 2.0) / radius


def _block_fit(values: np.ndarray, ok: np.ndarray, step: int) -> float:
    """``s`` of the least-squares fit ``v = a_j + b_j dx + c dy - s r²`` within each row ``j`` of blocks (each row its own
    level and tilt, one fall-off ``s`` for the frame) over the blocks with ≥ half their pixels usable, each block's
    ``v``, dx and r² the means over its usable pixels; rows with under 4 such blocks left out (NaN under 16 blocks
    in all). ``1 - k r²`` is ``-k (dx² + dy²)`` in log to first order and ``dy²`` is constant along a row, so the
    fall-off is read across the frame's width alone: whatever changes with height in the frame (the sky's gradient
    with elevation, a horizon, the ground at the bottom) goes into the rows' own levels."""
    dx, dy = _pixel_radius(values.shape)
    v, keep = _blocks(values, ok, step)
    # the block means of r² and dy: constant along a row of whole blocks (the row's level absorbs them), not in
    # the blocks the crop cuts (the mean over their usable rows), so both stay regressors
    x = _blocks(dx, ok, step)[0]
    common = np.stack([_blocks(dx ** 2 + dy ** 2, ok, step)[0], _blocks(dy, ok, step)[0]], -1)
    gram, rhs = np.zeros((2, 2)), np.zeros(2)
    used = 0
    for j in range(v.shape[0]):
        m = keep[j]
        if int(m.sum()) < 4:
            continue
        q, _ = np.linalg.qr(np.stack([np.ones(int(m.sum())), x[j, m]], 1))  # the row's level and tilt
        rv = v[j, m] - q @ (q.T @ v[j, m])
        rc = common[j, m] - q @ (q.T @ common[j, m])
        gram, rhs, used = gram + rc.T @ rc, rhs + rc.T @ rv, used + int(m.sum())
    if used < 16 or gram[0, 0] <= 0:
        return float("nan")
    coef = np.linalg.lstsq(gram, rhs, rcond=None)[0]
    return -float(coef[0])


def _blockiness(f: np.ndarray, ok: np.ndarray, block: int) -> float:
    """The median over the block grid's lines (between pixel ``block·m - 1`` and ``block·m``) of the log ratio of
    the mean |step| across the line to the mean |step| of the ``block - 1`` steps around it inside the two
    half-blocks beside it (each position's mean over the usable pixel pairs), for columns and rows, the smaller of
    the two (NaN when a direction has no line with its neighbours): a codec's square blocks lift both, a fixed
    column or row pattern one. The median over lines, against each line's own
    neighbours: a codec lifts every line; a few lines that step more for other reasons (a scene's edge, the centre
    line and the borders of a lens-distortion resampling, which an average over lines read as a 1-2 % grid) do not
    move it."""
    out = []
    half = block // 2
    for axis in (1, 0):
        d = np.abs(np.diff(f, axis=axis))
        m = ok[:, 1:] & ok[:, :-1] if axis == 1 else ok[1:] & ok[:-1]
        if axis == 0:
            d, m = d.T, m.T
        n = m.sum(0)
        step = np.where(n > 0, (d * m).sum(0) / np.maximum(n, 1), np.nan)  # mean |step| at each position
        logs = []
        for i in range(block - 1, len(step), block):  # the step between pixels i and i + 1 = block·m
            if i - (half - 1) < 0 or i + half + 1 > len(step):
                continue
            others = np.r_[step[i - (half - 1):i], step[i + 1:i + half + 1]]
            if math.isfinite(step[i]) and np.isfinite(others).all():
                logs.append(math.log(max(float(step[i]), 1e-6) / max(float(others.mean()), 1e-6)))
        if not logs:
            return float("nan")
        out.append(float(np.median(logs)))
    return float(min(out))


def _block_dct(f: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """:data:`DCT_POSITIONS` coefficients of the 8x8 grid blocks of ``f`` (0-255) whose pixels are all ``ok``."""
    import torch

    from synthaug.effects.camera_functional import dct_matrix  # the model's own JPEG DCT (orthonormal)

    b = CODEC_BLOCK
    h, w = f.shape[0] // b * b, f.shape[1] // b * b
    blocks = (f[:h, :w] - 128.0).reshape(h // b, b, w // b, b).transpose(0, 2, 1, 3).reshape(-1, b, b)
    good = ok[:h, :w].reshape(h // b, b, w // b, b).all((1, 3)).ravel()
    d = dct_matrix(torch.float64, "cpu").numpy()
    c = d @ blocks[good] @ d.T
    return np.stack([c[:, u, v] for u, v in DCT_POSITIONS], 1).astype(np.float32)


def _texture(log: np.ndarray, step: int) -> np.ndarray:
    from scipy.ndimage import uniform_filter

    b, _ = _blocks(log, np.ones(log.shape, bool), step)
    t = uniform_filter(b, SCENE_BAND[0], mode="nearest") - uniform_filter(b, SCENE_BAND[1], mode="nearest")
    return (t - t.mean()).astype(np.float32)


def _corr(a: np.ndarray, b: np.ndarray) -> float:
    a, b = a.ravel().astype(np.float64), b.ravel().astype(np.float64)
    den = math.sqrt(float((a * a).sum()) * float((b * b).sum()))
    return float((a * b).sum() / den) if den > 0 else 0.0


def _column_nanmedian(x: np.ndarray) -> np.ndarray:
    """Each column's median over its non-NaN entries (every column holding one): ``np.nanmedian(x, axis=0)`` to the
    bit, by one sort (NaNs sort last) instead of numpy's masked-array path for short columns, 4-5x faster on a
    frame's lines (``tests/test_frame_pattern.py`` checks it against numpy).

    Example:
        >>> x = np.array([[1.0, np.nan], [3.0, 5.0], [np.nan, 2.0], [2.0, np.nan]])
        >>> _column_nanmedian(x).tolist(), np.nanmedian(x, axis=0).tolist()
        ([2.0, 3.5], [2.0, 3.5])
    """
    s = np.sort(x, axis=0)
    n = np.count_nonzero(~np.isnan(x), axis=0)
    cols = np.arange(x.shape[1])
    return (s[(n - 1) // 2, cols] + s[n // 2, cols]) / 2


def destripe(frame: np.ndarray, background: np.ndarray, *, valid: np.ndarray | None = None,
             passes: int = DESTRIPE_PASSES, width: int = HIGH_PASS) -> tuple[np.ndarray, np.ndarray]:
    """Both looks with the gains fixed in the frame's columns and rows divided out, as read on ``background``.

    Each pass: a column's log gain is the median over the rows of ``log B`` minus its running mean over ``width``
    columns (the scene's edges cross a column in few rows, the gain in all), likewise each row's; both looks are
    divided by them. Only ``valid`` pixels are read (the running mean over the valid ones among the ``width``, the
    median over the valid ones of the line; a line with fewer than :data:`DESTRIPE_MIN_PIXELS` keeps its gain):
    a clipped pixel holds the 8-bit end, not its column's gain, and a saturated sky read as gains would stripe
    every other row of the frame. Float (H, W) in, float out.

    Args:
        valid: (H, W) bool, the pixels that carry the scene; None: those of ``background`` off the 8-bit ends.

    Example:
        >>> rng = np.random.default_rng(0)
        >>> scene = 0.5 + 0.002 * rng.standard_normal((64, 96))
        >>> gain = 1 + 0.03 * rng.standard_normal(96)  # a 3 % column pattern
        >>> f, b = destripe(scene * gain, scene * gain)
        >>> steps = lambda x: float(np.diff(np.log(x), axis=1).std())  # column to column
        >>> steps(b / scene) < 0.05 * steps(gain[None])
        True
        >>> bright = scene.copy()
        >>> bright[:40] += 0.6  # a saturated sky over 40 of the 64 rows: clipped, it holds no gain
        >>> look = np.clip(bright * gain, 0.0, 1.0)
        >>> f, b = destripe(look, look)
        >>> steps(b[40:] / scene[40:]) < 0.05 * steps(gain[None])
        True
    """
    from scipy import ndimage

    f, b = np.asarray(frame, np.float64), np.asarray(background, np.float64)
    ok = _unclipped(b) if valid is None else np.asarray(valid, bool)
    m, every = ok.astype(np.float64), bool(ok.all())
    # the valid pixels' share of each running window and the lines with enough of them: fixed over the passes
    near = {axis: np.maximum(ndimage.uniform_filter1d(m, width, axis=axis, mode="nearest"), 1e-12) for axis in (1, 0)}
    enough = {axis: ok.sum(axis=1 - axis) >= DESTRIPE_MIN_PIXELS for axis in (1, 0)}
    for _ in range(passes):
        for axis in (1, 0):
            lb = np.log(np.clip(b, 1.0 / 255.0, None))
            mean = ndimage.uniform_filter1d(lb * m, width, axis=axis, mode="nearest") / near[axis]
            hp = np.where(ok, lb - mean, np.nan)
            hp_lines = hp if axis == 1 else hp.T  # each gain's line a column of hp_lines
            g = np.zeros(enough[axis].shape)
            if enough[axis].any():  # (a frame without a clipped pixel: the plain median, 2x faster)
                g[enough[axis]] = (np.median(hp_lines[:, enough[axis]], axis=0) if every
                                   else _column_nanmedian(hp_lines[:, enough[axis]]))
            g = np.exp(-g)[None, :] if axis == 1 else np.exp(-g)[:, None]
            f, b = f * g, b * g
    return f, b


def unsharp_inverse(image: np.ndarray, amount: float, sigma: float) -> np.ndarray:
    """The exact inverse of the unsharp mask ``I + a (I - G_σ * I)`` on a float (H, W) image: division by its
    transfer function ``1 + a (1 - exp(-2π² σ² |f|²))`` (≥ 1, so stable), the image reflect-padded by 4σ.

    Example:
        >>> from scipy import ndimage
        >>> img = np.random.default_rng(0).random((40, 48))
        >>> sharp = img + 1.0 * (img - ndimage.gaussian_filter(img, 1.0, mode="reflect", truncate=8.0))
        >>> bool(np.abs(unsharp_inverse(sharp, 1.0, 1.0) - img)[8:-8, 8:-8].max() < 1e-3)
        True
    """
    pad = int(math.ceil(4.0 * sigma)) + 1
    x = np.pad(np.asarray(image, np.float64), pad, mode="reflect")
    fy = np.fft.fftfreq(x.shape[0])[:, None]
    fx = np.fft.rfftfreq(x.shape[1])[None, :]
    h = 1.0 + amount * (1.0 - np.exp(-2.0 * math.pi ** 2 * sigma ** 2 * (fx ** 2 + fy ** 2)))
    return np.fft.irfft2(np.fft.rfft2(x) / h, s=x.shape)[pad:-pad, pad:-pad]


def sharpening_setting(summaries: Sequence[dict[str, Any]], grid: Sequence[dict[str, float]], centre: float
                       ) -> dict[str, Any] | None:
    """The camera's sharpening read off the frames: of ``grid``'s unsharp masks (``sharpen_amount``,
    ``sharpen_sigma`` in frame px), the one whose inverse (:func:`unsharp_inverse`, on both looks) brings the mean
    edge ratio of the frames that kept their looks (``"looks"`` of :func:`frame_summary`) closest to ``centre``,
    the clean frames' mean.

    Returns:
        None without such frames; else ``setting`` and ``ratios`` (each grid setting's mean ratio once undone).
    """
    looks = [f["looks"] for f in summaries if f.get("looks") is not None]
    if not looks:
        return None
    ratios = []
    for g in grid:
        a, sg = float(g["sharpen_amount"]), float(g["sharpen_sigma"])
        # the captures' clipped pixels, which ``out`` leaves out (frame_summary), not those of the filtered looks
        r = [edge_ratio(unsharp_inverse(fr, a, sg), unsharp_inverse(bg, a, sg), outside=out, unclipped=out)
             for fr, bg, out in looks]
        ratios.append(float(np.nanmean(r)) if np.isfinite(r).any() else float("nan"))
    err = np.abs(np.asarray(ratios) - centre)
    if not np.isfinite(err).any():
        return None
    return {"setting": dict(grid[int(np.nanargmin(err))]), "ratios": ratios}


def edge_steps(frame: np.ndarray, background: np.ndarray, *, outside: np.ndarray | None = None,
               offsets: tuple[int, int] = EDGE_OFFSETS, unclipped: np.ndarray | None = None) -> dict[str, Any] | None:
    """Each edge :func:`edge_ratio` reads, and its steps across it: the edges found, oriented and kept on
    ``background``, the steps read on ``frame`` (arguments as :func:`edge_ratio`).

    Returns:
        None where :func:`edge_ratio` is NaN for want of looks or edges; else ``y``, ``x`` (frame px of each edge's
        centre), ``a1``, ``a2`` (the frame's step between ``±offsets[0]`` and ``±offsets[1]`` px across it) and
        ``shape`` (H, W).
    """
    from scipy import ndimage

    looks = _two_looks(frame, background, outside)
    if looks is None:
        return None
    f, b, ok = looks
    h, w = f.shape
    # a clipped pixel's step is the 8-bit end's, and it holds no line gain
    valid = _unclipped(f) & _unclipped(b) if unclipped is None else np.asarray(unclipped, bool)
    f, b = destripe(f, b, valid=valid)  # a fixed line pattern is in both looks: it would choose the edges it is read on
    gs = ndimage.gaussian_filter(b, 1.0)
    gx, gy = ndimage.sobel(gs, 1), ndimage.sobel(gs, 0)
    g = np.hypot(gx, gy)
    o1, o2 = offsets
    m = 2 * o2  # the profile must stay inside the frame
    inner = np.zeros((h, w), bool)
    inner[m:h - m, m:w - m] = True
    usable = ok & valid
    if not usable.all():  # away from the crop (the object's edges are not the scene's) and the clipped pixels
        # by the profile's reach (a square's dilation: the separable max filter, the same pixels 4x faster)
        inner &= ~ndimage.maximum_filter(~usable, size=2 * o2 + 1, mode="constant", cval=False)
    if inner.sum() < MIN_EDGES:
        return None
    ys, xs = np.nonzero(inner & (g >= np.quantile(g[inner], EDGE_QUANTILE)) & (g > 0))
    nx, ny = gx[ys, xs] / g[ys, xs], gy[ys, xs] / g[ys, xs]
    at = lambda img, o: ndimage.map_coordinates(img, [ys + o * ny, xs + o * nx], order=1)  # noqa: E731
    keep = (g[ys, xs] >= at(g, 1.0)) & (g[ys, xs] >= at(g, -1.0))  # the edge's centre: a maximum across it
    keep &= at(b, float(o2)) - at(b, -float(o2)) >= EDGE_MIN_CONTRAST
    ys, xs, nx, ny = ys[keep], xs[keep], nx[keep], ny[keep]
    if len(ys) < MIN_EDGES:
        return None
    return {"y": ys, "x": xs, "a1": at(f, float(o1)) - at(f, -float(o1)), "a2": at(f, float(o2)) - at(f, -float(o2)),
            "shape": (int(h), int(w))}


def edge_ratio(frame: np.ndarray, background: np.ndarray, *, outside: np.ndarray | None = None,
               offsets: tuple[int, int] = EDGE_OFFSETS, unclipped: np.ndarray | None = None) -> float:
    """The sharpness of a frame's edges: ``A(o1) / A(o2)`` of the mean antisymmetric edge profile (module docstring).

    Args:
        frame: (H, W) or (H, W, C) uint8 or float in [0, 1]: the profile is read here.
        background: the same scene without the object, an independent look (same shape): the edges are found,
            oriented and kept here. Both are first freed of fixed line gains (:func:`destripe`).
        outside: (H, W) bool, where edges may lie (the object's crop left out); None: everywhere. Edges are kept off
            the pixels clipped at either 8-bit end in either look as well.
        offsets: (o1, o2) px from the edge's centre.
        unclipped: (H, W) bool, the pixels off the 8-bit ends in both looks; None: found on the looks given. Looks
            that were filtered after the capture (an unsharp mask's inverse) pass their captures' own.

    Returns:
        The ratio, or NaN with fewer than :data:`MIN_EDGES` edges, frames of different shapes, or a background
        that is the frame itself (≥ :data:`SAME_LOOK` of the pixels equal: no independent look).

    Example:
        >>> from scipy import ndimage
        >>> rng = np.random.default_rng(0)
        >>> scene = ndimage.gaussian_filter((rng.random((24, 32)) > 0.5).repeat(8, 0).repeat(8, 1) * 0.5 + 0.25, 1.0)
        >>> look = lambda img: img + 0.01 * rng.standard_normal(img.shape)
        >>> sharp = scene + 1.0 * (scene - ndimage.gaussian_filter(scene, 1.0))  # unsharp mask, amount 1
        >>> edge_ratio(look(sharp), look(sharp)) > edge_ratio(look(scene), look(scene)) + 0.1
        True
    """
    return _steps_ratio(edge_steps(frame, background, outside=outside, offsets=offsets, unclipped=unclipped))


def _steps_ratio(steps: dict[str, Any] | None) -> float:
    """:func:`edge_ratio` of the edges :func:`edge_steps` found."""
    if steps is None:
        return float("nan")
    a1, a2 = float(np.sum(steps["a1"])), float(np.sum(steps["a2"]))
    return a1 / a2 if a2 > 0 else float("nan")


def edge_radial(steps: dict[str, Any] | None) -> float:
    """How the edges' sharpness changes from the frame's centre to its corners: ``b`` of the least-squares fit
    ``A(o1) = (a + b r²) A(o2)`` over the edges of :func:`edge_steps` (``r²`` the squared distance from the
    frame's centre over the half diagonal's, 1 at the corners).

    A camera's sharpening steepens every edge alike (``b`` ≈ 0); a lens changes the image's local scale with
    ``r²``, and with it the edges' sharpness, in a direction that depends on the scene and on where the lens sits
    among the camera's steps. On the reference camera k₁ +0.1 raises the frames' mean edge ratio and leaves the
    corners' edges steeper (``b`` +0.035 to +0.066 over scenes; clean cases at most :data:`EDGE_RADIAL_FLOOR`;
    ``results/diagnose/README.md``, stops 45 and 66). NaN where ``steps`` is None.

    Example:
        >>> y, x = np.array([47.5, 0.0, 95.0, 47.5]), np.array([63.5, 0.0, 127.0, 20.0])
        >>> r2 = ((x - 63.5) ** 2 + (y - 47.5) ** 2) / (0.25 * (128 ** 2 + 96 ** 2))
        >>> a2 = np.array([1.0, 2.0, 1.5, 0.5])
        >>> steps = {"y": y, "x": x, "a1": (0.6 + 0.05 * r2) * a2, "a2": a2, "shape": (96, 128)}
        >>> round(edge_radial(steps), 6), bool(np.isnan(edge_radial(None)))
        (0.05, True)
    """
    if steps is None:
        return float("nan")
    (h, w), y, x = steps["shape"], np.asarray(steps["y"], np.float64), np.asarray(steps["x"], np.float64)
    r2 = ((x - (w - 1) / 2) ** 2 + (y - (h - 1) / 2) ** 2) / (0.25 * (w * w + h * h))
    a2 = np.asarray(steps["a2"], np.float64)
    (_, b), *_ = np.linalg.lstsq(np.stack([a2, a2 * r2], 1), np.asarray(steps["a1"], np.float64), rcond=None)
    return float(b)


def _division_u(px: np.ndarray, py: np.ndarray, tx: float, ty: float, k: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``u = U(p) - t`` of the division model (``U(p) = p / (1 + k|p|²)``) and ``|p|²``: where the fixed point of
    :func:`_division_sample` starts, and what :func:`_division_jacobian` differentiates."""
    r2 = px * px + py * py
    return px / (1.0 + k * r2) - tx, py / (1.0 + k * r2) - ty, r2


def _division_sample(px: np.ndarray, py: np.ndarray, tx: float, ty: float, k: float,
                     iters: int = 16) -> tuple[np.ndarray, np.ndarray]:
    """Where the background frame shows what frame point ``p`` (normalised by the half diagonal) shows, for a
    scene moved by ``(tx, ty)`` (same units) between the two looks under the division model's ``k``:
    ``D(U(p) - t)`` with ``U(p) = p / (1 + k|p|²)`` and ``D`` its inverse (fixed point ``q = u (1 + k|q|²)``,
    a contraction by ``2|k||q|² ≤ 0.3`` a step for ``|k| < 0.3`` within the frame: 16 steps leave ``0.3¹⁶ < 1e-8`` of
    the error, so :func:`_division_jacobian`, the exact map's derivative, is this sample's)."""
    ux, uy, _ = _division_u(px, py, tx, ty, k)
    qx, qy = ux.copy(), uy.copy()
    with np.errstate(over="ignore", invalid="ignore"):  # a diverging iterate (|k| too large) ends NaN, checked
        for _ in range(iters):
            f = 1.0 + k * (qx * qx + qy * qy)
            qx, qy = ux * f, uy * f
    return qx, qy


def _division_jacobian(px: np.ndarray, py: np.ndarray, qx: np.ndarray, qy: np.ndarray, tx: float, ty: float,
                       k: float) -> tuple[np.ndarray, ...]:
    """The derivatives of :func:`_division_sample`'s ``q`` in ``tx``, ``ty`` and ``k``, by the implicit function
    theorem at its fixed point ``q = u s`` (``s = 1 + k|q|²``, ``u = U(p) - t``): ``(I - 2k u qᵀ) dq = s du + u |q|²
    dk`` with ``du/dt = -I`` and ``du/dk = -p |p|² / (1 + k|p|²)²``, solved by Sherman-Morrison.

    Returns:
        ``(dqx/dtx, dqy/dtx, dqx/dty, dqy/dty, dqx/dk, dqy/dk)``.

    Example:
        >>> rng = np.random.default_rng(0)
        >>> px, py = rng.uniform(-0.7, 0.7, (2, 50))
        >>> th, e = np.array([0.01, -0.02, -0.15]), 1e-6
        >>> qx, qy = _division_sample(px, py, *th, iters=40)
        >>> num = []
        >>> for j in range(3):
        ...     hi, lo = th.copy(), th.copy()
        ...     hi[j] += e
        ...     lo[j] -= e
        ...     (ax, ay), (bx, by) = _division_sample(px, py, *hi, iters=40), _division_sample(px, py, *lo, iters=40)
        ...     num += [(ax - bx) / (2 * e), (ay - by) / (2 * e)]
        >>> ana = _division_jacobian(px, py, qx, qy, *th)
        >>> max(float(np.abs(a - n).max()) for a, n in zip(ana, num)) < 1e-6
        True
    """
    ux, uy, r2 = _division_u(px, py, tx, ty, k)
    q2 = qx * qx + qy * qy
    s = 1.0 + k * q2
    den = 1.0 - 2.0 * k * (qx * ux + qy * uy)

    def solve(vx: np.ndarray, vy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # (I - 2k u qᵀ)⁻¹ v
        c = 2.0 * k * (qx * vx + qy * vy) / den
        return vx + c * ux, vy + c * uy

    dtx = solve(-s, np.zeros_like(s))
    dty = solve(np.zeros_like(s), -s)
    dk_u = -r2 / (1.0 + k * r2) ** 2  # du/dk = p times this
    dk = solve(s * px * dk_u + ux * q2, s * py * dk_u + uy * q2)
    return dtx + dty + dk


def radial_flow(frame: np.ndarray, background: np.ndarray, *, outside: np.ndarray | None = None,
                sigma: float = FLOW_SIGMA, iters: int = FLOW_ITERS) -> dict[str, float]:
    """The lens's radial distortion read off the scene's motion between two looks at it.

    Between the frame and its background frame the scene moves (the camera drifts, the scene sways); through
    a lens without distortion that motion is the same shift everywhere in the frame, through a distorted lens
    it is not: under the division model (``p_u = p_d / (1 + k |p_d|²)``, ``p`` normalised by the half diagonal,
    as :func:`~synthaug.effects.camera_functional.lens_distortion`) a scene shift ``t`` shows at frame point
    ``p`` as about ``t + k (|p|² t + 2 p (p·t))``, stretched toward the corners (pincushion, ``k > 0``) or
    shrunk (barrel) — the two-view estimate of radial distortion (Fitzgibbon 2001). The frame is fitted as the
    background seen through that map, ``F(p) ≈ (1 + g + (c + c₃ |p|²) p·t) B(D(U(p) - t)) + o`` (``g``, ``o``: a
    brightness change; ``c``, ``c₃``: a radial gain fixed in the frame, a vignetting, is in both looks and so
    differs by ``∇log V · t`` between a point and the one it moved from, ``(p·t)(c + c₃|p|²)`` to the third order;
    without them the reference camera's vignetting of 0.3 read k 0.10-0.17), by Gauss-Newton on both looks
    smoothed by ``sigma`` px (the map's derivative exact, :func:`_division_jacobian`), started from the phase
    correlation's shift, first on a quarter of the pixels, then on all of them, where the pixels lie ``outside``
    the object's crop and inside a 6-px margin.

    Args:
        frame, background: (H, W) or (H, W, C) uint8 or float in [0, 1]: two looks at the same scene.
        outside: (H, W) bool, where the scene may be compared (the object's crop left out); None: everywhere.
        sigma: the smoothing (px).
        iters: at most this many steps on the quarter of the pixels, and as many on all of them.

    Returns:
        ``k``, its least-squares standard error ``k_se`` (pixels treated as independent: a lower bound), the
        shift ``drift`` (frame px) and ``pixels`` used. ``k`` is NaN when the looks cannot tell it: a background
        that is the frame itself (no second look), other shapes, fewer than 1,000 usable pixels, a fit that
        diverges or moves more than :data:`FLOW_MAX_DRIFT_PX`, or a shift under
        :data:`MIN_DRIFT_PX` (the distortion's share of the motion is ``k`` times the shift).

    Example:
        >>> from scipy import ndimage
        >>> from synthaug.effects.camera_functional import lens_distortion
        >>> import torch
        >>> rng = np.random.default_rng(0)
        >>> scene = ndimage.gaussian_filter(rng.random((120, 160)), 2.0)
        >>> moved = ndimage.shift(scene, (0.6, -0.8), order=3, mode="reflect")
        >>> look = lambda s: lens_distortion(torch.tensor(s)[None, None], -0.15, recentre=False,
        ...                                  border="border")[0, 0].numpy()
        >>> out = radial_flow(look(moved), look(scene))
        >>> round(out["drift"], 1), abs(out["k"] + 0.15) < 0.02
        (1.0, True)
    """
    import cv2
    from scipy import ndimage

    nan = {"k": float("nan"), "k_se": float("nan"), "drift": float("nan"), "pixels": 0}
    looks = _two_looks(frame, background, outside)
    if looks is None:
        return nan
    f, b, ok = looks
    h, w = f.shape
    m = np.zeros((h, w), bool)
    m[FLOW_MARGIN:h - FLOW_MARGIN, FLOW_MARGIN:w - FLOW_MARGIN] = True
    m &= ok & _unclipped(f)
    if outside is not None:
        m &= ~ndimage.binary_dilation(~ok, iterations=3)
    if m.sum() < 1000:
        return nan
    fs, bs = ndimage.gaussian_filter(f, sigma), ndimage.gaussian_filter(b, sigma)
    gy_img, gx_img = np.gradient(bs)
    radius = 0.5 * math.hypot(h, w)
    yy, xx = np.nonzero(m)
    cx, cy = (w - 1) / 2.0, (h - 1) / 2.0
    px, py = (xx - cx) / radius, (yy - cy) / radius
    r2 = px * px + py * py
    # the cubic spline's coefficients once (as map_coordinates would make them at every call: the frame padded by
    # 12 px of its edge, then filtered), and the gradients' bilinear reads
    pad = 12
    coef = ndimage.spline_filter(np.pad(bs, pad, mode="edge"), 3, output=np.float64, mode="nearest")
    at = lambda img, x, y, order=1, off=0.0: ndimage.map_coordinates(  # noqa: E731
        img, [y * radius + cy + off, x * radius + cx + off], order=order, mode="nearest", prefilter=False)
    (sx, sy), _ = cv2.phaseCorrelate(bs.astype(np.float64), fs.astype(np.float64))
    if math.hypot(sx, sy) > FLOW_MAX_DRIFT_PX:  # a spurious peak (a bare sky): start from no motion
        sx, sy = 0.0, 0.0
    th = np.array([float(sx), float(sy), 0.0, 0.0, 0.0, 0.0, 0.0])  # t_x, t_y (px), k, gain, offset, static gain
    target = fs[yy, xx]

    def gauss_newton(th: np.ndarray, sel: np.ndarray, min_points: int, inside_k: float | None,
                     tol: tuple[float, float]):
        """Damped Gauss-Newton steps from ``th`` on the pixels ``sel`` whose scene lies inside the frame under the
        lens ``inside_k`` (None: the current step's k): the last step's (th, jac, resid, step), or None when the fit
        cannot go on (a diverged map, too few points, a singular system). Converged: a step under ``tol`` (k, px)."""
        sx_, sy_, sr2, star = px[sel], py[sel], r2[sel], target[sel]
        for _ in range(iters):
            t_x, t_y, k, g, o, c, c3 = th
            qx, qy = _division_sample(sx_, sy_, t_x / radius, t_y / radius, k)
            if not (np.isfinite(qx).all() and np.isfinite(qy).all()):
                return None
            bq = at(coef, qx, qy, 3, float(pad))
            gxq, gyq = at(gx_img, qx, qy), at(gy_img, qx, qy)
            # a radial gain fixed in the frame (vignetting) differs by ∇log V · t between p and where it moved
            # from: (p·t) (c + c3 |p|²) for V = 1 - k r² up to the third order
            pt = sx_ * t_x + sy_ * t_y
            gain = 1.0 + g + (c + c3 * sr2) * pt
            # the map's derivative in t_x, t_y (px) and k
            d = _division_jacobian(sx_, sy_, qx, qy, t_x / radius, t_y / radius, k)
            cols = [gain * (gxq * d[0] + gyq * d[1]), gain * (gxq * d[2] + gyq * d[3]),
                    gain * radius * (gxq * d[4] + gyq * d[5])]
            # only points whose scene lies inside the frame: a look rendered from a frame-sized scene repeats its
            # border beyond it (a barrel lens's corners), a real lens would show more scene there; neither moves
            # as t
            ki = k if inside_k is None else inside_k
            inside = (np.abs(sx_ / (1.0 + ki * sr2)) * radius <= cx - FLOW_MARGIN) & \
                     (np.abs(sy_ / (1.0 + ki * sr2)) * radius <= cy - FLOW_MARGIN)
            if inside.sum() < min_points:
                return None
            jac = np.stack(cols + [bq, np.ones_like(bq), bq * pt, bq * pt * sr2], 1)[inside]
            resid = (star - (gain * bq + o))[inside]
            if not np.isfinite(jac).all():
                return None
            try:
                step = np.linalg.solve(jac.T @ jac, jac.T @ resid)
            except np.linalg.LinAlgError:
                return None
            step[:2] = np.clip(step[:2], -1.0, 1.0)  # damped: at most 1 px and 0.05 in k a step (a far start)
            step[2] = float(np.clip(step[2], -0.05, 0.05))
            th = th + step
            if abs(th[2]) >= FLOW_MAX_K or not np.isfinite(th).all():
                return None
            if abs(step[2]) < tol[0] and np.abs(step[:2]).max() < tol[1]:  # converged
                break
        return th, jac, resid, step

    # coarse to fine: the steps from the start on every second pixel of every second row (a quarter of the cost),
    # then on every pixel from where they ended, with the points inside the frame under the k they ended at: a set
    # that follows each step's k makes the objective jump as points enter and leave it, and the steps then swing
    # between two states instead of converging. If the coarse steps failed, the fine ones start afresh.
    # A scene that moved less than half of MIN_DRIFT_PX on the coarse steps has no k to read: the fine steps are
    # skipped (k has no hold on a still scene's map, so they would swing to the iteration limit).
    every = np.ones(len(yy), bool)
    coarse = gauss_newton(th, (yy % 2 == 0) & (xx % 2 == 0), 250, None, (1e-3, 1e-2))
    if coarse is None:
        last = gauss_newton(th, every, 1000, None, (1e-5, 1e-3))
    elif math.hypot(coarse[0][0], coarse[0][1]) < 0.5 * MIN_DRIFT_PX:
        last = coarse
    else:
        last = gauss_newton(coarse[0], every, 1000, float(coarse[0][2]), (1e-5, 1e-3))
    if last is None:
        return nan
    th, jac, resid, step = last
    jtj = jac.T @ jac
    dof = max(len(resid) - len(th), 1)
    cov = np.linalg.pinv(jtj) * float(np.sum((resid - jac @ step) ** 2)) / dof
    drift = float(math.hypot(th[0], th[1]))
    if drift > FLOW_MAX_DRIFT_PX:
        return nan
    k = float(th[2]) if drift >= MIN_DRIFT_PX else float("nan")
    return {"k": k, "k_se": float(math.sqrt(max(cov[2, 2], 0.0))), "drift": drift, "pixels": int(m.sum())}


def frame_summary(frame: np.ndarray, *, exclude: Sequence[float] | None = None,
                  background: np.ndarray | None = None, step: int = FALLOFF_BLOCK,
                  keep_looks: bool = False) -> dict[str, Any]:
    """One frame's radial log fall-off, its codec blockiness and its scene's texture.

    Args:
        frame: (H, W) or (H, W, C) uint8 or float in [0, 1].
        exclude: ``(x0, y0, side)`` frame px: a square left out of the fit (the object's crop), widened by 2 px.
        background: the seed's background frame (the same scene without the object), or None: whether the
            frame's texture repeats there (``repeat``) says if the texture can tell its scene.
        step: block side (px).
        keep_looks: keep the two looks (float32 gray frame and background, where edges may lie) when the edge
            ratio is measured, for :func:`sharpening_setting`.

    Returns:
        ``log_slope`` (``s`` of ``log I = a + b dx + c dy - s r²``, least squares over the blocks; ``s > 0``:
        darker toward the corners; NaN with fewer than 16 usable blocks), ``texture`` (float32 (H/step, W/step):
        the band-passed block log image), ``repeat`` (its correlation with the background's texture; NaN without
        one), ``edge_ratio`` (:func:`edge_ratio` against the background frame; NaN without an independent one),
        ``edge_radial`` (:func:`edge_radial` of the same edges; NaN likewise),
        ``looks`` (with ``keep_looks``, else None), ``flow_k``, ``flow_k_se`` and ``flow_drift`` (:func:`radial_flow`
        against the background frame: the lens's k, its standard error and the scene's shift between the looks; NaN
        without an independent one or too small a shift) and ``shape`` (H, W).

    Example:
        >>> h, w = 96, 128
        >>> yy, xx = np.mgrid[0:h, 0:w]
        >>> r2 = ((xx - (w - 1) / 2) ** 2 + (yy - (h - 1) / 2) ** 2) / (0.25 * (w * w + h * h))
        >>> out = frame_summary(0.5 * (1 - 0.3 * r2))
        >>> round(falloff_k(out["log_slope"], (h, w)), 2)
        0.3
    """
    log, unclipped = _gray_log(frame)
    h, w = log.shape
    outside = np.ones((h, w), bool)  # outside the object's crop
    if exclude is not None:
        x0, y0, side = (float(v) for v in exclude)
        xa, xb = int(np.clip(np.floor(x0 - 2), 0, w)), int(np.clip(np.ceil(x0 + side + 2), 0, w))
        ya, yb = int(np.clip(np.floor(y0 - 2), 0, h)), int(np.clip(np.ceil(y0 + side + 2), 0, h))
        outside[ya:yb, xa:xb] = False
    slope = _block_fit(log, unclipped & outside, step)
    lin = np.exp(log)
    blockiness = _blockiness(lin, outside, CODEC_BLOCK)
    dct = _block_dct(lin * 255.0, outside & unclipped)
    tex = _texture(log, step)
    repeat, edges, radial, looks = float("nan"), float("nan"), float("nan"), None
    flow = {"k": float("nan"), "k_se": float("nan"), "drift": float("nan")}
    if background is not None:
        blog, b_unclipped = _gray_log(background)
        if blog.shape == log.shape:
            repeat = _corr(tex, _texture(blog, step))
            fg, bg = _gray(frame), _gray(background)  # once: the ratio and the kept looks read the same gray frames
            steps = edge_steps(fg, bg, outside=outside)
            edges, radial = _steps_ratio(steps), edge_radial(steps)
            if keep_looks and math.isfinite(edges):  # the clipped pixels kept out of the looks' later reads
                looks = (fg.astype(np.float32), bg.astype(np.float32), outside & unclipped & b_unclipped)
            flow = radial_flow(fg, bg, outside=outside)
    return {"log_slope": slope, "blockiness": blockiness, "dct": dct, "texture": tex, "repeat": repeat,
            "edge_ratio": edges, "edge_radial": radial, "looks": looks, "flow_k": flow["k"],
            "flow_k_se": flow["k_se"], "flow_drift": flow["drift"],
            "shape": (int(h), int(w))}


def scene_clusters(summaries: Sequence[dict[str, Any]], groups: Sequence[Any], *,
                   same: float = SAME_SCENE) -> np.ndarray:
    """Which frames show the same scene: connected components of "same scene" pairs.

    Two frames are one scene when their textures (:func:`frame_summary`) correlate ≥ ``same``; a frame whose
    texture does not repeat in its own background frame (``repeat`` < ``same`` or unknown: a bare sky, a noisy
    frame) cannot be placed by its texture and is one scene with every other such frame of its group (video).

    Returns:
        (N,) int labels, 0..C-1 in order of first appearance.

    Example:
        >>> rng = np.random.default_rng(0)
        >>> a, b = rng.standard_normal((2, 24, 32)).astype(np.float32)
        >>> f = [{"texture": t + 0.1 * rng.standard_normal(t.shape), "repeat": 0.9} for t in (a, a, b)]
        >>> f.append({"texture": rng.standard_normal(a.shape), "repeat": float("nan")})  # cannot be placed
        >>> f.append({"texture": rng.standard_normal(a.shape), "repeat": 0.2})           # nor this one
        >>> scene_clusters(f, ["v0", "v0", "v0", "v1", "v1"]).tolist()
        [0, 0, 1, 2, 2]
    """
    n = len(summaries)
    parent = list(range(n))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    def union(i: int, j: int) -> None:
        a, b = find(i), find(j)
        if a != b:
            parent[max(a, b)] = min(a, b)

    placed = [bool(np.isfinite(f.get("repeat", np.nan)) and f["repeat"] >= same) for f in summaries]
    names = [str(g) if g is not None else f"seed{i}" for i, g in enumerate(groups)]
    by_shape: dict[tuple, list[int]] = {}
    for i, f in enumerate(summaries):
        by_shape.setdefault(np.shape(f["texture"]), []).append(i)
    for idx in by_shape.values():
        t = np.stack([np.asarray(summaries[i]["texture"], np.float64).ravel() for i in idx])
        norm = np.linalg.norm(t, axis=1)
        c = (t @ t.T) / np.maximum(np.outer(norm, norm), 1e-30)
        for a, b in zip(*np.nonzero(np.triu(c >= same, 1))):
            union(idx[a], idx[b])
    first: dict[str, int] = {}
    for i in range(n):
        if not placed[i]:
            j = first.setdefault(names[i], i)
            union(i, j)
    roots = [find(i) for i in range(n)]
    order = {r: k for k, r in enumerate(dict.fromkeys(roots))}
    return np.array([order[r] for r in roots], dtype=np.int64)


def falloff_k(log_slope: float, shape: tuple[int, int], *, step: int = FALLOFF_BLOCK) -> float:
    """The vignetting strength ``k`` (``1 - k r²``, the fraction of light lost at the corners) whose log the fit of
    :func:`frame_summary` gives the slope ``log_slope`` on a frame of ``shape`` (H, W) (clipped to [-1, 0.99]).

    Example:
        >>> round(falloff_k(0.0, (96, 128)), 6), falloff_k(5.0, (96, 128))
        (0.0, 0.99)
    """
    from scipy.optimize import brentq

    dx, dy = _pixel_radius(shape)
    r2 = dx ** 2 + dy ** 2
    ok = np.ones(r2.shape, bool)

    def g(k: float) -> float:
        return _block_fit(np.log(np.clip(1.0 - k * r2, 1e-6, None)), ok, step) - log_slope

    lo, hi = -1.0, 0.99
    if not math.isfinite(log_slope):
        return float("nan")
    if g(hi) <= 0:
        return hi
    if g(lo) >= 0:
        return lo
    return float(brentq(g, lo, hi, xtol=1e-6))


def _over_scenes(summaries: Sequence[dict[str, Any]], groups: Sequence[Any], key: str, same: float,
                 centre: float = 0.0, *, two_sided: bool = False) -> dict[str, Any] | None:
    """The one-sided t-test (> ``centre``; ``two_sided``: ≠) of ``key`` over scenes: each scene's mean over its
    frames (None under 3)."""
    from scipy import stats

    keep = [i for i, f in enumerate(summaries) if math.isfinite(f.get(key, float("nan")))]
    if not keep:
        return None
    lab = scene_clusters([summaries[i] for i in keep], [groups[i] for i in keep], same=same)
    v = np.array([summaries[i][key] for i in keep])
    means = np.array([v[lab == c].mean() for c in range(int(lab.max()) + 1)])
    if len(means) < 3:
        return None
    t = stats.ttest_1samp(means, centre, alternative="two-sided" if two_sided else "greater")
    shapes = [tuple(summaries[i]["shape"]) for i in keep]
    return {"mean": float(means.mean()), "t": float(t.statistic), "p": float(t.pvalue), "scenes": int(len(means)),
            "frames": len(keep), "shape": max(set(shapes), key=shapes.count)}


def radial_falloff(summaries: Sequence[dict[str, Any]], groups: Sequence[Any], *,
                   same: float = SAME_SCENE) -> dict[str, Any] | None:
    """The camera's radial fall-off over the frames, tested over scenes.

    Args:
        summaries: one :func:`frame_summary` per seed.
        groups: each seed's video (None: its own).
        same: :func:`scene_clusters`' threshold.

    Returns:
        None with fewer than 3 scenes that have a slope; else ``log_slope`` (the mean over scenes of each
        scene's mean ``s``), ``t``, ``p`` (one-sided: darker toward the corners), ``k`` (:func:`falloff_k` of
        ``log_slope`` on the most common frame size), ``scenes``, ``frames``.

    Example:
        >>> rng = np.random.default_rng(0)
        >>> f = [{"log_slope": 0.35 + 0.2 * rng.standard_normal(), "texture": rng.standard_normal((24, 32)),
        ...       "repeat": 0.9, "shape": (96, 128)} for _ in range(30)]
        >>> out = radial_falloff(f, [i % 5 for i in range(30)])
        >>> out["scenes"], out["p"] < 1e-6, 0.2 < out["k"] < 0.4
        (30, True, True)
    """
    r = _over_scenes(summaries, groups, "log_slope", same)
    if r is None:
        return None
    return {"log_slope": r["mean"], "t": r["t"], "p": r["p"], "k": falloff_k(r["mean"], r["shape"]),
            "scenes": r["scenes"], "frames": r["frames"]}


def block_grid(summaries: Sequence[dict[str, Any]], groups: Sequence[Any], *,
               same: float = SAME_SCENE) -> dict[str, Any] | None:
    """A codec's block grid over the frames (their ``blockiness``), tested over scenes as :func:`radial_falloff`.

    Returns:
        None with fewer than 3 scenes; else ``log_ratio`` (the mean over scenes: the steps across the grid's
        lines are typically ``exp(log_ratio)`` times those inside the blocks beside them), ``t``, ``p``
        (one-sided), ``scenes``, ``frames``.

    Example:
        >>> rng = np.random.default_rng(0)
        >>> f = [{"blockiness": 0.2 + 0.05 * rng.standard_normal(), "texture": rng.standard_normal((24, 32)),
        ...       "repeat": 0.9, "shape": (96, 128)} for _ in range(10)]
        >>> out = block_grid(f, [None] * 10)
        >>> out["scenes"], out["p"] < 1e-6
        (10, True)
    """
    r = _over_scenes(summaries, groups, "blockiness", same)
    if r is None:
        return None
    return {"log_ratio": r["mean"], "t": r["t"], "p": r["p"], "scenes": r["scenes"], "frames": r["frames"]}


def tone_undone(summaries: Sequence[dict[str, Any]], exponent: float) -> list[dict[str, Any]]:
    """The frame summaries with each kept look's edges read again through the inverse of a tone curve ``x^g``.

    A tone curve after the optics bends every edge's profile: ``g`` > 1 steepens its bright half and flattens its
    dark one, and the edge ratio ``A(o1) / A(o2)`` moves although nothing sharpened the frame (gamma 1.4 puts the
    reference camera's frames above sharpening's clean floor). Once the curve is known (an accepted ``gamma``
    finding), sharpening is read on the looks mapped by ``x^(1/g)``, where the clean frames' calibration holds.

    Args:
        summaries: :func:`frame_summary` outputs; only those that kept their ``looks`` can be read again.
        exponent: ``g`` of the tone curve (``gamma_g``).

    Returns:
        The summaries with ``edge_ratio`` and ``edge_radial`` read on the undone looks (and those looks as
        ``looks``); NaN for a summary without looks (it drops out of :func:`sharp_edges`'s test).

    Example:
        >>> from scipy import ndimage
        >>> rng = np.random.default_rng(0)
        >>> scene = ndimage.gaussian_filter((rng.random((24, 32)) > 0.5).repeat(8, 0).repeat(8, 1) * 0.6 + 0.2, 1.0)
        >>> look = lambda img: np.clip(img + 0.005 * rng.standard_normal(img.shape), 0, 1)
        >>> s = {"looks": (look(scene) ** 1.5, look(scene) ** 1.5, None)}
        >>> r0 = edge_ratio(look(scene), look(scene))
        >>> abs(tone_undone([s], 1.5)[0]["edge_ratio"] - r0) < 0.01 < abs(edge_ratio(*s["looks"][:2]) - r0)
        True
    """
    if not (np.isfinite(exponent) and exponent > 0):
        raise ValueError(f"tone curve exponent must be finite and > 0, got {exponent}")
    out = []
    for f in summaries:
        looks = f.get("looks")
        if looks is None:
            out.append({**f, "edge_ratio": float("nan"), "edge_radial": float("nan")})
            continue
        frame, background, outside = looks
        undone = [np.clip(np.asarray(x, np.float64), 0.0, 1.0) ** (1.0 / exponent) for x in (frame, background)]
        steps = edge_steps(undone[0], undone[1], outside=outside, unclipped=outside)
        out.append({**f, "edge_ratio": _steps_ratio(steps), "edge_radial": edge_radial(steps),
                    "looks": (undone[0].astype(np.float32), undone[1].astype(np.float32), outside)})
    return out


def sharp_edges(summaries: Sequence[dict[str, Any]], groups: Sequence[Any], *, centre: float | None,
                same: float = SAME_SCENE) -> dict[str, Any] | None:
    """In-camera sharpening over the frames (their ``edge_ratio``), tested over scenes as :func:`radial_falloff`,
    against ``centre``: the mean ratio clean frames give (the calibration's; None: not calibrated, p = 1).

    Returns:
        None with fewer than 3 scenes that have a ratio; else ``ratio`` (the mean over scenes), ``t``, ``p``
        (one-sided: sharper than ``centre``), ``centre``, ``scenes``, ``frames``, and ``radial``: the mean over
        scenes of the frames' :func:`edge_radial` (NaN where fewer than 3 scenes have one), how the sharpness
        changes toward the corners (a lens's signature, not a sharpening's).

    Example:
        >>> rng = np.random.default_rng(0)
        >>> f = [{"edge_ratio": 0.75 + 0.03 * rng.standard_normal(), "texture": rng.standard_normal((24, 32)),
        ...       "repeat": 0.9, "shape": (96, 128)} for _ in range(10)]
        >>> out = sharp_edges(f, [None] * 10, centre=0.63)
        >>> out["scenes"], out["p"] < 1e-6, sharp_edges(f, [None] * 10, centre=None)["p"]
        (10, True, 1.0)
    """
    r = _over_scenes(summaries, groups, "edge_ratio", same, 0.0 if centre is None else centre)
    if r is None:
        return None
    rad = _over_scenes(summaries, groups, "edge_radial", same, two_sided=True)
    return {"ratio": r["mean"], "t": r["t"] if centre is not None else float("nan"),
            "p": r["p"] if centre is not None else 1.0, "centre": centre, "scenes": r["scenes"],
            "frames": r["frames"], "radial": float("nan") if rad is None else rad["mean"]}


def lens_flow(summaries: Sequence[dict[str, Any]], groups: Sequence[Any], *,
              same: float = SAME_SCENE) -> dict[str, Any] | None:
    """A lens's radial distortion over the frames (their ``flow_k``, :func:`radial_flow`), tested over scenes,
    two-sided (barrel or pincushion), as a random-effects meta-analysis of the scenes' readings: each frame weighed
    by its precision, ``1 / (flow_k_se² + τ²)`` (equal weights where a summary has no ``flow_k_se``).

    A frame's k is the distortion's share of the scene's motion divided by the motion, so its error grows as the
    shift shrinks: an unweighted mean over scenes is set by the frames that moved least (stop 100: it needed a shift of
    0.3 px to keep the clean cases' ``|k|`` under 0.027, and a case whose scene moved less had no reading). But
    ``flow_k_se`` treats the pixels as independent, which a scene under a block codec is not (JPEG's fixed grid: frames
    read k ±0.2 with errors of 0.02-0.05), and weights taken at their word then let a few such frames set the answer
    (a compressed clean camera read k 0.10, p_adj 0.002). So the scenes' excess spread ``τ²`` (DerSimonian-Laird: the
    spread beyond what the stated errors allow) is added to every error first, which brings the weights back toward
    equal where the errors are not to be trusted, and the weighted mean is tested by the Hartung-Knapp t (its
    variance the weighted spread of the scenes' k about it, ``S - 1`` degrees of freedom).

    Returns:
        None with fewer than 3 scenes that have a reading (the scene did not move between the looks, or there is
        no independent background frame); else ``k`` (the weighted mean over scenes), ``t``, ``p`` (two-sided),
        ``tau`` (the excess spread, k units), ``scenes``, ``frames``.

    Example:
        >>> rng = np.random.default_rng(0)
        >>> se = rng.uniform(0.01, 0.1, 10)  # frames that moved more read k more precisely
        >>> f = [{"flow_k": -0.15 + s * rng.standard_normal(), "flow_k_se": s, "texture": rng.standard_normal((24, 32)),
        ...       "repeat": 0.9, "shape": (96, 128)} for s in se]
        >>> out = lens_flow(f, [None] * 10)
        >>> out["scenes"], out["p"] < 1e-6, abs(out["k"] + 0.15) < 0.03
        (10, True, True)
    """
    from scipy import stats

    keep = [i for i, f in enumerate(summaries) if math.isfinite(f.get("flow_k", float("nan")))
            and (f.get("flow_k_se") is None or (math.isfinite(f["flow_k_se"]) and f["flow_k_se"] > 0))]
    if not keep:
        return None
    lab = scene_clusters([summaries[i] for i in keep], [groups[i] for i in keep], same=same)
    k = np.array([summaries[i]["flow_k"] for i in keep], np.float64)
    se = [summaries[i].get("flow_k_se") for i in keep]
    w = np.array([1.0 if s is None else 1.0 / (s * s) for s in se], np.float64)
    w_s = np.bincount(lab, weights=w)  # a scene: its frames' precision-weighted mean, weighed by their sum
    k_s = np.bincount(lab, weights=w * k) / w_s
    n = len(k_s)
    if n < 3:
        return None
    fixed = np.sum(w_s * k_s) / w_s.sum()
    q = float(np.sum(w_s * (k_s - fixed) ** 2))
    tau2 = max(0.0, (q - (n - 1)) / float(w_s.sum() - np.sum(w_s ** 2) / w_s.sum()))
    v = 1.0 / (1.0 / w_s + tau2)
    mean = float(np.sum(v * k_s) / v.sum())
    var = float(np.sum(v * (k_s - mean) ** 2) / ((n - 1) * v.sum()))
    t = mean / math.sqrt(var) if var > 0 else math.copysign(math.inf, mean) if mean else 0.0
    p = float(2.0 * stats.t.sf(abs(t), n - 1))
    return {"k": mean, "t": float(t), "p": p, "tau": math.sqrt(tau2), "scenes": int(n), "frames": len(keep)}


def _step_of(coef: np.ndarray, max_step: int = 64, min_values: int = 30) -> tuple[int, float]:
    """The quantisation step of one DCT coefficient's values: for each step ``q``, the phase coherence
    ``mean cos(2π c / q)`` (1: every value on a multiple of ``q``) of the values off its zero bin (``|c| >= q / 2``: a value inside it says nothing of
    ``q``); the largest ``q`` within 0.95 of the best coherence (a step's divisors are as coherent, its multiples and
    its neighbours are not). Returns (step, its coherence); (0, 0) when no step has ``min_values`` values."""
    c = np.abs(coef.astype(np.float64))
    best_q, coh = [], []
    for q in range(2, max_step + 1):
        v = c[c >= q / 2.0]
        if len(v) >= min_values:
            best_q.append(q)
            coh.append(float(np.cos(2.0 * np.pi * v / q).mean()))
    if not coh:
        return 0, 0.0
    coh_a = np.asarray(coh)
    if coh_a.max() <= 0:
        return 0, float(coh_a.max())
    j = int(np.flatnonzero(coh_a >= 0.95 * coh_a.max())[-1])
    return best_q[j], float(coh_a[j])


def jpeg_quality(summaries: Sequence[dict[str, Any]], *, min_coherence: float = 0.5) -> dict[str, Any] | None:
    """The JPEG quality of the frames: the quantisation steps their 8x8 blocks' DCT coefficients sit on
    (:func:`frame_summary`'s ``dct``, pooled over the frames of the most common size), matched to libjpeg's
    luminance table (:func:`synthaug.effects.camera_functional.jpeg_table`, the model's compression).

    Returns:
        None when fewer than 3 coefficients (2 of them AC) sit on a step (a frame that was never JPEG-coded, or
        a codec with other transforms: coherence below ``min_coherence``); else ``quality`` (the middle of the qualities whose table
        matches the measured steps best), ``steps`` ({"u,v": step}), ``coherence`` and ``mismatch`` (the median
        over the positions of |log(step / table step)| at the best quality).

    Example:
        >>> import cv2
        >>> rng = np.random.default_rng(0)
        >>> scene = cv2.GaussianBlur(rng.uniform(30, 220, (192, 256)), (0, 0), 2).astype(np.uint8)
        >>> jpeg = cv2.imdecode(cv2.imencode(".jpg", scene, [cv2.IMWRITE_JPEG_QUALITY, 40])[1], 0)
        >>> q = jpeg_quality([frame_summary(jpeg)])["quality"]
        >>> 35 <= q <= 45, jpeg_quality([frame_summary(scene)])
        (True, None)
    """
    import torch

    from synthaug.effects.camera_functional import jpeg_table

    rows = [f for f in summaries if f.get("dct") is not None and len(f["dct"])]
    if not rows:
        return None
    coef = np.concatenate([f["dct"] for f in rows])
    steps, cohs = {}, {}
    for j, (u, v) in enumerate(DCT_POSITIONS):
        q, coh = _step_of(coef[:, j])
        if q and coh >= min_coherence:
            steps[(u, v)], cohs[(u, v)] = q, coh
    if len(steps) < 3 or len(set(steps) - {(0, 0)}) < 2:  # a table, not one coefficient's chance lattice: a flat
        return None  # sky's blocks put the DC on multiples of 8 (8 x the block's level) whatever the codec
    qualities = np.arange(1, 101, dtype=np.float64)
    table = jpeg_table(torch.as_tensor(qualities)).numpy()  # (100, 8, 8)
    # the median over the positions: one position misread (a divisor of its step) does not move the quality
    err = np.median([np.abs(np.log(q / table[:, u, v])) for (u, v), q in steps.items()], 0)
    best = np.flatnonzero(err <= err.min() + 1e-9)
    return {"quality": float(qualities[best].mean()), "steps": {f"{u},{v}": q for (u, v), q in steps.items()},
            "coherence": float(np.mean(list(cohs.values()))), "mismatch": float(err.min())}
