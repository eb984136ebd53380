"""Stop 95: would another statistic of auto-exposure's absorbed channel (the fitted w_d against the frame's
brightness, within videos) find the weak power row (exposure_auto 0.5) more often? Reads the (w_d, frame brightness,
video) arrays dumped by dump_wd.py; no rendering (≈ 1 min).

    PYOPENGL_PLATFORM=egl python results/diagnose/null/exposure_s95/dump_wd.py outputs/exposure_s95_wd \
        outputs/bench_diagnose_power5_*/case_* outputs/bench_diagnose_null_hand2000/case_*   # ≈ 7 s a case
    PYTHONPATH=. python results/diagnose/null/exposure_s95/statistics.py > results/diagnose/null/exposure_s95/statistics.txt

Per statistic: its clean null (the 24 converged clean cases of seed base 2000, and as a second null the gray power
rows of the other effects), the one-sided floor by the calibration's rule (signed: a dependence of the wrong sign
counts as -|R²|), and each exposure case: Y/n (p_adj < 0.01, right sign, held-out R² above the clean floor),
R² / p_adj. The statistic in use is ``lin`` (Pearson of the values, within videos).
"""
import glob
import sys

import numpy as np

from synthaug.diagnose.calibration import one_sided_floor
from synthaug.diagnose.screening import _cv_r2, kfold
from synthaug.diagnose.stats import permutation_correlation, within_groups

Z1, N_TESTS, ALPHA = 3.0781, 41, 0.01  # null_floors.SOURCE's z (48 statistics); a gray case's Bonferroni count


def wins(y, g, c=2.5):
    """``y`` clipped per video at its median ± c MADs."""
    y = y.copy()
    for v in np.unique(g):
        s = g == v
        med = np.median(y[s])
        mad = 1.4826 * np.median(np.abs(y[s] - med))
        y[s] = np.clip(y[s], med - c * mad, med + c * mad)
    return y


def stat(B, w, g, variant, seed=0):
    rng = np.random.default_rng(seed)
    folds = kfold(len(w), 5, rng)
    x, y = B.astype(float), w.astype(float)
    if variant.startswith("log"):
        x, y = np.log(x), np.log(np.maximum(y, 1e-3))
    if "wins" in variant:
        y = wins(y, g, float(variant.split("wins")[1] or 2.5))
        x = wins(x, g, 3.0) if "xw" in variant else x
    r, p = permutation_correlation(x, y, rng, 9999, g, method="pearson")
    xm, ym = within_groups(x, g), within_groups(y, g)
    ok = np.isfinite(xm) & np.isfinite(ym)
    keep = np.cumsum(ok) - 1
    f_ok = [keep[h[ok[h]]] for h in folds]
    return r, p, _cv_r2(xm[ok], ym[ok], f_ok)


def signed(t):
    r, _, g = t
    return g if r < 0 else -abs(g)  # exposure's w_d falls with the frame's brightness


variants = sys.argv[1:] or ["lin", "lin_wins2.5", "lin_wins2", "log", "log_wins2.5", "lin_xw_wins2.5"]
folder = "outputs/exposure_s95_wd"
res = {}
for f in sorted(glob.glob(f"{folder}/*.npz")):
    d = np.load(f)
    res[f.split("/")[-1][:-4]] = {v: stat(d["B"], d["w"], d["g"], v) for v in variants}
clean = [n for n in res if "null_hand2000" in n]
others = [n for n in res if "power5" in n and "exposure" not in n]
expo = sorted(n for n in res if "exposure" in n)
print(f"{len(clean)} clean cases, {len(others)} cases of other effects, {len(expo)} exposure cases "
      f"({', '.join(sorted({n.split('__')[0] for n in expo}))})")
for v in variants:
    for label, null in (("clean", clean), ("other rows", others)):
        if not null:
            continue
        s = np.array([signed(res[n][v]) for n in null])
        floor = one_sided_floor(s, Z1)
        fa = sum(1 for n in null if res[n][v][1] * N_TESTS < ALPHA and signed(res[n][v]) > floor)
        cells = []
        for n in expo:
            r, p, g2 = res[n][v]
            hit = p * N_TESTS < ALPHA and r < 0 and g2 > floor
            cells.append(("Y" if hit else "n") + f"{g2:.2f}/{min(p * N_TESTS, 1):.3f}")
        print(f"{v:15s} null={label:10s} n={len(null):2d} mean={s.mean():+.3f} sd={s.std(ddof=1):.3f} "
              f"floor={floor:.3f} alarms={fa} | " + " ".join(cells))
