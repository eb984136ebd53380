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
from compare import case_pooled, load_all, spread_parts  # noqa: E402

SHIN = os.environ.get("SHIN", "80")


def main():
    ci, cases = load_all(sys.argv[1:])
    res = case_pooled(cases, ci, ["s", f"h{SHIN}"], [0.0, 1.0])
    print(f"## exponent {SHIN}: specular cases against their clean twins")
    for pre in ("bench_diagnose_power5", "fresh13000", "fresh11000"):
        for i in range(5):
            t, d, a = (res[f"outputs/{pre}_{row}/case_{i:03d}"][0] for row in ("clean", "specular", "specular_alt"))
            print(f"{pre} case {i}: twin {t:+.3f}; default {d:.3f} (+{d - t:.3f}); wider {a:.3f} (+{a - t:.3f})")
    print("## the clean spread: seed-level and case-level parts")
    for name, sel in (("converged calibration", "null_hand2000"), ("full-fit calibration", "null_full"),
                      ("clean power cases", "_clean/")):
        ks, ses = zip(*[r[:2] for n, r in res.items() if sel in n])
        seed, case = spread_parts(ks, ses)
        print(f"{name} ({len(ks)}): sd {np.std(ks, ddof=1):.3f} = seed-level {seed:.3f} (+) case-level {case:.3f}")


if __name__ == "__main__":
    main()
