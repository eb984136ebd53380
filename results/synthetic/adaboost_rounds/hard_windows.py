"""The best background windows a detector keeps in the small-drone test videos, read by ``puff_probe.py`` and
``../adaboost_distractors/probe.py``."""
from pathlib import Path

import numpy as np
import torch
from torchvision.ops import box_convert, box_iou

from synthaug.data.seedset import crop_patch
from synthaug.data.video import read_video_with_labels
from synthaug.detectors.sliding import detect_multiscale
from synthaug.evaluate.patches import _find_video

# the five test videos whose background outranks the drones (README section 6)
STEMS = ("V_DRONE_109", "V_DRONE_111", "V_DRONE_112", "V_DRONE_113", "V_DRONE_114")


def hardest_windows(det, keep: int, stems=STEMS, *, every: int = 5,
                    iou_max: float = 0.3) -> tuple[torch.Tensor, int]:
    """``det``'s ``keep`` best raw windows (10 a frame, no box refinement) overlapping no drone (IoU < ``iou_max``)
    on every ``every``-th frame of ``stems``, cut at the window (the detector's framing), as ``(keep, 1, P, P)``
    patches in [0, 1], best first; and how many such windows there were."""
    hard = []
    for stem in stems:
        frames, labs, _ = read_video_with_labels(_find_video(Path("../shared/data/halmstad/videos"), stem),
                                                 f"../shared/data/halmstad/labels/{stem}.json")
        for f in range(0, len(labs.boxes), every):
            if labs.boxes[f] is None:
                continue
            gt = np.asarray(labs.boxes[f], dtype=np.float64).reshape(-1, 4)
            d = detect_multiscale(det, torch.from_numpy(frames[f]).float()[None] / 255, max_detections=10,
                                  refine_boxes=False)
            if not len(d):
                continue
            xyxy = box_convert(d[:, :4], "xywh", "xyxy")
            gtx = torch.as_tensor(np.c_[gt[:, :2], gt[:, :2] + gt[:, 2:]], dtype=torch.float32)
            iou = box_iou(xyxy, gtx).max(1).values
            for (x, y, w, h), score, v in zip(d[:, :4].tolist(), d[:, 4].tolist(), iou.tolist()):
                if v < iou_max:
                    hard.append((score, crop_patch(frames[f], crop=[x + w / 2, y + h / 2, max(w, h)],
                                                   patch_size=int(det.window))[0]))
    hard.sort(key=lambda t: -t[0])
    return torch.from_numpy(np.stack([c for _, c in hard[:keep]])).float()[:, None] / 255, len(hard)
