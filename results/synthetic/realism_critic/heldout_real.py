"""The critic's two-sample drop against real patches it never saw (stop 82).

measure_gap.py tests the synthetic patches against the seed set's own real patches, which the critic (cross-fitted
by seed) was trained on for the other half of the seeds. Here the real side is another training seed's seed set
(seed set s + 5), keeping only its frames more than --gap frames away from every frame of seed set s in the same
video: real drones the critic never saw (no groups: no background is shared). HOG features, the classifier
two-sample test of synthaug.diagnose.gap, 5n synthetic patches drawn as training draws them.

    PYTHONPATH=. python results/synthetic/realism_critic/heldout_real.py --seeds 0 1 2 --selection set \
        --out results/synthetic/realism_critic/heldout_real.json   # stop 82
    # stop 83: the per-seed selection beside the set's
    PYTHONPATH=. python results/synthetic/realism_critic/heldout_real.py --seeds 0 1 2 --quantize off \
        --keep 1 0.25 --selection set seed --out results/synthetic/realism_critic/heldout_real_per_seed.json
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import torch

from synthaug.data.seedset import SeedSet
from synthaug.detectors.critic import hog_features, realism_variants
from synthaug.detectors.training_sets import synthetic_positives
from synthaug.diagnose.gap import classifier_two_sample_test


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--other", type=int, default=5, help="the held-out real patches come from seed set s + this")
    ap.add_argument("--gap", type=int, default=30, help="frames of one video closer than this to a seed are dropped")
    ap.add_argument("--keep", type=float, nargs="+", default=[1.0, 0.5, 0.25])
    ap.add_argument("--quantize", choices=["off", "on"], nargs="+", default=["off", "on"])
    ap.add_argument("--selection", choices=["seed", "set"], nargs="+", default=["seed"],
                    help="the critic's selection (synthetic_positives' realism_selection), one row per value")
    ap.add_argument("--seed-set", default="data/runs/ingest_drone_seed{s}/seedsets/drone_100")
    ap.add_argument("--fit", default="data/runs/fits/drone_100_seed{s}_hog.json")
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    torch.set_num_threads(1)
    rows = []
    for s in args.seeds:
        t0 = time.perf_counter()
        ss = SeedSet.load(args.seed_set.format(s=s))
        other = SeedSet.load(args.seed_set.format(s=s + args.other))
        near = {}
        for r in ss.records:
            near.setdefault(r["video"], []).append(int(r["frame"]))
        keep_rows = [i for i, r in enumerate(other.records)
                     if all(abs(int(r["frame"]) - f) > args.gap for f in near.get(r["video"], []))]
        real = hog_features(np.asarray(other.patches)[keep_rows])
        for q in args.quantize:
            for k, sel in realism_variants(args.keep, args.selection):
                syn = synthetic_positives(ss, "quadcopter", args.fit.format(s=s), 5 * len(ss), seed=s + 2,
                                          quantize=q == "on", realism_keep=k, realism_selection=sel)
                t = classifier_two_sample_test(real, hog_features(syn), seed=s, permutations=100)
                rows.append({"seed": s, "quantize": q, "realism_keep": k, "real_heldout": len(keep_rows),
                             **({"realism_selection": sel} if sel != "set" else {}),
                             "accuracy": t.accuracy, "ci": list(t.ci), "p_permutation": t.p_permutation})
                print(json.dumps(rows[-1]), flush=True)
        print(f"seed {s}: {time.perf_counter() - t0:.0f} s", flush=True)
    Path(args.out).write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
