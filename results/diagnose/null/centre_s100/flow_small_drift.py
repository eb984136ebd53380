"""Issue 20, stop 100: the lens's motion reading (``frame_pattern.radial_flow``) on every frame, small shifts
included (``MIN_DRIFT_PX`` set to 0 for this measurement only): per frame ``k``, its standard error ``k_se`` and the
scene's shift ``drift``, on the cases of ``edge_radial.py``'s groups (seed sets only; the frames and crops exactly
as ``frame_summary`` reads them). Writes one JSON row per case with the per-frame lists and the video of each seed.

Usage::

    PYTHONPATH=. python results/diagnose/null/centre_s100/flow_small_drift.py --out OUT.json clean:2000:24 ...
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from edge_radial import groups_parser, run_groups, write_out  # noqa: E402  (stop 45's case maker)


def case_row(seeds, geo) -> dict:
    from synthaug.diagnose import frame_pattern as fp

    p = seeds.patch_size
    ks, ses, drifts = [], [], []
    for i in range(len(seeds)):
        f, bg = np.asarray(seeds.frame(i)), np.asarray(seeds.background_frame(i))
        h, w = f.shape[:2]
        x0, y0, side = float(geo["origin"][i, 0]), float(geo["origin"][i, 1]), p * float(geo["frame_scale"][i])
        outside = np.ones((h, w), bool)
        xa, xb = int(np.clip(np.floor(x0 - 2), 0, w)), int(np.clip(np.ceil(x0 + side + 2), 0, w))
        ya, yb = int(np.clip(np.floor(y0 - 2), 0, h)), int(np.clip(np.ceil(y0 + side + 2), 0, h))
        outside[ya:yb, xa:xb] = False
        r = fp.radial_flow(fp._gray(f), fp._gray(bg), outside=outside)
        ks.append(r["k"]), ses.append(r["k_se"]), drifts.append(r["drift"])
    return {"k": ks, "k_se": ses, "drift": drifts, "video": [r.get("video") for r in seeds.records]}


def main() -> int:
    from synthaug.diagnose import frame_pattern as fp

    fp.MIN_DRIFT_PX = 0.0
    a = groups_parser().parse_args()
    t0 = time.perf_counter()
    def show(group: str, row: dict) -> None:
        d, kk = np.array(row["drift"], float), np.array(row["k"], float)
        print(group, row["case"], f"max drift {np.nanmax(d):.2f}", f"k(drift<0.3) {np.nanmean(kk[d < 0.3]):+.3f}",
              f"k(drift>=0.3) {np.nanmean(kk[d >= 0.3]) if (d >= 0.3).any() else float('nan'):+.3f}", flush=True)

    out = run_groups(a.groups, a.workdir, case_row, key="case", show=show, out_path=a.out, t0=t0)
    return write_out(out, a.out, t0)


if __name__ == "__main__":
    sys.exit(main())
