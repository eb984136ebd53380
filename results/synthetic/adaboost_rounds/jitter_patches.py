"""Does the synthetic positives' patch-level gain survive the sliding window's misalignment?

The protocol's patch set crops every object centred at its labelled box (and background windows the same size).
A frame detector never sees that crop: it scans a grid of windows (AdaBoost: a 4 px stride, scales 0.8 apart),
so the window nearest an object is off by up to 2 px and by up to 0.8^±0.5 in size, and the detection kept is the
best-scoring window nearby. Every patch of the test (or validation) patch set is cut again at 27 offsets (x and y
shifted by -2, 0, +2 patch px, side scaled by 0.8^-0.5, 1, 0.8^0.5) and every stored mined AdaBoost detector
(data/runs/cells/detectors, as ``mined_patches.py``) is scored on them: patch AP of the centred crops (the
protocol's), of one random offset per patch (rng 0), and of the best of the 27 per patch (positives and negatives
alike: what a scan and its non-maximum suppression keep). A quarter of the negatives (rng 0) keeps a detector's
scoring to ≈ 1.5 min; SEEDS restricts the detectors to those training seeds. Trains nothing.

    python results/synthetic/adaboost_rounds/jitter_patches.py test [SEED ...] > results/synthetic/adaboost_rounds/jitter_test.jsonl
"""
import json
import sys
import time
from pathlib import Path

import numpy as np
import torch

from synthaug.data.seedset import crop_patch
from synthaug.data.video import read_video_with_labels
from synthaug.detectors.base import load_detector
from synthaug.evaluate.patches import _find_video, patch_eval_set, patch_metrics
from synthaug.evaluate.protocol import load_protocol
from stored import stored_detectors  # this folder's (the script's directory is on sys.path)

VIDEOS, LABELS = "../shared/data/halmstad/videos", "../shared/data/halmstad/labels"
SHIFTS = (-2.0, 0.0, 2.0)  # patch px
SIDES = (0.8 ** -0.5, 1.0, 0.8 ** 0.5)

torch.set_num_threads(1)
split = sys.argv[1] if len(sys.argv) > 1 else "test"
seeds = {int(a) for a in sys.argv[2:]}
proto = load_protocol("configs/protocol/halmstad_v2.json")
t0 = time.perf_counter()
ps = patch_eval_set(VIDEOS, LABELS, split, proto, split_file="configs/splits/halmstad.json", class_name="drone")
P = proto.patch.patch_size
rng = np.random.default_rng(0)
# every positive, a quarter of the negatives
keep = np.nonzero((ps.labels == 1) | (rng.random(len(ps.labels)) < 0.25))[0]
labels = ps.labels[keep]
offsets = [(dx, dy, s) for s in SIDES for dy in SHIFTS for dx in SHIFTS]
jit = np.zeros((len(keep), len(offsets), P, P), np.uint8)
for v, stem in enumerate(ps.stems):
    frames, _, _ = read_video_with_labels(_find_video(Path(VIDEOS), stem), f"{LABELS}/{stem}.json")
    for j in np.nonzero(ps.video[keep] == v)[0]:
        i = keep[j]
        cx, cy, side = (float(c) for c in ps.crop[i])
        for k, (dx, dy, s) in enumerate(offsets):
            jit[j, k] = crop_patch(frames[ps.frame[i]], crop=[cx + dx * side / P, cy + dy * side / P, side * s],
                                   patch_size=P)[0]
    del frames
centre = offsets.index((0.0, 0.0, 1.0))
assert np.array_equal(jit[:, centre], ps.patches[keep]), "the centred re-crop must be the protocol's patch"
print(json.dumps({"split": split, "patches": len(keep), "positives": int(labels.sum()), "offsets": len(offsets),
                  "build_s": round(time.perf_counter() - t0, 1)}), flush=True)
pick = rng.integers(0, len(offsets), len(keep))
for seed, cell, ckpt in stored_detectors(seeds):
    det = load_detector(ckpt)
    scores = np.zeros(jit.shape[:2])
    for a in range(0, len(jit), 512):
        x = torch.from_numpy(jit[a:a + 512].reshape(-1, 1, P, P)).float() / 255
        scores[a:a + 512] = det.score_patches(x).double().numpy().reshape(-1, len(offsets))
    row = {"seed": seed, "cell": cell, "detector": Path(ckpt).stem}
    for name, s in (("centred", scores[:, centre]), ("random", scores[np.arange(len(pick)), pick]),
                    ("best", scores.max(1))):
        m = patch_metrics(s, labels)
        row[f"{name}_ap"], row[f"{name}_auc"] = round(m.ap.estimate, 4), round(m.roc_auc.estimate, 4)
    print(json.dumps(row), flush=True)
