"""Stop 95: dump each case's fitted w_d (the diagnosis's base render), frame brightness and video, for
statistics.py.

    PYOPENGL_PLATFORM=egl python results/diagnose/null/exposure_s95/dump_wd.py OUT_DIR CASE_DIR...
"""
import sys, os, numpy as np, time
from synthaug.diagnose.diagnosis_data import load_diagnosis_data
from synthaug.diagnose.screening import base_render, seed_metadata
from synthaug.diagnose.residuals import seed_groups
out = sys.argv[1]; os.makedirs(out, exist_ok=True)
for case in sys.argv[2:]:
    name = case.rstrip("/").replace("outputs/", "").replace("/", "__")
    f = f"{out}/{name}.npz"
    if os.path.exists(f): continue
    t = time.time()
    data = load_diagnosis_data(f"{case}/seeds", f"{case}/fit.json", "quadcopter")
    syn0, w0 = base_render(data, None)
    md = seed_metadata(data)
    np.savez(f, w=w0.numpy(), B=md["frame_brightness"], g=seed_groups(data), n=len(data))
    print(name, round(time.time() - t, 1), flush=True)
