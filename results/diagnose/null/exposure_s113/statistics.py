"""Issue 20, stop 113: would weighting each seed by the precision of its w_d lift auto-exposure's absorbed channel
(w_d against the frame's brightness, within videos) at its weak strength (exposure_auto 0.5)? Reads dump.py's
arrays; no rendering.

    PYTHONPATH=. python results/diagnose/null/exposure_s113/statistics.py outputs/s113_expo \
        > results/diagnose/null/exposure_s113/statistics.txt

Per statistic: the floor by the calibration's rule (calibration.one_sided_floor, signed: a dependence of the wrong
sign counts as -|R²|) over the 44 calibration cases (24 converged of base 2000, 20 full fits of base 4000; the larger
of the two sets' floors, as the library's floors are the larger over its sets), the clean power and fresh cases over
it, and per exposure row the cases named (p_adj < 0.01 by permutation within videos, Bonferroni over the gray
screening's count; right sign; held-out R² above the floor). ``lin`` is the library's statistic; ``w_one`` is the
weighted code with equal weights, a check that it reproduces ``lin``.
"""
import glob
import sys

import numpy as np

from synthaug.diagnose.calibration import one_sided_floor
from synthaug.diagnose.screening import CANDIDATE_GRIDS, _cv_r2, kfold, n_screening_tests
from synthaug.diagnose.stats import permutation_correlation, within_groups

Z1 = 3.0842  # null_floors.SOURCE's one-sided z
N_TESTS = n_screening_tests(list(CANDIDATE_GRIDS))
N_PERM = 9_999


def wcentre(x, w, g):
    """``x`` (..., n) minus its ``w``-weighted mean within each video of ``g``."""
    out = np.empty_like(x)
    for v in np.unique(g):
        s = g == v
        out[..., s] = x[..., s] - (w[..., s] * x[..., s]).sum(-1, keepdims=True) / w[..., s].sum(-1, keepdims=True)
    return out


def weighted(x, y, w, g, folds, rng):
    """Weighted Pearson r within videos, its permutation p ((y, w) permuted within videos), held-out weighted R²."""
    def r_of(yy, ww):
        xc, yc = wcentre(np.broadcast_to(x, yy.shape), ww, g), wcentre(yy, ww, g)
        return (ww * xc * yc).sum(-1) / np.sqrt((ww * xc * xc).sum(-1) * (ww * yc * yc).sum(-1))
    r = float(r_of(y, w))
    perm = np.tile(np.arange(len(y)), (N_PERM, 1))
    for v in np.unique(g):
        s = np.nonzero(g == v)[0]
        perm[:, s] = s[rng.permuted(np.tile(np.arange(len(s)), (N_PERM, 1)), axis=1)]
    pval = (int((np.abs(r_of(y[perm], w[perm])) >= abs(r) - 1e-12).sum()) + 1) / (N_PERM + 1)
    idx = np.arange(len(y))
    xc, yc = wcentre(x, w, g), wcentre(y, w, g)
    e_lin = e_const = 0.0
    for held in folds:
        tr = np.setdiff1d(idx, held)
        sw = np.sqrt(w[tr])
        A = np.stack([np.ones(len(tr)), xc[tr]], 1) * sw[:, None]
        coef, *_ = np.linalg.lstsq(A, yc[tr] * sw, rcond=None)
        pred = coef[0] + coef[1] * xc[held]
        mean = (w[tr] * yc[tr]).sum() / w[tr].sum()
        e_lin += float((w[held] * (yc[held] - pred) ** 2).sum())
        e_const += float((w[held] * (yc[held] - mean) ** 2).sum())
    return float(r), float(pval), 1.0 - e_lin / max(e_const, 1e-12)


def stat(d, variant, seed=0):
    rng = np.random.default_rng(seed)
    folds = kfold(len(d["w"]), 5, rng)
    x, y, g = d["B"].astype(float), d["w"].astype(float), d["g"]
    if variant == "lin":
        r, p = permutation_correlation(x, y, rng, N_PERM, g, method="pearson")
        xm, ym = within_groups(x, g), within_groups(y, g)
        return r, p, _cv_r2(xm, ym, folds)
    w = {"w_one": np.ones_like(d["ss"]), "w_ss": d["ss"], "w_prec": d["ss"] / np.maximum(d["rv"], 1e-12),
         "w_sqrt_prec": np.sqrt(d["ss"] / np.maximum(d["rv"], 1e-12))}[variant]
    return weighted(x, y, w / w.mean(), g, folds, rng)


def signed(r, r2):
    return r2 if r < 0 else -abs(r2)  # exposure's predicted sign: w_d falls as the frame brightens


def main():
    cases = {f.split("/")[-1][:-4]: dict(np.load(f)) for f in sorted(glob.glob(f"{sys.argv[1]}/*.npz"))}
    sets = {"calib converged (2000)": "bench_diagnose_null_hand2000", "calib full (4000)": "bench_diagnose_null_full",
            "clean 8000": "bench_diagnose_power5_clean_", "clean 13000": "fresh13000_clean",
            "clean 11000": "fresh11000_clean", "clean 15000": "fresh15000_clean", "clean 17000": "fresh17000_clean"}
    rows = {"8000 auto 0.5": "bench_diagnose_power5_exposure__", "8000 auto 0.8": "bench_diagnose_power5_exposure_alt",
            **{f"{b} auto {s}": f"s113_{b}_exposure{x}__" for b in (13000, 11000, 15000, 17000)
               for s, x in (("0.5", ""), ("0.8", "_alt"))}}
    print(f"{len(cases)} cases; Bonferroni count {N_TESTS}, {N_PERM} permutations, z {Z1}")
    for variant in ("lin", "w_one", "w_ss", "w_prec", "w_sqrt_prec"):
        res = {n: stat(d, variant) for n, d in cases.items()}
        pick = lambda pre: [res[n] for n in res if n.startswith(pre)]  # noqa: E731
        floors = [one_sided_floor([signed(r, r2) for r, _, r2 in pick(sets[k])], Z1) for k in list(sets)[:2]]
        floor = max(floors)
        named = lambda r, p, r2: r < 0 and min(1.0, p * N_TESTS) < 0.01 and r2 > floor  # noqa: E731
        out = [f"{variant:12s} floor {floor:.3f} ({floors[0]:.3f}, {floors[1]:.3f})"]
        for k in list(sets)[2:]:
            v = pick(sets[k])
            out.append(f"{k}: {sum(named(*t) for t in v)}/{len(v)}")
        print(" | ".join(out))
        for k, pre in rows.items():
            v = pick(pre)
            if v:
                print(f"    {k}: named {sum(named(*t) for t in v)}/{len(v)}  "
                      + " ".join(f"{'Y' if named(*t) else 'n'}{t[2]:.2f}/{min(1.0, t[1] * N_TESTS):.3f}" for t in v))


if __name__ == "__main__":
    main()
