"""Issue 20, stop 111: the highlight statistic on the same cases (nuisances, scenes, hidden draws) with 60 and with
240 seeds: is the clean spread that sets the floor the seeds' noise or the cases' materials?

    PYTHONPATH=. python results/diagnose/null/highlight_s110/rows_k.py --base-seed 8000 \
        --out results/diagnose/null/highlight_s111/rows_k_8000_s60.json specular_alt clean
    PYTHONPATH=. python results/diagnose/null/highlight_s110/rows_k.py --base-seed 8000 --seeds 240 \
        --out results/diagnose/null/highlight_s111/rows_k_8000_s240.json specular_alt clean   # ~80 s a case
    python results/diagnose/null/highlight_s111/seeds240.py
"""
import json
from pathlib import Path

import numpy as np
from scipy import stats

HERE = Path(__file__).parent
r60 = json.loads((HERE / "rows_k_8000_s60.json").read_text())["rows"]
r240 = json.loads((HERE / "rows_k_8000_s240.json").read_text())["rows"]
for row in ("clean", "specular_alt"):
    a = np.array([c["k"] for c in r60[row]["cases"]])
    b = np.array([c["k"] for c in r240[row]["cases"]])
    se_a = np.sqrt(np.mean([c["se"] ** 2 for c in r60[row]["cases"]]))
    se_b = np.sqrt(np.mean([c["se"] ** 2 for c in r240[row]["cases"]]))
    rho = stats.pearsonr(a, b)[0] if len(a) > 2 else float("nan")
    print(f"{row} ({len(a)} cases): 60 seeds mean {a.mean():+.3f} sd {a.std(ddof=1):.3f} (rms se {se_a:.3f}); "
          f"240 seeds mean {b.mean():+.3f} sd {b.std(ddof=1):.3f} (rms se {se_b:.3f}); "
          f"Pearson r between the two {rho:+.2f}")
    print("   60:", " ".join(f"{x:+.3f}" for x in a))
    print("  240:", " ".join(f"{x:+.3f}" for x in b))
