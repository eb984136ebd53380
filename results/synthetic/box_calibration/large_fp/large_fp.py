"""Are HOG's large false positives on the test videos boxes around a drone at the wrong scale, or background?

Reads back one training seed's stored HOG detectors (100 seeds: real only, and + 20x synthetic from the d_HOG fit,
the paper's framing; both must be in the runner's cache), detects on the test split as the runner does (its NMS and
detections a frame; the box map applied, the calibration not), keeps each detector's top N detections pooled over the
videos (N = the labelled objects), and counts per size of the detected box: the false positives at IoU 0.5, those
covering at least half of a labelled drone, and those touching one. Detections are kept in --cache (a pickle a
detector), so a second call only counts.

usage: PYTHONPATH=. python results/synthetic/box_calibration/large_fp/large_fp.py SEED [--cache DIR]
"""
import argparse
import pickle
import sys
from pathlib import Path

import numpy as np

from synthaug.data.boxes import xywh_to_xyxy


def detections(seed: int, cache: Path) -> list[Path]:
    """The two detectors' detections on the test split, ``(name, per-video per-frame [x, y, w, h, score], boxes)``."""
    import torch

    from synthaug.evaluate import runner as R
    from synthaug.evaluate.cells import CellCache
    from synthaug.evaluate.protocol import load_protocol

    torch.set_num_threads(1)
    args = R.build_parser().parse_args(
        ["synthetic", "--protocol", "configs/protocol/halmstad_v2.json", "--class", "drone", "--detectors", "hog",
         "--synthetic-ratios", "20", "--fit-distance", "hog", "--no-scale-check", "--no-patches", "--seed-counts",
         "100", "--box-calibration", "20", "--eval-split", "test", "--training-seeds", str(seed), "--read-only",
         "--out", "unused"])
    proto = load_protocol(args.protocol)
    runner = R.ProtocolRunner(proto, "drone", R.DataPaths(args.videos, args.labels, args.split, args.work),
                              CellCache(Path(args.work) / "cells", read_only=True), options=R.train_options(args),
                              scale_check=False, patches=False, eval_split="test")
    conds: list = []
    R._run_into = lambda results, runner, cond, *a, **k: conds.append(cond)  # collect the conditions, run nothing
    R.synthetic_comparison(runner, detectors=["hog"], seed_count=100, synthetic_ratios=[20], fit_distance="hog")
    out = []
    for cond in conds[:2]:  # real only, + 20x synthetic
        path = cache / f"seed{seed}_{R._slug(cond.name)}.pkl"
        if not path.exists():
            es = runner.eval_set()
            det, _, _, read_back = runner._trained(cond, seed)
            if not read_back:
                raise SystemExit(f"{cond.name}: no stored detector for seed {seed} (trained one instead)")
            raw = R.detect_on_eval_set(det, es, scales=None, nms_iou=proto.detection.nms_iou,
                                       max_detections=proto.detection.max_detections, refine_boxes=False)
            dets = R.refine_detections(det, es, raw, nms_iou=proto.detection.nms_iou)
            with open(path, "wb") as f:
                pickle.dump((cond.name, dets, es.boxes), f)
        out.append(path)
    return out


def count(path: Path) -> str:
    with open(path, "rb") as f:
        name, dets, gts = pickle.load(f)
    rows = []
    for vd, vg in zip(dets, gts):
        for d, g in zip(vd, vg):
            if d is None or len(d) == 0:
                continue
            d = np.asarray(d, float)
            g = np.zeros((0, 4)) if g is None or len(g) == 0 else np.asarray(g, float)[:, :4]
            dx, gx = xywh_to_xyxy(d[:, :4]), xywh_to_xyxy(g)
            ix = np.clip(np.minimum(dx[:, None, 2], gx[None, :, 2]) - np.maximum(dx[:, None, 0], gx[None, :, 0]), 0, None)
            iy = np.clip(np.minimum(dx[:, None, 3], gx[None, :, 3]) - np.maximum(dx[:, None, 1], gx[None, :, 1]), 0, None)
            inter = ix * iy
            ad, ag = (dx[:, 2] - dx[:, 0]) * (dx[:, 3] - dx[:, 1]), (gx[:, 2] - gx[:, 0]) * (gx[:, 3] - gx[:, 1])
            iou = (inter / (ad[:, None] + ag[None] - inter)).max(1) if len(g) else np.zeros(len(d))
            cover = (inter / ag[None]).max(1) if len(g) else np.zeros(len(d))
            rows += [(d[k, 4], d[k, 2:4].max(), iou[k], cover[k]) for k in range(len(d))]
    a = np.array(rows)
    n = int(sum(len(g) for vg in gts for g in vg if g is not None))
    a = a[np.argsort(-a[:, 0], kind="stable")][:n]
    lines = [f"{name}: top {n} detections"]
    for lo, hi in ((0, 24), (24, 48), (48, 96), (96, np.inf)):
        s = a[(a[:, 1] >= lo) & (a[:, 1] < hi)]
        fp = s[s[:, 2] < 0.5]
        lines.append(f"  {lo:g}-{hi:g} px: {len(s)} detections, {len(fp)} false positives @0.5, "
                     f"{int((fp[:, 3] >= 0.5).sum())} covering half a drone or more, {int((fp[:, 3] > 0).sum())} touching one")
    return "\n".join(lines)


def main(argv: list[str]) -> str:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("seed", type=int)
    ap.add_argument("--cache", type=Path, default=Path("/tmp/large_fp"))
    a = ap.parse_args(argv)
    a.cache.mkdir(parents=True, exist_ok=True)
    return "\n".join(count(p) for p in detections(a.seed, a.cache)) + "\n"


if __name__ == "__main__":
    sys.stdout.write(main(sys.argv[1:]))
