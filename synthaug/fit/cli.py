"""``synthaug fit``: seed set + mesh + distance -> capture-parameter file.

Example::

    synthaug fit --seeds data/halmstad/seedsets/drone_25 --mesh ../shared/data/meshes/quadcopter.glb \\
        --distance hog --out fits/drone_25_hog.json --workers 2
"""

from __future__ import annotations

import argparse
import json
import sys


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from synthaug._checks import float_in, int_at_least, positive_int

    # numbers are checked as they are parsed: a bad one exits 2 at once, naming the option
    parser.add_argument("--seeds", required=True, help="seed-set folder (synthaug ingest output)")
    parser.add_argument("--mesh", default="quadcopter", help="mesh file or built-in name")
    parser.add_argument("--distance", default="hog", help="eucl, hog, wl_random, wl_learned, cnn (or a *_smooth)")
    parser.add_argument("--out", required=True, help="output capture-parameter JSON")
    parser.add_argument("--optimizer", default="cmaes", choices=["cmaes", "anneal", "random"],
                        help="search: CMA-ES, the paper's simulated annealing, or random search")
    parser.add_argument("--budget", type=int_at_least(10), default=3500,
                        help="objective evaluations per seed (3500 ≈ 1.9 s on one core here)")
    parser.add_argument("--seed", type=int, default=0, help="seeds the search of every seed image")
    parser.add_argument("--init", default=None, choices=["uniform", "grid"],
                        help="start of the search: 'grid' = a rotation grid, then a short search of the other "
                             "parameters at its best poses (counted in the budget); 'uniform' = CMA-ES's "
                             "uniform look (the paper's random start; default: grid)")
    parser.add_argument("--object-scale", type=float_in(0, 1.5, low_open=True), default=None,
                        help="mesh size / patch side (default: the seed set's object_fraction)")
    parser.add_argument("--effects", nargs="*", default=None, help="effects in Θ (default: the paper's four)")
    parser.add_argument("--no-fit-scale", action="store_true", help="keep the object scale fixed (the paper)")
    parser.add_argument("--step-deg", type=float_in(0.1, 45), default=5.0, help="view-cache grid step (degrees)")
    parser.add_argument("--sprite-size", type=int_at_least(8), default=96, help="view-cache sprite side (px)")
    parser.add_argument("--workers", type=positive_int, default=1, help="local processes")
    parser.add_argument("--dask", default=None, help="Dask scheduler address, e.g. tcp://127.0.0.1:8786")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


def main(args: argparse.Namespace) -> int:
    from synthaug._checks import check_output_file, check_seedset_dir
    from synthaug.distances.registry import check_distance
    from synthaug.fit.fitting import FitConfig, fit_seedset
    from synthaug.params import CaptureParams

    try:
        check_seedset_dir(args.seeds)
        check_output_file(args.out)
        check_distance(args.distance)
        if args.effects:
            try:
                CaptureParams.vector_names(effects=args.effects)
            except ValueError as e:
                raise ValueError(f"--effects: {e}") from None
        cfg = FitConfig(distance=args.distance, optimizer=args.optimizer, budget=args.budget, seed=args.seed,
                        object_scale=args.object_scale, effects=tuple(args.effects) if args.effects else None,
                        fit_scale=not args.no_fit_scale, step_deg=args.step_deg, sprite_size=args.sprite_size,
                        **({"init": args.init} if args.init else {}))
        out = fit_seedset(args.seeds, args.mesh, args.out, cfg, workers=args.workers, dask_address=args.dask,
                          progress=not args.no_progress)
    except (ValueError, FileNotFoundError) as e:
        print(f"synthaug fit: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("synthaug fit: interrupted; rerun the same command to resume", file=sys.stderr)
        return 130
    doc = json.loads(out.read_text())
    print(json.dumps({"out": str(out), "seeds": len(doc["rows"]),
                      "distance_median": doc["metadata"]["distance_median"]}))
    return 0
