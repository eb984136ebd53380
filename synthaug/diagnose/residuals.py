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
colour               per-channel bias (grayscale seed sets: not applicable; RGB
                     seed sets are screened in chroma by the colour channel of
                     :mod:`synthaug.diagnose.screening`)
===================  ==========================================================

Fitted parameters can silently absorb a missing effect, which shows as a
dependence of a per-seed value on seed metadata; :func:`parameter_dependence`
tests every (parameter, metadata) pair with a permutation test of Spearman's ρ.

All tests use an explicit ``numpy.random.Generator``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np
import torch

from synthaug.diagnose.calibration import HAND_FLOORS, structure_significant
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


# ------------------------------------------------------------------ data
@dataclass
class DiagnosisData:
    """Everything needed to re-render the fitted images of a seed set, batched.

    Shape:
        real, background, coverage: (N, 1, P, P) float32 in [0, 1];
        normals (N, 3, P, P); origin, frame_size (N, 2); frame_scale (N,);
        fields: random fields (N, 1, P, P) (the fit's object-noise field, a shot-noise field).
    """

    real: torch.Tensor
    background: torch.Tensor
    coverage: torch.Tensor
    normals: torch.Tensor
    theta: Any
    fields: dict[str, torch.Tensor]
    origin: torch.Tensor
    frame_size: torch.Tensor
    frame_scale: torch.Tensor
    part_rotor: torch.Tensor | None
    distance_name: str
    distance: Any
    records: list[dict[str, Any]] = field(default_factory=list)
    fit_distance: np.ndarray | None = None
    resample_sigma: torch.Tensor | None = None  # (N,) patch px: the seed patches' crop resampling blur
    object_px: torch.Tensor | None = None  # (N,) the fitted object's size in frame px (object scale x crop side)
    frame_brightness: torch.Tensor | None = None  # (N,) mean of the whole frame (what auto-exposure meters)
    noise_levels: list[dict[str, np.ndarray]] | None = None  # per seed: its frame's noise level function
    real_rgb: torch.Tensor | None = None  # (N, 3, P, P) the RGB seed patches, when the seed set has them
    background_rgb: torch.Tensor | None = None  # (N, 3, P, P)
    colour_note: str | None = None  # why there is no colour channel (gray or single-channel data)

    def __len__(self) -> int:
        return int(self.real.shape[0])

    def subset(self, idx: Sequence[int] | np.ndarray) -> "DiagnosisData":
        idx_t = torch.as_tensor(np.asarray(idx, np.int64))
        take = lambda t: None if t is None else t[idx_t]  # noqa: E731
        return DiagnosisData(
            real=take(self.real), background=take(self.background), coverage=take(self.coverage),
            normals=take(self.normals), theta=self.theta[idx_t], fields={k: take(v) for k, v in self.fields.items()},
            origin=take(self.origin), frame_size=take(self.frame_size), frame_scale=take(self.frame_scale),
            part_rotor=take(self.part_rotor), distance_name=self.distance_name, distance=self.distance,
            records=[self.records[int(i)] for i in idx_t] if self.records else [],
            fit_distance=None if self.fit_distance is None else self.fit_distance[np.asarray(idx, np.int64)],
            resample_sigma=take(self.resample_sigma), object_px=take(self.object_px),
            frame_brightness=take(self.frame_brightness),
            noise_levels=None if self.noise_levels is None else [self.noise_levels[int(i)] for i in idx_t],
            real_rgb=take(self.real_rgb), background_rgb=take(self.background_rgb), colour_note=self.colour_note)


def _rotor_layers(cache_body: Any, theta: Any, size: int, scale: torch.Tensor, cov: torch.Tensor) -> torch.Tensor:
    cov_b, _ = cache_body.layers(theta.alpha.float(), theta.beta.float(), theta.gamma.float(), theta.t_x.float(),
                                 theta.t_y.float(), size=size, object_scale=scale)
    return (cov - cov_b).clamp(0.0, 1.0)


def load_diagnosis_data(seeds: Any, fit_path: str | Any, mesh: Any, *, distance: str | Any = "hog",
                        resampling: bool = True) -> DiagnosisData:
    """Load a seed set and its fit, and render the fitted layers of every seed.

    Args:
        seeds: a :class:`~synthaug.data.seedset.SeedSet` or its folder.
        fit_path: the fit file (``synthaug fit`` output).
        mesh: the mesh given to the fit (path or built-in name; ``"quadcopter"``
            also gives its rotor parts).
        distance: the detector's distance (name or module), e.g. ``"hog"``.
        resampling: put the seed patches' known crop-resampling blur
            (:func:`~synthaug.data.seedset.crop_resampling_sigma`) on the
            rendered object in every model, base and extended: a seed patch
            and its background are resampled crops, a render is not, and
            without it a missing blur of ~0.4 px reads as a camera effect.

    Returns:
        a :class:`DiagnosisData`.
    """
    import os

    from synthaug.data.fitted import fit_view_cache, fitted_scales
    from synthaug.data.seedset import SeedSet, crop_resampling_sigma
    from synthaug.diagnose.noise import seed_noise_levels
    from synthaug.diagnose.reference_camera import seed_geometry
    from synthaug.effects.pipeline import sample_fields
    from synthaug.fit.fitting import build_distance, patches_tensor
    from synthaug.params import CaptureParams

    if isinstance(seeds, (str, os.PathLike)):
        seeds = SeedSet.load(seeds)
    theta, extra, meta = CaptureParams.load_with_extra(fit_path)
    if theta.batch_size != len(seeds):
        raise ValueError(f"{fit_path} has {theta.batch_size} rows but the seed set has {len(seeds)} seeds")
    if theta.channels != 1:
        raise ValueError(f"only grayscale fits are supported, got {theta.channels} channels")
    cache = fit_view_cache(meta, mesh)
    p = seeds.patch_size
    scale = fitted_scales(extra, meta, 0.7).float()
    cov, nrm = cache.layers(theta.alpha.float(), theta.beta.float(), theta.gamma.float(), theta.t_x.float(),
                            theta.t_y.float(), size=p, object_scale=scale)
    part_rotor = None
    if isinstance(mesh, str) and mesh == "quadcopter":
        from synthaug.diagnose.reference_camera.real_object import real_object

        _, body, _ = real_object("quadcopter", 0.0, 0)
        body_cache = fit_view_cache(meta, body)
        part_rotor = _rotor_layers(body_cache, theta, p, scale, cov)
    fields: dict[str, list[torch.Tensor]] = {}
    names = tuple(theta.effects) + (("shot_noise",) if "shot_noise" not in theta.effects else ())
    for e in extra:
        # the fit's own object-noise field first (same generator, same order), then the candidates'
        f = sample_fields(names, (1, 1, p, p), torch.Generator().manual_seed(int(e.get("generator_seed", 0))))
        for k, v in f.items():
            fields.setdefault(k, []).append(v)
    geo = seed_geometry(seeds)
    frames = _read_frames(seeds)  # the whole frames: what auto-exposure meters, and the noise level function
    dist = build_distance(distance, seeds) if isinstance(distance, str) else distance
    name = distance if isinstance(distance, str) else getattr(distance, "name", type(distance).__name__)
    return DiagnosisData(
        real=patches_tensor(seeds.patches), background=patches_tensor(seeds.backgrounds), coverage=cov,
        normals=nrm, theta=theta, fields={k: torch.cat(v) for k, v in fields.items()}, origin=geo["origin"],
        frame_size=geo["frame_size"], frame_scale=geo["frame_scale"], part_rotor=part_rotor,
        distance_name=str(name), distance=dist, records=list(seeds.records),
        fit_distance=np.array([float(e.get("distance", np.nan)) for e in extra]),
        resample_sigma=torch.from_numpy(crop_resampling_sigma(geo["frame_scale"].double().numpy())).float()
        if resampling else None,
        object_px=(scale.double() * p * geo["frame_scale"].double()).float(),
        frame_brightness=None if frames is None else torch.tensor([float(f.mean()) / 255.0 for f in frames],
                                                                  dtype=torch.float64),
        noise_levels=None if frames is None else seed_noise_levels(seeds, frames=frames),
        **_colour_patches(seeds))


# Largest |R - G| or |B - G| (grey levels) of RGB seed patches that still count as single-channel: a gray
# video decoded to RGB carries +-1-2 levels of chroma from the codec's YUV rounding, no colour.
GRAY_CHROMA_LEVELS = 2


def is_single_channel(rgb: np.ndarray, *, tol: int = GRAY_CHROMA_LEVELS) -> bool:
    """Whether uint8 RGB images (..., 3) carry no colour: every |R - G| and |B - G| at most ``tol`` levels.

    Example:
        >>> g = np.full((2, 4, 4, 3), 120, np.uint8); g[..., 2] += 1
        >>> is_single_channel(g), is_single_channel(np.dstack([g[0, ..., :2], g[0, ..., :1] + 9]))
        (True, False)
    """
    a = np.asarray(rgb).astype(np.int16)
    if a.shape[-1] != 3:
        raise ValueError(f"expected RGB images (..., 3), got shape {a.shape}")
    return bool(a.size == 0 or max(int(np.abs(a[..., 0] - a[..., 1]).max()),
                                   int(np.abs(a[..., 2] - a[..., 1]).max())) <= tol)


def _colour_patches(seeds: Any) -> dict[str, Any]:
    """``real_rgb``/``background_rgb`` (N, 3, P, P) float32 when the seed set has RGB patches with colour;
    ``colour_note`` says why the colour channel is off otherwise."""
    col = seeds.colour()
    if col is None:
        return {"colour_note": "grayscale seed set (no RGB patches)"}
    rgb, bg = col
    if is_single_channel(rgb) and is_single_channel(bg):
        return {"colour_note": f"single-channel data: the RGB patches carry no colour (|R-G|, |B-G| <= "
                               f"{GRAY_CHROMA_LEVELS} grey levels)"}
    to_t = lambda a: torch.from_numpy(a).permute(0, 3, 1, 2).float() / 255.0  # noqa: E731
    return {"real_rgb": to_t(rgb), "background_rgb": to_t(bg)}


def _read_frames(seeds: Any) -> list[np.ndarray] | None:
    """Every seed's whole frame (uint8), read once; None when the seed set has no frames."""
    try:
        return [np.asarray(seeds.frame(i)) for i in range(len(seeds))]
    except (FileNotFoundError, OSError, KeyError, IndexError, ValueError):
        return None


def render_with(data: DiagnosisData, extension: dict[str, dict[str, torch.Tensor | float]] | None = None, *,
                w_d: torch.Tensor | None = None, clamp: bool = True, rgb: bool = False) -> torch.Tensor:
    """S(Θ_i ⊕ φ, B_i) for every seed of ``data``: the fit's Θ extended by candidate effects.

    Args:
        data: the seeds and their fitted layers.
        extension: ``{effect: {param: value}}``, a value a scalar (camera-wide), an (N,) tensor (per
            seed) or, with ``rgb``, a (1, 3) camera-wide or (N, 3) per-seed value per channel. Effects
            already in Θ are overridden.
        w_d: (N,) albedo replacing the fitted w_d (the per-seed nuisance re-solve).
        rgb: render over the RGB backgrounds (:attr:`DiagnosisData.background_rgb`): the fitted (gray)
            Θ on every channel of a neutral object.

    Returns:
        (N, 1, P, P) synthetic images ((N, 3, P, P) with ``rgb``).
    """
    from synthaug.effects.pipeline import simulate
    from synthaug.params import CaptureParams

    if rgb and data.background_rgb is None:
        raise ValueError("this seed set has no RGB patches (colour.npz)")
    extension = dict(extension or {})
    n, c = len(data), (3 if rgb else 1)
    values = {k: v.float()[:, :1].expand(n, c) if v.ndim == 2 else v.float() for k, v in data.theta.as_dict().items()}
    if w_d is not None:
        values["w_d"] = torch.as_tensor(w_d, dtype=torch.float32).reshape(n, 1).expand(n, c)
    effects = tuple(data.theta.effects) + tuple(e for e in extension if e not in data.theta.effects)
    for eff, params in extension.items():
        for k, v in params.items():
            values[k] = _per_channel_values(v, n, c)
    if data.resample_sigma is not None:  # the crop's resampling blur, combined with a defocus candidate
        if "defocus" not in effects:
            effects = effects + ("defocus",)
            values["defocus_sigma"] = torch.zeros(n, c)
        values["defocus_sigma"] = torch.sqrt(values["defocus_sigma"] ** 2
                                             + data.resample_sigma.float().reshape(n, 1) ** 2)
    theta = CaptureParams(values, channels=c, effects=effects, validate=False)
    extras: dict[str, torch.Tensor] = {"frame_scale": data.frame_scale}
    if data.part_rotor is not None:
        extras["part_rotor"] = data.part_rotor
    fields = {k: v.expand(n, c, *v.shape[-2:]) for k, v in data.fields.items()}
    background = data.background_rgb if rgb else data.background
    return simulate(data.coverage, data.normals, background, theta, fields=fields, origin=data.origin,
                    frame_size=data.frame_size, extras=extras, clamp=clamp)


def _per_channel_values(v: Any, n: int, c: int) -> torch.Tensor:
    """A parameter value as (N, C): a scalar or (N,) for every channel; (1, C) or (N, C) per channel."""
    t = torch.as_tensor(v, dtype=torch.float32)
    if t.ndim == 2 and t.shape[1] == c and t.shape[0] in (1, n):
        return t.expand(n, c)
    return t.reshape(-1, 1).expand(n, c)


def render_rgb(data: DiagnosisData, extension: dict[str, dict[str, Any]] | None = None, *,
               w_d: torch.Tensor | None = None, clamp: bool = True) -> torch.Tensor:
    """:func:`render_with` over the RGB backgrounds: (N, 3, P, P)."""
    return render_with(data, extension, w_d=w_d, clamp=clamp, rgb=True)


def solve_albedo_rgb(data: DiagnosisData, extension: dict[str, dict[str, Any]] | None = None) -> torch.Tensor:
    """Per-seed w_d of a neutral object, one value for all three channels (least squares over RGB)."""
    return solve_albedo(data, extension, rgb=True)


def chroma_distance(real: torch.Tensor, syn: torch.Tensor) -> np.ndarray:
    """Per-seed L2 of the chroma residual ``(R - G, B - G)``: blind to whatever acts alike on all channels
    (blur, tone, haze on a neutral object), it sees colour fringes and colour casts."""
    chroma = lambda x: torch.stack([x[:, 0] - x[:, 1], x[:, 2] - x[:, 1]], 1)  # noqa: E731
    return (chroma(real) - chroma(syn)).flatten(1).norm(dim=1).double().numpy()


def pairwise_distance(data: DiagnosisData, syn: torch.Tensor, real: torch.Tensor | None = None) -> np.ndarray:
    """d(X_i, Y_i) per seed in the detector's distance (features when it has them)."""
    real = data.real if real is None else real
    dist = data.distance
    with torch.no_grad():
        if hasattr(dist, "features"):
            return (dist.features(real) - dist.features(syn)).flatten(1).norm(dim=1).double().numpy()
        return np.array([float(dist(real[i:i + 1], syn[i:i + 1])[0]) for i in range(len(real))])


def pixel_distance(real: torch.Tensor, syn: torch.Tensor) -> np.ndarray:
    """Pixel L2 per seed (eq. 2)."""
    return (real - syn).flatten(1).norm(dim=1).double().numpy()


def solve_albedo(data: DiagnosisData, extension: dict[str, dict[str, Any]] | None = None,
                 *, lo: float = 0.0, hi: float = 1.0, rgb: bool = False) -> torch.Tensor:
    """Per-seed w_d minimising the pixel L2, by a linear fit between two renders.

    The image is affine in w_d for the paper's effects (material → blurs →
    overlay), so two renders give the exact least-squares w_d; with a
    nonlinear extension it is the secant solution. With ``rgb``: one w_d for the three channels
    of a neutral object, least squares over RGB.
    """
    a = render_with(data, extension, w_d=torch.full((len(data),), 0.2), clamp=False, rgb=rgb)
    b = render_with(data, extension, w_d=torch.full((len(data),), 0.6), clamp=False, rgb=rgb)
    slope = (b - a) / 0.4
    num = (((data.real_rgb if rgb else data.real) - a) * slope).flatten(1).sum(1)
    den = (slope * slope).flatten(1).sum(1).clamp_min(1e-9)
    return (0.2 + num / den).clamp(lo, hi)


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
    n, _, p, _ = res.shape
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
    # spectrum at the same frequency, high frequencies only (a shape misfit is broadband and isotropic)
    w_n = np.maximum(wobj.flatten(1).sum(1).numpy()[:, None], 1)
    spec_rows = _line_spectrum(res, wobj, -2) / w_n
    spec_cols = _line_spectrum(res, wobj, -1) / w_n
    freqs = np.fft.rfftfreq(p)
    hi = np.nonzero(freqs >= 0.2)[0]
    # a camera's periodic structure (fields, banding) is periodic in FRAME pixels: each seed's spectrum is
    # put on a common grid of frame frequencies (patch frequency / frame scale) before the peak is sought
    fs = data.frame_scale.double().numpy()
    grid = np.round(np.arange(0.1, 0.5 + 1e-9, 0.0125), 4)
    for label, a, b, what in (("rows", spec_rows, spec_cols, "vertical (along image columns: row-to-row)"),
                              ("columns", spec_cols, spec_rows, "horizontal (column-to-column)")):
        lr = np.log((a[:, hi] + 1e-12) / (b[:, hi] + 1e-12))
        lr_f = np.stack([np.interp(grid, freqs[hi] / fs[i], lr[i], left=np.nan, right=np.nan) for i in range(n)])
        cnt = np.isfinite(lr_f).sum(0)
        enough = cnt >= max(5, n // 4)
        score = np.where(enough, np.nansum(lr_f, 0) / np.maximum(cnt, 1), -np.inf)
        j = int(np.argmax(score))
        mean, t, pv = t_test(lr_f[:, j])
        pv = min(1.0, pv * int(enough.sum()))  # the peak was chosen among the frequencies
        f = float(grid[j])
        put(f"periodic_{label}", mean, pv, f"{what} periodic structure: peak at {f:.3f} cycles per frame px "
            f"(period {1 / f:.1f} frame px), {math.exp(mean):.1f}x the power of the other direction",
            frequency=f, period_px=float(1 / f), n_seeds=int(np.isfinite(lr_f[:, j]).sum()))
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
