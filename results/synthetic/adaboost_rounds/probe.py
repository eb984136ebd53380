"""Does AdaBoost use synthetic positives once it has more rounds? A patch-level probe (no mining, no frames).

Trains AdaBoost on one training seed's 100-seed drone seed set (its real positives, its negative pool) with and
without 20x synthetic positives from that seed's d_HOG fit (AdaBoost's defaults: 2000 candidates, the energy floor, every fitted effect, the seed's
own background, uniform poses, share 0.25 of the positive weight, the real-positive cascade), at several round
counts, and scores the protocol's patch sets of the validation and test videos (patch AP, ROC-AUC; 1 thread).

    python results/synthetic/adaboost_rounds/probe.py SEED ROUNDS [ROUNDS ...] > results/.../probe_seedS.jsonl
"""
import json
import sys
import time

import numpy as np
import torch

from synthaug.data.seedset import SeedSet
from synthaug.detectors.adaboost import gradient_level, train_adaboost
from synthaug.detectors.training_sets import negative_pool, real_positives, synthetic_positives
from synthaug.detectors.video_training import share_weights
from synthaug.evaluate.patches import patch_eval_set, patch_metrics, score_patch_set
from synthaug.evaluate.protocol import load_protocol

torch.set_num_threads(1)
seed = int(sys.argv[1])
rounds = [int(r) for r in sys.argv[2:]]
ss = SeedSet.load(f"data/runs/ingest_drone_seed{seed}/seedsets/drone_100")
fit = f"data/runs/fits/drone_100_seed{seed}_hog_quadcopter.json"
pos = real_positives(ss)
neg = negative_pool(ss, seed=seed)
floor = gradient_level(neg)  # the library's energy floor (TrainOptions.ada_energy_floor 1.0)
t0 = time.perf_counter()
syn = synthetic_positives(ss, "../shared/data/meshes/quadcopter.glb", fit, 20 * len(ss), seed=seed + 2)
t_syn = time.perf_counter() - t0
proto = load_protocol("configs/protocol/halmstad_v2.json")
sets = {split: patch_eval_set("../shared/data/halmstad/videos", "../shared/data/halmstad/labels", split, proto,
                              split_file="configs/splits/halmstad.json", class_name="drone")
        for split in ("val", "test")}
print(json.dumps({"seed": seed, "real": len(pos), "synthetic": len(syn), "negatives": len(neg),
                  "synthetic_s": round(t_syn, 1), **{f"{k}_patches": len(v) for k, v in sets.items()}}), flush=True)
for r in rounds:
    for cond in ("real", "synthetic"):
        p = pos if cond == "real" else torch.cat([pos, syn])
        w = None if cond == "real" else share_weights(len(pos), len(p), 0.25)
        t0 = time.perf_counter()
        det = train_adaboost(p, neg, n_rounds=r, candidates=2000, seed=seed, positive_weights=w, energy_floor=floor,
                             cascade_positives=None if cond == "real" else len(pos))
        row = {"seed": seed, "rounds": r, "condition": cond, "train_s": round(time.perf_counter() - t0, 1)}
        for split, ps in sets.items():
            vs = score_patch_set(det, ps)
            m = patch_metrics(np.concatenate([v.scores for v in vs]), np.concatenate([v.labels for v in vs]))
            row[f"{split}_ap"] = round(m.ap.estimate, 4)
            row[f"{split}_auc"] = round(m.roc_auc.estimate, 4)
        print(json.dumps(row), flush=True)
