"""Issue 20, stop 112: a location-free highlight statistic tried offline — the object's brightest excess over the
model's diffuse shading. Per seed: y = real − render(w_d 0.2), the albedo slope s fitted by least squares on the
object's interior (coverage ≥ 0.99, eroded by one pixel), and of the residual on the interior its maximum, its
mean over the 3 and 5 largest pixels and its 95th percentile. A highlight adds a localised peak whatever its place
(each video's light, smooth normals, a finer mesh move it); the shading's mismatches spread over the object.

    PYTHONPATH=. python results/diagnose/null/highlight_s112/peaks.py OUT.npz CASE_DIR...
"""
import pathlib
import sys

import numpy as np
import torch

from synthaug.diagnose.diagnosis_data import ALBEDO_POINTS, albedo_renders

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "highlight_s111"))
from gram import load_case, run_cases, specular_truth  # noqa: E402  (stop 111's)

STATS = ["max", "top3", "top5", "p95", "rms", "npix"]


def case_peaks(case: str) -> dict:
    seeds, data = load_case(case)
    (w0, w1), (r0, r1) = ALBEDO_POINTS, albedo_renders(data, None)
    a0 = r0.double()
    s = (r1.double() - a0) / (w1 - w0)
    y = data.real.double() - a0
    cov = (data.coverage.double() >= 0.99).double()
    inner = -torch.nn.functional.max_pool2d(-cov, 3, 1, 1)  # eroded by one pixel
    out = np.zeros((len(data), len(STATS)))
    for i in range(len(data)):
        m = inner[i, 0] > 0.5
        if int(m.sum()) < 8:
            out[i] = np.nan
            continue
        si, yi = s[i, 0][m], y[i, 0][m]
        w = float((si * yi).sum() / (si * si).sum().clamp_min(1e-12))
        r = (yi - w * si).numpy()
        r = r - np.median(r)
        srt = np.sort(r)[::-1]
        out[i] = [srt[0], srt[:3].mean(), srt[:5].mean(), np.percentile(r, 95), np.sqrt((r ** 2).mean()), len(r)]
    return {"stats": out, **specular_truth(seeds, case)}


def main() -> int:
    return run_cases(case_peaks, "stats", STATS)


if __name__ == "__main__":
    sys.exit(main())
