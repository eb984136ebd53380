"""Issue 20, stop 100: the frames' edge sharpness at the frame's centre against their mean, per case.

A camera's sharpening steepens every edge alike; a lens changes the local scale with r² and leaves the centre's edges
as they are. So besides the diagnosis's mean ratio (``sharp_edges``' ``ratio``) and trend (``radial``), this reads,
over the same edges and frames (``diagnosis_data._frame_summaries``, the diagnosis's own), the intercept ``a`` of
``A(2) = (a + b r²) A(4)`` (the ratio at r² = 0) and the ratio of the edges within r² < 0.25, each averaged over
scenes as ``sharp_edges`` averages the ratio.

Usage::

    PYTHONPATH=. python results/diagnose/null/centre_s100/edge_centre.py --out OUT.json clean:2000:24 \\
        clean:4000:20:full lens_distortion:alt:11000:5 ...
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from edge_radial import groups_parser, run_groups, write_out  # noqa: E402  (stop 45's case maker)

INNER_R2 = 0.25


def case_row(seeds, geo) -> dict:
    from synthaug.diagnose import frame_pattern as fp
    from synthaug.diagnose.diagnosis_data import _frame_summaries, _read_frames

    extra: list[tuple[float, float]] = []
    orig = fp.edge_radial

    def radial(steps):  # the same call, recording the centre's readings beside it
        if steps is None:
            extra.append((float("nan"), float("nan")))
            return orig(steps)
        (h, w), y, x = steps["shape"], np.asarray(steps["y"], float), np.asarray(steps["x"], float)
        r2 = ((x - (w - 1) / 2) ** 2 + (y - (h - 1) / 2) ** 2) / (0.25 * (w * w + h * h))
        a1, a2 = np.asarray(steps["a1"], float), np.asarray(steps["a2"], float)
        (a, _), *_ = np.linalg.lstsq(np.stack([a2, a2 * r2], 1), a1, rcond=None)
        inner = r2 < INNER_R2
        extra.append((float(a), float(a1[inner].sum() / a2[inner].sum()) if inner.sum() >= 5 else float("nan")))
        return orig(steps)

    fp.edge_radial = radial
    try:
        summaries = _frame_summaries(seeds, _read_frames(seeds), geo, seeds.patch_size)
    finally:
        fp.edge_radial = orig
    it = iter(extra)
    for s in summaries:  # edge_radial is called once for each frame with an independent look, in order
        if np.isfinite(s["edge_ratio"]):
            s["edge_a"], s["edge_inner"] = next(it)
    groups = [r.get("video") for r in seeds.records]
    row = {}
    for key in ("edge_ratio", "edge_radial", "edge_a", "edge_inner"):
        r = fp._over_scenes(summaries, groups, key, fp.SAME_SCENE, two_sided=True)
        row[key] = None if r is None else r["mean"]
        if r is not None:
            row["scenes"] = r["scenes"]
    return row


def main() -> int:
    a = groups_parser().parse_args()
    t0 = time.perf_counter()
    return write_out(run_groups(a.groups, a.workdir, case_row, out_path=a.out, t0=t0), a.out, t0)


if __name__ == "__main__":
    sys.exit(main())
