"""Issue 15: retrain a recorded mining round's HOG detector under variations and count its validation false positives.

Reads what ``record_rounds.py`` stored (positives, each round's negatives, the training inputs, the validation
frames) and, for each variant, trains the round's detector the way ``train_with_mining`` does (``_fit_once``) and
scores it with the stopping rule's ``validation_false_positives``. Prints one JSON line per variant.

Usage::

    PYTHONPATH=. OMP_NUM_THREADS=1 python results/learning_curve/mining_collapse/retrain.py --dir outputs/mining_collapse \
        --seed 1 --round 1 --variant base --variant gen=0 --variant hog_mining_rounds=0
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path

import torch

from synthaug.detectors import training
from synthaug.detectors.mining import validation_false_positives


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--dir", required=True)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--round", type=int, default=1)
    ap.add_argument("--variant", action="append", default=[],
                    help="base | gen=N (the HOG fit's generator seed) | OPTION=VALUE (a TrainOptions field) | "
                         "pos_every=K (every K-th positive)")
    a = ap.parse_args()
    torch.set_num_threads(1)
    d = Path(a.dir)
    inp = torch.load(d / f"inputs_seed{a.seed}.pt", weights_only=False)
    pos = torch.load(d / f"positives_seed{a.seed}.pt", weights_only=False)
    neg = torch.load(d / f"negatives_seed{a.seed}_round{a.round}.pt", weights_only=False)
    val = torch.load(d / "validation_frames.pt", weights_only=False)
    base_opt = inp["options"].for_family("hog")
    for v in a.variant or ["base"]:
        opt, seed, p, pw = base_opt, a.seed, pos, inp["positive_weights"]
        if v != "base":
            name, value = v.split("=", 1)
            if name == "gen":
                seed = int(value)
            elif name == "pos_every":
                p = pos[:: int(value)]
                pw = None if pw is None else pw[:: int(value)]
            else:
                field = type(getattr(base_opt, name))
                opt = dataclasses.replace(base_opt, **{name: field(value)})
        t = time.perf_counter()
        det = training._fit_once("hog", p, neg, seed, box_in_window=inp["box_in_window"],
                                 mining_frames=inp["mining_frames"], mining_boxes=inp["mining_boxes"], options=opt,
                                 positive_weights=pw)
        t_train = time.perf_counter() - t
        det.box_regressor = inp["box_regressor"]
        r = validation_false_positives(det, val, scales=opt.pyramid(), top_k=opt.val_top_k, iou=opt.val_iou,
                                       target_recall=opt.val_target_recall)
        print(json.dumps({"variant": v, "seed": a.seed, "round": a.round, "positives": int(p.shape[0]),
                          "negatives": int(neg.shape[0]), "fp": r["fp"], "ap": r.get("ap"),
                          "train_s": round(t_train, 1), "val_s": round(time.perf_counter() - t - t_train, 1),
                          "bias": [round(float(b), 3) for b in det.bias]}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
