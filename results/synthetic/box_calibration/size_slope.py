"""Median log(detected / labelled size) of the IoU-0.3 matches per size bucket, read by the labelled and by the
detected size, and the two regression slopes (log detected on log labelled and back), of stored runner results.

Usage: PYTHONPATH=. python results/synthetic/box_calibration/size_slope.py RESULT.json [...]  (stop 78)
"""
import numpy as np, sys
from synthaug.evaluate.results import ProtocolResult
def rows(path):
    r = ProtocolResult.load(path); out=[]
    for s in r.seeds.values():
        for v in s.videos:
            k = 1  # IoU 0.3 row (thresholds [0.5, 0.3])
            m = v.tp[k] & np.isfinite(v.match_size[k])
            out.append(np.stack([v.det_size[m], v.match_size[k][m]], 1))
    return np.concatenate(out)
for path in sys.argv[1:]:
    a = rows(path); d, t = np.log(a[:,0]), np.log(a[:,1]); e = d - t
    print(path.split('/')[-3:], len(a))
    for name, key in (("by labelled size", a[:,1]), ("by detected size", a[:,0])):
        cells = []
        for lo, hi in ((0,24),(24,48),(48,96)):
            sel = (key>=lo)&(key<hi)
            cells.append(f"{lo}-{hi}: n {sel.sum()}, median {np.median(e[sel]):+.3f}" if sel.sum() else f"{lo}-{hi}: -")
        print("  ", name, " | ".join(cells))
    # slope of log det on log true
    A = np.stack([t, np.ones_like(t)],1); print("   slope log det ~ log true", np.linalg.lstsq(A,d,rcond=None)[0].round(3),
          " slope log true ~ log det", np.linalg.lstsq(np.stack([d,np.ones_like(d)],1),t,rcond=None)[0].round(3))
