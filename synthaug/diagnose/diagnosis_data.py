"""The diagnosis's data: a seed set and its fit, re-rendered (issue 6).

:func:`load_diagnosis_data` reads the real patches, backgrounds, the fitted Θ and the fitted object's layers
into one batched :class:`DiagnosisData`; :func:`render_with` re-renders the fitted simulation S(Θ, B), with
an extension (effects added at given settings) when asked, :func:`solve_albedo` re-solves the diffuse weight
for it, and the distances compare renders with the real patches (the detector's, pixels, chroma). The
residual statistics on top of them are :mod:`synthaug.diagnose.residuals`'.
"""

from __future__ import annotations

import math

from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np
import torch

__all__ = [
    "DiagnosisData",
    "load_diagnosis_data",
    "render_with",
    "render_rgb",
    "paint_chroma_distances",
    "object_chroma_distance",
    "object_tint",
    "object_colour_factors",
    "solve_albedo",
    "solve_albedo_rgb",
    "albedo_renders",
    "ALBEDO_POINTS",
    "pairwise_distance",
    "pixel_distance",
    "chroma_distance",
    "is_single_channel",
    "GRAY_CHROMA_LEVELS",
]


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
    frame_lines: list[dict[str, np.ndarray]] | None = None  # per seed: its frame's line profiles (frame_pattern)
    frame_summaries: list[dict[str, Any]] | None = None  # per seed: frame_pattern.frame_summary of its frame
    real_rgb: torch.Tensor | None = None  # (N, 3, P, P) the RGB seed patches, when the seed set has them
    background_rgb: torch.Tensor | None = None  # (N, 3, P, P)
    colour_note: str | None = None  # why there is no colour channel (gray or single-channel data)
    object_rgb: np.ndarray | None = None  # (3,) the object's known colour (albedo factors, unit luma); None: grey

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
            frame_lines=None if self.frame_lines is None else [self.frame_lines[int(i)] for i in idx_t],
            frame_summaries=None if self.frame_summaries is None else [self.frame_summaries[int(i)] for i in idx_t],
            real_rgb=take(self.real_rgb), background_rgb=take(self.background_rgb), colour_note=self.colour_note,
            object_rgb=self.object_rgb)


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
        frame_lines=None if frames is None else _frame_lines(frames, geo, p),
        frame_summaries=None if frames is None else _frame_summaries(seeds, frames, geo, p),
        **_colour_patches(seeds))


def _frame_lines(frames: list[np.ndarray], geo: dict[str, torch.Tensor], p: int) -> list[dict[str, np.ndarray]]:
    """Each frame's line profiles (:func:`~synthaug.diagnose.frame_pattern.line_profiles`), its seed's crop left
    out."""
    from synthaug.diagnose.frame_pattern import line_profiles

    return [line_profiles(f, exclude=(float(geo["origin"][i, 0]), float(geo["origin"][i, 1]),
                                      p * float(geo["frame_scale"][i])))
            for i, f in enumerate(frames)]


def _frame_summaries(seeds: Any, frames: list[np.ndarray], geo: dict[str, torch.Tensor], p: int
                     ) -> list[dict[str, Any]]:
    """Each frame's radial fall-off, blockiness and scene texture
    (:func:`~synthaug.diagnose.frame_pattern.frame_summary`), its seed's crop left out, with its background frame
    (where the seed set has one) to tell whether its texture repeats."""
    from synthaug.diagnose.frame_pattern import SETTING_FRAMES, frame_summary

    out = []
    every = max(1, math.ceil(len(frames) / SETTING_FRAMES))  # the frames that keep their looks (a setting's read)
    for i, f in enumerate(frames):
        try:
            bg = np.asarray(seeds.background_frame(i))
        except (FileNotFoundError, OSError, KeyError, IndexError, ValueError, AttributeError):
            bg = None
        out.append(frame_summary(f, background=bg, exclude=(float(geo["origin"][i, 0]), float(geo["origin"][i, 1]),
                                                            p * float(geo["frame_scale"][i])),
                                 keep_looks=i % every == 0))
    return out


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
        w_d: (N,) albedo replacing the fitted w_d (the per-seed nuisance re-solve); with ``rgb`` also (N, 3),
            a painted object's albedo per channel (:func:`paint_chroma_distances`).
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
        w = torch.as_tensor(w_d, dtype=torch.float32)
        values["w_d"] = w if w.shape == (n, c) else w.reshape(n, 1).expand(n, c)
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


@torch.no_grad()
def paint_chroma_distances(data: DiagnosisData, extension: dict[str, dict[str, Any]] | None,
                           tints: torch.Tensor) -> np.ndarray:
    """Per-seed chroma distance (:func:`chroma_distance`) of the object painted with each of ``tints``.

    A paint multiplies the object's albedo per channel: w_d = w · t with the seed's w solved by least squares over
    RGB (as :func:`solve_albedo_rgb`). The render is affine in each channel's w_d (material, blurs, the colour
    effects on the object, overlay; unclamped), so two renders, w_d = 0 and 1 on every channel, give every paint's
    image exactly: ``I0 + w t_c (I1 - I0)``, then clamped to [0, 1] as a render is.

    Shape:
        tints (P, 3) -> (P, N).
    """
    n = len(data)
    i0 = render_rgb(data, extension, w_d=torch.zeros(n), clamp=False).double()
    d = render_rgb(data, extension, w_d=torch.ones(n), clamp=False).double() - i0
    r = data.real_rgb.double()
    a = ((r - i0) * d).flatten(2).sum(2)  # (N, 3)
    b = (d * d).flatten(2).sum(2)
    out = np.empty((len(tints), n))
    for k, t in enumerate(torch.as_tensor(tints, dtype=torch.float64)):
        w = ((a * t).sum(1) / (b * t * t).sum(1).clamp_min(1e-9)).clamp(0.0, 1.0)
        img = (i0 + (w[:, None] * t[None, :])[:, :, None, None] * d).clamp(0.0, 1.0)
        out[k] = chroma_distance(r, img)
    return out


def object_tint(data: DiagnosisData) -> torch.Tensor:
    """The model object's per-channel albedo factors, (1, 3): the paint (1, 1, 1) of a neutral object, or the known
    colour :attr:`DiagnosisData.object_rgb`."""
    tint = np.ones(3) if data.object_rgb is None else data.object_rgb
    return torch.as_tensor(tint, dtype=torch.float64)[None]


def object_chroma_distance(data: DiagnosisData, extension: dict[str, dict[str, Any]] | None) -> np.ndarray:
    """Per-seed chroma distance of the model (+ ``extension``) over the RGB backgrounds, w_d re-solved: a neutral
    object, or one of the known colour :attr:`DiagnosisData.object_rgb` — :func:`object_tint` through
    :func:`paint_chroma_distances` (for the neutral object the same distances as :func:`solve_albedo_rgb` and
    :func:`render_rgb` give, to float rounding, from one render fewer)."""
    return paint_chroma_distances(data, extension, object_tint(data))[0]


def object_colour_factors(rgb: Sequence[float]) -> np.ndarray:
    """An object's colour given as three positive RGB values (any scale: a measured patch, a paint's sRGB) as
    per-channel albedo factors of unit Rec. 601 luma: the colour without its brightness, which w_d carries.

    Example:
        >>> object_colour_factors([200, 200, 200]).tolist()
        [1.0, 1.0, 1.0]
        >>> f = object_colour_factors([1.0, 0.9, 0.8]); round(float(f @ [0.299, 0.587, 0.114]), 12)
        1.0
    """
    from synthaug.effects.camera_functional import LUMA_WEIGHTS

    v = np.asarray(rgb, np.float64)
    if v.shape != (3,) or not np.all(np.isfinite(v)) or not np.all(v > 0):
        raise ValueError(f"an object colour is three positive finite RGB values, got {list(np.ravel(rgb))}")
    return v / float(v @ np.asarray(LUMA_WEIGHTS, np.float64))


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
    a, b = albedo_renders(data, extension, rgb=rgb)
    w0, w1 = ALBEDO_POINTS
    slope = (b - a) / (w1 - w0)
    num = (((data.real_rgb if rgb else data.real) - a) * slope).flatten(1).sum(1)
    den = (slope * slope).flatten(1).sum(1).clamp_min(1e-9)
    return (w0 + num / den).clamp(lo, hi)


ALBEDO_POINTS = (0.2, 0.6)
"""The two albedos every seed is rendered at where its image is solved as a line in w_d (:func:`albedo_renders`)."""


def albedo_renders(data: DiagnosisData, extension: dict[str, dict[str, Any]] | None = None, *,
                   rgb: bool = False) -> tuple[torch.Tensor, torch.Tensor]:
    """The model (+ ``extension``) rendered unclamped at the two albedos :data:`ALBEDO_POINTS` on every seed: the
    image is affine in w_d (exactly for the paper's effects), so the two give it at any w_d
    (:func:`solve_albedo`; the highlight's joint fit, :func:`synthaug.diagnose.screening.highlight_strength`)."""
    return tuple(render_with(data, extension, w_d=torch.full((len(data),), w), clamp=False, rgb=rgb)
                 for w in ALBEDO_POINTS)
