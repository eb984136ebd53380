"""Issue 19, lockstep reproducibility: are fit values a function of the code and the machine only?

1. batch invariance: every candidate's value scored alone (batch 1), in batches of 2..200 (the objective's chunk
   of 96 crossed) and with random company in ``score_together`` — compared bit for bit;
2. lockstep fits of 8 seeds repeated, and with random delays (0-3 ms) before every ask (another load's timing):
   the fits, the number of rounds and a digest of every round's inputs and values, against the fits made alone;
3. the machine's kernel paths: the same objective values and fits in subprocesses with torch's CPU capability
   forced (ATEN_CPU_CAPABILITY=default/avx2/avx512), numpy's AVX-512 dispatch disabled, and 2 torch threads.

Usage (OMP_NUM_THREADS=1): python results/bench/fit_determinism_check.py [--json OUT]
"""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import random
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))


def setup(n=8):
    from bench_fit import _generated_seeds

    from synthaug.data.seedset import SeedSet
    from synthaug.fit.fitting import FitConfig, build_distance, patches_tensor, seed_seed
    from synthaug.fit.search import fit_objective
    from synthaug.render.cache import ViewCache

    seeds = SeedSet.load(str(_generated_seeds(Path(tempfile.mkdtemp()), n)))
    cache = ViewCache.build("quadcopter")
    dist = build_distance("hog", seeds)
    scale = float(seeds.object_fraction)
    T, B = patches_tensor(seeds.patches[:n]), patches_tensor(seeds.backgrounds[:n])
    ss = [seed_seed(0, i) for i in range(n)]
    objs = [fit_objective(T[i:i + 1], B[i:i + 1], cache, dist, FitConfig(), seed=ss[i], object_scale=scale)
            for i in range(n)]
    return T, B, cache, dist, scale, ss, objs


def batch_invariance(objs):
    from synthaug.fit.objective import score_together

    rng = np.random.default_rng(0)
    U = [rng.random((200, o.space.dim)) for o in objs]
    ref = [np.concatenate([o(u[j:j + 1]) for j in range(len(u))]) for o, u in zip(objs, U)]
    out = {}
    for b in (2, 7, 12, 24, 48, 95, 96, 97, 150, 200):
        mism = sum(int((o(u[:b]) != r[:b]).sum()) for o, u, r in zip(objs, U, ref))
        out[f"alone_batch_{b}_mismatches"] = f"{mism} of {len(objs) * b}"
    mism = tot = 0
    for _ in range(40):
        ks = sorted(rng.choice(len(objs), size=int(rng.integers(1, len(objs) + 1)), replace=False).tolist())
        sizes = [int(rng.integers(1, 60)) for _ in ks]
        starts = [int(rng.integers(0, 200 - s)) for s in sizes]
        vals = score_together([objs[k] for k in ks], [U[k][a:a + s] for k, a, s in zip(ks, starts, sizes)])
        for k, a, s, v in zip(ks, starts, sizes, vals):
            mism += int((v != ref[k][a:a + s]).sum())
            tot += s
    out["score_together_random_company_mismatches"] = f"{mism} of {tot}"
    return out


def lockstep_repeats(T, B, cache, dist, scale, ss, optimizer="cmaes"):
    import synthaug.fit.lockstep as L
    from synthaug.fit.fitting import FitConfig
    from synthaug.fit.search import fit_one, fit_together

    cfg = FitConfig(optimizer=optimizer)
    orig_score, orig_eval, log = L.score_together, L._Coordinator.evaluate, []

    def logged(objs, us):
        vals = orig_score(objs, us)
        h = hashlib.sha256()
        for u, v in zip(us, vals):
            h.update(np.ascontiguousarray(u).tobytes())
            h.update(v.tobytes())
        log.append((tuple(len(u) for u in us), h.hexdigest()[:12]))
        return vals

    def late(self, k):
        ask = orig_eval(self, k)

        def f(u):
            time.sleep(random.random() * 0.003)
            return ask(u)
        return f

    runs = []
    L.score_together = logged
    try:
        for mode in ("plain", "plain", "delays"):
            log.clear()
            L._Coordinator.evaluate = late if mode == "delays" else orig_eval
            r = fit_together(T, B, cache, dist, cfg, seeds=ss, object_scale=scale)
            runs.append({"mode": mode, "distances": [x["distance"] for x in r], "rounds": len(log),
                         "rounds_digest": hashlib.sha256(repr(log).encode()).hexdigest()[:12]})
    finally:
        L.score_together, L._Coordinator.evaluate = orig_score, orig_eval
    alone = [fit_one(T[i:i + 1], B[i:i + 1], cache, dist, cfg, seed=s, object_scale=scale)["distance"]
             for i, s in enumerate(ss)]
    same = all(r["distances"] == alone for r in runs) and len({r["rounds_digest"] for r in runs}) == 1
    return {"optimizer": optimizer, "runs": runs, "alone": alone, "all_identical": same}


def machine_probe():
    """(child) objective values' digest and the fits of seeds 0-2 under this process's kernel paths."""
    from synthaug.fit.fitting import FitConfig
    from synthaug.fit.search import fit_one

    torch.set_num_threads(int(os.environ.get("PROBE_TORCH_THREADS", "1")))
    T, B, cache, dist, scale, ss, objs = setup()
    rng = np.random.default_rng(0)
    vals = np.concatenate([o(rng.random((200, o.space.dim))) for o in objs])
    fits = [fit_one(T[i:i + 1], B[i:i + 1], cache, dist, FitConfig(), seed=ss[i], object_scale=scale)["distance"]
            for i in range(3)]
    print(json.dumps({"torch_capability": torch.backends.cpu.get_cpu_capability(),
                      "values_digest": hashlib.sha256(vals.tobytes()).hexdigest()[:12], "fits_seeds_0_2": fits}))


def machine_paths():
    out = {}
    cases = {"torch default (no SIMD)": {"ATEN_CPU_CAPABILITY": "default"}, "torch avx2": {"ATEN_CPU_CAPABILITY": "avx2"},
             "torch avx512": {"ATEN_CPU_CAPABILITY": "avx512"},
             "numpy AVX-512 off": {"NPY_DISABLE_CPU_FEATURES": "X86_V4 AVX512_ICL"},
             "2 torch threads": {"PROBE_TORCH_THREADS": "2", "OMP_NUM_THREADS": "2"}}
    for name, env in cases.items():
        p = subprocess.run([sys.executable, __file__, "--probe"], env={**os.environ, **env}, cwd=ROOT,
                           capture_output=True, text=True, check=True)
        out[name] = json.loads(p.stdout.strip().splitlines()[-1])
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--probe", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    if args.probe:
        machine_probe()
        return 0
    torch.set_num_threads(1)
    T, B, cache, dist, scale, ss, objs = setup()
    out = {"batch_invariance": batch_invariance(objs),
           "lockstep": [lockstep_repeats(T, B, cache, dist, scale, ss, o) for o in ("cmaes", "cmaes_numpy")],
           "machine_paths": machine_paths(),
           "load_average_at_end": os.getloadavg()}
    text = json.dumps(out, indent=1)
    print(text)
    if args.json:
        Path(args.json).write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
