"""Where do two machines part? SHA-256 prefixes of each stage of a real-only AdaBoost at patch level, for one seed.

Stages: the 100-seed set's patches, boxes and negatives (ingest: video decoding, selection, crops); the negative
pool (the seed frames' object-free crops); the energy floor; the 300-round detector trained as ``probe.py``'s
``real`` (its state dict); its scores on the test patch set. Run it on two machines and diff the outputs: the first
line that differs names the stage. Reads ``data/runs/ingest_drone_seed{SEED}`` (made by ``synthaug ingest`` or the
runner); ≈ 2 min.

    PYTHONPATH=. python results/synthetic/adaboost_distractors/fingerprints.py SEED > results/synthetic/adaboost_distractors/fingerprints_<machine>_seed<SEED>.txt
"""
import hashlib
import sys

import numpy as np
import torch

from synthaug.data.seedset import SeedSet
from synthaug.detectors.adaboost import gradient_level, train_adaboost
from synthaug.detectors.training_sets import negative_pool, real_positives
from synthaug.detectors.video_training import share_weights
from synthaug.evaluate.patches import patch_eval_set, score_patch_set
from synthaug.evaluate.protocol import load_protocol


def h(x) -> str:
    """SHA-256 prefix of an array's or tensor's bytes (contiguous, its own dtype)."""
    a = x.detach().cpu().numpy() if isinstance(x, torch.Tensor) else np.asarray(x)
    return hashlib.sha256(np.ascontiguousarray(a).tobytes()).hexdigest()[:16]


torch.set_num_threads(1)
seed = int(sys.argv[1])
print(f"cpu capability {torch.backends.cpu.get_cpu_capability()}, torch {torch.__version__}, numpy {np.__version__}")
ss = SeedSet.load(f"data/runs/ingest_drone_seed{seed}/seedsets/drone_100")
print(f"seed set patches {h(ss.patches)} boxes {h(np.asarray(ss.boxes, np.float64))} "
      f"negatives {h(np.asarray(ss.negatives))}")
pos, neg = real_positives(ss), negative_pool(ss, seed=seed)
print(f"positives {h(pos)} negative pool {h(neg)} ({len(neg)})")
floor = gradient_level(neg)
print(f"energy floor {float(floor)!r}")
det = train_adaboost(pos, neg, n_rounds=300, candidates=2000, seed=seed, energy_floor=floor,
                     positive_weights=share_weights(len(pos), len(pos), 0.25))


def leaves(d, prefix=""):
    """(name, value) of a nested state dict's leaves."""
    for k, v in d.items():
        yield from leaves(v, f"{prefix}{k}.") if isinstance(v, dict) else [(prefix + k, v)]


for k, v in leaves(det.state_dict()):
    print(f"detector {k} {h(v) if isinstance(v, (torch.Tensor, np.ndarray)) else repr(v)}")
ps = patch_eval_set("../shared/data/halmstad/videos", "../shared/data/halmstad/labels", "test",
                    load_protocol("configs/protocol/halmstad_v2.json"), split_file="configs/splits/halmstad.json",
                    class_name="drone")
print(f"test patch set {h(ps.patches)}")
print(f"test scores {h(np.concatenate([v.scores for v in score_patch_set(det, ps)]))}")
