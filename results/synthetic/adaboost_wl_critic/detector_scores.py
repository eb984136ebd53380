"""Stop 87: how the real-only AdaBoost detector scores the synthetic positives under each option (median score and
the share above its decision threshold 0), 2,000 drawn as its training draws them (seed + 2), on seed sets 0-2 of
the 100-seed drone runs with their d_HOG fits and their stored real-only detectors (stop 86's cells; seed 2 stop 88's,
added then: seeds 0-1 printed the same to the digit); then the
median extent of the object (|patch - background| > 0.03) in the real seed patches and in every draw (seed 0).

usage (repository root): python results/synthetic/adaboost_wl_critic/detector_scores.py   (~12 min for three seeds)
"""

from __future__ import annotations

import numpy as np
import torch

from synthaug.data.seedset import SeedSet
from synthaug.detectors.base import load_detector
from synthaug.detectors.training_sets import synthetic_positives

DETECTORS = {0: "data/runs/cells/detectors/10d17509b28cd202dc2669c2.pt",
             1: "data/runs/cells/detectors/15d751e3fa4c2a8b974f0b3b.pt",
             2: "data/runs/cells/detectors/47b6e311d8f783aedf78deb7.pt"}  # stop 88's real-only cell (run2.sh real r2 2)
MESH = "../shared/data/meshes/quadcopter.glb"
WL = dict(realism_keep=0.25, realism_features="weak_learners")
OPTIONS = {
    "every draw (uniform poses, float renders)": {},
    "poses around each seed's fitted rotation": dict(pose_sampling="fitted"),
    "fitted rotation at the seed's fitted offset": dict(pose_sampling="fitted_at_seed"),
    "HOG critic keeps 1/4": dict(realism_keep=0.25),
    "weak-learner critic keeps 1/4": WL,
    "framed as the seeds": dict(object_box="seed"),
    "8-bit": dict(quantize=True),
    "8-bit + HOG critic keeps 1/4": dict(quantize=True, realism_keep=0.25),
    "8-bit + weak-learner critic keeps 1/4": dict(quantize=True, **WL),
    "8-bit + fitted rotation at the seed's offset": dict(quantize=True, pose_sampling="fitted_at_seed"),
    "8-bit + fitted at the seed's offset + weak-learner critic": dict(quantize=True, pose_sampling="fitted_at_seed",
                                                                      **WL),
}


def extent(patches: np.ndarray, backgrounds: np.ndarray) -> tuple[float, float]:
    """Median height and width (px) of the pixels that differ from the background by more than 0.03."""
    m = np.abs(patches - backgrounds) > 0.03
    hw = [(np.ptp(np.nonzero(k)[0]) + 1, np.ptp(np.nonzero(k)[1]) + 1) if k.any() else (0, 0) for k in m]
    return tuple(float(v) for v in np.median(np.array(hw), 0))


def main() -> None:
    for seed, ckpt in DETECTORS.items():
        ss = SeedSet.load(f"data/runs/ingest_drone_seed{seed}/seedsets/drone_100")
        fit = f"data/runs/fits/drone_100_seed{seed}_hog_quadcopter.json"
        det = load_detector(ckpt)
        real = torch.from_numpy(np.asarray(ss.patches))[:, None].float() / 255
        accepted = (det.score_patches(real) > 0).float().mean().item()
        print(seed, f"{'the real seed patches':58s} share > 0 {accepted:.3f}")
        for name, kw in OPTIONS.items():
            syn, idx = synthetic_positives(ss, MESH, fit, 2000, seed=seed + 2, return_seed_index=True, **kw)
            s = det.score_patches(syn)
            print(seed, f"{name:58s} median score {s.median().item():+.2f}  "
                  f"share > 0 {(s > 0).float().mean().item():.3f}", flush=True)
            if seed == 0 and not kw:
                bg = np.asarray(ss.backgrounds, np.float64) / 255
                print("   object extent (h, w) px: real", extent(real.numpy()[:, 0].astype(np.float64), bg),
                      "every draw", extent(syn.numpy()[:, 0].astype(np.float64), bg[idx]))


if __name__ == "__main__":
    main()
