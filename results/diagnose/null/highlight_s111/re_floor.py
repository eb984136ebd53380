"""Issue 20, stop 111 (an idea measured offline, not adopted): a random-effects floor for the highlight — the clean
cases' case-level spread tau (their k's variance less their own errors') combined with each case's own error:
floor_i = max(centre, 0) + z · sqrt(tau² + se_i²), instead of one floor for every seed count and fit.

    PYTHONPATH=. python results/diagnose/null/highlight_s111/re_floor.py outputs/s111_gram_calib_spec.npz \
        outputs/s111_gram_clean.npz
"""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from compare import Z, case_pooled, channel_names, is_calibration, load_all, spread_parts  # noqa: E402


def main():
    ci, cases = load_all(sys.argv[1:])
    for shin in ("45", "80"):
        res = case_pooled(cases, ci, ["s", f"h{shin}"], [0.0, 1.0])
        cal = [r for n, r in res.items() if is_calibration(n)]
        m = np.array([r[0] for r in cal])
        centre = m.mean()
        tau = spread_parts(m, [r[1] for r in cal])[1]

        def named(r):
            return channel_names(*r, centre, max(centre, 0.0) + Z * np.sqrt(tau ** 2 + r[1] ** 2))
        cal_over = sum(named(r) for r in cal)
        clean = [named(r) for n, r in res.items() if "_clean/" in n]
        dflt = [named(r) for n, r in res.items() if "specular/" in n]
        alt = [named(r) for n, r in res.items() if "specular_alt/" in n]
        print(f"exponent {shin}: centre {centre:.3f}, tau {tau:.3f}; calibration cases over their floor {cal_over}/44; "
              f"clean power {sum(clean)}/60; default {sum(dflt)}/15; wider {sum(alt)}/15")


if __name__ == "__main__":
    main()
