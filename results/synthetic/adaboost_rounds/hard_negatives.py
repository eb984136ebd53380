"""Which false positives stand above AdaBoost's drones on the test frames? Stored calibrated cells only.

For each training seed, the real-only and the shape cell of ``run_calibration.sh`` (test split): the pooled ranking
of every test video's kept detections (matched at IoU ``IOU``), the score at which recall first reaches 0.5, and the false
positives ranked above it — in all and per test video (summed over seeds), with each video's objects found above
it. IOU (default 0.5) is the matching's: at 0.3 a detection on a drone with a loose box is no false positive, so the
two runs tell boxes from background. Reads the runner's stored results (≈ 10 s).

    PYTHONPATH=. python results/synthetic/adaboost_rounds/hard_negatives.py [IOU]
"""
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

from synthaug.evaluate.results import ProtocolResult

O = Path("results/synthetic/adaboost_rounds")
CELLS = {"real only": "adaboost_100_seeds.json",
         "shape cell": "adaboost_100_seeds_20x_synthetic_hog_quadcopter_fitted_poses_at_the_seeds_offsets_share_0.25_"
                       "shapes_varied_0.3_8_bit_the_25_least_synthetic_of_4x_drawn_of_each_seed_to_a_weak_learner_"
                       "critic.json"}
IOU = float(sys.argv[1]) if len(sys.argv) > 1 else 0.5
per_video = {c: defaultdict(lambda: [0, 0]) for c in CELLS}  # cell -> stem -> [FPs above, TPs above]
totals = {c: [] for c in CELLS}
stems = None
for folder in sorted(O.glob("cal_test_*/")):
    for cell, name in CELLS.items():
        r = ProtocolResult.load(folder / name)
        stems = r.stems
        for seed, pool in r.pools(IOU).items():
            s, t, n = pool.pooled()
            reach = np.nonzero(np.cumsum(t) >= 0.5 * n)[0]
            k = int(reach[0]) + 1 if reach.size else len(s)  # the detections down to recall 0.5
            fp = ~t[:k]
            totals[cell].append((seed, int(fp.sum()), k))
            for v in range(pool.n_videos):
                here = pool.video[:k] == v
                per_video[cell][r.stems[v]][0] += int((here & ~pool.is_positive[:k]).sum())
                per_video[cell][r.stems[v]][1] += int((here & pool.is_positive[:k]).sum())
for cell, rows in totals.items():
    rows.sort()
    print(f"IoU {IOU:g}, {cell}: false positives above recall 0.5 per seed "
          + ", ".join(f"{s}: {f}/{k}" for s, f, k in rows)
          + f"; mean {np.mean([f for _, f, _ in rows]):.1f}")
print("\n| test video | real only: FPs / TPs above recall 0.5 (all seeds) | shape cell |")
print("|---|---|---|")
for stem in stems:
    a, b = per_video["real only"][stem], per_video["shape cell"][stem]
    print(f"| {stem} | {a[0]} / {a[1]} | {b[0]} / {b[1]} |")
