"""``synthaug bench render``: samples/s and peak memory of SyntheticObjectDataset in a DataLoader.

Prints one JSON object. Example::

    synthaug bench render --mode patch --patch-size 64 --workers 2
    synthaug bench render --mode frame --workers 2
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import sys
import time


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from synthaug._checks import add_option, float_in, int_at_least, nonneg_int, positive_int

    sub = parser.add_subparsers(dest="bench", metavar="WHAT", required=True)
    p = sub.add_parser("render", help="rendering throughput of SyntheticObjectDataset",
                       formatter_class=parser.formatter_class)
    p.add_argument("--mode", choices=["patch", "frame", "both"], default="both", help="what to time")
    p.add_argument("--mesh", default="quadcopter", help="mesh path or built-in name")
    add_option(p, "--patch-size", aliases=["--size"], type=int_at_least(8), default=64, help="patch side (patch mode)")
    p.add_argument("--frame-size", type=int_at_least(16), nargs=2, default=(512, 640), metavar=("H", "W"),
                   help="frame height and width (frame mode)")
    p.add_argument("--workers", type=nonneg_int, default=2, help="DataLoader worker processes")
    p.add_argument("--batch-size", type=positive_int, default=256, help="items per batch")
    p.add_argument("--batches", type=positive_int, default=40, help="batches timed per repeat")
    p.add_argument("--repeats", type=positive_int, default=3, help="timed repeats (median reported)")
    p.add_argument("--step-deg", type=float_in(0.1, 45), default=5.0, help="view-cache grid step")
    p.add_argument("--seed", type=int, default=0, help="dataset seed")


def run_render(mode: str, args: argparse.Namespace) -> dict:
    import torch
    from torch.utils.data import DataLoader

    from synthaug._procs import loader_worker_init
    from synthaug.data.procedural import sky_backgrounds
    from synthaug.data.synthetic import SyntheticObjectDataset

    if mode == "patch":
        bgs = sky_backgrounds(16, (max(args.patch_size * 2, 96), max(args.patch_size * 2, 96)), seed=args.seed)
        bs = args.batch_size
    else:
        bgs = sky_backgrounds(8, tuple(args.frame_size), seed=args.seed)
        bs = max(1, args.batch_size // 8)
    n_items = bs * args.batches
    t0 = time.perf_counter()
    ds = SyntheticObjectDataset(args.mesh, bgs, length=n_items, mode=mode, patch_size=args.patch_size,
                                negative_fraction=0.0, seed=args.seed,
                                render={"step_deg": args.step_deg})
    setup_s = time.perf_counter() - t0
    loader = DataLoader(ds, batch_size=bs, num_workers=args.workers, shuffle=False,
                        collate_fn=(lambda b: b) if mode == "frame" else None,
                        persistent_workers=args.workers > 0, worker_init_fn=loader_worker_init())
    rates = []
    for rep in range(args.repeats + 1):  # first pass warms workers up
        ds.set_epoch(rep)
        t = time.perf_counter()
        count = 0
        for batch in loader:
            count += len(batch) if mode == "frame" else batch[0].shape[0]
        dt = time.perf_counter() - t
        if rep > 0:
            rates.append(count / dt)
    del loader
    peak_self = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    peak_children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    return {
        "mode": mode,
        "size": args.patch_size if mode == "patch" else list(args.frame_size),
        "effects": list(ds.effects),
        "workers": args.workers,
        "batch_size": bs,
        "items_per_repeat": n_items,
        "samples_per_s_median": round(statistics.median(rates), 1),
        "samples_per_s_all": [round(r, 1) for r in rates],
        "setup_s": round(setup_s, 2),
        "peak_rss_main_mib": round(peak_self, 1),
        "peak_rss_largest_child_mib": round(peak_children, 1),
        "torch_threads_main": torch.get_num_threads(),
    }


def main(args: argparse.Namespace) -> int:
    if args.bench != "render":
        print(f"unknown benchmark {args.bench}", file=sys.stderr)
        return 2
    modes = ["patch", "frame"] if args.mode == "both" else [args.mode]
    results = [run_render(m, args) for m in modes]
    print(json.dumps({"benchmark": "render", "results": results}, indent=1))
    return 0
