"""Frame AP@0.5 / @0.3 of stored protocol results on the test videos whose drones are brighter vs darker than their
background (per video: the median contrast sign of its seeds, ``convention.measure``; videos without a seed with a
median background are left out).

    PYTHONPATH=. python results/learning_curve/label_convention/by_sign.py SEEDSET_DIR RESULT.json [RESULT.json ...]
"""
import sys

import numpy as np

sys.path.insert(0, __file__.rsplit("/", 1)[0])
from convention import measure  # noqa: E402

from synthaug.evaluate.results import ProtocolResult  # noqa: E402

per_video = measure(sys.argv[1], k=4.0, floor=6.0)
sign = {v: float(np.median([s["sign"] for s in ss])) for v, ss in per_video.items()}
for path in sys.argv[2:]:
    res = ProtocolResult.load(path)
    stems = res.stems
    bright = np.array([sign.get(s, np.nan) > 0.3 for s in stems])
    dark = np.array([sign.get(s, np.nan) < -0.3 for s in stems])
    row = [f"{res.condition}:"]
    for iou in (0.5, 0.3):
        pools = res.pools(iou)
        for name, sel in (("bright", bright), ("dark", dark)):
            ap = np.mean([p.ap(sel.astype(np.int64)) for p in pools.values()])
            n = sum(p.n_positive[sel].sum() for p in list(pools.values())[:1])
            row.append(f"AP@{iou:g} {name} ({int(sel.sum())} videos, {n} drones) {ap:.3f}")
    print("  ".join(row))
