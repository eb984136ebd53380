"""Issue 20, stop 99: why a 4 % column pattern still raises the frames' edge ratio after ``destripe`` (stop 96).

For each case (the power table's seeds, nuisances and hidden settings, made as ``edge_radial.py`` makes them: seed
sets only, no fit), every frame's edge ratio as the diagnosis reads it (``frame_pattern.edge_steps``: destripe, edges
chosen on the background look, steps read on the frame), and the same with the camera's **true** column gains divided
out of both looks first ("oracle"), and mixed: edges chosen on the oracle-cleaned background but the steps read on
the destriped frame ("read"), and the reverse ("chosen"). Also destripe's error: the log gains it divides out against
the true ones (sd over columns, and the sd of its column-to-column steps), per case.

    PYTHONPATH=. python results/diagnose/null/column_edges.py clean:13000:5 column_pattern:alt:13000:5 \
        --workdir outputs/edge_radial --out results/diagnose/null/column_edges.json
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from edge_radial import group_cases, groups_parser  # noqa: E402

from synthaug.diagnose import frame_pattern as fp  # noqa: E402
from synthaug.diagnose.reference_camera import column_gains  # noqa: E402


def ratio(steps) -> float:
    return fp._steps_ratio(steps)


def steps_on(f: np.ndarray, b: np.ndarray, outside: np.ndarray):
    """edge_steps on looks already freed of their pattern (its own destripe made the identity)."""
    keep = fp.destripe
    fp.destripe = lambda f, b, **k: (f, b)
    try:
        return fp.edge_steps(f, b, outside=outside)
    finally:
        fp.destripe = keep


def main() -> int:
    a = groups_parser().parse_args()
    t0 = time.perf_counter()
    out = {}
    for group in a.groups:
        rows = []
        parts = group.split(":")
        for k, seeds, geo in group_cases(group, a.workdir):
            base = int(parts[1] if parts[0] == "clean" else parts[2])
            sd = 0.0
            if parts[0] == "column_pattern":
                from benchmarks.bench_diagnose_null import hidden_settings

                sd = float(hidden_settings("column_pattern", parts[1])["column_pattern"]["column_gain_sd"])
            p = seeds.patch_size
            per, err = [], []
            for i in range(len(seeds)):
                f, bg = fp._gray(np.asarray(seeds.frame(i))), fp._gray(np.asarray(seeds.background_frame(i)))
                h, w = f.shape[:2]
                g = column_gains(w, sd, base + k)[None, :] if sd > 0 else np.ones((1, w))
                outside = np.ones((h, w), bool)
                x0, y0, side = float(geo["origin"][i, 0]), float(geo["origin"][i, 1]), p * float(geo["frame_scale"][i])
                outside[int(max(0, np.floor(y0 - 2))):int(np.ceil(y0 + side + 2)),
                        int(max(0, np.floor(x0 - 2))):int(np.ceil(x0 + side + 2))] = False
                fd, bd = fp.destripe(f, bg)
                fo, bo = f / g, bg / g
                # destripe's read log gains (what it divided out), against the truth, centred
                read = np.median(np.log(np.clip(bg, 1 / 255, None)) - np.log(np.clip(bd, 1 / 255, None)), axis=0)
                e = read - np.log(g[0])
                e -= e.mean()
                err.append((float(e.std()), float(np.diff(e).std())))
                s_std = fp.edge_steps(f, bg, outside=outside)
                s_or = steps_on(fo, bo, outside)
                # the same edges as the oracle's, read on the destriped frame; and destripe's edges read on the oracle
                s_read = steps_on(fd, bo, outside)
                s_chosen = steps_on(fo, bd, outside)
                per.append((ratio(s_std), ratio(s_or), ratio(s_read), ratio(s_chosen)))
            per, err = np.array(per), np.array(err)
            row = {"k": k, "sd": sd, "frames": int(np.isfinite(per[:, 0]).sum()),
                   "as_read": float(np.nanmean(per[:, 0])), "oracle": float(np.nanmean(per[:, 1])),
                   "destriped_frame_oracle_edges": float(np.nanmean(per[:, 2])),
                   "oracle_frame_destriped_edges": float(np.nanmean(per[:, 3])),
                   "destripe_err_sd": float(err[:, 0].mean()), "destripe_err_step_sd": float(err[:, 1].mean())}
            rows.append(row)
            print(group, {kk: (round(v, 4) if isinstance(v, float) else v) for kk, v in row.items()}, flush=True)
        out[group] = rows
    out["seconds"] = round(time.perf_counter() - t0, 1)
    if a.out:
        Path(a.out).write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
