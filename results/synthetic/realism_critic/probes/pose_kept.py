"""Which patches does the critic reject within a seed (stop 83)? Seed set s of N seeds, the training draw (seed
s + 2, 4x): within-seed Spearman of the critic logit against pose and patch statistics; kept = per-seed selection.

    PYTHONPATH=. python results/synthetic/realism_critic/probes/pose_kept.py SEEDSET [N]
"""
import sys, json, numpy as np, torch
from scipy import stats
from synthaug.data.seedset import SeedSet
from synthaug.data.synthetic import SyntheticObjectDataset
from synthaug.detectors.training_sets import synthetic_positives
from synthaug.detectors.critic import realism_scores, least_synthetic
torch.set_num_threads(1)
s = int(sys.argv[1]); n = int(sys.argv[2]) if len(sys.argv) > 2 else 100
ss = SeedSet.load(f"data/runs/ingest_drone_seed{s}/seedsets/drone_{n}")
fit = f"data/runs/fits/drone_{n}_seed{s}_hog.json"
count = 20 * len(ss); drawn = 4 * count
syn, g = synthetic_positives(ss, "quadcopter", fit, drawn, seed=s + 2, return_seed_index=True)
ds = SyntheticObjectDataset("quadcopter", ss, params=fit, length=drawn, patch_size=int(ss.patches.shape[-1]),
                            negative_fraction=0.0, seed=s + 2, seed_geometry="auto")
P = [ds.make_params(i) for i in range(drawn)]
assert all(p.seed_index == gi for p, gi in zip(P, g))
keep = least_synthetic(np.asarray(ss.patches), syn, g, count, seed=s + 2, selection="seed")
k = np.zeros(drawn, bool); k[keep] = True
sc = realism_scores(np.asarray(ss.patches), syn, g, seed=s + 2)
# within-seed centred scores vs pose features
feat = {}
for name in ("alpha", "beta", "gamma", "t_x", "t_y"):
    feat[name] = np.array([float(p.pose[name]) for p in P])
feat["|cos beta|"] = np.abs(np.cos(feat["beta"])); feat["|sin beta|"] = np.abs(np.sin(feat["beta"]))
feat["|cos alpha|"] = np.abs(np.cos(feat["alpha"]))
x = syn[:, 0].numpy()
feat["patch std"] = x.reshape(drawn, -1).std(1)
feat["patch mean"] = x.reshape(drawn, -1).mean(1)
c = x[:, 12:28, 12:28].reshape(drawn, -1); feat["centre - surround mean"] = c.mean(1) - feat["patch mean"]
gx = np.abs(np.diff(x, axis=2)).mean((1, 2)); feat["mean |dx|"] = gx
def centred(v):
    out = v.copy()
    for j in np.unique(g): out[g == j] -= v[g == j].mean()
    return out
scc = centred(sc)
rows = []
for name, v in feat.items():
    r, p = stats.spearmanr(centred(v), scc)
    rows.append((name, r, p, v[k].mean(), v[~k].mean()))
print(f"seed set {s}, {n} seeds: within-seed Spearman of the critic logit (higher = looks synthetic)")
for name, r, p, mk, mr in sorted(rows, key=lambda t: -abs(t[1])):
    print(f"  {name:24s} rho {r:+.3f} (p {p:.1g})  kept mean {mk:+.3f}  dropped mean {mr:+.3f}")
