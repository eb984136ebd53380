"""Issue 15: HOG's all-frames mining round that collapses on validation (seed 1: AP 0.539 -> 0.023), recorded.

Runs the learning-curve runner's all-frames HOG cell (protocol halmstad_v2, ridge box map, the drone_v2 run.sh
settings) for the given training seeds, and stores every mining round's trained detector, positives and negatives
(``<out>/rounds_seed<seed>.pt``) so that the collapsed round can be taken apart (``analyse.py``).

Usage (repository root)::

    PYTHONPATH=. PYOPENGL_PLATFORM=egl OMP_NUM_THREADS=1 python results/learning_curve/mining_collapse/record_rounds.py \
        --out outputs/mining_collapse --training-seeds 1
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import torch

import synthaug.detectors.training as training
import synthaug.detectors.video_training as video_training


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    ap.add_argument("--training-seeds", type=int, nargs="+", default=[1])
    ap.add_argument("--seed-counts", nargs="*", default=[], help="seed counts (none: all frames only)")
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    rounds: dict[int, list] = {}
    fit_once = training._fit_once

    def recording(kind, positives, negatives, seed, **kw):  # noqa: ANN001, ANN202
        det = fit_once(kind, positives, negatives, seed, **kw)
        r = rounds.setdefault(seed, [])
        if not r:  # the positives are the same every round
            torch.save(positives, out / f"positives_seed{seed}.pt")
        torch.save(negatives, out / f"negatives_seed{seed}_round{len(r)}.pt")
        r.append(det.state_dict())
        torch.save(r, out / f"rounds_seed{seed}.pt")
        return det

    training._fit_once = recording
    train_with_mining = training.train_with_mining
    decoded = training._decoded_validation

    def keep_validation(val_frames, say):  # noqa: ANN001, ANN202
        val = decoded(val_frames, say)
        torch.save(val, out / "validation_frames.pt")
        return val

    def keep_inputs(kind, positives, negatives, seed=0, **kw):  # noqa: ANN001, ANN202
        torch.save({"kind": kind, "seed": seed, "options": kw.get("options"), "box_in_window": kw.get("box_in_window"),
                    "mining_frames": list(kw.get("mining_frames") or ()), "mining_boxes": kw.get("mining_boxes"),
                    "box_regressor": kw.get("box_regressor"), "positive_weights": kw.get("positive_weights")},
                   out / f"inputs_seed{seed}.pt")
        return train_with_mining(kind, positives, negatives, seed, **kw)

    training._decoded_validation = keep_validation
    video_training.train_with_mining = keep_inputs
    from synthaug.evaluate.runner import main as runner

    return runner(["learning-curve", "--protocol", "configs/protocol/halmstad_v2.json", "--class", "drone",
                   "--detectors", "hog", "--seed-counts", *a.seed_counts, "--all-frames", "--no-scale-check",
                   "--box-model", "ridge", "--no-patches", "--threads", "1",
                   "--training-seeds", *map(str, a.training_seeds), "--out", str(out / "cells")])


if __name__ == "__main__":
    sys.exit(main())
