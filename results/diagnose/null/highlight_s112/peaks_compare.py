"""Issue 20, stop 112: peaks.py's statistics judged as the library judges the highlight's k: pooled per case (mean or
median over seeds), the floor by the library's rule over the 44 calibration cases (``one_sided_floor`` at z 3.0842),
a one-sided t-test over seeds against the calibration mean at 49 tests, then the specular rows and the clean cases
over it; per-set counts in the order the cases were given.

    PYTHONPATH=. python results/diagnose/null/highlight_s112/peaks_compare.py outputs/s112_peaks_A.npz \
        outputs/s112_peaks_B.npz
"""
import sys

import numpy as np
from scipy import stats

from synthaug.diagnose.calibration import one_sided_floor

Z, NTEST, ALPHA = 3.0842, 49, 0.01


def main():
    cases = []
    names = None
    for p in sys.argv[1:]:
        d = np.load(p)
        names = list(d["stats"])
        cases += [(str(c), d[f"{i}:stats"]) for i, c in enumerate(d["cases"])]
    print("| statistic | pooling | converged μ±σ | full fits μ±σ | floor | clean > floor (max) | default named "
          "| wider named |")
    print("|---|---|---|---|---|---|---|---|")
    for j, st in enumerate(names[:-1]):
        for how in ("mean", "median"):
            res = {}
            for name, s in cases:
                v = s[:, j][np.isfinite(s[:, j])]
                m = float(v.mean() if how == "mean" else np.median(v))
                res[name] = (m, float(v.std(ddof=1) / np.sqrt(len(v))), len(v))
            cal = np.array([r[0] for n, r in res.items() if "null_hand2000" in n or "null_full" in n])
            hand = np.array([r[0] for n, r in res.items() if "hand2000" in n])
            full = np.array([r[0] for n, r in res.items() if "null_full" in n])
            centre, floor = cal.mean(), one_sided_floor(cal, Z)
            named = {n: bool(k > floor and stats.t.sf((k - centre) / se, n_ - 1) * NTEST < ALPHA)
                     for n, (k, se, n_) in res.items()}
            clean = [n for n in res if "_clean/" in n]
            dflt = [named[n] for n in res if "specular/" in n]
            alt = [named[n] for n in res if "specular_alt/" in n]
            per_set = lambda rows: "+".join(str(sum(rows[i:i + 5])) for i in range(0, len(rows), 5))  # noqa: E731
            print(f"| {st} | {how} | {hand.mean():.4f}±{hand.std(ddof=1):.4f} "
                  f"| {full.mean():.4f}±{full.std(ddof=1):.4f}"
                  f" | {floor:.4f} | {sum(named[n] for n in clean)}/{len(clean)} ({max(res[n][0] for n in clean):.4f}) "
                  f"| {sum(dflt)}/{len(dflt)} ({per_set(dflt)}) | {sum(alt)}/{len(alt)} ({per_set(alt)}) |")


if __name__ == "__main__":
    main()
