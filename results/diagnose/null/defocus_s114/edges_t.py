"""Stop 114: the frames' edge sharpness of cached bench cases as the diagnosis reads it (frame_evidence's sharpening:
mean ratio over scenes, its t against the clean centre, the scenes), on the frames as they are and through a tone
curve's inverse (GAMMA=g, as forward selection reads them once a gamma is accepted).
usage: [GAMMA=1.4] python edges_t.py WORKDIR... -> one line per case"""
import glob
import json
import os
import sys

from scipy import stats

from synthaug.diagnose.diagnosis_data import load_diagnosis_data
from synthaug.diagnose.screening import frame_evidence

g = float(os.environ.get("GAMMA", "1"))
given = {"gamma": {"gamma_g": g}} if g != 1 else None
for work in sys.argv[1:]:
    for case in sorted(glob.glob(f"{work}/case_*")):
        data = load_diagnosis_data(f"{case}/seeds", f"{case}/fit.json", "quadcopter")
        s = frame_evidence(data, given)["sharpening"]
        p_blur = float(stats.t.cdf(s["t"], s["scenes"] - 1))  # one-sided: blurrier than the clean centre
        print(json.dumps({"case": case, "gamma_undone": g, "ratio": round(s["ratio"], 4), "t": round(s["t"], 2),
                          "scenes": s["scenes"], "p_blurrier": float(f"{p_blur:.3g}")}), flush=True)
