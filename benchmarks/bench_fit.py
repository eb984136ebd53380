"""Fitting speed and quality: CMA-ES (batched) vs the paper's simulated annealing.

Per seed (40x40, ``hog`` by default, one torch thread): CMA-ES at ``--budget``
evaluations, simulated annealing at the same budget, and simulated annealing
at ``--reference-budget`` (default 10x the budget) as the reference optimum. Reports the median seconds per
seed and how many CMA-ES fits land within 5% of the 10x-annealing distance. With ``--fit-path``, the seeds
are also fitted ``--lockstep`` at a time (``synthaug fit``'s default: the populations of several seeds scored in
one batch, the same fits) and that path's seconds per seed are reported beside the one-at-a-time figure.
``--optimizers cmaes_pycma cmaes`` runs the ``cma`` package's CMA-ES and the numpy one (the default) side by side;
``--opt-seeds 0 1 2`` fits every seed once per optimiser seed (the objective and the reference fixed) and counts
within-5 % over all those fits; ``--reference-cache`` keeps the annealing runs between invocations.

Usage::

    python benchmarks/bench_fit.py --seeds data/halmstad/seedsets/drone_25 --n 8

Without ``--seeds`` (or if the folder is missing) a measured-like seed set is
generated (procedural skies + rendered quadcopter).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path


def _generated_seeds(tmp: Path, n: int) -> Path:
    import numpy as np
    import torch

    from synthaug.data.procedural import sky_backgrounds
    from synthaug.data.seedset import write_seedset
    from synthaug.fit.objective import FitSpace, RenderObjective
    from synthaug.params import CaptureParams
    from synthaug.render.cache import ViewCache

    cache = ViewCache.build("quadcopter")
    bgs = sky_backgrounds(n, (40, 40), seed=0)
    space = FitSpace.default(bounds={"sigma_n": (0, 0.05)})
    patches = []
    g = torch.Generator().manual_seed(0)
    for i in range(n):
        bg = torch.from_numpy(bgs[i:i + 1]).float()[:, None] / 255
        theta = CaptureParams.sample(1, generator=g)
        obj = RenderObjective(bg, bg, cache, None, space, object_scale=0.4, noise_seed=i)
        patches.append(np.round(obj.render(space.from_theta(theta))[0, 0].numpy() * 255).astype(np.uint8))
    path = tmp / "seeds"
    write_seedset(path, patches=np.stack(patches), backgrounds=bgs, boxes=[[0, 0, 16, 16]] * n,
                  centres=[[20, 20]] * n, crops=[[20, 20, 40]] * n, records=[{"video": "gen"}] * n,
                  frames=list(sky_backgrounds(n, (64, 64), seed=1)), background_frames=list(sky_backgrounds(n, (64, 64), seed=1)),
                  metadata={"patch_size": 40, "object_fraction": 0.7})
    return path


def _seed_objective(seeds, i, cache, dist, cfg, scale):
    """Seed i's objective and search space: the fit's bounds, the scale searched in 0.25-1.25 x ``scale``."""
    from synthaug.fit.fitting import patches_tensor, seed_seed
    from synthaug.fit.objective import FitSpace, RenderObjective

    space = FitSpace.default(bounds=dict(cfg.bounds), scale_range=(0.25 * scale, 1.25 * scale))
    obj = RenderObjective(patches_tensor(seeds.patches[i:i + 1]), patches_tensor(seeds.backgrounds[i:i + 1]),
                          cache, dist, space, object_scale=scale, noise_seed=seed_seed(0, i))
    return obj, space


def opt_seed(s: int, k: int) -> int:
    """The optimiser's generator seed of a seed with generator seed ``s`` at optimiser repeat ``k`` (``--opt-seeds``):
    ``s`` itself for k = 0 (the fit ``synthaug fit`` makes), another stream for each k > 0."""
    return s if k == 0 else int((s + 0x9E3779B1 * k) % (2**31 - 1))


def _fit_at(obj, cache, dist, cfg, s: int, k: int, scale: float) -> dict:
    """``synthaug fit``'s fit of one seed (its objective's noise field from ``s``, as always) with the optimiser
    seeded by :func:`opt_seed` (s, k): at k = 0 exactly ``fit_one``; at k > 0 the same objective, another search."""
    from synthaug.fit.search import fit_objective, fit_one, search

    if k == 0:
        return fit_one(obj.target, obj.background, cache, dist, cfg, seed=s, object_scale=scale)
    objective = fit_objective(obj.target, obj.background, cache, dist, cfg, seed=s, object_scale=scale)
    return search(objective, cfg, seed=opt_seed(s, k), object_scale=scale)


def _reference_key(obj, args, name: str, budget: int, s: int) -> str:
    """What a cached annealing run depends on: the seed's patch and background, the distance, mesh, budget,
    generator seed and the annealing's implementation."""
    import hashlib

    from synthaug.fit.optimizers import get_optimizer

    h = hashlib.sha256()
    for t in (obj.target, obj.background):
        h.update(t.numpy().tobytes())
    h.update(json.dumps([name, args.distance, args.mesh, budget, s, obj.object_scale, list(obj.space.free_names()),
                         get_optimizer("anneal").implementation()]).encode())
    return h.hexdigest()[:24]


def _lockstep(seeds, cache, dist, cfg, rows, args, key: str = "cmaes") -> dict:
    """The same seeds fitted ``args.lockstep`` at a time (``synthaug fit``'s path): seconds per seed by repeat,
    and whether every fit equals the one made alone."""
    from synthaug.fit.fitting import patches_tensor, seed_seed
    from synthaug.fit.search import fit_together

    n, k = len(rows), args.lockstep
    scale = float(seeds.object_fraction)
    per_seed, same = [], True
    for _ in range(args.repeats):
        t = time.perf_counter()
        results = []
        for start in range(0, n, k):
            group = list(range(start, min(n, start + k)))
            results += fit_together(patches_tensor(seeds.patches[group]), patches_tensor(seeds.backgrounds[group]),
                                    cache, dist, cfg, seeds=[seed_seed(0, i) for i in group], object_scale=scale)
        per_seed.append((time.perf_counter() - t) / n)
        same &= all(r["distance"] == row[key]["distance"] for r, row in zip(results, rows))
    print(json.dumps({"optimizer": cfg.optimizer, "lockstep": k, "seconds_per_seed": [round(x, 3) for x in per_seed]}),
          file=sys.stderr)
    return {"k": k, "seconds_per_seed_median": round(statistics.median(per_seed), 3),
            "seconds_per_seed_by_repeat": [round(x, 3) for x in per_seed], "same_fits_as_alone": bool(same)}


def _fit_seedset(source: str, tmp: Path, args, optimizer: str = "cmaes") -> dict:
    """Wall seconds per seed of ``fit_seedset(workers=W)`` (``synthaug fit --workers W``, every default) over
    ``--fit-seeds`` seeds, start-up included, by repeat."""
    from synthaug.data.seedset import SeedSet
    from synthaug.fit.fitting import FitConfig, fit_seedset

    seeds_path = source
    if len(SeedSet.load(source)) < args.fit_seeds:
        seeds_path = str(_generated_seeds(tmp / "fit_seedset", args.fit_seeds))
    n = min(args.fit_seeds, len(SeedSet.load(seeds_path)))
    per_seed = []
    for r in range(args.repeats):
        t = time.perf_counter()
        fit_seedset(seeds_path, args.mesh, tmp / f"fit_{optimizer}_w{args.workers}_{r}.json",
                    FitConfig(distance=args.distance, budget=args.budget, optimizer=optimizer), workers=args.workers,
                    indices=range(n))
        per_seed.append((time.perf_counter() - t) / n)
    print(json.dumps({"optimizer": optimizer, "fit_seedset_workers": args.workers,
                      "seconds_per_seed": [round(x, 3) for x in per_seed]}), file=sys.stderr)
    return {"workers": args.workers, "seeds": n, "seconds_per_seed_median": round(statistics.median(per_seed), 3),
            "seconds_per_seed_by_repeat": [round(x, 3) for x in per_seed]}


def _profile(seeds, cache, dist, cfg, scale, args) -> dict:
    """Where one CMA-ES fit's time goes: cProfile's top functions by own time, and the objective's cost per
    evaluation by batch size (a fixed cost per call shows as a falling curve)."""
    import cProfile
    import pstats

    import numpy as np

    from synthaug.fit.fitting import fit_one, seed_seed
    from synthaug.fit.optimizers import get_optimizer

    obj, space = _seed_objective(seeds, 0, cache, dist, cfg, scale)
    rng = np.random.default_rng(0)
    per_eval = {}
    for b in (1, 12, 24, 48, 96):
        u = rng.random((b, space.dim))
        obj(u)
        ts = []
        for _ in range(7):
            t = time.perf_counter()
            obj(u)
            ts.append(time.perf_counter() - t)
        per_eval[str(b)] = round(1e3 * statistics.median(ts) / b, 4)
    prof = cProfile.Profile()
    prof.enable()
    if args.fit_path:
        fit_one(obj.target, obj.background, cache, dist, cfg, seed=seed_seed(0, 0), object_scale=scale)
    else:
        get_optimizer("cmaes").minimize(obj, space.dim, x0=rng.random(space.dim), seed=0, budget=args.budget)
    prof.disable()
    st = pstats.Stats(prof)
    total = st.total_tt
    rows = sorted(st.stats.items(), key=lambda kv: -kv[1][2])[: args.profile]
    return {"objective_ms_per_evaluation_by_batch": per_eval, "fit_seconds_profiled": round(total, 3),
            "top_own_time": [{"function": f"{Path(k[0]).name}:{k[1]}({k[2]})", "own_s": round(v[2], 4),
                              "share": round(v[2] / total, 3), "calls": v[1]} for k, v in rows]}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="data/halmstad/seedsets/drone_25")
    parser.add_argument("--mesh", default="quadcopter")
    parser.add_argument("--distance", default="hog")
    parser.add_argument("--n", type=int, default=8)
    parser.add_argument("--budget", type=int, default=3500, help="CMA-ES (and equal-budget annealing) evaluations")
    parser.add_argument("--optimizers", nargs="+", default=["cmaes"], metavar="NAME",
                        help="the CMA-ES columns, side by side in one run (e.g. cmaes_pycma cmaes: the cma package "
                             "and the numpy engine, the default); the first one's figures are also the top-level keys")
    parser.add_argument("--reference-budget", type=int, default=None,
                        help="evaluations of the reference annealing run (default 10x --budget)")
    parser.add_argument("--fit-path", action="store_true",
                        help="time `synthaug fit`'s own path for CMA-ES (fit_one with FitConfig(distance, budget): the "
                             "rotation-grid start) instead of CMA-ES from the uniform look")
    parser.add_argument("--lockstep", type=int, default=8, metavar="K",
                        help="with --fit-path: also fit the seeds K at a time in lockstep (synthaug fit's default path: "
                             "their populations scored in one batch), --repeats times, and report the seconds per seed "
                             "(group wall time / K) beside the one-at-a-time figure; 0: skip")
    parser.add_argument("--opt-seeds", type=int, nargs="+", default=[0], metavar="K",
                        help="with --fit-path: fit every seed once per K with the optimiser's generator seeded by "
                             "opt_seed(seed, K) (0: the fit synthaug fit makes; the objective, its noise field and the "
                             "reference annealing stay fixed) and count within-5 %% over all of them")
    parser.add_argument("--reference-cache", default=None, metavar="JSON",
                        help="read / add the annealing runs (equal budget and reference) here, keyed by the seed's "
                             "patch, background, distance, budget and the annealing's implementation")
    parser.add_argument("--repeats", type=int, default=3, help="repeats of the lockstep timing (median reported)")
    parser.add_argument("--workers", type=int, default=0, metavar="W",
                        help="also time `synthaug fit`'s whole command path, fit_seedset(workers=W) with its defaults "
                             "(lockstep, process start-up included) on --fit-seeds seeds, --repeats times; 0: skip")
    parser.add_argument("--fit-seeds", type=int, default=32, help="seeds of the --workers timing (generated if needed)")
    parser.add_argument("--profile", type=int, default=0, metavar="K",
                        help="also profile the CMA-ES fit of the first seed (cProfile) and report the K functions "
                             "with the most own time, and the objective's cost per evaluation by batch size")
    args = parser.parse_args()

    import numpy as np
    import torch

    torch.set_num_threads(1)
    from synthaug.data.seedset import SeedSet
    from synthaug.fit.fitting import FitConfig, build_distance, seed_seed
    from synthaug.fit.optimizers import get_optimizer
    from synthaug.render.cache import ViewCache

    tmp = Path(tempfile.mkdtemp())
    source = args.seeds if Path(args.seeds, "seedset.json").exists() else str(_generated_seeds(tmp, args.n))
    seeds = SeedSet.load(source)
    cache = ViewCache.build(args.mesh)
    dist = build_distance(args.distance, seeds)
    cfgs = {o: FitConfig(distance=args.distance, budget=args.budget, optimizer=o) for o in args.optimizers}
    cfg = cfgs[args.optimizers[0]]
    if args.opt_seeds != [0] and not args.fit_path:
        parser.error("--opt-seeds needs --fit-path")
    if len(set(args.opt_seeds)) != len(args.opt_seeds) or min(args.opt_seeds) < 0:
        parser.error("--opt-seeds must be distinct and >= 0")
    cache_path = Path(args.reference_cache) if args.reference_cache else None
    ref_cache = json.loads(cache_path.read_text()) if cache_path is not None and cache_path.exists() else {}
    rows = []
    for i in range(min(args.n, len(seeds))):
        s = seed_seed(0, i)
        scale = float(seeds.object_fraction)
        obj, space = _seed_objective(seeds, i, cache, dist, cfg, scale)
        x0 = np.random.default_rng(s).random(space.dim)
        res = {}
        runs = [(o, o, args.budget) for o in args.optimizers] + [
            ("anneal", "anneal", args.budget), ("anneal_10x", "anneal", args.reference_budget or 10 * args.budget)]
        for name, opt, budget in runs:
            if name in cfgs and args.fit_path:
                by_k = []
                for k in args.opt_seeds:
                    t = time.perf_counter()
                    f = _fit_at(obj, cache, dist, cfgs[name], s, k, scale)
                    by_k.append({"opt_seed": k, "distance": f["distance"], "seconds": time.perf_counter() - t,
                                 "evals": f["stats"]["n_evals"], "restarts": f["stats"]["restarts"]})
                res[name] = dict(by_k[0])
                if args.opt_seeds != [0]:
                    res[name]["by_opt_seed"] = by_k
                continue
            key = _reference_key(obj, args, name, budget, s) if name.startswith("anneal") else None
            if key is not None and key in ref_cache:
                res[name] = dict(ref_cache[key], cached=True)
                continue
            t = time.perf_counter()
            r = get_optimizer(opt).minimize(obj, space.dim, x0=x0, seed=s, budget=budget)
            res[name] = {"distance": r.fun, "seconds": time.perf_counter() - t, "evals": r.n_evals}
            if key is not None and cache_path is not None:
                ref_cache[key] = res[name]
                cache_path.parent.mkdir(parents=True, exist_ok=True)
                cache_path.write_text(json.dumps(ref_cache, indent=1))
        ref = res["anneal_10x"]["distance"]
        for o in args.optimizers:
            res[f"{o}_within_5pct_of_anneal_10x"] = bool(res[o]["distance"] <= 1.05 * ref)
            if "by_opt_seed" in res[o]:
                res[f"{o}_within_5pct_by_opt_seed"] = [bool(r["distance"] <= 1.05 * ref) for r in res[o]["by_opt_seed"]]
        rows.append(res)
        print(json.dumps({"seed": i, **{k: (round(v["distance"], 4), round(v["seconds"], 2)) if isinstance(v, dict) else v
                                         for k, v in res.items()}}), file=sys.stderr)
    med = lambda k, f: statistics.median(r[k][f] for r in rows)  # noqa: E731

    def summary(o: str) -> dict:
        out = {"seconds_median": round(med(o, "seconds"), 3), "distance_median": round(med(o, "distance"), 4),
               "within_5pct_of_anneal_10x": sum(r[f"{o}_within_5pct_of_anneal_10x"] for r in rows),
               "ratio_anneal_over_distance_equal_budget_median": round(statistics.median(
                   r["anneal"]["distance"] / max(r[o]["distance"], 1e-12) for r in rows), 3)}
        if args.opt_seeds != [0]:  # every (seed, optimiser seed) fit
            fits = [(r, f) for r in rows for f in r[o]["by_opt_seed"]]
            ratio = lambda r, f: f["distance"] / r["anneal_10x"]["distance"]  # noqa: E731
            out["opt_seeds"] = list(args.opt_seeds)
            out["within_5pct_of_anneal_10x_all_fits"] = sum(ratio(r, f) <= 1.05 for r, f in fits)
            out["fits"] = len(fits)
            out["distance_over_anneal_10x_median_by_seed"] = [
                round(statistics.median(f["distance"] / r["anneal_10x"]["distance"] for f in r[o]["by_opt_seed"]), 4)
                for r in rows]
            out["distance_over_anneal_10x_median_all_fits"] = round(statistics.median(ratio(r, f) for r, f in fits), 4)
            out["distance_median_all_fits"] = round(statistics.median(f["distance"] for _, f in fits), 4)
            out["seconds_median_all_fits"] = round(statistics.median(f["seconds"] for _, f in fits), 3)
        return out

    first = summary(args.optimizers[0])
    out = {
        "benchmark": "fit", "seeds": source, "distance": args.distance, "budget": args.budget, "n": len(rows),
        "reference_budget": args.reference_budget or 10 * args.budget,
        "torch_threads": 1, "optimizers": list(args.optimizers),
        "cmaes_seconds_median": first["seconds_median"],
        "anneal_seconds_median": round(med("anneal", "seconds"), 3),
        "anneal_10x_seconds_median": round(med("anneal_10x", "seconds"), 3),
        "cmaes_distance_median": first["distance_median"],
        "anneal_distance_median": round(med("anneal", "distance"), 4),
        "anneal_10x_distance_median": round(med("anneal_10x", "distance"), 4),
        "cmaes_within_5pct_of_anneal_10x": first["within_5pct_of_anneal_10x"],
        "ratio_anneal_over_cmaes_distance_equal_budget_median": first["ratio_anneal_over_distance_equal_budget_median"],
        "cmaes_path": "synthaug fit (fit_one, rotation-grid start)" if args.fit_path else "CMA-ES from the uniform look",
        "by_optimizer": {o: summary(o) for o in args.optimizers},
        "per_seed": [{k: v for k, v in r.items()} for r in rows],
    }
    for o in args.optimizers:
        suffix = "" if o == args.optimizers[0] else f"_{o}"
        if args.fit_path and args.lockstep > 0:
            out["lockstep" + suffix] = _lockstep(seeds, cache, dist, cfgs[o], rows, args, key=o)
        if args.workers > 0:
            out["fit_seedset" + suffix] = _fit_seedset(source, tmp, args, optimizer=o)
    if args.profile:
        out["profile"] = _profile(seeds, cache, dist, cfg, scale, args)
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
