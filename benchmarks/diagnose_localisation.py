"""Diagnose why AP@IoU0.5 is low on the halmstad drones: localisation vs recognition (validation videos only).

Trains the CNN on drone_100 real seeds (the baseline cell), detects on the
validation videos (every k-th frame) and prints JSON with, over labelled frames:
the fraction whose best-overlapping detection (among the top 10 per frame)
reaches IoU >= 0.5 / >= 0.3 / any overlap, the median of that best IoU, and the
AP with the default pyramid vs a finer one (12 levels, ratio ~1.12). Run from the repository root:

    python benchmarks/diagnose_localisation.py --val-stride-k 30 --max-val-videos 10
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import torch


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--val-stride-k", type=int, default=30)
    p.add_argument("--max-val-videos", type=int, default=10)
    p.add_argument("--kind", default="cnn")
    args = p.parse_args()
    torch.set_num_threads(1)
    from torchvision.ops import box_convert, box_iou

    from synthaug.detectors.sliding import DEFAULT_SCALES, detect_multiscale, geometric_scales
    from synthaug.detectors.training import train_detector
    from synthaug.evaluate.ap import evaluate_detections
    from synthaug.evaluate.context import ExperimentContext

    ctx = ExperimentContext(out_dir=Path("/tmp/diag"), val_stride_k=args.val_stride_k, max_val_videos=args.max_val_videos, log=lambda m: None)
    es = ctx.eval_set("val")
    d = ctx.real_build(100)()
    det = train_detector(args.kind, d["positives"], d["negatives"], 0, box_in_window=d["box_in_window"],
                         mining_frames=d["mining_frames"], mining_boxes=d["mining_boxes"])
    out: dict = {"kind": args.kind, "val_frames": es.n_frames, "val_objects": es.n_objects, "box_in_window": d["box_in_window"]}
    variants = {"default_scales": list(DEFAULT_SCALES), "fine_scales_1.12": list(geometric_scales(1.4, 0.41, 12))}
    for name, scales in variants.items():
        t0 = time.perf_counter()
        dets, gts, best = [], [], []
        for frames, boxes in zip(es.frames, es.boxes):
            for f, g in zip(frames, boxes):
                dd = detect_multiscale(det, torch.from_numpy(f).float() / 255, scales=scales, max_detections=10).numpy().astype(np.float64)
                dets.append(dd)
                gts.append(g)
                if g is not None:
                    gt_xyxy = box_convert(torch.as_tensor(np.asarray(g, dtype=np.float64).reshape(-1, 4)), "xywh", "xyxy")
                    best.append(float(box_iou(gt_xyxy, box_convert(torch.from_numpy(dd[:, :4]), "xywh", "xyxy")).max()) if len(dd) else 0.0)
        best = np.array(best)
        out[name] = {"ap_iou0.5": evaluate_detections(dets, gts, 0.5).ap, "ap_iou0.3": evaluate_detections(dets, gts, 0.3).ap,
                     "top10_best_iou>=0.5": float((best >= 0.5).mean()), "top10_best_iou>=0.3": float((best >= 0.3).mean()),
                     "top10_any_overlap": float((best > 0).mean()), "median_best_iou": float(np.median(best)),
                     "seconds": round(time.perf_counter() - t0, 1)}
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
