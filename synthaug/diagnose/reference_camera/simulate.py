"""The reference camera as a simulator: the arguments checked into one record, each seed's record drawn
(:class:`MeasuredSeed`: every random number, frozen), then rendered, its object physics applied, captured
by the whole-frame camera (:mod:`~synthaug.diagnose.reference_camera.capture`), cropped and written with
its truth (:func:`make_measured_seedset`).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
import torch

from synthaug.diagnose.nuisances import Nuisances, SeedNuisance, drift_scene, shade_object, smooth_normals
from synthaug.diagnose.reference_camera.capture import capture, to_u8
from synthaug.diagnose.reference_camera.real_object import real_object
from synthaug.diagnose.reference_camera.settings import (
    AE_TARGET,
    OBJECT_ONLY_EFFECTS,
    PAPER_RANGES,
    WHOLE_FRAME_EFFECTS,
    Strength,
    _draw_strengths,
    resolve_hidden,
)
from synthaug.diagnose.reference_camera.truth import _FORMAT, _VERSION, _model_units, _truth_file
from synthaug.effects import camera_functional as Cx
from synthaug.effects import functional as Fx
from synthaug.effects.camera import CAMERA_EFFECTS
from synthaug.effects.material import TEXTURE_PAD, texture_field
from synthaug.effects.pipeline import apply_effects
from synthaug.effects.registry import PAPER_EFFECTS, RenderState, get_effect, ordered
from synthaug.params import CaptureParams


def _interlace(color: torch.Tensor, cov: torch.Tensor, shift: float, angle: float) -> tuple[torch.Tensor, torch.Tensor]:
    """Odd rows from the second field, the object displaced by ``shift`` px along ``angle``."""
    b, c, h, w = color.shape
    yy = torch.arange(h, dtype=color.dtype)[None, None, :, None]
    xx = torch.arange(w, dtype=color.dtype)[None, None, None, :]
    stack = torch.cat([color * cov, cov.expand(b, c, h, w)], 1)
    moved = Cx._sample(stack, xx - shift * math.cos(angle), yy - shift * math.sin(angle), "zeros")
    odd = (torch.arange(h) % 2 == 1)[None, None, :, None]
    out = torch.where(odd, moved, stack)
    premul, cv = out[:, :c], out[:, c:].clamp(0.0, 1.0)
    return torch.where(cv > 1e-6, premul / cv.clamp_min(1e-6), torch.zeros_like(premul)), cv


def _box(cov: np.ndarray, threshold: float = 0.5) -> np.ndarray | None:
    mask = cov >= threshold
    if not mask.any():
        return None
    ys = np.nonzero(mask.any(1))[0]
    xs = np.nonzero(mask.any(0))[0]
    return np.array([xs[0], ys[0], xs[-1] + 1 - xs[0], ys[-1] + 1 - ys[0]], np.float64)


# ------------------------------------------------------------------ setup
_PAPER_NAMES = ("w_d", "sigma_s", "sigma_u", "sigma_v", "alpha_m", "sigma_n")


@dataclass(frozen=True)
class _Setup:
    """The validated arguments of :func:`make_measured_seedset`, read by every step."""

    n_seeds: int
    frame_hw: tuple[int, int]
    object_px: tuple[float, float]
    crop_side: int  # side of the square the object is rendered in (frame px)
    patch_size: int
    object_fraction: float
    settings: dict[str, dict[str, Strength]]
    ranges: dict[str, tuple[float, float]]
    per_video: tuple[str, ...]
    n_videos: int
    read_noise: float
    background_noise_factor: float
    nuisances: Nuisances
    mesh_perturbation: float
    seed: int
    colour: bool
    view_step_deg: float
    sprite_size: int


def _setup(*, n_seeds: int, hidden: Any, mesh: Any, mesh_perturbation: float, frame_size: tuple[int, int],
           patch_size: int, object_fraction: float, object_px: tuple[float, float], seed: int,
           paper_ranges: Mapping[str, tuple[float, float]] | None, read_noise: float,
           background_noise_factor: float, n_videos: int, per_video: Sequence[str], view_step_deg: float,
           sprite_size: int, colour: bool, nuisances: Nuisances | None) -> _Setup:
    """Check :func:`make_measured_seedset`'s arguments (errors name the bad value) into one record."""
    if n_seeds < 1:
        raise ValueError(f"n_seeds must be >= 1, got {n_seeds}")
    h_f, w_f = (int(v) for v in frame_size)
    lo_px, hi_px = (float(v) for v in object_px)
    if not 4 <= lo_px <= hi_px:
        raise ValueError(f"object_px must be (low, high) with 4 <= low <= high, got {object_px}")
    crop_side = int(math.ceil(2.5 * hi_px / 2)) * 2
    if crop_side + 2 > min(h_f, w_f):
        raise ValueError(f"frame_size {frame_size} is too small for objects of {hi_px} px (need > {crop_side + 2})")
    if not 0 <= read_noise <= 0.2:
        raise ValueError(f"read_noise must be in [0, 0.2], got {read_noise}")
    if not 0 <= background_noise_factor <= 1:
        raise ValueError(f"background_noise_factor must be in [0, 1], got {background_noise_factor}")
    if n_videos < 1:
        raise ValueError(f"n_videos must be >= 1, got {n_videos}")
    per_video = tuple(per_video)
    bad_pv = sorted(set(per_video) - set(PAPER_RANGES))
    if bad_pv:
        raise ValueError(f"per_video: unknown parameter(s) {bad_pv}; known: {sorted(PAPER_RANGES)}")
    settings = resolve_hidden(hidden)
    nz = Nuisances.none() if nuisances is None else nuisances
    if not isinstance(nz, Nuisances):
        raise ValueError(f"nuisances must be a Nuisances record or None, got {type(nuisances).__name__}")
    if nz.mesh_perturbation > 0 and mesh_perturbation > 0:
        raise ValueError(f"give the mesh perturbation once: mesh_perturbation={mesh_perturbation} and "
                         f"nuisances.mesh_perturbation={nz.mesh_perturbation}")
    if not nz.mesh_is_model and not (isinstance(mesh, str) and mesh == "quadcopter") and \
            (nz.rotor_scale != 1.0 or nz.mesh_sections != 16):
        raise ValueError("nuisances.rotor_scale / mesh_sections apply to the built-in 'quadcopter' only, "
                         f"got mesh {mesh!r}")
    ranges = dict(PAPER_RANGES)
    bad = sorted(set(paper_ranges or {}) - set(ranges))
    if bad:
        raise ValueError(f"paper_ranges: unknown parameter(s) {bad}; known: {sorted(ranges)}")
    ranges.update({k: (float(v[0]), float(v[1])) for k, v in dict(paper_ranges or {}).items()})
    return _Setup(n_seeds=n_seeds, frame_hw=(h_f, w_f), object_px=(lo_px, hi_px), crop_side=crop_side,
                  patch_size=patch_size, object_fraction=object_fraction, settings=settings, ranges=ranges,
                  per_video=per_video, n_videos=n_videos, read_noise=read_noise,
                  background_noise_factor=background_noise_factor, nuisances=nz,
                  mesh_perturbation=max(mesh_perturbation, nz.mesh_perturbation), seed=seed, colour=colour,
                  view_step_deg=view_step_deg, sprite_size=sprite_size)


def _scenes(setup: _Setup, backgrounds: Sequence[np.ndarray] | None
            ) -> tuple[list[np.ndarray], list[np.ndarray | None]]:
    """Each seed's scene (float in [0, 1], (H, W), or (3, H, W) with ``colour``) and the colour of its air.

    The colour is a per-seed tint (RGB, unit luma; None in gray): a bluish sky is the gray sky times it.
    """
    from synthaug.data.procedural import sky_backgrounds

    n_seeds, (h_f, w_f), seed = setup.n_seeds, setup.frame_hw, setup.seed
    if backgrounds is None:
        scenes = [b.astype(np.float64) / 255.0 for b in sky_backgrounds(n_seeds, (h_f, w_f), seed=seed)]
    else:
        if len(backgrounds) == 0:
            raise ValueError("backgrounds must hold at least one frame")
        scenes = []
        for i in range(n_seeds):
            b = np.asarray(backgrounds[i % len(backgrounds)])
            if b.shape != (h_f, w_f):
                raise ValueError(f"backgrounds[{i % len(backgrounds)}] has shape {b.shape}, expected {(h_f, w_f)}")
            scenes.append(b.astype(np.float64) / 255.0 if b.dtype == np.uint8 else b.astype(np.float64))
    tints: list[np.ndarray | None] = [None] * n_seeds
    if setup.colour:  # red and green below blue
        for i in range(n_seeds):
            t = np.random.default_rng([seed, i, 3]).uniform([0.78, 0.9, 1.0], [0.9, 0.97, 1.0])
            tints[i] = t / float(np.dot(t, Cx.LUMA_WEIGHTS))  # unit luma: the colour of this scene's air
            scenes[i] = np.clip(scenes[i][None] * t[:, None, None], 0.0, 1.0)
    return scenes, tints


# ------------------------------------------------------------------ per seed: draw
@dataclass(frozen=True)
class MeasuredSeed:
    """The drawn, frozen record of one measured seed: every random number it uses, drawn before any rendering.

    Streams: ``[seed, index, 0]`` the scene's (Θ, pose, size, place and the noise fields), ``[seed, index, 1]``
    the hidden settings, ``[seed, video, 2]`` the per-video Θ; the nuisances' are their own
    (:meth:`~synthaug.diagnose.nuisances.Nuisances.draw_seed`). The scene does not depend on what is hidden,
    so the same seed with and without an effect differs only by the effect.

    Attributes:
        index, video: the seed's index and its video.
        paper: the paper's Θ (patch units: σ in patch px).
        camera: ``{effect: {param: value}}`` the hidden settings this seed sees, the physics behind the
            derived ones applied (settings' ``_DERIVED_PARAMS``: haze from the object's distance,
            auto-exposure from the scene's brightness, the rolling shutter along α_m).
        pose: (α, β, γ) requested, radians.
        size_px: object size (mesh unit length) in frame px.
        corner: (x0, y0), frame px, of the square the object is rendered in.
        nuisance: the nuisance values this seed sees.
        object_noise: (1, 1, S, S) the object noise's standard normal field (S: the render square's side).
        frame_noise, background_noise: (1, C, H, W) the sensor noise's standard normal fields of the frame
            and of its background frame.
        texture_noise: (1, 1, S + 2·TEXTURE_PAD, S + 2·TEXTURE_PAD) white noise of the albedo texture, or None.
    """

    index: int
    video: int
    paper: dict[str, float]
    camera: dict[str, dict[str, float]]
    pose: tuple[float, float, float]
    size_px: float
    corner: tuple[int, int]
    nuisance: SeedNuisance
    object_noise: torch.Tensor
    frame_noise: torch.Tensor
    background_noise: torch.Tensor
    texture_noise: torch.Tensor | None


def _draw_seed(setup: _Setup, index: int, scene: np.ndarray) -> MeasuredSeed:
    """Draw seed ``index``'s record (a pure function of ``(setup.seed, index)`` and its scene)."""
    seed, i, nz, side = setup.seed, index, setup.nuisances, setup.crop_side
    h_f, w_f = setup.frame_hw
    video = i % setup.n_videos
    rng = np.random.default_rng([seed, i, 0])
    cam = _draw_strengths(setup.settings, np.random.default_rng([seed, i, 1]))
    if "column_pattern" in cam:  # the sensor's pattern: the camera's, the same for every seed
        cam["column_pattern"]["pattern_seed"] = float(seed)
    paper = {k: float(rng.uniform(*setup.ranges[k])) for k in _PAPER_NAMES}
    video_rng = np.random.default_rng([seed, video, 2])
    for k in setup.per_video:  # the scene's light on the object's paint: one value per video
        paper[k] = float(video_rng.uniform(*setup.ranges[k]))
    alpha, beta, gamma = rng.uniform(-math.pi, math.pi), rng.uniform(-math.pi / 2, math.pi / 2), \
        rng.uniform(-math.pi, math.pi)
    size_px = float(rng.uniform(*setup.object_px))
    x0 = int(rng.integers(1, w_f - side - 1))
    y0 = int(rng.integers(1, h_f - side - 1))
    gen = torch.Generator().manual_seed(int(rng.integers(2 ** 62)))
    seed_nz = nz.draw_seed(seed=seed, index=i, video=video)  # own streams: nothing above changes
    texture = None
    object_noise = torch.randn((1, 1, side, side), generator=gen, dtype=torch.float64)
    if not nz.shading_is_model and nz.albedo_texture_amp > 0:
        texture = torch.randn((1, 1, side + 2 * TEXTURE_PAD, side + 2 * TEXTURE_PAD),
                              generator=torch.Generator().manual_seed(seed_nz.texture_seed), dtype=torch.float64)
    frame_shape = (1, 1 if scene.ndim == 2 else scene.shape[0], h_f, w_f)
    frame_noise = torch.randn(frame_shape, generator=gen, dtype=torch.float64)
    background_noise = torch.randn(frame_shape, generator=gen, dtype=torch.float64)
    return MeasuredSeed(index=i, video=video, paper=paper,
                        camera=_with_physics(cam, size_px, float(np.mean(scene)), paper["alpha_m"]),
                        pose=(float(alpha), float(beta), float(gamma)), size_px=size_px, corner=(x0, y0),
                        nuisance=seed_nz, object_noise=object_noise, frame_noise=frame_noise,
                        background_noise=background_noise, texture_noise=texture)


def _with_physics(cam: dict[str, dict[str, float]], size_px: float, scene_mean: float,
                  alpha_m: float) -> dict[str, dict[str, float]]:
    """``cam`` (freshly drawn, changed in place) with the settings of ``_DERIVED_PARAMS``
    (:mod:`~synthaug.diagnose.reference_camera.settings`) turned into the effects' own parameters."""
    if "haze" in cam and "haze_extinction_px" in cam["haze"]:  # more air in front of a farther object
        cam["haze"]["haze_amount"] = 1.0 - math.exp(-cam["haze"]["haze_extinction_px"] / size_px)
    if "exposure" in cam and "exposure_auto" in cam["exposure"]:  # auto-exposure follows the scene
        cam["exposure"]["exposure_gain"] = float(np.clip((AE_TARGET / max(scene_mean, 1e-3)) ** cam["exposure"]
                                                         ["exposure_auto"], 0.5, 2.0))
    if "rolling_shutter" in cam:
        rs = cam["rolling_shutter"]
        if "rs_magnitude" in rs:  # readout shear along this seed's motion
            rs["rs_skew"] = rs["rs_magnitude"] * math.cos(alpha_m)
            rs["rs_stretch"] = rs["rs_magnitude"] * math.sin(alpha_m)
    return cam


# ------------------------------------------------------------------ per seed: render, physics, capture
def _batched(image: np.ndarray) -> torch.Tensor:
    """(H, W) or (C, H, W) -> (1, C, H, W) tensor (sharing memory)."""
    t = torch.from_numpy(image)[None]
    return t[None] if t.ndim == 3 else t


def _render_layers(draw: MeasuredSeed, cache: Any, body_cache: Any | None, side: int
                   ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor | None]:
    """Coverage and normals of the real object in its render square, and its rotors' coverage (or None)."""
    pose = [torch.tensor([float(v)]) for v in (*draw.pose, 0.0, 0.0)]
    cov, nrm = cache.layers(*pose, size=side, object_scale=draw.size_px / side, dtype=torch.float64)
    if body_cache is None:
        return cov, nrm, None
    cov_body, _ = body_cache.layers(*pose, size=side, object_scale=draw.size_px / side, dtype=torch.float64)
    return cov, nrm, (cov - cov_body).clamp(0.0, 1.0)


def _annotated_box(setup: _Setup, draw: MeasuredSeed, cov: torch.Tensor) -> np.ndarray:
    """The box an annotator draws (x, y, w, h, frame px): the sharp object, after the geometric warps."""
    cam, (x0, y0), side = draw.camera, draw.corner, setup.crop_side
    cov_geo = cov
    if "rolling_shutter" in cam:
        rs = cam["rolling_shutter"]
        cov_geo = Cx.rolling_shutter(cov, cov, torch.tensor([rs["rs_skew"]]), torch.tensor([rs["rs_stretch"]]))[1]
    cov_frame = np.zeros(setup.frame_hw)
    cov_frame[y0:y0 + side, x0:x0 + side] = cov_geo[0, 0].numpy()
    if "lens_distortion" in cam:
        cov_frame = Cx.lens_distortion(torch.from_numpy(cov_frame)[None, None],
                                       torch.tensor([cam["lens_distortion"]["distortion_k1"]], dtype=torch.float64),
                                       recentre=False).numpy()[0, 0]
    box = _box(cov_frame)
    if box is None:  # pragma: no cover - a unit-size mesh is never empty at >= 4 px
        raise RuntimeError(f"seed {draw.index}: the object is not visible")
    return box


def _frame_sigmas(paper: Mapping[str, float], frame_scale: float) -> dict[str, float]:
    """The paper's blurs σ_s, σ_u, σ_v in frame px."""
    return {k: paper[k] * frame_scale for k in ("sigma_s", "sigma_u", "sigma_v")}


def _object_radiance(nz: Nuisances, draw: MeasuredSeed, cov: torch.Tensor, nrm: torch.Tensor,
                     side: int, paint: float = 1.0) -> torch.Tensor:
    """The object's colour before the model's material in one channel whose albedo the paint scales by ``paint``
    (:attr:`Nuisances.paint_rgb`; 1 in gray): the real material under its video's light, or (the fit's own shading)
    a neutral radiance 0.5 that the ``material`` effect then shades (its w_d carries the paint then)."""
    if nz.shading_is_model:
        return Fx.diffuse_material(nrm, cov, torch.tensor([[0.5]], dtype=torch.float64))
    texture = None
    if draw.texture_noise is not None:
        texture = texture_field(draw.texture_noise, torch.tensor([nz.albedo_texture_px], dtype=torch.float64),
                                (side, side))
    return shade_object(nrm, cov, draw.paper["w_d"] * paint, nz, draw.nuisance, texture=texture)


def _object_on_frame(setup: _Setup, draw: MeasuredSeed, scene: np.ndarray, cov: torch.Tensor, nrm: torch.Tensor,
                     rotor: torch.Tensor | None, frame_scale: float) -> torch.Tensor:
    """The linear frame (1, C, H, W): the object-only physics on the render square at frame scale (σ in frame
    px) — effects in the registry's order —, overlaid on the scene as it was when the frame was taken (a
    nuisance may move it against the background frame's), then boundary blur and object noise."""
    cam, paper, nz, side, (x0, y0) = draw.camera, draw.paper, setup.nuisances, setup.crop_side, draw.corner
    shot = _batched(drift_scene(scene, draw.nuisance))
    bg_crop = shot[..., y0:y0 + side, x0:x0 + side]
    values: dict[str, Any] = {"w_d": paper["w_d"], **_frame_sigmas(paper, frame_scale), "alpha_m": paper["alpha_m"],
                              "sigma_n": paper["sigma_n"]}
    object_effects = [e.name for e in ordered([e for e in OBJECT_ONLY_EFFECTS if e in cam and e in CAMERA_EFFECTS])]
    for eff in object_effects:
        values.update({s.name: cam[eff][s.name] for s in get_effect(eff).params})
    extras: dict[str, torch.Tensor] = {} if rotor is None else {"part_rotor": rotor}
    obj_normals = nrm  # only a hidden highlight reads them (the real material is shaded by _object_radiance)
    if "specular" in object_effects and not nz.shading_is_model:  # a hidden highlight is on the real material:
        values["specular_ks"] = values["specular_ks"] * draw.nuisance.light_strength  # its video's light strength,
        extras["light_dir"] = torch.tensor(draw.nuisance.light_dir, dtype=torch.float64)  # direction
        obj_normals = smooth_normals(nrm, cov, nz.normal_smoothing_px)  # and (smooth) normals
    obj_names = (() if not nz.shading_is_model else ("material",)) + ("motion_blur",) + tuple(object_effects)
    theta = CaptureParams(values, effects=PAPER_EFFECTS + tuple(object_effects), validate=False).to(torch.float64)
    paint = nz.paint_rgb if shot.shape[1] == 3 else np.ones(1)
    neutral = bool(np.all(paint == 1.0))
    colour0 = _object_radiance(nz, draw, cov, nrm, side)
    frame_lin = shot.clone()
    for c in range(shot.shape[1]):  # the same layers over each channel's background; the paint's albedo per channel
        col, th = colour0, theta
        if not neutral and nz.shading_is_model:  # the model's material shades w_d: the paint is its channel's w_d
            th = CaptureParams({**values, "w_d": paper["w_d"] * float(paint[c])}, effects=theta.effects,
                               validate=False).to(torch.float64)
        elif not neutral:
            col = _object_radiance(nz, draw, cov, nrm, side, float(paint[c]))
        state = RenderState(object_color=col, coverage=cov, normals=obj_normals, background=bg_crop[:, c:c + 1],
                            extras=extras, fields={"noise": draw.object_noise})
        state = apply_effects(state, th, obj_names, clamp=False)
        if "interlacing" in cam:
            col, cv = _interlace(state.object_color, state.coverage, cam["interlacing"]["interlace_shift"],
                                 paper["alpha_m"])
            state = state.replace(object_color=col, coverage=cv)
        state = apply_effects(state, theta, ("boundary_blur", "object_noise"), clamp=False)
        frame_lin[:, c:c + 1, y0:y0 + side, x0:x0 + side] = state.image
    return frame_lin


def _capture_frames(setup: _Setup, draw: MeasuredSeed, frame_lin: torch.Tensor, scene: np.ndarray,
                    tint: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None]:
    """The whole-frame camera on the frame and on the object-free background frame B (its noise reduced by
    ``background_noise_factor``): 8-bit (frame, B) in gray, and their RGB captures (or None) with ``colour``
    (the gray images are then the capture's luma)."""
    cam = draw.camera
    frame_u8 = to_u8(capture(frame_lin, cam, draw.frame_noise, 1.0, setup.read_noise, tint=tint), cam)
    bg_u8 = to_u8(capture(_batched(scene), cam, draw.background_noise, setup.background_noise_factor,
                           setup.read_noise, tint=tint), cam)
    if not setup.colour:
        return frame_u8, bg_u8, None, None
    import cv2

    return (cv2.cvtColor(frame_u8, cv2.COLOR_RGB2GRAY), cv2.cvtColor(bg_u8, cv2.COLOR_RGB2GRAY), frame_u8, bg_u8)


# ------------------------------------------------------------------ per seed: crop and truth
@dataclass(frozen=True)
class _SeedOutput:
    """What one seed adds to the seed set (the arguments of :func:`~synthaug.data.seedset.write_seedset`)."""

    patch: np.ndarray
    background: np.ndarray
    box: np.ndarray
    crop: Any
    frame: np.ndarray
    background_frame: np.ndarray
    patch_rgb: np.ndarray | None
    background_rgb: np.ndarray | None
    record: dict[str, Any]
    truth_row: dict[str, Any]
    truth_extra: dict[str, Any]


def _crop_seed(setup: _Setup, draw: MeasuredSeed, cache: Any, box: np.ndarray, side: float, frame_scale: float,
               captured: tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None]) -> _SeedOutput:
    """Object and background patches around ``box``, and the seed's truth (Θ in patch units)."""
    from synthaug.data.seedset import crop_patch

    frame_u8, bg_u8, frame_rgb, bg_rgb = captured
    p = setup.patch_size
    patch, crop = crop_patch(frame_u8, box=box, patch_size=p, object_fraction=setup.object_fraction)
    rgb = (None, None) if frame_rgb is None else \
        (crop_patch(frame_rgb, crop=crop, patch_size=p)[0], crop_patch(bg_rgb, crop=crop, patch_size=p)[0])
    cx, cy = float(crop[0]), float(crop[1])
    origin = [cx - side / 2, cy - side / 2]
    s = setup.crop_side
    render_c = (draw.corner[0] + (s - 1) / 2.0, draw.corner[1] + (s - 1) / 2.0)
    alpha, beta, gamma = draw.pose
    g_alpha, g_beta = (float(v) for v in cache.grid_pose(torch.tensor([alpha]), torch.tensor([beta])))
    theta_patch = {"alpha": g_alpha, "beta": g_beta, "gamma": gamma,
                   "t_x": (render_c[0] - cx) / side, "t_y": (render_c[1] - cy) / side,
                   **{k: draw.paper[k] for k in _PAPER_NAMES}}
    hidden_model = _model_units(draw.camera, frame_scale)
    w_f, h_f = setup.frame_hw[1], setup.frame_hw[0]
    truth = {"theta": theta_patch, "hidden": draw.camera, "hidden_model": hidden_model, "object_px": draw.size_px,
             "object_scale": draw.size_px / side, "render_centre": list(render_c), "origin": origin,
             "frame_scale": frame_scale, "alpha_requested": alpha, "beta_requested": beta,
             "sigma_frame": _frame_sigmas(draw.paper, frame_scale),
             **({} if setup.nuisances.is_none() else {"nuisance": draw.nuisance.as_dict()})}
    return _SeedOutput(
        patch=patch, background=crop_patch(bg_u8, crop=crop, patch_size=p)[0], box=box, crop=crop,
        frame=frame_u8, background_frame=bg_u8, patch_rgb=rgb[0], background_rgb=rgb[1],
        record={"video": f"refcam{draw.video:02d}", "frame": draw.index // setup.n_videos, "class": "drone",
                "background_method": "reference_camera", "background_quality": 1.0, "split": "train",
                "truth": truth},
        truth_row={**theta_patch, **{k: v for e in hidden_model.values() for k, v in e.items()}},
        truth_extra={"object_scale": draw.size_px / side, "origin": origin, "frame_size": [w_f, h_f],
                     "frame_scale": frame_scale})


def _simulate_seed(setup: _Setup, draw: MeasuredSeed, scene: np.ndarray, tint: np.ndarray | None, cache: Any,
                   body_cache: Any | None) -> _SeedOutput:
    """One seed through the reference camera: render, object physics, capture, crop."""
    cov, nrm, rotor = _render_layers(draw, cache, body_cache, setup.crop_side)
    box = _annotated_box(setup, draw, cov)
    side = max(box[2], box[3]) / setup.object_fraction
    frame_scale = side / setup.patch_size
    frame_lin = _object_on_frame(setup, draw, scene, cov, nrm, rotor, frame_scale)
    captured = _capture_frames(setup, draw, frame_lin, scene, tint)
    return _crop_seed(setup, draw, cache, box, side, frame_scale, captured)


def _header(setup: _Setup, mesh_desc: str) -> dict[str, Any]:
    """The seed set's metadata: its geometry and the ``reference_camera`` block (the truth of the case)."""
    (h_f, w_f), settings, nz = setup.frame_hw, setup.settings, setup.nuisances
    return {
        "patch_size": setup.patch_size, "object_fraction": setup.object_fraction, "frame_size": [w_f, h_f],
        "source": {"generator": _FORMAT, "version": _VERSION},
        "reference_camera": {
            "format": _FORMAT, "version": _VERSION, "hidden": settings, "mesh": mesh_desc,
            "mesh_perturbation": setup.mesh_perturbation, "seed": setup.seed, "read_noise": setup.read_noise,
            "background_noise_factor": setup.background_noise_factor, "paper_ranges": setup.ranges,
            "object_px": list(setup.object_px), "view_step_deg": setup.view_step_deg,
            "sprite_size": setup.sprite_size, "per_video": list(setup.per_video), "n_videos": setup.n_videos,
            "colour": bool(setup.colour),
            "whole_frame": [e for e in settings if e in WHOLE_FRAME_EFFECTS],
            "object_only": [e for e in settings if e in OBJECT_ONLY_EFFECTS],
            "truth_file": "truth.json",
            **({} if nz.is_none() else {"nuisances": nz.as_dict()}),
        },
    }


def _write(out_dir: str | os.PathLike, setup: _Setup, mesh_desc: str, seeds: list[_SeedOutput]) -> Path:
    """The seed set (:func:`~synthaug.data.seedset.write_seedset`) with ``truth.json`` beside."""
    from synthaug.data.seedset import write_seedset

    nz = setup.nuisances
    truth_bytes = _truth_file([s.truth_row for s in seeds], [s.truth_extra for s in seeds],
                              tuple(e for e in setup.settings if e in CAMERA_EFFECTS),
                              None if nz.is_none() else nz.as_dict())
    rgb = setup.colour
    return write_seedset(out_dir, patches=np.stack([s.patch for s in seeds]),
                         backgrounds=np.stack([s.background for s in seeds]), boxes=[s.box for s in seeds],
                         centres=[[s.box[0] + s.box[2] / 2, s.box[1] + s.box[3] / 2] for s in seeds],
                         crops=[s.crop for s in seeds], records=[s.record for s in seeds],
                         frames=[s.frame for s in seeds], background_frames=[s.background_frame for s in seeds],
                         metadata=_header(setup, mesh_desc), extra_files={"truth.json": truth_bytes},
                         patches_rgb=np.stack([s.patch_rgb for s in seeds]) if rgb else None,
                         backgrounds_rgb=np.stack([s.background_rgb for s in seeds]) if rgb else None)


# ------------------------------------------------------------------ main
def make_measured_seedset(
    out_dir: str | os.PathLike,
    *,
    n_seeds: int = 50,
    hidden: Mapping[str, Mapping[str, Strength]] | Sequence[str] | None = None,
    mesh: Any = "quadcopter",
    mesh_perturbation: float = 0.0,
    frame_size: tuple[int, int] = (256, 320),
    patch_size: int = 40,
    object_fraction: float = 0.7,
    object_px: tuple[float, float] = (22.0, 40.0),
    seed: int = 0,
    backgrounds: Sequence[np.ndarray] | None = None,
    paper_ranges: Mapping[str, tuple[float, float]] | None = None,
    read_noise: float = 0.004,
    background_noise_factor: float = 0.35,
    n_videos: int = 5,
    per_video: Sequence[str] = ("w_d",),
    view_step_deg: float = 10.0,
    sprite_size: int = 64,
    colour: bool = False,
    nuisances: "Nuisances | None" = None,
) -> Path:
    """Write a measured seed set through the reference camera (see the module docstring).

    Args:
        out_dir: the seed-set folder (replaced if it exists).
        n_seeds: number of seeds.
        hidden: camera effects switched on, ``{name: {param: value or (low, high)}}``
            or a list of names (realistic defaults: :data:`REALISTIC_STRENGTHS`);
            names from :data:`~synthaug.effects.camera.CAMERA_EFFECTS` or
            :data:`OUTSIDE_EFFECTS`. A value is the camera's (every seed), a
            pair is drawn per seed. ``rolling_shutter`` takes ``rs_magnitude``
            (px per row, along each seed's motion direction α_m) or explicit
            ``rs_skew``/``rs_stretch``.
        mesh: the REAL object: ``"quadcopter"`` (with true rotor parts), a path
            or a trimesh.
        mesh_perturbation: smooth deformation of the real mesh (fraction of its
            size, :func:`perturb_mesh`), so it differs from the fit's coarse model.
        frame_size: (H, W) of the frames.
        patch_size, object_fraction: seed-set patch geometry.
        object_px: (min, max) object size (mesh unit length) in frame pixels.
        seed: everything is a pure function of this seed.
        backgrounds: scene frames (uint8 or float in [0, 1], (H, W)), cycled;
            default: procedural skies.
        paper_ranges: overrides of :data:`PAPER_RANGES` (patch units).
        read_noise: std of the whole-frame sensor noise (intensity).
        background_noise_factor: the background frame's noise relative to the
            frame's (an aligned median of ~9 frames: about 0.35).
        n_videos: seeds are spread over this many "videos" (record ``video``).
        per_video: paper parameters drawn once per video rather than per seed.
            Default ``("w_d",)``: the diffuse weight is the object's paint under
            the scene's light, the same for every frame of a video (the
            orientation's shading is rendered); a camera effect that w_d
            absorbs then shows *within* a video.
        view_step_deg, sprite_size: the view cache of the real mesh.
        colour: capture in RGB (a bluish sky per seed, a neutral grey object unless the nuisances paint it,
            :attr:`Nuisances.paint_rgb`; the camera acts per
            channel: chromatic aberration displaces red and blue in opposite directions, white
            balance ``wb_gain`` g multiplies red by g and blue by 1/g, haze's airlight has the
            sky's colour). The seed set's patches and
            frames are then the Rec. 601 luma of the RGB capture, and ``colour.npz`` holds the RGB
            patches (``patches_rgb``, ``backgrounds_rgb``: (N, P, P, 3) uint8).
        nuisances: variation that is not a camera effect (:class:`~synthaug.diagnose.nuisances.Nuisances`:
            material and shading, each video's light, the real mesh, a scene that moves between the frame and
            its background), e.g. ``Nuisances.draw(np.random.default_rng(k))``. None or
            ``Nuisances.none()``: the fit's own model (the same bytes as before nuisances existed). Per-seed
            values come from :meth:`~synthaug.diagnose.nuisances.Nuisances.draw_seed`; the header's
            ``reference_camera.nuisances``, each record's ``truth.nuisance`` and ``truth.json``'s metadata
            store them. The camera's noise and the scene's Θ draws are unchanged by them.

    Returns:
        the seed-set folder.
    """
    from synthaug.render.cache import ViewCache

    setup = _setup(n_seeds=n_seeds, hidden=hidden, mesh=mesh, mesh_perturbation=mesh_perturbation,
                   frame_size=frame_size, patch_size=patch_size, object_fraction=object_fraction, object_px=object_px,
                   seed=seed, paper_ranges=paper_ranges, read_noise=read_noise,
                   background_noise_factor=background_noise_factor, n_videos=n_videos, per_video=per_video,
                   view_step_deg=view_step_deg, sprite_size=sprite_size, colour=colour, nuisances=nuisances)
    nz = setup.nuisances
    full_mesh, body_mesh, mesh_desc = real_object(mesh, setup.mesh_perturbation, seed, rotor_scale=nz.rotor_scale,
                                                  sections=nz.mesh_sections)
    cache = ViewCache.build(full_mesh, step_deg=view_step_deg, sprite_size=sprite_size)
    body_cache = None if body_mesh is None else ViewCache.build(body_mesh, step_deg=view_step_deg,
                                                                 sprite_size=sprite_size)
    scenes, tints = _scenes(setup, backgrounds)
    seeds = [_simulate_seed(setup, _draw_seed(setup, i, scenes[i]), scenes[i], tints[i], cache, body_cache)
             for i in range(n_seeds)]
    return _write(out_dir, setup, mesh_desc, seeds)
