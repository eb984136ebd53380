"""SyntheticObjectDataset: lazily rendered synthetic samples, mixed with real ones.

Each synthetic item takes one seed's capture parameters and background and a
random pose (the paper: keep the capture parameters, randomise the pose), and
is rendered on demand in the DataLoader worker that asks for it. The real part
is any map-style dataset of the user's; items ``0 .. len(real)-1`` are the real
ones, the rest synthetic, so a shuffling sampler mixes them at the chosen
``synthetic_per_real`` ratio.

Every item is a pure function of ``(seed, epoch, index)``: the same bytes with
any ``num_workers`` and across runs. Drawing and rendering are two steps, as
torchvision's ``make_params`` / ``transform``:
:meth:`SyntheticObjectDataset.make_params` draws an item's random choices into a
frozen :class:`ItemParams` (seed, pose, crop, noise fields, capture parameters)
and :meth:`SyntheticObjectDataset.render` turns params into items without
drawing (``render(make_params(i))`` is ``ds[i]``). The pose comes from a pose
sampler (:mod:`synthaug.data.poses`); real items from
:mod:`synthaug.data.mixing`. New poses every epoch, the PyTorch way: an
:class:`~synthaug.data.epochs.EpochSampler` yields ``(epoch, index)`` pairs, so the epoch reaches the
DataLoader workers even when they are persistent (or under a
``DistributedSampler``, which it wraps); Lightning calls its ``set_epoch``.
:meth:`set_epoch` on the dataset itself still works for plain integer indices
when workers are not persistent. The dataset implements ``__getitems__``, so a
DataLoader builds a whole batch in one vectorised call (the speed comes from
there).

Items are ``(image, target)``:

- patch mode: image (C, P, P) float32 in [0, 1]; target ``{"labels": int64 ()
  1 object / 0 background, "synthetic": bool (), "seed_index": int64 (),
  "theta": float32 (len Θ,)}`` (real items get ``seed_index = -1`` and a NaN
  Θ so that the default collate works on mixed batches);
- frame mode: image ``tv_tensors.Image`` (C, H, W); target ``{"boxes":
  tv_tensors.BoundingBoxes (N, 4) float32 XYXY with canvas_size (H, W),
  "labels": int64 (N,), ...}`` as torchvision's detection models and
  ``transforms.v2`` expect (a flip or crop moves the boxes with the image).
  Use :func:`collate_detection` as ``collate_fn``.

Real items come out in the same format as synthetic ones whatever the user's
dataset returns (uint8 or float arrays, (H, W), (H, W, C) or (C, H, W), an int
label or a target dict), and ``transforms`` (any callable on ``(image,
target)``, e.g. a ``transforms.v2.Compose``) is applied to both alike, with
its random draws seeded from ``(seed, epoch, index)``.

Example:
    >>> import numpy as np, torch
    >>> bg = np.full((40, 40), 128, np.uint8)
    >>> ds = SyntheticObjectDataset("quadcopter", [bg], length=4, render={"step_deg": 30, "sprite_size": 32})  # doctest: +SKIP
    >>> img, target = ds[0]  # doctest: +SKIP
"""

from __future__ import annotations

import math
import numbers
import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, Literal, overload

import numpy as np
import torch
from torch.utils.data import Dataset
from torchvision import tv_tensors

from synthaug._checks import one_of
from synthaug._procs import guard_loader_worker
from synthaug.data.captures import CAPTURE_SAMPLERS, CaptureSampler
from synthaug.data.dataset_args import check_arguments, is_integral, legacy_arguments, render_backend
from synthaug.data.epochs import EpochSampler, item_generator, item_seed
from synthaug.data.items import BACKGROUND_SAMPLING, ItemParams
from synthaug.data.mixing import RealItems, mixed_counts, to_float_image
from synthaug.data.poses import POSE_SAMPLING, FittedPose, PoseSampler, SeedOffset, pose_sampler
from synthaug.effects.pipeline import simulate
from synthaug.effects.registry import ordered
from synthaug.params import POSE_NAMES, POSE_SPECS, CaptureParams, fitted_object_scales

__all__ = ["SyntheticObjectDataset", "ItemParams", "EpochSampler", "collate_detection", "item_generator"]

Mode = Literal["patch", "frame"]


def collate_detection(batch: Sequence[tuple[Any, Any]]) -> tuple[tuple[Any, ...], tuple[Any, ...]]:
    """Detection collate: ``(images, targets)`` as tuples (torchvision convention)."""
    images, targets = zip(*batch)
    return images, targets


class SyntheticObjectDataset(Dataset):
    """Synthetic object samples (the paper's generator), optionally mixed with real ones.

    Args:
        mesh: mesh path, built-in name (``"quadcopter"``) or trimesh.
        backgrounds: one background per seed: a sequence of images ((H, W) /
            (H, W, C) uint8 or float in [0, 1], (C, H, W) tensors, or paths), or a
            seed set (anything with ``.backgrounds`` patches and
            ``.background_frame(i)``, as :class:`synthaug.data.seedset.SeedSet`).
            Patch mode crops a random patch from larger backgrounds.
        params: capture parameters, one row per seed: a
            :class:`~synthaug.params.CaptureParams`, a path to a file written by
            ``CaptureParams.save`` (e.g. ``synthaug fit``'s output), or None to
            sample one row per seed from the default ranges (with ``seed``).
            Only the capture parameters are used; poses are drawn per item.
        real: a map-style dataset of real samples to mix in (items ``(image,
            label_or_target)``), or None.
        synthetic_per_real: synthetic items per real item when ``real`` is given.
        length: number of synthetic items when ``real`` is None.
        mode: ``"patch"`` (fixed-size patches, labels 1/0) or ``"frame"`` (object
            composited into a whole background frame, box target).
        patch_size: side of patches in patch mode (the paper: 40).
        object_scale: mesh unit length (its longest side) as a fraction of the
            patch side. None: the per-seed scales of a fit file written with
            ``fit_scale`` (``synthaug fit``'s default), else 0.7 (the seed
            sets' default ``object_fraction``).
        object_box: patch mode: frame every synthetic object the way ``synthaug ingest`` frames a labelled
            real seed (:func:`synthaug.data.seedset.crop_patch`): the box of its coverage (≥ 0.5, before the
            capture effects) centred in the patch and its longest side ``object_box × patch_size`` pixels,
            whatever the drawn pose — a float in (0, 1], ``"seed"`` for the seed set's own
            ``object_fraction`` (``backgrounds`` must then be a seed set), or ``"fit"`` for the median size of the
            fitted renders' own boxes in their patches (the labelled box less the annotators' margin, as the fit
            measures it; ``params`` must be a fit with per-seed scales). The drawn t_x, t_y and the
            object scale then only set the first look the box is measured on. None (default, the paper):
            the mesh's unit length at ``object_scale`` and the drawn translation, so an edge-on view is a
            smaller object than a view from above. Measured: ``"seed"`` +0.05 to +0.07 AP@0.5 on ``synthaug demo``'s
            generated videos, whose labels are tight (``results/synthetic/demo_box/README.md``); on the real drone
            videos, whose labels are loose, ``"seed"`` loses and ``"fit"`` is level with None
            (``results/synthetic/drone_box/README.md``).
        object_box_share: the fraction of the synthetic objects that ``object_box`` frames (1, default: every one);
            the others keep the paper's framing (the mesh's scale and the drawn translation), a mixture of the two
            object-size distributions. Which items are framed is drawn per item, last, from its own generator (and
            only when the share is under 1, so no other draw moves).
        negative_fraction: patch mode: fraction of synthetic items that are
            background-only patches (label 0); frame mode: fraction of frames
            without an object.
        object_size: frame mode: (min, max) object size in pixels (mesh unit length).
        effects: effects to apply (default: all of ``params``' effects); leaving
            one out is the paper's ablation. For a CNN detector trained from a d_HOG fit, the
            fitted blurs left out measured better on the drone videos (``synthaug train``'s
            default for the CNN, :data:`~synthaug.detectors.video_training.FAMILY_EFFECTS_OFF`).
        channels: 1 (grayscale, default) or 3 (the paper's RGB extension, with
            per-channel capture parameters).
        seed: base seed; an item is a pure function of (seed, epoch, index).
        label: class id of the object (frame mode ``labels``; patch positives).
        render: the renderer: ``"cache"`` (default: views pre-rendered once, posed in torch, fast; the
            :class:`~synthaug.render.cache.ViewCache` is built now), a mapping of
            :meth:`ViewCache.build <synthaug.render.cache.ViewCache.build>` options (e.g. ``{"step_deg": 30,
            "sprite_size": 32}``), a prebuilt ``ViewCache`` (shared between datasets), or ``"exact"`` (one GL
            render per item in a private subprocess, slow).
        capture_sampling: ``"seed"`` (the paper: each item keeps one seed's
            capture parameters), ``"kde"`` (drawn from a kernel density over all
            seeds: combinations no seed had) or ``"uniform"`` (each parameter
            uniform between its min and max over the seeds: the paper's Fig. 10
            baseline): :class:`~synthaug.data.captures.SeedCapture`,
            :class:`~synthaug.data.captures.KDECapture`,
            :class:`~synthaug.data.captures.UniformCapture`; or a capture sampler of
            your own (:class:`~synthaug.data.captures.CaptureSampler`). The
            background always comes from one seed (see ``background_sampling``).
        pose_sampling: ``"uniform"`` (default, :class:`~synthaug.data.poses.UniformPose`: α, β, γ
            uniform over their sampling ranges, every view equally likely), ``"fitted"``
            (:class:`~synthaug.data.poses.FittedPose`: each item's rotation is its seed's *fitted*
            rotation composed with a random rotation of axis uniform on the sphere and angle
            ~ N(0, 20°) per axis component: the views the real seeds show, and views near them; needs
            ``params`` from a fit; t_x, t_y are drawn as with ``"uniform"``), ``"uniform_at_seed"`` /
            ``"fitted_at_seed"`` (the same rotations, with the object at its seed's fitted offset t_x, t_y, over
            the place its background was inpainted: :class:`~synthaug.data.poses.SeedOffset`; needs ``params``),
            or a pose sampler object:
            ``UniformPose(ranges)`` / ``FittedPose(params, jitter_deg, ranges)`` for other ranges or spread,
            or any object with ``sample(generator, seed_index, u) -> {"alpha", "beta", "gamma", "t_x", "t_y"}``
            (:class:`~synthaug.data.poses.PoseSampler`). ``synthaug train`` draws AdaBoost's synthetic positives at
            ``"fitted_at_seed"`` with ``shape_variation=0.3``, 8-bit, by default
            (:data:`~synthaug.detectors.video_training.FAMILY_SYNTHETIC`); this dataset keeps the paper's.
        seed_geometry: patch mode: where each seed's background patch sits in its
            frame, ``{"origin": (N, 2), "frame_size": (N, 2), "frame_scale": (N,)}``
            as :func:`synthaug.data.seedset.seed_geometry` returns it, passed to
            the position-aware camera effects (vignetting, chromatic aberration,
            lens distortion, the JPEG block grid). ``"auto"`` (default): the seed
            set's own when ``backgrounds`` is a seed set, else None; None: the
            patch is taken as the frame. The paper's four effects do not read it.
        shape_variation: domain randomisation of the silhouette (0, default: the paper, the mesh alone). > 0:
            each synthetic item draws one of ``shape_variants`` shapes made from the mesh by
            :func:`~synthaug.render.mesh.shape_variants` (the mesh itself, and variations with its axes stretched
            and every part, e.g. an arm, a rotor, a wing, scaled about its own centre, each factor log-uniform
            within ``±shape_variation``, drawn from ``seed``): arm length, rotor size and body proportions
            around a coarse model. The fitted capture parameters and object scale are used as they are.
        shape_variants: how many shapes ``shape_variation`` makes (>= 2; the first is the mesh itself); each is
            rendered into its own view cache once.
        background_sampling: ``"seed"`` (the paper: each object on its own seed's background, the one its capture
            parameters were fitted on) or ``"other"`` (each on the background of another seed, drawn uniformly; the
            capture parameters stay the item's seed's: the background factor of the synthetic distribution, issue
            16). The background's place in its frame then serves the position-aware effects. Needs 2 seeds.
            ``synthaug train``'s default for the CNN (measured better on the drone videos,
            :data:`~synthaug.detectors.video_training.FAMILY_BACKGROUND_SAMPLING`); this dataset keeps the paper's.
        realism_critic: patch mode: a realism critic, ``critic(patches, seed_index) -> logits`` ((M, C, P, P) float
            in [0, 1] and (M,) int in, (M,) "looks synthetic" scores out, higher: more synthetic), e.g. a
            :class:`~synthaug.detectors.critic.RealismCritic` fitted on the seed set's real patches and draws of
            this dataset without a critic (:meth:`RealismCritic.from_dataset
            <synthaug.detectors.critic.RealismCritic.from_dataset>`). Each synthetic object item then renders
            ``realism_candidates`` draws that keep its seed (capture parameters and background) and differ in
            everything else (pose, crop, noise fields, shape), and keeps the one the critic finds least synthetic
            (discriminator rejection sampling, per item: the lazy form of ``synthaug train``'s
            ``--realism-selection item``). Negative items are not scored. None (default): every draw, the paper.
            A picklable critic travels to DataLoader workers with the dataset.
        realism_candidates: draws per item with a ``realism_critic`` (>= 2; 4 keeps one in four, as
            ``synthaug train``'s ``--realism-keep 0.25``). The first candidate is the draw the item has without a
            critic.
        transforms: a callable ``(image, target) -> (image, target)`` applied to
            every item, real and synthetic alike, as torchvision datasets take
            one (e.g. ``transforms.v2.Compose([...])``: frame-mode boxes are
            ``tv_tensors.BoundingBoxes`` and move with the image). Its random
            draws (torch's global generator) are seeded per item from
            ``(seed, epoch, index)``, so items stay reproducible.

    The former arguments ``cache``, ``cache_options`` (now ``render``), ``pose_ranges`` and ``pose_jitter_deg``
    (now a ``pose_sampling`` object) are still accepted for one release, with a FutureWarning.
    """

    def __init__(
        self,
        mesh: Any,
        backgrounds: Any,
        params: CaptureParams | str | os.PathLike | None = None,
        *,
        real: Dataset | None = None,
        synthetic_per_real: float = 50,
        length: int | None = None,
        mode: Mode = "patch",
        patch_size: int = 40,
        object_scale: float | None = None,
        object_box: float | Literal["seed", "fit"] | None = None,
        object_box_share: float = 1.0,
        negative_fraction: float | None = None,
        object_size: tuple[float, float] = (20.0, 60.0),
        effects: Sequence[str] | None = None,
        channels: int = 1,
        seed: int = 0,
        label: int = 1,
        render: Literal["cache", "exact"] | Mapping[str, Any] | Any = "cache",
        capture_sampling: Literal["seed", "kde", "uniform"] | CaptureSampler = "seed",
        pose_sampling: Literal["uniform", "fitted", "uniform_at_seed", "fitted_at_seed"] | PoseSampler = "uniform",
        seed_geometry: Mapping[str, Any] | Literal["auto"] | None = "auto",
        shape_variation: float = 0.0,
        shape_variants: int = 8,
        background_sampling: Literal["seed", "other"] = "seed",
        realism_critic: Callable[[torch.Tensor, torch.Tensor], Any] | None = None,
        realism_candidates: int = 4,
        transforms: Any = None,
        **deprecated: Any,
    ) -> None:
        super().__init__()
        render, pose_sampling = legacy_arguments(deprecated, render=render, pose_sampling=pose_sampling,
                                                  params=params)
        backend = render_backend(render)
        neg = check_arguments(transforms=transforms, mode=mode, channels=channels, patch_size=patch_size,
                               synthetic_per_real=synthetic_per_real, length=length, real=real,
                               object_scale=object_scale, negative_fraction=negative_fraction, object_size=object_size,
                               shape_variation=shape_variation, shape_variants=shape_variants)
        self.transforms = transforms
        self.mode: Mode = mode
        self.channels = channels
        self.patch_size = int(patch_size)
        self.object_scale = 0.7 if object_scale is None else float(object_scale)
        self.seed_scales: torch.Tensor | None = None
        self.object_box = _check_object_box(object_box, backgrounds, mode)
        self.object_box_share = check_object_box_share(object_box_share, self.object_box)
        self.negative_fraction = neg
        self.object_size = (float(object_size[0]), float(object_size[1]))
        self.seed = int(seed)
        self.epoch = 0
        self.label = int(label)
        self.backend = backend  # "cache" / "exact" (the name render is the method)
        self._set_up_capture(backgrounds, params, effects=effects, object_scale=object_scale,
                             capture_sampling=capture_sampling, seed_geometry=seed_geometry)
        self.background_sampling = _check_background_sampling(background_sampling, len(self.backgrounds))
        self.realism_candidates = _check_realism_candidates(realism_candidates)
        self.realism_critic = realism_critic
        # after the capture set-up: "fitted" reads the fit's rotations (given, never the sampled rows)
        self._set_up_pose(pose_sampling, fitted=params is not None)
        # real items first, then the synthetic ones (synthaug.data.mixing says why the layout lives here)
        self.real = real
        self.n_real, self.n_synthetic = mixed_counts(real, synthetic_per_real, length)
        theta_size = len(CaptureParams.vector_names(channels=self.channels, effects=self.params.effects))
        self._real_items = None if real is None else RealItems(
            real, mode=self.mode, channels=self.channels, patch_size=self.patch_size, label=self.label,
            theta_size=theta_size)
        self._set_up_renderer(mesh, render, shape_variation=shape_variation, shape_variants=shape_variants)
        if self.object_box == "fit":
            if params is None or self.seed_scales is None:
                raise ValueError("object_box='fit' reads each seed's fitted pose and object scale: give params from a "
                                 "fit with per-seed scales (synthaug fit's default)")
            self.object_box = self._fitted_box_fraction()

    @property
    def realism_critic(self) -> Callable[[torch.Tensor, torch.Tensor], Any] | None:
        """The realism critic (see the class's ``realism_critic``); settable, e.g. to a
        :meth:`RealismCritic.from_dataset <synthaug.detectors.critic.RealismCritic.from_dataset>` of this dataset
        (checked as the argument is)."""
        return self._realism_critic

    @realism_critic.setter
    def realism_critic(self, critic: Callable[[torch.Tensor, torch.Tensor], Any] | None) -> None:
        self._realism_critic = _check_realism_critic(critic, self.mode, len(self.backgrounds))

    # ----------------------------------------------------------- set-up
    def _set_up_capture(self, backgrounds: Any, params: CaptureParams | str | os.PathLike | None, *,
                        effects: Sequence[str] | None, object_scale: float | None, capture_sampling: Any,
                        seed_geometry: Mapping[str, Any] | str | None) -> None:
        """One background and one row of capture parameters per seed, the effects, and how items draw them."""
        self.backgrounds = self._load_backgrounds(backgrounds)
        n_seeds = len(self.backgrounds)
        if n_seeds == 0:
            raise ValueError("backgrounds is empty: give at least one background image")
        self.params, scales = self._load_params(params, n_seeds)
        if object_scale is None and scales is not None:
            self.seed_scales = scales
        if self.params is None:  # "for now sampled": one row per seed from the default ranges
            g = torch.Generator().manual_seed(self.seed)
            self.params = CaptureParams.sample(n_seeds, generator=g, channels=self.channels)
        self.effects = tuple(self.params.effects if effects is None else effects)
        missing = [e for e in self.effects if e not in self.params.effects]
        if missing:
            raise ValueError(f"effects {missing} have no parameters in params (which has {list(self.params.effects)})")
        self._validate_sizes()
        if isinstance(capture_sampling, str):
            one_of(capture_sampling, CAPTURE_SAMPLERS, "capture_sampling", alternatives=" or a capture sampler")
        elif not isinstance(capture_sampling, CaptureSampler):
            raise ValueError(f"capture_sampling must be 'seed', 'kde', 'uniform' or a capture sampler (an object with "
                             f"sample(generator, seed_index) and rows(seed_indices, captures)), got {capture_sampling!r}")
        self.capture_sampling = capture_sampling
        if isinstance(seed_geometry, str):
            if seed_geometry != "auto":
                raise ValueError(f"seed_geometry must be a mapping, 'auto' or None, got {seed_geometry!r}")
            is_seedset = hasattr(backgrounds, "crops") and hasattr(backgrounds, "metadata")
            seed_geometry = None
            if is_seedset and self.mode == "patch":
                from synthaug.data.seedset import seed_geometry as _geometry

                seed_geometry = _geometry(backgrounds)
        self.seed_geometry = None if seed_geometry is None else self._check_geometry(seed_geometry, n_seeds)
        self.capture_sampler: CaptureSampler = (CAPTURE_SAMPLERS[capture_sampling](self.params)
                                                if isinstance(capture_sampling, str) else capture_sampling)
        self._random_effects = [e for e in ordered(list(self.effects)) if e.is_random]

    def _set_up_pose(self, pose_sampling: Any, *, fitted: bool) -> None:
        """The pose sampler: a :data:`~synthaug.data.poses.POSE_SAMPLING` name built here, or the user's own object."""
        if isinstance(pose_sampling, str):
            self.pose_sampler: PoseSampler = pose_sampler(pose_sampling, self.params if fitted else None)
        elif callable(getattr(pose_sampling, "sample", None)):
            self.pose_sampler = pose_sampling
        else:
            raise ValueError(f"pose_sampling must be one of {', '.join(map(repr, POSE_SAMPLING))} or a pose sampler "
                             f"(an object with sample(generator, seed_index, u)), got {type(pose_sampling).__name__}")
        if isinstance(self.pose_sampler, FittedPose) and len(self.pose_sampler.rotations) != len(self.backgrounds):
            raise ValueError(f"the FittedPose holds {len(self.pose_sampler.rotations)} rotations but there are "
                             f"{len(self.backgrounds)} seeds (one fitted rotation per seed)")
        if isinstance(self.pose_sampler, SeedOffset):
            if len(self.pose_sampler) != len(self.backgrounds):
                raise ValueError(f"the SeedOffset holds {len(self.pose_sampler)} offsets but there are "
                                 f"{len(self.backgrounds)} seeds (one fitted offset per seed)")
            if self.mode != "patch" or self.object_box is not None:
                raise ValueError("a seed's offset (pose_sampling '..._at_seed', SeedOffset) places the object on its "
                                 "seed's background patch: patch mode without object_box (which sets t_x, t_y itself)")

    def _set_up_renderer(self, mesh: Any, render: Any, *, shape_variation: float, shape_variants: int) -> None:
        """The view cache (given, or built now with the options ``render`` maps) or the exact renderer (its GL
        subprocess starts lazily); one per shape with ``shape_variation`` (checked by ``check_arguments``)."""
        self.shape_variation = float(shape_variation)
        meshes = [mesh]
        if self.shape_variation > 0:
            if self.backend == "cache" and not isinstance(render, (str, Mapping)):
                raise ValueError("shape_variation renders every shape into its own view cache: give render as "
                                 "'cache' or a mapping of cache options, not a prebuilt ViewCache")
            from synthaug.render.mesh import shape_variants as make_variants

            meshes = make_variants(mesh, int(shape_variants), strength=self.shape_variation, seed=self.seed)
        self._mesh = mesh
        self._caches: list[Any] = []
        self._renderers: list[Any] = []
        if self.backend == "cache":
            if isinstance(render, (str, Mapping)):
                # built here (in the main process, through a GL subprocess), memory-mapped by workers
                from synthaug.render.cache import ViewCache

                opts = {"sprite_size": 96 if self.mode == "patch" else 128,
                        **({} if isinstance(render, str) else dict(render))}
                self._caches = [ViewCache.build(m, **opts) for m in meshes]
            else:
                self._caches = [render]  # a prebuilt ViewCache
        else:
            from synthaug.render.server import Renderer

            self._renderers = [Renderer(m) for m in meshes]  # each starts its GL subprocess lazily, per process

    @property
    def n_shapes(self) -> int:
        """How many shapes the synthetic objects are drawn from (1 without ``shape_variation``)."""
        return max(len(self._caches), len(self._renderers))

    # ----------------------------------------------------------- set-up
    def _load_backgrounds(self, backgrounds: Any) -> list[torch.Tensor]:
        if hasattr(backgrounds, "background_frame") and hasattr(backgrounds, "backgrounds"):
            if self.mode == "patch":
                items = list(np.asarray(backgrounds.backgrounds))
            else:
                items = [backgrounds.background_frame(i) for i in range(len(backgrounds))]
        elif isinstance(backgrounds, np.ndarray) and backgrounds.ndim in (3, 4) and backgrounds.dtype != object:
            items = list(backgrounds)
        elif isinstance(backgrounds, torch.Tensor) and backgrounds.ndim == 4:
            items = list(backgrounds)
        elif isinstance(backgrounds, (str, os.PathLike)):
            raise ValueError(f"backgrounds must be a sequence of images or a seed set, got the path {backgrounds!r} "
                             f"(load a seed set with synthaug.data.seedset.SeedSet.load)")
        else:
            items = list(backgrounds)
        out = []
        for i, img in enumerate(items):
            t = to_float_image(img, self.channels, f"backgrounds[{i}]")
            out.append(t)
        return out

    @staticmethod
    def _load_params(params: Any, n: int) -> tuple[CaptureParams | None, torch.Tensor | None]:
        if params is None:
            return None, None  # sampled below
        scales = None
        if isinstance(params, (str, os.PathLike)):
            params, extra, _ = CaptureParams.load_with_extra(Path(params))
            scales = fitted_object_scales(extra)
        if not isinstance(params, CaptureParams):
            raise ValueError(f"params must be CaptureParams, a path or None, got {type(params).__name__}")
        if params.batch_size != n:
            raise ValueError(f"params has {params.batch_size} rows but there are {n} backgrounds (one row per seed)")
        return params, scales

    def _check_geometry(self, geo: Mapping[str, Any], n: int) -> dict[str, torch.Tensor]:
        if self.mode != "patch":
            raise ValueError("seed_geometry is for patch mode (frame mode places the object in the frame itself)")
        shapes = {"origin": (n, 2), "frame_size": (n, 2), "frame_scale": (n,)}
        missing = sorted(set(shapes) - set(geo))
        if missing:
            raise ValueError(f"seed_geometry lacks {missing} (needs {sorted(shapes)})")
        out = {}
        for k, shape in shapes.items():
            t = torch.as_tensor(geo[k], dtype=torch.float32)
            if tuple(t.shape) != shape or not bool(torch.isfinite(t).all()):
                raise ValueError(f"seed_geometry[{k!r}] must be finite with shape {shape} (one row per seed), "
                                 f"got {tuple(t.shape)}")
            out[k] = t
        if bool((out["frame_scale"] <= 0).any()) or bool((out["frame_size"] <= 0).any()):
            raise ValueError("seed_geometry frame_scale and frame_size must be > 0")
        return out

    def _validate_sizes(self) -> None:
        if self.params.channels != self.channels:
            raise ValueError(f"params has {self.params.channels} channel(s) but channels={self.channels}")
        need = self._crop()
        for i, b in enumerate(self.backgrounds):
            h, w = b.shape[-2:]
            if h < need or w < need:
                raise ValueError(f"backgrounds[{i}] is {h}x{w}, smaller than the {need}x{need} "
                                 f"{'patch' if self.mode == 'patch' else 'object crop'} this dataset needs")

    def _crop(self) -> int:
        """Side of the rendered square: the patch (patch mode), or the crop in which the object and its blur
        live (frame mode: largest object / 0.5, even)."""
        if self.mode == "patch":
            return self.patch_size
        return int(math.ceil(self.object_size[1] / 0.5 / 2)) * 2

    # --------------------------------------------------------- protocol
    def set_epoch(self, epoch: int) -> None:
        """New poses and noise for every synthetic item (call once per epoch)."""
        self.epoch = int(epoch)

    def __len__(self) -> int:
        return self.n_real + self.n_synthetic

    def __getitem__(self, index: int) -> tuple[torch.Tensor, dict[str, torch.Tensor]]:
        return self.__getitems__([index])[0]

    def __getitems__(self, indices: Sequence[Any]) -> list[tuple[torch.Tensor, dict[str, torch.Tensor]]]:
        """Items of a batch; each index is an int (the dataset's epoch) or an ``(epoch, index)`` pair."""
        guard_loader_worker()  # a DataLoader worker, even a user's plain one, dies with the process iterating it
        keys = []
        for i in indices:
            if isinstance(i, (tuple, list)):
                if len(i) != 2:
                    raise IndexError(f"an index is an int or an (epoch, index) pair, got {i!r}")
                keys.append((int(i[0]), int(i[1])))
            else:
                keys.append((self.epoch, int(i)))
        params, items = self._draw_batch(keys)
        todo = [k for k, item in enumerate(items) if item is None]
        if todo:  # the items a critic did not render while choosing
            for k, item in zip(todo, self._render_items([params[k] for k in todo])):
                items[k] = item
        if self.transforms is not None:
            items = [self._transform(item, p.epoch, p.index) for item, p in zip(items, params)]
        return items

    def make_params(self, index: int, epoch: int | None = None) -> ItemParams:
        """All random choices of item ``index`` in ``epoch`` (default: the dataset's), from its own generator.

        A pure function of (seed, epoch, index): the item's generator draws ten uniforms (seed, negative, five
        for the pose, the crop corner, the object size), then the random effects' fields, then the capture
        parameters (the capture sampler: "kde" / "uniform" draw, "seed" does not), and the pose sampler comes last (so that one that
        draws more, as "fitted", moves no other draw); after it only the shape (with ``shape_variation``) and the
        other seed's background (with ``background_sampling="other"``), each drawn only when asked for.

        With a ``realism_critic``, an object item's ``realism_candidates`` draws are rendered and scored here,
        and the params of the one kept are returned (candidate ``j >= 1`` draws as above from its own generator,
        with the item's seed): the choice is a draw too, so ``render(make_params(i))`` is still ``ds[i]``.

        Example:
            >>> p = ds.make_params(3)  # doctest: +SKIP
            >>> torch.equal(ds.render(p)[0], ds[3][0])  # doctest: +SKIP
            True
        """
        return self._draw_batch([(self.epoch if epoch is None else int(epoch), int(index))])[0][0]

    def _draw_batch(self, keys: Sequence[tuple[int, int]]) -> tuple[list[ItemParams], list[Any]]:
        """The params of each ``(epoch, index)`` and, for the items a critic chose among candidates, the rendered
        item (untransformed; None for the others, which are not rendered yet)."""
        n = len(self)
        params = []
        for epoch, index in keys:
            if index < 0:
                index += n
            if not 0 <= index < n:
                raise IndexError(f"index {index} out of range for a dataset of length {n}")
            params.append(ItemParams(index=index, epoch=epoch, real=True) if index < self.n_real else
                          self._draw(item_generator(self.seed, epoch, index), index, epoch))
        items: list[Any] = [None] * len(params)
        scored = [k for k, p in enumerate(params) if not p.real and not p.negative]
        if self.realism_critic is None or not scored:
            return params, items
        k_c = self.realism_candidates
        candidates = []
        for k in scored:
            p = params[k]
            candidates.append(p)
            base = item_seed(self.seed, p.epoch, p.index)
            candidates += [self._draw(item_generator(base, j, _CANDIDATE_STREAM), p.index, p.epoch, p.seed_index)
                           for j in range(1, k_c)]
        rendered = self._render_items(candidates)
        images = torch.stack([img for img, _ in rendered]).clamp(0, 1)
        seeds = torch.tensor([c.seed_index for c in candidates], dtype=torch.int64)
        logits = torch.as_tensor(np.asarray(self.realism_critic(images, seeds), dtype=np.float64))
        if logits.shape != (len(candidates),):
            raise ValueError(f"realism_critic must return one score per patch, shape ({len(candidates)},), got "
                             f"{tuple(logits.shape)}")
        if not bool(torch.isfinite(logits).all()):
            raise ValueError("realism_critic returned a non-finite score")
        best = logits.view(len(scored), k_c).argmin(1).tolist()  # the first of equal scores
        for slot, (k, b) in enumerate(zip(scored, best)):
            params[k], items[k] = candidates[slot * k_c + b], rendered[slot * k_c + b]
        return params, items

    def _draw(self, g: torch.Generator, index: int, epoch: int, seed_index: int | None = None) -> ItemParams:
        """One synthetic item's params from generator ``g`` (:meth:`make_params`' order of draws); ``seed_index``
        given: a critic's candidate, an object (never negative) of that seed, the draws of the seed and the
        negative flag made and ignored, so that everything after them keeps its place."""
        u = torch.rand(10, generator=g, dtype=torch.float64).tolist()
        n_seeds = len(self.backgrounds)
        negative = u[1] < self.negative_fraction if seed_index is None else False
        if seed_index is None:
            seed_index = min(int(u[0] * n_seeds), n_seeds - 1)
        crop = self._crop()
        fields: dict[str, torch.Tensor] = {}
        for eff in self._random_effects:
            fields.update(eff.sample_fields((1, self.channels, crop, crop), g))
        capture = self.capture_sampler.sample(g, seed_index)
        pose = self.pose_sampler.sample(g, seed_index, u[2:7])
        shapes = self.n_shapes  # drawn last, and only with shape_variation: no other draw moves
        variant = min(int(torch.rand(1, generator=g, dtype=torch.float64).item() * shapes), shapes - 1) if shapes > 1 else 0
        background = None  # drawn after everything else, and only with background_sampling="other"
        if self.background_sampling == "other":  # uniform over the other seeds
            j = min(int(torch.rand(1, generator=g, dtype=torch.float64).item() * (n_seeds - 1)), n_seeds - 2)
            background = j + int(j >= seed_index)
        framed = True  # drawn after everything else, and only with an object box's share under 1
        if self.object_box is not None and self.object_box_share < 1:
            framed = torch.rand(1, generator=g, dtype=torch.float64).item() < self.object_box_share
        h, w = self.backgrounds[seed_index if background is None else background].shape[-2:]
        lo, hi = self.object_size
        return ItemParams(
            index=index, epoch=epoch, real=False, seed_index=seed_index, negative=negative,
            pose=pose,
            crop_xy=(min(int(u[7] * (w - crop + 1)), w - crop), min(int(u[8] * (h - crop + 1)), h - crop)),
            object_px=lo + (hi - lo) * u[9] if self.mode == "frame" else None,
            capture=capture, fields=fields, variant=variant, background_index=background, framed=framed)

    @overload
    def render(self, params: ItemParams, *, transformed: bool = True) -> tuple[Any, dict[str, Any]]: ...

    @overload
    def render(self, params: Sequence[ItemParams], *, transformed: bool = True) -> list[tuple[Any, dict[str, Any]]]: ...

    def render(self, params: ItemParams | Sequence[ItemParams], *, transformed: bool = True) -> Any:
        """The item(s) of ``params`` (from :meth:`make_params`), exactly as ``ds[i]`` / ``__getitems__`` give them.

        Draws nothing except the ``transforms``' own draws (seeded from the params' seed, epoch and index as
        in ``ds[i]``). A sequence renders as one batch (vectorised) and returns a list; one params object
        returns one ``(image, target)``. ``transformed=False``: before the ``transforms`` (what a
        ``realism_critic`` scores).
        """
        single = isinstance(params, ItemParams)
        batch = [params] if single else list(params)
        for p in batch:
            if not isinstance(p, ItemParams):
                raise TypeError(f"render takes ItemParams (from make_params), got {type(p).__name__}")
            if p.real and not 0 <= p.index < self.n_real:
                raise ValueError(f"real item {p.index} out of range: this dataset has {self.n_real} real items")
            if not p.real and not 0 <= p.seed_index < len(self.backgrounds):
                raise ValueError(f"seed_index {p.seed_index} out of range: this dataset has "
                                 f"{len(self.backgrounds)} seeds")
            if not p.real and not 0 <= p.background < len(self.backgrounds):
                raise ValueError(f"background_index {p.background_index} out of range: this dataset has "
                                 f"{len(self.backgrounds)} seeds")
            if not p.real and not 0 <= p.variant < self.n_shapes:
                raise ValueError(f"variant {p.variant} out of range: this dataset has {self.n_shapes} shape(s)")
        out = self._render_items(batch)
        if self.transforms is not None and transformed:
            out = [self._transform(item, p.epoch, p.index) for item, p in zip(out, batch)]
        return out[0] if single else out

    def _render_items(self, batch: list[ItemParams]) -> list[tuple[Any, Any]]:
        """The items of checked params, before ``transforms``."""
        out: list[Any] = [None] * len(batch)
        for k, p in enumerate(batch):
            if p.real:
                out[k] = self._real_items[p.index]  # type: ignore[index]
        syn = [k for k, p in enumerate(batch) if not p.real]
        if syn:
            for k, item in zip(syn, self._synthetic_items([batch[k] for k in syn])):
                out[k] = item
        return out

    def _transform(self, item: tuple[Any, Any], epoch: int, index: int) -> tuple[Any, Any]:
        """``transforms(image, target)`` with torch's random draws seeded from (seed, epoch, index)."""
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(item_seed(self.seed ^ 0x7F4A7C15, epoch, index) & ((1 << 63) - 1))
            out = self.transforms(*item)
        if not isinstance(out, (tuple, list)) or len(out) != 2:
            raise ValueError(f"transforms must return (image, target), got {type(out).__name__}")
        return out[0], out[1]

    # -------------------------------------------------------- synthesis
    def _layers(self, pose: dict[str, torch.Tensor], size: int, object_scale: torch.Tensor,
                variant: torch.Tensor | None = None) -> tuple[torch.Tensor, torch.Tensor]:
        """Coverage and normals of each pose, of shape ``variant`` (None: the mesh itself)."""
        if variant is not None and bool((variant != 0).any()):
            cov = nrm = None
            for v in variant.unique().tolist():  # each shape's items together, put back in place
                at = (variant == v).nonzero().flatten()
                c, n = self._shape_layers(int(v), {k: t[at] for k, t in pose.items()}, size, object_scale[at])
                if cov is None:
                    cov = c.new_zeros((len(variant), *c.shape[1:]))
                    nrm = n.new_zeros((len(variant), *n.shape[1:]))
                cov[at], nrm[at] = c, n
            return cov, nrm
        return self._shape_layers(0, pose, size, object_scale)

    def _shape_layers(self, shape: int, pose: dict[str, torch.Tensor], size: int,
                      object_scale: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        if self.backend == "cache":
            return self._caches[shape].layers(pose["alpha"], pose["beta"], pose["gamma"], pose["t_x"], pose["t_y"],
                                              size=size, object_scale=object_scale)
        covs, nrms = [], []
        for k in range(len(object_scale)):  # exact: one GL render per item (scale may differ)
            c, n = self._renderers[shape].layers(*(pose[p][k:k + 1] for p in POSE_NAMES), size=size,
                                                 scale=float(object_scale[k]))
            covs.append(c)
            nrms.append(n)
        return torch.cat(covs), torch.cat(nrms)

    def _synthetic_items(self, batch: list[ItemParams]) -> list[tuple[torch.Tensor, dict[str, torch.Tensor]]]:
        """The synthetic items of ``batch``, rendered together (see :meth:`render`)."""
        crop = self._crop()
        seeds = torch.tensor([p.seed_index for p in batch])
        theta_rows = self.capture_sampler.rows(seeds, [p.capture for p in batch])
        pose = {n: torch.tensor([p.pose[n] for p in batch]) for n in POSE_NAMES}
        variant = torch.tensor([p.variant for p in batch], dtype=torch.int64)
        if self.mode == "patch":
            scale = (self.seed_scales[seeds].float() if self.seed_scales is not None
                     else torch.full((len(batch),), self.object_scale))
            if self.object_box is not None:
                pose, scale = self._box_framed_items(pose, crop, scale, variant,
                                                     torch.tensor([p.framed for p in batch], dtype=torch.bool))
        else:
            scale = torch.tensor([p.object_px / crop for p in batch])
        theta = theta_rows.replace(**pose) if self._pose_in_range(pose) else CaptureParams(
            {**theta_rows.as_dict(), **pose}, channels=self.channels, effects=self.params.effects, validate=False)
        bgs = torch.stack([
            self.backgrounds[p.background][:, p.crop_xy[1]:p.crop_xy[1] + crop,
                                              p.crop_xy[0]:p.crop_xy[0] + crop]
            for p in batch
        ])
        places = torch.tensor([p.background for p in batch])  # the seeds whose frames the pixels come from
        fields = {k: torch.cat([p.fields[k] for p in batch]) for k in batch[0].fields}
        frame_size = origin = None
        extras: dict[str, torch.Tensor] = {}
        if self.mode == "patch" and self.seed_geometry is not None:  # the background's place in its seed's frame
            geo = self.seed_geometry
            fsc = geo["frame_scale"][places]
            crop_xy = torch.tensor([p.crop_xy for p in batch], dtype=torch.float32)
            origin = geo["origin"][places] + crop_xy * fsc[:, None]
            frame_size = geo["frame_size"][places]
            extras["frame_scale"] = fsc
        if self.mode == "frame":
            origin = torch.tensor([p.crop_xy for p in batch], dtype=torch.float32)
            frame_size = torch.tensor([[self.backgrounds[p.background].shape[-1],
                                        self.backgrounds[p.background].shape[-2]] for p in batch],
                                      dtype=torch.float32)
        # Rendered in chunks of ~2**18 pixels: a chunk's layers stay in a core's cache through the effects'
        # many elementwise passes (a 256-patch batch at once spills to memory; ~20 % slower, issue 19). Every
        # step is per item, so the chunking changes no value.
        step = max(1, _CHUNK_PIXELS // (crop * crop))
        covs, chunks = [], []
        for i in range(0, len(batch), step):
            sl = slice(i, i + step)
            cov, nrm = self._layers({k: v[sl] for k, v in pose.items()}, crop, scale[sl], variant[sl])
            covs.append(cov)
            chunks.append(simulate(cov, nrm, bgs[sl], theta[sl], effects=self.effects,
                                   fields={k: v[sl] for k, v in fields.items()},
                                   origin=None if origin is None else origin[sl],
                                   frame_size=None if frame_size is None else frame_size[sl],
                                   extras={k: v[sl] for k, v in extras.items()}))
        images = chunks[0] if len(chunks) == 1 else torch.cat(chunks)
        cov = covs[0] if len(covs) == 1 else torch.cat(covs)
        # Every per-item tensor is a view of a batch tensor: from a DataLoader worker a batch then crosses as a
        # few shared blocks (one per storage), not one shared segment and file descriptor per item and key,
        # which cost more than rendering a frame (issue 19).
        vec = theta.to_vector().float()
        synthetic = torch.ones(len(batch), dtype=torch.bool)
        if self.mode == "patch":
            labels = torch.tensor([0 if p.negative else self.label for p in batch], dtype=torch.int64)
        else:
            frames = self._frame_batch(batch)
            labels = torch.full((len(batch), 1), self.label, dtype=torch.int64)
            corner = torch.tensor([p.crop_xy for p in batch])
            boxes, n_boxes = _boxes_from_coverage(cov[:, 0], corner[:, 0], corner[:, 1])
            boxes = boxes[:, None]
        out = []
        for k, p in enumerate(batch):
            target: dict[str, torch.Tensor] = {"synthetic": synthetic[k], "seed_index": seeds[k], "theta": vec[k]}
            if self.mode == "patch":
                target["labels"] = labels[k]
                out.append((bgs[k] if p.negative else images[k], target))
            else:
                frame = frames[k]
                n = 0
                if not p.negative:
                    x0, y0 = p.crop_xy
                    frame[:, y0:y0 + crop, x0:x0 + crop] = images[k]
                    n = n_boxes[k]
                target["boxes"] = tv_tensors.BoundingBoxes(boxes[k, :n], format="XYXY",
                                                           canvas_size=tuple(frame.shape[-2:]))
                target["labels"] = labels[k, :n]
                out.append((tv_tensors.Image(frame), target))
        return out

    def _coverage_boxes(self, pose: dict[str, torch.Tensor], size: int, scale: torch.Tensor,
                        variant: torch.Tensor | None = None) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Each pose's coverage box on a ``size`` square (≥ 0.5, else > 0; rendered in chunks as the items are):
        ``(B, 4)`` XYXY boxes (float64, px), their longest sides, and whether any pixel was covered."""
        step = max(1, _CHUNK_PIXELS // (size * size))
        boxes, seen = [], []
        for i in range(0, len(scale), step):
            sl = slice(i, i + step)
            cov, _ = self._layers({k: v[sl] for k, v in pose.items()}, size, scale[sl],
                                  None if variant is None else variant[sl])
            b, n = _boxes_from_coverage(cov[:, 0], torch.zeros(cov.shape[0]), torch.zeros(cov.shape[0]))
            boxes.append(b)
            seen += n
        box = torch.cat(boxes).double()
        return box, torch.maximum(box[:, 2] - box[:, 0], box[:, 3] - box[:, 1]), torch.tensor(seen, dtype=torch.bool)

    def _fitted_box_fraction(self) -> float:
        """``object_box="fit"``: the median over seeds of the fitted render's coverage box (its longest side, at the
        fitted pose and scale) as a fraction of the patch: the size at which the fit says the seeds' objects
        themselves sit in their patches, inside the labelled box's ``object_fraction`` and the annotators' margin."""
        size = self._crop()
        pose = {n: getattr(self.params, n).flatten().float() for n in POSE_NAMES}
        _, longest, seen = self._coverage_boxes(pose, size, self.seed_scales.float())
        if not seen.any():
            raise ValueError("object_box='fit': no seed's fitted render covers a pixel")
        return float(min(1.0, longest[seen].median().item() / size))

    def _box_framed(self, pose: dict[str, torch.Tensor], size: int, scale: torch.Tensor,
                    variant: torch.Tensor | None = None) -> tuple[dict[str, torch.Tensor], torch.Tensor]:
        """The pose and scale that frame each object as ingest frames a labelled seed (``object_box``).

        A first look at the pose, untranslated, on a square twice the patch's side at the same pixel size (so
        that nothing is cut), gives the coverage's box (≥ 0.5, else > 0); the scale is multiplied by
        ``object_box × size / longest side`` and the translation moves the box's centre onto the patch's.
        An object with no coverage at all keeps its pose and scale.
        """
        big = 2 * size
        zero = {**pose, "t_x": torch.zeros_like(pose["t_x"]), "t_y": torch.zeros_like(pose["t_y"])}
        box, longest, ok = self._coverage_boxes(zero, big, scale * (size / big), variant)
        k = torch.where(ok, self.object_box * size / longest.clamp_min(1.0), torch.ones_like(longest))
        cx = (box[:, 0] + box[:, 2]) / 2 - big / 2  # the box centre's offset from the square's centre, px
        cy = (box[:, 1] + box[:, 3]) / 2 - big / 2
        framed = dict(pose)
        framed["t_x"] = torch.where(ok, -cx * k / size, pose["t_x"].double()).to(pose["t_x"].dtype)
        framed["t_y"] = torch.where(ok, -cy * k / size, pose["t_y"].double()).to(pose["t_y"].dtype)
        return framed, (scale.double() * k).to(scale.dtype)

    def _box_framed_items(self, pose: dict[str, torch.Tensor], size: int, scale: torch.Tensor, variant: torch.Tensor,
                          framed: torch.Tensor) -> tuple[dict[str, torch.Tensor], torch.Tensor]:
        """:meth:`_box_framed` for the items where ``framed`` is True (``object_box_share``); the others keep their
        drawn pose and scale (the paper's framing). Each item's framing is its own, so a subset gives the same
        values."""
        if bool(framed.all()):
            return self._box_framed(pose, size, scale, variant)
        if not bool(framed.any()):
            return pose, scale
        sub, sub_scale = self._box_framed({k: v[framed] for k, v in pose.items()}, size, scale[framed],
                                          variant[framed])
        out = {k: v.clone() for k, v in pose.items()}
        for k, v in sub.items():
            out[k][framed] = v
        scale = scale.clone()
        scale[framed] = sub_scale
        return out, scale

    def _frame_batch(self, batch: list[ItemParams]) -> list[torch.Tensor]:
        """The batch's full frames (copies of their backgrounds), views of one storage.

        In a DataLoader worker that storage is allocated in shared memory, as
        ``default_collate`` does: the batch then crosses to the main process as
        one shared block, written once, instead of one copy into a new shared
        segment per frame (which cost more than rendering them: issue 19).
        """
        shapes = {tuple(self.backgrounds[p.background].shape) for p in batch}
        if len(shapes) != 1:  # backgrounds of different sizes: one tensor per frame
            return [self.backgrounds[p.background].clone() for p in batch]
        shape = (len(batch), *shapes.pop())
        if torch.utils.data.get_worker_info() is not None:
            storage = torch.UntypedStorage._new_shared(math.prod(shape) * 4)
            frames = torch.empty(0, dtype=torch.float32).set_(storage, 0, shape)
        else:
            frames = torch.empty(shape, dtype=torch.float32)
        for k, p in enumerate(batch):
            frames[k].copy_(self.backgrounds[p.background])
        return list(frames.unbind(0))

    def _pose_in_range(self, pose: dict[str, torch.Tensor]) -> bool:
        for spec in POSE_SPECS:
            v = pose[spec.name]
            if not spec.periodic and ((v < spec.low) | (v > spec.high)).any():
                return False
        return True


_CHUNK_PIXELS = 64 * 64 * 64  # pixels rendered together (see SyntheticObjectDataset._synthetic_items)
_CANDIDATE_STREAM = 0x43524954  # a critic's candidate j of an item draws from item_generator(item's seed, j, this)


def _check_realism_candidates(candidates: Any) -> int:
    """``realism_candidates`` (:class:`SyntheticObjectDataset`) as an int >= 2, checked with or without a critic (a
    bad value is a mistake either way)."""
    if not is_integral(candidates) or candidates < 2:
        raise ValueError(f"realism_candidates must be an integer >= 2 (draws per item, the critic keeps one), got "
                         f"{candidates!r}")
    return int(candidates)


def _check_realism_critic(critic: Any, mode: str, n_seeds: int) -> Any:
    """``realism_critic`` (:class:`SyntheticObjectDataset`) checked: None or a callable, in patch mode, fitted (when it
    says so with ``n_seeds``) on as many seeds as the dataset has."""
    if critic is None:
        return None
    if not callable(critic):
        raise ValueError(f"realism_critic must be a callable (patches, seed_index) -> scores, got "
                         f"{type(critic).__name__}")
    if mode != "patch":
        raise ValueError("realism_critic scores object patches: patch mode only")
    fitted = getattr(critic, "n_seeds", None)
    if fitted is not None and fitted != n_seeds:
        raise ValueError(f"the realism_critic was fitted on {fitted} seeds but this dataset has {n_seeds}: fit it on "
                         f"this dataset's seed set")
    return critic


def _check_background_sampling(background_sampling: Any, n_seeds: int) -> str:
    """``background_sampling`` checked against the seeds there are ("other" needs two)."""
    one_of(background_sampling, BACKGROUND_SAMPLING, "background_sampling")
    if background_sampling == "other" and n_seeds < 2:
        raise ValueError(f"background_sampling='other' puts each object on another seed's background: it needs at "
                         f"least 2 backgrounds, got {n_seeds}")
    return str(background_sampling)


def check_object_box_share(share: Any, object_box: Any) -> float:
    """``object_box_share`` as a float in (0, 1]; a share under 1 needs an ``object_box``."""
    if isinstance(share, bool) or not isinstance(share, numbers.Real) or not 0 < float(share) <= 1:
        raise ValueError(f"object_box_share must be a fraction in (0, 1], got {share!r}")
    if float(share) < 1 and object_box is None:
        raise ValueError(f"object_box_share {share!r} is the share of the objects that object_box frames: "
                         "give an object_box")
    return float(share)


def _check_object_box(object_box: Any, backgrounds: Any, mode: str) -> float | str | None:
    """``object_box`` as a fraction of the patch side (None: the paper's framing; ``"fit"``: resolved once the
    renderer exists, :meth:`SyntheticObjectDataset._fitted_box_fraction`)."""
    if object_box is None:
        return None
    if mode != "patch":
        raise ValueError("object_box frames patch-mode objects; frame mode draws object sizes with object_size")
    if isinstance(object_box, str):
        if object_box == "fit":
            return "fit"
        if object_box != "seed":
            raise ValueError(f"object_box must be a fraction in (0, 1], 'seed', 'fit' or None, got {object_box!r}")
        fraction = getattr(backgrounds, "object_fraction", None)
        if fraction is None:
            raise ValueError("object_box='seed' reads the seed set's object_fraction: give a seed set as backgrounds, "
                             "or the fraction itself")
        object_box = fraction
    if isinstance(object_box, bool) or not isinstance(object_box, numbers.Real) or not 0 < float(object_box) <= 1:
        raise ValueError(f"object_box must be a fraction in (0, 1], 'seed', 'fit' or None, got {object_box!r}")
    return float(object_box)


def _boxes_from_coverage(cov: torch.Tensor, x0: torch.Tensor, y0: torch.Tensor, threshold: float = 0.5,
                         ) -> tuple[torch.Tensor, list[int]]:
    """Tight XYXY boxes (pixel edges) of coverage >= threshold (or > 0 where none is), offset to the frame.

    Args:
        cov: (B, H, W) coverages; x0, y0: (B,) the crops' corners in their frames.

    Returns:
        (B, 4) float32 boxes and each item's box count: 1, or 0 where the object is not in view.
    """
    b, h, w = cov.shape
    # a row (column) holds a pixel >= t iff its maximum does: reduce the floats once, not boolean masks
    row_max, col_max = cov.amax(2), cov.amax(1)
    strong = (row_max.amax(1) >= threshold)[:, None]
    rows = torch.where(strong, row_max >= threshold, row_max > 0)
    cols = torch.where(strong, col_max >= threshold, col_max > 0)
    ys, xs = torch.arange(h), torch.arange(w)
    top = torch.where(rows, ys, h).amin(1)
    bottom = torch.where(rows, ys, -1).amax(1) + 1
    left = torch.where(cols, xs, w).amin(1)
    right = torch.where(cols, xs, -1).amax(1) + 1
    boxes = torch.stack([x0 + left, y0 + top, x0 + right, y0 + bottom], 1).to(torch.float32)
    return boxes, rows.any(1).to(torch.int64).tolist()
