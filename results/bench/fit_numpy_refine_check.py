"""What the grid refinement's short CMA-ES runs on the numpy engine would give (synthaug/fit/starts.py builds them
with CMAES(...), pycma, whatever the fit's optimizer): cmaes_numpy fits of the bench's 8 seeds x optimiser seeds
0 1 2 with starts.py's CMAES monkeypatched to engine="numpy", counted against the cached reference annealing of
results/bench/fit_engines_optseeds_v3.json. Usage (OMP_NUM_THREADS=1): python results/bench/fit_numpy_refine_check.py
"""
import sys, tempfile, json
from pathlib import Path
import torch
torch.set_num_threads(1)
sys.path.insert(0, "benchmarks")
import bench_fit as BF
from synthaug.data.seedset import SeedSet
from synthaug.fit.fitting import FitConfig, build_distance, seed_seed
import synthaug.fit.optimizers as O
from synthaug.render.cache import ViewCache
ref = json.load(open("results/bench/fit_engines_optseeds_v3.json"))
seeds = SeedSet.load(str(BF._generated_seeds(Path(tempfile.mkdtemp()), 8)))
cache = ViewCache.build("quadcopter"); dist = build_distance("hog", seeds); scale = float(seeds.object_fraction)
cfg = FitConfig(optimizer="cmaes_numpy")
Py = O.CMAES
class NumpyRefine(Py):
    def __init__(self, *a, **k):
        k.setdefault("engine", "numpy"); super().__init__(*a, **k)
O.CMAES = NumpyRefine
within = 0; rows = []
for i in range(8):
    s = seed_seed(0, i); obj, _ = BF._seed_objective(seeds, i, cache, dist, cfg, scale)
    r10 = ref["per_seed"][i]["anneal_10x"]["distance"]
    ds = []
    for k in (0, 1, 2):
        d = BF._fit_at(obj, cache, dist, cfg, s, k, scale)["distance"]; ds.append(d); within += d <= 1.05 * r10
    old = [f["distance"] for f in ref["per_seed"][i]["cmaes_numpy"]["by_opt_seed"]]
    rows.append({"seed": i, "numpy_refine": [round(x, 4) for x in ds], "pycma_refine": [round(x, 4) for x in old], "anneal_10x": round(r10, 4)})
    print(rows[-1], flush=True)
out = {"within_5pct_all_fits": int(within), "fits": 24, "per_seed": rows}
Path("results/bench/fit_numpy_refine_check.json").write_text(json.dumps(out, indent=1) + "\n")
print(json.dumps({"within_5pct_all_fits": int(within), "fits": 24}))
