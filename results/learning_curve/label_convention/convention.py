"""Issue 15: how the annotators' box relates to the drone it frames, per video, measured without any model.

Each seed of a seed set (``synthaug ingest``) has its patch (the labelled box centred at ``object_fraction`` of the
patch) and its object-free background (a temporal median of aligned neighbour frames, ``background_method ==
"median"``; inpainted backgrounds are skipped: they are not independent of the object). The object's extent is the
bounding box of the pixels whose |patch − background| exceeds a threshold (``--k`` times the background's own
robust noise, at least ``--floor`` gray levels), restricted to the connected component nearest the patch centre;
its ratio to the labelled box (longest sides, and width / height separately) is the annotators' margin for that
seed. Grouped by video: how much of the margin's spread lies between videos (one convention per video) rather than
within them, what IoU a perfect object localiser reaches once its box is grown by the pooled margin or by a margin
predicted from the object's size, and the object's contrast sign (brighter or darker than its background).

    PYTHONPATH=. python results/learning_curve/label_convention/convention.py NAME=SEEDSET_DIR [NAME=SEEDSET_DIR ...] \
        [--json OUT.json]
"""
from __future__ import annotations

import argparse
import json
from collections import defaultdict

import numpy as np
import torch
from scipy import ndimage
from torchvision.ops import box_iou

from synthaug.data.seedset import SeedSet


def object_extent(patch: np.ndarray, background: np.ndarray, *, k: float, floor: float,
                  ) -> tuple[float, float, float, float] | None:
    """``(x0, y0, x1, y1)`` in patch px (inclusive-exclusive) of the object's bounding box, or None when nothing
    stands out."""
    d = np.abs(patch.astype(np.float64) - background.astype(np.float64))
    ring = np.concatenate([d[:3].ravel(), d[-3:].ravel(), d[:, :3].ravel(), d[:, -3:].ravel()])
    noise = 1.4826 * np.median(np.abs(ring - np.median(ring)))
    mask = d > max(floor, np.median(ring) + k * noise)
    lab, n = ndimage.label(ndimage.binary_closing(mask, iterations=1))
    if n == 0:
        return None
    c = (np.asarray(patch.shape) - 1) / 2
    best, best_dist = 0, np.inf
    for i, sl in enumerate(ndimage.find_objects(lab), start=1):
        ys, xs = np.nonzero(lab[sl] == i)
        if ys.size < 4:
            continue
        dist = np.hypot(ys.mean() + sl[0].start - c[0], xs.mean() + sl[1].start - c[1])
        if dist < best_dist:
            best, best_dist = i, dist
    if best == 0:
        return None
    ys, xs = np.nonzero(lab == best)
    return float(xs.min()), float(ys.min()), float(xs.max() + 1), float(ys.max() + 1)


def measure(seedset_dir: str, *, k: float, floor: float) -> dict[str, list[dict[str, float]]]:
    ss = SeedSet.load(seedset_dir)
    p = int(ss.patches.shape[-1])
    frac = float(ss.metadata.get("object_fraction", 0.7)) if hasattr(ss, "metadata") and ss.metadata else 0.7
    per_video: dict[str, list[dict[str, float]]] = defaultdict(list)
    for i, rec in enumerate(ss.records):
        if rec.get("background_method") != "median":
            continue
        ext = object_extent(np.asarray(ss.patches[i]), np.asarray(ss.backgrounds[i]), k=k, floor=floor)
        if ext is None:
            continue
        bw, bh = float(rec["box"][2]), float(rec["box"][3])
        scale = frac * p / max(bw, bh)  # frame px -> patch px
        lw, lh = bw * scale, bh * scale
        ew, eh = ext[2] - ext[0], ext[3] - ext[1]
        d = (np.asarray(ss.patches[i], np.float64) - np.asarray(ss.backgrounds[i], np.float64))[
            int(ext[1]):int(ext[3]), int(ext[0]):int(ext[2])]
        strong = d[np.abs(d) > floor]
        sign = float(strong.sum() / max(np.abs(strong).sum(), 1e-9))  # +1: all brighter than the background
        per_video[rec["video"]].append({"longest": max(ew, eh) / max(lw, lh), "w": ew / lw, "h": eh / lh,
                                        "label_px": max(bw, bh), "object": list(ext), "sign": sign,
                                        "label": [(p - lw) / 2, (p - lh) / 2, (p + lw) / 2, (p + lh) / 2]})
    return per_video


def oracle_iou(per_video: dict[str, list[dict[str, float]]], w_ratio: float | np.ndarray,
               h_ratio: float | np.ndarray) -> np.ndarray:
    """IoU with the labelled box of a perfect object localiser mapped to the annotators' box by a margin: the
    object's own box, same centre, width / ``w_ratio`` and height / ``h_ratio`` (one pooled value, or one per seed)."""
    obj = np.array([s["object"] for v in per_video.values() for s in v])
    lab = np.array([s["label"] for v in per_video.values() for s in v])
    cx, cy = (obj[:, 0] + obj[:, 2]) / 2, (obj[:, 1] + obj[:, 3]) / 2
    w, h = (obj[:, 2] - obj[:, 0]) / w_ratio, (obj[:, 3] - obj[:, 1]) / h_ratio
    boxes = torch.from_numpy(np.stack([cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2], 1))
    return box_iou(boxes, torch.from_numpy(lab)).diagonal().numpy()


def size_model(per_video: dict[str, list[dict[str, float]]]) -> tuple[float, float]:
    """Least squares ``log(object / label) = a + b log(object's longest side, frame px)``: how the margin follows the
    object's size (what a box map that sees the object can learn)."""
    r = np.array([s["longest"] for v in per_video.values() for s in v])
    obj = r * np.array([s["label_px"] for v in per_video.values() for s in v])
    a, b = np.linalg.lstsq(np.stack([np.ones_like(obj), np.log(obj)], 1), np.log(r), rcond=None)[0]
    return float(a), float(b)


def oracle_iou_sized(per_video: dict[str, list[dict[str, float]]], model: tuple[float, float]) -> np.ndarray:
    """As :func:`oracle_iou`, the margin predicted from each object's size by :func:`size_model`."""
    px = np.array([s["longest"] * s["label_px"] for v in per_video.values() for s in v])
    r = np.exp(model[0] + model[1] * np.log(px))
    return oracle_iou(per_video, r, r)


def summary(per_video: dict[str, list[dict[str, float]]], reference: tuple[float, float] | None = None,
            model: tuple[float, float] | None = None) -> dict[str, float]:
    allr = np.array([s["longest"] for v in per_video.values() for s in v])
    wr = float(np.median([s["w"] for v in per_video.values() for s in v]))
    hr = float(np.median([s["h"] for v in per_video.values() for s in v]))
    ref = (wr, hr) if reference is None else reference
    iou = oracle_iou(per_video, *ref)
    model = size_model(per_video) if model is None else model
    iou_sized = oracle_iou_sized(per_video, model)
    px = np.array([s["longest"] * s["label_px"] for v in per_video.values() for s in v])
    lpx = np.array([s["label_px"] for v in per_video.values() for s in v])
    vids = {v: np.median([s["longest"] for s in ss]) for v, ss in per_video.items() if len(ss) >= 2}
    med = np.array(list(vids.values()))
    pooled = float(np.median(allr))
    # a centred box of the pooled margin against each video's own: IoU of nested centred squares = (min/max)^2
    viou = np.minimum(med, pooled) ** 2 / np.maximum(med, pooled) ** 2
    within = np.concatenate([np.log([s["longest"] for s in ss]) - np.log(np.median([s["longest"] for s in ss]))
                             for v, ss in per_video.items() if len(ss) >= 2])
    return {"seeds": int(allr.size), "videos": len(vids), "median_object_over_label": pooled,
            "q10": float(np.quantile(allr, 0.1)), "q90": float(np.quantile(allr, 0.9)),
            "video_median_q10": float(np.quantile(med, 0.1)), "video_median_q90": float(np.quantile(med, 0.9)),
            "video_median_min": float(med.min()), "video_median_max": float(med.max()),
            "sd_log_between_videos": float(np.std(np.log(med))), "sd_log_within_videos": float(np.std(within)),
            "videos_pooled_box_iou_below_0.5": int((viou < 0.5).sum()),
            "median_w_over_label_w": wr, "median_h_over_label_h": hr, "oracle_margin": list(ref),
            "oracle_iou_median": float(np.median(iou)), "oracle_share_iou_0.5": float((iou >= 0.5).mean()),
            "oracle_share_iou_0.3": float((iou >= 0.3).mean()),
            "object_px_median": float(np.median(px)), "label_px_median": float(np.median(lpx)),
            "size_model": list(model),
            "share_brighter": float(np.mean([s["sign"] > 0.3 for v in per_video.values() for s in v])),
            "videos_brighter": int(sum(np.median([s["sign"] for s in ss]) > 0.3 for ss in per_video.values())),
            "videos_darker": int(sum(np.median([s["sign"] for s in ss]) < -0.3 for ss in per_video.values())), "sized_oracle_iou_median": float(np.median(iou_sized)),
            "sized_oracle_share_iou_0.5": float((iou_sized >= 0.5).mean()),
            "sized_oracle_share_iou_0.3": float((iou_sized >= 0.3).mean())}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sets", nargs="+", help="NAME=SEEDSET_DIR")
    ap.add_argument("--k", type=float, default=4.0, help="threshold in robust noise units")
    ap.add_argument("--floor", type=float, default=6.0, help="threshold floor, gray levels")
    ap.add_argument("--json", default=None)
    ap.add_argument("--reference", default=None,
                    help="NAME of the set whose pooled margin the oracle uses for every set (default: each its own)")
    a = ap.parse_args()
    out: dict = {}
    measured = {}
    for item in a.sets:
        name, path = item.split("=", 1)
        measured[name] = measure(path, k=a.k, floor=a.floor)
    ref = model = None
    if a.reference:
        r = summary(measured[a.reference])
        ref = (r["median_w_over_label_w"], r["median_h_over_label_h"])
        model = tuple(r["size_model"])
    for name, pv in measured.items():
        out[name] = {"summary": summary(pv, ref, model), "per_video": {v: float(np.median([s["longest"] for s in ss]))
                                                                 for v, ss in sorted(pv.items())}}
        s = out[name]["summary"]
        print(f"{name}: {s['seeds']} seeds, {s['videos']} videos; object / label (longest side) median "
              f"{s['median_object_over_label']:.2f} [{s['q10']:.2f}, {s['q90']:.2f}]; per-video medians "
              f"{s['video_median_min']:.2f} … {s['video_median_max']:.2f}; sd(log) between videos "
              f"{s['sd_log_between_videos']:.2f}, within {s['sd_log_within_videos']:.2f}; videos where a box of the "
              f"pooled margin has IoU < 0.5: {s['videos_pooled_box_iou_below_0.5']}; w {s['median_w_over_label_w']:.2f}, "
              f"h {s['median_h_over_label_h']:.2f}; oracle localiser + pooled margin ({s['oracle_margin'][0]:.2f}, "
              f"{s['oracle_margin'][1]:.2f}): IoU median {s['oracle_iou_median']:.2f}, >= 0.5 {s['oracle_share_iou_0.5']:.0%}, "
              f">= 0.3 {s['oracle_share_iou_0.3']:.0%}; object {s['object_px_median']:.1f} px, label {s['label_px_median']:.1f} px "
              f"(medians); margin from the object's size (log r = {s['size_model'][0]:.2f} + {s['size_model'][1]:.2f} log px): "
              f"IoU median {s['sized_oracle_iou_median']:.2f}, >= 0.5 {s['sized_oracle_share_iou_0.5']:.0%}, "
              f">= 0.3 {s['sized_oracle_share_iou_0.3']:.0%}; brighter than the background {s['share_brighter']:.0%} of the seeds "
              f"({s['videos_brighter']} videos brighter, {s['videos_darker']} darker)", flush=True)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
