"""The stored (mined) AdaBoost detectors of the frame protocol scored on the protocol's patch sets.

Reads every AdaBoost detector the runner stored under data/runs/cells/detectors (100 drone seeds: real only, and the
synthetic cells of results/synthetic/adaboost_wl_critic) and scores the patch sets of the validation and test videos
(patch AP, ROC-AUC), so that the patch-level effect of the synthetic positives after hard-negative mining can be set
beside the frame-level one; then each synthetic cell minus real only as the protocol pairs frame AP (the same seeds,
2,000 resamples of the videos; and with the seeds resampled too). Trains nothing.

    python results/synthetic/adaboost_rounds/mined_patches.py > results/synthetic/adaboost_rounds/mined_patches.jsonl
"""
import json
from pathlib import Path

import numpy as np
import torch

from synthaug.detectors.base import load_detector
from synthaug.evaluate.patches import patch_eval_set, patch_metrics, score_patch_set
from synthaug.evaluate.protocol import load_protocol
from synthaug.evaluate.stats import PooledRanking, paired_difference
from stored import stored_detectors  # this folder's (the script's directory is on sys.path)

torch.set_num_threads(1)
proto = load_protocol("configs/protocol/halmstad_v2.json")
sets = {split: patch_eval_set("../shared/data/halmstad/videos", "../shared/data/halmstad/labels", split, proto,
                              split_file="configs/splits/halmstad.json", class_name="drone")
        for split in ("val", "test")}
pools = {}  # (cell, split) -> seed -> the seed's detector's per-video rankings
for seed, cell, ckpt in stored_detectors():
    det = load_detector(ckpt)
    row = {"seed": seed, "cell": cell, "detector": Path(ckpt).stem}
    for split, ps in sets.items():
        vs = score_patch_set(det, ps)
        pools.setdefault((cell, split), {})[seed] = PooledRanking([v.ranking() for v in vs])
        m = patch_metrics(np.concatenate([v.scores for v in vs]), np.concatenate([v.labels for v in vs]))
        row[f"{split}_ap"] = round(m.ap.estimate, 4)
        row[f"{split}_auc"] = round(m.roc_auc.estimate, 4)
    print(json.dumps(row), flush=True)
for (cell, split), pool in sorted(pools.items()):
    if cell == "real":
        continue
    for resample_seeds in (False, True):
        d = paired_difference(pools[("real", split)], pool, stems=sets[split].stems, resample_seeds=resample_seeds)
        iv = d.difference
        print(json.dumps({"paired": cell, "split": split, "seeds": sorted(d.seeds), "resampled": d.resampled,
                          "delta_ap": round(iv.estimate, 4), "ci": [round(iv.low, 4), round(iv.high, 4)],
                          "videos_up": f"{d.wins.improved}/{d.wins.improved + d.wins.worse + d.wins.tied}"}),
              flush=True)
