"""What AdaBoost's high-scoring background windows look like in the small-drone test videos (a picture).

Seed 0's stored detectors (real only and the shape cell; raw windows, no box map) run over every 5th frame of the
given test videos at the library's pyramid; the detections that overlap no labelled drone (IoU < 0.3) are false
positives. Writes one PNG: per detector a row of its 16 best-scoring false positives (each window with a margin of half
its side), and a row of the videos' drones at the same framing. Reads the stored detectors (≈ 2-4 min).

    PYTHONPATH=. python results/synthetic/adaboost_rounds/fp_crops.py OUT.png V_DRONE_111 V_DRONE_114
"""
import sys
from pathlib import Path

import cv2
import numpy as np
import torch
from torchvision.ops import box_convert, box_iou

from synthaug.data.seedset import crop_patch
from synthaug.data.video import read_video_with_labels
from synthaug.detectors.base import load_detector
from synthaug.detectors.sliding import detect_multiscale
from synthaug.evaluate.patches import _find_video
from stored import stored_detectors  # this folder's (the script's directory is on sys.path)

SEED0 = {cell: ckpt for _, cell, ckpt in stored_detectors((0,))}
DETECTORS = {"real only": SEED0["real"], "shape cell": SEED0["shape"]}
N, P = 16, 48
torch.set_num_threads(1)
out, stems = sys.argv[1], sys.argv[2:]
frames_all, boxes_all = [], []
for stem in stems:
    frames, labs, _ = read_video_with_labels(_find_video(Path("../shared/data/halmstad/videos"), stem),
                                             f"../shared/data/halmstad/labels/{stem}.json")
    for f in range(0, len(labs.boxes), 5):
        if labs.boxes[f] is not None:
            frames_all.append(frames[f])
            boxes_all.append(np.asarray(labs.boxes[f], dtype=np.float64).reshape(-1, 4))


def crop(frame: np.ndarray, xyxy) -> np.ndarray:
    x0, y0, x1, y1 = (float(v) for v in xyxy)
    side = 1.5 * max(x1 - x0, y1 - y0)
    return crop_patch(frame, crop=[(x0 + x1) / 2, (y0 + y1) / 2, side], patch_size=P)[0]


rows = []
for name, ckpt in DETECTORS.items():
    det = load_detector(ckpt)
    found = []
    for i, (frame, gt) in enumerate(zip(frames_all, boxes_all)):
        d = detect_multiscale(det, torch.from_numpy(frame).float()[None] / 255, max_detections=10, refine_boxes=False)
        g = torch.as_tensor(np.c_[gt[:, :2], gt[:, :2] + gt[:, 2:]], dtype=torch.float32)
        xyxy = box_convert(d[:, :4], "xywh", "xyxy")  # detect_multiscale returns xywh boxes
        iou = box_iou(xyxy, g).max(1).values if len(d) else torch.zeros(0)
        for b, score, v in zip(xyxy, d[:, 4], iou):
            if v < 0.3:
                found.append((float(score), i, b.tolist()))
    found.sort(key=lambda t: -t[0])
    print(f"{name}: {len(found)} false positives in {len(frames_all)} frames; best scores "
          + ", ".join(f"{s:.2f}" for s, _, _ in found[:N]), flush=True)
    rows.append([crop(frames_all[i], b) for _, i, b in found[:N]])
drones = [crop(f, [b[0], b[1], b[0] + b[2], b[1] + b[3]]) for f, bs in zip(frames_all, boxes_all) for b in bs]
rows.append([drones[k] for k in np.linspace(0, len(drones) - 1, N).astype(int)])
grid = np.full((len(rows) * (P + 4), N * (P + 4)), 255, np.uint8)
for r, row in enumerate(rows):
    for c, im in enumerate(row):
        grid[r * (P + 4):r * (P + 4) + P, c * (P + 4):c * (P + 4) + P] = im
cv2.imwrite(out, cv2.resize(grid, None, fx=2, fy=2, interpolation=cv2.INTER_NEAREST))
print(f"rows: {', '.join(DETECTORS)}, drones -> {out}")
