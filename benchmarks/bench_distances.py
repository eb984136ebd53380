"""Benchmark: image distances, pairs per second on 40x40 patches, batched.

    python benchmarks/bench_distances.py [--batch 1024] [--repeats 7] [--threads 1] [--names eucl hog ...]

For every registered distance (``list_distances()``; distances that need
fitted data are built by their registered ``example``), times the fitting
loop's call — one real seed ``(1, 1, 40, 40)`` against ``B`` synthetic patches
— and the fully batched one — ``B`` real against ``B`` synthetic — forward
only (``torch.no_grad``) and, for differentiable distances, forward+backward
w.r.t. the synthetic patches. Prints one JSON object with median pairs/s and
the issue's target (>= 5,000 pairs/s for hog, wl_* and cnn).
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time
from typing import Any, Callable

import torch

TARGET = 5000.0


def _median_rate(fn: Callable[[], Any], pairs: int, repeats: int, clock: Callable[[], float] = time.perf_counter) -> float:
    fn()  # warm-up
    times = []
    for _ in range(repeats):
        t0 = clock()
        fn()
        times.append(clock() - t0)
    return pairs / statistics.median(times)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--batch", type=int, default=1024)
    p.add_argument("--repeats", type=int, default=7)
    p.add_argument("--threads", type=int, default=None, help="torch threads (default: torch's choice, 2 here)")
    p.add_argument("--names", nargs="+", default=None, help="distances to time (default: all registered)")
    args = p.parse_args()

    from synthaug.distances import example_distance, list_distances

    if args.threads:
        torch.set_num_threads(args.threads)
    g = torch.Generator().manual_seed(0)
    real_one = torch.rand(1, 1, 40, 40, generator=g)
    real_many = torch.rand(args.batch, 1, 40, 40, generator=g)
    syn = torch.rand(args.batch, 1, 40, 40, generator=g)
    results: dict[str, Any] = {}
    for name in args.names or list_distances():
        try:
            t0 = time.perf_counter()
            d = example_distance(name, torch.Generator().manual_seed(0))
            build_s = time.perf_counter() - t0
        except Exception as e:  # report a distance that cannot be built here
            results[name] = {"skipped": f"{type(e).__name__}: {e}"}
            continue
        d.eval()

        def forward(real: torch.Tensor) -> Callable[[], Any]:
            def run() -> Any:
                with torch.no_grad():
                    return d(real, syn)

            return run

        r: dict[str, Any] = {
            "pairs_per_second_one_real_vs_batch": round(_median_rate(forward(real_one), args.batch, args.repeats)),
            "pairs_per_second_batch_vs_batch": round(_median_rate(forward(real_many), args.batch, args.repeats)),
            # per CPU-second of this process: robust to other jobs sharing the machine
            "pairs_per_cpu_second_one_real_vs_batch": round(_median_rate(forward(real_one), args.batch, args.repeats, time.process_time)),
            "example_build_seconds": round(build_s, 2),
        }
        if d.differentiable:

            def backward() -> None:
                x = syn.clone().requires_grad_(True)
                d(real_one, x).sum().backward()

            r["pairs_per_second_forward_backward"] = round(_median_rate(backward, args.batch, args.repeats))
        if name != "eucl":
            r["target_pairs_per_second"] = TARGET
            r["meets_target"] = r["pairs_per_second_one_real_vs_batch"] >= TARGET
        results[name] = r
    print(
        json.dumps(
            {
                "benchmark": "distances_40x40",
                "batch": args.batch,
                "repeats": args.repeats,
                "torch_threads": torch.get_num_threads(),
                "cpu": platform.processor() or platform.machine(),
                "torch": torch.__version__,
                "distances": results,
            },
            indent=2,
        )
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
