"""Where a condition's AP change comes from, per size bucket: its false positives as well as its found objects.

For each size bucket of the protocol: the bucket's AP@0.5 with COCO semantics (a true positive counts when its object
is in the bucket, a false positive when its own box's longest side is; ``ProtocolResult.pools(bucket=)``) for the
baseline and the condition, with the paired difference and its bootstrap over the test videos (the protocol's
resamples and seed); and, at each detector's R-precision point (its top N detections pooled over the videos, N the
number of labelled objects: a rank, so it compares detectors whose scores are on different scales), the objects of the
bucket found there and the false positives of the bucket's size among them (means over training seeds).

usage: PYTHONPATH=. python results/synthetic/box_calibration/precision_by_size.py BASELINE.json CONDITION.json [--out F.md]
A side may name several files of one condition (other training seeds), comma-separated: A.json,B.json.
"""
import argparse
import sys

import numpy as np

from synthaug.evaluate.protocol import SizeBucket
from synthaug.evaluate.results import ProtocolResult
from synthaug.evaluate.stats import paired_difference


def _top_n(result: ProtocolResult, seed: int, k: int, k_loose: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(is_tp, size, loose)`` of one seed's top-N pooled detections at IoU index ``k``: the object's size for a
    true positive, the box's own for a false positive; whether it matches at IoU index ``k_loose`` (a false positive
    that does is a misplaced box on an object, not a detection of background); N = the labelled objects."""
    videos = result.seeds[seed].videos
    scores = np.concatenate([v.scores for v in videos])
    tp = np.concatenate([np.asarray(v.tp[k], bool) for v in videos])
    loose = np.concatenate([np.asarray(v.tp[k_loose], bool) for v in videos])
    size = np.concatenate([np.where(np.asarray(v.tp[k], bool), v.match_size[k], v.det_size) for v in videos])
    n = int(sum(v.gt_size.size for v in videos))
    order = np.argsort(-scores, kind="stable")[:n]  # the pooled order of synthaug.evaluate.stats.PooledRanking
    return tp[order], size[order], loose[order]


def _at_r_precision(result: ProtocolResult, bucket, k: int, k_loose: int) -> tuple[float, float, float, float]:
    """Means over seeds, in the top N: objects of the bucket found, false positives of the bucket's size, those of
    them that match an object at the loose IoU; and the precision there."""
    found, fps, near, prec = [], [], [], []
    for s in result.seed_ids:
        tp, size, loose = _top_n(result, s, k, k_loose)
        inb = bucket.contains(size)
        found.append(float((tp & inb).sum()))
        fps.append(float((~tp & inb).sum()))
        near.append(float((~tp & inb & loose).sum()))
        prec.append(float(tp.mean()) if tp.size else float("nan"))
    return float(np.mean(found)), float(np.mean(fps)), float(np.mean(near)), float(np.mean(prec))


def main(argv: list[str]) -> str:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("baseline", help="stored result(s) of the baseline; several files of one condition: A.json,B.json")
    ap.add_argument("condition", help="stored result(s) of the condition, as the baseline")
    ap.add_argument("--out", default=None)
    a = ap.parse_args(argv)
    base, cond = (ProtocolResult.combine([ProtocolResult.load(f) for f in arg.split(",")])
                  for arg in (a.baseline, a.condition))
    proto = base.protocol
    k = proto.iou_thresholds.index(proto.main_iou)
    k_loose = int(np.argmin(proto.iou_thresholds))
    common = [s for s in base.seed_ids if s in cond.seed_ids]
    if not common:
        raise SystemExit("the two sides share no training seed")
    rows = []
    for bucket in proto.size_buckets:
        d = paired_difference(base.pools(bucket=bucket), cond.pools(bucket=bucket), resamples=proto.bootstrap.resamples,
                              seed=proto.bootstrap.seed)
        fb, pb, nb, _ = _at_r_precision(base, bucket, k, k_loose)
        fc, pc, nc, _ = _at_r_precision(cond, bucket, k, k_loose)
        rows.append(f"| {bucket.label} | {base.n_objects(bucket)} | {base.mean_ap(bucket=bucket):.3f} / "
                    f"{cond.mean_ap(bucket=bucket):.3f}, {d.difference.format(signed=True)} | {fb:.1f} / {fc:.1f} | "
                    f"{pb:.1f} / {pc:.1f} | {nb:.1f} / {nc:.1f} |")
    prb = _at_r_precision(base, SizeBucket(0.0, None), k, k_loose)[3]
    prc = _at_r_precision(cond, SizeBucket(0.0, None), k, k_loose)[3]
    d_all = paired_difference(base.pools(), cond.pools(), resamples=proto.bootstrap.resamples,
                            seed=proto.bootstrap.seed)
    head = (f"Baseline: {base.condition} ({a.baseline}); condition: {cond.condition} ({a.condition}); split "
            f"{base.split}, seeds {common}, {len(base.stems)} videos, IoU {proto.main_iou}. All sizes: AP "
            f"{base.mean_ap():.3f} / {cond.mean_ap():.3f}, {d_all.difference.format(signed=True)}; precision at the "
            f"R-precision point {prb:.3f} / {prc:.3f}.\n\n"
            f"| size | objects | AP@{proto.main_iou} of the bucket (COCO): base / cond, Δ [CI] | objects found in the "
            f"top N: base / cond | false positives of this size in the top N: base / cond | of which on an object at IoU "
            f"{proto.iou_thresholds[k_loose]} |\n|---|---|---|---|---|---|")
    text = head + "\n" + "\n".join(rows) + "\n"
    if a.out:
        with open(a.out, "w") as f:
            f.write(text)
    return text


if __name__ == "__main__":
    sys.stdout.write(main(sys.argv[1:]))
