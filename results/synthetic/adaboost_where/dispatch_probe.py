"""Stop 91: which library's instruction-set dispatch changes what a stored AdaBoost detector reports.

Scores every 60th labelled frame of every third drone validation video (35 frames) with one stored detector and
saves, per frame, the decoded frame, the detector's score map and its detections (box regressor applied) to an npz.
Run it once as is and once per environment cap, then compare the files (``--compare``): which arrays differ names the
part of the chain that the capped library computes.

    PYTHONPATH=. python results/synthetic/adaboost_where/dispatch_probe.py DETECTOR.pt OUT.npz
    ONEDNN_MAX_CPU_ISA=AVX2 PYTHONPATH=. python results/synthetic/adaboost_where/dispatch_probe.py DET.pt capped.npz
    PYTHONPATH=. python results/synthetic/adaboost_where/dispatch_probe.py --compare OUT.npz capped.npz
"""
import argparse
import json

import numpy as np
import torch

from synthaug.detectors.base import load_detector
from synthaug.detectors.frames import VideoFrames
from synthaug.detectors.sliding import detect_multiscale


def probe(detector_path: str, out: str) -> None:
    torch.set_num_threads(1)
    det = load_detector(detector_path)
    split = json.load(open("configs/splits/halmstad.json"))
    videos = [s for s in split["val"] if s.startswith("V_DRONE")][::3]
    frames = VideoFrames("../shared/data/halmstad/videos", "../shared/data/halmstad/labels", positive=videos, stride=60)
    arrays = {}
    for k, f in enumerate(frames):
        img = torch.as_tensor(np.asarray(f.image), dtype=torch.float32) / 255.0
        arrays[f"frame{k}"] = np.asarray(f.image)
        arrays[f"map{k}"] = det.score_map(img[None, None]).numpy()
        arrays[f"det{k}"] = detect_multiscale(det, img, max_detections=50).numpy()
    np.savez(out, **arrays)
    print(f"{len(arrays) // 3} frames -> {out}")


def compare(a_path: str, b_path: str) -> None:
    a, b = np.load(a_path), np.load(b_path)
    for kind in ("frame", "map", "det"):
        keys = [k for k in a.files if k.rstrip("0123456789") == kind]
        differ = [k for k in keys if a[k].shape != b[k].shape or not np.array_equal(a[k], b[k])]
        worst = max((float(np.abs(a[k] - b[k]).max()) for k in differ if a[k].shape == b[k].shape), default=0.0)
        print(f"{kind}: {len(differ)} of {len(keys)} frames differ (largest difference {worst:.3g})")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("paths", nargs=2)
    ap.add_argument("--compare", action="store_true", help="compare two files written before")
    a = ap.parse_args()
    (compare if a.compare else probe)(*a.paths)
