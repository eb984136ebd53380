"""The arguments of :class:`~synthaug.data.synthetic.SyntheticObjectDataset` on their own: the plain ones checked,
the renderer named, and the former spellings of one release folded into the arguments that now hold them.

One argument per concept: ``render`` holds the renderer (``"cache"``, a mapping of ``ViewCache.build`` options,
a prebuilt view cache, ``"exact"``; it replaced ``cache`` / ``cache_options``) and ``pose_sampling`` the pose
sampler (``"uniform"``, ``"fitted"`` or an object such as :class:`~synthaug.data.poses.UniformPose`; it replaced
``pose_ranges`` / ``pose_jitter_deg``). The former names are accepted for one release with a FutureWarning,
as torchvision handles renamed arguments.

Example:
    >>> render_backend({"step_deg": 30}), render_backend("exact")
    ('cache', 'exact')
    >>> is_integral(3.0), is_integral(True)
    (True, False)
"""

from __future__ import annotations

import math
import numbers
import os
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from synthaug.data.poses import FittedPose, UniformPose
from synthaug.params import CaptureParams

__all__ = ["check_arguments", "is_integral", "legacy_arguments", "render_backend"]


def is_integral(x: Any) -> bool:
    """An int (Python or numpy), or a float with no fractional part; never a bool."""
    if isinstance(x, (bool, np.bool_)):
        return False
    if isinstance(x, (int, np.integer)):
        return True
    return isinstance(x, (float, np.floating)) and math.isfinite(x) and float(x).is_integer()


def check_arguments(*, transforms: Any, mode: str, channels: int, patch_size: Any,
                     synthetic_per_real: Any, length: Any, real: Any, object_scale: float | None,
                     negative_fraction: float | None, object_size: tuple[float, float],
                     shape_variation: Any = 0.0, shape_variants: Any = 8) -> float:
    """:class:`SyntheticObjectDataset`'s plain arguments on their own; returns the negative fraction
    (default 0.5 in patch mode, 0 in frame mode)."""
    if transforms is not None and not callable(transforms):
        raise ValueError(f"transforms must be a callable on (image, target), got {type(transforms).__name__}")
    if mode not in ("patch", "frame"):
        raise ValueError(f"mode must be 'patch' or 'frame', got {mode!r}")
    if channels not in (1, 3):
        raise ValueError(f"channels must be 1 or 3, got {channels}")
    if not is_integral(patch_size) or patch_size < 8:
        raise ValueError(f"patch_size must be an integer >= 8, got {patch_size!r}")
    # checked whether or not real is given: a bad value is a mistake either way, never silently ignored
    if isinstance(synthetic_per_real, (bool, np.bool_)) or not isinstance(synthetic_per_real, numbers.Real) or \
            not math.isfinite(synthetic_per_real) or synthetic_per_real < 0:
        raise ValueError(f"synthetic_per_real must be a finite number >= 0, got {synthetic_per_real!r}")
    if length is not None and (not is_integral(length) or length < 0):
        raise ValueError(f"length must be an integer >= 0, got {length!r}")
    if real is not None and length is not None:
        raise ValueError("give length (synthetic items alone) or real (mixed with synthetic_per_real), not both")
    if object_scale is not None and not 0 < object_scale <= 1.5:
        raise ValueError(f"object_scale must be in (0, 1.5], got {object_scale}")
    neg = (0.5 if mode == "patch" else 0.0) if negative_fraction is None else float(negative_fraction)
    if not 0.0 <= neg <= 1.0:
        raise ValueError(f"negative_fraction must be in [0, 1], got {negative_fraction}")
    lo_sz, hi_sz = object_size
    if not (0 < lo_sz <= hi_sz):
        raise ValueError(f"object_size must be (min, max) with 0 < min <= max, got {object_size}")
    if isinstance(shape_variation, (bool, np.bool_)) or not isinstance(shape_variation, numbers.Real) or \
            not math.isfinite(shape_variation) or shape_variation < 0:
        raise ValueError(f"shape_variation must be a number >= 0, got {shape_variation!r}")
    if shape_variation > 0 and (not is_integral(shape_variants) or shape_variants < 2):
        raise ValueError(f"shape_variants must be an integer >= 2 with shape_variation > 0, got {shape_variants!r}")
    return neg


def render_backend(render: Any) -> str:
    """``"cache"`` or ``"exact"``: which renderer ``render`` asks for (a mapping or a view cache: ``"cache"``)."""
    if isinstance(render, str):
        if render not in ("cache", "exact"):
            raise ValueError(f"render must be 'cache', 'exact', a mapping of ViewCache.build options or a ViewCache, "
                             f"got {render!r}")
        return render
    if isinstance(render, Mapping) or callable(getattr(render, "layers", None)):
        return "cache"
    raise ValueError(f"render must be 'cache', 'exact', a mapping of ViewCache.build options or a ViewCache, got "
                     f"{type(render).__name__}")


# The constructor's former arguments, accepted for one release (torchvision's way with renamed arguments): each
# folds into the argument that now holds its concept, with a FutureWarning that names the new spelling.
_DEPRECATED = {
    "cache": "render=<the ViewCache>",
    "cache_options": "render={...ViewCache.build options...}",
    "pose_ranges": "pose_sampling=UniformPose(ranges) or FittedPose(params, jitter_deg, ranges)",
    "pose_jitter_deg": "pose_sampling=FittedPose(params, jitter_deg)",
}


def legacy_arguments(deprecated: Mapping[str, Any], *, render: Any, pose_sampling: Any,
                      params: Any) -> tuple[Any, Any]:
    """``render`` and ``pose_sampling`` with the former ``cache`` / ``cache_options`` / ``pose_ranges`` /
    ``pose_jitter_deg`` folded in (each with a FutureWarning); an unknown keyword is a TypeError."""
    unknown = sorted(set(deprecated) - set(_DEPRECATED))
    if unknown:
        raise TypeError(f"SyntheticObjectDataset got unexpected keyword argument(s) {unknown}")
    for name in deprecated:
        warnings.warn(f"SyntheticObjectDataset({name}=...) is deprecated and will be removed in the next release; "
                      f"use {_DEPRECATED[name]}", FutureWarning, stacklevel=3)
    cache, options = deprecated.get("cache"), deprecated.get("cache_options")
    if cache is not None or options is not None:
        if not (isinstance(render, str) and render == "cache"):
            raise ValueError("cache / cache_options are for the view cache: leave render at 'cache' "
                             "(or give render=<the ViewCache> / render={...options...} alone)")
        render = cache if cache is not None else dict(options)
    ranges, jitter = deprecated.get("pose_ranges"), deprecated.get("pose_jitter_deg")
    if jitter is not None and not (isinstance(jitter, numbers.Real) and math.isfinite(jitter) and jitter >= 0):
        raise ValueError(f"pose_jitter_deg must be finite and >= 0, got {jitter}")
    if ranges is not None or jitter is not None:
        if not isinstance(pose_sampling, str):
            raise ValueError("pose_ranges is for pose_sampling 'uniform' / 'fitted'; a pose sampler of your "
                             "own draws its own ranges")
        if pose_sampling == "uniform":
            pose_sampling = UniformPose(ranges)
        elif pose_sampling == "fitted":
            if params is None:
                raise ValueError("pose_sampling='fitted' draws around each seed's fitted pose: give params (a fit)")
            fit = CaptureParams.load(Path(params)) if isinstance(params, (str, os.PathLike)) else params
            pose_sampling = FittedPose(fit, 20.0 if jitter is None else jitter, ranges)
    return render, pose_sampling
