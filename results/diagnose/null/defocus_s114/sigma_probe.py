"""Stop 114, a probe (not adopted): can the frames' edges read a defocus's sigma? Blurring a frame already blurred by
sigma with a Gaussian of s blurs it by sqrt(sigma^2 + s^2), so the frames' mean edge ratio read after extra blurs s
(both looks, every frame) traces the clean frames' curve from u = sigma^2 on, as a function of u = s^2 shifted by
sigma^2. A quadratic in u through the readings at s = 0, 0.5, 0.8, 1.1, extrapolated to where it reaches the clean
mean (the calibrated centre), gives -sigma^2.  usage: python sigma_probe.py WORKDIR... -> one line per case"""
import glob
import json
import sys

import numpy as np
from scipy import ndimage

from synthaug.diagnose.calibration import gain_centre
from synthaug.diagnose.diagnosis_data import load_diagnosis_data
from synthaug.diagnose.frame_pattern import edge_ratio

EXTRA = (0.0, 0.5, 0.8, 1.1)
centre = gain_centre("sharpening", "frame")
for work in sys.argv[1:]:
    for case in sorted(glob.glob(f"{work}/case_*")):
        data = load_diagnosis_data(f"{case}/seeds", f"{case}/fit.json", "quadcopter")
        looks = [f["looks"] for f in data.frame_summaries if f.get("looks") is not None]
        means = []
        for s in EXTRA:
            blur = (lambda x: x) if s == 0 else (lambda x: ndimage.gaussian_filter(np.asarray(x, np.float64), s))
            r = [edge_ratio(blur(fr), blur(bg), outside=out, unclipped=out) for fr, bg, out in looks]
            means.append(float(np.nanmean(r)))
        u = np.square(EXTRA)
        c2, c1, c0 = np.polyfit(u, means, 2)
        roots = np.roots([c2, c1, c0 - centre])
        neg = [float(x.real) for x in roots if abs(x.imag) < 1e-12 and x.real < 0]
        sigma = float(np.sqrt(-max(neg))) if neg else 0.0
        truth = json.load(open(f"{case}/case.json"))["key"].get("hidden")
        print(json.dumps({"case": case, "hidden": truth, "ratios": [round(m, 4) for m in means],
                          "sigma_read": round(sigma, 3)}), flush=True)
