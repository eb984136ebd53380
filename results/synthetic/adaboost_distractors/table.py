"""The probe's rows as a table: each variant's patch AP and hard-window ROC-AUC, and its difference from real only
and from the shape cell, per seed and in the mean over the seeds given.

    python results/synthetic/adaboost_distractors/table.py results/synthetic/adaboost_distractors/probe_seed*.jsonl
"""
import json
import sys
from collections import defaultdict

rows = defaultdict(dict)  # variant -> seed -> row
for path in sys.argv[1:]:
    for line in open(path):
        r = json.loads(line)
        rows[r["variant"]][r["seed"]] = r
seeds = sorted(rows["real"])
keys = [k for k in ("val_ap", "test_ap", "hard_auc") if all(k in rows["real"][s] for s in seeds)]
print(f"seeds {seeds}; mean over seeds, per seed in parentheses")
print("| variant | " + " | ".join(keys) + " | " + " | ".join(f"Δ {k} vs real only" for k in keys)
      + " | " + " | ".join(f"Δ {k} vs shape" for k in keys) + " |")
print("|---" * (1 + 3 * len(keys)) + "|")
for v, by_seed in rows.items():
    common = [s for s in seeds if s in by_seed]
    cells = []
    for k in keys:
        cells.append(f"{sum(by_seed[s][k] for s in common) / len(common):.3f}")
    for base in ("real", "shape"):
        for k in keys:
            both = [s for s in common if s in rows[base]]
            d = [by_seed[s][k] - rows[base][s][k] for s in both]
            cells.append("" if v == base or not d else
                         f"{sum(d) / len(d):+.3f} ({' / '.join(f'{x:+.3f}' for x in d)})")
    print(f"| {v} ({len(common)}) | " + " | ".join(cells) + " |")
