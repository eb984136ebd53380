"""Stop 114: the setting a defocus is named at against the truth over this stop's defocus rows (sigma 0.7 and 1.0 on
five sets, 1.5 on three: 65 cases), and what the error follows among the case's nuisances (Spearman).
usage: python results/diagnose/null/defocus_s114/setting_bias.py -> setting_bias.txt"""
import glob
import json
from collections import Counter
from pathlib import Path

import numpy as np
from scipy import stats

HERE = Path(__file__).parent
rows = []
for f in sorted(glob.glob(str(HERE / "*" / "power5_defocus*.json"))):
    d = json.load(open(f))
    truth = d["hidden_settings"]["defocus"]["defocus_sigma"]
    for c in d["per_case"]:
        if c["settings"] and "defocus_sigma" in (c["settings"][0] or {}):
            rows.append((truth, c["settings"][0]["defocus_sigma"], c["nuisances"]))
print(f"{len(rows)} cases named defocus first")
for t in sorted({r[0] for r in rows}):
    named = Counter(r[1] for r in rows if r[0] == t)
    print(f"truth {t}: named {dict(sorted(named.items()))}")
err = np.array([r[1] - r[0] for r in rows])
print(f"error (named - truth): min {err.min():+.2f}, median {np.median(err):+.2f}, max {err.max():+.2f} frame px")
for key in ("normal_smoothing_px", "rotor_scale", "mesh_sections", "mesh_perturbation", "albedo_texture_px",
            "light_spread_deg", "ambient", "specular_ks"):
    rho, p = stats.spearmanr([r[2][key] for r in rows], err)
    print(f"  error vs {key}: Spearman {rho:+.2f} (p {p:.2g})")
