"""Paired table of the rows of mined_patches.py or jitter_patches.py: each synthetic cell minus its seed's real-only
detector, per measure (every field ending in _ap or _auc), with a t interval over the training seeds.

    PYTHONPATH=. python results/synthetic/adaboost_rounds/paired_table.py results/synthetic/adaboost_rounds/jitter_test_*.jsonl
    PYTHONPATH=. python results/synthetic/adaboost_rounds/paired_table.py results/synthetic/adaboost_rounds/mined_patches.jsonl
"""
import json
import sys

import numpy as np
from scipy import stats

rows = [json.loads(line) for f in sys.argv[1:] for line in open(f) if '"cell"' in line]
by = {}
for r in rows:
    by.setdefault(r["seed"], {})[r["cell"]] = r
print("| cell | measure | seeds | real only (mean) | cell (mean) | Δ mean [t 95 % over seeds] | seeds up |")
print("|---|---|---|---|---|---|---|")
for cell in ("pose", "shape"):
    seeds = sorted(s for s in by if cell in by[s] and "real" in by[s])
    for m in [k for k in rows[0] if k.endswith(("_ap", "_auc"))]:
        a = np.array([by[s]["real"][m] for s in seeds])
        b = np.array([by[s][cell][m] for s in seeds])
        d = b - a
        half = stats.t.ppf(0.975, len(d) - 1) * d.std(ddof=1) / np.sqrt(len(d)) if len(d) > 1 else float("nan")
        print(f"| {cell} | {m} | {len(seeds)} | {a.mean():.3f} | {b.mean():.3f} | {d.mean():+.4f} "
              f"[{d.mean() - half:+.4f}, {d.mean() + half:+.4f}] | {int((d > 0).sum())}/{len(d)} |")
