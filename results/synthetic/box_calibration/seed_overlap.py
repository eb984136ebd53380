"""Does the box calibration learn from frames the detector was trained on? (stop 74, issue 16)

The calibration frames (every k-th labelled frame of the training videos) and the real seed frames come from the same
videos. This reads a stored runner detector back, detects every k-th labelled training frame once (as
``calibrate_detector`` does), tags each matched detection by whether its frame lies within ``--near`` frames of one
of the detector's seed frames (same video), and fits the correction (``fit_calibration``) on all pairs, on the far
pairs only and on the near pairs only. Printed and written: the pairs per group and the correction each fit applies
at box sizes 16 / 32 / 64 px (dw, dh: log size; dx, dy: fraction of the box), with a bootstrap over frames of the far
fit (95 % percentile interval).

    PYTHONPATH=. python results/synthetic/box_calibration/seed_overlap.py --cell KEY [--cell KEY ...] \
        [--stride 20] [--near 10] [--protocol configs/protocol/halmstad_v2.json] \
        --out results/synthetic/box_calibration/seed_overlap.json

Detection as the runner's calibration runs it: the default scales, the protocol's ``nms_iou`` and ``max_detections``.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import torch

from synthaug.detectors.base import load_detector
from synthaug.detectors.box_calibration import detection_pairs, fit_calibration, size_features
from synthaug.detectors.frames import VideoFrames
from synthaug.detectors.sliding import detect_multiscale

RUNS = Path("data/runs")
SIZES = (16.0, 32.0, 64.0)


def correction_at(coef: torch.Tensor) -> list[list[float]]:
    """The deltas (dx, dy, dw, dh) the correction applies to square boxes of SIZES px."""
    boxes = torch.tensor([[0.0, 0.0, s, s] for s in SIZES], dtype=torch.float64)
    return [[round(float(v), 4) for v in row] for row in size_features(boxes) @ coef]


def seed_frames(cell: dict) -> dict[str, list[int]]:
    ident = cell["identity"]
    seed, n = ident["seed"], ident["condition"]["seed_count"]
    doc = json.loads((RUNS / f"ingest_{ident['class']}_seed{seed}" / "seedsets" / f"{ident['class']}_{n}"
                      / "seedset.json").read_text())
    out: dict[str, list[int]] = {}
    for r in doc["records"]:
        out.setdefault(r["video"], []).append(int(r["frame"]))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cell", nargs="+", required=True, help="stored detector keys (data/runs/cells/detectors/KEY)")
    ap.add_argument("--stride", type=int, default=20)
    ap.add_argument("--near", type=int, default=10, help="frames from a seed frame that count as near it")
    ap.add_argument("--resamples", type=int, default=1000)
    ap.add_argument("--data", default="../shared/data/halmstad")
    ap.add_argument("--protocol", default="configs/protocol/halmstad_v2.json", help="its detection settings")
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    detection = json.loads(Path(args.protocol).read_text())["detection"]
    report = {}
    for key in args.cell:
        cell = json.loads((RUNS / "cells" / "detectors" / f"{key}.json").read_text())
        det = load_detector(RUNS / "cells" / "detectors" / f"{key}.pt")
        seeds = seed_frames(cell)
        frames = VideoFrames(Path(args.data) / "videos", Path(args.data) / "labels",
                             positive=cell["result"]["meta"]["split"]["train"], stride=args.stride)
        t0 = time.perf_counter()
        rows = []  # (frame number, near, pairs, labelled)
        for item in frames:
            if item.boxes is None or np.asarray(item.boxes).size == 0:
                continue
            image = torch.as_tensor(np.asarray(item.image)).float() / 255.0
            d = detect_multiscale(det, image, nms_iou=detection["nms_iou"], max_detections=detection["max_detections"])
            p, g = detection_pairs(d.numpy(), item.boxes, min_iou=0.3)
            near = any(abs(item.index - f) <= args.near for f in seeds.get(item.video, ()))
            rows.append((near, p, g))
        secs = time.perf_counter() - t0

        def fit(sel):
            p = torch.cat([r[1] for r in sel]) if sel else torch.zeros(0, 4, dtype=torch.float64)
            g = torch.cat([r[2] for r in sel]) if sel else torch.zeros(0, 4, dtype=torch.float64)
            return int(p.shape[0]), (fit_calibration(p, g) if p.shape[0] >= 20 else None)

        groups = {"all": rows, "far": [r for r in rows if not r[0]], "near": [r for r in rows if r[0]]}
        res = {"frames": {k: len(v) for k, v in groups.items()}, "seconds": round(secs, 1), "sizes_px": list(SIZES)}
        for name, sel in groups.items():
            n, coef = fit(sel)
            res[name] = {"pairs": n, "correction": None if coef is None else correction_at(coef)}
        far = groups["far"]
        rng = np.random.default_rng(0)
        boots = []
        for _ in range(args.resamples):
            n, coef = fit([far[i] for i in rng.integers(0, len(far), len(far))])
            if coef is not None:
                boots.append(correction_at(coef))
        b = np.asarray(boots)
        res["far"]["interval_95"] = [np.round(np.percentile(b, 2.5, axis=0), 4).tolist(),
                                     np.round(np.percentile(b, 97.5, axis=0), 4).tolist()]
        report[key] = {"identity": cell["identity"]["condition"] | {"seed": cell["identity"]["seed"]}, **res}
        print(key, json.dumps(report[key]), flush=True)
    Path(args.out).write_text(json.dumps({"stride": args.stride, "near": args.near, "detection": detection,
                                          "cells": report}, indent=1) + "\n")


if __name__ == "__main__":
    main()
