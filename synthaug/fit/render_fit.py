"""Re-render the fitted image S(Θ^(i), B_i) of each seed from a fit file (for plots and diagnosis)."""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import torch

from synthaug.params import CaptureParams


def render_fitted(seeds: Any, fit_path: Any, mesh: Any = "quadcopter", *, indices: Sequence[int] | None = None,
                  cache: Any = None) -> tuple[torch.Tensor, torch.Tensor]:
    """Real patches and their fitted synthetic images.

    Returns:
        real (N, 1, P, P) and synthetic (N, 1, P, P), float in [0, 1].
    """
    from synthaug.data.fitted import fit_view_cache, fitted_scales
    from synthaug.fit.config import patches_tensor
    from synthaug.fit.objective import FitSpace, RenderObjective

    theta, extra, meta = CaptureParams.load_with_extra(fit_path)
    if theta.batch_size != len(seeds):
        raise ValueError(f"{fit_path} has {theta.batch_size} rows but the seed set has {len(seeds)} seeds")
    if cache is None:
        cache = fit_view_cache(meta, mesh)
    scales = fitted_scales(extra, meta, 0.7)
    idx = list(range(len(seeds))) if indices is None else list(indices)
    reals, syns = [], []
    for i in idx:
        scale = float(scales[i])
        space = FitSpace.default(channels=theta.channels, effects=theta.effects)
        obj = RenderObjective(patches_tensor(seeds.patches[i:i + 1]), patches_tensor(seeds.backgrounds[i:i + 1]),
                              cache, distance=None, space=space, object_scale=scale,
                              noise_seed=int(extra[i].get("generator_seed", 0)))
        u = space.from_theta(theta[i])
        syns.append(obj.render(u))
        reals.append(obj.target)
    return torch.cat(reals), torch.cat(syns)


def pairs_grid(real: torch.Tensor, syn: torch.Tensor, *, zoom: int = 2, cols: int = 4) -> np.ndarray:
    """uint8 grid of (real | synthetic) pairs."""
    from synthaug.data.preview import tile_grid

    tiles = []
    for r, s in zip(real, syn):
        pair = torch.cat([r[0], s[0]], dim=1)
        tiles.append(np.round(pair.clamp(0, 1).numpy() * 255).astype(np.uint8))
    return tile_grid(tiles, cols, zoom=zoom)
