"""The structured start of a seed's search: a rotation grid, then a short search of the rest at its best poses
(``FitConfig(init="grid")``)."""

from __future__ import annotations

from typing import Any, Callable

import numpy as np


def neutral_u(space: Any, object_scale: float) -> np.ndarray:
    """Search coordinates of a neutral Θ: rotations 0, t = 0, the default scale, capture parameters at the
    middle of their sampling ranges (clipped to the search bounds)."""
    from synthaug.params import POSE_SPECS, effect_param_specs

    specs = {sp.name: sp for sp in POSE_SPECS + effect_param_specs(space.effects)}
    u = np.full(space.dim, 0.5)
    free = [i for i, f in enumerate(space.free) if f]
    for j, col in enumerate(free):
        sp = specs[space.names[col].split("[")[0]]
        lo, hi = sp.sampling_range
        mid = 0.0 if sp.name in ("t_x", "t_y") else (lo + hi) / 2
        span = space.high[col] - space.low[col]
        u[j] = float(np.clip((mid - space.low[col]) / span, 0.0, 1.0)) if span > 0 else 0.5
    if space.scale_range is not None:
        u[-1] = space.scale_to_u(object_scale)
    return u


def pose_grid_starts(objective: Callable[[np.ndarray], np.ndarray], space: Any, *, budget: int,
                     object_scale: float, n_starts: int = 3, seed: int = 0, grid_share: float = 0.6,
                     n_refine: int | None = None, engine: str = "numpy") -> dict[str, Any]:
    """Structured start of a fit: a rotation grid, then a short search of the rest at the best poses.

    1. the objective on a near-uniform grid of rotations
       (:func:`~synthaug.fit.objective.rotation_grid`, about ``grid_share *
       budget`` of them; the spacing follows from the count), everything else at
       :func:`neutral_u` (t = 0, the default scale, mid-range capture
       parameters), in batched calls;
    2. at each of the ``n_refine`` best distinct poses (at least one grid
       spacing apart; default 2 × ``n_starts`` where each gets 60+
       evaluations, else ``n_starts``), a short CMA-ES over the other
       coordinates (translation, capture parameters, scale) with the rotation
       held, sharing the rest of ``budget`` (skipped under 24 each);
    3. the ``n_starts`` best refined points, best first, are the starts.

    ``engine``: the CMA-ES of step 2 (:class:`~synthaug.fit.optimizers.CMAES`'s ``"pycma"`` or ``"numpy"``; a fit
    passes its optimiser's, so a numpy-engine fit runs no pycma step).

    Returns:
        ``starts`` (K, D), ``stds`` (D,) per-coordinate CMA-ES step sizes (about
        half a grid spacing on the rotations), the best point ``x`` and value
        ``fun`` seen, ``n_evals`` (≤ ``budget``), ``trace``, ``grid_size``,
        ``spacing`` (rad), ``wall_s``.
    """
    import time

    from synthaug.fit.objective import rotation_angle, rotation_grid
    from synthaug.fit.optimizers import CMAES, _Tracker
    from synthaug.render.pose import rotation_matrices

    if budget < 16:
        raise ValueError(f"pose_grid_starts needs a budget >= 16 evaluations, got {budget}")
    if n_starts < 1:
        raise ValueError(f"n_starts must be >= 1, got {n_starts}")
    t0 = time.perf_counter()
    track = _Tracker(objective, budget)
    names = space.free_names()
    rot_cols = [names.index(k) for k in ("alpha", "beta", "gamma")]
    base = neutral_u(space, object_scale)
    if not 0 < grid_share <= 1:
        raise ValueError(f"grid_share must be in (0, 1], got {grid_share}")
    n_grid = max(8, int(grid_share * budget))
    grid, spacing = rotation_grid(n_grid)
    while len(grid) > n_grid:  # the grid's own rounding: stay within the share
        grid, spacing = rotation_grid(max(8, int(n_grid * n_grid / len(grid)) - 1))
    u = space.pose_to_u(grid, base)
    vals = track(u)
    # the best distinct poses (at least one spacing apart)
    order = np.argsort(vals, kind="stable")
    if n_refine is None:  # twice the starts where each still gets a useful search (measured: 60+ evaluations)
        n_refine = 2 * n_starts if (budget - len(grid)) >= 60 * 2 * n_starts else n_starts
    n_pick = max(int(n_refine), n_starts)
    head = order[: min(len(order), 40 * n_pick)]
    rots = rotation_matrices(grid[head, 0], grid[head, 1], grid[head, 2])
    picked: list[int] = []
    for j in range(len(head)):
        if all(rotation_angle(rots[j], rots[p]) >= 0.99 * spacing for p in picked):
            picked.append(j)
            if len(picked) == n_pick:
                break
    pts = [u[head[j]] for j in picked]
    pose_std = np.full(space.dim, 0.25)
    for col, k in zip(rot_cols, ("alpha", "beta", "gamma")):
        full = space.names.index(k)
        pose_std[col] = 0.5 * spacing / (space.high[full] - space.low[full])
    # 2. the other coordinates at each picked pose, rotation held
    other = [c for c in range(space.dim) if c not in rot_cols]
    left = budget - track.n
    refined: list[tuple[float, np.ndarray]] = []
    per = left // max(len(pts), 1)
    do_refine = bool(other) and per >= 24
    if do_refine:
        for k, p in enumerate(pts):
            def sub(v: np.ndarray, p: np.ndarray = p) -> np.ndarray:
                full = np.repeat(p[None], len(v), axis=0)
                full[:, other] = v
                return track(full)
            r = CMAES(popsize=12, sigma0=0.25, max_restarts=0, explore=0.0, engine=engine).minimize(
                sub, len(other), seed=seed + 7919 * (k + 1), budget=per, starts=p[other][None])
            x = p.copy()
            x[other] = r.x
            refined.append((min(r.fun, float(vals[head[picked[k]]])), x if r.fun < vals[head[picked[k]]] else p))
    else:
        refined = [(float(vals[head[j]]), u[head[j]]) for j in picked]
    refined.sort(key=lambda t: t[0])
    starts = np.stack([x for _, x in refined[:n_starts]])
    stds = pose_std
    if do_refine:  # the other coordinates are already near a fit
        stds = pose_std.copy()
        stds[other] = 0.15
    return {"starts": starts, "stds": stds, "x": np.asarray(track.best_x, float), "fun": float(track.best),
            "n_evals": int(track.n), "trace": list(track.trace), "grid_size": int(len(grid)),
            "spacing": float(spacing), "wall_s": time.perf_counter() - t0}
