"""Issue 15, AdaBoost's x2 failure: which pyramid levels and what window contrast its ranked false positives have.

For one trained AdaBoost (100 seeds, read back from the runner's cell cache), every pyramid level of every k-th
test frame at x1 and x2: the windows that survive per-level NMS, their score, their level, the window's mean
gradient magnitude (the weak learners' total energy / area) and whether the window box hits a labelled drone
(IoU >= 0.3 of the window box, before the box map). Prints per scale and level: the TP / FP counts among the
frame's top windows, and the contrast quantiles of TPs, FPs and of the training positives.

usage: PYTHONPATH=. python results/learning_curve/adaboost_scale/contrast.py [--seed 0] [--every 4]
"""
import argparse
import json

import numpy as np
import torch
import torchvision.ops as tv_ops

from synthaug.detectors.sliding import DEFAULT_SCALES, resize_image
from synthaug.detectors.weak_learners import interior_orientation_maps
from synthaug.evaluate.runner import Condition, build_parser, ProtocolRunner, DataPaths, train_options
from synthaug.evaluate.cells import CellCache
from synthaug.evaluate.protocol import load_protocol
from pathlib import Path

ap = argparse.ArgumentParser()
ap.add_argument("--seed", type=int, default=0)
ap.add_argument("--every", type=int, default=4)
ap.add_argument("--top", type=int, default=5)
a = ap.parse_args()
torch.set_num_threads(1)
args = build_parser().parse_args(["learning-curve", "--protocol", "configs/protocol/halmstad_v2.json", "--class", "drone",
                                  "--detectors", "adaboost", "--seed-counts", "100", "--out", "/tmp/unused"])
runner = ProtocolRunner(load_protocol(args.protocol), "drone", DataPaths(args.videos, args.labels, args.split, args.work),
                        CellCache(Path(args.work) / "cells", read_only=True), options=train_options(args))
det, meta, _, read_back = runner._trained(Condition("adaboost / 100 seeds", "adaboost", seed_count=100), a.seed)
assert read_back, "detector not in the cache"
print(det)
W, S = det.window, det.stride


def window_contrast(level):
    """Mean gradient magnitude of every window on the stride grid (interior pixels)."""
    mag = interior_orientation_maps(level, det.learners.n_bins)[0].sum(0, keepdim=True)[None]  # (1,1,H-2,W-2)
    m = torch.nn.functional.avg_pool2d(mag, W - 2, stride=S)[0, 0]
    return m


rows = {}
for scale in (1.0, 2.0):
    es = runner.eval_set(scale)
    for v, frames in enumerate(es.frames):
        for t in range(0, len(frames), a.every):
            img = torch.from_numpy(frames[t]).float()[None, None] / 255.0
            gt = es.boxes[v][t]
            gt = torch.zeros(0, 4) if gt is None else tv_ops.box_convert(torch.as_tensor(gt, dtype=torch.float32), "xywh", "xyxy")
            for li, s in enumerate(DEFAULT_SCALES):
                lev = resize_image(img, s)
                sm = det.score_map(lev)
                c = window_contrast(lev)[: sm.shape[0], : sm.shape[1]]
                ys, xs = torch.nonzero(torch.ones_like(sm, dtype=torch.bool), as_tuple=True)
                sy, sx = lev.shape[-2] / img.shape[-2], lev.shape[-1] / img.shape[-1]
                b = torch.stack([xs * S / sx, ys * S / sy, (xs * S + W) / sx, (ys * S + W) / sy], 1).float()
                sc = sm[ys, xs]
                keep = tv_ops.nms(b, sc, 0.3)[: a.top]
                iou = tv_ops.box_iou(b[keep], gt).amax(1) if len(gt) else torch.zeros(len(keep))
                for k, i in zip(keep.tolist(), iou.tolist()):
                    rows.setdefault((scale, s), []).append((float(sc[k]), float(c[ys[k], xs[k]]), i >= 0.3))
    print(f"x{scale:g} done", flush=True)

out = {}
for (scale, s), r in sorted(rows.items()):
    r = np.array(r)
    sc, con, tp = r[:, 0], r[:, 1], r[:, 2].astype(bool)
    hi = sc > 0  # windows the strong classifier calls object
    q = lambda x: [round(float(v), 4) for v in np.quantile(x, [0.05, 0.5, 0.95])] if len(x) else None
    out[f"x{scale:g} level {s:g}"] = {"windows": int(len(sc)), "score>0 TP": int((hi & tp).sum()), "score>0 FP": int((hi & ~tp).sum()),
                                     "contrast TP q05/50/95": q(con[tp & hi]), "contrast FP q05/50/95": q(con[~tp & hi])}
    print(f"x{scale:g} level {s:<5g} " + json.dumps(out[f'x{scale:g} level {s:g}']))
