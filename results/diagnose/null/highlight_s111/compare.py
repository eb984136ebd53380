"""Issue 20, stop 111: highlight estimators compared offline from gram.py's cached normal equations.

For each model (a subset of gram.py's columns and the statistic, a combination of their coefficients): per seed the
least-squares statistic and its error; pooled per case (weights 1/se², or the weighted median); the floor as the
library sets it (calibration.one_sided_floor at z 3.0842 over the 44 calibration cases: 24 converged, 20 full fits);
then the specular rows' cases above the floor (with the t-test at 49 tests) and the clean power cases above it.

    PYTHONPATH=. python results/diagnose/null/highlight_s111/compare.py outputs/s111_gram_calib_spec.npz \
        outputs/s111_gram_clean.npz
    SHINES=120,160,240 PYTHONPATH=. python ... outputs/s111_gramB_calib_spec.npz outputs/s111_gramB_clean.npz
"""
import os
import sys

import numpy as np
from scipy import stats

from synthaug.diagnose.calibration import one_sided_floor

Z, NTEST, ALPHA = 3.0842, 49, 0.01


def load(path):
    d = np.load(path)
    cols = list(d["cols"])
    cases = []
    for i, c in enumerate(d["cases"]):
        cases.append({"name": str(c), **{k: d[f"{i}:{k}"] for k in ("G", "b", "yy", "npix", "hidden_ks", "nuis_ks")}})
    return cols, cases


def per_seed(case, idx, c):
    G = case["G"][:, idx][:, :, idx]
    b = case["b"][:, idx]
    out_k, out_v = [], []
    for i in range(len(b)):
        g = G[i]
        if g[1, 1] < 1e-8 or np.linalg.cond(g) > 1e10:
            continue
        gi = np.linalg.inv(g)
        beta = gi @ b[i]
        rss = case["yy"][i] - b[i] @ beta
        out_k.append(c @ beta)
        out_v.append(max(rss / (int(case["npix"]) - len(idx)), 1e-12) * (c @ gi @ c))
    return np.array(out_k), np.array(out_v)


def pooled(k, v, how):
    w = 1 / v
    if how == "median":
        o = np.argsort(k)
        cw = np.cumsum(w[o]) / w.sum()
        m = float(k[o][np.searchsorted(cw, 0.5)])
    elif how == "huber":
        m = float((w * k).sum() / w.sum())
        for _ in range(20):
            r = (k - m) * np.sqrt(w)
            s = 1.4826 * np.median(np.abs(r))
            hw = np.minimum(1, 1.5 * s / np.maximum(np.abs(r), 1e-12))
            m = float((w * hw * k).sum() / (w * hw).sum())
    else:
        m = float((w * k).sum() / w.sum())
    n = len(k)
    se = float(np.sqrt((w * w * (k - m) ** 2).sum() * n / (n - 1)) / w.sum())
    return m, se


def main():
    cols, cases = [], []
    for p in sys.argv[1:]:
        cols, cs = load(p)
        cases += cs
    ci = {c: i for i, c in enumerate(cols)}
    models = {
        "h45 (adopted)": (["s", "h45"], [0, 1]),
        "h30": (["s", "h30"], [0, 1]),
        "h20": (["s", "h20"], [0, 1]),
        "h80": (["s", "h80"], [0, 1]),
        "h45+shift": (["s", "h45", "gx", "gy"], [0, 1, 0, 0]),
        "h45+shift+scale": (["s", "h45", "gx", "gy", "gs"], [0, 1, 0, 0, 0]),
        "h20+shift+scale": (["s", "h20", "gx", "gy", "gs"], [0, 1, 0, 0, 0]),
        "h10+h45 sum": (["s", "h10", "h45"], [0, 1, 1]),
        "h20+h80 sum": (["s", "h20", "h80"], [0, 1, 1]),
        "h10+h45 sum+shift+scale": (["s", "h10", "h45", "gx", "gy", "gs"], [0, 1, 1, 0, 0, 0]),
        "h80+shift": (["s", "h80", "gx", "gy"], [0, 1, 0, 0]),
        "h80+shift+scale": (["s", "h80", "gx", "gy", "gs"], [0, 1, 0, 0, 0]),
        "h30+h80 sum": (["s", "h30", "h80"], [0, 1, 1]),
        "h10+h80 sum": (["s", "h10", "h80"], [0, 1, 1]),
    }
    if os.environ.get("SHINES"):  # gram.py run with other exponents: one model per exponent, with and without shifts
        models = {}
        for e in os.environ["SHINES"].split(","):
            models[f"h{e}"] = (["s", f"h{e}"], [0, 1])
            models[f"h{e}+shift"] = (["s", f"h{e}", "gx", "gy"], [0, 1, 0, 0])
    groups = {"calib": lambda n: "null_hand2000" in n or "null_full" in n}
    for how in sys.argv[0:0] or ("mean", "median", "huber"):
        print(f"\n## pooling: {how}")
        print("| model | hand μ±σ | full μ±σ | floor | clean power >floor (max) | default named | alt named "
              "| alt k |")
        print("|---|---|---|---|---|---|---|---|")
        for name, (cs, c) in models.items():
            idx = [ci[x] for x in cs]
            res = []
            for case in cases:
                k, v = per_seed(case, idx, np.array(c, float))
                m, se = pooled(k, v, how)
                res.append((case["name"], m, se, len(k)))
            cal = np.array([m for n, m, *_ in res if groups["calib"](n)])
            hand = np.array([m for n, m, *_ in res if "hand2000" in n])
            full = np.array([m for n, m, *_ in res if "null_full" in n])
            centre = cal.mean()
            floor = one_sided_floor(cal, Z)
            clean = np.array([m for n, m, *_ in res if "_clean/" in n])

            def named(n, m, se, nn):
                t = (m - centre) / se
                return m > floor and stats.t.sf(t, nn - 1) * NTEST < ALPHA
            dflt = [named(*r) for r in res if "specular/" in r[0]]
            per_set = lambda rows: "+".join(str(sum(rows[i:i + 5])) for i in range(0, len(rows), 5))
            alt = [r for r in res if "specular_alt/" in r[0]]
            altn = [named(*r) for r in alt]
            print(f"| {name} | {hand.mean():.3f}±{hand.std(ddof=1):.3f} | {full.mean():.3f}±{full.std(ddof=1):.3f} | "
                  f"{floor:.3f} | {sum(named(*r) for r in res if '_clean/' in r[0])}/{len(clean)} ({clean.max():.3f}) "
                  f"| {sum(dflt)}/{len(dflt)} ({per_set(dflt)}) | {sum(altn)}/{len(altn)} ({per_set(altn)}) | "
                  f"{' '.join(f'{r[1]:.2f}' for r in alt)} |", flush=True)


if __name__ == "__main__":
    main()
