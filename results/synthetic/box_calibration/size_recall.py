"""Where a condition's AP change comes from, per size bucket: found objects (recall) or box sizes.

For each size bucket of the protocol (by the labelled box's longest side): the labelled objects, the share of them
found at IoU 0.3 and at IoU 0.5 (among the detector's kept detections: the recall at the end of the ranking, mean over
training seeds), the paired difference condition - baseline of each with its bootstrap-over-videos interval (the
protocol's resamples and seed, so the same video resamples as its AP differences), the median log(detected /
labelled) longest side of the IoU 0.3 matches, and the share of those matches that miss IoU 0.5.

usage: PYTHONPATH=. python results/synthetic/box_calibration/size_recall.py BASELINE.json CONDITION.json [--out F.md]
A side may name several files of one condition (other training seeds), comma-separated: A.json,B.json.
"""
import argparse
import sys

import numpy as np

from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.stats import bootstrap_statistic


def _per_video(result: ProtocolResult, bucket, k: int) -> tuple[np.ndarray, np.ndarray]:
    """``(found, labelled)``, each ``(seeds, videos)``: objects of the bucket matched at IoU index ``k``."""
    found, labelled = [], []
    for seed in result.seed_ids:
        f, n = [], []
        for v in result.seeds[seed].videos:
            tp = np.asarray(v.tp[k], dtype=bool)
            f.append(int(bucket.contains(np.asarray(v.match_size[k])[tp]).sum()))
            n.append(int(bucket.contains(v.gt_size).sum()))
        found.append(f)
        labelled.append(n)
    return np.asarray(found, float), np.asarray(labelled, float)


def _recall(found: np.ndarray, labelled: np.ndarray, counts: np.ndarray) -> float:
    den = labelled @ counts
    return float(np.mean((found @ counts) / den)) if np.all(den > 0) else float("nan")


def _boxes(result: ProtocolResult, bucket) -> tuple[float, float]:
    """Median log(detected / labelled) longest side of the IoU 0.3 matches, and their share missing IoU 0.5."""
    i5, i3 = result.protocol.iou_thresholds.index(0.5), result.protocol.iou_thresholds.index(0.3)
    logs, miss = [], []
    for seed in result.seed_ids:
        for v in result.seeds[seed].videos:
            m3 = np.asarray(v.match_size[i3], dtype=np.float64)
            sel = np.asarray(v.tp[i3], dtype=bool) & bucket.contains(m3)
            logs.append(np.log(np.asarray(v.det_size)[sel] / m3[sel]))
            miss.append(~np.asarray(v.tp[i5], dtype=bool)[sel])
    x, m = np.concatenate(logs), np.concatenate(miss)
    return (float(np.median(x)), float(m.mean())) if x.size else (float("nan"), float("nan"))


def main(argv: list[str]) -> str:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("baseline", help="stored result(s) of the baseline; several files of one condition: A.json,B.json")
    ap.add_argument("condition", help="stored result(s) of the condition, as the baseline")
    ap.add_argument("--out", default=None)
    a = ap.parse_args(argv)
    base, cond = (ProtocolResult.combine([ProtocolResult.load(f) for f in arg.split(",")])
                  for arg in (a.baseline, a.condition))
    p = base.protocol
    if cond.protocol.fingerprint() != p.fingerprint() or cond.stems != base.stems:
        raise SystemExit(f"{a.condition}: another protocol or other videos than {a.baseline}; the pairs would not hold")
    kw = dict(resamples=p.bootstrap.resamples, seed=p.bootstrap.seed, ci=p.bootstrap.ci)
    lines = [f"Baseline: {base.condition} ({a.baseline}); condition: {cond.condition} ({a.condition}); split "
             f"{base.split}, seeds {base.seed_ids} / {cond.seed_ids}, {len(base.stems)} videos.", "",
             "| size | objects (videos) | found @0.3: base / cond, Δ [CI] | found @0.5: base / cond, Δ [CI] "
             "| median log(det/labelled) @0.3: base / cond | miss 0.5 of 0.3 matches: base / cond |",
             "|---|---|---|---|---|---|"]
    for b in p.size_buckets:
        per_video = [int(b.contains(v.gt_size).sum()) for v in base.seeds[base.seed_ids[0]].videos]
        n, n_videos = sum(per_video), sum(c > 0 for c in per_video)  # one video: its interval is a point
        if n == 0:
            continue
        cells = []
        for iou in (0.3, 0.5):
            k = p.iou_thresholds.index(iou)
            fb, nb = _per_video(base, b, k)
            fc, nc = _per_video(cond, b, k)
            iv = bootstrap_statistic(lambda c: _recall(fc, nc, c) - _recall(fb, nb, c), len(base.stems), **kw)
            one = np.ones(len(base.stems))
            cells.append(f"{_recall(fb, nb, one):.3f} / {_recall(fc, nc, one):.3f}, "
                         f"{iv.estimate:+.3f} [{iv.low:+.3f}, {iv.high:+.3f}]")
        (sb, mb), (sc, mc) = _boxes(base, b), _boxes(cond, b)
        lines.append(f"| {b.label} | {n} ({n_videos}) | {cells[0]} | {cells[1]} | {sb:+.3f} / {sc:+.3f} "
                     f"| {mb:.3f} / {mc:.3f} |")
    text = "\n".join(lines) + "\n"
    if a.out:
        with open(a.out, "w") as f:
            f.write(text)
    return text


if __name__ == "__main__":
    print(main(sys.argv[1:]), end="")
