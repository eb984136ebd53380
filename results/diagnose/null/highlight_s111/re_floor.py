"""Issue 20, stop 111 (an idea measured offline, not adopted): a random-effects floor for the highlight — the clean
cases' case-level spread tau (their k's variance less their own errors') combined with each case's own error:
floor_i = max(centre, 0) + z · sqrt(tau² + se_i²), instead of one floor for every seed count and fit.

    PYTHONPATH=. python results/diagnose/null/highlight_s111/re_floor.py outputs/s111_gram_calib_spec.npz \
        outputs/s111_gram_clean.npz
"""
import sys
from pathlib import Path

import numpy as np
from scipy import stats

sys.path.insert(0, str(Path(__file__).parent))
from compare import ALPHA, NTEST, Z, load, per_seed, pooled  # noqa: E402


def main():
    cases = []
    for p in sys.argv[1:]:
        cols, cs = load(p)
        cases += cs
    ci = {c: i for i, c in enumerate(cols)}
    for shin in ("45", "80"):
        idx = [ci["s"], ci[f"h{shin}"]]
        res = {}
        for case in cases:
            k, v = per_seed(case, idx, np.array([0.0, 1.0]))
            res[case["name"]] = (*pooled(k, v, "mean"), len(k))
        cal = [res[n] for n in res if "null_hand2000" in n or "null_full" in n]
        m = np.array([r[0] for r in cal])
        se = np.array([r[1] for r in cal])
        centre = m.mean()
        tau = float(np.sqrt(max(m.var(ddof=1) - (se ** 2).mean(), 0.0)))

        def named(r):
            floor = max(centre, 0.0) + Z * np.sqrt(tau ** 2 + r[1] ** 2)
            return r[0] > floor and stats.t.sf((r[0] - centre) / r[1], r[2] - 1) * NTEST < ALPHA
        cal_over = sum(named(r) for r in cal)
        clean = [named(res[n]) for n in res if "_clean/" in n]
        dflt = [named(res[n]) for n in sorted(res) if "specular/" in n]
        alt = [named(res[n]) for n in sorted(res) if "specular_alt/" in n]
        print(f"exponent {shin}: centre {centre:.3f}, tau {tau:.3f}; calibration cases over their floor {cal_over}/44; "
              f"clean power {sum(clean)}/60; default {sum(dflt)}/15; wider {sum(alt)}/15")


if __name__ == "__main__":
    main()
