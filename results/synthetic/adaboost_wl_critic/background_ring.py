"""Stop 87: how far each capture effect moves a synthetic patch's outer 4-px ring off its seed's background (and
off the real seed patch). Seed set 0 of the 100-seed drone runs, 300 draws per effect set. ~2 min.

usage (repository root): python results/synthetic/adaboost_wl_critic/background_ring.py
"""
import numpy as np, torch
from synthaug.data.seedset import SeedSet
from synthaug.detectors.training_sets import synthetic_positives
seed = 0
ss = SeedSet.load(f"data/runs/ingest_drone_seed{seed}/seedsets/drone_100")
fit = f"data/runs/fits/drone_100_seed{seed}_hog_quadcopter.json"
real = np.asarray(ss.patches).astype(np.float64)
bgs = np.asarray(ss.backgrounds).astype(np.float64)
print("backgrounds dtype", np.asarray(ss.backgrounds).dtype, "real==bg in ring share", end=" ")
ring = np.zeros((40, 40), bool); ring[:4] = ring[-4:] = True; ring[:, :4] = ring[:, -4:] = True
print((np.abs(real - bgs)[:, ring] < 1e-6).mean())
for eff in (None, [], ["boundary_blur"], ["motion_blur"], ["object_noise"], ["material"]):
    syn, idx = synthetic_positives(ss, "../shared/data/meshes/quadcopter.glb", fit, 300, seed=2, return_seed_index=True, effects=eff)
    s = syn.numpy()[:, 0] * 255
    for name, ref in (("vs real", real), ("vs bg", bgs)):
        d = np.abs(s - ref[idx])[:, ring]
        print(eff, name, "median", round(float(np.median(d)), 5), "exact", round(float((d < 1e-6).mean()), 3), "> 0.5 level", round(float((d > 0.5).mean()), 3))
