"""Issue 20, stop 110: the highlight statistic on the power table's cases of every row, without the diagnosis.

Each row's cases are made as ``bench_diagnose_null.py --hidden EFFECT --strength S --base-seed B`` makes them (the same
workdirs, so a later bench run finds them cached) and ``screening.highlight_strength`` (centre: the calibrated clean
mean) is read on each; the row's k values are printed against the calibrated floor, and written as JSON.

    PYTHONPATH=. python results/diagnose/null/highlight_s110/rows_k.py --base-seed 8000 --out OUT.json ROW...

ROW: effect or effect_alt (e.g. haze haze_alt), clean (20 cases), effect_colour for colour cases. ``--seeds 240``
(stop 111): the same cases' nuisances and draws with 240 seeds each, made in their own folders.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[4]
sys.path.insert(0, str(ROOT / "benchmarks"))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("rows", nargs="+")
    ap.add_argument("--base-seed", type=int, required=True)
    ap.add_argument("--cases", type=int, default=5)
    ap.add_argument("--seeds", type=int, default=60,
                    help="seeds a case (stop 111); other than 60 the cases go to outputs/<row dir>_s<seeds>")
    ap.add_argument("--clean-cases", type=int, default=20)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    import torch

    torch.set_num_threads(1)
    from bench_diagnose_null import make_case, parser
    from synthaug.diagnose.calibration import gain_centre, gain_floor
    from synthaug.diagnose.diagnosis_data import load_diagnosis_data
    from synthaug.diagnose.screening import highlight_strength

    pre = "bench_diagnose_power5" if a.base_seed == 8000 else f"fresh{a.base_seed}"
    centre, floor = gain_centre("specular", "highlight"), gain_floor("specular", "highlight")
    out = {"command": " ".join(["python"] + sys.argv), "centre": centre, "floor": floor, "rows": {}}
    for row in a.rows:
        effect = None if row == "clean" else row.removesuffix("_alt").removesuffix("_colour")
        # the bench's own arguments, as run_rows.sh passes them (its defaults for the rest)
        ns = parser().parse_args(["--base-seed", str(a.base_seed), "--seeds", str(a.seeds), "--strength",
                                  "alt" if row.endswith("_alt") else "default"]
                                 + (["--hidden", effect] if effect else [])
                                 + (["--colour"] if row.endswith("_colour") or "_colour_" in row else []))
        n = a.clean_cases if row == "clean" else a.cases
        work = ROOT / "outputs" / (f"{pre}_{row}" + ("" if a.seeds == 60 else f"_s{a.seeds}"))
        ks, t0 = [], time.perf_counter()
        for k in range(n):
            seeds, fit, _, _ = make_case(work, k, ns)
            hl = highlight_strength(load_diagnosis_data(seeds, fit, "quadcopter"), centre=centre)
            ks.append({"k": hl["k"], "se": hl["se"], "p": hl["p"]})
        over = sum(1 for r in ks if floor is not None and r["k"] > floor)
        out["rows"][row] = {"cases": ks, "over_floor": over, "seconds": time.perf_counter() - t0}
        print(f"{row}: k {' '.join(format(r['k'], '+.3f') for r in ks)}; over the floor {floor}: {over}/{n}",
              flush=True)
        Path(a.out).write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
