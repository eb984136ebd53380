"""Stop 95: which power rows' cases gain an absorbed exposure or defocus finding with the signed floors (stored
statistics, no rerun; prints only the rows that change).

    PYTHONPATH=. python results/diagnose/null/exposure_s95/power_rows.py results/diagnose/null/before_s95/power5_*.json \
        results/diagnose/null/power5_*.json results/diagnose/null/rival_s94/fresh9000/*.json
"""
import json, sys, glob, numpy as np
from synthaug.diagnose.screening import ABSORPTION
from synthaug.diagnose import null_floors as nf
old = {"exposure": 0.243025, "defocus": 0.207789, "sharpening": 0.207789, "vignetting": 0.080354}
for f in sorted(sys.argv[1:]):
    d = json.load(open(f)); nd = d["null_distributions"]
    out = []
    for eff in ("exposure", "defocus"):
        sign = ABSORPTION[eff][2]
        e = nd.get(f"screen:{eff}:absorbed")
        if not e: continue
        g, r, p = (np.array(e[k]["values"]) for k in ("gain", "rho", "p_adjusted"))
        new = nf.SCREEN[f"{eff}:absorbed"]
        sn = (p < 0.01) & (r * sign > 0) & (g > new); so = (p < 0.01) & (r * sign > 0) & (g > old[eff])
        if sn.sum() != so.sum():
            out.append(f"{eff} absorbed {int(so.sum())}->{int(sn.sum())} cases {np.nonzero(sn & ~so)[0].tolist()}")
    firsts = [c["findings"][:1] for c in d["per_case"]]
    if out: print(f.split('/')[-1], "|", "; ".join(out), "| first now:", firsts)
