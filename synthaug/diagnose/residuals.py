"""Residual analysis: what the fitted simulation gets wrong, and where (issue 6, item 1).

For every seed the residual ``r_i = X_i - S(Θ_i, B_i)`` between the real patch
and its best-fit synthetic image is measured in pixels (and, per seed, in the
detector's feature space), in the object-centred patch frame, with masks from
the fitted coverage (object interior, boundary band, background) and the
patch's place in its full frame. Each *structure measure* is a statistic over
seeds with a null reference, so that a residual which is pure fitting noise
reads as nothing significant:

===================  ==========================================================
measure              statistic and null
===================  ==========================================================
interior_bias        mean residual in the object interior; t-test over seeds
boundary_bias        mean residual in the boundary band; t-test over seeds
radial               interior bias vs r² (frame position); permutation test
tone_curve           per-seed slope of residual vs fitted intensity; t-test
noise_vs_signal      per-seed slope of squared residual vs intensity; t-test
high_frequency       log power ratio real/synthetic above 0.25 cycles/px; t-test
block_8x8            residual jump across the frame's 8-px block grid vs
                     elsewhere; t-test over seeds of the log ratio
motion_direction     residual gradient energy along vs across the fitted motion
                     direction α_m; t-test of the log ratio
rows / columns       peak of the residual's row (column) spectrum over the
                     column (row) spectrum, in frame frequencies; t-test
                     over the seeds that resolve it
rotor_parts          mean residual on the rotor discs vs the body; t-test
column_pattern /     a gain pattern fixed in the frame's columns (rows): the
row_pattern          whole frames' high-passed line profiles agree across
                     videos at the same frame column (row); permutation test
                     of circular shifts per video (:mod:`frame_pattern`)
colour               per-channel bias (grayscale seed sets: not applicable; RGB
                     seed sets are screened in chroma by the colour channel of
                     :mod:`synthaug.diagnose.screening`)
===================  ==========================================================

Fitted parameters can silently absorb a missing effect, which shows as a
dependence of a per-seed value on seed metadata; :func:`parameter_dependence`
tests every (parameter, metadata) pair with a permutation test of Spearman's ρ.

All tests use an explicit ``numpy.random.Generator``. The data they read, and the re-rendered fit, are
:mod:`synthaug.diagnose.diagnosis_data`'s (its names are re-exported here).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import torch

from synthaug.diagnose.calibration import HAND_FLOORS, structure_significant
from synthaug.diagnose.diagnosis_data import (  # noqa: F401  (re-exported: their home before the split)
    GRAY_CHROMA_LEVELS,
    DiagnosisData,
    chroma_distance,
    is_single_channel,
    load_diagnosis_data,
    pairwise_distance,
    pixel_distance,
    render_rgb,
    render_with,
    solve_albedo,
    solve_albedo_rgb,
)
from synthaug.diagnose.stats import permutation_spearman, t_test, within_groups  # noqa: F401  (re-exported)

__all__ = [
    "DiagnosisData",
    "load_diagnosis_data",
    "render_with",
    "region_masks",
    "structure_measures",
    "parameter_dependence",
    "seed_metadata",
    "aligned_maps",
    "t_test",
    "permutation_spearman",
    "within_groups",
    "seed_groups",
    "feature_residual_map",
    "is_single_channel",
    "GRAY_CHROMA_LEVELS",
]


# The hand-set effect-size floors of the structure measures (kept as the fallback of statistics without a null
# calibration): the calibrated rule is synthaug.diagnose.calibration's.
EFFECT_FLOORS = HAND_FLOORS


# ------------------------------------------------------------------ masks and maps
def region_masks(coverage: torch.Tensor, *, band: int = 2) -> dict[str, torch.Tensor]:
    """Interior / boundary band / background masks from the fitted coverage.

    Args:
        coverage: (N, 1, P, P) fitted coverage.
        band: half-width (px) of the boundary band around the coverage edge.

    Returns:
        bool masks (N, 1, P, P): ``interior`` (coverage eroded by ``band``),
        ``boundary`` (dilated minus eroded), ``background`` (outside the dilation).

    Example:
        >>> c = torch.zeros(1, 1, 20, 20); c[..., 5:15, 5:15] = 1
        >>> m = region_masks(c)
        >>> int(m["interior"].sum()), int(m["boundary"].sum()), int(m["background"].sum())
        (36, 160, 204)
    """
    import torch.nn.functional as F

    obj = (coverage > 0.5).float()
    k = 2 * band + 1
    dil = F.max_pool2d(obj, k, 1, band) > 0.5
    ero = -F.max_pool2d(-obj, k, 1, band) > 0.5
    return {"interior": ero, "boundary": dil & ~ero, "background": ~dil}


def aligned_maps(residual: torch.Tensor) -> dict[str, np.ndarray]:
    """Mean and RMS residual over seeds in the object-centred patch frame (P, P)."""
    r = residual[:, 0].double().numpy()
    return {"mean": r.mean(0), "rms": np.sqrt((r ** 2).mean(0))}


def seed_metadata(data: DiagnosisData) -> dict[str, np.ndarray]:
    """Per-seed metadata a fitted parameter may depend on.

    Returns:
        ``radial_r2`` (squared distance of the patch centre from the frame
        centre, 1 at the corners), ``frame_x``, ``frame_y`` (same, signed),
        ``background_brightness`` (mean of B_i), ``object_size`` (frame px per
        patch px: the object's size in the frame), ``inverse_size``, and
        ``frame_brightness`` (mean of the whole frame: what a camera's
        auto-exposure meters) when the seed set has its frames.
    """
    p = data.real.shape[-1]
    c = data.origin.double() + (p / 2.0) * data.frame_scale.double()[:, None]
    fs = data.frame_size.double()
    half_diag = 0.5 * fs.norm(dim=1)
    dx = (c[:, 0] - (fs[:, 0] - 1) / 2) / half_diag
    dy = (c[:, 1] - (fs[:, 1] - 1) / 2) / half_diag
    size = data.frame_scale.double()
    out = {"radial_r2": (dx ** 2 + dy ** 2).numpy(), "frame_x": dx.numpy(), "frame_y": dy.numpy(),
           "background_brightness": data.background.double().mean((1, 2, 3)).numpy(),
           "object_size": size.numpy(), "inverse_size": (1.0 / size).numpy()}
    if data.frame_brightness is not None:
        out["frame_brightness"] = data.frame_brightness.double().numpy()
    return out


@torch.no_grad()
def feature_residual_map(data: DiagnosisData, syn: torch.Tensor) -> dict[str, Any] | None:
    """Where the detector's features differ: the residual in feature space, per spatial feature cell.

    For the HOG distance: the L2 norm of (block_real - block_syn) at every HOG block position
    (:func:`synthaug.detectors.hog.block_features`), per seed, in the object-centred patch frame. Other
    distances: None (their features are not laid out on the patch).

    Returns:
        ``{"mean": (Hb, Wb) mean over seeds, "per_seed": (N, Hb, Wb), "cell_px": block stride (px),
        "share_centre": share of the squared residual in the central half of the blocks}``.
    """
    config = getattr(data.distance, "config", None)
    if data.distance_name not in ("hog", "hog_smooth") or config is None:
        return None
    from synthaug.detectors.hog import block_features, cell_histograms

    br = block_features(cell_histograms(data.real.float(), config), config)
    bs = block_features(cell_histograms(syn.float(), config), config)
    per = (br - bs).pow(2).sum(1).sqrt().double().numpy()  # (N, Hb, Wb)
    hb, wb = per.shape[-2:]
    centre = np.zeros((hb, wb), bool)
    centre[hb // 4:hb - hb // 4, wb // 4:wb - wb // 4] = True
    sq = (per ** 2).sum(0)
    return {"mean": per.mean(0), "per_seed": per, "cell_px": int(config.cell_size),
            "share_centre": float(sq[centre].sum() / max(sq.sum(), 1e-12))}


def seed_groups(data: DiagnosisData) -> np.ndarray | None:
    """Group id per seed (its video), or None when the records do not say or every seed is its own group."""
    vids = [r.get("video") for r in data.records] if data.records else []
    if len(vids) != len(data) or any(v is None for v in vids):
        return None
    g = np.unique(np.asarray([str(v) for v in vids]), return_inverse=True)[1]
    return g if len(np.unique(g)) < len(g) else None


def _masked_mean(x: torch.Tensor, m: torch.Tensor) -> np.ndarray:
    m = m.float()
    return ((x * m).flatten(1).sum(1) / m.flatten(1).sum(1).clamp_min(1.0)).double().numpy()


def _slope(x: np.ndarray, y: np.ndarray) -> float:
    if len(x) < 4 or np.ptp(x) < 1e-6:
        return float("nan")
    xc = x - x.mean()
    return float((xc * (y - y.mean())).sum() / (xc * xc).sum())


def _log_power_ratio(real: torch.Tensor, syn: torch.Tensor, weight: torch.Tensor, fmin: float) -> np.ndarray:
    """Per-seed log(power of real / power of synthetic) above ``fmin`` cycles/px, in a window."""
    p = real.shape[-1]
    w = weight.float()
    fr = torch.fft.fft2((real - real.mean((-2, -1), keepdim=True)) * w)
    fs = torch.fft.fft2((syn - syn.mean((-2, -1), keepdim=True)) * w)
    f = torch.fft.fftfreq(p)
    rad = torch.sqrt(f[:, None] ** 2 + f[None, :] ** 2)
    sel = (rad > fmin)[None, None]
    pr = (fr.abs() ** 2 * sel).flatten(1).sum(1)
    ps = (fs.abs() ** 2 * sel).flatten(1).sum(1)
    return torch.log((pr + 1e-9) / (ps + 1e-9)).double().numpy()


def _block_jump_ratio(residual: torch.Tensor, data: DiagnosisData, weight: torch.Tensor) -> np.ndarray:
    """Per-seed log ratio of residual jumps across the frame's 8-px block grid vs other jumps."""
    from synthaug.effects.camera_functional import frame_coordinates

    n, _, p, _ = residual.shape
    g = frame_coordinates(n, p, p, origin=data.origin, frame_size=data.frame_size, frame_scale=data.frame_scale)
    out = []
    jx = (residual[..., :, 1:] - residual[..., :, :-1]) ** 2
    jy = (residual[..., 1:, :] - residual[..., :-1, :]) ** 2
    wx = weight[..., :, 1:] * weight[..., :, :-1]
    wy = weight[..., 1:, :] * weight[..., :-1, :]
    # a jump between two pixels crosses a block edge when floor(frame coordinate / 8) changes
    bx = torch.floor((g["x"][..., :, 1:] + 0.5) / 8) != torch.floor((g["x"][..., :, :-1] + 0.5) / 8)
    by = torch.floor((g["y"][..., 1:, :] + 0.5) / 8) != torch.floor((g["y"][..., :-1, :] + 0.5) / 8)
    for i in range(n):
        on = torch.cat([(jx[i] * wx[i])[bx[i]], (jy[i] * wy[i])[by[i]]])
        off = torch.cat([(jx[i] * wx[i])[~bx[i]], (jy[i] * wy[i])[~by[i]]])
        won = torch.cat([wx[i][bx[i]], wy[i][by[i]]]).sum()
        woff = torch.cat([wx[i][~bx[i]], wy[i][~by[i]]]).sum()
        if won < 1 or woff < 1:
            out.append(float("nan"))
            continue
        out.append(math.log((float(on.sum() / won) + 1e-9) / (float(off.sum() / woff) + 1e-9)))
    return np.array(out)


def _directional_ratio(residual: torch.Tensor, alpha_m: torch.Tensor, weight: torch.Tensor) -> np.ndarray:
    """Per-seed log(residual gradient energy along the motion direction / across it)."""
    gx = torch.zeros_like(residual)
    gy = torch.zeros_like(residual)
    gx[..., :, 1:-1] = (residual[..., :, 2:] - residual[..., :, :-2]) / 2
    gy[..., 1:-1, :] = (residual[..., 2:, :] - residual[..., :-2, :]) / 2
    a = alpha_m.float().reshape(-1, 1, 1, 1)
    along = gx * torch.cos(a) + gy * torch.sin(a)
    across = -gx * torch.sin(a) + gy * torch.cos(a)
    ea = (along ** 2 * weight).flatten(1).sum(1)
    ec = (across ** 2 * weight).flatten(1).sum(1)
    return torch.log((ea + 1e-9) / (ec + 1e-9)).double().numpy()


def _line_spectrum(residual: torch.Tensor, weight: torch.Tensor, axis: int) -> np.ndarray:
    """(N, P//2+1) power of the residual's profile along ``axis`` (-2: rows, y; -1: columns, x), per seed.

    Each line across ``axis`` is transformed, power averaged over the other axis.
    """
    r = (residual * weight)[:, 0]
    if axis == -2:
        r = r.transpose(-2, -1)
    r = r - r.mean(-1, keepdim=True)
    spec = torch.fft.rfft(r, dim=-1).abs() ** 2
    return spec.mean(1).double().numpy()


PERIODIC_MIN_FREQUENCY = 0.25
"""Cycles per frame px from which the ``periodic_*`` measures seek their peak (periods up to 4 frame px: interlaced
fields, a sensor's line banding, the 8-px block grid's harmonics from 4 px down). Below it an object of 20-30 px
has its shape's own anisotropy: on the 24 clean nuisance-varied calibration cases (seed base 2000) the seeds' mean
row/column log ratio reaches |0.50| below 0.25 cycles per frame px (median case 0.25) and |0.30| from 0.25 up
(median 0.17); the clean range of ``periodic_rows`` went from [-0.42, 0.58] to [-0.25, 0.35] (stop 96,
``results/diagnose/null/periodic_s96/``)."""


def periodic_profile(a: np.ndarray, b: np.ndarray, frame_scale: np.ndarray, *,
                     min_frequency: float = PERIODIC_MIN_FREQUENCY, step: float = 0.0125
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Each seed's log ratio of spectrum ``a`` over spectrum ``b`` on a common grid of frame frequencies.

    A camera's periodic structure (fields, banding) is periodic in FRAME pixels: each seed's log(a / b) over patch
    frequencies >= 0.2 cycles per patch px is put on the grid from ``min_frequency`` to 0.5 cycles per frame px
    (patch frequency / ``frame_scale``; NaN where the seed's patch band does not reach a grid frequency).

    Args:
        a, b: (N, P//2+1) power spectra per seed (``_line_spectrum``), P the patch size.
        frame_scale: (N,) frame px per patch px (``DiagnosisData.frame_scale``: the crop side over the patch size).

    Returns:
        (the grid (F,), the log ratios (N, F)).
    """
    n, n_f = a.shape
    freqs = np.fft.rfftfreq(2 * (n_f - 1))
    hi = np.nonzero(freqs >= 0.2)[0]
    grid = np.round(np.arange(min_frequency, 0.5 + 1e-9, step), 4)
    lr = np.log((a[:, hi] + 1e-12) / (b[:, hi] + 1e-12))
    return grid, np.stack([np.interp(grid, freqs[hi] / frame_scale[i], lr[i], left=np.nan, right=np.nan)
                           for i in range(n)])


def periodic_peak(a: np.ndarray, b: np.ndarray, frame_scale: np.ndarray, *,
                  min_frequency: float = PERIODIC_MIN_FREQUENCY, step: float = 0.0125) -> tuple[float, np.ndarray, int]:
    """The frequency where spectrum ``a`` most exceeds spectrum ``b`` over the seeds, in frame pixels: of
    :func:`periodic_profile`'s grid (arguments as there), the frequency with the largest mean log ratio among those
    at least a quarter of the seeds (and >= 5) measure.

    Returns:
        (peak frequency in cycles per frame px, (N,) each seed's log ratio there (NaN where the seed does not
        reach it), the number of grid frequencies the peak was chosen among (the Bonferroni count)).

    Example:
        >>> f = np.fft.rfftfreq(64); a = np.ones((8, 33)); a[:, np.argmin(abs(f - 0.4))] = 9.0
        >>> freq, lr, m = periodic_peak(a, np.ones((8, 33)), np.ones(8))
        >>> round(freq, 3), round(float(lr.mean()), 2)
        (0.4, 1.32)
    """
    grid, lr_f = periodic_profile(a, b, frame_scale, min_frequency=min_frequency, step=step)
    cnt = np.isfinite(lr_f).sum(0)
    enough = cnt >= max(5, len(lr_f) // 4)
    score = np.where(enough, np.nansum(lr_f, 0) / np.maximum(cnt, 1), -np.inf)
    j = int(np.argmax(score))
    return float(grid[j]), lr_f[:, j], int(enough.sum())


def structure_measures(data: DiagnosisData, syn: torch.Tensor, *, rng: np.random.Generator,
                       alpha: float = 0.01) -> dict[str, dict[str, Any]]:
    """The residual's measured structure, each measure with its null test.

    Args:
        data: the seeds.
        syn: (N, 1, P, P) best-fit synthetic images.
        rng: generator of the permutation tests.
        alpha: significance level (Bonferroni-corrected over the measures). A measure is significant when
            its test rejects at that level and its value leaves the range clean nuisance-varied data give it
            (:func:`synthaug.diagnose.calibration.structure_significant`).

    Returns:
        ``{measure: {"value": effect size, "p": p-value, "significant": bool, "floor": the clean range
        [lo, hi] (or a hand-set floor on |value|), "description": str, ...}}``.
    """
    real = data.real
    res = real - syn
    n = res.shape[0]
    m = region_masks(data.coverage)
    obj = data.coverage > 0.5
    meta = seed_metadata(data)
    out: dict[str, dict[str, Any]] = {}

    def put(name: str, x: np.ndarray | float, pval: float, desc: str, **more: Any) -> None:
        out[name] = {"value": float(np.nanmean(x)) if isinstance(x, np.ndarray) else float(x), "p": float(pval),
                     "description": desc, **more}

    bg_rms = float(np.sqrt(np.nanmean(_masked_mean(res ** 2, m["background"]))))
    for region in ("interior", "boundary", "background"):
        b = _masked_mean(res, m[region])
        mean, t, pv = t_test(b)
        e = np.sqrt(_masked_mean(res ** 2, m[region]))
        put(f"{region}_bias", b, pv, f"mean residual (real - synthetic) in the {region}: {mean:+.4f}",
            rms=float(np.nanmean(e)), rms_over_background=float(np.nanmean(e) / max(bg_rms, 1e-6)))
    ib = _masked_mean(res, m["interior"] | m["boundary"])
    rho, pv = permutation_spearman(meta["radial_r2"], ib, rng)
    put("radial", rho, pv, f"object residual vs radial position in the frame: Spearman rho {rho:+.2f}")

    slopes, vslopes = [], []
    for i in range(n):
        mi = obj[i, 0]
        if int(mi.sum()) < 8:
            slopes.append(np.nan)
            vslopes.append(np.nan)
            continue
        x = syn[i, 0][mi].double().numpy()
        y = res[i, 0][mi].double().numpy()
        slopes.append(_slope(x, y))
        yc = y - np.mean(y)
        vslopes.append(_slope(x, yc ** 2))
    mean, t, pv = t_test(np.array(slopes))
    put("tone_curve", mean, pv, f"object residual vs fitted intensity: mean slope {mean:+.3f} "
        f"({'real brighter where bright' if mean > 0 else 'real darker where bright'})")
    mean, t, pv = t_test(np.array(vslopes))
    put("noise_vs_signal", mean, pv, f"residual variance vs fitted intensity: mean slope {mean:+.2e}")

    wobj = (m["interior"] | m["boundary"]).float()
    lr = _log_power_ratio(real, syn, wobj, 0.25)
    mean, t, pv = t_test(lr)
    put("high_frequency", mean, pv, f"high-frequency power (> 0.25 cycles/px) real/synthetic on the object: "
        f"{math.exp(mean):.2f}x ({'real sharper or noisier' if mean > 0 else 'real blurrier'})")
    bj = _block_jump_ratio(res, data, wobj)
    mean, t, pv = t_test(bj)
    put("block_8x8", mean, pv, f"residual jumps across the frame's 8x8 block grid vs elsewhere: "
        f"{math.exp(mean):.2f}x")
    dr = _directional_ratio(res, data.theta.alpha_m[:, 0], (m["boundary"] | m["interior"]).float())
    mean, t, pv = t_test(dr)
    put("motion_direction", mean, pv, f"residual gradient energy along/across the fitted motion direction: "
        f"{math.exp(mean):.2f}x")
    # anisotropic periodic structure (interlaced fields, sensor banding): the row spectrum over the column
    # spectrum at the same frequency, high frequencies only (where a shape misfit is isotropic)
    w_n = np.maximum(wobj.flatten(1).sum(1).numpy()[:, None], 1)
    spec_rows = _line_spectrum(res, wobj, -2) / w_n
    spec_cols = _line_spectrum(res, wobj, -1) / w_n
    fs = data.frame_scale.double().numpy()
    for label, a, b, what in (("rows", spec_rows, spec_cols, "vertical (along image columns: row-to-row)"),
                              ("columns", spec_cols, spec_rows, "horizontal (column-to-column)")):
        f, lr_f, n_freqs = periodic_peak(a, b, fs)
        mean, t, pv = t_test(lr_f)
        pv = min(1.0, pv * n_freqs)  # the peak was chosen among the frequencies
        put(f"periodic_{label}", mean, pv, f"{what} periodic structure: peak at {f:.3f} cycles per frame px "
            f"(period {1 / f:.1f} frame px), {math.exp(mean):.1f}x the power of the other direction",
            frequency=f, period_px=float(1 / f), n_seeds=int(np.isfinite(lr_f).sum()))
    _frame_fixed_patterns(data, rng, put, out)
    if data.part_rotor is not None:
        rot = (data.part_rotor > 0.3) & obj
        body = obj & ~rot
        d = _masked_mean(res, rot) - _masked_mean(res, body)
        keep = (rot.flatten(1).sum(1) > 3).numpy()
        mean, t, pv = t_test(d[keep])
        put("rotor_parts", mean, pv, f"residual on the rotor discs minus on the body: {mean:+.4f}")
    out["colour"] = {"value": 0.0, "p": 1.0, "skipped": True,
                     "description": (f"{data.colour_note}: colour statistics skipped" if data.colour_note else
                                     "colour: screened in chroma by the screening's colour channel")}
    n_tests = len(out)
    for k, v in out.items():  # the rule of synthaug.diagnose.calibration: p < α / m and outside the clean null
        if v.get("skipped"):
            v["significant"], v["floor"] = False, None
            continue
        v["significant"], v["floor"] = structure_significant(k, v["value"], v["p"], alpha / n_tests)
    return out


# a line pattern is called periodic when its spectrum's peak is this many times the spectrum's median: the
# largest of ~128 exponential periodogram values of a white pattern exceeds 20 x their median (13.9 x their
# mean) with probability about 128 * exp(-13.9) = 1e-4
PERIODIC_PEAK_RATIO = 20.0


def _frame_fixed_patterns(data: DiagnosisData, rng: np.random.Generator, put: Any, out: dict[str, Any]) -> None:
    """``column_pattern`` / ``row_pattern``: gains fixed in the frame's columns (rows), the same in every video,
    measured on the whole frames (:mod:`synthaug.diagnose.frame_pattern`); skipped without frames or with
    fewer than two videos. Draws from a generator spawned from ``rng`` (``rng``'s own stream is untouched)."""
    from synthaug.diagnose.frame_pattern import fixed_line_pattern

    sub = rng.spawn(1)[0]
    groups = [r.get("video") for r in data.records] if len(data.records) == len(data) else [None] * len(data)
    for label, axis, lines in (("column_pattern", "x", "column"), ("row_pattern", "y", "row")):
        fp = None if data.frame_lines is None else \
            fixed_line_pattern([fl[axis] for fl in data.frame_lines], groups, sub)
        if fp is None:
            why = "the seed set has no frames" if data.frame_lines is None else "fewer than two videos of one size"
            out[label] = {"value": 0.0, "p": 1.0, "skipped": True,
                          "description": f"{lines} pattern fixed in the frame: not measured ({why})"}
            continue
        periodic = fp["peak_ratio"] >= PERIODIC_PEAK_RATIO
        shape = (f"periodic, period {fp['period_px']:.1f} frame px" if periodic else
                 f"not periodic (each {lines} its own gain)")
        put(label, fp["rho"], fp["p"],
            f"{lines} gains fixed in the frame: the whole frames' high-passed {lines} profiles of {fp['groups']} "
            f"videos agree {fp['rho']:+.2f} at the same frame {lines} (1: one pattern in every video); the common "
            f"pattern varies by {100 * fp['amplitude']:.2f} %, {shape}",
            amplitude=fp["amplitude"], period_px=fp["period_px"], peak_ratio=fp["peak_ratio"], periodic=periodic,
            videos=fp["groups"], n_frames=fp["seeds"])


def parameter_dependence(values: dict[str, np.ndarray], meta: dict[str, np.ndarray], *,
                         rng: np.random.Generator, alpha: float = 0.01, n_perm: int = 9999,
                         groups: np.ndarray | None = None) -> list[dict[str, Any]]:
    """Dependence of fitted per-seed parameters on seed metadata (an absorbed effect).

    Args:
        values: ``{parameter: (N,)}`` fitted values.
        meta: ``{metadata: (N,)}`` (:func:`seed_metadata`).
        rng: generator of the permutation tests.
        alpha: family-wise level (Bonferroni over all pairs).
        groups: group (video) of each seed: dependences measured within groups
            (:func:`permutation_spearman`); metadata constant within every group
            (e.g. background brightness of one scene) then carry no evidence.

    Returns:
        one dict per pair: ``parameter``, ``metadata``, ``rho``, ``p``, ``significant``.

    Example:
        >>> rng = np.random.default_rng(0)
        >>> r2 = rng.random(40)
        >>> out = parameter_dependence({"w_d": 0.5 * (1 - 0.3 * r2)}, {"radial_r2": r2}, rng=rng)
        >>> out[0]["rho"] < -0.99, out[0]["significant"]
        (True, True)
    """
    rows = []
    for pn, pv in values.items():
        for mn, mv in meta.items():
            rho, p = permutation_spearman(mv, pv, rng, n_perm, groups=groups)
            rows.append({"parameter": pn, "metadata": mn, "rho": rho, "p": p})
    k = max(len(rows), 1)
    for r in rows:
        r["significant"] = bool(r["p"] < alpha / k)
    return rows
