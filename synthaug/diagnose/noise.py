"""The camera's noise level function, measured on the seed frames (issue 6: noise variance vs. signal).

A fitted composite cannot testify about noise: the model's object noise is
one random realisation, and no distance to one noisy real image rewards the
right noise *model*. The whole frames can. Each seed keeps its frame F and
the frame's background B (the object removed; for video an aligned median of
neighbouring frames, much less noisy), so away from the object
``r = F - B`` is the camera's noise, and binned by the clean signal B it
gives the *noise level function* (NLF) var(I) of the camera (Liu et al.,
"Automatic estimation and removal of noise from a single image", PAMI 2008):

* read noise only (what the model's σ_n assumes): flat, log-log slope 0;
* photon (shot) noise, var = a + b·I: rising, slope up to 1;
* a tone curve f after the sensor: var scales by f'(x)², so a compressive
  curve x^g (g < 1) makes the NLF *fall* with brightness (slope
  2(g - 1)/g with read noise only) — the noise-based radiometric
  calibration of Matsushita & Lin (CVPR 2007); an expansive one (g > 1)
  makes it *rise*, as shot noise does. Their shapes differ: read noise
  through x^g is a power law (straight in log-log), shot noise over read
  noise is affine (flat, then rising; :func:`nlf_shape`); where the two
  coincide (shot noise far above the read noise) the signal's tone tells
  them apart (the tone curve changes it, shot noise does not;
  :func:`synthaug.diagnose.screening.tone_evidence`).

Per seed the log-log slope of the NLF is measured on flat background pixels
(textured pixels, where an aligned median carries registration error, and a
margin around the object are left out; a 5×5 local mean is removed so that
slow illumination changes between frames do not count as noise); the
slopes are t-tested over seeds. The extended model's gain is a held-out
log-likelihood: the NLF model of the candidate, fitted on training seeds,
against a flat NLF, on the pixels of held-out seeds (nats per pixel).

The shot noise's strength comes from the same measurements
(:func:`shot_noise_sigma`): the affine NLF ``var = a_i + σ_shot² · I``
(Foi et al., "Practical Poissonian-Gaussian noise modeling and fitting for
single-image raw-data", TIP 2008), each seed with its own constant part
(read noise, 8-bit rounding), one σ_shot for the camera, the measured
variances first divided by what the high-pass and the second look add
(:data:`HIGH_PASS_VAR`, ``looks``).

Example:
    >>> rng = np.random.default_rng(0)
    >>> b = np.tile(np.linspace(0.3, 0.9, 128), (96, 1))
    >>> f = b + rng.normal(size=b.shape) * np.sqrt(1e-5 + 2e-3 * b)    # shot noise
    >>> nlf = frame_noise_levels(f, b)
    >>> round(nlf_slope(nlf), 1) > 0.5
    True
"""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from synthaug.diagnose.stats import t_test

__all__ = ["frame_noise_levels", "nlf_slope", "seed_noise_levels", "aligned_neighbour", "noise_channel",
           "shot_noise_sigma", "nlf_shape", "NOISE_CANDIDATES", "HIGH_PASS_VAR", "SHAPE_MIN_SHARE"]

# Candidates the noise level function can testify for, with the sign of the log-log slope they produce (gamma:
# its compressive case, g < 1; an expansive curve, g > 1, rises like shot noise, and the NLF's shape or the
# patches' tone tells the two apart: nlf_shape, synthaug.diagnose.screening.shape_verdict and tone_evidence). The
# signs also orient the slope's calibrated floors.
NOISE_CANDIDATES: dict[str, int] = {"shot_noise": +1, "gamma": -1}
# A rising NLF's shape names its cause (:func:`nlf_shape`) only where the held-out log-likelihood it gains over the
# other shape is at least this share of the power law's own gain over a flat NLF: with shot noise far above the
# read noise the affine NLF a + b·I is itself a power law of slope 1, the two shapes coincide, and a consistent but
# negligible difference is no evidence (a utility choice, as the distance channels' 2 %).
SHAPE_MIN_SHARE = 0.05
# Smallest |log-log slope| that counts: the noise std changes by >= 10 % over a doubling of brightness.
SLOPE_FLOOR = 2 * math.log2(1.1)
# A difference of two independently rounded 8-bit frames has sd >= sqrt(2/12) = 0.41 grey levels; below 0.3 the two
# looks are not independent (a video codec copied the block), and the bin measures the codec, not the camera.
MIN_NOISE_SD = 0.3 / 255
# Variance of a standard normal truncated to ±4: the rejection's bias, undone.
_CLIPPED_VAR_4SD = 1.0 - 8.0 * math.exp(-8.0) / math.sqrt(2.0 * math.pi) / math.erf(4.0 / math.sqrt(2.0))
# What the 5x5 local mean removed from ``frame - background`` leaves of white noise's variance: r - mean25(r) weighs
# the centre (1 - 1/25) and 24 neighbours -1/25, so var = ((24/25)² + 24/25²) var(r) = (24/25) var(r).
HIGH_PASS_VAR = 1.0 - 1.0 / 25.0


def _box_mean(x: np.ndarray, k: int) -> np.ndarray:
    from scipy import ndimage

    return ndimage.uniform_filter(x, size=k, mode="reflect")


def frame_noise_levels(frame: np.ndarray, background: np.ndarray, *, exclude: np.ndarray | None = None,
                       n_bins: int = 12, min_count: int = 150, flat_quantile: float = 0.5) -> dict[str, np.ndarray]:
    """The noise level function of one frame: robust noise variance of ``frame - background`` per signal bin.

    Args:
        frame, background: (H, W) in [0, 1] (or uint8).
        exclude: (H, W) bool, pixels to leave out (the object and a margin), with the 5x5
            high-pass window around them. When more than 90 % of the other pixels of
            ``frame - background`` are exactly 0, the background frame is the frame itself there
            (an ingested background replaces only the object region): no bins.
        n_bins: signal bins between the 1st and 99th percentile of the background.
        min_count: bins with fewer pixels are dropped.
        flat_quantile: keep the flattest share of pixels (background gradient below this quantile).

    Returns:
        ``{"signal": (K,) mean background per bin, "var": (K,) noise variance, "count": (K,)}``;
        the variance of the high-passed difference within ±4 robust σ (MAD) of its median, corrected
        for that truncation (robust to the occasional misregistered edge); bins whose noise would
        clip at black or white, or whose noise is below :data:`MIN_NOISE_SD` (a codec's copy of the
        block, not a second exposure), are dropped.
    """
    from scipy import ndimage

    f = _unit(frame)
    b = _unit(background)
    if f.shape != b.shape or f.ndim != 2:
        raise ValueError(f"frame and background must be (H, W) of the same shape, got {f.shape} and {b.shape}")
    r = f - b
    if exclude is not None and np.mean(r[~np.asarray(exclude, bool)] == 0.0) > 0.9:
        # the background frame IS the frame off the object (ingest fills only the object region): no
        # independent second look at the scene, so no noise to measure
        return _empty()
    r = r - _box_mean(r, 5)
    # texture anywhere in the 5x5 high-pass window counts (a misregistered edge leaks into its neighbours)
    # (measured on the smoothed background: the scene's texture, not the noise of a noisy second look)
    bs = ndimage.gaussian_filter(b, 1.5)
    grad = ndimage.maximum_filter(np.hypot(ndimage.sobel(bs, 0), ndimage.sobel(bs, 1)), size=5, mode="nearest")
    keep = np.ones_like(b, bool)
    keep[:3, :] = keep[-3:, :] = False
    keep[:, :3] = keep[:, -3:] = False
    if exclude is not None:  # and the high-pass window around it (r there is not this frame's noise)
        keep &= ~ndimage.binary_dilation(np.asarray(exclude, bool), np.ones((5, 5), bool))
    if keep.sum() < min_count:
        return _empty()
    keep &= grad <= np.quantile(grad[keep], flat_quantile)
    keep &= (b > 2.5 / 255) & (b < 252.5 / 255)  # clipped pixels carry no noise
    s, rv = bs[keep], r[keep]  # binned by the smoothed signal: binning by a noisy one selects on its noise
    if s.size < min_count:
        return _empty()
    edges = np.quantile(s, np.linspace(0.01, 0.99, n_bins + 1))
    sig, var, cnt = [], [], []
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (s >= lo) & (s < hi)
        if m.sum() < min_count or hi - lo < 1e-6:
            continue
        x = rv[m]
        mu = float(np.median(x))
        sd = 1.4826 * float(np.median(np.abs(x - mu))) + 0.5 / 255  # (+ half a grey level: MAD is discrete)
        x = x[np.abs(x - mu) <= 4.0 * sd]  # reject misregistered edges, keep a continuous estimate
        v = float(np.mean((x - x.mean()) ** 2) / _CLIPPED_VAR_4SD)
        lvl = float(s[m].mean())
        if lvl - 3.0 * math.sqrt(v) < 0.0 or lvl + 3.0 * math.sqrt(v) > 1.0:  # noise clipped at black/white
            continue
        if math.sqrt(v) < MIN_NOISE_SD:  # below 8-bit rounding of two independent frames: a codec's copy
            continue
        sig.append(lvl)
        var.append(v)
        cnt.append(int(x.size))
    return {"signal": np.array(sig), "var": np.array(var), "count": np.array(cnt, np.int64)}


def _empty() -> dict[str, np.ndarray]:
    return {"signal": np.zeros(0), "var": np.zeros(0), "count": np.zeros(0, np.int64)}


def _unit(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x)
    return x.astype(np.float64) / 255.0 if x.dtype == np.uint8 else x.astype(np.float64)


def nlf_slope(nlf: dict[str, np.ndarray], *, min_span: float = 0.15) -> float:
    """Log-log slope of one frame's NLF (count-weighted least squares); NaN when the frame's signal
    spans less than ``min_span`` in log (too narrow to measure a slope) or has < 3 usable bins."""
    s, v, c = nlf["signal"], nlf["var"], nlf["count"]
    ok = (s > 0) & (v > 0)
    if ok.sum() < 3:
        return float("nan")
    x, y, w = np.log(s[ok]), np.log(v[ok]), c[ok].astype(np.float64)
    if x.max() - x.min() < min_span:
        return float("nan")
    xm = np.average(x, weights=w)
    return float(np.average((x - xm) * (y - np.average(y, weights=w)), weights=w)
                 / max(np.average((x - xm) ** 2, weights=w), 1e-12))


def _box_mask(shape: tuple[int, int], box: Sequence[float], margin: float) -> np.ndarray:
    ex = np.zeros(shape, bool)
    x, y, w, h = (float(v) for v in box)
    x0, y0 = int(max(0, math.floor(x - margin * w))), int(max(0, math.floor(y - margin * h)))
    x1, y1 = int(math.ceil(x + (1 + margin) * w)), int(math.ceil(y + (1 + margin) * h))
    ex[y0:y1, x0:x1] = True
    return ex


def aligned_neighbour(frame: np.ndarray, neighbour: np.ndarray, homography: Sequence[Sequence[float]],
                      box: Sequence[float] | None, margin: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """A neighbour frame warped onto ``frame`` (bilinear) and the pixels to leave out: outside the warp, and the
    neighbour's object (its ``box``, grown by ``margin``, warped)."""
    import cv2

    h, w = frame.shape[:2]
    H = np.asarray(homography, np.float64)
    warped = cv2.warpPerspective(_unit(neighbour).astype(np.float32), H, (w, h), flags=cv2.INTER_LINEAR,
                                 borderMode=cv2.BORDER_CONSTANT, borderValue=float("nan"))
    out = ~np.isfinite(warped)
    if box is not None:
        m = _box_mask(neighbour.shape[:2], box, margin).astype(np.uint8)
        out |= cv2.warpPerspective(m, H, (w, h), flags=cv2.INTER_NEAREST, borderMode=cv2.BORDER_CONSTANT,
                                   borderValue=0) > 0
    return np.where(out, _unit(frame), warped).astype(np.float64), out


def seed_noise_levels(seeds: Any, *, margin: float = 0.5, frames: Sequence[np.ndarray] | None = None,
                      **kwargs: Any) -> list[dict[str, np.ndarray]] | None:
    """The NLF of every seed's frame (object box grown by ``margin`` of its size left out), against its
    background frame when that is an independent look at the scene (a reference camera's), else against
    its aligned neighbour frame (ingested video: :meth:`~synthaug.data.seedset.SeedSet.neighbour_frame`).
    None without frames or when no seed has a second look (see :func:`frame_noise_levels`). ``frames``: the
    seeds' frames when already read."""
    out = []
    for i in range(len(seeds)):  # each NLF says how many looks of the camera's noise its differences hold
        try:
            f = seeds.frame(i) if frames is None else frames[i]
            b = seeds.background_frame(i)
            nb = seeds.neighbour_frame(i) if hasattr(seeds, "neighbour_frame") else None
        except (FileNotFoundError, OSError, KeyError, IndexError, ValueError):
            return None
        if f is None or b is None:
            return None
        ex = _box_mask(np.asarray(f).shape[:2], seeds.boxes[i], margin)
        levels = {**frame_noise_levels(f, b, exclude=ex, **kwargs), "looks": 1.0}  # B: a less noisy, averaged look
        if not len(levels["signal"]) and nb is not None:
            info = seeds.records[i].get("neighbour", {})
            warped, out_nb = aligned_neighbour(f, nb, info["homography"], info.get("box"), margin)
            levels = {**frame_noise_levels(f, warped, exclude=ex | out_nb, **kwargs), "looks": 2.0}  # two equal looks
        out.append(levels)
    return out if any(len(n["signal"]) for n in out) else None


def _fit_model(nlfs: Sequence[dict[str, np.ndarray]], kind: str) -> np.ndarray:
    """Pooled NLF model on training seeds, each seed with its own level (per-frame gain, exposure):
    ``log var = level_i + s · log I`` (``kind="power"``) or flat (``"flat"``): returns s (0 for flat)."""
    if kind == "flat":
        return np.zeros(1)
    xs, ys, ws = [], [], []
    for n in nlfs:
        ok = (n["signal"] > 0) & (n["var"] > 0)
        if ok.sum() < 2:
            continue
        x, y, w = np.log(n["signal"][ok]), np.log(n["var"][ok]), n["count"][ok].astype(np.float64)
        xs.append(x - np.average(x, weights=w))
        ys.append(y - np.average(y, weights=w))
        ws.append(w)
    if not xs:
        return np.zeros(1)
    x, y, w = np.concatenate(xs), np.concatenate(ys), np.concatenate(ws)
    return np.array([float((w * x * y).sum() / max((w * x * x).sum(), 1e-12))])


def _heldout_loglik(n: dict[str, np.ndarray], slope: float) -> float:
    """Mean Gaussian log-likelihood per pixel of a held-out frame's binned noise under ``var = c · I^slope``
    with the level c its own maximum-likelihood value (the frame's gain is a nuisance)."""
    ok = (n["signal"] > 0) & (n["var"] > 0)
    if ok.sum() < 2:
        return float("nan")
    s, v, c = n["signal"][ok], n["var"][ok], n["count"][ok].astype(np.float64)
    shape = s ** slope
    level = float((c * v / shape).sum() / c.sum())  # ML level: mean of v / shape
    model = level * shape
    return float((c * -0.5 * (np.log(2 * np.pi * model) + v / model)).sum() / c.sum())


def _normalised(n: dict[str, np.ndarray], positive_signal: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A seed's bins with a measurable variance (and a positive signal, for a log-log model): signal, the camera's
    variance (what the high-pass and the second look add divided out), pixel count."""
    ok = (n["var"] > 0) & (n["count"] > 0) & ((n["signal"] > 0) if positive_signal else True)
    return (n["signal"][ok], n["var"][ok] / (HIGH_PASS_VAR * float(n.get("looks", 1.0))),
            n["count"][ok].astype(np.float64))


def _affine_fit(nlfs: Sequence[dict[str, np.ndarray]], iterations: int = 3, positive_signal: bool = False
                ) -> float | None:
    """The common slope b of ``var = a_i + b · I`` (a constant per seed), iteratively re-weighted least squares (each
    bin's variance has relative standard error ``sqrt(2 / count)``: weights ``count / model²``); None with fewer
    than 3 seeds of >= 2 bins or no spread of brightness. ``b`` may be negative."""
    sig, var, cnt, seed = [], [], [], []
    for n in nlfs:
        s, v, c = _normalised(n, positive_signal)
        if len(s) < 2:
            continue
        sig.append(s)
        var.append(v)
        cnt.append(c)
        seed.append(np.full(len(s), len(sig) - 1))
    if len(sig) < 3:
        return None
    s, v, c, g = (np.concatenate(x) for x in (sig, var, cnt, seed))
    if np.ptp(s) <= 0:
        return None
    x = np.zeros((s.size, len(sig) + 1))
    x[np.arange(s.size), g] = 1.0
    x[:, -1] = s
    model = v
    for _ in range(max(1, iterations)):
        sw = np.sqrt(c) / np.maximum(model, 1e-12)
        coef = np.linalg.lstsq(x * sw[:, None], v * sw, rcond=None)[0]
        model = np.maximum(x @ coef, 1e-12)
    return float(coef[-1])


def _heldout_loglik_affine(s: np.ndarray, v: np.ndarray, c: np.ndarray, b: float) -> float:
    """Mean Gaussian log-likelihood per pixel of a held-out frame's binned noise (signal ``s``, variance ``v``, count
    ``c``: :func:`_normalised`) under ``var = a + b · I``, its constant ``a`` its own maximum-likelihood value
    (bounded so that the variance stays positive)."""
    from scipy.optimize import minimize_scalar

    lo = max(-b * float(s.min()), -b * float(s.max()), 0.0) + 1e-12

    def nll(a: float) -> float:
        m = a + b * s
        return float((c * 0.5 * (np.log(2 * np.pi * m) + v / m)).sum() / c.sum())

    return -float(minimize_scalar(nll, bounds=(lo, max(10.0 * lo, 10.0 * float(v.max()))), method="bounded").fun)


def nlf_shape(nlfs: Sequence[dict[str, np.ndarray]], folds: Sequence[np.ndarray]) -> dict[str, Any] | None:
    """Which shape a rising NLF has: a tone curve's power law ``var = c_i · I^s`` (a straight line in log-log: read
    noise through x^g, s = 2(g - 1)/g) or shot noise's affine ``var = a_i + b · I`` (Foi et al.; curved in log-log,
    flat where the read noise dominates). Each shape's common parameter is fitted on the training seeds of each fold,
    the held-out seed's own level (c_i, a_i) by maximum likelihood, and the held-out log-likelihoods compared per
    seed: > 0 the power law (a tone curve) fits better.

    Returns:
        ``gain`` (mean per-seed log-likelihood of the power law minus the affine NLF, nats per pixel), ``p``
        (Wilcoxon's signed-rank test over seeds, two-sided), ``positive`` of ``n`` seeds preferring the power law,
        ``per_seed``; None without 3 seeds of >= 2 bins.

    Example:
        >>> rng = np.random.default_rng(0)
        >>> b = np.tile(np.linspace(0.2, 0.9, 160), (120, 1))
        >>> tone = [frame_noise_levels((b ** (1 / 1.4) + rng.normal(size=b.shape) * r) ** 1.4, b)
        ...         for r in np.linspace(0.004, 0.008, 12)]            # read noise, then x^1.4
        >>> shot = [frame_noise_levels(b + rng.normal(size=b.shape) * np.sqrt(r ** 2 + 0.01 ** 2 * b), b)
        ...         for r in np.linspace(0.004, 0.008, 12)]            # read noise and weak shot noise
        >>> folds = [np.arange(i, 12, 4) for i in range(4)]
        >>> nlf_shape(tone, folds)["gain"] > 0, nlf_shape(shot, folds)["gain"] < 0
        (True, True)
    """
    n = len(nlfs)
    d = np.full(n, np.nan)
    for held in folds:
        train = [nlfs[j] for j in np.setdiff1d(np.arange(n), held)]
        s, b = float(_fit_model(train, "power")[0]), _affine_fit(train, positive_signal=True)
        if b is None:  # fewer than 3 training seeds with a measurable NLF
            continue
        for j in held:
            sj, vj, cj = _normalised(nlfs[j])
            if len(sj) >= 2:
                d[j] = (_heldout_loglik({"signal": sj, "var": vj, "count": cj}, s)
                        - _heldout_loglik_affine(sj, vj, cj, b))
    ok = d[np.isfinite(d)]
    if len(ok) < 3:
        return None
    from scipy.stats import wilcoxon

    # a signed-rank test over seeds: a few frames with a wide brightness range carry most of the likelihood (a
    # t-test gave p 0.02 for 24 of 24 seeds preferring the true power law)
    p = float(wilcoxon(ok).pvalue) if np.any(ok != 0) else 1.0
    return {"gain": float(ok.mean()), "p": p, "positive": int((ok > 0).sum()), "n": int(len(ok)),
            "per_seed": d.tolist()}


def noise_channel(nlfs: Sequence[dict[str, np.ndarray]], folds: Sequence[np.ndarray]) -> dict[str, Any]:
    """Evidence from the noise level function: per-seed slopes (t-test) and the held-out likelihood gain.

    Returns:
        ``slope`` (mean log-log slope), ``t``, ``p`` (two-sided), ``n_seeds`` (with a measurable
        slope), ``per_seed_slope``, ``gain`` (mean held-out log-likelihood gain of the pooled
        power-law NLF over a flat one, nats per pixel), ``per_seed_gain``, ``fitted_slope`` (on all seeds).
    """
    n = len(nlfs)
    slopes = np.array([nlf_slope(x) for x in nlfs])
    m, t, p = t_test(slopes)
    gains = np.full(n, np.nan)
    for held in folds:
        train = [nlfs[j] for j in np.setdiff1d(np.arange(n), held)]
        s = float(_fit_model(train, "power")[0])
        for j in held:
            gains[j] = _heldout_loglik(nlfs[j], s) - _heldout_loglik(nlfs[j], 0.0)
    return {"slope": m, "t": t, "p": p, "n_seeds": int(np.isfinite(slopes).sum()),
            "per_seed_slope": slopes.tolist(), "gain": float(np.nanmean(gains)) if np.isfinite(gains).any() else 0.0,
            "per_seed_gain": gains.tolist(), "fitted_slope": float(_fit_model(nlfs, "power")[0]),
            "shot_sigma": shot_noise_sigma(nlfs), "shape": nlf_shape(nlfs, folds) if m > 0 else None}


def shot_noise_sigma(nlfs: Sequence[dict[str, np.ndarray]], *, iterations: int = 3) -> float | None:
    """The camera's shot-noise strength σ_shot (frame noise variance ``a + σ_shot² · I``, the reference camera's and
    :func:`synthaug.effects.camera_functional.shot_noise`'s model) from the seeds' NLFs.

    Weighted least squares of the binned variances on ``[one constant per seed, I]``: each frame keeps its own
    constant part (read noise and rounding change with the frame's gain), the slope is the camera's. Each bin's
    variance estimate has relative standard error ``sqrt(2 / count)``, so the weights are ``count / model²``,
    iterated (``iterations`` re-weightings from the measured variances). A measured variance holds
    :data:`HIGH_PASS_VAR` (the 5x5 local mean removed) times ``looks`` (an NLF's key, default 1: the frame's own
    noise over a background averaged from many looks; 2: two equal looks, a frame minus its neighbour) of the
    camera's; a background with some noise of its own (relative variance κ²) makes σ_shot read ``sqrt(1 + κ²)``
    high (≈ 6 % for the reference camera's κ = 0.35), and a neighbour warped by a sub-pixel shift has had its noise
    smoothed by the bilinear interpolation (its variance down to a quarter at half a pixel in x and y), so there
    σ_shot reads up to ``sqrt(1.25 / 2)`` ≈ 0.79 of the truth.

    Returns:
        σ_shot ≥ 0 (0 when the fitted slope is negative: no rise with brightness), or None with fewer than 3
        seeds' NLFs of ≥ 2 bins or no spread of brightness.

    Example:
        >>> rng = np.random.default_rng(0)
        >>> b = np.tile(np.linspace(0.2, 0.9, 160), (120, 1))
        >>> nlfs = [frame_noise_levels(b + rng.normal(size=b.shape) * np.sqrt(r ** 2 + 0.03 ** 2 * b), b)
        ...         for r in (0.004, 0.006, 0.008)]
        >>> round(shot_noise_sigma(nlfs), 2)
        0.03
    """
    b = _affine_fit(nlfs, iterations)
    return None if b is None else math.sqrt(max(b, 0.0))
