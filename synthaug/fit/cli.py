"""``synthaug fit``: seed set + mesh + distance -> capture-parameter file.

Example::

    synthaug fit --seed-set data/halmstad/seedsets/drone_25 --mesh ../shared/data/meshes/quadcopter.glb \\
        --distance hog --out fits/drone_25_hog.json --workers 2
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from synthaug.fit.config import FitConfig


def _bound(text: str) -> tuple[str, tuple[float, float]]:
    """An argparse type: ``NAME=LOW,HIGH`` (a search bound of one capture parameter)."""
    from synthaug._checks import finite_float

    name, sep, rest = text.partition("=")
    parts = rest.split(",")
    if not sep or not name or len(parts) != 2:
        raise argparse.ArgumentTypeError(f"must be NAME=LOW,HIGH (e.g. sigma_n=0,0.1), got {text!r}")
    low, high = (finite_float(v) for v in parts)
    if not low < high:
        raise argparse.ArgumentTypeError(f"LOW must be < HIGH, got {text!r}")
    return name, (low, high)


def _json_object(text: str) -> dict:
    """An argparse type: a JSON object (``'{"cell": 8}'``)."""
    try:
        value = json.loads(text)
    except json.JSONDecodeError as e:
        raise argparse.ArgumentTypeError(f"must be a JSON object, got {text!r} ({e.msg})") from None
    if not isinstance(value, dict):
        raise argparse.ArgumentTypeError(f"must be a JSON object, got {text!r}")
    return value


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from synthaug._checks import (add_option, dataclass_defaults, float_in, int_at_least, nonneg_float,
                                  open_unit_float, positive_float, positive_int)
    from synthaug.fit.config import INITS, OBJECT_NOISE, FitConfig
    from synthaug.fit.optimizers import list_optimizers

    d = dataclass_defaults(FitConfig)  # every FitConfig field is an option here, with the dataclass's default
    # numbers are checked as they are parsed: a bad one exits 2 at once, naming the option
    add_option(parser, "--seed-set", aliases=["--seeds"], required=True,
               help="seed-set folder (synthaug ingest output)")
    parser.add_argument("--mesh", default="quadcopter", help="mesh file or built-in name")
    parser.add_argument("--distance", default=d["distance"],
                        help="eucl, hog, wl_random, wl_learned, cnn (or a *_smooth)")
    parser.add_argument("--distance-kwargs", type=_json_object, default=d["distance_kwargs"], metavar="JSON",
                        help="extra arguments of the distance factory, a JSON object")
    parser.add_argument("--out", required=True, help="output capture-parameter JSON")
    parser.add_argument("--optimizer", default=d["optimizer"], choices=list_optimizers(),
                        help="search: CMA-ES, the paper's simulated annealing, or random search")
    parser.add_argument("--budget", type=int_at_least(10), default=d["budget"],
                        help="objective evaluations per seed (3500 ≈ 1.9 s on one core here)")
    parser.add_argument("--seed", type=int, default=d["seed"], help="seeds the search of every seed image")
    parser.add_argument("--init", default=d["init"], choices=list(INITS),
                        help="start of the search: 'grid' = a rotation grid, then a short search of the other "
                             "parameters at its best poses (counted in the budget); 'uniform' = CMA-ES's "
                             "uniform look (the paper's random start)")
    parser.add_argument("--init-fraction", type=open_unit_float, default=d["init_fraction"],
                        help="share of the budget the grid start spends, in (0, 1)")
    parser.add_argument("--init-starts", type=positive_int, default=d["init_starts"],
                        help="distinct start poses handed to the optimiser (first run + restarts)")
    parser.add_argument("--object-noise", default=d["object_noise"], choices=list(OBJECT_NOISE),
                        help="'fit': σ_n searched (the paper); 'measured': σ_n of each seed pinned at its patch's "
                             "noise level (no speckle bought by the distance)")
    parser.add_argument("--object-scale", type=float_in(0, 1.5, low_open=True), default=d["object_scale"],
                        help="mesh size / patch side (default: the seed set's object_fraction)")
    parser.add_argument("--effects", nargs="*", default=d["effects"], help="effects in Θ (default: the paper's four)")
    parser.add_argument("--translation", type=nonneg_float, default=d["translation"],
                        help="search range of t_x, t_y around the annotated centre (patch fractions)")
    parser.add_argument("--fit-scale", action=argparse.BooleanOptionalAction, default=d["fit_scale"],
                        help="fit the object scale per seed too (the default); --no-fit-scale keeps it fixed (the paper)")
    parser.add_argument("--scale-range", type=positive_float, nargs=2, default=d["scale_range"],
                        metavar=("LOW", "HIGH"), help="relative range of the fitted scale (× object scale)")
    parser.add_argument("--bounds", type=_bound, nargs="*", default=d["bounds"],
                        metavar="NAME=LOW,HIGH",
                        help="search bounds narrower than the parameters' valid ranges (none given: no narrowing)")
    parser.add_argument("--step-deg", type=float_in(0.1, 45), default=d["step_deg"],
                        help="view-cache grid step (degrees)")
    parser.add_argument("--sprite-size", type=int_at_least(8), default=d["sprite_size"],
                        help="view-cache sprite side (px)")
    parser.add_argument("--workers", type=positive_int, default=1, help="local processes")
    parser.add_argument("--lockstep", type=positive_int, default=8,
                        help="seeds fitted together per process, their populations scored in one batch (the same fits, "
                             "faster; 1: one at a time)")
    parser.add_argument("--dask", default=None, help="Dask scheduler address, e.g. tcp://127.0.0.1:8786")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


def config_from_args(args: argparse.Namespace) -> FitConfig:
    """The :class:`~synthaug.fit.config.FitConfig` the parsed options describe."""
    from synthaug.fit.config import FitConfig

    if args.scale_range[0] >= args.scale_range[1]:
        raise ValueError(f"--scale-range: LOW must be < HIGH, got {args.scale_range}")
    return FitConfig(distance=args.distance, optimizer=args.optimizer, budget=args.budget, seed=args.seed,
                     object_scale=args.object_scale, effects=tuple(args.effects) if args.effects else None,
                     translation=args.translation, step_deg=args.step_deg, sprite_size=args.sprite_size,
                     distance_kwargs=dict(args.distance_kwargs), fit_scale=args.fit_scale,
                     scale_range=tuple(args.scale_range), bounds=dict(args.bounds), init=args.init,
                     init_fraction=args.init_fraction, init_starts=args.init_starts, object_noise=args.object_noise)


def main(args: argparse.Namespace) -> int:
    from synthaug._checks import check_output_file, check_seedset_dir
    from synthaug.distances.registry import check_distance
    from synthaug.fit.run import fit_seedset
    from synthaug.params import CaptureParams

    try:
        check_seedset_dir(args.seed_set)
        check_output_file(args.out)
        check_distance(args.distance)
        if args.effects:
            try:
                CaptureParams.vector_names(effects=args.effects)
            except ValueError as e:
                raise ValueError(f"--effects: {e}") from None
        cfg = config_from_args(args)
        out = fit_seedset(args.seed_set, args.mesh, args.out, cfg, workers=args.workers, dask_address=args.dask,
                          lockstep=args.lockstep, progress=not args.no_progress)
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
