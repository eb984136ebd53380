"""Stop 87: where the renders' background stops being the seed's own pixels, and what snapping faint coverage to 0
would do in AdaBoost's eyes (an experiment by monkeypatching motion blur and the coverage blur inside boundary blur;
nothing here is a library change).

usage (repository root): python results/synthetic/adaboost_wl_critic/coverage_snap.py TOL   (0: the library's blurs;
  TOL > 0: blurred coverage under TOL set to exactly 0, over 1 - TOL to 1). Seed set 0 of the 100-seed drone runs,
  2,000 draws (seed 2), its real-only AdaBoost detector (stop 86's cell). ~1 min.
"""
import numpy as np, torch, sys
import synthaug.effects.functional as F
from synthaug.data.seedset import SeedSet
from synthaug.detectors.training_sets import synthetic_positives
from synthaug.detectors.base import load_detector
tol = float(sys.argv[1])
_mb, _sb = F.motion_blur, F._separable_blur
def mb(*a, **k):
    color, cov = _mb(*a, **k)
    if tol:
        cov = torch.where(cov < tol, torch.zeros((), dtype=cov.dtype), cov)
        color = torch.where(cov > 0, color, torch.zeros((), dtype=color.dtype))
    return color, cov
def sb(*a, **k):  # boundary_blur's (blurred image, blurred coverage): the coverage snapped before its band weight
    blurred, m = _sb(*a, **k)
    if tol:
        m = torch.where(m < tol, 0.0, torch.where(m > 1 - tol, 1.0, m))
    return blurred, m
F.motion_blur, F._separable_blur = mb, sb
seed = 0
ss = SeedSet.load(f"data/runs/ingest_drone_seed{seed}/seedsets/drone_100")
fit = f"data/runs/fits/drone_100_seed{seed}_hog_quadcopter.json"
bgs = np.asarray(ss.backgrounds).astype(np.float64)
ring = np.zeros((40, 40), bool); ring[:4] = ring[-4:] = True; ring[:, :4] = ring[:, -4:] = True
syn, idx = synthetic_positives(ss, "../shared/data/meshes/quadcopter.glb", fit, 2000, seed=2, return_seed_index=True)
s = syn.numpy()[:, 0] * 255
d = np.abs(s - bgs[idx])
print(tol, "ring exact vs bg", round(float((d[:, ring] < 1e-6).mean()), 3), "whole patch exact", round(float((d < 1e-6).mean()), 3))
det = load_detector("data/runs/cells/detectors/10d17509b28cd202dc2669c2.pt")
sc = det.score_patches(syn)
print(tol, "median score", round(sc.median().item(), 2), "share > 0", round((sc > 0).float().mean().item(), 3))
