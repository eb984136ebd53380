"""A fit file's objects as layers: the view cache it was made with, each seed's scale, the coverage at Θ_i.

One home for what the copy-paste baseline (the fitted silhouettes), the re-rendering of fits
(:func:`synthaug.fit.render_fit.render_fitted`) and the diagnosis (its residuals) each read from a
``synthaug fit`` output.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

import torch

from synthaug.params import CaptureParams


def fit_view_cache(meta: Mapping[str, Any], mesh: Any = None) -> Any:
    """The :class:`~synthaug.render.cache.ViewCache` a fit was made with (its ``config``'s step and sprite size,
    :meth:`ViewCache.build`'s defaults for what it does not record); ``mesh`` defaults to the fit's own."""
    from synthaug.render.cache import ViewCache

    cfg = meta.get("config", {}) or {}
    options = {k: cfg[k] for k in ("step_deg", "sprite_size") if k in cfg}
    return ViewCache.build(mesh or meta.get("mesh") or "quadcopter", **options)


def fitted_scales(extra: Sequence[Mapping[str, Any]], meta: Mapping[str, Any], default: float) -> torch.Tensor:
    """Each seed's fitted object scale (``extra`` rows), else the file's ``object_scale``, else ``default``; (N,) float64."""
    fallback = float(meta.get("object_scale", default))
    return torch.tensor([float(e.get("object_scale", fallback)) for e in extra], dtype=torch.float64)


def fitted_layers(fit_file: str | Path, n: int, size: int, *, mesh: Any = None, cache: Any = None,
                  default_scale: float = 0.7) -> tuple[CaptureParams, list[dict[str, Any]], dict[str, Any],
                                                        torch.Tensor, torch.Tensor]:
    """Coverage (N, 1, size, size) and normals (N, 3, size, size) at each seed's fitted pose, translation and scale.

    Returns:
        ``(theta, extra, meta, coverage, normals)``.

    Raises:
        ValueError: the fit does not hold ``n`` rows (one per seed of the seed set it is used with).
    """
    theta, extra, meta = CaptureParams.load_with_extra(fit_file)
    if theta.batch_size != n:
        raise ValueError(f"{fit_file} has {theta.batch_size} rows but the seed set has {n} seeds")
    cache = cache if cache is not None else fit_view_cache(meta, mesh)
    f = lambda t: t.float().reshape(-1)  # noqa: E731
    cov, nrm = cache.layers(f(theta.alpha), f(theta.beta), f(theta.gamma), f(theta.t_x), f(theta.t_y), size=size,
                            object_scale=fitted_scales(extra, meta, default_scale).float())
    return theta, extra, meta, cov, nrm
