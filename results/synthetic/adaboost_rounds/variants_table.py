"""Table of probe_variants.py's rows: each variant minus real only of the same training seed (patch AP).

    PYTHONPATH=. python results/synthetic/adaboost_rounds/variants_table.py results/synthetic/adaboost_rounds/variants_seed*.jsonl
"""
import json
import sys

import numpy as np

rows = [json.loads(line) for f in sys.argv[1:] for line in open(f)]
by = {}
for r in rows:
    by.setdefault(r["variant"], {})[r["seed"]] = r
real = by.pop("real")
print("| variant | added | seeds | Δ validation patch AP (per seed) | mean | Δ test patch AP (per seed) | mean |")
print("|---|---|---|---|---|---|---|")
for name, per in by.items():
    seeds = sorted(s for s in per if s in real)
    cols = []
    for split in ("val", "test"):
        d = [per[s][f"{split}_ap"] - real[s][f"{split}_ap"] for s in seeds]
        cols += [" / ".join(f"{v:+.3f}" for v in d), f"{np.mean(d):+.3f}"]
    print(f"| {name} | {per[seeds[0]]['added']} | {','.join(map(str, seeds))} | "
          f"{cols[0]} | {cols[1]} | {cols[2]} | {cols[3]} |")
print("\nreal only (per seed): validation " + " / ".join(f"{real[s]['val_ap']:.3f}" for s in sorted(real))
      + ", test " + " / ".join(f"{real[s]['test_ap']:.3f}" for s in sorted(real)))
