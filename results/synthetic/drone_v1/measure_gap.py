"""Issue 16, item 1 on the real drone seeds: how far the training positives of each condition are from the
real seed patches in the detectors' features (HOG; the CNN's own d_CNN network), per training seed.

    OMP_NUM_THREADS=1 PYTHONPATH=. python results/synthetic/drone_v1/measure_gap.py   # from the repository root

Reads the seed sets the runner's cells drew (data/runs/ingest_drone_seed{s}/seedsets/drone_100) and the fits
(data/runs/fits/drone_100_seed{s}_{hog,cnn}.json); writes gap_seed{s}.json + figures under
results/synthetic/drone_v1/gap/ and prints one line per (seed, comparison, family).
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
import torch

from synthaug.data.seedset import SeedSet
from synthaug.diagnose.gap import gap_section, training_samples
from synthaug.distances.cnn import cnn_distance
from synthaug.effects.perturb import perturb_patches
from synthaug.params import CaptureParams

MESH = "../shared/data/meshes/quadcopter.glb"
OUT = Path("results/synthetic/drone_v1/gap")


def main() -> None:
    torch.set_num_threads(1)
    OUT.mkdir(parents=True, exist_ok=True)
    for s in (0, 1, 2):
        t0 = time.perf_counter()
        ss = SeedSet.load(f"data/runs/ingest_drone_seed{s}/seedsets/drone_100")
        n = len(ss)
        real = torch.as_tensor(np.asarray(ss.patches)).float().div(255).unsqueeze(1)
        groups = np.arange(n)
        syn = {}
        for dist in ("hog", "cnn"):
            fit = Path(f"data/runs/fits/drone_100_seed{s}_{dist}.json")
            if fit.is_file():
                CaptureParams.load_with_extra(fit)
                syn[f"synthetic_{dist}"] = training_samples(ss, MESH, fit, 5 * n, seed=s + 2)
        per = perturb_patches(real, 5, generator=torch.Generator().manual_seed(s + 3))
        syn["perturbed"] = (per, np.tile(groups, 5))
        # the CNN family in the features of a network trained on this seed set's real patches (d_CNN's network)
        neg = torch.as_tensor(np.asarray(ss.negatives)).float().div(255).unsqueeze(1)
        net = cnn_distance(positives=real, negatives=neg, seed=s).net
        res = gap_section(real, syn, real_groups=groups, families=("hog", "cnn"), detectors={"cnn": net},
                          seed=s, out_dir=OUT / f"seed{s}", permutations=100, kid_subsets=50)
        (OUT / f"gap_seed{s}.json").write_text(json.dumps(res, indent=1) + "\n")
        for name, comp in res["comparisons"].items():
            for fam, r in comp["families"].items():
                t = r["two_sample"]
                print(f"seed {s} {name:14s} {fam}: accuracy {t['accuracy']:.3f} [{t['ci'][0]:.3f}, {t['ci'][1]:.3f}] "
                      f"p_perm {t.get('p_permutation')}, KID {r['kid']['mean']:.4f}", flush=True)
        print(f"seed {s}: {time.perf_counter() - t0:.0f} s", flush=True)


if __name__ == "__main__":
    main()
