"""The table of measure.py's rows: per condition the mean held-out accuracy over training seeds, and its paired
difference from the paper's draws (and from the recipe, for the one-factor rows) with a t interval over the seeds
(scipy.stats.t), which carries both the classifier's noise and the seed sets' spread.

    python results/synthetic/recipe_gap/table.py results/synthetic/recipe_gap/gap.json > results/synthetic/recipe_gap/table.md
"""

from __future__ import annotations

import json
import sys

import numpy as np
from scipy import stats


def paired(a: dict[int, float], b: dict[int, float]) -> str:
    seeds = sorted(set(a) & set(b))
    d = np.array([a[s] - b[s] for s in seeds])
    if len(d) < 2:
        return "–"
    lo, hi = stats.t.interval(0.95, len(d) - 1, loc=d.mean(), scale=stats.sem(d))
    return f"{d.mean():+.3f} [{lo:+.3f}, {hi:+.3f}]"


def main() -> None:
    rows = json.loads(open(sys.argv[1]).read())
    names = list(dict.fromkeys(r["condition"] for r in rows))
    acc = {side: {n: {r["seed"]: r[side]["accuracy"] for r in rows if r["condition"] == n} for n in names}
           for side in ("own", "unseen")}
    seeds = sorted({r["seed"] for r in rows})
    print(f"HOG two-sample held-out accuracy (0.5 = indistinguishable), drones, 100-seed sets, training seeds "
          f"{', '.join(map(str, seeds))}; Δ: paired over seeds, 95 % t interval\n")
    print("| condition | own real: mean | Δ vs paper | Δ vs recipe | unseen real: mean | Δ vs paper | Δ vs recipe |")
    print("|---|---|---|---|---|---|---|")
    for n in names:
        cells = [n]
        for side in ("own", "unseen"):
            a = acc[side][n]
            cells += [f"{np.mean(list(a.values())):.3f} ({len(a)})",
                      "" if n == "paper" else paired(a, acc[side]["paper"]),
                      "" if not n.startswith("recipe_") else paired(a, acc[side]["recipe"])]
        print("| " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
