"""An 80-px crop around a detector's best window in eight frames of each given video, titled with the frame, its
score and whether the frame's label is null: where the labels say "not visible", is the drone there?

    PYTHONPATH=. python results/learning_curve/unlabelled_drones/evidence.py DETECTOR.pt OUT.png \
        [--videos V_DRONE_106 V_DRONE_107 V_DRONE_108]
"""
import argparse

import matplotlib
import numpy as np
import torch

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from synthaug.data.video import read_video_with_labels  # noqa: E402
from synthaug.detectors.base import load_detector  # noqa: E402
from synthaug.detectors.sliding import detect_multiscale  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("detector")
ap.add_argument("out")
ap.add_argument("--videos", nargs="+", default=["V_DRONE_106", "V_DRONE_107", "V_DRONE_108"])
ap.add_argument("--data", default="../shared/data/halmstad")
a = ap.parse_args()
det = load_detector(a.detector)
fig, axs = plt.subplots(len(a.videos), 8, figsize=(16, 2 * len(a.videos)), squeeze=False)
for row, v in enumerate(a.videos):
    frames, labels, _ = read_video_with_labels(f"{a.data}/videos/{v}.mp4", f"{a.data}/labels/{v}.json")
    for col, i in enumerate(np.linspace(0, len(labels.boxes) - 1, 8).astype(int)):
        x, y, w, h, s = detect_multiscale(det, torch.from_numpy(frames[i]).float() / 255, max_detections=1)[0, :5].tolist()
        cx, cy, r = x + w / 2, y + h / 2, 40
        ax = axs[row, col]
        ax.imshow(frames[i][max(0, int(cy - r)):int(cy + r), max(0, int(cx - r)):int(cx + r)], cmap="gray")
        ax.set_axis_off()
        ax.set_title(f"{v[-3:]} f{i} s{s:.2f} {'lab' if labels.boxes[i] is not None else 'null'}", fontsize=8)
plt.tight_layout()
plt.savefig(a.out, dpi=60)
