"""Stop 87: what each critic's selection does to the real-vs-synthetic gap in AdaBoost's own eyes.

For each training seed: the 100-seed seed set and its d_HOG fit (as the runner's AdaBoost cells use them), 8,000
synthetic positives drawn as AdaBoost's training draws them (seed + 2, every effect, uniform poses, own backgrounds),
and three sets of 2,000: the first 2,000 drawn (every draw, the paper), the quarter of each seed's draws the HOG critic
keeps, the quarter the weak-learner critic keeps. Each set against the 100 real seed patches in
:func:`synthaug.diagnose.measure_gap`: the two-sample test held out by seed (5 folds; 0.5 = indistinguishable), in
the stumps of the real-only AdaBoost detector trained on the same seed set (its cell's stored detector: the features
AdaBoost actually uses, independent of both critics' features) and in HOG.

usage (repository root): python results/synthetic/adaboost_wl_critic/gap.py --seeds 0 1 --out FILE.json
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from synthaug.data.seedset import SeedSet
from synthaug.detectors.base import load_detector
from synthaug.detectors.training_sets import synthetic_positives
from synthaug.diagnose.gap import measure_gap

# the stored real-only AdaBoost detectors of the runner's cells (drone, 100 seeds, halmstad_v2), by training seed
DETECTORS = {0: "data/runs/cells/detectors/10d17509b28cd202dc2669c2.pt",
             1: "data/runs/cells/detectors/15d751e3fa4c2a8b974f0b3b.pt",
             2: "data/runs/cells/detectors/47b6e311d8f783aedf78deb7.pt"}  # stop 88's real-only cell (run2.sh real r2 2)
MESH = "../shared/data/meshes/quadcopter.glb"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    out: dict = {}
    for seed in args.seeds:
        t0 = time.perf_counter()
        ss = SeedSet.load(f"data/runs/ingest_drone_seed{seed}/seedsets/drone_100")
        fit = f"data/runs/fits/drone_100_seed{seed}_hog_quadcopter.json"
        sets = {"every draw": dict(realism_keep=1.0),
                "HOG critic keeps 1/4": dict(realism_keep=0.25),
                "weak-learner critic keeps 1/4": dict(realism_keep=0.25, realism_features="weak_learners")}
        real = np.asarray(ss.patches)
        row = {}
        for name, kw in sets.items():
            syn, idx = synthetic_positives(ss, MESH, fit, 2000, seed=seed + 2, return_seed_index=True, **kw)
            gap = measure_gap(real, syn, ["adaboost", "hog"], detectors={"adaboost": DETECTORS[seed]}, folds=5,
                              seed=0, permutations=0, kid_subsets=20, groups_real=np.arange(len(real)),
                              groups_syn=idx)
            row[name] = {fam: {"accuracy": g["two_sample"]["accuracy"], "ci": g["two_sample"]["ci"],
                               "kid": g["kid"]["mean"]}
                         for fam, g in gap["families"].items()}
            print(seed, name, {f: round(v["accuracy"], 3) for f, v in row[name].items()}, flush=True)
        out[str(seed)] = {"sets": row, "seconds": round(time.perf_counter() - t0, 1)}
    Path(args.out).write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
