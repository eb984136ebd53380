"""Median log(detected / labelled size) of the IoU-0.3 matches per size bucket, read by the labelled and by the
detected size, and the two regression slopes (log detected on log labelled and back), of stored runner results.

Read by the labelled size, any detector whose box size is a noisy reading of the object's shows small objects'
boxes too large and large objects' too small (regression to the mean); read by the detected size, only what a
correction could still take out remains. Stop 78.

Usage: PYTHONPATH=. python results/synthetic/box_calibration/size_slope.py RESULT.json [...]
A result may name several files of one condition (other training seeds), comma-separated: A.json,B.json.
The buckets are the protocol's (``size_buckets_px``), as in ``size_recall.py``.
"""

from __future__ import annotations

import sys

import numpy as np

from synthaug.evaluate.results import ProtocolResult


def matched_sizes(res: ProtocolResult, iou: float = 0.3) -> np.ndarray:
    """(N, 2): the longest side of each true positive at ``iou`` and of the labelled box it matched, all seeds."""
    k = list(res.protocol.iou_thresholds).index(iou)
    rows = []
    for seed in res.seeds.values():
        for v in seed.videos:
            m = v.tp[k] & np.isfinite(v.match_size[k])
            rows.append(np.stack([v.det_size[m], v.match_size[k][m]], 1))
    return np.concatenate(rows)


def main(paths: list[str]) -> None:
    for path in paths:
        res = ProtocolResult.combine([ProtocolResult.load(f) for f in path.split(",")])
        a = matched_sizes(res)
        det, lab = np.log(a[:, 0]), np.log(a[:, 1])
        err = det - lab
        print(path, f"{len(a)} matches at IoU 0.3")
        for name, key in (("by labelled size", a[:, 1]), ("by detected size", a[:, 0])):
            cells = []
            for b in res.protocol.size_buckets:
                sel = b.contains(key)
                cells.append(f"{b.label}: n {sel.sum()}, median {np.median(err[sel]):+.3f}" if sel.any()
                             else f"{b.label}: -")
            print("  ", name, " | ".join(cells))
        ones = np.ones_like(det)
        fwd = np.linalg.lstsq(np.stack([lab, ones], 1), det, rcond=None)[0]
        back = np.linalg.lstsq(np.stack([det, ones], 1), lab, rcond=None)[0]
        print(f"   slope of log detected on log labelled {fwd[0]:.3f}; of log labelled on log detected {back[0]:.3f}")


if __name__ == "__main__":
    main(sys.argv[1:])
