"""Where a condition's AP change comes from, per size bucket: found objects (recall) or box sizes.

For each size bucket of the protocol (by the labelled box's longest side): the labelled objects, the share of them
found at IoU 0.3 and at IoU 0.5 (among the detector's kept detections: the recall at the end of the ranking, mean over
training seeds), the paired difference condition - baseline of each with its bootstrap-over-videos interval (the
protocol's resamples and seed, so the same video resamples as its AP differences), the median log(detected /
labelled) longest side of the IoU 0.3 matches, and the share of those matches that miss IoU 0.5.

With --false-positives (stop 81) a second table gives the other half of AP: per bucket, the bucket's AP@0.5 with COCO
semantics (a false positive counts in the bucket of its own box's size; ``ProtocolResult.pools(bucket=)``) with its
paired difference, and at each detector's R-precision point (its top N detections pooled over the videos, N the
labelled objects: a rank, so detectors whose scores are on different scales compare) the bucket's objects found there
and the false positives of the bucket's size among them, with those still on an object at the loose IoU (a misplaced
box rather than background); means over training seeds.

usage: PYTHONPATH=. python results/synthetic/box_calibration/size_recall.py BASELINE.json CONDITION.json
       [--false-positives] [--out F.md]
A side may name several files of one condition (other training seeds), comma-separated: A.json,B.json.
"""
import argparse
import sys

import numpy as np

from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.stats import bootstrap_statistic, paired_difference


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


def _top_n(result: ProtocolResult, k: int, k_loose: int) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per seed, ``(is_tp, size, loose)`` of its top-N pooled detections at IoU index ``k``: the object's size for a
    true positive, the box's own for a false positive; whether it matches at IoU index ``k_loose`` (a false positive
    that does is a misplaced box on an object, not a detection of background); N = the labelled objects."""
    out = []
    for seed in result.seed_ids:
        videos = result.seeds[seed].videos
        scores = np.concatenate([v.scores for v in videos])
        tp = np.concatenate([np.asarray(v.tp[k], bool) for v in videos])
        loose = np.concatenate([np.asarray(v.tp[k_loose], bool) for v in videos])
        size = np.concatenate([np.where(np.asarray(v.tp[k], bool), v.match_size[k], v.det_size) for v in videos])
        n = int(sum(v.gt_size.size for v in videos))
        order = np.argsort(-scores, kind="stable")[:n]  # the pooled order of synthaug.evaluate.stats.PooledRanking
        out.append((tp[order], size[order], loose[order]))
    return out


def _at_r_precision(tops: list[tuple[np.ndarray, np.ndarray, np.ndarray]], bucket) -> tuple[float, float, float]:
    """Means over seeds (``tops``: :func:`_top_n`), in the top N: objects of the bucket found, false positives of the
    bucket's size, and those of them that match an object at the loose IoU."""
    found, fps, near = [], [], []
    for tp, size, loose in tops:
        inb = bucket.contains(size)
        found.append(float((tp & inb).sum()))
        fps.append(float((~tp & inb).sum()))
        near.append(float((~tp & inb & loose).sum()))
    return float(np.mean(found)), float(np.mean(fps)), float(np.mean(near))


def _false_positive_lines(base: ProtocolResult, cond: ProtocolResult) -> list[str]:
    """The --false-positives table: bucket AP (COCO) and the top N's objects and false positives by size."""
    proto = base.protocol
    k = proto.iou_thresholds.index(proto.main_iou)
    k_loose = int(np.argmin(proto.iou_thresholds))
    kw = dict(resamples=proto.bootstrap.resamples, seed=proto.bootstrap.seed, ci=proto.bootstrap.ci)
    tops_b, tops_c = _top_n(base, k, k_loose), _top_n(cond, k, k_loose)
    d_all = paired_difference(base.pools(), cond.pools(), **kw)
    qb, qc = (float(np.mean([tp.mean() if tp.size else np.nan for tp, _, _ in t])) for t in (tops_b, tops_c))
    lines = ["", f"All sizes: AP@{proto.main_iou:g} {base.mean_ap():.3f} / {cond.mean_ap():.3f}, "
                 f"{d_all.difference.format(signed=True)}; precision at the R-precision point {qb:.3f} / {qc:.3f}.",
             "", f"| size | objects | AP@{proto.main_iou:g} of the bucket (COCO): base / cond, Δ [CI] | objects "
                 "found in the top N: base / cond | false positives of this size in the top N: base / cond | of which "
                 f"on an object at IoU {proto.iou_thresholds[k_loose]:g} |", "|---|---|---|---|---|---|"]
    for bucket in proto.size_buckets:
        if base.n_objects(bucket) == 0:
            continue
        d = paired_difference(base.pools(bucket=bucket), cond.pools(bucket=bucket), **kw)
        fb, pb, nb = _at_r_precision(tops_b, bucket)
        fc, pc, nc = _at_r_precision(tops_c, bucket)
        lines.append(f"| {bucket.label} | {base.n_objects(bucket)} | {base.mean_ap(bucket=bucket):.3f} / "
                     f"{cond.mean_ap(bucket=bucket):.3f}, {d.difference.format(signed=True)} | {fb:.1f} / {fc:.1f} | "
                     f"{pb:.1f} / {pc:.1f} | {nb:.1f} / {nc:.1f} |")
    return lines


def main(argv: list[str]) -> str:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("baseline", help="stored result(s) of the baseline; several files of one condition: A.json,B.json")
    ap.add_argument("condition", help="stored result(s) of the condition, as the baseline")
    ap.add_argument("--false-positives", action="store_true",
                    help="add the bucket APs and the top N's false positives by size")
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
    if a.false_positives:
        lines += _false_positive_lines(base, cond)
    text = "\n".join(lines) + "\n"
    if a.out:
        with open(a.out, "w") as f:
            f.write(text)
    return text


if __name__ == "__main__":
    print(main(sys.argv[1:]), end="")
