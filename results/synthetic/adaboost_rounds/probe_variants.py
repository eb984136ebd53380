"""AdaBoost's added positives screened at patch level (no mining, no frames): which synthetic variant, if any,
raises the patch AP of the validation videos over real only?

One training seed's 100-seed drone seed set, its negative pool, its d_HOG fit; AdaBoost as the library trains it
(2000 candidates, the energy floor, the real-positive cascade when positives are added) at ROUNDS rounds; the added
positives hold ``share`` of the positive weight (AdaBoost's default 0.25; "count": every positive the same). Patch
AP and ROC-AUC on the protocol's patch sets of the validation and test videos (1 thread).

    python results/synthetic/adaboost_rounds/probe_variants.py SEED ROUNDS VARIANT [VARIANT ...]
"""
import json
import sys
import time

import numpy as np
import torch

from synthaug.data.copypaste import copy_paste_positives
from synthaug.data.seedset import SeedSet
from synthaug.detectors.adaboost import gradient_level, train_adaboost
from synthaug.detectors.training_sets import negative_pool, perturbed_positives, real_positives, synthetic_positives
from synthaug.detectors.video_training import share_weights
from synthaug.evaluate.patches import patch_eval_set, patch_metrics, score_patch_set
from synthaug.evaluate.protocol import load_protocol

MESH = "../shared/data/meshes/quadcopter.glb"
# name -> (kind, ratio per seed, share, keyword arguments of the kind's generator)
VARIANTS = {
    "real": (None, 0, None, {}),
    "syn": ("synthetic", 20, 0.25, {}),
    "syn_count": ("synthetic", 20, "count", {}),
    "syn_share10": ("synthetic", 20, 0.10, {}),
    "syn_share50": ("synthetic", 20, 0.50, {}),
    "syn_5x": ("synthetic", 5, 0.25, {}),
    "syn_q": ("synthetic", 20, 0.25, {"quantize": True}),
    "syn_q_fit": ("synthetic", 20, 0.25, {"quantize": True, "pose_sampling": "fitted_at_seed"}),
    "syn_q_fit_shape": ("synthetic", 20, 0.25, {"quantize": True, "pose_sampling": "fitted_at_seed",
                                                "shape_variation": 0.3}),
    "syn_no_effects": ("synthetic", 20, 0.25, {"effects": []}),
    "syn_other": ("synthetic", 20, 0.25, {"background_sampling": "other"}),
    "syn_critic_wl": ("synthetic", 20, 0.25, {"realism_keep": 0.25, "realism_features": "weak_learners"}),
    "syn_critic_hog": ("synthetic", 20, 0.25, {"realism_keep": 0.25}),
    "copy_paste": ("copy_paste", 20, 0.25, {}),
    "perturbed": ("perturbed", 20, 0.25, {}),
}

torch.set_num_threads(1)
seed, rounds, names = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3:]
unknown = [n for n in names if n not in VARIANTS]
if unknown:
    sys.exit(f"unknown variants {unknown}; known: {sorted(VARIANTS)}")
ss = SeedSet.load(f"data/runs/ingest_drone_seed{seed}/seedsets/drone_100")
fit = f"data/runs/fits/drone_100_seed{seed}_hog_quadcopter.json"
pos = real_positives(ss)
neg = negative_pool(ss, seed=seed)
floor = gradient_level(neg)  # the library's energy floor (TrainOptions.ada_energy_floor 1.0)
proto = load_protocol("configs/protocol/halmstad_v2.json")
sets = {split: patch_eval_set("../shared/data/halmstad/videos", "../shared/data/halmstad/labels", split, proto,
                              split_file="configs/splits/halmstad.json", class_name="drone")
        for split in ("val", "test")}
for name in names:
    kind, ratio, share, kw = VARIANTS[name]
    t0 = time.perf_counter()
    n = ratio * len(ss)
    if kind == "synthetic":
        added = synthetic_positives(ss, MESH, fit, n, seed=seed + 2, **kw)
    elif kind == "copy_paste":
        added = copy_paste_positives(ss, fit, n, seed=seed + 4, mesh=MESH)
    elif kind == "perturbed":
        added = perturbed_positives(ss, ratio, seed=seed)[len(pos):]  # the real patches come first
    else:
        added = pos[:0]
    t_add = time.perf_counter() - t0
    p = torch.cat([pos, added])
    w = share_weights(len(pos), len(p), None if share == "count" else share)
    t0 = time.perf_counter()
    det = train_adaboost(p, neg, n_rounds=rounds, candidates=2000, seed=seed, positive_weights=w, energy_floor=floor,
                         cascade_positives=len(pos) if len(added) else None)
    row = {"seed": seed, "rounds": rounds, "variant": name, "added": len(added), "add_s": round(t_add, 1),
           "train_s": round(time.perf_counter() - t0, 1)}
    for split, ps in sets.items():
        vs = score_patch_set(det, ps)
        m = patch_metrics(np.concatenate([v.scores for v in vs]), np.concatenate([v.labels for v in vs]))
        row[f"{split}_ap"] = round(m.ap.estimate, 4)
        row[f"{split}_auc"] = round(m.roc_auc.estimate, 4)
    print(json.dumps(row), flush=True)
