"""Candidate screening: extend the model with each candidate effect, measure the held-out gain (issue 6, item 3).

Refitting every seed for every candidate would cost 14 full fits. Instead each
candidate's *camera-wide* parameters φ (1-2 numbers, the same for every seed,
as a camera's are) are screened on a small grid, with the per-seed Θ_i held at
the baseline fit except the object albedo w_d, which is re-solved per seed in
closed form (:func:`~synthaug.diagnose.residuals.solve_albedo`) for the base
and every extended model alike (so an effect that is just a gain on the
object — white balance on grayscale — cannot win by fixing w_d). The whole
grid is one batched render of all seeds per setting.

Gain on held-out seeds: k-fold over seeds, φ chosen on the training folds
(minimum mean distance), the held-out seeds' distance reduction
``g_i = (d_base,i - d_ext,i) / mean(d_base)`` measured with that φ. The
penalty ``λ · (number of φ)`` is subtracted from every ``g_i``, then a
one-sided t-test over seeds, Bonferroni-corrected over candidates and the
two distance spaces (the detector's, pixels), decides significance; a
finding must also exceed its floor measured on clean nuisance-varied data
(:mod:`synthaug.diagnose.calibration`), reach ``min_gain`` (2 %: worth
having; a lens's, less where the whole frames show it, :func:`frame_corroboration`)
and must not make the other space worse on held-out seeds; and no other candidate may explain the same
distance better (:func:`explained_better`: a significant sliver of what another effect describes better names
nothing). Both the detector's distance (e.g. HOG) and the
pixel distance are screened: HOG is nearly blind to intensity effects, pixels
to some shape effects. Every model, base and extended, includes the seed
patches' known crop-resampling blur (:func:`~synthaug.data.seedset.crop_resampling_sigma`).
With ``given`` (forward selection, :func:`synthaug.diagnose.report.diagnose`)
accepted extensions are part of the base and candidates are screened on top.

An effect the fitted parameters absorbed (vignetting into w_d, defocus into
σ_s) has no distance gain — Θ_i already matches each seed — but shows as a
dependence of the fitted value on seed metadata; its gain is the held-out
(k-fold) variance of that parameter the effect explains. It matters: at
generation the position and size are redrawn, so an absorbed effect comes
out wrong in every synthetic sample. Auto-exposure is found that way too: the
re-solved w_d follows the brightness of the whole frame (what the camera
meters), within videos.

Three more channels do not rest on the fitted patches. Vignetting is a gain
of 0.9-1 on an object near the centre, which w_d absorbs seed by seed; the
whole frames around the objects carry it as a radial fall-off of brightness
(the **frame** channel, :func:`frame_channel`: each frame's log fall-off,
tested over distinct scenes, :mod:`synthaug.diagnose.frame_pattern`), and the
fall-off it implies is the setting. A codec's 8x8 block grid is as visible on
the whole frames (the steps across its lines), where a 20-30 px object holds a
few of its edges: compression's frame channel (its setting, the quality, comes
from the distance screening). In-camera sharpening steepens every edge of the
frames, where on the object it is a 1-px halo: sharpening's frame channel, the
edges' step at 2 px over that at 4 px, read on the frame at edges found on its
independent background frame, tested over scenes against the clean frames'
mean (its setting: the unsharp mask whose inverse brings them back to it). A lens's radial distortion bends
the scene's motion between the frame and its background frame (a shift ``t`` reads ``t + k (|p|² t + 2 p (p·t))``
at frame point ``p``): lens distortion's frame channel, the division model's ``k`` fitted to that motion, tested
over scenes (two-sided; its setting is ``k``). The camera's noise level
function, measured on the seed frames off the object
(:mod:`synthaug.diagnose.noise`), testifies for ``shot_noise`` (rising with
brightness) and ``gamma`` (falling: a compressive tone curve after the sensor);
a pairwise distance cannot credit a noise model, and a tone curve on a dark
object is nearly a gain that w_d absorbs. A *rising* NLF has two causes: shot
noise adds variance ∝ signal and leaves the signal's tone alone, while an
expansive tone curve x^g (g > 1) scales the read noise by its slope f'(x) and
changes the tone of the signal itself. :func:`tone_evidence` tells them apart
on the patches: the tone curve the NLF implies (g = 2 / (2 - slope)) is
rendered on every seed; if it lowers the pixel distance to the real patches
(the object's tone against its real background), the rise is named ``gamma``,
else ``shot_noise`` — never both. For seed sets with RGB patches, the
chroma distance (R - G, B - G) of a neutral object (or of the object's known
colour, :attr:`DiagnosisData.object_rgb`) screens ``chromatic_aberration`` and
``white_balance`` and ``haze``, whose airlight has the sky's colour; haze and
chromatic aberration on a painted object must also explain the chroma better
than a case-wide paint of the object alone, which a white balance cannot be
told from (:data:`PAINT_MIMICS`). On single-channel data the colour-only candidates
(:data:`COLOUR_ONLY`: a lateral colour shift, a colour cast) are not offered
at all (:func:`offered_candidates`): in gray they are a radial blur and a gain,
which would only take the name of another effect (lens distortion, exposure).

Finally a real-vs-synthetic classifier (logistic regression on HOG features,
k-fold by seed; 50 % = indistinguishable) is scored before and after the
extension.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np
import torch

from synthaug.diagnose.calibration import HAND_MIN_GAIN, gain_centre, gain_floor, gain_upper
from synthaug.diagnose.noise import NOISE_CANDIDATES, SHAPE_MIN_SHARE, SLOPE_FLOOR, noise_channel
from synthaug.diagnose.diagnosis_data import (ALBEDO_POINTS, DiagnosisData, albedo_renders, pairwise_distance,
                                              pixel_distance, render_with, solve_albedo)
from synthaug.diagnose.residuals import seed_metadata
from synthaug.params import EFFECT_PARAM_SPECS

__all__ = ["CANDIDATE_GRIDS", "ABSORPTION", "COLOUR_ONLY", "PAINT_GRID", "PAINT_MIMICS", "object_colour",
           "screen_candidates", "screen_one", "absorption_gain",
           "realism_accuracy", "kfold", "offered_candidates", "tone_evidence", "FRAME_CANDIDATES",
           "frame_evidence", "frame_channel", "frame_corroboration", "distance_channel", "explained_better",
           "RIVAL_SPACES", "RIVAL_RULE", "OBJECTS_SHOW", "OBJECTS_RULE", "objects_agree", "shape_verdict",
           "FRAME_BLUR", "BLUR_ALPHA", "BLUR_RULE", "frames_blurred",
           "HIGHLIGHT_CANDIDATES", "HIGHLIGHT_SHININESS", "highlight_strength", "highlight_channel"]

Setting = dict[str, float]

# Camera-wide settings tried per candidate (realistic spans, neutral excluded). Blur radii are in FRAME
# pixels (a camera's), converted to each seed's patch pixels by its frame scale; the rolling shutter
# takes a magnitude along each seed's fitted motion direction; haze an extinction length in object frame px
# (its amount 1 - exp(-extinction / object px) per seed: a smaller-looking object is farther away).
CANDIDATE_GRIDS: dict[str, list[Setting]] = {
    "vignetting": [{"vignette_k": k} for k in (0.1, 0.2, 0.3, 0.4, 0.55)],
    "gamma": [{"gamma_g": g} for g in (0.6, 0.7, 0.8, 0.9, 1.12, 1.25, 1.4, 1.6)],
    "shot_noise": [{"shot_sigma": s} for s in (0.01, 0.02, 0.03, 0.045, 0.06, 0.08)],
    "defocus": [{"defocus_sigma": s} for s in (0.4, 0.6, 0.8, 1.0, 1.3, 1.7, 2.2)],
    "compression": [{"jpeg_quality": q} for q in (20.0, 30.0, 40.0, 50.0, 65.0, 80.0)],
    "specular": [{"specular_ks": k, "specular_shininess": s} for k, s in
                 itertools.product((0.15, 0.3, 0.45, 0.6), (10.0, 30.0, 80.0))],
    "haze": [{"haze_extinction_px": e, "haze_airlight": a} for e, a in
             itertools.product((3.0, 6.0, 10.0, 15.0, 25.0), (0.6, 0.8, 0.95))],
    "chromatic_aberration": [{"ca_shift": s} for s in (0.5, 1.0, 1.5, 2.0, 3.0)],
    "white_balance": [{"wb_gain": g} for g in (0.8, 0.9, 1.1, 1.25)],
    "sharpening": [{"sharpen_amount": a, "sharpen_sigma": s} for a, s in
                   itertools.product((0.3, 0.6, 1.0, 1.5), (0.7, 1.0, 1.5))],
    "lens_distortion": [{"distortion_k1": k} for k in (-0.25, -0.15, -0.08, 0.05, 0.1)],
    "rolling_shutter": [{"rs_magnitude": m} for m in (-0.15, -0.1, -0.05, 0.05, 0.1, 0.15)],
    "rotor_blur": [{"rotor_opacity": r} for r in (0.1, 0.25, 0.4, 0.6, 0.8)],
    "exposure": [{"exposure_gain": g, "exposure_offset": o} for g, o in
                 itertools.product((0.85, 1.0, 1.15), (-0.05, -0.02, 0.02, 0.05))],
}

# Absorbed effects: (fitted parameter, seed metadata, expected sign of the dependence).
ABSORPTION: dict[str, tuple[str, str, int]] = {
    "vignetting": ("w_d", "radial_r2", -1),
    "defocus": ("sigma_s", "object_size", -1),
    "sharpening": ("sigma_s", "object_size", +1),
    # auto-exposure: the camera's gain follows the whole frame's brightness, the object's albedo with it
    "exposure": ("w_d", "frame_brightness", -1),
}
# Absorbed effects tested by the linear (Pearson) correlation within videos, the very dependence whose held-out R2
# is the channel's gain; the others by Spearman's rank correlation. Auto-exposure's gain is a smooth function of the
# metered brightness, (target / B)^a, and over one video's brightness range the absorbed w_d is close to linear
# in B; ranks throw away that one video's brightness spans 5-10x another's. Measured on the power table's 10 cached
# exposure cases (results/diagnose/README.md, stop 39): Pearson p_adj <= 0.003 in all 10, Spearman 0.0004-0.017
# (2 of 10 above alpha), Pearson of the logs up to 0.087 (one seed's low w_d dominates its log); on 10 fresh cases
# the same findings as Spearman (the floor on the held-out R2, not p, is what misses there).
LINEAR_ABSORPTION: tuple[str, ...] = ("exposure",)


# Candidates screened in colour (seed sets with RGB patches): the chroma residual (R - G, B - G) of a neutral
# object sees their colour fringes / colour cast; in gray, CA is a radial blur and white balance a plain gain.
# Haze is screened in colour too: its airlight has the sky's colour (aerial perspective: a far object takes
# on the colour of the air in front of it).
COLOUR_CANDIDATES: tuple[str, ...] = ("chromatic_aberration", "white_balance", "haze")
# The object's own colour, read beside the colour channel (an appearance, not a camera effect; object_colour): a
# chroma offset of the albedo (synthaug.diagnose.nuisances.paint_tint, luma kept) of one of these lengths at any hue,
# one for the whole seed set. It is not part of the channel's model: on the object alone a paint and a camera's white
# balance (a gain along the colour-temperature axis) read the same (results/diagnose/README.md, stop 93).
PAINT_GRID: tuple[tuple[float, float], ...] = ((0.0, 0.0),) + tuple(
    (s, float(h)) for s in (0.025, 0.05, 0.1, 0.15, 0.2, 0.3) for h in range(0, 360, 15))
# The colour candidates a paint reproduces exactly (a case-wide per-channel gain on the object): named from the
# chroma alone, with the report's caveat. The others (haze's airlight, which follows each seed's sky colour and
# distance; chromatic aberration's fringes) must also explain more on a painted object than the best case-wide paint
# alone, on held-out seeds (the nested comparison since stop 94, setting and paint chosen together per fold): a
# slightly coloured object is otherwise named haze (18 of 40 clean colour cases, stop 93).
PAINT_MIMICS: tuple[str, ...] = ("white_balance",)

# Candidates with evidence on the whole frames (synthaug.diagnose.frame_pattern), fixed in the frame and carried by
# the background around the object as well: vignetting's radial fall-off (on the object a gain that w_d absorbs),
# a codec's 8x8 block grid (on a 20-30 px object a few block edges), in-camera sharpening's steeper edges (on the
# object a 1-px halo that the fitted blur, noise and shading mismatch drown: its distance gain stayed under the floor
# in 5 of 5 power cases at amount 1, results/diagnose/README.md, stop 40), a lens's radial distortion (on an object
# within r² < 0.4 of the centre an anisotropic stretch of a few percent the fitted pose absorbs; the scene's motion
# between the frame and its background frame shows it over the whole frame, stop 41).
FRAME_CANDIDATES: tuple[str, ...] = ("vignetting", "compression", "sharpening", "lens_distortion")
# Candidates that exist only in colour: a single channel has no lateral colour shift and no colour cast (in gray
# chromatic aberration is a ~1 px radial blur, white balance a gain that w_d absorbs), so on single-channel data
# they are not offered (:func:`offered_candidates`); haze stays: its extinction and airlight act on gray too.
COLOUR_ONLY: tuple[str, ...] = ("chromatic_aberration", "white_balance")


def offered_candidates(data: DiagnosisData, names: Sequence[str]) -> tuple[list[str], list[str]]:
    """The candidates ``names`` that ``data`` can identify, and those it cannot: without colour patches
    (:attr:`DiagnosisData.real_rgb` None: gray, or RGB whose channels are equal), the colour-only ones
    (:data:`COLOUR_ONLY`) are left out."""
    if data.real_rgb is not None:
        return list(names), []
    return [c for c in names if c not in COLOUR_ONLY], [c for c in names if c in COLOUR_ONLY]


def colour_values(data: DiagnosisData, effect: str, setting: Setting) -> dict[str, dict[str, Any]]:
    """A camera-wide setting as per-channel parameters: white balance g -> gains (g, 1, 1/g); haze's airlight
    -> the airlight brightness times each seed's sky colour (its RGB background's mean over its luma)."""
    if effect == "white_balance":
        g = float(setting["wb_gain"])
        return {effect: {"wb_gain": torch.tensor([[g, 1.0, 1.0 / g]])}}
    if effect == "haze":
        from synthaug.effects.camera_functional import LUMA_WEIGHTS

        out = extension_values(data, effect, setting)
        sky = data.background_rgb.double().mean((2, 3))  # (N, 3)
        tint = sky / (sky @ torch.tensor(LUMA_WEIGHTS, dtype=torch.float64)).clamp_min(1e-3)[:, None]
        out[effect]["haze_airlight"] = (float(setting["haze_airlight"]) * tint).clamp(0.0, 1.0)
        return out
    return {effect: dict(setting)}


def paint_tints() -> torch.Tensor:
    """:data:`PAINT_GRID` as per-channel factors (G, 3) (:func:`synthaug.diagnose.nuisances.paint_tint`)."""
    from synthaug.diagnose.nuisances import paint_tint

    return torch.tensor(np.stack([paint_tint(s, h) for s, h in PAINT_GRID]))


@torch.no_grad()
def object_colour(data: DiagnosisData, folds: list[np.ndarray], *, penalty: float = 0.005) -> dict[str, Any] | None:
    """The object's own colour, an appearance reading (RGB seed sets only; None otherwise): the paint of
    :data:`PAINT_GRID` that fits best over all seeds, and the held-out chroma gain of painting the model's
    neutral object (k-fold as the candidates, one-sided t over seeds). A white balance on a neutral object reads
    as a paint along the colour-temperature axis (hue near 0° or 180°): the two are not told apart here."""
    from synthaug.diagnose.diagnosis_data import paint_chroma_distances

    if data.real_rgb is None:
        return None
    d = paint_chroma_distances(data, None, paint_tints())
    if not float(np.mean(d[0])) > 0:
        return None
    gains, _ = _cv_gain(d[0], d, folds, penalty * 2)
    m, t, p = _one_sided(gains)
    best = int(np.argmin(d.mean(1)))
    s, h = PAINT_GRID[best]
    return {"setting": {"paint_saturation": s, "paint_hue_deg": h}, "gain": m, "t": t, "p": p,
            "raw_gain_all": float((d[0].mean() - d[best].mean()) / d[0].mean())}


@torch.no_grad()
def screen_colour(data: DiagnosisData, effect: str, folds: list[np.ndarray], base: np.ndarray, *,
                  penalty: float = 0.005, given: dict[str, Setting] | None = None,
                  paints: torch.Tensor | None = None) -> dict[str, Any] | None:
    """Held-out gain of ``effect`` in the chroma distance (RGB seed sets only; None otherwise), on the model's
    object: neutral grey, or the known colour :attr:`DiagnosisData.object_rgb`. With ``paints`` (per-channel
    factors (P, 3), :func:`paint_tints`), also the held-out gain of the effect on a painted object, the setting and
    the paint chosen together per fold (``joint_per_seed_gain``, penalised for the effect's parameters and the
    paint's two): the nested model that the object's own colour alone (the same paints) is tested against."""
    from synthaug.diagnose.diagnosis_data import object_tint, paint_chroma_distances

    if effect not in COLOUR_CANDIDATES or data.real_rgb is None or not float(np.mean(base)) > 0:
        return None  # no colour (or a base model that already matches the chroma exactly): nothing to screen
    grid = CANDIDATE_GRIDS[effect]
    tints = object_tint(data) if paints is None else torch.cat([object_tint(data), torch.as_tensor(paints)])
    ext_all, joint = [], []
    for setting in grid:  # one pair of renders per setting gives the model's object and every paint
        d = paint_chroma_distances(data, {**given_values(data, given, rgb=True),
                                          **colour_values(data, effect, setting)}, tints)
        ext_all.append(d[0])
        joint.append(d[1:])  # (P, N); empty without paints
    e = np.stack(ext_all)
    k = _n_params(effect)
    gains, chosen = _cv_gain(base, e, folds, penalty * k)
    m, t, p = _one_sided(gains)
    best = int(np.argmin(e.mean(1)))
    out = {"gain": m, "t": t, "p": p, "settings_per_fold": [grid[c] for c in chosen], "setting": grid[best],
           "raw_gain_all": float((base.mean() - e[best].mean()) / base.mean()), "per_seed_gain": gains.tolist()}
    if paints is not None:  # (G * P, N), setting-major
        out["joint_per_seed_gain"] = _cv_gain(base, np.concatenate(joint), folds, penalty * (k + 2))[0].tolist()
    return out


def _n_params(effect: str) -> int:
    return len(CANDIDATE_GRIDS[effect][0])


def extension_values(data: DiagnosisData, effect: str, setting: Setting) -> dict[str, dict[str, Any]]:
    """A camera-wide setting as the effect's per-seed parameters (patch units)."""
    s = dict(setting)
    fs = data.frame_scale.double()
    if effect == "defocus":
        return {effect: {"defocus_sigma": (s["defocus_sigma"] / fs).clamp(0.0, 3.0)}}
    if effect == "sharpening":
        return {effect: {"sharpen_amount": s["sharpen_amount"],
                         "sharpen_sigma": (s["sharpen_sigma"] / fs).clamp(0.3, 3.0)}}
    if effect == "white_balance":  # gains (g, 1, 1/g) on a neutral object, seen in gray: their Rec. 601 luma
        from synthaug.effects.camera_functional import LUMA_WEIGHTS

        g = float(s["wb_gain"])
        return {effect: {"wb_gain": LUMA_WEIGHTS[0] * g + LUMA_WEIGHTS[1] + LUMA_WEIGHTS[2] / g}}
    if effect == "haze":  # Koschmieder: the same object looks smaller when farther, behind more air
        amount = 1.0 - torch.exp(-s["haze_extinction_px"] / data.object_px.double().clamp_min(1.0))
        return {effect: {"haze_amount": amount.clamp(0.0, 0.95), "haze_airlight": s["haze_airlight"]}}
    if effect == "rolling_shutter":
        a = data.theta.alpha_m[:, 0].double()
        m = s["rs_magnitude"]
        return {effect: {"rs_skew": m * torch.cos(a), "rs_stretch": m * torch.sin(a)}}
    return {effect: s}


def kfold(n: int, k: int, rng: np.random.Generator) -> list[np.ndarray]:
    """``k`` disjoint held-out index sets covering ``range(n)``.

    Example:
        >>> folds = kfold(10, 3, np.random.default_rng(0))
        >>> sorted(np.concatenate(folds).tolist()) == list(range(10)), len(folds)
        (True, 3)
    """
    if n < 2:
        raise ValueError(f"need at least 2 seeds for cross-validation, got {n}")
    k = max(2, min(int(k), n))
    perm = rng.permutation(n)
    return [np.sort(perm[i::k]) for i in range(k)]


@dataclass
class Renders:
    """Distances of every seed under the base model and each grid setting."""

    base_feature: np.ndarray  # (N,)
    base_pixel: np.ndarray
    feature: np.ndarray  # (G, N)
    pixel: np.ndarray
    w_d: np.ndarray  # (G, N) re-solved albedo


def given_values(data: DiagnosisData, given: dict[str, Setting] | None, *, rgb: bool = False
                 ) -> dict[str, dict[str, Any]]:
    """Accepted extensions ``{effect: camera-wide setting}`` as per-seed parameters (:func:`extension_values`;
    with ``rgb``, per channel where the effect has colour: :func:`colour_values`)."""
    out: dict[str, dict[str, Any]] = {}
    for eff, setting in (given or {}).items():
        out.update(colour_values(data, eff, setting) if rgb and eff in COLOUR_CANDIDATES
                   else extension_values(data, eff, setting))
    return out


@torch.no_grad()
def base_render(data: DiagnosisData, given: dict[str, Setting] | None = None) -> tuple[torch.Tensor, torch.Tensor]:
    """The baseline model's best synthetic images (fitted Θ [+ accepted extensions], re-solved w_d) and that w_d."""
    ext = given_values(data, given) or None
    w = solve_albedo(data, ext)
    return render_with(data, ext, w_d=w), w


@torch.no_grad()
def _grid_renders(data: DiagnosisData, effect: str, base: tuple[np.ndarray, np.ndarray],
                  chunk: int = 128, given: dict[str, Setting] | None = None) -> Renders:
    feats, pixs, ws = [], [], []
    for setting in CANDIDATE_GRIDS[effect]:
        f_all, p_all, w_all = [], [], []
        for i in range(0, len(data), chunk):
            sub = data.subset(np.arange(i, min(i + chunk, len(data))))
            ext = {**given_values(sub, given), **extension_values(sub, effect, setting)}
            w = solve_albedo(sub, ext)
            syn = render_with(sub, ext, w_d=w)
            f_all.append(pairwise_distance(sub, syn))
            p_all.append(pixel_distance(sub.real, syn))
            w_all.append(w.numpy())
        feats.append(np.concatenate(f_all))
        pixs.append(np.concatenate(p_all))
        ws.append(np.concatenate(w_all))
    return Renders(base[0], base[1], np.stack(feats), np.stack(pixs), np.stack(ws))


def _cv_gain(base: np.ndarray, ext: np.ndarray, folds: list[np.ndarray], penalty: float
             ) -> tuple[np.ndarray, list[int]]:
    """Held-out per-seed relative gains (penalised) and the setting chosen per fold."""
    n = base.shape[0]
    gains = np.full(n, np.nan)
    chosen = []
    scale = float(np.mean(base))
    if not scale > 0:  # a base that matches every seed exactly: no gain to measure
        return gains, [0] * len(folds)
    for held in folds:
        train = np.setdiff1d(np.arange(n), held)
        g = int(np.argmin(ext[:, train].mean(1)))
        chosen.append(g)
        gains[held] = (base[held] - ext[g, held]) / scale - penalty
    return gains, chosen


def _one_sided(g: np.ndarray) -> tuple[float, float, float]:
    from scipy import stats

    g = g[np.isfinite(g)]
    if len(g) == 0:  # no seed measured anything: no evidence
        return 0.0, 0.0, 1.0
    m = float(g.mean())
    s = float(g.std(ddof=1)) if len(g) > 1 else 0.0
    if s == 0:
        return m, 0.0, 1.0 if m <= 0 else 0.0
    t = m / (s / math.sqrt(len(g)))
    return m, float(t), float(stats.t.sf(t, len(g) - 1))


def screen_one(data: DiagnosisData, effect: str, folds: list[np.ndarray], base: tuple[np.ndarray, np.ndarray],
               *, penalty: float = 0.005, given: dict[str, Setting] | None = None) -> dict[str, Any]:
    """Held-out gain of extending the model with ``effect`` (both distance spaces).

    Returns:
        ``{"effect", "n_params", "feature": {...}, "pixel": {...}, "setting": best φ on all seeds}`` where
        each space holds ``gain`` (mean penalised held-out relative gain), ``t``, ``p`` (one-sided,
        uncorrected), ``settings_per_fold``.
    """
    if effect not in CANDIDATE_GRIDS:
        raise ValueError(f"unknown candidate {effect!r}; candidates: {sorted(CANDIDATE_GRIDS)}")
    r = _grid_renders(data, effect, base, given=given)
    k = _n_params(effect)
    out: dict[str, Any] = {"effect": effect, "n_params": k}
    grid = CANDIDATE_GRIDS[effect]
    for space, b, e in (("feature", r.base_feature, r.feature), ("pixel", r.base_pixel, r.pixel)):
        gains, chosen = _cv_gain(b, e, folds, penalty * k)
        m, t, p = _one_sided(gains)
        best = int(np.argmin(e.mean(1)))
        out[space] = {"gain": m, "t": t, "p": p, "settings_per_fold": [grid[c] for c in chosen],
                      "setting": grid[best], "raw_gain_all": float((b.mean() - e[best].mean()) / b.mean()),
                      "per_seed_gain": gains.tolist()}
    return out


def _cv_r2(x: np.ndarray, y: np.ndarray, folds: list[np.ndarray]) -> float:
    """1 - held-out MSE of a line y ~ x over held-out MSE of the training mean."""
    n = len(x)
    e_lin, e_const = 0.0, 0.0
    for held in folds:
        tr = np.setdiff1d(np.arange(n), held)
        A = np.stack([np.ones(len(tr)), x[tr]], 1)
        coef, *_ = np.linalg.lstsq(A, y[tr], rcond=None)
        pred = coef[0] + coef[1] * x[held]
        e_lin += float(((y[held] - pred) ** 2).sum())
        e_const += float(((y[held] - y[tr].mean()) ** 2).sum())
    return 1.0 - e_lin / max(e_const, 1e-12)


def absorption_gain(data: DiagnosisData, effect: str, w_d: np.ndarray, folds: list[np.ndarray],
                    rng: np.random.Generator) -> dict[str, Any] | None:
    """Evidence that a fitted parameter absorbed ``effect``: its dependence on seed metadata.

    Returns:
        None for effects without an absorption signature, else ``parameter``,
        ``metadata``, ``rho`` (the correlation named by ``statistic``: ``"spearman"``, or ``"pearson"`` for
        :data:`LINEAR_ABSORPTION`), ``p`` (permutation within videos, two-sided),
        ``sign_ok`` and ``gain`` (held-out R² of the dependence: the variance
        of the fitted parameter the effect explains).
    """
    from synthaug.diagnose.residuals import seed_groups
    from synthaug.diagnose.stats import permutation_correlation, within_groups

    if effect not in ABSORPTION:
        return None
    param, meta_name, sign = ABSORPTION[effect]
    meta = seed_metadata(data).get(meta_name)
    if meta is None:  # e.g. no whole frames in the seed set: no frame brightness
        return None
    vals = w_d if param == "w_d" else data.theta.as_dict()[param][:, 0].double().numpy()
    groups = seed_groups(data)
    # 99,999 permutations: a p floor of 1e-5, far under the Bonferroni-adjusted alpha
    stat = "pearson" if effect in LINEAR_ABSORPTION else "spearman"
    rho, p = permutation_correlation(meta, vals, rng, 99_999, groups, method=stat)
    xm, ym = within_groups(meta, groups), within_groups(vals, groups)
    ok = np.isfinite(xm) & np.isfinite(ym)
    keep = np.cumsum(ok) - 1  # folds re-indexed onto the seeds that have a within-video value
    f_ok = [keep[h[ok[h]]] for h in folds]
    return {"parameter": param, "metadata": meta_name, "rho": rho, "statistic": stat, "p": p,
            "sign_ok": bool(rho * sign > 0),
            "within": "video" if groups is not None else None, "gain": _cv_r2(xm[ok], ym[ok], f_ok)}


# Candidates whose strength the objects' brightness carries beyond the model's diffuse shading (the highlight channel,
# :func:`highlight_strength`): a highlight adds light whatever the object's albedo, where every shading mismatch of
# the material (ambient, light direction, smooth normals, albedo texture) scales with it.
HIGHLIGHT_CANDIDATES: tuple[str, ...] = ("specular",)
HIGHLIGHT_SHININESS = 80.0
"""The highlight template's Blinn-Phong exponent. Chosen on the cases of every specular power row and their clean
calibration (stop 111, ``results/diagnose/null/highlight_s111/compare.py``: 44 calibration and 60 clean power cases,
15 at each realistic strength): a narrower lobe than the truth's (30 and 60) reads more highlight above the clean
spread: named at the default and the wider strength 12 and 2 of 15 at 45, 13 and 7 at 80, 14 and 7 at 120, 12 and 4
at 160, no clean case above the floor at any; 80 keeps the clean spread lowest of the best. (Counted on the reference
camera before stop 112 lit a hidden highlight by its video's light: since, 9 and 4 of 15 at 80.)"""


@torch.no_grad()
def highlight_strength(data: DiagnosisData, given: dict[str, Setting] | None = None, *,
                       shininess: float = HIGHLIGHT_SHININESS, centre: float | None = None) -> dict[str, Any] | None:
    """How much highlight the objects carry beyond the model's shading: per seed, the least-squares amplitude ``k``
    of the specular candidate's highlight (``specular_ks`` 1 at ``shininess``, the model's light and normals)
    fitted jointly with the albedo w_d (the image is affine in both: three renders), pooled over seeds with the
    weights ``1 / se_k²`` (seeds whose pose shows the template no highlight weigh nothing).

    A highlight is added light: its ``k`` is the same on a dark and a bright object, where the model's shading
    mismatches scale with the albedo and, fitted jointly with w_d, project on the template little. Tested
    one-sided over seeds against ``centre`` (the clean cases' mean: clean materials have some gloss too; 0 when
    None) with the weighted mean's sandwich standard error (the LS errors treat the pixels as independent).

    Returns:
        ``{"k", "se", "t", "p", "n", "shininess", "per_seed_k"}``, or None with fewer than 3 seeds whose template
        shows a highlight.
    """
    from scipy import stats

    n = len(data)
    gv = given_values(data, given)
    (w0, w1), (r0, r1) = ALBEDO_POINTS, albedo_renders(data, gv or None)
    a0 = r0.double().flatten(1)
    s = (r1.double().flatten(1) - a0) / (w1 - w0)
    ext = {**gv, **extension_values(data, "specular", {"specular_ks": 1.0, "specular_shininess": shininess})}
    h = render_with(data, ext, w_d=torch.full((n,), w0), clamp=False).double().flatten(1) - a0
    y = data.real.double().flatten(1) - a0
    ss, sh, hh = (s * s).sum(1), (s * h).sum(1), (h * h).sum(1)
    sy, hy = (s * y).sum(1), (h * y).sum(1)
    det = ss * hh - sh * sh
    ok = (hh > 1e-8) & (det > 1e-12 * ss * hh.clamp_min(1e-12))
    if int(ok.sum()) < 3:
        return None
    det = torch.where(ok, det, torch.ones_like(det))
    w_fit = (hh * sy - sh * hy) / det
    k = (ss * hy - sh * sy) / det
    res = y - w_fit[:, None] * s - k[:, None] * h
    dof = max(y.shape[1] - 2, 1)
    var_k = (res * res).sum(1) / dof * ss / det
    k, var_k = k[ok].numpy(), var_k[ok].clamp_min(1e-12).numpy()
    w = 1.0 / var_k
    m = float((w * k).sum() / w.sum())
    m_seeds = len(k)
    se = float(math.sqrt((w * w * (k - m) ** 2).sum() * m_seeds / (m_seeds - 1)) / w.sum())
    c = 0.0 if centre is None else float(centre)
    t = (m - c) / se if se > 0 else 0.0
    return {"k": m, "se": se, "t": float(t), "p": float(stats.t.sf(t, m_seeds - 1)), "n": m_seeds,
            "shininess": float(shininess), "per_seed_k": k.tolist()}


def highlight_channel(effect: str, hl: dict[str, Any] | None, n_tests: int, alpha: float) -> dict[str, Any] | None:
    """The highlight channel of ``effect`` (:data:`HIGHLIGHT_CANDIDATES`; evidence from :func:`highlight_strength`):
    its statistic (``gain``) the highlight amplitude ``k`` the objects carry beyond the model's shading, tested
    one-sided over seeds against the clean cases' mean (clean materials have some gloss; :func:`gain_centre`, 0
    before it is calibrated). Significant when the test rejects at α (Bonferroni) and ``k`` exceeds its calibrated
    clean floor; never without one (clean materials are glossy too: an amplitude means nothing without their
    range). Its setting: ``specular_ks`` = k at the template's exponent.

    Example:
        >>> hl = {"k": 0.45, "se": 0.06, "t": 6.0, "p": 1e-8, "n": 60, "shininess": 45.0}
        >>> ch = highlight_channel("specular", hl, 49, 0.01)
        >>> ch["channel"], ch["setting"], highlight_channel("defocus", hl, 49, 0.01)
        ('highlight', {'specular_ks': 0.45, 'specular_shininess': 45.0}, None)
    """
    if hl is None or effect not in HIGHLIGHT_CANDIDATES:
        return None
    p_adj = min(1.0, hl["p"] * n_tests)
    floor = gain_floor(effect, "highlight")
    centre = gain_centre(effect, "highlight")
    ks = round(min(max(hl["k"], 0.0), 1.0), 3)
    return {"channel": "highlight", "p_adjusted": p_adj, "z": _z(hl["p"]), "gain": hl["k"], "se": hl["se"],
            "seeds": hl["n"], "centre": centre, "floor": floor,
            "setting": {"specular_ks": ks, "specular_shininess": hl["shininess"]},
            "significant": bool(floor is not None and p_adj < alpha and hl["k"] > max(floor, 0.0))}


def n_screening_tests(names: Sequence[str]) -> int:
    """The Bonferroni count of screening ``names``: two distance spaces each, plus the absorbed, the
    noise-level, the colour, the frame and the highlight channels."""
    return (max(len(names), 1) * 2 + sum(1 for c in names if c in ABSORPTION)
            + sum(1 for c in names if c in NOISE_CANDIDATES) + sum(1 for c in names if c in COLOUR_CANDIDATES)
            + sum(1 for c in names if c in FRAME_CANDIDATES) + sum(1 for c in names if c in HIGHLIGHT_CANDIDATES))


def _z(p: float) -> float:
    """The normal score of a one-sided p-value (clipped to ±40)."""
    from scipy import stats

    return float(np.clip(stats.norm.isf(min(max(p, 1e-300), 1.0)), -40.0, 40.0))


def slope_floor(sign: int) -> float | None:
    """The calibrated floor of the NLF slope in direction ``sign`` (+1 rising, -1 falling): the clean range of
    the slope that way, stored under the candidate whose direction it is (:data:`NOISE_CANDIDATES`)."""
    for name, s in NOISE_CANDIDATES.items():
        if s == sign:
            return gain_floor(name, "noise_level")
    return None


def noise_level_channel(effect: str, nc: dict[str, Any] | None, n_tests: int, alpha: float,
                        tone: dict[str, Any] | None = None) -> dict[str, Any] | None:
    """The noise-level-function channel of ``effect``, from :func:`synthaug.diagnose.noise.noise_channel`.

    Shot noise: the NLF rises with brightness. A tone curve x^g: it falls (g < 1, compressive) or rises (g > 1,
    expansive). A rising NLF is given to one of the two by its shape where that is conclusive (``nc["shape"]``,
    :func:`synthaug.diagnose.noise.nlf_shape`: the power law of a tone curve or shot noise's affine NLF fits the
    held-out seeds better at p < ``alpha``, by at least :data:`~synthaug.diagnose.noise.SHAPE_MIN_SHARE` of the
    power law's gain over a flat NLF), else by ``tone`` (:func:`tone_evidence`): to ``gamma`` when the tone curve it
    implies lowers the pixel distance to the real patches (``tone["gain"] > 0``), else to ``shot_noise``; with
    neither a rising NLF is shot noise's. The slope's floor is the calibrated clean range in the direction tested
    (:func:`slope_floor`).
    """
    if effect not in NOISE_CANDIDATES or nc is None or nc["n_seeds"] < 3:
        return None
    sign = NOISE_CANDIDATES[effect]
    rising = nc["slope"] > 0
    if effect == "gamma" and rising:  # an expansive tone curve makes the noise rise with brightness too
        sign = +1
    p_one = nc["p"] / 2 if nc["slope"] * sign > 0 else 1.0 - nc["p"] / 2
    p_adj = min(1.0, p_one * n_tests)
    z = _z(p_one)
    floor = slope_floor(sign)  # calibrated: the slope in the tested direction on clean data
    big = nc["slope"] * sign > floor if floor is not None else abs(nc["slope"]) >= SLOPE_FLOOR
    # which of the two a rising NLF is: its shape where conclusive, else the patches' tone (tone curve: the implied
    # g helps; shot noise: the signal's tone is untouched, so the implied g hurts)
    named = True
    shape = nc.get("shape") if rising else None
    by_shape = shape_verdict(shape, nc["gain"], alpha)
    if rising:
        tone_curve = by_shape == "gamma" if by_shape is not None else (tone is not None and tone["gain"] > 0)
        named = tone_curve if effect == "gamma" else not tone_curve
    out = {"channel": "noise_level", "p_adjusted": p_adj, "z": z, "gain": nc["gain"], "slope": nc["slope"],
           "floor": floor if floor is not None else SLOPE_FLOOR,
           "significant": bool(p_adj < alpha and nc["slope"] * sign > 0 and big and nc["gain"] > 0 and named)}
    if rising and tone is not None:
        out["tone"] = {k: tone[k] for k in ("implied_gamma_g", "gain", "t", "explains")}
    if shape is not None:
        out["shape"] = {k: shape[k] for k in ("gain", "p", "positive", "n")} | {"explains": by_shape}
    return out


def shape_verdict(shape: dict[str, Any] | None, nlf_gain: float, alpha: float) -> str | None:
    """What a rising NLF's shape (:func:`synthaug.diagnose.noise.nlf_shape`) names: ``"gamma"`` (the power law fits
    the held-out seeds better), ``"shot_noise"`` (the affine NLF does), or None where it is not conclusive: its
    two-sided p at least ``alpha``, or its gain under :data:`~synthaug.diagnose.noise.SHAPE_MIN_SHARE` of the power
    law's held-out gain over a flat NLF (``nlf_gain``; the shapes coincide when shot noise dominates).

    Example:
        >>> shape_verdict({"gain": 0.001, "p": 2e-7}, 0.0034, 0.01)
        'gamma'
        >>> shape_verdict({"gain": 1e-5, "p": 0.009}, 0.012, 0.01) is None   # a negligible share
        True
        >>> shape_verdict({"gain": -0.0006, "p": 3e-5}, 0.004, 0.01)
        'shot_noise'
    """
    if shape is None or not shape["p"] < alpha or not nlf_gain > 0 or abs(shape["gain"]) < SHAPE_MIN_SHARE * nlf_gain:
        return None
    return "gamma" if shape["gain"] > 0 else "shot_noise"


@torch.no_grad()
def tone_evidence(data: DiagnosisData, nc: dict[str, Any] | None, base_pixel: np.ndarray, *,
                  given: dict[str, Setting] | None = None, chunk: int = 128) -> dict[str, Any] | None:
    """Shot noise or an expansive tone curve, for a rising noise level function (None otherwise).

    Both make the frames' noise rise with brightness; only the tone curve changes the signal. The tone curve
    the NLF implies (:func:`noise_setting`: g = 2 / (2 - slope)) is rendered on every seed (w_d re-solved, on
    top of ``given``) and its pixel distance to the real patch compared with the base model's
    (``base_pixel``): the object's tone against its real background. Its setting comes from the frames off the
    object, not from these patches, so the comparison needs no held-out folds.

    Returns:
        ``implied_gamma_g``, ``gain`` (mean relative pixel-distance reduction over seeds: > 0 the tone curve
        explains the patches, ≤ 0 it makes them worse), ``t``, ``p`` (one-sided, > 0), ``per_seed_gain`` and
        ``explains`` (``"gamma"`` or ``"shot_noise"``).
    """
    if nc is None or nc["n_seeds"] < 3 or not nc["slope"] > 0:
        return None
    g = noise_setting("gamma", nc)["gamma_g"]
    d = []
    for i in range(0, len(data), chunk):
        sub = data.subset(np.arange(i, min(i + chunk, len(data))))
        ext = {**given_values(sub, given), **extension_values(sub, "gamma", {"gamma_g": g})}
        d.append(pixel_distance(sub.real, render_with(sub, ext, w_d=solve_albedo(sub, ext))))
    scale = float(np.mean(base_pixel))
    if not scale > 0:
        return None
    per = (np.asarray(base_pixel) - np.concatenate(d)) / scale
    m, t, p = _one_sided(per)
    return {"implied_gamma_g": g, "gain": m, "t": t, "p": p, "per_seed_gain": per.tolist(),
            "explains": "gamma" if m > 0 else "shot_noise"}


def frame_evidence(data: DiagnosisData, given: dict[str, Setting] | None = None
                   ) -> dict[str, dict[str, Any] | None] | None:
    """The whole frames' evidence of each frame candidate, tested over scenes: ``{"vignetting":``
    :func:`~synthaug.diagnose.frame_pattern.radial_falloff`, ``"compression":``
    :func:`~synthaug.diagnose.frame_pattern.block_grid` with ``"quality"``, the JPEG quality its DCT steps read
    (:func:`~synthaug.diagnose.frame_pattern.jpeg_quality`; None for frames not JPEG-coded), ``"sharpening":``
    :func:`~synthaug.diagnose.frame_pattern.sharp_edges` against the calibrated clean mean, ``"lens_distortion":``
    :func:`~synthaug.diagnose.frame_pattern.lens_flow` ``}`` (a value None with fewer than 3 scenes; sharpening's
    and the lens's also without independent background frames, the lens's without a scene that moved between the
    two looks); None without frames. With an accepted tone curve in ``given`` (``gamma``), sharpening's edges are
    read through its inverse (:func:`~synthaug.diagnose.frame_pattern.tone_undone`): the curve bends every edge."""
    from synthaug.diagnose.frame_pattern import (block_grid, jpeg_quality, lens_flow, radial_falloff, sharp_edges,
                                                 sharpening_setting, tone_undone)

    if data.frame_summaries is None:
        return None
    groups = [r.get("video") for r in data.records] if len(data.records) == len(data) else [None] * len(data)
    grid = block_grid(data.frame_summaries, groups)
    if grid is not None:
        jq = jpeg_quality(data.frame_summaries)
        grid = {**grid, "quality": None if jq is None else jq["quality"]}
    centre, floor = gain_centre("sharpening", "frame"), gain_floor("sharpening", "frame")
    g = float((given or {}).get("gamma", {}).get("gamma_g", 1.0))
    edges = data.frame_summaries if g == 1.0 else tone_undone(data.frame_summaries, g)
    sharp = sharp_edges(edges, groups, centre=centre)
    if sharp is not None and g != 1.0:
        sharp = {**sharp, "tone_undone": g}
    if sharp is not None and centre is not None and floor is not None and sharp["ratio"] > floor:
        # sharper than clean frames: the setting whose inverse brings them back (read only then: 12 x N ratios)
        read = sharpening_setting(edges, CANDIDATE_GRIDS["sharpening"], centre)
        sharp = {**sharp, "setting": None if read is None else read["setting"]}
    return {"vignetting": radial_falloff(data.frame_summaries, groups), "compression": grid, "sharpening": sharp,
            "lens_distortion": lens_flow(data.frame_summaries, groups)}


def frame_channel(effect: str, ev: dict[str, dict[str, Any] | None] | None, n_tests: int, alpha: float
                  ) -> dict[str, Any] | None:
    """The frame channel of ``effect`` (:data:`FRAME_CANDIDATES`, evidence from :func:`frame_evidence`). Its
    statistic (``gain``): for vignetting the fall-off ``k`` the frames imply (the fraction of light lost at the
    corners), for compression the log ratio of the frames' steps across the 8x8 grid's lines to those inside the
    blocks beside them (median over the lines), for sharpening the edges' ``A(2) / A(4)`` (the share of an edge's
    step made 2 px from its centre; its test is against the clean mean, not 0), for lens distortion ``|k|`` of the
    division model that the scene's motion between the frame and its background frame reads (its test two-sided).
    Significant when the test over scenes rejects at α (Bonferroni) and the statistic exceeds its
    calibrated clean floor; sharpening's, in addition, only while its edges do not sharpen toward the corners
    beyond what clean frames show (``radial``, :func:`~synthaug.diagnose.frame_pattern.edge_radial` over scenes,
    against :data:`~synthaug.diagnose.frame_pattern.EDGE_RADIAL_FLOOR`, None without a reading; ``radial_veto``
    says it withheld the finding): a sharpening steepens every edge alike, a lens changes their sharpness with the
    distance from the centre."""
    e = None if ev is None or effect not in FRAME_CANDIDATES else ev.get(effect)
    if e is None:
        return None
    value = {"vignetting": e.get("k"), "compression": e.get("log_ratio"), "sharpening": e.get("ratio"),
             "lens_distortion": None if e.get("k") is None else abs(e["k"])}[effect]
    p_adj = min(1.0, e["p"] * n_tests)
    floor = gain_floor(effect, "frame")
    out = {"channel": "frame", "p_adjusted": p_adj, "z": _z(e["p"]), "gain": value, "floor": floor,
           "scenes": e["scenes"], "frames": e["frames"],
           "significant": bool(p_adj < alpha and value > max(floor or 0.0, 0.0))}
    if effect == "vignetting":
        out["log_slope"] = e["log_slope"]
    elif effect == "compression":
        out["jpeg_quality"] = e.get("quality")
    elif effect == "lens_distortion":
        out["k1"] = e["k"]
    else:
        from synthaug.diagnose.frame_pattern import EDGE_RADIAL_FLOOR

        # edges sharper toward the corners than clean frames' ever are: a lens's change of scale, not a sharpening
        radial = e.get("radial", float("nan"))
        veto = bool(math.isfinite(radial) and radial > EDGE_RADIAL_FLOOR)
        out.update(centre=e["centre"], setting=e.get("setting"), radial=radial if math.isfinite(radial) else None,
                   radial_floor=EDGE_RADIAL_FLOOR, radial_veto=veto, significant=out["significant"] and not veto)
    return out


def frame_corroboration(effect: str, ev: dict[str, dict[str, Any] | None] | None) -> dict[str, Any] | None:
    """A reading of the whole frames, beyond every clean frame's, that points at ``effect`` without being a test of
    its own: for lens distortion, edges that steepen toward the corners (the frames' edge-sharpness trend ``radial``,
    :func:`~synthaug.diagnose.frame_pattern.edge_radial` over scenes, above
    :data:`~synthaug.diagnose.frame_pattern.EDGE_RADIAL_FLOOR`: the reading that withholds sharpening), when the
    lens's own frame test has no reading (no scene that moved between the two looks). A lens changes the scale of a
    20-30 px object near the centre little, so its distance gain on the objects can be significant and above its
    clean floor yet under the 2 % utility rule (:data:`~synthaug.diagnose.calibration.HAND_MIN_GAIN`); the frames
    then say the effect is there. It lifts the utility rule only: the distance channel must still pass its test and
    its calibrated floor (:func:`screen_candidates`). One-sided, as calibrated: the trend's sign with a barrel lens
    is inside the clean range on the reference camera. None: no such reading.

    Example:
        >>> ev = {"sharpening": {"radial": 0.057}, "lens_distortion": None}
        >>> frame_corroboration("lens_distortion", ev)["statistic"], frame_corroboration("defocus", ev)
        ('edge_radial', None)
        >>> frame_corroboration("lens_distortion", {"sharpening": {"radial": 0.01}, "lens_distortion": None})
    """
    from synthaug.diagnose.frame_pattern import EDGE_RADIAL_FLOOR

    if effect != "lens_distortion" or ev is None or ev.get("lens_distortion") is not None:
        return None
    radial = float((ev.get("sharpening") or {}).get("radial", float("nan")))
    if not (math.isfinite(radial) and radial > EDGE_RADIAL_FLOOR):
        return None
    return {"statistic": "edge_radial", "value": radial, "floor": EDGE_RADIAL_FLOOR}


# Frame channels whose effect the objects show as the frames do: an in-camera sharpening filters every pixel of the
# frame, the object's included, so rendering it must fit the objects better than it fits clean ones. (Not vignetting,
# whose objects stay near the centre; not the lens, which changes a 20-30 px object's scale by a few per cent.)
OBJECTS_SHOW: tuple[str, ...] = ("sharpening",)
# ... in the report's words (its significance rule)
OBJECTS_RULE = ("A sharpening the whole frames show is named from them only where rendering it also fits the objects "
                "better than it fits clean data's objects (in the detector's features or in pixels).")


def objects_agree(effect: str, channels: Sequence[dict[str, Any]]) -> dict[str, Any] | None:
    """Whether the objects agree with a frame channel that names ``effect``: its held-out distance gain (rendering
    the objects with the effect) rises above where the clean cases' gain stays
    (:func:`~synthaug.diagnose.calibration.gain_upper`) in the detector's features or in pixels. On clean data the
    sharpening grid's best setting makes the objects' fit worse (clean calibration: pixels −0.034 on average, at most
    −0.030; features −0.021, at most −0.014), and under a lens, whose scale change steepens the frames' edges as a
    sharpening does, just as much (stop 100: pixels −0.024 to −0.033 over 30 lens cases); under a real sharpening the
    objects carry it too and the loss shrinks (amount 1, σ 1: pixels −0.019 to +0.004 over 15 cases). ``agree``
    False: both spaces at or below their clean bound. None: no calibrated bound (no check).

    Example:
        >>> from synthaug.diagnose.calibration import gain_upper
        >>> up = gain_upper("sharpening", "distance:pixel")
        >>> ch = [{"channel": "distance:feature", "gain": -0.03}, {"channel": "distance:pixel", "gain": up - 0.01}]
        >>> objects_agree("sharpening", ch)["agree"]
        False
        >>> objects_agree("sharpening", [ch[0], {**ch[1], "gain": up + 0.001}])["agree"]
        True
    """
    spaces = {}
    for c in channels:
        if c["channel"] in RIVAL_SPACES and c.get("gain") is not None:
            up = gain_upper(effect, c["channel"])
            if up is not None:
                spaces[c["channel"]] = {"gain": float(c["gain"]), "clean_upper": up}
    if not spaces:
        return None
    return {"agree": any(v["gain"] > v["clean_upper"] for v in spaces.values()), "spaces": spaces}


# Candidates that blur the whole frame, the scene's edges as much as the object's: a defocus of the camera. Where the
# frames' edges can be read (two independent looks), a blur the objects show and the frames do not is not the camera's.
FRAME_BLUR: tuple[str, ...] = ("defocus",)
# The level of the frames' blur test. It is a necessary condition, not a finding (the distance channel still makes
# the finding with its own test and floor): 5 % lets a defocus of 0.7 frame px through (p ≤ 0.004 in the 5 cases of
# base 13000 where it is faintest) and would withhold it from the frames of 19 of 20 clean cases there (one reads
# p 0.023; results/diagnose/README.md, stop 114).
BLUR_ALPHA = 0.05
# ... in the report's words (its significance rule)
BLUR_RULE = ("A defocus (a blur of the whole frame) is named only where the frames' edges, where they can be read, are "
             f"blurrier than clean frames' mean (one-sided test over scenes at {100 * BLUR_ALPHA:.0f} %).")


def frames_blurred(effect: str, ev: dict[str, dict[str, Any] | None] | None, *, alpha: float = BLUR_ALPHA
                   ) -> dict[str, Any] | None:
    """Whether the whole frames show the blur ``effect`` (:data:`FRAME_BLUR`) would give them: their edge sharpness
    (``ratio``, the edges' ``A(2) / A(4)``, :func:`~synthaug.diagnose.frame_pattern.sharp_edges`, read through an
    accepted tone curve's inverse as :func:`frame_evidence` reads it) below the clean frames' mean, by the t-test over
    scenes that tests a sharpening the other way (``p_blurrier`` = 1 − its one-sided p, below ``alpha``). On the
    reference camera clean frames read 0.63-0.64, a defocus of σ 0.7-1.5 frame px 0.54-0.63 (p ≤ 0.004), a tone
    curve that bends the objects' facets (gamma 1.4) 0.65-0.66, interlaced frames 0.63-0.64 (results/diagnose/
    README.md, stop 114). ``blurred`` False: the frames' edges are not blurrier than clean frames' (an extra blur on
    the objects is their own). None: not a blur of the frame, or no reading (fewer than 3 scenes, no independent look,
    no calibrated centre).

    Example:
        >>> ev = lambda t, p: {"sharpening": {"ratio": 0.62, "t": t, "p": p, "centre": 0.635, "scenes": 60}}
        >>> frames_blurred("defocus", ev(-2.8, 0.9962))["blurred"], frames_blurred("defocus", ev(5.6, 1e-7))["blurred"]
        (True, False)
        >>> frames_blurred("haze", ev(-2.8, 0.9962)), frames_blurred("defocus", {"sharpening": None})
        (None, None)
    """
    e = None if ev is None or effect not in FRAME_BLUR else ev.get("sharpening")
    if e is None or e.get("centre") is None or not math.isfinite(float(e.get("t", float("nan")))):
        return None
    p_blur = 1.0 - float(e["p"])  # the one-sided t-test of a sharpening (mean above the centre), the other way
    return {"ratio": float(e["ratio"]), "centre": float(e["centre"]), "t": float(e["t"]), "p_blurrier": p_blur,
            "alpha": alpha, "blurred": bool(p_blur < alpha), "scenes": e.get("scenes"),
            "tone_undone": e.get("tone_undone")}


def frame_setting(effect: str, fc: dict[str, Any] | None) -> Setting | None:
    """The camera setting a frame channel implies: vignetting's fall-off ``k``; compression's JPEG quality
    read from the frames' DCT steps, within the screening grid's range (None when the frames show no JPEG
    table, e.g. a video codec's other transforms: the distance screen's setting then stands); sharpening's
    unsharp mask whose inverse brings the frames' edges back to clean frames' (read when the edges are sharper
    than the clean floor; :func:`~synthaug.diagnose.frame_pattern.sharpening_setting`); lens distortion's
    ``k``, the division model's k₁ read off the scene's motion (within the parameter's range)."""
    if fc is None:
        return None
    if effect == "vignetting":
        return {"vignette_k": fc["gain"]}
    if effect == "sharpening":
        return fc.get("setting")
    if effect == "lens_distortion":
        spec = EFFECT_PARAM_SPECS["lens_distortion"][0]
        return {"distortion_k1": float(np.clip(fc["k1"], spec.low, spec.high))}
    q = fc.get("jpeg_quality")
    if effect == "compression" and q is not None:
        grid = [g["jpeg_quality"] for g in CANDIDATE_GRIDS["compression"]]
        return {"jpeg_quality": float(np.clip(q, min(grid), max(grid)))}
    return None


def noise_setting(effect: str, nc: dict[str, Any]) -> Setting | None:
    """The camera setting the NLF implies: a tone curve x^g with slope 2(g - 1)/g when read noise
    dominates, so g = 2 / (2 - slope); shot noise's σ_shot from the affine NLF
    (:func:`~synthaug.diagnose.noise.shot_noise_sigma`, within the parameter's range); None for effects it does
    not set (or without a measurable σ_shot)."""
    if effect == "gamma":
        return {"gamma_g": float(np.clip(2.0 / (2.0 - min(nc["fitted_slope"], 1.5)), 0.4, 2.5))}
    if effect == "shot_noise" and nc.get("shot_sigma") is not None:
        spec = EFFECT_PARAM_SPECS["shot_noise"][0]
        return {"shot_sigma": float(np.clip(nc["shot_sigma"], spec.low, spec.high))}
    return None


def _logistic_cv_accuracy(x: np.ndarray, y: np.ndarray, groups: np.ndarray, folds: list[np.ndarray],
                          l2: float = 1e-2) -> float:
    """k-fold (by seed) accuracy of an L2 logistic regression (LBFGS)."""
    correct, total = 0, 0
    for held in folds:
        te = np.isin(groups, held)
        tr = ~te
        mu, sd = x[tr].mean(0), x[tr].std(0) + 1e-6
        xt = torch.from_numpy((x[tr] - mu) / sd)
        yt = torch.from_numpy(y[tr].astype(np.float64))
        w = torch.zeros(x.shape[1], dtype=torch.float64, requires_grad=True)
        b = torch.zeros(1, dtype=torch.float64, requires_grad=True)
        opt = torch.optim.LBFGS([w, b], max_iter=100, line_search_fn="strong_wolfe")

        def closure() -> torch.Tensor:
            opt.zero_grad()
            z = xt @ w + b
            loss = torch.nn.functional.binary_cross_entropy_with_logits(z, yt) + l2 * (w * w).sum()
            loss.backward()
            return loss

        opt.step(closure)
        with torch.no_grad():
            z = torch.from_numpy((x[te] - mu) / sd) @ w + b
        correct += int(((z > 0).numpy() == (y[te] > 0.5)).sum())
        total += int(te.sum())
    return correct / max(total, 1)


@torch.no_grad()
def realism_accuracy(data: DiagnosisData, syn: torch.Tensor, folds: list[np.ndarray]) -> float:
    """Cross-validated accuracy of a real-vs-synthetic classifier on HOG features (0.5 = indistinguishable)."""
    from synthaug.detectors.hog import hog

    n = len(data)
    x = torch.cat([hog(data.real), hog(syn)]).double().numpy()
    y = np.concatenate([np.ones(n), np.zeros(n)])
    groups = np.concatenate([np.arange(n), np.arange(n)])
    return _logistic_cv_accuracy(x, y, groups, folds)


def screen_candidates(data: DiagnosisData, candidates: Sequence[str] | None = None, *, k: int = 5, seed: int = 0,
                      alpha: float = 0.01, penalty: float = 0.005, min_gain: float = HAND_MIN_GAIN,
                      progress: Callable[[str], None] | None = None, given: dict[str, Setting] | None = None,
                      n_tests: int | None = None, tone: dict[str, Any] | None = None) -> list[dict[str, Any]]:
    """Screen candidate effects on held-out seeds; return them ranked, each with its evidence.

    Args:
        data: the seeds and their fit.
        candidates: effect names (default: all of :data:`CANDIDATE_GRIDS`), screened in this order.
        k: folds of the cross-validation.
        seed: seed of the folds and permutation tests.
        alpha: family-wise significance level (Bonferroni over candidates and channels).
        penalty: subtracted from each held-out relative gain per extra parameter.
        min_gain: a significant distance gain must also reach this raw relative size (an extension worth
            having, not a detectable sliver), unless the whole frames show the effect beyond every clean frame
            (:func:`frame_corroboration`: the channel then carries ``corroborated_by``); besides, every channel must
            exceed its floor measured on clean nuisance-varied data (:mod:`synthaug.diagnose.calibration`), and the
            other distance space must not get worse on held-out seeds. A candidate that blurs the whole frame
            (:data:`FRAME_BLUR`) names nothing where the frames' edges are not blurrier than clean frames'
            (:func:`frames_blurred`; the channels it withheld carry ``frames_veto``).
        given: extensions already accepted, ``{effect: setting}``: the base
            model includes them and every candidate is screened on top of them
            (the conditional gain of forward selection).
        n_tests: the Bonferroni count (default: this call's tests).
        tone: the tone evidence of a rising noise level function (:func:`tone_evidence`) decided earlier, on
            the base model (forward selection passes the first round's, so that an accepted effect screened
            alongside does not rename the NLF's rise in a later round); None: measured here.

    Returns:
        one dict per candidate, ranked (significant distance gains by size, then significant absorbed
        parameters, then the rest by evidence):
        ``effect``, ``significant``, ``channel`` (``"distance:feature"``,
        ``"distance:pixel"``, ``"absorbed"``, ``"noise_level"``, ``"distance:colour"`` or ``"frame"``),
        ``score`` (z), ``p_adjusted``,
        ``gain`` (held-out), ``screen``, ``absorption``, ``noise`` (the noise level function's
        evidence, for its candidates), ``noise_setting``.
    """
    names = list(CANDIDATE_GRIDS) if candidates is None else list(candidates)
    bad = [c for c in names if c not in CANDIDATE_GRIDS]
    if bad:
        raise ValueError(f"unknown candidate(s) {bad}; candidates: {sorted(CANDIDATE_GRIDS)}")
    if n_tests is None:  # counted over the candidates asked for: leaving the colour-only ones out of gray data
        n_tests = n_screening_tests(names)  # does not loosen the others' tests (the calibrated rule's count)
    names = offered_candidates(data, names)[0]  # no colour-only candidate on single-channel data
    rng = np.random.default_rng(seed)
    folds = kfold(len(data), k, rng)
    syn0, w0 = base_render(data, given)
    base = (pairwise_distance(data, syn0), pixel_distance(data.real, syn0))
    nc = None  # the camera's noise level function (frames needed): one measurement for its candidates
    if data.noise_levels is not None and any(c in NOISE_CANDIDATES for c in names):
        nc = noise_channel(data.noise_levels, folds)
        if tone is None:
            tone = tone_evidence(data, nc, base[1], given=given)
    frame_ev = (frame_evidence(data, given) if any(c in FRAME_CANDIDATES or c in FRAME_BLUR for c in names)
                else None)
    hl = (highlight_strength(data, given, centre=gain_centre("specular", "highlight"))
          if any(c in HIGHLIGHT_CANDIDATES for c in names) else None)
    base_colour, paint_gains, tints = None, None, None
    if data.real_rgb is not None and any(c in COLOUR_CANDIDATES for c in names):
        from synthaug.diagnose.diagnosis_data import object_tint, paint_chroma_distances

        gv = given_values(data, given, rgb=True) or None
        rival = any(c in COLOUR_CANDIDATES and c not in PAINT_MIMICS for c in names)
        tints = paint_tints() if rival else None
        # one pair of renders: the model's object, and (for a candidate a paint does not mimic) every paint
        d = paint_chroma_distances(data, gv, object_tint(data) if tints is None
                                   else torch.cat([object_tint(data), tints]))
        base_colour = d[0]
        if rival and float(np.mean(base_colour)) > 0:
            # the object's own colour as the rival explanation: the best case-wide paint, chosen per fold
            paint_gains = _cv_gain(base_colour, d[1:], folds, penalty * 2)[0]
    rows = []
    for name in names:
        if progress:
            progress(name)
        sc = screen_one(data, name, folds, base, penalty=penalty, given=given)
        if name in COLOUR_CANDIDATES and base_colour is None:
            sc["colour_skipped"] = data.colour_note or "no colour channel"
        ab = absorption_gain(data, name, w0.numpy(), folds, rng)
        channels = []
        corroboration = frame_corroboration(name, frame_ev)
        for space, other in (("feature", "pixel"), ("pixel", "feature")):
            channels.append(distance_channel(sc, space, other, n_tests=n_tests, alpha=alpha, penalty=penalty,
                                             floor=gain_floor(name, f"distance:{space}"), min_gain=min_gain,
                                             corroboration=corroboration))
        if ab is not None:
            p_adj = min(1.0, ab["p"] * n_tests)
            n = len(data)
            z = abs(math.atanh(max(min(ab["rho"], 0.999999), -0.999999))) * math.sqrt(max(n - 3, 1))
            floor = gain_floor(name, "absorbed")
            channels.append({"channel": "absorbed", "p_adjusted": p_adj, "z": z if ab["sign_ok"] else -z,
                             "gain": ab["gain"], "rho": ab["rho"], "floor": floor,
                             "significant": bool(p_adj < alpha and ab["sign_ok"] and ab["gain"] > max(floor or 0.0,
                                                                                                      0.0))})
        blur = frames_blurred(name, frame_ev)
        if blur is not None and not blur["blurred"]:  # the objects' blur is not the frame's
            for c in channels:  # frames_veto says it withheld the finding (as objects_veto does; the report's reason)
                if c["significant"]:
                    c.update(significant=False, frames_veto=blur)
        nl = noise_level_channel(name, nc, n_tests, alpha, tone)
        if nl is not None:
            channels.append(nl)
        fc = frame_channel(name, frame_ev, n_tests, alpha)
        if fc is not None:
            if name in OBJECTS_SHOW:  # a filter of the whole image: the objects must not fit as clean ones do
                fc["objects"] = objects_agree(name, channels)
                # objects_veto says it withheld a finding the frames made (as radial_veto does; the report's reason)
                fc["objects_veto"] = bool(fc["significant"] and fc["objects"] is not None
                                          and not fc["objects"]["agree"])
                fc["significant"] = fc["significant"] and not fc["objects_veto"]
            channels.append(fc)
        hc = highlight_channel(name, hl, n_tests, alpha)
        if hc is not None:
            channels.append(hc)
        rival_paint = paint_gains is not None and name not in PAINT_MIMICS
        col = None if base_colour is None else screen_colour(data, name, folds, base_colour, penalty=penalty,
                                                            given=given, paints=tints if rival_paint else None)
        if col is not None:
            sc["colour"] = col
            p_adj = min(1.0, col["p"] * n_tests)
            floor = gain_floor(name, "distance:colour")  # from clean colour cases (None: not calibrated)
            over = None  # beyond the object's own colour: the effect on a painted object against the paint alone
            if rival_paint:
                m_o, _, p_o = _one_sided(np.asarray(col["joint_per_seed_gain"]) - paint_gains)
                over = {"gain": m_o, "p_adjusted": min(1.0, p_o * n_tests)}
            channels.append({"channel": "distance:colour", "p_adjusted": p_adj, "raw_gain_all": col["raw_gain_all"],
                             "z": _z(col["p"]), "gain": col["gain"], "floor": floor, "over_paint": over,
                             "significant": bool(p_adj < alpha and col["gain"] > max(floor or 0.0, 0.0)
                                                 and col["raw_gain_all"] >= min_gain
                                                 and (over is None or over["p_adjusted"] < alpha))})
        rows.append({"effect": name, "significant": None, "channel": None, "score": None, "p_adjusted": None,
                     "gain": None, "channels": channels, "screen": sc, "absorption": ab,
                     "noise": nc if nl is not None else None,
                     "tone": tone if nl is not None else None,
                     "noise_setting": noise_setting(name, nc) if nl is not None else None,
                     "frame_setting": frame_setting(name, fc),
                     "highlight_setting": None if hc is None else hc["setting"]})
    explained_better([r["effect"] for r in rows], [r["channels"] for r in rows])
    for r in rows:
        channels = r["channels"]
        sig = [c for c in channels if c["significant"]]
        sig_dist = [c for c in sig if c["channel"] not in ("absorbed", "frame", "highlight")]
        best = max(sig_dist, key=lambda c: c["gain"]) if sig_dist else max(sig or channels, key=lambda c: c["z"])
        r.update({"significant": bool(sig), "channel": best["channel"], "score": best["z"],
                  "p_adjusted": best["p_adjusted"], "gain": best["gain"]})
    rows.sort(key=_rank)
    return rows


# The distance spaces where a candidate must explain the residual at least as well as every other candidate screened
# beside it (explained_better). Not the chroma channel: there the rival of every candidate is the object's own colour
# (PAINT_MIMICS, the channel's over_paint), and a candidate's chroma gain says how much of that colour it happens to
# absorb as much as how well it explains the camera.
RIVAL_SPACES: tuple[str, ...] = ("distance:feature", "distance:pixel")
# ... in the report's words (its significance rule)
RIVAL_RULE = ("A significant held-out distance gain (the detector's features or pixels) names its effect only where no "
              "other candidate explains the same distance better on held-out seeds, significant or not.")


def explained_better(effects: Sequence[str], channels: Sequence[list[dict[str, Any]]]) -> None:
    """Un-name a distance gain that another candidate explains better: in each space of :data:`RIVAL_SPACES`, a
    significant channel whose held-out gain is below another candidate's held-out gain in the same space (significant
    or not, provided the other space does not get worse with it: ``other_ok``, the validity rule of
    :func:`distance_channel`) is made not significant, and records ``explained_better_by`` (that candidate and its
    gain). The ranking's own rule (:func:`_rank`: what explains the most, not the most precisely measured sliver)
    extended to the candidates that did not pass their test: a significant sliver of a residual that another effect
    describes better does not name its effect (stop 94: haze at airlight 0.85 was named defocus, pixel gains 4.9 % and
    6.5 %). The rivals are the candidates of the same screening: every candidate in forward selection's first round,
    the still significant ones in a later round. A channel the whole frames corroborate (``corroborated_by``,
    :func:`frame_corroboration`: a lens whose frames' edges steepen toward the corners) keeps its name: its evidence
    is more than the distance. Edits ``channels`` (one list per effect, as :func:`screen_candidates` builds them) in
    place.

    Example:
        >>> ch = [[{"channel": "distance:pixel", "gain": 0.049, "significant": True, "other_ok": True}],
        ...       [{"channel": "distance:pixel", "gain": 0.065, "significant": False, "other_ok": True}]]
        >>> explained_better(["defocus", "haze"], ch)
        >>> ch[0][0]["significant"], ch[0][0]["explained_better_by"]
        (False, {'effect': 'haze', 'gain': 0.065})
    """
    for space in RIVAL_SPACES:
        gains = [next((c["gain"] for c in chs if c["channel"] == space and c["other_ok"] and math.isfinite(c["gain"])),
                      None) for chs in channels]
        for i, chs in enumerate(channels):
            ch = next((c for c in chs if c["channel"] == space), None)
            rivals = [(g, e) for j, (g, e) in enumerate(zip(gains, effects)) if j != i and g is not None]
            if ch is None or not ch["significant"] or ch.get("corroborated_by") or not rivals:
                continue
            g, e = max(rivals)
            if g > ch["gain"]:
                ch["significant"] = False
                ch["explained_better_by"] = {"effect": e, "gain": g}


def distance_channel(sc: dict[str, Any], space: str, other: str, *, n_tests: int, alpha: float, penalty: float,
                     floor: float | None, min_gain: float = HAND_MIN_GAIN,
                     corroboration: dict[str, Any] | None = None) -> dict[str, Any]:
    """A candidate's distance channel in ``space`` (``"feature"`` or ``"pixel"``) from its screening ``sc``
    (:func:`screen_one`): significant when the one-sided test over held-out seeds rejects at α (Bonferroni over
    ``n_tests``), the penalised held-out gain exceeds the calibrated clean ``floor`` (None: not calibrated), the raw
    gain over all seeds reaches ``min_gain`` — or, short of it, the frames ``corroboration``
    (:func:`frame_corroboration`) show the effect, recorded as ``corroborated_by`` — and the ``other`` space does
    not get worse on held-out seeds (an "extension" that buys pixel distance by erasing detail the detector sees is
    not more realistic).

    Example:
        >>> sc = {"n_params": 1, "pixel": {"p": 1e-5, "gain": 0.012, "raw_gain_all": 0.017},
        ...       "feature": {"p": 0.4, "gain": 0.0, "raw_gain_all": 0.005}}
        >>> ch = distance_channel(sc, "pixel", "feature", n_tests=40, alpha=0.01, penalty=0.005, floor=0.011)
        >>> ch["significant"], ch["corroborated_by"]
        (False, None)
        >>> cb = {"statistic": "edge_radial", "value": 0.057, "floor": 0.046}
        >>> distance_channel(sc, "pixel", "feature", n_tests=40, alpha=0.01, penalty=0.005, floor=0.011,
        ...                  corroboration=cb)["corroborated_by"]["statistic"]
        'edge_radial'
    """
    s = sc[space]
    p_adj = min(1.0, s["p"] * n_tests)
    other_ok = sc[other]["gain"] + penalty * sc["n_params"] >= 0.0
    worth = s["raw_gain_all"] >= min_gain or corroboration is not None
    big = worth and (floor is None or s["gain"] > floor)
    significant = bool(p_adj < alpha and s["gain"] > 0 and big and other_ok)
    return {"channel": f"distance:{space}", "p_adjusted": p_adj, "z": _z(s["p"]), "gain": s["gain"],
            "other_space_gain": sc[other]["gain"], "other_ok": bool(other_ok), "raw_gain_all": s["raw_gain_all"],
            "floor": floor, "significant": significant,
            "corroborated_by": corroboration if significant and s["raw_gain_all"] < min_gain else None}


def _rank(row: dict[str, Any]) -> tuple[int, float]:
    """Significant distance gains first, largest held-out gain first (what explains the most, not the
    most precisely measured sliver); then absorbed-parameter findings; then the rest by evidence."""
    if not row["significant"]:
        return 2, -row["score"]
    if row["channel"] in ("absorbed", "noise_level", "frame", "highlight"):
        return 1, -row["score"]
    return 0, -row["gain"]
