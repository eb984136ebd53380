"""What one process does: fit a group of seeds in lockstep and write one part per seed.

Worker processes (spawned, or Dask workers) call :func:`_fit_indices` by reference; :data:`_CTX` holds the
per-process state (seed set, view cache, distance), built once per process.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any, Sequence

import torch

from synthaug.data.seedset import seed_geometry
from synthaug.fit.config import FitConfig, _cfg_json, _warm_cache, patches_tensor, seed_seed
from synthaug.fit.search import fit_together
from synthaug.params import atomic_write_text

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
    ctx = _context(seeds_path, mesh, cfg, distance)
    seeds = ctx["seeds"]
    scale = cfg.object_scale if cfg.object_scale is not None else float(seeds.object_fraction)
    t0 = time.perf_counter()
    camera = cfg.effects is not None and bool(set(cfg.effects) - {"boundary_blur", "motion_blur", "object_noise",
                                                                   "material"})
    if camera and "geometry" not in ctx:  # camera effects may depend on where the patch sits in its frame
        ctx["geometry"] = seed_geometry(seeds)
    geometries = None
    if camera:
        g = ctx["geometry"]
        geometries = [{k: g[k][i:i + 1] for k in ("origin", "frame_size", "frame_scale")} for i in indices]
    idx = list(indices)
    results = fit_together(patches_tensor(seeds.patches[idx]), patches_tensor(seeds.backgrounds[idx]), ctx["cache"],
                           ctx["distance"], cfg, seeds=[seed_seed(cfg.seed, i) for i in idx], object_scale=scale,
                           geometries=geometries)
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
