"""Do the fitted blurs make AdaBoost's synthetic positives look like the sky's soft blobs? A cheap probe.

Hard background windows: seed 0's stored real-only detector (mined) over every 5th frame of the five test videos
whose background outranks drones (section 6: V_DRONE_109, 111-114), raw windows overlapping no drone (IoU < 0.3),
its best ``HARD`` of them cut at the window (the detector's own framing). Positives: the same videos' objects as the
patch protocol crops them. Then AdaBoost is trained as ``probe_variants.py`` does (seed 0, no mining, 300 rounds) with
real only, + 20x synthetic (the library's AdaBoost defaults), the same without the fitted boundary and motion blur,
and 8-bit + the seeds' fitted poses, and each is scored on positives against those hard windows (ROC-AUC, and the
share of hard windows above the positives' median score). ≈ 8 min.

    PYTHONPATH=. python results/synthetic/adaboost_rounds/puff_probe.py > results/synthetic/adaboost_rounds/puff_probe.txt
"""
import numpy as np
import torch

from synthaug.data.seedset import SeedSet
from synthaug.detectors.adaboost import gradient_level, train_adaboost
from synthaug.detectors.base import load_detector
from synthaug.detectors.training_sets import negative_pool, real_positives, synthetic_positives
from synthaug.detectors.video_training import share_weights
from synthaug.evaluate.patches import patch_eval_set, patch_metrics
from synthaug.evaluate.protocol import load_protocol
from synthaug.params import CaptureParams
from hard_windows import STEMS, hardest_windows  # this folder's (the script's directory is on sys.path)
from stored import stored_detectors

HARD, MESH, SEED = 400, "../shared/data/meshes/quadcopter.glb", 0
torch.set_num_threads(1)
real_det = load_detector({cell: ckpt for _, cell, ckpt in stored_detectors((SEED,))}["real"])
neg_hard, n_windows = hardest_windows(real_det, HARD)
proto = load_protocol("configs/protocol/halmstad_v2.json")
ps = patch_eval_set("../shared/data/halmstad/videos", "../shared/data/halmstad/labels", "test", proto,
                    videos=list(STEMS))
pos_test = torch.from_numpy(ps.patches[ps.labels == 1]).float()[:, None] / 255
print(f"{n_windows} background windows, the best {len(neg_hard)} kept; {len(pos_test)} objects", flush=True)

ss = SeedSet.load(f"data/runs/ingest_drone_seed{SEED}/seedsets/drone_100")
fit = f"data/runs/fits/drone_100_seed{SEED}_hog_quadcopter.json"
effects = CaptureParams.load_with_extra(fit)[0].effects
pos, neg = real_positives(ss), negative_pool(ss, seed=SEED)
floor = gradient_level(neg)
variants = {"real only": None, "+ synthetic (AdaBoost's defaults)": {},
            "+ synthetic without boundary and motion blur":
                {"effects": [e for e in effects if e not in ("boundary_blur", "motion_blur")]},
            "+ synthetic, 8-bit, fitted poses at the seeds' offsets":
                {"quantize": True, "pose_sampling": "fitted_at_seed"}}
print(f"fitted effects: {list(effects)}")
for name, kw in variants.items():
    added = pos[:0] if kw is None else synthetic_positives(ss, MESH, fit, 20 * len(ss), seed=SEED + 2, **kw)
    p = torch.cat([pos, added])
    det = train_adaboost(p, neg, n_rounds=300, candidates=2000, seed=SEED, energy_floor=floor,
                         positive_weights=share_weights(len(pos), len(p), 0.25),
                         cascade_positives=len(pos) if len(added) else None)
    sp, sn = det.score_patches(pos_test).double().numpy(), det.score_patches(neg_hard).double().numpy()
    auc = patch_metrics(np.r_[sp, sn], np.r_[np.ones(len(sp)), np.zeros(len(sn))].astype(int)).roc_auc.estimate
    print(f"{name}: ROC-AUC objects vs hard windows {auc:.3f}; hard windows above the objects' median score "
          f"{float((sn > np.median(sp)).mean()):.3f}", flush=True)
