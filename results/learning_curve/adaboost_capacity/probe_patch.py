"""AdaBoost capacity probe on the validation videos' patch protocol (a cheap proxy before frame-level runs).

Trains AdaBoost on the 100-seed drone seed set's real positives + its negative pool (no mining) at several
(rounds, candidates) and scores the protocol's patch set of the *validation* split (AP, ROC-AUC). Usage:

    python results/learning_curve/adaboost_capacity/probe_patch.py data/halmstad/seedsets/drone_100 \
        100:2000 300:2000 100:8000 300:8000
"""
import json
import sys
import time

import numpy as np
import torch

from synthaug.data.seedset import SeedSet
from synthaug.detectors.adaboost import train_adaboost
from synthaug.detectors.training_sets import negative_pool, real_positives
from synthaug.evaluate.patches import patch_eval_set, patch_metrics, score_patch_set
from synthaug.evaluate.protocol import load_protocol

torch.set_num_threads(1)
ss = SeedSet.load(sys.argv[1])
pos = real_positives(ss)
pos = torch.cat([pos, pos.flip(-1)])
neg = negative_pool(ss, seed=0)
proto = load_protocol("configs/protocol/halmstad_v1.json")
t0 = time.perf_counter()
ps = patch_eval_set("../shared/data/halmstad/videos", "../shared/data/halmstad/labels", "val", proto,
                    split_file="configs/splits/halmstad.json", class_name="drone")
print(f"val patch set in {time.perf_counter() - t0:.0f} s; positives {len(pos)}, negatives {len(neg)}", flush=True)
rows = []
for spec in sys.argv[2:]:
    r, c = (int(v) for v in spec.split(":"))
    t0 = time.perf_counter()
    det = train_adaboost(pos, neg, n_rounds=r, candidates=c, seed=0)
    t_train = time.perf_counter() - t0
    vs = score_patch_set(det, ps)
    scores = np.concatenate([v.scores for v in vs])
    labels = np.concatenate([v.labels for v in vs])
    m = patch_metrics(scores, labels)
    row = {"rounds": r, "candidates": c, "stumps": len(det.learners.weights), "train_s": round(t_train, 1),
           "patch_ap": round(m.ap.estimate, 4), "roc_auc": round(m.roc_auc.estimate, 4)}
    rows.append(row)
    print(json.dumps(row), flush=True)
