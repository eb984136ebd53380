"""``synthaug experiment``: run the paper's experiments on videos in the shared format.

Usage::

    python -m synthaug.evaluate.experiments_cli baselines --class drone --out results/baselines \\
        --cells results/cells_drone.json --frame-stride 15

    python -m synthaug.evaluate.experiments_cli fig11_ratio table1_perturbation --class drone \\
        --out results/paper/drone --cells results/cells_drone.json --detectors cnn hog

Each experiment writes ``<name>.md`` (table), ``<name>.png`` (plot) and
``<name>.json`` (numbers) into ``--out``; trained-and-scored configurations
("cells") are cached in ``--cells`` so that a rerun resumes and experiments
share cells. Ratios of synthetic to real images are chosen on the validation
videos by ``fig11_ratio`` (``<out>/chosen_ratio.json``) and used by the
experiments that follow. Capture-parameter fits missing from ``--params-dir`` are
made on the fly (``synthaug fit`` defaults, CMA-ES). Defaults are
:class:`~synthaug.evaluate.context.ExperimentContext`'s and
:class:`~synthaug.detectors.training.TrainOptions`'.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import torch

from synthaug._checks import (add_option, check_output_dir, dataclass_defaults, int_at_least, nonneg_float,
                              positive_float, positive_int)
from synthaug.detectors.train_cli import add_budget_options, budget_options
from synthaug.detectors.training import TrainOptions
from synthaug.evaluate.context import ExperimentContext
from synthaug.evaluate.experiments import EXPERIMENTS


def add_arguments(parser: argparse.ArgumentParser) -> None:
    d = dataclass_defaults(ExperimentContext)  # defaults read from the dataclasses: they cannot drift
    # numbers are checked as they are parsed: a bad one exits 2 at once, naming the option (not after fitting)
    parser.add_argument("experiments", nargs="+", choices=[*EXPERIMENTS, "all"], help="experiments to run, in order")
    parser.add_argument("--class", dest="class_name", default=d["class_name"],
                        help="object class (selects videos and seed sets)")
    parser.add_argument("--out", type=Path, required=True, help="results folder")
    parser.add_argument("--cells", type=Path, default=None, help="cell cache JSON (default <out>/cells.json)")
    add_option(parser, "--seed-sets", aliases=["--seedsets"], type=Path, default=d["seedsets_dir"],
               help="folder of <class>_<n> seed sets")
    parser.add_argument("--mesh", default=None, help="mesh (default: quadcopter for drone, twin_prop_airplane for airplane)")
    add_option(parser, "--params-dir", aliases=["--fits"], type=Path, default=d["fits_dir"],
               help="folder of capture-parameter files <class>_<n>_<distance>.json (default <out>/fits)")
    parser.add_argument("--videos", type=Path, default=d["videos_dir"], help="folder of videos")
    parser.add_argument("--labels", type=Path, default=d["labels_dir"], help="folder of per-video label JSON files")
    parser.add_argument("--split", type=Path, default=d["split_file"], help="split JSON (by video)")
    add_option(parser, "--frame-stride", aliases=["--stride-k"], type=positive_int, default=d["stride_k"],
               help="score every k-th test frame")
    add_option(parser, "--val-frame-stride", aliases=["--val-stride-k"], type=positive_int, default=d["val_stride_k"],
               help="every k-th validation frame (model selection)")
    parser.add_argument("--max-test-videos", type=positive_int, default=None, help="use at most this many test videos (quick look; None: all)")
    parser.add_argument("--max-val-videos", type=positive_int, default=None, help="use at most this many validation videos (None: all)")
    parser.add_argument("--scales", type=positive_float, nargs="+", default=None, help="pyramid factors (default: sliding.DEFAULT_SCALES)")
    parser.add_argument("--detectors", nargs="+", default=None, choices=["hog", "adaboost", "cnn"],
                        help="detectors (default: each experiment's own)")
    parser.add_argument("--ratios", type=nonneg_float, nargs="+", default=None, help="fig11: synthetic per real (>= 0)")
    parser.add_argument("--seed-counts", type=positive_int, nargs="+", default=None, help="baselines / fig12: seed-set sizes")
    parser.add_argument("--distances", nargs="+", default=None, help="table2: distances")
    parser.add_argument("--frame-step", type=positive_int, default=1, help="baselines: use every n-th labelled training frame")
    parser.add_argument("--refit", action="store_true", help="fig9: refit Θ without each effect (the paper) instead of dropping it at generation")
    parser.add_argument("--report-only", action="store_true", help="train nothing: rewrite the tables from the cell cache (missing cells show '–')")
    parser.add_argument("--seed", type=int, default=d["seed"], help="training seed of every cell")
    parser.add_argument("--threads", type=positive_int, default=1, help="torch threads")
    parser.add_argument("--fit-workers", type=positive_int, default=d["fit_workers"], help="processes fitting Θ")
    parser.add_argument("--fit-budget", type=int_at_least(10), default=d["fit_budget"],
                        help="objective evaluations per seed fit")
    add_budget_options(parser)


DEFAULT_MESH = {"drone": "../shared/data/meshes/quadcopter.glb", "airplane": "../shared/data/meshes/twin_prop_airplane.glb"}


def main(args: argparse.Namespace) -> int:
    if args.threads < 1:
        print(f"synthaug experiment: error: --threads must be >= 1, got {args.threads}", file=sys.stderr)
        return 2
    torch.set_num_threads(args.threads)
    mesh = args.mesh or DEFAULT_MESH.get(args.class_name)
    if mesh is None:
        print(f"synthaug experiment: error: no default mesh for class {args.class_name!r}; give --mesh", file=sys.stderr)
        return 2
    opts = TrainOptions(**budget_options(args))

    def log(msg: str) -> None:
        print(f"[{time.strftime('%H:%M:%S')}] {msg}", flush=True)

    try:
        check_output_dir(args.out)
        if args.distances is not None:
            from synthaug.distances.registry import list_distances

            unknown = [d for d in args.distances if d not in list_distances()]
            if unknown:
                raise ValueError(f"--distances: unknown {unknown}; registered: {list_distances()}")
        ctx = ExperimentContext(out_dir=args.out, class_name=args.class_name, seedsets_dir=args.seed_sets, mesh=mesh, fits_dir=args.params_dir,
                                videos_dir=args.videos, labels_dir=args.labels, split_file=args.split, stride_k=args.frame_stride,
                                val_stride_k=args.val_frame_stride, max_test_videos=args.max_test_videos, max_val_videos=args.max_val_videos,
                                scales=None if args.scales is None else tuple(args.scales), options=opts, seed=args.seed,
                                fit_workers=args.fit_workers, fit_budget=args.fit_budget, log=log, cells_path=args.cells,
                                cached_only=args.report_only)
        names = list(EXPERIMENTS) if "all" in args.experiments else list(args.experiments)
        summary = {}
        for name in names:
            kw: dict = {}
            if args.detectors is not None:
                kw["detectors"] = args.detectors
            if name == "fig11_ratio" and args.ratios is not None:
                kw["ratios"] = args.ratios
            if name in ("baselines", "fig12_seeds") and args.seed_counts is not None:
                kw["seed_counts"] = args.seed_counts
            if name == "baselines":
                kw["frame_step"] = args.frame_step
            if name == "table2_detector_distance" and args.distances is not None:
                kw["distances"] = args.distances
            if name == "fig9_effects_off":
                kw["refit"] = args.refit
            t0 = time.perf_counter()
            log(f"experiment {name} {kw}")
            EXPERIMENTS[name](ctx, **kw)
            summary[name] = {"seconds": round(time.perf_counter() - t0, 1), "table": str(args.out / f"{name}.md")}
            log(f"experiment {name} done in {summary[name]['seconds']}s")
    except (ValueError, FileNotFoundError) as e:
        print(f"synthaug experiment: error: {e}", file=sys.stderr)
        return 2
    print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    _parser = argparse.ArgumentParser(prog="synthaug experiment", description=__doc__.split("\n\n")[0])
    add_arguments(_parser)
    sys.exit(main(_parser.parse_args()))
