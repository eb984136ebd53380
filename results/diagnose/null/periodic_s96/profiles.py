"""Stop 96: the per-frequency row/column log ratio of each case's base residual (what ``periodic_rows`` /
``periodic_columns`` choose their peak from), and, over the cases, how large the seeds' mean gets below and above
a frequency (among the frequencies enough seeds measure, as the measures require).

    PYTHONPATH=. python results/diagnose/null/periodic_s96/profiles.py OUT.json CASE_DIR...
    e.g. ... profiles.py /tmp/clean2000.json outputs/bench_diagnose_null_hand2000/case_0*

Measured (24 clean calibration cases, seed base 2000): the largest |mean| below 0.25 cycles per frame px 0.50
(median over cases and directions 0.25), from 0.25 up 0.30 (median 0.17); five interlacing (0.5, 2.5) cases of seed
base 11000 peak at 0.40-0.46 with 0.54-0.86.
"""
import json
import sys
import warnings
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent))

from recalibrate import residual_spectra  # noqa: E402  (the case's residual spectra, as recalibrate.py reads them)

from synthaug.diagnose.residuals import periodic_profile  # noqa: E402

CUT = 0.25


def profile(case: str) -> dict:
    _, _, rows, cols, fs = residual_spectra(case)
    out = {}
    for label, x, y in (("rows", rows, cols), ("columns", cols, rows)):
        grid, lr = periodic_profile(x, y, fs, min_frequency=0.1)
        out["grid"], out[label] = grid.tolist(), lr.tolist()
    return out


def main() -> int:
    torch.set_num_threads(1)
    warnings.simplefilter("ignore", RuntimeWarning)
    out = {case: profile(case) for case in sys.argv[2:]}
    below, above = [], []
    for case, v in out.items():
        g = np.array(v["grid"])
        for label in ("rows", "columns"):
            r = np.array(v[label], dtype=float)
            ok = np.isfinite(r).sum(0) >= max(5, r.shape[0] // 4)
            s = np.abs(np.nanmean(r, 0))
            if (ok & (g < CUT)).any():
                below.append(float(np.nanmax(s[ok & (g < CUT)])))
            above.append(float(np.nanmax(s[ok & (g >= CUT)])))
        print(case, "rows mean log ratio:", " ".join(f"{x:+.2f}" for x in np.nanmean(np.array(v["rows"]), 0)[::2]))
    print(f"largest |mean| below {CUT}: {max(below):.2f} (median {np.median(below):.2f}); from {CUT} up: "
          f"{max(above):.2f} (median {np.median(above):.2f})")
    with open(sys.argv[1], "w") as fh:
        json.dump(out, fh)
    return 0


if __name__ == "__main__":
    sys.exit(main())
