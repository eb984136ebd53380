"""Rendering benchmark: DataLoader throughput (patch 64x64 and 640x512 frames) and view-cache error.

Usage::

    python benchmarks/bench_render.py            # prints JSON

Throughput comes from ``synthaug bench render`` (2 workers, all four effects);
the approximation error compares the 5° view cache with exact GL renders at
random poses (``synthaug.render.cache.approximation_error``).
"""

from __future__ import annotations

import argparse
import json
import sys


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--batches", type=int, default=40)
    parser.add_argument("--error-poses", type=int, default=200)
    args = parser.parse_args()

    from synthaug.data.bench import add_arguments, run_render
    from synthaug.render.cache import ViewCache, approximation_error
    from synthaug.render.server import Renderer

    p = argparse.ArgumentParser()
    add_arguments(p)
    ns = p.parse_args(["render", "--workers", str(args.workers), "--repeats", str(args.repeats),
                       "--batches", str(args.batches)])
    results = [run_render("patch", ns), run_render("frame", ns)]
    cache = ViewCache.build("quadcopter", step_deg=5.0, sprite_size=96)
    with Renderer("quadcopter") as r:
        err = {s: approximation_error(cache, r, n=args.error_poses, size=s) for s in (40, 64)}
    print(json.dumps({"benchmark": "render", "throughput": results, "view_cache_error": err}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
