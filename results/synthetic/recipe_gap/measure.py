"""Issue 16's two-sample target for the positives the library now ships: AdaBoost's recipe (stop 104) in HOG features.

For each training seed s: 5n synthetic positives drawn exactly as training draws them
(:func:`synthaug.detectors.training_sets.synthetic_positives`, seed s + 2) under each condition below, their HOG
features (:func:`synthaug.detectors.critic.hog_features`) tested against two real samples with the classifier
two-sample test of :mod:`synthaug.diagnose.gap` (0.5 = indistinguishable):
  own     the seed set's own n real patches, folds by seed (a seed's real and synthetic patches held out together),
          the test of ``../factors/ranking.md`` and ``../placement/``;
  unseen  real drones no critic saw: seed set s + OTHER's patches, minus every frame within GAP frames of one of seed
          set s's in the same video (``../realism_critic/heldout_real.py``'s measure).
Conditions: the paper's draws (issue 16's "today's synthetic images"), HOG's default (the HOG critic's quarter), the
recipe (8-bit, AdaBoost's default of stops 104-107), the recipe rounded at native scale (its default since stop 108),
and the recipe with one factor put back to the paper's at a time (which factor does it).

    OMP_NUM_THREADS=1 PYOPENGL_PLATFORM=egl PYTHONPATH=. python results/synthetic/recipe_gap/measure.py \
        --out results/synthetic/recipe_gap/gap.json
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import torch

from synthaug.data.seedset import SeedSet
from synthaug.detectors.critic import hog_features
from synthaug.detectors.training_sets import synthetic_positives
from synthaug.diagnose.gap import classifier_two_sample_test

PAPER = {"pose_sampling": "uniform", "shape_variation": 0.0, "quantize": False, "realism_keep": 1.0,
         "realism_features": "hog"}
RECIPE = {"pose_sampling": "fitted_at_seed", "shape_variation": 0.3, "quantize": True, "realism_keep": 0.25,
          "realism_features": "weak_learners"}
CONDITIONS = {
    "paper": PAPER,
    "hog_default": {**PAPER, "realism_keep": 0.25},
    "recipe": RECIPE,
    "recipe_native": {**RECIPE, "quantize": "native_scale"},  # AdaBoost's default since stop 108
    "recipe_uniform_poses": {**RECIPE, "pose_sampling": "uniform"},
    "recipe_fitted_poses_uniform_offsets": {**RECIPE, "pose_sampling": "fitted"},
    "recipe_mesh_alone": {**RECIPE, "shape_variation": 0.0},
    "recipe_float": {**RECIPE, "quantize": False},
    "recipe_every_draw": {**RECIPE, "realism_keep": 1.0},
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--conditions", nargs="+", choices=list(CONDITIONS), default=list(CONDITIONS))
    ap.add_argument("--other", type=int, default=4, help="the unseen real patches come from seed set s + this")
    ap.add_argument("--gap", type=int, default=30, help="frames of one video closer than this to a seed are dropped")
    ap.add_argument("--seed-set", default="data/runs/ingest_drone_seed{s}/seedsets/drone_100")
    ap.add_argument("--fit", default="data/runs/fits/drone_100_seed{s}_hog_quadcopter.json")
    ap.add_argument("--mesh", default="../shared/data/meshes/quadcopter.glb")
    ap.add_argument("--permutations", type=int, default=100)
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    torch.set_num_threads(1)
    out = Path(args.out)
    rows = json.loads(out.read_text()) if out.is_file() else []
    done = {(r["seed"], r["condition"]) for r in rows}
    for s in args.seeds:
        ss = SeedSet.load(args.seed_set.format(s=s))
        other = SeedSet.load(args.seed_set.format(s=s + args.other))
        near: dict[str, list[int]] = {}
        for r in ss.records:
            near.setdefault(r["video"], []).append(int(r["frame"]))
        keep = [i for i, r in enumerate(other.records)
                if all(abs(int(r["frame"]) - f) > args.gap for f in near.get(r["video"], []))]
        own = hog_features(np.asarray(ss.patches))
        unseen = hog_features(np.asarray(other.patches)[keep])
        for name in args.conditions:
            if (s, name) in done:
                continue
            t0 = time.perf_counter()
            syn, idx = synthetic_positives(ss, args.mesh, args.fit.format(s=s), 5 * len(ss), seed=s + 2,
                                           return_seed_index=True, **CONDITIONS[name])
            f = hog_features(syn)
            row = {"seed": s, "condition": name, "options": CONDITIONS[name], "n_real": len(ss),
                   "n_unseen": len(keep), "n_synthetic": int(len(syn))}
            for side, real, groups in (("own", own, np.arange(len(ss))), ("unseen", unseen, None)):
                t = classifier_two_sample_test(real, f, seed=s, permutations=args.permutations,
                                               groups_real=groups, groups_syn=None if groups is None else idx)
                row[side] = {"accuracy": t.accuracy, "ci": list(t.ci), "p_permutation": t.p_permutation}
            row["seconds"] = round(time.perf_counter() - t0, 1)
            rows.append(row)
            out.write_text(json.dumps(rows, indent=1) + "\n")
            print(f"seed {s} {name:36s} own {row['own']['accuracy']:.3f}  unseen {row['unseen']['accuracy']:.3f}  "
                  f"({row['seconds']:.0f} s)", flush=True)


if __name__ == "__main__":
    main()
