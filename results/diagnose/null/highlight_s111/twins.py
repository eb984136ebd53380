"""Issue 20, stop 111: what limits the highlight channel, from gram.py's cached normal equations (exponent SHIN).

1. Each specular case against its clean twin (the clean row's case of the same base seed and index: the same scenes,
   nuisances and poses, nothing hidden): the twin's k and what the hidden highlight adds to it.
2. The clean spread of the pooled k split into a seed-level part (the rms of the cases' sandwich errors) and a
   case-level part (the rest of the cases' variance): what more seeds would and would not remove.

    PYTHONPATH=. python results/diagnose/null/highlight_s111/twins.py outputs/s111_gram_calib_spec.npz \
        outputs/s111_gram_clean.npz
"""
import os
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from compare import load, per_seed, pooled  # noqa: E402

SHIN = os.environ.get("SHIN", "80")


def main():
    cases = []
    for p in sys.argv[1:]:
        cols, cs = load(p)
        cases += cs
    ci = {c: i for i, c in enumerate(cols)}
    idx, c = [ci["s"], ci[f"h{SHIN}"]], np.array([0.0, 1.0])
    k_of, se_of = {}, {}
    for case in cases:
        k, v = per_seed(case, idx, c)
        k_of[case["name"]], se_of[case["name"]] = pooled(k, v, "mean")
    print(f"## exponent {SHIN}: specular cases against their clean twins")
    for pre in ("bench_diagnose_power5", "fresh13000", "fresh11000"):
        for i in range(5):
            t = k_of[f"outputs/{pre}_clean/case_{i:03d}"]
            d, a = k_of[f"outputs/{pre}_specular/case_{i:03d}"], k_of[f"outputs/{pre}_specular_alt/case_{i:03d}"]
            print(f"{pre} case {i}: twin {t:+.3f}; default {d:.3f} (+{d - t:.3f}); wider {a:.3f} (+{a - t:.3f})")
    print("## the clean spread: seed-level and case-level parts")
    for name, sel in (("converged calibration", "null_hand2000"), ("full-fit calibration", "null_full"),
                      ("clean power cases", "_clean/")):
        ks = np.array([k_of[n] for n in k_of if sel in n])
        ses = np.array([se_of[n] for n in k_of if sel in n])
        seed = float(np.sqrt((ses ** 2).mean()))
        case = float(np.sqrt(max(ks.var(ddof=1) - seed ** 2, 0.0)))
        print(f"{name} ({len(ks)}): sd {ks.std(ddof=1):.3f} = seed-level {seed:.3f} (+) case-level {case:.3f}")


if __name__ == "__main__":
    main()
