"""Per-seed fitting Θ^(i) = argmin_Θ d(X_i, S(Θ, B_i)) over a whole seed set.

:func:`fit_seedset` writes a capture-parameter file (``CaptureParams.save``
format, so :class:`~synthaug.data.synthetic.SyntheticObjectDataset` reads it
directly) with, per seed, the fitted Θ and in ``extra`` the final distance,
the optimiser's statistics and trace, and the seed's provenance.

It is resumable: each finished seed is written atomically to a ``.parts``
folder beside the output; a rerun skips finished seeds, and since every seed
has its own generator seed (a hash of the base seed and the seed index) the
final file is identical whether the run was interrupted or not, and whatever
the number of processes. Runs in-process, on local processes
(``workers > 1``), or on a Dask cluster (``dask_address``).

Every part records a fingerprint of what it depends on (:func:`fit_inputs`:
the seed set's content, the mesh, every :class:`FitConfig` option, the
synthaug version, and a caller-given distance's state); a rerun reuses a part
only when its fingerprint is the current one, and recomputes the others with a
warning naming what changed (another ``--distance``, ``--budget``, seed set...).
Local workers die with their parent (:mod:`synthaug._procs`), so a ``kill -9``
leaves no process behind.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import shutil
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np
import torch

from synthaug._io import digest, sha256_file
from synthaug.data.seedset import seed_geometry
from synthaug.params import FIT_RESULT_FORMAT as RESULT_FORMAT
from synthaug.params import FIT_RESULT_VERSION as RESULT_VERSION
from synthaug.params import CaptureParams, atomic_write_text, effect_param_specs

log = logging.getLogger("synthaug.fit")

INITS = ("uniform", "grid")
OBJECT_NOISE = ("fit", "measured")


@dataclass(frozen=True)
class FitConfig:
    """Options of a fit (stored in the output's metadata).

    Attributes:
        distance: registered distance name (``eucl``, ``hog``, ``wl_random``, ``wl_learned``, ``cnn``...).
        optimizer: ``cmaes`` (default), ``anneal`` (the paper's simulated annealing) or ``random``.
        budget: objective evaluations per seed.
        seed: base seed; seed i uses a hash of (seed, i).
        object_scale: mesh unit length / patch side; None = the seed set's object_fraction.
        effects: effects in Θ (default: the paper's four).
        translation: search range of t_x, t_y around the annotated centre (patch fractions).
        step_deg, sprite_size: view-cache options.
        distance_kwargs: extra arguments of the distance factory.
        fit_scale: also fit the object scale per seed, log-uniform in
            ``scale_range`` × object_scale (an extension of the paper: real
            boxes are often loose, so the object's size in the patch varies).
        scale_range: relative range of the fitted scale.
        bounds: search bounds narrower than the parameters' valid ranges
            (default: σ_n ≤ 0.1, a strong sensor noise for 8-bit video; wider,
            the HOG distance buys gradient energy with noise instead of shape).
        init: how the search starts when no start is given. ``uniform``: the
            optimiser's own start (CMA-ES: a batched uniform look over the whole
            box, then restarts from its best distinct points). ``grid``: a
            structured pose initialisation (:func:`pose_grid_starts`): the
            objective on a near-uniform grid of rotations (t = 0, the default
            scale, capture parameters mid-range), then a short search of the
            other parameters at the best distinct poses; the best ``init_starts``
            become the optimiser's starts. Counted in ``budget``. The default:
            on 24 reference-camera seeds (HOG, benchmarks/bench_fit_init.py) it
            cut the median fitted distance from 1.70 to 1.03 at 800 evaluations
            and from 1.43 to 0.63 at 3500, and the median rotation error from
            73° / 95° to 17° / 8°, at the same cost per seed.
        init_fraction: share of the budget the grid stage spends (grid and refinement).
        init_starts: number of distinct poses handed to the optimiser (first run + restarts).
        object_noise: ``"fit"`` (the paper: σ_n searched like the other parameters) or
            ``"measured"``: σ_n of each seed pinned at its real patch's noise level
            (:func:`~synthaug.fit.noise_level.noise_sigma`, clipped to the σ_n bounds) and not
            searched. A feature distance otherwise buys the gradient energy the coarse render
            lacks with object noise (speckle) that the real patches do not have.
    """

    distance: str = "hog"
    optimizer: str = "cmaes"
    budget: int = 3500
    seed: int = 0
    object_scale: float | None = None
    effects: tuple[str, ...] | None = None
    translation: float = 0.15
    step_deg: float = 5.0
    sprite_size: int = 96
    distance_kwargs: dict[str, Any] = field(default_factory=dict)
    fit_scale: bool = True
    scale_range: tuple[float, float] = (0.25, 1.25)
    bounds: dict[str, tuple[float, float]] = field(default_factory=lambda: {"sigma_n": (0.0, 0.1)})
    init: str = "grid"
    init_fraction: float = 0.35
    init_starts: int = 3
    object_noise: str = "fit"

    def __post_init__(self) -> None:
        if self.budget < 10:
            raise ValueError(f"budget must be >= 10 evaluations, got {self.budget}")
        if self.init not in INITS:
            raise ValueError(f"unknown init {self.init!r}; choose from {list(INITS)}")
        if not 0 < self.init_fraction < 1:
            raise ValueError(f"init_fraction must be in (0, 1), got {self.init_fraction}")
        if self.init_starts < 1:
            raise ValueError(f"init_starts must be >= 1, got {self.init_starts}")
        if self.object_noise not in OBJECT_NOISE:
            raise ValueError(f"unknown object_noise {self.object_noise!r}; choose from {list(OBJECT_NOISE)}")

        if self.object_scale is not None and not 0 < self.object_scale <= 1.5:
            raise ValueError(f"object_scale must be in (0, 1.5], got {self.object_scale}")
        if self.effects is not None:  # unknown names fail now, not after the first expensive step
            try:
                CaptureParams.vector_names(effects=self.effects)
            except ValueError as e:
                raise ValueError(f"effects: {e}") from None
        from synthaug.fit.optimizers import list_optimizers

        if self.optimizer not in list_optimizers():
            raise ValueError(f"unknown optimizer {self.optimizer!r}; choose from {list_optimizers()}")


def seed_seed(base: int, index: int) -> int:
    from synthaug.data.synthetic import item_seed

    return item_seed(base, 0x5EED, index) % (2**31 - 1)


def patches_tensor(a: np.ndarray) -> torch.Tensor:
    """uint8 (N, P, P) -> float32 (N, 1, P, P) in [0, 1]."""
    return torch.from_numpy(np.asarray(a, np.float32) / 255.0)[:, None]


def build_distance(name: str, seeds: Any | None = None, *, seed: int = 0, **kwargs: Any) -> Any:
    """A registered distance, trained on the seed set where it needs data (``wl_learned``, ``cnn``).

    Raises:
        ValueError: unknown name (listing the known ones), or a data-hungry
            distance without a seed set / negatives.
    """
    from synthaug.distances import get_distance, get_entry, list_distances

    try:
        entry = get_entry(name)
    except (KeyError, ValueError):
        raise ValueError(f"unknown distance {name!r}; registered: {list_distances()}") from None
    kw = dict(kwargs)
    if entry.needs_fit and not {"net", "checkpoint", "detector", "positives"} & set(kw):
        if seeds is None:
            raise ValueError(f"distance {name!r} is trained on the seeds: give a seed set")
        if len(seeds.negatives) == 0:
            raise ValueError(f"distance {name!r} needs negatives, and the seed set has none")
        kw.setdefault("positives", patches_tensor(seeds.patches))
        kw.setdefault("negatives", patches_tensor(seeds.negatives))
        kw.setdefault("seed", seed)
    elif name.startswith("wl_random") and seeds is not None:
        kw.setdefault("reference", patches_tensor(seeds.patches))
        kw.setdefault("seed", seed)
    return get_distance(name, **kw)


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
    n_init = int(cfg.init_fraction * cfg.budget)
    rotations_free = {"alpha", "beta", "gamma"} <= set(space.free_names())
    if x0 is None and cfg.init == "grid" and n_init >= 16 and rotations_free:
        init = pose_grid_starts(evaluate, space, budget=n_init,
                                object_scale=object_scale, n_starts=cfg.init_starts, seed=seed)
    elif x0 is None:
        x0 = np.random.default_rng(seed).random(space.dim)
        names = space.free_names()
        for k in ("t_x", "t_y", "object_scale"):
            if k in names:
                x0[names.index(k)] = 0.5  # the annotated centre, the middle of the scale range
    opt = get_optimizer(cfg.optimizer)
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
                     n_refine: int | None = None) -> dict[str, Any]:
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
            r = CMAES(popsize=12, sigma0=0.25, max_restarts=0, explore=0.0).minimize(
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


# --------------------------------------------------------------- workers
_CTX: dict[str, Any] = {}


def _context(seeds_path: str, mesh: Any, cfg: FitConfig, distance: Any, *, seeds: Any = None,
             cache: Any = None) -> dict[str, Any]:
    """Per-process state (seed set, view cache, distance), built once per process.

    ``seeds`` / ``cache`` hand over objects the caller already loaded (in-process
    runs). The distance is refreshed on every call: it is not part of the key,
    and a caller may pass a new one with the same configuration (the d_CNN refit).
    """
    key = json.dumps([seeds_path, str(mesh), _cfg_json(cfg)], sort_keys=True, default=str)
    if _CTX.get("key") != key:
        from synthaug.data.seedset import SeedSet

        torch.set_num_threads(1)
        _CTX.clear()
        _CTX.update(key=key, seeds=seeds if seeds is not None else SeedSet.load(seeds_path),
                    cache=cache if cache is not None else _warm_cache(mesh, cfg))
    _CTX["distance"] = distance
    return _CTX


def _fit_indices(indices: Sequence[int], seeds_path: str, mesh: Any, cfg: FitConfig, distance: Any, parts: str,
                 fingerprint: dict[str, Any] | None = None) -> list[int]:
    """Fit the seeds ``indices`` in lockstep (:mod:`synthaug.fit.lockstep`) and write one part per seed."""
    from synthaug.fit.lockstep import run_lockstep

    ctx = _context(seeds_path, mesh, cfg, distance)
    seeds = ctx["seeds"]
    scale = cfg.object_scale if cfg.object_scale is not None else float(seeds.object_fraction)
    t0 = time.perf_counter()
    camera = cfg.effects is not None and bool(set(cfg.effects) - {"boundary_blur", "motion_blur", "object_noise",
                                                                   "material"})
    if camera and "geometry" not in ctx:  # camera effects may depend on where the patch sits in its frame
        ctx["geometry"] = seed_geometry(seeds)
    objectives, searches = [], []
    for index in indices:
        s = seed_seed(cfg.seed, index)
        geometry = None
        if camera:
            g = ctx["geometry"]
            geometry = {k: g[k][index:index + 1] for k in ("origin", "frame_size", "frame_scale")}
        objective = fit_objective(patches_tensor(seeds.patches[index:index + 1]),
                                  patches_tensor(seeds.backgrounds[index:index + 1]), ctx["cache"], ctx["distance"],
                                  cfg, seed=s, object_scale=scale, geometry=geometry)
        objectives.append(objective)
        searches.append(lambda evaluate, o=objective, s=s: search(o, cfg, seed=s, object_scale=scale,
                                                                    evaluate=evaluate))
    results = run_lockstep(objectives, searches)
    seconds = round((time.perf_counter() - t0) / max(len(indices), 1), 3)
    for index, res in zip(indices, results):
        res["stats"]["seconds"] = seconds  # the group's wall time per seed
        res["index"] = index
        res["generator_seed"] = seed_seed(cfg.seed, index)
        if fingerprint is not None:  # what the part depends on: a rerun with other inputs recomputes it
            res["fingerprint"] = fingerprint["digest"]
            res["inputs"] = fingerprint["inputs"]
        atomic_write_text(Path(parts) / f"seed_{index:05d}.json", json.dumps(res))
    return list(indices)


def _groups(todo: Sequence[int], size: int) -> list[list[int]]:
    return [list(todo[i:i + size]) for i in range(0, len(todo), size)]


def _cfg_json(cfg: FitConfig) -> dict[str, Any]:
    d = asdict(cfg)
    d["effects"] = list(cfg.effects) if cfg.effects is not None else None
    if d["object_noise"] == "fit":  # added later: absent at the paper's setting, so earlier fits stay current
        d.pop("object_noise")
    return d


def _hash_object(h: Any, x: Any, depth: int = 0) -> None:
    """Feed a deterministic description of ``x`` (tensors and arrays by value) into the hash ``h``."""
    if isinstance(x, torch.nn.Module):  # parameters, buffers, submodules and plain attributes (learners...)
        h.update(f"module:{type(x).__module__}.{type(x).__qualname__}".encode())
        _hash_object(h, {k: v for k, v in vars(x).items() if "hook" not in k}, depth + 1)
        return
    if isinstance(x, torch.Tensor):
        t = x.detach().cpu().contiguous()
        h.update(f"tensor:{t.dtype}:{tuple(t.shape)}".encode())
        h.update(t.view(torch.uint8).numpy().tobytes() if t.numel() else b"")
        return
    if isinstance(x, np.ndarray):
        a = np.ascontiguousarray(x)
        h.update(f"array:{a.dtype}:{a.shape}".encode())
        if a.dtype != object:
            h.update(a.tobytes())
            return
        x = a.tolist()
    if x is None or isinstance(x, (bool, int, float, str, bytes)):
        h.update(repr(x).encode())
    elif isinstance(x, dict):
        h.update(b"{")
        for k in sorted(x, key=str):
            h.update(str(k).encode())
            _hash_object(h, x[k], depth + 1)
        h.update(b"}")
    elif isinstance(x, (list, tuple, set, frozenset)):
        h.update(b"[")
        for v in (sorted(x, key=repr) if isinstance(x, (set, frozenset)) else x):
            _hash_object(h, v, depth + 1)
        h.update(b"]")
    elif callable(x) and hasattr(x, "__qualname__") and not hasattr(x, "__dict__"):
        h.update(f"fn:{getattr(x, '__module__', '')}.{x.__qualname__}".encode())
    else:
        h.update(f"obj:{type(x).__module__}.{type(x).__qualname__}".encode())
        if depth < 24 and hasattr(x, "__dict__"):
            _hash_object(h, {k: v for k, v in vars(x).items() if not k.startswith("__")}, depth + 1)


def object_digest(x: Any) -> str:
    """SHA-256 of an object's state (a prebuilt distance: its networks' weights, its arrays, its options)."""
    h = hashlib.sha256()
    _hash_object(h, x)
    return h.hexdigest()[:20]


def seedset_digest(seeds_path: str | os.PathLike) -> str:
    """SHA-256 of a seed set's header and arrays (``seedset.json`` + ``arrays.npz``): what a fit reads."""
    from synthaug.data.seedset import ARRAYS, HEADER

    root = Path(seeds_path)
    return digest({name: sha256_file(root / name) for name in (HEADER, ARRAYS) if (root / name).is_file()},
                  length=64)


def mesh_digest(mesh: Any) -> str:
    """SHA-256 of a mesh file's bytes, ``builtin:<name>`` for a built-in mesh, of the arrays for a Trimesh."""
    from synthaug.render.mesh import BUILTIN_MESHES

    if isinstance(mesh, str) and mesh in BUILTIN_MESHES:  # as load_mesh: the name wins over a file
        return f"builtin:{mesh}"
    if isinstance(mesh, (str, os.PathLike)):
        return sha256_file(mesh)
    return object_digest({"vertices": np.asarray(mesh.vertices), "faces": np.asarray(mesh.faces)})


def fit_inputs(seeds_path: str | os.PathLike, mesh: Any, cfg: FitConfig, distance: Any = None) -> dict[str, Any]:
    """Everything a per-seed fit depends on: the seed set's content, the mesh, every option, the synthaug
    version, and the state of a caller-given distance (None: built from ``cfg`` and the seeds)."""
    from synthaug import __version__

    out = {"seedset_sha256": seedset_digest(seeds_path), "mesh_sha256": mesh_digest(mesh), "config": _cfg_json(cfg),
           "synthaug_version": __version__}
    if distance is not None:
        out["distance_object"] = object_digest(distance)
    return out


_INPUT_NAMES = {"seedset_sha256": "the seed set's content", "mesh_sha256": "the mesh",
                "synthaug_version": "the synthaug version", "distance_object": "the given distance object"}


def what_changed(old: dict[str, Any] | None, new: dict[str, Any]) -> str:
    """A short human description of how two :func:`fit_inputs` differ (``""`` when they are equal)."""
    if not isinstance(old, dict):
        return "it records no fingerprint (written by an older synthaug)"
    diffs = []
    oc, nc = old.get("config", {}) or {}, new.get("config", {}) or {}
    for k in sorted(set(oc) | set(nc)):
        if oc.get(k) != nc.get(k):
            diffs.append(f"{k} {json.dumps(oc.get(k), default=str)} -> {json.dumps(nc.get(k), default=str)}")
    for k in ("seedset_sha256", "mesh_sha256", "synthaug_version", "distance_object"):
        if old.get(k) != new.get(k):
            what = _INPUT_NAMES[k]
            if k == "synthaug_version":
                what += f" {old.get(k)} -> {new.get(k)}"
            diffs.append(what)
    return ", ".join(diffs)


def _read_part(path: Path) -> dict[str, Any] | None:
    try:
        doc = json.loads(path.read_text())
        return doc if isinstance(doc, dict) and "theta" in doc else None
    except (OSError, ValueError):
        return None


def _check_parts(parts: Path, fingerprint: dict[str, Any]) -> set[int]:
    """The indices of the parts that may be reused; the others (other inputs, unreadable) are removed, with a
    warning naming what changed."""
    fp = fingerprint["digest"]
    config = parts / "config.json"
    if config.is_file():
        try:
            old = json.loads(config.read_text())
        except (OSError, ValueError):
            old = None
        old_inputs = old.get("inputs") if isinstance(old, dict) else None
        if not isinstance(old, dict) or old.get("fingerprint") != fp:
            why = what_changed(old_inputs, fingerprint["inputs"]) or "its config file is unreadable"
            log.warning("synthaug fit: %s holds an interrupted run with other inputs (%s)", parts, why)
    done: set[int] = set()
    stale: dict[str, list[int]] = {}
    for p in sorted(parts.glob("seed_*.json")):
        try:
            i = int(p.stem.split("_")[1])
        except (IndexError, ValueError):
            continue
        doc = _read_part(p)
        if doc is not None and doc.get("fingerprint") == fp:
            done.add(i)
            continue
        why = "unreadable" if doc is None else what_changed(doc.get("inputs"), fingerprint["inputs"])
        stale.setdefault(why or "another fingerprint", []).append(i)
        p.unlink(missing_ok=True)
    for why, idx in stale.items():
        shown = ", ".join(map(str, idx[:8])) + (", ..." if len(idx) > 8 else "")
        log.warning("synthaug fit: recomputing %d finished seed(s) [%s] of an earlier run in %s: %s",
                    len(idx), shown, parts, why)
    atomic_write_text(config, json.dumps({"fingerprint": fp, "inputs": fingerprint["inputs"]}, indent=1,
                                         default=str))
    return done


def fit_seedset(
    seeds_path: str | os.PathLike,
    mesh: Any,
    out_path: str | os.PathLike,
    cfg: FitConfig = FitConfig(),
    *,
    workers: int = 1,
    dask_address: str | None = None,
    indices: Sequence[int] | None = None,
    progress: bool | Callable[[int, int], None] = False,
    distance: Any = None,
    lockstep: int = 8,
) -> Path:
    """Fit every seed of a seed set and write the capture-parameter file.

    Args:
        seeds_path: seed-set folder (``synthaug ingest`` output).
        mesh: mesh path or built-in name.
        out_path: output JSON (capture-parameter format, plus per-seed extras).
        cfg: fit options.
        workers: local processes (1 = in this process).
        dask_address: a Dask scheduler address (``tcp://...``), or a
            ``distributed.Client`` / ``LocalCluster`` object; overrides ``workers``.
        indices: fit only these seeds (default: all).
        progress: show a tqdm bar (True) or call ``progress(done, total)``.
        distance: a prebuilt distance (default: :func:`build_distance` on the seeds).
        lockstep: seeds fitted together in one process, their optimisers' populations scored in one batch
            (:mod:`synthaug.fit.lockstep`; the fits are the same as one at a time, only faster: issue 19).

    Returns:
        the output path.
    """
    from synthaug.data.seedset import SeedSet

    if not isinstance(lockstep, int) or isinstance(lockstep, bool) or lockstep < 1:
        raise ValueError(f"lockstep must be an int >= 1, got {lockstep!r}")
    seeds_path = str(Path(seeds_path))
    seeds = SeedSet.load(seeds_path)  # validates the seed set (clear errors) before any work
    n = len(seeds)
    if n == 0:
        raise ValueError(f"seed set {seeds_path} holds no seeds")
    todo_all = list(range(n)) if indices is None else sorted({int(i) for i in indices})
    bad = [i for i in todo_all if not 0 <= i < n]
    if bad:
        raise ValueError(f"seed indices out of range for {n} seeds: {bad[:5]}")
    from synthaug.render.mesh import load_mesh

    load_mesh(mesh)  # a missing/corrupt mesh fails here, naming the file
    if seeds.patches.shape[-1] < 16:
        raise ValueError(f"seed patches of {seeds.patches.shape[-1]} px are too small to fit")
    out = Path(out_path)
    if out.is_dir():
        raise ValueError(f"the output {out} is a directory; give the path of a JSON file (--out)")
    if isinstance(dask_address, str):
        _probe_dask(dask_address)  # a dead or malformed scheduler address fails before the distance is built
    # a caller-given distance is hashed as given (a built one follows from cfg and the seed set)
    inputs = fit_inputs(seeds_path, mesh, cfg, distance)
    if distance is None:
        distance = build_distance(cfg.distance, seeds, seed=cfg.seed, **cfg.distance_kwargs)
    fingerprint = {"digest": digest(inputs), "inputs": inputs}
    cache = _warm_cache(mesh, cfg)  # checks step_deg / sprite_size; sprites built once before workers load them
    client = _dask_client(dask_address) if isinstance(dask_address, str) else dask_address  # a dead one fails now
    parts = out.parent / f".{out.name}.parts"
    fresh = not parts.exists()
    try:
        parts.mkdir(parents=True, exist_ok=True)
        _fit_parts(seeds, seeds_path, mesh, cfg, distance, parts, out, fingerprint, todo_all, cache, workers=workers,
             dask_address=client, progress=progress, lockstep=lockstep)
    except BaseException:
        if fresh and not any(parts.glob("seed_*.json")):  # nothing to resume: leave nothing behind
            shutil.rmtree(parts, ignore_errors=True)
        raise
    finally:
        if client is not None and client is not dask_address:
            client.close()
    if indices is None:
        shutil.rmtree(parts, ignore_errors=True)
    return out


def _fit_parts(seeds: Any, seeds_path: str, mesh: Any, cfg: FitConfig, distance: Any, parts: Path, out: Path,
         fingerprint: dict[str, Any], todo_all: list[int], cache: Any, *, workers: int,
         dask_address: Any, progress: bool | Callable[[int, int], None], lockstep: int = 1) -> None:
    """Fit the seeds not finished yet (of ``todo_all``) into ``parts``, ``lockstep`` at a time, then assemble ``out``."""
    done = _check_parts(parts, fingerprint)
    todo = [i for i in todo_all if i not in done]
    bar = None
    if progress is True:
        from tqdm import tqdm

        bar = tqdm(total=len(todo_all), initial=len(todo_all) - len(todo), unit="seed", desc=f"fit {cfg.distance}")

    def tick() -> None:
        if bar is not None:
            bar.update(1)
        elif callable(progress):
            progress(len({int(p.stem.split("_")[1]) for p in parts.glob("seed_*.json")}), len(todo_all))

    if dask_address is not None:
        _run_dask(dask_address, todo, seeds_path, mesh, cfg, distance, str(parts), tick, fingerprint,
                  lockstep=lockstep)
    elif workers <= 1:
        # one thread, as in worker processes (same floating-point results); the caller's setting is restored
        threads = torch.get_num_threads()
        try:
            _context(seeds_path, mesh, cfg, distance, seeds=seeds, cache=cache)
            for group in _groups(todo, lockstep):
                for _ in _fit_indices(group, seeds_path, mesh, cfg, distance, str(parts), fingerprint):
                    tick()
        finally:
            torch.set_num_threads(threads)
    else:
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor, as_completed

        from synthaug._procs import pool_kwargs

        # workers die with this process (a kill -9 of the command leaves nothing running)
        with ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn"), **pool_kwargs()) as ex:
            futs = [ex.submit(_fit_indices, group, seeds_path, mesh, cfg, distance, str(parts), fingerprint)
                    for group in _groups(todo, min(lockstep, -(-len(todo) // workers)))]
            for f in as_completed(futs):
                for _ in f.result():
                    tick()
    if bar is not None:
        bar.close()
    _assemble(seeds, todo_all, cfg, mesh, seeds_path, parts, out, fingerprint["digest"])


def _warm_cache(mesh: Any, cfg: FitConfig) -> Any:
    from synthaug.render.cache import ViewCache

    return ViewCache.build(mesh, step_deg=cfg.step_deg, sprite_size=cfg.sprite_size)


def _probe_dask(address: str, *, timeout_s: float = 10.0) -> None:
    """Fail at once, naming ``--dask``, when ``address`` cannot be a live scheduler: ``distributed`` is missing,
    or a ``tcp://host:port`` address is malformed or refuses a plain socket (known in milliseconds, where a
    ``distributed.Client`` would retry for 30 s)."""
    import importlib.util
    import socket
    from urllib.parse import urlsplit

    if importlib.util.find_spec("distributed") is None:
        raise ValueError("--dask needs the 'distributed' package (pip install distributed)")
    parsed = urlsplit(address if "://" in address else f"tcp://{address}")
    if parsed.scheme != "tcp":
        return
    try:
        host, port = parsed.hostname, parsed.port
    except ValueError:
        host, port = None, None
    if not host or port is None:
        raise ValueError(f"--dask: {address!r} is not a scheduler address (tcp://HOST:PORT)")
    try:
        socket.create_connection((host, port), timeout=timeout_s).close()
    except OSError as e:
        raise ValueError(f"--dask: no Dask scheduler answers at {address} ({e.strerror or e})") from None


def _dask_client(address: str, *, timeout_s: float = 10.0) -> Any:
    """A ``distributed.Client`` on ``address`` (probed first by :func:`_probe_dask`), connected within
    ``timeout_s``; errors name ``--dask``."""
    _probe_dask(address, timeout_s=timeout_s)
    from distributed import Client

    try:
        return Client(address, timeout=f"{timeout_s}s")
    except (OSError, TimeoutError, ValueError) as e:
        raise ValueError(f"--dask: cannot connect to the Dask scheduler at {address} ({e})") from None


def _run_dask(address: Any, todo: list[int], seeds_path: str, mesh: Any, cfg: FitConfig, distance: Any,
              parts: str, tick: Callable[[], None], fingerprint: dict[str, Any] | None = None, *,
              lockstep: int = 1) -> None:
    from distributed import Client, as_completed

    own = isinstance(address, str)
    client = Client(address) if own else (address if isinstance(address, Client) else Client(address))
    try:
        dist_f = client.scatter(distance, broadcast=True)
        futs = [client.submit(_fit_indices, group, seeds_path, mesh, cfg, dist_f, parts, fingerprint, pure=False)
                for group in _groups(todo, lockstep)]
        for f in as_completed(futs):
            for _ in f.result():
                tick()
    finally:
        if own or not isinstance(address, Client):
            client.close()


def _assemble(seeds: Any, indices: list[int], cfg: FitConfig, mesh: Any, seeds_path: str, parts: Path,
              out: Path, fingerprint: str | None = None) -> None:
    rows, extra, timing = [], [], []
    for i in indices:
        res = json.loads((parts / f"seed_{i:05d}.json").read_text())
        if fingerprint is not None and res.get("fingerprint") != fingerprint:  # another run wrote it meanwhile
            raise RuntimeError(f"{parts / f'seed_{i:05d}.json'} was written by a run with other inputs "
                               f"while this one ran (two runs into the same --out?); rerun the command")
        rows.append(res["theta"])
        rec = seeds.records[i] if i < len(seeds.records) else {}
        stats = dict(res["stats"])
        # wall-clock figures go to a side file: the fit file itself is reproducible byte for byte
        timing.append({"seed_index": i, "seconds": stats.pop("seconds", None), "wall_s": stats.pop("wall_s", None),
                       "init_wall_s": stats.pop("init_wall_s", None)})
        extra.append({"seed_index": i, "distance": res["distance"], "generator_seed": res["generator_seed"],
                      "object_scale": res["object_scale"],
                      "optimizer": stats, "video": rec.get("video"), "frame": rec.get("frame"),
                      "class": rec.get("class")})
    channels = 1
    theta = CaptureParams.from_vector(torch.tensor(rows, dtype=torch.float64), channels=channels,
                                      effects=cfg.effects)
    meta = {"result_format": RESULT_FORMAT, "result_version": RESULT_VERSION, "config": _cfg_json(cfg),
            "seeds": seeds_path, "mesh": str(mesh),
            **({"inputs_fingerprint": fingerprint} if fingerprint is not None else {}),
            "object_scale": cfg.object_scale if cfg.object_scale is not None else float(seeds.object_fraction),
            "distance_median": float(np.median([e["distance"] for e in extra]))}
    theta.save(out, extra=extra, metadata=meta)
    secs = [t["seconds"] for t in timing if t["seconds"] is not None]
    atomic_write_text(out.with_name(out.stem + ".timing.json"), json.dumps(
        {"median_seconds_per_seed": float(np.median(secs)) if secs else None, "per_seed": timing}, indent=1))
