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


def load_all(paths):
    """The cases of several gram.py outputs (the same columns) and the columns' index."""
    cols, cases = [], []
    for p in paths:
        cols, cs = load(p)
        cases += cs
    return {c: i for i, c in enumerate(cols)}, cases


def is_calibration(name):
    """A case of the 44 clean calibration cases (24 converged, 20 full fits)."""
    return "null_hand2000" in name or "null_full" in name


def case_pooled(cases, ci, columns, c, how="mean"):
    """{case name: (pooled statistic, its error, seeds used)} of the model ``columns`` (gram.py's names), statistic
    ``c`` (one weight per column)."""
    idx, c = [ci[x] for x in columns], np.asarray(c, float)
    out = {}
    for case in cases:
        k, v = per_seed(case, idx, c)
        out[case["name"]] = (*pooled(k, v, how), len(k))
    return out


def channel_names(k, se, n, centre, floor):
    """The channel's test: k over the floor and the one-sided t-test against the centre rejecting (Bonferroni)."""
    return k > floor and stats.t.sf((k - centre) / se, n - 1) * NTEST < ALPHA


def spread_parts(ks, ses):
    """The cases' spread of k split into a seed-level part (the rms of their own errors) and the case-level rest."""
    seed = float(np.sqrt((np.asarray(ses) ** 2).mean()))
    return seed, float(np.sqrt(max(np.var(ks, ddof=1) - seed ** 2, 0.0)))


def judged(res, default_key="specular/"):
    """The library's rule applied to ``res`` ({case name: (pooled k, its error, seeds)}): the floor over the 44
    calibration cases (``one_sided_floor`` at z Z), the channel's test on every case; the calibration cases' k
    (``hand``: converged, ``full``: full fits), the clean and wider cases' names, how many clean cases are named, and
    the default (``default_key`` in the name) and wider (``specular_alt/``) rows named, as "named/cases (per set of 5)".
    """
    cal = np.array([r[0] for n, r in res.items() if is_calibration(n)])
    centre, floor = cal.mean(), one_sided_floor(cal, Z)
    named = {n: channel_names(*r, centre, floor) for n, r in res.items()}
    clean = [n for n in res if "_clean/" in n]
    alt = [n for n in res if "specular_alt/" in n]

    def count(rows):
        return f"{sum(rows)}/{len(rows)} (" + "+".join(str(sum(rows[i:i + 5])) for i in range(0, len(rows), 5)) + ")"

    return {"hand": np.array([r[0] for n, r in res.items() if "hand2000" in n]),
            "full": np.array([r[0] for n, r in res.items() if "null_full" in n]), "floor": floor,
            "clean": clean, "alt": alt, "clean_named": sum(named[n] for n in clean),
            "default": count([named[n] for n in res if default_key in n]), "wider": count([named[n] for n in alt])}


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
    ci, cases = load_all(sys.argv[1:])
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
    for how in ("mean", "median", "huber"):
        print(f"\n## pooling: {how}")
        print("| model | hand μ±σ | full μ±σ | floor | clean power >floor (max) | default named | alt named "
              "| alt k |")
        print("|---|---|---|---|---|---|---|---|")
        for name, (cs, c) in models.items():
            res = case_pooled(cases, ci, cs, c, how)
            j = judged(res)
            hand, full, clean, alt = j["hand"], j["full"], j["clean"], j["alt"]
            print(f"| {name} | {hand.mean():.3f}±{hand.std(ddof=1):.3f} | {full.mean():.3f}±{full.std(ddof=1):.3f} | "
                  f"{j['floor']:.3f} | {j['clean_named']}/{len(clean)} ({max(res[n][0] for n in clean):.3f}) "
                  f"| {j['default']} | {j['wider']} | {' '.join(f'{res[n][0]:.2f}' for n in alt)} |", flush=True)


if __name__ == "__main__":
    main()
