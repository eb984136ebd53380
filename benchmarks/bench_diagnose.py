"""Benchmark: diagnosis of a 100-seed measured set with all 14 candidates screened (target: < 10 min).

Usage::

    python benchmarks/bench_diagnose.py [--seeds 100] [--hidden compression] [--threads 2]

Prints JSON: wall seconds of the diagnosis (the seed set and its fit are made first, untimed), and the finding.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=100)
    ap.add_argument("--hidden", default="compression")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=1)
    a = ap.parse_args()
    import numpy as np
    import torch

    torch.set_num_threads(a.threads)
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from test_diagnose import converged_fit  # the tests' fit helper (per-seed CMA from the truth)

    from synthaug.diagnose.reference_camera import make_measured_seedset
    from synthaug.diagnose.report import diagnose

    with tempfile.TemporaryDirectory() as d:
        t = time.perf_counter()
        seeds = make_measured_seedset(Path(d) / "s", n_seeds=a.seeds, hidden=[a.hidden] if a.hidden else None,
                                      frame_size=(192, 256), object_px=(20.0, 32.0), view_step_deg=20,
                                      sprite_size=48, seed=3, paper_ranges={"w_d": (0.3, 0.45)})
        fit = converged_fit(seeds, Path(d) / "fit.json")
        prep = time.perf_counter() - t
        times = []
        for _ in range(a.repeats):
            t = time.perf_counter()
            rep = diagnose(seeds, "quadcopter", fit, out_dir=Path(d) / "out")
            times.append(time.perf_counter() - t)
    print(json.dumps({"bench": "diagnose", "n_seeds": a.seeds, "candidates": 14, "hidden": a.hidden,
                      "threads": a.threads, "median_seconds": float(np.median(times)), "all_seconds": times,
                      "prep_seconds_untimed": prep, "findings": [f["effect"] for f in rep["findings"]]}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
