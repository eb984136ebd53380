"""Stop 95: would the signed floors of the absorbed channels (synthaug/diagnose/null_floors.py) raise an alarm on
any stored clean output? Per output and absorbed channel: clean alarms with the floors before (old) -> after, and
the two largest held-out R² of the right sign. Reads stored JSONs only (seconds).

    PYTHONPATH=. python results/diagnose/null/exposure_s95/clean_alarms.py results/diagnose/null/frame_refresh/*.json \
        results/diagnose/null/fresh*.json results/diagnose/null/colour_clean*.json
"""
import json, sys, numpy as np
from synthaug.diagnose.screening import ABSORPTION
from synthaug.diagnose import null_floors as nf
old = {"exposure": 0.243025, "defocus": 0.207789, "sharpening": 0.207789, "vignetting": 0.080354}
for f in sys.argv[1:]:
    d = json.load(open(f)); nd = d["null_distributions"]
    out = []
    for eff, (_, _, sign) in ABSORPTION.items():
        e = nd.get(f"screen:{eff}:absorbed")
        if not e: continue
        g, r, p = (np.array(e[k]["values"]) for k in ("gain", "rho", "p_adjusted"))
        new = nf.SCREEN[f"{eff}:absorbed"]
        a_new = int(((p < 0.01) & (r * sign > 0) & (g > new)).sum()); a_old = int(((p < 0.01) & (r * sign > 0) & (g > old[eff])).sum())
        near = np.round(np.sort(g[(r * sign > 0)])[-2:], 3).tolist()
        out.append(f"{eff} {a_old}->{a_new} (top right-sign R2 {near})")
    print(f.split('/')[-1], d.get("cases"), d.get("base_seed"), d.get("fit"), "|", "; ".join(out))
