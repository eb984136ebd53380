"""Stop 83: how many seeds the critic's quarter keeps (set selection), the training draw (seed s + 2, 4x).

    PYTHONPATH=. python results/synthetic/realism_critic/probes/keep_spread.py N SEEDSET...
"""
import sys, numpy as np, torch, json
from synthaug.data.seedset import SeedSet
from synthaug.detectors.training_sets import synthetic_positives
from synthaug.detectors.critic import least_synthetic
torch.set_num_threads(1)
n = int(sys.argv[1]); seeds = [int(x) for x in sys.argv[2:]]
for s in seeds:
    ss = SeedSet.load(f"data/runs/ingest_drone_seed{s}/seedsets/drone_{n}")
    count = 20 * len(ss)
    syn, g = synthetic_positives(ss, "quadcopter", f"data/runs/fits/drone_{n}_seed{s}_hog.json", count * 4, seed=s + 2,
                                 return_seed_index=True)
    keep = least_synthetic(np.asarray(ss.patches), syn, g, count, seed=s + 2, selection="set")
    per = np.bincount(g[keep], minlength=len(ss)); drawn = np.bincount(g, minlength=len(ss))
    p = per / per.sum(); ent = np.exp(-(p[p > 0] * np.log(p[p > 0])).sum())
    pd = drawn / drawn.sum(); entd = np.exp(-(pd[pd > 0] * np.log(pd[pd > 0])).sum())
    print(json.dumps({"n": n, "seed": s, "eff_seeds_kept": round(float(ent), 1), "eff_seeds_drawn": round(float(entd), 1),
                      "seeds_with_none": int((per == 0).sum()), "max_share": round(float(p.max()), 3),
                      "kept_per_seed": per.tolist() if n <= 12 else sorted(per.tolist())[::-1][:15]}), flush=True)
