"""Issue 20, stop 99: a column pattern's frames against their clean twins, as the diagnosis reads their edges.

Stop 96 found a 4 % column pattern still raising the frames' edge ratio after ``destripe`` (13000: 0.647-0.651 against
clean cases <= 0.642). A case with a hidden column pattern and the clean case of the same base seed and index share
their scenes, nuisances and noise (the pattern is the only difference), so each frame's ratio can be compared with
its clean twin's. Per case: the mean edge ratio over the 60 frames (``frame_summary``, the diagnosis's path) of the
clean case and of each pattern strength, and the per-frame excess over the clean twin against the frame's share of
clipped pixels (Spearman over the frames; the pattern's first frames had 40-65 % of the sky at 255).
Seed sets only (no fit), made once under ``--workdir`` as ``edge_radial.py`` makes them; 2-4 s a case.

    PYTHONPATH=. python results/diagnose/null/column_edges.py 13000 5 --out results/diagnose/null/clip_s99/column_edges_13000.json
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from scipy import stats

sys.path.insert(0, str(Path(__file__).resolve().parent))

from edge_radial import group_cases  # noqa: E402

from synthaug.diagnose import frame_pattern as fp  # noqa: E402


def frame_ratios(seeds, geo) -> tuple[np.ndarray, np.ndarray]:
    """Each frame's edge ratio as the diagnosis reads it, and its share of clipped pixels (either look)."""
    r, clip = [], []
    for i in range(len(seeds)):
        f, b = np.asarray(seeds.frame(i)), np.asarray(seeds.background_frame(i))
        x0, y0, side = float(geo["origin"][i, 0]), float(geo["origin"][i, 1]), seeds.patch_size * float(geo["frame_scale"][i])
        r.append(fp.frame_summary(f, background=b, exclude=(x0, y0, side))["edge_ratio"])
        clip.append(float(np.mean(~(fp._unclipped(fp._gray(f)) & fp._unclipped(fp._gray(b))))))
    return np.asarray(r), np.asarray(clip)


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("base", type=int)
    ap.add_argument("cases", type=int)
    ap.add_argument("--workdir", default="outputs/edge_radial")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    t0 = time.perf_counter()
    clean = {k: frame_ratios(s, g) for k, s, g in group_cases(f"clean:{a.base}:{a.cases}", a.workdir)}
    rows = []
    for strength in ("default", "alt"):
        for k, seeds, geo in group_cases(f"column_pattern:{strength}:{a.base}:{a.cases}", a.workdir):
            r, clip = frame_ratios(seeds, geo)
            excess = r - clean[k][0]
            ok = np.isfinite(excess)
            rho = stats.spearmanr(excess[ok], clip[ok]).statistic if ok.sum() > 2 else float("nan")
            row = {"strength": strength, "k": k, "clean": float(np.nanmean(clean[k][0])), "pattern": float(np.nanmean(r)),
                   "excess": float(np.nanmean(r) - np.nanmean(clean[k][0])), "clipped_share": float(clip.mean()),
                   "spearman_excess_vs_clipped": float(rho)}
            rows.append(row)
            print({kk: (round(v, 4) if isinstance(v, float) else v) for kk, v in row.items()}, flush=True)
    out = {"command": " ".join(sys.argv), "rows": rows, "seconds": round(time.perf_counter() - t0, 1)}
    if a.out:
        Path(a.out).write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
