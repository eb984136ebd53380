"""Issue 20, stop 113: how much the frames' brightness moves within each video of each auto-exposure case, beside
the library's held-out R² there (what limits the weak strength: the signal or the w_d's noise). Reads dump.py's
arrays.

    PYTHONPATH=. python results/diagnose/null/exposure_s113/brightness_range.py outputs/s113_expo \
        > results/diagnose/null/exposure_s113/brightness_range.txt
"""
import glob
import sys

import numpy as np
from scipy import stats

from synthaug.diagnose.screening import _cv_r2, kfold
from synthaug.diagnose.stats import within_groups


def main():
    rows = []
    for f in sorted(glob.glob(f"{sys.argv[1]}/*exposure*.npz")):
        d = np.load(f)
        g = d["g"]
        lb, lw = within_groups(np.log(d["B"]), g), within_groups(np.log(d["w"]), g)
        r2 = _cv_r2(within_groups(d["B"], g), within_groups(d["w"], g), kfold(len(g), 5, np.random.default_rng(0)))
        alt = "_alt" in f
        rows.append((alt, float(np.nanstd(lb)), float(np.nanstd(lw)), r2))
        print(f"{f.split('/')[-1][:-4]:48s} sd log B within {rows[-1][1]:.3f}  sd log w_d within {rows[-1][2]:.3f}"
              f"  held-out R² {r2:.2f}")
    for alt in (False, True):
        v = np.array([r[1:] for r in rows if r[0] == alt])
        rho, p = stats.spearmanr(v[:, 0], v[:, 2])
        print(f"auto {'0.8' if alt else '0.5'}: {len(v)} cases, Spearman(sd log B, R²) {rho:.2f} (p {p:.3f}); "
              f"median sd log B {np.median(v[:, 0]):.3f}, sd log w_d {np.median(v[:, 1]):.3f}")


if __name__ == "__main__":
    main()
