"""Issue 20, stop 110: the highlight channel's clean values added to the calibration, without touching the rest.

For each calibration output (``bench_diagnose_null.py`` JSON) its cases are made again with the command it records
(``make_case``: the same seeds, nuisances and fit), checked against it (the specular candidate's stored held-out
pixel gain, case by case), and the highlight statistic (``screening.highlight_strength``, the raw ``k``) is added to
a copy of the output as ``screen:specular:highlight``; every other statistic is copied as it is. The floors are then
pooled from the copies (``bench_diagnose_null.py --floors-from COPIES --write-floors``).

    PYTHONPATH=. python results/diagnose/null/highlight_s110/recalibrate.py \
        --calibration \
        results/diagnose/null/centre_s100/calibration/calibration_set_hand.json=outputs/bench_diagnose_null_hand2000 \
        results/diagnose/null/centre_s100/calibration/full_fit_calibrated.json=outputs/bench_diagnose_null_full \
        --write-dir results/diagnose/null/highlight_s110/calibration --tol 5e-3  # ~20 min, cases made again
"""
from __future__ import annotations

import argparse
import json
import shlex
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[4]
sys.path.insert(0, str(ROOT / "benchmarks"))


def case_args(command: str) -> argparse.Namespace:
    """The arguments of a recorded bench command, parsed by the bench's own command line (its defaults where the
    command left them)."""
    from bench_diagnose_null import parser

    return parser().parse_args(shlex.split(command.split(" <- ")[0])[2:])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--calibration", nargs="+", required=True, metavar="JSON=WORKDIR")
    ap.add_argument("--write-dir", required=True)
    ap.add_argument("--tol", type=float, default=2e-3,
                    help="largest stored-vs-remade gain difference accepted (2e-3: two thirds of a clean sd)")
    a = ap.parse_args()
    import torch

    torch.set_num_threads(1)
    from bench_diagnose_null import make_case
    from synthaug.diagnose import screening as S
    from synthaug.diagnose.diagnosis_data import load_diagnosis_data

    out_dir = Path(a.write_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    for spec in a.calibration:
        path, work = spec.split("=")
        d = json.loads(Path(path).read_text())
        ns = case_args(d["command"])
        stored = d["null_distributions"]["screen:specular:distance:pixel"]["gain"]["values"]
        ks, diffs, t0 = [], [], time.perf_counter()
        for k in range(d["cases"]):
            seeds, fit, _, _ = make_case(Path(work), k, ns)
            data = load_diagnosis_data(seeds, fit, "quadcopter")
            folds = S.kfold(len(data), 5, np.random.default_rng(0))
            syn, _ = S.base_render(data)
            sc = S.screen_one(data, "specular", folds, (S.pairwise_distance(data, syn),
                                                        S.pixel_distance(data.real, syn)))
            diffs.append(abs(sc["pixel"]["gain"] - stored[k]))
            ks.append(S.highlight_strength(data)["k"])
            print(f"{path} case {k}: k {ks[-1]:+.4f}, specular pixel gain {sc['pixel']['gain']:+.6f} (stored "
                  f"{stored[k]:+.6f})", flush=True)
        if max(diffs) > a.tol:
            raise SystemExit(f"{path}: the remade cases differ from the stored ones (largest gain difference "
                             f"{max(diffs):.2e}); not written")
        v = np.asarray(ks)
        d["null_distributions"]["screen:specular:highlight"] = {
            "n": len(v), "significant": 0,
            "gain": {"mean": float(v.mean()), "sd": float(v.std(ddof=1)), "min": float(v.min()),
                     "median": float(np.median(v)), "max": float(v.max()), "values": [round(float(x), 6) for x in v]}}
        d["highlight_refresh"] = {"by": " ".join(["python"] + sys.argv), "largest_gain_difference": max(diffs),
                                  "seconds": time.perf_counter() - t0}
        target = out_dir / Path(path).name
        target.write_text(json.dumps(d, indent=1))
        print(json.dumps({"wrote": str(target), "cases": len(v), "k_mean": float(v.mean()),
                          "k_sd": float(v.std(ddof=1)), "k_max": float(v.max()),
                          "largest_gain_difference": max(diffs)}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
