"""Issue 15: the k-means minima of HOG's component initialisation on the all-frames drone positives.

Reads the positives ``record_rounds.py`` stored (5,804 labelled training frames, flipped copies added as
``HOGDetector.fit`` adds them), and prints, for the HOG fit's generator seeds 0-9, the cluster sizes and the
inertia of one k-means++ run (``restarts=1``, the training before ``hog_kmeans_restarts``) and of ten.

Usage::

    PYTHONPATH=. python results/learning_curve/mining_collapse/kmeans_minima.py --dir outputs/mining_collapse --seed 1
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import torch

from synthaug.detectors.base import to_float_patches
from synthaug.detectors.hog import DEFAULT_HOG
from synthaug.detectors.hog_dpm import _hog_chunked, kmeans, kmeans_inertia


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--dir", required=True)
    ap.add_argument("--seed", type=int, default=1, help="the training seed whose stored positives are read")
    ap.add_argument("--k", type=int, default=3)
    a = ap.parse_args()
    torch.set_num_threads(1)
    pos = to_float_patches(torch.load(Path(a.dir) / f"positives_seed{a.seed}.pt", weights_only=False), 40)
    f = _hog_chunked(torch.cat([pos, pos.flip(-1)]), DEFAULT_HOG)
    print(f"{f.shape[0]} positives (with flips), HOG length {f.shape[1]}")
    print("generator seed | one run: sizes, inertia | ten runs: sizes, inertia")
    for g in range(10):
        row = [str(g)]
        for restarts in (1, 10):
            lab = kmeans(f, a.k, generator=torch.Generator().manual_seed(g), restarts=restarts)
            row.append(f"{torch.bincount(lab, minlength=a.k).tolist()} {kmeans_inertia(f, lab):.1f}")
        print(" | ".join(row))
    return 0


if __name__ == "__main__":
    sys.exit(main())
