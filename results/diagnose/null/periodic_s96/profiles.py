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

import numpy as np
import torch

from synthaug.diagnose.diagnosis_data import load_diagnosis_data
from synthaug.diagnose.residuals import _line_spectrum, region_masks
from synthaug.diagnose.screening import base_render

CUT = 0.25


def profile(case: str) -> dict:
    data = load_diagnosis_data(f"{case}/seeds", f"{case}/fit.json", "quadcopter")
    syn, _ = base_render(data)
    res = data.real - syn
    n, _, p, _ = res.shape
    m = region_masks(data.coverage)
    wobj = (m["interior"] | m["boundary"]).float()
    a, b = _line_spectrum(res, wobj, -2), _line_spectrum(res, wobj, -1)
    freqs = np.fft.rfftfreq(p)
    hi = np.nonzero(freqs >= 0.2)[0]
    fs = data.frame_scale.double().numpy()
    grid = np.round(np.arange(0.1, 0.5 + 1e-9, 0.0125), 4)
    out = {"grid": grid.tolist()}
    for label, x, y in (("rows", a, b), ("columns", b, a)):
        lr = np.log((x[:, hi] + 1e-12) / (y[:, hi] + 1e-12))
        out[label] = np.stack([np.interp(grid, freqs[hi] / fs[i], lr[i], left=np.nan, right=np.nan)
                               for i in range(n)]).tolist()
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
