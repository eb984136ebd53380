"""Per test video, AP@0.5 of real only, the shape cell and the shape cell + rendered distractors, each training
seed's stored cells side by side (stop 101; nothing is retrained), and the videos' mean difference.

    PYTHONPATH=. python results/synthetic/adaboost_distractors/per_video.py DIST_FOLDER [SEED ...]

DIST_FOLDER holds seed<N>/ with the distractor cell's JSON; real only and the shape cell are read from
intel_cal_test/seed<N>/ (seeds 0, 1, stop 98) or, where absent there, from DIST_FOLDER/seed<N>/ itself or
frame_s101/seed<N>/ (seed 2, stop 101).
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.stats import PooledRanking

HERE = Path(__file__).resolve().parent
SMALL = ("V_DRONE_109", "V_DRONE_111", "V_DRONE_112", "V_DRONE_113", "V_DRONE_114")  # stop 97's cloud videos


def cells(folder: Path, seed: int) -> dict[str, ProtocolResult]:
    out = {}
    for where in (HERE / "intel_cal_test" / f"seed{seed}", folder / f"seed{seed}", HERE / "frame_s101" / f"seed{seed}"):
        for f in sorted(where.glob("*.json")) if where.is_dir() else []:
            tag = "dist" if "distractors" in f.name else "shape" if "synthetic" in f.name else "real"
            out.setdefault(tag, ProtocolResult.load(f))
    return out


def main() -> None:
    folder, seeds = Path(sys.argv[1]), [int(s) for s in sys.argv[2:]] or [0, 1]
    rows: dict[str, dict[str, list[float]]] = {}
    for s in seeds:
        c = cells(folder, s)
        missing = {"real", "shape", "dist"} - set(c)
        if missing:
            sys.exit(f"seed {s}: no {sorted(missing)} cell")
        for tag, r in c.items():
            for v in r.seeds[s].videos:
                rows.setdefault(v.stem, {}).setdefault(tag, []).append(PooledRanking([v.ranking(0.5)]).ap())
    print(f"seeds {seeds}; AP@0.5 per video, mean over seeds ({', '.join(SMALL)}: the cloud videos of stop 97 *)")
    print(f"{'video':14s} {'real':>6s} {'shape':>6s} {'dist':>6s} {'dist-real':>10s} {'dist-shape':>11s}")
    d_real, d_shape = [], []
    for stem in sorted(rows):
        m = {k: float(np.mean(v)) for k, v in rows[stem].items()}
        d_real.append(m["dist"] - m["real"])
        d_shape.append(m["dist"] - m["shape"])
        mark = " *" if stem in SMALL else ""
        print(f"{stem:14s} {m['real']:6.3f} {m['shape']:6.3f} {m['dist']:6.3f} {d_real[-1]:+10.3f} "
              f"{d_shape[-1]:+11.3f}{mark}")
    small = [k for k, stem in enumerate(sorted(rows)) if stem in SMALL]
    other = [k for k in range(len(rows)) if k not in small]
    for name, idx in (("cloud videos", small), ("other videos", other)):
        print(f"mean over the {name}: dist - real {np.mean([d_real[k] for k in idx]):+.3f}, "
              f"dist - shape {np.mean([d_shape[k] for k in idx]):+.3f}")


if __name__ == "__main__":
    main()
