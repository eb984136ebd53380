"""Per test video, AP@0.5 of real only, + 20x perturbed, + 20x copy-paste and the shape cell + 5x soft distractors,
mean over training seeds 0-2 (stop 103; stored cells, nothing retrained).

    PYTHONPATH=. python results/synthetic/adaboost_distractors/frame_s103/per_video_baselines.py
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.stats import PooledRanking

D = Path(__file__).resolve().parents[1]
PT = "adaboost_100_seeds_20x_perturbed_share_0.25.json"
CP = "adaboost_100_seeds_20x_copy_paste_hog_quadcopter_silhouettes_share_0.25.json"


def main() -> None:
    s5 = sorted((D / "frame_s102/soft5/seed0").glob("*.json"))[0].name
    real = [D / "intel_cal_test/seed0", D / "intel_cal_test/seed1", D / "frame_s101/seed2"]
    files = {"real": [f / "adaboost_100_seeds.json" for f in real],
             "pert": [D / "frame_s102/perturbed/seed0" / PT, D / "frame_s102/perturbed/seed1" / PT,
                      D / "frame_s103/baselines/seed2" / PT],
             "copy": [D / f"frame_s103/baselines/seed{s}" / CP for s in range(3)],
             "soft": [D / f"frame_s102/soft5/seed{s}" / s5 for s in range(3)]}
    rows: dict[str, dict[str, list[float]]] = {}
    for tag, fs in files.items():
        for s, f in enumerate(fs):
            for v in ProtocolResult.load(f).seeds[s].videos:
                rows.setdefault(v.stem, {}).setdefault(tag, []).append(PooledRanking([v.ranking(0.5)]).ap())
    print("AP@0.5 per test video, mean of training seeds 0-2")
    print(f"{'video':12s} {'real':>6s} {'pert':>6s} {'copy':>6s} {'soft':>6s} | pert-real copy-real soft-real soft-copy")
    for stem in sorted(rows):
        m = {k: float(np.mean(v)) for k, v in rows[stem].items()}
        print(f"{stem:12s} {m['real']:6.3f} {m['pert']:6.3f} {m['copy']:6.3f} {m['soft']:6.3f} | "
              f"{m['pert'] - m['real']:+9.3f} {m['copy'] - m['real']:+9.3f} {m['soft'] - m['real']:+9.3f} "
              f"{m['soft'] - m['copy']:+9.3f}")


if __name__ == "__main__":
    main()
