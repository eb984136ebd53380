"""Stop 92: AdaBoost at 100 seeds, real only (``../adaboost_critic/{val,test}_eN``) against the shape cell
(``../adaboost_wl_critic/{val,test}_sN``), both trained on one machine: each training seed's AP@0.5, the per-seed
differences, their spread across seeds, a t interval over the seeds (the seeds as the only source of variation; the
tables' bootstrap intervals resample the test videos as well) and how far a seed's real-only AP predicts its
shape-cell AP (what pairing by seed buys).
Reads stored results only (≈ 5 s).

usage (repository root): PYTHONPATH=. python results/synthetic/adaboost_where/per_seed.py [SEEDS...]  (default 0-9;
missing seeds are skipped)
"""
import sys
from pathlib import Path

import numpy as np
from scipy import stats

from synthaug.evaluate.results import ProtocolResult

H = Path("results/synthetic/adaboost_critic")
O = Path("results/synthetic/adaboost_wl_critic")
SHAPES = ("adaboost_100_seeds_20x_synthetic_hog_quadcopter_fitted_poses_at_the_seeds_offsets_share_0.25_shapes_varied_"
          "0.3_8_bit_the_25_least_synthetic_of_4x_drawn_of_each_seed_to_a_weak_learner_critic.json")


def per_seed(split: str, seeds: list[int]) -> tuple[list[int], np.ndarray, np.ndarray]:
    kept, real, shapes = [], [], []
    for s in seeds:
        e, c = H / f"{split}_e{s}" / "adaboost_100_seeds.json", O / f"{split}_s{s}" / SHAPES
        if not (e.exists() and c.exists()):
            continue
        kept.append(s)
        real.append(ProtocolResult.load(e).per_seed_ap()[s])
        shapes.append(ProtocolResult.load(c).per_seed_ap()[s])
    return kept, np.array(real), np.array(shapes)


def main(argv: list[str]) -> None:
    seeds = [int(a) for a in argv] or list(range(10))
    for split in ("val", "test"):
        kept, real, shapes = per_seed(split, seeds)
        if len(kept) < 3:
            print(f"{split}: {len(kept)} seeds with both cells; need 3")
            continue
        d = shapes - real
        t = stats.ttest_rel(shapes, real)
        lo, hi = t.confidence_interval(0.95)
        r = stats.pearsonr(real, shapes)
        print(f"{split}: seeds {' / '.join(map(str, kept))}")
        print(f"  real only   {' / '.join(f'{x:.3f}' for x in real)}  mean {real.mean():.3f}  "
              f"sd {real.std(ddof=1):.3f}")
        print(f"  shape cell  {' / '.join(f'{x:.3f}' for x in shapes)}  mean {shapes.mean():.3f}  "
              f"sd {shapes.std(ddof=1):.3f}")
        print(f"  difference  {' '.join(f'{x:+.3f}' for x in d)}  mean {d.mean():+.3f}  "
              f"t over seeds [{lo:+.3f}, {hi:+.3f}] (p {t.pvalue:.2f}), {int((d > 0).sum())}/{len(d)} seeds up")
        print(f"  the two cells' APs across seeds: Pearson r {r.statistic:+.2f} (p {r.pvalue:.2f}); pairing by seed "
              f"narrows the difference's sd from {np.hypot(real.std(ddof=1), shapes.std(ddof=1)):.3f} (unpaired) to "
              f"{d.std(ddof=1):.3f}")


if __name__ == "__main__":
    main(sys.argv[1:])
