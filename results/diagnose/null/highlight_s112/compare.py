"""Issue 20, stop 112: the highlight estimator with the shading nuisances' regressors (gram.py's columns), compared
offline as stop 111's compare.py does (the library's floor rule and the channel's test on every cached case).

    PYTHONPATH=. python results/diagnose/null/highlight_s112/compare.py outputs/s112_gram_calib_spec.npz \
        outputs/s112_gram_clean.npz
"""
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "highlight_s111"))
from compare import Z, case_pooled, channel_names, is_calibration, load_all, spread_parts  # noqa: E402

from synthaug.diagnose.calibration import one_sided_floor  # noqa: E402

BASE = ["s", "h80"]
EXTRA = {
    "h80 (library)": [],
    "+lx,ly": ["lx", "ly"],
    "+sm": ["sm"],
    "+amb": ["amb"],
    "+lx,ly,sm": ["lx", "ly", "sm"],
    "+lx,ly,amb": ["lx", "ly", "amb"],
    "+lx,ly,sm,amb": ["lx", "ly", "sm", "amb"],
    "+sm,amb": ["sm", "amb"],
    "+lx,ly,sm,amb,gx,gy": ["lx", "ly", "sm", "amb", "gx", "gy"],
}


def main():
    ci, cases = load_all(sys.argv[1:])
    print("| model | converged μ±σ | full fits μ±σ | floor | clean power > floor (max) | clean seed ⊕ case sd "
          "| default named | wider named | wider k |")
    print("|---|---|---|---|---|---|---|---|---|")
    for h in ("h80", "h45"):
        for name, extra in EXTRA.items():
            cols = ["s", h] + extra
            res = case_pooled(cases, ci, cols, [0, 1] + [0] * len(extra))
            cal = np.array([r[0] for n, r in res.items() if is_calibration(n)])
            hand = np.array([r[0] for n, r in res.items() if "hand2000" in n])
            full = np.array([r[0] for n, r in res.items() if "null_full" in n])
            centre, floor = cal.mean(), one_sided_floor(cal, Z)
            named = {n: channel_names(*r, centre, floor) for n, r in res.items()}
            clean = [n for n in res if "_clean/" in n]
            seed, casel = spread_parts([res[n][0] for n in clean], [res[n][1] for n in clean])
            dflt = [named[n] for n in res if "specular/" in n]
            alt = [n for n in res if "specular_alt/" in n]
            altn = [named[n] for n in alt]
            per_set = lambda rows: "+".join(str(sum(rows[i:i + 5])) for i in range(0, len(rows), 5))  # noqa: E731
            label = name if h == "h80" else name.replace("h80 (library)", "h45") + " (h45)"
            print(f"| {label} | {hand.mean():.3f}±{hand.std(ddof=1):.3f} | {full.mean():.3f}±{full.std(ddof=1):.3f} "
                  f"| {floor:.3f} | {sum(named[n] for n in clean)}/{len(clean)} "
                  f"({max(res[n][0] for n in clean):.3f}) | {seed:.3f} ⊕ {casel:.3f} "
                  f"| {sum(dflt)}/{len(dflt)} ({per_set(dflt)}) | {sum(altn)}/{len(altn)} ({per_set(altn)}) | "
                  f"{' '.join(f'{res[n][0]:.2f}' for n in alt)} |", flush=True)


if __name__ == "__main__":
    main()
