"""One seed's fit: its objective (:func:`fit_objective`) and the search that minimises it (:func:`search`),
from the start :mod:`synthaug.fit.starts` gives or from a random one; :func:`fit_one` is both, :func:`fit_together` several seeds at once."""

from __future__ import annotations

from typing import Any, Callable, Sequence

import numpy as np
import torch

from synthaug.fit.config import FitConfig
from synthaug.fit.starts import pose_grid_starts
from synthaug.params import CaptureParams, effect_param_specs


def fit_one(target: torch.Tensor, background: torch.Tensor, cache: Any, distance: Any, cfg: FitConfig, *,
            seed: int, object_scale: float, x0: np.ndarray | None = None, space: Any = None,
            geometry: dict[str, torch.Tensor] | None = None) -> dict[str, Any]:
    """Fit Θ for one seed. Returns ``{"theta": list, "distance": float, "stats": dict}``.

    Without ``x0``: with ``cfg.init == "uniform"`` the pose starts at the
    annotated centre (t = 0) and rotations and capture parameters at random
    (the paper), drawn from ``seed``; with ``"grid"``, at the best poses of
    :func:`pose_grid_starts`. A given ``x0`` is the start either way.
    """
    objective = fit_objective(target, background, cache, distance, cfg, seed=seed, object_scale=object_scale,
                              space=space, geometry=geometry)
    return search(objective, cfg, seed=seed, object_scale=object_scale, x0=x0)


def fit_together(targets: torch.Tensor, backgrounds: torch.Tensor, cache: Any, distance: Any, cfg: FitConfig, *,
                 seeds: Sequence[int], object_scale: float,
                 geometries: Sequence[dict[str, torch.Tensor] | None] | None = None) -> list[dict[str, Any]]:
    """:func:`fit_one` for several seeds (``targets``/``backgrounds`` (K, C, P, P), one generator seed each),
    fitted in lockstep (:func:`~synthaug.fit.lockstep.run_lockstep`): the same results, their populations scored
    in one batch."""
    from synthaug.fit.lockstep import run_lockstep

    geometries = [None] * len(seeds) if geometries is None else list(geometries)
    objectives = [fit_objective(targets[k:k + 1], backgrounds[k:k + 1], cache, distance, cfg, seed=s,
                                object_scale=object_scale, geometry=geometries[k]) for k, s in enumerate(seeds)]
    return run_lockstep(objectives, [lambda evaluate, o=o, s=s: search(o, cfg, seed=s, object_scale=object_scale,
                                                                       evaluate=evaluate)
                                     for o, s in zip(objectives, seeds)])


def fit_objective(target: torch.Tensor, background: torch.Tensor, cache: Any, distance: Any, cfg: FitConfig, *,
                  seed: int, object_scale: float, space: Any = None,
                  geometry: dict[str, torch.Tensor] | None = None) -> Any:
    """The :class:`~synthaug.fit.objective.RenderObjective` of one seed's fit (its search space from ``cfg``)."""
    from synthaug.fit.objective import FitSpace, RenderObjective

    if space is None:
        names = CaptureParams.vector_names(effects=cfg.effects)
        bounds = {k: tuple(v) for k, v in cfg.bounds.items() if k in names}
        fixed = None
        if cfg.object_noise == "measured" and "sigma_n" in names:
            from synthaug.fit.noise_level import noise_sigma

            spec = next(sp for sp in effect_param_specs(cfg.effects) if sp.name == "sigma_n")
            lo, hi = bounds.get("sigma_n", (spec.low, spec.high))
            fixed = {"sigma_n": float(np.clip(float(noise_sigma(target)[0]), lo, hi))}
        space = FitSpace.default(channels=target.shape[1], effects=cfg.effects, translation=cfg.translation,
                                 bounds=bounds, fixed=fixed,
                                 scale_range=(cfg.scale_range[0] * object_scale, cfg.scale_range[1] * object_scale)
                                 if cfg.fit_scale else None)
    geo = geometry or {}
    return RenderObjective(target, background, cache, distance, space, object_scale=object_scale,
                           noise_seed=seed, origin=geo.get("origin"), frame_size=geo.get("frame_size"),
                           extras={"frame_scale": geo["frame_scale"]} if "frame_scale" in geo else None)


def search(objective: Any, cfg: FitConfig, *, seed: int, object_scale: float, x0: np.ndarray | None = None,
           evaluate: Callable[[np.ndarray], np.ndarray] | None = None) -> dict[str, Any]:
    """Minimise a seed's objective (:func:`fit_objective`) as ``cfg`` says: the start, then the optimiser.

    ``evaluate`` scores candidates in place of ``objective`` with the same values (the lockstep's
    batched scoring, :mod:`synthaug.fit.lockstep`); ``objective`` still gives the search space.
    """
    from synthaug.fit.optimizers import get_optimizer

    space = objective.space
    if evaluate is None:
        evaluate = objective
    init = None
    opt = get_optimizer(cfg.optimizer)
    n_init = int(cfg.init_fraction * cfg.budget)
    rotations_free = {"alpha", "beta", "gamma"} <= set(space.free_names())
    if x0 is None and cfg.init == "grid" and n_init >= 16 and rotations_free:
        init = pose_grid_starts(evaluate, space, budget=n_init, object_scale=object_scale, n_starts=cfg.init_starts,
                                seed=seed, engine=getattr(opt, "engine", "numpy"))  # the fit's own CMA-ES
    elif x0 is None:
        x0 = np.random.default_rng(seed).random(space.dim)
        names = space.free_names()
        for k in ("t_x", "t_y", "object_scale"):
            if k in names:
                x0[names.index(k)] = 0.5  # the annotated centre, the middle of the scale range
    if init is None:
        result = opt.minimize(evaluate, space.dim, x0=x0, seed=seed, budget=cfg.budget)
        best_x, best, stats = result.x, result.fun, result.stats()
    else:
        result = opt.minimize(evaluate, space.dim, seed=seed, budget=cfg.budget - init["n_evals"],
                              starts=init["starts"], stds=init["stds"])
        n0 = init["n_evals"]
        best_x, best = (result.x, result.fun) if result.fun < init["fun"] else (init["x"], init["fun"])
        stats = result.stats()
        stats["n_evals"] = int(n0 + result.n_evals)
        stats["trace"] = [list(t) for t in init["trace"]] + [[int(n0 + n), float(v)] for n, v in result.trace
                                                           if v < init["fun"]]
        stats["init"] = {"name": "grid", "n_evals": int(n0), "grid_size": init["grid_size"],
                         "spacing_deg": round(float(np.degrees(init["spacing"])), 3), "best": float(init["fun"])}
        stats["init_wall_s"] = round(init["wall_s"], 4)
    theta = space.to_theta(best_x[None]).wrapped()
    return {"theta": theta.to_vector()[0].tolist(), "distance": float(best), "stats": stats,
            "object_scale": float(space.scale(best_x[None], object_scale)[0])}
